//! Triangular Bézier patches of any degree (ALGORITHMS.md §9).
//!
//! A patch of degree `n` over the domain triangle `T = (t0, t1, t2)` is
//! `S(u) = sum_{|β| = n} b_β B_β(λ(u))`, with the Bernstein polynomials
//! `B_β(λ) = n!/(β0! β1! β2!) λ0^β0 λ1^β1 λ2^β2` of the barycentric coordinates `λ` of `u`.
//! Control points are stored in the order of [`crate::index`].
//!
//! Evaluation is de Casteljau's algorithm (O(n³), stable inside `T`); the direct
//! Bernstein sum is offered for cross-checking. The blossom (polar form) `F(u_1, …, u_n)`
//! is de Casteljau with a different point at each level; it gives derivatives
//! (`D_d S(u) = n F(u, …, u, d)` for a direction `d`) and the control points of the
//! patch restricted to any sub-triangle (`F(s0^β0, s1^β1, s2^β2)`).
//!
//! Reference: L. Ramshaw, Blossoms are polar forms, CAGD 6 (1989) 323–358; G. Farin,
//! Triangular Bernstein–Bézier patches, CAGD 3 (1986) 83–127.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::SplineError;
use crate::domain::DomainTriangle;
use crate::index::{multi_indices, multinomial, tri_count, tri_index};
use crate::point::{Point, combine3};

/// Largest supported degree of a Bézier patch.
pub const MAX_BEZIER_DEGREE: usize = 64;

/// A triangular Bézier patch with control points of type `P`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TriBezier<P = DVec3> {
    degree: usize,
    domain: DomainTriangle,
    control: Vec<P>,
}

/// Control points up to this count (degree 10) are copied to a stack buffer for
/// evaluation, larger nets to the heap.
const STACK_POINTS: usize = 66;

/// Runs `f` on a scratch copy of `control` (on the stack for small nets, sized in tiers
/// so that small degrees do not pay for initialising a large buffer).
#[inline]
pub(crate) fn with_scratch<P: Point, R>(control: &[P], f: impl FnOnce(&mut [P]) -> R) -> R {
    #[inline(always)]
    fn on_stack<P: Point, R, const N: usize>(control: &[P], f: impl FnOnce(&mut [P]) -> R) -> R {
        let mut buf = [P::ZERO; N];
        buf[..control.len()].copy_from_slice(control);
        f(&mut buf[..control.len()])
    }
    match control.len() {
        0..=10 => on_stack::<P, R, 10>(control, f),
        11..=28 => on_stack::<P, R, 28>(control, f),
        29..=STACK_POINTS => on_stack::<P, R, STACK_POINTS>(control, f),
        _ => f(&mut control.to_vec()),
    }
}

/// One de Casteljau level in place: `buf` holds degree `m + 1` values; afterwards its
/// first `tri_count(m)` entries hold the degree-`m` values `sum_i w_i b_{β + e_i}`.
/// (Reads at positions at or after every write position, so one buffer suffices.)
#[inline]
pub(crate) fn casteljau_level<P: Point>(buf: &mut [P], m: usize, w: [f64; 3]) {
    let mut dst = 0;
    for k in 0..=m {
        let row = tri_index(m + 1, 0, k);
        let next_row = tri_index(m + 1, 0, k + 1);
        for j in 0..=m - k {
            buf[dst] = combine3(buf[row + j], buf[row + j + 1], buf[next_row + j], w);
            dst += 1;
        }
    }
}

/// The Bernstein polynomials of degree `n` at barycentric coordinates `l`, in storage
/// order, by the upward recursion `B^{m+1}_γ = sum_i l_i B^m_{γ - e_i}` (non-negative
/// inside the triangle, sums to one exactly up to rounding). `out` is resized to
/// `(n + 1)(n + 2) / 2` values.
///
/// # Errors
/// [`SplineError::Degree`] above [`MAX_BEZIER_DEGREE`], the largest patch degree, checked
/// before `out` grows (a mistyped degree such as `1 << 20` used to allocate half a
/// trillion values).
///
/// ```
/// use tri_spline::bezier::bernstein_basis;
/// let mut values = Vec::new();
/// bernstein_basis(2, [0.5, 0.5, 0.0], &mut values)?;
/// assert_eq!(values, [0.25, 0.5, 0.25, 0.0, 0.0, 0.0]);
/// assert!(bernstein_basis(1 << 20, [1.0, 0.0, 0.0], &mut values).is_err());
/// # Ok::<(), tri_spline::SplineError>(())
/// ```
pub fn bernstein_basis(n: usize, l: [f64; 3], out: &mut Vec<f64>) -> Result<(), SplineError> {
    if n > MAX_BEZIER_DEGREE {
        return Err(SplineError::Degree { degree: n, min: 0, max: MAX_BEZIER_DEGREE });
    }
    out.clear();
    out.resize(tri_count(n), 0.0);
    out[0] = 1.0;
    // Work downwards in storage position so that degree-m values are read before they
    // are overwritten by degree-(m+1) values.
    for m in 0..n {
        for k in (0..=m + 1).rev() {
            for j in (0..=m + 1 - k).rev() {
                let i0 = m + 1 - j - k;
                let mut value = 0.0;
                if i0 >= 1 {
                    value += l[0] * out[tri_index(m, j, k)];
                }
                if j >= 1 {
                    value += l[1] * out[tri_index(m, j - 1, k)];
                }
                if k >= 1 {
                    value += l[2] * out[tri_index(m, j, k - 1)];
                }
                out[tri_index(m + 1, j, k)] = value;
            }
        }
    }
    Ok(())
}

impl<P: Point> TriBezier<P> {
    /// A patch of degree `degree` over `domain` with control points in storage order.
    ///
    /// # Errors
    /// [`SplineError::Degree`] above [`MAX_BEZIER_DEGREE`], [`SplineError::Count`] if
    /// there are not `(n+1)(n+2)/2` control points, [`SplineError::NonFinite`] for a
    /// NaN or infinite control point.
    ///
    /// ```
    /// use glam::{DVec2, DVec3};
    /// use tri_spline::{DomainTriangle, TriBezier};
    /// // The linear patch through three points is the plane through them.
    /// let control = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
    /// let patch = TriBezier::new(1, DomainTriangle::reference(), control)?;
    /// assert_eq!(patch.eval(DVec2::new(0.25, 0.5)), DVec3::new(0.25, 0.5, 0.0));
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn new(degree: usize, domain: DomainTriangle, control: Vec<P>) -> Result<Self, SplineError> {
        if degree > MAX_BEZIER_DEGREE {
            return Err(SplineError::Degree { degree, min: 0, max: MAX_BEZIER_DEGREE });
        }
        if control.len() != tri_count(degree) {
            return Err(SplineError::Count {
                what: "Bézier control points",
                expected: tri_count(degree),
                got: control.len(),
            });
        }
        if let Some(index) = control.iter().position(|p| !p.is_finite_point()) {
            return Err(SplineError::NonFinite { what: "control point", index });
        }
        Ok(Self { degree, domain, control })
    }

    /// The degree `n`.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The domain triangle.
    pub fn domain(&self) -> &DomainTriangle {
        &self.domain
    }

    /// The control points in storage order.
    pub fn control_points(&self) -> &[P] {
        &self.control
    }

    /// Mutable control points (the count is fixed).
    pub fn control_points_mut(&mut self) -> &mut [P] {
        &mut self.control
    }

    /// The control point `b_β`.
    ///
    /// # Panics
    /// If `β0 + β1 + β2` is not the degree (the message names `β` and the degree);
    /// [`try_control_point`](Self::try_control_point) returns an error instead.
    pub fn control_point(&self, beta: [usize; 3]) -> P {
        self.try_control_point(beta).unwrap_or_else(|e| panic!("TriBezier::control_point: {e}"))
    }

    /// The control point `b_β`, for a multi-index given by a caller.
    ///
    /// # Errors
    /// [`SplineError::MultiIndexDegree`] unless `β0 + β1 + β2` is the degree (also when the
    /// sum overflows, which used to wrap to a valid-looking degree).
    ///
    /// ```
    /// use tri_spline::{DomainTriangle, SplineError, TriBezier};
    /// let patch = TriBezier::new(1, DomainTriangle::reference(), vec![1.0, 2.0, 3.0])?;
    /// assert_eq!(patch.try_control_point([0, 1, 0])?, 2.0);
    /// assert!(matches!(patch.try_control_point([1, 1, 0]), Err(SplineError::MultiIndexDegree { degree: 1, .. })));
    /// # Ok::<(), SplineError>(())
    /// ```
    pub fn try_control_point(&self, beta: [usize; 3]) -> Result<P, SplineError> {
        let sum = beta[0].checked_add(beta[1]).and_then(|s| s.checked_add(beta[2]));
        if sum != Some(self.degree) {
            return Err(SplineError::MultiIndexDegree { beta, degree: self.degree });
        }
        Ok(self.control[tri_index(self.degree, beta[1], beta[2])])
    }

    /// `S(u)` by de Casteljau's algorithm.
    ///
    /// ```
    /// use glam::{DVec2, DVec3};
    /// use tri_spline::{DomainTriangle, TriBezier};
    /// // A patch interpolates its corner control points b_200, b_020, b_002.
    /// let control: Vec<DVec3> = (0..6).map(|i| DVec3::new(i as f64, (i * i) as f64, 1.0)).collect();
    /// let patch = TriBezier::new(2, DomainTriangle::reference(), control.clone())?;
    /// assert_eq!(patch.eval(DVec2::ZERO), control[0]);
    /// assert_eq!(patch.eval(DVec2::X), control[2]);
    /// assert_eq!(patch.eval(DVec2::Y), control[5]);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval(&self, u: DVec2) -> P {
        self.eval_barycentric(self.domain.barycentric(u))
    }

    /// `S` at barycentric coordinates `l` by de Casteljau's algorithm.
    ///
    /// ```
    /// use tri_spline::{DomainTriangle, TriBezier};
    /// let domain = DomainTriangle::equilateral();
    /// // A linear patch is `sum_i l_i b_i`, on any domain triangle.
    /// let patch = TriBezier::new(1, domain, vec![1.0, 2.0, 6.0])?;
    /// assert_eq!(patch.eval_barycentric([0.5, 0.25, 0.25]), 2.5);
    /// let l = [0.2, 0.3, 0.5];
    /// assert!((patch.eval_barycentric(l) - patch.eval(domain.point(l))).abs() < 1e-14);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval_barycentric(&self, l: [f64; 3]) -> P {
        with_scratch(&self.control, |buf| {
            for m in (0..self.degree).rev() {
                casteljau_level(buf, m, l);
            }
            buf[0]
        })
    }

    /// `S(u)` as the direct Bernstein sum (for checking; de Casteljau is preferred).
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::{DomainTriangle, TriBezier};
    /// let u = DVec2::new(0.2, 0.3);
    /// // The Bernstein polynomials sum to one: equal control points give a constant.
    /// let constant = TriBezier::new(3, DomainTriangle::reference(), vec![7.0; 10])?;
    /// assert!((constant.eval_bernstein(u) - 7.0).abs() < 1e-14);
    /// // The sum agrees with de Casteljau's algorithm.
    /// let patch = TriBezier::new(3, DomainTriangle::reference(), (0..10).map(|i| (i * i) as f64).collect())?;
    /// assert!((patch.eval_bernstein(u) - patch.eval(u)).abs() < 1e-12);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval_bernstein(&self, u: DVec2) -> P {
        let l = self.domain.barycentric(u);
        let mut sum = P::ZERO;
        for (beta, &b) in multi_indices(self.degree).zip(&self.control) {
            let weight =
                multinomial(beta) * l[0].powi(beta[0] as i32) * l[1].powi(beta[1] as i32) * l[2].powi(beta[2] as i32);
            sum = sum + b * weight;
        }
        sum
    }

    /// The blossom `F(u_1, …, u_n)`: symmetric, affine in each argument,
    /// `F(u, …, u) = S(u)` and `b_β = F(t0^β0, t1^β1, t2^β2)`.
    ///
    /// # Errors
    /// [`SplineError::Count`] unless exactly `n` arguments are given.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::{DomainTriangle, TriBezier};
    /// let patch = TriBezier::new(2, DomainTriangle::reference(), vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0])?;
    /// let [t0, t1, t2] = patch.domain().corners();
    /// assert_eq!(patch.blossom(&[t1, t2])?, patch.control_point([0, 1, 1]));
    /// let u = DVec2::new(0.2, 0.3);
    /// assert!((patch.blossom(&[u, u])? - patch.eval(u)).abs() < 1e-15);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn blossom(&self, args: &[DVec2]) -> Result<P, SplineError> {
        if args.len() != self.degree {
            return Err(SplineError::Count { what: "blossom arguments", expected: self.degree, got: args.len() });
        }
        Ok(with_scratch(&self.control, |buf| {
            for (level, m) in (0..self.degree).rev().enumerate() {
                casteljau_level(buf, m, self.domain.barycentric(args[level]));
            }
            buf[0]
        }))
    }

    /// The directional derivative `D_d S(u) = n F(u, …, u, d)` (with `d` a vector).
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::{DomainTriangle, TriBezier};
    /// // On the reference triangle x = λ1, so x² = λ1² is the Bernstein polynomial B_020.
    /// let square = TriBezier::new(2, DomainTriangle::reference(), vec![0.0, 0.0, 1.0, 0.0, 0.0, 0.0])?;
    /// let u = DVec2::new(0.3, 0.2);
    /// assert!((square.derivative(u, DVec2::X) - 0.6).abs() < 1e-15);
    /// assert!(square.derivative(u, DVec2::Y).abs() < 1e-15);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn derivative(&self, u: DVec2, d: DVec2) -> P {
        if self.degree == 0 {
            return P::ZERO;
        }
        let l = self.domain.barycentric(u);
        with_scratch(&self.control, |buf| {
            casteljau_level(buf, self.degree - 1, self.domain.direction(d));
            for m in (0..self.degree - 1).rev() {
                casteljau_level(buf, m, l);
            }
            buf[0] * self.degree as f64
        })
    }

    /// `S(u)` and its partial derivatives with respect to the two domain coordinates, in
    /// one de Casteljau pass.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::{DomainTriangle, TriBezier};
    /// // x y = λ1 λ2 = B_011 / 2 on the reference triangle.
    /// let xy = TriBezier::new(2, DomainTriangle::reference(), vec![0.0, 0.0, 0.0, 0.0, 0.5, 0.0])?;
    /// let (value, [dx, dy]) = xy.eval_with_gradient(DVec2::new(0.3, 0.2));
    /// assert!((value - 0.06).abs() < 1e-15);
    /// assert!((dx - 0.2).abs() < 1e-15 && (dy - 0.3).abs() < 1e-15);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval_with_gradient(&self, u: DVec2) -> (P, [P; 2]) {
        if self.degree == 0 {
            return (self.control[0], [P::ZERO; 2]);
        }
        let l = self.domain.barycentric(u);
        with_scratch(&self.control, |buf| {
            for m in (1..self.degree).rev() {
                casteljau_level(buf, m, l);
            }
            // Three points of the linear patch left after n - 1 levels.
            let n = self.degree as f64;
            let value = combine3(buf[0], buf[1], buf[2], l);
            let du = combine3(buf[0], buf[1], buf[2], self.domain.direction(DVec2::X)) * n;
            let dv = combine3(buf[0], buf[1], buf[2], self.domain.direction(DVec2::Y)) * n;
            (value, [du, dv])
        })
    }

    /// The same surface as a patch of degree `n + 1` (degree elevation:
    /// `b'_γ = sum_i γ_i / (n + 1) b_{γ - e_i}`).
    ///
    /// # Errors
    /// [`SplineError::Degree`] above [`MAX_BEZIER_DEGREE`].
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::bezier::MAX_BEZIER_DEGREE;
    /// use tri_spline::index::tri_count;
    /// use tri_spline::{DomainTriangle, TriBezier};
    /// let patch = TriBezier::new(2, DomainTriangle::reference(), vec![0.0, 1.0, 4.0, 2.0, 3.0, 5.0])?;
    /// let higher = patch.elevate()?;
    /// assert_eq!((higher.degree(), higher.control_points().len()), (3, 10));
    /// let u = DVec2::new(0.2, 0.5);
    /// assert!((higher.eval(u) - patch.eval(u)).abs() < 1e-14);
    /// let top = TriBezier::new(MAX_BEZIER_DEGREE, DomainTriangle::reference(), vec![0.0; tri_count(MAX_BEZIER_DEGREE)])?;
    /// assert!(top.elevate().is_err());
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn elevate(&self) -> Result<Self, SplineError> {
        let n = self.degree;
        if n + 1 > MAX_BEZIER_DEGREE {
            return Err(SplineError::Degree { degree: n + 1, min: 0, max: MAX_BEZIER_DEGREE });
        }
        let scale = 1.0 / (n + 1) as f64;
        let control = multi_indices(n + 1)
            .map(|[i, j, k]| {
                let mut p = P::ZERO;
                if i > 0 {
                    p = p + self.control[tri_index(n, j, k)] * (i as f64 * scale);
                }
                if j > 0 {
                    p = p + self.control[tri_index(n, j - 1, k)] * (j as f64 * scale);
                }
                if k > 0 {
                    p = p + self.control[tri_index(n, j, k - 1)] * (k as f64 * scale);
                }
                p
            })
            .collect();
        Ok(Self { degree: n + 1, domain: self.domain, control })
    }

    /// The patch restricted to the sub-triangle `corners` (any non-degenerate triangle,
    /// inside the domain or not): a patch over `corners` with control points
    /// `F(s0^β0, s1^β1, s2^β2)` describing the same polynomial.
    ///
    /// # Errors
    /// [`SplineError::DegenerateDomain`] for a degenerate sub-triangle.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::{DomainTriangle, TriBezier};
    /// let patch = TriBezier::new(2, DomainTriangle::reference(), vec![0.0, 1.0, 4.0, 2.0, 3.0, 5.0])?;
    /// let corners = [DVec2::new(0.1, 0.1), DVec2::new(0.6, 0.1), DVec2::new(0.1, 0.6)];
    /// let sub = patch.subpatch(corners)?;
    /// assert_eq!(sub.domain().corners(), corners);
    /// // The same polynomial: equal values, and the sub-patch interpolates at its corners.
    /// let u = DVec2::new(0.25, 0.3);
    /// assert!((sub.eval(u) - patch.eval(u)).abs() < 1e-14);
    /// assert!((sub.control_point([2, 0, 0]) - patch.eval(corners[0])).abs() < 1e-14);
    /// assert!(patch.subpatch([DVec2::ZERO, DVec2::X, DVec2::X * 2.0]).is_err());
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn subpatch(&self, corners: [DVec2; 3]) -> Result<Self, SplineError> {
        let domain = DomainTriangle::new(corners)?;
        let mut args = Vec::with_capacity(self.degree);
        let control = multi_indices(self.degree)
            .map(|beta| {
                args.clear();
                for (corner, &count) in corners.iter().zip(&beta) {
                    args.extend(std::iter::repeat_n(*corner, count));
                }
                self.blossom(&args).expect("internal: blossom argument count")
            })
            .collect();
        Ok(Self { degree: self.degree, domain, control })
    }

    /// The four patches of the midpoint subdivision of the domain: the corner triangles
    /// at `t0`, `t1`, `t2` and the middle one `(m12, m20, m01)`.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::{DomainTriangle, TriBezier};
    /// let patch = TriBezier::new(2, DomainTriangle::reference(), vec![0.0, 1.0, 4.0, 2.0, 3.0, 5.0])?;
    /// let pieces = patch.split4();
    /// assert_eq!(pieces[3].domain().corners(), [DVec2::new(0.5, 0.5), DVec2::new(0.0, 0.5), DVec2::new(0.5, 0.0)]);
    /// // Each piece matches the patch on its quarter (here at its centroid).
    /// for piece in &pieces {
    ///     let c = piece.domain().point([1.0 / 3.0; 3]);
    ///     assert!((piece.eval(c) - patch.eval(c)).abs() < 1e-14);
    /// }
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn split4(&self) -> [Self; 4] {
        let [t0, t1, t2] = self.domain.corners();
        let (m01, m12, m20) = ((t0 + t1) * 0.5, (t1 + t2) * 0.5, (t2 + t0) * 0.5);
        [[t0, m01, m20], [m01, t1, m12], [m20, m12, t2], [m12, m20, m01]]
            .map(|corners| self.subpatch(corners).expect("internal: midpoint triangles of a valid domain"))
    }
}

impl TriBezier<DVec3> {
    /// The unit normal `S_x × S_y / |S_x × S_y|` (oriented like the domain's `x, y`
    /// axes); `None` where the patch is singular.
    ///
    /// ```
    /// use glam::{DVec2, DVec3};
    /// use tri_spline::{DomainTriangle, TriBezier};
    /// let u = DVec2::new(0.2, 0.3);
    /// let flat = TriBezier::new(1, DomainTriangle::reference(), vec![DVec3::ZERO, DVec3::X, DVec3::Y])?;
    /// assert!((flat.normal(u).unwrap() - DVec3::Z).length() < 1e-15);
    /// // All control points equal: the patch is a point, with no normal.
    /// let point = TriBezier::new(1, DomainTriangle::reference(), vec![DVec3::ONE; 3])?;
    /// assert_eq!(point.normal(u), None);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn normal(&self, u: DVec2) -> Option<DVec3> {
        let (_, [du, dv]) = self.eval_with_gradient(u);
        // (At unit scale: the product of tangents far from 1 underflows or overflows.)
        mesh_topo::scale::unit_normal(du, dv)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Normals do not depend on the scale (the tangents' cross product underflowed at
    /// 2^-600 and overflowed at 2^600: no normal anywhere).
    #[test]
    fn normals_do_not_depend_on_the_scale() {
        let unit = patch(3, 7);
        let u = DVec2::new(0.5, 0.4);
        let normal = unit.normal(u).unwrap();
        for exponent in [-600, 600] {
            let factor = 2f64.powi(exponent);
            let control = unit.control_points().iter().map(|p| *p * factor).collect();
            let scaled = TriBezier::new(3, *unit.domain(), control).unwrap();
            assert_eq!(scaled.normal(u), Some(normal), "2^{exponent}");
        }
    }

    fn patch(n: usize, seed: u64) -> TriBezier<DVec3> {
        // Deterministic pseudo-random control points.
        let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let control = (0..tri_count(n)).map(|_| DVec3::new(next(), next(), next())).collect();
        let domain = DomainTriangle::new([DVec2::new(0.1, 0.2), DVec2::new(1.3, -0.1), DVec2::new(0.4, 1.1)]).unwrap();
        TriBezier::new(n, domain, control).unwrap()
    }

    #[test]
    fn corners_are_interpolated() {
        for n in 0..7 {
            let p = patch(n, n as u64);
            let [t0, t1, t2] = p.domain().corners();
            assert!((p.eval(t0) - p.control_point([n, 0, 0])).length() < 1e-14);
            assert!((p.eval(t1) - p.control_point([0, n, 0])).length() < 1e-14);
            assert!((p.eval(t2) - p.control_point([0, 0, n])).length() < 1e-14);
        }
    }

    #[test]
    fn basis_sums_to_one_and_matches_direct_formula() {
        let mut basis = Vec::new();
        for n in 0..10 {
            let l = [0.2, 0.5, 0.3];
            bernstein_basis(n, l, &mut basis).unwrap();
            assert!((basis.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            for (beta, b) in multi_indices(n).zip(&basis) {
                let direct = multinomial(beta)
                    * l[0].powi(beta[0] as i32)
                    * l[1].powi(beta[1] as i32)
                    * l[2].powi(beta[2] as i32);
                assert!((direct - b).abs() < 1e-14, "{n} {beta:?}");
            }
        }
    }

    #[test]
    fn degree_elevation_and_subdivision_keep_the_surface() {
        let p = patch(4, 7);
        let e = p.elevate().unwrap();
        let pieces = p.split4();
        for &l in &[[0.2, 0.3, 0.5], [0.7, 0.1, 0.2], [0.05, 0.9, 0.05], [0.3, 0.3, 0.4]] {
            let u = p.domain().point(l);
            assert!((p.eval(u) - e.eval(u)).length() < 1e-14);
            for piece in &pieces {
                assert!((p.eval(u) - piece.eval(u)).length() < 1e-13);
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let p = patch(5, 3);
        let u = DVec2::new(0.5, 0.4);
        let (value, [du, dv]) = p.eval_with_gradient(u);
        assert!((value - p.eval(u)).length() < 1e-14);
        let h = 1e-6;
        let fd_u = (p.eval(u + DVec2::X * h) - p.eval(u - DVec2::X * h)) / (2.0 * h);
        let fd_v = (p.eval(u + DVec2::Y * h) - p.eval(u - DVec2::Y * h)) / (2.0 * h);
        assert!((du - fd_u).length() < 1e-7, "{du} {fd_u}");
        assert!((dv - fd_v).length() < 1e-7);
        let d = DVec2::new(0.3, -0.8);
        assert!((p.derivative(u, d) - (du * d.x + dv * d.y)).length() < 1e-12);
        let normal = p.normal(u).unwrap();
        assert!(normal.dot(du).abs() < 1e-12 && normal.dot(dv).abs() < 1e-12);
    }

    #[test]
    fn bad_input_is_rejected() {
        let d = DomainTriangle::reference();
        assert!(matches!(TriBezier::new(2, d, vec![0.0; 5]), Err(SplineError::Count { expected: 6, .. })));
        assert!(matches!(TriBezier::new(1, d, vec![0.0, f64::NAN, 1.0]), Err(SplineError::NonFinite { index: 1, .. })));
        assert!(TriBezier::new(1000, d, vec![0.0]).is_err());
        assert!(TriBezier::new(1, d, vec![0.0; 3]).unwrap().blossom(&[]).is_err());
    }

    /// Used to allocate `tri_count(1 << 20)` values (about 4 TiB) before failing.
    #[test]
    fn bernstein_basis_rejects_a_degree_beyond_the_limit_before_allocating() {
        let mut out = vec![7.0];
        for n in [MAX_BEZIER_DEGREE + 1, 1 << 20, usize::MAX] {
            let result = bernstein_basis(n, [1.0, 0.0, 0.0], &mut out);
            assert!(matches!(result, Err(SplineError::Degree { degree, max: MAX_BEZIER_DEGREE, .. }) if degree == n));
            assert_eq!(out, [7.0], "left untouched");
        }
        bernstein_basis(MAX_BEZIER_DEGREE, [0.2, 0.3, 0.5], &mut out).unwrap();
        assert_eq!(out.len(), tri_count(MAX_BEZIER_DEGREE));
    }

    /// A multi-index of the wrong degree, or one whose sum overflows (it wrapped to 0 for
    /// a degree-0 patch and then indexed out of bounds), is an error; the panicking
    /// accessor names the multi-index.
    #[test]
    fn control_point_checks_the_multi_index() {
        let p = TriBezier::new(0, DomainTriangle::reference(), vec![5.0]).unwrap();
        assert_eq!(p.try_control_point([0, 0, 0]), Ok(5.0));
        for beta in [[1, 0, 0], [usize::MAX, 1, 0], [0, usize::MAX, 1]] {
            assert_eq!(p.try_control_point(beta), Err(SplineError::MultiIndexDegree { beta, degree: 0 }));
        }
        let caught = std::panic::catch_unwind(|| p.control_point([usize::MAX, 1, 0])).unwrap_err();
        let message = caught.downcast_ref::<String>().unwrap();
        assert!(message.contains("multi-index [18446744073709551615, 1, 0] does not sum to the degree 0"), "{message}");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        #[test]
        fn casteljau_equals_bernstein_and_blossom_is_symmetric(
            n in 1usize..8, seed in 0u64..1000, a in 0.0..1.0f64, b in 0.0..1.0f64,
        ) {
            let p = patch(n, seed);
            let l = [a * (1.0 - b), b, (1.0 - a) * (1.0 - b)];
            let u = p.domain().point(l);
            prop_assert!((p.eval(u) - p.eval_bernstein(u)).length() < 1e-13);
            // Blossom symmetry: reversing the arguments does not change the value.
            let args: Vec<DVec2> = (0..n).map(|i| u + DVec2::new(i as f64 * 0.1, -(i as f64) * 0.05)).collect();
            let reversed: Vec<DVec2> = args.iter().rev().copied().collect();
            prop_assert!((p.blossom(&args).unwrap() - p.blossom(&reversed).unwrap()).length() < 1e-13);
        }

        #[test]
        fn affine_invariance(n in 1usize..7, seed in 0u64..1000, a in 0.0..1.0f64, b in 0.0..1.0f64,
                             m in proptest::array::uniform9(-2.0..2.0f64), t in proptest::array::uniform3(-5.0..5.0f64)) {
            let p = patch(n, seed);
            let map = |q: DVec3| DVec3::new(
                m[0] * q.x + m[1] * q.y + m[2] * q.z + t[0],
                m[3] * q.x + m[4] * q.y + m[5] * q.z + t[1],
                m[6] * q.x + m[7] * q.y + m[8] * q.z + t[2],
            );
            let mapped = TriBezier::new(n, *p.domain(), p.control_points().iter().map(|&q| map(q)).collect()).unwrap();
            let u = p.domain().point([a * (1.0 - b), b, (1.0 - a) * (1.0 - b)]);
            prop_assert!((mapped.eval(u) - map(p.eval(u))).length() < 1e-12);
        }

        #[test]
        fn convex_hull(n in 2usize..8, seed in 0u64..1000, a in 0.0..1.0f64, b in 0.0..1.0f64) {
            // Inside the domain the surface lies in the convex hull of its control points
            // (the hull itself, not only its bounding box; degree 1 has a flat hull).
            let p = patch(n, seed);
            let u = p.domain().point([a * (1.0 - b), b, (1.0 - a) * (1.0 - b)]);
            prop_assert!(crate::hull_check::in_convex_hull(p.eval(u), p.control_points(), 1e-13));
        }
    }
}
