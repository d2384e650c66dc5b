//! Multi-band (M-adic) Loop subdivision from the three-direction box spline N(2,2,2):
//! exact masks for any arity `M`, ternary (1-to-9) and quaternary (1-to-16) subdivision
//! of triangle meshes.
//!
//! # Regular masks
//! The quartic C2 box spline with directions `e1 = (1,0)`, `e2 = (0,1)`, `e3 = (1,1)`,
//! each twice, refines with the `M`-adic symbol
//! `a_M(z) = M^-4 prod_{xi in (e1, e1, e2, e2, e3, e3)} (1 + z^xi + ... + z^((M-1) xi))`.
//! With coarse vertices at the integer lattice points (triangles `(i,j), (i+1,j),
//! (i+1,j+1)` and `(i,j), (i+1,j+1), (i,j+1)`), the fine point at `y = (s/M, t/M)` is
//! `sum_p a_M[M (y - p) + 2 (M-1) (1,1)] c(p)`. [`box_spline_masks`] returns these
//! stencils exactly, as integer numerators over `M^4`; `M = 2` gives Loop's regular
//! rules, `M = 3` the ternary and `M = 4` the quaternary ones (Zhao's thesis, seed 002;
//! the composition `a_{M1 M2}(z) = a_{M1}(z) a_{M2}(z^{M1})` holds exactly). They apply
//! to any regular (valence 6) triangulation; [`subdivide_lattice`] applies them to a
//! periodic lattice (a regular torus).
//!
//! # Ternary Loop on meshes ([`ternary_subdivide`])
//! Only two rules differ from the regular ones at a vertex `v` of valence `n` with
//! neighbours `q_0 .. q_{n-1}`:
//! - vertex point `alpha v + (1 - alpha) / n sum q_l` with `alpha = 5/9`;
//! - the point at 1/3 of edge `(v, q_j)`:
//!   `4/9 v + sum_l gamma_l q_{j+l}` with
//!   `gamma_l = (1/n) sum_k ghat_k cos(2 pi k l / n)`, `ghat_0 = 5/9`,
//!   `ghat_k = lambda^min(k, n-k)` (a Fourier construction that gives the 1-ring
//!   spectrum `1, lambda, lambda, lambda^2, ..., 1/9`; [`TernaryOptions::lambda`],
//!   default 1/3, which reproduces the regular stencil at `n = 6`).
//!
//! Every fine edge point is the 1/3-point of one end of its edge, so these are all the
//! edge rules; the triangle centre is `8/27` of each corner plus `1/27` of each vertex
//! across an edge. The rules are the ones proposed by the specification of this project
//! from the seed's parameters (the seed's own formulas are missing); their C1 property
//! is checked numerically by [`crate::analysis`].
//!
//! Boundaries (a proposal, without a smoothness claim): the boundary polygon follows the
//! ternary cubic B-spline (vertex `(4, 19, 4)/27`, 1/3-point `(16, 10, 1)/27`), the
//! 1/3-point of an interior edge at a boundary vertex uses the regular stencil restricted
//! to the edge's two triangles (`(36, 20, 10, 10)/76`), and a triangle centre replaces a
//! missing vertex across a boundary edge by the reflected corner `a + b - c`.
//!
//! # Quaternary Loop ([`quaternary_subdivide`])
//! The seed's extraordinary quaternary rules cannot be reconstructed from its text, so a
//! quaternary step is two Loop steps: by the composition identity this equals the
//! quaternary box-spline masks on regular parts, and it is C1 wherever Loop is. Vertex
//! and face order are those of two Loop steps (see [`crate::forward`]).
//!
//! # Output order of a ternary step
//! - vertices `0 .. V`: vertex points; `V + 2e` and `V + 2e + 1`: the points at 1/3
//!   and 2/3 of edge `e` from its first vertex (the origin of its first half-edge,
//!   `HalfedgeMesh::edge_vertices(e)[0]`); `V + 2E + f`: the centre of face `f`;
//! - faces: face `f` with corners `c_k` and the points `n_k`, `f_k` at 1/3 and 2/3 of its
//!   half-edge `k` (from `c_k` to `c_{k+1}`) and centre `g` gives
//!   `9f + k = (c_k, n_k, f_{k-1})`, `9f + 3 + k = (n_k, f_k, g)`,
//!   `9f + 6 + k = (f_{k-1}, n_k, g)` for `k = 0, 1, 2`.
//!
//! Counts per step: `V' = V + (M-1) E + F (M-1)(M-2)/2`, `F' = M^2 F`.

use std::collections::BTreeMap;

use glam::DVec3;
use mesh_topo::{HalfedgeId, HalfedgeMesh};
use serde::{Deserialize, Serialize};

use crate::LoopError;
use crate::forward::topology::Topology;
use crate::forward::{
    Attribute, LoopMesh, LoopOptions, MAX_LEVELS, SparseRow, SubdivisionMatrix, check_finite_largest,
    check_finite_values, check_level_limit, check_no_overflow, checked_refined, subdivide, too_many_levels,
};

/// Largest arity [`box_spline_masks`] accepts (numerators then stay far below `u64`).
pub const MAX_ARITY: u32 = 64;

/// The vertices, edges and faces of a triangle mesh after one `arity`-band step (2:
/// Loop, 3: ternary, 4: quaternary) from `[vertices, edges, faces]`: every edge split
/// into `M`, every triangle into `M^2`, so `V' = V + (M-1) E + (M-1)(M-2)/2 F`,
/// `E' = M E + 3 M(M-1)/2 F` and `F' = M^2 F`, exact on any triangle mesh, closed or not
/// (isolated vertices stay). Saturates at `u64::MAX`. The one count recurrence of the
/// Loop family: the size checks of [`subdivide`], [`ternary_subdivide`] and the facade's
/// counts follow it.
///
/// ```
/// use subdiv_loop::mband::counts_after_step;
///
/// // The tetrahedron (4 vertices, 6 edges, 4 faces) after a Loop, a ternary and a
/// // quaternary step (two Loop steps: 4 -> 10 -> 34 vertices).
/// assert_eq!(counts_after_step(2, [4, 6, 4]), [10, 24, 16]);
/// assert_eq!(counts_after_step(3, [4, 6, 4]), [20, 54, 36]);
/// assert_eq!(counts_after_step(4, [4, 6, 4]), counts_after_step(2, [10, 24, 16]));
/// assert_eq!(counts_after_step(2, [u64::MAX, 1, 1])[0], u64::MAX);
/// ```
pub fn counts_after_step(arity: u32, [vertices, edges, faces]: [u64; 3]) -> [u64; 3] {
    let m = u64::from(arity);
    let (m1, m2) = (m.saturating_sub(1), m.saturating_sub(2));
    let inner_vertices = m1.saturating_mul(m2) / 2;
    let inner_edges = m.saturating_mul(m1) / 2 * 3;
    [
        vertices.saturating_add(edges.saturating_mul(m1)).saturating_add(faces.saturating_mul(inner_vertices)),
        edges.saturating_mul(m).saturating_add(faces.saturating_mul(inner_edges)),
        faces.saturating_mul(m.saturating_mul(m)),
    ]
}

/// One weight of a regular stencil: the coarse lattice point (relative to the fine
/// point's coarse cell corner) and the integer numerator (over `M^4`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct LatticeWeight {
    /// Coarse lattice point `p = (i, j)`.
    pub point: (i32, i32),
    /// Weight numerator; the weight is `numerator / M^4`.
    pub numerator: u64,
}

/// The exact `M`-adic refinement masks of the box spline N(2,2,2).
///
/// ```
/// use subdiv_loop::mband::box_spline_masks;
///
/// let loop_masks = box_spline_masks(2)?;
/// // Loop's regular vertex rule: 10/16 on the vertex, 1/16 on each neighbour.
/// let vertex = loop_masks.stencil(0, 0);
/// assert_eq!(vertex.len(), 7);
/// assert!(vertex.iter().any(|w| w.point == (0, 0) && w.numerator == 10));
/// assert_eq!(loop_masks.denominator(), 16);
/// // The ternary vertex weight 5/9 = 45/81.
/// let ternary = box_spline_masks(3)?;
/// assert!(ternary.stencil(0, 0).iter().any(|w| w.point == (0, 0) && w.numerator == 45));
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct BoxSplineMasks {
    arity: u32,
    /// Symbol coefficients (numerators), `(4(M-1)+1)^2`, index `i + size * j` for
    /// `z1^i z2^j`.
    symbol: Vec<u64>,
    /// Stencils of the `M^2` cosets, index `s + M t`.
    stencils: Vec<Vec<LatticeWeight>>,
}

impl BoxSplineMasks {
    /// The arity `M`.
    ///
    /// ```
    /// use subdiv_loop::mband::box_spline_masks;
    ///
    /// let masks = box_spline_masks(4)?;
    /// assert_eq!(masks.arity(), 4);
    /// // M^2 fine points per coarse cell, weights over M^4, symbol of side 4 (M - 1) + 1.
    /// assert_eq!((masks.denominator(), masks.symbol_size()), (256, 13));
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn arity(&self) -> u32 {
        self.arity
    }

    /// The common denominator `M^4`.
    pub fn denominator(&self) -> u64 {
        (self.arity as u64).pow(4)
    }

    /// Side of the symbol's coefficient square, `4(M-1) + 1`.
    pub fn symbol_size(&self) -> usize {
        4 * (self.arity as usize - 1) + 1
    }

    /// The numerator of the coefficient of `z1^i z2^j` in `M^4 a_M(z)` (0 outside).
    ///
    /// ```
    /// use subdiv_loop::mband::box_spline_masks;
    ///
    /// // M = 2: M^4 a_2(z) = (1 + z1)^2 (1 + z2)^2 (1 + z1 z2)^2.
    /// let masks = box_spline_masks(2)?;
    /// assert_eq!(masks.symbol_coefficient(2, 2), 10); // Loop's regular vertex weight 10/16
    /// assert_eq!((masks.symbol_coefficient(4, 4), masks.symbol_coefficient(4, 0)), (1, 0));
    /// assert_eq!(masks.symbol_coefficient(5, 2), 0); // outside the 5 x 5 square
    /// // At z = (1, 1) each of the six factors is M: the coefficients sum to M^6.
    /// for m in 2..=4u32 {
    ///     let masks = box_spline_masks(m)?;
    ///     let size = masks.symbol_size();
    ///     let sum: u64 = (0..size * size).map(|k| masks.symbol_coefficient(k % size, k / size)).sum();
    ///     assert_eq!(sum, u64::from(m).pow(6));
    /// }
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn symbol_coefficient(&self, i: usize, j: usize) -> u64 {
        let size = self.symbol_size();
        if i < size && j < size { self.symbol[i + size * j] } else { 0 }
    }

    /// The stencil of the fine point at `(s/M, t/M)` (`0 <= s, t < M`): coarse lattice
    /// points and numerators. The stencil of `(s/M + i, t/M + j)` is the same shifted by
    /// `(i, j)`.
    ///
    /// # Panics
    /// If `s` or `t` is not below `M`.
    pub fn stencil(&self, s: u32, t: u32) -> &[LatticeWeight] {
        assert!(s < self.arity && t < self.arity, "coset ({s}, {t}) out of range for M = {}", self.arity);
        &self.stencils[(s + self.arity * t) as usize]
    }
}

/// The exact `M`-adic masks of the three-direction box spline N(2,2,2), for
/// `2 <= M <= 64`.
///
/// ```
/// use subdiv_loop::mband::box_spline_masks;
///
/// // Loop's regular edge rule at (1/2, 0): 3/8 on the ends, 1/8 on the opposite vertices.
/// let loop_masks = box_spline_masks(2)?;
/// let edge: Vec<_> = loop_masks.stencil(1, 0).iter().map(|w| (w.point, w.numerator)).collect();
/// assert_eq!(edge, [((0, -1), 2), ((0, 0), 6), ((1, 0), 6), ((1, 1), 2)]);
/// // Every stencil of every arity is affine: its numerators sum to M^4.
/// for m in 2..=5 {
///     let masks = box_spline_masks(m)?;
///     let sum = |s, t| masks.stencil(s, t).iter().map(|w| w.numerator).sum::<u64>();
///     assert!((0..m).all(|s| (0..m).all(|t| sum(s, t) == masks.denominator())));
/// }
/// assert!(box_spline_masks(1).is_err());
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// [`LoopError::InvalidParameter`] for `M` outside `2 ..= 64`.
pub fn box_spline_masks(arity: u32) -> Result<BoxSplineMasks, LoopError> {
    if !(2..=MAX_ARITY).contains(&arity) {
        return Err(LoopError::InvalidParameter {
            name: "arity",
            reason: format!("M = {arity}; the box-spline masks are built for 2 <= M <= {MAX_ARITY}"),
        });
    }
    let m = arity as usize;
    let size = 4 * (m - 1) + 1;
    // Multiply the six factors (1 + z^xi + ... + z^((M-1) xi)).
    let mut symbol = vec![0u64; size * size];
    symbol[0] = 1;
    for direction in [(1, 0), (1, 0), (0, 1), (0, 1), (1, 1), (1, 1)] {
        let mut next = vec![0u64; size * size];
        for j in 0..size {
            for i in 0..size {
                let c = symbol[i + size * j];
                if c == 0 {
                    continue;
                }
                for k in 0..m {
                    let (a, b) = (i + k * direction.0, j + k * direction.1);
                    if a < size && b < size {
                        next[a + size * b] += c;
                    }
                }
            }
        }
        symbol = next;
    }
    let offset = 2 * (m as i64 - 1);
    let mut stencils = Vec::with_capacity(m * m);
    for t in 0..m as i64 {
        for s in 0..m as i64 {
            let mut weights = Vec::new();
            // Index (s - M p_i + offset, t - M p_j + offset) in 0..size.
            for pj in -3..=3i64 {
                for pi in -3..=3i64 {
                    let (a, b) = (s - m as i64 * pi + offset, t - m as i64 * pj + offset);
                    if (0..size as i64).contains(&a) && (0..size as i64).contains(&b) {
                        let numerator = symbol[a as usize + size * b as usize];
                        if numerator != 0 {
                            weights.push(LatticeWeight { point: (pi as i32, pj as i32), numerator });
                        }
                    }
                }
            }
            stencils.push(weights);
        }
    }
    Ok(BoxSplineMasks { arity, symbol, stencils })
}

/// Applies the `M`-adic box-spline masks to values on a periodic `width x height`
/// lattice (vertex `(i, j)` at index `i + width * j`; a regular torus), giving the
/// `M width x M height` fine lattice.
///
/// ```
/// use subdiv_loop::mband::{box_spline_masks, subdivide_lattice};
///
/// // Constant data stays constant (every coset sums to 1).
/// let fine = subdivide_lattice(&vec![2.5f64; 6 * 5], 6, 5, &box_spline_masks(3)?)?;
/// assert_eq!(fine.len(), 18 * 15);
/// assert!(fine.iter().all(|v| (v - 2.5).abs() < 1e-14));
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// [`LoopError::InvalidParameter`] if the lattice is smaller than 4 x 4 (stencils would
/// wrap onto themselves), `values.len() != width * height`, or either lattice has more
/// points than memory holds (sizes are checked, never wrapped);
/// [`LoopError::NonFiniteAttribute`] (naming the lattice index) and
/// [`LoopError::AttributeOverflow`] as for
/// [`refine_attribute`](crate::forward::refine_attribute).
pub fn subdivide_lattice<T: Attribute>(
    values: &[T],
    width: usize,
    height: usize,
    masks: &BoxSplineMasks,
) -> Result<Vec<T>, LoopError> {
    let bad = |reason: String| LoopError::InvalidParameter { name: "lattice", reason };
    let Some(points) = width.checked_mul(height) else {
        return Err(bad(format!("a {width} x {height} lattice has more points than a slice holds")));
    };
    if width < 4 || height < 4 || values.len() != points {
        return Err(bad(format!("{} values for a {width} x {height} lattice (at least 4 x 4)", values.len())));
    }
    check_finite_values(values)?;
    let m = masks.arity as usize;
    let denominator = masks.denominator() as f64;
    // The coarse sizes fit (they hold `values`); the fine ones must be checked (a wrapped
    // size would index out of range). Then every size is below `usize::MAX / 4`, so the
    // `i64` stencil offsets below do not wrap either.
    let fine_bytes = |w: usize, h: usize| w.checked_mul(h)?.checked_mul(size_of::<T>().max(1));
    let fine_sizes = m.checked_mul(width).zip(m.checked_mul(height));
    let Some((fine_width, fine_height)) =
        fine_sizes.filter(|&(w, h)| fine_bytes(w, h).is_some_and(|bytes| bytes <= isize::MAX as usize))
    else {
        return Err(bad(format!("a {width} x {height} lattice refined by {m} has more points than memory holds")));
    };
    let mut fine = Vec::with_capacity(fine_width * fine_height);
    for fj in 0..fine_height {
        for fi in 0..fine_width {
            let (ci, cj, s, t) = (fi / m, fj / m, fi % m, fj % m);
            let stencil = masks.stencil(s as u32, t as u32);
            let at = |w: &LatticeWeight| {
                let i = (ci as i64 + w.point.0 as i64).rem_euclid(width as i64) as usize;
                let j = (cj as i64 + w.point.1 as i64).rem_euclid(height as i64) as usize;
                &values[i + width * j]
            };
            let mut value = at(&stencil[0]).scaled(stencil[0].numerator as f64 / denominator);
            for w in &stencil[1..] {
                value.add_scaled(at(w), w.numerator as f64 / denominator);
            }
            fine.push(value);
        }
    }
    checked_refined(fine)
}

/// Options of ternary Loop subdivision.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TernaryOptions {
    /// The subdominant eigenvalue `lambda` of the 1-ring rule, in `(1/9, 1/2]`
    /// (default 1/3, "Loop's choice", which gives the regular stencil at valence 6; the
    /// seed recommends `lambda <= 1/3` at valence 3).
    pub lambda: f64,
}

impl Default for TernaryOptions {
    fn default() -> Self {
        Self { lambda: 1.0 / 3.0 }
    }
}

impl TernaryOptions {
    fn validate(&self) -> Result<(), LoopError> {
        if self.lambda > 1.0 / 9.0 && self.lambda <= 0.5 {
            Ok(())
        } else {
            Err(LoopError::InvalidParameter {
                name: "lambda",
                reason: format!("{} is outside (1/9, 1/2], the range of the ternary 1-ring rule", self.lambda),
            })
        }
    }
}

/// Ternary vertex weight (the seed's alpha).
pub const TERNARY_ALPHA: f64 = 5.0 / 9.0;

/// The ring weights `gamma_l` (`l = 0 .. n-1`) of the 1/3-point of an edge at a vertex
/// of valence `n`.
///
/// ```
/// use subdiv_loop::mband::ternary_edge_weights;
///
/// // Valence 6 with lambda = 1/3: the regular stencil, (20, 10, 2, 1, 2, 10) / 81.
/// let gamma = ternary_edge_weights(6, 1.0 / 3.0)?;
/// assert!((gamma[0] * 81.0 - 20.0).abs() < 1e-13);
/// assert!(ternary_edge_weights(2, 1.0 / 3.0).is_err());
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// [`LoopError::InvalidParameter`] for a valence outside `3 ..=`
/// [`MAX_VALENCE`](crate::analysis::MAX_VALENCE) (the valences the rule is analysed
/// for; the cost grows as `n^2`) or `lambda` outside `(1/9, 1/2]`, as for
/// [`TernaryOptions`].
pub fn ternary_edge_weights(n: usize, lambda: f64) -> Result<Vec<f64>, LoopError> {
    if !(3..=crate::analysis::MAX_VALENCE).contains(&n) {
        return Err(LoopError::InvalidParameter {
            name: "valence",
            reason: format!("{n}; the ternary edge weights cover valences 3 to {}", crate::analysis::MAX_VALENCE),
        });
    }
    TernaryOptions { lambda }.validate()?;
    Ok(edge_weights(n, lambda))
}

/// [`ternary_edge_weights`] for any valence of a mesh (checked `lambda`): the sum of the
/// definition up to [`MAX_VALENCE`](crate::analysis::MAX_VALENCE), its `O(n)` closed
/// form above (the sum is `O(n^2)`: minutes at a vertex of valence `10^5`).
fn edge_weights(n: usize, lambda: f64) -> Vec<f64> {
    if n > crate::analysis::MAX_VALENCE {
        return edge_weights_closed(n, lambda);
    }
    (0..n)
        .map(|l| {
            let mut sum = 5.0 / 9.0;
            for k in 1..n {
                let angle = std::f64::consts::TAU * (k * l) as f64 / n as f64;
                sum += lambda.powi(k.min(n - k) as i32) * angle.cos();
            }
            sum / n as f64
        })
        .collect()
}

/// The closed form of [`edge_weights`]: with `θ = 2π l / n` and `H = (n - 1) / 2`,
/// `sum_k λ^min(k, n-k) cos(kθ) = 2 Re sum_{k=1}^{H} z^k` (`z = λ e^{iθ}`, a geometric
/// series), plus `λ^(n/2) (-1)^l` for even `n`. `|z| <= 1/2`, so `1 - z` is well away
/// from 0.
fn edge_weights_closed(n: usize, lambda: f64) -> Vec<f64> {
    let turn = |m: u128| std::f64::consts::TAU * (m % n as u128) as f64 / n as f64;
    let h = (n - 1) / 2;
    let lambda_h = lambda.powf(h as f64);
    (0..n)
        .map(|l| {
            let (sin, cos) = turn(l as u128).sin_cos();
            let (sin_h, cos_h) = turn(l as u128 * h as u128).sin_cos();
            // z (1 - z^H) / (1 - z), real part.
            let (zr, zi) = (lambda * cos, lambda * sin);
            let (ar, ai) = (1.0 - lambda_h * cos_h, -lambda_h * sin_h);
            let (nr, ni) = (zr * ar - zi * ai, zr * ai + zi * ar);
            let (dr, di) = (1.0 - zr, -zi);
            let mut sum = 5.0 / 9.0 + 2.0 * (nr * dr + ni * di) / (dr * dr + di * di);
            if n.is_multiple_of(2) {
                sum += lambda.powf((n / 2) as f64) * if l % 2 == 0 { 1.0 } else { -1.0 };
            }
            sum / n as f64
        })
        .collect()
}

/// Subdivides a triangle mesh `levels` times with ternary (1-to-9) Loop.
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::mband::{TernaryOptions, ternary_subdivide};
///
/// let mesh = HalfedgeMesh::from_soup(&shapes::icosahedron())?;
/// let fine = ternary_subdivide(&mesh, 1, &TernaryOptions::default())?;
/// // V' = V + 2E + F, F' = 9F.
/// assert_eq!((fine.vertex_count(), fine.face_count()), (12 + 60 + 20, 180));
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// [`LoopError::InvalidParameter`] for `lambda` outside `(1/9, 1/2]` or more than
/// [`MAX_LEVELS`] levels; the mesh errors of [`subdivide`] (non-triangles, pillows,
/// non-finite positions, [`LoopError::Overflow`]); [`mesh_topo::MeshError::TooLarge`] if
/// a level would have more vertices or face corners than `u32` handles address, and
/// [`mesh_topo::MeshError::OutOfMemory`] if the output would not fit in the memory the
/// system has available, both found from the counts before any level is built.
pub fn ternary_subdivide(mesh: &HalfedgeMesh, levels: u32, options: &TernaryOptions) -> Result<LoopMesh, LoopError> {
    let largest = check_finite_largest(mesh.positions())?;
    let (positions, triangles) = ternary_levels(mesh, mesh.positions(), levels, options)?;
    check_no_overflow(&positions, largest)?;
    Ok(LoopMesh { positions, triangles })
}

/// Refines any per-vertex attribute with the ternary stencils.
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::mband::{TernaryOptions, ternary_refine_attribute, ternary_subdivide};
///
/// let mesh = HalfedgeMesh::from_soup(&shapes::octahedron())?;
/// let options = TernaryOptions::default();
/// // Positions refined as an attribute are the subdivided positions.
/// let fine = ternary_subdivide(&mesh, 1, &options)?;
/// assert_eq!(ternary_refine_attribute(&mesh, 1, &options, mesh.positions())?, fine.positions);
/// // Constant data stays constant: V' = V + 2E + F = 6 + 24 + 8 values.
/// let ones = ternary_refine_attribute(&mesh, 1, &options, &[1.0f64; 6])?;
/// assert_eq!(ones.len(), 38);
/// assert!(ones.iter().all(|v| (v - 1.0).abs() < 1e-15));
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// [`LoopError::AttributeCount`] if `values` does not have one entry per vertex,
/// [`LoopError::NonFiniteAttribute`] and [`LoopError::AttributeOverflow`] as for
/// [`refine_attribute`](crate::forward::refine_attribute); the errors of
/// [`ternary_subdivide`].
pub fn ternary_refine_attribute<T: Attribute>(
    mesh: &HalfedgeMesh,
    levels: u32,
    options: &TernaryOptions,
    values: &[T],
) -> Result<Vec<T>, LoopError> {
    if values.len() != mesh.vertex_count() {
        return Err(LoopError::AttributeCount { expected: mesh.vertex_count(), found: values.len() });
    }
    check_finite_values(values)?;
    checked_refined(ternary_levels(mesh, values, levels, options)?.0)
}

/// The sparse matrix of `levels` ternary steps (rows: fine vertices).
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::mband::{TERNARY_ALPHA, TernaryOptions, ternary_matrix, ternary_subdivide};
///
/// let mesh = HalfedgeMesh::from_soup(&shapes::icosahedron())?;
/// let options = TernaryOptions::default();
/// let s = ternary_matrix(&mesh, 1, &options)?;
/// assert_eq!((s.rows(), s.columns()), (12 + 2 * 30 + 20, 12));
/// assert!(s.row_sums().iter().all(|sum| (sum - 1.0).abs() < 1e-14));
/// assert!((s.get(0, 0) - TERNARY_ALPHA).abs() < 1e-15); // the vertex weight 5/9
/// let fine = ternary_subdivide(&mesh, 1, &options)?;
/// let applied = s.apply(mesh.positions())?;
/// assert!(applied.iter().zip(&fine.positions).all(|(a, b)| a.distance(*b) < 1e-14));
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// As [`ternary_subdivide`].
pub fn ternary_matrix(
    mesh: &HalfedgeMesh,
    levels: u32,
    options: &TernaryOptions,
) -> Result<SubdivisionMatrix, LoopError> {
    let units: Vec<SparseRow> = (0..mesh.vertex_count() as u32).map(SparseRow::unit).collect();
    let rows = ternary_refine_attribute(mesh, levels, options, &units)?;
    Ok(SubdivisionMatrix::from_rows(rows, mesh.vertex_count()))
}

/// Subdivides a triangle mesh `levels` times with quaternary (1-to-16) Loop: two Loop
/// steps per level (see the [module docs](self)).
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::forward::LoopOptions;
/// use subdiv_loop::mband::quaternary_subdivide;
///
/// let mesh = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
/// let fine = quaternary_subdivide(&mesh, 1, &LoopOptions::default())?;
/// // V' = V + 3E + 3F, F' = 16F.
/// assert_eq!((fine.vertex_count(), fine.face_count()), (4 + 18 + 12, 64));
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// As [`subdivide`]; [`LoopError::InvalidParameter`] for more than
/// [`MAX_LEVELS`]` / 2` levels.
pub fn quaternary_subdivide(mesh: &HalfedgeMesh, levels: u32, options: &LoopOptions) -> Result<LoopMesh, LoopError> {
    // Two Loop steps per level, so half as many levels as Loop's limit. Beyond it the
    // errors of the steps come first (a mesh with a face is too large after 8 levels),
    // then the limit, named in quaternary levels.
    match subdivide(mesh, 2 * levels.min(MAX_LEVELS / 2 + 1), options) {
        Err(LoopError::InvalidParameter { name: "levels", .. }) => Err(too_many_levels(levels, MAX_LEVELS / 2)),
        result => result,
    }
}

/// Runs `levels` ternary steps (building the half-edge mesh of each intermediate level).
pub(crate) fn ternary_levels<T: Attribute>(
    mesh: &HalfedgeMesh,
    values: &[T],
    levels: u32,
    options: &TernaryOptions,
) -> Result<(Vec<T>, Vec<[u32; 3]>), LoopError> {
    options.validate()?;
    Topology::from_mesh(mesh)?; // triangles only, no pillows
    let (vertices, faces) = check_ternary_sizes(mesh, levels)?;
    crate::forward::check_output_memory(vertices as u64, faces as u64, size_of::<T>(), 0)?;
    let mut triangles: Vec<[u32; 3]> = mesh.faces().map(|f| face_corners(mesh, f)).collect();
    if levels == 0 {
        return Ok((values.to_vec(), triangles));
    }
    let mut weights = BTreeMap::new();
    let (mut current, tri) = ternary_step(mesh, values, options.lambda, &mut weights);
    triangles = tri;
    for _ in 1..levels {
        let soup = mesh_topo::PolygonSoup::from_faces(vec![DVec3::ZERO; current.len()], &triangles);
        let level_mesh = HalfedgeMesh::from_soup(&soup)?;
        let (next, tri) = ternary_step(&level_mesh, &current, options.lambda, &mut weights);
        current = next;
        triangles = tri;
    }
    Ok((current, triangles))
}

/// Every level of `levels` ternary steps must be a mesh that `u32` handles address (as
/// [`HalfedgeMesh::from_soup`] requires of each level built on the way): checked from the
/// counts before any work, so that too many levels fail at once, not after filling the
/// memory. A step makes `V + 2E + F` vertices (two per edge, one per face), `3E + 9F`
/// edges and `9F` faces, boundary or not.
fn check_ternary_sizes(mesh: &HalfedgeMesh, levels: u32) -> Result<(usize, usize), LoopError> {
    let mut counts = [mesh.vertex_count(), mesh.edge_count(), mesh.face_count()].map(|n| n as u64);
    let as_usize = |n: u64| usize::try_from(n).unwrap_or(usize::MAX);
    // A mesh with a face fails by level 11; then the level limit.
    for _ in 0..levels.min(MAX_LEVELS + 1) {
        counts = counts_after_step(3, counts);
        mesh_topo::check_capacity(as_usize(counts[0]), as_usize(counts[2]).saturating_mul(3))?;
    }
    check_level_limit(levels).map(|()| (as_usize(counts[0]), as_usize(counts[2])))
}

fn face_corners(mesh: &HalfedgeMesh, f: mesh_topo::FaceId) -> [u32; 3] {
    let mut corners = [0u32; 3];
    for (k, v) in mesh.face_vertices(f).take(3).enumerate() {
        corners[k] = v.raw();
    }
    corners
}

/// Weighted sum of values at vertex indices.
fn combine<T: Attribute>(values: &[T], terms: &[(u32, f64)]) -> T {
    let mut out = values[terms[0].0 as usize].scaled(terms[0].1);
    for &(i, w) in &terms[1..] {
        out.add_scaled(&values[i as usize], w);
    }
    out
}

/// One ternary step on a validated triangle mesh.
fn ternary_step<T: Attribute>(
    mesh: &HalfedgeMesh,
    values: &[T],
    lambda: f64,
    weights: &mut BTreeMap<usize, Vec<f64>>,
) -> (Vec<T>, Vec<[u32; 3]>) {
    let (nv, ne) = (mesh.vertex_count(), mesh.edge_count());
    let mut out: Vec<Option<T>> = vec![None; nv + 2 * ne + mesh.face_count()];
    // Slot of the 1/3-point at the origin of half-edge h.
    let near_slot = |h: HalfedgeId| nv + 2 * h.edge().index() + usize::from(h.edge().halfedge(0) != h);
    for v in mesh.vertices() {
        let p = v.raw();
        if mesh.is_isolated(v) {
            out[v.index()] = Some(values[v.index()].clone());
            continue;
        }
        let outgoing: Vec<HalfedgeId> = mesh.outgoing_halfedges(v).collect();
        let ring: Vec<u32> = outgoing.iter().map(|&h| mesh.target(h).raw()).collect();
        let n = ring.len();
        if mesh.is_boundary_vertex(v) {
            // Circulation order: v_k (last fan vertex), v_0, v_1, ..., v_{k-1}.
            let (last, first) = (ring[0], ring[1]);
            out[v.index()] = Some(combine(values, &[(p, 19.0 / 27.0), (first, 4.0 / 27.0), (last, 4.0 / 27.0)]));
            for (j, &h) in outgoing.iter().enumerate() {
                let q = ring[j];
                let terms = if j == 0 {
                    vec![(p, 16.0 / 27.0), (q, 10.0 / 27.0), (first, 1.0 / 27.0)]
                } else if j == 1 {
                    vec![(p, 16.0 / 27.0), (q, 10.0 / 27.0), (last, 1.0 / 27.0)]
                } else {
                    let (before, after) = (ring[j - 1], ring[(j + 1) % n]);
                    vec![(p, 36.0 / 76.0), (q, 20.0 / 76.0), (before, 10.0 / 76.0), (after, 10.0 / 76.0)]
                };
                out[near_slot(h)] = Some(combine(values, &terms));
            }
            continue;
        }
        let mut vertex = vec![(p, TERNARY_ALPHA)];
        vertex.extend(ring.iter().map(|&q| (q, (1.0 - TERNARY_ALPHA) / n as f64)));
        out[v.index()] = Some(combine(values, &vertex));
        let gamma = weights.entry(n).or_insert_with(|| edge_weights(n, lambda));
        for (j, &h) in outgoing.iter().enumerate() {
            let mut terms = vec![(p, 4.0 / 9.0)];
            terms.extend((0..n).map(|l| (ring[(j + l) % n], gamma[l])));
            out[near_slot(h)] = Some(combine(values, &terms));
        }
    }
    let mut triangles = Vec::with_capacity(9 * mesh.face_count());
    for f in mesh.faces() {
        let c = face_corners(mesh, f);
        let halfedges: Vec<HalfedgeId> = mesh.face_halfedges(f).collect();
        let centre = (nv + 2 * ne + f.index()) as u32;
        let mut terms: Vec<(u32, f64)> = c.iter().map(|&v| (v, 8.0 / 27.0)).collect();
        for (k, &h) in halfedges.iter().enumerate() {
            let twin = h.twin();
            if mesh.is_boundary_halfedge(twin) {
                // Reflected corner a + b - c across the boundary edge.
                terms.extend([(c[k], 1.0 / 27.0), (c[(k + 1) % 3], 1.0 / 27.0), (c[(k + 2) % 3], -1.0 / 27.0)]);
            } else {
                terms.push((mesh.target(mesh.next(twin)).raw(), 1.0 / 27.0));
            }
        }
        out[centre as usize] = Some(combine(values, &terms));
        let (mut near, mut far) = ([0u32; 3], [0u32; 3]);
        for (k, &h) in halfedges.iter().enumerate() {
            near[k] = near_slot(h) as u32;
            far[k] = near_slot(h.twin()) as u32;
        }
        for k in 0..3 {
            triangles.push([c[k], near[k], far[(k + 2) % 3]]);
        }
        for k in 0..3 {
            triangles.push([near[k], far[k], centre]);
        }
        for k in 0..3 {
            triangles.push([far[(k + 2) % 3], near[k], centre]);
        }
    }
    let values = out.into_iter().map(|v| v.expect("internal: every ternary point is computed")).collect();
    (values, triangles)
}

#[cfg(test)]
mod tests;
