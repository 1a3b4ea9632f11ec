//! Whether two paths name the same file, however they are spelled: relative
//! or absolute, through `..` or symbolic links, or as two hard links.
//!
//! A render checks every file it will write against the files it reads and
//! against each other with this, before any work, so `-output scene.txt`
//! (any extension) can never destroy the scene.

use std::path::{Component, Path, PathBuf};

/// A path resolved as far as the file system allows, and the file's
/// device and inode when it exists.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FileIdentity {
    /// Absolute, with links in the folder part (and in the file itself,
    /// when it exists) resolved.
    pub resolved: PathBuf,
    /// `(device, inode)` of an existing file.
    pub inode: Option<(u64, u64)>,
}

impl FileIdentity {
    /// Resolves `path`: the whole path when the file exists (following a
    /// link to its target), else its folder plus its file name.
    pub fn of(path: &Path) -> FileIdentity {
        let resolved = std::fs::canonicalize(path).unwrap_or_else(|_| {
            let name = path.file_name().map(PathBuf::from).unwrap_or_default();
            let parent = match path.parent() {
                Some(p) if !p.as_os_str().is_empty() => p,
                _ => Path::new("."),
            };
            match std::fs::canonicalize(parent) {
                Ok(dir) => dir.join(name),
                Err(_) => lexical_absolute(path),
            }
        });
        FileIdentity {
            resolved,
            inode: inode(path),
        }
    }

    /// True if writing one would replace or change the other.
    pub fn same(&self, other: &FileIdentity) -> bool {
        self.resolved == other.resolved
            || matches!((self.inode, other.inode), (Some(a), Some(b)) if a == b)
    }
}

/// True if `a` and `b` name the same file (see [`FileIdentity`]).
pub fn same_file(a: &Path, b: &Path) -> bool {
    FileIdentity::of(a).same(&FileIdentity::of(b))
}

/// Refuses `output` if it is one of `inputs` (however spelled): writing it
/// would destroy an input.
pub fn check_not_input(output: &Path, inputs: &[PathBuf]) -> Result<(), super::OutputError> {
    let out = FileIdentity::of(output);
    match inputs.iter().find(|i| FileIdentity::of(i).same(&out)) {
        Some(input) => Err(super::OutputError::Refused {
            path: output.into(),
            reason: format!(
                "would overwrite the input file {}; choose another name",
                input.display()
            ),
        }),
        None => Ok(()),
    }
}

#[cfg(unix)]
fn inode(path: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
}

#[cfg(not(unix))]
fn inode(_: &Path) -> Option<(u64, u64)> {
    None
}

/// `path` made absolute and `.`/`..` removed without the file system (for a
/// folder that does not exist, where nothing can be written anyway).
fn lexical_absolute(path: &Path) -> PathBuf {
    let base = std::env::current_dir().unwrap_or_default();
    let mut out = PathBuf::new();
    for c in base.join(path).components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            other => out.push(other),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spellings_links_and_hard_links_of_one_file_are_the_same() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("sub")).unwrap();
        let scene = d.join("scene.txt");
        std::fs::write(&scene, "x").unwrap();
        assert!(same_file(&scene, &d.join("sub/../scene.txt")));
        assert!(same_file(&scene, &d.join("./scene.txt")));
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(&scene, d.join("link.png")).unwrap();
            assert!(same_file(&scene, &d.join("link.png")));
            std::os::unix::fs::symlink(d, d.join("sub/up")).unwrap();
            assert!(same_file(&scene, &d.join("sub/up/scene.txt")));
            std::fs::hard_link(&scene, d.join("hard.png")).unwrap();
            assert!(same_file(&scene, &d.join("hard.png")));
        }
        assert!(!same_file(&scene, &d.join("other.png")));
        // Two files not yet written, spelled differently.
        assert!(same_file(&d.join("new.png"), &d.join("sub/../new.png")));
        assert!(!same_file(&d.join("a.png"), &d.join("b.png")));
    }
}
