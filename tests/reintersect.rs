//! Re-intersection property test (as pbrt's): random rays hit random shapes
//! (spheres, ellipsoids kept as transformed shapes, ellipsoids under a
//! keyframed motion hit at one instant, triangles, planes, a closed triangle
//! mesh; flattened and with transforms kept) at random
//! positions up to 10⁵ from the origin and random sizes (10⁻³..10³); from
//! each hit, rays are spawned in random directions with
//! [`glint::world::Hit::spawn_ray`]:
//!
//! - a ray leaving a surface away from a convex closed shape's inside, or
//!   either way from an open one (a plane, a single triangle), must hit
//!   nothing (the world holds only that shape): any hit is a self-hit;
//! - a ray leaving into a closed shape's inside must hit its far side: a hit
//!   must exist, and for spheres and ellipsoids its `t` must be the far root
//!   of the exact (f64) intersection, not the near one at the spawn point.
//!
//! Sizes are kept at least 10⁻⁵ of the distance from the origin (one unit at
//! 10⁵, 128 f32 ulps there): a smaller object cannot be told apart from its
//! rounding in f32 at all. The world is built with its rendering-space origin
//! at the world origin, so the shapes really are far from it (the hard case;
//! camera-centred rendering space only helps).
//!
//! Deterministic (a seeded generator); a failure prints the case and seed.

use crate::common::Rng;
use glam::{DMat4, DVec3};
use glint::math::{Keyframe, Motion, Ray, Vec3};
use glint::scene::{Background, Camera, Mesh, Node, Scene, ShapeDesc};
use glint::stats::Counters;
use glint::world::{BuildOptions, Hit, World};
use std::sync::Arc;

/// A direction in the hemisphere around `n`, sometimes nearly tangent.
fn hemisphere(r: &mut Rng, n: DVec3) -> DVec3 {
    let mut w = r.unit64();
    if w.dot(n) < 0.0 {
        w = -w;
    }
    if r.f64() < 0.15 {
        // Grazing: tilt towards the tangent plane, down to 1e-7 of a radian.
        let tangent = (w - n * w.dot(n)).normalize_or_zero();
        let lift = r.log_range64(1e-7, 1e-2);
        w = (tangent + n * lift).normalize_or(n);
    }
    w
}

/// Where a shape is, and how large: a random position up to 10⁵ from the
/// origin (sometimes at it) and a size in 10⁻³..10³ not below 10⁻⁵ of it.
fn placement(r: &mut Rng) -> (DVec3, f64) {
    let pos = if r.f64() < 0.1 {
        DVec3::ZERO
    } else {
        r.unit64() * r.log_range64(1e-2, 1e5)
    };
    loop {
        let size = r.log_range64(1e-3, 1e3);
        if size >= 1e-5 * pos.length() {
            return (pos, size);
        }
    }
}

fn rotation(r: &mut Rng) -> DMat4 {
    DMat4::from_axis_angle(r.unit64(), r.range64(0.0, std::f64::consts::TAU))
}

/// The kinds of shape tried.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    Sphere,
    Ellipsoid,
    /// An ellipsoid under a keyframed motion (motion blur), hit at one
    /// instant of its path.
    MovingEllipsoid,
    Triangle,
    Plane,
    Cube,
}

/// One random shape: its scene node, its object-to-world matrix (f64) and
/// what it is.
struct Case {
    kind: Kind,
    node: Node,
    /// Object-to-world matrix of the unit shape (sphere, cube `[-1,1]³`).
    m: DMat4,
    /// Triangle: the vertices; plane: a point and the normal.
    pts: Vec<DVec3>,
    /// The instant of every ray (a moving shape's `m` is its pose then).
    time: f32,
}

fn node(shape: ShapeDesc) -> Node {
    Node::Shape {
        shape,
        material: None,
    }
}

fn xf(m: DMat4, child: Node) -> Node {
    Node::Transform {
        matrix: m,
        child: Box::new(child),
    }
}

fn f32v(v: DVec3) -> Vec3 {
    v.as_vec3()
}

fn cube_mesh() -> Mesh {
    Mesh {
        positions: (0..8)
            .map(|i| {
                Vec3::new(
                    (i & 1) as f32 * 2.0 - 1.0,
                    ((i >> 1) & 1) as f32 * 2.0 - 1.0,
                    ((i >> 2) & 1) as f32 * 2.0 - 1.0,
                )
            })
            .collect(),
        triangles: vec![
            [0, 2, 3],
            [0, 3, 1],
            [4, 5, 7],
            [4, 7, 6],
            [0, 1, 5],
            [0, 5, 4],
            [2, 6, 7],
            [2, 7, 3],
            [0, 4, 6],
            [0, 6, 2],
            [1, 3, 7],
            [1, 7, 5],
        ],
        ..Mesh::default()
    }
}

fn random_case(r: &mut Rng, kind: Kind) -> Case {
    let (pos, size) = placement(r);
    match kind {
        Kind::Sphere => {
            // Written directly in world coordinates (baked as written).
            let c = f32v(pos);
            let rad = size as f32;
            Case {
                kind,
                node: node(ShapeDesc::Sphere {
                    center: c.as_dvec3(),
                    radius: rad,
                }),
                m: DMat4::from_translation(c.as_dvec3())
                    * DMat4::from_scale(DVec3::splat(rad as f64)),
                pts: vec![],
                time: 0.0,
            }
        }
        Kind::Ellipsoid | Kind::Cube => {
            let scale = DVec3::new(
                size * r.range64(0.3, 3.0),
                size * r.range64(0.3, 3.0),
                size * r.range64(0.3, 3.0),
            );
            let m = DMat4::from_translation(pos) * rotation(r) * DMat4::from_scale(scale);
            let shape = if kind == Kind::Ellipsoid {
                ShapeDesc::Sphere {
                    center: Vec3::ZERO.as_dvec3(),
                    radius: 1.0,
                }
            } else {
                ShapeDesc::Mesh(Arc::new(cube_mesh()))
            };
            Case {
                kind,
                node: xf(m, node(shape)),
                m,
                pts: vec![],
                time: 0.0,
            }
        }
        Kind::MovingEllipsoid => {
            // Two poses a few sizes apart, turned and squashed differently;
            // the rays live at one instant between them.
            let key = |r: &mut Rng, time: f32| Keyframe {
                time,
                translation: f32v(pos + r.unit64() * size * r.range64(0.0, 3.0)),
                rotation: glam::DQuat::from_axis_angle(r.unit64(), r.range64(0.0, 6.0)).as_quat(),
                scale: f32v(DVec3::new(
                    size * r.range64(0.3, 3.0),
                    size * r.range64(0.3, 3.0),
                    size * r.range64(0.3, 3.0),
                )),
            };
            let motion = Motion::new(vec![key(r, 0.0), key(r, 1.0)]).expect("increasing times");
            let time = r.f64() as f32;
            // The pose glint interpolates (in f32), as an exact matrix.
            let (t, q, s) = motion.pose(time);
            let m =
                DMat4::from_scale_rotation_translation(s.as_dvec3(), q.as_dquat(), t.as_dvec3());
            let sphere = node(ShapeDesc::Sphere {
                center: Vec3::ZERO.as_dvec3(),
                radius: 1.0,
            });
            Case {
                kind,
                node: Node::Moving {
                    motion: Arc::new(motion),
                    child: Box::new(sphere),
                },
                m,
                pts: vec![],
                time,
            }
        }
        Kind::Triangle => {
            let rot = rotation(r);
            let corner = |r: &mut Rng| {
                f32v(
                    pos + rot.transform_vector3(
                        DVec3::new(r.range64(-1.0, 1.0), r.range64(-1.0, 1.0), 0.0) * size,
                    ),
                )
            };
            loop {
                let v = [corner(r), corner(r), corner(r)];
                let d = v.map(|p| p.as_dvec3());
                let area = (d[1] - d[0]).cross(d[2] - d[0]).length();
                if area > 0.2 * size * size {
                    return Case {
                        kind,
                        node: node(ShapeDesc::Triangle(v.map(|p| p.as_dvec3()))),
                        m: DMat4::IDENTITY,
                        pts: d.to_vec(),
                        time: 0.0,
                    };
                }
            }
        }
        Kind::Plane => {
            let n = f32v(r.unit64());
            let q = f32v(pos);
            let offset = n.dot(q);
            // The plane as glint stores it: unit normal, offset along it.
            let (nd, len) = (n.as_dvec3(), n.as_dvec3().length());
            Case {
                kind,
                node: node(ShapeDesc::Plane {
                    normal: n,
                    offset: f64::from(offset),
                }),
                m: DMat4::IDENTITY,
                pts: vec![
                    nd * (offset as f64 / len / len),
                    nd / len,
                    DVec3::splat(size),
                ],
                time: 0.0,
            }
        }
    }
}

fn scene(root: Node) -> Scene {
    Scene {
        camera: Camera::Perspective {
            center: Vec3::ZERO.as_dvec3(),
            direction: Vec3::NEG_Z,
            up: Vec3::Y,
            angle_deg: 40.0,
        },
        lights: vec![],
        background: Background::default(),
        materials: vec![],
        root,
        effects: Default::default(),
    }
}

/// A random point of the shape's surface (f64, exact) with its outward (or,
/// for open shapes, some) normal.
fn surface_point(r: &mut Rng, c: &Case) -> (DVec3, DVec3) {
    match c.kind {
        Kind::Sphere | Kind::Ellipsoid | Kind::MovingEllipsoid => {
            let u = r.unit64();
            let n = c.m.inverse().transpose().transform_vector3(u).normalize();
            (c.m.transform_point3(u), n)
        }
        Kind::Cube => {
            let axis = (r.u64() % 3) as usize;
            let sign = if r.f64() < 0.5 { -1.0 } else { 1.0 };
            let mut p = DVec3::new(
                r.range64(-1.0, 1.0),
                r.range64(-1.0, 1.0),
                r.range64(-1.0, 1.0),
            );
            p[axis] = sign;
            let mut n = DVec3::ZERO;
            n[axis] = sign;
            let n = c.m.inverse().transpose().transform_vector3(n).normalize();
            (c.m.transform_point3(p), n)
        }
        Kind::Triangle => {
            let (a, b) = (r.f64(), r.f64());
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let [p0, p1, p2] = [c.pts[0], c.pts[1], c.pts[2]];
            let n = (p1 - p0).cross(p2 - p0).normalize();
            (p0 + a * (p1 - p0) + b * (p2 - p0), n)
        }
        Kind::Plane => {
            let (q, n, size) = (c.pts[0], c.pts[1], c.pts[2].x);
            let t = (r.unit64() - n * r.unit64().dot(n)) * size;
            (q + t - n * t.dot(n), n)
        }
    }
}

fn closed(kind: Kind) -> bool {
    matches!(
        kind,
        Kind::Sphere | Kind::Ellipsoid | Kind::MovingEllipsoid | Kind::Cube
    )
}

/// The exact (f64) parameters where `ray` crosses the unit sphere / unit
/// cube behind `m`: `(t_enter, t_exit)`.
fn exact_span(c: &Case, ray: &Ray) -> Option<(f64, f64)> {
    let inv = c.m.inverse();
    let o = inv.transform_point3(ray.origin.as_dvec3());
    let d = inv.transform_vector3(ray.dir.as_dvec3());
    match c.kind {
        Kind::Sphere | Kind::Ellipsoid | Kind::MovingEllipsoid => {
            let a = d.dot(d);
            let b = o.dot(d);
            let perp = o - d * (b / a);
            let disc = a * (1.0 - perp.dot(perp));
            (disc >= 0.0).then(|| {
                let s = disc.sqrt();
                ((-b - s) / a, (-b + s) / a)
            })
        }
        Kind::Cube => {
            let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
            for i in 0..3 {
                let (a, b) = ((-1.0 - o[i]) / d[i], (1.0 - o[i]) / d[i]);
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            }
            (t0 <= t1).then_some((t0, t1))
        }
        _ => None,
    }
}

struct Tally {
    hits: usize,
    away: usize,
    into: usize,
    far_checked: usize,
    /// Inward rays from mesh hits so close to an edge that the offset left
    /// the mesh through the adjacent face.
    edge: usize,
}

/// Shoots `shots` rays at random points of the case's shape and checks the
/// rays spawned from each hit. Returns the failures (empty when all is well).
fn check_case(r: &mut Rng, c: &Case, world: &World, shots: usize, t: &mut Tally) -> Vec<String> {
    let mut fails = Vec::new();
    let mut counters = Counters::default();
    for _ in 0..shots {
        let (p, n) = surface_point(r, c);
        // From outside, or (closed shapes, sometimes) from inside.
        let inside = closed(c.kind) && r.f64() < 0.3;
        let side = if !closed(c.kind) && r.f64() < 0.5 {
            -n
        } else {
            n
        };
        let origin = if inside {
            c.m.transform_point3(r.unit64() * r.range64(0.0, 0.5))
        } else {
            p + hemisphere(r, side)
                * r.log_range64(0.05, 50.0)
                * c.m.transform_vector3(DVec3::ONE).length().max(1e-3)
        };
        let origin = if c.kind == Kind::Plane || c.kind == Kind::Triangle {
            let size = if c.kind == Kind::Plane {
                c.pts[2].x
            } else {
                (c.pts[1] - c.pts[0]).length()
            };
            p + hemisphere(r, side) * r.log_range64(0.05, 50.0) * size
        } else {
            origin
        };
        let ray = Ray::new(f32v(origin), f32v(p - origin)).at_time(c.time);
        let Some(h) = world.intersect(&ray, 0.0, f32::INFINITY, &mut counters) else {
            continue; // a grazing ray may miss: nothing to spawn from
        };
        t.hits += 1;
        for _ in 0..8 {
            let mut d = r.unit64();
            if r.f64() < 0.3 {
                // Nearly tangent to the surface, on either side.
                let nn = h.normal.as_dvec3();
                let tangent = (d - nn * d.dot(nn)).normalize_or_zero();
                let lift = r.log_range64(1e-7, 1e-2) * if r.f64() < 0.5 { -1.0 } else { 1.0 };
                d = (tangent + nn * lift).normalize_or(nn);
            }
            let dir = f32v(d);
            let spawned = h.spawn_ray(dir).at_time(c.time);
            let again = world.intersect(&spawned, 0.0, f32::INFINITY, &mut counters);
            // Into the inside of a closed shape (the normal is outward), or not.
            let into = closed(c.kind) && dir.dot(h.normal) < 0.0;
            let what = || {
                let inv = c.m.inverse();
                format!(
                    "{:?} m = {:?} pts = {:?}\n hit {h:?}\n from {ray:?}\n spawned {spawned:?}\n got {again:?}\n object-space hit {:?}, spawn origin {:?}",
                    c.kind,
                    c.m,
                    c.pts,
                    inv.transform_point3(h.point.as_dvec3()),
                    inv.transform_point3(spawned.origin.as_dvec3()),
                )
            };
            if !into {
                t.away += 1;
                if let Some(a) = again {
                    fails.push(format!("self-hit at t = {} ({})", a.t, what()));
                }
                continue;
            }
            t.into += 1;
            if c.kind == Kind::Cube {
                // The offset is along the hit face's normal. A hit very near
                // an edge (grazing rays along the adjacent face produce them)
                // can be pushed out through the adjacent face, or start so
                // close to it that its hit is within that triangle's own
                // error of t = 0 (rejected, as it must be): "inward" has no
                // meaning at that scale. Counted, and bounded below.
                let inv = c.m.inverse();
                let o = inv.transform_point3(spawned.origin.as_dvec3());
                let hp = inv.transform_point3(h.point.as_dvec3());
                // A few offsets, or 1e-4 of the cube's size: the triangle
                // test's own bound on the error of t (pbrt's deltaT, about
                // 1e-5 of the triangle's extent seen from the origin)
                // rejects hits closer than that as indistinguishable from 0.
                let reach = (4.0 * (o - hp).length()).max(1e-4);
                let faces_near = (0..3).filter(|&i| 1.0 - hp[i].abs() < reach).count();
                if o.abs().max_element() > 1.0 || faces_near >= 2 {
                    t.edge += 1;
                    continue;
                }
            }
            let Some(a) = again else {
                fails.push(format!(
                    "an inward ray escaped its closed shape ({})",
                    what()
                ));
                continue;
            };
            if c.kind == Kind::Cube {
                // The far side is another face: the hit must lie inward of the
                // spawn point's face by more than their rounding.
                let depth = (h.point - a.point).dot(h.normal) as f64;
                let slack = 4.0 * (h.error.length() + a.error.length()) as f64;
                let gap = -(a.normal.dot(h.normal) as f64 - 1.0).abs();
                if depth <= slack && gap > -1e-3 {
                    fails.push(format!("an inward ray re-hit its own face ({})", what()));
                }
                continue;
            }
            let Some((_, t_far)) = exact_span(c, &spawned) else {
                continue; // grazing at the limit of f64: no reference
            };
            // The near side is within the offset of the spawn point; check
            // only where the far side is clearly further.
            let near = 20.0 * (spawned.origin - h.point).length() as f64
                / (dir.dot(h.normal).abs() as f64).max(1e-3)
                / spawned.dir.length() as f64;
            if t_far <= near.max(1e-6 * t_far.abs()) {
                continue;
            }
            t.far_checked += 1;
            let ta = a.t as f64;
            if !(ta > 0.5 * t_far && ta < 1.5 * t_far) {
                fails.push(format!(
                    "inward ray: t = {ta}, far side at {t_far} ({})",
                    what()
                ));
            }
        }
    }
    fails
}

fn run(kind: Kind, flatten: bool, seed: u64) {
    let mut r = Rng::new(seed);
    let mut fails = Vec::new();
    let mut t = Tally {
        hits: 0,
        away: 0,
        into: 0,
        far_checked: 0,
        edge: 0,
    };
    for case in 0..400 {
        let c = random_case(&mut r, kind);
        let world = World::build_at(
            &scene(c.node.clone()),
            BuildOptions {
                flatten,
                ..BuildOptions::default()
            },
            DVec3::ZERO,
        );
        let f = check_case(&mut r, &c, &world, 25, &mut t);
        fails.extend(f.into_iter().map(|f| format!("case {case}: {f}")));
    }
    println!(
        "{kind:?} (flatten {flatten}): {} hits, {} rays away, {} into ({} far sides checked, {} from within the error bound of an edge)",
        t.hits, t.away, t.into, t.far_checked, t.edge
    );
    // Edge hits come from the grazing eye rays (along a face, into the
    // next one at its edge): a minority.
    assert!(
        t.edge * 10 <= t.into,
        "{} of {} inward rays started at an edge",
        t.edge,
        t.into
    );
    assert!(t.hits > 5000, "only {} hits", t.hits);
    if closed(kind) {
        assert!(t.into > 5000 && t.away > 5000);
    }
    if matches!(kind, Kind::Sphere | Kind::Ellipsoid | Kind::MovingEllipsoid) {
        assert!(
            t.far_checked > 3000,
            "only {} far sides checked",
            t.far_checked
        );
    }
    assert!(
        fails.is_empty(),
        "{} failures of {}, first:\n{}",
        fails.len(),
        t.away + t.into,
        fails[..fails.len().min(3)].join("\n")
    );
}

#[test]
fn spheres() {
    run(Kind::Sphere, true, 1);
}

#[test]
fn ellipsoids_kept_transformed() {
    run(Kind::Ellipsoid, true, 2);
}

#[test]
fn moving_ellipsoids() {
    run(Kind::MovingEllipsoid, true, 8);
}

#[test]
fn triangles() {
    run(Kind::Triangle, true, 3);
}

#[test]
fn planes() {
    run(Kind::Plane, true, 4);
}

#[test]
fn closed_meshes() {
    run(Kind::Cube, true, 5);
}

#[test]
fn closed_meshes_kept_transformed() {
    run(Kind::Cube, false, 6);
}

/// The check can fail: spawning from the bare hit point (no offset) re-hits.
#[test]
fn the_property_fails_without_the_offset() {
    let mut r = Rng::new(7);
    let mut self_hits = 0;
    for _ in 0..200 {
        let c = random_case(&mut r, Kind::Sphere);
        let world = World::build_at(&scene(c.node.clone()), BuildOptions::default(), DVec3::ZERO);
        let (p, n) = surface_point(&mut r, &c);
        let origin = p + n * 3.0 * c.m.transform_vector3(DVec3::X).length();
        let ray = Ray::new(f32v(origin), f32v(p - origin));
        let mut cn = Counters::default();
        let Some(h): Option<Hit> = world.intersect(&ray, 0.0, f32::INFINITY, &mut cn) else {
            continue;
        };
        for _ in 0..8 {
            let d = f32v(hemisphere(&mut r, h.normal.as_dvec3()));
            let bare = Ray::new(h.point, d);
            self_hits += world
                .intersect(&bare, 0.0, f32::INFINITY, &mut cn)
                .is_some() as usize;
        }
    }
    assert!(
        self_hits > 50,
        "only {self_hits} self-hits without the offset"
    );
}
