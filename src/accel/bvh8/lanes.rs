//! Eight f32 lanes for the 8-wide node test, as two glam `Vec4`s: two SSE
//! operations each on the x86-64 baseline (VEX-encoded in `dispatch.rs`'s
//! AVX2 copy), scalar elsewhere. No `unsafe`, no `std::arch`: stable,
//! portable Rust. (Plain `[f32; 8]` loops left to LLVM's vectoriser came
//! out as a mix of 4- and 8-lane operations with shuffles to build the
//! mask, and ran slower than the 4-wide tree.)
//!
//! `min` and `max` are glam's SSE `minps`/`maxps`, which return the second
//! operand when either is NaN: the semantics `traverse.rs`'s slab test
//! relies on.

use glam::Vec4;

/// Lanes per node.
pub(crate) const W: usize = 8;

/// Eight f32 lanes: lanes 0–3 in `.0[0]`, 4–7 in `.0[1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub(crate) struct Lanes(pub [Vec4; 2]);

impl Lanes {
    pub const INFINITY: Lanes = Lanes([Vec4::INFINITY; 2]);
    pub const NEG_INFINITY: Lanes = Lanes([Vec4::NEG_INFINITY; 2]);

    #[inline(always)]
    pub fn splat(x: f32) -> Lanes {
        Lanes([Vec4::splat(x); 2])
    }

    /// `self · m − s`, fused (one rounding, on every target: `mul_add` is an
    /// FMA instruction where the CPU has one, else the C library's exact
    /// `fmaf`): the slab distance of one plane per lane.
    #[inline(always)]
    pub fn mul_sub(self, m: Lanes, s: Lanes) -> Lanes {
        Lanes([
            self.0[0].mul_add(m.0[0], -s.0[0]),
            self.0[1].mul_add(m.0[1], -s.0[1]),
        ])
    }

    /// Lane-wise `maxps(self, o)`: `o` when either is NaN.
    #[inline(always)]
    pub fn max(self, o: Lanes) -> Lanes {
        Lanes([self.0[0].max(o.0[0]), self.0[1].max(o.0[1])])
    }

    /// Lane-wise `minps(self, o)`: `o` when either is NaN.
    #[inline(always)]
    pub fn min(self, o: Lanes) -> Lanes {
        Lanes([self.0[0].min(o.0[0]), self.0[1].min(o.0[1])])
    }

    /// Lanes from an array.
    #[inline(always)]
    pub fn from_array(a: [f32; W]) -> Lanes {
        Lanes([Vec4::from_slice(&a[..4]), Vec4::from_slice(&a[4..])])
    }

    /// The smallest lane (`minps` folded: for lanes without NaN, the
    /// minimum).
    #[inline(always)]
    pub fn min_element(self) -> f32 {
        self.0[0].min(self.0[1]).min_element()
    }

    /// The largest lane (`maxps` folded: for lanes without NaN, the
    /// maximum).
    #[inline(always)]
    pub fn max_element(self) -> f32 {
        self.0[0].max(self.0[1]).max_element()
    }

    /// Bit `i` set where lane `i`'s sign bit is.
    #[inline(always)]
    pub fn sign_bits(self) -> u32 {
        self.0[0].is_negative_bitmask() | self.0[1].is_negative_bitmask() << 4
    }

    /// Bit `i` set where lane `i` is finite.
    #[inline(always)]
    pub fn finite_bits(self) -> u32 {
        // `|x| < inf`, false for infinities and NaN (glam's
        // `is_finite_mask` was called out of line).
        let inf = Vec4::INFINITY;
        self.0[0].abs().cmplt(inf).bitmask() | self.0[1].abs().cmplt(inf).bitmask() << 4
    }

    /// The eight lanes as an array (cheap to index by a run-time lane).
    #[inline(always)]
    pub fn to_array(self) -> [f32; W] {
        let (a, b) = (self.0[0].to_array(), self.0[1].to_array());
        [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]]
    }

    /// Bit `i` set where `self[i] <= o[i]`.
    #[inline(always)]
    pub fn le_mask(self, o: Lanes) -> u32 {
        self.0[0].cmple(o.0[0]).bitmask() | self.0[1].cmple(o.0[1]).bitmask() << 4
    }

    /// Lane-wise maximum of the bit patterns read as `i32` (`vpmaxsd`):
    /// the f32 maximum wherever one operand's sign bit is clear, which is
    /// all the slab test needs (see `traverse::RayData::boxes`).
    #[inline(always)]
    pub fn max_bits(self, o: Lanes) -> Lanes {
        self.pick(o, |a, b| a >= b)
    }

    /// Lane-wise minimum of the bit patterns read as `i32` (`vpminsd`).
    #[inline(always)]
    pub fn min_bits(self, o: Lanes) -> Lanes {
        self.pick(o, |a, b| a <= b)
    }

    /// Bit `i` set where `self[i] <= o[i]`, the bit patterns read as `i32`.
    #[inline(always)]
    pub fn le_mask_bits(self, o: Lanes) -> u32 {
        let (a, b) = (self.to_array(), o.to_array());
        (0..W).fold(0, |m, i| m | u32::from(bits(a[i]) <= bits(b[i])) << i)
    }

    /// Per lane, `neg`'s value where `self < 0`, else `pos`'s.
    #[inline(always)]
    pub fn by_sign(self, neg: Lanes, pos: Lanes) -> Lanes {
        let pick = |i: usize| Vec4::select(self.0[i].cmplt(Vec4::ZERO), neg.0[i], pos.0[i]);
        Lanes([pick(0), pick(1)])
    }

    /// The largest lane of those in `mask` (`−inf` for none), or an upper
    /// bound of them: a NaN lane in `mask` counts as `+inf` (`minps`
    /// returns its second operand for NaN), so the bound is `+inf`.
    #[inline(always)]
    pub fn max_of(self, mask: u32) -> f32 {
        // A plain loop (the iterator form, `filter` and `fold`, called its
        // closure out of line once per lane: 11% of a camera packet's
        // instructions). `x > m` is false for NaN.
        // Lanes outside `mask` lowered to `−inf` by a `minps` against a
        // table of `±inf` per four-bit nibble, then one reduction (a loop
        // over the lanes' bits branched or called a closure per lane: 5-11%
        // of a camera packet's instructions).
        let lo = self.0[0].min(KEEP[mask as usize & 15]);
        let hi = self.0[1].min(KEEP[mask as usize >> 4 & 15]);
        lo.max(hi).max_element()
    }

    /// Per lane, `self`'s value where `keep(self, o)` on the bit patterns
    /// read as `i32`, else `o`'s.
    #[inline(always)]
    fn pick(self, o: Lanes, keep: impl Fn(i32, i32) -> bool) -> Lanes {
        let (a, b) = (self.to_array(), o.to_array());
        let v: [f32; W] = std::array::from_fn(|i| {
            if keep(bits(a[i]), bits(b[i])) {
                a[i]
            } else {
                b[i]
            }
        });
        Lanes([
            Vec4::new(v[0], v[1], v[2], v[3]),
            Vec4::new(v[4], v[5], v[6], v[7]),
        ])
    }
}

/// Per four-bit mask, four lanes of `+inf` where its bit is set and `−inf`
/// where clear ([`Lanes::max_of`]).
const KEEP: [Vec4; 16] = {
    const fn lane(m: usize, i: usize) -> f32 {
        if m >> i & 1 != 0 {
            f32::INFINITY
        } else {
            f32::NEG_INFINITY
        }
    }
    let mut t = [Vec4::ZERO; 16];
    let mut m = 0;
    while m < 16 {
        t[m] = Vec4::new(lane(m, 0), lane(m, 1), lane(m, 2), lane(m, 3));
        m += 1;
    }
    t
};

/// An f32's bit pattern as an `i32`: ordered as the f32 values are among
/// values with the sign bit clear (`+0` to `+inf`); every value with the
/// sign bit set (`−0` included) is below them all.
#[inline(always)]
fn bits(x: f32) -> i32 {
    x.to_bits() as i32
}

impl std::ops::Index<usize> for Lanes {
    type Output = f32;
    #[inline(always)]
    fn index(&self, i: usize) -> &f32 {
        // Through the array: `Vec4`'s own index is a `match`, a jump table
        // for a run-time lane.
        &self.0[i / 4].as_ref()[i % 4]
    }
}

impl std::ops::IndexMut<usize> for Lanes {
    #[inline(always)]
    fn index_mut(&mut self, i: usize) -> &mut f32 {
        &mut self.0[i / 4].as_mut()[i % 4]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lanes(x: [f32; 8]) -> Lanes {
        let mut l = Lanes::splat(0.0);
        for (i, x) in x.into_iter().enumerate() {
            l[i] = x;
        }
        l
    }

    #[test]
    fn nan_gives_the_second_operand() {
        let a = lanes([f32::NAN, 1.0, 2.0, f32::NAN, 0.0, 5.0, -1.0, 3.0]);
        let b = lanes([4.0, f32::NAN, 1.0, 2.0, 1.0, 6.0, -2.0, 3.0]);
        let mx = a.max(b);
        let mn = a.min(b);
        assert_eq!(mx[0], 4.0);
        assert!(mx[1].is_nan());
        assert_eq!(
            (mx[2], mx[3], mx[4], mx[5], mx[6]),
            (2.0, 2.0, 1.0, 6.0, -1.0)
        );
        assert_eq!(mn[0], 4.0);
        assert!(mn[1].is_nan());
        assert_eq!((mn[2], mn[4], mn[5], mn[6]), (1.0, 0.0, 5.0, -2.0));
        assert_eq!(a.le_mask(b), 0b1011_0000);
        let x = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        assert_eq!(lanes(x).to_array(), x);
    }

    /// The packet walk's helpers: finite and sign bits, the extremes, and
    /// the largest lane of a mask (a NaN in the mask bounds it at `+inf`).
    #[test]
    fn lane_bits_and_extremes() {
        let a = lanes([
            1.0,
            -0.0,
            f32::INFINITY,
            f32::NAN,
            -3.0,
            0.0,
            f32::NEG_INFINITY,
            2.5,
        ]);
        assert_eq!(a.finite_bits(), 0b1011_0011);
        assert_eq!(a.sign_bits() & !(1 << 3), 0b0101_0010);
        let b = lanes([1.0, -2.0, 7.0, 0.5, -3.0, 0.0, 4.0, 2.5]);
        assert_eq!((b.min_element(), b.max_element()), (-3.0, 7.0));
        assert_eq!(b.max_of(0b1000_0011), 2.5);
        assert_eq!(b.max_of(0b0100_0000), 4.0);
        assert_eq!(b.max_of(0), f32::NEG_INFINITY);
        assert_eq!(a.max_of(0b0001_0001), 1.0);
        assert_eq!(a.max_of(0b0001_1001), f32::INFINITY);
        assert_eq!(Lanes::from_array(b.to_array()), b);
    }

    /// The integer forms agree with the float ones wherever one operand is
    /// `≥ +0`, and put every negative value (`−0` included) below `+0`.
    #[test]
    fn bit_patterns_order_like_floats_from_plus_zero() {
        let a = lanes([0.5, 2.0, -3.0, -0.0, 0.0, f32::INFINITY, -1.0, 1e-40]);
        let b = lanes([1.0, 0.0, 0.0, 0.0, -0.0, 7.0, -2.0, 0.0]);
        assert_eq!(
            a.max_bits(b).to_array().map(f32::to_bits),
            [1.0, 2.0, 0.0, 0.0, 0.0, f32::INFINITY, -2.0, 1e-40].map(f32::to_bits)
        );
        // Between two negatives the order is reversed (the integer maximum
        // of −1 and −2 is −2, the minimum −1): harmless where the other
        // side of the test is `≥ +0`.
        assert_eq!(
            a.min_bits(b).to_array().map(f32::to_bits),
            [0.5, 0.0, -3.0, -0.0, -0.0, 7.0, -1.0, 0.0].map(f32::to_bits)
        );
        assert_eq!(a.le_mask_bits(b), 0b0100_1101);
    }
}
