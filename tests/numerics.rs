//! Extreme but legal scenes, built by hand, rendered with shadows, shade-back
//! and several bounces: every pixel of the colour, depth and normal planes
//! must be a number (no NaN, no infinity; a miss has the documented infinite
//! depth and zero normal).
//!
//! The scenes come from [`extreme_scenes`] and are rendered by
//! [`check_scene`], which takes the [`BuildOptions`], so the same cases can
//! be run against every acceleration structure (`AccelKind`) as they appear.

use glint::integrator::{Branch, RayObserver, Whitted};
use glint::material::TextureSpace;
use glint::math::{Mat4, Ray, Vec3};
use glint::render::{render, screen_point, CameraModel, Frame, PixelOffset};
use glint::scene::{
    Background, Camera, Light, Material, Mesh, Node, Phong, Scene, ShapeDesc, TextureKind,
};
use glint::stats::Counters;
use glint::world::{BuildOptions, World};
use std::sync::Arc;

// ---- scene-building helpers -------------------------------------------------

fn shape(shape: ShapeDesc, material: usize) -> Node {
    Node::Shape {
        shape,
        material: Some(material),
    }
}

fn sphere(center: Vec3, radius: f32, material: usize) -> Node {
    shape(
        ShapeDesc::Sphere {
            center: center.as_dvec3(),
            radius,
        },
        material,
    )
}

fn plane(normal: Vec3, offset: f32, material: usize) -> Node {
    shape(
        ShapeDesc::Plane {
            normal,
            offset: f64::from(offset),
        },
        material,
    )
}

fn tri(a: Vec3, b: Vec3, c: Vec3, material: usize) -> Node {
    shape(
        ShapeDesc::Triangle([a.as_dvec3(), b.as_dvec3(), c.as_dvec3()]),
        material,
    )
}

fn xf(matrix: Mat4, child: Node) -> Node {
    Node::Transform {
        matrix: matrix.as_dmat4(),
        child: Box::new(child),
    }
}

fn v(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

fn persp(center: Vec3, direction: Vec3, up: Vec3, angle_deg: f32) -> Camera {
    Camera::Perspective {
        center: center.as_dvec3(),
        direction,
        up,
        angle_deg,
    }
}

fn ortho(center: Vec3, direction: Vec3, up: Vec3, size: f32) -> Camera {
    Camera::Orthographic {
        center: center.as_dvec3(),
        direction,
        up,
        size,
    }
}

fn point_light(position: Vec3, attenuation: Vec3) -> Light {
    Light::Point {
        position: position.as_dvec3(),
        color: Vec3::splat(0.8),
        attenuation,
    }
}

/// Materials every scene uses: 0 matte, 1 shiny mirror, 2 glass, 3 a
/// checkerboard of 0 and 2, 4 a mirror-glass with every term on.
fn materials() -> Vec<Material> {
    let matte = Phong {
        diffuse: v(0.8, 0.4, 0.2),
        ..Phong::default()
    };
    let mirror = Phong {
        diffuse: v(0.1, 0.1, 0.1),
        specular: Vec3::ONE,
        exponent: 50.0,
        reflective: Vec3::splat(0.9),
        ..Phong::default()
    };
    let glass = Phong {
        diffuse: Vec3::ZERO,
        specular: Vec3::ONE,
        exponent: 100.0,
        reflective: Vec3::splat(0.2),
        transparent: Vec3::splat(0.9),
        ior: 1.5,
        glossiness: 0.0,
        emission: Vec3::ZERO,
    };
    let both = Phong {
        diffuse: Vec3::splat(0.3),
        specular: Vec3::splat(0.5),
        exponent: 0.0,
        reflective: Vec3::splat(0.5),
        transparent: Vec3::splat(0.5),
        ior: 2.4,
        glossiness: 0.0,
        emission: Vec3::ZERO,
    };
    vec![
        Material::Phong(matte),
        Material::Phong(mirror),
        Material::Phong(glass),
        Material::Texture {
            kind: TextureKind::Checkerboard,
            transform: Mat4::IDENTITY,
            a: 0,
            b: 2,
        },
        Material::Phong(both),
    ]
}

fn scene(camera: Camera, lights: Vec<Light>, objects: Vec<Node>) -> Scene {
    Scene {
        camera,
        lights,
        background: Background {
            color: v(0.2, 0.3, 0.4),
            ambient: Vec3::splat(0.1),
        },
        materials: materials(),
        root: Node::Group(objects),
        effects: Default::default(),
    }
}

/// A light above and one directional light, the usual lighting.
fn lights() -> Vec<Light> {
    vec![
        point_light(v(3.0, 5.0, 4.0), v(1.0, 0.1, 0.01)),
        Light::Directional {
            direction: v(-0.3, -1.0, -0.5),
            color: Vec3::splat(0.5),
        },
    ]
}

fn look_at_origin() -> Camera {
    persp(v(0.0, 0.0, 5.0), Vec3::NEG_Z, Vec3::Y, 60.0)
}

/// The hand-built extreme scenes, by name.
pub fn extreme_scenes() -> Vec<(&'static str, Scene)> {
    let mut out = Vec::new();

    // Zero-area triangles: a point, collinear vertices, a repeated vertex,
    // and a whole mesh of them, in front of a real triangle.
    let degenerate_mesh = Mesh {
        positions: vec![v(0.0, 0.0, 1.0), v(1.0, 1.0, 1.0), v(2.0, 2.0, 1.0)],
        triangles: vec![[0, 1, 2], [0, 0, 0], [1, 2, 1]],
        ..Mesh::default()
    };
    out.push((
        "zero-area triangles",
        scene(
            look_at_origin(),
            lights(),
            vec![
                tri(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, 1),
                tri(v(-1.0, -1.0, 0.5), Vec3::ZERO, v(1.0, 1.0, 0.5), 2),
                tri(v(-1.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(-1.0, 0.0, 0.0), 4),
                tri(
                    v(-1e-30, 0.0, 0.0),
                    v(1e-30, 0.0, 0.0),
                    v(0.0, 1e-30, 0.0),
                    4,
                ),
                shape(ShapeDesc::Mesh(Arc::new(degenerate_mesh)), 1),
                tri(
                    v(-2.0, -2.0, -1.0),
                    v(2.0, -2.0, -1.0),
                    v(0.0, 2.0, -1.0),
                    3,
                ),
            ],
        ),
    ));

    // Coincident planes: the same plane three times (one with the normal
    // flipped), different materials, seen from both sides.
    out.push((
        "coincident planes",
        scene(
            persp(v(0.0, 1.0, 5.0), v(0.0, -0.5, -1.0), Vec3::Y, 90.0),
            lights(),
            vec![
                plane(Vec3::Y, -1.0, 1),
                plane(v(0.0, 2.0, 0.0), -2.0, 2),
                plane(Vec3::NEG_Y, 1.0, 4),
                sphere(Vec3::ZERO, 1.0, 2),
            ],
        ),
    ));

    // Coincident triangles: one triangle twice, and once with the opposite
    // winding, all glass and mirror, with a sphere through them.
    let (a, b, c) = (v(-2.0, -2.0, 0.0), v(2.0, -2.0, 0.0), v(0.0, 2.0, 0.0));
    out.push((
        "coincident triangles",
        scene(
            look_at_origin(),
            lights(),
            vec![
                tri(a, b, c, 2),
                tri(a, b, c, 1),
                tri(a, c, b, 4),
                sphere(Vec3::ZERO, 0.5, 4),
                plane(Vec3::Z, -3.0, 3),
            ],
        ),
    ));

    // Huge scale: everything a million times larger, directly and through
    // transforms, with a checkerboard evaluated at huge coordinates.
    let big = 1e6;
    out.push((
        "huge scale",
        scene(
            persp(v(0.0, 0.0, 5.0 * big), Vec3::NEG_Z, Vec3::Y, 60.0),
            vec![
                point_light(v(3.0, 5.0, 4.0) * big, v(0.0, 0.0, 1.0)),
                point_light(v(-3.0, 5.0, 4.0) * big, v(1.0, 1.0, 1.0)),
            ],
            vec![
                sphere(Vec3::ZERO, big, 3),
                xf(
                    Mat4::from_scale(Vec3::splat(big)),
                    sphere(v(1.5, 1.5, 0.0), 0.5, 1),
                ),
                xf(
                    Mat4::from_scale(Vec3::splat(big)),
                    tri(
                        v(-3.0, -3.0, -1.0),
                        v(3.0, -3.0, -1.0),
                        v(0.0, -1.0, -1.0),
                        2,
                    ),
                ),
                plane(Vec3::Y, -2.0 * big, 3),
                sphere(v(1e30, 0.0, -1e30), 1e29, 3),
            ],
        ),
    ));

    // Tiny scale: a millionth of the usual size.
    let small = 1e-6;
    out.push((
        "tiny scale",
        scene(
            persp(v(0.0, 0.0, 5.0 * small), Vec3::NEG_Z, Vec3::Y, 60.0),
            vec![point_light(v(3.0, 5.0, 4.0) * small, v(1.0, 0.0, 1.0))],
            vec![
                sphere(Vec3::ZERO, small, 4),
                xf(
                    Mat4::from_scale(Vec3::splat(small)),
                    sphere(v(1.5, 1.5, 0.0), 0.5, 1),
                ),
                tri(
                    v(-3.0, -3.0, -1.0) * small,
                    v(3.0, -3.0, -1.0) * small,
                    v(0.0, 3.0, -1.0) * small,
                    3,
                ),
                plane(Vec3::Y, -2.0 * small, 1),
            ],
        ),
    ));

    // A sphere squashed almost flat, and one stretched almost to a needle,
    // under a rotation: the inverse matrix has huge entries.
    out.push((
        "near-singular scale",
        scene(
            look_at_origin(),
            lights(),
            vec![
                xf(
                    Mat4::from_rotation_x(0.7) * Mat4::from_scale(v(2.0, 1e-6, 2.0)),
                    sphere(Vec3::ZERO, 1.0, 2),
                ),
                xf(
                    Mat4::from_translation(v(1.0, 0.0, 0.0))
                        * Mat4::from_rotation_z(0.3)
                        * Mat4::from_scale(v(1e-7, 1.0, 1e-7)),
                    sphere(Vec3::ZERO, 1.0, 4),
                ),
                xf(
                    Mat4::from_scale(v(1e-6, 1e-6, 1e-6)) * Mat4::from_scale(v(1e6, 1e6, 1e6)),
                    sphere(v(-1.5, 0.0, 0.0), 0.5, 1),
                ),
                plane(Vec3::Z, -2.0, 3),
            ],
        ),
    ));

    // Rays parallel to the axes and to planes: an orthographic camera looking
    // down -z at planes containing its rays, and a triangle seen edge-on.
    out.push((
        "rays parallel to axes and planes",
        scene(
            ortho(v(0.0, 0.0, 5.0), Vec3::NEG_Z, Vec3::Y, 4.0),
            vec![Light::Directional {
                direction: Vec3::NEG_X,
                color: Vec3::ONE,
            }],
            vec![
                plane(Vec3::X, 0.0, 1),
                plane(Vec3::Y, 0.0, 2),
                tri(v(0.5, -1.0, -1.0), v(0.5, 1.0, -1.0), v(0.5, 0.0, 1.0), 4),
                sphere(v(-1.0, 1.0, 0.0), 0.5, 4),
                plane(Vec3::Z, -3.0, 0),
            ],
        ),
    ));

    // The camera exactly on a plane (perspective and orthographic): rays
    // along the plane, and rays starting on it.
    for (name, camera) in [
        (
            "perspective camera on a plane",
            persp(v(0.0, 0.0, 5.0), Vec3::NEG_Z, Vec3::Y, 60.0),
        ),
        (
            "orthographic camera on a plane",
            ortho(v(0.0, 0.0, 5.0), v(0.0, -1.0, -1.0), Vec3::Y, 4.0),
        ),
    ] {
        out.push((
            name,
            scene(
                camera,
                lights(),
                vec![
                    plane(Vec3::Y, 0.0, 1),
                    plane(Vec3::Z, 5.0, 2),
                    sphere(v(0.0, 0.5, 0.0), 0.5, 4),
                ],
            ),
        ));
    }

    // The camera inside a sphere (glass, then mirror), perspective and
    // orthographic (whose rays also go backwards).
    for (name, camera) in [
        (
            "perspective camera inside a sphere",
            persp(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 90.0),
        ),
        (
            "orthographic camera inside a sphere",
            ortho(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y, 1.0),
        ),
    ] {
        out.push((
            name,
            scene(
                camera,
                vec![point_light(Vec3::ZERO, v(1.0, 0.0, 0.0))],
                vec![
                    sphere(Vec3::ZERO, 2.0, 2),
                    sphere(Vec3::ZERO, 3.0, 1),
                    sphere(v(0.0, 0.0, -1.0), 0.25, 4),
                ],
            ),
        ));
    }

    // Point lights exactly on surfaces: on a sphere, on a plane, at a
    // triangle's vertex, and at a point a camera ray hits.
    out.push((
        "point light on a surface",
        scene(
            look_at_origin(),
            vec![
                point_light(v(0.0, 1.0, 0.0), v(0.0, 0.0, 1.0)),
                point_light(v(2.0, -1.0, 0.0), v(0.0, 1.0, 0.0)),
                point_light(v(-2.0, -1.0, -1.0), v(1.0, 0.0, 0.0)),
                point_light(v(0.0, 0.0, 1.0), v(0.0, 0.0, 1.0)),
            ],
            vec![
                sphere(Vec3::ZERO, 1.0, 1),
                plane(Vec3::Y, -1.0, 3),
                tri(
                    v(-2.0, -1.0, -1.0),
                    v(-1.0, -1.0, -1.0),
                    v(-1.5, 0.0, -1.0),
                    4,
                ),
            ],
        ),
    ));

    // All-zero attenuation, also with the light on the surface (the
    // denominator is zero there), and a black light.
    out.push((
        "all-zero attenuation",
        scene(
            look_at_origin(),
            vec![
                point_light(v(3.0, 5.0, 4.0), Vec3::ZERO),
                point_light(v(0.0, 1.0, 0.0), Vec3::ZERO),
                Light::Point {
                    position: v(0.0, 0.0, 3.0).as_dvec3(),
                    color: Vec3::ZERO,
                    attenuation: Vec3::ZERO,
                },
            ],
            vec![sphere(Vec3::ZERO, 1.0, 4), plane(Vec3::Y, -1.0, 3)],
        ),
    ));

    // Camera vectors with huge (but finite) lengths, an up vector nearly
    // parallel to the direction, and lights given by huge vectors.
    for (name, camera) in [
        (
            "huge camera vectors",
            persp(
                v(0.0, 0.0, 5.0),
                v(0.0, 0.0, -3e38),
                v(0.0, 2e38, 0.0),
                60.0,
            ),
        ),
        (
            "tiny camera vectors",
            ortho(
                v(0.0, 0.0, 5.0),
                v(0.0, 0.0, -1e-38),
                v(0.0, 1e-40, 0.0),
                4.0,
            ),
        ),
        (
            "nearly parallel up vector",
            persp(
                v(0.0, 0.0, 5.0),
                v(0.1, 0.2, -0.3),
                v(0.1, 0.2, -0.300_000_1),
                60.0,
            ),
        ),
    ] {
        out.push((
            name,
            scene(
                camera,
                vec![
                    Light::Directional {
                        direction: v(-3e38, -3e38, -3e38),
                        color: Vec3::ONE,
                    },
                    Light::Directional {
                        direction: v(1e-40, -1e-40, 0.0),
                        color: Vec3::ONE,
                    },
                    point_light(v(3e38, 3e38, 3e38), Vec3::X),
                ],
                vec![sphere(Vec3::ZERO, 1.0, 4), plane(Vec3::Y, -1.0, 3)],
            ),
        ));
    }

    // Materials at the ends of their ranges: huge and tiny indices of
    // refraction, a huge exponent, a huge light.
    let mut extreme = scene(
        look_at_origin(),
        vec![Light::Point {
            position: v(0.0, 0.0, 5.0).as_dvec3(),
            color: Vec3::splat(1e30),
            attenuation: Vec3::X,
        }],
        vec![
            sphere(v(-1.0, 0.0, 0.0), 0.9, 5),
            sphere(v(1.0, 0.0, 0.0), 0.9, 6),
            sphere(v(0.0, 1.0, -1.0), 0.9, 7),
            plane(Vec3::Z, -3.0, 0),
        ],
    );
    let glassy = |ior: f32, exponent: f32| {
        Material::Phong(Phong {
            diffuse: Vec3::splat(0.2),
            specular: Vec3::ONE,
            exponent,
            reflective: Vec3::splat(0.5),
            transparent: Vec3::splat(0.5),
            ior,
            glossiness: 0.0,
            emission: Vec3::ZERO,
        })
    };
    extreme.materials.push(glassy(3e38, 1.0));
    extreme.materials.push(glassy(1e-38, 3e38));
    extreme.materials.push(glassy(1.0, 1e-38));
    out.push(("extreme materials", extreme));
    out
}

// ---- rendering and checking --------------------------------------------------

/// Every way the integrator can be set up that changes which code runs.
fn integrators() -> Vec<Whitted> {
    let mut out = Vec::new();
    for transparent_shadows in [false, true] {
        for shade_back in [false, true] {
            for texture_space in [TextureSpace::World, TextureSpace::Object] {
                out.push(Whitted {
                    bounces: 6,
                    weight_cutoff: 0.0,
                    shadows: true,
                    shade_back,
                    transparent_shadows,
                    texture_space,
                    ..Whitted::default()
                });
            }
        }
    }
    out
}

/// Where a frame is not all numbers: `None`, or the first bad pixel.
pub fn first_non_finite(frame: &Frame) -> Option<String> {
    for (k, ((c, d), n)) in frame
        .color
        .iter()
        .zip(&frame.depth)
        .zip(&frame.normal)
        .enumerate()
    {
        let (x, y) = (k as u32 % frame.width, k as u32 / frame.width);
        let hit = *n != Vec3::ZERO;
        let depth_ok = d.is_finite() || (*d == f32::INFINITY && !hit);
        if !c.is_finite() || !depth_ok || !n.is_finite() {
            return Some(format!(
                "pixel ({x}, {y}): colour {c}, depth {d}, normal {n}"
            ));
        }
        if hit && (n.length() - 1.0).abs() > 1e-3 {
            return Some(format!("pixel ({x}, {y}): normal {n} is not unit length"));
        }
    }
    None
}

/// Remembers the first ray with a non-finite origin or direction, or a zero
/// direction.
#[derive(Default)]
struct FiniteRays {
    bad: Option<String>,
}

impl RayObserver for FiniteRays {
    fn ray(&mut self, b: Branch, ray: &Ray, _: f32, n: Option<Vec3>) {
        let (kind, depth) = (b.kind, b.depth);
        let ok = ray.origin.is_finite()
            && ray.dir.is_finite()
            && ray.dir != Vec3::ZERO
            && n.is_none_or(|n| n.is_finite());
        if !ok && self.bad.is_none() {
            self.bad = Some(format!(
                "{kind:?} ray at depth {depth}: {ray:?}, normal {n:?}"
            ));
        }
    }
}

/// Renders `scene` built with `opts` under every integrator set-up, both
/// pixel conventions, and returns what went wrong (empty when all is well).
pub fn check_scene(name: &str, scene: &Scene, opts: BuildOptions) -> Vec<String> {
    let world = World::build(scene, opts);
    let camera = CameraModel::new(world.camera());
    let mut problems = Vec::new();
    // A NaN camera ray hits nothing and would pass for background.
    'sizes: for (w, h) in [(24, 24), (25, 17)] {
        for j in 0..h {
            for i in 0..w {
                let s = screen_point(i, j, PixelOffset::CENTER.0, w, h);
                let r = camera.ray(s);
                if !r.origin.is_finite() || !r.dir.is_finite() || r.dir == Vec3::ZERO {
                    problems.push(format!("{name}: camera ray at ({i}, {j}) is {r:?}"));
                    break 'sizes;
                }
            }
        }
    }
    // Every ray of every ray tree: a NaN secondary ray also hits nothing, so
    // it would hide as a black or background contribution.
    for integrator in integrators() {
        let mut obs = FiniteRays::default();
        let (w, h) = (25, 17);
        for j in 0..h {
            for i in 0..w {
                let ray = camera.ray(screen_point(i, j, PixelOffset::CENTER.0, w, h));
                let mut c = Counters::default();
                crate::common::eye_ray(&integrator, &world, &ray, camera.tmin(), &mut c, &mut obs);
            }
        }
        if let Some(bad) = obs.bad {
            problems.push(format!("{name} ({opts:?}, {integrator:?}): {bad}"));
        }
    }
    for integrator in integrators() {
        for offset in [PixelOffset::CENTER, PixelOffset::CORNER] {
            // Odd and even sizes put pixels exactly on the image's centre lines.
            for size in [(24, 24), (25, 17)] {
                let (frame, _) = render(&world, &camera, &integrator, size, offset);
                if let Some(p) = first_non_finite(&frame) {
                    problems.push(format!(
                        "{name} ({opts:?}, {integrator:?}, {offset:?}, {size:?}): {p}"
                    ));
                }
            }
        }
    }
    problems
}

fn check_all(opts: BuildOptions) {
    let problems: Vec<String> = extreme_scenes()
        .iter()
        .flat_map(|(name, s)| check_scene(name, s, opts))
        .collect();
    assert!(problems.is_empty(), "\n{}", problems.join("\n"));
}

#[test]
fn extreme_scenes_render_finite_flattened() {
    check_all(BuildOptions::default());
}

#[test]
fn extreme_scenes_render_finite_with_transforms_kept() {
    check_all(BuildOptions {
        flatten: false,
        ..BuildOptions::default()
    });
}

/// The scenes really do exercise what they claim: most hit something.
#[test]
fn extreme_scenes_are_not_empty() {
    for (name, s) in extreme_scenes() {
        let world = World::build(&s, BuildOptions::default());
        let camera = CameraModel::new(world.camera());
        let (frame, _) = render(
            &world,
            &camera,
            &Whitted::default(),
            (16, 16),
            PixelOffset::CENTER,
        );
        let hits = frame.normal.iter().filter(|n| **n != Vec3::ZERO).count();
        assert!(hits > 0, "{name}: the camera sees nothing");
    }
}
