use super::float::offset_ray_origin;
use glam::Vec3;

/// A ray `origin + t * dir` at an instant `time`. `dir` is not necessarily
/// unit length: rays carried into an object's space keep the world-space `t`
/// by keeping the scaled direction.
///
/// Why the time lives in the ray: motion blur needs every ray of one camera
/// sample (shadow, reflected, refracted) to see the scene at the same
/// instant, and moving shapes read it where they intersect; nothing between
/// the camera and the shape has to know about motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3,
    /// Direction (any non-zero length).
    pub dir: Vec3,
    /// Instant within the shutter interval at which the ray travels (0 for
    /// scenes without motion).
    pub time: f32,
}

impl Ray {
    /// Builds a ray from an origin and a direction, at time 0.
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self {
            origin,
            dir,
            time: 0.0,
        }
    }

    /// The same ray at instant `time`.
    #[inline]
    pub fn at_time(self, time: f32) -> Self {
        Self { time, ..self }
    }

    /// A ray spawned from this one (shadow, reflected, refracted): it lives
    /// at the same instant.
    #[inline]
    pub fn child(&self, origin: Vec3, dir: Vec3) -> Self {
        Self {
            origin,
            dir,
            time: self.time,
        }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

/// How far short of its target a ray spawned *to* a point stops, as a
/// fraction of the way (pbrt's `ShadowEpsilon`): a shadow ray towards a
/// light ends at `t = 1 − SHADOW_EPSILON`, so a surface the light lies on
/// (within rounding) does not shadow it.
pub const SHADOW_EPSILON: f32 = 1e-4;

/// A point on a surface as an intersection computed it: the point, a
/// conservative per-axis bound on its floating-point error (the true surface
/// point lies within `p ± error`), and the unit geometric normal there.
/// Secondary rays leave from it through [`SurfacePoint::spawn_ray`] and
/// friends, never from `p` itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// The computed point.
    pub p: Vec3,
    /// Per-axis bound on `|p − true point|`.
    pub error: Vec3,
    /// Unit geometric normal (either orientation: only its line matters here).
    pub n: Vec3,
}

impl SurfacePoint {
    /// The origin of a ray leaving towards `w`: `p` pushed out of its error
    /// box along the normal, on `w`'s side ([`offset_ray_origin`]).
    #[inline]
    pub fn offset_origin(&self, w: Vec3) -> Vec3 {
        offset_ray_origin(self.p, self.error, self.n, w)
    }

    /// A ray leaving the surface in direction `dir`, to be traced with any
    /// `t > 0`: it cannot re-hit the surface at its start.
    #[inline]
    pub fn spawn_ray(&self, dir: Vec3) -> Ray {
        Ray::new(self.offset_origin(dir), dir)
    }

    /// A ray from the surface to the point `target` (a point light): `t = 1`
    /// is the target; trace it over `(0, 1 − SHADOW_EPSILON)`.
    #[inline]
    pub fn spawn_ray_to(&self, target: Vec3) -> Ray {
        let origin = self.offset_origin(target - self.p);
        Ray::new(origin, target - origin)
    }

    /// A ray between two surface points (an area light's sample, a
    /// visibility test): both ends are offset out of their error boxes, each
    /// towards the other, so neither surface is hit at its end. `t = 1` is
    /// the far end; trace it over `(0, 1 − SHADOW_EPSILON)`.
    #[inline]
    pub fn spawn_ray_to_surface(&self, to: &SurfacePoint) -> Ray {
        let end = to.offset_origin(self.p - to.p);
        let origin = self.offset_origin(end - self.p);
        Ray::new(origin, end - origin)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn on_floor(p: Vec3, err: f32) -> SurfacePoint {
        SurfacePoint {
            p,
            error: Vec3::splat(err),
            n: Vec3::Y,
        }
    }

    #[test]
    fn spawned_rays_start_on_the_side_they_leave_towards() {
        let s = on_floor(Vec3::ZERO, 1e-6);
        assert!(s.spawn_ray(Vec3::new(0.3, 1.0, 0.0)).origin.y > 0.0);
        assert!(s.spawn_ray(Vec3::new(0.3, -1.0, 0.0)).origin.y < 0.0);
    }

    #[test]
    fn a_ray_to_a_point_ends_there_at_t_one() {
        let s = on_floor(Vec3::new(1.0, 0.0, 2.0), 1e-6);
        let light = Vec3::new(-3.0, 5.0, 0.5);
        let r = s.spawn_ray_to(light);
        assert!((r.at(1.0) - light).length() < 1e-6);
        assert!(r.origin.y > 0.0);
    }

    #[test]
    fn a_ray_between_surfaces_leaves_both_error_boxes() {
        let a = on_floor(Vec3::new(0.0, 0.0, 0.0), 1e-3);
        let b = SurfacePoint {
            p: Vec3::new(0.0, 4.0, 0.0),
            error: Vec3::splat(1e-3),
            n: Vec3::NEG_Y,
        };
        let r = a.spawn_ray_to_surface(&b);
        assert!(r.origin.y >= 1e-3);
        assert!(r.at(1.0).y <= 4.0 - 1e-3);
    }
}
