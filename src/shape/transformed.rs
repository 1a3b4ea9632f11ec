use super::Shape;
#[cfg(test)]
use super::Sphere;
use crate::math::float::{abs_linear, transform_error, transform_point_with_error};
use crate::math::{gamma, Aabb, Mat4, Ray, SurfacePoint, Vec3};
use glam::DMat4;

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
        Self::from_f64(shape, to_world.as_dmat4())
    }

    /// Wraps `shape` under `to_world` given in f64 (the inverse is taken in
    /// f64 too, then both are rounded); `None` when the matrix is singular
    /// or does not fit in f32.
    pub fn from_f64(shape: Shape, to_world: DMat4) -> Option<Self> {
        let to_object = to_world.inverse();
        let (w, o) = (to_world.as_mat4(), to_object.as_mat4());
        (to_world.determinant() != 0.0 && w.is_finite() && o.is_finite() && w.determinant() != 0.0)
            .then_some(Self {
                shape,
                to_world: w,
                to_object: o,
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

    /// The hit at (world) parameter `t`: the object-space hit carried to
    /// world space with its error (pbrt's transform of a point with error),
    /// and the normal by the inverse transpose, which keeps it perpendicular
    /// under non-uniform scale.
    ///
    /// The bound has one more term: a ray spawned from this point is carried
    /// back into object space by `to_object`, which rounds its origin again,
    /// by up to `γ(3)·(|M⁻¹|·|p| + |t⁻¹|)` in object space. That amount,
    /// carried forward by `|M|`, is added, so the offset along the normal
    /// also covers the trip back.
    pub fn surface(&self, ray: &Ray, t: f32) -> SurfacePoint {
        let obj = self.shape.surface(&self.object_ray(ray), t);
        let (p, err) = transform_point_with_error(&self.to_world, obj.p, obj.error);
        let back =
            (1.0 + gamma(3)) * (abs_linear(&self.to_world) * transform_error(&self.to_object, p));
        SurfacePoint {
            p,
            error: err + back,
            n: self
                .to_object
                .transpose()
                .transform_vector3(obj.n)
                .normalize_or_zero(),
        }
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
    use crate::math::Vec3;

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
        let n = x.surface(&r, t).n;
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

    #[test]
    fn surface_error_covers_the_distance_to_the_exact_surface() {
        let s = Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        let m = Mat4::from_translation(Vec3::new(3e4, -2e3, 7e3))
            * Mat4::from_rotation_x(0.4)
            * Mat4::from_scale(Vec3::new(40.0, 3.0, 15.0));
        let x = Transformed::new(Shape::Sphere(s), m).unwrap();
        let mut checked = 0;
        for k in 0..64 {
            let a = k as f32 * 0.37;
            let target = m.transform_point3(Vec3::new(a.cos() * 0.5, a.sin() * 0.5, 0.2));
            let from = target + Vec3::new(a.sin() * 300.0, 200.0, a.cos() * 300.0);
            let r = Ray::new(from, target - from);
            let Some(t) = x.intersect(&r, 0.0, f32::INFINITY) else {
                continue;
            };
            let sp = x.surface(&r, t);
            // The surface point radially below (in object space), exactly.
            let md = m.as_dmat4();
            let q = md.inverse().transform_point3(sp.p.as_dvec3());
            let on = md.transform_point3(q / q.length());
            let n = sp.n.as_dvec3();
            let along = n.dot(sp.p.as_dvec3() - on).abs();
            assert!(
                along <= n.abs().dot(sp.error.as_dvec3()),
                "{along} vs {}",
                sp.error
            );
            checked += 1;
        }
        assert!(checked > 50);
    }

    /// A matrix that does not fit in f32, or whose inverse does not, is
    /// rejected (the shape would be drawn through infinities); a matrix of
    /// extreme but representable scales is kept.
    #[test]
    fn matrices_beyond_f32_are_rejected() {
        let s = Shape::Sphere(Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        });
        let scale = |x, y| DMat4::from_scale(glam::DVec3::new(x, y, 1.0));
        assert!(Transformed::from_f64(s.clone(), scale(1e39, 1.0)).is_none());
        assert!(Transformed::from_f64(s.clone(), scale(1e-39, 1e30)).is_none());
        assert!(Transformed::from_f64(s, scale(1e-20, 1e20)).is_some());
    }
}
