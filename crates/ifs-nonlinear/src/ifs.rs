//! Iterated function systems built from subdivision rules (ALGORITHMS.md §15.1, §13).
//!
//! Three concrete systems implement the [`Ifs`] trait that the renderers use:
//! * [`AffineIfs`]: affine maps of R^2 or R^3, e.g. the seed form `T_i = P̂^{-1} S_i P̂`
//!   ([`AffineIfs::from_rule`]) or any user maps ([`AffineIfs::new`]);
//! * [`BarycentricIfs`]: the barycentric form `b ↦ b S_i`, rendered as `b · P` (any number of
//!   control points, curves and patches in 2D or 3D);
//! * [`ComplexBezierIfs`]: Goldman's complex-parameter Bézier subdivision (§13).
//!
//! The nonlinear IFS `F ∘ T_i ∘ F^{-1}` is in [`crate::nonlinear`].

use nalgebra::DMatrix;
use num_complex::Complex64;

use crate::error::{IfsError, Result, check_finite};
use crate::matrices::{ContractivityReport, SubdivisionRule, complex_bezier_split, contractivity_of};

/// An iterated function system as the renderers see it: K maps acting on a flat state
/// vector (a point, or barycentric coordinates), and a projection from states to points.
///
/// Implementations must be cheap to apply and must not allocate in [`apply`](Self::apply)
/// or [`point`](Self::point): the renderers call them in their inner loops.
pub trait Ifs: Sync {
    /// K, the number of maps.
    fn map_count(&self) -> usize;
    /// Length of a state vector.
    fn state_len(&self) -> usize;
    /// Dimension of the rendered points (2 or 3; [`point`](Self::point) pads with 0).
    fn point_dim(&self) -> usize;
    /// Applies map `map` to `state`, writing `out` (both of length [`state_len`](Self::state_len)).
    /// Returns `false` when the state is outside the map's domain (nonlinear maps).
    fn apply(&self, map: usize, state: &[f64], out: &mut [f64]) -> bool;
    /// The point a state stands for.
    fn point(&self, state: &[f64]) -> [f64; 3];
    /// The default start set of the deterministic algorithm, as concatenated states (the
    /// control points, i.e. barycentric unit vectors).
    fn default_start(&self) -> Vec<f64>;
    /// |det| of each map's linear part (volume factor), for the default chaos-game weights.
    fn determinants(&self) -> Vec<f64>;
    /// Describes the domain of the maps, for error messages (empty for affine maps).
    fn domain(&self) -> &'static str {
        ""
    }
    /// The contractivity report of the maps' linear parts (largest singular value and
    /// joint-spectral-radius bounds), when the system knows it; for a nonlinear IFS, that of
    /// the linear IFS it conjugates.
    fn contractivity_report(&self) -> Option<ContractivityReport> {
        None
    }
}

/// `Ifs` for references and boxes, forwarding every method (so that `&dyn Ifs` and
/// `Box<dyn Ifs>` work wherever an `Ifs` is expected).
macro_rules! forward_ifs {
    ($($pointer:ty),*) => {$(
        impl<I: Ifs + ?Sized> Ifs for $pointer {
            fn map_count(&self) -> usize {
                (**self).map_count()
            }
            fn state_len(&self) -> usize {
                (**self).state_len()
            }
            fn point_dim(&self) -> usize {
                (**self).point_dim()
            }
            fn apply(&self, map: usize, state: &[f64], out: &mut [f64]) -> bool {
                (**self).apply(map, state, out)
            }
            fn point(&self, state: &[f64]) -> [f64; 3] {
                (**self).point(state)
            }
            fn default_start(&self) -> Vec<f64> {
                (**self).default_start()
            }
            fn determinants(&self) -> Vec<f64> {
                (**self).determinants()
            }
            fn domain(&self) -> &'static str {
                (**self).domain()
            }
            fn contractivity_report(&self) -> Option<ContractivityReport> {
                (**self).contractivity_report()
            }
        }
    )*};
}

forward_ifs!(&I, Box<I>);

/// An affine map `x ↦ M x + t` of R^d (d ≤ 3; unused rows and columns are zero).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AffineMap {
    /// Linear part `M` (column convention: `x'_r = Σ_c M[r][c] x_c + t_r`).
    pub linear: [[f64; 3]; 3],
    /// Translation `t`.
    pub translation: [f64; 3],
}

impl AffineMap {
    /// A planar map `(x, y) ↦ (a x + b y + e, c x + d y + f)` (the usual IFS-code order
    /// `a b c d e f`).
    ///
    /// ```
    /// use ifs_nonlinear::AffineMap;
    /// // x' = 2x + 3y + 5, y' = 7x + 11y + 13.
    /// let map = AffineMap::planar(2.0, 3.0, 7.0, 11.0, 5.0, 13.0);
    /// assert_eq!((map.linear, map.translation), ([[2.0, 3.0, 0.0], [7.0, 11.0, 0.0], [0.0; 3]], [5.0, 13.0, 0.0]));
    /// assert_eq!(map.apply(2, [1.0, 1.0, 0.0]), [10.0, 31.0, 0.0]);
    /// ```
    pub fn planar(a: f64, b: f64, c: f64, d: f64, e: f64, f: f64) -> Self {
        Self { linear: [[a, b, 0.0], [c, d, 0.0], [0.0; 3]], translation: [e, f, 0.0] }
    }

    /// Applies the map to the first `dim` coordinates of `p`.
    ///
    /// ```
    /// use ifs_nonlinear::AffineMap;
    /// // A quarter turn about the z axis, then a shift by (0, 0, 1).
    /// let linear = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    /// let map = AffineMap { linear, translation: [0.0, 0.0, 1.0] };
    /// assert_eq!(map.apply(3, [1.0, 2.0, 3.0]), [-2.0, 1.0, 4.0]);
    /// assert_eq!(map.apply(2, [1.0, 2.0, 3.0]), [-2.0, 1.0, 0.0]); // in 2D, z is ignored and comes out 0
    /// ```
    #[inline]
    pub fn apply(&self, dim: usize, p: [f64; 3]) -> [f64; 3] {
        let m = &self.linear;
        let t = &self.translation;
        if dim == 2 {
            [m[0][0] * p[0] + m[0][1] * p[1] + t[0], m[1][0] * p[0] + m[1][1] * p[1] + t[1], 0.0]
        } else {
            std::array::from_fn(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + t[r])
        }
    }

    fn linear_part(&self, dim: usize) -> DMatrix<f64> {
        DMatrix::from_fn(dim, dim, |r, c| self.linear[r][c])
    }
}

/// Affine IFS of R^2 or R^3.
#[derive(Debug, Clone, PartialEq)]
pub struct AffineIfs {
    dim: usize,
    maps: Vec<AffineMap>,
}

impl AffineIfs {
    /// Any affine maps of R^`dim` (entries beyond `dim` are ignored and set to 0).
    ///
    /// # Errors
    /// [`IfsError::ParameterOutOfRange`] for `dim` not 2 or 3 or no maps;
    /// [`IfsError::NotFinite`] for a non-finite coefficient.
    ///
    /// ```
    /// use ifs_nonlinear::{AffineIfs, AffineMap};
    /// // Barnsley's fern.
    /// let fern = AffineIfs::new(2, vec![
    ///     AffineMap::planar(0.0, 0.0, 0.0, 0.16, 0.0, 0.0),
    ///     AffineMap::planar(0.85, 0.04, -0.04, 0.85, 0.0, 1.6),
    ///     AffineMap::planar(0.2, -0.26, 0.23, 0.22, 0.0, 1.6),
    ///     AffineMap::planar(-0.15, 0.28, 0.26, 0.24, 0.0, 0.44),
    /// ])?;
    /// assert_eq!(fern.maps().len(), 4);
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn new(dim: usize, mut maps: Vec<AffineMap>) -> Result<Self> {
        if !(2..=3).contains(&dim) {
            return Err(IfsError::ParameterOutOfRange {
                name: "dim",
                value: dim.to_string(),
                reason: "must be 2 or 3",
            });
        }
        if maps.is_empty() {
            return Err(IfsError::ParameterOutOfRange {
                name: "maps",
                value: "0".into(),
                reason: "need at least one map",
            });
        }
        for (i, map) in maps.iter_mut().enumerate() {
            for r in 0..3 {
                for c in 0..3 {
                    if r >= dim || c >= dim {
                        map.linear[r][c] = 0.0;
                    }
                    check_finite(map.linear[r][c], || format!("map {i}, linear entry ({r}, {c})"))?;
                }
                if r >= dim {
                    map.translation[r] = 0.0;
                }
                check_finite(map.translation[r], || format!("map {i}, translation {r}"))?;
            }
        }
        Ok(Self { dim, maps })
    }

    /// The seed form (ALGORITHMS.md §15.1): with `P̂ = [P | 1]` ((d+1)×(d+1) for d + 1
    /// control points in R^d), the maps on homogeneous row vectors `[x, 1]` are
    /// `T_i = P̂^{-1} S_i P̂`; their last column is `(0, …, 0, 1)^T`.
    ///
    /// # Errors
    /// [`IfsError::NotSquare`] unless there are exactly `d + 1` control points (use
    /// [`BarycentricIfs`] otherwise); [`IfsError::ControlCountMismatch`] when the rule acts on
    /// another number of points; [`IfsError::SingularControl`] for affinely dependent
    /// control points (e.g. collinear in 2D); [`IfsError::NotFinite`].
    ///
    /// ```
    /// use ifs_nonlinear::{AffineIfs, IfsError, bezier_split};
    /// let rule = bezier_split(2, 0.5)?;
    /// let ifs = AffineIfs::from_rule(&rule, &[[-1.0, 0.0], [0.0, 5.0], [1.0, 0.0]])?;
    /// // The spec's P̂^{-1} L P̂ = [[1/2, 5/4, 0], [0, 1/4, 0], [-1/2, 5/4, 1]] (row vectors).
    /// let l = ifs.maps()[0];
    /// assert_eq!([l.linear[0][0], l.linear[1][0], l.linear[1][1], l.translation[0], l.translation[1]],
    ///            [0.5, 1.25, 0.25, -0.5, 1.25]);
    /// let collinear = AffineIfs::from_rule(&rule, &[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]);
    /// assert!(matches!(collinear, Err(IfsError::SingularControl { .. })));
    /// # Ok::<(), IfsError>(())
    /// ```
    pub fn from_rule<const D: usize>(rule: &SubdivisionRule<f64>, control: &[[f64; D]]) -> Result<Self> {
        if !(2..=3).contains(&D) {
            return Err(IfsError::ParameterOutOfRange { name: "dim", value: D.to_string(), reason: "must be 2 or 3" });
        }
        check_points(control)?;
        if control.len() != D + 1 {
            return Err(IfsError::NotSquare { dim: D, needed: D + 1, got: control.len() });
        }
        if rule.size() != control.len() {
            return Err(IfsError::ControlCountMismatch { expected: rule.size(), got: control.len() });
        }
        let p_hat = DMatrix::from_fn(D + 1, D + 1, |r, c| if c < D { control[r][c] } else { 1.0 });
        let diameter = control
            .iter()
            .flat_map(|a| control.iter().map(move |b| (0..D).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()))
            .fold(0.0, f64::max);
        let determinant = p_hat.determinant();
        let well_conditioned = determinant.abs() > 1e-12 * diameter.powi(D as i32);
        if !well_conditioned {
            return Err(IfsError::SingularControl { determinant });
        }
        let inverse = p_hat.clone().try_inverse().ok_or(IfsError::SingularControl { determinant })?;
        let maps = rule
            .matrices()
            .iter()
            .map(|s| {
                let t = &inverse * s * &p_hat;
                let mut map = AffineMap { linear: [[0.0; 3]; 3], translation: [0.0; 3] };
                for k in 0..D {
                    for j in 0..D {
                        map.linear[k][j] = t[(j, k)];
                    }
                    map.translation[k] = t[(D, k)];
                }
                map
            })
            .collect();
        Self::new(D, maps)
    }

    /// The maps.
    pub fn maps(&self) -> &[AffineMap] {
        &self.maps
    }

    /// Dimension (2 or 3).
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Largest singular value of the linear parts and the joint-spectral-radius estimate of
    /// the linear parts (which, in the seed form, are conjugate to the restrictions of the
    /// `S_i` to the difference space).
    ///
    /// ```
    /// use ifs_nonlinear::{AffineIfs, sierpinski};
    /// let ifs = AffineIfs::from_rule(&sierpinski(), &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])?;
    /// let report = ifs.contractivity();
    /// assert!((report.max_singular_value - 0.5).abs() < 1e-12 && report.is_contractive());
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn contractivity(&self) -> ContractivityReport {
        let linear: Vec<DMatrix<f64>> = self.maps.iter().map(|m| m.linear_part(self.dim)).collect();
        contractivity_of(&linear)
    }

    /// [`contractivity`](Self::contractivity) as an error when not certified contractive.
    ///
    /// # Errors
    /// [`IfsError::NotContractive`].
    ///
    /// ```
    /// use ifs_nonlinear::{AffineIfs, AffineMap, IfsError};
    /// let half = |e| AffineMap::planar(0.5, 0.0, 0.0, 0.5, e, 0.0);
    /// let report = AffineIfs::new(2, vec![half(0.0), half(0.5)])?.require_contractive()?;
    /// assert!((report.max_singular_value - 0.5).abs() < 1e-12 && report.jsr_upper < 1.0);
    /// // A map that doubles lengths has no attractor.
    /// let expanding = AffineIfs::new(2, vec![AffineMap::planar(2.0, 0.0, 0.0, 2.0, 0.0, 0.0)])?;
    /// assert!(matches!(expanding.require_contractive(), Err(IfsError::NotContractive { .. })));
    /// # Ok::<(), IfsError>(())
    /// ```
    pub fn require_contractive(&self) -> Result<ContractivityReport> {
        self.contractivity().require()
    }
}

impl Ifs for AffineIfs {
    fn map_count(&self) -> usize {
        self.maps.len()
    }
    fn state_len(&self) -> usize {
        self.dim
    }
    fn point_dim(&self) -> usize {
        self.dim
    }
    #[inline]
    fn apply(&self, map: usize, state: &[f64], out: &mut [f64]) -> bool {
        let m = &self.maps[map];
        if self.dim == 2 {
            let (x, y) = (state[0], state[1]);
            out[0] = m.linear[0][0] * x + m.linear[0][1] * y + m.translation[0];
            out[1] = m.linear[1][0] * x + m.linear[1][1] * y + m.translation[1];
        } else {
            let p = m.apply(3, [state[0], state[1], state[2]]);
            out[..3].copy_from_slice(&p);
        }
        true
    }
    #[inline]
    fn point(&self, state: &[f64]) -> [f64; 3] {
        if self.dim == 2 { [state[0], state[1], 0.0] } else { [state[0], state[1], state[2]] }
    }
    fn default_start(&self) -> Vec<f64> {
        // The fixed points of the maps lie on the attractor.
        self.maps.iter().flat_map(|m| fixed_point(m, self.dim)[..self.dim].to_vec()).collect()
    }
    fn determinants(&self) -> Vec<f64> {
        self.maps.iter().map(|m| m.linear_part(self.dim).determinant().abs()).collect()
    }
    fn contractivity_report(&self) -> Option<ContractivityReport> {
        Some(self.contractivity())
    }
}

/// Fixed point of an affine map (`(I - M)^{-1} t`), or the translation if `I - M` is singular.
fn fixed_point(map: &AffineMap, dim: usize) -> [f64; 3] {
    let a = DMatrix::from_fn(dim, dim, |r, c| f64::from(r == c) - map.linear[r][c]);
    let t = nalgebra::DVector::from_fn(dim, |r, _| map.translation[r]);
    match a.lu().solve(&t) {
        Some(x) if x.iter().all(|v| v.is_finite()) => std::array::from_fn(|k| if k < dim { x[k] } else { 0.0 }),
        _ => map.translation,
    }
}

pub(crate) fn check_points<const D: usize>(points: &[[f64; D]]) -> Result<()> {
    for (i, p) in points.iter().enumerate() {
        for (k, &v) in p.iter().enumerate() {
            check_finite(v, || format!("control point {i}, coordinate {k}"))?;
        }
    }
    Ok(())
}

/// The barycentric form (ALGORITHMS.md §15.1, recommended): states are row vectors b with
/// Σ b = 1, maps `b ↦ b S_i`, rendered point `b · P`. Works for any number of control
/// points (cubic curves in the plane, 9- or 16-point patches in space, ...).
#[derive(Debug, Clone, PartialEq)]
pub struct BarycentricIfs {
    size: usize,
    dim: usize,
    /// Row-major m×m matrices, one after the other.
    matrices: Vec<f64>,
    control: Vec<[f64; 3]>,
    determinants: Vec<f64>,
    report: ContractivityReport,
}

impl BarycentricIfs {
    /// Builds the IFS from a contractive rule and its control points (2D or 3D).
    ///
    /// # Errors
    /// [`IfsError::ControlCountMismatch`], [`IfsError::NotFinite`], and
    /// [`IfsError::NotContractive`] when the joint spectral radius on the difference space
    /// is not certified below 1.
    ///
    /// ```
    /// use ifs_nonlinear::{BarycentricIfs, tensor_patch_split};
    /// // A bilinear patch in space (a hyperbolic paraboloid), as 4 maps.
    /// let rule = tensor_patch_split(1, 1)?;
    /// let ifs = BarycentricIfs::new(&rule, &[[0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 1.0]])?;
    /// assert!(ifs.contractivity().jsr_upper < 1.0);
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn new<const D: usize>(rule: &SubdivisionRule<f64>, control: &[[f64; D]]) -> Result<Self> {
        if !(2..=3).contains(&D) {
            return Err(IfsError::ParameterOutOfRange { name: "dim", value: D.to_string(), reason: "must be 2 or 3" });
        }
        check_points(control)?;
        if rule.size() != control.len() {
            return Err(IfsError::ControlCountMismatch { expected: rule.size(), got: control.len() });
        }
        let report = rule.require_contractive()?;
        let m = rule.size();
        let matrices = rule.matrices().iter().flat_map(|s| (0..m * m).map(move |i| s[(i / m, i % m)])).collect();
        let control = control.iter().map(|p| std::array::from_fn(|k| if k < D { p[k] } else { 0.0 })).collect();
        Ok(Self { size: m, dim: D, matrices, control, determinants: rule.difference_determinants(), report })
    }

    /// The contractivity report computed at construction.
    pub fn contractivity(&self) -> ContractivityReport {
        self.report
    }
}

impl Ifs for BarycentricIfs {
    fn map_count(&self) -> usize {
        self.matrices.len() / (self.size * self.size)
    }
    fn state_len(&self) -> usize {
        self.size
    }
    fn point_dim(&self) -> usize {
        self.dim
    }
    #[inline]
    fn apply(&self, map: usize, state: &[f64], out: &mut [f64]) -> bool {
        let m = self.size;
        let s = &self.matrices[map * m * m..(map + 1) * m * m];
        out[..m].fill(0.0);
        for (row, &b) in s.chunks_exact(m).zip(state) {
            if b != 0.0 {
                for (o, &w) in out.iter_mut().zip(row) {
                    *o += b * w;
                }
            }
        }
        true
    }
    #[inline]
    fn point(&self, state: &[f64]) -> [f64; 3] {
        let mut p = [0.0; 3];
        for (b, c) in state.iter().zip(&self.control) {
            for k in 0..3 {
                p[k] += b * c[k];
            }
        }
        p
    }
    fn default_start(&self) -> Vec<f64> {
        unit_vectors(self.size, 1)
    }
    fn determinants(&self) -> Vec<f64> {
        self.determinants.clone()
    }
    fn contractivity_report(&self) -> Option<ContractivityReport> {
        Some(self.report)
    }
}

/// The m unit vectors of R^m (complex: interleaved re, im when `stride` = 2), concatenated.
fn unit_vectors(m: usize, stride: usize) -> Vec<f64> {
    let mut out = vec![0.0; m * m * stride];
    for j in 0..m {
        out[j * m * stride + j * stride] = 1.0;
    }
    out
}

/// Goldman's complex-parameter Bézier subdivision as an IFS (ALGORITHMS.md §13): the
/// de Casteljau matrices with t replaced by `z = r e^{iφ}` act on complex barycentric row
/// vectors; the rendered point is `b · P` with the control points P in C (= the plane).
///
/// States are interleaved (re, im) pairs.
#[derive(Debug, Clone, PartialEq)]
pub struct ComplexBezierIfs {
    size: usize,
    z: Complex64,
    matrices: Vec<Complex64>,
    control: Vec<Complex64>,
    report: ContractivityReport,
}

impl ComplexBezierIfs {
    /// Builds the IFS of degree `control.len() - 1` (2-point scheme: 2 control points;
    /// 3-point quadratic scheme: 3; any degree works).
    ///
    /// **Convergence [ERRATUM of seed 003, ALGORITHMS.md §13]**: the seed claims `r = |z| < 1`
    /// suffices. It does not: both `|z| < 1` and `|1 - z| < 1` are necessary (the spectra of
    /// the two maps on the difference space are {z, …, z^n} and {1-z, …, (1-z)^n}); for n ≥ 2
    /// the joint spectral radius is also estimated and must be certified below 1.
    ///
    /// # Errors
    /// [`IfsError::TooFewPoints`] for fewer than 2 control points; [`IfsError::NotFinite`];
    /// [`IfsError::NotContractive`] naming the failed condition (e.g. z = -0.5 has
    /// |z| = 0.5 but |1 - z| = 1.5).
    ///
    /// ```
    /// use ifs_nonlinear::{ComplexBezierIfs, IfsError};
    /// use num_complex::Complex64;
    /// let control = [Complex64::new(0.0, 0.0), Complex64::new(1.0, 0.0)];
    /// let levy = ComplexBezierIfs::new(Complex64::new(0.5, 0.5), &control)?;
    /// assert!((levy.contractivity().jsr_upper - 0.5f64.sqrt()).abs() < 1e-12);
    /// let diverging = ComplexBezierIfs::new(Complex64::new(-0.5, 0.0), &control);
    /// assert!(matches!(diverging, Err(IfsError::NotContractive { .. })));
    /// # Ok::<(), IfsError>(())
    /// ```
    pub fn new(z: Complex64, control: &[Complex64]) -> Result<Self> {
        if control.len() < 2 {
            return Err(IfsError::TooFewPoints { what: "complex Bézier subdivision", needed: 2, got: control.len() });
        }
        for (i, p) in control.iter().enumerate() {
            check_finite(p.re, || format!("control point {i}, real part"))?;
            check_finite(p.im, || format!("control point {i}, imaginary part"))?;
        }
        let degree = control.len() - 1;
        let rule = complex_bezier_split(degree, z)?;
        let (r, s) = (z.norm(), (Complex64::new(1.0, 0.0) - z).norm());
        let report = rule.contractivity();
        let failed = if r >= 1.0 {
            Some(format!("; |z| = {r} >= 1"))
        } else if s >= 1.0 {
            Some(format!("; |1 - z| = {s} >= 1 (|z| < 1 alone does not suffice)"))
        } else if !report.is_contractive() {
            Some(format!(
                "; |z| = {r} and |1 - z| = {s} are < 1 but the joint spectral radius is not certified < 1{}",
                report.capped_detail()
            ))
        } else {
            None
        };
        if let Some(detail) = failed {
            return Err(IfsError::NotContractive { jsr_lower: report.jsr_lower, jsr_upper: report.jsr_upper, detail });
        }
        let m = degree + 1;
        let matrices = rule.matrices().iter().flat_map(|s| (0..m * m).map(move |i| s[(i / m, i % m)])).collect();
        Ok(Self { size: m, z, matrices, control: control.to_vec(), report })
    }

    /// The parameter z.
    pub fn z(&self) -> Complex64 {
        self.z
    }

    /// The contractivity report on the difference space.
    pub fn contractivity(&self) -> ContractivityReport {
        self.report
    }
}

impl Ifs for ComplexBezierIfs {
    fn map_count(&self) -> usize {
        2
    }
    fn state_len(&self) -> usize {
        2 * self.size
    }
    fn point_dim(&self) -> usize {
        2
    }
    #[inline]
    fn apply(&self, map: usize, state: &[f64], out: &mut [f64]) -> bool {
        let m = self.size;
        let s = &self.matrices[map * m * m..(map + 1) * m * m];
        out[..2 * m].fill(0.0);
        for (row, b) in s.chunks_exact(m).zip(state.chunks_exact(2)) {
            let b = Complex64::new(b[0], b[1]);
            if b != Complex64::new(0.0, 0.0) {
                for (o, &w) in out.chunks_exact_mut(2).zip(row) {
                    let v = b * w;
                    o[0] += v.re;
                    o[1] += v.im;
                }
            }
        }
        true
    }
    #[inline]
    fn point(&self, state: &[f64]) -> [f64; 3] {
        let mut p = Complex64::new(0.0, 0.0);
        for (b, c) in state.chunks_exact(2).zip(&self.control) {
            p += Complex64::new(b[0], b[1]) * c;
        }
        [p.re, p.im, 0.0]
    }
    fn default_start(&self) -> Vec<f64> {
        unit_vectors(self.size, 2)
    }
    fn determinants(&self) -> Vec<f64> {
        // Area factor of the two similarities for the 2-point scheme: |z|^2 and |1 - z|^2;
        // for higher degrees the same weights (the first difference eigenvalues).
        let w = Complex64::new(1.0, 0.0) - self.z;
        vec![self.z.norm_sqr(), w.norm_sqr()]
    }
    fn contractivity_report(&self) -> Option<ContractivityReport> {
        Some(self.report)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matrices::{bezier_split, sierpinski};

    #[test]
    fn seed_form_of_the_quartic_bump_matches_the_spec() {
        let ifs = AffineIfs::from_rule(&bezier_split(2, 0.5).unwrap(), &[[-1.0, 0.0], [0.0, 5.0], [1.0, 0.0]]).unwrap();
        let [l, r] = [ifs.maps()[0], ifs.maps()[1]];
        assert_eq!(l.linear[0], [0.5, 0.0, 0.0]);
        assert_eq!(l.linear[1], [1.25, 0.25, 0.0]);
        assert_eq!(l.translation, [-0.5, 1.25, 0.0]);
        assert_eq!(r.linear[1], [-1.25, 0.25, 0.0]);
        assert_eq!(r.translation, [0.5, 1.25, 0.0]);
    }

    #[test]
    fn seed_form_needs_a_square_control_matrix() {
        let cubic = bezier_split(3, 0.5).unwrap();
        let err = AffineIfs::from_rule(&cubic, &[[0.0, 0.0], [1.0, 1.0], [2.0, 0.0], [3.0, 1.0]]).unwrap_err();
        assert_eq!(err, IfsError::NotSquare { dim: 2, needed: 3, got: 4 });
        let in_space =
            AffineIfs::from_rule(&cubic, &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
        assert!(in_space.is_ok());
        let coplanar =
            AffineIfs::from_rule(&cubic, &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]]);
        assert!(matches!(coplanar, Err(IfsError::SingularControl { .. })));
        let nan = AffineIfs::from_rule(&sierpinski(), &[[0.0, f64::NAN], [1.0, 0.0], [0.0, 1.0]]);
        assert!(matches!(nan, Err(IfsError::NotFinite { .. })));
    }

    /// NaN or infinite input to every IFS constructor is a `NotFinite` error naming where it
    /// is (map and entry, or control point and coordinate), never a system that renders NaN.
    #[test]
    fn non_finite_maps_and_control_points_are_named() {
        let what = |result: Result<()>| match result {
            Err(IfsError::NotFinite { what, .. }) => what,
            other => panic!("{other:?}"),
        };
        let mut maps = vec![AffineMap::planar(0.5, 0.0, 0.0, 0.5, 0.0, 0.0); 3];
        maps[2].translation[1] = f64::INFINITY;
        assert_eq!(what(AffineIfs::new(2, maps).map(|_| ())), "map 2, translation 1");
        let mut maps = vec![AffineMap::planar(0.5, 0.0, 0.0, 0.5, 0.0, 0.0); 2];
        maps[1].linear[0][1] = f64::NAN;
        assert_eq!(what(AffineIfs::new(2, maps).map(|_| ())), "map 1, linear entry (0, 1)");
        let rule = bezier_split(2, 0.5).unwrap();
        let control = [[0.0, 0.0], [1.0, 2.0], [f64::NAN, 0.0]];
        assert_eq!(what(BarycentricIfs::new(&rule, &control).map(|_| ())), "control point 2, coordinate 0");
        let z = Complex64::new(0.5, 0.5);
        let control = [Complex64::new(0.0, 0.0), Complex64::new(1.0, f64::NAN)];
        assert_eq!(what(ComplexBezierIfs::new(z, &control).map(|_| ())), "control point 1, imaginary part");
        let segment = [Complex64::new(0.0, 0.0), Complex64::new(1.0, 0.0)];
        assert_eq!(what(ComplexBezierIfs::new(Complex64::new(f64::NAN, 0.5), &segment).map(|_| ())), "z (real part)");
    }

    /// Every map keeps the affine structure: the seed-form maps send the control points to
    /// the sub-piece's control points, for random affine images of the control points too.
    #[test]
    fn seed_form_commutes_with_affine_maps() {
        let rule = bezier_split(2, 0.5).unwrap();
        let p = [[0.0, 0.0], [1.0, 2.0], [3.0, 0.0]];
        let affine = |q: [f64; 2]| [0.3 * q[0] - 1.2 * q[1] + 4.0, 0.7 * q[0] + 0.2 * q[1] - 1.0];
        let ifs = AffineIfs::from_rule(&rule, &p).unwrap();
        let image = AffineIfs::from_rule(&rule, &p.map(affine)).unwrap();
        for (map, (a, b)) in ifs.maps().iter().zip(image.maps()).enumerate() {
            for q in [[0.2, 0.5], [1.0, -1.0]] {
                let lhs = affine(a.apply(2, [q[0], q[1], 0.0])[..2].try_into().unwrap());
                let rhs = b.apply(2, [affine(q)[0], affine(q)[1], 0.0]);
                assert!((lhs[0] - rhs[0]).abs() < 1e-12 && (lhs[1] - rhs[1]).abs() < 1e-12, "map {map}");
            }
            // T_i maps control point j to row j of S_i P.
            for (j, pj) in p.iter().enumerate() {
                let image_point = a.apply(2, [pj[0], pj[1], 0.0]);
                let expected: Vec<f64> =
                    (0..2).map(|k| (0..3).map(|c| rule.matrices()[map][(j, c)] * p[c][k]).sum()).collect();
                assert!((image_point[0] - expected[0]).abs() < 1e-12 && (image_point[1] - expected[1]).abs() < 1e-12);
            }
        }
    }
}
