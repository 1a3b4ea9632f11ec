//! The Whitted ray tree: local Phong shading with shadow rays, plus one
//! reflected and one refracted child ray per hit, recursing until `bounces`
//! or until a branch's contribution drops below `weight_cutoff`.
//!
//! With distribution effects it is Cook's distribution ray tracer: area
//! lights get `shadow_samples` shadow rays stratified over their surface,
//! glossy materials `glossy_samples` rays over their lobe, and the ambient
//! term an ambient-occlusion factor; every choice is a dimension of the
//! camera sample's stream. Without them (point and directional lights,
//! mirrors, no AO) the tree takes no stream dimension and is exactly the
//! classic one.

use super::ao::{unoccluded, AoSettings};
use super::optics::{reflect, refract};
use super::{Branch, RayKind, RayObserver, Trace};
use crate::accel::{PacketRay, PACKET};
use crate::light::{is_delta, prepare_area, sample_light, Incident};
use crate::material::glossy::{lobe_exponent, sample_lobe};
use crate::material::{eval, phong_light, TextureSpace};
use crate::math::{Ray, Spawn, SurfacePoint, Vec3, SHADOW_EPSILON};
use crate::scene::{Light, Phong, RenderLight};
use crate::world::{Hit, World};
use glam::Vec3A;

/// Area-light samples computed ahead of their shadow rays at a time.
const SHADOW_CHUNK: usize = 4;

/// The fewest shadow rays from one point towards one area light traced as
/// a packet (`Trace::blocked_packet`); fewer are traced one by one.
/// Callgrind, render instructions at 160x120, 1 spp, 1 thread, the knot of
/// `scenes/sphere_lights_knot.txt` under one small far light (every
/// packet walked together): packets of 8 rays 17% fewer than alone, of 4
/// rays 3% more; under the scene's own two near lights (most packets too
/// spread for the packet walk) 2% fewer at 8 rays, 4% more at 4.
const SHADOW_PACKET_MIN: usize = PACKET;

/// Shadow packets are taken only towards a light whose directions from the
/// point spread by at most this along every axis (`Prepared::narrow`: a
/// sphere light small or far enough; the packet walk refuses wider
/// spreads than 1/8). Towards near lights most packets were refused and
/// cost time: `scenes/sphere_lights_knot.txt` with 8 rays a light, 2%
/// fewer instructions but 4-5% more time, without this gate.
const SHADOW_PACKET_SPREAD: f32 = 0.125;

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
    /// Shadow rays per area light per shaded point.
    pub shadow_samples: u32,
    /// Rays over a glossy lobe at the first glossy hit of a camera ray
    /// (deeper glossy hits take one, so the tree does not grow as
    /// `glossy_samples^depth`).
    pub glossy_samples: u32,
    /// Multiply the ambient term by the ambient occlusion of the point.
    pub ambient_occlusion: Option<AoSettings>,
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
            shadow_samples: 1,
            glossy_samples: 1,
            ambient_occlusion: None,
        }
    }
}

/// A shaded point as its lights see it: the material, the shading and
/// geometric normals (facing the side the ray came from), the incoming
/// ray's unit direction and instant, and the point's depth in the tree.
struct Shaded {
    m: Phong,
    n: Vec3,
    ng: Vec3,
    d: Vec3,
    time: f32,
    depth: u32,
}

/// The directions a child ray may take: around `axis` on the `side` of the
/// surface, spread by `glossiness` (0: `axis` alone).
struct Lobe {
    axis: Vec3,
    side: Vec3,
    glossiness: f32,
}

impl Whitted {
    /// Colour seen along `ray` (hits with `t > tmin`), a ray at branch `b`
    /// of the tree, and the hit itself; every random decision (light point,
    /// glossy lobe, hemisphere) takes the next dimension of the stream.
    /// [`Integrator::li`](super::Integrator::li) is this for a camera ray.
    pub fn trace_sampled<O: RayObserver>(
        &self,
        cx: &mut Trace<O>,
        ray: &Ray,
        tmin: f32,
        b: Branch,
    ) -> (Vec3, Option<Hit>) {
        // The hit shaded where the world wrote it: moved out of the
        // `Option` first, it was copied with 16-byte loads of the world's
        // 4-byte stores, which a CPU cannot forward (a stall at every hit;
        // perf, scene6_07 at 16 spp: a third of this function's own time).
        let hit = cx.closest(ray, tmin, b);
        (self.shade_hit(cx, ray, hit.as_ref(), b), hit)
    }

    /// The colour [`trace_sampled`](Self::trace_sampled) gives `ray` at
    /// branch `b` once its closest hit `hit` is known.
    #[inline(always)]
    pub(super) fn shade_hit<O: RayObserver>(
        &self,
        cx: &mut Trace<O>,
        ray: &Ray,
        hit: Option<&Hit>,
        b: Branch,
    ) -> Vec3 {
        match hit {
            None => cx.world.background().color,
            Some(h) => Vec3::from(self.shade(cx, ray, h, b)),
        }
    }

    /// [`shade_color`](Self::shade_color) handed back as a 16-byte value:
    /// a `Vec3` return came back through memory as an 8-byte and a 4-byte
    /// store, which the caller read as two overlapping 8-byte loads, and
    /// the second cannot be forwarded from the stores (perf, scene6_07 at
    /// 1 spp: the largest share of the pixel loop's own samples, on the
    /// colour's first use). One 16-byte store is read back by one 16-byte
    /// load.
    fn shade<O: RayObserver>(&self, cx: &mut Trace<O>, ray: &Ray, hit: &Hit, b: Branch) -> Vec3A {
        Vec3A::from(self.shade_color(cx, ray, hit, b))
    }

    /// The colour a ray at branch `b` brings back from its hit `hit`: the
    /// ambient term, each light's (with its shadow rays) and the reflected
    /// and refracted children.
    #[inline(always)]
    fn shade_color<O: RayObserver>(
        &self,
        cx: &mut Trace<O>,
        ray: &Ray,
        hit: &Hit,
        b: Branch,
    ) -> Vec3 {
        let world = cx.world;
        let d = ray.dir.normalize();
        let back = hit.normal.dot(d) > 0.0;
        if back && !self.shade_back {
            return Vec3::ZERO;
        }
        // The normals face the side the ray came from: `ng` the geometric
        // one, `n` the shading one (the same vector unless the triangle is
        // smooth-shaded). Light and mirror directions use `n`; what crosses
        // the surface is decided by `ng`, so a smooth normal never lets
        // light through the geometric surface.
        let (n, ng) = if back {
            (-hit.shading_normal, -hit.normal)
        } else {
            (hit.shading_normal, hit.normal)
        };
        let p = hit.point;
        let (time, depth) = (ray.time, b.depth);
        let at = &Shaded {
            m: self.material_at(world, hit),
            n,
            ng,
            d,
            time,
            depth,
        };
        let m = &at.m;

        let mut color = world.background().ambient * m.diffuse;
        if let Some(ao) = &self.ambient_occlusion {
            if color != Vec3::ZERO {
                color *= unoccluded(cx, &hit.surface_point(), ng, time, ao, depth);
            }
        }
        // The lights' shadow rays share their offset origins (`Spawn`).
        let from = &mut Spawn::leaving(hit.surface_point(), hit.prim);
        for (i, light) in world.lights().iter().enumerate() {
            if !is_delta(light) {
                // An area light: the mean over `shadow_samples` points of
                // it, stratified by one split dimension of the stream, each
                // with its own shadow ray (the penumbra is the fraction of
                // them blocked), from the hit to the sampled point with both
                // ends offset out of their error bounds.
                // With several samples, what they share is worked out
                // once, and the samples of a chunk ahead of their shadow
                // rays: their independent arithmetic overlaps instead of
                // waiting on each traversal in turn.
                let k = self.shadow_samples.max(1);
                if k == 1 {
                    for u in cx.stream.split_2d(1) {
                        let inc = sample_light(light, from.from.p, u);
                        let target = ShadowTarget::of(light, &inc);
                        color += self.lit(cx, at, from, inc.to_light, inc.color, target);
                    }
                    continue;
                }
                let Some(prepared) = prepare_area(light, from.from.p) else {
                    continue;
                };
                let mut us = cx.stream.split_2d(k);
                let mut sum = Vec3::ZERO;
                if k as usize >= SHADOW_PACKET_MIN
                    && prepared.narrow(SHADOW_PACKET_SPREAD)
                    && cx.packets
                    && self.shadows
                    && !self.transparent_shadows
                {
                    // The chunk's shadow rays leave one point for one light:
                    // traced as one packet (the same answers as alone).
                    while us.len() > 0 {
                        let mut chunk = [Incident::NONE; PACKET];
                        let len = chunk.len().min(us.len());
                        for (slot, u) in chunk.iter_mut().zip(us.by_ref()) {
                            *slot = prepared.sample(u);
                        }
                        self.lit_packet(cx, at, from, light, &chunk[..len], &mut sum);
                    }
                    color += sum / k as f32;
                    continue;
                }
                while us.len() > 0 {
                    let mut chunk = [Incident::NONE; SHADOW_CHUNK];
                    let len = chunk.len().min(us.len());
                    for (slot, u) in chunk.iter_mut().zip(us.by_ref()) {
                        *slot = prepared.sample(u);
                    }
                    for inc in &chunk[..len] {
                        sum += self.lit(
                            cx,
                            at,
                            from,
                            inc.to_light,
                            inc.color,
                            ShadowTarget::of(light, inc),
                        );
                    }
                }
                color += sum / k as f32;
                continue;
            }
            let inc = world.incident(i, p);
            color += self.lit(
                cx,
                at,
                from,
                inc.to_light,
                inc.color,
                ShadowTarget::of(light, &inc),
            );
        }

        if depth >= self.bounces {
            return color;
        }
        // Light arriving along child rays of `kind` and `weight` around
        // `axis`, on the `side` of the surface.
        let child = |cx: &mut Trace<O>, axis, side, kind, weight| {
            let lobe = Lobe {
                axis,
                side,
                glossiness: m.glossiness,
            };
            let depth = depth + 1;
            let b = Branch {
                kind,
                depth,
                weight,
            };
            self.spread(cx, &hit.surface_point(), time, lobe, b)
        };
        let refl_w = b.weight * m.reflective.max_element();
        if refl_w > 0.0 && refl_w >= self.weight_cutoff {
            let mut r = reflect(d, n);
            if n != ng && r.dot(ng) <= 0.0 {
                // A smooth normal would mirror the ray into the surface.
                r = reflect(d, ng);
            }
            color += m.reflective * child(cx, r, ng, RayKind::Reflected, refl_w);
        }
        let trans_w = b.weight * m.transparent.max_element();
        if trans_w > 0.0 && trans_w >= self.weight_cutoff {
            // Entering or leaving is decided by the side of the geometric normal.
            let (n_i, n_t) = if back { (m.ior, 1.0) } else { (1.0, m.ior) };
            let through = refract(d, n, n_i, n_t)
                .filter(|t| n == ng || t.dot(ng) < 0.0)
                .or_else(|| {
                    if n == ng {
                        None
                    } else {
                        refract(d, ng, n_i, n_t)
                    }
                });
            if let Some(t) = through {
                color += m.transparent * child(cx, t, -ng, RayKind::Transmitted, trans_w);
            }
        }
        color
    }

    /// Colour arriving from the surface point `from` along child rays at
    /// branch `b`: one ray along the lobe's axis for a mirror or clear glass
    /// (`glossiness` 0), else the mean of rays over the lobe. Child rays are
    /// spawned clear of `from`'s error bound at instant `time`.
    fn spread<O: RayObserver>(
        &self,
        cx: &mut Trace<O>,
        from: &SurfacePoint,
        time: f32,
        lobe: Lobe,
        b: Branch,
    ) -> Vec3 {
        if lobe.glossiness <= 0.0 {
            let child = from.spawn_ray(lobe.axis).at_time(time);
            return self.trace_sampled(cx, &child, 0.0, b).0;
        }
        let e = lobe_exponent(lobe.glossiness);
        // Many rays at a camera ray's first hit, one deeper.
        let k = if b.depth == 1 {
            self.glossy_samples.max(1)
        } else {
            1
        };
        let mut sum = Vec3::ZERO;
        for u in cx.stream.split_2d(k) {
            let w = sample_lobe(lobe.axis, lobe.side, e, u);
            let child = from.spawn_ray(w).at_time(time);
            cx.counters.glossy += 1;
            sum += self.trace_sampled(cx, &child, 0.0, b).0;
        }
        sum / k as f32
    }

    /// The Phong parameters at a hit. World-space lookups (the 6.837
    /// scenes' texture matrices map world points) hand the rendering-space
    /// hit to the world's materials, whose texture matrices have the move
    /// back to world space folded in; object-space lookups hand the hit in
    /// its object's space to the scene's own matrices.
    fn material_at(&self, world: &World, hit: &Hit) -> Phong {
        match self.texture_space {
            TextureSpace::World => eval(world.materials(), hit.material, hit.point),
            TextureSpace::Object => eval(
                world.object_materials(),
                hit.material,
                world.object_from_world()[hit.instance as usize].transform_point3(hit.point),
            ),
        }
    }

    /// Phong light reflected towards `-d` from light of `color` arriving
    /// from `to_light`, times what of it gets through from `target` (one
    /// shadow ray when shadows are on).
    ///
    /// Inlined, with the light's direction and colour by value: called out
    /// of line with the [`Incident`] by reference, it read the colour with
    /// a load that straddled the halves of the 16-byte store that had just
    /// written it, which a CPU cannot forward (perf, scene6_07 at 16 spp:
    /// that one load was a fifth of this function's time).
    #[inline(always)]
    fn lit<O: RayObserver>(
        &self,
        cx: &mut Trace<O>,
        at: &Shaded,
        from: &mut Spawn,
        to_light: Vec3,
        color: Vec3,
        target: ShadowTarget,
    ) -> Vec3 {
        let (reflected, shadowed) = self.unshadowed(at, to_light, color);
        if shadowed {
            reflected * self.light_through(cx, from, at.time, target, at.depth)
        } else {
            reflected
        }
    }

    /// The Phong light [`lit`](Self::lit) reflects before its shadow ray,
    /// and whether it takes one (shadows are on, the light reflects
    /// something and does not sit at the point).
    #[inline(always)]
    fn unshadowed(&self, at: &Shaded, to_light: Vec3, color: Vec3) -> (Vec3, bool) {
        let Shaded { n, ng, d, .. } = *at;
        if n != ng && to_light.dot(ng) <= 0.0 {
            // Smooth shading: a light behind the geometric surface does not
            // shine through it, whatever the interpolated normal says.
            return (Vec3::ZERO, false);
        }
        let reflected = phong_light(&at.m, n, to_light, -d, color);
        if reflected == Vec3::ZERO {
            return (reflected, false); // nothing to shadow: no shadow ray needed
        }
        // A light exactly at the point (zero direction) has nothing in
        // between, and a zero-direction shadow ray would be meaningless.
        (reflected, self.shadows && to_light != Vec3::ZERO)
    }

    /// Adds [`lit`](Self::lit) of each sample of `incs` (at most
    /// [`PACKET`]) of the area light `light` to `sum`, in order, with
    /// opaque shadows: the same sum bit for bit, the shadow rays traced as
    /// one packet ([`Trace::blocked_packet`]; fewer than
    /// [`SHADOW_PACKET_MIN`] one by one).
    ///
    /// Out of line: inlined, its arrays in `shade`'s frame made the
    /// renders that take no packets 3-7% slower at the same instructions
    /// (1 thread, alternated with `354a762`, load 1.1; out of line 0.95-0.99).
    #[inline(never)]
    fn lit_packet<O: RayObserver>(
        &self,
        cx: &mut Trace<O>,
        at: &Shaded,
        from: &mut Spawn,
        light: &RenderLight,
        incs: &[Incident],
        sum: &mut Vec3,
    ) {
        let mut reflected = [Vec3::ZERO; PACKET];
        let mut rays = [PacketRay {
            ray: Ray::new(Vec3::ZERO, Vec3::Z),
            tmin: 0.0,
            tmax: 0.0,
        }; PACKET];
        // Which samples take a shadow ray (bit `r`), and how many.
        let (mut shadowed, mut n) = (0u32, 0);
        for (r, inc) in incs.iter().enumerate() {
            let (refl, s) = self.unshadowed(at, inc.to_light, inc.color);
            reflected[r] = refl;
            if s {
                let (ray, tmax) = ShadowTarget::of(light, inc).ray_from(from, at.time);
                rays[n] = PacketRay {
                    ray,
                    tmin: 0.0,
                    tmax,
                };
                shadowed |= 1 << r;
                n += 1;
            }
        }
        let blocked = if n >= SHADOW_PACKET_MIN {
            cx.blocked_packet(&rays[..n], from.leaving, at.depth)
        } else {
            let mut blocked = 0;
            for (r, q) in rays[..n].iter().enumerate() {
                blocked |= u32::from(cx.blocked(&q.ray, q.tmax, from.leaving, at.depth)) << r;
            }
            blocked
        };
        let mut k = 0;
        for (r, refl) in reflected[..incs.len()].iter().enumerate() {
            *sum += if shadowed >> r & 1 == 0 {
                *refl
            } else {
                k += 1;
                *refl
                    * if blocked >> (k - 1) & 1 != 0 {
                        Vec3::ZERO
                    } else {
                        Vec3::ONE
                    }
            };
        }
    }

    /// Fraction of a light's colour that reaches the surface point `from`
    /// from `target` at instant `time`: 0 or 1 with opaque shadows; with
    /// transparent shadows the product of the `transparentColor` of
    /// everything in between.
    ///
    /// Inlined (the opaque case): out of line, the target came through
    /// memory written in pieces and read back wider, a store-forwarding
    /// stall at every shadow ray (perf, scene6_07 at 16 spp: a fifth of
    /// this function's samples on the load after it).
    #[inline(always)]
    fn light_through<O: RayObserver>(
        &self,
        cx: &mut Trace<O>,
        from: &mut Spawn,
        time: f32,
        target: ShadowTarget,
        depth: u32,
    ) -> Vec3 {
        if !self.transparent_shadows {
            let (shadow, tmax) = target.ray_from(from, time);
            let blocked = cx.blocked(&shadow, tmax, from.leaving, depth);
            return if blocked { Vec3::ZERO } else { Vec3::ONE };
        }
        self.filtered_through(cx, from, time, target, depth)
    }

    /// [`light_through`](Self::light_through) with transparent shadows.
    #[inline(never)]
    fn filtered_through<O: RayObserver>(
        &self,
        cx: &mut Trace<O>,
        from: &mut Spawn,
        time: f32,
        target: ShadowTarget,
        depth: u32,
    ) -> Vec3 {
        let Trace {
            world,
            counters: c,
            observer: obs,
            ..
        } = cx;
        super::count_ray(c, RayKind::Shadow);
        let mut filter = Vec3::ONE;
        let mut from = *from;
        // Each pass steps past one occluder, spawning the next segment from
        // its hit; the cap guards against a ray trapped between coincident
        // surfaces.
        for _ in 0..64 {
            let (ray, tmax) = target.ray_from(&mut from, time);
            let Some(h) = world.intersect(&ray, 0.0, tmax, c) else {
                obs.ray(Branch::probe(RayKind::Shadow, depth), &ray, tmax, None);
                return filter;
            };
            obs.ray(
                Branch::probe(RayKind::Shadow, depth),
                &ray,
                h.t,
                Some(h.normal),
            );
            filter *= self.material_at(world, &h).transparent;
            if filter == Vec3::ZERO {
                return filter;
            }
            from = Spawn::new(h.surface_point());
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
    /// A sampled point of an area light's surface, with its error bound.
    Surface(SurfacePoint),
}

impl ShadowTarget {
    /// Where the shadow ray for the light `inc` from `light` goes: the
    /// sampled point of an area light, a point light's position, or a
    /// directional light's direction.
    fn of(light: &RenderLight, inc: &Incident) -> Self {
        match (inc.at, light) {
            (Some(at), _) => ShadowTarget::Surface(at),
            (None, Light::Point { position, .. }) => ShadowTarget::Point(*position),
            (None, _) => ShadowTarget::Direction(inc.to_light),
        }
    }

    /// The shadow ray from `from` and the `tmax` it is traced to: a point
    /// light's ray ends at the light (`t = 1`), kept `SHADOW_EPSILON` short
    /// of it so a surface the light sits on does not shadow it; an area
    /// light's sample likewise, with its own end offset out of its error
    /// bound too. The ray travels at instant `time` (motion blur: shadows
    /// of moving objects are cast where they are at that instant).
    #[inline(always)] // (its result went through memory in pieces: see `phong_light`)
    fn ray_from(self, from: &mut Spawn, time: f32) -> (Ray, f32) {
        let (ray, tmax) = match self {
            ShadowTarget::Point(p) => (from.spawn_ray_to(p), 1.0 - SHADOW_EPSILON),
            ShadowTarget::Direction(d) => (from.spawn_ray(d), f32::INFINITY),
            ShadowTarget::Surface(s) => (from.spawn_ray_to_surface(&s), 1.0 - SHADOW_EPSILON),
        };
        (ray.at_time(time), tmax)
    }
}
