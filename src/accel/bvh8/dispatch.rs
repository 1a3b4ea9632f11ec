//! The traversal compiled twice: for the x86-64 baseline (SSE2) and for
//! AVX2 with FMA, picked per query by a run-time check of the CPU (a cached
//! flag).
//!
//! Why: release binaries must run on any x86-64, so glam's `Vec4` compiles
//! to SSE2; the AVX2 copy of the same source gets three-operand (VEX)
//! instructions, fused multiply-adds and more freedom in scheduling. The
//! arithmetic is the same IEEE operations in the same order (Rust never
//! fuses a multiply and an add on its own; the box test's fused ones are
//! `f32::mul_add`, one rounding on every target, and the min/max intrinsics
//! keep their SSE semantics), so both copies return bit-identical results.
//! Elsewhere only the portable copy exists. The price of that identity: on
//! an x86-64 without FMA (before 2013) the portable copy's `mul_add` is a
//! call to the C library's exact `fmaf`, slower than a multiply and an add.
//! The AVX2 copy also tests a node's eight boxes with 256-bit operations
//! (`traverse::RayData::boxes_avx`, given an `Avx` token made only here).

use super::node::{Node, Tri4};
use super::packet::{self, PacketRay};
use super::traverse::{
    self, BoxTest, Closest, Fallback, Portable, RayData, ANY_OCTANT, DEEP, SHALLOW,
};
use crate::math::Ray;
use crate::stats::TraversalStats;

/// Closest hit (see `traverse::closest`), on the best copy for this CPU, with
/// the deep stack when the tree is `deep` (`traverse::SHALLOW_DEPTH`).
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn closest<S: TraversalStats, F: Fallback + ?Sized>(
    nodes: &[Node],
    tris: &[Tri4],
    fallback: &F,
    ray: &Ray,
    tmin: f32,
    tmax: f32,
    stats: &mut S,
    deep: bool,
) -> Option<Closest> {
    #[cfg(target_arch = "x86_64")]
    if avx2_fma() {
        // SAFETY: calling a `#[target_feature(enable = "avx2,fma")]` function
        // is sound exactly when the CPU supports AVX2 and FMA, checked just
        // above.
        return unsafe { avx2::closest(nodes, tris, fallback, ray, tmin, tmax, stats, deep) };
    }
    portable::closest(nodes, tris, fallback, ray, tmin, tmax, stats, deep)
}

/// Any hit but triangle `skip` (see `traverse::any`), on the best copy for
/// this CPU.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn any<S: TraversalStats, F: Fallback + ?Sized>(
    nodes: &[Node],
    tris: &[Tri4],
    fallback: &F,
    ray: &Ray,
    (tmin, tmax): (f32, f32),
    skip: u32,
    stats: &mut S,
    deep: bool,
) -> bool {
    #[cfg(target_arch = "x86_64")]
    if avx2_fma() {
        // SAFETY: as in `closest`: AVX2 and FMA are present, checked just
        // above.
        return unsafe { avx2::any(nodes, tris, fallback, ray, (tmin, tmax), skip, stats, deep) };
    }
    portable::any(nodes, tris, fallback, ray, (tmin, tmax), skip, stats, deep)
}

/// The closest hit of each ray of a packet (see `packet::closest`), on the
/// best copy for this CPU.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn closest8<S: TraversalStats, F: Fallback + ?Sized>(
    nodes: &[Node],
    tris: &[Tri4],
    fallback: &F,
    rays: &[PacketRay],
    out: &mut [Option<Closest>],
    stats: &mut S,
    deep: bool,
) {
    #[cfg(target_arch = "x86_64")]
    if avx2_fma() {
        // SAFETY: as in `closest`: AVX2 and FMA are present, checked just
        // above.
        return unsafe { avx2::closest8(nodes, tris, fallback, rays, out, stats, deep) };
    }
    portable::closest8(nodes, tris, fallback, rays, out, stats, deep)
}

/// Which rays of a packet are blocked (see `packet::any`), on the best
/// copy for this CPU.
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn any8<S: TraversalStats, F: Fallback + ?Sized>(
    nodes: &[Node],
    tris: &[Tri4],
    fallback: &F,
    rays: &[PacketRay],
    skip: &[u32],
    stats: &mut S,
    deep: bool,
) -> u32 {
    #[cfg(target_arch = "x86_64")]
    if avx2_fma() {
        // SAFETY: as in `closest`: AVX2 and FMA are present, checked just
        // above.
        return unsafe { avx2::any8(nodes, tris, fallback, rays, skip, stats, deep) };
    }
    portable::any8(nodes, tris, fallback, rays, skip, stats, deep)
}

/// The packet walks with box test `bt` and the stack the tree's depth
/// needs. Always inlined, as [`closest_with`].
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn closest8_with<S: TraversalStats, F: Fallback + ?Sized, B: BoxTest>(
    bt: B,
    nodes: &[Node],
    tris: &[Tri4],
    fallback: &F,
    rays: &[PacketRay],
    out: &mut [Option<Closest>],
    stats: &mut S,
    deep: bool,
) {
    if deep {
        packet::closest::<S, F, B, DEEP>(bt, nodes, tris, fallback, rays, out, stats)
    } else {
        packet::closest::<S, F, B, SHALLOW>(bt, nodes, tris, fallback, rays, out, stats)
    }
}

/// See [`closest8_with`].
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn any8_with<S: TraversalStats, F: Fallback + ?Sized, B: BoxTest>(
    bt: B,
    nodes: &[Node],
    tris: &[Tri4],
    fallback: &F,
    rays: &[PacketRay],
    skip: &[u32],
    stats: &mut S,
    deep: bool,
) -> u32 {
    if deep {
        packet::any::<S, F, B, DEEP>(bt, nodes, tris, fallback, rays, skip, stats)
    } else {
        packet::any::<S, F, B, SHALLOW>(bt, nodes, tris, fallback, rays, skip, stats)
    }
}

/// Whether the CPU has AVX2 and FMA (each a cached flag).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn avx2_fma() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

/// `$walk` with `O` the ray's octant as a constant: one copy of the walk per
/// octant, so that the node step loads each of its six planes from a fixed
/// offset in the node (no index reloaded per plane from the stack, where
/// register pressure puts it).
///
/// Used for the any-hit walk only. Measured (Intel Xeon, 2 cores): the
/// octant copies took 6.1% fewer instructions an any-hit query and 6.6% a
/// closest one (callgrind, every 16th bunny40k ray); timed, shadow rays ran
/// 4-8% faster and coherent camera rays 2-3%, but incoherent closest-hit
/// rays, which switch octant from ray to ray, 4-13% slower. An AO render
/// (incoherent any-hit rays) kept its time within 1%.
macro_rules! by_octant {
    ($rd:expr, |O| $walk:expr) => {
        match $rd.octant() {
            0 => {
                const O: usize = 0;
                $walk
            }
            1 => {
                const O: usize = 1;
                $walk
            }
            2 => {
                const O: usize = 2;
                $walk
            }
            3 => {
                const O: usize = 3;
                $walk
            }
            4 => {
                const O: usize = 4;
                $walk
            }
            5 => {
                const O: usize = 5;
                $walk
            }
            6 => {
                const O: usize = 6;
                $walk
            }
            _ => {
                const O: usize = 7;
                $walk
            }
        }
    };
}

/// The closest-hit walk with box test `bt`: the ray's constants, then the
/// stack the tree's depth needs. Always inlined, so that each copy below
/// compiles it with its own target features.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn closest_with<S: TraversalStats, F: Fallback + ?Sized, B: BoxTest>(
    bt: B,
    nodes: &[Node],
    tris: &[Tri4],
    fallback: &F,
    ray: &Ray,
    tmin: f32,
    tmax: f32,
    stats: &mut S,
    deep: bool,
) -> Option<Closest> {
    let rd = &RayData::new(ray);
    match (deep, rd.reduce_as_ints(tmin)) {
        (false, true) => traverse::closest::<S, F, _, SHALLOW, ANY_OCTANT, true>(
            bt, nodes, tris, fallback, rd, tmin, tmax, stats,
        ),
        (true, true) => traverse::closest::<S, F, _, DEEP, ANY_OCTANT, true>(
            bt, nodes, tris, fallback, rd, tmin, tmax, stats,
        ),
        (false, false) => traverse::closest::<S, F, _, SHALLOW, ANY_OCTANT, false>(
            bt, nodes, tris, fallback, rd, tmin, tmax, stats,
        ),
        (true, false) => traverse::closest::<S, F, _, DEEP, ANY_OCTANT, false>(
            bt, nodes, tris, fallback, rd, tmin, tmax, stats,
        ),
    }
}

/// The any-hit walk with box test `bt` (see [`closest_with`]).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn any_with<S: TraversalStats, F: Fallback + ?Sized, B: BoxTest>(
    bt: B,
    nodes: &[Node],
    tris: &[Tri4],
    fallback: &F,
    ray: &Ray,
    (tmin, tmax): (f32, f32),
    skip: u32,
    stats: &mut S,
    deep: bool,
) -> bool {
    let rd = &RayData::new(ray);
    match (deep, rd.reduce_as_ints(tmin)) {
        (false, true) => by_octant!(rd, |O| traverse::any::<S, F, _, SHALLOW, O, true>(
            bt, nodes, tris, fallback, rd, tmin, tmax, skip, stats
        )),
        (true, true) => traverse::any::<S, F, _, DEEP, ANY_OCTANT, true>(
            bt, nodes, tris, fallback, rd, tmin, tmax, skip, stats,
        ),
        // Rare (a negative `tmin`, an origin beyond about 1e20): one copy
        // per stack, the octant read at run time.
        (false, false) => traverse::any::<S, F, _, SHALLOW, ANY_OCTANT, false>(
            bt, nodes, tris, fallback, rd, tmin, tmax, skip, stats,
        ),
        (true, false) => traverse::any::<S, F, _, DEEP, ANY_OCTANT, false>(
            bt, nodes, tris, fallback, rd, tmin, tmax, skip, stats,
        ),
    }
}

#[cfg(test)]
pub(crate) use portable::{any8 as portable_any8, closest8 as portable_closest8};

/// The portable copies, out of line: inlined into the dispatchers above,
/// their stack frame and saved registers were set up on every query even
/// when the AVX2 copy ran (callgrind, scene6_07: 40 instructions a shadow
/// ray in the dispatcher alone).
mod portable {
    use super::*;

    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub(super) fn closest<S: TraversalStats, F: Fallback + ?Sized>(
        nodes: &[Node],
        tris: &[Tri4],
        fallback: &F,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        stats: &mut S,
        deep: bool,
    ) -> Option<Closest> {
        closest_with(
            Portable, nodes, tris, fallback, ray, tmin, tmax, stats, deep,
        )
    }

    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub(super) fn any<S: TraversalStats, F: Fallback + ?Sized>(
        nodes: &[Node],
        tris: &[Tri4],
        fallback: &F,
        ray: &Ray,
        (tmin, tmax): (f32, f32),
        skip: u32,
        stats: &mut S,
        deep: bool,
    ) -> bool {
        any_with(
            Portable,
            nodes,
            tris,
            fallback,
            ray,
            (tmin, tmax),
            skip,
            stats,
            deep,
        )
    }
    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub(crate) fn closest8<S: TraversalStats, F: Fallback + ?Sized>(
        nodes: &[Node],
        tris: &[Tri4],
        fallback: &F,
        rays: &[PacketRay],
        out: &mut [Option<Closest>],
        stats: &mut S,
        deep: bool,
    ) {
        closest8_with(Portable, nodes, tris, fallback, rays, out, stats, deep)
    }

    #[allow(clippy::too_many_arguments)]
    #[inline(never)]
    pub(crate) fn any8<S: TraversalStats, F: Fallback + ?Sized>(
        nodes: &[Node],
        tris: &[Tri4],
        fallback: &F,
        rays: &[PacketRay],
        skip: &[u32],
        stats: &mut S,
        deep: bool,
    ) -> u32 {
        any8_with(Portable, nodes, tris, fallback, rays, skip, stats, deep)
    }
}

/// The AVX2 copies: the portable traversal inlined into functions compiled
/// with AVX2 and FMA enabled.
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::*;
    use crate::accel::bvh8::traverse::Avx;

    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn closest<S: TraversalStats, F: Fallback + ?Sized>(
        nodes: &[Node],
        tris: &[Tri4],
        fallback: &F,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        stats: &mut S,
        deep: bool,
    ) -> Option<Closest> {
        // SAFETY: these functions are called only after `avx2_fma()`
        // (`Avx::new`'s contract).
        let avx = unsafe { Avx::new() };
        closest_with(avx, nodes, tris, fallback, ray, tmin, tmax, stats, deep)
    }

    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn any<S: TraversalStats, F: Fallback + ?Sized>(
        nodes: &[Node],
        tris: &[Tri4],
        fallback: &F,
        ray: &Ray,
        (tmin, tmax): (f32, f32),
        skip: u32,
        stats: &mut S,
        deep: bool,
    ) -> bool {
        // SAFETY: these functions are called only after `avx2_fma()`
        // (`Avx::new`'s contract).
        let avx = unsafe { Avx::new() };
        any_with(
            avx,
            nodes,
            tris,
            fallback,
            ray,
            (tmin, tmax),
            skip,
            stats,
            deep,
        )
    }

    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn closest8<S: TraversalStats, F: Fallback + ?Sized>(
        nodes: &[Node],
        tris: &[Tri4],
        fallback: &F,
        rays: &[PacketRay],
        out: &mut [Option<Closest>],
        stats: &mut S,
        deep: bool,
    ) {
        // SAFETY: these functions are called only after `avx2_fma()`
        // (`Avx::new`'s contract).
        let avx = unsafe { Avx::new() };
        closest8_with(avx, nodes, tris, fallback, rays, out, stats, deep)
    }

    #[allow(clippy::too_many_arguments)]
    #[target_feature(enable = "avx2,fma")]
    pub(super) fn any8<S: TraversalStats, F: Fallback + ?Sized>(
        nodes: &[Node],
        tris: &[Tri4],
        fallback: &F,
        rays: &[PacketRay],
        skip: &[u32],
        stats: &mut S,
        deep: bool,
    ) -> u32 {
        // SAFETY: these functions are called only after `avx2_fma()`
        // (`Avx::new`'s contract).
        let avx = unsafe { Avx::new() };
        any8_with(avx, nodes, tris, fallback, rays, skip, stats, deep)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh8::node::NO_ITEM;
    use crate::accel::testutil::{ray, soup, Rng};
    use crate::accel::Bvh8;
    use crate::stats::Counters;

    /// The portable copy (the only one on a CPU without AVX2, so never the
    /// dispatched one here) gives the dispatched copy's answers and
    /// statistics, bit for bit, with either stack.
    #[test]
    fn the_portable_copy_answers_as_the_dispatched_one() {
        let prims = soup(9, 2000);
        let b = Bvh8::new(&prims, (0..prims.len() as u32).collect());
        let (nodes, tris, fb) = (&b.nodes, &b.tris, prims.as_slice());
        let mut r = Rng::new(10);
        let (mut hits, mut blocked) = (0, 0);
        for _ in 0..1000 {
            let q = ray(&mut r);
            for deep in [false, true] {
                let (mut c1, mut c2) = (Counters::default(), Counters::default());
                let inf = f32::INFINITY;
                let want = closest(nodes, tris, fb, &q, 0.0, inf, &mut c1, deep);
                let got = portable::closest(nodes, tris, fb, &q, 0.0, inf, &mut c2, deep);
                assert_eq!(got, want);
                let want = any(nodes, tris, fb, &q, (0.0, 0.2), NO_ITEM, &mut c1, deep);
                let got = portable::any(nodes, tris, fb, &q, (0.0, 0.2), NO_ITEM, &mut c2, deep);
                assert_eq!(got, want);
                assert_eq!(format!("{c1:?}"), format!("{c2:?}"));
                hits += usize::from(want);
                blocked += usize::from(got);
            }
        }
        assert!((100..1900).contains(&hits) && blocked == hits, "{hits}");
    }
}
