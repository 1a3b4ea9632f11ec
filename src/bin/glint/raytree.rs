//! `glint raytree SCENE --pixel X Y -o FILE`: every ray one pixel spawns
//! (with `--integrator path`: one path of the path tracer).

use crate::args::{ImageArgs, SceneArgs, ShadingArgs};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::Args;
use glint::app::usage;
use glint::integrator::{IntegratorKind, PathSettings, PathTracer};
use glint::job::{FlagNames, JobError};
use glint::render::{CameraModel, PixelOffset};
use glint::sampler::{Sampler, SamplerKind};
use glint::viz::raytree;
use glint::world::{BuildOptions, World};

/// Arguments of `glint raytree`.
#[derive(Args)]
pub struct RaytreeArgs {
    // The accelerator does not change the tree.
    #[command(flatten)]
    scene: SceneArgs,
    /// The pixel: x from the left, y from the top (0-based).
    #[arg(long, num_args = 2, value_names = ["X", "Y"], required = true)]
    pixel: Vec<u32>,
    // Output: .json (the tree), .obj or .ply (segments to load beside the
    // scene), .png/.tga/.ppm/.bmp (the image with the tree drawn over it).
    #[command(flatten)]
    image: ImageArgs,
    #[command(flatten)]
    shading: ShadingArgs,
    /// Whose rays: whitted (the ray tree the shaded image traces through the pixel centre) or path (one path of the path tracer, with its light samples and their MIS weights; see --sample).
    #[arg(long, default_value = "whitted", value_parser = PossibleValuesParser::new(["whitted", "path"]).try_map(|s| s.parse::<IntegratorKind>()))]
    integrator: IntegratorKind,
    /// With --integrator path: which sample of the pixel (0-based, below --spp) to trace, as `glint render --integrator path` with the same --spp, --sampler and --seed traces it.
    #[arg(long, default_value_t = 0)]
    sample: u32,
    /// With --integrator path: samples per pixel of the render whose path is shown (1 to 4096).
    #[arg(long, default_value_t = 1)]
    spp: u32,
    /// With --integrator path: the sampler of that render (default sobol, as the path tracer renders).
    #[arg(long)]
    sampler: Option<SamplerKind>,
    /// With --integrator path: the seed of that render.
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

/// Runs `glint raytree`.
pub fn run(a: RaytreeArgs) -> Result<(), JobError> {
    let (w, h) = a.image.size();
    let (x, y) = (a.pixel[0], a.pixel[1]);
    let output = &a.image.output;
    if w == 0 || h == 0 {
        return Err(usage(format!(
            "image size {w}x{h}: width and height must be at least 1"
        )));
    }
    if x >= w || y >= h {
        return Err(usage(format!(
            "--pixel {x} {y} is outside the {w}x{h} image"
        )));
    }
    let ext = output
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let image = !matches!(ext.as_str(), "json" | "obj" | "ply");
    if image {
        glint::output::check_image(output, w, h)
            .map_err(|e| usage(format!("{e} (or .json, .obj, .ply for the tree itself)")))?;
    }
    let path = matches!(a.integrator, IntegratorKind::Path(_));
    if !path && (a.sample != 0 || a.spp != 1 || a.sampler.is_some() || a.seed != 0) {
        return Err(usage(
            "--sample, --spp, --sampler and --seed choose a path: they need --integrator path"
                .to_string(),
        ));
    }
    if !(1..=4096).contains(&a.spp) {
        return Err(usage(format!(
            "--spp {}: expected a sample count from 1 to 4096",
            a.spp
        )));
    }
    if a.sample >= a.spp {
        return Err(usage(format!(
            "--sample {} is not one of the {} samples per pixel (0 to {})",
            a.sample,
            a.spp,
            a.spp - 1
        )));
    }
    // Issue 15: the numbers' ranges, and never overwrite an input.
    let shading = a.shading.shading(a.integrator);
    shading.validate(FlagNames::Glint).map_err(usage)?;
    let mut scene = glint::job::load_scene_for(&a.scene.scene, output, (w, h))?;
    if shading.smooth {
        scene.smooth_meshes();
    }
    // World space: the exported rays are in the scene's coordinates.
    let world = World::build_world_space(
        &scene,
        BuildOptions {
            accel: a.scene.accel,
            flatten: true,
        },
    );
    let camera =
        CameraModel::of_world(&world, &scene.effects).at_time(scene.effects.lens.shutter[0]);
    let integrator = shading.whitted();
    let tracer = PathTracer::new(
        &world,
        PathSettings {
            max_bounces: shading.bounces,
            texture_space: shading.texture_space,
            ..PathSettings::default()
        },
    );
    let tree = if path {
        let sampler = Sampler::new(a.sampler.unwrap_or(SamplerKind::Sobol), a.spp, a.seed);
        raytree::record_sample(&world, &camera, &tracer, (w, h), (x, y), &sampler, a.sample)
    } else {
        raytree::record(
            &world,
            &camera,
            &integrator,
            (w, h),
            (x, y),
            PixelOffset::CENTER,
        )
    };
    let counts: Vec<String> = tree
        .counts()
        .iter()
        .map(|(k, n)| format!("{n} {k}"))
        .collect();
    match ext.as_str() {
        "json" => {
            let text = serde_json::to_string_pretty(&tree.to_json())
                .map_err(|e| JobError::Internal(e.to_string()))?;
            glint::output::write_file(output, (text + "\n").as_bytes())?;
        }
        "obj" => glint::output::write_file(output, tree.to_obj().as_bytes())?,
        "ply" => glint::output::write_file(output, tree.to_ply().as_bytes())?,
        _ => {
            let canvas = if path {
                raytree::overlay(&world, &camera, &tracer, (w, h), &tree)
            } else {
                raytree::overlay(&world, &camera, &integrator, (w, h), &tree)
            };
            glint::output::write_rgb(output, w, h, &canvas.pixels)?;
        }
    }
    println!(
        "pixel ({x}, {y}): {} rays ({}), written to {}",
        tree.rays.len(),
        counts.join(", "),
        output.display()
    );
    Ok(())
}

impl RaytreeArgs {
    #[cfg(test)]
    pub fn accel(&self) -> glint::accel::AccelKind {
        self.scene.accel
    }
}
