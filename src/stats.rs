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
    /// Ray–primitive intersection tests.
    pub intersection_tests: u64,
    /// Accelerator nodes or grid cells visited.
    pub nodes_visited: u64,
}

impl Counters {
    /// All rays of every kind.
    pub fn rays_total(&self) -> u64 {
        self.primary + self.shadow + self.reflected + self.refracted + self.occlusion
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
        self.intersection_tests += o.intersection_tests;
        self.nodes_visited += o.nodes_visited;
    }
}
