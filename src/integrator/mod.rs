//! Integrators: what colour a ray brings back. [`Whitted`] is the classic ray
//! tree; [`RayObserver`] lets a caller watch every ray it spawns; the
//! [`Integrator`] trait is what the render loop calls, so new integrators
//! (ambient occlusion, path tracing) plug in without touching the loop.

pub mod ao;
mod kind;
mod observer;
pub mod optics;
pub mod path;
mod whitted;

pub use ao::{AmbientOcclusion, AoSettings};
pub use kind::IntegratorKind;
pub use observer::{NoObserver, RayKind, RayObserver, RayRecorder, RecordedRay};
pub use path::{LightChoice, PathSettings, PathTracer, Strategy};
pub use whitted::Whitted;

use crate::math::{Ray, Vec3};
use crate::sampler::SampleStream;
use crate::stats::Counters;
use crate::world::{Hit, World};

/// Adds a ray of `kind` to the statistics: the one place that maps a ray's
/// role to its counter, for every integrator.
pub(crate) fn count_ray(c: &mut Counters, kind: RayKind) {
    match kind {
        RayKind::Primary => c.primary += 1,
        RayKind::Reflected => c.reflected += 1,
        RayKind::Transmitted => c.refracted += 1,
        RayKind::Shadow => c.shadow += 1,
        RayKind::Occlusion => c.occlusion += 1,
    }
}

/// Radiance along camera rays: the one interface between the render loop and
/// the light transport.
///
/// `stream` is the camera sample's [`SampleStream`], already past the pixel
/// position: every random decision (light point, lens, time, glossy lobe,
/// hemisphere) takes its next dimension, so stratification reaches every
/// effect and the image stays independent of threads and tiles.
pub trait Integrator: Sync {
    /// Colour seen along the camera ray `ray` (hits with `t > tmin`), and the
    /// camera ray's hit (for the depth and normal planes).
    fn li(
        &self,
        world: &World,
        ray: &Ray,
        tmin: f32,
        stream: &mut SampleStream,
        counters: &mut Counters,
        observer: &mut impl RayObserver,
    ) -> (Vec3, Option<Hit>);
}

impl Integrator for Whitted {
    /// The classic tree takes no stream dimensions; area lights, glossy
    /// lobes and ambient occlusion take theirs as they are met.
    #[inline]
    fn li(
        &self,
        world: &World,
        ray: &Ray,
        tmin: f32,
        stream: &mut SampleStream,
        counters: &mut Counters,
        observer: &mut impl RayObserver,
    ) -> (Vec3, Option<Hit>) {
        self.trace_sampled(
            world,
            ray,
            tmin,
            RayKind::Primary,
            0,
            1.0,
            stream,
            counters,
            observer,
        )
    }
}
