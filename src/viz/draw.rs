//! Drawing on an RGB image: clipped line segments and simple marks. The
//! image is linear RGB, row 0 at the top, as [`crate::render::Frame`] holds it.

use crate::math::{Vec2, Vec3};

/// An RGB image to draw on: `width`×`height` pixels, row 0 at the top.
pub struct Canvas {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels, row-major, top row first.
    pub pixels: Vec<Vec3>,
}

impl Canvas {
    /// A canvas holding `pixels` (top row first).
    pub fn new(width: u32, height: u32, pixels: Vec<Vec3>) -> Self {
        assert_eq!(pixels.len(), (width * height) as usize);
        Self {
            width,
            height,
            pixels,
        }
    }

    /// Sets pixel `(x, y)` (y from the top) if it is inside the image.
    pub fn put(&mut self, x: i64, y: i64, c: Vec3) {
        if x >= 0 && y >= 0 && x < self.width as i64 && y < self.height as i64 {
            self.pixels[(y as u64 * self.width as u64 + x as u64) as usize] = c;
        }
    }

    /// Draws the segment from `a` to `b`, in continuous pixel coordinates
    /// with y *up* from the bottom edge (as [`crate::render::pixel_of_screen`]
    /// gives them), clipped to the image first so that a segment reaching
    /// far outside costs no more than one crossing the frame. `dash` > 0
    /// leaves gaps: `dash` pixels drawn, `dash` skipped.
    pub fn line(&mut self, a: Vec2, b: Vec2, c: Vec3, dash: u32) {
        let (w, h) = (self.width as f32, self.height as f32);
        let Some((a, b)) = clip(a, b, Vec2::ZERO, Vec2::new(w, h)) else {
            return;
        };
        let steps = (b - a).abs().max_element().ceil().max(1.0) as u32;
        for k in 0..=steps {
            if dash > 0 && (k / dash) % 2 == 1 {
                continue;
            }
            let p = a + (b - a) * (k as f32 / steps as f32);
            self.put(p.x.floor() as i64, (h - p.y).floor() as i64, c);
        }
    }

    /// A small cross centred on `p` (pixel coordinates, y up), for points
    /// such as where a shadow ray was blocked.
    pub fn cross(&mut self, p: Vec2, radius: i64, c: Vec3) {
        let (x, y) = (
            p.x.floor() as i64,
            (self.height as f32 - p.y).floor() as i64,
        );
        for d in -radius..=radius {
            self.put(x + d, y + d, c);
            self.put(x + d, y - d, c);
        }
    }

    /// Darkens the whole image towards black by `f` (0 = unchanged), so
    /// drawings over it stand out.
    pub fn dim(&mut self, f: f32) {
        for p in &mut self.pixels {
            *p *= 1.0 - f;
        }
    }
}

/// Liang–Barsky: the part of segment `a`–`b` inside the box `lo`..`hi`, or
/// `None` when it misses the box.
pub fn clip(a: Vec2, b: Vec2, lo: Vec2, hi: Vec2) -> Option<(Vec2, Vec2)> {
    if !(a.is_finite() && b.is_finite()) {
        return None;
    }
    let d = b - a;
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for (p, q) in [
        (-d.x, a.x - lo.x),
        (d.x, hi.x - a.x),
        (-d.y, a.y - lo.y),
        (d.y, hi.y - a.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
    }
    (t0 <= t1).then(|| (a + d * t0, a + d * t1))
}

/// A 3×5 pixel font for the characters scale bars and legends need: digits,
/// `.`, `-`, `+`, `e`, `x`, `%`, `/` and space. Each glyph is five rows of
/// three bits, most significant bit on the left.
fn glyph(c: char) -> [u8; 5] {
    match c {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '3' => [7, 1, 3, 1, 7],
        '4' => [5, 5, 7, 1, 1],
        '5' => [7, 4, 7, 1, 7],
        '6' => [7, 4, 7, 5, 7],
        '7' => [7, 1, 1, 2, 2],
        '8' => [7, 5, 7, 5, 7],
        '9' => [7, 5, 7, 1, 7],
        '.' => [0, 0, 0, 0, 2],
        '-' => [0, 0, 7, 0, 0],
        '+' => [0, 2, 7, 2, 0],
        'e' => [0, 7, 7, 4, 7],
        'x' => [0, 5, 2, 5, 0],
        '%' => [5, 1, 2, 4, 5],
        '/' => [1, 1, 2, 4, 4],
        _ => [0; 5],
    }
}

/// Width in pixels of `text` drawn at `scale` (glyphs 3 wide plus 1 apart).
pub fn text_width(text: &str, scale: u32) -> u32 {
    (text.chars().count() as u32 * 4).saturating_sub(1) * scale
}

impl Canvas {
    /// Writes `text` with its lower-left corner at `p` (pixel coordinates, y
    /// up), each font pixel `scale`×`scale`, on a black backing so it reads
    /// on any image.
    pub fn text(&mut self, p: Vec2, text: &str, c: Vec3, scale: u32) {
        let s = scale.max(1) as i64;
        let left = p.x.floor() as i64;
        let top = (self.height as f32 - p.y).floor() as i64 - 5 * s;
        let width = text_width(text, scale) as i64;
        for y in top - 1..top + 5 * s + 1 {
            for x in left - 1..left + width + 1 {
                self.put(x, y, Vec3::ZERO);
            }
        }
        for (k, ch) in text.chars().enumerate() {
            let g = glyph(ch);
            for (row, bits) in g.iter().enumerate() {
                for col in 0..3 {
                    if bits & (4 >> col) != 0 {
                        for dy in 0..s {
                            for dx in 0..s {
                                let x = left + (k as i64 * 4 + col) * s + dx;
                                self.put(x, top + row as i64 * s + dy, c);
                            }
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clipping_keeps_the_inside_part() {
        let (lo, hi) = (Vec2::ZERO, Vec2::new(10.0, 10.0));
        let (a, b) = clip(Vec2::new(-5.0, 5.0), Vec2::new(15.0, 5.0), lo, hi).unwrap();
        assert_eq!((a, b), (Vec2::new(0.0, 5.0), Vec2::new(10.0, 5.0)));
        assert!(clip(Vec2::new(-5.0, -5.0), Vec2::new(-1.0, 20.0), lo, hi).is_none());
        let inside = (Vec2::new(1.0, 2.0), Vec2::new(3.0, 4.0));
        assert_eq!(clip(inside.0, inside.1, lo, hi), Some(inside));
        assert!(clip(Vec2::new(f32::NAN, 0.0), Vec2::ONE, lo, hi).is_none());
    }

    #[test]
    fn a_line_across_the_frame_touches_both_edges() {
        let mut c = Canvas::new(8, 4, vec![Vec3::ZERO; 32]);
        c.line(Vec2::new(-100.0, 2.5), Vec2::new(100.0, 2.5), Vec3::ONE, 0);
        // y = 2.5 up from the bottom of a 4-high image is row 1 from the top.
        let row: Vec<bool> = (0..8).map(|x| c.pixels[8 + x] == Vec3::ONE).collect();
        assert!(row.iter().all(|&b| b), "{row:?}");
        assert_eq!(c.pixels.iter().filter(|p| **p == Vec3::ONE).count(), 8);
    }
}
