//! The parser's state and its token-level readers: braces, keywords, numbers,
//! vectors, and blocks of named fields. Every reader reports failures at the
//! token it stopped on, so the block parsers never have to compute positions.

use super::lexer::{tokenize, Kind, Token};
use super::Result;
use crate::format::diagnostic::{quote, ParseError};
use crate::limits::MAX_COLOR;
use crate::math::Vec3;
use crate::scene::Mesh;
use glam::DVec3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Tokens with a read position, plus what the block parsers share.
pub(super) struct Parser<'a> {
    tokens: Vec<Token<'a>>,
    next: usize,
    /// Where "end of file" errors point.
    end: (usize, usize),
    src: &'a str,
    /// The scene file: used in messages and to resolve mesh names.
    pub file: &'a Path,
    /// The size of the material table, once the `Materials` block is read.
    pub material_count: Option<usize>,
    /// `MaterialIndex` uses read before the `Materials` block (blocks may come
    /// in any order), checked when the table's size is known.
    pub pending_indices: Vec<(usize, Token<'a>)>,
    /// Meshes loaded so far, so a file named twice is read once.
    pub meshes: HashMap<PathBuf, Arc<Mesh>>,
    /// Asked before each mesh file is opened (see [`crate::format::MeshGate`]).
    pub gate: Option<crate::format::MeshGate<'a>>,
    /// Current Group/Transform nesting, bounded so that hostile input cannot
    /// overflow the stack.
    pub depth: usize,
}

impl<'a> Parser<'a> {
    /// A parser at the start of `src`.
    pub fn new(src: &'a str, file: &'a Path) -> Self {
        let (tokens, end) = tokenize(src);
        Self {
            tokens,
            next: 0,
            end,
            src,
            file,
            material_count: None,
            pending_indices: Vec::new(),
            meshes: HashMap::new(),
            gate: None,
            depth: 0,
        }
    }

    /// The next token, consumed.
    pub fn next(&mut self) -> Option<Token<'a>> {
        let t = self.tokens.get(self.next).copied();
        self.next += usize::from(t.is_some());
        t
    }

    /// The next token, not consumed.
    pub fn peek(&self) -> Option<Token<'a>> {
        self.tokens.get(self.next).copied()
    }

    /// An error at `at` (or at the end of the file) naming the token found.
    pub fn error(&self, at: Option<Token<'a>>, expected: impl Into<String>) -> ParseError {
        let found = at.map_or_else(|| "end of file".to_owned(), |t| quote(t.text));
        self.error_found(at, expected, found)
    }

    /// An error at `at` (or at the end of the file) with a custom `found` text.
    pub fn error_found(
        &self,
        at: Option<Token<'a>>,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> ParseError {
        let (line, col) = at.map_or(self.end, |t| (t.line, t.col));
        ParseError::at(self.file, self.src, line, col, expected, found)
    }

    /// Reads the `{` that must follow the keyword `block`.
    pub fn open(&mut self, block: Token<'a>) -> Result<Token<'a>> {
        match self.next() {
            Some(t) if t.kind == Kind::Open => Ok(t),
            other => Err(self.error(other, format!("'{{' after {}", quote(block.text)))),
        }
    }

    /// Reads the `}` that ends `block`.
    pub fn close(&mut self, block: Token<'a>) -> Result<Token<'a>> {
        match self.next() {
            Some(t) if t.kind == Kind::Close => Ok(t),
            other => Err(self.error(other, closing(block))),
        }
    }

    /// Reads any word, such as a file name; `what` describes it for errors.
    pub fn word(&mut self, what: &str) -> Result<Token<'a>> {
        match self.next() {
            Some(t) if t.kind == Kind::Word => Ok(t),
            other => Err(self.error(other, what)),
        }
    }

    /// Reads a decimal number: `1`, `-2.5`, `0.`, `.5`, `1e-3`. Rust's float
    /// parser alone would also take `nan` and `inf`, which no scene means.
    pub fn number(&mut self) -> Result<(f32, Token<'a>)> {
        let t = self.next();
        let Some(tok) = t.filter(|t| t.kind == Kind::Word && is_decimal(t.text)) else {
            return Err(self.error(t, "a number"));
        };
        match tok.text.parse::<f32>() {
            Ok(v) if v.is_finite() => Ok((v, tok)),
            _ => Err(self.error(t, "a number within single-precision range")),
        }
    }

    /// [`Parser::number`] in double precision, for the numbers that place
    /// things in the world (the camera's centre, transforms, a sphere's or
    /// area light's centre, a triangle's vertices, a plane's offset, a point
    /// light's position, a quad light's corner): they keep every
    /// digit the file gives until the scene is moved into the camera-centred
    /// rendering space. The numbers accepted are exactly those
    /// [`Parser::number`] accepts.
    pub fn number64(&mut self) -> Result<(f64, Token<'a>)> {
        let (_, tok) = self.number()?;
        // A decimal that parses as a finite f32 parses as a finite f64.
        let v: f64 = tok
            .text
            .parse()
            .map_err(|_| self.error(Some(tok), "a number"))?;
        Ok((v, tok))
    }

    /// Reads three numbers; the tokens are kept for error messages.
    pub fn vec3(&mut self) -> Result<(Vec3, [Token<'a>; 3])> {
        let (x, tx) = self.number()?;
        let (y, ty) = self.number()?;
        let (z, tz) = self.number()?;
        Ok((Vec3::new(x, y, z), [tx, ty, tz]))
    }

    /// [`Parser::vec3`] in double precision (see [`Parser::number64`]).
    pub fn dvec3(&mut self) -> Result<(DVec3, [Token<'a>; 3])> {
        let (x, tx) = self.number64()?;
        let (y, ty) = self.number64()?;
        let (z, tz) = self.number64()?;
        Ok((DVec3::new(x, y, z), [tx, ty, tz]))
    }

    /// Reads three numbers each within `[0, max]` (a colour, or attenuation
    /// coefficients); `what` names one component for errors.
    pub fn vec3_within(&mut self, max: f32, what: &str) -> Result<Vec3> {
        let (v, toks) = self.vec3()?;
        for (x, tok) in v.to_array().into_iter().zip(toks) {
            if !(0.0..=max).contains(&x) {
                return Err(self.error(Some(tok), format!("{what} from 0 to {max}")));
            }
        }
        Ok(v)
    }

    /// Reads a colour: components from 0 to [`MAX_COLOR`].
    pub fn color(&mut self) -> Result<Vec3> {
        self.vec3_within(MAX_COLOR, "a colour component")
    }

    /// Reads an integer (optionally signed, no fraction or exponent).
    pub fn integer(&mut self) -> Result<(i64, Token<'a>)> {
        let t = self.next();
        let digits = |s: &str| {
            let s = s.strip_prefix(['+', '-']).unwrap_or(s);
            !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit())
        };
        t.filter(|t| t.kind == Kind::Word && digits(t.text))
            .and_then(|tok| Some((tok.text.parse::<i64>().ok()?, tok)))
            .ok_or_else(|| self.error(t, "an integer"))
    }

    /// Reads an integer that must be `>= 0`; `what` describes it for errors.
    pub fn non_negative(&mut self, what: &str) -> Result<(usize, Token<'a>)> {
        let (v, tok) = self.integer()?;
        usize::try_from(v)
            .map(|v| (v, tok))
            .map_err(|_| self.error(Some(tok), format!("{what} (0 or more)")))
    }

    /// Reads `keyword n`, the count that starts a Lights, Materials or Group block.
    pub fn count(&mut self, keyword: &str) -> Result<usize> {
        match self.next() {
            Some(t) if t.is(keyword) => {
                Ok(self.non_negative(&format!("a count after '{keyword}'"))?.0)
            }
            other => Err(self.error(other, format!("'{keyword}'"))),
        }
    }

    /// Reads `{ field value ... }` after the keyword `block`: fields in any
    /// order, each at most once, values read by `on_field`. Returns the `}`.
    pub fn fields(
        &mut self,
        block: Token<'a>,
        names: &[&str],
        on_field: impl FnMut(&mut Self, Token<'a>) -> Result<()>,
    ) -> Result<Token<'a>> {
        self.fields_with(block, names, &[], on_field)
    }

    /// Like [`Parser::fields`], but a field listed in `limits` may appear up
    /// to its given number of times (a texture's two `materialIndex` entries).
    pub fn fields_with(
        &mut self,
        block: Token<'a>,
        names: &[&str],
        limits: &[(&str, usize)],
        mut on_field: impl FnMut(&mut Self, Token<'a>) -> Result<()>,
    ) -> Result<Token<'a>> {
        self.open(block)?;
        let mut seen: Vec<&str> = Vec::new();
        loop {
            match self.next() {
                Some(t) if t.kind == Kind::Close => return Ok(t),
                Some(t) if t.kind == Kind::Word && names.contains(&t.text) => {
                    let max = limits.iter().find(|l| l.0 == t.text).map_or(1, |l| l.1);
                    let times = seen.iter().filter(|s| **s == t.text).count();
                    if times == max {
                        let expected = match max {
                            1 => format!("each {} field at most once", block.text),
                            _ => format!("at most {max} '{}' entries in {}", t.text, block.text),
                        };
                        let found = format!("a {} {}", ordinal(max + 1), quote(t.text));
                        return Err(self.error_found(Some(t), expected, found));
                    }
                    seen.push(t.text);
                    on_field(self, t)?;
                }
                other => {
                    let list: Vec<String> = names.iter().map(|n| format!("'{n}'")).collect();
                    let expected = format!("{}, or {}", list.join(", "), closing(block));
                    return Err(self.error(other, expected));
                }
            }
        }
    }

    /// The value of a required field, or an error at the block's `}`.
    pub fn require<T>(
        &self,
        v: Option<T>,
        close: Token<'a>,
        field: &str,
        block: Token<'a>,
    ) -> Result<T> {
        v.ok_or_else(|| self.error(Some(close), format!("'{field}' in {}", block.text)))
    }
}

/// "'}' closing Sphere from 4:5": what ends a block, with where it started.
pub(super) fn closing(block: Token<'_>) -> String {
    format!(
        "'}}' closing the {} at {}:{}",
        block.text, block.line, block.col
    )
}

/// "1 object", "2 objects".
pub(super) fn plural(n: usize, item: &str) -> String {
    format!("{n} {item}{}", if n == 1 { "" } else { "s" })
}

/// "1st", "2nd", "3rd", "11th", "22nd".
pub(super) fn ordinal(n: usize) -> String {
    let suffix = match (n % 10, n % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    format!("{n}{suffix}")
}

/// Three number tokens as one quoted text, for errors about a whole vector.
pub(super) fn vec_text(toks: &[Token<'_>; 3]) -> String {
    quote(&format!(
        "{} {} {}",
        toks[0].text, toks[1].text, toks[2].text
    ))
}

/// True for `[+-]digits[.digits][e[+-]digits]` with at least one mantissa digit.
fn is_decimal(s: &str) -> bool {
    let s = s.strip_prefix(['+', '-']).unwrap_or(s);
    let (mantissa, exponent) = match s.find(['e', 'E']) {
        Some(i) => (&s[..i], Some(&s[i + 1..])),
        None => (s, None),
    };
    let (int, frac) = mantissa.split_once('.').unwrap_or((mantissa, ""));
    let all_digits = |p: &str| p.bytes().all(|b| b.is_ascii_digit());
    let mantissa_ok = all_digits(int) && all_digits(frac) && !(int.is_empty() && frac.is_empty());
    let exponent_ok = exponent.is_none_or(|e| {
        let e = e.strip_prefix(['+', '-']).unwrap_or(e);
        !e.is_empty() && all_digits(e)
    });
    mantissa_ok && exponent_ok
}

#[cfg(test)]
mod tests {
    use super::*;

    fn num(s: &str) -> std::result::Result<f32, String> {
        let mut p = Parser::new(s, Path::new("t.txt"));
        p.number().map(|(v, _)| v).map_err(|e| e.to_string())
    }

    #[test]
    fn numbers_in_every_notation() {
        assert_eq!(num("3"), Ok(3.0));
        assert_eq!(num("-2.5"), Ok(-2.5));
        assert_eq!(num("0."), Ok(0.0));
        assert_eq!(num(".5"), Ok(0.5));
        assert_eq!(num("-1e-3"), Ok(-0.001));
        assert_eq!(num("+2E+2"), Ok(200.0));
    }

    #[test]
    fn nan_inf_and_junk_are_not_numbers() {
        for bad in [
            "nan", "NaN", "inf", "-inf", "infinity", ".", "1e", "e5", "1.2.3", "0x10", "--1", "1,5",
        ] {
            let e = num(bad).unwrap_err();
            assert!(e.contains("expected a number"), "{bad}: {e}");
        }
        assert!(num("1e39").unwrap_err().contains("single-precision"));
        assert!(num("").unwrap_err().ends_with("found end of file"));
    }

    #[test]
    fn ordinals() {
        let v: Vec<_> = [1, 2, 3, 4, 11, 12, 13, 21, 22, 103]
            .iter()
            .map(|&n| ordinal(n))
            .collect();
        assert_eq!(
            v,
            ["1st", "2nd", "3rd", "4th", "11th", "12th", "13th", "21st", "22nd", "103rd"]
        );
    }

    #[test]
    fn integers_reject_fractions() {
        let mut p = Parser::new("7 -3 2.0", Path::new("t.txt"));
        assert_eq!(p.integer().unwrap().0, 7);
        assert_eq!(p.integer().unwrap().0, -3);
        assert!(p.integer().is_err());
    }
}
