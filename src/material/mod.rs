//! Materials at a surface point: textures resolve to Phong parameters, and
//! the Phong model turns one light into reflected colour.

pub mod glossy;
mod noise;
mod phong;
mod texture;

pub use noise::{noise, octave_sum};
pub use phong::phong_light;
pub use texture::pattern;

use crate::math::Vec3;

/// Where a hit point is taken before a texture's own matrix maps it into
/// texture space.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum TextureSpace {
    /// The world-space hit point: what the 6.837 scenes are written for (their
    /// texture matrices already contain the inverse of the object's transform;
    /// see `ARCHITECTURE.md`).
    #[default]
    World,
    /// The hit point in the space of the object's innermost transform, so a
    /// texture sticks to its object wherever the scene moves it.
    Object,
}
use crate::scene::{Material, Phong};

/// The Phong parameters of material `index` at the **world-space** hit point
/// `p`. Textures map `p` through their own matrix into texture space and
/// blend two earlier materials there, recursively (a checkerboard of two
/// woods is a texture of textures); the parser guarantees references point
/// backwards, so this terminates. Every parameter is blended
/// ([`Phong::lerp`]), so a texture can mix glass with wood as well as two
/// colours, and the ambient term (ambient light × blended diffuse) follows
/// the pattern too.
///
/// **Why world space, not the object space of the hit primitive.** In the
/// 6.837 format the texture `Transform` maps *world* points into texture
/// space: scene6_15 and scene6_16 give each cube a texture matrix of
/// `UniformScale 2 · (the cube's own Transform)⁻¹`, so the pattern is carried
/// along with its cube only if the lookup point is the world point. Looked up
/// in object space, the cube's inverse transform would be applied twice, which
/// tilts and shifts the pattern. The reference renders decide it pixel for
/// pixel: scene6_15 (whose Noise uses the standard Perlin table, so the same
/// blotches appear in the same places) differs from the reference by a mean
/// of 3.7/255 per channel with world-space lookups and by 18.2/255 in object
/// space; on its octave-0 marble cube (a pure sine, no noise at all) 3.7
/// against 30.1. With the reference's ambient quirk reproduced, world-space
/// lookups match it exactly (`tests/textures.rs`). Objects without a
/// transform (scene6_13, 6_17, 6_18) cannot tell the two apart.
pub fn eval(materials: &[Material], index: u32, p: Vec3) -> Phong {
    match &materials[index as usize] {
        Material::Phong(ph) => *ph,
        Material::Texture {
            kind,
            transform,
            a,
            b,
        } => {
            let q = transform.transform_point3(p);
            let s = pattern(kind, q);
            // Nested textures are looked up at the same world point: each
            // applies its own matrix to it.
            if s <= 0.0 {
                eval(materials, *a as u32, p)
            } else if s >= 1.0 {
                eval(materials, *b as u32, p)
            } else {
                eval(materials, *a as u32, p).lerp(&eval(materials, *b as u32, p), s)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Mat4;
    use crate::scene::TextureKind;

    fn glass() -> Phong {
        Phong {
            diffuse: Vec3::new(0.1, 0.2, 0.3),
            specular: Vec3::ONE,
            exponent: 100.0,
            reflective: Vec3::splat(0.3),
            transparent: Vec3::splat(0.7),
            ior: 2.0,
            glossiness: 0.0,
            emission: Vec3::ZERO,
        }
    }

    fn wood() -> Phong {
        Phong {
            diffuse: Vec3::new(0.6, 0.5, 0.3),
            specular: Vec3::ZERO,
            exponent: 1.0,
            reflective: Vec3::new(0.1, 0.0, 0.05),
            transparent: Vec3::ZERO,
            ior: 1.0,
            glossiness: 0.0,
            emission: Vec3::ZERO,
        }
    }

    fn texture(kind: TextureKind, transform: Mat4, a: usize, b: usize) -> Material {
        Material::Texture {
            kind,
            transform,
            a,
            b,
        }
    }

    #[test]
    fn a_blend_mixes_every_phong_parameter() {
        // Noise with one octave at texture point (0, 0, 0.5) is exactly 0.5
        // (derived by hand in noise.rs): an even mix of the two materials.
        let table = [
            Material::Phong(glass()),
            Material::Phong(wood()),
            texture(TextureKind::Noise { octaves: 1 }, Mat4::IDENTITY, 0, 1),
        ];
        let m = eval(&table, 2, Vec3::new(0.0, 0.0, 0.5));
        let (g, w) = (glass(), wood());
        let mid = |a: Vec3, b: Vec3| (a + b) / 2.0;
        let close = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-6;
        assert!(close(m.diffuse, mid(g.diffuse, w.diffuse)), "{m:?}");
        assert!(close(m.specular, mid(g.specular, w.specular)), "{m:?}");
        assert!(
            close(m.reflective, mid(g.reflective, w.reflective)),
            "{m:?}"
        );
        assert!(
            close(m.transparent, mid(g.transparent, w.transparent)),
            "{m:?}"
        );
        assert!((m.exponent - 50.5).abs() < 1e-4, "{m:?}");
        assert!((m.ior - 1.5).abs() < 1e-6, "{m:?}");
    }

    #[test]
    fn pure_cells_return_the_material_unchanged() {
        let table = [
            Material::Phong(glass()),
            Material::Phong(wood()),
            texture(TextureKind::Checkerboard, Mat4::IDENTITY, 0, 1),
        ];
        assert_eq!(eval(&table, 2, Vec3::splat(0.5)), glass());
        assert_eq!(eval(&table, 2, Vec3::new(1.5, 0.5, 0.5)), wood());
    }

    #[test]
    fn the_texture_matrix_maps_the_lookup_point() {
        // Scale 2: world x = 0.75 is texture x = 1.5, the second cell.
        let table = [
            Material::Phong(glass()),
            Material::Phong(wood()),
            texture(
                TextureKind::Checkerboard,
                Mat4::from_scale(Vec3::splat(2.0)),
                0,
                1,
            ),
        ];
        assert_eq!(eval(&table, 2, Vec3::new(0.25, 0.25, 0.25)), glass());
        assert_eq!(eval(&table, 2, Vec3::new(0.75, 0.25, 0.25)), wood());
    }

    #[test]
    fn textures_nest_each_with_its_own_matrix() {
        // A checkerboard (cells of 3 world units) of two checkerboards with
        // unit cells, as scene6_18 nests two woods in a checkerboard.
        let red = Phong {
            diffuse: Vec3::X,
            ..Phong::default()
        };
        let green = Phong {
            diffuse: Vec3::Y,
            ..Phong::default()
        };
        let table = [
            Material::Phong(red),
            Material::Phong(green),
            texture(TextureKind::Checkerboard, Mat4::IDENTITY, 0, 1),
            texture(
                TextureKind::Checkerboard,
                Mat4::from_translation(Vec3::X),
                0,
                1,
            ),
            texture(
                TextureKind::Checkerboard,
                Mat4::from_scale(Vec3::splat(1.0 / 3.0)),
                2,
                3,
            ),
        ];
        // Outer cell 0 (x < 3) uses entry 2: x = 0.5 → red, x = 1.5 → green.
        assert_eq!(eval(&table, 4, Vec3::new(0.5, 0.5, 0.5)).diffuse, Vec3::X);
        assert_eq!(eval(&table, 4, Vec3::new(1.5, 0.5, 0.5)).diffuse, Vec3::Y);
        // Outer cell 1 (3 ≤ x < 6) uses entry 3, shifted by one: x = 3.5 looks
        // up 4.5 there (red), where entry 2 would have given green.
        assert_eq!(eval(&table, 4, Vec3::new(3.5, 0.5, 0.5)).diffuse, Vec3::X);
        assert_eq!(eval(&table, 4, Vec3::new(4.5, 0.5, 0.5)).diffuse, Vec3::Y);
    }
}
