//! Pictures that explain sampling: the course's sample and filter views
//! (`-render_samples`, `-render_filter`, `../shared/scenes/6837/NOTES.md`
//! A7) and a heat map of camera rays per pixel with a scale bar.
//!
//! Every view returns an [`Image`]: linear RGB pixels, row 0 at the top.

use super::{Filter, SampleRecord};
use crate::math::Vec3;

/// A picture: `width`×`height` linear RGB pixels, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// The pixels.
    pub pixels: Vec<Vec3>,
}

impl Image {
    fn new(width: u32, height: u32, fill: Vec3) -> Self {
        Self {
            width,
            height,
            pixels: vec![fill; width as usize * height as usize],
        }
    }

    /// Sets pixel `(x, y)` counted from the bottom-left (the course's image
    /// convention); outside the image is ignored.
    fn put_up(&mut self, x: u32, y: u32, c: Vec3) {
        if x < self.width && y < self.height {
            let row = self.height - 1 - y;
            self.pixels[(row * self.width + x) as usize] = c;
        }
    }

    /// Sets pixel `(x, row)` counted from the top-left.
    fn put(&mut self, x: u32, row: u32, c: Vec3) {
        if x < self.width && row < self.height {
            self.pixels[(row * self.width + x) as usize] = c;
        }
    }
}

/// The course's `-render_samples FILE zoom`: a `(w·z)×(h·z)` image whose
/// pixel blocks form a checkerboard (grey 0.2 where `i + j` is even, else
/// black), each sample drawn as one pixel in its own colour at
/// `(⌊(i + sx)·z⌋, ⌊(j + sy)·z⌋)`.
pub fn samples_view(w: u32, h: u32, zoom: u32, samples: &[SampleRecord]) -> Image {
    let z = zoom.max(1);
    let mut img = Image::new(w * z, h * z, Vec3::ZERO);
    for j in 0..h {
        for i in 0..w {
            if (i + j) % 2 == 0 {
                for y in j * z..(j + 1) * z {
                    for x in i * z..(i + 1) * z {
                        img.put_up(x, y, Vec3::splat(0.2));
                    }
                }
            }
        }
    }
    for s in samples {
        let (i, j) = s.pixel;
        let x = ((i as f32 + s.offset.x) * z as f32) as u32;
        let y = ((j as f32 + s.offset.y) * z as f32) as u32;
        img.put_up(x, y, s.color);
    }
    img
}

/// The course's `-render_filter FILE zoom`: a `(w·z+1)×(h·z+1)` image on a
/// dark blue `(0, 0, 0.5)` background; for the pixels within the filter's
/// support of the central pixel `(⌊w/2⌋, ⌊h/2⌋)`, each of the `z×z`
/// sub-pixels shows the (unnormalised) weight as grey, with pixel borders as
/// blue `(0, 0, 1)` lines at multiples of `z`.
///
/// The course's code takes `c = w/2` for both axes; glint uses `h/2` for the
/// vertical one, the same for the square images the course renders.
pub fn filter_view(filter: &Filter, w: u32, h: u32, zoom: u32) -> Image {
    let z = zoom.max(1);
    let mut img = Image::new(w * z + 1, h * z + 1, Vec3::new(0.0, 0.0, 0.5));
    let (cx, cy) = (w / 2, h / 2);
    let r = filter.support();
    let zf = z as f32;
    for j in cy.saturating_sub(r)..=(cy + r).min(h.saturating_sub(1)) {
        for i in cx.saturating_sub(r)..=(cx + r).min(w.saturating_sub(1)) {
            for j2 in 0..z {
                for i2 in 0..z {
                    // f32 like the course: see `filter.rs`.
                    let dx = i as f32 + i2 as f32 / zf - (cx as f32 + 0.5);
                    let dy = j as f32 + j2 as f32 / zf - (cy as f32 + 0.5);
                    let g = filter.weight(dx, dy);
                    img.put_up(i * z + i2, j * z + j2, Vec3::splat(g));
                }
            }
        }
    }
    let blue = Vec3::new(0.0, 0.0, 1.0);
    for q in (0..=w * z).step_by(z as usize) {
        for y in 0..img.height {
            img.put_up(q, y, blue);
        }
    }
    for q in (0..=h * z).step_by(z as usize) {
        for x in 0..img.width {
            img.put_up(x, q, blue);
        }
    }
    img
}

/// Colour of `t` in `[0, 1]` on a black–purple–red–yellow–white ramp
/// (monotonic in brightness, readable in grey print).
pub fn heat(t: f32) -> Vec3 {
    const STOPS: [(f32, f32, f32); 5] = [
        (0.0, 0.0, 0.0),
        (0.35, 0.05, 0.55),
        (0.85, 0.2, 0.15),
        (1.0, 0.85, 0.1),
        (1.0, 1.0, 1.0),
    ];
    let t = t.clamp(0.0, 1.0) * (STOPS.len() - 1) as f32;
    let k = (t as usize).min(STOPS.len() - 2);
    let f = t - k as f32;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    Vec3::new(a.0, a.1, a.2).lerp(Vec3::new(b.0, b.1, b.2), f)
}

/// A heat map of `counts` (per pixel, row 0 at the top of a `w`×`h` image),
/// each pixel enlarged to at least 256 pixels of total width, over a scale
/// bar from the smallest to the largest count with both numbers written
/// under its ends.
pub fn heat_map(w: u32, h: u32, counts: &[u32]) -> Image {
    let lo = counts.iter().copied().min().unwrap_or(0);
    let hi = counts.iter().copied().max().unwrap_or(0);
    let scale = 256u32.div_ceil(w.max(1)).max(1);
    let (mw, mh) = (w * scale, h * scale);
    let bar_h = 12;
    let text_h = 2 * 5 + 4;
    let width = mw.max(64);
    let mut img = Image::new(width, mh + 4 + bar_h + 4 + text_h, Vec3::splat(1.0));
    let norm = |c: u32| {
        if hi == lo {
            0.5
        } else {
            (c - lo) as f32 / (hi - lo) as f32
        }
    };
    for row in 0..h {
        for x in 0..w {
            let c = heat(norm(counts[(row * w + x) as usize]));
            for dy in 0..scale {
                for dx in 0..scale {
                    img.put(x * scale + dx, row * scale + dy, c);
                }
            }
        }
    }
    for x in 0..width {
        let c = heat(x as f32 / (width - 1).max(1) as f32);
        for y in 0..bar_h {
            img.put(x, mh + 4 + y, c);
        }
    }
    let text_row = mh + 4 + bar_h + 4;
    draw_number(&mut img, 0, text_row, lo, 2);
    let hi_text = hi.to_string();
    let hi_w = hi_text.len() as u32 * 4 * 2;
    draw_number(&mut img, width.saturating_sub(hi_w), text_row, hi, 2);
    img
}

/// 3×5 bitmaps of the digits, one row per `u8`, bit 2 = left column.
const DIGITS: [[u8; 5]; 10] = [
    [7, 5, 5, 5, 7],
    [2, 6, 2, 2, 7],
    [7, 1, 7, 4, 7],
    [7, 1, 7, 1, 7],
    [5, 5, 7, 1, 1],
    [7, 4, 7, 1, 7],
    [7, 4, 7, 5, 7],
    [7, 1, 1, 1, 1],
    [7, 5, 7, 5, 7],
    [7, 5, 7, 1, 7],
];

/// Writes `n` in black at `(x, row)` (top-left), each font pixel `s`×`s`.
fn draw_number(img: &mut Image, x: u32, row: u32, n: u32, s: u32) {
    for (k, ch) in n.to_string().bytes().enumerate() {
        let glyph = DIGITS[(ch - b'0') as usize];
        let gx = x + k as u32 * 4 * s;
        for (r, bits) in glyph.iter().enumerate() {
            for c in 0..3u32 {
                if bits >> (2 - c) & 1 == 1 {
                    for dy in 0..s {
                        for dx in 0..s {
                            img.put(gx + c * s + dx, row + r as u32 * s + dy, Vec3::ZERO);
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
    use crate::math::Vec2;

    #[test]
    fn samples_view_places_samples_and_checkers() {
        let s = [SampleRecord {
            pixel: (1, 0),
            offset: Vec2::new(0.5, 0.25),
            color: Vec3::X,
        }];
        let img = samples_view(2, 2, 4, &s);
        assert_eq!((img.width, img.height), (8, 8));
        // Pixel (0,0) is grey (even), at the bottom-left.
        assert_eq!(img.pixels[(7 * 8) as usize], Vec3::splat(0.2));
        // Pixel (1,0) is black; its sample at x = 6, y = 1 (row 6).
        assert_eq!(img.pixels[(7 * 8 + 5) as usize], Vec3::ZERO);
        assert_eq!(img.pixels[(6 * 8 + 6) as usize], Vec3::X);
    }

    /// Every pixel of a samples view, from the image coordinates alone: a
    /// checkerboard of `z×z` blocks (grey where the pixel's `i + j` is
    /// even), and each sample at `⌊(i + s)·z⌋` in its colour. An odd width
    /// and an even height, so neither is a multiple of the other.
    #[test]
    fn samples_view_pixels_are_the_checkers_and_samples() {
        let (w, h, z) = (3u32, 2u32, 4u32);
        let s = [
            SampleRecord {
                pixel: (2, 1),
                offset: Vec2::new(0.3, 0.8),
                color: Vec3::X,
            },
            SampleRecord {
                pixel: (0, 0),
                offset: Vec2::new(0.99, 0.0),
                color: Vec3::Y,
            },
        ];
        let img = samples_view(w, h, z, &s);
        let (iw, ih) = (w * z, h * z);
        assert_eq!((img.width, img.height), (iw, ih));
        for y in 0..ih {
            for x in 0..iw {
                let want = match (x, y) {
                    (9, 7) => Vec3::X, // (2 + 0.3)·4 = 9.2, (1 + 0.8)·4 = 7.2
                    (3, 0) => Vec3::Y, // 0.99·4 = 3.96
                    _ if (x / z + y / z) % 2 == 0 => Vec3::splat(0.2),
                    _ => Vec3::ZERO,
                };
                let got = img.pixels[((ih - 1 - y) * iw + x) as usize];
                assert_eq!(got, want, "({x}, {y}) from the bottom left");
            }
        }
    }

    /// Pixels outside the image are ignored, whether counted from the
    /// bottom or from the top.
    #[test]
    fn pixels_outside_the_image_are_ignored() {
        let mut img = Image::new(3, 2, Vec3::ZERO);
        for (x, y) in [(3, 0), (0, 2), (3, 2), (7, 1)] {
            img.put_up(x, y, Vec3::ONE);
            img.put(x, y, Vec3::ONE);
        }
        assert!(img.pixels.iter().all(|&p| p == Vec3::ZERO));
        img.put_up(2, 1, Vec3::X);
        img.put(2, 1, Vec3::Y);
        assert_eq!(img.pixels[2], Vec3::X); // top right
        assert_eq!(img.pixels[5], Vec3::Y); // bottom right
    }

    #[test]
    fn filter_view_box_is_one_pixel_of_white() {
        let img = filter_view(&Filter::Box(0.5), 3, 3, 4);
        assert_eq!((img.width, img.height), (13, 13));
        let white = img.pixels.iter().filter(|&&p| p == Vec3::ONE).count();
        assert_eq!(white, 9, "3x3 sub-pixels inside the centre pixel's lines");
        assert_eq!(img.pixels[14], Vec3::new(0.0, 0.0, 0.5));
        assert_eq!(img.pixels[0], Vec3::new(0.0, 0.0, 1.0));
    }

    /// Every pixel of a tent filter's view, from the image coordinates
    /// alone: blue lines at multiples of the zoom, the weight at each
    /// sub-pixel's offset from the centre pixel's centre within the support
    /// (one pixel around the centre for a radius of 1.5), dark blue beyond.
    /// A 5x3 image: the centre is (2, 1), and the support reaches the
    /// bottom and top rows. And a 4x6 image: the centre is (2, 3)
    /// (`⌊w/2⌋, ⌊h/2⌋`, which odd sizes alone would not tell from `w mod 2`).
    #[test]
    fn filter_view_pixels_are_the_weights_at_their_offsets() {
        let z = 4u32;
        let tent = Filter::Tent(1.5);
        for ((w, h), (cx, cy)) in [((5u32, 3u32), (2u32, 1u32)), ((4, 6), (2, 3))] {
            let img = filter_view(&tent, w, h, z);
            let (iw, ih) = (w * z + 1, h * z + 1);
            assert_eq!((img.width, img.height), (iw, ih));
            for y in 0..ih {
                for x in 0..iw {
                    let want = if x % z == 0 || y % z == 0 {
                        Vec3::new(0.0, 0.0, 1.0)
                    } else if (x / z).abs_diff(cx) <= 1 && (y / z).abs_diff(cy) <= 1 {
                        let dx = x as f32 / 4.0 - (cx as f32 + 0.5);
                        let dy = y as f32 / 4.0 - (cy as f32 + 0.5);
                        Vec3::splat(tent.weight(dx, dy))
                    } else {
                        Vec3::new(0.0, 0.0, 0.5)
                    };
                    let got = img.pixels[((ih - 1 - y) * iw + x) as usize];
                    assert_eq!(got, want, "{w}x{h}: ({x}, {y}) from the bottom left");
                }
            }
        }
    }

    /// The ramp's stops at t = 0, 1/4, 1/2, 3/4, 1, linear between them,
    /// clamped outside [0, 1].
    #[test]
    fn heat_ramp_passes_through_its_stops() {
        let near = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-6;
        let cases = [
            (-1.0, Vec3::ZERO),
            (0.0, Vec3::ZERO),
            (0.125, Vec3::new(0.175, 0.025, 0.275)),
            (0.25, Vec3::new(0.35, 0.05, 0.55)),
            (0.5, Vec3::new(0.85, 0.2, 0.15)),
            (0.625, Vec3::new(0.925, 0.525, 0.125)),
            (0.75, Vec3::new(1.0, 0.85, 0.1)),
            (0.875, Vec3::new(1.0, 0.925, 0.55)),
            (1.0, Vec3::ONE),
            (2.0, Vec3::ONE),
        ];
        for (t, want) in cases {
            assert!(near(heat(t), want), "heat({t}) = {}", heat(t));
        }
    }

    #[test]
    fn heat_map_has_the_scale_and_both_ends() {
        let counts = [4, 4, 4, 16];
        let img = heat_map(2, 2, &counts);
        assert_eq!(img.width, 256);
        assert_eq!(img.pixels[0], heat(0.0));
        assert_eq!(img.pixels[(128 * 256 + 200) as usize], heat(1.0));
        assert!(img.pixels.contains(&Vec3::ZERO)); // digits
        assert!(heat(0.3).length() < heat(0.7).length());
    }

    /// Every pixel of a small heat map, from its description: the cells
    /// enlarged, a white gap, the scale bar, a white gap, and the two
    /// numbers in the 3x5 font at twice its size (each glyph 6 pixels wide
    /// in an 8-pixel advance, left-aligned under the bar's start and
    /// right-aligned under its end), white elsewhere.
    #[test]
    fn heat_map_pixels_are_the_described_ones() {
        let (w, h) = (3u32, 2u32);
        let counts = [3, 7, 5, 7, 3, 12];
        let img = heat_map(w, h, &counts);
        let (lo, hi) = (3u32, 12u32);
        let s = 86; // ceil(256 / 3)
        let (mw, mh) = (w * s, h * s);
        assert_eq!((img.width, img.height), (mw, mh + 4 + 12 + 4 + 14));
        let text = mh + 20;
        // Black where the font of `n`, placed from `x0`, covers `(x, row)`.
        let ink = |n: u32, x0: u32, x: u32, row: u32| {
            let digits = n.to_string().into_bytes();
            if x < x0 || row < text || row >= text + 10 {
                return false;
            }
            let (u, r) = (x - x0, ((row - text) / 2) as usize);
            let (k, within) = ((u / 8) as usize, u % 8);
            k < digits.len()
                && within < 6
                && DIGITS[(digits[k] - b'0') as usize][r] & (4 >> (within / 2)) != 0
        };
        let white = Vec3::ONE;
        for row in 0..img.height {
            for x in 0..img.width {
                let want = if row < mh {
                    let c = counts[(row / s * w + x / s) as usize];
                    heat((c - lo) as f32 / (hi - lo) as f32)
                } else if (mh + 4..mh + 16).contains(&row) {
                    heat(x as f32 / (mw - 1) as f32)
                } else if ink(lo, 0, x, row) || ink(hi, mw - 16, x, row) {
                    Vec3::ZERO
                } else {
                    white
                };
                assert_eq!(
                    img.pixels[(row * img.width + x) as usize],
                    want,
                    "({x}, {row})"
                );
            }
        }
        // The font itself: "1" is the glyph 2,6,2,2,7 (a serif and a base).
        assert_eq!(DIGITS[1], [2, 6, 2, 2, 7]);
    }
}
