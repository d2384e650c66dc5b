//! Reverse Chaikin: exact multiresolution of polygons (Samavati & Bartels local reversal;
//! spec §3).
//!
//! Every fine pair `(f_{2i}, f_{2i+1})` on one coarse segment determines both end points of
//! that segment (inverting the Chaikin block `[[3/4, 1/4], [1/4, 3/4]]`), so every coarse
//! point gets two candidates, `a_i` from its own segment and `b_i` from the previous one:
//!
//! ```text
//! a_i = 3/2 f_{2i} - 1/2 f_{2i+1}        b_i = 3/2 f_{2i-1} - 1/2 f_{2i-2}
//! c_i = (a_i + b_i)/2 = -1/4 f_{2i-2} + 3/4 f_{2i-1} + 3/4 f_{2i} - 1/4 f_{2i+1}
//! d_i = (a_i - b_i)/2 =  1/4 f_{2i-2} - 3/4 f_{2i-1} + 3/4 f_{2i} - 1/4 f_{2i+1}
//! ```
//!
//! `c_i` is the local least-squares choice; the stored detail is `d_i` (half the seed's
//! local error `e_i = a_i - b_i`). Reconstruction takes `a_i = c_i + d_i`,
//! `b_{i+1} = c_{i+1} - d_{i+1}`, `f_{2i} = 3/4 a_i + 1/4 b_{i+1}`,
//! `f_{2i+1} = 1/4 a_i + 3/4 b_{i+1}`. If `F` is a Chaikin refinement, `a_i = b_i = c_i` and
//! all details vanish. `|C| + |D| = |F|`, both directions run in linear time.
//!
//! **Open polygons** use the endpoint-keeping Chaikin of [`CurveScheme::chaikin`](crate::CurveScheme::chaikin)
//! (`F = f_0, Q_0, R_0, ..., Q_{n-2}, R_{n-2}, f_last`, `2n` points for `n` coarse
//! points). The end points have a single candidate from their segment; they are set to the
//! kept fine end points and the detail records the difference: `c_0 = f_0`,
//! `d_0 = a_0 - f_0`, `c_{n-1} = f_last`, `d_{n-1} = b_{n-1} - f_last` (spec §3.2).
//!
//! ```
//! use subdiv_curve::{CurveScheme, Topology, reverse::{reconstruct_chaikin, reverse_chaikin}};
//! let coarse = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]];
//! let fine = CurveScheme::chaikin().refine(&coarse, Topology::Closed, 1)?;
//! let split = reverse_chaikin(&fine, Topology::Closed)?;
//! assert_eq!(split.coarse, coarse.to_vec());
//! assert!(split.details.iter().all(|d| d == &[0.0, 0.0]));
//! // Any polygon of even length splits and reconstructs.
//! let mut moved = fine.clone();
//! moved[3][1] += 0.5;
//! let split = reverse_chaikin(&moved, Topology::Closed)?;
//! let back = reconstruct_chaikin(&split.coarse, &split.details, Topology::Closed)?;
//! assert!(back.iter().zip(&moved).all(|(a, b)| (a[0] - b[0]).abs() < 1e-15 && (a[1] - b[1]).abs() < 1e-15));
//! # Ok::<(), subdiv_curve::CurveError>(())
//! ```

use crate::scheme::Topology;
use crate::{CurveError, CurvePoint};

/// Coarse points and detail coefficients of one reverse Chaikin step.
#[derive(Debug, Clone, PartialEq)]
pub struct ChaikinSplit<P> {
    /// The coarse polygon (`n` points).
    pub coarse: Vec<P>,
    /// One detail vector per coarse point (`d_i`, see the [module docs](self)).
    pub details: Vec<P>,
}

fn combine<P: CurvePoint>(terms: [(P, f64); 4]) -> P {
    terms.iter().fold(P::zero(), |sum, &(p, w)| sum.plus(p.scale(w)))
}

/// Number of coarse points of a fine polygon, or the reason it is not a Chaikin length.
fn coarse_len(fine_len: usize, topology: Topology) -> Result<usize, CurveError> {
    let closed = topology.is_closed();
    let needed = if closed { 6 } else { 4 };
    if fine_len < needed {
        return Err(CurveError::TooFewPoints { what: "reverse Chaikin".into(), needed, got: fine_len, closed });
    }
    if !fine_len.is_multiple_of(2) {
        return Err(CurveError::IncompatibleLength {
            what: "reverse Chaikin",
            detail: format!(
                "{fine_len} points: Chaikin refinement of {} polygon has an even number of points",
                if closed { "a closed" } else { "an open (endpoint-keeping)" }
            ),
        });
    }
    Ok(fine_len / 2)
}

/// One reverse Chaikin step: coarse points and details with `|coarse| + |details| = |fine|`.
///
/// # Errors
/// [`CurveError::TooFewPoints`] (closed: fewer than 6 fine points, i.e. 3 coarse; open:
/// fewer than 4), [`CurveError::IncompatibleLength`] for an odd number of points,
/// [`CurveError::NonFinite`], [`CurveError::Overflow`] for coordinates so large (near
/// `f64::MAX`) that a coarse point, a detail or a candidate point is not finite.
///
/// ```
/// use subdiv_curve::{Topology, reverse::reverse_chaikin};
/// let open = [[0.0], [1.0], [3.0], [4.0]]; // endpoint-keeping Chaikin of [0], [4]
/// let split = reverse_chaikin(&open, Topology::open())?;
/// assert_eq!(split.coarse, vec![[0.0], [4.0]]);
/// assert!(reverse_chaikin(&open[..3], Topology::open()).is_err());
/// # Ok::<(), subdiv_curve::CurveError>(())
/// ```
pub fn reverse_chaikin<P: CurvePoint>(fine: &[P], topology: Topology) -> Result<ChaikinSplit<P>, CurveError> {
    let n = coarse_len(fine.len(), topology)?;
    crate::point::check_finite(fine)?;
    let mut coarse = Vec::with_capacity(n);
    let mut details = Vec::with_capacity(n);
    match topology {
        Topology::Closed => {
            let f = |k: usize| fine[k % (2 * n)];
            for i in 0..n {
                let (f0, f1, f2, f3) = (f(2 * i + 2 * n - 2), f(2 * i + 2 * n - 1), f(2 * i), f(2 * i + 1));
                coarse.push(combine([(f0, -0.25), (f1, 0.75), (f2, 0.75), (f3, -0.25)]));
                details.push(combine([(f0, 0.25), (f1, -0.75), (f2, 0.75), (f3, -0.25)]));
            }
        }
        Topology::Open(_) => {
            let (q, r) = (|i: usize| fine[1 + 2 * i], |i: usize| fine[2 + 2 * i]);
            let first = fine[0];
            let last = fine[2 * n - 1];
            // a_0 - f_0 and b_{n-1} - f_last.
            coarse.push(first);
            details.push(q(0).scale(1.5).minus(r(0).scale(0.5)).minus(first));
            for i in 1..n - 1 {
                let (q0, r0, q1, r1) = (q(i - 1), r(i - 1), q(i), r(i));
                coarse.push(combine([(q0, -0.25), (r0, 0.75), (q1, 0.75), (r1, -0.25)]));
                details.push(combine([(q0, 0.25), (r0, -0.75), (q1, 0.75), (r1, -0.25)]));
            }
            coarse.push(last);
            details.push(r(n - 2).scale(1.5).minus(q(n - 2).scale(0.5)).minus(last));
        }
    }
    // The weights sum to at most 2 in absolute value: only coordinates beyond half of
    // `f64::MAX` overflow, which would otherwise pass on as infinities. Reconstruction
    // forms the candidates `c_i + d_i` and `c_i - d_i` (`a_i`, `b_i`): a split whose
    // candidates are not finite could not be rebuilt, so it is refused here.
    crate::point::check_result_finite("reverse Chaikin (coarse points)", &coarse)?;
    crate::point::check_result_finite("reverse Chaikin (details)", &details)?;
    let candidates_finite =
        |i: usize| coarse[i].plus(details[i]).is_finite() && coarse[i].minus(details[i]).is_finite();
    if let Some(index) = (0..n).find(|&i| !candidates_finite(i)) {
        return Err(CurveError::Overflow { what: "reverse Chaikin (candidate points)", index });
    }
    Ok(ChaikinSplit { coarse, details })
}

/// Inverse of [`reverse_chaikin`]: the fine polygon from coarse points and details (exact
/// up to rounding). With all details zero this is [`CurveScheme::chaikin`](crate::CurveScheme::chaikin) refinement.
///
/// # Errors
/// [`CurveError::IncompatibleLength`] if `details` and `coarse` differ in length,
/// [`CurveError::TooFewPoints`] (closed: 3 coarse points, open: 2), [`CurveError::NonFinite`],
/// [`CurveError::Overflow`] if a fine point is not finite (coordinates near `f64::MAX`).
///
/// ```
/// use subdiv_curve::{CurveScheme, Topology, reverse::reconstruct_chaikin};
/// let coarse = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
/// let fine = reconstruct_chaikin(&coarse, &[[0.0, 0.0]; 3], Topology::Closed)?;
/// assert_eq!(fine, CurveScheme::chaikin().refine(&coarse, Topology::Closed, 1)?);
/// assert!(reconstruct_chaikin(&coarse, &[[0.0, 0.0]; 2], Topology::Closed).is_err());
/// # Ok::<(), subdiv_curve::CurveError>(())
/// ```
pub fn reconstruct_chaikin<P: CurvePoint>(
    coarse: &[P],
    details: &[P],
    topology: Topology,
) -> Result<Vec<P>, CurveError> {
    if coarse.len() != details.len() {
        return Err(CurveError::IncompatibleLength {
            what: "Chaikin reconstruction",
            detail: format!("{} coarse points but {} details", coarse.len(), details.len()),
        });
    }
    let n = coarse.len();
    let needed = if topology.is_closed() { 3 } else { 2 };
    if n < needed {
        return Err(CurveError::TooFewPoints {
            what: "Chaikin reconstruction".into(),
            needed,
            got: n,
            closed: topology.is_closed(),
        });
    }
    crate::point::check_finite(coarse)?;
    crate::point::check_finite(details)?;
    let a = |i: usize| coarse[i].plus(details[i]);
    let b = |i: usize| coarse[i].minus(details[i]);
    let segment =
        |a_i: P, b_next: P| (a_i.scale(0.75).plus(b_next.scale(0.25)), a_i.scale(0.25).plus(b_next.scale(0.75)));
    let mut fine = Vec::with_capacity(2 * n);
    match topology {
        Topology::Closed => {
            for i in 0..n {
                let (first, second) = segment(a(i), b((i + 1) % n));
                fine.push(first);
                fine.push(second);
            }
        }
        Topology::Open(_) => {
            fine.push(coarse[0]);
            for i in 0..n - 1 {
                // The end points' details hold a_0 - c_0 and b_{n-1} - c_{n-1}.
                let b_next = if i + 1 == n - 1 { coarse[n - 1].plus(details[n - 1]) } else { b(i + 1) };
                let (first, second) = segment(a(i), b_next);
                fine.push(first);
                fine.push(second);
            }
            fine.push(coarse[n - 1]);
        }
    }
    crate::point::check_result_finite("Chaikin reconstruction", &fine)?;
    Ok(fine)
}

/// A multiresolution pyramid of reverse Chaikin steps: the base polygon and the details
/// of each level, coarsest first.
#[derive(Debug, Clone, PartialEq)]
pub struct ChaikinPyramid<P> {
    /// The coarsest polygon.
    pub base: Vec<P>,
    /// `details[k]` lifts level `k` to level `k + 1`.
    pub details: Vec<Vec<P>>,
    /// Closed or open.
    pub topology: Topology,
}

/// Reverses `levels` Chaikin steps (fewer if the polygon gets too short or odd).
///
/// # Errors
/// As [`reverse_chaikin`], for the first step only.
///
/// ```
/// use subdiv_curve::{CurveScheme, Topology, reverse::decompose_chaikin};
/// let base = [[0.0, 0.0], [3.0, 0.0], [3.0, 2.0], [0.0, 2.0]];
/// let fine = CurveScheme::chaikin().refine(&base, Topology::Closed, 3)?;
/// let pyramid = decompose_chaikin(&fine, Topology::Closed, 10)?;
/// assert_eq!(pyramid.details.len(), 3); // 32 -> 16 -> 8 -> 4 points; 4 is not even 2 * 3
/// assert!(pyramid.base.iter().zip(&base).all(|(a, b)| (a[0] - b[0]).abs() < 1e-13));
/// assert_eq!(pyramid.reconstruct(3)?.len(), 32);
/// # Ok::<(), subdiv_curve::CurveError>(())
/// ```
pub fn decompose_chaikin<P: CurvePoint>(
    fine: &[P],
    topology: Topology,
    levels: usize,
) -> Result<ChaikinPyramid<P>, CurveError> {
    let mut current = fine.to_vec();
    let mut details = Vec::new();
    for level in 0..levels {
        match reverse_chaikin(&current, topology) {
            Ok(split) => {
                details.push(split.details);
                current = split.coarse;
            }
            Err(e) if level == 0 => return Err(e),
            Err(_) => break,
        }
    }
    details.reverse();
    Ok(ChaikinPyramid { base: current, details, topology })
}

impl<P: CurvePoint> ChaikinPyramid<P> {
    /// The polygon of level `level` (0 = base), rebuilt from the details.
    ///
    /// # Errors
    /// [`CurveError::IncompatibleLength`] if `level` exceeds the number of levels.
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Topology, reverse::decompose_chaikin};
    /// let base = [[0.0, 0.0], [3.0, 0.0], [3.0, 2.0], [0.0, 2.0]];
    /// let mut fine = CurveScheme::chaikin().refine(&base, Topology::Closed, 2)?;
    /// fine[5][1] += 0.25; // no longer a Chaikin polygon: the details keep the bump
    /// let pyramid = decompose_chaikin(&fine, Topology::Closed, 2)?;
    /// let back = pyramid.reconstruct(2)?;
    /// assert!(back.iter().zip(&fine).all(|(a, b)| (a[0] - b[0]).abs() < 1e-14 && (a[1] - b[1]).abs() < 1e-14));
    /// assert_eq!(pyramid.reconstruct(0)?, pyramid.base);
    /// assert!(pyramid.reconstruct(3).is_err());
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn reconstruct(&self, level: usize) -> Result<Vec<P>, CurveError> {
        if level > self.details.len() {
            return Err(CurveError::IncompatibleLength {
                what: "Chaikin pyramid",
                detail: format!("level {level} requested, the pyramid has {}", self.details.len()),
            });
        }
        let mut current = self.base.clone();
        for details in &self.details[..level] {
            current = reconstruct_chaikin(&current, details, self.topology)?;
        }
        Ok(current)
    }
}
