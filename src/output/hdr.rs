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

/// OpenEXR holding only the window `(x0, y0, w, h)` of a `fw`×`fh` frame:
/// the data window is the piece, the display window the whole frame (y down
/// from the top, as EXR counts), with `attrs` as text attributes.
pub(super) fn write_exr_window(
    path: &Path,
    (fw, fh): (u32, u32),
    (x0, y0, w, h): (u32, u32, u32, u32),
    pixels: &[Vec3],
    attrs: &[(&str, String)],
) -> Result<(), String> {
    use exr::prelude::*;
    let mut la = LayerAttributes {
        layer_position: Vec2(x0 as i32, y0 as i32),
        ..LayerAttributes::default()
    };
    for (k, v) in attrs {
        la.other.insert(
            Text::from(*k),
            exr::meta::attribute::AttributeValue::Text(Text::from(v.as_str())),
        );
    }
    let wu = w as usize;
    let layer = Layer::new(
        (wu, h as usize),
        la,
        Encoding::SMALL_LOSSLESS,
        SpecificChannels::rgb(|p: Vec2<usize>| {
            let c = pixels[p.y() * wu + p.x()];
            (c.x, c.y, c.z)
        }),
    );
    let mut image = Image::from_layer(layer);
    image.attributes.display_window =
        exr::meta::attribute::IntegerBounds::new((0, 0), (fw as usize, fh as usize));
    image.write().to_file(path).map_err(|e| e.to_string())
}

/// What [`crate::output::read_exr_window`] finds in a windowed EXR.
#[derive(Clone, Debug)]
pub struct ExrWindow {
    /// The display window's size (the whole frame).
    pub display: (u32, u32),
    /// The data window: `(x0, y0, w, h)`, y down from the top.
    pub window: (u32, u32, u32, u32),
    /// Text attributes of the layer.
    pub attributes: Vec<(String, String)>,
    /// The window's pixels, row-major, top row first.
    pub pixels: Vec<Vec3>,
}

/// Reads an EXR written by [`write_exr_window`] (or any RGB EXR whose data
/// window lies inside its display window starting at the origin).
pub(super) fn read_exr_window(path: &Path) -> Result<ExrWindow, String> {
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![Vec3::ZERO; res.width() * res.height()]),
        |(w, px): &mut (usize, Vec<Vec3>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * *w + pos.x()] = Vec3::new(r, g, b);
        },
    )
    .map_err(|e| format!("{}: {e}", path.display()))?;
    let d = image.attributes.display_window;
    let layer = &image.layer_data;
    let pos = layer.attributes.layer_position;
    let size = layer.size;
    if d.position.x() != 0 || d.position.y() != 0 || pos.x() < 0 || pos.y() < 0 {
        return Err(format!(
            "{}: the display window must start at 0, 0 and hold the data window",
            path.display()
        ));
    }
    let attributes = layer
        .attributes
        .other
        .iter()
        .filter_map(|(k, v)| match v {
            exr::meta::attribute::AttributeValue::Text(t) => Some((k.to_string(), t.to_string())),
            _ => None,
        })
        .collect();
    Ok(ExrWindow {
        display: (d.size.width() as u32, d.size.height() as u32),
        window: (
            pos.x() as u32,
            pos.y() as u32,
            size.width() as u32,
            size.height() as u32,
        ),
        attributes,
        pixels: layer.channel_data.pixels.1.clone(),
    })
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
