//! The render loop's sampling properties: identical to the old loop at one
//! sample per pixel, independent of the thread count, converging as samples
//! grow (stratified and low-discrepancy faster than random), and adaptive
//! subdivision spending rays only on edges.

use crate::common;

use glint::format::load_scene;
use glint::integrator::Whitted;
use glint::math::Vec3;
use glint::render::{
    render_image, render_region, Adaptive, CameraModel, Control, Filter, Frame, PixelOffset, Rect,
    Settings,
};
use glint::sampler::{GridLayout, Sampler, SamplerKind};
use glint::scene::{Node, Scene};
use glint::stats::Counters;
use glint::world::{BuildOptions, World};
use std::path::Path;

fn world_of(scene: &Scene) -> (World, CameraModel) {
    let world = World::build(scene, BuildOptions::default());
    let camera = CameraModel::new(world.camera());
    (world, camera)
}

fn render(world: &World, cam: &CameraModel, w: &Whitted, s: &Settings) -> (Frame, Counters) {
    let r = render_image(world, cam, w, s, Control::default());
    (r.frame, r.counters)
}

fn whitted() -> Whitted {
    Whitted {
        bounces: 5,
        weight_cutoff: 0.01,
        shadows: true,
        shade_back: true,
        ..Whitted::default()
    }
}

/// Root-mean-square error over every channel of two frames (linear values
/// clamped to [0, 1], as displayed).
fn rmse(a: &Frame, b: &Frame) -> f64 {
    let sum: f64 = a
        .color
        .iter()
        .zip(&b.color)
        .map(|(p, q)| {
            let d = p.clamp(Vec3::ZERO, Vec3::ONE) - q.clamp(Vec3::ZERO, Vec3::ONE);
            d.length_squared() as f64
        })
        .sum();
    (sum / (3 * a.color.len()) as f64).sqrt()
}

fn sampled(size: (u32, u32), kind: SamplerKind, spp: u32, filter: Filter) -> Settings {
    Settings {
        sampler: Sampler::new(kind, spp, 0),
        filter,
        pixel_cost: true,
        ..Settings::one_ray(size, PixelOffset::CENTER)
    }
}

/// At one sample per pixel the band loop (one ray, written in place) gives
/// the tiled path's image bit for bit (colour, depth, normals) and its
/// counters, at the centre and at the corner, on course scenes and a size
/// that is not a multiple of the tile or the band.
#[test]
fn one_sample_per_pixel_bands_equal_tiles() {
    let Some(dir) = common::scenes("one_sample_per_pixel_bands_equal_tiles") else {
        return;
    };
    for name in [
        "scene4_14_faceted_gem.txt",
        "scene2_07_sphere_triangles.txt",
    ] {
        let scene = load_scene(&dir.join(name)).unwrap();
        let (world, cam) = world_of(&scene);
        for offset in [PixelOffset::CENTER, PixelOffset::CORNER] {
            let size = (77, 45);
            let s = Settings::one_ray(size, offset);
            let whole = Rect {
                x0: 0,
                row0: 0,
                x1: size.0,
                row1: size.1,
            };
            let tiled = render_region(&world, &cam, &whitted(), &s, Control::default(), whole);
            let (old, oc) = (tiled.frame, tiled.counters);
            let (new, nc) = render(&world, &cam, &whitted(), &s);
            assert_eq!(oc, nc, "{name}: counters");
            let bits = |f: &Frame| {
                f.color
                    .iter()
                    .chain(&f.normal)
                    .flat_map(|v| v.to_array())
                    .chain(f.depth.iter().copied())
                    .map(f32::to_bits)
                    .collect::<Vec<_>>()
            };
            assert!(bits(&old) == bits(&new), "{name} {offset:?}: images differ");
            assert!(new.samples.iter().all(|&n| n == 1));
        }
    }
}

/// The same image, bit for bit, on 1 and 2 threads, for every sampler with
/// a filter wider than a pixel (tile margins), and for adaptive sampling.
#[test]
fn images_do_not_depend_on_the_thread_count() {
    let Some(dir) = common::scenes("images_do_not_depend_on_the_thread_count") else {
        return;
    };
    let scene = load_scene(&dir.join("scene4_14_faceted_gem.txt")).unwrap();
    let (world, cam) = world_of(&scene);
    let size = (70, 40);
    let mut cases: Vec<Settings> = [
        SamplerKind::Random,
        SamplerKind::Jittered,
        SamplerKind::Sobol,
        SamplerKind::Uniform(GridLayout::CENTERS),
    ]
    .iter()
    .map(|&k| sampled(size, k, 4, Filter::Gaussian(0.8)))
    .collect();
    cases.push(Settings {
        adaptive: Some(Adaptive {
            threshold: 0.05,
            max_depth: 3,
        }),
        tile_size: 16,
        ..Settings::one_ray(size, PixelOffset::CENTER)
    });
    for s in cases {
        let on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| render(&world, &cam, &whitted(), &s))
        };
        let (a, ca) = on(1);
        let (b, cb) = on(2);
        let bits = |f: &Frame| {
            f.color
                .iter()
                .flat_map(|v| v.to_array())
                .map(f32::to_bits)
                .collect::<Vec<_>>()
        };
        assert!(bits(&a) == bits(&b), "{s:?}: 1 and 2 threads differ");
        assert_eq!(a.samples, b.samples);
        assert_eq!(ca, cb);
    }
}

/// Same through the command line: `--threads 1` and `--threads 2` write the
/// same float image (PFM keeps the bits).
#[test]
fn cli_threads_1_and_2_write_the_same_file() {
    let Some(dir) = common::scenes("cli_threads_1_and_2_write_the_same_file") else {
        return;
    };
    let scratch = common::scratch("threads");
    let out = scratch.as_ref();
    let scene = dir.join("scene7_01_sphere_triangle.txt");
    let run = |threads: &str, file: &str| {
        let st = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
            .args([
                "render",
                scene.to_str().unwrap(),
                "-o",
                file,
                "--size",
                "90",
                "70",
            ])
            .args([
                "--spp",
                "9",
                "--sampler",
                "jittered",
                "--filter",
                "tent:1.5",
            ])
            .args(["--threads", threads, "--quiet"])
            .current_dir(out)
            .status()
            .unwrap();
        assert!(st.success());
        std::fs::read(out.join(file)).unwrap()
    };
    assert!(run("1", "one.pfm") == run("2", "two.pfm"));
}

/// scene7_01 (a sphere and a triangle in flat colours on blue: hard edges
/// only) at 48×48, box filter: RMSE against a 1024-spp render falls as spp
/// grows, and at 16 spp jittered and Sobol beat random.
#[test]
fn error_falls_with_samples_and_stratification_helps() {
    let Some(dir) = common::scenes("error_falls_with_samples_and_stratification_helps") else {
        return;
    };
    let scene = load_scene(&dir.join("scene7_01_sphere_triangle.txt")).unwrap();
    let (world, cam) = world_of(&scene);
    let size = (48, 48);
    let box_ = Filter::Box(0.5);
    let (truth, _) = render(
        &world,
        &cam,
        &whitted(),
        &sampled(size, SamplerKind::Jittered, 1024, box_),
    );
    let mut at16 = Vec::new();
    for kind in [
        SamplerKind::Random,
        SamplerKind::Jittered,
        SamplerKind::Sobol,
    ] {
        let errs: Vec<f64> = [1, 4, 16, 64]
            .iter()
            .map(|&n| {
                // A different seed from the reference's.
                let s = Settings {
                    sampler: Sampler::new(kind, n, 99),
                    ..sampled(size, kind, n, box_)
                };
                rmse(&render(&world, &cam, &whitted(), &s).0, &truth)
            })
            .collect();
        eprintln!("{kind}: RMSE at 1/4/16/64 spp = {errs:.4?}");
        assert!(errs.windows(2).all(|w| w[1] < w[0]), "{kind}: {errs:?}");
        at16.push(errs[2]);
    }
    assert!(
        at16[1] < at16[0],
        "jittered {} vs random {}",
        at16[1],
        at16[0]
    );
    assert!(at16[2] < at16[0], "sobol {} vs random {}", at16[2], at16[0]);
}

/// Adaptive subdivision on a flat image (scene7_01 with its objects removed:
/// background only) traces exactly the pixel corners.
#[test]
fn adaptive_traces_only_the_corners_of_a_flat_image() {
    let Some(dir) = common::scenes("adaptive_traces_only_the_corners_of_a_flat_image") else {
        return;
    };
    let mut scene = load_scene(&dir.join("scene7_01_sphere_triangle.txt")).unwrap();
    scene.root = Node::Group(Vec::new());
    let (world, cam) = world_of(&scene);
    let (w, h) = (40, 30);
    let s = Settings {
        adaptive: Some(Adaptive {
            threshold: 0.0,
            max_depth: 4,
        }),
        ..Settings::one_ray((w, h), PixelOffset::CENTER)
    };
    let (f, c) = render(&world, &cam, &whitted(), &s);
    assert_eq!(c.primary, ((w + 1) * (h + 1)) as u64);
    assert!(f.samples.iter().all(|&n| n == 4));
    assert!(f.color.iter().all(|&p| p == world.background().color));
}

/// On scene7_01's edges adaptive subdivision reaches the RMSE of uniform
/// 16 spp (4×4 cell centres) with fewer camera rays.
#[test]
fn adaptive_matches_uniform_16_with_fewer_rays() {
    let Some(dir) = common::scenes("adaptive_matches_uniform_16_with_fewer_rays") else {
        return;
    };
    let scene = load_scene(&dir.join("scene7_01_sphere_triangle.txt")).unwrap();
    let (world, cam) = world_of(&scene);
    let size = (48, 48);
    let box_ = Filter::Box(0.5);
    let (truth, _) = render(
        &world,
        &cam,
        &whitted(),
        &sampled(size, SamplerKind::Jittered, 1024, box_),
    );
    let uniform = sampled(size, SamplerKind::Uniform(GridLayout::CENTERS), 16, box_);
    let (fu, cu) = render(&world, &cam, &whitted(), &uniform);
    let adaptive = Settings {
        adaptive: Some(Adaptive {
            threshold: 0.02,
            max_depth: 3,
        }),
        ..Settings::one_ray(size, PixelOffset::CENTER)
    };
    let (fa, ca) = render(&world, &cam, &whitted(), &adaptive);
    let (eu, ea) = (rmse(&fu, &truth), rmse(&fa, &truth));
    let ratio = ca.primary as f64 / cu.primary as f64;
    eprintln!(
        "uniform 16: RMSE {eu:.4}, {} rays; adaptive: RMSE {ea:.4}, {} rays (ratio {ratio:.3})",
        cu.primary, ca.primary
    );
    assert!(ea <= eu, "adaptive RMSE {ea} above uniform 16's {eu}");
    assert!(
        ratio < 1.0,
        "adaptive used {ratio:.2}x the rays of uniform 16"
    );
    // More rays where there are edges: the busiest pixel used more than the
    // 4 corners, and most pixels (flat) used only those.
    assert!(*fa.samples.iter().max().unwrap() > 4);
    let flat = fa.samples.iter().filter(|&&n| n == 4).count();
    assert!(flat > fa.samples.len() / 2);
}

/// The sample and filter views and the heat map through `glint render`.
#[test]
fn glint_writes_the_views_and_sampling_stats() {
    let Some(dir) = common::scenes("glint_writes_the_views_and_sampling_stats") else {
        return;
    };
    let scratch = common::scratch("views");
    let out = scratch.as_ref();
    let scene = dir.join("scene7_01_sphere_triangle.txt");
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "-o",
            "img.png",
            "--size",
            "9",
            "9",
        ])
        .args([
            "--spp",
            "4",
            "--sampler",
            "jittered",
            "--filter",
            "gaussian:0.7",
        ])
        .args([
            "--render-samples",
            "s.png",
            "10",
            "--render-filter",
            "f.png",
            "10",
        ])
        .args(["--stats-json", "st.json", "--quiet"])
        .current_dir(out)
        .status()
        .unwrap();
    assert!(st.success());
    let dims = |f: &str| image::image_dimensions(out.join(f)).unwrap();
    assert_eq!(dims("s.png"), (90, 90));
    assert_eq!(dims("f.png"), (91, 91));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("st.json")).unwrap()).unwrap();
    assert_eq!(json["samples_per_pixel"], 4.0);
    assert!(json["rays_per_pixel"].as_f64().unwrap() >= 4.0);
    assert_eq!(json["filter"], "gaussian:0.7");

    let st = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
        .args([
            "render",
            scene.to_str().unwrap(),
            "-o",
            "a.png",
            "--size",
            "20",
            "20",
        ])
        .args([
            "--adaptive",
            "0.05",
            "--max-depth",
            "3",
            "--samples-image",
            "heat.png",
        ])
        .args(["--quiet", "--stats"])
        .current_dir(out)
        .output()
        .unwrap();
    assert!(st.status.success());
    let text = String::from_utf8_lossy(&st.stdout);
    assert!(text.contains("samples / pixel"), "{text}");
    assert!(text.contains("adaptive"), "{text}");
    let (hw, hh) = dims("heat.png");
    assert!(hw >= 256 && hh > hw, "{hw}x{hh}: map plus scale bar");
    assert!(Path::new(&out.join("a.png")).exists());
}

/// The band loop (filters inside their pixel) and the tiled film with
/// margins compute the same pixels: a box of radius 0.5 goes through the
/// bands, one a hair wider (support 1, same weights for every sample inside
/// its pixel, 0 for the neighbours') through tiles and the merge; the images
/// agree bit for bit.
#[test]
fn band_loop_and_tiled_film_agree() {
    let Some(dir) = common::scenes("band_loop_and_tiled_film_agree") else {
        return;
    };
    let scene = load_scene(&dir.join("scene4_14_faceted_gem.txt")).unwrap();
    let (world, cam) = world_of(&scene);
    let size = (70, 45);
    let bands = sampled(size, SamplerKind::Jittered, 4, Filter::Box(0.5));
    let tiled = sampled(size, SamplerKind::Jittered, 4, Filter::Box(0.500_001));
    assert_eq!((bands.filter.support(), tiled.filter.support()), (0, 1));
    let (a, ca) = render(&world, &cam, &whitted(), &bands);
    let (b, cb) = render(&world, &cam, &whitted(), &tiled);
    let bits = |f: &Frame| {
        f.color
            .iter()
            .flat_map(|v| v.to_array())
            .map(f32::to_bits)
            .collect::<Vec<_>>()
    };
    assert!(bits(&a) == bits(&b));
    assert_eq!(a.depth, b.depth);
    assert_eq!(a.samples, b.samples);
    assert_eq!(a.cost, b.cost);
    assert_eq!(ca, cb);
}
