//! Whether a subdivision's output fits in memory, checked before any work: a level too
//! many would otherwise run until the system kills the process (Linux overcommits, so
//! the allocation itself does not fail, and the pages are only claimed as the output is
//! written).
//!
//! [`SurfaceScheme::subdivide`] makes this check itself, naming the levels that fit
//! ([`OutputTooLarge`]); the member crates' own subdivision functions check too, with
//! [`mesh_topo::memory::check_available`] (a `MeshError::OutOfMemory`).
//! [`available_bytes`] and [`SurfaceScheme::check_output_fits`] let a caller make the
//! check for any budget (say, a share of the memory, or a fixed limit in a service).
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

pub use mesh_topo::memory::available_bytes;

use mesh_topo::PolygonSoup;

use crate::{ElementCounts, SurfaceScheme};

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

/// Bytes an output soup of `counts` holds ([`PolygonSoup::array_bytes_for`]).
pub(crate) fn soup_bytes(scheme: SurfaceScheme, counts: ElementCounts) -> u128 {
    PolygonSoup::array_bytes_for(counts.vertices as u128, corners(scheme, counts), counts.faces as u128)
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
}
