//! The measurements of `docs/antialiasing.md`: RMSE against a 1024-spp
//! render, per sampler and sample count, and for adaptive subdivision, on two
//! scenes; writes `docs/images/aa/results.csv` and example images.
//!
//! Needs the course data (scene7_01 and scene7_02):
//! `GLINT_SHARED=/path/to/shared cargo run --release --example antialiasing_study [SCENES_DIR] [OUT_DIR]`
//! (SCENES_DIR defaults to `$GLINT_SHARED/scenes/6837`, else
//! `../shared/scenes/6837`; without it the example exits 2 saying so).
//! It writes into OUT_DIR, `target/antialiasing_study` unless given;
//! `docs/images/aa` refreshes the document's images. Then
//! `python3 scripts/plot_antialiasing.py` draws the plot.

use glint::format::load_scene;
use glint::integrator::Whitted;
use glint::math::Vec3;
use glint::output::write_rgb;
use glint::render::{
    render_image, Adaptive, CameraModel, Control, Filter, Frame, PixelOffset, Rendered, Settings,
};
use glint::sampler::{GridLayout, Sampler, SamplerKind};
use glint::world::{BuildOptions, World};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

const SIZE: u32 = 96;

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

/// Enlarges by 3 (nearest) so single pixels are visible in the document.
fn save(dir: &Path, name: &str, f: &Frame) {
    let k = 3;
    let (w, h) = (f.width * k, f.height * k);
    let px: Vec<Vec3> = (0..h)
        .flat_map(|r| (0..w).map(move |x| (r, x)))
        .map(|(r, x)| f.color[((r / k) * f.width + x / k) as usize])
        .collect();
    write_rgb(&dir.join(format!("{name}.png")), w, h, &px).unwrap();
}

fn main() {
    let scenes = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            std::env::var_os("GLINT_SHARED")
                .map_or_else(|| PathBuf::from("../shared"), PathBuf::from)
                .join("scenes/6837")
        });
    if !scenes.join("scene7_01_sphere_triangle.txt").is_file() {
        eprintln!(
            "antialiasing_study: needs the course data: no scene7_01_sphere_triangle.txt in {} (set GLINT_SHARED or pass the scenes folder)",
            scenes.display()
        );
        std::process::exit(2);
    }
    let out_dir = std::env::args()
        .nth(2)
        .map_or_else(|| PathBuf::from("target/antialiasing_study"), PathBuf::from);
    let out = out_dir.as_path();
    std::fs::create_dir_all(out).unwrap();
    let integrator = Whitted {
        bounces: 5,
        weight_cutoff: 0.01,
        shadows: true,
        shade_back: true,
        ..Whitted::default()
    };
    let mut csv = String::from("scene,method,param,rays_per_pixel,rmse\n");
    for (tag, file) in [
        ("sphere_triangle", "scene7_01_sphere_triangle.txt"),
        ("checkerboard", "scene7_02_checkerboard.txt"),
    ] {
        let scene = load_scene(&scenes.join(file)).unwrap();
        let world = World::build(&scene, BuildOptions::default());
        let cam = CameraModel::new(world.camera());
        let base = Settings::one_ray((SIZE, SIZE), PixelOffset::CENTER);
        let run = |s: &Settings| -> Rendered {
            render_image(&world, &cam, &integrator, s, Control::default())
        };
        let with = |kind, spp, seed| Settings {
            sampler: Sampler::new(kind, spp, seed),
            filter: Filter::Box(0.5),
            ..base
        };
        let truth = run(&with(SamplerKind::Jittered, 1024, 12345)).frame;
        save(out, &format!("{tag}_reference_1024"), &truth);
        let pixels = (SIZE * SIZE) as f64;
        for (name, kind) in [
            ("uniform", SamplerKind::Uniform(GridLayout::CENTERS)),
            ("random", SamplerKind::Random),
            ("jittered", SamplerKind::Jittered),
            ("sobol", SamplerKind::Sobol),
        ] {
            for spp in [1, 4, 16, 64, 256] {
                let r = run(&with(kind, spp, 1));
                let e = rmse(&r.frame, &truth);
                let rpp = r.counters.primary as f64 / pixels;
                writeln!(csv, "{tag},{name},{spp},{rpp:.3},{e:.6}").unwrap();
                eprintln!("{tag} {name} {spp}: {e:.5}");
                if spp == 16 || (spp == 1 && name == "uniform") {
                    save(out, &format!("{tag}_{name}_{spp}"), &r.frame);
                }
            }
        }
        for depth in [2, 3] {
            for t in [0.2, 0.1, 0.05, 0.02, 0.01, 0.005] {
                let s = Settings {
                    adaptive: Some(Adaptive {
                        threshold: t,
                        max_depth: depth,
                    }),
                    ..base
                };
                let r = run(&s);
                let e = rmse(&r.frame, &truth);
                let rpp = r.counters.primary as f64 / pixels;
                writeln!(csv, "{tag},adaptive_d{depth},{t},{rpp:.3},{e:.6}").unwrap();
                eprintln!("{tag} adaptive d{depth} t{t}: {rpp:.2} rays/px {e:.5}");
                if depth == 3 && t == 0.02 {
                    save(out, &format!("{tag}_adaptive_d3_t0.02"), &r.frame);
                    let m = glint::render::views::heat_map(SIZE, SIZE, &r.frame.samples);
                    write_rgb(
                        &out.join(format!("{tag}_adaptive_heat.png")),
                        m.width,
                        m.height,
                        &m.pixels,
                    )
                    .unwrap();
                }
            }
        }
    }
    std::fs::write(out.join("results.csv"), csv).unwrap();
}
