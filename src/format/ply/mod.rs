//! Stanford PLY meshes (Turk, 1994): ASCII and binary of either byte order.
//!
//! What is read: the `vertex` element's `x y z` (any numeric type), its
//! `nx ny nz` when all three are present, its `red green blue` when all three
//! are (integers are divided by their type's maximum, so `uchar` 255 is 1);
//! faces from the `face` element's `vertex_indices` (or `vertex_index`) list,
//! polygons of any size fanned from their first corner as OBJ faces are; and
//! the `tristrips` element some scanners write (strips cut by `-1`, every
//! other triangle turned so all face the same way). Every other element and
//! property is skipped.
//!
//! Why by hand: the PLY crates read every property into a map of boxed
//! values per element, several times slower than the OBJ reader this one
//! must match. The format is small; this reader is fuzzed
//! (`fuzz/fuzz_targets/ply_loader.rs`).
//!
//! Errors name the file and the place: the line and column for the header
//! and ASCII bodies, the byte offset (and which element) for binary bodies.
//! Counts are checked against the bytes left before anything is allocated,
//! so a header claiming 2³² vertices in a small file is refused at once.

mod ascii;
mod binary;
mod header;
#[cfg(test)]
mod tests;

use super::diagnostic::ParseError;
use crate::math::Vec3;
use crate::scene::Mesh;
use ascii::read_ascii;
use binary::read_binary;
use header::{Format, Header, Role};
use std::path::Path;

/// Reads a PLY file into a [`Mesh`].
pub fn load_ply(path: &Path) -> Result<Mesh, ParseError> {
    let bytes = super::input::read_input(path)
        .map_err(|e| ParseError::unreadable(path, &e, "a readable PLY file"))?;
    parse_ply(&bytes, path)
}

/// Parses PLY bytes already in memory; `path` is only used in messages.
pub fn parse_ply(bytes: &[u8], path: &Path) -> Result<Mesh, ParseError> {
    let header = Header::parse(bytes, path)?;
    let body = &bytes[header.body_start..];
    let mut sink = Sink::new(&header);
    match header.format {
        Format::Ascii => read_ascii(&header, body, path, &mut sink)?,
        Format::Binary(big) => read_binary(&header, body, big, path, &mut sink)?,
    }
    sink.finish(&header, path)
}

/// Where the element being read is, for messages.
#[derive(Clone, Copy)]
enum Place {
    /// ASCII: line and column of the body (1-based, counted from the file's
    /// first line).
    Text(usize, usize),
    /// Binary: byte offset from the start of the file.
    Byte(usize),
}

/// Collects the mesh as elements are read.
struct Sink {
    mesh: Mesh,
    /// Per corner of each triangle: the place it was read (only for the
    /// first bad index, so only the place of each face is kept).
    pending: Option<(u64, Place, String)>,
    vertex_count: u64,
}

impl Sink {
    fn new(h: &Header) -> Sink {
        let mut mesh = Mesh::default();
        let n = h.vertices as usize;
        mesh.positions.reserve_exact(n);
        if h.has_normals {
            mesh.normals.reserve_exact(n);
        }
        if h.has_colors {
            mesh.colors.reserve_exact(n);
        }
        Sink {
            mesh,
            pending: None,
            vertex_count: h.vertices,
        }
    }

    /// Checks a corner index (the first bad one is kept with its place).
    #[inline]
    fn index(&mut self, i: i64, place: Place, what: &dyn Fn() -> String) -> Option<u32> {
        if i >= 0 && (i as u64) < self.vertex_count {
            Some(i as u32)
        } else {
            if self.pending.is_none() {
                self.pending = Some((i as u64, place, format!("{i} in {}", what())));
            }
            None
        }
    }

    fn finish(self, h: &Header, path: &Path) -> Result<Mesh, ParseError> {
        if let Some((_, place, found)) = self.pending {
            let expected = format!(
                "vertex indices from 0 to {}",
                self.vertex_count.saturating_sub(1)
            );
            return Err(placed(path, h, place, &expected, found));
        }
        if self.mesh.triangles.is_empty() {
            return Err(ParseError::at(
                path,
                &h.text,
                0,
                0,
                "a PLY mesh with at least one face",
                format!("{} vertices and no faces", self.mesh.positions.len()),
            ));
        }
        Ok(self.mesh)
    }
}

/// An error at `place`.
fn placed(path: &Path, h: &Header, place: Place, expected: &str, found: String) -> ParseError {
    match place {
        Place::Text(line, col) => {
            let text = h
                .file
                .split(|&b| b == b'\n')
                .nth(line.saturating_sub(1))
                .map(String::from_utf8_lossy)
                .unwrap_or_default();
            // `at` quotes line 1 of the text it is given.
            ParseError::at(path, &text, 1, col, expected, found).with_line(line)
        }
        Place::Byte(offset) => ParseError::at(
            path,
            "",
            0,
            0,
            expected,
            format!("{found} at byte {offset}"),
        ),
    }
}

/// One element instance's values as read: scalars by property, lists aside.
#[derive(Default)]
struct Values {
    scalars: Vec<f64>,
    /// Corner indices of the face or strip list.
    list: Vec<i64>,
}

impl Values {
    /// Room for the `n` scalar properties of an element, zeroed.
    fn start_element(&mut self, n: usize) {
        self.scalars.clear();
        self.scalars.resize(n, 0.0);
    }
}

/// Turns one read element instance into mesh data.
fn emit(
    sink: &mut Sink,
    h: &Header,
    e: usize,
    v: &Values,
    index: u64,
    place: Place,
    path: &Path,
) -> Result<(), ParseError> {
    let (el, roles) = (&h.elements[e], &h.roles[e]);
    match el.name.as_str() {
        "vertex" => {
            let (mut p, mut n, mut c) = ([0f32; 3], [0f32; 3], [0f32; 3]);
            for (k, role) in roles.iter().enumerate() {
                let x = v.scalars[k];
                match *role {
                    Role::Pos(i) => p[i] = x as f32,
                    Role::Normal(i) => n[i] = x as f32,
                    Role::Color(i) => c[i] = (x / el.props[k].ty.max() as f64) as f32,
                    _ => {}
                }
            }
            let p = Vec3::from(p);
            if !p.is_finite() {
                return Err(placed(
                    path,
                    h,
                    place,
                    "a finite vertex position",
                    format!("{p} (vertex {index})"),
                ));
            }
            sink.mesh.positions.push(p);
            if h.has_normals {
                let n = Vec3::from(n);
                sink.mesh
                    .normals
                    .push(if n.is_finite() { n } else { Vec3::ZERO });
            }
            if h.has_colors {
                sink.mesh.colors.push(Vec3::from(c));
            }
        }
        "face" => {
            let what = || format!("face {index}");
            let c = &v.list;
            if c.len() < 3 {
                return Err(placed(
                    path,
                    h,
                    place,
                    "a face of at least 3 corners",
                    format!("{} corners (face {index})", c.len()),
                ));
            }
            let first = sink.index(c[0], place, &what);
            let mut prev = sink.index(c[1], place, &what);
            for &k in &c[2..] {
                let cur = sink.index(k, place, &what);
                if let (Some(a), Some(b), Some(d)) = (first, prev, cur) {
                    sink.mesh.triangles.push([a, b, d]);
                }
                prev = cur;
            }
        }
        "tristrips" => {
            let what = || format!("triangle strip {index}");
            let mut run: Vec<u32> = Vec::new();
            for &k in &v.list {
                if k == -1 {
                    run.clear();
                    continue;
                }
                let Some(i) = sink.index(k, place, &what) else {
                    continue;
                };
                run.push(i);
                let m = run.len();
                if m >= 3 {
                    let (a, b, c) = (run[m - 3], run[m - 2], run[m - 1]);
                    // Every other triangle of a strip winds the other way.
                    let t = if m % 2 == 1 { [a, b, c] } else { [b, a, c] };
                    sink.mesh.triangles.push(t);
                }
            }
        }
        _ => {}
    }
    Ok(())
}
