//! A caustic photon map (Jensen 1996) for the path tracer: light that
//! reaches a non-delta surface through one or more delta lobes (mirror,
//! clear glass) from an emitting primitive, estimated by density
//! estimation instead of by the paths that happen to hit the light after
//! the delta lobes.
//!
//! **The photons.** `count` photons leave the world's emitting triangles
//! and spheres and its `AreaLight`s (each chosen with probability
//! proportional to its power, a point uniform over its emitting area, a
//! face of a flat light at random, a direction cosine-distributed about
//! the normal), each carrying `Le·π·A / (P(emitter)·count)`. A photon goes on
//! through delta lobes only (its power times the lobe's weight; where a
//! non-delta lobe is chosen it ends); it is stored at every surface with
//! a non-delta lobe it meets after at least one delta lobe (paths of
//! light that scatter diffusely before or between delta lobes are the
//! path tracer's). The
//! photons' sample dimensions come from one Owen-scrambled Sobol sequence
//! over the photon indices, they are traced in order-preserving parallel
//! chunks, and the tree is built from that order: the map, hence the
//! image, is the same for any thread count and piece split.
//!
//! **The estimate.** At a point `x` with normal `n` and BSDF `f`, the
//! caustic radiance towards `wo` is `Σ f(wo, wiₚ)·Φₚ·(1 − dₚ/r)·3/(π r²)`
//! over the `k` nearest photons whose surface faces the same way (within
//! [`NORMAL_COS`]), `r` the distance of the farthest of them (at most
//! `max_radius`): the cone filter of Jensen, which blurs the caustic's
//! edges less than a box does. The estimate is biased (it blurs over `r`)
//! and consistent (`r` shrinks as `count` grows). Where the non-delta
//! lobes are all Lambertian, `f` is the same for every photon and the
//! irradiance `Σ Φₚ·(1 − dₚ/r)·3/(π r²)` is precomputed at every
//! fourth photon (Christensen 1999): a lookup reads the
//! nearest of those within its own `r`, from one cell of a grid.
//!
//! Delta lobes are symmetric here (no `η²` factor in the dielectric), so
//! photons use the same BSDF as the paths.

use crate::bsdf::{Bsdf, Lobe};
use crate::math::warp::{concentric_disk, cosine_hemisphere, uniform_triangle};
use crate::math::{Spawn, SurfacePoint, Vec3};
use crate::sampler::{Sampler, SamplerKind};
use crate::scene::{AreaShape, RenderAreaShape};
use crate::shape::Shape;
use crate::stats::Counters;
use crate::world::World;
use rayon::prelude::*;
use std::f32::consts::PI;

/// Photons whose surface normal is within this cosine of the gathering
/// point's count (photons on a wall meeting it at a corner do not).
pub const NORMAL_COS: f32 = 0.7;

/// Delta lobes a photon passes through at most.
const MAX_DELTA_BOUNCES: u32 = 32;

/// Every how many photons one carries a precomputed irradiance
/// (Christensen 1999: the lookup tree is that much smaller).
const LOOKUP_STRIDE: usize = 4;

/// Photons traced per parallel chunk.
const CHUNK: u32 = 4096;

/// The settings of a caustic map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CausticSettings {
    /// Photons shot from the emitters (0: no map).
    pub photons: u32,
    /// Nearest photons an estimate uses.
    pub nearest: u32,
    /// Largest search radius, as a fraction of the world's bounding box
    /// diagonal.
    pub max_radius: f32,
    /// Seed of the photons' sample sequence.
    pub seed: u64,
    /// The shutter interval: each photon flies at a time uniform over it
    /// (the map holds the caustics averaged over the exposure).
    pub shutter: [f32; 2],
}

impl Default for CausticSettings {
    fn default() -> Self {
        Self {
            photons: 0,
            nearest: 64,
            max_radius: 0.02,
            seed: 0,
            shutter: [0.0, 0.0],
        }
    }
}

/// A stored photon: where it landed, the direction it came from, its
/// power, and the normal of the surface facing it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    /// Where it landed.
    pub p: Vec3,
    /// Unit direction towards where it came from.
    pub wi: Vec3,
    /// Power (flux) it carries.
    pub power: Vec3,
    /// Unit normal of the surface there, on the side it arrived from.
    pub n: Vec3,
}

/// An emitter photons leave, its radiance and the probability of choosing
/// it.
#[derive(Clone, Copy, Debug)]
pub struct Source {
    /// What emits.
    pub from: Emits,
    /// Radiance it emits (front side; both faces of a flat area light).
    pub emission: Vec3,
    /// Probability of choosing it (the sources' sum to 1).
    pub probability: f32,
}

/// What a [`Source`] is.
#[derive(Clone, Copy, Debug)]
pub enum Emits {
    /// An emitting triangle or sphere: its index in the world.
    Prim(u32),
    /// An `AreaLight`'s surface (not in the aggregate: it blocks no ray).
    Area(RenderAreaShape),
}

/// The photons, in a balanced kd-tree over their positions.
#[derive(Clone, Debug, Default)]
pub struct CausticMap {
    /// Photons in kd-tree order: the node at `i` splits its subtree at its
    /// photon's position along `axis[i]`, children at `2i+1` and `2i+2`
    /// (a left-balanced implicit tree).
    photons: Vec<Photon>,
    axis: Vec<u8>,
    /// Irradiance at every [`LOOKUP_STRIDE`]th photon, for Lambertian
    /// surfaces.
    lookup: Lookup,
    nearest: usize,
    max_radius2: f32,
    /// Photons emitted (the count their power divides by).
    emitted: u32,
    /// The photon pass's rays and traversal work.
    pub counters: Counters,
}

impl CausticMap {
    /// Shoots `settings.photons` photons from `sources` and keeps the
    /// caustic ones. `material` reads a primitive's material at a point.
    pub fn build<M>(
        world: &World,
        sources: &[Source],
        settings: CausticSettings,
        material: M,
    ) -> Self
    where
        M: Fn(u32, u32, Vec3) -> crate::scene::Phong + Sync,
    {
        let bounds = world.bounds();
        let diag = if bounds.is_finite() && !bounds.is_empty() {
            bounds.extent().length()
        } else {
            1.0
        };
        let max_radius = settings.max_radius * diag;
        let n = settings.photons;
        let mut cdf = Vec::with_capacity(sources.len());
        let mut run = 0.0;
        for s in sources {
            run += s.probability;
            cdf.push(run);
        }
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        let sampler = Sampler::new(SamplerKind::Sobol, n.max(1), settings.seed);
        let chunks = n.div_ceil(CHUNK);
        let traced: Vec<(Vec<Photon>, Counters)> = (0..chunks)
            .into_par_iter()
            .map(|c| {
                let mut out = Vec::new();
                let mut counters = Counters::default();
                for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                    trace_photon(
                        world,
                        sources,
                        &cdf,
                        (&sampler, settings.shutter),
                        i,
                        n,
                        &material,
                        &mut counters,
                        &mut out,
                    );
                }
                (out, counters)
            })
            .collect();
        let mut counters = Counters::default();
        for t in &traced {
            counters += t.1;
        }
        let photons: Vec<Photon> = traced.into_iter().flat_map(|t| t.0).collect();
        let mut map = Self::from_photons(photons, settings.nearest, max_radius);
        map.emitted = n;
        map.counters = counters;
        map
    }

    /// The map of `photons` (in a fixed order: the map depends on it only
    /// through ties), estimating from the `nearest` photons within
    /// `max_radius`.
    pub fn from_photons(mut photons: Vec<Photon>, nearest: u32, max_radius: f32) -> Self {
        let picks: Vec<Photon> = photons.iter().step_by(LOOKUP_STRIDE).copied().collect();
        let mut axis = vec![0u8; photons.len()];
        let mut tree = vec![
            photons.first().copied().unwrap_or(Photon {
                p: Vec3::ZERO,
                wi: Vec3::Z,
                power: Vec3::ZERO,
                n: Vec3::Z,
            });
            photons.len()
        ];
        balance(&mut photons, 0, &mut tree, &mut axis);
        let mut map = Self {
            photons: tree,
            axis,
            lookup: Lookup::default(),
            nearest: nearest.max(1) as usize,
            max_radius2: max_radius * max_radius,
            emitted: 0,
            counters: Counters::default(),
        };
        // Irradiance at every LOOKUP_STRIDE-th photon (in emission order),
        // each estimated from its neighbours without itself.
        let points: Vec<(Vec3, Vec3, Vec3, f32)> = picks
            .par_iter()
            .map(|ph| {
                let (e, r2) = map.estimate(ph.p, ph.n, Some(ph.p), |_| Vec3::ONE);
                (ph.p, ph.n, e, r2)
            })
            .collect();
        map.lookup = Lookup::build(points);
        map
    }

    /// `Σ weight(photon)·Φ·(1 − d/r)·3/(π r²)` over the nearest photons
    /// facing `n` around `x`, and `r²`.
    fn estimate(
        &self,
        x: Vec3,
        n: Vec3,
        skip: Option<Vec3>,
        weight: impl Fn(&Photon) -> Vec3,
    ) -> (Vec3, f32) {
        let mut heap = Heap::new(self.nearest);
        let mut r2 = self.max_radius2;
        self.knn(0, x, n, skip, &mut heap, &mut r2);
        if heap.len == 0 {
            return (Vec3::ZERO, 0.0);
        }
        let r2 = if heap.len == self.nearest {
            heap.max()
        } else {
            self.max_radius2
        };
        if r2 <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let r = r2.sqrt();
        let mut sum = Vec3::ZERO;
        for &(d2, i) in &heap.items[..heap.len] {
            let ph = &self.photons[i as usize];
            let w = 1.0 - d2.sqrt() / r;
            if w > 0.0 {
                sum += weight(ph) * ph.power * w;
            }
        }
        (sum * (3.0 / (PI * r2)), r2)
    }

    /// The stored photons (in tree order).
    pub fn photons(&self) -> &[Photon] {
        &self.photons
    }

    /// Photons emitted.
    pub fn emitted(&self) -> u32 {
        self.emitted
    }

    /// The caustic radiance leaving `x` (normal `n`) towards `wo` through
    /// `bsdf`. Where the BSDF's non-delta lobes are all Lambertian (`f`
    /// does not depend on the photons' directions), the irradiance stored
    /// at the nearest photon times `f`; elsewhere the nearest photons'
    /// estimate with `f` of each.
    pub fn radiance(&self, x: Vec3, n: Vec3, wo: Vec3, bsdf: &Bsdf) -> Vec3 {
        if self.photons.is_empty() {
            return Vec3::ZERO;
        }
        let n = if n.dot(wo) < 0.0 { -n } else { n };
        let lambert = bsdf
            .lobes()
            .iter()
            .all(|l| l.is_delta() || matches!(l, Lobe::Lambert { .. }));
        if lambert {
            return self
                .lookup
                .value_at(x, n)
                .map_or(Vec3::ZERO, |e| bsdf.f(wo, n) * e);
        }
        self.estimate(x, n, None, |ph| bsdf.f(wo, ph.wi)).0
    }

    fn knn(&self, i: usize, x: Vec3, n: Vec3, skip: Option<Vec3>, heap: &mut Heap, r2: &mut f32) {
        let Some(ph) = self.photons.get(i) else {
            return;
        };
        let a = self.axis[i] as usize;
        let delta = x[a] - ph.p[a];
        let (near, far) = if delta < 0.0 {
            (2 * i + 1, 2 * i + 2)
        } else {
            (2 * i + 2, 2 * i + 1)
        };
        if near < self.photons.len() {
            self.knn(near, x, n, skip, heap, r2);
        }
        if far < self.photons.len() && delta * delta < *r2 {
            self.knn(far, x, n, skip, heap, r2);
        }
        let d2 = (ph.p - x).length_squared();
        if d2 < *r2 && ph.n.dot(n) >= NORMAL_COS && skip != Some(ph.p) {
            heap.push(d2, i as u32);
            if heap.len == heap.cap {
                *r2 = heap.max();
            }
        }
    }
}

/// Points with a value, each standing for the ball of radius `r` around
/// it, in a uniform grid: each cell lists the points whose ball reaches
/// it, so a lookup reads one cell.
#[derive(Clone, Debug, Default)]
struct Lookup {
    /// Position and `r²` of each point.
    p: Vec<[f32; 4]>,
    n: Vec<Vec3>,
    value: Vec<Vec3>,
    origin: Vec3,
    inv_cell: f32,
    dims: [usize; 3],
    /// `items[start[c]..start[c + 1]]`: the points of cell `c`.
    start: Vec<u32>,
    items: Vec<u32>,
}

/// Most cells a lookup grid has.
const MAX_CELLS: usize = 1 << 22;

impl Lookup {
    /// The grid of `(position, normal, value, r²)` points.
    fn build(points: Vec<(Vec3, Vec3, Vec3, f32)>) -> Self {
        let points: Vec<_> = points
            .into_iter()
            .filter(|q| q.3 > 0.0 && q.3.is_finite() && q.0.is_finite())
            .collect();
        if points.is_empty() {
            return Self::default();
        }
        let mut radii: Vec<f32> = points.iter().map(|q| q.3.sqrt()).collect();
        let r_max = radii.iter().fold(0.0f32, |a, &b| a.max(b));
        let mid = radii.len() / 2;
        let mut cell = *radii.select_nth_unstable_by(mid, f32::total_cmp).1;
        let (lo, hi) = points
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), q| {
                (lo.min(q.0), hi.max(q.0))
            });
        let (lo, hi) = (lo - Vec3::splat(r_max), hi + Vec3::splat(r_max));
        let ext = hi - lo;
        // Cells of the median radius, coarser where there would be too
        // many of them or too many entries (points of large radius among
        // small ones span many cells).
        let budget = 64.0 * points.len() as f64 + 1e6;
        let dims = loop {
            let d = (ext / cell).ceil().max(Vec3::ONE);
            let dims = [d.x as usize, d.y as usize, d.z as usize];
            let entries: f64 = radii
                .iter()
                .map(|&r| (2.0 * f64::from(r / cell) + 2.0).powi(3))
                .sum();
            if dims[0] * dims[1] * dims[2] <= MAX_CELLS && entries <= budget {
                break dims;
            }
            cell *= 1.25;
        };
        let inv_cell = 1.0 / cell;
        let index = |c: [usize; 3]| (c[2] * dims[1] + c[1]) * dims[0] + c[0];
        let cell_of = |v: f32, k: usize| (((v - lo[k]) * inv_cell) as usize).min(dims[k] - 1);
        // Each point's cells: those of its ball's box that the ball reaches.
        let each = |q: &(Vec3, Vec3, Vec3, f32), f: &mut dyn FnMut(usize)| {
            let r = q.3.sqrt();
            let a = [0, 1, 2].map(|k| cell_of(q.0[k] - r, k));
            let b = [0, 1, 2].map(|k| cell_of(q.0[k] + r, k));
            for z in a[2]..=b[2] {
                for y in a[1]..=b[1] {
                    for x in a[0]..=b[0] {
                        let cmin = lo + Vec3::new(x as f32, y as f32, z as f32) * cell;
                        let near = q.0.clamp(cmin, cmin + Vec3::splat(cell));
                        if (near - q.0).length_squared() <= q.3 {
                            f(index([x, y, z]));
                        }
                    }
                }
            }
        };
        let mut start = vec![0u32; dims[0] * dims[1] * dims[2] + 1];
        for q in &points {
            each(q, &mut |c| start[c + 1] += 1);
        }
        for c in 1..start.len() {
            start[c] += start[c - 1];
        }
        let mut fill = start.clone();
        let mut items = vec![0u32; *start.last().unwrap_or(&0) as usize];
        for (i, q) in points.iter().enumerate() {
            each(q, &mut |c| {
                items[fill[c] as usize] = i as u32;
                fill[c] += 1;
            });
        }
        Self {
            p: points.iter().map(|q| [q.0.x, q.0.y, q.0.z, q.3]).collect(),
            n: points.iter().map(|q| q.1).collect(),
            value: points.iter().map(|q| q.2).collect(),
            origin: lo,
            inv_cell,
            dims,
            start,
            items,
        }
    }

    /// The value of the nearest point to `x` facing `n` (within
    /// [`NORMAL_COS`]) whose ball holds `x`.
    fn value_at(&self, x: Vec3, n: Vec3) -> Option<Vec3> {
        if self.p.is_empty() {
            return None;
        }
        let g = (x - self.origin) * self.inv_cell;
        // (NaN fails too.)
        if g.min_element().partial_cmp(&0.0) == Some(std::cmp::Ordering::Less) || g.is_nan() {
            return None;
        }
        let c = [g.x as usize, g.y as usize, g.z as usize];
        if c[0] >= self.dims[0] || c[1] >= self.dims[1] || c[2] >= self.dims[2] {
            return None;
        }
        let cell = (c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0];
        let (a, b) = (self.start[cell] as usize, self.start[cell + 1] as usize);
        let mut best = (f32::INFINITY, usize::MAX);
        for &i in &self.items[a..b] {
            let q = self.p[i as usize];
            let (dx, dy, dz) = (x.x - q[0], x.y - q[1], x.z - q[2]);
            let d2 = dx * dx + dy * dy + dz * dz;
            if d2 < q[3] && d2 < best.0 && self.n[i as usize].dot(n) >= NORMAL_COS {
                best = (d2, i as usize);
            }
        }
        self.value.get(best.1).copied()
    }
}

/// A bounded max-heap of (squared distance, photon) pairs.
struct Heap {
    items: Vec<(f32, u32)>,
    len: usize,
    cap: usize,
}

impl Heap {
    fn new(cap: usize) -> Self {
        Self {
            items: vec![(0.0, 0); cap],
            len: 0,
            cap,
        }
    }

    fn max(&self) -> f32 {
        self.items[0].0
    }

    fn push(&mut self, d2: f32, i: u32) {
        if self.len < self.cap {
            let mut k = self.len;
            self.items[k] = (d2, i);
            self.len += 1;
            while k > 0 {
                let parent = (k - 1) / 2;
                if self.items[parent].0 >= self.items[k].0 {
                    break;
                }
                self.items.swap(parent, k);
                k = parent;
            }
        } else if d2 < self.items[0].0 {
            self.items[0] = (d2, i);
            let mut k = 0;
            loop {
                let (l, r) = (2 * k + 1, 2 * k + 2);
                let mut m = k;
                if l < self.len && self.items[l].0 > self.items[m].0 {
                    m = l;
                }
                if r < self.len && self.items[r].0 > self.items[m].0 {
                    m = r;
                }
                if m == k {
                    break;
                }
                self.items.swap(m, k);
                k = m;
            }
        }
    }
}

/// Size of the left subtree of a left-balanced tree of `n` nodes.
fn left_size(n: usize) -> usize {
    if n <= 1 {
        return 0;
    }
    // Levels of the full part, and the last level's nodes.
    let h = usize::BITS - 1 - n.leading_zeros(); // floor(log2 n)
    let full = (1usize << h) - 1; // nodes above the last level
    let last = n - full;
    let half_last = 1usize << (h - 1);
    (full - 1) / 2 + last.min(half_last)
}

/// Builds the left-balanced tree of `pts` at node `node` of `tree`.
fn balance(pts: &mut [Photon], node: usize, tree: &mut [Photon], axis: &mut [u8]) {
    if pts.is_empty() {
        return;
    }
    let (lo, hi) = pts
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.p), hi.max(p.p))
        });
    let ext = hi - lo;
    let a = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let m = left_size(pts.len());
    pts.select_nth_unstable_by(m, |p, q| p.p[a].total_cmp(&q.p[a]));
    tree[node] = pts[m];
    axis[node] = a as u8;
    let (left, rest) = pts.split_at_mut(m);
    balance(left, 2 * node + 1, tree, axis);
    balance(&mut rest[1..], 2 * node + 2, tree, axis);
}

/// Traces photon `i` of `n` and stores it if it lands as a caustic.
#[allow(clippy::too_many_arguments)]
fn trace_photon<M>(
    world: &World,
    sources: &[Source],
    cdf: &[f32],
    (sampler, shutter): (&Sampler, [f32; 2]),
    i: u32,
    n: u32,
    material: &M,
    counters: &mut Counters,
    out: &mut Vec<Photon>,
) where
    M: Fn(u32, u32, Vec3) -> crate::scene::Phong,
{
    let mut stream = sampler.stream((u32::MAX, u32::MAX), i);
    let uc = stream.next_1d();
    let u_point = stream.next_2d();
    let u_dir = stream.next_2d();
    let u_time = stream.next_1d();
    let time = shutter[0] + u_time * (shutter[1] - shutter[0]).max(0.0);
    let k = cdf
        .partition_point(|&c| c <= uc)
        .min(sources.len().saturating_sub(1));
    let Some(src) = sources.get(k) else {
        return;
    };
    if src.probability <= 0.0 {
        return;
    }
    let sphere = |center: Vec3, radius: f32| {
        let z = 1.0 - 2.0 * u_point.x;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = 2.0 * PI * u_point.y;
        let nrm = Vec3::new(r * phi.cos(), r * phi.sin(), z);
        let error = crate::math::gamma(5) * (center.abs() + (nrm * radius).abs());
        let y = SurfacePoint {
            p: center + nrm * radius,
            error,
            n: nrm,
        };
        (y, 4.0 * PI * radius * radius)
    };
    // A flat light emits from both faces: one chosen by the next value.
    let face = |n: Vec3, u: f32| if u < 0.5 { n } else { -n };
    let flat = |p: Vec3, n: Vec3, area: f32, u: f32| {
        let error = crate::math::gamma(5) * p.abs();
        (
            SurfacePoint {
                p,
                error,
                n: face(n, u),
            },
            2.0 * area,
        )
    };
    let u_face = stream.next_1d();
    let ((y, area), prim): ((SurfacePoint, f32), Option<u32>) = match src.from {
        Emits::Prim(prim) => match &world.prims()[prim as usize].shape {
            Shape::Triangle(t) => {
                let [a, b, c] = t.v;
                (
                    (
                        t.surface_at(uniform_triangle(u_point)),
                        0.5 * (b - a).cross(c - a).length(),
                    ),
                    Some(prim),
                )
            }
            Shape::Sphere(s) => (sphere(s.center, s.radius), Some(prim)),
            _ => return,
        },
        Emits::Area(AreaShape::Quad {
            corner,
            edge1,
            edge2,
        }) => {
            let n = edge1.cross(edge2);
            let p = corner + edge1 * u_point.x + edge2 * u_point.y;
            (flat(p, n.normalize_or_zero(), n.length(), u_face), None)
        }
        Emits::Area(AreaShape::Disk {
            center,
            normal,
            radius,
        }) => {
            let n = normal.normalize_or_zero();
            let (t1, t2) = n.any_orthonormal_pair();
            let d = concentric_disk(u_point) * radius;
            let p = center + t1 * d.x + t2 * d.y;
            (flat(p, n, PI * radius * radius, u_face), None)
        }
        Emits::Area(AreaShape::Sphere { center, radius }) => (sphere(center, radius), None),
    };
    if y.n == Vec3::ZERO || area.is_nan() || area <= 0.0 {
        return;
    }
    let dir = cosine_hemisphere(y.n, u_dir);
    let mut power = src.emission * (PI * area / (src.probability * n as f32));
    let mut spawn = match prim {
        Some(prim) => Spawn::leaving(y, prim),
        None => Spawn::new(y),
    };
    let mut ray = spawn.spawn_ray(dir).at_time(time);
    counters.photon += 1;
    let mut deltas = 0;
    loop {
        let Some(h) = world.intersect(&ray, 0.0, f32::INFINITY, counters) else {
            return;
        };
        let m = material(h.material, h.instance, h.point);
        let bsdf = Bsdf::from_phong(&m, h.normal);
        let wo = -ray.dir.normalize();
        if deltas > 0 && !bsdf.is_delta() {
            let nf = if h.normal.dot(wo) < 0.0 {
                -h.normal
            } else {
                h.normal
            };
            out.push(Photon {
                p: h.point,
                wi: wo,
                power,
                n: nf,
            });
        }
        if deltas >= MAX_DELTA_BOUNCES {
            return;
        }
        let uc = stream.next_1d();
        let u = stream.next_2d();
        let Some(bs) = bsdf.sample_f(wo, uc, u) else {
            return;
        };
        if !bs.delta {
            return;
        }
        let w = bs.weight(h.normal);
        if !(w.is_finite() && w.max_element() > 0.0) {
            return;
        }
        power *= w;
        deltas += 1;
        let mut s = Spawn::leaving(h.surface_point(), h.prim);
        ray = s.spawn_ray(bs.wi).at_time(time);
        counters.photon += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;
    use crate::sampler::{hash, unit_f32};

    fn unit(i: u64, k: u64) -> f32 {
        unit_f32(hash(&[i, k]))
    }

    /// Photons on the plane z = 0 (normal +z) at hashed points of the
    /// square [0, 1]², each of power `power`, and a few on the wall x = 0
    /// (normal +x) that no estimate on the floor may count.
    fn plane_photons(n: u64, power: f32) -> Vec<Photon> {
        let mut v: Vec<Photon> = (0..n)
            .map(|i| Photon {
                p: Vec3::new(unit(i, 0), unit(i, 1), 0.0),
                wi: Vec3::new(0.3, 0.1, 1.0).normalize(),
                power: Vec3::splat(power),
                n: Vec3::Z,
            })
            .collect();
        v.extend((0..n / 10).map(|i| Photon {
            p: Vec3::new(0.0, unit(i, 2), unit(i, 3) * 0.05),
            wi: Vec3::X,
            power: Vec3::splat(100.0 * power),
            n: Vec3::X,
        }));
        v
    }

    /// The nearest-photon estimate against a brute-force one: the same
    /// photons, the same radius, the same sum.
    #[test]
    fn nearest_photons_are_those_of_brute_force() {
        let photons = plane_photons(3000, 1e-3);
        let (k, max_r) = (20, 0.2);
        let map = CausticMap::from_photons(photons.clone(), k, max_r);
        assert_eq!(map.photons().len(), photons.len());
        for q in 0..200 {
            let x = Vec3::new(unit(q, 7) * 1.2 - 0.1, unit(q, 8) * 1.2 - 0.1, 0.001);
            let (got, r2) = map.estimate(x, Vec3::Z, None, |_| Vec3::ONE);
            let mut d: Vec<(f32, usize)> = photons
                .iter()
                .enumerate()
                .filter(|(_, p)| p.n.dot(Vec3::Z) >= NORMAL_COS)
                .map(|(i, p)| ((p.p - x).length_squared(), i))
                .filter(|&(d2, _)| d2 < max_r * max_r)
                .collect();
            d.sort_by(|a, b| a.0.total_cmp(&b.0));
            d.truncate(k as usize);
            let want_r2 = if d.len() == k as usize {
                d.last().unwrap().0
            } else {
                max_r * max_r
            };
            assert_eq!(r2, if d.is_empty() { 0.0 } else { want_r2 }, "{x}");
            let r = want_r2.sqrt();
            let want: f32 = d
                .iter()
                .map(|&(d2, i)| photons[i].power.x * (1.0 - d2.sqrt() / r).max(0.0))
                .sum::<f32>()
                * 3.0
                / (PI * want_r2);
            assert!(
                (got.x - want).abs() <= 1e-4 * want.max(1e-3),
                "{x}: {got} vs {want}"
            );
        }
    }

    /// Uniform photons of total power P over the unit square: the
    /// irradiance estimate in its interior is P (per unit area), within
    /// the noise of 64 photons; the lookup returns the irradiance of a
    /// nearby point; off the square (beyond every photon's radius) and on
    /// a surface facing another way there is none.
    #[test]
    fn uniform_photons_give_their_irradiance() {
        let n = 40_000;
        let total = 2.0;
        let map = CausticMap::from_photons(plane_photons(n, total / n as f32), 64, 0.1);
        let lambert = Bsdf::new(Vec3::Z, &[Lobe::Lambert { r: Vec3::ONE }]);
        let (mut sum, mut sq2) = (Vec2::ZERO, Vec2::ZERO);
        let m = 400;
        for q in 0..m {
            let x = Vec3::new(0.2 + 0.6 * unit(q, 4), 0.2 + 0.6 * unit(q, 5), 0.0);
            let (e, _) = map.estimate(x, Vec3::Z, None, |_| Vec3::ONE);
            let l = map.radiance(x, Vec3::Z, Vec3::Z, &lambert);
            // Lambert's f = 1/π: the radiance is E/π.
            for v in [e.x / total, l.x * PI / total] {
                assert!(v > 0.2 && v < 2.0, "{x}: {e} {l}");
            }
            sum += Vec2::new(e.x, l.x * PI) / total;
            sq2 += (Vec2::new(e.x, l.x * PI) / total - Vec2::ONE).powf(2.0);
        }
        // Unbiased on average (the cone filter's weights and the nearest
        // photons' radius; measured 1.008; the lookup 0.977: the nearest
        // stored estimate is more often one of a sparse spot, whose cell is
        // larger), and the noise of 64 photons' estimate (measured RMS 0.16
        // and 0.15).
        let mean = sum / m as f32;
        assert!((mean - Vec2::ONE).abs().max_element() < 0.03, "mean {mean}");
        let rms = (sq2 / m as f32).powf(0.5);
        assert!(rms.max_element() < 0.25, "rms {rms}");
        let far = Vec3::new(3.0, 3.0, 0.0);
        assert_eq!(map.radiance(far, Vec3::Z, Vec3::Z, &lambert), Vec3::ZERO);
        // A surface facing +y at the square's middle sees none of them.
        let side = Vec3::new(0.5, 0.5, 0.0);
        assert_eq!(map.radiance(side, Vec3::Y, Vec3::Y, &lambert), Vec3::ZERO);
    }

    /// The grid lookup against brute force: the nearest point facing the
    /// same way whose ball holds the query.
    #[test]
    fn lookup_finds_the_nearest_point_whose_ball_holds_the_query() {
        let pts: Vec<(Vec3, Vec3, Vec3, f32)> = (0..2000)
            .map(|i| {
                let p = Vec3::new(unit(i, 0), unit(i, 1), unit(i, 2) * 0.1);
                let n = if i % 7 == 0 { Vec3::X } else { Vec3::Z };
                // Radii from 0.01 to 0.2: cells of the median, and large
                // balls spanning many.
                let r = 0.01 + 0.19 * unit(i, 3).powi(4);
                (p, n, Vec3::splat(i as f32), r * r)
            })
            .collect();
        let grid = Lookup::build(pts.clone());
        for q in 0..2000 {
            let x = Vec3::new(
                unit(q, 5) * 1.4 - 0.2,
                unit(q, 6) * 1.4 - 0.2,
                unit(q, 7) * 0.2 - 0.05,
            );
            let want = pts
                .iter()
                .map(|t| ((t.0 - x).length_squared(), t))
                .filter(|(d2, t)| *d2 < t.3 && t.1.dot(Vec3::Z) >= NORMAL_COS)
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, t)| t.2);
            assert_eq!(grid.value_at(x, Vec3::Z), want, "{x}");
        }
        assert_eq!(
            Lookup::build(Vec::new()).value_at(Vec3::ZERO, Vec3::Z),
            None
        );
    }

    #[test]
    fn left_balanced_subtrees_fill_the_implicit_tree() {
        for n in 1..200usize {
            // Indices 2i+1 / 2i+2 of a tree of n nodes: the left subtree of
            // the root holds exactly the indices below n that descend from 1.
            let mut count = 0;
            let mut level = vec![1usize];
            while !level.is_empty() {
                level.retain(|&i| i < n);
                count += level.len();
                level = level.iter().flat_map(|&i| [2 * i + 1, 2 * i + 2]).collect();
            }
            assert_eq!(left_size(n), count, "{n}");
        }
    }
}
