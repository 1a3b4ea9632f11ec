//! `glint raytree SCENE --pixel X Y -o FILE`: every ray one pixel spawns.

use crate::args::{ImageArgs, SceneArgs, ShadingArgs};
use clap::Args;
use glint::app::usage;
use glint::job::{FlagNames, JobError};
use glint::render::{CameraModel, PixelOffset};
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
    // Issue 15: the numbers' ranges, and never overwrite an input.
    let shading = a
        .shading
        .shading(glint::integrator::IntegratorKind::Whitted);
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
    let tree = raytree::record(
        &world,
        &camera,
        &integrator,
        (w, h),
        (x, y),
        PixelOffset::CENTER,
    );
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
            let canvas = raytree::overlay(&world, &camera, &integrator, (w, h), &tree);
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
