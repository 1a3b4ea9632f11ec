//! Shadow rays from one surface point, sharing their offset origins.
//!
//! A ray leaving a [`SurfacePoint`] starts at `offset_ray_origin(p, error,
//! n, w)`, which depends on the direction `w` only through the side of the
//! surface it points to (the sign test `w·n < 0`). A shaded point sends one
//! shadow ray per light, most of them to the same side, so [`Spawn`] keeps
//! the origin of each side once computed (before it, a profile put 4.8%
//! of a render in spawning shadow rays, most of it in `offset_ray_origin`).
//! The rays are the ones `SurfacePoint::spawn_ray`, `spawn_ray_to` and
//! `spawn_ray_to_surface` make, bit for bit.

use super::float::offset_ray_origin;
use super::{Ray, SurfacePoint, Vec3};

/// A surface point with the offset origins of its two sides, each computed
/// on first use.
#[derive(Clone, Copy, Debug)]
pub struct Spawn {
    /// The point rays leave.
    pub from: SurfacePoint,
    /// The primitive (its index in the world) `from` lies on, when known:
    /// a flat one cannot block the rays leaving it (`World::occluded_leaving`).
    pub leaving: Option<u32>,
    /// Origins for directions with `w·n >= 0` (or NaN) and with `w·n < 0`.
    origins: [Option<Vec3>; 2],
}

impl Spawn {
    /// Rays from `from`, no origin computed yet.
    #[inline]
    pub fn new(from: SurfacePoint) -> Self {
        Self {
            from,
            leaving: None,
            origins: [None; 2],
        }
    }

    /// Rays from `from`, a point of primitive `prim`.
    #[inline]
    pub fn leaving(from: SurfacePoint, prim: u32) -> Self {
        Self {
            leaving: Some(prim),
            ..Self::new(from)
        }
    }

    /// `from.offset_origin(w)`: the side is decided by the very test
    /// `offset_ray_origin` makes, so a cached origin is the one it returns.
    // Always inlined: the origin just computed is used from registers
    // (out of line it came back through memory in pieces, a
    // store-forwarding stall; see `material::phong_light`).
    #[inline(always)]
    fn origin(&mut self, w: Vec3) -> Vec3 {
        let f = &self.from;
        let side = usize::from(w.dot(f.n) < 0.0);
        // (Not `get_or_insert_with`: LLVM kept that out of line, and the
        // origin came back through memory.)
        if let Some(o) = self.origins[side] {
            return o;
        }
        let o = offset_ray_origin(f.p, f.error, f.n, w);
        self.origins[side] = Some(o);
        o
    }

    /// [`SurfacePoint::spawn_ray`].
    #[inline]
    pub fn spawn_ray(&mut self, dir: Vec3) -> Ray {
        Ray::new(self.origin(dir), dir)
    }

    /// [`SurfacePoint::spawn_ray_to`].
    #[inline]
    pub fn spawn_ray_to(&mut self, target: Vec3) -> Ray {
        let origin = self.origin(target - self.from.p);
        Ray::new(origin, target - origin)
    }

    /// [`SurfacePoint::spawn_ray_to_surface`].
    #[inline]
    pub fn spawn_ray_to_surface(&mut self, to: &SurfacePoint) -> Ray {
        let end = to.offset_origin(self.from.p - to.p);
        let origin = self.origin(end - self.from.p);
        Ray::new(origin, end - origin)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every ray equals the `SurfacePoint` method's, in any order of calls
    /// (both sides, repeated sides, zero, NaN and mixed directions).
    #[test]
    fn same_rays_as_the_surface_point() {
        let mut r = crate::testutil::Rng::new(0x1234_5679);
        // Hundredths in [-10, 10]: zero components come up.
        let mut rnd = || r.below(2001) as f32 / 100.0 - 10.0;
        let bits = |r: Ray| [r.origin, r.dir].map(|v| v.to_array().map(f32::to_bits));
        for _ in 0..2000 {
            let n = Vec3::new(rnd(), rnd(), rnd()).normalize_or_zero();
            let sp = SurfacePoint {
                p: Vec3::new(rnd(), rnd(), rnd()) * 100.0,
                error: Vec3::new(rnd().abs(), rnd().abs(), rnd().abs()) * 1e-4,
                n,
            };
            let mut s = Spawn::new(sp);
            for k in 0..8 {
                let w = match k % 4 {
                    0 => Vec3::ZERO,
                    1 if rnd() > 8.0 => Vec3::new(f32::NAN, 1.0, 0.0),
                    _ => Vec3::new(rnd(), rnd(), rnd()),
                };
                let to = SurfacePoint {
                    p: Vec3::new(rnd(), rnd(), rnd()) * 10.0,
                    error: Vec3::splat(1e-5),
                    n: Vec3::Y,
                };
                assert_eq!(bits(s.spawn_ray(w)), bits(sp.spawn_ray(w)));
                let t = sp.p + w;
                assert_eq!(bits(s.spawn_ray_to(t)), bits(sp.spawn_ray_to(t)));
                let a = bits(s.spawn_ray_to_surface(&to));
                assert_eq!(a, bits(sp.spawn_ray_to_surface(&to)));
            }
        }
    }
}
