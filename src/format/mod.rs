//! Readers for scene and mesh files.
//!
//! The MIT 6.837 scene format (`docs/scene-format.md`) becomes a
//! [`crate::scene::Scene`]; the meshes it names are Wavefront OBJ files, read
//! by [`obj::load_obj`]. Every error is a [`ParseError`] pointing at a line
//! and column; no input makes these readers panic.

mod diagnostic;
mod mit6837;

pub mod obj;
mod obj_lean;

pub use diagnostic::ParseError;

use crate::scene::Scene;
use std::path::Path;

/// Reads a scene file; meshes are resolved relative to the scene file's folder.
/// A `.obj` file is read as a mesh and framed by [`Scene::for_mesh`].
pub fn load_scene(path: &Path) -> Result<Scene, ParseError> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
    {
        return Ok(Scene::for_mesh(obj::load_obj(path)?));
    }
    let bytes = std::fs::read(path)
        .map_err(|e| ParseError::unreadable(path, &e, "a readable scene file"))?;
    let src = diagnostic::decode(&bytes, path)?;
    parse_scene(src, path)
}

/// Parses scene text; `file` is used in messages and to resolve `obj_file`
/// names (relative to its parent dir).
pub fn parse_scene(src: &str, file: &Path) -> Result<Scene, ParseError> {
    mit6837::parse(src, file)
}
