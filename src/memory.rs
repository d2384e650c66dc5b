//! Whether a subdivision's output fits in memory, checked before any work: a level too
//! many would otherwise run until the system kills the process (Linux overcommits, so
//! the allocation itself does not fail, and the pages are only claimed as the output is
//! written).
//!
//! [`SurfaceScheme::subdivide`] makes this check itself; [`available_bytes`] and
//! [`SurfaceScheme::check_output_fits`] let a caller make it for any budget (say, a
//! share of the memory, or a fixed limit in a service).
//!
//! ```
//! use multires::prelude::*;
//! use multires::{ElementCounts, memory};
//!
//! let bunny = ElementCounts { vertices: 1839, edges: 5511, faces: 3674 };
//! // Eight Loop levels make 240 779 264 triangles: 6.7 GB of soup.
//! let needed = SurfaceScheme::Loop.output_bytes(SurfaceScheme::Loop.closed_counts(bunny, 8));
//! assert_eq!(needed / 100_000_000, 67);
//! let refused = SurfaceScheme::Loop.check_output_fits(bunny, 8, 4_000_000_000).unwrap_err();
//! assert!(refused.to_string().ends_with("6.7 GB for the output alone, 4.0 GB available (at most 7 level(s) fit)"));
//! if let Some(bytes) = memory::available_bytes() {
//!     println!("{bytes} bytes available now");
//! }
//! ```

use std::fmt;
use std::path::{Path, PathBuf};

use crate::{ElementCounts, SurfaceScheme};

/// Outputs up to this size are made without asking the system what it has (reading its
/// files costs more than making a small mesh): every machine this runs on has it.
pub(crate) const ALWAYS_FITS_BYTES: u128 = 256 << 20;

/// A subdivision whose output alone needs more memory than is available (see
/// [`SurfaceScheme::check_output_fits`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OutputTooLarge {
    /// The scheme.
    pub scheme: SurfaceScheme,
    /// The levels asked for.
    pub levels: u32,
    /// The counts of the output ([`SurfaceScheme::closed_counts`]: exact for the Loop
    /// family, an upper bound for Doo-Sabin on an open mesh).
    pub counts: ElementCounts,
    /// The bytes of the output soup ([`SurfaceScheme::output_bytes`]).
    pub needed_bytes: u128,
    /// The bytes available (the system's, for [`SurfaceScheme::subdivide`], or the
    /// caller's budget).
    pub available_bytes: u64,
    /// The most levels whose output fits (`None`: not even the input's size does).
    pub fitting_levels: Option<u32>,
}

impl fmt::Display for OutputTooLarge {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Exact for the Loop family; for Doo-Sabin the counts of a closed mesh, which bound
        // those of an open one under the default boundary rule.
        let bound = if self.scheme.accepts_polygons() { "up to " } else { "" };
        write!(
            f,
            "{} x{} would make {bound}{} vertices and {} faces, {} for the output alone, {} available (",
            self.scheme,
            self.levels,
            self.counts.vertices,
            self.counts.faces,
            gigabytes(self.needed_bytes),
            gigabytes(u128::from(self.available_bytes))
        )?;
        match self.fitting_levels {
            Some(k) => write!(f, "at most {k} level(s) fit)"),
            None => f.write_str("not even the input fits)"),
        }
    }
}

impl std::error::Error for OutputTooLarge {}

fn gigabytes(bytes: u128) -> String {
    format!("{:.1} GB", bytes as f64 / 1e9)
}

/// The face corners of an output of `counts`: the Loop family writes triangles (`3F`),
/// Doo-Sabin `2E` on a closed mesh.
fn corners(scheme: SurfaceScheme, counts: ElementCounts) -> u128 {
    if scheme.accepts_polygons() { 2 * counts.edges as u128 } else { 3 * counts.faces as u128 }
}

/// Bytes an output soup of `counts` holds: positions (three `f64`), one `u32` index per
/// corner and one offset per face.
pub(crate) fn soup_bytes(scheme: SurfaceScheme, counts: ElementCounts) -> u128 {
    24 * counts.vertices as u128 + 4 * corners(scheme, counts) + 4 * (counts.faces as u128 + 1)
}

/// [`SurfaceScheme::check_output_fits`].
pub(crate) fn output_fits(
    scheme: SurfaceScheme,
    input: ElementCounts,
    levels: u32,
    available: u64,
) -> Result<(), OutputTooLarge> {
    let fine = scheme.closed_counts(input, levels);
    let needed = soup_bytes(scheme, fine);
    // Beyond the `u32` index range the member crates refuse at once, naming their limit.
    let largest = u128::from(u32::MAX);
    let indexable = [fine.vertices as u128, corners(scheme, fine), fine.faces as u128].iter().all(|&n| n <= largest);
    if needed <= u128::from(available) || !indexable {
        return Ok(());
    }
    // The outputs grow with the level: the last level that fits is before the first that
    // does not (a few dozen levels at most reach the index range).
    let fits = |k: u32| soup_bytes(scheme, scheme.closed_counts(input, k)) <= u128::from(available);
    let fitting_levels = (0..levels).take_while(|&k| fits(k)).last();
    Err(OutputTooLarge {
        scheme,
        levels,
        counts: fine,
        needed_bytes: needed,
        available_bytes: available,
        fitting_levels,
    })
}

/// Memory the system can give now, in bytes: `MemAvailable` plus `SwapFree` of `/proc/meminfo`
/// (Linux), or less if the process's control group has less left under its limit (a
/// container's memory limit); `None` where that cannot be read, and then nothing is
/// refused.
///
/// Reads a few small files: about as long as making a mesh of some thousand faces.
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

    /// The bunny of `tests/data` (1839 vertices, 5511 edges, 3674 triangles).
    const BUNNY: ElementCounts = ElementCounts { vertices: 1839, edges: 5511, faces: 3674 };

    #[test]
    fn an_output_larger_than_the_memory_is_refused_with_the_levels_that_fit() {
        let available = 16_000_000_000;
        // Loop level 8: 240.8M faces, 6.7 GB; level 9: 963.1M faces, 27.0 GB.
        assert!(output_fits(SurfaceScheme::Loop, BUNNY, 8, available).is_ok());
        let refused = output_fits(SurfaceScheme::Loop, BUNNY, 9, available).unwrap_err();
        assert_eq!(refused.fitting_levels, Some(8));
        assert_eq!(refused.counts, SurfaceScheme::Loop.closed_counts(BUNNY, 9));
        assert_eq!((refused.needed_bytes, refused.available_bytes), (26_967_277_620, available));
        let reason = refused.to_string();
        assert!(
            reason.starts_with("loop x9 would make 481558530 vertices and 963117056 faces, 27.0 GB for"),
            "{reason}"
        );
        assert!(
            reason.ends_with("27.0 GB for the output alone, 16.0 GB available (at most 8 level(s) fit)"),
            "{reason}"
        );
        let reason = output_fits(SurfaceScheme::DooSabin, BUNNY, 9, available).unwrap_err().to_string();
        assert!(reason.starts_with("doo-sabin x9 would make up to 722337792 vertices"), "{reason}");
        assert!(reason.ends_with("(at most 8 level(s) fit)"), "{reason}");
        let reason = output_fits(SurfaceScheme::QuaternaryLoop, BUNNY, 3, 100_000).unwrap_err().to_string();
        assert!(reason.ends_with("(not even the input fits)"), "{reason}");
        // Past the index range (and saturated counts): left to the library's limits.
        assert!(output_fits(SurfaceScheme::Loop, BUNNY, 11, available).is_ok());
        assert!(output_fits(SurfaceScheme::Loop, BUNNY, 200, 1).is_ok());
        // A mesh that does not grow (no faces), asked for every level there is: its counts
        // stop changing, so the answer comes at once (the steps were all counted before).
        let points = ElementCounts { vertices: 1_000_000, edges: 0, faces: 0 };
        assert!(output_fits(SurfaceScheme::Loop, points, u32::MAX, 100_000_000).is_ok());
        let reason = output_fits(SurfaceScheme::Loop, points, u32::MAX, 1_000).unwrap_err().to_string();
        assert!(reason.ends_with("(not even the input fits)"), "{reason}");
    }

    #[test]
    fn the_soup_bytes_are_those_of_the_arrays() {
        // An octahedron: 6 positions, 24 corners, 8 faces and their end offset.
        let octahedron = ElementCounts { vertices: 6, edges: 12, faces: 8 };
        for scheme in [SurfaceScheme::Loop, SurfaceScheme::DooSabin] {
            assert_eq!(soup_bytes(scheme, octahedron), 6 * 24 + 24 * 4 + 9 * 4);
        }
        // An open triangle grid (2 x 1 cells: 6 vertices, 9 edges, 4 triangles): Loop
        // writes its 12 corners, not twice its edges.
        let grid = ElementCounts { vertices: 6, edges: 9, faces: 4 };
        assert_eq!(soup_bytes(SurfaceScheme::Loop, grid), 6 * 24 + 12 * 4 + 5 * 4);
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
