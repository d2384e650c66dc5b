//! Multiresolution in one type: a base mesh plus per-level details, from reverse Loop or
//! reverse Doo-Sabin, with one file format (the member crates' versioned encodings,
//! told apart by their magic numbers).

use mesh_topo::{HalfedgeMesh, PolygonSoup};
use serde::{Deserialize, Serialize};
use subdiv_doo::DooPyramid;
use subdiv_loop::pyramid::LoopPyramid;

use crate::{Boundaries, Error, SurfaceScheme};

/// How many levels [`decompose`] reverses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Depth {
    /// Exactly this many (an error if the connectivity allows fewer).
    Levels(u32),
    /// As many as the connectivity allows (at least one).
    Max,
}

/// A multiresolution pyramid of either family.
///
/// ```
/// use multires::prelude::*;
///
/// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
/// let fine = HalfedgeMesh::from_soup(&SurfaceScheme::LoopWarren.subdivide(&octahedron, 2)?)?;
/// let pyramid = decompose(&fine, SurfaceScheme::LoopWarren, Depth::Max)?;
/// assert!(matches!(pyramid, Pyramid::Loop(_)));
/// assert_eq!(pyramid.scheme(), SurfaceScheme::LoopWarren);
/// assert_eq!((pyramid.level_count(), pyramid.base().face_count()), (2, 8));
/// // The base mesh plus the details: as many vectors as the fine mesh has vertices.
/// assert_eq!(pyramid.base().vertex_count() + pyramid.detail_count(), fine.vertex_count());
/// # Ok::<(), multires::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub enum Pyramid {
    /// From reverse Loop.
    Loop(LoopPyramid),
    /// From reverse Doo-Sabin.
    Doo(DooPyramid),
}

/// One row of [`Pyramid::rate_distortion`]: errors relative to the bounding-box
/// diagonal of the exact finest mesh.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RateDistortion {
    /// Fraction of the detail vectors kept (the largest ones).
    pub fraction: f64,
    /// Number of detail vectors kept.
    pub kept: usize,
    /// Largest vertex distance to the exact finest mesh / bounding-box diagonal.
    pub max_error: f64,
    /// Root-mean-square vertex distance / bounding-box diagonal.
    pub rms_error: f64,
}

impl From<subdiv_loop::pyramid::RateDistortion> for RateDistortion {
    fn from(row: subdiv_loop::pyramid::RateDistortion) -> Self {
        // (The total number of details is the pyramid's `detail_count`.)
        let subdiv_loop::pyramid::RateDistortion { fraction, kept, total: _, max_error, rms_error } = row;
        Self { fraction, kept, max_error, rms_error }
    }
}

impl From<subdiv_doo::pyramid::RateDistortion> for RateDistortion {
    fn from(row: subdiv_doo::pyramid::RateDistortion) -> Self {
        let subdiv_doo::pyramid::RateDistortion { fraction, kept, max_error, rms_error } = row;
        Self { fraction, kept, max_error, rms_error }
    }
}

/// Decomposes `mesh` into a base mesh and details by repeated reverse subdivision of
/// `scheme`.
///
/// ```
/// use multires::prelude::*;
///
/// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
/// let fine = HalfedgeMesh::from_soup(&SurfaceScheme::Loop.subdivide(&octahedron, 2)?)?;
/// let pyramid = decompose(&fine, SurfaceScheme::Loop, Depth::Max)?;
/// assert_eq!(pyramid.level_count(), 2);
/// assert_eq!(pyramid.base().face_count(), 8);
/// let rebuilt = pyramid.reconstruct(2)?;
/// let worst = rebuilt.positions.iter().zip(fine.positions()).map(|(p, q)| p.distance(*q)).fold(0.0, f64::max);
/// assert!(worst < 1e-12);
/// # Ok::<(), multires::Error>(())
/// ```
///
/// # Errors
/// [`Error::NotReversible`] for the M-band Loop schemes; otherwise the member crate's
/// error, e.g. when the mesh does not have the scheme's subdivision connectivity (it
/// names where the structure breaks).
pub fn decompose(mesh: &HalfedgeMesh, scheme: SurfaceScheme, depth: Depth) -> Result<Pyramid, Error> {
    decompose_with(mesh, scheme, depth, &Boundaries::default())
}

/// [`decompose`] inverting the boundary rules of `boundaries` (those that made the mesh:
/// a mesh made with other rules has non-zero details, or no reading at all).
///
/// ```
/// use multires::prelude::*;
///
/// // Two Doo-Sabin steps with the Chaikin boundary rule on an open grid, reversed.
/// let grid = HalfedgeMesh::from_soup(&shapes::grid(3, 3, shapes::CellKind::Quads)?)?;
/// let boundaries = Boundaries::chaikin();
/// let fine = HalfedgeMesh::from_soup(&SurfaceScheme::DooSabin.subdivide_with(&grid, 2, &boundaries)?)?;
/// let pyramid = decompose_with(&fine, SurfaceScheme::DooSabin, Depth::Levels(2), &boundaries)?;
/// assert_eq!(pyramid.base().face_count(), 9);
/// let rebuilt = pyramid.reconstruct(2)?;
/// let worst = rebuilt.positions.iter().zip(fine.positions()).map(|(p, q)| p.distance(*q)).fold(0.0, f64::max);
/// assert!(worst < 1e-12);
/// # Ok::<(), multires::Error>(())
/// ```
///
/// # Errors
/// As [`decompose`], and [`Error::NotApplicable`] for a boundary option of another family.
pub fn decompose_with(
    mesh: &HalfedgeMesh,
    scheme: SurfaceScheme,
    depth: Depth,
    boundaries: &Boundaries,
) -> Result<Pyramid, Error> {
    boundaries.check(scheme)?;
    if let Some(options) = loop_options(scheme, depth, boundaries) {
        return Ok(Pyramid::Loop(subdiv_loop::pyramid::decompose(mesh, &options)?));
    }
    if let Some(options) = doo_options(scheme, depth, boundaries) {
        return Ok(Pyramid::Doo(subdiv_doo::decompose(mesh, &options)?.pyramid));
    }
    Err(Error::NotReversible { scheme })
}

/// [`decompose_with`] of a polygon soup, as a mesh file holds it. A Loop-family soup in
/// the canonical order (what Loop subdivision and reconstruction write) is reversed
/// straight from its face list, without building its half-edge mesh
/// (`subdiv_loop::pyramid::decompose_soup`), and so is the first level of a Doo-Sabin
/// soup in its canonical order under the shrinking boundary rule
/// (`subdiv_doo::decompose_soup`); any other soup is built into a half-edge mesh first.
/// The result, or the error, is that of `decompose_with(&HalfedgeMesh::from_soup(soup)?, ...)`.
///
/// ```
/// use multires::prelude::*;
///
/// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
/// let fine = SurfaceScheme::Loop.subdivide(&octahedron, 3)?; // a soup
/// let pyramid = decompose_soup(&fine, SurfaceScheme::Loop, Depth::Max, &Boundaries::default())?;
/// assert_eq!((pyramid.level_count(), pyramid.base().face_count()), (3, 8));
/// # Ok::<(), multires::Error>(())
/// ```
///
/// # Errors
/// As [`decompose_with`], and the soup's own errors as a mesh ([`Error::Mesh`]).
pub fn decompose_soup(
    soup: &PolygonSoup,
    scheme: SurfaceScheme,
    depth: Depth,
    boundaries: &Boundaries,
) -> Result<Pyramid, Error> {
    // A boundary option of another family goes the mesh's way too, so that the soup's
    // errors come first, as they do there.
    if boundaries.check(scheme).is_ok()
        && let Some(options) = loop_options(scheme, depth, boundaries)
    {
        return match subdiv_loop::pyramid::decompose_soup(soup, &options) {
            Ok(pyramid) => Ok(Pyramid::Loop(pyramid)),
            // From a soup, only building its mesh fails this way (a mesh built from a soup
            // has finite positions): reported as the `?` below reports it.
            Err(subdiv_loop::LoopError::Mesh(error)) => Err(Error::Mesh(error)),
            Err(error) => Err(error.into()),
        };
    }
    if boundaries.check(scheme).is_ok()
        && let Some(options) = doo_options(scheme, depth, boundaries)
    {
        return match subdiv_doo::decompose_soup(soup, &options) {
            Ok(decomposition) => Ok(Pyramid::Doo(decomposition.pyramid)),
            Err(subdiv_doo::DooError::Mesh(error)) => Err(Error::Mesh(error)),
            Err(error) => Err(error.into()),
        };
    }
    decompose_with(&HalfedgeMesh::from_soup(soup)?, scheme, depth, boundaries)
}

/// The Doo-Sabin decomposition options of a Doo-Sabin scheme, `None` otherwise.
fn doo_options(scheme: SurfaceScheme, depth: Depth, boundaries: &Boundaries) -> Option<subdiv_doo::DecomposeOptions> {
    let rule = scheme.doo_rule()?;
    let options = match depth {
        Depth::Levels(n) => subdiv_doo::DecomposeOptions::levels(rule, n),
        Depth::Max => subdiv_doo::DecomposeOptions::max(rule),
    };
    Some(options.with_boundary(boundaries.doo))
}

/// The Loop decomposition options of a reversible Loop-family scheme, `None` otherwise.
fn loop_options(
    scheme: SurfaceScheme,
    depth: Depth,
    boundaries: &Boundaries,
) -> Option<subdiv_loop::pyramid::DecomposeOptions> {
    let rules = scheme.loop_options_with(boundaries)?;
    let levels = match depth {
        Depth::Levels(n) => subdiv_loop::pyramid::Levels::Count(n as usize),
        Depth::Max => subdiv_loop::pyramid::Levels::Max,
    };
    Some(subdiv_loop::pyramid::DecomposeOptions { rules, levels, seed_vertices: Vec::new() })
}

impl Pyramid {
    /// The scheme whose reverse made the pyramid.
    pub fn scheme(&self) -> SurfaceScheme {
        match self {
            Pyramid::Loop(p) => match p.rules.weights {
                subdiv_loop::forward::VertexWeights::Loop => SurfaceScheme::Loop,
                subdiv_loop::forward::VertexWeights::Warren => SurfaceScheme::LoopWarren,
            },
            Pyramid::Doo(p) => match p.rule {
                subdiv_doo::FaceRule::DooSabin => SurfaceScheme::DooSabin,
                subdiv_doo::FaceRule::Simple => SurfaceScheme::DooSimple,
                _ => SurfaceScheme::DooCentroid,
            },
        }
    }

    /// Number of refinement levels above the base mesh.
    pub fn level_count(&self) -> usize {
        match self {
            Pyramid::Loop(p) => p.level_count(),
            Pyramid::Doo(p) => p.level_count(),
        }
    }

    /// Total number of detail vectors.
    pub fn detail_count(&self) -> usize {
        match self {
            Pyramid::Loop(p) => p.detail_count(),
            Pyramid::Doo(p) => p.detail_count(),
        }
    }

    /// The coarsest mesh.
    pub fn base(&self) -> &PolygonSoup {
        match self {
            Pyramid::Loop(p) => &p.base,
            Pyramid::Doo(p) => &p.base,
        }
    }

    /// Rebuilds level `level` (0 = the base mesh) with every detail: exact.
    ///
    /// ```
    /// use multires::prelude::*;
    ///
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let fine = SurfaceScheme::Loop.subdivide(&octahedron, 2)?;
    /// let pyramid = decompose_soup(&fine, SurfaceScheme::Loop, Depth::Max, &Boundaries::default())?;
    /// assert_eq!(pyramid.reconstruct(0)?, *pyramid.base());
    /// // All details are zero (a Loop surface): level 1 is one Loop step of the base.
    /// let (level1, once) = (pyramid.reconstruct(1)?, SurfaceScheme::Loop.subdivide(&octahedron, 1)?);
    /// assert_eq!((level1.face_count(), &level1.indices), (8 * 4, &once.indices));
    /// assert!(level1.positions.iter().zip(&once.positions).all(|(p, q)| p.distance(*q) < 1e-12));
    /// assert!(pyramid.reconstruct(3).is_err()); // two levels only
    /// # Ok::<(), multires::Error>(())
    /// ```
    ///
    /// # Errors
    /// The member crate's error if `level` is beyond [`level_count`](Self::level_count) or
    /// the pyramid is inconsistent (e.g. read from a damaged file).
    pub fn reconstruct(&self, level: usize) -> Result<PolygonSoup, Error> {
        Ok(match self {
            Pyramid::Loop(p) => p.reconstruct(level)?,
            Pyramid::Doo(p) => p.reconstruct(level, None)?,
        })
    }

    /// Rebuilds level `level` keeping only the largest `fraction` of the details: the
    /// compression use.
    ///
    /// ```
    /// use multires::prelude::*;
    ///
    /// // A Doo-Sabin surface with one vertex moved: non-zero details.
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let mut fine = HalfedgeMesh::from_soup(&SurfaceScheme::DooSabin.subdivide(&cube, 2)?)?;
    /// fine.positions_mut()[10].x += 0.2;
    /// let pyramid = decompose(&fine, SurfaceScheme::DooSabin, Depth::Levels(2))?;
    /// // Keeping every detail is the exact reconstruction; keeping none loses the bump.
    /// assert_eq!(pyramid.reconstruct_keeping(2, 1.0)?, pyramid.reconstruct(2)?);
    /// let smooth = pyramid.reconstruct_keeping(2, 0.0)?;
    /// assert!(smooth.positions[10].distance(fine.positions()[10]) > 0.01);
    /// assert_eq!(smooth.indices, fine.to_soup().indices);
    /// assert!(pyramid.reconstruct_keeping(2, 1.5).is_err());
    /// # Ok::<(), multires::Error>(())
    /// ```
    ///
    /// # Errors
    /// As [`reconstruct`](Self::reconstruct), and when `fraction` is not in `[0, 1]`.
    pub fn reconstruct_keeping(&self, level: usize, fraction: f64) -> Result<PolygonSoup, Error> {
        Ok(match self {
            Pyramid::Loop(p) => p.compressed(fraction)?.reconstruct(level)?,
            Pyramid::Doo(p) => p.reconstruct(level, Some(fraction))?,
        })
    }

    /// Errors of [`reconstruct_keeping`](Self::reconstruct_keeping) at the finest level
    /// for each fraction.
    ///
    /// ```
    /// use multires::prelude::*;
    ///
    /// // A Loop surface with one vertex moved: non-zero details.
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let mut fine = HalfedgeMesh::from_soup(&SurfaceScheme::Loop.subdivide(&octahedron, 2)?)?;
    /// fine.positions_mut()[20].z += 0.3;
    /// let pyramid = decompose(&fine, SurfaceScheme::Loop, Depth::Max)?;
    /// let rows = pyramid.rate_distortion(&[0.0, 1.0])?;
    /// assert_eq!((rows[0].kept, rows[1].kept), (0, pyramid.detail_count()));
    /// // No detail: the bump is smoothed away. Every detail: exact.
    /// assert!(rows[0].max_error > 0.0 && rows[0].rms_error < rows[0].max_error);
    /// assert!(rows[1].max_error < 1e-12);
    /// # Ok::<(), multires::Error>(())
    /// ```
    ///
    /// # Errors
    /// As [`reconstruct_keeping`](Self::reconstruct_keeping).
    pub fn rate_distortion(&self, fractions: &[f64]) -> Result<Vec<RateDistortion>, Error> {
        Ok(match self {
            Pyramid::Loop(p) => p.rate_distortion(fractions)?.into_iter().map(RateDistortion::from).collect(),
            Pyramid::Doo(p) => p.rate_distortion(fractions)?.into_iter().map(RateDistortion::from).collect(),
        })
    }

    /// The `.mres` file contents (the member crate's versioned encoding).
    ///
    /// ```
    /// use multires::doo::is_doo_pyramid;
    /// use multires::loop_subdiv::pyramid::LoopPyramid;
    /// use multires::prelude::*;
    ///
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// for scheme in [SurfaceScheme::Loop, SurfaceScheme::DooSabin] {
    ///     let fine = HalfedgeMesh::from_soup(&scheme.subdivide(&octahedron, 1)?)?;
    ///     let pyramid = decompose(&fine, scheme, Depth::Levels(1))?;
    ///     let bytes = pyramid.to_bytes()?;
    ///     // Each family writes its own format, told apart by the magic number.
    ///     let loop_file = scheme == SurfaceScheme::Loop;
    ///     assert_eq!((LoopPyramid::is_loop_pyramid(&bytes), is_doo_pyramid(&bytes)), (loop_file, !loop_file));
    ///     assert_eq!(Pyramid::from_bytes(&bytes)?, pyramid);
    /// }
    /// # Ok::<(), multires::Error>(())
    /// ```
    ///
    /// # Errors
    /// The member crate's encoding error.
    pub fn to_bytes(&self) -> Result<Vec<u8>, Error> {
        Ok(match self {
            Pyramid::Loop(p) => p.to_bytes()?,
            Pyramid::Doo(p) => p.to_bytes()?,
        })
    }

    /// Reads a `.mres` file of either family.
    ///
    /// ```
    /// use multires::prelude::*;
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = HalfedgeMesh::from_soup(&SurfaceScheme::DooSabin.subdivide(&cube, 1)?)?;
    /// let pyramid = decompose(&fine, SurfaceScheme::DooSabin, Depth::Levels(1))?;
    /// let bytes = pyramid.to_bytes()?;
    /// assert_eq!(Pyramid::from_bytes(&bytes)?, pyramid);
    /// assert!(Pyramid::from_bytes(&bytes[..bytes.len() / 2]).is_err()); // truncated
    /// # Ok::<(), multires::Error>(())
    /// ```
    ///
    /// # Errors
    /// [`Error::NotAPyramid`] if neither magic number matches; the member crate's error
    /// for a truncated, corrupted or newer-version file.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, Error> {
        if LoopPyramid::is_loop_pyramid(bytes) {
            Ok(Pyramid::Loop(LoopPyramid::from_bytes(bytes)?))
        } else if subdiv_doo::is_doo_pyramid(bytes) {
            Ok(Pyramid::Doo(DooPyramid::from_bytes(bytes)?))
        } else {
            Err(Error::NotAPyramid)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_topo::shapes;

    /// Moves every vertex a little so that the details are not zero.
    fn perturbed(soup: &PolygonSoup) -> HalfedgeMesh {
        let mut soup = soup.clone();
        for (i, p) in soup.positions.iter_mut().enumerate() {
            let t = i as f64;
            *p += glam::DVec3::new((t * 0.37).sin(), (t * 0.71).cos(), (t * 1.13).sin()) * 0.01;
        }
        HalfedgeMesh::from_soup(&soup).unwrap()
    }

    #[test]
    fn every_reversible_scheme_reconstructs_exactly() {
        let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron()).unwrap();
        let cube = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        for scheme in SurfaceScheme::ALL.into_iter().filter(|s| s.is_reversible()) {
            let coarse = if scheme.accepts_polygons() { &cube } else { &octahedron };
            let fine = perturbed(&scheme.subdivide(coarse, 2).unwrap());
            let pyramid = decompose(&fine, scheme, Depth::Levels(2)).unwrap();
            assert_eq!(pyramid.scheme(), scheme);
            let rebuilt = Pyramid::from_bytes(&pyramid.to_bytes().unwrap()).unwrap().reconstruct(2).unwrap();
            assert_eq!(rebuilt.indices, fine.to_soup().indices, "{scheme}");
            let worst = rebuilt.positions.iter().zip(fine.positions()).map(|(p, q)| p.distance(*q)).fold(0.0, f64::max);
            assert!(worst < 1e-12, "{scheme}: {worst}");
            let table = pyramid.rate_distortion(&[0.0, 1.0]).unwrap();
            assert!(table[1].max_error < 1e-12 && table[0].max_error > 0.0, "{scheme}: {table:?}");
        }
    }

    #[test]
    fn a_soup_decomposes_as_its_mesh() {
        let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron()).unwrap();
        let cube = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        let grid = HalfedgeMesh::from_soup(&shapes::grid(3, 2, shapes::CellKind::Quads).unwrap()).unwrap();
        let mut soups = Vec::new();
        for scheme in SurfaceScheme::ALL.into_iter().filter(|s| s.is_reversible()) {
            // (Doo-Sabin: a refined octahedron is in the canonical order the soup path takes.)
            let coarse_meshes = if scheme.accepts_polygons() { vec![&cube, &octahedron] } else { vec![&octahedron] };
            for coarse in coarse_meshes {
                let fine = perturbed(&scheme.subdivide(coarse, 2).unwrap()).to_soup();
                let mut not_finite = fine.clone();
                not_finite.positions[3].x = f64::NAN;
                let mut out_of_range = fine.clone();
                out_of_range.indices[2] = fine.vertex_count() as u32;
                soups.extend([fine, not_finite, out_of_range]);
            }
        }
        soups.push(SurfaceScheme::DooSabin.subdivide_with(&grid, 1, &Boundaries::chaikin()).unwrap());
        for soup in &soups {
            for scheme in SurfaceScheme::ALL {
                for boundaries in [Boundaries::default(), Boundaries::keep_corners(), Boundaries::chaikin()] {
                    for depth in [Depth::Levels(1), Depth::Max] {
                        let through_mesh = HalfedgeMesh::from_soup(soup)
                            .map_err(Error::from)
                            .and_then(|mesh| decompose_with(&mesh, scheme, depth, &boundaries));
                        let direct = decompose_soup(soup, scheme, depth, &boundaries);
                        assert_eq!(format!("{direct:?}"), format!("{through_mesh:?}"), "{scheme} {depth:?}");
                    }
                }
            }
        }
    }

    #[test]
    fn boundary_options_are_inverted_with_zero_details() {
        let triangles = HalfedgeMesh::from_soup(&shapes::grid(4, 3, shapes::CellKind::Triangles).unwrap()).unwrap();
        let quads = HalfedgeMesh::from_soup(&shapes::grid(4, 3, shapes::CellKind::Quads).unwrap()).unwrap();
        let cases = [
            (SurfaceScheme::Loop, &triangles, Boundaries::keep_corners()),
            (SurfaceScheme::LoopWarren, &triangles, Boundaries::keep_corners()),
            (SurfaceScheme::DooSabin, &quads, Boundaries::chaikin()),
            (SurfaceScheme::DooCentroid, &quads, Boundaries::chaikin()),
        ];
        for (scheme, coarse, boundaries) in cases {
            let fine = HalfedgeMesh::from_soup(&scheme.subdivide_with(coarse, 2, &boundaries).unwrap()).unwrap();
            let pyramid = decompose_with(&fine, scheme, Depth::Levels(2), &boundaries).unwrap();
            assert_eq!(pyramid.base().face_count(), coarse.face_count(), "{scheme}");
            let pyramid = Pyramid::from_bytes(&pyramid.to_bytes().unwrap()).unwrap();
            // Keeping no detail rebuilds the mesh: every detail is zero.
            let table = pyramid.rate_distortion(&[0.0]).unwrap();
            assert!(table[0].max_error < 1e-12, "{scheme}: {table:?}");
            // With the default rules the same mesh has details (Loop) or no reading (Doo-Sabin).
            match decompose(&fine, scheme, Depth::Levels(2)) {
                Ok(default) => assert!(default.rate_distortion(&[0.0]).unwrap()[0].max_error > 1e-6, "{scheme}"),
                Err(error) => assert!(matches!(error, Error::Doo(_)), "{scheme}: {error}"),
            }
        }
        let error = decompose_with(&triangles, SurfaceScheme::Loop, Depth::Max, &Boundaries::chaikin()).unwrap_err();
        assert!(matches!(error, Error::NotApplicable { .. }), "{error}");
    }

    #[test]
    fn m_band_schemes_are_not_reversible() {
        let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron()).unwrap();
        let error = decompose(&octahedron, SurfaceScheme::TernaryLoop, Depth::Max).unwrap_err();
        assert!(matches!(error, Error::NotReversible { .. }), "{error}");
    }

    #[test]
    fn unknown_bytes_are_not_a_pyramid() {
        assert!(matches!(Pyramid::from_bytes(b"not a pyramid"), Err(Error::NotAPyramid)));
        assert!(matches!(Pyramid::from_bytes(&[]), Err(Error::NotAPyramid)));
    }
}
