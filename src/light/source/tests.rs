//! Runtime lights: the same answers as the Whitted entry points where they
//! overlap, densities that integrate to 1 over the sphere of directions
//! (quadrature), `pdf_li` equal to the density `sample_li` reports, and the
//! emitted radiance a ray finds agreeing with what the samples carry.

use super::*;
use crate::light::{incident, sample_light};
use crate::math::testing::sphere_integral;

fn bits(v: Vec3) -> [u32; 3] {
    v.to_array().map(f32::to_bits)
}

/// Stratified `u` on a `k × k` grid.
fn grid(k: usize) -> impl Iterator<Item = Vec2> {
    let at = move |i: usize| (i as f32 + 0.5) / k as f32;
    (0..k).flat_map(move |i| (0..k).map(move |j| Vec2::new(at(i), at(j))))
}

fn area(shape: RenderAreaShape) -> RenderLight {
    Light::Area {
        shape,
        color: Vec3::new(1.0, 0.8, 0.5),
        power: 30.0,
    }
}

fn scene_area_lights() -> Vec<RenderLight> {
    vec![
        area(AreaShape::Quad {
            corner: Vec3::new(-0.5, 2.0, -0.25),
            edge1: Vec3::new(1.0, 0.2, 0.0),
            edge2: Vec3::new(0.0, 0.0, 0.75),
        }),
        area(AreaShape::Disk {
            center: Vec3::new(0.3, 1.5, 0.2),
            normal: Vec3::new(0.2, -3.0, 0.1),
            radius: 0.6,
        }),
        area(AreaShape::Sphere {
            center: Vec3::new(-0.4, 1.8, 0.5),
            radius: 0.7,
        }),
    ]
}

/// A one-sided triangle facing down (its normal is `-y`) above the origin.
fn triangle_light() -> LightSource {
    LightSource::Area(AreaLight {
        shape: Emitter::Triangle(Triangle::new(
            Vec3::new(-0.5, 1.2, -0.4),
            Vec3::new(0.8, 1.1, -0.6),
            Vec3::new(0.2, 1.4, 0.9),
        )),
        radiance: Vec3::new(2.0, 1.0, 0.5),
        two_sided: false,
    })
}

/// Shading points around (and for flat lights, behind) the lights.
fn points() -> [Vec3; 4] {
    [
        Vec3::ZERO,
        Vec3::new(0.7, -0.5, 0.3),
        Vec3::new(-1.5, 0.4, 1.0),
        Vec3::new(0.1, 3.5, -0.2),
    ]
}

/// Delta lights answer as `light::incident`, bit for bit (directions of
/// every size, a zero and a NaN direction, a point light), and sample as
/// delta lights with no density anywhere else.
#[test]
fn delta_lights_match_incident_bit_for_bit() {
    let dirs = [
        Vec3::new(0.3, -1.7, 0.2),
        Vec3::new(-0.0, -2.0, 0.0),
        Vec3::new(1e38, 3e38, -1e38),
        Vec3::new(1e-40, 0.0, -3e-41),
        Vec3::ZERO,
        Vec3::new(f32::NAN, 1.0, 0.0),
    ];
    let mut lights: Vec<RenderLight> = (dirs.iter())
        .map(|&direction| Light::Directional {
            direction,
            color: Vec3::new(0.5, 1.0, 2.0),
        })
        .collect();
    lights.push(Light::Point {
        position: Vec3::new(1.0, 2.0, 3.0),
        color: Vec3::ONE,
        attenuation: Vec3::new(0.5, 0.25, 0.125),
    });
    for p in points() {
        for l in &lights {
            let src = LightSource::from_scene(l);
            assert!(src.is_delta());
            let (a, b) = (src.incident(p).unwrap(), incident(l, p));
            assert_eq!(bits(a.to_light), bits(b.to_light), "{l:?}");
            assert_eq!(bits(a.color), bits(b.color));
            assert_eq!(a.at, b.at);
            if let Some(s) = src.sample_li(p, Vec2::new(0.3, 0.7)) {
                assert!(s.delta && s.pdf == 1.0, "{s:?}");
                assert_eq!((s.wi, s.li), (b.to_light, b.color));
                assert_eq!(src.pdf_li(p, s.wi), 0.0);
            } else {
                assert!(b.to_light == Vec3::ZERO || b.to_light.is_nan(), "{l:?}");
            }
        }
    }
    let point = LightSource::from_scene(&lights[6]);
    let s = point.sample_li(Vec3::ZERO, Vec2::ZERO).unwrap();
    assert_eq!(s.to, LightPoint::Position(Vec3::new(1.0, 2.0, 3.0)));
    assert!((s.dist - 14f32.sqrt()).abs() < 1e-6);
}

/// The scene's area lights sample the same points as the Whitted tree's
/// `sample_light` (the same bits: one geometry), and the radiance over the
/// density is its estimate.
#[test]
fn area_samples_are_the_whitted_samples() {
    for l in scene_area_lights() {
        let src = LightSource::from_scene(&l);
        assert!(!src.is_delta());
        for p in points() {
            for u in grid(16) {
                let inc = sample_light(&l, p, u);
                let Some(s) = src.sample_li(p, u) else {
                    assert_eq!(inc.color, Vec3::ZERO, "{l:?} {p} {u}");
                    continue;
                };
                assert_eq!(bits(s.wi), bits(inc.to_light), "{l:?} {p} {u}");
                let LightPoint::Surface(at) = s.to else {
                    panic!("{s:?}")
                };
                assert_eq!(Some(at), inc.at);
                let est = s.li / s.pdf;
                assert!(
                    (est - inc.color).abs().max_element() <= 1e-4 * inc.color.max_element(),
                    "{l:?} {p} {u}: {est} vs {}",
                    inc.color
                );
            }
        }
    }
}

/// Every area light from every point: `pdf_li` integrates to 1 over the
/// sphere when the light is seen (0 when only its back is), each sample's
/// density is `pdf_li`'s for its direction, the ray along it hits the light
/// at the sample's distance, and the mean of `li/pdf` equals the emitted
/// radiance integrated over the directions that hit the light.
#[test]
fn densities_integrate_to_one_and_agree() {
    let mut lights: Vec<LightSource> = (scene_area_lights().iter())
        .map(LightSource::from_scene)
        .collect();
    lights.push(triangle_light());
    for light in &lights {
        let a = light.area().unwrap();
        for p in points() {
            let total = sphere_integral(|w| Vec3::splat(light.pdf_li(p, w))).x;
            let seen =
                sphere_integral(|w| match a.intersect(&Ray::new(p, w), 0.0, f32::INFINITY) {
                    Some(h) => h.le,
                    None => Vec3::ZERO,
                });
            let (mut sum, mut n, mut got) = (Vec3::ZERO.as_dvec3(), 0, 0);
            for u in grid(64) {
                n += 1;
                let Some(s) = light.sample_li(p, u) else {
                    continue;
                };
                got += 1;
                let pdf = light.pdf_li(p, s.wi);
                assert!(
                    (pdf - s.pdf).abs() <= 2e-3 * s.pdf,
                    "{light:?} {p} {u}: {pdf} vs {s:?}"
                );
                let h = a.intersect(&Ray::new(p, s.wi), 0.0, f32::INFINITY);
                let h = h.unwrap_or_else(|| panic!("{light:?} {p} {u}: {s:?} misses"));
                assert!((h.t - s.dist).abs() < 1e-3 * s.dist, "{h:?} {s:?}");
                assert_eq!(h.le, s.li);
                sum += (s.li / s.pdf).as_dvec3();
            }
            if got == 0 {
                // Behind a one-sided light: nothing is sampled, and no
                // direction has a density or finds radiance.
                assert!(
                    total == 0.0 && seen == Vec3::ZERO.as_dvec3(),
                    "{light:?} {p}"
                );
                continue;
            }
            assert_eq!(got, n, "{light:?} {p}: some samples failed");
            assert!((total - 1.0).abs() < 1e-2, "{light:?} {p}: ∫pdf {total}");
            let mean = sum / n as f64;
            assert!(
                ((mean - seen) / seen).abs().max_element() < 1e-2,
                "{light:?} {p}: sampled {mean} vs ∫Le {seen}"
            );
        }
    }
}

/// A one-sided emitter sends nothing behind it; a two-sided one the same
/// on both sides; the sphere nothing inside it.
#[test]
fn sides_and_insides() {
    let tri = triangle_light();
    let above = Vec3::new(0.1, 3.0, 0.0);
    assert!(tri.sample_li(above, Vec2::splat(0.5)).is_none());
    assert_eq!(tri.pdf_li(above, Vec3::NEG_Y), 0.0);
    assert!(tri.sample_li(Vec3::ZERO, Vec2::splat(0.5)).is_some());
    let quad = LightSource::from_scene(&scene_area_lights()[0]);
    let (a, b) = (Vec3::new(0.0, 0.0, 0.1), Vec3::new(0.0, 4.0, 0.1));
    let (sa, sb) = (
        quad.sample_li(a, Vec2::splat(0.5)).unwrap(),
        quad.sample_li(b, Vec2::splat(0.5)).unwrap(),
    );
    assert_eq!(sa.li, sb.li);
    let sphere = LightSource::from_scene(&scene_area_lights()[2]);
    let inside = Vec3::new(-0.4, 1.9, 0.5);
    assert!(sphere.sample_li(inside, Vec2::splat(0.5)).is_none());
    assert_eq!(sphere.pdf_li(inside, Vec3::Y), 0.0);
}

/// A tiny, far sphere: the density stays finite (the solid angle does not
/// cancel to 0) and still matches `pdf_li`.
#[test]
fn small_far_spheres_keep_a_finite_density() {
    let light = LightSource::from_scene(&area(AreaShape::Sphere {
        center: Vec3::new(0.0, 1000.0, 0.0),
        radius: 0.01,
    }));
    let s = light.sample_li(Vec3::ZERO, Vec2::splat(0.5)).unwrap();
    let want = 1.0 / (PI * 1e-10);
    assert!((s.pdf - want).abs() < 1e-3 * want, "{s:?}");
    assert!((light.pdf_li(Vec3::ZERO, Vec3::Y) - s.pdf).abs() < 1e-3 * s.pdf);
}
