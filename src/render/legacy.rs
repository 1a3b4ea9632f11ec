//! The pixel loop as it was before tiles and samplers: one ray per pixel at a
//! fixed offset, rows in parallel. Kept as the baseline of
//! `glint bench --loop` (the new loop must be no slower at 1 spp) and as an
//! oracle: at one sample per pixel the tile loop must give the same image bit
//! for bit (`tests/sampling.rs`).

use super::{screen_point, CameraModel, Frame, PixelOffset};
use crate::integrator::{NoObserver, RayKind, Whitted};
use crate::stats::Counters;
use crate::world::World;
use rayon::prelude::*;

/// One Whitted ray through each pixel at `offset`, rows in parallel.
pub fn render_rows(
    world: &World,
    camera: &CameraModel,
    integrator: &Whitted,
    (width, height): (u32, u32),
    offset: PixelOffset,
) -> (Frame, Counters) {
    let mut frame = Frame::new(width, height);
    let w = width as usize;
    let counters = frame
        .color
        .par_chunks_mut(w)
        .zip(frame.depth.par_chunks_mut(w))
        .zip(frame.normal.par_chunks_mut(w))
        .zip(frame.samples.par_chunks_mut(w))
        .zip(frame.complete.par_iter_mut())
        .enumerate()
        .map(|(row, ((((color, depth), normal), samples), complete))| {
            let mut c = Counters::default();
            // Row 0 of the frame is the top of the image; screen j grows upwards.
            let j = height - 1 - row as u32;
            for i in 0..width {
                let s = screen_point(i, j, offset.0, width, height);
                let ray = camera.ray(s);
                let (col, hit) = integrator.trace(
                    world,
                    &ray,
                    camera.tmin(),
                    RayKind::Primary,
                    0,
                    1.0,
                    &mut c,
                    &mut NoObserver,
                );
                let k = i as usize;
                color[k] = col;
                samples[k] = 1;
                if let Some(h) = hit {
                    depth[k] = h.t;
                    normal[k] = h.normal;
                }
            }
            *complete = true;
            c
        })
        .reduce(Counters::default, |mut a, b| {
            a += b;
            a
        });
    (frame, counters)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{render_image, Control, Settings};

    /// At one ray a pixel, the old loop gives the current loop's frame
    /// (colour, depth, normal, sample counts), rows in the same order, on an
    /// asymmetric scene at two offsets (`tests/sampling.rs` checks the
    /// course's scenes).
    #[test]
    fn the_old_loop_gives_the_current_loop_s_frame() {
        let (world, camera) = super::super::tests::small_world();
        let it = Whitted::default();
        let size = (37, 21);
        for offset in [PixelOffset::CENTER, PixelOffset(crate::math::Vec2::ZERO)] {
            let (old, _) = render_rows(&world, &camera, &it, size, offset);
            let settings = Settings::one_ray(size, offset);
            let new = render_image(&world, &camera, &it, &settings, Control::default()).frame;
            assert_eq!(old.color, new.color);
            assert_eq!(old.depth, new.depth);
            assert_eq!(old.normal, new.normal);
            assert_eq!(old.samples, new.samples);
            assert!(old.is_complete());
            assert!(old.depth.iter().any(|d| d.is_finite()));
        }
    }
}
