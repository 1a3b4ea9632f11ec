//! A lean reader for the common case of OBJ meshes: only `v x y z` lines,
//! `f` lines of plain positive vertex indices, comments and blank lines. It
//! parses chunks of lines in parallel and knows nothing about errors: on any
//! line it does not accept (including every malformed one) it gives up, and
//! the careful reader (`obj.rs`: positioned checks, then `tobj`) reads the
//! file instead, so errors and unusual files behave exactly as before.
//!
//! Why: the careful reader takes 3–4 s for a 4M-triangle mesh; this one
//! reads it in a fraction of that. Numbers are parsed by `str::parse::<f32>`
//! as `tobj` does, and polygons become the same fans, so both readers give
//! the same triangles.

use crate::math::Vec3;
use crate::scene::Mesh;
use rayon::prelude::*;

/// Bytes per parallel chunk (cut at line ends).
const CHUNK: usize = 1 << 20;

/// What one chunk of lines holds.
#[derive(Default)]
struct Part {
    positions: Vec<Vec3>,
    /// Triangles with 1-based indices into the whole file's vertices.
    triangles: Vec<[u32; 3]>,
    /// The largest amount by which a face index exceeds the vertices
    /// defined before it *within this chunk*: the chunk is valid when the
    /// vertices of the chunks before it cover it.
    excess: i64,
}

/// The mesh of `text`, or `None` when the careful reader must decide.
pub(crate) fn parse(text: &str) -> Option<Mesh> {
    if !text.is_ascii() {
        return None; // Unicode whitespace: the careful reader's business
    }
    let bytes = text.as_bytes();
    // Chunk boundaries just after a '\n'.
    let mut cuts = vec![0];
    while let Some(&last) = cuts.last() {
        let want = last + CHUNK;
        if want >= bytes.len() {
            break;
        }
        match bytes[want..].iter().position(|&b| b == b'\n') {
            Some(p) => cuts.push(want + p + 1),
            None => break,
        }
    }
    cuts.push(bytes.len());
    let parts: Vec<Part> = cuts
        .par_windows(2)
        .map(|w| chunk(&text[w[0]..w[1]]))
        .collect::<Option<_>>()?;
    let mut mesh = Mesh::default();
    let total_v: usize = parts.iter().map(|p| p.positions.len()).sum();
    let total_t: usize = parts.iter().map(|p| p.triangles.len()).sum();
    u32::try_from(total_v).ok()?;
    mesh.positions.reserve_exact(total_v);
    mesh.triangles.reserve_exact(total_t);
    for p in parts {
        if p.excess > mesh.positions.len() as i64 {
            return None; // an index beyond the vertices defined so far
        }
        mesh.positions.extend_from_slice(&p.positions);
        mesh.triangles
            .extend(p.triangles.iter().map(|t| t.map(|i| i - 1)));
    }
    Some(mesh)
}

/// Parses one chunk of whole lines.
fn chunk(text: &str) -> Option<Part> {
    let mut part = Part {
        excess: i64::MIN,
        ..Part::default()
    };
    let mut corners: Vec<u32> = Vec::with_capacity(8);
    for line in text.split('\n') {
        let mut words = line.split_ascii_whitespace();
        match words.next() {
            None => {}
            Some(w) if w.starts_with('#') => {}
            Some("v") => {
                let mut c = [0f32; 3];
                for x in &mut c {
                    *x = words.next()?.parse().ok().filter(|x: &f32| x.is_finite())?;
                }
                if words.next().is_some() {
                    return None; // `w` or colours
                }
                part.positions.push(Vec3::from(c));
            }
            Some("f") => {
                corners.clear();
                for w in words {
                    if !w.bytes().all(|b| b.is_ascii_digit()) {
                        return None; // slashes, signs: the careful reader
                    }
                    let i: u32 = w.parse().ok().filter(|&i| i > 0)?;
                    corners.push(i);
                }
                if corners.len() < 3 {
                    return None;
                }
                let defined = part.positions.len() as i64;
                let most = *corners.iter().max()? as i64;
                part.excess = part.excess.max(most - defined);
                for k in 2..corners.len() {
                    part.triangles
                        .push([corners[0], corners[k - 1], corners[k]]);
                }
            }
            Some(_) => return None,
        }
    }
    Some(part)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::obj::parse_obj_careful;
    use std::path::Path;

    /// Triangles as coordinates: what both readers must agree on.
    fn corners(m: &Mesh) -> Vec<[Vec3; 3]> {
        m.triangles
            .iter()
            .map(|t| t.map(|i| m.positions[i as usize]))
            .collect()
    }

    #[test]
    fn same_triangles_as_the_careful_reader() {
        for src in [
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
            "# c\nv 0 0 0\n\nv 1 0 0\r\nv 0 1 0\nf 1 2 3\nv 5 5 5\nf 4 1 2\n",
            "v 1e-3 -2.5E2 +7\nv .5 1. 3\nv 9 9 9\n  f\t3 2 1  \n",
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 2 0\nf 1 2 3 4 5\n",
        ] {
            let lean = parse(src).expect("lean reads it");
            let careful = parse_obj_careful(src.as_bytes(), Path::new("m.obj")).unwrap();
            assert_eq!(corners(&lean), corners(&careful), "{src:?}");
        }
    }

    #[test]
    fn anything_unusual_is_left_to_the_careful_reader() {
        for src in [
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -3\n",
            "v 0 0 0 1\n",
            "v 0 nan 0\n",
            "v 0 0\n",
            "o thing\nv 0 0 0\n",
            "f 1 2 3\nv 0 0 0\n",
            "v 0 0 0\nv 1 0 0\nf 1 2\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n",
            "v 0 0 0\u{a0}\n",
        ] {
            assert!(parse(src).is_none(), "{src:?}");
        }
    }

    #[test]
    fn indices_may_refer_to_vertices_of_earlier_chunks() {
        // More than one chunk: vertices first, faces later.
        let mut src = String::new();
        let n = 3 * (CHUNK / 20 + 1000);
        for i in 0..n {
            src += &format!("v {i} {} 0.25\n", i % 7);
        }
        for i in 0..n / 3 {
            src += &format!("f {} {} {}\n", 3 * i + 1, 3 * i + 2, 3 * i + 3);
        }
        assert!(src.len() > 2 * CHUNK);
        let lean = parse(&src).unwrap();
        let careful = parse_obj_careful(src.as_bytes(), Path::new("m.obj")).unwrap();
        assert_eq!(corners(&lean), corners(&careful));
        // A face in the first chunk referring to a vertex defined later.
        let bad = format!("f 1 2 {}\n{src}", n);
        assert!(parse(&bad).is_none());
    }
}
