//! Shapes in world space: intersection (`t` only, the hot path), the normal at a
//! hit (computed once, for the closest hit), and bounds.
//!
//! A ray hits a shape at `t` only when `tmin < t < tmax`, strictly: a ray that
//! starts on a surface (after the origin offset) cannot re-hit it at `t = tmin`.

mod moving;
mod plane;
mod sphere;
mod transformed;
mod triangle;

pub use moving::Moving;
pub use plane::Plane;
pub use sphere::Sphere;
pub use transformed::Transformed;
pub use triangle::Triangle;

use crate::math::{Aabb, Ray, Vec3};

/// One intersectable shape of the world.
#[derive(Clone, Debug)]
pub enum Shape {
    /// A sphere in world space.
    Sphere(Sphere),
    /// An infinite plane.
    Plane(Plane),
    /// A triangle in world space.
    Triangle(Triangle),
    /// A shape that could not be baked into world space (a sphere under
    /// non-uniform scale): rays are carried into its space instead.
    Transformed(Box<Transformed>),
    /// A shape under a keyframed motion (motion blur): rays are carried into
    /// its space at their own time.
    Moving(Box<Moving>),
}

impl Shape {
    /// The nearest hit parameter in `(tmin, tmax)`, if any.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<f32> {
        match self {
            Shape::Sphere(s) => s.intersect(ray, tmin, tmax),
            Shape::Plane(p) => p.intersect(ray, tmin, tmax),
            Shape::Triangle(t) => t.intersect(ray, tmin, tmax),
            Shape::Transformed(x) => x.intersect(ray, tmin, tmax),
            Shape::Moving(m) => m.intersect(ray, tmin, tmax),
        }
    }

    /// Unit geometric normal at the point `p` of this shape's surface (outward
    /// for spheres, counter-clockwise front for triangles), at instant `time`
    /// (only moving shapes look at it).
    pub fn normal(&self, p: Vec3, time: f32) -> Vec3 {
        match self {
            Shape::Sphere(s) => s.normal(p),
            Shape::Plane(pl) => pl.normal,
            Shape::Triangle(t) => t.normal,
            Shape::Transformed(x) => x.normal(p, time),
            Shape::Moving(m) => m.normal(p, time),
        }
    }

    /// World-space bounds; infinite for planes.
    pub fn bounds(&self) -> Aabb {
        match self {
            Shape::Sphere(s) => s.bounds(),
            Shape::Plane(p) => p.bounds(),
            Shape::Triangle(t) => t.bounds(),
            Shape::Transformed(x) => x.bounds(),
            Shape::Moving(m) => m.bounds(),
        }
    }
}
