//! The per-face rules of the Doo-Sabin family and their inverses.
//!
//! Every rule maps the corners `v_0 .. v_{m-1}` of an `m`-gon to the corners of the
//! smaller face it leaves behind (its F_F face, see [`crate::forward`]):
//!
//! ```text
//! ṽ_i = sum_k w_k v_{(i + k) mod m},    sum_k w_k = 1,    w_k = w_{m-k}
//! ```
//!
//! a symmetric circulant matrix whose eigenvalues are the discrete Fourier values
//! `λ_k = sum_j w_j cos(2π jk / m)` (`λ_0 = 1`). All three rules of this crate have the form
//!
//! ```text
//! w_j = α δ_{j,0} + β (δ_{j,1} + δ_{j,m-1}) + γ / m + δ cos(2π j / m) / m
//! ```
//!
//! | rule | α | β | γ | δ | eigenvalues `λ_k`, `k ≠ 0` |
//! |---|---|---|---|---|---|
//! | [`FaceRule::DooSabin`] | 1/4 | 0 | 3/4 | 1/2 | `1/2` for `k = ±1`, else `1/4` |
//! | [`FaceRule::Simple`] | 1/2 | 1/8 | 1/4 | 0 | `1/2 + cos(2πk/m)/4` |
//! | [`FaceRule::Centroid`] | `1 - a` | 0 | `a` | 0 | `1 - a` for all `k` |
//!
//! so each rule can be applied in `O(m)` operations per face even for huge faces (small
//! faces use the dense weights, which is faster). Doo-Sabin's weights are the classic
//! `w_0 = 1/4 + 5/(4m)`, `w_j = (3 + 2 cos(2πj/m)) / (4m)` (Doo and Sabin 1978, and the
//! mask of CGAL and of the `subdiv-kernels` crate); on quads they are `(9, 3, 1, 3)/16`,
//! the tensor-product quadratic B-spline.
//!
//! # Inverses ("expansion")
//! Reverse Doo-Sabin expands every F_F face back to the coarse face it came from. The
//! inverse weights are `u_j = (1/m) sum_k λ_k^{-1} cos(2π jk/m)`; closed forms:
//! Doo-Sabin `u_j = 4 δ_{j0} - (3 + 4 cos(2πj/m)) / m`; centroid contraction
//! `v_i = (ṽ_i - a d̃) / (1 - a)` with `d̃` the centroid of the small face. The seed paper's
//! eq. (6) prints `+ a/(1-a) d̃`: the sign is wrong (erratum 2 of the specification), and
//! the factor by which distances to the centroid grow is `1/(1 - a)`, not `1/a`. The
//! simple variant's inverse has no short closed form; large faces solve its cyclic
//! tridiagonal system in `O(m)`.
//!
//! # Smoothness
//! Doo-Sabin and the simple variant give C1 limit surfaces at every face size. The
//! centroid contraction does not for faces of four or more sides: all non-trivial face
//! eigenvalues equal `1 - a`, so the subdominant eigenvalue of the local subdivision
//! matrix has multiplicity `m - 1 > 2` and Reif's condition fails (specification §4.2;
//! see [`crate::analysis`]). Even on a regular quad grid it is not C1. Linear precision
//! additionally requires `a = 1/2`, which on triangles coincides with Doo-Sabin.

use std::f64::consts::TAU;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::DooError;

/// One of the three per-face rules of the Doo-Sabin family.
///
/// ```
/// use subdiv_doo::FaceRule;
/// let w = FaceRule::DooSabin.weights(4);
/// assert_eq!(w, vec![9.0 / 16.0, 3.0 / 16.0, 1.0 / 16.0, 3.0 / 16.0]);
/// // The simple variant equals Doo-Sabin on quads, but not on triangles.
/// assert_eq!(FaceRule::Simple.weights(4), w);
/// assert_ne!(FaceRule::Simple.weights(3), FaceRule::DooSabin.weights(3));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub enum FaceRule {
    /// The original Doo-Sabin weights (the default):
    /// `w_0 = 1/4 + 5/(4m)`, `w_j = (3 + 2 cos(2πj/m)) / (4m)`. C1 everywhere.
    #[default]
    DooSabin,
    /// The "simple" variant: each new point is the average of the vertex, the midpoints of
    /// its two face edges and the face centroid. Equal to Doo-Sabin on quads; C1.
    Simple,
    /// The centroid contraction of the reverse-Doo paper: `ṽ_i = a d + (1 - a) v_i` with
    /// `d` the face centroid, `0 < a < 1` (use `a = 1/2`: it is the only value with linear
    /// precision). **Not C1 on faces with four or more sides** (see the module docs).
    Centroid {
        /// The contraction parameter, `0 < a < 1`.
        a: f64,
    },
}

impl FaceRule {
    /// The centroid contraction with `a = 1/2`.
    pub const CENTROID_HALF: FaceRule = FaceRule::Centroid { a: 0.5 };

    /// Short name: `doo-sabin`, `doo-simple` or `doo-centroid`.
    ///
    /// ```
    /// use subdiv_doo::FaceRule;
    /// assert_eq!(FaceRule::DooSabin.name(), "doo-sabin");
    /// assert_eq!(FaceRule::Simple.name(), "doo-simple");
    /// // The centroid parameter is not part of the name.
    /// assert_eq!(FaceRule::Centroid { a: 0.3 }.name(), "doo-centroid");
    /// assert_eq!(FaceRule::CENTROID_HALF.name(), "doo-centroid");
    /// ```
    pub fn name(&self) -> &'static str {
        match self {
            FaceRule::DooSabin => "doo-sabin",
            FaceRule::Simple => "doo-simple",
            FaceRule::Centroid { .. } => "doo-centroid",
        }
    }

    /// Checks the rule's parameter.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooError, DooOptions, FaceRule, subdivide};
    ///
    /// assert!(FaceRule::DooSabin.validate().is_ok());
    /// assert!(FaceRule::CENTROID_HALF.validate().is_ok());
    /// let error = FaceRule::Centroid { a: 1.0 }.validate().unwrap_err();
    /// assert!(matches!(error, DooError::InvalidParameter { name: "a", .. }));
    /// // `subdivide` checks the rule first and reports the same error.
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let options = DooOptions::new(FaceRule::Centroid { a: 1.0 }, 1);
    /// assert_eq!(subdivide(&cube, &options).unwrap_err(), error);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    ///
    /// # Errors
    /// [`DooError::InvalidParameter`] if the centroid parameter is not in `(0, 1)`.
    pub fn validate(&self) -> Result<(), DooError> {
        match *self {
            FaceRule::Centroid { a } if !(a > 0.0 && a < 1.0) => Err(DooError::InvalidParameter {
                name: "a",
                value: a,
                reason: "the centroid contraction needs 0 < a < 1",
            }),
            _ => Ok(()),
        }
    }

    /// The coefficients `(α, β, γ, δ)` of the module docs.
    fn coefficients(&self) -> (f64, f64, f64, f64) {
        match *self {
            FaceRule::DooSabin => (0.25, 0.0, 0.75, 0.5),
            FaceRule::Simple => (0.5, 0.125, 0.25, 0.0),
            FaceRule::Centroid { a } => (1.0 - a, 0.0, a, 0.0),
        }
    }

    /// The weights `w_0 .. w_{m-1}` for an `m`-gon (`w_0` on the vertex itself, `w_k` on
    /// the vertex `k` steps further along the face). They sum to 1.
    ///
    /// ```
    /// use subdiv_doo::FaceRule;
    ///
    /// // Doo-Sabin on a triangle: w_0 = 1/4 + 5/12 = 2/3, w_1 = w_2 = (3 + 2 cos(2π/3)) / 12 = 1/6,
    /// // which is also the centroid contraction with a = 1/2.
    /// let w = FaceRule::DooSabin.weights(3);
    /// assert!((w[0] - 2.0 / 3.0).abs() < 1e-15 && (w[1] - 1.0 / 6.0).abs() < 1e-15 && w[1] == w[2]);
    /// assert!(FaceRule::CENTROID_HALF.weights(3).iter().zip(&w).all(|(a, b)| (a - b).abs() < 1e-15));
    /// // Every rule at every face size: affine (sum 1) and symmetric (w_k = w_{m-k}).
    /// for rule in [FaceRule::DooSabin, FaceRule::Simple, FaceRule::Centroid { a: 0.3 }] {
    ///     for m in 3..=9 {
    ///         let w = rule.weights(m);
    ///         assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-14);
    ///         assert!((1..m).all(|k| (w[k] - w[m - k]).abs() < 1e-15));
    ///     }
    /// }
    /// ```
    ///
    /// # Panics
    /// If `m < 3`, `m >` [`MAX_FACE_CORNERS`] or the rule fails [`FaceRule::validate`]
    /// (the weights of such a rule are not finite).
    pub fn weights(&self, m: usize) -> Vec<f64> {
        self.check_face(m);
        self.dense_weights(m)
    }

    /// [`FaceRule::weights`] unchecked: the crate's face maps are built for rules that
    /// their callers validate.
    fn dense_weights(&self, m: usize) -> Vec<f64> {
        let (alpha, beta, gamma, delta) = self.coefficients();
        let mf = m as f64;
        (0..m)
            .map(|j| {
                let mut w = gamma / mf + delta * cos_turns(j, m) / mf;
                if j == 0 {
                    w += alpha;
                }
                if j == 1 || j == m - 1 {
                    w += beta;
                }
                w
            })
            .collect()
    }

    /// The eigenvalues `λ_0 .. λ_{m-1}` of the face map of an `m`-gon (`λ_0 = 1`,
    /// `λ_k = λ_{m-k}`).
    ///
    /// ```
    /// use subdiv_doo::FaceRule;
    /// let l = FaceRule::DooSabin.eigenvalues(5);
    /// assert!((l[1] - 0.5).abs() < 1e-15 && (l[2] - 0.25).abs() < 1e-15);
    /// ```
    ///
    /// # Panics
    /// As [`FaceRule::weights`].
    pub fn eigenvalues(&self, m: usize) -> Vec<f64> {
        self.check_face(m);
        self.dense_eigenvalues(m)
    }

    fn dense_eigenvalues(&self, m: usize) -> Vec<f64> {
        let (alpha, beta, _, delta) = self.coefficients();
        (0..m)
            .map(|k| {
                if k == 0 {
                    return 1.0;
                }
                let mut l = alpha + 2.0 * beta * cos_turns(k, m);
                if k == 1 || k == m - 1 {
                    l += delta / 2.0;
                }
                l
            })
            .collect()
    }

    /// The inverse weights `u_0 .. u_{m-1}`: `v_i = sum_k u_k ṽ_{(i + k) mod m}` recovers
    /// the corners of an `m`-gon from those of its F_F face.
    ///
    /// ```
    /// use subdiv_doo::FaceRule;
    /// let u = FaceRule::DooSabin.inverse_weights(4);
    /// let expected = [2.25, -0.75, 0.25, -0.75];
    /// assert!(u.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-15));
    /// ```
    ///
    /// # Panics
    /// As [`FaceRule::weights`].
    pub fn inverse_weights(&self, m: usize) -> Vec<f64> {
        self.check_face(m);
        self.dense_inverse_weights(m)
    }

    fn dense_inverse_weights(&self, m: usize) -> Vec<f64> {
        let mf = m as f64;
        match *self {
            FaceRule::DooSabin => (0..m)
                .map(|j| {
                    let c = cos_turns(j, m);
                    let base = -(3.0 + 4.0 * c) / mf;
                    if j == 0 { 4.0 + base } else { base }
                })
                .collect(),
            FaceRule::Centroid { a } => (0..m).map(|j| (if j == 0 { 1.0 } else { 0.0 } - a / mf) / (1.0 - a)).collect(),
            FaceRule::Simple if m <= DENSE_MAX => {
                let lambda = self.dense_eigenvalues(m);
                (0..m).map(|j| (0..m).map(|k| cos_turns(j * k % m, m) / lambda[k]).sum::<f64>() / mf).collect()
            }
            FaceRule::Simple => {
                // The DFT sum is O(m^2) (minutes for large faces): the weights are the
                // inverse map of the unit vector `e_0` instead, the O(m) solve of
                // `inverse_large`, symmetrised (`u_j = u_{m-j}`) against rounding.
                let rhs: Vec<DVec3> =
                    (0..m).map(|j| DVec3::splat(if j == 0 { 1.0 } else { 0.0 } - 0.25 / mf)).collect();
                let mut u = vec![DVec3::ZERO; m];
                solve_cyclic_tridiagonal(0.5, 0.125, &rhs, &mut u);
                (0..m).map(|j| if j == 0 { u[0].x } else { (u[j].x + u[m - j].x) / 2.0 }).collect()
            }
        }
    }

    /// The panics of [`FaceRule::weights`].
    fn check_face(&self, m: usize) {
        assert!((3..=MAX_FACE_CORNERS).contains(&m), "faces have 3 to {MAX_FACE_CORNERS} corners, not {m}");
        if let Err(error) = self.validate() {
            panic!("{error}");
        }
    }
}

/// The most corners of a face whose weights [`FaceRule::weights`] and its kin compute: no
/// face of a mesh has more ([`mesh_topo::check_capacity`]), and the weights of a larger
/// one would not fit in memory.
pub const MAX_FACE_CORNERS: usize = mesh_topo::MAX_ELEMENTS / 2;

/// `cos(2π j / m)`, exact at multiples of a quarter and of a sixth of a turn (so that
/// triangle and quad weights are exact: `(9, 3, 1, 3)/16` on quads).
///
/// Computed from the shorter way round (`min(j, m - j)`), so that `cos_turns(j, m)` and
/// `cos_turns(m - j, m)` are the same number: the weights are exactly symmetric, as
/// [`symmetric_fixed`] needs.
fn cos_turns(j: usize, m: usize) -> f64 {
    let j = (j % m).min(m - j % m);
    match (12 * j).checked_rem(m) {
        Some(0) => match 12 * j / m {
            0 => 1.0,
            2 | 10 => 0.5,
            3 | 9 => 0.0,
            4 | 8 => -0.5,
            6 => -1.0,
            _ => (TAU * j as f64 / m as f64).cos(),
        },
        _ => (TAU * j as f64 / m as f64).cos(),
    }
}

/// Faces up to this size use dense precomputed weights; larger ones the `O(m)` forms.
pub(crate) const DENSE_MAX: usize = 16;

/// A rule with its weights precomputed for the small face sizes, applied face by face.
#[derive(Debug, Clone)]
pub(crate) struct FaceMaps {
    rule: FaceRule,
    /// `forward[m]` = weights of an m-gon (empty for m < 3).
    forward: Vec<Vec<f64>>,
    /// `inverse[m]` = inverse weights of an m-gon.
    inverse: Vec<Vec<f64>>,
}

impl FaceMaps {
    /// Precomputes the dense weights of every size up to [`DENSE_MAX`].
    pub(crate) fn new(rule: FaceRule) -> Self {
        let mut forward = vec![Vec::new(); DENSE_MAX + 1];
        let mut inverse = vec![Vec::new(); DENSE_MAX + 1];
        for m in 3..=DENSE_MAX {
            forward[m] = rule.dense_weights(m);
            inverse[m] = rule.dense_inverse_weights(m);
        }
        Self { rule, forward, inverse }
    }

    /// Writes the F_F corners of the face with corners `points` into `out`
    /// (`out.len() == points.len() >= 3`).
    #[inline]
    pub(crate) fn forward(&self, points: &[DVec3], out: &mut [DVec3]) {
        let m = points.len();
        debug_assert!(m >= 3 && out.len() == m);
        match m {
            3 => symmetric_fixed::<3>(&self.forward[3], points, out),
            4 => symmetric_fixed::<4>(&self.forward[4], points, out),
            5 => symmetric_fixed::<5>(&self.forward[5], points, out),
            6 => symmetric_fixed::<6>(&self.forward[6], points, out),
            _ if m <= DENSE_MAX => circulant(&self.forward[m], points, out),
            _ => self.forward_large(points, out),
        }
    }

    /// Writes the coarse corners recovered from the F_F corners `points` into `out`.
    #[inline]
    pub(crate) fn inverse(&self, points: &[DVec3], out: &mut [DVec3]) {
        let m = points.len();
        debug_assert!(m >= 3 && out.len() == m);
        match m {
            3 => symmetric_fixed::<3>(&self.inverse[3], points, out),
            4 => symmetric_fixed::<4>(&self.inverse[4], points, out),
            // The usual valences (F_V faces, and the F_F faces of their reading).
            5 => symmetric_fixed::<5>(&self.inverse[5], points, out),
            6 => symmetric_fixed::<6>(&self.inverse[6], points, out),
            _ if m <= DENSE_MAX => circulant(&self.inverse[m], points, out),
            _ => self.inverse_large(points, out),
        }
    }

    /// `O(m)` forward map from the `(α, β, γ, δ)` form.
    fn forward_large(&self, points: &[DVec3], out: &mut [DVec3]) {
        let m = points.len();
        let (alpha, beta, gamma, delta) = self.rule.coefficients();
        let centroid = mean(points);
        let (cos_sum, sin_sum) = if delta != 0.0 { fourier_sums(points) } else { (DVec3::ZERO, DVec3::ZERO) };
        for i in 0..m {
            let mut p = alpha * points[i] + gamma * centroid;
            if beta != 0.0 {
                p += beta * (points[(i + m - 1) % m] + points[(i + 1) % m]);
            }
            if delta != 0.0 {
                let theta = TAU * i as f64 / m as f64;
                p += (delta / m as f64) * (theta.cos() * cos_sum + theta.sin() * sin_sum);
            }
            out[i] = p;
        }
    }

    /// `O(m)` inverse map.
    fn inverse_large(&self, points: &[DVec3], out: &mut [DVec3]) {
        let m = points.len();
        let centroid = mean(points);
        match self.rule {
            FaceRule::DooSabin => {
                // v_i = 4 ṽ_i - 3 d̃ - (4/m) sum_j cos(2π(j - i)/m) ṽ_j
                let (cos_sum, sin_sum) = fourier_sums(points);
                for i in 0..m {
                    let theta = TAU * i as f64 / m as f64;
                    out[i] = 4.0 * points[i]
                        - 3.0 * centroid
                        - (4.0 / m as f64) * (theta.cos() * cos_sum + theta.sin() * sin_sum);
                }
            }
            FaceRule::Centroid { a } => {
                for i in 0..m {
                    out[i] = (points[i] - a * centroid) / (1.0 - a);
                }
            }
            FaceRule::Simple => {
                // v/2 + (v_{i-1} + v_{i+1})/8 = ṽ_i - d̃/4 (the centroid is invariant).
                let rhs: Vec<DVec3> = points.iter().map(|&p| p - 0.25 * centroid).collect();
                solve_cyclic_tridiagonal(0.5, 0.125, &rhs, out);
            }
        }
    }
}

/// `out_i = sum_k w_k p_{(i + k) mod m}`.
#[inline]
fn circulant(w: &[f64], points: &[DVec3], out: &mut [DVec3]) {
    let m = points.len();
    for (i, o) in out.iter_mut().enumerate() {
        let mut acc = DVec3::ZERO;
        for (k, &wk) in w.iter().enumerate() {
            let idx = if i + k >= m { i + k - m } else { i + k };
            acc += wk * points[idx];
        }
        *o = acc;
    }
}

/// [`circulant`] for a size known at compile time, with weights symmetric as those of
/// every rule are (`w_k = w_{M-k}`, as the maps commute with reflections of the face):
/// each pair of corners at the same distance is added before it is weighted, about half
/// the products of the plain sum.
#[inline]
fn symmetric_fixed<const M: usize>(w: &[f64], points: &[DVec3], out: &mut [DVec3]) {
    let (w, points, out) = (&w[..M], &points[..M], &mut out[..M]);
    debug_assert!((1..M).all(|k| w[k] == w[M - k]), "internal: symmetric weights");
    for (i, o) in out.iter_mut().enumerate() {
        let mut acc = w[0] * points[i];
        for (k, &wk) in w.iter().enumerate().take(M.div_ceil(2)).skip(1) {
            acc += wk * (points[(i + k) % M] + points[(i + M - k) % M]);
        }
        if M.is_multiple_of(2) {
            acc += w[M / 2] * points[(i + M / 2) % M];
        }
        *o = acc;
    }
}

fn mean(points: &[DVec3]) -> DVec3 {
    points.iter().copied().sum::<DVec3>() / points.len() as f64
}

/// `(sum_j cos(2πj/m) p_j, sum_j sin(2πj/m) p_j)`.
fn fourier_sums(points: &[DVec3]) -> (DVec3, DVec3) {
    let m = points.len() as f64;
    let mut c = DVec3::ZERO;
    let mut s = DVec3::ZERO;
    for (j, &p) in points.iter().enumerate() {
        let (sin, cos) = (TAU * j as f64 / m).sin_cos();
        c += cos * p;
        s += sin * p;
    }
    (c, s)
}

/// Solves `diag x_i + off (x_{i-1} + x_{i+1}) = rhs_i` (indices mod m) for a diagonally
/// dominant cyclic system (`|diag| > 2 |off|`), by the Sherman-Morrison form of the
/// Thomas algorithm.
fn solve_cyclic_tridiagonal(diag: f64, off: f64, rhs: &[DVec3], out: &mut [DVec3]) {
    let m = rhs.len();
    // A = T + u v^T with T tridiagonal (corners removed), u = (γ, 0, .., 0, off),
    // v = (1, 0, .., 0, off/γ).
    let gamma = -diag;
    let mut main = vec![diag; m];
    main[0] -= gamma;
    main[m - 1] -= off * off / gamma;
    let solve = |b: &dyn Fn(usize) -> DVec3, x: &mut [DVec3]| {
        // Thomas algorithm with constant off-diagonals.
        let mut c_prime = vec![0.0; m];
        let mut d_prime = vec![DVec3::ZERO; m];
        c_prime[0] = off / main[0];
        d_prime[0] = b(0) / main[0];
        for i in 1..m {
            let denom = main[i] - off * c_prime[i - 1];
            c_prime[i] = off / denom;
            d_prime[i] = (b(i) - off * d_prime[i - 1]) / denom;
        }
        x[m - 1] = d_prime[m - 1];
        for i in (0..m - 1).rev() {
            x[i] = d_prime[i] - c_prime[i] * x[i + 1];
        }
    };
    let mut y = vec![DVec3::ZERO; m];
    solve(&|i| rhs[i], &mut y);
    let mut z = vec![DVec3::ZERO; m];
    let u = |i: usize| {
        if i == 0 {
            DVec3::splat(gamma)
        } else if i == m - 1 {
            DVec3::splat(off)
        } else {
            DVec3::ZERO
        }
    };
    solve(&u, &mut z);
    let v_last = off / gamma;
    let factor = (y[0] + v_last * y[m - 1]) / (DVec3::ONE + z[0] + v_last * z[m - 1]);
    for i in 0..m {
        out[i] = y[i] - factor * z[i];
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)]
mod tests {
    use super::*;

    const RULES: [FaceRule; 4] =
        [FaceRule::DooSabin, FaceRule::Simple, FaceRule::CENTROID_HALF, FaceRule::Centroid { a: 0.3 }];

    fn polygon(m: usize) -> Vec<DVec3> {
        (0..m)
            .map(|i| {
                let t = i as f64;
                DVec3::new((0.7 * t).sin() + t, (1.3 * t).cos() * 2.0, 0.1 * t * t - 1.0)
            })
            .collect()
    }

    #[test]
    fn weights_match_the_papers() {
        // Doo-Sabin: w_0 = 1/4 + 5/(4m), w_j = (3 + 2cos(2πj/m))/(4m).
        for m in 3..20 {
            let w = FaceRule::DooSabin.weights(m);
            let mf = m as f64;
            assert!((w[0] - (0.25 + 5.0 / (4.0 * mf))).abs() < 1e-15);
            for (j, &wj) in w.iter().enumerate().skip(1) {
                let expected = (3.0 + 2.0 * (TAU * j as f64 / mf).cos()) / (4.0 * mf);
                assert!((wj - expected).abs() < 1e-15, "m={m} j={j}");
            }
            for rule in RULES {
                let w = rule.weights(m);
                assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-14);
                for j in 1..m {
                    assert!((w[j] - w[m - j]).abs() < 1e-15, "symmetric");
                }
            }
        }
        // Simple: average of vertex, two edge midpoints and the centroid.
        let w = FaceRule::Simple.weights(5);
        assert!((w[0] - (0.5 + 0.05)).abs() < 1e-15);
        assert!((w[1] - (0.125 + 0.05)).abs() < 1e-15);
        assert!((w[2] - 0.05).abs() < 1e-15);
        // Centroid a = 1/2 on triangles equals Doo-Sabin (spec §4.2).
        let (c, d) = (FaceRule::CENTROID_HALF.weights(3), FaceRule::DooSabin.weights(3));
        assert!(c.iter().zip(&d).all(|(a, b)| (a - b).abs() < 1e-15));
    }

    #[test]
    fn eigenvalues_are_the_fourier_values_of_the_weights() {
        for rule in RULES {
            for m in 3..12 {
                let w = rule.weights(m);
                let l = rule.eigenvalues(m);
                for k in 0..m {
                    let direct: f64 = (0..m).map(|j| w[j] * (TAU * (j * k) as f64 / m as f64).cos()).sum();
                    assert!((direct - l[k]).abs() < 1e-14, "{rule:?} m={m} k={k}");
                }
            }
        }
        let simple = FaceRule::Simple.eigenvalues(6);
        assert!((simple[1] - 0.625).abs() < 1e-15);
        assert!(FaceRule::Centroid { a: 0.3 }.eigenvalues(7)[1..].iter().all(|&l| (l - 0.7).abs() < 1e-15));
    }

    #[test]
    fn inverse_weights_match_the_closed_forms_of_the_spec() {
        let u3 = FaceRule::DooSabin.inverse_weights(3);
        for (a, b) in u3.iter().zip([5.0 / 3.0, -1.0 / 3.0, -1.0 / 3.0]) {
            assert!((a - b).abs() < 1e-15);
        }
        let u5 = FaceRule::DooSabin.inverse_weights(5);
        assert!((u5[0] - 2.6).abs() < 1e-12 && (u5[1] + 0.847214).abs() < 1e-6 && (u5[2] - 0.047214).abs() < 1e-6);
        // The DFT formula agrees with every closed form.
        for rule in RULES {
            for m in 3..10 {
                let l = rule.eigenvalues(m);
                let u = rule.inverse_weights(m);
                for j in 0..m {
                    let dft: f64 = (0..m).map(|k| cos_turns(j * k, m) / l[k]).sum::<f64>() / m as f64;
                    assert!((dft - u[j]).abs() < 1e-13, "{rule:?} m={m} j={j}");
                }
            }
        }
    }

    #[test]
    fn dense_and_large_paths_agree_and_invert() {
        for rule in RULES {
            let maps = FaceMaps::new(rule);
            for m in [3, 4, 5, 6, 7, 16, 17, 40, 257] {
                let p = polygon(m);
                let scale = p.iter().map(|q| q.length()).fold(1.0, f64::max);
                let mut small = vec![DVec3::ZERO; m];
                maps.forward(&p, &mut small);
                // Reference: the plain weighted sum.
                let w = rule.weights(m);
                for i in 0..m {
                    let reference: DVec3 = (0..m).map(|k| w[k] * p[(i + k) % m]).sum();
                    assert!((reference - small[i]).length() < 1e-13 * scale, "{rule:?} m={m}");
                }
                let mut back = vec![DVec3::ZERO; m];
                maps.inverse(&small, &mut back);
                for i in 0..m {
                    assert!((back[i] - p[i]).length() < 1e-12 * scale, "{rule:?} m={m}: {} vs {}", back[i], p[i]);
                }
                if m > 4 && m <= DENSE_MAX {
                    let mut large = vec![DVec3::ZERO; m];
                    maps.forward_large(&p, &mut large);
                    maps.inverse_large(&small, &mut back);
                    for i in 0..m {
                        assert!((large[i] - small[i]).length() < 1e-13 * scale);
                        assert!((back[i] - p[i]).length() < 1e-12 * scale);
                    }
                }
            }
        }
    }

    #[test]
    fn centroid_parameter_is_checked() {
        assert!(FaceRule::Centroid { a: 0.0 }.validate().is_err());
        assert!(FaceRule::Centroid { a: 1.0 }.validate().is_err());
        assert!(FaceRule::Centroid { a: f64::NAN }.validate().is_err());
        assert!(FaceRule::Centroid { a: 0.5 }.validate().is_ok());
    }

    #[test]
    fn large_simple_inverse_weights_are_linear_time_and_invert() {
        // m = 200 000 used to take minutes (a DFT sum per weight).
        let m = 200_000;
        let u = FaceRule::Simple.inverse_weights(m);
        // Affine, up to the rounding of 200 000 terms.
        assert!((u.iter().sum::<f64>() - 1.0).abs() < 1e-10);
        // The solve agrees with the DFT sum just above the dense sizes, and inverts the
        // forward weights.
        for m in [DENSE_MAX + 1, 40] {
            let (u, l, w) =
                (FaceRule::Simple.inverse_weights(m), FaceRule::Simple.eigenvalues(m), FaceRule::Simple.weights(m));
            for j in 0..m {
                let dft: f64 = (0..m).map(|k| cos_turns(j * k, m) / l[k]).sum::<f64>() / m as f64;
                assert!((dft - u[j]).abs() < 1e-13, "m={m} j={j}");
                assert_eq!(u[j], u[(m - j) % m]);
                let product: f64 = (0..m).map(|k| w[k] * u[(j + m - k) % m]).sum();
                assert!((product - if j == 0 { 1.0 } else { 0.0 }).abs() < 1e-13, "m={m} j={j}");
            }
        }
    }

    #[test]
    #[should_panic(expected = "corners")]
    fn weights_of_a_face_larger_than_any_mesh_face_panic_with_a_message() {
        // Used to panic on a capacity overflow.
        FaceRule::DooSabin.weights(usize::MAX);
    }

    #[test]
    #[should_panic(expected = "0 < a < 1")]
    fn inverse_weights_of_a_bad_centroid_parameter_panic_with_a_message() {
        // `a = 1` used to give infinite weights.
        FaceRule::Centroid { a: 1.0 }.inverse_weights(4);
    }

    #[test]
    #[should_panic(expected = "0 < a < 1")]
    fn weights_of_a_nan_centroid_parameter_panic_with_a_message() {
        FaceRule::Centroid { a: f64::NAN }.weights(4);
    }
}
