//! The binaries as a user meets them: exit statuses, messages, every shared
//! scene rendering, output formats.

use crate::common::*;
use std::path::Path;
use std::process::Command;

fn raytracer(args: &[&str], dir: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

/// One of glint's own scenes, as an absolute path.
fn own(name: &str) -> String {
    own_scene(name).to_string_lossy().into_owned()
}

fn abs(p: &str) -> String {
    std::fs::canonicalize(p)
        .unwrap()
        .to_string_lossy()
        .into_owned()
}

#[test]
fn malformed_scenes_exit_2_with_position_and_no_panic() {
    let dir = scratch("malformed");
    for (file, pos) in [
        ("truncated.txt", ":18:15: expected a number"),
        ("too_many_objects.txt", ":18:5: expected 2 objects"),
        ("unknown_keyword.txt", ": expected"),
        ("missing_mesh.txt", "a readable OBJ file"),
        ("material_index_out_of_range.txt", ": expected"),
        ("bad_number.txt", ": expected a number"),
        ("binary.txt", ": expected"),
        ("empty.txt", ":1:1: expected"),
    ] {
        let input = abs(&format!("tests/malformed/{file}"));
        let out = raytracer(
            &["-input", &input, "-size", "10", "10", "-output", "x.png"],
            &dir,
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{file}: {err}");
        assert!(err.contains(pos), "{file}: message lacks {pos:?}: {err}");
        assert!(!err.contains("panicked"), "{file}: {err}");
        assert!(
            !dir.join("x.png").exists(),
            "{file}: wrote an image for bad input"
        );
    }
}

#[test]
fn glint_render_reports_bad_input_with_status_2() {
    let dir = scratch("glint-bad");
    let input = abs("tests/malformed/too_few_objects.txt");
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["render", &input, "-o", "x.png"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("too_few_objects.txt:18:1: expected 3 objects"),
        "{err}"
    );
    assert!(err.contains('^'), "no caret under the column: {err}");
}

#[test]
fn unknown_flag_is_named_and_preview_flags_are_ignored() {
    let dir = scratch("flags");
    let scene = own("whitted.txt");
    let out = raytracer(&["-input", &scene, "-frobnicate"], &dir);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("-frobnicate"));

    let out = raytracer(
        &[
            "-input",
            &scene,
            "-size",
            "20",
            "20",
            "-output",
            "a.png",
            "-tessellation",
            "10",
            "5",
            "-gouraud",
        ],
        &dir,
    );
    assert!(out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "one line on stderr: {err}");
    assert!(err.contains("-tessellation") && err.contains("-gouraud"));
    assert!(dir.join("a.png").exists());
}

/// A folder that does not exist is named, before any work (the formats
/// themselves are checked in `tests/formats.rs`).
#[test]
fn missing_output_folder_is_named() {
    let dir = scratch("formats");
    let scene = own("whitted.txt");
    let out = raytracer(
        &[
            "-input",
            &scene,
            "-size",
            "4",
            "4",
            "-output",
            "no/such/dir/out.png",
        ],
        &dir,
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("does not exist"));
}

/// `raytracer -help` lists every flag, one line each, and exits 0; a missing
/// value names its flag and exits 2.
#[test]
fn raytracer_help_and_missing_values() {
    for h in ["-help", "--help", "-h"] {
        let out = Command::new(env!("CARGO_BIN_EXE_raytracer"))
            .arg(h)
            .output()
            .unwrap();
        assert!(out.status.success(), "{h}");
        let text = String::from_utf8_lossy(&out.stdout);
        for flag in [
            "-input", "-output", "-size", "-shadows", "-bounces", "-weight", "-grid",
        ] {
            assert!(text.contains(flag), "{h}: {flag} missing from {text}");
        }
    }
    let dir = scratch("missing-value");
    for (args, flag) in [
        (&["-input"][..], "-input"),
        (&["-input", "a.txt", "-size", "20"][..], "-size"),
        (&["-input", "a.txt", "-bounces"][..], "-bounces"),
    ] {
        let out = raytracer(args, &dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(flag), "{args:?}: {err}");
    }
}

/// File-level errors show the whole path as given and no `:0:0:` position.
#[test]
fn missing_scene_path_is_shown_in_full() {
    let dir = scratch("long-path");
    let long = dir.join("a-folder-name-long-enough-to-have-been-cut-before/and/the/scene.txt");
    let out = raytracer(
        &["-input", &long.to_string_lossy(), "-output", "x.png"],
        &dir,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains(&*long.to_string_lossy()), "{err}");
    assert!(!err.contains(":0:0"), "{err}");
    assert!(err.contains("No such file or directory"), "{err}");
}

#[test]
fn glint_info_counts_the_scene() {
    let scene = own("mesh_knot_16k.txt");
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(["info", &scene])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("16384 triangles"), "{text}");
    assert!(text.contains("bounds"), "{text}");
}

/// Every scene of the course renders (small, all features on) without error,
/// and no pixel is NaN or infinite.
#[test]
fn every_shared_scene_renders_with_finite_pixels() {
    let Some(scenes) = scenes("every_shared_scene_renders_with_finite_pixels") else {
        return;
    };
    let names = scene_files(&scenes, "scene");
    assert!(names.len() >= 90, "only {} scenes found", names.len());
    renders_finite(names);
}

/// Every one of glint's own example scenes renders, with finite pixels.
#[test]
fn every_own_scene_renders_with_finite_pixels() {
    let names = scene_files(&own_scene(""), "");
    assert!(names.len() >= 8, "only {} scenes found", names.len());
    renders_finite(names);
}

/// The `.txt` scene files of `dir` whose names start with `prefix`, sorted.
fn scene_files(dir: &Path, prefix: &str) -> Vec<std::path::PathBuf> {
    let mut names: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| {
            let p = e.unwrap().path();
            (p.extension().is_some_and(|x| x == "txt")
                && p.file_name().unwrap().to_string_lossy().starts_with(prefix))
            .then_some(p)
        })
        .collect();
    names.sort();
    names
}

/// Renders each scene small with every Whitted feature on; no pixel may be NaN or infinite.
fn renders_finite(names: Vec<std::path::PathBuf>) {
    use glint::job::Job;
    for path in names {
        let mut job = Job::new(path.clone(), 24, 24);
        job.shading.shadows = true;
        job.shading.shade_back = true;
        job.shading.bounces = 3;
        job.shading.weight_cutoff = 0.01;
        let report = job
            .run()
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert!(
            report.frame.color.iter().all(|c| c.is_finite()),
            "{}: non-finite pixel",
            path.display()
        );
    }
}

/// Ctrl-C during a long render: the process stops, saves the rows it has as
/// `NAME.partial.EXT`, says so, and leaves an existing `NAME.EXT` untouched.
#[test]
fn sigint_saves_a_partial_image_and_keeps_the_original() {
    let dir = scratch("sigint");
    let original = b"not really a png, but precious".to_vec();
    std::fs::write(dir.join("out.png"), &original).unwrap();
    let scene = own("whitted.txt");
    // Big enough to run for many seconds on any machine.
    let child = Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .args([
            "-input", &scene, "-size", "3000", "3000", "-output", "out.png",
        ])
        .args([
            "-shadows",
            "-shade_back",
            "-bounces",
            "8",
            "-weight",
            "0.0001",
            "-quiet",
        ])
        .current_dir(&dir)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(err.contains("out.partial.png"), "{err}");
    assert_eq!(std::fs::read(dir.join("out.png")).unwrap(), original);
    let partial = image::open(dir.join("out.partial.png")).unwrap();
    assert_eq!((partial.width(), partial.height()), (3000, 3000));
}

#[test]
fn glint_renders_a_bare_obj() {
    let dir = scratch("obj");
    let mesh = own("meshes/knot_1k.obj");
    let out = Command::new(env!("CARGO_BIN_EXE_glint"))
        .args([
            "render",
            &mesh,
            "-o",
            "bunny.png",
            "--size",
            "64",
            "48",
            "--shadows",
            "--quiet",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(dir.join("bunny.png")).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (64, 48));
    // The framing camera must actually see the mesh: not every pixel is background.
    let bg = *img.get_pixel(0, 0);
    assert!(img.pixels().filter(|p| **p != bg).count() > 64 * 48 / 20);
}

#[test]
fn zero_and_huge_sizes_are_refused_up_front() {
    let dir = scratch("sizes");
    let scene = own("whitted.txt");
    let out = raytracer(
        &["-input", &scene, "-size", "0", "0", "-output", "z.png"],
        &dir,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("image size 0x0: width and height must be at least 1"),
        "{err}"
    );
    assert!(!dir.join("z.png").exists());

    let out = raytracer(
        &[
            "-input", &scene, "-size", "100000", "100000", "-output", "h.png",
        ],
        &dir,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("image size 100000x100000 would need 596.0 GiB of memory"),
        "{err}"
    );
    assert!(err.contains("choose a smaller size"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!dir.join("h.png").exists());
    // Refused before loading anything: with a scene that does not exist, the
    // size is still what is refused. (How long a refusal takes is measured
    // by `scripts/bench-refusals.sh`, not asserted here.)
    let out = raytracer(
        &[
            "-input",
            "missing.txt",
            "-size",
            "100000",
            "100000",
            "-output",
            "h.png",
        ],
        &dir,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("596.0 GiB of memory"), "{err}");
    assert!(!err.contains("missing.txt"), "{err}");
}

#[test]
fn hdr_outputs_by_extension() {
    let dir = scratch("hdr-cli");
    let scene = own("whitted.txt");
    for name in ["out.exr", "out.pfm"] {
        let out = raytracer(
            &["-input", &scene, "-size", "40", "30", "-output", name],
            &dir,
        );
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let pfm = std::fs::read(dir.join("out.pfm")).unwrap();
    assert!(pfm.starts_with(b"PF\n40 30\n-1.0\n"));
    assert_eq!(pfm.len(), 14 + 40 * 30 * 12);
    let exr = std::fs::read(dir.join("out.exr")).unwrap();
    assert!(
        exr.starts_with(&[0x76, 0x2f, 0x31, 0x01]),
        "EXR magic number"
    );
}

/// `raytracer -stats` prints the scene's bounds in the file's own
/// coordinates (world space), not in the camera-centred space glint renders
/// in: a sphere of radius 1 at (10, 20, 30) seen from (10, 20, 40).
#[test]
fn raytracer_stats_prints_world_bounds() {
    let dir = scratch("stats-bounds");
    std::fs::write(
        dir.join("s.txt"),
        "PerspectiveCamera { center 10 20 40 direction 0 0 -1 up 0 1 0 angle 30 }
         Group { numObjects 1 Sphere { center 10 20 30 radius 1 } }",
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .args([
            "-input", "s.txt", "-size", "8", "8", "-output", "s.png", "-stats",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .find(|l| l.contains("scene bounds"))
        .unwrap_or_else(|| panic!("{text}"));
    assert!(
        line.ends_with("(9.0000, 19.0000, 29.0000) -> (11.0000, 21.0000, 31.0000)"),
        "{line}"
    );
}
