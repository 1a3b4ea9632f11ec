//! One render as both command lines describe it: load, build, render, write.
//! The binaries only translate their flags into a [`Job`].

use crate::accel::AccelKind;
use crate::animation::FrameTime;
use crate::format::{load_scene_files, ParseError};
use crate::integrator::{AmbientOcclusion, AoSettings, PathSettings, PathTracer, Whitted};
use crate::limits;
use crate::output::{
    check_image, check_not_input, check_path, check_writable, write_file, write_rgb, FileIdentity,
    OutputError,
};
use crate::piece::PieceSpec;
use crate::render::views::{filter_view, heat_map, samples_view, Image};
use crate::render::{
    render_image, render_region, Adaptive, CameraModel, Control, Filter, Frame, PixelOffset,
    Settings, TILE_SIZE,
};
use crate::sampler::{Sampler, SamplerKind};
use crate::scene::{EffectSamples, Light, Material, Scene};
use crate::stats::Counters;
use crate::viz::draw::Canvas;
use crate::viz::grid::{legend, voxelize, GridView};
use crate::world::{BuildOptions, World};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use thiserror::Error;

/// A render request.
#[derive(Clone, Debug)]
pub struct Job {
    /// Scene file.
    pub input: PathBuf,
    /// Colour image, if wanted.
    pub output: Option<PathBuf>,
    /// How the colour image's 8-bit formats encode values (the course's
    /// linear truncation unless `glint render --srgb`).
    pub encoding: crate::output::Encoding,
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
    /// Where in the pixel the eye ray goes with one sample per pixel, and the
    /// point whose nearest sample fills the depth and normal planes.
    pub pixel_offset: PixelOffset,
    /// Many samples per pixel; `None`: one ray at `pixel_offset`.
    pub sampler: Option<Sampler>,
    /// Reconstruction filter.
    pub filter: Filter,
    /// Whitted's adaptive subdivision instead of the sampler's positions.
    pub adaptive: Option<Adaptive>,
    /// The course's `-render_samples FILE zoom` view.
    pub samples_view: Option<(PathBuf, u32)>,
    /// The course's `-render_filter FILE zoom` view.
    pub filter_view: Option<(PathBuf, u32)>,
    /// Heat map of camera rays per pixel, with a scale bar.
    pub samples_image: Option<PathBuf>,
    /// Heat maps of intersection tests and nodes visited per pixel, with
    /// scale bars and totals (`--cost-image`).
    pub cost_image: Option<PathBuf>,
    /// Render only this piece of the frame and write it as an EXR with a
    /// data window (`--tile I/N`, `--crop`); see [`crate::piece`].
    pub piece: Option<PieceSpec>,
    /// Render this frame of the scene's animation (`--frame K --fps F`):
    /// the shutter interval moves to start at `K / F`; see
    /// [`crate::animation`].
    pub frame: Option<FrameTime>,
    /// Set by a Ctrl-C handler: stop, and save what was rendered as
    /// `NAME.partial.EXT`.
    pub cancel: Option<Arc<AtomicBool>>,
    /// Draw a progress bar with ETA on stderr.
    pub progress: bool,
    /// Write the statistics as JSON here.
    pub stats_json: Option<PathBuf>,
    /// Rays per effect given on the command line; each one set overrides
    /// the scene's `Samples`/`AmbientOcclusion` count.
    pub effect_samples: SampleOverrides,
    /// Render the grey ambient-occlusion image instead of the shaded one.
    pub ao_image: bool,
    /// Render with the path tracer (`integrator::path`) and these settings
    /// instead of the Whitted tree (its texture space is `integrator`'s).
    pub path: Option<PathSettings>,
    /// Render the uniform grid's occupied cells instead of the scene
    /// (`-visualize_grid`, `-visualize_grid_count`); the grid's resolution is
    /// the one `build.accel` asks for, if it is a grid.
    pub visualize_grid: Option<GridView>,
    /// Shade every mesh smooth (`--smooth`): see [`Scene::smooth_meshes`].
    pub smooth: bool,
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
    /// Stopped by the user; what was rendered is in these files.
    #[error("interrupted: saved the rows rendered so far to {}", list(.0))]
    Interrupted(Vec<PathBuf>),
}

fn list(paths: &[PathBuf]) -> String {
    let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    if names.is_empty() {
        "no file (no output was requested)".into()
    } else {
        names.join(", ")
    }
}

/// `out.png` → `out.partial.png`: where an interrupted render is saved, so
/// the file the user asked for is never replaced by an incomplete image.
pub fn partial_path(p: &Path) -> PathBuf {
    let stem = p
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = match p.extension() {
        Some(ext) => format!("{stem}.partial.{}", ext.to_string_lossy()),
        None => format!("{stem}.partial"),
    };
    p.with_file_name(name)
}

/// Installs a Ctrl-C handler that sets the returned flag; a second Ctrl-C
/// exits at once (status 130) for a user who does not want to wait.
pub fn interrupt_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    // Failing to install (e.g. a handler exists already) only loses the
    // graceful stop; rendering itself is unaffected.
    let _ = ctrlc::set_handler(move || {
        if f.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
        eprintln!("\ninterrupt: finishing the rows in flight, then saving a partial image (Ctrl-C again to quit now)");
    });
    flag
}

impl JobError {
    /// The process exit status for this error: 2 for bad input, 1 otherwise.
    pub fn exit_code(&self) -> i32 {
        match self {
            // A request that names no writable image is the user's to fix;
            // checked before any work.
            JobError::Parse(_)
            | JobError::Usage(_)
            | JobError::Output(
                OutputError::Format { .. }
                | OutputError::NoDir { .. }
                | OutputError::Refused { .. },
            ) => 2,
            JobError::Output(_) | JobError::Internal(_) => 1,
            JobError::Interrupted(_) => 130,
        }
    }
}

/// Loads `scene` for a command that writes the single file `output` (the
/// `glint raytree`, `traverse` and `structure` views), rendering at `size`
/// if `output` is an image: first checks that `output` can be written (and
/// an image of that size fits memory and the format) and is not the scene,
/// then, once the scene has named its meshes, that it is none of them.
/// Nothing is written.
pub fn load_scene_for(scene: &Path, output: &Path, size: (u32, u32)) -> Result<Scene, JobError> {
    check_writable(output)?;
    if check_path(output).is_ok() {
        check_frame_memory(size.0, size.1, available_memory())?;
        check_image(output, size.0, size.1)?;
    }
    check_not_input(output, &[scene.to_path_buf()])?;
    let (loaded, files) = load_scene_files(scene)?;
    check_not_input(output, &files)?;
    Ok(loaded)
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
    /// Time to read the scene and its meshes.
    pub load_ms: f64,
    /// Time to flatten the scene and build the aggregate.
    pub world_ms: f64,
    /// Time spent tracing.
    pub render: Duration,
    /// Number of primitives in the world.
    pub primitives: usize,
    /// Bounds of the world's bounded primitives (planes excluded), in world
    /// space (the scene file's coordinates, not the camera-centred rendering
    /// space).
    pub bounds: crate::math::Aabb,
    /// The rendered planes.
    pub frame: Frame,
    /// The sampling settings rendered with.
    pub settings: Settings,
}

impl Job {
    /// Every image file this job will write (colour, depth, normals).
    pub fn image_paths(&self) -> impl Iterator<Item = &Path> {
        let depth = self.depth.as_ref().map(|(_, _, p)| p.as_path());
        self.output
            .as_deref()
            .into_iter()
            .chain(depth)
            .chain(self.normals.as_deref())
            .chain(self.samples_view.as_ref().map(|(p, _)| p.as_path()))
            .chain(self.filter_view.as_ref().map(|(p, _)| p.as_path()))
            .chain(self.samples_image.as_deref())
            .chain(self.cost_image.as_deref())
    }

    /// A piece renders one image, an EXR: nothing else this job could write
    /// would be a piece of anything.
    fn check_piece(&self, p: &PieceSpec) -> Result<(), JobError> {
        let exr = self
            .output
            .as_ref()
            .is_some_and(|o| o.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")));
        if !exr {
            return Err(JobError::Usage(format!(
                "{}: a piece of a frame is written as OpenEXR: give an output ending in .exr",
                p.label
            )));
        }
        if self.image_paths().count() > 1 {
            return Err(JobError::Usage(format!(
                "{}: only the colour image can be rendered in pieces (no depth, normals, views or cost images)",
                p.label
            )));
        }
        if self.adaptive.is_some() {
            return Err(JobError::Usage(format!(
                "{}: adaptive sampling shares corner rays between tiles, so it cannot be split into pieces",
                p.label
            )));
        }
        if p.rect.x1 > self.width || p.rect.row1 > self.height {
            return Err(JobError::Usage(format!(
                "{} lies outside the {}x{} frame",
                p.label, self.width, self.height
            )));
        }
        Ok(())
    }

    /// This job for frame `f` of the scene's animation: [`Job::frame`] set,
    /// and the last run of `#` in every output file name replaced by the
    /// frame number ([`crate::animation::frame_path`]), so one command line
    /// serves every frame of a job array.
    pub fn at_frame(mut self, f: FrameTime) -> Self {
        let k = f.index;
        let name = |p: &mut PathBuf| *p = crate::animation::frame_path(p, k);
        self.output.iter_mut().for_each(name);
        self.normals.iter_mut().for_each(name);
        self.samples_image.iter_mut().for_each(name);
        self.cost_image.iter_mut().for_each(name);
        self.stats_json.iter_mut().for_each(name);
        self.depth.iter_mut().for_each(|d| name(&mut d.2));
        self.samples_view.iter_mut().for_each(|v| name(&mut v.0));
        self.filter_view.iter_mut().for_each(|v| name(&mut v.0));
        self.frame = Some(f);
        self
    }

    /// The hash of everything that decides the image (not the accelerator,
    /// the thread count or the outputs, which do not).
    fn piece_hash(&self, scene: &Scene, settings: &Settings) -> String {
        let mut parts = format!(
            "{settings:?}|{:?}|flatten {}|texture {:?}",
            self.integrator, self.build.flatten, self.integrator.texture_space
        );
        if let Some(p) = &self.path {
            parts += &format!("|path {p:?}");
        }
        crate::piece::settings_hash(scene, &parts)
    }

    /// Every file this job may write, with what it is: the images, their
    /// `.partial` twins (written when interrupted) and the statistics.
    /// **A new kind of output must be added here**: [`Job::preflight`]
    /// checks this list against the inputs and against itself.
    pub fn outputs(&self) -> Vec<(String, PathBuf)> {
        let mut out: Vec<(String, PathBuf)> = Vec::new();
        let images = [
            ("colour image", self.output.as_deref()),
            (
                "depth image",
                self.depth.as_ref().map(|(_, _, p)| p.as_path()),
            ),
            ("normals image", self.normals.as_deref()),
        ];
        for (what, path) in images {
            if let Some(p) = path {
                out.push((what.into(), p.into()));
                out.push((format!("{what} if interrupted"), partial_path(p)));
            }
        }
        let views = [
            (
                "samples view",
                self.samples_view.as_ref().map(|v| v.0.as_path()),
            ),
            (
                "filter view",
                self.filter_view.as_ref().map(|v| v.0.as_path()),
            ),
            ("samples heat map", self.samples_image.as_deref()),
            ("cost image", self.cost_image.as_deref()),
        ];
        for (what, path) in views {
            if let Some(p) = path {
                out.push((what.into(), p.into()));
                out.push((format!("{what} if interrupted"), partial_path(p)));
            }
        }
        if let Some(p) = &self.stats_json {
            out.push(("statistics file".into(), p.clone()));
        }
        out
    }

    /// Every check that needs no scene, done before any work: image size
    /// and memory, each output's format, folder and size limits, the
    /// numeric settings' ranges, and that no output is the scene file or
    /// another output. The meshes are checked once the scene has named them
    /// (still before anything is written).
    pub fn preflight(&self) -> Result<(), JobError> {
        if self.width == 0 || self.height == 0 {
            return Err(JobError::Usage(format!(
                "image size {}x{}: width and height must be at least 1",
                self.width, self.height
            )));
        }
        check_frame_memory(self.width, self.height, available_memory())?;
        if self.ao_image && self.path.is_some() {
            return Err(JobError::Usage(
                "choose one integrator: the AO image or the path tracer".into(),
            ));
        }
        self.check_settings()?;
        for path in self.image_paths() {
            check_path(path)?;
        }
        let images = [self.output.as_deref(), self.normals.as_deref()];
        let depth = self.depth.as_ref().map(|(_, _, p)| p.as_path());
        for path in images.into_iter().chain([depth]).flatten() {
            check_image(path, self.width, self.height)?;
        }
        self.check_views()?;
        if let Some(p) = &self.stats_json {
            check_writable(p)?;
        }
        self.check_clashes(std::slice::from_ref(&self.input))
    }

    /// The numeric settings are in their documented ranges
    /// ([`crate::limits`]); the command lines check them with the flag's
    /// name first, this catches any other caller.
    fn check_settings(&self) -> Result<(), JobError> {
        let usage = |m: String| JobError::Usage(m);
        if let Some(n) = self.threads {
            limits::int_in("threads", n, 1, limits::MAX_THREADS).map_err(usage)?;
        }
        limits::int_in("bounces", self.integrator.bounces, 0, limits::MAX_BOUNCES)
            .map_err(usage)?;
        limits::finite_in("weight", self.integrator.weight_cutoff, 0.0, f32::MAX).map_err(usage)?;
        if let Some((t0, t1, _)) = &self.depth {
            for t in [*t0, *t1] {
                limits::finite_in("depth", t, f32::MIN, f32::MAX).map_err(usage)?;
            }
        }
        if let Some(s) = &self.sampler {
            let spp = s.spp();
            limits::int_in("samples per pixel", spp, 1, limits::MAX_SAMPLES).map_err(usage)?;
        }
        if let Some(a) = &self.adaptive {
            limits::finite_in("adaptive threshold", a.threshold, 0.0, f32::MAX).map_err(usage)?;
        }
        self.filter
            .validate()
            .map_err(|e| usage(format!("filter: {e}")))?;
        Ok(())
    }

    /// The zoomed views (`-render_samples`, `-render_filter`) are `zoom²`
    /// times the image: their size must fit memory and their format too.
    fn check_views(&self) -> Result<(), JobError> {
        let views = [
            (self.samples_view.as_ref(), 0),
            (self.filter_view.as_ref(), 1),
        ];
        for (view, border) in views {
            let Some((path, zoom)) = view else { continue };
            let side = |n: u32| u64::from(n) * u64::from((*zoom).max(1)) + border;
            let (w, h) = (side(self.width), side(self.height));
            let (Ok(w), Ok(h)) = (u32::try_from(w), u32::try_from(h)) else {
                return Err(JobError::Usage(format!(
                    "{}: a {w}x{h} view is too large; choose a smaller zoom",
                    path.display()
                )));
            };
            // The format's own limit first: it holds on any machine.
            check_image(path, w, h)?;
            check_frame_memory(w, h, available_memory())?;
        }
        Ok(())
    }

    /// Refuses the job if an output is one of `inputs` or another output,
    /// however either is spelled (links, `..`, hard links).
    pub fn check_clashes(&self, inputs: &[PathBuf]) -> Result<(), JobError> {
        let outputs: Vec<(String, PathBuf, FileIdentity)> = self
            .outputs()
            .into_iter()
            .map(|(what, p)| {
                let id = FileIdentity::of(&p);
                (what, p, id)
            })
            .collect();
        let refuse = |path: &Path, reason: String| {
            JobError::Output(OutputError::Refused {
                path: path.into(),
                reason,
            })
        };
        for input in inputs {
            let id = FileIdentity::of(input);
            if let Some((what, p, _)) = outputs.iter().find(|o| o.2.same(&id)) {
                return Err(refuse(
                    p,
                    format!(
                        "the {what} would overwrite the input file {}; choose another name",
                        input.display()
                    ),
                ));
            }
        }
        for (i, (what, p, id)) in outputs.iter().enumerate() {
            if let Some((other, _, _)) = outputs[..i].iter().find(|o| o.2.same(id)) {
                return Err(refuse(
                    p,
                    format!("the {other} and the {what} are the same file; choose two names"),
                ));
            }
        }
        Ok(())
    }

    /// A job with the course's defaults (no outputs yet).
    pub fn new(input: PathBuf, width: u32, height: u32) -> Self {
        Self {
            input,
            output: None,
            encoding: crate::output::Encoding::Linear,
            width,
            height,
            depth: None,
            normals: None,
            integrator: Whitted::default(),
            build: BuildOptions::default(),
            threads: None,
            pixel_offset: PixelOffset::CENTER,
            sampler: None,
            filter: Filter::default(),
            adaptive: None,
            samples_view: None,
            filter_view: None,
            samples_image: None,
            cost_image: None,
            piece: None,
            frame: None,
            cancel: None,
            progress: false,
            stats_json: None,
            effect_samples: SampleOverrides::default(),
            ao_image: false,
            path: None,
            visualize_grid: None,
            smooth: false,
        }
    }

    /// The render settings this job asks for.
    pub fn settings(&self) -> Settings {
        let mut s = Settings::one_ray((self.width, self.height), self.pixel_offset);
        if let Some(sampler) = self.sampler {
            s.sampler = sampler;
        }
        s.filter = self.filter;
        s.adaptive = self.adaptive;
        s.keep_samples = self.samples_view.is_some();
        s.pixel_cost = self.cost_image.is_some();
        s.tile_size = TILE_SIZE;
        s
    }

    /// [`Job::settings`] for `scene`: time and lens samples multiply the
    /// camera samples per pixel (when the scene has motion blur or depth of
    /// field). When no sampler was asked for and the scene samples anything
    /// (area lights, glossy materials, shutter, lens, ambient occlusion),
    /// Owen-scrambled Sobol replaces the fixed one-ray sampler, whose regular
    /// grid would band soft shadows and strobe motion.
    pub fn effect_settings(&self, scene: &Scene, samples: EffectSamples) -> Settings {
        let mut s = self.settings();
        let lens = &scene.effects.lens;
        let mut camera_rays = 1u32;
        if lens.has_motion_blur() {
            camera_rays = camera_rays.saturating_mul(samples.time);
        }
        if lens.has_depth_of_field() {
            camera_rays = camera_rays.saturating_mul(samples.lens);
        }
        let kind = match self.sampler {
            Some(sm) => sm.kind,
            None if camera_rays > 1
                || self.ao_image
                || self.path.is_some()
                || uses_sampling(scene) =>
            {
                SamplerKind::Sobol
            }
            None => s.sampler.kind,
        };
        if kind != s.sampler.kind || camera_rays > 1 {
            s.sampler = Sampler::new(
                kind,
                s.sampler.spp().saturating_mul(camera_rays),
                s.sampler.seed,
            );
        }
        s
    }

    /// Loads, renders and writes every requested image.
    pub fn run(&self) -> Result<Report, JobError> {
        self.preflight()?;
        if let Some(p) = &self.piece {
            self.check_piece(p)?;
        }
        let t_load = Instant::now();
        let (mut scene, files) = load_scene_files(&self.input)?;
        if self.smooth {
            scene.smooth_meshes();
        }
        // The meshes are known now; nothing has been written yet.
        self.check_clashes(&files)?;
        let load_ms = t_load.elapsed().as_secs_f64() * 1e3;
        let mut voxels = None;
        let scene = match self.visualize_grid {
            Some(view) => {
                let res = match self.build.accel {
                    AccelKind::Grid { res } => res,
                    _ => None,
                };
                // World space: the cells become geometry of a new scene in
                // the scene's own coordinates.
                let v = voxelize(&World::build_world_space(&scene, self.build), res);
                let cells = v.scene(&scene, view);
                voxels = Some((v, view));
                cells
            }
            None => scene,
        };
        let mut scene = scene;
        if let Some(f) = self.frame {
            // Before the piece hash: pieces of different frames never merge.
            scene.effects.lens.shutter = f.shutter(scene.effects.lens.shutter);
        }
        let t_world = Instant::now();
        let world = World::build(&scene, self.build);
        let world_ms = t_world.elapsed().as_secs_f64() * 1e3;
        let camera = CameraModel::of_world(&world, &scene.effects);
        let samples = self.effect_samples.apply(scene.effects.samples);
        let mut integrator = self.integrator;
        integrator.shadow_samples = samples.shadow;
        integrator.glossy_samples = samples.glossy;
        let ao = |distance| AoSettings {
            samples: samples.ao,
            distance,
        };
        integrator.ambient_occlusion = scene.effects.ambient_occlusion.map(|a| ao(a.distance));
        let ao_integrator = AmbientOcclusion {
            settings: ao(scene
                .effects
                .ambient_occlusion
                .map_or(f32::INFINITY, |a| a.distance)),
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(self.threads.unwrap_or(0))
            .build()
            .map_err(|e| {
                let n = self
                    .threads
                    .map_or_else(|| "one per core".to_owned(), |n| n.to_string());
                JobError::Internal(format!(
                    "could not start the worker threads ({n}): {e}; try fewer with --threads/-threads"
                ))
            })?;
        let bar = self
            .progress
            .then(|| progress_bar(u64::from(self.width) * u64::from(self.height)));
        let tick = |pixels: u64| {
            if let Some(b) = &bar {
                b.inc(pixels);
            }
        };
        let control = Control {
            cancel: self.cancel.as_deref(),
            on_progress: Some(&tick),
        };
        let settings = self.effect_settings(&scene, samples);
        let start = Instant::now();
        let path_tracer = self.path.map(|p| {
            PathTracer::new(
                &world,
                PathSettings {
                    texture_space: integrator.texture_space,
                    ..p
                },
            )
        });
        let rendered = pool.install(|| match (&self.piece, self.ao_image, &path_tracer) {
            (Some(p), _, Some(pt)) => {
                render_region(&world, &camera, pt, &settings, control, p.rect)
            }
            (None, _, Some(pt)) => render_image(&world, &camera, pt, &settings, control),
            (Some(p), false, None) => {
                render_region(&world, &camera, &integrator, &settings, control, p.rect)
            }
            (Some(p), true, None) => {
                render_region(&world, &camera, &ao_integrator, &settings, control, p.rect)
            }
            (None, false, None) => render_image(&world, &camera, &integrator, &settings, control),
            (None, true, None) => render_image(&world, &camera, &ao_integrator, &settings, control),
        });
        let (frame, counters) = (rendered.frame, rendered.counters);
        let render_time = start.elapsed();
        if let Some(b) = bar {
            b.finish_and_clear();
        }
        let mut frame = frame;
        if let Some((v, GridView::Count)) = &voxels {
            let mut canvas =
                Canvas::new(frame.width, frame.height, std::mem::take(&mut frame.color));
            legend(&mut canvas, v.max_count());
            frame.color = canvas.pixels;
        }
        let complete = match &self.piece {
            Some(p) => (p.rect.row0..p.rect.row1).all(|r| frame.complete[r as usize]),
            None => frame.is_complete(),
        };
        let (w, h) = (self.width, self.height);
        let mut written = Vec::new();
        if let (Some(out), Some(p)) = (&self.output, &self.piece) {
            let out = if complete {
                out.clone()
            } else {
                partial_path(out)
            };
            let hash = self.piece_hash(&scene, &settings);
            let stats = serde_json::json!({
                "rays_primary": counters.primary,
                "rays_shadow": counters.shadow,
                "rays_reflected": counters.reflected,
                "rays_refracted": counters.refracted,
                "intersection_tests": counters.intersection_tests,
                "nodes_visited": counters.nodes_visited,
                "render_ms": render_time.as_secs_f64() * 1e3,
            });
            crate::piece::write(&out, &frame, p, &hash, &stats)?;
            written.push(out);
        }
        if let (None, Some(out)) = (&self.piece, &self.output) {
            let out = if complete {
                out.clone()
            } else {
                partial_path(out)
            };
            crate::output::write_rgb_as(&out, w, h, &frame.color, self.encoding)?;
            written.push(out);
        }
        let mut write_sized = |out: &PathBuf,
                               (w, h): (u32, u32),
                               pixels: &[crate::math::Vec3]|
         -> Result<(), JobError> {
            let out = if complete {
                out.clone()
            } else {
                partial_path(out)
            };
            write_rgb(&out, w, h, pixels)?;
            written.push(out);
            Ok(())
        };
        let mut write =
            |out: &PathBuf, pixels: &[crate::math::Vec3]| write_sized(out, (w, h), pixels);
        if let Some((t0, t1, out)) = &self.depth {
            write(out, &frame.depth_image(*t0, *t1))?;
        }
        if let Some(out) = &self.normals {
            write(out, &frame.normals_image())?;
        }
        let mut write_view =
            |out: &PathBuf, img: Image| write_sized(out, (img.width, img.height), &img.pixels);
        if let Some((out, zoom)) = &self.samples_view {
            write_view(out, samples_view(w, h, *zoom, &rendered.samples))?;
        }
        if let Some((out, zoom)) = &self.filter_view {
            write_view(out, filter_view(&settings.filter, w, h, *zoom))?;
        }
        if let Some(out) = &self.samples_image {
            write_view(out, heat_map(w, h, &frame.samples))?;
        }
        if let Some(out) = &self.cost_image {
            let c = crate::viz::cost::image(&frame);
            write_sized(out, (c.width, c.height), &c.pixels)?;
        }
        if !complete {
            return Err(JobError::Interrupted(written));
        }
        let report = Report {
            scene,
            counters,
            accel: world.accel().describe(),
            build_ms: world.build_ms(),
            load_ms,
            world_ms,
            render: render_time,
            primitives: world.prims().len(),
            bounds: world_space(world.bounds(), world.origin()),
            frame,
            settings,
        };
        if let Some(path) = &self.stats_json {
            let text = serde_json::to_string_pretty(&report.stats())
                .map_err(|e| JobError::Internal(e.to_string()))?;
            write_file(path, (text + "\n").as_bytes())?;
        }
        Ok(report)
    }
}

/// Effect ray counts from the command line; `None` keeps the scene's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SampleOverrides {
    /// `--shadow-samples`.
    pub shadow: Option<u32>,
    /// `--glossy-samples`.
    pub glossy: Option<u32>,
    /// `--time-samples`.
    pub time: Option<u32>,
    /// `--lens-samples`.
    pub lens: Option<u32>,
    /// `--ao-samples`.
    pub ao: Option<u32>,
}

impl SampleOverrides {
    /// The scene's counts with these overrides applied.
    pub fn apply(&self, scene: EffectSamples) -> EffectSamples {
        EffectSamples {
            shadow: self.shadow.unwrap_or(scene.shadow),
            glossy: self.glossy.unwrap_or(scene.glossy),
            time: self.time.unwrap_or(scene.time),
            lens: self.lens.unwrap_or(scene.lens),
            ao: self.ao.unwrap_or(scene.ao),
        }
    }
}

/// Whether anything in `scene` takes random decisions: an area light, a
/// glossy material, a shutter interval, a lens, ambient occlusion.
pub fn uses_sampling(scene: &Scene) -> bool {
    let e = &scene.effects;
    scene.lights.iter().any(|l| matches!(l, Light::Area { .. }))
        || scene
            .materials
            .iter()
            .any(|m| matches!(m, Material::Phong(p) if p.glossiness > 0.0))
        || e.lens.has_motion_blur()
        || e.lens.has_depth_of_field()
        || e.ambient_occlusion.is_some()
}

fn progress_bar(pixels: u64) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(pixels);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{bar:40} {percent:>3}% pixels {pos}/{len}  elapsed {elapsed}  eta {eta}",
    ) {
        bar.set_style(style);
    }
    bar
}

/// The statistics of one render, as printed by `--stats` and written by
/// `--stats-json` (the keys are the JSON field names).
#[derive(Clone, Debug, serde::Serialize)]
pub struct Stats {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Aggregate and its parameters.
    pub accel: String,
    /// Primitives in the world (mesh triangles count one each).
    pub primitives: usize,
    /// Triangles in the scene.
    pub triangles: usize,
    /// Scene and mesh reading time.
    pub load_ms: f64,
    /// Flattening plus aggregate build time.
    pub world_ms: f64,
    /// Aggregate build time.
    pub build_ms: f64,
    /// Tracing time.
    pub render_ms: f64,
    /// Eye rays.
    pub rays_primary: u64,
    /// Shadow rays.
    pub rays_shadow: u64,
    /// Reflected rays.
    pub rays_reflected: u64,
    /// Refracted rays.
    pub rays_refracted: u64,
    /// Of the reflected and refracted rays, those over a glossy lobe.
    pub rays_glossy: u64,
    /// Ambient-occlusion rays.
    pub rays_occlusion: u64,
    /// All rays.
    pub rays_total: u64,
    /// Ray–primitive intersection tests.
    pub intersection_tests: u64,
    /// Nodes or cells visited.
    pub nodes_visited: u64,
    /// Tests per ray.
    pub tests_per_ray: f64,
    /// Nodes or cells per ray.
    pub nodes_per_ray: f64,
    /// Rays per second of tracing time.
    pub rays_per_second: f64,
    /// Pixel sampling: sampler and samples per pixel, or adaptive settings.
    pub sampling: String,
    /// Reconstruction filter.
    pub filter: String,
    /// Camera rays per pixel (samples per pixel).
    pub samples_per_pixel: f64,
    /// Rays of every kind per pixel.
    pub rays_per_pixel: f64,
}

/// Bytes per pixel of a [`Frame`] (colour `Vec3`, depth `f32`, normal
/// `Vec3`, sample count `u32`) plus the tile films' filter sums (`Vec3` and
/// `f32`) that exist until the merge.
pub const FRAME_BYTES_PER_PIXEL: u64 = 12 + 4 + 12 + 4 + 16 + 16;

pub use crate::limits::FALLBACK_AVAILABLE;

/// Bytes this process can allocate now: see [`limits::available_memory`]
/// (`MemAvailable`, and the address-space limit if one is set).
pub fn available_memory() -> u64 {
    limits::available_memory()
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
    /// The statistics of this render.
    pub fn stats(&self) -> Stats {
        let c = &self.counters;
        let rays = c.rays_total().max(1) as f64;
        let pixels = (u64::from(self.frame.width) * u64::from(self.frame.height)).max(1) as f64;
        let secs = self.render.as_secs_f64();
        Stats {
            width: self.frame.width,
            height: self.frame.height,
            accel: self.accel.clone(),
            primitives: self.primitives,
            triangles: self.scene.summary().triangles,
            load_ms: self.load_ms,
            world_ms: self.world_ms,
            build_ms: self.build_ms,
            render_ms: secs * 1e3,
            rays_primary: c.primary,
            rays_shadow: c.shadow,
            rays_reflected: c.reflected,
            rays_refracted: c.refracted,
            rays_glossy: c.glossy,
            rays_occlusion: c.occlusion,
            rays_total: c.rays_total(),
            intersection_tests: c.intersection_tests,
            nodes_visited: c.nodes_visited,
            tests_per_ray: c.intersection_tests as f64 / rays,
            nodes_per_ray: c.nodes_visited as f64 / rays,
            rays_per_second: rays / secs.max(1e-9),
            sampling: describe_sampling(&self.settings),
            filter: if self.settings.adaptive.is_some() {
                "pixel square (adaptive)".into()
            } else {
                self.settings.filter.to_string()
            },
            samples_per_pixel: c.primary as f64 / pixels,
            rays_per_pixel: c.rays_total() as f64 / pixels,
        }
    }

    /// The human-readable statistics table.
    pub fn stats_text(&self) -> String {
        let st = self.stats();
        let mut s = String::new();
        let mut line = |k: &str, v: String| s.push_str(&format!("{k:<28}{v}\n"));
        line("image", format!("{}x{}", st.width, st.height));
        line("accelerator", st.accel.clone());
        line("primitives", st.primitives.to_string());
        line("triangles", st.triangles.to_string());
        line("load time", format!("{:.2} ms", st.load_ms));
        line(
            "world time",
            format!("{:.2} ms (flatten + build)", st.world_ms),
        );
        line("build time", format!("{:.2} ms", st.build_ms));
        line("render time", format!("{:.2} ms", st.render_ms));
        line("primary rays", st.rays_primary.to_string());
        line("shadow rays", st.rays_shadow.to_string());
        line("reflected rays", st.rays_reflected.to_string());
        line("refracted rays", st.rays_refracted.to_string());
        line("  of which glossy", st.rays_glossy.to_string());
        line("occlusion rays", st.rays_occlusion.to_string());
        line("rays total", st.rays_total.to_string());
        line("intersection tests", st.intersection_tests.to_string());
        line("nodes visited", st.nodes_visited.to_string());
        line("sampling", st.sampling.clone());
        line("filter", st.filter.clone());
        line("rays / second", format!("{:.0}", st.rays_per_second));
        line("samples / pixel", format!("{:.3}", st.samples_per_pixel));
        line("rays / pixel", format!("{:.3}", st.rays_per_pixel));
        line("tests / ray", format!("{:.3}", st.tests_per_ray));
        line("nodes / ray", format!("{:.3}", st.nodes_per_ray));
        s
    }
}

/// One line naming how pixels were sampled.
fn describe_sampling(s: &Settings) -> String {
    match s.adaptive {
        Some(a) => format!(
            "adaptive (threshold {}, max depth {})",
            a.threshold, a.max_depth
        ),
        None => format!(
            "{} x {} (seed {})",
            s.sampler.kind,
            s.sampler.spp(),
            s.sampler.seed
        ),
    }
}

/// Runs a binary's `main` body so that a bug in glint reaches the user as one
/// line naming it an internal error, with exit status 1, and never as a Rust
/// panic message with a backtrace hint.
pub fn run_guarded(
    program: &'static str,
    body: impl FnOnce() -> std::process::ExitCode,
) -> std::process::ExitCode {
    std::panic::set_hook(Box::new(move |info| {
        let place = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        let what = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_default();
        eprintln!("{program}: internal error (a bug in glint, please report it): {what}{place}");
    }));
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(body)) {
        Ok(code) => code,
        Err(_) => std::process::ExitCode::from(1),
    }
}

/// `b` (rendering space) moved back to world space by the rendering
/// origin `o`; an empty box stays empty.
fn world_space(b: crate::math::Aabb, o: glam::DVec3) -> crate::math::Aabb {
    if b.is_empty() {
        return b;
    }
    let shift = |v: crate::math::Vec3| (v.as_dvec3() + o).as_vec3();
    crate::math::Aabb {
        min: shift(b.min),
        max: shift(b.max),
    }
}

/// The course's statistics report (`raytracing_stats.C`, NOTES.md A6), for
/// `raytracer -stats`: time, pixels, scene bounds, grid cells, rays by kind,
/// intersections, cells traversed and the per-ray figures, which count
/// non-shadow plus shadow rays. `glint --stats` and `--stats-json` keep the
/// full counters.
pub fn course_stats_text(report: &Report) -> String {
    // The grid's resolution, from its description (`grid 10x10x7`).
    let grid: Option<[u32; 3]> = report.accel.strip_prefix("grid ").and_then(|r| {
        let v: Vec<u32> = r.split('x').filter_map(|n| n.trim().parse().ok()).collect();
        <[u32; 3]>::try_from(v).ok()
    });
    let bounds = Some(report.bounds);
    let st = report.stats();
    let secs = report.render.as_secs_f64();
    let whole = secs as u64;
    let pixels = u64::from(st.width) * u64::from(st.height);
    let rays = st.rays_total.max(1) as f64;
    let non_shadow = st.rays_total - st.rays_shadow;
    let mut s =
        String::from("********************************************\nRAY TRACING STATISTICS\n");
    let mut line = |k: &str, v: String| s.push_str(&format!("  {k:<27}{v}\n"));
    line(
        "total time",
        format!("{}:{:02}:{:02}", whole / 3600, whole / 60 % 60, whole % 60),
    );
    line(
        "num pixels",
        format!("{pixels} ({}x{})", st.width, st.height),
    );
    line(
        "scene bounds",
        match bounds.filter(|b| !b.is_empty()) {
            Some(b) => format!(
                "({:.4}, {:.4}, {:.4}) -> ({:.4}, {:.4}, {:.4})",
                b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
            ),
            None => "NULL".into(),
        },
    );
    line(
        "num grid cells",
        match grid {
            Some([x, y, z]) => format!(
                "{} ({x}x{y}x{z})",
                u64::from(x) * u64::from(y) * u64::from(z)
            ),
            None => "NULL".into(),
        },
    );
    line("num non-shadow rays", non_shadow.to_string());
    line("num shadow rays", st.rays_shadow.to_string());
    line("total intersections", st.intersection_tests.to_string());
    line("total cells traversed", st.nodes_visited.to_string());
    line("rays per second", format!("{:.1}", rays / secs.max(1e-9)));
    line(
        "rays per pixel",
        format!("{:.3}", rays / pixels.max(1) as f64),
    );
    line(
        "intersections per ray",
        format!("{:.3}", st.intersection_tests as f64 / rays),
    );
    line(
        "cells traversed per ray",
        format!("{:.3}", st.nodes_visited as f64 / rays),
    );
    s.push_str("********************************************\n");
    s
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
        assert!(msg.contains("596.0 GiB"), "{msg}");
        assert!(msg.contains("12.0 GiB allowed"), "{msg}");
        // The product cannot overflow.
        assert!(check_frame_memory(u32::MAX, u32::MAX, u64::MAX).is_err());
        assert!(available_memory() > 0);
    }
}
