//! Unidirectional path tracing (Kajiya 1986) with next-event estimation and
//! multiple importance sampling (Veach 1997, the power heuristic) between
//! light sampling and BSDF sampling.
//!
//! At every vertex the path takes one light sample (a light chosen with
//! probability proportional to its power, [`LightChoice`]; a point or
//! direction of it) and one BSDF sample (which lobe, which direction); the
//! BSDF sample continues the path. Light found by
//! either strategy is weighted by the power heuristic of the two densities,
//! so each path of light is counted once:
//! - delta lights (point, directional) only through light sampling (a ray
//!   never hits them), weight 1;
//! - delta lobes (mirror, clear glass) only through BSDF sampling (light
//!   sampling cannot find their direction), weight 1;
//! - emitters that cannot be sampled (emission on a plane, a transformed or
//!   moving shape) and the background's uniform environment only through
//!   BSDF sampling, weight 1.
//!
//! Emitters that can be sampled are the triangles (single or of meshes) and
//! spheres whose material has an `emittedColor`: a triangle by area, a
//! sphere by the cone of directions it fills as seen from the point; and
//! the scene's `AreaLight`s (quad, disk, sphere), which are not in the
//! aggregate: a ray crossing one before its hit
//! (`World::intersect_emitters`) adds its emission, weighted by MIS, and
//! goes on, since they block no ray (shadow rays pass through them too).
//!
//! **Sample dimensions.** Every vertex takes the same [`DIMS_PER_VERTEX`]
//! dimensions of the pixel's [`SampleStream`](crate::sampler::SampleStream) in the same order, used or
//! not (light choice, light point, lobe, direction, roulette), so dimension
//! `k` of a pixel's samples means the same decision in every path and the
//! sampler's stratification reaches every bounce. The image depends on
//! nothing but the streams: it is the same for any thread count, tile order
//! or piece split.
//!
//! **Caustic map.** With photons in `PathSettings::caustic_map`, the light
//! of emitting primitives and area lights that reaches a non-delta vertex through delta
//! lobes comes from a caustic photon map ([`super::caustic_map`]), added
//! at every non-delta vertex, and the paths that find it are not counted
//! again: consistent, not unbiased (docs/path-tracing.md).
//!
//! **Depth.** `max_bounces` counts scattering events: 0 shows the emitters
//! seen directly, 1 adds direct lighting, each further one a bounce of
//! indirect light (Mitsuba's `max_depth` is one more). Russian roulette
//! after `rr_depth` scattering events lets a path survive with probability
//! `min(0.95, rr_scale · max β)` (β: the path's throughput) and divides
//! the survivors by it: unbiased. The scale 2 (not the usual 1) keeps
//! paths whose throughput has fallen to a half: on the caustic Cornell box
//! it lowers the variance at equal samples by a third for 10% more rays
//! (docs/path-tracing.md).

use super::caustic_map::{CausticMap, CausticSettings, Emits, Source};
use super::{Branch, Integrator, RayKind, RayObserver, Trace};
use crate::bsdf::Bsdf;
use crate::light::{incident, LightPoint};
use crate::material::{eval, TextureSpace};

use crate::math::warp::uniform_triangle;
use crate::math::{Ray, Spawn, SurfacePoint, Vec2, Vec3, SHADOW_EPSILON};
use crate::scene::{Light, Material, Phong};
use crate::shape::Shape;
use crate::world::{Hit, World};
use std::f32::consts::{PI, TAU};

/// Stream dimensions every path vertex takes: light choice (1-D), light
/// point (2-D), lobe (1-D), direction (2-D), roulette (1-D).
pub const DIMS_PER_VERTEX: u32 = 5;

/// Which strategies find the light: both weighted by MIS (the default), or
/// one alone (for comparisons; each alone converges to the same image
/// wherever it can find the light at all).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Strategy {
    /// Light and BSDF sampling, weighted by the power heuristic.
    #[default]
    Mis,
    /// Light sampling only (emitters hit by a BSDF ray after a non-delta
    /// bounce count nothing, unless light sampling cannot find them).
    Light,
    /// BSDF sampling only (no shadow rays: delta lights are never found).
    Bsdf,
}

/// How light sampling chooses which light to sample. Either is unbiased
/// (every light that sends anything has a non-zero probability, and the
/// sample is divided by it); they differ in noise.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightChoice {
    /// Each light with probability proportional to an estimate of its
    /// power ([`PathTracer::light_power`]): a bright small light is sampled
    /// more often than a dim large wall of emitting triangles.
    #[default]
    Power,
    /// Every light with the same probability.
    Uniform,
}

/// Which caustic paths the image keeps: light that reaches a non-delta
/// scattering vertex through one or more delta lobes (mirror, glass) from
/// an emitter or the environment, which only BSDF sampling finds. All of
/// them (the default, unbiased); the others drop some, for measuring how
/// much of the noise they carry (docs/path-tracing.md), and lose their
/// light (biased).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CausticPaths {
    /// Every path.
    #[default]
    Keep,
    /// Without the caustics seen directly: those whose non-delta vertex
    /// is the camera ray's hit.
    DropSeen,
    /// Without any caustic path, at any depth.
    DropAll,
}

/// The path tracer's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSettings {
    /// Most scattering events on a path (see the module documentation).
    pub max_bounces: u32,
    /// Bounces before Russian roulette may end a path.
    pub rr_depth: u32,
    /// Russian roulette's survival probability over the throughput's
    /// largest channel (at most 0.95; see the module documentation).
    pub rr_scale: f32,
    /// Which strategies are used.
    pub strategy: Strategy,
    /// How light sampling chooses a light.
    pub light_choice: LightChoice,
    /// Where textures are looked up.
    pub texture_space: TextureSpace,
    /// Which caustic paths count ([`CausticPaths::Keep`]: all).
    pub caustics: CausticPaths,
    /// The caustic photon map: with photons, the caustics from emitting
    /// primitives come from it instead of from paths
    /// ([`super::caustic_map`]).
    pub caustic_map: CausticSettings,
}

impl Default for PathSettings {
    /// 64 bounces, roulette from the fourth with survival `min(0.95,
    /// 2·max β)`, MIS, lights chosen by power, world-space textures.
    fn default() -> Self {
        Self {
            max_bounces: 64,
            rr_depth: 3,
            rr_scale: 2.0,
            strategy: Strategy::Mis,
            light_choice: LightChoice::Power,
            texture_space: TextureSpace::World,
            caustics: CausticPaths::Keep,
            caustic_map: CausticSettings::default(),
        }
    }
}

/// An emitting primitive that light sampling can choose.
#[derive(Clone, Copy, Debug)]
enum Emitter {
    /// A triangle: its primitive and area.
    Triangle { prim: u32, area: f32 },
    /// A sphere's primitive.
    Sphere { prim: u32 },
}

/// The path tracer for one world: its settings and the emitters found in
/// the world's primitives.
#[derive(Clone, Debug)]
pub struct PathTracer {
    /// Settings.
    pub settings: PathSettings,
    emitters: Vec<Emitter>,
    /// For each primitive, its index in `emitters` (`u32::MAX`: none).
    emitter_of_prim: Vec<u32>,
    /// `emitters.len() + world.lights().len()`.
    light_count: usize,
    /// Probability of choosing each light (emitters first, then the
    /// scene's lights), summing to 1 (all 0 when no light sends anything).
    pmf: Vec<f32>,
    /// Running sums of `pmf`, the last exactly 1.
    cdf: Vec<f32>,
    /// The caustic photon map, when its settings ask for photons.
    caustic_map: Option<std::sync::Arc<CausticMap>>,
}

/// A light sample: direction, radiance arriving divided by nothing, the
/// density per unit solid angle of the direction including the choice of
/// the light (0 for delta lights, whose `radiance` is what arrives), and
/// where the shadow ray goes.
struct LightSample {
    wi: Vec3,
    radiance: Vec3,
    pdf: f32,
    target: Target,
}

#[derive(Clone, Copy)]
enum Target {
    Point(Vec3),
    Direction(Vec3),
    Surface(SurfacePoint),
}

/// The largest emission a material can have anywhere (a texture blends
/// its two entries).
fn max_emission(materials: &[Material], index: usize, depth: u32) -> Vec3 {
    match materials.get(index) {
        Some(Material::Phong(p)) => p.emission,
        Some(Material::Texture { a, b, .. }) if depth < 64 => {
            max_emission(materials, *a, depth + 1).max(max_emission(materials, *b, depth + 1))
        }
        _ => Vec3::ZERO,
    }
}

/// The power heuristic (β = 2) weight of a strategy of density `a` against
/// one of density `b`.
#[inline]
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 && (a2 + b2).is_finite() {
        a2 / (a2 + b2)
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}

impl PathTracer {
    /// The path tracer for `world`: finds its emitting triangles and spheres.
    pub fn new(world: &World, settings: PathSettings) -> Self {
        let mut emitters = Vec::new();
        let mut emitter_of_prim = vec![u32::MAX; world.prims().len()];
        for (i, p) in world.prims().iter().enumerate() {
            if max_emission(world.materials(), p.material as usize, 0).max_element() <= 0.0 {
                continue;
            }
            let e = match &p.shape {
                Shape::Triangle(t) if !t.is_degenerate() => {
                    let [a, b, c] = t.v;
                    let area = 0.5 * (b - a).cross(c - a).length();
                    (area > 0.0).then_some(Emitter::Triangle {
                        prim: i as u32,
                        area,
                    })
                }
                Shape::Sphere(_) => Some(Emitter::Sphere { prim: i as u32 }),
                _ => None,
            };
            if let Some(e) = e {
                emitter_of_prim[i] = emitters.len() as u32;
                emitters.push(e);
            }
        }
        let light_count = emitters.len() + world.lights().len();
        let mut tracer = Self {
            settings,
            emitters,
            emitter_of_prim,
            light_count,
            pmf: Vec::new(),
            cdf: Vec::new(),
            caustic_map: None,
        };
        let weights: Vec<f64> = (0..light_count)
            .map(|k| match settings.light_choice {
                LightChoice::Power => tracer.light_power(world, k) as f64,
                LightChoice::Uniform => 1.0,
            })
            .map(|w| if w.is_finite() && w > 0.0 { w } else { 0.0 })
            .collect();
        let total: f64 = weights.iter().sum();
        if total > 0.0 {
            let mut run = 0.0;
            for w in &weights {
                run += w;
                tracer.pmf.push((w / total) as f32);
                tracer.cdf.push((run / total) as f32);
            }
            // The last light with any weight ends at exactly 1.
            if let Some(k) = weights.iter().rposition(|&w| w > 0.0) {
                for c in &mut tracer.cdf[k..] {
                    *c = 1.0;
                }
            }
        } else {
            tracer.pmf = vec![0.0; light_count];
            tracer.cdf = vec![1.0; light_count];
        }
        // (No delta lobe anywhere: no caustic, no photon pass.)
        let delta = world.materials().iter().any(|m| match m {
            Material::Phong(p) => Bsdf::from_phong(p, Vec3::Z)
                .lobes()
                .iter()
                .any(|l| l.is_delta()),
            _ => false,
        });
        if settings.caustic_map.photons > 0 && delta {
            tracer.caustic_map = tracer.build_caustic_map(world);
        }
        tracer
    }

    /// The caustic photon map of the emitting primitives and the scene's
    /// area lights, each chosen by its power; `None` when none sends
    /// anything.
    fn build_caustic_map(&self, world: &World) -> Option<std::sync::Arc<CausticMap>> {
        let mut sources: Vec<Source> = Vec::new();
        for (k, e) in self.emitters.iter().enumerate() {
            let prim = match *e {
                Emitter::Triangle { prim, .. } | Emitter::Sphere { prim } => prim,
            };
            let m = world.prims()[prim as usize].material as usize;
            sources.push(Source {
                from: Emits::Prim(prim),
                emission: max_emission(world.materials(), m, 0),
                probability: self.light_power(world, k),
            });
        }
        for (i, light) in world.lights().iter().enumerate() {
            if let Light::Area {
                shape,
                color,
                power,
            } = light
            {
                sources.push(Source {
                    from: Emits::Area(*shape),
                    emission: crate::light::area::radiance(shape, *color, *power),
                    probability: self.light_power(world, self.emitters.len() + i),
                });
            }
        }
        for s in &mut sources {
            if !(s.probability.is_finite() && s.probability > 0.0) {
                s.probability = 0.0;
            }
        }
        let total: f32 = sources.iter().map(|s| s.probability).sum();
        if total <= 0.0 {
            return None;
        }
        for s in &mut sources {
            s.probability /= total;
        }
        let material = |material: u32, instance: u32, p: Vec3| {
            let mut scratch = None;
            *self.material(world, material, instance, p, &mut scratch)
        };
        Some(std::sync::Arc::new(CausticMap::build(
            world,
            &sources,
            self.settings.caustic_map,
            material,
        )))
    }

    /// The caustic photon map, if the settings asked for one.
    pub fn caustic_map(&self) -> Option<&CausticMap> {
        self.caustic_map.as_deref()
    }

    /// An estimate of the power light `k` sends (emitters first, then the
    /// scene's lights), in units of the channel mean of its colour, for
    /// choosing lights: an emitting triangle `π·A·L`, an emitting sphere
    /// `4π²r²·L`, an `AreaLight` its `power`, a point light `4π·I`, a
    /// directional light `π·R²·E` over the disk of the world's bounding
    /// sphere (radius `R`). Delta lights and surfaces are weighed on one
    /// scale only roughly; any positive weights keep the estimate unbiased.
    pub fn light_power(&self, world: &World, k: usize) -> f32 {
        let mean = |c: Vec3| c.max(Vec3::ZERO).element_sum() / 3.0;
        if let Some(e) = self.emitters.get(k) {
            let (prim, size) = match *e {
                Emitter::Triangle { prim, area } => (prim, PI * area),
                Emitter::Sphere { prim } => match &world.prims()[prim as usize].shape {
                    Shape::Sphere(s) => (prim, 4.0 * PI * PI * s.radius * s.radius),
                    _ => return 0.0,
                },
            };
            let m = world.prims()[prim as usize].material as usize;
            return size * mean(max_emission(world.materials(), m, 0));
        }
        match world.lights().get(k - self.emitters.len()) {
            Some(Light::Area { color, power, .. }) => power.max(0.0) * mean(*color),
            Some(Light::Point { color, .. }) => 4.0 * PI * mean(*color),
            Some(Light::Directional { color, .. }) => {
                let b = world.bounds();
                let r = if b.is_finite() && !b.is_empty() {
                    0.5 * b.extent().length()
                } else {
                    1.0
                };
                PI * r * r * mean(*color)
            }
            None => 0.0,
        }
    }

    /// The probability with which light sampling chooses light `k`
    /// (emitters first, then the scene's lights).
    pub fn light_probability(&self, k: usize) -> f32 {
        self.pmf.get(k).copied().unwrap_or(0.0)
    }

    /// The light that `uc ∈ [0, 1)` chooses, and its probability.
    fn choose_light(&self, uc: f32) -> Option<(usize, f32)> {
        let k = self.cdf.partition_point(|&c| c <= uc);
        let p = *self.pmf.get(k)?;
        (p > 0.0).then_some((k, p))
    }

    /// How many lights light sampling chooses from (emitting primitives
    /// and the scene's lights).
    pub fn light_count(&self) -> usize {
        self.light_count
    }

    /// The material at a point of primitive `material`/`instance`: a plain
    /// one read in place from the world's table, a texture evaluated into
    /// `scratch`. (Returned by value, the material was copied through the
    /// stack and read back across the copy's stores, a store-forwarding
    /// stall: perf put a tenth of `li`'s time on the load after it.)
    #[inline]
    fn material<'a>(
        &self,
        world: &'a World,
        material: u32,
        instance: u32,
        p: Vec3,
        scratch: &'a mut Option<Phong>,
    ) -> &'a Phong {
        let table = match self.settings.texture_space {
            TextureSpace::World => world.materials(),
            TextureSpace::Object => world.object_materials(),
        };
        if let Some(Material::Phong(m)) = table.get(material as usize) {
            return m;
        }
        scratch.insert(match self.settings.texture_space {
            TextureSpace::World => eval(table, material, p),
            TextureSpace::Object => eval(
                table,
                material,
                world.object_from_world()[instance as usize].transform_point3(p),
            ),
        })
    }

    /// Radiance an emitting surface sends from `hit` back along `ray`
    /// (front side only).
    fn emitted(&self, m: &Phong, hit: &Hit, ray: &Ray) -> Vec3 {
        if m.emission != Vec3::ZERO && hit.normal.dot(ray.dir) < 0.0 {
            m.emission
        } else {
            Vec3::ZERO
        }
    }

    /// The density per unit solid angle with which light sampling from `p`
    /// would have chosen the point `hit` of an emitter (including the
    /// choice of the light); 0 if it could not.
    fn pdf_light(&self, world: &World, p: Vec3, hit: &Hit) -> f32 {
        let Some(&k) = self.emitter_of_prim.get(hit.prim as usize) else {
            return 0.0;
        };
        let Some(e) = self.emitters.get(k as usize) else {
            return 0.0;
        };
        let choose = self.light_probability(k as usize);
        match *e {
            Emitter::Triangle { area, .. } => {
                let d = hit.point - p;
                let cos = hit.normal.dot(d).abs() / d.length();
                if cos <= 0.0 {
                    0.0
                } else {
                    choose * d.length_squared() / (cos * area)
                }
            }
            Emitter::Sphere { prim } => match &world.prims()[prim as usize].shape {
                Shape::Sphere(s) => choose * cone_pdf(p, s.center, s.radius),
                _ => 0.0,
            },
        }
    }

    /// One light sample from the point `from` (light chosen by `uc`, point
    /// by `u`): `None` when the light sends nothing there.
    fn sample_light(
        &self,
        world: &World,
        from: Vec3,
        uc: f32,
        u: Vec2,
    ) -> Option<(LightSample, f32)> {
        let (k, choose) = self.choose_light(uc)?;
        if let Some(e) = self.emitters.get(k) {
            let (prim, y) = match *e {
                Emitter::Triangle { prim, .. } => {
                    let Shape::Triangle(t) = &world.prims()[prim as usize].shape else {
                        return None;
                    };
                    (prim, t.surface_at(uniform_triangle(u)))
                }
                Emitter::Sphere { prim } => {
                    let Shape::Sphere(s) = &world.prims()[prim as usize].shape else {
                        return None;
                    };
                    (prim, sample_sphere_cone(from, s.center, s.radius, u)?)
                }
            };
            let d = y.p - from;
            let dist2 = d.length_squared();
            if dist2 <= 0.0 || !dist2.is_finite() {
                return None;
            }
            let wi = d / dist2.sqrt();
            // Front side only: the emitter's normal must face the point.
            if y.n.dot(wi) >= 0.0 {
                return None;
            }
            let p = &world.prims()[prim as usize];
            let mut scratch = None;
            let m = self.material(world, p.material, p.instance, y.p, &mut scratch);
            if m.emission == Vec3::ZERO {
                return None;
            }
            let hit = Hit {
                t: 0.0,
                point: y.p,
                error: y.error,
                normal: y.n,
                shading_normal: y.n,
                prim,
                material: p.material,
                instance: p.instance,
            };
            let pdf = self.pdf_light(world, from, &hit);
            if !(pdf > 0.0 && pdf.is_finite()) {
                return None;
            }
            return Some((
                LightSample {
                    wi,
                    radiance: m.emission,
                    pdf,
                    target: Target::Surface(y),
                },
                choose,
            ));
        }
        let index = k - self.emitters.len();
        let light = &world.lights()[index];
        let (inc, target) = match light {
            Light::Area { .. } => {
                // Sampled as a surface that BSDF sampling can also hit
                // (`World::intersect_emitters`): the density per solid
                // angle, for MIS.
                let ls = world.light_sources().get(index)?.sample_li(from, u)?;
                let (LightPoint::Surface(at), true) = (ls.to, ls.pdf > 0.0 && ls.pdf.is_finite())
                else {
                    return None;
                };
                if ls.li == Vec3::ZERO {
                    return None;
                }
                return Some((
                    LightSample {
                        wi: ls.wi,
                        radiance: ls.li,
                        pdf: choose * ls.pdf,
                        target: Target::Surface(at),
                    },
                    choose,
                ));
            }
            Light::Point { position, .. } => (incident(light, from), Target::Point(*position)),
            Light::Directional { .. } => {
                let inc = incident(light, from);
                (inc, Target::Direction(inc.to_light))
            }
        };
        if inc.to_light == Vec3::ZERO || inc.color == Vec3::ZERO {
            return None;
        }
        Some((
            LightSample {
                wi: inc.to_light,
                radiance: inc.color,
                pdf: 0.0,
                target,
            },
            choose,
        ))
    }
}

/// Whether the shadow ray from `from` to a light sample's target is
/// blocked (counted and shown to the observer as a shadow ray).
fn occluded<O: RayObserver>(
    cx: &mut Trace<O>,
    from: &mut Spawn,
    target: Target,
    time: f32,
    depth: u32,
) -> bool {
    let (ray, tmax) = match target {
        Target::Point(p) => (from.spawn_ray_to(p), 1.0 - SHADOW_EPSILON),
        Target::Direction(d) => (from.spawn_ray(d), f32::INFINITY),
        Target::Surface(s) => (from.spawn_ray_to_surface(&s), 1.0 - SHADOW_EPSILON),
    };
    cx.blocked(&ray.at_time(time), tmax, from.leaving, depth)
}

/// The density per unit solid angle of [`sample_sphere_cone`] from `p`
/// (0 from inside the sphere, which emits outwards only).
fn cone_pdf(p: Vec3, center: Vec3, radius: f32) -> f32 {
    let d2 = (center - p).length_squared();
    let r2 = radius * radius;
    if d2 <= r2 {
        return 0.0;
    }
    let sin2 = r2 / d2;
    let cos_max = (1.0 - sin2).max(0.0).sqrt();
    // 1 − cos θmax without cancellation for small spheres.
    let one_minus = sin2 / (1.0 + cos_max);
    1.0 / (TAU * one_minus)
}

/// A point of the sphere seen from `p`: a direction uniform in the cone
/// the sphere fills (density [`cone_pdf`]), and where it meets the sphere
/// (the area lights' sampling, `light::area::sphere_cone`).
fn sample_sphere_cone(p: Vec3, center: Vec3, radius: f32, u: Vec2) -> Option<SurfacePoint> {
    crate::light::area::sphere_cone(center, radius, p, u).map(|s| s.at)
}

impl Integrator for PathTracer {
    fn li_hit<O: RayObserver>(
        &self,
        cx: &mut Trace<O>,
        camera_ray: &Ray,
        tmin: f32,
        camera_hit: Option<&Hit>,
    ) -> Vec3 {
        let world = cx.world;
        let s = &self.settings;
        let background = world.background().color;
        let mut radiance = Vec3::ZERO;
        let mut beta = Vec3::ONE;
        let mut ray = *camera_ray;
        let mut ray_tmin = tmin;
        let mut kind = RayKind::Primary;
        // The previous vertex: where the ray left, the BSDF density of its
        // direction, and whether it came from a delta lobe.
        let mut prev: Option<(Vec3, f32, bool)> = None;
        let mut depth = 0u32;
        // Whether the last non-delta vertex starts caustics that
        // `settings.caustics` drops, and whether light found now (through
        // delta lobes since that vertex) is one.
        let (mut from_dropping, mut dropped) = (false, false);
        // Whether light found now reached the path through delta lobes
        // since a non-delta vertex: the caustic map's light, when there is
        // one (then the emitting primitives' light is not added again).
        let (mut from_mapped, mut mapped) = (false, false);
        // The camera ray's hit is given; the path's other rays are traced.
        let mut given = Some(camera_hit);
        loop {
            let weight = beta.max_element();
            let hit = match given.take() {
                Some(hit) => hit.copied(),
                None => cx.closest(
                    &ray,
                    ray_tmin,
                    Branch {
                        kind,
                        depth,
                        weight,
                    },
                ),
            };
            // The scene's area lights: emitting surfaces that do not block
            // (shadow rays pass through them too), crossed before the hit.
            let t_hit = hit.map_or(f32::INFINITY, |h| h.t);
            let mut t_from = ray_tmin;
            while let Some((i, eh)) = world.intersect_emitters(&ray, t_from, t_hit) {
                t_from = eh.t;
                if eh.le == Vec3::ZERO {
                    continue;
                }
                // (Caustics of the area lights come from the map, if any.)
                if dropped || mapped {
                    continue;
                }
                let w = match prev {
                    None | Some((_, _, true)) => 1.0,
                    Some((p, pdf_bsdf, false)) => {
                        let pdf_light = self.light_probability(self.emitters.len() + i as usize)
                            * world.light_sources()[i as usize].pdf_li(p, ray.dir.normalize());
                        match s.strategy {
                            _ if pdf_light <= 0.0 => 1.0,
                            Strategy::Mis => power_heuristic(pdf_bsdf, pdf_light),
                            Strategy::Light => 0.0,
                            Strategy::Bsdf => 1.0,
                        }
                    }
                };
                radiance += beta * eh.le * w;
                cx.observer.light(w, beta * eh.le * w);
            }
            let Some(h) = hit else {
                // The uniform environment: found only by BSDF sampling.
                if dropped {
                    break;
                }
                radiance += beta * background;
                if background != Vec3::ZERO {
                    cx.observer.light(1.0, beta * background);
                }
                break;
            };
            let mut scratch = None;
            let m = self.material(world, h.material, h.instance, h.point, &mut scratch);
            let le = self.emitted(m, &h, &ray);
            let skip = mapped
                && self
                    .emitter_of_prim
                    .get(h.prim as usize)
                    .is_some_and(|&k| k != u32::MAX);
            if le != Vec3::ZERO && !dropped && !skip {
                let w = match prev {
                    None | Some((_, _, true)) => 1.0,
                    Some((p, pdf_bsdf, false)) => {
                        let pdf_light = self.pdf_light(world, p, &h);
                        match s.strategy {
                            _ if pdf_light <= 0.0 => 1.0,
                            Strategy::Mis => power_heuristic(pdf_bsdf, pdf_light),
                            Strategy::Light => 0.0,
                            Strategy::Bsdf => 1.0,
                        }
                    }
                };
                radiance += beta * le * w;
                cx.observer.light(w, beta * le * w);
            }
            if depth >= s.max_bounces {
                break;
            }
            // This vertex's dimensions, taken whether used or not, and
            // computed only where used: light choice, light point, lobe,
            // direction, roulette.
            let dim = cx.stream.dimension();
            cx.stream.skip_n(DIMS_PER_VERTEX);

            let bsdf = Bsdf::from_phong(m, h.normal);
            let wo = -ray.dir.normalize();
            let mut spawn = Spawn::leaving(h.surface_point(), h.prim);
            if let (Some(map), false) = (&self.caustic_map, bsdf.is_delta()) {
                let c = beta * map.radiance(h.point, h.normal, wo, &bsdf);
                if c != Vec3::ZERO {
                    radiance += c;
                    cx.observer.light(1.0, c);
                }
            }
            if s.strategy != Strategy::Bsdf && !bsdf.is_delta() {
                if let Some((ls, choose)) = self.sample_light(
                    world,
                    h.point,
                    cx.stream.get_1d(dim),
                    cx.stream.get_2d(dim + 1),
                ) {
                    let f = bsdf.f(wo, ls.wi);
                    let cos = ls.wi.dot(h.normal).abs();
                    if f != Vec3::ZERO && cos > 0.0 {
                        let blocked = occluded(cx, &mut spawn, ls.target, ray.time, depth + 1);
                        // The MIS weight; only light sampling finds delta
                        // lights, whose `radiance` is what arrives.
                        let w = match s.strategy {
                            Strategy::Mis if ls.pdf > 0.0 => {
                                power_heuristic(ls.pdf, bsdf.pdf(wo, ls.wi))
                            }
                            _ => 1.0,
                        };
                        if blocked {
                            cx.observer.light(w, Vec3::ZERO);
                        } else {
                            let contribution = beta
                                * if ls.pdf > 0.0 {
                                    f * cos * ls.radiance * (w / ls.pdf)
                                } else {
                                    f * cos * ls.radiance / choose
                                };
                            radiance += contribution;
                            cx.observer.light(w, contribution);
                        }
                    }
                }
            }
            // One lobe needs no choice.
            let u_lobe = if bsdf.lobes().len() > 1 {
                cx.stream.get_1d(dim + 2)
            } else {
                0.0
            };
            let Some(bs) = bsdf.sample_f(wo, u_lobe, cx.stream.get_2d(dim + 3)) else {
                break;
            };
            let weight = bs.weight(h.normal);
            if !(weight.is_finite() && weight.max_element() > 0.0) {
                break;
            }
            beta *= weight;
            depth += 1;
            if depth > s.rr_depth {
                let survive = (beta.max_element() * s.rr_scale).min(0.95);
                if cx.stream.get_1d(dim + 4) >= survive {
                    break;
                }
                beta /= survive;
            }
            kind = if bs.wi.dot(h.normal) * wo.dot(h.normal) < 0.0 {
                RayKind::Transmitted
            } else {
                RayKind::Reflected
            };
            // (`depth` is already this vertex's depth + 1.)
            if !bs.delta {
                from_dropping = match s.caustics {
                    CausticPaths::Keep => false,
                    CausticPaths::DropSeen => depth == 1,
                    CausticPaths::DropAll => true,
                };
            }
            dropped = from_dropping && bs.delta;
            from_mapped |= !bs.delta && self.caustic_map.is_some();
            mapped = from_mapped && bs.delta;
            prev = Some((h.point, bs.pdf, bs.delta));
            ray = spawn.spawn_ray(bs.wi).at_time(camera_ray.time);
            ray_tmin = 0.0;
        }
        radiance
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A world of two emitting triangles (a 2 × 1 rectangle of radiance
    /// 1), a small bright sphere (radius 0.1, radiance 40), a dark
    /// emitter, and the scene's lights: a point light, a directional light
    /// and an `AreaLight`.
    fn lights_world() -> World {
        let text = "PerspectiveCamera { center 0 1 5 direction 0 0 -1 up 0 1 0 angle 40 }\n\
            Lights { numLights 3\n\
              PointLight { position 0 3 0 color 2 2 2 }\n\
              DirectionalLight { direction 0 -1 0 color 0.5 0.5 0.5 }\n\
              AreaLight { quad { corner -1 4 -1 edge1 2 0 0 edge2 0 0 2 } color 1 1 1 power 30 }\n\
            }\n\
            Background { color 0 0 0 }\n\
            Materials { numMaterials 3\n\
              PhongMaterial { diffuseColor 0 0 0 emittedColor 1 1 1 }\n\
              PhongMaterial { diffuseColor 0 0 0 emittedColor 40 40 40 }\n\
              PhongMaterial { diffuseColor 0.5 0.5 0.5 }\n\
            }\n\
            Group { numObjects 4\n\
              MaterialIndex 0\n\
              Triangle { vertex0 -1 0 -2 vertex1 1 0 -2 vertex2 1 1 -2 }\n\
              Triangle { vertex0 -1 0 -2 vertex1 1 1 -2 vertex2 -1 1 -2 }\n\
              MaterialIndex 1 Sphere { center 0 2 0 radius 0.1 }\n\
              MaterialIndex 2 Sphere { center 0 0 0 radius 0.5 }\n\
            }\n";
        let scene = crate::format::parse_scene(text, std::path::Path::new("lights.txt")).unwrap();
        World::build(&scene, crate::world::BuildOptions::default())
    }

    /// Choosing lights by power: the probabilities sum to 1, follow the
    /// power estimates (the bright small sphere of power 4π²·0.01·40 is
    /// chosen more often than the dim triangles of π·1·1 each), the choice
    /// made by `uc` over a fine grid picks each light with its
    /// probability, and `pdf_light` reports the probability it chooses
    /// with. Uniform choice gives every light 1/n.
    #[test]
    fn lights_are_chosen_by_power_with_the_probability_reported() {
        let world = lights_world();
        for choice in [LightChoice::Power, LightChoice::Uniform] {
            let settings = PathSettings {
                light_choice: choice,
                ..PathSettings::default()
            };
            let pt = PathTracer::new(&world, settings);
            let n = pt.light_count();
            assert_eq!(n, 3 + 3, "two triangles, a sphere and three lights");
            let probs: Vec<f32> = (0..n).map(|k| pt.light_probability(k)).collect();
            let sum: f32 = probs.iter().sum();
            assert!((sum - 1.0).abs() < 1e-6, "{choice:?}: {probs:?}");
            let powers: Vec<f32> = (0..n).map(|k| pt.light_power(&world, k)).collect();
            let total: f32 = powers.iter().sum();
            for k in 0..n {
                let want = match choice {
                    LightChoice::Power => powers[k] / total,
                    LightChoice::Uniform => 1.0 / n as f32,
                };
                assert!((probs[k] - want).abs() < 1e-6, "{choice:?} {k}: {probs:?}");
            }
            if choice == LightChoice::Power {
                assert!((powers[0] - PI).abs() < 1e-4, "{powers:?}");
                let sphere = 4.0 * PI * PI * 0.01 * 40.0;
                assert!((powers[2] - sphere).abs() < 1e-3 * sphere, "{powers:?}");
                assert!((powers[5] - 30.0).abs() < 1e-4, "{powers:?}");
                assert!(probs[2] > probs[0], "{probs:?}");
            }
            // The choice by a fine grid of `uc` picks each light with its
            // probability.
            let m = 100_000;
            let mut count = vec![0u32; n];
            for i in 0..m {
                let (k, p) = pt.choose_light((i as f32 + 0.5) / m as f32).unwrap();
                assert_eq!(p, probs[k]);
                count[k] += 1;
            }
            for k in 0..n {
                let f = count[k] as f32 / m as f32;
                assert!(
                    (f - probs[k]).abs() < 1e-4,
                    "{choice:?} {k}: {f} vs {}",
                    probs[k]
                );
            }
            // pdf_light of a point of the sphere includes its probability
            // (the world is in rendering space: the sphere as built).
            let Shape::Sphere(sphere) = &world.prims()[2].shape else {
                panic!("primitive 2 is the emitting sphere");
            };
            let (c, r) = (sphere.center, sphere.radius);
            let from = c + Vec3::new(0.0, -2.0, 2.0);
            let y = sample_sphere_cone(from, c, r, Vec2::splat(0.3)).unwrap();
            let hit = Hit {
                t: 1.0,
                point: y.p,
                error: y.error,
                normal: y.n,
                shading_normal: y.n,
                prim: 2,
                material: 1,
                instance: 0,
            };
            let want = probs[2] * cone_pdf(from, c, r);
            let got = pt.pdf_light(&world, from, &hit);
            assert!((got - want).abs() < 1e-5 * want, "{got} vs {want}");
        }
    }

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        for (a, b) in [(1.0, 1.0), (0.3, 7.0), (5.0, 0.0), (0.0, 2.0)] {
            let s = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((s - 1.0).abs() < 1e-6, "{a} {b}");
        }
        assert_eq!(power_heuristic(f32::INFINITY, 1.0), 1.0);
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
    }

    /// The cone's directions: the density integrates to 1 over the cone
    /// (uniform in solid angle, so it is 1/solid angle), and every sampled
    /// point lies on the sphere's near side.
    #[test]
    fn sphere_cone_samples_the_visible_cap() {
        let (c, r) = (Vec3::new(0.0, 0.0, -4.0), 1.0);
        let p = Vec3::ZERO;
        let pdf = cone_pdf(p, c, r);
        let cos_max = (1.0f32 - 1.0 / 16.0).sqrt();
        assert!((pdf - 1.0 / (TAU * (1.0 - cos_max))).abs() / pdf < 1e-4);
        let k = 32;
        for i in 0..k {
            for j in 0..k {
                let u = Vec2::new((i as f32 + 0.5) / k as f32, (j as f32 + 0.5) / k as f32);
                let y = sample_sphere_cone(p, c, r, u).unwrap();
                assert!(((y.p - c).length() - r).abs() < 1e-5);
                // Visible from p: the normal faces p.
                assert!(y.n.dot(p - y.p) >= -1e-4, "{y:?}");
            }
        }
        assert_eq!(cone_pdf(c, c, r), 0.0);
    }
}
