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

/// `items` moved to a vector from [`with_capacity`]; left where they are if
/// they are too few to fill a huge page.
pub(super) fn moved<T: Copy>(items: Vec<T>) -> Vec<T> {
    if items.len() * size_of::<T>() < HUGE_PAGE {
        return items;
    }
    let mut v = with_capacity(items.len());
    v.extend_from_slice(&items);
    v
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moved_vectors_keep_their_items_large_and_small() {
        for len in [0, 1, 1000, 3 * HUGE_PAGE / 8 + 5] {
            let items: Vec<u64> = (0..len as u64).map(|i| i.wrapping_mul(0x9E37_79B9_7F4A_7C15)).collect();
            assert_eq!(moved(items.clone()), items);
        }
    }
}
