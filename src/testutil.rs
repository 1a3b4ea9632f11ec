//! The tests' random numbers: one small deterministic generator for the
//! unit tests (`cfg(test)`) and the integration tests (`tests/common`
//! includes this file with `#[path]`), so a failure names a seed that
//! reproduces it everywhere. It draws test inputs (rays, points, soups);
//! the renderer's own samplers are `src/sampler/`.

#![allow(dead_code)]

use glam::{DVec3, Vec3};

/// splitmix64 (Steele, Lea and Flood 2014): every seed, 0 included, gives
/// a full-period, well-mixed stream.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// The stream of `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 random bits.
    pub fn u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1), 24 bits.
    pub fn f(&mut self) -> f32 {
        (self.u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in [0, 1), 53 bits.
    pub fn f64(&mut self) -> f64 {
        (self.u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f()
    }

    /// Uniform in [lo, hi), in f64.
    pub fn range64(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.f64()
    }

    /// Log-uniform in [lo, hi) (both positive): every scale as likely.
    pub fn log_range64(&mut self, lo: f64, hi: f64) -> f64 {
        (lo.ln() + (hi.ln() - lo.ln()) * self.f64()).exp()
    }

    /// Uniform in 0..n (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.u64() % n as u64) as usize
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f32) -> bool {
        self.f() < p
    }

    /// Uniform in the box [lo, hi)³.
    pub fn v(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }

    /// A uniformly distributed unit vector (rejection from the ball, away
    /// from its centre).
    pub fn unit(&mut self) -> Vec3 {
        loop {
            let v = self.v(-1.0, 1.0);
            let l = v.length();
            if l > 0.05 && l <= 1.0 {
                return v / l;
            }
        }
    }

    /// [`Rng::unit`] in f64.
    pub fn unit64(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                self.range64(-1.0, 1.0),
                self.range64(-1.0, 1.0),
                self.range64(-1.0, 1.0),
            );
            let l = v.length();
            if l > 0.05 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Rng;

    /// The stream is splitmix64's (its published first output for seed 0),
    /// and the floats stay in [0, 1) with a mean near 1/2.
    #[test]
    fn splitmix_stream_and_ranges() {
        assert_eq!(Rng::new(0).u64(), 0xe220_a839_7b1d_cdaf);
        let mut r = Rng::new(7);
        let n = 100_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let (a, b) = (r.f(), r.f64());
            assert!((0.0..1.0).contains(&a) && (0.0..1.0).contains(&b));
            sum += b;
            assert!(r.below(3) < 3);
            assert!((r.unit().length() - 1.0).abs() < 1e-5);
        }
        assert!((sum / n as f64 - 0.5).abs() < 0.005, "{}", sum / n as f64);
    }
}
