//! Where to divide a BVH node: midpoint, median, or binned SAH.

use super::{Split, MAX_LEAF};
use crate::math::{Aabb, Vec3};

/// A primitive during the build: its id, padded box and the box's centre.
#[derive(Clone, Copy, Debug)]
pub(super) struct Item {
    pub id: u32,
    pub bounds: Aabb,
    pub centroid: Vec3,
}

/// SAH bins (pbrt uses 12: more bins barely change the tree).
pub(super) const BINS: usize = 12;

/// Cost of visiting a node relative to one primitive test (pbrt's 1/8).
pub(super) const TRAVERSAL_COST: f32 = 0.125;

/// Below this depth every split is a median split, whatever was asked: the
/// median halves the count, so the tree stays under `32 + log2(n) ≤ 64`
/// levels, the traversal stack's size, even on inputs where SAH or midpoint
/// peel off one primitive per level.
pub(super) const FORCE_MEDIAN_DEPTH: usize = 32;

/// How to divide `items` (the primitives of a node with box `bounds`):
/// `Some((k, axis))` after reordering them so that `items[..k]` and
/// `items[k..]` are the children, or `None` for a leaf.
///
/// The axis is the one where the centroids spread most. When all centroids
/// coincide no split separates anything and the node is a leaf, unless it
/// holds more than a leaf's `u16` count, in which case it is halved anyway.
pub(super) fn choose(
    items: &mut [Item],
    bounds: &Aabb,
    split: Split,
    depth: usize,
) -> Option<(usize, usize)> {
    let n = items.len();
    if n <= 1 {
        return None;
    }
    let cb = Aabb::from_points(items.iter().map(|it| it.centroid));
    let ext = cb.extent();
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    if ext[axis].is_nan() || ext[axis] <= 0.0 {
        return (n > u16::MAX as usize).then_some((n / 2, axis));
    }
    let split = if depth >= FORCE_MEDIAN_DEPTH {
        Split::Median
    } else {
        split
    };
    let k = match split {
        Split::Midpoint if n > MAX_LEAF => {
            midpoint(items, &cb, axis).unwrap_or_else(|| median(items, axis))
        }
        Split::Median if n > MAX_LEAF => median(items, axis),
        Split::Midpoint | Split::Median => return None,
        Split::Sah => sah(items, bounds, &cb, axis)?,
    };
    Some((k, axis))
}

/// Moves the items satisfying `pred` to the front; returns how many.
fn partition(items: &mut [Item], pred: impl Fn(&Item) -> bool) -> usize {
    let mut k = 0;
    for i in 0..items.len() {
        if pred(&items[i]) {
            items.swap(i, k);
            k += 1;
        }
    }
    k
}

/// Splits at the middle of the centroids' extent; `None` when one side would
/// be empty (possible only through rounding: the extent is non-zero).
fn midpoint(items: &mut [Item], cb: &Aabb, axis: usize) -> Option<usize> {
    let mid = 0.5 * (cb.min[axis] + cb.max[axis]);
    let k = partition(items, |it| it.centroid[axis] < mid);
    (k > 0 && k < items.len()).then_some(k)
}

/// Splits into equal halves by centroid along `axis` (a partial sort).
fn median(items: &mut [Item], axis: usize) -> usize {
    let k = items.len() / 2;
    items.select_nth_unstable_by(k, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
    k
}

/// Binned SAH (pbrt's): the centroids' extent along `axis` is cut into
/// [`BINS`] equal bins, and each of the `BINS - 1` planes between bins is
/// priced as `TRAVERSAL_COST + (n_l·A_l + n_r·A_r) / A`, with `A_l`, `A_r`
/// the areas of the boxes of each side's primitives and `A` the node's.
/// The node stays a leaf when that beats the cheapest split (a leaf costs
/// `n` tests) and it holds at most [`MAX_LEAF`]. Two primitives are always
/// separated, as pbrt does: the SAH would rarely disagree.
fn sah(items: &mut [Item], bounds: &Aabb, cb: &Aabb, axis: usize) -> Option<usize> {
    let n = items.len();
    if n <= 2 {
        return Some(median(items, axis));
    }
    let lo = cb.min[axis];
    let scale = BINS as f32 / (cb.max[axis] - lo);
    let bin = |it: &Item| (((it.centroid[axis] - lo) * scale) as usize).min(BINS - 1);

    let mut count = [0u32; BINS];
    let mut boxes = [Aabb::EMPTY; BINS];
    for it in items.iter() {
        let b = bin(it);
        count[b] += 1;
        boxes[b] = boxes[b].union(&it.bounds);
    }
    // Sweep from the right for the right-hand sides, then from the left.
    let mut right_area = [0.0f32; BINS];
    let mut right_count = [0u32; BINS];
    let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
    for i in (1..BINS).rev() {
        acc = acc.union(&boxes[i]);
        cnt += count[i];
        right_area[i] = acc.surface_area();
        right_count[i] = cnt;
    }
    let (mut acc, mut cnt) = (Aabb::EMPTY, 0);
    let mut best = (f32::INFINITY, 0);
    for i in 0..BINS - 1 {
        acc = acc.union(&boxes[i]);
        cnt += count[i];
        let (nl, nr) = (cnt, right_count[i + 1]);
        if nl == 0 || nr == 0 {
            continue;
        }
        let cost = nl as f32 * acc.surface_area() + nr as f32 * right_area[i + 1];
        if cost < best.0 {
            best = (cost, i);
        }
    }
    let cost = TRAVERSAL_COST + best.0 / bounds.surface_area();
    if n <= MAX_LEAF && cost >= n as f32 {
        return None;
    }
    let k = partition(items, |it| bin(it) <= best.1);
    Some(if k > 0 && k < n {
        k
    } else {
        median(items, axis)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn item(id: u32, c: Vec3, r: f32) -> Item {
        Item {
            id,
            bounds: Aabb::new(c - Vec3::splat(r), c + Vec3::splat(r)),
            centroid: c,
        }
    }

    fn node_bounds(items: &[Item]) -> Aabb {
        items.iter().fold(Aabb::EMPTY, |b, it| b.union(&it.bounds))
    }

    #[test]
    fn sah_separates_two_clusters() {
        // 10 small boxes around x = 0 and 10 around x = 10, jittered in y so
        // that the midpoint and median choices do not coincide with SAH's.
        let mut items: Vec<Item> = (0..20)
            .map(|i| {
                let x = if i < 10 {
                    0.1 * i as f32
                } else {
                    10.0 + 0.3 * (i - 10) as f32
                };
                item(i, Vec3::new(x, 0.05 * i as f32, 0.0), 0.05)
            })
            .collect();
        items.swap(3, 15);
        let b = node_bounds(&items);
        let (k, axis) = choose(&mut items, &b, Split::Sah, 0).unwrap();
        assert_eq!((k, axis), (10, 0));
        assert!(items[..k].iter().all(|it| it.id < 10));
        assert!(items[k..].iter().all(|it| it.id >= 10));
    }

    #[test]
    fn sah_prefers_the_gap_over_the_median() {
        // 3 items on the left, 9 on the right: the median would cut the right
        // cluster, SAH cuts the gap.
        let mut items: Vec<Item> = (0..12)
            .map(|i| {
                let x = if i < 3 {
                    i as f32 * 0.1
                } else {
                    20.0 + i as f32 * 0.1
                };
                item(i, Vec3::new(x, 0.0, 0.0), 0.05)
            })
            .collect();
        let b = node_bounds(&items);
        let (k, _) = choose(&mut items, &b, Split::Sah, 0).unwrap();
        assert_eq!(k, 3);
        let (k, _) = choose(&mut items, &b, Split::Median, 0).unwrap();
        assert_eq!(k, 6);
    }

    #[test]
    fn sah_keeps_a_small_overlapping_pile_as_a_leaf() {
        // Three big boxes almost on top of each other: splitting cannot pay.
        let mut items: Vec<Item> = (0..3)
            .map(|i| item(i, Vec3::new(0.001 * i as f32, 0.0, 0.0), 1.0))
            .collect();
        let b = node_bounds(&items);
        assert_eq!(choose(&mut items, &b, Split::Sah, 0), None);
    }

    #[test]
    fn midpoint_cuts_the_centroid_extent_in_half() {
        let mut items: Vec<Item> = [0.0, 1.0, 2.0, 9.0, 10.0]
            .iter()
            .enumerate()
            .map(|(i, &x)| item(i as u32, Vec3::new(0.0, 0.0, x), 0.1))
            .collect();
        let b = node_bounds(&items);
        assert_eq!(choose(&mut items, &b, Split::Midpoint, 0), Some((3, 2)));
    }

    #[test]
    fn coincident_centroids_make_a_leaf() {
        let mut items: Vec<Item> = (0..10).map(|i| item(i, Vec3::ONE, 0.5)).collect();
        let b = node_bounds(&items);
        for s in [Split::Sah, Split::Median, Split::Midpoint] {
            assert_eq!(choose(&mut items, &b, s, 0), None);
        }
    }

    /// Binned SAH takes the cheapest of the planes between bins: each
    /// plane's cost, recomputed here from the items themselves (no sweeps),
    /// is no lower than the chosen split's.
    #[test]
    fn sah_takes_the_cheapest_plane() {
        let mut r = crate::accel::testutil::Rng::new(40);
        let mut uneven = 0;
        for trial in 0..300 {
            let n = 5 + trial % 40;
            let mut items: Vec<Item> = (0..n)
                .map(|i| item(i as u32, r.v(0.0, 10.0), 0.05 + r.f()))
                .collect();
            let b = node_bounds(&items);
            let Some((k, axis)) = choose(&mut items, &b, Split::Sah, 0) else {
                continue;
            };
            let area = |s: &[Item]| node_bounds(s).surface_area();
            let chosen = k as f32 * area(&items[..k]) + (n - k) as f32 * area(&items[k..]);
            let cb = Aabb::from_points(items.iter().map(|it| it.centroid));
            let (lo, width) = (cb.min[axis], cb.extent()[axis] / BINS as f32);
            let mut best = f32::INFINITY;
            for plane in 1..BINS {
                let cut = lo + width * plane as f32;
                let (l, r): (Vec<Item>, Vec<Item>) =
                    items.iter().partition(|it| it.centroid[axis] < cut);
                if !l.is_empty() && !r.is_empty() {
                    best = best.min(l.len() as f32 * area(&l) + r.len() as f32 * area(&r));
                }
            }
            assert!(chosen <= best * 1.0001, "trial {trial}: {chosen} > {best}");
            uneven += usize::from(k != n / 2);
        }
        // Not the median in disguise.
        assert!(uneven > 100, "{uneven}");
    }

    /// Coincident centroids make a leaf, unless there are more than a
    /// leaf's `u16` count can say: then the node is halved anyway.
    #[test]
    fn too_many_coincident_centroids_are_halved() {
        for (n, want) in [
            (65_535, None),
            (65_536, Some((32_768, 0))),
            (70_001, Some((35_000, 0))),
        ] {
            let mut items: Vec<Item> = (0..n).map(|i| item(i, Vec3::ONE, 0.5)).collect();
            let b = node_bounds(&items);
            assert_eq!(choose(&mut items, &b, Split::Sah, 0), want, "{n}");
        }
    }

    /// The midpoint splits strictly below the middle, and where rounding
    /// leaves one side empty (centroids a few ulps apart, or so far out
    /// that their sum overflows) it falls back to the median.
    #[test]
    fn midpoint_is_strict_and_falls_back_where_rounding_empties_a_side() {
        let xs = |v: &[f32]| -> Vec<Item> {
            v.iter()
                .enumerate()
                .map(|(i, &x)| item(i as u32, Vec3::new(x, 0.0, 0.0), 0.01))
                .collect()
        };
        let mut items = xs(&[0.0, 5.0, 5.0, 5.0, 10.0]);
        let b = node_bounds(&items);
        assert_eq!(choose(&mut items, &b, Split::Midpoint, 0), Some((1, 0)));
        // 1 and the next float: their mean rounds to 1, and nothing is below.
        let next = f32::from_bits(1f32.to_bits() + 1);
        // 3e38 and 3.3e38: their sum overflows and everything is below it.
        for v in [
            [1.0, 1.0, 1.0, next, next, next],
            [3e38, 3e38, 3e38, 3.3e38, 3.3e38, 3.3e38],
        ] {
            let mut items = xs(&v);
            let b = node_bounds(&items);
            assert_eq!(
                choose(&mut items, &b, Split::Midpoint, 0),
                Some((3, 0)),
                "{v:?}"
            );
        }
    }

    #[test]
    fn deep_nodes_fall_back_to_the_median() {
        let mut items: Vec<Item> = (0..9)
            .map(|i| item(i, Vec3::new(2f32.powi(i as i32), 0.0, 0.0), 0.01))
            .collect();
        let b = node_bounds(&items);
        let (k, _) = choose(&mut items, &b, Split::Sah, FORCE_MEDIAN_DEPTH).unwrap();
        assert_eq!(k, 4);
    }
}
