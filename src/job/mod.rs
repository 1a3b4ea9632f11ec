//! One render as both command lines describe it, in stages:
//!
//! - [`spec`]: the request ([`Job`]) and [`Job::validate`], the one place
//!   every number of a request is checked against its range;
//! - [`preflight`]: every check before any work (formats, memory, outputs
//!   that would overwrite an input or each other, pieces);
//! - [`pipeline`]: load, build the world, render with the chosen
//!   [`IntegratorKind`](crate::integrator::IntegratorKind) (one dispatch);
//! - [`outputs`]: the requested files, a list of [`Output`]s, and their writing;
//! - [`report`]: what the job measured ([`Report`], [`Stats`]).
//!
//! The binaries translate their flags into a [`Job`]; they own the terminal
//! (progress bars, Ctrl-C), which reaches the job through a
//! [`crate::render::Control`] given to [`Job::run_with`].

pub mod outputs;
pub mod pipeline;
pub mod preflight;
pub mod report;
pub mod spec;

pub use outputs::{Output, MAX_ZOOM};
pub use preflight::{available_memory, check_frame_memory, load_scene_for, FRAME_BYTES_PER_PIXEL};
pub use report::{course_stats_text, Report, Stats};
pub use spec::{depths, uses_sampling, FlagNames, Job, SampleOverrides, Sampling, Shading};

pub use crate::limits::FALLBACK_AVAILABLE;

use crate::format::ParseError;
use crate::output::OutputError;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// Why a job failed; [`JobError::exit_code`] is the process exit status.
#[derive(Debug, Error)]
pub enum JobError {
    /// The scene could not be read.
    #[error("{}", .0.render())]
    Parse(#[from] ParseError),
    /// An image could not be written.
    #[error("{0}")]
    Output(#[from] OutputError),
    /// The request itself is invalid (e.g. a zero image size).
    #[error("{0}")]
    Usage(String),
    /// Anything else (thread pool creation, ...).
    #[error("{0}")]
    Internal(String),
    /// Stopped by the user; what was rendered is in these files.
    #[error("interrupted: saved the rows rendered so far to {}", list(.0))]
    Interrupted(Vec<PathBuf>),
}

/// Exit status of a request the user must fix (a bad flag, scene or
/// output name), refused before any work.
pub const EXIT_USAGE: u8 = 2;
/// Exit status of a failure while working (an image that could not be
/// written, an internal error).
pub const EXIT_FAILURE: u8 = 1;
/// Exit status of a render stopped by Ctrl-C (128 + SIGINT).
pub const EXIT_INTERRUPTED: u8 = 130;

impl JobError {
    /// The process exit status for this error: [`EXIT_USAGE`] for bad
    /// input, [`EXIT_INTERRUPTED`] when stopped, [`EXIT_FAILURE`] otherwise.
    pub fn exit_code(&self) -> u8 {
        match self {
            // A request that names no writable image is the user's to fix;
            // checked before any work.
            JobError::Parse(_)
            | JobError::Usage(_)
            | JobError::Output(
                OutputError::Format { .. }
                | OutputError::NoDir { .. }
                | OutputError::Refused { .. },
            ) => EXIT_USAGE,
            JobError::Output(_) | JobError::Internal(_) => EXIT_FAILURE,
            JobError::Interrupted(_) => EXIT_INTERRUPTED,
        }
    }
}

fn list(paths: &[PathBuf]) -> String {
    let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    if names.is_empty() {
        "no file (no output was requested)".into()
    } else {
        names.join(", ")
    }
}

/// `out.png` → `out.partial.png`: where an interrupted render is saved, so
/// the file the user asked for is never replaced by an incomplete image.
pub fn partial_path(p: &Path) -> PathBuf {
    let stem = p
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = match p.extension() {
        Some(ext) => format!("{stem}.partial.{}", ext.to_string_lossy()),
        None => format!("{stem}.partial"),
    };
    p.with_file_name(name)
}
