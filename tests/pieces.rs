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
    let merge = Command::new("bash")
        .arg(root.join("deploy/slurm/merge.sbatch"))
        .env("PATH", &path)
        .env("OUT", "slurm.exr")
        .current_dir(&dir)
        .output()
        .unwrap();
    ok(&merge);

    // Kubernetes: completions = N in the command; run the container's shell
    // command for every index.
    let yaml = std::fs::read_to_string(root.join("deploy/k8s/render-job.yaml")).unwrap();
    let completions: u32 = yaml
        .lines()
        .find_map(|l| l.trim().strip_prefix("completions:"))
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    assert!(yaml.contains("completionMode: Indexed"));
    let command = yaml
        .lines()
        .skip_while(|l| !l.trim().starts_with("args:"))
        .nth(1)
        .unwrap()
        .trim()
        .trim_start_matches("- ")
        .replace("/work/", "");
    assert!(
        command.contains(&format!(
            "--tile-from-env JOB_COMPLETION_INDEX/{completions}"
        )),
        "{command}"
    );
    std::fs::create_dir_all(dir.join("pieces-k8s")).unwrap();
    let command = command.replace("pieces/", "pieces-k8s/");
    for i in 0..completions {
        let out = Command::new("sh")
            .args(["-c", &command])
            .env("PATH", &path)
            .env("JOB_COMPLETION_INDEX", i.to_string())
            .env("SIZE", "48 36")
            .env("SPP", "2")
            .current_dir(&dir)
            .output()
            .unwrap();
        ok(&out);
    }
    let pieces: Vec<String> = (0..completions)
        .map(|i| format!("pieces-k8s/piece-{i}.exr"))
        .collect();
    let args: Vec<&str> = ["merge"]
        .into_iter()
        .chain(pieces.iter().map(String::as_str))
        .chain(["-o", "k8s.exr"])
        .collect();
    ok(&glint(&args, &dir));

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
    assert_eq!(
        std::fs::read(dir.join("k8s.exr")).unwrap(),
        s,
        "Kubernetes pieces differ"
    );
    assert!(std::fs::read_to_string(root.join("deploy/Dockerfile"))
        .unwrap()
        .contains("cargo build --release --bin glint"));
}
