//! A four-lane pre-test for the watertight triangle test: which of four
//! triangles the ray *might* hit, computed with 4-lane f32 arithmetic, so
//! that the exact test ([`intersect_triangle`](super::intersect_triangle),
//! f64 edge functions) runs only on those lanes.
//!
//! Why a filter and not a 4-lane copy of the test: the exact test decides
//! inside/outside by the signs of f64 edge functions and computes `t` from
//! them in f64; a 4-lane f64 version would need 2-lane SSE2 twice over.
//! Most lanes of a leaf block are clear misses, which f32 edge functions
//! with an error bound prove cheaply; the (usually zero or one) remaining
//! lanes take the scalar path, so every answer is the scalar test's answer,
//! bit for bit, by construction.
//!
//! **Why the filter never drops a hit.** The ray-space vertices are computed
//! with the very f32 operations of `WatertightRay::transform` (a difference,
//! a product, a sum, in that order; Rust never fuses them), so they are the
//! scalar test's values exactly. The scalar test's edge function `e = P − Q`
//! (`P = p·q'`, `Q = p'·q`, products of those f32 values) is computed in f64,
//! where both products are exact and the one rounded difference keeps the
//! sign: it decides on the exact sign of `P − Q`. Here the products are
//! rounded to f32, `u = fl(P)` and `w = fl(Q)`, and compared. Rounding to
//! nearest is monotone (`P ≥ Q` implies `fl(P) ≥ fl(Q)`, subnormals and
//! overflow to ±∞ included), so `u < w` proves `P < Q` and `u > w` proves
//! `P > Q`: no error bound is needed, only ties are lost (`u = w` proves
//! nothing, and the lane is kept). A lane is dropped only when some edge is
//! proven negative and another proven positive: exactly the scalar test's
//! rejection `(e₀<0 ∨ e₁<0 ∨ e₂<0) ∧ (e₀>0 ∨ …)`, on proven signs only. NaN
//! (unused lanes, or `∞ − ∞` in the transform) makes both comparisons false,
//! and the lane is kept.

use super::triangle::WatertightRay;
use crate::math::Vec4;

/// The per-ray constants of [`may_hit4`]: the permuted origin and the shear,
/// each splatted to four lanes. Made once per ray (a traversal tests many
/// blocks with one ray), so that a block's test starts with its vertices.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay4 {
    /// The permutation of [`WatertightRay`].
    k: [usize; 3],
    /// The origin's permuted coordinates `[o[kx], o[ky], o[kz]]`, splatted.
    o: [Vec4; 3],
    /// The shear's x and y, splatted.
    sx: Vec4,
    sy: Vec4,
    /// The shear's z (`1 / d_z`), splatted: the exact 4-lane test scales
    /// the z coordinates by it.
    pub(super) sz: Vec4,
}

impl WatertightRay4 {
    /// The splatted constants of `r`.
    #[inline(always)]
    pub fn new(r: &WatertightRay) -> Self {
        let [kx, ky, kz] = r.k;
        WatertightRay4 {
            k: r.k,
            o: [
                Vec4::splat(r.origin[kx]),
                Vec4::splat(r.origin[ky]),
                Vec4::splat(r.origin[kz]),
            ],
            sx: Vec4::splat(r.shear.x),
            sy: Vec4::splat(r.shear.y),
            sz: Vec4::splat(r.shear.z),
        }
    }
}

/// Four triangles in ray space (`WatertightRay::transform`, lane-wise):
/// `x[k]`, `y[k]`, `z[k]` are vertex `k`'s coordinates, one lane per
/// triangle, `z` not yet scaled by the shear.
#[derive(Clone, Copy, Debug)]
pub struct RaySpace4 {
    pub(super) x: [Vec4; 3],
    pub(super) y: [Vec4; 3],
    pub(super) z: [Vec4; 3],
}

impl RaySpace4 {
    /// The vertices `v` of a block (`v[k][a]` is coordinate `a` of vertex
    /// `k`) in the ray space of `r`: the very f32 operations of
    /// `WatertightRay::transform`, so each lane holds the scalar test's
    /// values exactly.
    #[inline(always)]
    pub fn new(r: &WatertightRay4, v: &[[Vec4; 3]; 3]) -> Self {
        let [kx, ky, kz] = r.k;
        let (o, sx, sy) = (&r.o, r.sx, r.sy);
        let z = [v[0][kz] - o[2], v[1][kz] - o[2], v[2][kz] - o[2]];
        let x = std::array::from_fn(|i| (v[i][kx] - o[0]) + sx * z[i]);
        let y = std::array::from_fn(|i| (v[i][ky] - o[1]) + sy * z[i]);
        RaySpace4 { x, y, z }
    }
}

/// The lanes (bit `i` for lane `i`) of four triangles that the exact
/// watertight test might hit, ignoring the `t` range: every lane on which
/// [`intersect_triangle`](super::intersect_triangle) returns a hit, for any
/// `tmin`/`tmax`, is in the mask. `v[k][a]` is coordinate `a` of vertex `k`,
/// one lane per triangle; `r` is [`WatertightRay4::new`] of the ray's
/// [`WatertightRay`].
#[inline(always)]
pub fn may_hit4(r: &WatertightRay4, v: &[[Vec4; 3]; 3]) -> u32 {
    RaySpace4::new(r, v).may_hit()
}

impl RaySpace4 {
    /// [`may_hit4`] on vertices already in ray space.
    #[inline(always)]
    pub fn may_hit(&self) -> u32 {
        let (x, y) = (&self.x, &self.y);
        // (proven negative, proven positive) for the edge function of
        // vertices i, j: a strict order of the rounded products is the
        // exact one (see above).
        let signs = |i: usize, j: usize| {
            let (u, w) = (x[i] * y[j], y[i] * x[j]);
            (u.cmplt(w), u.cmpgt(w))
        };
        let (n0, p0) = signs(1, 2);
        let (n1, p1) = signs(2, 0);
        let (n2, p2) = signs(0, 1);
        let rejected = (n0 | n1 | n2) & (p0 | p1 | p2);
        !rejected.bitmask() & 0xf
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::math::testing::Lcg;
    use crate::math::{Ray, Vec3};
    use crate::shape::intersect_triangle;

    /// The block of four triangles, `v[k][a]` holding coordinate `a` of
    /// vertex `k` lane by lane.
    pub(in crate::shape) fn block(t: &[[Vec3; 3]; 4]) -> [[Vec4; 3]; 3] {
        std::array::from_fn(|k| std::array::from_fn(|a| Vec4::from_array(t.map(|tri| tri[k][a]))))
    }

    /// Case `i` of the random blocks both 4-lane tests check: four
    /// triangles at one of six scales (1e-30 to 1e30) and three offsets,
    /// and a point of lane 0's triangle to aim at: a vertex, a point of an
    /// edge (where edge functions tie or nearly do) or near the interior.
    /// Returns the triangles, the point and the scale.
    pub(in crate::shape) fn aimed(g: &mut Lcg, i: usize) -> ([[Vec3; 3]; 4], Vec3, f32) {
        let scale = [1e-30f32, 1e-6, 1.0, 1e3, 1e15, 1e30][i % 6];
        let centre = g.vec(scale * [0.0, 2.0, 1e4][i / 6 % 3]);
        let tris: [[Vec3; 3]; 4] = std::array::from_fn(|_| [0; 3].map(|_| centre + g.vec(scale)));
        let [a, b, c] = tris[0];
        let s = g.next();
        let target = match i % 3 {
            0 => a,
            1 => a + s * (b - a),
            _ => (a + b + c) / 3.0 + g.vec(scale * 0.5),
        };
        (tris, target, scale)
    }

    /// Checks the filter's promise on one ray and block of four triangles.
    fn check(ray: &Ray, tris: &[[Vec3; 3]; 4]) -> (usize, usize) {
        let w = WatertightRay::new(ray);
        let mask = may_hit4(&WatertightRay4::new(&w), &block(tris));
        let mut hits = 0;
        for (lane, [p0, p1, p2]) in tris.iter().enumerate() {
            let hit = intersect_triangle(&w, *p0, *p1, *p2, f32::NEG_INFINITY, f32::INFINITY);
            if hit.is_some() {
                hits += 1;
                assert!(mask & (1 << lane) != 0, "{ray:?} {tris:?} lane {lane}");
            }
        }
        (hits, mask.count_ones() as usize)
    }

    /// Random triangles at many scales and offsets, rays aimed at their
    /// vertices and at points of their edges (where signs are ties or nearly
    /// so) and at random points: the filter keeps every hit and drops most
    /// misses.
    #[test]
    fn never_drops_a_hit() {
        let mut g = Lcg(7);
        let (mut hits, mut kept, mut total) = (0, 0, 0);
        for i in 0..40_000 {
            let (tris, target, scale) = aimed(&mut g, i);
            let from = target + g.vec(scale * 8.0);
            let ray = Ray::new(from, target - from);
            if !ray.dir.is_finite() || ray.dir == Vec3::ZERO {
                continue;
            }
            let (h, k) = check(&ray, &tris);
            hits += h;
            kept += k;
            total += 4;
        }
        eprintln!("{hits} hits, {kept} lanes kept of {total}");
        assert!(hits > 10_000, "{hits}");
        // Most misses are filtered out. Measured: 24% of the misses kept
        // (31,364 of 128,305), mostly at the 1e-30 scale, whose products
        // underflow to ties and are all kept, and lanes next to the
        // aimed-at triangle; an f32 error bound on the edge functions (the
        // filter's first form) kept 34%.
        let misses_kept = kept - hits;
        assert!(misses_kept * 10 < (total - hits) * 3, "{kept} of {total}");
    }

    /// Two triangles sharing an edge, rays through points of the edge: at
    /// least one hits (the watertight promise) and the filter keeps it.
    #[test]
    fn keeps_shared_edge_hits() {
        let (a, b) = (Vec3::new(0.1, 0.3, 0.7), Vec3::new(0.9, 0.6, 0.2));
        let c = Vec3::new(0.2, 1.1, 0.4);
        let d = a + b - c;
        let tris = [[a, b, c], [b, a, d], [a, b, c], [b, a, d]];
        for i in 0..5000 {
            let s = (i as f32 * 0.618_034).fract();
            let p = a + s * (b - a);
            let from = p + Vec3::new((i as f32 * 0.37).sin(), 2.0, (i as f32 * 0.73).cos());
            let (hits, _) = check(&Ray::new(from, p - from), &tris);
            assert!(hits >= 2);
        }
    }

    /// Unused lanes (NaN vertices) and huge coordinates are kept (the exact
    /// test decides), never wrongly dropped.
    #[test]
    fn nan_and_overflow_lanes_are_kept() {
        let w = WatertightRay::new(&Ray::new(Vec3::ZERO, Vec3::Z));
        let v = [[Vec4::NAN; 3]; 3];
        assert_eq!(may_hit4(&WatertightRay4::new(&w), &v), 0xf);
        let big = Vec3::splat(f32::MAX);
        let tris = [[big, -big, Vec3::new(f32::MAX, -f32::MAX, 1.0)]; 4];
        check(&Ray::new(Vec3::ZERO, Vec3::Z), &tris);
    }
}
