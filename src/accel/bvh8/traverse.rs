//! Closest-hit and any-hit traversal: per-ray constants computed once, eight
//! boxes per node step, nearest child first, blocks of four triangles per leaf.

use super::lanes::{Lanes, W};
use super::node::{is_leaf, leaf_range, prefetch, Node, Tri4, EMPTY, NO_ITEM, OTHER};
use crate::math::{Ray, Vec3};
use crate::shape::{intersect_triangle, RaySpace4, WatertightRay, WatertightRay4};
use crate::stats::TraversalStats;
use glam::Vec4;

/// Entries of the traversal stack for any tree: at most `W − 1` pending per
/// inner level and `build::MAX_DEPTH` levels (exact: see the test
/// `a_worst_case_tree_fills_the_deep_stack`).
pub(crate) const DEEP: usize = (W - 1) * super::build::MAX_DEPTH;
/// Entries of the stack for trees at most [`SHALLOW_DEPTH`] deep, the usual
/// case (the deep stack's zeroing, 1 KB per ray, was 6% of a render's
/// time).
pub(crate) const SHALLOW: usize = 64;
/// The deepest tree the [`SHALLOW`] stack serves.
pub(crate) const SHALLOW_DEPTH: usize = (SHALLOW - 1) / (W - 1);

/// How items that are not triangles are tested (the world's spheres and
/// transformed shapes); a mesh has none.
pub trait Fallback {
    /// Whether the tree holds triangles only (then a leaf block's ids are
    /// never looked through for other items: a mesh's walk skips that
    /// check at compile time).
    const TRIANGLES_ONLY: bool = false;

    /// The hit parameter of item `id` in `(tmin, tmax)`.
    fn intersect(&self, id: u32, ray: &Ray, tmin: f32, tmax: f32) -> Option<f32>;
}

/// No items but triangles.
pub struct TrianglesOnly;

impl Fallback for TrianglesOnly {
    const TRIANGLES_ONLY: bool = true;

    #[inline]
    fn intersect(&self, _: u32, _: &Ray, _: f32, _: f32) -> Option<f32> {
        None
    }
}

/// The tree a walk runs through: its nodes and leaf blocks, how items that
/// are not triangles are tested, and which stack its depth needs. What
/// every walk (single ray or packet, closest or any hit) takes along.
pub(crate) struct Tree<'a, F: ?Sized> {
    pub nodes: &'a [Node],
    pub tris: &'a [Tri4],
    pub fallback: &'a F,
    /// Deeper than [`SHALLOW_DEPTH`]: walks take the [`DEEP`] stack.
    pub deep: bool,
}

impl<F: ?Sized> Clone for Tree<'_, F> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<F: ?Sized> Copy for Tree<'_, F> {}

impl<'a, F: Fallback + ?Sized> Tree<'a, F> {
    /// Inner node `c`, counted in `n_nodes` when `S` keeps statistics.
    #[inline(always)]
    pub(crate) fn node<S: TraversalStats>(&self, c: u32, n_nodes: &mut u64) -> &'a Node {
        if S::ENABLED {
            *n_nodes += 1;
        }
        &self.nodes[c as usize]
    }

    /// The blocks of leaf `c`.
    #[inline(always)]
    pub(crate) fn leaf(&self, c: u32) -> &'a [Tri4] {
        let (start, count) = leaf_range(c);
        &self.tris[start..start + count]
    }

    /// Starts loading child `c` (a node or its leaf's first block): a node
    /// with several children hit prefetches each as it pushes or sorts it,
    /// so that the nearest one's load and the others' overlap (one pass
    /// over the mask: a separate prefetch pass cost the any-hit walk 7%
    /// more instructions).
    #[inline(always)]
    pub(crate) fn prefetch_child(&self, c: u32) {
        if !is_leaf(c) {
            if let Some(n) = self.nodes.get(c as usize) {
                prefetch(n);
            }
        } else if let Some(b) = self.tris.get(leaf_range(c).0) {
            prefetch(b);
        }
    }

    /// Leaf `c` for a closest-hit walk: each block's triangles (in `(tmin,
    /// test_tmax]`), then its other items, each kept by
    /// [`Nearest::closer`]. Returns the items tested (0 unless
    /// `S::ENABLED`).
    #[inline(always)]
    pub(crate) fn nearest_in_leaf<S: TraversalStats, B: BoxTest>(
        &self,
        bt: B,
        c: u32,
        lr: &LeafRay,
        tmin: f32,
        near: &mut Nearest,
    ) -> u64 {
        let mut tests = 0;
        let blocks = self.leaf(c);
        // The first block was asked for with the leaf (or is being loaded
        // now); the others are asked for at once, so that their loads
        // overlap the first block's test instead of following it (on
        // meshes larger than the cache, the blocks' loads are a quarter of
        // the incoherent walk's time). Not in the any-hit walk, which stops
        // at the first block that blocks: measured, no gain there.
        for b in blocks.iter().skip(1) {
            prefetch(b);
        }
        for b in blocks {
            if S::ENABLED {
                tests += b.items();
            }
            let (mut mask, t, bary) = lr.triangles(bt, b, tmin, near.test_tmax(), NO_ITEM);
            while mask != 0 {
                let i = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                near.offer(t[i], b.ids[i], Some([bary[0][i], bary[1][i], bary[2][i]]));
            }
            if !F::TRIANGLES_ONLY && b.has_other() {
                for id in b.others() {
                    if let Some(t) = self.fallback.intersect(id, lr.ray, tmin, near.test_tmax()) {
                        near.offer(t, id, None);
                    }
                }
            }
        }
        tests
    }

    /// Leaf `c` for an any-hit walk: whether an item but `skip` lies on the
    /// ray in `(tmin, tmax)`, stopping at the first block that holds one;
    /// and the items tested up to there (0 unless `S::ENABLED`).
    #[inline(always)]
    pub(crate) fn blocked_in_leaf<S: TraversalStats, B: BoxTest>(
        &self,
        bt: B,
        c: u32,
        lr: &LeafRay,
        (tmin, tmax): (f32, f32),
        skip: u32,
    ) -> (bool, u64) {
        let mut tests = 0;
        for b in self.leaf(c) {
            if S::ENABLED {
                tests += b.items();
            }
            if lr.triangles(bt, b, tmin, tmax, skip).0 != 0
                || (!F::TRIANGLES_ONLY
                    && b.has_other()
                    && b.others()
                        .any(|id| self.fallback.intersect(id, lr.ray, tmin, tmax).is_some()))
            {
                return (true, tests);
            }
        }
        (false, tests)
    }
}

/// Everything a ray needs at every node, computed once per ray (what it
/// needs at leaves is a [`LeafRay`]).
pub(crate) struct RayData {
    pub ray: Ray,
    /// `origin · inv` per axis, splatted: a slab distance is then one fused
    /// multiply-subtract, `plane · inv − origin · inv`.
    pub(crate) oi: [Lanes; 3],
    /// `1 / dir` per axis, splatted, with tiny components clamped (see
    /// [`safe_inverse`]).
    pub(crate) inv: [Lanes; 3],
    /// Bit `a` set where the ray runs towards −axis `a` (see
    /// [`octant`](Self::octant)); it picks the near and far planes (see
    /// [`planes`](Self::planes)).
    octant: usize,
    /// Whether every `origin · inv` is finite: then no slab distance is
    /// NaN (see [`reduce_as_ints`](Self::reduce_as_ints)).
    finite: bool,
}

/// An entry of a walk's stack of pending children. The stacks are arrays
/// on the machine stack made once per query, and as plain arrays they had
/// to be zeroed first: 512 bytes for a closest-hit walk's 64 entries,
/// sixteen 32-byte stores a ray (1-4% of bunny40k's single-ray throughput,
/// `examples/packet_rays`). Slots are written only by the pushes, each at
/// the stack pointer, which then moves past it (the sorted push writes
/// eight slots from the pointer and moves it by fewer); every read is of a
/// slot below the pointer, after a decrement, so it was written by a push
/// and nothing has written it since but another push. That is the proof
/// each `assume_init` points to, here and in the packet walks.
pub(crate) type Slot<T> = std::mem::MaybeUninit<T>;

/// The octant parameter of [`closest`] and [`any`] that reads the ray's
/// planes from [`RayData`] at run time (`0..8` fixes them at compile time).
pub(crate) const ANY_OCTANT: usize = 8;

/// The octant parameter of [`closest`] that walks each descent (the node
/// steps from a popped child down to a leaf) with the copy of the node loop
/// for the ray's octant, picked at run time: for coherent rays (see
/// `Query::coherent`), whose octant the jump's predictor has seen before.
pub(crate) const BY_OCTANT: usize = 9;

/// What a ray needs at leaves: the watertight test's permutation and shear,
/// and the same splatted for the four-lane pre-test. Made at the first leaf
/// a ray reaches: many rays (shadow rays from the floor, camera rays past
/// the mesh) never reach one.
pub(crate) struct LeafRay<'r> {
    /// The ray itself (for the fallback's items), by reference: a copy
    /// made every query's `Option<LeafRay>` larger to set up.
    ray: &'r Ray,
    wt: WatertightRay,
    w4: WatertightRay4,
}

/// `1 / d` per axis, with every component of magnitude below `1e-18` taken
/// as `±1e-18` (its sign kept), as Embree's `rcp_safe` does: a zero
/// component's `±inf` would make `plane · inv − origin · inv` an `inf − inf`
/// NaN, which keeps the box (conservative, but a ray parallel to an axis,
/// as every ray of an orthographic camera is, would then cull nothing on
/// that axis).
///
/// Still conservative: a clamped ray's slab for that axis is the one of a
/// ray drifting at most `2e-18 · t` from the true one, so a box it rejects
/// holds no point of the true ray closer than `t = margin / 2e-18`, with
/// `margin` (`overlap::margin`, `1e-5` of the scene's magnitude) the padding
/// every box has: `5·10¹²` scene sizes for a unit direction.
///
/// A NaN component also becomes `±1e-18` (`max` returns its second
/// operand when the first is NaN): the box test then culls as for that
/// finite direction, and the triangle test, which sees the NaN, hits
/// nothing, as brute force does.
///
/// Branch-free, and the clamp before the division: its result starts every
/// ray's first box test, and a clamp of the quotient (or one relative to
/// the largest component) measured 5% slower on the benchmark's rays.
#[inline(always)]
fn safe_inverse(d: Vec3) -> Vec3 {
    let d = glam::Vec3A::from(d);
    let tiny = glam::Vec3A::splat(1e-18);
    Vec3::from(glam::Vec3A::ONE / d.abs().max(tiny).copysign(d))
}

impl RayData {
    /// A ray's `1 / dir` (clamped, see [`safe_inverse`]) and `origin ·
    /// inv`, the values [`new`](Self::new) splats.
    #[inline(always)]
    pub(crate) fn inv_oi(ray: &Ray) -> (Vec3, Vec3) {
        let inv = safe_inverse(ray.dir);
        (inv, ray.origin * inv)
    }

    /// [`inv_oi`](Self::inv_oi) of eight rays at once, one lane per ray
    /// (`d` and `o` their directions' and origins' components per axis):
    /// the same operations ([`safe_inverse`]'s `abs`, `maxps`, `copysign`
    /// and division, then the product) on four lanes at a time, so the
    /// same values.
    #[inline(always)]
    pub(crate) fn inv_oi_lanes(d: Lanes, o: Lanes) -> (Lanes, Lanes) {
        let tiny = Vec4::splat(1e-18);
        let inv = |d: Vec4| Vec4::ONE / d.abs().max(tiny).copysign(d);
        let inv = Lanes([inv(d.0[0]), inv(d.0[1])]);
        (inv, Lanes([o.0[0] * inv.0[0], o.0[1] * inv.0[1]]))
    }

    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let (inv, oi) = Self::inv_oi(ray);
        // The sign bit of `1 / d`: set for `d < 0`, for `d = −0` (`−∞`) and
        // for `d = −∞` (`−0`), as `inv < 0 || (inv == 0 && d < 0)` was; a NaN
        // direction makes every slab NaN, whichever plane is near.
        let neg = |a: usize| usize::from(inv[a].is_sign_negative());
        RayData {
            ray: *ray,
            oi: [Lanes::splat(oi.x), Lanes::splat(oi.y), Lanes::splat(oi.z)],
            inv: [
                Lanes::splat(inv.x),
                Lanes::splat(inv.y),
                Lanes::splat(inv.z),
            ],
            octant: neg(0) | neg(1) << 1 | neg(2) << 2,
            finite: oi.is_finite(),
        }
    }

    /// Whether [`boxes`](Self::boxes) may reduce a query's slab distances
    /// with integer operations: `tmin` is `+0` or more (not NaN, not `−0`)
    /// and no slab distance can be NaN. A slab distance `plane · inv −
    /// origin · inv` is NaN only if `origin · inv` is not finite: `inv` is
    /// finite and non-zero for a finite direction (clamped, see
    /// [`safe_inverse`], which also turns a NaN component finite), planes
    /// are finite or `±inf` (an empty slot), and a finite `origin · inv`
    /// subtracted from a finite or infinite product is never NaN. Such rays
    /// (an origin beyond about `1e20` or NaN) and negative `tmin` take the
    /// float reduction.
    #[inline(always)]
    pub fn reduce_as_ints(&self, tmin: f32) -> bool {
        self.finite && tmin >= 0.0 && tmin.is_sign_positive()
    }

    /// The ray's octant, `0..8`: the `O` for which [`closest`] and [`any`]
    /// know its near and far planes at compile time.
    #[inline(always)]
    pub fn octant(&self) -> usize {
        self.octant
    }

    /// Indices into `Node::planes` of the near and far plane per axis: from
    /// `O` when it is an octant (constant offsets: the node step then loads
    /// each plane straight from the node, with no index to reload), else
    /// from the ray's octant bits. Derived from the bits, not stored: an
    /// index read back from memory has to be bounds-checked, and the
    /// closest-hit walk reloaded and re-checked all six after every leaf
    /// (callgrind, scene6_07: some 20 instructions a leaf); these are
    /// below 6 by construction.
    #[inline(always)]
    fn planes<const O: usize>(&self) -> ([usize; 3], [usize; 3]) {
        let o = if O < ANY_OCTANT {
            debug_assert_eq!(O, self.octant);
            O
        } else {
            self.octant
        };
        let s = |a: usize| (o >> a) & 1;
        (
            [3 * s(0), 1 + 3 * s(1), 2 + 3 * s(2)],
            [3 - 3 * s(0), 4 - 3 * s(1), 5 - 3 * s(2)],
        )
    }

    /// The slab test against a node's eight boxes: a bit mask of the boxes
    /// the ray meets within `[tmin, tmax]`, and their entry distances.
    ///
    /// Each slab distance is one fused multiply-subtract, `plane · inv −
    /// origin · inv` (Embree's form): one rounding of the exact product
    /// minus the rounded `origin · inv`, an error of a few ulps of the
    /// larger of `plane` and `origin` along the axis, as `(plane − origin) ·
    /// inv` had; the boxes' padding (`overlap::margin`, about 80 ulps of the
    /// scene's magnitude) absorbs it.
    ///
    /// The four distances per side are reduced as a tree, `max(max(x, y),
    /// max(z, tmin))`, not a chain: one dependent operation fewer in the
    /// walk's critical path from a node's load to its children's mask.
    ///
    /// With `I` ([`reduce_as_ints`](Self::reduce_as_ints)), the
    /// reduction and the final `tn <= tf` compare the f32 bit patterns as
    /// `i32` (Embree's AVX-512 traversal does the same): one-cycle integer
    /// operations in place of four-cycle float ones on that critical path.
    /// Exact, because `tmin ≥ +0` sits in the `max` and no operand is NaN:
    /// the integer order is the float order among values with the sign bit
    /// clear, and every negative value (`−0` too) is below `+0`, so `tn` is
    /// the float maximum (a negative slab never wins against `tmin`); and
    /// where some far distance is negative, `tf` comes out negative (not
    /// necessarily the most negative), below `tn`: the box is rejected as
    /// the float test rejects it. The one difference is a far distance of
    /// exactly `−0`, which the float test keeps and this one rejects: the
    /// ray leaves that box at `t = 0`, where a hit (`t > tmin ≥ 0`) cannot
    /// be; the boxes' padding dwarfs the rounding of a distance that near.
    ///
    /// Without `I`, a NaN slab distance (an `inf − inf`) never rejects a
    /// box: `Lanes::max`/`min` return their second operand when either is
    /// NaN, a NaN slab is always a first operand, and a NaN result of the
    /// inner pair is again a first operand (`tmin` and `tmax` are never
    /// NaN), so such a slab is ignored.
    #[inline(always)]
    pub(crate) fn boxes<B: BoxTest, const O: usize, const I: bool>(
        &self,
        bt: B,
        n: &Node,
        tmin: Lanes,
        tmax: Lanes,
    ) -> (u32, Lanes) {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = bt.avx() {
            return self.boxes_avx::<O, I>(avx, n, tmin, tmax);
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = bt;
        let p = &n.planes;
        let (near, far) = self.planes::<O>();
        let tnx = p[near[0]].mul_sub(self.inv[0], self.oi[0]);
        let tny = p[near[1]].mul_sub(self.inv[1], self.oi[1]);
        let tnz = p[near[2]].mul_sub(self.inv[2], self.oi[2]);
        let tfx = p[far[0]].mul_sub(self.inv[0], self.oi[0]);
        let tfy = p[far[1]].mul_sub(self.inv[1], self.oi[1]);
        let tfz = p[far[2]].mul_sub(self.inv[2], self.oi[2]);
        if I {
            let tn = tnx.max_bits(tny).max_bits(tnz.max_bits(tmin));
            let tf = tfx.min_bits(tfy).min_bits(tfz.min_bits(tmax));
            return (tn.le_mask_bits(tf), tn);
        }
        let tn = tnx.max(tny).max(tnz.max(tmin));
        let tf = tfx.min(tfy).min(tfz.min(tmax));
        (tn.le_mask(tf), tn)
    }

    /// [`boxes`](Self::boxes) with 256-bit AVX operations: the same
    /// operations on the same operands in the same order (`vfmsub`, fused
    /// as `f32::mul_add` is; `vmaxps`/`vminps` in the same tree, whose NaN
    /// rule is `maxps`'s, and an ordered `<=` compare; or `vpmaxsd`/
    /// `vpminsd` and `vpcmpgtd`, the `i32` order of the portable
    /// `*_bits`), so the mask and the distances are bit-identical to the
    /// portable test.
    ///
    /// Deliberately no `#[target_feature]`: a function with one cannot be
    /// `#[inline(always)]`, and LLVM kept it out of line (a call per node).
    /// Without it, this body is inlined into `dispatch`'s AVX2 copy, and the
    /// `_mm256_*` intrinsics then inline into that AVX2 function.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn boxes_avx<const O: usize, const I: bool>(
        &self,
        _: Avx,
        n: &Node,
        tmin: Lanes,
        tmax: Lanes,
    ) -> (u32, Lanes) {
        use std::arch::x86_64::*;
        // SAFETY: an `Avx` value exists only where AVX2 (hence AVX) and FMA
        // were detected at run time (`Avx::new` is `unsafe` with that
        // contract, and its callers check `is_x86_feature_detected!` first),
        // so the AVX and FMA intrinsics run on a CPU that has them. `Lanes` is `repr(C)` of two
        // `Vec4`s: eight contiguous f32s (32 bytes), so the unaligned loads
        // read exactly one `Lanes` each, in bounds, and the transmute back
        // is between two 32-byte plain-float types.
        unsafe {
            let ld = |l: &Lanes| _mm256_loadu_ps(l as *const Lanes as *const f32);
            // The ray's splats are re-broadcast from their low four lanes,
            // not loaded whole: `RayData::new` writes each `Lanes` as two
            // 16-byte halves, and a 32-byte load of two separate stores
            // cannot be forwarded from them (it waits for both to reach the
            // cache, at every query). Same values, so the same results.
            let bc =
                |l: &Lanes| _mm256_broadcastss_ps(_mm_loadu_ps(l as *const Lanes as *const f32));
            let p = &n.planes;
            let (o, i) = (&self.oi, &self.inv);
            let t = |k: usize, a: usize| _mm256_fmsub_ps(ld(&p[k]), bc(&i[a]), bc(&o[a]));
            let (near, far) = self.planes::<O>();
            let tnx = t(near[0], 0);
            let tny = t(near[1], 1);
            let tnz = t(near[2], 2);
            let tfx = t(far[0], 0);
            let tfy = t(far[1], 1);
            let tfz = t(far[2], 2);
            if I {
                let i = |v: __m256| _mm256_castps_si256(v);
                let max = |a: __m256i, b: __m256i| _mm256_max_epi32(a, b);
                let min = |a: __m256i, b: __m256i| _mm256_min_epi32(a, b);
                let tn = max(max(i(tnx), i(tny)), max(i(tnz), i(ld(&tmin))));
                let tf = min(min(i(tfx), i(tfy)), min(i(tfz), i(ld(&tmax))));
                // `tn <= tf` is `!(tn > tf)`: AVX2 has only the latter.
                let out = _mm256_castsi256_ps(_mm256_cmpgt_epi32(tn, tf));
                let mask = !(_mm256_movemask_ps(out) as u32) & 0xff;
                return (mask, std::mem::transmute::<__m256i, Lanes>(tn));
            }
            let tn = _mm256_max_ps(_mm256_max_ps(tnx, tny), _mm256_max_ps(tnz, ld(&tmin)));
            let tf = _mm256_min_ps(_mm256_min_ps(tfx, tfy), _mm256_min_ps(tfz, ld(&tmax)));
            let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OS>(tn, tf)) as u32;
            (mask, std::mem::transmute::<__m256, Lanes>(tn))
        }
    }
}

impl<'r> LeafRay<'r> {
    #[inline(always)]
    pub(crate) fn new(ray: &'r Ray) -> Self {
        let wt = WatertightRay::new(ray);
        LeafRay {
            ray,
            wt,
            w4: WatertightRay4::new(&wt),
        }
    }

    /// The watertight test (`shape::triangle::intersect_triangle`) on the
    /// four lanes of a block: the mask of lanes hit in `(tmin, tmax)`, their
    /// parameters and barycentrics (`bary[k][lane]`). A 4-lane f32 pre-test
    /// (`RaySpace4::may_hit`) drops the lanes it proves missed; if any
    /// remain, the AVX copy runs the exact test on all four lanes at once
    /// (`shape::hit4_avx`), the portable one calls the very function brute
    /// force calls once per remaining lane: results are bit-identical either
    /// way. Unused and non-triangle lanes (NaN vertices) are skipped by
    /// their ids.
    ///
    /// Lanes holding item `skip` are not tested ([`NO_ITEM`] skips none:
    /// unused lanes are never tested anyway).
    ///
    /// The barycentrics of each lane hit come along too: the closest hit
    /// hands them to `Triangle::surface_at`, so the world need not re-run
    /// the test for them (the any-hit walk ignores them; they are dead code
    /// there once inlined).
    #[inline(always)]
    pub(crate) fn triangles<B: BoxTest>(
        &self,
        bt: B,
        b: &Tri4,
        tmin: f32,
        tmax: f32,
        skip: u32,
    ) -> (u32, [f32; 4], [[f32; 4]; 3]) {
        let rs = RaySpace4::new(&self.w4, &b.v);
        let mut todo = rs.may_hit() & triangle_lanes(b);
        // `NO_ITEM` lanes are not triangle lanes: nothing more to drop (and
        // where `skip` is that constant, no compare is compiled).
        if skip != NO_ITEM {
            todo &= !lanes_of(b, skip);
        }
        // Arrays, not a `Vec4`: a `Vec4` indexed by a run-time lane compiles
        // to a jump table.
        let mut t = [0.0; 4];
        let mut bary = [[0.0; 4]; 3];
        if todo == 0 {
            return (0, t, bary);
        }
        #[cfg(target_arch = "x86_64")]
        if bt.avx().is_some() {
            // SAFETY: an `Avx` token exists only where AVX2 (hence AVX) was
            // detected at run time (see `Avx::new`).
            let h = unsafe { crate::shape::hit4_avx(&self.w4, &rs, tmin, tmax) };
            return (h.mask & todo, h.t, h.b);
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = bt;
        let mut mask = 0;
        while todo != 0 {
            let lane = todo.trailing_zeros() as usize;
            todo &= todo - 1;
            let p = |k: usize| Vec3::new(b.v[k][0][lane], b.v[k][1][lane], b.v[k][2][lane]);
            if let Some(h) = intersect_triangle(&self.wt, p(0), p(1), p(2), tmin, tmax) {
                mask |= 1 << lane;
                t[lane] = h.t;
                for (k, w) in h.b.into_iter().enumerate() {
                    bary[k][lane] = w;
                }
            }
        }
        (mask, t, bary)
    }
}

/// Which box test the traversal uses: [`Portable`] (glam `Vec4` pairs) or,
/// on x86-64, [`Avx`] (one 256-bit operation per step). A value, so that
/// the AVX test needs a token only a run-time check can make.
pub(crate) trait BoxTest: Copy {
    /// The proof that AVX is available, for the AVX test.
    #[cfg(target_arch = "x86_64")]
    fn avx(self) -> Option<Avx>;
}

/// The portable box test.
#[derive(Clone, Copy)]
pub(crate) struct Portable;

impl BoxTest for Portable {
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn avx(self) -> Option<Avx> {
        None
    }
}

/// The AVX box test, and the proof that the CPU has AVX2 (so AVX) and FMA:
/// made only by the `unsafe` [`Avx::new`].
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy)]
pub(crate) struct Avx(());

#[cfg(target_arch = "x86_64")]
impl Avx {
    /// # Safety
    /// The CPU must support AVX2 and FMA (`is_x86_feature_detected!` of
    /// `"avx2"` and `"fma"`).
    #[inline(always)]
    pub(crate) unsafe fn new() -> Avx {
        Avx(())
    }
}

#[cfg(target_arch = "x86_64")]
impl BoxTest for Avx {
    #[inline(always)]
    fn avx(self) -> Option<Avx> {
        Some(self)
    }
}

/// The lanes of a block that hold triangles (not [`OTHER`] items, not unused:
/// [`NO_ITEM`] has the flag too).
#[inline(always)]
pub(crate) fn triangle_lanes(b: &Tri4) -> u32 {
    // Both flags are the id's top bit: the lanes whose id, read as an f32,
    // has its sign bit clear (one `movmskps`; no arithmetic on the bits).
    const _: () = assert!(OTHER == 1 << 31 && NO_ITEM & OTHER != 0);
    !Vec4::from_array(b.ids.map(f32::from_bits)).is_negative_bitmask() & 0xf
}

/// The lanes of a block whose id is `id`.
#[inline(always)]
fn lanes_of(b: &Tri4, id: u32) -> u32 {
    glam::UVec4::from_array(b.ids)
        .cmpeq(glam::UVec4::splat(id))
        .bitmask()
}

/// Pushes the children in `mask` (at least two) far to near and returns the
/// nearest, so that the nearest is visited first and the others are popped
/// in order of distance; starts loading each ([`Tree::prefetch_child`]).
/// Three or more in a walk with `I` take the sorted push of
/// [`order_keyed`].
#[inline(always)]
fn order<F: Fallback + ?Sized, B: BoxTest, const I: bool>(
    bt: B,
    tree: &Tree<F>,
    node: &Node,
    mut mask: u32,
    dist: Lanes,
    stack: &mut [Slot<(u32, f32)>],
    sp: &mut usize,
) -> u32 {
    // An array, not `Lanes` indexing: a `Vec4` indexed by a run-time lane
    // compiles to a jump table.
    let lanes = dist;
    let dist = dist.to_array();
    let second = mask & (mask - 1);
    if second & (second - 1) == 0 {
        // Exactly two, the usual case: one compare. The same order as the
        // sort below (on a tie the higher slot is visited first), so the
        // walk is the same.
        let (i, j) = (
            mask.trailing_zeros() as usize,
            second.trailing_zeros() as usize,
        );
        let (a, b) = ((node.child[i], dist[i]), (node.child[j], dist[j]));
        tree.prefetch_child(a.0);
        tree.prefetch_child(b.0);
        let (near, far) = if a.1 < b.1 { (a, b) } else { (b, a) };
        stack[*sp].write(far);
        *sp += 1;
        return near.0;
    }
    // (The sorted push writes eight entries: the insertion sort below where
    // the stack has no room for them, which no tree fills in practice.)
    if I && *sp + W <= stack.len() {
        return order_keyed(bt, tree, node, mask, lanes, stack, sp);
    }
    let mut kids = [(0u32, 0f32); W];
    let mut k = 0;
    while mask != 0 {
        let i = mask.trailing_zeros() as usize;
        mask &= mask - 1;
        let e = (node.child[i], dist[i]);
        tree.prefetch_child(e.0);
        insert_far_first(&mut kids, k, e, |e| e.1);
        k += 1;
    }
    for &e in &kids[..k - 1] {
        stack[*sp].write(e);
        *sp += 1;
    }
    kids[k - 1].0
}

/// [`order`] of three or more children whose entry distances are not
/// negative (a walk with `I`): each child's sort key is its distance's
/// bit pattern (ordered as the distance is) with the low three bits
/// replaced by `7 − slot`, so keys are distinct, ordered by distance down
/// to 8 ulps and, nearer than that, the higher slot first (as `order`'s
/// compare). The keys sorted far to near are pushed with the distance
/// they carry (at most 7 ulps short of the true one: a pending child is
/// dropped on a slightly stricter test, never one that could hold the
/// hit). On AVX2, a sorting network on the eight lanes and two 32-byte
/// stores: no branch per child, where the insertion sort took a
/// data-dependent branch per child placed.
#[inline(always)]
fn order_keyed<F: Fallback + ?Sized, B: BoxTest>(
    bt: B,
    tree: &Tree<F>,
    node: &Node,
    mask: u32,
    dist: Lanes,
    stack: &mut [Slot<(u32, f32)>],
    sp: &mut usize,
) -> u32 {
    let k = mask.count_ones() as usize;
    let mut m = mask;
    while m != 0 {
        tree.prefetch_child(node.child[m.trailing_zeros() as usize]);
        m &= m - 1;
    }
    #[cfg(target_arch = "x86_64")]
    if let Some(avx) = bt.avx() {
        return order_keyed_avx(avx, node, mask, k, dist, stack, sp);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = bt;
    let dist = dist.to_array();
    let mut keys = [i32::MIN; W];
    for (i, key) in keys.iter_mut().enumerate() {
        if mask >> i & 1 != 0 {
            *key = (dist[i].to_bits() & !7 | (7 - i as u32)) as i32;
        }
    }
    keys.sort_unstable_by(|a, b| b.cmp(a));
    let entry = |key: i32| {
        let key = key as u32;
        (node.child[7 - (key & 7) as usize], f32::from_bits(key & !7))
    };
    let out = &mut stack[*sp..*sp + W];
    for (o, &key) in out.iter_mut().zip(&keys[..k]) {
        o.write(entry(key));
    }
    *sp += k - 1;
    entry(keys[k - 1]).0
}

/// [`order_keyed`] on AVX2: the keys of the eight lanes (`i32::MIN` for
/// the children missed) sorted by a bitonic network of `vpmaxsd`/`vpminsd`
/// (six stages), the children gathered by their slots (`vpermd`), and the
/// eight (child, distance) pairs stored at the top of the stack, of which
/// the first `k` are the children hit, far to near.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn order_keyed_avx(
    _: Avx,
    node: &Node,
    mask: u32,
    k: usize,
    dist: Lanes,
    stack: &mut [Slot<(u32, f32)>],
    sp: &mut usize,
) -> u32 {
    use std::arch::x86_64::*;
    let out = &mut stack[*sp..*sp + W];
    // SAFETY: an `Avx` value exists only where AVX2 was detected at run
    // time (see `Avx::new`). `Lanes` is eight contiguous f32s and
    // `node.child` eight u32s (32 bytes each), read by unaligned loads in
    // bounds; `out` is eight (u32, f32) slots (`MaybeUninit` has the
    // layout of what it holds), 64 bytes, written by two unaligned 32-byte
    // stores in bounds (child at offset 0 and distance at 4 in each pair:
    // asserted at compile time below). Both stores write all eight slots,
    // so the `k − 1` the stack grows by are written.
    unsafe {
        let d = _mm256_loadu_si256(&dist as *const Lanes as *const __m256i);
        let slot = _mm256_setr_epi32(7, 6, 5, 4, 3, 2, 1, 0);
        // All ones in the lanes of the children hit.
        let hit = _mm256_cmpgt_epi32(
            _mm256_and_si256(
                _mm256_set1_epi32(mask as i32),
                _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128),
            ),
            _mm256_setzero_si256(),
        );
        let key = _mm256_or_si256(_mm256_andnot_si256(_mm256_set1_epi32(7), d), slot);
        let key = _mm256_blendv_epi8(_mm256_set1_epi32(i32::MIN), key, hit);
        // A compare-exchange stage: each lane against its partner `p`
        // (lane `i ^ j`), the larger key kept in the lanes of `MAX`. Six
        // stages (partners 1; 2, 1; 4, 2, 1) sort the eight lanes, largest
        // first.
        macro_rules! stage {
            ($v:expr, $p:expr, $max:literal) => {{
                let (v, p) = ($v, $p);
                _mm256_blend_epi32::<$max>(_mm256_min_epi32(v, p), _mm256_max_epi32(v, p))
            }};
        }
        let x1 = |v| _mm256_shuffle_epi32::<0b1011_0001>(v);
        let x2 = |v| _mm256_shuffle_epi32::<0b0100_1110>(v);
        let x4 = |v| _mm256_permute4x64_epi64::<0b0100_1110>(v);
        // The nearest child (the smallest key hit) by its own reduction,
        // beside the network: the walk goes on with it while the others
        // are sorted and stored.
        let near = _mm256_blendv_epi8(_mm256_set1_epi32(i32::MAX), key, hit);
        let near = _mm256_min_epi32(near, x1(near));
        let near = _mm256_min_epi32(near, x2(near));
        let near = _mm256_min_epi32(near, x4(near));
        let nearest = node.child[((_mm256_cvtsi256_si32(near) as u32 & 7) ^ 7) as usize];
        let v = stage!(key, x1(key), 0b1001_1001);
        let v = stage!(v, x2(v), 0b1100_0011);
        let v = stage!(v, x1(v), 0b1010_0101);
        let v = stage!(v, x4(v), 0b0000_1111);
        let v = stage!(v, x2(v), 0b0011_0011);
        let v = stage!(v, x1(v), 0b0101_0101);
        // Slot `7 − (key & 7)` is `key ^ 7` in the three bits `vpermd` reads.
        let child = _mm256_loadu_si256(node.child.as_ptr() as *const __m256i);
        let child = _mm256_permutevar8x32_epi32(child, _mm256_xor_si256(v, _mm256_set1_epi32(7)));
        let dist = _mm256_andnot_si256(_mm256_set1_epi32(7), v);
        let (lo, hi) = (
            _mm256_unpacklo_epi32(child, dist),
            _mm256_unpackhi_epi32(child, dist),
        );
        let p = out.as_mut_ptr() as *mut __m256i;
        _mm256_storeu_si256(p, _mm256_permute2x128_si256::<0x20>(lo, hi));
        _mm256_storeu_si256(p.add(1), _mm256_permute2x128_si256::<0x31>(lo, hi));
        *sp += k - 1;
        nearest
    }
}

// The entries' layout the AVX push writes: child, then distance.
const _: () =
    assert!(std::mem::offset_of!((u32, f32), 0) == 0 && std::mem::offset_of!((u32, f32), 1) == 4);

/// Inserts `e` into `kids[..k]` (one step of an insertion sort), kept far
/// to near by `dist`; `e` goes after (nearer than) the entries as far as
/// it.
#[inline(always)]
pub(crate) fn insert_far_first<T: Copy>(kids: &mut [T], k: usize, e: T, dist: impl Fn(&T) -> f32) {
    let mut j = k;
    while j > 0 && dist(&kids[j - 1]) < dist(&e) {
        kids[j] = kids[j - 1];
        j -= 1;
    }
    kids[j] = e;
}

/// The closest hit of a traversal: its parameter, its item id, and, for a
/// triangle, the watertight test's barycentrics (`None` for an item the
/// fallback tested).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Closest {
    pub t: f32,
    pub id: u32,
    pub bary: Option<[f32; 3]>,
}

/// A closest-hit walk's best hit so far and the upper end of its range,
/// which shrinks to that hit's `t`.
pub(crate) struct Nearest {
    pub tmax: f32,
    pub best: Option<Closest>,
}

impl Nearest {
    /// The upper end of the range a leaf tests once `best` is found: `tmax`
    /// itself (`best` is the closest so far, at `tmax`) taken inclusively,
    /// so that a hit at exactly the same `t` is seen and
    /// [`closer`](Self::closer) can break the tie. Hits are at `t > tmin ≥
    /// −∞` and finite, and the next float above a finite `t` is the bit
    /// pattern one up for `t > 0` (`+inf` above the largest finite value);
    /// for `t ≤ 0` (a negative `tmin`) one down on the magnitude, and the
    /// smallest positive value above `−0`: `f32::next_up` for a finite
    /// value, without its branches for NaN and infinities (it runs once
    /// per block tested).
    #[inline(always)]
    pub(crate) fn test_tmax(&self) -> f32 {
        if self.best.is_some() {
            let b = self.tmax.to_bits();
            f32::from_bits(if b as i32 >= 0 {
                b + 1
            } else if b == 1 << 31 {
                1
            } else {
                b - 1
            })
        } else {
            self.tmax
        }
    }

    /// Whether a hit `(t, id)` replaces `best` (at `tmax`): nearer, or as
    /// near with a smaller item id. The rule makes the closest hit a
    /// function of the ray and the set of items alone, not of the order the
    /// walk meets them in (brute force's order, by id, gives the same
    /// answer): a packet walk, which visits a ray's nodes in a different
    /// order than that ray's own walk, returns the very same hit.
    #[inline(always)]
    pub(crate) fn closer(&self, t: f32, id: u32) -> bool {
        match self.best {
            None => true,
            Some(b) => t < self.tmax || (t == self.tmax && id < b.id),
        }
    }

    /// Keeps hit `(t, id)` if it is [`closer`](Self::closer).
    #[inline(always)]
    pub(crate) fn offer(&mut self, t: f32, id: u32, bary: Option<[f32; 3]>) {
        if self.closer(t, id) {
            self.tmax = t;
            self.best = Some(Closest { t, id, bary });
        }
    }
}

/// The closest hit ([`Closest`]), with an `N`-entry stack ([`SHALLOW`]
/// or [`DEEP`] for the tree's depth). Always inlined, so that `dispatch`'s
/// AVX2 copy compiles it with AVX2.
#[inline(always)]
pub(crate) fn closest<
    S: TraversalStats,
    F: Fallback + ?Sized,
    B: BoxTest,
    const N: usize,
    const O: usize,
    const I: bool,
>(
    bt: B,
    tree: &Tree<F>,
    rd: &RayData,
    tmin: f32,
    tmax: f32,
    stats: &mut S,
) -> Option<Closest> {
    if tree.nodes.is_empty() {
        return None;
    }
    let (mut n_nodes, mut n_tests) = (0u64, 0u64);
    let mut near = Nearest { tmax, best: None };
    let tmin4 = Lanes::splat(tmin);
    debug_assert!(!I || rd.reduce_as_ints(tmin));
    let mut stack = [const { Slot::<(u32, f32)>::uninit() }; N];
    let mut sp = 0usize;
    // Made at the first leaf (see `LeafRay`).
    let mut leaf_ray = None;
    let mut cur = 0u32;
    let best = 'walk: loop {
        // Down through inner nodes to a leaf, in a loop of its own, the
        // leaf test and the pop after it. Measured against one loop for
        // both (with the branch-free dominant axis of `WatertightRay`):
        // 5-7% faster on incoherent and shadow rays (examples/packet_rays,
        // bunny40k), for the same instructions a node step (the register
        // allocator still reloads the ray's splats from the stack at each
        // step); which of the two changes gives how much was not isolated.
        if O == BY_OCTANT {
            if !is_leaf(cur) {
                let (s, tmax) = ((&mut stack[..], &mut sp), near.tmax);
                macro_rules! down {
                    ($($o:literal)*) => {
                        match rd.octant() {
                            $($o => descend::<S, F, B, $o, I>(bt, tree, rd, tmin4, tmax, cur, s, &mut n_nodes),)*
                            _ => descend::<S, F, B, 7, I>(bt, tree, rd, tmin4, tmax, cur, s, &mut n_nodes),
                        }
                    };
                }
                match down!(0 1 2 3 4 5 6) {
                    Some(c) => cur = c,
                    None => break 'walk near.best,
                }
            }
        } else {
            while !is_leaf(cur) {
                let node = tree.node::<S>(cur, &mut n_nodes);
                let (mask, dist) = rd.boxes::<_, O, I>(bt, node, tmin4, Lanes::splat(near.tmax));
                cur = if mask == 0 {
                    match pop_nearer(&stack, &mut sp, near.tmax) {
                        Some(c) => c,
                        None => break 'walk near.best,
                    }
                } else if mask & (mask - 1) == 0 {
                    node.child[mask.trailing_zeros() as usize]
                } else {
                    order::<F, B, I>(bt, tree, node, mask, dist, &mut stack, &mut sp)
                };
            }
        }
        if cur != EMPTY {
            let lr = &*leaf_ray.get_or_insert_with(|| LeafRay::new(&rd.ray));
            n_tests += tree.nearest_in_leaf::<S, _>(bt, cur, lr, tmin, &mut near);
        }
        match pop_nearer(&stack, &mut sp, near.tmax) {
            Some(c) => cur = c,
            None => break 'walk near.best,
        }
    };
    stats.add(n_nodes, n_tests);
    best
}

/// The node steps of a closest-hit walk from `cur` down to a leaf (or
/// [`EMPTY`]), pushing the other children hit; `None` when the ray leaves
/// the tree without reaching another leaf nearer than `tmax`. `tmax` is
/// the walk's current one: it changes only at leaves.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn descend<S: TraversalStats, F: Fallback + ?Sized, B: BoxTest, const O: usize, const I: bool>(
    bt: B,
    tree: &Tree<F>,
    rd: &RayData,
    tmin4: Lanes,
    tmax: f32,
    mut cur: u32,
    (stack, sp): (&mut [Slot<(u32, f32)>], &mut usize),
    n_nodes: &mut u64,
) -> Option<u32> {
    let tmax4 = Lanes::splat(tmax);
    while !is_leaf(cur) {
        let node = tree.node::<S>(cur, n_nodes);
        let (mask, dist) = rd.boxes::<_, O, I>(bt, node, tmin4, tmax4);
        cur = if mask == 0 {
            pop_nearer(stack, sp, tmax)?
        } else if mask & (mask - 1) == 0 {
            node.child[mask.trailing_zeros() as usize]
        } else {
            order::<F, B, I>(bt, tree, node, mask, dist, stack, sp)
        };
    }
    Some(cur)
}

/// Pops the nearest pending child of a closest-hit walk that can still hold
/// a hit at most `tmax` away (entries are pushed far to near, so the top is
/// the nearest); `None` once the stack holds no such child.
#[inline(always)]
fn pop_nearer(stack: &[Slot<(u32, f32)>], sp: &mut usize, tmax: f32) -> Option<u32> {
    while *sp > 0 {
        *sp -= 1;
        // SAFETY: the slots below the stack pointer are written (see
        // `Slot`), and this one is below the pointer as it was.
        let (r, d) = unsafe { stack[*sp].assume_init() };
        if d <= tmax {
            return Some(r);
        }
    }
    None
}

/// Whether anything but triangle `skip` lies on the ray in `(tmin, tmax)`:
/// stops at the first hit. `skip` is a triangle the caller knows cannot
/// block the ray (the one it leaves; [`NO_ITEM`] for none): its lanes are
/// not tested. Always inlined (see [`closest`]).
#[inline(always)]
pub(crate) fn any<
    S: TraversalStats,
    F: Fallback + ?Sized,
    B: BoxTest,
    const N: usize,
    const O: usize,
    const I: bool,
>(
    bt: B,
    tree: &Tree<F>,
    rd: &RayData,
    (tmin, tmax): (f32, f32),
    skip: u32,
    stats: &mut S,
) -> bool {
    if tree.nodes.is_empty() {
        return false;
    }
    let (mut n_nodes, mut n_tests) = (0u64, 0u64);
    let (tmin4, tmax4) = (Lanes::splat(tmin), Lanes::splat(tmax));
    debug_assert!(!I || rd.reduce_as_ints(tmin));
    let mut stack = [const { Slot::<u32>::uninit() }; N];
    let mut sp = 0usize;
    // Made at the first leaf (see `LeafRay`).
    let mut leaf_ray = None;
    let mut cur = 0u32;
    let hit = 'walk: loop {
        // Down to a leaf in a loop of its own (see `closest`).
        while !is_leaf(cur) {
            let node = tree.node::<S>(cur, &mut n_nodes);
            // No sort by distance: any occluder ends the walk, and
            // sorting costs more than it saves for shadow rays.
            let (mut mask, _) = rd.boxes::<_, O, I>(bt, node, tmin4, tmax4);
            if mask == 0 {
                if sp == 0 {
                    break 'walk false;
                }
                sp -= 1;
                // SAFETY: below the stack pointer (see `Slot`).
                cur = unsafe { stack[sp].assume_init() };
                continue;
            }
            // The far side of the node's first division first: its upper
            // slot where the ray runs towards +axis, else its lower one
            // (`Node::split`). A shadow ray leaving a surface skims the
            // boxes around its origin, and what blocks it lies further
            // on. On the anchors' shadow rays (`examples/packet_rays`,
            // `shadow1`) 1.05x on bunny40k and 1.14-1.17x on the spheres
            // against the lowest slot first; with the meshes and rays
            // mirrored through the origin 1.02x and 1.01x (the lowest slot
            // was the far side there already): the upper slot first
            // regardless of direction was 0.91x there.
            let first = node.far_slot(rd.octant(), mask);
            cur = node.child[first];
            mask &= !(1 << first);
            if mask != 0 {
                // Several children: start loading them all, pushing the
                // others in the same pass.
                tree.prefetch_child(cur);
                while mask != 0 {
                    let c = node.child[mask.trailing_zeros() as usize];
                    tree.prefetch_child(c);
                    stack[sp].write(c);
                    sp += 1;
                    mask &= mask - 1;
                }
            }
        }
        if cur != EMPTY {
            let lr = &*leaf_ray.get_or_insert_with(|| LeafRay::new(&rd.ray));
            let (blocked, tests) = tree.blocked_in_leaf::<S, _>(bt, cur, lr, (tmin, tmax), skip);
            n_tests += tests;
            if blocked {
                break 'walk true;
            }
        }
        if sp == 0 {
            break 'walk false;
        }
        sp -= 1;
        // SAFETY: below the stack pointer (see `Slot`).
        cur = unsafe { stack[sp].assume_init() };
    };
    stats.add(n_nodes, n_tests);
    hit
}

#[cfg(test)]
#[path = "traverse_tests.rs"]
pub(super) mod tests;
