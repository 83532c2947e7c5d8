//! The tree's arrays on transparent huge pages, where the system has them.
//!
//! Incoherent rays read nodes and leaves all over a large tree (56 MiB for
//! the 1 M-triangle terrain): with 4 KiB pages most of those reads also
//! miss the CPU's address-translation cache (a few thousand entries, a
//! few to a dozen MB of 4 KiB pages) and wait for a page-table walk; a
//! 2 MiB page covers 512 times as much. Linux gives a process huge pages
//! for memory it marks with `madvise(MADV_HUGEPAGE)` before first touching
//! it (under the default `madvise` setting of
//! `/sys/kernel/mm/transparent_hugepage/enabled`), as Embree does for its
//! BVH (`os_advise` in its `common/sys/alloc.cpp`). It is a hint: where
//! the kernel has no free huge pages, or on other systems, the memory is
//! ordinary and nothing else changes (`docs/performance.md` has the
//! timings).

/// Bytes per huge page (x86-64 and most 64-bit Arm Linux systems).
const HUGE_PAGE: usize = 2 << 20;

/// An empty vector with room for `len` items whose memory is marked for
/// huge pages, where it spans at least one whole huge page. Fill it before
/// anything else touches the memory: pages already in use stay small.
pub(super) fn with_capacity<T>(len: usize) -> Vec<T> {
    let mut v = Vec::with_capacity(len);
    #[cfg(target_os = "linux")]
    {
        let start = v.as_mut_ptr() as usize;
        let end = start + len * size_of::<T>();
        let (first, last) = (start.next_multiple_of(HUGE_PAGE), end / HUGE_PAGE * HUGE_PAGE);
        if last > first {
            // SAFETY: [first, last) lies inside the allocation `v` owns, and
            // the advice only asks for larger pages: it never changes the
            // memory's contents or who may use it. A failure (say, a kernel
            // without transparent huge pages) leaves ordinary pages, so the
            // result is ignored.
            unsafe { libc::madvise(first as *mut libc::c_void, last - first, libc::MADV_HUGEPAGE) };
        }
    }
    v
}
