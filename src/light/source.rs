//! Lights as the integrators that weigh samples use them: built once with
//! the world (in rendering space), each samples a direction towards itself
//! with the density of that choice ([`LightSource::sample_li`]) and reports
//! the density of any direction ([`LightSource::pdf_li`]). Point and
//! directional lights are delta lights (one direction, no density); an area
//! light is also a surface a ray can hit ([`AreaLight::intersect`]), which
//! then knows the radiance it emits.
//!
//! An emitting primitive (a triangle of a glowing mesh) is one more
//! [`AreaLight`], of shape [`Emitter::Triangle`], sampled by area.
//!
//! The Whitted tree keeps its own, older entry points (`light::incident`,
//! `light::sample_light`), which return the light already divided by its
//! density; both share the geometry of `light::area`.

use super::area::{self, disk_point, quad_point, sphere_cone, toward};
use super::{point_incident, Incident};
use crate::math::warp::uniform_triangle;
use crate::math::{Ray, SurfacePoint, Vec2, Vec3};
use crate::scene::{AreaShape, Light, RenderAreaShape, RenderLight};
use crate::shape::{Plane, Sphere, Triangle};
use std::f32::consts::{PI, TAU};

/// A light of the world.
#[derive(Clone, Debug, PartialEq)]
pub enum LightSource {
    /// A point light: `intensity · attenuation(d)` arrives from `position`.
    Point {
        /// Position (rendering space).
        position: Vec3,
        /// Colour and intensity.
        intensity: Vec3,
        /// Constant, linear and quadratic attenuation coefficients.
        attenuation: Vec3,
    },
    /// Light from infinitely far away.
    Directional {
        /// Unit direction towards the light.
        to_light: Vec3,
        /// Colour and intensity arriving.
        radiance: Vec3,
    },
    /// A surface that emits.
    Area(AreaLight),
}

/// A light with a surface: uniform radiance over an emitter shape.
#[derive(Clone, Debug, PartialEq)]
pub struct AreaLight {
    /// The emitting surface.
    pub shape: Emitter,
    /// Emitted radiance.
    pub radiance: Vec3,
    /// Whether both faces emit (the scene's flat lights); else only the
    /// side the shape's normal points to.
    pub two_sided: bool,
}

/// The surface of an area light, prepared for sampling and intersection.
#[derive(Clone, Debug, PartialEq)]
pub enum Emitter {
    /// The parallelogram `corner + s·edge1 + t·edge2`, `s, t ∈ [0, 1]`.
    Quad {
        /// One corner.
        corner: Vec3,
        /// First edge.
        edge1: Vec3,
        /// Second edge.
        edge2: Vec3,
        /// Its plane (normal along `edge1 × edge2`).
        plane: Plane,
        /// `(edge2 × N)/|N|²` and `(N × edge1)/|N|²`: a point's `s` and `t`
        /// as dot products with its offset from `corner`.
        dual: [Vec3; 2],
    },
    /// A flat disk.
    Disk {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
        /// Its plane (unit normal).
        plane: Plane,
    },
    /// A sphere, emitting outwards, sampled by the cone it subtends.
    Sphere(Sphere),
    /// A triangle (of an emitting mesh), sampled by area.
    Triangle(Triangle),
}

/// Where a light sample lies, for the shadow ray towards it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightPoint {
    /// A point light's position: `SurfacePoint::spawn_ray_to`, traced to
    /// `1 − SHADOW_EPSILON`.
    Position(Vec3),
    /// Infinitely far along the sample's direction: `spawn_ray`, traced to
    /// infinity.
    Infinite,
    /// A point of an area light with its error bound:
    /// `SurfacePoint::spawn_ray_to_surface`, traced to `1 − SHADOW_EPSILON`.
    Surface(SurfacePoint),
}

/// A direction towards a light, sampled from a shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the shading point towards the light.
    pub wi: Vec3,
    /// Radiance arriving along `wi` if nothing is in between (for a delta
    /// light: what arrives, the delta's weight).
    pub li: Vec3,
    /// Density of `wi` per unit solid angle (1 for a delta light).
    pub pdf: f32,
    /// Distance to the light point (infinite for a directional light).
    pub dist: f32,
    /// Where the shadow ray goes.
    pub to: LightPoint,
    /// Whether the light is a delta light (no other strategy finds it).
    pub delta: bool,
}

/// A ray's hit on an area light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterHit {
    /// Ray parameter.
    pub t: f32,
    /// The point, its error bound and the emitter's normal there.
    pub at: SurfacePoint,
    /// Radiance emitted back along the ray.
    pub le: Vec3,
}

impl LightSource {
    /// The runtime light of a scene light (already in rendering space):
    /// directions normalised, an area light's radiance computed once from
    /// its power, exactly as the Whitted entry points compute them.
    pub fn from_scene(light: &RenderLight) -> Self {
        match light {
            Light::Point {
                position,
                color,
                attenuation,
            } => LightSource::Point {
                position: *position,
                intensity: *color,
                attenuation: *attenuation,
            },
            Light::Directional { color, .. } => LightSource::Directional {
                to_light: super::incident(light, Vec3::ZERO).to_light,
                radiance: *color,
            },
            Light::Area {
                shape,
                color,
                power,
            } => LightSource::Area(AreaLight {
                shape: Emitter::from_scene(shape),
                radiance: area::radiance(shape, *color, *power),
                two_sided: !matches!(shape, AreaShape::Sphere { .. }),
            }),
        }
    }

    /// Whether the light comes from one point or direction.
    pub fn is_delta(&self) -> bool {
        !matches!(self, LightSource::Area(_))
    }

    /// The area light, if this is one.
    pub fn area(&self) -> Option<&AreaLight> {
        match self {
            LightSource::Area(a) => Some(a),
            _ => None,
        }
    }

    /// What a delta light sends to `p`, in the Whitted tree's terms
    /// (`light::incident` of the scene light, bit for bit); `None` for an
    /// area light.
    #[inline]
    pub fn incident(&self, p: Vec3) -> Option<Incident> {
        match *self {
            LightSource::Point {
                position,
                intensity,
                attenuation,
            } => Some(point_incident(position, intensity, attenuation, p)),
            LightSource::Directional { to_light, radiance } => Some(Incident {
                to_light,
                color: radiance,
                at: None,
            }),
            LightSource::Area(_) => None,
        }
    }

    /// A direction from `p` towards the light, chosen by `u ∈ [0,1)²` (delta
    /// lights ignore it), with the radiance arriving and its density.
    /// `None` when the light sends nothing to `p` (`p` on or inside the
    /// light, behind a one-sided emitter, too far for f32).
    pub fn sample_li(&self, p: Vec3, u: Vec2) -> Option<LightSample> {
        match self {
            LightSource::Point { position, .. } => {
                let inc = self.incident(p)?;
                (inc.to_light != Vec3::ZERO).then(|| LightSample {
                    wi: inc.to_light,
                    li: inc.color,
                    pdf: 1.0,
                    dist: (*position - p).length(),
                    to: LightPoint::Position(*position),
                    delta: true,
                })
            }
            LightSource::Directional { to_light, radiance } => {
                (*to_light != Vec3::ZERO).then_some(LightSample {
                    wi: *to_light,
                    li: *radiance,
                    pdf: 1.0,
                    dist: f32::INFINITY,
                    to: LightPoint::Infinite,
                    delta: true,
                })
            }
            LightSource::Area(a) => a.sample_li(p, u),
        }
    }

    /// The density with which [`sample_li`](Self::sample_li) returns the
    /// unit direction `wi` from `p` (0 for delta lights and for directions
    /// that miss the light).
    pub fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32 {
        match self {
            LightSource::Area(a) => a.pdf_li(p, wi),
            _ => 0.0,
        }
    }
}

impl Emitter {
    /// The emitter of a scene area light's shape.
    pub fn from_scene(shape: &RenderAreaShape) -> Self {
        match *shape {
            AreaShape::Quad {
                corner,
                edge1,
                edge2,
            } => Emitter::quad(corner, edge1, edge2),
            AreaShape::Disk {
                center,
                normal,
                radius,
            } => {
                let n = normal.normalize_or_zero();
                Emitter::Disk {
                    center,
                    radius,
                    plane: Plane {
                        normal: n,
                        offset: n.dot(center),
                    },
                }
            }
            AreaShape::Sphere { center, radius } => Emitter::Sphere(Sphere { center, radius }),
        }
    }

    /// The parallelogram `corner + s·edge1 + t·edge2`.
    pub fn quad(corner: Vec3, edge1: Vec3, edge2: Vec3) -> Self {
        let n = edge1.cross(edge2);
        let nn = n.length_squared();
        let inv = if nn > 0.0 { 1.0 / nn } else { 0.0 };
        let unit = n.normalize_or_zero();
        Emitter::Quad {
            corner,
            edge1,
            edge2,
            plane: Plane {
                normal: unit,
                offset: unit.dot(corner),
            },
            dual: [edge2.cross(n) * inv, n.cross(edge1) * inv],
        }
    }

    /// The one-sided area (sampled uniformly, except the sphere).
    pub fn area(&self) -> f32 {
        match self {
            Emitter::Quad { edge1, edge2, .. } => edge1.cross(*edge2).length(),
            Emitter::Disk { radius, .. } => PI * radius * radius,
            Emitter::Sphere(s) => 4.0 * PI * s.radius * s.radius,
            Emitter::Triangle(t) => {
                let [a, b, c] = t.v;
                0.5 * (b - a).cross(c - a).length()
            }
        }
    }

    /// The closest hit of `ray` with `tmin < t < tmax`.
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<(f32, SurfacePoint)> {
        match self {
            Emitter::Quad {
                corner,
                plane,
                dual,
                ..
            } => {
                let (t, at) = plane.hit(ray, tmin, tmax)?;
                let q = at.p - *corner;
                let (s, u) = (q.dot(dual[0]), q.dot(dual[1]));
                ((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&u)).then_some((t, at))
            }
            Emitter::Disk {
                center,
                radius,
                plane,
            } => {
                let (t, at) = plane.hit(ray, tmin, tmax)?;
                ((at.p - *center).length_squared() <= radius * radius).then_some((t, at))
            }
            Emitter::Sphere(s) => {
                let t = s.intersect(ray, tmin, tmax)?;
                Some((t, s.surface(ray, t)))
            }
            Emitter::Triangle(tr) => {
                let h = tr.hit(ray, tmin, tmax)?;
                Some((h.t, tr.surface_at(h.b)))
            }
        }
    }
}

impl AreaLight {
    /// Radiance leaving the light's point of normal `n` in direction `w`.
    #[inline]
    pub fn le(&self, n: Vec3, w: Vec3) -> Vec3 {
        if self.two_sided || n.dot(w) > 0.0 {
            self.radiance
        } else {
            Vec3::ZERO
        }
    }

    /// The closest hit of `ray` on the light, with the radiance it sends
    /// back along the ray.
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<EmitterHit> {
        let (t, at) = self.shape.intersect(ray, tmin, tmax)?;
        Some(EmitterHit {
            t,
            at,
            le: self.le(at.n, -ray.dir),
        })
    }

    /// The cosine at the light point of normal `n` between the emitting
    /// side and the direction back to the shading point (`w` from the
    /// shading point); 0 if that side does not emit.
    #[inline]
    fn emitting_cos(&self, n: Vec3, w: Vec3) -> f32 {
        let c = -n.dot(w);
        if self.two_sided {
            c.abs()
        } else {
            c.max(0.0)
        }
    }

    /// See [`LightSource::sample_li`]: a point uniform over the surface
    /// (density `d²/(cos θ_light · A)` per solid angle); for a sphere a
    /// direction uniform over the cone it subtends (density `1/Ω`).
    pub fn sample_li(&self, p: Vec3, u: Vec2) -> Option<LightSample> {
        let at = match &self.shape {
            Emitter::Sphere(s) => {
                let cone = sphere_cone(s.center, s.radius, p, u)?;
                let pdf = 1.0 / cone_solid_angle(cone.cos_max, cone.sin2_max);
                return (pdf.is_finite() && pdf > 0.0).then(|| LightSample {
                    wi: cone.w,
                    li: self.radiance,
                    pdf,
                    dist: (cone.at.p - p).length(),
                    to: LightPoint::Surface(cone.at),
                    delta: false,
                });
            }
            Emitter::Quad {
                corner,
                edge1,
                edge2,
                ..
            } => quad_point(*corner, *edge1, *edge2, u).0,
            Emitter::Disk {
                center,
                radius,
                plane,
            } => disk_point(*center, plane.normal, *radius, u),
            Emitter::Triangle(t) => t.surface_at(uniform_triangle(u)),
        };
        let (w, dist2, _) = toward(p, &at)?;
        let cos = self.emitting_cos(at.n, w);
        let pdf = dist2 / (cos * self.shape.area());
        (pdf.is_finite() && pdf > 0.0).then(|| LightSample {
            wi: w,
            li: self.radiance,
            pdf,
            dist: dist2.sqrt(),
            to: LightPoint::Surface(at),
            delta: false,
        })
    }

    /// See [`LightSource::pdf_li`].
    pub fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32 {
        if let Emitter::Sphere(s) = &self.shape {
            let to_c = s.center - p;
            let d2 = to_c.length_squared();
            let sin2_max = s.radius * s.radius / d2;
            if sin2_max >= 1.0 {
                return 0.0; // inside: sample_li sends nothing
            }
            let cos_max = (1.0 - sin2_max).max(0.0).sqrt();
            let inside = wi.dot(to_c) >= cos_max * d2.sqrt();
            let pdf = 1.0 / cone_solid_angle(cos_max, sin2_max);
            return if inside && pdf.is_finite() { pdf } else { 0.0 };
        }
        let Some((t, at)) = self.shape.intersect(&Ray::new(p, wi), 0.0, f32::INFINITY) else {
            return 0.0;
        };
        let cos = self.emitting_cos(at.n, wi);
        let pdf = t * t / (cos * self.shape.area());
        if pdf.is_finite() {
            pdf
        } else {
            0.0
        }
    }
}

/// The solid angle of a cone of half-angle θ, `2π(1 − cos θ)`, written as
/// `2π·sin²θ/(1 + cos θ)`, which does not cancel for small cones.
fn cone_solid_angle(cos_max: f32, sin2_max: f32) -> f32 {
    TAU * sin2_max / (1.0 + cos_max)
}

#[cfg(test)]
mod tests;
