//! glint: a teaching-grade, production-fast CPU ray tracer.
pub mod math;
pub mod scene;
