//! Nested grids: a coarse uniform grid whose crowded cells hold a finer grid
//! over the cell's (padded) box, the lecture's other adaptive grid beside the
//! octree.
//!
//! Every level is an ordinary [`Lattice`] filled by the uniform grid's own
//! code (`grid::build::fill`) and walked by the same [`CellWalk`]: a cell
//! that holds a finer grid is walked by a second 3DDDA over the part of the
//! ray inside the cell, `[t_enter, t_exit]`, before the coarse walk moves on.
//!
//! Resolutions: the coarse grid has `∛N` cells along its longest axis (a
//! third of the uniform grid's `3·∛N`); a cell holding more than `threshold`
//! primitives gets `2·∛n` cells along its longest axis for its `n`, and so
//! on down to `depth` levels below the coarse one. A crowded cell's own list
//! is dropped: its finer grid holds every one of its primitives.
//!
//! A finer grid is built only where it pays, by the octree's surface-area
//! estimate: a ray through the cell crosses finer cell `c` with probability
//! about `area(c) / area(cell)`, so it costs about
//! `Σ area(c)/area(cell) · (1 + n_c)` against `n` for the list. Primitives
//! that all span the whole cell (big overlapping boxes, such as moving
//! objects whose boxes cover their path) would be copied into every finer
//! cell at every level, `cells^depth · n` entries; that grid is dropped
//! before it recurses, which bounds the memory.
//!
//! Exactness is the uniform grid's rule at every level: the closest hit is
//! kept across cells and levels (one mailbox for the whole ray), and the walk
//! stops once it lies before the exit of the cell just finished, whatever
//! its level. A finer cell's exit is never after its coarse cell's, so
//! stopping inside a finer grid is as safe as stopping in the coarse one.

use super::grid::build::{box_entries, fill, fit_entries, resolution_with};
use super::grid::{CellWalk, Face, Lattice};
use super::mailbox::ItemTests;
use super::overlap::{bounds_of, covering, padded};
use super::{Aggregate, PrimHit, Query};
use crate::math::{Aabb, Ray};
use crate::primitive::Primitive;
use crate::stats::Counters;

/// Cells per `∛N` along the longest axis of the coarse grid.
const COARSE_DENSITY: f32 = 1.0;
/// Cells per `∛n` along the longest axis of a finer grid.
const FINE_DENSITY: f32 = 2.0;
/// Cost of stepping into one cell, in primitive tests (the octree's value).
const CELL_COST: f32 = 1.0;

/// One level: a lattice, its cells' primitives and the finer grids of its
/// crowded cells.
struct Level {
    lattice: Lattice,
    /// CSR cells: cell `k` holds `items[offsets[k]..offsets[k + 1]]`.
    offsets: Vec<u32>,
    items: Vec<u32>,
    /// Per cell: 0, or 1 + the index of its finer grid in `children`.
    child: Vec<u32>,
    children: Vec<Level>,
}

/// A coarse grid with finer grids in its crowded cells.
pub struct NestedGrid {
    top: Level,
    /// Unpadded union of the primitives' boxes.
    bounds: Aabb,
    threshold: u32,
    depth: u32,
}

impl NestedGrid {
    /// A nested grid over the primitives `ids` of `prims`: cells holding more
    /// than `threshold` primitives get a finer grid, at most `depth` levels
    /// below the coarse one.
    pub fn new(prims: &[Primitive], ids: Vec<u32>, threshold: u32, depth: u32) -> Self {
        let bounds = bounds_of(prims, &ids);
        let (region, m) = covering(&bounds);
        let b = Builder {
            prims,
            margin: m,
            threshold: threshold.max(1) as usize,
        };
        let top = b
            .level(region, &ids, COARSE_DENSITY, depth, false)
            .expect("the coarse level is always built");
        Self {
            top,
            bounds,
            threshold,
            depth,
        }
    }

    /// Finer grids at every level below the coarse one.
    pub fn subgrids(&self) -> usize {
        fn count(l: &Level) -> usize {
            l.children.len() + l.children.iter().map(count).sum::<usize>()
        }
        count(&self.top)
    }

    /// Cells of every level.
    pub fn cells(&self) -> usize {
        fn count(l: &Level) -> usize {
            l.lattice.cells() + l.children.iter().map(count).sum::<usize>()
        }
        count(&self.top)
    }

    /// The coarse grid's cells per axis.
    pub fn coarse_res(&self) -> [u32; 3] {
        self.top.lattice.res
    }

    /// Calls `visit(items, t_exit)` for every leaf cell (one without a finer
    /// grid) the ray crosses within `[t0, t1]`, front to back over all
    /// levels, until `visit` returns true; returns whether it did. `seen`
    /// is told every cell walked, at every level (for the traversal views).
    fn walk(
        level: &Level,
        ray: &Ray,
        t0: f32,
        t1: f32,
        c: &mut Counters,
        visit: &mut impl FnMut(&[u32], f32, &mut Counters) -> bool,
        seen: &mut impl FnMut(&CellVisit),
    ) -> bool {
        for cell in CellWalk::new(&level.lattice, ray, t0, t1) {
            c.nodes_visited += 1;
            let k = level.lattice.linear(cell.index);
            seen(&CellVisit {
                bounds: level.lattice.cell_bounds(cell.index),
                entered: cell.entered,
                finer: level.child[k] != 0,
            });
            let stop = match level.child[k] {
                0 => {
                    let items =
                        &level.items[level.offsets[k] as usize..level.offsets[k + 1] as usize];
                    visit(items, cell.t_exit, c)
                }
                j => Self::walk(
                    &level.children[j as usize - 1],
                    ray,
                    cell.t_enter,
                    cell.t_exit,
                    c,
                    visit,
                    seen,
                ),
            };
            if stop {
                return true;
            }
        }
        false
    }

    /// The closest hit, calling `visit` with every cell the search walks at
    /// every level, in order: the renderer's search itself
    /// ([`Aggregate::intersect`] passes a visitor that does nothing), which
    /// the traversal views record.
    pub fn intersect_visiting(
        &self,
        q: Query,
        c: &mut Counters,
        mut visit: impl FnMut(&CellVisit),
    ) -> Option<PrimHit> {
        let mut tests = ItemTests::new(q, true);
        let test =
            &mut |items: &[u32], t_exit: f32, c: &mut Counters| tests.closest_in(items, t_exit, c);
        Self::walk(&self.top, q.ray, q.tmin, q.tmax, c, test, &mut visit);
        tests.best()
    }
}

/// One cell of a nested grid's walk, at any level.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellVisit {
    /// The cell's box.
    pub bounds: Aabb,
    /// The face it was entered through (`None` where the walk started).
    pub entered: Option<Face>,
    /// Whether the cell holds a finer grid (walked next) rather than a list.
    pub finer: bool,
}

struct Builder<'a> {
    prims: &'a [Primitive],
    margin: f32,
    threshold: usize,
}

impl Builder<'_> {
    /// A grid over `region` holding `ids`, with `levels` more levels allowed
    /// below it; `None` if `must_pay` and a ray would test about as many
    /// primitives in it as in the plain list `ids` (see the module comment).
    fn level(
        &self,
        region: Aabb,
        ids: &[u32],
        density: f32,
        levels: u32,
        must_pay: bool,
    ) -> Option<Level> {
        let res = if region.is_empty() {
            [1, 1, 1]
        } else {
            let res = resolution_with(&region, ids.len(), None, density);
            fit_entries(self.prims, ids, &region, res, self.margin)
        };
        let lattice = Lattice::new(region, res);
        let cells = lattice.cells();
        if must_pay {
            // Every cell has the same area: Σ area(c)/area · (1 + n_c), with
            // the boxes' cell counts for Σ n_c (an upper bound, known before
            // filling: a crowded cell that does not pay costs O(n), not a fill).
            let entries = box_entries(self.prims, ids, &lattice, self.margin);
            let share = lattice.cell_bounds([0, 0, 0]).surface_area() / region.surface_area();
            let cost = share * (CELL_COST * cells as f32 + entries as f32);
            // A NaN cost (a region without area) does not pay either.
            let pays = cost < ids.len() as f32;
            if !pays {
                return None;
            }
        }
        let (offsets, items) = fill(self.prims, ids, &lattice, self.margin);
        let mut child = vec![0u32; cells];
        let mut children = Vec::new();
        // Compacted lists: a crowded cell's primitives move to its finer grid.
        let mut new_offsets = Vec::with_capacity(cells + 1);
        let mut new_items = Vec::with_capacity(items.len());
        new_offsets.push(0);
        for k in 0..cells {
            let list = &items[offsets[k] as usize..offsets[k + 1] as usize];
            if levels > 0 && list.len() > self.threshold {
                let cb = lattice.cell_bounds(index_of(&lattice, k));
                // Padded like the cells the list was filled from, so the finer
                // grid covers every hit the coarse cell's primitives have in it.
                let sub = self.level(
                    padded(&cb, self.margin),
                    list,
                    FINE_DENSITY,
                    levels - 1,
                    true,
                );
                if let Some(sub) = sub {
                    children.push(sub);
                    child[k] = children.len() as u32;
                    new_offsets.push(new_items.len() as u32);
                    continue;
                }
            }
            new_items.extend_from_slice(list);
            new_offsets.push(new_items.len() as u32);
        }
        Some(Level {
            lattice,
            offsets: new_offsets,
            items: new_items,
            child,
            children,
        })
    }
}

/// Cell coordinates of linear index `k` (the inverse of `Lattice::linear`).
fn index_of(l: &Lattice, k: usize) -> [u32; 3] {
    let (rx, ry) = (l.res[0] as usize, l.res[1] as usize);
    [
        (k % rx) as u32,
        (k / rx % ry) as u32,
        (k / (rx * ry)) as u32,
    ]
}

fn level_bytes(l: &Level) -> usize {
    (l.offsets.len() + l.items.len() + l.child.len()) * 4
        + l.children.iter().map(level_bytes).sum::<usize>()
}

impl Aggregate for NestedGrid {
    fn intersect(&self, q: Query, c: &mut Counters) -> Option<PrimHit> {
        self.intersect_visiting(q, c, |_| {})
    }

    fn occluded(&self, q: Query, c: &mut Counters) -> bool {
        let mut tests = ItemTests::new(q, true);
        let visit = &mut |items: &[u32], _, c: &mut Counters| tests.any(items, c);
        Self::walk(&self.top, q.ray, q.tmin, q.tmax, c, visit, &mut |_| {})
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn describe(&self) -> String {
        let [x, y, z] = self.top.lattice.res;
        format!(
            "nested-grid:{}:{} {x}x{y}x{z}, {} finer grids, {} cells",
            self.threshold,
            self.depth,
            self.subgrids(),
            self.cells()
        )
    }

    fn memory_bytes(&self) -> usize {
        level_bytes(&self.top)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::testutil::{assert_agrees, soup, sphere};
    use crate::math::Vec3;

    fn all(prims: &[Primitive]) -> Vec<u32> {
        (0..prims.len() as u32).collect()
    }

    #[test]
    fn agrees_with_brute_force_at_every_setting() {
        let prims = soup(21, 1200);
        for (threshold, depth) in [(16, 2), (1, 1), (4, 3), (1000, 2)] {
            let g = NestedGrid::new(&prims, all(&prims), threshold, depth);
            assert_agrees(&g, &prims, 2000);
        }
    }

    #[test]
    fn crowded_cells_get_finer_grids_and_sparse_ones_do_not() {
        // A dense cluster of tiny spheres in one corner, a few big ones elsewhere.
        let mut prims: Vec<Primitive> = (0..400)
            .map(|i| {
                let p = Vec3::new((i % 8) as f32, (i / 8 % 8) as f32, (i / 64) as f32) * 0.01;
                sphere(p, 0.003)
            })
            .collect();
        prims.extend((0..7).map(|i| sphere(Vec3::splat(2.0 + i as f32), 0.2)));
        let g = NestedGrid::new(&prims, all(&prims), 16, 2);
        assert!(g.subgrids() >= 1);
        // The cluster (0.08 wide) sits in one coarse cell (about 1.2 wide).
        assert!(g.coarse_res()[0] <= 8);
        assert_eq!(g.top.children.len(), 1);
        let none = NestedGrid::new(&prims, all(&prims), 10_000, 2);
        assert_eq!(none.subgrids(), 0);
        let mut with = Counters::default();
        let mut without = Counters::default();
        let r = Ray::new(Vec3::new(0.035, 0.035, -1.0), Vec3::Z);
        let a = g.intersect(Query::new(&prims, &r, 0.0, f32::INFINITY), &mut with);
        let b = none.intersect(Query::new(&prims, &r, 0.0, f32::INFINITY), &mut without);
        assert_eq!(a, b);
        assert!(with.intersection_tests < without.intersection_tests);
        assert_agrees(&g, &prims, 2000);
    }

    #[test]
    fn depth_one_with_threshold_zero_is_finer_wherever_it_pays() {
        // 30 tight clusters of 10 tiny spheres: a finer grid separates them.
        let mut r = crate::accel::testutil::Rng::new(22);
        let mut prims = Vec::new();
        for _ in 0..30 {
            let c = r.v(-5.0, 5.0);
            prims.extend((0..10).map(|_| sphere(c + r.v(-0.05, 0.05), 1e-3)));
        }
        let g = NestedGrid::new(&prims, all(&prims), 0, 1);
        // A finer grid over n points costs about 2·∛n cells a ray, so it pays
        // from n = 3 on: every cell of 4 or more got one.
        for (k, &c) in g.top.child.iter().enumerate() {
            let n = (g.top.offsets[k + 1] - g.top.offsets[k]) as usize;
            assert!(c > 0 || n <= 3, "cell {k} kept {n} primitives");
            // Two points cost more in a finer grid (its cells) than in a list.
            if c > 0 {
                let mut ids = g.top.children[c as usize - 1].items.clone();
                ids.sort_unstable();
                ids.dedup();
                assert!(ids.len() > 2, "cell {k}: a finer grid for {}", ids.len());
            }
        }
        assert!(g.subgrids() >= 20, "{} finer grids", g.subgrids());
        assert_agrees(&g, &prims, 2000);
    }

    #[test]
    fn primitives_spanning_every_cell_get_no_finer_grid() {
        // 200 ellipsoids around one point, tested against cells by their
        // boxes (as moving objects are, by their path's box): each box
        // covers every finer cell, so finer grids would hold cells × 200
        // copies a level and test no fewer primitives.
        use crate::math::Mat4;
        use crate::shape::{Shape, Sphere, Transformed};
        let mut r = crate::accel::testutil::Rng::new(5);
        let prims: Vec<Primitive> = (0..200)
            .map(|_| {
                let m = Mat4::from_translation(r.v(-0.1, 0.1))
                    * Mat4::from_scale(Vec3::new(3.0, 2.0, 1.0 + r.f()));
                let s = Shape::Sphere(Sphere {
                    center: Vec3::ZERO,
                    radius: 1.0,
                });
                crate::accel::testutil::prim(Shape::Transformed(Box::new(
                    Transformed::new(s, m).expect("invertible"),
                )))
            })
            .collect();
        let g = NestedGrid::new(&prims, all(&prims), 16, 3);
        assert_eq!(g.subgrids(), 0);
        // The coarse grid alone: at most every primitive in every cell.
        let bound = (g.top.lattice.cells() * (prims.len() + 3)) * 4 + 4;
        assert!(g.memory_bytes() <= bound, "{} bytes", g.memory_bytes());
        assert_agrees(&g, &prims, 500);
    }

    /// A finer grid is built exactly when a ray is expected to test fewer
    /// primitives in it than in the list: over a cube cut 3×3×3 (4 points
    /// make `round(2·∛4) = 3` cells an axis), Σ area(c)/area·(1 + n_c) =
    /// (27 + entries)/9 against 4, which pays with 8 entries and not with 9
    /// (tiny spheres on a cell face count in 2 cells, on an edge in 4).
    #[test]
    fn a_finer_grid_is_built_exactly_when_its_cost_is_below_the_list_s() {
        let third = 1.0 / 3.0;
        let at = |x: f32, y: f32| sphere(Vec3::new(x, y, 0.5), 1e-3);
        let entries_8 = vec![
            at(third, 0.1),
            at(third, 0.5),
            at(0.5, third),
            at(0.9, third),
        ];
        let entries_9 = vec![
            at(third, third),
            at(third, 0.9),
            at(0.9, 2.0 * third),
            at(0.5, 0.5),
        ];
        let region = Aabb::new(Vec3::ZERO, Vec3::ONE);
        for (prims, pays) in [(entries_8, true), (entries_9, false)] {
            let b = Builder {
                prims: &prims,
                margin: 1e-5,
                threshold: 1,
            };
            let ids = all(&prims);
            let lattice = Lattice::new(region, [3, 3, 3]);
            let entries = box_entries(&prims, &ids, &lattice, b.margin);
            assert_eq!(entries, if pays { 8 } else { 9 });
            let level = b.level(region, &ids, FINE_DENSITY, 0, true);
            assert_eq!(level.is_some(), pays, "{entries} entries");
            if let Some(l) = level {
                assert_eq!(l.lattice.res, [3, 3, 3]);
            }
        }
    }

    /// The sum of `f` over every level.
    fn sum_levels(l: &Level, f: &impl Fn(&Level) -> usize) -> usize {
        f(l) + l.children.iter().map(|c| sum_levels(c, f)).sum::<usize>()
    }

    /// Levels of finer grids below `l`.
    fn levels_below(l: &Level) -> u32 {
        l.children
            .iter()
            .map(|c| 1 + levels_below(c))
            .max()
            .unwrap_or(0)
    }

    /// What the grid reports (cells, coarse resolution, memory, name) is
    /// what its levels hold; no grid nests deeper than asked; and the walk
    /// marks the cells holding a finer grid, each followed by a cell of it.
    #[test]
    fn reports_what_it_holds_and_nests_no_deeper_than_asked() {
        let prims = soup(23, 1200);
        let mut finer_seen = 0;
        for (threshold, depth) in [(4, 1), (2, 2), (1, 3)] {
            let g = NestedGrid::new(&prims, all(&prims), threshold, depth);
            let levels = levels_below(&g.top);
            assert!((1..=depth).contains(&levels), "{levels} levels");
            let [x, y, z] = g.coarse_res();
            assert_eq!(g.coarse_res(), g.top.lattice.res);
            assert!(x > 1 && y > 1 && z > 1);
            let cells = sum_levels(&g.top, &|l| l.lattice.cells());
            assert_eq!(g.cells(), cells);
            assert!(cells > (x * y * z) as usize);
            // Per level: `cells + 1` offsets, a child slot per cell, the items.
            let items = sum_levels(&g.top, &|l| l.items.len());
            let grids = 1 + g.subgrids();
            assert_eq!(g.memory_bytes(), 4 * (2 * cells + grids + items));
            assert_eq!(
                g.describe(),
                format!(
                    "nested-grid:{threshold}:{depth} {x}x{y}x{z}, {} finer grids, {cells} cells",
                    g.subgrids()
                )
            );
            let mut r = crate::accel::testutil::Rng::new(24);
            for _ in 0..200 {
                let q = crate::accel::testutil::ray(&mut r);
                let mut seen = Vec::new();
                let mut c = Counters::default();
                let got =
                    g.intersect_visiting(Query::new(&prims, &q, 0.0, f32::INFINITY), &mut c, |v| {
                        seen.push(*v)
                    });
                let want = g.intersect(Query::new(&prims, &q, 0.0, f32::INFINITY), &mut c);
                assert_eq!(got, want);
                for w in seen.windows(2) {
                    if w[0].finer {
                        let outer = crate::accel::overlap::padded(&w[0].bounds, 1e-4);
                        let inner = w[1].bounds;
                        assert!(
                            outer.min.cmple(inner.min).all() && inner.max.cmple(outer.max).all()
                        );
                        finer_seen += 1;
                    }
                }
            }
        }
        assert!(finer_seen > 10, "{finer_seen}");
    }
}
