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
//! And whether an output fits before it is made: [`available_bytes`] (what the system
//! and the process's control group have left) and [`check_available`], which the
//! subdivision crates call with the size of their output before any work.
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

use std::path::{Path, PathBuf};

use crate::MeshError;

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

/// Outputs up to this many bytes are made without asking the system what it has
/// ([`check_available`]): reading its files costs more than making a small mesh, and
/// every machine this runs on has that much.
pub const ALWAYS_FITS_BYTES: u128 = 256 << 20;

/// Fails with [`MeshError::OutOfMemory`] when an output of `needed_bytes` (`what`) would
/// not fit in the memory the system has available now ([`available_bytes`]): the check
/// the subdivision functions make before any work, as a level too many would otherwise
/// run until the system kills the process (Linux overcommits, so no allocation fails).
/// Up to [`ALWAYS_FITS_BYTES`] nothing is read; where the memory cannot be read, nothing
/// is refused.
///
/// ```
/// use mesh_topo::MeshError;
/// use mesh_topo::memory::check_available;
///
/// assert!(check_available("mesh", 1 << 20).is_ok());
/// // A zettabyte: no machine has it.
/// match check_available("mesh", 1 << 70) {
///     Err(MeshError::OutOfMemory { needed_bytes, .. }) => assert_eq!(needed_bytes, 1 << 70),
///     other => assert!(other.is_ok() && mesh_topo::memory::available_bytes().is_none()),
/// }
/// ```
///
/// # Errors
/// [`MeshError::OutOfMemory`] with the bytes needed and available.
pub fn check_available(what: &'static str, needed_bytes: u128) -> Result<(), MeshError> {
    if needed_bytes <= ALWAYS_FITS_BYTES {
        return Ok(());
    }
    match available_bytes() {
        Some(available_bytes) if needed_bytes > u128::from(available_bytes) => {
            Err(MeshError::OutOfMemory { what, needed_bytes, available_bytes })
        }
        _ => Ok(()),
    }
}

/// Memory the system can give now, in bytes: `MemAvailable` plus `SwapFree` of `/proc/meminfo`
/// (Linux), or less if the process's control group has less left under its limit (a
/// container's memory limit); `None` where that cannot be read, and then nothing is
/// refused.
///
/// Reads a few small files: about as long as making a mesh of some thousand faces.
///
/// ```
/// if let Some(bytes) = mesh_topo::memory::available_bytes() {
///     println!("{bytes} bytes available now");
/// }
/// ```
pub fn available_bytes() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let system = meminfo_available(&info)?;
    let groups = std::fs::read_to_string("/proc/self/cgroup").unwrap_or_default();
    let headroom = control_group_files(&groups)
        .into_iter()
        .filter_map(|(limit, usage)| {
            let read = |path: &Path| std::fs::read_to_string(path).ok()?.trim().parse::<u64>().ok();
            // An unlimited group says `max` (v2) and fails the parse.
            Some(read(&limit)?.saturating_sub(read(&usage).unwrap_or(0)))
        })
        .min();
    Some(headroom.map_or(system, |headroom| headroom.min(system)))
}

/// `MemAvailable + SwapFree` in bytes, from the text of `/proc/meminfo`.
fn meminfo_available(info: &str) -> Option<u64> {
    let kilobytes = |key: &str| {
        info.lines()
            .find_map(|line| line.strip_prefix(key)?.strip_prefix(':'))
            .and_then(|rest| rest.trim().strip_suffix("kB")?.trim().parse::<u64>().ok())
    };
    let available = kilobytes("MemAvailable")?;
    Some(available.saturating_add(kilobytes("SwapFree").unwrap_or(0)).saturating_mul(1024))
}

/// The (limit, usage) files of the memory controller for the group that
/// `/proc/self/cgroup` (`groups`) names and for each of its ancestors (a limit may be set
/// on any of them): cgroup v2 (`0::/path`, `memory.max` and `memory.current`) and v1
/// (`n:memory:/path`, `memory.limit_in_bytes` and `memory.usage_in_bytes`).
fn control_group_files(groups: &str) -> Vec<(PathBuf, PathBuf)> {
    let mut files = Vec::new();
    for line in groups.lines() {
        let mut fields = line.splitn(3, ':');
        let (Some(_), Some(controllers), Some(path)) = (fields.next(), fields.next(), fields.next()) else {
            continue;
        };
        let (root, limit, usage) = if controllers.is_empty() {
            ("/sys/fs/cgroup", "memory.max", "memory.current")
        } else if controllers.split(',').any(|c| c == "memory") {
            ("/sys/fs/cgroup/memory", "memory.limit_in_bytes", "memory.usage_in_bytes")
        } else {
            continue;
        };
        let mut dir = Path::new(root).join(path.trim_start_matches('/'));
        loop {
            files.push((dir.join(limit), dir.join(usage)));
            if dir == Path::new(root) || !dir.pop() {
                break;
            }
        }
    }
    files
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

    #[test]
    fn the_memory_files_are_read_as_linux_writes_them() {
        let info = "MemTotal:       24000000 kB\nMemFree:        20000000 kB\nMemAvailable:   21000000 kB\n\
                    SwapTotal:       1000000 kB\nSwapFree:         500000 kB\n";
        assert_eq!(meminfo_available(info), Some((21_000_000 + 500_000) * 1024));
        assert_eq!(meminfo_available("MemAvailable:   1000 kB\n"), Some(1_024_000));
        assert_eq!(meminfo_available("MemFree: 1000 kB\n"), None);
        // v2 (the unified line) and v1 (the memory controller among others), each group
        // with its ancestors up to the mount; other controllers are passed over.
        let groups = "0::/user.slice/job\n4:cpu,memory:/box\n3:cpuset:/\n";
        let files: Vec<(String, String)> = control_group_files(groups)
            .into_iter()
            .map(|(limit, usage)| (limit.display().to_string(), usage.display().to_string()))
            .collect();
        let expected = [
            ("/sys/fs/cgroup/user.slice/job/memory.max", "/sys/fs/cgroup/user.slice/job/memory.current"),
            ("/sys/fs/cgroup/user.slice/memory.max", "/sys/fs/cgroup/user.slice/memory.current"),
            ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
            ("/sys/fs/cgroup/memory/box/memory.limit_in_bytes", "/sys/fs/cgroup/memory/box/memory.usage_in_bytes"),
            ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes"),
        ];
        assert_eq!(files, expected.map(|(l, u)| (l.to_owned(), u.to_owned())));
        assert!(control_group_files("garbage\n1:cpu:/x\n").is_empty());
    }

    #[test]
    fn this_system_reports_its_memory() {
        if cfg!(target_os = "linux") {
            assert!(available_bytes().is_some_and(|bytes| bytes > 0));
        }
    }
}
