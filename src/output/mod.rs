//! Writing images: the format comes from the file extension, and the file is
//! written next to its destination and renamed into place, so an existing
//! image is never replaced by a partial one.
//!
//! - 8-bit formats (`.png`, `.tga`, `.ppm`, `.bmp`): `ldr`, clamped to
//!   `[0, 1]` and quantised like the course's image code.
//! - High dynamic range (`.exr`, `.pfm`): `hdr`, linear 32-bit floats,
//!   unclamped, so values above 1 survive for tone mapping later.

mod hdr;
mod ldr;

pub use ldr::to_byte;

use crate::math::Vec3;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why an image could not be written.
#[derive(Debug, Error)]
pub enum OutputError {
    /// The extension names no format glint writes.
    #[error("{path}: unsupported image format (supported: {exts})", exts = SUPPORTED_EXTENSIONS)]
    Format {
        /// The file.
        path: PathBuf,
    },
    /// The folder to write into does not exist.
    #[error("{path}: the directory {dir} does not exist")]
    NoDir {
        /// The file.
        path: PathBuf,
        /// Its folder.
        dir: PathBuf,
    },
    /// Encoding or file-system failure.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

/// The image formats glint writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    /// An 8-bit format the `image` crate encodes.
    Ldr(image::ImageFormat),
    /// OpenEXR, RGB 32-bit float.
    Exr,
    /// Portable float map, RGB 32-bit float.
    Pfm,
}

impl Format {
    /// The format named by `path`'s extension (case-insensitive).
    fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "exr" => return Some(Format::Exr),
            "pfm" => return Some(Format::Pfm),
            _ => {}
        }
        match image::ImageFormat::from_extension(&ext)? {
            f @ (image::ImageFormat::Png
            | image::ImageFormat::Tga
            | image::ImageFormat::Pnm
            | image::ImageFormat::Bmp) => Some(Format::Ldr(f)),
            _ => None,
        }
    }
}

/// The extensions glint writes, for messages and help texts.
pub const SUPPORTED_EXTENSIONS: &str = ".png, .tga, .ppm, .bmp, .exr, .pfm";

/// Checks, before any work, that an image could be written to `path`: its
/// extension names a supported format and its folder exists. A render calls
/// this first, so a typo in an output name costs nothing.
pub fn check_path(path: &Path) -> Result<(), OutputError> {
    Format::from_path(path).ok_or_else(|| OutputError::Format { path: path.into() })?;
    let dir = folder_of(path);
    if dir.is_dir() {
        Ok(())
    } else {
        Err(OutputError::NoDir {
            path: path.into(),
            dir,
        })
    }
}

/// The folder `path` is written into (`.` for a bare name).
fn folder_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Writes `pixels` (linear RGB, row-major, top row first) as the image format
/// `path`'s extension names.
pub fn write_rgb(path: &Path, width: u32, height: u32, pixels: &[Vec3]) -> Result<(), OutputError> {
    let format =
        Format::from_path(path).ok_or_else(|| OutputError::Format { path: path.into() })?;
    if pixels.len() as u64 != u64::from(width) * u64::from(height) {
        return Err(OutputError::Io {
            path: path.into(),
            message: "pixel count does not match the image size".into(),
        });
    }
    write_atomically(path, |tmp| match format {
        Format::Ldr(f) => ldr::write(tmp, f, width, height, pixels),
        Format::Exr => hdr::write_exr(tmp, width, height, pixels),
        Format::Pfm => hdr::write_pfm(tmp, width, height, pixels),
    })
}

/// Runs `write` on a temporary file in `path`'s folder, then renames it to
/// `path`; on any failure the temporary file is removed and `path` is left
/// as it was.
fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), OutputError> {
    let dir = folder_of(path);
    if !dir.is_dir() {
        return Err(OutputError::NoDir {
            path: path.into(),
            dir,
        });
    }
    let io = |message: String| OutputError::Io {
        path: path.into(),
        message,
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    let result = write(&tmp).and_then(|()| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
    result.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io(e)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_directory_is_an_error_and_unknown_format_too() {
        let e = write_rgb(Path::new("/no/such/dir/x.png"), 1, 1, &[Vec3::ONE]).unwrap_err();
        assert!(matches!(e, OutputError::NoDir { .. }));
        let e = write_rgb(Path::new("/no/such/dir/x.exr"), 1, 1, &[Vec3::ONE]).unwrap_err();
        assert!(matches!(e, OutputError::NoDir { .. }));
        let e = write_rgb(Path::new("x.xyz"), 1, 1, &[Vec3::ONE]).unwrap_err();
        assert!(matches!(e, OutputError::Format { .. }));
        let e = write_rgb(Path::new("x.jpg"), 1, 1, &[Vec3::ONE]).unwrap_err();
        assert!(matches!(e, OutputError::Format { .. }));
    }

    #[test]
    fn formats_by_extension() {
        assert_eq!(Format::from_path(Path::new("a.EXR")), Some(Format::Exr));
        assert_eq!(Format::from_path(Path::new("a.pfm")), Some(Format::Pfm));
        assert_eq!(
            Format::from_path(Path::new("a.png")),
            Some(Format::Ldr(image::ImageFormat::Png))
        );
        assert_eq!(Format::from_path(Path::new("noext")), None);
    }

    #[test]
    fn wrong_pixel_count_is_an_error() {
        let dir = std::env::temp_dir();
        for ext in ["png", "exr", "pfm"] {
            let p = dir.join(format!("glint-count-{}.{ext}", std::process::id()));
            let e = write_rgb(&p, 2, 2, &[Vec3::ONE]).unwrap_err();
            assert!(e.to_string().contains("pixel count"), "{e}");
            assert!(!p.exists());
        }
    }
}
