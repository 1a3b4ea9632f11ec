//! glTF and GLB documents: any bytes, loaded, built and traced, must never
//! panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../exercise.rs"]
mod exercise;

fuzz_target!(|data: &[u8]| exercise::gltf(data));
