use crate::math::Vec3;

/// A light source.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// Light from infinitely far away, travelling along `direction`.
    Directional {
        /// Direction the light travels (towards the scene); need not be unit.
        direction: Vec3,
        /// Colour and intensity.
        color: Vec3,
    },
    /// A point light whose intensity falls off as `1 / (c + l·d + q·d²)`.
    Point {
        /// Position.
        position: Vec3,
        /// Colour and intensity.
        color: Vec3,
        /// Constant, linear and quadratic attenuation coefficients.
        attenuation: Vec3,
    },
}
