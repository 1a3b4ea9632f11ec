//! Wavefront OBJ meshes, read with `tobj` (polygons triangulated as fans).
//!
//! `tobj` reports errors without positions, and finds out-of-range face
//! indices only at the end of each object, so the text is first checked here
//! line by line: every `v`/`vt`/`vn`/`f`/`l` line that `tobj` would reject is
//! reported at its line and column. Anything `tobj` still rejects is reported
//! at the line it was reading when it stopped.
//!
//! Vertex normals (`vn`) are read when every face corner names one (`v//vn`
//! or `v/vt/vn`): the mesh is then shaded smooth with them, as with PLY and
//! glTF normals. A position whose corners name different normals (a crease)
//! is repeated once per further normal, with the same f32 coordinates, so
//! the surface stays watertight. A file mixing corners with and without
//! normals is read flat.

use super::diagnostic::{decode, quote, words, ParseError};
use crate::limits::{MAX_FACE_CORNERS, MAX_OBJ_LINE_BYTES};
use crate::math::Vec3;
use crate::scene::Mesh;
use std::collections::HashMap;
use std::io;
use std::path::Path;

/// Reads an OBJ file into a [`Mesh`] (positions and triangles only).
pub fn load_obj(path: &Path) -> Result<Mesh, ParseError> {
    load(path).map_err(|e| match e {
        LoadError::Io(e) => ParseError::unreadable(path, &e, "a readable OBJ file"),
        LoadError::Parse(e) => e,
    })
}

/// Parses OBJ text already in memory; `path` is only used in messages. The
/// same checks as [`load_obj`], without touching the disk.
pub fn load_obj_from_bytes(bytes: &[u8], path: &Path) -> Result<Mesh, ParseError> {
    parse_obj(bytes, path)
}

/// Why a mesh could not be loaded: the scene parser reports an unreadable
/// file at the `obj_file` token that named it, and bad contents in the OBJ.
pub(crate) enum LoadError {
    /// The file could not be read.
    Io(io::Error),
    /// The file's contents are not a valid OBJ mesh.
    Parse(ParseError),
}

/// Reads and parses an OBJ file.
pub(crate) fn load(path: &Path) -> Result<Mesh, LoadError> {
    let bytes = super::input::read_input(path).map_err(LoadError::Io)?;
    parse_obj(&bytes, path).map_err(LoadError::Parse)
}

/// Parses OBJ `bytes`; `path` is used in messages. Plain meshes (`v`/`f`
/// lines only) take the lean parallel reader (`obj_lean.rs`); anything else,
/// and every malformed file, the careful one below.
pub(crate) fn parse_obj(bytes: &[u8], path: &Path) -> Result<Mesh, ParseError> {
    let text = decode(bytes, path)?;
    if let Some(mesh) = super::obj_lean::parse(text) {
        return Ok(mesh);
    }
    parse_obj_careful(bytes, path)
}

/// The careful reader: every line checked with positions, then `tobj`.
pub(crate) fn parse_obj_careful(bytes: &[u8], path: &Path) -> Result<Mesh, ParseError> {
    let text = decode(bytes, path)?;
    let corners = check(text, path)?;
    // `tobj` turns a polyline of 3+ points into a face; a mesh has no lines,
    // so blank them (keeping the line count, for error positions).
    let without_lines;
    let bytes = if text.split('\n').any(|l| first_word(l) == Some("l")) {
        without_lines = text
            .split('\n')
            .map(|l| if first_word(l) == Some("l") { "" } else { l })
            .collect::<Vec<_>>()
            .join("\n");
        without_lines.as_bytes()
    } else {
        // Not `bytes`: `text` has no byte-order mark.
        text.as_bytes()
    };
    let options = tobj::LoadOptions {
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let mut reader = io::Cursor::new(bytes);
    // Materials are not needed: skip any `mtllib` without touching the disk.
    let loaded = tobj::load_obj_buf(&mut reader, &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    });
    let (models, _) = loaded.map_err(|e| {
        // `tobj` reads one line at a time, so the failing line is the one that
        // ends where the reader stopped.
        let stop = usize::try_from(reader.position())
            .unwrap_or(usize::MAX)
            .min(bytes.len());
        let line = bytes[..stop.saturating_sub(1)]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1;
        let line_text = text.split('\n').nth(line - 1).unwrap_or("").trim();
        let found = format!("{} ({e})", quote(line_text));
        ParseError::at(path, text, line, 1, "a valid OBJ line", found)
    })?;
    let mut mesh = Mesh::default();
    if models.iter().all(|m| m.mesh.indices.is_empty()) {
        // Any text file is a valid OBJ without faces; a mesh that draws
        // nothing is almost certainly the wrong file.
        let vertices = text
            .split('\n')
            .filter(|l| first_word(l) == Some("v"))
            .count();
        let found = match vertices {
            0 => "no vertices and no faces".to_owned(),
            n => format!("{n} vertices but no faces"),
        };
        return Err(ParseError::at(
            path,
            text,
            0,
            0,
            "an OBJ mesh with at least one face ('f' line)",
            found,
        ));
    }
    // The file's normals, when every face corner names one (`v//vn`,
    // `v/vt/vn`); a file mixing corners with and without them is read flat
    // (`--smooth` computes normals for it).
    let with_normals = corners.with_normal > 0 && corners.without_normal == 0;
    let too_many = || ParseError::at(path, text, 0, 0, "fewer than 2^32 vertices", "more");
    for model in models {
        let m = model.mesh;
        let base = u32::try_from(mesh.positions.len()).map_err(|_| too_many())?;
        let positions: Vec<Vec3> = (m.positions.chunks_exact(3))
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect();
        let mut indices = m.indices;
        if with_normals && m.normal_indices.len() == indices.len() {
            let normals: Vec<Vec3> = (m.normals.chunks_exact(3))
                .map(|c| Vec3::new(c[0], c[1], c[2]))
                .collect();
            let (extra, vertex_normals) =
                split_by_normal(&positions, &mut indices, &m.normal_indices, &normals)
                    .ok_or_else(too_many)?;
            mesh.normals.extend(vertex_normals);
            mesh.positions.extend(positions);
            mesh.positions.extend(extra);
        } else {
            mesh.positions.extend(positions);
        }
        u32::try_from(mesh.positions.len()).map_err(|_| too_many())?;
        mesh.triangles.extend(
            indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    if mesh.normals.len() != mesh.positions.len() {
        mesh.normals.clear();
    }
    Ok(mesh)
}

/// Gives each position the normal its corners name: `indices` (positions)
/// and `normal_indices` (normals) are per corner. A position whose corners
/// all name one normal keeps its index; one whose corners name several (a
/// crease) is repeated, once per further normal, after the `positions`
/// (returned, with the normal of every vertex: the file's own, or zero, "no
/// normal", for a position no face uses or a normal that is not finite).
/// `None` if an index is out of range or the vertices outgrow `u32`.
pub(super) fn split_by_normal(
    positions: &[Vec3],
    indices: &mut [u32],
    normal_indices: &[u32],
    normals: &[Vec3],
) -> Option<(Vec<Vec3>, Vec<Vec3>)> {
    const NONE: u32 = u32::MAX;
    let normal = |k: u32| {
        let n = *normals.get(k as usize)?;
        Some(if n.is_finite() { n } else { Vec3::ZERO })
    };
    let mut normal_of = vec![NONE; positions.len()];
    let mut extra = Vec::new();
    let mut extra_normals = Vec::new();
    let mut repeated: HashMap<(u32, u32), u32> = HashMap::new();
    for (p, &n) in indices.iter_mut().zip(normal_indices) {
        normal(n)?;
        let slot = normal_of.get_mut(*p as usize)?;
        if *slot == NONE {
            *slot = n;
        } else if *slot != n {
            let next = u32::try_from(positions.len() + extra.len()).ok()?;
            let i = *repeated.entry((*p, n)).or_insert(next);
            if i == next {
                extra.push(positions[*p as usize]);
                extra_normals.push(normal(n)?);
            }
            *p = i;
        }
    }
    let mut out: Vec<Vec3> = normal_of
        .iter()
        .map(|&n| {
            if n == NONE {
                Some(Vec3::ZERO)
            } else {
                normal(n)
            }
        })
        .collect::<Option<_>>()?;
    out.extend(extra_normals);
    Some((extra, out))
}

/// How many face corners name a normal and how many do not.
#[derive(Default)]
struct Corners {
    with_normal: usize,
    without_normal: usize,
}

/// Counts of the elements defined so far, which face indices refer to.
#[derive(Default)]
struct Counts {
    v: usize,
    vt: usize,
    vn: usize,
    /// Whether vertices carry colours; `tobj` needs all or none to.
    colored: Option<bool>,
}

/// Checks every line `tobj` could reject, with positions; counts the face
/// corners with and without a normal.
fn check(text: &str, path: &Path) -> Result<Corners, ParseError> {
    let mut counts = Counts::default();
    let mut corners = Corners::default();
    for (i, line) in text.split('\n').enumerate() {
        if line.len() > MAX_OBJ_LINE_BYTES {
            // Checked before the line is split: one face line of 100 MB used
            // to take gigabytes and abort the process.
            return Err(ParseError::at(
                path,
                text,
                i + 1,
                1,
                format!("a line of at most {MAX_OBJ_LINE_BYTES} bytes"),
                format!("a line of {} bytes", line.len()),
            ));
        }
        let words = words(line);
        let Some(&(_, first)) = words.first() else {
            continue;
        };
        let at = |col: usize, expected: String, found: String| {
            ParseError::at(path, text, i + 1, col, expected, found)
        };
        let end_col = line.trim_end().chars().count() + 1;
        let found = |k: usize| {
            words
                .get(k)
                .map_or_else(|| "end of line".to_owned(), |w| quote(w.1))
        };
        let col = |k: usize| words.get(k).map_or(end_col, |w| w.0);
        match first {
            "v" | "vt" | "vn" => {
                let needed = if first == "vt" { 2 } else { 3 };
                for k in 1..=needed {
                    match words.get(k).and_then(|w| w.1.parse::<f32>().ok()) {
                        // Only positions reach the renderer, so only they must be finite.
                        Some(x) if x.is_finite() || first != "v" => {}
                        Some(_) => return Err(at(col(k), "a finite number".into(), found(k))),
                        None => {
                            return Err(at(
                                col(k),
                                format!("{needed} numbers after '{first}'"),
                                found(k),
                            ))
                        }
                    }
                }
                match first {
                    "v" => check_vertex_tail(&words, &mut counts)
                        .map_err(|(k, e)| at(col(k), e, found(k)))?,
                    "vt" => counts.vt += 1,
                    _ => counts.vn += 1,
                }
            }
            "f" => {
                if words.len() == 1 {
                    return Err(at(
                        col(1),
                        format!("vertex indices after '{first}'"),
                        found(1),
                    ));
                }
                if let Some(&(c, _)) = words.get(MAX_FACE_CORNERS + 1) {
                    let found = format!("a face with {} corners", words.len() - 1);
                    return Err(at(
                        c,
                        format!("at most {MAX_FACE_CORNERS} corners in a face"),
                        found,
                    ));
                }
                for (k, &(c, w)) in words.iter().enumerate().skip(1) {
                    check_corner(w, &counts).map_err(|e| at(c, e, found(k)))?;
                    if w.split('/').nth(2).is_some_and(|n| !n.is_empty()) {
                        corners.with_normal += 1;
                    } else {
                        corners.without_normal += 1;
                    }
                }
            }
            _ => {}
        }
    }
    Ok(corners)
}

/// After `v x y z`: nothing, a `w` divisor, or an RGB colour, as `tobj` reads
/// them. Returns the word index and expectation of a problem.
fn check_vertex_tail(words: &[(usize, &str)], counts: &mut Counts) -> Result<(), (usize, String)> {
    let colored = match words.len() {
        4 => false,
        5 => {
            let w: f32 = words[4]
                .1
                .parse()
                .map_err(|_| (4, "a number (the w coordinate)".to_owned()))?;
            let finite =
                (1..4).all(|k| words[k].1.parse::<f32>().is_ok_and(|x| (x / w).is_finite()));
            if w == 0.0 || !finite {
                return Err((4, "a w coordinate giving finite x/w, y/w, z/w".to_owned()));
            }
            false
        }
        7 => {
            // `tobj` silently stops at a bad colour, leaving the colour list
            // out of step with the vertices.
            if let Some(k) = (4..7).find(|&k| words[k].1.parse::<f32>().is_err()) {
                return Err((k, "a number (a vertex colour)".to_owned()));
            }
            true
        }
        _ => {
            return Err((
                words.len().min(5),
                "'v x y z', 'v x y z w' or 'v x y z r g b'".to_owned(),
            ))
        }
    };
    if *counts.colored.get_or_insert(colored) != colored {
        return Err((4, "vertex colours on every vertex or on none".to_owned()));
    }
    counts.v += 1;
    Ok(())
}

/// One face corner `v`, `v/t`, `v//n` or `v/t/n`: 1-based, or negative to
/// count back from the last element defined; it must refer to an element
/// defined earlier in the file.
fn check_corner(word: &str, counts: &Counts) -> Result<(), String> {
    let parts: Vec<&str> = word.split('/').collect();
    if parts.len() > 3 || parts[0].is_empty() {
        return Err("a face corner 'v', 'v/vt', 'v//vn' or 'v/vt/vn'".to_owned());
    }
    let kinds = [
        ("vertex", counts.v),
        ("texture coordinate", counts.vt),
        ("normal", counts.vn),
    ];
    for (part, (what, n)) in parts.iter().zip(kinds) {
        if part.is_empty() {
            continue;
        }
        let i: i64 = part.parse().map_err(|_| format!("a {what} index"))?;
        let ok = if i > 0 {
            i.unsigned_abs() <= n as u64
        } else {
            i < 0 && i.unsigned_abs() <= n as u64
        };
        if !ok {
            return Err(match n {
                0 => format!("a {what} index, but no {what} is defined before this face"),
                _ => format!("a {what} index from 1 to {n} (or -1 to -{n})"),
            });
        }
    }
    Ok(())
}

/// The first word of a line.
fn first_word(line: &str) -> Option<&str> {
    line.split_whitespace().next()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(src: &str) -> Result<Mesh, ParseError> {
        parse_obj(src.as_bytes(), Path::new("m.obj"))
    }

    #[test]
    fn vertex_normals_are_read_per_position() {
        // A quad whose corners name their normals out of order.
        let m = parse(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
             vn 0 0 1\nvn 0 0.6 0.8\nvn 1 0 0\nvn 0 1 0\n\
             f 1//2 2//1 3//4 4//3\n",
        )
        .unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(
            m.normals,
            vec![Vec3::new(0.0, 0.6, 0.8), Vec3::Z, Vec3::Y, Vec3::X]
        );
        // `v/vt/vn` corners too; the same file without normals is flat.
        let m = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1\n");
        assert_eq!(m.unwrap().normals, vec![Vec3::Z; 3]);
        let m = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1 2 3\n").unwrap();
        assert!(m.normals.is_empty());
    }

    #[test]
    fn a_crease_repeats_its_positions() {
        // Two triangles folded along the edge 1-2, each with its own normal:
        // the edge's positions are repeated for the second normal.
        let m = parse(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 1\nvn 0 0 1\nvn 1 0 0\n\
             f 1//1 2//1 3//1\nf 2//2 4//2 3//2\n",
        )
        .unwrap();
        assert_eq!(m.positions.len(), 6);
        assert_eq!(m.triangles, vec![[0, 1, 2], [4, 3, 5]]);
        assert_eq!(m.positions[4], m.positions[1]);
        assert_eq!(m.positions[5], m.positions[2]);
        assert_eq!(m.normals[..3], [Vec3::Z; 3]);
        assert_eq!(m.normals[3..], [Vec3::X; 3]);
        // Corners with and without normals: flat.
        let m = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2 3//1\n").unwrap();
        assert!(m.normals.is_empty());
    }

    #[test]
    fn polygons_are_triangulated() {
        let m = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n").unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles.len(), 2);
    }

    #[test]
    fn slashes_negative_indices_and_groups() {
        let src = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\n\
                   o a\nf 1/1/1 2//1 3/1\no b\nf -3 -2 -1\n";
        let m = parse(src).unwrap();
        assert_eq!(m.triangles.len(), 2);
        for t in &m.triangles {
            assert!(t.iter().all(|&i| (i as usize) < m.positions.len()));
        }
    }

    #[test]
    fn out_of_range_index_is_located() {
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2  4\n").unwrap_err();
        assert_eq!((e.line, e.col), (4, 8));
        assert_eq!(e.found, "'4'");
        assert!(e.expected.contains("1 to 3"), "{e}");
        let e = parse("v 0 0 0\nf 0 1 1\n").unwrap_err();
        assert_eq!((e.line, e.col), (2, 3));
    }

    #[test]
    fn bad_vertices_are_located() {
        let e = parse("v 0 0 0\nv 1 nan 0\n").unwrap_err();
        assert_eq!(
            (e.line, e.col, e.expected.as_str()),
            (2, 5, "a finite number")
        );
        let e = parse("v 0 0\n").unwrap_err();
        assert_eq!((e.line, e.col, e.found.as_str()), (1, 6, "end of line"));
        let e = parse("v 1 1 1 0\n").unwrap_err();
        assert_eq!((e.line, e.col), (1, 9));
    }

    #[test]
    fn polylines_are_ignored() {
        let m = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2 3\nf 1 2 3\nl 1 2\n").unwrap();
        assert_eq!(m.triangles.len(), 1);
    }

    #[test]
    fn errors_only_tobj_finds_are_located_by_line() {
        let e = parse("l 1 2 3 4\nv 0 0 0\n\nusemtl\nf 1 1 1\n").unwrap_err();
        assert_eq!((e.line, e.col), (4, 1));
        assert!(e.found.starts_with("'usemtl'"), "{e}");
    }

    proptest::proptest! {
        /// Whatever the text, loading never panics, and a mesh it accepts has
        /// finite positions and in-range triangle indices.
        #[test]
        fn arbitrary_obj_text_is_safe(
            src in "((v|vt|vn|f|l|o|g|usemtl|mtllib|#)( [-+0-9./eEnaif]{1,5}){0,7}\n){0,16}"
        ) {
            if let Ok(m) = parse(&src) {
                proptest::prop_assert!(m.positions.iter().all(|p| p.is_finite()));
                let n = m.positions.len();
                proptest::prop_assert!(m.triangles.iter().flatten().all(|&i| (i as usize) < n));
            }
        }
    }

    #[test]
    fn a_file_without_faces_is_an_error_naming_it() {
        // Loaded silently as an empty mesh before issue 15.
        for (src, found) in [
            ("hello, world\n", "no vertices and no faces"),
            ("v 0 0 0\nv 1 0 0\n", "2 vertices but no faces"),
        ] {
            let e = parse(src).unwrap_err();
            let want = format!(
                "m.obj: expected an OBJ mesh with at least one face ('f' line), found {found}"
            );
            assert_eq!(e.to_string(), want);
        }
    }

    #[test]
    fn long_lines_and_huge_faces_are_refused_before_splitting() {
        let mut src = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\nf");
        src.push_str(&" 1".repeat(MAX_FACE_CORNERS + 1));
        let e = parse(&src).unwrap_err();
        assert_eq!((e.line, e.col), (4, 2 * MAX_FACE_CORNERS + 3));
        assert!(e.expected.contains("at most 65536 corners"), "{e}");
        src.push_str(&" 1".repeat(MAX_OBJ_LINE_BYTES / 2));
        let e = parse(&src).unwrap_err();
        assert_eq!((e.line, e.col), (4, 1));
        assert!(e.render().len() < 1000);
    }

    #[test]
    fn a_byte_order_mark_is_accepted() {
        let m = parse("\u{feff}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert_eq!(m.triangles.len(), 1);
    }

    #[test]
    fn binary_is_rejected() {
        assert!(parse_obj(b"v 0 0 0\n\xff\xfe", Path::new("m.obj")).is_err());
    }

    #[test]
    fn missing_file_is_an_io_error() {
        let e = load_obj(Path::new("no/such/file.obj")).unwrap_err();
        assert_eq!((e.line, e.col), (0, 0));
        assert!(e.to_string().contains("No such file or directory"), "{e}");
    }
}
