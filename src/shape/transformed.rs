use super::Shape;
#[cfg(test)]
use super::Sphere;
use crate::math::float::{abs_linear, transform_error, transform_point_with_error};
use crate::math::{gamma, Aabb, Mat4, Ray, SurfacePoint};
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
}
