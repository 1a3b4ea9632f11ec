//! A binary bounding-volume hierarchy.
//!
//! - `build.rs`: recursive top-down build, written straight into a flat
//!   depth-first node array (first child next to its parent, the second at
//!   a stored offset).
//! - `split.rs`: how a node's primitives are divided: midpoint, median or
//!   binned SAH ([`Split`]).
//! - `traverse.rs`: the closest-hit and any-hit loops with a small stack.
//!
//! The BVH has its own array of primitive ids, reordered so that every leaf's
//! primitives are contiguous; the world's primitive list is never reordered
//! (every aggregate indexes the same list, and hits report world indices).

mod build;
mod split;
mod traverse;

pub use traverse::NodeVisit;

use super::{Aggregate, PrimHit, Query, Split};
use crate::math::Aabb;
use crate::primitive::Primitive;
use crate::stats::Counters;

/// Most primitives in a leaf the builder makes by choice; only a set of
/// primitives whose centroids coincide (which no split can separate) makes a
/// larger one.
pub const MAX_LEAF: usize = 4;

/// One node of the flattened tree (32 bytes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// The node's box (unions of padded primitive boxes).
    pub bounds: Aabb,
    /// Leaf: index of its first id in the id array. Inner node: index of the
    /// second child (the first child is the next node).
    pub offset: u32,
    /// Leaf: number of primitives (≥ 1). Inner node: 0.
    pub count: u16,
    /// Inner node: the split axis, which orders the children for a ray.
    pub axis: u8,
}

impl Node {
    /// True for leaves.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

/// A BVH over the bounded primitives.
pub struct Bvh {
    nodes: Vec<Node>,
    ids: Vec<u32>,
    split: Split,
    /// Unpadded union of the primitives' boxes.
    bounds: Aabb,
}

impl Bvh {
    /// A BVH over the primitives `ids` of `prims`, dividing nodes by `split`.
    pub fn new(prims: &[Primitive], ids: Vec<u32>, split: Split) -> Self {
        build::build(prims, ids, split)
    }

    /// The nodes, depth-first; node 0 is the root (absent when empty).
    pub fn nodes(&self) -> &[Node] {
        &self.nodes
    }

    /// Primitive ids in leaf order.
    pub fn ids(&self) -> &[u32] {
        &self.ids
    }

    /// The closest hit, calling `visit` with every node whose box the search
    /// tests, and whether the ray entered it: the renderer's search itself
    /// ([`Aggregate::intersect`] passes a visitor that does nothing).
    pub fn intersect_visiting(
        &self,
        q: Query,
        c: &mut Counters,
        visit: impl FnMut(NodeVisit),
    ) -> Option<PrimHit> {
        traverse::closest(self, q, c, visit)
    }

    /// Depth of the deepest leaf (a lone root is 0).
    pub fn depth(&self) -> usize {
        fn go(nodes: &[Node], k: usize) -> usize {
            let n = &nodes[k];
            if n.is_leaf() {
                0
            } else {
                1 + go(nodes, k + 1).max(go(nodes, n.offset as usize))
            }
        }
        if self.nodes.is_empty() {
            0
        } else {
            go(&self.nodes, 0)
        }
    }
}

impl Aggregate for Bvh {
    fn intersect(&self, q: Query, c: &mut Counters) -> Option<PrimHit> {
        traverse::closest(self, q, c, |_| {})
    }

    fn occluded(&self, q: Query, c: &mut Counters) -> bool {
        traverse::any(self, q, c)
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<Node>() + self.ids.len() * 4
    }

    fn describe(&self) -> String {
        format!("bvh-{} {} nodes", self.split, self.nodes.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::testutil::{assert_agrees, soup, sphere};
    use crate::math::{Ray, Vec3};

    fn all(prims: &[Primitive]) -> Vec<u32> {
        (0..prims.len() as u32).collect()
    }

    #[test]
    fn two_separated_spheres_make_two_leaves() {
        let prims = vec![sphere(Vec3::X * 10.0, 1.0), sphere(Vec3::ZERO, 1.0)];
        for split in [Split::Sah, Split::Median, Split::Midpoint] {
            let b = Bvh::new(&prims, all(&prims), split);
            if split == Split::Sah {
                assert_eq!(b.nodes().len(), 3);
                assert_eq!(b.nodes()[0].offset, 2);
                assert!(b.nodes()[1].is_leaf() && b.nodes()[2].is_leaf());
                // Leaf order follows space; the world's order is untouched.
                assert_eq!(b.ids(), [1, 0]);
            } else {
                // At most MAX_LEAF primitives: a single leaf.
                assert_eq!(b.nodes().len(), 1);
            }
            assert_agrees(&b, &prims, 500);
        }
    }

    /// 16 unit spheres along the x axis, 3 apart.
    fn row_of_16() -> Vec<Primitive> {
        (0..16)
            .map(|i| sphere(Vec3::X * (3.0 * i as f32), 1.0))
            .collect()
    }

    #[test]
    fn the_far_child_is_skipped_once_the_near_one_hits() {
        let prims = row_of_16();
        let b = Bvh::new(&prims, all(&prims), Split::Sah);
        for (o, d, first) in [(-5.0, 1.0, 0), (60.0, -1.0, 15)] {
            let r = Ray::new(Vec3::X * o, Vec3::X * d);
            let mut c = Counters::default();
            let h = b
                .intersect(Query::new(&prims, &r, 0.0, f32::INFINITY), &mut c)
                .unwrap();
            assert_eq!(h.prim, first);
            assert!(c.intersection_tests <= 2, "{c:?}");
            assert!(c.nodes_visited <= 2 * b.depth() as u64 + 1, "{c:?}");
        }
    }

    #[test]
    fn occlusion_stops_at_the_first_hit() {
        let prims = row_of_16();
        let b = Bvh::new(&prims, all(&prims), Split::Median);
        // Leaves hold 4 spheres (in arbitrary order): the ray starts between
        // the 2nd and 3rd leaf and must stop inside the 3rd.
        let r = Ray::new(Vec3::new(22.5, 0.0, 0.0), Vec3::X);
        let mut c = Counters::default();
        assert!(b.occluded(Query::new(&prims, &r, 0.0, f32::INFINITY), &mut c));
        assert!(c.intersection_tests <= MAX_LEAF as u64, "{c:?}");
        assert!(!b.occluded(Query::new(&prims, &r, 0.0, 0.5), &mut c));
    }

    #[test]
    fn agrees_with_brute_force() {
        let prims = soup(21, 1500);
        for split in [Split::Sah, Split::Median, Split::Midpoint] {
            let b = Bvh::new(&prims, all(&prims), split);
            assert!(b.depth() < 64);
            assert_agrees(&b, &prims, 3000);
        }
    }

    #[test]
    fn an_empty_bvh_has_depth_0() {
        assert_eq!(Bvh::new(&[], vec![], Split::Sah).depth(), 0);
    }
}
