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
    {
        const HUGE: usize = 2 << 20;
        let bytes = v.capacity() * std::mem::size_of::<T>();
        if bytes < 4 * HUGE {
            return; // too small to hold a few whole huge pages
        }
        let start = v.as_ptr() as usize;
        let (lo, hi) = (start.next_multiple_of(HUGE), (start + bytes) / HUGE * HUGE);
        if hi > lo {
            // SAFETY: `[lo, hi)` lies inside `v`'s own live allocation (its
            // capacity), and `MADV_HUGEPAGE` changes no contents, mapping or
            // protection: it only lets the kernel back the range with huge
            // pages. No Rust reference or invariant depends on how pages are
            // backed, so this cannot cause undefined behaviour; an error
            // (e.g. a kernel without THP) leaves everything as it was.
            unsafe {
                libc::madvise(lo as *mut libc::c_void, hi - lo, libc::MADV_HUGEPAGE);
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = v; // elsewhere: ordinary pages
}
