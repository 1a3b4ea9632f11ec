//! The MIT 6.837 (Fall 2004) scene format: a lexer that keeps positions, a
//! recursive-descent parser, and the semantic checks that the course's
//! `assert`-based reader left out. `docs/scene-format.md` describes the format
//! as implemented here.

mod cursor;
mod lexer;
mod materials;
mod objects;
mod parser;
mod transform;

#[cfg(test)]
mod tests;

use crate::format::ParseError;

/// Results of the parser's readers.
type Result<T> = std::result::Result<T, ParseError>;

pub(crate) use parser::{parse, parse_gated, parse_with_meshes};
