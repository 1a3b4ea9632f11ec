//! The world rays are shot at: the scene's object tree flattened into a list
//! of primitives, an aggregate over the bounded ones, and the unbounded ones
//! (planes) tested on every ray.
//!
//! **Rendering space.** Everything in a [`World`] (primitives, lights, its
//! camera, texture and object matrices, every ray and hit) is in *rendering
//! space*: world space translated so that the camera sits at the origin
//! (pbrt-v4's "camera-world" space). f32 resolution is finest near 0, so it
//! is spent where the image is, and a scene far from the world's origin
//! renders like the same scene near it. The translation is applied in f64 at
//! build time ([`World::origin`] is where the rendering-space origin lies in
//! world space); rays for a world come from [`World::camera`], and a
//! world-space point or ray is brought in with [`World::ray_from_world`].

mod build;
mod lights;

pub use crate::primitive::Primitive;
pub use build::BuildOptions;

use crate::accel::Aggregate;
use crate::math::{Aabb, Mat4, Ray, SurfacePoint, Vec3};
use crate::scene::{Background, Camera, Light, Material};
use crate::shape::Shape;
use crate::stats::Counters;
use glam::DVec3;

/// What a ray hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter.
    pub t: f32,
    /// The point (rendering space).
    pub point: Vec3,
    /// Per-axis bound on the floating-point error of `point`: the true
    /// surface point lies within `point ± error`.
    pub error: Vec3,
    /// Unit geometric normal (the shape's outward/front side, not flipped
    /// towards the ray).
    pub normal: Vec3,
    /// Unit shading normal: on a smooth-shaded triangle the vertex normals
    /// interpolated at the hit, turned to `normal`'s side; elsewhere
    /// exactly `normal`. Light and reflection use it; rays are spawned by
    /// `normal` (see `integrator::whitted`).
    pub shading_normal: Vec3,
    /// Primitive index.
    pub prim: u32,
    /// Material index.
    pub material: u32,
    /// Object-space index (see [`Primitive::instance`]).
    pub instance: u32,
}

impl Hit {
    /// The hit as a [`SurfacePoint`], from which secondary rays are spawned.
    #[inline]
    pub fn surface_point(&self) -> SurfacePoint {
        SurfacePoint {
            p: self.point,
            error: self.error,
            n: self.normal,
        }
    }

    /// A ray leaving the hit in direction `dir` (trace it with `t > 0`).
    #[inline]
    pub fn spawn_ray(&self, dir: Vec3) -> Ray {
        self.surface_point().spawn_ray(dir)
    }
}

/// Everything the integrator needs: geometry, materials, lights, background,
/// all in rendering space (see the module documentation).
pub struct World {
    /// All primitives.
    pub prims: Vec<Primitive>,
    /// Aggregate over the bounded primitives.
    pub accel: Box<dyn Aggregate>,
    /// Primitives with infinite bounds (planes), tested on every ray.
    pub unbounded: Vec<u32>,
    /// Material table (the scene's, plus a default for shapes that had none),
    /// for lookups at rendering-space points: texture matrices have the
    /// translation back to world space folded in (in f64), so a texture
    /// stays exactly where the scene put it.
    pub materials: Vec<Material>,
    /// The same table with the scene's own texture matrices, for lookups at
    /// object-space points (`TextureSpace::Object`).
    pub object_materials: Vec<Material>,
    /// Lights (point lights moved into rendering space).
    pub lights: Vec<Light>,
    /// The scene's camera in rendering space (its centre at the origin):
    /// build the [`crate::render::CameraModel`] for this world from it.
    pub camera: Camera,
    /// Where the rendering-space origin lies in world space.
    pub origin: DVec3,
    /// Background and ambient light.
    pub background: Background,
    /// Rendering-space-to-object matrices, indexed by [`Primitive::instance`];
    /// entry 0 is the rendering-to-world translation.
    pub object_from_world: Vec<Mat4>,
    /// Milliseconds spent building the aggregate.
    pub build_ms: f64,
    /// The scene's object tree over `prims` (groups, transforms, shapes), as
    /// flattening met it: what `bvh-hierarchy` is built from.
    pub scene_tree: crate::accel::SceneTree,
    /// What of `lights` is the same at every shading point, prepared once.
    prepared_lights: lights::PreparedLights,
    /// Vertex normals of smooth-shaded triangles by primitive index, each
    /// matching its triangle's vertex order (zero for a flat primitive);
    /// empty when every triangle is flat, so flat scenes pay one test of
    /// an empty vector per closest hit.
    pub vertex_normals: Vec<[Vec3; 3]>,
}

impl World {
    /// Closest hit with `tmin < t < tmax`.
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32, c: &mut Counters) -> Option<Hit> {
        let mut best = (self.accel).intersect_barycentric(&self.prims, ray, tmin, tmax, c);
        let mut tmax = best.map_or(tmax, |h| h.0.t);
        for &i in &self.unbounded {
            c.intersection_tests += 1;
            if let Some(t) = self.unbounded_hit(i, ray, tmin, tmax) {
                tmax = t;
                best = Some((crate::accel::PrimHit { t, prim: i }, None));
            }
        }
        best.map(|(h, bary)| {
            let p = &self.prims[h.prim as usize];
            // The aggregate's barycentrics are the ones `Triangle::surface`
            // would re-run the watertight test for (same ray, same vertices).
            let s = match (&p.shape, bary) {
                (Shape::Triangle(tr), Some(b)) => tr.surface_at(b),
                (shape, _) => shape.surface(ray, h.t),
            };
            let shading_normal = match self.vertex_normals.get(h.prim as usize) {
                Some(n) if n[0] != Vec3::ZERO => self.interpolated_normal(p, n, ray, bary, s.n),
                _ => s.n,
            };
            Hit {
                t: h.t,
                point: s.p,
                error: s.error,
                normal: s.n,
                shading_normal,
                prim: h.prim,
                material: p.material,
                instance: p.instance,
            }
        })
    }

    /// The vertex normals `n` of primitive `p` (a triangle) interpolated at
    /// the hit's barycentrics (`bary`, or the watertight test run again
    /// when the aggregate did not keep them), on the side of the geometric
    /// normal `ng`.
    #[cold]
    fn interpolated_normal(
        &self,
        p: &Primitive,
        n: &[Vec3; 3],
        ray: &Ray,
        bary: Option<[f32; 3]>,
        ng: Vec3,
    ) -> Vec3 {
        let Shape::Triangle(tr) = &p.shape else {
            return ng;
        };
        let Some(b) = bary.or_else(|| tr.hit(ray, f32::NEG_INFINITY, f32::INFINITY).map(|h| h.b))
        else {
            return ng;
        };
        let ns = (b[0] * n[0] + b[1] * n[1] + b[2] * n[2]).normalize_or(ng);
        if ns.dot(ng) < 0.0 {
            -ns
        } else {
            ns
        }
    }

    /// What the world's light number `index` (`light`, i.e.
    /// `&self.lights[index]`) sends to point `p`: `light::incident(light,
    /// p)`, with a directional light's normalised direction prepared once
    /// per world (and re-done should the light have changed since).
    #[inline]
    pub fn incident(&self, index: usize, light: &Light, p: Vec3) -> crate::light::Incident {
        self.prepared_lights.incident(index, light, p)
    }

    /// Whether anything lies on the ray with `tmin < t < tmax`.
    pub fn occluded(&self, ray: &Ray, tmin: f32, tmax: f32, c: &mut Counters) -> bool {
        self.unbounded_occludes(ray, tmin, tmax, None, c)
            || self.accel.occluded(&self.prims, ray, tmin, tmax, c)
    }

    /// Whether an unbounded primitive (a plane) other than `skip` lies on
    /// the ray.
    #[inline]
    fn unbounded_occludes(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        skip: Option<u32>,
        c: &mut Counters,
    ) -> bool {
        for &i in &self.unbounded {
            if Some(i) != skip {
                c.intersection_tests += 1;
                if self.unbounded_hit(i, ray, tmin, tmax).is_some() {
                    return true;
                }
            }
        }
        false
    }

    /// The hit of unbounded primitive `i`: a plane's test inlined here (it
    /// runs for every ray; through `Shape::intersect`'s call it was 5% of a
    /// 16-spp render of scene6_07), anything else through its shape.
    #[inline]
    fn unbounded_hit(&self, i: u32, ray: &Ray, tmin: f32, tmax: f32) -> Option<f32> {
        match &self.prims[i as usize].shape {
            Shape::Plane(p) => p.intersect(ray, tmin, tmax),
            shape => shape.intersect(ray, tmin, tmax),
        }
    }

    /// [`occluded`](Self::occluded) for a ray spawned off primitive `from`
    /// (a hit's `prim`, see `math::Spawn`). A triangle cannot block a ray
    /// leaving it: the ray starts at an origin offset past the hit's error
    /// bounds to the side it goes (`offset_ray_origin`), so the triangle's
    /// plane lies behind it, and the watertight test rejects every `t`
    /// within its own error of 0 (`deltaT`). So the accelerator may skip
    /// that triangle's test (`Aggregate::occluded_except`): the answer is
    /// `occluded`'s unless `occluded` reported the ray's own triangle,
    /// which would be shadow acne (`tests/reintersect.rs` checks that
    /// spawned rays never re-hit their own surface). A plane is flat too:
    /// the one a ray leaves is not tested. Curved, moving and instanced
    /// primitives are tested as usual.
    #[inline(always)] // (the shadow ray stays in registers: see `phong_light`)
    pub fn occluded_leaving(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        from: Option<u32>,
        c: &mut Counters,
    ) -> bool {
        match from.and_then(|i| self.prims.get(i as usize).map(|p| (i, &p.shape))) {
            Some((i, Shape::Triangle(_))) => {
                self.unbounded_occludes(ray, tmin, tmax, None, c)
                    || (self.accel).occluded_except(&self.prims, ray, tmin, tmax, i, c)
            }
            Some((i, Shape::Plane(_))) => {
                self.unbounded_occludes(ray, tmin, tmax, Some(i), c)
                    || self.accel.occluded(&self.prims, ray, tmin, tmax, c)
            }
            _ => self.occluded(ray, tmin, tmax, c),
        }
    }

    /// A world-space ray in this world's rendering space (the origin moved
    /// in f64; `t` is unchanged).
    pub fn ray_from_world(&self, ray: &Ray) -> Ray {
        ray.child((ray.origin.as_dvec3() - self.origin).as_vec3(), ray.dir)
    }

    /// A rendering-space point in world space (in f64, exactly as the
    /// rendering space was made).
    pub fn point_to_world(&self, p: Vec3) -> DVec3 {
        p.as_dvec3() + self.origin
    }

    /// Bounds of the bounded primitives (planes excluded).
    pub fn bounds(&self) -> Aabb {
        self.accel.bounds()
    }
}
