//! The pixel loop: camera rays through every pixel, traced in parallel by rows,
//! into a [`Frame`] of colour, depth and normal planes.

mod camera;
mod frame;

pub use camera::{pixel_of_screen, screen_point, CameraModel};
pub use frame::Frame;

use crate::integrator::{NoObserver, RayKind, Whitted};
use crate::math::{Vec2, Vec3};
use crate::stats::Counters;
use crate::world::World;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// How a caller steers a running render: stop it early, watch its progress.
#[derive(Default, Clone, Copy)]
pub struct Control<'a> {
    /// When set (e.g. by a Ctrl-C handler), rows not yet started are skipped.
    pub cancel: Option<&'a AtomicBool>,
    /// Called once per finished row, from the worker threads.
    pub on_row: Option<&'a (dyn Fn() + Sync)>,
}

impl Control<'_> {
    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }
}

/// Where in each pixel the single eye ray goes.
///
/// `(0.5, 0.5)` is the pixel centre. The 6.837 reference renders match the
/// pixel's lower-left corner `(0, 0)` exactly (screen point `i/w`, the usual
/// loop of the course's ray-casting assignments), so `raytracer` uses that;
/// `glint render` uses the centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelOffset(pub Vec2);

impl PixelOffset {
    /// The pixel centre.
    pub const CENTER: PixelOffset = PixelOffset(Vec2::splat(0.5));
    /// The pixel's lower-left corner (the course's convention).
    pub const CORNER: PixelOffset = PixelOffset(Vec2::ZERO);
}

/// Renders `world` seen through `camera` into a `width`×`height` frame with
/// one ray through each pixel at `offset`. Returns the merged counters.
pub fn render(
    world: &World,
    camera: &CameraModel,
    integrator: &Whitted,
    (width, height): (u32, u32),
    offset: PixelOffset,
) -> (Frame, Counters) {
    render_with(
        world,
        camera,
        integrator,
        (width, height),
        offset,
        Control::default(),
    )
}

/// [`render`] under a [`Control`]. Rows skipped after a cancel stay black and
/// are listed in [`Frame::complete`] as `false`.
pub fn render_with(
    world: &World,
    camera: &CameraModel,
    integrator: &Whitted,
    (width, height): (u32, u32),
    offset: PixelOffset,
    control: Control,
) -> (Frame, Counters) {
    let mut frame = Frame::new(width, height);
    let w = width as usize;
    let counters = frame
        .color
        .par_chunks_mut(w)
        .zip(frame.depth.par_chunks_mut(w))
        .zip(frame.normal.par_chunks_mut(w))
        .zip(frame.complete.par_iter_mut())
        .enumerate()
        .map(|(row, (((color, depth), normal), complete))| {
            let mut c = Counters::default();
            if control.cancelled() {
                return c;
            }
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
                if let Some(h) = hit {
                    depth[k] = h.t;
                    normal[k] = h.normal;
                }
            }
            *complete = true;
            if let Some(f) = control.on_row {
                f();
            }
            c
        })
        .reduce(Counters::default, |mut a, b| {
            a += b;
            a
        });
    (frame, counters)
}

/// Grey level of the depth image: `t0` (near) is white, `t1` is black,
/// clamped outside; a miss (infinite `t`) is black.
pub fn depth_grey(t: f32, t0: f32, t1: f32) -> f32 {
    if !t.is_finite() || t1 == t0 {
        return 0.0;
    }
    ((t1 - t) / (t1 - t0)).clamp(0.0, 1.0)
}

/// Colour of the normals image: the absolute value of each component.
pub fn normal_rgb(n: Vec3) -> Vec3 {
    n.abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_maps_near_to_white() {
        assert_eq!(depth_grey(9.0, 9.0, 10.0), 1.0);
        assert_eq!(depth_grey(10.0, 9.0, 10.0), 0.0);
        assert_eq!(depth_grey(9.5, 9.0, 10.0), 0.5);
        assert_eq!(depth_grey(5.0, 9.0, 10.0), 1.0);
        assert_eq!(depth_grey(f32::INFINITY, 9.0, 10.0), 0.0);
    }
}
