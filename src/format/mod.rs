//! Readers for scene and mesh files.
//!
//! The MIT 6.837 scene format (`docs/scene-format.md`) becomes a
//! [`crate::scene::Scene`]; the meshes it names are Wavefront OBJ files, read
//! by [`obj::load_obj`]. Every error is a [`ParseError`] pointing at a line
//! and column; no input makes these readers panic.

mod diagnostic;
mod input;
mod mit6837;

pub mod obj;
mod obj_lean;

pub use diagnostic::ParseError;

use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// Reads a scene file; meshes are resolved relative to the scene file's folder.
/// A `.obj` file is read as a mesh and framed by [`Scene::for_mesh`].
///
/// Files are read with bounds (see [`crate::limits`]): devices and folders
/// are refused, and a file larger than the memory available allows is
/// refused before it is read.
pub fn load_scene(path: &Path) -> Result<Scene, ParseError> {
    load_scene_files(path).map(|(scene, _)| scene)
}

/// [`load_scene`], and every file it read: the scene file first, then the
/// meshes it names (so a render can refuse to overwrite any of them).
pub fn load_scene_files(path: &Path) -> Result<(Scene, Vec<PathBuf>), ParseError> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
    {
        return Ok((Scene::for_mesh(obj::load_obj(path)?), vec![path.into()]));
    }
    let bytes = input::read_input(path)
        .map_err(|e| ParseError::unreadable(path, &e, "a readable scene file"))?;
    let src = diagnostic::decode(&bytes, path)?;
    let (scene, mut files) = mit6837::parse_with_meshes(src, path)?;
    files.insert(0, path.into());
    Ok((scene, files))
}

/// Decides whether a scene may read a mesh file, before it is opened: given
/// the path the scene names (relative names joined to the scene's folder), it
/// returns the path to read, or an error whose text the parse error quotes at
/// the `obj_file` token. `glint serve` uses one to keep every file inside its
/// root and to refuse anything but regular files (a FIFO would block).
pub type MeshGate<'a> = &'a (dyn Fn(&Path) -> std::io::Result<PathBuf> + Sync);

/// [`load_scene_files`] for an MIT 6.837 scene file whose mesh files are
/// first passed through `gate`. The scene file itself is read as given: the
/// caller checks it.
pub fn load_scene_gated(path: &Path, gate: MeshGate) -> Result<(Scene, Vec<PathBuf>), ParseError> {
    let bytes = input::read_input(path)
        .map_err(|e| ParseError::unreadable(path, &e, "a readable scene file"))?;
    let src = diagnostic::decode(&bytes, path)?;
    let (scene, mut files) = mit6837::parse_gated(src, path, Some(gate))?;
    files.insert(0, path.into());
    Ok((scene, files))
}

/// The BOM-skipping UTF-8 decoding `load_scene` applies, for the parser's tests.
#[cfg(test)]
pub(crate) fn diagnostic_decode_for_tests(bytes: &[u8]) -> &str {
    diagnostic::decode(bytes, Path::new("t.txt")).expect("UTF-8")
}

/// Parses scene text; `file` is used in messages and to resolve `obj_file`
/// names (relative to its parent dir).
pub fn parse_scene(src: &str, file: &Path) -> Result<Scene, ParseError> {
    mit6837::parse(src, file)
}
