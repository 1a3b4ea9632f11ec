//! Where reflection and refraction directions come from: the functions
//! live with the BSDFs (`crate::bsdf::optics`), which sit below the
//! integrators.

pub use crate::bsdf::optics::{reflect, refract};
