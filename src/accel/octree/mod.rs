//! An octree: an adaptive grid whose crowded cells are halved again.
//!
//! - `build.rs`: when to split and which child gets which primitive.
//! - `traverse.rs`: [`LeafWalk`], the leaves a ray crosses, front to back.
//!
//! Each node is halved along its long axes (all three for a cube-like box:
//! eight children; `split_axes` says why thin axes are not split).
//!
//! **Storage policy: primitives live only in leaves, pushed down into every
//! child they overlap** (not kept at the intermediate level where they
//! straddle a split plane). Why: a primitive kept at an inner node would be
//! tested by every ray through that node, however far from it; and with all
//! primitives in leaves, a leaf's `[t_enter, t_exit]` bounds every hit the
//! ray can have there, which is what lets the walk stop at the first leaf
//! holding the closest hit, exactly as the grid does. The price, references
//! duplicated across leaves, is kept down by the exact triangle/sphere–box
//! test and the subdivision limits, and the mailbox keeps a duplicated
//! primitive from being tested twice by one ray.
//!
//! The other policy is there to measure it ([`Storage::Inner`],
//! `--accel octree-inner`): a primitive that overlaps more than one child
//! stays at the node, is tested when a ray enters the node (before its
//! children), and is never copied. The walk then also yields the inner nodes
//! that hold primitives, with `t_exit = t_enter`: after testing them only the
//! part of the ray before the node is known to be done, which keeps the early
//! exit exact.

mod build;
mod traverse;

pub use traverse::{Leaf, LeafWalk};

/// Where a primitive that straddles a split plane is stored.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Storage {
    /// Pushed down into every child it overlaps (the default).
    #[default]
    Leaves,
    /// Kept at the inner node where it straddles a split.
    Inner,
}

use super::mailbox::ItemTests;
use super::{Aggregate, PrimHit, Query};
use crate::math::{Aabb, Ray, Vec3};
use crate::primitive::Primitive;
use crate::stats::Counters;

/// A node holding at most this many primitives is not split.
pub const LEAF_SIZE: usize = 8;
/// Nodes at this depth (the root is 0) are not split: 8 levels give up to
/// 256 cells per axis where the scene is dense.
///
/// Between the two, a node is split only when the split pays (see
/// `build.rs`).
pub const MAX_DEPTH: u32 = 8;

/// One node of the flattened tree; its box is implicit (halving the root's).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Node {
    /// Children stored contiguously from `first`, one per combination of
    /// halves of the split `axes` (2, 4 or 8), in the order of [`slot`].
    Inner {
        /// Index of the first child.
        first: u32,
        /// Bit `a` set when the node is halved along axis `a`.
        axes: u8,
        /// First of the primitives kept at this node ([`Storage::Inner`]).
        start: u32,
        /// Number of primitives kept here (always 0 with [`Storage::Leaves`]).
        count: u32,
    },
    /// `items[start..start + count]`.
    Leaf {
        /// First item.
        start: u32,
        /// Number of items.
        count: u32,
    },
}

/// The axes a node with box `b` is halved along: those at least half as long
/// as its longest. Why not always all three: a flat scene's box is a thin
/// slab, and halving its thickness would copy every primitive into both
/// halves at every level (8^depth instead of 4^depth cells); elongated boxes
/// would likewise be sliced into ever thinner plates. This keeps cells close
/// to cubes, as a classic octree's are.
pub(crate) fn split_axes(b: &Aabb) -> u8 {
    let e = b.extent();
    let longest = e.max_element();
    (0..3)
        .filter(|&a| e[a] >= 0.5 * longest)
        .fold(0, |m, a| m | 1 << a)
}

/// The children of a node halved along `axes`, as child codes: bit `a` of a
/// code is set for the upper half along axis `a` (always 0 for an axis not
/// split). Ascending, which is also their storage order.
pub(crate) fn child_codes(axes: u8) -> impl Iterator<Item = usize> {
    (0..8).filter(move |c| c & !(axes as usize) == 0)
}

/// Where child `c` is stored, relative to the node's first child: the bits
/// of the split axes, packed.
#[inline]
pub(crate) fn slot(c: usize, axes: u8) -> usize {
    let mut s = 0;
    let mut j = 0;
    for a in 0..3 {
        if axes & (1 << a) != 0 {
            s |= ((c >> a) & 1) << j;
            j += 1;
        }
    }
    s
}

/// The box of child `c` of a node with box `b` halved along `axes`. Build
/// and traversal both derive boxes with this function, so they agree on
/// every split plane.
#[inline]
pub(crate) fn child_box(b: &Aabb, c: usize, axes: u8) -> Aabb {
    let mid = b.center();
    let bit = |m: usize, a: usize| m & (1 << a) != 0;
    let split = glam::BVec3::new(
        bit(axes as usize, 0),
        bit(axes as usize, 1),
        bit(axes as usize, 2),
    );
    let high = glam::BVec3::new(bit(c, 0), bit(c, 1), bit(c, 2)) & split;
    let low = split & !high;
    Aabb::new(
        Vec3::select(high, mid, b.min),
        Vec3::select(low, mid, b.max),
    )
}

/// An octree over the bounded primitives.
pub struct Octree {
    nodes: Vec<Node>,
    items: Vec<u32>,
    /// The padded box the root node covers.
    root: Aabb,
    /// Unpadded union of the primitives' boxes.
    bounds: Aabb,
    depth: u32,
    storage: Storage,
    /// References kept at inner nodes.
    inner_refs: usize,
}

impl Octree {
    /// An octree over the primitives `ids` of `prims`, primitives in leaves.
    pub fn new(prims: &[Primitive], ids: Vec<u32>) -> Self {
        build::build(prims, &ids, Storage::Leaves)
    }

    /// An octree with the given storage policy.
    pub fn with_storage(prims: &[Primitive], ids: Vec<u32>, storage: Storage) -> Self {
        build::build(prims, &ids, storage)
    }

    /// The leaves `ray` crosses within `[tmin, tmax]`, front to back.
    pub fn walk(&self, ray: &Ray, tmin: f32, tmax: f32) -> LeafWalk<'_> {
        LeafWalk::new(self, ray, tmin, tmax)
    }

    /// The closest hit, calling `visit` with every leaf the search walks, in
    /// order: the renderer's search itself ([`Aggregate::intersect`] passes
    /// a visitor that does nothing), which the traversal views record.
    pub fn intersect_visiting(
        &self,
        q: Query,
        c: &mut Counters,
        mut visit: impl FnMut(&Leaf),
    ) -> Option<PrimHit> {
        let mut tests = ItemTests::new(q, true);
        let mut walk = self.walk(q.ray, q.tmin, q.tmax);
        // Leaves come front to back: nothing later can beat a hit in one.
        for leaf in walk.by_ref() {
            visit(&leaf);
            if tests.closest_in(leaf.items, leaf.t_exit, c) {
                break;
            }
        }
        c.nodes_visited += walk.visited;
        tests.best()
    }

    /// The box the root covers (the primitives' bounds, padded).
    pub fn root_bounds(&self) -> Aabb {
        self.root
    }

    /// Nodes, inner and leaves.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// References kept at inner nodes (0 with [`Storage::Leaves`]).
    pub fn inner_references(&self) -> usize {
        self.inner_refs
    }

    /// References stored over all nodes.
    pub fn references(&self) -> usize {
        self.items.len()
    }

    /// Depth of the deepest leaf.
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// Every node's box, depth (the root is 0) and whether it is a leaf,
    /// parents before children: for drawing the structure.
    pub fn node_boxes(&self) -> Vec<(Aabb, u32, bool)> {
        let mut out = Vec::new();
        if self.nodes.is_empty() {
            return out;
        }
        let mut stack = vec![(0usize, self.root, 0u32)];
        while let Some((k, b, d)) = stack.pop() {
            match self.nodes[k] {
                Node::Leaf { .. } => out.push((b, d, true)),
                Node::Inner { first, axes, .. } => {
                    out.push((b, d, false));
                    for c in child_codes(axes) {
                        let child = first as usize + slot(c, axes);
                        stack.push((child, child_box(&b, c, axes), d + 1));
                    }
                }
            }
        }
        out
    }
}

impl Aggregate for Octree {
    fn intersect(&self, q: Query, c: &mut Counters) -> Option<PrimHit> {
        self.intersect_visiting(q, c, |_| {})
    }

    fn occluded(&self, q: Query, c: &mut Counters) -> bool {
        let mut tests = ItemTests::new(q, true);
        let mut walk = self.walk(q.ray, q.tmin, q.tmax);
        let hit = walk.by_ref().any(|leaf| tests.any(leaf.items, c));
        c.nodes_visited += walk.visited;
        hit
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn describe(&self) -> String {
        let name = match self.storage {
            Storage::Leaves => "octree",
            Storage::Inner => "octree-inner",
        };
        format!(
            "{name} {} nodes, depth {}, {} refs ({} at inner nodes)",
            self.nodes.len(),
            self.depth,
            self.items.len(),
            self.inner_refs
        )
    }

    fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>() + self.items.len() * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::testutil::{assert_agrees, prim, soup, sphere};
    use crate::shape::{Shape, Triangle};

    fn all(prims: &[Primitive]) -> Vec<u32> {
        (0..prims.len() as u32).collect()
    }

    #[test]
    fn few_primitives_make_a_single_leaf() {
        let prims = vec![sphere(Vec3::ZERO, 1.0), sphere(Vec3::X * 3.0, 1.0)];
        let o = Octree::new(&prims, all(&prims));
        assert_eq!(o.node_count(), 1);
        assert_eq!(o.depth(), 0);
        assert_agrees(&o, &prims, 500);
    }

    /// 64 small spheres on a 4×4×4 lattice.
    fn lattice_of_64() -> Vec<Primitive> {
        (0..64)
            .map(|i| {
                let p = Vec3::new((i % 4) as f32, (i / 4 % 4) as f32, (i / 16) as f32);
                sphere(p, 0.2)
            })
            .collect()
    }

    /// A root split on every axis, its children first, holding `count`
    /// references itself.
    fn root_split_in_8(count: u32) -> Node {
        Node::Inner {
            first: 1,
            axes: 7,
            start: 0,
            count,
        }
    }

    #[test]
    fn crowded_cells_split_and_primitives_live_in_leaves() {
        // 64 small spheres on a 4×4×4 lattice: one split separates them into
        // octants of 8, which stay leaves.
        let prims = lattice_of_64();
        let o = Octree::new(&prims, all(&prims));
        assert_eq!(o.node_count(), 9);
        assert_eq!(o.depth(), 1);
        assert_eq!(o.references(), 64);
        assert_eq!(o.inner_references(), 0);
        // The drawing's boxes: the root, then its eight octants as leaves.
        let boxes = o.node_boxes();
        assert_eq!(boxes[0], (o.root_bounds(), 0, false));
        assert_eq!(boxes.len(), 9);
        let octant = o.root_bounds().extent() * 0.5;
        for &(b, d, leaf) in &boxes[1..] {
            assert!(leaf && d == 1);
            assert!((b.extent() - octant).abs().max_element() < 1e-5);
        }
        assert_eq!(o.nodes[0], root_split_in_8(0));
        assert_agrees(&o, &prims, 2000);
    }

    #[test]
    fn splitting_without_progress_stops() {
        // Six copies of the two halves of a square: with padding, every
        // octant the square touches overlaps all twelve triangles.
        let (a, b, c, d) = (
            Vec3::new(-10.0, -10.0, 0.0),
            Vec3::new(10.0, -10.0, 0.0),
            Vec3::new(10.0, 10.0, 0.0),
            Vec3::new(-10.0, 10.0, 0.0),
        );
        let halves = [Triangle::new(a, b, c), Triangle::new(a, c, d)];
        let prims: Vec<Primitive> = (0..12)
            .map(|i| prim(Shape::Triangle(halves[i % 2])))
            .collect();
        let o = Octree::new(&prims, all(&prims));
        assert_eq!(o.node_count(), 1);
        assert_agrees(&o, &prims, 500);
    }

    #[test]
    fn leaves_come_front_to_back_and_chain() {
        let prims = soup(11, 600);
        let o = Octree::new(&prims, all(&prims));
        assert!(o.depth() >= 2);
        let rays = [
            Ray::new(Vec3::new(-9.0, 0.3, 0.2), Vec3::X),
            Ray::new(Vec3::new(0.1, 0.2, 0.3), Vec3::new(-1.0, 0.5, 0.25)),
            Ray::new(Vec3::new(7.0, 8.0, -9.0), Vec3::new(-0.7, -0.8, 0.9)),
        ];
        for r in rays {
            let (t0, t1) = o.root.hit(&r, r.dir.recip(), 0.0, f32::INFINITY).unwrap();
            let leaves: Vec<Leaf> = o.walk(&r, 0.0, f32::INFINITY).collect();
            assert_eq!(leaves[0].t_enter, t0);
            assert_eq!(leaves.last().unwrap().t_exit, t1);
            for w in leaves.windows(2) {
                assert_eq!(w[0].t_exit, w[1].t_enter);
            }
            for l in &leaves {
                // The leaf's box holds the middle of its interval.
                let p = r.at(0.5 * (l.t_enter + l.t_exit));
                let b = crate::accel::overlap::padded(&l.bounds, 1e-4);
                assert!(b.min.cmple(p).all() && p.cmple(b.max).all());
            }
        }
    }

    #[test]
    fn agrees_with_brute_force() {
        let prims = soup(12, 1500);
        let o = Octree::new(&prims, all(&prims));
        // What it reports is what it holds: the root box holds every
        // primitive, the memory is the nodes and a 4-byte id per
        // reference, and the drawing has a box per node, children inside
        // their parents and one level deeper.
        let all_boxes = prims.iter().fold(Aabb::EMPTY, |b, p| b.union(&p.bounds()));
        let root = o.root_bounds();
        assert!(root.min.cmple(all_boxes.min).all() && root.max.cmpge(all_boxes.max).all());
        assert_eq!(
            o.memory_bytes(),
            o.node_count() * std::mem::size_of::<Node>() + 4 * o.references()
        );
        let boxes = o.node_boxes();
        assert_eq!(boxes.len(), o.node_count());
        let leaves = o
            .nodes
            .iter()
            .filter(|n| matches!(n, Node::Leaf { .. }))
            .count();
        assert_eq!(boxes.iter().filter(|b| b.2).count(), leaves);
        assert_eq!(boxes.iter().map(|b| b.1).max(), Some(o.depth()));
        let mut parents = vec![boxes[0]];
        for &(b, d, leaf) in &boxes[1..] {
            parents.truncate(d as usize);
            let (p, pd, _) = *parents.last().expect("a parent");
            assert_eq!(pd + 1, d);
            let p = crate::accel::overlap::padded(&p, 1e-4);
            assert!(p.min.cmple(b.min).all() && b.max.cmple(p.max).all());
            if !leaf {
                parents.push((b, d, leaf));
            }
        }
        assert_agrees(&o, &prims, 3000);
    }

    #[test]
    fn inner_storage_keeps_straddlers_and_agrees() {
        let prims = soup(12, 1500);
        let leaves = Octree::new(&prims, all(&prims));
        let inner = Octree::with_storage(&prims, all(&prims), Storage::Inner);
        assert!(inner.inner_references() > 0);
        let kept: u32 = inner
            .nodes
            .iter()
            .map(|n| match n {
                Node::Inner { count, .. } => *count,
                Node::Leaf { .. } => 0,
            })
            .sum();
        assert_eq!(inner.inner_references(), kept as usize);
        assert_eq!(leaves.inner_references(), 0);
        // Nothing is copied: each primitive is stored exactly once.
        assert_eq!(inner.references(), prims.len());
        assert!(leaves.references() > prims.len());
        assert_agrees(&inner, &prims, 3000);
    }

    #[test]
    fn a_straddling_sphere_stays_at_the_root() {
        // 64 small spheres on a lattice plus one big sphere across the middle.
        let mut prims = lattice_of_64();
        prims.push(sphere(Vec3::splat(1.5), 0.3));
        let o = Octree::with_storage(&prims, all(&prims), Storage::Inner);
        assert_eq!(o.nodes[0], root_split_in_8(1));
        assert_eq!(o.items[0], 64);
        let leaf_items: Vec<Leaf> = o
            .walk(
                &Ray::new(Vec3::new(1.5, 1.5, -5.0), Vec3::Z),
                0.0,
                f32::INFINITY,
            )
            .collect();
        assert!(!leaf_items[0].is_leaf);
        assert_eq!(leaf_items[0].t_enter, leaf_items[0].t_exit);
        assert_agrees(&o, &prims, 2000);
    }
}
