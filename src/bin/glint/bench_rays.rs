//! `glint bench rays MESH.obj PREFIX`: the fast BVH against the anchors'
//! ray files (`../shared/anchors`: the same triangles and rays Embree's
//! harness traces), with the checksums Embree prints, so that a ratio of the
//! two throughputs compares equal work.
//!
//! Timing follows Embree's harness: the best of five builds; per ray set one
//! warm-up pass, then the best of three passes; rays are handed out in
//! chunks of 4096 to the worker threads. Packets as the harness makes them
//! for `rtcIntersect8`/`rtcOccluded8`: camera rays in tiles of 4×2 pixels of
//! the 1024-pixel-wide image, shadow rays eight consecutive ones at a time.

use glint::format::obj::load_obj;
use glint::math::{Ray, Vec3};
use glint::query::{MeshScene, PacketRay, PACKET};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Settings of `glint bench rays`.
pub struct RaysArgs {
    /// The OBJ mesh.
    pub mesh: PathBuf,
    /// Ray files are `PREFIX.primary.rays`, `.incoherent.rays`, `.shadow.rays`.
    pub prefix: String,
    /// Worker threads (default: all cores).
    pub threads: Option<usize>,
    /// Print one JSON object instead of text.
    pub json: bool,
    /// Also count nodes visited and triangles tested per ray (an extra,
    /// untimed pass).
    pub stats: bool,
}

/// One ray of a ray file: origin, tmin, direction, tmax.
struct RayRec {
    ray: Ray,
    tmin: f32,
    tmax: f32,
}

/// Reads a ray file: a little-endian `u64` count, then `count` records of
/// eight `f32` (`ox oy oz tmin dx dy dz tmax`).
fn read_rays(path: &Path) -> Result<Vec<RayRec>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let bad = || {
        format!(
            "{}: not a ray file (count and 32-byte records)",
            path.display()
        )
    };
    let head: [u8; 8] = bytes
        .get(..8)
        .ok_or_else(bad)?
        .try_into()
        .map_err(|_| bad())?;
    let n = usize::try_from(u64::from_le_bytes(head)).map_err(|_| bad())?;
    let body = &bytes[8..];
    if body.len() / 32 != n || body.len() % 32 != 0 {
        return Err(bad());
    }
    Ok(body
        .chunks_exact(32)
        .map(|r| {
            let f =
                |k: usize| f32::from_le_bytes([r[4 * k], r[4 * k + 1], r[4 * k + 2], r[4 * k + 3]]);
            RayRec {
                ray: Ray::new(Vec3::new(f(0), f(1), f(2)), Vec3::new(f(4), f(5), f(6))),
                tmin: f(3),
                tmax: f(7),
            }
        })
        .collect())
}

/// Closest-hit or any-hit results of one pass.
#[derive(Clone, Copy, Default)]
struct Sums {
    hits: u64,
    tsum: f64,
}

impl std::ops::Add for Sums {
    type Output = Sums;
    fn add(self, o: Sums) -> Sums {
        Sums {
            hits: self.hits + o.hits,
            tsum: self.tsum + o.tsum,
        }
    }
}

/// Rays handed to a thread at a time (as Embree's harness does).
const CHUNK: usize = 4096;

/// How a pass queries its rays one at a time.
#[derive(Clone, Copy, PartialEq)]
enum Query {
    /// Closest hits, with the coherent hint (`MeshScene::intersect_coherent`):
    /// the camera rays, traced row by row.
    Coherent,
    /// Closest hits without the hint (`MeshScene::intersect`).
    Closest,
    /// Any hit (`MeshScene::occluded`).
    Shadow,
}

fn pass(scene: &MeshScene, rays: &[RayRec], query: Query) -> Sums {
    rays.par_chunks(CHUNK)
        .map(|chunk| {
            let mut s = Sums::default();
            for r in chunk {
                let hit = match query {
                    Query::Shadow => {
                        s.hits += u64::from(scene.occluded(&r.ray, r.tmin, r.tmax));
                        continue;
                    }
                    Query::Coherent => scene.intersect_coherent(&r.ray, r.tmin, r.tmax),
                    Query::Closest => scene.intersect(&r.ray, r.tmin, r.tmax),
                };
                if let Some(h) = hit {
                    s.hits += 1;
                    s.tsum += f64::from(h.t);
                }
            }
            s
        })
        .reduce(Sums::default, |a, b| a + b)
}

/// Width of the anchors' camera image (`raygen.c`), whose rays the
/// primary file holds row by row.
const IMAGE_WIDTH: usize = 1024;

/// The camera rays as packets of 4×2-pixel tiles, tile rows top to bottom
/// (Embree's harness's order); `None` unless the rays fill whole rows of
/// tiles.
fn camera_tiles(rays: &[RayRec]) -> Option<Vec<[PacketRay; PACKET]>> {
    if rays.is_empty() || !rays.len().is_multiple_of(2 * IMAGE_WIDTH) {
        return None;
    }
    let per_row = IMAGE_WIDTH / 4;
    let tiles = rays.len() / PACKET;
    Some(
        (0..tiles)
            .map(|k| {
                let (ty, tx) = (k / per_row, k % per_row);
                std::array::from_fn(|l| {
                    let r = &rays[(2 * ty + l / 4) * IMAGE_WIDTH + 4 * tx + l % 4];
                    PacketRay {
                        ray: r.ray,
                        tmin: r.tmin,
                        tmax: r.tmax,
                    }
                })
            })
            .collect(),
    )
}

/// Rays eight consecutive ones at a time (the last packet may be short).
fn consecutive(rays: &[RayRec]) -> Vec<Vec<PacketRay>> {
    rays.chunks(PACKET)
        .map(|c| {
            c.iter()
                .map(|r| PacketRay {
                    ray: r.ray,
                    tmin: r.tmin,
                    tmax: r.tmax,
                })
                .collect()
        })
        .collect()
}

/// One pass of packets (closest hits, or occlusion for `shadow`), 512
/// packets (4096 rays) handed out at a time.
fn packet_pass<P: AsRef<[PacketRay]> + Sync>(
    scene: &MeshScene,
    packets: &[P],
    shadow: bool,
) -> Sums {
    packets
        .par_chunks(CHUNK / PACKET)
        .map(|chunk| {
            let mut s = Sums::default();
            let mut out = [None; PACKET];
            for p in chunk {
                let p = p.as_ref();
                if shadow {
                    s.hits += u64::from(scene.occluded_packet(p).count_ones());
                } else {
                    scene.intersect_packet(p, &mut out);
                    for h in out[..p.len()].iter().flatten() {
                        s.hits += 1;
                        s.tsum += f64::from(h.t);
                    }
                }
            }
            s
        })
        .reduce(Sums::default, |a, b| a + b)
}

/// [`measure`] for packets.
fn measure_packets<P: AsRef<[PacketRay]> + Sync>(
    scene: &MeshScene,
    packets: &[P],
    shadow: bool,
) -> (f64, Sums) {
    let sums = packet_pass(scene, packets, shadow);
    let best = best_of_three(|| {
        packet_pass(scene, packets, shadow);
    });
    let rays: usize = packets.iter().map(|p| p.as_ref().len()).sum();
    (rays as f64 / best / 1e6, sums)
}

/// Warm-up, then the best of three: Mrays/s and the checksums.
fn measure(scene: &MeshScene, rays: &[RayRec], query: Query) -> (f64, Sums) {
    let sums = pass(scene, rays, query);
    let best = best_of_three(|| {
        pass(scene, rays, query);
    });
    (rays.len() as f64 / best / 1e6, sums)
}

/// Seconds of the fastest of three runs of `run` (run after a warm-up).
fn best_of_three(mut run: impl FnMut()) -> f64 {
    (0..3)
        .map(|_| {
            let t = Instant::now();
            run();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Runs the benchmark and prints its report.
pub fn run(a: &RaysArgs) -> Result<(), String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(a.threads.unwrap_or(0))
        .build()
        .map_err(|e| e.to_string())?;
    pool.install(|| run_in_pool(a))
}

fn run_in_pool(a: &RaysArgs) -> Result<(), String> {
    let t = Instant::now();
    let mesh = load_obj(&a.mesh).map_err(|e| e.render())?;
    let load_ms = t.elapsed().as_secs_f64() * 1e3;
    let rays = |kind: &str| read_rays(Path::new(&format!("{}.{kind}.rays", a.prefix)));
    let (primary, incoherent, shadow) = (rays("primary")?, rays("incoherent")?, rays("shadow")?);
    // Best of five builds, as Embree's harness reports its best of five:
    // a build's time moves by a fifth between passes on this kind of
    // virtual machine (fresh pages are zeroed, and the host may have to
    // back them first), so two minima compare only over as many tries.
    let mut build_ms = f64::INFINITY;
    let mut scene = None;
    for _ in 0..5 {
        drop(scene.take());
        let t = Instant::now();
        let s = MeshScene::new(&mesh.positions, &mesh.triangles).map_err(|e| e.to_string())?;
        build_ms = build_ms.min(t.elapsed().as_secs_f64() * 1e3);
        scene = Some(s);
    }
    let scene = scene.expect("built five times");
    let tris = scene.triangle_count();
    let bytes = scene.memory_bytes() as f64 / tris.max(1) as f64;
    let (mp, p) = measure(&scene, &primary, Query::Coherent);
    let (mg, g) = measure(&scene, &primary, Query::Closest);
    let (mi, i) = measure(&scene, &incoherent, Query::Closest);
    let (ms, s) = measure(&scene, &shadow, Query::Shadow);
    let tiles = camera_tiles(&primary);
    let (mp8, p8) = match &tiles {
        Some(t) => measure_packets(&scene, t, false),
        None => (f64::NAN, Sums::default()),
    };
    let (ms8, s8) = measure_packets(&scene, &consecutive(&shadow), true);
    let threads = rayon::current_num_threads();
    if a.stats {
        for (name, rays, query) in [
            ("primary", &primary, Query::Coherent),
            ("incoherent", &incoherent, Query::Closest),
            ("shadow", &shadow, Query::Shadow),
        ] {
            let mut c = glint::stats::Counters::default();
            for r in rays.iter() {
                match query {
                    Query::Shadow => {
                        scene.occluded_with(&r.ray, r.tmin, r.tmax, &mut c);
                    }
                    Query::Coherent => {
                        scene.intersect_coherent_with(&r.ray, r.tmin, r.tmax, &mut c);
                    }
                    Query::Closest => {
                        scene.intersect_with(&r.ray, r.tmin, r.tmax, &mut c);
                    }
                }
            }
            let n = rays.len().max(1) as f64;
            eprintln!(
                "  {name:10} {:.1} nodes/ray, {:.1} triangles tested/ray",
                c.nodes_visited as f64 / n,
                c.intersection_tests as f64 / n
            );
        }
        let packets = |name: &str, c: glint::stats::Counters, n: usize| {
            let n = n.max(1) as f64;
            eprintln!(
                "  {name:10} {:.2} node visits/ray (one per packet), {:.1} triangles tested/ray",
                c.nodes_visited as f64 / n,
                c.intersection_tests as f64 / n
            );
        };
        if let Some(t) = &tiles {
            let mut c = glint::stats::Counters::default();
            let mut out = [None; PACKET];
            t.iter()
                .for_each(|p| scene.intersect_packet_with(p, &mut out, &mut c));
            packets("primary packets", c, primary.len());
        }
        let mut c = glint::stats::Counters::default();
        for p in consecutive(&shadow) {
            scene.occluded_packet_with(&p, &mut c);
        }
        packets("shadow packets", c, shadow.len());
    }
    if a.json {
        let v = serde_json::json!({
            "triangles": tris,
            "threads": threads,
            "load_ms": load_ms,
            "build_ms": build_ms,
            "bytes_per_triangle": bytes,
            "primary": {"mrays": mp, "hits": p.hits, "tsum": p.tsum},
            "primary_unhinted": {"mrays": mg, "hits": g.hits, "tsum": g.tsum},
            "incoherent": {"mrays": mi, "hits": i.hits, "tsum": i.tsum},
            "shadow": {"mrays": ms, "occluded": s.hits},
            "primary_packets": {"mrays": mp8, "hits": p8.hits, "tsum": p8.tsum},
            "shadow_packets": {"mrays": ms8, "occluded": s8.hits},
        });
        println!("{v}");
    } else {
        println!(
            "# glint bvh8 mesh={} tris={tris} threads={threads} (obj load {load_ms:.0} ms)",
            a.mesh.display()
        );
        println!(
            "build: best {build_ms:.1} ms, {bytes:.1} bytes/triangle (nodes + triangle blocks)"
        );
        println!(
            "  primary    {mp:8.2} Mrays/s  hits={} tsum={:.6}",
            p.hits, p.tsum
        );
        println!(
            "  primary, without the coherent hint {mg:8.2} Mrays/s  hits={} tsum={:.6}",
            g.hits, g.tsum
        );
        println!(
            "  incoherent {mi:8.2} Mrays/s  hits={} tsum={:.6}",
            i.hits, i.tsum
        );
        println!(
            "  shadow     {ms:8.2} Mrays/s  occluded={} of {}",
            s.hits,
            shadow.len()
        );
        if tiles.is_some() {
            println!(
                "  primary, packets of 4x2 pixels {mp8:8.2} Mrays/s  hits={} tsum={:.6}",
                p8.hits, p8.tsum
            );
        }
        println!(
            "  shadow, packets of 8           {ms8:8.2} Mrays/s  occluded={} of {}",
            s8.hits,
            shadow.len()
        );
    }
    Ok(())
}
