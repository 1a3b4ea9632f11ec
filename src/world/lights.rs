//! Per-light data that does not depend on the shading point, computed once
//! with the world: a directional light's unit direction towards the light.
//! `light::incident` normalised it (in f64) for every shading point and
//! light, about 2% of a render's instructions.
//!
//! `World::lights` is a public field, so a cache built with the world could
//! fall behind an edit of it. Each entry therefore keeps the bits of the
//! direction it was made from, and is used only while the light still has
//! exactly those bits (three integer compares); otherwise the light is
//! evaluated as before. The answer is `light::incident`'s either way.

use crate::light::{incident, Incident};
use crate::math::Vec3;
use crate::scene::Light;

/// A directional light's direction as it was when normalised, and the
/// result (`-normalize(direction)`, as `light::incident` computes it).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Direction {
    bits: [u32; 3],
    to_light: Vec3,
}

/// The prepared lights of a world, index for index with its `lights`.
#[derive(Clone, Debug, Default)]
pub(crate) struct PreparedLights {
    directions: Vec<Option<Direction>>,
}

fn bits(v: Vec3) -> [u32; 3] {
    v.to_array().map(f32::to_bits)
}

impl PreparedLights {
    /// Prepares `lights` (directional lights' directions).
    pub(crate) fn new(lights: &[Light]) -> Self {
        let directions = lights
            .iter()
            .map(|l| match l {
                Light::Directional { direction, .. } => Some(Direction {
                    bits: bits(*direction),
                    to_light: incident(l, Vec3::ZERO).to_light,
                }),
                _ => None,
            })
            .collect();
        Self { directions }
    }

    /// `light::incident(light, p)` for `light`, the world's light number
    /// `index`: a directional light's direction from the table while the
    /// light still has the direction it was prepared with.
    #[inline]
    pub(crate) fn incident(&self, index: usize, light: &Light, p: Vec3) -> Incident {
        if let (Light::Directional { direction, color }, Some(Some(d))) =
            (light, self.directions.get(index))
        {
            if bits(*direction) == d.bits {
                return Incident {
                    to_light: d.to_light,
                    color: *color,
                    at: None,
                };
            }
        }
        incident(light, p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn directional(direction: Vec3) -> Light {
        Light::Directional {
            direction,
            color: Vec3::new(0.5, 1.0, 2.0),
        }
    }

    /// The table gives `incident`'s answer, for prepared lights and for
    /// lights changed (or added) after preparing.
    #[test]
    fn same_as_incident_and_never_stale() {
        let point = Light::Point {
            position: Vec3::new(1.0, 2.0, 3.0),
            color: Vec3::ONE,
            attenuation: Vec3::X,
        };
        let dirs = [
            Vec3::new(0.3, -1.7, 0.2),
            Vec3::new(-0.0, -2.0, 0.0),
            Vec3::new(1e38, 3e38, -1e38),
            Vec3::new(1e-40, 0.0, -3e-41),
            Vec3::ZERO,
            Vec3::new(f32::NAN, 1.0, 0.0),
        ];
        let mut lights: Vec<Light> = dirs.iter().map(|&d| directional(d)).collect();
        lights.push(point.clone());
        let prepared = PreparedLights::new(&lights);
        let p = Vec3::new(0.25, -4.0, 9.0);
        let check = |lights: &[Light]| {
            for (i, l) in lights.iter().enumerate() {
                let (a, b) = (prepared.incident(i, l, p), incident(l, p));
                assert_eq!(bits(a.to_light), bits(b.to_light), "{l:?}");
                assert_eq!(bits(a.color), bits(b.color));
                assert_eq!(a.at, b.at);
            }
        };
        check(&lights);
        // Edited after preparing: new directions (a sign of zero too), a
        // light of another kind, an extra light.
        lights[0] = directional(Vec3::new(0.3, -1.7, 0.25));
        lights[1] = directional(Vec3::new(0.0, -2.0, 0.0));
        lights[2] = point.clone();
        lights[6] = directional(Vec3::new(1.0, 1.0, 1.0));
        lights.push(directional(Vec3::new(0.0, 0.0, 5.0)));
        check(&lights);
    }
}
