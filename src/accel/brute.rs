use super::mailbox::ItemTests;
use super::overlap::bounds_of;
use super::{Aggregate, PrimHit, Query};
use crate::math::Aabb;
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
        let bounds = bounds_of(prims, &ids);
        Self { ids, bounds }
    }
}

impl Aggregate for Brute {
    fn intersect(&self, q: Query, c: &mut Counters) -> Option<PrimHit> {
        let mut tests = ItemTests::new(q, false);
        tests.closest(&self.ids, c);
        tests.best()
    }

    fn occluded(&self, q: Query, c: &mut Counters) -> bool {
        ItemTests::new(q, false).any(&self.ids, c)
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
