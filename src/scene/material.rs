use crate::math::{Mat4, Vec3};

/// Phong parameters: what a surface point's shading needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phong {
    /// Diffuse reflectance (also the ambient reflectance).
    pub diffuse: Vec3,
    /// Specular reflectance.
    pub specular: Vec3,
    /// Phong exponent.
    pub exponent: f32,
    /// Mirror reflectance: weight of the reflected ray.
    pub reflective: Vec3,
    /// Transmittance: weight of the refracted ray.
    pub transparent: Vec3,
    /// Index of refraction of the inside of the surface.
    pub ior: f32,
    /// Spread of the reflected and refracted rays, `0..=1` (a roughness):
    /// 0 is a perfect mirror and clear glass, larger values blur them over
    /// a Phong lobe (see `material::glossy`).
    pub glossiness: f32,
    /// Emitted radiance (W·sr⁻¹·m⁻², per colour channel), leaving the
    /// surface's front side (both sides of a triangle or plane, the outside
    /// of a sphere). Seen by the path tracer (directly and by rays that
    /// bounce onto the surface) and sampled as an area light there; the
    /// Whitted tree and the AO integrator ignore it. Zero for the course's
    /// materials.
    pub emission: Vec3,
}

impl Default for Phong {
    /// The course's parser defaults: white diffuse, no specular, exponent 1,
    /// not reflective, opaque, index of refraction 1; and no gloss, no
    /// emission.
    fn default() -> Self {
        Self {
            diffuse: Vec3::ONE,
            specular: Vec3::ZERO,
            exponent: 1.0,
            reflective: Vec3::ZERO,
            transparent: Vec3::ZERO,
            ior: 1.0,
            glossiness: 0.0,
            emission: Vec3::ZERO,
        }
    }
}

impl Phong {
    /// Component-wise blend `(1 - s)·a + s·b` of every parameter, so textures
    /// can mix glass with metal as well as two colours.
    pub fn lerp(&self, b: &Phong, s: f32) -> Phong {
        let l = |x: Vec3, y: Vec3| x.lerp(y, s);
        Phong {
            diffuse: l(self.diffuse, b.diffuse),
            specular: l(self.specular, b.specular),
            exponent: self.exponent + (b.exponent - self.exponent) * s,
            reflective: l(self.reflective, b.reflective),
            transparent: l(self.transparent, b.transparent),
            ior: self.ior + (b.ior - self.ior) * s,
            glossiness: self.glossiness + (b.glossiness - self.glossiness) * s,
            emission: l(self.emission, b.emission),
        }
    }
}

/// The procedural patterns a texture material can have.
#[derive(Clone, Debug, PartialEq)]
pub enum TextureKind {
    /// 3-D checker: parity of the sum of the floored coordinates.
    Checkerboard,
    /// Perlin noise summed over `octaves`.
    Noise {
        /// Number of octaves.
        octaves: u32,
    },
    /// `sin(frequency·x + amplitude·turbulence)` veins.
    Marble {
        /// Number of octaves of turbulence.
        octaves: u32,
        /// Frequency of the sine.
        frequency: f32,
        /// Strength of the turbulence.
        amplitude: f32,
    },
    /// Rings around the texture-space y axis, perturbed by noise.
    Wood {
        /// Number of octaves of turbulence.
        octaves: u32,
        /// Ring frequency.
        frequency: f32,
        /// Strength of the turbulence.
        amplitude: f32,
    },
}

/// An entry of the material table.
#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// A plain Phong material.
    Phong(Phong),
    /// A solid texture blending two earlier materials of the table.
    Texture {
        /// Which pattern.
        kind: TextureKind,
        /// Maps points into texture space.
        transform: Mat4,
        /// Material where the pattern is 0.
        a: usize,
        /// Material where the pattern is 1.
        b: usize,
    },
}
