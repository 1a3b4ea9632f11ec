//! The traversal's unit tests.

use super::super::build::{self, MAX_DEPTH};
use super::*;
use crate::accel::bvh8::node::leaf;
use crate::stats::NoStats;

/// The worst case for the stack: a chain of `MAX_DEPTH` inner nodes,
/// each with seven leaves beside the next node, and a ray through every
/// box, the next node's nearest (and in the last slot, which `any`
/// follows first in a node of unknown division). Every leaf is an empty
/// block but the last, one triangle at x = 4.
fn caterpillar() -> (Vec<Node>, Vec<Tri4>) {
    let mut tri = Tri4::EMPTY;
    let v = [[4.0, -1.0, -1.0], [4.0, 2.0, -1.0], [4.0, -1.0, 2.0]];
    for (k, vk) in v.iter().enumerate() {
        for (a, &c) in vk.iter().enumerate() {
            tri.v[k][a].x = c;
        }
    }
    tri.ids[0] = 7;
    let tris = vec![Tri4::EMPTY, tri];
    let nodes = (0..MAX_DEPTH)
        .map(|i| {
            let mut n = Node::EMPTY;
            let next = if i + 1 < MAX_DEPTH {
                i as u32 + 1
            } else {
                leaf(1, 1)
            };
            n.set(W - 1, next, Vec3::splat(-5.0), Vec3::splat(5.0));
            for s in 0..W - 1 {
                n.set(s, leaf(0, 1), Vec3::new(0.0, -5.0, -5.0), Vec3::splat(5.0));
            }
            n
        })
        .collect();
    (nodes, tris)
}

/// [`DEEP`] entries serve the deepest tree the builder makes, with a
/// ray that leaves `W − 1` children pending at every level, and one
/// entry fewer does not: the bound is exact.
#[test]
fn a_worst_case_tree_fills_the_deep_stack() {
    let (nodes, tris) = caterpillar();
    assert_eq!(build::depth(&nodes), MAX_DEPTH);
    let rd = RayData::new(&Ray::new(Vec3::new(-10.0, 0.0, 0.0), Vec3::X));
    // Both walks with an `N`-entry stack, up to `tmax`: `None` if the
    // stack overflowed (a panic), else the closest hit and `any`.
    fn walks<const N: usize>(
        nodes: &[Node],
        tris: &[Tri4],
        rd: &RayData,
        tmax: f32,
    ) -> Option<(Option<Closest>, bool)> {
        let s = &mut NoStats;
        let tree = &Tree {
            nodes,
            tris,
            fallback: &TrianglesOnly,
            deep: true,
        };
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let hit = closest::<_, _, _, N, ANY_OCTANT, true>(Portable, tree, rd, 0.0, tmax, s);
            let range = (0.0, tmax);
            let any = any::<_, _, _, N, ANY_OCTANT, true>(Portable, tree, rd, range, NO_ITEM, s);
            (hit, any)
        }))
        .ok()
    }
    let (hit, blocked) = walks::<DEEP>(&nodes, &tris, &rd, f32::INFINITY).expect("enough");
    let hit = hit.expect("the triangle at x = 4");
    assert_eq!((hit.t, hit.id), (14.0, 7));
    assert!(blocked);
    // A ray that stops short of the triangle: both walks go through the
    // whole chain, every leaf pending.
    assert_eq!(walks::<DEEP>(&nodes, &tris, &rd, 13.0), Some((None, false)));
    const SHORT: usize = DEEP - 1;
    assert!(walks::<SHORT>(&nodes, &tris, &rd, f32::INFINITY).is_none());
    assert!(walks::<SHORT>(&nodes, &tris, &rd, 13.0).is_none());
}

/// Each octant's compile-time planes are the ones `RayData` picks at run
/// time for a ray in that octant (zero components included: `−0` runs
/// towards −axis, `+0` towards +axis), so each octant's copy of the walk
/// tests the same planes.
#[test]
fn octant_copies_use_the_rays_planes() {
    fn check<const O: usize>() {
        for zero in [false, true] {
            let c = |a: usize, x: f32| {
                let x = if zero && a == O % 3 { 0.0 } else { x };
                if (O >> a) & 1 == 1 {
                    -x
                } else {
                    x
                }
            };
            let dir = Vec3::new(c(0, 0.3), c(1, 0.5), c(2, 0.7));
            let rd = RayData::new(&Ray::new(Vec3::new(0.1, -0.2, 0.3), dir));
            assert_eq!(rd.octant(), O, "{dir:?}");
            assert_eq!(rd.planes::<O>(), rd.planes::<ANY_OCTANT>(), "{dir:?}");
            let mut node = Node::EMPTY;
            node.set(0, 0, Vec3::splat(-1.0), Vec3::splat(1.0));
            node.set(1, 0, Vec3::splat(0.5), Vec3::splat(2.0));
            let (tmin, tmax) = (Lanes::splat(0.0), Lanes::splat(10.0));
            for ((m, d), (rm, rdist)) in [
                (
                    rd.boxes::<_, O, false>(Portable, &node, tmin, tmax),
                    rd.boxes::<_, ANY_OCTANT, false>(Portable, &node, tmin, tmax),
                ),
                (
                    rd.boxes::<_, O, true>(Portable, &node, tmin, tmax),
                    rd.boxes::<_, ANY_OCTANT, true>(Portable, &node, tmin, tmax),
                ),
            ] {
                assert_eq!(
                    (m, d.to_array().map(f32::to_bits)),
                    (rm, rdist.to_array().map(f32::to_bits))
                );
                assert_eq!(m & 1, 1, "the box around the origin");
            }
        }
    }
    check::<0>();
    check::<1>();
    check::<2>();
    check::<3>();
    check::<4>();
    check::<5>();
    check::<6>();
    check::<7>();
}

/// Whole numbers in `[-4, 4]` from the tests' generator: boxes and
/// origins on a shared grid, so origins on planes and zero direction
/// components come up often.
struct Grid(crate::testutil::Rng);

impl Grid {
    fn next(&mut self) -> f32 {
        self.0.below(9) as f32 - 4.0
    }

    /// A node with seven or eight boxes (the rest empty).
    fn node(&mut self) -> Node {
        let mut node = Node::EMPTY;
        for i in 0..W - (self.next() > 2.0) as usize {
            let lo = Vec3::new(self.next(), self.next(), self.next());
            let hi = lo + Vec3::new(self.next().abs(), self.next().abs(), self.next().abs());
            node.set(i, 0, lo, hi);
        }
        node
    }

    /// A ray from a grid point, its direction half the grid's values
    /// in x and y and `z` times them in z.
    fn ray(&mut self, z: f32) -> RayData {
        let dir = Vec3::new(self.next() * 0.5, self.next() * 0.5, self.next() * z);
        RayData::new(&Ray::new(
            Vec3::new(self.next(), self.next(), self.next()),
            dir,
        ))
    }
}

/// The AVX box test gives the portable test's masks and distances bit
/// for bit, directions with zero components (clamped by
/// `safe_inverse`) and origins on a box's planes included.
#[cfg(target_arch = "x86_64")]
#[test]
fn avx_boxes_match_portable() {
    if !crate::testdata::avx2_fma("avx_boxes_match_portable") {
        return;
    }
    // SAFETY: AVX2 and FMA detected just above.
    let avx = unsafe { Avx::new() };
    let mut g = Grid(crate::testutil::Rng::new(0x9e37_79b9));
    for _ in 0..20_000 {
        let node = g.node();
        let rd = g.ray(0.5);
        let dir = rd.ray.dir;
        let (tmin, tmax) = (Lanes::splat(0.0), Lanes::splat(g.next().abs() + 1.0));
        for ((pm, pd), (am, ad)) in [
            (
                rd.boxes::<_, ANY_OCTANT, false>(Portable, &node, tmin, tmax),
                rd.boxes::<_, ANY_OCTANT, false>(avx, &node, tmin, tmax),
            ),
            (
                rd.boxes::<_, ANY_OCTANT, true>(Portable, &node, tmin, tmax),
                rd.boxes::<_, ANY_OCTANT, true>(avx, &node, tmin, tmax),
            ),
        ] {
            assert_eq!(pm, am);
            for i in 0..W {
                assert_eq!(pd[i].to_bits(), ad[i].to_bits(), "{dir:?} lane {i}");
            }
        }
    }
}

/// The integer reduction keeps exactly the boxes the float one keeps,
/// at the same entry distances, but for boxes the ray leaves at `t = 0`
/// exactly (a far distance of `−0`: no hit in `t > tmin ≥ 0` can lie
/// there), on random boxes and rays with `tmin` of `+0` and above;
/// and a query with a negative `tmin`, `−0` or an infinite
/// `origin · inv` does not use it.
#[test]
fn integer_reduction_keeps_the_float_tests_boxes() {
    let mut g = Grid(crate::testutil::Rng::new(0x1234_5678));
    let mut kept = 0;
    for _ in 0..20_000 {
        let node = g.node();
        let rd = g.ray(0.75);
        let dir = rd.ray.dir;
        let t0 = g.next().abs() * 0.25;
        assert!(rd.reduce_as_ints(t0));
        let (tmin, tmax) = (Lanes::splat(t0), Lanes::splat(t0 + g.next().abs() + 1.0));
        let (fm, fd) = rd.boxes::<_, ANY_OCTANT, false>(Portable, &node, tmin, tmax);
        let (im, id) = rd.boxes::<_, ANY_OCTANT, true>(Portable, &node, tmin, tmax);
        kept += im.count_ones();
        for i in 0..W {
            let (f, k) = (fm >> i & 1 == 1, im >> i & 1 == 1);
            if f && k {
                assert_eq!(fd[i], id[i], "{dir:?} lane {i}");
            } else if f != k {
                assert!(
                    f && !k,
                    "the integer test kept a box the float test rejects"
                );
                // A far distance of exactly `−0`, the only value `≥ 0`
                // as a float and negative as an integer.
                let (_, far) = rd.planes::<ANY_OCTANT>();
                let minus_zero = (0..3).any(|a| {
                    let t = node.planes[far[a]][i].mul_add(rd.inv[a][0], -rd.oi[a][0]);
                    t.to_bits() == (-0f32).to_bits()
                });
                assert!(t0 == 0.0 && minus_zero, "{dir:?} lane {i}");
            }
        }
    }
    // Measured: 4,753 boxes kept (and the float test's answer checked
    // on every one of the 160,000 lanes).
    assert!(kept > 2_000, "{kept}");
    let rd = RayData::new(&Ray::new(Vec3::ZERO, Vec3::X));
    assert!(rd.reduce_as_ints(0.0) && !rd.reduce_as_ints(-0.0));
    assert!(!rd.reduce_as_ints(-1e-3) && !rd.reduce_as_ints(f32::NAN));
    let far = RayData::new(&Ray::new(Vec3::new(1e21, 0.0, 0.0), Vec3::Y));
    assert!(!far.reduce_as_ints(0.0), "1e21 · 1e18 overflows");
}

/// `Nearest::test_tmax` (its own bit arithmetic) is `f32::next_up` of the
/// best hit's `t` for finite values of every kind, and `tmax` itself
/// before any hit.
#[test]
fn test_tmax_is_next_up_of_the_best_hit() {
    let mut r = crate::testutil::Rng::new(42);
    let mut ts = vec![
        0.0,
        -0.0,
        f32::from_bits(1),
        -f32::from_bits(1),
        f32::MIN_POSITIVE,
        -f32::MIN_POSITIVE,
        1.0,
        -1.0,
        f32::MAX,
        f32::MIN,
    ];
    ts.extend(
        (0..1000)
            .map(|_| f32::from_bits(r.u64() as u32))
            .filter(|t| t.is_finite()),
    );
    for t in ts {
        let best = Some(Closest {
            t,
            id: 3,
            bary: None,
        });
        let n = Nearest { tmax: t, best };
        assert_eq!(n.test_tmax().to_bits(), t.next_up().to_bits(), "{t:e}");
    }
    let n = Nearest {
        tmax: 5.0,
        best: None,
    };
    assert_eq!(n.test_tmax(), 5.0);
}

/// `order` of three or more children in a walk with non-negative
/// distances (the keyed, sorted push), on both copies where the CPU has
/// AVX2: the children hit are pushed far to near by distance down to 8
/// ulps (nearer than that, the higher slot first), each with its distance
/// at most 7 ulps short, the nearest returned and not pushed; the AVX2
/// network's stack is the portable sort's, entry for entry.
#[test]
fn the_sorted_push_orders_children_far_to_near() {
    let mut node = Node::EMPTY;
    for (s, c) in node.child.iter_mut().enumerate() {
        *c = 100 + s as u32;
    }
    let tree = Tree {
        nodes: &[],
        tris: &[],
        fallback: &TrianglesOnly,
        deep: false,
    };
    let mut r = crate::accel::testutil::Rng::new(3);
    for round in 0..20_000 {
        let mask = loop {
            let m = r.u64() as u32 & 0xff;
            if m.count_ones() >= 3 {
                break m;
            }
        };
        // Distances from 0 up, with ties and near-ties now and then.
        let base = r.f() * 10.0;
        let d: [f32; W] = std::array::from_fn(|_| match round % 3 {
            0 => r.f() * 10.0,
            1 => f32::from_bits(base.to_bits() + (r.f() * 12.0) as u32),
            _ => (r.f() * 3.0).floor(),
        });
        let dist = Lanes([Vec4::from_slice(&d[..4]), Vec4::from_slice(&d[4..])]);
        let run = |avx: bool| {
            let mut stack = [const { Slot::new((0u32, 0f32)) }; SHALLOW];
            let mut sp = 5;
            #[cfg(target_arch = "x86_64")]
            let near = if avx {
                // SAFETY: only called where AVX2 and FMA were detected.
                let bt = unsafe { Avx::new() };
                order::<_, _, true>(bt, &tree, &node, mask, dist, &mut stack, &mut sp)
            } else {
                order::<_, _, true>(Portable, &tree, &node, mask, dist, &mut stack, &mut sp)
            };
            #[cfg(not(target_arch = "x86_64"))]
            let near = order::<_, _, true>(Portable, &tree, &node, mask, dist, &mut stack, &mut sp);
            // SAFETY: every slot was written at its creation.
            let pushed = stack[5..sp].iter().map(|s| unsafe { s.assume_init() });
            (near, pushed.collect::<Vec<_>>())
        };
        let (near, pushed) = run(false);
        let k = mask.count_ones() as usize;
        assert_eq!(pushed.len(), k - 1);
        let key = |c: u32| {
            let s = (c - 100) as usize;
            assert!(mask >> s & 1 != 0, "slot {s} was not hit");
            (d[s].to_bits() & !7, std::cmp::Reverse(s))
        };
        let mut seen: Vec<u32> = pushed.iter().map(|e| e.0).collect();
        seen.push(near);
        for w in seen.windows(2) {
            assert!(key(w[0]) > key(w[1]), "{mask:08b} {d:?}: {seen:?}");
        }
        seen.sort_unstable();
        seen.dedup();
        assert_eq!(seen.len(), k);
        for &(c, e) in &pushed {
            let t = d[(c - 100) as usize];
            assert!(e <= t && t.to_bits() - e.to_bits() <= 7, "{e} for {t}");
        }
        #[cfg(target_arch = "x86_64")]
        if crate::testdata::avx2_fma("the_sorted_push_orders_children_far_to_near") {
            assert_eq!(run(true), (near, pushed));
        }
    }
}

/// One node with two leaves side by side along x, its first division
/// `split` (`Node::split`): slot 0's box x in [0, 1] with a triangle in
/// the plane x = 0.5 above y = 0, slot 1's box x in [2, 3] with one in
/// x = 2.5 below it, both boxes across y and z in [-5, 5].
/// Calls `walk` with the tree of that node.
pub(in crate::accel::bvh8) fn on_two_leaves<R>(
    split: u8,
    walk: impl FnOnce(&Tree<TrianglesOnly>) -> R,
) -> R {
    // A triangle in the plane x = `x`, covering y from `y0` to `y1` (of
    // the same sign) and z in [-4, 4].
    let block = |x: f32, y0: f32, y1: f32, id: u32| {
        let mut b = Tri4::EMPTY;
        let v = [[x, y0, -4.0], [x, y1, -4.0], [x, 0.5 * (y0 + y1), 4.0]];
        for (k, vk) in v.iter().enumerate() {
            for (a, &c) in vk.iter().enumerate() {
                b.v[k][a].x = c;
            }
        }
        b.ids[0] = id;
        b
    };
    let mut n = Node {
        split,
        ..Node::EMPTY
    };
    n.set(
        0,
        leaf(0, 1),
        Vec3::new(0.0, -5.0, -5.0),
        Vec3::new(1.0, 5.0, 5.0),
    );
    n.set(
        1,
        leaf(1, 1),
        Vec3::new(2.0, -5.0, -5.0),
        Vec3::new(3.0, 5.0, 5.0),
    );
    let tris = [block(0.5, 0.5, 4.0, 0), block(2.5, -4.0, -0.5, 1)];
    walk(&Tree {
        nodes: &[n],
        tris: &tris,
        fallback: &TrianglesOnly,
        deep: false,
    })
}

/// The any-hit walk enters the far side of a node's first division
/// first (`Node::split`), on the node of [`on_two_leaves`] with two rays
/// through both boxes: one running towards +x below y = 0 (blocked by
/// slot 1's triangle only) and one towards −x above it (blocked by slot
/// 0's only). Far side first, each ray tests one leaf; near side first, it
/// would test both. A node divided on an axis a ray does not run towards
/// −(its octant bit clear), or whose division is unknown (`split` 0),
/// has its upper slot entered first.
#[test]
fn any_enters_the_far_side_of_the_first_division_first() {
    let up = Ray::new(Vec3::new(-1.0, -2.0, 0.0), Vec3::X);
    let down = Ray::new(Vec3::new(4.0, 2.0, 0.0), Vec3::new(-1.0, 0.0, 0.0));
    // (triangles tested, blocked) of `any` on the node.
    let walk = |split: u8, ray: &Ray| {
        on_two_leaves(split, |tree| {
            let mut c = crate::stats::Counters::default();
            let range = (0.0, f32::INFINITY);
            let rd = &RayData::new(ray);
            let hit = any::<_, _, _, SHALLOW, ANY_OCTANT, true>(
                Portable, tree, rd, range, NO_ITEM, &mut c,
            );
            (c.intersection_tests, hit)
        })
    };
    assert_eq!(walk(1, &up), (1, true));
    assert_eq!(walk(1, &down), (1, true));
    assert_eq!(walk(2, &up), (1, true));
    assert_eq!(walk(2, &down), (2, true));
    assert_eq!(walk(0, &down), (2, true));
}
