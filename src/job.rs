//! One render as both command lines describe it: load, build, render, write.
//! The binaries only translate their flags into a [`Job`].

use crate::format::{load_scene, ParseError};
use crate::integrator::Whitted;
use crate::output::{write_rgb, OutputError};
use crate::render::{render, CameraModel, Frame, PixelOffset};
use crate::scene::Scene;
use crate::stats::Counters;
use crate::world::{BuildOptions, World};
use std::path::PathBuf;
use std::time::{Duration, Instant};
use thiserror::Error;

/// A render request.
#[derive(Clone, Debug)]
pub struct Job {
    /// Scene file.
    pub input: PathBuf,
    /// Colour image, if wanted.
    pub output: Option<PathBuf>,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Depth image: near `t`, far `t`, file.
    pub depth: Option<(f32, f32, PathBuf)>,
    /// Normals image.
    pub normals: Option<PathBuf>,
    /// Ray-tree settings.
    pub integrator: Whitted,
    /// World-building settings.
    pub build: BuildOptions,
    /// Worker threads (all cores when `None`).
    pub threads: Option<usize>,
    /// Where in the pixel the eye ray goes.
    pub pixel_offset: PixelOffset,
}

/// Why a job failed. Bad input maps to exit status 2, the rest to 1.
#[derive(Debug, Error)]
pub enum JobError {
    /// The scene could not be read.
    #[error("{}", .0.render())]
    Parse(#[from] ParseError),
    /// An image could not be written.
    #[error("{0}")]
    Output(#[from] OutputError),
    /// The request itself is invalid (e.g. a zero image size).
    #[error("{0}")]
    Usage(String),
    /// Anything else (thread pool creation, ...).
    #[error("{0}")]
    Internal(String),
}

impl JobError {
    /// The process exit status for this error: 2 for bad input, 1 otherwise.
    pub fn exit_code(&self) -> i32 {
        match self {
            JobError::Parse(_) | JobError::Usage(_) => 2,
            JobError::Output(_) | JobError::Internal(_) => 1,
        }
    }
}

/// What a finished job measured.
#[derive(Clone, Debug)]
pub struct Report {
    /// The scene as loaded.
    pub scene: Scene,
    /// Merged ray counters.
    pub counters: Counters,
    /// Aggregate description.
    pub accel: String,
    /// Aggregate build time.
    pub build_ms: f64,
    /// Time spent tracing.
    pub render: Duration,
    /// Number of primitives in the world.
    pub primitives: usize,
    /// The rendered planes.
    pub frame: Frame,
}

impl Job {
    /// A job with the course's defaults (no outputs yet).
    pub fn new(input: PathBuf, width: u32, height: u32) -> Self {
        Self {
            input,
            output: None,
            width,
            height,
            depth: None,
            normals: None,
            integrator: Whitted::default(),
            build: BuildOptions::default(),
            threads: None,
            pixel_offset: PixelOffset::CENTER,
        }
    }

    /// Loads, renders and writes every requested image.
    pub fn run(&self) -> Result<Report, JobError> {
        if self.width == 0 || self.height == 0 {
            return Err(JobError::Usage(format!(
                "image size {}x{}: width and height must be at least 1",
                self.width, self.height
            )));
        }
        check_frame_memory(self.width, self.height, available_memory())?;
        let scene = load_scene(&self.input)?;
        let world = World::build(&scene, self.build);
        let camera = CameraModel::new(&scene.camera);
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(self.threads.unwrap_or(0))
            .build()
            .map_err(|e| JobError::Internal(e.to_string()))?;
        let start = Instant::now();
        let (frame, counters) = pool.install(|| {
            render(
                &world,
                &camera,
                &self.integrator,
                (self.width, self.height),
                self.pixel_offset,
            )
        });
        let render_time = start.elapsed();
        let (w, h) = (self.width, self.height);
        if let Some(out) = &self.output {
            write_rgb(out, w, h, &frame.color)?;
        }
        if let Some((t0, t1, out)) = &self.depth {
            write_rgb(out, w, h, &frame.depth_image(*t0, *t1))?;
        }
        if let Some(out) = &self.normals {
            write_rgb(out, w, h, &frame.normals_image())?;
        }
        Ok(Report {
            scene,
            counters,
            accel: world.accel.describe(),
            build_ms: world.build_ms,
            render: render_time,
            primitives: world.prims.len(),
            frame,
        })
    }
}

/// Bytes per pixel of a [`Frame`]: colour `Vec3`, depth `f32`, normal `Vec3`.
pub const FRAME_BYTES_PER_PIXEL: u64 = 12 + 4 + 12;

/// Memory assumed available where `/proc/meminfo` cannot be read.
pub const FALLBACK_AVAILABLE: u64 = 16 << 30;

/// Bytes the system can give this process now: `MemAvailable` from
/// `/proc/meminfo` on Linux, else [`FALLBACK_AVAILABLE`].
pub fn available_memory() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("MemAvailable:"))?;
            let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            kib.checked_mul(1024)
        })
        .unwrap_or(FALLBACK_AVAILABLE)
}

/// Refuses, before anything is allocated, an image whose frame planes would
/// take more than three quarters of `available` bytes (the rest is left for
/// the scene, the output encoder and everything else running).
pub fn check_frame_memory(width: u32, height: u32, available: u64) -> Result<(), JobError> {
    let need = u128::from(width) * u128::from(height) * u128::from(FRAME_BYTES_PER_PIXEL);
    let limit = u128::from(available / 4 * 3);
    if need <= limit {
        return Ok(());
    }
    let gib = |b: u128| b as f64 / f64::from(1u32 << 30);
    Err(JobError::Usage(format!(
        "image size {width}x{height} would need {:.1} GiB of memory for its frame \
         ({FRAME_BYTES_PER_PIXEL} bytes per pixel), more than the {:.1} GiB allowed \
         (3/4 of the {:.1} GiB available); choose a smaller size",
        gib(need),
        gib(limit),
        gib(u128::from(available)),
    )))
}

impl Report {
    /// The human-readable statistics table.
    pub fn stats_text(&self) -> String {
        let c = &self.counters;
        let rays = c.rays_total().max(1) as f64;
        let pixels = (self.frame.width as u64 * self.frame.height as u64).max(1) as f64;
        let secs = self.render.as_secs_f64();
        let mut s = String::new();
        let mut line = |k: &str, v: String| s.push_str(&format!("{k:<28}{v}\n"));
        line(
            "image",
            format!("{}x{}", self.frame.width, self.frame.height),
        );
        line("accelerator", self.accel.clone());
        line("primitives", self.primitives.to_string());
        line("build time", format!("{:.2} ms", self.build_ms));
        line("render time", format!("{:.2} ms", secs * 1e3));
        line("primary rays", c.primary.to_string());
        line("shadow rays", c.shadow.to_string());
        line("reflected rays", c.reflected.to_string());
        line("refracted rays", c.refracted.to_string());
        line("rays total", c.rays_total().to_string());
        line("intersection tests", c.intersection_tests.to_string());
        line("nodes visited", c.nodes_visited.to_string());
        line("rays / second", format!("{:.0}", rays / secs.max(1e-9)));
        line("rays / pixel", format!("{:.3}", rays / pixels));
        line(
            "tests / ray",
            format!("{:.3}", c.intersection_tests as f64 / rays),
        );
        line(
            "nodes / ray",
            format!("{:.3}", c.nodes_visited as f64 / rays),
        );
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_memory_limit() {
        let gib = 1u64 << 30;
        assert!(check_frame_memory(1000, 1000, gib).is_ok());
        let e = check_frame_memory(100_000, 100_000, 16 * gib).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        let msg = e.to_string();
        assert!(msg.contains("100000x100000"), "{msg}");
        assert!(msg.contains("260.8 GiB"), "{msg}");
        assert!(msg.contains("12.0 GiB allowed"), "{msg}");
        // The product cannot overflow.
        assert!(check_frame_memory(u32::MAX, u32::MAX, u64::MAX).is_err());
        assert!(available_memory() > 0);
    }
}
