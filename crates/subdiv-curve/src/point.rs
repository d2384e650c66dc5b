//! The point types the schemes work on.
//!
//! Every algorithm of this crate is generic over [`CurvePoint`], implemented for plain
//! arrays `[f64; D]` (any `D`), for [`glam::DVec2`] and [`glam::DVec3`], and for `f64`
//! (scalar data: basis functions, eigenvectors, function values).

use glam::{DVec2, DVec3};

/// A point of `R^DIM` as far as linear subdivision needs it: affine combinations and
/// coordinate access. All rules of this crate are affine combinations (weights summing to
/// 1), so results commute with affine maps of the points.
pub trait CurvePoint: Copy + core::fmt::Debug + PartialEq + Send + Sync + 'static {
    /// Number of coordinates.
    const DIM: usize;
    /// The origin.
    fn zero() -> Self;
    /// Coordinate `axis` (`0 <= axis < DIM`).
    fn coord(&self, axis: usize) -> f64;
    /// The point whose coordinate `axis` is `f(axis)`.
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self;
    /// `self + other`.
    fn plus(self, other: Self) -> Self;
    /// `self - other`.
    fn minus(self, other: Self) -> Self;
    /// `factor * self`.
    fn scale(self, factor: f64) -> Self;
    /// Whether every coordinate is finite.
    fn is_finite(&self) -> bool {
        (0..Self::DIM).all(|axis| self.coord(axis).is_finite())
    }
    /// The 3-vector of the first three coordinates (missing ones are 0): used by the
    /// curvature estimate and the SVG projection.
    fn to_dvec3(&self) -> DVec3 {
        let c = |axis: usize| if axis < Self::DIM { self.coord(axis) } else { 0.0 };
        DVec3::new(c(0), c(1), c(2))
    }
}

impl CurvePoint for f64 {
    const DIM: usize = 1;
    #[inline]
    fn zero() -> Self {
        0.0
    }
    #[inline]
    fn coord(&self, _axis: usize) -> f64 {
        *self
    }
    #[inline]
    fn from_fn(mut f: impl FnMut(usize) -> f64) -> Self {
        f(0)
    }
    #[inline]
    fn plus(self, other: Self) -> Self {
        self + other
    }
    #[inline]
    fn minus(self, other: Self) -> Self {
        self - other
    }
    #[inline]
    fn scale(self, factor: f64) -> Self {
        self * factor
    }
}

impl<const D: usize> CurvePoint for [f64; D] {
    const DIM: usize = D;
    #[inline]
    fn zero() -> Self {
        [0.0; D]
    }
    #[inline]
    fn coord(&self, axis: usize) -> f64 {
        self[axis]
    }
    #[inline]
    fn from_fn(f: impl FnMut(usize) -> f64) -> Self {
        core::array::from_fn(f)
    }
    #[inline]
    fn plus(self, other: Self) -> Self {
        core::array::from_fn(|k| self[k] + other[k])
    }
    #[inline]
    fn minus(self, other: Self) -> Self {
        core::array::from_fn(|k| self[k] - other[k])
    }
    #[inline]
    fn scale(self, factor: f64) -> Self {
        core::array::from_fn(|k| self[k] * factor)
    }
}

impl CurvePoint for DVec2 {
    const DIM: usize = 2;
    #[inline]
    fn zero() -> Self {
        DVec2::ZERO
    }
    #[inline]
    fn coord(&self, axis: usize) -> f64 {
        self[axis]
    }
    #[inline]
    fn from_fn(mut f: impl FnMut(usize) -> f64) -> Self {
        DVec2::new(f(0), f(1))
    }
    #[inline]
    fn plus(self, other: Self) -> Self {
        self + other
    }
    #[inline]
    fn minus(self, other: Self) -> Self {
        self - other
    }
    #[inline]
    fn scale(self, factor: f64) -> Self {
        self * factor
    }
}

impl CurvePoint for DVec3 {
    const DIM: usize = 3;
    #[inline]
    fn zero() -> Self {
        DVec3::ZERO
    }
    #[inline]
    fn coord(&self, axis: usize) -> f64 {
        self[axis]
    }
    #[inline]
    fn from_fn(mut f: impl FnMut(usize) -> f64) -> Self {
        DVec3::new(f(0), f(1), f(2))
    }
    #[inline]
    fn plus(self, other: Self) -> Self {
        self + other
    }
    #[inline]
    fn minus(self, other: Self) -> Self {
        self - other
    }
    #[inline]
    fn scale(self, factor: f64) -> Self {
        self * factor
    }
}

/// Checks that every point is finite.
///
/// # Errors
/// [`CurveError::NonFinite`](crate::CurveError::NonFinite) naming the first bad point and axis.
///
/// ```
/// use subdiv_curve::{CurveError, check_finite};
/// assert!(check_finite(&[[0.0, 1.0], [2.0, 3.0]]).is_ok());
/// let err = check_finite(&[[0.0, 1.0], [2.0, f64::INFINITY]]).unwrap_err();
/// assert!(matches!(err, CurveError::NonFinite { index: 1, axis: 1, .. }));
/// ```
pub fn check_finite<P: CurvePoint>(points: &[P]) -> Result<(), crate::CurveError> {
    for (index, point) in points.iter().enumerate() {
        for axis in 0..P::DIM {
            let value = point.coord(axis);
            if !value.is_finite() {
                return Err(crate::CurveError::NonFinite { index, axis, value });
            }
        }
    }
    Ok(())
}

/// Largest absolute coordinate (0 for no points).
pub(crate) fn largest_coordinate<P: CurvePoint>(points: &[P]) -> f64 {
    points.iter().flat_map(|p| (0..P::DIM).map(move |axis| p.coord(axis).abs())).fold(0.0, f64::max)
}

/// Checks that every point of a result computed from finite input is finite.
///
/// # Errors
/// [`CurveError::Overflow`](crate::CurveError::Overflow) naming `what` and the first point
/// that is not.
pub(crate) fn check_result_finite<P: CurvePoint>(what: &'static str, points: &[P]) -> Result<(), crate::CurveError> {
    match points.iter().position(|p| !p.is_finite()) {
        Some(index) => Err(crate::CurveError::Overflow { what, index }),
        None => Ok(()),
    }
}

/// Diagonal of the bounding box (0 for empty input): the length scale of tolerances.
/// Extents far from 1 are squared at unit scale (see [`unit_scale`]): their squares
/// overflowed beyond about 1e154 (an infinite tolerance accepted the first sweep of an
/// iteration) and underflowed below 1e-154.
pub(crate) fn bbox_diagonal<P: CurvePoint>(points: &[P]) -> f64 {
    let extents: Vec<f64> = (0..P::DIM)
        .map(|axis| {
            let (lo, hi) = points
                .iter()
                .map(|p| p.coord(axis))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)));
            if lo <= hi { hi - lo } else { 0.0 }
        })
        .collect();
    let scale = unit_scale(extents.iter().copied());
    extents.iter().map(|e| (e * scale) * (e * scale)).sum::<f64>().sqrt() / scale
}

/// The power of two that brings the largest magnitude of `values` into `[1, 2)` when it
/// lies outside `2^±256`, else 1 (also for none, zero or non-finite values). Scaling by
/// a power of two is exact, so quantities measured at that scale are those of the values
/// as given, without the squares' overflow or underflow; inside the range nothing changes.
/// (The rule of `mesh_topo::scale::unit_scale_of`, kept here: curves do not depend on
/// the mesh crate.)
pub(crate) fn unit_scale(values: impl IntoIterator<Item = f64>) -> f64 {
    const SAFE_EXPONENT: i32 = 256;
    let largest = values.into_iter().fold(0.0f64, |largest, x| largest.max(x.abs()));
    if largest == 0.0 || !largest.is_finite() {
        return 1.0;
    }
    let exponent = largest.log2().floor() as i32;
    if (-SAFE_EXPONENT..=SAFE_EXPONENT).contains(&exponent) {
        return 1.0;
    }
    // 2^-exponent, a normal number for every exponent kept.
    f64::from_bits(((1023 - exponent.clamp(-1022, 1022)) as u64) << 52)
}
