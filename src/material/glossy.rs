//! Glossy lobes: directions spread around the mirror (or refracted)
//! direction with density proportional to `cos^e α` (α the angle to the
//! lobe's axis), the Phong lobe of the lecture.

use crate::math::{Vec2, Vec3};
use std::f32::consts::TAU;

/// Lobe exponent of a glossiness (roughness) `g ∈ (0, 1]`: `2/g² − 2`, the
/// usual correspondence between a Phong exponent and a roughness, so that
/// `g → 0` is a mirror and `g = 1` a uniform hemisphere (exponent 0).
pub fn lobe_exponent(glossiness: f32) -> f32 {
    let g = glossiness.clamp(1e-4, 1.0);
    (2.0 / (g * g) - 2.0).max(0.0)
}

/// A direction of the lobe of exponent `e` around the unit `axis`, chosen
/// by `u ∈ [0,1)²` with density proportional to `cos^e α` (so the ray's
/// weight is simply the material's reflective or transparent colour).
///
/// `side` is the unit normal of the side the ray must leave towards
/// (`+n` for reflection, `−n` for transmission). A direction that falls on
/// the wrong side of the surface is mirrored across the tangent plane:
/// dropping it would darken rough surfaces at grazing angles, and the
/// mirror image stays close to the lobe.
pub fn sample_lobe(axis: Vec3, side: Vec3, e: f32, u: Vec2) -> Vec3 {
    let cos_a = u.x.powf(1.0 / (e + 1.0));
    let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
    let phi = TAU * u.y;
    let (t1, t2) = axis.any_orthonormal_pair();
    let w = ((t1 * phi.cos() + t2 * phi.sin()) * sin_a + axis * cos_a).normalize_or(axis);
    let s = w.dot(side);
    if s < 0.0 {
        w - 2.0 * s * side
    } else {
        w
    }
}

/// The density (per unit solid angle) with which [`sample_lobe`] returns
/// the unit direction `w`: the `cos^e α` lobe, `(e+1)/(2π)·cos^e α` over the
/// hemisphere around `axis`, plus the same at `w`'s mirror image across the
/// tangent plane (the directions that were folded onto `w`); 0 on the wrong
/// side of the surface.
pub fn lobe_pdf(axis: Vec3, side: Vec3, e: f32, w: Vec3) -> f32 {
    let s = w.dot(side);
    if s < 0.0 {
        return 0.0;
    }
    let folded = w - 2.0 * s * side;
    let lobe = |v: Vec3| {
        let c = v.dot(axis);
        if c > 0.0 {
            c.powf(e)
        } else {
            0.0
        }
    };
    (e + 1.0) / TAU * (lobe(w) + lobe(folded))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponent_of_glossiness() {
        assert_eq!(lobe_exponent(1.0), 0.0);
        assert!((lobe_exponent(0.1) - 198.0).abs() < 1e-3);
        assert!(lobe_exponent(0.0) > 1e7);
    }

    #[test]
    fn lobe_mean_cosine_matches_the_exponent() {
        // E[cos α] = (e + 1) / (e + 2) for the cos^e lobe.
        let axis = Vec3::new(0.0, 0.0, 1.0);
        for e in [0.0f32, 1.0, 10.0, 100.0] {
            let k = 64;
            let mut sum = 0.0;
            for i in 0..k {
                for j in 0..k {
                    let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                    sum += sample_lobe(axis, axis, e, u).dot(axis);
                }
            }
            let mean = sum / (k * k) as f32;
            assert!((mean - (e + 1.0) / (e + 2.0)).abs() < 2e-3, "{e}: {mean}");
        }
    }

    #[test]
    fn lobe_is_symmetric_around_its_axis() {
        // Uniform azimuth: the mean direction lies along the axis, its
        // length the mean cosine, for an axis in no special position.
        let axis = Vec3::new(0.3, -0.5, 0.8).normalize();
        for e in [1.0f32, 10.0] {
            let k = 64;
            let mut sum = Vec3::ZERO;
            for i in 0..k {
                for j in 0..k {
                    let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                    sum += sample_lobe(axis, axis, e, u);
                }
            }
            let mean = sum / (k * k) as f32;
            let across = (mean - mean.dot(axis) * axis).length();
            assert!(
                across < 1e-3,
                "{e}: mean {mean} leans {across} off the axis"
            );
        }
    }

    #[test]
    fn lobe_centres_on_its_axis_when_the_side_differs() {
        // A mirror direction 45° from the normal: the lobe's mean lies along
        // the axis (few rays cross the surface to be mirrored back).
        let n = Vec3::Y;
        let axis = Vec3::new(1.0, 1.0, 0.0).normalize();
        let k = 64;
        let mut sum = Vec3::ZERO;
        for i in 0..k {
            for j in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                sum += sample_lobe(axis, n, 20.0, u);
            }
        }
        let mean = (sum / (k * k) as f32).normalize();
        assert!(mean.dot(axis) > 0.999, "mean direction {mean}");
    }

    #[test]
    fn directions_stay_on_the_requested_side() {
        let n = Vec3::Y;
        let axis = Vec3::new(1.0, 0.05, 0.0).normalize(); // grazing
        for i in 0..32 {
            for j in 0..32 {
                let u = Vec2::new(i as f32 / 32.0, j as f32 / 32.0);
                let (up, down) = (sample_lobe(axis, n, 5.0, u), sample_lobe(axis, -n, 5.0, u));
                assert!(up.dot(n) >= 0.0 && down.dot(n) <= 0.0);
                // A mirrored direction is still a unit vector.
                assert!((up.length() - 1.0).abs() < 1e-5, "{up}");
                assert!((down.length() - 1.0).abs() < 1e-5, "{down}");
            }
        }
    }
}
