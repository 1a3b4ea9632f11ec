//! Accelerator rays at the edges (issue 18): rays that start exactly on cell
//! faces and on the grid's boundary, inside the scene box, run parallel to
//! the axes along cell planes, and pass through cell corners, for every
//! accelerator, against brute force. `tests/accel_agree.rs` draws its rays at
//! random, so they almost never start on a cell face or graze a corner.
//!
//! The scene is the awkward one for a grid: unit squares lying on the integer
//! planes of [0, 4]³ (on the cell faces of a 4×4×4 grid), small spheres
//! centred on lattice corners, and one long tilted triangle crossing many
//! cells, whose hits often lie cells beyond where a ray first meets a cell
//! holding it. The end-to-end test renders a scene built so that a grid
//! which stops at the first cell with any candidate hit draws a different
//! picture.

use crate::common::Rng;
use glint::accel::grid::Lattice;
use glint::accel::{AccelKind, Grid, Split};
use glint::integrator::Whitted;
use glint::math::{Ray, Vec3};
use glint::render::{render, CameraModel, PixelOffset};
use glint::scene::{Background, Camera, Light, Material, Node, Phong, Scene, ShapeDesc};
use glint::stats::Counters;
use glint::world::{BuildOptions, World};

/// Every accelerator, with grids whose cells are the unit cells of the
/// scene's lattice, half of them, and a resolution that fits nothing.
fn accelerators() -> Vec<AccelKind> {
    vec![
        AccelKind::Grid { res: None },
        AccelKind::Grid {
            res: Some([4, 4, 4]),
        },
        AccelKind::Grid {
            res: Some([8, 8, 8]),
        },
        AccelKind::Grid {
            res: Some([3, 5, 7]),
        },
        AccelKind::Octree,
        AccelKind::OctreeInner,
        AccelKind::NESTED_GRID,
        AccelKind::NestedGrid {
            threshold: 1,
            depth: 3,
        },
        AccelKind::Bvh(Split::Sah),
        AccelKind::Bvh(Split::Median),
        AccelKind::Bvh(Split::Midpoint),
        AccelKind::BvhHierarchy,
        AccelKind::Bvh8,
    ]
}

fn shape(shape: ShapeDesc) -> Node {
    Node::Shape {
        shape,
        material: Some(0),
    }
}

/// Unit squares on integer planes, spheres on lattice corners, one long
/// tilted triangle: deterministic, about 150 primitives in [0, 4]³.
fn lattice_scene() -> Scene {
    let mut r = Rng::new(7);
    let mut kids = Vec::new();
    for _ in 0..60 {
        let axis = r.below(3);
        let mut o = [r.below(4) as f32, r.below(4) as f32, r.below(4) as f32];
        o[axis] = r.below(5) as f32;
        let o = Vec3::from(o);
        let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
        kids.push(shape(ShapeDesc::Triangle([
            o.as_dvec3(),
            (o + u).as_dvec3(),
            (o + u + v).as_dvec3(),
        ])));
        kids.push(shape(ShapeDesc::Triangle([
            o.as_dvec3(),
            (o + u + v).as_dvec3(),
            (o + v).as_dvec3(),
        ])));
    }
    for _ in 0..12 {
        let c = Vec3::new(r.below(5) as f32, r.below(5) as f32, r.below(5) as f32);
        kids.push(shape(ShapeDesc::Sphere {
            center: c.as_dvec3(),
            radius: 0.25,
        }));
    }
    kids.push(shape(ShapeDesc::Triangle([
        Vec3::new(0.0, 0.1, 0.0).as_dvec3(),
        Vec3::new(4.0, 3.9, 0.3).as_dvec3(),
        Vec3::new(0.2, 3.5, 4.0).as_dvec3(),
    ])));
    Scene {
        camera: Camera::Perspective {
            center: Vec3::new(2.0, 2.0, 12.0).as_dvec3(),
            direction: Vec3::NEG_Z,
            up: Vec3::Y,
            angle_deg: 40.0,
        },
        lights: vec![],
        background: Background::default(),
        materials: vec![Material::Phong(Phong::default())],
        root: Node::Group(kids),
        effects: Default::default(),
    }
}

/// The ray families, built on the lattice of a grid over the scene (its
/// planes are the integer planes of the scene moved by the grid's padding).
fn edge_rays(l: &Lattice) -> Vec<(&'static str, Ray, f32, f32)> {
    let mut r = Rng::new(11);
    let mut rays = Vec::new();
    let (lo, hi) = (l.bounds.min, l.bounds.max);
    let inside = |r: &mut Rng| lo + Vec3::new(r.f(), r.f(), r.f()) * (hi - lo);
    let corner = |i: [u32; 3]| {
        Vec3::new(
            l.plane(0, i[0] as i32),
            l.plane(1, i[1] as i32),
            l.plane(2, i[2] as i32),
        )
    };
    let signed_axes = [
        Vec3::X,
        Vec3::Y,
        Vec3::Z,
        Vec3::NEG_X,
        Vec3::NEG_Y,
        Vec3::NEG_Z,
    ];
    for _ in 0..3000 {
        // On a cell face (index 0 and res are the grid's boundary), heading
        // anywhere: along the face's normal either way, within the face, at
        // random, or at a point inside the box.
        let a = r.below(3);
        let i = r.below(l.res[a] as usize + 1) as u32;
        let mut o = inside(&mut r);
        o[a] = l.plane(a, i as i32);
        let d = match r.below(4) {
            0 => signed_axes[r.below(6)],
            1 => {
                let mut d = r.unit();
                d[a] = 0.0;
                d.normalize_or(Vec3::AXES[(a + 1) % 3])
            }
            2 => r.unit(),
            _ => (inside(&mut r) - o).normalize_or(Vec3::X),
        };
        let family = if i == 0 || i == l.res[a] {
            "on the grid boundary"
        } else {
            "on a cell face"
        };
        rays.push((family, Ray::new(o, d), 0.0, f32::INFINITY));
        // The same line started at its face through tmin instead.
        rays.push((family, Ray::new(o - 1.5 * d, d), 1.5, f32::INFINITY));

        // Inside the box, with a range that may end inside too.
        let o = inside(&mut r);
        let tmax = if r.below(2) == 0 {
            f32::INFINITY
        } else {
            0.5 + 4.0 * r.f()
        };
        rays.push(("inside the box", Ray::new(o, r.unit()), 0.0, tmax));

        // Parallel to an axis, along a line where two cell planes meet (a
        // cell edge), or along a single plane, from outside or inside.
        let a = r.below(3);
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let mut o = Vec3::ZERO;
        o[b] = l.plane(b, r.below(l.res[b] as usize + 1) as i32);
        o[c] = if r.below(2) == 0 {
            l.plane(c, r.below(l.res[c] as usize + 1) as i32)
        } else {
            lo[c] + r.f() * (hi[c] - lo[c])
        };
        o[a] = if r.below(2) == 0 {
            lo[a] - 1.0
        } else {
            hi[a] + 1.0
        };
        if r.below(3) == 0 {
            o[a] = lo[a] + r.f() * (hi[a] - lo[a]);
        }
        let d = if r.below(2) == 0 {
            Vec3::AXES[a]
        } else {
            -Vec3::AXES[a]
        };
        rays.push(("parallel to an axis", Ray::new(o, d), 0.0, f32::INFINITY));

        // Through a lattice corner, from outside the box, and starting at one.
        let k = [0, 1, 2].map(|a| r.below(l.res[a] as usize + 1) as u32);
        let p = corner(k);
        let from = (lo + hi) * 0.5 + r.unit() * (hi - lo).length();
        rays.push((
            "through a cell corner",
            Ray::new(from, p - from),
            0.0,
            f32::INFINITY,
        ));
        let diag = Vec3::new(
            if r.below(2) == 0 { 1.0 } else { -1.0 },
            if r.below(2) == 0 { 1.0 } else { -1.0 },
            if r.below(2) == 0 { 1.0 } else { -1.0 },
        );
        let d = if r.below(2) == 0 { diag } else { r.unit() };
        rays.push(("from a cell corner", Ray::new(p, d), 0.0, f32::INFINITY));
    }
    rays
}

/// Same primitive at the same `t`, or a tie (two primitives at `t` equal
/// within 1e-4 relative: squares share edges, the quads' halves their
/// diagonal).
fn same(want: Option<(u32, f32)>, got: Option<(u32, f32)>) -> bool {
    match (want, got) {
        (None, None) => true,
        (Some((wp, wt)), Some((gp, gt))) if wp == gp => wt == gt,
        (Some((_, wt)), Some((_, gt))) => (wt - gt).abs() <= 1e-4 * wt.abs().max(gt.abs()),
        _ => false,
    }
}

#[test]
fn edge_rays_agree_with_brute_force_for_every_accelerator() {
    let scene = lattice_scene();
    let opts = |accel| BuildOptions {
        accel,
        flatten: true,
    };
    let brute = World::build_world_space(&scene, opts(AccelKind::None));
    let ids: Vec<u32> = (0..brute.prims().len() as u32).collect();
    let mut c = Counters::default();
    for res in [[4, 4, 4], [8, 8, 8], [3, 5, 7]] {
        let lattice = *Grid::new(brute.prims(), ids.clone(), Some(res)).lattice();
        let rays = edge_rays(&lattice);
        let answers: Vec<_> = rays
            .iter()
            .map(|(_, ray, t0, t1)| {
                (
                    brute
                        .intersect(ray, *t0, *t1, &mut c)
                        .map(|h| (h.prim, h.t)),
                    brute.occluded(ray, *t0, *t1, &mut c),
                )
            })
            .collect();
        let hits = answers.iter().filter(|a| a.0.is_some()).count();
        assert!(
            hits > rays.len() / 4,
            "{res:?}: only {hits} of {} rays hit",
            rays.len()
        );
        for accel in accelerators() {
            let world = World::build_world_space(&scene, opts(accel));
            for ((family, ray, t0, t1), (want, want_occ)) in rays.iter().zip(&answers) {
                let got = world
                    .intersect(ray, *t0, *t1, &mut c)
                    .map(|h| (h.prim, h.t));
                assert!(
                    same(*want, got),
                    "{accel}, lattice {res:?}, ray {family}: {ray:?} in ({t0}, {t1})\n\
                     brute force {want:?}, {accel} {got:?}"
                );
                assert_eq!(
                    *want_occ,
                    world.occluded(ray, *t0, *t1, &mut c),
                    "{accel}, lattice {res:?}, occlusion of a ray {family}: {ray:?} in ({t0}, {t1})"
                );
            }
        }
    }
}

/// A scene where the first cell holding a candidate is usually not the cell
/// of the hit: a long floor (two triangles spanning the whole grid) under a
/// row of balls, seen from low down. A ray to a ball's lower half first
/// crosses cells the floor passes through, and the floor's hit lies behind
/// the ball, cells later. A grid that accepts the first cell's best hit
/// draws floor where the balls' lower halves are.
fn balls_on_a_floor() -> Scene {
    let floor = |a: Vec3, b: Vec3, c: Vec3| Node::Shape {
        shape: ShapeDesc::Triangle([a.as_dvec3(), b.as_dvec3(), c.as_dvec3()]),
        material: Some(0),
    };
    let (p0, p1, p2, p3) = (
        Vec3::new(-8.0, 0.0, -8.0),
        Vec3::new(8.0, 0.0, -8.0),
        Vec3::new(8.0, 0.0, 8.0),
        Vec3::new(-8.0, 0.0, 8.0),
    );
    let mut kids = vec![floor(p0, p2, p1), floor(p0, p3, p2)];
    for i in 0..5 {
        kids.push(Node::Shape {
            shape: ShapeDesc::Sphere {
                center: Vec3::new(-6.0 + 3.0 * i as f32, 1.0, -2.0 + i as f32).as_dvec3(),
                radius: 1.0,
            },
            material: Some(1),
        });
    }
    Scene {
        camera: Camera::Perspective {
            center: Vec3::new(0.0, 1.5, 14.0).as_dvec3(),
            direction: Vec3::new(0.0, -0.12, -1.0),
            up: Vec3::Y,
            angle_deg: 50.0,
        },
        lights: vec![Light::Directional {
            direction: Vec3::new(-0.3, -1.0, -0.5),
            color: Vec3::ONE,
        }],
        background: Background {
            color: Vec3::splat(0.2),
            ambient: Vec3::splat(0.1),
        },
        materials: vec![
            Material::Phong(Phong {
                diffuse: Vec3::new(0.9, 0.9, 0.2),
                ..Phong::default()
            }),
            Material::Phong(Phong {
                diffuse: Vec3::new(0.2, 0.3, 0.9),
                ..Phong::default()
            }),
        ],
        root: Node::Group(kids),
        effects: Default::default(),
    }
}

/// End to end: every accelerator draws the balls-on-a-floor picture exactly
/// as brute force does (same primitive, same `t`, so the same colour).
#[test]
fn balls_on_a_floor_render_alike_with_every_accelerator() {
    let scene = balls_on_a_floor();
    let size = (96, 64);
    let draw = |accel| {
        let world = World::build(
            &scene,
            BuildOptions {
                accel,
                flatten: true,
            },
        );
        let cam = CameraModel::new(world.camera());
        let w = Whitted {
            shadows: true,
            ..Whitted::default()
        };
        render(&world, &cam, &w, size, PixelOffset::CENTER).0.color
    };
    let want = draw(AccelKind::None);
    let ball = Vec3::new(0.2, 0.3, 0.9);
    let ball_pixels = want
        .iter()
        .filter(|c| c.z > c.x && (c.z - c.x) > 0.05 * ball.z)
        .count();
    assert!(
        ball_pixels > 300,
        "the balls should fill the picture: {ball_pixels}"
    );
    for accel in accelerators() {
        let got = draw(accel);
        let wrong = got
            .iter()
            .zip(&want)
            .filter(|(g, w)| (**g - **w).abs().max_element() > 1e-6)
            .count();
        assert_eq!(
            wrong,
            0,
            "{accel}: {wrong} of {} pixels differ from brute force",
            want.len()
        );
    }
}
