use crate::math::{Aabb, Ray, Vec3};

/// A triangle with its edges and unit normal precomputed (Möller–Trumbore
/// needs the edges on every test; the normal is needed once per hit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// First vertex.
    pub v0: Vec3,
    /// `v1 - v0`.
    pub e1: Vec3,
    /// `v2 - v0`.
    pub e2: Vec3,
    /// Unit normal of the counter-clockwise front; zero for a degenerate triangle.
    pub normal: Vec3,
}

impl Triangle {
    /// A triangle from its vertices.
    pub fn new(v0: Vec3, v1: Vec3, v2: Vec3) -> Self {
        let e1 = v1 - v0;
        let e2 = v2 - v0;
        Self {
            v0,
            e1,
            e2,
            normal: e1.cross(e2).normalize_or_zero(),
        }
    }

    /// The three vertices.
    pub fn vertices(&self) -> [Vec3; 3] {
        [self.v0, self.v0 + self.e1, self.v0 + self.e2]
    }

    /// Möller–Trumbore. Degenerate triangles (zero normal) never report a hit,
    /// so no NaN normal can reach shading.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<f32> {
        let p = ray.dir.cross(self.e2);
        let det = self.e1.dot(p);
        if det == 0.0 || !det.is_finite() || self.normal == Vec3::ZERO {
            return None;
        }
        let inv = 1.0 / det;
        let s = ray.origin - self.v0;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(self.e1);
        let v = ray.dir.dot(q) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = self.e2.dot(q) * inv;
        (t > tmin && t < tmax).then_some(t)
    }

    /// Bounding box of the three vertices.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.vertices())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> Triangle {
        Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)
    }

    #[test]
    fn hit_inside() {
        let r = Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z);
        assert!((tri().intersect(&r, 0.0, f32::INFINITY).unwrap() - 1.0).abs() < 1e-6);
        assert_eq!(tri().normal, Vec3::Z);
    }

    #[test]
    fn hit_from_behind_too() {
        let r = Ray::new(Vec3::new(0.25, 0.25, -1.0), Vec3::Z);
        assert!(tri().intersect(&r, 0.0, f32::INFINITY).is_some());
    }

    #[test]
    fn miss_outside_and_behind_origin() {
        let r = Ray::new(Vec3::new(0.75, 0.75, 1.0), Vec3::NEG_Z);
        assert!(tri().intersect(&r, 0.0, f32::INFINITY).is_none());
        let r = Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::Z);
        assert!(tri().intersect(&r, 0.0, f32::INFINITY).is_none());
    }

    #[test]
    fn edge_on_ray_misses() {
        let r = Ray::new(Vec3::new(-1.0, 0.25, 0.0), Vec3::X);
        assert!(tri().intersect(&r, 0.0, f32::INFINITY).is_none());
    }

    #[test]
    fn degenerate_never_hits() {
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0);
        assert_eq!(t.normal, Vec3::ZERO);
        let r = Ray::new(Vec3::new(0.5, 0.0, 1.0), Vec3::NEG_Z);
        assert!(t.intersect(&r, 0.0, f32::INFINITY).is_none());
    }
}
