//! Area lights: a point of the light's surface chosen by a 2-D sample, and
//! the light it sends to a surface point, divided by the probability
//! density of choosing it, so that the mean over samples is the light's
//! whole contribution.

use super::Incident;
use crate::math::float::sincos_turn;
pub use crate::math::warp::concentric_disk;
use crate::math::{gamma, SurfacePoint, Vec2, Vec3};
use crate::scene::{AreaShape, RenderAreaShape};
use std::f32::consts::{PI, TAU};

/// Surface area of the emitting side(s): flat lights emit from both faces.
pub fn emitting_area(shape: &RenderAreaShape) -> f32 {
    match *shape {
        AreaShape::Quad { edge1, edge2, .. } => 2.0 * edge1.cross(edge2).length(),
        AreaShape::Disk { radius, .. } => 2.0 * PI * radius * radius,
        AreaShape::Sphere { radius, .. } => 4.0 * PI * radius * radius,
    }
}

/// Radiance of a light of `power` (flux) and `color` over `shape`.
pub fn radiance(shape: &RenderAreaShape, color: Vec3, power: f32) -> Vec3 {
    let a = emitting_area(shape);
    if a > 0.0 {
        color * (power / (PI * a))
    } else {
        Vec3::ZERO
    }
}

/// Light arriving at `p` from the point of `shape` chosen by `u ∈ [0,1)²`,
/// already divided by the sample's density (`radiance · cos θ_light · A / d²`
/// for area sampling, `radiance · Ω` for cone sampling).
pub fn sample(shape: &RenderAreaShape, radiance: Vec3, p: Vec3, u: Vec2) -> Incident {
    Prepared::new(shape, radiance, p).sample(u)
}

/// [`sample`] for one light and one point `p`, with what every sample of
/// that pair shares worked out once: a quad's normal and area, a disk's
/// frame, a sphere's cone (its axis, frame and solid angle). A shaded point
/// sends several shadow rays to an area light; each sample is then the
/// per-sample work alone. Every sample equals [`sample`]'s bit for bit (it
/// is [`sample`]).
#[derive(Clone, Copy, Debug)]
pub enum Prepared {
    /// A parallelogram: corner, edges, unit normal and (one-sided) area.
    Quad {
        /// `corner + s·edge1 + t·edge2`, `(s, t) ∈ [0, 1)²`.
        corner: Vec3,
        /// First edge.
        edge1: Vec3,
        /// Second edge.
        edge2: Vec3,
        /// Unit normal `edge1 × edge2`.
        n: Vec3,
        /// One face's area.
        area: f32,
        /// The light's radiance.
        radiance: Vec3,
        /// The lit point.
        p: Vec3,
    },
    /// A disk: centre, unit normal, frame in its plane, radius.
    Disk {
        /// Centre.
        center: Vec3,
        /// Unit normal.
        n: Vec3,
        /// Orthonormal pair spanning the disk's plane.
        frame: (Vec3, Vec3),
        /// Radius.
        radius: f32,
        /// The light's radiance.
        radiance: Vec3,
        /// The lit point.
        p: Vec3,
    },
    /// A sphere seen from outside: its cone from `p`, and the light each
    /// sample carries (`radiance · Ω`, the same for all).
    Sphere {
        /// The cone.
        cone: Cone,
        /// `radiance · Ω`.
        color: Vec3,
    },
    /// `p` inside a sphere light: it lights nothing there.
    Nothing,
}

impl Prepared {
    /// Whether every direction from the point to the light keeps the sign
    /// of each component and spreads it by at most `spread` of its
    /// smallest magnitude: a sphere whose centre lies at least `r (1 + 2 /
    /// spread)` away along every axis (rays to it may share a packet's
    /// walk, `bvh8`'s spread limit). Quads and disks answer no.
    #[inline]
    pub fn narrow(&self, spread: f32) -> bool {
        match self {
            Prepared::Sphere { cone, .. } => (cone.to_c.abs() * spread)
                .cmpge(Vec3::splat(cone.r * (spread + 2.0)))
                .all(),
            _ => false,
        }
    }

    /// What samples of `shape` (of `radiance`) seen from `p` share.
    // Always inlined (and `sample`, and the cone's): out of line, the
    // prepared light came back through memory, a store-forwarding stall.
    #[inline(always)]
    pub fn new(shape: &RenderAreaShape, radiance: Vec3, p: Vec3) -> Self {
        match *shape {
            AreaShape::Quad {
                corner,
                edge1,
                edge2,
            } => {
                let (n, area) = quad_frame(edge1, edge2);
                Prepared::Quad {
                    corner,
                    edge1,
                    edge2,
                    n,
                    area,
                    radiance,
                    p,
                }
            }
            AreaShape::Disk {
                center,
                normal,
                radius,
            } => {
                let n = normal.normalize_or_zero();
                Prepared::Disk {
                    center,
                    n,
                    frame: n.any_orthonormal_pair(),
                    radius,
                    radiance,
                    p,
                }
            }
            AreaShape::Sphere { center, radius } => match Cone::new(center, radius, p) {
                None => Prepared::Nothing,
                Some(cone) => Prepared::Sphere {
                    cone,
                    color: radiance * cone.solid_angle(),
                },
            },
        }
    }

    /// The sample `u ∈ [0,1)²`: what [`sample`] returns for it.
    #[inline(always)]
    pub fn sample(&self, u: Vec2) -> Incident {
        match *self {
            Prepared::Quad {
                corner,
                edge1,
                edge2,
                n,
                area,
                radiance,
                p,
            } => from_area_point(p, quad_at(corner, edge1, edge2, n, u), area, radiance),
            Prepared::Disk {
                center,
                n,
                frame,
                radius,
                radiance,
                p,
            } => {
                let at = disk_at(center, n, frame, radius, u);
                from_area_point(p, at, PI * radius * radius, radiance)
            }
            Prepared::Sphere { cone, color } => {
                let s = cone.sample(u);
                Incident {
                    to_light: s.w,
                    color,
                    at: Some(s.at),
                }
            }
            Prepared::Nothing => Incident::NONE,
        }
    }
}

/// The point of the parallelogram `corner + s·edge1 + t·edge2` at
/// `(s, t) = u`, with its error bound and unit normal `edge1 × edge2`, and
/// the parallelogram's (one-sided) area.
#[inline]
pub(super) fn quad_point(corner: Vec3, edge1: Vec3, edge2: Vec3, u: Vec2) -> (SurfacePoint, f32) {
    let (n, area) = quad_frame(edge1, edge2);
    (quad_at(corner, edge1, edge2, n, u), area)
}

/// A parallelogram's unit normal `edge1 × edge2` and (one-sided) area.
#[inline]
fn quad_frame(edge1: Vec3, edge2: Vec3) -> (Vec3, f32) {
    let n = edge1.cross(edge2);
    let area = n.length();
    (n / area.max(f32::MIN_POSITIVE), area)
}

/// [`quad_point`]'s point, given the unit normal.
#[inline]
fn quad_at(corner: Vec3, edge1: Vec3, edge2: Vec3, n: Vec3, u: Vec2) -> SurfacePoint {
    let (a, b) = (u.x * edge1, u.y * edge2);
    let y = corner + a + b;
    // Two products and two sums per coordinate.
    let error = gamma(4) * (corner.abs() + a.abs() + b.abs());
    SurfacePoint { p: y, error, n }
}

/// The point of the disk around `center` with unit normal `n` chosen by
/// `u` (uniform over its area), with its error bound.
#[inline]
pub(super) fn disk_point(center: Vec3, n: Vec3, radius: f32, u: Vec2) -> SurfacePoint {
    disk_at(center, n, n.any_orthonormal_pair(), radius, u)
}

/// [`disk_point`], given the frame `n.any_orthonormal_pair()`.
#[inline]
fn disk_at(center: Vec3, n: Vec3, (t1, t2): (Vec3, Vec3), radius: f32, u: Vec2) -> SurfacePoint {
    let d = concentric_disk(u) * radius;
    let (a, b) = (d.x * t1, d.y * t2);
    let y = center + a + b;
    // Off the disk's plane only by the rounding of the in-plane
    // offsets (`t1`, `t2` are unit within a few ulps) and the sums.
    let error = gamma(6) * (center.abs() + a.abs() + b.abs());
    SurfacePoint { p: y, error, n }
}

/// From `p` towards the light point `at`: the unit direction, the squared
/// distance and the cosine between the light's normal and the direction
/// (signed); `None` when the point is `p` itself or too far for f32.
#[inline]
pub(super) fn toward(p: Vec3, at: &SurfacePoint) -> Option<(Vec3, f32, f32)> {
    let d = at.p - p;
    let dist2 = d.length_squared();
    if dist2 == 0.0 || !dist2.is_finite() {
        return None;
    }
    let dist = dist2.sqrt();
    let w = d / dist;
    Some((w, dist2, at.n.dot(w)))
}

fn from_area_point(p: Vec3, at: SurfacePoint, area: f32, radiance: Vec3) -> Incident {
    let Some((w, dist2, cos)) = toward(p, &at) else {
        return Incident::NONE;
    };
    // Both faces emit.
    let cos_l = cos.abs();
    Incident {
        to_light: w,
        color: radiance * (cos_l * area / dist2),
        at: Some(at),
    }
}

/// A direction of the cone a sphere subtends from a point outside it, and
/// where it meets the sphere.
#[derive(Clone, Copy, Debug)]
pub(crate) struct ConeSample {
    /// Unit direction from the point.
    pub w: Vec3,
    /// The nearest point of the sphere along `w`.
    pub at: SurfacePoint,
    /// Cosine of the cone's half-angle.
    pub cos_max: f32,
    /// `sin²` of the half-angle, `r²/d²` (exact where `1 − cos_max`
    /// cancels, for small or far spheres).
    pub sin2_max: f32,
}

/// Uniform over the cone of directions the sphere subtends from `p`: every
/// sample hits the visible cap, and the density `1 / Ω` is the same for
/// all. `None` when `p` is inside the sphere.
#[inline]
pub(crate) fn sphere_cone(c: Vec3, r: f32, p: Vec3, u: Vec2) -> Option<ConeSample> {
    Some(Cone::new(c, r, p)?.sample(u))
}

/// The cone a sphere subtends from a point outside it: what every sample
/// of `sphere_cone` from that point shares.
#[derive(Clone, Copy, Debug)]
pub struct Cone {
    c: Vec3,
    r: f32,
    /// From the point to the centre.
    to_c: Vec3,
    /// `to_c` normalised.
    axis: Vec3,
    frame: (Vec3, Vec3),
    /// `1 − cos_max`, as `sin2_max / (1 + cos_max)`: without the
    /// cancellation of the difference for small or far spheres.
    one_minus_cos: f32,
    /// `1 / sin` and `1 / sin²` of the half-angle, `d / r` and `d² / r²`.
    inv_sin_max: f32,
    inv_sin2_max: f32,
    /// Cosine of the cone's half-angle.
    pub cos_max: f32,
    /// `sin²` of the half-angle, `r²/d²`.
    pub sin2_max: f32,
}

impl Cone {
    /// The cone of the sphere (`c`, `r`) from `p`; `None` from inside.
    #[inline(always)]
    pub fn new(c: Vec3, r: f32, p: Vec3) -> Option<Self> {
        let to_c = c - p;
        let d2 = to_c.length_squared();
        if d2 <= r * r {
            return None;
        }
        let d = d2.sqrt();
        let axis = to_c / d;
        let sin2_max = r * r / d2;
        let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
        Some(Self {
            c,
            r,
            to_c,
            axis,
            frame: axis.any_orthonormal_pair(),
            one_minus_cos: sin2_max / (1.0 + cos_max),
            inv_sin_max: d / r,
            inv_sin2_max: d2 / (r * r),
            cos_max,
            sin2_max,
        })
    }

    /// The solid angle of the cone, `2π (1 − cos_max)`.
    #[inline(always)]
    pub fn solid_angle(&self) -> f32 {
        TAU * self.one_minus_cos
    }

    /// The direction `u` picks, uniform in the cone, and where it meets
    /// the sphere.
    ///
    /// The point comes from the angle `α` at the centre between the
    /// sphere's normal there and the way back to the point (pbrt-v4's
    /// `Sphere::Sample`): with `θ` the direction's angle from the axis,
    /// `cos α = sin²θ / sin θmax + cos θ · √(1 − sin²θ / sin²θmax)` (the
    /// law of sines in the triangle of point, centre and sample), the
    /// normal `sin α · radial − cos α · axis` in the direction's own
    /// half-plane. Not by intersecting the ray with the sphere and
    /// normalising the offset from the centre: that chain of three square
    /// roots and a division, every one waiting on the one before, stood
    /// ahead of every shadow ray (perf, sphere_lights_knot at 16 spp: about
    /// a fifth of `Whitted::shade`'s samples, `shade` being 31% of the
    /// render); here two of the
    /// roots run side by side, and the normal comes out of unit length
    /// by construction, with no normalisation.
    #[inline(always)]
    pub(super) fn sample(&self, u: Vec2) -> ConeSample {
        let Self {
            c,
            r,
            axis,
            frame: (t1, t2),
            to_c: _,
            one_minus_cos,
            inv_sin_max,
            inv_sin2_max,
            cos_max,
            sin2_max,
        } = *self;
        // cos θ uniform in [cos θmax, 1]; sin²θ = (1 − cos θ)(1 + cos θ),
        // without the cancellation of 1 − cos²θ near the axis.
        let a = u.x * one_minus_cos;
        let cos_t = 1.0 - a;
        let sin2_t = (a * (2.0 - a)).max(0.0);
        let sin_t = sin2_t.sqrt();
        let (sin_p, cos_p) = sincos_turn(u.y);
        let radial = t1 * cos_p + t2 * sin_p;
        let w = radial * sin_t + axis * cos_t;
        let cos_a =
            (sin2_t * inv_sin_max + cos_t * (1.0 - sin2_t * inv_sin2_max).max(0.0).sqrt()).min(1.0);
        let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
        // Unit up to the roundings of the frame, of the sine and cosine and
        // of the sum: `|n|` within 5 roundings of 1 (the test
        // `cone_normals_are_unit_within_five_roundings`; one Newton step
        // towards unit length halved that but cost 3% of an area-light
        // render, being on the way to every shadow ray).
        let n = radial * sin_a - axis * cos_a;
        let rn = r * n;
        let y = c + rn;
        // Off the exact sphere by `r` times `n`'s length error (5 roundings
        // of each coordinate of `rn`) and by the roundings of the product
        // and the sum (one each): bounded by the terms' sizes, not by
        // `|y|`, which is small where the centre and the offset cancel.
        let error = gamma(7) * (c.abs() + rn.abs());
        ConeSample {
            w,
            at: SurfacePoint { p: y, error, n },
            cos_max,
            sin2_max,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::testing::{check_error_box, Lcg};

    /// A sphere is narrow where its centre lies at least `r (1 + 2 / s)`
    /// away along every axis: then every sampled direction keeps the signs
    /// and spreads by at most `s`; quads are never narrow.
    #[test]
    fn narrow_spheres_keep_their_directions_close() {
        let s = 0.125;
        let sphere = |center, radius| AreaShape::Sphere { center, radius };
        let p = Vec3::ZERO;
        let narrow = |c: Vec3, r| Prepared::new(&sphere(c, r), Vec3::ONE, p).narrow(s);
        assert!(narrow(Vec3::new(20.0, -30.0, 17.5), 1.0));
        assert!(!narrow(Vec3::new(20.0, -30.0, 16.5), 1.0));
        assert!(!narrow(Vec3::new(0.0, 100.0, 100.0), 0.1));
        assert!(!narrow(Vec3::new(9.0, 7.0, 6.0), 1.2));
        let c = Vec3::new(30.0, -40.0, 25.0);
        let prepared = Prepared::new(&sphere(c, 1.0), Vec3::ONE, p);
        assert!(prepared.narrow(s));
        let mut rng = Lcg(3);
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::ZERO);
        for _ in 0..2000 {
            let inc = prepared.sample(Vec2::new(rng.next(), rng.next()));
            let d = inc.at.unwrap().p - p;
            assert_eq!(d.is_negative_bitmask(), c.is_negative_bitmask());
            (lo, hi) = (lo.min(d.abs()), hi.max(d.abs()));
        }
        assert!((hi - lo).cmple(lo * s).all(), "{lo} {hi}");
        let quad = AreaShape::Quad {
            corner: c,
            edge1: Vec3::X * 0.01,
            edge2: Vec3::Z * 0.01,
        };
        assert!(!Prepared::new(&quad, Vec3::ONE, p).narrow(s));
    }

    /// Mean of the estimator over a fine grid of samples.
    fn irradiance(shape: &RenderAreaShape, p: Vec3, n: Vec3) -> f32 {
        let k = 200;
        let mut sum = 0.0;
        for i in 0..k {
            for j in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                let inc = sample(shape, Vec3::ONE, p, u);
                sum += inc.color.x * n.dot(inc.to_light).max(0.0);
            }
        }
        sum / (k * k) as f32
    }

    #[test]
    fn small_lights_act_like_their_solid_angle() {
        // Irradiance from a small source of unit radiance facing the point:
        // about its solid angle; at the origin and elsewhere.
        let d = 10.0;
        for p in [Vec3::ZERO, Vec3::new(3.0, -2.0, 5.0)] {
            let quad = AreaShape::Quad {
                corner: p + Vec3::new(-0.1, d, -0.1),
                edge1: Vec3::new(0.2, 0.0, 0.0),
                edge2: Vec3::new(0.0, 0.0, 0.2),
            };
            let e = irradiance(&quad, p, Vec3::Y);
            assert!((e - 0.04 / (d * d)).abs() < 1e-3 * e, "{p}: {e}");
            let disk = AreaShape::Disk {
                center: p + Vec3::new(0.0, d, 0.0),
                normal: Vec3::NEG_Y,
                radius: 0.1,
            };
            let e = irradiance(&disk, p, Vec3::Y);
            assert!((e - PI * 0.01 / (d * d)).abs() < 1e-3 * e, "{p}: {e}");
            let r = 0.5;
            let sphere = AreaShape::Sphere {
                center: p + Vec3::new(0.0, d, 0.0),
                radius: r,
            };
            // Exact: π sin²θ_max cos α for a sphere wholly above the
            // horizon, α away from the normal (straight above, and tilted:
            // the tilt sees whether directions spread evenly round the axis).
            for alpha in [0.0f32, 0.7] {
                let n = Vec3::new(alpha.sin(), alpha.cos(), 0.0);
                let e = irradiance(&sphere, p, n);
                let want = PI * r * r / (d * d) * alpha.cos();
                assert!(
                    (e - want).abs() < 1e-3 * want,
                    "{p}, {alpha}: {e} vs {want}"
                );
            }
        }
    }

    #[test]
    fn sphere_samples_are_the_near_points_along_their_directions() {
        let c = Vec3::new(1.0, 2.0, 3.0);
        let sphere = AreaShape::Sphere {
            center: c,
            radius: 1.5,
        };
        let p = Vec3::new(-2.0, 4.0, 0.5);
        let tangent = ((p - c).length_squared() - 1.5 * 1.5).sqrt();
        for i in 0..16 {
            for j in 0..16 {
                let u = Vec2::new((i as f32 + 0.5) / 16.0, (j as f32 + 0.5) / 16.0);
                let inc = sample(&sphere, Vec3::ONE, p, u);
                let y = inc.at.unwrap().p;
                // On the sphere, on the sample's direction, and on the side
                // facing p (no farther than the tangent points).
                assert!(((y - c).length() - 1.5).abs() < 1e-5, "{u}: {y}");
                assert!((inc.to_light.length() - 1.0).abs() < 1e-6, "{u}");
                assert!(
                    (y - p).normalize().dot(inc.to_light) > 1.0 - 1e-6,
                    "{u}: {y}"
                );
                assert!((y - p).length() <= tangent + 1e-4, "{u}: {y}");
            }
        }
    }

    #[test]
    fn a_sphere_light_lights_nothing_inside_it() {
        let sphere = AreaShape::Sphere {
            center: Vec3::new(1.0, 2.0, 3.0),
            radius: 3.0,
        };
        let at = |r: f32| {
            sample(
                &sphere,
                Vec3::ONE,
                Vec3::new(1.0, 2.0 + r, 3.0),
                Vec2::splat(0.5),
            )
        };
        assert_eq!(at(2.8), Incident::NONE);
        assert!(at(3.2).color.x > 0.0);
    }

    #[test]
    fn radiance_spreads_power_over_the_area() {
        let s = AreaShape::Sphere {
            center: Vec3::ZERO,
            radius: 2.0,
        };
        let l = radiance(&s, Vec3::ONE, 100.0);
        assert!((l.x - 100.0 / (PI * 16.0 * PI)).abs() < 1e-6);
    }

    #[test]
    fn a_light_without_area_sends_nothing() {
        // Its radiance would be power / 0 = ∞, and ∞ times the zero area
        // (or solid angle) of a sample is NaN in the pixel.
        let shapes = [
            AreaShape::Quad {
                corner: Vec3::new(0.0, 2.0, 0.0),
                edge1: Vec3::X,
                edge2: 2.0 * Vec3::X,
            },
            AreaShape::Disk {
                center: Vec3::new(0.0, 2.0, 0.0),
                normal: Vec3::NEG_Y,
                radius: 0.0,
            },
            AreaShape::Sphere {
                center: Vec3::new(0.0, 2.0, 0.0),
                radius: 0.0,
            },
        ];
        for shape in &shapes {
            let l = radiance(shape, Vec3::ONE, 100.0);
            assert_eq!(l, Vec3::ZERO, "{shape:?}");
            let inc = sample(shape, l, Vec3::ZERO, Vec2::new(0.3, 0.6));
            assert_eq!(inc.color, Vec3::ZERO, "{shape:?}");
        }
    }

    #[test]
    fn a_point_on_the_light_or_out_of_range_gets_nothing() {
        let quad = AreaShape::Quad {
            corner: Vec3::ZERO,
            edge1: Vec3::X,
            edge2: Vec3::Z,
        };
        // The sample is the shading point itself: no direction, and the
        // density's 1/d² is infinite.
        assert_eq!(
            sample(&quad, Vec3::ONE, Vec3::ZERO, Vec2::ZERO),
            Incident::NONE
        );
        // The squared distance overflows f32.
        let far = Vec3::splat(3e19);
        assert_eq!(
            sample(&quad, Vec3::ONE, far, Vec2::splat(0.5)),
            Incident::NONE
        );
    }

    /// A shadow ray's far end is offset out of the sample's error box: a box
    /// too small lets the light's own plane (a ceiling around a ceiling
    /// light) block the ray at some samples, one too large lets occluders
    /// just below the light through. Over quads and disks from the origin to
    /// 10⁵ away and from 10⁻³ to 10³ across (and spheres likewise), the box
    /// holds the exact point (f64) and is within a few roundings of the
    /// coordinates' size.
    #[test]
    fn sample_points_lie_in_tight_error_boxes() {
        let mut g = Lcg(7);
        let mut r = || g.next();
        let mut v = |scale: f32| Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * 2.0 * scale;
        let g = gamma(12);
        for i in 0..4000 {
            let far = 10f32.powi(i % 6);
            let size = 10f32.powi(i % 7 - 3);
            let u = (v(0.5) + Vec3::splat(0.5)).truncate();
            let (e1, e2) = (v(size), v(size));
            let corner = v(far);
            let quad = AreaShape::Quad {
                corner,
                edge1: e1,
                edge2: e2,
            };
            if let Some(at) = sample(&quad, Vec3::ONE, corner + Vec3::splat(3.0 * far), u).at {
                let truth =
                    corner.as_dvec3() + u.x as f64 * e1.as_dvec3() + u.y as f64 * e2.as_dvec3();
                let limit = g * (corner.abs() + e1.abs() + e2.abs());
                check_error_box(at, truth, None, limit, &format!("quad {quad:?} at {u}"));
            }
            let (center, normal) = (v(far), v(1.0));
            let disk = AreaShape::Disk {
                center,
                normal,
                radius: size,
            };
            if let Some(at) = sample(&disk, Vec3::ONE, center + normal * far, u).at {
                let n = normal.as_dvec3().normalize();
                let limit = g * (center.abs() + Vec3::splat(size));
                check_error_box(
                    at,
                    center.as_dvec3(),
                    Some(n),
                    limit,
                    &format!("disk {disk:?} at {u}"),
                );
            }
            let sphere = AreaShape::Sphere {
                center,
                radius: size,
            };
            if let Some(at) = sample(&sphere, Vec3::ONE, center + normal * far * 3.0, u).at {
                // The nearest point of the exact sphere (a sphere smaller
                // than the rounding of its centre's coordinates may sample
                // the centre itself).
                let (c, n) = (center.as_dvec3(), at.n.as_dvec3());
                let out = (at.p.as_dvec3() - c).try_normalize().unwrap_or(n);
                let truth = c + out * size as f64;
                let limit = g * (center.abs() + Vec3::splat(size));
                check_error_box(at, truth, Some(n), limit, &format!("{sphere:?} at {u}"));
            }
        }
    }

    /// The sampled normal is unit within 5 roundings (`f32::EPSILON / 2`),
    /// what [`Cone::sample`]'s error bound counts on: cones from 1e-3 to
    /// 1e3 across, from the origin to 1e5 away, seen from 1 to 11 radii
    /// from their centre, in every direction.
    #[test]
    fn cone_normals_are_unit_within_five_roundings() {
        let mut g = Lcg(11);
        let mut r = || g.next();
        let mut worst = 0f64;
        for i in 0..100_000 {
            let far = 10f32.powi(i % 6);
            let size = 10f32.powi(i % 7 - 3);
            let c = Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5) * 2.0 * far;
            let dir = Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5).normalize();
            let p = c + dir * size * (1.0 + 10.0 * r());
            if let Some(cone) = Cone::new(c, size, p) {
                let n = cone.sample(Vec2::new(r(), r())).at.n.as_dvec3();
                worst = worst.max((n.length() - 1.0).abs() / (f32::EPSILON as f64 / 2.0));
            }
        }
        assert!(worst <= 5.0, "|n| off 1 by {worst} roundings");
        assert!(worst > 0.5, "the check sees roundings: {worst}");
    }
}
