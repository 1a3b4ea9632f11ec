//! The world rays are shot at: the scene's object tree flattened into a list
//! of world-space primitives, an aggregate over the bounded ones, and the
//! unbounded ones (planes) tested on every ray.

mod build;

pub use crate::primitive::Primitive;
pub use build::BuildOptions;

use crate::accel::Aggregate;
use crate::math::{Aabb, Mat4, Ray, Vec3};
use crate::scene::{Background, Light, Material};
use crate::stats::Counters;

/// What a ray hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter.
    pub t: f32,
    /// World-space point.
    pub point: Vec3,
    /// Unit geometric normal (the shape's outward/front side, not flipped
    /// towards the ray).
    pub normal: Vec3,
    /// Primitive index.
    pub prim: u32,
    /// Material index.
    pub material: u32,
    /// Object-space index (see [`Primitive::instance`]).
    pub instance: u32,
}

/// Everything the integrator needs: geometry, materials, lights, background.
pub struct World {
    /// All primitives.
    pub prims: Vec<Primitive>,
    /// Aggregate over the bounded primitives.
    pub accel: Box<dyn Aggregate>,
    /// Primitives with infinite bounds (planes), tested on every ray.
    pub unbounded: Vec<u32>,
    /// Material table (the scene's, plus a default for shapes that had none).
    pub materials: Vec<Material>,
    /// Lights.
    pub lights: Vec<Light>,
    /// Background and ambient light.
    pub background: Background,
    /// World-to-object matrices, indexed by [`Primitive::instance`]; entry 0 is
    /// the identity.
    pub object_from_world: Vec<Mat4>,
    /// Milliseconds spent building the aggregate.
    pub build_ms: f64,
}

impl World {
    /// Closest hit with `tmin < t < tmax`.
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32, c: &mut Counters) -> Option<Hit> {
        let mut best = self.accel.intersect(&self.prims, ray, tmin, tmax, c);
        let mut tmax = best.map_or(tmax, |h| h.t);
        for &i in &self.unbounded {
            c.intersection_tests += 1;
            if let Some(t) = self.prims[i as usize].shape.intersect(ray, tmin, tmax) {
                tmax = t;
                best = Some(crate::accel::PrimHit { t, prim: i });
            }
        }
        best.map(|h| {
            let p = &self.prims[h.prim as usize];
            let point = ray.at(h.t);
            Hit {
                t: h.t,
                point,
                normal: p.shape.normal(point, ray.time),
                prim: h.prim,
                material: p.material,
                instance: p.instance,
            }
        })
    }

    /// Whether anything lies on the ray with `tmin < t < tmax`.
    pub fn occluded(&self, ray: &Ray, tmin: f32, tmax: f32, c: &mut Counters) -> bool {
        self.unbounded.iter().any(|&i| {
            c.intersection_tests += 1;
            self.prims[i as usize]
                .shape
                .intersect(ray, tmin, tmax)
                .is_some()
        }) || self.accel.occluded(&self.prims, ray, tmin, tmax, c)
    }

    /// Bounds of the bounded primitives (planes excluded).
    pub fn bounds(&self) -> Aabb {
        self.accel.bounds()
    }
}
