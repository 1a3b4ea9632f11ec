//! Assignment 7 (supersampling and filtering): every command line of
//! `commands/A7_cmd.txt` runs, and its images are compared with the
//! independent reference renders.
//!
//! - Deterministic images (uniform samples, the `-render_samples` view with
//!   uniform samples, every `-render_filter` view) are compared pixel by
//!   pixel: mean absolute difference and fraction of pixels off by more than
//!   24, with a bound per image = the measured difference plus about 10%
//!   (0.05 / 0 where we match exactly), and the reason for any difference.
//! - Random and jittered images cannot match pixel for pixel: their mean
//!   colour and their edge sharpness are compared.
//!
//! Findings about the reference (measured with the scripts' numbers quoted
//! below, see also ARCHITECTURE.md "Sampling"):
//! 1. Its uniform sampler puts `k×k` samples at `(a+1)/(k+1)` (2×2 at 1/3 and
//!    2/3), not at cell centres; `raytracer -uniform_samples` reproduces that
//!    (`GridLayout::Inset`), glint's `--sampler uniform` uses cell centres.
//!    Its sample positions map to screen point `(i + s)/w`, as glint does.
//! 2. Its gaussian is not cut at 2σ (only by the pixel support
//!    `⌈2σ − 0.5⌉`), so its kernel is square. `raytracer -gaussian_filter`
//!    uses that kernel (`Filter::GaussianSquare`) and matches filter7_01f,
//!    filter7_01i, filter7_01c_low_res and filter7_02c exactly; `glint
//!    render --filter gaussian:σ` keeps the round kernel cut at 2σ.
//! 3. Its filter7_01c (`-gaussian_filter 0.5`) was drawn with σ = 0.4:
//!    `raytracer -gaussian_filter 0.4` reproduces it exactly. A suspect
//!    reference.
//! 4. scene7_01's hypotenuse lies on `x + y = 0`, through lattice sample
//!    points, so at 12×12 a few edge pixels flip with rounding (each is 0.7%
//!    of the image). The watertight triangle test (`docs/numerics.md`)
//!    computes the edge functions exactly, so a sample exactly on the edge
//!    counts as inside; Möller–Trumbore's rounding decided some of them the
//!    other way.
//! 5. The checkerboard scenes carry the reference's texture quirks (see
//!    `tests/reference_images.rs`), hence their wide bounds.

use crate::common::*;

/// Deterministic images: (name, max mean abs, max fraction off, why).
const DETERMINISTIC: &[(&str, f64, f64, &str)] = &[
    ("filter7_01a.tga", 0.05, 0.0, "exact (measured 0)"),
    ("filter7_01b.tga", 0.05, 0.0, "exact (measured 0)"),
    (
        "filter7_01c.tga",
        1.7,
        0.032,
        "reference drawn with sigma 0.4 (measured 1.54, 2.86%; sigma 0.4 matches exactly)",
    ),
    ("filter7_01d.tga", 0.05, 0.0, "exact (measured 0)"),
    ("filter7_01e.tga", 0.05, 0.0, "exact (measured 0.001)"),
    ("filter7_01f.tga", 0.05, 0.0, "exact (measured 0)"),
    ("filter7_01g.tga", 0.05, 0.0, "exact (measured 0)"),
    ("filter7_01h.tga", 0.05, 0.0, "exact (measured 0)"),
    ("filter7_01i.tga", 0.05, 0.0, "exact (measured 0)"),
    ("filter7_01a_low_res.tga", 0.05, 0.0, "exact (measured 0)"),
    ("filter7_01b_low_res.tga", 0.05, 0.0, "exact (measured 0)"),
    ("filter7_01c_low_res.tga", 0.05, 0.0, "exact (measured 0)"),
    ("filter7_02a.tga", 0.05, 0.0, "exact (measured 0)"),
    ("filter7_02b.tga", 0.05, 0.0, "exact (measured 0)"),
    ("filter7_02c.tga", 0.05, 0.0, "exact (measured 0)"),
    (
        "samples7_01b.tga",
        0.2,
        0.002,
        "a few samples on the hypotenuse (measured 0.03, 0.02%)",
    ),
    (
        "samples7_01e.tga",
        0.2,
        0.002,
        "a few samples on the hypotenuse (measured 0.04, 0.03%)",
    ),
    (
        "samples7_01h.tga",
        0.2,
        0.002,
        "a few samples on the hypotenuse (measured 0.09, 0.06%)",
    ),
    (
        "samples7_01b_low_res.tga",
        0.2,
        0.002,
        "a few samples on the hypotenuse (measured 0.08, 0.05%)",
    ),
    (
        "samples7_02b.tga",
        2.5,
        0.034,
        "checker quirk recolours samples (measured 2.26, 3.03%)",
    ),
    (
        "output7_01d_low_res.tga",
        2.2,
        0.077,
        "hypotenuse ties at 12x12 (measured 1.94, 6.94%)",
    ),
    (
        "output7_01e_low_res.tga",
        2.3,
        0.030,
        "hypotenuse ties at 12x12; the watertight triangle test counts samples exactly on the edge as inside, one pixel more than before (measured 2.08, 2.78%)",
    ),
    (
        "output7_01f_low_res.tga",
        2.4,
        0.001,
        "hypotenuse ties at 12x12, no pixel off by more than 24 (measured 2.16, 0%)",
    ),
    (
        "output7_02d.tga",
        46.0,
        0.83,
        "checker quirks (measured 41.9, 75.2%)",
    ),
    (
        "output7_02e.tga",
        35.0,
        0.83,
        "checker quirks (measured 31.5, 75.2%)",
    ),
    (
        "output7_02f.tga",
        37.0,
        0.83,
        "checker quirks (measured 33.3, 75.3%)",
    ),
];

/// Runs every line of A7_cmd.txt once into `dir`; panics naming the lines
/// that fail.
fn run_all(data: &CourseData, dir: &std::path::Path) -> Vec<CmdLine> {
    let lines = command_lines(&data.scenes, "A7_cmd.txt");
    assert!(
        lines.len() >= 60,
        "A7_cmd.txt has {} image lines",
        lines.len()
    );
    let failures: Vec<String> = lines
        .iter()
        .filter_map(|l| {
            run_raytracer(&data.scenes, &l.args, dir)
                .err()
                .map(|e| format!("{}: {e}", l.text))
        })
        .collect();
    assert!(
        failures.is_empty(),
        "lines failed:\n{}",
        failures.join("\n")
    );
    lines
}

/// Mean of `|∂x| + |∂y|` over the image and channels: how sharp its edges
/// are (antialiasing and wider filters lower it).
fn sharpness(w: u32, h: u32, px: &[[u8; 3]]) -> f64 {
    let (w, h) = (w as usize, h as usize);
    let mut sum = 0.0;
    for y in 0..h {
        for x in 0..w {
            let here = px[y * w + x];
            let right = (x + 1 < w).then(|| px[y * w + x + 1]);
            let below = (y + 1 < h).then(|| px[(y + 1) * w + x]);
            for (c, &v) in here.iter().enumerate() {
                for n in right.iter().chain(below.iter()) {
                    sum += (n[c] as f64 - v as f64).abs();
                }
            }
        }
    }
    sum / (3 * w * h) as f64
}

/// The stochastic output lines and the one-ray render of the same scene
/// they are measured against, with whether their mean colour can be compared
/// with the reference directly (untextured scenes) or only its change from
/// the one-ray render (textured scenes whose texture differs by design),
/// or not at all (scene7_02's checker at 0.1-unit cells: a different pattern
/// aliases differently).
const STOCHASTIC: &[(&str, &str, Mean)] = &[
    (
        "output7_01a_low_res.tga",
        "output7_01_low_res.tga",
        Mean::Direct,
    ),
    (
        "output7_01b_low_res.tga",
        "output7_01_low_res.tga",
        Mean::Direct,
    ),
    (
        "output7_01c_low_res.tga",
        "output7_01_low_res.tga",
        Mean::Direct,
    ),
    (
        "output7_01g_low_res.tga",
        "output7_01_low_res.tga",
        Mean::Direct,
    ),
    (
        "output7_01h_low_res.tga",
        "output7_01_low_res.tga",
        Mean::Direct,
    ),
    (
        "output7_01i_low_res.tga",
        "output7_01_low_res.tga",
        Mean::Direct,
    ),
    ("output7_02a.tga", "output7_02.tga", Mean::None),
    ("output7_02b.tga", "output7_02.tga", Mean::None),
    ("output7_02c.tga", "output7_02.tga", Mean::None),
    ("output7_02g.tga", "output7_02.tga", Mean::None),
    ("output7_02h.tga", "output7_02.tga", Mean::None),
    ("output7_02i.tga", "output7_02.tga", Mean::None),
    ("output7_03b.tga", "output7_03a.tga", Mean::Shift),
    ("output7_03c.tga", "output7_03a.tga", Mean::Shift),
    ("output7_03d.tga", "output7_03a.tga", Mean::Shift),
    ("output7_04b.tga", "output7_04a.tga", Mean::Shift),
    ("output7_05b.tga", "output7_05a.tga", Mean::Shift),
    ("output7_05c.tga", "output7_05a.tga", Mean::Shift),
    ("output7_06b.tga", "output7_06a.tga", Mean::Direct),
];

#[derive(Clone, Copy, PartialEq)]
enum Mean {
    Direct,
    Shift,
    None,
}

/// Mean colour bound for [`Mean::Direct`] at 12×12, 0-255 scale: one pixel
/// is 0.7% of the image, and an edge pixel on the hypotenuse's ties moves a
/// channel's mean by up to 1.8 (measured worst 6.1, blue of 7_01i).
const MEAN_12: f64 = 7.0;
/// The same at 200×200 (measured 0.25 for 7_06b).
const MEAN_LARGE: f64 = 0.5;
/// Bound on the change of mean from the one-ray render, ours against the
/// reference's (measured worst 0.19).
const SHIFT: f64 = 0.4;
/// Bound on the sharpness ratio (antialiased / one ray), ours minus the
/// reference's (measured worst 0.118, 7_03b: textures differ). Both must
/// also be below 1.15.
const SHARPNESS: f64 = 0.14;

/// The `-gaussian_filter 0.4` renders whose reference is sharper than the
/// course's kernel of σ = 0.4 makes them: ours (that kernel, which the
/// references' filter views match exactly at σ = 0.6, 1.0, 1.7 and 2.3) is
/// blurrier by this much at most (measured 0.120-0.172, worst output7_03b;
/// a square kernel of σ = 0.25 measures 0.940 there, the reference 0.943).
/// The references' smallest σ are suspect (filter7_01c, drawn for 0.5, is
/// exactly σ = 0.4), so these may only be blurrier than the reference, by at
/// most [`SMALL_SIGMA_BLUR`], and never sharper by more than [`SHARPNESS`].
const SMALL_SIGMA: &[&str] = &[
    "output7_03b.tga",
    "output7_03c.tga",
    "output7_03d.tga",
    "output7_04b.tga",
    "output7_05b.tga",
    "output7_05c.tga",
];
const SMALL_SIGMA_BLUR: f64 = 0.19;

#[test]
fn assignment7_every_line_runs_and_matches() {
    let Some(data) = course_data("assignment7_every_line_runs_and_matches") else {
        return;
    };
    let scratch = scratch("A7-sampling");
    let dir = scratch.as_ref();
    let lines = run_all(&data, dir);
    let mut failures = Vec::new();

    // Every image named on a line was written.
    for l in &lines {
        for o in &l.outputs {
            if !dir.join(o).exists() {
                failures.push(format!("{o}: not written by `{}`", l.text));
            }
        }
    }

    for &(name, max_mean, max_off, why) in DETERMINISTIC {
        let measured = diff(&dir.join(name), &reference_for(&data.refs, name));
        if let Ok(d) = &measured {
            // Shown with `--nocapture`: the numbers the bounds come from.
            eprintln!(
                "measured {name}: mean abs {:.3}, {:.3}% off",
                d.mean_abs,
                100.0 * d.frac_off
            );
        }
        match measured {
            Ok(d) if d.mean_abs <= max_mean && d.frac_off <= max_off => {}
            Ok(d) => failures.push(format!(
                "{name}: mean abs {:.3} (max {max_mean}), {:.2}% off (max {:.1}%) [{why}]",
                d.mean_abs,
                100.0 * d.frac_off,
                100.0 * max_off
            )),
            Err(e) => failures.push(format!("{name}: {e}")),
        }
    }

    let load = |p: std::path::PathBuf| load_rgb8(&p).unwrap_or_else(|e| panic!("{e}"));
    for &(name, base, mean) in STOCHASTIC {
        let (w, h, ours) = load(dir.join(name));
        let (_, _, ours1) = load(dir.join(base));
        let (rw, rh, refs) = load(reference_for(&data.refs, name));
        let (_, _, refs1) = load(reference_for(&data.refs, base));
        assert_eq!((w, h), (rw, rh), "{name}");
        let (mo, mr) = (mean_rgb(&ours), mean_rgb(&refs));
        match mean {
            Mean::Direct => {
                let bound = if w <= 12 { MEAN_12 } else { MEAN_LARGE };
                if (0..3).any(|c| (mo[c] - mr[c]).abs() > bound) {
                    failures.push(format!(
                        "{name}: mean {mo:.1?} vs reference {mr:.1?} (max {bound})"
                    ));
                }
            }
            Mean::Shift => {
                let (mo1, mr1) = (mean_rgb(&ours1), mean_rgb(&refs1));
                let so: Vec<f64> = (0..3).map(|c| mo[c] - mo1[c]).collect();
                let sr: Vec<f64> = (0..3).map(|c| mr[c] - mr1[c]).collect();
                if (0..3).any(|c| (so[c] - sr[c]).abs() > SHIFT) {
                    failures.push(format!(
                        "{name}: mean moved by {so:.2?} from one ray, reference by {sr:.2?}"
                    ));
                }
            }
            Mean::None => {}
        }
        let ro = sharpness(w, h, &ours) / sharpness(w, h, &ours1);
        let rr = sharpness(w, h, &refs) / sharpness(w, h, &refs1);
        eprintln!("measured {name}: sharpness {ro:.3}, reference {rr:.3}");
        let blur_allowed = if SMALL_SIGMA.contains(&name) {
            SMALL_SIGMA_BLUR
        } else {
            SHARPNESS
        };
        if ro - rr > SHARPNESS || rr - ro > blur_allowed || ro > 1.15 {
            failures.push(format!(
                "{name}: sharpness {ro:.3} of the one-ray render's, reference {rr:.3}"
            ));
        }
    }

    // Random and jittered sample views: the same picture up to where the
    // dots fall. Mean colours agree (measured within 0.6), and every pixel
    // block holds its n dots (a few may coincide at 20× zoom).
    for l in lines
        .iter()
        .filter(|l| l.args.iter().any(|a| a == "-render_samples"))
    {
        if l.args.iter().any(|a| a == "-uniform_samples") {
            continue;
        }
        let name = &l.outputs[0];
        let (w, h, ours) = load(dir.join(name));
        let (_, _, refs) = load(reference_for(&data.refs, name));
        let (mo, mr) = (mean_rgb(&ours), mean_rgb(&refs));
        if (0..3).any(|c| (mo[c] - mr[c]).abs() > 1.0) {
            failures.push(format!("{name}: mean {mo:.2?} vs reference {mr:.2?}"));
        }
        let n: usize = ["-random_samples", "-jittered_samples"]
            .iter()
            .find_map(|f| flag_value(&l.args, f))
            .unwrap()
            .parse()
            .unwrap();
        let size: usize = flag_value(&l.args, "-size").unwrap().parse().unwrap();
        let dots = ours
            .iter()
            .filter(|p| **p != [0, 0, 0] && **p != [51, 51, 51])
            .count();
        let want = n * size * size;
        if dots > want || (dots as f64) < 0.9 * want as f64 {
            failures.push(format!(
                "{name} ({w}x{h}): {dots} sample dots, expected about {want}"
            ));
        }
    }

    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `raytracer -gaussian_filter σ` uses the course implementations' square
/// kernel (limited only by the pixel support `⌈2σ − 0.5⌉`), so its filter
/// views match the references to the standard image tolerance (mean 1.0,
/// 0.5% of pixels off by more than 24, as `tests/reference_images.rs`'s
/// core images); `glint render --filter gaussian:σ` keeps the round kernel
/// cut at 2σ, and the same view is then visibly off the reference.
#[test]
fn raytracer_gaussian_is_the_courses_square_kernel_glint_cuts_at_two_sigma() {
    let Some(data) = course_data("raytracer_gaussian_square_kernel") else {
        return;
    };
    let dir = scratch("gaussian-kernels");
    // filter7_01c's reference, drawn for `-gaussian_filter 0.5`, is exactly
    // the square kernel of σ = 0.4 (the line's own σ is 1.54 off).
    let c = line_for(&data.scenes, "A7_cmd.txt", "filter7_01c.tga");
    let mut args = c.args.clone();
    let i = args.iter().position(|a| a == "-gaussian_filter").unwrap();
    args[i + 1] = "0.4".into();
    run_raytracer(&data.scenes, &args, &dir).unwrap();
    let d = diff(
        &dir.join("filter7_01c.tga"),
        &reference_for(&data.refs, "filter7_01c.tga"),
    );
    assert_eq!(d.unwrap().mean_abs, 0.0, "filter7_01c at sigma 0.4");
    let scene = std::fs::canonicalize(data.scenes.join("scene7_01_sphere_triangle.txt")).unwrap();
    for (name, sigma) in [("filter7_01f.tga", "1.7"), ("filter7_01i.tga", "2.3")] {
        let line = line_for(&data.scenes, "A7_cmd.txt", name);
        assert_eq!(flag_value(&line.args, "-gaussian_filter"), Some(sigma));
        run_raytracer(&data.scenes, &line.args, &dir).unwrap();
        let reference = reference_for(&data.refs, name);
        let d = diff(&dir.join(name), &reference).unwrap();
        assert!(
            d.mean_abs <= 1.0 && d.frac_off <= 0.005,
            "raytracer {name}: {d:?}"
        );

        let glint_out = format!("glint_{name}");
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
            .args(["render", "--quiet"])
            .arg(&scene)
            .args(["--size", "9", "9", "--output", "glint_render.tga"])
            .args(["--render-filter", &glint_out, "20"])
            .args(["--filter", &format!("gaussian:{sigma}")])
            .current_dir(&dir)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let g = diff(&dir.join(&glint_out), &reference).unwrap();
        // The round cut zeroes the support square's corners, which the
        // reference draws grey: measured 2.89 / 5.46% (1.7), 3.56 / 6.72% (2.3).
        assert!(
            g.mean_abs > 2.0 && g.frac_off > 0.04,
            "glint render {name} should keep the 2-sigma cut: {g:?}"
        );
    }
}
