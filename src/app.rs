//! What the applications (`glint`, `raytracer`) share and the library does
//! not do: the terminal (progress bar, messages, exit statuses) and signals
//! (Ctrl-C). Built with the `cli` feature, which the binaries require; the
//! library reports progress and takes cancellation through
//! [`crate::render::Control`].
//!
//! Exit statuses, for every command of both programs: 0 success;
//! [`EXIT_USAGE`] (2) a request refused before any work (a bad flag, scene
//! file or output name); [`EXIT_FAILURE`] (1) a failure while working (an
//! image that could not be written, an internal error);
//! [`EXIT_INTERRUPTED`] (130) stopped by Ctrl-C, with what was rendered
//! saved as `NAME.partial.EXT`.

use crate::job::{Job, JobError, Report};
pub use crate::job::{EXIT_FAILURE, EXIT_INTERRUPTED, EXIT_USAGE};
use crate::limits;
use crate::render::Control;
use std::io::IsTerminal;
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

/// The exit-status table, as `--help` prints it.
pub const EXIT_STATUS_HELP: &str = "Exit status: 0 success; 1 a failure while working (an image \
could not be written, an internal error); 2 a request refused before any work (a bad flag, \
scene file or output name); 130 stopped by Ctrl-C (the rows rendered so far are saved as \
NAME.partial.EXT).";

/// Prints `program: error` (bounded, see [`limits::bounded_message`]) and
/// returns its exit status; success is status 0. Every command of both
/// programs ends here.
pub fn exit(program: &str, result: Result<(), JobError>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{program}: {}", limits::bounded_message(&e.to_string()));
            ExitCode::from(e.exit_code())
        }
    }
}

/// A bad request, named by its flag: exit status [`EXIT_USAGE`].
pub fn usage(msg: impl Into<String>) -> JobError {
    JobError::Usage(msg.into())
}

/// Checks `job` as `names` spells the flags, prints its notes (a clamped
/// thread count) and runs it with a Ctrl-C handler and, unless `quiet` or
/// stdout is not a terminal, a progress bar.
pub fn run_job(
    program: &str,
    job: &Job,
    names: crate::job::FlagNames,
    quiet: bool,
) -> Result<Report, JobError> {
    for note in job.validate(names)? {
        eprintln!("{program}: {note}");
    }
    let cancel = interrupt_flag();
    let show = !quiet && std::io::stdout().is_terminal();
    let pixels = u64::from(job.width) * u64::from(job.height);
    // Made at the first finished piece of work: the bar's clock and ETA
    // count rendering only, not loading.
    let bar: OnceLock<indicatif::ProgressBar> = OnceLock::new();
    let tick = |n: u64| {
        if show {
            bar.get_or_init(|| progress_bar(pixels)).inc(n);
        }
    };
    let control = Control {
        cancel: Some(&cancel),
        on_progress: Some(&tick),
    };
    let result = job.run_with(control);
    if let Some(b) = bar.get() {
        b.finish_and_clear();
    }
    result
}

/// Installs a Ctrl-C handler that sets the returned flag; a second Ctrl-C
/// exits at once (status 130) for a user who does not want to wait.
pub fn interrupt_flag() -> Arc<AtomicBool> {
    let flag = Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    // Failing to install (e.g. a handler exists already) only loses the
    // graceful stop; rendering itself is unaffected.
    let _ = ctrlc::set_handler(move || {
        if f.swap(true, Ordering::SeqCst) {
            std::process::exit(i32::from(EXIT_INTERRUPTED));
        }
        eprintln!("\ninterrupt: finishing the rows in flight, then saving a partial image (Ctrl-C again to quit now)");
    });
    flag
}

fn progress_bar(pixels: u64) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(pixels);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{bar:40} {percent:>3}% pixels {pos}/{len}  elapsed {elapsed}  eta {eta}",
    ) {
        bar.set_style(style);
    }
    bar
}

/// Runs a binary's `main` body so that a bug in glint reaches the user as one
/// line naming it an internal error, with exit status 1, and never as a Rust
/// panic message with a backtrace hint.
pub fn run_guarded(program: &'static str, body: impl FnOnce() -> ExitCode) -> ExitCode {
    std::panic::set_hook(Box::new(move |info| {
        let place = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        let what = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_default();
        eprintln!("{program}: internal error (a bug in glint, please report it): {what}{place}");
    }));
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(body)) {
        Ok(code) => code,
        Err(_) => ExitCode::from(EXIT_FAILURE),
    }
}
