use crate::math::Vec3;
use glam::DVec3;

/// A light source. Positions are of type `P`: `DVec3` in a scene
/// description (as the file gave them, in double precision), `Vec3` in
/// rendering space ([`RenderLight`], what `crate::world` makes of it: moved
/// so that the camera is at the origin and rounded once).
#[derive(Clone, Debug, PartialEq)]
pub enum Light<P = DVec3> {
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
        position: P,
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
        shape: AreaShape<P>,
        /// Colour of the emitted light.
        color: Vec3,
        /// Total emitted flux, in units of `color`.
        power: f32,
    },
}

/// A light in rendering space: single-precision positions, camera at the
/// origin.
pub type RenderLight = Light<Vec3>;

/// An area light's surface in rendering space.
pub type RenderAreaShape = AreaShape<Vec3>;

impl<P: Copy> Light<P> {
    /// The same light with every position mapped by `f` (directions,
    /// edges and radii unchanged).
    pub fn map_points<Q>(&self, f: impl Fn(P) -> Q) -> Light<Q> {
        match self {
            Light::Directional { direction, color } => Light::Directional {
                direction: *direction,
                color: *color,
            },
            Light::Point {
                position,
                color,
                attenuation,
            } => Light::Point {
                position: f(*position),
                color: *color,
                attenuation: *attenuation,
            },
            Light::Area {
                shape,
                color,
                power,
            } => Light::Area {
                shape: shape.map_points(f),
                color: *color,
                power: *power,
            },
        }
    }
}

/// The surface of an area light. Flat lights emit from both faces. Points
/// are of type `P`, as in [`Light`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AreaShape<P = DVec3> {
    /// The parallelogram `corner + s·edge1 + t·edge2`, `s, t ∈ [0, 1]`.
    Quad {
        /// One corner.
        corner: P,
        /// First edge from `corner`.
        edge1: Vec3,
        /// Second edge from `corner`.
        edge2: Vec3,
    },
    /// A flat disk.
    Disk {
        /// Centre.
        center: P,
        /// Normal (need not be unit).
        normal: Vec3,
        /// Radius.
        radius: f32,
    },
    /// A sphere, emitting outwards.
    Sphere {
        /// Centre.
        center: P,
        /// Radius.
        radius: f32,
    },
}

impl<P: Copy> AreaShape<P> {
    /// The same surface with its point mapped by `f`.
    pub fn map_points<Q>(&self, f: impl Fn(P) -> Q) -> AreaShape<Q> {
        match *self {
            AreaShape::Quad {
                corner,
                edge1,
                edge2,
            } => AreaShape::Quad {
                corner: f(corner),
                edge1,
                edge2,
            },
            AreaShape::Disk {
                center,
                normal,
                radius,
            } => AreaShape::Disk {
                center: f(center),
                normal,
                radius,
            },
            AreaShape::Sphere { center, radius } => AreaShape::Sphere {
                center: f(center),
                radius,
            },
        }
    }
}
