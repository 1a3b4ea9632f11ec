//! Properties of the Whitted ray tree (the library's `Whitted`) on hand-built
//! and shared scenes: no self-intersection acne, the bounce and weight
//! limits, shadows, glossy spreads. `raytree_cli.rs` tests the `glint
//! raytree` command.

use crate::common;
use crate::common::Rng;
use glint::format::load_scene;
use glint::integrator::{NoObserver, RayKind, RayRecorder, Whitted};
use glint::math::{Ray, Vec2, Vec3};
use glint::render::{render, CameraModel, PixelOffset};
use glint::scene::{Background, Camera, Light, Material, Node, Phong, Scene, ShapeDesc};
use glint::stats::Counters;
use glint::world::{BuildOptions, World};

/// A tiny deterministic generator (xorshift), so failures reproduce.
/// From random eye-ray hits on glint's own scenes and the course's (meshes,
/// spheres, planes, under transforms), rays leaving the surface on either side
/// never re-hit the same primitive immediately (which is what shadow/reflection
/// acne is). The course's scenes are added when the data folder is present.
#[test]
fn secondary_rays_never_rehit_their_own_surface() {
    let mut rng = Rng::new(0x9e3779b97f4a7c15);
    let mut checked = 0;
    let mut paths = vec![
        common::own_scene("whitted.txt"),
        common::own_scene("mesh_knot_1k.txt"),
    ];
    if let Some(dir) =
        common::scenes("secondary_rays_never_rehit_their_own_surface (course scenes)")
    {
        paths.extend(
            [
                "scene4_14_faceted_gem.txt",
                "scene2_13_rotated_squashed_sphere.txt",
                "scene4_06_transparent_bars.txt",
                "scene6_07_bunny_mesh_40k.txt",
                "scene4_03_mirrored_floor.txt",
            ]
            .map(|n| dir.join(n)),
        );
    }
    for path in &paths {
        let name = path.display();
        let scene = load_scene(path).unwrap();
        let world = World::build(&scene, BuildOptions::default());
        let cam = CameraModel::new(world.camera());
        let mut c = Counters::default();
        for _ in 0..400 {
            let s = Vec2::new(rng.f(), rng.f());
            let Some(h) = world.intersect(&cam.ray(s), cam.tmin(), f32::INFINITY, &mut c) else {
                continue;
            };
            for _ in 0..8 {
                let d = rng.unit();
                let r = h.spawn_ray(d);
                if let Some(h2) = world.intersect(&r, 0.0, f32::INFINITY, &mut c) {
                    let flat = !matches!(
                        world.prims()[h.prim as usize].shape,
                        glint::shape::Shape::Sphere(_) | glint::shape::Shape::Transformed(_)
                    );
                    assert!(
                        !(h2.prim == h.prim && (flat || h2.t < 1e-3)),
                        "{name}: ray from {:?} re-hit its own primitive at t = {}",
                        h.point,
                        h2.t
                    );
                }
                checked += 1;
            }
        }
    }
    assert!(checked > 2000 * paths.len(), "only {checked} rays checked");
}

fn sphere(center: Vec3, radius: f32, material: usize) -> Node {
    Node::Shape {
        shape: ShapeDesc::Sphere {
            center: center.as_dvec3(),
            radius,
        },
        material: Some(material),
    }
}

fn floor_scene(glass: Phong) -> Scene {
    Scene {
        camera: Camera::Orthographic {
            center: Vec3::new(0.0, 5.0, 0.0).as_dvec3(),
            direction: Vec3::NEG_Y,
            up: Vec3::Z,
            size: 4.0,
        },
        lights: vec![Light::Directional {
            direction: Vec3::NEG_Y,
            color: Vec3::ONE,
        }],
        background: Background {
            color: Vec3::ZERO,
            ambient: Vec3::splat(0.1),
        },
        materials: vec![
            Material::Phong(Phong {
                diffuse: Vec3::splat(0.8),
                ..Phong::default()
            }),
            Material::Phong(glass),
        ],
        root: Node::Group(vec![
            Node::Shape {
                shape: ShapeDesc::Plane {
                    normal: Vec3::Y,
                    offset: 0.0,
                },
                material: Some(0),
            },
            sphere(Vec3::new(0.0, 2.0, 0.0), 0.5, 1),
        ]),
        effects: Default::default(),
    }
}

/// Colour of the floor straight below the sphere, seen from the side so the
/// eye ray does not pass through the sphere.
fn floor_below_sphere(scene: &Scene, w: Whitted) -> Vec3 {
    let world = World::build(scene, BuildOptions::default());
    let eye = world.ray_from_world(&Ray::new(
        Vec3::new(0.0, 0.1, 3.0),
        Vec3::new(0.0, -0.1, -3.0).normalize(),
    ));
    let (c, hit) = crate::common::eye_ray(
        &w,
        &world,
        &eye,
        0.0,
        &mut Counters::default(),
        &mut NoObserver,
    );
    assert!(
        world.point_to_world(hit.unwrap().point).length() < 1e-3,
        "the eye ray should hit the floor at the origin"
    );
    c
}

#[test]
fn opaque_and_transparent_shadows() {
    let glass = Phong {
        diffuse: Vec3::ZERO,
        transparent: Vec3::new(0.5, 0.25, 1.0),
        ior: 1.0,
        ..Phong::default()
    };
    let scene = floor_scene(glass);
    let lit = floor_below_sphere(&scene, Whitted::default());
    let opaque = floor_below_sphere(
        &scene,
        Whitted {
            shadows: true,
            ..Whitted::default()
        },
    );
    let filtered = floor_below_sphere(
        &scene,
        Whitted {
            shadows: true,
            transparent_shadows: true,
            ..Whitted::default()
        },
    );
    let ambient = Vec3::splat(0.1 * 0.8);
    assert!(
        (lit - (ambient + Vec3::splat(0.8))).length() < 1e-5,
        "{lit}"
    );
    // The course: any object between blocks the light, transparent or not.
    assert!((opaque - ambient).length() < 1e-5, "{opaque}");
    // Two surfaces of the sphere each filter by transparentColor.
    let through = Vec3::new(0.25, 0.0625, 1.0) * 0.8;
    assert!(
        (filtered - (ambient + through)).length() < 1e-4,
        "{filtered}"
    );
}

fn mirror_box() -> Scene {
    // Two facing mirrors: an eye ray between them bounces forever unless limited.
    let mirror = Phong {
        diffuse: Vec3::splat(0.1),
        reflective: Vec3::splat(0.5),
        ..Phong::default()
    };
    let mut scene = floor_scene(mirror);
    scene.root = Node::Group(vec![
        Node::Shape {
            shape: ShapeDesc::Plane {
                normal: Vec3::X,
                offset: -1.0,
            },
            material: Some(1),
        },
        Node::Shape {
            shape: ShapeDesc::Plane {
                normal: Vec3::NEG_X,
                offset: -1.0,
            },
            material: Some(1),
        },
    ]);
    scene
}

fn count_reflections(w: Whitted) -> (u32, Vec3) {
    let scene = mirror_box();
    let world = World::build(&scene, BuildOptions::default());
    let mut rec = RayRecorder::default();
    let eye = world.ray_from_world(&Ray::new(Vec3::ZERO, Vec3::new(1.0, 0.0, 0.2).normalize()));
    let (c, _) = crate::common::eye_ray(&w, &world, &eye, 0.0, &mut Counters::default(), &mut rec);
    let n = rec
        .rays
        .iter()
        .filter(|r| r.kind == RayKind::Reflected)
        .count() as u32;
    (n, c)
}

#[test]
fn bounces_limit_the_depth_of_the_tree() {
    for b in 0..6 {
        let (n, _) = count_reflections(Whitted {
            bounces: b,
            ..Whitted::default()
        });
        assert_eq!(n, b, "bounces {b}");
    }
}

#[test]
fn weight_cutoff_prunes_faint_branches() {
    // Each bounce halves the weight: 0.5, 0.25, 0.125, 0.0625 ...
    let (n, _) = count_reflections(Whitted {
        bounces: 20,
        weight_cutoff: 0.1,
        ..Whitted::default()
    });
    assert_eq!(n, 3);
    let (n, _) = count_reflections(Whitted {
        bounces: 20,
        weight_cutoff: 0.0,
        ..Whitted::default()
    });
    assert_eq!(n, 20);
}

#[test]
fn back_faces_are_black_unless_shade_back() {
    // The camera inside a sphere sees its inside: black by default, lit with shade_back.
    let mut scene = floor_scene(Phong::default());
    scene.camera = Camera::Perspective {
        center: Vec3::ZERO.as_dvec3(),
        direction: Vec3::NEG_Z,
        up: Vec3::Y,
        angle_deg: 30.0,
    };
    scene.lights = vec![Light::Point {
        position: Vec3::ZERO.as_dvec3(),
        color: Vec3::ONE,
        attenuation: Vec3::X,
    }];
    scene.root = sphere(Vec3::ZERO, 3.0, 0);
    let world = World::build(&scene, BuildOptions::default());
    let cam = CameraModel::new(world.camera());
    let px = |w: &Whitted| {
        let (f, _) = render(&world, &cam, w, (3, 3), PixelOffset::CENTER);
        f.color[4]
    };
    assert_eq!(px(&Whitted::default()), Vec3::ZERO);
    let lit = px(&Whitted {
        shade_back: true,
        ..Whitted::default()
    });
    assert!(
        (lit - Vec3::splat(0.1 * 0.8 + 0.8)).length() < 1e-4,
        "{lit}"
    );
}

/// The statistics count exactly the rays the tree holds, kind by kind: a
/// primary ray through a glass ball (reflective and transparent) above a
/// floor, with shadows and ambient occlusion, spawns every kind of ray.
#[test]
fn counters_count_each_kind_of_ray_in_the_tree() {
    let glass = Phong {
        diffuse: Vec3::splat(0.1),
        reflective: Vec3::splat(0.3),
        transparent: Vec3::splat(0.7),
        ior: 1.5,
        ..Phong::default()
    };
    let scene = floor_scene(glass);
    let world = World::build(&scene, BuildOptions::default());
    let w = Whitted {
        bounces: 4,
        shadows: true,
        ambient_occlusion: Some(glint::integrator::AoSettings {
            samples: 3,
            distance: 1.0,
        }),
        ..Whitted::default()
    };
    let eye = world.ray_from_world(&Ray::new(Vec3::new(0.1, 5.0, 0.05), Vec3::NEG_Y));
    let mut rec = RayRecorder::default();
    let mut c = Counters::default();
    crate::common::eye_ray(&w, &world, &eye, 0.0, &mut c, &mut rec);
    let count = |k: RayKind| rec.rays.iter().filter(|r| r.kind == k).count() as u64;
    let tree = [
        count(RayKind::Primary),
        count(RayKind::Reflected),
        count(RayKind::Transmitted),
        count(RayKind::Shadow),
        count(RayKind::Occlusion),
    ];
    assert_eq!(
        [c.primary, c.reflected, c.refracted, c.shadow, c.occlusion],
        tree
    );
    assert_eq!(tree[0], 1);
    assert!(tree.iter().all(|&n| n > 0), "every kind traced: {tree:?}");
}

/// Glossy reflection and transmission spread their rays over the lobe
/// `cos^e α` around the mirror / refracted direction, each on its own side
/// of the surface; an opaque, non-reflective surface spawns no child rays
/// even with no weight cutoff.
#[test]
fn glossy_children_spread_over_their_lobe_on_their_side() {
    let glossiness = 0.3;
    let e = 2.0 / (glossiness * glossiness) - 2.0;
    let glass = Phong {
        diffuse: Vec3::splat(0.1),
        reflective: Vec3::splat(0.5),
        transparent: Vec3::splat(0.5),
        ior: 1.5,
        glossiness,
        ..Phong::default()
    };
    let world = World::build(&floor_scene(glass), BuildOptions::default());
    let w = Whitted {
        bounces: 1,
        glossy_samples: 256,
        weight_cutoff: 0.0,
        ..Whitted::default()
    };
    let dir = Vec3::new(0.1, -1.0, 0.0).normalize();
    let eye = world.ray_from_world(&Ray::new(Vec3::new(0.0, 5.0, 0.0), dir));
    let mut rec = RayRecorder::default();
    let mut c = Counters::default();
    crate::common::eye_ray(&w, &world, &eye, 0.0, &mut c, &mut rec);
    let n = rec.rays[0].normal.expect("the eye ray hits the ball");
    let mirror = dir - 2.0 * dir.dot(n) * n;
    let children = |k: RayKind| -> Vec<Vec3> {
        rec.rays
            .iter()
            .filter(|r| r.kind == k && r.depth == 1)
            .map(|r| r.ray.dir.normalize())
            .collect()
    };
    let (refl, trans) = (children(RayKind::Reflected), children(RayKind::Transmitted));
    assert_eq!((refl.len(), trans.len()), (256, 256));
    assert_eq!(c.glossy, 512);
    assert!(
        refl.iter().all(|d| d.dot(n) > 0.0),
        "reflected rays leave outwards"
    );
    assert!(
        trans.iter().all(|d| d.dot(n) < 0.0),
        "transmitted rays go in"
    );
    // Density ∝ cos^e α: E[cos α] = (e + 1) / (e + 2) around the mirror
    // direction (the lobe lies well inside the hemisphere here).
    let mean_cos = refl.iter().map(|d| d.dot(mirror)).sum::<f32>() / 256.0;
    let want = (e + 1.0) / (e + 2.0);
    assert!(
        (mean_cos - want).abs() < 0.01,
        "mean cos {mean_cos}, lobe {want}"
    );
    let spread = refl.iter().map(|d| d.dot(mirror)).fold(1.0f32, f32::min);
    assert!(spread < 0.9, "the lobe is wide: least cos {spread}");

    // Opaque and not reflective: nothing to spawn, even with no cutoff.
    let matte = Phong {
        diffuse: Vec3::splat(0.5),
        ..Phong::default()
    };
    let world = World::build(&floor_scene(matte), BuildOptions::default());
    let mut rec = RayRecorder::default();
    let eye = world.ray_from_world(&Ray::new(Vec3::new(0.0, 5.0, 0.0), dir));
    crate::common::eye_ray(&w, &world, &eye, 0.0, &mut Counters::default(), &mut rec);
    assert_eq!(rec.rays.len(), 1, "{:?}", rec.rays);
}

/// A glossy mirror under a uniform sky: every lobe ray escapes to the
/// background, so the colour is exactly reflective × background, for any
/// number of lobe rays. Between two glossy mirrors only the camera ray's hit
/// spreads into `glossy_samples` rays; deeper hits take one each, and the
/// tree stops at `bounces`.
#[test]
fn glossy_reflection_averages_its_lobe_and_spreads_only_at_the_first_hit() {
    let gloss = Phong {
        reflective: Vec3::splat(0.5),
        glossiness: 0.4,
        diffuse: Vec3::ZERO,
        ..Phong::default()
    };
    let mut scene = floor_scene(gloss);
    scene.lights.clear();
    scene.background = Background {
        color: Vec3::splat(0.6),
        ambient: Vec3::ZERO,
    };
    let plane = |normal: Vec3, offset: f32| Node::Shape {
        shape: ShapeDesc::Plane {
            normal,
            offset: f64::from(offset),
        },
        material: Some(1),
    };
    scene.root = Node::Group(vec![plane(Vec3::Y, 0.0)]);
    let down = Vec3::new(0.3, -1.0, 0.1).normalize();
    for samples in [1, 5, 16] {
        let world = World::build(&scene, BuildOptions::default());
        let w = Whitted {
            bounces: 3,
            glossy_samples: samples,
            ..Whitted::default()
        };
        let eye = world.ray_from_world(&Ray::new(Vec3::new(0.0, 1.0, 0.0), down));
        let (c, _) = crate::common::eye_ray(
            &w,
            &world,
            &eye,
            0.0,
            &mut Counters::default(),
            &mut NoObserver,
        );
        assert!(
            (c - Vec3::splat(0.3)).abs().max_element() < 1e-6,
            "{samples} rays: {c}"
        );
    }

    scene.root = Node::Group(vec![plane(Vec3::Y, 0.0), plane(Vec3::NEG_Y, -1.0)]);
    let world = World::build(&scene, BuildOptions::default());
    let w = Whitted {
        bounces: 3,
        glossy_samples: 4,
        ..Whitted::default()
    };
    let eye = world.ray_from_world(&Ray::new(Vec3::new(0.0, 0.5, 0.0), down));
    let mut rec = RayRecorder::default();
    crate::common::eye_ray(&w, &world, &eye, 0.0, &mut Counters::default(), &mut rec);
    let at = |depth: u32| rec.rays.iter().filter(|r| r.depth == depth).count();
    assert_eq!([at(0), at(1), at(2), at(3), at(4)], [1, 4, 4, 4, 0]);
}
