//! Where the tests find the course's data (`../shared`), and what they do
//! when it is absent. Compiled into the unit tests (`cfg(test)`) and included
//! by `tests/common` with `#[path]`, so both kinds of test share one rule:
//!
//! - the folder is `$GLINT_SHARED`, or `../shared` beside the crate root;
//! - a test that needs it and does not find it prints one line naming the
//!   path looked for and the variable, and returns (skips);
//! - with `GLINT_REQUIRE_SHARED=1` (as `.ci/run` sets), a missing folder is a
//!   failure instead, so CI never skips silently.

#![allow(dead_code)]

use std::io::Write;
use std::path::{Path, PathBuf};

/// The course data folder: `$GLINT_SHARED`, else `../shared` next to the crate.
pub fn shared_root() -> PathBuf {
    match std::env::var_os("GLINT_SHARED") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => {
            let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
            repo.parent().unwrap_or(repo).join("shared")
        }
    }
}

/// Whether a missing data folder must fail the test (`GLINT_REQUIRE_SHARED=1`).
pub fn shared_required() -> bool {
    std::env::var("GLINT_REQUIRE_SHARED").is_ok_and(|v| v == "1")
}

/// `sub` inside the course data folder, if it exists. If it does not, the
/// test named `test` is reported as skipped on stderr (written past the test
/// harness's capture, so a plain `cargo test` shows it) and `None` is returned;
/// under `GLINT_REQUIRE_SHARED=1` this panics instead.
pub fn shared(sub: &str, test: &str) -> Option<PathBuf> {
    let path = shared_root().join(sub);
    if path.exists() {
        return Some(path);
    }
    let msg = format!(
        "{test}: needs the course data at {} (set GLINT_SHARED to the folder holding scenes/ and reference/)",
        path.display()
    );
    if shared_required() {
        panic!("GLINT_REQUIRE_SHARED=1 but {msg}");
    }
    // `eprintln!` would be captured and hidden for a passing test.
    let _ = writeln!(std::io::stderr(), "skipped {msg}");
    None
}

/// The course's scene folder (`scenes/6837`), or skip the test.
pub fn scenes(test: &str) -> Option<PathBuf> {
    shared("scenes/6837", test)
}

/// The reference renders (`reference/6837`), or skip the test.
pub fn references(test: &str) -> Option<PathBuf> {
    shared("reference/6837", test)
}

/// Whether the CPU has AVX2 and FMA, the features of the AVX copies of the
/// hot loops. When it does not, the test named `test` is reported as
/// skipped on stderr (like a test missing the course data) and `false` is
/// returned, so a CPU without them does not pass the agreement tests
/// silently.
#[cfg(target_arch = "x86_64")]
pub fn avx2_fma(test: &str) -> bool {
    let ok =
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma");
    if !ok {
        let _ = writeln!(
            std::io::stderr(),
            "skipped {test}: the CPU lacks AVX2 or FMA, so there is no AVX path to compare"
        );
    }
    ok
}
