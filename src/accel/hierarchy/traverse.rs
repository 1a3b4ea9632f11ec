//! Walking the hierarchy BVH: a stack of nodes whose boxes the ray enters,
//! the children of a node pushed far-first so the nearest entry is popped
//! next; a node whose entry lies beyond the best hit so far is dropped when
//! popped. `nodes_visited` counts every box tested.
//!
//! The stack lives in a per-thread scratch vector (nodes may have up to
//! [`MAX_CHILDREN`] children and the scene's depth is not bounded, so a fixed
//! array would need a limit), reused by every ray of the thread.

use super::{HierarchyBvh, Kind, MAX_CHILDREN, NO_SPACE};
use crate::accel::{PrimHit, Query};
use crate::math::Ray;
use crate::shape::Shape;
use crate::stats::Counters;
use std::cell::RefCell;

#[derive(Clone, Copy)]
struct Entry {
    node: u32,
    /// Where the ray enters the node's box.
    t: f32,
    /// Index into the walk's object rays, or [`NO_SPACE`] for the world ray.
    space: u32,
}

#[derive(Default)]
struct Scratch {
    stack: Vec<Entry>,
    /// The ray in the space of each carrying transform node entered so far.
    rays: Vec<Ray>,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// Visits, nearest entry first, the leaves whose boxes the ray enters within
/// `[tmin, *t_limit]`. `leaf(ids, ray, object_space, t_limit, c)` tests a
/// leaf with the ray in the leaf's space, may lower `*t_limit`, and returns
/// true to stop. `seen(node, entered)` is told every box tested (for the
/// traversal views).
fn walk(
    h: &HierarchyBvh,
    ray: &Ray,
    tmin: f32,
    t_limit: &mut f32,
    c: &mut Counters,
    mut leaf: impl FnMut(&[u32], &Ray, bool, &mut f32, &mut Counters) -> bool,
    mut seen: impl FnMut(u32, bool),
) {
    let Some(root) = h.nodes.first() else {
        return;
    };
    let inv = ray.dir.recip();
    c.nodes_visited += 1;
    let root_hit = root.bounds.hit(ray, inv, tmin, *t_limit);
    seen(0, root_hit.is_some());
    let Some((t0, _)) = root_hit else {
        return;
    };
    SCRATCH.with_borrow_mut(|s| {
        s.stack.clear();
        s.rays.clear();
        s.stack.push(Entry {
            node: 0,
            t: t0,
            space: NO_SPACE,
        });
        while let Some(e) = s.stack.pop() {
            if e.t > *t_limit {
                continue; // found something nearer since it was pushed
            }
            match h.nodes[e.node as usize].kind {
                Kind::Leaf {
                    start,
                    count,
                    object_space,
                } => {
                    let r = if object_space {
                        &s.rays[e.space as usize]
                    } else {
                        ray
                    };
                    let ids = &h.ids[start as usize..(start + count) as usize];
                    if leaf(ids, r, object_space, t_limit, c) {
                        return;
                    }
                }
                Kind::Inner {
                    first,
                    count,
                    space,
                } => {
                    let space = if space == NO_SPACE {
                        e.space
                    } else {
                        // Once per visit, not once per primitive below.
                        let m = &h.spaces[space as usize];
                        s.rays.push(Ray::new(
                            m.transform_point3(ray.origin),
                            m.transform_vector3(ray.dir),
                        ));
                        s.rays.len() as u32 - 1
                    };
                    let mut hits = [(0.0f32, 0u32); MAX_CHILDREN];
                    let mut n = 0;
                    for k in first..first + count {
                        c.nodes_visited += 1;
                        let hit = h.nodes[k as usize].bounds.hit(ray, inv, tmin, *t_limit);
                        seen(k, hit.is_some());
                        if let Some((t0, _)) = hit {
                            hits[n] = (t0, k);
                            n += 1;
                        }
                    }
                    hits[..n].sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
                    s.stack
                        .extend(hits[..n].iter().map(|&(t, node)| Entry { node, t, space }));
                }
            }
        }
    });
}

/// The shape a leaf tests: in object space, a wrapper's own shape (the build
/// puts only wrappers under the node's matrix in such leaves).
#[inline]
fn tested(shape: &Shape, object_space: bool) -> &Shape {
    match shape {
        Shape::Transformed(x) if object_space => &x.shape,
        other => other,
    }
}

/// Closest hit of `q`; `seen(node, entered)` for every box
/// tested.
pub(super) fn closest(
    h: &HierarchyBvh,
    q: Query,
    c: &mut Counters,
    seen: impl FnMut(u32, bool),
) -> Option<PrimHit> {
    let Query {
        prims, ray, tmin, ..
    } = q;
    let mut best = None;
    let mut t_best = q.tmax;
    walk(
        h,
        ray,
        tmin,
        &mut t_best,
        c,
        |ids, r, obj, t_best, c| {
            for &id in ids {
                c.intersection_tests += 1;
                if let Some(t) = tested(&prims[id as usize].shape, obj).intersect(r, tmin, *t_best)
                {
                    *t_best = t;
                    best = Some(PrimHit { t, prim: id });
                }
            }
            false
        },
        seen,
    );
    best
}

/// Whether anything lies on the ray of `q` in its range.
pub(super) fn any(h: &HierarchyBvh, q: Query, c: &mut Counters) -> bool {
    let Query {
        prims, ray, tmin, ..
    } = q;
    let mut hit = false;
    let mut t_limit = q.tmax;
    walk(
        h,
        ray,
        tmin,
        &mut t_limit,
        c,
        |ids, r, obj, t_limit, c| {
            hit = ids.iter().any(|&id| {
                c.intersection_tests += 1;
                tested(&prims[id as usize].shape, obj)
                    .intersect(r, tmin, *t_limit)
                    .is_some()
            });
            hit
        },
        |_, _| {},
    );
    hit
}
