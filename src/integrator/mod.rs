//! Integrators: what colour a ray brings back. [`Whitted`] is the classic ray
//! tree; [`RayObserver`] lets a caller watch every ray it spawns.

mod observer;
pub mod optics;
mod whitted;

pub use observer::{NoObserver, RayKind, RayObserver, RayRecorder, RecordedRay};
pub use whitted::Whitted;
