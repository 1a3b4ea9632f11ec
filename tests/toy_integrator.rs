//! A new integrator plugs in through the `Integrator` interface alone: one
//! written here, outside the library ("normals as colours"), renders through
//! `render_image` on every path of the pixel loop (bands, tiles with a wide
//! filter, adaptive subdivision) and through the ray-tree view, with no
//! change to the render loop or the job.

use crate::common::own_scene;
use glint::integrator::{Integrator, RayKind, RayObserver, Trace};
use glint::math::{Ray, Vec3};
use glint::render::{render_image, Adaptive, CameraModel, Control, Filter, PixelOffset, Settings};
use glint::sampler::{Sampler, SamplerKind};
use glint::world::{BuildOptions, Hit, World};

/// The camera ray's hit normal mapped from `[-1, 1]` to `[0, 1]`; black for a
/// miss. One ray per sample, no shading, no random decisions.
struct NormalsAsColours;

impl NormalsAsColours {
    fn colour(normal: Vec3) -> Vec3 {
        normal * 0.5 + Vec3::splat(0.5)
    }
}

impl Integrator for NormalsAsColours {
    fn li_hit<O: RayObserver>(&self, _: &mut Trace<O>, _: &Ray, _: f32, hit: Option<&Hit>) -> Vec3 {
        hit.map_or(Vec3::ZERO, |h| Self::colour(h.normal))
    }
}

/// glint's Whitted showcase (spheres over a floor that fills the view), or
/// with `sky`, a sphere and a triangle in front of nothing.
fn world(sky: bool) -> (World, CameraModel) {
    let scene = if sky {
        let src = "PerspectiveCamera { center 0 0 10 direction 0 0 -1 up 0 1 0 angle 30 }
             Lights { numLights 0 }
             Background { color 0 0 0 ambientLight 1 1 1 }
             Materials { numMaterials 1 PhongMaterial { diffuseColor 1 1 1 } }
             Group { numObjects 2 MaterialIndex 0
               Sphere { center -1 0 0 radius 1.5 }
               Triangle { vertex0 0.5 -2 -1 vertex1 2.5 -1 0 vertex2 1 2 1 } }";
        glint::format::parse_scene(src, std::path::Path::new("toy.txt")).unwrap()
    } else {
        glint::format::load_scene(&own_scene("whitted.txt")).unwrap()
    };
    let world = World::build(&scene, BuildOptions::default());
    let camera = CameraModel::new(world.camera());
    (world, camera)
}

/// One ray a pixel (the band loop): every pixel is its camera ray's normal
/// as a colour (the frame's normal plane is that hit's normal), black where
/// the ray escaped; one eye ray a pixel and nothing else traced.
#[test]
fn a_toy_integrator_renders_through_the_loop() {
    let (world, camera) = world(true);
    let (w, h) = (67, 45);
    let s = Settings::one_ray((w, h), PixelOffset::CENTER);
    let r = render_image(&world, &camera, &NormalsAsColours, &s, Control::default());
    assert!(r.frame.is_complete());
    assert_eq!(r.counters.primary, u64::from(w * h));
    assert_eq!(r.counters.shadow + r.counters.reflected, 0);
    let (mut hits, mut misses) = (0, 0);
    for k in 0..(w * h) as usize {
        let (c, d, n) = (r.frame.color[k], r.frame.depth[k], r.frame.normal[k]);
        if d.is_finite() {
            hits += 1;
            assert!((n.length() - 1.0).abs() < 1e-4, "pixel {k}: normal {n}");
            assert_eq!(c, NormalsAsColours::colour(n), "pixel {k}");
        } else {
            misses += 1;
            assert_eq!(c, Vec3::ZERO, "pixel {k}");
        }
    }
    // The sphere, the triangle and the sky: hits and misses, normals of many directions.
    assert!(hits > 0 && misses > 0, "{hits} hits, {misses} misses");
    let spread = r
        .frame
        .color
        .iter()
        .fold((Vec3::splat(1.0), Vec3::ZERO), |(lo, hi), &c| {
            (lo.min(c), hi.max(c))
        });
    assert!((spread.1 - spread.0).min_element() > 0.3, "{spread:?}");
}

/// The same integrator through the tiled path (16 jittered samples, a tent
/// filter reaching over tile edges) and adaptive subdivision: 16 camera rays
/// a pixel, and colours that are weighted means of normal colours, so inside
/// `[0, 1]`; adaptive subdivision splits where normals change (more than its
/// 4 corner points in some pixels) and not on the flat floor's far part.
#[test]
fn a_toy_integrator_renders_on_every_path() {
    let (world, camera) = world(false);
    let (w, h) = (67, 45);
    let one = Settings::one_ray((w, h), PixelOffset::CENTER);
    let tiles = Settings {
        sampler: Sampler::new(SamplerKind::Jittered, 16, 1),
        filter: Filter::Tent(1.5),
        ..one
    };
    let adaptive = Settings {
        adaptive: Some(Adaptive {
            threshold: 0.05,
            max_depth: 2,
        }),
        ..one
    };
    let r = render_image(
        &world,
        &camera,
        &NormalsAsColours,
        &tiles,
        Control::default(),
    );
    assert!(r.frame.is_complete());
    assert_eq!(r.counters.primary, u64::from(w * h * 16));
    assert!(r.frame.samples.iter().all(|&n| n == 16));
    let inside = |c: &Vec3| c.min_element() >= 0.0 && c.max_element() <= 1.0 + 1e-6;
    assert!(r.frame.color.iter().all(inside));
    let r = render_image(
        &world,
        &camera,
        &NormalsAsColours,
        &adaptive,
        Control::default(),
    );
    assert!(r.frame.is_complete());
    assert!(r.frame.color.iter().all(inside));
    assert!(r.frame.samples.iter().any(|&n| n > 4));
    assert!(r.frame.samples.contains(&4));
    assert!(r.counters.primary >= u64::from((w + 1) * (h + 1)));
}

/// The ray-tree view records what the toy integrator traced for a pixel: its
/// one eye ray, ending at the hit, and the pixel's colour.
#[test]
fn the_ray_tree_view_takes_a_toy_integrator() {
    let (world, camera) = world(false);
    let size = (67, 45);
    let tree = glint::viz::raytree::record(
        &world,
        &camera,
        &NormalsAsColours,
        size,
        (33, 22),
        PixelOffset::CENTER,
    );
    assert_eq!(tree.rays.len(), 1);
    let eye = tree.rays[0];
    assert_eq!(eye.kind, RayKind::Primary);
    let n = eye.normal.expect("the centre pixel's ray hits a sphere");
    assert!(eye.t_end.is_finite());
    assert_eq!(tree.color, NormalsAsColours::colour(n));
}
