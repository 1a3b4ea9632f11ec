//! Cost images (pbrt's "pixel statistics"): per pixel, how many
//! intersection tests and how many accelerator nodes or grid cells the
//! pixel's rays cost, as heat maps with a scale bar and the image's totals.
//!
//! The counts are the render's own counters, split by pixel in the render
//! loop ([`crate::render::PixelCost`]), so the per-pixel values add up to
//! the totals `--stats` prints.

use super::draw::Canvas;
use super::grid::ramp;
use crate::math::{Vec2, Vec3};
use crate::render::{Frame, PixelCost};

/// Which count of a pixel a panel shows.
type Metric = fn(&PixelCost) -> u64;

/// Height in pixels of the band under each panel holding the scale bar and
/// the totals.
const BAND: u32 = 22;

/// Two heat maps side by side, intersection tests on the left and nodes
/// visited on the right, each over a band with its scale bar (0 to the
/// largest per-pixel value) and the image's total. The image is
/// `2·width + 4` wide and `height + BAND` high.
pub fn image(frame: &Frame) -> Canvas {
    let (w, h) = (frame.width, frame.height);
    let (cw, ch) = (2 * w + 4, h + BAND);
    let mut canvas = Canvas::new(cw, ch, vec![Vec3::ZERO; (cw * ch) as usize]);
    let metrics: [(Metric, u32); 2] = [(|c| c.tests, 0), (|c| c.nodes, w + 4)];
    for (metric, x0) in metrics {
        let values: Vec<u64> = frame.cost.iter().map(metric).collect();
        let max = values.iter().copied().max().unwrap_or(0);
        let total: u64 = values.iter().sum();
        for row in 0..h {
            for x in 0..w {
                let v = values[(row * w + x) as usize];
                canvas.put(i64::from(x0 + x), i64::from(row), heat(v, max));
            }
        }
        // Scale bar: the ramp from 0 (left) to the maximum (right).
        let bar_w = w.saturating_sub(8).max(1);
        for k in 0..bar_w {
            let c = ramp(k as f32 / (bar_w - 1).max(1) as f32);
            for y in h + 2..h + 7 {
                canvas.put(i64::from(x0 + 4 + k), i64::from(y), c);
            }
        }
        let band_y = (BAND - 8) as f32;
        canvas.text(Vec2::new((x0 + 4) as f32, band_y - 1.0), "0", Vec3::ONE, 1);
        let m = max.to_string();
        let mw = super::draw::text_width(&m, 1) as f32;
        canvas.text(
            Vec2::new((x0 + 4 + bar_w) as f32 - mw, band_y - 1.0),
            &m,
            Vec3::ONE,
            1,
        );
        canvas.text(
            Vec2::new((x0 + 4) as f32 + 12.0, 2.0),
            &total.to_string(),
            Vec3::splat(0.85),
            1,
        );
    }
    canvas
}

/// The colour of `v` on a heat map whose largest value is `max`: black for
/// 0, then the ramp.
pub fn heat(v: u64, max: u64) -> Vec3 {
    if v == 0 || max == 0 {
        Vec3::ZERO
    } else {
        ramp(v as f32 / max as f32)
    }
}

/// The image's totals: (intersection tests, nodes visited).
pub fn totals(frame: &Frame) -> (u64, u64) {
    frame
        .cost
        .iter()
        .fold((0, 0), |(t, n), c| (t + c.tests, n + c.nodes))
}
