//! BVH traversal: depth-first with a small stack, the nearer child first.
//!
//! "Nearer" is judged by the sign of the ray's direction along the node's
//! split axis (pbrt's rule: no extra box test to order the children). A node
//! is skipped when the ray misses its box within `[tmin, t_best]`, so once a
//! hit is found every box whose entry lies beyond it is skipped without
//! descending. `nodes_visited` counts every node whose box is tested.

use super::split::FORCE_MEDIAN_DEPTH;
use super::Bvh;
use crate::accel::mailbox::ItemTests;
use crate::accel::{PrimHit, Query};
use crate::math::Ray;
use crate::stats::Counters;

/// Entries of the traversal stack: one per level at most, and the builder
/// keeps the tree within `FORCE_MEDIAN_DEPTH + 32` levels.
const STACK: usize = 64;
const _: () = assert!(FORCE_MEDIAN_DEPTH + 32 <= STACK);

/// One node the traversal tested.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeVisit {
    /// Node index (depth-first order; 0 is the root).
    pub node: u32,
    /// Whether the ray entered its box (within `[tmin, best hit so far]`).
    pub entered: bool,
}

/// Visits, front to back, the leaves whose boxes the ray enters within
/// `[tmin, *t_limit]`; `leaf` tests a leaf's ids, may lower `*t_limit`, and
/// returns true to stop the walk. `visit` sees every node whose box is
/// tested (a no-op for rendering, compiled away).
#[inline]
fn walk(
    bvh: &Bvh,
    ray: &Ray,
    tmin: f32,
    t_limit: &mut f32,
    c: &mut Counters,
    mut visit: impl FnMut(NodeVisit),
    mut leaf: impl FnMut(&[u32], &mut f32, &mut Counters) -> bool,
) {
    if bvh.nodes.is_empty() {
        return;
    }
    let inv = ray.dir.recip();
    let neg = [inv.x < 0.0, inv.y < 0.0, inv.z < 0.0];
    let mut stack = [0u32; STACK];
    let mut sp = 0;
    let mut k = 0usize;
    loop {
        let n = &bvh.nodes[k];
        c.nodes_visited += 1;
        let entered = n.bounds.hit(ray, inv, tmin, *t_limit).is_some();
        visit(NodeVisit {
            node: k as u32,
            entered,
        });
        if entered {
            if !n.is_leaf() {
                let (near, far) = if neg[n.axis as usize] {
                    (n.offset, k as u32 + 1)
                } else {
                    (k as u32 + 1, n.offset)
                };
                stack[sp] = far;
                sp += 1;
                k = near as usize;
                continue;
            }
            let start = n.offset as usize;
            if leaf(&bvh.ids[start..start + n.count as usize], t_limit, c) {
                return;
            }
        }
        if sp == 0 {
            return;
        }
        sp -= 1;
        k = stack[sp] as usize;
    }
}

/// Closest hit of `q`; `visit` sees every node tested.
pub(super) fn closest(
    bvh: &Bvh,
    q: Query,
    c: &mut Counters,
    visit: impl FnMut(NodeVisit),
) -> Option<PrimHit> {
    let mut tests = ItemTests::new(q, false);
    let mut t_best = q.tmax;
    walk(
        bvh,
        q.ray,
        q.tmin,
        &mut t_best,
        c,
        visit,
        |ids, t_best, c| {
            tests.closest(ids, c);
            *t_best = tests.t_best();
            false
        },
    );
    tests.best()
}

/// Whether anything lies on the ray of `q` in its range; stops at the
/// first hit found.
pub(super) fn any(bvh: &Bvh, q: Query, c: &mut Counters) -> bool {
    let mut tests = ItemTests::new(q, false);
    let mut hit = false;
    let mut t_limit = q.tmax;
    walk(
        bvh,
        q.ray,
        q.tmin,
        &mut t_limit,
        c,
        |_| {},
        |ids, _, c| {
            hit = tests.any(ids, c);
            hit
        },
    );
    hit
}
