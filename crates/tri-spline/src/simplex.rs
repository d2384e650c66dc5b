//! Bivariate simplex splines by their recurrence (ALGORITHMS.md §11.1).
//!
//! For a knot multiset `V` of at least three points in the plane, `M(u | V)` is:
//! * `|V| = 3`: `1 / |det(V)|` on the half-open triangle `[V)` and 0 elsewhere (see
//!   [`in_half_open`]), `det` being twice the signed area;
//! * `|V| >= 4`: for any three affinely independent knots `W = {w0, w1, w2}` of `V`,
//!   `M(u | V) = sum_j λ_j(u) M(u | V \ {w_j})`, with `λ` the barycentric coordinates of
//!   `u` with respect to `W`.
//!
//! With this normalisation the recurrence has coefficient one: it is Micchelli's
//! recurrence (coefficient `m / (m - 2)`, `m = |V| - 1`) for the simplex spline of
//! integral one, multiplied by `(m - 2)! / m!`, so that `M(· | V)` integrates to
//! `1 / ((|V| - 1)(|V| - 2))` (degree 0: `1/|det|` over an area `|det|/2` gives `1/2`).
//! ALGORITHMS.md §11.1 writes the factor as `2! (m-2)! / m!`, which is off by 2 against
//! its own base case; the test `integral_matches_normalisation` measures it. DMS only
//! uses ratios (it rescales by knot-triangle areas), so this does not affect the basis.
//! `M(· | V)` is a
//! piecewise polynomial of degree `|V| - 3`, non-negative, supported on the convex hull
//! of `V`. Its derivative along a vector `y = sum μ_j w_j` (`sum μ_j = 0`) is
//! `D_y M(u | V) = (|V| - 3) sum_j μ_j M(u | V \ {w_j})`.
//!
//! The value does not depend on the choice of `W` ([`WChoice`] selects one
//! deterministically; the tests compare the choices). Subsets of `V` are keyed by a
//! 64-bit mask, so at most 64 knots; every subset reached by the recurrence is
//! evaluated once per query point (memoised).
//!
//! References: C. A. Micchelli, A constructive approach to Kergin interpolation in R^k:
//! multivariate B-splines and Lagrange interpolation, Rocky Mountain J. Math. 10 (1980)
//! 485–497; C. de Boor, Splines as linear combinations of B-splines (1976).

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::DVec2;

use crate::SplineError;
use crate::domain::{BaryMap, in_half_open, is_degenerate, orient};

/// Largest number of knots of one simplex spline (subsets are 64-bit masks).
pub const MAX_SIMPLEX_KNOTS: usize = 64;

/// How the three knots `W` of each recurrence step are chosen.
///
/// The value of the recurrence does not depend on the choice, but its rounding error
/// does: a small `W` (three knots of one cluster) far from `u` gives large barycentric
/// coordinates of both signs and cancellation. Measured on DMS bases over a 4x4 square
/// grid with knot clouds of radius 0.12 edge, the worst partition-of-unity error over
/// 2500 interior points is 6e-15 / 8e-15 / 3e-14 for degrees 1 / 2 / 3 with `Widest`
/// and 2e-13 / 4e-12 / 7e-10 with `First`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum WChoice {
    /// A nearly largest-area triple (greedy: the first knot, the knot farthest from it,
    /// the knot farthest from their line, then the first knot replaced by the knot
    /// farthest from the line of the other two). The default.
    #[default]
    Widest,
    /// The first three affinely independent knots of the subset, in knot order
    /// (ALGORITHMS.md §11.1's suggestion).
    First,
    /// The last three (searching backwards).
    Last,
    /// The first, the middle and the last knot of the subset when independent,
    /// otherwise as `First`.
    Spread,
}

/// A fast hasher for subset masks (keys are already well spread 64-bit words).
#[derive(Default, Clone, Copy)]
pub(crate) struct MaskHasher(u64);

impl Hasher for MaskHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ u64::from(b)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (x ^ (x >> 31)).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }
}

/// Knot sets up to this size memoise in a dense table indexed by the subset mask
/// (2^15 entries); larger ones in a hash map.
const DENSE_MEMO_BITS: usize = 15;

/// Memo table of `M(u | subset)` for one query point and one knot set.
///
/// The dense table is invalidated in O(1) by bumping a generation stamp, so reusing it
/// across query points costs nothing.
#[derive(Debug, Default, Clone)]
pub(crate) struct Memo {
    dense: Vec<(u32, f64)>,
    stamp: u32,
    use_dense: bool,
    hash: HashMap<u64, f64, BuildHasherDefault<MaskHasher>>,
}

impl Memo {
    /// Forgets all values; prepares for subsets of a knot set of `knot_count` knots.
    pub fn reset(&mut self, knot_count: usize) {
        self.use_dense = knot_count <= DENSE_MEMO_BITS;
        if self.use_dense {
            let size = 1usize << knot_count;
            if self.dense.len() < size {
                self.dense.resize(size, (0, 0.0));
            }
            self.stamp = self.stamp.wrapping_add(1);
            if self.stamp == 0 {
                self.dense.iter_mut().for_each(|e| e.0 = 0);
                self.stamp = 1;
            }
        } else {
            self.hash.clear();
        }
    }

    #[inline]
    fn get(&self, mask: u64) -> Option<f64> {
        if self.use_dense {
            let (stamp, value) = self.dense[mask as usize];
            (stamp == self.stamp).then_some(value)
        } else {
            self.hash.get(&mask).copied()
        }
    }

    #[inline]
    fn insert(&mut self, mask: u64, value: f64) {
        if self.use_dense {
            self.dense[mask as usize] = (self.stamp, value);
        } else {
            self.hash.insert(mask, value);
        }
    }
}

/// The recurrence over subsets of `knots`, for one query point `u`. The caller resets
/// the memo for the knot set first.
pub(crate) struct SimplexRecurrence<'a> {
    pub knots: &'a [DVec2],
    pub u: DVec2,
    pub choice: WChoice,
    pub memo: &'a mut Memo,
    /// A subset found to be all collinear (then the spline is not a function).
    pub degenerate: Option<u64>,
}

/// Indices of the set bits of `mask`, ascending.
#[inline]
fn bits(mask: u64) -> impl DoubleEndedIterator<Item = usize> + Clone {
    (0..64).filter(move |&i| mask >> i & 1 == 1)
}

/// Indices of the set bits of `mask`, ascending, without scanning all 64 positions.
#[inline]
fn set_bits(mut mask: u64) -> impl Iterator<Item = usize> + Clone {
    std::iter::from_fn(move || {
        (mask != 0).then(|| {
            let i = mask.trailing_zeros() as usize;
            mask &= mask - 1;
            i
        })
    })
}

impl SimplexRecurrence<'_> {
    /// Three affinely independent knots of the subset (positions), or `None` if all of
    /// them are collinear.
    pub fn choose_w(&self, mask: u64) -> Option<[usize; 3]> {
        let knots = self.knots;
        let independent = |a: usize, b: usize, c: usize| !is_degenerate(knots[a], knots[b], knots[c]);
        let search = |order: &mut dyn Iterator<Item = usize>| -> Option<[usize; 3]> {
            let order: Vec<usize> = order.collect();
            let &a = order.first()?;
            let &b = order.iter().find(|&&b| knots[b] != knots[a])?;
            let &c = order.iter().find(|&&c| c != a && c != b && independent(a, b, c))?;
            Some([a, b, c])
        };
        match self.choice {
            WChoice::Widest => {
                // Greedy largest-area triple, ties to the lowest index.
                let farthest_from_point = |p: DVec2| {
                    let mut best = (usize::MAX, -1.0);
                    for i in set_bits(mask) {
                        let d = (knots[i] - p).length_squared();
                        if d > best.1 {
                            best = (i, d);
                        }
                    }
                    best.0
                };
                let farthest_from_line = |a: usize, b: usize| {
                    let mut best = (usize::MAX, -1.0);
                    for i in set_bits(mask) {
                        let d = orient(knots[a], knots[b], knots[i]).abs();
                        if i != a && i != b && d > best.1 {
                            best = (i, d);
                        }
                    }
                    best.0
                };
                if mask.count_ones() < 3 {
                    return None;
                }
                let a = mask.trailing_zeros() as usize;
                let b = farthest_from_point(knots[a]);
                let c = farthest_from_line(a, b);
                let a = farthest_from_line(b, c);
                if independent(a, b, c) { Some([a, b, c]) } else { search(&mut set_bits(mask)) }
            }
            WChoice::First => search(&mut set_bits(mask)),
            WChoice::Last => search(&mut bits(mask).rev()),
            WChoice::Spread => {
                let all: Vec<usize> = set_bits(mask).collect();
                let (a, b, c) = (all[0], all[all.len() / 2], all[all.len() - 1]);
                if independent(a, b, c) { Some([a, b, c]) } else { search(&mut all.into_iter()) }
            }
        }
    }

    /// `M(u | knots[mask])`.
    pub fn value(&mut self, mask: u64) -> f64 {
        if let Some(v) = self.memo.get(mask) {
            return v;
        }
        let v = self.compute(mask);
        self.memo.insert(mask, v);
        v
    }

    fn compute(&mut self, mask: u64) -> f64 {
        let u = self.u;
        // Outside the bounding box of the knots (strictly) the spline vanishes; on its
        // boundary the half-open rule of the base case decides.
        let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
        for i in set_bits(mask) {
            lo = lo.min(self.knots[i]);
            hi = hi.max(self.knots[i]);
        }
        if u.x < lo.x || u.y < lo.y || u.x > hi.x || u.y > hi.y {
            return 0.0;
        }
        if mask.count_ones() == 3 {
            let mut it = set_bits(mask);
            let (a, b, c) =
                (self.knots[it.next().unwrap()], self.knots[it.next().unwrap()], self.knots[it.next().unwrap()]);
            if is_degenerate(a, b, c) {
                self.degenerate.get_or_insert(mask);
                return 0.0;
            }
            return if in_half_open(u, a, b, c) { 1.0 / orient(a, b, c).abs() } else { 0.0 };
        }
        let Some(w) = self.choose_w(mask) else {
            self.degenerate.get_or_insert(mask);
            return 0.0;
        };
        let map = BaryMap::new(self.knots[w[0]], self.knots[w[1]], self.knots[w[2]])
            .expect("internal: W was checked to be independent");
        let l = map.coords(u);
        let mut sum = 0.0;
        for (j, &wj) in w.iter().enumerate() {
            if l[j] != 0.0 {
                sum += l[j] * self.value(mask & !(1u64 << wj));
            }
        }
        sum
    }

    /// `D_y M(u | knots[mask]) = (|V| - 3) sum_j μ_j M(u | V \ {w_j})`.
    pub fn derivative(&mut self, mask: u64, y: DVec2) -> f64 {
        let order = mask.count_ones() as f64 - 3.0;
        if order <= 0.0 {
            return 0.0;
        }
        let Some(w) = self.choose_w(mask) else {
            self.degenerate.get_or_insert(mask);
            return 0.0;
        };
        let map = BaryMap::new(self.knots[w[0]], self.knots[w[1]], self.knots[w[2]])
            .expect("internal: W was checked to be independent");
        let mu = map.direction(y);
        let mut sum = 0.0;
        for (j, &wj) in w.iter().enumerate() {
            sum += mu[j] * self.value(mask & !(1u64 << wj));
        }
        order * sum
    }
}

/// A simplex spline `M(· | V)` with the normalisation of the module docs.
#[derive(Debug, Clone, PartialEq)]
pub struct SimplexSpline {
    knots: Vec<DVec2>,
}

impl SimplexSpline {
    /// The simplex spline of `knots` (3 to [`MAX_SIMPLEX_KNOTS`] points, not all collinear).
    ///
    /// # Errors
    /// [`SplineError::TooFewKnots`], [`SplineError::Count`] above 64 knots,
    /// [`SplineError::NonFinite`], [`SplineError::DegenerateSimplex`] naming three
    /// collinear (or coincident) knots: the knots must be in general position.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::SimplexSpline;
    /// // Degree 0: 1/|det| on the half-open triangle.
    /// let m = SimplexSpline::new(vec![DVec2::ZERO, DVec2::X, DVec2::Y])?;
    /// assert_eq!(m.eval(DVec2::new(0.2, 0.2))?, 1.0);
    /// assert_eq!(m.eval(DVec2::new(0.8, 0.8))?, 0.0);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn new(knots: Vec<DVec2>) -> Result<Self, SplineError> {
        if knots.len() < 3 {
            return Err(SplineError::TooFewKnots { got: knots.len() });
        }
        if knots.len() > MAX_SIMPLEX_KNOTS {
            return Err(SplineError::Count {
                what: "simplex spline knots",
                expected: MAX_SIMPLEX_KNOTS,
                got: knots.len(),
            });
        }
        if let Some(index) = knots.iter().position(|k| !k.is_finite()) {
            return Err(SplineError::NonFinite { what: "knot", index });
        }
        // General position: no three knots collinear (else some subset reached by the
        // recurrence may be a measure on a line rather than a function).
        for a in 0..knots.len() {
            for b in a + 1..knots.len() {
                for c in b + 1..knots.len() {
                    if is_degenerate(knots[a], knots[b], knots[c]) {
                        return Err(SplineError::DegenerateSimplex { knots: vec![a, b, c] });
                    }
                }
            }
        }
        Ok(Self { knots })
    }

    /// The knots.
    pub fn knots(&self) -> &[DVec2] {
        &self.knots
    }

    /// The polynomial degree `|V| - 3`.
    pub fn degree(&self) -> usize {
        self.knots.len() - 3
    }

    fn full_mask(&self) -> u64 {
        if self.knots.len() == 64 { u64::MAX } else { (1u64 << self.knots.len()) - 1 }
    }

    /// `M(u | V)` with the default choice of `W`.
    ///
    /// # Errors
    /// None in practice (the knots were checked to be in general position); kept for
    /// [`SplineError::DegenerateSimplex`] should the recurrence meet a degenerate subset.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::SimplexSpline;
    /// // The corners of the unit square: the pyramid min(x, y, 1 - x, 1 - y) of volume 1/6.
    /// let m = SimplexSpline::new(vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y])?;
    /// assert_eq!(m.degree(), 1);
    /// for (x, y) in [(0.5f64, 0.25f64), (0.2, 0.7), (0.9, 0.4)] {
    ///     let pyramid = f64::min(x.min(y), (1.0 - x).min(1.0 - y));
    ///     assert!((m.eval(DVec2::new(x, y))? - pyramid).abs() < 1e-14);
    /// }
    /// assert_eq!(m.eval(DVec2::new(1.5, 0.5))?, 0.0);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval(&self, u: DVec2) -> Result<f64, SplineError> {
        self.eval_with(u, WChoice::Widest)
    }

    /// `M(u | V)` with the given choice of `W` (the value does not depend on it).
    ///
    /// # Errors
    /// As [`eval`](Self::eval).
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::{SimplexSpline, WChoice};
    /// let knots = vec![DVec2::ZERO, DVec2::X, DVec2::new(1.2, 0.9), DVec2::new(0.1, 1.1), DVec2::new(0.5, 0.45)];
    /// let m = SimplexSpline::new(knots)?;
    /// let u = DVec2::new(0.4, 0.3);
    /// let value = m.eval_with(u, WChoice::Widest)?;
    /// assert!(value > 0.0);
    /// for choice in [WChoice::First, WChoice::Last, WChoice::Spread] {
    ///     assert!((m.eval_with(u, choice)? - value).abs() < 1e-12);
    /// }
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval_with(&self, u: DVec2, choice: WChoice) -> Result<f64, SplineError> {
        let mut memo = Memo::default();
        memo.reset(self.knots.len());
        let mut rec = SimplexRecurrence { knots: &self.knots, u, choice, memo: &mut memo, degenerate: None };
        let v = rec.value(self.full_mask());
        match rec.degenerate {
            Some(mask) => Err(SplineError::DegenerateSimplex { knots: bits(mask).collect() }),
            None => Ok(v),
        }
    }

    /// The directional derivative `D_y M(u | V)`.
    ///
    /// # Errors
    /// As [`eval`](Self::eval).
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::SimplexSpline;
    /// // The pyramid min(x, y, 1 - x, 1 - y) over the unit square (see `eval`).
    /// let m = SimplexSpline::new(vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y])?;
    /// let u = DVec2::new(0.2, 0.4); // where x is the smallest of the four
    /// assert!((m.derivative(u, DVec2::X)? - 1.0).abs() < 1e-14);
    /// assert!(m.derivative(u, DVec2::Y)?.abs() < 1e-14);
    /// let u = DVec2::new(0.9, 0.5); // where 1 - x is
    /// assert!((m.derivative(u, DVec2::X)? + 1.0).abs() < 1e-14);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn derivative(&self, u: DVec2, y: DVec2) -> Result<f64, SplineError> {
        let mut memo = Memo::default();
        memo.reset(self.knots.len());
        let mut rec =
            SimplexRecurrence { knots: &self.knots, u, choice: WChoice::Widest, memo: &mut memo, degenerate: None };
        let v = rec.derivative(self.full_mask(), y);
        match rec.degenerate {
            Some(mask) => Err(SplineError::DegenerateSimplex { knots: bits(mask).collect() }),
            None => Ok(v),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn knots(seed: u64, count: usize) -> Vec<DVec2> {
        let mut state = seed.wrapping_add(0x1234_5678);
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..count).map(|_| DVec2::new(next(), next())).collect()
    }

    #[test]
    fn value_is_independent_of_w_choice() {
        for seed in 0..20 {
            let m = SimplexSpline::new(knots(seed, 6)).unwrap();
            for i in 0..10 {
                let u = DVec2::new(0.05 + 0.09 * i as f64, 0.93 - 0.08 * i as f64);
                let a = m.eval_with(u, WChoice::Widest).unwrap();
                for choice in [WChoice::First, WChoice::Last, WChoice::Spread] {
                    let b = m.eval_with(u, choice).unwrap();
                    assert!((a - b).abs() <= 1e-12 * a.abs().max(1.0), "{choice:?}");
                }
                assert!(a >= 0.0);
            }
        }
    }

    #[test]
    fn integral_matches_normalisation() {
        // M integrates to 1 / ((|V| - 1)(|V| - 2)) (module docs).
        let v = knots(3, 5);
        let m = SimplexSpline::new(v.clone()).unwrap();
        let (n, mut sum) = (400, 0.0);
        let h = 1.0 / n as f64;
        for i in 0..n {
            for j in 0..n {
                sum += m.eval(DVec2::new((i as f64 + 0.5) * h, (j as f64 + 0.5) * h)).unwrap() * h * h;
            }
        }
        let expected = 1.0 / (4.0 * 3.0);
        assert!((sum - expected).abs() < 2e-3, "{sum} vs {expected}");
    }

    #[test]
    fn derivative_matches_finite_differences() {
        let m = SimplexSpline::new(knots(11, 7)).unwrap();
        let h = 1e-6;
        for i in 0..8 {
            let u = DVec2::new(0.3 + 0.05 * i as f64, 0.6 - 0.04 * i as f64);
            for y in [DVec2::X, DVec2::Y, DVec2::new(0.6, -0.8)] {
                let fd = (m.eval(u + y * h).unwrap() - m.eval(u - y * h).unwrap()) / (2.0 * h);
                let d = m.derivative(u, y).unwrap();
                assert!((fd - d).abs() < 1e-5 * d.abs().max(1.0), "{u} {y}: {d} vs {fd}");
            }
        }
    }

    #[test]
    fn bad_knots_are_rejected() {
        assert!(matches!(SimplexSpline::new(vec![DVec2::ZERO, DVec2::X]), Err(SplineError::TooFewKnots { got: 2 })));
        assert!(matches!(
            SimplexSpline::new(vec![DVec2::ZERO, DVec2::X, DVec2::X * 2.0, DVec2::X * 3.0]),
            Err(SplineError::DegenerateSimplex { .. })
        ));
        // Not in general position: three collinear knots among four.
        assert!(matches!(
            SimplexSpline::new(vec![DVec2::ZERO, DVec2::Y, DVec2::X, DVec2::X * 2.0]),
            Err(SplineError::DegenerateSimplex { knots }) if knots == vec![0, 2, 3]
        ));
    }
}
