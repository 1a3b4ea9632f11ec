//! Ken Perlin's *improved noise* (SIGGRAPH 2002), the function the 6.837
//! course supplies as `PerlinNoise::noise` (a C++ port of Perlin's Java
//! reference implementation), and the octave sum the solid textures use.
//!
//! Written from the published algorithm: a lattice of pseudo-random gradients
//! chosen by hashing the integer cell corners through Perlin's fixed
//! permutation table, dotted with the offset to each corner and blended with
//! the quintic fade `6t⁵ − 15t⁴ + 10t³`. Because the *standard* table is used,
//! the values are those of every other faithful port, so scenes tuned with the
//! course's code get the same pattern (same blotches in the same places),
//! not merely a similar-looking one.
//!
//! Arithmetic is in `f64` like the reference (Java `double`): texture
//! coordinates can be large after a texture transform (scene6_18 scales by
//! 15), and the fractional part of a large `f32` loses bits quickly.

use glam::DVec3;

/// Perlin's permutation of 0..=255 (the table printed in the 2002 reference).
/// The reference doubles it to 512 entries to avoid a wrap; [`perm`] masks the
/// index instead, which reads the same values.
const PERMUTATION: [u8; 256] = [
    151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30, 69,
    142, 8, 99, 37, 240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94, 252, 219,
    203, 117, 35, 11, 32, 57, 177, 33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171, 168, 68, 175,
    74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83, 111, 229, 122, 60, 211, 133, 230,
    220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1, 216, 80, 73, 209, 76,
    132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86, 164, 100, 109, 198, 173,
    186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118, 126, 255, 82, 85, 212, 207, 206,
    59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170, 213, 119, 248, 152, 2, 44, 154, 163,
    70, 221, 153, 101, 155, 167, 43, 172, 9, 129, 22, 39, 253, 19, 98, 108, 110, 79, 113, 224, 232,
    178, 185, 112, 104, 218, 246, 97, 228, 251, 34, 242, 193, 238, 210, 144, 12, 191, 179, 162,
    241, 81, 51, 145, 235, 249, 14, 239, 107, 49, 192, 214, 31, 181, 199, 106, 157, 184, 84, 204,
    176, 115, 121, 50, 45, 127, 4, 150, 254, 138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141,
    128, 195, 78, 66, 215, 61, 156, 180,
];

/// `p[i]` of the reference's doubled table, for `0 ≤ i < 512`.
#[inline]
fn perm(i: usize) -> usize {
    PERMUTATION[i & 255] as usize
}

/// The quintic `6t⁵ − 15t⁴ + 10t³`: its first and second derivatives vanish
/// at 0 and 1, so noise is C² across cell faces (the 1985 cubic was only C¹,
/// which showed as creases in bump maps; that was the point of the 2002 paper).
#[inline]
fn fade(t: f64) -> f64 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

#[inline]
fn lerp(t: f64, a: f64, b: f64) -> f64 {
    a + t * (b - a)
}

/// Dot product of the offset `(x, y, z)` with one of the 12 cube-edge
/// gradients `(±1, ±1, 0)`, `(±1, 0, ±1)`, `(0, ±1, ±1)` picked by the low 4
/// bits of `hash` (16 cases; 4 edges repeat, which keeps the choice a bit
/// mask instead of a `% 12`).
#[inline]
fn grad(hash: usize, x: f64, y: f64, z: f64) -> f64 {
    let h = hash & 15;
    let u = if h < 8 { x } else { y };
    let v = if h < 4 {
        y
    } else if h == 12 || h == 14 {
        x
    } else {
        z
    };
    (if h & 1 == 0 { u } else { -u }) + (if h & 2 == 0 { v } else { -v })
}

/// Improved Perlin noise at `p`.
///
/// Properties the textures rely on (and the tests check): zero at every
/// integer lattice point; continuous with continuous first and second
/// derivatives; periodic with period 256 in each axis; values in roughly
/// `[-1, 1]` (most within ±0.5).
pub fn noise(p: DVec3) -> f64 {
    let f = p.floor();
    // Lattice cell, wrapped to the 256-periodic table (two's complement `& 255`
    // also wraps negative cells correctly, as Java's `(int)floor(x) & 255`).
    let xi = (f.x as i64 & 255) as usize;
    let yi = (f.y as i64 & 255) as usize;
    let zi = (f.z as i64 & 255) as usize;
    // Position inside the cell, in [0, 1).
    let (x, y, z) = (p.x - f.x, p.y - f.y, p.z - f.z);
    let (u, v, w) = (fade(x), fade(y), fade(z));

    // Hash the 8 corners exactly as the reference does.
    let a = perm(xi) + yi;
    let aa = perm(a) + zi;
    let ab = perm(a + 1) + zi;
    let b = perm(xi + 1) + yi;
    let ba = perm(b) + zi;
    let bb = perm(b + 1) + zi;

    lerp(
        w,
        lerp(
            v,
            lerp(u, grad(perm(aa), x, y, z), grad(perm(ba), x - 1.0, y, z)),
            lerp(
                u,
                grad(perm(ab), x, y - 1.0, z),
                grad(perm(bb), x - 1.0, y - 1.0, z),
            ),
        ),
        lerp(
            v,
            lerp(
                u,
                grad(perm(aa + 1), x, y, z - 1.0),
                grad(perm(ba + 1), x - 1.0, y, z - 1.0),
            ),
            lerp(
                u,
                grad(perm(ab + 1), x, y - 1.0, z - 1.0),
                grad(perm(bb + 1), x - 1.0, y - 1.0, z - 1.0),
            ),
        ),
    )
}

/// The octave sum the course's textures use:
/// `N(p) = Σ_{i < octaves} noise(2^i·p) / 2^i`, frequency doubling and
/// amplitude halving per octave. Signed (no `|·|`: the course's formula sums
/// the noise itself), so `N` stays centred on 0 and is bounded by about
/// `2 · max|noise|`. Zero octaves give 0 (scene6_15 uses that for a pure sine).
pub fn octave_sum(p: DVec3, octaves: u32) -> f64 {
    let mut sum = 0.0;
    let mut scale = 1.0;
    for _ in 0..octaves {
        sum += noise(p * scale) / scale;
        scale *= 2.0;
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_is_a_permutation() {
        let mut seen = [false; 256];
        for &v in &PERMUTATION {
            assert!(!seen[v as usize], "{v} twice");
            seen[v as usize] = true;
        }
    }

    #[test]
    fn zero_at_lattice_points() {
        // Every corner's offset is 0 there, so every gradient dot product is 0.
        for x in -3..=3 {
            for y in -3..=3 {
                for z in -3..=3 {
                    let p = DVec3::new(x as f64, y as f64, z as f64);
                    assert_eq!(noise(p), 0.0, "{p}");
                }
            }
        }
        assert_eq!(noise(DVec3::new(300.0, -1000.0, 77.0)), 0.0);
    }

    /// Values of the reference algorithm.
    ///
    /// `(0, 0, 0.5)` by hand: with `x = y = 0` the fades give `u = v = 0`, so
    /// only the corners `(0,0,0)` and `(0,0,1)` count, each with weight
    /// `w = fade(0.5) = 0.5`. Hashes: `A = p[0] + 0 = 151`, `AA = p[151] + 0 = 17`,
    /// corner hashes `p[17] = 36` and `p[18] = 103`.
    /// `36 & 15 = 4`: `u = x`, `v = z` (h ≥ 4, not 12 or 14), both signs `+`:
    /// `0 + 0.5 = 0.5`. `103 & 15 = 7`: `u = x`, `v = z`, both signs `−`, at the
    /// offset `(0, 0, −0.5)`: `−0 + 0.5 = 0.5`. Total `0.5·0.5 + 0.5·0.5 = 0.5`.
    ///
    /// The other values were computed with an independent transcription of
    /// Perlin's Java reference (`ImprovedNoise.java`) in Python, double
    /// precision (`tools/improved_noise_check.py`, which also reproduces the
    /// hand-derived value above).
    #[test]
    fn known_values_of_the_reference_algorithm() {
        let cases = [
            ((0.0, 0.0, 0.5), 0.5),
            ((0.5, 0.5, 0.5), -0.25),
            ((3.7, 42.0, 7.0), 0.114_155_999_999_999_92),
            ((-1.3, 2.7, -0.4), 0.106_073_457_665_587_01),
            ((10.25, -3.75, 100.5), -0.310_302_734_375),
        ];
        for ((x, y, z), want) in cases {
            let got = noise(DVec3::new(x, y, z));
            assert!(
                (got - want).abs() < 1e-12,
                "noise({x}, {y}, {z}) = {got}, want {want}"
            );
        }
    }

    /// Deterministic sample points in `[-span, span]³`.
    fn points(n: usize, seed: u64, span: f64) -> impl Iterator<Item = DVec3> {
        let mut r = crate::testutil::Rng::new(seed);
        (0..n).map(move |_| {
            DVec3::new(
                r.range64(-span, span),
                r.range64(-span, span),
                r.range64(-span, span),
            )
        })
    }

    #[test]
    fn range_is_about_plus_minus_one() {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in points(200_000, 0x9e37_79b9_7f4a_7c15, 40.0) {
            let n = noise(p);
            lo = lo.min(n);
            hi = hi.max(n);
        }
        // Improved noise is bounded by ~1.04 in theory; random samples stay
        // well inside, yet do explore most of the range.
        assert!(lo >= -1.05 && hi <= 1.05, "[{lo}, {hi}]");
        assert!(lo < -0.6 && hi > 0.6, "[{lo}, {hi}] suspiciously narrow");
    }

    #[test]
    fn mean_is_near_zero() {
        let n = 100_000;
        let mean: f64 = points(n, 7, 50.0).map(noise).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.01, "mean {mean}");
    }

    #[test]
    fn continuous_across_cell_faces() {
        // The gradients have length ≤ √2 and the fade's slope is ≤ 1.875, so
        // |∇noise| is small (< 4 is generous); a jump at a face would break it.
        let eps = 1e-7;
        for p in points(2_000, 3, 20.0) {
            for axis in [DVec3::X, DVec3::Y, DVec3::Z] {
                // Snap one coordinate onto a lattice plane and step across it.
                let mut q = p;
                let k = q.dot(axis).round();
                q = q - axis * q.dot(axis) + axis * k;
                let d = (noise(q + axis * eps) - noise(q - axis * eps)).abs();
                assert!(d <= 4.0 * 2.0 * eps, "jump {d} at {q}");
            }
            let d = (noise(p + DVec3::splat(eps)) - noise(p)).abs();
            assert!(d <= 4.0 * eps * 3f64.sqrt(), "jump {d} at {p}");
        }
    }

    #[test]
    fn periodic_with_period_256() {
        for p in points(1_000, 11, 30.0) {
            let a = noise(p);
            let b = noise(p + DVec3::new(256.0, -512.0, 256.0));
            assert!((a - b).abs() < 1e-9, "{a} vs {b} at {p}");
        }
    }

    #[test]
    fn octaves_double_frequency_and_halve_amplitude() {
        let p = DVec3::new(0.3, 1.7, -2.2);
        assert_eq!(octave_sum(p, 0), 0.0);
        assert_eq!(octave_sum(p, 1), noise(p));
        let three = noise(p) + noise(2.0 * p) / 2.0 + noise(4.0 * p) / 4.0;
        assert!((octave_sum(p, 3) - three).abs() < 1e-15);
    }
}
