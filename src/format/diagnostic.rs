//! Positioned parse errors and their rustc-style rendering.

use crate::limits::{is_invisible, push_visible, SNIPPET_CHARS};
use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};

/// An error in a scene or mesh file, located at a 1-based line and column.
///
/// `Display` gives the one-line form `file:line:col: expected X, found Y`,
/// with the file's path in full as it was given;
/// [`ParseError::render`] adds the offending source line with a caret under it.
/// Errors that have no position (the file cannot be read at all) use line 0,
/// column 0, and are shown as `file: expected X, found Y`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub struct ParseError {
    /// The file the error is in (a mesh error names the OBJ file).
    pub file: PathBuf,
    /// 1-based line; 0 when the file could not be read.
    pub line: usize,
    /// 1-based column in characters; 0 when the file could not be read.
    pub col: usize,
    /// What the reader wanted at this point.
    pub expected: String,
    /// What it found: a quoted token such as `'Sphre'`, or `end of file`.
    pub found: String,
    /// The text of line `line` (or, for a long line, a window of it around
    /// `col`, with `…` where it was cut), when there is one.
    pub source_line: Option<String>,
    /// Columns of line `line` left out before `source_line`'s first column
    /// (counting a leading `…` as one): the caret goes under
    /// `col - snippet_offset`.
    pub snippet_offset: usize,
}

impl std::fmt::Display for ParseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // A file name may hold anything but `/` and NUL, newlines included.
        let mut file = String::new();
        for c in self.file.display().to_string().chars() {
            push_visible(&mut file, c);
        }
        write!(f, "{file}")?;
        if self.line > 0 {
            write!(f, ":{}:{}", self.line, self.col)?;
        }
        write!(f, ": expected {}, found {}", self.expected, self.found)
    }
}

impl ParseError {
    /// An error at `line:col` of `src`, the text of `file`.
    pub(crate) fn at(
        file: &Path,
        src: &str,
        line: usize,
        col: usize,
        expected: impl Into<String>,
        found: impl Into<String>,
    ) -> Self {
        let snippet = line
            .checked_sub(1)
            .and_then(|i| src.split('\n').nth(i))
            .map(|l| snippet(l.trim_end_matches('\r'), col));
        let (source_line, snippet_offset) = match snippet {
            Some((text, offset)) => (Some(text), offset),
            None => (None, 0),
        };
        Self {
            file: file.to_owned(),
            line,
            col,
            expected: expected.into(),
            found: found.into(),
            source_line,
            snippet_offset,
        }
    }

    /// The same error at line `line` (for readers that quote one line of
    /// a large file without splitting all of it).
    pub(crate) fn with_line(mut self, line: usize) -> Self {
        self.line = line;
        self
    }

    /// An error for a file that could not be read at all (no position).
    pub(crate) fn unreadable(file: &Path, err: &io::Error, expected: &str) -> Self {
        Self {
            file: file.to_owned(),
            line: 0,
            col: 0,
            expected: expected.to_owned(),
            // The path leads the message already, in full.
            found: format!("a file that cannot be read ({})", io_reason(err)),
            source_line: None,
            snippet_offset: 0,
        }
    }

    /// The message, then the source line with the offending token underlined,
    /// laid out like rustc's diagnostics.
    pub fn render(&self) -> String {
        // The first line is the plain `file:line:col: expected X, found Y`
        // that editors and scripts parse; the snippet below is for people.
        let mut out = format!("{self}\n");
        let gutter = " ".repeat(self.line.to_string().len());
        let Some(text) = self.source_line.as_deref().filter(|_| self.line > 0) else {
            return out;
        };
        let col = self.col.saturating_sub(self.snippet_offset).max(1);
        let width = token_width(text, col);
        // Invisible characters are shown escaped (`\u{feff}`), so the padding
        // under each one is as wide as its escape. Tabs are copied into the
        // padding so the caret lines up however the terminal expands them.
        let (mut shown, mut pad, mut carets) = (String::new(), String::new(), 0);
        for (i, c) in text.chars().enumerate() {
            let before = shown.chars().count();
            if c == '\t' {
                shown.push('\t');
            } else {
                push_visible(&mut shown, c);
            }
            let w = shown.chars().count() - before;
            if i + 1 < col {
                pad.extend(std::iter::repeat_n(if c == '\t' { '\t' } else { ' ' }, w));
            } else if i + 1 < col + width {
                carets += w;
            }
        }
        let _ = writeln!(out, "{gutter} |");
        let _ = writeln!(out, "{} | {shown}", self.line);
        let _ = writeln!(out, "{gutter} | {pad}{}", "^".repeat(carets.max(1)));
        out
    }
}

/// The part of `line` quoted under an error at 1-based `col`: the whole line
/// if it is short, else [`SNIPPET_CHARS`] characters around the column with
/// `…` marking each cut, and the number of columns cut before it (a 100 MB
/// token must not become 100 MB of stderr).
fn snippet(line: &str, col: usize) -> (String, usize) {
    // Stop counting once the line is known to be long.
    if line
        .chars()
        .nth(SNIPPET_CHARS + SNIPPET_CHARS / 2)
        .is_none()
    {
        return (line.to_owned(), 0);
    }
    let first = col.saturating_sub(1).saturating_sub(SNIPPET_CHARS / 3);
    let mut text = String::new();
    if first > 0 {
        text.push('…');
    }
    let mut rest = line.chars().skip(first);
    text.extend(rest.by_ref().take(SNIPPET_CHARS));
    if rest.next().is_some() {
        text.push('…');
    }
    // With a leading `…`, the line's column `first + 1` is the snippet's 2nd.
    (text, first.saturating_sub(1))
}

/// Width in characters of the token starting at 1-based column `col`, at least 1.
fn token_width(line: &str, col: usize) -> usize {
    let rest = line.chars().skip(col.saturating_sub(1));
    let mut n = 0;
    for c in rest {
        if c.is_whitespace() || ((c == '{' || c == '}') && n > 0) {
            break;
        }
        n += 1;
        if c == '{' || c == '}' {
            break;
        }
    }
    n.max(1)
}

/// A token as it appears in messages: single-quoted, control characters
/// escaped, long tokens shortened.
pub(crate) fn quote(text: &str) -> String {
    const MAX: usize = 40;
    let mut s = String::from("'");
    for (i, c) in text.chars().enumerate() {
        if i == MAX {
            s.push('…');
            break;
        }
        if c.is_control() || is_invisible(c) || c == '\'' || c == '\\' {
            s.extend(c.escape_default());
        } else {
            s.push(c);
        }
    }
    s.push('\'');
    s
}

/// An I/O error's reason without the "(os error N)" suffix.
pub(crate) fn io_reason(err: &io::Error) -> String {
    let s = err.to_string();
    match s.find(" (os error") {
        Some(i) => s[..i].to_owned(),
        None => s,
    }
}

/// The bytes as UTF-8 text, or an error at the first byte that is not,
/// which is how binary files are turned away. A UTF-8 byte-order mark, which
/// some editors write at the start of a file, is skipped (positions count
/// from the character after it).
pub(crate) fn decode<'a>(bytes: &'a [u8], file: &Path) -> Result<&'a str, ParseError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    std::str::from_utf8(bytes).map_err(|e| {
        let good = e.valid_up_to();
        // The valid prefix is UTF-8, so it can be searched for the position.
        let prefix = std::str::from_utf8(&bytes[..good]).unwrap_or_default();
        let line = prefix.matches('\n').count() + 1;
        let line_start = prefix.rfind('\n').map_or(0, |i| i + 1);
        let col = prefix[line_start..].chars().count() + 1;
        let lossy = String::from_utf8_lossy(bytes);
        ParseError::at(
            file,
            &lossy,
            line,
            col,
            "UTF-8 text",
            format!("byte 0x{:02x} (is this a binary file?)", bytes[good]),
        )
    })
}

/// The whitespace-separated words of a line with their 1-based columns.
pub(crate) fn words(line: &str) -> Vec<(usize, &str)> {
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

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> ParseError {
        let src = "Group {\n\tSphre {\n}";
        ParseError::at(Path::new("a.txt"), src, 2, 2, "an object", quote("Sphre"))
    }

    #[test]
    fn display_is_one_line() {
        assert_eq!(
            sample().to_string(),
            "a.txt:2:2: expected an object, found 'Sphre'"
        );
    }

    #[test]
    fn file_level_errors_have_no_position_and_the_full_path() {
        let long = Path::new("/a/very/long/folder/name/that/goes/on/and/on/for/a/while/scene.txt");
        let io = io::Error::from(io::ErrorKind::NotFound);
        let e = ParseError::unreadable(long, &io, "a readable scene file");
        let text = e.to_string();
        assert!(
            text.starts_with(&format!("{}: expected", long.display())),
            "{text}"
        );
        assert!(!text.contains(":0:0"), "{text}");
        assert_eq!(e.render(), format!("{text}\n"));
    }

    #[test]
    fn render_underlines_the_token() {
        let r = sample().render();
        assert!(r.contains("2 | \tSphre {"), "{r}");
        assert!(r.contains("  | \t^^^^^\n"), "{r}");
    }

    #[test]
    fn quote_escapes_and_shortens() {
        assert_eq!(quote("a\u{0}b"), "'a\\u{0}b'");
        assert!(quote(&"x".repeat(100)).ends_with("…'"));
    }

    #[test]
    fn a_byte_order_mark_is_skipped() {
        // Failed before issue 15: the mark was part of the first token.
        assert_eq!(
            decode(b"\xEF\xBB\xBFGroup", Path::new("b.txt")),
            Ok("Group")
        );
    }

    #[test]
    fn invisible_characters_are_escaped_and_the_caret_still_lines_up() {
        let src = "a\u{200b}b Sphre";
        let e = ParseError::at(
            Path::new("a\nb.txt"),
            src,
            1,
            5,
            "an object",
            quote("Sphre"),
        );
        let r = e.render();
        assert!(r.starts_with("a\\u{a}b.txt:1:5:"), "{r}");
        assert!(r.contains("1 | a\\u{200b}b Sphre\n"), "{r}");
        assert!(r.contains("  |            ^^^^^\n"), "{r}");
        assert_eq!(quote("\u{feff}Group"), "'\\u{feff}Group'");
    }

    #[test]
    fn a_long_line_is_quoted_in_a_window_with_the_caret_on_the_column() {
        // Before issue 15 the whole line was echoed (100 MB in, 200 MB out).
        let line = format!("{} Sphre {}", "x".repeat(1_000_000), "y".repeat(1_000_000));
        let e = ParseError::at(
            Path::new("a.txt"),
            &line,
            1,
            1_000_002,
            "an object",
            "'Sphre'",
        );
        let r = e.render();
        assert!(r.len() < 1000, "{} bytes", r.len());
        let lines: Vec<&str> = r.lines().collect();
        // Columns are characters: the snippet starts with a 3-byte `…`.
        let caret = lines[3].chars().position(|c| c == '^').unwrap();
        let quoted: String = lines[2].chars().skip(caret).take(6).collect();
        assert_eq!(quoted, "Sphre ", "{r}");
        assert_eq!(lines[3].chars().skip(caret).collect::<String>(), "^^^^^");
        assert!(lines[2].contains('…'));
    }

    #[test]
    fn decode_points_at_the_first_bad_byte() {
        let e = decode(b"ab\ncd\xffe", Path::new("b.txt")).unwrap_err();
        assert_eq!((e.line, e.col), (2, 3));
        assert!(e.found.contains("0xff"));
    }
}
