//! Helpers for the crate's unit tests (compiled only for them).

use super::{SurfacePoint, Vec3};
use glam::DVec3;

/// A small seeded generator (a 64-bit LCG, top 24 bits): deterministic
/// inputs for property-style unit tests, so a failure names its case.
pub(crate) struct Lcg(pub u64);

impl Lcg {
    /// Uniform in `[0, 1)`, on a grid of `2⁻²⁴`.
    pub fn next(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }

    /// A point of the cube `[−s/2, s/2)³`.
    pub fn vec(&mut self, s: f32) -> Vec3 {
        Vec3::new(self.next() - 0.5, self.next() - 0.5, self.next() - 0.5) * s
    }
}

/// Checks a point's error box: non-negative, holding the true point `truth`
/// (f64) along the direction `along` (every axis when `None`; a surface's
/// normal where only the distance to the surface matters), and no looser
/// than `limit` per axis (a box of any size holds the point: the limit is
/// what makes the check see a bound that is too large).
pub(crate) fn check_error_box(
    at: SurfacePoint,
    truth: DVec3,
    along: Option<DVec3>,
    limit: Vec3,
    what: &str,
) {
    let (p, e) = (at.p.as_dvec3(), at.error.as_dvec3());
    assert!(at.error.min_element() >= 0.0, "{what}: {e}");
    match along {
        None => {
            let off = (p - truth).abs();
            assert!(off.cmple(e).all(), "{what}: off {off}, box {e}");
        }
        Some(n) => {
            let off = (p - truth).dot(n).abs();
            assert!(off <= e.dot(n.abs()), "{what}: off {off}, box {e}");
        }
    }
    assert!(at.error.cmple(limit).all(), "{what}: box {e} over {limit}");
}

/// Midpoint quadrature over the sphere on an equal-area grid (`z` and `φ`
/// uniform): `∫ g(ω) dω ≈ Σ g · 4π/N`, per channel. With 600 × 1200 cells
/// (each about 0.006 rad across; thin wedges at the poles) a lobe of
/// exponent up to 40 is integrated to better than 2e-3 wherever it points.
pub(crate) fn sphere_integral(mut g: impl FnMut(Vec3) -> Vec3) -> DVec3 {
    let (nz, nphi) = (600, 1200);
    let mut sum = DVec3::ZERO;
    for i in 0..nz {
        let z = -1.0 + 2.0 * (i as f64 + 0.5) / nz as f64;
        let r = (1.0 - z * z).max(0.0).sqrt();
        for j in 0..nphi {
            let phi = std::f64::consts::TAU * (j as f64 + 0.5) / nphi as f64;
            let w = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
            sum += g(w).as_dvec3();
        }
    }
    sum * 4.0 * std::f64::consts::PI / (nz * nphi) as f64
}
