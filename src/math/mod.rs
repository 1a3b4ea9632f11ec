//! Vectors and matrices (re-exported from glam), rays, boxes and the
//! self-intersection offset shared by every shape.

mod aabb;
pub mod float;
mod ray;

pub use aabb::Aabb;
pub use float::gamma;
pub use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
pub use ray::{offset_origin, Ray};
