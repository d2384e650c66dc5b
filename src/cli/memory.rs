//! The check that a subdivision's output fits in memory before any work is done: a
//! level too many would otherwise run until the system kills the process (Linux
//! overcommits, so the allocation itself does not fail).

use std::path::{Path, PathBuf};

use multires::{ElementCounts, SurfaceScheme};

use super::{CliError, CliResult};

/// The face corners of an output of `counts`: the Loop family writes triangles (`3F`),
/// Doo-Sabin `2E` on a closed mesh.
fn corners(scheme: SurfaceScheme, counts: ElementCounts) -> u128 {
    if scheme.accepts_polygons() { 2 * counts.edges as u128 } else { 3 * counts.faces as u128 }
}

/// Bytes an output soup of `counts` holds: positions (three `f64`), one `u32` index per
/// corner and one offset per face. The least the output of `scheme` can take (making it
/// takes more).
fn soup_bytes(scheme: SurfaceScheme, counts: ElementCounts) -> u128 {
    24 * counts.vertices as u128 + 4 * corners(scheme, counts) + 4 * (counts.faces as u128 + 1)
}

/// Refuses `levels` steps of `scheme` on `input` (of `counts`) when the output alone
/// would need more memory than the system has available now (an output past the `u32`
/// index range is left to the library, which refuses it with its limit).
pub fn check_output_fits(input: &Path, scheme: SurfaceScheme, counts: ElementCounts, levels: u32) -> CliResult {
    match available_bytes() {
        Some(available) => output_fits(scheme, counts, levels, available)
            .map_err(|reason| CliError::Input(format!("{}: {reason}", input.display()))),
        None => Ok(()),
    }
}

/// [`check_output_fits`] against `available` bytes: the reason, naming the levels that
/// would fit, if the output does not.
fn output_fits(scheme: SurfaceScheme, counts: ElementCounts, levels: u32, available: u64) -> Result<(), String> {
    let fine = scheme.closed_counts(counts, levels);
    let needed = soup_bytes(scheme, fine);
    // Beyond the `u32` index range the library refuses at once, naming its own limit.
    let largest = u128::from(u32::MAX);
    let indexable = [fine.vertices as u128, corners(scheme, fine), fine.faces as u128].iter().all(|&n| n <= largest);
    if needed <= u128::from(available) || !indexable {
        return Ok(());
    }
    // The outputs grow with the level: the last level that fits is before the first that
    // does not (a few dozen levels at most reach the index range).
    let fits = |k: u32| soup_bytes(scheme, scheme.closed_counts(counts, k)) <= u128::from(available);
    let fitting = (0..levels).take_while(|&k| fits(k)).last();
    let advice = match fitting {
        Some(k) => format!("at most {k} level(s) fit"),
        None => "not even the input fits".into(),
    };
    // Exact for the Loop family; for Doo-Sabin the counts of a closed mesh, which bound
    // those of an open one under the default boundary rule.
    let bound = if scheme.accepts_polygons() { "up to " } else { "" };
    Err(format!(
        "{} x{levels} would make {bound}{} vertices and {} faces, {} for the output alone; the system has {} \
         available ({advice})",
        scheme.name(),
        fine.vertices,
        fine.faces,
        gigabytes(needed),
        gigabytes(u128::from(available))
    ))
}

fn gigabytes(bytes: u128) -> String {
    format!("{:.1} GB", bytes as f64 / 1e9)
}

/// Memory the system can give now: `MemAvailable` plus `SwapFree` of `/proc/meminfo`
/// (Linux), or less if the process's control group has less left under its limit (a
/// container's memory limit); `None` where that cannot be read, and then nothing is
/// refused.
fn available_bytes() -> Option<u64> {
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
        let reason = output_fits(SurfaceScheme::Loop, BUNNY, 9, available).unwrap_err();
        assert!(
            reason.starts_with("loop x9 would make 481558530 vertices and 963117056 faces, 27.0 GB for"),
            "{reason}"
        );
        assert!(reason.ends_with("the system has 16.0 GB available (at most 8 level(s) fit)"), "{reason}");
        let reason = output_fits(SurfaceScheme::DooSabin, BUNNY, 9, available).unwrap_err();
        assert!(reason.starts_with("doo-sabin x9 would make up to 722337792 vertices"), "{reason}");
        assert!(reason.ends_with("(at most 8 level(s) fit)"), "{reason}");
        let reason = output_fits(SurfaceScheme::QuaternaryLoop, BUNNY, 3, 100_000).unwrap_err();
        assert!(reason.ends_with("(not even the input fits)"), "{reason}");
        // Past the index range (and saturated counts): left to the library's limits.
        assert!(output_fits(SurfaceScheme::Loop, BUNNY, 11, available).is_ok());
        assert!(output_fits(SurfaceScheme::Loop, BUNNY, 200, 1).is_ok());
        // A mesh that does not grow (no faces), asked for every level there is: its counts
        // stop changing, so the answer comes at once (the steps were all counted before).
        let points = ElementCounts { vertices: 1_000_000, edges: 0, faces: 0 };
        assert!(output_fits(SurfaceScheme::Loop, points, u32::MAX, 100_000_000).is_ok());
        let reason = output_fits(SurfaceScheme::Loop, points, u32::MAX, 1_000).unwrap_err();
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
    fn every_scheme_of_the_command_line_is_the_library_scheme_of_its_name() {
        use clap::ValueEnum;
        for scheme in super::super::SurfaceScheme::value_variants() {
            assert_eq!(scheme.word(), scheme.library().name());
        }
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
