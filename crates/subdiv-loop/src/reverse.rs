//! Reverse Loop subdivision with detail vectors: exact decomposition of a mesh with Loop
//! connectivity into its coarse mesh plus one detail per edge point, and exact
//! reconstruction (ALGORITHMS.md §7; seed paper: Le Thi Thu Nga, Nguyen Tan Khoi,
//! Nguyen Thanh Thuy, reverse Loop subdivision).
//!
//! # The exact local inverse
//! Loop's vertex rule maps a coarse vertex `p` of valence `l` with neighbours `q_j` to
//! `p' = α p + β Σ q_j` (`α = 1 − lβ`), and each incident edge to
//! `e'_j = 3/8 (p + q_j) + 1/8 (q_{j−1} + q_{j+1})`. Summing the edge points,
//! `Σ e'_j = 3l/8 p + 5/8 Σ q_j`; eliminating `Σ q_j` from the vertex rule gives
//!
//! `p = μ p' + η Σ e'_j`, with `μ = 5 / (8α − 3)` and `η = −8β / (8α − 3) = (α − 1) / (l (α − 3/8))`.
//!
//! These are exactly the weights published by the seed paper, so there is no separate
//! "published" variant: `μ + lη = 1` (affine), and the inverse exists whenever
//! `α ≠ 3/8` (always, for both weight choices; see [`inverse_weights`]). On the
//! boundary (Hoppe et al. rules `p' = 3/4 p + 1/8 (q_− + q_+)`, `e'_± = (p + q_±)/2`)
//! the inverse is `p = 2p' − (e'_− + e'_+)/2`; a fixed corner has `p = p'`.
//!
//! # Details and storage
//! The coarse positions come from the vertex points and their ring of edge points only.
//! Each edge point then stores its *detail* `D_e = F_e − EdgeRule(P)_e`, the difference
//! between the fine position and what Loop's edge rule predicts from the coarse mesh.
//! Reconstruction computes `F_e = EdgeRule(P)_e + D_e` and recovers each vertex point by
//! solving the inverse relation for `p'`. The coarse mesh plus the details hold
//! `|V_c| + |E_c| = |V_f|` vectors: exactly as many as the fine mesh. When the fine mesh
//! was made by Loop subdivision with the same [`LoopOptions`], every detail is zero (up to
//! rounding), and reconstruction with zero details *is* Loop subdivision.
//!
//! This works on any mesh with Loop connectivity, not only on meshes made by Loop
//! subdivision: [`reconstruct`]`(`[`reverse`]`(M)) = M` up to rounding (measured:
//! below 1e-15 of the bounding-box diagonal on perturbed, renumbered meshes).
//!
//! # Decisions where the specification leaves room
//! - The seed paper's `μ, η` are the exact inverse (above), so there is one reversal,
//!   not an "exact" and a "published" one. Noise is amplified by `|μ| + l|η|` (19 at
//!   valence 3, 4 at valence 6): a reversed mesh of noisy data can "puff out", but the
//!   details restore it exactly.
//! - Isolated vertices are vertex points of isolated coarse vertices and are copied, so
//!   that reversal loses nothing and `reverse(subdivide(C)) = C` holds for every `C`.
//! - An interior vertex of valence 2 (two triangles glued along all edges) is legal in a
//!   manifold mesh and uses the same formulas (`8α − 3 = 1/8` there, still invertible).
//! - The reversal must use the rules of the forward step ([`LoopOptions`]): with other
//!   weights the coarse mesh differs and the details are not zero, but reconstruction
//!   with the same options is still exact.

use std::borrow::Cow;
use std::cell::OnceCell;

use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use mesh_topo::{HalfedgeMesh, MeshError, PolygonSoup};

use crate::LoopError;
use crate::corner_table::{Corner, CornerTable, MeshCorners, NONE, VertexStar, next, prev};
use crate::detect::{
    CanonicalGroups, Coarsening, FineOrder, PairedEdge, Renumbering, Valences, canonical_groups, detect_mesh,
    detect_table, renumber_to_canonical, reverse_canonical_mesh, reverse_canonical_table,
};
use crate::forward::buffer::{Output, Slots, prefetch, worth_prefetching};
use crate::forward::kernel::{self, Rules, loop_beta, warren_beta};
use crate::forward::topology::{BASE_MASK, MAX_FACES, Topology};
use crate::forward::{LoopOptions, VertexWeights};

mod lattice;

/// `β_n` of the forward step's interior vertex rule (the very same numbers).
fn beta(weights: VertexWeights, valence: usize) -> f64 {
    match weights {
        VertexWeights::Loop => loop_beta(valence),
        VertexWeights::Warren => warren_beta(valence),
    }
}

/// `(μ, η)` of the exact inverse of the interior vertex rule at valence `l`:
/// `p = μ p' + η Σ e'_j`.
///
/// Valence 0 (an isolated vertex, which the forward step copies) gives `(1, 0)`, the
/// copy back: the formula would divide by zero there. Every other valence has finite
/// weights with `μ + lη = 1` (valences 1 and 2 included, though only 2 occurs in a
/// manifold mesh), so no error is needed.
///
/// ```
/// use subdiv_loop::forward::VertexWeights;
/// use subdiv_loop::reverse::inverse_weights;
/// let (mu, eta) = inverse_weights(VertexWeights::Loop, 6);
/// assert!((mu - 2.5).abs() < 1e-15 && (eta + 0.25).abs() < 1e-15);
/// let (mu, eta) = inverse_weights(VertexWeights::Loop, 3);
/// assert!((mu - 10.0).abs() < 1e-12 && (eta + 3.0).abs() < 1e-12);
/// assert_eq!(inverse_weights(VertexWeights::Warren, 0), (1.0, 0.0));
/// ```
pub fn inverse_weights(weights: VertexWeights, valence: usize) -> (f64, f64) {
    if valence == 0 {
        return (1.0, 0.0);
    }
    let beta = beta(weights, valence);
    let alpha = 1.0 - valence as f64 * beta;
    let denominator = 8.0 * alpha - 3.0;
    (5.0 / denominator, -8.0 * beta / denominator)
}

/// One reversed level: the coarse mesh, the details of the edge points, and the fine
/// numbering.
#[derive(Debug, Clone, PartialEq)]
pub struct ReversedLevel {
    /// The coarse mesh (vertex order: the vertex points in fine order; see
    /// [`detect`](crate::detect) for the face order).
    pub coarse: HalfedgeMesh,
    /// One detail vector per coarse edge, in the coarse mesh's edge order.
    pub details: Vec<DVec3>,
    /// How the fine mesh is numbered, `None` for the canonical order.
    pub order: Option<FineOrder>,
}

/// Options of [`reverse`].
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct ReverseOptions {
    /// The rules of the forward subdivision.
    pub rules: LoopOptions,
    /// Vertices known to be vertex points, typically one per component (see
    /// [`DetectOptions::seed_vertices`](crate::detect::DetectOptions::seed_vertices)).
    pub seed_vertices: Vec<u32>,
}

/// Reverses one level of Loop subdivision: detects the Loop connectivity of `fine`,
/// computes the coarse positions by the exact inverse (see the [module docs](self)) and
/// the detail of every edge point.
///
/// A component without a seed vertex whose valences are all regular (6 inside, 4 on the
/// boundary), which reads several ways, gets the reading with the smallest sum of squared
/// details among those detection would try, each component its own; so a refined torus
/// gives its coarse torus back in any numbering. (A mesh in the canonical order, as Loop
/// subdivision writes it, keeps the reading of that order unless every valence in it is
/// regular.) That choice is invariant under similarities, not under every affine map; a
/// seed fixes the reading.
///
/// ```
/// use glam::DVec3;
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::forward::LoopOptions;
/// use subdiv_loop::reverse::{ReverseOptions, reconstruct, reverse};
///
/// // Refine an octahedron with zero details (= one Loop step), then reverse it.
/// let coarse = HalfedgeMesh::from_soup(&shapes::octahedron())?;
/// let zeros = vec![DVec3::ZERO; coarse.edge_count()];
/// let fine = reconstruct(&coarse, &zeros, None, &LoopOptions::default())?;
/// assert_eq!(fine.vertex_count(), 6 + 12);
///
/// let level = reverse(&fine, &ReverseOptions::default())?;
/// assert_eq!(level.coarse.to_soup().indices, coarse.to_soup().indices);
/// for (p, q) in level.coarse.positions().iter().zip(coarse.positions()) {
///     assert!(p.distance(*q) < 1e-14);
/// }
/// assert!(level.details.iter().all(|d| d.length() < 1e-14));
/// assert!(level.order.is_none());
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// [`LoopError::Mesh`] for a non-finite position, and [`LoopError::NotTriangle`],
/// [`LoopError::SeedOutOfRange`], [`LoopError::SeedConflict`] and
/// [`LoopError::NotLoopConnectivity`] from detection; [`LoopError::Overflow`] for
/// finite coordinates so large (near `f64::MAX`) that the coarse positions or details
/// are not.
///
/// Coordinates beyond `2^±256` are reversed at unit scale, as a copy scaled by an exact
/// power of two, and the result scaled back (see [`mesh_topo::scale`]): the same
/// result as the mesh as given, without squares (of the automatic choice) or partial
/// sums that overflow or underflow.
pub fn reverse(fine: &HalfedgeMesh, options: &ReverseOptions) -> Result<ReversedLevel, LoopError> {
    // Coordinates far from 1: reversed at unit scale (see `mesh_topo::scale`), so that no
    // partial sum overflows where the result fits. Errors, and results beyond `f64`,
    // are left to the mesh as given, which reports them as before.
    let scale = mesh_topo::scale::unit_scale(fine.positions());
    if scale != 1.0 {
        let mut scaled = fine.clone();
        mesh_topo::scale::rescale(scaled.positions_mut(), scale);
        if let Ok(mut level) = reverse_as_given(&scaled, options)
            && mesh_topo::scale::rescale(level.coarse.positions_mut(), 1.0 / scale)
            && mesh_topo::scale::rescale(&mut level.details, 1.0 / scale)
        {
            return Ok(level);
        }
    }
    reverse_as_given(fine, options)
}

/// [`reverse`] without the change of scale.
fn reverse_as_given(fine: &HalfedgeMesh, options: &ReverseOptions) -> Result<ReversedLevel, LoopError> {
    let LevelParts { coarse, order, positions, details, .. } =
        reverse_level(FineLevel::Mesh(fine), fine.positions(), &options.seed_vertices, &options.rules)?;
    let coarse = HalfedgeMesh::from_soup(&coarse.into_soup(positions))
        .expect("internal: a detected coarse mesh is a valid mesh");
    Ok(ReversedLevel { coarse, details, order })
}

/// Rebuilds the fine mesh from a coarse mesh, one detail per coarse edge (in edge order)
/// and the fine numbering (`None`: canonical). With all details zero this is one step of
/// Loop subdivision in the canonical order.
///
/// ```
/// use glam::DVec3;
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::forward::{LoopOptions, subdivide};
/// use subdiv_loop::reverse::{ReverseOptions, reconstruct, reverse};
///
/// let coarse = HalfedgeMesh::from_soup(&shapes::icosahedron())?;
/// let options = LoopOptions::default();
/// let smooth = subdivide(&coarse, 1, &options)?;
/// let mut details = vec![DVec3::ZERO; coarse.edge_count()];
/// assert_eq!(reconstruct(&coarse, &details, None, &options)?.to_soup(), smooth.to_soup());
/// // A detail moves the edge point of its edge (fine vertex 12 + e) by exactly that much,
/// // and reversal gives it back.
/// details[7] = DVec3::new(0.1, -0.2, 0.3);
/// let fine = reconstruct(&coarse, &details, None, &options)?;
/// assert!(fine.positions()[12 + 7].distance(smooth.positions[12 + 7] + details[7]) < 1e-15);
/// let level = reverse(&fine, &ReverseOptions::default())?;
/// assert!(level.details.iter().zip(&details).all(|(a, b)| a.distance(*b) < 1e-14));
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// [`LoopError::NotTriangle`] for a non-triangle face, [`LoopError::InvalidDetails`] if
/// the number of details or the order does not fit the mesh or a detail is not finite,
/// [`LoopError::NonFiniteResult`] if a position overflows.
pub fn reconstruct(
    coarse: &HalfedgeMesh,
    details: &[DVec3],
    order: Option<&FineOrder>,
    rules: &LoopOptions,
) -> Result<HalfedgeMesh, LoopError> {
    let soup = reconstruct_levels(coarse, std::iter::once((details, order)), rules)?;
    Ok(HalfedgeMesh::from_soup(&soup).expect("internal: a refined mesh is valid"))
}

/// Rebuilds the mesh after several refinement steps (each: details and order) from a
/// coarse mesh.
///
/// A canonical step is one Loop step by the forward module's kernel (index-arithmetic
/// refinement) plus the details: `D_e` added to edge point `e`, and to each vertex
/// point the change the inverse relation implies, `8β/5 Σ_j D_{e_j}` inside (since
/// `η/μ = −8β/5`), `(D_− + D_+)/4` on the boundary, nothing at a fixed corner. A step
/// with an order goes through the corner table and is renumbered.
pub(crate) fn reconstruct_levels<'a>(
    coarse: &HalfedgeMesh,
    levels: impl ExactSizeIterator<Item = (&'a [DVec3], Option<&'a FineOrder>)>,
    rules: &LoopOptions,
) -> Result<PolygonSoup, LoopError> {
    let levels: Vec<_> = levels.collect();
    // Values far from 1: rebuilt at unit scale (see `reverse`), so that no partial sum
    // overflows where the result fits; errors and results beyond `f64` are left to the
    // values as given.
    let details = levels.iter().flat_map(|&(details, _)| details);
    let scale = mesh_topo::scale::unit_scale(coarse.positions().iter().chain(details));
    if scale != 1.0 {
        let mut scaled = coarse.clone();
        mesh_topo::scale::rescale(scaled.positions_mut(), scale);
        let details: Vec<Vec<DVec3>> =
            levels.iter().map(|&(details, _)| details.iter().map(|d| *d * scale).collect()).collect();
        let steps = details.iter().zip(&levels).map(|(details, &(_, order))| (&details[..], order));
        if let Ok(mut soup) = reconstruct_levels_as_given(&scaled, steps, rules)
            && mesh_topo::scale::rescale(&mut soup.positions, 1.0 / scale)
        {
            return Ok(soup);
        }
    }
    reconstruct_levels_as_given(coarse, levels.into_iter(), rules)
}

/// [`reconstruct_levels`] without the change of scale.
fn reconstruct_levels_as_given<'a>(
    coarse: &HalfedgeMesh,
    levels: impl ExactSizeIterator<Item = (&'a [DVec3], Option<&'a FineOrder>)>,
    rules: &LoopOptions,
) -> Result<PolygonSoup, LoopError> {
    crate::pyramid::check_input_positions(coarse.positions())?;
    let mut topology = Topology::from_mesh(coarse)?;
    // The base positions are read in place (copied only when no step follows).
    let mut positions = Cow::Borrowed(coarse.positions());
    let kernel_rules = Rules::new(rules);
    let levels: Vec<_> = levels.collect();
    let count = levels.len();
    // When every level fits the counts, the details are not read for finiteness before
    // the steps: a non-finite detail makes the result non-finite (every fine value has
    // a non-zero weight on it), and the check below then names the first one, so the
    // errors are the same as checking each level first.
    let fit = levels_fit(&topology, &levels);
    // True when the last step found every position finite (the input was checked).
    let mut known_finite = true;
    for (i, &(details, order)) in levels.iter().enumerate() {
        let level = i + 1;
        if !fit {
            check_details(topology.vertex_count, topology.edge_count, topology.face_count(), details, order, level)?;
        }
        if topology.face_count() as u64 > MAX_FACES || topology.edge_count > BASE_MASK as usize {
            return Err(LoopError::Mesh(MeshError::TooLarge {
                what: "faces",
                count: topology.face_count(),
                max: MAX_FACES as usize,
            }));
        }
        match order {
            None => {
                // The kernel adds the details to the values as it makes them; only the
                // last step's values are tested for finiteness (a non-finite value
                // carries over to every later level).
                let last = level == count;
                let additions = kernel::Details::new(details, last);
                let step = kernel::step_with_details(&topology, &positions, &kernel_rules, !last, &additions);
                known_finite = !last || additions.all_finite();
                positions = Cow::Owned(step.values);
                topology = step.topology;
            }
            Some(order) => {
                let table = CornerTable::from_topology(&topology);
                let (fine_table, fine_positions) = refine_level(&table, &positions, details, Some(order), rules);
                topology = fine_table.to_topology();
                positions = Cow::Owned(fine_positions);
                known_finite = false;
            }
        }
    }
    if !known_finite {
        if fit {
            for (i, &(details, _)) in levels.iter().enumerate() {
                check_details_finite(details, i + 1)?;
            }
        }
        // Also names the first non-finite vertex.
        check_finite(&positions, count)?;
    }
    // The triangles' memory becomes the indices (no copy); the offsets are filled in
    // parallel, as for the forward subdivision's soups.
    Ok(PolygonSoup {
        positions: positions.into_owned(),
        offsets: crate::forward::triangle_offsets(topology.triangles.len()),
        indices: topology.triangles.into_flattened(),
    })
}

/// Checks that `details` and `order` fit the coarse table (level numbers errors).
pub(crate) fn check_level(
    table: &CornerTable,
    details: &[DVec3],
    order: Option<&FineOrder>,
    level: usize,
) -> Result<(), LoopError> {
    check_details(table.vertex_count(), table.edge_count(), table.face_count(), details, order, level)
}

/// Checks details and order against the counts of the coarse mesh.
fn check_details(
    vertices: usize,
    edges: usize,
    faces: usize,
    details: &[DVec3],
    order: Option<&FineOrder>,
    level: usize,
) -> Result<(), LoopError> {
    if details.len() != edges {
        return Err(LoopError::InvalidDetails {
            level,
            reason: format!("{} details for a mesh with {edges} edges", details.len()),
        });
    }
    check_details_finite(details, level)?;
    if let Some(order) = order {
        order.check(vertices + edges, 4 * faces).map_err(|reason| LoopError::InvalidDetails { level, reason })?;
    }
    Ok(())
}

/// The finiteness part of [`check_details`].
fn check_details_finite(details: &[DVec3], level: usize) -> Result<(), LoopError> {
    if !crate::pyramid::all_finite(details)
        && let Some(i) = details.iter().position(|d| !d.is_finite())
    {
        return Err(LoopError::InvalidDetails { level, reason: format!("detail {i} is not finite") });
    }
    Ok(())
}

/// True if [`check_details`] (but for the finiteness of the details) and the size
/// check of [`reconstruct_levels`] pass at every level, from the counts alone: a step
/// makes `V + E` vertices, `2E + 3F` edges and `4F` faces of `V, E, F`.
fn levels_fit(topology: &Topology, levels: &[(&[DVec3], Option<&FineOrder>)]) -> bool {
    let (mut v, mut e, mut f) = (topology.vertex_count, topology.edge_count, topology.face_count());
    for &(details, order) in levels {
        if details.len() != e || f as u64 > MAX_FACES || e > BASE_MASK as usize {
            return false;
        }
        if let Some(order) = order
            && order.check(v + e, 4 * f).is_err()
        {
            return false;
        }
        (v, e, f) = (v + e, 2 * e + 3 * f, 4 * f);
    }
    true
}

pub(crate) fn check_finite(positions: &[DVec3], level: usize) -> Result<(), LoopError> {
    match positions.iter().position(|p| !p.is_finite()) {
        Some(vertex) => Err(LoopError::NonFiniteResult { level, vertex }),
        None => Ok(()),
    }
}

/// Below this many elements the loops run sequentially (rayon's overhead dominates).
const PARALLEL_THRESHOLD: usize = 1 << 14;

/// The star of coarse vertex `v` and the sum of the positions of the edge points of its
/// edges.
#[inline]
fn edge_point_star(coarse: &CornerTable, v: u32, edge_position: impl Fn(u32) -> DVec3) -> (VertexStar, DVec3) {
    let mut sum = DVec3::ZERO;
    let star = coarse.visit_star(v, |e, _| sum += edge_position(e));
    (star, sum)
}

/// Loop's edge rule on the coarse positions.
#[inline]
fn edge_rule(coarse: &CornerTable, positions: &[DVec3], e: u32) -> DVec3 {
    let c = coarse.edge_corner(e);
    let a = positions[coarse.vertex(c) as usize];
    let b = positions[coarse.vertex(next(c)) as usize];
    let t = coarse.twin(c);
    if t == NONE {
        0.5 * (a + b)
    } else {
        let r = positions[coarse.vertex(prev(c)) as usize];
        let s = positions[coarse.vertex(prev(t)) as usize];
        interior_edge_point(a, b, r, s)
    }
}

/// Loop's edge rule inside the mesh: the edge point of the edge from `a` to `b`, whose
/// two faces have their third vertices at `r` and `s`.
#[inline(always)]
fn interior_edge_point(a: DVec3, b: DVec3, r: DVec3, s: DVec3) -> DVec3 {
    0.375 * (a + b) + 0.125 * (r + s)
}

/// Maps `f` over `0..n`, in parallel for large `n` (see [`kernel::map_indices`]).
fn map_indices<T: Send>(n: usize, f: impl Fn(u32) -> T + Sync + Send) -> Vec<T> {
    kernel::map_indices(n, PARALLEL_THRESHOLD, f)
}

/// Coarse positions and details of a detected level.
pub(crate) fn reverse_positions(
    coarsening: &Coarsening,
    fine: &[DVec3],
    rules: &LoopOptions,
) -> (Vec<DVec3>, Vec<DVec3>) {
    const BOUNDARY: u32 = 1 << 31;
    let coarse = &coarsening.coarse;
    let nv = coarse.vertex_count();
    let edge_position = |e: u32| fine[coarsening.edge_point[e as usize] as usize];
    // The edge points around every coarse vertex, summed in one pass over the edges,
    // with the valence and boundary flag: one sum per vertex, of all its edge points
    // inside, of the boundary ones only on the boundary (restarted at the first
    // boundary edge).
    let mut sum = vec![DVec3::ZERO; nv];
    let mut valence = vec![0u32; nv];
    for e in 0..coarse.edge_count() as u32 {
        let c = coarse.edge_corner(e);
        let on_boundary = coarse.twin(c) == NONE;
        let point = edge_position(e);
        for v in [coarse.vertex(c), coarse.vertex(next(c))] {
            let v = v as usize;
            let seen_boundary = valence[v] & BOUNDARY != 0;
            valence[v] += 1;
            if on_boundary {
                if !seen_boundary {
                    sum[v] = DVec3::ZERO;
                    valence[v] |= BOUNDARY;
                }
                sum[v] += point;
            } else if !seen_boundary {
                sum[v] += point;
            }
        }
    }
    let weights = InverseWeights::new(rules.weights);
    let positions = map_indices(nv, |v| {
        let vertex_point = fine[coarsening.vertex_point[v as usize] as usize];
        let (n, flags) = (valence[v as usize] & !BOUNDARY, valence[v as usize] & BOUNDARY);
        coarse_position(vertex_point, sum[v as usize], n, flags != 0, rules, &weights)
    });
    let details = map_indices(coarse.edge_count(), |e| edge_position(e) - edge_rule(coarse, &positions, e));
    (positions, details)
}

/// The fine mesh of one reversal: the user's mesh, or a coarse level of an earlier
/// reversal (whose positions were computed here, so they need no input check).
#[derive(Clone, Copy)]
pub(crate) enum FineLevel<'a> {
    Mesh(&'a HalfedgeMesh),
    Table(&'a CornerTable),
}

/// What one reversal makes.
pub(crate) struct LevelParts {
    pub(crate) coarse: CornerTable,
    /// `None` when the fine mesh is in the canonical order.
    pub(crate) order: Option<FineOrder>,
    pub(crate) positions: Vec<DVec3>,
    pub(crate) details: Vec<DVec3>,
    /// The fine mesh may have a component without a seed that reads several ways (see
    /// [`reverse_level`]); false when it is known to have none.
    pub(crate) several_readings: bool,
}

/// One level reversed (`reverse_level_from`); a component that reads several ways and
/// has no seed gets the reading with the smallest details.
///
/// Detection labels each component from a vertex of irregular valence (or a seed), which
/// fixes the reading. A component whose valences are all regular (6 inside, 4 on the
/// boundary: a refined torus, a refined open cylinder) has several readings, and
/// detection takes the first valid one from its lowest vertex, which depends on the
/// numbering. Here every seed detection would try in such a component (its lowest vertex
/// and that vertex's neighbours) is reversed too, and a reading is kept over the first
/// only if the component's sum of squared details is strictly smaller, so a mesh made by
/// Loop subdivision gets its own reading back (zero details) in any numbering. A
/// component whose best reading so far has zero details (at most `(1e-12 d)^2` per
/// vertex, `d` the diagonal of the component's bounding box: the round-off of an exact
/// refinement) is settled and no other seed is tried there: a mesh made by Loop
/// subdivision then costs one reversal in the canonical order (its own reading), and in
/// another order the readings up to the first exact one; where several readings are
/// exact the first is kept, not one picked by round-off. The
/// components are independent (a component's details depend on its own reading only):
/// the k-th candidate of every such component is tried in one reversal, and a candidate
/// that is a vertex point of a reading already found is passed over (its reading is that
/// one), so the choice costs three or four more reversals on a torus (up to seven on
/// other meshes) and one final one when a better reading is found, on such meshes only.
///
/// Which meshes those are costs nothing on the fast paths: the search of a mesh in
/// another order (`renumber_to_canonical`) starts from seeds and irregular vertices only,
/// so it fails on a component without either; the candidates are then read through that
/// search, with a seed in every such component, and the general detection runs only if
/// some component has no valid reading (to name the error). A mesh in the canonical
/// order (written by Loop subdivision or a reconstruction, its reading given by its
/// numbering) is compared only when all its valences are regular, the check stopping at
/// the first irregular vertex. So a canonical mesh of a torus beside a mesh with
/// irregular vertices keeps the torus's canonical reading, the one it was made with.
///
/// A closed mesh of valence 6 everywhere without seeds has the sums of squared details
/// of all four readings of every component computed from one reading's corners in one
/// pass ([`lattice`]): from the canonical reading (before any other is reversed), or
/// else from the first round's reading. Where one reading's sum is below 99% of every
/// other's in every component, the readings in turn would choose it (see
/// `lattice_choice`), and it is returned (reversed, if it is not the one at hand)
/// without them; closer cases are decided in turn as above, so the result is the same
/// either way (a test compares the two on moved tori, bit for bit). On a mesh of one
/// component the pass stops once the reading at hand is known to be clearly the best.
/// (Bench group `regular_torus`, one thread, a refined torus of 131 072 vertices, moved:
/// the forward step 2.16 ms; seeded 3.17 ms in the canonical order and 10.2 ms
/// renumbered; automatic 5.80 ms and 25.8 ms (40 ms and 63 ms, with a forward step of
/// 2.5 ms, when the readings were reversed in turn: three more readings, each through
/// the search, which reads the fine corners once for all of them). The torus refined
/// exactly, automatic: 3.47 ms in the canonical order, 20.5 ms renumbered: its first
/// exact reading settles it.)
pub(crate) fn reverse_level(
    fine: FineLevel<'_>,
    positions: &[DVec3],
    seeds: &[u32],
    rules: &LoopOptions,
) -> Result<LevelParts, LoopError> {
    // The fast paths' reading; `None` when the general detection would have to run, as
    // for a component without a seed or an irregular vertex (or an error).
    // The fine corners, read at most once: by the renumbering path, or below.
    let fine_corners = OnceCell::new();
    let first = match reverse_level_fast_reading(fine, &fine_corners, positions, seeds, rules)? {
        Some(level) if !level.several_readings => return Ok(level),
        first => first,
    };
    // (Energies and zero thresholds are squares: `reverse` and `decompose` hand this
    // function meshes far from 1 at unit scale, where they neither overflow nor
    // underflow.)
    // A canonical reading that settles the choice or is clearly the best needs none of
    // the fine connectivity that comparing readings needs.
    if let Some(level) = &first
        && level.order.is_none()
        && canonical_reading_stands(&level.coarse, &level.details, positions, seeds, rules)
    {
        return Ok(first.expect("checked above"));
    }
    // The fine corners, read once for the searches of the readings compared, give the
    // components and their candidates too (no table of edges is built for them).
    let fine_corners = fine_corners.get_or_init(|| FineCorners::of(fine));
    let readings = match (fine, fine_corners) {
        (FineLevel::Table(table), FineCorners::Table(corners)) => {
            let starts = table.vertex_corners();
            RegularReadings::of_corners(table.vertex_count(), corners, |v| starts[v as usize], seeds)
        }
        (FineLevel::Mesh(mesh), FineCorners::Mesh(Some(mesh_corners))) => {
            let start = |v| mesh_corners.corner_at(mesh, v);
            RegularReadings::of_corners(mesh.vertex_count(), &mesh_corners.corners, start, seeds)
        }
        // A face that is not a triangle: the general detection names it.
        _ => return reverse_level_general(fine, positions, seeds, rules),
    };
    if readings.candidates.is_empty() {
        return match first {
            Some(first) => Ok(first),
            None => reverse_level_general(fine, positions, seeds, rules),
        };
    }
    // Per component: the smallest energy so far, and the seed of its reading (`None`: the
    // first reading's, or none found yet). Without a first reading, the first candidate
    // that gives a valid reading sets it, as detection would pick it.
    let mut best: Vec<(f64, Option<u32>)> = match &first {
        Some(first) => readings.energies(first).into_iter().map(|energy| (energy, None)).collect(),
        None => vec![(f64::INFINITY, None); readings.energies_len()],
    };
    // A component whose best reading so far has zero details is an exact refinement in
    // that reading: no other can do better than round-off, so none is tried.
    let zero = readings.zero_energies(positions);
    // The vertex points of the readings found so far: the labeling from a vertex point is
    // forced, so a candidate that is one gives a reading already compared (on a torus,
    // the six neighbours of a vertex point give three readings, two each).
    // Each reading from its seeds, as `reverse_level_from` would give it, with the fine
    // corners read once. Its fused canonical attempt is left out, as it cannot succeed:
    // when it gave the first reading, every seed tried here is an edge point of it (its
    // vertex points are passed over, see `covered`), which the canonical order does not
    // allow; else it failed with the caller's seeds alone, and more seeds only add to
    // what it requires. The positions were checked by the first attempt.
    let reverse_reading = |all: &[u32]| {
        #[cfg(test)]
        MORE_READINGS.set(MORE_READINGS.get() + 1);
        match reverse_searched(fine, fine_corners, positions, all, rules) {
            Some(level) => Ok(level),
            None => reverse_level_general(fine, positions, all, rules),
        }
    };
    let mut covered = vec![false; readings.component.len()];
    if let Some(first) = &first {
        readings.cover(first, &mut covered);
    }
    // The last reading found that is every such component's best so far (then no final
    // reversal is needed).
    let mut best_level = None;
    let rounds = readings.candidates.iter().map(|(_, seeds)| seeds.len()).max().unwrap_or(0);
    for round in 0..rounds {
        let tried: Vec<(usize, u32)> = readings
            .candidates
            .iter()
            .filter_map(|(c, seeds)| seeds.get(round).map(|&s| (*c, s)))
            .filter(|&(c, seed)| !covered[seed as usize] && !settled(best[c].0, zero[c]))
            .collect();
        if tried.is_empty() {
            continue;
        }
        let with_seeds = |extra: &[(usize, u32)]| {
            let mut all = seeds.to_vec();
            all.extend(extra.iter().map(|&(_, s)| s));
            reverse_reading(&all)
        };
        // Whether a component's best changed.
        let mut take = |level: &LevelParts, tried: &[(usize, u32)], covered: &mut [bool]| {
            let energies = readings.energies(level);
            let mut changed = false;
            for &(c, seed) in tried {
                if energies[c] < best[c].0 {
                    best[c] = (energies[c], Some(seed));
                    changed = true;
                }
            }
            readings.cover(level, covered);
            changed
        };
        match with_seeds(&tried) {
            Ok(level) => {
                if take(&level, &tried, &mut covered) {
                    best_level = None;
                }
                let best_everywhere = readings
                    .candidates
                    .iter()
                    .all(|(c, _)| tried.iter().any(|&(tried_c, seed)| tried_c == *c && best[*c].1 == Some(seed)));
                if best_everywhere {
                    best_level = Some(level);
                }
            }
            // A seed without a valid reading of its component (detection passes it over):
            // each component of this round on its own.
            Err(_) => {
                for &one in &tried {
                    if let Ok(level) = with_seeds(&[one])
                        && take(&level, &[one], &mut covered)
                    {
                        best_level = None;
                    }
                }
            }
        }
        // No canonical reading and no seeds: from the first round's reading of every
        // component, the sums of [`lattice`] may name each component's reading clearly
        // the best, which the later rounds would choose (see `lattice_choice`).
        // (Where every component's reading is settled, the later rounds try nothing.)
        if round == 0
            && first.is_none()
            && seeds.is_empty()
            && tried.len() == readings.candidates.len()
            && !readings.candidates.iter().all(|&(c, _)| settled(best[c].0, zero[c]))
            && let Some(level) = &best_level
            && let Some(chosen) = lattice_choice(level, positions, &readings, rules)
        {
            if chosen.iter().zip(&tried).all(|(&seed, &(_, tried))| seed == tried) {
                return Ok(best_level.expect("checked above"));
            }
            // (A reversal that fails leaves the choice to the later rounds.)
            if let Ok(level) = reverse_reading(&chosen) {
                return Ok(level);
            }
        }
    }
    let chosen: Vec<Option<u32>> = readings.candidates.iter().map(|&(c, _)| best[c].1).collect();
    if let Some(level) = best_level {
        return Ok(level);
    }
    match first {
        Some(first) if chosen.iter().all(Option::is_none) => Ok(first),
        // A component without a valid reading: the general detection names the error.
        None if chosen.iter().any(Option::is_none) => reverse_level_general(fine, positions, seeds, rules),
        _ => {
            let mut all = seeds.to_vec();
            all.extend(chosen.into_iter().flatten());
            reverse_reading(&all)
        }
    }
}

/// The largest sum of squared details of `count` vertices that counts as zero at the
/// scale `diagonal` (a bounding-box diagonal): `(1e-12 diagonal)^2` per vertex, the
/// round-off of an exact Loop refinement (the zero test of the Doo-Sabin automatic
/// choice, per vertex here).
fn zero_energy(diagonal: f64, count: usize) -> f64 {
    (1e-12 * diagonal).powi(2) * count as f64
}

/// Whether a component of best energy `energy` is settled: its details are zero by
/// [`zero_energy`] `zero` (false when either is not a number).
fn settled(energy: f64, zero: f64) -> bool {
    energy <= zero
}

#[cfg(test)]
thread_local! {
    /// Tests: the number of readings [`reverse_level`] reversed beyond the first.
    static MORE_READINGS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
    /// Tests: whether [`reverse_level`] may keep the first reading of a closed regular
    /// mesh by the sums of [`lattice`] (else the readings are reversed in turn, as where
    /// those sums do not apply).
    static BY_LATTICE: std::cell::Cell<bool> = const { std::cell::Cell::new(true) };
}

/// The sum of squared details of a reading.
fn detail_energy(details: &[DVec3]) -> f64 {
    details.iter().map(|d| d.length_squared()).sum()
}

/// Whether the canonical reading of a fine mesh (`positions`, read with `seeds`), of
/// coarse mesh `coarse` and details `details`, is the one comparing the readings in turn
/// would keep, known without comparing them: it settles the choice
/// ([`reading_is_settled`]), or, without seeds, the sums of [`lattice`] find
/// it clearly the best in every component (a closed mesh of valence 6 everywhere).
pub(crate) fn canonical_reading_stands(
    coarse: &CornerTable,
    details: &[DVec3],
    positions: &[DVec3],
    seeds: &[u32],
    rules: &LoopOptions,
) -> bool {
    let energy = detail_energy(details);
    reading_is_settled(coarse, energy, positions)
        || (seeds.is_empty()
            && compares_by_lattice()
            && lattice::first_reading_is_clearly_best(coarse, positions, energy, rules))
}

/// The seeds (one per component of `readings`, in its order) that reversing the readings
/// of a closed mesh of valence 6 everywhere in turn would choose, from `level`, the
/// reading of the first candidate of every component, where the sums of [`lattice`]
/// name one reading clearly the best in each: the first candidate that is one of its
/// vertex points (the candidates before it are not, and none of them is passed over
/// as a vertex point of a reading found before: only a candidate of that reading could
/// be). `None` where the sums do not apply or some component has no clear best.
fn lattice_choice(
    level: &LevelParts,
    positions: &[DVec3],
    readings: &RegularReadings,
    rules: &LoopOptions,
) -> Option<Vec<u32>> {
    if !compares_by_lattice() {
        return None;
    }
    let first_energy = detail_energy(&level.details);
    let sums =
        match lattice::Readings::judged(&level.coarse, &in_canonical_order(level, positions), first_energy, rules)? {
            // One component, clearly best in the reading at hand: its first candidate's.
            lattice::Judged::FirstClearlyBest => {
                return readings.candidates.iter().map(|(_, candidates)| candidates.first().copied()).collect();
            }
            lattice::Judged::Summed(sums) => sums,
        };
    // The canonical number of every fine vertex.
    let numbers = level.order.as_ref().map(|order| {
        let mut number = vec![0u32; positions.len()];
        for (canonical, &v) in order.vertex_of_canonical.iter().enumerate() {
            number[v as usize] = canonical as u32;
        }
        number
    });
    let canonical = |v: u32| numbers.as_ref().map_or(v, |number| number[v as usize]) as usize;
    let mut chosen = Vec::with_capacity(readings.candidates.len());
    for (_, candidates) in &readings.candidates {
        let lowest = canonical(*candidates.first()?);
        let winner = sums.clear_winner(sums.component_of(lowest))?;
        let seed = candidates.iter().find(|&&v| sums.reading_of(canonical(v)) == winner)?;
        chosen.push(*seed);
    }
    Some(chosen)
}

/// The fine `positions` in the canonical order of `level` (the fine vertex of each
/// canonical one), borrowed when the fine mesh is in that order.
fn in_canonical_order<'a>(level: &LevelParts, positions: &'a [DVec3]) -> Cow<'a, [DVec3]> {
    match &level.order {
        None => Cow::Borrowed(positions),
        Some(order) => Cow::Owned(gather(positions, &order.vertex_of_canonical)),
    }
}

/// Whether the readings of a closed regular mesh in the canonical order are compared by
/// the sums of [`lattice`] first (always, outside tests).
#[cfg(not(test))]
fn compares_by_lattice() -> bool {
    true
}

#[cfg(test)]
fn compares_by_lattice() -> bool {
    BY_LATTICE.get()
}

/// Whether every vertex of `table` with a face has regular valence (6 inside, 4 on the
/// boundary), and some face exists. Stops at the first irregular vertex, which most
/// meshes have among their first few. (The reference of the tests for
/// [`CanonicalLevel::valences_regular`], which the reversal reads off its own counts.)
#[cfg(test)]
pub(crate) fn all_valences_regular(table: &CornerTable) -> bool {
    table.face_count() > 0
        && (0..table.vertex_count() as u32).all(|v| match table.visit_star(v, |_, _| {}) {
            VertexStar::Interior { valence } => valence == 6,
            VertexStar::Boundary { valence, .. } => valence == 4,
            VertexStar::Isolated => true,
        })
}

/// [`reading_is_settled`] from the details (the tests' entry).
#[cfg(test)]
pub(crate) fn canonical_reading_is_settled(coarse: &CornerTable, details: &[DVec3], positions: &[DVec3]) -> bool {
    reading_is_settled(coarse, detail_energy(details), positions)
}

/// Whether the canonical reading of a fine mesh (`positions`), of coarse mesh `coarse`
/// and sum of squared details `energy`, settles the choice among its readings without
/// comparing them (see [`reverse_level`]): its details are zero at the scale of the mesh
/// ([`zero_energy`]), and the coarse mesh is one component with no isolated vertex, so
/// that the mesh's scale is its component's.
fn reading_is_settled(coarse: &CornerTable, energy: f64, positions: &[DVec3]) -> bool {
    let (lo, hi) = positions.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let diagonal = if positions.is_empty() { 0.0 } else { lo.distance(hi) };
    settled(energy, zero_energy(diagonal, positions.len())) && spans_one_component(coarse)
}

/// Whether `table` has a face and is one connected component, every vertex on a face (so
/// that the canonical refinement of it is one component too, with no isolated vertex).
fn spans_one_component(table: &CornerTable) -> bool {
    let corner_vertex = table.corner_vertices();
    let mut on_a_face = vec![false; table.vertex_count()];
    for &v in corner_vertex {
        on_a_face[v as usize] = true;
    }
    table.face_count() > 0 && on_a_face.iter().all(|&on| on) && every_component_has_one(table, &corner_vertex[..1])
}

/// Whether every connected component of `table` with a face holds one of `vertices`
/// (all in range): a search across edges from the faces at them reaches every face.
///
/// Components are joined by edges here, by faces across their twins: the same
/// components as by vertices wherever the faces at every vertex form a single fan, as
/// on every table the reversal reads (those of manifold meshes, and of soups that
/// passed [`CornerTable::fans_are_single`]). Faces by twins read one array in face
/// order; the search by vertices that this replaces circulated every star, and took a
/// fifth of the seeded reversal of a regular torus.
fn every_component_has_one(table: &CornerTable, vertices: &[u32]) -> bool {
    if vertices.is_empty() {
        return false;
    }
    let (corner_vertex, twin) = (table.corner_vertices(), table.twins());
    let mut wanted = vec![false; table.vertex_count()];
    for &v in vertices {
        wanted[v as usize] = true;
    }
    let faces = table.face_count();
    let mut reached = vec![false; faces];
    // A breadth-first search, its queue in one array (every face is queued once at most,
    // when first reached), with a branch-free push (the slot past the end is written, and
    // kept only for a face not reached before: whether a neighbour was reached follows no
    // pattern the processor could predict). The face taken next was queued long before,
    // so the reads of successive faces overlap instead of waiting for one another.
    let mut queue = vec![0u32; faces + 1];
    let mut end = 0;
    for (c, &v) in corner_vertex.iter().enumerate() {
        let f = c / 3;
        if !wanted[v as usize] || std::mem::replace(&mut reached[f], true) {
            continue;
        }
        let mut head = end;
        queue[end] = f as u32;
        end += 1;
        while head < end {
            let f = queue[head] as usize;
            head += 1;
            for &t in &twin[3 * f..3 * f + 3] {
                // (Across the boundary: the face itself, reached.)
                let g = if t == NONE { f } else { t as usize / 3 };
                queue[end] = g as u32;
                end += usize::from(!std::mem::replace(&mut reached[g], true));
            }
        }
    }
    reached.iter().all(|&r| r)
}

/// The neighbour across every corner of the vertex whose circulation starts at corner
/// `start` ([`NONE`]: an isolated vertex), in circulation order (as
/// [`CornerTable::outgoing`] lists the corners): the other end of each corner's half-edge.
fn neighbours(corners: &[Corner], start: u32) -> Vec<u32> {
    let mut neighbours = Vec::new();
    let mut c = start;
    while c != NONE {
        neighbours.push(corners[next(c) as usize].vertex);
        let following = corners[prev(c) as usize].twin;
        c = if following == start { NONE } else { following };
    }
    neighbours
}

/// The components of a fine mesh whose readings [`reverse_level`] compares, and how to
/// tell each component's details apart.
struct RegularReadings {
    /// The component of every fine vertex.
    component: Vec<u32>,
    /// Each component whose valences are all regular and that holds no seed, with the
    /// seeds detection would try there in turn: its lowest vertex, then that vertex's
    /// neighbours.
    candidates: Vec<(usize, Vec<u32>)>,
}

impl RegularReadings {
    /// [`RegularReadings::of_corners`] of a corner table.
    #[cfg(test)]
    fn of(table: &CornerTable, seeds: &[u32]) -> Self {
        let starts = table.vertex_corners();
        Self::of_corners(table.vertex_count(), &table.corners(), |v| starts[v as usize], seeds)
    }

    /// The readings of a fine mesh of `vertices` vertices from its `corners` alone, as the
    /// searches of the readings read them (no table of edges built for this); `start(v)`:
    /// the circulation start of vertex `v` (as [`CornerTable::vertex_corners`] has it).
    /// Components by a union-find over the faces' corners and regularity by a count of
    /// outgoing corners, two sequential passes (a search circulating every vertex's star
    /// twice cost as much as a reversal): component labels in order of lowest vertex, an
    /// isolated vertex a component of its own that is not regular.
    fn of_corners(vertices: usize, corners: &[Corner], start: impl Fn(u32) -> u32, seeds: &[u32]) -> Self {
        let valences = Valences::of(vertices, corners.iter().map(|corner| (corner.vertex, corner.twin)));
        let mut parent: Vec<u32> = (0..vertices as u32).collect();
        let root = |parent: &mut [u32], mut v: u32| {
            while parent[v as usize] != v {
                // Path halving.
                parent[v as usize] = parent[parent[v as usize] as usize];
                v = parent[v as usize];
            }
            v
        };
        for face in corners.chunks_exact(3) {
            for pair in face.windows(2) {
                let (a, b) = (root(&mut parent, pair[0].vertex), root(&mut parent, pair[1].vertex));
                // The lower root stays the root (any choice works; this one is cheap).
                let (low, high) = (a.min(b), a.max(b));
                parent[high as usize] = low;
            }
        }
        let mut component = vec![NONE; vertices];
        let mut regular = Vec::new();
        let mut lowest = Vec::new();
        for v in 0..vertices as u32 {
            let r = root(&mut parent, v);
            if component[r as usize] == NONE {
                component[r as usize] = regular.len() as u32;
                regular.push(true);
                lowest.push(v);
            }
            let label = component[r as usize];
            component[v as usize] = label;
            regular[label as usize] &= !valences.is_irregular(v);
        }
        Self::of_components(|v| neighbours(corners, start(v)), component, regular, &lowest, seeds)
    }

    /// The readings of the components `component` (of every vertex) given, per
    /// component, whether its valences are all `regular` and its `lowest` vertex: the
    /// regular components without a seed, each with its candidate seeds (`neighbours`:
    /// the neighbours of a vertex, as detection circulates them).
    fn of_components(
        neighbours: impl Fn(u32) -> Vec<u32>,
        component: Vec<u32>,
        mut regular: Vec<bool>,
        lowest: &[u32],
        seeds: &[u32],
    ) -> Self {
        for &seed in seeds {
            if let Some(&c) = component.get(seed as usize) {
                regular[c as usize] = false;
            }
        }
        let candidates = (0..regular.len())
            .filter(|&c| regular[c])
            .map(|c| {
                let v = lowest[c];
                (c, std::iter::once(v).chain(neighbours(v)).collect())
            })
            .collect();
        Self { component, candidates }
    }

    /// Marks the vertex points of `level` (a reading of the mesh) in `covered`.
    fn cover(&self, level: &LevelParts, covered: &mut [bool]) {
        let vertex_points = level.coarse.vertex_count();
        match &level.order {
            None => covered[..vertex_points].fill(true),
            Some(order) => {
                for &v in &order.vertex_of_canonical[..vertex_points] {
                    covered[v as usize] = true;
                }
            }
        }
    }

    /// Per component, the largest sum of squared details that is still zero at its scale
    /// ([`zero_energy`] of the bounding-box diagonal of its vertices and their number).
    fn zero_energies(&self, positions: &[DVec3]) -> Vec<f64> {
        let components = self.energies_len();
        let mut boxes = vec![(DVec3::INFINITY, DVec3::NEG_INFINITY, 0usize); components];
        for (&c, &p) in self.component.iter().zip(positions) {
            let (lo, hi, count) = &mut boxes[c as usize];
            (*lo, *hi, *count) = (lo.min(p), hi.max(p), *count + 1);
        }
        boxes.into_iter().map(|(lo, hi, count)| zero_energy(lo.distance(hi), count)).collect()
    }

    /// The number of components (the length of [`energies`](Self::energies)).
    fn energies_len(&self) -> usize {
        self.component.iter().max().map_or(0, |&c| c as usize + 1)
    }

    /// The sum of squared details of every component in `level` (a reading of the mesh):
    /// detail `e` is that of canonical fine vertex `V + e`.
    fn energies(&self, level: &LevelParts) -> Vec<f64> {
        let mut energies = vec![0.0; self.energies_len()];
        let first_odd = level.coarse.vertex_count();
        for (e, detail) in level.details.iter().enumerate() {
            let canonical = first_odd + e;
            let v = level.order.as_ref().map_or(canonical as u32, |order| order.vertex_of_canonical[canonical]);
            energies[self.component[v as usize] as usize] += detail.length_squared();
        }
        energies
    }
}

/// One level reversed, by the fused path when the fine mesh is canonical, else through
/// its canonical renumbering ([`reverse_renumbered`]) when that is found and valid, else
/// by detection and [`reverse_positions`] (which also names every error). A user's mesh
/// with a non-finite position is an error before any connectivity error, on every path.
/// (What [`reverse_level`] computes for each reading it compares, without the fused
/// attempt; the tests check that they agree.)
#[cfg(test)]
fn reverse_level_from(
    fine: FineLevel<'_>,
    positions: &[DVec3],
    seeds: &[u32],
    rules: &LoopOptions,
) -> Result<LevelParts, LoopError> {
    match reverse_level_fast(fine, positions, seeds, rules)? {
        Some(level) => Ok(level),
        None => reverse_level_general(fine, positions, seeds, rules),
    }
}

/// [`reverse_level_fast_reading`] with corners of its own.
#[cfg(test)]
fn reverse_level_fast(
    fine: FineLevel<'_>,
    positions: &[DVec3],
    seeds: &[u32],
    rules: &LoopOptions,
) -> Result<Option<LevelParts>, LoopError> {
    reverse_level_fast_reading(fine, &OnceCell::new(), positions, seeds, rules)
}

/// The fast paths of `reverse_level_from`: `None` when neither applies (the general
/// detection then decides); an error only for a non-finite position of a user's mesh.
/// The fine corners are read into `corners` if the renumbering path reads them (for the
/// caller, which may need them too, to read them once).
fn reverse_level_fast_reading(
    fine: FineLevel<'_>,
    corners: &OnceCell<FineCorners>,
    positions: &[DVec3],
    seeds: &[u32],
    rules: &LoopOptions,
) -> Result<Option<LevelParts>, LoopError> {
    let check_input = || match fine {
        FineLevel::Mesh(_) => crate::pyramid::check_input_positions(positions),
        FineLevel::Table(_) => Ok(()),
    };
    let fused = match fine {
        FineLevel::Mesh(mesh) => reverse_canonical_mesh(mesh, seeds, positions, rules),
        FineLevel::Table(table) => reverse_canonical_table(table, seeds, positions, rules),
    };
    if let Some(level) = fused {
        if !level.finite {
            // Finite input (else named here) whose reversal is not: an overflow.
            check_input()?;
            return Err(reversal_overflow(&level.positions, &level.details, positions));
        }
        // A canonical mesh's reading is that of its numbering, compared with the others
        // only when all its valences are regular (see `reverse_level`) and some component
        // has no seed (the seeds, vertex points here, are coarse vertices too).
        let several_readings = level.valences_regular && !every_component_has_one(&level.coarse, seeds);
        return Ok(Some(LevelParts {
            coarse: level.coarse,
            order: None,
            positions: level.positions,
            details: level.details,
            several_readings,
        }));
    }
    check_input()?;
    // A mesh in any other order: renumbered into the canonical order of the coarse mesh
    // that detection finds, and reversed by the canonical path, which also checks it.
    // Anything else (errors included) goes through the general detection.
    Ok(reverse_searched(fine, corners.get_or_init(|| FineCorners::of(fine)), positions, seeds, rules))
}

/// [`LoopError::Overflow`] for a reversal of finite `input` positions whose coarse
/// `positions` and `details` are not all finite: coordinates so large that a sum of the
/// inverse rules leaves the `f64` range. It names the first value that is not finite in
/// the fine mesh's canonical numbering: coarse vertex `v`, or the detail of coarse edge
/// `e` as `v_count + e` (its edge point).
fn reversal_overflow(positions: &[DVec3], details: &[DVec3], input: &[DVec3]) -> LoopError {
    let vertex = positions.iter().chain(details).position(|p| !p.is_finite()).unwrap_or(0);
    LoopError::Overflow { vertex, largest: crate::forward::largest_magnitude(input) }
}

/// The corners of a fine level as the search of [`renumber_to_canonical`] reads them,
/// read once when several searches run on one level (the readings [`reverse_level`]
/// compares).
enum FineCorners {
    /// Those of a half-edge mesh (`None`: a face is not a triangle).
    Mesh(Option<MeshCorners>),
    /// Those of a corner table.
    Table(Vec<Corner>),
}

impl FineCorners {
    fn of(fine: FineLevel<'_>) -> Self {
        match fine {
            FineLevel::Mesh(mesh) => Self::Mesh(CornerTable::mesh_corners(mesh)),
            FineLevel::Table(table) => Self::Table(table.corners()),
        }
    }
}

/// The renumbering path of [`reverse_level_fast_reading`]: a mesh in any order renumbered into
/// the canonical order of the coarse mesh that detection finds from `seeds` and the
/// irregular vertices, and reversed by the canonical path, which also checks it; `None`
/// if that fails. `corners`: [`FineCorners::of`] `fine`.
fn reverse_searched(
    fine: FineLevel<'_>,
    corners: &FineCorners,
    positions: &[DVec3],
    seeds: &[u32],
    rules: &LoopOptions,
) -> Option<LevelParts> {
    let renumbering = match (fine, corners) {
        (FineLevel::Mesh(mesh), FineCorners::Mesh(Some(corners))) => {
            let corner_at = |v| corners.corner_at(mesh, v);
            renumber_to_canonical(mesh.vertex_count(), &corners.corners, corner_at, seeds)
        }
        (FineLevel::Table(table), FineCorners::Table(corners)) => {
            let starts = table.vertex_corners();
            let corner_at = |v: u32| starts[v as usize];
            renumber_to_canonical(table.vertex_count(), corners, corner_at, seeds)
        }
        _ => None,
    };
    renumbering.and_then(|renumbering| reverse_renumbered(renumbering, positions, rules))
}

/// The general path of `reverse_level_from`: detection (which also names every error)
/// and [`reverse_positions`].
fn reverse_level_general(
    fine: FineLevel<'_>,
    positions: &[DVec3],
    seeds: &[u32],
    rules: &LoopOptions,
) -> Result<LevelParts, LoopError> {
    let coarsening = match fine {
        FineLevel::Mesh(mesh) => detect_mesh(mesh, seeds)?,
        FineLevel::Table(table) => detect_table(table, seeds)?,
    };
    let (coarse_positions, details) = reverse_positions(&coarsening, positions, rules);
    if !(crate::pyramid::all_finite(&coarse_positions) && crate::pyramid::all_finite(&details)) {
        return Err(reversal_overflow(&coarse_positions, &details, positions));
    }
    let order = coarsening.fine_order();
    // (Reached, for a valid mesh, when the search from the seeds and the irregular
    // vertices missed a component: one whose valences are all regular.)
    Ok(LevelParts { coarse: coarsening.coarse, order, positions: coarse_positions, details, several_readings: true })
}

/// A fine mesh in any order reversed through its canonical renumbering
/// ([`renumber_to_canonical`]) and [`reverse_canonical`]: the same coarse mesh,
/// positions, details and order, bit for bit, as the general detection followed by
/// [`reverse_positions`] (the edge points are summed in the same coarse edge order, the
/// details by the same formula). `None` when the renumbering is not found or the
/// renumbered mesh is not a valid canonical refinement.
fn reverse_renumbered(renumbering: Renumbering, positions: &[DVec3], rules: &LoopOptions) -> Option<LevelParts> {
    let canonical_positions = gather(positions, &renumbering.order.vertex_of_canonical);
    // The groups are made in the canonical pattern (coarse vertices below edge points,
    // the seed, if any, a vertex point); the rest is checked as for any canonical mesh.
    let identity = renumbering.is_identity();
    let level = reverse_canonical_groups(renumbering.groups, positions.len(), &canonical_positions, rules)?;
    if !level.finite {
        // An overflow: the general path reports it.
        return None;
    }
    let order = (!identity).then_some(renumbering.order);
    // The search reached every component from a seed or an irregular vertex.
    Some(LevelParts {
        coarse: level.coarse,
        order,
        positions: level.positions,
        details: level.details,
        several_readings: false,
    })
}

/// `values[i]` for every `i` of `indices`, in order: a gather at random, with the
/// values a few places ahead prefetched, by chunks in parallel when large.
fn gather(values: &[DVec3], indices: &[u32]) -> Vec<DVec3> {
    const AHEAD: usize = 16;
    let prefetching = worth_prefetching(size_of_val(values));
    let mut output = Output::<DVec3>::new(indices.len());
    {
        let mut slots = output.slots();
        let pieces: Vec<_> =
            indices.chunks(PARALLEL_THRESHOLD).map(|chunk| (chunk, slots.take_front(chunk.len()))).collect();
        let run = |(chunk, mut piece): (&[u32], Slots<'_, DVec3>)| {
            for (i, &v) in chunk.iter().enumerate() {
                if prefetching && let Some(&later) = chunk.get(i + AHEAD) {
                    prefetch(values, later as usize);
                }
                piece.push(values[v as usize]);
            }
        };
        if pieces.len() > 1 && kernel::pool_has_threads() {
            pieces.into_par_iter().for_each(run);
        } else {
            pieces.into_iter().for_each(run);
        }
    }
    output.into_vec()
}

/// A level reversed by [`reverse_canonical`].
pub(crate) struct CanonicalLevel {
    /// The coarse mesh (the fine mesh is its canonical refinement: no fine order).
    pub(crate) coarse: CornerTable,
    pub(crate) positions: Vec<DVec3>,
    pub(crate) details: Vec<DVec3>,
    /// True if every coarse position and detail is finite, as they are whenever the
    /// fine positions are (every fine vertex is a vertex point or an edge point, and a
    /// non-finite one makes its coarse position or detail non-finite): callers that
    /// must reject non-finite input only look at the input when this is false.
    pub(crate) finite: bool,
    /// Whether every coarse vertex has a regular valence (what `all_valences_regular`
    /// tells of `coarse`, read off the valences the reversal counts anyway).
    pub(crate) valences_regular: bool,
}

/// A fine mesh in the canonical order (see [`detect`](crate::detect)), detected and
/// reversed in one go: the same coarse mesh, positions and details, bit for bit, as
/// [`detect_mesh`] / [`detect_table`] followed by
/// [`reverse_positions`], in fewer passes over memory. `None` when anything differs
/// from a valid canonical refinement; the caller then takes the general path, which
/// also names the error.
///
/// Passes: the groups of four faces (parallel); the coarse corners in order, which
/// number the edges, pair the twins (checking the coarse faces as they pair) and sum
/// the edge points around every coarse vertex in edge order (sequential: these sums are
/// what [`reverse_positions`] adds, in the same order; on two threads a second pass
/// beside the pairing, else in the same loop), checking on the way that no two edges
/// join the same two vertices; the boundary edges, if any; the coarse positions
/// (parallel); the details by chunks of coarse edges (parallel).
pub(crate) fn reverse_canonical(
    faces: usize,
    vertex_count: usize,
    seeds: &[u32],
    face: impl Fn(usize) -> Option<[u32; 3]> + Sync,
    fine: &[DVec3],
    rules: &LoopOptions,
) -> Option<CanonicalLevel> {
    reverse_canonical_groups(canonical_groups(faces, seeds, face)?, vertex_count, fine, rules)
}

/// [`reverse_canonical`] from the coarse corners of the fine faces (the groups of four
/// faces read already).
fn reverse_canonical_groups(
    groups: CanonicalGroups,
    vertex_count: usize,
    fine: &[DVec3],
    rules: &LoopOptions,
) -> Option<CanonicalLevel> {
    let first_odd = groups.first_odd;
    let nv = first_odd as usize;
    let edge_position = |e: u32| fine[(first_odd + e) as usize];
    // The edge points around every coarse vertex, summed in edge order (the order of
    // `reverse_positions`), beside the pairing of the twins or inside it, with the
    // doubled-edge check on the way.
    let sum_edge_point = |sums: &mut EdgeSums, ends: [u32; 2], m: u32| sums.add_edge(ends, fine[m as usize]);
    // (Called only when the pairing prefetches, for large meshes.)
    let ahead = |sums: &EdgeSums, v: u32| prefetch(&sums.records, v as usize);
    let (coarse, edges, mut sums) = groups.into_table(vertex_count, EdgeSums::new(nv), sum_edge_point, ahead)?;
    if !sums.edges_are_simple() {
        return None;
    }
    let mut records = sums.records;
    // On the boundary only the boundary edges count, summed in edge order from zero:
    // boundary corners in corner order are the boundary edges in edge order.
    let (corner_vertex, twin, corner_edge) = (coarse.corner_vertices(), coarse.twins(), coarse.corner_edges());
    if 2 * coarse.edge_count() != coarse.corner_count() {
        for c in (0..twin.len() as u32).filter(|&c| twin[c as usize] == NONE) {
            let point = edge_position(corner_edge[c as usize]);
            for v in [corner_vertex[c as usize], corner_vertex[next(c) as usize]] {
                let record = &mut records[v as usize];
                if record.valence & VertexRecord::BOUNDARY == 0 {
                    record.sum = DVec3::ZERO;
                    record.valence |= VertexRecord::BOUNDARY;
                }
                record.sum += point;
            }
        }
    }
    let weights = InverseWeights::new(rules.weights);
    let positions = map_indices(nv, |v| {
        let VertexRecord { sum, valence, .. } = records[v as usize];
        let (n, flags) = (valence & !VertexRecord::BOUNDARY, valence & VertexRecord::BOUNDARY);
        coarse_position(fine[v as usize], sum, n, flags != 0, rules, &weights)
    });
    // What `all_valences_regular` tells from the table, from the counts at hand (whose
    // valence is the number of edges, as a circulation counts them): building the
    // circulation starts for it cost 7% of a two-level decomposition of the bunny. Most
    // meshes stop at their first few vertices.
    let valences_regular = coarse.face_count() > 0
        && records.iter().all(|record| matches!(record.valence, 0 | 6) || record.valence == 4 | VertexRecord::BOUNDARY);
    drop(records);
    let (details, details_finite) = canonical_details(coarse.corner_vertices(), &edges, &positions, edge_position);
    let finite = details_finite && crate::pyramid::all_finite(&positions);
    Some(CanonicalLevel { coarse, positions, details, finite, valences_regular })
}

/// Upper end points kept in each [`VertexRecord`] (the others go to
/// [`EdgeSums::overflow`]): a record fills one cache line.
const UPPER_SLOTS: usize = 8;

/// What the pass over the coarse edges in edge order gathers per coarse vertex, side by
/// side (one cache line per vertex in a scattered pass): the sum of the edge points of
/// its edges and their number (as [`reverse_positions`] computes them), and the upper
/// end points of the edges whose lower end point it is, so that a doubled edge shows
/// when it is added.
#[derive(Clone, Copy)]
#[repr(C, align(64))]
struct VertexRecord {
    /// Sum of the edge points of its edges (of its boundary edges on the boundary, once
    /// those are summed).
    sum: DVec3,
    /// Number of edges at the vertex, [`VertexRecord::BOUNDARY`] set on the boundary.
    valence: u32,
    /// Number of edges whose lower end point is the vertex.
    lower: u32,
    /// The upper end points of the first [`UPPER_SLOTS`] of those edges, [`NONE`] in the
    /// slots not used yet (no vertex is numbered [`NONE`]).
    upper: [u32; UPPER_SLOTS],
}

impl VertexRecord {
    const BOUNDARY: u32 = 1 << 31;
    const EMPTY: Self = Self { sum: DVec3::ZERO, valence: 0, lower: 0, upper: [NONE; UPPER_SLOTS] };
}

/// The state of the pass over the coarse edges in [`reverse_canonical`]: the sums of
/// the edge points, and the doubled-edge check of the coarse mesh (no two edges join the
/// same two vertices), done as the edges come instead of by a sort afterwards.
struct EdgeSums {
    records: Vec<VertexRecord>,
    /// `[lower, upper]` end points of the edges beyond their lower end point's slots.
    overflow: Vec<[u32; 2]>,
    /// True once an edge joined two vertices that an earlier edge in the slots joins.
    doubled: bool,
}

impl EdgeSums {
    fn new(vertex_count: usize) -> Self {
        Self { records: vec![VertexRecord::EMPTY; vertex_count], overflow: Vec::new(), doubled: false }
    }

    /// Adds edge `[a, b]` with edge point `point` (edges in edge order).
    #[inline(always)]
    fn add_edge(&mut self, [a, b]: [u32; 2], point: DVec3) {
        for v in [a, b] {
            let record = &mut self.records[v as usize];
            record.sum += point;
            record.valence += 1;
        }
        let (lower, upper) = (a.min(b), a.max(b));
        let record = &mut self.records[lower as usize];
        // All slots at once (unused ones hold NONE): a compare the compiler vectorises.
        self.doubled |= record.upper.iter().fold(false, |seen, &u| seen | (u == upper));
        match record.upper.get_mut(record.lower as usize) {
            Some(slot) => *slot = upper,
            None => self.overflow.push([lower, upper]),
        }
        record.lower += 1;
    }

    /// True if no two edges join the same two vertices. An edge beyond its lower end
    /// point's slots was compared with all of them when it was added, so only the
    /// overflow is left to compare with itself.
    fn edges_are_simple(&mut self) -> bool {
        if self.doubled {
            return false;
        }
        self.overflow.sort_unstable();
        self.overflow.windows(2).all(|w| w[0] != w[1])
    }
}

/// Non-zero if a coordinate of `p` is not finite (branch-free, so loops over it vectorise).
#[inline(always)]
pub(crate) fn non_finite_bits(p: DVec3) -> u64 {
    const EXPONENT: u64 = 0x7ff0_0000_0000_0000;
    let bits = |x: f64| u64::from(x.to_bits() & EXPONENT == EXPONENT);
    bits(p.x) | bits(p.y) | bits(p.z)
}

/// Edges ahead whose positions [`canonical_details`] prefetches.
const DETAILS_AHEAD: usize = 8;

/// Coarse edges per parallel work item of [`canonical_details`].
const DETAIL_CHUNK: usize = 2048;

/// The detail of every coarse edge, in edge order by chunks of edges (the coarse faces
/// were checked by the pairing that numbered the edges). The formula of [`edge_rule`],
/// on the end points and the vertex across the first half-edge that [`PairedEdge`]
/// keeps (see [`CanonicalGroups::into_table`](crate::detect::CanonicalGroups::into_table))
/// and the third vertex of its face (`corner_vertex`: the coarse corners' vertices).
/// Edge by edge rather than face by face: a face's corners alternate unpredictably
/// between the first half-edge of an edge and the second, and the branch on it cost a
/// two-level decomposition of the bunny a tenth of its time.
fn canonical_details(
    corner_vertex: &[u32],
    edges: &[PairedEdge],
    positions: &[DVec3],
    edge_position: impl Fn(u32) -> DVec3 + Sync,
) -> (Vec<DVec3>, bool) {
    let parallel = edges.len() >= PARALLEL_THRESHOLD / 4 && kernel::pool_has_threads();
    let prefetching = worth_prefetching(size_of_val(positions));
    let third = |edge: &PairedEdge| corner_vertex[prev(edge.first) as usize];
    let mut output = Output::<DVec3>::new(edges.len());
    let finite = {
        let mut slots = output.slots();
        let pieces: Vec<_> = (0..edges.len())
            .step_by(DETAIL_CHUNK)
            .map(|e0| {
                let n = DETAIL_CHUNK.min(edges.len() - e0);
                (e0, slots.take_front(n))
            })
            .collect();
        let run = |(e0, mut piece): (usize, Slots<'_, DVec3>)| {
            // Zero times every detail, summed: zero (of either sign) unless a detail is
            // not finite (`0 * inf` and `0 * NaN` are NaN), in two instructions a detail.
            let mut zeros = DVec3::ZERO;
            for e in e0..e0 + piece.len() {
                // The coarse vertices are in any order when the fine mesh was renumbered:
                // the positions of the edges a few places ahead are prefetched.
                if prefetching && let Some(ahead) = edges.get(e + DETAILS_AHEAD) {
                    for v in [ahead.ends[0], ahead.ends[1], third(ahead), ahead.opposite] {
                        prefetch(positions, v as usize);
                    }
                }
                let edge = &edges[e];
                let (a, b) = (positions[edge.ends[0] as usize], positions[edge.ends[1] as usize]);
                let predicted = if edge.opposite == NONE {
                    0.5 * (a + b)
                } else {
                    interior_edge_point(a, b, positions[third(edge) as usize], positions[edge.opposite as usize])
                };
                let detail = edge_position(e as u32) - predicted;
                zeros += 0.0 * detail;
                piece.push(detail);
            }
            zeros.is_finite()
        };
        if parallel {
            pieces.into_par_iter().map(run).reduce(|| true, |a, b| a && b)
        } else {
            // Every piece is written, whatever the others hold (no short circuit).
            pieces.into_iter().map(run).fold(true, |a, b| a & b)
        }
    };
    (output.into_vec(), finite)
}

/// The coarse position of a vertex from its vertex point and the sum of its edge
/// points (of the boundary ones on the boundary): the exact inverse of the vertex rule.
#[inline]
fn coarse_position(
    vertex_point: DVec3,
    sum: DVec3,
    valence: u32,
    on_boundary: bool,
    rules: &LoopOptions,
    weights: &InverseWeights,
) -> DVec3 {
    if on_boundary {
        if rules.keep_corners && valence == 2 { vertex_point } else { 2.0 * vertex_point - 0.5 * sum }
    } else if valence == 0 {
        vertex_point
    } else {
        let (mu, eta) = weights.get(valence as usize);
        mu * vertex_point + eta * sum
    }
}

/// [`inverse_weights`] tabulated for the usual valences (no cosine per vertex).
struct InverseWeights {
    weights: VertexWeights,
    table: [(f64, f64); 32],
}

impl InverseWeights {
    fn new(weights: VertexWeights) -> Self {
        let mut table = [(1.0, 0.0); 32];
        for (n, entry) in table.iter_mut().enumerate().skip(1) {
            *entry = inverse_weights(weights, n);
        }
        Self { weights, table }
    }

    #[inline]
    fn get(&self, valence: usize) -> (f64, f64) {
        if valence < self.table.len() { self.table[valence] } else { inverse_weights(self.weights, valence) }
    }
}

/// One reconstruction step on corner tables: the fine table (in the given order) and
/// its positions. Inputs must have passed [`check_level`].
pub(crate) fn refine_level(
    coarse: &CornerTable,
    positions: &[DVec3],
    details: &[DVec3],
    order: Option<&FineOrder>,
    rules: &LoopOptions,
) -> (CornerTable, Vec<DVec3>) {
    let nv = coarse.vertex_count();
    let edge_points = map_indices(coarse.edge_count(), |e| edge_rule(coarse, positions, e) + details[e as usize]);
    let edge_position = |e: u32| edge_points[e as usize];
    let vertex_points = map_indices(nv, |v| {
        let p = positions[v as usize];
        let (star, sum) = edge_point_star(coarse, v, edge_position);
        match star {
            VertexStar::Isolated => p,
            // Solve p = μ p' + η Σ e' for p'.
            VertexStar::Interior { valence } => {
                let (mu, eta) = inverse_weights(rules.weights, valence);
                (p - eta * sum) / mu
            }
            VertexStar::Boundary { valence, boundary_edges: [a, b] } => {
                if rules.keep_corners && valence == 2 {
                    p
                } else {
                    0.5 * p + 0.25 * (edge_points[a as usize] + edge_points[b as usize])
                }
            }
        }
    });
    let canonical = coarse.refine();
    let mut fine_positions = vertex_points;
    fine_positions.extend_from_slice(&edge_points);
    match order {
        None => (canonical, fine_positions),
        Some(order) => {
            let mut permuted = vec![DVec3::ZERO; fine_positions.len()];
            for (i, &v) in order.vertex_of_canonical.iter().enumerate() {
                permuted[v as usize] = fine_positions[i];
            }
            (canonical.permuted(&order.vertex_of_canonical, &order.face_of_canonical), permuted)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::{
        bipyramid, flip_random_edges, loop_step, loop_steps, open_fan, perturb, relative_distance, scramble,
    };
    use mesh_topo::PolygonSoup;
    use mesh_topo::shapes::{self, CellKind};
    use proptest::prelude::*;

    const TOLERANCE: f64 = 1e-12;

    fn mesh(soup: &PolygonSoup) -> HalfedgeMesh {
        HalfedgeMesh::from_soup(soup).expect("valid test mesh")
    }

    fn all_rules() -> [LoopOptions; 4] {
        [
            LoopOptions { weights: VertexWeights::Loop, keep_corners: false },
            LoopOptions { weights: VertexWeights::Warren, keep_corners: false },
            LoopOptions { weights: VertexWeights::Loop, keep_corners: true },
            LoopOptions { weights: VertexWeights::Warren, keep_corners: true },
        ]
    }

    fn test_shapes() -> Vec<(String, PolygonSoup)> {
        let mut out = vec![
            ("tetrahedron".to_string(), shapes::tetrahedron()),
            ("octahedron".to_string(), shapes::octahedron()),
            ("icosahedron".to_string(), shapes::icosahedron()),
            ("grid 3x2".to_string(), shapes::grid(3, 2, CellKind::Triangles).unwrap()),
            ("torus 4x3".to_string(), shapes::torus(4, 3, CellKind::Triangles).unwrap()),
            (
                "single triangle".to_string(),
                PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]]),
            ),
        ];
        for n in 3..=12 {
            out.push((format!("bipyramid {n}"), bipyramid(n)));
        }
        for n in 1..=5 {
            out.push((format!("open fan {n}"), open_fan(n)));
        }
        out
    }

    /// ALGORITHMS.md §7.2: l, α, μ, η with Loop's weights.
    #[test]
    fn published_inverse_weights_are_reproduced() {
        let table = [
            (3, 0.4375, 10.0, -3.0),
            (4, 0.515625, 4.444444, -0.861111),
            (5, 0.579534, 3.055728, -0.411146),
            (6, 0.625, 2.5, -0.25),
            (7, 0.656826, 2.217684, -0.173955),
            (8, 0.679458, 2.052832, -0.131604),
            (10, 0.708222, 1.875624, -0.087562),
            (20, 0.750480, 1.664537, -0.033227),
            (100, 0.765009, 1.602529, -0.006025),
        ];
        for (l, alpha, mu, eta) in table {
            let beta = super::beta(VertexWeights::Loop, l);
            assert!((1.0 - l as f64 * beta - alpha).abs() < 1e-6, "alpha at valence {l}");
            let (m, e) = inverse_weights(VertexWeights::Loop, l);
            assert!((m - mu).abs() < 1e-6, "mu at valence {l}: {m} vs {mu}");
            assert!((e - eta).abs() < 1e-6, "eta at valence {l}: {e} vs {eta}");
            // The seed paper's closed forms give the same numbers.
            let a = 1.0 - l as f64 * beta;
            assert!((m - 5.0 / (8.0 * a - 3.0)).abs() < 1e-12);
            assert!((e - (a - 1.0) / (l as f64 * (a - 0.375))).abs() < 1e-12);
        }
    }

    #[test]
    fn inverse_weights_are_finite_at_every_valence() {
        for weights in [VertexWeights::Loop, VertexWeights::Warren] {
            // Valence 0 used to give (NaN, NaN); it is the copy of an isolated vertex.
            assert_eq!(inverse_weights(weights, 0), (1.0, 0.0));
            for l in [1, 2, 1000, usize::MAX] {
                let (mu, eta) = inverse_weights(weights, l);
                assert!(mu.is_finite() && eta.is_finite(), "{weights:?} valence {l}");
            }
        }
    }

    #[test]
    fn inverse_weights_are_affine_and_invert_the_one_ring() {
        let mut rng = crate::reference::Rng::new(7);
        for weights in [VertexWeights::Loop, VertexWeights::Warren] {
            for l in 3..=30 {
                let (mu, eta) = inverse_weights(weights, l);
                assert!((mu + l as f64 * eta - 1.0).abs() < 1e-13, "{weights:?} valence {l}");
                // Forward rules on a random closed 1-ring, then the inverse.
                let p = rng.vector();
                let q: Vec<DVec3> = (0..l).map(|_| rng.vector()).collect();
                let beta = super::beta(weights, l);
                let vertex_point = (1.0 - l as f64 * beta) * p + beta * q.iter().sum::<DVec3>();
                let edge_sum: DVec3 =
                    (0..l).map(|j| 0.375 * (p + q[j]) + 0.125 * (q[(j + l - 1) % l] + q[(j + 1) % l])).sum();
                let recovered = mu * vertex_point + eta * edge_sum;
                assert!(recovered.distance(p) < 1e-13, "{weights:?} valence {l}: {}", recovered.distance(p));
            }
        }
    }

    #[test]
    fn reverse_of_loop_subdivision_is_the_coarse_mesh_with_zero_details() {
        for (name, soup) in test_shapes() {
            for rules in all_rules() {
                let fine = mesh(&loop_step(&mesh(&soup), &rules));
                let level = reverse(&fine, &ReverseOptions { rules, seed_vertices: Vec::new() })
                    .unwrap_or_else(|e| panic!("{name} {rules:?}: {e}"));
                let error = relative_distance(&level.coarse.to_soup(), &soup);
                assert!(error < TOLERANCE, "{name} {rules:?}: coarse error {error}");
                let diagonal = crate::pyramid::bounding_box_diagonal(&soup.positions);
                let largest = level.details.iter().map(|d| d.length()).fold(0.0, f64::max) / diagonal;
                assert!(largest < TOLERANCE, "{name} {rules:?}: detail {largest}");
                assert!(level.order.is_none(), "{name}: canonical order expected");
                // Storage: coarse vertices + details = fine vertices.
                assert_eq!(level.coarse.vertex_count() + level.details.len(), fine.vertex_count());
            }
        }
    }

    #[test]
    fn reconstruction_with_zero_details_is_loop_subdivision() {
        for (name, soup) in test_shapes() {
            for rules in all_rules() {
                let coarse = mesh(&soup);
                let zeros = vec![DVec3::ZERO; coarse.edge_count()];
                let fine = reconstruct(&coarse, &zeros, None, &rules).unwrap();
                let error = relative_distance(&fine.to_soup(), &loop_step(&coarse, &rules));
                assert!(error < TOLERANCE, "{name} {rules:?}: {error}");
            }
        }
    }

    #[test]
    fn perturbed_and_renumbered_loop_meshes_are_rebuilt_exactly() {
        for (name, soup) in test_shapes() {
            for (i, rules) in all_rules().into_iter().enumerate() {
                let fine = scramble(&perturb(&loop_steps(&soup, &rules, 1), 0.2, i as u64), 11 + i as u64);
                let level = reverse(&mesh(&fine), &ReverseOptions { rules, seed_vertices: Vec::new() })
                    .unwrap_or_else(|e| panic!("{name}: {e}"));
                assert!(level.order.is_some(), "{name}: a scrambled mesh is not in canonical order");
                let rebuilt = reconstruct(&level.coarse, &level.details, level.order.as_ref(), &rules).unwrap();
                let error = relative_distance(&rebuilt.to_soup(), &fine);
                assert!(error < TOLERANCE, "{name} {rules:?}: {error}");
            }
        }
    }

    /// A refined torus (valence 6 everywhere) reads four ways. Renumbered in any way, the
    /// automatic reversal gets the refinement's own reading back (zero details); with the
    /// vertices moved, it keeps the reading of smallest details among the seeds
    /// detection would try, and a given seed still fixes the reading.
    #[test]
    fn a_mesh_of_regular_valences_gets_the_reading_with_the_smallest_details() {
        let rules = LoopOptions::default();
        let torus = shapes::torus(6, 4, CellKind::Triangles).unwrap();
        let fine = loop_step(&mesh(&torus), &rules);
        let energy = |level: &ReversedLevel| level.details.iter().map(|d| d.length_squared()).sum::<f64>();
        for scramble_seed in 0..6 {
            let renumbered = scramble(&fine, scramble_seed);
            let level = reverse(&mesh(&renumbered), &ReverseOptions::default()).unwrap();
            assert!(energy(&level) < 1e-24, "seed {scramble_seed}: {}", energy(&level));
            // Every coarse vertex is a vertex of the torus (numbered as the reading found).
            let nearest = |p: DVec3| torus.positions.iter().map(|q| p.distance(*q)).fold(f64::INFINITY, f64::min);
            let far = level.coarse.positions().iter().map(|&p| nearest(p)).fold(0.0, f64::max);
            assert!(far < 1e-12, "seed {scramble_seed}: the torus's vertices back ({far})");
        }
        for moved_seed in 0..4 {
            let moved = mesh(&scramble(&perturb(&fine, 0.1, moved_seed), 100 + moved_seed));
            let chosen = energy(&reverse(&moved, &ReverseOptions::default()).unwrap());
            let table = CornerTable::from_mesh(&moved).unwrap();
            let readings = RegularReadings::of(&table, &[]);
            let [(0, seeds)] = &readings.candidates[..] else { panic!("one regular component") };
            assert_eq!(seeds.len(), 7, "vertex 0 and its six neighbours");
            let seeded: Vec<f64> = seeds
                .iter()
                .filter_map(|&seed| reverse(&moved, &ReverseOptions { rules, seed_vertices: vec![seed] }).ok())
                .map(|level| energy(&level))
                .collect();
            assert!(seeded.len() >= 2, "several readings");
            let smallest = seeded.iter().copied().fold(f64::INFINITY, f64::min);
            assert_eq!(chosen, smallest, "moved {moved_seed}: {seeded:?}");
            assert!(seeded.iter().any(|&e| e > smallest), "the readings differ");
        }
        // Not regular (an octahedron refined: valence 4 at its vertices): no alternatives.
        let octahedron = loop_step(&mesh(&shapes::octahedron()), &rules);
        let regular_components =
            |soup: &PolygonSoup| RegularReadings::of(&CornerTable::from_soup(soup).unwrap(), &[]).candidates.len();
        assert_eq!(regular_components(&octahedron), 0);
        assert_eq!(regular_components(&fine), 1);
        assert_eq!(regular_components(&side_by_side(&octahedron, &fine)), 1);
        assert_eq!(regular_components(&side_by_side(&fine, &fine)), 2);
        let two = CornerTable::from_soup(&side_by_side(&fine, &octahedron)).unwrap();
        let n = fine.vertex_count() as u32;
        assert!(!every_component_has_one(&two, &[]));
        assert!(!every_component_has_one(&two, &[0, 5]));
        assert!(!every_component_has_one(&two, &[n]));
        assert!(every_component_has_one(&two, &[n + 1, 3]));
        assert!(!all_valences_regular(&CornerTable::from_soup(&octahedron).unwrap()));
        assert!(all_valences_regular(&CornerTable::from_soup(&side_by_side(&fine, &fine)).unwrap()));
    }

    /// The search of `every_component_has_one` across faces finds the components that a
    /// search across the edges at every vertex finds (meshes whose fans are single): open
    /// and closed meshes side by side, an isolated vertex, every choice of one or two
    /// vertices.
    #[test]
    fn components_by_faces_are_those_by_vertices() {
        let by_vertices = |table: &CornerTable, vertices: &[u32]| {
            let mut reached = vec![false; table.vertex_count()];
            let mut stack = vertices.to_vec();
            for &v in vertices {
                reached[v as usize] = true;
            }
            while let Some(v) = stack.pop() {
                table.visit_star(v, |_, u| {
                    if !std::mem::replace(&mut reached[u as usize], true) {
                        stack.push(u);
                    }
                });
            }
            !vertices.is_empty()
                && (0..table.vertex_count() as u32).all(|v| reached[v as usize] || table.is_isolated(v))
        };
        let grid = shapes::grid(3, 2, CellKind::Triangles).unwrap();
        let torus = shapes::torus(4, 3, CellKind::Triangles).unwrap();
        let mut with_isolated = side_by_side(&grid, &shapes::octahedron());
        with_isolated.positions.push(DVec3::ZERO);
        for soup in [
            grid.clone(),
            side_by_side(&grid, &torus),
            side_by_side(&torus, &side_by_side(&shapes::octahedron(), &grid)),
            with_isolated,
        ] {
            let table = CornerTable::from_soup(&soup).unwrap();
            let n = table.vertex_count() as u32;
            for a in 0..n {
                assert_eq!(every_component_has_one(&table, &[a]), by_vertices(&table, &[a]), "{a}");
                for b in a..n {
                    assert_eq!(every_component_has_one(&table, &[a, b]), by_vertices(&table, &[a, b]), "{a} {b}");
                }
            }
        }
        assert!(spans_one_component(&CornerTable::from_soup(&grid).unwrap()));
        assert!(!spans_one_component(&CornerTable::from_soup(&side_by_side(&grid, &torus)).unwrap()));
    }

    /// `reverse` keeps the same reading whether the readings of a closed regular mesh in
    /// the canonical order are first compared by the sums of [`lattice`] or only reversed
    /// in turn, bit for bit: moved tori of several sizes, one and two components, both
    /// vertex weights, moved a little (the first reading clearly the best: no other
    /// reading reversed) and a lot (some other reading the best: the readings in turn
    /// decide). Renumbered, the reading of the first round (one reversal) is the one the
    /// sums judge.
    #[test]
    fn readings_compared_by_the_lattice_are_those_reversed_in_turn() {
        // Kept from the first round's reading: itself, and another reading.
        let (mut kept_by_lattice, mut kept_renumbered, mut decided_in_turn) = (0, [0, 0], 0);
        for weights in [VertexWeights::Loop, VertexWeights::Warren] {
            let rules = LoopOptions { weights, keep_corners: false };
            let torus = shapes::torus(6, 4, CellKind::Triangles).unwrap();
            let wide = shapes::torus(8, 6, CellKind::Triangles).unwrap();
            let canonical = |soup: &PolygonSoup, levels: u32| {
                let fine = crate::forward::subdivide(&mesh(soup), levels, &rules).unwrap();
                PolygonSoup::from_faces(fine.positions, fine.triangles)
            };
            let fines = [canonical(&torus, 1), canonical(&wide, 2), canonical(&side_by_side(&torus, &wide), 1)];
            for (i, fine) in fines.iter().enumerate() {
                for (seed, amount) in [(1, 0.01), (2, 0.05), (3, 0.3), (4, 1.0)] {
                    // In the canonical order, and renumbered four ways (the first round's
                    // reading, from the lowest vertex, is then any of the four).
                    for renumber in [None, Some(0), Some(1), Some(2), Some(3)] {
                        let moved = perturb(fine, amount, seed);
                        let moved = mesh(&match renumber {
                            Some(k) => scramble(&moved, 10 * seed + k),
                            None => moved,
                        });
                        let reversed = |by_lattice: bool| {
                            BY_LATTICE.set(by_lattice);
                            MORE_READINGS.set(0);
                            let level = reverse(&moved, &ReverseOptions { rules, seed_vertices: Vec::new() }).unwrap();
                            BY_LATTICE.set(true);
                            (level, MORE_READINGS.get())
                        };
                        let ((level, more), (in_turn, more_in_turn)) = (reversed(true), reversed(false));
                        let case = format!("{weights:?}, mesh {i}, moved {amount}, renumbered {renumber:?}");
                        assert_eq!(level.details, in_turn.details, "{case}");
                        assert_eq!(level.coarse.positions(), in_turn.coarse.positions(), "{case}");
                        assert_eq!(level.coarse.to_soup().indices, in_turn.coarse.to_soup().indices, "{case}");
                        assert_eq!(level.order, in_turn.order, "{case}");
                        if renumber.is_some() {
                            // The first round's reading, and the best one if another:
                            // fewer than in turn; or the readings in turn.
                            if more < more_in_turn {
                                assert!(more <= 2, "{case}: {more} readings with the sums");
                                kept_renumbered[more - 1] += 1;
                            } else {
                                assert_eq!(more, more_in_turn, "{case}");
                            }
                        } else if more == 0 {
                            assert!(more_in_turn >= 3, "{case}: kept by the sums, not by the readings in turn");
                            kept_by_lattice += 1;
                        } else {
                            assert_eq!(more, more_in_turn, "{case}");
                            decided_in_turn += 1;
                        }
                    }
                }
            }
        }
        // Every way was exercised.
        assert!(
            kept_by_lattice > 0 && kept_renumbered.iter().all(|&n| n > 0) && decided_in_turn > 0,
            "{kept_by_lattice} kept, {kept_renumbered:?} kept renumbered, {decided_in_turn} in turn"
        );
    }

    /// A component whose reading has zero details is settled: no other reading is
    /// reversed there. A refined torus in the canonical order costs no reading beyond
    /// its own, renumbered none beyond the first exact one, and beside a moved torus only
    /// the moved one's readings are tried; a moved torus alone still tries them all
    /// (reversed in turn, as where the sums of [`lattice`] do not apply).
    #[test]
    fn an_exact_reading_is_not_compared_with_others() {
        let rules = LoopOptions::default();
        let torus = shapes::torus(6, 4, CellKind::Triangles).unwrap();
        let fine = loop_step(&mesh(&torus), &rules);
        let energy = |level: &ReversedLevel| level.details.iter().map(|d| d.length_squared()).sum::<f64>();
        let readings_of = |soup: &PolygonSoup| {
            MORE_READINGS.set(0);
            let level = reverse(&mesh(soup), &ReverseOptions::default()).unwrap();
            (level, MORE_READINGS.get())
        };
        let (level, more) = readings_of(&fine);
        assert_eq!(more, 0, "canonical and exact: its own reading only");
        assert!(energy(&level) < 1e-24);
        let moved = perturb(&fine, 0.1, 1);
        BY_LATTICE.set(false);
        let (_, more_when_moved) = readings_of(&moved);
        BY_LATTICE.set(true);
        assert!(more_when_moved >= 3, "moved: the other readings are tried ({more_when_moved})");
        for scramble_seed in 0..6 {
            let renumbered = scramble(&fine, scramble_seed);
            let (level, more) = readings_of(&renumbered);
            assert!(energy(&level) < 1e-24, "seed {scramble_seed}");
            // The candidates in turn until an exact one: never the whole list (the lowest
            // vertex or a neighbour is a vertex point of the refinement's reading).
            let [(_, candidates)] =
                &RegularReadings::of(&CornerTable::from_soup(&renumbered).unwrap(), &[]).candidates[..]
            else {
                panic!("one regular component")
            };
            assert!(more < candidates.len(), "seed {scramble_seed}: {more} of {} readings", candidates.len());
            // Beside a moved torus: the exact one is settled, the moved one compared.
            let both = side_by_side(&renumbered, &scramble(&moved, 40 + scramble_seed));
            let (level, _) = readings_of(&both);
            let moved_alone = energy(&readings_of(&scramble(&moved, 40 + scramble_seed)).0);
            assert!((energy(&level) - moved_alone).abs() <= 1e-12 * moved_alone, "seed {scramble_seed}");
        }
        // Two exact tori refined together (canonical, two components): each settled by
        // its own reading, the check of one component seeing two.
        let pair = loop_step(&mesh(&side_by_side(&torus, &torus)), &rules);
        let (level, more) = readings_of(&pair);
        assert_eq!(more, 0, "two exact components: no other reading");
        assert!(energy(&level) < 1e-24);
        let one = |soup: &PolygonSoup| spans_one_component(&CornerTable::from_soup(soup).unwrap());
        assert!(one(&torus) && one(&fine));
        assert!(!one(&side_by_side(&torus, &torus)));
        let mut with_isolated = torus.clone();
        with_isolated.positions.push(DVec3::ZERO);
        assert!(!one(&with_isolated), "an isolated vertex is not on the component");
        // The threshold: round-off of an exact refinement, relative to the scale.
        assert_eq!(zero_energy(2.0, 10), 4e-24 * 10.0);
        assert_eq!(zero_energy(0.0, 1), 0.0, "all vertices at one point: exactly zero only");
        assert!(zero_energy(f64::NAN, 1).is_nan(), "(not finite: never settled)");
    }

    /// The components and candidates as a search from every vertex found them (the
    /// earlier formulation): the union-find and the corner counts must agree with it.
    fn readings_by_search(table: &CornerTable, seeds: &[u32]) -> RegularReadings {
        let vertices = table.vertex_count();
        let mut component = vec![NONE; vertices];
        let mut regular = Vec::new();
        let mut lowest = Vec::new();
        let mut stack = Vec::new();
        let is_regular = |v: u32| match table.visit_star(v, |_, _| {}) {
            VertexStar::Interior { valence } => valence == 6,
            VertexStar::Boundary { valence, .. } => valence == 4,
            VertexStar::Isolated => false,
        };
        for v in 0..vertices as u32 {
            if component[v as usize] != NONE {
                continue;
            }
            let label = regular.len() as u32;
            component[v as usize] = label;
            lowest.push(v);
            let mut all_regular = true;
            stack.push(v);
            while let Some(u) = stack.pop() {
                all_regular &= is_regular(u);
                table.visit_star(u, |_, w| {
                    if component[w as usize] == NONE {
                        component[w as usize] = label;
                        stack.push(w);
                    }
                });
            }
            regular.push(all_regular);
        }
        let neighbours = |v: u32| table.outgoing(v).map(|corner| table.vertex(next(corner))).collect();
        RegularReadings::of_components(neighbours, component, regular, &lowest, seeds)
    }

    #[test]
    fn components_and_candidates_are_those_of_a_search() {
        let rules = LoopOptions::default();
        let torus = loop_step(&mesh(&shapes::torus(6, 4, CellKind::Triangles).unwrap()), &rules);
        let octahedron = loop_step(&mesh(&shapes::octahedron()), &rules);
        let cylinder = loop_step(&mesh(&crate::reference::cylinder(6, 3)), &rules);
        let mut with_isolated = side_by_side(&torus, &cylinder);
        with_isolated.positions.insert(0, DVec3::ZERO);
        for index in &mut with_isolated.indices {
            *index += 1;
        }
        with_isolated.positions.push(DVec3::ONE);
        let soups = [
            torus.clone(),
            octahedron.clone(),
            cylinder.clone(),
            side_by_side(&torus, &octahedron),
            side_by_side(&octahedron, &scramble(&torus, 3)),
            side_by_side(&scramble(&cylinder, 1), &scramble(&torus, 2)),
            with_isolated,
        ];
        // Regular components without a seed, per soup.
        let expected = [1, 0, 1, 1, 1, 2, 2];
        for (i, soup) in soups.iter().enumerate() {
            let table = CornerTable::from_soup(soup).unwrap();
            assert_eq!(RegularReadings::of(&table, &[]).candidates.len(), expected[i], "soup {i}");
            for seeds in [vec![], vec![0], vec![soup.positions.len() as u32 - 1]] {
                let (fast, searched) = (RegularReadings::of(&table, &seeds), readings_by_search(&table, &seeds));
                assert_eq!(fast.component, searched.component, "soup {i}, seeds {seeds:?}");
                assert_eq!(fast.candidates, searched.candidates, "soup {i}, seeds {seeds:?}");
                // From the corners of the half-edge mesh, as `reverse_level` reads them.
                let mesh = HalfedgeMesh::from_soup(soup).unwrap();
                let mesh_corners = CornerTable::mesh_corners(&mesh).unwrap();
                let start = |v| mesh_corners.corner_at(&mesh, v);
                let from_mesh = RegularReadings::of_corners(mesh.vertex_count(), &mesh_corners.corners, start, &seeds);
                assert_eq!(from_mesh.component, searched.component, "soup {i}, seeds {seeds:?}");
                assert_eq!(from_mesh.candidates, searched.candidates, "soup {i}, seeds {seeds:?}");
            }
        }
    }

    /// The readings `reverse_level` compares are reversed without the fused attempt and
    /// with the fine corners read once: each equals `reverse_level_from` with the same
    /// seeds, on a torus in the canonical order and renumbered, moved or not, as a mesh
    /// and as a corner table, for every candidate seed.
    #[test]
    fn readings_with_read_corners_are_those_of_every_path() {
        let rules = LoopOptions::default();
        let fine = loop_step(&mesh(&shapes::torus(6, 4, CellKind::Triangles).unwrap()), &rules);
        let same = |a: &LevelParts, b: &LevelParts| {
            a.coarse == b.coarse && a.order == b.order && a.positions == b.positions && a.details == b.details
        };
        let mut compared = 0;
        for soup in [fine.clone(), perturb(&fine, 0.1, 3), scramble(&fine, 4), scramble(&perturb(&fine, 0.1, 5), 6)] {
            let half_edges = mesh(&soup);
            let table = CornerTable::from_mesh(&half_edges).unwrap();
            let readings = RegularReadings::of(&table, &[]);
            let [(_, candidates)] = &readings.candidates[..] else { panic!("one regular component") };
            for level in [FineLevel::Mesh(&half_edges), FineLevel::Table(&table)] {
                let corners = FineCorners::of(level);
                for &seed in candidates {
                    let searched = match reverse_searched(level, &corners, &soup.positions, &[seed], &rules) {
                        Some(parts) => Ok(parts),
                        None => reverse_level_general(level, &soup.positions, &[seed], &rules),
                    };
                    match (searched, reverse_level_from(level, &soup.positions, &[seed], &rules)) {
                        (Ok(a), Ok(b)) => {
                            assert!(same(&a, &b), "seed {seed}");
                            compared += 1;
                        }
                        (Err(a), Err(b)) => assert_eq!(a, b),
                        (a, b) => panic!("seed {seed}: {:?} vs {:?}", a.is_ok(), b.is_ok()),
                    }
                }
            }
        }
        assert!(compared >= 16, "{compared} readings compared");
    }

    /// `b` beside `a` in one soup: `b`'s vertices after `a`'s, moved away along x.
    fn side_by_side(a: &PolygonSoup, b: &PolygonSoup) -> PolygonSoup {
        let n = a.positions.len() as u32;
        let positions = a.positions.iter().copied().chain(b.positions.iter().map(|&p| p + DVec3::X * 10.0)).collect();
        let faces = a.faces().map(<[u32]>::to_vec).chain(b.faces().map(|f| f.iter().map(|&v| v + n).collect()));
        PolygonSoup::from_faces(positions, faces)
    }

    /// Each component of regular valences gets its own best reading: refined tori beside
    /// each other (and beside a mesh with irregular vertices), each renumbered, give
    /// their tori back with zero details, whatever the numbering; moved, each keeps the
    /// reading of its smallest details, which a seed in the other component does not
    /// change; seeds of one component must agree.
    #[test]
    fn each_component_of_regular_valences_gets_its_best_reading() {
        let rules = LoopOptions::default();
        let torus = shapes::torus(6, 4, CellKind::Triangles).unwrap();
        let fine = loop_step(&mesh(&torus), &rules);
        let octahedron = loop_step(&mesh(&shapes::octahedron()), &rules);
        let energy = |level: &ReversedLevel| level.details.iter().map(|d| d.length_squared()).sum::<f64>();
        for seed in 0..6 {
            let (a, b) = (scramble(&fine, seed), scramble(&fine, 50 + seed));
            for (name, soup) in [
                ("two tori", side_by_side(&a, &b)),
                ("octahedron and torus", side_by_side(&octahedron, &a)),
                ("torus and octahedron", side_by_side(&b, &octahedron)),
            ] {
                let level = reverse(&mesh(&soup), &ReverseOptions::default()).unwrap();
                assert!(energy(&level) < 1e-24, "{name}, seed {seed}: {}", energy(&level));
                let rebuilt = reconstruct(&level.coarse, &level.details, level.order.as_ref(), &rules).unwrap();
                assert!(relative_distance(&rebuilt.to_soup(), &soup) < TOLERANCE, "{name}, seed {seed}");
            }
        }
        // Moved: the energy chosen is the sum over the components of the smallest
        // energy among their seeded readings (each component's read alone).
        for moved_seed in 0..3 {
            let a = scramble(&perturb(&fine, 0.1, moved_seed), 100 + moved_seed);
            let b = scramble(&perturb(&fine, 0.1, 10 + moved_seed), 200 + moved_seed);
            let both = mesh(&side_by_side(&a, &b));
            let chosen = energy(&reverse(&both, &ReverseOptions::default()).unwrap());
            let best_alone = |part: &PolygonSoup| {
                let part = mesh(part);
                let [(_, seeds)] = &RegularReadings::of(&CornerTable::from_mesh(&part).unwrap(), &[]).candidates[..]
                else {
                    panic!("one regular component")
                };
                seeds
                    .iter()
                    .filter_map(|&seed| reverse(&part, &ReverseOptions { rules, seed_vertices: vec![seed] }).ok())
                    .map(|level| energy(&level))
                    .fold(f64::INFINITY, f64::min)
            };
            let expected = best_alone(&a) + best_alone(&b);
            assert!((chosen - expected).abs() <= 1e-12 * expected, "moved {moved_seed}: {chosen} vs {expected}");
            // A seed in the first torus fixes its reading; the second still gets its best.
            let n = a.positions.len() as u32;
            let seeded = reverse(&both, &ReverseOptions { rules, seed_vertices: vec![0] }).unwrap();
            let first_alone = energy(&reverse(&mesh(&a), &ReverseOptions { rules, seed_vertices: vec![0] }).unwrap());
            let expected = first_alone + best_alone(&b);
            assert!((energy(&seeded) - expected).abs() <= 1e-12 * expected, "moved {moved_seed}");
            // Seeds in both components: each fixed.
            let second_seed = n + RegularReadings::of(&CornerTable::from_soup(&b).unwrap(), &[]).candidates[0].1[1];
            let both_seeded = reverse(&both, &ReverseOptions { rules, seed_vertices: vec![0, second_seed] });
            assert!(both_seeded.is_ok() || matches!(both_seeded, Err(LoopError::NotLoopConnectivity { .. })));
        }
        // Two seeds of one component: vertex 0 and one of its neighbours cannot both be
        // vertex points.
        let table = CornerTable::from_soup(&fine).unwrap();
        let neighbour = table.vertex(next(table.outgoing(0).next().unwrap()));
        let error = reverse(&mesh(&fine), &ReverseOptions { rules, seed_vertices: vec![0, neighbour] }).unwrap_err();
        assert!(matches!(error, LoopError::SeedConflict { vertex } if vertex == neighbour), "{error}");
        // Two that can: the same reading as either alone.
        let level = reverse(&mesh(&fine), &ReverseOptions { rules, seed_vertices: vec![0] }).unwrap();
        let coarse_point = level.order.as_ref().map_or(1, |order| order.vertex_of_canonical[1]);
        let both = reverse(&mesh(&fine), &ReverseOptions { rules, seed_vertices: vec![0, coarse_point] }).unwrap();
        assert_eq!(both, level);
        let error = reverse(&mesh(&fine), &ReverseOptions { rules, seed_vertices: vec![0, 10_000] }).unwrap_err();
        assert!(matches!(error, LoopError::SeedOutOfRange { vertex: 10_000, .. }), "{error}");
    }

    /// The fast forward subdivision (`forward::subdivide`) numbers its output canonically:
    /// reversing it gives the coarse mesh back, numbering included, with zero details,
    /// and reconstruction with zero details equals it.
    #[test]
    fn reverse_of_the_fast_forward_is_exact() {
        for (name, soup) in test_shapes() {
            for rules in all_rules() {
                let coarse = mesh(&soup);
                let fine = crate::forward::subdivide(&coarse, 1, &rules).unwrap().to_soup();
                let level = reverse(&mesh(&fine), &ReverseOptions { rules, seed_vertices: Vec::new() })
                    .unwrap_or_else(|e| panic!("{name} {rules:?}: {e}"));
                assert!(level.order.is_none(), "{name}: the forward order is canonical");
                assert!(relative_distance(&level.coarse.to_soup(), &soup) < TOLERANCE, "{name} {rules:?}");
                let diagonal = crate::pyramid::bounding_box_diagonal(&soup.positions);
                assert!(level.details.iter().all(|d| d.length() < TOLERANCE * diagonal), "{name} {rules:?}");
                let zeros = vec![DVec3::ZERO; coarse.edge_count()];
                let rebuilt = reconstruct(&coarse, &zeros, None, &rules).unwrap();
                assert!(relative_distance(&rebuilt.to_soup(), &fine) < TOLERANCE, "{name} {rules:?}");
            }
        }
        // Three levels at once, decomposed back to the base.
        let rules = LoopOptions::default();
        let base = mesh(&bipyramid(7));
        let fine = mesh(&crate::forward::subdivide(&base, 3, &rules).unwrap().to_soup());
        let options =
            crate::pyramid::DecomposeOptions { rules, levels: crate::pyramid::Levels::Max, seed_vertices: Vec::new() };
        let pyramid = crate::pyramid::decompose(&fine, &options).unwrap();
        assert_eq!(pyramid.level_count(), 3);
        assert!(relative_distance(&pyramid.base, &base.to_soup()) < TOLERANCE);
        assert!(pyramid.levels.iter().all(|l| l.order.is_none()));
    }

    /// The doubled-edge check of the fused path: repeats within a vertex's slots, between
    /// its slots and the overflow, and within the overflow; the sums beside it.
    #[test]
    fn edge_sums_find_doubled_edges_in_the_slots_and_the_overflow() {
        let simple = |edges: &[[u32; 2]]| {
            let mut sums = EdgeSums::new(40);
            for (i, &ends) in edges.iter().enumerate() {
                sums.add_edge(ends, DVec3::splat(i as f64));
            }
            (sums.edges_are_simple(), sums.records[0].sum, sums.records[0].valence)
        };
        // 19 edges whose lower end point is vertex 0: 11 of them overflow its slots.
        let fan: Vec<[u32; 2]> = (1..20).map(|v| if v % 2 == 0 { [0, v] } else { [v, 0] }).collect();
        assert_eq!(simple(&fan), (true, DVec3::splat((0..19).sum::<u32>() as f64), 19));
        for repeat in [[3, 0], [0, 8], [0, 9], [15, 0], [0, 19]] {
            let mut doubled = fan.clone();
            doubled.push(repeat);
            assert!(!simple(&doubled).0, "{repeat:?}");
        }
        assert!(!simple(&[[1, 2], [3, 4], [2, 1]]).0);
        assert!(simple(&[[1, 2], [2, 3], [3, 1]]).0);
    }

    #[test]
    fn pillows_are_rejected_by_reverse_and_reconstruct() {
        let pillow = mesh(&PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2], [0, 2, 1]]));
        let zeros = vec![DVec3::ZERO; 3];
        let rules = LoopOptions::default();
        assert!(matches!(reconstruct(&pillow, &zeros, None, &rules), Err(LoopError::InteriorValenceTwo { .. })));
        assert!(matches!(reverse(&pillow, &ReverseOptions::default()), Err(LoopError::InteriorValenceTwo { .. })));
    }

    #[test]
    fn wrong_weights_leave_nonzero_details_but_still_reconstruct() {
        let soup =
            loop_step(&mesh(&bipyramid(7)), &LoopOptions { weights: VertexWeights::Warren, keep_corners: false });
        let fine = mesh(&soup);
        let level = reverse(&fine, &ReverseOptions::default()).unwrap();
        assert!(level.details.iter().any(|d| d.length() > 1e-3));
        let rebuilt =
            reconstruct(&level.coarse, &level.details, level.order.as_ref(), &LoopOptions::default()).unwrap();
        assert!(relative_distance(&rebuilt.to_soup(), &soup) < TOLERANCE);
    }

    #[test]
    fn bad_input_is_an_error() {
        let coarse = mesh(&shapes::octahedron());
        let rules = LoopOptions::default();
        let short = vec![DVec3::ZERO; coarse.edge_count() - 1];
        assert!(matches!(reconstruct(&coarse, &short, None, &rules), Err(LoopError::InvalidDetails { level: 1, .. })));
        let mut nan = vec![DVec3::ZERO; coarse.edge_count()];
        nan[3].y = f64::NAN;
        assert!(matches!(reconstruct(&coarse, &nan, None, &rules), Err(LoopError::InvalidDetails { .. })));
        // Details whose result is beyond `f64` (a vertex at `f64::MAX`, every detail
        // `f64::MAX`: its edge points are about 1.4 times that). Two such details beside
        // vertices near 1 fit, rebuilt at unit scale.
        let huge = vec![DVec3::splat(f64::MAX); coarse.edge_count()];
        let mut far = coarse.clone();
        far.positions_mut()[0] = DVec3::splat(f64::MAX);
        assert!(matches!(reconstruct(&far, &huge, None, &rules), Err(LoopError::NonFiniteResult { .. })));
        let mut two = vec![DVec3::ZERO; coarse.edge_count()];
        two[..2].fill(DVec3::splat(f64::MAX));
        assert!(reconstruct(&coarse, &two, None, &rules).unwrap().positions().iter().all(|p| p.is_finite()));
        let bad_order =
            FineOrder { vertex_of_canonical: vec![0; 18], face_of_canonical: (0..32).map(|k| 3 * k).collect() };
        let zeros = vec![DVec3::ZERO; coarse.edge_count()];
        assert!(matches!(
            reconstruct(&coarse, &zeros, Some(&bad_order), &rules),
            Err(LoopError::InvalidDetails { .. })
        ));
        let quads = mesh(&shapes::cube());
        assert!(matches!(
            reverse(&quads, &ReverseOptions::default()),
            Err(LoopError::NotTriangle { face: 0, corners: 4 })
        ));
        let mut fine = reconstruct(&coarse, &zeros, None, &rules).unwrap();
        fine.positions_mut()[4].x = f64::NAN;
        assert!(matches!(reverse(&fine, &ReverseOptions::default()), Err(LoopError::Mesh(_))));
    }

    /// The two-pass formulation of a canonical step that the kernel's additions replace:
    /// Loop's step, then each detail added to its edge point and, to each vertex point,
    /// its correction from the sum of its details (of its boundary edges on the
    /// boundary) accumulated edge by edge from zero.
    fn two_pass_step(topology: &Topology, positions: &[DVec3], details: &[DVec3], rules: &LoopOptions) -> Vec<DVec3> {
        let kernel_rules = Rules::new(rules);
        let mut fine = kernel::step(topology, positions, &kernel_rules, false).values;
        let nv = topology.vertex_count;
        let (mut sums, mut valences, mut boundary) = (vec![DVec3::ZERO; nv], vec![0usize; nv], vec![false; nv]);
        let mut e = 0;
        for (f, (corners, link)) in topology.triangles.iter().zip(&topology.links).enumerate() {
            for k in 0..3 {
                if link[k] < (4 * f + k) as u32 {
                    continue;
                }
                let on_boundary = link[k] == crate::forward::topology::INVALID;
                for v in [corners[k], corners[(k + 1) % 3]].map(|v| v as usize) {
                    valences[v] += 1;
                    if on_boundary && !boundary[v] {
                        boundary[v] = true;
                        sums[v] = DVec3::ZERO;
                    }
                    if on_boundary || !boundary[v] {
                        sums[v] += details[e];
                    }
                }
                fine[nv + e] += details[e];
                e += 1;
            }
        }
        for v in 0..nv {
            let n = valences[v];
            fine[v] += if boundary[v] {
                if kernel_rules.is_fixed_corner(n) { DVec3::ZERO } else { 0.25 * sums[v] }
            } else if n == 0 {
                DVec3::ZERO
            } else {
                (1.6 * kernel_rules.interior(n).1) * sums[v]
            };
        }
        fine
    }

    /// Reconstruction adds the details inside the forward kernel, from per-vertex sums
    /// made by a branch-free pass: bit for bit the two-pass formulation, at the first
    /// level (walks around every vertex) and the next (odd vertices from their groups),
    /// on closed meshes, boundaries, fixed corners and an isolated vertex, on one thread
    /// and on two (a mesh large enough for the parallel path).
    #[test]
    fn in_kernel_details_equal_the_two_pass_formulation_bit_for_bit() {
        let mut shapes = test_shapes();
        let mut lonely = shapes::grid(2, 2, CellKind::Triangles).unwrap();
        lonely.positions.push(DVec3::new(5.0, -1.0, 0.5));
        shapes.push(("grid with an isolated vertex".to_string(), lonely));
        shapes.push(("grid 48x48".to_string(), shapes::grid(48, 48, CellKind::Triangles).unwrap()));
        let mut rng = crate::reference::Rng::new(99);
        let two_threads = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        for (name, soup) in shapes {
            let base = mesh(&soup);
            for rules in all_rules() {
                // Expected: two levels by the two-pass formulation.
                let mut topology = Topology::from_mesh(&base).unwrap();
                let mut positions = base.positions().to_vec();
                let mut levels = Vec::new();
                for _ in 0..2 {
                    let details: Vec<DVec3> = (0..topology.edge_count).map(|_| 0.1 * rng.vector()).collect();
                    positions = two_pass_step(&topology, &positions, &details, &rules);
                    topology = kernel::refine_topology(&topology);
                    levels.push(details);
                }
                let bits = |p: &[DVec3]| p.iter().flat_map(|q| q.to_array().map(f64::to_bits)).collect::<Vec<_>>();
                let steps = || levels.iter().map(|d| (&d[..], None));
                let one = reconstruct_levels(&base, steps(), &rules).unwrap();
                assert_eq!(bits(&one.positions), bits(&positions), "{name} {rules:?}: one thread");
                let two = two_threads.install(|| reconstruct_levels(&base, steps(), &rules)).unwrap();
                assert_eq!(bits(&two.positions), bits(&positions), "{name} {rules:?}: two threads");
                assert_eq!(one.indices, two.indices);
            }
        }
    }

    /// Non-finite details are named by level and index whether the levels fit their
    /// counts (checked after the steps) or not (checked before each step).
    #[test]
    fn non_finite_details_are_named_before_later_errors() {
        let rules = LoopOptions::default();
        let pyramid = crate::pyramid::LoopPyramid::smooth(shapes::icosahedron(), rules, 3).unwrap();
        let mut nan = pyramid.clone();
        nan.levels[1].details[5].x = f64::NAN;
        let expected = |e: LoopError| matches!(e, LoopError::InvalidDetails { level: 2, ref reason } if reason == "detail 5 is not finite");
        assert!(expected(nan.reconstruct(3).unwrap_err()));
        nan.levels[2].details.pop();
        assert!(expected(nan.reconstruct(3).unwrap_err()));
        let mut short = pyramid.clone();
        short.levels[2].details.pop();
        assert!(matches!(short.reconstruct(3), Err(LoopError::InvalidDetails { level: 3, .. })));
        assert!(short.reconstruct(2).is_ok());
    }

    /// The renumbering path next to the general detection on one mesh: when the
    /// renumbering is found and reverses, the general path must give the very same level
    /// (coarse mesh, positions, details and order, bit for bit).
    fn renumbered_agrees_with_general(fine: &HalfedgeMesh, seed_vertex: Option<u32>, rules: &LoopOptions) -> bool {
        let corners = CornerTable::mesh_corners(fine).expect("triangles");
        let corner_at = |v| corners.corner_at(fine, v);
        let renumbering =
            renumber_to_canonical(fine.vertex_count(), &corners.corners, corner_at, seed_vertex.as_slice());
        let Some(fast) = renumbering.and_then(|r| reverse_renumbered(r, fine.positions(), rules)) else {
            return false;
        };
        let coarsening = detect_table(&CornerTable::from_mesh(fine).unwrap(), seed_vertex.as_slice())
            .expect("the general detection accepts what the renumbering accepts");
        let (positions, details) = reverse_positions(&coarsening, fine.positions(), rules);
        assert_eq!(fast.coarse, coarsening.coarse);
        assert_eq!(fast.order, coarsening.fine_order());
        let bits = |v: &[DVec3]| v.iter().flat_map(|p| p.to_array().map(f64::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&fast.positions), bits(&positions));
        assert_eq!(bits(&fast.details), bits(&details));
        true
    }

    #[test]
    fn renumbering_path_agrees_with_the_general_detection() {
        let rules = LoopOptions::default();
        for (name, soup) in test_shapes() {
            let fine = perturb(&loop_step(&mesh(&soup), &rules), 0.05, 3);
            for seed in [1, 2, 3] {
                let scrambled = mesh(&scramble(&fine, seed));
                // Regular tori are left to the general detection (a search over seeds).
                let found = renumbered_agrees_with_general(&scrambled, None, &rules);
                assert!(found || name.starts_with("torus"), "{name}");
                assert!(renumbered_agrees_with_general(&scrambled, Some(scrambled_vertex_point(&scrambled)), &rules));
            }
        }
    }

    /// A vertex point of a scrambled refinement (from the general detection).
    fn scrambled_vertex_point(fine: &HalfedgeMesh) -> u32 {
        let coarsening = detect_table(&CornerTable::from_mesh(fine).unwrap(), &[]).unwrap();
        *coarsening.vertex_point.last().unwrap()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(96))]

        /// The renumbering path is sound: on refined, renumbered meshes with edges
        /// flipped (most no longer Loop meshes), whatever it accepts the general detection
        /// accepts with the same result, bit for bit.
        #[test]
        fn renumbering_path_is_sound(
            soup in mesh_topo::testing::arb_triangle_mesh(),
            flips in 0usize..3,
            seed in any::<u64>(),
        ) {
            let rules = LoopOptions::default();
            let fine = scramble(&perturb(&loop_step(&mesh(&soup), &rules), 0.05, seed), seed);
            let fine = flip_random_edges(fine, flips, seed);
            let fine = mesh(&fine);
            let accepted = renumbered_agrees_with_general(&fine, None, &rules);
            if flips == 0 {
                // Unless every valence is regular (then the general detection searches).
                prop_assert!(accepted || detect_table(&CornerTable::from_mesh(&fine).unwrap(), &[]).is_ok());
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// reconstruct(reverse(M)) = M on random Loop-connectivity meshes: random meshes
        /// refined by the reference step, every vertex moved at random, renumbered.
        #[test]
        fn reconstruct_inverts_reverse(
            soup in mesh_topo::testing::arb_triangle_mesh(),
            rule in 0usize..4,
            seed in any::<u64>(),
            amount in 0.0..1.0f64,
        ) {
            let rules = all_rules()[rule];
            let fine = scramble(&perturb(&loop_step(&mesh(&soup), &rules), amount, seed), seed ^ 0x5555);
            let level = reverse(&mesh(&fine), &ReverseOptions { rules, seed_vertices: Vec::new() }).unwrap();
            prop_assert_eq!(level.coarse.vertex_count() + level.details.len(), fine.vertex_count());
            let rebuilt = reconstruct(&level.coarse, &level.details, level.order.as_ref(), &rules).unwrap();
            let error = relative_distance(&rebuilt.to_soup(), &fine);
            prop_assert!(error < TOLERANCE, "error {}", error);
        }

        /// reverse(subdivide(C)) = C, numbering included, with all details zero.
        #[test]
        fn reverse_inverts_subdivision(soup in mesh_topo::testing::arb_triangle_mesh(), rule in 0usize..4) {
            let rules = all_rules()[rule];
            let fine = loop_step(&mesh(&soup), &rules);
            let level = reverse(&mesh(&fine), &ReverseOptions { rules, seed_vertices: Vec::new() }).unwrap();
            prop_assert!(relative_distance(&level.coarse.to_soup(), &soup) < TOLERANCE);
            let diagonal = crate::pyramid::bounding_box_diagonal(&soup.positions);
            for d in &level.details {
                prop_assert!(d.length() < TOLERANCE * diagonal);
            }
            prop_assert!(level.order.is_none());
        }

        /// The same on the fast forward's output, two levels.
        #[test]
        fn decompose_inverts_the_fast_forward(soup in mesh_topo::testing::arb_triangle_mesh(), rule in 0usize..4) {
            let rules = all_rules()[rule];
            let fine = crate::forward::subdivide(&mesh(&soup), 2, &rules).unwrap().to_soup();
            let options = crate::pyramid::DecomposeOptions {
                rules,
                levels: crate::pyramid::Levels::Count(2),
                seed_vertices: Vec::new(),
            };
            let pyramid = crate::pyramid::decompose(&mesh(&fine), &options).unwrap();
            prop_assert!(relative_distance(&pyramid.base, &soup) < TOLERANCE);
            let diagonal = crate::pyramid::bounding_box_diagonal(&soup.positions);
            for d in pyramid.levels.iter().flat_map(|l| &l.details) {
                prop_assert!(d.length() < TOLERANCE * diagonal);
            }
        }

        /// Affine invariance: reversing A·M + t gives A·reverse(M) + t and the same
        /// details mapped by A, in the same reading (the moved mesh is seeded at a vertex
        /// point of the first's: on a mesh of regular valences only, the reading with the
        /// smallest details may change under a map that is not a similarity).
        #[test]
        fn reverse_commutes_with_affine_maps(soup in mesh_topo::testing::arb_triangle_mesh(), seed in any::<u64>()) {
            let rules = LoopOptions::default();
            let fine = perturb(&loop_step(&mesh(&soup), &rules), 0.3, seed);
            let map = glam::DMat3::from_cols(DVec3::new(1.0, 0.2, -0.3), DVec3::new(0.1, 0.9, 0.4), DVec3::new(-0.2, 0.3, 1.1));
            let shift = DVec3::new(3.0, -2.0, 0.5);
            let mut moved = fine.clone();
            for p in &mut moved.positions {
                *p = map * *p + shift;
            }
            let a = reverse(&mesh(&fine), &ReverseOptions::default()).unwrap();
            // Coarse vertex 0 is fine vertex 0 in the canonical order, else the order says.
            let vertex_point = a.order.as_ref().map_or(0, |order| order.vertex_of_canonical[0]);
            let seeded = ReverseOptions { rules, seed_vertices: vec![vertex_point] };
            let b = reverse(&mesh(&moved), &seeded).unwrap();
            let mut expected = a.coarse.to_soup();
            for p in &mut expected.positions {
                *p = map * *p + shift;
            }
            prop_assert!(relative_distance(&b.coarse.to_soup(), &expected) < 1e-11);
            for (da, db) in a.details.iter().zip(&b.details) {
                prop_assert!((map * *da).distance(*db) < 1e-11 * (1.0 + da.length()));
            }
        }
    }

    /// Finite coordinates so large that the inverse rules' sums overflow are
    /// [`LoopError::Overflow`] on every path (the canonical, renumbered and general
    /// reversals, a torus whose readings are compared, `decompose` and
    /// `decompose_soup`); `reverse` panicked building the coarse mesh from NaN
    /// positions, and `decompose` returned them. Coordinates up to 1e300 reverse to the
    /// scaled unit result.
    /// Far from 1 a mesh is reversed, decomposed and rebuilt at unit scale: the results
    /// are the unit ones scaled, to the bit (the regular torus reads several ways, so
    /// its choice is exercised too; the rebuilt mesh is the unit rebuild scaled).
    #[test]
    fn reversals_commute_with_powers_of_two() {
        use crate::pyramid::{DecomposeOptions, Levels, decompose, decompose_soup};
        let rules = LoopOptions::default();
        let options = DecomposeOptions { rules, levels: Levels::Max, seed_vertices: Vec::new() };
        for coarse in [shapes::icosahedron(), shapes::torus(6, 4, CellKind::Triangles).unwrap()] {
            let fine = perturb(&crate::forward::subdivide(&mesh(&coarse), 2, &rules).unwrap().into_soup(), 1e-2, 3);
            let unit = reverse(&mesh(&fine), &ReverseOptions::default()).unwrap();
            let unit_pyramid = decompose(&mesh(&fine), &options).unwrap();
            for exponent in [-900, 900] {
                let factor = 2f64.powi(exponent);
                let scale = |points: &[DVec3]| points.iter().map(|p| *p * factor).collect::<Vec<_>>();
                let scaled = PolygonSoup { positions: scale(&fine.positions), ..fine.clone() };
                let level = reverse(&mesh(&scaled), &ReverseOptions::default()).unwrap();
                assert_eq!(level.coarse.positions(), &scale(unit.coarse.positions())[..], "2^{exponent}");
                assert_eq!(level.details, scale(&unit.details));
                let pyramid = decompose(&mesh(&scaled), &options).unwrap();
                assert_eq!(pyramid, decompose_soup(&scaled, &options).unwrap());
                assert_eq!(pyramid.base.positions, scale(&unit_pyramid.base.positions));
                for (a, b) in pyramid.levels.iter().zip(&unit_pyramid.levels) {
                    assert_eq!(a.details, scale(&b.details));
                }
                // Rebuilt as the unit pyramid rebuilds (exact to round-off), scaled.
                let levels = pyramid.level_count();
                let rebuilt = pyramid.reconstruct(levels).unwrap().positions;
                assert_eq!(rebuilt, scale(&unit_pyramid.reconstruct(levels).unwrap().positions));
            }
        }
    }

    #[test]
    fn overflowing_coordinates_are_an_error() {
        use crate::pyramid::{DecomposeOptions, Levels, decompose, decompose_soup};
        let rules = LoopOptions::default();
        let refined = |soup: &PolygonSoup| crate::forward::subdivide(&mesh(soup), 1, &rules).unwrap().into_soup();
        let scaled = |soup: &PolygonSoup, largest: f64| {
            let unit = soup.positions.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
            PolygonSoup { positions: soup.positions.iter().map(|p| *p / unit * largest).collect(), ..soup.clone() }
        };
        let options = DecomposeOptions { rules, levels: Levels::Count(1), seed_vertices: Vec::new() };
        let mut overflows = 0;
        for (name, coarse) in [
            ("icosahedron", shapes::icosahedron()),
            ("open grid", shapes::grid(3, 3, CellKind::Triangles).unwrap()),
            ("regular torus", shapes::torus(6, 4, CellKind::Triangles).unwrap()),
        ] {
            let canonical = perturb(&refined(&coarse), 1e-3, 5);
            for fine in [canonical.clone(), scramble(&canonical, 9)] {
                let unit = reverse(&mesh(&scaled(&fine, 1.0)), &ReverseOptions::default()).unwrap();
                let large = reverse(&mesh(&scaled(&fine, 1e300)), &ReverseOptions::default()).unwrap();
                for (p, q) in large.coarse.positions().iter().zip(unit.coarse.positions()) {
                    assert!((*p / 1e300).distance(*q) < 1e-12, "{name}");
                }
                // Near `f64::MAX`: an overflow, or (reversed at unit scale, where no
                // partial sum overflows) a result that fits and rebuilds the input.
                let huge = scaled(&fine, 1.7e308);
                let rebuilt_level =
                    |level: ReversedLevel| reconstruct(&level.coarse, &level.details, level.order.as_ref(), &rules);
                for result in [
                    reverse(&mesh(&huge), &ReverseOptions::default()).and_then(rebuilt_level).map(|m| m.to_soup()),
                    decompose(&mesh(&huge), &options).and_then(|pyramid| pyramid.reconstruct(1)),
                    decompose_soup(&huge, &options).and_then(|pyramid| pyramid.reconstruct(1)),
                ] {
                    match result {
                        Err(LoopError::Overflow { largest, .. }) => {
                            assert_eq!(largest, 1.7e308, "{name}");
                            overflows += 1;
                        }
                        Ok(rebuilt) => {
                            assert_eq!(rebuilt.indices, huge.indices, "{name}");
                            let error = rebuilt
                                .positions
                                .iter()
                                .zip(&huge.positions)
                                .map(|(p, q)| (*p / 1.7e308 - *q / 1.7e308).abs().max_element());
                            assert!(error.fold(0.0, f64::max) < 1e-12, "{name}");
                        }
                        other => panic!("{name}: {other:?}"),
                    }
                }
            }
        }
        assert!(overflows >= 6, "{overflows}");
    }
}
