//! Stateless hashing: every random number glint draws is a hash of where it
//! is used (seed, pixel, sample index, dimension), never the next output of a
//! shared generator. That is what makes images independent of thread count
//! and tile order.

/// The SplitMix64 finaliser: a bijective 64-bit mix with full avalanche.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Hash of a sequence of words, each mixed in turn (order matters).
#[inline]
pub fn hash(words: &[u64]) -> u64 {
    hash_from(0x9e37_79b9_7f4a_7c15, words)
}

/// [`hash`] continued: `hash_from(hash(a), b) == hash(a ++ b)`, so a
/// prefix shared by many hashes (seed and pixel) is mixed once.
#[inline]
pub fn hash_from(start: u64, words: &[u64]) -> u64 {
    words.iter().fold(start, |h, &w| {
        mix64(h ^ w.wrapping_mul(0xd6e8_feb8_6659_fd93))
    })
}

/// A float in `[0, 1)` from the top 24 bits of `h` (exactly representable
/// in `f32`, so the result never rounds up to 1).
#[inline]
pub fn unit_f32(h: u64) -> f32 {
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// A float in `[0, 1)` from the top 24 bits of a 32-bit value (the
/// definition of a Sobol coordinate's float; the samplers convert from the
/// coordinate's reversed bits, `sobol::unit_pair`).
#[cfg(test)]
pub fn unit_from_u32(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// Element `i` of a pseudo-random permutation of `0..len` chosen by `p`
/// (Kensler, "Correlated Multi-Jittered Sampling", 2013): a bijection on the
/// next power of two, cycle-walked until it lands inside `0..len`.
pub fn permute(mut i: u32, len: u32, p: u32) -> u32 {
    debug_assert!(len > 0 && i < len);
    let mut w = len - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    loop {
        i ^= p;
        i = i.wrapping_mul(0xe170_893d);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | p >> 27);
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < len {
            break;
        }
    }
    ((i as u64 + p as u64) % len as u64) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permute_is_a_permutation() {
        for len in [1u32, 2, 3, 7, 16, 36, 100] {
            for p in [0u32, 1, 0xdead_beef, 12345] {
                let mut seen = vec![false; len as usize];
                for i in 0..len {
                    let j = permute(i, len, p);
                    assert!(j < len);
                    assert!(!seen[j as usize], "len {len} p {p}: {j} twice");
                    seen[j as usize] = true;
                }
            }
        }
    }

    #[test]
    fn a_continued_hash_is_the_hash_of_the_whole() {
        let words = [7u64, 0xdead_beef_0000_0001, 3, 1];
        for k in 0..=words.len() {
            assert_eq!(hash_from(hash(&words[..k]), &words[k..]), hash(&words));
        }
    }

    #[test]
    fn unit_floats_stay_below_one() {
        assert!(unit_f32(u64::MAX) < 1.0);
        assert!(unit_from_u32(u32::MAX) < 1.0);
        assert_eq!(unit_f32(0), 0.0);
    }
}
