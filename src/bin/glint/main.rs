//! The glint command line: `glint render SCENE -o OUT`, `glint info SCENE`.

use clap::{Parser, Subcommand};
use glint::app;
use glint::format::load_scene;
use glint::job::JobError;
use glint::limits;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "glint",
    version,
    about = "A teaching-grade, production-fast CPU ray tracer",
    after_help = app::EXIT_STATUS_HELP
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

mod args;
mod bench;
mod bench_rays;
mod deep;
mod merge;
mod raytree;
mod render;
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
    #[command(long_about = render::RENDER_HELP, after_help = app::EXIT_STATUS_HELP)]
    Render(Box<render::RenderArgs>),
    /// Record every ray one pixel spawns: .json tree, .obj/.ply segments, or drawn over the image
    /// (.png, .tga, .ppm, .bmp).
    Raytree(raytree::RaytreeArgs),
    /// Show the grid cells, octree leaves or BVH boxes an accelerator looks at for some pixels' eye rays:
    /// drawn over the image (.png, .tga, .ppm, .bmp), .obj segments or .json.
    Traverse(traverse::TraverseArgs),
    /// Draw a BVH's or an octree's boxes at one depth (or its leaves) over the rendered image
    /// (.png, .tga, .ppm, .bmp), or write them as .obj segments.
    Structure(structure::StructureArgs),
    /// Serve the scene live in a browser on 127.0.0.1: progressive render, click a pixel for its ray tree.
    Serve(serve::ServeArgs),
    /// Assemble the pieces of `glint render --tile I/N` (or --crop) into the whole image.
    Merge(merge::MergeArgs),
    /// Show what a scene file holds.
    Info {
        /// Scene file (MIT 6.837 format), a bare .obj or .ply mesh, or a glTF 2.0 scene (.gltf, .glb).
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

fn main() -> ExitCode {
    app::run_guarded("glint", real_main)
}

fn real_main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return clap_error(e),
    };
    let program = match cli.command {
        Command::Merge(_) => "glint merge",
        _ => "glint",
    };
    app::exit(program, run(cli.command))
}

/// Runs one subcommand: every one reports its error the same way
/// ([`app::exit`]).
fn run(command: Command) -> Result<(), JobError> {
    match command {
        Command::Render(a) => render::run(*a),
        Command::Info { scene } => info(scene),
        Command::Merge(a) => merge::run(a),
        Command::Raytree(a) => raytree::run(a),
        Command::Traverse(a) => traverse::run(a),
        Command::Structure(a) => structure::run(a),
        Command::Serve(a) => serve::run(a),
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
        } => bench_rays::run(&bench_rays::RaysArgs {
            mesh,
            prefix,
            threads,
            json,
            stats,
        })
        .map_err(app::usage),
        Command::Bench {
            what: None,
            scenes,
            course,
            mesh,
            size,
            runs,
            none_limit,
            only,
        } => {
            check_bench(size, runs, none_limit).map_err(app::usage)?;
            bench::run(&bench::BenchArgs {
                scenes,
                course,
                meshes: mesh,
                size,
                runs,
                none_limit_s: none_limit,
                only,
            })
            .map_err(app::usage)
        }
    }
}

fn info(path: PathBuf) -> Result<(), JobError> {
    let scene = load_scene(&path)?;
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
    Ok(())
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
        for sub in ["render", "raytree", "traverse", "structure"] {
            let help = long_help(sub);
            for name in glint::accel::AccelKind::NAMES {
                assert!(help.contains(name), "{name} is not in {sub} --help");
            }
        }
    }

    fn long_help(sub: &str) -> String {
        let mut cmd = Cli::command();
        cmd.find_subcommand_mut(sub)
            .expect("subcommand")
            .render_long_help()
            .to_string()
    }

    /// `glint render --help` names every integrator and the exit statuses.
    #[test]
    fn render_help_lists_every_integrator_and_the_exit_statuses() {
        let help = long_help("render");
        for name in glint::integrator::IntegratorKind::NAMES {
            assert!(help.contains(name), "{name} is not in render --help");
        }
        assert!(help.contains("Exit status: 0 success"), "{help}");
    }

    /// The shared groups give every view command the same defaults.
    #[test]
    fn the_view_commands_share_their_defaults() {
        let parse = |line: &str| {
            Cli::try_parse_from(line.split_whitespace())
                .unwrap()
                .command
        };
        let accel_of = |c: Command| match c {
            Command::Render(a) => a.accel(),
            Command::Raytree(a) => a.accel(),
            Command::Traverse(a) => a.accel(),
            Command::Structure(a) => a.accel(),
            _ => unreachable!(),
        };
        for line in [
            "glint render s.txt -o o.png",
            "glint raytree s.txt --pixel 1 1 -o o.png",
            "glint traverse s.txt --pixel 1 1 -o o.png",
            "glint structure s.txt -o o.png",
        ] {
            assert_eq!(
                accel_of(parse(line)),
                glint::accel::AccelKind::default(),
                "{line}"
            );
        }
    }
}
