use super::{Aggregate, PrimHit};
use crate::math::{Aabb, Ray};
use crate::primitive::Primitive;
use crate::stats::Counters;

/// Tests every primitive: the baseline every accelerator is measured against.
pub struct Brute {
    ids: Vec<u32>,
    bounds: Aabb,
}

impl Brute {
    /// Over the primitives `ids` of `prims`.
    pub fn new(prims: &[Primitive], ids: Vec<u32>) -> Self {
        let bounds = ids
            .iter()
            .fold(Aabb::EMPTY, |b, &i| b.union(&prims[i as usize].bounds()));
        Self { ids, bounds }
    }
}

impl Aggregate for Brute {
    fn intersect(
        &self,
        prims: &[Primitive],
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        c: &mut Counters,
    ) -> Option<PrimHit> {
        let mut best: Option<PrimHit> = None;
        let mut tmax = tmax;
        c.intersection_tests += self.ids.len() as u64;
        for &i in &self.ids {
            if let Some(t) = prims[i as usize].shape.intersect(ray, tmin, tmax) {
                tmax = t;
                best = Some(PrimHit { t, prim: i });
            }
        }
        best
    }

    fn occluded(
        &self,
        prims: &[Primitive],
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        c: &mut Counters,
    ) -> bool {
        for &i in &self.ids {
            c.intersection_tests += 1;
            if prims[i as usize].shape.intersect(ray, tmin, tmax).is_some() {
                return true;
            }
        }
        false
    }

    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn memory_bytes(&self) -> usize {
        self.ids.len() * 4
    }

    fn describe(&self) -> String {
        "none".into()
    }
}
