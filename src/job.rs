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
