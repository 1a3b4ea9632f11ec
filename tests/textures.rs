//! Solid textures against the independent reference renders.
//!
//! The reference implementation differs from glint in a few documented ways
//! that have nothing to do with where a texture puts its materials (its
//! source is public; the renders themselves show each quirk):
//! - its Checkerboard is `sin(3x)·sin(3y)·sin(3z) > 0`: cells of π/3 texture
//!   units, not 1;
//! - its ambient term uses a fixed colour per texture: 0 for a Checkerboard,
//!   the average of the two materials' diffuse colours for Noise, Marble and
//!   Wood, instead of the diffuse colour at the point;
//! - its Wood never reflects (so its checkerboard-of-woods floor does not
//!   either), although the woods' materials have a `reflectiveColor`;
//! - its pixel (i, j) looks through screen point (i/w, j/h) with the same
//!   angle on both axes, which squashes the 400×200 logo renders vertically;
//! - its Wood is its Marble formula (stripes, not rings).
//!
//! glint keeps the physics (ambient light × the material at the point,
//! reflective wood, an undistorted camera, rings) and unit checker cells. To
//! test the textures themselves, [`render_like_reference`] renders a scene
//! with all five quirks reproduced (wood drawn with the marble formula).
//! With them the checkerboards, the noise, the marble and the reference's
//! "wood" (including scene6_18's checkerboard of woods, a texture of
//! textures) match pixel for pixel, which also settles the lookup space
//! (world, see `material::eval`) and where nested textures are looked up.
//! glint's own rings are pinned down by the unit tests in
//! `material/texture.rs` and by the mean colours below.
//!
//! **"Mean colour within 5%"** means: for each of R, G and B, the mean of the
//! channel's 8-bit values over the compared pixels, ours `m` and the
//! reference's `r`, satisfy `|m − r| ≤ 0.05·r`.

use crate::common::*;

use glint::format::load_scene;
use glint::integrator::{NoObserver, Whitted};
use glint::math::{Mat4, Vec2, Vec3};
use glint::output::to_byte;
use glint::render::CameraModel;
use glint::scene::{Material, Phong, Scene, TextureKind};
use glint::stats::Counters;
use glint::world::{BuildOptions, World};
use rayon::prelude::*;
use std::path::Path;

const MAX_MEAN_REL: f64 = 0.05;

/// The ray-tree settings a command line asks for.
fn integrator_for(args: &[String]) -> Whitted {
    let has = |f: &str| args.iter().any(|a| a == f);
    Whitted {
        shadows: has("-shadows"),
        shade_back: has("-shade_back"),
        bounces: flag_value(args, "-bounces").map_or(0, |v| v.parse().unwrap()),
        weight_cutoff: flag_value(args, "-weight").map_or(0.0, |v| v.parse().unwrap()),
        ..Whitted::default()
    }
}

/// The image size a command line asks for.
fn size_for(args: &[String]) -> (u32, u32) {
    let i = args.iter().position(|a| a == "-size").expect("-size");
    (args[i + 1].parse().unwrap(), args[i + 2].parse().unwrap())
}

/// The reference's ambient reflectance of material `i`: a plain material's
/// diffuse colour; 0 for a Checkerboard; the mean of the two materials' for
/// the noise-based textures.
fn reference_ambient(materials: &[Material], i: usize) -> Vec3 {
    match &materials[i] {
        Material::Phong(p) => p.diffuse,
        Material::Texture {
            kind: TextureKind::Checkerboard,
            ..
        } => Vec3::ZERO,
        Material::Texture { a, b, .. } => {
            (reference_ambient(materials, *a) + reference_ambient(materials, *b)) / 2.0
        }
    }
}

/// Two scenes whose renders add up to the reference's picture of `scene`
/// (the ray tree is linear in the ambient light, so local lighting and
/// ambient can be rendered apart and summed):
/// - `lit`: no ambient light, checker cells scaled to π/3, woods not
///   reflective (and drawn with the marble formula if `wood_as_marble`);
/// - `ambient`: no lights, a black background, and each texture replaced by
///   a plain material with the reference's ambient reflectance.
fn reference_quirks(scene: &Scene, wood_as_marble: bool) -> (Scene, Scene) {
    let mut lit = scene.clone();
    lit.background.ambient = Vec3::ZERO;
    let sin_cells = Mat4::from_scale(Vec3::splat(3.0 / std::f32::consts::PI));
    let mut not_reflective = Vec::new();
    for m in &mut lit.materials {
        if let Material::Texture {
            kind,
            transform,
            a,
            b,
        } = m
        {
            match kind {
                // sin(3x) > 0 ⇔ ⌊3x/π⌋ even, so the reference's checker is
                // ours after a scale by 3/π in texture space.
                TextureKind::Checkerboard => *transform = sin_cells * *transform,
                TextureKind::Wood {
                    octaves,
                    frequency,
                    amplitude,
                } => {
                    not_reflective.extend([*a, *b]);
                    if !wood_as_marble {
                        continue;
                    }
                    // The reference's Wood is its Marble formula: stripes.
                    *kind = TextureKind::Marble {
                        octaves: *octaves,
                        frequency: *frequency,
                        amplitude: *amplitude,
                    };
                }
                _ => {}
            }
        }
    }
    for i in not_reflective {
        if let Material::Phong(p) = &mut lit.materials[i] {
            p.reflective = Vec3::ZERO;
        }
    }

    let mut ambient = scene.clone();
    ambient.lights.clear();
    ambient.background.color = Vec3::ZERO;
    ambient.materials = (0..scene.materials.len())
        .map(|i| match &scene.materials[i] {
            Material::Phong(p) => Material::Phong(*p),
            Material::Texture { .. } => Material::Phong(Phong {
                diffuse: reference_ambient(&scene.materials, i),
                ..Phong::default()
            }),
        })
        .collect();
    (lit, ambient)
}

/// Linear colours of `scene` at the reference's screen points for every
/// `step`-th pixel of a `w`×`h` image (rows top first).
fn trace_points(scene: &Scene, integrator: &Whitted, (w, h): (u32, u32), step: u32) -> Vec<Vec3> {
    let world = World::build(scene, BuildOptions::default());
    let camera = CameraModel::new(world.camera());
    let rows: Vec<u32> = (0..h).step_by(step as usize).collect();
    rows.par_iter()
        .flat_map_iter(|&row| {
            let j = h - 1 - row;
            let (world, camera) = (&world, &camera);
            (0..w).step_by(step as usize).map(move |i| {
                // The reference's framing: each axis spans [0, 1] on its own.
                let s = Vec2::new(i as f32 / w as f32, j as f32 / h as f32);
                let mut c = Counters::default();
                crate::common::eye_ray(
                    integrator,
                    world,
                    &camera.ray(s),
                    camera.tmin(),
                    &mut c,
                    &mut NoObserver,
                )
                .0
            })
        })
        .collect()
}

/// The command line's render with the reference's quirks, at every
/// `step`-th pixel; returns ours and the reference's pixels at those points.
fn render_like_reference(
    data: &CourseData,
    line: &CmdLine,
    step: u32,
    wood_as_marble: bool,
) -> (Vec<[u8; 3]>, Vec<[u8; 3]>) {
    let input = flag_value(&line.args, "-input").expect("-input");
    let scene = load_scene(&data.scenes.join(input)).expect("scene");
    let integrator = integrator_for(&line.args);
    let size = size_for(&line.args);
    let (lit, ambient) = reference_quirks(&scene, wood_as_marble);
    let a = trace_points(&lit, &integrator, size, step);
    let b = trace_points(&ambient, &integrator, size, step);
    let ours = a
        .iter()
        .zip(&b)
        .map(|(x, y)| {
            let c = *x + *y;
            [to_byte(c.x), to_byte(c.y), to_byte(c.z)]
        })
        .collect();

    let (w, h, px) = load_rgb8(&reference_for(&data.refs, &line.outputs[0])).unwrap();
    assert_eq!((w, h), size, "reference size");
    let reference = (0..h)
        .step_by(step as usize)
        .flat_map(|r| (0..w).step_by(step as usize).map(move |i| (r, i)))
        .map(|(r, i)| px[(r * w + i) as usize])
        .collect();
    (ours, reference)
}

fn fmt3(v: [f64; 3]) -> String {
    format!(
        "[{:+.2}%, {:+.2}%, {:+.2}%]",
        100.0 * v[0],
        100.0 * v[1],
        100.0 * v[2]
    )
}

/// Per-pixel tolerance of the quirk-reproduced renders: (command file,
/// output, pixel step, largest mean abs difference, largest fraction of
/// pixels off by more than 24), from the differences measured
/// plus a margin, the core images' tolerance where that covers them:
/// - checkerboards: mean 0.10-0.39, 0.06-0.42% off (6_13 the most);
/// - 6_15, 6_16, 6_17a: identical but for 6_17a's mean of 0.004;
/// - 6_18a (every 4th pixel of every 4th row, 5000 pixels): mean 0.70, 0.94%
///   off (47 pixels), on a logo seen through 5 bounces of reflection.
///
/// Moved by one pixel, the one-ray renders measure a mean of 2.0 to 44 and
/// 1.9% to 29% off: every one fails.
const PIXEL_CASES: &[(&str, &str, u32, f64, f64)] = &[
    ("A6_cmd.txt", "output6_13.tga", 1, 1.0, 0.005),
    ("A6_cmd.txt", "output6_14.tga", 1, 1.0, 0.005),
    ("A7_cmd.txt", "output7_02.tga", 1, 1.0, 0.005),
    ("A7_cmd.txt", "output7_05a.tga", 1, 1.0, 0.005),
    ("A6_cmd.txt", "output6_15.tga", 1, 1.0, 0.005),
    ("A6_cmd.txt", "output6_17a.tga", 1, 1.0, 0.005),
    ("A6_cmd.txt", "output6_16.tga", 1, 1.0, 0.005),
    ("A6_cmd.txt", "output6_18a.tga", 4, 1.0, 0.015),
];

/// Every textured render with the reference's quirks reproduced, pixel by
/// pixel: the checkerboards (scene6_13, 6_14, 7_02, 7_05a); scene6_15's Noise
/// (1 and 5 octaves) and Marble (0 and 5 octaves) on four transformed cubes;
/// scene6_17's 5-octave Marble vase on a Noise floor; scene6_16's woods and
/// scene6_18's checkerboard of woods (the reference's wood is its marble).
/// Perlin's standard permutation puts the same blotches on the same pixels.
/// This pins down the noise function, the octave sum, the clamp rescaling,
/// which material is which, the checker's parity and matrix, and that every
/// lookup, nested ones included, is at the world-space hit point (scene6_15's
/// cubes are transformed; object-space lookups put their inverse transforms
/// in twice: on the literal render, a mean error of 18.2/255 against 3.7).
///
/// Each one-ray render moved by one pixel must fail its tolerance too, so
/// the tolerance can see a misplaced pattern. The logo (scene6_18, 400×200,
/// 5 bounces) is traced at every 4th pixel of every 4th row.
#[test]
fn textures_match_the_reference_pixel_for_pixel_once_its_quirks_are_reproduced() {
    let Some(data) =
        course_data("textures_match_the_reference_pixel_for_pixel_once_its_quirks_are_reproduced")
    else {
        return;
    };
    let mut failures = Vec::new();
    for &(file, out, step, max_mean, max_off) in PIXEL_CASES {
        let line = line_for(&data.scenes, file, out);
        let (ours, reference) = render_like_reference(&data, &line, step, true);
        let d = diff_pixels(&ours, &reference);
        eprintln!(
            "{out}: mean abs {:.3}, {:.3}% off",
            d.mean_abs,
            100.0 * d.frac_off
        );
        let accepts = |d: &Diff| d.mean_abs <= max_mean && d.frac_off <= max_off;
        if !accepts(&d) {
            failures.push(format!("{out}: {d:?} (max {max_mean}, {max_off})"));
        }
        if step == 1 {
            let (w, h) = size_for(&line.args);
            for (dx, dy) in ONE_PIXEL_SHIFTS {
                let moved = diff_pixels(&shifted(w, h, &ours, dx, dy), &reference);
                eprintln!(
                    "{out} moved ({dx}, {dy}): mean abs {:.3}, {:.3}% off",
                    moved.mean_abs,
                    100.0 * moved.frac_off
                );
                if accepts(&moved) {
                    failures.push(format!(
                        "{out} moved by ({dx}, {dy}) still passes: {moved:?}"
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The literal command lines (`-grid` removed), mean colour against the
/// reference's. Per image: the largest |relative difference| allowed and why.
///
/// scene6_17 / scene7_03 (marble vase on a Noise floor, ambient light 0.4):
/// the reference lights every textured point with ambient × the *average* of
/// the two materials, so its black-and-white noise floor has a grey base
/// (0.4 × 0.5) where ours is black (the black material reflects no ambient
/// light). Measured: −18%, −22%, −14% (R, G, B), for both images; with that
/// quirk reproduced the difference falls under 5% (next test). The logo lines
/// (6_18a, 7_04a) are only in the next test: the reference's framing of
/// 400×200 images is distorted, so its mean colour is not comparable, and a
/// full render takes minutes without an acceleration structure.
#[test]
fn noise_marble_wood_mean_colour_of_the_command_lines() {
    let cases: &[(&str, &str, f64)] = &[
        ("A6_cmd.txt", "output6_15.tga", MAX_MEAN_REL),
        ("A6_cmd.txt", "output6_16.tga", MAX_MEAN_REL),
        ("A6_cmd.txt", "output6_17a.tga", 0.25),
        ("A7_cmd.txt", "output7_03a.tga", 0.25),
    ];
    let Some(data) = course_data("noise_marble_wood_mean_colour_of_the_command_lines") else {
        return;
    };
    let dir = scratch("textures-mean-colour");
    let mut failures = Vec::new();
    for &(file, out, max_rel) in cases {
        let line = line_for(&data.scenes, file, out);
        run_raytracer(&data.scenes, &line.args, &dir)
            .unwrap_or_else(|e| panic!("{}: {e}", line.text));
        let (_, _, ours) = load_rgb8(&dir.join(out)).unwrap();
        let (_, _, reference) = load_rgb8(&reference_for(&data.refs, out)).unwrap();
        let rel = relative_mean_diff(mean_rgb(&ours), mean_rgb(&reference));
        eprintln!("{out}: mean colour {} off the reference", fmt3(rel));
        if rel.iter().any(|r| r.abs() > max_rel) {
            failures.push(format!("{out}: {} (max ±{}%)", fmt3(rel), 100.0 * max_rel));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Every deterministic Noise/Marble/Wood image with the reference's quirks
/// reproduced (ambient, framing, non-reflective wood, checker cells): mean
/// colour within 5%. What remains is the textures' own statistics, including
/// Wood's rings against the reference's stripes (scene6_16, scene6_18).
///
/// The logo (400×200, 13 852 triangles, 5 bounces) is traced at every 4th
/// pixel of every 4th row, and compared with the reference's pixels at the
/// same positions: an unbiased estimate of the mean colour that keeps the
/// test under a minute without an acceleration structure.
#[test]
fn noise_marble_wood_mean_colour_with_the_quirks_reproduced() {
    let Some(data) = course_data("noise_marble_wood_mean_colour_with_the_quirks_reproduced") else {
        return;
    };
    let cases: &[(&str, &str, u32)] = &[
        ("A6_cmd.txt", "output6_15.tga", 1),
        ("A6_cmd.txt", "output6_16.tga", 1),
        ("A6_cmd.txt", "output6_17a.tga", 1),
        ("A7_cmd.txt", "output7_03a.tga", 1),
        ("A6_cmd.txt", "output6_18a.tga", 4),
    ];
    let mut failures = Vec::new();
    for &(file, out, step) in cases {
        let (ours, reference) =
            render_like_reference(&data, &line_for(&data.scenes, file, out), step, false);
        let rel = relative_mean_diff(mean_rgb(&ours), mean_rgb(&reference));
        eprintln!("{out}: mean colour {} off the reference", fmt3(rel));
        if rel.iter().any(|r| r.abs() > MAX_MEAN_REL) {
            failures.push(format!("{out}: {}", fmt3(rel)));
        }
        if out == "output6_18a.tga" {
            // scene7_04 is the same file rendered with the same flags, and
            // output7_04a is byte-identical to output6_18a: no second render.
            let (w, h, a) = load_rgb8(&reference_for(&data.refs, "output7_04a.tga")).unwrap();
            let (_, _, b) = load_rgb8(&reference_for(&data.refs, out)).unwrap();
            assert_eq!((w, h), (400, 200));
            assert!(a == b, "output7_04a no longer equals output6_18a");
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The example scenes that `docs/scene-format.md` shows keep parsing.
#[test]
fn documentation_examples_parse() {
    for t in ["checkerboard", "noise", "marble", "wood"] {
        let path = own_scene(&format!("texture_{t}.txt"));
        let scene = load_scene(&path).unwrap_or_else(|e| panic!("{}: {e:?}", path.display()));
        assert!(
            matches!(scene.materials[2], Material::Texture { .. }),
            "{t}: material 2 should be the texture"
        );
        assert!(Path::new(&format!("docs/images/texture_{t}.png")).is_file());
    }
}

/// With object-space lookups a texture moves with its object; with
/// world-space lookups (the 6.837 convention) it stays put in the world.
#[test]
fn object_space_textures_follow_their_object() {
    use glint::integrator::NoObserver;
    use glint::material::TextureSpace;
    use glint::math::{Mat4, Ray, Vec3};
    use glint::scene::{Background, Camera, Material, Node, Phong, Scene, ShapeDesc, TextureKind};
    use glint::stats::Counters;
    use glint::world::{BuildOptions, World};

    let red = Phong {
        diffuse: Vec3::X,
        ..Phong::default()
    };
    let blue = Phong {
        diffuse: Vec3::Z,
        ..Phong::default()
    };
    let scene_at = |shift: f32| Scene {
        camera: Camera::Orthographic {
            center: Vec3::new(0.0, 0.0, 5.0),
            direction: Vec3::NEG_Z,
            up: Vec3::Y,
            size: 4.0,
        },
        lights: vec![],
        background: Background {
            color: Vec3::ZERO,
            ambient: Vec3::ONE,
        },
        materials: vec![
            Material::Phong(red),
            Material::Phong(blue),
            Material::Texture {
                kind: TextureKind::Checkerboard,
                transform: Mat4::IDENTITY,
                a: 0,
                b: 1,
            },
        ],
        root: Node::Transform {
            matrix: Mat4::from_translation(Vec3::new(shift, 0.0, 0.0)),
            child: Box::new(Node::Shape {
                shape: ShapeDesc::Plane {
                    normal: Vec3::Z,
                    offset: 0.0,
                },
                material: Some(2),
            }),
        },
        effects: Default::default(),
    };
    let colour_at = |scene: &Scene, x: f32, space: TextureSpace| {
        let world = World::build(scene, BuildOptions::default());
        let w = Whitted {
            texture_space: space,
            ..Whitted::default()
        };
        let ray = world.ray_from_world(&Ray::new(Vec3::new(x, 0.5, 5.0), Vec3::NEG_Z));
        crate::common::eye_ray(
            &w,
            &world,
            &ray,
            0.0,
            &mut Counters::default(),
            &mut NoObserver,
        )
        .0
    };
    let (still, moved) = (scene_at(0.0), scene_at(1.0));
    // Object space: the point 0.5 units into the object is the same cell before and after the move.
    assert_eq!(
        colour_at(&still, 0.5, TextureSpace::Object),
        colour_at(&moved, 1.5, TextureSpace::Object)
    );
    // World space: the same world point keeps its colour, so the moved object's cell differs.
    assert_eq!(
        colour_at(&still, 0.5, TextureSpace::World),
        colour_at(&moved, 0.5, TextureSpace::World)
    );
    assert_ne!(
        colour_at(&moved, 1.5, TextureSpace::World),
        colour_at(&moved, 1.5, TextureSpace::Object)
    );
}
