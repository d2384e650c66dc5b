//! Smoothness analysis of curve schemes (spec §1.1, §1.3, §16).
//!
//! - [`Symbol`]: the z-transform `a(z) = sum_m a_m z^m` of a scheme's mask, with
//!   [`generation_degree`] (largest `d` with `(1+z)^{d+1} | a(z)`: polynomials of degree
//!   `d` have polynomial limits) and [`reproduction_degree`] (polynomial data of degree
//!   `d` is reproduced, with the parametrisation shift `tau = a'(1)/2`; conditions
//!   `a^{(r)}(1) = 2 tau (tau-1) ... (tau-r+1)`, Conti & Hormann 2011).
//! - [`contractivity`]: the difference-scheme test (Dyn 1992). With
//!   `a(z) = (1+z)^{m+1} b(z) / 2^m`, the scheme is C^m if the scheme with symbol `b` is
//!   contractive: `||b^{[L]}||_inf < 1` for some `L`, where
//!   `b^{[L]}(z) = b(z) b(z^2) ... b(z^{2^{L-1}})`. Conversely, the spectral radius of any
//!   product of the two finite subdivision matrices of `b` is a lower bound of its joint
//!   spectral radius; if it reaches 1, `b` is not contractive and (for schemes with stable
//!   integer shifts, Dyn & Levin 2002) the scheme is **not** C^m: the check is *refuted*.
//! - [`local_matrix`]: the subdivision matrix around a regular point, eigenvalues, and the
//!   eigen conditions ([`EigenChecks`]): C1 needs `1 = λ0 > λ1 > |λ2|` with a linear
//!   eigenvector for `λ1`; C2 additionally `λ2 = λ1^2 > |λ3|` with a quadratic eigenvector.
//!   These are *necessary* conditions (seed 004's Lemma 2 claims sufficiency; spec §16.3
//!   shows it is not): [`Analysis::smoothness`] needs both the eigen conditions and the
//!   difference test.
//! - [`ifs_matrices`]: the finite matrices `L`, `R` mapping the control points of one
//!   segment of the limit curve to those of its two halves (subdivision as an iterated
//!   function system, spec §15).
//! - [`analyze`] bundles everything; [`crate::framework::Framework::analyze`] does the
//!   same for the interpolatory-approximating framework, at an interpolated point.
//!
//! ```
//! use subdiv_curve::{CurveScheme, analysis};
//! let report = analysis::analyze(&CurveScheme::four_point(1.0 / 16.0)?);
//! assert_eq!((report.smoothness, report.c1, report.c2), (Some(1), true, false));
//! assert_eq!((report.generation_degree, report.reproduction_degree), (Some(3), Some(3)));
//! let cubic = analysis::analyze(&CurveScheme::cubic_bspline());
//! assert_eq!(cubic.smoothness, Some(2));
//! assert!((cubic.eigenvalues[2].re - 0.25).abs() < 1e-12);
//! # Ok::<(), subdiv_curve::CurveError>(())
//! ```

use nalgebra::{Complex, DMatrix, DVector};

use crate::CurveError;
use crate::scheme::CurveScheme;

/// Largest `L` tried by [`analyze`] in the difference test.
pub const DEFAULT_MAX_STEPS: usize = 12;

/// The most steps [`contractivity`] tries, whatever it is asked: the `L`-step product
/// has about `2^L` times the symbol's coefficients.
pub const MAX_CONTRACTIVITY_STEPS: usize = 24;
/// Largest smoothness order tried by [`analyze`].
pub const DEFAULT_MAX_ORDER: usize = 4;
/// Tolerance of eigenvalue equalities (`λ0 = 1`, `λ2 = λ1^2`). Loose enough for the
/// `sqrt(ε)` splitting of defective eigenvalues (the four-point scheme has a Jordan block
/// for 1/4, computed as `1/4 ± 3e-9`).
pub const EIGEN_TOLERANCE: f64 = 1e-7;
/// Minimum gap of the strict eigenvalue orderings (`|λ2| < λ1`, `|λ3| < λ2`), as in
/// spec §1.3.
pub const EIGEN_GAP: f64 = 1e-6;

/// A Laurent polynomial `sum_k coefficients[k] z^{lowest_power + k}`: the symbol of a
/// scheme, or of one of its difference schemes.
#[derive(Debug, Clone, PartialEq)]
pub struct Symbol {
    lowest_power: i32,
    coefficients: Vec<f64>,
}

impl Symbol {
    /// The symbol with these coefficients, the first one multiplying `z^lowest_power`.
    ///
    /// ```
    /// use subdiv_curve::analysis::Symbol;
    /// let chaikin = Symbol::new(-2, vec![0.25, 0.75, 0.75, 0.25]);
    /// assert_eq!(chaikin.eval(1.0), 2.0);
    /// assert_eq!(chaikin.one_plus_z_factors(), 3);
    /// ```
    pub fn new(lowest_power: i32, coefficients: Vec<f64>) -> Self {
        Symbol { lowest_power, coefficients }
    }

    /// The symbol of a scheme: `a_{-2(even.offset + j)} = even.weights[j]`,
    /// `a_{1 - 2(odd.offset + j)} = odd.weights[j]`.
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, analysis::Symbol};
    /// let cubic = Symbol::of_scheme(&CurveScheme::cubic_bspline());
    /// assert_eq!((cubic.lowest_power(), cubic.coefficients()), (-2, &[0.125, 0.5, 0.75, 0.5, 0.125][..]));
    /// ```
    pub fn of_scheme(scheme: &CurveScheme) -> Self {
        let mut terms = Vec::new();
        for (rule, parity) in [(scheme.even_rule(), 0), (scheme.odd_rule(), 1)] {
            for (j, &w) in rule.weights().iter().enumerate() {
                terms.push((parity - 2 * (rule.offset() + j as i32), w));
            }
        }
        let lowest = terms.iter().map(|t| t.0).min().expect("internal: rules are non-empty");
        let highest = terms.iter().map(|t| t.0).max().expect("internal: rules are non-empty");
        let mut coefficients = vec![0.0; (highest - lowest + 1) as usize];
        for (power, w) in terms {
            coefficients[(power - lowest) as usize] += w;
        }
        Symbol { lowest_power: lowest, coefficients }
    }

    /// Exponent of the first coefficient.
    pub fn lowest_power(&self) -> i32 {
        self.lowest_power
    }

    /// Exponent of the last coefficient.
    pub fn highest_power(&self) -> i32 {
        self.lowest_power + self.coefficients.len() as i32 - 1
    }

    /// The coefficients, lowest power first.
    pub fn coefficients(&self) -> &[f64] {
        &self.coefficients
    }

    /// Coefficient of `z^power` (0 outside the support).
    ///
    /// ```
    /// use subdiv_curve::CurveScheme;
    /// // Cubic B-spline: a(z) = (z^-2 + 4 z^-1 + 6 + 4 z + z^2) / 8.
    /// let cubic = CurveScheme::cubic_bspline().symbol();
    /// assert_eq!((cubic.coefficient(-1), cubic.coefficient(0), cubic.coefficient(2)), (0.5, 0.75, 0.125));
    /// assert_eq!((cubic.coefficient(-3), cubic.coefficient(3)), (0.0, 0.0)); // outside the support
    /// ```
    pub fn coefficient(&self, power: i32) -> f64 {
        let k = power - self.lowest_power;
        if k < 0 { 0.0 } else { self.coefficients.get(k as usize).copied().unwrap_or(0.0) }
    }

    /// `a(z)` at a real `z != 0`.
    ///
    /// ```
    /// use subdiv_curve::CurveScheme;
    /// // Chaikin: a(z) = (1+z)^3 / (4 z^2). Every convergent scheme has a(1) = 2 and a(-1) = 0.
    /// let chaikin = CurveScheme::chaikin().symbol();
    /// assert_eq!((chaikin.eval(1.0), chaikin.eval(-1.0)), (2.0, 0.0));
    /// assert_eq!(chaikin.eval(2.0), 27.0 / 16.0);
    /// ```
    pub fn eval(&self, z: f64) -> f64 {
        self.terms().map(|(m, a)| a * z.powi(m)).sum()
    }

    /// The `order`-th derivative at a real `z != 0`.
    ///
    /// ```
    /// use subdiv_curve::analysis::Symbol;
    /// let s = Symbol::new(-1, vec![1.0, 0.0, 1.0]); // 1/z + z
    /// assert_eq!(s.derivative(1.0, 1), 0.0);
    /// assert_eq!(s.derivative(1.0, 2), 2.0);
    /// ```
    pub fn derivative(&self, z: f64, order: u32) -> f64 {
        self.terms().map(|(m, a)| a * falling_factorial(m, order) * z.powi(m - order as i32)).sum()
    }

    fn terms(&self) -> impl Iterator<Item = (i32, f64)> + '_ {
        self.coefficients.iter().enumerate().map(|(k, &a)| (self.lowest_power + k as i32, a))
    }

    /// Scale of the `order`-th derivative at `z = ±1`, for relative tolerances.
    fn derivative_scale(&self, order: u32) -> f64 {
        self.terms().map(|(m, a)| (a * falling_factorial(m, order)).abs()).sum::<f64>().max(1.0)
    }

    /// Number of factors `(1+z)` of the symbol (derivatives at `z = -1` vanish to
    /// `1e-10` relative).
    ///
    /// ```
    /// use subdiv_curve::CurveScheme;
    /// assert_eq!(CurveScheme::chaikin().symbol().one_plus_z_factors(), 3); // (1+z)^3 / 4
    /// assert_eq!(CurveScheme::cubic_bspline().symbol().one_plus_z_factors(), 4); // (1+z)^4 / 8
    /// assert_eq!(CurveScheme::four_point(1.0 / 16.0)?.symbol().one_plus_z_factors(), 4); // generates cubics
    /// assert_eq!(CurveScheme::four_point(0.1)?.symbol().one_plus_z_factors(), 2);
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn one_plus_z_factors(&self) -> usize {
        let mut count = 0;
        while count < self.coefficients.len()
            && self.derivative(-1.0, count as u32).abs() <= 1e-10 * self.derivative_scale(count as u32)
        {
            count += 1;
        }
        count
    }

    /// `self / (1+z)`, or `None` when `(1+z)` is not a factor (remainder above `1e-10`
    /// relative).
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, analysis::Symbol};
    /// // Chaikin's symbol (1+z)^3 / (4 z^2) divides by (1+z) exactly three times.
    /// let chaikin = CurveScheme::chaikin().symbol();
    /// let once = chaikin.divide_by_one_plus_z().expect("(1+z)^3 has the factor");
    /// assert_eq!(once, Symbol::new(-2, vec![0.25, 0.5, 0.25]));
    /// let thrice = once.divide_by_one_plus_z().and_then(|s| s.divide_by_one_plus_z()).expect("two factors left");
    /// assert_eq!(thrice, Symbol::new(-2, vec![0.25]));
    /// assert_eq!(thrice.divide_by_one_plus_z(), None);
    /// ```
    pub fn divide_by_one_plus_z(&self) -> Option<Symbol> {
        let c = &self.coefficients;
        if c.len() < 2 {
            return None;
        }
        let mut quotient = vec![0.0; c.len() - 1];
        let mut carry = 0.0;
        // Highest power first: q_{k-1} = c_k - q_k.
        for k in (1..c.len()).rev() {
            carry = c[k] - carry;
            quotient[k - 1] = carry;
        }
        let remainder = c[0] - carry;
        let scale = c.iter().map(|x| x.abs()).sum::<f64>().max(1.0);
        (remainder.abs() <= 1e-10 * scale).then_some(Symbol { lowest_power: self.lowest_power, coefficients: quotient })
    }

    /// `factor * self`.
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, analysis::Symbol};
    /// // Chaikin's first difference scheme b = 2 a / (1+z)^2 = (1+z) / (2 z^2): norm 1/2 < 1, so C1.
    /// let chaikin = CurveScheme::chaikin().symbol();
    /// let twice = chaikin.divide_by_one_plus_z().and_then(|s| s.divide_by_one_plus_z()).expect("(1+z)^2 divides");
    /// assert_eq!(twice.scaled(2.0), Symbol::new(-2, vec![0.5, 0.5]));
    /// ```
    pub fn scaled(&self, factor: f64) -> Symbol {
        Symbol { lowest_power: self.lowest_power, coefficients: self.coefficients.iter().map(|a| a * factor).collect() }
    }

    /// `self(z) * other(z^stride)`.
    fn times_upsampled(&self, other: &Symbol, stride: usize) -> Symbol {
        let len = self.coefficients.len() + (other.coefficients.len() - 1) * stride;
        let mut product = vec![0.0; len];
        for (k, &b) in other.coefficients.iter().enumerate() {
            if b != 0.0 {
                for (j, &a) in self.coefficients.iter().enumerate() {
                    product[j + k * stride] += a * b;
                }
            }
        }
        Symbol { lowest_power: self.lowest_power + other.lowest_power * stride as i32, coefficients: product }
    }
}

fn falling_factorial(m: i32, order: u32) -> f64 {
    (0..order as i32).map(|l| (m - l) as f64).product()
}

/// Largest `d` such that the scheme maps polynomial data of degree `d` to polynomial limits
/// (`(1+z)^{d+1}` divides the symbol); `None` if `a(-1) != 0` (the scheme cannot converge).
///
/// ```
/// use subdiv_curve::{CurveScheme, analysis::{Symbol, generation_degree}};
/// assert_eq!(generation_degree(&CurveScheme::chaikin().symbol()), Some(2));
/// assert_eq!(generation_degree(&Symbol::new(0, vec![1.0, 1.0, 0.5])), None);
/// ```
pub fn generation_degree(symbol: &Symbol) -> Option<usize> {
    symbol.one_plus_z_factors().checked_sub(1)
}

/// Largest `d` such that polynomial data of degree `d` is reproduced, with the
/// parametrisation shift `tau = a'(1)/2` (fine point `m` sits at coarse parameter
/// `(m - tau)/2`): the scheme must generate degree `d` and satisfy
/// `a^{(r)}(1) = 2 tau (tau-1) ... (tau-r+1)` for `r <= d` (Conti & Hormann 2011).
/// `None` if it does not even reproduce constants (`a(1) != 2` or `a(-1) != 0`).
///
/// ```
/// use subdiv_curve::{CurveScheme, analysis::reproduction_degree};
/// assert_eq!(reproduction_degree(&CurveScheme::four_point(1.0 / 16.0)?.symbol()), Some(3));
/// assert_eq!(reproduction_degree(&CurveScheme::cubic_bspline().symbol()), Some(1));
/// assert_eq!(reproduction_degree(&CurveScheme::four_point(0.1)?.symbol()), Some(1));
/// # Ok::<(), subdiv_curve::CurveError>(())
/// ```
pub fn reproduction_degree(symbol: &Symbol) -> Option<usize> {
    let generated = generation_degree(symbol)?;
    let tau = symbol.derivative(1.0, 1) / 2.0;
    let mut reproduced = None;
    for r in 0..=generated as u32 {
        let expected = 2.0 * (0..r).map(|l| tau - l as f64).product::<f64>();
        if (symbol.derivative(1.0, r) - expected).abs() > 1e-10 * symbol.derivative_scale(r) {
            break;
        }
        reproduced = Some(r as usize);
    }
    reproduced
}

/// Outcome of one smoothness check.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// Proven (up to rounding) by a sufficient condition.
    Established,
    /// A necessary condition fails: the property does not hold.
    Refuted,
    /// Neither shown nor disproven within the limits of the check.
    Undecided,
}

/// The difference-scheme test of order `m` (C^m).
#[derive(Debug, Clone, PartialEq)]
pub struct Contractivity {
    /// The smoothness order `m` tested.
    pub order: usize,
    /// Whether `(1+z)^{m+1}` divides the symbol (necessary for C^m).
    pub divisible: bool,
    /// `||b^{[L]}||_inf` for `L = 1, 2, ...` (empty when not divisible).
    pub norms: Vec<f64>,
    /// Smallest `||b^{[L]}||^{1/L}` over the `L` tried (an upper bound of the joint
    /// spectral radius of `b`; `f64::INFINITY` when not divisible).
    pub best_rate: f64,
    /// The `L` attaining `best_rate`.
    pub best_steps: usize,
    /// Largest `ρ(B_w)^{1/|w|}` over products `B_w` of the two finite subdivision matrices of
    /// `b` of length at most 6: a lower bound of the joint spectral radius.
    pub lower_bound: f64,
}

impl Contractivity {
    /// Some `||b^{[L]}||` is below 1: C^m holds.
    pub fn established(&self) -> bool {
        self.divisible && self.norms.iter().any(|&n| n < 1.0 - 1e-12)
    }

    /// The factor is missing, or the joint spectral radius of `b` is at least 1: not C^m.
    pub fn refuted(&self) -> bool {
        !self.divisible || self.lower_bound >= 1.0 - EIGEN_TOLERANCE
    }

    /// Established, refuted or undecided.
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, analysis::{Status, contractivity}};
    /// let cubic = CurveScheme::cubic_bspline().symbol();
    /// assert_eq!(contractivity(&cubic, 2, 6).status(), Status::Established); // C2
    /// assert_eq!(contractivity(&cubic, 3, 6).status(), Status::Refuted); // but not C3
    /// ```
    pub fn status(&self) -> Status {
        if self.established() {
            Status::Established
        } else if self.refuted() {
            Status::Refuted
        } else {
            Status::Undecided
        }
    }
}

/// The difference-scheme test for C^`order`, trying `L = 1..=max_steps` (at most
/// [`MAX_CONTRACTIVITY_STEPS`]).
///
/// ```
/// use subdiv_curve::{CurveScheme, analysis::contractivity};
/// let dlg = CurveScheme::four_point(1.0 / 16.0)?.symbol();
/// let c1 = contractivity(&dlg, 1, 6);
/// assert!(c1.established() && (c1.norms[5].powf(1.0 / 6.0) - 0.69).abs() < 0.01);
/// let c2 = contractivity(&dlg, 2, 6);
/// assert!(c2.refuted() && (c2.norms[5] - 1.0).abs() < 1e-12);
/// # Ok::<(), subdiv_curve::CurveError>(())
/// ```
pub fn contractivity(symbol: &Symbol, order: usize, max_steps: usize) -> Contractivity {
    // The product's support doubles with every step: beyond this many it would only
    // exhaust the memory (the default tries 12).
    let max_steps = max_steps.min(MAX_CONTRACTIVITY_STEPS);
    let mut b = Some(symbol.clone());
    // (Stops once a division fails: `order` may be any number.)
    for _ in 0..=order {
        b = b.and_then(|s| s.divide_by_one_plus_z());
        if b.is_none() {
            break;
        }
    }
    let Some(b) = b.map(|s| s.scaled(2f64.powi(order as i32))) else {
        return Contractivity {
            order,
            divisible: false,
            norms: Vec::new(),
            best_rate: f64::INFINITY,
            best_steps: 0,
            lower_bound: f64::INFINITY,
        };
    };
    let mut norms = Vec::with_capacity(max_steps);
    let mut product = Symbol::new(0, vec![1.0]);
    for steps in 1..=max_steps {
        product = product.times_upsampled(&b, 1 << (steps - 1));
        let period = 1usize << steps;
        let norm = (0..period)
            .map(|r| product.coefficients.iter().skip(r).step_by(period).map(|c| c.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        norms.push(norm);
    }
    let (best_steps, best_rate) = norms
        .iter()
        .enumerate()
        .map(|(k, n)| (k + 1, n.powf(1.0 / (k + 1) as f64)))
        .fold((0, f64::INFINITY), |best, cur| if cur.1 < best.1 { cur } else { best });
    let (left, right) = window_matrices(&b, &neighbourhood_indices(&b));
    let lower_bound = joint_spectral_lower_bound(&left, &right, 6);
    Contractivity { order, divisible: true, norms, best_rate, best_steps, lower_bound }
}

/// The matrices `L_{kj} = a_{k - 2j}`, `R_{kj} = a_{k + 1 - 2j}` on the index window
/// `indices` (closed under both maps when it contains the segment window).
fn window_matrices(symbol: &Symbol, indices: &[i32]) -> (DMatrix<f64>, DMatrix<f64>) {
    let size = indices.len();
    let build =
        |shift: i32| DMatrix::from_fn(size, size, |r, c| symbol.coefficient(indices[r] + shift - 2 * indices[c]));
    (build(0), build(1))
}

/// Labels of the control points whose basis function overlaps the segment `(0, 1)`.
fn segment_indices(symbol: &Symbol) -> Vec<i32> {
    (1 - symbol.highest_power()..=-symbol.lowest_power()).collect()
}

/// Labels of the control points whose basis function overlaps `(-1, 1)`.
fn neighbourhood_indices(symbol: &Symbol) -> Vec<i32> {
    (-symbol.highest_power()..=-symbol.lowest_power()).collect()
}

/// Spectral radius, or `None` when the Schur iteration does not converge (the caller only
/// needs a lower bound and skips the product).
fn spectral_radius(matrix: &DMatrix<f64>) -> Option<f64> {
    bounded_eigenvalues(matrix).map(|values| values.iter().map(|l| l.norm()).fold(0.0, f64::max))
}

/// Eigenvalues by a Schur decomposition with an iteration cap. nalgebra's
/// `complex_eigenvalues` iterates without a cap and never returns on some of the
/// non-normal matrices met here (e.g. window matrices of a divergent four-point scheme);
/// on failure the transpose (same spectrum, different iteration path) is tried.
fn bounded_eigenvalues(matrix: &DMatrix<f64>) -> Option<Vec<Complex<f64>>> {
    let cap = 200 * matrix.nrows().max(1);
    [matrix.clone(), matrix.transpose()].into_iter().find_map(|m| {
        nalgebra::linalg::Schur::try_new(m, f64::EPSILON, cap)
            .map(|schur| schur.complex_eigenvalues().iter().copied().collect())
    })
}

fn joint_spectral_lower_bound(left: &DMatrix<f64>, right: &DMatrix<f64>, max_len: usize) -> f64 {
    let mut best: f64 = 0.0;
    let mut level = vec![DMatrix::identity(left.nrows(), left.ncols())];
    for len in 1..=max_len {
        let mut next = Vec::with_capacity(level.len() * 2);
        for product in &level {
            for factor in [left, right] {
                let p = product * factor;
                if let Some(radius) = spectral_radius(&p) {
                    best = best.max(radius.powf(1.0 / len as f64));
                }
                next.push(p);
            }
        }
        level = next;
    }
    best
}

/// The finite subdivision matrices of one segment (subdivision as an IFS, spec §15): the
/// limit curve on the parameter segment `[0, 1]` depends on the control points
/// `indices` (those whose basis function overlaps `(0, 1)`); `left` maps them to the
/// control points of `[0, 1/2]`, `right` to those of `[1/2, 1]` (same labelling, one level
/// finer): `L_{kj} = a_{k - 2j}`, `R_{kj} = a_{k + 1 - 2j}`. Rows sum to 1.
///
/// Parameters follow the symbol's indexing: control point `j` weighs the basis function
/// `φ(t - j)` with `φ(t) = sum_m a_m φ(2t - m)`, supported on `[lowest, highest]` power.
#[derive(Debug, Clone, PartialEq)]
pub struct SegmentMatrices {
    /// Control point indices of the segment, increasing.
    pub indices: Vec<i32>,
    /// Map to the left half.
    pub left: DMatrix<f64>,
    /// Map to the right half.
    pub right: DMatrix<f64>,
}

/// `L` and `R` of a scheme (see [`SegmentMatrices`]).
///
/// ```
/// use subdiv_curve::{CurveScheme, analysis::ifs_matrices};
/// let m = ifs_matrices(&CurveScheme::cubic_bspline());
/// assert_eq!(m.indices, vec![-1, 0, 1, 2]); // four control points per cubic segment
/// assert_eq!(m.left.row(0).iter().copied().collect::<Vec<_>>(), vec![0.5, 0.5, 0.0, 0.0]);
/// for r in 0..4 {
///     assert!((m.right.row(r).sum() - 1.0).abs() < 1e-15);
/// }
/// ```
pub fn ifs_matrices(scheme: &CurveScheme) -> SegmentMatrices {
    let symbol = scheme.symbol();
    let indices = segment_indices(&symbol);
    let (left, right) = window_matrices(&symbol, &indices);
    SegmentMatrices { indices, left, right }
}

/// A local subdivision matrix with the labels of its rows and columns.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalMatrix {
    /// Labels (offsets from the centre point) of the rows and columns.
    pub indices: Vec<i32>,
    /// `S[k][j]`: weight of coarse point `j` in fine point `k` (same labelling, one level
    /// finer, around the same parameter).
    pub matrix: DMatrix<f64>,
}

/// The subdivision matrix around the regular point `t = 0` (a coarse vertex of a primal
/// scheme, a knot of a dual one), on the control points whose basis functions overlap
/// `(-1, 1)`: `S_{kj} = a_{k - 2j}`. Five points for the cubic B-spline, seven for the
/// four-point scheme, four for Chaikin.
///
/// ```
/// use subdiv_curve::{CurveScheme, analysis::local_matrix};
/// let local = local_matrix(&CurveScheme::cubic_bspline());
/// assert_eq!(local.indices, vec![-2, -1, 0, 1, 2]);
/// assert_eq!(local.matrix[(2, 2)], 0.75);
/// ```
pub fn local_matrix(scheme: &CurveScheme) -> LocalMatrix {
    let symbol = scheme.symbol();
    let indices = neighbourhood_indices(&symbol);
    let size = indices.len();
    let matrix = DMatrix::from_fn(size, size, |r, c| symbol.coefficient(indices[r] - 2 * indices[c]));
    LocalMatrix { indices, matrix }
}

/// Eigenvalues sorted by decreasing modulus (ties: larger real part first); all NaN for
/// a matrix with a NaN or infinite entry, none for a matrix that is not square (or
/// empty): only a square matrix has a spectrum.
///
/// ```
/// use subdiv_curve::{CurveScheme, analysis::{eigenvalues, local_matrix}};
/// let spectrum = eigenvalues(&local_matrix(&CurveScheme::chaikin()).matrix);
/// let moduli: Vec<f64> = spectrum.iter().map(|l| (l.norm() * 1e9).round() / 1e9).collect();
/// assert_eq!(moduli, vec![1.0, 0.5, 0.25, 0.25]);
/// ```
pub fn eigenvalues(matrix: &DMatrix<f64>) -> Vec<Complex<f64>> {
    if !matrix.is_square() || matrix.is_empty() {
        return Vec::new();
    }
    // A NaN or infinite entry has no spectrum; the iterations would not end on it.
    if !matrix.iter().all(|v| v.is_finite()) {
        return vec![Complex::new(f64::NAN, f64::NAN); matrix.nrows().min(matrix.ncols())];
    }
    let mut values = bounded_eigenvalues(matrix).unwrap_or_else(|| {
        // Both orientations stalled: a relative perturbation at rounding level moves simple
        // eigenvalues by as much and unsticks the iteration.
        let scale = matrix.amax().max(f64::MIN_POSITIVE) * 4.0 * f64::EPSILON;
        let nudged = DMatrix::from_fn(matrix.nrows(), matrix.ncols(), |r, c| {
            matrix[(r, c)] + if r == c { scale * (1.0 + r as f64) } else { 0.0 }
        });
        bounded_eigenvalues(&nudged).unwrap_or_else(|| nudged.complex_eigenvalues().iter().copied().collect())
    });
    values.sort_by(|a, b| b.norm().total_cmp(&a.norm()).then(b.re.total_cmp(&a.re)));
    values
}

/// Unit vector spanning (approximately) the null space of `matrix - lambda I`: the right
/// singular vector of the smallest singular value.
fn eigenvector(matrix: &DMatrix<f64>, lambda: f64) -> DVector<f64> {
    let shifted = matrix - DMatrix::identity(matrix.nrows(), matrix.ncols()) * lambda;
    let svd = shifted.svd(false, true);
    let v_t = svd.v_t.expect("internal: V requested");
    let smallest = svd
        .singular_values
        .iter()
        .enumerate()
        .fold(0, |best, (k, s)| if *s < svd.singular_values[best] { k } else { best });
    v_t.row(smallest).transpose()
}

/// Distance of `values` (at positions `positions`) from the polynomials of degree `degree`,
/// relative to the size of `values`, and whether the best fit really has that degree.
fn polynomial_fit(positions: &[f64], values: &DVector<f64>, degree: usize) -> (f64, bool) {
    let vandermonde = DMatrix::from_fn(positions.len(), degree + 1, |r, c| positions[r].powi(c as i32));
    let svd = vandermonde.clone().svd(true, true);
    let Ok(coefficients) = svd.solve(values, 1e-12) else { return (f64::INFINITY, false) };
    let residual = (&vandermonde * &coefficients - values).norm() / values.norm().max(f64::MIN_POSITIVE);
    let scale = coefficients.norm().max(f64::MIN_POSITIVE);
    (residual, coefficients[degree].abs() > 1e-6 * scale)
}

/// The eigen conditions of a local subdivision matrix (necessary for C1 and C2).
#[derive(Debug, Clone, PartialEq)]
pub struct EigenChecks {
    /// `λ0 = 1` and `|λ1| < 1` (affine invariance, convergence at the point).
    pub dominant_one: bool,
    /// `λ1` real in `(0, 1)`, `|λ2| < λ1`, and its eigenvector samples a non-constant
    /// linear function (regular, injective characteristic map).
    pub c1: bool,
    /// `c1`, `λ2 = λ1^2` real, `|λ3| < λ2`, and its eigenvector samples a quadratic.
    pub c2: bool,
    /// Relative distance of the `λ1` eigenvector from linear samples.
    pub linear_residual: f64,
    /// Relative distance of the `λ2` eigenvector from quadratic samples.
    pub quadratic_residual: f64,
}

/// Checks the eigen conditions of `local`. `to_virtual`, when given, maps the local
/// control points to the coordinates in which polynomial eigenvectors are expected (the
/// virtual points of the framework); positions of the points are their labels.
///
/// ```
/// use subdiv_curve::{CurveScheme, analysis::{eigen_checks, local_matrix}};
/// let cubic = eigen_checks(&local_matrix(&CurveScheme::cubic_bspline()), None)?;
/// assert!(cubic.c1 && cubic.c2);
/// let chaikin = eigen_checks(&local_matrix(&CurveScheme::chaikin()), None)?;
/// assert!(chaikin.c1 && !chaikin.c2); // λ2 = λ3 = 1/4
/// # Ok::<(), subdiv_curve::CurveError>(())
/// ```
///
/// # Errors
/// [`CurveError::IncompatibleLength`] when the parts do not fit together (a hand-built
/// [`LocalMatrix`]): the matrix is not square, it is empty, there is not one label per
/// row, or `to_virtual` does not map vectors of that length to vectors of that length.
pub fn eigen_checks(local: &LocalMatrix, to_virtual: Option<&DMatrix<f64>>) -> Result<EigenChecks, CurveError> {
    let (rows, columns) = local.matrix.shape();
    let mismatch = |detail: String| Err(CurveError::IncompatibleLength { what: "eigen checks", detail });
    if rows != columns || rows == 0 {
        return mismatch(format!("the local matrix is {rows} x {columns}, not square and non-empty"));
    }
    if local.indices.len() != rows {
        return mismatch(format!("{} labels for a local matrix of {rows} rows", local.indices.len()));
    }
    if let Some(map) = to_virtual
        && map.shape() != (rows, rows)
    {
        let (r, c) = map.shape();
        return mismatch(format!("the map to virtual points is {r} x {c}, not {rows} x {rows}"));
    }
    Ok(checked_eigen_checks(local, to_virtual))
}

/// [`eigen_checks`] of parts that fit together (as [`local_matrix`] and the framework
/// build them).
pub(crate) fn checked_eigen_checks(local: &LocalMatrix, to_virtual: Option<&DMatrix<f64>>) -> EigenChecks {
    let values = eigenvalues(&local.matrix);
    let lambda = |k: usize| values.get(k).copied().unwrap_or(Complex::new(0.0, 0.0));
    let is_real = |l: Complex<f64>| l.im.abs() <= EIGEN_TOLERANCE;
    let positions: Vec<f64> = local.indices.iter().map(|&j| j as f64).collect();
    let in_virtual = |v: DVector<f64>| match to_virtual {
        Some(map) => map * v,
        None => v,
    };
    let dominant_one =
        (lambda(0) - Complex::new(1.0, 0.0)).norm() <= EIGEN_TOLERANCE && lambda(1).norm() < 1.0 - EIGEN_TOLERANCE;
    let (l1, l2, l3) = (lambda(1), lambda(2), lambda(3));
    let (linear_residual, linear_degree) = if is_real(l1) && values.len() >= 2 {
        polynomial_fit(&positions, &in_virtual(eigenvector(&local.matrix, l1.re)), 1)
    } else {
        (f64::INFINITY, false)
    };
    let c1 = dominant_one
        && is_real(l1)
        && l1.re > EIGEN_GAP
        && l2.norm() < l1.re - EIGEN_GAP
        && linear_residual <= 1e-8
        && linear_degree;
    let (quadratic_residual, quadratic_degree) = if is_real(l2) && values.len() >= 3 {
        polynomial_fit(&positions, &in_virtual(eigenvector(&local.matrix, l2.re)), 2)
    } else {
        (f64::INFINITY, false)
    };
    let c2 = c1
        && is_real(l2)
        && (l2.re - l1.re * l1.re).abs() <= EIGEN_TOLERANCE
        && l3.norm() < l2.re - EIGEN_GAP
        && quadratic_residual <= 1e-8
        && quadratic_degree;
    EigenChecks { dominant_one, c1, c2, linear_residual, quadratic_residual }
}

/// Everything [`analyze`] measures about a uniform scheme.
#[derive(Debug, Clone, PartialEq)]
pub struct Analysis {
    /// The scheme's name.
    pub scheme: String,
    /// Its symbol.
    pub symbol: Symbol,
    /// [`generation_degree`].
    pub generation_degree: Option<usize>,
    /// [`reproduction_degree`].
    pub reproduction_degree: Option<usize>,
    /// Difference-scheme tests for C^0 .. C^[`DEFAULT_MAX_ORDER`].
    pub contractivity: Vec<Contractivity>,
    /// The local subdivision matrix around a regular point.
    pub local: LocalMatrix,
    /// Its eigenvalues, by decreasing modulus.
    pub eigenvalues: Vec<Complex<f64>>,
    /// Eigen conditions of the local matrix.
    pub eigen: EigenChecks,
    /// C1: difference test established and eigen conditions hold.
    pub c1: bool,
    /// C2: difference test established and eigen conditions hold.
    pub c2: bool,
    /// Largest `k` for which C^k is established by the difference test (and, for k = 1, 2,
    /// the eigen conditions); `None` if not even C0 is established.
    pub smoothness: Option<usize>,
}

/// Symbol, degrees, difference tests, local matrix and eigen checks of a scheme.
///
/// ```
/// use subdiv_curve::{CurveScheme, analysis::analyze};
/// let chaikin = analyze(&CurveScheme::chaikin());
/// assert_eq!((chaikin.smoothness, chaikin.c1, chaikin.c2), (Some(1), true, false));
/// ```
pub fn analyze(scheme: &CurveScheme) -> Analysis {
    let symbol = scheme.symbol();
    let contractivity: Vec<Contractivity> =
        (0..=DEFAULT_MAX_ORDER).map(|m| self::contractivity(&symbol, m, DEFAULT_MAX_STEPS)).collect();
    let local = local_matrix(scheme);
    let eigenvalues = eigenvalues(&local.matrix);
    let eigen = checked_eigen_checks(&local, None);
    let smoothness = combine_smoothness(&contractivity, &eigen);
    Analysis {
        scheme: scheme.name().to_string(),
        generation_degree: generation_degree(&symbol),
        reproduction_degree: reproduction_degree(&symbol),
        symbol,
        c1: smoothness.is_some_and(|k| k >= 1),
        c2: smoothness.is_some_and(|k| k >= 2),
        contractivity,
        local,
        eigenvalues,
        eigen,
        smoothness,
    }
}

/// Largest `k` with C^0..C^k all established and, for `k = 1, 2`, the eigen conditions.
pub(crate) fn combine_smoothness(contractivity: &[Contractivity], eigen: &EigenChecks) -> Option<usize> {
    let mut smoothness = None;
    for check in contractivity {
        let eigen_ok = match check.order {
            0 => eigen.dominant_one,
            1 => eigen.c1,
            2 => eigen.c2,
            _ => true,
        };
        if !(check.established() && eigen_ok) {
            break;
        }
        smoothness = Some(check.order);
    }
    smoothness
}

/// The left eigenvector `ℓ` of the local matrix for eigenvalue 1, normalised to sum 1:
/// the limit position of the centre point is `sum_j ℓ_j p_j` (e.g. `(1, 4, 1)/6` for the
/// cubic B-spline). Returned as `(offset of the first entry, weights)` with exact zeros
/// trimmed (entries below `1e-14` are rounded to zero).
///
/// ```
/// use subdiv_curve::{CurveScheme, analysis::limit_stencil};
/// let (offset, weights) = limit_stencil(&CurveScheme::cubic_bspline()).expect("eigenvalue 1 is simple");
/// assert_eq!(offset, -1);
/// assert!((weights[0] - 1.0 / 6.0).abs() < 1e-15 && (weights[1] - 2.0 / 3.0).abs() < 1e-15);
/// ```
pub fn limit_stencil(scheme: &CurveScheme) -> Option<(i32, Vec<f64>)> {
    let local = local_matrix(scheme);
    let n = local.indices.len();
    let mut system = local.matrix.transpose() - DMatrix::identity(n, n);
    let mut rhs = DVector::zeros(n);
    for c in 0..n {
        system[(n - 1, c)] = 1.0;
    }
    rhs[n - 1] = 1.0;
    let weights = system.lu().solve(&rhs)?;
    let weights: Vec<f64> = weights.iter().map(|&w| if w.abs() < 1e-14 { 0.0 } else { w }).collect();
    let first = weights.iter().position(|&w| w != 0.0)?;
    let last = weights.iter().rposition(|&w| w != 0.0)?;
    Some((local.indices[first], weights[first..=last].to_vec()))
}

impl CurveScheme {
    /// The scheme's symbol ([`Symbol::of_scheme`]).
    ///
    /// ```
    /// use subdiv_curve::CurveScheme;
    /// assert_eq!(CurveScheme::chaikin().symbol().eval(-1.0), 0.0);
    /// ```
    pub fn symbol(&self) -> Symbol {
        Symbol::of_scheme(self)
    }
}
