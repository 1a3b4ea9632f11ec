//! Splits scene text into words and braces, each with its 1-based position.
//!
//! The course's reader used `fscanf("%s")`, so tokens had to be separated by
//! whitespace; here braces are tokens of their own and may touch words
//! (`Material{diffuseColor 1 0 0}`). `#` starts a comment that runs to the end
//! of the line. Numbers are not recognised here: whether `6.837.obj` is a
//! number or a file name depends on where it stands, so the parser decides.

/// What a token is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    /// `{`
    Open,
    /// `}`
    Close,
    /// Any other run of non-space characters: keyword, number or file name.
    Word,
}

/// One token and where it starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Token<'a> {
    /// Brace or word.
    pub kind: Kind,
    /// The token's text.
    pub text: &'a str,
    /// 1-based line.
    pub line: usize,
    /// 1-based column, counted in characters.
    pub col: usize,
}

impl Token<'_> {
    /// True for a word equal to `s`.
    pub fn is(&self, s: &str) -> bool {
        self.kind == Kind::Word && self.text == s
    }
}

/// The tokens of `src`, and the position just after the last one (where
/// "found end of file" errors point, so the caret sits on a visible line).
pub(super) fn tokenize(src: &str) -> (Vec<Token<'_>>, (usize, usize)) {
    let mut tokens = Vec::new();
    let (mut line, mut col) = (1, 1);
    let mut end = (1, 1);
    // Start of the word being read: byte offset, line, column.
    let mut word: Option<(usize, usize, usize)> = None;
    let mut in_comment = false;
    for (i, c) in src.char_indices() {
        if in_comment {
            in_comment = c != '\n';
        } else if c.is_whitespace() || matches!(c, '{' | '}' | '#') {
            if let Some((start, l, cl)) = word.take() {
                tokens.push(Token {
                    kind: Kind::Word,
                    text: &src[start..i],
                    line: l,
                    col: cl,
                });
                end = (line, col);
            }
            let kind = match c {
                '{' => Some(Kind::Open),
                '}' => Some(Kind::Close),
                _ => None,
            };
            if let Some(kind) = kind {
                tokens.push(Token {
                    kind,
                    text: &src[i..i + 1],
                    line,
                    col,
                });
                end = (line, col + 1);
            }
            in_comment = c == '#';
        } else if word.is_none() {
            word = Some((i, line, col));
        }
        if c == '\n' {
            line += 1;
            col = 1;
        } else {
            col += 1;
        }
    }
    if let Some((start, l, cl)) = word {
        tokens.push(Token {
            kind: Kind::Word,
            text: &src[start..],
            line: l,
            col: cl,
        });
        end = (line, col);
    }
    (tokens, end)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texts(src: &str) -> Vec<&str> {
        tokenize(src).0.iter().map(|t| t.text).collect()
    }

    #[test]
    fn braces_may_touch_words() {
        assert_eq!(
            texts("Material{diffuseColor 1 0 0}"),
            ["Material", "{", "diffuseColor", "1", "0", "0", "}"]
        );
        assert_eq!(texts("A { b }"), ["A", "{", "b", "}"]);
    }

    #[test]
    fn positions_are_one_based_characters() {
        let (toks, end) = tokenize("é {\n\tx 6.837.obj }");
        let pos: Vec<_> = toks.iter().map(|t| (t.line, t.col)).collect();
        assert_eq!(pos, [(1, 1), (1, 3), (2, 2), (2, 4), (2, 14)]);
        assert_eq!(end, (2, 15));
    }

    #[test]
    fn comments_run_to_end_of_line() {
        assert_eq!(texts("a # b { c\nd#e\nf"), ["a", "d", "f"]);
    }

    #[test]
    fn empty_input_ends_at_one_one() {
        let (toks, end) = tokenize("  \n ");
        assert!(toks.is_empty());
        assert_eq!(end, (1, 1));
    }
}
