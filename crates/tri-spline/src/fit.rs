//! Progressive iterative approximation: classical PIA, LSPIA and the seed paper's
//! geometric-approximation loop, with error reports, spectral radii of the iteration
//! matrices and a direct least-squares baseline (ALGORITHMS.md §12).
//!
//! Notation: data `D_j` at parameters `u_j` (`m` points), control points `C_k`
//! (`m_c`), collocation matrix `N_jk = N_k(u_j)` (`m × m_c`), residuals
//! `E = D - N C`, one vector per data point.
//!
//! * **Classical PIA** (interpolation, `m_c` targets for `m_c` control points):
//!   `C ← C + w (T - N_T C)` with `N_T` the square collocation matrix at the targets'
//!   parameters. Its residuals satisfy `E^k = (I - w N_T)^k E^0` exactly; it converges iff
//!   `ρ(I - w N_T) < 1`. For triangular Bézier patches at the uniform domain points,
//!   `ρ(I - N_T) = 1 - n!/n^n` (Chen & Wang 2011; the eigenvalues of `N_T` are those of the
//!   Bernstein operator, `n! / ((n - k)! n^k)`, Cooper & Waldron 2000).
//! * **LSPIA** (Deng & Lin 2014): `C ← C + μ Nᵀ (D - N C)`. For `0 < μ <= 2/λ_max(NᵀN)`
//!   the residual 2-norm never increases, and for `μ < 2/λ_max` with `N` of full column
//!   rank it converges to the least-squares fit, at rate `ρ(I - μ NᵀN)`. The default
//!   step is `μ = 1.5/c` with `c` a rigorous upper bound of `λ_max(NᵀN)` that is tight for
//!   non-negative bases ([`gram_lambda_max_bound`]), so the residual is monotone
//!   ([`default_lspia_step`] says why 1.5).
//! * **Seed loop** (seed 001 §III, ALGORITHMS.md §12.4): `P* := D`; repeat
//!   `C := R(P*)`, `E := D - N C`, `P* := P* + E`, with `R` the linear map from data to
//!   control points (i-fold reverse Loop). In control-point form `C ← C + R (D - N C)`: a
//!   PIA with weighting matrix `R`; it converges iff `ρ(I - R N) < 1`, to the oblique
//!   projection `C* = (R N)^{-1} R D`, which is neither interpolation nor least squares.
//!
//! **Errata of the seed's convergence argument** (ALGORITHMS.md §12.5): (a) the seed's
//! eq. (4) defines the error as a norm (a scalar) but eq. (6) adds it to a point; the
//! vector error `E_j = D_j - S(u_j)` is used here. (b) Non-negative matrix entries do not
//! imply non-negative eigenvalues, and `‖N‖∞ = 1` only gives `|λ| <= 1`. (c) Even with
//! `0 <= λ <= 1`, `ρ(I - N) < 1` needs `λ_min > 0`. (d) The analysed iteration (as many
//! control points as data) is not the implemented one (reverse Loop inside the loop,
//! fewer control points than data), whose errors do not tend to zero in general. Hence
//! nothing is assumed here: [`lspia_spectrum`], [`pia_spectral_radius`] and
//! [`seed_spectral_radius`] compute the spectral radius of the iteration at hand.
//!
//! What is monotone (§12.3, and what the tests check): `E^k = (I - w N)^k E^0`; the LSPIA
//! residual 2-norm; not the maximum error of PIA or of the seed loop (the seed's own
//! Table 2 shows `ε_max` and `N_ε` rising between iterations).
//!
//! References: H. Lin, G. Wang, C. Dong, Constructing iterative non-uniform B-spline
//! curve and surface to fit data points, Sci. China F 47 (2004) 315–331; J. Chen,
//! G.-J. Wang, Progressive iterative approximation for triangular Bézier surfaces, CAD 43
//! (2011) 889–895; C. Deng, H. Lin, Progressive and iterative approximation for least
//! squares B-spline curve and surface fitting, CAD 47 (2014) 32–44.

use std::time::Instant;

use faer::Mat;
use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::SplineError;
pub use crate::linalg::gram_lambda_max_bound;
use crate::linalg::{SparseMatrix, eigenvalues, least_squares, spectral_radius, symmetric_eigenvalues};

/// One row of the convergence table (the columns of the seed paper's Table 2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct IterationRecord {
    /// Iteration number, from 1 (the first control net, before any correction).
    pub k: usize,
    /// Largest error `max_j |E_j|`.
    pub eps_max: f64,
    /// Mean error `mean_j |E_j|`.
    pub eps_avg: f64,
    /// Percentage of data points with `|E_j| <= hit_tol`.
    pub n_eps: f64,
    /// Seconds since the iteration started (cumulative).
    pub seconds: f64,
}

/// Error statistics of a residual.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ErrorStats {
    /// `max_j |E_j|`.
    pub eps_max: f64,
    /// `mean_j |E_j|`.
    pub eps_avg: f64,
    /// Percentage of `|E_j| <= hit_tol`.
    pub n_eps: f64,
    /// `sqrt(sum_j |E_j|²)`, the residual 2-norm.
    pub norm2: f64,
}

/// Statistics of the residual vectors `residuals` (all zero for no residuals).
///
/// A NaN residual makes `eps_max`, `eps_avg` and `norm2` NaN and is not a hit: a NaN
/// must not look like a perfect fit (`f64::max` would drop it). Lengths and sums are
/// rescaled where squaring would overflow or underflow, so finite residuals give finite,
/// non-zero statistics at any magnitude (e.g. residuals of `1e200` or `1e-200`).
///
/// ```
/// use glam::DVec3;
/// use tri_spline::fit::error_stats;
/// let stats = error_stats(&[DVec3::new(3.0, 4.0, 0.0), DVec3::ZERO], 1.0);
/// assert_eq!((stats.eps_max, stats.eps_avg, stats.n_eps, stats.norm2), (5.0, 2.5, 50.0, 5.0));
/// assert!(error_stats(&[DVec3::NAN, DVec3::ONE], 1.0).eps_max.is_nan());
/// assert_eq!(error_stats(&[DVec3::splat(1e300)], 1.0).eps_max, 3f64.sqrt() * 1e300);
/// ```
pub fn error_stats(residuals: &[DVec3], hit_tol: f64) -> ErrorStats {
    let m = residuals.len().max(1) as f64;
    let (mut max, mut sum, mut sum2, mut hits) = (0.0f64, 0.0, 0.0, 0usize);
    let mut any_nan = false;
    for &e in residuals {
        let len = robust_length(e);
        any_nan |= len.is_nan();
        max = max.max(len);
        sum += len;
        sum2 += len * len;
        hits += usize::from(len <= hit_tol);
    }
    if any_nan {
        max = f64::NAN;
    }
    // Rare second passes, only where the plain sums left the f64 range: the mean is at
    // most the maximum, and the 2-norm at most sqrt(m) times it.
    let mut mean = sum / m;
    if mean.is_infinite() && max.is_finite() {
        mean = residuals.iter().map(|&e| robust_length(e) / m).sum();
    }
    let mut norm2 = sum2.sqrt();
    let squares_left_range = norm2.is_infinite() || (norm2 < MIN_SAFE_LENGTH && max > 0.0);
    if squares_left_range && max.is_finite() {
        norm2 = max * residuals.iter().map(|&e| (robust_length(e) / max).powi(2)).sum::<f64>().sqrt();
    }
    ErrorStats { eps_max: max, eps_avg: mean, n_eps: 100.0 * hits as f64 / m, norm2 }
}

/// Below this a length may have lost digits to underflowing squares (`2^-500`).
const MIN_SAFE_LENGTH: f64 = 3.054_936_363_499_605e-151;

/// `|v|`, rescaled by its largest coordinate when the plain formula's squares overflow
/// (finite `v` with an infinite length) or underflow (a tiny length): the same value,
/// bit for bit, for every `v` in between.
fn robust_length(v: DVec3) -> f64 {
    let plain = v.length();
    if (plain.is_infinite() || plain < MIN_SAFE_LENGTH) && v.is_finite() {
        let largest = v.abs().max_element();
        if largest > 0.0 {
            return largest * (v / largest).length();
        }
    }
    plain
}

/// When to stop and how to count hits.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct IterationOptions {
    /// Largest number of iterations (control nets evaluated), at least 1.
    pub max_iterations: usize,
    /// Stop as soon as `ε_avg` falls below this.
    pub tolerance: Option<f64>,
    /// A data point is "hit" when its error is at most this (for `N_ε`).
    pub hit_tol: f64,
}

/// The result of an iteration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IterationOutcome {
    /// The last control points.
    pub control: Vec<DVec3>,
    /// One record per iteration.
    pub records: Vec<IterationRecord>,
    /// Residual 2-norm per iteration (for monotonicity checks).
    pub residual_norms: Vec<f64>,
    /// Whether the tolerance was reached.
    pub reached_tolerance: bool,
}

/// A linear map between point sets, applied coordinate-wise (e.g. i-fold reverse Loop
/// from data points to control points).
pub trait LinearOperator: Sync {
    /// Number of input points.
    fn input_len(&self) -> usize;
    /// Number of output points.
    fn output_len(&self) -> usize;
    /// Applies the map.
    ///
    /// # Errors
    /// Whatever the underlying map reports.
    fn apply(&self, x: &[DVec3]) -> Result<Vec<DVec3>, SplineError>;
}

impl LinearOperator for SparseMatrix {
    fn input_len(&self) -> usize {
        self.cols()
    }
    fn output_len(&self) -> usize {
        self.rows()
    }
    fn apply(&self, x: &[DVec3]) -> Result<Vec<DVec3>, SplineError> {
        self.try_mul_vec(x)
    }
}

/// `second ∘ first`.
pub struct Composed<'a> {
    /// Applied first.
    pub first: &'a dyn LinearOperator,
    /// Applied to the result.
    pub second: &'a dyn LinearOperator,
}

impl LinearOperator for Composed<'_> {
    fn input_len(&self) -> usize {
        self.first.input_len()
    }
    fn output_len(&self) -> usize {
        self.second.output_len()
    }
    fn apply(&self, x: &[DVec3]) -> Result<Vec<DVec3>, SplineError> {
        self.second.apply(&self.first.apply(x)?)
    }
}

fn check_options(options: &IterationOptions) -> Result<(), SplineError> {
    if options.max_iterations == 0 {
        return Err(SplineError::BadOption { name: "iterations", value: "0".into(), reason: "at least 1" });
    }
    if !(options.hit_tol.is_finite() && options.hit_tol >= 0.0) {
        return Err(SplineError::BadOption {
            name: "hit_tol",
            value: options.hit_tol.to_string(),
            reason: "a finite non-negative distance",
        });
    }
    if let Some(t) = options.tolerance
        && !(t.is_finite() && t >= 0.0)
    {
        return Err(SplineError::BadOption {
            name: "tolerance",
            value: t.to_string(),
            reason: "a finite non-negative distance",
        });
    }
    Ok(())
}

/// What the linear problem's inputs are called in errors.
struct ProblemNames {
    /// The rows of the matrix (and the points on its left-hand side).
    rows: &'static str,
    /// A single such point, for [`SplineError::NonFinite`].
    point: &'static str,
    /// A row of the matrix with a non-finite entry.
    matrix_row: &'static str,
}

const DATA_NAMES: ProblemNames = ProblemNames {
    rows: "data points (rows of the collocation matrix)",
    point: "data point",
    matrix_row: "collocation matrix row",
};

/// Checks that `data` has one point per row of `n` and `control` one per column, and
/// that the three are finite (a NaN there would run through every iteration unnoticed).
fn check_problem(n: &SparseMatrix, data: &[DVec3], control: &[DVec3], names: &ProblemNames) -> Result<(), SplineError> {
    if data.len() != n.rows() {
        return Err(SplineError::Count { what: names.rows, expected: n.rows(), got: data.len() });
    }
    if control.len() != n.cols() {
        return Err(SplineError::Count { what: "initial control points", expected: n.cols(), got: control.len() });
    }
    if let Some(index) = data.iter().position(|p| !p.is_finite()) {
        return Err(SplineError::NonFinite { what: names.point, index });
    }
    if let Some(index) = control.iter().position(|p| !p.is_finite()) {
        return Err(SplineError::NonFinite { what: "initial control point", index });
    }
    if let Some(index) = n.first_non_finite_row() {
        return Err(SplineError::NonFinite { what: names.matrix_row, index });
    }
    Ok(())
}

fn residuals(n: &SparseMatrix, data: &[DVec3], control: &[DVec3]) -> Vec<DVec3> {
    let fitted = n.mul_vec(control);
    data.par_iter().zip(fitted).map(|(&d, s)| d - s).collect()
}

/// Most iteration records reserved before iterating.
const ITERATION_RESERVE: usize = 1024;

/// How a method's divergence is reported ([`SplineError::Diverged`]).
struct Divergence {
    method: &'static str,
    /// Why an update made a value non-finite, and what to do about it.
    hint: &'static str,
}

/// Shared loop: evaluate, check, record, stop, update.
///
/// The iterate and its residual are checked to be finite at every iteration: a step too
/// large overflows within a few iterations, and without the check NaN control points
/// would come back as a successful fit.
fn iterate(
    n: &SparseMatrix,
    data: &[DVec3],
    mut control: Vec<DVec3>,
    options: &IterationOptions,
    divergence: &Divergence,
    mut update: impl FnMut(&mut Vec<DVec3>, &[DVec3]) -> Result<(), SplineError>,
) -> Result<IterationOutcome, SplineError> {
    let start = Instant::now();
    // Grow with the iterations run: `max_iterations` is a cap (often huge, with a
    // tolerance to stop earlier), not a size to reserve up front.
    let reserve = options.max_iterations.min(ITERATION_RESERVE);
    let mut records = Vec::with_capacity(reserve);
    let mut norms = Vec::with_capacity(reserve);
    let mut reached = false;
    for k in 1..=options.max_iterations {
        let e = residuals(n, data, &control);
        let non_finite =
            control.par_iter().position_first(|p| !p.is_finite()).map(|index| ("control point", index)).or_else(|| {
                e.par_iter().position_first(|r| !r.is_finite()).map(|index| ("residual of data point", index))
            });
        if let Some((what, index)) = non_finite {
            // The first iterate is the (checked, finite) input: only N C itself can overflow.
            let hint = if k == 1 { "the input is so large that N C overflows; scale it down" } else { divergence.hint };
            return Err(SplineError::Diverged { method: divergence.method, iteration: k, what, index, hint });
        }
        let stats = error_stats(&e, options.hit_tol);
        records.push(IterationRecord {
            k,
            eps_max: stats.eps_max,
            eps_avg: stats.eps_avg,
            n_eps: stats.n_eps,
            seconds: start.elapsed().as_secs_f64(),
        });
        norms.push(stats.norm2);
        if options.tolerance.is_some_and(|t| stats.eps_avg < t) {
            reached = true;
            break;
        }
        if k == options.max_iterations {
            break;
        }
        update(&mut control, &e)?;
    }
    Ok(IterationOutcome { control, records, residual_norms: norms, reached_tolerance: reached })
}

/// LSPIA: `C ← C + μ Nᵀ (D - N C)` from `initial`.
///
/// # Errors
/// [`SplineError::Count`] / [`SplineError::NonFinite`] for inconsistent or non-finite
/// input (data, initial control points, entries of `n`), [`SplineError::BadOption`] for
/// bad options or a step `μ` outside `(0, ∞)`, [`SplineError::Diverged`] naming the
/// first iteration with a non-finite control point or residual: the step is far too
/// large (LSPIA is stable for `μ < 2/λ_max(NᵀN)`; [`default_lspia_step`] is safe).
///
/// ```
/// use glam::DVec3;
/// use tri_spline::SplineError;
/// use tri_spline::fit::{IterationOptions, default_lspia_step, lspia};
/// use tri_spline::linalg::SparseMatrix;
/// // Two control points, three data points: the ends and their midpoint.
/// let n = SparseMatrix::from_rows(2, vec![vec![(0, 1.0)], vec![(0, 0.5), (1, 0.5)], vec![(1, 1.0)]]);
/// let data = [DVec3::ZERO, DVec3::new(0.5, 0.1, 0.0), DVec3::X];
/// let options = IterationOptions { max_iterations: 50, tolerance: None, hit_tol: 1e-3 };
/// let fit = lspia(&n, &data, vec![DVec3::ZERO; 2], default_lspia_step(&n), &options)?;
/// assert!((fit.control[1] - DVec3::new(1.0, 0.0333, 0.0)).length() < 1e-3);
/// // A step far beyond 2/λ_max overflows within a few iterations: an error, not NaNs.
/// let diverged = lspia(&n, &data, vec![DVec3::ZERO; 2], 1e300, &options);
/// assert!(matches!(diverged, Err(SplineError::Diverged { method: "lspia", iteration: 3, .. })));
/// # Ok::<(), SplineError>(())
/// ```
pub fn lspia(
    n: &SparseMatrix,
    data: &[DVec3],
    initial: Vec<DVec3>,
    mu: f64,
    options: &IterationOptions,
) -> Result<IterationOutcome, SplineError> {
    check_options(options)?;
    check_problem(n, data, &initial, &DATA_NAMES)?;
    if !(mu.is_finite() && mu > 0.0) {
        return Err(SplineError::BadOption { name: "mu", value: mu.to_string(), reason: "a positive step" });
    }
    let nt = n.transpose();
    let divergence = Divergence {
        method: "lspia",
        hint: "the step μ is too large (LSPIA is stable for μ < 2/λ_max(NᵀN); default_lspia_step gives a safe step)",
    };
    iterate(n, data, initial, options, &divergence, |control, e| {
        let step = nt.mul_vec(e);
        control.par_iter_mut().zip(step).for_each(|(c, s)| *c += s * mu);
        Ok(())
    })
}

/// The default LSPIA step `1.5 / c`, `c >= λ_max(NᵀN)` ([`gram_lambda_max_bound`]).
///
/// Any `μ <= 2/λ_max` keeps the residual 2-norm monotone; `μ = 1/λ_max` removes the
/// top eigencomponent in one step but is slowest on the small eigenvalues, `μ → 2/λ_max`
/// is fastest there but barely damps the top one (it flips sign each step). On the
/// reference problems (Bézier degrees 3 to 24, B-patch degree 3) the factor 1.5 gave the
/// lowest `ε_avg` over the first ten iterations among 1, 1.5, 1.9 and 1.99.
///
/// ```
/// use tri_spline::fit::{default_lspia_step, lspia_spectrum};
/// use tri_spline::linalg::SparseMatrix;
/// let n = SparseMatrix::from_rows(2, vec![vec![(0, 1.0)], vec![(0, 0.5), (1, 0.5)], vec![(0, 0.2), (1, 0.8)]]);
/// let mu = default_lspia_step(&n);
/// let spectrum = lspia_spectrum(&n, mu)?;
/// // 1.5 / λ_max (the bound is tight here): inside the stable range (0, 2/λ_max).
/// assert!((mu * spectrum.lambda_max - 1.5).abs() < 1e-9);
/// assert!(spectrum.spectral_radius < 1.0);
/// # Ok::<(), tri_spline::SplineError>(())
/// ```
pub fn default_lspia_step(n: &SparseMatrix) -> f64 {
    1.5 / gram_lambda_max_bound(n, 50)
}

/// Classical PIA towards `targets` (one per control point) at the parameters whose
/// square collocation matrix is `n_targets`, reporting errors against all `data`
/// through `n`: `C ← C + w (T - N_T C)`, `C⁰ = initial`.
///
/// # Errors
/// As [`lspia`] (a weight outside `(0, ∞)` is [`SplineError::BadOption`]; divergence
/// means `ρ(I - w N_T) >= 1`, see [`pia_spectral_radius`]); [`SplineError::Count`] if
/// `n_targets` is not square of the control size; [`SplineError::NonFinite`] naming a
/// non-finite target.
///
/// ```
/// # use glam::{DVec2, DVec3};
/// # use tri_spline::index::multi_indices;
/// # use tri_spline::{DomainTriangle, SurfaceBasis};
/// // The quadratic Bézier basis at the six uniform domain points (square collocation).
/// let params: Vec<DVec2> = multi_indices(2).map(|[_, j, k]| DVec2::new(j as f64, k as f64) / 2.0).collect();
/// let n_t = SurfaceBasis::Bezier { degree: 2, domain: DomainTriangle::reference() }.collocation(&params)?;
/// use tri_spline::fit::{IterationOptions, pia};
/// // Interpolate a quadratic surface at the six points, starting from the data itself.
/// let data: Vec<DVec3> = params.iter().map(|u| DVec3::new(u.x, u.y, u.x * u.y)).collect();
/// let options = IterationOptions { max_iterations: 100, tolerance: Some(1e-12), hit_tol: 1e-9 };
/// let fit = pia(&n_t, &data, &n_t, &data, data.clone(), 1.0, &options)?;
/// // ρ(I - N_T) = 1 - 2!/2² = 1/2: the error halves at every step.
/// assert!(fit.reached_tolerance && fit.records.len() < 50);
/// assert!(pia(&n_t, &data, &n_t, &data, data.clone(), 0.0, &options).is_err());
/// # Ok::<(), tri_spline::SplineError>(())
/// ```
pub fn pia(
    n: &SparseMatrix,
    data: &[DVec3],
    n_targets: &SparseMatrix,
    targets: &[DVec3],
    initial: Vec<DVec3>,
    weight: f64,
    options: &IterationOptions,
) -> Result<IterationOutcome, SplineError> {
    check_options(options)?;
    check_problem(n, data, &initial, &DATA_NAMES)?;
    let target_names = ProblemNames {
        rows: "targets (rows of the target collocation matrix)",
        point: "target",
        matrix_row: "target collocation matrix row",
    };
    check_problem(n_targets, targets, &initial, &target_names)?;
    if !(weight.is_finite() && weight > 0.0) {
        return Err(SplineError::BadOption { name: "weight", value: weight.to_string(), reason: "a positive weight" });
    }
    let divergence = Divergence {
        method: "pia",
        hint: "the weight w is too large (PIA converges iff ρ(I - w N_T) < 1; pia_spectral_radius computes it)",
    };
    iterate(n, data, initial, options, &divergence, |control, _| {
        let fitted = n_targets.mul_vec(control);
        control.par_iter_mut().zip(targets.par_iter().zip(fitted)).for_each(|(c, (&t, f))| *c += (t - f) * weight);
        Ok(())
    })
}

/// The seed loop: `P* := D`; repeat `C := R(P*)`, `E := D - N C`, `P* := P* + E`.
///
/// # Errors
/// As [`lspia`] (divergence means `ρ(I - R N) >= 1`, see [`seed_spectral_radius`]);
/// [`SplineError::Count`] if `r` does not map data to control points (also when its
/// result has the wrong length); errors of `r`.
///
/// ```
/// # use glam::{DVec2, DVec3};
/// # use tri_spline::index::multi_indices;
/// # use tri_spline::linalg::SparseMatrix;
/// # use tri_spline::{DomainTriangle, SurfaceBasis};
/// // A linear patch (3 control points) against 6 data points at the degree-2 domain points;
/// // R picks the data at the three corners (positions 0, 2, 5).
/// let params: Vec<DVec2> = multi_indices(2).map(|[_, j, k]| DVec2::new(j as f64, k as f64) / 2.0).collect();
/// let n = SurfaceBasis::Bezier { degree: 1, domain: DomainTriangle::reference() }.collocation(&params)?;
/// let r = SparseMatrix::from_rows(6, vec![vec![(0, 1.0)], vec![(2, 1.0)], vec![(5, 1.0)]]);
/// use tri_spline::fit::{IterationOptions, seed_iteration};
/// // Data on z = x y; here R N = I, so the loop stays at C = R D, the corner data:
/// // the oblique projection (R N)^-1 R D, neither interpolation nor least squares.
/// let data: Vec<DVec3> = params.iter().map(|u| DVec3::new(u.x, u.y, u.x * u.y)).collect();
/// let options = IterationOptions { max_iterations: 3, tolerance: None, hit_tol: 1e-9 };
/// let fit = seed_iteration(&n, &data, &r, &options)?;
/// assert_eq!(fit.control, vec![data[0], data[2], data[5]]);
/// assert!(fit.records.iter().all(|record| record.eps_max == 0.25));
/// // R must map the data (6 points) to the control points (3).
/// assert!(seed_iteration(&n, &data, &r.transpose(), &options).is_err());
/// # Ok::<(), tri_spline::SplineError>(())
/// ```
pub fn seed_iteration(
    n: &SparseMatrix,
    data: &[DVec3],
    r: &dyn LinearOperator,
    options: &IterationOptions,
) -> Result<IterationOutcome, SplineError> {
    check_options(options)?;
    if r.input_len() != data.len() || r.output_len() != n.cols() {
        return Err(SplineError::Count {
            what: "reverse map (data -> control points)",
            expected: n.cols(),
            got: r.output_len(),
        });
    }
    let mut shifted = data.to_vec();
    let initial = r.apply(&shifted)?;
    check_problem(n, data, &initial, &DATA_NAMES)?;
    let divergence = Divergence {
        method: "seed",
        hint: "the seed loop does not converge here (it needs ρ(I - R N) < 1; seed_spectral_radius computes it)",
    };
    iterate(n, data, initial, options, &divergence, |control, e| {
        shifted.par_iter_mut().zip(e).for_each(|(p, &d)| *p += d);
        let next = r.apply(&shifted)?;
        // A caller's operator may break its own `output_len`.
        if next.len() != control.len() {
            return Err(SplineError::Count {
                what: "reverse map result (control points)",
                expected: control.len(),
                got: next.len(),
            });
        }
        *control = next;
        Ok(())
    })
}

/// Spectrum summary of LSPIA's iteration matrix `I - μ NᵀN`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LspiaSpectrum {
    /// Smallest eigenvalue of `NᵀN`.
    pub lambda_min: f64,
    /// Largest eigenvalue of `NᵀN`.
    pub lambda_max: f64,
    /// `ρ(I - μ NᵀN) = max(|1 - μ λ_min|, |1 - μ λ_max|)`.
    pub spectral_radius: f64,
}

/// The spectrum of `NᵀN` and the spectral radius of `I - μ NᵀN` (dense, `O(m_c³)`).
///
/// # Errors
/// [`SplineError::BadOption`] if `N` has no columns (no control points, no spectrum) or
/// `μ` is not finite (the radius would be NaN or infinite); [`SplineError::NonFinite`]
/// for a row of `N` with a non-finite entry; [`SplineError::Singular`] if the eigenvalue
/// computation fails.
///
/// ```
/// use tri_spline::SplineError;
/// use tri_spline::fit::lspia_spectrum;
/// use tri_spline::linalg::SparseMatrix;
/// // NᵀN = [[1.25, 0.25], [0.25, 1.25]] has the eigenvalues 1 and 1.5.
/// let n = SparseMatrix::from_rows(2, vec![vec![(0, 1.0)], vec![(0, 0.5), (1, 0.5)], vec![(1, 1.0)]]);
/// let spectrum = lspia_spectrum(&n, 1.0)?;
/// assert!((spectrum.lambda_min - 1.0).abs() < 1e-14 && (spectrum.lambda_max - 1.5).abs() < 1e-14);
/// // ρ(I - NᵀN) = max(|1 - 1|, |1 - 1.5|).
/// assert!((spectrum.spectral_radius - 0.5).abs() < 1e-14);
/// assert!(matches!(lspia_spectrum(&n, f64::NAN), Err(SplineError::BadOption { name: "mu", .. })));
/// # Ok::<(), SplineError>(())
/// ```
pub fn lspia_spectrum(n: &SparseMatrix, mu: f64) -> Result<LspiaSpectrum, SplineError> {
    if !mu.is_finite() {
        return Err(SplineError::BadOption { name: "mu", value: mu.to_string(), reason: "a finite step" });
    }
    if let Some(index) = n.first_non_finite_row() {
        return Err(SplineError::NonFinite { what: "collocation matrix row", index });
    }
    if n.cols() == 0 {
        return Err(SplineError::BadOption {
            name: "collocation matrix",
            value: format!("{} x 0", n.rows()),
            reason: "needs at least one control point (column)",
        });
    }
    // Dense product: N is often dense (Bézier rows) and m_c is small enough here.
    let dense = n.to_dense();
    let gram = dense.transpose() * &dense;
    let values = symmetric_eigenvalues(&gram)?;
    let (lambda_min, lambda_max) = (values[0], *values.last().expect("internal: non-empty"));
    let spectral_radius = (1.0 - mu * lambda_min).abs().max((1.0 - mu * lambda_max).abs());
    Ok(LspiaSpectrum { lambda_min, lambda_max, spectral_radius })
}

/// `ρ(I - w N_T)` for a square collocation matrix (dense, `O(m_c³)`).
///
/// # Errors
/// [`SplineError::Count`] if `n_targets` is not square; [`SplineError::BadOption`] if the
/// weight is not finite; [`SplineError::NonFinite`] for a row with a non-finite entry;
/// [`SplineError::Singular`] if the eigenvalue computation fails.
///
/// ```
/// # use glam::{DVec2, DVec3};
/// # use tri_spline::index::multi_indices;
/// # use tri_spline::{DomainTriangle, SurfaceBasis};
/// // The quadratic Bézier basis at the six uniform domain points (square collocation).
/// let params: Vec<DVec2> = multi_indices(2).map(|[_, j, k]| DVec2::new(j as f64, k as f64) / 2.0).collect();
/// let n_t = SurfaceBasis::Bezier { degree: 2, domain: DomainTriangle::reference() }.collocation(&params)?;
/// use tri_spline::fit::pia_spectral_radius;
/// // Chen & Wang: ρ(I - N_T) = 1 - n!/n^n for degree n at the uniform points.
/// assert!((pia_spectral_radius(&n_t, 1.0)? - 0.5).abs() < 1e-14);
/// // N_T has the eigenvalues 1, 1, 1, 1/2, 1/2, 1/2: a weight of 2.5 overshoots (|1 - 2.5| > 1).
/// assert!(pia_spectral_radius(&n_t, 2.5)? > 1.0);
/// # Ok::<(), tri_spline::SplineError>(())
/// ```
pub fn pia_spectral_radius(n_targets: &SparseMatrix, weight: f64) -> Result<f64, SplineError> {
    if !weight.is_finite() {
        return Err(SplineError::BadOption { name: "weight", value: weight.to_string(), reason: "a finite weight" });
    }
    if let Some(index) = n_targets.first_non_finite_row() {
        return Err(SplineError::NonFinite { what: "target collocation matrix row", index });
    }
    if n_targets.rows() != n_targets.cols() {
        return Err(SplineError::Count {
            what: "rows of the square PIA matrix",
            expected: n_targets.cols(),
            got: n_targets.rows(),
        });
    }
    let mut a = n_targets.to_dense() * faer::Scale(-weight);
    for i in 0..a.nrows() {
        a[(i, i)] += 1.0;
    }
    spectral_radius(&a)
}

/// `R N` as a dense `m_c × m_c` matrix: `R` applied to the columns of `N`, three at a
/// time (as the coordinates of point sets).
///
/// # Errors
/// Errors of `r`.
///
/// ```
/// # use glam::{DVec2, DVec3};
/// # use tri_spline::index::multi_indices;
/// # use tri_spline::linalg::SparseMatrix;
/// # use tri_spline::{DomainTriangle, SurfaceBasis};
/// // A linear patch (3 control points) against 6 data points at the degree-2 domain points;
/// // R picks the data at the three corners (positions 0, 2, 5).
/// let params: Vec<DVec2> = multi_indices(2).map(|[_, j, k]| DVec2::new(j as f64, k as f64) / 2.0).collect();
/// let n = SurfaceBasis::Bezier { degree: 1, domain: DomainTriangle::reference() }.collocation(&params)?;
/// let r = SparseMatrix::from_rows(6, vec![vec![(0, 1.0)], vec![(2, 1.0)], vec![(5, 1.0)]]);
/// use tri_spline::fit::weighted_collocation;
/// // The corners' rows of N are those of the identity: R N = I.
/// let rn = weighted_collocation(&n, &r)?;
/// assert_eq!((rn.nrows(), rn.ncols()), (3, 3));
/// assert!((0..3).all(|i| (0..3).all(|j| rn[(i, j)] == if i == j { 1.0 } else { 0.0 })));
/// # Ok::<(), tri_spline::SplineError>(())
/// ```
pub fn weighted_collocation(n: &SparseMatrix, r: &dyn LinearOperator) -> Result<Mat<f64>, SplineError> {
    let k = n.cols();
    let dense = n.to_dense();
    let mut out = Mat::<f64>::zeros(k, k);
    for first in (0..k).step_by(3) {
        let cols: Vec<usize> = (first..(first + 3).min(k)).collect();
        let packed: Vec<DVec3> = (0..n.rows())
            .map(|i| {
                let mut p = DVec3::ZERO;
                for (slot, &c) in cols.iter().enumerate() {
                    p[slot] = dense[(i, c)];
                }
                p
            })
            .collect();
        let mapped = r.apply(&packed)?;
        for (row, p) in mapped.iter().enumerate() {
            for (slot, &c) in cols.iter().enumerate() {
                out[(row, c)] = p[slot];
            }
        }
    }
    Ok(out)
}

/// `ρ(I - R N)`, the spectral radius of the seed loop's iteration matrix.
///
/// # Errors
/// As [`weighted_collocation`]; [`SplineError::Singular`] if the eigenvalues fail.
///
/// ```
/// # use glam::{DVec2, DVec3};
/// # use tri_spline::index::multi_indices;
/// # use tri_spline::linalg::SparseMatrix;
/// # use tri_spline::{DomainTriangle, SurfaceBasis};
/// // A linear patch (3 control points) against 6 data points at the degree-2 domain points;
/// // R picks the data at the three corners (positions 0, 2, 5).
/// let params: Vec<DVec2> = multi_indices(2).map(|[_, j, k]| DVec2::new(j as f64, k as f64) / 2.0).collect();
/// let n = SurfaceBasis::Bezier { degree: 1, domain: DomainTriangle::reference() }.collocation(&params)?;
/// let r = SparseMatrix::from_rows(6, vec![vec![(0, 1.0)], vec![(2, 1.0)], vec![(5, 1.0)]]);
/// use tri_spline::fit::seed_spectral_radius;
/// // R N = I: the loop reaches its fixed point at once.
/// assert!(seed_spectral_radius(&n, &r)?.abs() < 1e-15);
/// // Half of the corner data: I - R N = I / 2.
/// let half = SparseMatrix::from_rows(6, vec![vec![(0, 0.5)], vec![(2, 0.5)], vec![(5, 0.5)]]);
/// assert!((seed_spectral_radius(&n, &half)? - 0.5).abs() < 1e-15);
/// # Ok::<(), tri_spline::SplineError>(())
/// ```
pub fn seed_spectral_radius(n: &SparseMatrix, r: &dyn LinearOperator) -> Result<f64, SplineError> {
    let rn = weighted_collocation(n, r)?;
    let mut a = rn * faer::Scale(-1.0);
    for i in 0..a.nrows() {
        a[(i, i)] += 1.0;
    }
    spectral_radius(&a)
}

/// The eigenvalues of a dense matrix (re-exported helper for reports and tests).
///
/// # Errors
/// [`SplineError::Singular`] if the computation fails.
///
/// ```
/// use tri_spline::fit::matrix_eigenvalues;
/// // Upper triangular: the eigenvalues are the diagonal, all real.
/// let mut values = matrix_eigenvalues(&faer::mat![[2.0, 1.0], [0.0, 3.0]])?;
/// values.sort_by(|a, b| a.0.total_cmp(&b.0));
/// assert!((values[0].0 - 2.0).abs() < 1e-14 && (values[1].0 - 3.0).abs() < 1e-14);
/// assert!(values.iter().all(|v| v.1 == 0.0));
/// # Ok::<(), tri_spline::SplineError>(())
/// ```
pub fn matrix_eigenvalues(a: &Mat<f64>) -> Result<Vec<(f64, f64)>, SplineError> {
    eigenvalues(a)
}

/// The direct least-squares fit of the same control net (the baseline).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LeastSquaresReport {
    /// Errors of the least-squares fit at the data.
    pub stats: ErrorStats,
    /// Seconds for building the dense matrix, factorising and solving.
    pub seconds: f64,
    /// The solver used.
    pub solver: String,
    /// The least-squares control points.
    pub control: Vec<DVec3>,
}

/// Solves `min ‖N C - D‖` by dense Householder QR of `N` (conditioning of `N`, not of
/// `NᵀN`) and reports its errors and time.
///
/// # Errors
/// [`SplineError::Singular`] if `N` is rank deficient or has fewer rows than columns.
///
/// ```
/// use glam::DVec3;
/// use tri_spline::fit::least_squares_fit;
/// use tri_spline::linalg::SparseMatrix;
/// // A segment sampled at t = 0, 1/2, 1 with a bump in the middle: the fit spreads the bump.
/// let n = SparseMatrix::from_rows(2, vec![vec![(0, 1.0)], vec![(0, 0.5), (1, 0.5)], vec![(1, 1.0)]]);
/// let data = [DVec3::ZERO, DVec3::new(0.5, 0.3, 0.0), DVec3::X];
/// let fit = least_squares_fit(&n, &data, 0.15)?;
/// assert!((fit.control[0] - DVec3::new(0.0, 0.1, 0.0)).length() < 1e-14);
/// assert!((fit.stats.eps_max - 0.2).abs() < 1e-14 && fit.stats.n_eps < 100.0);
/// // Fewer data points than control points.
/// assert!(least_squares_fit(&n.transpose(), &data[..2], 0.15).is_err());
/// # Ok::<(), tri_spline::SplineError>(())
/// ```
pub fn least_squares_fit(n: &SparseMatrix, data: &[DVec3], hit_tol: f64) -> Result<LeastSquaresReport, SplineError> {
    let start = Instant::now();
    let control = least_squares(n, data)?;
    let seconds = start.elapsed().as_secs_f64();
    let stats = error_stats(&residuals(n, data, &control), hit_tol);
    Ok(LeastSquaresReport { stats, seconds, solver: "dense Householder QR (faer, sequential)".into(), control })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::index::multi_indices;
    use crate::{DomainTriangle, SurfaceBasis};
    use glam::DVec2;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn domain_points(n: usize, domain: &DomainTriangle) -> Vec<DVec2> {
        multi_indices(n)
            .map(|[i, j, k]| domain.point([i as f64 / n as f64, j as f64 / n as f64, k as f64 / n as f64]))
            .collect()
    }

    fn random_points(count: usize, seed: u64) -> Vec<DVec3> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..count)
            .map(|_| DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)))
            .collect()
    }

    fn options(k: usize) -> IterationOptions {
        IterationOptions { max_iterations: k, tolerance: None, hit_tol: 1e-3 }
    }

    #[test]
    fn pia_errors_follow_the_iteration_matrix_exactly() {
        // E^k = (I - w N)^k E^0 (§12.3), to rounding.
        let domain = DomainTriangle::equilateral();
        let n_deg = 3;
        let basis = SurfaceBasis::Bezier { degree: n_deg, domain };
        let params = domain_points(n_deg, &domain);
        let n = basis.collocation(&params).unwrap();
        let targets = random_points(params.len(), 1);
        let w = 0.9;
        let out = pia(&n, &targets, &n, &targets, targets.clone(), w, &options(8)).unwrap();
        let mut step = n.to_dense() * faer::Scale(-w);
        for i in 0..step.nrows() {
            step[(i, i)] += 1.0;
        }
        let mut e = Mat::<f64>::from_fn(targets.len(), 3, |i, j| {
            let s: DVec3 = n.row(i).0.iter().zip(n.row(i).1).map(|(&c, &v)| targets[c as usize] * v).sum();
            (targets[i] - s)[j]
        });
        for (record, &norm) in out.records.iter().zip(&out.residual_norms) {
            // Every data point's error length, hence max, mean and 2-norm, as predicted.
            let predicted: Vec<f64> =
                (0..targets.len()).map(|i| DVec3::new(e[(i, 0)], e[(i, 1)], e[(i, 2)]).length()).collect();
            let predicted_max = predicted.iter().copied().fold(0.0, f64::max);
            let predicted_avg = predicted.iter().sum::<f64>() / predicted.len() as f64;
            let predicted_norm = predicted.iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!((predicted_max - record.eps_max).abs() < 1e-14, "k = {}", record.k);
            assert!((predicted_avg - record.eps_avg).abs() < 1e-14, "k = {}", record.k);
            assert!((predicted_norm - norm).abs() < 1e-13, "k = {}", record.k);
            e = &step * &e;
        }
    }

    #[test]
    fn pia_on_uniform_bezier_converges_at_rate_one_minus_n_factorial_over_n_to_the_n() {
        let domain = DomainTriangle::equilateral();
        for (degree, rate) in [(2usize, 0.5), (3, 1.0 - 6.0 / 27.0), (4, 1.0 - 24.0 / 256.0)] {
            let basis = SurfaceBasis::Bezier { degree, domain };
            let n = basis.collocation(&domain_points(degree, &domain)).unwrap();
            // The computed spectral radius is the closed form.
            let rho = pia_spectral_radius(&n, 1.0).unwrap();
            assert!((rho - rate).abs() < 1e-12, "n = {degree}: {rho} vs {rate}");
            // The measured error ratio tends to it (measured while the error is still far
            // above rounding: about 1e-6 of its start).
            let targets = random_points(n.rows(), degree as u64);
            let steps = (1e-6f64.ln() / rate.ln()).ceil() as usize;
            let out = pia(&n, &targets, &n, &targets, targets.clone(), 1.0, &options(steps)).unwrap();
            let norms = &out.residual_norms;
            let ratio = norms[norms.len() - 1] / norms[norms.len() - 2];
            assert!((ratio - rate).abs() < 1e-6, "n = {degree}: measured {ratio} vs {rate}");
        }
    }

    #[test]
    fn lspia_residual_norm_never_increases_and_reaches_least_squares() {
        let domain = DomainTriangle::equilateral();
        let basis = SurfaceBasis::Bezier { degree: 3, domain };
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let params: Vec<DVec2> = (0..80)
            .map(|_| {
                let (a, b): (f64, f64) = (rng.random(), rng.random());
                let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                domain.point([1.0 - a - b, a, b])
            })
            .collect();
        let n = basis.collocation(&params).unwrap();
        let data = random_points(80, 6);
        let mu = default_lspia_step(&n);
        let spectrum = lspia_spectrum(&n, mu).unwrap();
        assert!(mu * spectrum.lambda_max <= 1.5 * (1.0 + 1e-12), "the step bound is an upper bound");
        assert!(spectrum.spectral_radius < 1.0);
        let out = lspia(&n, &data, vec![DVec3::ZERO; n.cols()], mu, &options(400)).unwrap();
        for pair in out.residual_norms.windows(2) {
            assert!(pair[1] <= pair[0] * (1.0 + 1e-15), "{} > {}", pair[1], pair[0]);
        }
        let ls = least_squares_fit(&n, &data, 1e-3).unwrap();
        let last = *out.residual_norms.last().unwrap();
        assert!((last - ls.stats.norm2) / ls.stats.norm2 < 1e-6, "{last} vs {}", ls.stats.norm2);
        // Even the optimal-looking larger step 2/λ_max keeps the norm monotone.
        let out = lspia(&n, &data, vec![DVec3::ZERO; n.cols()], 2.0 / spectrum.lambda_max, &options(50)).unwrap();
        for pair in out.residual_norms.windows(2) {
            assert!(pair[1] <= pair[0] * (1.0 + 1e-12));
        }
    }

    #[test]
    fn seed_loop_is_pia_with_weighting_matrix_r() {
        // With R = selection of the data at the domain points, the seed loop equals
        // C <- C + R (D - N C); its radius is rho(I - R N) and the residual at the fixed
        // point is the oblique projection's.
        let domain = DomainTriangle::equilateral();
        let (deg, fine) = (2usize, 4usize);
        let basis = SurfaceBasis::Bezier { degree: deg, domain };
        let params = domain_points(fine, &domain);
        let n = basis.collocation(&params).unwrap();
        // Control point (j, k) sits at fine grid point (2j, 2k).
        let select = SparseMatrix::from_rows(
            params.len(),
            multi_indices(deg).map(|[_, j, k]| vec![(crate::index::tri_index(fine, 2 * j, 2 * k), 1.0)]).collect(),
        );
        let data = random_points(params.len(), 9);
        let out = seed_iteration(&n, &data, &select, &options(60)).unwrap();
        let rho = seed_spectral_radius(&n, &select).unwrap();
        assert!((rho - 0.5).abs() < 1e-12, "R N is the square uniform collocation: {rho}");
        // Same iterates as PIA on the selected data.
        let sub = n.clone().transpose().transpose();
        let targets = select.mul_vec(&data);
        let n_sub = select.mul(&sub);
        let pia_out = pia(&n, &data, &n_sub, &targets, targets.clone(), 1.0, &options(60)).unwrap();
        for (a, b) in out.records.iter().zip(&pia_out.records) {
            assert!((a.eps_avg - b.eps_avg).abs() < 1e-13);
        }
        assert!(matches!(seed_iteration(&n, &data[1..], &select, &options(3)), Err(SplineError::Count { .. })));
    }

    #[test]
    fn bad_options_are_rejected() {
        let domain = DomainTriangle::equilateral();
        let n = SurfaceBasis::Bezier { degree: 1, domain }.collocation(&domain_points(1, &domain)).unwrap();
        let d = random_points(3, 1);
        assert!(lspia(&n, &d, d.clone(), 1.0, &options(0)).is_err());
        assert!(lspia(&n, &d, d.clone(), -1.0, &options(3)).is_err());
        assert!(lspia(&n, &d, d[..2].to_vec(), 1.0, &options(3)).is_err());
        let bad = IterationOptions { max_iterations: 3, tolerance: Some(f64::NAN), hit_tol: 0.1 };
        assert!(lspia(&n, &d, d.clone(), 1.0, &bad).is_err());
        let mut nan = d.clone();
        nan[1].y = f64::INFINITY;
        assert!(matches!(lspia(&n, &nan, d.clone(), 1.0, &options(3)), Err(SplineError::NonFinite { index: 1, .. })));
        // Tolerance stops early.
        let stop = IterationOptions { max_iterations: 10, tolerance: Some(1e-9), hit_tol: 0.1 };
        let out = pia(&n, &d, &n, &d, d.clone(), 1.0, &stop).unwrap();
        assert!(out.reached_tolerance && out.records.len() == 1);
    }

    #[test]
    fn huge_iteration_cap_is_not_preallocated() {
        // Used to panic with "capacity overflow" (and abort for 1e8) before iterating.
        let n = SparseMatrix::identity(3).unwrap();
        let d = vec![DVec3::ONE; 3];
        for max_iterations in [usize::MAX, 100_000_000] {
            let stop = IterationOptions { max_iterations, tolerance: Some(1.0), hit_tol: 0.1 };
            let out = lspia(&n, &d, vec![DVec3::ZERO; 3], 0.5, &stop).unwrap();
            assert_eq!(out.records.len(), 2);
            assert!(out.records.capacity() <= ITERATION_RESERVE);
            let out = pia(&n, &d, &n, &d, vec![DVec3::ZERO; 3], 0.5, &stop).unwrap();
            assert!(out.reached_tolerance);
        }
    }

    /// A finite but far too large step used to return `Ok` with NaN control points (and
    /// `eps_max = 0`, as `f64::max` drops NaN). Now the first non-finite iterate is an
    /// error naming the method and the iteration.
    #[test]
    fn a_step_far_too_large_is_a_divergence_error_not_nan() {
        let domain = DomainTriangle::equilateral();
        let n = SurfaceBasis::Bezier { degree: 2, domain }.collocation(&domain_points(4, &domain)).unwrap();
        let data = random_points(n.rows(), 3);
        let zero = vec![DVec3::ZERO; n.cols()];
        let lspia_out = lspia(&n, &data, zero.clone(), 1e300, &options(20));
        assert!(
            matches!(
                lspia_out,
                Err(SplineError::Diverged { method: "lspia", iteration: 3, what: "control point", .. })
            ),
            "{lspia_out:?}"
        );
        let message = lspia_out.unwrap_err().to_string();
        assert!(message.contains("2/λ_max(NᵀN)") && message.contains("default_lspia_step"), "{message}");
        // PIA and the seed loop share the check (here R scales by 1e200: ρ(I - R N) is huge).
        let targets = &data[..n.cols()];
        let n_targets = SparseMatrix::from_rows(n.cols(), (0..n.cols()).map(|i| row_of(&n, i)).collect());
        let pia_out = pia(&n, &data, &n_targets, targets, zero, 1e300, &options(20));
        assert!(matches!(pia_out, Err(SplineError::Diverged { method: "pia", iteration: 3, .. })), "{pia_out:?}");
        let amplify = SparseMatrix::from_rows(n.rows(), (0..n.cols()).map(|i| vec![(i, 1e200)]).collect());
        let seed_out = seed_iteration(&n, &data, &amplify, &options(20));
        assert!(matches!(seed_out, Err(SplineError::Diverged { method: "seed", .. })), "{seed_out:?}");
        // Data so large that N C overflows at once is reported at iteration 1, as such.
        let n_sum = SparseMatrix::from_rows(2, vec![vec![(0, 1.0), (1, 1.0)]]);
        let huge = vec![DVec3::splat(f64::MAX); 2];
        let out = lspia(&n_sum, &[DVec3::ZERO], huge, 0.1, &options(3));
        assert!(
            matches!(out, Err(SplineError::Diverged { iteration: 1, what: "residual of data point", index: 0, hint, .. }) if hint.contains("scale it down")),
            "{out:?}"
        );
    }

    fn row_of(n: &SparseMatrix, i: usize) -> Vec<(usize, f64)> {
        let (cols, vals) = n.row(i);
        cols.iter().zip(vals).map(|(&c, &v)| (c as usize, v)).collect()
    }

    /// NaN in the initial control net (or a target, or a matrix entry) used to run
    /// through every iteration and come back as `Ok` with NaN control points.
    #[test]
    fn non_finite_initial_nets_targets_and_matrices_are_rejected() {
        let n = SparseMatrix::from_rows(2, vec![vec![(0, 0.5), (1, 0.5)], vec![(0, 1.0)], vec![(1, 1.0)]]);
        let data = [DVec3::ONE, DVec3::X, DVec3::Y];
        let nan_initial = vec![DVec3::ZERO, DVec3::new(0.0, f64::NAN, 0.0)];
        let expected = SplineError::NonFinite { what: "initial control point", index: 1 };
        assert_eq!(lspia(&n, &data, nan_initial.clone(), 0.5, &options(5)), Err(expected.clone()));
        let square = SparseMatrix::identity(2).unwrap();
        assert_eq!(pia(&n, &data, &square, &data[1..], nan_initial, 0.5, &options(5)), Err(expected));
        let nan_target = [DVec3::X, DVec3::INFINITY];
        assert_eq!(
            pia(&n, &data, &square, &nan_target, vec![DVec3::ZERO; 2], 0.5, &options(5)),
            Err(SplineError::NonFinite { what: "target", index: 1 })
        );
        let nan_matrix = SparseMatrix::from_rows(2, vec![vec![(0, 1.0)], vec![(0, 1.0)], vec![(1, f64::NAN)]]);
        assert_eq!(
            lspia(&nan_matrix, &data, vec![DVec3::ZERO; 2], 0.5, &options(5)),
            Err(SplineError::NonFinite { what: "collocation matrix row", index: 2 })
        );
        // The seed loop's initial net is R D: a NaN entry of R is caught there.
        let nan_r = SparseMatrix::from_rows(3, vec![vec![(0, f64::NAN)], vec![(1, 1.0)]]);
        assert_eq!(
            seed_iteration(&n, &data, &nan_r, &options(5)),
            Err(SplineError::NonFinite { what: "initial control point", index: 0 })
        );
        // The spectra refuse what would make their radius NaN.
        assert!(matches!(lspia_spectrum(&n, f64::NAN), Err(SplineError::BadOption { name: "mu", .. })));
        assert!(matches!(pia_spectral_radius(&square, f64::INFINITY), Err(SplineError::BadOption { .. })));
        assert!(matches!(lspia_spectrum(&nan_matrix, 1.0), Err(SplineError::NonFinite { index: 2, .. })));
    }

    /// `error_stats(&[NaN], _)` reported `eps_max = 0`, a perfect fit; finite residuals
    /// beyond `1e154` (or below `1e-154`) had infinite (or zero) statistics.
    #[test]
    fn error_stats_propagate_nan_and_keep_extreme_magnitudes() {
        let nan = error_stats(&[DVec3::new(f64::NAN, 0.0, 0.0)], 1.0);
        assert!(nan.eps_max.is_nan() && nan.eps_avg.is_nan() && nan.norm2.is_nan());
        assert_eq!(nan.n_eps, 0.0);
        let mixed = error_stats(&[DVec3::X, DVec3::NAN, DVec3::Y], 1.0);
        assert!(mixed.eps_max.is_nan(), "NaN wins wherever it is: {mixed:?}");
        assert!((mixed.n_eps - 200.0 / 3.0).abs() < 1e-12);
        for scale in [1e300, 1e-300, f64::MAX / 2.0] {
            let residuals = [DVec3::new(3.0, 4.0, 0.0) * (scale / 5.0), DVec3::new(0.0, scale, 0.0)];
            let stats = error_stats(&residuals, 0.0);
            assert!((stats.eps_max / scale - 1.0).abs() < 1e-15, "{scale:e}: {stats:?}");
            assert!((stats.eps_avg / scale - 1.0).abs() < 1e-15, "{scale:e}: {stats:?}");
            assert!((stats.norm2 / scale - 2f64.sqrt()).abs() < 1e-15, "{scale:e}: {stats:?}");
        }
        // Unchanged to the bit in the ordinary range.
        let plain = [DVec3::new(0.1, -0.2, 0.3), DVec3::new(1e-3, 2e-3, 0.0)];
        let stats = error_stats(&plain, 0.01);
        assert_eq!(stats.eps_max, plain[0].length());
        assert_eq!(stats.norm2, (plain[0].length_squared() + plain[1].length_squared()).sqrt());
    }

    /// A sparse matrix used as an operator with a vector of the wrong length panicked in
    /// `mul_vec`; through `apply` it is an error.
    #[test]
    fn operators_report_a_wrong_input_length() {
        let r = SparseMatrix::identity(3).unwrap();
        assert_eq!(
            LinearOperator::apply(&r, &[DVec3::ZERO; 2]),
            Err(SplineError::Count { what: "vector entries (columns of the matrix)", expected: 3, got: 2 })
        );
    }

    #[test]
    fn mismatched_or_empty_matrices_are_errors() {
        // Used to index out of bounds: data shorter than the rows, and an empty spectrum.
        let n = SparseMatrix::identity(3).unwrap();
        assert!(matches!(
            least_squares_fit(&n, &[DVec3::ZERO; 2], 0.1),
            Err(SplineError::Count { expected: 3, got: 2, .. })
        ));
        assert!(matches!(lspia_spectrum(&SparseMatrix::from_rows(0, vec![]), 1.0), Err(SplineError::BadOption { .. })));
        assert!(matches!(
            lspia_spectrum(&SparseMatrix::from_rows(0, vec![vec![]; 2]), 1.0),
            Err(SplineError::BadOption { .. })
        ));
    }
}
