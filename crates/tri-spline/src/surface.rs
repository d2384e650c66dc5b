//! The three surface kinds behind one interface: bases for collocation matrices,
//! fitted surfaces for evaluation and sampling.

use glam::{DVec2, DVec3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::bezier::{MAX_BEZIER_DEGREE, bernstein_basis};
use crate::index::{checked_tri_count, tri_count};
use crate::linalg::SparseMatrix;
use crate::{BPatch, BPatchBasis, DmsBasis, DmsScratch, DmsSpline, DomainTriangle, SplineError, TriBezier};

/// The kind of surface, for reports and errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SurfaceKind {
    /// Triangular Bézier patch.
    Bezier,
    /// Seidel's B-patch.
    Bpatch,
    /// DMS triangular B-spline.
    TriBspline,
}

impl SurfaceKind {
    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Bezier => "bezier",
            Self::Bpatch => "bpatch",
            Self::TriBspline => "tri-bspline",
        }
    }
}

/// A spline basis of one of the three kinds, without control points.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum SurfaceBasis {
    /// Bernstein polynomials of a degree over a domain triangle.
    Bezier {
        /// The degree.
        degree: usize,
        /// The domain triangle.
        domain: DomainTriangle,
    },
    /// A B-patch basis.
    Bpatch(BPatchBasis),
    /// A DMS basis.
    Dms(DmsBasis),
}

impl SurfaceBasis {
    /// The kind.
    pub fn kind(&self) -> SurfaceKind {
        match self {
            Self::Bezier { .. } => SurfaceKind::Bezier,
            Self::Bpatch(_) => SurfaceKind::Bpatch,
            Self::Dms(_) => SurfaceKind::TriBspline,
        }
    }

    /// The polynomial degree.
    pub fn degree(&self) -> usize {
        match self {
            Self::Bezier { degree, .. } => *degree,
            Self::Bpatch(b) => b.degree(),
            Self::Dms(b) => b.degree(),
        }
    }

    /// Number of basis functions (`usize::MAX` for a Bézier degree whose count does not
    /// fit in `usize`, which no basis can have).
    pub fn count(&self) -> usize {
        match self {
            Self::Bezier { degree, .. } => checked_tri_count(*degree).unwrap_or(usize::MAX),
            Self::Bpatch(b) => tri_count(b.degree()),
            Self::Dms(b) => b.basis_count(),
        }
    }

    /// The collocation matrix `N_jk = N_k(u_j)` (exact zeros dropped), rows computed in
    /// parallel.
    ///
    /// # Errors
    /// [`SplineError::Degree`] for a Bézier degree above
    /// [`MAX_BEZIER_DEGREE`] (the variant's fields are
    /// public, so its degree is checked here, before anything is allocated).
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::{DomainTriangle, SurfaceBasis};
    /// let basis = SurfaceBasis::Bezier { degree: 2, domain: DomainTriangle::reference() };
    /// let n = basis.collocation(&[DVec2::new(0.25, 0.25), DVec2::ZERO])?;
    /// assert_eq!((n.rows(), n.cols()), (2, 6));
    /// assert!(SurfaceBasis::Bezier { degree: 1 << 20, domain: DomainTriangle::reference() }.collocation(&[]).is_err());
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn collocation(&self, params: &[DVec2]) -> Result<SparseMatrix, SplineError> {
        let rows: Vec<Vec<(usize, f64)>> = match self {
            Self::Bezier { degree, domain } => {
                if *degree > MAX_BEZIER_DEGREE {
                    return Err(SplineError::Degree { degree: *degree, min: 0, max: MAX_BEZIER_DEGREE });
                }
                params
                    .par_iter()
                    .map_init(Vec::new, |values, &u| {
                        bernstein_basis(*degree, domain.barycentric(u), values)
                            .expect("internal: the degree was checked above");
                        values.iter().enumerate().filter(|e| *e.1 != 0.0).map(|(i, &v)| (i, v)).collect()
                    })
                    .collect()
            }
            Self::Bpatch(basis) => params
                .par_iter()
                .map_init(Vec::new, |values, &u| {
                    basis.eval(u, values);
                    values.iter().enumerate().filter(|e| *e.1 != 0.0).map(|(i, &v)| (i, v)).collect()
                })
                .collect(),
            Self::Dms(basis) => params
                .par_iter()
                .map_init(DmsScratch::default, |scratch, &u| {
                    let mut row = Vec::new();
                    basis.eval_basis_with(u, scratch, &mut row);
                    row
                })
                .collect(),
        };
        Ok(SparseMatrix::from_rows(self.count(), rows))
    }

    /// The surface with these control points.
    ///
    /// # Errors
    /// [`SplineError::Count`] or [`SplineError::NonFinite`] for bad control points.
    ///
    /// ```
    /// use glam::{DVec2, DVec3};
    /// use tri_spline::{DomainTriangle, FittedSurface, SurfaceBasis};
    /// let basis = SurfaceBasis::Bezier { degree: 1, domain: DomainTriangle::reference() };
    /// let surface = basis.with_control(vec![DVec3::ZERO, DVec3::X, DVec3::Y])?;
    /// assert!(matches!(surface, FittedSurface::Bezier(_)));
    /// assert_eq!(surface.eval(DVec2::new(0.25, 0.5)), DVec3::new(0.25, 0.5, 0.0));
    /// assert!(basis.with_control(vec![DVec3::ZERO; 4]).is_err());
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn with_control(&self, control: Vec<DVec3>) -> Result<FittedSurface, SplineError> {
        Ok(match self {
            Self::Bezier { degree, domain } => FittedSurface::Bezier(TriBezier::new(*degree, *domain, control)?),
            Self::Bpatch(basis) => FittedSurface::Bpatch(basis.with_control(control)?),
            Self::Dms(basis) => FittedSurface::Dms(DmsSpline::new(basis.clone(), control)?),
        })
    }
}

/// A surface of one of the three kinds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum FittedSurface {
    /// A triangular Bézier patch.
    Bezier(TriBezier<DVec3>),
    /// A B-patch.
    Bpatch(BPatch<DVec3>),
    /// A DMS spline.
    Dms(DmsSpline<DVec3>),
}

impl FittedSurface {
    /// The point at parameter `u`.
    ///
    /// ```
    /// use glam::{DVec2, DVec3};
    /// use tri_spline::{BPatch, DomainTriangle, FittedSurface, KnotSequences, TriBezier};
    /// let domain = DomainTriangle::reference();
    /// let control: Vec<DVec3> = (0..6).map(|i| DVec3::new(i as f64, 1.0, (i * i) as f64)).collect();
    /// let bezier = FittedSurface::Bezier(TriBezier::new(2, domain, control.clone())?);
    /// // The same surface as a B-patch with coincident knots.
    /// let bpatch = FittedSurface::Bpatch(BPatch::new(2, KnotSequences::bezier(&domain, 2), control)?);
    /// let u = DVec2::new(0.2, 0.5);
    /// assert!((bezier.eval(u) - bpatch.eval(u)).length() < 1e-13);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval(&self, u: DVec2) -> DVec3 {
        match self {
            Self::Bezier(s) => s.eval(u),
            Self::Bpatch(s) => s.eval(u),
            Self::Dms(s) => s.eval(u),
        }
    }

    /// The unit normal at `u`, `None` where the surface is singular.
    ///
    /// ```
    /// use glam::{DVec2, DVec3};
    /// use tri_spline::{DomainTriangle, SurfaceBasis};
    /// let basis = SurfaceBasis::Bezier { degree: 1, domain: DomainTriangle::reference() };
    /// // The plane z = 1 - x - y, counter-clockwise over the domain: normal (1, 1, 1) / √3.
    /// let tilted = basis.with_control(vec![DVec3::Z, DVec3::X, DVec3::Y])?;
    /// assert!((tilted.normal(DVec2::new(0.2, 0.3)).unwrap() - DVec3::ONE / 3f64.sqrt()).length() < 1e-15);
    /// let collapsed = basis.with_control(vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0])?;
    /// assert_eq!(collapsed.normal(DVec2::new(0.2, 0.3)), None);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn normal(&self, u: DVec2) -> Option<DVec3> {
        match self {
            Self::Bezier(s) => s.normal(u),
            Self::Bpatch(s) => s.normal(u),
            Self::Dms(s) => s.normal(u),
        }
    }

    /// A triangulated sampling over `domain`: the regular grid with `samples` segments
    /// per side (`(s+1)(s+2)/2` points in the storage order of [`crate::index`], `s²`
    /// counter-clockwise triangles; 0 gives the one-segment grid). Points are evaluated
    /// in parallel.
    ///
    /// # Panics
    /// Above [`MAX_GRID_SEGMENTS`](crate::samples::MAX_GRID_SEGMENTS) segments per side
    /// (a mistyped size used to abort the process allocating); [`Self::try_sample`]
    /// returns an error instead.
    ///
    /// ```
    /// use glam::DVec3;
    /// use tri_spline::index::tri_index;
    /// use tri_spline::{DomainTriangle, SurfaceBasis};
    /// let domain = DomainTriangle::reference();
    /// let control: Vec<DVec3> = (0..6).map(|i| DVec3::new(i as f64, 1.0, (i * i) as f64)).collect();
    /// let surface = SurfaceBasis::Bezier { degree: 2, domain }.with_control(control.clone())?;
    /// let (points, triangles) = surface.sample(&domain, 4);
    /// assert_eq!((points.len(), triangles.len()), (15, 16));
    /// // Grid point (j, k) is the surface at t0 + (j/4)(t1 - t0) + (k/4)(t2 - t0).
    /// let u = domain.point([0.25, 0.5, 0.25]);
    /// assert!((points[tri_index(4, 2, 1)] - surface.eval(u)).length() < 1e-14);
    /// assert_eq!((points[0], points[4], points[14]), (control[0], control[2], control[5]));
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn sample(&self, domain: &DomainTriangle, samples: usize) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        self.try_sample(domain, samples).unwrap_or_else(|e| panic!("sample: {e}"))
    }

    /// [`Self::sample`] for a size given by a caller.
    ///
    /// # Errors
    /// [`SplineError::TooLarge`] above
    /// [`MAX_GRID_SEGMENTS`](crate::samples::MAX_GRID_SEGMENTS) segments per side, checked
    /// before allocating.
    ///
    /// ```
    /// use glam::DVec3;
    /// use tri_spline::samples::MAX_GRID_SEGMENTS;
    /// use tri_spline::{DomainTriangle, SplineError, SurfaceBasis};
    /// let domain = DomainTriangle::reference();
    /// let surface = SurfaceBasis::Bezier { degree: 1, domain }.with_control(vec![DVec3::ZERO, DVec3::X, DVec3::Y])?;
    /// let (points, triangles) = surface.try_sample(&domain, 2)?;
    /// assert_eq!((points.len(), triangles.len()), (6, 4));
    /// assert_eq!(points[1], DVec3::new(0.5, 0.0, 0.0));
    /// let too_fine = surface.try_sample(&domain, MAX_GRID_SEGMENTS + 1);
    /// assert!(matches!(too_fine, Err(SplineError::TooLarge { .. })));
    /// # Ok::<(), SplineError>(())
    /// ```
    pub fn try_sample(
        &self,
        domain: &DomainTriangle,
        samples: usize,
    ) -> Result<(Vec<DVec3>, Vec<[u32; 3]>), SplineError> {
        check_grid_segments(samples)?;
        let s = samples.max(1);
        let params: Vec<DVec2> = crate::index::multi_indices(s)
            .map(|[i, j, k]| domain.point([i as f64 / s as f64, j as f64 / s as f64, k as f64 / s as f64]))
            .collect();
        let positions = match self {
            Self::Dms(spline) => params
                .par_iter()
                .map_init(
                    || (DmsScratch::default(), Vec::new()),
                    |(scratch, values), &u| spline.eval_with(u, scratch, values),
                )
                .collect(),
            _ => params.par_iter().map(|&u| self.eval(u)).collect(),
        };
        Ok((positions, grid_triangles(s, domain.det() > 0.0)))
    }
}

/// [`SplineError::TooLarge`] above [`MAX_GRID_SEGMENTS`](crate::samples::MAX_GRID_SEGMENTS)
/// segments per side.
fn check_grid_segments(s: usize) -> Result<(), SplineError> {
    let max = crate::samples::MAX_GRID_SEGMENTS;
    if s > max {
        return Err(SplineError::TooLarge { what: "grid segments per side", requested: s, max });
    }
    Ok(())
}

/// The `s²` triangles of the regular triangular grid with `s` segments per side, vertex
/// `(j, k)` at position [`tri_index`](crate::index::tri_index)`(s, j, k)`; counter-clockwise
/// in the domain when `ccw`, else flipped.
///
/// # Panics
/// Above [`MAX_GRID_SEGMENTS`](crate::samples::MAX_GRID_SEGMENTS) segments per side (a
/// mistyped size used to abort the process allocating).
///
/// ```
/// use glam::DVec2;
/// use tri_spline::domain::orient;
/// use tri_spline::index::multi_indices;
/// use tri_spline::surface::grid_triangles;
/// // Positions 0, 1, 2 are row k = 0; 3, 4 row k = 1; 5 the apex.
/// assert_eq!(grid_triangles(2, true), vec![[0, 1, 3], [1, 4, 3], [1, 2, 4], [3, 4, 5]]);
/// assert_eq!(grid_triangles(2, false)[0], [0, 3, 1]);
/// // All s² triangles are counter-clockwise in the lattice coordinates (j, k).
/// let lattice: Vec<DVec2> = multi_indices(8).map(|[_, j, k]| DVec2::new(j as f64, k as f64)).collect();
/// let triangles = grid_triangles(8, true);
/// assert_eq!(triangles.len(), 64);
/// assert!(triangles.iter().all(|t| orient(lattice[t[0] as usize], lattice[t[1] as usize], lattice[t[2] as usize]) > 0.0));
/// ```
pub fn grid_triangles(s: usize, ccw: bool) -> Vec<[u32; 3]> {
    check_grid_segments(s).unwrap_or_else(|e| panic!("grid_triangles: {e}"));
    use crate::index::tri_index;
    let mut faces = Vec::with_capacity(s * s);
    let id = |j: usize, k: usize| tri_index(s, j, k) as u32;
    for k in 0..s {
        for j in 0..s - k {
            faces.push([id(j, k), id(j + 1, k), id(j, k + 1)]);
            if j + k + 1 < s {
                faces.push([id(j + 1, k), id(j + 1, k + 1), id(j, k + 1)]);
            }
        }
    }
    if !ccw {
        for f in &mut faces {
            f.swap(1, 2);
        }
    }
    faces
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_triangles_cover_the_triangle() {
        for s in 1..6 {
            let faces = grid_triangles(s, true);
            assert_eq!(faces.len(), s * s);
            let domain = DomainTriangle::reference();
            let points: Vec<DVec2> = crate::index::multi_indices(s)
                .map(|[i, j, k]| domain.point([i as f64 / s as f64, j as f64 / s as f64, k as f64 / s as f64]))
                .collect();
            let area: f64 = faces
                .iter()
                .map(|f| crate::domain::orient(points[f[0] as usize], points[f[1] as usize], points[f[2] as usize]))
                .inspect(|&a| assert!(a > 0.0))
                .sum();
            assert!((area - domain.det()).abs() < 1e-12);
        }
    }

    /// A sampling size beyond the limit is an error (it aborted the process allocating).
    #[test]
    fn oversized_samplings_are_errors() {
        let domain = DomainTriangle::reference();
        let plane = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        let surface = FittedSurface::Bezier(TriBezier::new(1, domain, plane).unwrap());
        let (points, faces) = surface.try_sample(&domain, 2).unwrap();
        assert_eq!((points.len(), faces.len()), (6, 4));
        assert_eq!(surface.try_sample(&domain, 0).unwrap(), surface.sample(&domain, 1));
        for samples in [crate::samples::MAX_GRID_SEGMENTS + 1, 1 << 40, usize::MAX] {
            let error = surface.try_sample(&domain, samples).unwrap_err();
            assert!(matches!(error, SplineError::TooLarge { requested, .. } if requested == samples), "{error}");
        }
    }

    #[test]
    fn collocation_rows_sum_to_one() {
        let domain = DomainTriangle::reference();
        let params: Vec<DVec2> = (0..20).map(|i| DVec2::new(0.03 * i as f64, 0.5 - 0.02 * i as f64)).collect();
        for basis in [
            SurfaceBasis::Bezier { degree: 5, domain },
            SurfaceBasis::Bpatch(BPatchBasis::new(3, crate::KnotSequences::bezier(&domain, 3)).unwrap()),
        ] {
            let n = basis.collocation(&params).unwrap();
            assert_eq!((n.rows(), n.cols()), (20, basis.count()));
            for i in 0..20 {
                assert!((n.row(i).1.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            }
        }
    }
}
