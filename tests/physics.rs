//! Physics of the Whitted ray tree against closed forms (issue 18).
//!
//! Every expected value here comes from a formula written out in the test
//! (Snell's law in angles, the critical angle, products of coefficients,
//! `1/(a + b·d + c·d²)`, the half vector), never from glint's own optics or
//! shading functions; what is measured is what the Whitted integrator does to
//! a real world's eye ray (`common::eye_ray`), watched through a `RayRecorder`. Worlds are built in world space so
//! the numbers in the scenes are the numbers the formulas use. Area lights
//! are checked through `light::sample_light`, the sampling the ray tree calls.

use glint::integrator::{RayKind, RayRecorder, RecordedRay, Whitted};
use glint::math::{Ray, Vec3};
use glint::scene::{Background, Camera, Light, Material, Node, Phong, Scene, ShapeDesc};
use glint::stats::Counters;
use glint::world::{BuildOptions, World};

/// A scene of `root` with these materials and lights (the camera is unused:
/// rays are traced by hand).
fn scene(root: Node, materials: Vec<Phong>, lights: Vec<Light>, bg: Background) -> Scene {
    Scene {
        camera: Camera::Orthographic {
            center: Vec3::new(0.0, 0.0, 10.0).as_dvec3(),
            direction: Vec3::NEG_Z,
            up: Vec3::Y,
            size: 2.0,
        },
        lights,
        background: bg,
        materials: materials.into_iter().map(Material::Phong).collect(),
        root,
        effects: Default::default(),
    }
}

fn plane(normal: Vec3, offset: f32, material: usize) -> Node {
    Node::Shape {
        shape: ShapeDesc::Plane {
            normal,
            offset: f64::from(offset),
        },
        material: Some(material),
    }
}

fn dark() -> Background {
    Background {
        color: Vec3::ZERO,
        ambient: Vec3::ZERO,
    }
}

/// Clear glass of index `ior`: no surface colour, all light transmitted.
fn glass(ior: f32) -> Phong {
    Phong {
        diffuse: Vec3::ZERO,
        transparent: Vec3::ONE,
        ior,
        ..Phong::default()
    }
}

/// Traces `ray` from the eye (depth 0, weight 1), recording every ray.
fn trace(world: &World, w: &Whitted, ray: Ray) -> (Vec3, Vec<RecordedRay>) {
    let mut rec = RayRecorder::default();
    let (c, _) = crate::common::eye_ray(w, world, &ray, 0.0, &mut Counters::default(), &mut rec);
    (c, rec.rays)
}

/// Refraction needs the inside of the glass lit: leaving hits are back faces.
fn glass_tracer() -> Whitted {
    Whitted {
        bounces: 6,
        shade_back: true,
        ..Whitted::default()
    }
}

/// A ray through a slab of glass of thickness `h` and index `n` comes out
/// parallel to itself, shifted sideways by `h·sin(θi − θt)/cos θt` with
/// `sin θt = sin θi / n`; inside, it travels at θt (exit `h·tan θt` further
/// along). Entering and leaving with swapped indices gives a different shift
/// (or total internal reflection), so this pins down both directions.
#[test]
fn glass_slab_shifts_a_ray_sideways_by_the_closed_form() {
    let h = 0.7f32;
    for &n in &[1.33f32, 1.5, 2.4] {
        // Top face y = 0 facing up, bottom face y = -h facing down.
        let s = scene(
            Node::Group(vec![plane(Vec3::Y, 0.0, 0), plane(Vec3::NEG_Y, h, 0)]),
            vec![glass(n)],
            vec![],
            dark(),
        );
        let world = World::build_world_space(&s, BuildOptions::default());
        for deg in [0.0f64, 10.0, 30.0, 50.0, 75.0] {
            let ti = deg.to_radians();
            let tt = (ti.sin() / n as f64).asin();
            let d = Vec3::new(ti.sin() as f32, -(ti.cos() as f32), 0.0);
            let entry = Vec3::new(0.2, 0.0, 0.3);
            let o = entry - 2.0 * d;
            let (_, rays) = trace(&world, &glass_tracer(), Ray::new(o, d));
            let out: Vec<&RecordedRay> = rays
                .iter()
                .filter(|r| r.kind == RayKind::Transmitted && r.depth == 2)
                .collect();
            assert_eq!(out.len(), 1, "n {n}, {deg}°: {rays:?}");
            let out = out[0];
            let exit = out.ray.origin;
            let dir = out.ray.dir.normalize();
            // Parallel to the incoming ray.
            assert!(
                (dir - d).length() < 1e-5,
                "n {n}, {deg}°: leaves along {dir}"
            );
            // Where it left the slab: h·tan θt past the entry point.
            let along = (h as f64 * tt.tan()) as f32;
            assert!(
                (exit - Vec3::new(entry.x + along, -h, entry.z)).length() < 1e-4,
                "n {n}, {deg}°: exit {exit}, expected x {}",
                entry.x + along
            );
            // The lateral shift: distance of the exit point from the line of
            // the incoming ray.
            let shift = (exit - o).cross(d).length() as f64;
            let expected = h as f64 * (ti - tt).sin() / tt.cos();
            assert!(
                (shift - expected).abs() < 1e-4,
                "n {n}, {deg}°: shift {shift}, closed form {expected}"
            );
        }
    }
}

/// From inside glass of index `n` towards air, light leaves only below the
/// critical angle `asin(1/n)`, bent to `asin(n·sin θi)`; beyond it nothing is
/// transmitted (total internal reflection).
#[test]
fn total_internal_reflection_beyond_the_critical_angle_only() {
    for &n in &[1.5f32, 2.0] {
        // The glass is below y = 0 (outward normal +y); rays come from below.
        let s = scene(plane(Vec3::Y, 0.0, 0), vec![glass(n)], vec![], dark());
        let world = World::build_world_space(&s, BuildOptions::default());
        let critical = (1.0 / n as f64).asin().to_degrees();
        let mut seen = (0, 0);
        for k in 0..=40 {
            let deg = critical - 20.0 + k as f64; // 20° either side, 1° apart
            if (deg - critical).abs() < 0.25 {
                continue; // the critical angle itself: too close to call in f32
            }
            let ti = deg.to_radians();
            let d = Vec3::new(ti.sin() as f32, ti.cos() as f32, 0.0);
            let (_, rays) = trace(&world, &glass_tracer(), Ray::new(-d, d));
            let out: Vec<&RecordedRay> = rays
                .iter()
                .filter(|r| r.kind == RayKind::Transmitted)
                .collect();
            if deg < critical {
                seen.0 += 1;
                assert_eq!(out.len(), 1, "n {n}, {deg:.2}° < {critical:.2}°: {rays:?}");
                let t = out[0].ray.dir.normalize();
                let sin_t = (n as f64 * ti.sin()) as f32;
                assert!(t.y > 0.0, "n {n}, {deg:.2}°: goes back in: {t}");
                assert!(
                    (t.x - sin_t).abs() < 1e-4,
                    "n {n}, {deg:.2}°: sin θt {} against n·sin θi {sin_t}",
                    t.x
                );
            } else {
                seen.1 += 1;
                assert!(out.is_empty(), "n {n}, {deg:.2}° > {critical:.2}°: {out:?}");
            }
        }
        assert!(seen.0 >= 15 && seen.1 >= 15, "{seen:?}");
    }
}

/// Each child ray's weight is its parent's times the max channel of the
/// coefficient that spawned it, and the colour is the sum of ambient, and
/// reflective and transparent colour times what each child sees.
#[test]
fn ray_tree_weights_and_colour_are_products_of_coefficients() {
    let r = Vec3::new(0.5, 0.3, 0.2);
    let t = Vec3::new(0.2, 0.4, 0.1);
    let kd = Vec3::new(0.3, 0.6, 0.9);
    let ambient = Vec3::new(0.1, 0.2, 0.3);
    let sky = Vec3::new(0.2, 0.5, 0.8);
    let m = Phong {
        diffuse: kd,
        reflective: r,
        transparent: t,
        ior: 1.0, // straight through: the transmitted ray sees the sky
        ..Phong::default()
    };
    let bg = Background {
        color: sky,
        ambient,
    };
    let d = Vec3::new(1.0, -1.0, 0.0).normalize();

    // One sheet: colour = ambient·kd + r·sky + t·sky.
    let one = scene(plane(Vec3::Y, 0.0, 0), vec![m], vec![], bg.clone());
    let world = World::build_world_space(&one, BuildOptions::default());
    let (c, rays) = trace(&world, &glass_tracer(), Ray::new(-d, d));
    let expected = ambient * kd + r * sky + t * sky;
    assert!((c - expected).length() < 1e-6, "{c} vs {expected}");
    let weight = |kind| {
        rays.iter()
            .find(|x| x.kind == kind && x.depth == 1)
            .unwrap()
            .weight
    };
    assert_eq!(weight(RayKind::Reflected), 0.5);
    assert_eq!(weight(RayKind::Transmitted), 0.4);
    // The mirror ray leaves at the angle it came in: d with its y negated.
    let mirrored = rays
        .iter()
        .find(|x| x.kind == RayKind::Reflected)
        .unwrap()
        .ray
        .dir
        .normalize();
    let expected_dir = Vec3::new(d.x, -d.y, d.z);
    assert!(
        (mirrored - expected_dir).length() < 1e-6,
        "reflected {mirrored}, expected {expected_dir}"
    );

    // Two sheets: every ray's weight is the product along its path, so the
    // depth-2 weights are the pairwise products of 0.5 and 0.4.
    let two = scene(
        Node::Group(vec![plane(Vec3::Y, 0.0, 0), plane(Vec3::Y, -1.0, 0)]),
        vec![m],
        vec![],
        bg,
    );
    let world = World::build_world_space(&two, BuildOptions::default());
    let w = Whitted {
        bounces: 2,
        ..glass_tracer()
    };
    let (_, rays) = trace(&world, &w, Ray::new(-d, d));
    let mut depth2: Vec<f32> = rays
        .iter()
        .filter(|x| x.depth == 2)
        .map(|x| x.weight)
        .collect();
    depth2.sort_by(f32::total_cmp);
    // The transmitted ray (0.4) reaches the lower sheet and splits into
    // 0.4·0.4 and 0.4·0.5; the reflected one (0.5) escapes to the sky.
    assert_eq!(depth2.len(), 2, "{rays:?}");
    assert!((depth2[0] - 0.16).abs() < 1e-6 && (depth2[1] - 0.2).abs() < 1e-6);
    // The cutoff prunes exactly the branches below it.
    let pruned = Whitted {
        weight_cutoff: 0.18,
        ..w
    };
    let (_, rays) = trace(&world, &pruned, Ray::new(-d, d));
    let depth2: Vec<f32> = rays
        .iter()
        .filter(|x| x.depth == 2)
        .map(|x| x.weight)
        .collect();
    assert_eq!(depth2.len(), 1, "{depth2:?}");
    assert!((depth2[0] - 0.2).abs() < 1e-6);
}

/// A matte floor `y = 0` seen at the origin, lit by a point light straight
/// above at height `h` with attenuation `k`; `extra` adds geometry.
fn floor_under_light(h: f32, k: Vec3, extra: Vec<Node>, shadows: bool) -> Vec3 {
    let mut kids = vec![plane(Vec3::Y, 0.0, 0)];
    kids.extend(extra);
    let s = scene(
        Node::Group(kids),
        vec![
            Phong {
                diffuse: Vec3::splat(0.8),
                ..Phong::default()
            },
            Phong::default(),
        ],
        vec![Light::Point {
            position: Vec3::new(0.0, h, 0.0).as_dvec3(),
            color: Vec3::ONE,
            attenuation: k,
        }],
        dark(),
    );
    let world = World::build_world_space(&s, BuildOptions::default());
    let w = Whitted {
        shadows,
        ..Whitted::default()
    };
    // From the side, under anything placed above the light.
    let o = Vec3::new(0.0, 0.1, 2.0);
    let (c, rays) = trace(&world, &w, Ray::new(o, -o));
    let hit = o + (-o) * rays[0].t_end;
    assert!(
        hit.length() < 1e-4,
        "the eye ray should hit the origin: {hit}"
    );
    c
}

/// A shadow ray towards a point light stops at the light: geometry beyond
/// it (here a ceiling above the light) casts no shadow, geometry between
/// does.
#[test]
fn geometry_beyond_a_point_light_casts_no_shadow() {
    let lit = 0.8; // kd · cos 0 · 1 / 1
    let ceiling = || plane(Vec3::NEG_Y, -3.0, 1); // y = 3, facing down
    for h in [0.5f32, 1.0, 2.9] {
        let c = floor_under_light(h, Vec3::X, vec![ceiling()], true);
        assert!((c.x - lit).abs() < 1e-5, "light at {h}, ceiling at 3: {c}");
    }
    // A shelf between floor and light does shadow it.
    let shelf = Node::Shape {
        shape: ShapeDesc::Triangle([
            Vec3::new(-1.0, 0.5, -1.0).as_dvec3(),
            Vec3::new(1.0, 0.5, -1.0).as_dvec3(),
            Vec3::new(0.0, 0.5, 1.0).as_dvec3(),
        ]),
        material: Some(1),
    };
    let c = floor_under_light(1.0, Vec3::X, vec![shelf, ceiling()], true);
    assert_eq!(c, Vec3::ZERO);
    // A light set into the ceiling itself: the shadow ray ends just short of
    // it, so the surface the light lies on does not block it.
    let c = floor_under_light(3.0, Vec3::X, vec![ceiling()], true);
    assert!((c.x - lit).abs() < 1e-5, "light on the ceiling: {c}");
}

/// The same for an area light: shadow rays end at the sampled point of the
/// light, so neither a ceiling the disk is set into nor one above it
/// shadows the floor, and the shaded colour equals the one without shadows.
#[test]
fn geometry_beyond_an_area_light_casts_no_shadow() {
    use glint::scene::AreaShape;
    let shade = |ceiling_y: Option<f32>, shadows: bool| {
        let mut kids = vec![plane(Vec3::Y, 0.0, 0)];
        kids.extend(ceiling_y.map(|y| plane(Vec3::NEG_Y, -y, 1)));
        let s = scene(
            Node::Group(kids),
            vec![
                Phong {
                    diffuse: Vec3::splat(0.8),
                    ..Phong::default()
                },
                Phong::default(),
            ],
            vec![Light::Area {
                shape: AreaShape::Disk {
                    center: Vec3::new(0.0, 1.0, 0.0).as_dvec3(),
                    normal: Vec3::NEG_Y,
                    radius: 0.5,
                },
                color: Vec3::ONE,
                power: 10.0,
            }],
            dark(),
        );
        let world = World::build_world_space(&s, BuildOptions::default());
        let w = Whitted {
            shadows,
            shadow_samples: 16,
            ..Whitted::default()
        };
        let o = Vec3::new(0.0, 0.1, 2.0);
        trace(&world, &w, Ray::new(o, -o)).0
    };
    let open = shade(None, false);
    assert!(open.x > 0.1, "the disk lights the floor: {open}");
    for y in [1.0, 2.0] {
        let c = shade(Some(y), true);
        assert!(
            (c - open).abs().max_element() < 1e-6,
            "ceiling at {y}: {c} vs {open}"
        );
    }
}

/// Point light falloff `1/(a + b·d + c·d²)` times Lambert's cosine, for a
/// point straight below the light and for points off to the side.
#[test]
fn point_light_attenuation_follows_the_closed_form() {
    for k in [
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.5, 0.25, 0.125),
        Vec3::new(2.0, 0.0, 0.3),
    ] {
        for h in [0.5f32, 1.0, 3.0, 7.5] {
            let c = floor_under_light(h, k, vec![], false);
            let d = h as f64;
            let expected = 0.8 / (k.x as f64 + k.y as f64 * d + k.z as f64 * d * d);
            let expected = expected.min(glint::limits::MAX_ATTENUATION_GAIN as f64);
            assert!(
                ((c.x as f64) - expected).abs() < 1e-5 * expected.max(1.0),
                "k {k}, h {h}: {} against {expected}",
                c.x
            );
        }
    }
    // Off to the side: distance √(x² + h²), cosine h / distance.
    let s = scene(
        plane(Vec3::Y, 0.0, 0),
        vec![Phong {
            diffuse: Vec3::ONE,
            ..Phong::default()
        }],
        vec![Light::Point {
            position: Vec3::new(0.0, 2.0, 0.0).as_dvec3(),
            color: Vec3::ONE,
            attenuation: Vec3::new(0.5, 0.25, 0.125),
        }],
        dark(),
    );
    let world = World::build_world_space(&s, BuildOptions::default());
    for x in [0.5f32, 1.0, 3.0] {
        let target = Vec3::new(x, 0.0, 0.0);
        let o = Vec3::new(x, 1.0, 1.0);
        let (c, _) = trace(&world, &Whitted::default(), Ray::new(o, target - o));
        let dist = (x as f64).hypot(2.0);
        let expected = (2.0 / dist) / (0.5 + 0.25 * dist + 0.125 * dist * dist);
        assert!(
            ((c.x as f64) - expected).abs() < 1e-5,
            "x {x}: {} against {expected}",
            c.x
        );
    }
}

/// On a unit sphere seen along `-z` (parallel rays: the eye direction is
/// `+z` everywhere) and lit from direction `l`, the highlight peaks where
/// the normal is the half vector `normalize(l + z)` and is `k_s` there.
#[test]
fn phong_highlight_sits_at_the_half_vector() {
    let shiny = Phong {
        diffuse: Vec3::ZERO,
        specular: Vec3::ONE,
        exponent: 400.0,
        ..Phong::default()
    };
    for to_light in [
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(-0.3, 0.8, 0.6),
        Vec3::new(0.5, -1.0, 0.4),
    ] {
        let l = to_light.normalize();
        let s = scene(
            Node::Shape {
                shape: ShapeDesc::Sphere {
                    center: Vec3::ZERO.as_dvec3(),
                    radius: 1.0,
                },
                material: Some(0),
            },
            vec![shiny],
            vec![Light::Directional {
                direction: -to_light,
                color: Vec3::ONE,
            }],
            dark(),
        );
        let world = World::build_world_space(&s, BuildOptions::default());
        let step = 0.01;
        let mut best = (f32::MIN, Vec3::ZERO);
        for i in -100..=100 {
            for j in -100..=100 {
                let o = Vec3::new(i as f32 * step, j as f32 * step, 5.0);
                let (c, rays) = trace(&world, &Whitted::default(), Ray::new(o, Vec3::NEG_Z));
                if rays[0].t_end.is_finite() && c.x > best.0 {
                    best = (c.x, o + Vec3::NEG_Z * rays[0].t_end);
                }
            }
        }
        let peak = (l + Vec3::Z).normalize();
        // The sampled maximum is within one grid step (in x and y) of the
        // peak; on the sphere that is a few steps at most.
        assert!(
            (best.1 - peak).length() < 3.0 * step,
            "light {l}: brightest at {}, half vector {peak}",
            best.1
        );
        assert!(
            best.0 > 0.97 && best.0 <= 1.0 + 1e-5,
            "peak value {}",
            best.0
        );
    }
}

/// Area lights through `glint::light`'s public sampling, against the closed
/// form for a disk: a disk of radius `R` and radiance `L` at height `h`
/// straight above a point facing it gives irradiance `π·L·R²/(h² + R²)`.
/// The radiance of a light of power `Φ` over a two-sided disk is
/// `Φ / (π · 2πR²)`. Point and directional lights are single-direction
/// (delta) lights, an area light is not.
#[test]
fn area_light_irradiance_matches_the_disk_closed_form() {
    use glint::light::{is_delta, sample_light};
    use glint::math::Vec2;
    use glint::scene::AreaShape;
    let (r, power) = (0.5f32, 10.0f32);
    let light = Light::Area {
        shape: AreaShape::Disk {
            center: Vec3::ZERO,
            normal: Vec3::NEG_Y,
            radius: r,
        },
        color: Vec3::ONE,
        power,
    };
    assert!(!is_delta(&light));
    assert!(is_delta(&Light::Point {
        position: Vec3::ZERO,
        color: Vec3::ONE,
        attenuation: Vec3::X,
    }));
    assert!(is_delta(&Light::Directional {
        direction: Vec3::NEG_Y,
        color: Vec3::ONE,
    }));
    let radiance =
        power as f64 / (std::f64::consts::PI * 2.0 * std::f64::consts::PI * (r * r) as f64);
    for h in [0.25f32, 1.0, 3.0] {
        let p = Vec3::new(0.0, -h, 0.0);
        // The mean over a fine grid of samples is the estimate of E.
        let k = 64;
        let mut sum = 0.0f64;
        for i in 0..k {
            for j in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                let inc = sample_light(&light, p, u);
                sum += (inc.color.x * inc.to_light.dot(Vec3::Y).max(0.0)) as f64;
            }
        }
        let e = sum / (k * k) as f64;
        let (h, r) = (h as f64, r as f64);
        let expected = std::f64::consts::PI * radiance * r * r / (h * h + r * r);
        assert!(
            (e - expected).abs() < 1e-2 * expected,
            "h {h}: irradiance {e}, closed form {expected}"
        );
    }
}
