//! Helpers for the accelerators' unit tests: random primitive soups (from
//! the tests' one generator, [`crate::testutil::Rng`]) and a comparison
//! with brute force.

use super::{Aggregate, Brute, Query};
use crate::math::{Ray, Vec3};
use crate::primitive::Primitive;
use crate::shape::{Shape, Sphere, Triangle};
use crate::stats::Counters;

pub(crate) use crate::testutil::Rng;

pub(crate) fn prim(shape: Shape) -> Primitive {
    Primitive {
        shape,
        material: 0,
        instance: 0,
    }
}

pub(crate) fn sphere(c: Vec3, r: f32) -> Primitive {
    prim(Shape::Sphere(Sphere {
        center: c,
        radius: r,
    }))
}

/// `n` small triangles and `n / 4` spheres scattered in [-5, 5]³.
pub(crate) fn soup(seed: u64, n: usize) -> Vec<Primitive> {
    let mut r = Rng::new(seed);
    let mut p = Vec::new();
    for _ in 0..n {
        let a = r.v(-5.0, 5.0);
        p.push(prim(Shape::Triangle(Triangle::new(
            a,
            a + r.v(-1.0, 1.0),
            a + r.v(-1.0, 1.0),
        ))));
    }
    for _ in 0..n / 4 {
        p.push(sphere(r.v(-5.0, 5.0), 0.1 + 0.5 * r.f()));
    }
    p
}

/// A 64x64 height field of 8,192 triangles (x and z from 0 to 64).
pub(crate) fn terrain() -> Vec<Primitive> {
    let z = |i: usize, j: usize| ((i as f32 * 0.3).sin() + (j as f32 * 0.2).cos()) * 2.0;
    let v = |i: usize, j: usize| Vec3::new(i as f32, z(i, j), j as f32);
    let mut p = Vec::new();
    for i in 0..64 {
        for j in 0..64 {
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i, j + 1), v(i + 1, j + 1));
            p.push(prim(Shape::Triangle(Triangle::new(a, b, d))));
            p.push(prim(Shape::Triangle(Triangle::new(a, d, c))));
        }
    }
    p
}

/// A random ray from above the [`terrain`] down to a point of it.
pub(crate) fn terrain_ray(r: &mut Rng) -> Ray {
    let o = Vec3::new(64.0 * r.f(), 30.0, 64.0 * r.f());
    let to = Vec3::new(64.0 * r.f(), 0.0, 64.0 * r.f());
    Ray::new(o, to - o)
}

/// A random ray from around the soup, aimed through it.
pub(crate) fn ray(r: &mut Rng) -> Ray {
    let o = r.v(-8.0, 8.0);
    Ray::new(o, r.v(-3.0, 3.0) - o)
}

/// Asserts that `accel` agrees with brute force on `rays` random rays, for
/// the closest hit and for occlusion, and returns the counters it used.
pub(crate) fn assert_agrees(accel: &dyn Aggregate, prims: &[Primitive], rays: usize) -> Counters {
    let mut r = Rng::new(7);
    let queries = (0..rays).map(|i| {
        let range = if i % 3 == 0 {
            (0.2, 0.9)
        } else {
            (0.0, f32::INFINITY)
        };
        (ray(&mut r), range.0, range.1)
    });
    assert_agrees_on(accel, prims, queries)
}

/// [`assert_agrees`] on given `(ray, tmin, tmax)` queries.
pub(crate) fn assert_agrees_on(
    accel: &dyn Aggregate,
    prims: &[Primitive],
    queries: impl IntoIterator<Item = (Ray, f32, f32)>,
) -> Counters {
    let ids = (0..prims.len() as u32).collect();
    let brute = Brute::new(prims, ids);
    let mut c = Counters::default();
    let mut cb = Counters::default();
    for (i, (ray, tmin, tmax)) in queries.into_iter().enumerate() {
        let want = brute.intersect(Query::new(prims, &ray, tmin, tmax), &mut cb);
        let got = accel.intersect(Query::new(prims, &ray, tmin, tmax), &mut c);
        // The coherent hint never changes an answer (`bvh8` walks such a
        // query with its per-octant copy); counted apart, so that the
        // counts returned are the plain queries'.
        let hinted = Query::new(prims, &ray, tmin, tmax).with_coherent(true);
        let coherent = accel.intersect(hinted, &mut Counters::default());
        assert_eq!(coherent, got, "ray {i}: the coherent hint changed the hit");
        match (want, got) {
            (None, None) => {}
            (Some(w), Some(g)) => assert!(
                (w.t - g.t).abs() <= 1e-4 * w.t.abs().max(1.0),
                "ray {i}: {w:?} vs {g:?}"
            ),
            _ => panic!(
                "ray {i} {ray:?}: brute {want:?}, {} {got:?}",
                accel.describe()
            ),
        }
        assert_eq!(
            brute.occluded(Query::new(prims, &ray, tmin, tmax), &mut cb),
            accel.occluded(Query::new(prims, &ray, tmin, tmax), &mut c),
            "ray {i}"
        );
    }
    c
}

/// `n` triangles at x = 1.2^k, all of one shape across the x axis (each
/// covers y + z ≥ 1/2 of its box): binned over the whole range, every
/// split peels off the few largest, so the BVH over them is a chain as
/// deep as the builder goes.
pub(crate) fn chain(n: i32) -> Vec<Primitive> {
    (0..n)
        .map(|k| {
            let x = 1.2f32.powi(k);
            let v = |y: f32, z: f32| Vec3::new(x, y, z);
            prim(Shape::Triangle(Triangle::new(
                v(-0.5, 1.0),
                v(1.0, 1.0),
                v(1.0, -0.5),
            )))
        })
        .collect()
}

/// The closest hit of `ray` in `(0, ∞)` that `a` finds among `prims`.
pub(crate) fn first_hit(
    a: &impl Aggregate,
    prims: &[Primitive],
    ray: &Ray,
) -> Option<super::PrimHit> {
    let q = Query::new(prims, ray, 0.0, f32::INFINITY);
    a.intersect(q, &mut Counters::default())
}
