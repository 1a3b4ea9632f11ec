//! Writing images: the format comes from the file extension, and the file is
//! written next to its destination and renamed into place, so an existing
//! image is never replaced by a partial one.

use crate::math::Vec3;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why an image could not be written.
#[derive(Debug, Error)]
pub enum OutputError {
    /// The extension names no format glint writes.
    #[error("{path}: unsupported image format (use .png, .tga, .ppm or .bmp)")]
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

/// 8-bit value of a linear channel: `int(c·255)` clamped to `[0, 255]`
/// (truncation, as the course's image code does); NaN becomes 0.
pub fn to_byte(c: f32) -> u8 {
    (c * 255.0).clamp(0.0, 255.0) as u8
}

/// Writes `pixels` (row-major, top row first) as an 8-bit RGB image.
pub fn write_rgb(path: &Path, width: u32, height: u32, pixels: &[Vec3]) -> Result<(), OutputError> {
    let format = image::ImageFormat::from_path(path)
        .map_err(|_| OutputError::Format { path: path.into() })?;
    if !matches!(
        format,
        image::ImageFormat::Png
            | image::ImageFormat::Tga
            | image::ImageFormat::Pnm
            | image::ImageFormat::Bmp
    ) {
        return Err(OutputError::Format { path: path.into() });
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(OutputError::NoDir {
            path: path.into(),
            dir,
        });
    }
    let bytes: Vec<u8> = pixels
        .iter()
        .flat_map(|p| p.to_array().map(to_byte))
        .collect();
    let img = image::RgbImage::from_raw(width, height, bytes).ok_or_else(|| OutputError::Io {
        path: path.into(),
        message: "pixel count does not match the image size".into(),
    })?;
    let io = |e: &dyn std::fmt::Display| OutputError::Io {
        path: path.into(),
        message: e.to_string(),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    img.save_with_format(&tmp, format).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io(&e)
    })?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io(&e)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bytes_truncate_and_clamp() {
        assert_eq!(to_byte(1.0), 255);
        assert_eq!(to_byte(0.999), 254);
        assert_eq!(to_byte(-1.0), 0);
        assert_eq!(to_byte(7.0), 255);
        assert_eq!(to_byte(f32::NAN), 0);
    }

    #[test]
    fn missing_directory_is_an_error_and_unknown_format_too() {
        let e = write_rgb(Path::new("/no/such/dir/x.png"), 1, 1, &[Vec3::ONE]).unwrap_err();
        assert!(matches!(e, OutputError::NoDir { .. }));
        let e = write_rgb(Path::new("x.xyz"), 1, 1, &[Vec3::ONE]).unwrap_err();
        assert!(matches!(e, OutputError::Format { .. }));
    }
}
