//! Per-light data that does not depend on the shading point, computed once
//! with the world: a directional light's unit direction towards the light.
//! `light::incident` normalised it (in f64) for every shading point and
//! light, about 2% of a render's instructions. The world's lights are
//! private and never change after the build, so the table cannot fall
//! behind them.

use crate::light::{incident, Incident};
use crate::math::Vec3;
use crate::scene::Light;

/// The prepared lights of a world, index for index with its lights: a
/// directional light's `-normalize(direction)`, as `light::incident`
/// computes it.
#[derive(Clone, Debug, Default)]
pub(crate) struct PreparedLights {
    directions: Vec<Option<Vec3>>,
}

impl PreparedLights {
    /// Prepares `lights` (directional lights' directions).
    pub(crate) fn new(lights: &[Light]) -> Self {
        let directions = lights
            .iter()
            .map(|l| match l {
                Light::Directional { .. } => Some(incident(l, Vec3::ZERO).to_light),
                _ => None,
            })
            .collect();
        Self { directions }
    }

    /// `light::incident(light, p)` for `light`, the light number `index` of
    /// the lights this table was prepared from.
    #[inline]
    pub(crate) fn incident(&self, index: usize, light: &Light, p: Vec3) -> Incident {
        if let (Light::Directional { color, .. }, Some(Some(to_light))) =
            (light, self.directions.get(index))
        {
            return Incident {
                to_light: *to_light,
                color: *color,
                at: None,
            };
        }
        incident(light, p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table gives `incident`'s answer, bit for bit, for directions of
    /// every size and for the lights of other kinds.
    #[test]
    fn same_as_incident() {
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        let dirs = [
            Vec3::new(0.3, -1.7, 0.2),
            Vec3::new(-0.0, -2.0, 0.0),
            Vec3::new(1e38, 3e38, -1e38),
            Vec3::new(1e-40, 0.0, -3e-41),
            Vec3::ZERO,
            Vec3::new(f32::NAN, 1.0, 0.0),
        ];
        let mut lights: Vec<Light> = (dirs.iter())
            .map(|&direction| Light::Directional {
                direction,
                color: Vec3::new(0.5, 1.0, 2.0),
            })
            .collect();
        lights.push(Light::Point {
            position: Vec3::new(1.0, 2.0, 3.0),
            color: Vec3::ONE,
            attenuation: Vec3::X,
        });
        let prepared = PreparedLights::new(&lights);
        let p = Vec3::new(0.25, -4.0, 9.0);
        for (i, l) in lights.iter().enumerate() {
            let (a, b) = (prepared.incident(i, l, p), incident(l, p));
            assert_eq!(bits(a.to_light), bits(b.to_light), "{l:?}");
            assert_eq!(bits(a.color), bits(b.color));
            assert_eq!(a.at, b.at);
        }
    }
}
