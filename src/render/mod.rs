//! The render loop: bands of rows or tiles over rayon, each pixel sampled by
//! a [`Sampler`] (or, with [`Adaptive`] settings, Whitted's corner
//! subdivision), traced by an [`Integrator`] and reconstructed by a
//! [`Filter`], in the frame itself or on a [`film`]. Every path is the one
//! pixel loop of `pixel.rs` with its own sink. The loop knows nothing of any
//! effect: everything random is a dimension of the sample stream it hands
//! the integrator.

mod adaptive;
mod camera;
pub mod film;
mod filter;
mod frame;
mod pixel;
pub mod views;

use crate::sampler::{SampleStream, Sampler};
pub use adaptive::Adaptive;
pub use camera::{pixel_of_screen, screen_point, CameraModel};
pub use filter::Filter;
pub use frame::{Frame, PixelCost};
pub use pixel::BAND_ROWS;

use crate::integrator::Integrator;
use crate::math::{Vec2, Vec3};
use crate::stats::Counters;
use crate::world::World;
pub use film::Rect;
use film::{merge, tiles, TileFilm};
use pixel::{render_unit, Band, Step, Supersample};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// How a caller steers a running render: stop it early, watch its progress.
#[derive(Default, Clone, Copy)]
pub struct Control<'a> {
    /// When set (e.g. by a Ctrl-C handler), tiles not yet started are skipped.
    pub cancel: Option<&'a AtomicBool>,
    /// Called with a number of pixels each time a piece of work finishes,
    /// from the worker threads (the calls add up to width × height).
    pub on_progress: Option<&'a (dyn Fn(u64) + Sync)>,
}

impl Control<'_> {
    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }

    fn progress(&self, pixels: u64) {
        if let Some(f) = self.on_progress {
            f(pixels);
        }
    }
}

/// Where in each pixel the single eye ray of a one-sample render goes.
///
/// `(0.5, 0.5)` is the pixel centre. The 6.837 reference renders match the
/// pixel's lower-left corner `(0, 0)` exactly (screen point `i/w`, the usual
/// loop of the course's ray-casting assignments), so `raytracer` uses that;
/// `glint render` uses the centre.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelOffset(pub Vec2);

impl PixelOffset {
    /// The pixel centre.
    pub const CENTER: PixelOffset = PixelOffset(Vec2::splat(0.5));
    /// The pixel's lower-left corner (the course's convention).
    pub const CORNER: PixelOffset = PixelOffset(Vec2::ZERO);
}

/// Default tile edge: 32×32 pixels is big enough that per-tile overhead
/// (film allocation, margins) is small and small enough for load balance on
/// many cores.
pub const TILE_SIZE: u32 = 32;

/// Everything that decides the image (besides the scene and integrator).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Image width and height.
    pub size: (u32, u32),
    /// Sample layout, count and seed.
    pub sampler: Sampler,
    /// Reconstruction filter.
    pub filter: Filter,
    /// In-pixel point whose nearest sample's hit fills the depth and normal
    /// planes (the pixel's "own" ray).
    pub reference: Vec2,
    /// Tile edge in pixels.
    pub tile_size: u32,
    /// Whitted's adaptive subdivision instead of the sampler's pixel
    /// positions (the sampler still provides the further dimensions).
    pub adaptive: Option<Adaptive>,
    /// Keep every sample (position, colour) for the `-render_samples` view.
    pub keep_samples: bool,
    /// Fill [`Frame::cost`], the per-pixel cost plane of `--cost-image`.
    /// Off unless asked for: writing it touches 16 bytes a pixel of fresh
    /// memory, which costs a one-ray render about 2%.
    pub pixel_cost: bool,
}

impl Settings {
    /// One ray per pixel at `offset`, box 0.5 (the pixel itself).
    pub fn one_ray((w, h): (u32, u32), offset: PixelOffset) -> Self {
        Self {
            size: (w, h),
            sampler: Sampler::fixed(offset.0),
            filter: Filter::default(),
            reference: offset.0,
            tile_size: TILE_SIZE,
            adaptive: None,
            keep_samples: false,
            pixel_cost: false,
        }
    }
}

/// One camera sample, kept for the `-render_samples` view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleRecord {
    /// Pixel `(i, j)`, image coordinates with `j` up.
    pub pixel: (u32, u32),
    /// Position inside the pixel, `[0,1)²`, `y` up.
    pub offset: Vec2,
    /// Colour the integrator returned.
    pub color: Vec3,
}

/// What a render produced.
#[derive(Clone, Debug)]
pub struct Rendered {
    /// The planes.
    pub frame: Frame,
    /// Merged ray counters.
    pub counters: Counters,
    /// Every camera sample in pixel order, if [`Settings::keep_samples`].
    pub samples: Vec<SampleRecord>,
}

/// Renders `world` seen through `camera` into a `width`×`height` frame with
/// one ray through each pixel at `offset`. Returns the merged counters.
pub fn render<I: Integrator>(
    world: &World,
    camera: &CameraModel,
    integrator: &I,
    size: (u32, u32),
    offset: PixelOffset,
) -> (Frame, Counters) {
    let r = render_image(
        world,
        camera,
        integrator,
        &Settings::one_ray(size, offset),
        Control::default(),
    );
    (r.frame, r.counters)
}

/// Renders with every [`Settings`] under a [`Control`]. Tiles skipped after a
/// cancel stay black and their rows are listed in [`Frame::complete`] as
/// `false`.
pub fn render_image<I: Integrator>(
    world: &World,
    camera: &CameraModel,
    integrator: &I,
    settings: &Settings,
    control: Control,
) -> Rendered {
    Render::new(world, camera, integrator, settings, control).run(None)
}

/// One render's inputs, as every path (bands, tiles, adaptive) takes them.
pub(super) struct Render<'a, I> {
    pub world: &'a World,
    pub camera: &'a CameraModel,
    pub integrator: &'a I,
    pub settings: &'a Settings,
    pub control: Control<'a>,
}

impl<'a, I: Integrator> Render<'a, I> {
    fn new(
        world: &'a World,
        camera: &'a CameraModel,
        integrator: &'a I,
        settings: &'a Settings,
        control: Control<'a>,
    ) -> Self {
        Self {
            world,
            camera,
            integrator,
            settings,
            control,
        }
    }

    /// The whole image (`region` `None`) or what `region`'s pixels need:
    /// adaptive subdivision when asked for (which ignores `region`), else
    /// the band loop for filters inside the pixel and the whole image, else
    /// the tiles.
    fn run(&self, region: Option<Rect>) -> Rendered {
        if let Some(a) = self.settings.adaptive {
            return adaptive::render(self, &a);
        }
        if region.is_none() && self.settings.filter.support() == 0 {
            return render_bands(self);
        }
        render_tiles(self, region)
    }

    /// The camera sample tracer the pixel strategies use.
    fn step(&self) -> Step<'a, I> {
        Step {
            world: self.world,
            camera: self.camera,
            integrator: self.integrator,
            size: self.settings.size,
        }
    }
}

/// Renders only what the pixels of `region` need: every tile whose film
/// (the tile grown by the filter's support) reaches into `region`. Inside
/// `region` the frame is bit for bit the frame [`render_image`] makes,
/// because each pixel is reconstructed from the same tile films, each a pure
/// function of the settings and the tile, summed in the same order; outside
/// it the frame is incomplete. This is what makes a frame's pieces, rendered
/// on different machines, merge exactly. It always takes the tiled path, which
/// gives the band loop's pixels bit for bit. Adaptive sampling is not supported
/// (its corner rays are shared across tiles): the region is then ignored.
pub fn render_region<I: Integrator>(
    world: &World,
    camera: &CameraModel,
    integrator: &I,
    settings: &Settings,
    control: Control,
    region: Rect,
) -> Rendered {
    Render::new(world, camera, integrator, settings, control).run(Some(region))
}

/// The tile loop of [`render_image`] and [`render_region`]: each tile's
/// pixels into a film of the tile and its filter margin, the films merged.
fn render_tiles<I: Integrator>(r: &Render<I>, region: Option<Rect>) -> Rendered {
    let (settings, control) = (r.settings, r.control);
    let (w, h) = settings.size;
    let rects = tiles(w, h, settings.tile_size);
    let support = settings.filter.support();
    let done: Vec<Option<(TileFilm, Counters, Vec<SampleRecord>)>> = rects
        .par_iter()
        .map(|&rect| {
            if control.cancelled() {
                return None;
            }
            if region.is_some_and(|r| !rect.grown(support, w, h).overlaps(&r)) {
                return None;
            }
            let step = r.step();
            let mut film = TileFilm::new(rect, settings.filter, (w, h));
            let (counters, kept) = render_unit(
                &mut Supersample::new(step, settings),
                rect,
                &mut film,
                settings.pixel_cost,
            );
            control.progress(rect.area() as u64);
            Some((film, counters, kept))
        })
        .collect();
    let mut counters = Counters::default();
    let mut samples = Vec::new();
    let mut films = Vec::with_capacity(done.len());
    for d in done {
        films.push(d.map(|(film, c, s)| {
            counters += c;
            samples.extend(s);
            film
        }));
    }
    let mut frame = Frame::new(w, h);
    merge(
        &films,
        settings.tile_size,
        settings.filter.support(),
        &mut frame,
    );
    if let Some(r) = region {
        film::complete_region(&films, &rects, support, r, &mut frame);
    }
    Rendered {
        frame,
        counters,
        samples,
    }
}

/// The loop for filters confined to their own pixel (support 0: box 0.5, the
/// course's default, and every one-sample render). No sample reaches another
/// pixel, so there are no margins to merge: the work unit is a band of
/// [`BAND_ROWS`] full rows written straight into the frame, with no film and
/// no copy. The arithmetic is the film's (`0 + w·c + …`, samples in index
/// order), so the image is the one the tiled path would give, bit for bit.
fn render_bands<I: Integrator>(r: &Render<I>) -> Rendered {
    let (settings, control) = (r.settings, r.control);
    let (w, h) = settings.size;
    // Each band fills its own depth (misses) before anything else.
    let mut frame = Frame::unset_depth(w, h);
    let wu = w as usize;
    let parts: Vec<(Counters, Vec<SampleRecord>)> = frame
        .color
        .par_chunks_mut(wu * BAND_ROWS)
        .zip(frame.depth.par_chunks_mut(wu * BAND_ROWS))
        .zip(frame.normal.par_chunks_mut(wu * BAND_ROWS))
        .zip(frame.samples.par_chunks_mut(wu * BAND_ROWS))
        .zip(frame.cost.par_chunks_mut(wu * BAND_ROWS))
        .zip(frame.complete.par_chunks_mut(BAND_ROWS))
        .enumerate()
        .map(
            |(band, (((((color, depth), normal), samples), cost), complete))| {
                depth.fill(f32::INFINITY);
                if control.cancelled() {
                    return (Counters::default(), Vec::new());
                }
                let row0 = (band * BAND_ROWS) as u32;
                let rect = Rect {
                    x0: 0,
                    row0,
                    x1: w,
                    row1: row0 + complete.len() as u32,
                };
                let mut sink = Band {
                    row0,
                    width: wu,
                    color,
                    depth,
                    normal,
                    samples,
                    cost,
                };
                let step = r.step();
                let out = render_unit(
                    &mut Supersample::new(step, settings),
                    rect,
                    &mut sink,
                    settings.pixel_cost,
                );
                complete.iter_mut().for_each(|d| *d = true);
                control.progress((complete.len() * wu) as u64);
                out
            },
        )
        .collect();
    let mut counters = Counters::default();
    let mut samples = Vec::new();
    for (c, s) in parts {
        counters += c;
        samples.extend(s);
    }
    Rendered {
        frame,
        counters,
        samples,
    }
}

/// Grey level of the depth image: `t0` (near) is white, `t1` is black,
/// clamped outside; a miss (infinite `t`) is black.
pub fn depth_grey(t: f32, t0: f32, t1: f32) -> f32 {
    if !t.is_finite() || t1 == t0 {
        return 0.0;
    }
    ((t1 - t) / (t1 - t0)).clamp(0.0, 1.0)
}

/// Colour of the normals image: the absolute value of each component.
pub fn normal_rgb(n: Vec3) -> Vec3 {
    n.abs()
}

#[cfg(test)]
mod packet_tests;
#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrator::Whitted;
    use crate::sampler::{GridLayout, Sampler, SamplerKind};
    use std::sync::atomic::AtomicU64;

    /// A lit triangle in front of an orthographic camera, tilted (its depth
    /// varies across a pixel).
    pub(super) fn small_world() -> (World, CameraModel) {
        let src = "OrthographicCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 size 4 }
             Lights { numLights 0 }
             Background { color 0 0 0 ambientLight 1 1 1 }
             Materials { numMaterials 1 PhongMaterial { diffuseColor 1 0.5 0.25 } }
             Group { numObjects 1 MaterialIndex 0
               Triangle { vertex0 -1 -1 0 vertex1 1 -1 0.5 vertex2 0 1 -0.5 } }";
        let scene = crate::format::parse_scene(src, std::path::Path::new("t.txt")).unwrap();
        let world = World::build(&scene, crate::world::BuildOptions::default());
        let camera = CameraModel::new(world.camera());
        (world, camera)
    }

    /// The band loop (one ray a pixel), the tile loop (4 jittered samples,
    /// a tent filter reaching across tiles) and adaptive subdivision, on a
    /// 37x21 image (partial tiles and bands).
    fn every_path(size: (u32, u32)) -> [Settings; 3] {
        let one = Settings::one_ray(size, PixelOffset::CENTER);
        let tiles = Settings {
            sampler: Sampler::new(SamplerKind::Jittered, 4, 0),
            filter: Filter::Tent(1.5),
            tile_size: 8,
            ..one
        };
        let adaptive = Settings {
            adaptive: Some(Adaptive {
                threshold: 0.1,
                max_depth: 2,
            }),
            tile_size: 8,
            ..one
        };
        [one, tiles, adaptive]
    }

    /// The band loop (with and without its one-ray shortcut, one and four
    /// samples a pixel) gives the tile loop's frame bit for bit: colour, depth, normal and sample count, on
    /// an image whose size is not a multiple of the bands or tiles, of a
    /// scene that is not symmetric (a flipped row or column would show).
    #[test]
    fn the_band_loop_equals_the_tile_loop() {
        let (world, camera) = small_world();
        let (w, h) = (37, 21);
        let whole = Rect {
            x0: 0,
            row0: 0,
            x1: w,
            row1: h,
        };
        // The lower-left corner is outside a tent of radius 1/2: weight 0.
        let corner = PixelOffset(Vec2::ZERO);
        for offset in [
            PixelOffset::CENTER,
            PixelOffset(Vec2::new(0.25, 0.125)),
            corner,
        ] {
            let one = Settings::one_ray((w, h), offset);
            // One ray through a tent of radius 1/2: the one-ray shortcut
            // only applies where the ray's weight is 1 (black where it is 0).
            let one_tent = Settings {
                filter: Filter::Tent(0.5),
                ..one
            };
            let kept = Settings {
                keep_samples: true,
                ..one
            };
            // Four jittered samples through a box of one pixel: still the
            // band loop (the filter reaches no neighbour).
            let four = Settings {
                sampler: Sampler::new(SamplerKind::Jittered, 4, 3),
                ..one
            };
            // A tent of radius 1/2 reaches no neighbour either (the band
            // loop), but its weights are not 1: the weighted mean's branch.
            let tent = Settings {
                filter: Filter::Tent(0.5),
                ..four
            };
            // Four samples on a grid: all as near the pixel centre, so the
            // depth and normal are the first sample's (the triangle is
            // tilted: each sample has its own depth).
            let grid = Settings {
                sampler: Sampler::new(SamplerKind::Uniform(GridLayout::CENTERS), 4, 0),
                ..one
            };
            // And every one of them with the per-pixel cost plane filled.
            let all = [one, one_tent, kept, four, tent, grid];
            let costed = all.map(|s| Settings {
                pixel_cost: true,
                ..s
            });
            for s in all.into_iter().chain(costed) {
                let it = &Whitted::default();
                let bands = render_image(&world, &camera, it, &s, Control::default());
                let tiles = render_region(&world, &camera, it, &s, Control::default(), whole);
                // The kept samples too (in pixel order: the loops differ).
                let sorted = |r: &Rendered| {
                    let mut v = r.samples.clone();
                    v.sort_by_key(|k| (k.pixel, k.offset.x.to_bits(), k.offset.y.to_bits()));
                    v
                };
                let n = if s.keep_samples { w * h } else { 0 };
                assert_eq!(bands.samples.len(), n as usize, "{s:?}");
                assert!(sorted(&bands) == sorted(&tiles), "{s:?}");
                let (bands, tiles) = (bands.frame, tiles.frame);
                assert!(bands.is_complete() && tiles.is_complete());
                let bits = |f: &Frame| {
                    let v = |c: &Vec3| c.to_array().map(f32::to_bits);
                    (
                        f.color.iter().map(v).collect::<Vec<_>>(),
                        f.depth.iter().map(|d| d.to_bits()).collect::<Vec<_>>(),
                        f.normal.iter().map(v).collect::<Vec<_>>(),
                        f.samples.clone(),
                        f.cost
                            .iter()
                            .map(|c| (c.tests, c.nodes))
                            .collect::<Vec<_>>(),
                    )
                };
                assert!(bits(&bands) == bits(&tiles), "{s:?}");
                if s.pixel_cost {
                    // The pixels' costs add up to the render's counters.
                    let r = render_image(&world, &camera, it, &s, Control::default());
                    let sum = |f: fn(&PixelCost) -> u64| r.frame.cost.iter().map(f).sum::<u64>();
                    assert_eq!(sum(|c| c.tests), r.counters.intersection_tests);
                    assert_eq!(sum(|c| c.nodes), r.counters.nodes_visited);
                    assert!(r.counters.intersection_tests > 0 && r.counters.nodes_visited > 0);
                }
                // Not trivially equal: lit and background pixels, hits and
                // misses (all black where the one ray's weight is 0).
                let black = s
                    .sampler
                    .fixed_offset()
                    .is_some_and(|o| s.filter.weight(o.x - 0.5, o.y - 0.5) == 0.0);
                assert_eq!(bands.color.iter().any(|c| c.x > 0.5), !black, "{s:?}");
                assert!(bands.color.contains(&Vec3::ZERO));
                assert!(bands.depth.iter().any(|d| d.is_finite()));
            }
        }
    }

    /// Progress reports add up to the number of pixels, on every path.
    #[test]
    fn progress_adds_up_to_every_pixel() {
        let (world, camera) = small_world();
        let size = (37, 21);
        for s in every_path(size) {
            let done = AtomicU64::new(0);
            let tick = |n: u64| {
                done.fetch_add(n, Ordering::Relaxed);
            };
            let control = Control {
                cancel: None,
                on_progress: Some(&tick),
            };
            let r = render_image(&world, &camera, &Whitted::default(), &s, control);
            assert!(r.frame.is_complete());
            assert_eq!(done.load(Ordering::Relaxed), 37 * 21, "{s:?}");
        }
    }

    /// A render cancelled before it starts traces no ray, leaves every row
    /// incomplete, reports no progress and returns a frame of misses
    /// (infinite depth); the same render not cancelled is complete and not
    /// black.
    #[test]
    fn a_cancelled_render_traces_nothing() {
        let (world, camera) = small_world();
        for s in every_path((37, 21)) {
            let stop = AtomicBool::new(true);
            let done = AtomicU64::new(0);
            let tick = |n: u64| {
                done.fetch_add(n, Ordering::Relaxed);
            };
            let control = Control {
                cancel: Some(&stop),
                on_progress: Some(&tick),
            };
            let r = render_image(&world, &camera, &Whitted::default(), &s, control);
            assert_eq!(r.counters.primary, 0, "{s:?}");
            assert!(r.frame.complete.iter().all(|&c| !c), "{s:?}");
            assert!(r.frame.depth.iter().all(|&t| t == f32::INFINITY), "{s:?}");
            assert_eq!(done.load(Ordering::Relaxed), 0);
            stop.store(false, Ordering::Relaxed);
            let r = render_image(&world, &camera, &Whitted::default(), &s, control);
            assert!(r.frame.is_complete() && r.counters.primary > 0);
            assert!(r.frame.color.iter().any(|&c| c.x > 0.5));
        }
    }

    #[test]
    fn depth_maps_near_to_white() {
        assert_eq!(depth_grey(9.0, 9.0, 10.0), 1.0);
        assert_eq!(depth_grey(10.0, 9.0, 10.0), 0.0);
        assert_eq!(depth_grey(9.5, 9.0, 10.0), 0.5);
        assert_eq!(depth_grey(5.0, 9.0, 10.0), 1.0);
        assert_eq!(depth_grey(f32::INFINITY, 9.0, 10.0), 0.0);
        // A range longer than 1 (a quotient, not a product).
        assert_eq!(depth_grey(9.5, 9.0, 11.0), 0.75);
        // An empty range: black, not NaN.
        assert_eq!(depth_grey(3.0, 5.0, 5.0), 0.0);
        assert_eq!(depth_grey(5.0, 5.0, 5.0), 0.0);
    }

    #[test]
    fn normals_show_as_their_absolute_values() {
        assert_eq!(
            normal_rgb(Vec3::new(-0.6, 0.8, -0.0)),
            Vec3::new(0.6, 0.8, 0.0)
        );
        assert_eq!(normal_rgb(Vec3::new(0.0, -1.0, 0.0)), Vec3::Y);
    }
}
