//! Ray queries for embedders and benchmarks: a triangle mesh from raw vertex
//! and index buffers, behind the fast BVH, queried without a counters
//! argument (statistics are opt-in through [`MeshScene::intersect_with`]).
//!
//! ```
//! use glint::math::{Ray, Vec3};
//! use glint::query::MeshScene;
//! let vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
//! let scene = MeshScene::new(&vertices, &[[0, 1, 2]]).unwrap();
//! let ray = Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::NEG_Z);
//! let hit = scene.intersect(&ray, 0.0, f32::INFINITY).unwrap();
//! assert_eq!((hit.t, hit.triangle), (1.0, 0));
//! // One of a run of rays going the same way (camera rays): the same hit.
//! assert_eq!(scene.intersect_coherent(&ray, 0.0, f32::INFINITY), Some(hit));
//! assert!(scene.occluded(&ray, 0.0, 2.0));
//! ```

use crate::accel::bvh8::{Bvh8, TrianglesOnly};
pub use crate::accel::bvh8::{PacketRay, PACKET};
use crate::math::{Ray, Vec3};
use crate::stats::{NoStats, TraversalStats};
use rayon::prelude::*;

/// What a query hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshHit {
    /// Ray parameter.
    pub t: f32,
    /// Index of the triangle in the index buffer.
    pub triangle: u32,
}

/// Why buffers were refused.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// An index refers past the vertex buffer.
    #[error("triangle {triangle} refers to vertex {index}, but there are {vertices} vertices")]
    IndexOutOfRange {
        /// The triangle.
        triangle: usize,
        /// The bad index.
        index: u32,
        /// Length of the vertex buffer.
        vertices: usize,
    },
    /// A vertex coordinate is infinite or NaN.
    #[error("vertex {0} has a coordinate that is not finite")]
    NotFinite(usize),
    /// More triangles than the BVH addresses.
    #[error("{0} triangles: at most 2^28 are supported")]
    TooLarge(usize),
}

/// Vertices or triangles checked per task of [`MeshScene::new`].
const CHECK_CHUNK: usize = 16 * 1024;

/// The index of the first item of `items` that is `bad`, checked in
/// chunks on all threads (each chunk a plain loop: rayon's search by item
/// checks whether to stop at every item).
fn first<T: Sync>(items: &[T], bad: impl Fn(&T) -> bool + Sync) -> Option<usize> {
    let chunk = items
        .par_chunks(CHECK_CHUNK)
        .position_first(|c| c.iter().any(&bad))?;
    let at = chunk * CHECK_CHUNK;
    Some(at + items[at..].iter().position(&bad).expect("in this chunk"))
}

/// A triangle mesh ready for ray queries. It keeps its own copy of the
/// triangles (in the BVH's leaf blocks), so the caller's buffers may be
/// dropped after [`MeshScene::new`].
pub struct MeshScene {
    bvh: Bvh8,
    triangles: usize,
}

impl MeshScene {
    /// Builds the BVH (in parallel on rayon's pool) over `indices`, triangles
    /// of `vertices`. Degenerate triangles are kept out (never hit).
    pub fn new<V>(vertices: &[V], indices: &[[u32; 3]]) -> Result<Self, MeshError>
    where
        V: Copy + Into<Vec3> + Sync,
    {
        if indices.len() >= 1 << 28 {
            return Err(MeshError::TooLarge(indices.len()));
        }
        // On all threads, chunk by chunk (a serial pass was a millisecond
        // of the 2-thread build of a 1M-triangle mesh); the first
        // offender, as one pass in order finds it.
        let bad_vertex = |v: &V| !(*v).into().is_finite();
        if let Some(i) = first(vertices, bad_vertex) {
            return Err(MeshError::NotFinite(i));
        }
        let out_of_range = |t: &[u32; 3]| t.iter().copied().find(|&i| i as usize >= vertices.len());
        if let Some(triangle) = first(indices, |t| out_of_range(t).is_some()) {
            return Err(MeshError::IndexOutOfRange {
                triangle,
                index: out_of_range(&indices[triangle]).expect("found out of range"),
                vertices: vertices.len(),
            });
        }
        Ok(MeshScene {
            bvh: Bvh8::from_mesh(vertices, indices),
            triangles: indices.len(),
        })
    }

    /// Closest hit with `tmin < t < tmax`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<MeshHit> {
        self.intersect_with(ray, tmin, tmax, &mut NoStats)
    }

    /// [`intersect`](Self::intersect) of a ray from a coherent run: rays
    /// traced one after another whose directions mostly keep their signs
    /// from one to the next (camera rays in scan order). The same hit, bit
    /// for bit, from a walk whose descents run a copy of the node loop
    /// compiled for the ray's octant (each plane loaded from a fixed
    /// offset in the node). Faster for such runs, slower where the octant
    /// changes from ray to ray (the jump to the octant's copy
    /// mispredicts); `docs/performance.md` has the numbers.
    #[inline]
    pub fn intersect_coherent(&self, ray: &Ray, tmin: f32, tmax: f32) -> Option<MeshHit> {
        self.intersect_coherent_with(ray, tmin, tmax, &mut NoStats)
    }

    /// Whether anything lies on the ray with `tmin < t < tmax` (stops at the
    /// first hit).
    #[inline]
    pub fn occluded(&self, ray: &Ray, tmin: f32, tmax: f32) -> bool {
        self.occluded_with(ray, tmin, tmax, &mut NoStats)
    }

    /// [`MeshScene::intersect`], counting nodes and tests into `stats`
    /// (e.g. a `stats::Counters`).
    #[inline]
    pub fn intersect_with<S: TraversalStats>(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        stats: &mut S,
    ) -> Option<MeshHit> {
        self.bvh
            .closest(&TrianglesOnly, ray, tmin, tmax, stats)
            .map(|(t, triangle)| MeshHit { t, triangle })
    }

    /// [`MeshScene::intersect_coherent`], counting into `stats`.
    #[inline]
    pub fn intersect_coherent_with<S: TraversalStats>(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        stats: &mut S,
    ) -> Option<MeshHit> {
        self.bvh
            .closest_coherent(&TrianglesOnly, ray, tmin, tmax, stats)
            .map(|(t, triangle)| MeshHit { t, triangle })
    }

    /// [`MeshScene::occluded`], counting into `stats`.
    #[inline]
    pub fn occluded_with<S: TraversalStats>(
        &self,
        ray: &Ray,
        tmin: f32,
        tmax: f32,
        stats: &mut S,
    ) -> bool {
        self.bvh.any(&TrianglesOnly, ray, tmin, tmax, stats)
    }

    /// The closest hit of each ray of a packet of at most [`PACKET`] rays
    /// into `out[..rays.len()]`: what [`MeshScene::intersect`] returns for
    /// each, bit for bit, in less time when the rays go the same way
    /// (neighbouring camera rays).
    ///
    /// # Panics
    /// If `rays` holds more than [`PACKET`] rays or `out` fewer than `rays`.
    #[inline]
    pub fn intersect_packet(&self, rays: &[PacketRay], out: &mut [Option<MeshHit>]) {
        self.intersect_packet_with(rays, out, &mut NoStats)
    }

    /// [`MeshScene::intersect_packet`], counting into `stats` (nodes once
    /// per packet, triangles once per ray).
    #[inline]
    pub fn intersect_packet_with<S: TraversalStats>(
        &self,
        rays: &[PacketRay],
        out: &mut [Option<MeshHit>],
        stats: &mut S,
    ) {
        let mut hits = [None; PACKET];
        self.bvh
            .closest_packet(&TrianglesOnly, rays, &mut hits[..], stats);
        for (o, h) in out[..rays.len()].iter_mut().zip(hits) {
            *o = h.map(|(t, triangle)| MeshHit { t, triangle });
        }
    }

    /// Which rays of a packet of at most [`PACKET`] are blocked: bit `r`
    /// set when [`MeshScene::occluded`] says so for ray `r`.
    ///
    /// # Panics
    /// If `rays` holds more than [`PACKET`] rays.
    #[inline]
    pub fn occluded_packet(&self, rays: &[PacketRay]) -> u32 {
        self.occluded_packet_with(rays, &mut NoStats)
    }

    /// [`MeshScene::occluded_packet`], counting into `stats`.
    #[inline]
    pub fn occluded_packet_with<S: TraversalStats>(
        &self,
        rays: &[PacketRay],
        stats: &mut S,
    ) -> u32 {
        self.bvh.any_packet(&TrianglesOnly, rays, &[], stats)
    }

    /// Triangles in the index buffer it was built from.
    pub fn triangle_count(&self) -> usize {
        self.triangles
    }

    /// Bytes of the structure: BVH nodes and the triangle blocks (which hold
    /// every triangle's vertices; nothing else is kept).
    pub fn memory_bytes(&self) -> usize {
        self.bvh.memory_bytes()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::Triangle;

    #[test]
    fn bad_buffers_are_refused() {
        let v = [[0.0f32; 3]; 3];
        assert!(matches!(
            MeshScene::new(&v, &[[0, 1, 3]]),
            Err(MeshError::IndexOutOfRange { index: 3, .. })
        ));
        let v = [[0.0, f32::NAN, 0.0]];
        assert_eq!(MeshScene::new(&v, &[]).err(), Some(MeshError::NotFinite(0)));
        // Buffers checked in parallel pieces report the first offender.
        let n = 5 * CHECK_CHUNK + 7;
        let mut v = vec![[0.0f32, 1.0, 2.0]; n];
        let mut t: Vec<[u32; 3]> = (0..n as u32 - 2).map(|i| [i, i + 1, i + 2]).collect();
        t[4 * CHECK_CHUNK + 3] = [0, n as u32 + 9, 1];
        t[2 * CHECK_CHUNK + 1] = [0, 1, n as u32];
        t[2 * CHECK_CHUNK + 2] = [n as u32 + 1, 1, 2];
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .expect("a thread pool");
        let refused = |v: &[[f32; 3]], t: &[[u32; 3]]| pool.install(|| MeshScene::new(v, t).err());
        assert_eq!(
            refused(&v, &t),
            Some(MeshError::IndexOutOfRange {
                triangle: 2 * CHECK_CHUNK + 1,
                index: n as u32,
                vertices: n
            })
        );
        v[3 * CHECK_CHUNK + 5][2] = f32::INFINITY;
        v[CHECK_CHUNK + 11][0] = f32::NAN;
        assert_eq!(
            refused(&v, &t),
            Some(MeshError::NotFinite(CHECK_CHUNK + 11))
        );
    }

    /// Same hits as testing every triangle with the shape's own test, one
    /// ray at a time and in packets.
    #[test]
    fn agrees_with_every_triangle_tested() {
        let mut r = crate::testutil::Rng::new(12345);
        let mut f = move || r.range(-1.0, 1.0);
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        for i in 0..3000u32 {
            let c = Vec3::new(f(), f(), f()) * 4.0;
            for _ in 0..3 {
                vertices.push(c + Vec3::new(f(), f(), f()) * 0.3);
            }
            indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let scene = MeshScene::new(&vertices, &indices).unwrap();
        let tris: Vec<Triangle> = indices
            .iter()
            .map(|t| {
                Triangle::new(
                    vertices[t[0] as usize],
                    vertices[t[1] as usize],
                    vertices[t[2] as usize],
                )
            })
            .collect();
        let mut rays = Vec::new();
        for _ in 0..2000 {
            let ray = Ray::new(Vec3::new(f(), f(), f()) * 6.0, Vec3::new(f(), f(), f()));
            let mut want: Option<(f32, u32)> = None;
            for (i, t) in tris.iter().enumerate() {
                let tmax = want.map_or(f32::INFINITY, |w| w.0);
                if let Some(t) = t.intersect(&ray, 0.0, tmax) {
                    want = Some((t, i as u32));
                }
            }
            let got = scene.intersect(&ray, 0.0, f32::INFINITY);
            assert_eq!(want.map(|w| w.0), got.map(|h| h.t), "{ray:?}");
            assert_eq!(want.is_some(), scene.occluded(&ray, 0.0, f32::INFINITY));
            rays.push(PacketRay {
                ray,
                tmin: 0.0,
                tmax: f32::INFINITY,
            });
        }
        // The same rays in packets: the single queries' answers.
        for p in rays.chunks(5) {
            let mut out = [None; PACKET];
            scene.intersect_packet(p, &mut out);
            let blocked = scene.occluded_packet(p);
            for (i, q) in p.iter().enumerate() {
                assert_eq!(out[i], scene.intersect(&q.ray, q.tmin, q.tmax));
                assert_eq!(
                    blocked >> i & 1 != 0,
                    scene.occluded(&q.ray, q.tmin, q.tmax)
                );
            }
        }
    }
}
