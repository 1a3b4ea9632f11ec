//! The traversal views record what the accelerators really do: the grid's
//! cells equal an independent parametric walk, in order, with the faces the
//! ray crossed; the BVH enters exactly the boxes a brute-force list says it
//! must.

use crate::common::*;
use glint::accel::bvh::NodeVisit;
use glint::accel::grid::{Face, Lattice};
use glint::accel::{Bvh, Grid, Query, Split};
use glint::math::{Ray, Vec3};
use glint::stats::Counters;
use glint::world::{BuildOptions, World};

/// A tiny deterministic generator (xorshift), so failures reproduce.
fn world() -> World {
    let scene = glint::format::load_scene(&own_scene("mesh_knot_1k.txt")).unwrap();
    World::build(&scene, BuildOptions::default())
}

fn bounded(world: &World) -> Vec<u32> {
    (0..world.prims().len() as u32)
        .filter(|i| !world.unbounded().contains(i))
        .collect()
}

/// The cells a ray crosses, by brute force: every crossing of every cell
/// plane inside the grid's box, in f64, sorted; a cell per interval, found
/// from the interval's midpoint; the face it was entered by is the plane
/// crossed at the interval's start.
fn reference_walk(l: &Lattice, ray: &Ray) -> Vec<([u32; 3], Option<Face>)> {
    let o = ray.origin.as_dvec3();
    let d = ray.dir.as_dvec3();
    // The ray's interval inside the box, and which slab it entered last.
    let (mut t0, mut t1, mut entry) = (0.0f64, f64::INFINITY, None);
    for a in 0..3 {
        let (lo, hi) = (l.bounds.min[a] as f64, l.bounds.max[a] as f64);
        let (ta, tb) = ((lo - o[a]) / d[a], (hi - o[a]) / d[a]);
        let (near, far) = (ta.min(tb), ta.max(tb));
        if near > t0 {
            t0 = near;
            entry = Some(Face {
                axis: a,
                min_side: d[a] > 0.0,
            });
        }
        t1 = t1.min(far);
    }
    if t0 >= t1 {
        return vec![];
    }
    let mut crossings: Vec<(f64, usize)> = Vec::new();
    for a in 0..3 {
        for i in 1..l.res[a] as i32 {
            let t = (l.plane(a, i) as f64 - o[a]) / d[a];
            if t > t0 && t < t1 {
                crossings.push((t, a));
            }
        }
    }
    crossings.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut bounds = vec![(t0, entry)];
    bounds.extend(crossings.iter().map(|&(t, a)| {
        (
            t,
            Some(Face {
                axis: a,
                min_side: d[a] > 0.0,
            }),
        )
    }));
    bounds.push((t1, None));
    bounds
        .windows(2)
        .map(|w| {
            let mid = o + d * (0.5 * (w[0].0 + w[1].0));
            let cell = [0, 1, 2].map(|a| {
                let k = ((mid[a] - l.bounds.min[a] as f64) / l.cell[a] as f64).floor();
                k.clamp(0.0, l.res[a] as f64 - 1.0) as u32
            });
            (cell, w[0].1)
        })
        .collect()
}

fn random_ray(r: &mut Rng, centre: Vec3, size: f32) -> Ray {
    let v = |r: &mut Rng| Vec3::new(r.f(), r.f(), r.f()) * 2.0 - 1.0;
    let o = centre + v(r) * size * 1.5;
    let target = centre + v(r) * size * 0.5;
    Ray::new(o, (target - o).normalize())
}

#[test]
fn grid_cells_equal_an_independent_parametric_walk() {
    let world = world();
    let b = world.bounds();
    let (centre, size) = (b.center(), b.extent().max_element());
    let mut r = Rng::new(0x2545f4914f6cdd1d);
    let mut compared = 0;
    for res in [[7, 5, 3], [13, 13, 13], [20, 9, 4]] {
        let grid = Grid::new(world.prims(), bounded(&world), Some(res));
        let l = *grid.lattice();
        for _ in 0..300 {
            let ray = random_ray(&mut r, centre, size);
            let mut visited = Vec::new();
            let hit = grid.intersect_visiting(
                Query::new(world.prims(), &ray, 0.0, f32::INFINITY),
                &mut Counters::default(),
                |c| {
                    visited.push((c.index, c.entered, c.t_enter, c.t_exit));
                },
            );
            let reference = reference_walk(&l, &ray);
            let ours: Vec<_> = visited.iter().map(|v| (v.0, v.1)).collect();
            match hit {
                // The search stops in the cell holding the hit: a prefix.
                Some(h) => {
                    assert!(ours.len() <= reference.len(), "{ray:?}");
                    assert_eq!(ours[..], reference[..ours.len()], "{ray:?}");
                    let last = visited.last().unwrap();
                    assert!(
                        h.t <= last.3 * (1.0 + 1e-5) + 1e-5,
                        "hit beyond the last cell"
                    );
                }
                None => assert_eq!(ours, reference, "{ray:?}"),
            }
            compared += ours.len();
        }
    }
    assert!(compared > 2000, "{compared} cells compared");
}

#[test]
fn bvh_enters_exactly_the_boxes_it_must() {
    let world = world();
    let b = world.bounds();
    let (centre, size) = (b.center(), b.extent().max_element());
    let mut r = Rng::new(0x9e3779b97f4a7c15);
    let mut entered_total = 0;
    for split in [Split::Sah, Split::Median, Split::Midpoint] {
        let bvh = Bvh::new(world.prims(), bounded(&world), split);
        let nodes = bvh.nodes();
        for _ in 0..300 {
            let ray = random_ray(&mut r, centre, size);
            let mut visits: Vec<NodeVisit> = Vec::new();
            let hit = bvh.intersect_visiting(
                Query::new(world.prims(), &ray, 0.0, f32::INFINITY),
                &mut Counters::default(),
                |v| visits.push(v),
            );
            let inv = ray.dir.recip();
            let t_final = hit.map_or(f32::INFINITY, |h| h.t);
            let entered: Vec<u32> = visits
                .iter()
                .filter(|v| v.entered)
                .map(|v| v.node)
                .collect();
            for (k, n) in nodes.iter().enumerate() {
                let k = k as u32;
                // Every box the ray meets before the final hit must be entered.
                if n.bounds.hit(&ray, inv, 0.0, t_final).is_some() {
                    assert!(
                        entered.contains(&k),
                        "node {k} ({split}) meets the ray before its hit but was not entered"
                    );
                }
            }
            for v in &visits {
                let n = &nodes[v.node as usize];
                // Entered means the box meets the ray; tested-and-missed means
                // it does not meet it before the final hit.
                let meets = n.bounds.hit(&ray, inv, 0.0, f32::INFINITY).is_some();
                assert!(
                    !v.entered || meets,
                    "node {} entered without meeting the ray",
                    v.node
                );
                if !v.entered {
                    assert!(n.bounds.hit(&ray, inv, 0.0, t_final).is_none());
                }
            }
            // Each node is tested at most once, and the root first.
            let mut seen = visits.iter().map(|v| v.node).collect::<Vec<_>>();
            if let Some(first) = seen.first() {
                assert_eq!(*first, 0);
            }
            seen.sort();
            seen.dedup();
            assert_eq!(seen.len(), visits.len());
            entered_total += entered.len();
        }
    }
    assert!(entered_total > 1000, "{entered_total}");
}

#[test]
fn traverse_command_writes_every_kind_of_output() {
    let dir = scratch("traverse");
    for (accel, out) in [
        ("grid:8x8x8", "g.png"),
        ("octree", "o.obj"),
        ("bvh", "b.json"),
    ] {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
            .arg("traverse")
            .arg(own_scene("mesh_knot_1k.txt"))
            .args([
                "--accel", accel, "--pixel", "20", "20", "--pixel", "30", "25", "--size", "48",
                "36", "-o", out,
            ])
            .current_dir(&dir)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{accel}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(
            std::fs::metadata(dir.join(out)).unwrap().len() > 100,
            "{out}"
        );
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("b.json")).unwrap()).unwrap();
    assert_eq!(json["rays"].as_array().unwrap().len(), 2);
}

#[test]
fn structure_command_and_course_stats_report() {
    let dir = scratch("structure");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_glint"))
        .arg("structure")
        .arg(own_scene("mesh_knot_1k.txt"))
        .args([
            "--accel", "bvh", "--depth", "2", "--size", "48", "36", "-o", "s.png",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("drew 4 boxes"));
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_raytracer"))
        .arg("-input")
        .arg(own_scene("mesh_knot_1k.txt"))
        .args([
            "-size", "20", "10", "-output", "k.png", "-grid", "6", "5", "4", "-stats",
        ])
        .current_dir(&dir)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success());
    for want in [
        "RAY TRACING STATISTICS",
        "num pixels                 200 (20x10)",
        "num grid cells             120 (6x5x4)",
        "num non-shadow rays        200",
        "cells traversed per ray",
    ] {
        assert!(text.contains(want), "{want:?} missing from\n{text}");
    }
}

/// The traversal views record the lecture's other choices too, through the
/// same searches the renderer runs: the recorded search finds brute force's
/// hit, and what it records is plausible (the nested grid's cells come
/// front to back along the ray, the octree-inner walk shows its inner nodes,
/// the hierarchy's first box is the root's).
#[test]
fn new_accelerators_are_recorded() {
    use glint::accel::{AccelKind, Aggregate};
    use glint::viz::traversal::Structure;
    let world = world();
    // The oracle: brute force over the same bounded primitives (the view,
    // like the aggregate, leaves the planes to the world).
    let brute = glint::accel::Brute::new(world.prims(), bounded(&world));
    let b = world.bounds();
    let (centre, size) = (b.center(), b.extent().max_element());
    for kind in [
        AccelKind::NESTED_GRID,
        AccelKind::OctreeInner,
        AccelKind::BvhHierarchy,
    ] {
        let s = Structure::build(&world, kind).expect("a recorded structure");
        let mut r = Rng::new(0x2545f4914f6cdd1d);
        let (mut inner, mut hits) = (0, 0);
        for _ in 0..300 {
            let ray = random_ray(&mut r, centre, size);
            let (hit, visits) = s.trace(&world, &ray, 0.0);
            let want = brute.intersect(
                Query::new(world.prims(), &ray, 0.0, f32::INFINITY),
                &mut Counters::default(),
            );
            assert_eq!(hit.map(|h| h.prim), want.map(|h| h.prim), "{kind}");
            hits += hit.is_some() as u32;
            inner += visits.iter().filter(|v| !v.leaf).count();
            if kind == AccelKind::BvhHierarchy {
                if let Some(first) = visits.first() {
                    assert!(first.bounds.extent().max_element() >= 0.9 * size, "{kind}");
                }
            }
        }
        assert!(hits > 30, "{kind}: {hits} hits");
        assert!(inner > 0, "{kind} recorded no inner box");
    }
}
