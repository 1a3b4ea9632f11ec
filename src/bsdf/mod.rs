//! BSDFs: how a surface point scatters light, for integrators that weigh
//! samples by their densities (a path tracer, multiple importance
//! sampling). A [`Bsdf`] is a few [`Lobe`]s in a local shading frame; it
//! evaluates `f(wo, wi)`, samples a direction with its value and density,
//! and reports the density of any direction.
//!
//! Conventions: `wo` (towards the viewer) and `wi` (towards the light) are
//! unit vectors in rendering space pointing away from the surface;
//! `f·|cos θi|/pdf` is a sample's weight. **The course's materials read
//! physically** through [`Bsdf::from_phong`]: `diffuseColor` is a Lambert
//! lobe `diffuseColor/π`, `specularColor` and `exponent` an energy-normalised
//! Phong lobe, `reflectiveColor` a mirror and `transparentColor` with
//! `indexOfRefraction` a Fresnel dielectric (with `glossiness`, their
//! glossy counterparts). The Whitted integrator does not use this module:
//! it keeps the course's Phong (`material::phong_light`, no `1/π`);
//! `docs/scene-format.md` states both readings.

mod lobe;
pub mod optics;
#[cfg(test)]
mod tests;

pub use lobe::Lobe;

use crate::material::glossy::lobe_exponent;
use crate::math::{Vec2, Vec3};
use crate::scene::Phong;

/// The most lobes a [`Bsdf`] holds (what [`Bsdf::from_phong`] can make).
pub const MAX_LOBES: usize = 4;

/// An orthonormal frame whose `z` is the surface normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    x: Vec3,
    y: Vec3,
    z: Vec3,
}

impl Frame {
    /// A frame around the unit normal `n`.
    pub fn from_normal(n: Vec3) -> Self {
        let (x, y) = n.any_orthonormal_pair();
        Self { x, y, z: n }
    }

    /// `v` in the frame's coordinates.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.x), v.dot(self.y), v.dot(self.z))
    }

    /// A vector given in the frame's coordinates, back in rendering space.
    #[inline]
    pub fn from_local(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }

    /// The normal.
    pub fn normal(&self) -> Vec3 {
        self.z
    }
}

/// A direction drawn from a BSDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// The unit direction towards where the light comes from.
    pub wi: Vec3,
    /// The BSDF's value for `(wo, wi)`: for a non-delta lobe the sum over
    /// every non-delta lobe; for a delta lobe that lobe's (the delta
    /// function's weight).
    pub f: Vec3,
    /// The density the direction was drawn with, per unit solid angle, of
    /// the whole mixture (for a delta lobe: the probability of choosing it).
    pub pdf: f32,
    /// Whether the direction came from a delta lobe (mirror, clear glass):
    /// no other strategy can find it, so it takes no MIS weight.
    pub delta: bool,
}

impl BsdfSample {
    /// `f·|cos θi|/pdf`: what the sample multiplies the light it carries by.
    pub fn weight(&self, n: Vec3) -> Vec3 {
        self.f * (self.wi.dot(n).abs() / self.pdf)
    }
}

/// The BSDF at a surface point: up to [`MAX_LOBES`] lobes in a shading
/// frame, one chosen per sample with probability proportional to its
/// [`Lobe::weight`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bsdf {
    frame: Frame,
    lobes: [Lobe; MAX_LOBES],
    /// Selection probabilities, summing to 1 over the first `len` lobes.
    probs: [f32; MAX_LOBES],
    len: usize,
}

impl Bsdf {
    /// A BSDF of `lobes` (at most [`MAX_LOBES`]; lobes of zero weight are
    /// dropped) around the unit surface normal `n`. The dielectric lobes
    /// read `n` as the outside.
    pub fn new(n: Vec3, lobes: &[Lobe]) -> Self {
        let mut b = Bsdf {
            frame: Frame::from_normal(n),
            lobes: [Lobe::Lambert { r: Vec3::ZERO }; MAX_LOBES],
            probs: [0.0; MAX_LOBES],
            len: 0,
        };
        for lobe in lobes.iter().filter(|l| l.weight() > 0.0) {
            assert!(b.len < MAX_LOBES, "a BSDF has at most {MAX_LOBES} lobes");
            b.lobes[b.len] = *lobe;
            b.probs[b.len] = lobe.weight();
            b.len += 1;
        }
        let total: f32 = b.probs.iter().sum();
        for p in &mut b.probs[..b.len] {
            *p /= total;
        }
        b
    }

    /// The physical reading of a course material at a point with unit
    /// normal `n` (the shape's outward normal: a dielectric is entered from
    /// its side). Colours are clamped to be non-negative, and if the sum
    /// `diffuse + specular + reflective + transparent` exceeds 1 in some
    /// channel, all four are scaled by one factor so that its largest
    /// channel is 1: the Whitted tree may reflect more than it receives, a
    /// physical material never does.
    pub fn from_phong(m: &Phong, n: Vec3) -> Self {
        let c = |v: Vec3| v.max(Vec3::ZERO);
        let (kd, ks, kr, kt) = (
            c(m.diffuse),
            c(m.specular),
            c(m.reflective),
            c(m.transparent),
        );
        let sum = (kd + ks + kr + kt).max_element();
        let scale = if sum > 1.0 { 1.0 / sum } else { 1.0 };
        let (kd, ks, kr, kt) = (kd * scale, ks * scale, kr * scale, kt * scale);
        let exponent = m.exponent.max(0.0);
        let (reflect, transmit) = if m.glossiness > 0.0 {
            let exponent = lobe_exponent(m.glossiness);
            let tint = kt;
            (
                Lobe::Glossy { r: kr, exponent },
                Lobe::GlossyDielectric {
                    tint,
                    exponent,
                    eta: m.ior,
                },
            )
        } else {
            (
                Lobe::Mirror { r: kr },
                Lobe::Dielectric {
                    tint: kt,
                    eta: m.ior,
                },
            )
        };
        let lobes = [
            Lobe::Lambert { r: kd },
            Lobe::Phong { ks, exponent },
            reflect,
            transmit,
        ];
        Bsdf::new(n, &lobes)
    }

    /// The lobes.
    pub fn lobes(&self) -> &[Lobe] {
        &self.lobes[..self.len]
    }

    /// The shading frame.
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// Whether every lobe is a delta lobe (light sampling is pointless:
    /// [`f`](Self::f) is 0 everywhere).
    pub fn is_delta(&self) -> bool {
        self.lobes().iter().all(Lobe::is_delta)
    }

    /// The sum of the non-delta lobes' values for light from `wi` leaving
    /// towards `wo`.
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let (wo, wi) = (self.frame.to_local(wo), self.frame.to_local(wi));
        self.lobes().iter().map(|l| l.f(wo, wi)).sum()
    }

    /// The density with which [`sample_f`](Self::sample_f) returns `wi`
    /// from a non-delta lobe: `Σ P(lobe)·pdf_lobe(wi)`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (wo, wi) = (self.frame.to_local(wo), self.frame.to_local(wi));
        self.local_pdf(wo, wi)
    }

    fn local_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        (self.lobes().iter().zip(&self.probs))
            .map(|(l, p)| p * l.pdf(wo, wi))
            .sum()
    }

    /// A direction for light leaving towards `wo`: `uc ∈ [0,1)` chooses
    /// the lobe, `u ∈ [0,1)²` the direction within it. `None` when the
    /// chosen lobe sends nothing that way (a direction below the surface,
    /// total internal reflection at the boundary of the critical angle).
    pub fn sample_f(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample> {
        let mut k = 0;
        let mut below = 0.0;
        while k + 1 < self.len && uc >= below + self.probs[k] {
            below += self.probs[k];
            k += 1;
        }
        let lobe = self.lobes.get(k).filter(|_| k < self.len)?;
        let wo_local = self.frame.to_local(wo);
        let s = lobe.sample(wo_local, u)?;
        let wi = self.frame.from_local(s.wi);
        if lobe.is_delta() {
            return Some(BsdfSample {
                wi,
                f: s.f,
                pdf: self.probs[k] * s.pdf,
                delta: true,
            });
        }
        let (f, pdf) = if self.len == 1 {
            (s.f, s.pdf)
        } else {
            let f = self.lobes().iter().map(|l| l.f(wo_local, s.wi)).sum();
            (f, self.local_pdf(wo_local, s.wi))
        };
        (pdf > 0.0).then_some(BsdfSample {
            wi,
            f,
            pdf,
            delta: false,
        })
    }
}
