//! Every fixture in `tests/malformed/` must fail to load with an error at an
//! exact line and column whose message says what went wrong.

use glint::format::{load_scene, parse_scene, ParseError};
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
        let err: ParseError = match load_scene(&fixture(c.file)) {
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
        let name = entry.unwrap().file_name().into_string().unwrap();
        let listed = CASES.iter().any(|c| c.file == name);
        assert!(
            listed || name.ends_with(".obj"),
            "{name} has no expected error"
        );
    }
    assert!(CASES.len() >= 15);
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
    std::fs::read_to_string("../shared/scenes/6837/scene4_14_faceted_gem.txt")
        .unwrap_or_else(|_| std::fs::read_to_string(fixture("too_few_objects.txt")).unwrap())
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
        let _ = parse_scene(&edited, Path::new("../shared/scenes/6837/x.txt"));
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
