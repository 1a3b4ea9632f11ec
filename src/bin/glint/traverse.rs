//! `glint traverse SCENE --pixel X Y -o FILE`: the cells, leaves or BVH boxes
//! an accelerator's search looked at for the eye rays of some pixels.

use crate::args::{ImageArgs, SceneArgs};
use clap::Args;
use glint::app::usage;
use glint::job::JobError;
use glint::render::{screen_point, CameraModel, PixelOffset};
use glint::viz::traversal::{self, Structure};
use glint::world::{BuildOptions, World};

/// Arguments of `glint traverse`.
#[derive(Args)]
pub struct TraverseArgs {
    // `--accel`: the structure whose search is recorded (grid, grid:NxNxN,
    // nested-grid, octree, octree-inner, a bvh).
    #[command(flatten)]
    scene: SceneArgs,
    /// A pixel whose eye ray to follow: x from the left, y from the top; repeat for more.
    #[arg(long, num_args = 2, value_names = ["X", "Y"], action = clap::ArgAction::Append)]
    pixel: Vec<u32>,
    /// Follow the eye rays of every pixel of this row (from the top).
    #[arg(long, value_name = "Y")]
    row: Option<u32>,
    // Output: .png/.tga/.ppm/.bmp (over the rendered image), .obj (3-D
    // segments), .json.
    #[command(flatten)]
    image: ImageArgs,
}

/// The pixels `--pixel` and `--row` name, all inside the image.
fn pixels(a: &TraverseArgs, (w, h): (u32, u32)) -> Result<Vec<(u32, u32)>, JobError> {
    if w == 0 || h == 0 {
        return Err(usage(format!(
            "image size {w}x{h}: width and height must be at least 1"
        )));
    }
    let mut pixels: Vec<(u32, u32)> = a.pixel.chunks(2).map(|p| (p[0], p[1])).collect();
    if let Some(y) = a.row {
        pixels.extend((0..w).map(|x| (x, y)));
    }
    if pixels.is_empty() {
        return Err(usage("give at least one --pixel X Y or a --row Y"));
    }
    if let Some(&(x, y)) = pixels.iter().find(|(x, y)| *x >= w || *y >= h) {
        return Err(usage(format!(
            "pixel ({x}, {y}) is outside the {w}x{h} image"
        )));
    }
    Ok(pixels)
}

/// Runs `glint traverse`.
pub fn run(a: TraverseArgs) -> Result<(), JobError> {
    let (w, h) = a.image.size();
    let output = &a.image.output;
    let accel = a.scene.accel;
    let pixels = pixels(&a, (w, h))?;
    let ext = output
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if !matches!(ext.as_str(), "obj" | "json") {
        glint::output::check_path(output).map_err(|e| usage(format!("{e} (or .obj, .json)")))?;
    }
    // Never overwrites the scene or a mesh it names (issue 15).
    let scene = glint::job::load_scene_for(&a.scene.scene, output, (w, h))?;
    // World space: the exported cells and boxes are in the scene's coordinates.
    let world = World::build_world_space(&scene, BuildOptions::default());
    let camera =
        CameraModel::of_world(&world, &scene.effects).at_time(scene.effects.lens.shutter[0]);
    let structure = Structure::build(&world, accel).ok_or_else(|| {
        usage(format!(
            "--accel {accel}: no walk to record; choose grid, octree, octree-inner or a bvh"
        ))
    })?;
    let bvh = matches!(structure, Structure::Bvh(_));
    let mut segments = Vec::new();
    let mut json = Vec::new();
    let mut looked = 0;
    for &(x, y) in &pixels {
        let ray = camera.ray(screen_point(x, h - 1 - y, PixelOffset::CENTER.0, w, h));
        let (hit, visits) = structure.trace(&world, &ray, camera.tmin());
        looked += visits.len();
        segments.extend(traversal::segments(&ray, hit, &visits, bvh));
        json.push(serde_json::json!({
            "pixel": [x, y],
            "hit_t": hit.map(|h| h.t),
            "visits": visits.iter().map(|v| serde_json::json!({
                "min": [v.bounds.min.x, v.bounds.min.y, v.bounds.min.z],
                "max": [v.bounds.max.x, v.bounds.max.y, v.bounds.max.z],
                "entered": v.entered,
                "leaf": v.leaf,
                "face": v.face.map(|f| serde_json::json!({"axis": f.axis, "min_side": f.min_side})),
            })).collect::<Vec<_>>(),
        }));
    }
    match ext.as_str() {
        "obj" => glint::output::write_file(output, traversal::to_obj(&segments).as_bytes())?,
        "json" => {
            let text = serde_json::to_string_pretty(
                &serde_json::json!({ "accel": accel.to_string(), "rays": json }),
            )
            .map_err(|e| JobError::Internal(e.to_string()))?;
            glint::output::write_file(output, (text + "\n").as_bytes())?;
        }
        _ => {
            crate::structure::write_over_render(output, &world, &camera, (w, h), &segments)?;
        }
    }
    println!(
        "{} rays, {looked} boxes looked at ({}), written to {}",
        pixels.len(),
        accel,
        output.display()
    );
    Ok(())
}

impl TraverseArgs {
    #[cfg(test)]
    pub fn accel(&self) -> glint::accel::AccelKind {
        self.scene.accel
    }
}
