//! The watertight test of one triangle against up to eight rays at once,
//! with AVX: [`intersect_triangle`](super::intersect_triangle) ray by ray,
//! one lane per ray, bit for bit. For packets of rays that reach a leaf
//! together (`accel::bvh8::packet`): a block's triangles are tested one at a
//! time against the packet's rays, so that every 256-bit operation serves
//! eight (triangle, ray) pairs, where a ray alone fills four f32 lanes with
//! a block (`RaySpace4`) and the exact f64 test four.
//!
//! Each ray has its own permutation (the dominant axis of its direction,
//! `kz`, made `z`); one call tests the lanes of one `kz`, whose vertex
//! coordinates are the same three broadcasts. A packet's rays usually share
//! it ([`WatertightRay8::by_axis`] says which lanes have which).
//!
//! The steps, per lane:
//! 1. the vertices in the ray's space, the very f32 operations of
//!    `WatertightRay::transform` (a difference, a product, a sum; no fused
//!    multiply-add: the intrinsics below are separate multiplies and adds,
//!    and LLVM does not fuse them);
//! 2. the f32 pre-test of `triangle4` (a lane is dropped only where a
//!    strict order of the rounded products proves an edge function
//!    negative and another positive: see that module's comment), which
//!    never drops a lane the exact test hits;
//! 3. on the lanes left, the exact test of `triangle4_avx::hit4_avx`: the
//!    scalar test's f64 edge functions, determinant, `t`, `deltaT` and
//!    barycentrics, each step the scalar test's IEEE operation on the same
//!    operands in the same order, with its comparisons (ordered `<`, `>`,
//!    `<=`; `det != 0` unordered, true for NaN as the scalar `det == 0.0` is
//!    false); the f64 half in two 4-lane halves.
//!
//! The one operation with a different NaN rule is `max` (`f32::max` returns
//! the number, `vmaxps`/`vmaxpd` the second operand), used only for
//! `deltaT`, only where `tmin ≥ 0`: it matters only for lanes whose `t` is
//! in `(tmin, tmax)`, where every ray-space coordinate, scaled `z` and edge
//! function is finite (`hit4_avx`'s comment gives the argument), so `max`
//! sees no NaN in a lane that can be a hit.

use super::triangle::WatertightRay;
use crate::math::{gamma, Vec4};

/// Eight f32 lanes, 32-byte aligned (one 256-bit load).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub struct F8(pub [f32; 8]);

/// The per-ray constants of the watertight test for up to eight rays, one
/// lane per ray: each ray's origin in its own permuted axes and its shear.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay8 {
    /// Lane `r`: `[o[kx], o[ky], o[kz]]` of ray `r`'s origin, its own
    /// permutation.
    o: [F8; 3],
    /// Each ray's shear (`WatertightRay::shear`).
    s: [F8; 3],
    /// The lanes whose dominant axis (`kz`) is `a`, for each axis `a`.
    pub by_axis: [u32; 3],
}

impl WatertightRay8 {
    /// The constants of `ray(r)` in lane `r` for each `r < 8` where it is
    /// `Some`; the other lanes are zero and belong to no axis.
    #[inline(always)]
    pub fn new(mut ray: impl FnMut(usize) -> Option<WatertightRay>) -> Self {
        let mut w = WatertightRay8 {
            o: [F8::default(); 3],
            s: [F8::default(); 3],
            by_axis: [0; 3],
        };
        for r in 0..8 {
            let Some(q) = ray(r) else { continue };
            for a in 0..3 {
                w.o[a].0[r] = q.origin[q.k[a]];
                w.s[a].0[r] = q.shear[a];
            }
            w.by_axis[q.k[2]] |= 1 << r;
        }
        w
    }
}

/// The hits of the watertight test of one triangle on eight rays.
#[derive(Clone, Copy, Debug)]
pub struct Hits8 {
    /// Bit `r` set when ray `r` hits in its `(tmin, tmax)`.
    pub mask: u32,
    /// Each ray's `t` (meaningful where `mask` is set).
    pub t: F8,
    /// Barycentric weight of vertex `k` for ray `r`: `b[k].0[r]`.
    pub b: [F8; 3],
}

/// [`intersect_triangle`](super::intersect_triangle) of triangle `j` of
/// the block `v` (`v[k][a]`: coordinate `a` of vertex `k`, one lane per
/// triangle, as `bvh8`'s leaf blocks hold them) on the rays of `r` in
/// `lanes`, each in its own `(tmin, tmax)` (lane `r` of each), bit for bit
/// (see the module's comment). Every lane of `lanes` must have dominant
/// axis `kz` (`r.by_axis[kz]`); lanes outside `lanes` are never hit.
///
/// Deliberately no `#[target_feature]` (as `hit4_avx`): inlined into a
/// caller compiled with AVX2, the intrinsics inline too.
///
/// # Safety
/// The CPU must support AVX (`is_x86_feature_detected!("avx")`).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub unsafe fn hit8_avx(
    r: &WatertightRay8,
    kz: usize,
    v: &[[Vec4; 3]; 3],
    j: usize,
    lanes: u32,
    tmin: &F8,
    tmax: &F8,
) -> Hits8 {
    debug_assert!(kz < 3 && lanes & !r.by_axis[kz] == 0);
    // One copy per axis: the coordinates' offsets in the block are then
    // constants (no table, no bounds checks).
    // SAFETY: the caller guarantees AVX.
    unsafe {
        match kz {
            0 => hit8::<0>(r, v, j, lanes, tmin, tmax),
            1 => hit8::<1>(r, v, j, lanes, tmin, tmax),
            _ => hit8::<2>(r, v, j, lanes, tmin, tmax),
        }
    }
}

/// [`hit8_avx`] for dominant axis `KZ`.
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn hit8<const KZ: usize>(
    r: &WatertightRay8,
    v: &[[Vec4; 3]; 3],
    j: usize,
    lanes: u32,
    tmin: &F8,
    tmax: &F8,
) -> Hits8 {
    use std::arch::x86_64::*;
    let kz = KZ;
    let miss = Hits8 {
        mask: 0,
        t: F8::default(),
        b: [F8::default(); 3],
    };
    // SAFETY (every intrinsic below): the caller guarantees AVX; the loads
    // and stores are of 32-byte aligned `F8`s.
    unsafe {
        let ld = |v: &F8| _mm256_load_ps(v.0.as_ptr());
        let (kx, ky) = ((KZ + 1) % 3, (KZ + 2) % 3);
        // Coordinate `a` of vertex `k`, broadcast from the block.
        let bc_v = |k: usize, a: usize| _mm256_broadcast_ss(&v[k][a].as_ref()[j]);
        let (ox, oy, oz) = (ld(&r.o[0]), ld(&r.o[1]), ld(&r.o[2]));
        let (sx, sy) = (ld(&r.s[0]), ld(&r.s[1]));
        let (sub, add, mul) = (_mm256_sub_ps, _mm256_add_ps, _mm256_mul_ps);
        let bc = _mm256_set1_ps;
        // 1. Ray space: `z = p[kz] − o[kz]`, `x = (p[kx] − o[kx]) + sx·z`.
        let z = [
            sub(bc_v(0, kz), oz),
            sub(bc_v(1, kz), oz),
            sub(bc_v(2, kz), oz),
        ];
        let x = [
            add(sub(bc_v(0, kx), ox), mul(sx, z[0])),
            add(sub(bc_v(1, kx), ox), mul(sx, z[1])),
            add(sub(bc_v(2, kx), ox), mul(sx, z[2])),
        ];
        let y = [
            add(sub(bc_v(0, ky), oy), mul(sy, z[0])),
            add(sub(bc_v(1, ky), oy), mul(sy, z[1])),
            add(sub(bc_v(2, ky), oy), mul(sy, z[2])),
        ];
        // 2. The pre-test: (proven negative, proven positive) per edge.
        let signs = |i: usize, j: usize| {
            let (u, w) = (mul(x[i], y[j]), mul(y[i], x[j]));
            (
                _mm256_cmp_ps::<_CMP_LT_OQ>(u, w),
                _mm256_cmp_ps::<_CMP_GT_OQ>(u, w),
            )
        };
        let (n0, p0) = signs(1, 2);
        let (n1, p1) = signs(2, 0);
        let (n2, p2) = signs(0, 1);
        let or3 = |a, b, c| _mm256_or_ps(_mm256_or_ps(a, b), c);
        let rejected = _mm256_and_ps(or3(n0, n1, n2), or3(p0, p1, p2));
        let mut mask = lanes & !(_mm256_movemask_ps(rejected) as u32);
        if mask == 0 {
            return miss;
        }
        // 3. The exact test, f64, in two halves of four rays.
        let (e_lo, det_lo, in_lo) = edges::<0>(&x, &y);
        let (e_hi, det_hi, in_hi) = edges::<1>(&x, &y);
        mask &= in_lo | in_hi << 4;
        if mask == 0 {
            return miss;
        }
        let sz = ld(&r.s[2]);
        let zs = [mul(z[0], sz), mul(z[1], sz), mul(z[2], sz)];
        let (t_lo, inv_lo) = solve::<0>(&e_lo, det_lo, &zs);
        let (t_hi, inv_hi) = solve::<1>(&e_hi, det_hi, &zs);
        let t = join(t_lo, t_hi);
        let in_range = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GT_OQ>(t, ld(tmin)),
            _mm256_cmp_ps::<_CMP_LT_OQ>(t, ld(tmax)),
        );
        mask &= _mm256_movemask_ps(in_range) as u32;
        if mask == 0 {
            return miss;
        }
        // The scalar test's deltaT, where `tmin ≥ 0`, in its order.
        let sign = _mm256_set1_ps(-0.0);
        let abs = |v: __m256| _mm256_andnot_ps(sign, v);
        let max3 = |v: [__m256; 3]| {
            let m = _mm256_max_ps(abs(v[0]), abs(v[1]));
            _mm256_max_ps(m, abs(v[2]))
        };
        let max_z = max3(zs);
        let max_z_unscaled = max3(z);
        let max_x = max3(x);
        let max_y = max3(y);
        let delta_z = mul(bc(gamma(3)), max_z);
        let delta_x = mul(bc(gamma(5)), add(max_x, max_z_unscaled));
        let delta_y = mul(bc(gamma(5)), add(max_y, max_z_unscaled));
        let delta_e = mul(
            bc(2.0),
            add(
                add(mul(mul(bc(gamma(2)), max_x), max_y), mul(delta_y, max_x)),
                mul(delta_x, max_y),
            ),
        );
        let sign_d = _mm256_set1_pd(-0.0);
        let abs_d = |v: __m256d| _mm256_andnot_pd(sign_d, v);
        let max_e =
            |e: &[__m256d; 3]| _mm256_max_pd(_mm256_max_pd(abs_d(e[0]), abs_d(e[1])), abs_d(e[2]));
        let max_e = join(max_e(&e_lo), max_e(&e_hi));
        let inv_abs = join(abs_d(inv_lo), abs_d(inv_hi));
        let delta_t = mul(
            mul(
                bc(3.0),
                add(
                    add(mul(mul(bc(gamma(3)), max_e), max_z), mul(delta_e, max_z)),
                    mul(delta_z, max_e),
                ),
            ),
            inv_abs,
        );
        // Rejected where `tmin ≥ 0` and `t <= delta_t` (false for NaN).
        let close = _mm256_and_ps(
            _mm256_cmp_ps::<_CMP_GE_OQ>(ld(tmin), _mm256_setzero_ps()),
            _mm256_cmp_ps::<_CMP_LE_OQ>(t, delta_t),
        );
        mask &= !(_mm256_movemask_ps(close) as u32);
        let mut out = Hits8 {
            mask,
            t: F8::default(),
            b: [F8::default(); 3],
        };
        _mm256_store_ps(out.t.0.as_mut_ptr(), t);
        for k in 0..3 {
            let b = join(
                _mm256_mul_pd(e_lo[k], inv_lo),
                _mm256_mul_pd(e_hi[k], inv_hi),
            );
            _mm256_store_ps(out.b[k].0.as_mut_ptr(), b);
        }
        out
    }
}

/// Half `H` (rays `4H..4H + 4`) of eight f32 lanes, widened to f64
/// (exact).
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn half<const H: i32>(v: std::arch::x86_64::__m256) -> std::arch::x86_64::__m256d {
    use std::arch::x86_64::*;
    // SAFETY: the caller guarantees AVX.
    unsafe { _mm256_cvtps_pd(_mm256_extractf128_ps::<H>(v)) }
}

/// Two halves of f64 lanes rounded to f32 (to nearest, as `as f32`) and
/// joined into eight lanes.
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn join(
    lo: std::arch::x86_64::__m256d,
    hi: std::arch::x86_64::__m256d,
) -> std::arch::x86_64::__m256 {
    use std::arch::x86_64::*;
    // SAFETY: the caller guarantees AVX.
    unsafe { _mm256_set_m128(_mm256_cvtpd_ps(hi), _mm256_cvtpd_ps(lo)) }
}

/// Half `H` of the exact test's first step: the edge functions (`e0 =
/// edge(b, c)`, `e1 = edge(c, a)`, `e2 = edge(a, b)`, `edge(p, q) = p.x·q.y
/// − p.y·q.x` in f64), the determinant `(e0 + e1) + e2`, and the mask of
/// the four lanes that pass (not a negative and a positive edge function,
/// and `det != 0`).
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn edges<const H: i32>(
    x: &[std::arch::x86_64::__m256; 3],
    y: &[std::arch::x86_64::__m256; 3],
) -> (
    [std::arch::x86_64::__m256d; 3],
    std::arch::x86_64::__m256d,
    u32,
) {
    use std::arch::x86_64::*;
    // SAFETY: the caller guarantees AVX.
    unsafe {
        let xd = [half::<H>(x[0]), half::<H>(x[1]), half::<H>(x[2])];
        let yd = [half::<H>(y[0]), half::<H>(y[1]), half::<H>(y[2])];
        let e = [
            _mm256_sub_pd(_mm256_mul_pd(xd[1], yd[2]), _mm256_mul_pd(yd[1], xd[2])),
            _mm256_sub_pd(_mm256_mul_pd(xd[2], yd[0]), _mm256_mul_pd(yd[2], xd[0])),
            _mm256_sub_pd(_mm256_mul_pd(xd[0], yd[1]), _mm256_mul_pd(yd[0], xd[1])),
        ];
        let zero = _mm256_setzero_pd();
        let neg = _mm256_or_pd(
            _mm256_or_pd(
                _mm256_cmp_pd::<_CMP_LT_OQ>(e[0], zero),
                _mm256_cmp_pd::<_CMP_LT_OQ>(e[1], zero),
            ),
            _mm256_cmp_pd::<_CMP_LT_OQ>(e[2], zero),
        );
        let pos = _mm256_or_pd(
            _mm256_or_pd(
                _mm256_cmp_pd::<_CMP_GT_OQ>(e[0], zero),
                _mm256_cmp_pd::<_CMP_GT_OQ>(e[1], zero),
            ),
            _mm256_cmp_pd::<_CMP_GT_OQ>(e[2], zero),
        );
        let det = _mm256_add_pd(_mm256_add_pd(e[0], e[1]), e[2]);
        let inside = _mm256_andnot_pd(
            _mm256_and_pd(neg, pos),
            _mm256_cmp_pd::<_CMP_NEQ_UQ>(det, zero),
        );
        (e, det, _mm256_movemask_pd(inside) as u32)
    }
}

/// Half `H` of the exact test's `t`, unrounded (`t_scaled · inv_det` with
/// `t_scaled = (e0·z0 + e1·z1) + e2·z2` over the scaled `z`, and `inv_det
/// = 1 / det`), and `inv_det`.
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn solve<const H: i32>(
    e: &[std::arch::x86_64::__m256d; 3],
    det: std::arch::x86_64::__m256d,
    zs: &[std::arch::x86_64::__m256; 3],
) -> (std::arch::x86_64::__m256d, std::arch::x86_64::__m256d) {
    use std::arch::x86_64::*;
    // SAFETY: the caller guarantees AVX.
    unsafe {
        let zw = [half::<H>(zs[0]), half::<H>(zs[1]), half::<H>(zs[2])];
        let t_scaled = _mm256_add_pd(
            _mm256_add_pd(_mm256_mul_pd(e[0], zw[0]), _mm256_mul_pd(e[1], zw[1])),
            _mm256_mul_pd(e[2], zw[2]),
        );
        let inv_det = _mm256_div_pd(_mm256_set1_pd(1.0), det);
        (_mm256_mul_pd(t_scaled, inv_det), inv_det)
    }
}

#[cfg(all(test, target_arch = "x86_64"))]
mod tests {
    use super::*;
    use crate::math::testing::Lcg;
    use crate::math::{Ray, Vec3};
    use crate::shape::intersect_triangle;
    use crate::shape::triangle4::tests::{aimed, block};

    /// Tests `tri` on the rays of lanes `r` (each with its own range), one
    /// call per dominant axis, and checks every lane against the scalar
    /// test, `t` and barycentrics bit for bit. Returns the hits.
    fn check(rays: &[(Ray, f32, f32); 8], tri: &[Vec3; 3], j: usize) -> usize {
        let w: Vec<WatertightRay> = rays.iter().map(|q| WatertightRay::new(&q.0)).collect();
        let w8 = WatertightRay8::new(|r| Some(w[r]));
        let tmin = F8(rays.map(|q| q.1));
        let tmax = F8(rays.map(|q| q.2));
        // The triangle in lane `j` of a block, the others unused.
        let mut tris = [[Vec3::splat(f32::NAN); 3]; 4];
        tris[j] = *tri;
        let v = block(&tris);
        let (mut mask, mut t, mut b) = (0u32, [0f32; 8], [[0f32; 8]; 3]);
        assert_eq!(w8.by_axis.iter().fold(0, |a, m| a | m), 0xff);
        for kz in 0..3 {
            let lanes = w8.by_axis[kz];
            if lanes == 0 {
                continue;
            }
            // SAFETY: the callers checked for AVX2.
            let h = unsafe { hit8_avx(&w8, kz, &v, j, lanes, &tmin, &tmax) };
            assert_eq!(h.mask & !lanes, 0);
            mask |= h.mask;
            for r in 0..8 {
                if h.mask >> r & 1 != 0 {
                    t[r] = h.t.0[r];
                    for (bk, hk) in b.iter_mut().zip(&h.b) {
                        bk[r] = hk.0[r];
                    }
                }
            }
        }
        let mut hits = 0;
        for (r, q) in rays.iter().enumerate() {
            let want = intersect_triangle(&w[r], tri[0], tri[1], tri[2], q.1, q.2);
            assert_eq!(mask >> r & 1 != 0, want.is_some(), "{q:?} {tri:?} lane {r}");
            if let Some(h) = want {
                hits += 1;
                assert_eq!(h.t.to_bits(), t[r].to_bits(), "lane {r}");
                for (k, bk) in b.iter().enumerate() {
                    assert_eq!(h.b[k].to_bits(), bk[r].to_bits(), "lane {r}");
                }
            }
        }
        hits
    }

    /// Random triangles at every scale, eight rays aimed at a vertex, a
    /// point of an edge or the interior (ties and near ties of the edge
    /// functions) from near and far origins, from one origin (a camera's)
    /// or eight, with mixed dominant axes, `tmin` below and at zero and
    /// ranges that cut hits off: every lane is the scalar test's answer.
    #[test]
    fn agrees_with_the_scalar_test_bit_for_bit() {
        if !crate::testdata::avx2_fma("agrees_with_the_scalar_test_bit_for_bit") {
            return;
        }
        let mut g = Lcg(23);
        let (mut hits, mut lanes) = (0, 0);
        for i in 0..20_000 {
            let (mut tris, target, scale) = aimed(&mut g, i);
            if i % 7 == 0 {
                // A degenerate triangle.
                tris[0][2] = tris[0][0];
            }
            let tri = tris[0];
            let reach = match i / 18 % 4 {
                3 => 10f32.powf(-8.0 + 4.0 * g.next()),
                k => [8.0, 1e-3, 1e4][k],
            };
            let from = target + g.vec(scale * reach);
            let rays: [(Ray, f32, f32); 8] = std::array::from_fn(|r| {
                // Around the aimed-at point, from one origin or from eight.
                let o = if i % 2 == 0 {
                    from
                } else {
                    target + g.vec(scale * reach)
                };
                let to = if r == 0 {
                    target
                } else {
                    target + g.vec(scale * [0.0, 1e-6, 0.3][r % 3])
                };
                let (tmin, tmax) = match (i + r) % 4 {
                    0 => (0.0, f32::INFINITY),
                    1 => (f32::NEG_INFINITY, f32::INFINITY),
                    2 => (-0.0, 1.0 + (g.next() - 0.5) * 1e-6),
                    _ => (1e-4, 1.0 + (g.next() - 0.5) * 1e-6),
                };
                (Ray::new(o, to - o), tmin, tmax)
            });
            if rays
                .iter()
                .any(|q| !q.0.dir.is_finite() || q.0.dir == Vec3::ZERO)
            {
                continue;
            }
            hits += check(&rays, &tri, i % 4);
            lanes += 8;
        }
        // Measured: 32,510 lane hits of 143,960 lanes (the others miss,
        // or their hit falls outside a short range or within `deltaT`).
        assert!(hits > lanes / 6 && hits < lanes / 3, "{hits} of {lanes}");
    }

    /// Unused (NaN) and huge vertices whose products overflow f32, and rays
    /// along the triangle's plane.
    #[test]
    fn nan_huge_and_edge_on_triangles_agree() {
        if !crate::testdata::avx2_fma("nan_huge_and_edge_on_triangles_agree") {
            return;
        }
        let nan = Vec3::splat(f32::NAN);
        let big = Vec3::splat(f32::MAX);
        let tris = [
            [nan; 3],
            [big, -big, Vec3::new(f32::MAX, -f32::MAX, 1.0)],
            [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 1.0, 0.0)],
            [
                Vec3::new(-1.0, -1.0, 2.0),
                Vec3::new(1.0, -1.0, 2.0),
                Vec3::new(0.0, 1.0, 2.0),
            ],
        ];
        let rays = [
            Ray::new(Vec3::ZERO, Vec3::Z),
            Ray::new(Vec3::new(-1.0, 0.5, 0.0), Vec3::X),
            Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::new(1e-3, 2e-3, 1.0)),
            Ray::new(Vec3::new(0.2, 0.2, 5.0), Vec3::new(1e-3, 2e-3, -1.0)),
        ];
        for tri in &tris {
            for (tmin, tmax) in [(0.0, f32::INFINITY), (f32::NEG_INFINITY, f32::INFINITY)] {
                let q: [(Ray, f32, f32); 8] = std::array::from_fn(|r| (rays[r % 4], tmin, tmax));
                check(&q, tri, 3);
            }
        }
    }
}
