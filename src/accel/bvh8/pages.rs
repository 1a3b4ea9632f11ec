//! The BVH's large arrays on transparent huge pages (Linux).
//!
//! A 1M-triangle tree and its build arrays are about 130 MB: some 32,000
//! 4 KB pages. The build then spends a tenth of its time in page faults (a
//! profile of `glint bench rays` on sphere1m), and incoherent rays miss the
//! TLB at nearly every node. 2 MB pages (which the kernel gives to ranges
//! marked `MADV_HUGEPAGE` when transparent huge pages are in `madvise`
//! mode, the common default) cut both; Embree asks for them too.

/// Asks the kernel to back the unused capacity of `v` with 2 MB pages, if it
/// is large. Call it right after allocating, before the memory is written
/// (pages already touched stay small). A hint only: contents, addresses and
/// results never change, and failure is ignored.
pub(crate) fn huge_pages<T>(v: &Vec<T>) {
    #[cfg(target_os = "linux")]
    if let Some((lo, hi)) = huge_range(v.as_ptr() as usize, v.capacity() * size_of::<T>()) {
        // SAFETY: `[lo, hi)` lies inside `v`'s own live allocation (its
        // capacity; `huge_range` returns a range within the one it is given,
        // which its test checks), and `MADV_HUGEPAGE` changes no contents,
        // mapping or protection: it only lets the kernel back the range with
        // huge pages. No Rust reference or invariant depends on how pages
        // are backed, so this cannot cause undefined behaviour; an error
        // (e.g. a kernel without THP) leaves everything as it was.
        unsafe {
            libc::madvise(lo as *mut libc::c_void, hi - lo, libc::MADV_HUGEPAGE);
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = v; // elsewhere: ordinary pages
}

/// 2 MB: a transparent huge page on x86-64 and most arm64 kernels.
const HUGE: usize = 2 << 20;

/// The whole huge pages inside `[start, start + bytes)`, when the range is
/// large enough (four huge pages) to hold a few of them.
#[cfg_attr(not(target_os = "linux"), allow(dead_code))]
fn huge_range(start: usize, bytes: usize) -> Option<(usize, usize)> {
    if bytes < 4 * HUGE {
        return None; // too small to hold a few whole huge pages
    }
    let (lo, hi) = (start.next_multiple_of(HUGE), (start + bytes) / HUGE * HUGE);
    (hi > lo).then_some((lo, hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The range asked for is the whole huge pages inside the allocation:
    /// aligned, within it, and missing less than a page at either end.
    #[test]
    fn the_range_is_the_whole_huge_pages_inside() {
        for start in [0x1000_0000, 0x1000_0000 + 4096, 0x1020_0000 - 64] {
            for bytes in [4 * HUGE - 1, 4 * HUGE, 5 * HUGE + 12_345, 100 * HUGE] {
                let got = huge_range(start, bytes);
                if bytes < 4 * HUGE {
                    assert_eq!(got, None);
                    continue;
                }
                let (lo, hi) = got.expect("a large range holds whole pages");
                let end = start + bytes;
                assert!(lo % HUGE == 0 && hi % HUGE == 0, "{lo:#x} {hi:#x}");
                assert!(start <= lo && lo < hi && hi <= end, "{lo:#x} {hi:#x}");
                assert!(lo - start < HUGE && end - hi < HUGE, "{lo:#x} {hi:#x}");
            }
        }
    }
}
