//! One kind of ray of `glint bench rays` alone, on one thread, for A/B runs
//! and profiles of the packet code:
//! `cargo run --release --example packet_rays -- MESH.obj PREFIX KIND [PASSES] [EVERY]`
//! with KIND one of `camera8` (the camera rays as 4x2-pixel packets),
//! `camera1` (the same rays one at a time, with the coherent hint, as
//! `glint bench rays` traces them), `camera1u` (one at a time without the
//! hint), `shadow8` (eight consecutive
//! shadow rays a packet), `shadow1`, `incoherent1` (the incoherent rays one
//! at a time). Runs PASSES passes (default 3) over
//! every EVERY-th packet (default 1; a larger one makes a short workload for
//! callgrind) and prints the best pass's Mrays/s and the checksums (hits and
//! sum of `t`, or occluded rays), which equal `glint bench rays`'s for EVERY
//! 1.

use glint::format::obj::load_obj;
use glint::math::{Ray, Vec3};
use glint::query::{MeshScene, PacketRay, PACKET};
use std::time::Instant;

/// Width of the anchors' camera image (`raygen.c`).
const IMAGE_WIDTH: usize = 1024;

/// A ray file: a little-endian `u64` count, then `count` records of eight
/// `f32` (`ox oy oz tmin dx dy dz tmax`).
fn read_rays(path: &str) -> Result<Vec<PacketRay>, String> {
    let bytes = std::fs::read(path).map_err(|e| format!("{path}: {e}"))?;
    let body = bytes.get(8..).ok_or("short ray file")?;
    Ok(body
        .chunks_exact(32)
        .map(|r| {
            let f = |i: usize| f32::from_le_bytes(r[4 * i..4 * i + 4].try_into().expect("4 bytes"));
            PacketRay {
                ray: Ray::new(Vec3::new(f(0), f(1), f(2)), Vec3::new(f(4), f(5), f(6))),
                tmin: f(3),
                tmax: f(7),
            }
        })
        .collect())
}

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let usage =
        "usage: packet_rays MESH.obj PREFIX camera8|camera1|camera1u|shadow8|shadow1|incoherent1 [PASSES] [EVERY]";
    let arg = |i: usize| args.get(i).ok_or(usage);
    let num = |i: usize, d: usize| args.get(i).map_or(Ok(d), |s| s.parse().map_err(|_| usage));
    let (kind, passes, every) = (arg(3)?.as_str(), num(4, 3)?, num(5, 1)?.max(1));
    let mesh = load_obj(std::path::Path::new(arg(1)?)).map_err(|e| e.render())?;
    let scene = MeshScene::new(&mesh.positions, &mesh.triangles).map_err(|e| e.to_string())?;
    let file = if kind.starts_with("camera") {
        "primary"
    } else if kind.starts_with("incoherent") {
        "incoherent"
    } else {
        "shadow"
    };
    let rays = read_rays(&format!("{}.{file}.rays", arg(2)?))?;
    let packets: Vec<Vec<PacketRay>> = if kind.starts_with("camera") {
        let per_row = IMAGE_WIDTH / 4;
        (0..rays.len() / PACKET)
            .map(|k| {
                let (ty, tx) = (k / per_row, k % per_row);
                (0..PACKET)
                    .map(|l| rays[(2 * ty + l / 4) * IMAGE_WIDTH + 4 * tx + l % 4])
                    .collect()
            })
            .collect()
    } else {
        rays.chunks(PACKET).map(<[PacketRay]>::to_vec).collect()
    };
    let packets: Vec<_> = packets.into_iter().step_by(every).collect();
    let n: usize = packets.iter().map(Vec::len).sum();
    let mut best = f64::INFINITY;
    let (mut hits, mut tsum) = (0u64, 0f64);
    for _ in 0..passes {
        (hits, tsum) = (0, 0.0);
        let t = Instant::now();
        let mut out = [None; PACKET];
        for p in &packets {
            match kind {
                "camera8" => {
                    scene.intersect_packet(p, &mut out);
                    for h in out[..p.len()].iter().flatten() {
                        hits += 1;
                        tsum += f64::from(h.t);
                    }
                }
                "camera1" => {
                    for r in p {
                        if let Some(h) = scene.intersect_coherent(&r.ray, r.tmin, r.tmax) {
                            hits += 1;
                            tsum += f64::from(h.t);
                        }
                    }
                }
                "camera1u" | "incoherent1" => {
                    for r in p {
                        if let Some(h) = scene.intersect(&r.ray, r.tmin, r.tmax) {
                            hits += 1;
                            tsum += f64::from(h.t);
                        }
                    }
                }
                "shadow8" => hits += u64::from(scene.occluded_packet(p).count_ones()),
                "shadow1" => {
                    for r in p {
                        hits += u64::from(scene.occluded(&r.ray, r.tmin, r.tmax));
                    }
                }
                _ => return Err(usage.into()),
            }
        }
        best = best.min(t.elapsed().as_secs_f64());
    }
    println!(
        "{kind}: {:.3} Mrays/s ({n} rays, best of {passes}) hits={hits} tsum={tsum:.6}",
        n as f64 / best / 1e6
    );
    Ok(())
}
