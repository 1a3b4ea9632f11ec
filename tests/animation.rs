//! Animations: `--frame K` renders the scene at time `K / fps`, with objects
//! and the camera where their keyframes put them then; frames are tasks
//! (`--frame-from-env`, `#` in output names) and their pieces merge exactly.

use crate::common::*;
use glint::math::Vec3;
use std::path::Path;
use std::process::Command;

fn glint(args: &[&str], dir: &Path, env: &[(&str, &str)]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(args)
        .envs(env.iter().copied())
        .current_dir(dir)
        .output()
        .unwrap()
}

fn ok(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn pixels(path: &Path) -> Vec<Vec3> {
    glint::output::read_exr_window(path).unwrap().pixels
}

/// How two images differ: mean absolute difference per channel, and the
/// fraction of pixels with a channel off by more than `0.01`.
fn compare(a: &[Vec3], b: &[Vec3]) -> (f32, f32) {
    assert_eq!(a.len(), b.len());
    let mut sum = 0.0;
    let mut off = 0;
    for (p, q) in a.iter().zip(b) {
        let d = (*p - *q).abs();
        sum += d.x + d.y + d.z;
        off += usize::from(d.max_element() > 0.01);
    }
    (sum / (3 * a.len()) as f32, off as f32 / a.len() as f32)
}

const CAMERA: &str = "PerspectiveCamera { center 0 1 8 direction 0 -0.1 -1 up 0 1 0 angle 40 }";
const REST: &str = "
Lights { numLights 1 DirectionalLight { direction -0.3 -1 -0.5 color 0.9 0.9 0.9 } }
Background { color 0.2 0.3 0.4 ambientLight 0.2 0.2 0.2 }
Materials { numMaterials 2
  PhongMaterial { diffuseColor 0.7 0.7 0.7 }
  PhongMaterial { diffuseColor 0.9 0.2 0.1 specularColor 0.5 0.5 0.5 exponent 30 } }
";

fn scene(dir: &Path, name: &str, camera: &str, ball: &str) -> String {
    let text = format!(
        "{camera}\n{REST}\nGroup {{ numObjects 3 MaterialIndex 0 Plane {{ normal 0 1 0 offset -1 }}\n\
         Sphere {{ center -2 0 -2 radius 0.6 }}\nMaterialIndex 1\n{ball} }}\n"
    );
    std::fs::write(dir.join(name), text).unwrap();
    name.to_string()
}

/// A ball on keyframes, `x = 0` at time 0 and `x = 4` at time 2: frame 12 at
/// 24 fps (time 0.5) sees it at `x = 1`, where a still scene puts it.
#[test]
fn a_frame_sees_objects_where_their_keyframes_put_them() {
    let dir = scratch("anim-objects");
    let d = dir.as_ref();
    let moving = scene(
        d,
        "moving.txt",
        CAMERA,
        "KeyframedTransform { numKeyframes 2 Keyframe { time 0 } Keyframe { time 2 translate 4 0 0 }\n\
         Sphere { center 0 0 0 radius 0.8 } }",
    );
    let still = scene(d, "still.txt", CAMERA, "Sphere { center 1 0 0 radius 0.8 }");
    let size = ["--size", "96", "72", "--shadows"];
    ok(&glint(
        &[
            &["render", &moving, "--frame", "12", "-o", "f12.exr"][..],
            &size,
        ]
        .concat(),
        d,
        &[],
    ));
    ok(&glint(
        &[&["render", &still, "-o", "still.exr"][..], &size].concat(),
        d,
        &[],
    ));
    ok(&glint(
        &[
            &["render", &moving, "--frame", "0", "-o", "f0.exr"][..],
            &size,
        ]
        .concat(),
        d,
        &[],
    ));
    let (f12, still, f0) = (
        pixels(&d.join("f12.exr")),
        pixels(&d.join("still.exr")),
        pixels(&d.join("f0.exr")),
    );
    // Measured: mean 2.4e-9, no pixel off by 0.01 (the moving sphere is
    // intersected through its inverse pose, the still one directly: the
    // same hits up to rounding). The bounds leave room for a few edge
    // pixels that rounding could flip, not for the ball moving a pixel
    // (a one-pixel shift of the ball's edge changes ~2% of the pixels).
    let (mean, off) = compare(&f12, &still);
    println!("frame 12 vs still: mean {mean}, {off} of the pixels off");
    assert!(
        mean < 1e-5 && off < 0.001,
        "frame 12 vs still: {mean} {off}"
    );
    // The frame number matters: frame 0 has the ball elsewhere (measured:
    // 16% of the pixels off).
    let (mean0, off0) = compare(&f0, &still);
    println!("frame 0 vs still: mean {mean0}, {off0} of the pixels off");
    assert!(off0 > 0.03, "frame 0 looks like frame 12: {mean0} {off0}");
}

/// The camera's own keyframes move it: frame 6 at 12 fps (time 0.5) of a
/// camera sliding from `x = 0` to `x = 2` over one second equals a still
/// camera at `x = 1`; with a turn, the centre moves on a circle about the
/// origin (rotation about the rig's origin) and the view turns with it.
#[test]
fn a_moving_camera_is_where_its_keyframes_put_it() {
    let dir = scratch("anim-camera");
    let d = dir.as_ref();
    let ball = "Sphere { center 0 0 0 radius 0.8 }";
    let rig = "PerspectiveCamera { center 0 1 8 direction 0 -0.1 -1 up 0 1 0 angle 40\n\
               numKeyframes 2 Keyframe { time 0 } Keyframe { time 1 translate 2 0 0 rotate 0 1 0 20 } }";
    let moving = scene(d, "rig.txt", rig, ball);
    // At t = 0.5: translation (1, 0, 0), rotation 10° about y.
    let (s, c) = 10f64.to_radians().sin_cos();
    let (cx, cz) = (8.0 * s + 1.0, 8.0 * c);
    let (dx, dz) = (-s, -c);
    let still_cam = format!(
        "PerspectiveCamera {{ center {cx} 1 {cz} direction {dx} -0.1 {dz} up 0 1 0 angle 40 }}"
    );
    let still = scene(d, "still.txt", &still_cam, ball);
    let size = ["--size", "96", "72"];
    ok(&glint(
        &[
            &[
                "render", &moving, "--frame", "6", "--fps", "12", "-o", "f6.exr",
            ][..],
            &size,
        ]
        .concat(),
        d,
        &[],
    ));
    ok(&glint(
        &[&["render", &still, "-o", "still.exr"][..], &size].concat(),
        d,
        &[],
    ));
    let (mean, off) = compare(&pixels(&d.join("f6.exr")), &pixels(&d.join("still.exr")));
    println!("frame 6 vs still camera: mean {mean}, {off} of the pixels off");
    // The still camera's numbers are decimal roundings of the rig's pose
    // (about 1e-7 relative), so edge pixels could flip; measured: mean
    // 1.2e-8, no pixel off by 0.01.
    assert!(
        mean < 1e-5 && off < 0.001,
        "frame 6 vs still camera: {mean} {off}"
    );
}

/// A frame is a task: its number from the environment, `#` in the output
/// name, and its pieces merge into the frame bit for bit; pieces of two
/// frames refuse to merge.
#[test]
fn frames_are_tasks_and_their_pieces_merge_exactly() {
    let dir = scratch("anim-tasks");
    let d = dir.as_ref();
    let orbit = own_scene("animation_orbit.txt");
    let orbit = orbit.to_str().unwrap();
    let base = ["render", orbit, "--size", "64", "48", "--shadows", "-q"];
    ok(&glint(
        &[&base[..], &["--frame", "9", "-o", "whole.exr"]].concat(),
        d,
        &[],
    ));
    ok(&glint(
        &[
            &base[..],
            &["--frame-from-env", "TASK", "-o", "frame_####.exr"],
        ]
        .concat(),
        d,
        &[("TASK", "9")],
    ));
    assert_eq!(
        std::fs::read(d.join("whole.exr")).unwrap(),
        std::fs::read(d.join("frame_0009.exr")).unwrap(),
        "--frame-from-env TASK=9 differs from --frame 9"
    );
    let mut names = Vec::new();
    for i in 0..3 {
        let name = format!("p{i}.exr");
        let tile = format!("{i}/3");
        ok(&glint(
            &[&base[..], &["--frame", "9", "--tile", &tile, "-o", &name]].concat(),
            d,
            &[],
        ));
        names.push(name);
    }
    ok(&glint(
        &["merge", &names[0], &names[1], &names[2], "-o", "merged.exr"],
        d,
        &[],
    ));
    let a = pixels(&d.join("whole.exr"));
    let b = pixels(&d.join("merged.exr"));
    let bits = |v: &[Vec3]| -> Vec<u32> {
        v.iter()
            .flat_map(|p| p.to_array())
            .map(f32::to_bits)
            .collect()
    };
    assert!(bits(&a) == bits(&b), "merged pieces differ from the frame");
    // A piece of frame 10 among frame 9's: refused, nothing written.
    ok(&glint(
        &[
            &base[..],
            &["--frame", "10", "--tile", "1/3", "-o", "q1.exr"],
        ]
        .concat(),
        d,
        &[],
    ));
    let out = glint(
        &["merge", &names[0], "q1.exr", &names[2], "-o", "mixed.exr"],
        d,
        &[],
    );
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("q1.exr"), "{err}");
    assert!(!d.join("mixed.exr").exists());
}

#[test]
fn bad_frame_requests_exit_2() {
    let dir = scratch("anim-bad");
    let d = dir.as_ref();
    let orbit = own_scene("animation_orbit.txt");
    let orbit = orbit.to_str().unwrap();
    for (args, env, msg) in [
        (vec!["--frame", "3", "--fps", "0"], vec![], "--fps"),
        (vec!["--frame", "3", "--fps", "NaN"], vec![], "--fps"),
        (vec!["--frame", "20000000"], vec![], "frame number"),
        (vec!["--frame-from-env", "NOPE"], vec![], "not set"),
        (vec!["--frame-from-env", "T"], vec![("T", "x")], "T=x"),
    ] {
        let out = glint(
            &[
                &["render", orbit, "--size", "8", "8", "-o", "x.png"][..],
                &args,
            ]
            .concat(),
            d,
            &env,
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(msg), "{args:?}: {err}");
        assert!(!d.join("x.png").exists());
    }
}

/// `deploy/slurm/animation.sbatch` run as Slurm would run three of its
/// tasks: each writes its own frame, the one `--frame K` writes.
#[test]
fn the_slurm_animation_script_renders_its_frames() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = scratch("anim-slurm");
    let d = dir.as_ref();
    let bin = Path::new(env!("CARGO_BIN_EXE_glint")).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    std::fs::create_dir_all(d.join("scenes")).unwrap();
    std::fs::copy(
        root.join("scenes/animation_orbit.txt"),
        d.join("scenes/animation_orbit.txt"),
    )
    .unwrap();
    let script = root.join("deploy/slurm/animation.sbatch");
    let text = std::fs::read_to_string(&script).unwrap();
    assert!(text.contains("#SBATCH --array=0-47"));
    assert!(text.contains("--frame-from-env SLURM_ARRAY_TASK_ID"));
    for k in ["0", "23", "47"] {
        let out = Command::new("bash")
            .arg(&script)
            .env("PATH", &path)
            .env("SLURM_ARRAY_TASK_ID", k)
            .env("SIZE", "40 30")
            .env("SPP", "2")
            .current_dir(d)
            .output()
            .unwrap();
        ok(&out);
    }
    ok(&glint(
        &[
            "render",
            "scenes/animation_orbit.txt",
            "-o",
            "k23.png",
            "--size",
            "40",
            "30",
            "--spp",
            "2",
            "--shadows",
            "--frame",
            "23",
        ],
        d,
        &[],
    ));
    for k in ["0000", "0023", "0047"] {
        assert!(
            d.join(format!("frames/frame_{k}.png")).exists(),
            "frame {k}"
        );
    }
    assert_eq!(
        std::fs::read(d.join("frames/frame_0023.png")).unwrap(),
        std::fs::read(d.join("k23.png")).unwrap()
    );
}
