//! The glint command line: `glint render SCENE -o OUT`, `glint info SCENE`.

use clap::{Args, Parser, Subcommand};
use glint::accel::AccelKind;
use glint::format::load_scene;
use glint::job::Job;
use glint::material::TextureSpace;
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

#[derive(Subcommand)]
enum Command {
    /// Time every accelerator on the course's meshes (and any OBJ given);
    /// `glint bench rays MESH PREFIX` traces the anchors' ray files.
    #[command(args_conflicts_with_subcommands = true)]
    Bench {
        /// `rays`: the fast BVH on a mesh and ray files, Embree's checksums.
        #[command(subcommand)]
        what: Option<BenchWhat>,
        /// Folder holding the 6.837 scenes.
        #[arg(long, default_value = "../shared/scenes/6837")]
        scenes: PathBuf,
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
        /// Only the cases whose name contains this text.
        #[arg(long)]
        only: Option<String>,
    },
    /// Render a scene to an image.
    Render(RenderArgs),
    /// Show what a scene file holds.
    Info {
        /// Scene file (MIT 6.837 format).
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

#[derive(Args)]
struct RenderArgs {
    /// Scene file (MIT 6.837 format).
    scene: PathBuf,
    /// Output image (.png, .tga, .ppm, .bmp; .exr, .pfm for unclamped float).
    #[arg(short, long)]
    output: PathBuf,
    /// Image size in pixels.
    #[arg(long, num_args = 2, value_names = ["W", "H"], default_values_t = [400, 400])]
    size: Vec<u32>,
    /// Maximum number of reflection/refraction bounces.
    #[arg(long, default_value_t = 5)]
    bounces: u32,
    /// Prune ray-tree branches contributing less than this.
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
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Print statistics.
    #[arg(long)]
    stats: bool,
    /// Accelerator: bvh4 (the fast default), none, grid, grid:NxNxN, octree, bvh (= bvh-sah), bvh-median, bvh-midpoint.
    #[arg(long, default_value = "bvh4")]
    accel: AccelKind,
    /// Keep the transform hierarchy instead of baking it into world space (to measure flattening).
    #[arg(long)]
    no_flatten: bool,
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
    let cli = Cli::parse();
    match cli.command {
        Command::Render(a) => render(a),
        Command::Info { scene } => info(scene),
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
            mesh,
            size,
            runs,
            none_limit,
            only,
        } => match bench::run(&bench::BenchArgs {
            scenes,
            meshes: mesh,
            size,
            runs,
            none_limit_s: none_limit,
            only,
        }) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("glint: {e}");
                ExitCode::from(2)
            }
        },
    }
}

fn render(a: RenderArgs) -> ExitCode {
    let mut job = Job::new(a.scene, a.size[0], a.size[1]);
    job.output = Some(a.output);
    job.integrator.bounces = a.bounces;
    job.integrator.weight_cutoff = a.weight;
    job.integrator.shadows = a.shadows || a.transparent_shadows;
    job.integrator.transparent_shadows = a.transparent_shadows;
    job.integrator.shade_back = a.shade_back;
    job.threads = a.threads;
    job.build.accel = a.accel;
    job.integrator.texture_space = match a.texture_space {
        Space::World => TextureSpace::World,
        Space::Object => TextureSpace::Object,
    };
    job.build.flatten = !a.no_flatten;
    job.stats_json = a.stats_json;
    job.progress = !a.quiet && std::io::stdout().is_terminal();
    job.cancel = Some(glint::job::interrupt_flag());
    job.normals = a.normals;
    if let Some(d) = a.depth {
        let (Ok(t0), Ok(t1)) = (d[0].parse(), d[1].parse()) else {
            eprintln!("glint: --depth expects two numbers and a file, got {d:?}");
            return ExitCode::from(2);
        };
        job.depth = Some((t0, t1, PathBuf::from(&d[2])));
    }
    match job.run() {
        Ok(report) => {
            if a.stats {
                print!("{}", report.stats_text());
            }
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("glint: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}

fn info(path: PathBuf) -> ExitCode {
    let scene = match load_scene(&path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("glint: {}", e.render());
            return ExitCode::from(2);
        }
    };
    let s = scene.summary();
    let world = glint::world::World::build(&scene, Default::default());
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

fn camera_name(c: &glint::scene::Camera) -> &'static str {
    match c {
        glint::scene::Camera::Orthographic { .. } => "orthographic",
        glint::scene::Camera::Perspective { .. } => "perspective",
    }
}
