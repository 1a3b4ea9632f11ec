//! `glint merge PIECES... -o OUT`: assembles the pieces `glint render --tile`
//! wrote into the whole frame, exactly as one machine would have rendered it.

use clap::Args;
use glint::app;
use glint::job::JobError;
use std::path::PathBuf;

/// Arguments of `glint merge`.
#[derive(Args)]
pub struct MergeArgs {
    /// The piece files (.exr) written by `glint render --tile I/N` or `--crop`.
    #[arg(required = true)]
    pieces: Vec<PathBuf>,
    /// The whole image, in any format glint writes (.png, .tga, .ppm, .bmp, .exr, .pfm).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the merged statistics (the pieces' counters added up) as JSON.
    #[arg(long, value_name = "FILE")]
    stats_json: Option<PathBuf>,
}

/// Runs `glint merge`: exit 2, writing nothing, when the pieces do not make
/// exactly one frame.
pub fn run(a: MergeArgs) -> Result<(), JobError> {
    glint::output::check_path(&a.output)?;
    // Issue 15: no output may be a piece, or the other output.
    let mut outputs = vec![&a.output];
    outputs.extend(&a.stats_json);
    for out in &outputs {
        glint::output::check_writable(out)?;
        glint::output::check_not_input(out, &a.pieces)?;
    }
    if let Some(json) = &a.stats_json {
        if glint::output::same_file(json, &a.output) {
            let msg = "the merged image and the statistics file are the same file";
            return Err(app::usage(format!(
                "{}: {msg}; choose two names",
                json.display()
            )));
        }
    }
    let pieces = a
        .pieces
        .iter()
        .map(|p| glint::piece::read(p))
        .collect::<Result<Vec<_>, _>>()
        .map_err(app::usage)?;
    let ((w, h), pixels, stats) = glint::piece::merge(&pieces).map_err(app::usage)?;
    glint::output::write_rgb(&a.output, w, h, &pixels)?;
    if let Some(path) = &a.stats_json {
        let text = serde_json::to_string_pretty(&stats).unwrap_or_default();
        glint::output::write_file(path, (text + "\n").as_bytes())?;
    }
    println!(
        "merged {} pieces into {} ({w}x{h}, settings {})",
        pieces.len(),
        a.output.display(),
        pieces[0].hash
    );
    Ok(())
}
