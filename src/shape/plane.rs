use crate::math::{Aabb, Mat4, Ray, Vec3};

/// The plane `normal · p = offset`, stored with a unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Unit normal.
    pub normal: Vec3,
    /// Signed distance of the plane from the origin along `normal`.
    pub offset: f32,
}

impl Plane {
    /// The plane `n · p = d` for any non-zero `n` (the file's convention).
    /// Returns `None` for a zero normal.
    pub fn new(n: Vec3, d: f32) -> Option<Self> {
        let len = n.length();
        (len > 0.0 && len.is_finite()).then(|| Self {
            normal: n / len,
            offset: d / len,
        })
    }

    /// The plane carried through an invertible affine matrix: the normal by the
    /// inverse transpose, a point of the plane by the matrix itself.
    pub fn transformed(&self, m: &Mat4) -> Option<Self> {
        let p = m.transform_point3(self.normal * self.offset);
        let n = m.inverse().transpose().transform_vector3(self.normal);
        let len = n.length();
        (len > 0.0 && len.is_finite()).then(|| {
            let n = n / len;
            Self {
                normal: n,
                offset: n.dot(p),
            }
        })
    }

    /// Hit parameter in `(tmin, tmax)`; rays parallel to the plane miss.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<f32> {
        let denom = self.normal.dot(ray.dir);
        if denom == 0.0 {
            return None;
        }
        let t = (self.offset - self.normal.dot(ray.origin)) / denom;
        (t > tmin && t < tmax).then_some(t)
    }

    /// Planes are unbounded, so they stay out of the acceleration structures
    /// and are tested on every ray. A plane whose normal lies exactly along an
    /// axis is still bounded along that one axis (its box is a slab of zero
    /// thickness), which is all a box can say about it.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::new(Vec3::NEG_INFINITY, Vec3::INFINITY);
        let n = self.normal;
        for axis in 0..3 {
            let others = (0..3).filter(|&a| a != axis).all(|a| n[a] == 0.0);
            if others && n[axis] != 0.0 {
                let at = self.offset / n[axis];
                b.min[axis] = at;
                b.max[axis] = at;
            }
        }
        b
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_is_in_units_of_the_given_normal() {
        let p = Plane::new(Vec3::new(0.0, 2.0, 0.0), 2.0).unwrap();
        let r = Ray::new(Vec3::new(0.0, 5.0, 0.0), Vec3::NEG_Y);
        assert!((p.intersect(&r, 0.0, f32::INFINITY).unwrap() - 4.0).abs() < 1e-6);
    }

    #[test]
    fn parallel_and_behind_miss() {
        let p = Plane::new(Vec3::Y, 0.0).unwrap();
        let par = Ray::new(Vec3::Y, Vec3::X);
        assert!(p.intersect(&par, 0.0, f32::INFINITY).is_none());
        let away = Ray::new(Vec3::Y, Vec3::Y);
        assert!(p.intersect(&away, 0.0, f32::INFINITY).is_none());
    }

    #[test]
    fn hit_from_below_has_same_normal() {
        let p = Plane::new(Vec3::Y, 1.0).unwrap();
        let r = Ray::new(Vec3::ZERO, Vec3::Y);
        assert!((p.intersect(&r, 0.0, f32::INFINITY).unwrap() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn axis_plane_is_bounded_along_its_normal_only() {
        let b = Plane::new(Vec3::new(0.0, -2.0, 0.0), 3.0).unwrap().bounds();
        assert_eq!((b.min.y, b.max.y), (-1.5, -1.5));
        assert!(b.min.x.is_infinite() && b.max.z.is_infinite());
        assert!(!b.is_finite());
        let tilted = Plane::new(Vec3::new(0.0, 1.0, 1.0), 1.0).unwrap().bounds();
        assert!(tilted.min.y.is_infinite() && tilted.min.z.is_infinite());
    }

    #[test]
    fn zero_normal_is_rejected() {
        assert!(Plane::new(Vec3::ZERO, 1.0).is_none());
    }

    #[test]
    fn transformed_plane() {
        let p = Plane::new(Vec3::Y, 1.0).unwrap();
        let m = Mat4::from_translation(Vec3::new(0.0, 2.0, 0.0))
            * Mat4::from_rotation_z(std::f32::consts::FRAC_PI_2);
        let q = p.transformed(&m).unwrap();
        // y = 1 rotated by 90° about z becomes x = -1, then moved up (no effect on x).
        assert!((q.normal - Vec3::NEG_X).length() < 1e-6);
        assert!((q.offset - 1.0).abs() < 1e-6);
    }
}
