//! Times reading one generated mesh in every mesh format glint reads (issue
//! 39's parsing-speed check): OBJ (the lean parallel reader; with `vn`
//! normals, the careful one), ASCII PLY,
//! binary PLY (both byte orders) and glTF (GLB), each through
//! `glint::format::load_scene` (read, parse, frame; no acceleration
//! structure), median of 3 runs, with each format's ratio to OBJ.
//!
//! ```sh
//! cargo run --release --example mesh_formats_bench            # 4M triangles
//! cargo run --release --example mesh_formats_bench -- 1000000 # fewer
//! ```

use glint::format::load_scene;
use std::fmt::Write as _;
use std::time::Instant;

fn main() {
    let triangles: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(4_000_000);
    // A grid of n x n quads, two triangles each, on a wavy sheet.
    let n = ((triangles / 2) as f64).sqrt().ceil() as u32;
    let mut pos = Vec::new();
    for i in 0..=n {
        for j in 0..=n {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            pos.push([x, y, 0.05 * (9.0 * x).sin() * (7.0 * y).cos()]);
        }
    }
    let k = |i: u32, j: u32| i * (n + 1) + j;
    let mut tri = Vec::new();
    for i in 0..n {
        for j in 0..n {
            tri.push([k(i, j), k(i + 1, j), k(i + 1, j + 1)]);
            tri.push([k(i, j), k(i + 1, j + 1), k(i, j + 1)]);
        }
    }
    let dir = tempfile::tempdir().expect("a temporary folder");
    let mut files = Vec::new();
    let mut obj = String::new();
    for p in &pos {
        writeln!(obj, "v {} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for t in &tri {
        writeln!(obj, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1).unwrap();
    }
    files.push(("OBJ", "m.obj", obj.into_bytes()));
    // With vertex normals: `tobj` and the per-position normal split
    // (`format/obj.rs`) instead of the lean reader.
    let mut obj_vn = String::new();
    for p in &pos {
        writeln!(obj_vn, "v {} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for _ in &pos {
        obj_vn.push_str("vn 0 0 1\n");
    }
    for t in &tri {
        let [a, b, c] = t.map(|i| i + 1);
        writeln!(obj_vn, "f {a}//{a} {b}//{b} {c}//{c}").unwrap();
    }
    files.push(("OBJ with vn", "vn.obj", obj_vn.into_bytes()));
    let header = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex {}\nproperty float x\nproperty float y\n\
             property float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
            pos.len(),
            tri.len()
        )
    };
    let mut ascii = header("ascii");
    for p in &pos {
        writeln!(ascii, "{} {} {}", p[0], p[1], p[2]).unwrap();
    }
    for t in &tri {
        writeln!(ascii, "3 {} {} {}", t[0], t[1], t[2]).unwrap();
    }
    files.push(("PLY ASCII", "a.ply", ascii.into_bytes()));
    for (name, file, big) in [
        ("PLY binary LE", "le.ply", false),
        ("PLY binary BE", "be.ply", true),
    ] {
        let fmt = if big {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        };
        let mut b = header(fmt).into_bytes();
        let f = |b: &mut Vec<u8>, x: [u8; 4]| b.extend(x);
        for p in &pos {
            for x in p {
                f(
                    &mut b,
                    if big {
                        x.to_be_bytes()
                    } else {
                        x.to_le_bytes()
                    },
                );
            }
        }
        for t in &tri {
            b.push(3);
            for &i in t {
                f(
                    &mut b,
                    if big {
                        i.to_be_bytes()
                    } else {
                        i.to_le_bytes()
                    },
                );
            }
        }
        files.push((name, file, b));
    }
    files.push(("glTF (GLB)", "m.glb", glb(&pos, &tri)));
    println!(
        "{} triangles, {} vertices; median of 3 runs of load_scene",
        tri.len(),
        pos.len()
    );
    println!("| format | file size | median s | vs OBJ |");
    println!("|---|---|---|---|");
    let mut obj_time = None;
    for (name, file, bytes) in &files {
        let path = dir.path().join(file);
        std::fs::write(&path, bytes).unwrap();
        let mut times: Vec<f64> = (0..3)
            .map(|_| {
                let t = Instant::now();
                let scene = load_scene(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
                let s = t.elapsed().as_secs_f64();
                assert_eq!(scene.summary().triangles, tri.len());
                s
            })
            .collect();
        times.sort_by(f64::total_cmp);
        let m = times[1];
        let base = *obj_time.get_or_insert(m);
        println!(
            "| {name} | {:.1} MB | {m:.3} | {:.2}x |",
            bytes.len() as f64 / 1e6,
            m / base
        );
        std::fs::remove_file(&path).unwrap();
    }
}

/// A GLB holding the mesh: positions then u32 indices in the binary chunk.
fn glb(pos: &[[f32; 3]], tri: &[[u32; 3]]) -> Vec<u8> {
    let mut bin = Vec::new();
    pos.iter()
        .flatten()
        .for_each(|x| bin.extend(x.to_le_bytes()));
    let pl = bin.len();
    tri.iter()
        .flatten()
        .for_each(|i| bin.extend(i.to_le_bytes()));
    let lo = |c: usize| pos.iter().map(|p| p[c]).fold(f32::INFINITY, f32::min);
    let hi = |c: usize| pos.iter().map(|p| p[c]).fold(f32::NEG_INFINITY, f32::max);
    let mut json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"buffers":[{{"byteLength":{}}}],
"bufferViews":[{{"buffer":0,"byteLength":{pl}}},{{"buffer":0,"byteOffset":{pl},"byteLength":{}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{},"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}},
{{"bufferView":1,"componentType":5125,"count":{},"type":"SCALAR"}}]}}"#,
        bin.len(),
        bin.len() - pl,
        pos.len(),
        lo(0),
        lo(1),
        lo(2),
        hi(0),
        hi(1),
        hi(2),
        tri.len() * 3
    )
    .into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}
