//! Vectors and matrices (re-exported from glam), rays, boxes and the
//! self-intersection offset shared by every shape.

mod aabb;
mod motion;
mod ray;

pub use aabb::Aabb;
pub use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec4};
pub use motion::{Keyframe, Motion, SWEEP_STEPS};
pub use ray::{offset_origin, Ray};
