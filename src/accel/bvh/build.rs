//! Building a BVH top-down, straight into the flat node array.

use super::split::{choose, Item};
use super::{Bvh, Node, Split};
use crate::accel::overlap::{bounds_of, margin, padded};
use crate::math::Aabb;
use crate::primitive::Primitive;

/// Builds the BVH over `ids`.
pub(super) fn build(prims: &[Primitive], ids: Vec<u32>, split: Split) -> Bvh {
    let bounds = bounds_of(prims, &ids);
    let m = margin(&bounds);
    let mut items: Vec<Item> = ids
        .iter()
        .map(|&id| {
            let b = padded(&prims[id as usize].bounds(), m);
            Item {
                id,
                bounds: b,
                centroid: b.center(),
            }
        })
        .collect();
    let mut b = Builder {
        split,
        nodes: Vec::with_capacity(2 * items.len()),
    };
    if !items.is_empty() {
        b.node(&mut items, 0, 0);
    }
    Bvh {
        nodes: b.nodes,
        ids: items.iter().map(|it| it.id).collect(),
        split,
        bounds,
    }
}

struct Builder {
    split: Split,
    nodes: Vec<Node>,
}

impl Builder {
    /// Appends the subtree over `items`, which sit at `start..` in the final
    /// id order. Depth-first: the first child is built right after its
    /// parent, so only the second child's index needs storing.
    fn node(&mut self, items: &mut [Item], start: usize, depth: usize) {
        let k = self.nodes.len();
        let bounds = items.iter().fold(Aabb::EMPTY, |b, it| b.union(&it.bounds));
        self.nodes.push(Node {
            bounds,
            offset: start as u32,
            count: items.len() as u16,
            axis: 0,
        });
        let Some((mid, axis)) = choose(items, &bounds, self.split, depth) else {
            return; // a leaf, already filled in
        };
        let (left, right) = items.split_at_mut(mid);
        self.node(left, start, depth + 1);
        self.nodes[k] = Node {
            bounds,
            offset: self.nodes.len() as u32,
            count: 0,
            axis: axis as u8,
        };
        self.node(right, start + mid, depth + 1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh::split::FORCE_MEDIAN_DEPTH;
    use crate::math::Vec3;

    /// A node's children are one level deeper: built from just above
    /// `FORCE_MEDIAN_DEPTH`, the root is cut by SAH and both its children
    /// by the median. Two far-apart copies of 3 + 9 boxes: SAH separates
    /// the copies, and would cut each copy at its gap (3 | 9), where the
    /// median cuts it 6 | 6, across the gap.
    #[test]
    fn children_are_one_level_deeper() {
        let mut items = Vec::new();
        for base in [0.0, 1000.0] {
            for i in 0..12 {
                let x = base
                    + if i < 3 {
                        0.1 * i as f32
                    } else {
                        20.0 + 0.1 * i as f32
                    };
                let c = Vec3::new(x, 0.0, 0.0);
                items.push(Item {
                    id: items.len() as u32,
                    bounds: Aabb::new(c - Vec3::splat(0.05), c + Vec3::splat(0.05)),
                    centroid: c,
                });
            }
        }
        let mut b = Builder {
            split: Split::Sah,
            nodes: Vec::new(),
        };
        b.node(&mut items, 0, FORCE_MEDIAN_DEPTH - 1);
        let root = b.nodes[0];
        assert!(!root.is_leaf());
        assert!(b.nodes[1].bounds.max.x < 100.0, "SAH separates the copies");
        for child in [1, root.offset as usize] {
            assert!(!b.nodes[child].is_leaf());
            // The child's first child: six boxes across the gap.
            let first = b.nodes[child + 1];
            assert!(first.bounds.extent().x > 19.0, "{first:?}");
        }
    }
}
