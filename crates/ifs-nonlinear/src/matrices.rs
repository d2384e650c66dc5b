//! Subdivision matrices (ALGORITHMS.md §13, §15.1, blossoms §9) and their contractivity
//! on the difference space.
//!
//! A [`SubdivisionRule`] holds K square m×m matrices `S_1 … S_K` whose rows sum to 1: the
//! control points of sub-piece i are `S_i · P` (P = the m control points as rows). The
//! same matrices, acting on barycentric row vectors `b ↦ b · S_i`, are the maps of the IFS
//! whose attractor is the curve or patch.
//!
//! Control-point orders:
//! * Bézier curve of degree n: `P_0 … P_n`.
//! * Tensor-product patch of degrees (n_u, n_v): `P_{i j}` at index `i (n_v + 1) + j`, i along u.
//! * Triangular Bézier patch of degree n: `b_β`, |β| = n, listed by β0 descending, then
//!   β1 descending (first `(n,0,0)`, then `(n-1,1,0)`, `(n-1,0,1)`, …); see [`triangle_multi_indices`].

use std::borrow::Cow;

use nalgebra::{ComplexField, DMatrix};
use num_complex::Complex64;

use crate::error::{IfsError, Result, check_finite};

/// Tolerance on row sums: `|sum - 1| <= ROW_SUM_TOLERANCE * max(1, sum of |entries|)`.
pub const ROW_SUM_TOLERANCE: f64 = 1e-12;

/// K square subdivision matrices of one size m, rows summing to 1, entries real (`f64`)
/// or complex ([`Complex64`], Goldman's complex-parameter schemes).
#[derive(Debug, Clone, PartialEq)]
pub struct SubdivisionRule<T: ComplexField<RealField = f64> = f64> {
    matrices: Vec<DMatrix<T>>,
}

impl<T: ComplexField<RealField = f64>> SubdivisionRule<T> {
    /// Validates and wraps K square matrices of one size m.
    ///
    /// # Errors
    /// [`IfsError::BadMatrix`] when there is no matrix, a matrix is not square or of another
    /// size than the first, an entry is not finite, or a row does not sum to 1 (affine
    /// invariance, ALGORITHMS.md §1.2).
    ///
    /// ```
    /// use ifs_nonlinear::SubdivisionRule;
    /// use nalgebra::dmatrix;
    /// let rule = SubdivisionRule::new(vec![dmatrix![1.0, 0.0; 0.5, 0.5], dmatrix![0.5, 0.5; 0.0, 1.0]])?;
    /// assert_eq!((rule.map_count(), rule.size()), (2, 2));
    /// assert!(SubdivisionRule::new(vec![dmatrix![1.0, 0.5; 0.5, 0.5]]).is_err()); // row 0 sums to 1.5
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn new(matrices: Vec<DMatrix<T>>) -> Result<Self> {
        let Some(first) = matrices.first() else {
            return Err(IfsError::BadMatrix { matrix: 0, reason: "no matrices given".into() });
        };
        let m = first.nrows();
        for (index, s) in matrices.iter().enumerate() {
            if s.nrows() != s.ncols() || s.nrows() != m || m == 0 {
                return Err(IfsError::BadMatrix {
                    matrix: index,
                    reason: format!("shape {}x{}, expected {m}x{m} (m >= 1)", s.nrows(), s.ncols()),
                });
            }
            for row in 0..m {
                let mut sum = T::zero();
                let mut magnitude = 0.0;
                for col in 0..m {
                    let entry = s[(row, col)].clone();
                    if !(entry.clone().real().is_finite() && entry.clone().imaginary().is_finite()) {
                        return Err(IfsError::BadMatrix {
                            matrix: index,
                            reason: format!("entry ({row}, {col}) is not finite"),
                        });
                    }
                    magnitude += entry.clone().modulus();
                    sum += entry;
                }
                let defect = (sum - T::one()).modulus();
                if defect > ROW_SUM_TOLERANCE * magnitude.max(1.0) {
                    return Err(IfsError::BadMatrix {
                        matrix: index,
                        reason: format!("row {row} sums to 1 + {defect:e}, not 1 (the rule must be affine invariant)"),
                    });
                }
            }
        }
        Ok(Self { matrices })
    }

    /// The matrices `S_1 … S_K`.
    pub fn matrices(&self) -> &[DMatrix<T>] {
        &self.matrices
    }

    /// K, the number of sub-pieces (maps of the IFS).
    pub fn map_count(&self) -> usize {
        self.matrices.len()
    }

    /// m, the number of control points the matrices act on.
    pub fn size(&self) -> usize {
        self.matrices[0].nrows()
    }

    /// The restrictions `D_i` of the maps `b ↦ b S_i` to the difference space
    /// `{b : Σ b = 0}`, in the basis `e_j - e_{j+1}` ((m-1)×(m-1), row-vector convention).
    /// Their joint spectral radius decides convergence (ALGORITHMS.md §13, §15.1).
    ///
    /// ```
    /// use ifs_nonlinear::bezier_split;
    /// use nalgebra::dmatrix;
    /// // Quadratic de Casteljau at t = 1/2: triangular, spectra {1/2, 1/4} on the difference space.
    /// let d = bezier_split(2, 0.5)?.difference_matrices();
    /// assert_eq!(d[0], dmatrix![0.5, 0.0; 0.25, 0.25]);
    /// assert_eq!(d[1], dmatrix![0.25, 0.25; 0.0, 0.5]);
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn difference_matrices(&self) -> Vec<DMatrix<T>> {
        self.matrices.iter().map(difference_restriction).collect()
    }

    /// Joint-spectral-radius estimate and norms on the difference space, see
    /// [`ContractivityReport`].
    ///
    /// ```
    /// use ifs_nonlinear::bezier_split;
    /// let report = bezier_split(2, 0.5)?.contractivity();
    /// // Spectra {1/2, 1/4} on the difference space: joint spectral radius 1/2.
    /// assert!((report.jsr_lower - 0.5).abs() < 1e-9 && report.jsr_upper < 0.6);
    /// assert!(report.is_contractive());
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn contractivity(&self) -> ContractivityReport {
        contractivity_of(&self.difference_matrices())
    }

    /// [`contractivity`](Self::contractivity), as an error when the rule is not
    /// (certifiably) contractive.
    ///
    /// # Errors
    /// [`IfsError::NotContractive`] with the bounds found (the detail says when the search
    /// was capped by [`CONTRACTIVITY_WORK_BUDGET`], i.e. the verdict may be inconclusive).
    ///
    /// ```
    /// use ifs_nonlinear::{IfsError, SubdivisionRule, bezier_split};
    /// use nalgebra::dmatrix;
    /// assert!(bezier_split(3, 0.5)?.require_contractive()?.jsr_upper < 1.0);
    /// // The identity "subdivision" never shrinks anything.
    /// let identity = SubdivisionRule::new(vec![dmatrix![1.0, 0.0; 0.0, 1.0]])?;
    /// assert!(matches!(identity.require_contractive(), Err(IfsError::NotContractive { .. })));
    /// # Ok::<(), IfsError>(())
    /// ```
    pub fn require_contractive(&self) -> Result<ContractivityReport> {
        self.contractivity().require()
    }

    /// |det D_i| for each map: the volume factor on the difference space, used for the
    /// default chaos-game probabilities.
    ///
    /// ```
    /// use ifs_nonlinear::bezier_split;
    /// // Splitting a quadratic at t: det D_0 = t · t², det D_1 = (1-t)³.
    /// let dets = bezier_split(2, 0.25)?.difference_determinants();
    /// assert!((dets[0] - 1.0 / 64.0).abs() < 1e-15 && (dets[1] - 27.0 / 64.0).abs() < 1e-15);
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn difference_determinants(&self) -> Vec<f64> {
        self.difference_matrices()
            .into_iter()
            .map(|d| if d.nrows() == 0 { 1.0 } else { d.determinant().modulus() })
            .collect()
    }
}

/// Restriction of `b ↦ b S` to `{Σ b = 0}` in the basis `d_j = e_j - e_{j+1}`: the row j of
/// the result holds the coordinates of `d_j S`, which are its prefix sums.
///
/// One running sum per row, advanced column by column (O(m²), in storage order); summing
/// each prefix afresh was O(m³), minutes for the 4225-point patches of degree (64, 64).
/// Each entry sees the same additions in the same order, so it is the same to the bit.
fn difference_restriction<T: ComplexField<RealField = f64>>(s: &DMatrix<T>) -> DMatrix<T> {
    let m = s.nrows();
    let n = m.saturating_sub(1);
    let mut restriction = DMatrix::zeros(n, n);
    let mut prefixes = vec![T::zero(); n];
    for k in 0..n {
        for (j, prefix) in prefixes.iter_mut().enumerate() {
            *prefix += s[(j, k)].clone() - s[(j + 1, k)].clone();
            restriction[(j, k)] = prefix.clone();
        }
    }
    restriction
}

/// Contractivity of a set of linear maps (the restrictions to the difference space).
///
/// For word length k, `upper_k = max_{|w| = k} ||D_w||_2^{1/k}` bounds the joint spectral
/// radius from above and `lower_k = max_{|w| = k} ρ(D_w)^{1/k}` from below; the report
/// keeps the best of each over the lengths tried (up to [`MAX_WORD_LENGTH`], at most
/// [`MAX_WORDS_PER_LENGTH`] products per length, [`CERTIFIED_WORDS_PER_LENGTH`] once the
/// upper bound is below 1). Length 1 uses the exact largest singular value, longer words
/// the cheaper bound `min(||A||_F, sqrt(||A||_1 ||A||_inf))`.
///
/// The work is also capped by [`CONTRACTIVITY_WORK_BUDGET`]: products and eigenvalue
/// problems cost O(m³) each, so for large matrices (e.g. the 441 × 441 matrices of a
/// degree-(20, 20) tensor patch) the full search took over a minute. A step that does not fit
/// the budget is replaced by an O(m²) bound (length 1: `min(||A||_F, sqrt(||A||_1
/// ||A||_inf))` for the singular value, `sqrt(|tr A²| / m)` for the spectral radius) or,
/// for longer words, not taken; [`capped`](Self::capped) then says so. The bounds stay
/// valid, only less tight: a capped report that is not contractive is inconclusive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContractivityReport {
    /// Largest singular value over the maps' linear parts (word length 1). Below 1: each
    /// map is a contraction in the Euclidean norm of the chosen coordinates. When the
    /// budget did not allow the exact value (see [`capped`](Self::capped)), an upper bound
    /// of it.
    pub max_singular_value: f64,
    /// Lower bound of the joint spectral radius (largest `ρ(D_w)^{1/|w|}` found).
    pub jsr_lower: f64,
    /// Upper bound of the joint spectral radius (smallest `max_w ||D_w||^{1/|w|}` over lengths).
    pub jsr_upper: f64,
    /// The word length that gave `jsr_upper`.
    pub word_length: u32,
    /// True when [`CONTRACTIVITY_WORK_BUDGET`] cut the search short (large matrices): the
    /// bounds are valid but looser, and a verdict of "not contractive" may be inconclusive.
    pub capped: bool,
}

impl ContractivityReport {
    /// True when the upper bound certifies a joint spectral radius below 1.
    pub fn is_contractive(&self) -> bool {
        self.jsr_upper < 1.0
    }

    /// The report itself when it certifies contraction, else the
    /// [`IfsError::NotContractive`] it stands for (what both `require_contractive`s give).
    pub(crate) fn require(self) -> Result<Self> {
        if self.is_contractive() {
            Ok(self)
        } else {
            Err(IfsError::NotContractive {
                jsr_lower: self.jsr_lower,
                jsr_upper: self.jsr_upper,
                detail: self.capped_detail(),
            })
        }
    }

    /// The explanation that [`IfsError::NotContractive`] appends when the search was capped
    /// (empty otherwise).
    pub(crate) fn capped_detail(&self) -> String {
        if self.capped {
            "; the search was capped by the work budget for matrices of this size, so the rule may still be \
             contractive"
                .into()
        } else {
            String::new()
        }
    }
}

/// Longest word length tried by the joint-spectral-radius estimate.
pub const MAX_WORD_LENGTH: u32 = 10;
/// Most products evaluated per word length.
pub const MAX_WORDS_PER_LENGTH: usize = 1024;
/// Most products per word length once the upper bound is below 1.
pub const CERTIFIED_WORDS_PER_LENGTH: usize = 256;
/// Most products whose spectral radius is computed per word length (eigenvalues are dearer).
const MAX_SPECTRA_PER_LENGTH: usize = 16;

/// Most work of one contractivity estimate, in estimated multiply-adds: a product of two
/// m×m matrices counts m³, an eigenvalue problem (spectral radius, or the Gram matrix's
/// for a singular value) 50 m³. About a second on one desktop core. The spectral radii,
/// which only tighten the lower bound, may use a third of it, so that the products, which
/// decide the verdict, keep the rest. Every preset, every Bézier curve rule up to degree
/// 64 and tensor patches up to degree (8, 8) stay below it (their reports are the same as
/// without a cap). See [`ContractivityReport::capped`].
pub const CONTRACTIVITY_WORK_BUDGET: f64 = 6e9;

/// The share of [`CONTRACTIVITY_WORK_BUDGET`] that the spectral radii may use.
const SPECTRA_SHARE: f64 = 1.0 / 3.0;

/// Cost of a Schur decomposition relative to a matrix product of the same size (measured:
/// 13 at m = 60, 50 at m = 440).
const EIGEN_COST_FACTOR: f64 = 50.0;

pub(crate) fn contractivity_of<T: ComplexField<RealField = f64>>(maps: &[DMatrix<T>]) -> ContractivityReport {
    let n = maps.first().map_or(0, DMatrix::nrows);
    if n == 0 {
        // Single control point: the difference space is {0}, everything contracts.
        return ContractivityReport {
            max_singular_value: 0.0,
            jsr_lower: 0.0,
            jsr_upper: 0.0,
            word_length: 1,
            capped: false,
        };
    }
    let k_maps = maps.len();
    let product_cost = (n as f64).powi(3);
    let eigen_cost = EIGEN_COST_FACTOR * product_cost;
    let mut work = 0.0;
    let mut spectra_work = 0.0;
    // Borrowed at length 1: the maps of a large patch are hundreds of megabytes.
    let mut words: Cow<'_, [DMatrix<T>]> = Cow::Borrowed(maps);
    let mut report = ContractivityReport {
        max_singular_value: 0.0,
        jsr_lower: 0.0,
        jsr_upper: f64::INFINITY,
        word_length: 1,
        capped: false,
    };
    for length in 1..=MAX_WORD_LENGTH {
        let exponent = 1.0 / f64::from(length);
        let upper = if length == 1 {
            // Each exact singular value: a Gram product and an eigenvalue problem.
            let exact_cost = k_maps as f64 * (product_cost + eigen_cost);
            report.max_singular_value = if work + exact_cost <= CONTRACTIVITY_WORK_BUDGET {
                work += exact_cost;
                words.iter().map(spectral_norm).fold(0.0, f64::max)
            } else {
                report.capped = true;
                words.iter().map(norm_bound).fold(0.0, f64::max)
            };
            report.max_singular_value
        } else {
            words.iter().map(norm_bound).fold(0.0, f64::max)
        };
        let upper = upper.powf(exponent);
        if upper < report.jsr_upper {
            report.jsr_upper = upper;
            report.word_length = length;
        }
        let stride = words.len().div_ceil(MAX_SPECTRA_PER_LENGTH).max(1);
        let spectra_cost = words.len().div_ceil(stride) as f64 * eigen_cost;
        let lower = if work + spectra_cost <= CONTRACTIVITY_WORK_BUDGET
            && spectra_work + spectra_cost <= SPECTRA_SHARE * CONTRACTIVITY_WORK_BUDGET
        {
            work += spectra_cost;
            spectra_work += spectra_cost;
            words.iter().step_by(stride).map(spectral_radius).fold(0.0, f64::max)
        } else {
            report.capped = true;
            words.iter().map(trace_radius_bound).fold(0.0, f64::max)
        }
        .powf(exponent);
        report.jsr_lower = report.jsr_lower.max(lower);
        // Once contractivity is certified, a smaller budget refines the estimate.
        let budget = if report.jsr_upper < 1.0 { CERTIFIED_WORDS_PER_LENGTH } else { MAX_WORDS_PER_LENGTH };
        if words.len() * k_maps > budget || report.jsr_upper - report.jsr_lower < 1e-3 {
            break;
        }
        let products_cost = (words.len() * k_maps) as f64 * product_cost;
        if work + products_cost > CONTRACTIVITY_WORK_BUDGET {
            report.capped = true;
            break;
        }
        work += products_cost;
        words = Cow::Owned(words.iter().flat_map(|w| maps.iter().map(move |s| w * s)).collect());
    }
    report
}

/// A lower bound of the spectral radius in O(m²), for matrices too large for an eigenvalue
/// problem: with eigenvalues λ_i, `|tr A| = |Σ λ_i| <= m ρ` and `|tr A²| = |Σ λ_i²| <= m ρ²`.
fn trace_radius_bound<T: ComplexField<RealField = f64>>(a: &DMatrix<T>) -> f64 {
    // tr A² = Σ_jk A_jk A_kj, by tiles so that both factors are read from cache.
    const TILE: usize = 64;
    let m = a.nrows();
    if m == 0 {
        return 0.0;
    }
    let mut trace = T::zero();
    let mut trace_of_square = T::zero();
    for j in 0..m {
        trace += a[(j, j)].clone();
    }
    for k0 in (0..m).step_by(TILE) {
        for j0 in (0..m).step_by(TILE) {
            for k in k0..(k0 + TILE).min(m) {
                for j in j0..(j0 + TILE).min(m) {
                    trace_of_square += a[(j, k)].clone() * a[(k, j)].clone();
                }
            }
        }
    }
    let m = m as f64;
    (trace.modulus() / m).max((trace_of_square.modulus() / m).sqrt())
}

/// A cheap upper bound of the spectral norm: `min(||A||_F, sqrt(||A||_1 ||A||_inf))`.
///
/// One pass in storage (column) order: the row sums accumulate column by column, which
/// adds each row's entries in the same order as summing the row on its own (same bits),
/// without striding through memory (seconds for the 4224 × 4224 matrices of the largest
/// patches).
fn norm_bound<T: ComplexField<RealField = f64>>(m: &DMatrix<T>) -> f64 {
    let (rows, cols) = m.shape();
    let mut row_sums = vec![0.0; rows];
    let mut col_max = 0.0;
    for c in 0..cols {
        let mut col_sum = 0.0;
        for (r, row_sum) in row_sums.iter_mut().enumerate() {
            let modulus = m[(r, c)].clone().modulus();
            *row_sum += modulus;
            col_sum += modulus;
        }
        col_max = f64::max(col_max, col_sum);
    }
    let row_max = row_sums.into_iter().fold(0.0, f64::max);
    let frobenius = m.iter().map(|x| x.clone().modulus_squared()).sum::<f64>().sqrt();
    frobenius.min((row_max * col_max).sqrt())
}

/// Largest singular value, as the square root of the spectral radius of `A^H A` (complex
/// Schur form, which converges reliably on these small matrices); falls back to
/// [`norm_bound`] if the iteration does not converge.
fn spectral_norm<T: ComplexField<RealField = f64>>(m: &DMatrix<T>) -> f64 {
    let gram = m.adjoint() * m;
    to_complex(&gram).and_then(spectral_radius_complex).map_or_else(|| norm_bound(m), f64::sqrt)
}

fn to_complex<T: ComplexField<RealField = f64>>(m: &DMatrix<T>) -> Option<DMatrix<Complex64>> {
    Some(m.map(|x| Complex64::new(x.clone().real(), x.imaginary())))
}

fn spectral_radius_complex(m: DMatrix<Complex64>) -> Option<f64> {
    let schur = nalgebra::linalg::Schur::try_new(m, 1e-14, 1000)?;
    Some(schur.eigenvalues()?.iter().map(|e| e.norm()).fold(0.0, f64::max))
}

fn spectral_radius<T: ComplexField<RealField = f64>>(m: &DMatrix<T>) -> f64 {
    // No convergence: the radius is unknown; 0 keeps the lower bound valid.
    to_complex(m).and_then(spectral_radius_complex).unwrap_or(0.0)
}

/// The two de Casteljau subdivision matrices of a degree-n Bézier curve split at parameter
/// `t` (ALGORITHMS.md §13 with z = t real): `L_{jk} = C(j,k) t^k (1-t)^{j-k}` (k ≤ j) and
/// `R_{jk} = C(n-j, k-j) t^{k-j} (1-t)^{n-k}` (k ≥ j).
///
/// # Errors
/// [`IfsError::ParameterOutOfRange`] for degree 0 or above 64, or t outside (0, 1);
/// [`IfsError::NotFinite`] for a non-finite t.
///
/// ```
/// use ifs_nonlinear::bezier_split;
/// let rule = bezier_split(2, 0.5)?;
/// let l = &rule.matrices()[0];
/// assert_eq!(l[(2, 0)], 0.25); // (1-t)^2
/// assert_eq!(l[(2, 1)], 0.5); // 2t(1-t)
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn bezier_split(degree: usize, t: f64) -> Result<SubdivisionRule<f64>> {
    check_finite(t, || "split parameter t".into())?;
    if !(t > 0.0 && t < 1.0) {
        return Err(IfsError::ParameterOutOfRange {
            name: "t",
            value: t.to_string(),
            reason: "the split parameter must lie in (0, 1)",
        });
    }
    check_degree(degree)?;
    SubdivisionRule::new(bezier_matrices(degree, t).to_vec())
}

/// [`bezier_split`] with a complex parameter z (Goldman, ALGORITHMS.md §13). Any finite z is
/// accepted here; convergence (|z| < 1, |1 - z| < 1 and the joint spectral radius) is
/// checked when an IFS is built from the rule, see [`crate::ComplexBezierIfs::new`].
///
/// # Errors
/// [`IfsError::ParameterOutOfRange`] for degree 0 or above 64; [`IfsError::NotFinite`].
///
/// ```
/// use ifs_nonlinear::complex_bezier_split;
/// use num_complex::Complex64;
/// let rule = complex_bezier_split(1, Complex64::new(0.5, 0.5))?;
/// assert_eq!(rule.matrices()[1][(0, 0)], Complex64::new(0.5, -0.5)); // 1 - z
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn complex_bezier_split(degree: usize, z: Complex64) -> Result<SubdivisionRule<Complex64>> {
    check_finite(z.re, || "z (real part)".into())?;
    check_finite(z.im, || "z (imaginary part)".into())?;
    check_degree(degree)?;
    SubdivisionRule::new(bezier_matrices(degree, z).to_vec())
}

fn check_degree(degree: usize) -> Result<()> {
    if (1..=64).contains(&degree) {
        Ok(())
    } else {
        Err(IfsError::ParameterOutOfRange { name: "degree", value: degree.to_string(), reason: "must be in 1..=64" })
    }
}

fn binomial(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64).round()
}

/// De Casteljau split matrices `[L, R]` for any scalar (real t or complex z).
fn bezier_matrices<T: ComplexField<RealField = f64>>(n: usize, t: T) -> [DMatrix<T>; 2] {
    let one_minus = T::one() - t.clone();
    let pow = |x: &T, e: usize| (0..e).fold(T::one(), |acc, _| acc * x.clone());
    let coefficient = |c: f64| T::from_real(c);
    let left = DMatrix::from_fn(n + 1, n + 1, |j, k| {
        if k <= j { coefficient(binomial(j, k)) * pow(&t, k) * pow(&one_minus, j - k) } else { T::zero() }
    });
    let right = DMatrix::from_fn(n + 1, n + 1, |j, k| {
        if k >= j { coefficient(binomial(n - j, k - j)) * pow(&t, k - j) * pow(&one_minus, n - k) } else { T::zero() }
    });
    [left, right]
}

/// The two local subdivision matrices of a uniform binary curve scheme given by its mask
/// (ALGORITHMS.md §1.1, §15.1): `p^{k+1}_i = Σ_j a_{i-2j} p^k_j` with
/// `a_{mask_offset + k} = mask[k]`. With the mask supported on [lo, hi], one segment of the
/// limit curve (parameter [0, 1]) depends on the m = hi - lo control points
/// `p_{1-hi} … p_{-lo}`, and its halves on the same window one level finer:
/// `S_0[r][c] = a_{r - 2c + hi - 1}`, `S_1[r][c] = a_{r - 2c + hi}`. The IFS of these
/// matrices has the limit segment as attractor (Chaikin: a quadratic B-spline arc, cubic
/// B-spline mask: a cubic arc, four-point scheme: an interpolating C1 arc).
///
/// # Errors
/// [`IfsError::ParameterOutOfRange`] for an empty, all-zero or too long (> 64) mask or one
/// with fewer than two non-zero taps; [`IfsError::NotFinite`]; [`IfsError::BadMatrix`] when
/// a row of a local matrix does not sum to 1 (the mask does not satisfy `Σ a_{2k} = Σ
/// a_{2k+1} = 1`).
///
/// ```
/// use ifs_nonlinear::uniform_scheme_split;
/// // Cubic B-spline: a_{-2..2} = (1, 4, 6, 4, 1)/8; 4 control points per segment.
/// let rule = uniform_scheme_split(-2, &[0.125, 0.5, 0.75, 0.5, 0.125])?;
/// assert_eq!(rule.size(), 4);
/// assert_eq!(rule.matrices()[0].row(1).iter().copied().collect::<Vec<_>>(), vec![0.125, 0.75, 0.125, 0.0]);
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn uniform_scheme_split(mask_offset: i32, mask: &[f64]) -> Result<SubdivisionRule<f64>> {
    for (k, &a) in mask.iter().enumerate() {
        check_finite(a, || format!("mask entry {k}"))?;
    }
    let first = mask.iter().position(|&a| a != 0.0);
    let last = mask.iter().rposition(|&a| a != 0.0);
    let (Some(first), Some(last)) = (first, last) else {
        return Err(IfsError::ParameterOutOfRange { name: "mask", value: format!("{mask:?}"), reason: "all zero" });
    };
    if last == first || mask.len() > 64 {
        return Err(IfsError::ParameterOutOfRange {
            name: "mask",
            value: format!("{} taps", mask.len()),
            reason: "needs 2..=64 taps with at least two non-zero",
        });
    }
    let lo = i64::from(mask_offset) + first as i64;
    let hi = i64::from(mask_offset) + last as i64;
    let a = |k: i64| -> f64 {
        let index = k - i64::from(mask_offset);
        if (0..mask.len() as i64).contains(&index) { mask[index as usize] } else { 0.0 }
    };
    let m = (hi - lo) as usize;
    // Row r is the fine point 1 - hi + r (+ 1 for the right half), column c the coarse point 1 - hi + c.
    let half = |right: i64| DMatrix::from_fn(m, m, |r, c| a(r as i64 - 2 * c as i64 + hi - 1 + right));
    SubdivisionRule::new(vec![half(0), half(1)])
}

/// The two local matrices (left and right half of one segment) of a curve scheme of the
/// `subdiv-curve` crate, from its symbol (mask): [`uniform_scheme_split`] applied to
/// `scheme.symbol()`. Every uniform binary scheme there (Chaikin, cubic B-spline,
/// four-point, the combined two-parameter family, user rules) has such finite matrices;
/// the attractor of the resulting IFS is one segment of the limit curve.
///
/// # Errors
/// As [`uniform_scheme_split`] (e.g. a rule that is not affine invariant).
///
/// ```
/// use ifs_nonlinear::curve_scheme_split;
/// use subdiv_curve::CurveScheme;
/// let rule = curve_scheme_split(&CurveScheme::cubic_bspline())?;
/// assert_eq!((rule.map_count(), rule.size()), (2, 4)); // four control points per cubic segment
/// assert!(rule.contractivity().is_contractive());
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn curve_scheme_split(scheme: &subdiv_curve::CurveScheme) -> Result<SubdivisionRule<f64>> {
    let symbol = scheme.symbol();
    uniform_scheme_split(symbol.lowest_power(), symbol.coefficients())
}

/// The four quadrant matrices of a tensor-product Bézier patch of degrees (n_u, n_v), split
/// at u = 1/2 and v = 1/2: `S = S_u ⊗ S_v` in the order (u low, v low), (u low, v high),
/// (u high, v low), (u high, v high). Bilinear: (1, 1), biquadratic: (2, 2), bicubic: (3, 3).
///
/// # Errors
/// [`IfsError::ParameterOutOfRange`] for a degree of 0 or above 64.
///
/// ```
/// use ifs_nonlinear::tensor_patch_split;
/// let rule = tensor_patch_split(3, 3)?; // bicubic: 16 control points, 4 maps
/// assert_eq!((rule.map_count(), rule.size()), (4, 16));
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn tensor_patch_split(degree_u: usize, degree_v: usize) -> Result<SubdivisionRule<f64>> {
    check_degree(degree_u)?;
    check_degree(degree_v)?;
    let [lu, ru] = bezier_matrices(degree_u, 0.5);
    let [lv, rv] = bezier_matrices(degree_v, 0.5);
    SubdivisionRule::new(vec![lu.kronecker(&lv), lu.kronecker(&rv), ru.kronecker(&lv), ru.kronecker(&rv)])
}

/// The multi-indices β (|β| = n) of a triangular Bézier patch in the crate's order:
/// β0 descending, then β1 descending.
///
/// ```
/// assert_eq!(ifs_nonlinear::triangle_multi_indices(1)?, vec![[1, 0, 0], [0, 1, 0], [0, 0, 1]]);
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
///
/// # Errors
/// [`IfsError::ParameterOutOfRange`] above [`MAX_MULTI_INDEX_DEGREE`], checked before
/// allocating (a mistyped degree used to abort the process, or overflow the count).
pub fn triangle_multi_indices(n: usize) -> Result<Vec<[usize; 3]>> {
    if n > MAX_MULTI_INDEX_DEGREE {
        return Err(IfsError::ParameterOutOfRange {
            name: "n",
            value: n.to_string(),
            reason: "triangle multi-indices: at most degree 1024 (525 825 indices)",
        });
    }
    Ok(multi_indices(n))
}

/// The largest degree of [`triangle_multi_indices`].
pub const MAX_MULTI_INDEX_DEGREE: usize = 1024;

/// [`triangle_multi_indices`] of a degree known to be small.
fn multi_indices(n: usize) -> Vec<[usize; 3]> {
    let mut out = Vec::with_capacity((n + 1) * (n + 2) / 2);
    for b0 in (0..=n).rev() {
        for b1 in (0..=n - b0).rev() {
            out.push([b0, b1, n - b0 - b1]);
        }
    }
    out
}

/// Position of β in [`triangle_multi_indices`]`(|β|)`.
fn triangle_index(beta: [usize; 3]) -> usize {
    let n = beta[0] + beta[1] + beta[2];
    // Entries with a larger β0: Σ_{b0 = β0+1}^{n} (n - b0 + 1) = (n - β0)(n - β0 + 1) / 2.
    let before = (n - beta[0]) * (n - beta[0] + 1) / 2;
    before + (n - beta[0] - beta[1])
}

/// Blossom (polar form) of the degree-n triangular Bézier patch whose control points are
/// the unit vectors of R^m: the weights with which `F(u_1, …, u_n)` combines the control
/// points (ALGORITHMS.md §9; de Casteljau with argument u_r at level r).
fn blossom_weights(n: usize, arguments: &[[f64; 3]]) -> Vec<f64> {
    debug_assert_eq!(arguments.len(), n);
    let m = (n + 1) * (n + 2) / 2;
    // Level r holds, for each β with |β| = n - r, a weight vector of length m.
    let mut level: Vec<Vec<f64>> = (0..m)
        .map(|i| {
            let mut e = vec![0.0; m];
            e[i] = 1.0;
            e
        })
        .collect();
    for (r, u) in arguments.iter().enumerate() {
        let degree = n - r - 1;
        level = multi_indices(degree)
            .into_iter()
            .map(|beta| {
                let mut acc = vec![0.0; m];
                for (k, &weight) in u.iter().enumerate() {
                    let mut up = beta;
                    up[k] += 1;
                    for (a, b) in acc.iter_mut().zip(&level[triangle_index(up)]) {
                        *a += weight * b;
                    }
                }
                acc
            })
            .collect();
    }
    level.pop().expect("internal: blossom level 0 has one entry")
}

/// The four midpoint-quadrisection matrices of a degree-n triangular Bézier patch
/// (ALGORITHMS.md §9, §15.1): the sub-patch over the sub-triangle (s0, s1, s2) has control
/// points `F(s0^{β0}, s1^{β1}, s2^{β2})` (blossom). Sub-triangles, in barycentric
/// coordinates of the domain triangle (t0, t1, t2) with midpoints m_ij:
/// (t0, m01, m02), (m01, t1, m12), (m02, m12, t2) and the central (m12, m02, m01), all with
/// the orientation of the domain.
///
/// # Errors
/// [`IfsError::ParameterOutOfRange`] for degree 0 or above 12.
///
/// ```
/// use ifs_nonlinear::triangle_patch_split;
/// let rule = triangle_patch_split(2)?; // 6 control points, 4 maps
/// assert_eq!((rule.map_count(), rule.size()), (4, 6));
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn triangle_patch_split(degree: usize) -> Result<SubdivisionRule<f64>> {
    if !(1..=12).contains(&degree) {
        return Err(IfsError::ParameterOutOfRange {
            name: "degree",
            value: degree.to_string(),
            reason: "triangular patches: must be in 1..=12",
        });
    }
    let t = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mid = |a: usize, b: usize| -> [f64; 3] { std::array::from_fn(|k| 0.5 * (t[a][k] + t[b][k])) };
    let (m01, m02, m12) = (mid(0, 1), mid(0, 2), mid(1, 2));
    let triangles = [[t[0], m01, m02], [m01, t[1], m12], [m02, m12, t[2]], [m12, m02, m01]];
    let betas = multi_indices(degree);
    let m = betas.len();
    let matrices = triangles
        .iter()
        .map(|s| {
            let mut matrix = DMatrix::zeros(m, m);
            for (row, beta) in betas.iter().enumerate() {
                let arguments: Vec<[f64; 3]> =
                    (0..3).flat_map(|corner| std::iter::repeat_n(s[corner], beta[corner])).collect();
                for (col, w) in blossom_weights(degree, &arguments).into_iter().enumerate() {
                    matrix[(row, col)] = w;
                }
            }
            matrix
        })
        .collect();
    SubdivisionRule::new(matrices)
}

/// The three corner maps of the Sierpiński gasket on a linear triangle (ALGORITHMS.md
/// §15.1): `S_i` keeps corner i and halves the other two towards it, e.g.
/// `S_1 = [[1,0,0],[1/2,1/2,0],[1/2,0,1/2]]`.
///
/// ```
/// let rule = ifs_nonlinear::sierpinski();
/// assert_eq!(rule.matrices()[0][(1, 0)], 0.5);
/// ```
pub fn sierpinski() -> SubdivisionRule<f64> {
    let matrices = (0..3)
        .map(|corner| {
            DMatrix::from_fn(3, 3, |r, c| {
                if r == corner { f64::from(c == corner) } else { 0.5 * f64::from(c == corner || c == r) }
            })
        })
        .collect();
    SubdivisionRule::new(matrices).expect("internal: Sierpinski matrices are affine")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row_sums_are_one<T: ComplexField<RealField = f64>>(rule: &SubdivisionRule<T>) {
        for s in rule.matrices() {
            for r in 0..s.nrows() {
                let sum = s.row(r).iter().fold(T::zero(), |a, b| a + b.clone());
                assert!((sum - T::one()).modulus() < 1e-13);
            }
        }
    }

    #[test]
    fn bezier_matrices_match_the_spec() {
        let rule = bezier_split(2, 0.5).unwrap();
        let [l, r] = [&rule.matrices()[0], &rule.matrices()[1]];
        assert_eq!(l, &nalgebra::dmatrix![1.0, 0.0, 0.0; 0.5, 0.5, 0.0; 0.25, 0.5, 0.25]);
        assert_eq!(r, &nalgebra::dmatrix![0.25, 0.5, 0.25; 0.0, 0.5, 0.5; 0.0, 0.0, 1.0]);
        for degree in 1..=7 {
            row_sums_are_one(&bezier_split(degree, 0.3).unwrap());
            row_sums_are_one(&complex_bezier_split(degree, Complex64::new(0.5, 0.4)).unwrap());
        }
    }

    #[test]
    fn complex_quadratic_matrices_match_the_spec() {
        let z = Complex64::new(0.3, 0.6);
        let w = Complex64::new(1.0, 0.0) - z;
        let rule = complex_bezier_split(2, z).unwrap();
        let l = &rule.matrices()[0];
        let r = &rule.matrices()[1];
        let close = |a: Complex64, b: Complex64| (a - b).norm() < 1e-15;
        assert!(close(l[(2, 0)], w * w) && close(l[(2, 1)], 2.0 * z * w) && close(l[(2, 2)], z * z));
        assert!(close(r[(0, 0)], w * w) && close(r[(0, 1)], 2.0 * z * w) && close(r[(1, 1)], w));
    }

    #[test]
    fn bad_parameters_are_errors() {
        assert!(matches!(bezier_split(2, 1.0), Err(IfsError::ParameterOutOfRange { name: "t", .. })));
        assert!(matches!(bezier_split(0, 0.5), Err(IfsError::ParameterOutOfRange { name: "degree", .. })));
        assert!(matches!(bezier_split(2, f64::NAN), Err(IfsError::NotFinite { .. })));
        assert!(matches!(triangle_patch_split(0), Err(IfsError::ParameterOutOfRange { .. })));
        let not_square = DMatrix::from_element(2, 3, 1.0 / 3.0);
        assert!(matches!(SubdivisionRule::new(vec![not_square]), Err(IfsError::BadMatrix { matrix: 0, .. })));
    }

    #[test]
    fn oversized_multi_index_degrees_are_errors() {
        assert_eq!(triangle_multi_indices(MAX_MULTI_INDEX_DEGREE).unwrap().len(), 1025 * 1026 / 2);
        for n in [MAX_MULTI_INDEX_DEGREE + 1, usize::MAX] {
            assert!(matches!(triangle_multi_indices(n), Err(IfsError::ParameterOutOfRange { name: "n", .. })));
        }
    }

    #[test]
    fn triangle_indices_round_trip() {
        for n in 0..6 {
            for (i, beta) in triangle_multi_indices(n).unwrap().into_iter().enumerate() {
                assert_eq!(triangle_index(beta), i);
            }
        }
    }

    /// Sub-patch control points evaluate to the same surface: for a linear-in-parameters
    /// check, the patch over the sub-triangle at its local barycentric (λ) equals the patch
    /// at the corresponding global point.
    #[test]
    fn triangle_sub_patches_lie_on_the_patch() {
        let n = 3;
        let betas = triangle_multi_indices(n).unwrap();
        // Scalar control values (any), evaluated with the blossom at the diagonal.
        let values: Vec<f64> = (0..betas.len()).map(|i| ((i * 7 + 3) % 11) as f64 - 4.0).collect();
        let eval = |lambda: [f64; 3], vals: &[f64]| -> f64 {
            let w = blossom_weights(n, &[lambda; 3]);
            w.iter().zip(vals).map(|(a, b)| a * b).sum()
        };
        let rule = triangle_patch_split(n).unwrap();
        let t = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let mid = |a: usize, b: usize| -> [f64; 3] { std::array::from_fn(|k| 0.5 * (t[a][k] + t[b][k])) };
        let corners = [
            [t[0], mid(0, 1), mid(0, 2)],
            [mid(0, 1), t[1], mid(1, 2)],
            [mid(0, 2), mid(1, 2), t[2]],
            [mid(1, 2), mid(0, 2), mid(0, 1)],
        ];
        for (s, sub) in rule.matrices().iter().zip(corners) {
            let sub_values: Vec<f64> =
                (0..s.nrows()).map(|r| (0..s.ncols()).map(|c| s[(r, c)] * values[c]).sum()).collect();
            for local in [[0.2, 0.3, 0.5], [1.0, 0.0, 0.0], [0.1, 0.8, 0.1]] {
                let global: [f64; 3] = std::array::from_fn(|k| (0..3).map(|c| local[c] * sub[c][k]).sum());
                assert!((eval(local, &sub_values) - eval(global, &values)).abs() < 1e-12);
            }
        }
        row_sums_are_one(&rule);
        // Blossom symmetry: argument order does not matter.
        let a = blossom_weights(n, &[[0.2, 0.3, 0.5], [0.6, 0.1, 0.3], [0.0, 0.5, 0.5]]);
        let b = blossom_weights(n, &[[0.0, 0.5, 0.5], [0.2, 0.3, 0.5], [0.6, 0.1, 0.3]]);
        assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-15));
    }

    /// Uniform schemes: Chaikin's local matrices, and the cubic B-spline IFS draws the
    /// closed-form cubic B-spline segment (from the fixed point of S_0 = the weights of
    /// c(0), every level-k point is exactly a curve point).
    #[test]
    fn uniform_scheme_local_matrices() {
        let chaikin = uniform_scheme_split(-2, &[0.25, 0.75, 0.75, 0.25]).unwrap();
        assert_eq!(chaikin.matrices()[0], nalgebra::dmatrix![0.75, 0.25, 0.0; 0.25, 0.75, 0.0; 0.0, 0.75, 0.25]);
        assert_eq!(chaikin.matrices()[1], nalgebra::dmatrix![0.25, 0.75, 0.0; 0.0, 0.75, 0.25; 0.0, 0.25, 0.75]);
        assert!(chaikin.contractivity().is_contractive());
        let four_point =
            uniform_scheme_split(-3, &[-1.0 / 16.0, 0.0, 9.0 / 16.0, 1.0, 9.0 / 16.0, 0.0, -1.0 / 16.0]).unwrap();
        assert_eq!(four_point.size(), 6);
        let report = four_point.contractivity();
        assert!(report.is_contractive(), "{report:?}");
        assert!(uniform_scheme_split(0, &[0.5, 0.25]).is_err()); // not affine
        assert!(uniform_scheme_split(0, &[0.0, 1.0, 0.0]).is_err());

        let cubic = uniform_scheme_split(-2, &[0.125, 0.5, 0.75, 0.5, 0.125]).unwrap();
        let p = [[0.0, 0.0], [1.0, 2.0], [3.0, 1.5], [4.0, -1.0]];
        let curve = |t: f64| -> [f64; 2] {
            let w = [
                (1.0 - t).powi(3),
                3.0 * t.powi(3) - 6.0 * t * t + 4.0,
                -3.0 * t.powi(3) + 3.0 * t * t + 3.0 * t + 1.0,
                t.powi(3),
            ];
            std::array::from_fn(|k| (0..4).map(|j| w[j] * p[j][k]).sum::<f64>() / 6.0)
        };
        let ifs = crate::BarycentricIfs::new(&cubic, &p).unwrap();
        let levels = 6;
        let start = [1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0, 0.0];
        let points = crate::deterministic_points(&ifs, Some(&start), levels, 1 << 16).unwrap();
        for (word, q) in points.iter().enumerate() {
            // Word letters v_1 … v_k (v_1 most significant); t = binary fraction of the reversed word.
            let t: f64 = (0..levels).map(|i| ((word >> i) & 1) as f64 * 0.5f64.powi(i as i32 + 1)).sum();
            let c = curve(t);
            assert!((c[0] - q[0]).abs() < 1e-12 && (c[1] - q[1]).abs() < 1e-12, "t = {t}");
        }
    }

    /// Our matrices from the mask agree with `subdiv-curve`'s own segment matrices (an
    /// independent construction), for every scheme it ships.
    #[test]
    fn curve_scheme_matrices_agree_with_subdiv_curve() {
        use subdiv_curve::CurveScheme;
        let schemes = [
            CurveScheme::chaikin(),
            CurveScheme::cubic_bspline(),
            CurveScheme::four_point(1.0 / 16.0).unwrap(),
            CurveScheme::combined(-1.0 / 64.0, 3.0 / 32.0).unwrap(),
        ];
        for scheme in schemes {
            let ours = curve_scheme_split(&scheme).unwrap();
            let theirs = subdiv_curve::analysis::ifs_matrices(&scheme);
            assert_eq!(ours.matrices()[0], theirs.left, "{}", scheme.name());
            assert_eq!(ours.matrices()[1], theirs.right, "{}", scheme.name());
            assert!(ours.contractivity().is_contractive(), "{}", scheme.name());
        }
    }

    #[test]
    fn tensor_patch_quadrants_are_kronecker_products() {
        let rule = tensor_patch_split(2, 1).unwrap();
        assert_eq!(rule.size(), 6);
        row_sums_are_one(&rule);
        // Bilinear: the (u low, v low) quadrant maps corner P00 to itself.
        let bilinear = tensor_patch_split(1, 1).unwrap();
        assert_eq!(bilinear.matrices()[0].row(0).iter().copied().collect::<Vec<_>>(), vec![1.0, 0.0, 0.0, 0.0]);
        assert!(bilinear.contractivity().is_contractive());
    }

    #[test]
    fn sierpinski_is_contractive_with_ratio_one_half() {
        let report = sierpinski().contractivity();
        assert!((report.jsr_lower - 0.5).abs() < 1e-12 && report.jsr_upper < 0.5 + 1e-9, "{report:?}");
        assert_eq!(sierpinski().difference_determinants(), vec![0.25; 3]);
    }

    /// `tensor_patch_split(20, 20).contractivity()` ran for minutes (products and Schur
    /// decompositions of 440 × 440 matrices, up to 1024 per word length); the work budget
    /// now caps it (here about 0.1 s), says so, and leaves small rules untouched.
    #[test]
    fn large_patch_contractivity_is_capped_small_rules_are_not() {
        let large = tensor_patch_split(20, 20).unwrap().contractivity();
        assert!(large.capped, "{large:?}");
        // Valid bounds, just loose: the true joint spectral radius is 1/2.
        assert!(large.jsr_lower <= 0.5 + 1e-9 && large.jsr_upper >= 0.5, "{large:?}");
        let err = tensor_patch_split(20, 20).unwrap().require_contractive().unwrap_err();
        assert!(err.to_string().contains("capped"), "{err}");
        // Known small cases: the same verdict and bounds as without a cap.
        let bicubic = tensor_patch_split(3, 3).unwrap().contractivity();
        assert!(!bicubic.capped && bicubic.is_contractive() && bicubic.jsr_upper == 0.7844014540894104, "{bicubic:?}");
        let quadratic = bezier_split(2, 0.5).unwrap().contractivity();
        assert!(!quadratic.capped && (quadratic.jsr_lower - 0.5).abs() < 1e-12 && quadratic.jsr_upper < 0.53);
        let diverging = complex_bezier_split(2, Complex64::new(-0.5, 0.0)).unwrap().contractivity();
        assert!(!diverging.capped && !diverging.is_contractive() && diverging.jsr_lower >= 1.5 - 1e-12);
    }

    /// The running-sum difference restriction equals the defining prefix sums to the bit.
    #[test]
    fn difference_restriction_is_the_prefix_sum_formula() {
        let rule = tensor_patch_split(2, 3).unwrap();
        for s in rule.matrices() {
            let fast = difference_restriction(s);
            let n = s.nrows() - 1;
            for j in 0..n {
                for k in 0..n {
                    let prefix = (0..=k).fold(0.0, |acc, l| acc + (s[(j, l)] - s[(j + 1, l)]));
                    assert_eq!(fast[(j, k)].to_bits(), prefix.to_bits());
                }
            }
        }
    }

    /// The O(m²) lower bound never exceeds the spectral radius.
    #[test]
    fn trace_bound_is_below_the_spectral_radius() {
        let rule = triangle_patch_split(3).unwrap();
        let mut maps = rule.difference_matrices();
        maps.push(nalgebra::dmatrix![0.0, 2.0; -2.0, 0.0]); // eigenvalues ±2i: tr A² = -8
        for d in &maps {
            let bound = trace_radius_bound(d);
            assert!(bound > 0.0 && bound <= spectral_radius(d) * (1.0 + 1e-12), "{bound} {}", spectral_radius(d));
        }
        assert!((trace_radius_bound(&maps[maps.len() - 1]) - 2.0).abs() < 1e-15);
    }

    #[test]
    fn non_contractive_complex_parameter_is_detected() {
        let rule = complex_bezier_split(1, Complex64::new(-0.5, 0.0)).unwrap();
        let report = rule.contractivity();
        assert!(report.jsr_lower >= 1.5 - 1e-12, "{report:?}");
        assert!(matches!(rule.require_contractive(), Err(IfsError::NotContractive { .. })));
    }
}
