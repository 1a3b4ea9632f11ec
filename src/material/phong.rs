use crate::math::Vec3;
use crate::scene::Phong;

/// Light reflected towards the viewer by one light:
/// `k_d·c·max(N·L, 0) + k_s·c·max(N·H, 0)^e` with the half vector `H`.
///
/// `n` faces the viewer's side, `to_light` and `to_eye` are unit vectors.
/// The specular term is *not* cut off when the light is behind the surface
/// (`N·L ≤ 0`): the course's scenes 3_10 and 3_12 exist to show the resulting
/// highlight that wraps past the terminator, and the reference renders have
/// it (with the cut-off, 5.7% of scene3_10's pixels differ; without, 0.7%).
// Always inlined: out of line, its `Vec3` arguments went through the stack
// in pieces that the callee's wider loads could not be forwarded from (a
// store-forwarding stall per call, a third of its time in a profile).
#[inline(always)]
pub fn phong_light(m: &Phong, n: Vec3, to_light: Vec3, to_eye: Vec3, light: Vec3) -> Vec3 {
    let n_dot_l = n.dot(to_light);
    let mut c = m.diffuse * n_dot_l.max(0.0);
    if m.specular != Vec3::ZERO {
        let h = (to_light + to_eye).normalize_or_zero();
        let s = n.dot(h).max(0.0);
        c += m.specular * specular_power(s, m.exponent);
    }
    c * light
}

/// `s^e` for `s` in `[0, 1]`: by repeated squaring when `e` is a whole
/// number up to [`SQUARING_MAX`] (the course's exponents all are), else
/// `powf`. Why: `powf` was 3.4% of a 16-spp render of scene6_07 (perf);
/// squaring takes at most 2·log2(e) multiplies; each squaring doubles the
/// relative error so far, so the result is within about `e·2⁻²³` of the
/// exact power (test `squaring_matches_powf`): at most 1.2e-4 at `e = 1024`,
/// far below the 1/255 of an 8-bit pixel, and the same on every platform.
#[inline]
fn specular_power(s: f32, e: f32) -> f32 {
    // (`e as u32` saturates, and maps NaN to 0: the round trip holds only
    // for whole numbers in range. `fract` would call `truncf` on x86-64.)
    let n = e as u32;
    if n as f32 == e && e <= SQUARING_MAX {
        let (mut base, mut n, mut r) = (s, n, 1.0f32);
        while n != 0 {
            if n & 1 == 1 {
                r *= base;
            }
            base *= base;
            n >>= 1;
        }
        r
    } else {
        s.powf(e)
    }
}

/// The largest exponent [`specular_power`] raises by squaring.
const SQUARING_MAX: f32 = 1024.0;

#[cfg(test)]
mod tests {
    use super::*;

    fn m() -> Phong {
        Phong {
            diffuse: Vec3::new(0.5, 0.5, 0.5),
            specular: Vec3::ONE,
            exponent: 10.0,
            ..Phong::default()
        }
    }

    #[test]
    fn lambert_term() {
        let l = Vec3::new(0.0, 1.0, 1.0).normalize();
        let c = phong_light(
            &Phong {
                specular: Vec3::ZERO,
                ..m()
            },
            Vec3::Y,
            l,
            Vec3::Y,
            Vec3::ONE,
        );
        assert!((c.x - 0.5 * l.y).abs() < 1e-6);
    }

    #[test]
    fn highlight_peaks_at_mirror_direction() {
        let l = Vec3::new(1.0, 1.0, 0.0).normalize();
        let e = Vec3::new(-1.0, 1.0, 0.0).normalize();
        let c = phong_light(&m(), Vec3::Y, l, e, Vec3::ONE);
        assert!((c.x - (0.5 * l.y + 1.0)).abs() < 1e-5);
        let off = phong_light(&m(), Vec3::Y, l, Vec3::Y, Vec3::ONE);
        assert!(off.x < c.x);
    }

    #[test]
    fn squaring_matches_powf() {
        // Whole exponents (squared) and others (powf), over [0, 1], against
        // the power in f64: relative error within (e + 2)·2⁻²³ (the bound
        // the squaring's doubling errors give), or below f32's normal range.
        for e in [
            0.0f32, 1.0, 2.0, 3.0, 7.0, 10.0, 64.0, 100.0, 1023.0, 1024.0, 2.5, 1500.0,
        ] {
            for k in 0..=1000 {
                let s = k as f32 / 1000.0;
                let got = specular_power(s, e);
                let want = (s as f64).powf(e as f64) as f32;
                let want64 = (s as f64).powf(e as f64);
                let rel = (e as f64 + 2.0) * 2f64.powi(-23);
                let ok = (got as f64 - want64).abs() <= rel * want64 || want64 < 1e-37;
                assert!(ok, "{s}^{e}: {got} vs {want}");
            }
        }
        assert_eq!(specular_power(0.0, 0.0), 1.0); // powf's 0^0
        assert_eq!(specular_power(0.5, 1.0), 0.5);
    }

    /// Whole exponents up to the limit take the squaring path, the same
    /// bits on every platform (here: the product written out for `e = 10`
    /// and `e = 1024`); above it and for fractions, `powf` itself.
    #[test]
    fn whole_exponents_are_squared_others_use_powf() {
        for k in 0..=100 {
            let s = k as f32 / 100.0;
            let (s2, s8) = (s * s, (s * s) * (s * s) * ((s * s) * (s * s)));
            assert_eq!(
                specular_power(s, 10.0).to_bits(),
                (s2 * s8).to_bits(),
                "{s}"
            );
            let mut p = s;
            for _ in 0..10 {
                p *= p;
            }
            assert_eq!(specular_power(s, 1024.0).to_bits(), p.to_bits(), "{s}");
            for e in [1025.0, 2.5] {
                assert_eq!(
                    specular_power(s, e).to_bits(),
                    s.powf(e).to_bits(),
                    "{s}^{e}"
                );
            }
        }
    }

    #[test]
    fn light_straight_behind_gives_nothing() {
        let c = phong_light(&m(), Vec3::Y, Vec3::NEG_Y, Vec3::Y, Vec3::ONE);
        assert_eq!(c, Vec3::ZERO);
    }
}

#[cfg(test)]
mod wrap_tests {
    use super::*;

    #[test]
    fn highlight_wraps_past_the_terminator() {
        // Light slightly below the horizon, eye above: N·L < 0 but N·H > 0.
        let m = Phong {
            diffuse: Vec3::ONE,
            specular: Vec3::ONE,
            exponent: 1.0,
            ..Phong::default()
        };
        let l = Vec3::new(1.0, -0.1, 0.0).normalize();
        let e = Vec3::new(-0.2, 1.0, 0.0).normalize();
        let c = phong_light(&m, Vec3::Y, l, e, Vec3::ONE);
        assert!(c.x > 0.0, "specular must remain: {c}");
    }
}
