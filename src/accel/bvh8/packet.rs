//! Packets: up to eight rays walked through the tree together, for rays
//! that go the same way (a tile's camera rays, shadow rays towards one
//! light). Per node, one box test for the whole packet ([`Frustum`]: slab
//! bounds from the extremes of the rays' `1 / dir` and `origin · inv`,
//! which keep every box any ray's own test keeps); per leaf's box, each
//! ray's own test; per leaf, each ray's own triangle test
//! (`Tree::nearest_in_leaf`). What the packet saves is the node work: one
//! box test and one ordering a node for all its rays.
//!
//! Same hits as single rays, bit for bit: a ray's closest hit is the
//! nearest of the items in the leaves it tests, which hold every item the
//! ray meets in its range, the tie between two items at the same `t` going
//! to the smaller id (`Nearest::closer`), whatever the order of the
//! visit; an any-hit answer is a yes or a no.
//!
//! Packets whose rays do not share an octant or whose directions spread
//! too far for tight bounds ([`MAX_SPREAD`]), and rays the single walk
//! would take off the integer reduction (`RayData::reduce_as_ints`: a
//! negative `tmin`, an origin far out), are walked one ray at a time.

use super::lanes::{Lanes, W};
use super::node::{is_leaf, Node, EMPTY, NO_ITEM};
use super::traverse::{
    self, insert_far_first, BoxTest, Closest, Fallback, LeafRay, Nearest, RayData, Slot, Tree,
    ANY_OCTANT,
};
#[cfg(target_arch = "x86_64")]
use super::traverse::{triangle_lanes, Avx};
use crate::math::Ray;
use crate::shape::F8;
#[cfg(target_arch = "x86_64")]
use crate::shape::{hit8_avx, WatertightRay, WatertightRay8};
use crate::stats::TraversalStats;
use glam::Vec4;

/// Most rays in a packet.
pub const PACKET: usize = 8;

/// The largest spread of a packet's `1 / d` along an axis, relative to
/// its smallest magnitude, that the packet walk takes (see
/// [`Frustum::new`]).
const MAX_SPREAD: f32 = 0.125;

/// One ray of a packet: the ray and its `(tmin, tmax)` range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PacketRay {
    /// The ray.
    pub ray: Ray,
    /// Hits must lie beyond this.
    pub tmin: f32,
    /// Hits must lie before this.
    pub tmax: f32,
}

/// The packet as a whole, for rays that share an octant: each ray's `1 /
/// dir` and `origin · inv` (one lane per ray, for the exact per-ray test
/// of a leaf's box) and their extremes over the packet (for one test of a
/// node's eight boxes on behalf of every ray).
///
/// Why one test serves all: a slab distance is `fma(plane, inv, −oi)`,
/// rounded once; the exact value grows with `inv` when `plane ≥ 0` (falls
/// when `plane < 0`) and falls as `oi` grows, and rounding keeps that
/// order. So `fma(plane, inv_lo or inv_hi, −oi_hi)`, the extremes picked
/// by the plane's sign, is at most every ray's own near distance, and the
/// mirror image at least every ray's far distance; a box whose bounds
/// fail `tn ≤ tf` (with the smallest `tmin` and largest `tmax`) fails
/// every ray's own test too. The rays share an octant, so the near plane
/// of an axis is the same one for all. Entry bounds are never NaN: walked
/// rays have finite `oi` and finite, non-zero `inv` (`reduce_as_ints`),
/// planes are finite or `±inf`.
struct Frustum {
    inv: [Lanes; 3],
    oi: [Lanes; 3],
    tmin: Lanes,
    inv_lo: [Lanes; 3],
    inv_hi: [Lanes; 3],
    oi_lo: [Lanes; 3],
    oi_hi: [Lanes; 3],
    tmin_lo: Lanes,
    /// Bit `a` set where the rays run towards −axis `a`.
    octant: usize,
}

impl Frustum {
    /// The packet of `rays` and the rays it walks (bit `r`): those the
    /// single walk takes on its integer path (`RayData::reduce_as_ints`);
    /// `None` for the packet if those do not share an octant. Filler
    /// lanes copy the first walked ray.
    #[inline(always)]
    fn new(rays: &[PacketRay]) -> (Option<Frustum>, u32) {
        // The rays' components as lanes (lanes past the packet copy its
        // last ray), and each one's `1 / dir` and `origin · inv` with the
        // operations of `RayData::inv_oi`, four lanes at a time.
        let n = rays.len();
        let mut d = [[0f32; PACKET]; 3];
        let mut o = [[0f32; PACKET]; 3];
        let mut tmin = [0f32; PACKET];
        for r in 0..PACKET {
            let q = &rays[r.min(n - 1)];
            for a in 0..3 {
                d[a][r] = q.ray.dir[a];
                o[a][r] = q.ray.origin[a];
            }
            tmin[r] = q.tmin;
        }
        let mut inv = [Lanes::splat(0.0); 3];
        let mut oi = [Lanes::splat(0.0); 3];
        // Finite `origin · inv` on every axis, and `tmin` at `+0` or more.
        let t = Lanes::from_array(tmin);
        let mut ok = t.0[0].cmpge(Vec4::ZERO).bitmask() | t.0[1].cmpge(Vec4::ZERO).bitmask() << 4;
        ok &= !t.sign_bits();
        for a in 0..3 {
            (inv[a], oi[a]) =
                RayData::inv_oi_lanes(Lanes::from_array(d[a]), Lanes::from_array(o[a]));
            ok &= oi[a].finite_bits();
        }
        let walked = ok & ((1 << n) - 1);
        if walked == 0 {
            return (None, 0);
        }
        // One octant: each axis's sign bits of `1 / d` all set or all clear
        // on the walked rays.
        let mut octant = 0;
        for (a, inv) in inv.iter().enumerate() {
            let neg = inv.sign_bits() & walked;
            if neg != 0 && neg != walked {
                return (None, walked);
            }
            octant |= usize::from(neg != 0) << a;
        }
        let mut t = t;
        if walked != 0xff {
            // Lanes of rays not walked copy the first walked ray's.
            let first = walked.trailing_zeros() as usize;
            for l in inv.iter_mut().chain(&mut oi).chain([&mut t]) {
                let v0 = l[first];
                for r in 0..PACKET {
                    if walked >> r & 1 == 0 {
                        l[r] = v0;
                    }
                }
            }
        }
        let lanes = |l: Lanes| {
            (
                l,
                Lanes::splat(l.min_element()),
                Lanes::splat(l.max_element()),
            )
        };
        let (x, y, z) = (lanes(inv[0]), lanes(inv[1]), lanes(inv[2]));
        let (ox, oy, oz, t) = (lanes(oi[0]), lanes(oi[1]), lanes(oi[2]), lanes(t));
        // Directions that differ much along an axis (the bounds of a
        // component's `1 / d` far apart relative to its size) make the
        // bounds loose: the packet would enter boxes none of its rays
        // enters. Such packets are walked one ray at a time.
        let tight = |l: &(Lanes, Lanes, Lanes)| {
            let (lo, hi) = (l.1[0], l.2[0]);
            hi - lo <= MAX_SPREAD * lo.abs().min(hi.abs())
        };
        if ![&x, &y, &z].into_iter().all(tight) {
            return (None, walked);
        }
        let f = Frustum {
            inv: [x.0, y.0, z.0],
            oi: [ox.0, oy.0, oz.0],
            tmin: t.0,
            inv_lo: [x.1, y.1, z.1],
            inv_hi: [x.2, y.2, z.2],
            oi_lo: [ox.1, oy.1, oz.1],
            oi_hi: [ox.2, oy.2, oz.2],
            tmin_lo: t.1,
            octant,
        };
        (Some(f), walked)
    }

    /// The boxes of `n` some ray of the packet may enter before `tmax_hi`
    /// (its largest `tmax`), and a lower bound of the rays' entry
    /// distances per box.
    ///
    /// With an [`Avx`] test, the same operations on 256-bit lanes (see
    /// [`boxes_avx`](Self::boxes_avx)).
    #[inline(always)]
    fn boxes<B: BoxTest>(&self, bt: B, n: &Node, tmax_hi: f32) -> (u32, Lanes) {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = bt.avx() {
            return self.boxes_avx(avx, n, tmax_hi);
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = bt;
        let (near, far) = self.planes(n);
        let near = |a: usize| {
            let pl = *near[a];
            pl.mul_sub(pl.by_sign(self.inv_hi[a], self.inv_lo[a]), self.oi_hi[a])
        };
        let far = |a: usize| {
            let pl = *far[a];
            pl.mul_sub(pl.by_sign(self.inv_lo[a], self.inv_hi[a]), self.oi_lo[a])
        };
        let tn = near(0).max(near(1)).max(near(2).max(self.tmin_lo));
        let tf = far(0).min(far(1)).min(far(2).min(Lanes::splat(tmax_hi)));
        (tn.le_mask(tf), tn)
    }

    /// The rays (a mask) that enter child `c`'s box of `n` within their own
    /// `(tmin, tmax)`: each ray's own float slab test (the same fused
    /// products as `RayData::boxes`, so the same distances), whose
    /// boxes include those of its integer form.
    #[inline(always)]
    fn rays_into<B: BoxTest>(&self, bt: B, n: &Node, c: usize, tmax: Lanes) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if let Some(avx) = bt.avx() {
            return self.rays_into_avx(avx, n, c, tmax);
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = bt;
        let (near, far) = self.planes(n);
        let t = |p: &Lanes, a: usize| Lanes::splat(p[c]).mul_sub(self.inv[a], self.oi[a]);
        let tn = t(near[0], 0)
            .max(t(near[1], 1))
            .max(t(near[2], 2).max(self.tmin));
        let tf = t(far[0], 0).min(t(far[1], 1)).min(t(far[2], 2).min(tmax));
        tn.le_mask(tf)
    }

    /// [`boxes`](Self::boxes) on 256-bit lanes: the same operations on
    /// the same operands in the same order (`by_sign` as a `<` compare and
    /// a blend, `vfmsub` fused as `f32::mul_add` is, `vmaxps`/`vminps`
    /// with `maxps`'s NaN rule in the same tree, an ordered `<=`), so the
    /// same mask and distances.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn boxes_avx(&self, _: Avx, n: &Node, tmax_hi: f32) -> (u32, Lanes) {
        use std::arch::x86_64::*;
        // SAFETY: an `Avx` value exists only where AVX2 (hence AVX) and
        // FMA were detected at run time (see `Avx::new`). `Lanes` is
        // `repr(C)` of two `Vec4`s, eight contiguous f32s, so each
        // unaligned load reads one `Lanes`, and the transmute back is
        // between two 32-byte plain-float types.
        unsafe {
            let ld = |l: &Lanes| _mm256_loadu_ps(l as *const Lanes as *const f32);
            let zero = _mm256_setzero_ps();
            let (near, far) = self.planes(n);
            // `pl.by_sign(neg, pos).mul_sub(…)`: `neg` where `pl < 0`.
            let t = |pl: &Lanes, neg: &Lanes, pos: &Lanes, oi: &Lanes| {
                let pl = ld(pl);
                let lt = _mm256_cmp_ps::<_CMP_LT_OQ>(pl, zero);
                _mm256_fmsub_ps(pl, _mm256_blendv_ps(ld(pos), ld(neg), lt), ld(oi))
            };
            let near = |a: usize| t(near[a], &self.inv_hi[a], &self.inv_lo[a], &self.oi_hi[a]);
            let far = |a: usize| t(far[a], &self.inv_lo[a], &self.inv_hi[a], &self.oi_lo[a]);
            let (max, min) = (_mm256_max_ps, _mm256_min_ps);
            let tn = max(max(near(0), near(1)), max(near(2), ld(&self.tmin_lo)));
            let tmax = _mm256_set1_ps(tmax_hi);
            let tf = min(min(far(0), far(1)), min(far(2), tmax));
            let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tn, tf)) as u32;
            (mask, std::mem::transmute::<__m256, Lanes>(tn))
        }
    }

    /// [`rays_into`](Self::rays_into) on 256-bit lanes, the same
    /// operations in the same order (as [`boxes_avx`](Self::boxes_avx)).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn rays_into_avx(&self, _: Avx, n: &Node, c: usize, tmax: Lanes) -> u32 {
        use std::arch::x86_64::*;
        // SAFETY: as in `boxes_avx`; `p[c]` is an f32 of a `Lanes` (`c <
        // 8`, indexed through the array, bounds-checked).
        unsafe {
            let ld = |l: &Lanes| _mm256_loadu_ps(l as *const Lanes as *const f32);
            let (near, far) = self.planes(n);
            let t = |p: &Lanes, a: usize| {
                _mm256_fmsub_ps(_mm256_set1_ps(p[c]), ld(&self.inv[a]), ld(&self.oi[a]))
            };
            let (max, min) = (_mm256_max_ps, _mm256_min_ps);
            let tn = max(
                max(t(near[0], 0), t(near[1], 1)),
                max(t(near[2], 2), ld(&self.tmin)),
            );
            let tf = min(
                min(t(far[0], 0), t(far[1], 1)),
                min(t(far[2], 2), ld(&tmax)),
            );
            _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tn, tf)) as u32
        }
    }

    /// The near and far planes of `n` per axis for the packet's octant
    /// (`RayData::planes`' choice), picked from the octant's bits: no
    /// index to load and bounds-check per plane.
    #[inline(always)]
    fn planes<'n>(&self, n: &'n Node) -> ([&'n Lanes; 3], [&'n Lanes; 3]) {
        let p = &n.planes;
        let pick = |a: usize, neg: bool| if neg { &p[a + 3] } else { &p[a] };
        let s = |a: usize| self.octant >> a & 1 != 0;
        (
            [pick(0, s(0)), pick(1, s(1)), pick(2, s(2))],
            [pick(0, !s(0)), pick(1, !s(1)), pick(2, !s(2))],
        )
    }
}

/// The closest hit of each ray of `rays` (at most [`PACKET`]) into
/// `out[..rays.len()]`, with an `N`-entry stack (as `traverse::closest`).
/// A packet [`Frustum::new`] accepts takes the packet walk (one box test
/// per node for the packet, each ray's own test at leaves' boxes); other
/// packets, and rays off the integer path, the single walk. Always
/// inlined, so that `dispatch`'s AVX2 copy compiles it with AVX2.
#[inline(always)]
pub(crate) fn closest<S: TraversalStats, F: Fallback + ?Sized, B: BoxTest, const N: usize>(
    bt: B,
    tree: &Tree<F>,
    rays: &[PacketRay],
    out: &mut [Option<Closest>],
    stats: &mut S,
) {
    let out = &mut out[..rays.len()];
    out.fill(None);
    if tree.nodes.is_empty() || rays.is_empty() {
        return;
    }
    let (f, walked) = Frustum::new(rays);
    let walked = if f.is_some() { walked } else { 0 };
    for (r, q) in rays.iter().enumerate() {
        if walked & 1 << r == 0 {
            // The single walk's choice of arithmetic (`ClosestHit::walk`):
            // a packet the frustum refuses costs its rays no more than
            // their own walks.
            let rd = &RayData::new(&q.ray);
            out[r] = if rd.reduce_as_ints(q.tmin) {
                traverse::closest::<S, F, B, N, ANY_OCTANT, true>(
                    bt, tree, rd, q.tmin, q.tmax, stats,
                )
            } else {
                traverse::closest::<S, F, B, N, ANY_OCTANT, false>(
                    bt, tree, rd, q.tmin, q.tmax, stats,
                )
            };
        }
    }
    if let Some(f) = f {
        closest_frustum::<S, F, B, N>(bt, tree, rays, (&f, walked), out, stats)
    }
}

/// Which rays of `rays` something but triangle `skip[r]` blocks (bit `r`;
/// `skip` empty or one id per ray, [`NO_ITEM`] for none), as
/// `traverse::any` answers for each; the walks chosen as in [`closest`].
#[inline(always)]
pub(crate) fn any<S: TraversalStats, F: Fallback + ?Sized, B: BoxTest, const N: usize>(
    bt: B,
    tree: &Tree<F>,
    rays: &[PacketRay],
    skip: &[u32],
    stats: &mut S,
) -> u32 {
    if tree.nodes.is_empty() || rays.is_empty() {
        return 0;
    }
    debug_assert!(skip.is_empty() || skip.len() == rays.len());
    let (f, walked) = Frustum::new(rays);
    let walked = if f.is_some() { walked } else { 0 };
    let mut hit = 0u32;
    for (r, q) in rays.iter().enumerate() {
        if walked & 1 << r == 0 {
            // The single walk (`dispatch::AnyHit`): a packet the frustum
            // refuses costs its rays no more than their own walks.
            let rd = &RayData::new(&q.ray);
            let skip = skip.get(r).copied().unwrap_or(NO_ITEM);
            let h = super::dispatch::any_one(bt, tree, rd, (q.tmin, q.tmax), skip, stats);
            hit |= u32::from(h) << r;
        }
    }
    match f {
        Some(f) => hit | any_frustum::<S, F, B, N>(bt, tree, rays, (&f, walked), skip, stats),
        None => hit,
    }
}

/// The rays of `active` entering each child in `mask` of `node`: all of
/// them for an inner node (its own test sorts them out), each ray's own
/// test for a leaf.
#[inline(always)]
fn child_rays<B: BoxTest>(
    bt: B,
    f: &Frustum,
    node: &Node,
    i: usize,
    active: u32,
    tmax: Lanes,
) -> u32 {
    if is_leaf(node.child[i]) {
        f.rays_into(bt, node, i, tmax) & active
    } else {
        active
    }
}

/// Calls `f(r, ray, leaf)` for each ray `r` of the mask `active`, with its
/// [`LeafRay`] (made at the first leaf it reaches).
#[inline(always)]
fn each_ray<'r>(
    rays: &'r [PacketRay],
    leaf_ray: &mut [Option<LeafRay<'r>>; PACKET],
    active: u32,
    mut f: impl FnMut(usize, &'r PacketRay, &LeafRay<'r>),
) {
    let mut todo = active;
    while todo != 0 {
        let r = todo.trailing_zeros() as usize;
        todo &= todo - 1;
        let q = &rays[r];
        f(
            r,
            q,
            leaf_ray[r].get_or_insert_with(|| LeafRay::new(&q.ray)),
        );
    }
}

/// Each ray's `tmax`, one lane per ray.
#[inline(always)]
fn tmax_lanes(rays: &[PacketRay]) -> Lanes {
    let mut tmax = Lanes::splat(0.0);
    for (r, q) in rays.iter().enumerate() {
        tmax[r] = q.tmax;
    }
    tmax
}

/// A closest-hit walk's [`Nearest`] of each ray of a packet, as arrays:
/// `tmax`, `Nearest::test_tmax` (kept up to date) and the best hit.
struct Nearests {
    tmax: F8,
    test_tmax: F8,
    best: [Option<Closest>; PACKET],
}

impl Nearests {
    #[inline(always)]
    fn new(rays: &[PacketRay]) -> Self {
        let mut tmax = F8::default();
        for (r, q) in rays.iter().enumerate() {
            tmax.0[r] = q.tmax;
        }
        Nearests {
            tmax,
            test_tmax: tmax,
            best: [None; PACKET],
        }
    }

    /// Each ray's `tmax`, as lanes.
    #[inline(always)]
    fn tmax(&self) -> Lanes {
        Lanes::from_array(self.tmax.0)
    }

    /// Ray `r`'s [`Nearest`].
    #[inline(always)]
    fn get(&self, r: usize) -> Nearest {
        Nearest {
            tmax: self.tmax.0[r],
            best: self.best[r],
        }
    }

    /// Sets ray `r`'s [`Nearest`].
    #[inline(always)]
    fn set(&mut self, r: usize, near: Nearest) {
        self.test_tmax.0[r] = near.test_tmax();
        (self.tmax.0[r], self.best[r]) = (near.tmax, near.best);
    }

    /// `Nearest::offer` for ray `r`.
    #[inline(always)]
    fn offer(&mut self, r: usize, t: f32, id: u32, bary: Option<[f32; 3]>) {
        let mut near = self.get(r);
        near.offer(t, id, bary);
        self.set(r, near);
    }
}

/// The closest-hit walk of a packet sharing an octant (see [`Frustum`]),
/// for the rays `walked`.
#[inline(always)]
fn closest_frustum<S: TraversalStats, F: Fallback + ?Sized, B: BoxTest, const N: usize>(
    bt: B,
    tree: &Tree<F>,
    rays: &[PacketRay],
    (f, walked): (&Frustum, u32),
    out: &mut [Option<Closest>],
    stats: &mut S,
) {
    let (mut n_nodes, mut n_tests) = (0u64, 0u64);
    let mut near = Nearests::new(rays);
    let mut leaf_ray: [Option<LeafRay>; PACKET] = Default::default();
    #[cfg(target_arch = "x86_64")]
    let mut leaf8 = None;
    // Not zeroed (see `traverse::Slot`).
    let mut stack = [const { Slot::<(u32, u32, f32)>::uninit() }; N];
    let mut sp = 0usize;
    let (mut cur, mut active) = (0u32, walked);
    while active != 0 {
        let mut leaf_done = false;
        if !is_leaf(cur) {
            let node = tree.node::<S>(cur, &mut n_nodes);
            let tmax = near.tmax();
            let (mut mask, dist) = f.boxes(bt, node, tmax.max_of(active));
            let dist = dist.to_array();
            // Nearest first: the others pushed far to near.
            let mut kids = [(0u32, 0u32, 0f32); W];
            let mut k = 0;
            while mask != 0 {
                let i = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                let m = child_rays(bt, f, node, i, active, tmax);
                if m == 0 {
                    continue;
                }
                let e = (node.child[i], m, dist[i]);
                tree.prefetch_child(e.0);
                insert_far_first(&mut kids, k, e, |e| e.2);
                k += 1;
            }
            if k > 0 {
                for &e in &kids[..k - 1] {
                    stack[sp].write(e);
                    sp += 1;
                }
                (cur, active) = (kids[k - 1].0, kids[k - 1].1);
                continue;
            }
        } else if cur != EMPTY {
            #[cfg(target_arch = "x86_64")]
            if let Some(avx) = bt.avx() {
                let lr = leaf8.get_or_insert_with(|| LeafRays::new(rays, walked));
                n_tests += nearest_in_leaf8::<S, F>(avx, tree, cur, lr, active, &mut near);
                leaf_done = true;
            }
            if !leaf_done {
                each_ray(rays, &mut leaf_ray, active, |r, q, lr| {
                    let mut n = near.get(r);
                    n_tests += tree.nearest_in_leaf::<S, _>(bt, cur, lr, q.tmin, &mut n);
                    near.set(r, n);
                });
            }
        }
        // Pop the nearest pending child that some ray can still find a
        // closer hit in (the entry's distance is below each ray's own).
        active = 0;
        let tmax = near.tmax();
        while sp > 0 {
            sp -= 1;
            // SAFETY: below the stack pointer (see `traverse::Slot`).
            let (c, m, d) = unsafe { stack[sp].assume_init() };
            let keep = Lanes::splat(d).le_mask(tmax) & m;
            if keep != 0 {
                (cur, active) = (c, keep);
                break;
            }
        }
    }
    for (r, o) in out.iter_mut().enumerate() {
        if walked & 1 << r != 0 {
            *o = near.best[r];
        }
    }
    stats.add(n_nodes, n_tests);
}

/// The any-hit walk of a packet sharing an octant (see [`Frustum`]), for
/// the rays `walked`.
#[inline(always)]
fn any_frustum<S: TraversalStats, F: Fallback + ?Sized, B: BoxTest, const N: usize>(
    bt: B,
    tree: &Tree<F>,
    rays: &[PacketRay],
    (f, walked): (&Frustum, u32),
    skip: &[u32],
    stats: &mut S,
) -> u32 {
    let skip_of = |r: usize| skip.get(r).copied().unwrap_or(NO_ITEM);
    let (mut n_nodes, mut n_tests) = (0u64, 0u64);
    let tmax = tmax_lanes(rays);
    let tmax_hi = tmax.max_of(walked);
    let mut leaf_ray: [Option<LeafRay>; PACKET] = Default::default();
    #[cfg(target_arch = "x86_64")]
    let (mut leaf8, tmax8) = (None, F8(tmax.to_array()));
    // Not zeroed (see `traverse::Slot`).
    let mut stack = [const { Slot::<(u32, u32)>::uninit() }; N];
    let mut sp = 0usize;
    let mut hit = 0u32;
    // Rays still looking for a hit, and those in the current subtree.
    let mut open = walked;
    let (mut cur, mut active) = (0u32, walked);
    loop {
        let mut leaf_done = false;
        if !is_leaf(cur) {
            let node = tree.node::<S>(cur, &mut n_nodes);
            let (mut mask, _) = f.boxes(bt, node, tmax_hi);
            // The far side of the node's first division first, as
            // `traverse::any` goes (`shadow8`: 1.01x on bunny40k, 1.10x
            // on the spheres; mirrored, 1.03x and 1.00x).
            let mut next = None;
            while mask != 0 {
                let i = node.far_slot(f.octant, mask);
                mask &= !(1 << i);
                // Each ray's own test for inner children too: shadow
                // rays from eight surface points make loose packet
                // bounds, and the rays a child keeps prune its subtree
                // (callgrind, every 32nd packet: sphere1m's shadow rays
                // 14% fewer instructions, bunny40k's 3% more).
                let m = f.rays_into(bt, node, i, tmax) & active;
                if m == 0 {
                    continue;
                }
                tree.prefetch_child(node.child[i]);
                if next.is_none() {
                    next = Some((node.child[i], m));
                } else {
                    stack[sp].write((node.child[i], m));
                    sp += 1;
                }
            }
            if let Some((c, m)) = next {
                (cur, active) = (c, m);
                continue;
            }
        } else if cur != EMPTY {
            #[cfg(target_arch = "x86_64")]
            if let Some(avx) = bt.avx() {
                let lr = leaf8.get_or_insert_with(|| LeafRays::new(rays, walked));
                let (blocked, tests) =
                    blocked_in_leaf8::<S, F>(avx, tree, cur, lr, active, &tmax8, skip);
                n_tests += tests;
                hit |= blocked;
                open &= !blocked;
                leaf_done = true;
            }
            if !leaf_done {
                each_ray(rays, &mut leaf_ray, active, |r, q, lr| {
                    let range = (q.tmin, q.tmax);
                    let (blocked, tests) =
                        tree.blocked_in_leaf::<S, _>(bt, cur, lr, range, skip_of(r));
                    n_tests += tests;
                    if blocked {
                        hit |= 1 << r;
                        open &= !(1 << r);
                    }
                });
            }
        }
        active = 0;
        while sp > 0 && open != 0 {
            sp -= 1;
            // SAFETY: below the stack pointer (see `traverse::Slot`).
            let (c, m) = unsafe { stack[sp].assume_init() };
            if m & open != 0 {
                (cur, active) = (c, m & open);
                break;
            }
        }
        if active == 0 {
            break;
        }
    }
    stats.add(n_nodes, n_tests);
    hit
}

/// The packet's rays at leaves, for the AVX leaf test: each walked ray's
/// watertight constants (`shape::WatertightRay8`) and `tmin`, one lane per
/// ray. Made at the first leaf the packet reaches.
#[cfg(target_arch = "x86_64")]
struct LeafRays<'r> {
    rays: &'r [PacketRay],
    w8: WatertightRay8,
    tmin: F8,
}

#[cfg(target_arch = "x86_64")]
impl<'r> LeafRays<'r> {
    #[inline(always)]
    fn new(rays: &'r [PacketRay], walked: u32) -> Self {
        let mut tmin = F8::default();
        for (r, q) in rays.iter().enumerate() {
            tmin.0[r] = q.tmin;
        }
        LeafRays {
            rays,
            w8: WatertightRay8::new(|r| {
                (walked >> r & 1 != 0).then(|| WatertightRay::new(&rays[r].ray))
            }),
            tmin,
        }
    }

    /// The rays of `active` grouped by dominant axis (`kz`, the lanes of
    /// one [`hit8_avx`] call), and how many groups: usually one.
    #[inline(always)]
    fn groups(&self, active: u32) -> ([(usize, u32); 3], usize) {
        let mut g = [(0, 0); 3];
        let mut n = 0;
        for (kz, &lanes) in self.w8.by_axis.iter().enumerate() {
            if active & lanes != 0 {
                g[n] = (kz, active & lanes);
                n += 1;
            }
        }
        (g, n)
    }
}

/// Leaf `c` for the closest-hit walk of the rays `active`, on AVX: each
/// triangle against all those rays at once (`shape::hit8_avx`, each ray's
/// own watertight test bit for bit), each hit offered to its ray's
/// [`Nearest`] (`tmax`, `best`); the items that are not triangles ray by
/// ray, as `Tree::nearest_in_leaf` tests them. Each ray ends with the
/// hit its own `nearest_in_leaf` keeps: a hit is kept by the rule of
/// `Nearest::closer`, which makes the result the nearest hit in the ray's
/// range, ties to the smallest id, whatever the order of the offers; the
/// range a triangle is tested in (`Nearest::test_tmax` after the previous
/// offers) only leaves out hits that rule would refuse. Returns the items
/// tested, per ray (0 unless `S::ENABLED`).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn nearest_in_leaf8<S: TraversalStats, F: Fallback + ?Sized>(
    _avx: Avx,
    tree: &Tree<F>,
    c: u32,
    lr: &LeafRays,
    active: u32,
    near: &mut Nearests,
) -> u64 {
    let mut tests = 0;
    let (groups, n_groups) = lr.groups(active);
    for b in tree.leaf(c) {
        if S::ENABLED {
            tests += b.items() * u64::from(active.count_ones());
        }
        let mut tri = triangle_lanes(b);
        while tri != 0 {
            let j = tri.trailing_zeros() as usize;
            tri &= tri - 1;
            for &(kz, lanes) in &groups[..n_groups] {
                // SAFETY: an `Avx` token exists only where AVX2 (hence AVX)
                // was detected at run time (see `Avx::new`).
                let h = unsafe { hit8_avx(&lr.w8, kz, &b.v, j, lanes, &lr.tmin, &near.test_tmax) };
                let mut m = h.mask;
                while m != 0 {
                    let r = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let bary = [h.b[0].0[r], h.b[1].0[r], h.b[2].0[r]];
                    near.offer(r, h.t.0[r], b.ids[j], Some(bary));
                }
            }
        }
        if !F::TRIANGLES_ONLY && b.has_other() {
            let mut todo = active;
            while todo != 0 {
                let r = todo.trailing_zeros() as usize;
                todo &= todo - 1;
                let q = &lr.rays[r];
                for id in b.others() {
                    let tt = near.test_tmax.0[r];
                    if let Some(t) = tree.fallback.intersect(id, &q.ray, q.tmin, tt) {
                        near.offer(r, t, id, None);
                    }
                }
            }
        }
    }
    tests
}

/// Leaf `c` for the any-hit walk of the rays `active` (ranges `tmin` and
/// `tmax`, `skip` as [`any`]'s), on AVX: each triangle against the rays
/// not yet blocked, at once (`shape::hit8_avx`); the items that are not
/// triangles ray by ray. Returns the rays blocked (each ray's own
/// `Tree::blocked_in_leaf` answer) and the items tested up to the block
/// that blocks each (0 unless `S::ENABLED`).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn blocked_in_leaf8<S: TraversalStats, F: Fallback + ?Sized>(
    _avx: Avx,
    tree: &Tree<F>,
    c: u32,
    lr: &LeafRays,
    active: u32,
    tmax: &F8,
    skip: &[u32],
) -> (u32, u64) {
    let mut tests = 0;
    let mut open = active;
    let (groups, n_groups) = lr.groups(active);
    for b in tree.leaf(c) {
        if open == 0 {
            break;
        }
        if S::ENABLED {
            tests += b.items() * u64::from(open.count_ones());
        }
        let mut tri = triangle_lanes(b);
        while tri != 0 && open != 0 {
            let j = tri.trailing_zeros() as usize;
            tri &= tri - 1;
            let mut rays = open;
            if !skip.is_empty() {
                let mut todo = open;
                while todo != 0 {
                    let r = todo.trailing_zeros() as usize;
                    todo &= todo - 1;
                    if skip[r] == b.ids[j] {
                        rays &= !(1 << r);
                    }
                }
            }
            for &(kz, lanes) in &groups[..n_groups] {
                let lanes = lanes & rays;
                if lanes != 0 {
                    // SAFETY: an `Avx` token exists only where AVX2 (hence
                    // AVX) was detected at run time (see `Avx::new`).
                    open &= !unsafe { hit8_avx(&lr.w8, kz, &b.v, j, lanes, &lr.tmin, tmax) }.mask;
                }
            }
        }
        if !F::TRIANGLES_ONLY && b.has_other() {
            let mut todo = open;
            while todo != 0 {
                let r = todo.trailing_zeros() as usize;
                todo &= todo - 1;
                let q = &lr.rays[r];
                let mut others = b.others();
                if others.any(|id| {
                    tree.fallback
                        .intersect(id, &q.ray, q.tmin, q.tmax)
                        .is_some()
                }) {
                    open &= !(1 << r);
                }
            }
        }
    }
    (active & !open, tests)
}

#[cfg(test)]
#[path = "packet_tests.rs"]
mod tests;
