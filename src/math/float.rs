//! Floating-point error analysis helpers (pbrt-v3 §3.9, pbrt-v4 §6.8).
//!
//! Every f32 operation rounds its exact result by a relative error of at
//! most `ε = 2⁻²⁴` (half an ulp). A chain of `n` such roundings stays within
//! the factor `(1 ± ε)ⁿ`, which is bounded by `1 ± γ(n)` with
//! `γ(n) = n·ε / (1 − n·ε)`: the constant of every error bound in `shape`.

use glam::{Mat3, Mat4, Vec3};

/// Half an ulp of 1: the largest relative error of one rounded f32 operation.
pub const MACHINE_EPSILON: f32 = f32::EPSILON * 0.5;

/// `γ(n) = n·ε / (1 − n·ε)`: bounds the relative error of `n` successive
/// rounded f32 operations (Higham's bound, as in pbrt).
#[inline]
pub const fn gamma(n: u32) -> f32 {
    let ne = n as f32 * MACHINE_EPSILON;
    ne / (1.0 - ne)
}

/// `m·p` for an affine `m`, and a bound on the error of the result given a
/// bound `err` on the error of `p` (pbrt-v4's `Transform` of a `Point3fi`):
/// each output coordinate is three products and three sums, so it carries
/// `γ(3)·(Σ|m_ij·p_j| + |t_i|)` of its own, plus the input's error carried
/// by `|m|` and inflated by `1 + γ(3)`.
#[inline]
pub fn transform_point_with_error(m: &Mat4, p: Vec3, err: Vec3) -> (Vec3, Vec3) {
    let q = m.transform_point3(p);
    let lin = abs_linear(m);
    let t = m.w_axis.truncate().abs();
    let own = gamma(3) * (lin * p.abs() + t);
    let carried = (1.0 + gamma(3)) * (lin * err);
    (q, own + carried)
}

/// The error `fl(m·p)` adds to `p` (an affine `m`): `γ(3)·(Σ|m_ij·p_j| + |t_i|)`.
#[inline]
pub fn transform_error(m: &Mat4, p: Vec3) -> Vec3 {
    gamma(3) * (abs_linear(m) * p.abs() + m.w_axis.truncate().abs())
}

/// The element-wise absolute value of the linear (upper 3×3) part of `m`.
#[inline]
pub fn abs_linear(m: &Mat4) -> Mat3 {
    Mat3::from_cols(
        m.x_axis.truncate().abs(),
        m.y_axis.truncate().abs(),
        m.z_axis.truncate().abs(),
    )
}

/// pbrt's `OffsetRayOrigin`: moves `p`, whose coordinates are within `err`
/// of the true surface point, along the geometric normal `n` to the side
/// that `w` leaves towards, far enough that the whole error box lies behind
/// the offset plane, and then rounds each moved coordinate one more ulp away
/// from `p` (the sum `p + offset` rounds too). A ray starting there cannot
/// re-hit the surface it leaves, whatever its direction.
// Always inlined: out of line, its Vec3 arguments stalled on store
// forwarding (see `material::phong_light`).
#[inline(always)]
pub fn offset_ray_origin(p: Vec3, err: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    let d = n.abs().dot(err);
    // Negated towards the back side by flipping sign bits (no branch: the
    // side changes from ray to ray).
    let flip = u32::from(w.dot(n) < 0.0) << 31;
    let offset = (d * n)
        .to_array()
        .map(|o| f32::from_bits(o.to_bits() ^ flip));
    let offset = Vec3::from_array(offset);
    let po = p + offset;
    Vec3::new(
        step_away(po.x, offset.x),
        step_away(po.y, offset.y),
        step_away(po.z, offset.z),
    )
}

/// `x.next_up()` where `offset > 0`, `x.next_down()` where `offset < 0`,
/// else `x`, bit for bit, without branches: the sign of an offset follows
/// the surface's normal, which changes from hit to hit, and branches on it
/// were mispredicted. Each choice is a `select_unpredictable` (a
/// conditional move) and each condition a plain `&`/`|` of comparisons:
/// written with `if`s, or with masks, the compiler branched on them (perf,
/// sphere_lights_knot: the mispredicted jumps were a fifth of
/// `Spawn::spawn_ray_to_surface`).
#[inline(always)]
pub fn step_away(x: f32, offset: f32) -> f32 {
    use std::hint::select_unpredictable as pick;
    const SIGN: u32 = 0x8000_0000;
    const INF: u32 = 0x7f80_0000;
    let (up, down) = (offset > 0.0, offset < 0.0);
    let bits = x.to_bits();
    let abs = bits & !SIGN;
    // Away from zero: a positive x stepped up, a negative one down.
    let grow = up == (bits & SIGN == 0);
    let stepped = pick(grow, bits.wrapping_add(1), bits.wrapping_sub(1));
    // ±0 steps to the smallest subnormal of the step's sign.
    let stepped = pick(abs == 0, pick(up, 1, SIGN | 1), stepped);
    // NaN stays, and so does an infinity stepped further out (one up from
    // an infinity's bits is a NaN's).
    let keep = !(up | down) | (abs > INF) | (stepped & !SIGN > INF);
    f32::from_bits(pick(keep, bits, stepped))
}

/// `(sin 2πu, cos 2πu)` for a turn fraction `u` in `[−1, 1]`, within
/// 2.5e-7 of the exact values (test `sincos_turn_is_accurate`), both
/// returned in registers: `libm`'s `sincosf` writes them through pointers,
/// and it and the wait for its results were a tenth of an area-light
/// render (perf, sphere_lights_knot at 16 spp). Out of line: inlined into
/// the Whitted tree's sample loop it made the render 30% slower.
/// The turn is reduced exactly to a nearest quarter (`r = u − q/4`,
/// `|r| ≤ 1/8`, exact in f32), and the sine and cosine of `2πr` taken from
/// their Taylor series to the 9th and 10th power (the first term left out
/// is below 2.5e-9 and 2.6e-8 at `π/4`), as polynomials in `r`.
#[inline(never)]
pub fn sincos_turn(u: f32) -> (f32, f32) {
    // Round to the nearest quarter without libm's `roundf` (a call on
    // the baseline target): adding 1.5·2²³ leaves no fraction bits.
    const SHIFT: f32 = 12_582_912.0;
    let q = (u * 4.0 + SHIFT) - SHIFT;
    let r = u - q * 0.25;
    // The series in `r` itself (each coefficient carries its power of
    // 2π), grouped in pairs on powers of r⁴ (Estrin's scheme): three
    // dependent multiply-adds deep instead of Horner's five, on the way
    // to every lens and sphere-light sample.
    // (2π)ⁿ / n!, rounded once to f32.
    const fn k(n: u32) -> f32 {
        let (mut x, mut i) = (1.0f64, 1);
        while i <= n {
            x *= std::f64::consts::TAU / i as f64;
            i += 1;
        }
        x as f32
    }
    const S: [f32; 5] = [k(1), -k(3), k(5), -k(7), k(9)];
    const C: [f32; 5] = [-k(2), k(4), -k(6), k(8), -k(10)];
    let r2 = r * r;
    let r4 = r2 * r2;
    let s = r * ((S[0] + r2 * S[1]) + r4 * ((S[2] + r2 * S[3]) + r4 * S[4]));
    let c = (1.0 + r2 * C[0]) + r4 * ((C[1] + r2 * C[2]) + r4 * (C[3] + r2 * C[4]));
    rotate_quarters(s, c, q as i32)
}

/// `(sin, cos)` of an angle `q` quarter turns further (`q` mod 4 is taken
/// from the two's complement bits): `(s, c)`, `(c, −s)`, `(−s, −c)`,
/// `(−c, s)` for `q` mod 4 = 0, 1, 2, 3. An odd quarter swaps the two; the
/// sine's sign flips for 2 and 3, the cosine's for 1 and 2. Done on the
/// bits with masks, not a `match`: the quarter is random from call to
/// call, and the `match`'s jump table was mispredicted at most calls
/// (callgrind --branch-sim, dof_spheres_lit: 70% of its jumps, 28% of
/// all the render's mispredicts).
#[inline(always)]
fn rotate_quarters(s: f32, c: f32, q: i32) -> (f32, f32) {
    let q = q as u32;
    let odd = (q & 1).wrapping_neg();
    let (sb, cb) = (s.to_bits(), c.to_bits());
    let sin = (sb & !odd) | (cb & odd);
    let cos = (cb & !odd) | (sb & odd);
    (
        f32::from_bits(sin ^ ((q & 2) << 30)),
        f32::from_bits(cos ^ (q.wrapping_add(1) & 2) << 30),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `step_away` is `next_up` / `next_down` / nothing by the offset's
    /// sign, bit for bit: on the special values, every power of two's
    /// neighbours, and a sweep of random bit patterns.
    #[test]
    fn step_away_is_next_up_or_down() {
        let want = |x: f32, o: f32| {
            if o > 0.0 {
                x.next_up()
            } else if o < 0.0 {
                x.next_down()
            } else {
                x
            }
        };
        let mut xs = vec![
            0.0,
            -0.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
            f32::MAX,
            f32::MIN,
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::from_bits(1),
            f32::from_bits(0x8000_0001),
        ];
        for e in 0..255u32 {
            for m in [0, 1, 0x7f_ffff] {
                xs.push(f32::from_bits(e << 23 | m));
                xs.push(f32::from_bits(0x8000_0000 | e << 23 | m));
            }
        }
        let mut h = 0x9e37_79b9_u32;
        for _ in 0..200_000 {
            h ^= h << 13;
            h ^= h >> 17;
            h ^= h << 5;
            xs.push(f32::from_bits(h));
        }
        for &x in &xs {
            for o in [1.0, -1.0, 0.0, -0.0, 1e-30, -1e-30, f32::NAN] {
                let (got, exp) = (step_away(x, o), want(x, o));
                assert_eq!(
                    got.to_bits(),
                    exp.to_bits(),
                    "{x:e} ({:#x}) by {o}",
                    x.to_bits()
                );
            }
        }
    }

    /// `sincos_turn` against f64 over a fine grid of turns, the quarter
    /// boundaries and both ends: within 2.5e-7, and on the unit circle.
    #[test]
    fn sincos_turn_is_accurate() {
        let n = 1 << 20;
        let mut worst = 0.0f64;
        let check = |u: f32, worst: &mut f64| {
            let (s, c) = sincos_turn(u);
            let (es, ec) = (u as f64 * std::f64::consts::TAU).sin_cos();
            let e = (s as f64 - es).abs().max((c as f64 - ec).abs());
            assert!(e < 2.5e-7, "u {u}: ({s}, {c}) vs ({es}, {ec})");
            *worst = worst.max(e);
        };
        for i in -n..=n {
            check(i as f32 / n as f32, &mut worst);
        }
        for k in -8..=8 {
            let b = k as f32 / 8.0;
            for u in [b.next_down(), b, b.next_up()] {
                if (-1.0..=1.0).contains(&u) {
                    check(u, &mut worst);
                }
            }
        }
        assert!(worst > 0.0 && worst < 2.5e-7, "{worst}");
    }

    /// The masks rotate as negation and swapping do, bit for bit (zeros,
    /// NaN and infinities included), for every quarter `sincos_turn` makes.
    #[test]
    fn rotate_quarters_is_the_quarter_turn() {
        let reference = |s: f32, c: f32, q: i32| match q & 3 {
            0 => (s, c),
            1 => (c, -s),
            2 => (-s, -c),
            _ => (-c, s),
        };
        let vals = [0.0, -0.0, 0.5, -0.75, 1.0, f32::NAN, f32::INFINITY, -1e-40];
        for q in -4..=4 {
            for &s in &vals {
                for &c in &vals {
                    let (a, b) = rotate_quarters(s, c, q);
                    let (x, y) = reference(s, c, q);
                    assert_eq!(
                        (a.to_bits(), b.to_bits()),
                        (x.to_bits(), y.to_bits()),
                        "{q}"
                    );
                }
            }
        }
    }

    #[test]
    fn gamma_is_slightly_above_n_epsilon() {
        assert!(gamma(1) > MACHINE_EPSILON);
        assert!(gamma(7) > 7.0 * MACHINE_EPSILON && gamma(7) < 7.001 * MACHINE_EPSILON);
        assert!(gamma(3) < gamma(5));
    }

    #[test]
    fn offset_clears_the_error_box_on_the_side_of_the_new_direction() {
        let p = Vec3::new(1e4, 2.0, -3.0);
        let err = Vec3::new(1e-3, 2e-3, 0.0);
        let n = Vec3::new(0.6, 0.8, 0.0);
        let up = offset_ray_origin(p, err, n, Vec3::new(0.0, 1.0, 0.5));
        let down = offset_ray_origin(p, err, n, Vec3::new(0.0, -1.0, 0.5));
        let reach = n.abs().dot(err); // 0.0022: the box's extent along n
        assert!((up - p).dot(n) >= reach && (down - p).dot(n) <= -reach);
        assert_eq!(up.z, p.z); // no offset along an axis the normal lacks
    }

    #[test]
    fn a_tiny_error_still_moves_one_ulp() {
        let p = Vec3::new(1.0, 0.0, 0.0);
        let q = offset_ray_origin(p, Vec3::ZERO, Vec3::X, Vec3::X);
        assert_eq!(q, p); // no offset at all along any axis: nothing to round
        let q = offset_ray_origin(p, Vec3::splat(1e-9), Vec3::X, Vec3::X);
        assert!(q.x > p.x);
    }

    #[test]
    fn transform_error_covers_the_exact_product() {
        let m = Mat4::from_translation(Vec3::new(1e5, -3.0, 7.5))
            * Mat4::from_rotation_y(0.7)
            * Mat4::from_scale(Vec3::new(2.0, 0.3, 1.1));
        let p = Vec3::new(0.3, -1.7, 2.9);
        let (q, e) = transform_point_with_error(&m, p, Vec3::ZERO);
        let exact = m.as_dmat4().transform_point3(p.as_dvec3());
        let off = (q.as_dvec3() - exact).abs();
        assert!(off.cmple(e.as_dvec3()).all(), "{off} > {e}");
        assert!(e.max_element() > 0.0);
    }
}
