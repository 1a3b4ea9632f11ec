//! Pieces of a frame (`--tile I/N`, `--crop`) merge into exactly the image a
//! single render makes, wrong sets of pieces are refused, and the Slurm and
//! Kubernetes files of `deploy/` really render and merge a frame.

use crate::common::*;
use std::path::Path;
use std::process::Command;

fn glint(args: &[&str], dir: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_glint"))
        .args(args)
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

/// Renders `scene` whole and as `n` pieces, merges, and compares bit for bit.
fn pieces_equal_single(dir: &Path, scene: &str, flags: &[&str], n: u32) {
    let scene = own_scene(scene).to_string_lossy().into_owned();
    let base = [&["render", scene.as_str()][..], flags].concat();
    ok(&glint(&[&base[..], &["-o", "single.exr"]].concat(), dir));
    let mut names = Vec::new();
    for i in 0..n {
        let name = format!("piece-{n}-{i}.exr");
        let tile = format!("{i}/{n}");
        ok(&glint(
            &[&base[..], &["-o", &name, "--tile", &tile]].concat(),
            dir,
        ));
        names.push(name);
    }
    let merged = format!("merged-{n}.exr");
    let args: Vec<&str> = ["merge"]
        .into_iter()
        .chain(names.iter().map(String::as_str))
        .chain(["-o", &merged])
        .collect();
    ok(&glint(&args, dir));
    let a = glint::output::read_exr_window(&dir.join("single.exr")).unwrap();
    let b = glint::output::read_exr_window(&dir.join(&merged)).unwrap();
    assert_eq!(a.display, b.display);
    let same = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .all(|(p, q)| p.to_array().map(f32::to_bits) == q.to_array().map(f32::to_bits));
    assert!(same, "{scene} {flags:?}: {n} pieces differ from one render");
    assert_eq!(
        std::fs::read(dir.join("single.exr")).unwrap(),
        std::fs::read(dir.join(&merged)).unwrap(),
        "the files differ"
    );
}

#[test]
fn one_four_and_seven_pieces_merge_bit_for_bit() {
    let dir = scratch("pieces");
    // A wide Gaussian (support 3 pixels) reaching across piece borders.
    let wide = [
        "--size",
        "61",
        "47",
        "--spp",
        "4",
        "--sampler",
        "uniform",
        "--filter",
        "gaussian:1.5",
        "--shadows",
        "--bounces",
        "3",
        "--quiet",
    ];
    // Stochastic sampling and a tent filter, on a mesh.
    let random = [
        "--size",
        "53",
        "40",
        "--spp",
        "5",
        "--sampler",
        "random",
        "--seed",
        "11",
        "--filter",
        "tent:1.3",
        "--shadows",
        "--quiet",
    ];
    // The path tracer: every bounce's dimensions from the pixel's stream.
    let path = [
        "--size",
        "29",
        "23",
        "--spp",
        "3",
        "--integrator",
        "path",
        "--bounces",
        "6",
        "--quiet",
    ];
    for n in [1, 4, 7] {
        pieces_equal_single(&dir, "whitted.txt", &wide, n);
        pieces_equal_single(&dir, "mesh_knot_1k.txt", &random, n);
        pieces_equal_single(&dir, "cornell_caustics.txt", &path, n);
        // The caustic photon map: every piece builds the same one.
        let mapped = [&path[..], &["--caustic-photons", "20000"]].concat();
        pieces_equal_single(&dir, "cornell_caustics.txt", &mapped, n);
    }
    // A crop's pixels equal the whole render's in that rectangle.
    let scene = own_scene("whitted.txt").to_string_lossy().into_owned();
    let base = [&["render", scene.as_str()][..], &wide[..]].concat();
    ok(&glint(&[&base[..], &["-o", "single.exr"]].concat(), &dir));
    ok(&glint(
        &[&base[..], &["-o", "c.exr", "--crop", "10", "5", "33", "29"]].concat(),
        &dir,
    ));
    let c = glint::output::read_exr_window(&dir.join("c.exr")).unwrap();
    let s = glint::output::read_exr_window(&dir.join("single.exr")).unwrap();
    assert_eq!(c.window, (10, 5, 23, 24));
    assert_eq!(c.display, (61, 47));
    for row in 0..24 {
        for x in 0..23 {
            assert_eq!(
                c.pixels[row * 23 + x],
                s.pixels[(row + 5) * 61 + x + 10],
                "crop pixel {x},{row}"
            );
        }
    }
    assert!(c
        .attributes
        .iter()
        .any(|(k, v)| k == "glint.piece" && v == "crop 10 5 33 29"));
}

#[test]
fn wrong_sets_of_pieces_are_refused_and_nothing_is_written() {
    let dir = scratch("pieces-bad");
    let scene = own_scene("whitted.txt").to_string_lossy().into_owned();
    // 100 rows: four rows of 32-pixel render tiles, so three pieces split
    // along tile rows and render no pixel twice (box filter, no margin).
    let flags = ["--size", "40", "100", "--spp", "2", "--quiet"];
    for i in 0..3 {
        let (name, tile) = (format!("p{i}.exr"), format!("{i}/3"));
        ok(&glint(
            &[
                &["render", &scene][..],
                &flags,
                &["-o", &name, "--tile", &tile],
            ]
            .concat(),
            &dir,
        ));
    }
    // Other settings (4 samples instead of 2) for piece 1.
    ok(&glint(
        &[
            "render",
            &scene,
            "--size",
            "40",
            "30",
            "--spp",
            "4",
            "--quiet",
            "-o",
            "other.exr",
            "--tile",
            "1/3",
        ],
        &dir,
    ));
    for (pieces, wants) in [
        (&["p0.exr", "p2.exr"][..], &["missing pieces: tile 1/3"][..]),
        (
            &["p0.exr", "p1.exr", "p1.exr", "p2.exr"][..],
            &["overlap", "p1.exr (tile 1/3)"][..],
        ),
        (
            &["p0.exr", "other.exr", "p2.exr"][..],
            &["different renders", "other.exr (tile 1/3)"][..],
        ),
    ] {
        let args: Vec<&str> = ["merge"]
            .into_iter()
            .chain(pieces.iter().copied())
            .chain(["-o", "out.png"])
            .collect();
        let out = glint(&args, &dir);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{pieces:?}: {err}");
        for w in wants {
            assert!(err.contains(w), "{pieces:?}: {w:?} missing from {err}");
        }
        assert!(!dir.join("out.png").exists(), "{pieces:?}: wrote an image");
    }
    // The good set works, with merged statistics.
    ok(&glint(
        &[
            "merge",
            "p0.exr",
            "p1.exr",
            "p2.exr",
            "-o",
            "out.png",
            "--stats-json",
            "s.json",
        ],
        &dir,
    ));
    let stats: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("s.json")).unwrap()).unwrap();
    assert_eq!(stats["pieces"], 3);
    assert_eq!(stats["rays_primary"], 40 * 100 * 2);
    // Bad piece requests exit 2 before any work.
    for bad in [
        &["--tile", "3/3"][..],
        &["--tile", "1/101"][..],
        &["--crop", "0", "0", "41", "100"][..],
        &["--tile-from-env", "NO_SUCH_VAR_GLINT/3"][..],
    ] {
        let out = glint(
            &[&["render", &scene][..], &flags, &["-o", "x.exr"], bad].concat(),
            &dir,
        );
        assert_eq!(out.status.code(), Some(2), "{bad:?}");
    }
    let out = glint(
        &[
            &["render", &scene][..],
            &flags,
            &["-o", "x.png", "--tile", "0/3"],
        ]
        .concat(),
        &dir,
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains(".exr"));
}

/// Runs the files of `deploy/` as a scheduler would, index by index, with
/// the real `glint` on the PATH and a small frame, and checks that merging
/// the pieces gives the single render.
#[test]
fn slurm_script_and_kubernetes_job_render_mergeable_pieces() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = scratch("deploy");
    let bin = Path::new(env!("CARGO_BIN_EXE_glint")).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    std::fs::create_dir_all(dir.join("scenes")).unwrap();
    std::fs::copy(
        root.join("scenes/whitted.txt"),
        dir.join("scenes/whitted.txt"),
    )
    .unwrap();

    // Slurm: the array's size is the script's N; run each task.
    let sbatch = std::fs::read_to_string(root.join("deploy/slurm/render.sbatch")).unwrap();
    let array = sbatch
        .lines()
        .find_map(|l| l.strip_prefix("#SBATCH --array=0-"))
        .unwrap();
    let tasks: u32 = array.trim().parse::<u32>().unwrap() + 1;
    assert!(
        sbatch.contains(&format!("N={tasks}")),
        "N differs from the array size"
    );
    assert!(sbatch.contains("--tile-from-env SLURM_ARRAY_TASK_ID/$N"));
    for i in 0..tasks {
        let out = Command::new("bash")
            .arg(root.join("deploy/slurm/render.sbatch"))
            .env("PATH", &path)
            .env("SLURM_ARRAY_TASK_ID", i.to_string())
            .env("SIZE", "48 36")
            .env("SPP", "2")
            .current_dir(&dir)
            .output()
            .unwrap();
        ok(&out);
    }
    // Without glint on the PATH a task says how to get it there, exit 2.
    let bare = Command::new("bash")
        .arg(root.join("deploy/slurm/render.sbatch"))
        .env("PATH", "/usr/bin:/bin")
        .env("SLURM_ARRAY_TASK_ID", "0")
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(bare.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bare.stderr).contains("cargo install --path ."));
    let merge = Command::new("bash")
        .arg(root.join("deploy/slurm/merge.sbatch"))
        .env("PATH", &path)
        .env("OUT", "slurm.exr")
        .current_dir(&dir)
        .output()
        .unwrap();
    ok(&merge);

    // Kubernetes: the image laid out as deploy/Dockerfile builds it, the
    // volume an empty folder at its mount path, every pod of the render Job
    // and then the merge Job run exactly as the manifests say, chrooted
    // into the image (scripts/container_sim.py); only SIZE and SPP, the
    // manifest's own variables, are set smaller.
    let yaml = std::fs::read_to_string(root.join("deploy/k8s/render-job.yaml")).unwrap();
    let completions: u32 = yaml
        .lines()
        .find_map(|l| l.trim().strip_prefix("completions:"))
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    assert!(yaml.contains("completionMode: Indexed"));
    assert!(
        yaml.contains(&format!(
            "--tile-from-env JOB_COMPLETION_INDEX/{completions}"
        )),
        "the command's N differs from completions"
    );
    let k8s = if python_has_yaml() {
        std::fs::create_dir_all(dir.join("k8s")).unwrap();
        let sim = Command::new("python3")
            .arg(root.join("scripts/container_sim.py"))
            .arg(bin)
            .arg(dir.join("k8s"))
            .args(["--env", "SIZE=48 36", "--env", "SPP=2"])
            .arg(root.join("deploy/k8s/render-job.yaml"))
            .arg(root.join("deploy/k8s/merge-job.yaml"))
            .output()
            .unwrap();
        ok(&sim);
        Some(dir.join("k8s/root/work/frame.exr"))
    } else {
        None
    };

    // Both equal the single render with the same flags.
    let single = [
        "render",
        "scenes/whitted.txt",
        "-o",
        "single.exr",
        "--size",
        "48",
        "36",
        "--spp",
        "2",
        "--sampler",
        "sobol",
        "--filter",
        "gaussian:0.5",
        "--shadows",
        "--shade-back",
        "--bounces",
        "5",
        "--quiet",
    ];
    ok(&glint(&single, &dir));
    let s = std::fs::read(dir.join("single.exr")).unwrap();
    assert_eq!(
        std::fs::read(dir.join("slurm.exr")).unwrap(),
        s,
        "Slurm pieces differ"
    );
    if let Some(frame) = k8s {
        assert_eq!(
            std::fs::read(frame).unwrap(),
            s,
            "the Kubernetes Jobs' frame differs"
        );
    }
    assert!(std::fs::read_to_string(root.join("deploy/Dockerfile"))
        .unwrap()
        .contains("cargo build --release --bin glint"));
    // The build context leaves the build folder out.
    let ignore = std::fs::read_to_string(root.join(".dockerignore")).unwrap();
    assert!(ignore.lines().any(|l| l.trim() == "target/"));
}

/// Whether `python3` with PyYAML is here for `scripts/container_sim.py`
/// (CI installs it and sets `GLINT_REQUIRE_PYYAML=1`, so it cannot skip).
fn python_has_yaml() -> bool {
    let has = Command::new("python3")
        .args(["-c", "import yaml"])
        .status()
        .is_ok_and(|s| s.success());
    if !has {
        assert!(
            std::env::var("GLINT_REQUIRE_PYYAML").as_deref() != Ok("1"),
            "python3 has no PyYAML, and GLINT_REQUIRE_PYYAML=1"
        );
        eprintln!("skipped the Kubernetes simulation: python3 has no PyYAML (set GLINT_REQUIRE_PYYAML=1 to require it)");
    }
    has
}

/// A crop anywhere (one pixel, one tile, across tiles, at every edge and
/// corner) of an image seven tiles wide and three high renders exactly the
/// whole render's pixels there and exits 0 without a `.partial` file, with a
/// filter inside its pixel and with one reaching three pixels out; `--tile`
/// bands of the same image merge into it bit for bit.
#[test]
fn crops_anywhere_on_an_image_many_tiles_wide_are_exact_and_complete() {
    let dir = scratch("crops");
    let scene = own_scene("whitted.txt").to_string_lossy().into_owned();
    let (w, h) = (200usize, 70usize); // 7 x 3 tiles of 32
    for filter in ["box:0.5", "gaussian:1.5"] {
        let base = [
            "render",
            scene.as_str(),
            "--size",
            "200",
            "70",
            "--spp",
            "2",
            "--sampler",
            "sobol",
            "--filter",
            filter,
            "--shadows",
            "--quiet",
        ];
        ok(&glint(&[&base[..], &["-o", "full.exr"]].concat(), &dir));
        let full = glint::output::read_exr_window(&dir.join("full.exr")).unwrap();
        let crops: [[usize; 4]; 9] = [
            [100, 35, 101, 36], // one pixel
            [64, 32, 96, 64],   // exactly one tile
            [40, 10, 130, 50],  // across tiles
            [0, 0, 1, 1],       // top-left corner pixel
            [199, 69, 200, 70], // bottom-right corner pixel
            [150, 0, 200, 70],  // right edge, full height
            [0, 60, 200, 70],   // bottom edge, full width
            [0, 20, 13, 41],    // left edge
            [31, 31, 33, 33],   // four tiles' corner
        ];
        for [x0, y0, x1, y1] in crops {
            let name = format!("crop-{x0}-{y0}-{x1}-{y1}.exr");
            let c: Vec<String> = [x0, y0, x1, y1].iter().map(|v| v.to_string()).collect();
            let out = glint(
                &[
                    &base[..],
                    &["-o", &name, "--crop", &c[0], &c[1], &c[2], &c[3]],
                ]
                .concat(),
                &dir,
            );
            assert_eq!(
                out.status.code(),
                Some(0),
                "{filter} crop {c:?}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            assert!(!dir.join(name.replace(".exr", ".partial.exr")).exists());
            let p = glint::output::read_exr_window(&dir.join(&name)).unwrap();
            let (cw, ch) = (x1 - x0, y1 - y0);
            assert_eq!(p.window, (x0 as u32, y0 as u32, cw as u32, ch as u32));
            for row in 0..ch {
                for x in 0..cw {
                    let (a, b) = (p.pixels[row * cw + x], full.pixels[(row + y0) * w + x + x0]);
                    assert_eq!(
                        a.to_array().map(f32::to_bits),
                        b.to_array().map(f32::to_bits),
                        "{filter} crop {c:?}: pixel ({}, {})",
                        x + x0,
                        row + y0
                    );
                }
            }
        }
        // --tile bands of the same wide image: each exits 0, and they merge
        // into the whole render's file.
        let mut names = Vec::new();
        for i in 0..5 {
            let name = format!("band-{i}.exr");
            let out = glint(
                &[&base[..], &["-o", &name, "--tile", &format!("{i}/5")]].concat(),
                &dir,
            );
            assert_eq!(out.status.code(), Some(0), "{filter} tile {i}/5");
            names.push(name);
        }
        let args: Vec<&str> = ["merge"]
            .into_iter()
            .chain(names.iter().map(String::as_str))
            .chain(["-o", "bands.exr"])
            .collect();
        ok(&glint(&args, &dir));
        assert_eq!(
            std::fs::read(dir.join("bands.exr")).unwrap(),
            std::fs::read(dir.join("full.exr")).unwrap(),
            "{filter}: bands differ from the whole render"
        );
        assert_eq!(h, full.display.1 as usize);
    }
}
