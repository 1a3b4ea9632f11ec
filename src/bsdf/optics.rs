//! Where reflection and refraction directions come from, and how much
//! light a smooth dielectric reflects (Fresnel).

use crate::math::Vec3;

/// Mirror direction of `d` about the unit normal `n`: `d - 2(d·n)n`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Refracted direction of unit `d` through a surface with unit normal `n`
/// facing the incoming side (`d·n < 0`), from index `n_i` into index `n_t`
/// (Snell: `n_i sin θi = n_t sin θt`). `None` on total internal reflection.
#[inline]
pub fn refract(d: Vec3, n: Vec3, n_i: f32, n_t: f32) -> Option<Vec3> {
    let eta = n_i / n_t;
    let cos_i = -d.dot(n);
    // `eta · sin θi` rather than `eta² · sin² θi`: with an extreme index
    // ratio `eta²` overflows, and `∞ · 0` at normal incidence was NaN.
    let sin_t = eta * (1.0 - cos_i * cos_i).max(0.0).sqrt();
    if sin_t > 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
    // The tangential part `d + cos θi·n` has length sin θi, so scaled by
    // `eta` it has length sin θt and the sum is already unit length. The
    // textbook `eta·d + (eta·cos θi - cos θt)·n` cancels catastrophically
    // when `eta` is huge (both terms near ±eta·n: NaN after normalising).
    Some((eta * (d + cos_i * n) - cos_t * n).normalize_or(-n))
}

/// Fresnel reflectance of a smooth dielectric boundary for unpolarised
/// light (the mean of the two polarisations' squared amplitude ratios),
/// with `cos_i` the cosine between the incident direction and the normal of
/// the outside and `eta` the index inside over the index outside. A
/// negative `cos_i` means the light arrives from inside (the ratio is
/// inverted); 1 under total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let (cos_i, eta) = if cos_i < 0.0 {
        (-cos_i, 1.0 / eta)
    } else {
        (cos_i, eta)
    };
    let cos_i = cos_i.min(1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let parallel = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let perpendicular = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (parallel * parallel + perpendicular * perpendicular) / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirror() {
        let d = Vec3::new(1.0, -1.0, 0.0);
        assert_eq!(reflect(d, Vec3::Y), Vec3::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn snell_law_holds() {
        let d = Vec3::new(0.6, -0.8, 0.0);
        let t = refract(d, Vec3::Y, 1.0, 1.5).unwrap();
        let sin_i = d.x;
        let sin_t = t.x;
        assert!((1.0 * sin_i - 1.5 * sin_t).abs() < 1e-6);
        assert!(t.y < 0.0 && (t.length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn equal_indices_go_straight() {
        let d = Vec3::new(0.6, -0.8, 0.0);
        assert!((refract(d, Vec3::Y, 1.3, 1.3).unwrap() - d).length() < 1e-6);
    }

    #[test]
    fn total_internal_reflection_beyond_critical_angle() {
        // Critical angle from 1.5 to 1: asin(1/1.5) ≈ 41.8°.
        let steep = Vec3::new(0.6, -0.8, 0.0); // 36.9° from the normal
        assert!(refract(steep, Vec3::Y, 1.5, 1.0).is_some());
        let grazing = Vec3::new(0.8, -0.6, 0.0); // 53.1°
        assert!(refract(grazing, Vec3::Y, 1.5, 1.0).is_none());
    }

    #[test]
    fn extreme_index_ratios_stay_finite() {
        for (n_i, n_t) in [
            (1.0, 3e38),
            (3e38, 1.0),
            (1.0, 1e-38),
            (1e-38, 1.0),
            // eta overflows to infinity: the direction falls back to -n.
            (3e38, 1e-38),
        ] {
            for d in [Vec3::NEG_Y, Vec3::new(1e-3, -1.0, 0.0).normalize()] {
                if let Some(t) = refract(d, Vec3::Y, n_i, n_t) {
                    assert!(t.is_finite(), "{n_i} -> {n_t}: {t}");
                    assert!((t.length() - 1.0).abs() < 1e-5);
                    assert!(t.y < 0.0);
                }
            }
        }
        // Into a huge index the ray bends onto the normal.
        let d = Vec3::new(0.6, -0.8, 0.0);
        let t = refract(d, Vec3::Y, 1.0, 3e38).unwrap();
        assert!((t - Vec3::NEG_Y).length() < 1e-6);
    }

    #[test]
    fn normal_incidence_passes() {
        let t = refract(Vec3::NEG_Y, Vec3::Y, 1.0, 2.0).unwrap();
        assert!((t - Vec3::NEG_Y).length() < 1e-6);
    }

    #[test]
    fn fresnel_closed_forms() {
        // Normal incidence: ((η − 1)/(η + 1))², from either side.
        for eta in [1.5f32, 1.33, 2.4] {
            let want = ((eta - 1.0) / (eta + 1.0)).powi(2);
            assert!((fresnel_dielectric(1.0, eta) - want).abs() < 1e-6);
            assert!((fresnel_dielectric(-1.0, eta) - want).abs() < 1e-6);
        }
        // Brewster's angle (tan θ = η): the parallel part vanishes, so the
        // reflectance is half the perpendicular one, ((c − ηc_t)/(c + ηc_t))²/2.
        let eta = 1.5f32;
        let theta = eta.atan();
        let (c, s) = (theta.cos(), theta.sin());
        let ct = (1.0 - (s / eta).powi(2)).sqrt();
        let want = ((c - eta * ct) / (c + eta * ct)).powi(2) / 2.0;
        assert!((fresnel_dielectric(c, eta) - want).abs() < 1e-6);
        // Grazing: everything is reflected; beyond the critical angle from
        // inside (sin θ > 1/η) too; equal indices reflect nothing.
        assert!((fresnel_dielectric(1e-7, eta) - 1.0).abs() < 1e-4);
        assert_eq!(fresnel_dielectric(-0.6, eta), 1.0);
        assert!(fresnel_dielectric(-0.8, eta) < 1.0);
        assert!(fresnel_dielectric(0.3, 1.0) < 1e-12);
    }
}
