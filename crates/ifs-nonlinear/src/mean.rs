//! Nonlinear subdivision through nonlinear averaging (Schaefer–Vouga–Goldman; seed 003;
//! ALGORITHMS.md §14).
//!
//! A linear scheme whose rules are affine combinations becomes nonlinear when every
//! weighted average `Σ w_j y_j` is replaced by a quasi-arithmetic mean
//! `M_w(y) = F(Σ w_j F^{-1}(y_j))`; the scheme is the conjugate `S_F = F ∘ S ∘ F^{-1}`.
//! [`Mean`] provides the scalar means; [`CircleMean`] the complex, circle- and
//! spiral-preserving geometric mean. [`MeanMode`] says whether a planar point is averaged
//! per coordinate or, as in the seed's functional setting, with x linear and only y
//! through the mean.

use num_complex::Complex64;

use crate::error::{IfsError, Result, check_finite};
use crate::matrices::{ROW_SUM_TOLERANCE, SubdivisionRule};

/// Checks the weights of a weighted mean of `count` values: one finite weight per value, at
/// least one value, and an affine combination (sum 1 within [`ROW_SUM_TOLERANCE`] relative
/// to `Σ |w|`, as for subdivision-matrix rows). An empty list or all-zero weights used to
/// return F(0) (0 for the arithmetic mean, 1 for the geometric) as if it were a mean.
///
/// # Errors
/// [`IfsError::ParameterOutOfRange`] for a length mismatch, no values, or a sum other than
/// 1 (zero, overflowing, ...); [`IfsError::NotFinite`] naming a NaN or infinite weight.
fn check_weights(count: usize, weights: &[f64]) -> Result<()> {
    if weights.len() != count || count == 0 {
        return Err(IfsError::ParameterOutOfRange {
            name: "weights",
            value: format!("{} weights for {} values", weights.len(), count),
            reason: "need one weight per value, at least one value",
        });
    }
    for (j, &w) in weights.iter().enumerate() {
        check_finite(w, || format!("weight {j}"))?;
    }
    let sum: f64 = weights.iter().sum();
    let magnitude: f64 = weights.iter().map(|w| w.abs()).sum();
    if !(magnitude.is_finite() && (sum - 1.0).abs() <= ROW_SUM_TOLERANCE * magnitude.max(1.0)) {
        return Err(IfsError::ParameterOutOfRange {
            name: "weights",
            value: format!("{weights:?} (sum {sum})"),
            reason: "the weights of a mean must sum to 1 (not 0, not overflowing)",
        });
    }
    Ok(())
}

/// A quasi-arithmetic mean `M_w(y) = F(Σ w_j F^{-1}(y_j))` (weights summing to 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mean {
    /// F = identity: the linear scheme.
    Arithmetic,
    /// F = exp, values > 0: `M_t(a, b) = a^{1-t} b^t`. Reproduces `e^{p(x)}` whenever the
    /// linear scheme reproduces the polynomial p.
    Geometric,
    /// F(u) = 1/u, values > 0.
    Harmonic,
    /// F(u) = u^{1/p} (p ≠ 0), values ≥ 0 (> 0 for p < 0); p = 2 is the root-mean-square,
    /// whose inverse square root is the seed's "Gauss" IFS transform. `Power(0.0)` is the
    /// geometric mean (the limit p → 0).
    Power(f64),
    /// F = cos on [0, π], values in [-1, 1]: `M(a, b) = cos((arccos a + arccos b)/2)`
    /// reproduces `cos(p(x))` while p stays in [0, π] (local branch).
    Cosine,
}

impl Mean {
    /// Human-readable name.
    pub fn name(&self) -> String {
        match self {
            Mean::Arithmetic => "arithmetic mean".into(),
            Mean::Geometric => "geometric mean".into(),
            Mean::Harmonic => "harmonic mean".into(),
            Mean::Power(p) => format!("power mean (p = {p})"),
            Mean::Cosine => "cosine mean".into(),
        }
    }

    fn domain(&self) -> &'static str {
        match self {
            Mean::Arithmetic => "finite numbers",
            Mean::Geometric | Mean::Harmonic => "positive numbers",
            Mean::Power(p) if *p < 0.0 => "positive numbers",
            Mean::Power(p) if *p == 0.0 => "positive numbers",
            Mean::Power(_) => "non-negative numbers",
            Mean::Cosine => "numbers in [-1, 1]",
        }
    }

    /// A NaN or infinite power-mean exponent would make every mean NaN or meaningless.
    fn check_exponent(&self) -> Result<()> {
        if let Mean::Power(p) = self {
            check_finite(*p, || "power mean exponent p".into())?;
        }
        Ok(())
    }

    /// F^{-1}: from values to the linear picture, with the domain check.
    ///
    /// # Errors
    /// [`IfsError::Domain`] naming `index` when y is outside the mean's domain (e.g. y ≤ 0
    /// for the geometric mean), not finite, or so close to its edge that F^{-1}(y) is not
    /// finite (e.g. 1/y for a subnormal y); [`IfsError::NotFinite`] for a `Power(p)` with a
    /// NaN or infinite p.
    ///
    /// ```
    /// use ifs_nonlinear::{IfsError, Mean};
    /// assert_eq!(Mean::Geometric.to_linear(1.0, 0)?, 0.0); // ln 1
    /// assert_eq!(Mean::Harmonic.to_linear(4.0, 0)?, 0.25); // 1/4
    /// assert_eq!(Mean::Power(2.0).to_linear(3.0, 0)?, 9.0); // 3²
    /// assert!(matches!(Mean::Geometric.to_linear(-2.0, 7), Err(IfsError::Domain { index: 7, .. })));
    /// # Ok::<(), IfsError>(())
    /// ```
    pub fn to_linear(&self, y: f64, index: usize) -> Result<f64> {
        self.check_exponent()?;
        let ok = y.is_finite()
            && match self {
                Mean::Arithmetic => true,
                Mean::Geometric | Mean::Harmonic => y > 0.0,
                Mean::Power(p) if *p <= 0.0 => y > 0.0,
                Mean::Power(_) => y >= 0.0,
                Mean::Cosine => (-1.0..=1.0).contains(&y),
            };
        if !ok {
            return Err(IfsError::Domain { index, value: y.to_string(), what: self.name(), domain: self.domain() });
        }
        let u = match self {
            Mean::Arithmetic => y,
            Mean::Geometric => y.ln(),
            Mean::Harmonic => 1.0 / y,
            Mean::Power(p) if *p == 0.0 => y.ln(),
            Mean::Power(p) => y.powf(*p),
            Mean::Cosine => y.acos(),
        };
        if !u.is_finite() {
            return Err(IfsError::Domain {
                index,
                value: y.to_string(),
                what: self.name(),
                domain: "values whose image in the linear picture (F^{-1}) is finite",
            });
        }
        Ok(u)
    }

    /// F: from the linear picture back to values.
    ///
    /// # Errors
    /// [`IfsError::Domain`] naming `index` when u is outside F's domain (a negative weight
    /// can push an average outside it, e.g. below 0 for a power mean) or F(u) is not finite;
    /// [`IfsError::NotFinite`] for a `Power(p)` with a NaN or infinite p.
    ///
    /// ```
    /// use ifs_nonlinear::{IfsError, Mean};
    /// // F undoes F^{-1}: a round trip through the linear picture.
    /// for mean in [Mean::Geometric, Mean::Harmonic, Mean::Power(2.0), Mean::Cosine] {
    ///     let u = mean.to_linear(0.5, 0)?;
    ///     assert!((mean.from_linear(u, 0)? - 0.5).abs() < 1e-15, "{}", mean.name());
    /// }
    /// // An average pushed below 0 has no image under F(u) = u^{1/2} (p = 2).
    /// assert!(matches!(Mean::Power(2.0).from_linear(-0.1, 3), Err(IfsError::Domain { index: 3, .. })));
    /// # Ok::<(), IfsError>(())
    /// ```
    pub fn from_linear(&self, u: f64, index: usize) -> Result<f64> {
        self.check_exponent()?;
        let y = match self {
            Mean::Arithmetic => u,
            Mean::Geometric => u.exp(),
            Mean::Harmonic => 1.0 / u,
            Mean::Power(p) if *p == 0.0 => u.exp(),
            Mean::Power(p) => u.powf(1.0 / p),
            Mean::Cosine => u.cos(),
        };
        let ok = y.is_finite()
            && match self {
                Mean::Harmonic => u > 0.0,
                Mean::Power(p) if *p != 0.0 => u >= 0.0,
                _ => true,
            };
        if !ok {
            return Err(IfsError::Domain {
                index,
                value: format!("{u} (averaged)"),
                what: self.name(),
                domain: "the image of the mean's inverse map",
            });
        }
        Ok(y)
    }

    /// The two-point mean `M_t(a, b) = F((1-t) F^{-1}(a) + t F^{-1}(b))`; t outside [0, 1]
    /// extrapolates.
    ///
    /// # Errors
    /// [`IfsError::NotFinite`] for a NaN or infinite t (or power-mean exponent);
    /// [`IfsError::Domain`] (index 0 for a, 1 for b; index 0 when the result is not finite).
    ///
    /// ```
    /// use ifs_nonlinear::Mean;
    /// assert_eq!(Mean::Geometric.mean(2.0, 8.0, 0.5)?, 4.0);
    /// assert!((Mean::Harmonic.mean(1.0, 3.0, 0.5)? - 1.5).abs() < 1e-15);
    /// assert!(Mean::Geometric.mean(-1.0, 2.0, 0.5).is_err());
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn mean(&self, a: f64, b: f64, t: f64) -> Result<f64> {
        check_finite(t, || "mean parameter t".into())?;
        if let Mean::Geometric = self {
            let (log_a, log_b) = (self.to_linear(a, 0)?, self.to_linear(b, 1)?);
            // Exact for the common midpoint case, unless a·b overflows or underflows.
            let product = a * b;
            let direct = if t == 0.5 && product.is_finite() && product > 0.0 {
                product.sqrt()
            } else {
                a.powf(1.0 - t) * b.powf(t)
            };
            if direct.is_finite() && direct > 0.0 {
                return Ok(direct);
            }
            // The powers overflowed or underflowed on their own: go through the logarithms,
            // which either fit or give a typed error (e.g. t = -2 with a = 1e300).
            return self.from_linear((1.0 - t) * log_a + t * log_b, 0);
        }
        let u = (1.0 - t) * self.to_linear(a, 0)? + t * self.to_linear(b, 1)?;
        self.from_linear(u, 0)
    }

    /// The weighted mean `F(Σ w_j F^{-1}(y_j))`. Indices in errors are positions in `values`.
    /// The weights must form an affine combination (sum 1): F(Σ w_j u_j) with other sums
    /// is not a mean (all-zero weights gave F(0) for any values).
    ///
    /// # Errors
    /// [`IfsError::Domain`]; [`IfsError::ParameterOutOfRange`] when the lengths differ, there
    /// is no value, or the weights do not sum to 1 (e.g. all zero); [`IfsError::NotFinite`]
    /// naming a NaN or infinite weight.
    ///
    /// ```
    /// use ifs_nonlinear::Mean;
    /// // The seed's quadratic middle point: y0^{1/4} y1^{1/2} y2^{1/4}.
    /// let m = Mean::Geometric.weighted(&[1.0, 4.0, 16.0], &[0.25, 0.5, 0.25])?;
    /// assert!((m - 4.0).abs() < 1e-14);
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn weighted(&self, values: &[f64], weights: &[f64]) -> Result<f64> {
        check_weights(values.len(), weights)?;
        let mut u = 0.0;
        for (j, (&y, &w)) in values.iter().zip(weights).enumerate() {
            if w != 0.0 {
                u += w * self.to_linear(y, j)?;
            }
        }
        self.from_linear(u, 0)
    }
}

/// How a planar point is averaged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MeanMode {
    /// Both coordinates through the mean.
    PerCoordinate,
    /// The functional setting of seed 003: x averaged linearly, only y through the mean.
    #[default]
    YOnly,
}

/// One planar weighted average under `mean` and `mode`; `indices` maps weight positions to
/// input point indices for error messages.
fn average_points(
    points: &[[f64; 2]],
    indices: &[usize],
    weights: &[f64],
    mean: Mean,
    mode: MeanMode,
) -> Result<[f64; 2]> {
    let mut linear = [0.0; 2];
    for coordinate in 0..2 {
        let through_mean = coordinate == 1 || mode == MeanMode::PerCoordinate;
        let m = if through_mean { mean } else { Mean::Arithmetic };
        let mut u = 0.0;
        for ((&w, &i), p) in weights.iter().zip(indices).zip(indices.iter().map(|&i| points[i])) {
            if w != 0.0 {
                u += w * m.to_linear(p[coordinate], i)?;
            }
        }
        linear[coordinate] = m.from_linear(u, indices[0])?;
    }
    Ok(linear)
}

fn check_input(points: &[[f64; 2]], what: &'static str, needed: usize) -> Result<()> {
    if points.len() < needed {
        return Err(IfsError::TooFewPoints { what, needed, got: points.len() });
    }
    for (i, p) in points.iter().enumerate() {
        for (k, &v) in p.iter().enumerate() {
            crate::error::check_finite(v, || format!("point {i}, coordinate {k}"))?;
        }
    }
    Ok(())
}

/// The two-point nonlinear scheme (seed maps f_1, f_2 on every segment): keeps the points
/// and inserts the mean of each neighbour pair, `n` points → `2n - 1`.
///
/// # Errors
/// [`IfsError::TooFewPoints`] below 2 points, [`IfsError::NotFinite`], and
/// [`IfsError::Domain`] naming the first offending point.
///
/// ```
/// use ifs_nonlinear::{Mean, MeanMode, two_point_subdivide};
/// // Samples of y = 3 e^{0.7 x}: the inserted points lie on the same exponential.
/// let points: Vec<[f64; 2]> = (0..4).map(|i| [i as f64, 3.0 * (0.7 * i as f64).exp()]).collect();
/// let fine = two_point_subdivide(&points, Mean::Geometric, MeanMode::YOnly)?;
/// assert_eq!(fine.len(), 7);
/// assert!((fine[1][1] - 3.0 * (0.35f64).exp()).abs() < 1e-14);
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn two_point_subdivide(points: &[[f64; 2]], mean: Mean, mode: MeanMode) -> Result<Vec<[f64; 2]>> {
    check_input(points, "the two-point scheme", 2)?;
    let mut out = Vec::with_capacity(2 * points.len() - 1);
    for i in 0..points.len() - 1 {
        out.push(points[i]);
        out.push(average_points(points, &[i, i + 1], &[0.5, 0.5], mean, mode)?);
    }
    out.push(*points.last().expect("internal: at least two points"));
    Ok(out)
}

/// The three-point (quadratic) nonlinear scheme: the polyline `p_0 … p_{2n}` is read as n
/// quadratic Bézier pieces `(p_{2i}, p_{2i+1}, p_{2i+2})`, each split at 1/2 with the mean
/// replacing the de Casteljau averages; `2n + 1` points → `4n + 1`. The middle new point
/// of a piece is `M_{1/4,1/2,1/4}(p_0, p_1, p_2)`, e.g. `y_0^{1/4} y_1^{1/2} y_2^{1/4}` for
/// the geometric mean (seed 003).
///
/// # Errors
/// [`IfsError::TooFewPoints`] below 3 points; [`IfsError::ParameterOutOfRange`] for an
/// even number of points; [`IfsError::NotFinite`]; [`IfsError::Domain`].
///
/// ```
/// use ifs_nonlinear::{Mean, MeanMode, three_point_subdivide};
/// let fine = three_point_subdivide(&[[0.0, 1.0], [1.0, 4.0], [2.0, 16.0]], Mean::Geometric, MeanMode::YOnly)?;
/// assert_eq!(fine.len(), 5);
/// assert!((fine[2][1] - 4.0).abs() < 1e-14 && fine[2][0] == 1.0);
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn three_point_subdivide(points: &[[f64; 2]], mean: Mean, mode: MeanMode) -> Result<Vec<[f64; 2]>> {
    check_input(points, "the three-point scheme", 3)?;
    if points.len().is_multiple_of(2) {
        return Err(IfsError::ParameterOutOfRange {
            name: "points",
            value: points.len().to_string(),
            reason: "the three-point scheme needs an odd number of points (quadratic pieces sharing ends)",
        });
    }
    let mut out = Vec::with_capacity(2 * points.len() - 1);
    for piece in 0..points.len() / 2 {
        let i = 2 * piece;
        out.push(points[i]);
        out.push(average_points(points, &[i, i + 1], &[0.5, 0.5], mean, mode)?);
        out.push(average_points(points, &[i, i + 1, i + 2], &[0.25, 0.5, 0.25], mean, mode)?);
        out.push(average_points(points, &[i + 1, i + 2], &[0.5, 0.5], mean, mode)?);
    }
    out.push(*points.last().expect("internal: at least three points"));
    Ok(out)
}

/// Any linear subdivision rule made nonlinear: the control polygon (m points) becomes the
/// K sub-polygons whose rows are `M_{row of S_i}(P)`.
///
/// # Errors
/// [`IfsError::ControlCountMismatch`], [`IfsError::NotFinite`], [`IfsError::Domain`].
///
/// ```
/// use ifs_nonlinear::{Mean, MeanMode, bezier_split, subdivide_with_rule};
/// let pieces = subdivide_with_rule(&bezier_split(1, 0.5)?, &[[0.0, 1.0], [2.0, 9.0]], Mean::Geometric, MeanMode::YOnly)?;
/// // Left half of the segment: the first point and the geometric midpoint (1, sqrt(1 * 9)).
/// assert_eq!(pieces[0][0], [0.0, 1.0]);
/// assert!((pieces[0][1][0] - 1.0).abs() < 1e-15 && (pieces[0][1][1] - 3.0).abs() < 1e-14);
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn subdivide_with_rule(
    rule: &SubdivisionRule<f64>,
    control: &[[f64; 2]],
    mean: Mean,
    mode: MeanMode,
) -> Result<Vec<Vec<[f64; 2]>>> {
    check_input(control, "nonlinear subdivision", 1)?;
    if control.len() != rule.size() {
        return Err(IfsError::ControlCountMismatch { expected: rule.size(), got: control.len() });
    }
    let indices: Vec<usize> = (0..control.len()).collect();
    rule.matrices()
        .iter()
        .map(|s| {
            (0..s.nrows())
                .map(|r| {
                    let weights: Vec<f64> = s.row(r).iter().copied().collect();
                    average_points(control, &indices, &weights, mean, mode)
                })
                .collect()
        })
        .collect()
}

/// The complex geometric mean about a centre c: circle- and spiral-preserving
/// (ALGORITHMS.md §14.3). `M_t(a, b) = c + |a-c|^{1-t} |b-c|^t e^{i(arg(a-c) + tΔθ)}` with
/// `Δθ = arg((b-c)/(a-c)) ∈ (-π, π)`: points on a circle about c stay on it with linearly
/// interpolated angle; different radii give logarithmic spirals.
///
/// The centre is private and checked by [`CircleMean::new`]: a NaN centre made every mean
/// NaN.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CircleMean {
    center: Complex64,
}

impl CircleMean {
    /// Mean about `center`.
    ///
    /// # Errors
    /// [`IfsError::NotFinite`] for a NaN or infinite centre coordinate.
    ///
    /// ```
    /// use ifs_nonlinear::{CircleMean, IfsError};
    /// use num_complex::Complex64;
    /// assert_eq!(CircleMean::new(Complex64::new(1.0, 2.0))?.center(), Complex64::new(1.0, 2.0));
    /// assert!(matches!(CircleMean::new(Complex64::new(f64::NAN, 0.0)), Err(IfsError::NotFinite { .. })));
    /// # Ok::<(), IfsError>(())
    /// ```
    pub fn new(center: Complex64) -> Result<Self> {
        check_finite(center.re, || "circle-mean centre, real part".into())?;
        check_finite(center.im, || "circle-mean centre, imaginary part".into())?;
        Ok(Self { center })
    }

    /// The centre c.
    pub fn center(&self) -> Complex64 {
        self.center
    }

    /// Weighted mean `c + exp(Σ w_j log_j(p_j - c))` where each logarithm takes the branch
    /// nearest to the first point's (so that the two-point case is the formula above).
    ///
    /// The weights must sum to 1, as for [`Mean::weighted`].
    ///
    /// # Errors
    /// [`IfsError::Domain`] naming the point that coincides with the centre, or whose angle
    /// from the first point is ±π (the mean is then undefined), and (index 0) when the mean
    /// is not finite (extreme weights); [`IfsError::NotFinite`] for a NaN or infinite point
    /// or weight; [`IfsError::ParameterOutOfRange`] when the lengths differ, there is no
    /// point, or the weights do not sum to 1.
    ///
    /// ```
    /// use ifs_nonlinear::CircleMean;
    /// use num_complex::Complex64;
    /// let mean = CircleMean::new(Complex64::new(0.0, 0.0))?;
    /// let m = mean.weighted(&[Complex64::new(1.0, 0.0), Complex64::new(0.0, 1.0)], &[0.5, 0.5])?;
    /// let expected = Complex64::from_polar(1.0, std::f64::consts::FRAC_PI_4);
    /// assert!((m - expected).norm() < 1e-15);
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn weighted(&self, points: &[Complex64], weights: &[f64]) -> Result<Complex64> {
        check_weights(points.len(), weights)?;
        let reference = self.relative(points[0], 0)?;
        let mut log_sum = Complex64::new(0.0, 0.0);
        for (j, (&p, &w)) in points.iter().zip(weights).enumerate() {
            let q = self.relative(p, j)?;
            let delta = angle_between(q, reference);
            if delta.abs() >= std::f64::consts::PI - 1e-12 {
                return Err(IfsError::Domain {
                    index: j,
                    value: format!("{p}"),
                    what: "circle-preserving mean".into(),
                    domain: "points less than half a turn (angle < π about the centre) from the first point",
                });
            }
            log_sum += w * Complex64::new(q.norm().ln(), reference.arg() + delta);
        }
        let mean = self.center + log_sum.exp();
        if !(mean.re.is_finite() && mean.im.is_finite()) {
            return Err(IfsError::Domain {
                index: 0,
                value: format!("{log_sum} (averaged logarithm)"),
                what: "circle-preserving mean".into(),
                domain: "averages whose exponential is finite",
            });
        }
        Ok(mean)
    }

    /// Two-point mean with parameter t.
    ///
    /// # Errors
    /// As [`weighted`](Self::weighted).
    ///
    /// ```
    /// use ifs_nonlinear::{CircleMean, IfsError};
    /// use num_complex::Complex64;
    /// // About c = 1 + i: radii 1 and 4, a quarter turn apart; the midpoint has radius 2 at 45°.
    /// let c = Complex64::new(1.0, 1.0);
    /// let mean = CircleMean::new(c)?;
    /// let m = mean.mean(c + 1.0, c + Complex64::new(0.0, 4.0), 0.5)?;
    /// assert!((m - (c + Complex64::from_polar(2.0, std::f64::consts::FRAC_PI_4))).norm() < 1e-14);
    /// assert!(matches!(mean.mean(c, c + 1.0, 0.5), Err(IfsError::Domain { index: 0, .. }))); // the centre itself
    /// # Ok::<(), IfsError>(())
    /// ```
    pub fn mean(&self, a: Complex64, b: Complex64, t: f64) -> Result<Complex64> {
        self.weighted(&[a, b], &[1.0 - t, t])
    }

    fn relative(&self, p: Complex64, index: usize) -> Result<Complex64> {
        if !(p.re.is_finite() && p.im.is_finite()) {
            return Err(IfsError::NotFinite {
                what: format!("point {index}"),
                value: if p.re.is_finite() { p.im } else { p.re },
            });
        }
        let q = p - self.center;
        if q.norm() == 0.0 {
            return Err(IfsError::Domain {
                index,
                value: format!("{p}"),
                what: "circle-preserving mean".into(),
                domain: "points other than the centre",
            });
        }
        // Finite point and centre, but an offset beyond f64 (e.g. 1e308 about -1e308).
        if !q.norm().is_finite() {
            return Err(IfsError::Domain {
                index,
                value: format!("{p}"),
                what: "circle-preserving mean".into(),
                domain: "points whose offset from the centre is finite",
            });
        }
        Ok(q)
    }

    /// The two-point scheme with this mean: keeps the points and inserts the mean of each
    /// neighbour pair (`n` → `2n - 1` points).
    ///
    /// # Errors
    /// [`IfsError::TooFewPoints`] below 2 points, and as [`weighted`](Self::weighted)
    /// (indices are input positions).
    ///
    /// ```
    /// use ifs_nonlinear::CircleMean;
    /// use num_complex::Complex64;
    /// // Points on the unit circle at angles 0, 1, 2: the new points bisect the angles.
    /// let mean = CircleMean::new(Complex64::new(0.0, 0.0))?;
    /// let coarse: Vec<Complex64> = (0..3).map(|k| Complex64::from_polar(1.0, k as f64)).collect();
    /// let fine = mean.two_point_subdivide(&coarse)?;
    /// assert_eq!(fine.len(), 5);
    /// assert!(fine.iter().enumerate().all(|(k, p)| (p - Complex64::from_polar(1.0, k as f64 / 2.0)).norm() < 1e-15));
    /// assert!(mean.two_point_subdivide(&coarse[..1]).is_err());
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn two_point_subdivide(&self, points: &[Complex64]) -> Result<Vec<Complex64>> {
        if points.len() < 2 {
            return Err(IfsError::TooFewPoints { what: "the two-point scheme", needed: 2, got: points.len() });
        }
        let mut out = Vec::with_capacity(2 * points.len() - 1);
        for i in 0..points.len() - 1 {
            out.push(points[i]);
            let m = self.mean(points[i], points[i + 1], 0.5).map_err(|e| shift_index(e, i))?;
            out.push(m);
        }
        out.push(points[points.len() - 1]);
        Ok(out)
    }

    /// The three-point (quadratic) scheme with this mean: as [`three_point_subdivide`], the
    /// polyline `p_0 … p_{2n}` is read as quadratic pieces split at 1/2, every de Casteljau
    /// average replaced by the circle-preserving mean (`2n + 1` → `4n + 1` points).
    ///
    /// # Errors
    /// [`IfsError::TooFewPoints`] below 3 points; [`IfsError::ParameterOutOfRange`] for an
    /// even number of points; as [`weighted`](Self::weighted) (indices are input positions).
    ///
    /// ```
    /// use ifs_nonlinear::CircleMean;
    /// use num_complex::Complex64;
    /// let mean = CircleMean::new(Complex64::new(0.0, 0.0))?;
    /// let arc: Vec<Complex64> = [0.0, 0.5, 1.0].iter().map(|&a| Complex64::from_polar(2.0, a)).collect();
    /// let fine = mean.three_point_subdivide(&arc)?;
    /// assert!(fine.iter().all(|p| (p.norm() - 2.0).abs() < 1e-14));
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn three_point_subdivide(&self, points: &[Complex64]) -> Result<Vec<Complex64>> {
        if points.len() < 3 {
            return Err(IfsError::TooFewPoints { what: "the three-point scheme", needed: 3, got: points.len() });
        }
        if points.len().is_multiple_of(2) {
            return Err(IfsError::ParameterOutOfRange {
                name: "points",
                value: points.len().to_string(),
                reason: "the three-point scheme needs an odd number of points (quadratic pieces sharing ends)",
            });
        }
        let mut out = Vec::with_capacity(2 * points.len() - 1);
        for piece in 0..points.len() / 2 {
            let i = 2 * piece;
            let (a, b, c) = (points[i], points[i + 1], points[i + 2]);
            out.push(a);
            out.push(self.mean(a, b, 0.5).map_err(|e| shift_index(e, i))?);
            out.push(self.weighted(&[a, b, c], &[0.25, 0.5, 0.25]).map_err(|e| shift_index(e, i))?);
            out.push(self.mean(b, c, 0.5).map_err(|e| shift_index(e, i + 1))?);
        }
        out.push(points[points.len() - 1]);
        Ok(out)
    }
}

/// `arg(q / reference)`. The quotient is formed directly, as always, unless it overflows or
/// underflows (`Complex64` division squares the divisor, so points near 1e160 from the
/// centre gave NaN); then from the unit vectors, which cannot.
fn angle_between(q: Complex64, reference: Complex64) -> f64 {
    let quotient = q / reference;
    if quotient.re.is_finite() && quotient.im.is_finite() && quotient != Complex64::new(0.0, 0.0) {
        quotient.arg()
    } else {
        (q.unscale(q.norm()) / reference.unscale(reference.norm())).arg()
    }
}

fn shift_index(error: IfsError, by: usize) -> IfsError {
    match error {
        IfsError::Domain { index, value, what, domain } => IfsError::Domain { index: index + by, value, what, domain },
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matrices::bezier_split;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * a.abs().max(b.abs()).max(1.0)
    }

    /// Samples of y = c e^{λx} stay exactly on the curve at every level (geometric mean).
    #[test]
    fn geometric_mean_reproduces_exponentials() {
        let (c, lambda) = (2.5, -1.3);
        let f = |x: f64| c * (lambda * x).exp();
        let mut points: Vec<[f64; 2]> = [-1.0, 0.0, 0.5, 2.0].iter().map(|&x| [x, f(x)]).collect();
        for _ in 0..6 {
            points = two_point_subdivide(&points, Mean::Geometric, MeanMode::YOnly).unwrap();
            assert!(points.iter().all(|p| close(p[1], f(p[0]), 4e-15)));
        }
        assert_eq!(points.len(), 3 * 64 + 1);
    }

    /// The quadratic rule reproduces exp(quadratic): with Bézier coefficients of q in the
    /// log picture, every piece end lies on e^{q(x)} and every value is exp of the linear
    /// scheme's value (conjugation).
    #[test]
    fn quadratic_rule_reproduces_exp_of_a_quadratic() {
        // q(x) = -x²/2 on [-2, 2]: Bézier coefficients (-2, 2, -2) at x = -2, 0, 2.
        let q = |x: f64| -x * x / 2.0;
        let linear: Vec<[f64; 2]> = vec![[-2.0, -2.0], [0.0, 2.0], [2.0, -2.0]];
        let mut points: Vec<[f64; 2]> = linear.iter().map(|p| [p[0], p[1].exp()]).collect();
        let mut lin = linear;
        for _ in 0..5 {
            points = three_point_subdivide(&points, Mean::Geometric, MeanMode::YOnly).unwrap();
            lin = three_point_subdivide(&lin, Mean::Arithmetic, MeanMode::YOnly).unwrap();
            for (p, l) in points.iter().zip(&lin) {
                assert!(close(p[1], l[1].exp(), 1e-14) && p[0] == l[0]);
            }
            for end in points.iter().step_by(2) {
                assert!(close(end[1], q(end[0]).exp(), 1e-13), "{end:?}");
            }
        }
    }

    /// Conjugation identity S_F(y) = F(S(F^{-1}(y))) for every mean, in both modes.
    #[test]
    fn conjugation_identity() {
        let points = [[0.1, 0.2], [0.3, 0.9], [0.45, 0.4], [0.7, 0.7], [0.9, 0.1]];
        let means =
            [Mean::Arithmetic, Mean::Geometric, Mean::Harmonic, Mean::Power(2.0), Mean::Power(-0.5), Mean::Cosine];
        for mean in means {
            for mode in [MeanMode::YOnly, MeanMode::PerCoordinate] {
                let nonlinear = three_point_subdivide(&points, mean, mode).unwrap();
                let x_mean = if mode == MeanMode::PerCoordinate { mean } else { Mean::Arithmetic };
                let linear_in: Vec<[f64; 2]> = points
                    .iter()
                    .enumerate()
                    .map(|(i, p)| [x_mean.to_linear(p[0], i).unwrap(), mean.to_linear(p[1], i).unwrap()])
                    .collect();
                let linear = three_point_subdivide(&linear_in, Mean::Arithmetic, MeanMode::PerCoordinate).unwrap();
                for (a, b) in nonlinear.iter().zip(&linear) {
                    assert!(close(a[0], x_mean.from_linear(b[0], 0).unwrap(), 1e-13), "{mean:?} {a:?} {b:?}");
                    assert!(close(a[1], mean.from_linear(b[1], 0).unwrap(), 1e-13), "{mean:?} {a:?} {b:?}");
                }
            }
        }
    }

    #[test]
    fn domain_errors_name_the_point() {
        let points = [[0.0, 1.0], [1.0, 2.0], [2.0, -3.0], [3.0, 1.0]];
        let err = two_point_subdivide(&points, Mean::Geometric, MeanMode::YOnly).unwrap_err();
        assert!(matches!(err, IfsError::Domain { index: 2, .. }), "{err}");
        assert!(err.to_string().contains("point 2"));
        let err = two_point_subdivide(&[[0.0, 1.0], [0.0, 0.0]], Mean::Harmonic, MeanMode::YOnly).unwrap_err();
        assert!(matches!(err, IfsError::Domain { index: 1, .. }));
        assert!(two_point_subdivide(&[[0.0, 2.0], [1.0, 0.5]], Mean::Cosine, MeanMode::YOnly).is_err());
        assert!(three_point_subdivide(&[[0.0, 1.0], [1.0, 1.0]], Mean::Geometric, MeanMode::YOnly).is_err());
        assert!(matches!(
            three_point_subdivide(&[[0.0, 1.0], [1.0, 1.0], [2.0, 1.0], [3.0, 1.0]], Mean::Geometric, MeanMode::YOnly),
            Err(IfsError::ParameterOutOfRange { .. })
        ));
        assert!(matches!(
            two_point_subdivide(&[[0.0, f64::NAN], [1.0, 1.0]], Mean::Geometric, MeanMode::YOnly),
            Err(IfsError::NotFinite { .. })
        ));
        // Per coordinate, x = 0 is outside the geometric mean's domain.
        let err = two_point_subdivide(&[[1.0, 1.0], [0.0, 1.0]], Mean::Geometric, MeanMode::PerCoordinate).unwrap_err();
        assert!(matches!(err, IfsError::Domain { index: 1, .. }));
    }

    /// Every mean used to "average" an empty list or all-zero weights to F(0) (`Ok(0)` for
    /// the arithmetic mean, `Ok(1)` for the geometric); NaN weights came back as a domain
    /// error about the average.
    #[test]
    fn weights_must_be_finite_and_sum_to_one() {
        let means =
            [Mean::Arithmetic, Mean::Geometric, Mean::Harmonic, Mean::Power(2.0), Mean::Power(-0.5), Mean::Cosine];
        for mean in means {
            let out_of_range = |result: Result<f64>| matches!(result, Err(IfsError::ParameterOutOfRange { .. }));
            assert!(out_of_range(mean.weighted(&[], &[])), "{mean:?}");
            assert!(out_of_range(mean.weighted(&[0.5, 0.25], &[0.0, 0.0])), "{mean:?}");
            assert!(out_of_range(mean.weighted(&[0.5, 0.25], &[1.0, 1.0])), "{mean:?}");
            assert!(out_of_range(mean.weighted(&[0.5], &[0.5, 0.5])), "{mean:?}");
            let nan_weight = mean.weighted(&[0.5, 0.25], &[0.5, f64::NAN]);
            assert!(matches!(&nan_weight, Err(IfsError::NotFinite { what, .. }) if what == "weight 1"), "{mean:?}");
            let t_nan = mean.mean(0.5, 0.25, f64::NAN);
            assert!(matches!(&t_nan, Err(IfsError::NotFinite { what, .. }) if what == "mean parameter t"));
            // Affine weights (negative ones included) still work.
            assert!(mean.weighted(&[0.5, 0.25, 0.5], &[-0.25, 1.0, 0.25]).is_ok(), "{mean:?}");
        }
        assert_eq!(Mean::Arithmetic.weighted(&[2.0, 4.0], &[0.25, 0.75]).unwrap(), 3.5);
        for p in [f64::NAN, f64::INFINITY] {
            let exponent = |result: Result<f64>| matches!(result, Err(IfsError::NotFinite { .. }));
            assert!(exponent(Mean::Power(p).to_linear(1.0, 0)), "{p}"); // 1^NaN = 1 used to pass
            assert!(exponent(Mean::Power(p).weighted(&[1.0, 0.5], &[0.5, 0.5])), "{p}");
        }
    }

    /// The geometric midpoint sqrt(a b) overflowed for a = b = 1e200 (`Ok(inf)`), and
    /// extrapolation gave `Ok(inf)`; the harmonic 1/y of a subnormal y was infinite.
    #[test]
    fn means_of_finite_values_are_finite_or_errors() {
        assert_eq!(Mean::Geometric.mean(1e200, 1e200, 0.5).unwrap(), 1e200);
        assert_eq!(Mean::Geometric.mean(1e-200, 1e-200, 0.5).unwrap(), 1e-200);
        assert!(matches!(Mean::Geometric.mean(1e300, 1e-300, -2.0), Err(IfsError::Domain { index: 0, .. })));
        assert!(matches!(Mean::Harmonic.to_linear(5e-324, 3), Err(IfsError::Domain { index: 3, .. })));
        assert_eq!(Mean::Geometric.mean(2.0, 8.0, 0.5).unwrap(), 4.0);
    }

    /// `CircleMean::new` accepted a NaN centre (every mean NaN); zero weights gave the
    /// centre + 1; points 1e300 from the centre gave NaN (complex division overflow).
    #[test]
    fn circle_mean_checks_centre_weights_and_range() {
        let nan_centre = CircleMean::new(Complex64::new(0.0, f64::NAN));
        assert!(matches!(&nan_centre, Err(IfsError::NotFinite { what, .. }) if what.contains("imaginary")));
        let mean = CircleMean::new(Complex64::new(0.0, 0.0)).unwrap();
        let (a, b) = (Complex64::new(1.0, 0.0), Complex64::new(0.0, 1.0));
        assert!(matches!(mean.weighted(&[a, b], &[0.0, 0.0]), Err(IfsError::ParameterOutOfRange { .. })));
        assert!(matches!(mean.weighted(&[a, b], &[f64::NAN, 1.0]), Err(IfsError::NotFinite { .. })));
        assert!(matches!(mean.weighted(&[], &[]), Err(IfsError::ParameterOutOfRange { .. })));
        let far = mean.mean(Complex64::new(1e300, 0.0), Complex64::new(0.0, 1e300), 0.5).unwrap();
        let expected = Complex64::from_polar(1e300, std::f64::consts::FRAC_PI_4);
        assert!((far - expected).norm() <= 1e-12 * 1e300, "{far}"); // exp(690.8): ~1e-13 relative
        // Extrapolating far beyond f64: an error, not infinity.
        let overflow = mean.mean(Complex64::new(1e300, 0.0), Complex64::new(1e-300, 0.0), -2.0);
        assert!(matches!(overflow, Err(IfsError::Domain { index: 0, .. })), "{overflow:?}");
        let offset = CircleMean::new(Complex64::new(-1e308, 0.0)).unwrap().mean(Complex64::new(1e308, 0.0), b, 0.5);
        assert!(matches!(offset, Err(IfsError::Domain { index: 0, .. })), "{offset:?}");
    }

    #[test]
    fn power_means_interpolate_between_the_classical_ones() {
        let (a, b) = (1.0, 9.0);
        assert!(close(Mean::Power(1.0).mean(a, b, 0.5).unwrap(), 5.0, 1e-15));
        assert!(close(Mean::Power(-1.0).mean(a, b, 0.5).unwrap(), Mean::Harmonic.mean(a, b, 0.5).unwrap(), 1e-15));
        assert!(close(Mean::Power(0.0).mean(a, b, 0.5).unwrap(), 3.0, 1e-15));
        assert!(close(Mean::Power(2.0).mean(a, b, 0.5).unwrap(), 41.0f64.sqrt(), 1e-15));
        assert!(close(Mean::Power(1e-4).mean(a, b, 0.5).unwrap(), 3.0, 1e-3));
        // Cosine mean reproduces cos of a linear function.
        let m = Mean::Cosine.mean(0.3f64.cos(), 1.1f64.cos(), 0.5).unwrap();
        assert!(close(m, 0.7f64.cos(), 1e-15));
    }

    /// The circle-preserving mean reproduces circular arcs: after several levels of the
    /// two-point scheme every point is on the circle, at uniformly interpolated angles.
    #[test]
    fn circle_mean_reproduces_arcs_and_spirals() {
        let c = Complex64::new(1.0, -2.0);
        let mean = CircleMean::new(c).unwrap();
        let radius = 1.7;
        let angles = [0.1, 1.3, 2.9, 4.0];
        let mut points: Vec<Complex64> = angles.iter().map(|&a| c + Complex64::from_polar(radius, a)).collect();
        for _ in 0..5 {
            points = mean.two_point_subdivide(&points).unwrap();
            assert!(points.iter().all(|p| ((p - c).norm() - radius).abs() < 1e-13));
        }
        // Angles between the original 0.1 and 1.3 are uniform: 32 steps of 1.2/32.
        for (i, p) in points.iter().take(33).enumerate() {
            let expected = 0.1 + 1.2 * i as f64 / 32.0;
            assert!(((p - c).arg() - expected).abs() < 1e-13);
        }
        // Different radii: logarithmic spiral r = r0 e^{kθ}.
        let spiral = |theta: f64| c + Complex64::from_polar(0.5 * (0.3 * theta).exp(), theta);
        let mut points: Vec<Complex64> = [0.0, 1.0, 2.0].iter().map(|&t| spiral(t)).collect();
        for _ in 0..4 {
            points = mean.two_point_subdivide(&points).unwrap();
        }
        for (i, p) in points.iter().enumerate() {
            assert!((p - spiral(2.0 * i as f64 / 32.0)).norm() < 1e-13);
        }
        let at_centre = mean.two_point_subdivide(&[Complex64::new(0.0, 0.0), c]).unwrap_err();
        assert!(matches!(at_centre, IfsError::Domain { index: 1, .. }));
        let opposite = mean.mean(c + 1.0, c - 1.0, 0.5).unwrap_err();
        assert!(matches!(opposite, IfsError::Domain { index: 1, .. }));
    }

    /// The three-point scheme with the circle mean: points on a circle at angles
    /// θ_0, θ_1, θ_2 stay on the circle, at the angles of the linear quadratic scheme applied
    /// to the angles (the mean is linear in log-polar coordinates).
    #[test]
    fn circle_mean_three_point_scheme_keeps_arcs() {
        let c = Complex64::new(-0.5, 2.0);
        let mean = CircleMean::new(c).unwrap();
        let angles = [0.2, 0.9, 1.3, 2.0, 2.4];
        let mut points: Vec<Complex64> = angles.iter().map(|&a| c + Complex64::from_polar(3.0, a)).collect();
        let mut linear: Vec<[f64; 2]> = angles.iter().map(|&a| [a, a]).collect();
        for _ in 0..4 {
            points = mean.three_point_subdivide(&points).unwrap();
            linear = three_point_subdivide(&linear, Mean::Arithmetic, MeanMode::YOnly).unwrap();
        }
        assert_eq!(points.len(), linear.len());
        for (p, l) in points.iter().zip(&linear) {
            assert!(((p - c).norm() - 3.0).abs() < 1e-13 && ((p - c).arg() - l[1]).abs() < 1e-13);
        }
        assert!(matches!(mean.three_point_subdivide(&points[..4]), Err(IfsError::ParameterOutOfRange { .. })));
        let through_centre = [c + 1.0, c, c - 1.0];
        assert!(matches!(mean.three_point_subdivide(&through_centre), Err(IfsError::Domain { index: 1, .. })));
    }

    #[test]
    fn rule_based_nonlinear_subdivision_matches_the_named_schemes() {
        let points = [[0.0, 1.0], [1.0, 5.0], [2.0, 2.0]];
        let pieces =
            subdivide_with_rule(&bezier_split(2, 0.5).unwrap(), &points, Mean::Geometric, MeanMode::YOnly).unwrap();
        let three = three_point_subdivide(&points, Mean::Geometric, MeanMode::YOnly).unwrap();
        for (a, b) in pieces[0].iter().zip(&three[..3]).chain(pieces[1].iter().zip(&three[2..])) {
            assert!(close(a[0], b[0], 1e-15) && close(a[1], b[1], 1e-14));
        }
    }
}
