//! Vectors and matrices (re-exported from glam), rays, boxes, and the
//! floating-point error bounds and ray spawning that keep secondary rays off
//! the surface they leave (see `docs/numerics.md`).

mod aabb;
pub mod float;
mod motion;
mod ray;
mod spawn;
#[cfg(test)]
pub(crate) mod testing;
pub mod warp;

pub use aabb::Aabb;
pub use float::gamma;
pub use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec4};
pub use motion::{Keyframe, Motion, SWEEP_STEPS};
pub use ray::{Ray, SurfacePoint, SHADOW_EPSILON};
pub use spawn::Spawn;
