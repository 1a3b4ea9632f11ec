//! Every deterministic image of the assignments' sample command lines,
//! rendered by the `raytracer` binary exactly as the line says and compared
//! with the independent reference renders in `../shared/reference/6837`.
//!
//! **Tolerance** (issue 18): set from the measured differences plus a margin,
//! tight enough that a render moved by one pixel fails. The core images are
//! allowed a mean absolute error of [`CORE`]`.mean` on the 0-255 scale and
//! [`CORE`]`.frac` of their pixels off by more than 24 in some channel;
//! images measured above that are listed in [`WIDER`] with their numbers.
//! [`check_lines`] proves the point on every render it checks: the render
//! moved one pixel in each direction, and a blank image, must fail, and
//! [`the_checker_rejects_shifted_and_blank_references`] does the same with
//! the references alone.
//!
//! The reference is one student's implementation, so an image where we are
//! sure the reference is wrong gets an explained tolerance in `EXCEPTIONS`,
//! and its quirks are reproduced and compared pixel by pixel in
//! `tests/textures.rs`.

use crate::common::*;

/// What one image may differ from its reference by.
#[derive(Clone, Copy, Debug)]
struct Tolerance {
    /// Largest mean absolute difference (0-255 scale, over all channels).
    mean: f64,
    /// Largest fraction of pixels off by more than 24 in some channel.
    frac: f64,
}

impl Tolerance {
    fn accepts(&self, d: &Diff) -> bool {
        d.mean_abs <= self.mean && d.frac_off <= self.frac
    }
}

/// The core images: every line of A1-A4 and A6's untextured lines. Measured
/// (docs/testing.md, "Reference images"): the largest differences
/// of any of them outside [`WIDER`] are a mean of 0.59 (output4_06f) and
/// 0.37% of pixels off (output6_11b); most are below 0.05 and 0.05%. The
/// margin is 0.4 on the mean and 0.13 points on the fraction.
const CORE: Tolerance = Tolerance {
    mean: 1.0,
    frac: 0.005,
};

/// Images that a one-pixel shift changes too little for [`CORE`] to see
/// (a small object on a flat background: only its outline moves; measured
/// shifts as small as a mean of 0.165 and 0.17% of pixels, output2_05_no_back
/// and normals2_11) get this instead. All of them (17 of 110) measure a mean
/// of at most 0.003 and no pixel off; the margin is 0.1 on each.
const FINE: Tolerance = Tolerance {
    mean: 0.1,
    frac: 0.001,
};

/// Core images measured above [`CORE`]: (name, tolerance, measured).
const WIDER: &[(&str, Tolerance, &str)] = &[
    (
        "depth2_07.tga",
        Tolerance {
            mean: 1.9,
            frac: 0.0035,
        },
        "measured mean 1.72 but only 0.25% of pixels off by more than 24: small \
         depth differences spread over the surfaces, not a misplaced edge \
         (moved by one pixel: 0.96% off, which fails)",
    ),
    (
        "output6_12b.tga",
        Tolerance {
            mean: 0.55,
            frac: 0.010,
        },
        "measured mean 0.44, 0.87% off: the faceted gem at 5 bounces, where \
         the 6_12a render of the same gem with fewer bounces measures \
         0.15 and 0.22% (moved by one pixel: mean 2.96, which fails)",
    ),
];

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
/// these references pixel by pixel (with its own measured tolerance and the
/// same one-pixel-shift proof), so the pattern, its parity, the texture
/// matrix and the world-space lookup are right. The bounds here are the
/// measured differences plus ~10%: they only guard against the literal
/// renders getting worse, and a one-pixel shift is not required to fail them.
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

/// The tolerance for output `name` whose reference is `reference` (`w`×`h`),
/// and whether it is one of the knowingly wrong references (whose literal
/// render need not see a shift). An image gets [`FINE`] when a one-pixel
/// shift of its own reference would pass [`CORE`].
fn tolerance(name: &str, w: u32, h: u32, reference: &[[u8; 3]]) -> (Tolerance, bool) {
    if let Some(e) = EXCEPTIONS.iter().find(|e| e.0 == name) {
        let t = Tolerance {
            mean: e.1,
            frac: e.2,
        };
        return (t, true);
    }
    if let Some(wider) = WIDER.iter().find(|w| w.0 == name) {
        return (wider.1, false);
    }
    let shift_passes = ONE_PIXEL_SHIFTS
        .iter()
        .any(|&(dx, dy)| CORE.accepts(&diff_pixels(&shifted(w, h, reference, dx, dy), reference)));
    (if shift_passes { FINE } else { CORE }, false)
}

/// Why `ours` (an image that passed against `reference`) proves nothing if
/// a copy moved by one pixel, or a blank image, would pass too; `None` when
/// all of them fail as they should.
fn blind_spot(
    name: &str,
    tol: Tolerance,
    w: u32,
    h: u32,
    ours: &[[u8; 3]],
    reference: &[[u8; 3]],
) -> Option<String> {
    for (dx, dy) in ONE_PIXEL_SHIFTS {
        let d = diff_pixels(&shifted(w, h, ours, dx, dy), reference);
        if tol.accepts(&d) {
            return Some(format!(
                "{name} moved by ({dx}, {dy}) still passes: mean abs {:.3}, {:.3}% off (max {}, {}%)",
                d.mean_abs,
                100.0 * d.frac_off,
                tol.mean,
                100.0 * tol.frac
            ));
        }
    }
    let blank = vec![[0u8; 3]; ours.len()];
    let d = diff_pixels(&blank, reference);
    tol.accepts(&d)
        .then(|| format!("a black image passes as {name}: {d:?}"))
}

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
            let reference = reference_for(&data.refs, name);
            let (w, h, ours, theirs) = match (load_rgb8(&dir.join(name)), load_rgb8(&reference)) {
                (Ok(a), Ok(b)) if (a.0, a.1) == (b.0, b.1) => (b.0, b.1, a.2, b.2),
                (Ok(a), Ok(b)) => {
                    failures.push(format!(
                        "{name}: size {:?}, reference {:?}",
                        (a.0, a.1),
                        (b.0, b.1)
                    ));
                    continue;
                }
                (Err(e), _) | (_, Err(e)) => {
                    failures.push(format!("{name}: {e}"));
                    continue;
                }
            };
            let (tol, knowingly_wrong) = tolerance(name, w, h, &theirs);
            let d = diff_pixels(&ours, &theirs);
            // Shown with `--nocapture`: the numbers the tolerances come from.
            eprintln!(
                "measured {tag} {name}: mean abs {:.3}, {:.3}% off",
                d.mean_abs,
                100.0 * d.frac_off
            );
            if !tol.accepts(&d) {
                failures.push(format!(
                    "{name}: mean abs {:.3} (max {}), {:.3}% pixels off (max {:.2}%)",
                    d.mean_abs,
                    tol.mean,
                    100.0 * d.frac_off,
                    100.0 * tol.frac
                ));
                continue;
            }
            checked += 1;
            if !knowingly_wrong {
                if let Some(why) = blind_spot(name, tol, w, h, &ours, &theirs) {
                    failures.push(why);
                }
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
        "bvh8",
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

/// The checker itself (issue 18): every reference this file compares with,
/// moved by one pixel in each direction, fails its own tolerance against
/// the unmoved reference, and so does a black image. Needs no rendering.
#[test]
fn the_checker_rejects_shifted_and_blank_references() {
    let Some(data) = course_data("the_checker_rejects_shifted_and_blank_references") else {
        return;
    };
    let mut names: Vec<String> = [
        "A1_cmd.txt",
        "A2_cmd.txt",
        "A3_cmd.txt",
        "A4_cmd.txt",
        "A6_cmd.txt",
    ]
    .iter()
    .flat_map(|f| plain_lines(&data, f))
    .flat_map(|l| l.outputs)
    .collect();
    names.sort();
    names.dedup();
    assert!(names.len() >= 60, "only {} references", names.len());
    let mut blind = Vec::new();
    for name in &names {
        let (w, h, px) = load_rgb8(&reference_for(&data.refs, name)).expect("reference");
        let (tol, _) = tolerance(name, w, h, &px);
        if let Some(why) = blind_spot(name, tol, w, h, &px, &px) {
            blind.push(why);
        }
    }
    assert!(
        blind.is_empty(),
        "{} of {} references:\n{}",
        blind.len(),
        names.len(),
        blind.join("\n")
    );
}
