//! glint as a library: load a scene, render it into an in-memory image, and
//! query rays against a triangle mesh.
//!
//! `cargo run --release --example library` prints what it found; `cargo test`
//! runs the same code as this example's test (it uses only glint's own
//! `scenes/`, no course data).

use glint::format::load_scene;
use glint::format::obj::load_obj;
use glint::integrator::Whitted;
use glint::math::{Ray, Vec3};
use glint::query::MeshScene;
use glint::render::{render_image, CameraModel, Control, PixelOffset, Settings};
use glint::world::{BuildOptions, World};
use std::path::Path;

/// What the example found.
struct Findings {
    /// Mean colour of the rendered image.
    mean: Vec3,
    /// Primary rays the render traced.
    primary: u64,
    /// Triangles of the queried mesh.
    triangles: usize,
    /// Of the rays aimed from a ring around the mesh at a triangle's
    /// centroid, how many hit the mesh no farther than that centroid; and
    /// whether `occluded` agreed with `intersect` on each.
    hits: usize,
    rays: usize,
    agree: bool,
}

fn run() -> Findings {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));

    // 1. A scene file, built into a world (flattened, with the default
    //    accelerator), seen through its camera.
    let scene = load_scene(&root.join("scenes/whitted.txt")).expect("scenes/whitted.txt");
    let world = World::build(&scene, BuildOptions::default());
    let camera = CameraModel::of_world(&world, &scene.effects);
    let integrator = Whitted {
        bounces: 5,
        shadows: true,
        shade_back: true,
        ..Whitted::default()
    };

    // 2. Rendered into memory: a Frame of linear colours (and depth,
    //    normals, sample counts), one ray through each pixel centre.
    let settings = Settings::one_ray((160, 120), PixelOffset::CENTER);
    let rendered = render_image(&world, &camera, &integrator, &settings, Control::default());
    let frame = rendered.frame;
    assert!(frame.is_complete());
    let mean = frame.color.iter().copied().sum::<Vec3>() / frame.color.len() as f32;

    // 3. A mesh from raw buffers behind the fast BVH, queried directly.
    let mesh = load_obj(&root.join("scenes/meshes/knot_1k.obj")).expect("knot_1k.obj");
    let query = MeshScene::new(&mesh.positions, &mesh.triangles).expect("a valid mesh");
    let (lo, hi) = mesh.positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(a, b), &p| (a.min(p), b.max(p)),
    );
    let centre = (lo + hi) * 0.5;
    let reach = (hi - lo).length();
    let (mut hits, mut agree) = (0, true);
    let rays = 64;
    for k in 0..rays {
        let a = k as f32 / rays as f32 * std::f32::consts::TAU;
        let origin = centre + reach * Vec3::new(a.cos(), 0.3, a.sin());
        let [i, j, l] = mesh.triangles[k * mesh.triangles.len() / rays];
        let target =
            (mesh.positions[i as usize] + mesh.positions[j as usize] + mesh.positions[l as usize])
                / 3.0;
        let ray = Ray::new(origin, (target - origin).normalize());
        let hit = query.intersect(&ray, 0.0, f32::INFINITY);
        // The ray reaches the centroid unless something nearer stops it.
        let far = (target - origin).length() * 1.0001;
        hits += usize::from(hit.is_some_and(|h| h.t <= far));
        agree &= query.occluded(&ray, 0.0, f32::INFINITY) == hit.is_some();
    }
    Findings {
        mean,
        primary: rendered.counters.primary,
        triangles: query.triangle_count(),
        hits,
        rays,
        agree,
    }
}

#[cfg_attr(test, allow(dead_code))]
fn main() {
    let f = run();
    println!(
        "rendered scenes/whitted.txt at 160x120: {} primary rays, mean colour {:.3}",
        f.primary, f.mean
    );
    println!(
        "knot_1k.obj: {} triangles; {} of {} rays aimed at a triangle's centroid hit the mesh by there; occluded agrees with intersect: {}",
        f.triangles, f.hits, f.rays, f.agree
    );
}

#[test]
fn the_library_renders_and_queries() {
    let f = run();
    assert_eq!(f.primary, 160 * 120);
    assert!(f.mean.min_element() > 0.02, "a lit image: {}", f.mean);
    assert_eq!(f.triangles, 1152);
    assert_eq!(f.hits, f.rays);
    assert!(f.agree);
}
