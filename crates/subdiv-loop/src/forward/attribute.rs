//! Per-vertex data that refines with the subdivision stencils.

use glam::{DVec2, DVec3, DVec4, Vec2, Vec3, Vec4};

use crate::LoopError;

/// Per-vertex data that supports weighted sums: positions, colours, texture
/// coordinates, scalar fields, ... (OpenSubdiv calls these *primvars*).
///
/// Subdivision computes every fine value as an affine combination of coarse values
/// (weights summing to 1), through exactly these two operations. The stencils applied
/// to an attribute are the same code as the ones applied to positions, so refining
/// positions as an attribute gives bit-identical results to [`subdivide`].
///
/// Implemented for `f64`, `f32`, the `glam` vectors `DVec2/3/4`, `Vec2/3/4` (colours:
/// weights are rounded to `f32`) and `[f64; N]` (any fixed number of channels).
///
/// ```
/// use subdiv_loop::forward::Attribute;
///
/// #[derive(Clone, Debug, PartialEq)]
/// struct Temperature(f64);
///
/// impl Attribute for Temperature {
///     fn scaled(&self, weight: f64) -> Self {
///         Temperature(self.0 * weight)
///     }
///     fn add_scaled(&mut self, other: &Self, weight: f64) {
///         self.0 += other.0 * weight;
///     }
/// }
/// let mut t = Temperature(1.0).scaled(0.5);
/// t.add_scaled(&Temperature(3.0), 0.5);
/// assert_eq!(t, Temperature(2.0));
/// ```
///
/// [`subdivide`]: crate::forward::subdivide
pub trait Attribute: Clone + Send + Sync {
    /// `self * weight`.
    fn scaled(&self, weight: f64) -> Self;

    /// `self += other * weight`.
    fn add_scaled(&mut self, other: &Self, weight: f64);

    /// `self += other`.
    #[inline]
    fn add(&mut self, other: &Self) {
        self.add_scaled(other, 1.0);
    }

    /// Whether every component is finite (no NaN, no infinity). The refining functions
    /// refuse input values for which this is false
    /// ([`LoopError::NonFiniteAttribute`]), and report finite input whose refinement
    /// is not ([`LoopError::AttributeOverflow`]), so that a NaN never spreads silently
    /// over its neighbours' fine values. The default, `true`, is for types without such
    /// a notion; the implementations of this crate test every component.
    #[inline]
    fn is_finite(&self) -> bool {
        true
    }
}

/// [`LoopError::NonFiniteAttribute`] for the first of `values` that is not finite.
pub(crate) fn check_finite_values<T: Attribute>(values: &[T]) -> Result<(), LoopError> {
    match values.iter().position(|value| !value.is_finite()) {
        Some(vertex) => Err(LoopError::NonFiniteAttribute { vertex }),
        None => Ok(()),
    }
}

/// `refined`, or [`LoopError::AttributeOverflow`] for the first of its values that is not
/// finite (the input was checked: only an overflow of the sums makes one).
pub(crate) fn checked_refined<T: Attribute>(refined: Vec<T>) -> Result<Vec<T>, LoopError> {
    match refined.iter().position(|value| !value.is_finite()) {
        Some(vertex) => Err(LoopError::AttributeOverflow { vertex }),
        None => Ok(refined),
    }
}

impl Attribute for f64 {
    #[inline]
    fn scaled(&self, weight: f64) -> Self {
        self * weight
    }
    #[inline]
    fn is_finite(&self) -> bool {
        f64::is_finite(*self)
    }
    #[inline]
    fn add_scaled(&mut self, other: &Self, weight: f64) {
        *self += other * weight;
    }
    #[inline]
    fn add(&mut self, other: &Self) {
        *self += other;
    }
}

impl Attribute for f32 {
    #[inline]
    fn scaled(&self, weight: f64) -> Self {
        self * weight as f32
    }
    #[inline]
    fn is_finite(&self) -> bool {
        f32::is_finite(*self)
    }
    #[inline]
    fn add_scaled(&mut self, other: &Self, weight: f64) {
        *self += other * weight as f32;
    }
    #[inline]
    fn add(&mut self, other: &Self) {
        *self += other;
    }
}

macro_rules! impl_vector_attribute {
    ($($ty:ty => $scalar:ty),* $(,)?) => {$(
        impl Attribute for $ty {
            #[inline]
            fn scaled(&self, weight: f64) -> Self {
                *self * (weight as $scalar)
            }
            #[inline]
            fn add_scaled(&mut self, other: &Self, weight: f64) {
                *self += *other * (weight as $scalar);
            }
            #[inline]
            fn add(&mut self, other: &Self) {
                *self += *other;
            }
            #[inline]
            fn is_finite(&self) -> bool {
                <$ty>::is_finite(*self)
            }
        }
    )*};
}

impl_vector_attribute!(DVec2 => f64, DVec3 => f64, DVec4 => f64, Vec2 => f32, Vec3 => f32, Vec4 => f32);

impl<const N: usize> Attribute for [f64; N] {
    #[inline]
    fn scaled(&self, weight: f64) -> Self {
        self.map(|x| x * weight)
    }
    #[inline]
    fn is_finite(&self) -> bool {
        self.iter().all(|x| x.is_finite())
    }
    #[inline]
    fn add_scaled(&mut self, other: &Self, weight: f64) {
        for (x, y) in self.iter_mut().zip(other) {
            *x += y * weight;
        }
    }
    #[inline]
    fn add(&mut self, other: &Self) {
        for (x, y) in self.iter_mut().zip(other) {
            *x += y;
        }
    }
}

/// A sparse row vector: sorted `(column, weight)` pairs without repeats.
///
/// Refining the unit rows `e_i` of the coarse vertices as an attribute gives the rows of
/// the subdivision matrix, through the very stencil code used for positions.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct SparseRow(pub(crate) Vec<(u32, f64)>);

impl SparseRow {
    /// The unit row `e_column`.
    pub(crate) fn unit(column: u32) -> Self {
        Self(vec![(column, 1.0)])
    }
}

impl Attribute for SparseRow {
    fn scaled(&self, weight: f64) -> Self {
        Self(self.0.iter().map(|&(c, w)| (c, w * weight)).collect())
    }

    fn add_scaled(&mut self, other: &Self, weight: f64) {
        // Merge two sorted lists.
        let mut merged = Vec::with_capacity(self.0.len() + other.0.len());
        let (mut i, mut j) = (0, 0);
        while i < self.0.len() || j < other.0.len() {
            let take_left = j == other.0.len() || (i < self.0.len() && self.0[i].0 < other.0[j].0);
            let take_right = i == self.0.len() || (j < other.0.len() && other.0[j].0 < self.0[i].0);
            if take_left {
                merged.push(self.0[i]);
                i += 1;
            } else if take_right {
                merged.push((other.0[j].0, other.0[j].1 * weight));
                j += 1;
            } else {
                merged.push((self.0[i].0, self.0[i].1 + other.0[j].1 * weight));
                i += 1;
                j += 1;
            }
        }
        self.0 = merged;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sparse_rows_merge_sorted_and_sum_repeats() {
        let mut a = SparseRow(vec![(1, 1.0), (4, 2.0)]);
        a.add_scaled(&SparseRow(vec![(0, 1.0), (4, 1.0), (7, 3.0)]), 0.5);
        assert_eq!(a, SparseRow(vec![(0, 0.5), (1, 1.0), (4, 2.5), (7, 1.5)]));
        assert_eq!(a.scaled(2.0).0[0], (0, 1.0));
    }

    #[test]
    fn vector_attributes_are_affine() {
        let mut v = DVec3::new(1.0, 2.0, 3.0).scaled(0.25);
        v.add_scaled(&DVec3::splat(4.0), 0.75);
        assert_eq!(v, DVec3::new(3.25, 3.5, 3.75));
        let mut c = [1.0, 0.0].scaled(0.5);
        c.add(&[0.5, 0.5]);
        assert_eq!(c, [1.0, 0.5]);
        let mut x = 2.0f32.scaled(0.5);
        x.add_scaled(&4.0, 0.25);
        assert_eq!(x, 2.0);
    }
}
