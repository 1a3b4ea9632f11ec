use super::Shape;
#[cfg(test)]
use super::Sphere;
use crate::math::{Aabb, Mat4, Ray, Vec3};

/// A shape seen through an affine matrix: used where baking into world space
/// is impossible (a sphere under non-uniform scale) or switched off. Rays go
/// into object space with the direction left unnormalised, so `t` is the same
/// in both spaces.
#[derive(Clone, Debug)]
pub struct Transformed {
    /// The shape in object space.
    pub shape: Shape,
    /// Object-to-world matrix.
    pub to_world: Mat4,
    /// World-to-object matrix.
    pub to_object: Mat4,
}

impl Transformed {
    /// Wraps `shape` under `to_world`; `None` when the matrix is singular.
    pub fn new(shape: Shape, to_world: Mat4) -> Option<Self> {
        let to_object = to_world.inverse();
        (to_object.is_finite() && to_world.determinant() != 0.0).then_some(Self {
            shape,
            to_world,
            to_object,
        })
    }

    fn object_ray(&self, ray: &Ray) -> Ray {
        ray.child(
            self.to_object.transform_point3(ray.origin),
            self.to_object.transform_vector3(ray.dir),
        )
    }

    /// Hit parameter (world `t`).
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<f32> {
        self.shape.intersect(&self.object_ray(ray), tmin, tmax)
    }

    /// World normal at world point `p`: the object normal carried by the
    /// inverse transpose, which keeps it perpendicular under non-uniform scale.
    pub fn normal(&self, p: Vec3, time: f32) -> Vec3 {
        let n_obj = self.shape.normal(self.to_object.transform_point3(p), time);
        self.to_object
            .transpose()
            .transform_vector3(n_obj)
            .normalize_or_zero()
    }

    /// The box of the object box's 8 transformed corners.
    pub fn bounds(&self) -> Aabb {
        let b = self.shape.bounds();
        if b.is_finite() {
            b.transformed(&self.to_world)
        } else {
            b // an unbounded shape stays unbounded (and 0·inf would give NaN)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn squashed_sphere_normal_is_perpendicular() {
        let s = Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        let m = Mat4::from_scale(Vec3::new(2.0, 0.5, 1.0));
        let x = Transformed::new(Shape::Sphere(s), m).unwrap();
        let r = Ray::new(Vec3::new(1.0, 5.0, 0.0), Vec3::NEG_Y);
        let t = x.intersect(&r, 0.0, f32::INFINITY).unwrap();
        let p = r.at(t);
        // On the ellipse x²/4 + y²/0.25 = 1 at x = 1: y = sqrt(0.75)/2.
        assert!((p.y - 0.75f32.sqrt() / 2.0).abs() < 1e-5);
        let n = x.normal(p, 0.0);
        // Gradient of x²/4 + 4y²: (x/2, 8y, 0).
        let g = Vec3::new(p.x / 2.0, 8.0 * p.y, 0.0).normalize();
        assert!((n - g).length() < 1e-5);
    }

    #[test]
    fn rotated_and_translated_t_is_world_t() {
        let s = Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        let m = Mat4::from_translation(Vec3::new(0.0, 0.0, -5.0))
            * Mat4::from_rotation_y(0.7)
            * Mat4::from_scale(Vec3::new(1.0, 3.0, 1.0));
        let x = Transformed::new(Shape::Sphere(s), m).unwrap();
        let r = Ray::new(Vec3::ZERO, Vec3::NEG_Z);
        let t = x.intersect(&r, 0.0, f32::INFINITY).unwrap();
        assert!((t - 4.0).abs() < 1e-5);
    }

    #[test]
    fn singular_matrix_is_rejected() {
        let s = Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        assert!(
            Transformed::new(Shape::Sphere(s), Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0)))
                .is_none()
        );
    }
}
