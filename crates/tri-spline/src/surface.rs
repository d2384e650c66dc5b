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
    pub fn eval(&self, u: DVec2) -> DVec3 {
        match self {
            Self::Bezier(s) => s.eval(u),
            Self::Bpatch(s) => s.eval(u),
            Self::Dms(s) => s.eval(u),
        }
    }

    /// The unit normal at `u`, `None` where the surface is singular.
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
    pub fn sample(&self, domain: &DomainTriangle, samples: usize) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        self.try_sample(domain, samples).unwrap_or_else(|e| panic!("sample: {e}"))
    }

    /// [`Self::sample`] for a size given by a caller.
    ///
    /// # Errors
    /// [`SplineError::TooLarge`] above
    /// [`MAX_GRID_SEGMENTS`](crate::samples::MAX_GRID_SEGMENTS) segments per side, checked
    /// before allocating.
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
