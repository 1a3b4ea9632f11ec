//! Walking an octree front to back: the leaves a ray crosses, in order.
//!
//! How the children are ordered: at an inner node the ray crosses up to three
//! of the node's mid-planes (one per split axis) inside the node's `[t0, t1]`. The child it starts
//! in is read off, per axis, from whether the ray is already past the
//! mid-plane at `t0`; each crossing, in increasing `t`, flips that axis's bit
//! of the child index. That gives up to four children, each with its own
//! `[t_enter, t_exit]`, pushed far-first on a small stack so the nearest is
//! popped next. The stack's top is thus always the nearest unvisited part of
//! the ray, which is what lets the consumer stop early.

use super::{child_box, slot, Node, Octree, MAX_DEPTH};
use crate::math::{Aabb, Ray, Vec3};

/// One leaf of a walk, or (with the inner storage policy) an inner node
/// holding primitives, yielded before its children.
#[derive(Clone, Copy, Debug)]
pub struct Leaf<'a> {
    /// False for an inner node's own primitives: its `t_exit` is then its
    /// `t_enter` (its children, still to come, cover the rest of its span).
    pub is_leaf: bool,
    /// Node index.
    pub node: u32,
    /// The leaf's box.
    pub bounds: Aabb,
    /// Depth (the root is 0).
    pub depth: u32,
    /// Ray parameter where the ray enters the leaf (or the walk's start).
    pub t_enter: f32,
    /// Ray parameter where it leaves (or the walk's end).
    pub t_exit: f32,
    /// Primitive ids stored in the leaf.
    pub items: &'a [u32],
}

#[derive(Clone, Copy)]
struct Entry {
    node: u32,
    depth: u32,
    bounds: Aabb,
    t0: f32,
    t1: f32,
}

/// Popping a node pushes at most 4 children (a ray crosses at most three
/// split planes in it), 3 of which stay on the stack while the first is
/// explored: `3·MAX_DEPTH + 1` entries, exactly what the worst case uses
/// (`tests::a_corner_ray_fills_the_stack`).
const STACK: usize = 3 * MAX_DEPTH as usize + 1;

/// The leaves a ray crosses within `[tmin, tmax]`, front to back.
pub struct LeafWalk<'a> {
    tree: &'a Octree,
    origin: Vec3,
    inv: Vec3,
    /// Axes the ray does not move along (`1/dir` is not finite).
    parallel: [bool; 3],
    stack: [Entry; STACK],
    len: usize,
    /// Nodes popped so far, inner nodes and leaves (for the counters).
    pub visited: u64,
}

impl<'a> LeafWalk<'a> {
    pub(super) fn new(tree: &'a Octree, ray: &Ray, tmin: f32, tmax: f32) -> Self {
        let inv = ray.dir.recip();
        let empty = Entry {
            node: 0,
            depth: 0,
            bounds: Aabb::EMPTY,
            t0: 0.0,
            t1: 0.0,
        };
        let mut w = LeafWalk {
            tree,
            origin: ray.origin,
            inv,
            parallel: [0, 1, 2].map(|a| !inv[a].is_finite()),
            stack: [empty; STACK],
            len: 0,
            visited: 0,
        };
        if !tree.root.is_empty() {
            if let Some((t0, t1)) = tree.root.hit(ray, inv, tmin, tmax) {
                w.stack[0] = Entry {
                    node: 0,
                    depth: 0,
                    bounds: tree.root,
                    t0,
                    t1,
                };
                w.len = 1;
            }
        }
        w
    }

    /// Pushes the children of inner node `e` that the ray crosses, far first.
    fn push_children(&mut self, e: &Entry, first: u32, axes: u8) {
        let mid = e.bounds.center();
        let mut child = 0usize;
        let mut cross = [(0.0f32, 0usize); 3];
        let mut n = 0;
        for a in 0..3 {
            if axes & (1 << a) == 0 {
                continue; // not split: every child spans the node's extent
            }
            if self.parallel[a] {
                if self.origin[a] >= mid[a] {
                    child |= 1 << a;
                }
                continue;
            }
            let tm = (mid[a] - self.origin[a]) * self.inv[a];
            // Upper half at t0: moving up and already across, or moving down
            // and not yet across. A start exactly on the plane takes the half
            // the ray is entering.
            let upper = if self.inv[a] > 0.0 {
                tm <= e.t0
            } else {
                tm > e.t0
            };
            if upper {
                child |= 1 << a;
            }
            if tm > e.t0 && tm < e.t1 {
                cross[n] = (tm, a);
                n += 1;
            }
        }
        cross[..n].sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
        // Children in ray order with their intervals.
        let mut seq = [(0usize, 0.0f32, 0.0f32); 4];
        let mut t = e.t0;
        for (i, &(tc, a)) in cross[..n].iter().enumerate() {
            seq[i] = (child, t, tc);
            t = tc;
            child ^= 1 << a;
        }
        seq[n] = (child, t, e.t1);
        for &(c, t0, t1) in seq[..=n].iter().rev() {
            self.stack[self.len] = Entry {
                node: first + slot(c, axes) as u32,
                depth: e.depth + 1,
                bounds: child_box(&e.bounds, c, axes),
                t0,
                t1,
            };
            self.len += 1;
        }
    }
}

impl<'a> Iterator for LeafWalk<'a> {
    type Item = Leaf<'a>;

    fn next(&mut self) -> Option<Leaf<'a>> {
        while self.len > 0 {
            self.len -= 1;
            let e = self.stack[self.len];
            self.visited += 1;
            match self.tree.nodes[e.node as usize] {
                Node::Inner {
                    first,
                    axes,
                    start,
                    count,
                } => {
                    self.push_children(&e, first, axes);
                    if count > 0 {
                        let tree: &'a Octree = self.tree;
                        return Some(Leaf {
                            is_leaf: false,
                            node: e.node,
                            bounds: e.bounds,
                            depth: e.depth,
                            t_enter: e.t0,
                            t_exit: e.t0,
                            items: &tree.items[start as usize..(start + count) as usize],
                        });
                    }
                }
                Node::Leaf { start, count } => {
                    let tree: &'a Octree = self.tree;
                    let items = &tree.items[start as usize..(start + count) as usize];
                    return Some(Leaf {
                        is_leaf: true,
                        node: e.node,
                        bounds: e.bounds,
                        depth: e.depth,
                        t_enter: e.t0,
                        t_exit: e.t1,
                        items,
                    });
                }
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::super::Storage;
    use super::*;
    use crate::math::{Ray, Vec3};

    /// The worst case for the stack, built by hand: a chain of `MAX_DEPTH`
    /// inner nodes, each halved along all three axes, the next one in the
    /// corner slot at the origin, the other seven empty leaves; and a ray
    /// from that corner that crosses all three of every cell's middle
    /// planes (x at `s/2`, y at `s/2.2`, z at `s/2.4`, all before the cell's
    /// exit at `s/1.2`), so every inner node leaves three children pending.
    #[test]
    fn a_corner_ray_fills_the_stack() {
        let depth = MAX_DEPTH as usize;
        let mut nodes = vec![Node::Inner {
            first: 1,
            axes: 7,
            start: 0,
            count: 0,
        }];
        for level in 0..depth {
            let first = nodes.len();
            for slot in 0..8 {
                nodes.push(if slot == 0 && level + 1 < depth {
                    Node::Inner {
                        first: (first + 8) as u32,
                        axes: 7,
                        start: 0,
                        count: 0,
                    }
                } else {
                    Node::Leaf { start: 0, count: 0 }
                });
            }
        }
        let cube = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let tree = Octree {
            nodes,
            items: Vec::new(),
            root: cube,
            bounds: cube,
            depth: MAX_DEPTH,
            storage: Storage::Leaves,
            inner_refs: 0,
        };
        let ray = Ray::new(Vec3::ZERO, Vec3::new(1.0, 1.1, 1.2));
        let mut w = LeafWalk::new(&tree, &ray, 0.0, f32::INFINITY);
        // After each leaf comes back, the stack holds what was pending
        // beside it: one entry fewer than when the leaf was popped.
        let (mut peak, mut leaves, mut depths) = (w.len, 0, Vec::new());
        while let Some(leaf) = w.next() {
            peak = peak.max(w.len + 1);
            leaves += 1;
            depths.push(leaf.depth);
        }
        // Three leaves a level, one level deeper each time, four at the end
        // (popped nearest first: the chain's end comes first).
        let mut want: Vec<u32> = vec![MAX_DEPTH; 4];
        want.extend((1..MAX_DEPTH).rev().flat_map(|d| [d; 3]));
        assert_eq!(depths, want);
        // Four children crossed in each cell of the chain: three leaves and
        // the next node, four leaves at the end.
        assert_eq!(w.visited as usize, 1 + 4 * depth);
        assert_eq!(leaves, 3 * depth + 1);
        assert_eq!(peak, 3 * depth + 1);
        assert_eq!(peak, STACK);
    }
}
