//! Camera packets: `World::intersect_packet` gives each camera ray the hit
//! `World::intersect` gives it alone, bit for bit, on every accelerator and
//! kind of primitive; and renders that trace camera rays in packets are the
//! renders that trace them one by one (the cost plane's renders, which
//! trace each pixel's rays alone), on every path of the pixel loop, for
//! every integrator, on 1 and 2 threads.

use super::pixel::PACKET_PIXEL_SPAN;
use super::*;
use crate::accel::{AccelKind, PacketRay, Split, PACKET};
use crate::integrator::{AmbientOcclusion, PathSettings, PathTracer, Whitted};
use crate::sampler::{Sampler, SamplerKind};
use crate::scene::Scene;
use crate::world::{BuildOptions, Hit};

/// One of glint's own scenes.
fn own(name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name);
    crate::format::load_scene(&path).unwrap()
}

fn world_of(scene: &Scene, accel: AccelKind, flatten: bool) -> (World, CameraModel) {
    let world = World::build(scene, BuildOptions { accel, flatten });
    let camera = CameraModel::of_world(&world, &scene.effects);
    (world, camera)
}

/// A hit's every field as bits (`None`: empty).
fn bits(h: &Option<Hit>) -> Vec<u32> {
    h.iter()
        .flat_map(|h| {
            let v = |v: Vec3| v.to_array().map(f32::to_bits);
            [h.t.to_bits()]
                .into_iter()
                .chain(v(h.point))
                .chain(v(h.error))
                .chain(v(h.normal))
                .chain(v(h.shading_normal))
                .chain([h.prim, h.material, h.instance])
        })
        .collect()
}

/// The scenes of the tests: a 1k-triangle mesh on a plane (smooth
/// normals), spheres and planes with a sky, moving shapes under a
/// shutter (each camera ray at its own time), a thin lens.
/// The accelerators the packet tests compare: bvh8 walks packets, the
/// others answer ray by ray.
const ACCELS: [AccelKind; 4] = [
    AccelKind::Bvh8,
    AccelKind::Bvh(Split::Sah),
    AccelKind::Grid { res: None },
    AccelKind::None,
];

const SCENES: [&str; 4] = [
    "mesh_knot_1k.txt",
    "whitted.txt",
    "motion_spinning.txt",
    "dof_row.txt",
];

/// The camera rays of every 12th row of a 317×240 image (rows of 40
/// packets, the last of five rays) at two samples, in packets of a row's
/// neighbours at one sample index, against each ray alone: the same hit,
/// bit for bit, on every accelerator, with and without flattening
/// (transformed shapes as wrappers), through the packet walk on bvh8
/// (fewer nodes than the rays alone) and ray by ray elsewhere.
#[test]
fn packet_hits_are_single_ray_hits() {
    let (w, h) = (317u32, 240u32);
    let sampler = Sampler::new(SamplerKind::Sobol, 2, 5);
    let (mut hits, mut misses) = (0, 0);
    for name in SCENES {
        let scene = own(name);
        for accel in ACCELS {
            for flatten in [true, false] {
                let (world, camera) = world_of(&scene, accel, flatten);
                assert_eq!(world.walks_packets(), accel == AccelKind::Bvh8);
                let (mut alone, mut packed) = (Counters::default(), Counters::default());
                for j in (0..h).step_by(12) {
                    for x0 in (0..w).step_by(PACKET) {
                        for k in 0..sampler.spp() {
                            let rays: Vec<PacketRay> = (x0..(x0 + PACKET as u32).min(w))
                                .map(|i| {
                                    let mut s = sampler.stream((i, j), k);
                                    let o = s.next_2d();
                                    let ray =
                                        camera.sample_ray(screen_point(i, j, o, w, h), &mut s);
                                    let tmin = camera.tmin();
                                    let tmax = f32::INFINITY;
                                    PacketRay { ray, tmin, tmax }
                                })
                                .collect();
                            let mut out = [None; PACKET];
                            world.intersect_packet(&rays, &mut out, &mut packed);
                            for (q, got) in rays.iter().zip(&out) {
                                let want = world.intersect(&q.ray, q.tmin, q.tmax, &mut alone);
                                assert!(
                                    bits(got) == bits(&want),
                                    "{name} {accel} flatten {flatten}: {q:?}: {got:?} != {want:?}"
                                );
                                if want.is_some() {
                                    hits += 1;
                                } else {
                                    misses += 1;
                                }
                            }
                        }
                    }
                }
                if accel == AccelKind::Bvh8 {
                    assert!(
                        packed.nodes_visited < alone.nodes_visited,
                        "{name} flatten {flatten}: {packed:?} vs {alone:?}"
                    );
                } else {
                    assert_eq!(packed, alone, "{name} {accel}");
                }
            }
        }
    }
    assert!(hits > 0 && misses > 0, "{hits} hits, {misses} misses");
}

/// The loop takes packets on bvh8 where a pixel spans at most
/// `PACKET_PIXEL_SPAN`: the knot's 40° camera at 403 pixels and above,
/// not at 320; on other accelerators never.
#[test]
fn packets_are_taken_for_narrow_pixels_on_bvh8() {
    let scene = own("mesh_knot_1k.txt");
    let whitted = &Whitted::default();
    for accel in [AccelKind::Bvh8, AccelKind::Bvh(Split::Sah)] {
        let (world, camera) = world_of(&scene, accel, true);
        let step = |size| Step {
            world: &world,
            camera: &camera,
            integrator: whitted,
            size,
        };
        let bvh8 = accel == AccelKind::Bvh8;
        assert_eq!(step((403, 14)).packets(), bvh8);
        assert_eq!(step((640, 480)).packets(), bvh8);
        assert!(!step((320, 240)).packets());
        assert_eq!(step((14, 403)).packets(), bvh8);
    }
}

/// An orthographic camera's rays start at `t = −∞`: the render loop takes
/// no packets for them (the packet walk would take them one by one).
#[test]
fn orthographic_cameras_take_no_packets() {
    let (world, camera) = tests::small_world();
    assert!(world.walks_packets() && camera.tmin() < 0.0);
    assert!(camera.pixel_span((4000, 4000)) <= PACKET_PIXEL_SPAN);
    let step = Step {
        world: &world,
        camera: &camera,
        integrator: &Whitted::default(),
        // Pixels narrow enough for packets (the orthographic screen is 4
        // wide): only the camera's `tmin` refuses them.
        size: (4000, 4000),
    };
    assert!(!step.packets());
}

/// The pixel loop's paths with packets: one ray a pixel (bands of 4 rows
/// in blocks of 8, the last partial), 4 jittered samples through a box
/// (bands, the accumulator), 2 Sobol samples through a tent reaching over
/// tile edges with the samples kept (tiles whose splats must come in the
/// per-pixel order), and a piece of the frame (`render_region`). The image
/// is a wide strip (403×14): eight pixels of a row are a narrow enough fan
/// of rays for the packet walk only in images some hundreds of pixels
/// wide (`PACKET_PIXEL_SPAN`, and `bvh8::packet`'s spread limit).
fn settings(size: (u32, u32)) -> Vec<(Settings, Option<Rect>)> {
    let one = Settings::one_ray(size, PixelOffset::CENTER);
    let four = Settings {
        sampler: Sampler::new(SamplerKind::Jittered, 4, 3),
        ..one
    };
    let tent = Settings {
        sampler: Sampler::new(SamplerKind::Sobol, 2, 1),
        filter: Filter::Tent(1.5),
        tile_size: 16,
        keep_samples: true,
        ..one
    };
    let piece = Rect {
        x0: 5,
        row0: 3,
        x1: 250,
        row1: 11,
    };
    vec![(one, None), (four, None), (tent, None), (tent, Some(piece))]
}

/// Colour, depth, normal and sample-count planes as bits.
fn planes(f: &Frame) -> Vec<u32> {
    let v = |c: &Vec3| c.to_array().map(f32::to_bits);
    (f.color.iter().flat_map(v))
        .chain(f.normal.iter().flat_map(v))
        .chain(f.depth.iter().map(|d| d.to_bits()))
        .chain(f.samples.iter().copied())
        .collect()
}

/// `integrator` on `world` with `s` (and `region`), on `threads` threads.
fn render_with<I: Integrator>(
    world: &World,
    camera: &CameraModel,
    integrator: &I,
    (s, region): (&Settings, Option<Rect>),
    threads: usize,
) -> Rendered {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| match region {
        None => render_image(world, camera, integrator, s, Control::default()),
        Some(r) => render_region(world, camera, integrator, s, Control::default(), r),
    })
}

/// Renders with packets (bvh8, no cost plane) against the same renders
/// with each camera ray alone (the cost plane's): the same planes and
/// kept samples bit for bit, the same rays of every kind, fewer nodes
/// visited; and the same again on two threads, counters too.
fn packets_render_as_single_rays<I: Integrator>(name: &str, integrator: impl Fn(&World) -> I) {
    let scene = own(name);
    let (world, camera) = world_of(&scene, AccelKind::Bvh8, true);
    let integrator = &integrator(&world);
    for (s, region) in settings((403, 14)) {
        let packed = render_with(&world, &camera, integrator, (&s, region), 1);
        let costed = Settings {
            pixel_cost: true,
            ..s
        };
        let alone = render_with(&world, &camera, integrator, (&costed, region), 1);
        let what = format!("{name} {s:?} {region:?}");
        assert!(planes(&packed.frame) == planes(&alone.frame), "{what}");
        assert!(packed.samples == alone.samples, "{what}");
        let rays = |c: &Counters| Counters {
            intersection_tests: 0,
            nodes_visited: 0,
            ..*c
        };
        assert_eq!(rays(&packed.counters), rays(&alone.counters), "{what}");
        assert!(
            packed.counters.nodes_visited < alone.counters.nodes_visited,
            "{what}: {:?} vs {:?}",
            packed.counters,
            alone.counters
        );
        let two = render_with(&world, &camera, integrator, (&s, region), 2);
        assert!(planes(&two.frame) == planes(&packed.frame), "{what}");
        assert_eq!(two.counters, packed.counters, "{what}");
        // Not trivially equal: hits and colours.
        assert!(packed.frame.depth.iter().any(|d| d.is_finite()), "{what}");
        assert!(packed.frame.color.iter().any(|c| *c != Vec3::ZERO));
    }
}

#[test]
fn whitted_packet_renders_are_single_ray_renders() {
    let whitted = Whitted {
        bounces: 3,
        weight_cutoff: 0.01,
        shadows: true,
        shade_back: true,
        ..Whitted::default()
    };
    for name in SCENES {
        packets_render_as_single_rays(name, |_| whitted);
    }
}

#[test]
fn ao_and_path_packet_renders_are_single_ray_renders() {
    for name in ["mesh_knot_1k.txt", "dof_row.txt"] {
        packets_render_as_single_rays(name, |_| AmbientOcclusion::default());
    }
    let settings = PathSettings {
        max_bounces: 4,
        ..PathSettings::default()
    };
    for name in ["mesh_knot_1k.txt", "motion_spinning.txt"] {
        packets_render_as_single_rays(name, |w| PathTracer::new(w, settings));
    }
}

/// Shadow packets: each hit of a scene with area lights sends 8 (and 12:
/// a full packet and a part) shadow rays to one light; every ray's
/// `World::occluded_packet` answer is its `occluded_leaving` answer alone,
/// on every accelerator, with and without flattening; the statistics are
/// the single rays' ray by ray elsewhere, and fewer nodes on bvh8 where
/// its packet walk takes them.
#[test]
fn shadow_packet_answers_are_single_ray_answers() {
    use crate::light::{is_delta, prepare_area};
    use crate::math::{Spawn, SHADOW_EPSILON};
    let (w, h) = (96u32, 72u32);
    let sampler = Sampler::new(SamplerKind::Sobol, 1, 7);
    let (mut blocked, mut clear) = (0, 0);
    for name in SHADOW_SCENES {
        let scene = own(name);
        for accel in ACCELS {
            for flatten in [true, false] {
                let (world, camera) = world_of(&scene, accel, flatten);
                let (mut alone, mut packed) = (Counters::default(), Counters::default());
                for j in (0..h).step_by(3) {
                    for i in (0..w).step_by(3) {
                        let mut s = sampler.stream((i, j), 0);
                        let o = s.next_2d();
                        let ray = camera.sample_ray(screen_point(i, j, o, w, h), &mut s);
                        let mut c = Counters::default();
                        let Some(hit) = world.intersect(&ray, camera.tmin(), f32::INFINITY, &mut c)
                        else {
                            continue;
                        };
                        let from = &mut Spawn::leaving(hit.surface_point(), hit.prim);
                        for light in world.lights().iter().filter(|l| !is_delta(l)) {
                            let Some(prepared) = prepare_area(light, from.from.p) else {
                                continue;
                            };
                            for k in [8, 12] {
                                let rays: Vec<PacketRay> = (s.split_2d(k))
                                    .filter_map(|u| prepared.sample(u).at)
                                    .map(|at| PacketRay {
                                        ray: from.spawn_ray_to_surface(&at).at_time(ray.time),
                                        tmin: 0.0,
                                        tmax: 1.0 - SHADOW_EPSILON,
                                    })
                                    .collect();
                                for rays in rays.chunks(PACKET) {
                                    let got =
                                        world.occluded_packet(rays, from.leaving, &mut packed);
                                    for (r, q) in rays.iter().enumerate() {
                                        let want = world.occluded_leaving(
                                            &q.ray,
                                            q.tmin,
                                            q.tmax,
                                            from.leaving,
                                            &mut alone,
                                        );
                                        assert_eq!(
                                            got >> r & 1 != 0,
                                            want,
                                            "{name} {accel} flatten {flatten}: {q:?}"
                                        );
                                        if want {
                                            blocked += 1;
                                        } else {
                                            clear += 1;
                                        }
                                    }
                                    assert_eq!(got >> rays.len(), 0, "{name} {accel}");
                                }
                            }
                        }
                    }
                }
                if accel == AccelKind::Bvh8 {
                    assert!(
                        packed.nodes_visited < alone.nodes_visited,
                        "{name} flatten {flatten}: {packed:?} vs {alone:?}"
                    );
                } else {
                    assert_eq!(packed, alone, "{name} {accel}");
                }
            }
        }
    }
    assert!(blocked > 0 && clear > 0, "{blocked} blocked, {clear} clear");
}

/// Scenes with area lights for the shadow packets: spheres on planes
/// (the plane a ray leaves skipped), moving shapes (each ray at its own
/// time), the 16k-triangle knot on a floor of two triangles (the triangle
/// a ray leaves skipped) under two sphere lights, and a thin lens.
const SHADOW_SCENES: [&str; 4] = [
    "area_soft_shadows.txt",
    "motion_spinning.txt",
    "sphere_lights_knot.txt",
    "dof_row.txt",
];

/// `scene` with its sphere lights six times as far and a fifth as large:
/// from every point their rays are narrow enough for packets
/// (`Prepared::narrow`), which the scenes' own near lights seldom are.
fn far_lights(mut scene: Scene) -> Scene {
    use crate::scene::{AreaShape, Light};
    for l in &mut scene.lights {
        if let Light::Area {
            shape: AreaShape::Sphere { center, radius },
            ..
        } = l
        {
            *center *= 6.0;
            *radius *= 0.2;
        }
    }
    scene
}

/// An integrator that traces every ray alone (`Trace::packets` off):
/// what the render loop's integrators do without shadow packets.
struct Alone<I>(I);

impl<I: Integrator> Integrator for Alone<I> {
    fn li<O: crate::integrator::RayObserver>(
        &self,
        cx: &mut crate::integrator::Trace<O>,
        ray: &crate::math::Ray,
        tmin: f32,
    ) -> (Vec3, Option<Hit>) {
        cx.packets = false;
        self.0.li(cx, ray, tmin)
    }

    fn li_hit<O: crate::integrator::RayObserver>(
        &self,
        cx: &mut crate::integrator::Trace<O>,
        ray: &crate::math::Ray,
        tmin: f32,
        hit: Option<&Hit>,
    ) -> Vec3 {
        cx.packets = false;
        self.0.li_hit(cx, ray, tmin, hit)
    }
}

/// Whitted renders with 8 and 12 shadow rays per area light, their
/// shadow rays in packets (bvh8) against the same renders with each
/// shadow ray alone: the same planes and kept samples bit for bit, the
/// same rays of every kind, no more nodes visited (fewer in some); on 1
/// and 2 threads
/// (counters too); with transparent shadows (which take no packets) the
/// same counters exactly.
#[test]
fn shadow_packet_renders_are_single_ray_renders() {
    let mut fewer = false;
    for (name, far) in SHADOW_SCENES
        .iter()
        .map(|n| (*n, false))
        .chain([("sphere_lights_knot.txt", true)])
    {
        let scene = if far {
            far_lights(own(name))
        } else {
            own(name)
        };
        let (world, camera) = world_of(&scene, AccelKind::Bvh8, true);
        for (shadow_samples, transparent_shadows) in [(8, false), (12, false), (8, true)] {
            let whitted = Whitted {
                bounces: 2,
                weight_cutoff: 0.01,
                shadows: true,
                shade_back: true,
                transparent_shadows,
                shadow_samples,
                ..Whitted::default()
            };
            for (s, region) in settings((64, 24)).into_iter().take(3) {
                let packed = render_with(&world, &camera, &whitted, (&s, region), 1);
                let alone = render_with(&world, &camera, &Alone(whitted), (&s, region), 1);
                let what = format!("{name} {far} {shadow_samples} {transparent_shadows} {s:?}");
                assert!(planes(&packed.frame) == planes(&alone.frame), "{what}");
                assert!(packed.samples == alone.samples, "{what}");
                let rays = |c: &Counters| Counters {
                    intersection_tests: 0,
                    nodes_visited: 0,
                    ..*c
                };
                assert_eq!(rays(&packed.counters), rays(&alone.counters), "{what}");
                assert!(packed.counters.shadow > 0, "{what}");
                if transparent_shadows {
                    assert_eq!(packed.counters, alone.counters, "{what}");
                } else {
                    // A packet counts each node once for its rays: at most
                    // their own walks' (as many where every packet spreads
                    // too far for the packet walk: the spheres' lights).
                    assert!(
                        packed.counters.nodes_visited <= alone.counters.nodes_visited,
                        "{what}: {:?} vs {:?}",
                        packed.counters,
                        alone.counters
                    );
                    fewer |= packed.counters.nodes_visited < alone.counters.nodes_visited;
                }
                let two = render_with(&world, &camera, &whitted, (&s, region), 2);
                assert!(planes(&two.frame) == planes(&packed.frame), "{what}");
                assert_eq!(two.counters, packed.counters, "{what}");
                assert!(packed.frame.color.iter().any(|c| *c != Vec3::ZERO));
            }
        }
    }
    assert!(fewer, "no render took a shadow packet's walk");
}

/// A ray tree's observer sees the same rays, in the same order, whether
/// the shadow rays go in packets or alone (`Trace::blocked_packet` tells
/// it ray after ray).
#[test]
fn shadow_packets_show_the_observer_every_ray_in_order() {
    use crate::integrator::{Branch, RayRecorder, Trace};
    let scene = far_lights(own("sphere_lights_knot.txt"));
    let (world, camera) = world_of(&scene, AccelKind::Bvh8, true);
    let whitted = Whitted {
        shadows: true,
        shadow_samples: 12,
        ..Whitted::default()
    };
    let sampler = Sampler::new(SamplerKind::Sobol, 1, 3);
    let (w, h) = (40u32, 30u32);
    let (mut shadow_rays, mut fewer) = (0, false);
    for j in 0..h {
        for i in 0..w {
            let trace = |packets: bool| {
                let mut stream = sampler.stream((i, j), 0);
                let o = stream.next_2d();
                let ray = camera.sample_ray(screen_point(i, j, o, w, h), &mut stream);
                let mut rec = RayRecorder::default();
                let mut counters = Counters::default();
                let cx = &mut Trace {
                    world: &world,
                    stream: &mut stream,
                    counters: &mut counters,
                    observer: &mut rec,
                    packets,
                };
                let (c, _) = whitted.trace_sampled(cx, &ray, camera.tmin(), Branch::CAMERA);
                // (Debug text: a blocked shadow ray's `t_end` is NaN.)
                let rays = format!("{:?}", rec.rays);
                let nodes = counters.nodes_visited;
                (
                    (c.to_array().map(f32::to_bits), rays, rec.rays.len()),
                    nodes,
                )
            };
            let ((packed, n_packed), (alone, n_alone)) = (trace(true), trace(false));
            assert_eq!(packed, alone, "pixel ({i}, {j})");
            assert!(n_packed <= n_alone, "pixel ({i}, {j})");
            fewer |= n_packed < n_alone;
            shadow_rays += alone.2.saturating_sub(1);
        }
    }
    assert!(
        shadow_rays > 0 && fewer,
        "{shadow_rays} shadow rays, packets {fewer}"
    );
}
