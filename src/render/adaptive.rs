//! Whitted's adaptive supersampling (1980): trace the four corners of every
//! pixel (each corner shared with the neighbouring pixels); where they differ
//! by more than a threshold, split the square into quadrants, trace the five
//! new points, and recurse to a maximum depth. A square's value is the mean
//! of its four quadrants, or of its corners when it is not split.
//!
//! All points lie on a lattice of `2^depth` steps per pixel, and a point's
//! colour is a pure function of its lattice coordinates (its higher sample
//! dimensions are keyed on them too), so a point traced twice, by two tiles,
//! gives the same colour: tiles stay independent and the image stays the
//! same for any thread count.
//!
//! Pass 1 traces the pixel corners (`(w+1)·(h+1)` rays, rows in parallel);
//! pass 2 subdivides tile by tile, sharing the new points within a tile.
//! Points on an edge between two tiles that both split it are traced by
//! both; the statistics count every ray actually traced.

use super::film::{merge, tiles, TileFilm};
use super::pixel::{render_unit, PixelSink, PixelStrategy, PixelValue, Step};
use super::{Filter, Frame, PixelCost, Render, Rendered, SampleRecord, Settings};
use crate::integrator::Integrator;
use crate::math::{Vec2, Vec3};
use crate::stats::Counters;
use rayon::prelude::*;
use std::collections::HashMap;

/// Settings of the subdivision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    /// Split a square when, in some channel, its corners (clamped to
    /// `[0, 1]`, as displayed) differ by more than this.
    pub threshold: f32,
    /// Deepest subdivision: squares of `2^-max_depth` pixels.
    pub max_depth: u32,
}

impl Adaptive {
    /// Default maximum depth: 4 × 4 sub-squares, as many points as 16-spp
    /// uniform sampling at most.
    pub const DEFAULT_MAX_DEPTH: u32 = 2;
    /// Deepest subdivision accepted (256 × 256 sub-squares per pixel).
    pub const MAX_DEPTH: u32 = 8;
}

/// Lattice coordinates of a point: `2^max_depth` steps per pixel, `y` up.
type Point = (u32, u32);

/// Colour, camera-ray hit and cost of a traced pixel corner.
#[derive(Clone, Copy)]
struct Traced {
    color: Vec3,
    hit: Option<(f32, Vec3)>,
    cost: PixelCost,
}

/// What traces lattice points: the per-sample step and the settings.
struct Tracer<'a, I> {
    step: Step<'a, I>,
    settings: &'a Settings,
    /// Lattice steps per pixel.
    steps: u32,
}

impl<I: Integrator> Tracer<'_, I> {
    /// The point's colour and camera-ray hit, through the loops' one
    /// per-sample step with a stream of the point's own.
    fn trace(&self, (x, y): Point, counters: &mut Counters) -> (Vec3, Option<(f32, Vec3)>) {
        let s = self.steps;
        let o = Vec2::new((x % s) as f32 / s as f32, (y % s) as f32 / s as f32);
        let key = (x as u64) | (y as u64) << 32;
        let mut stream = self.settings.sampler.stream_for_key(key);
        let (color, hit) = self.step.sample((x / s, y / s, o), &mut stream, counters);
        (color, hit.map(|h| (h.t, h.normal)))
    }

    /// A pixel corner, with what tracing it cost.
    fn corner(&self, p: Point, counters: &mut Counters) -> Traced {
        let before = *counters;
        let (color, hit) = self.trace(p, counters);
        Traced {
            color,
            hit,
            cost: PixelCost {
                tests: counters.intersection_tests - before.intersection_tests,
                nodes: counters.nodes_visited - before.nodes_visited,
            },
        }
    }
}

/// Renders with adaptive subdivision (called by [`super::render_image`]).
pub(super) fn render<I: Integrator>(r: &Render<I>, a: &Adaptive) -> Rendered {
    let (settings, control) = (r.settings, r.control);
    let (w, h) = settings.size;
    let depth = a.max_depth.min(Adaptive::MAX_DEPTH);
    let tracer = Tracer {
        step: r.step(),
        settings,
        steps: 1 << depth,
    };
    // Pass 1: the pixel corners, rows of corners in parallel (bottom first).
    let corner_rows: Vec<Option<(Vec<Traced>, Counters)>> = (0..=h)
        .into_par_iter()
        .map(|j| {
            if control.cancelled() {
                return None;
            }
            let mut c = Counters::default();
            let row = (0..=w)
                .map(|i| tracer.corner((i << depth, j << depth), &mut c))
                .collect();
            Some((row, c))
        })
        .collect();
    let mut counters = Counters::default();
    let corners_done = corner_rows.iter().all(Option::is_some);
    for (_, c) in corner_rows.iter().flatten() {
        counters += *c;
    }
    let rects = tiles(w, h, settings.tile_size);
    let films: Vec<Option<(TileFilm, Counters)>> = rects
        .par_iter()
        .map(|&rect| {
            if !corners_done || control.cancelled() {
                return None;
            }
            // The pixel's colour is set directly (weight 1): the film's filter is
            // unused, a box of the pixel's own square by construction.
            let mut film = TileFilm::new(rect, Filter::Box(0.5), (w, h));
            let mut strategy = Subdivide {
                tracer: &tracer,
                threshold: a.threshold,
                corners: &corner_rows,
                cache: HashMap::new(),
            };
            let (c, _) = render_unit(&mut strategy, rect, &mut film, settings.pixel_cost);
            control.progress(rect.area() as u64);
            Some((film, c))
        })
        .collect();
    let films: Vec<Option<TileFilm>> = films
        .into_iter()
        .map(|f| {
            f.map(|(film, c)| {
                counters += c;
                film
            })
        })
        .collect();
    let mut frame = Frame::new(w, h);
    merge(&films, settings.tile_size, 0, &mut frame);
    Rendered {
        frame,
        counters,
        samples: Vec::new(),
    }
}

/// Pass 2's strategy for the pixels of one tile: every pixel's square,
/// subdivided where needed, new points traced once per tile.
struct Subdivide<'a, 't, I> {
    tracer: &'a Tracer<'t, I>,
    threshold: f32,
    corners: &'a [Option<(Vec<Traced>, Counters)>],
    cache: HashMap<Point, Vec3>,
}

impl<I> Subdivide<'_, '_, I> {
    /// The pixel corner `(i, j)` of pass 1.
    fn corner(&self, i: u32, j: u32) -> Traced {
        self.corners[j as usize]
            .as_ref()
            .expect("pass 1 complete")
            .0[i as usize]
    }
}

impl<I: Integrator> PixelStrategy for Subdivide<'_, '_, I> {
    /// Also returns the cost of the corners the pixel owns: its lower-left
    /// one, and the right or top one on the image's last column or row, so
    /// every corner belongs to exactly one pixel and the pixels' costs add
    /// up to the render's counters.
    fn pixel<S: PixelSink>(
        &mut self,
        sink: &mut S,
        x: u32,
        row: u32,
        counters: &mut Counters,
        _: &mut Vec<SampleRecord>,
    ) -> PixelCost {
        let (w, h) = self.tracer.settings.size;
        let (i, j) = (x, h - 1 - row);
        let s = self.tracer.steps;
        let c = [
            self.corner(i, j).color,
            self.corner(i + 1, j).color,
            self.corner(i, j + 1).color,
            self.corner(i + 1, j + 1).color,
        ];
        let mut used = vec![
            (i * s, j * s),
            ((i + 1) * s, j * s),
            (i * s, (j + 1) * s),
            ((i + 1) * s, (j + 1) * s),
        ];
        let mut sq = Square {
            tracer: self.tracer,
            threshold: self.threshold,
            cache: &mut self.cache,
            counters,
            used: &mut used,
        };
        let color = sq.value((i * s, j * s), s, c);
        used.sort_unstable();
        used.dedup();
        // Depth and normal: the pixel's lower-left corner ray.
        let (depth, normal) = self.corner(i, j).hit.unwrap_or((f32::INFINITY, Vec3::ZERO));
        sink.pixel(
            x,
            row,
            PixelValue {
                color: Some(color),
                depth,
                normal,
                samples: used.len() as u32,
            },
        );
        let mut owned = self.corner(i, j).cost;
        let mut own = |ci: u32, cj: u32| {
            let c = self.corner(ci, cj).cost;
            owned.tests += c.tests;
            owned.nodes += c.nodes;
        };
        if i + 1 == w {
            own(w, j);
        }
        if j + 1 == h {
            own(i, h);
        }
        if i + 1 == w && j + 1 == h {
            own(w, h);
        }
        owned
    }
}

/// The recursion over one pixel's square.
struct Square<'a, 't, I> {
    tracer: &'a Tracer<'t, I>,
    threshold: f32,
    cache: &'a mut HashMap<Point, Vec3>,
    counters: &'a mut Counters,
    used: &'a mut Vec<Point>,
}

impl<I: Integrator> Square<'_, '_, I> {
    /// Colour of a lattice point, traced once per tile.
    fn point(&mut self, p: Point) -> Vec3 {
        self.used.push(p);
        if let Some(&c) = self.cache.get(&p) {
            return c;
        }
        let c = self.tracer.trace(p, self.counters).0;
        self.cache.insert(p, c);
        c
    }

    /// Mean colour over the square at lattice point `p0` (lower-left) with
    /// edge `size` lattice steps and corner colours `c` (`[00, 10, 01, 11]`).
    fn value(&mut self, p0: Point, size: u32, c: [Vec3; 4]) -> Vec3 {
        if size == 1 || spread(&c) <= self.threshold {
            return (c[0] + c[1] + c[2] + c[3]) * 0.25;
        }
        let hs = size / 2;
        let (x, y) = p0;
        let b = self.point((x + hs, y));
        let l = self.point((x, y + hs));
        let m = self.point((x + hs, y + hs));
        let r = self.point((x + size, y + hs));
        let t = self.point((x + hs, y + size));
        let q00 = self.value((x, y), hs, [c[0], b, l, m]);
        let q10 = self.value((x + hs, y), hs, [b, c[1], m, r]);
        let q01 = self.value((x, y + hs), hs, [l, m, c[2], t]);
        let q11 = self.value((x + hs, y + hs), hs, [m, r, t, c[3]]);
        (q00 + q10 + q01 + q11) * 0.25
    }
}

/// Largest per-channel range of four colours, clamped to the displayable
/// `[0, 1]` (differences among over-bright values do not show).
fn spread(c: &[Vec3; 4]) -> f32 {
    let d = c.map(|v| v.clamp(Vec3::ZERO, Vec3::ONE));
    let lo = d[0].min(d[1]).min(d[2]).min(d[3]);
    let hi = d[0].max(d[1]).max(d[2]).max(d[3]);
    (hi - lo).max_element()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::{CameraModel, Control};
    use crate::world::World;
    use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

    #[test]
    fn spread_is_the_largest_channel_range() {
        let c = [
            Vec3::new(0.1, 0.5, 0.0),
            Vec3::new(0.2, 0.5, 0.0),
            Vec3::new(0.1, 0.9, 0.0),
            Vec3::new(0.1, 0.5, 3.0),
        ];
        assert!((spread(&c) - 1.0).abs() < 1e-6); // blue clamped to 1
        assert_eq!(spread(&[Vec3::ONE; 4]), 0.0);
    }

    /// An 8x8 orthographic view (x and y from -4 to 4), one world unit per
    /// pixel, of a lit half-plane `axis < e`: a triangle whose edge
    /// `axis = e` runs straight through one column (`x`) or one row (`y`)
    /// of pixels.
    fn edge_scene(axis: char, e: f32) -> (World, CameraModel) {
        let far = 100.0;
        let v = |along: f32, across: f32| match axis {
            'x' => format!("{across} {along} 0"),
            _ => format!("{along} {across} 0"),
        };
        let src = format!(
            "OrthographicCamera {{ center 0 0 10 direction 0 0 -1 up 0 1 0 size 8 }}
             Lights {{ numLights 0 }}
             Background {{ color 0 0 0 ambientLight 1 1 1 }}
             Materials {{ numMaterials 1 PhongMaterial {{ diffuseColor 1 1 1 }} }}
             Group {{ numObjects 1 MaterialIndex 0
               Triangle {{ vertex0 {} vertex1 {} vertex2 {} }} }}",
            v(-far, e),
            v(far, e),
            v(0.0, -far)
        );
        let scene = crate::format::parse_scene(&src, std::path::Path::new("edge.txt")).unwrap();
        let world = World::build(&scene, crate::world::BuildOptions::default());
        let camera = CameraModel::new(world.camera());
        (world, camera)
    }

    /// Adaptive settings for the 8x8 edge view.
    fn edge_settings(max_depth: u32, threshold: f32) -> Settings {
        Settings {
            adaptive: Some(Adaptive {
                threshold,
                max_depth,
            }),
            ..Settings::one_ray((8, 8), super::super::PixelOffset::CENTER)
        }
    }

    /// Both sides lit: the two edges' triangles face opposite ways.
    fn lit_both_sides() -> crate::integrator::Whitted {
        crate::integrator::Whitted {
            shade_back: true,
            ..Default::default()
        }
    }

    fn edge_frame(axis: char, e: f32, max_depth: u32, threshold: f32) -> (Frame, Counters) {
        let (world, camera) = edge_scene(axis, e);
        let settings = edge_settings(max_depth, threshold);
        let r = super::super::render_image(
            &world,
            &camera,
            &lit_both_sides(),
            &settings,
            Control::default(),
        );
        (r.frame, r.counters)
    }

    /// An integrator whose colour is the point's first stream value: points
    /// that share a stream get the same colour.
    struct StreamValue;

    impl Integrator for StreamValue {
        fn li_hit<O: crate::integrator::RayObserver>(
            &self,
            cx: &mut crate::integrator::Trace<O>,
            _: &crate::math::Ray,
            _: f32,
            _: Option<&crate::world::Hit>,
        ) -> Vec3 {
            Vec3::splat(cx.stream.next_1d())
        }
    }

    /// Every lattice point has a stream of its own, so the noise of two
    /// points is independent. Unsplit, a pixel is the mean of its four
    /// corners' values: with a stream per point all 64 pixels differ; with
    /// a stream shared by all the points (a key of 0) they would be equal,
    /// and with one per lattice column (a key of `x` alone) every column of
    /// pixels would be one value.
    #[test]
    fn every_lattice_point_has_its_own_stream() {
        let (world, camera) = edge_scene('x', 0.3);
        for depth in [0, 2] {
            let s = edge_settings(depth, 2.0);
            let f =
                super::super::render_image(&world, &camera, &StreamValue, &s, Control::default())
                    .frame;
            let mut bits: Vec<u32> = f.color.iter().map(|c| c.x.to_bits()).collect();
            bits.sort_unstable();
            bits.dedup();
            assert_eq!(bits.len(), 64, "depth {depth}");
        }
    }

    /// A cancel that arrives between the passes (here from the first
    /// tile's progress report, on one thread, so in pass 2) stops the tiles
    /// not yet started: one 2x2 tile is done, the frame is incomplete.
    #[test]
    fn a_cancel_in_the_second_pass_stops_it() {
        let (world, camera) = edge_scene('x', 0.3);
        let settings = Settings {
            tile_size: 2,
            ..edge_settings(2, 0.01)
        };
        let stop = AtomicBool::new(false);
        let done = AtomicU64::new(0);
        let tick = |n: u64| {
            done.fetch_add(n, Ordering::Relaxed);
            stop.store(true, Ordering::Relaxed);
        };
        let control = Control {
            cancel: Some(&stop),
            on_progress: Some(&tick),
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let r = pool.install(|| {
            super::super::render_image(&world, &camera, &lit_both_sides(), &settings, control)
        });
        assert_eq!(done.load(Ordering::Relaxed), 4);
        // Rows are complete only when all their tiles are.
        assert!(r.frame.complete.iter().all(|&c| !c));
        assert!(!r.frame.is_complete());
    }

    /// Closed form: the lattice has `s = 2^depth` columns per pixel; the
    /// subdivision splits exactly the squares the edge crosses, down to one
    /// lattice step, where a square straddling the edge is worth 1/2. So the
    /// edge pixel is `(⌊0.3·s⌋ + 1/2)/s` of the lit value (0.5, 0.25, 0.375,
    /// 0.3125, 0.28125 for depths 0 to 4: exact binary fractions), pixels
    /// before the edge are lit and pixels past it are background. The edge
    /// lies 0.3 of the way across a pixel: at 0.3, column 4 (x from -4 to
    /// 4, left to right) or row 3 from the top (frame rows count from the
    /// top); and at -3.7, the first column or the bottom row, where lattice
    /// coordinates start at 0 (a point `x · size` for `x + size` is then
    /// traced on the lit side).
    #[test]
    fn an_edge_pixel_is_the_lattice_fraction_it_covers() {
        for depth in 0..=4 {
            let s = (1u32 << depth) as f32;
            let want = ((0.3 * s).floor() + 0.5) / s;
            for (axis, e) in [('x', 0.3), ('y', 0.3), ('x', -3.7), ('y', -3.7)] {
                let (f, _) = edge_frame(axis, e, depth, 0.01);
                // Inside: ambient 1 times diffuse 1, exactly (a wrong mean of
                // a flat square would scale it).
                let lit = Vec3::ONE;
                // The edge's column, or its row counted from the bottom.
                let edge = (e + 4.0).floor() as i32;
                for row in 0..8usize {
                    for col in 0..8usize {
                        // Position across the edge, in pixels from the edge's pixel.
                        let k = if axis == 'x' {
                            col as i32 - edge
                        } else {
                            (7 - row as i32) - edge
                        };
                        let expect = match k {
                            ..=-1 => lit,
                            0 => lit * want,
                            _ => Vec3::ZERO,
                        };
                        let got = f.color[row * 8 + col];
                        assert_eq!(
                            got, expect,
                            "axis {axis} at {e}, depth {depth}, pixel ({col}, {row})"
                        );
                    }
                }
            }
        }
    }

    /// Where the corners agree nothing is split: 4 points a pixel, its
    /// corners. The edge pixel at depth 3 (lattice `[0, 8]²`, the edge at
    /// x = 2.4) splits the whole square (5 new points), then the two squares
    /// of size 4 in `x ∈ [0, 4]` (9 new: `(2, 4)` is shared), then the four
    /// of size 2 in `x ∈ [2, 4]` (17 new: three shared), and stops at size 1:
    /// 4 + 5 + 9 + 17 = 35 points. In one tile, the 8 edge pixels share
    /// with the pixel above their top edge's 3 new points (x = 2, 3, 4), so
    /// the camera rays are the 81 corners plus 8 × 31 − 7 × 3 = 308. A
    /// threshold above every difference splits nothing, and the edge pixel
    /// is the mean of its corners, 1/2.
    #[test]
    fn only_the_squares_the_edge_crosses_are_split() {
        // Threshold 0: flat squares (spread exactly 0) are still not split.
        let (f, c) = edge_frame('x', 0.3, 3, 0.0);
        for row in 0..8 {
            for col in 0..8 {
                let want = if col == 4 { 35 } else { 4 };
                assert_eq!(f.samples[row * 8 + col], want, "pixel ({col}, {row})");
            }
        }
        assert_eq!(c.primary, 308);
        let (f, c) = edge_frame('x', 0.3, 3, 2.0);
        assert_eq!(c.primary, 81);
        assert!(f.samples.iter().all(|&n| n == 4));
        let lit = f.color[7 * 8];
        assert_eq!(f.color[7 * 8 + 4], lit * 0.5);
    }
}
