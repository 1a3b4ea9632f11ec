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
pub fn phong_light(m: &Phong, n: Vec3, to_light: Vec3, to_eye: Vec3, light: Vec3) -> Vec3 {
    let n_dot_l = n.dot(to_light);
    let mut c = m.diffuse * n_dot_l.max(0.0);
    if m.specular != Vec3::ZERO {
        let h = (to_light + to_eye).normalize_or_zero();
        let s = n.dot(h).max(0.0);
        c += m.specular * s.powf(m.exponent);
    }
    c * light
}

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
