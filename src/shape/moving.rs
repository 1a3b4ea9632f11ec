use super::Shape;
use crate::math::float::{abs_linear, transform_error, transform_point_with_error};
use crate::math::{gamma, Aabb, Mat4, Motion, Ray, SurfacePoint};
use std::sync::Arc;

/// A shape under a keyframed motion: at instant `t` its object-to-world
/// matrix is `parent · motion(t)`. Rays are carried into the shape's space
/// at their own time (direction unnormalised, so `t` is the world `t`); the
/// bounds cover the whole path, so accelerators need not know about time.
#[derive(Clone, Debug)]
pub struct Moving {
    /// The shape in the motion's object space (may itself move).
    pub shape: Shape,
    /// The keyframes, shared by every primitive of one moving object.
    pub motion: Arc<Motion>,
    /// Static object-to-world part applied after the motion.
    pub parent: Mat4,
    parent_inv: Mat4,
    bounds: Aabb,
}

impl Moving {
    /// `shape` moving by `motion` under the static `parent`; `None` when
    /// `parent` is singular.
    pub fn new(shape: Shape, motion: Arc<Motion>, parent: Mat4) -> Option<Self> {
        let parent_inv = parent.inverse();
        if !parent_inv.is_finite() || parent.determinant() == 0.0 {
            return None;
        }
        let bounds = motion.swept_bounds(&shape.bounds(), &parent);
        Some(Self {
            shape,
            motion,
            parent,
            parent_inv,
            bounds,
        })
    }

    /// World-to-object matrix at `time`.
    #[inline]
    fn to_object(&self, time: f32) -> Mat4 {
        self.motion.inverse_matrix(time) * self.parent_inv
    }

    /// World-to-object matrix at `time` (the one [`Self::intersect`] uses)
    /// and its inverse taken in f64 and rounded, so the pair agree as
    /// [`super::Transformed`]'s do.
    #[inline]
    fn matrices(&self, time: f32) -> (Mat4, Mat4) {
        let to_object = self.to_object(time);
        (to_object, to_object.as_dmat4().inverse().as_mat4())
    }

    /// `ray` carried into the shape's space at its own time.
    #[inline]
    fn object_ray(&self, ray: &Ray, to_object: &Mat4) -> Ray {
        ray.child(
            to_object.transform_point3(ray.origin),
            to_object.transform_vector3(ray.dir),
        )
    }

    /// Hit parameter (world `t`) of `ray` at `ray.time`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<f32> {
        let m = self.to_object(ray.time);
        self.shape.intersect(&self.object_ray(ray, &m), tmin, tmax)
    }

    /// The hit at (world) parameter `t` of `ray`, at `ray.time`: the
    /// object-space hit carried to world space through the matrix
    /// interpolated at that instant, with its error, as
    /// [`super::Transformed::surface`] does (including the term for the
    /// trip of a spawned ray's origin back into object space); the normal
    /// by the inverse transpose.
    pub fn surface(&self, ray: &Ray, t: f32) -> SurfacePoint {
        let (to_object, to_world) = self.matrices(ray.time);
        let obj = self.shape.surface(&self.object_ray(ray, &to_object), t);
        let (p, err) = transform_point_with_error(&to_world, obj.p, obj.error);
        let back = (1.0 + gamma(3)) * (abs_linear(&to_world) * transform_error(&to_object, p));
        SurfacePoint {
            p,
            error: err + back,
            n: to_object
                .transpose()
                .transform_vector3(obj.n)
                .normalize_or_zero(),
        }
    }

    /// Box of the whole path.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Keyframe, Quat, Vec3};
    use crate::shape::Sphere;

    fn slide() -> Moving {
        let motion = Motion::new(vec![
            Keyframe::identity(0.0),
            Keyframe {
                translation: Vec3::new(4.0, 0.0, 0.0),
                ..Keyframe::identity(1.0)
            },
        ])
        .unwrap();
        let s = Shape::Sphere(Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        });
        Moving::new(s, Arc::new(motion), Mat4::from_translation(Vec3::Z * -5.0)).unwrap()
    }

    #[test]
    fn hits_where_the_shape_is_at_the_ray_time() {
        let m = slide();
        let r = Ray::new(Vec3::new(2.0, 0.0, 0.0), Vec3::NEG_Z);
        assert!(m.intersect(&r, 0.0, f32::INFINITY).is_none());
        let t = m.intersect(&r.at_time(0.5), 0.0, f32::INFINITY).unwrap();
        assert!((t - 4.0).abs() < 1e-5);
        let n = m.surface(&r.at_time(0.5), t).n;
        assert!((n - Vec3::Z).length() < 1e-5);
        let b = m.bounds();
        assert!(b.min.x <= -1.0 && b.max.x >= 5.0 && b.max.z >= -4.0);
    }

    #[test]
    fn rotation_turns_the_normal() {
        let motion = Motion::new(vec![
            Keyframe::identity(0.0),
            Keyframe {
                rotation: Quat::from_rotation_y(std::f32::consts::PI),
                ..Keyframe::identity(1.0)
            },
        ])
        .unwrap();
        let tri = Shape::Triangle(super::super::Triangle::new(
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ));
        let m = Moving::new(tri, Arc::new(motion), Mat4::IDENTITY).unwrap();
        let r = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::NEG_Z);
        for (time, want) in [(0.0, Vec3::Z), (1.0, Vec3::NEG_Z)] {
            let r = r.at_time(time);
            let t = m.intersect(&r, 0.0, f32::INFINITY).unwrap();
            let s = m.surface(&r, t);
            assert!((s.n - want).length() < 1e-5, "{time}: {}", s.n);
            assert!(s.p.length() < 1e-5, "{}", s.p);
        }
    }
}
