//! The fast BVH against brute force, its build and its statistics.

use super::*;
use crate::accel::testutil::{assert_agrees, soup, sphere, terrain};

fn all(prims: &[Primitive]) -> Vec<u32> {
    (0..prims.len() as u32).collect()
}

#[test]
fn agrees_with_brute_force_on_a_soup() {
    for (seed, n) in [(3, 1), (4, 7), (21, 1500), (22, 20000)] {
        let prims = soup(seed, n);
        let b = Bvh8::new(&prims, all(&prims));
        assert_agrees(&b, &prims, 3000);
    }
}

/// A sphere that is primitive 0 (its leaf id is the bare `OTHER` flag,
/// the one id whose index bits are all zero) shares a leaf block with
/// triangles and is still found, by the closest-hit walk and by the
/// any-hit walk: a flag test that confused "flagged" with "non-zero"
/// would pass it by. Then a soup with its spheres first, against brute
/// force.
#[test]
fn a_sphere_that_is_primitive_0_blocks_and_is_hit() {
    use crate::accel::testutil::prim;
    use crate::shape::{Shape, Triangle};
    let tri = |x: f32| {
        let v = Vec3::new(x, -1.0, -1.0);
        prim(Shape::Triangle(Triangle::new(
            v,
            v + Vec3::new(0.0, 2.0, 0.0),
            v + Vec3::new(0.0, 0.0, 2.0),
        )))
    };
    let prims = vec![sphere(Vec3::ZERO, 0.5), tri(3.0), tri(4.0)];
    let b = Bvh8::new(&prims, all(&prims));
    // One leaf, one block: the sphere's lane beside the triangles'.
    assert_eq!(b.tris.len(), 1);
    let mut c = Counters::default();
    let ray = Ray::new(Vec3::new(-5.0, 0.1, 0.2), Vec3::X);
    let hit = b.intersect(Query::new(&prims, &ray, 0.0, f32::INFINITY), &mut c);
    assert_eq!(hit.map(|h| h.prim), Some(0));
    // The sphere is met at t of about 4.5, the triangles at 8 and 9:
    // up to 6 only the sphere can block.
    assert!(b.occluded(Query::new(&prims, &ray, 0.0, 6.0), &mut c));
    assert!(!b.occluded(Query::new(&prims, &ray, 0.0, 4.4), &mut c));

    let mut soup = soup(8, 400);
    soup.rotate_right(100);
    let b = Bvh8::new(&soup, all(&soup));
    assert_agrees(&b, &soup, 3000);
}

/// Degenerate triangles (one point, collinear points, a NaN or an
/// infinite vertex) are left out of the build: a non-finite one would
/// poison the bounds the whole tree is binned in. The rest of the soup
/// still gives brute force's hits, and the tree's bounds stay finite.
#[test]
fn degenerate_triangles_are_left_out() {
    use crate::accel::testutil::prim;
    use crate::shape::{Shape, Triangle};
    let mut prims = soup(5, 500);
    let a = Vec3::new(1.0, 2.0, 3.0);
    for v in [
        [a, a, a],
        [a, a * 2.0, a * 3.0],
        [a, Vec3::NAN, a * 2.0],
        [a, Vec3::INFINITY, -a],
    ] {
        let t = Triangle::new(v[0], v[1], v[2]);
        assert!(t.is_degenerate());
        prims.push(prim(Shape::Triangle(t)));
    }
    let b = Bvh8::new(&prims, all(&prims));
    assert!(b.bounds().is_finite());
    // The blocks hold every other item once (spheres flagged), and
    // nothing else.
    let mut ids: Vec<u32> = b.tris.iter().flat_map(|t| t.ids).collect();
    ids.retain(|&id| id != node::NO_ITEM);
    ids.iter_mut().for_each(|id| *id &= !node::OTHER);
    ids.sort_unstable();
    assert!(ids.iter().copied().eq(0..prims.len() as u32 - 4), "{ids:?}");
    assert_agrees(&b, &prims, 3000);
}

/// The tree's SAH cost, from its stored boxes: the root step, plus for
/// every child box its surface area relative to the root's, times 1 for
/// a node and times its number of 4-triangle blocks for a leaf.
fn sah_cost(b: &Bvh8) -> f64 {
    use node::{is_leaf, leaf_range, EMPTY};
    let area = |n: &node::Node, i: usize| {
        let p = &n.planes;
        let lo = Vec3::new(p[0][i], p[1][i], p[2][i]);
        let hi = Vec3::new(p[3][i], p[4][i], p[5][i]);
        Aabb::new(lo, hi).surface_area() as f64
    };
    let root = &b.nodes[0];
    let mut root_box = Aabb::new(Vec3::INFINITY, Vec3::NEG_INFINITY);
    let mut sum = 0.0;
    for n in &b.nodes {
        for i in 0..lanes::W {
            let c = n.child[i];
            if c == EMPTY {
                continue;
            }
            let weight = if is_leaf(c) {
                leaf_range(c).1 as f64
            } else {
                1.0
            };
            sum += weight * area(n, i);
            if std::ptr::eq(n, root) {
                let p = &n.planes;
                root_box = root_box
                    .grow(Vec3::new(p[0][i], p[1][i], p[2][i]))
                    .grow(Vec3::new(p[3][i], p[4][i], p[5][i]));
            }
        }
    }
    1.0 + sum / root_box.surface_area() as f64
}

/// Build quality, which no agreement test can see (any tree gives
/// the right hits): the SAH cost of the tree and the nodes and
/// triangles a fixed set of rays visits stay within 3% of the values
/// measured with the builder as it is, either way. A build that splits
/// worse (a wrong bin, a wrong cost, a wrong axis) exceeds them; a
/// counter that stops counting falls below; a deliberate change to the
/// builder updates the table (its commit says from what).
#[test]
fn build_quality_stays_where_it_was_measured() {
    // (mesh, and its measured SAH cost, nodes and tests a ray pair)
    for (name, prims, cost_max, nodes_max, tests_max) in [
        ("soup", soup(5, 3000), 34.320, 14.04, 51.52),
        ("terrain", terrain(), 8.000, 9.19, 13.74),
    ] {
        let b = Bvh8::new(&prims, all(&prims));
        let cost = sah_cost(&b);
        let mut c = Counters::default();
        let mut r = crate::accel::testutil::Rng::new(11);
        let rays = 2000;
        for _ in 0..rays {
            let ray = if name == "soup" {
                crate::accel::testutil::ray(&mut r)
            } else {
                crate::accel::testutil::terrain_ray(&mut r)
            };
            b.intersect(Query::new(&prims, &ray, 0.0, f32::INFINITY), &mut c);
            b.occluded(Query::new(&prims, &ray, 0.0, f32::INFINITY), &mut c);
        }
        let nodes = c.nodes_visited as f64 / rays as f64;
        let tests = c.intersection_tests as f64 / rays as f64;
        eprintln!("{name}: SAH cost {cost:.3}, {nodes:.2} nodes and {tests:.2} tests a ray pair");
        // Both ways: more is a worse build, less (or none) a counter
        // that stopped counting; a real improvement updates the table.
        let near = |v: f64, m: f64| (v - m).abs() <= 0.03 * m;
        assert!(near(cost, cost_max), "{name}: SAH cost {cost}");
        assert!(near(nodes, nodes_max), "{name}: {nodes} nodes a ray pair");
        assert!(
            near(tests, tests_max),
            "{name}: {tests} triangle tests a ray pair"
        );
    }
}

/// The parallel build (a range of 4k items or more has its children
/// built on other threads, their nodes appended and renumbered) makes
/// the one-thread build's tree, node for node and block for block.
#[test]
fn the_parallel_build_equals_the_serial_one() {
    let prims = soup(8, 40_000);
    let build = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool")
            .install(|| Bvh8::new(&prims, all(&prims)))
    };
    let (one, four) = (build(1), build(4));
    assert_eq!(one.nodes.len(), four.nodes.len());
    assert!(one.nodes.len() > 1000);
    for (a, b) in one.nodes.iter().zip(&four.nodes) {
        assert_eq!((a.child, a.split), (b.child, b.split));
        assert_eq!(format!("{:?}", a.planes), format!("{:?}", b.planes));
    }
    assert_eq!(format!("{:?}", one.tris), format!("{:?}", four.tris));
}

/// The same on a mesh built from its vertex and index buffers (the
/// embedder's path, `query::MeshScene`), large enough that its top levels
/// are divided ahead and partitioned on several threads: a 330×330 grid
/// of bumpy quads (218k triangles) stored row by row, on 1 and 2 threads.
#[test]
fn a_mesh_built_on_two_threads_equals_the_serial_one() {
    let k = 330;
    let vertices: Vec<Vec3> = (0..=k)
        .flat_map(|i| {
            (0..=k).map(move |j| {
                let (x, z) = (i as f32 * 0.1, j as f32 * 0.1);
                Vec3::new(x, (x * 1.3).sin() * (z * 0.7).cos(), z)
            })
        })
        .collect();
    let at = |i: usize, j: usize| (i * (k + 1) + j) as u32;
    let indices: Vec<[u32; 3]> = (0..k)
        .flat_map(|i| (0..k).map(move |j| (i, j)))
        .flat_map(|(i, j)| {
            [
                [at(i, j), at(i + 1, j), at(i, j + 1)],
                [at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)],
            ]
        })
        .collect();
    let build = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool")
            .install(|| Bvh8::from_mesh(&vertices, &indices))
    };
    let (one, two) = (build(1), build(2));
    assert_eq!(one.nodes.len(), two.nodes.len());
    assert!(one.nodes.len() > 5_000, "{}", one.nodes.len());
    for (a, b) in one.nodes.iter().zip(&two.nodes) {
        assert_eq!((a.child, a.split), (b.child, b.split));
        assert_eq!(format!("{:?}", a.planes), format!("{:?}", b.planes));
    }
    assert_eq!(format!("{:?}", one.tris), format!("{:?}", two.tris));
}

/// Each node's slots run from the lower to the upper side of its first
/// division, whose axis `Node::split` names (what the any-hit walk's
/// order relies on): on a lattice of small triangles, 24 by 12 by 6 of
/// them (so nodes divide on every axis), the children's centres along
/// that axis split into a lower run of slots and an upper one. A wrong
/// axis, or slots out of order, puts centres of both runs on both sides.
#[test]
fn slots_run_along_the_first_division() {
    let (nx, ny, nz) = (24, 12, 6);
    let mut vertices = Vec::new();
    for i in 0..nx * ny * nz {
        let c = Vec3::new(
            (i % nx) as f32,
            (i / nx % ny) as f32,
            (i / (nx * ny)) as f32,
        );
        vertices.extend([
            c,
            c + Vec3::new(0.1, 0.0, 0.0),
            c + Vec3::new(0.0, 0.1, 0.1),
        ]);
    }
    let indices: Vec<[u32; 3]> = (0..nx * ny * nz)
        .map(|i| [0, 1, 2].map(|k| (3 * i + k) as u32))
        .collect();
    let b = Bvh8::from_mesh(&vertices, &indices);
    let mut axes = [0; 3];
    for n in &b.nodes {
        let len = n.child.iter().take_while(|&&c| c != node::EMPTY).count();
        if len < 2 {
            continue;
        }
        assert_eq!(n.split.count_ones(), 1, "{:#b}", n.split);
        let a = n.split.trailing_zeros() as usize;
        assert!(a < 3);
        axes[a] += 1;
        let centre = |i: usize| 0.5 * (n.planes[a][i] + n.planes[a + 3][i]);
        let parted = (1..len).any(|k| {
            let low = (0..k).map(centre).fold(f32::MIN, f32::max);
            let high = (k..len).map(centre).fold(f32::MAX, f32::min);
            low < high
        });
        assert!(parted, "{:?}", (0..len).map(centre).collect::<Vec<_>>());
    }
    // Measured: nodes first divided on each axis.
    assert!(axes.iter().all(|&n| n >= 3), "{axes:?}");
    eprintln!("nodes first divided on x, y, z: {axes:?}");
}

/// Every item sits in exactly one lane of one block, and each leaf's
/// blocks hold exactly its items (leaves of up to eight items take two
/// blocks; the second holds what the first could not).
#[test]
fn every_item_is_in_one_block_of_its_leaf() {
    use crate::accel::testutil::{prim, Rng};
    use crate::shape::{Shape, Triangle};
    use node::{is_leaf, leaf_range, EMPTY, NO_ITEM, OTHER};
    // 50 piles of 6 copies of a triangle: no plane separates a pile, so
    // each is a leaf of six items (two blocks); and a soup.
    let mut r = Rng::new(13);
    let mut prims = soup(12, 1000);
    for _ in 0..50 {
        let a = r.v(-20.0, 20.0);
        let t = Triangle::new(a, a + Vec3::X, a + Vec3::Y);
        prims.extend((0..6).map(|_| prim(Shape::Triangle(t))));
    }
    let b = Bvh8::new(&prims, all(&prims));
    let mut seen = vec![0u32; prims.len()];
    let mut leaves = 0;
    for n in &b.nodes {
        for &c in &n.child {
            if c == EMPTY || !is_leaf(c) {
                continue;
            }
            let (first, blocks) = leaf_range(c);
            for t in &b.tris[first..first + blocks] {
                let used = t.ids.iter().filter(|&&id| id != NO_ITEM).count();
                assert!(used > 0);
                for &id in t.ids.iter().filter(|&&id| id != NO_ITEM) {
                    seen[(id & !OTHER) as usize] += 1;
                }
            }
            leaves += 1;
        }
    }
    assert!(leaves > 100);
    assert!(
        seen.iter().all(|&k| k == 1),
        "an item in no block or in two"
    );
}

/// A build of more than `build::LARGE_ITEMS` items (split cost 2.5 and
/// leaves of up to eight blocks) makes leaves of more than four blocks,
/// holds each item in one block, and agrees with brute force: a height
/// field of 263,538 triangles, rays down onto it, rays of random direction
/// from above it and bounded ones.
#[test]
fn a_large_build_agrees_with_brute_force() {
    use crate::accel::testutil::{assert_agrees_on, prim, Rng};
    use crate::shape::{Shape, Triangle};
    use node::{is_leaf, leaf_range, EMPTY, NO_ITEM, OTHER};
    let k = 363;
    let y = |i: usize, j: usize| ((i as f32 * 0.05).sin() + (j as f32 * 0.07).cos()) * 3.0;
    let v = |i: usize, j: usize| Vec3::new(i as f32 * 0.2, y(i, j), j as f32 * 0.2);
    let mut prims = Vec::with_capacity(2 * k * k);
    for i in 0..k {
        for j in 0..k {
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i, j + 1), v(i + 1, j + 1));
            prims.push(prim(Shape::Triangle(Triangle::new(a, b, d))));
            prims.push(prim(Shape::Triangle(Triangle::new(a, d, c))));
        }
    }
    assert!(prims.len() > 1 << 18, "{}", prims.len());
    let b = Bvh8::new(&prims, all(&prims));
    let mut seen = vec![0u8; prims.len()];
    let mut widest = 0;
    for n in &b.nodes {
        for &c in n.child.iter().filter(|&&c| c != EMPTY && is_leaf(c)) {
            let (first, blocks) = leaf_range(c);
            widest = widest.max(blocks);
            for t in &b.tris[first..first + blocks] {
                for &id in t.ids.iter().filter(|&&id| id != NO_ITEM) {
                    seen[(id & !OTHER) as usize] += 1;
                }
            }
        }
    }
    assert!(widest > 4, "the widest leaf holds {widest} blocks");
    assert!(
        seen.iter().all(|&s| s == 1),
        "an item in no block or in two"
    );
    let size = 0.2 * k as f32;
    let mut r = Rng::new(29);
    let queries: Vec<_> = (0..150)
        .map(|i| {
            let o = Vec3::new(size * r.f(), 4.0 + 4.0 * r.f(), size * r.f());
            let dir = if i % 2 == 0 {
                Vec3::new(size * r.f(), 0.0, size * r.f()) - o
            } else {
                r.v(-1.0, 1.0)
            };
            let (tmin, tmax) = if i % 3 == 0 {
                (0.5, 20.0)
            } else {
                (0.0, f32::INFINITY)
            };
            (Ray::new(o, dir), tmin, tmax)
        })
        .collect();
    let hits = queries
        .iter()
        .filter(|(ray, tmin, tmax)| {
            let q = Query::new(&prims, ray, *tmin, *tmax);
            b.intersect(q, &mut Counters::default()).is_some()
        })
        .count();
    assert!(hits > 50, "{hits} of 150 rays hit");
    assert_agrees_on(&b, &prims, queries);
}
#[test]
fn nearest_first_visits_few_nodes() {
    let prims: Vec<Primitive> = (0..4096)
        .map(|i| sphere(Vec3::X * (3.0 * i as f32), 1.0))
        .collect();
    let b = Bvh8::new(&prims, all(&prims));
    let r = Ray::new(Vec3::X * -5.0, Vec3::X);
    let mut c = Counters::default();
    let h = b
        .intersect(Query::new(&prims, &r, 0.0, f32::INFINITY), &mut c)
        .unwrap();
    assert_eq!(h.prim, 0);
    // Depth is about log8(4096 / 4) = 4; ordered traversal stops right after.
    assert!(c.nodes_visited <= 12, "{c:?}");
}

/// Rays parallel to axes (`+0` and `−0` components, and components far
/// below the `1e-18` the slab test clamps to), some running exactly
/// along the terrain's grid planes and its boxes' faces, find brute
/// force's hits; and they still cull on the axes they do not move
/// along: straight down, they visit no more nodes than the same rays
/// tilted a little (a zero component's slab, left NaN, would keep every
/// box at the ray's height: several times as many).
#[test]
fn axis_parallel_rays_agree_and_still_cull() {
    let prims = terrain();
    let b = Bvh8::new(&prims, all(&prims));
    let mut r = crate::accel::testutil::Rng::new(5);
    let mut queries = Vec::new();
    for i in 0..400 {
        let (x, z) = (64.0 * r.f(), 64.0 * r.f());
        let (x, z) = if i % 4 == 0 {
            (x.floor(), z.floor())
        } else {
            (x, z)
        };
        let (sx, sz) = if i % 2 == 0 {
            (0.0, -0.0)
        } else {
            (-1e-30, 1e-25)
        };
        queries.push((
            Ray::new(Vec3::new(x, 30.0, z), Vec3::new(sx, -1.0, sz)),
            0.0,
            f32::INFINITY,
        ));
        let along_x = Ray::new(
            Vec3::new(-3.0, -1.0 + 2.0 * r.f(), z),
            Vec3::new(1.0, 0.0, sz),
        );
        queries.push((along_x, 0.0, f32::INFINITY));
    }
    let mut c = Counters::default();
    crate::accel::testutil::assert_agrees_on(&b, &prims, queries.iter().copied());
    for (q, _, _) in queries.iter().step_by(2) {
        b.intersect(Query::new(&prims, q, 0.0, f32::INFINITY), &mut c);
    }
    let mut tilted = Counters::default();
    for (q, _, _) in queries.iter().step_by(2) {
        let d = Vec3::new(1e-3, -1.0, 1e-3);
        b.intersect(
            Query::new(&prims, &Ray::new(q.origin, d), 0.0, f32::INFINITY),
            &mut tilted,
        );
    }
    assert!(
        c.nodes_visited <= tilted.nodes_visited + tilted.nodes_visited / 10,
        "{} nodes straight down, {} tilted",
        c.nodes_visited,
        tilted.nodes_visited
    );
}

/// Queries the integer reduction cannot take (a negative `tmin`, `−0`,
/// an origin so far out that `origin · inv` overflows) run the float
/// one and still find brute force's hits, closest and any.
#[test]
fn queries_off_the_integer_path_agree_with_brute_force() {
    let prims = soup(13, 2000);
    let b = Bvh8::new(&prims, all(&prims));
    let mut r = crate::accel::testutil::Rng::new(3);
    let mut queries = Vec::new();
    for i in 0..600 {
        let q = crate::accel::testutil::ray(&mut r);
        let tmin = [-1.0, -0.0, -1e-3][i % 3];
        queries.push((q, tmin, f32::INFINITY));
        // From 1e22 away, aimed back through the soup (the integer
        // path: `origin · inv` is about 1); then a ray parallel to y at
        // y = 4e20, whose clamped `inv` (1e18) overflows that product:
        // only a ray that cannot reach the scene in finite `t` can.
        let far = Ray::new(q.origin * 1e22, q.origin * -1e22);
        queries.push((far, 0.5, 1.5));
        let along = Ray::new(Vec3::new(1e21, 4e20, q.origin.z), Vec3::NEG_X);
        queries.push((along, 0.0, f32::INFINITY));
    }
    // A NaN direction component: nothing is hit, by either.
    let nan = Ray::new(Vec3::ZERO, Vec3::new(f32::NAN, 1.0, 0.5));
    queries.push((nan, 0.0, f32::INFINITY));
    let rd = |q: usize| traverse::RayData::new(&queries[q].0);
    assert!(rd(1).reduce_as_ints(0.5));
    assert!(!rd(2).reduce_as_ints(0.0), "the origin's product overflows");
    crate::accel::testutil::assert_agrees_on(&b, &prims, queries);
}

/// A coherent query (each descent by the ray's octant) returns the usual
/// walk's hit and barycentrics, bit for bit, and visits the same nodes and
/// tests the same triangles: on rays of every octant in random order, and
/// on a fan of camera rays in scan order, on both the dispatched and the
/// portable copy.
#[test]
fn the_coherent_walk_is_the_usual_walk() {
    let prims = soup(17, 4000);
    let b = Bvh8::new(&prims, all(&prims));
    assert!(!b.deep);
    let mut r = crate::accel::testutil::Rng::new(8);
    let mut rays: Vec<Ray> = (0..1500)
        .map(|_| crate::accel::testutil::ray(&mut r))
        .collect();
    for y in 0..40 {
        for x in 0..40 {
            let d = Vec3::new(x as f32 / 20.0 - 1.0, y as f32 / 20.0 - 1.0, 1.0);
            rays.push(Ray::new(Vec3::new(0.1, -0.2, -6.0), d));
        }
    }
    let octants: std::collections::HashSet<usize> = rays
        .iter()
        .map(|q| traverse::RayData::new(q).octant())
        .collect();
    assert_eq!(octants.len(), 8);
    let tree = b.tree(&prims[..]);
    let (mut hits, mut c1, mut c2) = (0, Counters::default(), Counters::default());
    for q in &rays {
        for tmax in [f32::INFINITY, 0.7] {
            let query = &Query::new(&prims, q, 0.0, tmax);
            let plain = dispatch::run(ClosestHit::<_, _, traverse::Closest, false> {
                tree,
                query,
                stats: &mut c1,
                hit: PhantomData,
            });
            let coherent = |stats| ClosestHit::<_, _, traverse::Closest, true> {
                tree,
                query,
                stats,
                hit: PhantomData,
            };
            assert_eq!(dispatch::run(coherent(&mut c2)), plain, "{q:?}");
            let mut c3 = Counters::default();
            assert_eq!(dispatch::run_portable(coherent(&mut c3)), plain, "{q:?}");
            hits += usize::from(plain.is_some());
        }
    }
    assert_eq!(format!("{c1:?}"), format!("{c2:?}"));
    assert!((500..5500).contains(&hits), "{hits}");
}

#[test]
fn both_stack_sizes_agree() {
    let prims = soup(9, 3000);
    let b = Bvh8::new(&prims, all(&prims));
    let d = build::depth(&b.nodes);
    assert!((2..=traverse::SHALLOW_DEPTH).contains(&d), "{d}");
    assert!(!b.deep);
    let deep = Bvh8 { deep: true, ..b };
    for i in 0..2000 {
        let f = i as f32;
        let o = Vec3::new((f * 0.37).sin(), (f * 0.73).cos(), -9.0);
        let r = Ray::new(
            o,
            Vec3::new((f * 0.11).cos() * 0.3, (f * 0.29).sin() * 0.3, 1.0),
        );
        let stats = &mut crate::stats::NoStats;
        for deep_stack in [false, true] {
            let tree = Tree {
                deep: deep_stack,
                ..deep.tree(&prims[..])
            };
            let (tmin, tmax) = (0.0, f32::INFINITY);
            let query = &Query::new(&prims, &r, tmin, tmax);
            let c = dispatch::run(ClosestHit::<_, _, traverse::Closest> {
                tree,
                query,
                stats,
                hit: PhantomData,
            });
            assert_eq!(c, deep.closest_hit(&prims[..], &r, tmin, tmax, stats));
            let skip = NO_ITEM;
            let a = dispatch::run(AnyHit {
                tree,
                query,
                skip,
                stats,
            });
            assert_eq!(a, c.is_some());
        }
    }
}

/// A tree deeper than the shallow stack serves gets the deep one, and a
/// ray that needs it gets through. Triangles at x = 1.2^k (k < 400),
/// all of one shape across the x axis, make a chain: binned over the
/// whole range, every split peels off the few largest, so each node
/// holds a child with the rest. A ray along the x axis from the small
/// end passes through every box and hits no triangle (each covers
/// y + z ≥ 1/2 of its box), so it visits the chain child first and
/// keeps every other child of every level pending: more entries than
/// the shallow stack holds (with it, the walk indexes entry 64 of 64).
/// Also the memory and node count reported.
#[test]
fn a_deep_tree_uses_the_deep_stack() {
    let prims = crate::accel::testutil::chain(400);
    let b = Bvh8::new(&prims, all(&prims));
    let d = build::depth(&b.nodes);
    assert!(d > traverse::SHALLOW_DEPTH, "depth {d}");
    // Planned for its level, every node sits within the deepest level.
    assert!(d <= build::MAX_DEPTH, "depth {d}");
    assert!(b.deep);
    let ray = Ray::new(Vec3::new(0.5, 0.0, 0.0), Vec3::X);
    let mut c = Counters::default();
    assert!(b
        .intersect(Query::new(&prims, &ray, 0.0, f32::INFINITY), &mut c)
        .is_none());
    assert!(!b.occluded(Query::new(&prims, &ray, 0.0, f32::INFINITY), &mut c));
    // It tested every triangle, so it entered every leaf.
    assert_eq!(c.intersection_tests, 2 * 400, "{c:?}");
    let back = Ray::new(Vec3::new(0.5, 0.9, 0.9), Vec3::X);
    assert!(b
        .intersect(Query::new(&prims, &back, 0.0, f32::INFINITY), &mut c)
        .is_some());
    assert_eq!(b.memory_bytes(), 256 * b.node_count() + 160 * b.tris.len());
    assert!(b.node_count() > d);
}

/// The barycentrics the traversal hands out are the ones the world's
/// `Triangle::surface` would re-run the test for, bit for bit (and a
/// fallback item, the soup's spheres, has none).
#[test]
fn barycentrics_are_the_triangles_own() {
    let prims = soup(12, 3000);
    let b = Bvh8::new(&prims, all(&prims));
    let mut hits = 0;
    for i in 0..3000 {
        let f = i as f32;
        let o = Vec3::new((f * 0.37).sin(), (f * 0.73).cos(), -9.0);
        let r = Ray::new(
            o,
            Vec3::new((f * 0.11).cos() * 0.3, (f * 0.29).sin() * 0.3, 1.0),
        );
        let Some(h) = b.closest_hit(
            &prims[..],
            &r,
            0.0,
            f32::INFINITY,
            &mut crate::stats::NoStats,
        ) else {
            continue;
        };
        let crate::shape::Shape::Triangle(tr) = &prims[h.id as usize].shape else {
            assert_eq!(h.bary, None, "a sphere's hit has no barycentrics");
            continue;
        };
        let own = tr.hit(&r, f32::NEG_INFINITY, f32::INFINITY).unwrap();
        assert_eq!(h.bary.unwrap().map(f32::to_bits), own.b.map(f32::to_bits));
        assert_eq!(tr.surface_at(own.b), tr.surface(&r, h.t));
        hits += 1;
    }
    assert!(hits > 100, "{hits}");
}

/// Skipping the triangle a ray leaves changes no answer: shadow rays
/// spawned off triangle hits in every direction (most of them start in
/// a leaf holding their own triangle) are blocked exactly when `any`
/// says so. And the skip is real: a ray through one triangle alone is
/// blocked unless that triangle is skipped.
#[test]
fn skipping_the_triangle_a_ray_leaves_changes_no_answer() {
    let prims = soup(14, 3000);
    let b = Bvh8::new(&prims, all(&prims));
    let ns = &mut crate::stats::NoStats;
    let inf = f32::INFINITY;
    let (mut rays, mut blocked) = (0, 0);
    for i in 0..3000 {
        let f = i as f32;
        let o = Vec3::new((f * 0.37).sin(), (f * 0.73).cos(), -9.0);
        let r = Ray::new(
            o,
            Vec3::new((f * 0.11).cos() * 0.3, (f * 0.29).sin() * 0.3, 1.0),
        );
        let Some(h) = b.closest_hit(&prims[..], &r, 0.0, inf, ns) else {
            continue;
        };
        let (crate::shape::Shape::Triangle(tr), Some(bary)) = (&prims[h.id as usize].shape, h.bary)
        else {
            continue;
        };
        let sp = tr.surface_at(bary);
        for k in 0..16 {
            let g = (i * 16 + k) as f32;
            let w = Vec3::new((g * 0.71).sin(), (g * 1.37).cos(), (g * 0.53).sin() - 0.2);
            let s = sp.spawn_ray(w);
            let all = b.any(&prims[..], &s, 0.0, inf, ns);
            assert_eq!(
                all,
                b.any_except(&prims[..], &s, 0.0, inf, h.id, ns),
                "{s:?}"
            );
            rays += 1;
            blocked += usize::from(all);
        }
    }
    eprintln!("{blocked} of {rays} spawned rays blocked");
    assert!(
        rays > 5000 && blocked > rays / 20 && blocked < rays,
        "{blocked} of {rays}"
    );
    // One triangle, a ray through its centroid.
    let one = vec![prims
        .iter()
        .find(|p| matches!(p.shape, crate::shape::Shape::Triangle(_)))
        .unwrap()
        .clone()];
    let crate::shape::Shape::Triangle(tr) = &one[0].shape else {
        unreachable!()
    };
    let c = (tr.v[0] + tr.v[1] + tr.v[2]) / 3.0;
    let s = Ray::new(c - 3.0 * tr.normal, tr.normal);
    let b1 = Bvh8::new(&one, vec![0]);
    assert!(b1.any(&one[..], &s, 0.0, inf, ns));
    assert!(!b1.any_except(&one[..], &s, 0.0, inf, 0, ns));
    assert!(b1.any_except(&one[..], &s, 0.0, inf, 1, ns));
    // The same triangle again behind the ray's origin, in the same
    // block: the 4-lane pre-test (which ignores the `t` range) keeps
    // both lanes, the exact test hits the skipped one alone.
    let mut two = vec![one[0].clone(), one[0].clone()];
    let behind = |p: Vec3| p - 6.0 * tr.normal;
    two[1].shape = crate::shape::Shape::Triangle(crate::shape::Triangle::new(
        behind(tr.v[0]),
        behind(tr.v[1]),
        behind(tr.v[2]),
    ));
    let b2 = Bvh8::new(&two, vec![0, 1]);
    assert_eq!(b2.tris.len(), 1, "one block");
    assert!(b2.any(&two[..], &s, 0.0, inf, ns));
    assert!(!b2.any_except(&two[..], &s, 0.0, inf, 0, ns));
}

#[test]
fn statistics_are_optional() {
    let prims = soup(5, 500);
    let b = Bvh8::new(&prims, all(&prims));
    let r = Ray::new(Vec3::new(-9.0, 0.1, 0.2), Vec3::X);
    let mut c = Counters::default();
    let with = b.closest(&prims[..], &r, 0.0, f32::INFINITY, &mut c);
    let without = b.closest(
        &prims[..],
        &r,
        0.0,
        f32::INFINITY,
        &mut crate::stats::NoStats,
    );
    assert_eq!(with, without);
    assert!(c.nodes_visited > 0);
}
