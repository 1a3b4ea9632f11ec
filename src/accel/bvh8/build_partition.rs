//! The build's partition of a range of references: in place with the
//! sides' bounds gathered in the same pass, or without a branch per item
//! (BlockQuicksort) for ranges whose items change sides often.

use super::PrimRef;
use crate::math::Aabb;
use glam::Vec3A;
use rayon::prelude::*;

/// Bounds and centroid bounds, accumulated item by item.
pub(super) struct Acc {
    lo: Vec3A,
    hi: Vec3A,
    clo: Vec3A,
    chi: Vec3A,
}

impl Acc {
    pub(super) fn new() -> Self {
        Acc {
            lo: Vec3A::INFINITY,
            hi: Vec3A::NEG_INFINITY,
            clo: Vec3A::INFINITY,
            chi: Vec3A::NEG_INFINITY,
        }
    }

    #[inline(always)]
    pub(super) fn add(&mut self, lo: Vec3A, hi: Vec3A, c: Vec3A) {
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
        self.clo = self.clo.min(c);
        self.chi = self.chi.max(c);
    }

    pub(super) fn union(&self, o: &Acc) -> Acc {
        Acc {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
            clo: self.clo.min(o.clo),
            chi: self.chi.max(o.chi),
        }
    }

    pub(super) fn boxes(&self) -> (Aabb, Aabb) {
        (
            Aabb::new(self.lo.into(), self.hi.into()),
            Aabb::new(self.clo.into(), self.chi.into()),
        )
    }
}

/// Ranges of up to this many items (in the cache) whose sides alternate
/// often are partitioned without a branch per item (see [`partition`]).
pub(super) const BLOCK_PARTITION_MAX: usize = 8 * 1024;
/// The block of [`block_partition`].
pub(super) const BLOCK: usize = 64;

/// Partition: items for which `left` holds first. Returns their count and
/// both sides' bounds and centroid bounds. Two ways to the same sides:
/// when the first 32 items change sides at least four times (an unordered
/// mesh, like a scan), a branch per item would often be mispredicted, and
/// [`block_partition`] has none (the bounds then take a second pass over
/// the cached range); otherwise (long runs, as in a mesh stored in order,
/// or a range too large for the cache) the in-place loop gathers the
/// bounds in the same pass. Measured (build, 1 thread): bunny40k 7-9%
/// faster, the spheres (stored in order) within 2%. `parallel`: the range
/// goes to [`parallel_partition`], which gives the in-place loop's
/// permutation (for ranges of at least `PARALLEL_PARTITION` items only:
/// below, the serial ways may differ from it).
pub(super) fn partition(
    v: &mut [PrimRef],
    left: impl Fn(Vec3A) -> bool + Sync,
    parallel: bool,
) -> (usize, (Aabb, Aabb), (Aabb, Aabb)) {
    let n = v.len();
    if parallel {
        assert!(
            n >= PARALLEL_PARTITION,
            "the parallel partition of a small range"
        );
        return parallel_partition(v, left);
    }
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
pub(super) fn side_changes(v: &[PrimRef], left: &impl Fn(Vec3A) -> bool) -> usize {
    let sides = v.iter().map(|p| left(p.centroid()));
    sides
        .clone()
        .zip(sides.skip(1))
        .filter(|(a, b)| a != b)
        .count()
}

/// In-place partition with the bounds gathered in the same pass (a second
/// pass over a large range costs as much as the partition).
pub(super) fn fused_partition(
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
pub(super) fn block_partition(v: &mut [PrimRef], left: &impl Fn(Vec3A) -> bool) -> usize {
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

/// Ranges of at least this many items are partitioned on several threads
/// (when there are several, and fewer tasks than threads to keep them
/// busy).
pub(super) const PARALLEL_PARTITION: usize = 32 * 1024;
/// Ranges of at least this many items are partitioned on several threads
/// whatever else runs.
pub(super) const SHARED_PARALLEL_PARTITION: usize = 256 * 1024;
/// Items per task of [`parallel_partition`]'s passes (a multiple of 64:
/// each task owns whole words of the side bits).
const PARALLEL_CHUNK: usize = 8 * 1024;

/// [`fused_partition`] on several threads, with the same result: the same
/// permutation of `v` (not only the same sides), so that the tree built
/// on top is the same item for item whatever the thread count.
///
/// The in-place loop swaps the `t`-th item from the left that goes right
/// with the `t`-th item from the right that goes left, until the two
/// scans meet at `k`, the count going left; so the items it moves are
/// exactly those on the wrong side of `k`, paired in that order. Here:
/// one pass in chunks records each item's side (a bit) and gathers both
/// sides' bounds (min and max: the same whatever the order); the count
/// gives `k`; then the pairs are swapped in parallel pieces, each walking
/// the bits from its first pair (found by counting bits, [`Sides::nth`]),
/// and touching slices of `v` that no other piece touches. (Lists of the
/// misplaced items' positions, gathered and then read, cost a tenth more
/// than the whole partition on a 1M-item range.)
pub(super) fn parallel_partition(
    v: &mut [PrimRef],
    left: impl Fn(Vec3A) -> bool + Sync,
) -> (usize, (Aabb, Aabb), (Aabb, Aabb)) {
    const { assert!(PARALLEL_CHUNK.is_multiple_of(64)) };
    let n = v.len();
    let mut bits = vec![0u64; n.div_ceil(64)];
    let (k, l, r) = v
        .par_chunks(PARALLEL_CHUNK)
        .zip(bits.par_chunks_mut(PARALLEL_CHUNK / 64))
        .map(|(items, bits)| {
            let (mut l, mut r, mut k) = (Acc::new(), Acc::new(), 0);
            for (items, word) in items.chunks(64).zip(bits.iter_mut()) {
                let mut w = 0u64;
                for (i, p) in items.iter().enumerate() {
                    let c = p.centroid();
                    let goes_left = left(c);
                    if goes_left {
                        l.add(p.lo(), p.hi(), c);
                    } else {
                        r.add(p.lo(), p.hi(), c);
                    }
                    w |= (goes_left as u64) << i;
                }
                *word = w;
                k += w.count_ones() as usize;
            }
            (k, l, r)
        })
        .reduce(
            || (0, Acc::new(), Acc::new()),
            |a, b| (a.0 + b.0, a.1.union(&b.1), a.2.union(&b.2)),
        );
    let sides = Sides::new(&bits, n);
    // The misplaced: zeros below `k` (they go right), ones from `k` on
    // (they go left), as many of each; every zero below `k` comes before
    // any zero above it, every one from `k` on after any one below it.
    let m = k - sides.ones_below(k);
    if m == 0 {
        return (k, l.boxes(), r.boxes());
    }
    let ones = sides.ones_below(n);
    // Pair `t`: the `t`-th zero (ascending) with the `t`-th one from the
    // top. Pieces of pairs `[t0, t1)` own `v[zero(t0)..zero(t1))` on the
    // left (`zero(m)`: `k`) and `v[one(t1)+1..one(t0)+1)` on the right.
    let per = PARALLEL_CHUNK.max(m.div_ceil(4 * rayon::current_num_threads().max(1)));
    let zero = |t: usize| if t == m { k } else { sides.nth(t, false) };
    let top = |t: usize| {
        if t == m {
            k
        } else {
            sides.nth(ones - 1 - t, true) + 1
        }
    };
    let (lo, hi) = v.split_at_mut(k);
    // `lo` starts where the next piece's left side does, `hi` ends where
    // its right side does.
    let (mut lo, mut hi) = (&mut lo[zero(0)..], &mut hi[..top(0) - k]);
    let mut pieces = Vec::with_capacity(m.div_ceil(per));
    for t0 in (0..m).step_by(per) {
        let t1 = (t0 + per).min(m);
        let (a0, a1) = (zero(t0), zero(t1));
        let (b0, b1) = (top(t1), top(t0));
        let (mine, rest) = std::mem::take(&mut lo).split_at_mut(a1 - a0);
        lo = rest;
        let cut = hi.len() - (b1 - b0);
        let (rest, theirs) = std::mem::take(&mut hi).split_at_mut(cut);
        hi = rest;
        pieces.push(((mine, a0), (theirs, b0), t1 - t0));
    }
    pieces
        .into_par_iter()
        .for_each(|((a, a0), (b, b0), pairs)| {
            // Zeros ascending from `a0`, ones descending from the top of `b`.
            let zeros = sides.from(a0, false);
            let down = sides.down_from(b0 + b.len(), true);
            for (i, j) in zeros.zip(down).take(pairs) {
                std::mem::swap(&mut a[i - a0], &mut b[j - b0]);
            }
        });
    (k, l.boxes(), r.boxes())
}

/// The sides of a range's items, a bit per item (1: left), with counts of
/// ones before each word for finding the `t`-th one or zero.
pub(super) struct Sides<'a> {
    bits: &'a [u64],
    /// Ones in the words before each word (and in all of them, last).
    before: Vec<u32>,
}

impl<'a> Sides<'a> {
    pub(super) fn new(bits: &'a [u64], n: usize) -> Self {
        debug_assert!(bits.len() == n.div_ceil(64) && n < u32::MAX as usize);
        let mut before = Vec::with_capacity(bits.len() + 1);
        let mut c = 0;
        for w in bits {
            before.push(c);
            c += w.count_ones();
        }
        before.push(c);
        Sides { bits, before }
    }

    /// Ones among the first `i` items.
    pub(super) fn ones_below(&self, i: usize) -> usize {
        let (w, b) = (i / 64, i % 64);
        let partial = if b == 0 {
            0
        } else {
            (self.bits[w] & ((1u64 << b) - 1)).count_ones()
        };
        (self.before[w] + partial) as usize
    }

    /// Where the `t`-th (from 0) one, or zero, is; it must exist (zeros
    /// past the last item do not count: only the last word has them, and
    /// no zero asked for lies beyond the ones that follow it).
    pub(super) fn nth(&self, t: usize, one: bool) -> usize {
        let count = |w: usize| {
            let ones = self.before[w] as usize;
            if one {
                ones
            } else {
                64 * w - ones
            }
        };
        // The last word whose count before it is at most `t`.
        let (mut w, mut end) = (0, self.bits.len());
        while w < end {
            let mid = (w + end) / 2;
            if count(mid + 1) <= t {
                w = mid + 1;
            } else {
                end = mid;
            }
        }
        let mut word = if one { self.bits[w] } else { !self.bits[w] };
        for _ in 0..t - count(w) {
            word &= word - 1;
        }
        64 * w + word.trailing_zeros() as usize
    }

    /// The positions of ones (or zeros) from `i` on, ascending (as many as
    /// asked for: they must exist).
    pub(super) fn from(&self, i: usize, one: bool) -> impl Iterator<Item = usize> + '_ {
        let pick = move |w: u64| if one { w } else { !w };
        let (mut w, mut word) = (i / 64, pick(self.bits[i / 64]) & (u64::MAX << (i % 64)));
        std::iter::from_fn(move || {
            while word == 0 {
                w += 1;
                word = pick(self.bits[w]);
            }
            let at = 64 * w + word.trailing_zeros() as usize;
            word &= word - 1;
            Some(at)
        })
    }

    /// The positions of ones (or zeros) below `end`, descending.
    pub(super) fn down_from(&self, end: usize, one: bool) -> impl Iterator<Item = usize> + '_ {
        let pick = move |w: u64| if one { w } else { !w };
        let (last, b) = ((end - 1) / 64, (end - 1) % 64);
        let (mut w, mut word) = (last, pick(self.bits[last]) & (u64::MAX >> (63 - b)));
        std::iter::from_fn(move || {
            while word == 0 {
                w -= 1;
                word = pick(self.bits[w]);
            }
            let top = 63 - word.leading_zeros() as usize;
            word &= !(1u64 << top);
            Some(64 * w + top)
        })
    }
}
