//! The argument groups the subcommands share (flattened into each), so a
//! flag means the same and has the same default in `render`, `raytree`,
//! `traverse` and `structure`.

use clap::Args;
use glint::accel::AccelKind;
use glint::integrator::IntegratorKind;
use glint::job::{FlagNames, SampleOverrides, Sampling, Shading};
use glint::material::TextureSpace;
use glint::render::{Filter, PixelOffset};
use glint::sampler::SamplerKind;
use std::path::PathBuf;

/// The scene and its accelerator.
#[derive(Args)]
pub struct SceneArgs {
    /// Scene file (MIT 6.837 format), a bare .obj or .ply mesh, or a glTF 2.0 scene (.gltf, .glb).
    pub scene: PathBuf,
    /// Accelerator: bvh8 (the fast default; bvh4 is an alias), none, grid, grid:NxNxN, nested-grid[:THRESHOLD[:DEPTH]] (defaults 16:2), octree, octree-inner, bvh (= bvh-sah), bvh-median, bvh-midpoint, bvh-hierarchy. `traverse` and `structure` show the one named (bvh8 as its binary SAH twin).
    #[arg(long, default_value = "bvh8")]
    pub accel: AccelKind,
}

/// The output file and the image size.
#[derive(Args)]
pub struct ImageArgs {
    /// Output file; its extension chooses the format (the formats are in the command's description).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Image size in pixels.
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = [400, 400])]
    pub size: Vec<u32>,
}

impl ImageArgs {
    /// `(width, height)`.
    pub fn size(&self) -> (u32, u32) {
        (self.size[0], self.size[1])
    }
}

/// The ray tree's settings.
#[derive(Args)]
pub struct ShadingArgs {
    /// Maximum number of reflection/refraction bounces (0 to 64; default 5). With --integrator path: scattering events per path (default 64; 0 shows emitters only, 1 direct light; Mitsuba's max_depth is one more); --max-depth says the same there.
    #[arg(long)]
    pub bounces: Option<u32>,
    /// Prune ray-tree branches contributing less than this (finite, >= 0).
    #[arg(long, default_value_t = 0.01)]
    pub weight: f32,
    /// Cast shadow rays.
    #[arg(long)]
    pub shadows: bool,
    /// Filter light through transparent occluders instead of opaque shadows (implies --shadows).
    #[arg(long)]
    pub transparent_shadows: bool,
    /// Light the back sides of surfaces.
    #[arg(long)]
    pub shade_back: bool,
    /// Where textures are looked up: world (what 6.837 scenes are written for) or object (textures stick to moving objects).
    #[arg(long, value_enum, default_value_t = Space::World)]
    pub texture_space: Space,
    /// Smooth shading for every mesh: vertex normals interpolated across triangles, computed (angle-weighted) for meshes whose file has none. Meshes whose file gives normals (PLY, glTF) are smooth without it.
    #[arg(long)]
    pub smooth: bool,
}

/// Command-line names of [`TextureSpace`].
#[derive(Clone, Copy, clap::ValueEnum)]
pub enum Space {
    World,
    Object,
}

impl ShadingArgs {
    /// The settings for `integrator`, whose default bounces apply when none
    /// are given (ranges are checked by the job's `validate`).
    pub fn shading(&self, integrator: IntegratorKind) -> Shading {
        Shading {
            bounces: self.bounces.unwrap_or(integrator.default_bounces()),
            weight_cutoff: self.weight,
            shadows: self.shadows || self.transparent_shadows,
            transparent_shadows: self.transparent_shadows,
            shade_back: self.shade_back,
            texture_space: match self.texture_space {
                Space::World => TextureSpace::World,
                Space::Object => TextureSpace::Object,
            },
            smooth: self.smooth,
        }
    }
}

/// Where samples go in the pixels, how many, and how they are filtered.
#[derive(Args)]
pub struct SamplingArgs {
    /// Samples (camera rays) per pixel (1 to 4096).
    #[arg(long, default_value_t = 1)]
    pub spp: u32,
    /// Sample layout: uniform (grid of cell centres), random, jittered, sobol (Owen-scrambled; the default with --spp above 1).
    #[arg(long)]
    pub sampler: Option<SamplerKind>,
    /// Seed of the random samplers (changes the noise, not its statistics).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Reconstruction filter: box:R, tent:R or gaussian:SIGMA (radius in pixels; gaussian cut at 2 sigma, a round kernel; `raytracer -gaussian_filter` keeps the course's square kernel, also gaussian-square:SIGMA).
    #[arg(long, default_value = "box:0.5")]
    pub filter: Filter,
    /// Whitted's adaptive supersampling: split a pixel square where its corners differ by more than this (0..1).
    #[arg(long, value_name = "THRESHOLD")]
    pub adaptive: Option<f32>,
    /// Deepest adaptive subdivision (squares of 2^-D pixels), 0 to 8 (default 2). With --integrator path: the path's depth limit instead, as --bounces N (N scattering events, 0 to 64: 0 shows emitters only, 1 direct light; Mitsuba's max_depth is N+1); with --integrator path and --adaptive it is ambiguous (an error): use --bounces and --adaptive-depth.
    #[arg(long, value_name = "D")]
    pub max_depth: Option<u32>,
    /// Deepest adaptive subdivision (squares of 2^-D pixels), 0 to 8 (default 2): --max-depth's adaptive meaning under any integrator.
    #[arg(long, value_name = "D")]
    pub adaptive_depth: Option<u32>,
    /// Shadow rays per area light per shaded point, 1 to 4096 (overrides the scene's Samples).
    #[arg(long, value_name = "N")]
    pub shadow_samples: Option<u32>,
    /// Rays per glossy lobe, 1 to 4096 (overrides the scene's Samples).
    #[arg(long, value_name = "N")]
    pub glossy_samples: Option<u32>,
    /// Shutter instants per pixel sample, 1 to 4096: camera rays = spp x time x lens (overrides the scene's Samples).
    #[arg(long, value_name = "N")]
    pub time_samples: Option<u32>,
    /// Lens points per pixel sample, 1 to 4096: camera rays = spp x time x lens (overrides the scene's Samples).
    #[arg(long, value_name = "N")]
    pub lens_samples: Option<u32>,
    /// Ambient-occlusion rays per shaded point, 1 to 4096 (overrides the scene's AmbientOcclusion).
    #[arg(long, value_name = "N")]
    pub ao_samples: Option<u32>,
}

impl SamplingArgs {
    /// The settings, with one ray through each pixel's centre when there
    /// is one sample per pixel (ranges are checked by the job's `validate`),
    /// and the path depth `--max-depth` gives under `integrator` (see
    /// [`glint::job::depths`]).
    pub fn sampling(
        &self,
        shading: &ShadingArgs,
        integrator: IntegratorKind,
    ) -> Result<(Sampling, Option<u32>), String> {
        let (max_depth, bounces) = glint::job::depths(
            FlagNames::Glint,
            integrator,
            self.max_depth,
            self.adaptive_depth,
            self.adaptive.is_some(),
            shading.bounces,
        )?;
        let sampling = Sampling {
            pixel_offset: PixelOffset::CENTER,
            spp: self.spp,
            sampler: self.sampler,
            seed: self.seed,
            filter: self.filter,
            adaptive: self.adaptive,
            max_depth,
            effects: SampleOverrides {
                shadow: self.shadow_samples,
                glossy: self.glossy_samples,
                time: self.time_samples,
                lens: self.lens_samples,
                ao: self.ao_samples,
            },
        };
        Ok((sampling, bounces))
    }
}
