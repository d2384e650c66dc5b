//! The values a spline can take: anything that can be combined affinely.

use std::ops::{Add, Mul, Sub};

use glam::{DVec2, DVec3};

/// A control-point type: scalars, planar or spatial points.
///
/// Every algorithm of this crate only forms affine combinations of control points
/// (weights summing to one), so any vector space over `f64` works.
pub trait Point:
    Copy + Add<Output = Self> + Sub<Output = Self> + Mul<f64, Output = Self> + Send + Sync + PartialEq + 'static
{
    /// The zero vector.
    const ZERO: Self;
    /// Euclidean length.
    fn length(self) -> f64;
    /// Whether every coordinate is finite.
    fn is_finite_point(self) -> bool;
}

impl Point for f64 {
    const ZERO: Self = 0.0;
    fn length(self) -> f64 {
        self.abs()
    }
    fn is_finite_point(self) -> bool {
        self.is_finite()
    }
}

impl Point for DVec2 {
    const ZERO: Self = DVec2::ZERO;
    fn length(self) -> f64 {
        DVec2::length(self)
    }
    fn is_finite_point(self) -> bool {
        self.is_finite()
    }
}

impl Point for DVec3 {
    const ZERO: Self = DVec3::ZERO;
    fn length(self) -> f64 {
        DVec3::length(self)
    }
    fn is_finite_point(self) -> bool {
        self.is_finite()
    }
}

/// `a * wa + b * wb + c * wc`.
#[inline(always)]
pub(crate) fn combine3<P: Point>(a: P, b: P, c: P, w: [f64; 3]) -> P {
    a * w[0] + b * w[1] + c * w[2]
}
