//! Aggregates: structures that find the closest hit among many primitives.
//! Every accelerator implements [`Aggregate`]; [`Brute`] is the baseline and
//! the oracle the property tests compare the others with.
//!
//! | module      | structure                                   | traversal                     |
//! |-------------|---------------------------------------------|-------------------------------|
//! | `brute`     | a list                                      | test everything               |
//! | [`grid`]    | uniform grid, cells as offsets + flat list  | 3DDDA, an iterator of cells   |
//! | [`octree`]  | adaptive grid, primitives in the leaves     | front-to-back, an iterator of leaves |
//! | [`bvh`]     | binary BVH (midpoint, median or binned SAH) | stack, nearer child first     |
//! | [`nested_grid`] | coarse grid, crowded cells hold finer grids | 3DDDA at each level       |
//! | [`hierarchy`] | BVH of the scene's own groups and transforms | stack, nearest entry first  |
//! | [`bvh8`]    | 8-wide BVH, 4-triangle leaf blocks (default) | 8 boxes per step, nearest first |
//!
//! Three rules every accelerator follows, so that each returns *exactly* the
//! hit brute force returns:
//! - **The closest hit is kept across cells.** A primitive tested in one cell
//!   can hit beyond that cell; the hit is kept as the current best (and shrinks
//!   the ray's `tmax`), and the walk stops only once the best hit lies inside
//!   the cell just finished (`t <= t_exit`). A hit beyond the cell is thus
//!   "not accepted yet", and the mailbox never hides a primitive whose hit
//!   was found early.
//! - **Boxes are padded** by a margin relative to the scene's magnitude
//!   (`overlap::margin`), so that a hit the shape test reports a few ulps
//!   outside its exact box (a triangle lying in a cell's face, a ray grazing a
//!   shared edge) is still inside every box and cell the traversal looks at.
//! - **Cell intervals are computed in `t`**, from the split planes, with one
//!   formula for the start cell and for every step, so consecutive cells share
//!   their boundary `t` exactly and none is skipped.

#[cfg(test)]
mod aggregate_tests;
mod brute;
pub mod bvh;
pub mod bvh8;
pub mod grid;
pub mod hierarchy;
mod kind;
mod mailbox;
pub mod nested_grid;
pub mod octree;
mod overlap;
#[cfg(test)]
pub(crate) mod testutil;
#[cfg(test)]
mod work_tests;

pub use brute::Brute;
pub use bvh::Bvh;
pub use bvh8::{Bvh8, PacketRay, PACKET};
pub use grid::Grid;
pub use hierarchy::{HierarchyBvh, SceneTree};
pub use kind::{AccelKind, ParseAccelError, Split};
pub use nested_grid::NestedGrid;
pub use octree::{Octree, Storage};

use crate::math::{Aabb, Ray};
use crate::primitive::Primitive;
use crate::stats::Counters;

/// The closest hit an aggregate found: parameter and primitive index.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrimHit {
    /// Ray parameter.
    pub t: f32,
    /// Index into the world's primitive list.
    pub prim: u32,
}

/// A closest hit with its barycentrics when the aggregate's own triangle
/// test found it (see [`Aggregate::intersect_barycentric`]).
pub type BaryHit = (PrimHit, Option<[f32; 3]>);

/// A ray query against an aggregate: the primitives it indexes, the ray,
/// and the open range `(tmin, tmax)` a hit must lie in.
#[derive(Clone, Copy, Debug)]
pub struct Query<'a> {
    /// The world's primitive list (aggregates hold indices into it).
    pub prims: &'a [Primitive],
    /// The ray.
    pub ray: &'a Ray,
    /// Hits lie beyond this.
    pub tmin: f32,
    /// Hits lie before this.
    pub tmax: f32,
    /// A hint, never a change of answer: the ray is one of a run traced
    /// one after another whose directions mostly keep their signs (a
    /// tile's camera rays in scan order). `bvh8` then walks it with a copy
    /// of its closest-hit walk compiled for the ray's octant, which is
    /// faster for such runs and slower where the octant changes from one
    /// ray to the next (see `docs/performance.md`). Other aggregates ignore
    /// it.
    pub coherent: bool,
}

impl<'a> Query<'a> {
    /// `ray` against `prims` in `(tmin, tmax)`, not [`coherent`](Self::coherent).
    pub fn new(prims: &'a [Primitive], ray: &'a Ray, tmin: f32, tmax: f32) -> Self {
        Self {
            prims,
            ray,
            tmin,
            tmax,
            coherent: false,
        }
    }

    /// The same query with the [`coherent`](Self::coherent) hint set to
    /// `coherent`.
    pub fn with_coherent(self, coherent: bool) -> Self {
        Self { coherent, ..self }
    }

    /// The same query up to `tmax`.
    pub fn until(self, tmax: f32) -> Self {
        Self { tmax, ..self }
    }

    /// Whether primitive `id` lies on the ray in `(tmin, tmax)`, and where.
    #[inline]
    pub(crate) fn hit(&self, id: u32) -> Option<f32> {
        self.prims[id as usize]
            .shape
            .intersect(self.ray, self.tmin, self.tmax)
    }
}

/// A structure over (a subset of) the world's primitives. The primitives are
/// passed in rather than owned so that every aggregate indexes the same list.
pub trait Aggregate: Send + Sync {
    /// Closest hit of query `q`.
    fn intersect(&self, q: Query, counters: &mut Counters) -> Option<PrimHit>;

    /// [`intersect`](Self::intersect), with the barycentrics of the hit
    /// when it is a triangle and the aggregate's own test produced them
    /// (`None` otherwise). They are what `Triangle::hit` gives for the same
    /// ray, bit for bit (the same watertight test on the same vertices in
    /// the same order), so the world builds the surface point from them
    /// instead of re-running the test. The default has none.
    fn intersect_barycentric(
        &self,
        q: Query,
        counters: &mut Counters,
    ) -> Option<(PrimHit, Option<[f32; 3]>)> {
        self.intersect(q, counters).map(|h| (h, None))
    }

    /// Whether [`intersect_packet`](Self::intersect_packet) walks its rays
    /// together. When it does not (the default: ray by ray), a caller
    /// gains nothing by gathering rays into packets.
    fn walks_packets(&self) -> bool {
        false
    }

    /// [`intersect_barycentric`](Self::intersect_barycentric) of each ray
    /// of a packet (at most [`PACKET`]) against `prims`, into
    /// `out[..rays.len()]`: each ray's answer alone, bit for bit. The
    /// default asks ray by ray; the wide BVH walks the packet together
    /// (`Bvh8::closest_packet`).
    fn intersect_packet(
        &self,
        prims: &[Primitive],
        rays: &[PacketRay],
        out: &mut [Option<BaryHit>],
        counters: &mut Counters,
    ) {
        for (q, o) in rays.iter().zip(out) {
            *o = self.intersect_barycentric(Query::new(prims, &q.ray, q.tmin, q.tmax), counters);
        }
    }

    /// Whether anything lies on the ray of `q` in its range (stops at the
    /// first hit: shadow rays need no closest hit).
    fn occluded(&self, q: Query, counters: &mut Counters) -> bool;

    /// [`occluded`](Self::occluded) for a ray that primitive `except`
    /// cannot block (a flat primitive the ray leaves: see
    /// `World::occluded_leaving`), so an aggregate may skip testing it. The
    /// default tests it anyway, which gives the same answer.
    fn occluded_except(&self, q: Query, except: u32, counters: &mut Counters) -> bool {
        let _ = except;
        self.occluded(q, counters)
    }

    /// [`occluded_except`](Self::occluded_except) of each ray of a packet
    /// (at most [`PACKET`]) against `prims`: bit `r` set when something
    /// blocks ray `r`, each ray's answer alone. `except` is empty or holds
    /// one primitive per ray that cannot block it ([`u32::MAX`] for none:
    /// [`occluded`](Self::occluded)). The default asks ray by ray, with the
    /// same statistics; the wide BVH walks the packet together
    /// (`Bvh8::any_packet`, counting each node once for the packet).
    fn occluded_packet(
        &self,
        prims: &[Primitive],
        rays: &[PacketRay],
        except: &[u32],
        counters: &mut Counters,
    ) -> u32 {
        let mut blocked = 0;
        for (r, q) in rays.iter().enumerate() {
            let q = Query::new(prims, &q.ray, q.tmin, q.tmax);
            let b = match except.get(r) {
                Some(&i) if i != u32::MAX => self.occluded_except(q, i, counters),
                _ => self.occluded(q, counters),
            };
            blocked |= u32::from(b) << r;
        }
        blocked
    }

    /// Bounds of everything inside.
    fn bounds(&self) -> Aabb;

    /// Name and parameters, for statistics (`"bvh-sah"`, `"grid 10x10x7"`).
    fn describe(&self) -> String;

    /// Bytes of the structure itself (nodes, cells, id lists; not the
    /// primitives), for `glint bench`. Required: a default of 0 let the
    /// fast BVH report no memory at all (a mutation run found it).
    fn memory_bytes(&self) -> usize;
}
