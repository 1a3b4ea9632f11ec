//! Structure views: the boxes of a BVH's or an octree's nodes at a chosen
//! depth, drawn over the rendered image, coloured by depth.

use super::grid::ramp;
use super::traversal::box_edges;
use crate::accel::{Bvh, Octree};
use crate::math::{Aabb, Vec3};

/// Every node of `bvh` as (box, depth, leaf), parents before children.
pub fn bvh_boxes(bvh: &Bvh) -> Vec<(Aabb, u32, bool)> {
    let nodes = bvh.nodes();
    let mut out = Vec::new();
    if nodes.is_empty() {
        return out;
    }
    let mut stack = vec![(0usize, 0u32)];
    while let Some((k, d)) = stack.pop() {
        let n = &nodes[k];
        out.push((n.bounds, d, n.is_leaf()));
        if !n.is_leaf() {
            // Children of a flattened node: the next one, and `offset`.
            stack.push((n.offset as usize, d + 1));
            stack.push((k + 1, d + 1));
        }
    }
    out
}

/// Every node of `octree` as (box, depth, leaf).
pub fn octree_boxes(octree: &Octree) -> Vec<(Aabb, u32, bool)> {
    octree.node_boxes()
}

/// The segments of the boxes to draw: the nodes at `depth`, or with `None`
/// every leaf; coloured by depth on the heat ramp (root blue, deepest red).
pub fn segments(boxes: &[(Aabb, u32, bool)], depth: Option<u32>) -> Vec<((Vec3, Vec3), Vec3)> {
    let max = boxes.iter().map(|b| b.1).max().unwrap_or(0).max(1);
    boxes
        .iter()
        .filter(|(_, d, leaf)| match depth {
            Some(want) => *d == want,
            None => *leaf,
        })
        .flat_map(|(b, d, _)| {
            let c = ramp(*d as f32 / max as f32);
            box_edges(b).into_iter().map(move |e| (e, c))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::testutil::soup;
    use crate::accel::Split;

    /// Every level of a BVH covers all primitives: the boxes at each depth,
    /// plus the leaves above it, contain every primitive's box.
    #[test]
    fn bvh_levels_cover_every_primitive() {
        let prims = soup(3, 300);
        let ids: Vec<u32> = (0..prims.len() as u32).collect();
        let bvh = Bvh::new(&prims, ids, Split::Sah);
        let boxes = bvh_boxes(&bvh);
        assert_eq!(boxes.len(), bvh.nodes().len());
        let deepest = boxes.iter().map(|b| b.1).max().unwrap();
        assert_eq!(deepest as usize, bvh.depth());
        for d in 0..=deepest {
            let level: Vec<&Aabb> = boxes
                .iter()
                .filter(|(_, bd, leaf)| *bd == d || (*leaf && *bd < d))
                .map(|(b, ..)| b)
                .collect();
            for p in &prims {
                let pb = p.bounds();
                assert!(
                    level
                        .iter()
                        .any(|b| b.min.cmple(pb.min).all() && pb.max.cmple(b.max).all()),
                    "depth {d} misses a primitive"
                );
            }
        }
        assert!(!segments(&boxes, Some(1)).is_empty());
        assert_eq!(
            segments(&boxes, None).len(),
            12 * boxes.iter().filter(|b| b.2).count()
        );
    }
}
