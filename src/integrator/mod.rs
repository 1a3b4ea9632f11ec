//! Integrators: what colour a ray brings back. [`Whitted`] is the classic ray
//! tree; [`RayObserver`] lets a caller watch every ray it spawns; the
//! [`Integrator`] trait is what the render loop calls, so new integrators
//! (ambient occlusion, path tracing) plug in without touching the loop.

pub mod ao;
pub mod caustic_map;
mod kind;
mod observer;
pub mod optics;
pub mod path;
mod whitted;

pub use ao::{AmbientOcclusion, AoSettings};
pub use kind::IntegratorKind;
pub use observer::{Branch, NoObserver, RayKind, RayObserver, RayRecorder, RecordedRay};
pub use path::{CausticPaths, LightChoice, PathSettings, PathTracer, Strategy};
pub use whitted::Whitted;

use crate::accel::PacketRay;
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

/// What every ray of one camera sample is traced with: the world, the
/// sample's [`SampleStream`] (already past the pixel position: every random
/// decision, light point, lens, time, glossy lobe or hemisphere, takes its
/// next dimension, so stratification reaches every effect and the image
/// stays independent of threads and tiles), the counters and the observer.
pub struct Trace<'a, 's, O> {
    /// The scene.
    pub world: &'a World,
    /// The camera sample's stream.
    pub stream: &'a mut SampleStream<'s>,
    /// Statistics.
    pub counters: &'a mut Counters,
    /// Told every ray traced.
    pub observer: &'a mut O,
    /// Whether the integrator traces coherent rays together where it has
    /// them (shadow rays from one point towards one area light:
    /// [`blocked_packet`](Self::blocked_packet)), the same answers as ray
    /// by ray. The render loop sets it where the world walks packets
    /// (`World::walks_packets`).
    pub packets: bool,
}

impl<O: RayObserver> Trace<'_, '_, O> {
    /// The closest hit of `ray` beyond `tmin`, the ray counted and shown to
    /// the observer as one at branch `b`. A camera ray (kind
    /// [`RayKind::Primary`]) is traced as one of a coherent run
    /// (`World::intersect_coherent`): the render loop traces a tile's
    /// camera rays one after another, and they keep their direction's
    /// signs from one to the next.
    #[inline]
    pub fn closest(&mut self, ray: &Ray, tmin: f32, b: Branch) -> Option<Hit> {
        let (w, c) = (self.world, &mut *self.counters);
        let hit = if b.kind == RayKind::Primary {
            w.intersect_coherent(ray, tmin, f32::INFINITY, c)
        } else {
            w.intersect(ray, tmin, f32::INFINITY, c)
        };
        self.seen(ray, hit.as_ref(), b);
        hit
    }

    /// Counts `ray`, a ray at branch `b` whose closest hit `hit` was found
    /// elsewhere (a camera ray traced in a packet, `World::intersect_packet`),
    /// and shows it to the observer: what [`closest`](Self::closest) does
    /// besides the intersection.
    #[inline]
    pub fn seen(&mut self, ray: &Ray, hit: Option<&Hit>, b: Branch) {
        count_ray(self.counters, b.kind);
        let t_end = hit.map_or(f32::INFINITY, |h| h.t);
        let normal = hit.map(|h| h.normal);
        self.observer.ray(b, ray, t_end, normal);
    }

    /// Whether something blocks the shadow ray `ray` before `tmax`, but
    /// primitive `leaving` (the one it leaves, when known; see
    /// `World::occluded_leaving`); counted and shown to the observer as a
    /// shadow ray at recursion `depth`.
    #[inline]
    pub fn blocked(&mut self, ray: &Ray, tmax: f32, leaving: Option<u32>, depth: u32) -> bool {
        count_ray(self.counters, RayKind::Shadow);
        let blocked = (self.world).occluded_leaving(ray, 0.0, tmax, leaving, self.counters);
        self.observer.shadow(ray, tmax, blocked, depth);
        blocked
    }

    /// [`blocked`](Self::blocked) for each ray of a packet of shadow rays
    /// (at most `PACKET`, each to its own `tmin = 0` and `tmax`), all
    /// leaving primitive `leaving` (`World::occluded_packet`): bit `r` set
    /// when ray `r` is blocked. Counted and shown to the observer ray
    /// after ray, in order, as [`blocked`](Self::blocked) does.
    #[inline]
    pub fn blocked_packet(&mut self, rays: &[PacketRay], leaving: Option<u32>, depth: u32) -> u32 {
        let blocked = (self.world).occluded_packet(rays, leaving, self.counters);
        for (r, q) in rays.iter().enumerate() {
            count_ray(self.counters, RayKind::Shadow);
            (self.observer).shadow(&q.ray, q.tmax, blocked >> r & 1 != 0, depth);
        }
        blocked
    }
}

/// Radiance along camera rays: the one interface between the render loop and
/// the light transport. An integrator says what it makes of a camera ray's
/// closest hit ([`li_hit`](Self::li_hit)); the camera ray itself is traced
/// by [`li`](Self::li), or by the render loop together with its neighbours'
/// (a packet: `World::intersect_packet`, the same hits bit for bit).
pub trait Integrator: Sync {
    /// Colour seen along the camera ray `ray` (hits with `t > tmin`), and the
    /// camera ray's hit (for the depth and normal planes): the ray traced
    /// ([`Trace::closest`] at [`Branch::CAMERA`]), then
    /// [`li_hit`](Self::li_hit).
    #[inline]
    fn li<O: RayObserver>(&self, cx: &mut Trace<O>, ray: &Ray, tmin: f32) -> (Vec3, Option<Hit>) {
        let hit = cx.closest(ray, tmin, Branch::CAMERA);
        (self.li_hit(cx, ray, tmin, hit.as_ref()), hit)
    }

    /// The colour [`li`](Self::li) gives a camera ray already traced: `hit`
    /// is its closest hit beyond `tmin` (`World::intersect(ray, tmin, ∞)`),
    /// counted and shown to the observer ([`Trace::seen`]). By reference:
    /// the hit is read where the world wrote it (a copy moved it with wide
    /// loads of the world's narrow stores, which a CPU cannot forward).
    fn li_hit<O: RayObserver>(
        &self,
        cx: &mut Trace<O>,
        ray: &Ray,
        tmin: f32,
        hit: Option<&Hit>,
    ) -> Vec3;
}

impl Integrator for Whitted {
    /// The classic tree takes no stream dimensions; area lights, glossy
    /// lobes and ambient occlusion take theirs as they are met.
    #[inline]
    fn li_hit<O: RayObserver>(
        &self,
        cx: &mut Trace<O>,
        ray: &Ray,
        _: f32,
        hit: Option<&Hit>,
    ) -> Vec3 {
        self.shade_hit(cx, ray, hit, Branch::CAMERA)
    }
}
