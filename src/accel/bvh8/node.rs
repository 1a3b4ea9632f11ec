//! The fast BVH's memory layout: 8-wide nodes with their children's boxes in
//! structure-of-arrays form, and leaves of triangles four at a time.

use super::lanes::{Lanes, W};
use glam::Vec4;

/// A child reference: an inner node's index, or a leaf (high bit set) whose
/// low 28 bits are its first [`Tri4`] block and bits 28–30 its block count
/// minus one.
pub(crate) type ChildRef = u32;

/// The high bit of a [`ChildRef`]: a leaf.
pub(crate) const LEAF: u32 = 1 << 31;
/// An unused child slot (its box is empty, so no ray ever follows it).
pub(crate) const EMPTY: ChildRef = u32::MAX;
/// Bits for a leaf's first block.
pub(crate) const START_BITS: u32 = 28;
/// Most items one leaf holds (eight blocks of four, in the builds of
/// large meshes; others stop at four blocks, see `build::LEAF_ITEMS`;
/// the SAH decides below).
pub(crate) const MAX_LEAF_ITEMS: usize = 32;
const _: () = assert!(MAX_LEAF_ITEMS <= 4 * 8, "a leaf holds at most eight blocks");

/// A leaf reference: `count` (1..=8) blocks or items from `start`.
#[inline]
pub(crate) fn leaf(start: usize, count: usize) -> ChildRef {
    debug_assert!(start < 1 << START_BITS && (1..=8).contains(&count));
    LEAF | ((count as u32 - 1) << START_BITS) | start as u32
}

/// The `(start, count)` of a leaf reference.
#[inline]
pub(crate) fn leaf_range(r: ChildRef) -> (usize, usize) {
    (
        (r & ((1 << START_BITS) - 1)) as usize,
        (((r >> START_BITS) & 7) + 1) as usize,
    )
}

/// Whether a reference is a leaf (or [`EMPTY`], which is never followed).
#[inline]
pub(crate) fn is_leaf(r: ChildRef) -> bool {
    r & LEAF != 0
}

/// A node with up to [`W`] (eight) children. `planes` holds the children's
/// boxes as `[min x, min y, min z, max x, max y, max z]`, one lane per child,
/// so that one ray is tested against all eight boxes with a handful of
/// 8-lane operations (one AVX instruction each, two SSE ones); a ray's
/// octant picks which of min/max is the near plane.
///
/// 224 bytes, padded and aligned to 256: four cache lines, two aligned
/// 128-byte pairs, which the CPU's adjacent-line prefetcher fetches
/// together. Eight children per node (Embree's choice on AVX machines)
/// halve the chain of dependent node loads of a 4-wide tree, and a node's
/// test costs about the same.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(256))]
pub(crate) struct Node {
    /// Children's boxes, padded by the scene margin.
    pub planes: [Lanes; 6],
    /// Children: node indices or leaf references.
    pub child: [ChildRef; W],
    /// `1 << axis` of the axis the node's range was first divided on: its
    /// children's slots run from that division's lower side to its upper
    /// side (0 where unknown). An any-hit walk enters the far side first
    /// (see `traverse::any`). In the line of `child`, which the step reads
    /// anyway, and in the padding: the node is no larger.
    pub split: u8,
}

impl Node {
    /// A node whose slots are all empty (empty boxes: `min > max`).
    pub const EMPTY: Node = Node {
        planes: [
            Lanes::INFINITY,
            Lanes::INFINITY,
            Lanes::INFINITY,
            Lanes::NEG_INFINITY,
            Lanes::NEG_INFINITY,
            Lanes::NEG_INFINITY,
        ],
        child: [EMPTY; W],
        split: 0,
    };

    /// The slot of `mask` (not empty) on the far side of the node's first
    /// division for rays of `octant`: the highest where they run towards
    /// +axis of [`split`](Self::split) (or the division is unknown), else
    /// the lowest. The any-hit walks enter it first.
    #[inline(always)]
    pub fn far_slot(&self, octant: usize, mask: u32) -> usize {
        debug_assert!(mask != 0);
        (if octant & usize::from(self.split) != 0 {
            mask.trailing_zeros()
        } else {
            31 - mask.leading_zeros()
        }) as usize
    }

    /// Sets slot `i` to `r` with the box `[lo, hi]`.
    pub fn set(&mut self, i: usize, r: ChildRef, lo: glam::Vec3, hi: glam::Vec3) {
        for a in 0..3 {
            self.planes[a][i] = lo[a];
            self.planes[a + 3][i] = hi[a];
        }
        self.child[i] = r;
    }
}

/// Asks the CPU to start loading every cache line of `*p` (a node: four, a
/// block: three); a hint with no effect on results. Traversal calls it for
/// the children a ray enters, so that their loads overlap instead of waiting
/// one after another (a profile of the 1M-triangle mesh put a third of the
/// time on the first load of a node or a triangle block).
#[inline(always)]
pub(crate) fn prefetch<T>(p: &T) {
    let base = (p as *const T).cast::<i8>();
    for off in (0..std::mem::size_of::<T>()).step_by(64) {
        // `wrapping_add` forms the address without any access.
        prefetch_line(base.wrapping_add(off));
    }
}

/// One line's prefetch hint (x86-64), nothing elsewhere (portable fallback).
#[inline(always)]
fn prefetch_line(p: *const i8) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // SAFETY: `_mm_prefetch` needs the `sse` target feature, which every
        // x86-64 CPU has (it is in the x86_64 baseline Rust compiles for, so
        // `cfg(target_arch = "x86_64")` implies it). PREFETCHT0 never faults
        // and never reads into or writes a register or memory: it only hints
        // the cache, for any address, valid or not.
        unsafe { _mm_prefetch::<_MM_HINT_T0>(p) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// An item id flag marking a lane that is not a triangle (its vertices are
/// NaN): the leaf test skips it, and the item is tested through the
/// aggregate's fallback (spheres, transformed shapes).
pub(crate) const OTHER: u32 = 1 << 31;
/// The id of an unused lane (NaN vertices too).
pub(crate) const NO_ITEM: u32 = u32::MAX;

/// Four triangles, vertex coordinates in structure-of-arrays form:
/// `v[vertex][axis]` holds that coordinate of the four triangles (160 bytes).
///
/// Aligned to 32 (160 is a multiple, so no padding): a block then spans
/// three cache lines, never four (at 16 it straddled a fourth half the time,
/// and the block loads are the leaves' cache misses).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(32))]
pub(crate) struct Tri4 {
    /// `v[k][a]`: coordinate `a` of vertex `k`, one lane per triangle.
    pub v: [[Vec4; 3]; 3],
    /// Item ids (primitive indices), [`OTHER`]-flagged or [`NO_ITEM`].
    pub ids: [u32; 4],
}

impl Tri4 {
    /// A block with every lane unused.
    pub const EMPTY: Tri4 = Tri4 {
        v: [[Vec4::NAN; 3]; 3],
        ids: [NO_ITEM; 4],
    };

    /// Whether some lane holds a non-triangle item.
    #[inline]
    pub fn has_other(&self) -> bool {
        self.ids.iter().any(|&id| id != NO_ITEM && id & OTHER != 0)
    }

    /// The ids of the items that are not triangles (the flag cleared).
    #[inline(always)]
    pub fn others(&self) -> impl Iterator<Item = u32> + '_ {
        self.ids
            .iter()
            .filter(|&&id| id != NO_ITEM && id & OTHER != 0)
            .map(|&id| id & !OTHER)
    }

    /// How many items the block holds (its used lanes).
    #[inline(always)]
    pub fn items(&self) -> u64 {
        self.ids.iter().filter(|&&id| id != NO_ITEM).count() as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leaf_references_round_trip() {
        for (s, c) in [(0, 1), (12345, 8), ((1 << START_BITS) - 1, 3)] {
            let r = leaf(s, c);
            assert!(is_leaf(r));
            assert_eq!(leaf_range(r), (s, c));
        }
        assert!(!is_leaf(7));
        assert!(is_leaf(EMPTY));
    }

    #[test]
    fn layout_is_cache_friendly() {
        assert_eq!(std::mem::size_of::<Node>(), 256);
        assert_eq!(std::mem::align_of::<Node>(), 256);
        assert_eq!(std::mem::align_of::<Tri4>(), 32);
        assert_eq!(std::mem::size_of::<Tri4>(), 160);
    }
}
