use crate::math::Vec3;
use crate::scene::TextureKind;

/// Blend factor in `[0, 1]` of a texture at texture-space point `p`:
/// 0 selects the first material, 1 the second.
pub fn pattern(kind: &TextureKind, p: Vec3) -> f32 {
    match kind {
        TextureKind::Checkerboard => {
            // Wrapping: far-away points saturate the casts, and the plain sum
            // overflowed (a panic in debug builds); parity survives wrapping.
            let s = (p.x.floor() as i64)
                .wrapping_add(p.y.floor() as i64)
                .wrapping_add(p.z.floor() as i64);
            (s.rem_euclid(2)) as f32
        }
        // Noise, Marble and Wood: solid textures issue; until then, the first material.
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checker_parity() {
        let k = TextureKind::Checkerboard;
        assert_eq!(pattern(&k, Vec3::new(0.5, 0.5, 0.5)), 0.0);
        assert_eq!(pattern(&k, Vec3::new(1.5, 0.5, 0.5)), 1.0);
        assert_eq!(pattern(&k, Vec3::new(-0.5, 0.5, 0.5)), 1.0);
        assert_eq!(pattern(&k, Vec3::new(-0.5, -0.5, 0.5)), 0.0);
    }

    #[test]
    fn checker_far_away_does_not_overflow() {
        let k = TextureKind::Checkerboard;
        for p in [Vec3::splat(1e30), Vec3::splat(-1e30), Vec3::splat(f32::NAN)] {
            let s = pattern(&k, p);
            assert!(s == 0.0 || s == 1.0);
        }
    }
}
