use super::Shape;
use crate::math::{Aabb, Mat4, Motion, Ray, Vec3};
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

    /// Hit parameter (world `t`) of `ray` at `ray.time`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<f32> {
        let m = self.to_object(ray.time);
        let local = ray.child(m.transform_point3(ray.origin), m.transform_vector3(ray.dir));
        self.shape.intersect(&local, tmin, tmax)
    }

    /// World normal at world point `p` at `time` (inverse transpose, as for
    /// [`super::Transformed`]).
    pub fn normal(&self, p: Vec3, time: f32) -> Vec3 {
        let m = self.to_object(time);
        let n_obj = self.shape.normal(m.transform_point3(p), time);
        m.transpose().transform_vector3(n_obj).normalize_or_zero()
    }

    /// Box of the whole path.
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Keyframe, Quat};
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
        let n = m.normal(r.at(t), 0.5);
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
        assert!((m.normal(Vec3::ZERO, 0.0) - Vec3::Z).length() < 1e-5);
        assert!((m.normal(Vec3::ZERO, 1.0) + Vec3::Z).length() < 1e-5);
    }
}
