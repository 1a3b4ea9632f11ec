//! Building the 8-wide BVH: binned SAH splits, each node taking up to eight
//! children by splitting its largest child again, then the leaves'
//! triangles copied into four-wide blocks. In small scenes a range of a
//! leaf's size also weighs an 8-wide node (one node test, then its
//! children's leaves) against the leaf, which the binary SAH cannot see
//! for enclosing geometry such as a room's walls. With several threads, a large
//! node's binary levels are divided ahead on all of them (`expand`), large
//! ranges are binned and partitioned in parallel, and large nodes' children
//! are built in parallel: the tree is the one-thread build's, node for node
//! and item for item.

use super::lanes::W;
use super::node::{is_leaf, leaf, leaf_range, Node, Tri4, EMPTY, MAX_LEAF_ITEMS, OTHER};
use super::pages::huge_pages;
use crate::accel::overlap::margin;
use crate::math::{Aabb, Vec3};
use glam::{Vec3A, Vec4};
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};

#[path = "build_partition.rs"]
mod partition;
use partition::*;

/// What one item of the source is.
pub(crate) enum Item {
    /// A triangle (tested four at a time in the leaves).
    Triangle([Vec3; 3]),
    /// Something else with these bounds, tested through the fallback.
    Other(Aabb),
    /// Never hit (a degenerate triangle): left out of the tree.
    Skip,
}

/// The items a BVH is built over. Ids are what the traversal reports (the
/// world's primitive indices, a mesh's triangle indices).
pub(crate) trait Source: Sync {
    /// How many items.
    fn count(&self) -> usize;
    /// The id of the `k`-th item.
    fn id(&self, k: usize) -> u32;
    /// The item with id `id`.
    fn item(&self, id: u32) -> Item;
    /// The vertices of item `id`, which [`Source::item`] called a triangle
    /// (filling the leaves: without `item`'s degeneracy check again).
    fn vertices(&self, id: u32) -> [Vec3; 3];
    /// A hint that `vertices(id)` will be asked for soon (no effect on
    /// results; by default nothing).
    fn prefetch(&self, _id: u32) {}
}

/// Bins per axis of the SAH sweep.
const BINS: usize = 32;
/// Cost of a binary split step relative to testing one block of four items.
/// Since a node's free slots split its larger leaves (see
/// [`Builder::plan_and_split`]), a larger leaf costs a ray fewer blocks than
/// the SAH counts, and fewer node levels pay on meshes larger than the
/// cache (each level a dependent load). Measured against 1.0
/// (`examples/packet_rays`, the anchors' rays, 1 thread, medians of three
/// alternated runs): 1.5 gave incoherent rays 1.03x on bunny40k, 1.10x on
/// sphere1m and 1.12x on sphere4m, camera and shadow rays 0.995-1.03x;
/// 2.0 more on sphere1m's incoherent rays (1.17x) but bunny40k's shadow
/// rays 0.97x. Builds of up to [`WIDE_ITEMS`] items (scenes: a room, rows
/// of spheres) keep [`SMALL_SPLIT_COST`], builds of more than
/// [`LARGE_ITEMS`] take [`LARGE_SPLIT_COST`] and of more than
/// [`HUGE_ITEMS`] [`HUGE_SPLIT_COST`].
const SPLIT_COST: f32 = 1.5;
/// [`SPLIT_COST`] of builds of more than [`LARGE_ITEMS`] items, with
/// leaves of up to [`MAX_LEAF_ITEMS`] (eight blocks) instead of
/// [`LEAF_ITEMS`]. Their trees are far larger than the caches: there a
/// node level is one more load from memory a ray waits for, while a larger
/// leaf's blocks are asked for at once (`Tree::nearest_in_leaf`). 2.0 with
/// four-block leaves, against 1.5 (`examples/packet_rays`, 1 thread
/// pinned, medians of 3-5 alternated runs): incoherent rays 1.05x on
/// sphere4m and 1.03x on sphere1m, camera rays 1.01x on both, shadow rays
/// 0.99x. Then on sphere1m (1.05M items), 2.5 with eight-block leaves
/// against 2.0 with four (`glint bench rays`, 1 thread pinned, four
/// batches of 5-7 alternated runs, medians): incoherent rays 1.042x,
/// 0.999x, 1.015x and 1.035x, camera rays 0.995-0.999x, shadow rays
/// 0.985-0.993x; 3.0 read 1.066x and 1.016x, but camera rays 0.982-0.985x
/// and shadow rays 0.970-0.975x. bunny40k (40k items) keeps 1.5: 2.0 cost
/// its shadow rays 3%.
const LARGE_SPLIT_COST: f32 = 2.5;
/// The builds of more items than this take [`LARGE_SPLIT_COST`]: a
/// quarter million triangles, some 13 MB of nodes and blocks, past what a
/// core's caches hold of a tree a ray walks at random.
const LARGE_ITEMS: usize = 1 << 18;
/// [`SPLIT_COST`] of builds of more than [`HUGE_ITEMS`] items: larger
/// leaves still, where even the tree's lower node levels miss every
/// cache. Measured on sphere4m (4.2M items) against a split cost of 2.0
/// with four-block leaves (`examples/packet_rays`, 1 thread pinned, 3-5
/// alternated runs): incoherent rays 1.08x (3.0: 1.05x, 5.0: 1.08x),
/// camera rays 0.99x, shadow rays 0.975x. On sphere1m (1.05M items, which
/// stays at [`LARGE_SPLIT_COST`]) the same cost gave incoherent rays
/// 1.055x but camera rays 0.97x and shadow rays 0.91x.
const HUGE_SPLIT_COST: f32 = 4.0;
/// The builds of more items than this take [`HUGE_SPLIT_COST`]: two
/// million triangles, a tree of some 100 MB.
const HUGE_ITEMS: usize = 1 << 21;
/// Most items a leaf holds in builds of up to [`LARGE_ITEMS`] items (four
/// blocks), and where a range's centroids coincide.
const LEAF_ITEMS: usize = 16;
/// [`SPLIT_COST`] of builds of up to [`WIDE_ITEMS`] items. Their items are
/// often not triangles (spheres, planes), each tested alone however the
/// SAH groups them in blocks of four, and their trees fit in the cache:
/// 1.5 made the depth-of-field scene of `scenes/` (a few spheres on a
/// plane) render in 1.19x the time of 1.0.
const SMALL_SPLIT_COST: f32 = 1.0;
/// Below this many items a node's subtrees are built on one thread. 4k
/// rather than 16k: bunny40k's 2-thread build 5.7-6.1 ms instead of
/// 6.4-6.8 (the top node's eight children, about 5k items each but
/// uneven, now split their work too), sphere1m's the same within noise.
const PARALLEL_ITEMS: usize = 4 * 1024;
/// Binning is split over threads above this many items.
const PARALLEL_BINNING: usize = 64 * 1024;
/// The two halves of a range of at least this many items are planned on
/// two threads.
const PARALLEL_PLANS: usize = 8 * 1024;
/// Deepest node level: the traversal stack holds at most `(W − 1) · depth`
/// pending children.
pub(crate) const MAX_DEPTH: usize = 20;

/// One item during the build: its box, with its id and kind in the fourth
/// lanes (32 bytes). Each corner is one aligned 16-byte load that is
/// already a `Vec3A` (three 4-byte fields and an id took four instructions
/// per corner to load, and the partition's swap then stalled reloading
/// them). The fourth lanes hold small integers as floats (never denormal,
/// which would slow the arithmetic that carries them along unused).
#[derive(Clone, Copy, Debug)]
struct PrimRef {
    /// Lower corner; `w`: the id's low 16 bits.
    lo: Vec4,
    /// Upper corner; `w`: the id's high 15 bits, plus `2^15` for an item
    /// that is not a triangle, or `−1` for one left out.
    hi: Vec4,
}

impl PrimRef {
    /// The flag in `hi.w` of an item that is not a triangle.
    const OTHER_W: u32 = 1 << 15;

    /// Item `id` (below 2^31) with box `b`.
    fn new(b: &Aabb, id: u32, other: bool) -> Self {
        debug_assert!(id & OTHER == 0);
        let high = (id >> 16) | if other { Self::OTHER_W } else { 0 };
        PrimRef {
            lo: b.min.extend((id & 0xffff) as f32),
            hi: b.max.extend(high as f32),
        }
    }

    /// A placeholder for an item that is left out.
    fn skipped() -> Self {
        PrimRef {
            lo: Vec4::ZERO,
            hi: Vec4::new(0.0, 0.0, 0.0, -1.0),
        }
    }

    fn is_skipped(&self) -> bool {
        self.hi.w < 0.0
    }

    #[inline(always)]
    fn lo(&self) -> Vec3A {
        Vec3A::from_vec4(self.lo)
    }

    #[inline(always)]
    fn hi(&self) -> Vec3A {
        Vec3A::from_vec4(self.hi)
    }

    #[inline(always)]
    fn centroid(&self) -> Vec3A {
        (self.lo() + self.hi()) * 0.5
    }

    fn id(&self) -> u32 {
        self.lo.w as u32 | (self.hi.w as u32 & (Self::OTHER_W - 1)) << 16
    }

    /// Whether the item is not a triangle.
    fn other(&self) -> bool {
        self.hi.w as u32 & Self::OTHER_W != 0
    }

    /// Keeps `v` in the lower corner's `x`, once the tree is built and
    /// the box no longer needed (its bits as they are: only moved, never
    /// computed with). The id and kind stay readable.
    fn set_note(&mut self, v: u32) {
        self.lo.x = f32::from_bits(v);
    }

    /// What [`PrimRef::set_note`] kept.
    fn note(&self) -> u32 {
        self.lo.x.to_bits()
    }
}

/// A contiguous range of references: its bounds, its centroids' bounds.
#[derive(Clone, Copy, Debug)]
struct Range {
    begin: usize,
    end: usize,
    bounds: Aabb,
    cbounds: Aabb,
}

impl Range {
    fn len(&self) -> usize {
        self.end - self.begin
    }
}

/// How to divide a range.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Plan {
    /// Items whose centroid falls below bin `pos` (of `bins`) of `axis` go left.
    /// `wide`: a small range that the SAH gives an 8-wide node rather than
    /// a leaf (see [`Builder::wide_cost`]), so that its halves, divided
    /// within a node, go on dividing where that pays (see [`Part::split`]).
    /// (Bytes, not words: ranges carry two plans, and the node loop moves
    /// ranges about.)
    Bin {
        axis: u8,
        pos: u8,
        bins: u8,
        wide: bool,
    },
    /// Equal halves along the centroids' longest axis.
    Median { axis: u8 },
}

/// The built tree (see `Bvh8`).
pub(crate) struct Built {
    pub nodes: Vec<Node>,
    pub tris: Vec<Tri4>,
    pub bounds: Aabb,
    /// Node levels ([`depth`] of `nodes`).
    pub depth: usize,
}

/// Builds the tree over every item of `src`.
pub(crate) fn build<S: Source>(src: &S) -> Built {
    let n = src.count();
    let too_many =
        || format!("the fast BVH holds fewer than 2^28 primitives, with ids below 2^31 (got {n})");
    assert!(n < 1 << 28, "{}", too_many());
    // An indexed map writes straight into the vector (a filtering
    // collect would gather pieces and copy them); skipped items are
    // dropped afterwards in place.
    let mut refs: Vec<PrimRef> = Vec::with_capacity(n);
    huge_pages(&refs);
    refs.par_extend((0..n).into_par_iter().with_min_len(4096).map(|k| {
        let id = src.id(k);
        assert!(id & OTHER == 0, "{}", too_many());
        match src.item(id) {
            Item::Triangle(v) => PrimRef::new(&Aabb::from_points(v), id, false),
            Item::Other(b) => PrimRef::new(&b, id, true),
            Item::Skip => PrimRef::skipped(),
        }
    }));
    // One pass for the bounds, which also finds any item left out (rare:
    // then a second pass drops them).
    let (bounds, cbounds, skipped) = root_bounds(&refs);
    if skipped {
        refs.retain(|r| !r.is_skipped());
    }
    if refs.is_empty() {
        return Built {
            nodes: Vec::new(),
            tris: Vec::new(),
            bounds: Aabb::EMPTY,
            depth: 0,
        };
    }
    let builder = Builder::new(refs.len(), margin(&bounds));
    let all = Range {
        begin: 0,
        end: refs.len(),
        bounds,
        cbounds,
    };
    let plan = builder.plan(&refs, &all, 0);
    // About one node per 6-7 items (measured on sphere1m): reserve enough
    // that the vector never moves (unused capacity costs no memory).
    let mut nodes = Vec::with_capacity(refs.len() / 4 + 1);
    huge_pages(&nodes);
    let root = builder.subtree(&mut refs, all, plan, 0, &mut nodes);
    if is_leaf(root) {
        // A tree of one leaf still starts at a node.
        let mut node = Node::EMPTY;
        builder.set_child(&mut node, 0, root, &all);
        nodes.push(node);
        builder.deeper(1);
    }
    let depth = builder.deepest.into_inner();
    debug_assert_eq!(depth, self::depth(&nodes));
    let tris = fill_leaves(&mut nodes, &mut refs, src);
    Built {
        nodes,
        tris,
        bounds,
        depth,
    }
}

/// Node levels of a built tree (0 when empty): parents precede their
/// children in `nodes`, so one pass in order finds every node's level.
pub(crate) fn depth(nodes: &[Node]) -> usize {
    let mut level = vec![0u8; nodes.len()];
    let mut deepest = 0;
    for (i, n) in nodes.iter().enumerate() {
        let l = level[i].saturating_add(1);
        deepest = deepest.max(l as usize);
        for &c in &n.child {
            if !is_leaf(c) {
                debug_assert!(c as usize > i);
                level[c as usize] = l;
            }
        }
    }
    deepest
}

/// Bounds of the boxes and of the centroids.
fn bounds_of(refs: &[PrimRef]) -> (Aabb, Aabb) {
    let one = |r: &[PrimRef]| {
        r.iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), p| {
            (
                Aabb::new(b.min.min(p.lo.truncate()), b.max.max(p.hi.truncate())),
                c.grow(p.centroid().into()),
            )
        })
    };
    if refs.len() < PARALLEL_BINNING {
        return one(refs);
    }
    refs.par_chunks(8192).map(one).reduce(
        || (Aabb::EMPTY, Aabb::EMPTY),
        |a, b| (a.0.union(&b.0), a.1.union(&b.1)),
    )
}

/// Bounds and centroid bounds of the items not left out, and whether any
/// was.
fn root_bounds(refs: &[PrimRef]) -> (Aabb, Aabb, bool) {
    let one = |r: &[PrimRef]| {
        let (mut acc, mut skipped) = (Acc::new(), false);
        for p in r {
            if p.is_skipped() {
                skipped = true;
            } else {
                acc.add(p.lo(), p.hi(), p.centroid());
            }
        }
        (acc, skipped)
    };
    let (acc, skipped) = if refs.len() < PARALLEL_BINNING {
        one(refs)
    } else {
        refs.par_chunks(8192)
            .map(one)
            .reduce(|| (Acc::new(), false), |a, b| (a.0.union(&b.0), a.1 | b.1))
    };
    let (b, c) = acc.boxes();
    (b, c, skipped)
}

/// Blocks of four a leaf of `n` items needs: the SAH counts blocks, not
/// items, so leaves come out full.
#[inline]
fn blocks(n: usize) -> f32 {
    n.div_ceil(4) as f32
}

/// Per-axis bins: item counts and box bounds. `B` bins: small ranges use
/// fewer, because clearing and sweeping 32 bins costs more than binning a
/// handful of items (most nodes of a tree are small).
#[derive(Clone)]
struct Bins<const B: usize> {
    count: [[u32; B]; 3],
    lo: [[Vec3A; B]; 3],
    hi: [[Vec3A; B]; 3],
}

impl<const B: usize> Bins<B> {
    fn new() -> Self {
        Bins {
            count: [[0; B]; 3],
            lo: [[Vec3A::INFINITY; B]; 3],
            hi: [[Vec3A::NEG_INFINITY; B]; 3],
        }
    }

    fn add(&mut self, refs: &[PrimRef], map: &BinMap) {
        for r in refs {
            let (lo, hi) = (r.lo(), r.hi());
            // The centroid lane-wise: the same operations as `centroid`.
            let k = map.bins::<B>((lo + hi) * 0.5);
            for a in 0..3 {
                let k = k[a];
                self.count[a][k] += 1;
                self.lo[a][k] = self.lo[a][k].min(lo);
                self.hi[a][k] = self.hi[a][k].max(hi);
            }
        }
    }

    fn merge(mut self, o: Self) -> Self {
        for a in 0..3 {
            for k in 0..B {
                self.count[a][k] += o.count[a][k];
                self.lo[a][k] = self.lo[a][k].min(o.lo[a][k]);
                self.hi[a][k] = self.hi[a][k].max(o.hi[a][k]);
            }
        }
        self
    }
}

/// Centroid → bin, per axis, for `B` bins (the scale assumes 1; `bins`
/// multiplies by `B`).
struct BinMap {
    min: Vec3,
    scale: Vec3,
}

impl BinMap {
    fn new(cb: &Aabb) -> Self {
        let e = cb.extent();
        // Just under 1 so that the largest centroid lands in the last bin.
        let s = 1.0 - 1e-6;
        BinMap {
            min: cb.min,
            scale: Vec3::select(e.cmpgt(Vec3::ZERO), Vec3::splat(s) / e, Vec3::ZERO),
        }
    }

    #[inline]
    fn bins<const B: usize>(&self, c: Vec3A) -> [usize; 3] {
        let k = (c - Vec3A::from(self.min)) * Vec3A::from(self.scale) * B as f32;
        // Clamped to [0, B - 1] in float, lane-wise (NaN gives 0: `max`
        // returns its argument when a lane is NaN), then truncated: the
        // same bins as truncating first and clamping the integer (B - 1 is
        // an integer), but the conversion is a plain 32-bit one (a
        // saturating f32-to-usize conversion per axis was a tenth of the
        // build's time).
        let k = k.max(Vec3A::ZERO).min(Vec3A::splat((B - 1) as f32));
        truncate::<B>(k)
    }
}

/// The integer parts of `k`'s lanes, each in `[0, B − 1]` (so the mask
/// changes nothing and spares the bins' bounds checks). On x86-64 one SSE2
/// conversion of the vector (`cvttps2dq`, where `as i32` adds saturation
/// and NaN checks per lane that the clamp has made useless); elsewhere `as
/// i32`. Both truncate, so the bins are the same.
#[inline(always)]
fn truncate<const B: usize>(k: Vec3A) -> [usize; 3] {
    const { assert!(B.is_power_of_two()) };
    #[cfg(target_arch = "x86_64")]
    let [x, y, z] = {
        use std::arch::x86_64::{_mm_cvtsi128_si32, _mm_cvttps_epi32, _mm_shuffle_epi32};
        // SAFETY: these intrinsics need only SSE2, which every x86-64 CPU
        // has (it is in the x86_64 baseline Rust compiles for, so
        // `cfg(target_arch = "x86_64")` implies it); they touch no memory.
        unsafe {
            let v = _mm_cvttps_epi32(k.into());
            [
                _mm_cvtsi128_si32(v),
                _mm_cvtsi128_si32(_mm_shuffle_epi32::<0b01_01_01_01>(v)),
                _mm_cvtsi128_si32(_mm_shuffle_epi32::<0b10_10_10_10>(v)),
            ]
        }
    };
    #[cfg(not(target_arch = "x86_64"))]
    let [x, y, z] = [k.x as i32, k.y as i32, k.z as i32];
    [
        x as usize & (B - 1),
        y as usize & (B - 1),
        z as usize & (B - 1),
    ]
}

/// Whether a centroid goes left of bin `pos` (of `bins`) of `axis` in
/// range `r`: the same arithmetic as `BinMap::bins`, on one axis, without
/// the conversion: for `k ≥ 0` and `pos ≤ bins − 1`, `trunc(min(k, bins −
/// 1)) < pos` exactly when `k < pos`. All three axes at once, the plan's
/// picked from the mask.
#[inline(always)]
fn left_of(r: &Range, axis: u8, pos: u8, bins: u8) -> impl Fn(Vec3A) -> bool + Sync + Copy {
    let (axis, pos, bins) = (axis as usize, pos as usize, bins as usize);
    let map = BinMap::new(&r.cbounds);
    let (min, scale) = (map.min[axis], map.scale[axis] * bins as f32);
    let (min, scale) = (Vec3A::splat(min), Vec3A::splat(scale));
    let pos = Vec3A::splat(pos as f32);
    // NaN gives 0, as in `BinMap::bins`.
    move |c: Vec3A| ((c - min) * scale).max(Vec3A::ZERO).cmplt(pos).bitmask() >> axis & 1 != 0
}

/// Bins for ranges of fewer than `SMALL_RANGE` items.
const SMALL_BINS: usize = 8;
/// See [`SMALL_BINS`].
const SMALL_RANGE: usize = 64;

/// The cheapest plane over `B` bins (see [`sweep`]), binned on this
/// thread: the bins stay in this frame (returning them was a copy of up to
/// 3.4 KB per node).
fn serial_sweep<const B: usize>(items: &[PrimRef], cb: &Aabb, ce: Vec3) -> (f32, usize, usize) {
    let mut b = Bins::<B>::new();
    b.add(items, &BinMap::new(cb));
    sweep(&b, items.len(), ce)
}

/// Bins of a very large range, binned in parallel.
fn large_bins(items: &[PrimRef], cb: &Aabb) -> Bins<BINS> {
    let map = BinMap::new(cb);
    items
        .par_chunks(16 * 1024)
        .fold(Bins::new, |mut b, c| {
            b.add(c, &map);
            b
        })
        .reduce(Bins::new, Bins::merge)
}

/// The cheapest plane: `(cost, axis, first bin on the right)`; the cost is
/// the children's `area × blocks` (infinite when no plane separates items).
fn sweep<const B: usize>(bins: &Bins<B>, n: usize, ce: Vec3) -> (f32, usize, usize) {
    let mut best = (f32::INFINITY, 0, 0);
    for a in 0..3 {
        if ce[a] <= 0.0 {
            continue;
        }
        // Right-to-left: cost of the right side of each plane.
        let mut right = [0f32; B];
        let (mut lo, mut hi, mut c) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY, 0usize);
        for k in (1..B).rev() {
            lo = lo.min(bins.lo[a][k]);
            hi = hi.max(bins.hi[a][k]);
            c += bins.count[a][k] as usize;
            right[k] = if c == 0 {
                f32::INFINITY
            } else {
                area(lo, hi) * blocks(c)
            };
        }
        let (mut lo, mut hi, mut c) = (Vec3A::INFINITY, Vec3A::NEG_INFINITY, 0usize);
        #[allow(clippy::needless_range_loop)] // k indexes bins and `right` alike
        for k in 1..B {
            lo = lo.min(bins.lo[a][k - 1]);
            hi = hi.max(bins.hi[a][k - 1]);
            c += bins.count[a][k - 1] as usize;
            if c == 0 || c == n {
                continue;
            }
            let cost = area(lo, hi) * blocks(c) + right[k];
            if cost < best.0 {
                best = (cost, a, k);
            }
        }
    }
    best
}

fn area(lo: Vec3A, hi: Vec3A) -> f32 {
    let e = (hi - lo).max(Vec3A::ZERO);
    2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
}

/// The axis of `e`'s largest component (the first of equals).
fn longest(e: Vec3) -> usize {
    if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    }
}

/// Node levels that median splits, which at least quarter a range per
/// level (two halvings of the up to seven a node takes), need at most to
/// finish a range of `n` items (about log4(n)).
fn levels_left(n: usize) -> usize {
    (usize::BITS - n.leading_zeros()) as usize / 2 + 2
}

/// The plan of `r` at node level `depth` when it needs no bins: a leaf
/// for four items or fewer, the median for coincident centroids (above a
/// leaf's capacity) and for a range too deep for the SAH to finish under
/// `MAX_DEPTH` (switching while median splits still fit: only degenerate
/// inputs ever get there). `None`: the bins decide, and their plan is the
/// same at every level where this stays `None`.
fn forced(r: &Range, depth: usize) -> Option<Option<Plan>> {
    let n = r.len();
    if n <= 4 {
        return Some(None);
    }
    let ce = r.cbounds.extent();
    let axis = longest(ce);
    if ce[axis] <= 0.0 {
        // Coincident centroids: no plane separates them.
        return Some((n > LEAF_ITEMS).then_some(Plan::Median { axis: axis as u8 }));
    }
    if depth + levels_left(n) >= MAX_DEPTH {
        return Some(Some(Plan::Median { axis: axis as u8 }));
    }
    None
}

impl Plan {
    /// The axis the plan divides on.
    fn axis(self) -> u8 {
        match self {
            Plan::Bin { axis, .. } | Plan::Median { axis } => axis,
        }
    }

    /// Whether the plan makes a small range an 8-wide node rather than a leaf.
    fn wide(self) -> bool {
        matches!(self, Plan::Bin { wide: true, .. })
    }
}

/// A range with its plan, made for node level `depth`, perhaps already
/// divided into its halves (with their plans) ahead of its turn: see
/// [`Builder::expand`].
struct Part {
    r: Range,
    /// How the range divides as a subtree of its own (`None`: a leaf).
    plan: Option<Plan>,
    /// How the node loop divides the range within the node it is a child
    /// of (`None`: it stays one child). `plan`, except within a wide node
    /// (the halves of a range with a wide plan, and theirs): there a
    /// division costs no node test, so a range divides by its cheapest
    /// plane when that pays within two levels ([`Builder::free_split`]);
    /// the node loop takes the largest first while the node has slots.
    split: Option<Plan>,
    /// Whether the range is within a wide node (its halves are too).
    wide: bool,
    depth: usize,
    halves: Option<Box<(Part, Part)>>,
}

impl Part {
    fn new(r: Range, plan: Option<Plan>, depth: usize) -> Self {
        Part {
            r,
            plan,
            split: plan,
            wide: false,
            depth,
            halves: None,
        }
    }

    /// Whether the node loop divides the range as the binary SAH (or,
    /// within a wide node, [`Builder::free_split`]) asks, not only to fill
    /// a slot.
    fn sah_divides(&self) -> bool {
        self.split.is_some() && (self.wide || self.plan.is_some())
    }

    /// A range with its [`Builder::plan_and_split`].
    fn divided(r: Range, (plan, split): Split, depth: usize) -> Self {
        Part {
            split,
            ..Part::new(r, plan, depth)
        }
    }

    /// A range within a wide node, whose items are `items`.
    fn within(b: &Builder, items: &[PrimRef], r: Range, plan: Option<Plan>, depth: usize) -> Self {
        Part {
            split: b.free_split(items, &r),
            wide: true,
            ..Part::new(r, plan, depth)
        }
    }
}

/// A range's plan and its split within its parent node (see
/// [`Builder::plan_and_split`]).
type Split = (Option<Plan>, Option<Plan>);

/// [`Node::split`] of a node divided by `plan`.
fn split_bit(plan: Option<Plan>) -> u8 {
    plan.map_or(0, |p| 1 << p.axis())
}

/// The child the node loop divides next: the largest by surface area of
/// those that divide (the last of equals), given each child's range and
/// whether it divides.
fn next_to_split<'a>(kids: impl Iterator<Item = (&'a Range, bool)>) -> Option<usize> {
    kids.enumerate()
        .filter(|(_, (_, divides))| *divides)
        .max_by(|x, y| {
            x.1 .0
                .bounds
                .surface_area()
                .total_cmp(&y.1 .0.bounds.surface_area())
        })
        .map(|(i, _)| i)
}

/// Binary levels of a node (1 + 2 + 4 = 7 divisions: its eight children
/// when the tree is balanced) divided on several threads at once ahead of
/// the node's loop, for ranges of `PARALLEL_ITEMS` or more.
const SPECULATE_LEVELS: usize = 3;
/// Ranges below this many items are not divided ahead of their turn.
const SPECULATE_ITEMS: usize = 4 * 1024;

/// Builds of up to this many items weigh a wide node against each small
/// range's leaf (see [`Builder::wide_cost`]); larger ones (meshes) only
/// the binary split. On meshes (bunny40k, sphere1m, with this limit
/// lifted) the wide nodes cut leaf tests by 12-15% but the rays were no
/// faster (within a few percent either way: each extra node level is
/// another load on a tree far larger than the caches), while the tree
/// took 8-11% more bytes and the build 35-50% longer (each small range's
/// node is first found on a copy). The scenes of a few items it is for,
/// rooms and rows of spheres, rendered 2-10% faster.
const WIDE_ITEMS: usize = 4096;

struct Builder {
    pad: Vec3,
    /// Whether small ranges may become wide nodes ([`WIDE_ITEMS`]).
    wide: bool,
    /// Whether the build is of more than [`LARGE_ITEMS`] items.
    large: bool,
    /// Whether the build is of more than [`HUGE_ITEMS`] items.
    huge: bool,
    /// The deepest node level built so far (see [`depth`]).
    deepest: AtomicUsize,
}

impl Builder {
    /// The builder of `n` items, whose boxes are padded by `pad`.
    fn new(n: usize, pad: f32) -> Builder {
        Builder {
            pad: Vec3::splat(pad),
            wide: n <= WIDE_ITEMS,
            large: n > LARGE_ITEMS,
            huge: n > HUGE_ITEMS,
            deepest: AtomicUsize::new(0),
        }
    }

    /// Most items a leaf holds: [`MAX_LEAF_ITEMS`] in builds of more than
    /// [`LARGE_ITEMS`] items, else [`LEAF_ITEMS`].
    fn leaf_items(&self) -> usize {
        if self.large {
            MAX_LEAF_ITEMS
        } else {
            LEAF_ITEMS
        }
    }

    /// The SAH's cost of a binary division relative to a block's test:
    /// [`SPLIT_COST`], [`SMALL_SPLIT_COST`] in builds of up to
    /// [`WIDE_ITEMS`] items, [`LARGE_SPLIT_COST`] in builds of more than
    /// [`LARGE_ITEMS`] and [`HUGE_SPLIT_COST`] of more than [`HUGE_ITEMS`].
    fn split_cost(&self) -> f32 {
        if self.wide {
            SMALL_SPLIT_COST
        } else if self.huge {
            HUGE_SPLIT_COST
        } else if self.large {
            LARGE_SPLIT_COST
        } else {
            SPLIT_COST
        }
    }

    /// How to divide `r`, or `None` for a leaf.
    /// `items` are the range's references; `depth` is the node level the
    /// range's node would sit at.
    fn plan(&self, items: &[PrimRef], r: &Range, depth: usize) -> Option<Plan> {
        self.plan_and_split(items, r, depth).0
    }

    /// [`plan`](Self::plan), and how the node loop may divide `r` as a
    /// child within its parent node ([`Part::split`]): by the plan, or,
    /// in a build of more than [`WIDE_ITEMS`] items, for a leaf of more
    /// than four items, by its cheapest plane all the same. A node's
    /// eight boxes cost one test whatever they hold, so a slot the SAH's
    /// divisions leave free is better spent on splitting a leaf: a ray
    /// then tests only the blocks whose boxes it meets. The node loop
    /// gives such slots out only after the SAH's divisions (see
    /// [`Builder::children`]), so the tree's nodes are the ones the SAH
    /// alone makes, and only leaves change. Embree's builder divides every
    /// child of more than four items while its node has slots, largest
    /// first whether or not the SAH would: on the anchors' rays it tested
    /// fewer blocks than glint did for as many nodes (its statistics
    /// counters, `EMBREE_STAT_COUNTERS`). Measured here with a split cost
    /// of 1.0 (`glint bench rays --stats`): 17-25% fewer triangle tests a
    /// ray on the anchors' meshes for the same nodes, 0.3-0.8% more bytes.
    fn plan_and_split(&self, items: &[PrimRef], r: &Range, depth: usize) -> Split {
        if let Some(plan) = forced(r, depth) {
            return (plan, plan);
        }
        let (n, ce) = (r.len(), r.cbounds.extent());
        let best = if n < SMALL_RANGE {
            serial_sweep::<SMALL_BINS>(items, &r.cbounds, ce)
        } else if n < PARALLEL_BINNING {
            serial_sweep::<BINS>(items, &r.cbounds, ce)
        } else {
            sweep(&large_bins(items, &r.cbounds), n, ce)
        };
        let whole = r.bounds.surface_area();
        let split = self.split_cost() * whole + best.0;
        let bin = |wide| Plan::Bin {
            axis: best.1 as u8,
            pos: best.2 as u8,
            bins: if n < SMALL_RANGE { SMALL_BINS } else { BINS } as u8,
            wide,
        };
        if n <= self.leaf_items() && whole * blocks(n) <= split {
            // The binary SAH charges each binary level a node test and
            // sees only two children: it cannot see that the items of a
            // room (each plane leaves one side with the whole room's box)
            // spread over an 8-wide node's children cost less than a leaf.
            let wide = self.wide
                && best.0.is_finite()
                && self.wide_cost(items, r, bin(true)) < whole * blocks(n);
            if wide {
                return (Some(bin(true)), Some(bin(true)));
            }
            // (`forced` made ranges of four items or fewer leaves.) Not
            // in builds of up to `WIDE_ITEMS` items, which weigh wide
            // nodes instead: there the depth-of-field scene of `scenes/`
            // (a few spheres on a plane) rendered in 1.05-1.09x the time.
            let fill = !self.wide && best.0.is_finite();
            return (None, fill.then(|| bin(false)));
        }
        let plan = if best.0.is_finite() {
            bin(false)
        } else {
            Plan::Median {
                axis: longest(ce) as u8,
            }
        };
        (Some(plan), Some(plan))
    }

    /// The cheapest plane of a small range within a wide node (whose items
    /// are `items`), if dividing by it lowers the range's `area × blocks`,
    /// or dividing by it and then each half by its own cheapest plane does.
    /// A division within a node adds no node test, only children. The
    /// second level is needed for enclosing geometry: the items of a
    /// room's walls in one range have the room's box, and peeling one wall
    /// off leaves the rest with it and often the same blocks, so only the
    /// next division pays. [`Builder::wide_cost`] then weighs the node's
    /// children as they come out against the leaf.
    fn free_split(&self, items: &[PrimRef], r: &Range) -> Option<Plan> {
        let n = r.len();
        debug_assert!(n <= MAX_LEAF_ITEMS);
        if n < 2 {
            return None;
        }
        // (own cost, cheapest plane's cost, its axis and bin)
        let cost = |items: &[PrimRef], r: &Range| {
            let own = r.bounds.surface_area() * blocks(r.len());
            if r.len() < 2 {
                return (own, own, 0, 0);
            }
            let (c, axis, pos) = serial_sweep::<SMALL_BINS>(items, &r.cbounds, r.cbounds.extent());
            (own, c, axis, pos)
        };
        let (own, one, axis, pos) = cost(items, r);
        if !one.is_finite() {
            return None;
        }
        let plan = Plan::Bin {
            axis: axis as u8,
            pos: pos as u8,
            bins: SMALL_BINS as u8,
            wide: false,
        };
        if one < own {
            return Some(plan);
        }
        let mut copy = [PrimRef::skipped(); MAX_LEAF_ITEMS];
        let buf = &mut copy[..n];
        buf.copy_from_slice(items);
        let whole = Range {
            begin: 0,
            end: n,
            ..*r
        };
        let (a, b) = Self::divide_small(buf, &whole, plan);
        let two: f32 = [a, b]
            .iter()
            .map(|h| {
                let (own, c, _, _) = cost(&buf[h.begin..h.end], h);
                own.min(c)
            })
            .sum();
        (two < own).then_some(plan)
    }

    /// The SAH cost of making the small range `r` (its items are `items`)
    /// an 8-wide node whose first division is `first`: one node test
    /// (the split cost, as a binary level is charged) plus its children's
    /// `area × blocks`, the children being those the node loop makes
    /// (within a wide node: [`Part::split`]), found here on a copy of the
    /// items. The binary SAH charges a node test per binary level; a wide
    /// node's up to three levels of divisions cost one.
    fn wide_cost(&self, items: &[PrimRef], r: &Range, first: Plan) -> f32 {
        let n = items.len();
        debug_assert!(n <= MAX_LEAF_ITEMS && n == r.len());
        let mut copy = [PrimRef::skipped(); MAX_LEAF_ITEMS];
        let buf = &mut copy[..n];
        buf.copy_from_slice(items);
        let whole = Range {
            begin: 0,
            end: n,
            ..*r
        };
        let mut kids = [(whole, None); W];
        let (a, b) = Self::divide_small(buf, &whole, first);
        kids[0] = (a, self.free_split(&buf[a.begin..a.end], &a));
        kids[1] = (b, self.free_split(&buf[b.begin..b.end], &b));
        let mut len = 2;
        while len < W {
            let Some(i) = next_to_split(kids[..len].iter().map(|(k, s)| (k, s.is_some()))) else {
                break;
            };
            let (k, s) = kids[i];
            let (a, b) = Self::divide_small(&mut buf[k.begin..k.end], &k, s.expect("divides"));
            kids.copy_within(i + 1..len, i + 2);
            kids[i] = (a, self.free_split(&buf[a.begin..a.end], &a));
            kids[i + 1] = (b, self.free_split(&buf[b.begin..b.end], &b));
            len += 1;
        }
        let leaves: f32 = kids[..len]
            .iter()
            .map(|(k, _)| k.bounds.surface_area() * blocks(k.len()))
            .sum();
        self.split_cost() * r.bounds.surface_area() + leaves
    }

    /// Divides the copy `buf` of a small range `r` by the bin plan `plan`,
    /// for [`Builder::wide_cost`] and [`Builder::free_split`]: the sides of
    /// [`Builder::divide`], with their bounds, the order within each side
    /// perhaps another (no cost depends on it). Not `divide` itself: a
    /// third caller changed how the compiler inlined it and its partition
    /// into the large builds' path (5% more instructions building a 64k
    /// mesh).
    fn divide_small(buf: &mut [PrimRef], r: &Range, plan: Plan) -> (Range, Range) {
        let Plan::Bin {
            axis, pos, bins, ..
        } = plan
        else {
            unreachable!("small ranges divide by bins")
        };
        let left = left_of(r, axis, pos, bins);
        let mut out = [PrimRef::skipped(); MAX_LEAF_ITEMS];
        let (mut l, mut rt) = (0, buf.len());
        for p in buf.iter() {
            if left(p.centroid()) {
                out[l] = *p;
                l += 1;
            } else {
                rt -= 1;
                out[rt] = *p;
            }
        }
        buf.copy_from_slice(&out[..buf.len()]);
        debug_assert!(l > 0 && l < buf.len());
        let ((lb, lc), (rb, rc)) = (bounds_of(&buf[..l]), bounds_of(&buf[l..]));
        let m = r.begin + l;
        (
            Range {
                begin: r.begin,
                end: m,
                bounds: lb,
                cbounds: lc,
            },
            Range {
                begin: m,
                end: r.end,
                bounds: rb,
                cbounds: rc,
            },
        )
    }

    /// Divides `r` (its items are `refs`, which starts at `r.begin`) by
    /// `plan` into two non-empty ranges with their bounds.
    #[cfg(test)]
    fn divide(&self, refs: &mut [PrimRef], r: &Range, plan: Plan) -> (Range, Range) {
        self.divide_among(refs, r, plan, 1)
    }

    /// [`Builder::divide`] by a task that shares the threads with up to
    /// `tasks − 1` others: a large range is partitioned on all threads
    /// while there are fewer tasks than threads (else the others keep them
    /// busy, and the serial loop is cheaper: the parallel partition reads
    /// the items that change sides twice), or when it is very large.
    fn divide_among(
        &self,
        refs: &mut [PrimRef],
        r: &Range,
        plan: Plan,
        tasks: usize,
    ) -> (Range, Range) {
        let n = refs.len();
        // (The thread count only for large ranges: most are small.)
        let parallel = n >= PARALLEL_PARTITION && {
            let threads = rayon::current_num_threads();
            threads > 1 && (tasks < threads || n >= SHARED_PARALLEL_PARTITION)
        };
        let (mid, (lb, lc), (rb, rc)) = match plan {
            Plan::Bin {
                axis, pos, bins, ..
            } => partition(refs, left_of(r, axis, pos, bins), parallel),
            Plan::Median { axis } => {
                let axis = axis as usize;
                let mid = refs.len() / 2;
                refs.select_nth_unstable_by(mid, |a, b| {
                    a.centroid()[axis].total_cmp(&b.centroid()[axis])
                });
                let (l, rt) = refs.split_at(mid);
                (mid, bounds_of(l), bounds_of(rt))
            }
        };
        debug_assert!(mid > 0 && mid < refs.len());
        let m = r.begin + mid;
        (
            Range {
                begin: r.begin,
                end: m,
                bounds: lb,
                cbounds: lc,
            },
            Range {
                begin: m,
                end: r.end,
                bounds: rb,
                cbounds: rc,
            },
        )
    }

    /// The plans of the two halves `a` and `b` of a range whose items are
    /// `items`: on two threads when the range is large (each plan is a pass
    /// over its half; a half of more than `PARALLEL_BINNING` items is also
    /// binned in parallel chunks).
    fn plans(&self, items: &[PrimRef], a: &Range, b: &Range, depth: usize) -> (Split, Split) {
        let (ia, ib) = items.split_at(a.len());
        let plan = |items, r| self.plan_and_split(items, r, depth);
        if a.len() + b.len() >= PARALLEL_PLANS && rayon::current_num_threads() > 1 {
            rayon::join(|| plan(ia, a), || plan(ib, b))
        } else {
            (plan(ia, a), plan(ib, b))
        }
    }

    fn set_child(&self, node: &mut Node, i: usize, c: u32, r: &Range) {
        node.set(i, c, r.bounds.min - self.pad, r.bounds.max + self.pad);
    }

    /// Divides `p` (its items are `items`) into its halves with their plans
    /// for node level `depth`: the halves divided ahead of time if there
    /// are any, else dividing now. Halves divided ahead carry plans made
    /// for a level up to two above `depth` (a range of a node's binary
    /// levels may end up a child, whose halves are then its node's); their
    /// plans are the same at `depth`, because `expand` only divides ranges
    /// far enough from `MAX_DEPTH` that the median is not forced on them or
    /// their halves any sooner (see [`forced`]).
    ///
    /// `root`: `p` is the node's own range, divided by its `plan` (else a
    /// child divided within the node, by its `split`). The halves are
    /// within a wide node when the plan that divides `p` is wide or `p`
    /// itself is within one (not past the node: a root's halves are
    /// within a wide node only by its own plan).
    fn halves(
        &self,
        items: &mut [PrimRef],
        p: Part,
        depth: usize,
        root: bool,
        tasks: usize,
    ) -> (Part, Part) {
        let by = if root { p.plan } else { p.split };
        let by = by.expect("a range that divides");
        let wide = by.wide() || (p.wide && !root);
        let (mut a, mut b) = match p.halves {
            Some(h) => {
                // Only large ranges are divided ahead, never wide ones.
                debug_assert!(!wide && by == p.plan.expect("divided by its plan"));
                *h
            }
            None => {
                let (a, b) = self.divide_among(items, &p.r, by, tasks);
                let (pa, pb) = self.plans(items, &a, &b, depth);
                if wide {
                    let (ia, ib) = items.split_at(a.len());
                    (
                        Part::within(self, ia, a, pa.0, depth),
                        Part::within(self, ib, b, pb.0, depth),
                    )
                } else {
                    (Part::divided(a, pa, depth), Part::divided(b, pb, depth))
                }
            }
        };
        for h in [&mut a, &mut b] {
            debug_assert!(h.depth <= depth && depth <= h.depth + 2);
            debug_assert!(
                forced(&h.r, depth).is_none_or(|plan| plan == h.plan),
                "a plan made a level up differs"
            );
            h.depth = depth;
        }
        (a, b)
    }

    /// Divides `p` (its items are `items`) and its halves down to `levels`
    /// binary levels, the two halves of each range on two threads, with
    /// the halves' plans made for node level `depth`. Each division is the
    /// one the node's loop (or a child's, one or more levels down) makes
    /// when it gets there: a range with a plan is always divided, by the
    /// same plan and from the same order of items, whichever thread does it
    /// and when. The plans are made for `depth` and used perhaps a few
    /// levels deeper: only ranges whose plan is the same at every one of
    /// those levels are divided ahead (see [`forced`]).
    fn expand(
        &self,
        items: &mut [PrimRef],
        p: &mut Part,
        depth: usize,
        levels: usize,
        tasks: usize,
    ) {
        let n = p.r.len();
        if levels == 0
            || n < SPECULATE_ITEMS
            || p.plan.is_none()
            || p.depth + SPECULATE_LEVELS + levels_left(n) >= MAX_DEPTH
        {
            return;
        }
        if p.halves.is_none() {
            let plan = p.plan.expect("checked");
            let (a, b) = self.divide_among(items, &p.r, plan, tasks);
            let (pa, pb) = self.plans(items, &a, &b, depth);
            p.halves = Some(Box::new((
                Part::divided(a, pa, depth),
                Part::divided(b, pb, depth),
            )));
        }
        let (a, b) = &mut **p.halves.as_mut().expect("just made");
        let (ia, ib) = items.split_at_mut(a.r.len());
        rayon::join(
            || self.expand(ia, a, depth, levels - 1, 2 * tasks),
            || self.expand(ib, b, depth, levels - 1, 2 * tasks),
        );
    }

    /// Builds the subtree over `r` (whose items are exactly `refs`) and
    /// appends its nodes to `out`, parent first. Returns its reference: a
    /// leaf (its first item: `fill_leaves` finds where it ends and rewrites
    /// it to blocks) or the index of its root in `out`.
    fn subtree(
        &self,
        refs: &mut [PrimRef],
        r: Range,
        plan: Option<Plan>,
        depth: usize,
        out: &mut Vec<Node>,
    ) -> u32 {
        self.subtree_of(refs, Part::new(r, plan, depth), depth, out)
    }

    /// [`Builder::subtree`] of a range that may be divided already.
    fn subtree_of(
        &self,
        refs: &mut [PrimRef],
        part: Part,
        depth: usize,
        out: &mut Vec<Node>,
    ) -> u32 {
        let r = part.r;
        if part.plan.is_none() {
            return leaf(r.begin, 1);
        }
        // (On one thread the parallel path would only add copies.)
        if r.len() >= PARALLEL_ITEMS && rayon::current_num_threads() > 1 {
            let laid = self.parallel_subtree(refs, part, depth, 1);
            let at = out.len();
            lay_out(&laid, out);
            return at as u32;
        }
        let split = split_bit(part.plan);
        let (kids, len) = self.children(refs, part, depth, 1);
        let kids = kids.into_iter().take(len).map(|k| k.expect("filled"));
        let at = out.len();
        out.push(Node::EMPTY);
        let mut node = Node {
            split,
            ..Node::EMPTY
        };
        for (i, k) in kids.enumerate() {
            let kr = k.r;
            let sub = refs_of(refs, &r, &kr);
            let c = self.subtree_of(sub, k, depth + 1, out);
            self.set_child(&mut node, i, c, &kr);
        }
        self.deeper(depth + 1);
        out[at] = node;
        at as u32
    }

    /// The node of `part` at node level `depth` (its range divides) and
    /// its children's ranges: the node's binary levels divided, the
    /// largest child that divides first, until it has `W` children or
    /// none divides. Returns them in order, and how many.
    fn children(
        &self,
        refs: &mut [PrimRef],
        part: Part,
        depth: usize,
        tasks: usize,
    ) -> ([Option<Part>; W], usize) {
        let r = part.r;
        // (On the stack: a vector here was an allocation per node.)
        let mut all: [Option<Part>; W] = Default::default();
        let (a, b) = self.halves(refs, part, depth + 1, true, tasks);
        (all[0], all[1]) = (Some(a), Some(b));
        let mut len = 2;
        while len < W {
            // The children the SAH divides first; then, into the slots
            // left, the leaves that divide (see `plan_and_split`).
            let kids = || all[..len].iter().map(|k| k.as_ref().expect("filled"));
            let pick = next_to_split(kids().map(|k| (&k.r, k.sah_divides())))
                .or_else(|| next_to_split(kids().map(|k| (&k.r, k.split.is_some()))));
            let Some(i) = pick else { break };
            let k = all[i].take().expect("filled");
            let kr = k.r;
            let (a, b) = self.halves(refs_of(refs, &r, &kr), k, depth + 1, false, tasks);
            // `a` and `b` take `k`'s place, in order.
            for j in (i + 1..len).rev() {
                all[j + 1] = all[j].take();
            }
            (all[i], all[i + 1]) = (Some(a), Some(b));
            len += 1;
        }
        (all, len)
    }

    /// [`Builder::subtree_of`] on several threads, of a range that divides:
    /// its binary levels divided ahead on all threads, then its children
    /// built in parallel, each into an array of its own (or, if large, a
    /// [`Laid`] of its own), laid out in one array at the end.
    fn parallel_subtree(
        &self,
        refs: &mut [PrimRef],
        mut part: Part,
        depth: usize,
        tasks: usize,
    ) -> Laid {
        let r = part.r;
        let split = split_bit(part.plan);
        self.expand(refs, &mut part, depth + 1, SPECULATE_LEVELS, tasks);
        let (kids, len) = self.children(refs, part, depth, tasks);
        let kids = kids.into_iter().take(len).map(|k| k.expect("filled"));
        let mut slices = Vec::with_capacity(W);
        let mut rest = &mut *refs;
        let mut base = r.begin;
        for k in kids {
            let (mine, tail) = rest.split_at_mut(k.r.end - base);
            let begin = k.r.begin - base;
            base = k.r.end;
            slices.push((&mut mine[begin..], k));
            rest = tail;
        }
        let tasks = tasks * slices.len();
        let subs: Vec<(u32, Range, Laid)> = slices
            .into_par_iter()
            .map(|(s, k)| {
                let kr = k.r;
                if k.plan.is_some() && kr.len() >= PARALLEL_ITEMS {
                    (0, kr, self.parallel_subtree(s, k, depth + 1, tasks))
                } else {
                    // Built in this thread's scratch array, then copied
                    // (from the cache) to one of the exact size: fresh
                    // arrays of a guessed size took fresh pages.
                    SCRATCH.with_borrow_mut(|v| {
                        v.clear();
                        let c = self.subtree_of(s, k, depth + 1, v);
                        (c, kr, Laid::Flat(v.to_vec()))
                    })
                }
            })
            .collect();
        // The children's nodes follow the node, one child's after another.
        let mut node = Node {
            split,
            ..Node::EMPTY
        };
        let mut at = 1;
        for (i, (c, k, laid)) in subs.iter().enumerate() {
            let c = if is_leaf(*c) { *c } else { c + at as u32 };
            self.set_child(&mut node, i, c, k);
            at += laid.len();
        }
        self.deeper(depth + 1);
        Laid::Parent {
            node: Box::new(node),
            kids: subs.into_iter().map(|(_, _, laid)| laid).collect(),
            len: at,
        }
    }

    /// Notes a node at level `level` (1: the root).
    fn deeper(&self, level: usize) {
        // Read first: the deepest level seldom changes, and a write per
        // node would move the line between the threads.
        if self.deepest.load(Relaxed) < level {
            self.deepest.fetch_max(level, Relaxed);
        }
    }
}

thread_local! {
    /// Where [`Builder::parallel_subtree`] builds a small child's nodes.
    static SCRATCH: std::cell::RefCell<Vec<Node>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The nodes of a subtree whose children were built on several threads,
/// each child's into an array of its own, before they are laid out in one
/// array by [`lay_out`] (which copies each node once: appending each
/// level's children to their parent's array copied every node once per
/// level, and took fresh memory for each level's copy).
enum Laid {
    /// Nodes in order, their children's indices counted from the first.
    Flat(Vec<Node>),
    /// A node (its children's indices counted from its own place), then
    /// its children's nodes, one child's after another: `len` nodes.
    Parent {
        node: Box<Node>,
        kids: Vec<Laid>,
        len: usize,
    },
}

impl Laid {
    fn len(&self) -> usize {
        match self {
            Laid::Flat(v) => v.len(),
            Laid::Parent { len, .. } => *len,
        }
    }

    /// The runs of nodes of `self`, laid out from `at`: (where the run
    /// starts, its nodes). A node's children's indices count from the
    /// start of its run.
    fn runs<'a>(&'a self, at: usize, out: &mut Vec<(usize, &'a [Node])>) {
        match self {
            Laid::Flat(v) => {
                if !v.is_empty() {
                    out.push((at, v));
                }
            }
            Laid::Parent { node, kids, .. } => {
                out.push((at, std::slice::from_ref(&**node)));
                let mut p = at + 1;
                for k in kids {
                    k.runs(p, out);
                    p += k.len();
                }
            }
        }
    }
}

/// Appends the nodes of `laid` to `out`, their children's indices shifted
/// to where they land, on all threads.
fn lay_out(laid: &Laid, out: &mut Vec<Node>) {
    let mut runs = Vec::new();
    laid.runs(0, &mut runs);
    let total = laid.len();
    // The run holding node `g` is at or after `first[g / STEP]`, and a
    // run is about a subtree of 2-4k items (hundreds of nodes): a step or
    // two from there.
    const STEP: usize = 256;
    let mut first = Vec::with_capacity(total.div_ceil(STEP));
    let mut i = 0;
    for g in (0..total).step_by(STEP) {
        while i + 1 < runs.len() && runs[i + 1].0 <= g {
            i += 1;
        }
        first.push(i);
    }
    let base = out.len();
    out.par_extend((0..total).into_par_iter().with_min_len(1024).map(|g| {
        let mut i = first[g / STEP];
        while i + 1 < runs.len() && runs[i + 1].0 <= g {
            i += 1;
        }
        let (start, run) = runs[i];
        let shift = (base + start) as u32;
        let mut n = run[g - start];
        for ch in &mut n.child {
            if !is_leaf(*ch) {
                *ch += shift;
            }
        }
        n
    }));
}

/// The items of `k` within `refs`, which holds the items of `r`.
fn refs_of<'a>(refs: &'a mut [PrimRef], r: &Range, k: &Range) -> &'a mut [PrimRef] {
    &mut refs[k.begin - r.begin..k.end - r.begin]
}

/// Turns the leaves' item ranges into ranges of [`Tri4`] blocks and fills
/// the blocks (leaves in item order, so each leaf's blocks are contiguous).
///
/// Each leaf's new reference is kept in its first item's spare lane
/// ([`PrimRef::set_note`]) and each block's items packed in a word, not
/// in an array of a word per item (4 MB on a 1M-triangle mesh, zeroed
/// and mostly unused) and one of two words per block: sphere1m's build
/// took 1289 page faults instead of 1549.
fn fill_leaves<S: Source>(nodes: &mut [Node], refs: &mut [PrimRef], src: &S) -> Vec<Tri4> {
    use std::sync::atomic::{AtomicU64, Ordering::Relaxed};
    // The leaves tile the items in order; until here a leaf's reference
    // holds only its first item. Mark those (a bit per item), then each
    // leaf runs to the next one's first item.
    let n = refs.len();
    let starts: Vec<AtomicU64> = (0..n.div_ceil(64)).map(|_| AtomicU64::new(0)).collect();
    nodes.par_iter().for_each(|node| {
        for &c in &node.child {
            if is_leaf(c) && c != EMPTY {
                let s = leaf_range(c).0;
                starts[s / 64].fetch_or(1 << (s % 64), Relaxed);
            }
        }
    });
    debug_assert!(
        n == 0 || starts[0].load(Relaxed) & 1 != 0,
        "the first item starts a leaf"
    );
    let word = |w: usize| starts.get(w).map_or(0, |x| x.load(Relaxed));
    // The first item of the leaf after the one starting at `s` (or `n`): a
    // leaf holds at most 16 items, so that is in this word or the next.
    let next = |s: usize| {
        let (w, b) = (s / 64, s % 64);
        let here = word(w) & (u64::MAX << b << 1);
        if here != 0 {
            return w * 64 + here.trailing_zeros() as usize;
        }
        let after = word(w + 1);
        if after != 0 {
            (w + 1) * 64 + after.trailing_zeros() as usize
        } else {
            n
        }
    };
    // The leaves starting in items `[from, to)` (`from` a multiple of
    // 64): (first item, items).
    let leaves = |from: usize, to: usize| {
        (from / 64..to.div_ceil(64))
            .flat_map(move |w| {
                let mut bits = word(w);
                std::iter::from_fn(move || {
                    (bits != 0).then(|| {
                        let s = w * 64 + bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        s
                    })
                })
            })
            .map(move |s| {
                let end = next(s);
                debug_assert!(end - s <= MAX_LEAF_ITEMS);
                (s, end - s)
            })
    };
    // Blocks of the leaves starting in each chunk of items, and where each
    // chunk's blocks start (leaves in item order).
    const CHUNK: usize = 16 * 1024;
    let chunk_blocks: Vec<usize> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            leaves(c * CHUNK, ((c + 1) * CHUNK).min(n))
                .map(|(_, k)| k.div_ceil(4))
                .sum()
        })
        .collect();
    let total: usize = chunk_blocks.iter().sum();
    // Each leaf's reference to its blocks, at its first item; every
    // block's items (first and count: [`block_word`]), filled chunk by
    // chunk into their own slices.
    let mut block_items: Vec<u32> = vec![0; total];
    let mut pieces = Vec::with_capacity(chunk_blocks.len());
    let mut rest = &mut block_items[..];
    let mut first = 0;
    for &k in &chunk_blocks {
        let (mine, tail) = rest.split_at_mut(k);
        pieces.push((first, mine));
        rest = tail;
        first += k;
    }
    refs.par_chunks_mut(CHUNK).zip(pieces).enumerate().for_each(
        |(c, (refs_out, (first, blocks_out)))| {
            let mut b = 0;
            for (s, k) in leaves(c * CHUNK, ((c + 1) * CHUNK).min(n)) {
                let nb = k.div_ceil(4);
                refs_out[s - c * CHUNK].set_note(leaf(first + b, nb));
                for (j, out) in blocks_out[b..b + nb].iter_mut().enumerate() {
                    *out = block_word(s + 4 * j, (k - 4 * j).min(4));
                }
                b += nb;
            }
        },
    );
    let refs = &*refs;
    nodes.par_iter_mut().for_each(|n| {
        for c in &mut n.child {
            if is_leaf(*c) && *c != EMPTY {
                *c = refs[leaf_range(*c).0].note();
            }
        }
    });
    let mut tris = Vec::with_capacity(block_items.len());
    huge_pages(&tris);
    let items = |at: u32| {
        let (s, k) = block_range(at);
        &refs[s..s + k]
    };
    tris.par_extend(
        block_items
            .par_iter()
            .enumerate()
            .with_min_len(1024)
            .map(|(b, &at)| {
                // The vertices are a gather from the source: ask for those
                // of a block further on (misses overlap instead of queueing).
                if let Some(&ahead) = block_items.get(b + PREFETCH_BLOCKS) {
                    for r in items(ahead) {
                        src.prefetch(r.id());
                    }
                }
                block(items(at), src)
            }),
    );
    tris
}

/// The items of a block, `k` (1 to 4) from item `s`, in a word.
fn block_word(s: usize, k: usize) -> u32 {
    debug_assert!(s < 1 << 28 && (1..=4).contains(&k));
    (s as u32) << 2 | (k as u32 - 1)
}

/// The `(first item, count)` of a [`block_word`].
fn block_range(w: u32) -> (usize, usize) {
    ((w >> 2) as usize, (w & 3) as usize + 1)
}

/// How many blocks ahead `fill_leaves` asks for vertices.
const PREFETCH_BLOCKS: usize = 8;

/// One block of up to four items.
fn block<S: Source>(items: &[PrimRef], src: &S) -> Tri4 {
    let mut b = Tri4::EMPTY;
    for (lane, r) in items.iter().enumerate() {
        let id = r.id();
        if r.other() {
            b.ids[lane] = id | OTHER;
            continue;
        }
        b.ids[lane] = id;
        for (k, p) in src.vertices(id).iter().enumerate() {
            for a in 0..3 {
                b.v[k][a][lane] = p[a];
            }
        }
    }
    b
}

#[cfg(test)]
#[path = "build_tests.rs"]
mod tests;
