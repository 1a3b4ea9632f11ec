//! Readers for scene and mesh files.
//!
//! The MIT 6.837 scene format (`docs/scene-format.md`) becomes a
//! [`crate::scene::Scene`]; the meshes it names are Wavefront OBJ files, read
//! by [`obj::load_obj`]. Every error is a [`ParseError`] pointing at a line
//! and column; no input makes these readers panic.

mod diagnostic;
mod input;
mod mit6837;

pub mod gltf;
pub mod obj;
mod obj_lean;
pub mod ply;

pub use diagnostic::ParseError;

use crate::scene::{self, Scene};
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
    if MeshKind::of(path) == Some(MeshKind::Gltf) {
        return gltf::load_gltf_files(path);
    }
    if let Some(kind) = MeshKind::of(path) {
        let mesh = load_mesh_file(path).map_err(|e| match e {
            obj::LoadError::Io(e) => ParseError::unreadable(path, &e, kind.expected()),
            obj::LoadError::Parse(e) => e,
        })?;
        return Ok((Scene::for_mesh(mesh), vec![path.into()]));
    }
    let bytes = input::read_input(path)
        .map_err(|e| ParseError::unreadable(path, &e, "a readable scene file"))?;
    let src = diagnostic::decode(&bytes, path)?;
    let (scene, mut files) = mit6837::parse_with_meshes(src, path)?;
    files.insert(0, path.into());
    Ok((scene, files))
}

/// The mesh formats, known by their file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshKind {
    /// Wavefront OBJ (`.obj`).
    Obj,
    /// Stanford PLY (`.ply`).
    Ply,
    /// glTF 2.0 (`.gltf`, `.glb`): a whole scene; as a mesh, its triangles
    /// with every node's transform applied.
    Gltf,
}

impl MeshKind {
    /// The format of `path` by its extension (any case), if it is a mesh.
    pub fn of(path: &Path) -> Option<MeshKind> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "obj" => Some(MeshKind::Obj),
            "ply" => Some(MeshKind::Ply),
            "gltf" | "glb" => Some(MeshKind::Gltf),
            _ => None,
        }
    }

    pub(crate) fn expected(self) -> &'static str {
        match self {
            MeshKind::Obj => "a readable OBJ file",
            MeshKind::Ply => "a readable PLY file",
            MeshKind::Gltf => "a readable glTF file",
        }
    }
}

/// Reads a mesh file: PLY by its extension, OBJ otherwise (the course's
/// `obj_file` names have always been read as OBJ, whatever they end in).
pub(crate) fn load_mesh_file(path: &Path) -> Result<scene::Mesh, obj::LoadError> {
    match MeshKind::of(path) {
        Some(MeshKind::Ply) => {
            let bytes = input::read_input(path).map_err(obj::LoadError::Io)?;
            ply::parse_ply(&bytes, path).map_err(obj::LoadError::Parse)
        }
        Some(MeshKind::Gltf) => gltf::load_gltf(path)
            .map(|s| gltf::flatten_to_mesh(&s))
            .map_err(obj::LoadError::Parse),
        _ => obj::load(path),
    }
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
