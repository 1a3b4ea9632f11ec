//! The film: weighted sums of samples per pixel, kept per tile and merged in
//! a fixed order.
//!
//! Each sample is *splatted*: it adds `w·colour` and `w` to every pixel
//! within the filter's support, `w` the filter weight of the sample's offset
//! from that pixel's centre; a pixel is `Σ w·colour / Σ w`. A tile splats
//! into its own [`TileFilm`], which covers the tile plus a margin of the
//! filter's support (clipped to the image), so a tile's film is a pure
//! function of the settings and the tile: tiles can render on any thread (or,
//! later, any machine). [`merge`] then adds, for every pixel, the films that
//! cover it in tile order, which fixes the floating-point summation order.

use super::{Filter, Frame};
use crate::math::{Vec2, Vec3};

/// A rectangle of pixels in frame coordinates (`x` right, `row` down from
/// the top of the image), half-open.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    /// First column.
    pub x0: u32,
    /// First row.
    pub row0: u32,
    /// One past the last column.
    pub x1: u32,
    /// One past the last row.
    pub row1: u32,
}

impl Rect {
    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.x1 - self.x0
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.row1 - self.row0
    }

    /// Number of pixels.
    pub fn area(&self) -> usize {
        self.width() as usize * self.height() as usize
    }

    /// Whether `(x, row)` lies inside.
    pub fn contains(&self, x: u32, row: u32) -> bool {
        (self.x0..self.x1).contains(&x) && (self.row0..self.row1).contains(&row)
    }

    /// Whether the two share a pixel.
    pub fn overlaps(&self, o: &Rect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.row0 < o.row1 && o.row0 < self.row1
    }

    /// Grown by `m` pixels on every side, clipped to a `w`×`h` image.
    pub fn grown(&self, m: u32, w: u32, h: u32) -> Rect {
        Rect {
            x0: self.x0.saturating_sub(m),
            row0: self.row0.saturating_sub(m),
            x1: (self.x1 + m).min(w),
            row1: (self.row1 + m).min(h),
        }
    }
}

/// What one tile contributed: filter sums over the tile and its margin, and
/// the per-pixel planes (depth, normal, sample count) of the tile itself.
#[derive(Clone, Debug)]
pub struct TileFilm {
    /// The tile's own pixels.
    pub tile: Rect,
    /// The pixels it splats into: the tile plus the filter margin.
    pub area: Rect,
    filter: Filter,
    support: i32,
    image: (u32, u32),
    sum: Vec<Vec3>,
    weight: Vec<f32>,
    /// Depth of the kept hit, per tile pixel.
    pub depth: Vec<f32>,
    /// Normal of the kept hit, per tile pixel.
    pub normal: Vec<Vec3>,
    /// Camera rays traced per tile pixel.
    pub samples: Vec<u32>,
    /// What each tile pixel's rays cost.
    pub cost: Vec<super::frame::PixelCost>,
}

impl TileFilm {
    /// An empty film for `tile` of a `w`×`h` image reconstructed with `filter`.
    pub fn new(tile: Rect, filter: Filter, (w, h): (u32, u32)) -> Self {
        let support = filter.support();
        let area = tile.grown(support, w, h);
        let n = tile.area();
        Self {
            tile,
            area,
            filter,
            support: support as i32,
            image: (w, h),
            sum: vec![Vec3::ZERO; area.area()],
            weight: vec![0.0; area.area()],
            depth: vec![f32::INFINITY; n],
            normal: vec![Vec3::ZERO; n],
            samples: vec![0; n],
            cost: vec![Default::default(); n],
        }
    }

    /// How many pixels a sample's filter reaches beyond its own.
    #[inline]
    pub fn support(&self) -> u32 {
        self.support as u32
    }

    /// Index of tile pixel `(x, row)` in the per-pixel planes.
    #[inline]
    pub fn tile_index(&self, x: u32, row: u32) -> usize {
        (row - self.tile.row0) as usize * self.tile.width() as usize + (x - self.tile.x0) as usize
    }

    /// Adds a sample of colour `c` taken at in-pixel offset `o` (`y` up) of
    /// pixel `(x, row)` to every pixel its filter reaches.
    #[inline]
    pub fn splat(&mut self, x: u32, row: u32, o: Vec2, c: Vec3) {
        if self.support == 0 {
            // The common case (box 0.5, or any filter narrower than a
            // pixel): only the pixel itself.
            let w = self.filter.weight(o.x - 0.5, o.y - 0.5);
            if w != 0.0 {
                let k = self.area_index(x, row);
                self.sum[k] += c * w;
                self.weight[k] += w;
            }
            return;
        }
        let s = self.support;
        let (w, h) = (self.image.0 as i32, self.image.1 as i32);
        for b in -s..=s {
            // Pixel `b` above in the image is `b` rows up in the frame.
            let r = row as i32 - b;
            if r < 0 || r >= h {
                continue;
            }
            for a in -s..=s {
                let px = x as i32 + a;
                if px < 0 || px >= w {
                    continue;
                }
                let wt = self
                    .filter
                    .weight(o.x - 0.5 - a as f32, o.y - 0.5 - b as f32);
                if wt != 0.0 {
                    let k = self.area_index(px as u32, r as u32);
                    self.sum[k] += c * wt;
                    self.weight[k] += wt;
                }
            }
        }
    }

    /// Sets the reconstructed colour of tile pixel `(x, row)` directly,
    /// with weight 1 (a filter inside the pixel, whose samples the loop
    /// summed itself, or a strategy such as adaptive subdivision that
    /// integrates the pixel itself).
    #[inline]
    pub fn set_pixel(&mut self, x: u32, row: u32, c: Vec3) {
        let k = self.area_index(x, row);
        self.sum[k] = c;
        self.weight[k] = 1.0;
    }

    #[inline]
    fn area_index(&self, x: u32, row: u32) -> usize {
        (row - self.area.row0) as usize * self.area.width() as usize + (x - self.area.x0) as usize
    }
}

/// Splits a `w`×`h` image into tiles of `size`×`size` (the last row and
/// column smaller), row-major from the top-left.
pub fn tiles(w: u32, h: u32, size: u32) -> Vec<Rect> {
    let size = size.max(1);
    let mut out = Vec::new();
    for row0 in (0..h).step_by(size as usize) {
        for x0 in (0..w).step_by(size as usize) {
            out.push(Rect {
                x0,
                row0,
                x1: (x0 + size).min(w),
                row1: (row0 + size).min(h),
            });
        }
    }
    out
}

/// Merges tile films (in the order of [`tiles`]; `None` = not rendered) into
/// `frame`: each pixel adds the films covering it in tile order and divides
/// by the summed weight (black if no sample reached it). A row is complete
/// when every tile that could reach it was rendered.
pub fn merge(films: &[Option<TileFilm>], tile_size: u32, support: u32, frame: &mut Frame) {
    use rayon::prelude::*;
    let (w, h) = (frame.width, frame.height);
    let ts = tile_size.max(1);
    let cols = w.div_ceil(ts);
    let rows = h.div_ceil(ts);
    let tile_range = |p: u32, n: u32| {
        let lo = p.saturating_sub(support) / ts;
        let hi = ((p + support).min(n * ts - 1)) / ts;
        lo..=hi
    };
    let wu = w as usize;
    frame
        .color
        .par_chunks_mut(wu)
        .zip(frame.depth.par_chunks_mut(wu))
        .zip(frame.normal.par_chunks_mut(wu))
        .zip(frame.samples.par_chunks_mut(wu))
        .zip(frame.cost.par_chunks_mut(wu))
        .zip(frame.complete.par_iter_mut())
        .enumerate()
        .for_each(
            |(row, (((((line, depth), normal), samples), cost), complete))| {
                let row = row as u32;
                let tys = tile_range(row, rows);
                *complete = tys
                    .clone()
                    .all(|ty| (0..cols).all(|tx| films[(ty * cols + tx) as usize].is_some()));
                // Per-pixel planes, and with a support of 0 the colour too, come
                // from the tile owning the pixel alone.
                let own_ty = row / ts;
                for f in (0..cols).filter_map(|tx| films[(own_ty * cols + tx) as usize].as_ref()) {
                    for x in f.tile.x0..f.tile.x1 {
                        let k = f.tile_index(x, row);
                        let p = x as usize;
                        depth[p] = f.depth[k];
                        normal[p] = f.normal[k];
                        samples[p] = f.samples[k];
                        cost[p] = f.cost[k];
                        if support == 0 {
                            let a = f.area_index(x, row);
                            let wt = f.weight[a];
                            line[p] = if wt > 0.0 { f.sum[a] / wt } else { Vec3::ZERO };
                        }
                    }
                }
                if support == 0 {
                    return;
                }
                for (x, out) in line.iter_mut().enumerate() {
                    let x = x as u32;
                    let mut acc: Option<(Vec3, f32)> = None;
                    for ty in tys.clone() {
                        for tx in tile_range(x, cols) {
                            let Some(f) = &films[(ty * cols + tx) as usize] else {
                                continue;
                            };
                            if !f.area.contains(x, row) {
                                continue;
                            }
                            let k = f.area_index(x, row);
                            let (s, wt) = (f.sum[k], f.weight[k]);
                            acc = Some(match acc {
                                None => (s, wt),
                                Some((a, aw)) => (a + s, aw + wt),
                            });
                        }
                    }
                    *out = match acc {
                        Some((s, wt)) if wt > 0.0 => s / wt,
                        _ => Vec3::ZERO,
                    };
                }
            },
        );
}

/// After [`merge`] of a render limited to `region` (tiles skipped where
/// their films cannot reach it): marks the rows of `region` complete when
/// every tile whose film reaches into `region` was rendered, so a crop of
/// any shape is complete without the tile columns it does not need. Rows
/// outside `region` keep [`merge`]'s answer.
pub fn complete_region(
    films: &[Option<TileFilm>],
    rects: &[Rect],
    support: u32,
    region: Rect,
    frame: &mut Frame,
) {
    let (w, h) = (frame.width, frame.height);
    let needed = rects
        .iter()
        .zip(films)
        .filter(|(t, _)| t.grown(support, w, h).overlaps(&region));
    let mut all = true;
    for (_, f) in needed {
        all &= f.is_some();
    }
    if all {
        for row in region.row0..region.row1.min(h) {
            frame.complete[row as usize] = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Half-open rectangles: a pixel is inside when both its column and its
    /// row are; two rectangles overlap when they share a pixel in both
    /// directions (touching edges share none).
    #[test]
    fn rectangles_contain_and_overlap_half_open() {
        let r = Rect {
            x0: 2,
            row0: 3,
            x1: 5,
            row1: 7,
        };
        assert!(r.contains(2, 3) && r.contains(4, 6));
        for (x, row) in [(5, 3), (1, 3), (2, 7), (2, 2), (5, 7), (9, 9)] {
            assert!(!r.contains(x, row), "({x}, {row})");
        }
        let at = |x0, row0, x1, row1| Rect { x0, row0, x1, row1 };
        assert!(r.overlaps(&at(4, 6, 9, 9)) && at(4, 6, 9, 9).overlaps(&r));
        assert!(r.overlaps(&at(0, 0, 3, 4)) && r.overlaps(&r));
        for o in [
            at(5, 3, 8, 7), // touches the right edge
            at(0, 3, 2, 7), // touches the left edge
            at(2, 7, 5, 9), // touches the bottom
            at(2, 0, 5, 3), // touches the top
            at(3, 8, 4, 9), // columns shared, rows not
            at(6, 4, 8, 5), // rows shared, columns not
        ] {
            assert!(!r.overlaps(&o) && !o.overlaps(&r), "{o:?}");
        }
    }

    #[test]
    fn tiles_cover_the_image_once() {
        for (w, h, s) in [(1, 1, 16), (33, 17, 16), (64, 64, 32), (5, 100, 7)] {
            let mut seen = vec![0u8; (w * h) as usize];
            for t in tiles(w, h, s) {
                for row in t.row0..t.row1 {
                    for x in t.x0..t.x1 {
                        seen[(row * w + x) as usize] += 1;
                    }
                }
            }
            assert!(seen.iter().all(|&c| c == 1), "{w}x{h} by {s}");
        }
    }

    /// A frame of one sample a pixel at offset `o`, coloured by `colour`,
    /// splatted tile by tile (tiles of `ts`) and merged.
    fn splat_every_pixel(
        (w, h): (u32, u32),
        ts: u32,
        filter: Filter,
        o: Vec2,
        colour: impl Fn(u32, u32) -> Vec3,
    ) -> Frame {
        let films: Vec<Option<TileFilm>> = tiles(w, h, ts)
            .iter()
            .map(|&t| {
                let mut f = TileFilm::new(t, filter, (w, h));
                for row in t.row0..t.row1 {
                    for x in t.x0..t.x1 {
                        f.splat(x, row, o, colour(x, row));
                    }
                }
                Some(f)
            })
            .collect();
        let mut frame = Frame::new(w, h);
        merge(&films, ts, filter.support(), &mut frame);
        frame
    }

    /// The same samples splatted through different tilings give the same
    /// pixels up to rounding (the order of the sums differs), and a pixel is
    /// the weighted mean of the samples around it.
    #[test]
    fn merge_is_a_weighted_mean_across_tile_borders() {
        let (w, h) = (7u32, 5u32);
        let filter = Filter::Tent(1.5);
        let colour = |x: u32, row: u32| Vec3::new(x as f32, row as f32, 1.0);
        let render = |ts: u32| splat_every_pixel((w, h), ts, filter, Vec2::new(0.3, 0.6), colour);
        let a = render(2);
        let b = render(16);
        for (p, q) in a.color.iter().zip(&b.color) {
            assert!((*p - *q).length() < 1e-5, "{p} vs {q}");
        }
        assert!(a.is_complete());
        // Blue is 1 everywhere, so its weighted mean is exactly 1.
        assert!(a.color.iter().all(|c| (c.z - 1.0).abs() < 1e-6));
        // An interior pixel sees neighbours on both sides: its red lies
        // strictly between its neighbours'.
        let c = a.color[(2 * w + 3) as usize];
        assert!(c.x > 2.0 && c.x < 4.0, "{c}");
    }

    /// A pixel no sample reaches with a positive weight is black, not
    /// `0/0`: samples at pixel corners through a tent of radius 0.6 (which
    /// reaches neighbours, the merge's summing path) are `√½ > 0.6` from
    /// every pixel centre.
    #[test]
    fn a_pixel_without_weight_is_black() {
        let f = splat_every_pixel((5, 4), 2, Filter::Tent(0.6), Vec2::ZERO, |_, _| Vec3::ONE);
        assert!(f.color.iter().all(|&c| c == Vec3::ZERO), "{:?}", f.color);
    }

    /// Closed form of the splat's direction conventions: every pixel holds
    /// one sample at offset `o = (0.3, 0.6)` (y up) coloured by its column
    /// and its row. A pixel `(x, row)` receives the sample of the pixel `a`
    /// columns left and `b` rows *below* it (frame row `row + b`) with
    /// weight `W(o.x − 0.5 − a, o.y − 0.5 − b)` (the sample's offset from
    /// this pixel's centre, y up), so its colour is the weighted mean of
    /// `x − a` and `row + b`, computed here without films. Borders and
    /// corners included: a border pixel receives only the samples of pixels
    /// inside the image (what the filter reaches beyond the edge is
    /// dropped, not clamped onto the edge pixel).
    #[test]
    fn border_pixels_are_the_closed_form_means_of_in_image_samples() {
        let (w, h) = (9i32, 8i32);
        let filter = Filter::Tent(1.5);
        let o = Vec2::new(0.3, 0.6);
        let frame = splat_every_pixel((w as u32, h as u32), 4, filter, o, |x, row| {
            Vec3::new(x as f32, row as f32, 1.0)
        });
        for row in 0..h {
            for x in 0..w {
                let (mut sum, mut total) = (Vec3::ZERO, 0.0);
                for a in -2i32..=2 {
                    for b in -2i32..=2 {
                        let (sx, srow) = (x - a, row + b);
                        if !(0..w).contains(&sx) || !(0..h).contains(&srow) {
                            continue;
                        }
                        let wt = filter.weight(o.x - 0.5 - a as f32, o.y - 0.5 - b as f32);
                        sum += wt * Vec3::new(sx as f32, srow as f32, 1.0);
                        total += wt;
                    }
                }
                let want = sum / total;
                let got = frame.color[(row * w + x) as usize];
                assert!(
                    (got - want).abs().max_element() < 1e-5,
                    "({x}, {row}): {got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn missing_tiles_leave_rows_incomplete() {
        let (w, h) = (8, 8);
        let rects = tiles(w, h, 4);
        let mut films: Vec<Option<TileFilm>> = rects
            .iter()
            .map(|&t| Some(TileFilm::new(t, Filter::Box(0.5), (w, h))))
            .collect();
        films[3] = None; // bottom-right tile
        let mut frame = Frame::new(w, h);
        merge(&films, 4, 0, &mut frame);
        assert_eq!(
            frame.complete,
            [true, true, true, true, false, false, false, false]
        );
    }
}
