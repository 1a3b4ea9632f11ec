//! `glint traverse SCENE --pixel X Y -o FILE`: the cells, leaves or BVH boxes
//! an accelerator's search looked at for the eye rays of some pixels.

use clap::Args;
use glint::accel::AccelKind;
use glint::integrator::Whitted;
use glint::render::{render, screen_point, CameraModel, PixelOffset};
use glint::viz::draw::Canvas;
use glint::viz::traversal::{self, Structure};
use glint::world::{BuildOptions, World};
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `glint traverse`.
#[derive(Args)]
pub struct TraverseArgs {
    /// Scene file (MIT 6.837 format) or a bare .obj mesh.
    scene: PathBuf,
    /// A pixel whose eye ray to follow: x from the left, y from the top; repeat for more.
    #[arg(long, num_args = 2, value_names = ["X", "Y"], action = clap::ArgAction::Append)]
    pixel: Vec<u32>,
    /// Follow the eye rays of every pixel of this row (from the top).
    #[arg(long, value_name = "Y")]
    row: Option<u32>,
    /// Accelerator: grid, grid:NxNxN, octree, bvh, bvh-median, bvh-midpoint.
    #[arg(long, default_value = "grid")]
    accel: AccelKind,
    /// Output: .png/.tga/.ppm/.bmp (over the rendered image), .obj (3-D segments), .json.
    #[arg(short, long)]
    output: PathBuf,
    /// Image size in pixels.
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = [400, 400])]
    size: Vec<u32>,
}

/// Runs `glint traverse`.
pub fn run(a: TraverseArgs) -> ExitCode {
    match run_inner(a) {
        Ok(()) => ExitCode::SUCCESS,
        Err((code, msg)) => {
            eprintln!("glint: {}", glint::limits::bounded_message(&msg));
            ExitCode::from(code)
        }
    }
}

fn run_inner(a: TraverseArgs) -> Result<(), (u8, String)> {
    let (w, h) = (a.size[0], a.size[1]);
    if w == 0 || h == 0 {
        return Err((
            2,
            format!("image size {w}x{h}: width and height must be at least 1"),
        ));
    }
    let mut pixels: Vec<(u32, u32)> = a.pixel.chunks(2).map(|p| (p[0], p[1])).collect();
    if let Some(y) = a.row {
        pixels.extend((0..w).map(|x| (x, y)));
    }
    if pixels.is_empty() {
        return Err((2, "give at least one --pixel X Y or a --row Y".into()));
    }
    if let Some(&(x, y)) = pixels.iter().find(|(x, y)| *x >= w || *y >= h) {
        return Err((2, format!("pixel ({x}, {y}) is outside the {w}x{h} image")));
    }
    let ext = a
        .output
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if !matches!(ext.as_str(), "obj" | "json") {
        glint::output::check_path(&a.output).map_err(|e| (2, format!("{e} (or .obj, .json)")))?;
    }
    // Never overwrites the scene or a mesh it names (issue 15).
    let scene = glint::job::load_scene_for(&a.scene, &a.output, (w, h))
        .map_err(|e| (e.exit_code() as u8, e.to_string()))?;
    // World space: the exported cells and boxes are in the scene's coordinates.
    let world = World::build_world_space(&scene, BuildOptions::default());
    let camera =
        CameraModel::of_world(&world, &scene.effects).at_time(scene.effects.lens.shutter[0]);
    let structure = Structure::build(&world, a.accel).ok_or((
        2,
        format!(
            "--accel {}: no walk to record; choose grid, nested-grid, octree, octree-inner, bvh, bvh-median, bvh-midpoint or bvh-hierarchy (bvh is the binary SAH BVH; the 8-wide bvh8 records no walk)",
            a.accel
        ),
    ))?;
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
    let io = |e: glint::output::OutputError| (1, e.to_string());
    match ext.as_str() {
        "obj" => glint::output::write_file(&a.output, traversal::to_obj(&segments).as_bytes())
            .map_err(io)?,
        "json" => {
            let text = serde_json::to_string_pretty(
                &serde_json::json!({ "accel": a.accel.to_string(), "rays": json }),
            )
            .map_err(|e| (1, e.to_string()))?;
            glint::output::write_file(&a.output, (text + "\n").as_bytes()).map_err(io)?;
        }
        _ => {
            let shading = Whitted {
                shadows: true,
                ..Whitted::default()
            };
            let (frame, _) = render(&world, &camera, &shading, (w, h), PixelOffset::CENTER);
            let mut canvas = Canvas::new(w, h, frame.color);
            canvas.dim(0.6);
            traversal::draw(&mut canvas, &camera, &segments);
            glint::output::write_rgb(&a.output, w, h, &canvas.pixels)
                .map_err(|e| (1, e.to_string()))?;
        }
    }
    println!(
        "{} rays, {looked} boxes looked at ({}), written to {}",
        pixels.len(),
        a.accel,
        a.output.display()
    );
    Ok(())
}
