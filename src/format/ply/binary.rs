//! Binary PLY bodies, of either byte order.

use super::header::{Header, Property, Role, Scalar};
use super::{emit, placed, Place, Sink, Values};
use crate::format::diagnostic::ParseError;
use crate::limits::MAX_FACE_CORNERS;
use std::path::Path;

/// Reads a binary body.
pub(super) fn read_binary(
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
    let mut v = Values::default();
    for (e, (el, roles)) in h.elements.iter().zip(&h.roles).enumerate() {
        v.start_element(el.props.len());
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
