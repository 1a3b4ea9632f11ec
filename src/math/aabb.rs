use super::Ray;
use glam::{Mat4, Vec3};

/// An axis-aligned bounding box. The empty box has `min = +inf`, `max = -inf`
/// so that `union` with it is the identity.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Vec3,
    /// Largest corner.
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    /// A box from two corners.
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// The smallest box holding all `points`.
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.grow(p))
    }

    /// True when the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// True when every coordinate is finite (planes have unbounded boxes).
    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    /// The box grown to hold `p`.
    pub fn grow(&self, p: Vec3) -> Self {
        Self::new(self.min.min(p), self.max.max(p))
    }

    /// The smallest box holding both.
    pub fn union(&self, o: &Aabb) -> Self {
        Self::new(self.min.min(o.min), self.max.max(o.max))
    }

    /// Box extent per axis.
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }

    /// Centre point.
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Surface area (0 for an empty box), used by the SAH.
    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// The box of the 8 transformed corners: a conservative bound of the
    /// transformed contents.
    pub fn transformed(&self, m: &Mat4) -> Self {
        if self.is_empty() {
            return *self;
        }
        let mut out = Self::EMPTY;
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            );
            out = out.grow(m.transform_point3(c));
        }
        out
    }

    /// Slab test: the parameter interval `[t0, t1]` inside the box clipped to
    /// `[tmin, tmax]`, or `None`. `inv_dir` is `1 / ray.dir` (infinities allowed:
    /// IEEE arithmetic makes axis-parallel rays work without special cases, and
    /// the `max`/`min` order below discards the NaN of `0 * inf`).
    #[inline]
    pub fn hit(&self, ray: &Ray, inv_dir: Vec3, tmin: f32, tmax: f32) -> Option<(f32, f32)> {
        let t_a = (self.min - ray.origin) * inv_dir;
        let t_b = (self.max - ray.origin) * inv_dir;
        let t_near = t_a.min(t_b);
        let t_far = t_a.max(t_b);
        let t0 = tmin.max(t_near.x).max(t_near.y).max(t_near.z);
        let t1 = tmax.min(t_far.x).min(t_far.y).min(t_far.z);
        (t0 <= t1).then_some((t0, t1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slab_hit_and_miss() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let r = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
        let (t0, t1) = b.hit(&r, r.dir.recip(), 0.0, f32::INFINITY).unwrap();
        assert!((t0 - 4.0).abs() < 1e-6 && (t1 - 6.0).abs() < 1e-6);
        let miss = Ray::new(Vec3::new(2.0, 0.0, -5.0), Vec3::Z);
        assert!(b.hit(&miss, miss.dir.recip(), 0.0, f32::INFINITY).is_none());
    }

    #[test]
    fn transformed_box_holds_rotated_corners() {
        let b = Aabb::new(Vec3::splat(-1.0), Vec3::splat(1.0));
        let m = Mat4::from_rotation_z(std::f32::consts::FRAC_PI_4);
        let t = b.transformed(&m);
        assert!((t.max.x - 2f32.sqrt()).abs() < 1e-5);
    }

    #[test]
    fn empty_is_union_identity() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        assert_eq!(Aabb::EMPTY.union(&b), b);
        assert!(Aabb::EMPTY.is_empty());
        assert_eq!(Aabb::EMPTY.surface_area(), 0.0);
    }
}
