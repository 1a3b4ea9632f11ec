//! Every fixture in `tests/malformed/` must fail to load with an error at an
//! exact line and column whose message says what went wrong.

use glint::format::{load_scene, obj::load_obj, parse_scene, ParseError};
use proptest::prelude::*;
use std::path::{Path, PathBuf};

/// A fixture, where its error must point, and text the message must contain.
struct Case {
    file: &'static str,
    line: usize,
    col: usize,
    message: &'static str,
}

const fn case(file: &'static str, line: usize, col: usize, message: &'static str) -> Case {
    Case {
        file,
        line,
        col,
        message,
    }
}

const CASES: &[Case] = &[
    case(
        "truncated.txt",
        18,
        15,
        "expected a number, found end of file",
    ),
    case(
        "too_many_objects.txt",
        18,
        5,
        "expected 2 objects (numObjects 2), found a 3rd 'Sphere'",
    ),
    case(
        "too_few_objects.txt",
        18,
        1,
        "expected 3 objects (numObjects 3), found '}' after 2 objects",
    ),
    case(
        "too_few_materials.txt",
        12,
        1,
        "expected 3 materials (numMaterials 3), found '}' after 2 materials",
    ),
    case(
        "too_many_materials.txt",
        11,
        5,
        "expected 1 material (numMaterials 1), found a 2nd 'PhongMaterial'",
    ),
    case(
        "too_many_lights.txt",
        11,
        5,
        "expected 1 light (numLights 1), found a 2nd 'PointLight'",
    ),
    case(
        "too_few_lights.txt",
        11,
        1,
        "expected 2 lights (numLights 2), found '}' after 1 light",
    ),
    case("bad_number.txt", 17, 18, "expected a number, found 'O'"),
    case("unknown_keyword.txt", 16, 5, "found 'Sphre'"),
    case(
        "missing_mesh.txt",
        17,
        18,
        "expected a readable OBJ file, found 'does_not_exist.obj' (No such file or directory)",
    ),
    case(
        "bad_mesh_index.txt",
        6,
        7,
        "bad_index.obj:6:7: expected a vertex index from 1 to 3",
    ),
    case(
        "material_index_out_of_range.txt",
        15,
        19,
        "expected a material index from 0 to 0 (numMaterials 1), found '1'",
    ),
    case(
        "texture_later_material.txt",
        13,
        23,
        "expected the index of an earlier material (0 to 0), found '2'",
    ),
    case("nan.txt", 16, 23, "expected a number, found 'nan'"),
    case("inf.txt", 5, 10, "expected a number, found 'inf'"),
    case(
        "zero_radius.txt",
        16,
        34,
        "expected a positive radius, found '0'",
    ),
    case(
        "zero_normal.txt",
        16,
        20,
        "expected a non-zero plane normal, found '0 0 0'",
    ),
    case(
        "empty.txt",
        1,
        1,
        "expected a camera (OrthographicCamera or PerspectiveCamera), found end of file",
    ),
    case("whitespace_only.txt", 1, 1, "found end of file"),
    case("binary.txt", 1, 1, "expected UTF-8 text, found byte 0x89"),
    case(
        "binary_tail.txt",
        3,
        4,
        "expected UTF-8 text, found byte 0xc3",
    ),
    case(
        "missing_open_brace.txt",
        17,
        9,
        "expected '{' after 'Sphere', found 'center'",
    ),
    case(
        "missing_close_brace.txt",
        19,
        2,
        "expected '}' closing the Group at 13:1, found end of file",
    ),
    case("negative_count.txt", 14, 16, "found '-2'"),
    case(
        "second_camera.txt",
        7,
        1,
        "expected one camera, found a second camera 'PerspectiveCamera'",
    ),
    case(
        "no_group.txt",
        11,
        2,
        "expected a top-level Group, found end of file",
    ),
    case(
        "bad_angle.txt",
        5,
        11,
        "expected an angle between 0 and 180 degrees (exclusive), found '0'",
    ),
    case(
        "up_parallel.txt",
        4,
        8,
        "expected an up vector not parallel to the camera direction, found '0 0 3'",
    ),
    case(
        "transform_without_object.txt",
        19,
        5,
        "expected a transform command or the object to transform, found '}'",
    ),
    // Truncated inside every kind of block.
    case(
        "truncated_camera.txt",
        4,
        11,
        "expected a number, found end of file",
    ),
    case(
        "truncated_lights.txt",
        12,
        23,
        "expected 'position', 'color', 'attenuation', or '}' closing the PointLight at 11:5, found end of file",
    ),
    case(
        "truncated_background.txt",
        10,
        25,
        "expected a number, found end of file",
    ),
    case(
        "truncated_materials.txt",
        13,
        17,
        "expected a number, found end of file",
    ),
    case(
        "truncated_group.txt",
        16,
        37,
        "'MaterialIndex', or '}' closing the Group at 13:1, found end of file",
    ),
    case(
        "truncated_transform.txt",
        18,
        18,
        "expected a number, found end of file",
    ),
    case(
        "truncated_texture.txt",
        15,
        22,
        "expected an integer, found end of file",
    ),
    // Numbers, keywords and braces.
    case(
        "number_out_of_range.txt",
        16,
        34,
        "expected a number within single-precision range, found '1e39'",
    ),
    case("comma_number.txt", 5, 10, "expected a number, found '2,5'"),
    case("hex_number.txt", 16, 21, "expected a number, found '0x10'"),
    case(
        "fractional_count.txt",
        9,
        18,
        "expected an integer, found '1.0'",
    ),
    case(
        "unknown_block.txt",
        8,
        1,
        "expected a block (OrthographicCamera, PerspectiveCamera, Lights, Background, Materials, Group, Samples, AmbientOcclusion), found 'Light'",
    ),
    case(
        "unknown_field.txt",
        16,
        36,
        "expected 'center', 'radius', or '}' closing the Sphere at 16:5, found 'color'",
    ),
    case(
        "duplicate_field.txt",
        16,
        36,
        "expected each Sphere field at most once, found a 2nd 'radius'",
    ),
    case(
        "missing_field.txt",
        16,
        27,
        "expected 'radius' in Sphere, found '}'",
    ),
    case(
        "stray_close_brace.txt",
        7,
        1,
        "expected a block (OrthographicCamera, PerspectiveCamera, Lights, Background, Materials, Group, Samples, AmbientOcclusion), found '}'",
    ),
    case(
        "missing_camera_brace.txt",
        2,
        5,
        "expected '{' after 'OrthographicCamera', found 'center'",
    ),
    // Values that would make geometry or shading meaningless.
    case(
        "negative_radius.txt",
        16,
        34,
        "expected a positive radius, found '-0.5'",
    ),
    case(
        "zero_direction.txt",
        3,
        15,
        "expected a non-zero camera direction, found '0 0 0'",
    ),
    case(
        "zero_up.txt",
        4,
        8,
        "expected a non-zero up vector, found '0.0 0 0'",
    ),
    case(
        "zero_light_direction.txt",
        10,
        34,
        "expected a non-zero light direction, found '0 0 0'",
    ),
    case("negative_size.txt", 5, 10, "expected a positive size, found '-5'"),
    case(
        "singular_transform.txt",
        16,
        5,
        "expected an invertible transform, found 'Transform' with a singular matrix",
    ),
    case(
        "negative_exponent.txt",
        10,
        44,
        "expected an exponent >= 0, found '-2'",
    ),
    case(
        "zero_ior.txt",
        10,
        57,
        "expected a positive index of refraction, found '0'",
    ),
    case(
        "texture_first.txt",
        10,
        34,
        "expected a material defined earlier (this texture is the first entry), found '0'",
    ),
    // Meshes that cannot be read, or whose contents are bad.
    case(
        "mesh_is_directory.txt",
        16,
        29,
        "expected a readable OBJ file, found 'directory.obj' (Is a directory)",
    ),
    case(
        "mesh_is_dot.txt",
        16,
        29,
        "expected a readable OBJ file, found '.' (Is a directory)",
    ),
    case(
        "obj_nan_mesh.txt",
        2,
        5,
        "nan_vertex.obj:2:5: expected a finite number, found 'nan'",
    ),
    // OBJ files on their own (read with `load_obj`).
    case(
        "bad_index.obj",
        6,
        7,
        "expected a vertex index from 1 to 3 (or -1 to -3), found '4'",
    ),
    case(
        "zero_index.obj",
        4,
        3,
        "expected a vertex index from 1 to 3 (or -1 to -3), found '0'",
    ),
    case(
        "negative_index.obj",
        4,
        9,
        "expected a vertex index from 1 to 3 (or -1 to -3), found '-4'",
    ),
    case(
        "face_before_vertices.obj",
        2,
        3,
        "expected a vertex index, but no vertex is defined before this face, found '1'",
    ),
    case(
        "bad_corner.obj",
        4,
        3,
        "expected a face corner 'v', 'v/vt', 'v//vn' or 'v/vt/vn', found '1/1/1/1'",
    ),
    case(
        "empty_face.obj",
        4,
        2,
        "expected vertex indices after 'f', found end of line",
    ),
    case(
        "nan_vertex.obj",
        2,
        5,
        "expected a finite number, found 'nan'",
    ),
    case(
        "inf_vertex.obj",
        3,
        7,
        "expected a finite number, found '-inf'",
    ),
    case(
        "short_vertex.obj",
        2,
        6,
        "expected 3 numbers after 'v', found end of line",
    ),
    // Distribution ray tracing's blocks (area lights, glossiness, lens and
    // shutter, keyframes, ambient occlusion, sample counts).
    case(
        "area_flat_quad.txt",
        11,
        47,
        "expected an edge2 not parallel to edge1 (a quad with an area), found '2 0 0'",
    ),
    case(
        "area_two_shapes.txt",
        12,
        9,
        "expected one shape per AreaLight, found a second shape 'sphere'",
    ),
    case(
        "area_missing_power.txt",
        13,
        5,
        "expected 'power' in AreaLight, found '}'",
    ),
    case(
        "area_zero_radius.txt",
        11,
        50,
        "expected a positive radius, found '0'",
    ),
    case(
        "bad_glossiness.txt",
        10,
        73,
        "expected a glossiness from 0 to 1, found '1.5'",
    ),
    case(
        "negative_emission.txt",
        10,
        55,
        "expected a colour component from 0 to 10000, found '-4'",
    ),
    case(
        "aperture_without_focus.txt",
        7,
        1,
        "expected 'focusDistance (with an aperture)' in PerspectiveCamera, found '}'",
    ),
    case(
        "shutter_backwards.txt",
        6,
        15,
        "expected a shutter close time not before the open time, found '0.5'",
    ),
    case(
        "camera_keyframe_order.txt",
        8,
        21,
        "expected a keyframe time after the previous one (1), found '0.5'",
    ),
    case(
        "camera_too_few_keyframes.txt",
        9,
        1,
        "expected 3 keyframes (numKeyframes 3), found '}' after 2 keyframes",
    ),
    case(
        "keyframe_time_order.txt",
        13,
        25,
        "expected a keyframe time after the previous one (0.5), found '0.5'",
    ),
    case(
        "keyframe_zero_scale.txt",
        12,
        35,
        "expected a non-zero scale, found '0'",
    ),
    case(
        "too_few_keyframes.txt",
        13,
        9,
        "expected 2 keyframes (numKeyframes 2), found 'Sphere' after 1 keyframe",
    ),
    case(
        "ao_zero_distance.txt",
        10,
        14,
        "expected a positive distance, found '0'",
    ),
    case(
        "zero_samples.txt",
        9,
        12,
        "expected a sample count from 1 to 4096, found '0'",
    ),
    case(
        "bad_number.obj",
        3,
        5,
        "expected 3 numbers after 'v', found 'one'",
    ),
    case(
        "binary.obj",
        2,
        118,
        "expected UTF-8 text, found byte 0x80 (is this a binary file?)",
    ),
];

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/malformed")
        .join(name)
}

#[test]
fn every_fixture_fails_where_expected() {
    let mut failures = Vec::new();
    for c in CASES {
        let path = fixture(c.file);
        let loaded = match c.file.ends_with(".obj") {
            true => load_obj(&path).map(drop),
            false => load_scene(&path).map(drop),
        };
        let err: ParseError = match loaded {
            Ok(_) => {
                failures.push(format!("{}: parsed without error", c.file));
                continue;
            }
            Err(e) => e,
        };
        let text = err.to_string();
        if (err.line, err.col) != (c.line, c.col) || !text.contains(c.message) {
            failures.push(format!(
                "{}: want {}:{} containing {:?}\n   got {text}",
                c.file, c.line, c.col, c.message
            ));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

#[test]
fn every_fixture_is_in_the_table() {
    let dir = fixture("");
    for entry in std::fs::read_dir(&dir).unwrap() {
        let entry = entry.unwrap();
        if entry.file_type().unwrap().is_dir() {
            continue; // `directory.obj`, named by mesh_is_directory.txt
        }
        let name = entry.file_name().into_string().unwrap();
        assert!(
            CASES.iter().any(|c| c.file == name),
            "{name} has no expected error"
        );
    }
    assert!(CASES.len() >= 40, "only {} cases", CASES.len());
}

#[test]
fn render_shows_the_line_and_a_caret() {
    let err = load_scene(&fixture("unknown_keyword.txt")).unwrap_err();
    let r = err.render();
    let first = r.lines().next().unwrap();
    assert!(
        first.contains("unknown_keyword.txt:16:5: expected an object"),
        "{r}"
    );
    assert!(first.ends_with("found 'Sphre'"), "{r}");
    assert!(
        r.contains("16 |     Sphre { center 0 0 0 radius 1 }\n"),
        "{r}"
    );
    assert!(r.contains("   |     ^^^^^\n"), "{r}");
}

#[test]
fn unreadable_scene_file_says_so() {
    let err = load_scene(&fixture("no_such_scene.txt")).unwrap_err();
    assert_eq!((err.line, err.col), (0, 0));
    assert!(
        err.to_string().contains("expected a readable scene file"),
        "{err}"
    );
    assert!(
        err.to_string().contains("No such file or directory"),
        "{err}"
    );
}

/// A small but complete scene to mutate.
fn seed_scene() -> String {
    let whitted = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/whitted.txt");
    std::fs::read_to_string(whitted).expect("scenes/whitted.txt")
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    /// Arbitrary edits never panic; the parser returns a scene or an error.
    #[test]
    fn edits_never_panic(pos in 0usize..4000, len in 0usize..20, insert in "[ -~\\n\\t{}#\u{e9}]{0,12}") {
        let src = seed_scene();
        let mut start = pos.min(src.len());
        while !src.is_char_boundary(start) { start -= 1; }
        let mut end = (start + len).min(src.len());
        while !src.is_char_boundary(end) { end -= 1; }
        let edited = format!("{}{}{}", &src[..start], insert, &src[end..]);
        let _ = parse_scene(&edited, Path::new("scenes/x.txt"));
    }

    /// Arbitrary text never panics either, and errors point inside the text.
    #[test]
    fn arbitrary_text_never_panics(src in "\\PC{0,200}") {
        if let Err(e) = parse_scene(&src, Path::new("x.txt")) {
            prop_assert!(e.line >= 1 && e.col >= 1);
            prop_assert!(e.line <= src.split('\n').count());
        }
    }
}

fn accepted(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/accepted")
        .join(name)
}

/// Exponent notation is a number like any other (only `nan`/`inf` and the
/// like are refused).
#[test]
fn exponent_notation_is_accepted() {
    let scene = load_scene(&accepted("exponent_notation.txt")).unwrap();
    let glint::scene::Camera::Perspective {
        center, angle_deg, ..
    } = scene.camera
    else {
        panic!("perspective camera expected");
    };
    assert_eq!(center.z, 10.0);
    assert_eq!(angle_deg, 30.0);
    assert_eq!(scene.background.color.x, 0.1);
    let glint::scene::Light::Point { attenuation, .. } = scene.lights[0] else {
        panic!("point light expected");
    };
    assert_eq!(attenuation.y, 1e-3);
    assert_eq!(attenuation.z, 2.5e-4);
    let mut radii = Vec::new();
    if let glint::scene::Node::Group(children) = &scene.root {
        for c in children {
            if let glint::scene::Node::Shape {
                shape: glint::scene::ShapeDesc::Sphere { radius, .. },
                ..
            } = c
            {
                radii.push(*radius);
            }
        }
    }
    assert_eq!(radii, [1.5, 5.0]);
}

/// Degenerate triangles are not an error: the scene loads, renders with
/// shadows and reflections, every pixel is finite, and only the real
/// triangles show.
#[test]
fn degenerate_triangles_render_with_finite_pixels() {
    let mut job = glint::job::Job::new(accepted("degenerate_triangles.txt"), 32, 32);
    job.shading.shadows = true;
    job.shading.shade_back = true;
    job.shading.bounces = 3;
    job.threads = Some(1);
    let report = job.run().unwrap();
    let f = &report.frame;
    assert!(f.color.iter().all(|c| c.is_finite()));
    assert!(f.normal.iter().all(|n| n.is_finite()));
    assert!(f.depth.iter().all(|d| !d.is_nan()));
    // Every hit is on one of the two real triangles, both facing +z.
    let hits: Vec<_> = f
        .normal
        .iter()
        .filter(|n| **n != glint::math::Vec3::ZERO)
        .collect();
    assert!(!hits.is_empty());
    assert!(hits.iter().all(|n| (n.z - 1.0).abs() < 1e-6), "{hits:?}");
    assert_eq!(
        report.primitives,
        4 + 4,
        "degenerate ones are kept, harmlessly"
    );
}
