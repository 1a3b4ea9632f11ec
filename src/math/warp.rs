//! Warps from the unit square to the shapes that sampling needs (disk,
//! hemisphere, triangle), each with the density it produces.

use crate::math::float::sincos_turn;
use crate::math::{Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

/// Shirley and Chiu's concentric map from the square to the unit disk: it
/// keeps strata compact (a polar map squeezes them near the centre).
#[inline]
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let a = 2.0 * u - Vec2::ONE;
    if a == Vec2::ZERO {
        return Vec2::ZERO;
    }
    // The angle in turns (an eighth of a turn per unit of the ratio), its
    // sine and cosine by `sincos_turn`, not libm's `sincosf`.
    let (r, turns) = if a.x.abs() > a.y.abs() {
        (a.x, 0.125 * (a.y / a.x))
    } else {
        (a.y, 0.25 - 0.125 * (a.x / a.y))
    };
    let (sin, cos) = sincos_turn(turns);
    Vec2::new(cos, sin) * r
}

/// A direction of the hemisphere around unit `n` with density `cos θ / π`
/// (Malley: a point of the unit disk lifted onto the hemisphere).
#[inline]
pub fn cosine_hemisphere(n: Vec3, u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    let (t1, t2) = n.any_orthonormal_pair();
    (t1 * d.x + t2 * d.y + n * z).normalize_or(n)
}

/// The density of [`cosine_hemisphere`] at a direction whose cosine with
/// the axis is `cos_theta`: `cos θ / π` above, 0 below.
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Barycentrics of a point uniform over a triangle's area (pbrt-v4's
/// warp: equal areas of the square go to equal areas of the triangle, and
/// the diagonal of the square is not a seam).
#[inline]
pub fn uniform_triangle(u: Vec2) -> [f32; 3] {
    let (b0, b1) = if u.x < u.y {
        let b0 = u.x / 2.0;
        (b0, u.y - b0)
    } else {
        let b1 = u.y / 2.0;
        (u.x - b1, b1)
    };
    [b0, b1, 1.0 - b0 - b1]
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    /// Equal areas of the square go to equal areas of the disk: over a
    /// fine grid, the moments and the share of each ring and sector are a
    /// uniform disk's.
    #[test]
    fn concentric_map_is_uniform_over_the_disk() {
        let k = 200;
        let (mut m, mut inner) = (DVec3::ZERO, 0);
        let mut sectors = [0u32; 8];
        for i in 0..k {
            for j in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                let d = concentric_disk(u).as_dvec2();
                m += DVec3::new(d.x, d.y, d.x * d.x);
                inner += u32::from(d.length() < 0.5);
                let a = d.y.atan2(d.x).rem_euclid(std::f64::consts::TAU);
                sectors[((a / std::f64::consts::FRAC_PI_4) as usize).min(7)] += 1;
            }
        }
        let n = (k * k) as f64;
        let m = m / n;
        assert!(m.x.abs() < 1e-3 && m.y.abs() < 1e-3, "mean {m}");
        assert!((m.z - 0.25).abs() < 1e-3, "E[x²] {}", m.z);
        assert!((inner as f64 / n - 0.25).abs() < 2e-3, "inner ring {inner}");
        for s in sectors {
            assert!((s as f64 / n - 0.125).abs() < 2e-3, "{sectors:?}");
        }
        // And continuously (what keeps strata compact): neighbours on the
        // grid stay neighbours, across the diagonals between the branches.
        let at = |i: i32, j: i32| concentric_disk(Vec2::new(i as f32, j as f32) / k as f32);
        for i in 0..k {
            for j in 0..k {
                let d = at(i, j);
                let step = (at(i + 1, j) - d).length().max((at(i, j + 1) - d).length());
                assert!(step < 4.0 / k as f32, "({i}, {j}): {step}");
            }
        }
    }

    #[test]
    fn concentric_map_stays_in_the_disk() {
        for i in 0..=10 {
            for j in 0..=10 {
                let d = concentric_disk(Vec2::new(i as f32 / 10.0, j as f32 / 10.0));
                assert!(d.length() <= 1.0 + 1e-6);
            }
        }
        assert!((concentric_disk(Vec2::new(1.0, 0.5)) - Vec2::X).length() < 1e-6);
    }

    /// Cosine-weighted directions: over a fine grid of the square, none
    /// falls below the horizon, the mean of `cos θ` is 2/3, and the share
    /// with `cos θ > c` is `1 − c²` (the integral of `cos θ/π` over that cap).
    #[test]
    fn cosine_hemisphere_has_its_density() {
        let n = Vec3::new(0.2, -0.9, 0.4).normalize();
        // (A cut may fall on one ring of the grid, 4/k of the points: the
        // tolerance allows it.)
        let k = 1000;
        let cuts = [0.1f32, 0.3, 0.5, 0.7, 0.9];
        let (mut cos, mut above) = (0.0f64, [0u32; 5]);
        for i in 0..k {
            for j in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                let w = cosine_hemisphere(n, u);
                let c = w.dot(n);
                assert!(c >= 0.0 && (w.length() - 1.0).abs() < 1e-5, "{u}: {w}");
                cos += c as f64;
                for (a, cut) in above.iter_mut().zip(cuts) {
                    *a += u32::from(c > cut);
                }
            }
        }
        let n2 = (k * k) as f64;
        assert!((cos / n2 - 2.0 / 3.0).abs() < 1e-3, "{}", cos / n2);
        for (a, cut) in above.iter().zip(cuts) {
            let share = *a as f64 / n2;
            let want = 1.0 - (cut * cut) as f64;
            assert!(
                (share - want).abs() < 5e-3,
                "cos > {cut}: {share} vs {want}"
            );
        }
        assert_eq!(cosine_hemisphere_pdf(-0.5), 0.0);
        assert!((cosine_hemisphere_pdf(1.0) - 1.0 / std::f32::consts::PI).abs() < 1e-7);
    }

    /// Uniform over the triangle: barycentrics sum to 1, stay in [0, 1],
    /// and each has mean 1/3 and second moment 1/6 (a uniform triangle's).
    #[test]
    fn uniform_triangle_is_uniform() {
        let k = 200;
        let (mut m1, mut m2) = (DVec3::ZERO, DVec3::ZERO);
        for i in 0..k {
            for j in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                let b = uniform_triangle(u);
                assert!(b.iter().all(|&x| (0.0..=1.0).contains(&x)), "{b:?}");
                assert!((b[0] + b[1] + b[2] - 1.0).abs() < 1e-6);
                let b = DVec3::from(b.map(f64::from));
                m1 += b;
                m2 += b * b;
            }
        }
        let n = (k * k) as f64;
        assert!(
            (m1 / n - DVec3::splat(1.0 / 3.0)).abs().max_element() < 1e-3,
            "{m1}"
        );
        assert!(
            (m2 / n - DVec3::splat(1.0 / 6.0)).abs().max_element() < 1e-3,
            "{m2}"
        );
    }
}
