//! 3DDDA: the cells a ray crosses, in order, as an iterator.
//!
//! How the walk steps to the next cell: every axis keeps `t_next`, the ray
//! parameter where it crosses that axis's next cell boundary; the current
//! cell ends at the smallest of the three, the walk moves one cell along that
//! axis, and that axis's `t_next` is recomputed from the boundary plane (not
//! incremented, so no error accumulates). Ties (a ray through an edge or
//! corner) step one axis at a time, yielding zero-length cells rather than
//! skipping a diagonal neighbour.

use super::Lattice;
use crate::math::Ray;

/// The face of a cell a ray came in through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Face {
    /// Axis the face is perpendicular to (0, 1, 2 for x, y, z).
    pub axis: usize,
    /// True for the cell's min side along `axis` (the ray moves towards
    /// `+axis`), false for its max side.
    pub min_side: bool,
}

/// One cell of a walk.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cell {
    /// Cell coordinates.
    pub index: [u32; 3],
    /// Ray parameter where the ray enters the cell (or the walk's start).
    pub t_enter: f32,
    /// Ray parameter where it leaves (or the walk's end).
    pub t_exit: f32,
    /// The face it entered through; `None` for the first cell when the ray
    /// starts inside the grid.
    pub entered: Option<Face>,
}

/// The cells a ray crosses within `[tmin, tmax]`, front to back.
#[derive(Clone, Debug)]
pub struct CellWalk {
    lattice: Lattice,
    origin: [f32; 3],
    /// `1 / dir`, per axis; unused where `step` is 0.
    inv: [f32; 3],
    /// -1, 0 (parallel to the axis) or +1.
    step: [i32; 3],
    idx: [i32; 3],
    t_next: [f32; 3],
    t: f32,
    t_end: f32,
    entered: Option<Face>,
    done: bool,
}

impl CellWalk {
    /// The walk of `ray` over `lattice` within `[tmin, tmax]` (empty when the
    /// ray misses the grid's box in that interval).
    pub fn new(lattice: &Lattice, ray: &Ray, tmin: f32, tmax: f32) -> Self {
        let mut w = CellWalk {
            lattice: *lattice,
            origin: ray.origin.to_array(),
            inv: [0.0; 3],
            step: [0; 3],
            idx: [0; 3],
            t_next: [f32::INFINITY; 3],
            t: tmin,
            t_end: tmax,
            entered: None,
            done: true,
        };
        if lattice.bounds.is_empty() {
            return w;
        }
        // Slab test, remembering which slab the ray entered last (the face).
        let (min, max) = (lattice.bounds.min, lattice.bounds.max);
        let mut t0 = tmin;
        let mut t1 = tmax;
        let mut entry = None;
        for a in 0..3 {
            let (o, d) = (ray.origin[a], ray.dir[a]);
            let inv = 1.0 / d;
            if !inv.is_finite() {
                // Parallel (or so nearly that 1/d overflows): inside the slab
                // or a miss. Written negated so a NaN origin misses.
                if !(o >= min[a] && o <= max[a]) {
                    return w;
                }
                continue;
            }
            w.inv[a] = inv;
            w.step[a] = if d > 0.0 { 1 } else { -1 };
            let (mut near, mut far) = ((min[a] - o) * inv, (max[a] - o) * inv);
            if near > far {
                std::mem::swap(&mut near, &mut far);
            }
            if near > t0 {
                t0 = near;
                entry = Some(Face {
                    axis: a,
                    min_side: d > 0.0,
                });
            }
            t1 = t1.min(far);
        }
        if t0.is_nan() || t1.is_nan() || t0 > t1 {
            return w;
        }
        w.t = t0;
        w.t_end = t1;
        w.entered = entry;
        w.done = false;
        for a in 0..3 {
            let p = ray.origin[a] + t0 * ray.dir[a];
            w.idx[a] = lattice.coord(a, if w.step[a] == 0 { ray.origin[a] } else { p });
            if w.step[a] != 0 {
                w.settle(a, t0);
                w.t_next[a] = w.plane_t(a, w.idx[a] + (w.step[a] > 0) as i32);
            }
        }
        w
    }

    /// Ray parameter at boundary plane `i` of `axis`.
    #[inline]
    fn plane_t(&self, axis: usize, i: i32) -> f32 {
        (self.lattice.plane(axis, i) - self.origin[axis]) * self.inv[axis]
    }

    /// Moves the start cell along `axis` until its boundaries, in `t`, are on
    /// either side of `t0`: the cell found from the rounded point `ray.at(t0)`
    /// may be one off, and a cell too far ahead would skip its predecessor.
    /// A start exactly on a boundary picks the cell the ray is entering.
    fn settle(&mut self, a: usize, t0: f32) {
        let last = self.lattice.res[a] as i32 - 1;
        if self.step[a] > 0 {
            while self.idx[a] > 0 && self.plane_t(a, self.idx[a]) > t0 {
                self.idx[a] -= 1;
            }
            while self.idx[a] < last && self.plane_t(a, self.idx[a] + 1) <= t0 {
                self.idx[a] += 1;
            }
        } else {
            while self.idx[a] < last && self.plane_t(a, self.idx[a] + 1) > t0 {
                self.idx[a] += 1;
            }
            while self.idx[a] > 0 && self.plane_t(a, self.idx[a]) <= t0 {
                self.idx[a] -= 1;
            }
        }
    }
}

impl Iterator for CellWalk {
    type Item = Cell;

    fn next(&mut self) -> Option<Cell> {
        if self.done {
            return None;
        }
        let tn = self.t_next;
        let a = if tn[0] <= tn[1] && tn[0] <= tn[2] {
            0
        } else if tn[1] <= tn[2] {
            1
        } else {
            2
        };
        let cell = Cell {
            index: self.idx.map(|i| i as u32),
            t_enter: self.t,
            t_exit: tn[a].min(self.t_end).max(self.t),
            entered: self.entered,
        };
        if tn[a].is_nan() || tn[a] >= self.t_end {
            self.done = true;
        } else {
            self.idx[a] += self.step[a];
            if self.idx[a] < 0 || self.idx[a] >= self.lattice.res[a] as i32 {
                self.done = true;
            } else {
                self.t = cell.t_exit;
                self.t_next[a] = self.plane_t(a, self.idx[a] + (self.step[a] > 0) as i32);
                self.entered = Some(Face {
                    axis: a,
                    min_side: self.step[a] > 0,
                });
            }
        }
        Some(cell)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::{Aabb, Vec3};

    /// A 4×4×4 grid of unit cells over [0, 4]³.
    fn lattice() -> Lattice {
        Lattice::new(Aabb::new(Vec3::ZERO, Vec3::splat(4.0)), [4, 4, 4])
    }

    fn walk(o: Vec3, d: Vec3) -> Vec<Cell> {
        CellWalk::new(&lattice(), &Ray::new(o, d), 0.0, f32::INFINITY).collect()
    }

    fn indices(cells: &[Cell]) -> Vec<[u32; 3]> {
        cells.iter().map(|c| c.index).collect()
    }

    /// `settle`'s promise, from every wrong start cell: it ends on the cell
    /// whose boundaries, in `t`, bracket `t0`: the boundary the ray crosses
    /// into the cell at or before `t0`, the one it leaves by after `t0`
    /// (the grid's first or last cell where `t0` lies outside). The rounded
    /// start point is rarely more than one cell off, so random rays alone
    /// never reach most of these loops.
    #[test]
    fn settling_from_any_start_cell_brackets_t0() {
        let mut r = crate::accel::testutil::Rng::new(17);
        let lat = Lattice::new(Aabb::new(Vec3::ZERO, Vec3::new(4.0, 5.0, 6.0)), [4, 5, 3]);
        let mut checked = 0;
        for i in 0..1000 {
            let o = r.v(-2.0, 8.0);
            let d = r.v(-0.5, 0.5);
            // Some starts exactly on a boundary plane (t0 = a plane's t).
            let tmin = if i % 3 == 0 { 0.0 } else { r.f() * 4.0 };
            let mut w = CellWalk::new(&lat, &Ray::new(o, d), tmin, f32::INFINITY);
            if w.done {
                continue;
            }
            let t0 = w.t;
            for a in 0..3 {
                let last = lat.res[a] as i32 - 1;
                for start in 0..=last {
                    w.idx[a] = start;
                    w.settle(a, t0);
                    let (c, s) = (w.idx[a], w.step[a]);
                    assert!((0..=last).contains(&c));
                    // Entered through plane `c` (moving up) or `c + 1`
                    // (moving down), left through the other.
                    let (inn, out) = if s > 0 { (c, c + 1) } else { (c + 1, c) };
                    let first = if s > 0 { c == 0 } else { c == last };
                    let end = if s > 0 { c == last } else { c == 0 };
                    assert!(
                        first || w.plane_t(a, inn) <= t0,
                        "ray {i} axis {a} from {start}"
                    );
                    assert!(
                        end || w.plane_t(a, out) > t0,
                        "ray {i} axis {a} from {start}"
                    );
                    checked += 1;
                }
            }
        }
        assert!(checked > 2000, "{checked}");
    }

    #[test]
    fn axis_parallel_ray_from_outside() {
        let cells = walk(Vec3::new(-1.0, 0.5, 2.5), Vec3::X);
        assert_eq!(
            indices(&cells),
            [[0, 0, 2], [1, 0, 2], [2, 0, 2], [3, 0, 2]]
        );
        let t: Vec<(f32, f32)> = cells.iter().map(|c| (c.t_enter, c.t_exit)).collect();
        assert_eq!(t, [(1.0, 2.0), (2.0, 3.0), (3.0, 4.0), (4.0, 5.0)]);
        let x_min = Some(Face {
            axis: 0,
            min_side: true,
        });
        assert!(cells.iter().all(|c| c.entered == x_min));
    }

    #[test]
    fn diagonal_ray_through_corners_visits_each_neighbour() {
        // Through the cell corners (1,1), (2,2), (3,3): ties step x first,
        // giving zero-length cells instead of skipping diagonally.
        let cells = walk(Vec3::new(-1.0, -1.0, 0.5), Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(
            indices(&cells),
            [
                [0, 0, 0],
                [1, 0, 0],
                [1, 1, 0],
                [2, 1, 0],
                [2, 2, 0],
                [3, 2, 0],
                [3, 3, 0]
            ]
        );
        assert_eq!(cells[1].t_enter, cells[1].t_exit);
        assert_eq!(cells[0].t_enter, 1.0);
        assert_eq!(cells.last().unwrap().t_exit, 5.0);
    }

    #[test]
    fn general_diagonal_ray() {
        let cells = walk(Vec3::new(0.5, 0.25, -1.0), Vec3::new(1.0, 0.5, 1.0));
        // z enters at t = 1 (x = 1.5, y = 0.75) and crosses 1, 2 at t = 2, 3;
        // x crosses 2, 3, 4 at t = 1.5, 2.5, 3.5; y crosses 1 at t = 1.5 (a
        // tie with x: x steps first).
        assert_eq!(
            indices(&cells),
            [
                [1, 0, 0],
                [2, 0, 0],
                [2, 1, 0],
                [2, 1, 1],
                [3, 1, 1],
                [3, 1, 2]
            ]
        );
        assert_eq!(cells[0].t_enter, 1.0);
        assert_eq!(
            cells[0].entered,
            Some(Face {
                axis: 2,
                min_side: true
            })
        );
    }

    #[test]
    fn ray_starting_inside() {
        let cells = walk(Vec3::new(2.5, 1.5, 0.5), Vec3::NEG_X);
        assert_eq!(indices(&cells), [[2, 1, 0], [1, 1, 0], [0, 1, 0]]);
        assert_eq!(cells[0].entered, None);
        assert_eq!((cells[0].t_enter, cells[0].t_exit), (0.0, 0.5));
        assert_eq!(
            cells[1].entered,
            Some(Face {
                axis: 0,
                min_side: false
            })
        );
    }

    #[test]
    fn ray_starting_on_a_boundary_takes_the_cell_it_enters() {
        let fwd = walk(Vec3::new(2.0, 1.5, 0.5), Vec3::X);
        assert_eq!(indices(&fwd), [[2, 1, 0], [3, 1, 0]]);
        let back = walk(Vec3::new(2.0, 1.5, 0.5), Vec3::NEG_X);
        assert_eq!(indices(&back), [[1, 1, 0], [0, 1, 0]]);
    }

    #[test]
    fn ray_lying_in_a_boundary_plane_walks_one_row() {
        let cells = walk(Vec3::new(-1.0, 2.0, 4.0), Vec3::X);
        assert_eq!(cells.len(), 4);
        assert!(cells.iter().all(|c| c.index[1] == 2 && c.index[2] == 3));
    }

    #[test]
    fn misses_and_limits() {
        assert!(walk(Vec3::new(-1.0, 5.0, 0.5), Vec3::X).is_empty());
        assert!(walk(Vec3::new(-1.0, 0.5, 0.5), Vec3::NEG_X).is_empty());
        let r = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::X);
        let cells: Vec<Cell> = CellWalk::new(&lattice(), &r, 2.5, 3.5).collect();
        assert_eq!(indices(&cells), [[1, 0, 0], [2, 0, 0]]);
        assert_eq!((cells[0].t_enter, cells[1].t_exit), (2.5, 3.5));
        let empty = Lattice::new(Aabb::EMPTY, [1, 1, 1]);
        assert_eq!(CellWalk::new(&empty, &r, 0.0, 1e9).count(), 0);
    }

    /// Against dense sampling: every cell a point of the ray falls in is
    /// visited, consecutive cells are face neighbours, intervals chain.
    #[test]
    fn random_rays_agree_with_sampling() {
        let l = Lattice::new(
            Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(2.0, 0.5, 3.0)),
            [7, 3, 5],
        );
        let mut r = crate::testutil::Rng::new(1);
        let mut rnd = move || r.f();
        for _ in 0..500 {
            let o = Vec3::new(rnd() * 5.0 - 2.0, rnd() * 2.0 - 0.75, rnd() * 3.0 + 1.0);
            let d = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
            let r = Ray::new(o, d);
            let cells: Vec<Cell> = CellWalk::new(&l, &r, 0.0, 50.0).collect();
            for w in cells.windows(2) {
                assert_eq!(w[0].t_exit, w[1].t_enter);
                let diff: u32 = (0..3).map(|a| w[0].index[a].abs_diff(w[1].index[a])).sum();
                assert_eq!(diff, 1);
            }
            let Some((t0, t1)) = l.bounds.hit(&r, d.recip(), 0.0, 50.0) else {
                assert!(cells.is_empty());
                continue;
            };
            for k in 1..1000 {
                let t = t0 + (t1 - t0) * k as f32 / 1000.0;
                let p = r.at(t);
                let c = [0, 1, 2].map(|a| l.coord(a, p[a]) as u32);
                let hit = cells
                    .iter()
                    .find(|cell| cell.index == c)
                    .unwrap_or_else(|| panic!("cell {c:?} of t = {t} not visited"));
                assert!(hit.t_enter - 1e-4 <= t && t <= hit.t_exit + 1e-4);
            }
        }
    }
}
