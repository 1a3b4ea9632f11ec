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

use super::packet::{self, PacketRay};
use super::traverse::{
    self, BoxTest, Closest, Fallback, Portable, RayData, Tree, ANY_OCTANT, BY_OCTANT, DEEP, SHALLOW,
};
use crate::accel::{PrimHit, Query};
use crate::stats::TraversalStats;
use std::marker::PhantomData;

/// A walk through the tree, generic over the box test: [`run`] runs it on
/// the best copy for this CPU. `walk` is always inlined, so that each copy
/// below compiles it with its own target features.
pub(crate) trait Walk {
    /// What the walk answers.
    type Out;
    /// The walk with box test `bt`.
    fn walk<B: BoxTest>(&mut self, bt: B) -> Self::Out;
}

/// `w` on the AVX2 copy where the CPU has AVX2 and FMA, else on the
/// portable one.
#[inline]
pub(crate) fn run<W: Walk>(w: W) -> W::Out {
    #[cfg(target_arch = "x86_64")]
    if avx2_fma() {
        // SAFETY: calling a `#[target_feature(enable = "avx2,fma")]` function
        // is sound exactly when the CPU supports AVX2 and FMA, checked just
        // above.
        return unsafe { avx2::run(w) };
    }
    portable::run(w)
}

#[cfg(test)]
pub(crate) use portable::run as run_portable;

/// The portable copy, out of line: inlined into [`run`], its stack frame
/// and saved registers were set up on every query even when the AVX2 copy
/// ran (callgrind, scene6_07: 40 instructions a shadow ray in the
/// dispatcher alone).
mod portable {
    use super::*;

    #[inline(never)]
    pub(crate) fn run<W: Walk>(mut w: W) -> W::Out {
        w.walk(Portable)
    }
}

/// The AVX2 copy: the portable traversal inlined into a function compiled
/// with AVX2 and FMA enabled.
#[cfg(target_arch = "x86_64")]
mod avx2 {
    use super::*;
    use crate::accel::bvh8::traverse::Avx;

    #[target_feature(enable = "avx2,fma")]
    pub(super) fn run<W: Walk>(mut w: W) -> W::Out {
        // SAFETY: this function is called only after `avx2_fma()`
        // (`Avx::new`'s contract).
        let avx = unsafe { Avx::new() };
        w.walk(avx)
    }
}

/// Whether the CPU has AVX2 and FMA (each a cached flag).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn avx2_fma() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

/// How a closest-hit walk hands its hit back: the conversion runs in the
/// walk, so that the walk writes the caller's own type (the `Aggregate`
/// answer) straight into the caller's return slot. Converted after the
/// return instead, the hit the walk had just written as 4-byte stores was
/// read back as 16-byte loads, which wait for the stores to reach the cache
/// (a store-forwarding stall at every query; perf, scene6_07: 0.6% of the
/// render).
pub(crate) trait FromClosest {
    fn from_closest(c: Closest) -> Self;
}

impl FromClosest for Closest {
    #[inline(always)]
    fn from_closest(c: Closest) -> Self {
        c
    }
}

impl FromClosest for PrimHit {
    #[inline(always)]
    fn from_closest(c: Closest) -> Self {
        PrimHit { t: c.t, prim: c.id }
    }
}

impl FromClosest for (PrimHit, Option<[f32; 3]>) {
    #[inline(always)]
    fn from_closest(c: Closest) -> Self {
        (PrimHit { t: c.t, prim: c.id }, c.bary)
    }
}

/// The closest hit of one ray in `(tmin, tmax)` (see `traverse::closest`),
/// as an `H` ([`FromClosest`]). With `C`, the walk of a coherent query
/// ([`Query::coherent`]: each descent by the ray's octant, see
/// [`BY_OCTANT`]); a type of its own, so that its copy of the walk is a
/// function of its own too: in one function with the usual walk, the
/// usual walk's code changed and ran 3% slower (`glint bench rays`).
pub(crate) struct ClosestHit<'a, F: ?Sized, S, H = Closest, const C: bool = false> {
    pub tree: Tree<'a, F>,
    /// The ray and its range (the query's `prims` are unused: the tree's
    /// fallback tests the items that are not triangles). By reference, not
    /// copied in: the world writes a query's `tmin` and `tmax` as two 4-byte
    /// stores just before the call, and the copy moved them as one 8-byte
    /// load, which a CPU cannot forward from two stores (a stall of some 15
    /// cycles at every query; perf, scene6_07: 3% of the render in the
    /// wrapper). Read in place, each is loaded on its own.
    pub query: &'a Query<'a>,
    pub stats: &'a mut S,
    pub hit: PhantomData<H>,
}

impl<F: Fallback + ?Sized, S: TraversalStats, H: FromClosest, const C: bool> Walk
    for ClosestHit<'_, F, S, H, C>
{
    type Out = Option<H>;

    /// The ray's constants, then the stack the tree's depth needs.
    #[inline(always)]
    fn walk<B: BoxTest>(&mut self, bt: B) -> Option<H> {
        // By reference, fields read in place: moving `self` or its tree
        // into locals copied them on every query (callgrind: some 25
        // instructions a ray).
        let (t, q) = (&self.tree, self.query);
        let rd = &RayData::new(q.ray);
        let (tmin, tmax, stats) = (q.tmin, q.tmax, &mut *self.stats);
        let hit = match (t.deep, rd.reduce_as_ints(tmin)) {
            (false, true) if C => {
                traverse::closest::<S, F, _, SHALLOW, BY_OCTANT, true>(bt, t, rd, tmin, tmax, stats)
            }
            (false, true) => traverse::closest::<S, F, _, SHALLOW, ANY_OCTANT, true>(
                bt, t, rd, tmin, tmax, stats,
            ),
            (true, true) => {
                traverse::closest::<S, F, _, DEEP, ANY_OCTANT, true>(bt, t, rd, tmin, tmax, stats)
            }
            (false, false) => traverse::closest::<S, F, _, SHALLOW, ANY_OCTANT, false>(
                bt, t, rd, tmin, tmax, stats,
            ),
            (true, false) => {
                traverse::closest::<S, F, _, DEEP, ANY_OCTANT, false>(bt, t, rd, tmin, tmax, stats)
            }
        };
        hit.map(H::from_closest)
    }
}

/// Whether anything but triangle `skip` lies on one ray in `(tmin, tmax)`
/// (see `traverse::any`).
pub(crate) struct AnyHit<'a, F: ?Sized, S> {
    pub tree: Tree<'a, F>,
    /// The ray and its range, by reference (see [`ClosestHit::query`]).
    pub query: &'a Query<'a>,
    pub skip: u32,
    pub stats: &'a mut S,
}

/// `$walk` with `O` the ray's octant as a constant: one copy of the walk per
/// octant, so that the node step loads each of its six planes from a fixed
/// offset in the node (no index reloaded per plane from the stack, where
/// register pressure puts it).
///
/// Used for the any-hit walk only (a coherent closest-hit query picks its
/// octant's copy per descent instead, see [`BY_OCTANT`]). Measured (Intel
/// Xeon, 2 cores): the octant copies took 6.1% fewer instructions an
/// any-hit query and 6.6% a closest one (callgrind, every 16th bunny40k
/// ray); timed, shadow rays ran 4-8% faster and coherent camera rays 2-3%,
/// but incoherent closest-hit rays, which switch octant from ray to ray,
/// 4-13% slower. An AO render (incoherent any-hit rays) kept its time
/// within 1%.
macro_rules! by_octant {
    ($rd:expr, |O| $walk:expr) => {
        by_octant!(@ $rd, $walk, [0 1 2 3 4 5 6] 7)
    };
    (@ $rd:expr, $walk:expr, [$($o:literal)*] $last:literal) => {
        match $rd.octant() {
            $($o => {
                const O: usize = $o;
                $walk
            })*
            _ => {
                const O: usize = $last;
                $walk
            }
        }
    };
}

impl<F: Fallback + ?Sized, S: TraversalStats> Walk for AnyHit<'_, F, S> {
    type Out = bool;

    /// As [`ClosestHit`]'s, with the octant fixed at compile time on the
    /// usual path (see [`by_octant`]).
    #[inline(always)]
    fn walk<B: BoxTest>(&mut self, bt: B) -> bool {
        // Fields read in place (see `ClosestHit`'s walk).
        let (t, q) = (&self.tree, self.query);
        let rd = &RayData::new(q.ray);
        let (range, skip, stats) = ((q.tmin, q.tmax), self.skip, &mut *self.stats);
        any_one(bt, t, rd, range, skip, stats)
    }
}

/// [`AnyHit`]'s walk of one ray: the copy per octant on the usual path
/// (see [`by_octant`]). Also the walk of a packet's rays that the packet
/// walk does not take (`packet::any`), so that they cost no more than
/// alone.
#[inline(always)]
pub(crate) fn any_one<S: TraversalStats, F: Fallback + ?Sized, B: BoxTest>(
    bt: B,
    t: &Tree<F>,
    rd: &RayData,
    range: (f32, f32),
    skip: u32,
    stats: &mut S,
) -> bool {
    match (t.deep, rd.reduce_as_ints(range.0)) {
        (false, true) => by_octant!(rd, |O| traverse::any::<S, F, _, SHALLOW, O, true>(
            bt, t, rd, range, skip, stats
        )),
        (true, true) => {
            traverse::any::<S, F, _, DEEP, ANY_OCTANT, true>(bt, t, rd, range, skip, stats)
        }
        // Rare (a negative `tmin`, an origin beyond about 1e20): one copy
        // per stack, the octant read at run time.
        (false, false) => {
            traverse::any::<S, F, _, SHALLOW, ANY_OCTANT, false>(bt, t, rd, range, skip, stats)
        }
        (true, false) => {
            traverse::any::<S, F, _, DEEP, ANY_OCTANT, false>(bt, t, rd, range, skip, stats)
        }
    }
}

/// The closest hit of each ray of a packet into `out` (see
/// `packet::closest`).
pub(crate) struct ClosestHits<'a, F: ?Sized, S> {
    pub tree: Tree<'a, F>,
    pub rays: &'a [PacketRay],
    pub out: &'a mut [Option<Closest>],
    pub stats: &'a mut S,
}

impl<F: Fallback + ?Sized, S: TraversalStats> Walk for ClosestHits<'_, F, S> {
    type Out = ();

    /// The stack the tree's depth needs.
    #[inline(always)]
    fn walk<B: BoxTest>(&mut self, bt: B) {
        let (tree, rays) = (&self.tree, self.rays);
        let (out, stats) = (&mut *self.out, &mut *self.stats);
        if tree.deep {
            packet::closest::<S, F, B, DEEP>(bt, tree, rays, out, stats)
        } else {
            packet::closest::<S, F, B, SHALLOW>(bt, tree, rays, out, stats)
        }
    }
}

/// Which rays of a packet something but their `skip` blocks (see
/// `packet::any`).
pub(crate) struct AnyHits<'a, F: ?Sized, S> {
    pub tree: Tree<'a, F>,
    pub rays: &'a [PacketRay],
    pub skip: &'a [u32],
    pub stats: &'a mut S,
}

impl<F: Fallback + ?Sized, S: TraversalStats> Walk for AnyHits<'_, F, S> {
    type Out = u32;

    /// The stack the tree's depth needs.
    #[inline(always)]
    fn walk<B: BoxTest>(&mut self, bt: B) -> u32 {
        let (tree, rays, skip) = (&self.tree, self.rays, self.skip);
        let stats = &mut *self.stats;
        if tree.deep {
            packet::any::<S, F, B, DEEP>(bt, tree, rays, skip, stats)
        } else {
            packet::any::<S, F, B, SHALLOW>(bt, tree, rays, skip, stats)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh8::node::NO_ITEM;
    use crate::accel::bvh8::PACKET;
    use crate::accel::testutil::{ray, soup, Rng};
    use crate::accel::Bvh8;
    use crate::stats::Counters;

    /// The portable copy gives the dispatched (AVX2) copy's answers and
    /// statistics, bit for bit, with either stack, for single rays and
    /// packets. Skipped, with a line, on a CPU without AVX2 and FMA (where
    /// both are the portable copy).
    #[test]
    fn the_portable_copy_answers_as_the_dispatched_one() {
        #[cfg(target_arch = "x86_64")]
        if !crate::testdata::avx2_fma("the_portable_copy_answers_as_the_dispatched_one") {
            return;
        }
        let prims = soup(9, 2000);
        let b = Bvh8::new(&prims, (0..prims.len() as u32).collect());
        let mut r = Rng::new(10);
        let (mut hits, mut blocked) = (0, 0);
        let mut packet = Vec::new();
        for _ in 0..1000 {
            let q = ray(&mut r);
            packet.push(PacketRay {
                ray: q,
                tmin: 0.0,
                tmax: 3.0,
            });
            for deep in [false, true] {
                let tree = Tree {
                    deep,
                    ..b.tree(prims.as_slice())
                };
                let (mut c1, mut c2) = (Counters::default(), Counters::default());
                let (to_inf, short) = (
                    Query::new(&[], &q, 0.0, f32::INFINITY),
                    Query::new(&[], &q, 0.0, 0.2),
                );
                let closest = |stats| ClosestHit::<_, _, Closest> {
                    tree,
                    query: &to_inf,
                    stats,
                    hit: PhantomData,
                };
                let want = run(closest(&mut c1));
                let got = run_portable(closest(&mut c2));
                assert_eq!(got, want);
                let any = |stats| AnyHit {
                    tree,
                    query: &short,
                    skip: NO_ITEM,
                    stats,
                };
                let want = run(any(&mut c1));
                let got = run_portable(any(&mut c2));
                assert_eq!(got, want);
                hits += usize::from(want);
                blocked += usize::from(got);
                if packet.len() == PACKET {
                    let rays = &packet[..];
                    let (mut a, mut c) = ([None; PACKET], [None; PACKET]);
                    run(ClosestHits {
                        tree,
                        rays,
                        out: &mut a,
                        stats: &mut c1,
                    });
                    run_portable(ClosestHits {
                        tree,
                        rays,
                        out: &mut c,
                        stats: &mut c2,
                    });
                    assert_eq!(a, c);
                    let skip = &[];
                    let x = run(AnyHits {
                        tree,
                        rays,
                        skip,
                        stats: &mut c1,
                    });
                    let y = run_portable(AnyHits {
                        tree,
                        rays,
                        skip,
                        stats: &mut c2,
                    });
                    assert_eq!(x, y);
                }
                assert_eq!(format!("{c1:?}"), format!("{c2:?}"));
            }
            if packet.len() == PACKET {
                packet.clear();
            }
        }
        assert!((100..1900).contains(&hits) && blocked == hits, "{hits}");
    }
}
