use glam::Vec3;

/// A ray `origin + t * dir` at an instant `time`. `dir` is not necessarily
/// unit length: rays carried into an object's space keep the world-space `t`
/// by keeping the scaled direction.
///
/// Why the time lives in the ray: motion blur needs every ray of one camera
/// sample (shadow, reflected, refracted) to see the scene at the same
/// instant, and moving shapes read it where they intersect; nothing between
/// the camera and the shape has to know about motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Start point.
    pub origin: Vec3,
    /// Direction (any non-zero length).
    pub dir: Vec3,
    /// Instant within the shutter interval at which the ray travels (0 for
    /// scenes without motion).
    pub time: f32,
}

impl Ray {
    /// Builds a ray from an origin and a direction, at time 0.
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self {
            origin,
            dir,
            time: 0.0,
        }
    }

    /// The same ray at instant `time`.
    #[inline]
    pub fn at_time(self, time: f32) -> Self {
        Self { time, ..self }
    }

    /// A ray spawned from this one (shadow, reflected, refracted): it lives
    /// at the same instant.
    #[inline]
    pub fn child(&self, origin: Vec3, dir: Vec3) -> Self {
        Self {
            origin,
            dir,
            time: self.time,
        }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

/// Moves a surface point off the surface along the geometric normal, to the side
/// the new ray leaves towards, so the new ray cannot re-hit the surface it starts on.
///
/// Why a scaled offset and not a fixed epsilon: f32 hit points carry an error
/// proportional to their magnitude (and to the magnitude of the ray's origin and
/// `t` that produced them), so a fixed epsilon is too small far from the origin
/// and too large near it. The constant covers the few ulps of error the
/// intersection routines accumulate (see the acne test in `tests/`).
#[inline]
pub fn offset_origin(p: Vec3, n: Vec3, dir: Vec3) -> Vec3 {
    let scale = p.abs().max_element().max(1.0);
    let eps = 1e-4 * scale;
    if n.dot(dir) >= 0.0 {
        p + n * eps
    } else {
        p - n * eps
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_goes_to_the_side_of_the_new_direction() {
        let p = Vec3::new(0.0, 0.0, 0.0);
        let n = Vec3::Y;
        assert!(offset_origin(p, n, Vec3::new(0.3, 1.0, 0.0)).y > 0.0);
        assert!(offset_origin(p, n, Vec3::new(0.3, -1.0, 0.0)).y < 0.0);
    }

    #[test]
    fn offset_scales_with_magnitude() {
        let n = Vec3::Y;
        let near = offset_origin(Vec3::ZERO, n, n).y;
        let far = offset_origin(Vec3::splat(1e4), n, n).y - 1e4;
        assert!(far > near * 100.0);
    }
}
