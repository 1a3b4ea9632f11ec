//! The work each textbook accelerator does per ray, held where it was
//! measured. Every accelerator returns brute force's hits whatever its
//! structure (the agreement tests), so a build that subdivides worse (a
//! wrong split position, resolution, depth or leaf size) is invisible to
//! them; the nodes (or cells) visited and the primitives tested per ray are
//! not.

use super::testutil::{ray, soup, terrain, terrain_ray, Rng};
use super::{Aggregate, Bvh, Grid, NestedGrid, Octree, Query, Split, Storage};
use crate::stats::Counters;

/// Nodes (or cells) visited and primitive tests per ray pair (closest and
/// any hit), as measured when the table was written: `(scene, accelerator,
/// nodes, tests)`.
const MEASURED: [(&str, &str, f64, f64); 14] = [
    ("soup", "grid", 23.06, 8.36),
    ("soup", "octree", 21.68, 23.64),
    ("soup", "octree-inner", 7.40, 1376.73),
    ("soup", "bvh-midpoint", 96.39, 31.53),
    ("soup", "bvh-median", 91.80, 40.65),
    ("soup", "bvh-sah", 124.00, 10.01),
    ("soup", "nested-grid", 8.36, 28.81),
    ("terrain", "grid", 18.99, 19.44),
    ("terrain", "octree", 34.62, 20.77),
    ("terrain", "octree-inner", 12.93, 1830.43),
    ("terrain", "bvh-midpoint", 53.15, 10.10),
    ("terrain", "bvh-median", 53.07, 10.54),
    ("terrain", "bvh-sah", 60.89, 4.59),
    ("terrain", "nested-grid", 20.71, 17.19),
];

/// Within 3% of the measured work, either way.
#[test]
fn every_accelerator_s_work_per_ray_stays_where_it_was_measured() {
    for (scene, prims) in [("soup", soup(5, 3000)), ("terrain", terrain())] {
        let ids = || (0..prims.len() as u32).collect::<Vec<_>>();
        let p = &prims[..];
        let accels: [(&str, Box<dyn Aggregate>); 7] = [
            ("grid", Box::new(Grid::new(p, ids(), None))),
            ("octree", Box::new(Octree::new(p, ids()))),
            (
                "octree-inner",
                Box::new(Octree::with_storage(p, ids(), Storage::Inner)),
            ),
            (
                "bvh-midpoint",
                Box::new(Bvh::new(p, ids(), Split::Midpoint)),
            ),
            ("bvh-median", Box::new(Bvh::new(p, ids(), Split::Median))),
            ("bvh-sah", Box::new(Bvh::new(p, ids(), Split::Sah))),
            ("nested-grid", Box::new(NestedGrid::new(p, ids(), 16, 2))),
        ];
        for (name, acc) in accels {
            let mut c = Counters::default();
            let mut r = Rng::new(11);
            let rays = 2000;
            for _ in 0..rays {
                let ray = if scene == "soup" {
                    ray(&mut r)
                } else {
                    terrain_ray(&mut r)
                };
                acc.intersect(Query::new(p, &ray, 0.0, f32::INFINITY), &mut c);
                acc.occluded(Query::new(p, &ray, 0.0, f32::INFINITY), &mut c);
            }
            let nodes = c.nodes_visited as f64 / rays as f64;
            let tests = c.intersection_tests as f64 / rays as f64;
            eprintln!("    (\"{scene}\", \"{name}\", {nodes:.2}, {tests:.2}),");
            let &(_, _, n_max, t_max) = MEASURED
                .iter()
                .find(|m| m.0 == scene && m.1 == name)
                .unwrap();
            // Both ways: more work is a worse build, less (or none) a
            // counter that stopped counting; a real improvement updates
            // the table.
            let near = |v: f64, m: f64| (v - m).abs() <= 0.03 * m;
            assert!(
                near(nodes, n_max),
                "{scene} {name}: {nodes} nodes a ray pair"
            );
            assert!(
                near(tests, t_max),
                "{scene} {name}: {tests} tests a ray pair"
            );
        }
    }
}
