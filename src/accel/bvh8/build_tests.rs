//! The build's unit tests.

use super::*;
use crate::accel::testutil::Rng;

fn refs(n: usize, seed: u64) -> Vec<PrimRef> {
    let mut r = Rng::new(seed);
    (0..n)
        .map(|i| {
            let (c, h) = (r.v(-10.0, 10.0), r.v(0.0, 0.5));
            PrimRef::new(&Aabb::new(c - h, c + h), i as u32, false)
        })
        .collect()
}

/// A builder with wide nodes for small ranges (as for small scenes).
fn builder() -> Builder {
    Builder {
        pad: Vec3::ZERO,
        wide: true,
        large: false,
        huge: false,
        deepest: AtomicUsize::new(0),
    }
}

/// A range over all of `items`.
fn range(items: &[PrimRef]) -> Range {
    let (bounds, cbounds) = bounds_of(items);
    Range {
        begin: 0,
        end: items.len(),
        bounds,
        cbounds,
    }
}

/// Boxes of half-size `h` around `centres`.
fn boxes(centres: impl IntoIterator<Item = Vec3>, h: Vec3) -> Vec<PrimRef> {
    centres
        .into_iter()
        .enumerate()
        .map(|(i, c)| PrimRef::new(&Aabb::new(c - h, c + h), i as u32, false))
        .collect()
}

/// A reference keeps its box, id and kind whatever the id (up to the
/// largest allowed, `2^31 − 1`), and its fourth lanes are plain floats
/// (zero or normal: a denormal there would slow every operation that
/// carries them along).
#[test]
fn references_keep_ids_and_kinds_in_plain_floats() {
    let b = Aabb::new(Vec3::new(-1.0, 2.0, -3.0), Vec3::new(4.0, 5.0, 6.0));
    for id in [
        0,
        1,
        0xffff,
        0x1_0000,
        0x7fff_ffff,
        0x1234_5678,
        0x7fff_0000,
    ] {
        for other in [false, true] {
            let r = PrimRef::new(&b, id, other);
            assert_eq!((r.id(), r.other(), r.is_skipped()), (id, other, false));
            assert_eq!((r.lo.truncate(), r.hi.truncate()), (b.min, b.max));
            for w in [r.lo.w, r.hi.w] {
                assert!(w == 0.0 || w.is_normal(), "{id:#x}: {w}");
            }
        }
    }
    assert!(PrimRef::skipped().is_skipped());
}

/// The plan's bin plane is the cheapest of all planes on all axes:
/// each plane's cost, recomputed here from the items themselves (the
/// boxes of each side and their blocks of four), is no lower, and no
/// plane leaves a side empty. Ranges below `SMALL_RANGE` use its bins,
/// larger ones `BINS`; one axis is flat in a quarter of the trials.
#[test]
fn the_plan_takes_the_cheapest_bin_plane() {
    let b = builder();
    let mut r = Rng::new(41);
    let mut splits = 0;
    for trial in 0..240 {
        let n = 9 + trial % 100;
        let mut spread = r.v(0.5, 10.0);
        if trial % 4 == 0 {
            spread[trial % 3] = 0.0;
        }
        let centres: Vec<Vec3> = (0..n).map(|_| r.v(0.0, 1.0) * spread).collect();
        let items = boxes(centres, Vec3::splat(0.2));
        let rg = range(&items);
        let Some(Plan::Bin {
            axis, pos, bins, ..
        }) = b.plan(&items, &rg, 0)
        else {
            continue;
        };
        let (axis, pos, bins) = (axis as usize, pos as usize, bins as usize);
        assert_eq!(bins, if n < SMALL_RANGE { SMALL_BINS } else { BINS });
        let map = BinMap::new(&rg.cbounds);
        let bin = |p: &PrimRef, a: usize| {
            let k = (p.centroid()[a] - map.min[a]) * map.scale[a] * bins as f32;
            k.max(0.0).min((bins - 1) as f32) as usize
        };
        let cost = |a: usize, k: usize| -> Option<f32> {
            let (l, rt): (Vec<PrimRef>, Vec<PrimRef>) = items.iter().partition(|p| bin(p, a) < k);
            let side = |s: &[PrimRef]| bounds_of(s).0.surface_area() * blocks(s.len());
            (!l.is_empty() && !rt.is_empty()).then(|| side(&l) + side(&rt))
        };
        let chosen = cost(axis, pos).expect("the plane leaves no side empty");
        let best = (0..3)
            .filter(|&a| rg.cbounds.extent()[a] > 0.0)
            .flat_map(|a| (1..bins).filter_map(move |k| cost(a, k)))
            .fold(f32::INFINITY, f32::min);
        assert!(chosen <= best * 1.0001, "trial {trial}: {chosen} > {best}");
        splits += 1;
    }
    assert!(splits > 200, "{splits}");
}

/// When a range stays a leaf, and when the median takes over: four or
/// fewer items, and coincident centroids up to a leaf's capacity, make a
/// leaf (more are halved); a pile of overlapping boxes that no plane
/// separates profitably stays a leaf, two clusters are split; and a
/// range too deep for the SAH to finish under `MAX_DEPTH` is cut by
/// the median along its centroids' longest axis (100 items: 7 bits,
/// 7/2 + 2 = 5 levels left).
#[test]
fn the_plan_stops_at_leaves_and_falls_back_to_the_median() {
    let b = builder();
    let plan = |items: &[PrimRef], depth| b.plan(items, &range(items), depth);
    let pile = |n: usize| boxes(vec![Vec3::ONE; n], Vec3::splat(0.5));
    assert!(plan(
        &boxes([Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z], Vec3::splat(0.1)),
        0
    )
    .is_none());
    for n in [5, LEAF_ITEMS] {
        assert!(plan(&pile(n), 0).is_none(), "{n}");
    }
    for n in [LEAF_ITEMS + 1, 100] {
        assert!(
            matches!(plan(&pile(n), 0), Some(Plan::Median { .. })),
            "{n}"
        );
    }
    let overlapping = boxes(
        (0..8).map(|i| Vec3::X * (0.025 * i as f32)),
        Vec3::splat(0.5),
    );
    assert!(plan(&overlapping, 0).is_none());
    let clusters = boxes(
        (0..8).map(|i| Vec3::X * (100.0 * (i / 4) as f32)),
        Vec3::splat(0.5),
    );
    assert!(matches!(
        plan(&clusters, 0),
        Some(Plan::Bin {
            axis: 0,
            pos: 1..=7,
            ..
        })
    ));
    let mut r = Rng::new(42);
    for axis in 0..3 {
        let mut spread = Vec3::ONE;
        spread[axis] = 10.0;
        let items = boxes((0..100).map(|_| r.v(0.0, 1.0) * spread), Vec3::splat(0.1));
        let deep = MAX_DEPTH - 5;
        assert!(
            matches!(plan(&items, deep), Some(Plan::Median { axis: a }) if a as usize == axis),
            "axis {axis}"
        );
        assert!(matches!(plan(&items, deep - 1), Some(Plan::Bin { .. })));
    }
}

/// `divide` puts on the left exactly the items whose bin (as the sweep
/// binned them) is below the plan's plane, keeps every item, and
/// returns each side's bounds; the median halves a range.
#[test]
fn divide_follows_the_bins_and_the_median_halves() {
    let b = builder();
    let mut r = Rng::new(43);
    let mut cuts = 0;
    for trial in 0..60 {
        let n = 9 + 2 * trial;
        let mut items = boxes((0..n).map(|_| r.v(0.0, 4.0)), Vec3::splat(0.1));
        let rg = range(&items);
        let Some(
            plan @ Plan::Bin {
                axis, pos, bins, ..
            },
        ) = b.plan(&items, &rg, 0)
        else {
            continue;
        };
        let (axis, pos, bins) = (axis as usize, pos as usize, bins as usize);
        let map = BinMap::new(&rg.cbounds);
        let bin = |p: &PrimRef| {
            let c = p.centroid();
            if bins == SMALL_BINS {
                map.bins::<SMALL_BINS>(c)[axis]
            } else {
                map.bins::<BINS>(c)[axis]
            }
        };
        let mut before: Vec<u32> = items.iter().map(|p| p.id()).collect();
        let (left, right) = b.divide(&mut items, &rg, plan);
        assert_eq!((left.begin, left.end, right.end), (0, right.begin, n));
        assert!(items[..left.end].iter().all(|p| bin(p) < pos));
        assert!(items[right.begin..].iter().all(|p| bin(p) >= pos));
        assert_eq!(bounds_of(&items[..left.end]), (left.bounds, left.cbounds));
        assert_eq!(
            bounds_of(&items[right.begin..]),
            (right.bounds, right.cbounds)
        );
        let mut after: Vec<u32> = items.iter().map(|p| p.id()).collect();
        before.sort_unstable();
        after.sort_unstable();
        assert_eq!(before, after);
        cuts += 1;
    }
    assert!(cuts > 50, "{cuts}");
    // A centroid exactly on plane 4 of 8 (k = 4.0) is in bin 4: right.
    let scale = BinMap::new(&Aabb::new(Vec3::ZERO, Vec3::X * 4.0)).scale.x * 8.0;
    let mut c = f32::from_bits((4.0 / scale).to_bits() - 8);
    while c * scale != 4.0 {
        assert!(c * scale < 4.0, "no float lands on the plane");
        c = f32::from_bits(c.to_bits() + 1);
    }
    let xs = [0.0, 0.0, c, 4.0, 4.0];
    let mut items = boxes(xs.map(|x| Vec3::X * x), Vec3::ZERO);
    let rg = range(&items);
    let plan = Plan::Bin {
        axis: 0,
        pos: 4,
        bins: 8,
        wide: false,
    };
    let (left, _) = b.divide(&mut items, &rg, plan);
    assert_eq!(left.end, 2);
    for n in [9, 100] {
        let mut pile = boxes(vec![Vec3::ONE; n], Vec3::splat(0.5));
        let rg = range(&pile);
        let (left, right) = b.divide(&mut pile, &rg, Plan::Median { axis: 0 });
        assert_eq!((left.end, right.begin, right.end), (n / 2, n / 2, n));
    }
}

/// Every node is planned for its own level. A geometric chain (which
/// SAH peels a few items at a time) started at each level a range of
/// its size can reach (from level 15 on, 300 items are already
/// median-split above) ends within `MAX_DEPTH`, at the depths measured
/// when this test was written (and again when the split cost and the
/// leaf size changed: the chain started at the root now ends at 4, not
/// 8). Planning a node's children at its
/// own level instead moves the switch a level down (the chain then ends
/// at 17 or 18: within `MAX_DEPTH` here, but not in general). Like
/// `build_quality_stays_where_it_was_measured`, a deliberate change to
/// the builder updates the table.
#[test]
fn a_chain_started_at_any_level_ends_where_it_was_measured() {
    let b = builder();
    // The chain runs on in a node's first child, and mirrored in its
    // second.
    let measured = [
        (1.0, [4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 18, 19]),
        (
            -1.0,
            [16, 16, 16, 16, 17, 17, 17, 16, 16, 18, 18, 18, 18, 18, 19],
        ),
    ];
    for (dir, measured) in measured {
        let chain = boxes((0..300).map(|k| Vec3::X * dir * 1.2f32.powi(k)), Vec3::ZERO);
        let mut ends = Vec::new();
        for start in 0..=14 {
            let mut items = chain.clone();
            let rg = range(&items);
            let plan = b.plan(&items, &rg, start);
            let mut out = Vec::new();
            b.subtree(&mut items, rg, plan, start, &mut out);
            ends.push(start + depth(&out));
        }
        assert!(ends.iter().all(|&e| e <= MAX_DEPTH), "{ends:?}");
        assert_eq!(ends, measured, "direction {dir}");
    }
}

/// The parallel path (children of 4k items or more built on other
/// threads) plans for the same levels as the serial one: started at
/// level 12, where the median takes over within a few levels, it
/// builds the one-thread build's nodes, in the same order.
#[test]
fn the_parallel_path_plans_for_the_same_levels() {
    let b = builder();
    let mut r = Rng::new(44);
    let centres: Vec<Vec3> = (0..PARALLEL_ITEMS + 4000)
        .map(|_| r.v(0.0, 100.0))
        .collect();
    let items = boxes(centres, Vec3::splat(0.3));
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        pool.install(|| {
            let mut items = items.clone();
            let rg = range(&items);
            let plan = b.plan(&items, &rg, 12);
            let mut out = Vec::new();
            b.subtree(&mut items, rg, plan, 12, &mut out);
            let ids: Vec<u32> = items.iter().map(|p| p.id()).collect();
            (format!("{out:?}"), ids)
        })
    };
    assert!(run(1) == run(4), "the parallel path built another tree");
}

/// The partition puts the items the predicate holds for first, keeps
/// every item, and returns their count and both sides' bounds, also
/// when one side is empty, both for unordered items (from 128 on, the
/// switch to `block_partition`) and for items sorted along the cut's
/// axis (long runs: the in-place loop throughout), at sizes around the
/// block and the switch's limit.
#[test]
fn partition_separates_and_bounds_both_sides() {
    let mut r = Rng::new(45);
    let sizes = [1, 2, 3, 10, 101, 128, 129, 200, 1000, BLOCK_PARTITION_MAX];
    for n in sizes.into_iter().chain([BLOCK_PARTITION_MAX + 1]) {
        let mut items = boxes((0..n).map(|_| r.v(0.0, 1.0)), Vec3::splat(0.01));
        for sorted in [false, true] {
            if sorted {
                items.sort_by(|a, b| a.centroid().x.total_cmp(&b.centroid().x));
            }
            for cut in [-1.0, 0.1, 0.3, 0.5, 0.9, 2.0] {
                let mut v = items.clone();
                let (k, lb, rb) = partition(&mut v, |c| c.x < cut, false);
                assert_eq!(k, items.iter().filter(|p| p.centroid().x < cut).count());
                assert!(v[..k].iter().all(|p| p.centroid().x < cut));
                assert!(v[k..].iter().all(|p| p.centroid().x >= cut));
                assert_eq!((lb, rb), (bounds_of(&v[..k]), bounds_of(&v[k..])));
                let mut ids: Vec<u32> = v.iter().map(|p| p.id()).collect();
                ids.sort_unstable();
                assert!(ids.iter().copied().eq(0..n as u32), "n {n}: items lost");
            }
        }
    }
}

/// The block partition alone: every size from 0 to a few blocks and
/// beyond, any share of items on the left, returns the count on the
/// left with those items first and keeps every item.
#[test]
fn block_partition_separates_at_any_size_and_share() {
    let mut r = Rng::new(46);
    for n in (0..=3 * BLOCK + 2).chain([5 * BLOCK, 777]) {
        let items = boxes((0..n).map(|_| r.v(0.0, 1.0)), Vec3::ZERO);
        for cut in [0.0, 0.05, 0.5, 0.95, 1.0] {
            let mut v = items.clone();
            let k = block_partition(&mut v, &|c: Vec3A| c.x < cut);
            assert_eq!(k, items.iter().filter(|p| p.centroid().x < cut).count());
            assert!(v[..k].iter().all(|p| p.centroid().x < cut));
            assert!(v[k..].iter().all(|p| p.centroid().x >= cut));
            let mut ids: Vec<u32> = v.iter().map(|p| p.id()).collect();
            ids.sort_unstable();
            assert!(ids.iter().copied().eq(0..n as u32), "n {n} cut {cut}");
        }
    }
}

/// Splitting the work over threads changes nothing: the bounds and the
/// bins of a range too large for one thread (chunks binned in parallel,
/// then merged) are those of one pass over it, and two ranges' bins
/// merged are their union's.
#[test]
fn parallel_bounds_and_bins_equal_one_pass() {
    let n = PARALLEL_BINNING + 1000;
    let items = refs(n, 7);
    let (mut b, mut cb) = (Aabb::EMPTY, Aabb::EMPTY);
    for p in &items {
        b = b.union(&Aabb::new(p.lo.truncate(), p.hi.truncate()));
        cb = cb.grow(p.centroid().into());
    }
    assert_eq!(bounds_of(&items), (b, cb));
    let map = BinMap::new(&cb);
    let par = large_bins(&items, &cb);
    let mut one = Bins::<BINS>::new();
    one.add(&items, &map);
    assert_eq!(par.count, one.count);
    assert_eq!((par.lo, par.hi), (one.lo, one.hi));
    for a in 0..3 {
        assert_eq!(one.count[a].iter().sum::<u32>() as usize, n);
        // Every bin is used: the centroids are spread over the range.
        assert!(one.count[a].iter().all(|&c| c > 0));
    }
    let (left, right) = items.split_at(n / 3);
    let (mut l, mut r) = (Bins::<SMALL_BINS>::new(), Bins::<SMALL_BINS>::new());
    l.add(left, &map);
    r.add(right, &map);
    let merged = l.merge(r);
    let mut whole = Bins::<SMALL_BINS>::new();
    whole.add(&items, &map);
    assert_eq!(merged.count, whole.count);
    assert_eq!((merged.lo, merged.hi), (whole.lo, whole.hi));
}

/// The parallel partition gives the in-place loop's result item for item
/// (not only the same sides: the same order within each, so the tree
/// built on top is the same), with the same bounds, for unordered and
/// sorted items, any share on the left (none and all included), and
/// sizes around its chunks.
#[test]
fn the_parallel_partition_permutes_as_the_serial_one() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .expect("a thread pool");
    let mut r = Rng::new(47);
    for n in [PARALLEL_PARTITION, 3 * 8192 + 17, 100_003] {
        let mut items = boxes((0..n).map(|_| r.v(0.0, 1.0)), Vec3::splat(0.01));
        for sorted in [false, true] {
            if sorted {
                items.sort_by(|a, b| a.centroid().x.total_cmp(&b.centroid().x));
            }
            for cut in [-1.0, 0.01, 0.3, 0.5, 0.97, 2.0] {
                let left = |c: Vec3A| c.x < cut;
                let mut serial = items.clone();
                let s = fused_partition(&mut serial, left);
                let mut par = items.clone();
                let p = pool.install(|| parallel_partition(&mut par, left));
                assert_eq!(s, p, "n {n} cut {cut}");
                let ids = |v: &[PrimRef]| v.iter().map(|p| p.id()).collect::<Vec<u32>>();
                assert!(ids(&serial) == ids(&par), "n {n} cut {cut} sorted {sorted}");
            }
        }
    }
}

/// The parallel partition's bit walks find what a scan finds: the `t`-th
/// one and zero, the ones and zeros from any position up and down, the
/// ones below any position, on words full, empty and mixed, with a last
/// word part full.
#[test]
fn the_sides_find_what_a_scan_finds() {
    let mut r = Rng::new(49);
    let n: usize = 64 * 7 + 13;
    let mut bits = vec![0u64; n.div_ceil(64)];
    bits[0] = u64::MAX;
    bits[2] = 0x8000_0000_0000_0001;
    for (w, word) in bits.iter_mut().enumerate().skip(3) {
        for b in 0..64 {
            if 64 * w + b < n && r.f() < 0.3 {
                *word |= 1 << b;
            }
        }
    }
    let bit = |i: usize| bits[i / 64] >> (i % 64) & 1 != 0;
    let sides = Sides::new(&bits, n);
    for one in [true, false] {
        let at: Vec<usize> = (0..n).filter(|&i| bit(i) == one).collect();
        for (t, &i) in at.iter().enumerate() {
            assert_eq!(sides.nth(t, one), i, "{t}-th, one {one}");
            let up: Vec<usize> = sides.from(i, one).take(at.len() - t).collect();
            assert_eq!(up, at[t..], "from {i}, one {one}");
            let down: Vec<usize> = sides.down_from(i + 1, one).take(t + 1).collect();
            assert!(down.iter().eq(at[..=t].iter().rev()), "down from {i}");
        }
    }
    for i in 0..=n {
        assert_eq!(sides.ones_below(i), (0..i).filter(|&j| bit(j)).count());
    }
}

/// Dividing ranges ahead of their turn on several threads (the top
/// levels: `expand`, the parallel partition, the halves planned on two
/// threads) builds the one-thread build's nodes in the same order, and
/// leaves the items in the same order: on a large range mixing a uniform
/// spread, dense clusters and piles of coincident boxes (which only the
/// median divides), unordered and sorted along an axis, at levels where
/// every plan is the bins' and where the median takes over sooner.
#[test]
fn dividing_ahead_builds_the_serial_tree() {
    let b = builder();
    let mut r = Rng::new(48);
    let mut centres: Vec<Vec3> = (0..150_000).map(|_| r.v(0.0, 100.0)).collect();
    for _ in 0..40 {
        let c = r.v(0.0, 100.0);
        centres.extend((0..2000).map(|_| c + r.v(0.0, 0.01)));
    }
    let pile = r.v(0.0, 100.0);
    centres.extend((0..6000).map(|_| pile));
    let items = boxes(centres, Vec3::splat(0.05));
    let mut sorted = items.clone();
    sorted.sort_by(|a, b| a.centroid().y.total_cmp(&b.centroid().y));
    for (items, start) in [(&items, 0), (&sorted, 0), (&items, 5)] {
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a thread pool");
            pool.install(|| {
                let mut items = items.clone();
                let rg = range(&items);
                let plan = b.plan(&items, &rg, start);
                let mut out = Vec::new();
                b.subtree(&mut items, rg, plan, start, &mut out);
                let ids: Vec<u32> = items.iter().map(|p| p.id()).collect();
                (format!("{out:?}"), ids)
            })
        };
        let one = run(1);
        assert!(
            one == run(2),
            "2 threads built another tree (from level {start})"
        );
        assert!(
            one == run(3),
            "3 threads built another tree (from level {start})"
        );
    }
}

/// A closed room: a cube of 12 triangles with two spheres inside. Every
/// plane leaves one side with the whole room's box, so the binary SAH
/// alone keeps one leaf of all 14 items, which every ray tests whole. A
/// wide node is cheaper by the SAH: the root gets several children (the
/// walls apart), rays from inside (as a camera's, bounces' and shadow
/// rays are) test less than half the items, and hits are brute force's.
/// A build of more than `WIDE_ITEMS` items keeps the binary SAH's leaf.
#[test]
fn a_closed_room_becomes_a_wide_node() {
    use crate::accel::bvh8::Bvh8;
    use crate::accel::testutil::{assert_agrees, prim, sphere};
    use crate::accel::{Aggregate, Query};
    use crate::math::Ray;
    use crate::shape::{Shape, Triangle};
    use crate::stats::Counters;
    // The cube [-1, 1]³, two triangles a face.
    let mut prims = Vec::new();
    for axis in 0..3 {
        for side in [-1.0f32, 1.0] {
            let corner = |u: f32, v: f32| {
                let mut p = Vec3::ZERO;
                p[axis] = side;
                p[(axis + 1) % 3] = u;
                p[(axis + 2) % 3] = v;
                p
            };
            let (a, b, c, d) = (
                corner(-1.0, -1.0),
                corner(1.0, -1.0),
                corner(1.0, 1.0),
                corner(-1.0, 1.0),
            );
            prims.push(prim(Shape::Triangle(Triangle::new(a, b, c))));
            prims.push(prim(Shape::Triangle(Triangle::new(a, c, d))));
        }
    }
    prims.push(sphere(Vec3::new(-0.5, -0.7, 0.2), 0.3));
    prims.push(sphere(Vec3::new(0.4, -0.6, -0.3), 0.4));
    let ids: Vec<u32> = (0..prims.len() as u32).collect();
    let b = Bvh8::new(&prims, ids.clone());
    let kids = |b: &Bvh8| b.nodes[0].child.iter().filter(|&&c| c != EMPTY).count();
    assert!(kids(&b) >= 4, "{} children", kids(&b));
    let mut r = Rng::new(49);
    let mut c = Counters::default();
    let rays = 2000;
    for _ in 0..rays {
        let o = r.v(-0.95, 0.95);
        let d = (r.v(-1.0, 1.0) + Vec3::splat(1e-3)).normalize();
        let ray = Ray::new(o, d);
        let hit = b.intersect(Query::new(&prims, &ray, 0.0, f32::INFINITY), &mut c);
        assert!(hit.is_some(), "a ray from inside leaves the room");
    }
    let tests = c.intersection_tests as f64 / rays as f64;
    assert!(tests < prims.len() as f64 / 2.0, "{tests} tests a ray");
    assert_agrees(&b, &prims, 2000);
    // A large build: the same room among many far-away specks, whose
    // room range stays one leaf.
    let mut many = prims.clone();
    for k in 0..WIDE_ITEMS {
        many.push(sphere(Vec3::new(100.0 + k as f32, 0.0, 0.0), 0.01));
    }
    let big = Bvh8::new(&many, (0..many.len() as u32).collect());
    let mut leaf_items = 0;
    for n in &big.nodes {
        for &ch in &n.child {
            if ch != EMPTY && is_leaf(ch) {
                let (start, count) = leaf_range(ch);
                let holds_wall = big.tris[start..start + count]
                    .iter()
                    .any(|t| t.ids.contains(&0));
                if holds_wall {
                    leaf_items = big.tris[start..start + count]
                        .iter()
                        .flat_map(|t| t.ids)
                        .filter(|&id| id != super::super::node::NO_ITEM)
                        .count();
                }
            }
        }
    }
    assert_eq!(leaf_items, prims.len(), "the room is one leaf");
}

/// `divide_small` (the wide node's search, on a copy) makes the sides
/// `divide` makes, with the same bounds, on small ranges of every size
/// and any bin plane.
#[test]
fn divide_small_makes_the_sides_of_divide() {
    let b = builder();
    let mut r = Rng::new(50);
    let mut cuts = 0;
    for trial in 0..300 {
        let n = 2 + trial % (MAX_LEAF_ITEMS - 1);
        let items = boxes((0..n).map(|_| r.v(0.0, 3.0)), Vec3::splat(0.2));
        let rg = range(&items);
        for axis in 0..3u8 {
            for pos in 1..SMALL_BINS as u8 {
                let plan = Plan::Bin {
                    axis,
                    pos,
                    bins: SMALL_BINS as u8,
                    wide: false,
                };
                let map = BinMap::new(&rg.cbounds);
                let left = items
                    .iter()
                    .filter(|p| map.bins::<SMALL_BINS>(p.centroid())[axis as usize] < pos as usize)
                    .count();
                if left == 0 || left == n {
                    continue;
                }
                let (mut x, mut y) = (items.clone(), items.clone());
                let (xa, xb) = b.divide(&mut x, &rg, plan);
                let (ya, yb) = Builder::divide_small(&mut y, &rg, plan);
                let key = |r: &Range| (r.begin, r.end, r.bounds, r.cbounds);
                assert_eq!((key(&xa), key(&xb)), (key(&ya), key(&yb)));
                let ids = |v: &[PrimRef]| {
                    let mut ids: Vec<u32> = v.iter().map(|p| p.id()).collect();
                    ids.sort_unstable();
                    ids
                };
                assert_eq!(ids(&x[..xa.end]), ids(&y[..ya.end]));
                cuts += 1;
            }
        }
    }
    assert!(cuts > 1000, "{cuts}");
}

/// The split cost and the leaves' size follow the build's size: scenes'
/// builds of up to `WIDE_ITEMS` items, meshes' of more than `LARGE_ITEMS`
/// and of more than `HUGE_ITEMS`, the rest.
#[test]
fn the_split_cost_follows_the_build_size() {
    let cost = |n| Builder::new(n, 0.0).split_cost();
    assert_eq!(cost(1), SMALL_SPLIT_COST);
    assert_eq!(cost(WIDE_ITEMS), SMALL_SPLIT_COST);
    assert_eq!(cost(WIDE_ITEMS + 1), SPLIT_COST);
    assert_eq!(cost(LARGE_ITEMS), SPLIT_COST);
    assert_eq!(cost(LARGE_ITEMS + 1), LARGE_SPLIT_COST);
    assert_eq!(cost(HUGE_ITEMS), LARGE_SPLIT_COST);
    assert_eq!(cost(HUGE_ITEMS + 1), HUGE_SPLIT_COST);
    let leaf = |n| Builder::new(n, 0.0).leaf_items();
    assert_eq!(
        (
            leaf(LARGE_ITEMS),
            leaf(LARGE_ITEMS + 1),
            leaf(HUGE_ITEMS + 1)
        ),
        (LEAF_ITEMS, MAX_LEAF_ITEMS, MAX_LEAF_ITEMS)
    );
}
