//! Building a BVH top-down, straight into the flat node array.

use super::split::{choose, Item};
use super::{Bvh, Node, Split};
use crate::accel::overlap::{margin, padded};
use crate::math::Aabb;
use crate::primitive::Primitive;

/// Builds the BVH over `ids`.
pub(super) fn build(prims: &[Primitive], ids: Vec<u32>, split: Split) -> Bvh {
    let bounds = ids
        .iter()
        .fold(Aabb::EMPTY, |b, &i| b.union(&prims[i as usize].bounds()));
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
