//! Sparse collocation matrices and the dense linear algebra of the fitting reports
//! (spectra, least squares), all sequential inside faer so that results do not depend
//! on the number of threads.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::{Mat, Par};
use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::SplineError;
use crate::point::Point;

/// A sparse matrix in compressed-row form (`u32` column indices).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SparseMatrix {
    rows: usize,
    cols: usize,
    row_start: Vec<usize>,
    col_index: Vec<u32>,
    values: Vec<f64>,
}

impl SparseMatrix {
    /// From per-row `(column, value)` lists (columns need not be sorted; duplicates are
    /// summed).
    ///
    /// # Panics
    /// If a column index is `>= cols` (an internal invariant of the callers) or beyond
    /// the `u32` column indices.
    ///
    /// ```
    /// use tri_spline::linalg::SparseMatrix;
    /// // Row 0 lists column 2 twice (summed) and out of order (sorted).
    /// let a = SparseMatrix::from_rows(3, vec![vec![(2, 1.0), (0, 2.0), (2, 0.5)], vec![]]);
    /// assert_eq!((a.rows(), a.cols(), a.nnz()), (2, 3, 2));
    /// assert_eq!(a.row(0), (&[0, 2][..], &[2.0, 1.5][..]));
    /// assert_eq!(a.mul_vec(&[1.0, 1.0, 1.0]), vec![3.5, 0.0]);
    /// ```
    pub fn from_rows(cols: usize, rows: Vec<Vec<(usize, f64)>>) -> Self {
        let mut row_start = Vec::with_capacity(rows.len() + 1);
        row_start.push(0);
        let mut col_index = Vec::new();
        let mut values = Vec::new();
        let n_rows = rows.len();
        for mut row in rows {
            row.sort_unstable_by_key(|e| e.0);
            let start = col_index.len();
            for (c, v) in row {
                assert!(c < cols && u32::try_from(c).is_ok(), "internal: column {c} out of range {cols}");
                if col_index.len() > start && *col_index.last().expect("internal: non-empty") as usize == c {
                    *values.last_mut().expect("internal: non-empty") += v;
                } else {
                    col_index.push(c as u32);
                    values.push(v);
                }
            }
            row_start.push(col_index.len());
        }
        Self { rows: n_rows, cols, row_start, col_index, values }
    }

    /// The identity of size `n` (`n` from 0 to [`MAX_DIMENSION`]; about 20 bytes per row).
    ///
    /// # Errors
    /// [`SplineError::TooLarge`] above [`MAX_DIMENSION`], checked before allocating (a
    /// mistyped size used to abort the process allocating a row list per row).
    ///
    /// ```
    /// use tri_spline::linalg::{MAX_DIMENSION, SparseMatrix};
    /// assert_eq!(SparseMatrix::identity(3)?.mul_vec(&[1.0, 2.0, 3.0]), vec![1.0, 2.0, 3.0]);
    /// assert!(SparseMatrix::identity(MAX_DIMENSION + 1).is_err());
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn identity(n: usize) -> Result<Self, SplineError> {
        if n > MAX_DIMENSION {
            return Err(SplineError::TooLarge { what: "identity matrix size", requested: n, max: MAX_DIMENSION });
        }
        // Built directly: the compressed form of the identity needs no sorting or merging.
        Ok(Self {
            rows: n,
            cols: n,
            row_start: (0..=n).collect(),
            col_index: (0..n).map(|i| i as u32).collect(),
            values: vec![1.0; n],
        })
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Row `i` as `(columns, values)`.
    ///
    /// # Panics
    /// If `i >= self.rows()`.
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        assert!(i < self.rows, "row {i} is out of range (there are {})", self.rows);
        let r = self.row_start[i]..self.row_start[i + 1];
        (&self.col_index[r.clone()], &self.values[r])
    }

    /// The first row holding a NaN or infinite entry, if any.
    ///
    /// ```
    /// use tri_spline::linalg::SparseMatrix;
    /// let a = SparseMatrix::from_rows(2, vec![vec![(0, 1.0)], vec![], vec![(1, f64::NAN)]]);
    /// assert_eq!(a.first_non_finite_row(), Some(2));
    /// assert_eq!(SparseMatrix::from_rows(2, vec![vec![(1, 1.0)]]).first_non_finite_row(), None);
    /// ```
    pub fn first_non_finite_row(&self) -> Option<usize> {
        let entry = self.values.iter().position(|v| !v.is_finite())?;
        // The row whose range holds the entry: the last row starting at or before it.
        Some(self.row_start.partition_point(|&start| start <= entry) - 1)
    }

    /// `A x`, rows in parallel (each output entry from one task: deterministic).
    ///
    /// # Panics
    /// Unless `x` has one entry per column; [`try_mul_vec`](Self::try_mul_vec) returns an
    /// error instead.
    ///
    /// ```
    /// use glam::DVec3;
    /// use tri_spline::linalg::SparseMatrix;
    /// let a = SparseMatrix::from_rows(2, vec![vec![(0, 1.0), (1, 2.0)], vec![(1, 3.0)]]);
    /// assert_eq!(a.mul_vec(&[1.0, 1.0]), vec![3.0, 3.0]);
    /// // Points are combined coordinate-wise.
    /// assert_eq!(a.mul_vec(&[DVec3::X, DVec3::Y]), vec![DVec3::new(1.0, 2.0, 0.0), DVec3::new(0.0, 3.0, 0.0)]);
    /// ```
    pub fn mul_vec<P: Point>(&self, x: &[P]) -> Vec<P> {
        self.try_mul_vec(x).unwrap_or_else(|e| panic!("SparseMatrix::mul_vec: {e}"))
    }

    /// `A x` as [`mul_vec`](Self::mul_vec), for a vector built by the caller.
    ///
    /// # Errors
    /// [`SplineError::Count`] unless `x` has one entry per column.
    ///
    /// ```
    /// use tri_spline::SplineError;
    /// use tri_spline::linalg::SparseMatrix;
    /// let a = SparseMatrix::from_rows(2, vec![vec![(0, 1.0), (1, 2.0)]]);
    /// assert_eq!(a.try_mul_vec(&[1.0, 1.0])?, vec![3.0]);
    /// assert!(matches!(a.try_mul_vec(&[1.0]), Err(SplineError::Count { expected: 2, got: 1, .. })));
    /// # Ok::<(), SplineError>(())
    /// ```
    pub fn try_mul_vec<P: Point>(&self, x: &[P]) -> Result<Vec<P>, SplineError> {
        if x.len() != self.cols {
            return Err(SplineError::Count {
                what: "vector entries (columns of the matrix)",
                expected: self.cols,
                got: x.len(),
            });
        }
        Ok(self.mul_vec_unchecked(x))
    }

    /// `A x` for `x` of the right length.
    fn mul_vec_unchecked<P: Point>(&self, x: &[P]) -> Vec<P> {
        (0..self.rows)
            .into_par_iter()
            .with_min_len(256)
            .map(|i| {
                let (cols, vals) = self.row(i);
                cols.iter().zip(vals).fold(P::ZERO, |s, (&c, &v)| s + x[c as usize] * v)
            })
            .collect()
    }

    /// The transpose.
    ///
    /// ```
    /// use tri_spline::linalg::SparseMatrix;
    /// let a = SparseMatrix::from_rows(3, vec![vec![(0, 1.0), (2, 2.0)], vec![(1, 3.0)]]);
    /// let t = a.transpose();
    /// assert_eq!((t.rows(), t.cols()), (3, 2));
    /// assert_eq!(t.to_dense()[(2, 0)], 2.0);
    /// assert_eq!(t.transpose(), a);
    /// ```
    pub fn transpose(&self) -> Self {
        let mut counts = vec![0usize; self.cols + 1];
        for &c in &self.col_index {
            counts[c as usize + 1] += 1;
        }
        for c in 0..self.cols {
            counts[c + 1] += counts[c];
        }
        let mut fill = counts.clone();
        let mut col_index = vec![0u32; self.nnz()];
        let mut values = vec![0.0; self.nnz()];
        for i in 0..self.rows {
            let (cols, vals) = self.row(i);
            for (&c, &v) in cols.iter().zip(vals) {
                let at = fill[c as usize];
                col_index[at] = i as u32;
                values[at] = v;
                fill[c as usize] += 1;
            }
        }
        Self { rows: self.cols, cols: self.rows, row_start: counts, col_index, values }
    }

    /// The product `self * other`.
    ///
    /// # Panics
    /// Unless `other` has one row per column of `self`.
    ///
    /// ```
    /// use tri_spline::linalg::SparseMatrix;
    /// let a = SparseMatrix::from_rows(2, vec![vec![(0, 1.0), (1, 2.0)], vec![(1, 3.0)]]);
    /// let square = a.mul(&a).to_dense();
    /// assert_eq!([square[(0, 0)], square[(0, 1)], square[(1, 0)], square[(1, 1)]], [1.0, 8.0, 0.0, 9.0]);
    /// assert_eq!(a.mul(&SparseMatrix::identity(2)?), a);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn mul(&self, other: &SparseMatrix) -> Self {
        assert!(
            self.cols == other.rows,
            "SparseMatrix::mul: the left factor has {} columns but the right one {} rows",
            self.cols,
            other.rows
        );
        let rows = (0..self.rows)
            .into_par_iter()
            .map(|i| {
                let (cols, vals) = self.row(i);
                let mut row: Vec<(usize, f64)> = Vec::new();
                for (&k, &a) in cols.iter().zip(vals) {
                    let (oc, ov) = other.row(k as usize);
                    row.extend(oc.iter().zip(ov).map(|(&c, &b)| (c as usize, a * b)));
                }
                row
            })
            .collect();
        Self::from_rows(other.cols, rows)
    }

    /// `max_j sum_i |a_ij|` (the 1-norm).
    ///
    /// ```
    /// use tri_spline::linalg::SparseMatrix;
    /// // [[1, -2], [0, 4]]: column sums 1 and 6.
    /// let a = SparseMatrix::from_rows(2, vec![vec![(0, 1.0), (1, -2.0)], vec![(1, 4.0)]]);
    /// assert_eq!(a.norm_1(), 6.0);
    /// ```
    pub fn norm_1(&self) -> f64 {
        let mut sums = vec![0.0; self.cols];
        for (&c, &v) in self.col_index.iter().zip(&self.values) {
            sums[c as usize] += v.abs();
        }
        sums.into_iter().fold(0.0, f64::max)
    }

    /// `max_i sum_j |a_ij|` (the infinity norm).
    ///
    /// ```
    /// use tri_spline::linalg::SparseMatrix;
    /// // [[1, -2], [0, 4]]: row sums 3 and 4.
    /// let a = SparseMatrix::from_rows(2, vec![vec![(0, 1.0), (1, -2.0)], vec![(1, 4.0)]]);
    /// assert_eq!(a.norm_inf(), 4.0);
    /// ```
    pub fn norm_inf(&self) -> f64 {
        (0..self.rows).map(|i| self.row(i).1.iter().map(|v| v.abs()).sum::<f64>()).fold(0.0, f64::max)
    }

    /// Whether every stored entry is non-negative.
    ///
    /// ```
    /// use tri_spline::linalg::SparseMatrix;
    /// assert!(SparseMatrix::from_rows(2, vec![vec![(0, 0.5), (1, 0.5)]]).is_non_negative());
    /// assert!(!SparseMatrix::from_rows(2, vec![vec![(0, 1.5), (1, -0.5)]]).is_non_negative());
    /// ```
    pub fn is_non_negative(&self) -> bool {
        self.values.iter().all(|&v| v >= 0.0)
    }

    /// As a dense faer matrix.
    ///
    /// ```
    /// use tri_spline::linalg::SparseMatrix;
    /// let dense = SparseMatrix::from_rows(3, vec![vec![(2, 5.0)], vec![(0, 1.0)]]).to_dense();
    /// assert_eq!((dense.nrows(), dense.ncols()), (2, 3));
    /// assert_eq!((dense[(0, 2)], dense[(1, 0)], dense[(0, 0)]), (5.0, 1.0, 0.0));
    /// ```
    pub fn to_dense(&self) -> Mat<f64> {
        let mut m = Mat::<f64>::zeros(self.rows, self.cols);
        for i in 0..self.rows {
            let (cols, vals) = self.row(i);
            for (&c, &v) in cols.iter().zip(vals) {
                m[(i, c as usize)] += v;
            }
        }
        m
    }
}

/// Largest dimension of [`SparseMatrix::identity`]: column indices are stored as `u32`.
pub const MAX_DIMENSION: usize = u32::MAX as usize;

/// Most power iterations [`gram_lambda_max_bound`] runs, whatever it is asked.
pub const MAX_POWER_ITERATIONS: usize = 1 << 16;

/// A rigorous upper bound on `λ_max(NᵀN)`, tight for non-negative `N`: the
/// Collatz–Wielandt bound `max_i (A x)_i / x_i` along power iterations with a positive
/// vector (Perron–Frobenius), else `‖N‖₁ ‖N‖∞`.
///
/// ```
/// use tri_spline::linalg::{SparseMatrix, gram_lambda_max_bound, symmetric_eigenvalues};
/// let n = SparseMatrix::from_rows(2, vec![
///     vec![(0, 1.0)], vec![(0, 0.5), (1, 0.5)], vec![(0, 0.2), (1, 0.8)], vec![(1, 1.0)],
/// ]);
/// let dense = n.to_dense();
/// let exact = *symmetric_eigenvalues(&(dense.transpose() * &dense))?.last().unwrap();
/// let bound = gram_lambda_max_bound(&n, 50);
/// // An upper bound, tight here, and far below the crude one.
/// assert!(bound >= exact * (1.0 - 1e-12) && bound <= exact * (1.0 + 1e-9));
/// assert!(bound < n.norm_1() * n.norm_inf() - 0.1);
/// # Ok::<(), tri_spline::SplineError>(())
/// ```
pub fn gram_lambda_max_bound(n: &SparseMatrix, iterations: usize) -> f64 {
    let crude = n.norm_1() * n.norm_inf();
    if !n.is_non_negative() || n.cols() == 0 {
        return crude;
    }
    let nt = n.transpose();
    let mut x = vec![1.0f64; n.cols()];
    let mut best = crude;
    // (At most `MAX_POWER_ITERATIONS`: a caller's `usize::MAX` would never end.)
    for _ in 0..iterations.min(MAX_POWER_ITERATIONS) {
        let y = nt.mul_vec(&n.mul_vec(&x));
        // Components that vanish would make the ratio meaningless: stop there.
        if x.iter().any(|&v| v <= 0.0) {
            break;
        }
        let bound = y.iter().zip(&x).map(|(a, b)| a / b).fold(0.0, f64::max);
        best = best.min(bound);
        let scale = y.iter().fold(0.0, |m: f64, &v| m.max(v));
        if scale <= 0.0 {
            break;
        }
        let next: Vec<f64> = y.into_iter().map(|v| v / scale).collect();
        // A fixed point repeats itself: every further iteration gives the same bound.
        if next == x {
            break;
        }
        x = next;
    }
    best
}

/// Eigenvalues (real and imaginary parts) of a dense square matrix, computed
/// sequentially.
///
/// # Errors
/// [`SplineError::Singular`] if the eigenvalue iteration does not converge.
///
/// ```
/// use tri_spline::linalg::eigenvalues;
/// // A quarter turn has the eigenvalues ±i.
/// let mut values = eigenvalues(&faer::mat![[0.0, -1.0], [1.0, 0.0]])?;
/// values.sort_by(|a, b| a.1.total_cmp(&b.1));
/// assert!(values[0].0.abs() < 1e-15 && (values[0].1 + 1.0).abs() < 1e-15);
/// assert!(values[1].0.abs() < 1e-15 && (values[1].1 - 1.0).abs() < 1e-15);
/// # Ok::<(), tri_spline::SplineError>(())
/// ```
pub fn eigenvalues(a: &Mat<f64>) -> Result<Vec<(f64, f64)>, SplineError> {
    let n = a.nrows();
    let mut re = faer::diag::Diag::<f64>::zeros(n);
    let mut im = faer::diag::Diag::<f64>::zeros(n);
    let par = Par::Seq;
    let scratch = faer::linalg::evd::evd_scratch::<f64>(
        n,
        faer::linalg::evd::ComputeEigenvectors::No,
        faer::linalg::evd::ComputeEigenvectors::No,
        par,
        Default::default(),
    );
    faer::linalg::evd::evd_real(
        a.as_ref(),
        re.as_mut(),
        im.as_mut(),
        None,
        None,
        par,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    )
    .map_err(|_| SplineError::Singular { what: "eigenvalues of the iteration matrix" })?;
    Ok((0..n).map(|i| (re.column_vector()[i], im.column_vector()[i])).collect())
}

/// Eigenvalues of a dense symmetric matrix, ascending, computed sequentially.
///
/// # Errors
/// [`SplineError::Singular`] if the iteration does not converge.
///
/// ```
/// use tri_spline::linalg::symmetric_eigenvalues;
/// let values = symmetric_eigenvalues(&faer::mat![[2.0, 1.0], [1.0, 2.0]])?;
/// assert!((values[0] - 1.0).abs() < 1e-15 && (values[1] - 3.0).abs() < 1e-15);
/// # Ok::<(), tri_spline::SplineError>(())
/// ```
pub fn symmetric_eigenvalues(a: &Mat<f64>) -> Result<Vec<f64>, SplineError> {
    let n = a.nrows();
    let mut s = faer::diag::Diag::<f64>::zeros(n);
    let par = Par::Seq;
    let scratch = faer::linalg::evd::self_adjoint_evd_scratch::<f64>(
        n,
        faer::linalg::evd::ComputeEigenvectors::No,
        par,
        Default::default(),
    );
    faer::linalg::evd::self_adjoint_evd(
        a.as_ref(),
        s.as_mut(),
        None,
        par,
        MemStack::new(&mut MemBuffer::new(scratch)),
        Default::default(),
    )
    .map_err(|_| SplineError::Singular { what: "eigenvalues of NᵀN" })?;
    let mut values: Vec<f64> = (0..n).map(|i| s.column_vector()[i]).collect();
    values.sort_by(f64::total_cmp);
    Ok(values)
}

/// The spectral radius `max |λ|` of a dense square matrix.
///
/// # Errors
/// As [`eigenvalues`].
///
/// ```
/// use tri_spline::linalg::spectral_radius;
/// // Eigenvalues ±i√2: the radius is √2 (the largest |entry| is 2).
/// let rho = spectral_radius(&faer::mat![[0.0, -2.0], [1.0, 0.0]])?;
/// assert!((rho - 2f64.sqrt()).abs() < 1e-15);
/// # Ok::<(), tri_spline::SplineError>(())
/// ```
pub fn spectral_radius(a: &Mat<f64>) -> Result<f64, SplineError> {
    Ok(eigenvalues(a)?.into_iter().map(|(re, im)| re.hypot(im)).fold(0.0, f64::max))
}

/// Least-squares solution of `N C ≈ D` by a dense Householder QR of `N` (not the
/// normal equations, whose condition number is the square of `N`'s), sequential.
///
/// # Errors
/// [`SplineError::Count`] unless there is one data point per row of `N`;
/// [`SplineError::Singular`] when `N` has fewer rows than columns or is rank deficient
/// (a zero on the diagonal of `R`).
///
/// ```
/// use glam::DVec3;
/// use tri_spline::SplineError;
/// use tri_spline::linalg::{SparseMatrix, least_squares};
/// // The line through two control points, sampled at t = 0, 1/2, 1.
/// let n = SparseMatrix::from_rows(2, vec![vec![(0, 1.0)], vec![(0, 0.5), (1, 0.5)], vec![(1, 1.0)]]);
/// let (a, b) = (DVec3::new(1.0, 2.0, 3.0), DVec3::new(-1.0, 0.0, 5.0));
/// let control = least_squares(&n, &[a, (a + b) * 0.5, b])?;
/// assert!((control[0] - a).length() < 1e-14 && (control[1] - b).length() < 1e-14);
/// // Two equal columns: rank deficient.
/// let twins = SparseMatrix::from_rows(2, vec![vec![(0, 1.0), (1, 1.0)], vec![(0, 2.0), (1, 2.0)]]);
/// assert!(matches!(least_squares(&twins, &[a, b]), Err(SplineError::Singular { .. })));
/// # Ok::<(), SplineError>(())
/// ```
pub fn least_squares(n: &SparseMatrix, data: &[DVec3]) -> Result<Vec<DVec3>, SplineError> {
    let (m, k) = (n.rows(), n.cols());
    if data.len() != m {
        return Err(SplineError::Count {
            what: "data points (rows of the collocation matrix)",
            expected: m,
            got: data.len(),
        });
    }
    if m < k || k == 0 {
        return Err(SplineError::Singular { what: "least squares (fewer data points than control points)" });
    }
    use faer::linalg::qr::no_pivoting::{factor, solve};
    let par = Par::Seq;
    let mut qr = n.to_dense();
    let block = factor::recommended_block_size::<f64>(m, k);
    let mut q_coeff = Mat::<f64>::zeros(block, k);
    factor::qr_in_place(
        qr.as_mut(),
        q_coeff.as_mut(),
        par,
        MemStack::new(&mut MemBuffer::new(factor::qr_in_place_scratch::<f64>(m, k, block, par, Default::default()))),
        Default::default(),
    );
    // R: upper triangle; Householder basis: strictly lower part with a unit diagonal.
    let mut r = Mat::<f64>::zeros(k, k);
    let mut basis = qr;
    for j in 0..k {
        for i in 0..=j {
            r[(i, j)] = basis[(i, j)];
        }
        for i in 0..j {
            basis[(i, j)] = 0.0;
        }
        basis[(j, j)] = 1.0;
    }
    let scale = (0..k).map(|i| r[(i, i)].abs()).fold(0.0, f64::max);
    if (0..k).any(|i| r[(i, i)].abs() <= 1e-14 * scale) {
        return Err(SplineError::Singular { what: "least squares (collocation matrix is rank deficient)" });
    }
    let mut rhs = Mat::<f64>::from_fn(m, 3, |i, j| data[i][j]);
    solve::solve_lstsq_in_place_with_conj(
        basis.as_ref(),
        q_coeff.as_ref(),
        r.as_ref(),
        faer::Conj::No,
        rhs.as_mut(),
        par,
        MemStack::new(&mut MemBuffer::new(solve::solve_lstsq_in_place_scratch::<f64>(m, k, block, 3, par))),
    );
    Ok((0..k).map(|i| DVec3::new(rhs[(i, 0)], rhs[(i, 1)], rhs[(i, 2)])).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> SparseMatrix {
        SparseMatrix::from_rows(
            3,
            vec![
                vec![(0, 0.5), (2, 0.5)],
                vec![(1, 1.0)],
                vec![(0, 0.25), (1, 0.25), (2, 0.5)],
                vec![(2, 0.7), (2, 0.3)],
            ],
        )
    }

    #[test]
    fn products_and_transpose() {
        let a = sample();
        assert_eq!(a.nnz(), 7);
        let x = [1.0, 2.0, 4.0];
        assert_eq!(a.mul_vec(&x), vec![2.5, 2.0, 2.75, 4.0]);
        let t = a.transpose();
        let y = [1.0, 1.0, 1.0, 1.0];
        assert_eq!(t.mul_vec(&y), vec![0.75, 1.25, 2.0]);
        let ata = t.mul(&a);
        let dense = ata.to_dense();
        let direct = a.to_dense().transpose() * a.to_dense();
        assert!((dense - direct).norm_max() < 1e-15);
        assert_eq!(a.norm_inf(), 1.0);
        assert_eq!(a.norm_1(), 2.0);
    }

    /// Any iteration count ends: at a fixed point at once (the identity), else after
    /// [`MAX_POWER_ITERATIONS`], with the bound of the iterations asked for.
    #[test]
    fn lambda_bound_ends_for_any_iteration_count() {
        assert_eq!(gram_lambda_max_bound(&SparseMatrix::identity(3).unwrap(), usize::MAX), 1.0);
        let a = sample();
        let capped = gram_lambda_max_bound(&a, usize::MAX);
        assert!(capped <= gram_lambda_max_bound(&a, 50));
        assert_eq!(capped, gram_lambda_max_bound(&a, MAX_POWER_ITERATIONS));
    }

    /// A vector of the wrong length panicked with "internal: dimension mismatch", which
    /// blamed this crate rather than the caller's vector.
    #[test]
    fn vectors_of_the_wrong_length_are_errors_or_named_panics() {
        let a = sample();
        for len in [0, 2, 4] {
            let x = vec![1.0; len];
            assert_eq!(
                a.try_mul_vec(&x),
                Err(SplineError::Count { what: "vector entries (columns of the matrix)", expected: 3, got: len })
            );
        }
        assert_eq!(a.try_mul_vec(&[1.0, 2.0, 4.0]).unwrap(), a.mul_vec(&[1.0, 2.0, 4.0]));
        let caught = std::panic::catch_unwind(|| a.mul_vec(&[1.0])).unwrap_err();
        let message = caught.downcast_ref::<String>().unwrap();
        assert!(message.contains("vector entries (columns of the matrix): expected 3 entries, got 1"), "{message}");
    }

    /// `identity(1 << 40)` used to abort the process allocating a row list per row.
    #[test]
    fn identity_beyond_the_u32_columns_is_an_error_before_allocating() {
        for n in [MAX_DIMENSION + 1, 1 << 40, usize::MAX] {
            assert_eq!(
                SparseMatrix::identity(n),
                Err(SplineError::TooLarge { what: "identity matrix size", requested: n, max: MAX_DIMENSION })
            );
        }
        let built = SparseMatrix::identity(4).unwrap();
        assert_eq!(built, SparseMatrix::from_rows(4, (0..4).map(|i| vec![(i, 1.0)]).collect()));
        assert_eq!(SparseMatrix::identity(0).unwrap().rows(), 0);
    }

    #[test]
    fn non_finite_entries_are_found_by_row() {
        assert_eq!(sample().first_non_finite_row(), None);
        let m =
            SparseMatrix::from_rows(2, vec![vec![], vec![(0, 1.0), (1, f64::NAN)], vec![], vec![(0, f64::INFINITY)]]);
        assert_eq!(m.first_non_finite_row(), Some(1));
        let m = SparseMatrix::from_rows(2, vec![vec![], vec![(0, 1.0)], vec![], vec![(0, f64::INFINITY)]]);
        assert_eq!(m.first_non_finite_row(), Some(3));
    }

    #[test]
    #[should_panic(expected = "the left factor has 3 columns but the right one 2 rows")]
    fn products_of_mismatched_matrices_panic_with_the_sizes() {
        let _ = sample().mul(&SparseMatrix::identity(2).unwrap());
    }

    #[test]
    #[should_panic(expected = "row 4 is out of range (there are 4)")]
    fn rows_beyond_the_matrix_panic_with_the_count() {
        let _ = sample().row(4);
    }

    #[test]
    #[should_panic(expected = "out of range")]
    fn a_column_beyond_u32_panics_rather_than_wrapping() {
        // Stored column 0 before (an `as u32`).
        SparseMatrix::from_rows(usize::MAX, vec![vec![(1 << 32, 1.0)]]);
    }

    #[test]
    fn lambda_bound_is_an_upper_bound_and_tight() {
        let a = sample();
        let ata = a.transpose().mul(&a).to_dense();
        let exact = symmetric_eigenvalues(&ata).unwrap().into_iter().fold(0.0, f64::max);
        let bound = gram_lambda_max_bound(&a, 50);
        assert!(bound >= exact * (1.0 - 1e-12) && bound <= exact * (1.0 + 1e-6), "{bound} vs {exact}");
    }

    #[test]
    fn spectra() {
        // Rotation by 90 degrees scaled by 0.5: eigenvalues ±0.5i.
        let a = Mat::<f64>::from_fn(2, 2, |i, j| [[0.0, -0.5], [0.5, 0.0]][i][j]);
        assert!((spectral_radius(&a).unwrap() - 0.5).abs() < 1e-15);
    }

    #[test]
    fn least_squares_fits_a_line() {
        // Fit c0 + c1 t to points on a line plus symmetric noise: exact line back.
        let ts = [0.0, 1.0, 2.0, 3.0];
        let n = SparseMatrix::from_rows(2, ts.iter().map(|&t| vec![(0, 1.0 - t / 3.0), (1, t / 3.0)]).collect());
        let noise = [0.1, -0.1, -0.1, 0.1];
        let data: Vec<DVec3> = ts.iter().zip(noise).map(|(&t, e)| DVec3::new(t, 2.0 * t + e, 1.0)).collect();
        let c = least_squares(&n, &data).unwrap();
        assert!((c[0] - DVec3::new(0.0, 0.0, 1.0)).length() < 1e-12, "{:?}", c);
        assert!((c[1] - DVec3::new(3.0, 6.0, 1.0)).length() < 1e-12);
        let deficient = SparseMatrix::from_rows(2, vec![vec![(0, 1.0)], vec![(0, 1.0)]]);
        assert!(least_squares(&deficient, &data[..2]).is_err());
    }

    #[test]
    fn least_squares_needs_one_data_point_per_row() {
        // Used to index `data` out of bounds.
        let n = SparseMatrix::identity(3).unwrap();
        for len in [0, 2, 4] {
            let data = vec![DVec3::ZERO; len];
            assert_eq!(
                least_squares(&n, &data),
                Err(SplineError::Count { what: "data points (rows of the collocation matrix)", expected: 3, got: len })
            );
        }
    }
}
