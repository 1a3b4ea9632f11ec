//! The Whitted ray tree: local Phong shading with shadow rays, plus one
//! reflected and one refracted child ray per hit, recursing until `bounces`
//! or until a branch's contribution drops below `weight_cutoff`.

use super::optics::{reflect, refract};
use super::{RayKind, RayObserver};
use crate::light::incident;
use crate::material::{eval, phong_light, TextureSpace};
use crate::math::{offset_origin, Ray, Vec3};
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
        let m = eval(
            &world.materials,
            hit.material,
            self.texture_point(world, hit),
        );

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
                let shadow = Ray::new(offset_origin(p, n, inc.to_light), inc.to_light);
                color +=
                    reflected * self.light_through(world, &shadow, inc.distance, depth, c, obs);
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
            let child = Ray::new(offset_origin(p, n, r), r);
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
                let child = Ray::new(offset_origin(p, n, t), t);
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

    /// The point handed to the material: the world-space hit (the 6.837
    /// scenes' texture matrices map world points) or, on request, the hit in
    /// its object's space.
    fn texture_point(&self, world: &World, hit: &Hit) -> Vec3 {
        match self.texture_space {
            TextureSpace::World => hit.point,
            TextureSpace::Object => {
                world.object_from_world[hit.instance as usize].transform_point3(hit.point)
            }
        }
    }

    /// Fraction of a light's colour that reaches the end of `shadow` at
    /// `distance`: 0 or 1 with opaque shadows; with transparent shadows the
    /// product of the `transparentColor` of everything in between.
    fn light_through(
        &self,
        world: &World,
        shadow: &Ray,
        distance: f32,
        depth: u32,
        c: &mut Counters,
        obs: &mut impl RayObserver,
    ) -> Vec3 {
        c.shadow += 1;
        if !self.transparent_shadows {
            let blocked = world.occluded(shadow, 0.0, distance, c);
            obs.shadow(shadow, distance, blocked, depth);
            return if blocked { Vec3::ZERO } else { Vec3::ONE };
        }
        let mut filter = Vec3::ONE;
        let mut ray = *shadow;
        let mut left = distance;
        // Each pass steps past one occluder; the cap guards against a ray
        // trapped between coincident surfaces.
        for _ in 0..64 {
            let Some(h) = world.intersect(&ray, 0.0, left, c) else {
                obs.ray(RayKind::Shadow, &ray, left, depth, 0.0, None);
                return filter;
            };
            obs.ray(RayKind::Shadow, &ray, h.t, depth, 0.0, Some(h.normal));
            filter *= eval(&world.materials, h.material, self.texture_point(world, &h)).transparent;
            if filter == Vec3::ZERO {
                return filter;
            }
            left -= h.t;
            ray = Ray::new(offset_origin(h.point, h.normal, ray.dir), ray.dir);
        }
        Vec3::ZERO
    }
}
