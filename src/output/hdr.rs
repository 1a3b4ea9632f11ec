//! High-dynamic-range images: linear RGB as 32-bit floats, unclamped.

use crate::math::Vec3;
use std::io::Write as _;
use std::path::Path;

/// OpenEXR with R, G, B channels of 32-bit floats (scan line 0 at the top,
/// as in the frame).
pub(super) fn write_exr(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[Vec3],
) -> Result<(), String> {
    let w = width as usize;
    exr::prelude::write_rgb_file(path, w, height as usize, |x, y| {
        let p = pixels[y * w + x];
        (p.x, p.y, p.z)
    })
    .map_err(|e| e.to_string())
}

/// Portable float map: the header `PF\n{w} {h}\n-1.0\n` (the negative scale
/// marks little-endian data), then RGB triples of little-endian `f32`, rows
/// from the *bottom* of the image to the top as the format requires.
pub(super) fn write_pfm(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[Vec3],
) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| e.to_string())?;
    let mut out = std::io::BufWriter::new(file);
    let io = |e: std::io::Error| e.to_string();
    write!(out, "PF\n{width} {height}\n-1.0\n").map_err(io)?;
    let w = width as usize;
    if w > 0 {
        for row in pixels.chunks_exact(w).rev() {
            for p in row {
                for c in p.to_array() {
                    out.write_all(&c.to_le_bytes()).map_err(io)?;
                }
            }
        }
    }
    out.into_inner()
        .map_err(|e| e.error().to_string())?
        .sync_all()
        .map_err(io)
}
