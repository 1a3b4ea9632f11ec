//! `glint structure SCENE --accel bvh --depth D -o FILE`: an accelerator's
//! boxes at one depth (or its leaves) drawn over the rendered image.

use crate::args::{ImageArgs, SceneArgs};
use clap::Args;
use glint::app::usage;
use glint::integrator::Whitted;
use glint::job::JobError;
use glint::render::{render, CameraModel, PixelOffset};
use glint::viz::draw::Canvas;
use glint::viz::traversal::{self, Structure};
use glint::world::{BuildOptions, World};

/// Arguments of `glint structure`.
#[derive(Args)]
pub struct StructureArgs {
    // `--accel`: the structure drawn (octree, octree-inner, a bvh).
    #[command(flatten)]
    scene: SceneArgs,
    /// Draw the nodes at this depth (the root is 0); default: every leaf.
    #[arg(long)]
    depth: Option<u32>,
    // Output image (.png, .tga, .ppm, .bmp) or .obj (3-D segments).
    #[command(flatten)]
    image: ImageArgs,
}

/// Runs `glint structure`.
pub fn run(a: StructureArgs) -> Result<(), JobError> {
    let (w, h) = a.image.size();
    let output = &a.image.output;
    let accel = a.scene.accel;
    if w == 0 || h == 0 {
        return Err(usage(format!(
            "image size {w}x{h}: width and height must be at least 1"
        )));
    }
    let obj = output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"));
    if !obj {
        glint::output::check_path(output).map_err(|e| usage(format!("{e} (or .obj)")))?;
    }
    // Never overwrites the scene or a mesh it names (issue 15).
    let scene = glint::job::load_scene_for(&a.scene.scene, output, (w, h))?;
    // World space: the boxes drawn (and exported) are in the scene's coordinates.
    let world = World::build_world_space(&scene, BuildOptions::default());
    let boxes = match Structure::build(&world, accel) {
        Some(Structure::Bvh(b)) => glint::viz::structure::bvh_boxes(&b),
        Some(Structure::Octree(o)) => glint::viz::structure::octree_boxes(&o),
        _ => {
            return Err(usage(format!(
                "--accel {accel}: choose octree, octree-inner or a bvh"
            )))
        }
    };
    let segments = glint::viz::structure::segments(&boxes, a.depth);
    let deepest = boxes.iter().map(|b| b.1).max().unwrap_or(0);
    if obj {
        glint::output::write_file(output, traversal::to_obj(&segments).as_bytes())?;
    } else {
        let camera =
            CameraModel::of_world(&world, &scene.effects).at_time(scene.effects.lens.shutter[0]);
        write_over_render(output, &world, &camera, (w, h), &segments)?;
    }
    println!(
        "{accel}: {} nodes, depth {deepest}; drew {} boxes to {}",
        boxes.len(),
        segments.len() / 12,
        output.display()
    );
    Ok(())
}

impl StructureArgs {
    #[cfg(test)]
    pub fn accel(&self) -> glint::accel::AccelKind {
        self.scene.accel
    }
}

/// Writes to `output` the line `segments` drawn over a dimmed render of
/// `world` (Whitted shading with shadows) through `camera`, at `size`.
pub(crate) fn write_over_render(
    output: &std::path::Path,
    world: &World,
    camera: &CameraModel,
    (w, h): (u32, u32),
    segments: &[((glint::math::Vec3, glint::math::Vec3), glint::math::Vec3)],
) -> Result<(), JobError> {
    let shading = Whitted {
        shadows: true,
        ..Whitted::default()
    };
    let (frame, _) = render(world, camera, &shading, (w, h), PixelOffset::CENTER);
    let mut canvas = Canvas::new(w, h, frame.color);
    canvas.dim(0.6);
    traversal::draw(&mut canvas, camera, segments);
    glint::output::write_rgb(output, w, h, &canvas.pixels)?;
    Ok(())
}
