//! What a job asks for, as both command lines describe it, and the one
//! place where every number of a request is checked against its range
//! ([`Job::validate`]).

use super::outputs::Output;
use super::JobError;
use crate::accel::AccelKind;
use crate::animation::FrameTime;
use crate::integrator::{IntegratorKind, Whitted};
use crate::limits;
use crate::material::TextureSpace;
use crate::output::Encoding;
use crate::piece::PieceSpec;
use crate::render::{Adaptive, Filter, PixelOffset, Settings, TILE_SIZE};
use crate::sampler::{Sampler, SamplerKind};
use crate::scene::{EffectSamples, Light, Material, Scene};
use crate::viz::grid::GridView;
use crate::world::BuildOptions;
use std::path::PathBuf;

/// A render request: what to load, how to shade and sample it, what to write.
#[derive(Clone, Debug)]
pub struct Job {
    /// Scene file.
    pub input: PathBuf,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Which integrator computes the image.
    pub integrator: IntegratorKind,
    /// The ray tree's settings.
    pub shading: Shading,
    /// Where in the pixels rays go and how samples are reconstructed.
    pub sampling: Sampling,
    /// World-building settings.
    pub build: BuildOptions,
    /// Worker threads (all cores when `None`).
    pub threads: Option<usize>,
    /// The files to write, at most one of each kind ([`Job::set_output`]).
    pub outputs: Vec<Output>,
    /// Render only this piece of the frame and write it as an EXR with a
    /// data window (`--tile I/N`, `--crop`); see [`crate::piece`].
    pub piece: Option<PieceSpec>,
    /// Render this frame of the scene's animation (`--frame K --fps F`):
    /// the shutter interval moves to start at `K / F`; see
    /// [`crate::animation`].
    pub frame: Option<FrameTime>,
    /// Render the uniform grid's occupied cells instead of the scene
    /// (`-visualize_grid`, `-visualize_grid_count`); the grid's resolution is
    /// the one `build.accel` asks for, if it is a grid.
    pub visualize_grid: Option<GridView>,
    /// How the colour image's 8-bit formats encode values (the course's
    /// linear truncation unless `glint render --srgb`).
    pub encoding: Encoding,
}

/// The ray tree's settings, as the command lines give them; the scene adds
/// its effect samples when the job renders ([`Shading::whitted`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shading {
    /// Maximum number of reflection/refraction bounces.
    pub bounces: u32,
    /// Prune branches contributing less than this.
    pub weight_cutoff: f32,
    /// Cast shadow rays.
    pub shadows: bool,
    /// Filter light through transparent occluders.
    pub transparent_shadows: bool,
    /// Light the back sides of surfaces.
    pub shade_back: bool,
    /// Where textures are looked up.
    pub texture_space: TextureSpace,
    /// Shade every mesh smooth (`--smooth`): see [`Scene::smooth_meshes`].
    pub smooth: bool,
}

impl Default for Shading {
    /// The course's defaults: local shading only, no shadows.
    fn default() -> Self {
        let w = Whitted::default();
        Self {
            bounces: w.bounces,
            weight_cutoff: w.weight_cutoff,
            shadows: w.shadows,
            transparent_shadows: w.transparent_shadows,
            shade_back: w.shade_back,
            texture_space: w.texture_space,
            smooth: false,
        }
    }
}

impl Shading {
    /// The ray tree with these settings and one ray per effect.
    pub fn whitted(&self) -> Whitted {
        Whitted {
            bounces: self.bounces,
            weight_cutoff: self.weight_cutoff,
            shadows: self.shadows,
            transparent_shadows: self.transparent_shadows,
            shade_back: self.shade_back,
            texture_space: self.texture_space,
            ..Whitted::default()
        }
    }

    /// Bounces and weight in their ranges ([`limits`]).
    pub fn validate(&self, names: FlagNames) -> Result<(), String> {
        limits::int_in(&names.flag("bounces"), self.bounces, 0, limits::MAX_BOUNCES)?;
        limits::finite_in(&names.flag("weight"), self.weight_cutoff, 0.0, f32::MAX)?;
        Ok(())
    }
}

/// How pixels are sampled and reconstructed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampling {
    /// Where in the pixel the eye ray goes with one sample per pixel, and the
    /// point whose nearest sample fills the depth and normal planes.
    pub pixel_offset: PixelOffset,
    /// Camera samples per pixel.
    pub spp: u32,
    /// Their layout; `None`: one ray at `pixel_offset` when `spp` is 1,
    /// Owen-scrambled Sobol otherwise.
    pub sampler: Option<SamplerKind>,
    /// Seed of the random samplers.
    pub seed: u64,
    /// Reconstruction filter.
    pub filter: Filter,
    /// Whitted's adaptive subdivision with this threshold instead of the
    /// sampler's positions.
    pub adaptive: Option<f32>,
    /// Deepest adaptive subdivision.
    pub max_depth: u32,
    /// Rays per effect given on the command line; each one set overrides
    /// the scene's `Samples`/`AmbientOcclusion` count.
    pub effects: SampleOverrides,
}

impl Default for Sampling {
    fn default() -> Self {
        Self {
            pixel_offset: PixelOffset::CENTER,
            spp: 1,
            sampler: None,
            seed: 0,
            filter: Filter::default(),
            adaptive: None,
            max_depth: Adaptive::DEFAULT_MAX_DEPTH,
            effects: SampleOverrides::default(),
        }
    }
}

impl Sampling {
    /// The sampler asked for; `None`: the fixed one-ray sampler.
    pub fn sampler(&self) -> Option<Sampler> {
        (self.spp > 1 || self.sampler.is_some()).then(|| {
            Sampler::new(
                self.sampler.unwrap_or(SamplerKind::Sobol),
                self.spp,
                self.seed,
            )
        })
    }

    /// The adaptive subdivision asked for.
    pub fn adaptive(&self) -> Option<Adaptive> {
        self.adaptive.map(|threshold| Adaptive {
            threshold,
            max_depth: self.max_depth,
        })
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

/// What the depth flags mean together (named as `names` spells them):
/// `--max-depth D` (`max_depth`), `--adaptive-depth D` (`adaptive_depth`),
/// whether `--adaptive` is on, and `--bounces N` (`bounces`). Returns the
/// adaptive subdivision depth, and the path tracer's depth limit when
/// `--max-depth` gives it (`None`: `--bounces` or the default decides).
///
/// `--max-depth` is the adaptive subdivision's depth, except under
/// `--integrator path` without `--adaptive`, where it is the path's depth
/// limit (the name issue 37 gives it): N scattering events, as
/// `--bounces N` (0 shows the emitters alone, 1 adds direct light;
/// Mitsuba's `max_depth` is N + 1). Under `--integrator path` with
/// `--adaptive` it could mean either: an error that names the unambiguous
/// flags, `--bounces` and `--adaptive-depth`. Giving one depth twice is an
/// error too.
pub fn depths(
    names: FlagNames,
    integrator: IntegratorKind,
    max_depth: Option<u32>,
    adaptive_depth: Option<u32>,
    adaptive: bool,
    bounces: Option<u32>,
) -> Result<(u32, Option<u32>), String> {
    let [max, ad, b, ia, it] = [
        "max-depth",
        "adaptive-depth",
        "bounces",
        "adaptive",
        "integrator",
    ]
    .map(|f| names.flag(f));
    let adaptive_depth_or_default = adaptive_depth.unwrap_or(Adaptive::DEFAULT_MAX_DEPTH);
    let Some(d) = max_depth else {
        return Ok((adaptive_depth_or_default, None));
    };
    if !matches!(integrator, IntegratorKind::Path(_)) {
        if adaptive_depth.is_some() {
            return Err(format!(
                "{max} and {ad} both set the adaptive subdivision depth: give one"
            ));
        }
        return Ok((d, None));
    }
    if adaptive {
        return Err(format!(
            "{max} {d} is ambiguous with {it} path and {ia}: give the path's depth limit as \
             {b} N (N scattering events) and the adaptive subdivision depth as {ad} D"
        ));
    }
    if bounces.is_some() {
        return Err(format!(
            "{max} {d} and {b} both set the path's depth limit under {it} path: give one"
        ));
    }
    limits::int_in(&max, d, 0, limits::MAX_BOUNCES)?;
    Ok((adaptive_depth_or_default, Some(d)))
}

/// How a validation message names a setting: as the flag of the command
/// line that set it, or plainly for a library caller.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlagNames {
    /// `glint`'s flags: `--max-depth`.
    Glint,
    /// The course's `raytracer` flags: `-max_depth`.
    Course,
    /// The setting's name alone: `max-depth`.
    Plain,
}

impl FlagNames {
    /// The flag of the setting named `long` (glint's spelling, no dashes).
    pub fn flag(self, long: &str) -> String {
        match self {
            FlagNames::Glint => format!("--{long}"),
            FlagNames::Course => format!("-{}", long.replace('-', "_")),
            FlagNames::Plain => long.to_owned(),
        }
    }

    /// The flag that set the samples per pixel: `raytracer` has one flag a
    /// layout.
    fn spp(self, kind: Option<SamplerKind>) -> String {
        let course = match kind {
            Some(SamplerKind::Uniform(_)) => "uniform_samples",
            Some(SamplerKind::Random) => "random_samples",
            Some(SamplerKind::Jittered) => "jittered_samples",
            _ => "sobol_samples",
        };
        match self {
            FlagNames::Course => format!("-{course}"),
            _ => self.flag("spp"),
        }
    }

    /// The flag that set the filter: `raytracer` has one flag a shape.
    fn filter(self, f: Filter) -> String {
        match (self, f) {
            (FlagNames::Course, Filter::Box(_)) => "-box_filter".into(),
            (FlagNames::Course, Filter::Tent(_)) => "-tent_filter".into(),
            (FlagNames::Course, Filter::Gaussian(_) | Filter::GaussianSquare(_)) => {
                "-gaussian_filter".into()
            }
            _ => self.flag("filter"),
        }
    }

    /// The flag that set a grid's resolution.
    fn grid(self) -> String {
        match self {
            FlagNames::Course => "-grid".into(),
            _ => self.flag("accel"),
        }
    }
}

impl Job {
    /// A job with the course's defaults and no outputs yet.
    pub fn new(input: PathBuf, width: u32, height: u32) -> Self {
        Self {
            input,
            width,
            height,
            integrator: IntegratorKind::default(),
            shading: Shading::default(),
            sampling: Sampling::default(),
            build: BuildOptions::default(),
            threads: None,
            outputs: Vec::new(),
            piece: None,
            frame: None,
            visualize_grid: None,
            encoding: Encoding::Linear,
        }
    }

    /// Every number of the request in its documented range ([`limits`]),
    /// named as `names` spells the flags. Returns notes to print: a thread
    /// count above [`limits::THREADS_PER_CORE`] per core is accepted and
    /// clamped ([`Job::pool_threads`]).
    pub fn validate(&self, names: FlagNames) -> Result<Vec<String>, JobError> {
        self.check_ranges(names).map_err(JobError::Usage)?;
        let mut notes = Vec::new();
        if let Some(n) = self.threads {
            let (_, note) = limits::threads(&names.flag("threads"), n, limits::cores())
                .map_err(JobError::Usage)?;
            notes.extend(note);
        }
        Ok(notes)
    }

    fn check_ranges(&self, names: FlagNames) -> Result<(), String> {
        if self.width == 0 || self.height == 0 {
            return Err(format!(
                "image size {}x{}: width and height must be at least 1",
                self.width, self.height
            ));
        }
        self.shading.validate(names)?;
        let s = &self.sampling;
        limits::int_in(&names.spp(s.sampler), s.spp, 1, limits::MAX_SAMPLES)?;
        s.filter
            .validate()
            .map_err(|e| format!("{}: {e}", names.filter(s.filter)))?;
        if let Some(t) = s.adaptive {
            limits::finite_in(&names.flag("adaptive"), t, 0.0, f32::MAX)?;
        }
        limits::int_in(
            &names.flag("max-depth"),
            s.max_depth,
            0,
            Adaptive::MAX_DEPTH,
        )?;
        let e = &s.effects;
        for (name, n) in [
            ("shadow-samples", e.shadow),
            ("glossy-samples", e.glossy),
            ("time-samples", e.time),
            ("lens-samples", e.lens),
            ("ao-samples", e.ao),
        ] {
            if let Some(n) = n {
                limits::int_in(&names.flag(name), n, 1, limits::MAX_SAMPLES)?;
            }
        }
        if let IntegratorKind::Path(p) = self.integrator {
            limits::int_in(
                &names.flag("caustic-photons"),
                p.caustic_map.photons,
                0,
                limits::MAX_PHOTONS,
            )?;
        }
        if let AccelKind::Grid { res: Some(r) } = self.build.accel {
            if r.contains(&0) {
                return Err(format!(
                    "{} {} {} {}: every resolution must be at least 1",
                    names.grid(),
                    r[0],
                    r[1],
                    r[2]
                ));
            }
        }
        self.outputs.iter().try_for_each(|o| o.validate(names))
    }

    /// Worker threads for the pool: the count asked for, at most
    /// [`limits::THREADS_PER_CORE`] per core; 0 (one per core) if none.
    pub fn pool_threads(&self) -> usize {
        self.threads.map_or(0, |n| {
            limits::threads("threads", n, limits::cores()).map_or(n, |(n, _)| n)
        })
    }

    /// The render settings this job asks for.
    pub fn settings(&self) -> Settings {
        let s = &self.sampling;
        let mut out = Settings::one_ray((self.width, self.height), s.pixel_offset);
        if let Some(sampler) = s.sampler() {
            out.sampler = sampler;
        }
        out.filter = s.filter;
        out.adaptive = s.adaptive();
        out.keep_samples = self
            .outputs
            .iter()
            .any(|o| matches!(o, Output::SamplesView { .. }));
        out.pixel_cost = self.outputs.iter().any(|o| matches!(o, Output::Cost(_)));
        out.tile_size = TILE_SIZE;
        out
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
        let sampled = self.integrator != IntegratorKind::Whitted || uses_sampling(scene);
        let kind = match self.sampling.sampler() {
            Some(sm) => sm.kind,
            None if camera_rays > 1 || sampled => SamplerKind::Sobol,
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

    /// This job for frame `f` of the scene's animation: [`Job::frame`] set,
    /// and the last run of `#` in every output file name replaced by the
    /// frame number ([`crate::animation::frame_path`]), so one command line
    /// serves every frame of a job array.
    pub fn at_frame(mut self, f: FrameTime) -> Self {
        for o in &mut self.outputs {
            let p = o.path_mut();
            *p = crate::animation::frame_path(p, f.index);
        }
        self.frame = Some(f);
        self
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Every range is checked here, named as the command line spells it.
    #[test]
    fn validate_names_the_flag_of_each_range() {
        type Case = (fn(&mut Job), &'static str, &'static str);
        let cases: [Case; 11] = [
            (
                |j| j.shading.bounces = 65,
                "--bounces: 65 is out of range (0 to 64)",
                "-bounces: 65",
            ),
            (
                |j| j.shading.weight_cutoff = f32::NAN,
                "--weight: NaN",
                "-weight: NaN",
            ),
            (|j| j.threads = Some(0), "--threads: 0", "-threads: 0"),
            (
                |j| {
                    j.sampling.spp = 0;
                    j.sampling.sampler = Some(SamplerKind::Random);
                },
                "--spp: 0",
                "-random_samples: 0",
            ),
            (
                |j| j.sampling.max_depth = 9,
                "--max-depth: 9",
                "-max_depth: 9",
            ),
            (
                |j| j.sampling.adaptive = Some(-1.0),
                "--adaptive: -1",
                "-adaptive: -1",
            ),
            (
                |j| j.sampling.filter = Filter::Tent(0.0),
                "--filter: tent radius 0",
                "-tent_filter: tent radius 0",
            ),
            (
                |j| {
                    j.build.accel = AccelKind::Grid {
                        res: Some([0, 1, 1]),
                    }
                },
                "--accel 0 1 1: every resolution",
                "-grid 0 1 1: every resolution",
            ),
            (
                |j| {
                    j.set_output(Output::Depth {
                        near: 0.0,
                        far: f32::INFINITY,
                        path: "d.png".into(),
                    })
                },
                "--depth: inf",
                "-depth: inf",
            ),
            (
                |j| {
                    j.set_output(Output::SamplesView {
                        path: "v.png".into(),
                        zoom: 0,
                    })
                },
                "--render-samples: 0",
                "-render_samples: 0",
            ),
            (|j| j.width = 0, "image size 0x8", "image size 0x8"),
        ];
        for (set, glint, course) in cases {
            let mut j = Job::new("s.txt".into(), 8, 8);
            set(&mut j);
            let e = j.validate(FlagNames::Glint).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(e.to_string().starts_with(glint), "{e} (wanted {glint})");
            let e = j.validate(FlagNames::Course).unwrap_err().to_string();
            assert!(e.starts_with(course), "{e} (wanted {course})");
        }
    }

    #[test]
    fn effect_sample_overrides_are_bounded() {
        let mut j = Job::new("s.txt".into(), 8, 8);
        assert!(j.validate(FlagNames::Plain).unwrap().is_empty());
        j.sampling.effects.ao = Some(4097);
        let e = j.validate(FlagNames::Glint).unwrap_err().to_string();
        assert!(e.starts_with("--ao-samples: 4097"), "{e}");
        j.sampling.effects.ao = Some(4096);
        assert!(j.validate(FlagNames::Glint).is_ok());
    }

    #[test]
    fn many_threads_are_clamped_with_a_note() {
        let mut j = Job::new("s.txt".into(), 8, 8);
        j.threads = Some(limits::MAX_THREADS);
        let notes = j.validate(FlagNames::Course).unwrap();
        let cap = limits::cores() * limits::THREADS_PER_CORE;
        assert!(j.pool_threads() <= cap.min(limits::MAX_THREADS));
        if cap < limits::MAX_THREADS {
            assert!(notes[0].starts_with("-threads 1024: using"), "{notes:?}");
        }
    }
}
