//! 8-bit images through the `image` crate.

use crate::math::Vec3;
use std::path::Path;

/// 8-bit value of a linear channel: `int(c·255)` clamped to `[0, 255]`
/// (truncation, as the course's image code does); NaN becomes 0.
pub fn to_byte(c: f32) -> u8 {
    (c * 255.0).clamp(0.0, 255.0) as u8
}

/// Encodes `pixels` (top row first) into `path` as `format`.
pub(super) fn write(
    path: &Path,
    format: image::ImageFormat,
    width: u32,
    height: u32,
    pixels: &[Vec3],
) -> Result<(), String> {
    let bytes: Vec<u8> = pixels
        .iter()
        .flat_map(|p| p.to_array().map(to_byte))
        .collect();
    let img = image::RgbImage::from_raw(width, height, bytes)
        .ok_or("pixel count does not match the image size")?;
    img.save_with_format(path, format)
        .map_err(|e| e.to_string())
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
}
