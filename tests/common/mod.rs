//! Shared helpers of the integration tests: running the handouts' command
//! lines with the real binary and comparing images with the references.

#![allow(dead_code)]

use glint::integrator::{Integrator, RayObserver, Trace};
use glint::math::{Ray, Vec2, Vec3};
use glint::sampler::Sampler;
use glint::stats::Counters;
use glint::world::{Hit, World};
use std::path::{Path, PathBuf};
use std::process::Command;

/// Where the course data is, and how a test skips without it (one rule for
/// unit and integration tests).
#[path = "../../src/testdata.rs"]
pub mod testdata;

/// The tests' one random generator, shared with the unit tests.
#[path = "../../src/testutil.rs"]
pub mod testutil;
pub use testutil::Rng;

/// The course's scenes, or `None` (test reported as skipped) when the data
/// folder is absent.
pub fn scenes(test: &str) -> Option<PathBuf> {
    testdata::scenes(test)
}

/// The independent reference renders, or `None` (skipped) when absent.
pub fn references(test: &str) -> Option<PathBuf> {
    testdata::references(test)
}

/// Colour and hit of the eye ray `ray` (hits with `t > tmin`) through the
/// integrator's interface, every random decision at the centre of its
/// stratum: the stream of a one-sample render at the pixel centre.
pub fn eye_ray<I: Integrator>(
    integrator: &I,
    world: &World,
    ray: &Ray,
    tmin: f32,
    counters: &mut Counters,
    observer: &mut impl RayObserver,
) -> (Vec3, Option<Hit>) {
    let sampler = Sampler::fixed(Vec2::splat(0.5));
    let mut stream = sampler.stream((0, 0), 0);
    stream.skip();
    let cx = &mut Trace {
        world,
        stream: &mut stream,
        counters,
        observer,
        packets: false,
    };
    integrator.li(cx, ray, tmin)
}

/// glint's own example scenes (`scenes/` in the repository).
pub fn own_scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

/// How far an image is from its reference.
#[derive(Debug, Clone, Copy)]
pub struct Diff {
    /// Mean absolute difference over all channels, 0-255 scale.
    pub mean_abs: f64,
    /// Fraction of pixels with some channel off by more than 24.
    pub frac_off: f64,
}

/// Compares two images of the same size.
pub fn diff(a: &Path, b: &Path) -> Result<Diff, String> {
    let ia = image::open(a)
        .map_err(|e| format!("{}: {e}", a.display()))?
        .to_rgb8();
    let ib = image::open(b)
        .map_err(|e| format!("{}: {e}", b.display()))?
        .to_rgb8();
    if ia.dimensions() != ib.dimensions() {
        return Err(format!(
            "size {:?} vs reference {:?}",
            ia.dimensions(),
            ib.dimensions()
        ));
    }
    let mut sum = 0u64;
    let mut off = 0u64;
    for (pa, pb) in ia.pixels().zip(ib.pixels()) {
        let mut worst = 0;
        for c in 0..3 {
            let d = (pa[c] as i32 - pb[c] as i32).unsigned_abs();
            sum += d as u64;
            worst = worst.max(d);
        }
        if worst > 24 {
            off += 1;
        }
    }
    let n = (ia.width() * ia.height()) as f64;
    Ok(Diff {
        mean_abs: sum as f64 / (3.0 * n),
        frac_off: off as f64 / n,
    })
}

/// One handout command line, with the images it writes.
pub struct CmdLine {
    /// The line as written.
    pub text: String,
    /// Its arguments after `raytracer`.
    pub args: Vec<String>,
    /// Output file names the line names (colour, depth, normals, sample and
    /// filter views).
    pub outputs: Vec<String>,
}

/// The lines of `commands/<file>` that write at least one image.
pub fn command_lines(scenes: &Path, file: &str) -> Vec<CmdLine> {
    let text = std::fs::read_to_string(scenes.join("commands").join(file)).expect("command file");
    text.lines()
        .filter_map(|l| {
            let args: Vec<String> = l.split_whitespace().skip(1).map(String::from).collect();
            let mut outputs = Vec::new();
            for (i, a) in args.iter().enumerate() {
                match a.as_str() {
                    "-output" | "-normals" | "-render_samples" | "-render_filter" => {
                        outputs.push(args[i + 1].clone())
                    }
                    "-depth" => outputs.push(args[i + 3].clone()),
                    _ => {}
                }
            }
            (!outputs.is_empty()).then(|| CmdLine {
                text: l.trim().to_string(),
                args,
                outputs,
            })
        })
        .collect()
}

/// Runs `raytracer` with `args`, reading the scene from `scenes` and
/// writing into `out_dir`. Returns stderr on failure.
pub fn run_raytracer(scenes: &Path, args: &[String], out_dir: &Path) -> Result<(), String> {
    let scenes = std::fs::canonicalize(scenes).expect("scenes folder");
    let mut args = args.to_vec();
    if let Some(i) = args.iter().position(|a| a == "-input") {
        args[i + 1] = scenes.join(&args[i + 1]).to_string_lossy().into_owned();
    }
    let out = Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .args(&args)
        .current_dir(out_dir)
        .output()
        .map_err(|e| e.to_string())?;
    if out.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&out.stderr).into_owned())
    }
}

/// A fresh, empty scratch folder for one test, removed (with everything in
/// it) when the value is dropped. Derefs to its path.
pub struct Scratch(tempfile::TempDir);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

/// A [`Scratch`] folder named after the test, under the system's temp dir.
pub fn scratch(name: &str) -> Scratch {
    Scratch(
        tempfile::Builder::new()
            .prefix(&format!("glint-test-{name}-"))
            .tempdir()
            .expect("temporary folder"),
    )
}

/// The reference PNG in `refs` for an output named `name` (`output1_01.tga` → `output1_01.png`).
pub fn reference_for(refs: &Path, name: &str) -> PathBuf {
    refs.join(Path::new(name).with_extension("png"))
}

/// The line of `commands/<file>` that writes `output` (e.g. `output6_13.tga`).
pub fn line_for(scenes: &Path, file: &str, output: &str) -> CmdLine {
    command_lines(scenes, file)
        .into_iter()
        .find(|l| l.outputs.iter().any(|o| o == output))
        .unwrap_or_else(|| panic!("{file} has no line writing {output}"))
}

/// The value after `flag` in `args`.
pub fn flag_value<'a>(args: &'a [String], flag: &str) -> Option<&'a str> {
    let i = args.iter().position(|a| a == flag)?;
    args.get(i + 1).map(String::as_str)
}

/// Per-channel mean of 8-bit RGB pixels, on the 0-255 scale.
pub fn mean_rgb(pixels: &[[u8; 3]]) -> [f64; 3] {
    let mut sum = [0f64; 3];
    for p in pixels {
        for c in 0..3 {
            sum[c] += p[c] as f64;
        }
    }
    sum.map(|s| s / pixels.len().max(1) as f64)
}

/// Per-channel relative difference of two mean colours: `(ours - ref) / ref`.
pub fn relative_mean_diff(ours: [f64; 3], reference: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|c| (ours[c] - reference[c]) / reference[c])
}

/// The pixels of an image file, row-major, top row first.
pub fn load_rgb8(path: &Path) -> Result<(u32, u32, Vec<[u8; 3]>), String> {
    let img = image::open(path)
        .map_err(|e| format!("{}: {e}", path.display()))?
        .to_rgb8();
    let (w, h) = img.dimensions();
    Ok((w, h, img.pixels().map(|p| p.0).collect()))
}

/// [`Diff`] of two equally long pixel lists.
pub fn diff_pixels(a: &[[u8; 3]], b: &[[u8; 3]]) -> Diff {
    assert_eq!(a.len(), b.len(), "pixel counts differ");
    let mut sum = 0u64;
    let mut off = 0u64;
    for (pa, pb) in a.iter().zip(b) {
        let mut worst = 0;
        for c in 0..3 {
            let d = (pa[c] as i32 - pb[c] as i32).unsigned_abs();
            sum += d as u64;
            worst = worst.max(d);
        }
        if worst > 24 {
            off += 1;
        }
    }
    let n = a.len().max(1) as f64;
    Diff {
        mean_abs: sum as f64 / (3.0 * n),
        frac_off: off as f64 / n,
    }
}

/// The course's scenes and reference renders together.
pub struct CourseData {
    /// `scenes/6837`: scene files, meshes, `commands/`.
    pub scenes: PathBuf,
    /// `reference/6837`: the independent reference renders.
    pub refs: PathBuf,
}

/// Both course folders, or `None` (test reported as skipped) when absent.
pub fn course_data(test: &str) -> Option<CourseData> {
    Some(CourseData {
        scenes: scenes(test)?,
        refs: references(test)?,
    })
}

/// The four one-pixel moves (right, left, down, up) the image checks must see.
pub const ONE_PIXEL_SHIFTS: [(i32, i32); 4] = [(1, 0), (-1, 0), (0, 1), (0, -1)];

/// A `w`×`h` image (row-major, top row first) moved by `(dx, dy)` pixels;
/// the row or column uncovered at the edge repeats its neighbour, so the
/// shift is all that changes.
pub fn shifted(w: u32, h: u32, pixels: &[[u8; 3]], dx: i32, dy: i32) -> Vec<[u8; 3]> {
    assert_eq!(pixels.len(), (w * h) as usize, "pixel count");
    let (w, h) = (w as i32, h as i32);
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let sx = (x - dx).clamp(0, w - 1);
            let sy = (y - dy).clamp(0, h - 1);
            pixels[(sy * w + sx) as usize]
        })
        .collect()
}
