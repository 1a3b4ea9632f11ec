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

pub use crate::primitive::Primitive;
pub use build::BuildOptions;

use crate::accel::{Aggregate, PacketRay, Query, PACKET};
use crate::light::{EmitterHit, Incident, LightSource};
use crate::math::{Aabb, Mat4, Ray, SurfacePoint, Vec3};
use crate::scene::{Background, Camera, Material, RenderLight};
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
    prims: Vec<Primitive>,
    /// Aggregate over the bounded primitives.
    accel: Box<dyn Aggregate>,
    /// Primitives with infinite bounds (planes), tested on every ray.
    unbounded: Vec<u32>,
    /// Material table (the scene's, plus a default for shapes that had none),
    /// for lookups at rendering-space points: texture matrices have the
    /// translation back to world space folded in (in f64), so a texture
    /// stays exactly where the scene put it.
    materials: Vec<Material>,
    /// The same table with the scene's own texture matrices, for lookups at
    /// object-space points (`TextureSpace::Object`).
    object_materials: Vec<Material>,
    /// Lights moved into rendering space (positions rounded once).
    lights: Vec<RenderLight>,
    /// The scene's camera in rendering space (its centre at the origin):
    /// build the [`crate::render::CameraModel`] for this world from it.
    camera: Camera,
    /// Where the rendering-space origin lies in world space.
    origin: DVec3,
    /// Background and ambient light.
    background: Background,
    /// Rendering-space-to-object matrices, indexed by [`Primitive::instance`];
    /// entry 0 is the rendering-to-world translation.
    object_from_world: Vec<Mat4>,
    /// Milliseconds spent building the aggregate.
    build_ms: f64,
    /// The scene's object tree over `prims` (groups, transforms, shapes), as
    /// flattening met it: what `bvh-hierarchy` is built from.
    scene_tree: crate::accel::SceneTree,
    /// The lights as the integrators use them, index for index with
    /// `lights`: built once (directions normalised, radiances computed).
    sources: Vec<LightSource>,
    /// Indices of the area lights in `sources`: surfaces a ray can hit,
    /// kept out of the aggregate (the Whitted tree never sees them).
    emitters: Vec<u32>,
    /// Vertex normals of smooth-shaded triangles by primitive index, each
    /// matching its triangle's vertex order (zero for a flat primitive);
    /// empty when every triangle is flat, so flat scenes pay one test of
    /// an empty vector per closest hit.
    vertex_normals: Vec<[Vec3; 3]>,
}

impl World {
    /// All primitives.
    #[inline]
    pub fn prims(&self) -> &[Primitive] {
        &self.prims
    }

    /// The aggregate over the bounded primitives.
    #[inline]
    pub fn accel(&self) -> &dyn Aggregate {
        &*self.accel
    }

    /// Indices of the primitives with infinite bounds (planes), tested on
    /// every ray.
    #[inline]
    pub fn unbounded(&self) -> &[u32] {
        &self.unbounded
    }

    /// The material table for lookups at rendering-space points (see the
    /// field's documentation: texture matrices map rendering space).
    #[inline]
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// The material table with the scene's own texture matrices, for
    /// lookups at object-space points.
    #[inline]
    pub fn object_materials(&self) -> &[Material] {
        &self.object_materials
    }

    /// The scene's lights in rendering space.
    #[inline]
    pub fn lights(&self) -> &[RenderLight] {
        &self.lights
    }

    /// The scene's camera in rendering space (its centre at the origin):
    /// build the [`crate::render::CameraModel`] for this world from it.
    #[inline]
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Where the rendering-space origin lies in world space.
    #[inline]
    pub fn origin(&self) -> DVec3 {
        self.origin
    }

    /// Background colour and ambient light.
    #[inline]
    pub fn background(&self) -> &Background {
        &self.background
    }

    /// Rendering-space-to-object matrices, indexed by
    /// [`Primitive::instance`]; entry 0 is the rendering-to-world
    /// translation.
    #[inline]
    pub fn object_from_world(&self) -> &[Mat4] {
        &self.object_from_world
    }

    /// Milliseconds spent building the aggregate.
    pub fn build_ms(&self) -> f64 {
        self.build_ms
    }

    /// The scene's object tree over the primitives, as flattening met it.
    pub fn scene_tree(&self) -> &crate::accel::SceneTree {
        &self.scene_tree
    }

    /// Closest hit with `tmin < t < tmax`.
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32, c: &mut Counters) -> Option<Hit> {
        let best = (self.accel).intersect_barycentric(Query::new(&self.prims, ray, tmin, tmax), c);
        self.finish_hit(ray, tmin, tmax, best, c)
    }

    /// [`intersect`](Self::intersect) of a ray from a coherent run (a
    /// tile's camera rays traced one by one, see [`Query::coherent`]): the
    /// same hit, found faster where the rays keep their direction's signs.
    pub fn intersect_coherent(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        c: &mut Counters,
    ) -> Option<Hit> {
        let q = Query::new(&self.prims, ray, tmin, tmax).with_coherent(true);
        let best = (self.accel).intersect_barycentric(q, c);
        self.finish_hit(ray, tmin, tmax, best, c)
    }

    /// Whether [`intersect_packet`](Self::intersect_packet) walks a
    /// packet's rays together: the aggregate is the wide BVH (`bvh8`, the
    /// default; its non-triangle items, spheres, moving or transformed
    /// shapes, are tested ray by ray at its leaves). Other aggregates
    /// answer ray by ray, so a caller need not gather rays for them.
    pub fn walks_packets(&self) -> bool {
        self.accel.walks_packets()
    }

    /// The closest hit of each ray of a packet (at most [`PACKET`] rays,
    /// each in its own `(tmin, tmax)`) into `out[..rays.len()]`: for each,
    /// what [`intersect`](Self::intersect) gives it alone, bit for bit
    /// (`Aggregate::intersect_packet`, then the unbounded primitives and
    /// the hit record ray by ray).
    ///
    /// # Panics
    /// If `rays` holds more than [`PACKET`] rays or `out` fewer than `rays`.
    pub fn intersect_packet(&self, rays: &[PacketRay], out: &mut [Option<Hit>], c: &mut Counters) {
        assert!(rays.len() <= PACKET && out.len() >= rays.len());
        let mut found = [None; PACKET];
        let found = &mut found[..rays.len()];
        (self.accel).intersect_packet(&self.prims, rays, found, c);
        for ((q, best), o) in rays.iter().zip(found.iter()).zip(out) {
            *o = self.finish_hit(&q.ray, q.tmin, q.tmax, *best, c);
        }
    }

    /// The closest hit of `ray` given the aggregate's `best`: the unbounded
    /// primitives tested before it, then the hit record of the nearest.
    #[inline(always)]
    fn finish_hit(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        mut best: Option<crate::accel::BaryHit>,
        c: &mut Counters,
    ) -> Option<Hit> {
        let mut tmax = best.map_or(tmax, |h| h.0.t);
        for &i in &self.unbounded {
            c.intersection_tests += 1;
            if let Some(t) = self.unbounded_hit(i, ray, tmin, tmax) {
                tmax = t;
                best = Some((crate::accel::PrimHit { t, prim: i }, None));
            }
        }
        // Not a closure passed to `Option::map`: compiled out of line, it
        // handed the hit back through memory in narrower stores than the
        // caller's 16-byte loads of it, which cannot be forwarded (perf,
        // scene6_07: the largest share of `intersect_packet`'s samples).
        let (h, bary) = best?;
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
        Some(Hit {
            t: h.t,
            point: s.p,
            error: s.error,
            normal: s.n,
            shading_normal,
            prim: h.prim,
            material: p.material,
            instance: p.instance,
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

    /// What the world's light number `index` sends to point `p`:
    /// `light::incident(&self.lights()[index], p)`, bit for bit, from the
    /// light source prepared with the world.
    #[inline]
    pub fn incident(&self, index: usize, p: Vec3) -> Incident {
        match self.sources[index].incident(p) {
            Some(inc) => inc,
            None => crate::light::incident(&self.lights[index], p),
        }
    }

    /// The lights as the integrators that weigh samples use them, index for
    /// index with [`lights`](Self::lights).
    #[inline]
    pub fn light_sources(&self) -> &[LightSource] {
        &self.sources
    }

    /// Indices (into [`light_sources`](Self::light_sources)) of the lights
    /// with a surface.
    pub fn emitters(&self) -> &[u32] {
        &self.emitters
    }

    /// The closest hit with `tmin < t < tmax` on the surface of an area
    /// light, and which light it is. Area lights are not in the aggregate
    /// ([`intersect`](Self::intersect) and [`occluded`](Self::occluded) do
    /// not see them, so the Whitted tree's rays and statistics are what they
    /// were); an integrator that sees emitters asks here too, with `tmax` at
    /// its closest hit.
    pub fn intersect_emitters(
        &self,
        ray: &Ray,
        tmin: f32,
        mut tmax: f32,
    ) -> Option<(u32, EmitterHit)> {
        let mut best = None;
        for &i in &self.emitters {
            if let LightSource::Area(a) = &self.sources[i as usize] {
                if let Some(h) = a.intersect(ray, tmin, tmax) {
                    tmax = h.t;
                    best = Some((i, h));
                }
            }
        }
        best
    }

    /// Whether anything lies on the ray with `tmin < t < tmax`.
    pub fn occluded(&self, ray: &Ray, tmin: f32, tmax: f32, c: &mut Counters) -> bool {
        self.unbounded_occludes(ray, tmin, tmax, None, c)
            || self
                .accel
                .occluded(Query::new(&self.prims, ray, tmin, tmax), c)
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
                    || (self.accel).occluded_except(Query::new(&self.prims, ray, tmin, tmax), i, c)
            }
            Some((i, Shape::Plane(_))) => {
                self.unbounded_occludes(ray, tmin, tmax, Some(i), c)
                    || self
                        .accel
                        .occluded(Query::new(&self.prims, ray, tmin, tmax), c)
            }
            _ => self.occluded(ray, tmin, tmax, c),
        }
    }

    /// [`occluded_leaving`](Self::occluded_leaving) of each ray of a
    /// packet (at most [`PACKET`] rays, each in its own `(tmin, tmax)`),
    /// every ray spawned off primitive `from`: bit `r` set when something
    /// blocks ray `r`, its answer alone bit for bit. The planes first, ray
    /// by ray; the rays they do not block then go to the aggregate as one
    /// packet (`Aggregate::occluded_packet`: the wide BVH walks them
    /// together, others ask ray by ray with the same statistics).
    ///
    /// # Panics
    /// If `rays` holds more than [`PACKET`] rays.
    pub fn occluded_packet(&self, rays: &[PacketRay], from: Option<u32>, c: &mut Counters) -> u32 {
        assert!(rays.len() <= PACKET);
        if rays.is_empty() {
            return 0;
        }
        // What `occluded_leaving` skips: the triangle in the aggregate, or
        // the plane among the unbounded primitives.
        let (plane, except) =
            match from.and_then(|i| self.prims.get(i as usize).map(|p| (i, &p.shape))) {
                Some((i, Shape::Triangle(_))) => (None, i),
                Some((i, Shape::Plane(_))) => (Some(i), u32::MAX),
                _ => (None, u32::MAX),
            };
        let except = [except; PACKET];
        if self.unbounded.is_empty() {
            return (self.accel).occluded_packet(&self.prims, rays, &except[..rays.len()], c);
        }
        let mut blocked = 0;
        let mut rest = [rays[0]; PACKET];
        let mut index = [0u8; PACKET];
        let mut n = 0;
        for (r, q) in rays.iter().enumerate() {
            if self.unbounded_occludes(&q.ray, q.tmin, q.tmax, plane, c) {
                blocked |= 1 << r;
            } else {
                (rest[n], index[n]) = (*q, r as u8);
                n += 1;
            }
        }
        if n > 0 {
            let b = (self.accel).occluded_packet(&self.prims, &rest[..n], &except[..n], c);
            for (k, &r) in index[..n].iter().enumerate() {
                blocked |= (b >> k & 1) << r;
            }
        }
        blocked
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{AreaShape, Light, Node, Scene, ShapeDesc as Desc};

    /// A quad light over a sphere: the aggregate and the occlusion test see
    /// only the sphere (the Whitted tree's rays are what they were), and
    /// `intersect_emitters` finds the light with its radiance, nearest first
    /// and only within `tmax`.
    #[test]
    fn emitters_are_seen_only_on_request() {
        let quad = AreaShape::Quad {
            corner: DVec3::new(-1.0, 3.0, -1.0),
            edge1: Vec3::new(2.0, 0.0, 0.0),
            edge2: Vec3::new(0.0, 0.0, 2.0),
        };
        let scene = Scene {
            camera: Camera::Orthographic {
                center: Vec3::ZERO.as_dvec3(),
                direction: Vec3::NEG_Z,
                up: Vec3::Y,
                size: 1.0,
            },
            lights: vec![
                Light::Point {
                    position: Vec3::new(0.0, 5.0, 0.0).as_dvec3(),
                    color: Vec3::ONE,
                    attenuation: Vec3::X,
                },
                Light::Area {
                    shape: quad,
                    color: Vec3::ONE,
                    power: 8.0,
                },
            ],
            background: Background::default(),
            materials: vec![],
            root: Node::Group(vec![Node::Shape {
                shape: Desc::Sphere {
                    center: Vec3::ZERO.as_dvec3(),
                    radius: 1.0,
                },
                material: None,
            }]),
            effects: Default::default(),
        };
        let world = World::build_world_space(&scene, BuildOptions::default());
        assert_eq!(world.emitters(), &[1]);
        assert_eq!(world.light_sources().len(), 2);
        let mut c = Counters::default();
        let up = Ray::new(Vec3::new(0.2, 1.5, 0.1), Vec3::Y);
        assert!(world.intersect(&up, 0.0, f32::INFINITY, &mut c).is_none());
        assert!(!world.occluded(&up, 0.0, f32::INFINITY, &mut c));
        let (i, h) = world.intersect_emitters(&up, 0.0, f32::INFINITY).unwrap();
        assert_eq!(i, 1);
        assert!(
            (h.t - 1.5).abs() < 1e-6 && (h.at.p.y - 3.0).abs() < 1e-6,
            "{h:?}"
        );
        // Power 8 over both faces of a 2 × 2 quad: radiance 8/(π·8).
        assert!(
            (h.le - Vec3::splat(1.0 / std::f32::consts::PI))
                .abs()
                .max_element()
                < 1e-6
        );
        assert!(world.intersect_emitters(&up, 0.0, 1.4).is_none());
        // From below the sphere, the light is still there (the caller limits
        // `tmax` to its own closest hit).
        let from_below = Ray::new(Vec3::new(0.0, -2.0, 0.0), Vec3::Y);
        let hit = world
            .intersect(&from_below, 0.0, f32::INFINITY, &mut c)
            .unwrap();
        assert!(world.intersect_emitters(&from_below, 0.0, hit.t).is_none());
        assert!(world
            .intersect_emitters(&from_below, 0.0, f32::INFINITY)
            .is_some());
    }
}
