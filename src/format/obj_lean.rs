//! A lean reader for the common case of OBJ meshes: only `v x y z` lines,
//! `vn x y z` lines, `f` lines of plain positive vertex indices (or, in every
//! face of the file, `v//vn` corners), comments and blank lines. It
//! parses chunks of lines in parallel and knows nothing about errors: on any
//! line it does not accept (including every malformed one) it gives up, and
//! the careful reader (`obj.rs`: positioned checks, then `tobj`) reads the
//! file instead, so errors and unusual files behave exactly as before.
//!
//! Why: the careful reader takes 3–4 s for a 4M-triangle mesh; this one
//! reads it in a fraction of that. Numbers are parsed by `str::parse::<f32>`
//! as `tobj` does, and polygons become the same fans, so both readers give
//! the same triangles.

use crate::limits::{MAX_FACE_CORNERS, MAX_OBJ_LINE_BYTES};
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
    /// `vn` normals.
    normals: Vec<Vec3>,
    /// Per triangle of a `v//vn` face: its corners' 1-based normal indices.
    normal_corners: Vec<[u32; 3]>,
    /// [`Part::excess`] for normal indices.
    normal_excess: i64,
    /// Whether the chunk has faces of plain indices, and of `v//vn` corners.
    plain_faces: bool,
    normal_faces: bool,
}

/// The mesh of `text`, or `None` when the careful reader must decide
/// (anything unusual, every error, and the limits of `crate::limits`).
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
    if parts.iter().any(|p| p.plain_faces) && parts.iter().any(|p| p.normal_faces) {
        return None; // corners with and without normals: read flat, carefully
    }
    let mut mesh = Mesh::default();
    let total_v: usize = parts.iter().map(|p| p.positions.len()).sum();
    let total_t: usize = parts.iter().map(|p| p.triangles.len()).sum();
    u32::try_from(total_v).ok()?;
    mesh.positions.reserve_exact(total_v);
    mesh.triangles.reserve_exact(total_t);
    let mut normals: Vec<Vec3> = Vec::new();
    let mut normal_indices: Vec<u32> = Vec::new();
    for p in parts {
        if p.excess > mesh.positions.len() as i64 || p.normal_excess > normals.len() as i64 {
            return None; // an index beyond the elements defined so far
        }
        mesh.positions.extend_from_slice(&p.positions);
        mesh.triangles
            .extend(p.triangles.iter().map(|t| t.map(|i| i - 1)));
        normals.extend_from_slice(&p.normals);
        normal_indices.extend(p.normal_corners.iter().flatten().map(|i| i - 1));
    }
    // A mesh with no faces is an error the careful reader words.
    if mesh.triangles.is_empty() {
        return None;
    }
    if !normal_indices.is_empty() {
        // Every face named normals: each position gets its own (a crease
        // repeats the position), as the careful reader does.
        let mut indices: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
        let (extra, vertex_normals) =
            super::obj::split_by_normal(&mesh.positions, &mut indices, &normal_indices, &normals)?;
        mesh.positions.extend(extra);
        mesh.normals = vertex_normals;
        for (t, c) in mesh.triangles.iter_mut().zip(indices.chunks_exact(3)) {
            *t = [c[0], c[1], c[2]];
        }
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
    let mut normal_corners: Vec<u32> = Vec::with_capacity(8);
    part.normal_excess = i64::MIN;
    for line in text.split('\n') {
        // Over-long lines and huge faces get the careful reader's positioned
        // refusal (issue 15's limits), before anything is split.
        if line.len() > MAX_OBJ_LINE_BYTES {
            return None;
        }
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
            Some("vn") => {
                // Only positions must be finite (a bad normal shades flat).
                let mut c = [0f32; 3];
                for x in &mut c {
                    *x = words.next()?.parse().ok()?;
                }
                if words.next().is_some() {
                    return None;
                }
                part.normals.push(Vec3::from(c));
            }
            Some("f") => {
                corners.clear();
                normal_corners.clear();
                let index = |w: &str| -> Option<u32> {
                    if !w.bytes().all(|b| b.is_ascii_digit()) {
                        return None; // slashes, signs: the careful reader
                    }
                    w.parse().ok().filter(|&i| i > 0)
                };
                for w in words {
                    match w.split_once("//") {
                        Some((v, n)) => {
                            corners.push(index(v)?);
                            normal_corners.push(index(n)?);
                        }
                        None => corners.push(index(w)?),
                    }
                }
                if corners.len() < 3 || corners.len() > MAX_FACE_CORNERS {
                    return None;
                }
                let with_normals = !normal_corners.is_empty();
                if with_normals && normal_corners.len() != corners.len() {
                    return None; // some corners with a normal, some without
                }
                part.plain_faces |= !with_normals;
                part.normal_faces |= with_normals;
                let defined = part.positions.len() as i64;
                let most = *corners.iter().max()? as i64;
                part.excess = part.excess.max(most - defined);
                for k in 2..corners.len() {
                    part.triangles
                        .push([corners[0], corners[k - 1], corners[k]]);
                }
                if with_normals {
                    let defined = part.normals.len() as i64;
                    let most = *normal_corners.iter().max()? as i64;
                    part.normal_excess = part.normal_excess.max(most - defined);
                    let n = &normal_corners;
                    for k in 2..n.len() {
                        part.normal_corners.push([n[0], n[k - 1], n[k]]);
                    }
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
    fn normals_as_the_careful_reader_reads_them() {
        // Corner positions and normals, whatever the vertex numbering.
        let shaded = |m: &Mesh| -> Vec<[(Vec3, Vec3); 3]> {
            (m.triangles.iter())
                .map(|t| t.map(|i| (m.positions[i as usize], m.normals[i as usize])))
                .collect()
        };
        for src in [
            // Normals out of order, a quad.
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvn 0 0.6 0.8\nvn 1 0 0\nvn 0 1 0\n\
             f 1//2 2//1 3//4 4//3\n",
            // A crease: the shared edge's positions get two normals.
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 1\nvn 0 0 1\nvn 1 0 0\n\
             f 1//1 2//1 3//1\nf 2//2 4//2 3//2\n",
            // A normal that is not finite shades flat (zero).
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 inf\nvn 0 0 1\nf 1//1 2//2 3//2\n",
        ] {
            let lean = parse(src).expect("lean reads it");
            let careful = parse_obj_careful(src.as_bytes(), Path::new("m.obj")).unwrap();
            assert_eq!(lean.positions.len(), careful.positions.len(), "{src:?}");
            assert_eq!(shaded(&lean), shaded(&careful), "{src:?}");
        }
        // Positions keep the file's numbering when no corner disagrees.
        let m = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 3//1 1//1 2//1\n").unwrap();
        assert_eq!(m.triangles, vec![[2, 0, 1]]);
        assert_eq!(m.normals, vec![Vec3::Z; 3]);
    }

    #[test]
    fn anything_unusual_is_left_to_the_careful_reader() {
        for src in [
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\nf 1 2 3\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1\n",
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
