//! The one pixel loop. Every way of rendering (bands of rows straight into
//! the frame, tiles into films, Whitted's adaptive subdivision) is the same
//! three parts, each generic so that it compiles to one tight loop per
//! integrator, strategy and sink:
//!
//! - [`render_unit`] visits the pixels of a rectangle in blocks and measures
//!   what each pixel cost;
//! - a [`PixelStrategy`] decides where a pixel's camera samples go
//!   ([`Supersample`]: the sampler's positions; adaptive subdivision: the
//!   lattice points its corners call for) and traces each with the one
//!   per-sample step, [`Step::sample`];
//! - a [`PixelSink`] takes every film channel (colour, depth, normal, sample
//!   count, cost): a band of the frame ([`Band`]) or a tile's film
//!   ([`TileFilm`]).
//!
//! Kept samples (the `-render_samples` view) come back from [`render_unit`]
//! in pixel order.

use super::film::{Rect, TileFilm};
use super::{screen_point, CameraModel, Filter, PixelCost, SampleRecord, Settings};
use crate::accel::{PacketRay, PACKET};
use crate::integrator::{Branch, Integrator, NoObserver, Trace};
use crate::math::{Ray, Vec2, Vec3};
use crate::sampler::{SampleStream, Sampler};
use crate::stats::Counters;
use crate::world::{Hit, World};

/// Rows per work unit of the band loop (filters inside their pixel): small enough to balance the load
/// over many threads, large enough that each unit has thousands of rays. Also the height of
/// the pixel loop's blocks.
pub const BAND_ROWS: usize = 4;
/// Columns per block: a unit is traced in blocks of `BLOCK × BAND_ROWS`
/// pixels, not row by row, so neighbouring rays follow each other through
/// the accelerator while its nodes are still in cache (the faceted gem 4-6%
/// faster than row order when measured; the same pixels, the same arithmetic,
/// so the same image).
pub(super) const BLOCK: usize = 8;

/// The widest pixel (radians between neighbouring pixels' rays:
/// `CameraModel::pixel_span`) for which camera rays are traced in packets.
/// Eight pixels of a row make a fan as wide as eight pixels: in a small
/// image the packet's bounds are loose (or the walk refuses the packet
/// for its spread and walks the rays alone, after the work of trying).
/// Callgrind, render instructions of one binary with packets against
/// without, camera rays alone at 4 spp (AVX2 path): scene6_07 (40k
/// triangles, 26°) 1.056 at 96 pixels (a pixel of 0.0048), 1.040 at 160
/// (0.0029), 1.000 at 256 (0.0018); `scenes/mesh_knot_64k.txt` (40°)
/// 1.056 at 96 (0.0076), 1.026 at 160 (0.0046), 1.001 at 256 (0.0028).
/// Both break even near 0.002: 364 pixels across at 40°, 231 at 26°.
pub(super) const PACKET_PIXEL_SPAN: f32 = 0.002;

/// The per-sample step of every loop: the camera ray through offset `o` of
/// pixel `(i, j)` (screen `j` up), at the stream's time and lens point,
/// traced by the integrator.
pub(super) struct Step<'a, I> {
    pub world: &'a World,
    pub camera: &'a CameraModel,
    pub integrator: &'a I,
    /// Image width and height.
    pub size: (u32, u32),
}

impl<I: Integrator> Step<'_, I> {
    /// Colour and camera-ray hit of one sample.
    #[inline]
    pub fn sample(
        &self,
        (i, j, o): (u32, u32, Vec2),
        stream: &mut SampleStream,
        counters: &mut Counters,
    ) -> (Vec3, Option<Hit>) {
        let ray = self.ray((i, j, o), stream);
        let cx = &mut Trace {
            world: self.world,
            stream,
            counters,
            observer: &mut NoObserver,
            packets: self.world.walks_packets(),
        };
        self.integrator.li(cx, &ray, self.camera.tmin())
    }

    /// The camera ray of one sample (what [`sample`](Self::sample)
    /// traces), taking the stream's time and lens dimensions.
    #[inline(always)]
    fn ray(&self, (i, j, o): (u32, u32, Vec2), stream: &mut SampleStream) -> Ray {
        let (w, h) = self.size;
        self.camera.sample_ray(screen_point(i, j, o, w, h), stream)
    }

    /// [`sample`](Self::sample) for a camera ray `ray` whose closest hit
    /// `hit` was found already (in a packet): the same colour and hit.
    #[inline]
    fn shade(
        &self,
        ray: &Ray,
        hit: Option<&Hit>,
        stream: &mut SampleStream,
        counters: &mut Counters,
    ) -> Vec3 {
        let cx = &mut Trace {
            world: self.world,
            stream,
            counters,
            observer: &mut NoObserver,
            packets: self.world.walks_packets(),
        };
        cx.seen(ray, hit, Branch::CAMERA);
        self.integrator.li_hit(cx, ray, self.camera.tmin(), hit)
    }

    /// Whether the camera rays of neighbouring pixels are worth tracing
    /// in packets (`World::intersect_packet`): the world's aggregate walks
    /// packets, the camera is a perspective one (pinhole or thin lens; an
    /// orthographic camera's rays start at `t = −∞`, which the packet walk
    /// takes one ray at a time), and a pixel spans at most
    /// [`PACKET_PIXEL_SPAN`].
    pub(super) fn packets(&self) -> bool {
        self.world.walks_packets()
            && self.camera.tmin() >= 0.0
            && self.camera.pixel_span(self.size) <= PACKET_PIXEL_SPAN
    }
}

/// One pixel's film channels as a strategy hands them to the sink.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct PixelValue {
    /// The reconstructed colour; `None` when the sink spreads each sample's
    /// colour itself ([`PixelSink::spreads`]).
    pub color: Option<Vec3>,
    /// Ray parameter of the kept camera-ray hit (infinite for a miss).
    pub depth: f32,
    /// Normal at the kept hit (zero for a miss).
    pub normal: Vec3,
    /// Camera rays (or lattice points) the pixel used.
    pub samples: u32,
}

/// Where a loop writes every film channel of its pixels (`x` right, `row`
/// down from the top of the frame).
pub(super) trait PixelSink {
    /// Whether a sample's colour reaches pixels beyond its own (a filter of
    /// support above 0): then each sample goes through
    /// [`PixelSink::splat`] and [`PixelValue::color`] is `None`.
    fn spreads(&self) -> bool;
    /// Adds a sample of colour `c` at in-pixel offset `o` (`y` up) of pixel
    /// `(x, row)` to every pixel its filter reaches.
    fn splat(&mut self, x: u32, row: u32, o: Vec2, c: Vec3);
    /// Sets the channels of pixel `(x, row)`, once its samples are done.
    fn pixel(&mut self, x: u32, row: u32, v: PixelValue);
    /// Sets what tracing pixel `(x, row)` cost.
    fn cost(&mut self, x: u32, row: u32, c: PixelCost);
}

/// A band of whole frame rows, written in place: the sink of filters that
/// stay inside their pixel (no film, no merge, no copy).
pub(super) struct Band<'f> {
    /// Frame row of the band's first row.
    pub row0: u32,
    /// Frame width.
    pub width: usize,
    pub color: &'f mut [Vec3],
    pub depth: &'f mut [f32],
    pub normal: &'f mut [Vec3],
    pub samples: &'f mut [u32],
    pub cost: &'f mut [PixelCost],
}

impl Band<'_> {
    #[inline(always)]
    fn index(&self, x: u32, row: u32) -> usize {
        (row - self.row0) as usize * self.width + x as usize
    }
}

impl PixelSink for Band<'_> {
    #[inline(always)]
    fn spreads(&self) -> bool {
        false
    }

    #[inline(always)]
    fn splat(&mut self, _: u32, _: u32, _: Vec2, _: Vec3) {
        unreachable!("a band's filter stays inside the pixel")
    }

    #[inline(always)]
    fn pixel(&mut self, x: u32, row: u32, v: PixelValue) {
        let p = self.index(x, row);
        if let Some(c) = v.color {
            self.color[p] = c;
        }
        self.depth[p] = v.depth;
        self.normal[p] = v.normal;
        self.samples[p] = v.samples;
    }

    #[inline(always)]
    fn cost(&mut self, x: u32, row: u32, c: PixelCost) {
        let p = self.index(x, row);
        self.cost[p] = c;
    }
}

impl PixelSink for TileFilm {
    #[inline(always)]
    fn spreads(&self) -> bool {
        self.support() > 0
    }

    #[inline(always)]
    fn splat(&mut self, x: u32, row: u32, o: Vec2, c: Vec3) {
        TileFilm::splat(self, x, row, o, c);
    }

    #[inline(always)]
    fn pixel(&mut self, x: u32, row: u32, v: PixelValue) {
        if let Some(c) = v.color {
            self.set_pixel(x, row, c);
        }
        let k = self.tile_index(x, row);
        self.depth[k] = v.depth;
        self.normal[k] = v.normal;
        self.samples[k] = v.samples;
    }

    #[inline(always)]
    fn cost(&mut self, x: u32, row: u32, c: PixelCost) {
        let k = self.tile_index(x, row);
        self.cost[k] = c;
    }
}

/// How a pixel's camera samples are chosen, traced and reduced to its
/// channels.
pub(super) trait PixelStrategy {
    /// Traces pixel `(x, row)` (frame coordinates) into `sink`, counting its
    /// rays in `counters` and pushing its samples to `kept` if they are to be
    /// kept. Returns the cost of work done for the pixel outside
    /// `counters` (rays shared between pixels and traced beforehand; zero
    /// when there are none).
    fn pixel<S: PixelSink>(
        &mut self,
        sink: &mut S,
        x: u32,
        row: u32,
        counters: &mut Counters,
        kept: &mut Vec<SampleRecord>,
    ) -> PixelCost;

    /// Traces the pixels `x0..x1` of row `row` into `sink` as
    /// [`pixel`](Self::pixel) would one after the other (the same channels,
    /// splats in the same order, kept samples in the same order per
    /// pixel), when the strategy traces them together; returns `false`,
    /// having done nothing, when it does not (the default). Not asked for
    /// a cost plane: a pixel's cost is its own rays'.
    fn row<S: PixelSink>(
        &mut self,
        sink: &mut S,
        (x0, x1, row): (u32, u32, u32),
        counters: &mut Counters,
        kept: &mut Vec<SampleRecord>,
    ) -> bool {
        let _ = (sink, x0, x1, row, counters, kept);
        false
    }
}

/// The loop: every pixel of `rect`, rows in groups of [`BAND_ROWS`], each
/// group in blocks of [`BLOCK`] columns traced row by row (whole rows, in
/// order, when the sink spreads samples over neighbours); with `cost`, each
/// pixel's rays' intersection tests and nodes visited go to the sink's cost
/// plane (so the pixels' costs add up to the returned counters plus the
/// strategy's shared work). The kept samples come back in pixel order (rows
/// top down, then columns; each pixel's in index order).
#[inline]
pub(super) fn render_unit<P: PixelStrategy, S: PixelSink>(
    strategy: &mut P,
    rect: Rect,
    sink: &mut S,
    cost: bool,
) -> (Counters, Vec<SampleRecord>) {
    let mut counters = Counters::default();
    let mut kept = Vec::new();
    // Samples splatted over neighbours add up in the order they come: rows
    // in order, whole, keep that sum's order (and the image) what it is.
    let block = if sink.spreads() {
        rect.width().max(1)
    } else {
        BLOCK as u32
    };
    for r0 in (rect.row0..rect.row1).step_by(BAND_ROWS) {
        let r1 = (r0 + BAND_ROWS as u32).min(rect.row1);
        for x0 in (rect.x0..rect.x1).step_by(block as usize) {
            let x1 = (x0 + block).min(rect.x1);
            for row in r0..r1 {
                if !cost && strategy.row(sink, (x0, x1, row), &mut counters, &mut kept) {
                    continue;
                }
                for x in x0..x1 {
                    let before = counters;
                    let shared = strategy.pixel(sink, x, row, &mut counters, &mut kept);
                    if cost {
                        sink.cost(
                            x,
                            row,
                            PixelCost {
                                tests: counters.intersection_tests - before.intersection_tests
                                    + shared.tests,
                                nodes: counters.nodes_visited - before.nodes_visited + shared.nodes,
                            },
                        );
                    }
                }
            }
        }
    }
    if !kept.is_empty() {
        // A stable sort keeps each pixel's samples in index order.
        kept.sort_by_key(|s| (std::cmp::Reverse(s.pixel.1), s.pixel.0));
    }
    (counters, kept)
}

/// A pixel's samples as they arrive: the filter-weighted colour sum, and the
/// hit of the sample nearest the pixel's reference point.
#[derive(Clone, Copy, Debug)]
struct Accumulator {
    sum: Vec3,
    weight: f32,
    nearest: f32,
    depth: f32,
    normal: Vec3,
}

impl Accumulator {
    const EMPTY: Self = Self {
        sum: Vec3::ZERO,
        weight: 0.0,
        nearest: f32::INFINITY,
        depth: f32::INFINITY,
        normal: Vec3::ZERO,
    };

    /// Adds colour `c` with filter weight `wt`.
    #[inline(always)]
    fn add(&mut self, c: Vec3, wt: f32) {
        if wt == 1.0 {
            // `c · 1` is `c`: the box filters' case.
            self.sum += c;
            self.weight += 1.0;
        } else if wt != 0.0 {
            self.sum += c * wt;
            self.weight += wt;
        }
    }

    /// Keeps `hit` if its sample, at squared distance `d2` from the
    /// reference point, is the nearest so far (the first of equals).
    ///
    /// Chosen with a mask, not a branch: which of a pixel's samples lies
    /// nearest is random, and the branch was mispredicted about every other
    /// sample (callgrind --branch-sim, dof_spheres_lit at 4 spp: a fifth of
    /// the render's mispredicts).
    #[inline(always)]
    fn hit(&mut self, d2: f32, hit: Option<&Hit>) {
        let (t, n) = hit.map_or((f32::INFINITY, Vec3::ZERO), |h| (h.t, h.normal));
        let keep = u32::from(d2 < self.nearest).wrapping_neg();
        let pick =
            |new: f32, old: f32| f32::from_bits((new.to_bits() & keep) | (old.to_bits() & !keep));
        self.nearest = pick(d2, self.nearest);
        self.depth = pick(t, self.depth);
        self.normal = Vec3::new(
            pick(n.x, self.normal.x),
            pick(n.y, self.normal.y),
            pick(n.z, self.normal.z),
        );
    }

    /// The weighted mean (black when no sample had weight). `sum / 1` is
    /// `sum`, as the film's merge gives it, so a band and a tile agree bit for bit.
    #[inline(always)]
    fn color(&self) -> Vec3 {
        if self.weight == 1.0 {
            self.sum
        } else if self.weight > 0.0 {
            self.sum / self.weight
        } else {
            Vec3::ZERO
        }
    }
}

/// The sampler's strategy: `spp` samples at the sampler's positions,
/// reconstructed by the filter; a one-ray render takes a short path.
pub(super) struct Supersample<'a, I> {
    step: Step<'a, I>,
    sampler: &'a Sampler,
    filter: Filter,
    reference: Vec2,
    keep: bool,
    /// One ray per pixel at a fixed offset: its position and weight, the
    /// same for every pixel.
    fixed: Option<(Vec2, f32)>,
    /// The one-ray render (the default): a pixel is its sample's colour, no
    /// sums, weights or distances.
    one_ray: Option<Vec2>,
    /// Trace the camera rays of up to [`PACKET`] neighbouring pixels of a
    /// row together (see [`Step::packets`]).
    packets: bool,
    /// Each pixel's samples of a packet row, `(offset, colour)`, pixel by
    /// pixel, when the sink spreads them: splatted in the order the
    /// per-pixel loop splats them.
    splats: Vec<(Vec2, Vec3)>,
}

impl<'a, I: Integrator> Supersample<'a, I> {
    pub fn new(step: Step<'a, I>, settings: &'a Settings) -> Self {
        let sampler = &settings.sampler;
        let filter = settings.filter;
        let fixed = sampler
            .fixed_offset()
            .map(|o| (o, filter.weight(o.x - 0.5, o.y - 0.5)));
        let one_ray = match fixed {
            Some((o, wt)) if sampler.spp() == 1 && wt == 1.0 && !settings.keep_samples => Some(o),
            _ => None,
        };
        let packets = step.packets();
        Self {
            step,
            sampler,
            filter,
            reference: settings.reference,
            keep: settings.keep_samples,
            fixed,
            one_ray,
            packets,
            splats: Vec::new(),
        }
    }

    /// A camera sample's in-pixel offset and filter weight, taken from
    /// (or, when fixed, skipped in) its stream.
    #[inline(always)]
    fn offset(&self, stream: &mut SampleStream<'a>) -> (Vec2, f32) {
        match self.fixed {
            Some(f) => {
                stream.skip();
                f
            }
            None => {
                let o = stream.next_2d();
                (o, self.filter.weight(o.x - 0.5, o.y - 0.5))
            }
        }
    }

    /// The camera sample `k` of pixel `(i, j)`: its stream (past the
    /// camera's dimensions), in-pixel offset, filter weight and ray.
    #[inline(always)]
    fn camera_sample(&self, (i, j): (u32, u32), k: u32) -> (SampleStream<'a>, Vec2, f32, Ray) {
        let mut stream = self.sampler.stream((i, j), k);
        let (o, wt) = self.offset(&mut stream);
        let ray = self.step.ray((i, j, o), &mut stream);
        (stream, o, wt, ray)
    }

    /// Pixels `x0..x0 + n` of row `row` (`n` at most [`PACKET`]): the
    /// camera rays of each sample index traced as one packet, then each
    /// sample shaded and reduced as [`PixelStrategy::pixel`] does. Each
    /// pixel's samples are added in index order, and spread samples
    /// splatted pixel after pixel, so the channels are the per-pixel
    /// loop's bit for bit. (The one-ray shortcut's pixel, `0 + c`, is the
    /// accumulator's: a sum from zero of one sample of weight 1.)
    fn packet<S: PixelSink>(
        &mut self,
        sink: &mut S,
        (x0, n, row): (u32, usize, u32),
        counters: &mut Counters,
        kept: &mut Vec<SampleRecord>,
    ) {
        let j = self.step.size.1 - 1 - row;
        let spp = self.sampler.spp();
        let spreads = sink.spreads();
        if spreads {
            self.splats.clear();
            self.splats
                .resize(n * spp as usize, (Vec2::ZERO, Vec3::ZERO));
        }
        let tmin = self.step.camera.tmin();
        let mut acc = [Accumulator::EMPTY; PACKET];
        let mut rays = [PacketRay {
            ray: Ray::new(Vec3::ZERO, Vec3::Z),
            tmin,
            tmax: f32::INFINITY,
        }; PACKET];
        let mut hits = [None; PACKET];
        for k in 0..spp {
            let mut samples: [Option<(SampleStream, Vec2, f32)>; PACKET] = Default::default();
            for (p, (q, s)) in rays.iter_mut().zip(&mut samples).take(n).enumerate() {
                let (stream, o, wt, ray) = self.camera_sample((x0 + p as u32, j), k);
                q.ray = ray;
                *s = Some((stream, o, wt));
            }
            (self.step.world).intersect_packet(&rays[..n], &mut hits[..n], counters);
            for (p, s) in samples.iter_mut().take(n).enumerate() {
                let Some((stream, o, wt)) = s else {
                    unreachable!("every pixel of the packet has its sample")
                };
                let (o, i) = (*o, x0 + p as u32);
                let hit = hits[p].as_ref();
                let c = (self.step).shade(&rays[p].ray, hit, stream, counters);
                if spreads {
                    self.splats[p * spp as usize + k as usize] = (o, c);
                } else {
                    acc[p].add(c, *wt);
                }
                let d2 = if spp == 1 {
                    0.0
                } else {
                    (o - self.reference).length_squared()
                };
                acc[p].hit(d2, hit);
                if self.keep {
                    kept.push(SampleRecord {
                        pixel: (i, j),
                        offset: o,
                        color: c,
                    });
                }
            }
        }
        for (p, acc) in acc.iter().take(n).enumerate() {
            let x = x0 + p as u32;
            if spreads {
                let samples = &self.splats[p * spp as usize..(p + 1) * spp as usize];
                for &(o, c) in samples {
                    sink.splat(x, row, o, c);
                }
            }
            sink.pixel(
                x,
                row,
                PixelValue {
                    color: (!spreads).then(|| acc.color()),
                    depth: acc.depth,
                    normal: acc.normal,
                    samples: spp,
                },
            );
        }
    }
}

impl<I: Integrator> PixelStrategy for Supersample<'_, I> {
    #[inline(always)]
    fn pixel<S: PixelSink>(
        &mut self,
        sink: &mut S,
        x: u32,
        row: u32,
        counters: &mut Counters,
        kept: &mut Vec<SampleRecord>,
    ) -> PixelCost {
        // Row 0 of the frame is the top of the image; screen j grows upwards.
        let (i, j) = (x, self.step.size.1 - 1 - row);
        let spreads = sink.spreads();
        if let (Some(o), false) = (self.one_ray, spreads) {
            let mut stream = self.sampler.stream((i, j), 0);
            stream.skip();
            let (c, hit) = self.step.sample((i, j, o), &mut stream, counters);
            sink.pixel(
                x,
                row,
                PixelValue {
                    // `0 + c` is the film's arithmetic (it turns a -0 into +0).
                    color: Some(Vec3::ZERO + c),
                    depth: hit.map_or(f32::INFINITY, |h| h.t),
                    normal: hit.map_or(Vec3::ZERO, |h| h.normal),
                    samples: 1,
                },
            );
            return PixelCost::default();
        }
        let spp = self.sampler.spp();
        let mut acc = Accumulator::EMPTY;
        for k in 0..spp {
            let mut stream = self.sampler.stream((i, j), k);
            let (o, wt) = self.offset(&mut stream);
            let (c, hit) = self.step.sample((i, j, o), &mut stream, counters);
            if spreads {
                sink.splat(x, row, o, c);
            } else {
                acc.add(c, wt);
            }
            // A lone sample is the nearest: skip the distance.
            let d2 = if spp == 1 {
                0.0
            } else {
                (o - self.reference).length_squared()
            };
            acc.hit(d2, hit.as_ref());
            if self.keep {
                kept.push(SampleRecord {
                    pixel: (i, j),
                    offset: o,
                    color: c,
                });
            }
        }
        sink.pixel(
            x,
            row,
            PixelValue {
                color: (!spreads).then(|| acc.color()),
                depth: acc.depth,
                normal: acc.normal,
                samples: spp,
            },
        );
        PixelCost::default()
    }

    /// Packets of up to [`PACKET`] pixels of the row, when the step takes
    /// packets.
    fn row<S: PixelSink>(
        &mut self,
        sink: &mut S,
        (x0, x1, row): (u32, u32, u32),
        counters: &mut Counters,
        kept: &mut Vec<SampleRecord>,
    ) -> bool {
        if !self.packets {
            return false;
        }
        for x in (x0..x1).step_by(PACKET) {
            let n = (x1 - x).min(PACKET as u32) as usize;
            self.packet(sink, (x, n, row), counters, kept);
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(t: f32, normal: Vec3) -> Hit {
        Hit {
            t,
            point: Vec3::ZERO,
            error: Vec3::ZERO,
            normal,
            shading_normal: normal,
            prim: 0,
            material: 0,
            instance: 0,
        }
    }

    /// A pixel keeps the hit of its sample nearest the reference point (the
    /// first of equals; a miss as well), whatever the order of arrival.
    #[test]
    fn the_nearest_sample_s_hit_is_kept() {
        let mut a = Accumulator::EMPTY;
        a.hit(0.5, Some(&hit(3.0, Vec3::X)));
        a.hit(0.2, Some(&hit(4.0, Vec3::Y)));
        a.hit(0.3, Some(&hit(5.0, Vec3::Z)));
        a.hit(0.2, None);
        assert_eq!((a.depth, a.normal), (4.0, Vec3::Y));
        a.hit(0.1, None);
        assert_eq!((a.depth, a.normal), (f32::INFINITY, Vec3::ZERO));
        assert_eq!(
            (Accumulator::EMPTY.depth, Accumulator::EMPTY.normal),
            (f32::INFINITY, Vec3::ZERO)
        );
    }

    /// The weighted mean: weights of 1 add the colour itself, weights of 0
    /// nothing, others the weighted colour; no weight at all is black.
    #[test]
    fn the_colour_is_the_weighted_mean() {
        let mut a = Accumulator::EMPTY;
        assert_eq!(a.color(), Vec3::ZERO);
        a.add(Vec3::new(1.0, 2.0, 4.0), 0.0);
        assert_eq!(a.color(), Vec3::ZERO);
        a.add(Vec3::new(1.0, 2.0, 4.0), 1.0);
        assert_eq!(a.color(), Vec3::new(1.0, 2.0, 4.0));
        a.add(Vec3::new(3.0, 0.0, 0.0), 0.5);
        assert_eq!(a.color(), Vec3::new(2.5, 2.0, 4.0) / 1.5);
    }

    /// The loop visits every pixel of a rectangle exactly once, in blocks of
    /// `BLOCK` columns of `BAND_ROWS` rows, and fills the cost plane with
    /// each pixel's share when asked.
    #[test]
    fn the_loop_visits_every_pixel_once_in_blocks() {
        struct Order(Vec<(u32, u32)>);
        impl PixelStrategy for Order {
            fn pixel<S: PixelSink>(
                &mut self,
                sink: &mut S,
                x: u32,
                row: u32,
                counters: &mut Counters,
                _: &mut Vec<SampleRecord>,
            ) -> PixelCost {
                self.0.push((x, row));
                counters.intersection_tests += x as u64;
                sink.pixel(
                    x,
                    row,
                    PixelValue {
                        color: None,
                        depth: 0.0,
                        normal: Vec3::ZERO,
                        samples: 1,
                    },
                );
                PixelCost { tests: 0, nodes: 1 }
            }
        }
        let rect = Rect {
            x0: 3,
            row0: 2,
            x1: 3 + 19,
            row1: 2 + 9,
        };
        let mut film = TileFilm::new(rect, Filter::Box(0.5), (40, 20));
        let mut order = Order(Vec::new());
        let (c, kept) = render_unit(&mut order, rect, &mut film, true);
        assert!(kept.is_empty());
        let mut want = Vec::new();
        for r0 in [2, 6, 10] {
            for x0 in [3, 11, 19] {
                for row in r0..(r0 + 4).min(11) {
                    for x in x0..(x0 + 8).min(22) {
                        want.push((x, row));
                    }
                }
            }
        }
        assert_eq!(order.0, want);
        assert_eq!(
            c.intersection_tests,
            want.iter().map(|&(x, _)| x as u64).sum::<u64>()
        );
        // A film that spreads samples over neighbours gets whole rows in
        // order (the order its sums add up in).
        let mut spread = TileFilm::new(rect, Filter::Tent(1.5), (40, 20));
        let mut rows = Order(Vec::new());
        render_unit(&mut rows, rect, &mut spread, false);
        let row_major: Vec<_> = (2..11).flat_map(|r| (3..22).map(move |x| (x, r))).collect();
        assert_eq!(rows.0, row_major);
        for &(x, row) in &want {
            let k = film.tile_index(x, row);
            assert_eq!(
                film.cost[k],
                PixelCost {
                    tests: x as u64,
                    nodes: 1
                }
            );
            assert_eq!(film.samples[k], 1);
        }
    }
}
