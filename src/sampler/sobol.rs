//! Owen-scrambled Sobol points, hash-based (Burley, "Practical Hash-based
//! Owen Scrambling", JCGT 2020).
//!
//! The first two Sobol dimensions form a (0,2)-sequence: every prefix of
//! 2^m points has exactly one point in each of the 2^m elementary intervals
//! of any shape. A nested uniform (Owen) scramble keeps that property while
//! making every pixel's set independent and the estimate unbiased. Higher
//! dimensions of the sample stream reuse the same two dimensions with the
//! sample index itself Owen-scrambled by a different seed per dimension
//! ("padding"), which decorrelates them without needing high Sobol
//! dimensions (which are poorly stratified in 2-D projections anyway).
//! The one exception is the first 2-D value after the pixel position: it
//! takes Sobol dimensions 2 and 3 of the pixel's own point
//! ([`point_2d_upper`]), so that pixel position and lens point (or
//! whatever comes first) are stratified together in 4-D.

/// Sobol dimension 0: the van der Corput sequence, i.e. the bits of `i`
/// reversed into a 32-bit binary fraction. (The definition, for tests:
/// [`scrambled_dim0`] folds it into the scramble.)
#[cfg(test)]
pub fn sobol_dim0(i: u32) -> u32 {
    i.reverse_bits()
}

/// Sobol dimension 1 (primitive polynomial `x + 1`): the direction numbers
/// follow `v_{k+1} = v_k ^ (v_k >> 1)` from `v_0 = 1/2`, and the point is
/// the XOR of `v_k` over the set bits `k` of `i`. That is linear over bits,
/// so it is the XOR of one table entry per byte of `i`: the same value as
/// the bit-by-bit loop ([`sobol_dim1_bits`]) in four lookups instead of up
/// to 32 steps (the loop was the largest part of a 16-spp render's
/// sampling). (For tests: [`point_2d`] uses the reversed table directly.)
#[cfg(test)]
pub fn sobol_dim1(i: u32) -> u32 {
    sobol_dim1_reversed(i).reverse_bits()
}

/// [`sobol_dim1`] with its bits reversed, straight from the table
/// ([`DIM1_REV_BYTES`]: bit reversal is linear over XOR, so the table holds
/// reversed entries), for the Owen scramble, which works on reversed bits.
#[inline]
fn sobol_dim1_reversed(i: u32) -> u32 {
    let t = &DIM1_REV_BYTES;
    t[0][(i & 0xff) as usize]
        ^ t[1][(i >> 8 & 0xff) as usize]
        ^ t[2][(i >> 16 & 0xff) as usize]
        ^ t[3][(i >> 24) as usize]
}

/// [`sobol_dim1`] bit by bit: the definition, which builds the table.
const fn sobol_dim1_bits(mut i: u32) -> u32 {
    let mut v = 1u32 << 31;
    let mut r = 0u32;
    while i != 0 {
        if i & 1 != 0 {
            r ^= v;
        }
        i >>= 1;
        v ^= v >> 1;
    }
    r
}

/// `DIM1_REV_BYTES[k][b]`: [`sobol_dim1_bits`] of byte `b` placed at byte
/// `k` of the index, bits reversed (4 KB, computed at compile time).
static DIM1_REV_BYTES: [[u32; 256]; 4] = {
    let mut t = [[0u32; 256]; 4];
    let mut k = 0;
    while k < 4 {
        let mut b = 0;
        while b < 256 {
            t[k][b] = sobol_dim1_bits((b as u32) << (8 * k)).reverse_bits();
            b += 1;
        }
        k += 1;
    }
    t
};

/// Direction numbers of a Sobol dimension as 32-bit binary fractions: the
/// primitive polynomial of degree `s` with inner coefficients `a` (bit
/// `s − 1 − j` is the coefficient of `x^(s−j)`) and initial odd integers
/// `m` (Joe and Kuo's `new-joe-kuo-6.21201` table, the source of every
/// common Sobol implementation). `v_k = m_k / 2^(k+1)` for the first `s`,
/// then `v_k = v_(k−s) ⊕ v_(k−s)/2^s ⊕ ⨁_j a_j v_(k−j)`.
const fn direction_numbers(s: usize, a: u32, m: [u32; 3]) -> [u32; 32] {
    let mut v = [0u32; 32];
    let mut k = 0;
    while k < 32 {
        if k < s {
            v[k] = m[k] << (31 - k);
        } else {
            let mut x = v[k - s] ^ (v[k - s] >> s);
            let mut j = 1;
            while j < s {
                if (a >> (s - 1 - j)) & 1 != 0 {
                    x ^= v[k - j];
                }
                j += 1;
            }
            v[k] = x;
        }
        k += 1;
    }
    v
}

/// Sobol dimensions 2 (`x² + x + 1`, m = 1, 3) and 3 (`x³ + x + 1`,
/// m = 1, 3, 1).
const DIRECTIONS_2_3: [[u32; 32]; 2] = [
    direction_numbers(2, 1, [1, 3, 0]),
    direction_numbers(3, 1, [1, 3, 1]),
];

/// Sobol dimension `d` (2 or 3) of index `i`, bit by bit (builds the
/// tables; the definition, for tests).
const fn sobol_upper_bits(d: usize, mut i: u32) -> u32 {
    let v = &DIRECTIONS_2_3[d - 2];
    let mut r = 0u32;
    let mut k = 0;
    while i != 0 {
        if i & 1 != 0 {
            r ^= v[k];
        }
        i >>= 1;
        k += 1;
    }
    r
}

/// `UPPER_REV_BYTES[d − 2][k][b]`: [`sobol_upper_bits`] of byte `b` at byte
/// `k` of the index, bits reversed, as [`DIM1_REV_BYTES`] (8 KB).
static UPPER_REV_BYTES: [[[u32; 256]; 4]; 2] = {
    let mut t = [[[0u32; 256]; 4]; 2];
    let mut d = 0;
    while d < 2 {
        let mut k = 0;
        while k < 4 {
            let mut b = 0;
            while b < 256 {
                t[d][k][b] = sobol_upper_bits(d + 2, (b as u32) << (8 * k)).reverse_bits();
                b += 1;
            }
            k += 1;
        }
        d += 1;
    }
    t
};

/// Sobol dimension `2 + d` (`d` 0 or 1) of `i`, bits reversed.
#[inline]
fn sobol_upper_reversed(d: usize, i: u32) -> u32 {
    let t = &UPPER_REV_BYTES[d];
    t[0][(i & 0xff) as usize]
        ^ t[1][(i >> 8 & 0xff) as usize]
        ^ t[2][(i >> 16 & 0xff) as usize]
        ^ t[3][(i >> 24) as usize]
}

/// Sobol dimensions 2 and 3 of the point `index` whose dimensions 0 and 1
/// [`point_2d`] gives for the same `index` and `shuffle`, Owen-scrambled by
/// `sx` and `sy`. Together the four coordinates are a scrambled Sobol
/// (t, 4)-sequence with t = 3: every prefix of 2^m points puts exactly 8
/// in each elementary box of volume 2^(3−m), so a pixel's positions and
/// the next 2-D decision (a lens point) are stratified jointly, not only
/// each on its own.
#[cfg(test)]
pub fn point_2d_upper(index: u32, shuffle: u32, sx: u32, sy: u32) -> (u32, u32) {
    reverse_pair(upper_reversed(owen_scramble(index, shuffle), sx, sy))
}

/// [`point_2d_upper`] of the already shuffled index `i`
/// (`owen_scramble(index, shuffle)`), both coordinates still bit-reversed
/// (for [`unit_pair`]).
#[inline]
pub fn upper_reversed(i: u32, sx: u32, sy: u32) -> (u32, u32) {
    (
        laine_karras(sobol_upper_reversed(0, i), sx),
        laine_karras(sobol_upper_reversed(1, i), sy),
    )
}

/// Laine and Karras's hash, improved by Burley: a permutation of `x` in which
/// each bit depends only on the bits below it. Applied to bit-reversed values
/// it is a nested uniform scramble.
#[inline]
fn laine_karras(mut x: u32, seed: u32) -> u32 {
    x ^= x.wrapping_mul(0x3d20_adea);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6c56);
    x ^= x.wrapping_mul(0x53a2_2864);
    x
}

/// Nested uniform (Owen) scramble of a 32-bit binary fraction: each bit is
/// flipped by a hash of the bits above it.
#[cfg(test)]
pub fn owen_scramble(x: u32, seed: u32) -> u32 {
    laine_karras(x.reverse_bits(), seed).reverse_bits()
}

/// The 2-D point `index` of the Owen-scrambled Sobol (0,2)-sequence, with the
/// index shuffled by `shuffle` and the two coordinates scrambled by `sx` and
/// `sy`, as 32-bit binary fractions.
///
/// Written with four bit reversals instead of the definition's seven
/// (`owen_scramble(sobol_dim0(i), sx)`, `owen_scramble(sobol_dim1(i), sy)`):
/// the scramble reverses its argument first, which undoes `sobol_dim0`'s
/// reversal, and dimension 1 comes reversed from its table. Same values (a
/// unit test compares with the definition). The samplers go further, from
/// the parts below: a stream reverses its index once
/// ([`shuffle_reversed`]), and the coordinates' final reversals are folded
/// into their conversion to floats ([`unit_pair`]).
#[cfg(test)]
pub fn point_2d(index: u32, shuffle: u32, sx: u32, sy: u32) -> (u32, u32) {
    reverse_pair(point_reversed(owen_scramble(index, shuffle), sx, sy))
}

/// [`point_2d`] of the already shuffled index `i`
/// (`owen_scramble(index, shuffle)`), both coordinates still bit-reversed
/// (for [`unit_pair`]).
#[inline]
pub fn point_reversed(i: u32, sx: u32, sy: u32) -> (u32, u32) {
    (
        laine_karras(i, sx),
        laine_karras(sobol_dim1_reversed(i), sy),
    )
}

/// `owen_scramble(index, shuffle)` from `index.reverse_bits()`: a stream
/// reverses its index once for all its dimensions, so the scramble's first
/// reversal is not repeated per value.
#[inline]
pub fn shuffle_reversed(index_reversed: u32, shuffle: u32) -> u32 {
    reverse(laine_karras(index_reversed, shuffle))
}

/// `REVERSED_BYTES[k][b]`: byte `b` at byte `k` of a `u32`, bits reversed
/// (4 KB, computed at compile time). Bit reversal is an OR of one entry per
/// byte.
static REVERSED_BYTES: [[u32; 256]; 4] = {
    let mut t = [[0u32; 256]; 4];
    let mut k = 0;
    while k < 4 {
        let mut b = 0;
        while b < 256 {
            t[k][b] = ((b as u32) << (8 * k)).reverse_bits();
            b += 1;
        }
        k += 1;
    }
    t
};

/// `x.reverse_bits()` by table: four loads and ORs. On the x86-64 baseline
/// there is no reversal instruction, and `reverse_bits` is a byte swap and
/// three mask-and-shift rounds (about 17 instructions).
#[inline]
pub fn reverse(x: u32) -> u32 {
    let t = &REVERSED_BYTES;
    t[0][(x & 0xff) as usize]
        | t[1][(x >> 8 & 0xff) as usize]
        | t[2][(x >> 16 & 0xff) as usize]
        | t[3][(x >> 24) as usize]
}

/// `unit_from_u32(x.reverse_bits())`: only the top 24 bits of the reversal
/// are kept, the reversal of the low three bytes of `x`, so the top byte's
/// entry is not needed.
#[inline]
fn unit_reversed(x: u32) -> f32 {
    let t = &REVERSED_BYTES;
    let top = t[0][(x & 0xff) as usize]
        | t[1][(x >> 8 & 0xff) as usize]
        | t[2][(x >> 16 & 0xff) as usize];
    (top >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// Both coordinates reversed.
#[cfg(test)]
fn reverse_pair((a, b): (u32, u32)) -> (u32, u32) {
    (a.reverse_bits(), b.reverse_bits())
}

/// `Vec2(unit_from_u32(a.reverse_bits()), unit_from_u32(b.reverse_bits()))`:
/// a point from its bit-reversed coordinates.
#[inline]
pub fn unit_pair((a, b): (u32, u32)) -> crate::math::Vec2 {
    crate::math::Vec2::new(unit_reversed(a), unit_reversed(b))
}

/// `owen_scramble(sobol_dim0(i), seed)`: the scramble's first reversal
/// undoes `sobol_dim0`'s.
#[cfg(test)]
pub fn scrambled_dim0(i: u32, seed: u32) -> u32 {
    laine_karras(i, seed).reverse_bits()
}

/// `unit_from_u32(scrambled_dim0(i, seed))`.
#[inline]
pub fn unit_dim0(i: u32, seed: u32) -> f32 {
    unit_reversed(laine_karras(i, seed))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first 2^m points fall one in each elementary interval of every
    /// shape 2^a × 2^(m−a): the defining (0,2) property, which the scramble
    /// must keep.
    #[test]
    fn scrambled_prefixes_are_0_2_nets() {
        for (shuffle, sx, sy) in [(0, 0, 0), (17, 0xabc, 0x12345), (0xdead, 0xbeef, 0xcafe)] {
            for m in 0..=8u32 {
                let n = 1u32 << m;
                for a in 0..=m {
                    let (bx, by) = (a, m - a);
                    let mut seen = vec![false; n as usize];
                    for i in 0..n {
                        let (x, y) = point_2d(i, shuffle, sx, sy);
                        let cx = if bx == 0 { 0 } else { x >> (32 - bx) };
                        let cy = if by == 0 { 0 } else { y >> (32 - by) };
                        let cell = (cy << bx | cx) as usize;
                        assert!(!seen[cell], "m={m} a={a}: cell {cell} twice");
                        seen[cell] = true;
                    }
                }
            }
        }
    }

    /// `point_2d` and `scrambled_dim0` give the definition's values.
    #[test]
    fn points_are_the_definitions() {
        let mut x = 0x2545_f491u32;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x
        };
        for k in 0..100_000u32 {
            let (index, shuffle, sx, sy) =
                (if k < 4096 { k } else { next() }, next(), next(), next());
            let i = owen_scramble(index, shuffle);
            let want = (
                owen_scramble(sobol_dim0(i), sx),
                owen_scramble(sobol_dim1(i), sy),
            );
            assert_eq!(point_2d(index, shuffle, sx, sy), want);
            assert_eq!(scrambled_dim0(i, sx), want.0);
            let want_upper = (
                owen_scramble(sobol_upper_bits(2, i), sx),
                owen_scramble(sobol_upper_bits(3, i), sy),
            );
            assert_eq!(point_2d_upper(index, shuffle, sx, sy), want_upper);
            assert_eq!(shuffle_reversed(index.reverse_bits(), shuffle), i);
            let (x, y) = point_reversed(i, sx, sy);
            let unit = |v: u32| crate::sampler::hash::unit_from_u32(v.reverse_bits());
            assert_eq!(unit_pair((x, y)), crate::math::Vec2::new(unit(x), unit(y)));
        }
    }

    /// Dimensions 0 to 3 of the same index form a (3, 4)-sequence: the
    /// first 2^m points (any shuffle and scrambles) put exactly 8 points in
    /// every elementary box `2^-a0 × 2^-a1 × 2^-a2 × 2^-a3` with
    /// `a0 + a1 + a2 + a3 = m − 3`. Wrong direction numbers break it.
    #[test]
    fn four_dimensions_form_a_3_4_sequence() {
        for (shuffle, s) in [(0u32, [0u32; 4]), (0x9e37, [5, 0xabc, 0x1234_5678, 77])] {
            for m in 3..=10u32 {
                let n = 1u32 << m;
                let pts: Vec<[u32; 4]> = (0..n)
                    .map(|i| {
                        let (x0, x1) = point_2d(i, shuffle, s[0], s[1]);
                        let (x2, x3) = point_2d_upper(i, shuffle, s[2], s[3]);
                        [x0, x1, x2, x3]
                    })
                    .collect();
                let k = m - 3;
                for a0 in 0..=k {
                    for a1 in 0..=k - a0 {
                        for a2 in 0..=k - a0 - a1 {
                            let a = [a0, a1, a2, k - a0 - a1 - a2];
                            let mut count = vec![0u32; 1 << k];
                            for p in &pts {
                                let mut cell = 0usize;
                                for d in 0..4 {
                                    let c = if a[d] == 0 { 0 } else { p[d] >> (32 - a[d]) };
                                    cell = cell << a[d] | c as usize;
                                }
                                count[cell] += 1;
                            }
                            assert!(count.iter().all(|&c| c == 8), "m={m} a={a:?}");
                        }
                    }
                }
            }
        }
    }

    /// The upper dimensions' first values in plain index order (Joe and
    /// Kuo's, as SciPy lists them in Gray-code order: 0, .5, .25, .75,
    /// .625, .125, .875, .375 for dimension 2), and the tables are the bit
    /// loop.
    #[test]
    fn upper_dimensions_match_known_values() {
        let d2 = [0.0, 0.5, 0.75, 0.25, 0.375, 0.875, 0.625, 0.125];
        let d3 = [0.0, 0.5, 0.75, 0.25, 0.125, 0.625, 0.875, 0.375];
        for i in 0..8u32 {
            let f = |d| sobol_upper_bits(d, i) as f64 / 4294967296.0;
            assert_eq!((f(2), f(3)), (d2[i as usize], d3[i as usize]), "index {i}");
        }
        let mut x = 0x9e37_79b9u32;
        for _ in 0..10_000 {
            x = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            for d in 0..2 {
                assert_eq!(
                    sobol_upper_reversed(d, x).reverse_bits(),
                    sobol_upper_bits(d + 2, x)
                );
            }
        }
    }

    #[test]
    fn table_reversal_is_reverse_bits() {
        let mut x = 0x9e37_79b9u32;
        for i in (0..70_000).chain([u32::MAX, 1 << 31, 0x00ff_ff00]) {
            x = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            for v in [i, x] {
                assert_eq!(reverse(v), v.reverse_bits());
                let unit = crate::sampler::hash::unit_from_u32(v.reverse_bits());
                assert_eq!(unit_reversed(v), unit);
                assert_eq!(unit_dim0(v, x), {
                    crate::sampler::hash::unit_from_u32(scrambled_dim0(v, x))
                });
            }
        }
    }

    #[test]
    fn dimension_1_table_is_the_bit_loop() {
        let mut x = 0x9e37_79b9u32;
        for i in (0..70_000).chain([u32::MAX, 1 << 31, 0x00ff_ff00]) {
            x = x.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
            assert_eq!(sobol_dim1(i), sobol_dim1_bits(i));
            assert_eq!(sobol_dim1(x), sobol_dim1_bits(x));
        }
    }

    #[test]
    fn dimension_1_matches_known_values() {
        // Sobol's second dimension in plain (not Gray-code) index order.
        let want = [0.0, 0.5, 0.75, 0.25, 0.625, 0.125, 0.375, 0.875];
        for (i, w) in want.iter().enumerate() {
            let got = sobol_dim1(i as u32) as f64 / 4294967296.0;
            assert_eq!(got, *w, "index {i}");
        }
    }
}
