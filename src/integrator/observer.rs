use crate::math::{Ray, Vec3};

/// The role of a ray in the ray tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// From the camera.
    Primary,
    /// Towards a light.
    Shadow,
    /// Mirror reflection.
    Reflected,
    /// Refraction.
    Transmitted,
    /// An ambient-occlusion probe of the hemisphere.
    Occlusion,
}

/// A ray's place in the ray tree: its role, its recursion depth (0 for a
/// camera ray) and its contribution to the pixel (for pruning and the
/// observer).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Branch {
    /// The ray's role.
    pub kind: RayKind,
    /// Recursion depth.
    pub depth: u32,
    /// Contribution (max channel of the path's weight).
    pub weight: f32,
}

impl Branch {
    /// A camera ray.
    pub const CAMERA: Branch = Branch {
        kind: RayKind::Primary,
        depth: 0,
        weight: 1.0,
    };

    /// A ray of `kind` at recursion `depth` that carries no colour of its
    /// own (a shadow or occlusion probe).
    pub fn probe(kind: RayKind, depth: u32) -> Branch {
        Branch {
            kind,
            depth,
            weight: 0.0,
        }
    }
}

/// Watches the rays an integrator spawns. Rendering passes [`NoObserver`],
/// whose empty inline method compiles away; the ray-tree view passes a
/// recorder, so the picture shows exactly what the renderer did.
pub trait RayObserver {
    /// A ray at branch `b` of the tree was traced from `ray.origin` to
    /// `ray.at(t_end)` (`t_end` is infinite for a miss), meeting a surface
    /// of normal `normal`.
    fn ray(&mut self, b: Branch, ray: &Ray, t_end: f32, normal: Option<Vec3>);

    /// An opaque shadow ray towards a light `distance` away was traced, and
    /// `blocked` tells whether something lay in between. The default reports
    /// it through [`RayObserver::ray`] with `t_end` = `distance`, or NaN when
    /// blocked (an any-hit query does not say where).
    fn shadow(&mut self, ray: &Ray, distance: f32, blocked: bool, depth: u32) {
        let t_end = if blocked { f32::NAN } else { distance };
        self.ray(Branch::probe(RayKind::Shadow, depth), ray, t_end, None);
    }

    /// The ray reported last carried light to the path: a light sample's
    /// shadow ray, or a scattered ray that hit an emitter. `weight` is its
    /// multiple-importance-sampling weight (1 where only one strategy can
    /// find that light) and `contribution` the radiance it added to the
    /// pixel (zero for a blocked shadow ray). Only the path tracer reports
    /// it.
    fn light(&mut self, weight: f32, contribution: Vec3) {
        let _ = (weight, contribution);
    }
}

/// Observes nothing.
pub struct NoObserver;

impl RayObserver for NoObserver {
    #[inline(always)]
    fn ray(&mut self, _: Branch, _: &Ray, _: f32, _: Option<Vec3>) {}

    #[inline(always)]
    fn shadow(&mut self, _: &Ray, _: f32, _: bool, _: u32) {}

    #[inline(always)]
    fn light(&mut self, _: f32, _: Vec3) {}
}

/// One recorded ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecordedRay {
    /// Role.
    pub kind: RayKind,
    /// The ray.
    pub ray: Ray,
    /// Where it ended (infinite: it escaped). For a shadow ray, the light's
    /// distance, whether or not it got there (see `occluded`).
    pub t_end: f32,
    /// A shadow ray that something blocked before the light.
    pub occluded: bool,
    /// Recursion depth (0 = eye ray).
    pub depth: u32,
    /// Contribution weight.
    pub weight: f32,
    /// Surface normal at the end point, if it hit.
    pub normal: Option<Vec3>,
    /// For a ray that carried light to the path (the path tracer's light
    /// samples and emitters hit): its MIS weight and the radiance it added
    /// ([`RayObserver::light`]).
    pub light: Option<(f32, Vec3)>,
}

/// Records every ray, in the order traced.
#[derive(Default, Debug)]
pub struct RayRecorder {
    /// The rays.
    pub rays: Vec<RecordedRay>,
}

impl RayObserver for RayRecorder {
    fn ray(&mut self, b: Branch, ray: &Ray, t_end: f32, normal: Option<Vec3>) {
        self.rays.push(RecordedRay {
            kind: b.kind,
            ray: *ray,
            t_end,
            occluded: false,
            depth: b.depth,
            weight: b.weight,
            normal,
            light: None,
        });
    }

    fn shadow(&mut self, ray: &Ray, distance: f32, blocked: bool, depth: u32) {
        self.rays.push(RecordedRay {
            kind: RayKind::Shadow,
            ray: *ray,
            t_end: distance,
            occluded: blocked,
            depth,
            weight: 0.0,
            normal: None,
            light: None,
        });
    }

    fn light(&mut self, weight: f32, contribution: Vec3) {
        if let Some(r) = self.rays.last_mut() {
            r.light = Some((weight, contribution));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An observer that keeps only what `ray` is told.
    #[derive(Default)]
    struct Rays(Vec<(RayKind, f32, u32)>);

    impl RayObserver for Rays {
        fn ray(&mut self, b: Branch, _: &Ray, t_end: f32, _: Option<Vec3>) {
            self.0.push((b.kind, t_end, b.depth));
        }
    }

    #[test]
    fn default_shadow_reports_a_shadow_ray_ending_at_the_light_or_nan() {
        let ray = Ray::new(Vec3::ZERO, Vec3::X);
        let mut o = Rays::default();
        o.shadow(&ray, 2.5, false, 1);
        o.shadow(&ray, 2.5, true, 3);
        assert_eq!(o.0[0], (RayKind::Shadow, 2.5, 1));
        assert_eq!((o.0[1].0, o.0[1].2), (RayKind::Shadow, 3));
        assert!(o.0[1].1.is_nan(), "a blocked shadow ray does not say where");
    }
}
