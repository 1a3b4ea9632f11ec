//! Splitting: `n` values of one dimension for one camera sample (the `n`
//! shadow rays to an area light, the `n` rays of a glossy lobe, the `n`
//! ambient-occlusion rays).
//!
//! Why this form: the `n` values are sample `index·n + k` (k < n) of the same
//! layout run with `spp·n` samples per pixel. So the `n` values of one camera
//! sample are stratified among themselves (a power-of-two run of Sobol
//! points is itself a net), and the `spp·n` values of all the pixel's samples
//! are stratified together: splitting and supersampling give the same
//! quality per ray, as the lecture's cost formula assumes.

use super::{DimKey, GridLayout, SampleStream, Sampler, SamplerKind, SobolDim};
use crate::math::Vec2;

/// The `n` values of one split dimension; see [`SampleStream::split_2d`].
#[derive(Clone, Debug)]
pub struct Split2d {
    source: Source,
    base: u32,
    dim: u32,
    k: u32,
    n: u32,
}

/// Where a split's values come from.
#[derive(Clone, Debug)]
enum Source {
    /// Sobol points: what the dimension's values share, worked out once
    /// (they depend on neither the sample count nor the grid).
    Sobol(SobolDim),
    /// Any other layout, run with `spp·n` samples per pixel.
    Other {
        sampler: Sampler,
        /// The hash prefix of the seed and the (possibly re-keyed) pixel.
        prefix: u64,
        /// The dimension's hash, shared by its `n` values.
        key: DimKey,
    },
}

impl SampleStream<'_> {
    /// The next dimension, split into `n` 2-D values (`n = 0` is taken as
    /// 1; with `n = 1` this is the value [`SampleStream::next_2d`] gives).
    pub fn split_2d(&mut self, n: u32) -> Split2d {
        let n = n.max(1);
        let dim = self.dim;
        self.dim += 1;
        let s = self.sampler;
        let kind = match s.kind {
            // A grid's cells are sampled at their centres whatever the pixel
            // layout asks (the course's pixel corners would put every shadow
            // ray on the light's edge).
            SamplerKind::Uniform(_) => SamplerKind::Uniform(GridLayout::CENTERS),
            // A key stream is not part of any stratified set.
            _ if self.index == u32::MAX => SamplerKind::Random,
            k => k,
        };
        let base = if self.index == u32::MAX {
            0
        } else {
            self.index.saturating_mul(n)
        };
        // A sample's own pixel keeps its stream's prefix (the same seed
        // and pixel key); a key stream's values are keyed apart from it.
        let prefix = if self.index == u32::MAX {
            s.prefix(self.pixel_key ^ 0x5151_0000_0000_0000)
        } else {
            self.prefix
        };
        let key = DimKey::new(prefix, dim);
        let source = if matches!(kind, SamplerKind::Sobol) {
            Source::Sobol(SobolDim::new(prefix, key, dim))
        } else {
            Source::Other {
                sampler: Sampler::new(kind, s.spp.saturating_mul(n), s.seed),
                prefix,
                key,
            }
        };
        Split2d {
            source,
            base,
            dim,
            k: 0,
            n,
        }
    }
}

impl Iterator for Split2d {
    type Item = Vec2;

    fn next(&mut self) -> Option<Vec2> {
        if self.k == self.n {
            return None;
        }
        let index = self.base + self.k;
        let v = match &self.source {
            Source::Sobol(d) => d.value(super::sobol::reverse(index)),
            Source::Other {
                sampler,
                prefix,
                key,
            } => sampler.value_2d_keyed(*prefix, *key, index, self.dim),
        };
        self.k += 1;
        Some(v)
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = (self.n - self.k) as usize;
        (left, Some(left))
    }
}

impl ExactSizeIterator for Split2d {}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_split_value_is_the_plain_value() {
        for kind in [
            SamplerKind::Random,
            SamplerKind::Jittered,
            SamplerKind::Sobol,
        ] {
            let s = Sampler::new(kind, 16, 3);
            let mut a = s.stream((4, 5), 7);
            let mut b = s.stream((4, 5), 7);
            a.next_2d();
            b.next_2d();
            assert_eq!(a.split_2d(1).next(), Some(b.next_2d()), "{kind}");
            assert_eq!(a.dimension(), b.dimension());
        }
    }

    #[test]
    fn split_values_are_stratified() {
        // 16 Sobol values of one camera sample: one in each 4×4 cell.
        let s = Sampler::new(SamplerKind::Sobol, 4, 9);
        for index in 0..4 {
            let mut st = s.stream((1, 2), index);
            st.next_2d();
            let mut cells = [false; 16];
            for v in st.split_2d(16) {
                let c = (v.x * 4.0) as usize + 4 * (v.y * 4.0) as usize;
                assert!(!cells[c], "two values in cell {c}");
                cells[c] = true;
            }
        }
    }

    #[test]
    fn uniform_split_uses_cell_centres() {
        let s = Sampler::fixed(Vec2::ZERO);
        let mut st = s.stream((0, 0), 0);
        st.next_2d();
        let mut v: Vec<Vec2> = st.split_2d(4).collect();
        v.sort_by(|a, b| (a.y, a.x).partial_cmp(&(b.y, b.x)).unwrap());
        assert_eq!(v[0], Vec2::splat(0.25));
        assert_eq!(v[3], Vec2::splat(0.75));
    }
}
