//! Every limit glint puts on its inputs, in one place, with the helpers both
//! command lines call to check a flag's value.
//!
//! A hostile or mistyped value must end in a clear message and exit status 2,
//! never in a hang, an abort or gigabytes of output. The values here are
//! listed in `docs/reliability.md`; a change to one is a change to that page.

use std::fmt::Display;
use std::str::FromStr;

/// Most worker threads accepted (`--threads`/`-threads`). Rayon creates them
/// all up front; beyond a few per core they only cost memory and start-up.
pub const MAX_THREADS: usize = 1024;

/// Threads per core beyond which a request is clamped (with a note).
pub const THREADS_PER_CORE: usize = 4;

/// Deepest reflection/refraction recursion accepted (`-bounces`). The course's
/// scenes use at most 10; the ray tree can branch at every level, so the
/// weight cutoff, not this cap, is what keeps glass-in-glass scenes fast.
pub const MAX_BOUNCES: u32 = 64;

/// Most samples per pixel (`-random_samples N`, `--spp N`, ...): the work
/// of a render grows with it, and 4096 is beyond any use in the course.
pub const MAX_SAMPLES: u32 = 4096;

/// Most photons of the path tracer's caustic map (`--caustic-photons N`):
/// each stored photon takes 48 bytes, and in a scene of glass every one
/// may be stored (2^24 photons: at most 0.8 GB).
pub const MAX_PHOTONS: u32 = 1 << 24;

/// Most noise octaves a texture may ask for. Octave `i` samples at frequency
/// `2^i`; past about 30 octaves the terms are below `f64` resolution of the
/// sum, so more only costs time (2e9 octaves used to hang a render).
pub const MAX_OCTAVES: u32 = 32;

/// Largest colour component a scene may give (materials' diffuse and
/// specular colours, lights, background, ambient light). Reflective and
/// transparent colours are at most 1. With these, and the attenuation gain
/// below, a pixel stays far below `f32::MAX`: each ray adds at most
/// `10^12` per light, and its weight never grows down the tree.
pub const MAX_COLOR: f32 = 1e4;

/// Most a point light's attenuation `1/(a + b·d + c·d²)` may amplify it.
pub const MAX_ATTENUATION_GAIN: f32 = 1e4;

/// Longest line, in bytes, an OBJ file may have. A face line with this many
/// bytes already has about 100,000 corners.
pub const MAX_OBJ_LINE_BYTES: usize = 1 << 20;

/// Most corners one OBJ face may have (it is triangulated as a fan).
pub const MAX_FACE_CORNERS: usize = 65_536;

/// Parsing takes at most about this many bytes of memory per byte of input
/// (a scene's tokens are 40 bytes each, and a token can be 2 bytes long; an
/// OBJ's triangles become world primitives and acceleration nodes). An input
/// file may be at most `available memory / INPUT_MEMORY_FACTOR` bytes.
pub const INPUT_MEMORY_FACTOR: u64 = 20;

/// Characters of a source line quoted around the error column.
pub const SNIPPET_CHARS: usize = 100;

/// Longest line, in bytes, of any message printed on stderr; longer lines
/// (e.g. a path of 100,000 characters) are shortened in the middle.
pub const MAX_MESSAGE_LINE: usize = 2048;

/// Memory assumed available where `/proc/meminfo` cannot be read.
pub const FALLBACK_AVAILABLE: u64 = 16 << 30;

/// Bytes this process can still allocate: the smaller of the system's
/// `MemAvailable` and what the address-space limit (`ulimit -v`, `prlimit
/// --as`) leaves above the current size. Either unknown: the other; both
/// unknown: [`FALLBACK_AVAILABLE`].
pub fn available_memory() -> u64 {
    let system = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| kib_field(&s, "MemAvailable:"));
    let limit = address_space_left();
    match (system, limit) {
        (Some(a), Some(b)) => a.min(b),
        (Some(a), None) | (None, Some(a)) => a,
        (None, None) => FALLBACK_AVAILABLE,
    }
}

/// `RLIMIT_AS` minus the current virtual size, read from `/proc/self/*`
/// (no `unsafe`, no libc call); `None` when unlimited or unknown.
fn address_space_left() -> Option<u64> {
    let limits = std::fs::read_to_string("/proc/self/limits").ok()?;
    let line = limits
        .lines()
        .find(|l| l.starts_with("Max address space"))?;
    // "Max address space   SOFT   HARD   bytes": the soft limit is in force.
    let soft: u64 = line
        .trim_start_matches("Max address space")
        .split_whitespace()
        .next()?
        .parse()
        .ok()?;
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let used = kib_field(&status, "VmSize:").unwrap_or(0);
    Some(soft.saturating_sub(used))
}

/// The value of a `NAME:  1234 kB` line, in bytes.
fn kib_field(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// Largest input file accepted with `available` bytes of memory.
pub fn max_input_bytes(available: u64) -> u64 {
    available / INPUT_MEMORY_FACTOR
}

/// Parses a flag's value, quoting a bounded part of it in the message.
pub fn parse_flag<T: FromStr>(flag: &str, s: &str) -> Result<T, String> {
    s.parse()
        .map_err(|_| format!("{flag}: {} is not a valid number", shorten(s)))
}

/// A finite float flag within `[min, max]` (`NaN`, `inf` and values outside
/// are refused with the flag's name).
pub fn finite_in(flag: &str, v: f32, min: f32, max: f32) -> Result<f32, String> {
    if v.is_finite() && v >= min && v <= max {
        Ok(v)
    } else {
        Err(format!(
            "{flag}: {v} is out of range (a finite number from {min} to {max})"
        ))
    }
}

/// A finite float flag, parsed: see [`finite_in`].
pub fn parse_finite(flag: &str, s: &str, min: f32, max: f32) -> Result<f32, String> {
    finite_in(flag, parse_flag(flag, s)?, min, max)
}

/// An integer flag within `[min, max]`.
pub fn int_in<T: PartialOrd + Display + Copy>(
    flag: &str,
    v: T,
    min: T,
    max: T,
) -> Result<T, String> {
    if v >= min && v <= max {
        Ok(v)
    } else {
        Err(format!("{flag}: {v} is out of range ({min} to {max})"))
    }
}

/// Checks a thread count: 1 to [`MAX_THREADS`], refused otherwise. A count
/// above [`THREADS_PER_CORE`] per core is clamped to that, and the note to
/// print is returned with it.
pub fn threads(flag: &str, n: usize, cores: usize) -> Result<(usize, Option<String>), String> {
    let n = int_in(flag, n, 1, MAX_THREADS)?;
    let cap = cores
        .max(1)
        .saturating_mul(THREADS_PER_CORE)
        .min(MAX_THREADS);
    if n > cap {
        let note = format!(
            "{flag} {n}: using {cap} threads ({THREADS_PER_CORE} per core on {cores} cores); \
             more would only add overhead"
        );
        Ok((cap, Some(note)))
    } else {
        Ok((n, None))
    }
}

/// The number of cores this process may use (1 if unknown).
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// A user-given text for a message: at most 60 characters and 160 bytes
/// once control and invisible characters are escaped (an escape such as
/// `\u{feff}` is 8 bytes, so 60 of them made a 500-byte message: found by
/// the `job_args` fuzzer), single-quoted.
pub fn shorten(s: &str) -> String {
    const MAX_CHARS: usize = 60;
    const MAX_BYTES: usize = 160;
    let mut out = String::from("'");
    for (i, c) in s.chars().enumerate() {
        if i == MAX_CHARS || out.len() >= MAX_BYTES {
            out.push('…');
            break;
        }
        push_visible(&mut out, c);
    }
    out.push('\'');
    out
}

/// Appends `c`, or its `\u{..}` escape if it would not show (control and
/// format characters: a byte-order mark, zero-width spaces, bidi overrides).
pub fn push_visible(out: &mut String, c: char) {
    if is_invisible(c) {
        out.extend(c.escape_unicode());
    } else {
        out.push(c);
    }
}

/// True for characters a terminal would not show, or would show as something
/// else: control characters (except tab) and Unicode format characters.
pub fn is_invisible(c: char) -> bool {
    (c.is_control() && c != '\t')
        || matches!(c,
            '\u{00AD}' | '\u{061C}' | '\u{180E}'
            | '\u{200B}'..='\u{200F}'
            | '\u{2028}'..='\u{202E}'
            | '\u{2060}'..='\u{206F}'
            | '\u{FEFF}'
            | '\u{FFF9}'..='\u{FFFB}')
}

/// A message made safe to print: every line at most [`MAX_MESSAGE_LINE`]
/// bytes (shortened in the middle), so no input can flood stderr.
pub fn bounded_message(msg: &str) -> String {
    let mut out = String::with_capacity(msg.len().min(64 * 1024));
    for (i, line) in msg.split('\n').enumerate() {
        if i > 0 {
            out.push('\n');
        }
        if line.len() <= MAX_MESSAGE_LINE {
            out.push_str(line);
            continue;
        }
        let half = MAX_MESSAGE_LINE / 2 - 16;
        let head = floor_boundary(line, half);
        let tail = ceil_boundary(line, line.len() - half);
        let cut = line.len() - head - (line.len() - tail);
        out.push_str(&line[..head]);
        out.push_str(&format!(" […{cut} bytes…] "));
        out.push_str(&line[tail..]);
    }
    out
}

fn floor_boundary(s: &str, mut i: usize) -> usize {
    while !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn ceil_boundary(s: &str, mut i: usize) -> usize {
    while !s.is_char_boundary(i) {
        i += 1;
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nan_and_infinity_are_refused() {
        for s in ["NaN", "nan", "inf", "-inf", "infinity"] {
            let e = parse_finite("-weight", s, 0.0, f32::MAX).unwrap_err();
            assert!(e.starts_with("-weight: "), "{e}");
        }
        assert_eq!(parse_finite("-weight", "0.01", 0.0, 1.0), Ok(0.01));
        assert!(parse_finite("-weight", "-1", 0.0, 1.0).is_err());
        assert!(parse_finite("-weight", "x", 0.0, 1.0)
            .unwrap_err()
            .contains("'x'"));
    }

    #[test]
    fn thread_counts_are_capped() {
        assert_eq!(threads("-threads", 2, 2), Ok((2, None)));
        let (n, note) = threads("-threads", 100, 2).unwrap();
        assert_eq!(n, 8);
        assert!(note.unwrap().contains("using 8 threads"));
        assert!(threads("-threads", 0, 2).is_err());
        let e = threads("--threads", 100_000, 2).unwrap_err();
        assert!(e.contains("--threads") && e.contains("1024"), "{e}");
        // Never more than MAX_THREADS, however many cores.
        assert_eq!(threads("t", 1024, 10_000).unwrap().0, 1024);
    }

    #[test]
    fn long_values_are_shortened_and_escaped() {
        let s = shorten(&"9".repeat(10_000));
        assert!(s.chars().count() < 70, "{s}");
        assert_eq!(shorten("a\u{feff}b\n"), "'a\\u{feff}b\\u{a}'");
        // Sixty invisible characters: bounded in bytes too.
        let s = shorten(&"\u{feff}\u{17}".repeat(30));
        assert!(s.len() <= 160 + 16, "{} bytes: {s}", s.len());
        assert!(s.ends_with("…'"), "{s}");
    }

    #[test]
    fn bounded_message_keeps_short_lines_and_cuts_long_ones() {
        assert_eq!(bounded_message("a\nb"), "a\nb");
        let long = format!("start{}end", "é".repeat(100_000));
        let b = bounded_message(&long);
        assert!(b.len() <= MAX_MESSAGE_LINE + 32, "{}", b.len());
        assert!(b.starts_with("start") && b.ends_with("end"));
    }

    #[test]
    fn memory_is_never_zero_and_inputs_scale_with_it() {
        assert!(available_memory() > 0);
        assert_eq!(max_input_bytes(20 << 20), 1 << 20);
    }
}
