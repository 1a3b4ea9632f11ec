//! What every aggregate promises beyond its hits (the agreement tests
//! check those): the barycentric query and the query that may skip a
//! primitive answer as the plain ones do, the bounds hold every primitive,
//! the structure reports its memory and its name, and brute force counts
//! its tests.

use super::testutil::{ray, soup, Rng};
use super::{Aggregate, Brute, Bvh, Bvh8, Grid, NestedGrid, Octree, Query, Split, Storage};
use crate::math::{Aabb, Ray, Vec3};
use crate::primitive::Primitive;
use crate::stats::Counters;

/// Every aggregate over all of `p` (the scene hierarchy's BVH has its own
/// tests: it needs a scene tree).
fn every_aggregate(p: &[Primitive]) -> Vec<(&'static str, Box<dyn Aggregate>)> {
    let ids = || (0..p.len() as u32).collect::<Vec<_>>();
    vec![
        ("none", Box::new(Brute::new(p, ids()))),
        ("grid", Box::new(Grid::new(p, ids(), None))),
        ("octree", Box::new(Octree::new(p, ids()))),
        (
            "octree-inner",
            Box::new(Octree::with_storage(p, ids(), Storage::Inner)),
        ),
        ("bvh-sah", Box::new(Bvh::new(p, ids(), Split::Sah))),
        (
            "nested-grid:16:2",
            Box::new(NestedGrid::new(p, ids(), 16, 2)),
        ),
        ("bvh8", Box::new(Bvh8::new(p, ids()))),
    ]
}

/// Every aggregate over nothing (the hierarchy's over an empty tree too)
/// has empty bounds and hits nothing.
#[test]
fn every_aggregate_over_nothing_hits_nothing() {
    use super::{HierarchyBvh, SceneTree};
    let mut all = every_aggregate(&[]);
    let tree = &SceneTree::Group(vec![]);
    all.push((
        "bvh-hierarchy",
        Box::new(HierarchyBvh::new(&[], vec![], tree)),
    ));
    let r = &Ray::new(Vec3::ZERO, Vec3::X);
    for (name, a) in all {
        let mut c = Counters::default();
        let q = Query::new(&[], r, 0.0, f32::INFINITY);
        assert!(a.intersect(q, &mut c).is_none(), "{name}");
        assert!(!a.occluded(q, &mut c), "{name}");
        assert!(a.bounds().is_empty(), "{name}");
    }
}

#[test]
fn every_aggregate_keeps_the_trait_s_promises() {
    let prims = soup(3, 400);
    let all = prims.iter().fold(Aabb::EMPTY, |b, p| b.union(&p.bounds()));
    for (name, a) in every_aggregate(&prims) {
        let b = a.bounds();
        assert!(
            b.min.cmple(all.min).all() && b.max.cmpge(all.max).all(),
            "{name}: {b:?} does not hold {all:?}"
        );
        assert!(a.memory_bytes() >= 4 * prims.len(), "{name}");
        // Statistics name the structure first (`--accel`'s spelling).
        let d = a.describe();
        assert!(
            d == name || d.starts_with(&format!("{name} ")),
            "{name}: {d}"
        );
        let mut r = Rng::new(5);
        let mut hits = 0;
        for _ in 0..400 {
            let ray = ray(&mut r);
            let mut c = Counters::default();
            let inf = f32::INFINITY;
            let h = a.intersect(Query::new(&prims, &ray, 0.0, inf), &mut c);
            let hb = a.intersect_barycentric(Query::new(&prims, &ray, 0.0, inf), &mut c);
            assert_eq!(h, hb.map(|(h, _)| h), "{name}");
            let o = a.occluded(Query::new(&prims, &ray, 0.0, inf), &mut c);
            assert_eq!(o, h.is_some(), "{name}");
            // `u32::MAX` is no primitive: nothing may be skipped.
            let oe = a.occluded_except(Query::new(&prims, &ray, 0.0, inf), u32::MAX, &mut c);
            assert_eq!(o, oe, "{name}");
            hits += usize::from(o);
        }
        // Both answers occur.
        assert!((40..360).contains(&hits), "{name}: {hits} of 400 rays hit");
    }
}

/// `occluded_packet` answers each ray of a packet as `occluded_except`
/// does alone (skip ids: none, a primitive, `u32::MAX`), for packets of
/// 1 to 8 random rays and of up to 8 rays from one point towards a small
/// patch (which bvh8 walks together); with the same statistics where the
/// aggregate asks ray by ray, and fewer nodes visited on bvh8.
#[test]
fn every_aggregate_answers_packets_as_single_rays() {
    use super::PacketRay;
    let prims = soup(7, 400);
    for (name, a) in every_aggregate(&prims) {
        let mut r = Rng::new(11);
        let (mut packed, mut alone) = (Counters::default(), Counters::default());
        for k in 0..300 {
            let n = 1 + k % 8;
            let rays: Vec<PacketRay> = if k % 2 == 0 {
                (0..n)
                    .map(|_| PacketRay {
                        ray: ray(&mut r),
                        tmin: 0.0,
                        tmax: f32::INFINITY,
                    })
                    .collect()
            } else {
                let o = ray(&mut r).origin;
                let to = Vec3::new(r.f(), r.f(), r.f()) * 4.0 - 2.0;
                (0..n)
                    .map(|_| PacketRay {
                        ray: Ray::new(o, to + Vec3::new(r.f(), r.f(), r.f()) * 0.01 - o),
                        tmin: 0.0,
                        tmax: 1.0,
                    })
                    .collect()
            };
            let skip: Vec<u32> = (0..n)
                .map(|i| match (k + i) % 3 {
                    0 => u32::MAX,
                    _ => r.below(prims.len()) as u32,
                })
                .collect();
            for except in [&[][..], &skip[..]] {
                let (mut cp, mut c1) = (Counters::default(), Counters::default());
                let got = a.occluded_packet(&prims, &rays, except, &mut cp);
                for (i, q) in rays.iter().enumerate() {
                    let query = Query::new(&prims, &q.ray, q.tmin, q.tmax);
                    let want = match except.get(i) {
                        Some(&e) => a.occluded_except(query, e, &mut c1),
                        None => a.occluded(query, &mut c1),
                    };
                    assert_eq!(got >> i & 1 != 0, want, "{name} {k} {i}");
                }
                assert_eq!(got >> n, 0, "{name}");
                if name != "bvh8" {
                    assert_eq!(cp, c1, "{name}");
                }
                packed.nodes_visited += cp.nodes_visited;
                alone.nodes_visited += c1.nodes_visited;
            }
        }
        if name == "bvh8" {
            assert!(
                packed.nodes_visited < alone.nodes_visited,
                "{packed:?} {alone:?}"
            );
        }
    }
}

/// Brute force tests every primitive for a closest hit, and primitives in
/// order up to the first that blocks a shadow ray (all of them on a miss).
#[test]
fn brute_force_counts_every_test() {
    let prims = soup(4, 200);
    let n = prims.len() as u64;
    let brute = Brute::new(&prims, (0..n as u32).collect());
    let mut r = Rng::new(9);
    let miss = Ray::new(Vec3::splat(100.0), Vec3::X);
    let mut rays: Vec<Ray> = (0..50).map(|_| ray(&mut r)).collect();
    rays.push(miss);
    for ray in rays {
        let first = prims
            .iter()
            .position(|p| p.shape.intersect(&ray, 0.0, f32::INFINITY).is_some());
        let mut c = Counters::default();
        brute.intersect(Query::new(&prims, &ray, 0.0, f32::INFINITY), &mut c);
        assert_eq!(c.intersection_tests, n);
        let mut c = Counters::default();
        let blocked = brute.occluded(Query::new(&prims, &ray, 0.0, f32::INFINITY), &mut c);
        assert_eq!(blocked, first.is_some());
        assert_eq!(c.intersection_tests, first.map_or(n, |i| i as u64 + 1));
    }
}

/// The memory the textbook structures report is their layout's: a BVH's
/// 32-byte nodes and one 4-byte id per primitive; a grid's `cells + 1`
/// offsets and its references, 4 bytes each. And their visiting queries
/// (what the traversal views draw) return the plain query's hit.
#[test]
fn textbook_structures_report_their_layout_and_visit_to_the_same_hit() {
    let prims = soup(6, 300);
    let n = prims.len();
    let ids = || (0..n as u32).collect::<Vec<_>>();
    let bvh = Bvh::new(&prims, ids(), Split::Sah);
    assert_eq!(std::mem::size_of::<super::bvh::Node>(), 32);
    assert_eq!(bvh.ids().len(), n);
    assert_eq!(bvh.memory_bytes(), 32 * bvh.nodes().len() + 4 * n);
    let grid = Grid::new(&prims, ids(), None);
    assert!(grid.references() >= n);
    let cells = grid.lattice().cells();
    assert_eq!(grid.memory_bytes(), 4 * (cells + 1 + grid.references()));
    let mut r = Rng::new(2);
    let mut visited_hits = 0;
    for _ in 0..200 {
        let ray = ray(&mut r);
        let inf = f32::INFINITY;
        let mut c = Counters::default();
        let want = bvh.intersect(Query::new(&prims, &ray, 0.0, inf), &mut c);
        let mut entered = 0;
        let got = bvh.intersect_visiting(Query::new(&prims, &ray, 0.0, inf), &mut c, |v| {
            entered += usize::from(v.entered);
        });
        assert_eq!(got, want);
        if got.is_some() {
            assert!(entered > 0);
            visited_hits += 1;
        }
        let want = grid.intersect(Query::new(&prims, &ray, 0.0, inf), &mut c);
        let got = grid.intersect_visiting(Query::new(&prims, &ray, 0.0, inf), &mut c, |_| {});
        assert_eq!(got, want);
    }
    assert!(visited_hits > 20);
}
