//! Linear stationary binary curve schemes described by two rules (masks).
//!
//! A scheme is given by its *even* and *odd* rule. Each rule is a short list of weights
//! with an offset: at level `k`, for every index `i`,
//!
//! ```text
//! p^{k+1}_{2i}   = sum_j even.weights[j] * p^k_{i + even.offset + j}
//! p^{k+1}_{2i+1} = sum_j odd.weights[j]  * p^k_{i + odd.offset + j}
//! ```
//!
//! The mask of the scheme (spec §1.1) is `a_{-2(even.offset + j)} = even.weights[j]` and
//! `a_{1 - 2(odd.offset + j)} = odd.weights[j]`, so that `p^{k+1}_m = sum_i a_{m - 2i} p^k_i`;
//! its symbol is `a(z) = sum_m a_m z^m` ([`crate::analysis::Symbol`]).
//!
//! The [`Layout`] says how the new points sit on an *open* polygon: a **primal** scheme has
//! a vertex rule (even, new point at coarse vertex `i`) and an edge rule (odd, new point on
//! the edge `(i, i+1)`), so `n` points become `2n - 1`; a **dual** scheme puts both new
//! points on the edge `(i, i+1)` and keeps the two end points, so `n` points become `2n`
//! (the endpoint-keeping variant of Chaikin, spec §2.1). Closed polygons of `n` points
//! become `2n` points in both layouts. Indices that fall outside an open polygon read
//! *phantom points* ([`EndRule`], spec §16.4).
//!
//! Adding a scheme takes two rules:
//!
//! ```
//! use subdiv_curve::{CurveScheme, Rule, Topology};
//! // Midpoint insertion: the limit is the control polygon itself.
//! let midpoint = CurveScheme::primal("midpoint", Rule::new(0, &[1.0])?, Rule::new(0, &[0.5, 0.5])?)?;
//! let fine = midpoint.refine(&[[0.0, 0.0], [2.0, 0.0]], Topology::open(), 1)?;
//! assert_eq!(fine, vec![[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]);
//! # Ok::<(), subdiv_curve::CurveError>(())
//! ```

use crate::CurveError;

/// One subdivision rule: the new point is `sum_j weights[j] * p[i + offset + j]`.
///
/// Weights are affine (they sum to 1); exact zeros at either end are trimmed so that the
/// stored rule is as short as possible.
#[derive(Debug, Clone, PartialEq)]
pub struct Rule {
    offset: i32,
    weights: Vec<f64>,
}

/// Longest rule accepted (a safety bound, not a limitation of the algorithms).
pub const MAX_RULE_LEN: usize = 32;

impl Rule {
    /// A rule reading `weights.len()` consecutive points starting at `i + offset`.
    ///
    /// # Errors
    /// [`CurveError::InvalidRule`] if the weights are empty (or all zero), longer than
    /// [`MAX_RULE_LEN`], not finite, or do not sum to 1 within `1e-12`, or if the first
    /// non-zero weight is more than [`MAX_RULE_LEN`] points away from `i`.
    ///
    /// ```
    /// use subdiv_curve::Rule;
    /// let edge = Rule::new(-1, &[0.0, 0.5, 0.5, 0.0])?; // zeros are trimmed
    /// assert_eq!((edge.offset(), edge.weights()), (0, &[0.5, 0.5][..]));
    /// assert!(Rule::new(0, &[0.5, 0.4]).is_err());
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn new(offset: i32, weights: &[f64]) -> Result<Self, CurveError> {
        if let Some(bad) = weights.iter().find(|w| !w.is_finite()) {
            return Err(CurveError::InvalidRule(format!("weight {bad} is not finite")));
        }
        let first = weights.iter().position(|&w| w != 0.0);
        let last = weights.iter().rposition(|&w| w != 0.0);
        let (Some(first), Some(last)) = (first, last) else {
            return Err(CurveError::InvalidRule("a rule needs at least one non-zero weight".into()));
        };
        let trimmed = &weights[first..=last];
        if trimmed.len() > MAX_RULE_LEN {
            return Err(CurveError::InvalidRule(format!(
                "{} weights; at most {MAX_RULE_LEN} are supported",
                trimmed.len()
            )));
        }
        let sum: f64 = trimmed.iter().sum();
        if (sum - 1.0).abs() > 1e-12 {
            return Err(CurveError::InvalidRule(format!(
                "weights sum to {sum}, not 1: rules must be affine combinations"
            )));
        }
        // A rule reads near its point: far offsets would make the analysis's symbols and
        // the refinement's padding as long as the offset (gigabytes at 1e9).
        let reach = MAX_RULE_LEN as i32;
        let reads_from = i32::try_from(first).ok().and_then(|f| offset.checked_add(f));
        let Some(reads_from) = reads_from.filter(|o| (-reach..=reach).contains(o)) else {
            return Err(CurveError::InvalidRule(format!(
                "offset {offset} (first non-zero weight {first} further): a rule reads points at most \
                 {MAX_RULE_LEN} away from its own"
            )));
        };
        Ok(Rule { offset: reads_from, weights: trimmed.to_vec() })
    }

    /// Offset of the first point read, relative to `i`.
    pub fn offset(&self) -> i32 {
        self.offset
    }

    /// The weights, first to last.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Offsets of the first and last point read, relative to `i`.
    pub(crate) fn reach(&self) -> (i32, i32) {
        (self.offset, self.offset + self.weights.len() as i32 - 1)
    }

    /// Applies the rule at index `i` to a point lookup.
    ///
    /// The sum starts with the first term (not with zero) and adds the others in order,
    /// exactly as the specialised loops of the refinement engine do, so that every path
    /// computes every point bit for bit alike (signed zeros included).
    #[inline]
    pub(crate) fn apply<P: crate::CurvePoint>(&self, i: i64, point: impl Fn(i64) -> P) -> P {
        let first = i + self.offset as i64;
        let mut sum = point(first).scale(self.weights[0]);
        for (j, &w) in self.weights.iter().enumerate().skip(1) {
            sum = sum.plus(point(first + j as i64).scale(w));
        }
        sum
    }
}

/// Where the new points of a scheme sit on an open polygon (closed polygons are the same
/// in both layouts). See the crate docs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    /// Even rule = vertex point of vertex `i`, odd rule = edge point of edge `(i, i+1)`.
    Primal,
    /// Both rules make points on edge `(i, i+1)`; open polygons keep their end points.
    Dual,
}

/// How phantom points beyond the ends of an open polygon are made (spec §16.4), recomputed
/// from the current polygon at every level. For rules reaching `k > 1` points past an end,
/// the same rule extends: `P_{-k} = 2 P_0 - P_k` (reflect) or `P_{-k} = P_0` (repeat).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum EndRule {
    /// `P_{-1} = 2 P_0 - P_1` (point reflection). With the cubic B-spline (any primal
    /// scheme with a symmetric vertex rule) the end points stay fixed, bit for bit at every
    /// level, and the limit interpolates them.
    #[default]
    Reflect,
    /// `P_{-1} = P_0`. The cubic B-spline then does not interpolate the end points.
    Repeat,
}

/// A closed polygon, or an open one with its end rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Topology {
    /// Indices wrap around.
    Closed,
    /// Open polygon; phantom points beyond the ends follow the [`EndRule`].
    Open(EndRule),
}

impl Topology {
    /// An open polygon with the default end rule ([`EndRule::Reflect`]).
    ///
    /// ```
    /// use subdiv_curve::{EndRule, Topology};
    /// assert_eq!(Topology::open(), Topology::Open(EndRule::Reflect));
    /// assert!(!Topology::open().is_closed() && Topology::Closed.is_closed());
    /// ```
    pub fn open() -> Self {
        Topology::Open(EndRule::Reflect)
    }

    /// Whether the polygon is closed.
    pub fn is_closed(self) -> bool {
        matches!(self, Topology::Closed)
    }
}

/// The most points one refinement makes: `u32::MAX`, the index range of the project's
/// meshes. More levels than that allows give [`CurveError::TooLarge`] before anything is
/// allocated (at 16 or 24 bytes a point, that many points are already 64 or 96 GiB).
pub const MAX_REFINED_POINTS: usize = u32::MAX as usize;

/// A uniform binary curve subdivision scheme: a name, a [`Layout`] and two [`Rule`]s.
///
/// ```
/// use subdiv_curve::{CurveScheme, Topology};
/// let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
/// let fine = CurveScheme::chaikin().refine(&square, Topology::Closed, 2)?;
/// assert_eq!(fine.len(), 16);
/// assert_eq!(fine[0], [0.25 * 0.75 + 0.75 * 0.25, 0.0]); // a corner-cut point on the bottom edge
/// # Ok::<(), subdiv_curve::CurveError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct CurveScheme {
    name: String,
    layout: Layout,
    even: Rule,
    odd: Rule,
}

/// Tension range of the four-point scheme for which this crate *establishes* convergence
/// (C0) with the difference-scheme test of [`crate::analysis`] (at most 12 steps), bounds
/// rounded inwards. Outside it the scheme is rejected. Dyn, Levin and Gregory proved
/// convergence for `|w| < 1/4` and C1 for `0 < w < (sqrt(5) - 1)/8`; the test here
/// establishes C1 for `0 < w` up to about `0.17` (w = 1/16 is the classical choice).
pub const FOUR_POINT_TENSION_RANGE: (f64, f64) = (-0.4668, 0.4692);

impl CurveScheme {
    /// A primal scheme from its vertex (even) and edge (odd) rules.
    ///
    /// # Errors
    /// [`CurveError::InvalidRule`] if the name is empty.
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Rule};
    /// let cubic = CurveScheme::primal("cubic", Rule::new(-1, &[0.125, 0.75, 0.125])?, Rule::new(0, &[0.5, 0.5])?)?;
    /// assert_eq!(cubic, CurveScheme::cubic_bspline().renamed("cubic"));
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn primal(name: impl Into<String>, vertex_rule: Rule, edge_rule: Rule) -> Result<Self, CurveError> {
        Self::with_layout(name.into(), Layout::Primal, vertex_rule, edge_rule)
    }

    /// A dual scheme from the rules of the first and second new point on each edge.
    ///
    /// # Errors
    /// [`CurveError::InvalidRule`] if the name is empty.
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Rule};
    /// let chaikin = CurveScheme::dual("corner cutting", Rule::new(0, &[0.75, 0.25])?, Rule::new(0, &[0.25, 0.75])?)?;
    /// assert_eq!(chaikin.symbol().coefficients(), &[0.25, 0.75, 0.75, 0.25]);
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn dual(name: impl Into<String>, first_rule: Rule, second_rule: Rule) -> Result<Self, CurveError> {
        Self::with_layout(name.into(), Layout::Dual, first_rule, second_rule)
    }

    fn with_layout(name: String, layout: Layout, even: Rule, odd: Rule) -> Result<Self, CurveError> {
        if name.trim().is_empty() {
            return Err(CurveError::InvalidRule("a scheme needs a name".into()));
        }
        Ok(CurveScheme { name, layout, even, odd })
    }

    /// The same scheme under another name.
    pub fn renamed(mut self, name: impl Into<String>) -> Self {
        self.name = name.into();
        self
    }

    /// Chaikin corner cutting (spec §2.1): `f_{2i} = 3/4 c_i + 1/4 c_{i+1}`,
    /// `f_{2i+1} = 1/4 c_i + 3/4 c_{i+1}`; the limit is the uniform quadratic B-spline (C1).
    /// Open polygons keep their end points: `c_0, 3/4 c_0 + 1/4 c_1, ..., c_{n-1}`
    /// (`2n` points), the variant that [`crate::reverse`] inverts exactly.
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Topology};
    /// let fine = CurveScheme::chaikin().refine(&[[0.0], [4.0]], Topology::open(), 1)?;
    /// assert_eq!(fine, vec![[0.0], [1.0], [3.0], [4.0]]);
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn chaikin() -> Self {
        let first = Rule { offset: 0, weights: vec![0.75, 0.25] };
        let second = Rule { offset: 0, weights: vec![0.25, 0.75] };
        CurveScheme { name: "chaikin".into(), layout: Layout::Dual, even: first, odd: second }
    }

    /// The uniform cubic B-spline (spec §2.2): `p_{2i} = (p_{i-1} + 6 p_i + p_{i+1})/8`,
    /// `p_{2i+1} = (p_i + p_{i+1})/2`. C2.
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Topology};
    /// let fine = CurveScheme::cubic_bspline().refine(&[0.0, 8.0, 0.0], Topology::Closed, 1)?;
    /// assert_eq!(fine, vec![1.0, 4.0, 6.0, 4.0, 1.0, 0.0]);
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn cubic_bspline() -> Self {
        let vertex = Rule { offset: -1, weights: vec![0.125, 0.75, 0.125] };
        let edge = Rule { offset: 0, weights: vec![0.5, 0.5] };
        CurveScheme { name: "cubic-bspline".into(), layout: Layout::Primal, even: vertex, odd: edge }
    }

    /// The Dyn-Levin-Gregory four-point interpolatory scheme with tension `w` (spec §2.3):
    /// `p_{2i} = p_i`, `p_{2i+1} = (1/2 + w)(p_i + p_{i+1}) - w (p_{i-1} + p_{i+2})`.
    /// `w = 1/16` is the classical choice (C1, reproduces cubics).
    ///
    /// # Errors
    /// [`CurveError::ParameterOutOfRange`] if `w` is not inside
    /// [`FOUR_POINT_TENSION_RANGE`] (or not finite).
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Topology};
    /// let dlg = CurveScheme::four_point(1.0 / 16.0)?;
    /// let fine = dlg.refine(&[0.0, 0.0, 16.0, 0.0], Topology::Closed, 1)?;
    /// // Edge (0, 1) reads p_3, p_0, p_1, p_2 (cyclically): 9/16 (0 + 0) - 1/16 (0 + 16).
    /// assert_eq!(fine[1], -1.0);
    /// assert_eq!(fine[4], 16.0); // interpolatory: p_{2i} = p_i
    /// assert!(CurveScheme::four_point(0.5).is_err());
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn four_point(w: f64) -> Result<Self, CurveError> {
        check_four_point_tension("tension w", w)?;
        let vertex = Rule { offset: 0, weights: vec![1.0] };
        let edge = Rule::new(-1, &[-w, 0.5 + w, 0.5 + w, -w])?;
        Ok(CurveScheme { name: format!("four-point(w={w})"), layout: Layout::Primal, even: vertex, odd: edge })
    }

    /// The unified two-parameter scheme of seed formula (4) (spec §16.2):
    /// `p_{2i} = p_i + gamma Δ²p_i`, `p_{2i+1} = (1/2 - omega)(p_i + p_{i+1}) + omega (p_{i-1} + p_{i+2})`.
    /// `(omega, gamma) = (-1/16, 0)` is the four-point scheme, `(0, 1/8)` the cubic B-spline;
    /// its symbol has the factor `(1+z)^4` (necessary for C2) iff `omega = gamma/2 - 1/16`.
    ///
    /// # Errors
    /// [`CurveError::ParameterOutOfRange`] if `gamma` is outside `[0, 1/4)`, `|omega| > 1/2`,
    /// or the scheme is not established to converge (difference scheme not contractive
    /// within 12 steps, [`crate::analysis::contractivity`]).
    ///
    /// ```
    /// use subdiv_curve::CurveScheme;
    /// assert_eq!(CurveScheme::combined(0.0, 0.125)?.symbol(), CurveScheme::cubic_bspline().symbol());
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn combined(omega: f64, gamma: f64) -> Result<Self, CurveError> {
        check_range("gamma", gamma, 0.0, 0.25, "0 <= gamma < 1/4", true)?;
        check_range("omega", omega, -0.5, 0.5, "-1/2 <= omega <= 1/2 (and convergent with gamma)", false)?;
        let vertex = Rule::new(-1, &[gamma, 1.0 - 2.0 * gamma, gamma])?;
        let edge = Rule::new(-1, &[omega, 0.5 - omega, 0.5 - omega, omega])?;
        let scheme = CurveScheme {
            name: format!("combined(omega={omega}, gamma={gamma})"),
            layout: Layout::Primal,
            even: vertex,
            odd: edge,
        };
        let c0 = crate::analysis::contractivity(&scheme.symbol(), 0, 12);
        if !c0.established() {
            return Err(CurveError::ParameterOutOfRange {
                parameter: "omega",
                value: omega,
                range: format!(
                    "where the scheme converges with gamma = {gamma} (difference scheme not contractive within 12 \
                     steps, best norm {:.4}); the C2 line omega = gamma/2 - 1/16, 0 < gamma < 1/4, is safe",
                    c0.best_rate
                ),
            });
        }
        Ok(scheme)
    }

    /// The scheme's name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Primal or dual.
    pub fn layout(&self) -> Layout {
        self.layout
    }

    /// The even rule (vertex rule of a primal scheme).
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Rule};
    /// // The four-point scheme is interpolatory: its vertex rule copies p_i.
    /// assert_eq!(CurveScheme::four_point(1.0 / 16.0)?.even_rule(), &Rule::new(0, &[1.0])?);
    /// assert_eq!(CurveScheme::chaikin().even_rule().weights(), &[0.75, 0.25]);
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn even_rule(&self) -> &Rule {
        &self.even
    }

    /// The odd rule (edge rule of a primal scheme).
    ///
    /// ```
    /// use subdiv_curve::CurveScheme;
    /// // (-1, 9, 9, -1)/16 on p_{i-1} .. p_{i+2}.
    /// let dlg = CurveScheme::four_point(1.0 / 16.0)?;
    /// assert_eq!((dlg.odd_rule().offset(), dlg.odd_rule().weights()), (-1, &[-0.0625, 0.5625, 0.5625, -0.0625][..]));
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn odd_rule(&self) -> &Rule {
        &self.odd
    }

    /// Fewest points the scheme refines: 3 for closed polygons (spec §2.4), and for open
    /// ones 2, or more when the rules reach further past an end than the polygon can
    /// reflect (`P_{-k} = 2 P_0 - P_k` needs `k < n`).
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Topology};
    /// assert_eq!(CurveScheme::cubic_bspline().min_points(Topology::open()), 2);
    /// assert_eq!(CurveScheme::chaikin().min_points(Topology::Closed), 3);
    /// ```
    pub fn min_points(&self, topology: Topology) -> usize {
        match topology {
            Topology::Closed => 3,
            Topology::Open(_) => {
                let (left, right) = self.open_halo(2);
                2.max(left + 1).max(right + 1)
            }
        }
    }

    /// Number of points after `levels` steps from `n` points.
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Topology};
    /// assert_eq!(CurveScheme::cubic_bspline().refined_len(5, Topology::open(), 2), 17);
    /// assert_eq!(CurveScheme::chaikin().refined_len(5, Topology::open(), 2), 20); // 2n per level, ends kept
    /// assert_eq!(CurveScheme::chaikin().refined_len(5, Topology::Closed, 2), 20);
    /// ```
    ///
    /// A length of `usize::MAX / 2` or more reads as `usize::MAX` (refining that many
    /// points is refused anyway, see [`MAX_REFINED_POINTS`]).
    pub fn refined_len(&self, n: usize, topology: Topology, levels: u32) -> usize {
        let mut len = n;
        for _ in 0..levels {
            let next = self.next_len(len, topology);
            if next == len {
                // No point, or one of an open primal polygon: it stays so.
                break;
            }
            if next >= usize::MAX / 2 {
                return usize::MAX;
            }
            len = next;
        }
        len
    }

    /// [`refined_len`](Self::refined_len), or [`CurveError::TooLarge`] beyond
    /// [`MAX_REFINED_POINTS`]: checked before a refinement allocates anything, so that too
    /// many levels fail at once.
    pub(crate) fn checked_refined_len(&self, n: usize, topology: Topology, levels: u32) -> Result<usize, CurveError> {
        let len = self.refined_len(n, topology, levels);
        if len > MAX_REFINED_POINTS {
            return Err(CurveError::TooLarge { points: n, levels, max: MAX_REFINED_POINTS });
        }
        Ok(len)
    }

    /// The length after one step (saturating).
    pub(crate) fn next_len(&self, n: usize, topology: Topology) -> usize {
        match (topology, self.layout) {
            (Topology::Closed, _) => n.saturating_mul(2),
            (Topology::Open(_), Layout::Primal) => n.saturating_mul(2).saturating_sub(1),
            (Topology::Open(_), Layout::Dual) => n.saturating_mul(2),
        }
    }

    /// Whether, on an open polygon with [`EndRule::Reflect`], the new end points equal the
    /// old ones exactly: a primal scheme whose vertex rule is symmetric about its centre
    /// (`w_{-k} = w_k`) maps the end point `P_0` with phantoms `P_{-k} = 2 P_0 - P_k` to
    /// `w_0 P_0 + sum_k w_k (P_k + 2 P_0 - P_k) = P_0` (the weights sum to 1). Such end
    /// points are copied instead of summed, so that they stay bit for bit (the sum would
    /// only be within a rounding error or two of `P_0`).
    pub(crate) fn reflect_keeps_ends(&self) -> bool {
        let weights = self.even.weights();
        self.layout == Layout::Primal
            && 2 * self.even.offset() + weights.len() as i32 - 1 == 0
            && weights.iter().eq(weights.iter().rev())
    }

    /// Phantom points needed past each end of an open polygon of `n` points.
    pub(crate) fn open_halo(&self, n: usize) -> (usize, usize) {
        let (even_lo, even_hi) = self.even.reach();
        let (odd_lo, odd_hi) = self.odd.reach();
        let n = n as i32;
        let (even_last, odd_last) = match self.layout {
            Layout::Primal => (n - 1, n - 2),
            Layout::Dual => (n - 2, n - 2),
        };
        let left = (-even_lo.min(odd_lo)).max(0) as usize;
        let right = ((even_last + even_hi).max(odd_last + odd_hi) - (n - 1)).max(0) as usize;
        (left, right)
    }

    /// True if refining `points` `levels` times cannot overflow: a level multiplies the
    /// largest coordinate by at most the larger absolute weight sum of the two rules,
    /// times 3 for the phantom points of open ends (`2 P_0 - P_1`). Only coordinates
    /// within that factor of `f64::MAX` fail it, so the result is checked for them alone.
    pub(crate) fn cannot_overflow<P: crate::CurvePoint>(&self, points: &[P], levels: u32) -> bool {
        let absolute_sum = |rule: &Rule| rule.weights().iter().map(|w| w.abs()).sum::<f64>();
        let growth = 3.0 * absolute_sum(self.even_rule()).max(absolute_sum(self.odd_rule()));
        let bound = crate::point::largest_coordinate(points) * growth.powi(levels.min(i32::MAX as u32) as i32);
        bound < f64::MAX / 2.0
    }

    /// Checks that `points` can be refined: enough points, all finite.
    pub(crate) fn validate<P: crate::CurvePoint>(&self, points: &[P], topology: Topology) -> Result<(), CurveError> {
        let needed = self.min_points(topology);
        if points.len() < needed {
            return Err(CurveError::TooFewPoints {
                what: self.name.clone(),
                needed,
                got: points.len(),
                closed: topology.is_closed(),
            });
        }
        crate::point::check_finite(points)
    }
}

pub(crate) fn check_four_point_tension(parameter: &'static str, w: f64) -> Result<(), CurveError> {
    let (lo, hi) = FOUR_POINT_TENSION_RANGE;
    if w.is_finite() && lo <= w && w <= hi {
        Ok(())
    } else {
        Err(CurveError::ParameterOutOfRange {
            parameter,
            value: w,
            range: format!(
                "{lo} <= w <= {hi} (where the four-point scheme is established to converge; C1 needs 0 < w < \
                 (sqrt(5)-1)/8)"
            ),
        })
    }
}

pub(crate) fn check_range(
    parameter: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    range: &str,
    hi_open: bool,
) -> Result<(), CurveError> {
    let inside = value.is_finite() && value >= lo && if hi_open { value < hi } else { value <= hi };
    if inside { Ok(()) } else { Err(CurveError::ParameterOutOfRange { parameter, value, range: range.to_string() }) }
}
