//! The exact watertight test on the four triangles of a block at once, with
//! AVX: [`intersect_triangle`](super::intersect_triangle) lane by lane, bit
//! for bit.
//!
//! Why: the scalar test's edge functions, determinant and `t` are f64 (each
//! product of two f32 values is exact there, so every sign is exact). SSE2
//! holds two f64 lanes; AVX holds four, so one 256-bit operation does a
//! step of the scalar test for the whole block. The leaves called the
//! scalar test once per lane the 4-lane pre-test kept, at about 275
//! instructions a call (callgrind, bunny40k).
//!
//! **Why bit for bit.** Every step is the scalar test's IEEE operation on
//! the same operands in the same order (Rust never fuses a multiply and an
//! add; `vcvtps2pd` is exact and `vcvtpd2ps` rounds to nearest like `as
//! f32`), with the scalar test's comparisons, NaN cases included (a NaN
//! edge function is neither negative nor positive, a NaN determinant is not
//! zero, a NaN `t` is out of range, a NaN `deltaT` rejects nothing). The
//! one operation with different NaN rules is `max` (`f32::max` returns the
//! number, `vmaxps` its second operand): it is used only for `deltaT`, only
//! when `tmin ≥ 0`, and there it only matters for lanes whose `t` is in
//! `(tmin, tmax)`, so finite and positive. Such a `t` needs a finite
//! non-zero determinant (an infinite one gives `t = 0` or NaN) and a finite
//! `t_scaled`, so every edge function and every scaled `z` is finite (a
//! non-finite one makes a product infinite or `0 · ∞ = NaN`), and so is
//! every ray-space coordinate (each is a factor of an edge function or of
//! a scaled `z`): `max` sees no NaN in a lane that can be a hit.

use super::triangle4::{RaySpace4, WatertightRay4};
use crate::math::{gamma, Vec4};

/// The hits of the watertight test on a block's four lanes.
#[derive(Clone, Copy, Debug)]
pub struct Hits4 {
    /// Bit `i` set when lane `i` is hit in `(tmin, tmax)`.
    pub mask: u32,
    /// Each lane's `t` (meaningful where `mask` is set).
    pub t: [f32; 4],
    /// Barycentric weight of vertex `k` in lane `i`: `b[k][i]`.
    pub b: [[f32; 4]; 3],
}

/// [`intersect_triangle`](super::intersect_triangle) on the four lanes of
/// `s` (a block in the ray space of `r`), bit for bit (see the module's
/// comment), for the same `tmin` and `tmax`. Lanes whose vertices are NaN
/// (unused) come out as the scalar test would leave them: not hit.
///
/// Deliberately no `#[target_feature]`, as `bvh8`'s AVX box test: such a
/// function cannot be `#[inline(always)]`; inlined into a caller compiled
/// with AVX2, the intrinsics inline too.
///
/// # Safety
/// The CPU must support AVX (`is_x86_feature_detected!("avx")`).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub unsafe fn hit4_avx(r: &WatertightRay4, s: &RaySpace4, tmin: f32, tmax: f32) -> Hits4 {
    use std::arch::x86_64::*;
    // SAFETY (every intrinsic below): the caller guarantees AVX; the
    // conversions between `Vec4` and `__m128` are glam's own (same 16-byte
    // layout), and the stores write 16 bytes into `[f32; 4]` arrays.
    unsafe {
        let wide = |v: Vec4| _mm256_cvtps_pd(v.into());
        let narrow = |v: __m256d| Vec4::from(_mm256_cvtpd_ps(v));
        let (x, y) = (s.x.map(wide), s.y.map(wide));
        // edge(p, q) = p.x·q.y − p.y·q.x, in f64.
        let edge = |i: usize, j: usize| {
            _mm256_sub_pd(_mm256_mul_pd(x[i], y[j]), _mm256_mul_pd(y[i], x[j]))
        };
        let e = [edge(1, 2), edge(2, 0), edge(0, 1)];
        let zero = _mm256_setzero_pd();
        let or3 = |m: [__m256d; 3]| _mm256_or_pd(_mm256_or_pd(m[0], m[1]), m[2]);
        let neg = or3(e.map(|e| _mm256_cmp_pd::<_CMP_LT_OQ>(e, zero)));
        let pos = or3(e.map(|e| _mm256_cmp_pd::<_CMP_GT_OQ>(e, zero)));
        let det = _mm256_add_pd(_mm256_add_pd(e[0], e[1]), e[2]);
        // Kept: not (a negative and a positive edge), and `det != 0` (true
        // for NaN, as the scalar `det == 0.0` is false).
        let inside = _mm256_andnot_pd(
            _mm256_and_pd(neg, pos),
            _mm256_cmp_pd::<_CMP_NEQ_UQ>(det, zero),
        );
        let mut mask = _mm256_movemask_pd(inside) as u32;
        if mask == 0 {
            return Hits4 {
                mask,
                t: [0.0; 4],
                b: [[0.0; 4]; 3],
            };
        }
        let z = s.z.map(|z| z * r.sz);
        let zw = z.map(wide);
        let t_scaled = _mm256_add_pd(
            _mm256_add_pd(_mm256_mul_pd(e[0], zw[0]), _mm256_mul_pd(e[1], zw[1])),
            _mm256_mul_pd(e[2], zw[2]),
        );
        let inv_det = _mm256_div_pd(_mm256_set1_pd(1.0), det);
        let t = narrow(_mm256_mul_pd(t_scaled, inv_det));
        mask &= (t.cmpgt(Vec4::splat(tmin)) & t.cmplt(Vec4::splat(tmax))).bitmask();
        if tmin >= 0.0 && mask != 0 {
            // The scalar test's deltaT, lane-wise, in its order.
            let max3 = |v: [Vec4; 3]| v[0].abs().max(v[1].abs()).max(v[2].abs());
            let max_z = max3(z);
            let max_z_unscaled = max3(s.z);
            let max_x = max3(s.x);
            let max_y = max3(s.y);
            let delta_z = gamma(3) * max_z;
            let delta_x = gamma(5) * (max_x + max_z_unscaled);
            let delta_y = gamma(5) * (max_y + max_z_unscaled);
            let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
            let sign = _mm256_set1_pd(-0.0);
            let abs = |v: __m256d| _mm256_andnot_pd(sign, v);
            let max_e = narrow(_mm256_max_pd(
                _mm256_max_pd(abs(e[0]), abs(e[1])),
                abs(e[2]),
            ));
            let delta_t = 3.0
                * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e)
                * narrow(abs(inv_det));
            // Rejected where `t <= delta_t` (false for NaN).
            mask &= !t.cmple(delta_t).bitmask();
        }
        let mut out = Hits4 {
            mask,
            t: t.to_array(),
            b: [[0.0; 4]; 3],
        };
        for (k, b) in out.b.iter_mut().enumerate() {
            *b = narrow(_mm256_mul_pd(e[k], inv_det)).to_array();
        }
        out
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::math::testing::Lcg;
    use crate::math::{Ray, Vec3};
    use crate::shape::triangle4::tests::{aimed, block};
    use crate::shape::{intersect_triangle, WatertightRay};

    /// Checks one ray against four triangles: every lane's answer is the
    /// scalar test's, `t` and barycentrics bit for bit. Returns the hits.
    fn check(ray: &Ray, tris: &[[Vec3; 3]; 4], tmin: f32, tmax: f32) -> usize {
        let w = WatertightRay::new(ray);
        let w4 = WatertightRay4::new(&w);
        // SAFETY: the callers checked for AVX2.
        let got = unsafe { hit4_avx(&w4, &RaySpace4::new(&w4, &block(tris)), tmin, tmax) };
        let mut hits = 0;
        for (lane, [p0, p1, p2]) in tris.iter().enumerate() {
            let want = intersect_triangle(&w, *p0, *p1, *p2, tmin, tmax);
            let bit = got.mask & (1 << lane) != 0;
            assert_eq!(bit, want.is_some(), "{ray:?} {tris:?} lane {lane}");
            if let Some(h) = want {
                hits += 1;
                assert_eq!(h.t.to_bits(), got.t[lane].to_bits(), "lane {lane}");
                for k in 0..3 {
                    assert_eq!(h.b[k].to_bits(), got.b[k][lane].to_bits(), "lane {lane}");
                }
            }
        }
        hits
    }

    /// Random triangles at every scale, rays aimed at vertices, edge points
    /// and interiors (ties and near ties of the edge functions), from near
    /// and far, with `tmin` below and at zero and ranges that cut hits off:
    /// the 4-lane test agrees with the scalar test on every lane.
    #[test]
    fn agrees_with_the_scalar_test_bit_for_bit() {
        if !crate::testdata::avx2_fma("agrees_with_the_scalar_test_bit_for_bit") {
            return;
        }
        let mut g = Lcg(11);
        let mut hits = 0;
        for i in 0..40_000 {
            let (mut tris, target, scale) = aimed(&mut g, i);
            if i % 7 == 0 {
                // A shared edge, and a degenerate lane.
                tris[1] = [tris[0][1], tris[0][0], tris[1][2]];
                tris[3] = [tris[0][0], tris[0][1], tris[0][0]];
            }
            // Near origins (reach 1e-8 to 1e-4 of the triangles' size) put
            // `t` near the scalar test's `deltaT`, which then decides.
            let reach = match i / 18 % 4 {
                3 => 10f32.powf(-8.0 + 4.0 * g.next()),
                k => [8.0, 1e-3, 1e4][k],
            };
            let from = target + g.vec(scale * reach);
            let ray = Ray::new(from, target - from);
            if !ray.dir.is_finite() || ray.dir == Vec3::ZERO {
                continue;
            }
            for (tmin, tmax) in [(0.0, f32::INFINITY), (f32::NEG_INFINITY, f32::INFINITY)] {
                hits += check(&ray, &tris, tmin, tmax);
            }
            // A range ending just before or after the aimed-at point.
            let tmax = 1.0 + (g.next() - 0.5) * 1e-6;
            hits += check(&ray, &tris, 1e-4, tmax);
        }
        // Measured: 67,215 lane hits in about 120,000 checks (some rays
        // miss lane 0's triangle, some hits fall outside the short range,
        // and other lanes are hit now and then).
        assert!((50_000..90_000).contains(&hits), "{hits}");
    }

    /// Unused lanes (NaN vertices), huge coordinates whose products
    /// overflow f32, and a ray along a triangle's plane.
    #[test]
    fn nan_huge_and_edge_on_lanes_agree() {
        if !crate::testdata::avx2_fma("nan_huge_and_edge_on_lanes_agree") {
            return;
        }
        let nan = Vec3::splat(f32::NAN);
        let big = Vec3::splat(f32::MAX);
        let flat = [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 1.0, 0.0)];
        let tris = [
            [nan; 3],
            [big, -big, Vec3::new(f32::MAX, -f32::MAX, 1.0)],
            flat,
            [
                Vec3::new(-1.0, -1.0, 2.0),
                Vec3::new(1.0, -1.0, 2.0),
                Vec3::new(0.0, 1.0, 2.0),
            ],
        ];
        for ray in [
            Ray::new(Vec3::ZERO, Vec3::Z),
            Ray::new(Vec3::new(-1.0, 0.5, 0.0), Vec3::X),
            Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::new(1e-3, 2e-3, 1.0)),
        ] {
            for (tmin, tmax) in [(0.0, f32::INFINITY), (f32::NEG_INFINITY, f32::INFINITY)] {
                check(&ray, &tris, tmin, tmax);
            }
        }
    }
}
