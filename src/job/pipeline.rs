//! The stages of a job after its preflight: load the scene, build the
//! world, choose the integrator and render, write the piece or the images,
//! report.

use super::report::Report;
use super::{partial_path, Job, JobError};
use crate::accel::AccelKind;
use crate::format::load_scene_files;
use crate::integrator::caustic_map::CausticSettings;
use crate::integrator::{
    AmbientOcclusion, AoSettings, Integrator, IntegratorKind, PathSettings, PathTracer, Whitted,
};
use crate::render::{render_image, render_region, CameraModel, Control, Rect, Rendered, Settings};
use crate::scene::{EffectSamples, Scene};
use crate::viz::draw::Canvas;
use crate::viz::grid::{legend, voxelize, GridView, Voxels};
use crate::world::World;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// The scene as the job renders it.
struct Loaded {
    scene: Scene,
    /// With `-visualize_grid_count`, the grid whose legend goes on the image.
    voxels: Option<Voxels>,
    load_ms: f64,
}

/// What the render stage made.
struct Traced {
    rendered: Rendered,
    settings: Settings,
    time: Duration,
}

/// One render's fixed inputs; [`Stage::render`] runs it with any integrator.
struct Stage<'a> {
    world: &'a World,
    camera: &'a CameraModel,
    settings: &'a Settings,
    control: Control<'a>,
    /// The piece of the frame to render, or all of it.
    region: Option<Rect>,
}

impl Stage<'_> {
    /// The generic render entry: the whole frame or the piece.
    fn render<I: Integrator>(&self, integrator: &I) -> Rendered {
        let (world, camera, settings) = (self.world, self.camera, self.settings);
        match self.region {
            Some(r) => render_region(world, camera, integrator, settings, self.control, r),
            None => render_image(world, camera, integrator, settings, self.control),
        }
    }
}

impl Job {
    /// Loads, renders and writes every requested image.
    pub fn run(&self) -> Result<Report, JobError> {
        self.run_with(Control::default())
    }

    /// [`Job::run`] under `control`: its cancel flag stops the render early
    /// (what was rendered is saved as `NAME.partial.EXT` and the job fails
    /// with [`JobError::Interrupted`]); its progress callback hears of every
    /// finished piece of work.
    pub fn run_with(&self, control: Control) -> Result<Report, JobError> {
        self.preflight()?;
        let loaded = self.load()?;
        let t_world = Instant::now();
        let world = World::build(&loaded.scene, self.build);
        let world_ms = t_world.elapsed().as_secs_f64() * 1e3;
        let mut traced = self.trace(&loaded.scene, &world, control)?;
        if let Some(v) = &loaded.voxels {
            let frame = &mut traced.rendered.frame;
            let mut canvas =
                Canvas::new(frame.width, frame.height, std::mem::take(&mut frame.color));
            legend(&mut canvas, v.max_count());
            frame.color = canvas.pixels;
        }
        let frame = &traced.rendered.frame;
        let complete = match &self.piece {
            Some(p) => (p.rect.row0..p.rect.row1).all(|r| frame.complete[r as usize]),
            None => frame.is_complete(),
        };
        let mut written = self.write_piece(&loaded.scene, &traced, complete)?;
        written.extend(self.write_images(&traced.rendered, &traced.settings, complete)?);
        if !complete {
            return Err(JobError::Interrupted(written));
        }
        let report = Report {
            counters: traced.rendered.counters,
            accel: world.accel().describe(),
            build_ms: world.build_ms(),
            load_ms: loaded.load_ms,
            world_ms,
            render: traced.time,
            primitives: world.prims().len(),
            bounds: world_space(world.bounds(), world.origin()),
            frame: traced.rendered.frame,
            settings: traced.settings,
            scene: loaded.scene,
        };
        self.write_stats(&report)?;
        Ok(report)
    }

    /// Reads the scene (checking its meshes against the outputs), replaces
    /// it with its grid's cells for `-visualize_grid`, and moves its shutter
    /// to the animation frame.
    fn load(&self) -> Result<Loaded, JobError> {
        let t_load = Instant::now();
        let (mut scene, files) = load_scene_files(&self.input)?;
        if self.shading.smooth {
            scene.smooth_meshes();
        }
        // The meshes are known now; nothing has been written yet.
        self.check_clashes(&files)?;
        let load_ms = t_load.elapsed().as_secs_f64() * 1e3;
        let mut voxels = None;
        if let Some(view) = self.visualize_grid {
            let res = match self.build.accel {
                AccelKind::Grid { res } => res,
                _ => None,
            };
            // World space: the cells become geometry of a new scene in
            // the scene's own coordinates.
            let v = voxelize(&World::build_world_space(&scene, self.build), res);
            scene = v.scene(&scene, view);
            voxels = (view == GridView::Count).then_some(v);
        }
        if let Some(f) = self.frame {
            // Before the piece hash: pieces of different frames never merge.
            scene.effects.lens.shutter = f.shutter(scene.effects.lens.shutter);
        }
        Ok(Loaded {
            scene,
            voxels,
            load_ms,
        })
    }

    /// Renders `world` with the job's integrator on its own thread pool:
    /// the one dispatch from [`IntegratorKind`] to an integrator.
    fn trace(&self, scene: &Scene, world: &World, control: Control) -> Result<Traced, JobError> {
        let camera = CameraModel::of_world(world, &scene.effects);
        let samples = self.sampling.effects.apply(scene.effects.samples);
        let settings = self.effect_settings(scene, samples);
        let pool = self.pool()?;
        let stage = Stage {
            world,
            camera: &camera,
            settings: &settings,
            control,
            region: self.piece.as_ref().map(|p| p.rect),
        };
        let start = Instant::now();
        let rendered = pool.install(|| match self.integrator {
            IntegratorKind::Whitted => stage.render(&self.whitted(scene, samples)),
            IntegratorKind::Ao => stage.render(&ambient_occlusion(scene, samples)),
            IntegratorKind::Path(p) => {
                let tracer = PathTracer::new(
                    world,
                    PathSettings {
                        texture_space: self.shading.texture_space,
                        caustic_map: CausticSettings {
                            shutter: scene.effects.lens.shutter,
                            ..p.caustic_map
                        },
                        ..p
                    },
                );
                let mut rendered = stage.render(&tracer);
                if let Some(map) = tracer.caustic_map() {
                    rendered.counters += map.counters;
                }
                rendered
            }
        });
        Ok(Traced {
            rendered,
            settings,
            time: start.elapsed(),
        })
    }

    /// The ray tree with the scene's (or the command line's) effect samples.
    fn whitted(&self, scene: &Scene, samples: EffectSamples) -> Whitted {
        let mut w = self.shading.whitted();
        w.shadow_samples = samples.shadow;
        w.glossy_samples = samples.glossy;
        w.ambient_occlusion = scene.effects.ambient_occlusion.map(|a| AoSettings {
            samples: samples.ao,
            distance: a.distance,
        });
        w
    }

    fn pool(&self) -> Result<rayon::ThreadPool, JobError> {
        rayon::ThreadPoolBuilder::new()
            .num_threads(self.pool_threads())
            .build()
            .map_err(|e| {
                let n = self
                    .threads
                    .map_or_else(|| "one per core".to_owned(), |n| n.to_string());
                JobError::Internal(format!(
                    "could not start the worker threads ({n}): {e}; try fewer with --threads/-threads"
                ))
            })
    }

    /// Writes the piece of a frame (`--tile`, `--crop`) as an EXR with its
    /// data window, settings hash and statistics.
    fn write_piece(
        &self,
        scene: &Scene,
        traced: &Traced,
        complete: bool,
    ) -> Result<Vec<PathBuf>, JobError> {
        let (Some(out), Some(p)) = (self.colour(), &self.piece) else {
            return Ok(Vec::new());
        };
        let out = if complete {
            out.to_path_buf()
        } else {
            partial_path(out)
        };
        let counters = &traced.rendered.counters;
        let stats = serde_json::json!({
            "rays_primary": counters.primary,
            "rays_shadow": counters.shadow,
            "rays_reflected": counters.reflected,
            "rays_refracted": counters.refracted,
            "intersection_tests": counters.intersection_tests,
            "nodes_visited": counters.nodes_visited,
            "render_ms": traced.time.as_secs_f64() * 1e3,
        });
        let hash = self.piece_hash(scene, &traced.settings);
        crate::piece::write(&out, &traced.rendered.frame, p, &hash, &stats)?;
        Ok(vec![out])
    }

    /// The hash of everything that decides the image (not the accelerator,
    /// the thread count or the outputs, which do not).
    fn piece_hash(&self, scene: &Scene, settings: &Settings) -> String {
        let whitted = self.shading.whitted();
        let mut parts = format!(
            "{settings:?}|{whitted:?}|flatten {}|texture {:?}",
            self.build.flatten, whitted.texture_space
        );
        match self.integrator {
            IntegratorKind::Whitted => {}
            // The path settings as the command line gives them (texture
            // space at its default: the shading's is in the string already).
            IntegratorKind::Path(p) => parts.push_str(&format!(
                "|path {:?}",
                PathSettings {
                    texture_space: PathSettings::default().texture_space,
                    ..p
                }
            )),
            k => parts.push_str(&format!("|integrator {k}")),
        }
        crate::piece::settings_hash(scene, &parts)
    }
}

/// The grey ambient-occlusion image's integrator: the scene's distance
/// (unbounded without an `AmbientOcclusion` block) and sample count.
fn ambient_occlusion(scene: &Scene, samples: EffectSamples) -> AmbientOcclusion {
    AmbientOcclusion {
        settings: AoSettings {
            samples: samples.ao,
            distance: scene
                .effects
                .ambient_occlusion
                .map_or(f32::INFINITY, |a| a.distance),
        },
    }
}

/// `b` (rendering space) moved back to world space by the rendering
/// origin `o`; an empty box stays empty.
fn world_space(b: crate::math::Aabb, o: glam::DVec3) -> crate::math::Aabb {
    if b.is_empty() {
        return b;
    }
    let shift = |v: crate::math::Vec3| (v.as_dvec3() + o).as_vec3();
    crate::math::Aabb {
        min: shift(b.min),
        max: shift(b.max),
    }
}
