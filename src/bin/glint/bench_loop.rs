//! `glint bench-loop`: the tile loop against the old row loop at one sample
//! per pixel, in one process, alternating the two so both see the same
//! machine load; medians and their ratio.

use glint::format::load_scene;
use glint::integrator::Whitted;
use glint::render::legacy::render_rows;
use glint::render::{render, CameraModel, PixelOffset};
use glint::world::{BuildOptions, World};
use std::path::PathBuf;
use std::time::Instant;

/// Settings of the loop benchmark.
pub struct LoopArgs {
    /// Scene files.
    pub scenes: Vec<PathBuf>,
    /// Square image size.
    pub size: u32,
    /// Timed runs per loop (after one warm-up each).
    pub runs: usize,
}

/// Runs the benchmark and prints a markdown table.
pub fn run(args: &LoopArgs) -> Result<(), String> {
    let integrator = Whitted {
        bounces: 5,
        weight_cutoff: 0.01,
        shadows: true,
        shade_back: true,
        ..Whitted::default()
    };
    println!(
        "{0}x{0} pixels, 1 sample per pixel (centre), shadows, 5 bounces, BVH; median of {1} alternating runs; {2} threads\n",
        args.size,
        args.runs,
        rayon::current_num_threads()
    );
    println!("| scene | old row loop ms | tile loop ms | tile / old |");
    println!("|---|---|---|---|");
    let mut ratios = Vec::new();
    for path in &args.scenes {
        let scene = load_scene(path).map_err(|e| e.render())?;
        let world = World::build(&scene, BuildOptions::default());
        let cam = CameraModel::new(world.camera());
        let size = (args.size, args.size);
        let old = || render_rows(&world, &cam, &integrator, size, PixelOffset::CENTER);
        let new = || render(&world, &cam, &integrator, size, PixelOffset::CENTER);
        // Warm-up (page faults, caches), and a check that both agree.
        let (a, b) = (old().0, new().0);
        if a.color != b.color {
            return Err(format!("{}: the two loops disagree", path.display()));
        }
        let (mut t_old, mut t_new) = (Vec::new(), Vec::new());
        for _ in 0..args.runs.max(1) {
            let t = Instant::now();
            std::hint::black_box(new());
            t_new.push(t.elapsed().as_secs_f64() * 1e3);
            let t = Instant::now();
            std::hint::black_box(old());
            t_old.push(t.elapsed().as_secs_f64() * 1e3);
        }
        let (mo, mn) = (median(&mut t_old), median(&mut t_new));
        ratios.push(mn / mo);
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        println!("| {name} | {mo:.1} | {mn:.1} | {:.3} |", mn / mo);
    }
    let g = ratios.iter().map(|r| r.ln()).sum::<f64>() / ratios.len().max(1) as f64;
    println!("\ngeometric mean of tile / old: {:.3}", g.exp());
    Ok(())
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}
