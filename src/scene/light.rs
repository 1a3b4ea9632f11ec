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
    /// A light with a surface (soft shadows): a Lambertian emitter whose
    /// radiance is `color · power / (π · emitting area)`, so `power` is the
    /// total flux whatever the size (a bigger light at the same power is
    /// dimmer per unit area, and its shadows are softer).
    Area {
        /// The emitting surface.
        shape: AreaShape,
        /// Colour of the emitted light.
        color: Vec3,
        /// Total emitted flux, in units of `color`.
        power: f32,
    },
}

/// The surface of an area light. Flat lights emit from both faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AreaShape {
    /// The parallelogram `corner + s·edge1 + t·edge2`, `s, t ∈ [0, 1]`.
    Quad {
        /// One corner.
        corner: Vec3,
        /// First edge from `corner`.
        edge1: Vec3,
        /// Second edge from `corner`.
        edge2: Vec3,
    },
    /// A flat disk.
    Disk {
        /// Centre.
        center: Vec3,
        /// Normal (need not be unit).
        normal: Vec3,
        /// Radius.
        radius: f32,
    },
    /// A sphere, emitting outwards.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
    },
}
