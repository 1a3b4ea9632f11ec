//! Light sampling: what a light sends to a surface point. Point and
//! directional lights send it along one direction ([`incident`]); area lights
//! ([`area`]) are sampled: [`sample_light`] takes a 2-D sample choosing a
//! point of the light. These are the Whitted tree's entry points (the light
//! already divided by its density); [`source`] has the runtime lights that
//! report their densities, and emitter surfaces.

pub mod area;
pub mod source;

pub use source::{AreaLight, Emitter, EmitterHit, LightPoint, LightSample, LightSource};

use crate::math::{SurfacePoint, Vec2, Vec3};
use crate::scene::{Light, RenderLight};

/// Light arriving at a point from one light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Incident {
    /// Unit direction from the point towards the light.
    pub to_light: Vec3,
    /// Colour arriving (after attenuation).
    pub color: Vec3,
    /// The chosen point of an area light's surface, with a bound on its
    /// floating-point error and the light's normal there: shadow rays go to
    /// it with both ends offset ([`SurfacePoint::spawn_ray_to_surface`]).
    /// `None` for point and directional lights.
    pub at: Option<SurfacePoint>,
}

impl Incident {
    /// No light at all.
    pub const NONE: Incident = Incident {
        to_light: Vec3::ZERO,
        color: Vec3::ZERO,
        at: None,
    };
}

/// Whether the light comes from a single point or direction (one shadow ray
/// says everything) rather than from a surface that must be sampled.
pub fn is_delta(light: &RenderLight) -> bool {
    !matches!(light, Light::Area { .. })
}

/// What samples of the area light `light` seen from `p` share
/// ([`area::Prepared`]); `None` for point and directional lights.
#[inline(always)]
pub fn prepare_area(light: &RenderLight, p: Vec3) -> Option<area::Prepared> {
    match light {
        Light::Area {
            shape,
            color,
            power,
        } => Some(area::Prepared::new(
            shape,
            area::radiance(shape, *color, *power),
            p,
        )),
        _ => None,
    }
}

/// What `light` sends to point `p` through the light point chosen by `u`
/// (ignored by point and directional lights), divided by the density of
/// that choice: the mean over stratified `u` is the light's contribution.
pub fn sample_light(light: &RenderLight, p: Vec3, u: Vec2) -> Incident {
    match light {
        Light::Area {
            shape,
            color,
            power,
        } => area::sample(shape, area::radiance(shape, *color, *power), p, u),
        _ => incident(light, p),
    }
}

/// What `light` sends to point `p`; an area light is taken at the centre of
/// its sample domain (use [`sample_light`] to sample it).
pub fn incident(light: &RenderLight, p: Vec3) -> Incident {
    match light {
        Light::Area { .. } => sample_light(light, p, Vec2::splat(0.5)),
        // Directions are normalised in f64: in f32, the length of a vector
        // longer than ~1e19 overflows (shorter than ~1e-19 underflows) and the
        // light was silently lost.
        Light::Directional { direction, color } => Incident {
            to_light: -direction.as_dvec3().normalize_or_zero().as_vec3(),
            color: *color,
            at: None,
        },
        Light::Point {
            position,
            color,
            attenuation,
        } => point_incident(*position, *color, *attenuation, p),
    }
}

/// What a point light at `position` sends to `p`: direction and distance
/// in f64, the colour attenuated.
#[inline]
pub(crate) fn point_incident(position: Vec3, color: Vec3, attenuation: Vec3, p: Vec3) -> Incident {
    let d = position.as_dvec3() - p.as_dvec3();
    let dist = d.length();
    Incident {
        to_light: d.normalize_or_zero().as_vec3(),
        color: color * attenuation_factor(attenuation, dist as f32),
        at: None,
    }
}

/// `1 / (c + l·d + q·d²)`; a zero denominator (all coefficients 0, or d = 0
/// with no constant term) means no falloff rather than an infinite light.
pub fn attenuation_factor(k: Vec3, d: f32) -> f32 {
    let denom = k.x + k.y * d + k.z * d * d;
    if denom > 0.0 && denom.is_finite() {
        // Capped: `attenuation 0 0 1e-30` (or a point right at the light)
        // would otherwise make the light infinitely bright.
        (1.0 / denom).min(crate::limits::MAX_ATTENUATION_GAIN)
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn attenuation_constant_linear_quadratic() {
        assert_eq!(attenuation_factor(Vec3::new(1.0, 0.0, 0.0), 10.0), 1.0);
        assert!((attenuation_factor(Vec3::new(0.0, 0.5, 0.0), 4.0) - 0.5).abs() < 1e-6);
        assert!((attenuation_factor(Vec3::new(0.0, 0.0, 0.25), 4.0) - 0.25).abs() < 1e-6);
        assert!((attenuation_factor(Vec3::new(1.0, 1.0, 1.0), 1.0) - 1.0 / 3.0).abs() < 1e-6);
        assert_eq!(attenuation_factor(Vec3::ZERO, 0.0), 1.0);
    }

    #[test]
    fn point_light_direction_and_falloff() {
        let l = Light::Point {
            position: Vec3::new(0.0, 4.0, 0.0),
            color: Vec3::ONE,
            attenuation: Vec3::new(0.0, 0.0, 1.0),
        };
        let i = incident(&l, Vec3::ZERO);
        assert_eq!(i.to_light, Vec3::Y);
        assert!((i.color.x - 1.0 / 16.0).abs() < 1e-6);
    }

    #[test]
    fn huge_and_tiny_vectors_keep_their_direction() {
        for scale in [1e38, 1e-40] {
            let l = Light::Directional {
                direction: Vec3::new(0.0, -2.0, 0.0) * scale,
                color: Vec3::ONE,
            };
            assert_eq!(incident(&l, Vec3::ZERO).to_light, Vec3::Y, "{scale}");
        }
        let l = Light::Point {
            position: Vec3::new(0.0, 3e38, 0.0),
            color: Vec3::ONE,
            attenuation: Vec3::X,
        };
        let i = incident(&l, Vec3::new(0.0, -3e38, 0.0));
        assert_eq!(i.to_light, Vec3::Y);
        assert_eq!(i.color, Vec3::ONE);
    }

    #[test]
    fn directional_light_points_against_its_direction() {
        let l = Light::Directional {
            direction: Vec3::new(0.0, -2.0, 0.0),
            color: Vec3::ONE,
        };
        let i = incident(&l, Vec3::ZERO);
        assert_eq!(i.to_light, Vec3::Y);
    }
}
