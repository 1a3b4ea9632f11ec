//! What a finished job measured: the [`Report`], its [`Stats`] (printed by
//! `--stats`, written by `--stats-json`) and the course's statistics report.

use crate::render::{Frame, Settings};
use crate::scene::Scene;
use crate::stats::Counters;
use std::time::Duration;

/// What a finished job measured.
#[derive(Clone, Debug)]
pub struct Report {
    /// The scene as loaded.
    pub scene: Scene,
    /// Merged ray counters.
    pub counters: Counters,
    /// Aggregate description.
    pub accel: String,
    /// Aggregate build time.
    pub build_ms: f64,
    /// Time to read the scene and its meshes.
    pub load_ms: f64,
    /// Time to flatten the scene and build the aggregate.
    pub world_ms: f64,
    /// Time spent tracing.
    pub render: Duration,
    /// Number of primitives in the world.
    pub primitives: usize,
    /// Bounds of the world's bounded primitives (planes excluded), in world
    /// space (the scene file's coordinates, not the camera-centred rendering
    /// space).
    pub bounds: crate::math::Aabb,
    /// The rendered planes.
    pub frame: Frame,
    /// The sampling settings rendered with.
    pub settings: Settings,
}

/// The statistics of one render, as printed by `--stats` and written by
/// `--stats-json` (the keys are the JSON field names).
#[derive(Clone, Debug, serde::Serialize)]
pub struct Stats {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Aggregate and its parameters.
    pub accel: String,
    /// Primitives in the world (mesh triangles count one each).
    pub primitives: usize,
    /// Triangles in the scene.
    pub triangles: usize,
    /// Scene and mesh reading time.
    pub load_ms: f64,
    /// Flattening plus aggregate build time.
    pub world_ms: f64,
    /// Aggregate build time.
    pub build_ms: f64,
    /// Tracing time.
    pub render_ms: f64,
    /// Eye rays.
    pub rays_primary: u64,
    /// Shadow rays.
    pub rays_shadow: u64,
    /// Reflected rays.
    pub rays_reflected: u64,
    /// Refracted rays.
    pub rays_refracted: u64,
    /// Of the reflected and refracted rays, those over a glossy lobe.
    pub rays_glossy: u64,
    /// Ambient-occlusion rays.
    pub rays_occlusion: u64,
    /// Photon rays (the path tracer's caustic map).
    pub rays_photon: u64,
    /// All rays.
    pub rays_total: u64,
    /// Ray–primitive intersection tests.
    pub intersection_tests: u64,
    /// Nodes or cells visited.
    pub nodes_visited: u64,
    /// Tests per ray.
    pub tests_per_ray: f64,
    /// Nodes or cells per ray.
    pub nodes_per_ray: f64,
    /// Rays per second of tracing time.
    pub rays_per_second: f64,
    /// Pixel sampling: sampler and samples per pixel, or adaptive settings.
    pub sampling: String,
    /// Reconstruction filter.
    pub filter: String,
    /// Camera rays per pixel (samples per pixel).
    pub samples_per_pixel: f64,
    /// Rays of every kind per pixel.
    pub rays_per_pixel: f64,
}

impl Report {
    /// The statistics of this render.
    pub fn stats(&self) -> Stats {
        let c = &self.counters;
        let rays = c.rays_total().max(1) as f64;
        let pixels = (u64::from(self.frame.width) * u64::from(self.frame.height)).max(1) as f64;
        let secs = self.render.as_secs_f64();
        Stats {
            width: self.frame.width,
            height: self.frame.height,
            accel: self.accel.clone(),
            primitives: self.primitives,
            triangles: self.scene.summary().triangles,
            load_ms: self.load_ms,
            world_ms: self.world_ms,
            build_ms: self.build_ms,
            render_ms: secs * 1e3,
            rays_primary: c.primary,
            rays_shadow: c.shadow,
            rays_reflected: c.reflected,
            rays_refracted: c.refracted,
            rays_glossy: c.glossy,
            rays_occlusion: c.occlusion,
            rays_photon: c.photon,
            rays_total: c.rays_total(),
            intersection_tests: c.intersection_tests,
            nodes_visited: c.nodes_visited,
            tests_per_ray: c.intersection_tests as f64 / rays,
            nodes_per_ray: c.nodes_visited as f64 / rays,
            rays_per_second: rays / secs.max(1e-9),
            sampling: describe_sampling(&self.settings),
            filter: if self.settings.adaptive.is_some() {
                "pixel square (adaptive)".into()
            } else {
                self.settings.filter.to_string()
            },
            samples_per_pixel: c.primary as f64 / pixels,
            rays_per_pixel: c.rays_total() as f64 / pixels,
        }
    }

    /// The human-readable statistics table.
    pub fn stats_text(&self) -> String {
        let st = self.stats();
        let mut s = String::new();
        let mut line = |k: &str, v: String| s.push_str(&format!("{k:<28}{v}\n"));
        line("image", format!("{}x{}", st.width, st.height));
        line("accelerator", st.accel.clone());
        line("primitives", st.primitives.to_string());
        line("triangles", st.triangles.to_string());
        line("load time", format!("{:.2} ms", st.load_ms));
        line(
            "world time",
            format!("{:.2} ms (flatten + build)", st.world_ms),
        );
        line("build time", format!("{:.2} ms", st.build_ms));
        line("render time", format!("{:.2} ms", st.render_ms));
        line("primary rays", st.rays_primary.to_string());
        line("shadow rays", st.rays_shadow.to_string());
        line("reflected rays", st.rays_reflected.to_string());
        line("refracted rays", st.rays_refracted.to_string());
        line("  of which glossy", st.rays_glossy.to_string());
        line("occlusion rays", st.rays_occlusion.to_string());
        if st.rays_photon > 0 {
            line("photon rays", st.rays_photon.to_string());
        }
        line("rays total", st.rays_total.to_string());
        line("intersection tests", st.intersection_tests.to_string());
        line("nodes visited", st.nodes_visited.to_string());
        line("sampling", st.sampling.clone());
        line("filter", st.filter.clone());
        line("rays / second", format!("{:.0}", st.rays_per_second));
        line("samples / pixel", format!("{:.3}", st.samples_per_pixel));
        line("rays / pixel", format!("{:.3}", st.rays_per_pixel));
        line("tests / ray", format!("{:.3}", st.tests_per_ray));
        line("nodes / ray", format!("{:.3}", st.nodes_per_ray));
        s
    }
}

/// One line naming how pixels were sampled.
fn describe_sampling(s: &Settings) -> String {
    match s.adaptive {
        Some(a) => format!(
            "adaptive (threshold {}, max depth {})",
            a.threshold, a.max_depth
        ),
        None => format!(
            "{} x {} (seed {})",
            s.sampler.kind,
            s.sampler.spp(),
            s.sampler.seed
        ),
    }
}

/// The course's statistics report (`raytracing_stats.C`, NOTES.md A6), for
/// `raytracer -stats`: time, pixels, scene bounds, grid cells, rays by kind,
/// intersections, cells traversed and the per-ray figures, which count
/// non-shadow plus shadow rays. `glint --stats` and `--stats-json` keep the
/// full counters.
pub fn course_stats_text(report: &Report) -> String {
    // The grid's resolution, from its description (`grid 10x10x7`).
    let grid: Option<[u32; 3]> = report.accel.strip_prefix("grid ").and_then(|r| {
        let v: Vec<u32> = r.split('x').filter_map(|n| n.trim().parse().ok()).collect();
        <[u32; 3]>::try_from(v).ok()
    });
    let bounds = Some(report.bounds);
    let st = report.stats();
    let secs = report.render.as_secs_f64();
    let whole = secs as u64;
    let pixels = u64::from(st.width) * u64::from(st.height);
    let rays = st.rays_total.max(1) as f64;
    let non_shadow = st.rays_total - st.rays_shadow;
    let mut s =
        String::from("********************************************\nRAY TRACING STATISTICS\n");
    let mut line = |k: &str, v: String| s.push_str(&format!("  {k:<27}{v}\n"));
    line(
        "total time",
        format!("{}:{:02}:{:02}", whole / 3600, whole / 60 % 60, whole % 60),
    );
    line(
        "num pixels",
        format!("{pixels} ({}x{})", st.width, st.height),
    );
    line(
        "scene bounds",
        match bounds.filter(|b| !b.is_empty()) {
            Some(b) => format!(
                "({:.4}, {:.4}, {:.4}) -> ({:.4}, {:.4}, {:.4})",
                b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
            ),
            None => "NULL".into(),
        },
    );
    line(
        "num grid cells",
        match grid {
            Some([x, y, z]) => format!(
                "{} ({x}x{y}x{z})",
                u64::from(x) * u64::from(y) * u64::from(z)
            ),
            None => "NULL".into(),
        },
    );
    line("num non-shadow rays", non_shadow.to_string());
    line("num shadow rays", st.rays_shadow.to_string());
    line("total intersections", st.intersection_tests.to_string());
    line("total cells traversed", st.nodes_visited.to_string());
    line("rays per second", format!("{:.1}", rays / secs.max(1e-9)));
    line(
        "rays per pixel",
        format!("{:.3}", rays / pixels.max(1) as f64),
    );
    line(
        "intersections per ray",
        format!("{:.3}", st.intersection_tests as f64 / rays),
    );
    line(
        "cells traversed per ray",
        format!("{:.3}", st.nodes_visited as f64 / rays),
    );
    s.push_str("********************************************\n");
    s
}
