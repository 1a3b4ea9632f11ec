//! What distribution ray tracing adds to a 6.837 scene: a thin lens and a
//! shutter on the camera, per-effect ray counts, ambient occlusion, a
//! moving camera.

use crate::math::Motion;
use std::sync::Arc;

/// Thin lens and shutter of the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lens {
    /// Lens radius in world units (0: a pinhole, everything sharp).
    pub aperture: f32,
    /// Distance from the eye, along the viewing direction, of the plane in
    /// focus.
    pub focus_distance: f32,
    /// Shutter open and close instants; rays get times spread over
    /// `[open, close]` (equal: no motion blur, every ray at `open`).
    pub shutter: [f32; 2],
}

impl Default for Lens {
    /// A pinhole with the shutter open at instant 0 only.
    fn default() -> Self {
        Self {
            aperture: 0.0,
            focus_distance: 1.0,
            shutter: [0.0, 0.0],
        }
    }
}

impl Lens {
    /// Whether rays get different times.
    pub fn has_motion_blur(&self) -> bool {
        self.shutter[1] > self.shutter[0]
    }

    /// Whether rays start at different lens points.
    pub fn has_depth_of_field(&self) -> bool {
        self.aperture > 0.0
    }
}

/// Rays per effect. Shadow, glossy and AO rays are split: that many per
/// shaded point. Time and lens samples are camera rays: a pixel takes
/// `spp · time · lens` camera samples, each with its own time and lens
/// point, so the total follows the lecture's cost formula.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EffectSamples {
    /// Shadow rays per area light per shaded point.
    pub shadow: u32,
    /// Rays per glossy lobe (at a camera ray's first glossy hit).
    pub glossy: u32,
    /// Shutter instants per pixel sample.
    pub time: u32,
    /// Lens points per pixel sample.
    pub lens: u32,
    /// Ambient-occlusion rays per shaded point.
    pub ao: u32,
}

impl Default for EffectSamples {
    fn default() -> Self {
        Self {
            shadow: 1,
            glossy: 1,
            time: 1,
            lens: 1,
            ao: 16,
        }
    }
}

/// The ambient-occlusion factor on the Phong ambient term.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AmbientOcclusion {
    /// Occluders farther than this do not count (positive; may be infinite).
    pub distance: f32,
}

/// Everything distribution ray tracing adds to a scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Effects {
    /// Thin lens and shutter.
    pub lens: Lens,
    /// Rays per effect.
    pub samples: EffectSamples,
    /// Ambient occlusion on the ambient term, if wanted.
    pub ambient_occlusion: Option<AmbientOcclusion>,
    /// The camera rig's keyframed motion (world space, applied to the
    /// camera's centre, direction and up), for a moving camera in an
    /// animation or in motion blur; `None`: the camera stands still.
    pub camera_motion: Option<Arc<Motion>>,
}
