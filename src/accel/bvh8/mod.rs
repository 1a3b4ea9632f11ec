//! The fast BVH, glint's default accelerator: 8-wide nodes tested with
//! 8-lane box tests, leaves of four-triangle blocks (a 4-lane pre-test, then
//! the shared watertight test on the lanes it could not rule out), binned
//! SAH built in parallel.
//!
//! - `node.rs`: the layout (`Node`: eight boxes in structure-of-arrays form,
//!   256 bytes; `Tri4`: four triangles' vertices, 160 bytes) and prefetch;
//!   `lanes.rs`: the eight-lane arithmetic of the box test.
//! - `build.rs`: binned SAH (32 bins, costs counted in blocks of four),
//!   children built in parallel above 4k items, a branch-free partition
//!   for unordered ranges, leaves filled last.
//! - `traverse.rs`: per-ray constants (inverse direction, octant, shear),
//!   nearest-child-first closest hit, any hit from the far side of each
//!   node's first division (`Node::split`) with early exit.
//! - `packet.rs`: up to eight rays walked together (one box test per node
//!   for the packet), each with the hit its own walk finds, bit for bit.
//! - `dispatch.rs`: the traversal compiled for SSE2 and for AVX2 with FMA, picked at
//!   run time; `pages.rs`: the large arrays on transparent huge pages.
//!
//! Of two items hit at the very same `t`, every walk keeps the one with the
//! smaller id (`traverse::closer`), as brute force does: the closest hit
//! depends on the ray and the items only, not on the order of the visit.
//!
//! What it shares with the textbook [`Bvh`](super::Bvh): the padding rule
//! (boxes grown by `overlap::margin`) and the triangle arithmetic
//! (`shape::intersect_triangle`, the watertight test; `shape::may_hit4` only
//! drops lanes that test provably rejects), which is why it returns exactly
//! brute force's hits. Non-triangle primitives (spheres, transformed shapes)
//! sit in the same leaves and are tested one at a time.
//!
//! The SIMD is glam's `Vec4` (SSE2 on x86-64, scalar elsewhere; two of them
//! for eight lanes), stable
//! Rust. `unsafe` appears in four places, each with its soundness argument:
//! the prefetch hint (`node.rs`), `madvise` (`pages.rs`), the call of the
//! AVX2 copy after the CPU check (`dispatch.rs`) and the build's SSE2 bin
//! conversion (`build.rs`); each has a portable path.

mod build;
mod dispatch;
mod lanes;
mod node;
mod packet;
mod pages;
mod traverse;

pub use packet::{PacketRay, PACKET};
pub use traverse::{Fallback, TrianglesOnly};

use dispatch::{AnyHit, AnyHits, ClosestHit, ClosestHits, FromClosest};
use std::marker::PhantomData;
use traverse::Tree;

use super::{Aggregate, PrimHit, Query};
use crate::math::{Aabb, Ray, Vec3};
use crate::primitive::Primitive;
use crate::shape::{is_degenerate_triangle, Shape};
use crate::stats::{Counters, TraversalStats};
use build::{Item, Source};
pub(crate) use node::Node;
use node::{Tri4, NO_ITEM};

/// The fast BVH (8-wide nodes; the name predates them) over triangles
/// (and, through a [`Fallback`], other shapes).
pub struct Bvh8 {
    nodes: Vec<Node>,
    tris: Vec<Tri4>,
    bounds: Aabb,
    /// Deeper than `traverse::SHALLOW_DEPTH`: needs the large stack.
    deep: bool,
}

/// The world's bounded primitives as a build source.
struct Prims<'a> {
    prims: &'a [Primitive],
    ids: &'a [u32],
}

impl Source for Prims<'_> {
    fn count(&self) -> usize {
        self.ids.len()
    }
    fn id(&self, k: usize) -> u32 {
        self.ids[k]
    }
    fn item(&self, id: u32) -> Item {
        match &self.prims[id as usize].shape {
            Shape::Triangle(t) if t.is_degenerate() => Item::Skip,
            Shape::Triangle(t) => Item::Triangle(t.v),
            other => Item::Other(other.bounds()),
        }
    }
    fn vertices(&self, id: u32) -> [Vec3; 3] {
        match &self.prims[id as usize].shape {
            Shape::Triangle(t) => t.v,
            _ => unreachable!("only triangles are asked for their vertices"),
        }
    }
}

/// An indexed triangle mesh as a build source (ids are triangle indices).
struct IndexedMesh<'a, V> {
    vertices: &'a [V],
    indices: &'a [[u32; 3]],
}

impl<V: Copy + Into<Vec3> + Sync> Source for IndexedMesh<'_, V> {
    fn count(&self) -> usize {
        self.indices.len()
    }
    fn id(&self, k: usize) -> u32 {
        k as u32
    }
    fn item(&self, id: u32) -> Item {
        let [a, b, c] = self.indices[id as usize].map(|i| self.vertices[i as usize].into());
        // The same degeneracy rule as the world's triangles.
        if is_degenerate_triangle(a, b, c) {
            Item::Skip
        } else {
            Item::Triangle([a, b, c])
        }
    }
    fn vertices(&self, id: u32) -> [Vec3; 3] {
        self.indices[id as usize].map(|i| self.vertices[i as usize].into())
    }
    fn prefetch(&self, id: u32) {
        // The indices are read (a miss waits for nothing but these hints).
        if let Some(t) = self.indices.get(id as usize) {
            for &i in t {
                if let Some(v) = self.vertices.get(i as usize) {
                    node::prefetch(v);
                }
            }
        }
    }
}

impl Fallback for [Primitive] {
    #[inline]
    fn intersect(&self, id: u32, ray: &Ray, tmin: f32, tmax: f32) -> Option<f32> {
        self[id as usize].shape.intersect(ray, tmin, tmax)
    }
}

impl Bvh8 {
    /// A BVH over the primitives `ids` of `prims`.
    pub fn new(prims: &[Primitive], ids: Vec<u32>) -> Self {
        Self::from_built(build::build(&Prims { prims, ids: &ids }))
    }

    /// A BVH over an indexed triangle mesh; hits report triangle indices.
    /// Indices must be in range (`query::MeshScene` checks them).
    pub(crate) fn from_mesh<V: Copy + Into<Vec3> + Sync>(
        vertices: &[V],
        indices: &[[u32; 3]],
    ) -> Self {
        Self::from_built(build::build(&IndexedMesh { vertices, indices }))
    }

    fn from_built(b: build::Built) -> Self {
        Bvh8 {
            deep: b.depth > traverse::SHALLOW_DEPTH,
            nodes: b.nodes,
            tris: b.tris,
            bounds: b.bounds,
        }
    }

    /// Bytes held by nodes and triangle blocks.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(&self.nodes[..]) + std::mem::size_of_val(&self.tris[..])
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The tree for a walk, with `fallback` testing the items that are not
    /// triangles.
    fn tree<'a, F: ?Sized>(&'a self, fallback: &'a F) -> Tree<'a, F> {
        Tree {
            nodes: &self.nodes,
            tris: &self.tris,
            fallback,
            deep: self.deep,
        }
    }

    /// Closest hit `(t, id)` with `tmin < t < tmax`; non-triangle items are
    /// tested by `fallback`, statistics go to `stats` (`NoStats`: none).
    #[inline]
    pub fn closest<S: TraversalStats, F: Fallback + ?Sized>(
        &self,
        fallback: &F,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        stats: &mut S,
    ) -> Option<(f32, u32)> {
        self.closest_hit(fallback, ray, tmin, tmax, stats)
            .map(|h| (h.t, h.id))
    }

    /// [`closest`](Self::closest) of a ray from a coherent run (see
    /// [`Query::coherent`]): the same hit.
    #[inline]
    pub fn closest_coherent<S: TraversalStats, F: Fallback + ?Sized>(
        &self,
        fallback: &F,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        stats: &mut S,
    ) -> Option<(f32, u32)> {
        let q = Query::new(&[], ray, tmin, tmax).with_coherent(true);
        (self.closest_query::<S, F, traverse::Closest>(fallback, &q, stats)).map(|h| (h.t, h.id))
    }

    /// [`closest`](Self::closest) with a triangle hit's barycentrics.
    #[inline]
    pub(crate) fn closest_hit<S: TraversalStats, F: Fallback + ?Sized>(
        &self,
        fallback: &F,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        stats: &mut S,
    ) -> Option<traverse::Closest> {
        self.closest_query(fallback, &Query::new(&[], ray, tmin, tmax), stats)
    }

    /// [`closest_hit`](Self::closest_hit) of `query`'s ray and range (its
    /// `prims` unused: `fallback` tests the other items), as an `H`.
    #[inline]
    fn closest_query<S: TraversalStats, F: Fallback + ?Sized, H: FromClosest>(
        &self,
        fallback: &F,
        query: &Query,
        stats: &mut S,
    ) -> Option<H> {
        let tree = self.tree(fallback);
        let hit = PhantomData;
        if query.coherent {
            return dispatch::run(ClosestHit::<_, _, _, true> {
                tree,
                query,
                stats,
                hit,
            });
        }
        dispatch::run(ClosestHit::<_, _, _, false> {
            tree,
            query,
            stats,
            hit,
        })
    }

    /// Whether anything lies on the ray with `tmin < t < tmax`.
    #[inline]
    pub fn any<S: TraversalStats, F: Fallback + ?Sized>(
        &self,
        fallback: &F,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        stats: &mut S,
    ) -> bool {
        self.any_except(fallback, ray, tmin, tmax, NO_ITEM, stats)
    }

    /// [`any`](Self::any) without testing triangle `skip`, which the caller
    /// knows cannot block the ray (see `Aggregate::occluded_except`).
    #[inline]
    pub(crate) fn any_except<S: TraversalStats, F: Fallback + ?Sized>(
        &self,
        fallback: &F,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        skip: u32,
        stats: &mut S,
    ) -> bool {
        self.any_query(fallback, &Query::new(&[], ray, tmin, tmax), skip, stats)
    }

    /// [`any_except`](Self::any_except) of `query`'s ray and range (see
    /// [`closest_query`](Self::closest_query)).
    #[inline]
    fn any_query<S: TraversalStats, F: Fallback + ?Sized>(
        &self,
        fallback: &F,
        query: &Query,
        skip: u32,
        stats: &mut S,
    ) -> bool {
        let tree = self.tree(fallback);
        dispatch::run(AnyHit {
            tree,
            query,
            skip,
            stats,
        })
    }

    /// The closest hit `(t, id)` of each ray of a packet (at most
    /// [`PACKET`] rays; `out[..rays.len()]` receives them): the same hits
    /// as [`closest`](Self::closest) for each ray alone, bit for bit, for
    /// fewer node loads when the rays go the same way (a tile's camera
    /// rays). Statistics count per ray, as the single walk does.
    pub fn closest_packet<S: TraversalStats, F: Fallback + ?Sized>(
        &self,
        fallback: &F,
        rays: &[PacketRay],
        out: &mut [Option<(f32, u32)>],
        stats: &mut S,
    ) {
        let mut hits = [None; PACKET];
        self.closest_hit_packet(fallback, rays, &mut hits, stats);
        for (o, h) in out.iter_mut().zip(&hits[..rays.len()]) {
            *o = h.map(|h| (h.t, h.id));
        }
    }

    /// [`closest_packet`](Self::closest_packet) with each triangle hit's
    /// barycentrics.
    ///
    /// # Panics
    /// If `rays` holds more than [`PACKET`] rays or `out` fewer than `rays`.
    #[inline]
    pub(crate) fn closest_hit_packet<S: TraversalStats, F: Fallback + ?Sized>(
        &self,
        fallback: &F,
        rays: &[PacketRay],
        out: &mut [Option<traverse::Closest>],
        stats: &mut S,
    ) {
        assert!(rays.len() <= PACKET && out.len() >= rays.len());
        let tree = self.tree(fallback);
        dispatch::run(ClosestHits {
            tree,
            rays,
            out,
            stats,
        })
    }

    /// Which rays of a packet (at most [`PACKET`]) something blocks: bit
    /// `r` for ray `r`, the answer [`any`](Self::any) gives for it alone.
    /// `skip` is empty or holds one triangle per ray that cannot block it
    /// (the one a shadow ray leaves; [`u32::MAX`] for none).
    ///
    /// # Panics
    /// If `rays` holds more than [`PACKET`] rays, or `skip` is neither
    /// empty nor as long as `rays`.
    pub fn any_packet<S: TraversalStats, F: Fallback + ?Sized>(
        &self,
        fallback: &F,
        rays: &[PacketRay],
        skip: &[u32],
        stats: &mut S,
    ) -> u32 {
        assert!(rays.len() <= PACKET && (skip.is_empty() || skip.len() == rays.len()));
        let tree = self.tree(fallback);
        dispatch::run(AnyHits {
            tree,
            rays,
            skip,
            stats,
        })
    }
}

impl Aggregate for Bvh8 {
    fn intersect(&self, q: Query, c: &mut Counters) -> Option<PrimHit> {
        self.closest_query(q.prims, &q, c)
    }

    fn intersect_barycentric(
        &self,
        q: Query,
        c: &mut Counters,
    ) -> Option<(PrimHit, Option<[f32; 3]>)> {
        self.closest_query(q.prims, &q, c)
    }

    fn walks_packets(&self) -> bool {
        true
    }

    fn intersect_packet(
        &self,
        prims: &[Primitive],
        rays: &[PacketRay],
        out: &mut [Option<super::BaryHit>],
        c: &mut Counters,
    ) {
        let mut hits = [None; PACKET];
        self.closest_hit_packet(prims, rays, &mut hits, c);
        for (o, h) in out.iter_mut().zip(&hits[..rays.len()]) {
            *o = h.map(|h| (PrimHit { t: h.t, prim: h.id }, h.bary));
        }
    }

    fn occluded(&self, q: Query, c: &mut Counters) -> bool {
        self.occluded_except(q, NO_ITEM, c)
    }

    fn occluded_packet(
        &self,
        prims: &[Primitive],
        rays: &[PacketRay],
        except: &[u32],
        c: &mut Counters,
    ) -> u32 {
        self.any_packet(prims, rays, except, c)
    }

    fn occluded_except(&self, q: Query, except: u32, c: &mut Counters) -> bool {
        self.any_query(q.prims, &q, except, c)
    }

    fn memory_bytes(&self) -> usize {
        Bvh8::memory_bytes(self)
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn describe(&self) -> String {
        format!(
            "bvh8 {} nodes, {} blocks",
            self.nodes.len(),
            self.tris.len()
        )
    }
}

#[cfg(test)]
mod tests;
