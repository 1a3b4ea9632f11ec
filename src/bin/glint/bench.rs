//! `glint bench`: every accelerator on glint's own example scenes (by
//! default) or the course's bunnies and 6.837 logo (`--course DIR`), plus any
//! OBJ given (e.g. a generated mesh of a million triangles), in one table;
//! with glint's own scenes also two generated scenes with deep transform
//! hierarchies (`deep.rs`), flattened and not.
//!
//! Times are medians of several runs in this one process, so the ratios
//! between accelerators are taken under the same machine load.

use glint::accel::{AccelKind, Split};
use glint::format::{load_scene, obj::load_obj};
use glint::integrator::Whitted;
use glint::math::Vec3;
use glint::render::{render, CameraModel, PixelOffset};
use glint::scene::{Node, Scene, ShapeDesc};
use glint::world::{BuildOptions, World};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Settings of a benchmark run.
pub struct BenchArgs {
    /// Folder of glint's own example scenes (`scenes/`).
    pub scenes: PathBuf,
    /// Folder of the 6.837 scenes: bench those instead of glint's own.
    pub course: Option<PathBuf>,
    /// Extra OBJ meshes to bench (e.g. meshgen's million-triangle sphere).
    pub meshes: Vec<PathBuf>,
    /// Image size (square).
    pub size: u32,
    /// Timed runs per accelerator (the median is reported).
    pub runs: usize,
    /// Brute force is skipped when its estimated time exceeds this.
    pub none_limit_s: f64,
    /// Only the cases whose name contains this (or, comma-separated, any of
    /// these).
    pub only: Option<String>,
}

const ACCELS: [AccelKind; 10] = [
    AccelKind::None,
    AccelKind::Grid { res: None },
    AccelKind::NESTED_GRID,
    AccelKind::Octree,
    AccelKind::OctreeInner,
    AccelKind::Bvh(Split::Midpoint),
    AccelKind::Bvh(Split::Median),
    AccelKind::Bvh(Split::Sah),
    AccelKind::BvhHierarchy,
    AccelKind::Bvh8,
];

/// One scene to bench, flattened or not (`--no-flatten` rows show what the
/// hierarchy BVH's transform nodes save over per-primitive wrappers).
struct Case {
    name: String,
    scene: Scene,
    flatten: bool,
}

struct Row {
    build_ms: f64,
    memory_kb: f64,
    render_ms: f64,
    tests_per_ray: f64,
    nodes_per_ray: f64,
    estimated: bool,
}

/// Runs the benchmark and prints the table (markdown) to stdout.
pub fn run(args: &BenchArgs) -> Result<(), String> {
    let mut cases: Vec<(String, Scene)> = Vec::new();
    let mut deep: Vec<(String, Scene)> = Vec::new();
    let (dir, names, stadium): (&Path, &[&str], _) = match &args.course {
        Some(dir) => (
            dir,
            &[
                "scene6_04_bunny_mesh_200.txt",
                "scene6_05_bunny_mesh_1k.txt",
                "scene6_06_bunny_mesh_5k.txt",
                "scene6_07_bunny_mesh_40k.txt",
                "scene6_18_6.837_logo.txt",
            ],
            (
                "bunny_in_stadium",
                dir.join("bunny_40k.obj"),
                Some((-0.07, 200.0)),
            ),
        ),
        None => (
            &args.scenes,
            &[
                "whitted.txt",
                "mesh_knot_1k.txt",
                "mesh_knot_16k.txt",
                "mesh_knot_64k.txt",
            ],
            (
                "knot_in_stadium",
                args.scenes.join("meshes/knot_16k.obj"),
                None,
            ),
        ),
    };
    for name in names {
        let scene = load_scene(&dir.join(name)).map_err(|e| e.render())?;
        cases.push((name.trim_end_matches(".txt").to_string(), scene));
    }
    cases.push((stadium.0.into(), stadium_scene(&stadium.1, stadium.2)?));
    for mesh in &args.meshes {
        cases.push((display_name(mesh), mesh_scene(mesh)?));
    }
    if args.course.is_none() {
        // Deep transform hierarchies, flattened and not.
        deep.push(("tree_d5_b3".into(), super::deep::tree(5, 3)));
        let knot = load_obj(&args.scenes.join("meshes/knot_1k.obj")).map_err(|e| e.render())?;
        deep.push(("knot_1k_x64".into(), super::deep::instances(knot, 4)));
    }
    let mut cases: Vec<Case> = cases
        .into_iter()
        .map(|(name, scene)| Case {
            name,
            scene,
            flatten: true,
        })
        .collect();
    for (name, scene) in deep {
        for flatten in [true, false] {
            let name = if flatten {
                name.clone()
            } else {
                format!("{name} (no-flatten)")
            };
            cases.push(Case {
                name,
                scene: scene.clone(),
                flatten,
            });
        }
    }
    if let Some(only) = &args.only {
        cases.retain(|c| only.split(',').any(|o| c.name.contains(o)));
    }
    let integrator = Whitted {
        bounces: 5,
        weight_cutoff: 0.01,
        shadows: true,
        shade_back: true,
        transparent_shadows: false,
        ..Whitted::default()
    };
    println!(
        "{}x{} pixels, shadows, shade_back, 5 bounces; median of {} runs; {} threads\n",
        args.size,
        args.size,
        args.runs,
        rayon::current_num_threads()
    );
    println!("| scene | triangles | accelerator | build ms | memory KB | render ms | tests/ray | nodes/ray | speedup vs none |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for Case {
        name,
        scene,
        flatten,
    } in &cases
    {
        let (scene, flatten) = (scene, *flatten);
        let tris = scene.summary().triangles;
        let mut rows: Vec<(AccelKind, Row)> = Vec::new();
        for &accel in ACCELS.iter().skip(1) {
            rows.push((
                accel,
                measure(scene, accel, flatten, &integrator, args.size, args.runs),
            ));
        }
        let none = estimate_or_measure_none(scene, flatten, &integrator, args);
        let none_ms = none.render_ms;
        rows.insert(0, (AccelKind::None, none));
        for (accel, r) in &rows {
            let mark = if r.estimated { "~" } else { "" };
            println!(
                "| {name} | {tris} | {accel} | {:.1} | {:.0} | {mark}{:.1} | {mark}{:.2} | {:.2} | {mark}{:.1}x |",
                r.build_ms,
                r.memory_kb,
                r.render_ms,
                r.tests_per_ray,
                r.nodes_per_ray,
                none_ms / r.render_ms
            );
        }
    }
    println!("\n~ = brute force not run (estimated over {:.0} s): its time is extrapolated from a 16x16 render", args.none_limit_s);
    Ok(())
}

fn measure(
    scene: &Scene,
    accel: AccelKind,
    flatten: bool,
    integrator: &Whitted,
    size: u32,
    runs: usize,
) -> Row {
    let mut builds = Vec::new();
    let mut renders = Vec::new();
    let mut counters = Default::default();
    let mut memory = 0;
    for _ in 0..runs.max(1) {
        let t = Instant::now();
        let world = World::build(scene, BuildOptions { accel, flatten });
        builds.push(t.elapsed().as_secs_f64() * 1e3);
        memory = world.accel().memory_bytes();
        let cam = CameraModel::new(world.camera());
        let t = Instant::now();
        let (_, c) = render(&world, &cam, integrator, (size, size), PixelOffset::CENTER);
        renders.push(t.elapsed().as_secs_f64() * 1e3);
        counters = c;
    }
    let rays = counters.rays_total().max(1) as f64;
    Row {
        build_ms: median(&mut builds),
        memory_kb: memory as f64 / 1024.0,
        render_ms: median(&mut renders),
        tests_per_ray: counters.intersection_tests as f64 / rays,
        nodes_per_ray: counters.nodes_visited as f64 / rays,
        estimated: false,
    }
}

/// Brute force costs (rays × primitives): measure it on a 16×16 image first
/// and run the full size only when the extrapolation stays under the limit.
fn estimate_or_measure_none(
    scene: &Scene,
    flatten: bool,
    integrator: &Whitted,
    args: &BenchArgs,
) -> Row {
    let small = measure(scene, AccelKind::None, flatten, integrator, 16, 1);
    let scale = (args.size as f64 / 16.0).powi(2);
    if small.render_ms * scale / 1e3 <= args.none_limit_s {
        return measure(scene, AccelKind::None, flatten, integrator, args.size, 1);
    }
    // Tests per ray are a property of brute force (every bounded primitive
    // plus the planes), so the small render's figure holds at full size.
    Row {
        render_ms: small.render_ms * scale,
        estimated: true,
        ..small
    }
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

fn display_name(p: &Path) -> String {
    p.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// The "teapot in a stadium": a mesh on a floor of two triangles thousands of
/// times as wide (400 units under the 40k bunny, which is 0.15 across). A
/// uniform grid sized to the whole scene puts the mesh into a handful of
/// cells; a BVH adapts. `floor` is (height, half width), or `None` for a
/// floor just under the mesh, 1350 mesh sizes to each side.
fn stadium_scene(mesh: &Path, floor: Option<(f32, f32)>) -> Result<Scene, String> {
    let mut scene = mesh_scene(mesh)?;
    let (y, w) = floor.unwrap_or_else(|| {
        let b = World::build(&scene, BuildOptions::default()).bounds();
        let size = (b.max - b.min).max_element();
        (b.min.y - 0.05 * size, 1350.0 * size)
    });
    let corners = [
        Vec3::new(-w, y, -w),
        Vec3::new(w, y, -w),
        Vec3::new(w, y, w),
        Vec3::new(-w, y, w),
    ]
    .map(|p| p.as_dvec3());
    let floor = |a: usize, b: usize, c: usize| Node::Shape {
        shape: ShapeDesc::Triangle([corners[a], corners[b], corners[c]]),
        material: Some(0),
    };
    scene.root = Node::Group(vec![scene.root, floor(0, 2, 1), floor(0, 3, 2)]);
    Ok(scene)
}

/// An OBJ mesh framed by [`Scene::for_mesh`].
fn mesh_scene(path: &Path) -> Result<Scene, String> {
    Ok(Scene::for_mesh(load_obj(path).map_err(|e| e.render())?))
}
