//! `glint raytree SCENE --pixel X Y -o FILE`: every ray one pixel spawns.

use clap::Args;
use glint::accel::AccelKind;
use glint::integrator::Whitted;
use glint::limits;
use glint::render::{CameraModel, PixelOffset};
use glint::viz::raytree;
use glint::world::{BuildOptions, World};
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `glint raytree`.
#[derive(Args)]
pub struct RaytreeArgs {
    /// Scene file (MIT 6.837 format) or a bare .obj mesh.
    scene: PathBuf,
    /// The pixel: x from the left, y from the top (0-based).
    #[arg(long, num_args = 2, value_names = ["X", "Y"], required = true)]
    pixel: Vec<u32>,
    /// Output: .json (the tree), .obj or .ply (segments to load beside the
    /// scene), .png/.tga/.ppm/.bmp (the image with the tree drawn over it).
    #[arg(short, long)]
    output: PathBuf,
    /// Image size in pixels.
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = [400, 400])]
    size: Vec<u32>,
    /// Maximum number of reflection/refraction bounces.
    #[arg(long, default_value_t = 5)]
    bounces: u32,
    /// Prune ray-tree branches contributing less than this.
    #[arg(long, default_value_t = 0.01)]
    weight: f32,
    /// Cast shadow rays.
    #[arg(long)]
    shadows: bool,
    /// Filter light through transparent occluders.
    #[arg(long)]
    transparent_shadows: bool,
    /// Light the back sides of surfaces.
    #[arg(long)]
    shade_back: bool,
    /// Accelerator (the tree does not depend on it).
    #[arg(long, default_value = "bvh")]
    accel: AccelKind,
}

/// Runs `glint raytree`.
pub fn run(a: RaytreeArgs) -> ExitCode {
    match run_inner(a) {
        Ok(()) => ExitCode::SUCCESS,
        Err((code, msg)) => {
            eprintln!("glint: {}", limits::bounded_message(&msg));
            ExitCode::from(code)
        }
    }
}

fn run_inner(a: RaytreeArgs) -> Result<(), (u8, String)> {
    let (w, h) = (a.size[0], a.size[1]);
    let (x, y) = (a.pixel[0], a.pixel[1]);
    if w == 0 || h == 0 {
        return Err((
            2,
            format!("image size {w}x{h}: width and height must be at least 1"),
        ));
    }
    if x >= w || y >= h {
        return Err((2, format!("--pixel {x} {y} is outside the {w}x{h} image")));
    }
    let ext = a
        .output
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let image = !matches!(ext.as_str(), "json" | "obj" | "ply");
    if image {
        glint::output::check_image(&a.output, w, h)
            .map_err(|e| (2, format!("{e} (or .json, .obj, .ply for the tree itself)")))?;
    }
    // Issue 15: the numbers' ranges, and never overwrite an input.
    limits::int_in("--bounces", a.bounces, 0, limits::MAX_BOUNCES).map_err(|e| (2, e))?;
    limits::finite_in("--weight", a.weight, 0.0, f32::MAX).map_err(|e| (2, e))?;
    let scene = glint::job::load_scene_for(&a.scene, &a.output, (w, h))
        .map_err(|e| (e.exit_code() as u8, e.to_string()))?;
    // World space: the exported rays are in the scene's coordinates.
    let world = World::build_world_space(
        &scene,
        BuildOptions {
            accel: a.accel,
            flatten: true,
        },
    );
    let camera =
        CameraModel::of_world(&world, &scene.effects).at_time(scene.effects.lens.shutter[0]);
    let integrator = Whitted {
        bounces: a.bounces,
        weight_cutoff: a.weight,
        shadows: a.shadows || a.transparent_shadows,
        transparent_shadows: a.transparent_shadows,
        shade_back: a.shade_back,
        ..Whitted::default()
    };
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
    let io = |e: glint::output::OutputError| (1, e.to_string());
    match ext.as_str() {
        "json" => {
            let text =
                serde_json::to_string_pretty(&tree.to_json()).map_err(|e| (1, e.to_string()))?;
            glint::output::write_file(&a.output, (text + "\n").as_bytes()).map_err(io)?;
        }
        "obj" => glint::output::write_file(&a.output, tree.to_obj().as_bytes()).map_err(io)?,
        "ply" => glint::output::write_file(&a.output, tree.to_ply().as_bytes()).map_err(io)?,
        _ => {
            let canvas = raytree::overlay(&world, &camera, &integrator, (w, h), &tree);
            glint::output::write_rgb(&a.output, w, h, &canvas.pixels)
                .map_err(|e| (1, e.to_string()))?;
        }
    }
    println!(
        "pixel ({x}, {y}): {} rays ({}), written to {}",
        tree.rays.len(),
        counts.join(", "),
        a.output.display()
    );
    Ok(())
}
