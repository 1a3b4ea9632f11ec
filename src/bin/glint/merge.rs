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
        eprintln!("glint merge: {}", glint::limits::bounded_message(&msg));
        ExitCode::from(code)
    };
    if let Err(e) = glint::output::check_path(&a.output) {
        return fail(2, e.to_string());
    }
    // Issue 15: no output may be a piece, or the other output.
    let mut outputs = vec![&a.output];
    outputs.extend(&a.stats_json);
    for out in &outputs {
        let checked = glint::output::check_writable(out)
            .and_then(|()| glint::output::check_not_input(out, &a.pieces));
        if let Err(e) = checked {
            return fail(2, e.to_string());
        }
    }
    if let Some(json) = &a.stats_json {
        if glint::output::same_file(json, &a.output) {
            let msg = "the merged image and the statistics file are the same file";
            return fail(2, format!("{}: {msg}; choose two names", json.display()));
        }
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
        if let Err(e) = glint::output::write_file(path, (text + "\n").as_bytes()) {
            return fail(1, e.to_string());
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
