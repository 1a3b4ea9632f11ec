//! Writing images: the format comes from the file extension, and the file is
//! written next to its destination and renamed into place, so an existing
//! image is never replaced by a partial one.
//!
//! - 8-bit formats (`.png`, `.tga`, `.ppm`, `.bmp`): `ldr`, clamped to
//!   `[0, 1]` and quantised like the course's image code.
//! - High dynamic range (`.exr`, `.pfm`): `hdr`, linear 32-bit floats,
//!   unclamped, so values above 1 survive for tone mapping later.

mod hdr;
mod identity;
mod ldr;

pub use hdr::ExrWindow;
pub use identity::{check_not_input, same_file, FileIdentity};
pub use ldr::{to_byte, to_byte_srgb, Encoding};

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
    /// The request cannot be written as asked (a size beyond the format's
    /// limits, a folder in the way, a file that is also an input...);
    /// found before any work.
    #[error("{path}: {reason}")]
    Refused {
        /// The file.
        path: PathBuf,
        /// Why.
        reason: String,
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
    /// The largest width and height this format can store, and a short name.
    fn max_side(self) -> (u32, &'static str) {
        match self {
            // TGA stores each side in 16 bits.
            Format::Ldr(image::ImageFormat::Tga) => (u16::MAX.into(), "TGA"),
            // PNG, BMP and EXR store sides as signed 32-bit integers.
            Format::Ldr(image::ImageFormat::Png) => (i32::MAX as u32, "PNG"),
            Format::Ldr(image::ImageFormat::Bmp) => (i32::MAX as u32, "BMP"),
            Format::Exr => (i32::MAX as u32, "OpenEXR"),
            Format::Ldr(_) => (u32::MAX, "PPM"),
            Format::Pfm => (u32::MAX, "PFM"),
        }
    }

    /// Why a `width`×`height` image does not fit this format, if it does not.
    fn size_problem(self, width: u32, height: u32) -> Option<String> {
        let (max, name) = self.max_side();
        if width > max || height > max {
            return Some(format!(
                "{width}x{height} is too large for {name}, which stores at most {max} pixels per side"
            ));
        }
        if self == Format::Ldr(image::ImageFormat::Bmp) {
            // A BMP's file size is a 32-bit field; rows are padded to 4 bytes.
            let row = (u64::from(width) * 3).div_ceil(4) * 4;
            if row * u64::from(height) + 54 > u64::from(u32::MAX) {
                return Some(format!(
                    "{width}x{height} is too large for BMP, whose files are at most 4 GiB"
                ));
            }
        }
        None
    }

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
    check_writable(path)
}

/// [`check_path`], and that a `width`×`height` image fits the format (a TGA
/// side is at most 65535 pixels): all checked before any work.
pub fn check_image(path: &Path, width: u32, height: u32) -> Result<(), OutputError> {
    check_path(path)?;
    let format =
        Format::from_path(path).ok_or_else(|| OutputError::Format { path: path.into() })?;
    match format.size_problem(width, height) {
        Some(reason) => Err(OutputError::Refused {
            path: path.into(),
            reason,
        }),
        None => Ok(()),
    }
}

/// Checks that any file could be written to `path` by renaming a temporary
/// file over it: its folder exists, and nothing but a file (or a link) is in
/// the way.
pub fn check_writable(path: &Path) -> Result<(), OutputError> {
    let dir = folder_of(path);
    if !dir.is_dir() {
        return Err(OutputError::NoDir {
            path: path.into(),
            dir,
        });
    }
    match std::fs::metadata(path) {
        Ok(m) if !m.is_file() => Err(OutputError::Refused {
            path: path.into(),
            reason: "exists and is not a regular file (a directory or a device);                      glint only replaces files"
                .into(),
        }),
        _ => Ok(()),
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
/// `path`'s extension names; 8-bit formats get the linear values truncated
/// ([`Encoding::Linear`]).
pub fn write_rgb(path: &Path, width: u32, height: u32, pixels: &[Vec3]) -> Result<(), OutputError> {
    write_rgb_as(path, width, height, pixels, Encoding::Linear)
}

/// [`write_rgb`] with the 8-bit formats in `encoding` (the float formats,
/// `.exr` and `.pfm`, always keep the linear values).
pub fn write_rgb_as(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[Vec3],
    encoding: Encoding,
) -> Result<(), OutputError> {
    let format =
        Format::from_path(path).ok_or_else(|| OutputError::Format { path: path.into() })?;
    if pixels.len() as u64 != u64::from(width) * u64::from(height) {
        return Err(OutputError::Io {
            path: path.into(),
            message: "pixel count does not match the image size".into(),
        });
    }
    write_atomically(path, |tmp| match format {
        Format::Ldr(f) => ldr::write(tmp, f, (width, height), pixels, encoding),
        Format::Exr => hdr::write_exr(tmp, width, height, pixels),
        Format::Pfm => hdr::write_pfm(tmp, width, height, pixels),
    })
}

/// Writes `bytes` to `path` atomically, like every image (for the
/// statistics JSON).
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    write_atomically(path, |tmp| {
        std::fs::write(tmp, bytes).map_err(|e| e.to_string())
    })
}

/// Writes the window `(x0, y0, w, h)` of a `frame`-sized image as OpenEXR
/// (data window = the window, display window = the frame), with `attrs` as
/// text attributes in its header; atomically, like [`write_rgb`].
pub fn write_exr_window(
    path: &Path,
    frame: (u32, u32),
    window: (u32, u32, u32, u32),
    pixels: &[Vec3],
    attrs: &[(&str, String)],
) -> Result<(), OutputError> {
    if pixels.len() as u64 != u64::from(window.2) * u64::from(window.3) {
        return Err(OutputError::Io {
            path: path.into(),
            message: "pixel count does not match the window".into(),
        });
    }
    write_atomically(path, |tmp| {
        hdr::write_exr_window(tmp, frame, window, pixels, attrs)
    })
}

/// Reads an EXR's display window, data window, text attributes and pixels
/// (what [`write_exr_window`] writes).
pub fn read_exr_window(path: &Path) -> Result<ExrWindow, String> {
    hdr::read_exr_window(path)
}

/// Runs `write` on a temporary file in `path`'s folder, then renames it to
/// `path`; on any failure the temporary file is removed and `path` is left
/// as it was.
///
/// The temporary name is short (`.glint` and 6 random characters), so any
/// name the file system accepts for `path` (up to 255 bytes) works; a name
/// derived from `path` would be longer than `path` itself.
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
    let mut builder = tempfile::Builder::new();
    builder.prefix(".glint").suffix(".tmp");
    // The default is 0600; 0666 lets the umask decide, as for any new file.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let tmp = builder.tempfile_in(&dir).map_err(|e| io(e.to_string()))?;
    // Dropping `tmp` on an error removes the file.
    write(tmp.path()).map_err(io)?;
    tmp.persist(path).map_err(|e| io(e.error.to_string()))?;
    Ok(())
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
    fn format_limits_are_checked_before_writing() {
        // Issue 15: a 70000-wide TGA rendered for seconds, then failed.
        let dir = tempfile::tempdir().unwrap();
        let tga = dir.path().join("wide.tga");
        let e = check_image(&tga, 70_000, 1).unwrap_err();
        assert!(
            e.to_string().contains("at most 65535 pixels per side"),
            "{e}"
        );
        assert!(check_image(&tga, 65_535, 1).is_ok());
        assert!(check_image(&dir.path().join("w.png"), 70_000, 1).is_ok());
        let e = check_image(&dir.path().join("w.bmp"), 40_000, 40_000).unwrap_err();
        assert!(e.to_string().contains("4 GiB"), "{e}");
        assert!(check_image(&dir.path().join("w.ppm"), u32::MAX, 1).is_ok());
    }

    #[test]
    fn a_folder_in_the_way_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.png");
        std::fs::create_dir(&p).unwrap();
        let e = check_path(&p).unwrap_err();
        assert!(matches!(e, OutputError::Refused { .. }), "{e}");
    }

    #[test]
    fn a_255_character_name_works_and_no_temporary_file_is_left() {
        // Issue 15: the temporary name `.NAME.PID.tmp` was longer than NAME.
        let dir = tempfile::tempdir().unwrap();
        let name = format!("{}.png", "n".repeat(251));
        assert_eq!(name.len(), 255);
        let p = dir.path().join(&name);
        write_rgb(&p, 2, 1, &[Vec3::ONE, Vec3::ZERO]).unwrap();
        let names: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, [std::ffi::OsString::from(name)]);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&p).unwrap().permissions().mode();
            assert_ne!(mode & 0o044, 0, "not readable by others: {mode:o}");
        }
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
