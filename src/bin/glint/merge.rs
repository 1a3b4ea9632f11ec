//! `glint merge PIECES... -o OUT`: assembles the pieces `glint render --tile`
//! wrote into the whole frame, exactly as one machine would have rendered it.

use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;

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
pub fn run(a: MergeArgs) -> ExitCode {
    let fail = |code: u8, msg: String| {
        eprintln!("glint merge: {msg}");
        ExitCode::from(code)
    };
    if let Err(e) = glint::output::check_path(&a.output) {
        return fail(2, e.to_string());
    }
    let mut pieces = Vec::new();
    for p in &a.pieces {
        match glint::piece::read(p) {
            Ok(piece) => pieces.push(piece),
            Err(e) => return fail(2, e),
        }
    }
    let ((w, h), pixels, stats) = match glint::piece::merge(&pieces) {
        Ok(m) => m,
        Err(e) => return fail(2, e),
    };
    if let Err(e) = glint::output::write_rgb(&a.output, w, h, &pixels) {
        return fail(1, e.to_string());
    }
    if let Some(path) = &a.stats_json {
        let text = serde_json::to_string_pretty(&stats).unwrap_or_default();
        if let Err(e) = std::fs::write(path, text + "\n") {
            return fail(1, format!("{}: {e}", path.display()));
        }
    }
    println!(
        "merged {} pieces into {} ({w}x{h}, settings {})",
        pieces.len(),
        a.output.display(),
        pieces[0].hash
    );
    ExitCode::SUCCESS
}
