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
        Ray::new(
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
    pub fn normal(&self, p: Vec3) -> Vec3 {
        let n_obj = self.shape.normal(self.to_object.transform_point3(p));
        self.to_object
            .transpose()
            .transform_vector3(n_obj)
            .normalize_or_zero()
    }

    /// World bounds, as tight as the shape allows: a triangle by its three
    /// transformed vertices (a rotated triangle's box is smaller than its
    /// rotated box), a sphere by the exact box of the ellipsoid it becomes;
    /// anything else by its object box's 8 transformed corners.
    pub fn bounds(&self) -> Aabb {
        match &self.shape {
            Shape::Triangle(t) => {
                Aabb::from_points(t.vertices().map(|p| self.to_world.transform_point3(p)))
            }
            Shape::Sphere(s) => {
                // Along axis i the ellipsoid reaches r·|row i| of the linear
                // part from its centre (the support function of a sphere
                // under a linear map).
                let m = &self.to_world;
                let half = Vec3::new(
                    m.row(0).truncate().length(),
                    m.row(1).truncate().length(),
                    m.row(2).truncate().length(),
                ) * s.radius.abs();
                let c = m.transform_point3(s.center);
                Aabb::new(c - half, c + half)
            }
            other => {
                let b = other.bounds();
                if b.is_finite() {
                    b.transformed(&self.to_world)
                } else {
                    b // an unbounded shape stays unbounded (and 0·inf would give NaN)
                }
            }
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
        let n = x.normal(p);
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
    fn triangle_box_uses_its_vertices() {
        let t = super::super::Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y);
        let m = Mat4::from_rotation_z(std::f32::consts::FRAC_PI_4);
        let x = Transformed::new(Shape::Triangle(t), m).unwrap();
        let corners = t.bounds().transformed(&m);
        let b = x.bounds();
        assert!(b.surface_area() < corners.surface_area());
        assert!((b.max.y - 2f32.sqrt() / 2.0).abs() < 1e-6);
        assert!((b.min.x + 2f32.sqrt() / 2.0).abs() < 1e-6);
    }

    #[test]
    fn sphere_box_is_the_ellipsoid_box() {
        let s = Sphere {
            center: Vec3::X,
            radius: 2.0,
        };
        let m = Mat4::from_rotation_z(std::f32::consts::FRAC_PI_4)
            * Mat4::from_scale(Vec3::new(3.0, 1.0, 1.0));
        let x = Transformed::new(Shape::Sphere(s), m).unwrap();
        let b = x.bounds();
        // x = (3u cos45 - v sin45), over the ellipse 3u, v of radius 2: 2·√(4.5 + 0.5).
        let c = m.transform_point3(Vec3::X);
        assert!((b.max.x - c.x - 2.0 * 5f32.sqrt()).abs() < 1e-5);
        assert!((b.max.z - c.z - 2.0).abs() < 1e-6);
        assert!(b.surface_area() < s.bounds().transformed(&m).surface_area());
        // Rays along the axes just inside the box hit, just outside miss.
        for k in 0..64 {
            let dir = Vec3::new((k as f32 * 0.1).cos(), (k as f32 * 0.1).sin(), 0.3);
            let far = c + dir.normalize() * 20.0;
            if let Some(t) = x.intersect(&Ray::new(far, c - far), 0.0, f32::INFINITY) {
                let p = far + t * (c - far);
                assert!(p.cmpge(b.min - 1e-4).all() && p.cmple(b.max + 1e-4).all());
            }
        }
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
