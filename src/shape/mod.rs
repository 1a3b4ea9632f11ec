//! Shapes in world space: intersection (`t` only, the hot path), the surface
//! point at a hit with its floating-point error bound and normal (computed
//! once, for the closest hit), and bounds.
//!
//! A ray hits a shape at `t` only when `tmin < t < tmax`, strictly. Secondary
//! rays start outside the error box of the point they leave
//! ([`crate::math::SurfacePoint`]), so they cannot re-hit its surface there.

mod moving;
mod plane;
mod sphere;
mod transformed;
mod triangle;
mod triangle4;
mod triangle4_avx;
mod triangle8_avx;

pub use moving::Moving;
pub use plane::Plane;
pub use sphere::Sphere;
pub use transformed::Transformed;
pub use triangle::{
    intersect_triangle, is_degenerate_triangle, Triangle, TriangleHit, WatertightRay,
};
pub use triangle4::{may_hit4, RaySpace4, WatertightRay4};
#[cfg(target_arch = "x86_64")]
pub use triangle4_avx::hit4_avx;
pub use triangle4_avx::Hits4;
#[cfg(target_arch = "x86_64")]
pub use triangle8_avx::hit8_avx;
pub use triangle8_avx::{Hits8, WatertightRay8, F8};

use crate::math::{Aabb, Ray, SurfacePoint};

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

    /// The hit at parameter `t` of `ray` (a `t` this shape reported): the
    /// point, a conservative bound on its floating-point error, and the unit
    /// geometric normal (outward for spheres, counter-clockwise front for
    /// triangles). Computed once, for the closest hit.
    pub fn surface(&self, ray: &Ray, t: f32) -> SurfacePoint {
        match self {
            Shape::Sphere(s) => s.surface(ray, t),
            Shape::Plane(pl) => pl.surface(ray, t),
            Shape::Triangle(tr) => tr.surface(ray, t),
            Shape::Transformed(x) => x.surface(ray, t),
            Shape::Moving(m) => m.surface(ray, t),
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
