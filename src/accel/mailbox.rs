//! Mailboxing: not testing a primitive twice for one ray when it sits in
//! several cells the ray crosses.
//!
//! The classic mailbox stores "last ray id" in every primitive, which needs
//! shared mutable state (and a ray counter) across threads. This one lives on
//! the stack of one traversal instead: a small direct-mapped cache of the ids
//! tested so far, slot = `id mod SLOTS`. A collision only evicts an entry, so
//! the cache can forget (a primitive gets re-tested: wasted work, same result)
//! but never claims a primitive was tested when it was not. Neighbouring
//! primitives of a mesh have consecutive ids and so land in different slots.
//!
//! Skipping a re-test is sound because the traversal keeps its best hit
//! across cells and only shrinks `tmax`: if the first test found nothing in
//! `(tmin, tmax_then)` it finds nothing in the smaller interval now, and if it
//! found a hit, that hit is already the best or beaten.

use super::{PrimHit, Query};
use crate::stats::Counters;

/// Slots in the cache (a power of two). 64 × 4 bytes is one small memset per
/// ray; measured on random triangle soups it removes nearly all duplicates.
const SLOTS: usize = 64;

/// The ids recently tested by one ray.
pub(crate) struct Mailbox {
    slots: [u32; SLOTS],
}

impl Mailbox {
    /// An empty mailbox (`u32::MAX` is never a primitive id).
    #[inline]
    pub(crate) fn new() -> Self {
        Self {
            slots: [u32::MAX; SLOTS],
        }
    }

    /// True when `id` was not seen before (and records it); false when it
    /// was tested already and can be skipped.
    #[inline]
    pub(crate) fn first_visit(&mut self, id: u32) -> bool {
        let slot = &mut self.slots[id as usize & (SLOTS - 1)];
        if *slot == id {
            false
        } else {
            *slot = id;
            true
        }
    }
}

/// The primitive tests of one query: leaves' or cells' items, each tested
/// at most once when mailboxing is on (cells and leaves front to back:
/// grid, octree, nested grid), one `intersection_tests` count per
/// primitive tested; the closest hit so far is kept across them.
pub(crate) struct ItemTests<'a> {
    q: Query<'a>,
    best: Option<PrimHit>,
    seen: Option<Mailbox>,
}

impl<'a> ItemTests<'a> {
    /// Tests for query `q`, with mailboxing on or off.
    #[inline]
    pub(crate) fn new(q: Query<'a>, mailbox: bool) -> Self {
        Self {
            q,
            best: None,
            seen: mailbox.then(Mailbox::new),
        }
    }

    /// Whether `id` is to be tested (not skipped by the mailbox).
    #[inline]
    fn fresh(&mut self, id: u32) -> bool {
        self.seen.as_mut().is_none_or(|m| m.first_visit(id))
    }

    /// Whether an item of `items` lies on the ray in the query's range
    /// (stops at the first).
    #[inline]
    pub(crate) fn any(&mut self, items: &[u32], c: &mut Counters) -> bool {
        items.iter().any(|&id| {
            if !self.fresh(id) {
                return false;
            }
            c.intersection_tests += 1;
            self.q.hit(id).is_some()
        })
    }

    /// Tests `items` against the best hit so far, keeping the closer (the
    /// range's end shrinks to it).
    #[inline]
    pub(crate) fn closest(&mut self, items: &[u32], c: &mut Counters) {
        for &id in items {
            if !self.fresh(id) {
                continue;
            }
            c.intersection_tests += 1;
            if let Some(t) = self.q.hit(id) {
                self.q.tmax = t;
                self.best = Some(PrimHit { t, prim: id });
            }
        }
    }

    /// [`closest`](Self::closest) on the items of a cell the ray leaves at
    /// `t_exit`; true once the best hit is accepted (it lies within the
    /// cell: nothing in a later cell can be closer).
    #[inline]
    pub(crate) fn closest_in(&mut self, items: &[u32], t_exit: f32, c: &mut Counters) -> bool {
        self.closest(items, c);
        self.q.tmax <= t_exit
    }

    /// The upper end of the range still searched: the best hit's `t`, or
    /// the query's `tmax` while there is none.
    #[inline]
    pub(crate) fn t_best(&self) -> f32 {
        self.q.tmax
    }

    /// The closest hit found.
    #[inline]
    pub(crate) fn best(&self) -> Option<PrimHit> {
        self.best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn remembers_and_forgets_only_on_collision() {
        let mut m = Mailbox::new();
        assert!(m.first_visit(3));
        assert!(!m.first_visit(3));
        assert!(m.first_visit(4));
        assert!(!m.first_visit(3));
        // Same slot as 3: evicts it, so 3 is (harmlessly) tested again.
        assert!(m.first_visit(3 + SLOTS as u32));
        assert!(m.first_visit(3));
    }
}
