//! The refinement engine shared by every scheme: ping-pong buffers with phantom or
//! wrap-around halos, and inner loops specialised on the rule lengths.
//!
//! One level reads the current polygon from a buffer that carries a few extra points on
//! each side (the *halo*: wrapped points of a closed polygon, phantom points of an open
//! one, see [`EndRule`]), so that the inner loop needs no index arithmetic
//! and no branches. Buffers are sized once for the finest intermediate level and reused
//! across levels and across calls ([`Refiner`]); the last level is written straight into
//! the caller's output vector.

use crate::scheme::{CurveScheme, EndRule, Layout, Rule, Topology};
use crate::{CurveError, CurvePoint};

/// Reusable refinement context: keeps its two work buffers between calls, so refining
/// many polygons (or the same one many times, as in a benchmark) allocates nothing after
/// the first call.
///
/// ```
/// use subdiv_curve::{CurveScheme, Refiner, Topology};
/// let mut refiner = Refiner::new();
/// let mut out = Vec::new();
/// let triangle = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
/// refiner.refine_into(&CurveScheme::cubic_bspline(), &triangle, Topology::Closed, 4, &mut out)?;
/// assert_eq!(out.len(), 3 << 4);
/// # Ok::<(), subdiv_curve::CurveError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Refiner<P> {
    pub(crate) front: Vec<P>,
    pub(crate) back: Vec<P>,
}

impl<P: CurvePoint> Default for Refiner<P> {
    fn default() -> Self {
        Self::new()
    }
}

/// Halo sizes (points before, points after) for a polygon of `n` points.
pub(crate) fn halo(scheme: &CurveScheme, n: usize, topology: Topology) -> (usize, usize) {
    match topology {
        Topology::Open(_) => scheme.open_halo(n),
        Topology::Closed => {
            let (even_lo, even_hi) = scheme.even_rule().reach();
            let (odd_lo, odd_hi) = scheme.odd_rule().reach();
            ((-even_lo.min(odd_lo)).max(0) as usize, even_hi.max(odd_hi).max(0) as usize)
        }
    }
}

/// Fills the halo of `buffer` = `[left halo | n points | right halo]`.
pub(crate) fn fill_halo<P: CurvePoint>(buffer: &mut [P], left: usize, n: usize, right: usize, topology: Topology) {
    debug_assert!(buffer.len() >= left + n + right && n > 0);
    for k in 1..=left {
        buffer[left - k] = match topology {
            Topology::Closed => buffer[left + (n - k % n) % n],
            Topology::Open(EndRule::Reflect) => buffer[left].scale(2.0).minus(buffer[left + k.min(n - 1)]),
            Topology::Open(EndRule::Repeat) => buffer[left],
        };
    }
    let last = left + n - 1;
    for k in 1..=right {
        buffer[last + k] = match topology {
            Topology::Closed => buffer[left + (n - 1 + k) % n],
            Topology::Open(EndRule::Reflect) => buffer[last].scale(2.0).minus(buffer[last - k.min(n - 1)]),
            Topology::Open(EndRule::Repeat) => buffer[last],
        };
    }
}

/// One level: `source` holds the `n` current points at `left..left + n` with a filled
/// halo; `target` receives exactly `scheme.next_len(n)` points.
pub(crate) fn step<P: CurvePoint>(
    scheme: &CurveScheme,
    source: &[P],
    left: usize,
    n: usize,
    topology: Topology,
    target: &mut [P],
) {
    debug_assert_eq!(target.len(), scheme.next_len(n, topology));
    let (even, odd) = (scheme.even_rule(), scheme.odd_rule());
    // Index in `source` of the first point read by a rule applied at coarse index `i`.
    let base = |rule: &Rule, i: usize| (left as i64 + i as i64 + rule.offset() as i64) as usize;
    match (topology, scheme.layout()) {
        (Topology::Closed, _) => pairs(even, odd, source, base(even, 0), base(odd, 0), target),
        (Topology::Open(_), Layout::Primal) => {
            let (pairs_part, last) = target.split_at_mut(2 * (n - 1));
            pairs(even, odd, source, base(even, 0), base(odd, 0), pairs_part);
            last[0] = even.apply((left + n - 1) as i64, |j| source[j as usize]);
        }
        (Topology::Open(_), Layout::Dual) => {
            let end = target.len() - 1;
            target[0] = source[left];
            target[end] = source[left + n - 1];
            pairs(even, odd, source, base(even, 0), base(odd, 0), &mut target[1..end]);
        }
    }
}

/// `target[2i] = even rule at source[even_base + i ..]`, `target[2i+1] = odd rule at
/// source[odd_base + i ..]`, dispatched to a loop specialised on the two rule lengths.
fn pairs<P: CurvePoint>(even: &Rule, odd: &Rule, source: &[P], even_base: usize, odd_base: usize, target: &mut [P]) {
    macro_rules! dispatch {
        ($(($e:literal, $o:literal)),*) => {
            match (even.weights().len(), odd.weights().len()) {
                $(($e, $o) => pairs_fixed::<P, $e, $o>(even.weights(), odd.weights(), source, even_base, odd_base, target),)*
                _ => pairs_any(even.weights(), odd.weights(), source, even_base, odd_base, target),
            }
        };
    }
    dispatch!(
        (1, 1),
        (1, 2),
        (1, 3),
        (1, 4),
        (1, 5),
        (1, 6),
        (2, 1),
        (2, 2),
        (2, 3),
        (2, 4),
        (2, 5),
        (2, 6),
        (3, 1),
        (3, 2),
        (3, 3),
        (3, 4),
        (3, 5),
        (3, 6),
        (4, 1),
        (4, 2),
        (4, 3),
        (4, 4),
        (4, 5),
        (4, 6),
        (5, 1),
        (5, 2),
        (5, 3),
        (5, 4),
        (5, 5),
        (5, 6)
    )
}

#[inline(always)]
fn weighted<P: CurvePoint, const N: usize>(weights: &[f64; N], points: &[P]) -> P {
    let points: &[P; N] = points.try_into().expect("internal: window length");
    let mut sum = points[0].scale(weights[0]);
    for k in 1..N {
        sum = sum.plus(points[k].scale(weights[k]));
    }
    sum
}

fn pairs_fixed<P: CurvePoint, const E: usize, const O: usize>(
    even: &[f64],
    odd: &[f64],
    source: &[P],
    even_base: usize,
    odd_base: usize,
    target: &mut [P],
) {
    let even: &[f64; E] = even.try_into().expect("internal: even rule length");
    let odd: &[f64; O] = odd.try_into().expect("internal: odd rule length");
    let count = target.len() / 2;
    if count == 0 {
        return;
    }
    let even_source = &source[even_base..even_base + count + E - 1];
    let odd_source = &source[odd_base..odd_base + count + O - 1];
    for ((pair, even_window), odd_window) in
        target.chunks_exact_mut(2).zip(even_source.windows(E)).zip(odd_source.windows(O))
    {
        pair[0] = weighted(even, even_window);
        pair[1] = weighted(odd, odd_window);
    }
}

fn pairs_any<P: CurvePoint>(
    even: &[f64],
    odd: &[f64],
    source: &[P],
    even_base: usize,
    odd_base: usize,
    target: &mut [P],
) {
    let sum = |weights: &[f64], window: &[P]| {
        weights.iter().zip(window).fold(P::zero(), |acc, (&w, &p)| acc.plus(p.scale(w)))
    };
    for (i, pair) in target.chunks_exact_mut(2).enumerate() {
        pair[0] = sum(even, &source[even_base + i..]);
        pair[1] = sum(odd, &source[odd_base + i..]);
    }
}

impl<P: CurvePoint> Refiner<P> {
    /// An empty context (buffers grow on first use).
    pub fn new() -> Self {
        Refiner { front: Vec::new(), back: Vec::new() }
    }

    /// Refines `points` `levels` times with `scheme`, writing the result into `out`
    /// (replaced entirely; its allocation is reused).
    ///
    /// # Errors
    /// [`CurveError::TooFewPoints`] (see [`CurveScheme::min_points`]),
    /// [`CurveError::NonFinite`] for a NaN or infinite coordinate.
    ///
    /// # Performance
    /// Linear in the output size; no allocation once the buffers have reached their size.
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Refiner, Topology};
    /// let mut out = Vec::new();
    /// let result = Refiner::new().refine_into(&CurveScheme::chaikin(), &[[0.0, f64::NAN]; 3], Topology::Closed, 1, &mut out);
    /// assert!(result.is_err());
    /// ```
    pub fn refine_into(
        &mut self,
        scheme: &CurveScheme,
        points: &[P],
        topology: Topology,
        levels: u32,
        out: &mut Vec<P>,
    ) -> Result<(), CurveError> {
        scheme.validate(points, topology)?;
        if levels == 0 {
            out.clear();
            out.extend_from_slice(points);
            return Ok(());
        }
        let (left, right) = halo(scheme, points.len(), topology);
        let penultimate = scheme.refined_len(points.len(), topology, levels - 1);
        let capacity = penultimate + left + right;
        for buffer in [&mut self.front, &mut self.back] {
            if buffer.len() < capacity {
                buffer.resize(capacity, P::zero());
            }
        }
        let mut n = points.len();
        self.front[left..left + n].copy_from_slice(points);
        for level in 0..levels {
            fill_halo(&mut self.front, left, n, right, topology);
            let next = scheme.next_len(n, topology);
            if level + 1 == levels {
                // Every entry is overwritten by the step: keep the old ones instead of
                // zeroing (a reused output of the same length costs no extra pass).
                out.truncate(next);
                out.resize(next, P::zero());
                step(scheme, &self.front, left, n, topology, out);
            } else {
                step(scheme, &self.front, left, n, topology, &mut self.back[left..left + next]);
                std::mem::swap(&mut self.front, &mut self.back);
            }
            n = next;
        }
        Ok(())
    }
}

impl CurveScheme {
    /// Refines `points` `levels` times (a fresh [`Refiner`]; use one directly to reuse
    /// buffers).
    ///
    /// # Errors
    /// [`CurveError::TooFewPoints`] (see [`CurveScheme::min_points`]),
    /// [`CurveError::NonFinite`] for a NaN or infinite coordinate.
    ///
    /// ```
    /// use glam::DVec3;
    /// use subdiv_curve::{CurveScheme, EndRule, Topology};
    /// let open = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 1.0)];
    /// let fine = CurveScheme::cubic_bspline().refine(&open, Topology::Open(EndRule::Reflect), 3)?;
    /// assert_eq!((fine.len(), fine[0], fine[16]), (17, open[0], open[2])); // reflect keeps the ends
    /// let err = CurveScheme::cubic_bspline().refine(&open[..1], Topology::open(), 3).unwrap_err();
    /// assert!(err.to_string().contains("at least 2 points"));
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn refine<P: CurvePoint>(&self, points: &[P], topology: Topology, levels: u32) -> Result<Vec<P>, CurveError> {
        let mut out = Vec::new();
        Refiner::new().refine_into(self, points, topology, levels, &mut out)?;
        Ok(out)
    }
}
