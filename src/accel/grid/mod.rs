//! A uniform grid walked with 3DDDA (Amanatides & Woo).
//!
//! - `build.rs`: the automatic resolution and putting primitives into cells.
//! - `traverse.rs`: [`CellWalk`], the iterator of cells a ray crosses. The
//!   renderer's loop below and the grid visualization consume the same walk.
//!
//! The intersect loop tests each cell's primitives (once per ray, thanks to
//! the mailbox), keeps the closest hit found so far whatever cell it lies in,
//! and stops once that hit is no farther than the current cell's exit: a hit
//! beyond the cell might still be beaten by a primitive in a later cell.

pub(crate) mod build;
mod traverse;

pub use traverse::{Cell, CellWalk, Face};

use super::mailbox::ItemTests;
use super::{Aggregate, PrimHit, Query};
use crate::math::{Aabb, Ray, Vec3};
use crate::primitive::Primitive;
use crate::stats::Counters;

/// The geometry of the grid: where its cells are. Cell `i` along axis `a`
/// spans the planes [`Lattice::plane`]`(a, i)` to `plane(a, i + 1)`; building
/// and walking use that one formula so they agree on every boundary.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lattice {
    /// Padded box the cells tile.
    pub bounds: Aabb,
    /// Cells per axis (each ≥ 1).
    pub res: [u32; 3],
    /// Size of one cell.
    pub cell: Vec3,
}

impl Lattice {
    /// Cells per axis over `bounds`.
    pub fn new(bounds: Aabb, res: [u32; 3]) -> Self {
        let n = Vec3::new(res[0] as f32, res[1] as f32, res[2] as f32);
        Self {
            bounds,
            res,
            cell: bounds.extent() / n,
        }
    }

    /// Position of the `i`-th cell boundary along `axis`.
    #[inline]
    pub fn plane(&self, axis: usize, i: i32) -> f32 {
        self.bounds.min[axis] + i as f32 * self.cell[axis]
    }

    /// The cell holding `p` along `axis`, clamped into the grid.
    #[inline]
    pub fn coord(&self, axis: usize, p: f32) -> i32 {
        let i = ((p - self.bounds.min[axis]) / self.cell[axis]).floor();
        // `as` saturates (and maps NaN to 0), so the clamp is always in range.
        (i as i32).clamp(0, self.res[axis] as i32 - 1)
    }

    /// The box of cell `[ix, iy, iz]`.
    pub fn cell_bounds(&self, c: [u32; 3]) -> Aabb {
        let lo = Vec3::new(
            self.plane(0, c[0] as i32),
            self.plane(1, c[1] as i32),
            self.plane(2, c[2] as i32),
        );
        let hi = Vec3::new(
            self.plane(0, c[0] as i32 + 1),
            self.plane(1, c[1] as i32 + 1),
            self.plane(2, c[2] as i32 + 1),
        );
        Aabb::new(lo, hi)
    }

    /// Linear index of a cell (x fastest).
    #[inline]
    pub fn linear(&self, c: [u32; 3]) -> usize {
        c[0] as usize
            + self.res[0] as usize * (c[1] as usize + self.res[1] as usize * c[2] as usize)
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.res.iter().map(|&r| r as usize).product()
    }
}

/// A uniform grid over the bounded primitives. Cells are stored compactly
/// (CSR): cell `k` holds `items[offsets[k]..offsets[k + 1]]`.
pub struct Grid {
    lattice: Lattice,
    offsets: Vec<u32>,
    items: Vec<u32>,
    /// Unpadded union of the primitives' boxes.
    bounds: Aabb,
    mailbox: bool,
}

impl Grid {
    /// A grid over the primitives `ids` of `prims`; `res` fixes the cells per
    /// axis, `None` picks them from the primitive count (see `build.rs`).
    pub fn new(prims: &[Primitive], ids: Vec<u32>, res: Option<[u32; 3]>) -> Self {
        build::build(prims, &ids, res)
    }

    /// Where the cells are.
    pub fn lattice(&self) -> &Lattice {
        &self.lattice
    }

    /// Primitive ids in cell `c`.
    pub fn cell_items(&self, c: [u32; 3]) -> &[u32] {
        let k = self.lattice.linear(c);
        &self.items[self.offsets[k] as usize..self.offsets[k + 1] as usize]
    }

    /// References stored over all cells (a primitive counts once per cell).
    pub fn references(&self) -> usize {
        self.items.len()
    }

    /// The cells `ray` crosses within `[tmin, tmax]`, in order.
    pub fn walk(&self, ray: &Ray, tmin: f32, tmax: f32) -> CellWalk {
        CellWalk::new(&self.lattice, ray, tmin, tmax)
    }

    /// The closest hit, calling `visit` with every cell the search walks,
    /// in order (the last one holds the accepted hit, if any). This is the
    /// renderer's search itself: [`Aggregate::intersect`] calls it with a
    /// visitor that does nothing, and the traversal views record with it.
    pub fn intersect_visiting(
        &self,
        q: Query,
        c: &mut Counters,
        mut visit: impl FnMut(&Cell),
    ) -> Option<PrimHit> {
        let mut tests = ItemTests::new(q, self.mailbox);
        for cell in self.walk(q.ray, q.tmin, q.tmax) {
            c.nodes_visited += 1;
            visit(&cell);
            if tests.closest_in(self.cell_items(cell.index), cell.t_exit, c) {
                break;
            }
        }
        tests.best()
    }

    /// Turns mailboxing off (on by default), to measure what it saves.
    pub fn set_mailbox(&mut self, on: bool) {
        self.mailbox = on;
    }
}

impl Aggregate for Grid {
    fn intersect(&self, q: Query, c: &mut Counters) -> Option<PrimHit> {
        self.intersect_visiting(q, c, |_| {})
    }

    fn occluded(&self, q: Query, c: &mut Counters) -> bool {
        let mut tests = ItemTests::new(q, self.mailbox);
        self.walk(q.ray, q.tmin, q.tmax).any(|cell| {
            c.nodes_visited += 1;
            tests.any(self.cell_items(cell.index), c)
        })
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn memory_bytes(&self) -> usize {
        (self.offsets.len() + self.items.len()) * 4
    }

    fn describe(&self) -> String {
        let [x, y, z] = self.lattice.res;
        format!("grid {x}x{y}x{z}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::testutil::{
        assert_agrees, assert_agrees_on, first_hit, ray, soup, sphere, Rng,
    };

    fn all(prims: &[Primitive]) -> Vec<u32> {
        (0..prims.len() as u32).collect()
    }

    #[test]
    fn agrees_with_brute_force() {
        let prims = soup(1, 400);
        for res in [None, Some([1, 1, 1]), Some([7, 2, 13]), Some([40, 40, 40])] {
            let g = Grid::new(&prims, all(&prims), res);
            assert_agrees(&g, &prims, 3000);
        }
    }

    #[test]
    fn every_primitive_is_in_a_cell_its_box_covers() {
        let prims = soup(2, 200);
        let g = Grid::new(&prims, all(&prims), None);
        let mut seen = vec![false; prims.len()];
        for z in 0..g.lattice.res[2] {
            for y in 0..g.lattice.res[1] {
                for x in 0..g.lattice.res[0] {
                    let cb = g.lattice.cell_bounds([x, y, z]);
                    for &id in g.cell_items([x, y, z]) {
                        seen[id as usize] = true;
                        let pb = prims[id as usize].bounds();
                        assert!(crate::accel::overlap::boxes_overlap(
                            &crate::accel::overlap::padded(&pb, 1e-3),
                            &cb
                        ));
                    }
                }
            }
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn a_hit_beyond_the_cell_waits_for_a_closer_one() {
        // A big sphere whose front is in a later cell than the small sphere,
        // but which the ray tests first (it overlaps the first cell too).
        let prims = vec![
            sphere(Vec3::new(6.0, 0.0, 0.0), 5.5),
            sphere(Vec3::new(3.0, 0.0, 0.0), 0.2),
        ];
        let g = Grid::new(&prims, all(&prims), Some([12, 1, 1]));
        let r = Ray::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::X);
        let h = first_hit(&g, &prims, &r).unwrap();
        assert_eq!(h.prim, 0);
        assert!((h.t - 1.5).abs() < 1e-5);
        let r = Ray::new(Vec3::new(3.0, 0.0, -3.0), Vec3::Z);
        let h = first_hit(&g, &prims, &r).unwrap();
        assert_eq!(h.prim, 1);
    }

    #[test]
    fn flat_grids() {
        // All triangles in the plane z = 1: one layer of cells.
        let mut rng = Rng::new(3);
        let prims: Vec<Primitive> = (0..100)
            .map(|_| {
                let a = rng.v(-3.0, 3.0) * Vec3::new(1.0, 1.0, 0.0) + Vec3::Z;
                crate::accel::testutil::prim(crate::shape::Shape::Triangle(
                    crate::shape::Triangle::new(a, a + Vec3::X, a + Vec3::Y),
                ))
            })
            .collect();
        let g = Grid::new(&prims, all(&prims), None);
        assert_eq!(g.lattice.res[2], 1);
        assert!(g.lattice.cell.z > 0.0);
        assert_agrees(&g, &prims, 2000);
    }

    /// Rays starting exactly on cell boundaries, and rays lying in a
    /// boundary plane (parallel to it), over triangles lying in those planes.
    #[test]
    fn rays_on_cell_boundaries_agree() {
        let mut prims = soup(6, 300);
        let g0 = Grid::new(&prims, all(&prims), Some([6, 6, 6]));
        let l = *g0.lattice();
        let mut r = Rng::new(8);
        // Squares in the boundary planes, so hits land on cell faces.
        for _ in 0..60 {
            let a = r.below(3);
            let mut p = r.v(-5.0, 5.0);
            p[a] = l.plane(a, 1 + (r.f() * 5.0) as i32);
            let (u, v) = (Vec3::AXES[(a + 1) % 3], Vec3::AXES[(a + 2) % 3]);
            prims.push(crate::accel::testutil::prim(crate::shape::Shape::Triangle(
                crate::shape::Triangle::new(p, p + u, p + v),
            )));
        }
        let g = Grid::new(&prims, all(&prims), Some([6, 6, 6]));
        let l = *g.lattice();
        let queries: Vec<(Ray, f32, f32)> = (0..6000)
            .map(|i| {
                let a = i % 3;
                let mut o = r.v(-6.0, 6.0);
                o[a] = l.plane(a, (r.f() * 7.0) as i32);
                let mut d = r.v(-1.0, 1.0);
                match i % 4 {
                    0 => d[a] = 0.0, // in the plane
                    1 => d = Vec3::AXES[(a + 1 + i / 4 % 2) % 3],
                    2 => d = -Vec3::AXES[a],
                    _ => {}
                }
                (Ray::new(o, d), 0.0, f32::INFINITY)
            })
            .collect();
        assert_agrees_on(&g, &prims, queries);
    }

    /// Mailboxing changes the work, never the answer.
    #[test]
    fn mailbox_saves_tests() {
        let prims = soup(4, 2000);
        let mut g = Grid::new(&prims, all(&prims), None);
        let mut r = Rng::new(5);
        let rays: Vec<Ray> = (0..2000).map(|_| ray(&mut r)).collect();
        let run = |g: &Grid| {
            let mut c = Counters::default();
            let hits: Vec<Option<PrimHit>> = rays
                .iter()
                .map(|r| g.intersect(Query::new(&prims, r, 0.0, f32::INFINITY), &mut c))
                .collect();
            (hits, c.intersection_tests)
        };
        let (with, tests_with) = run(&g);
        g.set_mailbox(false);
        let (without, tests_without) = run(&g);
        assert_eq!(with, without);
        assert!(
            tests_with < tests_without,
            "{tests_with} vs {tests_without}"
        );
    }
}
