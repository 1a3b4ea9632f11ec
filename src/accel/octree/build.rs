//! Building an octree: split while crowded, push primitives down.

use super::{child_box, child_codes, split_axes, Node, Octree, Storage, LEAF_SIZE, MAX_DEPTH};
use crate::accel::overlap::{bounds_of, covering, padded, shape_overlaps};
use crate::math::Aabb;
use crate::primitive::Primitive;

/// Builds the tree over `ids`.
pub(super) fn build(prims: &[Primitive], ids: &[u32], storage: Storage) -> Octree {
    let bounds = bounds_of(prims, ids);
    let (root, m) = covering(&bounds);
    let mut b = Builder {
        prims,
        margin: m,
        nodes: vec![Node::Leaf { start: 0, count: 0 }],
        items: Vec::new(),
        depth: 0,
        storage,
        inner_refs: 0,
    };
    b.node(0, root, ids.to_vec(), 0);
    Octree {
        nodes: b.nodes,
        items: b.items,
        root,
        bounds,
        depth: b.depth,
        storage,
        inner_refs: b.inner_refs,
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
    storage: Storage,
    inner_refs: usize,
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
    ///
    /// With [`Storage::Inner`], primitives overlapping more than one child
    /// stay here; they cost one test per ray entering the node either way,
    /// so they are added to the split's cost as they are.
    fn node(&mut self, k: usize, bx: Aabb, ids: Vec<u32>, depth: u32) {
        self.depth = self.depth.max(depth);
        if ids.len() <= LEAF_SIZE || depth >= MAX_DEPTH {
            return self.leaf(k, &ids);
        }
        let axes = split_axes(&bx);
        let mut children: Vec<(Aabb, Vec<u32>)> = child_codes(axes)
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
        let kept = match self.storage {
            Storage::Leaves => Vec::new(),
            Storage::Inner => keep_straddlers(&ids, &mut children),
        };
        let area = bx.surface_area();
        let cost = TRAVERSAL_COST
            + kept.len() as f32
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
            start: self.items.len() as u32,
            count: kept.len() as u32,
        };
        self.items.extend_from_slice(&kept);
        self.inner_refs += kept.len();
        self.nodes
            .extend(children.iter().map(|_| Node::Leaf { start: 0, count: 0 }));
        for (s, (cb, ch)) in children.into_iter().enumerate() {
            self.node(first + s, cb, ch, depth + 1);
        }
    }

    fn leaf(&mut self, k: usize, ids: &[u32]) {
        debug_assert!(matches!(self.nodes[k], Node::Leaf { .. }));
        self.nodes[k] = Node::Leaf {
            start: self.items.len() as u32,
            count: ids.len() as u32,
        };
        self.items.extend_from_slice(ids);
    }
}

/// Removes from `children` every id listed in more than one of them and
/// returns those ids (in `ids` order): they stay at the parent.
fn keep_straddlers(ids: &[u32], children: &mut [(Aabb, Vec<u32>)]) -> Vec<u32> {
    let mut count: std::collections::HashMap<u32, u8> = std::collections::HashMap::new();
    for (_, ch) in children.iter() {
        for &id in ch {
            *count.entry(id).or_default() += 1;
        }
    }
    let straddles = |id: &u32| count.get(id).is_some_and(|&n| n > 1);
    for (_, ch) in children.iter_mut() {
        ch.retain(|id| !straddles(id));
    }
    ids.iter().copied().filter(|id| straddles(id)).collect()
}
