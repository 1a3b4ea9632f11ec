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

/// Watches the rays an integrator spawns. Rendering passes [`NoObserver`],
/// whose empty inline method compiles away; the ray-tree view passes a
/// recorder, so the picture shows exactly what the renderer did.
pub trait RayObserver {
    /// A ray was traced from `ray.origin` to `ray.at(t_end)` (`t_end` is
    /// infinite for a miss) at recursion `depth` with contribution `weight`.
    fn ray(
        &mut self,
        kind: RayKind,
        ray: &Ray,
        t_end: f32,
        depth: u32,
        weight: f32,
        normal: Option<Vec3>,
    );
}

/// Observes nothing.
pub struct NoObserver;

impl RayObserver for NoObserver {
    #[inline(always)]
    fn ray(&mut self, _: RayKind, _: &Ray, _: f32, _: u32, _: f32, _: Option<Vec3>) {}
}

/// One recorded ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecordedRay {
    /// Role.
    pub kind: RayKind,
    /// The ray.
    pub ray: Ray,
    /// Where it ended (infinite: it escaped).
    pub t_end: f32,
    /// Recursion depth (0 = eye ray).
    pub depth: u32,
    /// Contribution weight.
    pub weight: f32,
    /// Surface normal at the end point, if it hit.
    pub normal: Option<Vec3>,
}

/// Records every ray, in the order traced.
#[derive(Default, Debug)]
pub struct RayRecorder {
    /// The rays.
    pub rays: Vec<RecordedRay>,
}

impl RayObserver for RayRecorder {
    fn ray(
        &mut self,
        kind: RayKind,
        ray: &Ray,
        t_end: f32,
        depth: u32,
        weight: f32,
        normal: Option<Vec3>,
    ) {
        self.rays.push(RecordedRay {
            kind,
            ray: *ray,
            t_end,
            depth,
            weight,
            normal,
        });
    }
}
