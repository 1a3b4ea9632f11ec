//! The glint command line: `glint render SCENE -o OUT`, `glint info SCENE`.

use clap::{Args, Parser, Subcommand};
use glint::accel::AccelKind;
use glint::format::load_scene;
use glint::job::Job;
use glint::limits;
use glint::material::TextureSpace;
use glint::render::{Adaptive, Filter};
use glint::sampler::{Sampler, SamplerKind};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "glint",
    version,
    about = "A teaching-grade, production-fast CPU ray tracer"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

mod bench;
mod bench_rays;
mod deep;
mod merge;
mod raytree;
mod serve;
mod structure;
mod traverse;

#[derive(Subcommand)]
enum Command {
    /// Time every accelerator on glint's own example scenes (or the course's meshes, and any OBJ given);
    /// `glint bench rays MESH PREFIX` traces the anchors' ray files.
    #[command(args_conflicts_with_subcommands = true)]
    Bench {
        /// `rays`: the fast BVH on a mesh and ray files, Embree's checksums.
        #[command(subcommand)]
        what: Option<BenchWhat>,
        /// Folder of glint's own example scenes.
        #[arg(long, default_value = "scenes")]
        scenes: PathBuf,
        /// Bench the course's bunnies and logo from this folder instead (e.g. ../shared/scenes/6837).
        #[arg(long, value_name = "DIR")]
        course: Option<PathBuf>,
        /// Extra OBJ meshes, e.g. the anchors' meshgen output (see scripts/bench.sh).
        #[arg(long)]
        mesh: Vec<PathBuf>,
        /// Square image size.
        #[arg(long, default_value_t = 400)]
        size: u32,
        /// Timed runs per accelerator (median reported).
        #[arg(long, default_value_t = 3)]
        runs: usize,
        /// Skip brute force (and extrapolate it) when it would take longer than this many seconds.
        #[arg(long, default_value_t = 60.0)]
        none_limit: f64,
        /// Only the cases whose name contains this text (or any of several, comma-separated).
        #[arg(long)]
        only: Option<String>,
    },
    /// Render a scene to an image.
    #[command(long_about = RENDER_HELP)]
    Render(Box<RenderArgs>),
    /// Record every ray one pixel spawns: .json tree, .obj/.ply segments, or drawn over the image.
    Raytree(raytree::RaytreeArgs),
    /// Show the grid cells, octree leaves or BVH boxes an accelerator looks at for some pixels' eye rays.
    Traverse(traverse::TraverseArgs),
    /// Draw a BVH's or an octree's boxes at one depth (or its leaves) over the rendered image.
    Structure(structure::StructureArgs),
    /// Assemble the pieces of `glint render --tile I/N` (or --crop) into the whole image.
    Merge(merge::MergeArgs),
    /// Serve the scene live in a browser on 127.0.0.1: progressive render, click a pixel for its ray tree.
    Serve(serve::ServeArgs),
    /// Show what a scene file holds.
    Info {
        /// Scene file (MIT 6.837 format) or a bare .obj mesh.
        scene: PathBuf,
    },
}

#[derive(Subcommand)]
enum BenchWhat {
    /// Build the default BVH over MESH and trace PREFIX.primary.rays,
    /// PREFIX.incoherent.rays (closest hit) and PREFIX.shadow.rays (any hit).
    Rays {
        /// The mesh (OBJ).
        mesh: PathBuf,
        /// Ray file prefix (as written by the anchors' raygen and embree_bench).
        prefix: String,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
        /// Also print nodes visited and triangles tested per ray (untimed pass).
        #[arg(long)]
        stats: bool,
    },
}

const RENDER_HELP: &str = "Render a scene to an image.

SCENE is a scene file in the MIT 6.837 format, or a bare Wavefront .obj mesh, which renders \
directly: glint frames it with a camera looking at its bounding box and one light.

The output format comes from the extension: .png, .tga (uncompressed 24-bit), .ppm (binary P6) \
and .bmp are 8-bit, clamped to [0, 1]; .exr (OpenEXR) and .pfm (portable float map) keep the \
linear 32-bit values unclamped. An unsupported extension is refused before any work (exit 2).

The eye ray of each pixel goes through the pixel's centre. The `raytracer` command, which \
runs the course's command lines verbatim, uses the pixel's lower-left corner instead, the \
course's convention, which its reference images match exactly.

Conventions (docs/scene-format.md, \"Conventions\"): a pixel is diffuse colour x irradiance, with no \
1/pi; a flat area light's power is shared by its two faces; an orthographic camera sees objects \
behind its centre plane (rays start at t = -inf, as in the course), a perspective camera does not; \
`aperture` is the lens radius and the focus is a plane at `focusDistance` along the view direction.";

#[derive(Args)]
struct RenderArgs {
    /// Scene file (MIT 6.837 format) or a bare .obj mesh.
    scene: PathBuf,
    /// Output image: .png, .tga, .ppm, .bmp (8-bit); .exr, .pfm (unclamped float).
    #[arg(short, long)]
    output: PathBuf,
    /// Encode 8-bit outputs (.png .tga .ppm .bmp) with the sRGB curve, rounded, and mark PNGs sRGB, as image viewers assume. The default stores the linear values truncated to bytes, the course's convention: raytracer's reference images, glint's thumbnails and image hashes compare byte for byte across both commands. .exr/.pfm stay linear.
    #[arg(long)]
    srgb: bool,
    /// Image size in pixels.
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = [400, 400])]
    size: Vec<u32>,
    /// Maximum number of reflection/refraction bounces (0 to 64; default 5). With --integrator path: scattering events per path (default 64; 0 shows emitters only, 1 direct light).
    #[arg(long)]
    bounces: Option<u32>,
    /// Prune ray-tree branches contributing less than this (finite, >= 0).
    #[arg(long, default_value_t = 0.01)]
    weight: f32,
    /// Cast shadow rays.
    #[arg(long)]
    shadows: bool,
    /// Filter light through transparent occluders instead of opaque shadows.
    #[arg(long)]
    transparent_shadows: bool,
    /// Light the back sides of surfaces.
    #[arg(long)]
    shade_back: bool,
    /// Worker threads, 1 to 1024 (default: all cores; more than 4 per core are clamped).
    #[arg(long)]
    threads: Option<usize>,
    /// Print statistics.
    #[arg(long)]
    stats: bool,
    /// Accelerator: bvh8 (the fast default; bvh4 is an alias), none, grid, grid:NxNxN, nested-grid[:THRESHOLD[:DEPTH]] (defaults 16:2), octree, octree-inner, bvh (= bvh-sah), bvh-median, bvh-midpoint, bvh-hierarchy.
    #[arg(long, default_value = "bvh8")]
    accel: AccelKind,
    /// Keep the transform hierarchy instead of baking it into world space (to measure flattening).
    #[arg(long)]
    no_flatten: bool,
    /// Smooth shading for every mesh: vertex normals interpolated across triangles, computed (angle-weighted) for meshes whose file has none. Meshes whose file gives normals (PLY, glTF) are smooth without it.
    #[arg(long)]
    smooth: bool,
    /// Write statistics as JSON to this file.
    #[arg(long, value_name = "FILE")]
    stats_json: Option<PathBuf>,
    /// Where textures are looked up: world (what 6.837 scenes are written for) or object (textures stick to moving objects).
    #[arg(long, value_enum, default_value_t = Space::World)]
    texture_space: Space,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
    /// Also write a depth image: near, far, file.
    #[arg(long, num_args = 3, value_names = ["T0", "T1", "FILE"])]
    depth: Option<Vec<String>>,
    /// Also write a normals image.
    #[arg(long)]
    normals: Option<PathBuf>,
    /// Samples (camera rays) per pixel.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=65536))]
    spp: u32,
    /// Sample layout: uniform (grid of cell centres), random, jittered, sobol (Owen-scrambled; the default with --spp above 1).
    #[arg(long)]
    sampler: Option<SamplerKind>,
    /// Seed of the random samplers (changes the noise, not its statistics).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Reconstruction filter: box:R, tent:R or gaussian:SIGMA (radius in pixels; gaussian cut at 2 sigma, a round kernel; `raytracer -gaussian_filter` keeps the course's square kernel, also gaussian-square:SIGMA).
    #[arg(long, default_value = "box:0.5")]
    filter: Filter,
    /// Whitted's adaptive supersampling: split a pixel square where its corners differ by more than this (0..1).
    #[arg(long, value_name = "THRESHOLD")]
    adaptive: Option<f32>,
    /// Deepest adaptive subdivision (squares of 2^-D pixels).
    #[arg(long, value_name = "D", default_value_t = Adaptive::DEFAULT_MAX_DEPTH, value_parser = clap::value_parser!(u32).range(0..=Adaptive::MAX_DEPTH as i64))]
    max_depth: u32,
    /// Write a heat map of camera rays per pixel, with a scale bar.
    #[arg(long, value_name = "FILE")]
    samples_image: Option<PathBuf>,
    /// Also write per-pixel cost: intersection tests (left) and nodes or cells visited (right), as heat maps with scale bars and totals.
    #[arg(long, value_name = "FILE")]
    cost_image: Option<PathBuf>,
    /// Render only piece I of N (0-based horizontal bands of the frame) and write it as an EXR with that data window, for `glint merge`.
    #[arg(long, value_name = "I/N", conflicts_with_all = ["tile_from_env", "crop"])]
    tile: Option<String>,
    /// Like --tile, with I read from an environment variable: SLURM_ARRAY_TASK_ID/N, JOB_COMPLETION_INDEX/N (Kubernetes), ...
    #[arg(long, value_name = "VAR/N", conflicts_with = "crop")]
    tile_from_env: Option<String>,
    /// Render only the pixels X0..X1 x Y0..Y1 (half-open; x right, y down from the top) as an EXR piece.
    #[arg(long, num_args = 4, value_names = ["X0", "Y0", "X1", "Y1"])]
    crop: Option<Vec<u32>>,
    /// Render frame K of the scene's animation (moving objects and camera): time K/FPS, the shutter moved there; '#'s in output names become the frame number (shot_####.png).
    #[arg(long, value_name = "K", conflicts_with = "frame_from_env")]
    frame: Option<u32>,
    /// Like --frame, with K read from an environment variable (SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX, ...).
    #[arg(long, value_name = "VAR")]
    frame_from_env: Option<String>,
    /// Frames per second of --frame (frame K starts at K/FPS in the scene's time unit).
    #[arg(long, default_value_t = glint::animation::DEFAULT_FPS)]
    fps: f64,
    /// The course's sample view: every sample as a dot in a zoomed checkerboard of pixels.
    #[arg(long, num_args = 2, value_names = ["FILE", "ZOOM"])]
    render_samples: Option<Vec<String>>,
    /// The course's filter view: the filter's weights around the central pixel, zoomed.
    #[arg(long, num_args = 2, value_names = ["FILE", "ZOOM"])]
    render_filter: Option<Vec<String>>,
    /// Shadow rays per area light per shaded point (overrides the scene's Samples).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=4096))]
    shadow_samples: Option<u32>,
    /// Rays per glossy lobe (overrides the scene's Samples).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=4096))]
    glossy_samples: Option<u32>,
    /// Shutter instants per pixel sample: camera rays = spp x time x lens (overrides the scene's Samples).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=4096))]
    time_samples: Option<u32>,
    /// Lens points per pixel sample: camera rays = spp x time x lens (overrides the scene's Samples).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=4096))]
    lens_samples: Option<u32>,
    /// Ambient-occlusion rays per shaded point (overrides the scene's AmbientOcclusion).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=4096))]
    ao_samples: Option<u32>,
    /// What to compute: whitted (shaded image), ao (grey ambient-occlusion image) or path (path tracing with light sampling and MIS; see docs/path-tracing.md).
    #[arg(long, value_enum, default_value_t = IntegratorName::Whitted)]
    integrator: IntegratorName,
}

/// Command-line names of the integrators.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum IntegratorName {
    Whitted,
    Ao,
    Path,
}

/// Command-line names of [`TextureSpace`].
#[derive(Clone, Copy, clap::ValueEnum)]
enum Space {
    World,
    Object,
}

fn main() -> ExitCode {
    glint::job::run_guarded("glint", real_main)
}

fn real_main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return clap_error(e),
    };
    match cli.command {
        Command::Render(a) => render(*a),
        Command::Info { scene } => info(scene),
        Command::Merge(a) => merge::run(a),
        Command::Raytree(a) => raytree::run(a),
        Command::Serve(a) => serve::run(a),
        Command::Traverse(a) => traverse::run(a),
        Command::Structure(a) => structure::run(a),
        Command::Bench {
            what:
                Some(BenchWhat::Rays {
                    mesh,
                    prefix,
                    threads,
                    json,
                    stats,
                }),
            ..
        } => match bench_rays::run(&bench_rays::RaysArgs {
            mesh,
            prefix,
            threads,
            json,
            stats,
        }) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("glint: {e}");
                ExitCode::from(2)
            }
        },
        Command::Bench {
            what: None,
            scenes,
            course,
            mesh,
            size,
            runs,
            none_limit,
            only,
        } => match check_bench(size, runs, none_limit).and_then(|()| {
            bench::run(&bench::BenchArgs {
                scenes,
                course,
                meshes: mesh,
                size,
                runs,
                none_limit_s: none_limit,
                only,
            })
        }) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("glint: {}", limits::bounded_message(&e));
                ExitCode::from(2)
            }
        },
    }
}

fn render(a: RenderArgs) -> ExitCode {
    let mut job = Job::new(a.scene.clone(), a.size[0], a.size[1]);
    if let Err(msg) = check_numbers(&a, &mut job) {
        eprintln!("glint: {}", limits::bounded_message(&msg));
        return ExitCode::from(2);
    }
    job.output = Some(a.output);
    if a.srgb {
        job.encoding = glint::output::Encoding::Srgb;
    }
    job.integrator.shadows = a.shadows || a.transparent_shadows;
    job.integrator.transparent_shadows = a.transparent_shadows;
    job.integrator.shade_back = a.shade_back;
    job.build.accel = a.accel;
    job.integrator.texture_space = match a.texture_space {
        Space::World => TextureSpace::World,
        Space::Object => TextureSpace::Object,
    };
    job.build.flatten = !a.no_flatten;
    job.smooth = a.smooth;
    job.stats_json = a.stats_json;
    job.progress = !a.quiet && std::io::stdout().is_terminal();
    job.cancel = Some(glint::job::interrupt_flag());
    job.normals = a.normals;
    if let Some(d) = a.depth {
        let t = |s: &str| limits::parse_finite("--depth", s, f32::MIN, f32::MAX);
        let (t0, t1) = match (t(&d[0]), t(&d[1])) {
            (Ok(t0), Ok(t1)) => (t0, t1),
            (Err(msg), _) | (_, Err(msg)) => {
                eprintln!("glint: {msg} (--depth T0 T1 FILE)");
                return ExitCode::from(2);
            }
        };
        job.depth = Some((t0, t1, PathBuf::from(&d[2])));
    }
    if a.spp > 1 || a.sampler.is_some() {
        job.sampler = Some(Sampler::new(
            a.sampler.unwrap_or(SamplerKind::Sobol),
            a.spp,
            a.seed,
        ));
    }
    job.filter = a.filter;
    if let Some(t) = a.adaptive {
        if t.is_nan() || t < 0.0 {
            eprintln!("glint: --adaptive {t}: the threshold must be at least 0");
            return ExitCode::from(2);
        }
        job.adaptive = Some(Adaptive {
            threshold: t,
            max_depth: a.max_depth,
        });
    }
    job.samples_image = a.samples_image;
    job.effect_samples = glint::job::SampleOverrides {
        shadow: a.shadow_samples,
        glossy: a.glossy_samples,
        time: a.time_samples,
        lens: a.lens_samples,
        ao: a.ao_samples,
    };
    job.ao_image = a.integrator == IntegratorName::Ao;
    if a.integrator == IntegratorName::Path {
        job.path = Some(glint::integrator::PathSettings {
            max_bounces: job.integrator.bounces,
            ..Default::default()
        });
    }
    job.cost_image = a.cost_image;
    let size = (job.width, job.height);
    let piece = match (&a.tile, &a.tile_from_env, &a.crop) {
        (Some(t), _, _) => Some(
            glint::piece::parse_index(t)
                .and_then(|(i, n)| glint::piece::band(i, n, size, glint::render::TILE_SIZE)),
        ),
        (_, Some(t), _) => Some(
            glint::piece::index_from_env(t, |v| std::env::var(v).ok())
                .and_then(|(i, n)| glint::piece::band(i, n, size, glint::render::TILE_SIZE)),
        ),
        (_, _, Some(c)) => Some(glint::piece::crop([c[0], c[1], c[2], c[3]], size)),
        _ => None,
    };
    match piece {
        Some(Err(e)) => {
            eprintln!("glint: {e}");
            return ExitCode::from(2);
        }
        Some(Ok(p)) => job.piece = Some(p),
        None => {}
    }
    for (what, v, slot) in [
        ("--render-samples", a.render_samples, &mut job.samples_view),
        ("--render-filter", a.render_filter, &mut job.filter_view),
    ] {
        if let Some(v) = v {
            match v[1].parse::<u32>() {
                Ok(z) if (1..=1000).contains(&z) => *slot = Some((PathBuf::from(&v[0]), z)),
                _ => {
                    eprintln!("glint: {what} expects a file and a zoom from 1 to 1000, got {v:?}");
                    return ExitCode::from(2);
                }
            }
        }
    }
    let frame = match (a.frame, &a.frame_from_env) {
        (Some(k), _) => Some(Ok(k)),
        (_, Some(var)) => Some(glint::animation::frame_from_env(var, |v| {
            std::env::var(v).ok()
        })),
        _ => None,
    };
    if let Some(k) = frame {
        match k.and_then(|k| glint::animation::FrameTime::new(k, a.fps)) {
            Ok(f) => job = job.at_frame(f),
            Err(e) => {
                eprintln!("glint: {e}");
                return ExitCode::from(2);
            }
        }
    }
    match job.run() {
        Ok(report) => {
            if a.stats {
                print!("{}", report.stats_text());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("glint: {}", limits::bounded_message(&e.to_string()));
            ExitCode::from(e.exit_code() as u8)
        }
    }
}

fn info(path: PathBuf) -> ExitCode {
    let scene = match load_scene(&path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("glint: {}", limits::bounded_message(&e.render()));
            return ExitCode::from(2);
        }
    };
    let s = scene.summary();
    // World space: the bounds printed are the scene file's coordinates.
    let world = glint::world::World::build_world_space(&scene, Default::default());
    let b = world.bounds();
    println!("scene       {}", path.display());
    println!("camera      {}", camera_name(&scene.camera));
    println!(
        "objects     {} spheres, {} planes, {} triangles ({} meshes)",
        s.spheres, s.planes, s.triangles, s.meshes
    );
    println!(
        "structure   {} groups, {} transforms",
        s.groups, s.transforms
    );
    println!("lights      {}", s.lights);
    println!("materials   {}", s.materials);
    if b.is_empty() {
        println!("bounds      (no bounded objects)");
    } else {
        println!(
            "bounds      ({:.4}, {:.4}, {:.4}) .. ({:.4}, {:.4}, {:.4})",
            b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
        );
    }
    ExitCode::SUCCESS
}

/// Prints a command-line error as clap would, but never more than a few
/// kilobytes: clap quotes a bad value whole, and one argument may be 128 kB.
fn clap_error(e: clap::Error) -> ExitCode {
    let text = e.render().to_string();
    if !e.use_stderr() || text.len() <= 8192 {
        e.exit()
    }
    eprint!("{}", limits::bounded_message(&text));
    ExitCode::from(2)
}

/// `glint bench`'s numbers: a size the frame check allows, 1 to 1000 runs,
/// and a finite time limit.
fn check_bench(size: u32, runs: usize, none_limit: f64) -> Result<(), String> {
    limits::int_in("--size", size, 1, 16_384)?;
    limits::int_in("--runs", runs, 1, 1000)?;
    if !(none_limit.is_finite() && none_limit >= 0.0) {
        return Err(format!(
            "--none-limit: {none_limit} is not a finite number of seconds >= 0"
        ));
    }
    Ok(())
}

/// The numeric render flags, in their documented ranges ([`limits`]):
/// `--weight nan` rendered before issue 15, `--threads 100000` hung.
fn check_numbers(a: &RenderArgs, job: &mut Job) -> Result<(), String> {
    let default_bounces = match a.integrator {
        IntegratorName::Path => glint::integrator::PathSettings::default().max_bounces,
        _ => 5,
    };
    let bounces = a.bounces.unwrap_or(default_bounces);
    job.integrator.bounces = limits::int_in("--bounces", bounces, 0, limits::MAX_BOUNCES)?;
    job.integrator.weight_cutoff = limits::finite_in("--weight", a.weight, 0.0, f32::MAX)?;
    if let Some(n) = a.threads {
        let (n, note) = limits::threads("--threads", n, limits::cores())?;
        if let Some(note) = note {
            eprintln!("glint: {note}");
        }
        job.threads = Some(n);
    }
    Ok(())
}

fn camera_name(c: &glint::scene::Camera) -> &'static str {
    match c {
        glint::scene::Camera::Orthographic { .. } => "orthographic",
        glint::scene::Camera::Perspective { .. } => "perspective",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// `glint render --help` names every accelerator `--accel` accepts.
    #[test]
    fn render_help_lists_every_accelerator() {
        let mut cmd = Cli::command();
        let help = cmd
            .find_subcommand_mut("render")
            .expect("render subcommand")
            .render_long_help()
            .to_string();
        for name in AccelKind::NAMES {
            assert!(help.contains(name), "{name} is not in render --help");
        }
    }
}
