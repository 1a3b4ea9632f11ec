//! Every deterministic image of the assignments' sample command lines,
//! rendered by the `raytracer` binary exactly as the line says and compared
//! with the independent reference renders in `../shared/reference/6837`.
//!
//! Tolerance (from the issue): mean absolute error ≤ 3 on the 0-255 scale and
//! at most 2% of pixels off by more than 24 in some channel. The reference is
//! one student's implementation, so an image where we are sure the reference
//! is wrong gets a wider, explained tolerance in `EXCEPTIONS`.

mod common;
use common::*;

/// Images whose reference we believe is wrong: (name, max mean abs, max fraction off, why).
///
/// The checkerboard renders. The reference implementation (its source is
/// public) has two quirks, both visible in these images:
/// 1. its checker is `sin(3x)·sin(3y)·sin(3z) > 0`, cells of π/3 ≈ 1.047
///    texture units instead of unit cells, so cell edges drift away from the
///    texture origin (by a whole cell across scene7_02's floor of 0.1-unit
///    cells);
/// 2. it gives textured surfaces no ambient light (its checkerboard's ambient
///    reflectance is 0), so every lit cell is 0.1-0.2 × 255 darker than ours;
///    ambient light × the diffuse colour at the point, as for any material, is
///    the physics.
///
/// `tests/textures.rs` reproduces exactly those two quirks and then matches
/// these references to the standard tolerance (mean abs 0.2-0.5), so the
/// pattern, its parity, the texture matrix and the world-space lookup are
/// right. The bounds here are the measured differences plus ~10%: they only
/// guard against the literal renders getting worse.
const EXCEPTIONS: &[(&str, f64, f64, &str)] = &[
    (
        "output6_13.tga",
        14.0,
        0.70,
        "sin checker, no ambient on textures (measured 12.5, 66%)",
    ),
    (
        "output6_14.tga",
        36.0,
        0.42,
        "sin checker, no ambient on textures (measured 33.2, 39%)",
    ),
    (
        "output7_02.tga",
        58.0,
        0.78,
        "sin checker, no ambient on textures (measured 54.6, 75%)",
    ),
    (
        "output7_05a.tga",
        37.0,
        0.42,
        "sin checker, no ambient on textures (measured 34.0, 39%)",
    ),
];

const MAX_MEAN_ABS: f64 = 3.0;
const MAX_FRAC_OFF: f64 = 0.02;

/// Every image-writing line of `file` except textured scenes (checked by
/// [`check_outputs`] and `tests/textures.rs`) and grid visualizations.
fn plain_lines(data: &CourseData, file: &str) -> Vec<CmdLine> {
    command_lines(&data.scenes, file)
        .into_iter()
        .filter(|l| !textured_or_visualization(&data.scenes, l))
        .collect()
}

fn check_assignment(test: &str, file: &str) {
    let Some(data) = course_data(test) else {
        return;
    };
    check_lines(&data, file, plain_lines(&data, file));
}

/// Whether a command line's scene uses solid textures or asks for a grid
/// visualization (not a render to compare).
fn textured_or_visualization(scenes: &std::path::Path, line: &CmdLine) -> bool {
    let scene = flag_value(&line.args, "-input").unwrap_or_default();
    let text = std::fs::read_to_string(scenes.join(scene)).unwrap_or_default();
    line.args.iter().any(|a| a.starts_with("-visualize_grid"))
        || ["Checkerboard", "Noise", "Marble", "Wood"]
            .iter()
            .any(|k| text.contains(k))
}

/// The lines of `file` that write one of `outputs`, exactly as written.
fn check_outputs(test: &str, file: &str, outputs: &[&str]) {
    let Some(data) = course_data(test) else {
        return;
    };
    let lines = outputs
        .iter()
        .map(|o| line_for(&data.scenes, file, o))
        .collect();
    check_lines(&data, &format!("{file}-{}", outputs.join("-")), lines);
}

/// Runs `lines` in a scratch folder named after `tag` and compares every
/// image; returns how many matched, panics listing the mismatches.
fn check_lines(data: &CourseData, tag: &str, lines: Vec<CmdLine>) -> usize {
    let dir = scratch(tag);
    let mut failures = Vec::new();
    let mut checked = 0;
    for line in lines {
        if let Err(e) = run_raytracer(&data.scenes, &line.args, &dir) {
            failures.push(format!("{}\n    failed to run: {e}", line.text));
            continue;
        }
        for name in &line.outputs {
            let (max_mean, max_off) = EXCEPTIONS
                .iter()
                .find(|e| e.0 == name)
                .map_or((MAX_MEAN_ABS, MAX_FRAC_OFF), |e| (e.1, e.2));
            let measured = diff(&dir.join(name), &reference_for(&data.refs, name));
            if let Ok(d) = &measured {
                // Shown with `--nocapture`: the numbers the tolerances come from.
                eprintln!(
                    "measured {tag} {name}: mean abs {:.3}, {:.3}% off",
                    d.mean_abs,
                    100.0 * d.frac_off
                );
            }
            match measured {
                Ok(d) if d.mean_abs <= max_mean && d.frac_off <= max_off => checked += 1,
                Ok(d) => failures.push(format!(
                    "{name}: mean abs {:.2} (max {max_mean}), {:.2}% pixels off (max {:.1}%)",
                    d.mean_abs,
                    100.0 * d.frac_off,
                    100.0 * max_off
                )),
                Err(e) => failures.push(format!("{name}: {e}")),
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} images matched; mismatches:\n{}",
        checked,
        failures.join("\n")
    );
    assert!(checked > 0, "no image was checked");
    checked
}

#[test]
fn assignment1_ray_casting() {
    check_assignment("assignment1_ray_casting", "A1_cmd.txt");
}

#[test]
fn assignment2_transforms_and_perspective() {
    check_assignment("assignment2_transforms_and_perspective", "A2_cmd.txt");
}

#[test]
fn assignment3_phong() {
    check_assignment("assignment3_phong", "A3_cmd.txt");
}

#[test]
fn assignment4_shadows_reflection_refraction() {
    check_assignment("assignment4_shadows_reflection_refraction", "A4_cmd.txt");
}

/// The deterministic textured lines of assignment 6 (one ray per pixel; the
/// `-visualize_grid` lines are out of scope). Noise, Marble and Wood cannot
/// match another implementation pixel for pixel: their mean colours are
/// checked in `tests/textures.rs`, which also shows that the checkerboards
/// below match to the standard tolerance once the reference's two quirks
/// (see `EXCEPTIONS`) are reproduced.
#[test]
fn assignment6_checkerboard_textures() {
    check_outputs(
        "assignment6_checkerboard_textures",
        "A6_cmd.txt",
        &["output6_13.tga", "output6_14.tga"],
    );
}

/// Assignment 7's checkerboard scenes rendered with one ray per pixel (the
/// sampling and filtering lines need flags `raytracer` does not have yet).
#[test]
fn assignment7_checkerboard_textures() {
    check_outputs(
        "assignment7_checkerboard_textures",
        "A7_cmd.txt",
        &["output7_02.tga", "output7_05a.tga"],
    );
}

/// Assignment 6's untextured renders (bunnies up to 40k triangles,
/// transforms, mirrors, glass) with every accelerator: the line's own `-grid`
/// size is kept for the grid (`-accel grid` after `-grid nx ny nz` keeps the
/// resolution); lines without `-grid` run the grid at its automatic resolution.
#[test]
fn assignment6_with_every_accelerator() {
    let Some(data) = course_data("assignment6_with_every_accelerator") else {
        return;
    };
    for accel in [
        "none",
        "grid",
        "octree",
        "bvh-sah",
        "bvh-median",
        "bvh-midpoint",
        "nested-grid",
        "octree-inner",
        "bvh-hierarchy",
        "bvh4",
    ] {
        let lines = plain_lines(&data, "A6_cmd.txt")
            .into_iter()
            .map(|mut l| {
                l.args.extend(["-accel".to_string(), accel.to_string()]);
                l
            })
            .collect();
        let n = check_lines(&data, &format!("A6-{accel}"), lines);
        assert!(n >= 20, "{accel}: only {n} images checked");
    }
}

/// Assignment 5's lines all ask for `-visualize_grid`: there is no plain
/// render among them to compare, which this test pins down so the suite
/// notices if the command file changes.
#[test]
fn assignment5_has_only_visualizations() {
    let Some(scenes) = scenes("assignment5_has_only_visualizations") else {
        return;
    };
    assert!(command_lines(&scenes, "A5_cmd.txt")
        .iter()
        .all(|l| textured_or_visualization(&scenes, l)));
}
