//! Seeing the machinery: pictures and 3-D files of what the renderer did.
//!
//! Every view records the renderer's own work through the interfaces the
//! renderer uses (the integrator's [`RayObserver`](crate::integrator::RayObserver),
//! the accelerators' traversal iterators), never a separate copy of it.
//!
//! - [`raytree`]: every ray one pixel spawned, as JSON, OBJ/PLY line
//!   segments, or drawn over the rendered image.
//! - [`traversal`]: the cells, leaves or BVH boxes one ray's search looked at.
//! - [`structure`]: a BVH's or octree's boxes at one depth.
//! - [`grid`]: the uniform grid's occupied cells as boxes (assignment 5).
//! - [`cost`]: per-pixel intersection tests and nodes visited as heat maps.
//! - [`draw`]: lines, marks and labels on an RGB image.

pub mod cost;
pub mod draw;
pub mod grid;
pub mod raytree;
pub mod structure;
pub mod traversal;
