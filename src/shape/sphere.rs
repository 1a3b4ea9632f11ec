use crate::math::{gamma, Aabb, Ray, SurfacePoint, Vec3};

/// A sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: Vec3,
    /// Radius (positive).
    pub radius: f32,
}

impl Sphere {
    /// Nearest root of `|o + t·d - c|² = r²` in `(tmin, tmax)`.
    ///
    /// Why this form: with `b' = (o - c)·d`, the discriminant is computed as
    /// `r²·|d|² - |(o - c) - (b'/|d|²)·d|²·|d|²` (the squared distance from the centre
    /// to the ray's line), which does not cancel catastrophically when the ray
    /// starts far away; and the second root comes from `c/(a·t1)` (Vieta), which
    /// keeps precision for the small root.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<f32> {
        let oc = ray.origin - self.center;
        let a = ray.dir.length_squared();
        let half_b = oc.dot(ray.dir);
        let c = oc.length_squared() - self.radius * self.radius;
        let perp = oc - (half_b / a) * ray.dir;
        let disc = a * (self.radius * self.radius - perp.length_squared());
        if disc < 0.0 || a == 0.0 {
            return None;
        }
        let q = -(half_b + half_b.signum() * disc.sqrt());
        let (mut t0, mut t1) = if q == 0.0 { (0.0, 0.0) } else { (q / a, c / q) };
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        if t0 > tmin && t0 < tmax {
            Some(t0)
        } else if t1 > tmin && t1 < tmax {
            Some(t1)
        } else {
            None
        }
    }

    /// The hit at parameter `t` of `ray` (pbrt's reprojection): the point is
    /// computed relative to the centre and scaled back onto the sphere, which
    /// removes the error `t` carries along the ray; what remains is the
    /// rounding of that reprojection, `γ(5)·|p − c|` (pbrt-v3 §3.9.4), and of
    /// adding the centre back, `γ(1)·|p|`.
    pub fn surface(&self, ray: &Ray, t: f32) -> SurfacePoint {
        let rel = (ray.origin - self.center) + t * ray.dir;
        let len = rel.length();
        let rel = if len > 0.0 && len.is_finite() {
            rel * (self.radius / len)
        } else {
            rel
        };
        let p = self.center + rel;
        SurfacePoint {
            p,
            error: gamma(5) * rel.abs() + gamma(1) * p.abs(),
            n: rel.normalize_or_zero(),
        }
    }

    /// Bounding box.
    pub fn bounds(&self) -> Aabb {
        Aabb::new(
            self.center - Vec3::splat(self.radius),
            self.center + Vec3::splat(self.radius),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::testing::Lcg;

    fn unit() -> Sphere {
        Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        }
    }

    #[test]
    fn hit_from_outside_gives_near_root() {
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        let t = unit().intersect(&r, 0.0, f32::INFINITY).unwrap();
        assert!((t - 4.0).abs() < 1e-6);
        assert_eq!(unit().surface(&r, t).n, Vec3::NEG_Z);
    }

    #[test]
    fn miss() {
        let r = Ray::new(Vec3::new(0.0, 1.5, -5.0), Vec3::Z);
        assert!(unit().intersect(&r, 0.0, f32::INFINITY).is_none());
    }

    #[test]
    fn inside_gives_far_root() {
        let r = Ray::new(Vec3::ZERO, Vec3::X);
        let t = unit().intersect(&r, 0.0, f32::INFINITY).unwrap();
        assert!((t - 1.0).abs() < 1e-6);
    }

    #[test]
    fn behind_is_a_miss() {
        let r = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::Z);
        assert!(unit().intersect(&r, 0.0, f32::INFINITY).is_none());
    }

    #[test]
    fn tangent_touches_once() {
        let r = Ray::new(Vec3::new(0.0, 1.0, -5.0), Vec3::Z);
        let t = unit().intersect(&r, 0.0, f32::INFINITY).unwrap();
        assert!((t - 5.0).abs() < 1e-3);
    }

    #[test]
    fn unnormalized_direction_keeps_world_t() {
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z * 2.0);
        let t = unit().intersect(&r, 0.0, f32::INFINITY).unwrap();
        assert!((t - 2.0).abs() < 1e-6);
    }

    #[test]
    fn far_away_ray_keeps_precision() {
        let s = Sphere {
            center: Vec3::ZERO,
            radius: 0.01,
        };
        let r = Ray::new(Vec3::new(0.0, 0.0, -1e4), Vec3::Z);
        let t = s.intersect(&r, 0.0, f32::INFINITY).unwrap();
        assert!((t - (1e4 - 0.01)).abs() < 2e-3);
    }

    #[test]
    fn respects_t_range() {
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        assert!(unit().intersect(&r, 0.0, 3.9).is_none());
        let t = unit().intersect(&r, 4.5, f32::INFINITY).unwrap();
        assert!((t - 6.0).abs() < 1e-6);
    }

    #[test]
    fn surface_point_is_on_the_sphere_within_its_error() {
        let s = Sphere {
            center: Vec3::new(1e4, -2e3, 5e3),
            radius: 3.0,
        };
        let r = Ray::new(
            Vec3::new(0.0, 1.0, 0.0),
            s.center - Vec3::new(0.0, 1.0, 0.0),
        );
        let t = s.intersect(&r, 0.0, f32::INFINITY).unwrap();
        let sp = s.surface(&r, t);
        // The exact distance from the centre, in f64, within the error box.
        let d = (sp.p.as_dvec3() - s.center.as_dvec3()).length() - 3.0;
        assert!(d.abs() <= sp.error.length() as f64, "{d} vs {}", sp.error);
        assert!(sp.error.max_element() > 0.0);
        assert!((sp.n.length() - 1.0).abs() < 1e-6);
    }

    /// The surface point's box holds the exact sphere along the normal and
    /// is within a few roundings of the coordinates' size, for spheres
    /// 10⁻³..10³ across and 10⁻³..10⁵ from the origin, hit from outside and
    /// from inside; the normal is the exact outward one.
    #[test]
    fn surface_points_lie_in_tight_error_boxes() {
        let mut g = Lcg(5);
        let mut checked = 0;
        for i in 0..20_000 {
            let radius = 10f32.powi(i % 7 - 3);
            let far = 10f32.powi(i % 9 - 3);
            let s = Sphere {
                center: g.vec(2.0 * far),
                radius,
            };
            let target = s.center + g.vec(radius);
            let (from, dir) = if i % 3 == 0 {
                (target, g.vec(2.0))
            } else {
                let from = s.center + g.vec(2.0).normalize_or(Vec3::X) * radius * 3.0;
                (from, target - from)
            };
            let r = Ray::new(from, dir);
            let Some(t) = s.intersect(&r, 0.0, f32::INFINITY) else {
                continue;
            };
            let sp = s.surface(&r, t);
            // The box meets the exact sphere: the nearest point of the box
            // is no farther from the centre than the radius, the farthest
            // corner no nearer (exact for any box, even one as large as a
            // sphere below the rounding of its centre).
            let (c, p, e) = (s.center.as_dvec3(), sp.p.as_dvec3(), sp.error.as_dvec3());
            let what = format!("{s:?} {r:?}: p {} box {}", sp.p, sp.error);
            assert!(sp.error.min_element() >= 0.0, "{what}");
            let near = (c.clamp(p - e, p + e) - c).length();
            let far = (p - c).abs() + e;
            let rad = radius as f64;
            assert!(near <= rad && far.length() >= rad, "{what}: {near} {far}");
            let limit = gamma(8) * (s.center.abs() + Vec3::splat(radius));
            assert!(sp.error.cmple(limit).all(), "{what}: over {limit}");
            // The normal is the outward one, where f32 resolves the sphere
            // (a radius of a thousand ulps of the centre or more).
            if radius > 1e-4 * s.center.abs().max_element() {
                let out = (p - c).normalize();
                assert!(
                    (sp.n.as_dvec3() - out).length() < 1e-3,
                    "{what}: n {}",
                    sp.n
                );
            }
            checked += 1;
        }
        assert!(checked > 15_000, "{checked}");
    }

    /// The range is open at both ends: a root exactly at `tmin` or `tmax` is
    /// not reported (the next one is, if it is inside).
    #[test]
    fn roots_at_the_ends_of_the_range_are_excluded() {
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        let s = unit();
        assert_eq!(s.intersect(&r, 4.0, f32::INFINITY), Some(6.0));
        assert_eq!(s.intersect(&r, 4.0, 6.0), None);
        assert_eq!(s.intersect(&r, 0.0, 4.0), None);
        assert_eq!(s.intersect(&r, 0.0, 6.0), Some(4.0));
        assert_eq!(s.intersect(&r, 6.0, f32::INFINITY), None);
    }

    /// A sphere of radius 0 hit through its centre (the one ray that can
    /// hit it) gives its centre, not a NaN point.
    #[test]
    fn a_point_sphere_hit_at_its_centre_is_finite() {
        let s = Sphere {
            center: Vec3::new(1.0, 2.0, 3.0),
            radius: 0.0,
        };
        let r = Ray::new(Vec3::new(1.0, 2.0, -2.0), Vec3::Z);
        let t = s.intersect(&r, 0.0, f32::INFINITY).unwrap();
        assert_eq!(t, 5.0);
        let sp = s.surface(&r, t);
        assert_eq!(sp.p, s.center);
        assert!(sp.error.is_finite() && sp.n.is_finite());
    }
}
