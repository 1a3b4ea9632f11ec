//! Build times of the fast BVH alone, for A/B runs of the build code:
//! `cargo run --release --example build_time -- MESH.obj THREADS [REPS]`
//! builds `query::MeshScene` over the OBJ's triangles REPS times (default
//! 7) in a pool of THREADS threads and prints the best and every time (ms).
//! `glint bench rays` prints the same best-of-five build time, then traces
//! its ray files; this skips the rays, so that two builds of the example
//! (say, before and after a change, copied aside) can be alternated quickly.

use glint::format::obj::load_obj;
use glint::query::MeshScene;
use std::time::Instant;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: build_time MESH.obj THREADS [REPS]";
    let mesh = args.get(1).ok_or(usage)?;
    let threads: usize = args.get(2).ok_or(usage)?.parse().map_err(|_| usage)?;
    let reps: usize = match args.get(3) {
        Some(r) => r.parse().map_err(|_| usage)?,
        None => 7,
    };
    let mesh = load_obj(std::path::Path::new(mesh)).map_err(|e| e.render())?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())?;
    let times = pool.install(|| {
        (0..reps)
            .map(|_| {
                let t = Instant::now();
                let scene = MeshScene::new(&mesh.positions, &mesh.triangles).expect("a valid mesh");
                let ms = t.elapsed().as_secs_f64() * 1e3;
                drop(scene);
                ms
            })
            .collect::<Vec<f64>>()
    });
    let best = times.iter().copied().fold(f64::INFINITY, f64::min);
    let all: Vec<String> = times.iter().map(|t| format!("{t:.1}")).collect();
    println!(
        "{} triangles, {threads} thread(s): best {best:.1} ms (runs: {})",
        mesh.triangles.len(),
        all.join(" ")
    );
    Ok(())
}
