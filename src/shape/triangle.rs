//! Triangles: the watertight ray–triangle test of Woop, Benthin and Wald
//! ("Watertight Ray/Triangle Intersection", JCGT 2013), shared by every path
//! that tests a triangle — the [`Triangle`] shape (brute force and the
//! textbook accelerators) and the fast BVH's four-at-once leaves — so that
//! they agree bit for bit.
//!
//! Why watertight: Möller–Trumbore computes each edge test from different
//! rounded quantities, so a ray through the edge two triangles share can slip
//! between them (a "crack" pixel). Here the ray is sheared so that it becomes
//! the +z axis, and the three edge functions are 2D cross products of the
//! same sheared vertices: the two triangles sharing an edge compute the same
//! edge value with opposite signs, and a ray exactly on the edge (value 0) is
//! resolved in double precision, so it hits at least one of them.

use crate::math::{Aabb, Ray, Vec3};

/// The per-ray constants of the watertight test: the axis permutation that
/// makes `|dir|` largest along z, and the shear that maps `dir` onto +z.
/// Computed once per ray by the fast BVH, once per test by [`Triangle`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayShear {
    /// Axes `[kx, ky, kz]`: `kz` is the dominant axis of the direction.
    pub k: [usize; 3],
    /// Shear constants `[dx/dz, dy/dz, 1/dz]` in the permuted axes.
    pub s: [f32; 3],
}

impl RayShear {
    /// The shear for direction `dir` (non-zero).
    #[inline]
    pub fn new(dir: Vec3) -> Self {
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Keep the winding: swapping two axes mirrors the projection.
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / dir[kz];
        Self {
            k: [kx, ky, kz],
            s: [dir[kx] * sz, dir[ky] * sz, sz],
        }
    }
}

/// The three edge functions `(u, v, w)` of the sheared vertices
/// `a = (ax, ay)`, `b`, `c`. When one is exactly zero (the ray passes through
/// an edge or a vertex in single precision) all three are recomputed in
/// double precision, which decides the sign consistently for both triangles
/// sharing the edge. The fast BVH calls this for the lanes it cannot decide.
#[inline]
pub fn edge_functions(ax: f32, ay: f32, bx: f32, by: f32, cx: f32, cy: f32) -> [f32; 3] {
    let u = cx * by - cy * bx;
    let v = ax * cy - ay * cx;
    let w = bx * ay - by * ax;
    if u == 0.0 || v == 0.0 || w == 0.0 {
        edge_functions_f64(ax, ay, bx, by, cx, cy)
    } else {
        [u, v, w]
    }
}

/// [`edge_functions`] in double precision (the products of f32 values are
/// exact in f64, so only the final subtraction rounds).
#[cold]
pub fn edge_functions_f64(ax: f32, ay: f32, bx: f32, by: f32, cx: f32, cy: f32) -> [f32; 3] {
    let (ax, ay, bx, by, cx, cy) = (
        f64::from(ax),
        f64::from(ay),
        f64::from(bx),
        f64::from(by),
        f64::from(cx),
        f64::from(cy),
    );
    [
        (cx * by - cy * bx) as f32,
        (ax * cy - ay * cx) as f32,
        (bx * ay - by * ax) as f32,
    ]
}

/// The watertight test of the ray `org + t·dir` (with `sh = RayShear::new(dir)`)
/// against the triangle `v`: the hit parameter in `(tmin, tmax)`, if any.
/// Both sides are hit (no back-face culling).
///
/// The arithmetic is written out step by step, in the order the four-lane
/// version in `accel::bvh4` repeats lane by lane: Rust never fuses or
/// reorders float operations, so the two give bit-identical results.
#[inline]
pub fn intersect_watertight(
    org: Vec3,
    sh: &RayShear,
    v: &[Vec3; 3],
    tmin: f32,
    tmax: f32,
) -> Option<f32> {
    let [kx, ky, kz] = sh.k;
    let [sx, sy, sz] = sh.s;
    let a = v[0] - org;
    let b = v[1] - org;
    let c = v[2] - org;
    let ax = a[kx] - sx * a[kz];
    let ay = a[ky] - sy * a[kz];
    let bx = b[kx] - sx * b[kz];
    let by = b[ky] - sy * b[kz];
    let cx = c[kx] - sx * c[kz];
    let cy = c[ky] - sy * c[kz];
    let [u, v_, w] = edge_functions(ax, ay, bx, by, cx, cy);
    if (u < 0.0 || v_ < 0.0 || w < 0.0) && (u > 0.0 || v_ > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v_ + w;
    if det == 0.0 {
        return None;
    }
    let az = sz * a[kz];
    let bz = sz * b[kz];
    let cz = sz * c[kz];
    let t = (u * az + v_ * bz + w * cz) / det;
    (t > tmin && t < tmax).then_some(t)
}

/// Whether a triangle has no area in single precision (its normal is zero):
/// such a triangle is never hit, so no NaN normal reaches shading.
#[inline]
pub fn is_degenerate(v0: Vec3, v1: Vec3, v2: Vec3) -> bool {
    (v1 - v0).cross(v2 - v0).normalize_or_zero() == Vec3::ZERO
}

/// A triangle: its vertices and its unit normal (needed once per hit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    /// The vertices, counter-clockwise seen from the front.
    pub v: [Vec3; 3],
    /// Unit normal of the counter-clockwise front; zero for a degenerate triangle.
    pub normal: Vec3,
}

impl Triangle {
    /// A triangle from its vertices.
    pub fn new(v0: Vec3, v1: Vec3, v2: Vec3) -> Self {
        Self {
            v: [v0, v1, v2],
            normal: (v1 - v0).cross(v2 - v0).normalize_or_zero(),
        }
    }

    /// The three vertices.
    pub fn vertices(&self) -> [Vec3; 3] {
        self.v
    }

    /// The watertight test ([`intersect_watertight`]). Degenerate triangles
    /// (zero normal) never report a hit.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<f32> {
        if self.normal == Vec3::ZERO {
            return None;
        }
        intersect_watertight(ray.origin, &RayShear::new(ray.dir), &self.v, tmin, tmax)
    }

    /// Bounding box of the three vertices.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.vertices())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> Triangle {
        Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)
    }

    #[test]
    fn hit_inside() {
        let r = Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z);
        assert!((tri().intersect(&r, 0.0, f32::INFINITY).unwrap() - 1.0).abs() < 1e-6);
        assert_eq!(tri().normal, Vec3::Z);
    }

    #[test]
    fn hit_from_behind_too() {
        let r = Ray::new(Vec3::new(0.25, 0.25, -1.0), Vec3::Z);
        assert!(tri().intersect(&r, 0.0, f32::INFINITY).is_some());
    }

    #[test]
    fn miss_outside_and_behind_origin() {
        let r = Ray::new(Vec3::new(0.75, 0.75, 1.0), Vec3::NEG_Z);
        assert!(tri().intersect(&r, 0.0, f32::INFINITY).is_none());
        let r = Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::Z);
        assert!(tri().intersect(&r, 0.0, f32::INFINITY).is_none());
    }

    #[test]
    fn edge_on_ray_misses() {
        let r = Ray::new(Vec3::new(-1.0, 0.25, 0.0), Vec3::X);
        assert!(tri().intersect(&r, 0.0, f32::INFINITY).is_none());
    }

    #[test]
    fn degenerate_never_hits() {
        let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::X * 2.0);
        assert_eq!(t.normal, Vec3::ZERO);
        assert!(is_degenerate(t.v[0], t.v[1], t.v[2]));
        let r = Ray::new(Vec3::new(0.5, 0.0, 1.0), Vec3::NEG_Z);
        assert!(t.intersect(&r, 0.0, f32::INFINITY).is_none());
    }

    /// The point of the watertight test: rays through the shared edge (and
    /// the shared vertices) of two triangles hit at least one of them, for
    /// edges at awkward, non-representable positions.
    #[test]
    fn shared_edges_have_no_cracks() {
        let mut misses = 0;
        for i in 0..2000 {
            let f = i as f32 / 2000.0;
            // Quad split along the diagonal from p0 to p2.
            let p0 = Vec3::new(-0.3 + 0.1 * f, -0.7, 0.37);
            let p1 = Vec3::new(0.9, -0.6 + 0.2 * f, 0.41);
            let p2 = Vec3::new(0.8, 0.7, 0.29 + 0.1 * f);
            let p3 = Vec3::new(-0.4, 0.6, 0.33);
            let t1 = Triangle::new(p0, p1, p2);
            let t2 = Triangle::new(p0, p2, p3);
            // A point on the diagonal (rounded: exactly on it or beside it).
            let s = (i % 97) as f32 / 97.0;
            let target = p0 + (p2 - p0) * s;
            let origin = Vec3::new(0.1 * f, -0.2, -3.0);
            let r = Ray::new(origin, target - origin);
            let hit = t1.intersect(&r, 0.0, f32::INFINITY).is_some()
                || t2.intersect(&r, 0.0, f32::INFINITY).is_some();
            misses += usize::from(!hit);
        }
        assert_eq!(misses, 0);
    }

    #[test]
    fn shear_makes_the_direction_the_z_axis() {
        let d = Vec3::new(0.3, -2.0, 0.5);
        let sh = RayShear::new(d);
        assert_eq!(sh.k[2], 1);
        // The sheared direction has zero x and y.
        let [kx, ky, kz] = sh.k;
        assert_eq!(d[kx] - sh.s[0] * d[kz], 0.0);
        assert_eq!(d[ky] - sh.s[1] * d[kz], 0.0);
    }
}
