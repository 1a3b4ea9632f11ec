//! A primitive: one shape of the world with its material and the object space
//! it came from. It sits between `shape` and `accel` so that dependencies point
//! one way: accelerators index primitives, the world owns them.

use crate::math::Aabb;
use crate::shape::Shape;

/// A shape with its material and the object space it came from.
#[derive(Clone, Debug)]
pub struct Primitive {
    /// World-space geometry.
    pub shape: Shape,
    /// Index into the world's material table (`World::materials`).
    pub material: u32,
    /// Index into `World::object_from_world`: the object space the shape
    /// came from, kept although its geometry was baked into world space.
    /// The 6.837 textures do *not* use it (their matrices map world points,
    /// see `material::eval`); it is there for object-space lookups.
    pub instance: u32,
}

impl Primitive {
    /// World-space bounds.
    pub fn bounds(&self) -> Aabb {
        self.shape.bounds()
    }
}
