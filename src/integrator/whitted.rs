//! The Whitted ray tree: local Phong shading with shadow rays, plus one
//! reflected and one refracted child ray per hit, recursing until `bounces`
//! or until a branch's contribution drops below `weight_cutoff`.

use super::optics::{reflect, refract};
use super::{RayKind, RayObserver};
use crate::light::incident;
use crate::material::{eval, phong_light, TextureSpace};
use crate::math::{Ray, SurfacePoint, Vec3, SHADOW_EPSILON};
use crate::scene::Light;
use crate::stats::Counters;
use crate::world::{Hit, World};

/// Settings of the ray tree.
#[derive(Clone, Copy, Debug)]
pub struct Whitted {
    /// Maximum number of reflection/refraction bounces (0: local shading only).
    pub bounces: u32,
    /// Branches whose weight (product of the reflective/transparent
    /// coefficients along the path, max channel) falls below this are pruned.
    pub weight_cutoff: f32,
    /// Cast shadow rays.
    pub shadows: bool,
    /// Light the back side of surfaces (by default a back side is black).
    pub shade_back: bool,
    /// Let light through transparent occluders, filtered by their
    /// `transparentColor`, instead of the course's opaque shadows.
    pub transparent_shadows: bool,
    /// Space in which textures are looked up.
    pub texture_space: TextureSpace,
}

impl Default for Whitted {
    fn default() -> Self {
        Self {
            bounces: 0,
            weight_cutoff: 0.0,
            shadows: false,
            shade_back: false,
            transparent_shadows: false,
            texture_space: TextureSpace::World,
        }
    }
}

impl Whitted {
    /// Colour seen along `ray` (hits with `t > tmin`), and the hit itself.
    #[allow(clippy::too_many_arguments)]
    pub fn trace(
        &self,
        world: &World,
        ray: &Ray,
        tmin: f32,
        kind: RayKind,
        depth: u32,
        weight: f32,
        c: &mut Counters,
        obs: &mut impl RayObserver,
    ) -> (Vec3, Option<Hit>) {
        match kind {
            RayKind::Primary => c.primary += 1,
            RayKind::Reflected => c.reflected += 1,
            RayKind::Transmitted => c.refracted += 1,
            RayKind::Shadow => c.shadow += 1,
        }
        let hit = world.intersect(ray, tmin, f32::INFINITY, c);
        obs.ray(
            kind,
            ray,
            hit.map_or(f32::INFINITY, |h| h.t),
            depth,
            weight,
            hit.map(|h| h.normal),
        );
        match hit {
            None => (world.background.color, None),
            Some(h) => (self.shade(world, ray, &h, depth, weight, c, obs), Some(h)),
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn shade(
        &self,
        world: &World,
        ray: &Ray,
        hit: &Hit,
        depth: u32,
        weight: f32,
        c: &mut Counters,
        obs: &mut impl RayObserver,
    ) -> Vec3 {
        let d = ray.dir.normalize();
        let back = hit.normal.dot(d) > 0.0;
        if back && !self.shade_back {
            return Vec3::ZERO;
        }
        // The shading normal faces the side the ray came from.
        let n = if back { -hit.normal } else { hit.normal };
        let p = hit.point;
        let m = self.material_at(world, hit);

        let mut color = world.background.ambient * m.diffuse;
        for light in &world.lights {
            let inc = incident(light, p);
            let reflected = phong_light(&m, n, inc.to_light, -d, inc.color);
            if reflected == Vec3::ZERO {
                continue; // nothing to shadow: no shadow ray needed
            }
            // A light exactly at the point (zero direction) has nothing in
            // between, and a zero-direction shadow ray would be meaningless.
            if self.shadows && inc.to_light != Vec3::ZERO {
                let target = match light {
                    Light::Point { position, .. } => ShadowTarget::Point(*position),
                    Light::Directional { .. } => ShadowTarget::Direction(inc.to_light),
                };
                color += reflected
                    * self.light_through(world, hit.surface_point(), target, depth, c, obs);
            } else {
                color += reflected;
            }
        }

        if depth >= self.bounces {
            return color;
        }
        let refl_w = weight * m.reflective.max_element();
        if refl_w > 0.0 && refl_w >= self.weight_cutoff {
            let r = reflect(d, n);
            let child = hit.spawn_ray(r);
            let (rc, _) = self.trace(
                world,
                &child,
                0.0,
                RayKind::Reflected,
                depth + 1,
                refl_w,
                c,
                obs,
            );
            color += m.reflective * rc;
        }
        let trans_w = weight * m.transparent.max_element();
        if trans_w > 0.0 && trans_w >= self.weight_cutoff {
            // Entering or leaving is decided by the side of the geometric normal.
            let (n_i, n_t) = if back { (m.ior, 1.0) } else { (1.0, m.ior) };
            if let Some(t) = refract(d, n, n_i, n_t) {
                let child = hit.spawn_ray(t);
                let (tc, _) = self.trace(
                    world,
                    &child,
                    0.0,
                    RayKind::Transmitted,
                    depth + 1,
                    trans_w,
                    c,
                    obs,
                );
                color += m.transparent * tc;
            }
        }
        color
    }

    /// The Phong parameters at a hit. World-space lookups (the 6.837
    /// scenes' texture matrices map world points) hand the rendering-space
    /// hit to the world's materials, whose texture matrices have the move
    /// back to world space folded in; object-space lookups hand the hit in
    /// its object's space to the scene's own matrices.
    fn material_at(&self, world: &World, hit: &Hit) -> crate::scene::Phong {
        match self.texture_space {
            TextureSpace::World => eval(&world.materials, hit.material, hit.point),
            TextureSpace::Object => eval(
                &world.object_materials,
                hit.material,
                world.object_from_world[hit.instance as usize].transform_point3(hit.point),
            ),
        }
    }

    /// Fraction of a light's colour that reaches the surface point `from`
    /// from `target`: 0 or 1 with opaque shadows; with transparent shadows
    /// the product of the `transparentColor` of everything in between.
    fn light_through(
        &self,
        world: &World,
        from: SurfacePoint,
        target: ShadowTarget,
        depth: u32,
        c: &mut Counters,
        obs: &mut impl RayObserver,
    ) -> Vec3 {
        c.shadow += 1;
        if !self.transparent_shadows {
            let (shadow, tmax) = target.ray_from(&from);
            let blocked = world.occluded(&shadow, 0.0, tmax, c);
            obs.shadow(&shadow, tmax, blocked, depth);
            return if blocked { Vec3::ZERO } else { Vec3::ONE };
        }
        let mut filter = Vec3::ONE;
        let mut from = from;
        // Each pass steps past one occluder, spawning the next segment from
        // its hit; the cap guards against a ray trapped between coincident
        // surfaces.
        for _ in 0..64 {
            let (ray, tmax) = target.ray_from(&from);
            let Some(h) = world.intersect(&ray, 0.0, tmax, c) else {
                obs.ray(RayKind::Shadow, &ray, tmax, depth, 0.0, None);
                return filter;
            };
            obs.ray(RayKind::Shadow, &ray, h.t, depth, 0.0, Some(h.normal));
            filter *= self.material_at(world, &h).transparent;
            if filter == Vec3::ZERO {
                return filter;
            }
            from = h.surface_point();
        }
        Vec3::ZERO
    }
}

/// Where a shadow ray goes.
#[derive(Clone, Copy, Debug)]
enum ShadowTarget {
    /// A point light at this (rendering-space) position.
    Point(Vec3),
    /// Infinitely far along this unit direction.
    Direction(Vec3),
}

impl ShadowTarget {
    /// The shadow ray from `from` and the `tmax` it is traced to: a point
    /// light's ray ends at the light (`t = 1`), kept `SHADOW_EPSILON` short
    /// of it so a surface the light sits on does not shadow it.
    fn ray_from(self, from: &SurfacePoint) -> (Ray, f32) {
        match self {
            ShadowTarget::Point(p) => (from.spawn_ray_to(p), 1.0 - SHADOW_EPSILON),
            ShadowTarget::Direction(d) => (from.spawn_ray(d), f32::INFINITY),
        }
    }
}
