//! ASCII PLY bodies.

use super::header::{Header, Role, Scalar};
use super::{emit, placed, Place, Sink, Values};
use crate::format::diagnostic::{quote, ParseError};
use crate::limits::MAX_FACE_CORNERS;
use std::path::Path;

/// Reads an ASCII body: whitespace-separated values, an element per line
/// in practice (any layout is accepted; places are the values' own).
pub(super) fn read_ascii(
    h: &Header,
    body: &[u8],
    path: &Path,
    sink: &mut Sink,
) -> Result<(), ParseError> {
    let first_line = h.text.split('\n').count() + 1;
    let mut tok = Tokens {
        bytes: body,
        pos: 0,
        line: first_line,
        line_start: 0,
    };
    let mut v = Values::default();
    for (e, (el, roles)) in h.elements.iter().zip(&h.roles).enumerate() {
        v.start_element(el.props.len());
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
