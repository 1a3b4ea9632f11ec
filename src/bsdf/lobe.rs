//! The lobes a BSDF is made of, each in the local shading frame (the
//! surface normal is `+z`): its value `f`, a sampled direction with the
//! density it was drawn with, and that density for any direction.
//!
//! Opaque lobes (Lambert, Phong, mirror, glossy reflection) reflect on the
//! side `wo` is on: a surface seen from below (`wo.z < 0`) is the mirror
//! image of one seen from above. The dielectric lobes use the side to tell
//! entering (`wo.z > 0`: from index 1 into `eta`) from leaving.

use super::optics::{fresnel_dielectric, refract};
use crate::material::glossy::{lobe_pdf, sample_lobe};
use crate::math::warp::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::math::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, TAU};

/// One lobe of a BSDF. Colours are reflectances in `[0, 1]` per channel
/// (the fraction of the light arriving that the lobe sends on).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lobe {
    /// Lambert's ideal diffuse reflector: `f = r / π`, albedo `r`.
    Lambert {
        /// Reflectance (the albedo).
        r: Vec3,
    },
    /// The modified Phong lobe, normalised (Lafortune and Willems 1994):
    /// `f = ks·(e+2)/(2π)·cos^e α`, with α the angle between `wi` and the
    /// mirror direction of `wo`. Its albedo is `ks` at normal incidence and
    /// less elsewhere, so it never reflects more than it receives. Sampled
    /// by [`sample_lobe`] (the `cos^e` lobe around the mirror direction,
    /// folded above the surface).
    Phong {
        /// Specular reflectance (the albedo at normal incidence).
        ks: Vec3,
        /// Phong exponent.
        exponent: f32,
    },
    /// A perfect mirror (a delta lobe): all of `r` goes to the mirror
    /// direction.
    Mirror {
        /// Reflectance.
        r: Vec3,
    },
    /// A smooth dielectric boundary (a delta lobe): the Fresnel fraction
    /// `F` of `tint` is reflected, `1 − F` refracted (Snell); no `1/η²`
    /// radiance scaling (it cancels on a closed object, and keeps the
    /// lobe's albedo at `tint` from either side).
    Dielectric {
        /// Colour of both the reflection and the transmission.
        tint: Vec3,
        /// Index of refraction inside (the normal's back side) over outside.
        eta: f32,
    },
    /// The glossiness lobe of the distribution ray tracer
    /// (`material::glossy`): directions around the mirror direction with
    /// density [`lobe_pdf`], valued `f = r·pdf / |cos θi|` so that a sample
    /// weighs exactly `r`, as the Whitted tree's glossy rays do. Its albedo
    /// is `r` at every angle; it is not reciprocal.
    Glossy {
        /// Reflectance (the albedo).
        r: Vec3,
        /// Lobe exponent (`material::glossy::lobe_exponent`).
        exponent: f32,
    },
    /// A rough dielectric made of two glossiness lobes: around the mirror
    /// direction with probability `F` (Fresnel at `wo`) and around the
    /// refracted direction with `1 − F`, valued `tint · pdf / |cos θi|`
    /// (albedo `tint`). As the exponent grows it becomes [`Lobe::Dielectric`].
    GlossyDielectric {
        /// Colour of both sides.
        tint: Vec3,
        /// Lobe exponent.
        exponent: f32,
        /// Index of refraction inside over outside.
        eta: f32,
    },
}

/// A direction sampled from a lobe (local frame), the value of the lobe
/// there and the density it was drawn with (for a delta lobe: the discrete
/// probability of that branch).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct LobeSample {
    pub wi: Vec3,
    pub f: Vec3,
    pub pdf: f32,
}

/// `w` on the upper side (`z ≥ 0`) and the sign that took it there.
#[inline]
fn upper(w: Vec3) -> (Vec3, f32) {
    if w.z < 0.0 {
        (Vec3::new(w.x, w.y, -w.z), -1.0)
    } else {
        (w, 1.0)
    }
}

/// `w` with its `z` multiplied by `s` (±1): into or out of the upper side.
#[inline]
fn flip(w: Vec3, s: f32) -> Vec3 {
    Vec3::new(w.x, w.y, w.z * s)
}

/// The mirror direction of `wo` about `+z`.
#[inline]
fn mirror(wo: Vec3) -> Vec3 {
    Vec3::new(-wo.x, -wo.y, wo.z)
}

/// `eta` if it is a usable index ratio, else 1 (no bending).
#[inline]
fn sane(eta: f32) -> f32 {
    if eta > 0.0 && eta.is_finite() {
        eta
    } else {
        1.0
    }
}

/// The refracted direction of `wo` (local frame) and the side it leaves
/// towards, `None` under total internal reflection.
fn transmitted(wo: Vec3, eta: f32) -> Option<Vec3> {
    let (n, n_i, n_t) = if wo.z >= 0.0 {
        (Vec3::Z, 1.0, eta)
    } else {
        (Vec3::NEG_Z, eta, 1.0)
    };
    refract(-wo, n, n_i, n_t)
}

impl Lobe {
    /// Whether the lobe sends light into single directions only.
    pub fn is_delta(&self) -> bool {
        matches!(self, Lobe::Mirror { .. } | Lobe::Dielectric { .. })
    }

    /// A bound on the lobe's albedo (its largest channel), used to choose
    /// among lobes.
    pub fn weight(&self) -> f32 {
        match *self {
            Lobe::Lambert { r }
            | Lobe::Phong { ks: r, .. }
            | Lobe::Mirror { r }
            | Lobe::Dielectric { tint: r, .. }
            | Lobe::Glossy { r, .. }
            | Lobe::GlossyDielectric { tint: r, .. } => r.max_element().max(0.0),
        }
    }

    /// The lobe's value for light arriving from `wi` leaving towards `wo`
    /// (0 for delta lobes).
    pub(super) fn f(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        match *self {
            Lobe::Lambert { r } => {
                if wo.z * wi.z > 0.0 {
                    r * FRAC_1_PI
                } else {
                    Vec3::ZERO
                }
            }
            Lobe::Phong { ks, exponent } => {
                if wo.z * wi.z <= 0.0 {
                    return Vec3::ZERO;
                }
                let (wo, s) = upper(wo);
                let c = mirror(wo).dot(flip(wi, s));
                if c <= 0.0 {
                    return Vec3::ZERO;
                }
                ks * ((exponent + 2.0) / TAU * c.powf(exponent))
            }
            Lobe::Mirror { .. } | Lobe::Dielectric { .. } => Vec3::ZERO,
            Lobe::Glossy { r, .. } | Lobe::GlossyDielectric { tint: r, .. } => {
                let cos = wi.z.abs();
                if cos == 0.0 {
                    return Vec3::ZERO;
                }
                r * (self.pdf(wo, wi) / cos)
            }
        }
    }

    /// The density of [`sample`](Self::sample) at `wi` (0 for delta lobes).
    pub(super) fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            Lobe::Lambert { .. } => {
                if wo.z * wi.z > 0.0 {
                    cosine_hemisphere_pdf(wi.z.abs())
                } else {
                    0.0
                }
            }
            Lobe::Phong { exponent: e, .. } | Lobe::Glossy { exponent: e, .. } => {
                if wo.z * wi.z <= 0.0 {
                    return 0.0;
                }
                let (wo, s) = upper(wo);
                lobe_pdf(mirror(wo), Vec3::Z, e, flip(wi, s))
            }
            Lobe::Mirror { .. } | Lobe::Dielectric { .. } => 0.0,
            Lobe::GlossyDielectric { exponent, eta, .. } => {
                let eta = sane(eta);
                let f = fresnel_dielectric(wo.z, eta);
                let side = if wo.z >= 0.0 { Vec3::Z } else { Vec3::NEG_Z };
                let r = lobe_pdf(mirror(wo), side, exponent, wi);
                let t = transmitted(wo, eta).map_or(0.0, |t| lobe_pdf(t, -side, exponent, wi));
                f * r + (1.0 - f) * t
            }
        }
    }

    /// A direction drawn by `u ∈ [0,1)²`, `None` when the lobe sends
    /// nothing (a direction below the surface, `wo` in the surface).
    pub(super) fn sample(&self, wo: Vec3, u: Vec2) -> Option<LobeSample> {
        if wo.z == 0.0 {
            return None;
        }
        let (up, s) = upper(wo);
        let side = Vec3::Z * s;
        let wi = match *self {
            Lobe::Lambert { .. } => flip(cosine_hemisphere(Vec3::Z, u), s),
            Lobe::Phong { exponent: e, .. } | Lobe::Glossy { exponent: e, .. } => {
                flip(sample_lobe(mirror(up), Vec3::Z, e, u), s)
            }
            Lobe::Mirror { r } => {
                let wi = mirror(wo);
                return Some(LobeSample {
                    wi,
                    f: r / wi.z.abs(),
                    pdf: 1.0,
                });
            }
            Lobe::Dielectric { tint, eta } => {
                let f = fresnel_dielectric(wo.z, sane(eta));
                let (wi, p) = if u.x < f {
                    (mirror(wo), f)
                } else {
                    (transmitted(wo, sane(eta))?, 1.0 - f)
                };
                return Some(LobeSample {
                    wi,
                    f: tint * (p / wi.z.abs()),
                    pdf: p,
                });
            }
            Lobe::GlossyDielectric { exponent, eta, .. } => {
                let f = fresnel_dielectric(wo.z, sane(eta));
                if u.x < f {
                    let u = Vec2::new(u.x / f, u.y);
                    sample_lobe(mirror(wo), side, exponent, u)
                } else {
                    let u = Vec2::new((u.x - f) / (1.0 - f), u.y);
                    sample_lobe(transmitted(wo, sane(eta))?, -side, exponent, u)
                }
            }
        };
        let pdf = self.pdf(wo, wi);
        (pdf > 0.0).then(|| LobeSample {
            wi,
            f: self.f(wo, wi),
            pdf,
        })
    }
}
