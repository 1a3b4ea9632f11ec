//! Cost images: the per-pixel counts add up to the render's totals, for
//! every accelerator and with many samples per pixel.

use crate::common::*;
use glint::accel::{AccelKind, Split};
use glint::integrator::Whitted;
use glint::render::{render_image, Adaptive, CameraModel, Control, PixelOffset, Settings};
use glint::sampler::{Sampler, SamplerKind};
use glint::world::{BuildOptions, World};

#[test]
fn per_pixel_costs_sum_to_the_totals() {
    let scene = glint::format::load_scene(&own_scene("whitted.txt")).unwrap();
    let integrator = Whitted {
        bounces: 3,
        weight_cutoff: 0.01,
        shadows: true,
        shade_back: true,
        ..Whitted::default()
    };
    for accel in [
        AccelKind::None,
        AccelKind::Grid { res: None },
        AccelKind::Octree,
        AccelKind::Bvh(Split::Sah),
    ] {
        let world = World::build(
            &scene,
            BuildOptions {
                accel,
                flatten: true,
            },
        );
        let camera = CameraModel::new(world.camera());
        // 0 is adaptive subdivision, whose pixels share their corner rays.
        for spp in [1, 4, 0] {
            let mut settings = Settings::one_ray((37, 23), PixelOffset::CENTER);
            settings.pixel_cost = true;
            if spp > 1 {
                settings.sampler = Sampler::new(SamplerKind::Jittered, spp, 7);
            }
            if spp == 0 {
                settings.adaptive = Some(Adaptive {
                    threshold: 0.05,
                    max_depth: 2,
                });
                // Tiles smaller than the image: points shared across tile
                // edges are traced by both tiles, and counted by both.
                settings.tile_size = 8;
            }
            let r = render_image(&world, &camera, &integrator, &settings, Control::default());
            let (tests, nodes) = glint::viz::cost::totals(&r.frame);
            assert_eq!(tests, r.counters.intersection_tests, "{accel} spp {spp}");
            assert_eq!(nodes, r.counters.nodes_visited, "{accel} spp {spp}");
            assert!(tests > 0);
            // Pixels differ: the mirror and glass cost more than the sky.
            let max = r.frame.cost.iter().map(|c| c.tests).max().unwrap();
            let min = r.frame.cost.iter().map(|c| c.tests).min().unwrap();
            assert!(max > min, "{accel}: a flat cost image");
        }
    }
}

#[test]
fn cost_image_from_the_command_line() {
    let dir = scratch("cost");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
        .arg("render")
        .arg(own_scene("mesh_knot_1k.txt"))
        .args([
            "-o",
            "k.png",
            "--size",
            "40",
            "30",
            "--shadows",
            "--accel",
            "grid",
        ])
        .args(["--cost-image", "cost.png", "--stats", "--quiet"])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(dir.join("cost.png")).unwrap();
    assert_eq!((img.width(), img.height()), (2 * 40 + 4, 30 + 22));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
        .arg("render")
        .arg(own_scene("mesh_knot_1k.txt"))
        .args([
            "-o",
            "k.png",
            "--size",
            "8",
            "8",
            "--adaptive",
            "0.1",
            "--cost-image",
            "c.png",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    // Adaptive subdivision has a cost image too: its pixels' shares of the
    // shared corner rays add up (the library test checks the sums).
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(dir.join("c.png")).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), (2 * 8 + 4, 8 + 22));
    // Not a flat map: the subdivided pixels (the knot's edges) cost more.
    let mut heat: Vec<_> = (0..8)
        .flat_map(|y| (0..8).map(move |x| (x, y)))
        .map(|(x, y)| img.get_pixel(x, y).0)
        .collect();
    heat.sort_unstable();
    heat.dedup();
    assert!(heat.len() > 1, "a flat adaptive cost image");
}
