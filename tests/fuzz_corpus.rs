//! Replays the committed fuzzing corpora (`fuzz/corpus/<target>/`) and the
//! inputs that once crashed a fuzz target (`fuzz/regressions/<target>/`)
//! through exactly the code the fuzz targets run (`fuzz/exercise.rs`), so
//! plain `cargo test` keeps every input the fuzzers found from panicking
//! again, without nightly flags or libFuzzer.

#[path = "../fuzz/exercise.rs"]
mod exercise;

use std::path::Path;

/// The files of `fuzz/<kind>/<target>/` (none if the folder is absent).
fn inputs(kind: &str, target: &str) -> Vec<(String, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz")
        .join(kind)
        .join(target);
    let Ok(entries) = std::fs::read_dir(&dir) else {
        return Vec::new();
    };
    let mut out: Vec<_> = entries
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect();
    out.sort();
    out
}

/// Runs `f` on every input, reporting each one that panics by name.
fn replay(target: &str, f: fn(&[u8])) -> usize {
    let mut all = inputs("corpus", target);
    all.extend(inputs("regressions", target));
    let failed: Vec<String> = all
        .iter()
        .filter(|(_, data)| std::panic::catch_unwind(|| f(data)).is_err())
        .map(|(name, _)| name.clone())
        .collect();
    assert!(failed.is_empty(), "{target}: panicked on {failed:?}");
    all.len()
}

#[test]
fn scene_parser_corpus_never_panics() {
    let n = replay("scene_parser", exercise::scene);
    assert!(n >= 100, "only {n} scene inputs");
}

#[test]
fn obj_loader_corpus_never_panics() {
    let n = replay("obj_loader", exercise::obj);
    assert!(n >= 10, "only {n} OBJ inputs");
}

#[test]
fn job_args_corpus_never_panics() {
    let n = replay("job_args", exercise::job_args);
    assert!(n >= 10, "only {n} command lines");
}

#[test]
fn ply_loader_corpus_never_panics() {
    let n = replay("ply_loader", exercise::ply);
    assert!(n >= 10, "only {n} PLY inputs");
}

#[test]
fn gltf_loader_corpus_never_panics() {
    let n = replay("gltf_loader", exercise::gltf);
    assert!(n >= 10, "only {n} glTF inputs");
}
