//! Command lines: any NUL-separated arguments, turned into a render job by the
//! same helpers the command lines use and checked before any work, must never
//! panic, and a job that passes the checks must be within every limit.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../exercise.rs"]
mod exercise;

fuzz_target!(|data: &[u8]| exercise::job_args(data));
