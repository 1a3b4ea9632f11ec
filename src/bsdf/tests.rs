//! Every lobe and the course materials' physical reading: densities
//! integrate to 1 (quadrature over the sphere), `pdf` is the density
//! `sample_f` reports, sampled and integrated albedos agree with the closed
//! forms, reciprocity where it holds, and no material reflects more than it
//! receives.

use super::*;
use crate::math::testing::{sphere_integral, Lcg};

/// Stratified values of `(uc, u)`: `k` strata per dimension.
fn grid(k: usize) -> impl Iterator<Item = (f32, Vec2)> {
    let at = move |i: usize| (i as f32 + 0.5) / k as f32;
    (0..k).flat_map(move |a| {
        (0..k).flat_map(move |b| (0..k).map(move |c| (at(a), Vec2::new(at(b), at(c)))))
    })
}

/// The mean sample weight `f·|cos|/pdf` over the grid (what the BSDF sends
/// on of unit light from everywhere: its albedo), the fraction of samples
/// that failed, and checks each sample: the reported density is `pdf`'s
/// and the value `f`'s (non-delta), the direction is unit and the weight
/// finite.
fn sampled_albedo(b: &Bsdf, wo: Vec3, k: usize) -> (Vec3, f64) {
    let n = b.frame().normal();
    let (mut sum, mut failed, mut count) = (Vec3::ZERO.as_dvec3(), 0usize, 0usize);
    for (uc, u) in grid(k) {
        count += 1;
        let Some(s) = b.sample_f(wo, uc, u) else {
            failed += 1;
            continue;
        };
        assert!((s.wi.length() - 1.0).abs() < 1e-4, "{wo} {u}: {}", s.wi);
        assert!(s.pdf > 0.0 && s.pdf.is_finite(), "{s:?}");
        if !s.delta {
            let pdf = b.pdf(wo, s.wi);
            assert!(
                (pdf - s.pdf).abs() <= 1e-3 * s.pdf,
                "{wo} {u}: {pdf} vs {s:?}"
            );
            // The glossiness lobes' values grow as 1/|cos θi| towards
            // the horizon, where the frame's round trip moves the cosine by
            // more than 1e-3 of itself: those few samples are not compared.
            let f = b.f(wo, s.wi);
            let ok = (f - s.f).abs().max_element() <= 1e-3 * s.f.max_element();
            assert!(ok || s.wi.dot(n).abs() < 1e-3, "{f} vs {s:?}");
        }
        let w = s.weight(n);
        assert!(w.is_finite(), "{s:?}");
        sum += w.as_dvec3();
    }
    ((sum / count as f64).as_vec3(), failed as f64 / count as f64)
}

/// Directions `wo` from the normal to grazing, on both sides, in a frame
/// whose normal is in no special position.
fn outgoing(n: Vec3) -> Vec<Vec3> {
    let f = Frame::from_normal(n);
    let mut v = Vec::new();
    for theta in [0.0f32, 0.3, 0.8, 1.2, 1.5] {
        for (phi, side) in [(0.4f32, 1.0f32), (2.5, -1.0)] {
            let local = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                side * theta.cos(),
            );
            v.push(f.from_local(local).normalize());
        }
    }
    v
}

fn normal() -> Vec3 {
    Vec3::new(0.3, 0.8, -0.5).normalize()
}

/// The non-delta lobes: for every `wo`, the density integrates to 1 over
/// the sphere (to 1 − P(failure) for a lobe that can fail), the value times
/// `|cos θi|` integrates to the albedo the samples estimate, and both match
/// the lobe's closed form where it has one. (Where the value is large, at
/// the peak of a narrow lobe, `f` and `pdf` of the same direction after its
/// round trip through the shading frame agree to 1e-3.)
#[test]
fn densities_integrate_to_one_and_values_to_the_albedo() {
    let n = normal();
    let c = Vec3::new(0.9, 0.5, 0.2);
    let lobes = [
        (Lobe::Lambert { r: c }, Some(c)),
        (
            Lobe::Phong {
                ks: c,
                exponent: 1.0,
            },
            None,
        ),
        (
            Lobe::Phong {
                ks: c,
                exponent: 30.0,
            },
            None,
        ),
        (
            Lobe::Glossy {
                r: c,
                exponent: 0.0,
            },
            Some(c),
        ),
        (
            Lobe::Glossy {
                r: c,
                exponent: 20.0,
            },
            Some(c),
        ),
        (
            Lobe::GlossyDielectric {
                tint: c,
                exponent: 40.0,
                eta: 1.5,
            },
            Some(c),
        ),
    ];
    for (lobe, closed) in lobes {
        let b = Bsdf::new(n, &[lobe]);
        for wo in outgoing(n) {
            let (sampled, failed) = sampled_albedo(&b, wo, 48);
            let total = sphere_integral(|wi| Vec3::splat(b.pdf(wo, wi))).x;
            assert!(
                (total + failed - 1.0).abs() < 2e-3,
                "{lobe:?} {wo}: ∫pdf {total}, failed {failed}"
            );
            let albedo = sphere_integral(|wi| b.f(wo, wi) * wi.dot(n).abs()).as_vec3();
            assert!(
                (albedo - sampled).abs().max_element() < 5e-3,
                "{lobe:?} {wo}: ∫f·cos {albedo}, sampled {sampled}"
            );
            if let Some(want) = closed {
                assert!(
                    (albedo - want).abs().max_element() < 5e-3,
                    "{lobe:?} {wo}: {albedo} vs {want}"
                );
            }
        }
    }
}

/// The normalised Phong lobe reflects exactly `ks` at normal incidence
/// (`(e+2)/(2π)·∫cos^{e+1} = 1`) and less at every other angle.
#[test]
fn phong_lobe_is_energy_normalised() {
    let n = Vec3::Z;
    for e in [0.0f32, 1.0, 10.0, 40.0] {
        let b = Bsdf::new(
            n,
            &[Lobe::Phong {
                ks: Vec3::ONE,
                exponent: e,
            }],
        );
        let albedo = |wo: Vec3| sphere_integral(|wi| b.f(wo, wi) * wi.z.abs()).x;
        let head_on = albedo(Vec3::Z);
        assert!((head_on - 1.0).abs() < 2e-3, "e {e}: {head_on}");
        let mut last = head_on;
        for theta in [0.4f32, 0.9, 1.3] {
            let a = albedo(Vec3::new(theta.sin(), 0.0, theta.cos()));
            assert!(a <= last + 1e-3, "e {e}, θ {theta}: {a} after {last}");
            last = a;
        }
    }
}

/// `f(wo, wi) = f(wi, wo)` for the lobes that are reciprocal (Lambert,
/// Phong, and BSDFs of them), over random pairs on both sides.
#[test]
fn reciprocal_lobes_are_reciprocal() {
    let n = normal();
    let mut g = Lcg(11);
    let mut dir = || {
        let v = Vec3::new(g.next() - 0.5, g.next() - 0.5, g.next() - 0.5);
        v.normalize_or(Vec3::X)
    };
    let c = Vec3::new(0.7, 0.4, 0.1);
    let b = Bsdf::new(
        n,
        &[
            Lobe::Lambert { r: c },
            Lobe::Phong {
                ks: Vec3::splat(0.2),
                exponent: 12.0,
            },
        ],
    );
    let mut nonzero = 0;
    for _ in 0..20000 {
        let (wo, wi) = (dir(), dir());
        let (a, r) = (b.f(wo, wi), b.f(wi, wo));
        assert!(
            (a - r).abs().max_element() <= 1e-5 * a.max_element().max(1e-3),
            "{wo} {wi}: {a} {r}"
        );
        nonzero += usize::from(a != Vec3::ZERO);
    }
    // Half the pairs are on one side.
    assert!(nonzero > 8000, "{nonzero}");
}

/// The mirror: all of `r` towards the mirror direction, with probability
/// 1, and nothing anywhere else.
#[test]
fn mirror_is_a_delta_lobe() {
    let n = normal();
    let r = Vec3::new(0.8, 0.6, 0.3);
    let b = Bsdf::new(n, &[Lobe::Mirror { r }]);
    assert!(b.is_delta());
    for wo in outgoing(n) {
        let s = b.sample_f(wo, 0.3, Vec2::new(0.2, 0.9)).unwrap();
        assert!(s.delta && s.pdf == 1.0);
        assert!(
            (s.wi - optics::reflect(-wo, n)).length() < 1e-5,
            "{wo}: {s:?}"
        );
        assert!((s.weight(n) - r).abs().max_element() < 1e-5, "{s:?}");
        assert_eq!(b.f(wo, s.wi), Vec3::ZERO);
        assert_eq!(b.pdf(wo, s.wi), 0.0);
    }
}

/// The smooth dielectric: reflection with probability F (Fresnel) and
/// refraction (Snell) with 1 − F, each sample weighing `tint`, from
/// either side; total internal reflection sends everything back.
#[test]
fn dielectric_splits_by_fresnel() {
    let n = normal();
    let tint = Vec3::new(0.9, 0.95, 1.0);
    let eta = 1.5;
    let b = Bsdf::new(n, &[Lobe::Dielectric { tint, eta }]);
    for wo in outgoing(n) {
        let cos = wo.dot(n);
        let fresnel = optics::fresnel_dielectric(cos, eta);
        let k = 1000;
        let mut reflected = 0;
        for i in 0..k {
            let u = Vec2::new((i as f32 + 0.5) / k as f32, 0.5);
            let s = b.sample_f(wo, 0.5, u).unwrap();
            assert!(s.delta);
            assert!(
                (s.weight(n) - tint).abs().max_element() < 1e-4,
                "{wo}: {s:?}"
            );
            if s.wi.dot(n) * cos > 0.0 {
                reflected += 1;
                assert!((s.wi - optics::reflect(-wo, n)).length() < 1e-5);
                assert!((s.pdf - fresnel).abs() < 1e-6);
            } else {
                // Snell: η_i sin θi = η_t sin θt.
                let (ni, nt) = if cos > 0.0 { (1.0, eta) } else { (eta, 1.0) };
                let sin = |w: Vec3| w.cross(n).length();
                assert!((ni * sin(wo) - nt * sin(s.wi)).abs() < 1e-4, "{wo}: {s:?}");
                assert!((s.pdf - (1.0 - fresnel)).abs() < 1e-6);
            }
        }
        // The two branches' probabilities sum to 1 and match F.
        let share = reflected as f32 / k as f32;
        assert!(
            (share - fresnel).abs() <= 1.0 / k as f32 + 1e-6,
            "{wo}: {share} vs {fresnel}"
        );
    }
    // Grazing from inside: beyond the critical angle, all reflected.
    let f = Frame::from_normal(n);
    let inside = f.from_local(Vec3::new(0.9, 0.0, -(1.0f32 - 0.81).sqrt()));
    for i in 0..10 {
        let s = b
            .sample_f(inside, 0.5, Vec2::new(i as f32 / 10.0, 0.5))
            .unwrap();
        assert!(s.wi.dot(n) < 0.0 && (s.pdf - 1.0).abs() < 1e-6, "{s:?}");
    }
}

/// A rough dielectric converges to the smooth one as its exponent grows:
/// its reflected share is F and its directions close in on the mirror and
/// refracted directions.
#[test]
fn glossy_dielectric_tends_to_the_smooth_one() {
    let n = Vec3::Z;
    let wo = Vec3::new(0.5, 0.0, 0.75f32.sqrt());
    let fresnel = optics::fresnel_dielectric(wo.z, 1.5);
    let t = optics::refract(-wo, n, 1.0, 1.5).unwrap();
    let b = Bsdf::new(
        n,
        &[Lobe::GlossyDielectric {
            tint: Vec3::ONE,
            exponent: 1e5,
            eta: 1.5,
        }],
    );
    let (mut reflected, mut count) = (0, 0);
    for (uc, u) in grid(20) {
        let s = b.sample_f(wo, uc, u).unwrap();
        count += 1;
        if s.wi.z > 0.0 {
            reflected += 1;
            assert!(s.wi.dot(optics::reflect(-wo, n)) > 0.999, "{s:?}");
        } else {
            assert!(s.wi.dot(t) > 0.999, "{s:?}");
        }
    }
    let share = reflected as f32 / count as f32;
    assert!((share - fresnel).abs() < 0.01, "{share} vs {fresnel}");
}

/// The course's materials read physically: the lobes they become, and a
/// white furnace: for every `wo`, no material sends on more than it
/// receives (sampled over all lobes, delta ones included), and a material
/// whose colours sum to at most 1 keeps its albedo where the closed form
/// is known.
#[test]
fn course_materials_never_reflect_more_than_they_receive() {
    let n = normal();
    let phong = |d: f32, s: f32, e: f32, r: f32, t: f32, g: f32| Phong {
        diffuse: Vec3::new(d, d * 0.5, d * 0.25),
        specular: Vec3::splat(s),
        exponent: e,
        reflective: Vec3::splat(r),
        transparent: Vec3::splat(t),
        ior: 1.5,
        glossiness: g,
    };
    let materials = [
        phong(1.0, 0.0, 1.0, 0.0, 0.0, 0.0),
        phong(1.0, 1.0, 20.0, 0.0, 0.0, 0.0),
        phong(0.8, 0.5, 64.0, 0.6, 0.0, 0.0),
        phong(0.1, 0.3, 10.0, 0.2, 0.9, 0.0),
        phong(0.5, 0.5, 5.0, 0.5, 0.5, 0.3),
        phong(0.0, 0.0, 1.0, 0.0, 1.0, 0.2),
        phong(3.0, 2.0, 1.0, 1.0, 1.0, 0.0),
    ];
    for m in &materials {
        let b = Bsdf::from_phong(m, n);
        for wo in outgoing(n) {
            let (albedo, _) = sampled_albedo(&b, wo, 24);
            assert!(albedo.max_element() <= 1.0 + 2e-3, "{m:?} {wo}: {albedo}");
        }
    }
    // Pure diffuse: the albedo is the diffuse colour, f = kd/π.
    let m = phong(0.8, 0.0, 1.0, 0.0, 0.0, 0.0);
    let b = Bsdf::from_phong(&m, n);
    assert_eq!(b.lobes(), &[Lobe::Lambert { r: m.diffuse }]);
    let (albedo, _) = sampled_albedo(&b, n, 24);
    assert!((albedo - m.diffuse).abs().max_element() < 1e-3, "{albedo}");
    // Over-bright colours are scaled by one factor (hue kept).
    let m = phong(1.0, 0.0, 1.0, 1.0, 0.0, 0.0);
    let b = Bsdf::from_phong(&m, n);
    assert_eq!(
        b.lobes(),
        &[
            Lobe::Lambert { r: m.diffuse * 0.5 },
            Lobe::Mirror {
                r: Vec3::splat(0.5)
            }
        ]
    );
    // Glass with gloss: the glossy lobes.
    let b = Bsdf::from_phong(&materials[5], n);
    assert!(matches!(b.lobes(), [Lobe::GlossyDielectric { eta, .. }] if *eta == 1.5));
}

/// Lobe choice: a mixture's density is the probability-weighted sum, and
/// each lobe is chosen in proportion to its weight.
#[test]
fn lobes_are_chosen_by_weight() {
    let n = Vec3::Z;
    let b = Bsdf::new(
        n,
        &[
            Lobe::Lambert {
                r: Vec3::splat(0.6),
            },
            Lobe::Mirror {
                r: Vec3::splat(0.2),
            },
        ],
    );
    let wo = Vec3::new(0.6, 0.0, 0.8);
    let k = 1000;
    let delta = (0..k)
        .filter(|&i| {
            let uc = (i as f32 + 0.5) / k as f32;
            b.sample_f(wo, uc, Vec2::splat(0.3)).unwrap().delta
        })
        .count();
    assert_eq!(delta, 250);
    let s = b.sample_f(wo, 0.1, Vec2::splat(0.3)).unwrap();
    assert!(
        (s.pdf - 0.75 * s.wi.z / std::f32::consts::PI).abs() < 1e-6,
        "{s:?}"
    );
    let s = b.sample_f(wo, 0.9, Vec2::splat(0.3)).unwrap();
    assert!((s.pdf - 0.25).abs() < 1e-6, "{s:?}");
    // No lobes: nothing.
    let none = Bsdf::new(n, &[Lobe::Lambert { r: Vec3::ZERO }]);
    assert!(none.lobes().is_empty() && none.sample_f(wo, 0.5, Vec2::splat(0.5)).is_none());
}
