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

use super::diagnostic::{decode, quote, ParseError};
use crate::limits::MAX_FACE_CORNERS;
use crate::math::Vec3;
use crate::scene::Mesh;
use std::path::Path;

/// Longest header accepted, in bytes (real headers are a few hundred).
const MAX_HEADER_BYTES: usize = 1 << 16;

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

/// The scalar types of PLY, under both their old and their sized names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(word: &str) -> Option<Scalar> {
        Some(match word {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    /// How messages name the type.
    fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "an int8",
            Scalar::U8 => "a uint8",
            Scalar::I16 => "an int16",
            Scalar::U16 => "a uint16",
            Scalar::I32 => "an int32",
            Scalar::U32 => "a uint32",
            Scalar::F32 => "a float32",
            Scalar::F64 => "a float64",
        }
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The largest value of an integer type (a colour's full intensity).
    fn max(self) -> f32 {
        match self {
            Scalar::I8 => 127.0,
            Scalar::U8 => 255.0,
            Scalar::I16 => 32767.0,
            Scalar::U16 => 65535.0,
            Scalar::I32 => 2147483647.0,
            Scalar::U32 => 4294967295.0,
            Scalar::F32 | Scalar::F64 => 1.0,
        }
    }
}

/// One property of an element.
#[derive(Clone, Debug)]
struct Property {
    name: String,
    /// `Some(count type)` for a list.
    list: Option<Scalar>,
    ty: Scalar,
}

/// One element of the header and where it was declared.
#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
    /// Header line of its `element` line (for count errors).
    line: usize,
}

impl Element {
    /// Bytes one instance takes at least (binary: lists hold their count;
    /// ASCII: a digit and a separator per value).
    fn min_bytes(&self, ascii: bool) -> u64 {
        self.props
            .iter()
            .map(|p| match (ascii, p.list) {
                (true, _) => 2,
                (false, Some(c)) => c.size() as u64,
                (false, None) => p.ty.size() as u64,
            })
            .sum()
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    /// Binary; `true` for big-endian.
    Binary(bool),
}

/// What a property of the vertex or face element means to the mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    Skip,
    /// Position component 0..3.
    Pos(usize),
    /// Normal component.
    Normal(usize),
    /// Colour component.
    Color(usize),
    /// The face's corner list.
    Corners,
    /// A triangle strip's list.
    Strip,
}

struct Header<'a> {
    /// The whole file (for the source line of an ASCII body error).
    file: &'a [u8],
    format: Format,
    elements: Vec<Element>,
    /// Roles of each element's properties.
    roles: Vec<Vec<Role>>,
    body_start: usize,
    vertices: u64,
    has_normals: bool,
    has_colors: bool,
    /// The header text (for positioned errors).
    text: String,
}

impl<'a> Header<'a> {
    fn parse(bytes: &'a [u8], path: &Path) -> Result<Header<'a>, ParseError> {
        let end = find_end_header(bytes);
        let Some((text_end, body_start)) = end else {
            let head = &bytes[..bytes.len().min(MAX_HEADER_BYTES)];
            let text = String::from_utf8_lossy(head);
            let found = if !bytes.starts_with(b"ply") {
                format!("{} at the start", quote(text.lines().next().unwrap_or("")))
            } else if bytes.len() > MAX_HEADER_BYTES {
                format!("no 'end_header' in the first {MAX_HEADER_BYTES} bytes")
            } else {
                "no 'end_header' line".to_owned()
            };
            return Err(ParseError::at(
                path,
                &text,
                1,
                1,
                "a PLY header ('ply' ... 'end_header')",
                found,
            ));
        };
        let text = decode(&bytes[..text_end], path)?.to_owned();
        let err = |line: usize, col: usize, expected: &str, found: String| {
            ParseError::at(path, &text, line, col, expected, found)
        };
        let mut format = None;
        let mut elements: Vec<Element> = Vec::new();
        for (i, raw) in text.split('\n').enumerate() {
            let line = i + 1;
            let l = raw.trim_end_matches('\r');
            let words: Vec<(usize, &str)> = words(l);
            let word = |k: usize| words.get(k).map(|w| w.1);
            let col = |k: usize| words.get(k).map_or(l.chars().count() + 1, |w| w.0);
            let found = |k: usize| word(k).map_or_else(|| "end of line".to_owned(), quote);
            if line == 1 {
                if word(0) != Some("ply") || words.len() != 1 {
                    return Err(err(1, 1, "'ply' on the first line", quote(l)));
                }
                continue;
            }
            match word(0) {
                None | Some("comment") | Some("obj_info") => {}
                Some("format") => {
                    if format.is_some() {
                        return Err(err(line, 1, "one 'format' line", quote(l)));
                    }
                    format = Some(match word(1) {
                        Some("ascii") => Format::Ascii,
                        Some("binary_little_endian") => Format::Binary(false),
                        Some("binary_big_endian") => Format::Binary(true),
                        _ => {
                            return Err(err(
                                line,
                                col(1),
                                "'ascii', 'binary_little_endian' or 'binary_big_endian'",
                                found(1),
                            ))
                        }
                    });
                    if word(2) != Some("1.0") {
                        return Err(err(line, col(2), "version '1.0'", found(2)));
                    }
                }
                Some("element") => {
                    let name =
                        word(1).ok_or_else(|| err(line, col(1), "an element name", found(1)))?;
                    let count = word(2)
                        .and_then(|w| w.parse::<u64>().ok())
                        .ok_or_else(|| err(line, col(2), "an element count", found(2)))?;
                    if words.len() > 3 {
                        return Err(err(line, col(3), "end of line", found(3)));
                    }
                    elements.push(Element {
                        name: name.to_owned(),
                        count,
                        props: Vec::new(),
                        line,
                    });
                }
                Some("property") => {
                    let Some(el) = elements.last_mut() else {
                        return Err(err(
                            line,
                            1,
                            "an 'element' line before its properties",
                            quote(l),
                        ));
                    };
                    let scalar = |k: usize| {
                        word(k).and_then(Scalar::parse).ok_or_else(|| {
                            err(
                                line,
                                col(k),
                                "a PLY type ('uchar', 'int', 'float', ...)",
                                found(k),
                            )
                        })
                    };
                    let (list, ty, name_at) = if word(1) == Some("list") {
                        let c = scalar(2)?;
                        if c.is_float() {
                            return Err(err(
                                line,
                                col(2),
                                "an integer type for a list's count",
                                found(2),
                            ));
                        }
                        (Some(c), scalar(3)?, 4)
                    } else {
                        (None, scalar(1)?, 2)
                    };
                    let name = word(name_at).ok_or_else(|| {
                        err(line, col(name_at), "a property name", found(name_at))
                    })?;
                    if words.len() > name_at + 1 {
                        return Err(err(
                            line,
                            col(name_at + 1),
                            "end of line",
                            found(name_at + 1),
                        ));
                    }
                    el.props.push(Property {
                        name: name.to_owned(),
                        list,
                        ty,
                    });
                }
                Some(_) => {
                    return Err(err(
                        line,
                        col(0),
                        "'format', 'element', 'property', 'comment' or 'end_header'",
                        found(0),
                    ))
                }
            }
        }
        let format = format.ok_or_else(|| err(2, 1, "a 'format' line", "none".to_owned()))?;
        // Roles and required properties.
        let mut roles = Vec::with_capacity(elements.len());
        let (mut vertices, mut has_normals, mut has_colors) = (0, false, false);
        let mut saw_vertex = false;
        for el in &elements {
            let find = |n: &str| {
                el.props
                    .iter()
                    .position(|p| p.name == n && p.list.is_none())
            };
            let mut r = vec![Role::Skip; el.props.len()];
            match el.name.as_str() {
                "vertex" => {
                    if saw_vertex {
                        return Err(err(el.line, 1, "one 'vertex' element", "a second".into()));
                    }
                    saw_vertex = true;
                    vertices = el.count;
                    for (k, n) in ["x", "y", "z"].iter().enumerate() {
                        let i = find(n).ok_or_else(|| {
                            err(
                                el.line,
                                1,
                                "a vertex element with properties x, y and z",
                                format!("no scalar '{n}'"),
                            )
                        })?;
                        r[i] = Role::Pos(k);
                    }
                    let triple = |names: [&str; 3]| {
                        let found: Vec<_> = names.iter().filter_map(|n| find(n)).collect();
                        (found.len() == 3).then_some(found)
                    };
                    if let Some(ix) = triple(["nx", "ny", "nz"]) {
                        has_normals = true;
                        ix.iter()
                            .enumerate()
                            .for_each(|(k, &i)| r[i] = Role::Normal(k));
                    }
                    let colors = triple(["red", "green", "blue"])
                        .or_else(|| triple(["r", "g", "b"]))
                        .or_else(|| triple(["diffuse_red", "diffuse_green", "diffuse_blue"]));
                    if let Some(ix) = colors {
                        has_colors = true;
                        ix.iter()
                            .enumerate()
                            .for_each(|(k, &i)| r[i] = Role::Color(k));
                    }
                }
                "face" | "tristrips" => {
                    let i = el
                        .props
                        .iter()
                        .position(|p| {
                            p.list.is_some()
                                && (p.name == "vertex_indices" || p.name == "vertex_index")
                        })
                        .ok_or_else(|| {
                            err(
                                el.line,
                                1,
                                "a list property 'vertex_indices'",
                                format!("none in element '{}'", el.name),
                            )
                        })?;
                    if el.props[i].ty.is_float() {
                        return Err(err(
                            el.line,
                            1,
                            "integer vertex indices",
                            "a float list".into(),
                        ));
                    }
                    r[i] = if el.name == "face" {
                        Role::Corners
                    } else {
                        Role::Strip
                    };
                }
                _ => {}
            }
            roles.push(r);
        }
        if !saw_vertex {
            return Err(err(2, 1, "a 'vertex' element", "none".into()));
        }
        // Counts against the bytes left: nothing is reserved for a count the
        // file cannot hold.
        let left = (bytes.len() - body_start) as u64;
        let mut need: u64 = 0;
        for el in &elements {
            let min = el.min_bytes(format == Format::Ascii).max(1);
            need = need.saturating_add(el.count.saturating_mul(min));
            if need > left.saturating_add(1) {
                return Err(err(
                    el.line,
                    1,
                    &format!("element counts the file can hold ({left} bytes after the header)"),
                    format!(
                        "{} '{}' elements of at least {min} bytes each",
                        el.count, el.name
                    ),
                ));
            }
        }
        if vertices > u64::from(u32::MAX) {
            let line = elements
                .iter()
                .find(|e| e.name == "vertex")
                .map_or(1, |e| e.line);
            return Err(err(
                line,
                1,
                "fewer than 2^32 vertices",
                vertices.to_string(),
            ));
        }
        Ok(Header {
            file: bytes,
            format,
            elements,
            roles,
            body_start,
            vertices,
            has_normals,
            has_colors,
            text,
        })
    }
}

/// The end of the header text and the start of the body: just after the
/// newline ending the `end_header` line.
fn find_end_header(bytes: &[u8]) -> Option<(usize, usize)> {
    let limit = bytes.len().min(MAX_HEADER_BYTES);
    let mut start = 0;
    while start < limit {
        let nl = bytes[start..limit].iter().position(|&b| b == b'\n')? + start;
        let line = &bytes[start..nl];
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        if line.trim_ascii() == b"end_header" {
            return Some((start, nl + 1));
        }
        start = nl + 1;
    }
    None
}

/// The whitespace-separated words of a line with their 1-based columns.
fn words(line: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut start: Option<(usize, usize)> = None;
    for (col, (i, c)) in line.char_indices().enumerate() {
        match (c.is_whitespace(), start) {
            (true, Some((s, sc))) => {
                out.push((sc, &line[s..i]));
                start = None;
            }
            (false, None) => start = Some((i, col + 1)),
            _ => {}
        }
    }
    if let Some((s, sc)) = start {
        out.push((sc, &line[s..]));
    }
    out
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
struct Values {
    scalars: Vec<f64>,
    /// Corner indices of the face or strip list.
    list: Vec<i64>,
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

/// Reads an ASCII body: whitespace-separated values, an element per line
/// in practice (any layout is accepted; places are the values' own).
fn read_ascii(h: &Header, body: &[u8], path: &Path, sink: &mut Sink) -> Result<(), ParseError> {
    let first_line = h.text.split('\n').count() + 1;
    let mut tok = Tokens {
        bytes: body,
        pos: 0,
        line: first_line,
        line_start: 0,
    };
    let mut v = Values {
        scalars: Vec::new(),
        list: Vec::new(),
    };
    for (e, (el, roles)) in h.elements.iter().zip(&h.roles).enumerate() {
        v.scalars.clear();
        v.scalars.resize(el.props.len(), 0.0);
        for index in 0..el.count {
            let mut place = None;
            v.list.clear();
            for (k, p) in el.props.iter().enumerate() {
                let what = || format!("{} {index} of {}", el.name, el.count);
                let (at, word) = tok.next().ok_or_else(|| {
                    let (l, c) = tok.here();
                    placed(
                        path,
                        h,
                        Place::Text(l, c),
                        &format!("property '{}' of {}", p.name, what()),
                        "end of file".into(),
                    )
                })?;
                place.get_or_insert(at);
                let bad = |expected: String| {
                    placed(
                        path,
                        h,
                        Place::Text(at.0, at.1),
                        &expected,
                        quote_bytes(word),
                    )
                };
                match p.list {
                    None => {
                        v.scalars[k] = ascii_value(word, p.ty).ok_or_else(|| {
                            bad(format!(
                                "{} value (property '{}' of {})",
                                p.ty.name(),
                                p.name,
                                what()
                            ))
                        })?;
                    }
                    Some(ct) => {
                        let n = ascii_value(word, ct)
                            .filter(|&n| n >= 0.0 && n <= MAX_FACE_CORNERS as f64)
                            .ok_or_else(|| {
                                bad(format!(
                                    "a list length from 0 to {MAX_FACE_CORNERS} ({})",
                                    what()
                                ))
                            })? as usize;
                        let keep = roles[k] != Role::Skip;
                        for _ in 0..n {
                            let (at, w) = tok.next().ok_or_else(|| {
                                let (l, c) = tok.here();
                                placed(
                                    path,
                                    h,
                                    Place::Text(l, c),
                                    &format!("a list value of {}", what()),
                                    "end of file".into(),
                                )
                            })?;
                            let x = ascii_value(w, p.ty).ok_or_else(|| {
                                placed(
                                    path,
                                    h,
                                    Place::Text(at.0, at.1),
                                    &format!("{} list value ({})", p.ty.name(), what()),
                                    quote_bytes(w),
                                )
                            })?;
                            if keep {
                                v.list.push(x as i64);
                            }
                        }
                    }
                }
            }
            let (l, c) = place.unwrap_or((0, 0));
            emit(sink, h, e, &v, index, Place::Text(l, c), path)?;
        }
    }
    Ok(())
}

fn quote_bytes(b: &[u8]) -> String {
    quote(&String::from_utf8_lossy(b))
}

/// A value of type `ty` written in ASCII: integers must be integers in the
/// type's range; `float` parses as `f32` (as OBJ coordinates do, so the same
/// text gives the same bits), `double` as `f64`.
fn ascii_value(w: &[u8], ty: Scalar) -> Option<f64> {
    let s = std::str::from_utf8(w).ok()?;
    match ty {
        Scalar::F32 => s.parse::<f32>().ok().map(f64::from),
        Scalar::F64 => s.parse::<f64>().ok(),
        _ => {
            let i: i64 = s.parse().ok()?;
            let (lo, hi) = match ty {
                Scalar::I8 => (i8::MIN as i64, i8::MAX as i64),
                Scalar::U8 => (0, u8::MAX as i64),
                Scalar::I16 => (i16::MIN as i64, i16::MAX as i64),
                Scalar::U16 => (0, u16::MAX as i64),
                Scalar::I32 => (i32::MIN as i64, i32::MAX as i64),
                _ => (0, u32::MAX as i64),
            };
            (lo..=hi).contains(&i).then_some(i as f64)
        }
    }
}

/// Whitespace-separated words of an ASCII body with their line and column.
struct Tokens<'a> {
    bytes: &'a [u8],
    pos: usize,
    line: usize,
    line_start: usize,
}

impl<'a> Tokens<'a> {
    #[inline]
    fn next(&mut self) -> Option<((usize, usize), &'a [u8])> {
        let b = self.bytes;
        while self.pos < b.len() && b[self.pos].is_ascii_whitespace() {
            if b[self.pos] == b'\n' {
                self.line += 1;
                self.line_start = self.pos + 1;
            }
            self.pos += 1;
        }
        if self.pos >= b.len() {
            return None;
        }
        let start = self.pos;
        while self.pos < b.len() && !b[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        Some((
            (self.line, start - self.line_start + 1),
            &b[start..self.pos],
        ))
    }

    fn here(&self) -> (usize, usize) {
        (self.line, self.pos - self.line_start + 1)
    }
}

/// Reads a binary body.
fn read_binary(
    h: &Header,
    body: &[u8],
    big: bool,
    path: &Path,
    sink: &mut Sink,
) -> Result<(), ParseError> {
    let mut r = Reader {
        bytes: body,
        pos: 0,
        big,
    };
    let base = h.body_start;
    let mut v = Values {
        scalars: Vec::new(),
        list: Vec::new(),
    };
    for (e, (el, roles)) in h.elements.iter().zip(&h.roles).enumerate() {
        v.scalars.clear();
        v.scalars.resize(el.props.len(), 0.0);
        let all_skipped = roles.iter().all(|&r| r == Role::Skip);
        for index in 0..el.count {
            let start = r.pos;
            let truncated = |r: &Reader, p: &Property| {
                placed(
                    path,
                    h,
                    Place::Byte(base + r.pos),
                    &format!(
                        "property '{}' of {} {index} of {}",
                        p.name, el.name, el.count
                    ),
                    "end of file".into(),
                )
            };
            v.list.clear();
            for (k, p) in el.props.iter().enumerate() {
                match p.list {
                    None => {
                        v.scalars[k] = r.scalar(p.ty).ok_or_else(|| truncated(&r, p))?;
                    }
                    Some(ct) => {
                        let at = r.pos;
                        let n = r.scalar(ct).ok_or_else(|| truncated(&r, p))?;
                        if !(0.0..=MAX_FACE_CORNERS as f64).contains(&n) {
                            return Err(placed(
                                path,
                                h,
                                Place::Byte(base + at),
                                &format!(
                                    "a list length from 0 to {MAX_FACE_CORNERS} ({} {index})",
                                    el.name
                                ),
                                format!("{n}"),
                            ));
                        }
                        let n = n as usize;
                        if roles[k] == Role::Skip {
                            r.skip(n * p.ty.size()).ok_or_else(|| truncated(&r, p))?;
                        } else {
                            for _ in 0..n {
                                v.list
                                    .push(r.scalar(p.ty).ok_or_else(|| truncated(&r, p))? as i64);
                            }
                        }
                    }
                }
            }
            if !all_skipped {
                emit(sink, h, e, &v, index, Place::Byte(base + start), path)?;
            }
        }
    }
    Ok(())
}

/// A cursor over a binary body.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    big: bool,
}

impl Reader<'_> {
    #[inline]
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let s = self.bytes.get(self.pos..self.pos + N)?;
        self.pos += N;
        let mut a: [u8; N] = s.try_into().ok()?;
        if self.big {
            a.reverse();
        }
        Some(a)
    }

    #[inline]
    fn skip(&mut self, n: usize) -> Option<()> {
        let end = self.pos.checked_add(n)?;
        (end <= self.bytes.len()).then(|| self.pos = end)
    }

    /// One scalar as f64 (exact for every PLY type).
    #[inline]
    fn scalar(&mut self, ty: Scalar) -> Option<f64> {
        Some(match ty {
            Scalar::I8 => i8::from_le_bytes(self.take()?) as f64,
            Scalar::U8 => u8::from_le_bytes(self.take()?) as f64,
            Scalar::I16 => i16::from_le_bytes(self.take()?) as f64,
            Scalar::U16 => u16::from_le_bytes(self.take()?) as f64,
            Scalar::I32 => i32::from_le_bytes(self.take()?) as f64,
            Scalar::U32 => u32::from_le_bytes(self.take()?) as f64,
            Scalar::F32 => f32::from_le_bytes(self.take()?) as f64,
            Scalar::F64 => f64::from_le_bytes(self.take()?),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(src: &[u8]) -> Result<Mesh, ParseError> {
        parse_ply(src, Path::new("m.ply"))
    }

    /// A square (two fanned triangles) and a triangle, with normals, in
    /// ASCII.
    const ASCII: &str = "ply\nformat ascii 1.0\ncomment made by hand\n\
        element vertex 5\nproperty float x\nproperty float y\nproperty float z\n\
        property float nx\nproperty float ny\nproperty float nz\n\
        property uchar red\nproperty uchar green\nproperty uchar blue\n\
        element face 2\nproperty list uchar int vertex_indices\nend_header\n\
        0 0 0 0 0 1 255 0 0\n1 0 0 0 0 1 0 255 0\n1 1 0 0 0 1 0 0 255\n\
        0 1 0 0 0 1 0 0 0\n0.5 0.5 1e-3 0 0 1 1 2 3\n\
        4 0 1 2 3\n3 0 2 4\n";

    /// The same mesh in binary, little- or big-endian.
    fn binary(big: bool) -> Vec<u8> {
        let order = if big { "big" } else { "little" };
        let mut out = ASCII
            .replace("format ascii", &format!("format binary_{order}_endian"))
            .split("end_header\n")
            .next()
            .unwrap()
            .to_owned()
            .into_bytes();
        out.extend_from_slice(b"end_header\n");
        let f = |out: &mut Vec<u8>, x: f32| {
            out.extend_from_slice(&if big {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            })
        };
        let i = |out: &mut Vec<u8>, x: i32| {
            out.extend_from_slice(&if big {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            })
        };
        let body = ASCII.split("end_header\n").nth(1).unwrap();
        let lines: Vec<&str> = body.lines().collect();
        for l in &lines[..5] {
            let w: Vec<&str> = l.split(' ').collect();
            for x in &w[..6] {
                f(&mut out, x.parse().unwrap());
            }
            for x in &w[6..] {
                out.push(x.parse().unwrap());
            }
        }
        for l in &lines[5..] {
            let w: Vec<i32> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            out.push(w[0] as u8);
            for &x in &w[1..] {
                i(&mut out, x);
            }
        }
        out
    }

    #[test]
    fn ascii_and_both_binaries_read_the_same_mesh() {
        let a = parse(ASCII.as_bytes()).unwrap();
        assert_eq!(a.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 2, 4]]);
        assert_eq!(a.positions[4], Vec3::new(0.5, 0.5, 1e-3));
        assert_eq!(a.normals, vec![Vec3::Z; 5]);
        assert_eq!(a.colors[0], Vec3::X);
        assert_eq!(a.colors[4], Vec3::new(1.0, 2.0, 3.0) / 255.0);
        for big in [false, true] {
            assert_eq!(parse(&binary(big)).unwrap(), a, "big-endian: {big}");
        }
    }

    #[test]
    fn same_triangles_as_the_obj_reader() {
        let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1e-3\nf 1 2 3 4\nf 1 3 5\n";
        let o = super::super::obj::load_obj_from_bytes(obj.as_bytes(), Path::new("m.obj")).unwrap();
        let p = parse(ASCII.as_bytes()).unwrap();
        assert_eq!((o.positions, o.triangles), (p.positions, p.triangles));
    }

    #[test]
    fn other_elements_and_properties_are_skipped() {
        let mut src = b"ply\nformat binary_little_endian 1.0\nelement range_grid 2\n\
            property list uchar int vertex_indices\nelement vertex 3\nproperty double x\n\
            property double y\nproperty double z\nproperty float confidence\n\
            element face 1\nproperty uchar flags\nproperty list uint8 uint32 vertex_index\n\
            end_header\n"
            .to_vec();
        src.extend_from_slice(&[2, 1, 0, 0, 0, 2, 0, 0, 0, 0]);
        for p in [[0.0f64, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            for x in p {
                src.extend_from_slice(&x.to_le_bytes());
            }
            src.extend_from_slice(&0.5f32.to_le_bytes());
        }
        src.extend_from_slice(&[7, 3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0]);
        let m = parse(&src).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        assert_eq!(m.positions[2], Vec3::Y);
        assert!(m.normals.is_empty() && m.colors.is_empty());
    }

    #[test]
    fn triangle_strips_keep_one_orientation() {
        let src = "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\n\
            property float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n\
            0 0 0\n0 1 0\n1 0 0\n1 1 0\n2 0 0\n6 0 2 1 3 -1 4\n";
        let m = parse(src.as_bytes()).unwrap();
        assert_eq!(m.triangles, vec![[0, 2, 1], [1, 2, 3]]);
        // Both face the same way.
        let n = |t: [u32; 3]| {
            let p = t.map(|i| m.positions[i as usize]);
            (p[1] - p[0]).cross(p[2] - p[0]).z
        };
        assert!(n(m.triangles[0]) > 0.0 && n(m.triangles[1]) > 0.0);
    }

    #[test]
    fn ascii_errors_have_line_and_column() {
        let bad = ASCII.replace("1 1 0 0 0 1 0 0 255", "1 x 0 0 0 1 0 0 255");
        let e = parse(bad.as_bytes()).unwrap_err();
        assert_eq!((e.line, e.col), (19, 3), "{e}");
        assert!(e.to_string().contains("vertex 2 of 5"), "{e}");
        assert_eq!(e.source_line.as_deref(), Some("1 x 0 0 0 1 0 0 255"));
        let bad = ASCII.replace("3 0 2 4", "3 0 2 5");
        let e = parse(bad.as_bytes()).unwrap_err();
        assert_eq!((e.line, e.col), (23, 1), "{e}");
        assert!(
            e.to_string().contains("from 0 to 4, found 5 in face 1"),
            "{e}"
        );
        let e = parse(
            ASCII
                .replace("property float y\n", "property flot y\n")
                .as_bytes(),
        )
        .unwrap_err();
        assert_eq!((e.line, e.col), (6, 10), "{e}");
        let e = parse(&ASCII.as_bytes()[..ASCII.len() - 4]).unwrap_err();
        assert!(e.to_string().contains("end of file"), "{e}");
    }

    #[test]
    fn binary_errors_name_the_byte_offset() {
        let mut b = binary(false);
        let header = b.len() - (5 * 27 + 2 + 4 * 4 + 3 * 4);
        // Face 1's last index (the file's last 4 bytes) out of range.
        let n = b.len();
        b[n - 4..].copy_from_slice(&9i32.to_le_bytes());
        let e = parse(&b).unwrap_err();
        let face1 = header + 5 * 27 + 17;
        assert!(
            e.to_string()
                .contains(&format!("found 9 in face 1 at byte {face1}")),
            "{e}"
        );
        // Truncated: the last face loses its last byte.
        let b = binary(true);
        let e = parse(&b[..b.len() - 1]).unwrap_err();
        assert!(e.to_string().contains("face 1 of 2"), "{e}");
        assert!(
            e.to_string()
                .contains(&format!("end of file at byte {}", b.len() - 4)),
            "{e}"
        );
    }

    #[test]
    fn hostile_counts_are_refused_before_allocating() {
        for count in ["4294967296", "18446744073709551615", "1000000"] {
            let src = ASCII.replace("element vertex 5", &format!("element vertex {count}"));
            let e = parse(src.as_bytes()).unwrap_err();
            assert_eq!(e.line, 4, "{e}");
            assert!(e.expected.contains("counts the file can hold"), "{e}");
        }
        let src = ASCII.replace("element face 2", "element face 99999999999");
        assert_eq!(parse(src.as_bytes()).unwrap_err().line, 14);
        // A last face claiming 255 corners.
        let mut b = binary(false);
        let n = b.len();
        b[n - 13] = 255;
        let e = parse(&b).unwrap_err();
        assert!(e.to_string().contains("end of file"), "{e}");
    }

    #[test]
    fn not_a_ply_file() {
        for (src, found) in [
            ("hello\n", "'hello' at the start"),
            ("ply\nformat ascii 1.0\n", "no 'end_header' line"),
            ("", "'' at the start"),
        ] {
            let e = parse(src.as_bytes()).unwrap_err();
            assert_eq!(e.found, found, "{e}");
        }
        let e = parse(
            ASCII
                .replace("element face 2", "element face 0")
                .split("4 0 1")
                .next()
                .unwrap()
                .as_bytes(),
        )
        .unwrap_err();
        assert!(e.to_string().contains("5 vertices and no faces"), "{e}");
    }

    proptest::proptest! {
        /// Whatever the bytes after a plausible header, reading never panics,
        /// and an accepted mesh has finite positions and in-range indices.
        #[test]
        fn arbitrary_bodies_are_safe(
            body in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..200),
            big in proptest::prelude::any::<bool>(),
            ascii in proptest::prelude::any::<bool>(),
        ) {
            let head = if ascii { ASCII.to_owned() } else { String::from_utf8_lossy(&binary(big)).into_owned() };
            let mut src = head.split("end_header\n").next().unwrap().as_bytes().to_vec();
            src.extend_from_slice(b"end_header\n");
            src.extend_from_slice(&body);
            if let Ok(m) = parse(&src) {
                proptest::prop_assert!(m.positions.iter().all(|p| p.is_finite()));
                let n = m.positions.len();
                proptest::prop_assert!(m.triangles.iter().flatten().all(|&i| (i as usize) < n));
            }
        }
    }
}
