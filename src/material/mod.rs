//! Materials at a surface point: textures resolve to Phong parameters, and
//! the Phong model turns one light into reflected colour.

mod phong;
mod texture;

pub use phong::phong_light;
pub use texture::pattern;

use crate::math::Vec3;
use crate::scene::{Material, Phong};

/// The Phong parameters of material `index` at texture-lookup point `p`
/// (object space). Textures blend two earlier materials, recursively; the
/// parser guarantees references point backwards, so this terminates.
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
