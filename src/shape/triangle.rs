//! Triangles and the watertight ray–triangle test (Woop, Benthin and Wald,
//! "Watertight Ray/Triangle Intersection", JCGT 2013; as in pbrt-v4).
//!
//! Why watertight: Möller–Trumbore computes each triangle's barycentrics from
//! its own edge vectors, so two triangles sharing an edge round differently
//! and a ray through the edge can slip between them (a pixel-sized hole in a
//! mesh). The watertight test moves the ray to the origin, permutes and
//! shears space so the ray runs along +z, and decides inside/outside by the
//! signs of three 2-D edge functions of the *transformed vertices*. A shared
//! vertex transforms to the same value in both triangles, and the edge
//! function of a shared edge is computed exactly (products of f32 values are
//! exact in f64, and an f64 difference has the exact sign), with opposite
//! signs from its two sides: a ray through an edge or a vertex hits at least
//! one of the triangles that share it.
//!
//! [`intersect_triangle`] is a free function on three vertices and a
//! [`WatertightRay`] (the per-ray permutation and shear), so an accelerator
//! that stores vertices its own way calls the identical arithmetic.

use super::plane::project_onto_plane;
use crate::math::{gamma, Aabb, Ray, SurfacePoint, Vec3};

/// The per-ray data of the watertight test: the ray's origin, the axis
/// permutation that makes the direction's largest component `z`, and the
/// shear that maps the direction onto `+z`. Compute it once per ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WatertightRay {
    pub(super) origin: Vec3,
    /// Permuted axes: `kz` is the direction's dominant axis.
    pub(super) k: [usize; 3],
    /// Shear `(−d_x/d_z, −d_y/d_z, 1/d_z)` in permuted axes.
    pub(super) shear: Vec3,
}

impl WatertightRay {
    /// The permutation and shear of `ray` (any non-zero direction).
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        // The dominant axis without branches: `x` where it is at least
        // both others, else `y` where it is at least `z`, else `z` (a NaN
        // component fails its comparisons, as the `if` chain this replaces
        // did). Traversal computes this once per ray, and the axis varies
        // from ray to ray: the branch it compiled to went each way about
        // half the time on incoherent rays (callgrind, bunny40k), which a
        // predictor cannot follow.
        let a = ray.dir.abs();
        let x_wins = (a.x >= a.y) & (a.x >= a.z);
        let y_wins = a.y >= a.z;
        let kz = usize::from(!x_wins) * (1 + usize::from(!y_wins));
        // The next two axes in cyclic order, by table (`(kz + 1) % 3` is a
        // division by a constant; the table is one load).
        const NEXT: [usize; 3] = [1, 2, 0];
        let kx = NEXT[kz];
        let ky = NEXT[kx];
        let d = ray.dir.to_array();
        let sz = 1.0 / d[kz];
        Self {
            origin: ray.origin,
            k: [kx, ky, kz],
            shear: Vec3::new(-d[kx] * sz, -d[ky] * sz, sz),
        }
    }

    /// Vertex `p` in ray space: relative to the origin, permuted and sheared
    /// in x and y (z is scaled later, only if the edge test passes).
    #[inline]
    fn transform(&self, p: Vec3) -> Vec3 {
        let q = p - self.origin;
        let [kx, ky, kz] = self.k;
        let z = q[kz];
        Vec3::new(q[kx] + self.shear.x * z, q[ky] + self.shear.y * z, z)
    }
}

/// A ray–triangle hit: the parameter and the barycentric weights of the three
/// vertices (`point = b[0]·p0 + b[1]·p1 + b[2]·p2`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Ray parameter.
    pub t: f32,
    /// Barycentric coordinates, each in `[0, 1]`, summing to 1 up to rounding.
    pub b: [f32; 3],
}

/// The watertight test of the ray behind `r` against triangle `(p0, p1, p2)`,
/// either side, accepting `tmin < t < tmax`. When `tmin ≥ 0`, a hit whose `t`
/// is not conservatively positive (within its own rounding error of 0, pbrt's
/// `deltaT`) is rejected too: it cannot be told apart from the ray's origin.
///
/// A degenerate triangle (collinear vertices) may report a hit with
/// meaningless barycentrics; callers skip degenerate triangles (see
/// [`Triangle::is_degenerate`]), which is cheaper than re-checking per ray.
#[inline]
pub fn intersect_triangle(
    r: &WatertightRay,
    p0: Vec3,
    p1: Vec3,
    p2: Vec3,
    tmin: f32,
    tmax: f32,
) -> Option<TriangleHit> {
    let (a, b, c) = (r.transform(p0), r.transform(p1), r.transform(p2));
    // Edge functions in f64: each product of two f32 values is exact there,
    // so every sign is exact and a shared edge gets exactly opposite values
    // from its two triangles (no fallback path needed for ties).
    let edge = |p: Vec3, q: Vec3| p.x as f64 * q.y as f64 - p.y as f64 * q.x as f64;
    let e0 = edge(b, c);
    let e1 = edge(c, a);
    let e2 = edge(a, b);
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return None; // the ray lies in the triangle's plane
    }
    let sz = r.shear.z;
    let (az, bz, cz) = (a.z * sz, b.z * sz, c.z * sz);
    let t_scaled = e0 * az as f64 + e1 * bz as f64 + e2 * cz as f64;
    let inv_det = 1.0 / det;
    let t = (t_scaled * inv_det) as f32;
    if !(t > tmin && t < tmax) {
        return None;
    }
    if tmin >= 0.0 {
        // pbrt-v4's bound on the error of t, from the errors of the
        // transformed coordinates (conservative here: our edge functions
        // are more accurate than the f32 ones it assumes). One change: the
        // x and y errors use the *unscaled* z (the shear adds `s·z` with
        // `|s| ≤ 1`), where pbrt uses z scaled by `1/d_z`; with the short
        // directions of rays carried into a large transform's object space
        // (`|d| ~ 1e-3`), pbrt's form overstates deltaT a thousandfold and
        // rejects real hits.
        let max_z = az.abs().max(bz.abs()).max(cz.abs());
        let max_z_unscaled = a.z.abs().max(b.z.abs()).max(c.z.abs());
        let max_x = a.x.abs().max(b.x.abs()).max(c.x.abs());
        let max_y = a.y.abs().max(b.y.abs()).max(c.y.abs());
        let delta_z = gamma(3) * max_z;
        let delta_x = gamma(5) * (max_x + max_z_unscaled);
        let delta_y = gamma(5) * (max_y + max_z_unscaled);
        let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
        let max_e = e0.abs().max(e1.abs()).max(e2.abs()) as f32;
        let delta_t = 3.0
            * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e)
            * (inv_det.abs() as f32);
        if t <= delta_t {
            return None;
        }
    }
    Some(TriangleHit {
        t,
        b: [
            (e0 * inv_det) as f32,
            (e1 * inv_det) as f32,
            (e2 * inv_det) as f32,
        ],
    })
}

/// Whether `Triangle::new(v0, v1, v2)` is degenerate, without its
/// normalisation (a square root and a division per triangle, which a mesh
/// build pays for every triangle).
///
/// Why the same answer: `Triangle::new` normalises the f64 cross product
/// `n` of the edges and calls the triangle degenerate when the result is
/// zero or not finite. If a vertex is not finite, an edge has a non-finite
/// component, which enters two components of `n` as a product with a
/// finite, infinite or NaN factor (`∞·0` is NaN): `n` is not finite, its
/// length is infinite or NaN, and `normalize_or_zero` gives zero. If the
/// vertices are finite, edges are at most `2¹²⁹` and `n`'s components at
/// most `2²⁵⁹` (finite); a non-zero component is at least `2⁻³⁵⁰` (products
/// of f64 differences of f32 values, then one rounded difference), so the
/// squared length lies in `[2⁻⁷⁰⁰, 2⁵²⁰]`, its root's reciprocal is finite
/// and positive, and the unit result has a component of at least `1/√3`,
/// non-zero and finite in f32. So: degenerate exactly when `n` is zero or
/// not finite.
#[inline]
pub fn is_degenerate_triangle(v0: Vec3, v1: Vec3, v2: Vec3) -> bool {
    let (a, b, c) = (v0.as_dvec3(), v1.as_dvec3(), v2.as_dvec3());
    let n = (b - a).cross(c - a);
    !(n.is_finite() && n != glam::DVec3::ZERO)
}

/// A triangle: its three vertices as given (exactly, so that triangles
/// sharing a vertex share its bits) and its unit normal.
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
        // The normal in f64: an f32 cross product of tiny or huge edges
        // underflows or overflows before it is normalised.
        let (a, b, c) = (v0.as_dvec3(), v1.as_dvec3(), v2.as_dvec3());
        let n = (b - a).cross(c - a).normalize_or_zero().as_vec3();
        Self {
            v: [v0, v1, v2],
            normal: if n.is_finite() { n } else { Vec3::ZERO },
        }
    }

    /// The three vertices.
    pub fn vertices(&self) -> [Vec3; 3] {
        self.v
    }

    /// Whether the vertices are collinear (no area, no normal): such a
    /// triangle is never hit.
    #[inline]
    pub fn is_degenerate(&self) -> bool {
        self.normal == Vec3::ZERO
    }

    /// The watertight test ([`intersect_triangle`]), with the barycentrics.
    #[inline]
    pub fn hit(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<TriangleHit> {
        if self.is_degenerate() {
            return None;
        }
        let [p0, p1, p2] = self.v;
        intersect_triangle(&WatertightRay::new(ray), p0, p1, p2, tmin, tmax)
    }

    /// Hit parameter in `(tmin, tmax)`; degenerate triangles never report a
    /// hit, so no NaN normal can reach shading.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<f32> {
        self.hit(ray, tmin, tmax).map(|h| h.t)
    }

    /// The hit at parameter `t` of `ray`, from barycentric interpolation
    /// (pbrt-v4): `p = Σ b_i·p_i` lies in the triangle's plane up to the
    /// rounding of three products and two sums and of the barycentrics
    /// themselves, bounded by `γ(7)·Σ|b_i·p_i|`. The barycentrics come from
    /// re-running the identical test (it is deterministic), once per closest
    /// hit rather than for every candidate.
    pub fn surface(&self, ray: &Ray, t: f32) -> SurfacePoint {
        match self.hit(ray, f32::NEG_INFINITY, f32::INFINITY) {
            Some(h) => self.surface_at(h.b),
            // Unreachable for a `t` this triangle reported; the projection
            // onto its plane is the safe answer anyway.
            None => project_onto_plane(ray.at(t), self.normal, self.normal.dot(self.v[0])),
        }
    }

    /// The surface point at barycentrics `b` (see [`surface`](Self::surface)),
    /// for a caller whose own run of the watertight test kept them.
    #[inline]
    pub fn surface_at(&self, b: [f32; 3]) -> SurfacePoint {
        let [p0, p1, p2] = self.v;
        let (q0, q1, q2) = (b[0] * p0, b[1] * p1, b[2] * p2);
        SurfacePoint {
            p: q0 + q1 + q2,
            error: gamma(7) * (q0.abs() + q1.abs() + q2.abs()),
            n: self.normal,
        }
    }

    /// Bounding box of the three vertices.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.vertices())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::testing::Lcg;
    use glam::DVec3;

    /// The cheap degeneracy test agrees with `Triangle::new`'s normal on
    /// random, collinear, repeated, tiny, huge and non-finite vertices.
    #[test]
    fn degeneracy_without_normalising() {
        let mut r = crate::testutil::Rng::new(0x2545_f491);
        let mut rnd = || r.u64() as u32;
        let specials = [
            0.0,
            -0.0,
            1.0,
            f32::MIN_POSITIVE,
            1e-45,
            f32::MAX,
            -f32::MAX,
            f32::INFINITY,
            f32::NAN,
            3.0,
        ];
        for i in 0..200_000 {
            let mut v = || {
                let mut c = || match rnd() % 4 {
                    0 => specials[rnd() as usize % specials.len()],
                    1 => (rnd() % 7) as f32 - 3.0,
                    _ => Some(f32::from_bits(rnd()))
                        .filter(|f| f.is_finite())
                        .unwrap_or(2.0),
                };
                Vec3::new(c(), c(), c())
            };
            let (a, b) = (v(), v());
            let c = match i % 4 {
                0 => a + (b - a) * 0.5, // collinear (up to rounding)
                1 => a,
                _ => v(),
            };
            assert_eq!(
                is_degenerate_triangle(a, b, c),
                Triangle::new(a, b, c).is_degenerate(),
                "{a:?} {b:?} {c:?}"
            );
        }
    }

    fn tri() -> Triangle {
        Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)
    }

    #[test]
    fn hit_inside() {
        let r = Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z);
        let h = tri().hit(&r, 0.0, f32::INFINITY).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6);
        assert!((h.b[0] - 0.5).abs() < 1e-6 && (h.b[1] - 0.25).abs() < 1e-6);
        assert!((h.b.iter().sum::<f32>() - 1.0).abs() < 1e-6);
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
    fn negative_tmin_sees_behind() {
        let r = Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::Z);
        let t = tri().intersect(&r, f32::NEG_INFINITY, f32::INFINITY);
        assert!((t.unwrap() + 1.0).abs() < 1e-6);
    }

    /// Edges and vertices belong to the triangle: a ray exactly through a
    /// point of any edge, or through a vertex, hits it, from either side
    /// (the edge function is exactly 0 there; two triangles sharing the edge
    /// both report the hit), for either winding (the other edge functions
    /// positive, or negative).
    #[test]
    fn rays_exactly_through_edges_and_vertices_hit() {
        let points = [
            Vec3::new(0.5, 0.5, 0.0), // edge p1–p2 (e0 = 0)
            Vec3::new(0.0, 0.5, 0.0), // edge p2–p0 (e1 = 0)
            Vec3::new(0.5, 0.0, 0.0), // edge p0–p1 (e2 = 0)
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
        ];
        let windings = [tri(), Triangle::new(Vec3::ZERO, Vec3::Y, Vec3::X)];
        for (t, p) in windings.iter().flat_map(|t| points.map(|p| (t, p))) {
            for dir in [Vec3::NEG_Z, Vec3::Z] {
                let r = Ray::new(p - dir, dir);
                let h = t.hit(&r, 0.0, f32::INFINITY);
                assert_eq!(h.map(|h| h.t), Some(1.0), "{t:?}: {p} along {dir}");
            }
        }
    }

    /// The range is open at both ends: a hit exactly at `tmin` or `tmax` is
    /// not reported.
    #[test]
    fn hits_at_the_ends_of_the_range_are_excluded() {
        let r = Ray::new(Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z);
        assert_eq!(tri().intersect(&r, 0.5, 1.5), Some(1.0));
        assert_eq!(tri().intersect(&r, 1.0, 2.0), None);
        assert_eq!(tri().intersect(&r, 0.0, 1.0), None);
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
        let r = Ray::new(Vec3::new(0.5, 0.0, 1.0), Vec3::NEG_Z);
        assert!(t.intersect(&r, 0.0, f32::INFINITY).is_none());
    }

    /// Two (nearly) coplanar triangles sharing an edge, rays crossing their
    /// plane at points of that edge from many directions: every ray hits at
    /// least one of them.
    #[test]
    fn shared_edge_has_no_gap() {
        let (a, b) = (Vec3::new(0.1, 0.3, 0.7), Vec3::new(0.9, 0.6, 0.2));
        let c = Vec3::new(0.2, 1.1, 0.4);
        let d = a + b - c;
        let halves = [Triangle::new(a, b, c), Triangle::new(b, a, d)];
        let mut misses = 0;
        for i in 0..2000 {
            let s = (i as f32 * 0.618_034).fract();
            let p = a + s * (b - a);
            let from = p + Vec3::new((i as f32 * 0.37).sin(), 2.0, (i as f32 * 0.73).cos());
            let r = Ray::new(from, p - from);
            if halves
                .iter()
                .all(|t| t.intersect(&r, 0.0, f32::INFINITY).is_none())
            {
                misses += 1;
            }
        }
        assert_eq!(misses, 0);
    }

    /// The branch-free choice of the dominant axis is the `if` chain's
    /// (`x` if at least both others, else `y` if at least `z`, else `z`),
    /// ties, zeros, infinities and NaN included, and the shear follows it.
    #[test]
    fn dominant_axis_is_the_if_chains() {
        let values = [0.0, -0.0, 1.0, -1.0, 2.0, 0.5, f32::INFINITY, f32::NAN];
        let mut seen = [0; 3];
        for &x in &values {
            for &y in &values {
                for &z in &values {
                    let d = Vec3::new(x, y, z);
                    let a = d.abs();
                    let want = if a.x >= a.y && a.x >= a.z {
                        0
                    } else if a.y >= a.z {
                        1
                    } else {
                        2
                    };
                    let w = WatertightRay::new(&Ray::new(Vec3::ZERO, d));
                    let (kx, ky) = ((want + 1) % 3, (want + 2) % 3);
                    assert_eq!(w.k, [kx, ky, want], "{d}");
                    let sz = 1.0 / d[want];
                    let shear = [-d[kx] * sz, -d[ky] * sz, sz];
                    // Bit for bit, but any NaN for NaN (its sign bit is
                    // not an IEEE result).
                    let bits = |v: [f32; 3]| v.map(|x| if x.is_nan() { 1 } else { x.to_bits() });
                    assert_eq!(bits(w.shear.to_array()), bits(shear), "{d}");
                    seen[want] += 1;
                }
            }
        }
        assert!(seen.iter().all(|&n| n > 50), "{seen:?}");
    }

    /// The free function is the method's arithmetic (an accelerator calling
    /// it gets bit-identical answers).
    #[test]
    fn free_function_matches_method() {
        let t = Triangle::new(Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 1.0, 2.5), Vec3::Z);
        let from = Vec3::new(10.0, 0.0, 0.0);
        let r = Ray::new(from, (t.v[0] + t.v[1] + t.v[2]) / 3.0 - from);
        let w = WatertightRay::new(&r);
        let [p0, p1, p2] = t.v;
        assert_eq!(
            intersect_triangle(&w, p0, p1, p2, 0.0, f32::INFINITY),
            t.hit(&r, 0.0, f32::INFINITY)
        );
        assert!(t.hit(&r, 0.0, f32::INFINITY).is_some());
    }

    /// pbrt's `deltaT` with `tmin = 0`: a hit whose exact `t` (f64, for the
    /// same f32 vertices and ray) is not positive is never reported, and a
    /// hit clear of the coordinates' rounding is never rejected. Triangles
    /// 10⁻³..10³ across, up to 10⁵ from the origin; ray origins on the
    /// triangle's plane (as far as f32 allows) or off it on either side by
    /// 10⁻⁹..1 of its size, towards it or away from it.
    #[test]
    fn a_hit_at_the_ray_origin_follows_the_sign_of_the_exact_t() {
        let mut g = Lcg(11);
        let (mut reported, mut rejected) = (0, 0);
        for i in 0..200_000 {
            let size = 10f32.powi(i % 7 - 3);
            let far = 10f32.powi(i % 6);
            let centre = g.vec(2.0 * far);
            let v = [0; 3].map(|_| centre + g.vec(2.0 * size));
            let d = v.map(|p| p.as_dvec3());
            let cross = (d[1] - d[0]).cross(d[2] - d[0]);
            if cross.length() < 0.1 * (size as f64).powi(2) {
                continue;
            }
            let n = cross.normalize();
            let (u, w) = (0.1 + 0.7 * g.next() as f64, 0.1 + 0.7 * g.next() as f64);
            let (u, w) = if u + w > 0.9 {
                (0.9 - w, 0.9 - u)
            } else {
                (u, w)
            };
            let q = d[0] + u * (d[1] - d[0]) + w * (d[2] - d[0]);
            let h = match i % 10 {
                0 => 0.0,
                k => {
                    let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                    sign * size as f64 * 10f64.powf(-9.0 * g.next() as f64)
                }
            };
            let o = (q + n * h).as_vec3();
            // Every fourth ray grazes the plane (the error of `t` grows as
            // the cosine falls): only the sign of `t` is checked there.
            let grazing = i % 4 == 3;
            let dir = if grazing {
                let w = g.vec(2.0).as_dvec3();
                let tangent = (w - n * w.dot(n)).normalize_or_zero();
                let cos = 10f64.powf(-1.0 - 4.0 * g.next() as f64) * (w.dot(n).signum());
                (tangent + n * cos).as_vec3()
            } else {
                g.vec(2.0)
            };
            let along = dir.as_dvec3().dot(n);
            if !grazing && along.abs() < 0.2 * dir.length() as f64 || along == 0.0 {
                continue;
            }
            let (od, dd) = (o.as_dvec3(), dir.as_dvec3());
            let t_exact = n.dot(d[0] - od) / along;
            let hit = intersect_triangle(
                &WatertightRay::new(&Ray::new(o, dir)),
                v[0],
                v[1],
                v[2],
                0.0,
                f32::INFINITY,
            );
            if let Some(hit) = hit {
                reported += 1;
                assert!(
                    t_exact > 0.0,
                    "{v:?} from {o} along {dir}: t {} but exactly {t_exact}",
                    hit.t
                );
                continue;
            }
            // Rejected (or missed): where the exact crossing is well inside,
            // only a t within rounding of 0 may be rejected.
            let x = od + t_exact * dd;
            let bary = |a: DVec3, b: DVec3| (b - a).cross(x - a).dot(n) / cross.length();
            let inside = [bary(d[1], d[2]), bary(d[2], d[0]), bary(d[0], d[1])];
            if !grazing && t_exact > 0.0 && inside.iter().all(|&b| b > 0.02) {
                // pbrt's bound is conservative: measured up to 2.4·10⁻⁴ of
                // the coordinates' size (a ray at a slant to a triangle
                // 10³ across, 10³ from the origin).
                rejected += 1;
                let reach = t_exact * dd.length() / (size + far) as f64;
                assert!(
                    reach < 1e-3,
                    "{v:?} from {o} along {dir}: missed at t {t_exact}"
                );
            }
        }
        assert!(
            reported > 40_000 && rejected > 10_000,
            "{reported} {rejected}"
        );
    }

    #[test]
    fn interpolated_point_is_in_the_plane_within_its_error() {
        let t = Triangle::new(
            Vec3::new(1e5, 3.0, -2e4),
            Vec3::new(1e5 + 7.0, 5.5, -2e4 + 1.0),
            Vec3::new(1e5 + 1.0, -4.0, -2e4 + 6.0),
        );
        let from = Vec3::new(0.0, 100.0, 0.0);
        let r = Ray::new(from, (t.v[0] + t.v[1] + t.v[2]) / 3.0 - from);
        let h = t.intersect(&r, 0.0, f32::INFINITY).unwrap();
        let sp = t.surface(&r, h);
        let (a, b, c) = (t.v[0].as_dvec3(), t.v[1].as_dvec3(), t.v[2].as_dvec3());
        let n = (b - a).cross(c - a).normalize();
        let dist = n.dot(sp.p.as_dvec3() - a);
        assert!(
            dist.abs() <= sp.error.as_dvec3().dot(n.abs()),
            "{dist} vs {}",
            sp.error
        );
        assert!((sp.p - r.at(h)).length() < 0.1);
    }
}
