use super::*;
use crate::accel::testutil::{assert_agrees, prim, ray, soup, Rng};
use crate::accel::Brute;
use crate::math::{Ray, Vec3};
use crate::shape::{Shape, Sphere, Transformed, Triangle};

fn all(prims: &[Primitive]) -> Vec<u32> {
    (0..prims.len() as u32).collect()
}

/// Groups of `chunk` consecutive primitives, grouped again in fours.
fn chunked(n: u32, chunk: u32) -> SceneTree {
    let shapes: Vec<SceneTree> = (0..n)
        .step_by(chunk as usize)
        .map(|s| SceneTree::Shape(s..(s + chunk).min(n)))
        .collect();
    SceneTree::Group(
        shapes
            .chunks(4)
            .map(|c| SceneTree::Group(c.to_vec()))
            .collect(),
    )
}

#[test]
fn agrees_with_brute_force() {
    let prims = soup(31, 800);
    for chunk in [1, 7, 100, 2000] {
        let h = HierarchyBvh::new(&prims, all(&prims), &chunked(prims.len() as u32, chunk));
        assert_agrees(&h, &prims, 2000);
    }
}

#[test]
fn wide_groups_are_split_and_single_children_skipped() {
    let prims = soup(32, 200);
    let n = prims.len() as u32;
    let flat = SceneTree::Group((0..n).map(|i| SceneTree::Shape(i..i + 1)).collect());
    let wrapped = SceneTree::Group(vec![SceneTree::Group(vec![flat])]);
    let h = HierarchyBvh::new(&prims, all(&prims), &wrapped);
    for node in &h.nodes {
        if let Kind::Inner { count, .. } = node.kind {
            assert!((2..=MAX_CHILDREN as u32).contains(&count));
        }
    }
    assert_eq!(h.ids.len(), prims.len());
    assert_agrees(&h, &prims, 2000);
}

#[test]
fn ids_outside_the_tree_are_kept_and_others_left_out() {
    let prims = soup(33, 100);
    let n = prims.len() as u32;
    // The tree mentions the first half only; the ids skip every tenth.
    let ids: Vec<u32> = (0..n).filter(|i| i % 10 != 0).collect();
    let h = HierarchyBvh::new(&prims, ids.clone(), &chunked(n / 2, 5));
    let mut got = h.ids.clone();
    got.sort_unstable();
    assert_eq!(got, ids);
    let brute = Brute::new(&prims, ids);
    let mut r = Rng::new(3);
    for _ in 0..2000 {
        let q = ray(&mut r);
        let mut c = Counters::default();
        assert_eq!(
            brute.intersect(Query::new(&prims, &q, 0.0, f32::INFINITY), &mut c),
            h.intersect(Query::new(&prims, &q, 0.0, f32::INFINITY), &mut c)
        );
    }
}

/// Unflattened: wrappers under one transform node are tested in its space,
/// the ray carried once per node visit, with bit-identical hits.
#[test]
fn a_transform_node_carries_the_ray_once() {
    let m = Mat4::from_translation(Vec3::new(0.5, -1.0, 2.0))
        * Mat4::from_rotation_y(0.7)
        * Mat4::from_scale(Vec3::new(1.0, 2.0, 0.5));
    let mut r = Rng::new(34);
    let object: Vec<Shape> = (0..300)
        .map(|i| {
            let a = r.v(-4.0, 4.0);
            if i % 3 == 0 {
                Shape::Sphere(Sphere {
                    center: a,
                    radius: 0.3,
                })
            } else {
                Shape::Triangle(Triangle::new(a, a + r.v(-1.0, 1.0), a + r.v(-1.0, 1.0)))
            }
        })
        .collect();
    let prims: Vec<Primitive> = object
        .into_iter()
        .map(|s| {
            prim(Shape::Transformed(Box::new(
                Transformed::new(s, m).unwrap(),
            )))
        })
        .collect();
    let n = prims.len() as u32;
    let tree = SceneTree::Group(vec![SceneTree::Transform {
        to_world: m,
        to_object: m.as_dmat4().inverse().as_mat4(),
        child: Box::new(SceneTree::Group(vec![
            SceneTree::Shape(0..n / 2),
            SceneTree::Shape(n / 2..n),
        ])),
    }]);
    let h = HierarchyBvh::new(&prims, all(&prims), &tree);
    assert_eq!(h.spaces(), 1);
    assert_layout(&h);
    assert!(h.describe().ends_with(", 1 carrying transforms"));
    assert!(matches!(
        h.nodes[0].kind,
        Kind::Inner {
            space: 0,
            count: 2,
            ..
        }
    ));
    let brute = Brute::new(&prims, all(&prims));
    let mut hits = 0;
    for _ in 0..3000 {
        let q = ray(&mut r);
        let mut c = Counters::default();
        let want = brute.intersect(Query::new(&prims, &q, 0.0, f32::INFINITY), &mut c);
        assert_eq!(
            want,
            h.intersect(Query::new(&prims, &q, 0.0, f32::INFINITY), &mut c)
        );
        assert_eq!(
            brute.occluded(Query::new(&prims, &q, 0.1, 5.0), &mut c),
            h.occluded(Query::new(&prims, &q, 0.1, 5.0), &mut c)
        );
        hits += want.is_some() as u32;
    }
    assert!(hits > 300, "{hits}");
    // The same wrappers under a different matrix in the tree are tested in
    // world space (each wrapper carries the ray itself): still exact.
    let other = SceneTree::Transform {
        to_world: Mat4::IDENTITY,
        to_object: Mat4::IDENTITY,
        child: Box::new(SceneTree::Shape(0..n)),
    };
    let h = HierarchyBvh::new(&prims, all(&prims), &other);
    assert_eq!(h.spaces(), 0);
    assert_agrees(&h, &prims, 1000);
}

#[test]
fn empty_tree_and_no_ids() {
    let h = HierarchyBvh::new(&[], vec![], &SceneTree::Group(vec![]));
    assert_eq!(h.node_count(), 0);
}

/// Depth of the deepest leaf below node `k`, walked from the node array.
fn depth_below(h: &HierarchyBvh, k: usize) -> usize {
    match h.nodes[k].kind {
        Kind::Leaf { .. } => 0,
        Kind::Inner { first, count, .. } => {
            1 + (first..first + count)
                .map(|c| depth_below(h, c as usize))
                .max()
                .expect("inner nodes have children")
        }
    }
}

/// The memory an aggregate reports is its layout's: the nodes, a 4-byte id
/// per primitive and a matrix per carrying transform.
fn assert_layout(h: &HierarchyBvh) {
    assert_eq!(
        h.memory_bytes(),
        h.nodes.len() * std::mem::size_of::<Node>() + 4 * h.ids.len() + 64 * h.spaces()
    );
}

/// What the hierarchy reports about itself (node count, depth, bounds,
/// name, memory) is what it holds, and its visiting query (the traversal
/// view's) finds the plain query's hit, telling the boxes it enters.
#[test]
fn reports_its_shape_and_visits_to_the_same_hit() {
    let prims = soup(36, 300);
    let h = HierarchyBvh::new(&prims, all(&prims), &chunked(prims.len() as u32, 7));
    assert_eq!(h.node_count(), h.nodes.len());
    assert!(h.node_count() > 10);
    assert_eq!(h.depth(), depth_below(&h, 0));
    assert!(h.depth() >= 3, "{}", h.depth());
    let all_boxes = prims.iter().fold(Aabb::EMPTY, |b, p| b.union(&p.bounds()));
    let b = h.bounds();
    assert!(b.min.cmple(all_boxes.min).all() && b.max.cmpge(all_boxes.max).all());
    assert_eq!(
        h.describe(),
        format!(
            "bvh-hierarchy {} nodes, depth {}, 0 carrying transforms",
            h.node_count(),
            h.depth()
        )
    );
    assert_layout(&h);
    let mut r = Rng::new(37);
    let (mut hits, mut leaves) = (0, 0);
    for _ in 0..300 {
        let q = ray(&mut r);
        let mut c = Counters::default();
        let want = h.intersect(Query::new(&prims, &q, 0.0, f32::INFINITY), &mut c);
        let mut entered = 0;
        let got = h.intersect_visiting(Query::new(&prims, &q, 0.0, f32::INFINITY), &mut c, |v| {
            entered += usize::from(v.entered);
            leaves += usize::from(v.leaf && v.entered);
        });
        assert_eq!(got, want);
        if got.is_some() {
            assert!(entered > 0);
            hits += 1;
        }
    }
    assert!(hits > 30 && leaves > 30, "{hits} hits, {leaves} leaves");
}

/// Every node's box holds exactly what lies below it: a leaf's the union of
/// its primitives' (padded) boxes, an inner node's the union of its
/// children's. An empty or missing box would not change a single hit (an
/// empty box's slabs cover every ray), only the culling, which agreement
/// with brute force cannot see.
#[test]
fn every_box_is_the_union_of_what_lies_below() {
    let prims = soup(34, 600);
    for chunk in [1, 7, 100] {
        let h = HierarchyBvh::new(&prims, all(&prims), &chunked(prims.len() as u32, chunk));
        let mut inner = 0;
        for node in &h.nodes {
            let below = match node.kind {
                Kind::Inner { first, count, .. } => {
                    inner += 1;
                    (first..first + count)
                        .fold(Aabb::EMPTY, |b, c| b.union(&h.nodes[c as usize].bounds))
                }
                Kind::Leaf { start, count, .. } => {
                    let ids = &h.ids[start as usize..(start + count) as usize];
                    let b = crate::accel::overlap::bounds_of(&prims, ids);
                    assert_eq!(node.bounds.union(&b), node.bounds);
                    continue;
                }
            };
            assert!(!node.bounds.is_empty());
            assert_eq!(node.bounds, below);
        }
        assert!(inner > 1);
        // A ray past the whole scene tests the root's box and nothing else.
        let mut c = Counters::default();
        let miss = Ray::new(Vec3::new(0.0, 100.0, 0.0), Vec3::X);
        assert!(h
            .intersect(Query::new(&prims, &miss, 0.0, f32::INFINITY), &mut c)
            .is_none());
        assert_eq!(c.nodes_visited, 1);
    }
}

/// Halving cuts across the longest spread of the centres: a row of small
/// spheres along any one axis is cut into halves that do not overlap along
/// it, at every inner node (a cut along another axis would interleave them).
#[test]
fn halving_cuts_along_the_longest_spread() {
    for axis in 0..3 {
        let prims: Vec<Primitive> = (0..64)
            .map(|i| {
                let mut c = Vec3::new(0.01 * (i as f32).sin(), 0.02 * (i as f32).cos(), 0.0);
                c[axis] = i as f32;
                crate::accel::testutil::sphere(c, 0.1)
            })
            .collect();
        let h = HierarchyBvh::new(&prims, all(&prims), &SceneTree::Shape(0..64));
        let mut inner = 0;
        for node in &h.nodes {
            if let Kind::Inner { first, count, .. } = node.kind {
                inner += 1;
                let mut kids: Vec<Aabb> = (first..first + count)
                    .map(|c| h.nodes[c as usize].bounds)
                    .collect();
                kids.sort_by(|a, b| a.min[axis].total_cmp(&b.min[axis]));
                for w in kids.windows(2) {
                    assert!(w[0].max[axis] < w[1].min[axis], "axis {axis}: {kids:?}");
                }
            }
        }
        assert!(inner >= 7, "{inner}");
    }
}

/// A node whose box the ray enters beyond the best hit so far is dropped
/// when popped, unopened: a group behind the hit costs the ray what the same
/// group beside the ray costs (its box tested, nothing below it).
#[test]
fn a_group_behind_the_hit_is_not_opened() {
    let cluster = |x: f32, y: f32| -> Vec<Primitive> {
        (0..8)
            .map(|i| crate::accel::testutil::sphere(Vec3::new(x, y, i as f32 * 0.3), 0.5))
            .collect()
    };
    let tree = SceneTree::Group(vec![
        SceneTree::Group((0..8).map(|i| SceneTree::Shape(i..i + 1)).collect()),
        SceneTree::Group((8..16).map(|i| SceneTree::Shape(i..i + 1)).collect()),
    ]);
    let visits = |far_y: f32| {
        let mut prims = cluster(0.0, 0.0);
        prims.extend(cluster(10.0, far_y));
        let h = HierarchyBvh::new(&prims, all(&prims), &tree);
        let mut c = Counters::default();
        let ray = Ray::new(Vec3::new(-5.0, 0.0, 0.1), Vec3::X);
        let hit = h.intersect(Query::new(&prims, &ray, 0.0, f32::INFINITY), &mut c);
        assert!(hit.is_some_and(|h| h.prim < 8 && h.t < 5.0));
        c.nodes_visited
    };
    assert_eq!(visits(0.0), visits(50.0));
}

/// The counters, on a tree small enough to count by hand: a root over two
/// leaves of three spheres, and a ray through all three boxes that misses
/// every sphere. Both queries test the root's box and its two children's (3
/// boxes) and all six spheres.
#[test]
fn counters_count_every_box_and_every_test() {
    let prims: Vec<Primitive> = [0.0, 2.0, 4.0, 10.0, 12.0, 14.0]
        .iter()
        .map(|&x| crate::accel::testutil::sphere(Vec3::new(x, 0.0, 0.0), 0.5))
        .collect();
    let tree = SceneTree::Group(vec![SceneTree::Shape(0..3), SceneTree::Shape(3..6)]);
    let h = HierarchyBvh::new(&prims, all(&prims), &tree);
    assert_eq!(h.nodes.len(), 3);
    // 0.45 off the axis in y and z: inside every box, outside every sphere.
    let ray = Ray::new(Vec3::new(-5.0, 0.45, 0.45), Vec3::X);
    let mut c = Counters::default();
    assert!(h
        .intersect(Query::new(&prims, &ray, 0.0, f32::INFINITY), &mut c)
        .is_none());
    assert_eq!((c.nodes_visited, c.intersection_tests), (3, 6));
    let mut c = Counters::default();
    assert!(!h.occluded(Query::new(&prims, &ray, 0.0, f32::INFINITY), &mut c));
    assert_eq!((c.nodes_visited, c.intersection_tests), (3, 6));
}
