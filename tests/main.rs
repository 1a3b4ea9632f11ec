//! glint's integration tests, built as one test binary.
//!
//! Each file beside this one is a module of the binary (`physics.rs` is
//! `physics::`); select one with `cargo test --test suite physics::`.
//! One binary instead of one per file: after a change to the library, cargo
//! compiles and links the test code once rather than thirty times (the cost
//! that dominated a mutation run's build), and `cargo test` runs all of the
//! integration tests on every core at once instead of file by file.

mod common;

mod accel_agree;
mod accel_edges;
mod animation;
mod assets;
mod cli;
mod conventions;
mod distribution;
mod formats;
mod fuzz_corpus;
mod hdr_output;
mod hostile;
mod layers;
mod malformed;
mod moved_scenes;
mod numerics;
mod path_tracing;
mod physics;
mod pieces;
mod raytree_cli;
mod reference_images;
mod reintersect;
mod sampling;
mod sampling_reference;
mod scene_props;
mod serve;
mod textures;
mod toy_integrator;
mod viz_cost;
mod viz_grid;
mod viz_traversal;
mod watertight;
mod whitted_tree;
