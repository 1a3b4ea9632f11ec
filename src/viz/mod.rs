//! Seeing the machinery: pictures and 3-D files of what the renderer did.
//!
//! Every view records the renderer's own work through the interfaces the
//! renderer uses (the integrator's [`RayObserver`](crate::integrator::RayObserver),
//! the accelerators' traversal iterators), never a separate copy of it.
//!
//! - [`raytree`]: every ray one pixel spawned, as JSON, OBJ/PLY line
//!   segments, or drawn over the rendered image.
//! - [`draw`]: lines, boxes and scale bars on an RGB image.

pub mod draw;
pub mod raytree;
