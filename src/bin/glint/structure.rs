//! `glint structure SCENE --accel bvh --depth D -o FILE`: an accelerator's
//! boxes at one depth (or its leaves) drawn over the rendered image.

use clap::Args;
use glint::accel::AccelKind;
use glint::integrator::Whitted;
use glint::render::{render, CameraModel, PixelOffset};
use glint::viz::draw::Canvas;
use glint::viz::traversal::{self, Structure};
use glint::world::{BuildOptions, World};
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `glint structure`.
#[derive(Args)]
pub struct StructureArgs {
    /// Scene file (MIT 6.837 format) or a bare .obj mesh.
    scene: PathBuf,
    /// Accelerator: octree, octree-inner, bvh, bvh-median, bvh-midpoint.
    #[arg(long, default_value = "bvh")]
    accel: AccelKind,
    /// Draw the nodes at this depth (the root is 0); default: every leaf.
    #[arg(long)]
    depth: Option<u32>,
    /// Output image (.png, .tga, .ppm, .bmp) or .obj (3-D segments).
    #[arg(short, long)]
    output: PathBuf,
    /// Image size in pixels.
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = [400, 400])]
    size: Vec<u32>,
}

/// Runs `glint structure`.
pub fn run(a: StructureArgs) -> ExitCode {
    let fail = |code: u8, msg: String| {
        eprintln!("glint: {}", glint::limits::bounded_message(&msg));
        ExitCode::from(code)
    };
    let (w, h) = (a.size[0], a.size[1]);
    if w == 0 || h == 0 {
        return fail(
            2,
            format!("image size {w}x{h}: width and height must be at least 1"),
        );
    }
    let obj = a
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if !obj {
        if let Err(e) = glint::output::check_path(&a.output) {
            return fail(2, format!("{e} (or .obj)"));
        }
    }
    // Never overwrites the scene or a mesh it names (issue 15).
    let scene = match glint::job::load_scene_for(&a.scene, &a.output, (w, h)) {
        Ok(s) => s,
        Err(e) => return fail(e.exit_code() as u8, e.to_string()),
    };
    // World space: the boxes drawn (and exported) are in the scene's coordinates.
    let world = World::build_world_space(&scene, BuildOptions::default());
    let boxes = match Structure::build(&world, a.accel) {
        Some(Structure::Bvh(b)) => glint::viz::structure::bvh_boxes(&b),
        Some(Structure::Octree(o)) => glint::viz::structure::octree_boxes(&o),
        _ => {
            return fail(
                2,
                format!(
                    "--accel {}: choose octree, octree-inner, bvh, bvh-median or bvh-midpoint (the 8-wide bvh8 is not drawn)",
                    a.accel
                ),
            )
        }
    };
    let segments = glint::viz::structure::segments(&boxes, a.depth);
    let deepest = boxes.iter().map(|b| b.1).max().unwrap_or(0);
    let written = if obj {
        glint::output::write_file(&a.output, traversal::to_obj(&segments).as_bytes())
            .map_err(|e| e.to_string())
    } else {
        let camera =
            CameraModel::of_world(&world, &scene.effects).at_time(scene.effects.lens.shutter[0]);
        let shading = Whitted {
            shadows: true,
            ..Whitted::default()
        };
        let (frame, _) = render(&world, &camera, &shading, (w, h), PixelOffset::CENTER);
        let mut canvas = Canvas::new(w, h, frame.color);
        canvas.dim(0.6);
        traversal::draw(&mut canvas, &camera, &segments);
        glint::output::write_rgb(&a.output, w, h, &canvas.pixels).map_err(|e| e.to_string())
    };
    match written {
        Ok(()) => {
            println!(
                "{}: {} nodes, depth {deepest}; drew {} boxes to {}",
                a.accel,
                boxes.len(),
                segments.len() / 12,
                a.output.display()
            );
            ExitCode::SUCCESS
        }
        Err(e) => fail(1, format!("{}: {e}", a.output.display())),
    }
}
