//! Distribution ray tracing against closed forms, and its noise as samples
//! grow.
//!
//! - Soft shadows: the unoccluded fraction of a rectangle light past an
//!   occluder's edge, and the irradiance of its visible part (Lambert's
//!   polygon formula), within 2%.
//! - Ambient occlusion: 1 on an open plane; beside a wall, the cosine-weighted
//!   open fraction `1 − (acos a − a√(1−a²))/π`, `a = d / max distance`,
//!   within 2%.
//! - Depth of field: a point on the focus plane images within a pixel; off
//!   the plane it spreads over a disk whose radius grows with the aperture
//!   as the thin-lens formula says.
//! - Motion blur: a moving sphere images as the mean of static renders at
//!   instants spread over the shutter, within noise.
//! - Noise: RMSE falls about as `N^-1/2` for each effect, faster with the
//!   Sobol sampler: for soft shadows, glossy reflection and ambient
//!   occlusion against a closed form or an independent integral (so a
//!   biased estimator stalls at its bias and fails), for motion blur and
//!   depth of field against a high-sample render.
//!
//! Numbers are printed with `--nocapture`.

use glint::integrator::{AmbientOcclusion, AoSettings, Integrator, NoObserver, Trace, Whitted};
use glint::light::{is_delta, sample_light};
use glint::math::{Keyframe, Motion, Ray, Vec2, Vec3};
use glint::render::{render_image, CameraModel, Control, PixelOffset, Settings};
use glint::sampler::{Sampler, SamplerKind};
use glint::scene::{
    AreaShape, Background, Camera, Effects, Lens, Light, Material, Node, Phong, Scene, ShapeDesc,
};
use glint::stats::Counters;
use glint::world::{BuildOptions, World};
use std::f32::consts::PI;
use std::sync::Arc;

fn shape(shape: ShapeDesc, material: usize) -> Node {
    Node::Shape {
        shape,
        material: Some(material),
    }
}

fn plane(normal: Vec3, offset: f32) -> ShapeDesc {
    ShapeDesc::Plane {
        normal,
        offset: f64::from(offset),
    }
}

fn sphere(center: Vec3, radius: f32) -> ShapeDesc {
    ShapeDesc::Sphere {
        center: center.as_dvec3(),
        radius,
    }
}

fn white() -> Material {
    Material::Phong(Phong {
        diffuse: Vec3::ONE,
        ..Phong::default()
    })
}

fn scene(camera: Camera, lights: Vec<Light>, materials: Vec<Material>, root: Node) -> Scene {
    Scene {
        camera,
        lights,
        background: Background {
            color: Vec3::ZERO,
            ambient: Vec3::ZERO,
        },
        materials,
        root,
        effects: Effects::default(),
    }
}

fn look_down() -> Camera {
    Camera::Perspective {
        center: Vec3::new(0.0, 10.0, 0.0).as_dvec3(),
        direction: Vec3::NEG_Y,
        up: Vec3::Z,
        angle_deg: 30.0,
    }
}

// ---------------------------------------------------------------------------
// Soft shadows

/// Light: the square [-2,2]² at height 4. Occluder: the half-plane x < 0 at
/// height 2 (two big triangles). Floor y = 0.
const H_LIGHT: f32 = 4.0;
const H_OCC: f32 = 2.0;

fn penumbra_scene() -> Scene {
    let quad = AreaShape::Quad {
        corner: Vec3::new(-2.0, H_LIGHT, -2.0).as_dvec3(),
        edge1: Vec3::new(4.0, 0.0, 0.0),
        edge2: Vec3::new(0.0, 0.0, 4.0),
    };
    // Radiance 1: power = π · (two faces · 16).
    let light = Light::Area {
        shape: quad,
        color: Vec3::ONE,
        power: PI * 32.0,
    };
    let (a, b, c, d) = (
        Vec3::new(-100.0, H_OCC, -100.0),
        Vec3::new(0.0, H_OCC, -100.0),
        Vec3::new(0.0, H_OCC, 100.0),
        Vec3::new(-100.0, H_OCC, 100.0),
    );
    let root = Node::Group(vec![
        shape(plane(Vec3::Y, 0.0), 0),
        shape(
            ShapeDesc::Triangle([a.as_dvec3(), b.as_dvec3(), c.as_dvec3()]),
            0,
        ),
        shape(
            ShapeDesc::Triangle([a.as_dvec3(), c.as_dvec3(), d.as_dvec3()]),
            0,
        ),
    ]);
    scene(look_down(), vec![light], vec![white()], root)
}

/// Irradiance at `p` (normal +y) from the light rectangle x ∈ [x0, x1],
/// z ∈ [-2, 2] at height 4, of radiance 1: Lambert's formula
/// `E = ½ Σ θ_i (n · û_i)` over the polygon's edges.
fn lambert(p: Vec3, x0: f32, x1: f32) -> f64 {
    let v = [
        Vec3::new(x0, H_LIGHT, -2.0),
        Vec3::new(x1, H_LIGHT, -2.0),
        Vec3::new(x1, H_LIGHT, 2.0),
        Vec3::new(x0, H_LIGHT, 2.0),
    ]
    .map(|q| (q - p).as_dvec3().normalize());
    let mut e = 0.0;
    for i in 0..4 {
        let (a, b) = (v[i], v[(i + 1) % 4]);
        let theta = a.dot(b).clamp(-1.0, 1.0).acos();
        e += theta * a.cross(b).normalize().y;
    }
    0.5 * e.abs()
}

/// A one-sample Sobol stream past the pixel position.
fn stream_of(sampler: &Sampler, k: u32) -> glint::sampler::SampleStream<'_> {
    let mut s = sampler.stream((3, 7), k);
    s.next_2d();
    s
}

#[test]
fn rectangle_light_past_an_occluder_edge() {
    let sc = penumbra_scene();
    let world = World::build_world_space(&sc, BuildOptions::default());
    let light = &world.lights()[0];
    assert!(!is_delta(light));
    let sampler = Sampler::new(SamplerKind::Sobol, 1, 1);
    let n = 4096;
    let mut worst_fraction: f32 = 0.0;
    let mut worst_irradiance: f64 = 0.0;
    for xp in [-1.5f32, -0.9, -0.5, 0.0, 0.4, 0.7, 1.2, 1.5, 2.5] {
        let p = Vec3::new(xp, 0.0, 0.3);
        // The occluder's edge x = 0 at height 2, seen from p, cuts the light
        // at x = -xp: the light is visible for x > -xp.
        let cut = (-xp).clamp(-2.0, 2.0);
        let want = (2.0 - cut) / 4.0;

        // Fraction of shadow rays that get through.
        let mut st = stream_of(&sampler, 0);
        let mut open = 0;
        let mut c = Counters::default();
        for u in st.split_2d(n) {
            let inc = sample_light(light, p, u);
            let ray = Ray::new(p + Vec3::Y * 1e-4, inc.to_light);
            // To just short of the chosen point of the light.
            let end = inc.at.expect("an area light's sample is a point").p;
            let tmax = (end - ray.origin).length() * (1.0 - 1e-4);
            open += u32::from(!world.occluded(&ray, 0.0, tmax, &mut c));
        }
        let got = open as f32 / n as f32;
        let err = (got - want).abs() / want.max(0.05);
        worst_fraction = worst_fraction.max(err);
        assert!(err < 0.02, "x = {xp}: fraction {got}, closed form {want}");

        // The rendered floor: diffuse 1 times the irradiance of the visible
        // part of the light.
        let w = Whitted {
            shadows: true,
            shadow_samples: n,
            ..Whitted::default()
        };
        let ray = Ray::new(Vec3::new(xp, 1.0, 0.3), Vec3::NEG_Y);
        let mut st = stream_of(&sampler, 0);
        let (col, _) = w.li(
            &mut Trace {
                world: &world,
                stream: &mut st,
                counters: &mut c,
                observer: &mut NoObserver,
                packets: false,
            },
            &ray,
            0.0,
        );
        let want_e = if cut < 2.0 { lambert(p, cut, 2.0) } else { 0.0 };
        let err = (col.x as f64 - want_e).abs() / want_e.max(0.05);
        worst_irradiance = worst_irradiance.max(err);
        assert!(
            err < 0.02,
            "x = {xp}: irradiance {}, Lambert {want_e}",
            col.x
        );
    }
    println!(
        "penumbra: worst relative error {:.4}% (unoccluded fraction), {:.4}% (irradiance), {n} shadow rays",
        100.0 * worst_fraction,
        100.0 * worst_irradiance
    );
}

// ---------------------------------------------------------------------------
// Ambient occlusion

fn ao_at(world: &World, origin: Vec3, samples: u32, distance: f32) -> f32 {
    ao_along(world, Ray::new(origin, Vec3::NEG_Y), samples, distance).0
}

/// The AO integrator's grey value for one camera ray, and the counters.
fn ao_along(world: &World, ray: Ray, samples: u32, distance: f32) -> (f32, Counters) {
    let sampler = Sampler::new(SamplerKind::Sobol, 1, 5);
    let ao = AmbientOcclusion {
        settings: AoSettings { samples, distance },
    };
    let mut st = stream_of(&sampler, 0);
    let mut counters = Counters::default();
    let cx = &mut Trace {
        world,
        stream: &mut st,
        counters: &mut counters,
        observer: &mut NoObserver,
        packets: false,
    };
    let (c, hit) = ao.li(cx, &ray, 0.0);
    assert!(hit.is_some());
    (c.x, counters)
}

#[test]
fn ambient_occlusion_tests_the_side_the_ray_sees() {
    // A floor y = 0 (normal +y) with a ball resting above it, next to the
    // point x = 0.6 the rays hit. From above, the ball hides part of the
    // sky; from below (the floor's back face), nothing is there: the
    // hemisphere must turn to the side the ray came from.
    let s = scene(
        look_down(),
        vec![],
        vec![white()],
        Node::Group(vec![
            shape(plane(Vec3::Y, 0.0), 0),
            shape(sphere(Vec3::new(0.0, 0.5, 0.0), 0.5), 0),
        ]),
    );
    let w = World::build_world_space(&s, BuildOptions::default());
    let p = Vec3::new(0.6, 0.0, 0.0);
    let (above, _) = ao_along(&w, Ray::new(p + 3.0 * Vec3::Y, Vec3::NEG_Y), 256, 10.0);
    let (below, counters) = ao_along(&w, Ray::new(p - 3.0 * Vec3::Y, Vec3::Y), 256, 10.0);
    assert!(above < 0.9, "the ball hides part of the sky above: {above}");
    assert_eq!(below, 1.0, "nothing is below the floor");
    // One camera ray and one occlusion ray per sample.
    assert_eq!((counters.primary, counters.occlusion), (1, 256));
}

#[test]
fn ambient_occlusion_open_plane_and_wall() {
    let open = scene(
        look_down(),
        vec![],
        vec![white()],
        shape(plane(Vec3::Y, 0.0), 0),
    );
    let w = World::build_world_space(&open, BuildOptions::default());
    for d in [1.0, 100.0, f32::INFINITY] {
        assert_eq!(ao_at(&w, Vec3::new(0.3, 1.0, -2.0), 256, d), 1.0);
    }
    // Floor y = 0 and wall x = 0 (facing +x).
    let corner = scene(
        look_down(),
        vec![],
        vec![white()],
        Node::Group(vec![
            shape(plane(Vec3::Y, 0.0), 0),
            shape(plane(Vec3::X, 0.0), 0),
        ]),
    );
    let w = World::build_world_space(&corner, BuildOptions::default());
    let max_d = 2.0;
    let mut worst: f32 = 0.0;
    for d in [0.1f32, 0.3, 0.6, 1.0, 1.5, 2.5] {
        let a = (d / max_d).min(1.0);
        let want = 1.0 - (a.acos() - a * (1.0 - a * a).sqrt()) / PI;
        let got = ao_at(&w, Vec3::new(d, 0.5, 0.0), 4096, max_d);
        let err = (got - want).abs() / want;
        worst = worst.max(err);
        assert!(err < 0.02, "d = {d}: AO {got}, closed form {want}");
    }
    // With no distance limit the wall hides exactly half (cosine-weighted).
    let got = ao_at(&w, Vec3::new(0.7, 0.5, 0.0), 4096, f32::INFINITY);
    assert!((got - 0.5).abs() < 0.01, "{got}");
    println!(
        "ambient occlusion: worst relative error {:.4}%",
        100.0 * worst
    );
}

#[test]
fn whitted_scales_only_its_ambient_term_by_ambient_occlusion() {
    // Floor y = 0 and wall x = 0, no distance limit: the wall hides half the
    // cosine-weighted hemisphere of a floor point, so the ambient term
    // (ambient 0.4 x diffuse 1) halves. A directional light straight down
    // adds its Lambert term 0.5 x cos 0, which AO must not touch.
    let mut corner = scene(
        look_down(),
        vec![Light::Directional {
            direction: Vec3::NEG_Y,
            color: Vec3::splat(0.5),
        }],
        vec![white()],
        Node::Group(vec![
            shape(plane(Vec3::Y, 0.0), 0),
            shape(plane(Vec3::X, 0.0), 0),
        ]),
    );
    corner.background.ambient = Vec3::splat(0.4);
    let world = World::build_world_space(&corner, BuildOptions::default());
    let sampler = Sampler::new(SamplerKind::Sobol, 1, 5);
    let ray = Ray::new(Vec3::new(0.7, 0.5, 0.0), Vec3::NEG_Y);
    let shade = |ao: Option<AoSettings>| {
        let w = Whitted {
            ambient_occlusion: ao,
            ..Whitted::default()
        };
        let mut st = stream_of(&sampler, 0);
        let (col, _) = w.li(
            &mut Trace {
                world: &world,
                stream: &mut st,
                counters: &mut Counters::default(),
                observer: &mut NoObserver,
                packets: false,
            },
            &ray,
            0.0,
        );
        col.x
    };
    let plain = shade(None);
    assert!(
        (plain - 0.9).abs() < 1e-5,
        "ambient 0.4 + Lambert 0.5: {plain}"
    );
    let occluded = shade(Some(AoSettings {
        samples: 4096,
        distance: f32::INFINITY,
    }));
    let want = 0.4 * 0.5 + 0.5;
    assert!(
        (occluded - want).abs() < 0.004,
        "{occluded}, closed form {want}"
    );
}

// ---------------------------------------------------------------------------
// Rendering helpers

const BLACK_BG: Background = Background {
    color: Vec3::ZERO,
    ambient: Vec3::ONE,
};

/// Renders `scene` with `spp` samples of `kind` (seed `seed`) at `size`.
fn render_with(
    sc: &Scene,
    integrator: &impl Integrator,
    size: u32,
    kind: SamplerKind,
    spp: u32,
    seed: u64,
) -> Vec<Vec3> {
    let world = World::build(sc, BuildOptions::default());
    let cam = CameraModel::new(world.camera()).with_lens(sc.effects.lens);
    let mut s = Settings::one_ray((size, size), PixelOffset::CENTER);
    s.sampler = Sampler::new(kind, spp, seed);
    render_image(&world, &cam, integrator, &s, Control::default())
        .frame
        .color
}

fn rmse(a: &[Vec3], b: &[Vec3]) -> f64 {
    let s: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).length_squared() as f64 / 3.0)
        .sum();
    (s / a.len() as f64).sqrt()
}

// ---------------------------------------------------------------------------
// Depth of field

const W: u32 = 64;
const FOCUS: f32 = 5.0;
const ANGLE: f32 = 30.0;

/// A tiny self-lit sphere at `p` seen by a camera at the origin looking
/// down -z, focused at [`FOCUS`], with lens radius `aperture`.
fn dot_scene(p: Vec3, radius: f32, aperture: f32) -> Scene {
    let mut sc = scene(
        Camera::Perspective {
            center: Vec3::ZERO.as_dvec3(),
            direction: Vec3::NEG_Z,
            up: Vec3::Y,
            angle_deg: ANGLE,
        },
        vec![],
        vec![white()],
        shape(sphere(p, radius), 0),
    );
    sc.background = BLACK_BG;
    sc.effects.lens = Lens {
        aperture,
        focus_distance: FOCUS,
        ..Lens::default()
    };
    sc
}

/// Intensity-weighted centroid (pixels, x right, y down) and RMS radius.
fn spot(img: &[Vec3]) -> (Vec2, f32) {
    let mut sum = 0.0f64;
    let mut c = glam::DVec2::ZERO;
    for (i, p) in img.iter().enumerate() {
        let w = p.x as f64;
        c += w * glam::DVec2::new((i as u32 % W) as f64 + 0.5, (i as u32 / W) as f64 + 0.5);
        sum += w;
    }
    let c = c / sum;
    let mut m2 = 0.0;
    for (i, p) in img.iter().enumerate() {
        let q = glam::DVec2::new((i as u32 % W) as f64 + 0.5, (i as u32 / W) as f64 + 0.5);
        m2 += p.x as f64 * (q - c).length_squared();
    }
    (c.as_vec2(), (m2 / sum).sqrt() as f32)
}

/// Where the pinhole projects `p` (pixels, y down).
fn project(p: Vec3) -> Vec2 {
    let span = 2.0 * (ANGLE.to_radians() / 2.0).tan();
    let z = -p.z;
    Vec2::new(
        (0.5 + p.x / z / span) * W as f32,
        (0.5 - p.y / z / span) * W as f32,
    )
}

#[test]
fn thin_lens_focus_and_blur() {
    let w = Whitted::default();
    // On the focus plane: sharp at any aperture.
    let p = Vec3::new(0.4, 0.25, -FOCUS);
    for aperture in [0.0, 0.1, 0.3] {
        let img = render_with(
            &dot_scene(p, 0.01, aperture),
            &w,
            W,
            SamplerKind::Sobol,
            256,
            0,
        );
        let (c, r) = spot(&img);
        let want = project(p);
        println!(
            "in focus, aperture {aperture}: centroid {c}, expected {want}, rms radius {r:.3} px"
        );
        assert!(
            (c - want).length() < 1.0,
            "aperture {aperture}: {c} vs {want}"
        );
        assert!(r < 1.0, "aperture {aperture}: rms radius {r}");
    }
    // Off the plane (depth 3): a disk of radius a·(f − z)/z on the focus
    // plane, i.e. a·(f − z)/(z·f·span) of the image width. The dot covers
    // about 0.13 of a pixel, so at 256 samples the whole blurred spot
    // holds only some 30 sample hits and its measured radius varies by
    // about 5% from one seed to the next; 1024 samples halve that, so the
    // 10% bound below is not a coin toss on the seed.
    let q = Vec3::new(0.1, -0.1, -3.0);
    let span = 2.0 * (ANGLE.to_radians() / 2.0).tan();
    let (_, r0) = spot(&render_with(
        &dot_scene(q, 0.005, 0.0),
        &w,
        W,
        SamplerKind::Sobol,
        1024,
        0,
    ));
    let mut radii = Vec::new();
    for aperture in [0.15f32, 0.3] {
        let img = render_with(
            &dot_scene(q, 0.005, aperture),
            &w,
            W,
            SamplerKind::Sobol,
            1024,
            0,
        );
        let (c, r) = spot(&img);
        // Uniform disk of radius R: mean squared radius R²/2.
        let measured = (2.0 * (r * r - r0 * r0)).max(0.0).sqrt();
        let want = aperture * (FOCUS - 3.0) / (3.0 * FOCUS * span) * W as f32;
        println!(
            "off focus, aperture {aperture}: blur radius {measured:.3} px, thin lens {want:.3} px, centroid {c}"
        );
        assert!((c - project(q)).length() < 0.5);
        assert!((measured - want).abs() < 0.1 * want, "{measured} vs {want}");
        radii.push(measured);
    }
    let ratio = radii[1] / radii[0];
    assert!(
        (ratio - 2.0).abs() < 0.1,
        "blur grows as the aperture: ratio {ratio}"
    );
}

// ---------------------------------------------------------------------------
// Motion blur

fn slide(from: Vec3, to: Vec3) -> Arc<Motion> {
    Arc::new(
        Motion::new(vec![
            Keyframe {
                translation: from,
                ..Keyframe::identity(0.0)
            },
            Keyframe {
                translation: to,
                ..Keyframe::identity(1.0)
            },
        ])
        .unwrap(),
    )
}

fn ball_scene(root: Node, shutter: [f32; 2]) -> Scene {
    let mut sc = scene(
        Camera::Perspective {
            center: Vec3::new(0.0, 0.0, 6.0).as_dvec3(),
            direction: Vec3::NEG_Z,
            up: Vec3::Y,
            angle_deg: 40.0,
        },
        vec![Light::Directional {
            direction: Vec3::new(-0.3, -1.0, -0.6),
            color: Vec3::splat(0.8),
        }],
        vec![
            white(),
            Material::Phong(Phong {
                diffuse: Vec3::new(0.9, 0.3, 0.2),
                ..Phong::default()
            }),
        ],
        root,
    );
    sc.background = Background {
        color: Vec3::new(0.1, 0.1, 0.2),
        ambient: Vec3::splat(0.2),
    };
    sc.effects.lens.shutter = shutter;
    sc
}

fn moving_ball() -> Node {
    Node::Group(vec![
        shape(plane(Vec3::Z, -1.5), 0),
        Node::Moving {
            motion: slide(Vec3::new(-1.2, 0.0, 0.0), Vec3::new(1.2, 0.3, 0.0)),
            child: Box::new(shape(sphere(Vec3::ZERO, 0.6), 1)),
        },
    ])
}

#[test]
fn moving_sphere_is_the_mean_of_static_ones() {
    let w = Whitted {
        shadows: true,
        ..Whitted::default()
    };
    let size = 48;
    let spp = 256;
    let blurred = render_with(
        &ball_scene(moving_ball(), [0.0, 1.0]),
        &w,
        size,
        SamplerKind::Sobol,
        spp,
        0,
    );
    let again = render_with(
        &ball_scene(moving_ball(), [0.0, 1.0]),
        &w,
        size,
        SamplerKind::Sobol,
        spp,
        9,
    );
    // Static renders at 32 instants spread over the shutter.
    let k = 32;
    let mut mean = vec![Vec3::ZERO; (size * size) as usize];
    for i in 0..k {
        let t = (i as f32 + 0.5) / k as f32;
        let m = slide(Vec3::new(-1.2, 0.0, 0.0), Vec3::new(1.2, 0.3, 0.0)).matrix(t);
        let root = Node::Group(vec![
            shape(plane(Vec3::Z, -1.5), 0),
            Node::Transform {
                matrix: m.as_dmat4(),
                child: Box::new(shape(sphere(Vec3::ZERO, 0.6), 1)),
            },
        ]);
        let img = render_with(
            &ball_scene(root, [0.0, 0.0]),
            &w,
            size,
            SamplerKind::Sobol,
            spp / 8,
            i as u64,
        );
        for (a, b) in mean.iter_mut().zip(img) {
            *a += b / k as f32;
        }
    }
    let halfway = {
        let root = Node::Group(vec![
            shape(plane(Vec3::Z, -1.5), 0),
            shape(sphere(Vec3::new(0.0, 0.15, 0.0), 0.6), 1),
        ]);
        render_with(
            &ball_scene(root, [0.0, 0.0]),
            &w,
            size,
            SamplerKind::Sobol,
            spp,
            0,
        )
    };
    let noise = rmse(&blurred, &again);
    let to_mean = rmse(&blurred, &mean);
    let to_static = rmse(&blurred, &halfway);
    println!(
        "motion: RMSE to the mean of {k} static renders {to_mean:.4}, between two seeds {noise:.4}, to the static halfway render {to_static:.4}"
    );
    assert!(to_mean < 2.0 * noise + 0.005, "{to_mean} vs noise {noise}");
    assert!(to_static > 10.0 * to_mean);
}

// ---------------------------------------------------------------------------
// Noise against samples

/// Least-squares slope of log RMSE against log N.
fn slope(ns: &[u32], errs: &[f64]) -> f64 {
    let xs: Vec<f64> = ns.iter().map(|&n| (n as f64).ln()).collect();
    let ys: Vec<f64> = errs.iter().map(|e| e.ln()).collect();
    let mx = xs.iter().sum::<f64>() / xs.len() as f64;
    let my = ys.iter().sum::<f64>() / ys.len() as f64;
    let num: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let den: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    num / den
}

/// RMSE against a 4096-sample Sobol reference at N = 4, 16, 64 camera
/// samples for the random and the Sobol sampler; checks the slopes. (The
/// reference is glint's own: a biased estimator converges to its own bias.
/// The closed-form tests above, and `convergence_to` with a closed form,
/// catch bias.)
fn convergence(name: &str, sc: &Scene, integrator: &impl Integrator, size: u32) {
    let reference = render_with(sc, integrator, size, SamplerKind::Sobol, 4096, 1234);
    convergence_to(name, sc, integrator, size, &reference);
}

/// RMSE against `truth` at N = 4, 16, 64 camera samples for the random and
/// the Sobol sampler; checks the slopes (an estimator converging to
/// anything but `truth` stalls at its bias and fails them).
fn convergence_to(
    name: &str,
    sc: &Scene,
    integrator: &impl Integrator,
    size: u32,
    reference: &[Vec3],
) {
    let ns = [4u32, 16, 64];
    let mut report = format!("{name}:");
    let mut at_64 = Vec::new();
    for kind in [SamplerKind::Random, SamplerKind::Sobol] {
        let errs: Vec<f64> = ns
            .iter()
            .map(|&n| rmse(&render_with(sc, integrator, size, kind, n, 7), reference))
            .collect();
        let s = slope(&ns, &errs);
        report += &format!(
            "  {kind}: RMSE {:.4} {:.4} {:.4}, slope {s:.2};",
            errs[0], errs[1], errs[2]
        );
        match kind {
            SamplerKind::Random => assert!(
                (-0.75..=-0.35).contains(&s),
                "{name}: random slope {s} ({errs:?})"
            ),
            _ => assert!(s < -0.35, "{name}: sobol slope {s} ({errs:?})"),
        }
        at_64.push(errs[2]);
    }
    println!("{report}");
    assert!(
        at_64[1] < at_64[0],
        "{name}: sobol {} vs random {}",
        at_64[1],
        at_64[0]
    );
}

/// The mean over a `k`×`k` grid of points of pixel (`i`, `j` from the top)
/// of `f` at the point where that camera ray meets the floor `y = 0` (with
/// the ray's direction); the pixel value of a box filter of radius ½ when
/// `f` is the radiance leaving the floor there. The camera's own mapping
/// from pixels to rays is glint's (tested in `render::camera`).
fn floor_pixels(sc: &Scene, size: u32, k: u32, f: impl Fn(Vec3, Vec3) -> f64 + Sync) -> Vec<Vec3> {
    let cam = CameraModel::new(&sc.camera);
    (0..size * size)
        .map(|idx| {
            let (i, y) = (idx % size, idx / size);
            let mut sum = 0.0;
            for a in 0..k {
                for b in 0..k {
                    let o = Vec2::new((a as f32 + 0.5) / k as f32, (b as f32 + 0.5) / k as f32);
                    let ray = cam.ray(glint::render::screen_point(i, size - 1 - y, o, size, size));
                    let (o, d) = (ray.origin.as_dvec3(), ray.dir.as_dvec3());
                    assert!(d.y < 0.0, "pixel ({i}, {y}) misses the floor");
                    let p = o + d * (-o.y / d.y);
                    sum += f(p.as_vec3(), d.normalize().as_vec3());
                }
            }
            Vec3::splat((sum / (k * k) as f64) as f32)
        })
        .collect()
}

/// Soft shadows against their closed form: the white floor under the
/// rectangle light, half of it hidden by the occluder's edge, seen from
/// below the occluder. Each pixel's truth is the mean over its area of
/// Lambert's irradiance of the part of the light the floor point sees
/// (`lambert`, independent of glint's light sampling); the renders' RMSE
/// against it falls as `N^-1/2` (faster with Sobol) and the fine render
/// matches it. An area-light estimator without the cosine in its density
/// converges to another image and fails both.
#[test]
fn soft_shadows_converge_to_the_closed_form() {
    let mut sc = penumbra_scene();
    sc.camera = Camera::Perspective {
        center: Vec3::new(0.0, 1.5, 0.0).as_dvec3(),
        direction: Vec3::NEG_Y,
        up: Vec3::Z,
        angle_deg: 120.0,
    };
    let w = Whitted {
        shadows: true,
        ..Whitted::default()
    };
    let size = 24;
    let truth = floor_pixels(&sc, size, 8, |p, _| {
        // The occluder's edge x = 0 at half the light's height: the floor
        // point sees the light where x > -p.x.
        let cut = (-p.x).clamp(-2.0, 2.0);
        if cut < 2.0 {
            lambert(p, cut, 2.0)
        } else {
            0.0
        }
    });
    convergence_to("soft shadows, closed form", &sc, &w, size, &truth);
    let fine = render_with(&sc, &w, size, SamplerKind::Sobol, 1024, 3);
    let err = rmse(&fine, &truth);
    let mean = truth.iter().map(|c| c.x as f64).sum::<f64>() / truth.len() as f64;
    println!("soft shadows at 1024 spp: RMSE {err:.5} against a mean of {mean:.3}");
    assert!(err < 0.01 * mean, "RMSE {err} at 1024 spp (mean {mean})");
}

/// Glossy reflection against an independent reference: a glossy floor
/// (reflective 0.8, glossiness 0.3, no diffuse) under a bright ceiling
/// (ambient-lit white, radiance 1) that covers only `z < Z_BRIGHT`, seen
/// obliquely. A floor point's value is 0.8 × the probability that a
/// direction of the `cos^e` lobe around its mirror direction (folded
/// across the floor where it points below it, as `material::glossy`
/// documents) reaches the bright part; the reference integrates that
/// density by a midpoint rule over the lobe's angles, with no sampling.
/// The renders' RMSE against it falls as `N^-1/2` and the fine render
/// matches it. A lobe around the normal instead of the mirror direction
/// moves the bright edge and fails both.
#[test]
fn glossy_reflection_converges_to_the_lobe_integral() {
    const H: f32 = 1.5;
    const Z_BRIGHT: f32 = -4.5;
    let glossy = Material::Phong(Phong {
        diffuse: Vec3::ZERO,
        reflective: Vec3::splat(0.8),
        glossiness: 0.3,
        ..Phong::default()
    });
    let (a, b, c, d) = (
        Vec3::new(-1000.0, H, -1000.0),
        Vec3::new(1000.0, H, -1000.0),
        Vec3::new(1000.0, H, Z_BRIGHT),
        Vec3::new(-1000.0, H, Z_BRIGHT),
    );
    let mut sc = scene(
        Camera::Perspective {
            center: Vec3::new(0.0, 1.0, 3.0).as_dvec3(),
            direction: Vec3::new(0.0, -1.0, -3.0),
            up: Vec3::Y,
            angle_deg: 30.0,
        },
        vec![],
        vec![glossy, white()],
        Node::Group(vec![
            shape(plane(Vec3::Y, 0.0), 0),
            shape(
                ShapeDesc::Triangle([a.as_dvec3(), b.as_dvec3(), c.as_dvec3()]),
                1,
            ),
            shape(
                ShapeDesc::Triangle([a.as_dvec3(), c.as_dvec3(), d.as_dvec3()]),
                1,
            ),
        ]),
    );
    sc.background.ambient = Vec3::ONE;
    let w = Whitted {
        bounces: 1,
        ..Whitted::default()
    };
    let e = glint::material::glossy::lobe_exponent(0.3) as f64;
    // Midpoint rule over the lobe: α from its axis, φ around it.
    let (na, nphi) = (96, 96);
    let truth = floor_pixels(&sc, 24, 3, |p, dir| {
        let m = Vec3::new(dir.x, -dir.y, dir.z).as_dvec3();
        let (t1, t2) = m.any_orthonormal_pair();
        let mut bright = 0.0;
        let mut total = 0.0;
        for ia in 0..na {
            let al = (ia as f64 + 0.5) / na as f64 * std::f64::consts::FRAC_PI_2;
            let wgt = al.cos().powf(e) * al.sin();
            for ip in 0..nphi {
                let ph = (ip as f64 + 0.5) / nphi as f64 * std::f64::consts::TAU;
                let mut v = (t1 * ph.cos() + t2 * ph.sin()) * al.sin() + m * al.cos();
                if v.y < 0.0 {
                    v.y = -v.y;
                }
                total += wgt;
                if v.y > 1e-9 {
                    let z = p.z as f64 + v.z * (H - p.y) as f64 / v.y;
                    if z < Z_BRIGHT as f64 {
                        bright += wgt;
                    }
                }
            }
        }
        0.8 * bright / total
    });
    convergence_to("glossy, lobe integral", &sc, &w, 24, &truth);
    let fine = render_with(&sc, &w, 24, SamplerKind::Sobol, 1024, 3);
    let err = rmse(&fine, &truth);
    let mean = truth.iter().map(|c| c.x as f64).sum::<f64>() / truth.len() as f64;
    println!("glossy at 1024 spp: RMSE {err:.5} against a mean of {mean:.3}");
    assert!(err < 0.01, "RMSE {err} at 1024 spp (mean {mean})");
}

#[test]
fn noise_falls_with_samples_motion_and_lens() {
    let w = Whitted::default();
    convergence(
        "motion blur",
        &ball_scene(moving_ball(), [0.0, 1.0]),
        &w,
        24,
    );
    let mut sc = ball_scene(
        Node::Group(vec![
            shape(plane(Vec3::Z, -1.5), 0),
            shape(sphere(Vec3::new(-0.8, 0.0, 1.5), 0.5), 1),
            shape(sphere(Vec3::new(0.8, 0.0, -0.5), 0.5), 1),
        ]),
        [0.0, 0.0],
    );
    sc.effects.lens.aperture = 0.25;
    sc.effects.lens.focus_distance = 6.0;
    convergence("depth of field", &sc, &w, 24);
}

#[test]
fn noise_falls_with_samples_ambient_occlusion() {
    let sc = ball_scene(
        Node::Group(vec![
            shape(plane(Vec3::Y, -0.6), 0),
            shape(sphere(Vec3::new(-0.5, 0.0, 0.0), 0.6), 1),
            shape(sphere(Vec3::new(0.7, -0.2, 0.4), 0.4), 1),
        ]),
        [0.0, 0.0],
    );
    let ao = AmbientOcclusion {
        settings: AoSettings {
            samples: 1,
            distance: 2.0,
        },
    };
    convergence("ambient occlusion", &sc, &ao, 24);
}

/// Ambient occlusion between a floor and a ceiling at height `h` with AO
/// distance `d > h`: a cosine-weighted ray at angle θ meets the ceiling at
/// `h / cos θ`, within `d` when `cos θ > h/d`, which has probability
/// `1 − (h/d)²`; so the open fraction is `(h/d)²` at every floor point. The
/// renders converge to that closed form (not to their own high-spp render):
/// AO ignoring its distance (0 everywhere) or any other bias stalls.
#[test]
fn ambient_occlusion_converges_to_its_closed_form() {
    let (h, d) = (1.0f32, 2.0f32);
    let sc = scene(
        Camera::Perspective {
            center: Vec3::new(0.0, 0.9, 0.0).as_dvec3(),
            direction: Vec3::NEG_Y,
            up: Vec3::Z,
            angle_deg: 60.0,
        },
        vec![],
        vec![white()],
        Node::Group(vec![
            shape(plane(Vec3::Y, 0.0), 0),
            shape(plane(Vec3::Y, h), 0),
        ]),
    );
    let ao = AmbientOcclusion {
        settings: AoSettings {
            samples: 1,
            distance: d,
        },
    };
    let size = 16;
    let truth = vec![Vec3::splat((h / d) * (h / d)); (size * size) as usize];
    convergence_to("ambient occlusion, closed form", &sc, &ao, size, &truth);
    let fine = render_with(&sc, &ao, size, SamplerKind::Sobol, 1024, 3);
    let mean = fine.iter().map(|c| c.x as f64).sum::<f64>() / fine.len() as f64;
    assert!((mean - 0.25).abs() < 0.005, "mean open fraction {mean}");
}

/// Thin lens: the in-focus surface is the plane `z = −focus_distance`, not
/// the sphere of that radius. A dot on the plane 18.7° off axis (5.6% farther
/// than the focus distance) stays sharp at a wide aperture; a dot on the
/// sphere of radius `FOCUS` in the same direction is blurred (thin lens:
/// a disk of 2.7 px radius, RMS 1.9 px).
#[test]
fn thin_lens_focuses_on_a_plane_not_a_sphere() {
    let w = Whitted::default();
    let on_plane = Vec3::new(1.2, 1.2, -FOCUS);
    let on_sphere = on_plane.normalize() * FOCUS;
    let aperture = 2.0;
    let img = render_with(
        &dot_scene(on_plane, 0.01, aperture),
        &w,
        W,
        SamplerKind::Sobol,
        256,
        0,
    );
    let (c, r) = spot(&img);
    println!("on the focus plane, off axis: centroid {c}, rms radius {r:.3} px");
    assert!((c - project(on_plane)).length() < 1.0, "{c}");
    assert!(
        r < 1.0,
        "a dot on the focus plane is blurred: rms radius {r}"
    );
    let (_, r) = spot(&render_with(
        &dot_scene(on_sphere, 0.01, aperture),
        &w,
        W,
        SamplerKind::Sobol,
        256,
        0,
    ));
    println!("on the sphere of the focus distance: rms radius {r:.3} px");
    assert!(
        r > 1.5,
        "a dot off the focus plane is sharp: rms radius {r}"
    );
}

/// Splitting: N shadow (AO) rays per camera sample at one camera sample per
/// pixel also converges, and Sobol splits beat random ones.
#[test]
fn split_rays_converge_too() {
    let sc = penumbra_scene();
    let world = World::build_world_space(&sc, BuildOptions::default());
    let points: Vec<Vec3> = (0..64)
        .map(|i| Vec3::new(-2.5 + 5.0 * (i as f32 + 0.5) / 64.0, 1.0, 0.2))
        .collect();
    let shade = |kind: SamplerKind, n: u32, seed: u64| -> Vec<Vec3> {
        let sampler = Sampler::new(kind, 1, seed);
        let w = Whitted {
            shadows: true,
            shadow_samples: n,
            ..Whitted::default()
        };
        points
            .iter()
            .enumerate()
            .map(|(i, &o)| {
                let mut st = sampler.stream((i as u32, 0), 0);
                st.next_2d();
                let cx = &mut Trace {
                    world: &world,
                    stream: &mut st,
                    counters: &mut Counters::default(),
                    observer: &mut NoObserver,
                    packets: false,
                };
                w.li(cx, &Ray::new(o, Vec3::NEG_Y), 0.0).0
            })
            .collect()
    };
    let reference = shade(SamplerKind::Sobol, 16384, 99);
    let ns = [4u32, 16, 64, 256];
    let mut finals = Vec::new();
    for kind in [SamplerKind::Random, SamplerKind::Sobol] {
        // Averaged over seeds: one row of 64 points is a small sample.
        let errs: Vec<f64> = ns
            .iter()
            .map(|&n| {
                let mean_square = (0..8)
                    .map(|seed| rmse(&shade(kind, n, seed), &reference).powi(2))
                    .sum::<f64>()
                    / 8.0;
                mean_square.sqrt()
            })
            .collect();
        let s = slope(&ns, &errs);
        println!("split shadow rays, {kind}: RMSE {errs:.5?}, slope {s:.2}");
        assert!(s < -0.35, "{kind}: slope {s}");
        finals.push(errs[3]);
    }
    assert!(finals[1] < finals[0]);
}

// ---------------------------------------------------------------------------
// Ray counts: the lecture's cost formula

const COUNT_SCENE: &str = "PerspectiveCamera { center 0 0 5 direction 0 0 -1 up 0 1 0 angle 20\n\
    aperture 0.05 focusDistance 5 shutter 0 1 }\n\
    Lights { numLights 1 AreaLight { quad { corner -1 -1 3 edge1 2 0 0 edge2 0 2 0 } color 1 1 1 power 30 } }\n\
    Samples { shadow 3 glossy 1 time 2 lens 5 }\n\
    AmbientOcclusion { samples 7 distance 1 }\n\
    Background { ambientLight 0.2 0.2 0.2 }\n\
    Group { numObjects 1 Plane { normal 0 0 1 offset 0 } }\n";

fn count_scene_path() -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("glint-distribution-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("counts.txt");
    std::fs::write(&path, COUNT_SCENE).unwrap();
    path
}

/// Camera rays = pixels × spp × time × lens; shadow rays = camera rays ×
/// shadow samples (one area light, every hit lit); AO rays = camera rays ×
/// AO samples. Command-line counts override the scene's.
#[test]
fn ray_counts_follow_the_cost_formula() {
    use glint::job::{Job, SampleOverrides};
    let path = count_scene_path();
    let (w, h) = (8u32, 6u32);
    let mut job = Job::new(path.clone(), w, h);
    job.shading.shadows = true;
    job.sampling.spp = 4;
    job.sampling.sampler = Some(SamplerKind::Sobol);
    let c = job.run().unwrap().counters;
    let camera = u64::from(w * h) * 4 * 2 * 5;
    assert_eq!(c.primary, camera);
    assert_eq!(c.shadow, camera * 3);
    assert_eq!(c.occlusion, camera * 7);
    assert_eq!(c.rays_total(), camera * (1 + 3 + 7));

    job.sampling.effects = SampleOverrides {
        shadow: Some(2),
        time: Some(3),
        lens: Some(1),
        ao: Some(4),
        ..SampleOverrides::default()
    };
    let c = job.run().unwrap().counters;
    let camera = u64::from(w * h) * 4 * 3;
    assert_eq!(c.primary, camera);
    assert_eq!(c.shadow, camera * 2);
    assert_eq!(c.occlusion, camera * 4);

    // The AO image: one AO probe set per camera ray, no shadow rays.
    job.integrator = glint::integrator::IntegratorKind::Ao;
    let r = job.run().unwrap();
    assert_eq!(r.counters.shadow, 0);
    assert_eq!(r.counters.occlusion, camera * 4);
    assert!(
        r.frame.color.iter().all(|c| c.x > 0.99),
        "an open plane is unoccluded"
    );
}

/// `glint render` takes the flags and `--stats` lists every kind of ray.
#[test]
fn cli_flags_and_stats() {
    let path = count_scene_path();
    let out = path.with_file_name("counts.png");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
        .args([
            "render",
            path.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .args([
            "--size",
            "4",
            "4",
            "--shadows",
            "--stats",
            "--quiet",
            "--spp",
            "2",
        ])
        .args([
            "--shadow-samples",
            "5",
            "--glossy-samples",
            "2",
            "--time-samples",
            "3",
        ])
        .args(["--lens-samples", "1", "--ao-samples", "2"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let value = |key: &str| -> u64 {
        let line = text
            .lines()
            .find(|l| l.starts_with(key))
            .unwrap_or_else(|| panic!("{key} in {text}"));
        line[key.len()..].trim().parse().unwrap()
    };
    let camera = 16 * 2 * 3;
    assert_eq!(value("primary rays"), camera);
    assert_eq!(value("shadow rays"), camera * 5);
    assert_eq!(value("occlusion rays"), camera * 2);
    assert_eq!(value("  of which glossy"), 0);
    let bad = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
        .args([
            "render",
            path.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .args(["--shadow-samples", "0"])
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(2));
}
