//! Ambient occlusion: the cosine-weighted fraction of the hemisphere above a
//! point that is open up to a distance. Used alone (the grey AO image of
//! [`AmbientOcclusion`]) and by [`super::Whitted`] as a factor on the Phong
//! ambient term.

use super::{Branch, Integrator, RayKind, RayObserver, Trace};
pub use crate::math::warp::cosine_hemisphere;
use crate::math::{Ray, SurfacePoint, Vec3};
use crate::world::Hit;

/// How ambient occlusion is estimated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AoSettings {
    /// Hemisphere rays per shaded point (at least 1).
    pub samples: u32,
    /// Occluders farther than this do not count (must be positive; may be
    /// infinite).
    pub distance: f32,
}

impl Default for AoSettings {
    fn default() -> Self {
        Self {
            samples: 16,
            distance: f32::INFINITY,
        }
    }
}

/// Fraction of `ao.samples` cosine-weighted rays from the surface point
/// `from` (unit normal `n` facing the side to test), spawned clear of its
/// error bound at instant `time`, that meet nothing within `ao.distance`: the
/// estimate of `(1/π) ∫ V(ω) cos θ dω`, which is 1 on an open plane. The
/// rays are at recursion `depth`.
pub fn unoccluded<O: RayObserver>(
    cx: &mut Trace<O>,
    from: &SurfacePoint,
    n: Vec3,
    time: f32,
    ao: &AoSettings,
    depth: u32,
) -> f32 {
    let k = ao.samples.max(1);
    let mut open = 0u32;
    for u in cx.stream.split_2d(k) {
        let w = cosine_hemisphere(n, u);
        let ray = from.spawn_ray(w).at_time(time);
        super::count_ray(cx.counters, RayKind::Occlusion);
        let blocked = cx.world.occluded(&ray, 0.0, ao.distance, cx.counters);
        let t_end = if blocked { f32::NAN } else { ao.distance };
        let b = Branch::probe(RayKind::Occlusion, depth);
        cx.observer.ray(b, &ray, t_end, None);
        open += u32::from(!blocked);
    }
    open as f32 / k as f32
}

/// The ambient-occlusion integrator: each camera ray's hit is shaded grey by
/// its unoccluded fraction (misses are white: the open sky).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AmbientOcclusion {
    /// Rays and distance.
    pub settings: AoSettings,
}

impl Integrator for AmbientOcclusion {
    fn li_hit<O: RayObserver>(
        &self,
        cx: &mut Trace<O>,
        ray: &Ray,
        _: f32,
        hit: Option<&Hit>,
    ) -> Vec3 {
        let Some(h) = hit else {
            return Vec3::ONE;
        };
        // Both sides of a surface are tested: the one the ray sees.
        let n = if h.normal.dot(ray.dir) > 0.0 {
            -h.normal
        } else {
            h.normal
        };
        let f = unoccluded(cx, &h.surface_point(), n, ray.time, &self.settings, 0);
        Vec3::splat(f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;

    #[test]
    fn cosine_directions_have_the_right_mean() {
        // E[cos θ] = 2/3 under the cos θ / π density.
        let k = 64;
        let mut sum = 0.0;
        for i in 0..k {
            for j in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                let w = cosine_hemisphere(Vec3::Y, u);
                assert!(w.y >= 0.0);
                sum += w.y;
            }
        }
        let mean = sum / (k * k) as f32;
        assert!((mean - 2.0 / 3.0).abs() < 3e-3, "{mean}");
    }
}
