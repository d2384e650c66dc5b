//! The two-parameter interpolatory-approximating framework (seed 004, Yao, Zhang & Tan;
//! spec §16), with per-point flags: points flagged *interpolate* (I) stay fixed at every
//! level, the others (A) are approximated.
//!
//! # Rules
//!
//! Parameters `(omega1, omega2, gamma)`, published choice `(-1/16, 0, 1/8)`. Write
//! `Δ²p_i = p_{i-1} - 2 p_i + p_{i+1}`. The *approximating scheme* `A` is the unified
//! scheme of seed formula (4) with `(omega2, gamma)`:
//! `p_{2i} = p_i + gamma Δ²p_i`, `p_{2i+1} = (1/2 - omega2)(p_i + p_{i+1}) + omega2 (p_{i-1} + p_{i+2})`
//! (rule (6); the cubic B-spline for the published values). The *interpolating rule* (5)
//! is the four-point rule with `omega1`: `p_{2i+1} = (1/2 - omega1)(p_i + p_{i+1}) + omega1 (p_{i-1} + p_{i+2})`.
//! I-vertices are copied: `p_{2i} = p_i`.
//!
//! The seed's mixed rules (7) and (8) (edges between an I and an A point) are lost; we use
//! the *virtual-point* rules of spec §16.3, derived as follows. Let `ℓ` be the limit
//! stencil of `A` ([`crate::analysis::limit_stencil`]: the left eigenvector of its local
//! matrix for eigenvalue 1, `(1, 4, 1)/6` for the cubic B-spline). For an I-point `i`
//! the *virtual point* `q_i` is the control point that, with the actual neighbours, has
//! `p_i` as its `A`-limit:
//!
//! ```text
//! ℓ_0 q_i + sum_{k != 0} ℓ_k p_{i+k} = p_i      (cubic B-spline: q_i = p_i - Δ²p_i / 4)
//! ```
//!
//! Let `g_j = q_j` at I-points and `g_j = p_j` at A-points (the *virtual polygon* `G`).
//! Every new point that is not an I-vertex (and, in the seed-compatible mode, not on an
//! edge joining two I-points) is rule `A` applied to `G`. For the published parameters this
//! gives exactly the rules of the spec: (7) `p_{2i+1} = (q_i + p_{i+1})/2`, (8)
//! `p_{2i+1} = (p_i + q_{i+1})/2`, (6') `p_{2i} = (g_{i-1} + 6 p_i + g_{i+1})/8`.
//!
//! **Why this is C2** (the virtual-point theorem, spec §16.3, checked numerically by
//! [`Framework::analyze`] and the tests): when no two I-points are closer than the radius
//! of `ℓ`, one step equals `A` applied to `G` with the I-entries overwritten by `p_i`;
//! and the virtual polygon of the new polygon is exactly `A(G)`, because the neighbours of
//! a new I-point are A-points with the values of `A(G)`, and `ℓ` is a left eigenvector:
//! `ℓ(A G around 2i) = ℓ(G around i) = p_i`. Hence the limit is the `A`-limit of `G`
//! (a uniform cubic B-spline curve for the published parameters, C2 everywhere) and it
//! passes through every `p_i` (the limit of `G` at `i` is `ℓ(G around i) = p_i`). After the
//! first step all new edge points are A-points, so I-points are isolated from level 1 on.
//!
//! # Modes ([`VirtualPoints`])
//!
//! - **Seed-compatible** (default): at every level `q_i` is computed from the actual
//!   neighbours, and edges between two I-points use rule (5) (only possible at the first
//!   step). `C2` from level 1 on.
//! - **Exact-global**: `G` is solved once from `ℓ(G around j) = p_j` for all I-points `j`
//!   jointly (neighbouring I-points couple; a closed polygon with every point flagged gives
//!   the interpolating cubic spline), then `A` runs on `G` and the I-entries are
//!   overwritten at every level. The limit is exactly the `A`-limit of `G` from level 0.
//!
//! # Open polygons
//!
//! Phantom points follow [`EndRule`], recomputed at every level (spec
//! §16.4). Since every non-I rule is `A` applied to `G`, the phantoms these rules read are
//! those of the virtual polygon (`2 g_0 - g_1` or `g_0`), and a virtual point next to an
//! end folds the phantom into its equation (an I end point under "reflect" gets `q = p`,
//! consistent with the cubic B-spline keeping reflected end points). Both modes therefore
//! agree whenever the I-points are isolated, ends included. Every I-point, end points
//! included, keeps its position at every level, so the limit passes through it:
//! `result[i << levels] == points[i]` bit for bit.
//!
//! ```
//! use subdiv_curve::{Framework, Topology};
//! let hexagon: Vec<[f64; 2]> = (0..6)
//!     .map(|k| { let t = k as f64 * std::f64::consts::PI / 3.0; [t.cos(), t.sin()] })
//!     .collect();
//! let flags = [true, false, false, true, false, false];
//! let fine = Framework::published().refine(&hexagon, &flags, Topology::Closed, 5)?;
//! assert_eq!(fine.len(), 6 << 5);
//! assert_eq!((fine[0], fine[3 << 5]), (hexagon[0], hexagon[3]));
//! # Ok::<(), subdiv_curve::CurveError>(())
//! ```

use nalgebra::DMatrix;

use crate::analysis::{self, Analysis, EigenChecks, LocalMatrix};
use crate::refine::{BlockLevel, Refiner, block_len, fill_halo, halo};
use crate::scheme::{CurveScheme, EndRule, Rule, Topology, check_four_point_tension};
use crate::{CurveError, CurvePoint};

/// How the virtual points of I-points are computed (see the [module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum VirtualPoints {
    /// From the actual neighbours at every level; rule (5) on edges joining two I-points.
    #[default]
    SeedCompatible,
    /// Solved once for all I-points jointly; the limit is the `A`-limit of the solution.
    ExactGlobal,
}

/// The framework with its parameters and mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Framework {
    omega1: f64,
    omega2: f64,
    gamma: f64,
    approximating: CurveScheme,
    interpolating_edge: Rule,
    limit_offset: i32,
    limit_weights: Vec<f64>,
    mode: VirtualPoints,
}

/// Iteration cap of the exact-global solve (convergence factor at most the row
/// dominance ratio, 1/2 for the published parameters).
const MAX_SWEEPS: usize = 2000;

impl Framework {
    /// The framework with parameters `(omega1, omega2, gamma)` in the seed-compatible mode.
    ///
    /// # Errors
    /// [`CurveError::ParameterOutOfRange`] naming the parameter and its range:
    /// `omega1` must make rule (5) a convergent four-point scheme (`-omega1` in
    /// [`crate::FOUR_POINT_TENSION_RANGE`]); `(omega2, gamma)` must make `A` convergent
    /// (see [`CurveScheme::combined`]) and its limit stencil strictly diagonally dominant
    /// (`ℓ_0 > sum |ℓ_k|`, needed by the virtual points; `gamma < 1/4` when `omega2 = 0`).
    ///
    /// ```
    /// use subdiv_curve::Framework;
    /// assert!(Framework::new(-1.0 / 16.0, 0.0, 0.125).is_ok());
    /// let err = Framework::new(-1.0 / 16.0, 0.0, 0.3).unwrap_err();
    /// assert!(err.to_string().contains("gamma = 0.3 is outside the allowed range 0 <= gamma < 1/4"));
    /// ```
    pub fn new(omega1: f64, omega2: f64, gamma: f64) -> Result<Self, CurveError> {
        check_four_point_tension("omega1 (as tension w = -omega1)", -omega1)?;
        let approximating = CurveScheme::combined(omega2, gamma).map_err(|e| match e {
            CurveError::ParameterOutOfRange { parameter: "omega", value, range } => {
                CurveError::ParameterOutOfRange { parameter: "omega2", value, range }
            }
            other => other,
        })?;
        let interpolating_edge = Rule::new(-1, &[omega1, 0.5 - omega1, 0.5 - omega1, omega1])?;
        let (limit_offset, limit_weights) =
            analysis::limit_stencil(&approximating).ok_or_else(|| CurveError::ParameterOutOfRange {
                parameter: "gamma",
                value: gamma,
                range: "values where the approximating scheme has a simple eigenvalue 1".into(),
            })?;
        let centre = (-limit_offset) as usize;
        let off_centre: f64 =
            limit_weights.iter().enumerate().filter(|(k, _)| *k != centre).map(|(_, w)| w.abs()).sum();
        if centre >= limit_weights.len() || limit_weights[centre] <= off_centre {
            return Err(CurveError::ParameterOutOfRange {
                parameter: "gamma",
                value: gamma,
                range: format!(
                    "values where the limit stencil {limit_weights:?} of the approximating rule is diagonally \
                     dominant (0 <= gamma < 1/4 for omega2 = 0)"
                ),
            });
        }
        Ok(Framework {
            omega1,
            omega2,
            gamma,
            approximating: approximating.renamed(format!("approximating rule (omega2={omega2}, gamma={gamma})")),
            interpolating_edge,
            limit_offset,
            limit_weights,
            mode: VirtualPoints::SeedCompatible,
        })
    }

    /// The published parameters `(-1/16, 0, 1/8)`: four-point on I-I edges, cubic B-spline
    /// elsewhere.
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Framework};
    /// assert_eq!(Framework::published().approximating_scheme().symbol(), CurveScheme::cubic_bspline().symbol());
    /// ```
    pub fn published() -> Self {
        Self::new(-1.0 / 16.0, 0.0, 0.125).expect("internal: the published parameters are valid")
    }

    /// The same framework in another mode.
    ///
    /// ```
    /// use subdiv_curve::{Framework, VirtualPoints};
    /// let exact = Framework::published().with_mode(VirtualPoints::ExactGlobal);
    /// assert_eq!(exact.mode(), VirtualPoints::ExactGlobal);
    /// ```
    pub fn with_mode(mut self, mode: VirtualPoints) -> Self {
        self.mode = mode;
        self
    }

    /// The virtual-point mode.
    pub fn mode(&self) -> VirtualPoints {
        self.mode
    }

    /// `(omega1, omega2, gamma)`.
    pub fn parameters(&self) -> (f64, f64, f64) {
        (self.omega1, self.omega2, self.gamma)
    }

    /// The approximating scheme `A` (rule (6), seed formula (4) with `(omega2, gamma)`).
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Framework};
    /// // On the C2 line omega2 = gamma/2 - 1/16 the approximating rule has the factor (1+z)^4.
    /// let (omega2, gamma) = (0.05 - 1.0 / 16.0, 0.1);
    /// let a = Framework::new(-1.0 / 16.0, omega2, gamma)?.approximating_scheme().symbol();
    /// assert_eq!(a, CurveScheme::combined(omega2, gamma)?.symbol());
    /// assert_eq!(a.one_plus_z_factors(), 4);
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn approximating_scheme(&self) -> &CurveScheme {
        &self.approximating
    }

    /// The uniform scheme of rule (5): the four-point scheme with tension `-omega1`.
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Framework};
    /// let dlg = Framework::published().interpolating_scheme();
    /// assert_eq!(dlg.symbol(), CurveScheme::four_point(1.0 / 16.0)?.symbol());
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn interpolating_scheme(&self) -> CurveScheme {
        CurveScheme::primal(
            format!("interpolating rule (omega1={})", self.omega1),
            Rule::new(0, &[1.0]).expect("internal: identity rule"),
            self.interpolating_edge.clone(),
        )
        .expect("internal: named scheme")
    }

    /// The limit stencil `ℓ` of `A`: `(offset of the first weight, weights)`.
    ///
    /// ```
    /// use subdiv_curve::Framework;
    /// // The cubic B-spline's limit stencil (1, 4, 1)/6, starting one point to the left.
    /// let framework = Framework::published();
    /// let (offset, weights) = framework.limit_stencil();
    /// assert_eq!((offset, weights.len()), (-1, 3));
    /// assert!(weights.iter().zip([1.0, 4.0, 1.0]).all(|(w, e)| (w - e / 6.0).abs() < 1e-14));
    /// ```
    pub fn limit_stencil(&self) -> (i32, &[f64]) {
        (self.limit_offset, &self.limit_weights)
    }

    fn limit_radius(&self) -> usize {
        let last = self.limit_offset + self.limit_weights.len() as i32 - 1;
        (-self.limit_offset).max(last).max(0) as usize
    }

    fn check_input<P: CurvePoint>(&self, points: &[P], flags: &[bool], topology: Topology) -> Result<(), CurveError> {
        if flags.len() != points.len() {
            return Err(CurveError::FlagCount { flags: flags.len(), points: points.len() });
        }
        let needed = self.approximating.min_points(topology).max(match topology {
            Topology::Closed => 3,
            Topology::Open(_) => self.limit_radius() + 1,
        });
        if points.len() < needed {
            return Err(CurveError::TooFewPoints {
                what: "the interpolatory-approximating framework".into(),
                needed,
                got: points.len(),
                closed: topology.is_closed(),
            });
        }
        crate::point::check_finite(points)
    }

    /// Refines `points` `levels` times; `flags[i]` says whether point `i` is interpolated.
    /// Point `i` of the input is entry `i << levels` of the result.
    ///
    /// # Errors
    /// [`CurveError::FlagCount`], [`CurveError::TooFewPoints`], [`CurveError::NonFinite`];
    /// [`CurveError::VirtualPoints`] if the exact-global system does not converge;
    /// [`CurveError::Overflow`] if finite coordinates near `f64::MAX` refine to points that
    /// are not finite; [`CurveError::TooLarge`] if the result would have more than
    /// [`MAX_REFINED_POINTS`](crate::MAX_REFINED_POINTS) points.
    ///
    /// ```
    /// use subdiv_curve::{CurveScheme, Framework, Topology};
    /// let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    /// // No I-point: exactly the cubic B-spline.
    /// let framework = Framework::published().refine(&square, &[false; 4], Topology::Closed, 3)?;
    /// assert_eq!(framework, CurveScheme::cubic_bspline().refine(&square, Topology::Closed, 3)?);
    /// // Open polygon, first point flagged, "repeat" phantoms: the end point is still interpolated.
    /// use subdiv_curve::EndRule;
    /// let fine = Framework::published().refine(&square, &[true, false, false, false], Topology::Open(EndRule::Repeat), 3)?;
    /// assert_eq!(fine[0], square[0]);
    /// assert_ne!(fine[fine.len() - 1], square[3]);
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn refine<P: CurvePoint>(
        &self,
        points: &[P],
        flags: &[bool],
        topology: Topology,
        levels: u32,
    ) -> Result<Vec<P>, CurveError> {
        let mut out = Vec::new();
        self.refine_into(&mut Refiner::new(), points, flags, topology, levels, &mut out)?;
        Ok(out)
    }

    /// [`Framework::refine`] into `out` (replaced entirely), with the work buffers of
    /// `refiner`: refining again allocates nothing once the buffers have their size.
    ///
    /// # Errors
    /// As [`Framework::refine`].
    ///
    /// ```
    /// use subdiv_curve::{Framework, Refiner, Topology};
    /// let (mut refiner, mut out) = (Refiner::new(), Vec::new());
    /// let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    /// Framework::published().refine_into(&mut refiner, &square, &[true, false, false, false], Topology::Closed, 4, &mut out)?;
    /// assert_eq!((out.len(), out[0]), (64, square[0]));
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn refine_into<P: CurvePoint>(
        &self,
        refiner: &mut Refiner<P>,
        points: &[P],
        flags: &[bool],
        topology: Topology,
        levels: u32,
        out: &mut Vec<P>,
    ) -> Result<(), CurveError> {
        self.check_input(points, flags, topology)?;
        self.approximating.checked_refined_len(points.len(), topology, levels)?;
        let interpolated: Vec<usize> = (0..points.len()).filter(|&i| flags[i]).collect();
        match self.mode {
            VirtualPoints::SeedCompatible => {
                self.refine_seed(refiner, points, &interpolated, topology, levels, out, block_len::<P>());
            }
            VirtualPoints::ExactGlobal => {
                let virtual_polygon = self.solve_virtual(points, &interpolated, topology)?;
                // (Its refinement would blame a point of the input for an infinite one.)
                crate::point::check_result_finite("virtual polygon", &virtual_polygon)?;
                refiner.refine_into(&self.approximating, &virtual_polygon, topology, levels, out)?;
                for &i in &interpolated {
                    out[i << levels] = points[i];
                }
            }
        }
        // Virtual points divide by the diagonal of their stencil: no cheap bound on how
        // they grow, so the result is checked (one read of what was just written).
        crate::point::check_result_finite("framework refinement", out)?;
        Ok(())
    }

    /// The virtual polygon `G` of `points` for the current mode: `q_i` at I-points
    /// (from the actual neighbours, or solved jointly in the exact-global mode), `p_j`
    /// elsewhere.
    ///
    /// # Errors
    /// As [`Framework::refine`].
    ///
    /// ```
    /// use subdiv_curve::{Framework, Topology};
    /// let g = Framework::published().virtual_polygon(&[0.0, 6.0, 0.0, 0.0], &[false, true, false, false], Topology::Closed)?;
    /// assert!((g[1] - 9.0).abs() < 1e-14); // q = p - Δ²p/4 = 6 - (0 - 12 + 0)/4
    /// # Ok::<(), subdiv_curve::CurveError>(())
    /// ```
    pub fn virtual_polygon<P: CurvePoint>(
        &self,
        points: &[P],
        flags: &[bool],
        topology: Topology,
    ) -> Result<Vec<P>, CurveError> {
        self.check_input(points, flags, topology)?;
        let interpolated: Vec<usize> = (0..points.len()).filter(|&i| flags[i]).collect();
        let polygon = match self.mode {
            VirtualPoints::ExactGlobal => self.solve_virtual(points, &interpolated, topology)?,
            VirtualPoints::SeedCompatible => {
                let (left, right) = self.halo(points.len(), topology);
                let mut extended = vec![P::zero(); left + points.len() + right];
                extended[left..left + points.len()].copy_from_slice(points);
                fill_halo(&mut extended, left, points.len(), right, topology);
                let level = Level::new(&extended, -(left as i64), points.len(), topology, &interpolated);
                let mut polygon = points.to_vec();
                for &i in &interpolated {
                    polygon[i] = self.virtual_point(&level, i as i64);
                }
                polygon
            }
        };
        // Finite input near `f64::MAX` can push a virtual point past it.
        crate::point::check_result_finite("virtual polygon", &polygon)?;
        Ok(polygon)
    }

    fn halo(&self, n: usize, topology: Topology) -> (usize, usize) {
        let (a_left, a_right) = halo(&self.approximating, n, topology);
        let radius = self.limit_radius();
        // Fix-ups evaluate rules of A on virtual points up to `radius` further out, and
        // rule (5) reads one point past each end of its edge.
        let (left, right) = (a_left + radius, a_right + radius);
        (left.max(1), right.max(2))
    }

    /// `q_i` from the actual neighbours: the row `ℓ(G around i) = p_i` with every other
    /// entry taken from the current polygon, phantom points of `G` folded in (so an I end
    /// point under "reflect" gets `q = p`). `i` may be an unwrapped index of a closed
    /// polygon (any copy inside the level's window).
    fn virtual_point<P: CurvePoint>(&self, level: &Level<'_, P>, i: i64) -> P {
        let n = level.n as i64;
        let mut diagonal = 0.0;
        let mut sum = level.actual(i);
        for (k, &w) in self.limit_weights.iter().enumerate() {
            let index = i + self.limit_offset as i64 + k as i64;
            for (real, factor) in phantom_combination(index, level.n, level.topology) {
                // A closed polygon reads the copy next to `i`, which has the same value.
                let at = if level.topology.is_closed() { index } else { real as i64 };
                if real as i64 == i.rem_euclid(n) {
                    diagonal += w * factor;
                } else {
                    sum = sum.minus(level.actual(at).scale(w * factor));
                }
            }
        }
        sum.scale(1.0 / diagonal)
    }

    /// The seed-compatible refinement, fused like [`Refiner::refine_into`]: each output
    /// block is refined depth-first from its support, and after the rules of each level the
    /// points reading a virtual point are redone from the block's window (which is widened
    /// by the virtual points' reach). Equal bit for bit to the level-by-level path.
    /// `block` is the number of output points per block.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn refine_seed<P: CurvePoint>(
        &self,
        refiner: &mut Refiner<P>,
        points: &[P],
        interpolated: &[usize],
        topology: Topology,
        levels: u32,
        out: &mut Vec<P>,
        block: usize,
    ) {
        let scheme = &self.approximating;
        if !refiner.size_output(scheme, points, topology, levels, out) {
            return;
        }
        // The I-points of each level, and the virtual points of those near the block.
        let per_level: Vec<Vec<usize>> = (0..levels).map(|k| interpolated.iter().map(|&i| i << k).collect()).collect();
        let radius = self.limit_radius() as i64;
        // Rule (5) reads one point further than an odd rule of `A` may.
        let margin = radius + 1;
        // Each worker's virtual points of the I-points near its current block.
        let fix_up_level = |(near, virtual_points): &mut (Vec<i64>, Vec<P>), block: BlockLevel<'_, P>| {
            let interpolated = &per_level[block.level];
            if interpolated.is_empty() {
                return;
            }
            let level = Level::new(block.source, block.source_first, block.coarse_len, topology, interpolated);
            let window_end = block.source_first + block.source.len() as i64;
            // I-points whose virtual point the window holds (all those the rules of the
            // block's target read, thanks to the margin).
            near.clear();
            unwrapped_positions(
                interpolated,
                block.coarse_len,
                topology,
                block.source_first + radius,
                window_end - radius,
                near,
            );
            virtual_points.clear();
            virtual_points.extend(near.iter().map(|&i| self.virtual_point(&level, i)));
            // Look-ups by (unwrapped) index among the few I-points near the block only.
            let level = Level { near: Some(near), virtual_points, ..level };
            self.fix_up(&level, near, block.target, block.target_first, block.fine_len, true);
        };
        refiner.refine_blocks(scheme, topology, points, out, block, margin, || (Vec::new(), Vec::new()), fix_up_level);
    }

    /// The level-by-level seed-compatible refinement: the reference for the fused one.
    #[cfg(test)]
    pub(crate) fn refine_seed_levelwise<P: CurvePoint>(
        &self,
        refiner: &mut Refiner<P>,
        points: &[P],
        flags: &[bool],
        topology: Topology,
        levels: u32,
        out: &mut Vec<P>,
    ) {
        use crate::refine::step;
        let scheme = &self.approximating;
        if levels == 0 {
            out.clear();
            out.extend_from_slice(points);
            return;
        }
        let (left, right) = self.halo(points.len(), topology);
        let capacity = scheme.refined_len(points.len(), topology, levels - 1) + left + right;
        for buffer in [&mut refiner.front, &mut refiner.back] {
            if buffer.len() < capacity {
                buffer.resize(capacity, P::zero());
            }
        }
        let (mut front, mut back) = (&mut refiner.front, &mut refiner.back);
        let mut n = points.len();
        front[left..left + n].copy_from_slice(points);
        let mut interpolated: Vec<usize> = (0..points.len()).filter(|&i| flags[i]).collect();
        let mut virtual_points = Vec::with_capacity(interpolated.len());
        for level in 0..levels {
            fill_halo(front, left, n, right, topology);
            let next = scheme.next_len(n, topology);
            let target: &mut [P] = if level + 1 == levels {
                out.truncate(next);
                out.resize(next, P::zero());
                out.as_mut_slice()
            } else {
                &mut back[left..left + next]
            };
            step(scheme, front, left, n, topology, target);
            let level_view = Level::new(front, -(left as i64), n, topology, &interpolated);
            virtual_points.clear();
            virtual_points.extend(interpolated.iter().map(|&i| self.virtual_point(&level_view, i as i64)));
            let level_view = Level { virtual_points: &virtual_points, ..level_view };
            let all: Vec<i64> = interpolated.iter().map(|&i| i as i64).collect();
            self.fix_up(&level_view, &all, target, 0, next, true);
            for i in &mut interpolated {
                *i *= 2;
            }
            if level + 1 < levels {
                std::mem::swap(&mut front, &mut back);
            }
            n = next;
        }
    }

    /// Recomputes the new points that read a virtual point (see the module docs): those
    /// around the I-points at (unwrapped) indices `around`, and near the ends of an open
    /// polygon, as far as they fall into `target` (fine indices `target_first..`, real ones
    /// for an open polygon, unwrapped ones for a closed polygon of `fine_len` points).
    fn fix_up<P: CurvePoint>(
        &self,
        level: &Level<'_, P>,
        around: &[i64],
        target: &mut [P],
        target_first: i64,
        fine_len: usize,
        seed_mode: bool,
    ) {
        let even = self.approximating.even_rule();
        let odd = self.approximating.odd_rule();
        let (even_lo, even_hi) = even.reach();
        let (odd_lo, odd_hi) = odd.reach();
        let n = level.n as i64;
        let fine_len = fine_len as i64;
        let target_end = target_first + target.len() as i64;
        // End vertices kept exactly (`CurveScheme::reflect_keeps_ends`; the virtual polygon
        // has `g = p` at a non-I end point, and reflects its own phantoms).
        let keeps_ends = level.topology == Topology::Open(EndRule::Reflect) && self.approximating.reflect_keeps_ends();
        // Outputs reading a phantom point must be redone when an I-point feeds the phantom
        // (phantoms of the virtual polygon, see `Level::virtual_or_actual`).
        let reach = [-even_lo, -odd_lo, even_hi, odd_hi, 1].into_iter().max().unwrap_or(1) as i64 + 1;
        let mut end_windows = 0..0;
        let mut end_windows_right = 0..0;
        if let Topology::Open(_) = level.topology {
            let near_start = level.interpolated.first().is_some_and(|&i| (i as i64) <= reach);
            let near_end = level.interpolated.last().is_some_and(|&i| (i as i64) >= n - 1 - reach);
            if near_start {
                end_windows = 0..(2 * reach + 2).min(fine_len);
            }
            if near_end {
                end_windows_right = (fine_len - 2 * reach - 2).max(0)..fine_len;
            }
        }
        let around_interpolated = around.iter().flat_map(|&i| {
            (i - even_hi as i64..=i - even_lo as i64)
                .map(|j| 2 * j)
                .chain((i - odd_hi as i64..=i - odd_lo as i64).map(|j| 2 * j + 1))
        });
        for fine in around_interpolated.chain(end_windows).chain(end_windows_right) {
            // Every copy of `fine` inside the target (a closed polygon's target may be
            // longer than one period).
            let (mut copy, period) = match level.topology {
                Topology::Closed => (target_first + (fine - target_first).rem_euclid(2 * n), 2 * n),
                Topology::Open(_) if (0..fine_len).contains(&fine) && fine >= target_first => (fine, fine_len),
                Topology::Open(_) => continue,
            };
            while copy < target_end {
                let j = copy.div_euclid(2);
                target[(copy - target_first) as usize] = if copy.rem_euclid(2) == 0 {
                    if level.is_interpolated(j) || (keeps_ends && (j == 0 || j == n - 1)) {
                        level.actual(j)
                    } else {
                        even.apply(j, |k| level.virtual_or_actual(k))
                    }
                } else if seed_mode && level.is_interpolated(j) && level.is_interpolated(j + 1) {
                    self.interpolating_edge.apply(j, |k| level.actual(k))
                } else {
                    odd.apply(j, |k| level.virtual_or_actual(k))
                };
                copy += period;
            }
        }
    }

    /// The exact-global virtual polygon: Gauss-Seidel on the strictly diagonally dominant
    /// system `ℓ(G around j) = p_j` (j interpolated), phantoms of `G` folded into the rows.
    fn solve_virtual<P: CurvePoint>(
        &self,
        points: &[P],
        interpolated: &[usize],
        topology: Topology,
    ) -> Result<Vec<P>, CurveError> {
        let n = points.len();
        let mut polygon = points.to_vec();
        if interpolated.is_empty() {
            return Ok(polygon);
        }
        let mut is_interpolated = vec![false; n];
        for &i in interpolated {
            is_interpolated[i] = true;
        }
        // Each row: (diagonal, known right-hand side, couplings to other unknowns).
        struct Row<P> {
            diagonal: f64,
            rhs: P,
            couplings: Vec<(usize, f64)>,
        }
        let mut rows = Vec::with_capacity(interpolated.len());
        for &j in interpolated {
            let mut terms: Vec<(usize, f64)> = Vec::new();
            for (k, &w) in self.limit_weights.iter().enumerate() {
                let index = j as i64 + self.limit_offset as i64 + k as i64;
                for (real, factor) in phantom_combination(index, n, topology) {
                    match terms.iter_mut().find(|t| t.0 == real) {
                        Some(t) => t.1 += w * factor,
                        None => terms.push((real, w * factor)),
                    }
                }
            }
            let mut diagonal = 0.0;
            let mut rhs = points[j];
            let mut couplings = Vec::new();
            for (real, coefficient) in terms {
                if real == j {
                    diagonal += coefficient;
                } else if is_interpolated[real] {
                    couplings.push((real, coefficient));
                } else {
                    rhs = rhs.minus(points[real].scale(coefficient));
                }
            }
            let off: f64 = couplings.iter().map(|c| c.1.abs()).sum();
            if diagonal.abs() <= off {
                return Err(CurveError::VirtualPoints(format!(
                    "the equation of point {j} is not diagonally dominant ({diagonal} vs {off})"
                )));
            }
            rows.push(Row { diagonal, rhs, couplings });
        }
        let scale = crate::point::bbox_diagonal(points).max(f64::MIN_POSITIVE);
        let tolerance = 8.0 * f64::EPSILON * scale;
        for _ in 0..MAX_SWEEPS {
            let mut change: f64 = 0.0;
            for (&j, row) in interpolated.iter().zip(&rows) {
                let mut value = row.rhs;
                for &(k, c) in &row.couplings {
                    value = value.minus(polygon[k].scale(c));
                }
                let value = value.scale(1.0 / row.diagonal);
                let delta = value.minus(polygon[j]);
                change = change.max((0..P::DIM).map(|a| delta.coord(a).abs()).fold(0.0, f64::max));
                polygon[j] = value;
            }
            if change <= tolerance {
                return Ok(polygon);
            }
        }
        Err(CurveError::VirtualPoints(format!("no convergence in {MAX_SWEEPS} sweeps")))
    }

    /// The subdivision matrix around an isolated I-point (all neighbours A), probed from
    /// one framework step on unit data, on the window of [`analysis::local_matrix`] of `A`
    /// (widened until closed).
    ///
    /// ```
    /// use subdiv_curve::Framework;
    /// let local = Framework::published().local_matrix();
    /// assert_eq!(local.indices, vec![-2, -1, 0, 1, 2]);
    /// assert_eq!(local.matrix.row(2).iter().copied().collect::<Vec<_>>(), vec![0.0, 0.0, 1.0, 0.0, 0.0]);
    /// ```
    pub fn local_matrix(&self) -> LocalMatrix {
        let mut indices = analysis::local_matrix(&self.approximating).indices;
        loop {
            let reach = indices.iter().map(|j| j.abs()).max().unwrap_or(0) as usize;
            let n = 8 * reach + 16;
            let centre = n / 2;
            let mut flags = vec![false; n];
            flags[centre] = true;
            // Column c of the step matrix: refine the unit vector e_c.
            let columns: Vec<Vec<f64>> = (0..n)
                .map(|c| {
                    let mut unit = vec![0.0; n];
                    unit[c] = 1.0;
                    self.clone()
                        .with_mode(VirtualPoints::SeedCompatible)
                        .refine(&unit, &flags, Topology::Closed, 1)
                        .expect("internal: valid probe")
                })
                .collect();
            let size = indices.len();
            let row_of = |k: i32| (2 * centre as i64 + k as i64) as usize;
            let col_of = |j: i32| (centre as i64 + j as i64) as usize;
            let closed = indices
                .iter()
                .all(|&k| (0..n).all(|c| indices.iter().any(|&j| col_of(j) == c) || columns[c][row_of(k)] == 0.0));
            if closed || size > 64 {
                let matrix = DMatrix::from_fn(size, size, |r, c| columns[col_of(indices[c])][row_of(indices[r])]);
                return LocalMatrix { indices, matrix };
            }
            let (lo, hi) = (indices[0] - 1, indices[size - 1] + 1);
            indices = (lo..=hi).collect();
        }
    }

    /// The map from local control points to local virtual points (identity except at the
    /// centre, where `q = (p_0 - sum_{k != 0} ℓ_k p_k) / ℓ_0`).
    fn local_virtual_map(&self, indices: &[i32]) -> DMatrix<f64> {
        let size = indices.len();
        let mut map = DMatrix::identity(size, size);
        let centre = indices.iter().position(|&j| j == 0).expect("internal: window contains the centre");
        let l0 = self.limit_weights[(-self.limit_offset) as usize];
        for (k, &w) in self.limit_weights.iter().enumerate() {
            let label = self.limit_offset + k as i32;
            if let Some(c) = indices.iter().position(|&j| j == label) {
                map[(centre, c)] = if label == 0 { 1.0 / l0 } else { -w / l0 };
            }
        }
        map
    }

    /// Measures the smoothness of the framework: the analyses of `A` and of rule (5), the
    /// local matrix at an I-point with its spectrum and eigen checks (eigenvectors taken in
    /// virtual coordinates), and the residual of the virtual-point theorem on a test
    /// polygon. `smoothness` combines `A`'s difference tests with the eigen checks at the
    /// I-point, and is `None` if the theorem fails.
    ///
    /// ```
    /// use subdiv_curve::Framework;
    /// let report = Framework::published().analyze();
    /// assert_eq!((report.smoothness, report.c1, report.c2), (Some(2), true, true));
    /// let spectrum: Vec<f64> = report.eigenvalues.iter().map(|l| (l.re * 1e12).round() / 1e12).collect();
    /// assert_eq!(spectrum, vec![1.0, 0.5, 0.25, 0.125, 0.125]);
    /// ```
    pub fn analyze(&self) -> FrameworkAnalysis {
        let approximating = analysis::analyze(&self.approximating);
        let interpolating = analysis::analyze(&self.interpolating_scheme());
        let local = self.local_matrix();
        let eigenvalues = analysis::eigenvalues(&local.matrix);
        let to_virtual = self.local_virtual_map(&local.indices);
        let eigen = analysis::checked_eigen_checks(&local, Some(&to_virtual));
        let theorem_residual = self.theorem_residual();
        let smoothness = if theorem_residual <= 1e-12 {
            analysis::combine_smoothness(&approximating.contractivity, &eigen)
        } else {
            None
        };
        FrameworkAnalysis {
            approximating,
            interpolating,
            local,
            eigenvalues,
            eigen,
            theorem_residual,
            c1: smoothness.is_some_and(|k| k >= 1),
            c2: smoothness.is_some_and(|k| k >= 2),
            smoothness,
        }
    }

    /// `max |framework step - A(G)|` over the non-I entries of one seed-compatible step on
    /// a fixed pseudo-random closed polygon with isolated I-points.
    fn theorem_residual(&self) -> f64 {
        let n = 40;
        let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
        let points: Vec<[f64; 2]> = (0..n)
            .map(|_| {
                let mut next = || {
                    state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
                    (state >> 11) as f64 / (1u64 << 53) as f64
                };
                [next(), next()]
            })
            .collect();
        let mut flags = vec![false; n];
        for i in (0..n).step_by(2 * self.limit_radius() + 3) {
            flags[i] = true;
        }
        let seed = self.clone().with_mode(VirtualPoints::SeedCompatible);
        let (Ok(fine), Ok(virtual_polygon)) = (
            seed.refine(&points, &flags, Topology::Closed, 1),
            seed.virtual_polygon(&points, &flags, Topology::Closed),
        ) else {
            return f64::INFINITY;
        };
        let Ok(expected) = self.approximating.refine(&virtual_polygon, Topology::Closed, 1) else {
            return f64::INFINITY;
        };
        (0..2 * n)
            .filter(|&f| !(f % 2 == 0 && flags[f / 2]))
            .map(|f| (0..2).map(|a| (fine[f][a] - expected[f][a]).abs()).fold(0.0, f64::max))
            .fold(0.0, f64::max)
    }
}

/// The framework's measured smoothness ([`Framework::analyze`]).
#[derive(Debug, Clone, PartialEq)]
pub struct FrameworkAnalysis {
    /// The approximating scheme `A` (rule (6)).
    pub approximating: Analysis,
    /// The uniform four-point scheme of rule (5).
    pub interpolating: Analysis,
    /// Local subdivision matrix at an isolated I-point.
    pub local: LocalMatrix,
    /// Its eigenvalues by decreasing modulus.
    pub eigenvalues: Vec<nalgebra::Complex<f64>>,
    /// Eigen conditions at the I-point (eigenvectors in virtual coordinates).
    pub eigen: EigenChecks,
    /// Residual of the virtual-point theorem (0 up to rounding when it holds).
    pub theorem_residual: f64,
    /// C1 established at and away from I-points.
    pub c1: bool,
    /// C2 established at and away from I-points.
    pub c2: bool,
    /// Largest `k` established.
    pub smoothness: Option<usize>,
}

/// One level of the seed-compatible refinement, for the fix-ups: a window of its points
/// (the whole level with its halo, or the part a block needs).
struct Level<'a, P> {
    /// Points at extended indices `first..` (wrapped copies or phantom points outside
    /// `0..n`).
    window: &'a [P],
    first: i64,
    n: usize,
    topology: Topology,
    /// Sorted indices of the I-points.
    interpolated: &'a [usize],
    /// If set: the sorted unwrapped indices of the I-points of a block's window that the
    /// fix-ups may look up (all it reads), and the slots of `virtual_points` refer to
    /// them; else the slots refer to `interpolated`.
    near: Option<&'a [i64]>,
    /// Virtual points by slot.
    virtual_points: &'a [P],
}

impl<'a, P: CurvePoint> Level<'a, P> {
    fn new(window: &'a [P], first: i64, n: usize, topology: Topology, interpolated: &'a [usize]) -> Self {
        Level { window, first, n, topology, interpolated, near: None, virtual_points: &[] }
    }

    /// Slot (in `near` if set, else in `interpolated`) of coarse index `j`, if it is an
    /// I-point.
    fn interpolated_slot(&self, j: i64) -> Option<usize> {
        if let Some(near) = self.near {
            return near.binary_search(&j).ok();
        }
        let j = match self.topology {
            Topology::Closed => j.rem_euclid(self.n as i64),
            Topology::Open(_) if (0..self.n as i64).contains(&j) => j,
            Topology::Open(_) => return None,
        };
        self.interpolated.binary_search(&(j as usize)).ok()
    }

    fn is_interpolated(&self, j: i64) -> bool {
        self.interpolated_slot(j).is_some()
    }

    /// The current point `j` (a copy of a closed polygon's point inside the window, or a
    /// phantom point of an open polygon).
    fn actual(&self, j: i64) -> P {
        let index = match self.topology {
            Topology::Closed => (j - self.first).rem_euclid(self.n as i64),
            Topology::Open(_) => j - self.first,
        };
        self.window[index as usize]
    }

    /// Entry `j` of the virtual polygon; past the ends of an open polygon, the phantom
    /// point of the virtual polygon.
    fn virtual_or_actual(&self, j: i64) -> P {
        if let Topology::Open(_) = self.topology
            && !(0..self.n as i64).contains(&j)
        {
            return phantom_combination(j, self.n, self.topology)
                .fold(P::zero(), |sum, (real, factor)| sum.plus(self.virtual_or_actual(real as i64).scale(factor)));
        }
        match self.interpolated_slot(j) {
            Some(slot) => self.virtual_points[slot],
            None => self.actual(j),
        }
    }
}

/// A possibly out-of-range index of an open polygon as a combination of real indices
/// (phantom rule), or wrapped for a closed one.
fn phantom_combination(index: i64, n: usize, topology: Topology) -> impl Iterator<Item = (usize, f64)> {
    let n = n as i64;
    let (terms, count) = match topology {
        Topology::Closed => ([(index.rem_euclid(n) as usize, 1.0), (0, 0.0)], 1),
        Topology::Open(_) if (0..n).contains(&index) => ([(index as usize, 1.0), (0, 0.0)], 1),
        Topology::Open(rule) => {
            let (end, beyond) = if index < 0 { (0, -index) } else { (n - 1, index - (n - 1)) };
            let mirror = if index < 0 { beyond.min(n - 1) } else { n - 1 - beyond.min(n - 1) };
            match rule {
                EndRule::Reflect => ([(end as usize, 2.0), (mirror as usize, -1.0)], 2),
                EndRule::Repeat => ([(end as usize, 1.0), (0, 0.0)], 1),
            }
        }
    };
    terms.into_iter().take(count)
}

/// Appends to `out` every index in `lo..hi` that is (a copy of) an entry of `sorted`
/// (indices of a polygon of `n` points; copies only for a closed one).
fn unwrapped_positions(sorted: &[usize], n: usize, topology: Topology, lo: i64, hi: i64, out: &mut Vec<i64>) {
    let n = n as i64;
    let (lo, hi) = match topology {
        Topology::Closed => (lo, hi),
        Topology::Open(_) => (lo.max(0), hi.min(n)),
    };
    if lo >= hi {
        return;
    }
    for copy in lo.div_euclid(n)..=(hi - 1).div_euclid(n) {
        let base = copy * n;
        let start = sorted.partition_point(|&i| (i as i64) < lo - base);
        out.extend(sorted[start..].iter().map(|&i| base + i as i64).take_while(|&i| i < hi));
    }
}

/// Flags for `n` points with the given indices set to *interpolate*.
///
/// # Errors
/// [`CurveError::IndexOutOfRange`] for an index `>= n`; [`CurveError::TooLarge`] for
/// more than [`MAX_REFINED_POINTS`](crate::MAX_REFINED_POINTS) points.
///
/// ```
/// use subdiv_curve::flags_from_indices;
/// assert_eq!(flags_from_indices(4, &[0, 2])?, vec![true, false, true, false]);
/// assert!(flags_from_indices(4, &[4]).is_err());
/// // More points than any polygon of the crate: an error, not a failed allocation.
/// assert!(flags_from_indices(usize::MAX, &[0]).is_err());
/// # Ok::<(), subdiv_curve::CurveError>(())
/// ```
pub fn flags_from_indices(n: usize, indices: &[usize]) -> Result<Vec<bool>, CurveError> {
    // No polygon has more points than a refinement may make.
    if n > crate::MAX_REFINED_POINTS {
        return Err(CurveError::TooLarge { points: n, levels: 0, max: crate::MAX_REFINED_POINTS });
    }
    let mut flags = vec![false; n];
    for &index in indices {
        *flags.get_mut(index).ok_or(CurveError::IndexOutOfRange { index, len: n })? = true;
    }
    Ok(flags)
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    /// Finite points whose virtual polygon overflows: `Overflow` naming the virtual
    /// polygon, in both modes (it was `Ok` with an infinity; the exact-global refinement
    /// blamed an input point for it).
    #[test]
    fn an_overflowing_virtual_polygon_is_an_error() {
        let points = [[1e308, 0.0], [-1e308, 0.0], [1e308, 1.0], [0.0, -1e308]];
        let flags = [true; 4];
        for framework in [Framework::published(), Framework::published().with_mode(VirtualPoints::ExactGlobal)] {
            let error = framework.virtual_polygon(&points, &flags, Topology::Closed).unwrap_err();
            assert!(matches!(error, CurveError::Overflow { what: "virtual polygon", .. }), "{error}");
            // The refinement: finite points (the interpolated points are the input's), or
            // the same error.
            match framework.refine(&points, &flags, Topology::Closed, 1) {
                Ok(refined) => assert!(refined.iter().all(|p| p.iter().all(|c| c.is_finite()))),
                Err(error) => assert!(matches!(error, CurveError::Overflow { what: "virtual polygon", .. }), "{error}"),
            }
        }
    }

    fn bits(points: &[[f64; 2]]) -> Vec<u64> {
        points.iter().flat_map(|p| p.map(f64::to_bits)).collect()
    }

    fn arb_framework() -> impl Strategy<Value = Framework> {
        prop_oneof![
            Just(Framework::published()),
            (-0.1f64..0.0, 0.0f64..0.2).prop_map(|(omega1, gamma)| {
                Framework::new(omega1, gamma / 2.0 - 1.0 / 16.0, gamma).expect("parameters on the C2 line")
            }),
            (-0.1f64..0.0, 0.0f64..0.2).prop_map(|(omega1, gamma)| {
                Framework::new(omega1, 0.0, gamma).expect("parameters with omega2 = 0")
            }),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(128))]

        /// The fused framework equals its level-by-level path bit for bit, in both modes.
        #[test]
        fn fused_framework_equals_level_by_level(
            framework in arb_framework(),
            closed in any::<bool>(),
            reflect in any::<bool>(),
            raw in prop::collection::vec((-10.0f64..10.0, -10.0f64..10.0, any::<bool>()), 4..30),
            levels in 0u32..6,
            exact in any::<bool>(),
            block in 1usize..40,
        ) {
            let topology = match (closed, reflect) {
                (true, _) => Topology::Closed,
                (false, true) => Topology::Open(EndRule::Reflect),
                (false, false) => Topology::Open(EndRule::Repeat),
            };
            let points: Vec<[f64; 2]> = raw.iter().map(|&(x, y, _)| [x, y]).collect();
            let flags: Vec<bool> = raw.iter().map(|&(_, _, flag)| flag).collect();
            let mode = if exact { VirtualPoints::ExactGlobal } else { VirtualPoints::SeedCompatible };
            let framework = framework.with_mode(mode);
            let mut refiner = Refiner::new();
            let mut fused = Vec::new();
            let result = framework.refine_into(&mut refiner, &points, &flags, topology, levels, &mut fused);
            prop_assume!(result.is_ok());
            let mut reference = Vec::new();
            match mode {
                VirtualPoints::SeedCompatible => {
                    // Also with small blocks: many block borders and I-points near them.
                    let interpolated: Vec<usize> = (0..points.len()).filter(|&i| flags[i]).collect();
                    let mut small_blocks = Vec::new();
                    framework.refine_seed(&mut refiner, &points, &interpolated, topology, levels, &mut small_blocks, block);
                    framework.refine_seed_levelwise(&mut refiner, &points, &flags, topology, levels, &mut reference);
                    prop_assert_eq!(bits(&small_blocks), bits(&reference));
                }
                VirtualPoints::ExactGlobal => {
                    let virtual_polygon = framework.virtual_polygon(&points, &flags, topology).expect("solvable");
                    refiner.refine_levelwise(framework.approximating_scheme(), &virtual_polygon, topology, levels, &mut reference);
                    for i in (0..points.len()).filter(|&i| flags[i]) {
                        reference[i << levels] = points[i];
                    }
                }
            }
            prop_assert_eq!(bits(&fused), bits(&reference));
        }
    }

    /// Small blocks: a long polygon with I-points everywhere, also next to block borders.
    #[test]
    fn fused_framework_across_many_blocks() {
        let points: Vec<[f64; 2]> = (0..700).map(|k| [(k as f64 * 0.37).sin(), (k as f64 * 0.11).cos()]).collect();
        let flags: Vec<bool> = (0..700).map(|k| k % 7 == 0 || k % 11 == 3 || k == 699).collect();
        for topology in [Topology::Closed, Topology::Open(EndRule::Reflect), Topology::Open(EndRule::Repeat)] {
            let framework = Framework::published();
            let mut refiner = Refiner::new();
            let (mut fused, mut reference) = (Vec::new(), Vec::new());
            framework.refine_into(&mut refiner, &points, &flags, topology, 6, &mut fused).expect("valid input");
            framework.refine_seed_levelwise(&mut refiner, &points, &flags, topology, 6, &mut reference);
            assert!(fused.len() > 2 * crate::refine::block_len::<[f64; 2]>());
            assert_eq!(bits(&fused), bits(&reference), "{topology:?}");
            let interpolated: Vec<usize> = (0..700).filter(|&i| flags[i]).collect();
            framework.refine_seed(&mut refiner, &points, &interpolated, topology, 6, &mut fused, 999);
            assert_eq!(bits(&fused), bits(&reference), "{topology:?}, 999-point blocks");
        }
    }

    /// Large outputs spread their blocks over the worker threads; the I-point corrections
    /// near block borders come out the same on 1, 2 and 3 threads, both modes.
    #[test]
    fn framework_on_any_thread_count_gives_the_same_bits() {
        let points: Vec<[f64; 2]> = (0..400).map(|k| [(k as f64 * 0.37).sin(), (k as f64 * 0.11).cos()]).collect();
        let flags: Vec<bool> = (0..400).map(|k| k % 7 == 0 || k % 11 == 3).collect();
        for topology in [Topology::Closed, Topology::Open(EndRule::Reflect)] {
            let framework = Framework::published();
            let mut reference = Vec::new();
            framework.refine_seed_levelwise(&mut Refiner::new(), &points, &flags, topology, 10, &mut reference);
            for mode in [VirtualPoints::SeedCompatible, VirtualPoints::ExactGlobal] {
                let framework = Framework::published().with_mode(mode);
                let mut single = Vec::new();
                framework.refine_into(&mut Refiner::new(), &points, &flags, topology, 10, &mut single).unwrap();
                if mode == VirtualPoints::SeedCompatible {
                    assert_eq!(bits(&single), bits(&reference), "{topology:?}");
                }
                for threads in [2, 3] {
                    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                    let mut refiner = Refiner::new();
                    let mut out = Vec::new();
                    pool.install(|| framework.refine_into(&mut refiner, &points, &flags, topology, 10, &mut out))
                        .unwrap();
                    assert_eq!(refiner.spare.len(), threads - 1);
                    assert_eq!(bits(&out), bits(&single), "{topology:?} {mode:?} on {threads} threads");
                }
            }
        }
    }
}
