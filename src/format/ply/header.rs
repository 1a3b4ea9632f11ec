//! The PLY header: the format line, the elements and their properties, and
//! what each property means to the mesh.

use crate::format::diagnostic::{decode, quote, words, ParseError};
use std::path::Path;

/// Longest header accepted, in bytes (real headers are a few hundred).
const MAX_HEADER_BYTES: usize = 1 << 16;

/// The scalar types of PLY, under both their old and their sized names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Scalar {
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
    pub(super) fn parse(word: &str) -> Option<Scalar> {
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
    pub(super) fn name(self) -> &'static str {
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

    pub(super) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    pub(super) fn is_float(self) -> bool {
        matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The largest value of an integer type (a colour's full intensity).
    pub(super) fn max(self) -> f32 {
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
pub(super) struct Property {
    pub(super) name: String,
    /// `Some(count type)` for a list.
    pub(super) list: Option<Scalar>,
    pub(super) ty: Scalar,
}

/// One element of the header and where it was declared.
#[derive(Clone, Debug)]
pub(super) struct Element {
    pub(super) name: String,
    pub(super) count: u64,
    pub(super) props: Vec<Property>,
    /// Header line of its `element` line (for count errors).
    pub(super) line: usize,
}

impl Element {
    /// Bytes one instance takes at least (binary: lists hold their count;
    /// ASCII: a digit and a separator per value).
    pub(super) fn min_bytes(&self, ascii: bool) -> u64 {
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
pub(super) enum Format {
    Ascii,
    /// Binary; `true` for big-endian.
    Binary(bool),
}

/// What a property of the vertex or face element means to the mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Role {
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

pub(super) struct Header<'a> {
    /// The whole file (for the source line of an ASCII body error).
    pub(super) file: &'a [u8],
    pub(super) format: Format,
    pub(super) elements: Vec<Element>,
    /// Roles of each element's properties.
    pub(super) roles: Vec<Vec<Role>>,
    pub(super) body_start: usize,
    pub(super) vertices: u64,
    pub(super) has_normals: bool,
    pub(super) has_colors: bool,
    /// The header text (for positioned errors).
    pub(super) text: String,
}

impl<'a> Header<'a> {
    pub(super) fn parse(bytes: &'a [u8], path: &Path) -> Result<Header<'a>, ParseError> {
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
