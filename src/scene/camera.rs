use crate::math::Vec3;
use glam::DVec3;

/// A camera as the scene file gives it. `direction` need not be unit length and
/// `up` need not be perpendicular to it; `crate::render::CameraModel` builds the
/// orthonormal frame. The centre is in double precision, as the file gave
/// it: a camera far from the origin keeps its exact place until
/// `crate::world` moves the scene into the camera-centred rendering space
/// (where it is the origin).
#[derive(Clone, Debug, PartialEq)]
pub enum Camera {
    /// Parallel projection: `size` is the extent of the image's longer side in
    /// world units.
    Orthographic {
        /// Centre of the image plane.
        center: DVec3,
        /// Viewing direction.
        direction: Vec3,
        /// Approximate up vector.
        up: Vec3,
        /// World-space extent of the longer image side.
        size: f32,
    },
    /// Pinhole projection: `angle_deg` is the full field of view across the
    /// image's longer side, in degrees.
    Perspective {
        /// Eye point.
        center: DVec3,
        /// Viewing direction.
        direction: Vec3,
        /// Approximate up vector.
        up: Vec3,
        /// Full field of view in degrees.
        angle_deg: f32,
    },
}
