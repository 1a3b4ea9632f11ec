//! Watertightness: rays aimed exactly at the shared edges and vertices of a
//! closed mesh never miss it, under every accelerator (and with transforms
//! kept, where the test runs in object space).
//!
//! The mesh is a bumpy, star-shaped sphere (a UV sphere with perturbed
//! radii), rotated, scaled and placed away from the origin so that the
//! rounding is not trivial. For every edge of every triangle (taken from the
//! built world, so the vertices are exactly the ones the test sees), rays go
//! from the mesh's centre, which it encloses, through the vertices and
//! through points of the edge, and from outside towards the centre through
//! the same points: each must hit. As a control, Möller–Trumbore (what glint
//! used before) run on the same rays and triangles misses some.

use glam::{DMat4, DVec3};
use glint::accel::{AccelKind, Split};
use glint::math::{Ray, Vec3};
use glint::scene::{Background, Camera, Mesh, Node, Scene, ShapeDesc};
use glint::shape::Shape as WorldShape;
use glint::stats::Counters;
use glint::world::{BuildOptions, World};
use std::sync::Arc;

fn bumpy_sphere() -> Mesh {
    let (nu, nv) = (48u32, 24u32);
    let mut m = Mesh::default();
    // Deterministic bumps: the radius varies smoothly, so the mesh stays
    // star-shaped around the origin.
    let radius = |th: f32, ph: f32| 1.0 + 0.15 * (3.0 * th).sin() * (5.0 * ph).cos();
    m.positions.push(Vec3::Y * radius(0.0, 0.0));
    for j in 1..nv {
        for i in 0..nu {
            let th = std::f32::consts::PI * j as f32 / nv as f32;
            let ph = std::f32::consts::TAU * i as f32 / nu as f32;
            let u = Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin());
            m.positions.push(u * radius(th, ph));
        }
    }
    m.positions
        .push(Vec3::NEG_Y * radius(std::f32::consts::PI, 0.0));
    let ring = |j: u32, i: u32| 1 + (j - 1) * nu + i % nu;
    let last = m.positions.len() as u32 - 1;
    for i in 0..nu {
        m.triangles.push([0, ring(1, i + 1), ring(1, i)]);
        m.triangles
            .push([last, ring(nv - 1, i), ring(nv - 1, i + 1)]);
        for j in 1..nv - 1 {
            m.triangles
                .push([ring(j, i), ring(j, i + 1), ring(j + 1, i + 1)]);
            m.triangles
                .push([ring(j, i), ring(j + 1, i + 1), ring(j + 1, i)]);
        }
    }
    m
}

/// Object to world: rotated, non-uniformly scaled, away from the origin.
fn placement() -> DMat4 {
    DMat4::from_translation(DVec3::new(1234.5, -321.25, 777.0))
        * DMat4::from_axis_angle(DVec3::new(0.3, 0.8, -0.5).normalize(), 0.9)
        * DMat4::from_scale(DVec3::new(3.0, 2.0, 2.5))
}

fn scene() -> Scene {
    Scene {
        camera: Camera::Perspective {
            center: Vec3::new(1200.0, -300.0, 790.0).as_dvec3(),
            direction: Vec3::new(1.0, -0.5, -0.3),
            up: Vec3::Y,
            angle_deg: 40.0,
        },
        lights: vec![],
        background: Background::default(),
        materials: vec![],
        root: Node::Transform {
            matrix: placement(),
            child: Box::new(Node::Shape {
                shape: ShapeDesc::Mesh(Arc::new(bumpy_sphere())),
                material: None,
            }),
        },
        effects: Default::default(),
    }
}

/// The rays: from the centre and from outside, through every vertex and
/// through three points of every edge of every triangle, in rendering space.
fn rays(world: &World) -> Vec<Ray> {
    let center = world
        .ray_from_world(&Ray::new(
            placement().transform_point3(DVec3::ZERO).as_vec3(),
            Vec3::X,
        ))
        .origin;
    let mut out = Vec::new();
    let mesh = bumpy_sphere();
    let m = placement();
    let world_vertex = |p: Vec3| (m.transform_point3(p.as_dvec3()) - world.origin()).as_vec3();
    for t in &mesh.triangles {
        let v = t.map(|i| world_vertex(mesh.positions[i as usize]));
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            for s in [0.0, 0.5, 1.0 / 3.0, 0.123_456_7] {
                let p = a + s * (b - a);
                out.push(Ray::new(center, p - center));
                let outside = center + (p - center) * 4.0;
                out.push(Ray::new(outside, p - outside));
            }
        }
    }
    out
}

fn misses(world: &World, rays: &[Ray]) -> usize {
    let mut c = Counters::default();
    rays.iter()
        .filter(|r| world.intersect(r, 0.0, f32::INFINITY, &mut c).is_none())
        .count()
}

#[test]
fn rays_through_edges_and_vertices_never_miss() {
    let kinds = [
        AccelKind::None,
        AccelKind::Grid { res: None },
        AccelKind::Grid {
            res: Some([7, 3, 5]),
        },
        AccelKind::Octree,
        AccelKind::Bvh(Split::Sah),
        AccelKind::Bvh8,
        AccelKind::Bvh(Split::Median),
        AccelKind::Bvh(Split::Midpoint),
    ];
    let s = scene();
    for flatten in [true, false] {
        for accel in kinds {
            let world = World::build(&s, BuildOptions { accel, flatten });
            let rays = rays(&world);
            assert!(rays.len() > 40_000);
            let n = misses(&world, &rays);
            assert_eq!(
                n,
                0,
                "{accel:?} (flatten {flatten}): {n} of {} rays missed",
                rays.len()
            );
        }
    }
}

/// Möller–Trumbore with per-triangle edges, as glint had it before.
fn moller_trumbore(v: [Vec3; 3], r: &Ray) -> Option<f32> {
    let (e1, e2) = (v[1] - v[0], v[2] - v[0]);
    let p = r.dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let inv = 1.0 / det;
    let s = r.origin - v[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let w = r.dir.dot(q) * inv;
    if w < 0.0 || u + w > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0).then_some(t)
}

/// The control: the same rays against the same (flattened) triangles with
/// Möller–Trumbore find holes, so the test above can fail.
#[test]
fn moller_trumbore_leaks_on_the_same_rays() {
    let world = World::build(&scene(), BuildOptions::default());
    let tris: Vec<[Vec3; 3]> = world
        .prims()
        .iter()
        .filter_map(|p| match &p.shape {
            WorldShape::Triangle(t) => Some(t.v),
            _ => None,
        })
        .collect();
    let leaks = rays(&world)
        .iter()
        .filter(|r| tris.iter().all(|&v| moller_trumbore(v, r).is_none()))
        .count();
    assert!(
        leaks > 0,
        "Möller–Trumbore found no hole: the rays are too easy"
    );
    println!("Möller–Trumbore: {leaks} rays slip through the mesh");
}
