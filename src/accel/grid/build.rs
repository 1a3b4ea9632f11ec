//! Building a grid: how many cells, and which primitives go in each.

use super::{Grid, Lattice};
use crate::accel::overlap::{bounds_of, covering, padded, shape_overlaps};
use crate::math::Aabb;
use crate::primitive::Primitive;

/// Most cells per axis the automatic resolution picks: 128³ ≈ 2M cells
/// (8 MB of offsets) is past the point where more cells pay for themselves
/// on the scenes this tracer meets.
const MAX_AUTO_RES: u32 = 128;

/// Most cells in total, whatever the caller asked for; a larger request is
/// scaled down uniformly so a typo on the command line cannot exhaust memory.
const MAX_CELLS: f64 = (1u64 << 24) as f64;

/// Most (cell, primitive) entries a grid may hold: 2^26, about 270 MB of
/// lists (and twice that while filling). Primitives whose boxes overlap
/// (thousands of big spheres around one point) would otherwise put every
/// primitive in every cell, `cells × n` entries; the resolution is lowered
/// until the boxes' cell counts fit (see [`fit_entries`]).
const MAX_ENTRIES: u64 = 1 << 26;

/// Cells along the longest axis per `∛n` that the uniform grid picks.
pub(crate) const DENSITY: f32 = 3.0;

/// Cells per axis for `n` primitives in `bounds` (see [`resolution_with`]).
pub(crate) fn resolution(bounds: &Aabb, n: usize, fixed: Option<[u32; 3]>) -> [u32; 3] {
    resolution_with(bounds, n, fixed, DENSITY)
}

/// Cells per axis for `n` primitives in `bounds`.
///
/// Automatic: `density·∛n` cells (`density` is [`DENSITY`] for the uniform grid) along the longest axis, the other axes scaled by
/// the box's aspect so cells are roughly cubes (pbrt's rule; about 27 cells
/// per primitive for a cube-shaped scene, a few primitives per cell for
/// surfaces); every axis ≥ 1 (a flat scene gets one layer), ≤ 128.
pub(crate) fn resolution_with(
    bounds: &Aabb,
    n: usize,
    fixed: Option<[u32; 3]>,
    density: f32,
) -> [u32; 3] {
    let res = match fixed {
        Some(r) => r.map(|v| v.max(1)),
        None => {
            let ext = bounds.extent();
            let per_unit = density * (n.max(1) as f32).cbrt() / ext.max_element();
            [0, 1, 2].map(|a| ((ext[a] * per_unit).round() as u32).clamp(1, MAX_AUTO_RES))
        }
    };
    let total: f64 = res.iter().map(|&r| r as f64).product();
    if total <= MAX_CELLS {
        return res;
    }
    let shrink = (MAX_CELLS / total).cbrt();
    res.map(|r| ((r as f64 * shrink) as u32).max(1))
}

/// `res`, lowered until the padded boxes of `ids` cover at most
/// [`MAX_ENTRIES`] cells in all (an upper bound of the entries `fill`
/// makes: its exact tests only remove cells); each pass scales every axis
/// by the cube root of the excess, down to one cell.
pub(crate) fn fit_entries(
    prims: &[Primitive],
    ids: &[u32],
    region: &Aabb,
    res: [u32; 3],
    m: f32,
) -> [u32; 3] {
    fit_within(prims, ids, region, res, m, MAX_ENTRIES)
}

/// [`fit_entries`] with the budget `max` (tests use small ones).
fn fit_within(
    prims: &[Primitive],
    ids: &[u32],
    region: &Aabb,
    mut res: [u32; 3],
    m: f32,
    max: u64,
) -> [u32; 3] {
    loop {
        let entries = box_entries(prims, ids, &Lattice::new(*region, res), m);
        if entries <= max || res == [1, 1, 1] {
            return res;
        }
        let shrink = (max as f64 / entries as f64).cbrt();
        res = res.map(|r| ((r as f64 * shrink) as u32).clamp(1, r.saturating_sub(1).max(1)));
    }
}

/// How many cells of `lattice` the padded boxes of `ids` cover, in all: an
/// upper bound of the entries [`fill`] makes (its exact tests only remove
/// cells), in O(n).
pub(crate) fn box_entries(prims: &[Primitive], ids: &[u32], lattice: &Lattice, m: f32) -> u64 {
    ids.iter()
        .map(|&id| {
            let b = padded(&prims[id as usize].shape.bounds(), m);
            (0..3)
                .map(|a| {
                    let lo = lattice.coord(a, b.min[a]) as u64;
                    let hi = lattice.coord(a, b.max[a]) as u64;
                    hi.saturating_sub(lo) + 1
                })
                .product::<u64>()
        })
        .sum()
}

/// Builds the grid over `ids`.
///
/// Each primitive goes into every cell its (padded) box overlaps; when that
/// is more than one cell, triangles and spheres are also checked against each
/// cell with an exact overlap test (`overlap::shape_overlaps`), so a long
/// diagonal triangle is not listed in the empty cells of its box. Cells are
/// filled by counting sort of (cell, id) pairs into offsets + a flat list.
pub(super) fn build(prims: &[Primitive], ids: &[u32], fixed: Option<[u32; 3]>) -> Grid {
    let bounds = bounds_of(prims, ids);
    let (padded_bounds, m) = covering(&bounds);
    let res = if bounds.is_empty() {
        [1, 1, 1]
    } else {
        let res = resolution(&padded_bounds, ids.len(), fixed);
        fit_entries(prims, ids, &padded_bounds, res, m)
    };
    let lattice = Lattice::new(padded_bounds, res);
    let (offsets, items) = fill(prims, ids, &lattice, m);
    Grid {
        lattice,
        offsets,
        items,
        bounds,
        mailbox: true,
    }
}

/// Puts each of `ids` into the cells of `lattice` it overlaps (cells padded
/// by `m`) and returns the cells in CSR form: cell `k` holds
/// `items[offsets[k]..offsets[k + 1]]`. The lattice is the caller's region,
/// so the nested grid fills a crowded cell's box with the same code.
pub(crate) fn fill(
    prims: &[Primitive],
    ids: &[u32],
    lattice: &Lattice,
    m: f32,
) -> (Vec<u32>, Vec<u32>) {
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(ids.len() * 2);
    for &id in ids {
        let shape = &prims[id as usize].shape;
        let b = padded(&shape.bounds(), m);
        let lo = [0, 1, 2].map(|a| lattice.coord(a, b.min[a]) as u32);
        let hi = [0, 1, 2].map(|a| lattice.coord(a, b.max[a]) as u32);
        let single = lo == hi;
        let before = pairs.len();
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let c = [x, y, z];
                    if single || shape_overlaps(shape, &padded(&lattice.cell_bounds(c), m)) {
                        pairs.push((lattice.linear(c) as u32, id));
                    }
                }
            }
        }
        if pairs.len() == before {
            // The exact test rejected every cell (rounding at a corner): be
            // conservative rather than lose the primitive.
            pairs.push((lattice.linear(lo) as u32, id));
        }
    }

    let cells = lattice.cells();
    let mut offsets = vec![0u32; cells + 1];
    for &(cell, _) in &pairs {
        offsets[cell as usize + 1] += 1;
    }
    for k in 0..cells {
        offsets[k + 1] += offsets[k];
    }
    let mut next = offsets.clone();
    let mut items = vec![0u32; pairs.len()];
    for &(cell, id) in &pairs {
        items[next[cell as usize] as usize] = id;
        next[cell as usize] += 1;
    }
    (offsets, items)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::overlap::margin;
    use crate::accel::testutil::{sphere, Rng};
    use crate::math::Vec3;

    #[test]
    fn overlapping_boxes_lower_the_resolution_to_the_entry_budget() {
        // 400 spheres of radius 10 around one point: every box covers the
        // whole region, so the automatic 22³ grid would list each of them
        // in all 10,648 cells (4.3M entries).
        let mut r = Rng::new(3);
        let prims: Vec<Primitive> = (0..400).map(|_| sphere(r.v(-1.0, 1.0), 10.0)).collect();
        let ids: Vec<u32> = (0..400).collect();
        let region = prims.iter().fold(Aabb::EMPTY, |b, p| b.union(&p.bounds()));
        let m = margin(&region);
        let region = padded(&region, m);
        let auto = resolution(&region, ids.len(), None);
        let budget = 100_000;
        let res = fit_within(&prims, &ids, &region, auto, m, budget);
        let cells = |r: [u32; 3]| r.iter().map(|&v| v as u64).product::<u64>();
        assert!(cells(res) < cells(auto), "{auto:?} -> {res:?}");
        let (_, items) = fill(&prims, &ids, &Lattice::new(region, res), m);
        assert!(items.len() as u64 <= budget, "{} entries", items.len());
        // Small primitives keep the automatic resolution.
        let small: Vec<Primitive> = (0..400).map(|_| sphere(r.v(-5.0, 5.0), 0.01)).collect();
        let b = small.iter().fold(Aabb::EMPTY, |b, p| b.union(&p.bounds()));
        let want = resolution(&b, 400, None);
        assert_eq!(fit_within(&small, &ids, &b, want, margin(&b), budget), want);
    }

    #[test]
    fn automatic_resolution_follows_aspect() {
        let b = Aabb::new(Vec3::ZERO, Vec3::new(4.0, 2.0, 0.0));
        // 1000 prims: 30 cells on the long axis, 15 on the next, 1 on the flat one.
        assert_eq!(resolution(&b, 1000, None), [30, 15, 1]);
        let cube = Aabb::new(Vec3::ZERO, Vec3::ONE);
        assert_eq!(resolution(&cube, 1, None), [3, 3, 3]);
        assert_eq!(resolution(&cube, 100_000_000, None), [128, 128, 128]);
    }

    #[test]
    fn fixed_resolution_is_kept_but_capped() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        assert_eq!(resolution(&b, 5, Some([1, 0, 7])), [1, 1, 7]);
        let huge = resolution(&b, 5, Some([10_000; 3]));
        assert!(huge.iter().map(|&r| r as f64).product::<f64>() <= MAX_CELLS);
    }
}
