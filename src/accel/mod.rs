//! Aggregates: structures that find the closest hit among many primitives.
//! Every accelerator implements [`Aggregate`]; [`Brute`] is the baseline and
//! the oracle the property tests compare the others with.

mod brute;

pub use brute::Brute;

use crate::math::{Aabb, Ray};
use crate::stats::Counters;
use crate::world::Primitive;

/// The closest hit an aggregate found: parameter and primitive index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimHit {
    /// Ray parameter.
    pub t: f32,
    /// Index into the world's primitive list.
    pub prim: u32,
}

/// A structure over (a subset of) the world's primitives. The primitives are
/// passed in rather than owned so that every aggregate indexes the same list.
pub trait Aggregate: Send + Sync {
    /// Closest hit with `tmin < t < tmax`.
    fn intersect(
        &self,
        prims: &[Primitive],
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        counters: &mut Counters,
    ) -> Option<PrimHit>;

    /// Whether anything lies on the ray with `tmin < t < tmax` (stops at the
    /// first hit: shadow rays need no closest hit).
    fn occluded(
        &self,
        prims: &[Primitive],
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        counters: &mut Counters,
    ) -> bool;

    /// Bounds of everything inside.
    fn bounds(&self) -> Aabb;

    /// Name and parameters, for statistics (`"bvh-sah"`, `"grid 10x10x7"`).
    fn describe(&self) -> String;
}

/// Which aggregate to build.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AccelKind {
    /// Test every primitive.
    #[default]
    None,
}
