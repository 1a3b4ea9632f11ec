//! Building an octree: split while crowded, push primitives down.

use super::{child_box, child_codes, split_axes, Node, Octree, LEAF_SIZE, MAX_DEPTH};
use crate::accel::overlap::{margin, padded, shape_overlaps};
use crate::math::Aabb;
use crate::primitive::Primitive;

/// Builds the tree over `ids`.
pub(super) fn build(prims: &[Primitive], ids: &[u32]) -> Octree {
    let bounds = ids
        .iter()
        .fold(Aabb::EMPTY, |b, &i| b.union(&prims[i as usize].bounds()));
    let m = margin(&bounds);
    let root = if bounds.is_empty() {
        bounds
    } else {
        padded(&bounds, m)
    };
    let mut b = Builder {
        prims,
        margin: m,
        nodes: vec![Node::Leaf { start: 0, count: 0 }],
        items: Vec::new(),
        depth: 0,
    };
    b.node(0, root, ids.to_vec(), 0);
    Octree {
        nodes: b.nodes,
        items: b.items,
        root,
        bounds,
        depth: b.depth,
    }
}

/// Cost of visiting an inner node relative to one primitive test.
const TRAVERSAL_COST: f32 = 1.0;

struct Builder<'a> {
    prims: &'a [Primitive],
    margin: f32,
    nodes: Vec<Node>,
    items: Vec<u32>,
    depth: u32,
}

impl Builder<'_> {
    /// Fills node `k`, covering `bx`, with `ids` (all overlapping `bx`).
    ///
    /// A node becomes a leaf when it holds at most [`LEAF_SIZE`] primitives,
    /// sits at [`MAX_DEPTH`], or when splitting does not pay by a
    /// surface-area estimate: a ray through the node enters child `c` with
    /// probability about `area(c) / area(node)`, so the split costs about
    /// `TRAVERSAL_COST + Σ area(c)/area(node) · n_c` tests against `n` for a
    /// leaf. That stops where primitives overlap so much that no split
    /// separates them (big overlapping triangles, a pile of coincident ones
    /// on a split plane), where more levels would only copy the same lists
    /// into ever more cells; a tight cluster in one corner still splits,
    /// since its child is a quarter of the area.
    fn node(&mut self, k: usize, bx: Aabb, ids: Vec<u32>, depth: u32) {
        self.depth = self.depth.max(depth);
        if ids.len() <= LEAF_SIZE || depth >= MAX_DEPTH {
            return self.leaf(k, &ids);
        }
        let axes = split_axes(&bx);
        let children: Vec<(Aabb, Vec<u32>)> = child_codes(axes)
            .map(|c| {
                let cb = child_box(&bx, c, axes);
                // Padded like the grid's cells: a primitive touching the split
                // plane goes to both sides, so rounding in the walk's `t`
                // intervals cannot lose it.
                let test = padded(&cb, self.margin);
                let ch = ids
                    .iter()
                    .copied()
                    .filter(|&id| shape_overlaps(&self.prims[id as usize].shape, &test))
                    .collect();
                (cb, ch)
            })
            .collect();
        let area = bx.surface_area();
        let cost = TRAVERSAL_COST
            + children
                .iter()
                .map(|(cb, ch)| cb.surface_area() / area * ch.len() as f32)
                .sum::<f32>();
        if cost.is_nan() || cost >= ids.len() as f32 {
            return self.leaf(k, &ids);
        }
        let first = self.nodes.len();
        self.nodes[k] = Node::Inner {
            first: first as u32,
            axes,
        };
        self.nodes
            .extend(children.iter().map(|_| Node::Leaf { start: 0, count: 0 }));
        for (s, (cb, ch)) in children.into_iter().enumerate() {
            self.node(first + s, cb, ch, depth + 1);
        }
    }

    fn leaf(&mut self, k: usize, ids: &[u32]) {
        self.nodes[k] = Node::Leaf {
            start: self.items.len() as u32,
            count: ids.len() as u32,
        };
        self.items.extend_from_slice(ids);
    }
}
