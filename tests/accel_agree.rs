//! Every accelerator must return exactly the hit brute force returns.
//!
//! Deterministic random scenes (a seeded generator, so any failure is
//! reproducible from the scene number and ray index it prints) are built as
//! `glint::scene::Scene` trees: spheres, single triangles, shared meshes,
//! planes, nested transforms with non-uniform scale and mirroring (so some
//! primitives stay `ShapeDesc::Transformed`), plus the awkward cases: flat
//! scenes, duplicated geometry, a dense cluster beside sparse objects, an
//! axis-aligned lattice probed by axis-parallel rays along its planes, far
//! from the origin, empty. Rays start inside and outside the bounds, with
//! random, axis-parallel (also `-0.0` components) or aimed directions, and
//! random `[tmin, tmax]` ranges.
//!
//! What "the same hit" means: the same primitive at the bit-identical `t`
//! (the same primitive computes the same root). Different primitives are
//! accepted only when their `t` agree within `1e-4` relative: coincident
//! triangles (one mesh instanced twice under one transform) are a genuine tie
//! that brute force breaks by list order and an accelerator by visit order.
//! The occlusion answer must be identical.
//!
//! Each test covers one accelerator (they run in parallel) over
//! `SCENES × RAYS_PER_SCENE` = 120,000 rays.

use crate::common::Rng;
use glint::accel::{AccelKind, Aggregate, Grid, Split};
use glint::math::{Keyframe, Mat4, Motion, Quat, Ray, Vec3};
use glint::scene::{Background, Camera, Mesh, Node, Scene, ShapeDesc};
use glint::stats::Counters;
use glint::world::{BuildOptions, World};
use rayon::prelude::*;
use std::sync::{Arc, OnceLock};

const SCENES: u64 = 48;
const RAYS_PER_SCENE: usize = 2500;

/// Scenes to check: [`SCENES`], or `ACCEL_AGREE_SCENES` for a longer soak
/// (`ACCEL_AGREE_SCENES=2000 cargo test --test suite accel_agree::`).
fn scene_count() -> u64 {
    std::env::var("ACCEL_AGREE_SCENES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(SCENES)
}

// ---------------------------------------------------------------------------
// Scenes

fn shape(shape: ShapeDesc) -> Node {
    Node::Shape {
        shape,
        material: None,
    }
}

fn xf(matrix: Mat4, child: Node) -> Node {
    Node::Transform {
        matrix: matrix.as_dmat4(),
        child: Box::new(child),
    }
}

fn sphere(c: Vec3, r: f32) -> Node {
    shape(ShapeDesc::Sphere {
        center: c.as_dvec3(),
        radius: r,
    })
}

fn triangle(a: Vec3, b: Vec3, c: Vec3) -> Node {
    shape(ShapeDesc::Triangle([
        a.as_dvec3(),
        b.as_dvec3(),
        c.as_dvec3(),
    ]))
}

/// A mesh of `n` random triangles over `k` shared vertices in a box of size
/// `size` around `at` (repeated indices make a few degenerate triangles).
fn random_mesh(r: &mut Rng, at: Vec3, size: f32, k: usize, n: usize) -> Arc<Mesh> {
    let positions = (0..k).map(|_| at + r.v(-size, size)).collect();
    let triangles = (0..n).map(|_| [0; 3].map(|_| r.below(k) as u32)).collect();
    Arc::new(Mesh {
        positions,
        triangles,
        ..Mesh::default()
    })
}

/// A random affine matrix: translation, rotation, and sometimes a
/// non-uniform scale or a mirror.
fn random_matrix(r: &mut Rng) -> Mat4 {
    let t = Mat4::from_translation(r.v(-4.0, 4.0));
    let rot = Mat4::from_axis_angle(r.unit(), r.range(0.0, 6.3));
    let scale = match r.below(4) {
        0 => Vec3::ONE,
        1 => Vec3::splat(r.range(0.3, 2.0)),
        2 => Vec3::new(r.range(0.3, 2.0), r.range(0.3, 2.0), r.range(0.3, 2.0)),
        _ => Vec3::new(-r.range(0.5, 1.5), r.range(0.5, 1.5), r.range(0.5, 1.5)),
    };
    t * rot * Mat4::from_scale(scale)
}

fn random_node(r: &mut Rng, depth: u32, budget: &mut usize) -> Node {
    let pick = if depth >= 3 { r.below(4) } else { r.below(7) };
    match pick {
        0 => {
            *budget = budget.saturating_sub(1);
            sphere(r.v(-5.0, 5.0), r.range(0.05, 1.5))
        }
        1 => {
            *budget = budget.saturating_sub(1);
            let a = r.v(-5.0, 5.0);
            let s = if r.chance(0.2) { 6.0 } else { 1.0 };
            triangle(a, a + r.v(-s, s), a + r.v(-s, s))
        }
        2 | 3 => {
            let n = 5 + r.below(60);
            *budget = budget.saturating_sub(n);
            let k = 3 + r.below(30);
            let (at, size) = (r.v(-4.0, 4.0), r.range(0.3, 3.0));
            shape(ShapeDesc::Mesh(random_mesh(r, at, size, k, n)))
        }
        4 | 5 => {
            let child = random_node(r, depth + 1, budget);
            xf(random_matrix(r), child)
        }
        _ => {
            let n = 2 + r.below(4);
            Node::Group((0..n).map(|_| random_node(r, depth + 1, budget)).collect())
        }
    }
}

/// Random objects, nested transforms, a plane now and then.
fn mixed(r: &mut Rng) -> Node {
    let mut budget = 30 + r.below(300);
    let mut kids = Vec::new();
    while budget > 0 {
        kids.push(random_node(r, 0, &mut budget));
    }
    if r.chance(0.5) {
        kids.push(shape(ShapeDesc::Plane {
            normal: r.unit(),
            offset: f64::from(r.range(-6.0, 6.0)),
        }));
    }
    // Drawn after everything above, so the scenes' other contents are as
    // before: an axis-aligned plane (bounded along its normal) and a deep
    // tree of transformed groups (the modeling hierarchy `bvh-hierarchy`
    // follows).
    if r.chance(0.3) {
        let mut normal = Vec3::ZERO;
        normal[r.below(3)] = if r.chance(0.5) { 1.0 } else { -2.0 };
        kids.push(shape(ShapeDesc::Plane {
            normal,
            offset: f64::from(r.range(-6.0, 6.0)),
        }));
    }
    if r.chance(0.5) {
        let depth = 3 + r.below(3) as u32;
        kids.push(deep_tree(r, depth));
    }
    Node::Group(kids)
}

/// A binary tree of transformed groups `depth` levels deep, with a sphere
/// or a small mesh at each leaf; mild matrices (some non-uniform or
/// mirroring) so that it stays a few units across.
fn deep_tree(r: &mut Rng, depth: u32) -> Node {
    if depth == 0 {
        return if r.chance(0.4) {
            sphere(r.v(-0.5, 0.5), r.range(0.1, 0.6))
        } else {
            let n = 3 + r.below(12);
            shape(ShapeDesc::Mesh(random_mesh(r, Vec3::ZERO, 0.7, 8, n)))
        };
    }
    let scale = match r.below(3) {
        0 => Vec3::splat(r.range(0.6, 1.0)),
        1 => Vec3::new(r.range(0.6, 1.1), r.range(0.6, 1.1), r.range(0.6, 1.1)),
        _ => Vec3::new(-r.range(0.7, 1.0), r.range(0.7, 1.0), r.range(0.7, 1.0)),
    };
    let m = Mat4::from_translation(r.v(-1.5, 1.5))
        * Mat4::from_axis_angle(r.unit(), r.range(0.0, 6.3))
        * Mat4::from_scale(scale);
    let kids = (0..2).map(|_| deep_tree(r, depth - 1)).collect();
    xf(m, Node::Group(kids))
}

/// Everything in one plane `z = c`: the bounds have zero thickness.
fn flat(r: &mut Rng) -> Node {
    let z = r.range(-2.0, 2.0);
    let n = 20 + r.below(300);
    let mut positions = Vec::new();
    for _ in 0..n {
        let a = Vec3::new(r.range(-5.0, 5.0), r.range(-5.0, 5.0), z);
        let mut near = || a + Vec3::new(r.range(-1.5, 1.5), r.range(-1.5, 1.5), 0.0);
        positions.extend([a, near(), near()]);
    }
    let mesh = Mesh {
        positions,
        triangles: (0..n as u32)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect(),
        ..Mesh::default()
    };
    Node::Group(vec![shape(ShapeDesc::Mesh(Arc::new(mesh)))])
}

/// One mesh used three times, twice under the same matrix (exact ties), and
/// a mesh holding each of its triangles twice.
fn shared(r: &mut Rng) -> Node {
    let mesh = random_mesh(r, Vec3::ZERO, 3.0, 40, 100);
    let m = random_matrix(r);
    let mut doubled = (*random_mesh(r, Vec3::ONE, 2.0, 20, 60)).clone();
    doubled.triangles.extend(doubled.triangles.clone());
    Node::Group(vec![
        xf(m, shape(ShapeDesc::Mesh(mesh.clone()))),
        xf(m, shape(ShapeDesc::Mesh(mesh.clone()))),
        xf(random_matrix(r), shape(ShapeDesc::Mesh(mesh))),
        shape(ShapeDesc::Mesh(Arc::new(doubled))),
        sphere(Vec3::ZERO, 1.0),
        sphere(Vec3::ZERO, 1.0),
    ])
}

/// Many tiny triangles in a small region plus big, sparse spheres: the
/// uniform grid's worst case, the octree's and BVH's home ground.
fn clustered(r: &mut Rng) -> Node {
    let at = r.v(-1.0, 1.0);
    let mut kids = vec![shape(ShapeDesc::Mesh(random_mesh(r, at, 0.05, 200, 250)))];
    for _ in 0..8 {
        kids.push(sphere(r.v(-20.0, 20.0), r.range(0.5, 3.0)));
    }
    Node::Group(kids)
}

/// Axis-aligned unit squares on the integer planes of [0, 4]³: surfaces lie
/// on cell and octant boundaries, and integer rays run along them.
fn lattice(r: &mut Rng) -> Node {
    let mut kids = Vec::new();
    for _ in 0..60 {
        let axis = r.below(3);
        let mut o = [r.below(4) as f32, r.below(4) as f32, r.below(4) as f32];
        o[axis] = r.below(5) as f32;
        let o = Vec3::from(o);
        let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
        kids.push(triangle(o, o + u, o + u + v));
        kids.push(triangle(o, o + u + v, o + v));
    }
    for _ in 0..5 {
        let c = Vec3::new(r.below(5) as f32, r.below(5) as f32, r.below(5) as f32);
        kids.push(sphere(c, 0.5));
    }
    Node::Group(kids)
}

fn scene(seed: u64) -> (Scene, bool) {
    let mut r = Rng::new(seed);
    let mut lattice_rays = false;
    let root = match seed {
        0 => Node::Group(vec![]),
        1 => sphere(Vec3::ZERO, 1.0),
        2 => shape(ShapeDesc::Plane {
            normal: Vec3::Y,
            offset: 0.0,
        }),
        _ => match seed % 6 {
            0 | 1 => mixed(&mut r),
            2 => flat(&mut r),
            3 => shared(&mut r),
            4 => clustered(&mut r),
            _ => {
                lattice_rays = true;
                lattice(&mut r)
            }
        },
    };
    // Every fourth scene lives far from the origin, where ulps are coarse.
    let root = if seed % 4 == 3 {
        xf(
            Mat4::from_translation(Vec3::new(1000.0, -300.0, 50.0)),
            root,
        )
    } else {
        root
    };
    let scene = Scene {
        camera: Camera::Perspective {
            center: (Vec3::Z * 10.0).as_dvec3(),
            direction: Vec3::NEG_Z,
            up: Vec3::Y,
            angle_deg: 40.0,
        },
        lights: vec![],
        background: Background::default(),
        materials: vec![],
        root,
        effects: Default::default(),
    };
    (scene, lattice_rays && seed % 4 != 3)
}

// ---------------------------------------------------------------------------
// Rays

struct Query {
    ray: Ray,
    tmin: f32,
    tmax: f32,
}

fn random_query(r: &mut Rng, world: &World, lattice: bool) -> Query {
    let b = world.bounds();
    let (lo, hi) = if b.is_empty() {
        (Vec3::splat(-1.0), Vec3::splat(1.0))
    } else {
        (b.min, b.max)
    };
    let size = (hi - lo).max(Vec3::splat(1e-3));
    let inside = |r: &mut Rng| lo + Vec3::new(r.f(), r.f(), r.f()) * size;
    let axes = [
        Vec3::X,
        Vec3::Y,
        Vec3::Z,
        Vec3::NEG_X,
        Vec3::NEG_Y,
        Vec3::NEG_Z,
    ];

    let origin = if lattice && r.chance(0.5) {
        // On the lattice's planes, edges and corners.
        Vec3::new(
            r.below(9) as f32 * 0.5,
            r.below(9) as f32 * 0.5,
            r.below(9) as f32 * 0.5,
        ) + if r.chance(0.5) {
            Vec3::ZERO
        } else {
            Vec3::X * -1.0
        }
    } else if r.chance(0.4) {
        inside(r)
    } else {
        let c = 0.5 * (lo + hi);
        c + (inside(r) - c) * r.range(1.2, 4.0)
    };
    let dir = match r.below(6) {
        0 => axes[r.below(6)],
        1 => {
            // One component exactly zero (sometimes negative zero).
            let mut d = r.unit();
            d[r.below(3)] = if r.chance(0.5) { 0.0 } else { -0.0 };
            if d == Vec3::ZERO {
                Vec3::X
            } else {
                d
            }
        }
        2 | 3 => {
            let d = inside(r) - origin;
            if d.length() > 1e-6 {
                d * r.range(0.1, 3.0) // not unit length on purpose
            } else {
                Vec3::Y
            }
        }
        _ => r.unit(),
    };
    let span = size.length() * 3.0 / dir.length();
    let (tmin, tmax) = match r.below(5) {
        0 => {
            let a = r.range(0.0, span);
            (a, a + r.range(0.0, span))
        }
        1 => (r.range(0.0, span), f32::INFINITY),
        2 => (0.0, r.range(0.0, span)),
        _ => (0.0, f32::INFINITY),
    };
    Query {
        ray: Ray::new(origin, dir),
        tmin,
        tmax,
    }
}

// ---------------------------------------------------------------------------
// Comparison

fn same_hit(want: Option<(u32, f32)>, got: Option<(u32, f32)>, ties: &mut usize) -> bool {
    match (want, got) {
        (None, None) => true,
        (Some((wp, wt)), Some((gp, gt))) if wp == gp => wt == gt,
        (Some((_, wt)), Some((_, gt))) => {
            *ties += 1;
            (wt - gt).abs() <= 1e-4 * wt.abs().max(gt.abs())
        }
        _ => false,
    }
}

/// One scene with its rays and brute force's answers to them.
struct Case {
    seed: u64,
    scene: Scene,
    queries: Vec<Query>,
    /// Closest hit (primitive, t) and occlusion, per query.
    answers: Vec<(Option<(u32, f32)>, bool)>,
}

/// The scenes, rays and brute-force answers, computed once per flattening
/// mode and shared by the tests (brute force is most of the work).
fn oracle(flatten: bool) -> &'static (Vec<Case>, Counters) {
    static FLAT: OnceLock<(Vec<Case>, Counters)> = OnceLock::new();
    static NESTED: OnceLock<(Vec<Case>, Counters)> = OnceLock::new();
    let cell = if flatten { &FLAT } else { &NESTED };
    cell.get_or_init(|| {
        let cases: Vec<(Case, Counters)> = (0..scene_count())
            .into_par_iter()
            .map(|seed| {
                let (scene, lattice) = scene(seed);
                let brute = World::build(
                    &scene,
                    BuildOptions {
                        accel: AccelKind::None,
                        flatten,
                    },
                );
                let mut r = Rng::new(seed ^ 0xabcdef);
                let mut c = Counters::default();
                let queries: Vec<Query> = (0..RAYS_PER_SCENE)
                    .map(|_| random_query(&mut r, &brute, lattice))
                    .collect();
                let answers = queries
                    .iter()
                    .map(|q| {
                        let hit = brute.intersect(&q.ray, q.tmin, q.tmax, &mut c);
                        let occ = brute.occluded(&q.ray, q.tmin, q.tmax, &mut c);
                        (hit.map(|h| (h.prim, h.t)), occ)
                    })
                    .collect();
                let case = Case {
                    seed,
                    scene,
                    queries,
                    answers,
                };
                (case, c)
            })
            .collect();
        let mut total = Counters::default();
        let cases = cases
            .into_iter()
            .map(|(case, c)| {
                total += c;
                case
            })
            .collect();
        (cases, total)
    })
}

/// Checks `accel` against brute force over every scene; returns the
/// counters of both, for the cost comparison printed with `--nocapture`.
fn check(accel: AccelKind, flatten: bool) -> (Counters, Counters) {
    let (cases, brute_counters) = oracle(flatten);
    let mut ca = Counters::default();
    let mut ties = 0;
    let mut rays = 0;
    for case in cases {
        let world = World::build(&case.scene, BuildOptions { accel, flatten });
        for (i, (q, &(want, want_occ))) in case.queries.iter().zip(&case.answers).enumerate() {
            let got = world
                .intersect(&q.ray, q.tmin, q.tmax, &mut ca)
                .map(|h| (h.prim, h.t));
            assert!(
                same_hit(want, got, &mut ties),
                "{accel:?} (flatten {flatten}), scene {}, ray {i}: {:?} in ({}, {})\n\
                 brute: {want:?}\n{}: {got:?}",
                case.seed,
                q.ray,
                q.tmin,
                q.tmax,
                world.accel().describe(),
            );
            let got = world.occluded(&q.ray, q.tmin, q.tmax, &mut ca);
            assert_eq!(
                want_occ, got,
                "{accel:?} (flatten {flatten}), scene {}, ray {i}: occlusion of {:?} in ({}, {})",
                case.seed, q.ray, q.tmin, q.tmax
            );
            rays += 1;
        }
    }
    assert!(rays >= 100_000 || scene_count() < SCENES);
    println!(
        "{accel} (flatten {flatten}): {rays} rays, {ties} ties between coincident primitives; \
         tests/ray {:.1} (brute {:.1}), nodes/ray {:.1}",
        ca.intersection_tests as f64 / (2 * rays) as f64,
        brute_counters.intersection_tests as f64 / (2 * rays) as f64,
        ca.nodes_visited as f64 / (2 * rays) as f64,
    );
    (ca, *brute_counters)
}

#[test]
fn grid_automatic() {
    let (a, b) = check(AccelKind::Grid { res: None }, true);
    assert!(a.intersection_tests < b.intersection_tests);
}

#[test]
fn grid_single_cell() {
    check(
        AccelKind::Grid {
            res: Some([1, 1, 1]),
        },
        true,
    );
}

#[test]
fn grid_fixed_resolutions() {
    check(
        AccelKind::Grid {
            res: Some([3, 5, 2]),
        },
        true,
    );
    check(
        AccelKind::Grid {
            res: Some([4, 4, 4]),
        },
        true,
    );
    check(
        AccelKind::Grid {
            res: Some([32, 1, 17]),
        },
        true,
    );
}

#[test]
fn octree() {
    let (a, b) = check(AccelKind::Octree, true);
    assert!(a.intersection_tests < b.intersection_tests);
}

#[test]
fn bvh_sah() {
    let (a, b) = check(AccelKind::Bvh(Split::Sah), true);
    assert!(a.intersection_tests < b.intersection_tests);
}

#[test]
fn bvh8() {
    let (a, b) = check(AccelKind::Bvh8, true);
    assert!(a.intersection_tests < b.intersection_tests);
}

#[test]
fn bvh8_unflattened() {
    check(AccelKind::Bvh8, false);
}

#[test]
fn bvh_median() {
    check(AccelKind::Bvh(Split::Median), true);
}

#[test]
fn bvh_midpoint() {
    check(AccelKind::Bvh(Split::Midpoint), true);
}

/// Without flattening, triangles and spheres stay `ShapeDesc::Transformed`.
#[test]
fn unflattened_worlds() {
    check(AccelKind::Bvh(Split::Sah), false);
    check(AccelKind::Grid { res: None }, false);
}

#[test]
fn octree_inner() {
    let (a, b) = check(AccelKind::OctreeInner, true);
    assert!(a.intersection_tests < b.intersection_tests);
}

#[test]
fn nested_grid() {
    let (a, b) = check(AccelKind::NESTED_GRID, true);
    assert!(a.intersection_tests < b.intersection_tests);
    for (threshold, depth) in [(1, 3), (4, 1)] {
        check(AccelKind::NestedGrid { threshold, depth }, true);
    }
}

#[test]
fn bvh_hierarchy() {
    let (a, b) = check(AccelKind::BvhHierarchy, true);
    assert!(a.intersection_tests < b.intersection_tests);
}

/// The new accelerators over `Transformed` wrappers; the hierarchy BVH then
/// carries rays into its transform nodes' spaces.
#[test]
fn unflattened_new_accelerators() {
    let (a, b) = check(AccelKind::BvhHierarchy, false);
    assert!(a.intersection_tests < b.intersection_tests);
    check(AccelKind::OctreeInner, false);
    check(AccelKind::NESTED_GRID, false);
}

/// Cost of each accelerator on two 10k-triangle scenes, from the counters:
/// `cargo test --release --test suite accel_agree::cost_report -- --ignored --nocapture`.
#[test]
#[ignore]
fn cost_report() {
    let mut r = Rng::new(99);
    // A soup of small random triangles in a 10-unit box, and a finely
    // tessellated sphere (a closed surface, as real meshes are).
    let soup = random_mesh(&mut r, Vec3::ZERO, 5.0, 30_000, 0);
    let mut soup = (*soup).clone();
    soup.triangles = (0..10_000u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    for t in 0..10_000 {
        let a = soup.positions[3 * t];
        soup.positions[3 * t + 1] = a + r.v(-0.4, 0.4);
        soup.positions[3 * t + 2] = a + r.v(-0.4, 0.4);
    }
    let (nu, nv) = (100u32, 50u32);
    let mut ball = Mesh::default();
    for j in 0..=nv {
        for i in 0..nu {
            let (th, ph) = (
                std::f32::consts::PI * j as f32 / nv as f32,
                std::f32::consts::TAU * i as f32 / nu as f32,
            );
            ball.positions
                .push(4.0 * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()));
        }
    }
    for j in 0..nv {
        for i in 0..nu {
            let (a, b) = (j * nu + i, j * nu + (i + 1) % nu);
            ball.triangles.push([a, b + nu, b]);
            ball.triangles.push([a, a + nu, b + nu]);
        }
    }
    for (name, mesh) in [("soup", soup), ("sphere", ball)] {
        let (sc, _) = scene(1);
        let sc = Scene {
            root: shape(ShapeDesc::Mesh(Arc::new(mesh))),
            ..sc
        };
        let kinds = [
            AccelKind::None,
            AccelKind::Grid { res: None },
            AccelKind::Octree,
            AccelKind::Bvh(Split::Midpoint),
            AccelKind::Bvh(Split::Median),
            AccelKind::Bvh(Split::Sah),
            AccelKind::OctreeInner,
            AccelKind::NESTED_GRID,
            AccelKind::BvhHierarchy,
            AccelKind::Bvh8,
        ];
        let mut rq = Rng::new(5);
        let probe = World::build(&sc, BuildOptions::default());
        let queries: Vec<Query> = (0..20_000)
            .map(|_| random_query(&mut rq, &probe, false))
            .collect();
        for accel in kinds {
            let w = World::build(
                &sc,
                BuildOptions {
                    accel,
                    flatten: true,
                },
            );
            let mut c = Counters::default();
            let start = std::time::Instant::now();
            let mut hits = 0;
            for q in &queries {
                hits += w.intersect(&q.ray, q.tmin, q.tmax, &mut c).is_some() as usize;
            }
            let us = start.elapsed().as_secs_f64() * 1e6 / queries.len() as f64;
            let n = queries.len() as f64;
            println!(
                "{name:6} {:32} build {:7.1} ms  tests/ray {:8.1}  nodes/ray {:6.1}  {us:6.2} µs/ray  ({hits} hits)",
                w.accel().describe(),
                w.build_ms(),
                c.intersection_tests as f64 / n,
                c.nodes_visited as f64 / n,
            );
        }
        // What mailboxing saves: the same grid with and without it.
        let w = World::build(&sc, BuildOptions::default());
        let ids: Vec<u32> = (0..w.prims().len() as u32).collect();
        for res in [None, Some([128, 128, 128])] {
            let mut grid = Grid::new(w.prims(), ids.clone(), res);
            for on in [true, false] {
                grid.set_mailbox(on);
                let mut c = Counters::default();
                for q in &queries {
                    grid.intersect(
                        glint::accel::Query::new(w.prims(), &q.ray, q.tmin, q.tmax),
                        &mut c,
                    );
                }
                println!(
                    "{name:6} {:32} mailbox {on:5}  tests/ray {:8.2}",
                    grid.describe(),
                    c.intersection_tests as f64 / queries.len() as f64
                );
            }
        }
    }
}

// ---------------------------------------------------------------------------
// Motion blur: moving objects and timed rays

/// A random keyframed motion over [0, 1]: two to four poses with
/// translation, rotation and (sometimes non-uniform) scale.
fn random_motion(r: &mut Rng) -> Arc<Motion> {
    let n = 2 + r.below(3);
    let keys = (0..n)
        .map(|i| Keyframe {
            time: i as f32 / (n - 1) as f32,
            translation: r.v(-3.0, 3.0),
            rotation: Quat::from_axis_angle(r.unit(), r.range(0.0, 3.0)),
            scale: if r.chance(0.5) {
                Vec3::splat(r.range(0.5, 1.5))
            } else {
                Vec3::new(r.range(0.5, 1.5), r.range(0.5, 1.5), r.range(0.5, 1.5))
            },
        })
        .collect();
    Arc::new(Motion::new(keys).expect("increasing times"))
}

/// Static objects beside moving ones (some nested in a static transform,
/// some moving inside a moving parent).
fn moving_scene(seed: u64) -> Scene {
    let mut r = Rng::new(seed ^ 0x6d6f7665);
    let mut budget = 20 + r.below(120);
    let mut kids = Vec::new();
    while budget > 0 {
        let node = random_node(&mut r, 1, &mut budget);
        kids.push(match r.below(4) {
            0 => node,
            1 => xf(
                random_matrix(&mut r),
                Node::Moving {
                    motion: random_motion(&mut r),
                    child: Box::new(node),
                },
            ),
            2 => Node::Moving {
                motion: random_motion(&mut r),
                child: Box::new(Node::Moving {
                    motion: random_motion(&mut r),
                    child: Box::new(node),
                }),
            },
            _ => Node::Moving {
                motion: random_motion(&mut r),
                child: Box::new(node),
            },
        });
    }
    let (base, _) = scene(1);
    Scene {
        root: Node::Group(kids),
        ..base
    }
}

/// Where the middle of `shape` is at `time` (its box centre carried along
/// its motion); `None` for unbounded shapes.
fn center_at(shape: &glint::shape::Shape, time: f32) -> Option<Vec3> {
    match shape {
        glint::shape::Shape::Moving(m) => {
            let inner = center_at(&m.shape, time)?;
            Some((m.parent * m.motion.matrix(time)).transform_point3(inner))
        }
        other => {
            let b = other.bounds();
            b.is_finite().then(|| b.center())
        }
    }
}

/// Every accelerator agrees with brute force on timed rays through moving
/// objects, whose boxes cover their whole path.
#[test]
fn moving_objects_and_timed_rays() {
    let kinds = [
        AccelKind::Grid { res: None },
        AccelKind::Grid {
            res: Some([7, 3, 5]),
        },
        AccelKind::Octree,
        AccelKind::Bvh(Split::Sah),
        AccelKind::Bvh(Split::Median),
        AccelKind::Bvh(Split::Midpoint),
        AccelKind::Bvh8,
        AccelKind::BvhHierarchy,
        AccelKind::OctreeInner,
        AccelKind::NestedGrid {
            threshold: 16,
            depth: 2,
        },
    ];
    let mut rays = 0;
    let mut hits = 0;
    for seed in 0..24u64 {
        let sc = moving_scene(seed);
        for flatten in [true, false] {
            let opts = |accel| BuildOptions { accel, flatten };
            let brute = World::build(&sc, opts(AccelKind::None));
            let worlds: Vec<World> = kinds.iter().map(|&k| World::build(&sc, opts(k))).collect();
            let mut r = Rng::new(seed ^ 0x7173);
            let mut c = Counters::default();
            for i in 0..600 {
                let q = random_query(&mut r, &brute, false);
                let time = r.f();
                // Half the rays aim at where a random primitive is at their time.
                let aim = if r.chance(0.5) && !brute.prims().is_empty() {
                    center_at(&brute.prims()[r.below(brute.prims().len())].shape, time)
                        .filter(|c| c.is_finite() && (*c - q.ray.origin).length() > 1e-3)
                } else {
                    None
                };
                let ray = match aim {
                    Some(c) => Ray::new(q.ray.origin, c - q.ray.origin).at_time(time),
                    None => q.ray.at_time(time),
                };
                let want = brute.intersect(&ray, q.tmin, q.tmax, &mut c);
                let want_occ = brute.occluded(&ray, q.tmin, q.tmax, &mut c);
                hits += usize::from(want.is_some());
                for w in &worlds {
                    let got = w.intersect(&ray, q.tmin, q.tmax, &mut c);
                    let mut ties = 0;
                    assert!(
                        same_hit(
                            want.map(|h| (h.prim, h.t)),
                            got.map(|h| (h.prim, h.t)),
                            &mut ties
                        ),
                        "{} (flatten {flatten}), moving scene {seed}, ray {i}: {ray:?}\n\
                         brute {want:?}\ngot {got:?}",
                        w.accel().describe()
                    );
                    assert_eq!(
                        want_occ,
                        w.occluded(&ray, q.tmin, q.tmax, &mut c),
                        "{} occlusion, moving scene {seed}, ray {i}",
                        w.accel().describe()
                    );
                }
                rays += 1;
            }
        }
    }
    println!(
        "moving objects: {rays} timed rays ({hits} hits) x {} accelerators",
        kinds.len()
    );
    assert!(hits > rays / 10, "too few hits to mean anything: {hits}");
}
