//! Building the 8-wide BVH: binned SAH splits (in parallel for large nodes),
//! each node taking up to eight children by splitting its largest child
//! again, then the leaves' triangles copied into four-wide blocks.

use super::lanes::W;
use super::node::{is_leaf, leaf, leaf_range, Node, Tri4, EMPTY, MAX_LEAF_ITEMS, OTHER};
use super::pages::huge_pages;
use crate::accel::overlap::margin;
use crate::math::{Aabb, Vec3};
use glam::{Vec3A, Vec4};
use rayon::prelude::*;

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
/// On the 8-wide tree 0.3, 0.5, 0.8 and 1.2 once measured the same within
/// noise; with the host's memory slower, 1.0 with leaves of up
/// to 16 items gave incoherent rays 5-14% more (fewer node levels, each a
/// cache miss on a large mesh), primary and shadow rays the same, and 8-13%
/// fewer bytes per triangle.
const SPLIT_COST: f32 = 1.0;
/// Below this many items a node's subtrees are built on one thread.
const PARALLEL_ITEMS: usize = 16 * 1024;
/// Binning is split over threads above this many items.
const PARALLEL_BINNING: usize = 64 * 1024;
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
#[derive(Clone, Copy, Debug)]
enum Plan {
    /// Items whose centroid falls below bin `pos` (of `bins`) of `axis` go left.
    Bin {
        axis: usize,
        pos: usize,
        bins: usize,
    },
    /// Equal halves along the centroids' longest axis.
    Median { axis: usize },
}

/// The built tree (see `Bvh8`).
pub(crate) struct Built {
    pub nodes: Vec<Node>,
    pub tris: Vec<Tri4>,
    pub bounds: Aabb,
}

/// Builds the tree over every item of `src`.
pub(crate) fn build<S: Source>(src: &S) -> Built {
    let n = src.count();
    assert!(
        n < 1 << 28 && (0..n).all(|k| src.id(k) & OTHER == 0),
        "the fast BVH holds fewer than 2^28 primitives, with ids below 2^31 (got {n})"
    );
    // An indexed map writes straight into the vector (a filtering
    // collect would gather pieces and copy them); skipped items are
    // dropped afterwards in place.
    let mut refs: Vec<PrimRef> = Vec::with_capacity(n);
    huge_pages(&refs);
    refs.par_extend((0..n).into_par_iter().with_min_len(4096).map(|k| {
        let id = src.id(k);
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
        };
    }
    let builder = Builder {
        pad: Vec3::splat(margin(&bounds)),
    };
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
    }
    let tris = fill_leaves(&mut nodes, &refs, src);
    Built {
        nodes,
        tris,
        bounds,
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

struct Builder {
    pad: Vec3,
}

impl Builder {
    /// How to divide `r`, or `None` for a leaf.
    /// `items` are the range's references; `depth` is the node level the
    /// range's node would sit at.
    fn plan(&self, items: &[PrimRef], r: &Range, depth: usize) -> Option<Plan> {
        let n = r.len();
        if n <= 4 {
            return None;
        }
        let ce = r.cbounds.extent();
        let axis = if ce.x >= ce.y && ce.x >= ce.z {
            0
        } else if ce.y >= ce.z {
            1
        } else {
            2
        };
        if ce[axis] <= 0.0 {
            // Coincident centroids: no plane separates them.
            return (n > MAX_LEAF_ITEMS).then_some(Plan::Median { axis });
        }
        // Median splits at least quarter a range per level (two halvings of
        // the up to seven a node takes), so at most about log4(n) more
        // levels finish it: switch to them while that still
        // fits under MAX_DEPTH (only degenerate inputs ever get here).
        let levels_left = (usize::BITS - n.leading_zeros()) as usize / 2 + 2;
        if depth + levels_left >= MAX_DEPTH {
            return Some(Plan::Median { axis });
        }
        let best = if n < SMALL_RANGE {
            serial_sweep::<SMALL_BINS>(items, &r.cbounds, ce)
        } else if n < PARALLEL_BINNING {
            serial_sweep::<BINS>(items, &r.cbounds, ce)
        } else {
            sweep(&large_bins(items, &r.cbounds), n, ce)
        };
        let whole = r.bounds.surface_area();
        let split = SPLIT_COST * whole + best.0;
        if n <= MAX_LEAF_ITEMS && whole * blocks(n) <= split {
            return None;
        }
        if !best.0.is_finite() {
            return Some(Plan::Median { axis });
        }
        Some(Plan::Bin {
            axis: best.1,
            pos: best.2,
            bins: if n < SMALL_RANGE { SMALL_BINS } else { BINS },
        })
    }

    /// Divides `r` (its items are `refs`, which starts at `r.begin`) by
    /// `plan` into two non-empty ranges with their bounds.
    fn divide(&self, refs: &mut [PrimRef], r: &Range, plan: Plan) -> (Range, Range) {
        let (mid, (lb, lc), (rb, rc)) = match plan {
            Plan::Bin { axis, pos, bins } => {
                let map = BinMap::new(&r.cbounds);
                let (min, scale) = (map.min[axis], map.scale[axis] * bins as f32);
                // The same arithmetic as `BinMap::bins`, on one axis, without
                // the conversion: for `k ≥ 0` and `pos ≤ bins − 1`,
                // `trunc(min(k, bins − 1)) < pos` exactly when `k < pos`.
                // All three axes at once, the plan's picked from the mask.
                let (min, scale) = (Vec3A::splat(min), Vec3A::splat(scale));
                let pos = Vec3A::splat(pos as f32);
                partition(refs, |c| {
                    // NaN gives 0, as in `BinMap::bins`.
                    ((c - min) * scale).max(Vec3A::ZERO).cmplt(pos).bitmask() >> axis & 1 != 0
                })
            }
            Plan::Median { axis } => {
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

    fn set_child(&self, node: &mut Node, i: usize, c: u32, r: &Range) {
        node.set(i, c, r.bounds.min - self.pad, r.bounds.max + self.pad);
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
        let Some(plan) = plan else {
            return leaf(r.begin, 1);
        };
        // Up to W children: split the largest child that wants splitting.
        // (On the stack: a vector here was an allocation per node.)
        let mut all = [(r, None); W];
        let (a, b) = self.divide(refs_of(refs, &r, &r), &r, plan);
        let pa = self.plan(refs_of(refs, &r, &a), &a, depth + 1);
        let pb = self.plan(refs_of(refs, &r, &b), &b, depth + 1);
        (all[0], all[1]) = ((a, pa), (b, pb));
        let mut len = 2;
        while len < W {
            let pick = all[..len]
                .iter()
                .enumerate()
                .filter(|(_, k)| k.1.is_some())
                .max_by(|x, y| {
                    x.1 .0
                        .bounds
                        .surface_area()
                        .total_cmp(&y.1 .0.bounds.surface_area())
                })
                .map(|(i, _)| i);
            let Some(i) = pick else { break };
            let (k, p) = all[i];
            let (a, b) = self.divide(refs_of(refs, &r, &k), &k, p.expect("filtered"));
            let pa = self.plan(refs_of(refs, &r, &a), &a, depth + 1);
            let pb = self.plan(refs_of(refs, &r, &b), &b, depth + 1);
            // `a` and `b` take `k`'s place, in order.
            all.copy_within(i + 1..len, i + 2);
            (all[i], all[i + 1]) = ((a, pa), (b, pb));
            len += 1;
        }
        let kids = &all[..len];
        let at = out.len();
        out.push(Node::EMPTY);
        let mut node = Node::EMPTY;
        // (On one thread the parallel path would only add copies.)
        if r.len() >= PARALLEL_ITEMS && rayon::current_num_threads() > 1 {
            // Children in parallel, each into its own array, then appended
            // with their node indices shifted.
            let mut slices = Vec::with_capacity(W);
            let mut rest = &mut *refs;
            let mut base = r.begin;
            for (k, p) in kids {
                let (mine, tail) = rest.split_at_mut(k.end - base);
                slices.push((&mut mine[k.begin - base..], *k, *p));
                rest = tail;
                base = k.end;
            }
            let subs: Vec<(u32, Vec<Node>)> = slices
                .into_par_iter()
                .map(|(s, k, p)| {
                    let mut v = Vec::with_capacity(s.len() / 8 + 1);
                    let c = self.subtree(s, k, p, depth + 1, &mut v);
                    (c, v)
                })
                .collect();
            for (i, ((c, v), (k, _))) in subs.into_iter().zip(kids).enumerate() {
                let shift = out.len() as u32;
                let c = if is_leaf(c) { c } else { c + shift };
                out.extend(v.into_iter().map(|mut n| {
                    for ch in &mut n.child {
                        if !is_leaf(*ch) {
                            *ch += shift;
                        }
                    }
                    n
                }));
                self.set_child(&mut node, i, c, k);
            }
        } else {
            for (i, (k, p)) in kids.iter().enumerate() {
                let sub = refs_of(refs, &r, k);
                let c = self.subtree(sub, *k, *p, depth + 1, out);
                self.set_child(&mut node, i, c, k);
            }
        }
        out[at] = node;
        at as u32
    }
}

/// The items of `k` within `refs`, which holds the items of `r`.
fn refs_of<'a>(refs: &'a mut [PrimRef], r: &Range, k: &Range) -> &'a mut [PrimRef] {
    &mut refs[k.begin - r.begin..k.end - r.begin]
}

/// Bounds and centroid bounds, accumulated item by item.
struct Acc {
    lo: Vec3A,
    hi: Vec3A,
    clo: Vec3A,
    chi: Vec3A,
}

impl Acc {
    fn new() -> Self {
        Acc {
            lo: Vec3A::INFINITY,
            hi: Vec3A::NEG_INFINITY,
            clo: Vec3A::INFINITY,
            chi: Vec3A::NEG_INFINITY,
        }
    }

    #[inline(always)]
    fn add(&mut self, lo: Vec3A, hi: Vec3A, c: Vec3A) {
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
        self.clo = self.clo.min(c);
        self.chi = self.chi.max(c);
    }

    fn union(&self, o: &Acc) -> Acc {
        Acc {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
            clo: self.clo.min(o.clo),
            chi: self.chi.max(o.chi),
        }
    }

    fn boxes(&self) -> (Aabb, Aabb) {
        (
            Aabb::new(self.lo.into(), self.hi.into()),
            Aabb::new(self.clo.into(), self.chi.into()),
        )
    }
}

/// Ranges of up to this many items (in the cache) whose sides alternate
/// often are partitioned without a branch per item (see [`partition`]).
const BLOCK_PARTITION_MAX: usize = 8 * 1024;
/// The block of [`block_partition`].
const BLOCK: usize = 64;

/// Partition: items for which `left` holds first. Returns their count and
/// both sides' bounds and centroid bounds. Two ways to the same sides:
/// when the first 32 items change sides at least four times (an unordered
/// mesh, like a scan), a branch per item would often be mispredicted, and
/// [`block_partition`] has none (the bounds then take a second pass over
/// the cached range); otherwise (long runs, as in a mesh stored in order,
/// or a range too large for the cache) the in-place loop gathers the
/// bounds in the same pass. Measured (build, 1 thread): bunny40k 7-9%
/// faster, the spheres (stored in order) within 2%.
fn partition(
    v: &mut [PrimRef],
    left: impl Fn(Vec3A) -> bool,
) -> (usize, (Aabb, Aabb), (Aabb, Aabb)) {
    let n = v.len();
    if (2 * BLOCK..=BLOCK_PARTITION_MAX).contains(&n) && side_changes(&v[..BLOCK / 2], &left) >= 4 {
        let k = block_partition(v, &left);
        let acc = |s: &[PrimRef]| {
            let mut a = Acc::new();
            for p in s {
                a.add(p.lo(), p.hi(), p.centroid());
            }
            a.boxes()
        };
        return (k, acc(&v[..k]), acc(&v[k..]));
    }
    fused_partition(v, left)
}

/// How often consecutive items change sides.
fn side_changes(v: &[PrimRef], left: &impl Fn(Vec3A) -> bool) -> usize {
    let sides = v.iter().map(|p| left(p.centroid()));
    sides
        .clone()
        .zip(sides.skip(1))
        .filter(|(a, b)| a != b)
        .count()
}

/// In-place partition with the bounds gathered in the same pass (a second
/// pass over a large range costs as much as the partition).
fn fused_partition(
    v: &mut [PrimRef],
    left: impl Fn(Vec3A) -> bool,
) -> (usize, (Aabb, Aabb), (Aabb, Aabb)) {
    let (mut l, mut r) = (Acc::new(), Acc::new());
    // `v[..i]` go left, `v[j..]` right; each item is loaded once and its
    // centroid computed once (the swap writes the values held).
    let (mut i, mut j) = (0, v.len());
    loop {
        let (a, ca) = loop {
            if i == j {
                return (i, l.boxes(), r.boxes());
            }
            let (p, c) = (v[i], v[i].centroid());
            if !left(c) {
                break (p, c);
            }
            l.add(p.lo(), p.hi(), c);
            i += 1;
        };
        // `a` (at `i`) goes right: find one from the end that goes left.
        let (b, cb) = loop {
            j -= 1;
            if j == i {
                r.add(a.lo(), a.hi(), ca);
                return (i, l.boxes(), r.boxes());
            }
            let (p, c) = (v[j], v[j].centroid());
            if left(c) {
                break (p, c);
            }
            r.add(p.lo(), p.hi(), c);
        };
        v[i] = b;
        v[j] = a;
        l.add(b.lo(), b.hi(), cb);
        r.add(a.lo(), a.hi(), ca);
        i += 1;
    }
}

/// Partition without data-dependent branches in the scan (BlockQuicksort,
/// Edelkamp and Weiß 2016): the offsets of the misplaced items of a block
/// at each end, found by arithmetic, then swapped in pairs. Returns the
/// count on the left.
fn block_partition(v: &mut [PrimRef], left: &impl Fn(Vec3A) -> bool) -> usize {
    // `v[..lb]` go left, `v[re..]` right.
    let (mut lb, mut re) = (0, v.len());
    let (mut off_l, mut off_r) = ([0u8; BLOCK], [0u8; BLOCK]);
    let (mut start_l, mut num_l, mut start_r, mut num_r) = (0, 0, 0, 0);
    while re - lb >= 2 * BLOCK {
        if num_l == 0 {
            start_l = 0;
            for (k, p) in v[lb..lb + BLOCK].iter().enumerate() {
                off_l[num_l] = k as u8;
                num_l += !left(p.centroid()) as usize;
            }
        }
        if num_r == 0 {
            start_r = 0;
            for (k, p) in v[re - BLOCK..re].iter().rev().enumerate() {
                off_r[num_r] = k as u8;
                num_r += left(p.centroid()) as usize;
            }
        }
        let num = num_l.min(num_r);
        for t in 0..num {
            v.swap(
                lb + off_l[start_l + t] as usize,
                re - 1 - off_r[start_r + t] as usize,
            );
        }
        (num_l, num_r) = (num_l - num, num_r - num);
        (start_l, start_r) = (start_l + num, start_r + num);
        if num_l == 0 {
            lb += BLOCK;
        }
        if num_r == 0 {
            re -= BLOCK;
        }
    }
    // The rest (fewer than two blocks, one perhaps half done) item by item.
    let (mut i, mut j) = (lb, re);
    loop {
        while i < j && left(v[i].centroid()) {
            i += 1;
        }
        while i < j && !left(v[j - 1].centroid()) {
            j -= 1;
        }
        if i >= j {
            return i;
        }
        v.swap(i, j - 1);
        i += 1;
        j -= 1;
    }
}

/// Turns the leaves' item ranges into ranges of [`Tri4`] blocks and fills
/// the blocks (leaves in item order, so each leaf's blocks are contiguous).
fn fill_leaves<S: Source>(nodes: &mut [Node], refs: &[PrimRef], src: &S) -> Vec<Tri4> {
    // The leaves tile the items in order; until here a leaf's reference
    // holds only its first item. Mark those, then each leaf runs to the
    // next one's first item.
    let mut leaf_len = vec![0u8; refs.len()];
    for n in nodes.iter() {
        for &c in &n.child {
            if is_leaf(c) && c != EMPTY {
                leaf_len[leaf_range(c).0] = 1;
            }
        }
    }
    let mut end = refs.len();
    for s in (0..refs.len()).rev() {
        if leaf_len[s] != 0 {
            debug_assert!(end - s <= MAX_LEAF_ITEMS);
            leaf_len[s] = (end - s) as u8;
            end = s;
        }
    }
    debug_assert_eq!(end, 0, "the first item starts a leaf");
    // Leaves in item order with their first block, and every block's
    // items.
    let mut first_block = vec![0u32; refs.len()];
    let mut block_items: Vec<(u32, u8)> = Vec::with_capacity(refs.len() / 3);
    for (s, &k) in leaf_len.iter().enumerate() {
        if k > 0 {
            first_block[s] = block_items.len() as u32;
            for b in (0..k).step_by(4) {
                block_items.push((s as u32 + b as u32, (k - b).min(4)));
            }
        }
    }
    nodes.par_iter_mut().for_each(|n| {
        for c in &mut n.child {
            if is_leaf(*c) && *c != EMPTY {
                let s = leaf_range(*c).0;
                *c = leaf(first_block[s] as usize, (leaf_len[s] as usize).div_ceil(4));
            }
        }
    });
    let mut tris = Vec::with_capacity(block_items.len());
    huge_pages(&tris);
    let items = |(s, k): (u32, u8)| &refs[s as usize..s as usize + k as usize];
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
mod tests {
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
        let b = Builder { pad: Vec3::ZERO };
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
            let Some(Plan::Bin { axis, pos, bins }) = b.plan(&items, &rg, 0) else {
                continue;
            };
            assert_eq!(bins, if n < SMALL_RANGE { SMALL_BINS } else { BINS });
            let map = BinMap::new(&rg.cbounds);
            let bin = |p: &PrimRef, a: usize| {
                let k = (p.centroid()[a] - map.min[a]) * map.scale[a] * bins as f32;
                k.max(0.0).min((bins - 1) as f32) as usize
            };
            let cost = |a: usize, k: usize| -> Option<f32> {
                let (l, rt): (Vec<PrimRef>, Vec<PrimRef>) =
                    items.iter().partition(|p| bin(p, a) < k);
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
        let b = Builder { pad: Vec3::ZERO };
        let plan = |items: &[PrimRef], depth| b.plan(items, &range(items), depth);
        let pile = |n: usize| boxes(vec![Vec3::ONE; n], Vec3::splat(0.5));
        assert!(plan(
            &boxes([Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z], Vec3::splat(0.1)),
            0
        )
        .is_none());
        for n in [5, MAX_LEAF_ITEMS] {
            assert!(plan(&pile(n), 0).is_none(), "{n}");
        }
        for n in [MAX_LEAF_ITEMS + 1, 100] {
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
                matches!(plan(&items, deep), Some(Plan::Median { axis: a }) if a == axis),
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
        let b = Builder { pad: Vec3::ZERO };
        let mut r = Rng::new(43);
        let mut cuts = 0;
        for trial in 0..60 {
            let n = 9 + 2 * trial;
            let mut items = boxes((0..n).map(|_| r.v(0.0, 4.0)), Vec3::splat(0.1));
            let rg = range(&items);
            let Some(plan @ Plan::Bin { axis, pos, bins }) = b.plan(&items, &rg, 0) else {
                continue;
            };
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
        let b = Builder { pad: Vec3::ZERO };
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

    /// The parallel path (children of 16k items or more built on other
    /// threads) plans for the same levels as the serial one: started at
    /// level 12, where the median takes over within a few levels, it
    /// builds the one-thread build's nodes, in the same order.
    #[test]
    fn the_parallel_path_plans_for_the_same_levels() {
        let b = Builder { pad: Vec3::ZERO };
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
                    let (k, lb, rb) = partition(&mut v, |c| c.x < cut);
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
}
