use super::{depth_grey, normal_rgb};
use crate::math::Vec3;

/// The work one pixel's rays cost: pbrt's "pixel statistics". Every
/// ray of every kind the pixel's samples spawned counts (shadow, reflected,
/// transmitted), so the per-pixel values add up to the render's totals.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Zeroable)]
pub struct PixelCost {
    /// Ray–primitive intersection tests.
    pub tests: u64,
    /// Accelerator nodes or grid cells visited.
    pub nodes: u64,
}

/// What a render produced per pixel, row-major with row 0 at the top.
///
/// Depth and normal hold the hit of the pixel's sample nearest to its
/// reference point (the centre, or the corner for the course's command line).
#[derive(Clone, Debug)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Linear RGB, unclamped.
    pub color: Vec<Vec3>,
    /// Ray parameter of the eye ray's hit (infinite for a miss).
    pub depth: Vec<f32>,
    /// Unit normal at the eye ray's hit (zero for a miss).
    pub normal: Vec<Vec3>,
    /// Camera rays (samples) per pixel; for adaptive sampling, the distinct
    /// lattice points the pixel's subdivision used (shared corners counted
    /// in every pixel they touch).
    pub samples: Vec<u32>,
    /// What tracing the pixel's samples cost the accelerators, if
    /// [`Settings::pixel_cost`](super::Settings::pixel_cost) asked for it
    /// (zero otherwise). Under adaptive sampling, where neighbours share
    /// rays, each shared ray counts in the pixel that traced it first (a
    /// pixel corner in the pixel whose lower-left corner it is, or on the
    /// image's right and top edges the pixel beside it), so the costs still
    /// add up to the render's counters.
    pub cost: Vec<PixelCost>,
    /// Per row (top first): whether it was rendered (a cancelled render
    /// leaves rows out; a render of a region marks the region's rows when
    /// the region's pixels in them are).
    pub complete: Vec<bool>,
}

impl Frame {
    /// A frame of misses.
    pub fn new(width: u32, height: u32) -> Self {
        let mut f = Self::unset_depth(width, height);
        f.depth.fill(f32::INFINITY);
        f
    }

    /// A frame of misses but for its depth, left zero: for the band loop,
    /// whose threads each fill their own band's depth (the fill of an
    /// 800x800 frame's 2.5 MB on one thread, inside the render's time:
    /// scene6_07 at 1 spp on 2 threads took 101.7 ms with it, 98.9
    /// without).
    pub(crate) fn unset_depth(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            width,
            height,
            // Zeroed allocations, not zero fills: a large one is fresh
            // zero pages from the kernel, faulted in on first write by the
            // render's threads, in parallel. A fill wrote all 30 MB of an
            // 800x800 frame on one thread first (7,500 page faults, ~35 ms
            // of system time, before the parallel loop starts).
            color: bytemuck::zeroed_vec(n),
            depth: bytemuck::zeroed_vec(n),
            normal: bytemuck::zeroed_vec(n),
            samples: vec![0; n],
            cost: bytemuck::zeroed_vec(n),
            complete: vec![false; height as usize],
        }
    }

    /// Whether every row was rendered.
    pub fn is_complete(&self) -> bool {
        self.complete.iter().all(|&c| c)
    }

    /// The depth image for the range `[t0, t1]` (near = white).
    pub fn depth_image(&self, t0: f32, t1: f32) -> Vec<Vec3> {
        self.depth
            .iter()
            .map(|&t| Vec3::splat(depth_grey(t, t0, t1)))
            .collect()
    }

    /// The normals image (`|n|` as RGB, black where nothing was hit).
    pub fn normals_image(&self) -> Vec<Vec3> {
        self.normal.iter().map(|&n| normal_rgb(n)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The depth and normals images are per-pixel maps of the planes, in
    /// pixel order: a frame of misses starts black in both.
    #[test]
    fn depth_and_normals_images_map_each_pixel() {
        let mut f = Frame::new(3, 1);
        assert_eq!(f.depth_image(1.0, 2.0), vec![Vec3::ZERO; 3]);
        assert_eq!(f.normals_image(), vec![Vec3::ZERO; 3]);
        f.depth[0] = 1.25;
        f.depth[2] = 1.0;
        f.normal[1] = Vec3::new(0.0, -0.6, 0.8);
        assert_eq!(
            f.depth_image(1.0, 2.0),
            vec![Vec3::splat(0.75), Vec3::ZERO, Vec3::ONE]
        );
        assert_eq!(
            f.normals_image(),
            vec![Vec3::ZERO, Vec3::new(0.0, 0.6, 0.8), Vec3::ZERO]
        );
    }
}
