//! Triangular multi-indices `β = (β0, β1, β2)`, `|β| = n`, and their storage order.
//!
//! Control points of a degree-`n` patch are stored row by row: row `k = β2` runs over
//! `j = β1 = 0..=n-k` (and `β0 = n - j - k`), so `β` sits at position
//! `k (n + 1) - k (k - 1) / 2 + j`. On a regular triangular grid whose corners are the
//! domain corners `t0, t1, t2`, position `(j, k)` is the grid point `t0 + (j/n)(t1 - t0)
//! + (k/n)(t2 - t0)`: the order is that of the grid rows from edge `t0 t1` to corner `t2`.

/// Number of multi-indices of degree `n`: `(n + 1)(n + 2) / 2`.
///
/// For the degrees of patches and grids (the count must fit in `usize`; see
/// [`checked_tri_count`] for a size given by a caller).
///
/// ```
/// use tri_spline::index::{multi_indices, tri_count};
/// assert_eq!(tri_count(3), 10);
/// assert_eq!(multi_indices(7).count(), tri_count(7));
/// ```
#[inline]
pub const fn tri_count(n: usize) -> usize {
    (n + 1) * (n + 2) / 2
}

/// `(n + 1)(n + 2) / 2`, or `None` if it does not fit in `usize` (from `n` about
/// `6.07e9` on 64-bit targets).
///
/// ```
/// use tri_spline::index::checked_tri_count;
/// assert_eq!(checked_tri_count(3), Some(10));
/// assert_eq!(checked_tri_count(usize::MAX), None);
/// ```
#[inline]
pub const fn checked_tri_count(n: usize) -> Option<usize> {
    // One of n + 1, n + 2 is even: halve it before multiplying, so that only a count
    // beyond `usize` overflows.
    let (Some(a), Some(b)) = (n.checked_add(1), n.checked_add(2)) else {
        return None;
    };
    if a % 2 == 0 { (a / 2).checked_mul(b) } else { a.checked_mul(b / 2) }
}

/// Number of multi-indices of all degrees `0..d` (exclusive): `d (d + 1)(d + 2) / 6`.
///
/// ```
/// use tri_spline::index::{tet_count, tri_count};
/// assert_eq!(tet_count(3), tri_count(0) + tri_count(1) + tri_count(2));
/// assert_eq!(tet_count(3), 10);
/// ```
#[inline]
pub const fn tet_count(d: usize) -> usize {
    d * (d + 1) * (d + 2) / 6
}

/// Storage position of `β = (n - j - k, j, k)` among the multi-indices of degree `n`.
///
/// ```
/// use tri_spline::index::{multi_indices, tri_index};
/// assert_eq!(tri_index(3, 1, 2), 8);
/// assert_eq!(multi_indices(3).position(|b| b == [0, 1, 2]), Some(8));
/// ```
#[inline(always)]
pub const fn tri_index(n: usize, j: usize, k: usize) -> usize {
    k * (n + 1) - (k * k.saturating_sub(1)) / 2 + j
}

/// Storage position of `β` (whose degree is `β0 + β1 + β2`).
///
/// ```
/// use tri_spline::index::{beta_index, multi_indices};
/// assert_eq!(beta_index([0, 1, 2]), 8);
/// assert!(multi_indices(5).enumerate().all(|(i, beta)| beta_index(beta) == i));
/// ```
#[inline(always)]
pub const fn beta_index(beta: [usize; 3]) -> usize {
    tri_index(beta[0] + beta[1] + beta[2], beta[1], beta[2])
}

/// The multi-indices of degree `n` in storage order, generated one by one (nothing is
/// allocated, so any `n` returns at once).
///
/// # Panics
/// If their number `(n + 1)(n + 2) / 2` does not fit in `usize` ([`checked_tri_count`]
/// is `None`): the iterator could not report its length.
///
/// ```
/// use tri_spline::index::multi_indices;
/// let all: Vec<[usize; 3]> = multi_indices(1).collect();
/// assert_eq!(all, vec![[1, 0, 0], [0, 1, 0], [0, 0, 1]]);
/// // Lazy: a huge degree costs nothing until iterated.
/// assert_eq!(multi_indices(1 << 30).next(), Some([1 << 30, 0, 0]));
/// ```
pub fn multi_indices(n: usize) -> impl ExactSizeIterator<Item = [usize; 3]> + Clone {
    let Some(remaining) = checked_tri_count(n) else {
        panic!("multi_indices: degree {n} has more multi-indices than usize can count");
    };
    MultiIndices { n, j: 0, k: 0, remaining }
}

/// The iterator of [`multi_indices`]: the next multi-index is `(n - j - k, j, k)`.
#[derive(Debug, Clone)]
struct MultiIndices {
    n: usize,
    j: usize,
    k: usize,
    remaining: usize,
}

impl Iterator for MultiIndices {
    type Item = [usize; 3];

    #[inline]
    fn next(&mut self) -> Option<[usize; 3]> {
        if self.remaining == 0 {
            return None;
        }
        let beta = [self.n - self.j - self.k, self.j, self.k];
        self.remaining -= 1;
        if self.j + self.k == self.n {
            self.j = 0;
            self.k += 1;
        } else {
            self.j += 1;
        }
        Some(beta)
    }

    #[inline]
    fn size_hint(&self) -> (usize, Option<usize>) {
        (self.remaining, Some(self.remaining))
    }
}

impl ExactSizeIterator for MultiIndices {}

/// `n! / (β0! β1! β2!)`, exactly as `f64` for the degrees used here.
///
/// ```
/// use tri_spline::index::{multi_indices, multinomial};
/// assert_eq!(multinomial([1, 1, 1]), 6.0);
/// assert_eq!(multinomial([2, 0, 3]), 10.0);
/// // The trinomial theorem: the coefficients of degree n sum to 3^n.
/// assert_eq!(multi_indices(4).map(multinomial).sum::<f64>(), 81.0);
/// ```
pub fn multinomial(beta: [usize; 3]) -> f64 {
    // Product of binomials, each exact in f64 up to far beyond the supported degrees
    // (a degree beyond `usize` is infinite).
    let Some(n) = beta[0].checked_add(beta[1]).and_then(|n| n.checked_add(beta[2])) else {
        return f64::INFINITY;
    };
    binomial(n, beta[0]) * binomial(beta[1] + beta[2], beta[1])
}

/// Binomial coefficient `C(n, k)` as `f64`: 0 for `k > n`, infinite beyond the `f64`
/// range (found after a few hundred factors, not `k` of them).
///
/// ```
/// use tri_spline::index::binomial;
/// assert_eq!(binomial(5, 2), 10.0);
/// assert_eq!(binomial(40, 20), 137_846_528_820.0);
/// assert_eq!(binomial(2, 5), 0.0);
/// assert!(binomial(1100, 550).is_infinite());
/// ```
pub fn binomial(n: usize, k: usize) -> f64 {
    if k > n {
        return 0.0;
    }
    let k = k.min(n - k);
    let mut value = 1.0;
    for i in 0..k {
        value = value * (n - i) as f64 / (i + 1) as f64;
        if value.is_infinite() {
            return value;
        }
    }
    value.round()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Arguments beyond the degrees in use end at once with the right value (they wrapped,
    /// or ran `k` iterations: hours at `usize::MAX / 2`).
    #[test]
    fn binomials_of_any_size_end() {
        assert_eq!(binomial(2, 3), 0.0);
        assert_eq!(binomial(10, 3), 120.0);
        assert_eq!(binomial(usize::MAX, usize::MAX / 2), f64::INFINITY);
        assert_eq!(binomial(usize::MAX, 0), 1.0);
        assert_eq!(multinomial([usize::MAX, 1, 0]), f64::INFINITY);
        assert_eq!(multinomial([1, 1, 1]), 6.0);
    }

    #[test]
    fn storage_order_is_dense_and_row_major() {
        for n in 0..9 {
            let betas: Vec<_> = multi_indices(n).collect();
            assert_eq!(betas.len(), tri_count(n));
            for (position, beta) in betas.iter().enumerate() {
                assert_eq!(beta.iter().sum::<usize>(), n);
                assert_eq!(beta_index(*beta), position);
            }
        }
        assert_eq!(tet_count(3), 1 + 3 + 6);
    }

    /// Used to allocate every multi-index up front: `multi_indices(1 << 20)` aborted the
    /// process allocating 13 TB, `1 << 31` panicked with a capacity overflow.
    #[test]
    fn multi_indices_are_lazy_and_counted_without_overflow() {
        assert_eq!(multi_indices(1 << 20).len(), ((1 << 20) + 1) * ((1 << 19) + 1));
        let huge = 1usize << 31;
        let mut it = multi_indices(huge);
        assert_eq!(it.len(), checked_tri_count(huge).unwrap());
        assert_eq!((it.next(), it.next()), (Some([huge, 0, 0]), Some([huge - 1, 1, 0])));
        assert_eq!(it.len(), checked_tri_count(huge).unwrap() - 2);
        // Row ends wrap to the next k (small n, all of them).
        assert_eq!(
            multi_indices(2).collect::<Vec<_>>(),
            [[2, 0, 0], [1, 1, 0], [0, 2, 0], [1, 0, 1], [0, 1, 1], [0, 0, 2]]
        );
        for n in 0..50 {
            assert_eq!(checked_tri_count(n), Some(tri_count(n)));
        }
        assert_eq!(checked_tri_count(1 << 31), Some(((1 << 31) + 1) * ((1 << 30) + 1)));
        assert_eq!(checked_tri_count(1 << 33), None);
        assert_eq!(checked_tri_count(usize::MAX - 1), None);
    }

    #[test]
    #[should_panic(expected = "more multi-indices than usize can count")]
    fn multi_indices_beyond_usize_panic_with_a_message() {
        let _ = multi_indices(usize::MAX);
    }

    #[test]
    fn multinomials() {
        assert_eq!(multinomial([1, 1, 1]), 6.0);
        assert_eq!(multinomial([2, 0, 0]), 1.0);
        assert_eq!(multinomial([2, 1, 1]), 12.0);
        assert_eq!(binomial(24, 12), 2_704_156.0);
    }
}
