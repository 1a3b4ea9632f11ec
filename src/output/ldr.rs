//! 8-bit images. PNG and BMP go through the `image` crate as they are; PPM
//! through its PNM encoder with the binary `P6` subtype chosen explicitly (its
//! default for `.ppm` is PAM, `P7`, which most PPM readers reject); TGA is
//! written here, because the `image` crate's encoder writes run-length packets
//! that cross scanlines (forbidden by TGA 2.0, and rejected by Pillow) and
//! stores rows top-down, whereas the course's files are bottom-up.

use crate::math::Vec3;
use image::codecs::pnm::{PnmEncoder, PnmSubtype, SampleEncoding};
use image::{ExtendedColorType, ImageEncoder};
use std::io::{BufWriter, Write};
use std::path::Path;

/// 8-bit value of a linear channel: `int(c·255)` clamped to `[0, 255]`
/// (truncation, as the course's image code does); NaN becomes 0.
pub fn to_byte(c: f32) -> u8 {
    (c * 255.0).clamp(0.0, 255.0) as u8
}

/// How linear values become 8-bit ones.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Encoding {
    /// [`to_byte`]: the linear value truncated, the course's convention
    /// (what `raytracer` and its reference images use).
    #[default]
    Linear,
    /// [`to_byte_srgb`]: the sRGB transfer curve, rounded, and for PNG the
    /// file's `sRGB` chunk, which is what image viewers assume.
    Srgb,
}

/// 8-bit sRGB value of a linear channel: clamped to `[0, 1]`, encoded with
/// the sRGB curve (`12.92·c` up to 0.0031308, else `1.055·c^(1/2.4) − 0.055`)
/// and rounded; NaN becomes 0.
pub fn to_byte_srgb(c: f32) -> u8 {
    let c = if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) };
    let v = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (v * 255.0).round().clamp(0.0, 255.0) as u8
}

/// Encodes `pixels` (top row first) into `path` as `format`, in `encoding`.
pub(super) fn write(
    path: &Path,
    format: image::ImageFormat,
    (width, height): (u32, u32),
    pixels: &[Vec3],
    encoding: Encoding,
) -> Result<(), String> {
    let byte = match encoding {
        Encoding::Linear => to_byte,
        Encoding::Srgb => to_byte_srgb,
    };
    let bytes: Vec<u8> = pixels.iter().flat_map(|p| p.to_array().map(byte)).collect();
    if bytes.len() as u64 != 3 * u64::from(width) * u64::from(height) {
        return Err("pixel count does not match the image size".into());
    }
    let file = std::fs::File::create(path).map_err(|e| e.to_string())?;
    let mut out = BufWriter::new(file);
    match format {
        image::ImageFormat::Tga => write_tga(&mut out, width, height, &bytes),
        image::ImageFormat::Png if encoding == Encoding::Srgb => {
            let mut enc = png::Encoder::new(&mut out, width, height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            enc.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
            let mut w = enc.write_header().map_err(|e| e.to_string())?;
            w.write_image_data(&bytes).map_err(|e| e.to_string())?;
            w.finish().map_err(|e| e.to_string())
        }
        image::ImageFormat::Pnm => PnmEncoder::new(&mut out)
            .with_subtype(PnmSubtype::Pixmap(SampleEncoding::Binary))
            .write_image(&bytes, width, height, ExtendedColorType::Rgb8)
            .map_err(|e| e.to_string()),
        f => image::RgbImage::from_raw(width, height, bytes)
            .ok_or_else(|| "pixel count does not match the image size".to_string())?
            .write_to(&mut out, f)
            .map_err(|e| e.to_string()),
    }?;
    out.flush().map_err(|e| e.to_string())
}

/// TGA 2.0 type 2 (uncompressed true colour), 24 bits per pixel, BGR order,
/// origin at the bottom left (descriptor 0): the layout of the course's
/// `SaveTGA`, which every reader opens. `rgb` is top row first.
fn write_tga(out: &mut impl Write, width: u32, height: u32, rgb: &[u8]) -> Result<(), String> {
    let (w, h) = (
        u16::try_from(width)
            .map_err(|_| format!("TGA images are at most 65535 wide, not {width}"))?,
        u16::try_from(height)
            .map_err(|_| format!("TGA images are at most 65535 high, not {height}"))?,
    );
    let mut header = [0u8; 18];
    header[2] = 2; // uncompressed true colour
    header[12..14].copy_from_slice(&w.to_le_bytes());
    header[14..16].copy_from_slice(&h.to_le_bytes());
    header[16] = 24; // bits per pixel
    out.write_all(&header).map_err(|e| e.to_string())?;
    let row_len = 3 * width as usize;
    let mut row = vec![0u8; row_len];
    for src in rgb.chunks_exact(row_len).rev() {
        for (d, s) in row.chunks_exact_mut(3).zip(src.chunks_exact(3)) {
            d.copy_from_slice(&[s[2], s[1], s[0]]);
        }
        out.write_all(&row).map_err(|e| e.to_string())?;
    }
    Ok(())
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

    /// The sRGB curve at its ends, its linear toe and mid-grey, rounded.
    #[test]
    fn srgb_bytes_follow_the_curve_and_round() {
        assert_eq!(to_byte_srgb(0.0), 0);
        assert_eq!(to_byte_srgb(1.0), 255);
        assert_eq!(to_byte_srgb(7.0), 255);
        assert_eq!(to_byte_srgb(-1.0), 0);
        assert_eq!(to_byte_srgb(f32::NAN), 0);
        // The toe: 12.92 · 0.002 · 255 = 6.59.
        assert_eq!(to_byte_srgb(0.002), 7);
        // 1.055 · 0.5^(1/2.4) − 0.055 = 0.7354 → 187.5 (188); linear gives 127.
        assert_eq!(to_byte_srgb(0.5), 188);
        // 0.2140 is the linear value of sRGB 0.5 (127.5): rounds to 128.
        assert_eq!(to_byte_srgb(0.2140), 128);
    }
}
