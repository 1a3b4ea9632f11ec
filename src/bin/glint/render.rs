//! `glint render SCENE -o OUT`: the flags become a [`Job`].

use crate::args::{ImageArgs, SamplingArgs, SceneArgs, ShadingArgs};
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::Args;
use glint::app;
use glint::integrator::IntegratorKind;
use glint::job::{FlagNames, Job, JobError, Output};
use glint::limits;
use glint::piece::PieceSpec;
use glint::world::BuildOptions;
use std::path::PathBuf;

pub const RENDER_HELP: &str = "Render a scene to an image.

SCENE is a scene file in the MIT 6.837 format; a bare Wavefront .obj or Stanford .ply mesh, which renders \
directly: glint frames it with a camera looking at its bounding box and one light; or a glTF 2.0 \
scene (.gltf with its buffers, .glb), with its first camera and its lights when it has them \
(docs/assets.md). Meshes with vertex normals shade smooth; --smooth computes them for the others.

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

/// Arguments of `glint render`.
#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    image: ImageArgs,
    #[command(flatten)]
    shading: ShadingArgs,
    #[command(flatten)]
    sampling: SamplingArgs,
    /// What to compute: whitted (the shaded image), ao (the grey ambient-occlusion image) or path (path tracing with light sampling and MIS; see docs/path-tracing.md).
    #[arg(long, default_value = "whitted", value_parser = PossibleValuesParser::new(IntegratorKind::NAMES).try_map(|s| s.parse::<IntegratorKind>()))]
    integrator: IntegratorKind,
    /// With --integrator path: shoot N photons from the emitting primitives and area lights into a caustic photon map, which then carries the light they send through mirrors and glass onto other surfaces (biased: it blurs over a few photons' distance; see docs/path-tracing.md). 0 (the default, up to 16777216): no map, paths carry every caustic.
    #[arg(long, default_value_t = 0, value_name = "N")]
    caustic_photons: u32,
    /// Encode 8-bit outputs (.png .tga .ppm .bmp) with the sRGB curve, rounded, and mark PNGs sRGB, as image viewers assume. The default stores the linear values truncated to bytes, the course's convention: raytracer's reference images, glint's thumbnails and image hashes compare byte for byte across both commands. .exr/.pfm stay linear.
    #[arg(long)]
    srgb: bool,
    /// Keep the transform hierarchy instead of baking it into world space (to measure flattening).
    #[arg(long)]
    no_flatten: bool,
    /// Worker threads, 1 to 1024 (default: all cores; more than 4 per core are clamped).
    #[arg(long)]
    threads: Option<usize>,
    /// Print statistics.
    #[arg(long)]
    stats: bool,
    /// Write statistics as JSON to this file.
    #[arg(long, value_name = "FILE")]
    stats_json: Option<PathBuf>,
    /// No progress bar.
    #[arg(short, long)]
    quiet: bool,
    /// Also write a depth image: near, far, file.
    #[arg(long, num_args = 3, value_names = ["T0", "T1", "FILE"])]
    depth: Option<Vec<String>>,
    /// Also write a normals image.
    #[arg(long)]
    normals: Option<PathBuf>,
    /// Write a heat map of camera rays per pixel, with a scale bar.
    #[arg(long, value_name = "FILE")]
    samples_image: Option<PathBuf>,
    /// Also write per-pixel cost: intersection tests (left) and nodes or cells visited (right), as heat maps with scale bars and totals.
    #[arg(long, value_name = "FILE")]
    cost_image: Option<PathBuf>,
    /// The course's sample view: every sample as a dot in a zoomed checkerboard of pixels (zoom 1 to 1000).
    #[arg(long, num_args = 2, value_names = ["FILE", "ZOOM"])]
    render_samples: Option<Vec<String>>,
    /// The course's filter view: the filter's weights around the central pixel, zoomed (zoom 1 to 1000).
    #[arg(long, num_args = 2, value_names = ["FILE", "ZOOM"])]
    render_filter: Option<Vec<String>>,
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
}

/// Runs `glint render`.
pub fn run(a: RenderArgs) -> Result<(), JobError> {
    let job = job(&a)?;
    let report = app::run_job("glint", &job, FlagNames::Glint, a.quiet)?;
    if a.stats {
        print!("{}", report.stats_text());
    }
    Ok(())
}

/// The job the flags ask for.
fn job(a: &RenderArgs) -> Result<Job, JobError> {
    let (w, h) = a.image.size();
    let mut job = Job::new(a.scene.scene.clone(), w, h);
    job.integrator = a.integrator;
    let (sampling, path_depth) = a
        .sampling
        .sampling(&a.shading, a.integrator)
        .map_err(app::usage)?;
    job.sampling = sampling;
    job.shading = a.shading.shading(a.integrator);
    if let Some(d) = path_depth {
        job.shading.bounces = d;
    }
    match &mut job.integrator {
        IntegratorKind::Path(p) => {
            p.max_bounces = job.shading.bounces;
            p.caustic_map.photons = a.caustic_photons;
        }
        _ if a.caustic_photons > 0 => {
            return Err(app::usage(
                "--caustic-photons: the caustic map is the path tracer's; add --integrator path",
            ))
        }
        _ => {}
    }
    if a.srgb {
        job.encoding = glint::output::Encoding::Srgb;
    }
    job.build = BuildOptions {
        accel: a.scene.accel,
        flatten: !a.no_flatten,
    };
    job.threads = a.threads;
    job.piece = piece(a, (w, h))?;
    for o in outputs(a)? {
        job.set_output(o);
    }
    match frame(a)? {
        Some(f) => Ok(job.at_frame(f)),
        None => Ok(job),
    }
}

/// Every file the flags ask for, in a fixed order.
fn outputs(a: &RenderArgs) -> Result<Vec<Output>, JobError> {
    let mut out = vec![Output::Colour(a.image.output.clone())];
    if let Some(d) = &a.depth {
        let t = |s: &str| limits::parse_flag::<f32>("--depth", s).map_err(app::usage);
        let (near, far) = (t(&d[0])?, t(&d[1])?);
        let path = PathBuf::from(&d[2]);
        out.push(Output::Depth { near, far, path });
    }
    out.extend(a.normals.clone().map(Output::Normals));
    for (flag, v) in [
        ("--render-samples", &a.render_samples),
        ("--render-filter", &a.render_filter),
    ] {
        let Some(v) = v else { continue };
        let path = PathBuf::from(&v[0]);
        let zoom = limits::parse_flag(flag, &v[1]).map_err(app::usage)?;
        out.push(match flag {
            "--render-samples" => Output::SamplesView { path, zoom },
            _ => Output::FilterView { path, zoom },
        });
    }
    out.extend(a.samples_image.clone().map(Output::SamplesHeatMap));
    out.extend(a.cost_image.clone().map(Output::Cost));
    out.extend(a.stats_json.clone().map(Output::Stats));
    Ok(out)
}

/// The piece of the frame `--tile`, `--tile-from-env` or `--crop` asks for.
fn piece(a: &RenderArgs, size: (u32, u32)) -> Result<Option<PieceSpec>, JobError> {
    let band = |(i, n)| glint::piece::band(i, n, size, glint::render::TILE_SIZE);
    let piece = match (&a.tile, &a.tile_from_env, &a.crop) {
        (Some(t), _, _) => glint::piece::parse_index(t).and_then(band),
        (_, Some(t), _) => {
            glint::piece::index_from_env(t, |v| std::env::var(v).ok()).and_then(band)
        }
        (_, _, Some(c)) => glint::piece::crop([c[0], c[1], c[2], c[3]], size),
        _ => return Ok(None),
    };
    piece.map(Some).map_err(app::usage)
}

/// The animation frame `--frame` or `--frame-from-env` asks for.
fn frame(a: &RenderArgs) -> Result<Option<glint::animation::FrameTime>, JobError> {
    let k = match (a.frame, &a.frame_from_env) {
        (Some(k), _) => Ok(k),
        (_, Some(var)) => glint::animation::frame_from_env(var, |v| std::env::var(v).ok()),
        _ => return Ok(None),
    };
    k.and_then(|k| glint::animation::FrameTime::new(k, a.fps))
        .map(Some)
        .map_err(app::usage)
}

impl RenderArgs {
    #[cfg(test)]
    pub fn accel(&self) -> glint::accel::AccelKind {
        self.scene.accel
    }
}
