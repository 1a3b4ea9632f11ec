//! Where the samples of a pixel go: the pixel position and every further
//! random decision an integrator makes (light point, lens, time, gloss,
//! hemisphere).
//!
//! A [`SampleStream`] belongs to one sample of one pixel. Its first value is
//! the 2-D position inside the pixel; every further request (`next_1d`,
//! `next_2d`) takes the next *dimension*. Each value is a pure function of
//! `(seed, pixel, sample index, dimension)`: nothing is shared between
//! threads and no generator state carries over, so an image is the same bit
//! for bit for any thread count and tile order.

mod hash;
mod sobol;
mod split;

pub use hash::{hash, hash_from, mix64, permute, unit_f32};
pub use split::Split2d;

use crate::math::Vec2;
use std::fmt;
use std::str::FromStr;

/// How the sample points of a pixel are laid out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SamplerKind {
    /// A regular `kx × ky` grid (`kx·ky = spp`), placed by the [`GridLayout`].
    Uniform(GridLayout),
    /// Independent uniform random points (white noise).
    Random,
    /// One random point in each cell of the `kx × ky` grid (stratified).
    Jittered,
    /// Owen-scrambled Sobol points: stratified at every power-of-two prefix
    /// and in every elementary interval shape; the pixel position and the
    /// first 2-D value after it jointly in 4-D. The default for stochastic use.
    Sobol,
}

/// Where a uniform grid puts its point within each cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum GridLayout {
    /// At this offset inside each of the `kx × ky` cells: `(0.5, 0.5)` is the
    /// cell centre (glint's uniform sampler), `(0, 0)` the cell's lower-left
    /// corner (the course's single ray at the pixel corner).
    Cell(Vec2),
    /// Evenly spaced with the borders as gaps: coordinate `(a+1)/(k+1)`. This
    /// is what the 6.837 reference renders' uniform sampler does (their
    /// 2×2 samples sit at 1/3 and 2/3; see `tests/sampling_reference.rs`).
    Inset,
}

impl GridLayout {
    /// Cell centres.
    pub const CENTERS: GridLayout = GridLayout::Cell(Vec2::splat(0.5));
    /// Cell lower-left corners.
    pub const CORNERS: GridLayout = GridLayout::Cell(Vec2::ZERO);
}

/// The samples a render takes per pixel: their layout, count and seed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sampler {
    /// Layout.
    pub kind: SamplerKind,
    /// Samples per pixel (at least 1).
    spp: u32,
    /// Grid columns for the grid-based kinds (`kx · ky = spp`).
    kx: u32,
    /// Seed of every hash (changes the noise, never its statistics).
    pub seed: u64,
}

impl Sampler {
    /// `spp` samples per pixel of `kind` (an `spp` of 0 is taken as 1).
    ///
    /// Grid kinds split `spp` into `kx × ky` with `kx` the largest divisor of
    /// `spp` not above `√spp`: a square for square counts (the course's 4, 9,
    /// 16, 36), else the most nearly square grid (a prime count gives a
    /// `1 × spp` column of strips, still one sample per stratum).
    pub fn new(kind: SamplerKind, spp: u32, seed: u64) -> Self {
        let spp = spp.max(1);
        let mut kx = (spp as f64).sqrt() as u32;
        while kx > 1 && !spp.is_multiple_of(kx) {
            kx -= 1;
        }
        Self {
            kind,
            spp,
            kx: kx.max(1),
            seed,
        }
    }

    /// One sample per pixel at a fixed in-pixel offset (`(0.5, 0.5)` = centre).
    pub fn fixed(offset: Vec2) -> Self {
        Self::new(SamplerKind::Uniform(GridLayout::Cell(offset)), 1, 0)
    }

    /// The pixel position shared by every pixel when there is one sample per
    /// pixel on a uniform grid (the one-ray renders), so a loop can hoist it.
    pub fn fixed_offset(&self) -> Option<Vec2> {
        match self.kind {
            SamplerKind::Uniform(layout) if self.spp == 1 => Some(self.grid_point(layout, 0)),
            _ => None,
        }
    }

    /// Samples per pixel.
    pub fn spp(&self) -> u32 {
        self.spp
    }

    /// Grid shape `(kx, ky)` of the grid-based kinds.
    pub fn grid(&self) -> (u32, u32) {
        (self.kx, self.spp / self.kx)
    }

    /// Whether every value is fixed (no randomness at all).
    pub fn is_deterministic(&self) -> bool {
        matches!(self.kind, SamplerKind::Uniform(_))
    }

    /// The stream of sample `index` of pixel `(i, j)` (image coordinates,
    /// `j` up), at dimension 0.
    pub fn stream(&self, pixel: (u32, u32), index: u32) -> SampleStream<'_> {
        let pixel_key = (pixel.0 as u64) | (pixel.1 as u64) << 32;
        let prefix = self.prefix(pixel_key);
        SampleStream {
            sampler: self,
            pixel_key,
            prefix,
            index,
            dim: 0,
            sobol: (matches!(self.kind, SamplerKind::Sobol) && index != u32::MAX)
                .then(|| SobolIndex::new(prefix, index)),
        }
    }

    /// A stream for a point that is not one of a pixel's `spp` samples (an
    /// adaptive corner): keyed by a caller-chosen unique `key`. Only its
    /// higher dimensions are used; their values are random-quality (the
    /// stratification of `spp`-sample sets does not apply).
    pub fn stream_for_key(&self, key: u64) -> SampleStream<'_> {
        let pixel_key = key ^ 0xa5a5_a5a5_0000_0000;
        SampleStream {
            sampler: self,
            pixel_key,
            prefix: self.prefix(pixel_key),
            index: u32::MAX,
            dim: 1,
            sobol: None,
        }
    }

    /// `hash(&[seed, pixel_key])`: the start of every hash of a pixel's
    /// values, mixed once per stream ([`hash_from`] continues it).
    #[inline]
    fn prefix(&self, pixel_key: u64) -> u64 {
        hash(&[self.seed, pixel_key])
    }

    /// Value of 2-D dimension `dim` for the stream's pixel (`prefix`, see
    /// [`prefix`](Self::prefix)) and index.
    #[inline]
    fn value_2d(&self, prefix: u64, index: u32, dim: u32) -> Vec2 {
        self.value_2d_keyed(prefix, DimKey::new(prefix, dim), index, dim)
    }

    /// [`value_2d`](Self::value_2d) with the dimension's hash worked out
    /// ahead ([`DimKey`]): the `n` values of a split dimension share it.
    #[inline]
    fn value_2d_keyed(&self, prefix: u64, key: DimKey, index: u32, dim: u32) -> Vec2 {
        // A key stream (index u32::MAX) is not part of any stratified set.
        let kind = if index == u32::MAX {
            SamplerKind::Random
        } else {
            self.kind
        };
        // The pixel position of a uniform grid needs no hash: this is the
        // whole cost of the one-ray-per-pixel path.
        if let (SamplerKind::Uniform(layout), 0) = (kind, dim) {
            return self.grid_point(layout, index % self.spp);
        }
        let h = key.h;
        match kind {
            SamplerKind::Random => Vec2::new(
                unit_f32(hash(&[h, index as u64, 0])),
                unit_f32(hash(&[h, index as u64, 1])),
            ),
            SamplerKind::Uniform(layout) => self.grid_point(layout, self.stratum(index, dim, h)),
            SamplerKind::Jittered => {
                let (kx, ky) = self.grid();
                let cell = self.stratum(index, dim, h);
                let (cx, cy) = ((cell % kx) as f32, (cell / kx) as f32);
                let jx = unit_f32(hash(&[h, index as u64, 2]));
                let jy = unit_f32(hash(&[h, index as u64, 3]));
                // `min` keeps a jitter that rounds up inside its cell.
                Vec2::new(
                    ((cx + jx) / kx as f32).min(ONE_BELOW),
                    ((cy + jy) / ky as f32).min(ONE_BELOW),
                )
            }
            SamplerKind::Sobol => SobolDim::new(prefix, key, dim).value(sobol::reverse(index)),
        }
    }

    /// The point of grid cell `cell` under `layout`.
    #[inline]
    fn grid_point(&self, layout: GridLayout, cell: u32) -> Vec2 {
        let (kx, ky) = self.grid();
        let (cx, cy) = ((cell % kx) as f32, (cell / kx) as f32);
        match layout {
            GridLayout::Cell(o) => Vec2::new((cx + o.x) / kx as f32, (cy + o.y) / ky as f32),
            GridLayout::Inset => {
                Vec2::new((cx + 1.0) / (kx + 1) as f32, (cy + 1.0) / (ky + 1) as f32)
            }
        }
    }

    /// Value of 1-D dimension `dim`.
    fn value_1d(&self, prefix: u64, index: u32, dim: u32) -> f32 {
        let h = Self::hash_1d(prefix, dim);
        let kind = if index == u32::MAX {
            SamplerKind::Random
        } else {
            self.kind
        };
        let n = self.spp as f32;
        match kind {
            SamplerKind::Random => unit_f32(hash(&[h, index as u64])),
            SamplerKind::Uniform(_) => {
                (permute(index % self.spp, self.spp, h as u32) as f32 + 0.5) / n
            }
            SamplerKind::Jittered => {
                let s = permute(index % self.spp, self.spp, h as u32) as f32;
                ((s + unit_f32(hash(&[h, index as u64]))) / n).min(ONE_BELOW)
            }
            SamplerKind::Sobol => sobol_1d(h, sobol::reverse(index)),
        }
    }

    /// The hash of 1-D dimension `dim` under the stream's `prefix`.
    #[inline]
    fn hash_1d(prefix: u64, dim: u32) -> u64 {
        hash_from(prefix, &[dim as u64, 1])
    }

    /// Grid cell of sample `index` in dimension `dim`: the index itself for
    /// the pixel position (dimension 0), a per-pixel, per-dimension
    /// permutation of it for the others, so that dimensions are not
    /// correlated with each other (a sample in the left of the pixel would
    /// otherwise always take the left of the light).
    fn stratum(&self, index: u32, dim: u32, h: u64) -> u32 {
        let i = index % self.spp;
        if dim == 0 {
            i
        } else {
            permute(i, self.spp, (h >> 16) as u32)
        }
    }
}

/// The Sobol value of a 1-D dimension whose hash is `h`, for the sample
/// whose index reversed is `index_reversed`.
#[inline]
fn sobol_1d(h: u64, index_reversed: u32) -> f32 {
    let i = sobol::shuffle_reversed(index_reversed, h as u32);
    sobol::unit_dim0(i, (h >> 32) as u32)
}

/// What the Sobol values of one 2-D dimension of one pixel share: the
/// index shuffle's seed and the two coordinates' scramble seeds.
#[derive(Clone, Copy, Debug)]
struct SobolDim {
    shuffle: u32,
    sx: u32,
    sy: u32,
    /// Dimension 1: Sobol dimensions 2 and 3 of the pixel position's point
    /// (the same index shuffle as dimension 0's), so that the pixel
    /// position and this first 2-D decision after it (the lens point of a
    /// thin-lens camera) are stratified jointly. With independent shuffles,
    /// as further dimensions have, the pairing of pixel and lens positions
    /// is random, and so is the coverage of a defocused edge.
    upper: bool,
}

impl SobolDim {
    /// Dimension `dim` whose hash under the stream's `prefix` is `key`.
    #[inline]
    fn new(prefix: u64, key: DimKey, dim: u32) -> Self {
        let upper = dim == 1;
        let shuffle = if upper {
            DimKey::hash(prefix, 0)
        } else {
            key.h
        };
        Self {
            shuffle: shuffle as u32,
            sx: (key.h >> 32) as u32,
            sy: key.mixed,
            upper,
        }
    }

    /// The value of the sample whose index reversed is `index_reversed`.
    #[inline]
    fn value(&self, index_reversed: u32) -> Vec2 {
        self.value_shuffled(sobol::shuffle_reversed(index_reversed, self.shuffle))
    }

    /// The value of the shuffled index `i` (`owen_scramble(index, shuffle)`).
    #[inline]
    fn value_shuffled(&self, i: u32) -> Vec2 {
        sobol::unit_pair(if self.upper {
            sobol::upper_reversed(i, self.sx, self.sy)
        } else {
            sobol::point_reversed(i, self.sx, self.sy)
        })
    }
}

/// What a Sobol stream's values share, worked out once per stream: its
/// index reversed (the first step of every index shuffle) and dimension
/// 0's hash and shuffled index, which dimension 1 shares.
#[derive(Clone, Copy, Debug)]
struct SobolIndex {
    index_reversed: u32,
    shuffled0: u32,
    h0: u64,
}

impl SobolIndex {
    #[inline]
    fn new(prefix: u64, index: u32) -> Self {
        let index_reversed = sobol::reverse(index);
        let h0 = DimKey::hash(prefix, 0);
        Self {
            index_reversed,
            shuffled0: sobol::shuffle_reversed(index_reversed, h0 as u32),
            h0,
        }
    }

    /// The 2-D value of dimension `dim` under the stream's `prefix`: the
    /// same as [`Sampler::value_2d`].
    #[inline]
    fn value_2d(&self, prefix: u64, dim: u32) -> Vec2 {
        match dim {
            0 => sobol::unit_pair(sobol::point_reversed(
                self.shuffled0,
                (self.h0 >> 32) as u32,
                mix64(self.h0) as u32,
            )),
            1 => {
                let key = DimKey::new(prefix, 1);
                sobol::unit_pair(sobol::upper_reversed(
                    self.shuffled0,
                    (key.h >> 32) as u32,
                    key.mixed,
                ))
            }
            _ => SobolDim::new(prefix, DimKey::new(prefix, dim), dim).value(self.index_reversed),
        }
    }
}

/// The largest `f32` below 1.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// The values of one sample of one pixel, dimension by dimension.
#[derive(Clone, Debug)]
pub struct SampleStream<'a> {
    sampler: &'a Sampler,
    pixel_key: u64,
    /// `hash(&[seed, pixel_key])`.
    prefix: u64,
    index: u32,
    dim: u32,
    /// The per-stream part of a Sobol stream's values (`None` for other
    /// kinds and for key streams).
    sobol: Option<SobolIndex>,
}

impl SampleStream<'_> {
    /// The next 2-D value in `[0, 1)²` (the first one is the pixel position).
    pub fn next_2d(&mut self) -> Vec2 {
        let v = self.get_2d(self.dim);
        self.dim += 1;
        v
    }

    /// The 2-D value of dimension `dim` (taken or not): for an integrator
    /// that reserves a block of dimensions ([`skip_n`](Self::skip_n)) and
    /// computes only those it uses.
    #[inline]
    pub fn get_2d(&self, dim: u32) -> Vec2 {
        match &self.sobol {
            Some(s) => s.value_2d(self.prefix, dim),
            None => self.sampler.value_2d(self.prefix, self.index, dim),
        }
    }

    /// The 1-D value of dimension `dim`, as [`get_2d`](Self::get_2d).
    #[inline]
    pub fn get_1d(&self, dim: u32) -> f32 {
        match &self.sobol {
            Some(s) => sobol_1d(Sampler::hash_1d(self.prefix, dim), s.index_reversed),
            None => self.sampler.value_1d(self.prefix, self.index, dim),
        }
    }

    /// The next 1-D value in `[0, 1)`.
    pub fn next_1d(&mut self) -> f32 {
        let v = self.get_1d(self.dim);
        self.dim += 1;
        v
    }

    /// Skips the next dimension (taken by the caller from elsewhere, e.g. a
    /// hoisted [`Sampler::fixed_offset`]).
    pub fn skip(&mut self) {
        self.dim += 1;
    }

    /// Skips the next `n` dimensions (read later with [`get_1d`](Self::get_1d)
    /// and [`get_2d`](Self::get_2d) where needed).
    pub fn skip_n(&mut self, n: u32) {
        self.dim += n;
    }

    /// How many dimensions have been taken so far.
    pub fn dimension(&self) -> u32 {
        self.dim
    }

    /// The sample index within the pixel.
    pub fn index(&self) -> u32 {
        self.index
    }
}

/// Error of [`SamplerKind::from_str`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnknownSampler(pub String);

impl fmt::Display for UnknownSampler {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "unknown sampler '{}' (expected uniform, random, jittered or sobol)",
            self.0
        )
    }
}

impl std::error::Error for UnknownSampler {}

impl FromStr for SamplerKind {
    type Err = UnknownSampler;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s {
            "uniform" => SamplerKind::Uniform(GridLayout::CENTERS),
            "random" => SamplerKind::Random,
            "jittered" | "stratified" => SamplerKind::Jittered,
            "sobol" => SamplerKind::Sobol,
            other => return Err(UnknownSampler(other.to_string())),
        })
    }
}

impl fmt::Display for SamplerKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            SamplerKind::Uniform(GridLayout::Inset) => "uniform (inset)",
            SamplerKind::Uniform(_) => "uniform",
            SamplerKind::Random => "random",
            SamplerKind::Jittered => "jittered",
            SamplerKind::Sobol => "sobol",
        })
    }
}

/// The hash of one dimension of one pixel's stream, and the Sobol
/// scramble seed derived from it: what every value of the dimension uses.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DimKey {
    h: u64,
    mixed: u32,
}

impl DimKey {
    /// Dimension `dim` under the stream's `prefix`.
    #[inline]
    pub(crate) fn new(prefix: u64, dim: u32) -> Self {
        let h = Self::hash(prefix, dim);
        Self {
            h,
            mixed: mix64(h) as u32,
        }
    }

    /// The dimension's hash alone.
    #[inline]
    fn hash(prefix: u64, dim: u32) -> u64 {
        hash_from(prefix, &[dim as u64])
    }
}

#[cfg(test)]
mod tests;
