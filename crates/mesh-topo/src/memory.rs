//! Hints for large arrays of fresh memory: transparent huge pages, and mapping pages up
//! front, on Linux (on other systems the hints do nothing).
//!
//! An array of many megabytes written right after it is allocated is memory nothing has
//! touched yet: with 4 KiB pages the kernel takes one page fault per page on first
//! touch, which can cost as much as the pass that writes the array.
//! [`advise_huge_pages`] asks Linux to back the array with transparent huge pages (2 MiB
//! on x86-64: one fault per huge page, fewer TLB misses, a cheaper release), and
//! [`map_pages`] maps the pages of a range in one system call instead of a fault per
//! page; [`filled_vec`] and [`advised_vec`] allocate vectors with the first hint. The hints change
//! how the kernel backs the pages, never what they hold, so calling them on any range of
//! memory is sound; errors (an older kernel, THP turned off) are ignored.
//!
//! ```
//! use mesh_topo::memory::filled_vec;
//!
//! // Eight megabytes of `u32::MAX`, on huge pages where the system offers them.
//! let labels = filled_vec(1 << 21, u32::MAX);
//! assert_eq!(labels.len(), 1 << 21);
//! assert!(labels.iter().all(|&x| x == u32::MAX));
//! ```

#![allow(unsafe_code)]

/// A vector of `len` copies of `value`; from one huge page of bytes on, its memory is
/// advised to be backed by transparent huge pages ([`advise_huge_pages`]) before it is
/// filled. For arrays that are allocated, filled and then written again at random, such
/// as the scratch arrays of a mesh pass.
pub fn filled_vec<T: Clone>(len: usize, value: T) -> Vec<T> {
    if len.saturating_mul(size_of::<T>()) < huge_page_size() {
        return vec![value; len];
    }
    let mut vec = advised_vec(len);
    vec.resize(len, value);
    vec
}

/// An empty vector with room for `capacity` elements, that room advised to be backed by
/// transparent huge pages ([`advise_huge_pages`]) from one huge page of bytes on: for
/// a large array about to be filled by pushes.
pub fn advised_vec<T>(capacity: usize) -> Vec<T> {
    let vec: Vec<T> = Vec::with_capacity(capacity);
    advise_huge_pages(vec.as_ptr().cast(), capacity.saturating_mul(size_of::<T>()));
    vec
}

/// Asks the kernel to back the whole huge pages inside the `bytes` bytes at `start` with
/// transparent huge pages, before anything touches them (nothing if the range holds no
/// whole huge page). Works when the system's THP mode is `always` or `madvise`.
pub fn advise_huge_pages(start: *const u8, bytes: usize) {
    let huge = huge_page_size();
    if bytes >= huge {
        #[cfg(target_os = "linux")]
        advise_whole_pages(start, bytes, huge, libc::MADV_HUGEPAGE);
    }
    #[cfg(not(target_os = "linux"))]
    let _ = start;
}

/// Maps every whole page inside the `bytes` bytes at `start` in one system call
/// (`MADV_POPULATE_WRITE`, Linux 5.14 and later), instead of one page fault per page as
/// the writes first touch them. The kernel still clears each new page, but without a
/// trap per page; a page already mapped keeps its contents.
pub fn map_pages(start: *const u8, bytes: usize) {
    #[cfg(target_os = "linux")]
    advise_whole_pages(start, bytes, base_page_size(), libc::MADV_POPULATE_WRITE);
    #[cfg(not(target_os = "linux"))]
    let _ = (start, bytes);
}

/// `madvise(advice)` on the whole pages of `page` bytes (a power of two, a multiple of
/// the base page) inside the `bytes` bytes at `start`. Only for the two advices above,
/// which never change what memory holds; errors are ignored.
#[cfg(target_os = "linux")]
fn advise_whole_pages(start: *const u8, bytes: usize, page: usize, advice: libc::c_int) {
    debug_assert!(advice == libc::MADV_HUGEPAGE || advice == libc::MADV_POPULATE_WRITE);
    let begin = (start as usize).next_multiple_of(page);
    let end = (start as usize).saturating_add(bytes) / page * page;
    if end > begin {
        // SAFETY: `[begin, end)` is page-aligned at both ends. MADV_HUGEPAGE only sets how
        // the kernel backs these pages (the VMA flag for huge pages). MADV_POPULATE_WRITE
        // faults the pages in as a write would, without writing: a page already mapped
        // keeps its contents, a new one is a zero-filled anonymous page of memory that
        // holds no value yet. Neither moves, frees, reads or writes memory, so no Rust
        // object can observe them; on a range that is not mapped the call fails, which
        // is ignored.
        unsafe { libc::madvise(begin as *mut libc::c_void, end - begin, advice) };
    }
}

/// The base page size of the system (4 KiB unless it says otherwise).
pub fn base_page_size() -> usize {
    #[cfg(target_os = "linux")]
    {
        static SIZE: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
        *SIZE.get_or_init(|| {
            // SAFETY: `sysconf` reads a constant of the system and has no other effect.
            let size = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
            usize::try_from(size).ok().filter(|size| size.is_power_of_two()).unwrap_or(4096)
        })
    }
    #[cfg(not(target_os = "linux"))]
    4096
}

/// The transparent huge page size (2 MiB on x86-64; read once from sysfs on Linux).
pub fn huge_page_size() -> usize {
    #[cfg(target_os = "linux")]
    {
        static SIZE: std::sync::OnceLock<usize> = std::sync::OnceLock::new();
        *SIZE.get_or_init(|| {
            std::fs::read_to_string("/sys/kernel/mm/transparent_hugepage/hpage_pmd_size")
                .ok()
                .and_then(|s| s.trim().parse().ok())
                .filter(|&size: &usize| size.is_power_of_two() && size >= 4096)
                .unwrap_or(2 << 20)
        })
    }
    #[cfg(not(target_os = "linux"))]
    {
        2 << 20
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hints never change memory: written values stay, on every page of a buffer and
    /// at its unaligned ends, and a filled vector holds its value everywhere.
    #[test]
    fn hints_keep_what_memory_holds() {
        let words = (3 * huge_page_size() + 4096) / 8 + 3;
        let values: Vec<u64> = (0..words as u64).map(|i| i.wrapping_mul(0x9e37_79b9)).collect();
        let bytes = values.len() * 8;
        advise_huge_pages(values.as_ptr().cast(), bytes);
        map_pages(values.as_ptr().cast(), bytes);
        assert!(values.iter().enumerate().all(|(i, &x)| x == (i as u64).wrapping_mul(0x9e37_79b9)));
        // Ranges that hold no whole page, and one that ends past the address space.
        advise_huge_pages(values.as_ptr().cast(), 100);
        map_pages(values.as_ptr().wrapping_add(1).cast(), 8);
        map_pages(values.as_ptr().cast(), usize::MAX);
        for len in [0, 1, 1000, words] {
            let filled = filled_vec(len, 7u64);
            assert_eq!(filled.len(), len);
            assert!(filled.iter().all(|&x| x == 7));
            let mut pushed = advised_vec::<u64>(len);
            assert!(pushed.is_empty() && pushed.capacity() >= len);
            pushed.extend(0..len as u64);
            assert!(pushed.iter().copied().eq(0..len as u64));
        }
        assert!(base_page_size().is_power_of_two() && huge_page_size() >= base_page_size());
    }
}
