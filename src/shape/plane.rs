use crate::math::{gamma, Aabb, Ray, SurfacePoint, Vec3};
use glam::DMat4;

/// The plane `normal · p = offset`, stored with a unit normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    /// Unit normal.
    pub normal: Vec3,
    /// Signed distance of the plane from the origin along `normal`.
    pub offset: f32,
}

impl Plane {
    /// The plane `n · p = d` for any non-zero `n` (the file's convention).
    /// Returns `None` for a zero normal.
    pub fn new(n: Vec3, d: f32) -> Option<Self> {
        let len = n.length();
        (len > 0.0 && len.is_finite()).then(|| Self {
            normal: n / len,
            offset: d / len,
        })
    }

    /// The plane carried through an invertible affine matrix: the normal by the
    /// inverse transpose, a point of the plane by the matrix itself. In f64,
    /// so a plane moved far away and back (the rendering space) keeps its
    /// offset to f32 precision.
    pub fn transformed(&self, m: &DMat4) -> Option<Self> {
        Self::carried(self.normal, self.offset as f64, m)
    }

    /// The plane `n · p = d` of a scene description, `d` in double
    /// precision as the file gave it, carried through `m` as
    /// [`Self::transformed`] does and rounded once: a plane far from the
    /// origin keeps its place in rendering space. `None` for a zero normal
    /// or a singular `m`. The normal is made unit in f32 as [`Self::new`]
    /// makes it.
    pub fn from_f64(n: Vec3, d: f64, m: &DMat4) -> Option<Self> {
        let len = n.length();
        if !(len > 0.0 && len.is_finite()) {
            return None;
        }
        Self::carried(n / len, d / len as f64, m)
    }

    /// The plane `normal · p = offset` (`normal` unit) carried through `m`.
    fn carried(normal: Vec3, offset: f64, m: &DMat4) -> Option<Self> {
        let p = m.transform_point3(normal.as_dvec3() * offset);
        let n = m.inverse().transpose().transform_vector3(normal.as_dvec3());
        let len = n.length();
        let n = n / len;
        let plane = Self {
            normal: n.as_vec3(),
            offset: n.dot(p) as f32,
        };
        (len > 0.0 && plane.normal.is_finite() && plane.offset.is_finite()).then_some(plane)
    }

    /// The hit at parameter `t` of `ray`: `ray.at(t)` projected onto the
    /// plane (the projection removes the error `t` carries along the ray).
    /// See `project_onto_plane` (below) for the error bound.
    pub fn surface(&self, ray: &Ray, t: f32) -> SurfacePoint {
        project_onto_plane(ray.at(t), self.normal, self.offset)
    }

    /// Hit parameter in `(tmin, tmax)`; rays parallel to the plane miss.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<f32> {
        let denom = self.normal.dot(ray.dir);
        if denom == 0.0 {
            return None;
        }
        let t = (self.offset - self.normal.dot(ray.origin)) / denom;
        (t > tmin && t < tmax).then_some(t)
    }

    /// [`intersect`](Self::intersect) with the [`surface`](Self::surface)
    /// point of the hit.
    #[inline]
    pub fn hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<(f32, SurfacePoint)> {
        let t = self.intersect(ray, tmin, tmax)?;
        Some((t, self.surface(ray, t)))
    }

    /// Planes are unbounded, so they stay out of the acceleration structures
    /// and are tested on every ray. A plane whose normal lies exactly along an
    /// axis is still bounded along that one axis (its box is a slab of zero
    /// thickness), which is all a box can say about it.
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::new(Vec3::NEG_INFINITY, Vec3::INFINITY);
        let n = self.normal;
        for axis in 0..3 {
            let others = (0..3).filter(|&a| a != axis).all(|a| n[a] == 0.0);
            if others && n[axis] != 0.0 {
                let at = self.offset / n[axis];
                b.min[axis] = at;
                b.max[axis] = at;
            }
        }
        b
    }
}

/// `p` projected onto the plane `n·x = d` (unit `n`), with its error bound.
///
/// The projection is `q = p − s·n` with `s = n·p − d`. Its error has two
/// parts: the rounding of each coordinate of `q` (a product and a
/// difference: `γ(2)·(|q| + |s·n|)`, taken as `γ(3)·(|q| + 2|s|·|n|)` for
/// slack), and how far the exactly computed `p − s·n` can still be from the
/// plane, along `n`: the error of `s` (a 3-term dot product and a
/// difference: `γ(4)·(Σ|n_i·p_i| + |d|)`, taken as `γ(5)`) plus `|s|·|1 − n·n|`
/// (`γ(3)·|s|` for an f32-normalised `n`, taken as `γ(4)`). The second part
/// is spread over the axes as `δ·|n|`, so that `|n|·error ≥ δ`.
pub fn project_onto_plane(p: Vec3, n: Vec3, d: f32) -> SurfacePoint {
    let s = n.dot(p) - d;
    let q = p - s * n;
    let along = gamma(5) * (n.abs().dot(p.abs()) + d.abs()) + gamma(4) * s.abs();
    SurfacePoint {
        p: q,
        error: gamma(3) * (q.abs() + 2.0 * s.abs() * n.abs()) + along * n.abs(),
        n,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::testing::{check_error_box, Lcg};

    #[test]
    fn offset_is_in_units_of_the_given_normal() {
        let p = Plane::new(Vec3::new(0.0, 2.0, 0.0), 2.0).unwrap();
        let r = Ray::new(Vec3::new(0.0, 5.0, 0.0), Vec3::NEG_Y);
        assert!((p.intersect(&r, 0.0, f32::INFINITY).unwrap() - 4.0).abs() < 1e-6);
    }

    #[test]
    fn parallel_and_behind_miss() {
        let p = Plane::new(Vec3::Y, 0.0).unwrap();
        let par = Ray::new(Vec3::Y, Vec3::X);
        assert!(p.intersect(&par, 0.0, f32::INFINITY).is_none());
        let away = Ray::new(Vec3::Y, Vec3::Y);
        assert!(p.intersect(&away, 0.0, f32::INFINITY).is_none());
    }

    #[test]
    fn hit_from_below_has_same_normal() {
        let p = Plane::new(Vec3::Y, 1.0).unwrap();
        let r = Ray::new(Vec3::ZERO, Vec3::Y);
        assert!((p.intersect(&r, 0.0, f32::INFINITY).unwrap() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn axis_plane_is_bounded_along_its_normal_only() {
        let b = Plane::new(Vec3::new(0.0, -2.0, 0.0), 3.0).unwrap().bounds();
        assert_eq!((b.min.y, b.max.y), (-1.5, -1.5));
        assert!(b.min.x.is_infinite() && b.max.z.is_infinite());
        assert!(!b.is_finite());
        let tilted = Plane::new(Vec3::new(0.0, 1.0, 1.0), 1.0).unwrap().bounds();
        assert!(tilted.min.y.is_infinite() && tilted.min.z.is_infinite());
    }

    #[test]
    fn zero_normal_is_rejected() {
        assert!(Plane::new(Vec3::ZERO, 1.0).is_none());
    }

    #[test]
    fn transformed_plane() {
        let p = Plane::new(Vec3::Y, 1.0).unwrap();
        let m = DMat4::from_translation(glam::DVec3::new(0.0, 2.0, 0.0))
            * DMat4::from_rotation_z(std::f64::consts::FRAC_PI_2);
        let q = p.transformed(&m).unwrap();
        // y = 1 rotated by 90° about z becomes x = -1, then moved up (no effect on x).
        assert!((q.normal - Vec3::NEG_X).length() < 1e-6);
        assert!((q.offset - 1.0).abs() < 1e-6);
    }

    /// A transform can leave the normal finite and push the offset past
    /// f32's range (`n·p` is computed in f64 and only then narrowed): that
    /// plane is refused too, not kept with an infinite offset that makes
    /// every hit parameter infinite or NaN.
    #[test]
    fn a_transform_that_overflows_the_offset_is_refused() {
        let p = Plane::new(Vec3::Y, 1.0).unwrap();
        for (shift, kept) in [(1e38, true), (1e39, false), (-1e39, false), (1e300, false)] {
            let m = DMat4::from_translation(glam::DVec3::new(0.0, shift, 0.0));
            let q = p.transformed(&m);
            assert_eq!(q.is_some(), kept, "shift {shift}: {q:?}");
            if let Some(q) = q {
                assert_eq!(q.normal, Vec3::Y);
                assert_eq!(q.offset, (1.0 + shift) as f32);
            }
        }
    }

    #[test]
    fn projected_hit_is_on_the_plane_within_its_error() {
        let p = Plane::new(Vec3::new(0.3, 1.0, -0.2), 7.5e3).unwrap();
        let r = Ray::new(Vec3::new(-4e4, 2e3, 1e4), Vec3::new(0.9, 0.05, -0.3));
        let t = p.intersect(&r, 0.0, f32::INFINITY).unwrap();
        let sp = p.surface(&r, t);
        let n = p.normal.as_dvec3();
        let dist = n.dot(sp.p.as_dvec3()) - p.offset as f64;
        assert!(
            dist.abs() <= sp.error.as_dvec3().dot(n.abs()),
            "{dist} vs {}",
            sp.error
        );
    }

    /// The range is open at both ends: a hit exactly at `tmin` or `tmax` is
    /// not reported.
    #[test]
    fn hits_at_the_ends_of_the_range_are_excluded() {
        let p = Plane::new(Vec3::Y, 1.0).unwrap();
        let r = Ray::new(Vec3::new(0.0, 5.0, 0.0), Vec3::NEG_Y);
        assert_eq!(p.intersect(&r, 0.0, 4.0), None);
        assert_eq!(p.intersect(&r, 4.0, 10.0), None);
        assert_eq!(p.intersect(&r, 3.5, 4.5), Some(4.0));
    }

    /// `project_onto_plane`'s box holds the exact projection (f64) along the
    /// normal and is within a few roundings of the coordinates' size, for
    /// planes 10⁻³..10⁵ from the origin and points on them or up to 10⁵ off
    /// them (a triangle's fallback, a disk light's samples).
    #[test]
    fn projections_lie_in_tight_error_boxes() {
        let mut g = Lcg(3);
        for i in 0..20_000 {
            let far = 10f32.powi(i % 9 - 3);
            let Some(plane) = Plane::new(g.vec(2.0), g.next() * far) else {
                continue;
            };
            let off = if i % 3 == 0 {
                0.0
            } else {
                10f32.powi(i % 11 - 5)
            };
            let p = g.vec(2.0 * far) + g.vec(2.0) * off;
            let (n, d) = (plane.normal, plane.offset);
            let sp = project_onto_plane(p, n, d);
            // The exact projection onto {x : n·x = d} for the stored (f32,
            // not exactly unit) n.
            let (nd, pd) = (n.as_dvec3(), p.as_dvec3());
            let truth = pd - nd * ((nd.dot(pd) - d as f64) / nd.length_squared());
            let limit = gamma(16) * (sp.p.abs() + Vec3::splat(p.abs().element_sum() + d.abs()));
            let what = format!("{plane:?} from {p}");
            check_error_box(sp, truth, Some(nd.normalize()), limit, &what);
        }
    }
}
