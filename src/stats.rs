//! Ray and traversal counters. Each render thread owns a [`Counters`] passed
//! down by `&mut` (no atomics on the hot path); they are merged at the end.

use std::ops::AddAssign;

/// What one thread counted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    /// Eye rays.
    pub primary: u64,
    /// Shadow rays.
    pub shadow: u64,
    /// Mirror-reflected rays.
    pub reflected: u64,
    /// Refracted (transmitted) rays.
    pub refracted: u64,
    /// Of the reflected and refracted rays, those spread over a glossy lobe.
    pub glossy: u64,
    /// Ambient-occlusion hemisphere rays.
    pub occlusion: u64,
    /// Rays of photons from the lights (the path tracer's caustic map).
    pub photon: u64,
    /// Ray–primitive intersection tests.
    pub intersection_tests: u64,
    /// Accelerator nodes or grid cells visited.
    pub nodes_visited: u64,
}

impl Counters {
    /// All rays of every kind.
    pub fn rays_total(&self) -> u64 {
        self.primary + self.shadow + self.reflected + self.refracted + self.occlusion + self.photon
    }
}

impl AddAssign for Counters {
    fn add_assign(&mut self, o: Self) {
        self.primary += o.primary;
        self.shadow += o.shadow;
        self.reflected += o.reflected;
        self.refracted += o.refracted;
        self.glossy += o.glossy;
        self.occlusion += o.occlusion;
        self.photon += o.photon;
        self.intersection_tests += o.intersection_tests;
        self.nodes_visited += o.nodes_visited;
    }
}

/// What a traversal reports when statistics are asked for: a generic
/// parameter of the fast BVH's loops, so that with [`NoStats`] the counting
/// compiles away and a query pays nothing for statistics it did not ask for.
pub trait TraversalStats {
    /// False for [`NoStats`]: the loops skip their local counting entirely.
    const ENABLED: bool;
    /// Adds one query's totals (called once per query, not per node).
    fn add(&mut self, nodes_visited: u64, intersection_tests: u64);
}

impl TraversalStats for Counters {
    const ENABLED: bool = true;
    #[inline]
    fn add(&mut self, nodes_visited: u64, intersection_tests: u64) {
        self.nodes_visited += nodes_visited;
        self.intersection_tests += intersection_tests;
    }
}

/// Statistics not wanted: every count is optimised away.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoStats;

impl TraversalStats for NoStats {
    const ENABLED: bool = false;
    #[inline(always)]
    fn add(&mut self, _: u64, _: u64) {}
}
