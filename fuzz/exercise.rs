//! What the fuzz targets do with one input, shared with `tests/fuzz_corpus.rs`
//! (which replays the committed corpora through exactly this code under
//! `cargo test`). Both functions must return normally for every input: a
//! panic is a crash.

use glint::format::gltf::parse_gltf;
use glint::format::ply::parse_ply;
use glint::format::{obj::load_obj_from_bytes, parse_scene};
use glint::integrator::{AoSettings, Integrator, NoObserver, Trace, Whitted};
use glint::job::{Job, Output};
use glint::limits;
use glint::math::{Vec2, Vec3};
use glint::render::{screen_point, CameraModel};
use glint::sampler::{Sampler, SamplerKind};
use glint::scene::{Background, Camera, Node, Scene, ShapeDesc};
use glint::stats::Counters;
use glint::world::{BuildOptions, World};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Scene text (lossily decoded) through the parser; a scene it accepts is
/// built into a world (flattened and not) and a few camera rays are traced
/// through the whole ray tree.
pub fn scene(data: &[u8]) {
    let src = String::from_utf8_lossy(data);
    let scene = match parse_scene(&src, Path::new("fuzz.txt")) {
        Ok(s) => s,
        Err(e) => {
            // Rendering the diagnostic walks the source line to the column.
            let _ = e.render();
            return;
        }
    };
    let _ = scene.summary();
    trace_a_few(&scene);
}

/// OBJ bytes through the mesh reader; a mesh it accepts must have in-range
/// indices and finite positions, and is built into a world and hit with rays.
pub fn obj(data: &[u8]) {
    let mesh = match load_obj_from_bytes(data, Path::new("fuzz.obj")) {
        Ok(m) => m,
        Err(e) => {
            let _ = e.render();
            return;
        }
    };
    let n = mesh.positions.len();
    assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < n));
    assert!(mesh.positions.iter().all(|p| p.is_finite()));
    let scene = Scene {
        camera: Camera::Perspective {
            center: Vec3::new(0.0, 0.0, 10.0).as_dvec3(),
            direction: Vec3::NEG_Z,
            up: Vec3::Y,
            angle_deg: 30.0,
        },
        lights: vec![],
        background: Background::default(),
        materials: vec![],
        root: Node::Group(vec![Node::Shape {
            shape: ShapeDesc::Mesh(Arc::new(mesh)),
            material: None,
        }]),
        effects: Default::default(),
    };
    trace_a_few(&scene);
}

/// PLY bytes through the PLY reader; a mesh it accepts must have in-range
/// indices and finite positions, and is built into a world and hit with
/// rays (smooth shaded when the file gave normals).
pub fn ply(data: &[u8]) {
    match parse_ply(data, Path::new("fuzz.ply")) {
        Ok(mesh) => check_and_trace(mesh),
        Err(e) => {
            let _ = e.render();
        }
    }
}

/// glTF or GLB bytes through the glTF reader (external buffers are refused
/// here: only `data:` URIs and the GLB chunk are read); a scene it accepts
/// is built and traced.
pub fn gltf(data: &[u8]) {
    match parse_gltf(
        data,
        Path::new("fuzz.gltf"),
        &mut |_| Err("no files".into()),
    ) {
        Ok(scene) => trace_a_few(&scene),
        Err(e) => {
            let _ = e.render();
        }
    }
}

fn check_and_trace(mesh: glint::scene::Mesh) {
    let n = mesh.positions.len();
    assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < n));
    assert!(mesh.positions.iter().all(|p| p.is_finite()));
    assert!(mesh.normals.is_empty() || mesh.normals.len() == n);
    let mut scene = Scene::for_mesh(mesh);
    scene.smooth_meshes();
    trace_a_few(&scene);
}

/// A command line (arguments separated by NUL bytes, read like the
/// `raytracer` flags) assembled into a [`Job`] with the validation helpers
/// both command lines call, then checked by [`Job::preflight`], which
/// touches no file (it only looks paths up). Whatever the arguments: no
/// panic, every message bounded, and a job that passes is within every limit.
pub fn job_args(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    let args: Vec<&str> = text.split('\0').collect();
    let mut job = Job::new(PathBuf::from("fuzz-scene.txt"), 8, 8);
    let mut it = args.iter().copied();
    let mut problem = None;
    while let Some(flag) = it.next() {
        let mut value = || it.next().unwrap_or("");
        let step: Result<(), String> = (|| {
            match flag {
                "-input" => job.input = value().into(),
                "-output" => job.set_output(Output::Colour(value().into())),
                "-normals" => job.set_output(Output::Normals(value().into())),
                "-stats_json" => job.set_output(Output::Stats(value().into())),
                "-size" => {
                    job.width = limits::parse_flag(flag, value())?;
                    job.height = limits::parse_flag(flag, value())?;
                }
                "-depth" => {
                    let t0 = limits::parse_finite(flag, value(), f32::MIN, f32::MAX)?;
                    let t1 = limits::parse_finite(flag, value(), f32::MIN, f32::MAX)?;
                    let path = value().into();
                    job.set_output(Output::Depth {
                        near: t0,
                        far: t1,
                        path,
                    });
                }
                "-weight" => {
                    job.shading.weight_cutoff = limits::parse_finite(flag, value(), 0.0, f32::MAX)?
                }
                "-bounces" => {
                    let n = limits::parse_flag(flag, value())?;
                    job.shading.bounces = limits::int_in(flag, n, 0, limits::MAX_BOUNCES)?;
                }
                "-threads" => {
                    let n = limits::parse_flag(flag, value())?;
                    job.threads = Some(limits::threads(flag, n, 2)?.0);
                }
                // Unchecked values, as a library caller could set them: the
                // job's own checks must catch them.
                "-raw_weight" => job.shading.weight_cutoff = value().parse().unwrap_or(f32::NAN),
                "-raw_threads" => job.threads = value().parse().ok(),
                "-raw_bounces" => job.shading.bounces = value().parse().unwrap_or(u32::MAX),
                _ => {}
            }
            Ok(())
        })();
        if let Err(e) = step {
            problem = Some(e);
            break;
        }
    }
    if let Some(msg) = problem {
        assert!(msg.len() < 400, "flag message of {} bytes", msg.len());
        return;
    }
    match job.preflight() {
        Ok(()) => {
            assert!(job.width >= 1 && job.height >= 1);
            assert!(job
                .threads
                .is_none_or(|n| (1..=limits::MAX_THREADS).contains(&n)));
            assert!(job.shading.bounces <= limits::MAX_BOUNCES);
            let w = job.shading.weight_cutoff;
            assert!(w.is_finite() && w >= 0.0);
            let outs = job.files();
            for (i, (_, a)) in outs.iter().enumerate() {
                assert!(
                    !glint::output::same_file(a, &job.input),
                    "{a:?} is the input"
                );
                for (_, b) in &outs[..i] {
                    assert!(!glint::output::same_file(a, b), "{a:?} and {b:?}");
                }
            }
        }
        Err(e) => {
            let msg = limits::bounded_message(&e.to_string());
            assert!(msg.len() < 64 * 1024, "message of {} bytes", msg.len());
            assert!(matches!(e.exit_code(), 1 | 2), "{e}");
        }
    }
}

/// Builds `scene` both ways and traces a 3x3 grid of camera rays with every
/// integrator feature on. A hit reached by a finite ray must have a `t` and a
/// normal that are not NaN.
fn trace_a_few(scene: &Scene) {
    let sampler = Sampler::new(SamplerKind::Sobol, 1, 0);
    for flatten in [true, false] {
        let world = World::build(
            scene,
            BuildOptions {
                flatten,
                ..BuildOptions::default()
            },
        );
        let camera = CameraModel::of_world(&world, &scene.effects);
        let _ = world.bounds();
        for transparent_shadows in [false, true] {
            let integrator = Whitted {
                bounces: 3,
                weight_cutoff: 0.01,
                shadows: true,
                shade_back: true,
                transparent_shadows,
                // Both lookup spaces, without doubling the work per input.
                texture_space: if transparent_shadows {
                    glint::material::TextureSpace::Object
                } else {
                    glint::material::TextureSpace::World
                },
                // Every sampled effect too (area lights and glossy lobes
                // come from the scene).
                shadow_samples: 2,
                glossy_samples: 2,
                ambient_occlusion: Some(AoSettings {
                    samples: 2,
                    distance: 1.0,
                }),
            };
            let mut c = Counters::default();
            for j in 0..3 {
                for i in 0..3 {
                    let mut stream = sampler.stream((i, j), 0);
                    stream.next_2d();
                    let ray =
                        camera.sample_ray(screen_point(i, j, Vec2::splat(0.5), 3, 3), &mut stream);
                    let cx = &mut Trace {
                        world: &world,
                        stream: &mut stream,
                        counters: &mut c,
                        observer: &mut NoObserver,
                        packets: world.walks_packets(),
                    };
                    let (_color, hit) = integrator.li(cx, &ray, camera.tmin());
                    if let Some(h) = hit.filter(|_| ray.origin.is_finite() && ray.dir.is_finite()) {
                        assert!(!h.t.is_nan(), "NaN t for {ray:?}");
                        assert!(!h.normal.is_nan(), "NaN normal for {ray:?}: {h:?}");
                    }
                }
            }
        }
    }
}
