//! glint: a teaching-grade, production-fast CPU ray tracer.
pub mod accel;
pub mod animation;
#[cfg(feature = "cli")]
pub mod app;
pub mod bsdf;
pub mod format;
pub mod integrator;
pub mod job;
pub mod light;
pub mod limits;
pub mod material;
pub mod math;
pub mod output;
pub mod piece;
pub mod primitive;
pub mod query;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod shape;
pub mod stats;
#[cfg(test)]
pub(crate) mod testdata;
#[cfg(test)]
pub(crate) mod testutil;
pub mod viz;
pub mod world;
