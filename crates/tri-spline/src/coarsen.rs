//! The control net by reverse Loop subdivision, and the reverse-Loop map as a matrix.
//!
//! `i` levels of [`subdiv_loop::reverse::reverse`] turn the data mesh into its coarse
//! control net (ALGORITHMS.md §7, §12.4 step 2). The fitting loop of the seed paper
//! applies this reversal to a new point set at every iteration, and the convergence
//! check needs the matrix `R N`; both are cheap once `R` is a sparse matrix. `R` is
//! linear in the positions, and the reversed position of a coarse vertex depends only on
//! its vertex point's closed one-ring in the fine mesh (the inverse vertex rule uses the
//! vertex point and its edge points). So `R` is read off the library's own reversal by
//! probing: colour the fine vertices so that no two of one closed one-ring share a colour
//! (a greedy distance-2 colouring), set the positions to the indicator vectors of three
//! colours at a time (one per coordinate) and reverse; each coarse vertex then reads the
//! weight of every fine vertex of its one-ring from the coordinate of that vertex's
//! colour. This reuses the reversal algorithm rather than re-implementing it, and costs a
//! few reversals per level (about (colours / 3)); the levels compose by sparse products.
//! A test checks `R x == reverse^i(x)` on random positions.

use glam::DVec3;
use mesh_topo::HalfedgeMesh;
use serde::{Deserialize, Serialize};
use subdiv_loop::forward::LoopOptions;
use subdiv_loop::reverse::{ReverseOptions, reverse};

use crate::SplineError;
use crate::linalg::SparseMatrix;

/// The result of `levels` reverse-Loop steps.
#[derive(Debug, Clone, PartialEq)]
pub struct Coarsening {
    /// Number of levels reversed.
    pub levels: u32,
    /// The coarse mesh (its positions are `R` applied to the input positions).
    pub coarse: HalfedgeMesh,
    /// For each coarse vertex, the input vertex it survives as (its vertex point through
    /// all levels).
    pub fine_vertex: Vec<usize>,
    /// `R`: coarse vertices × input vertices.
    pub operator: SparseMatrix,
}

/// Options of the reversal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct CoarsenOptions {
    /// The Loop rules assumed for the data (ALGORITHMS.md §12.4 measures with fixed
    /// corners: `keep_corners = true`, the default here).
    pub rules: LoopOptions,
    /// An input vertex known to be a vertex point at every level (e.g. a corner of a
    /// regular grid); detection chooses when `None`.
    pub seed_vertex: Option<u32>,
}

impl Default for CoarsenOptions {
    fn default() -> Self {
        Self { rules: LoopOptions { keep_corners: true, ..LoopOptions::default() }, seed_vertex: None }
    }
}

/// One level's linear map, by probing (module docs).
fn level_operator(
    fine: &HalfedgeMesh,
    options: &ReverseOptions,
) -> Result<(SparseMatrix, HalfedgeMesh, Vec<usize>), SplineError> {
    let level = reverse(fine, options)?;
    let coarse_count = level.coarse.vertex_count();
    let vertex_point: Vec<usize> = match &level.order {
        Some(order) => order.vertex_of_canonical[..coarse_count].iter().map(|&v| v as usize).collect(),
        None => (0..coarse_count).collect(),
    };
    let n = fine.vertex_count();
    let ring = |v: usize| -> Vec<usize> {
        let id = fine.vertex(v).expect("internal: vertex index");
        std::iter::once(v).chain(fine.vertex_neighbors(id).map(|w| w.index())).collect()
    };
    // Greedy distance-2 colouring: a vertex avoids the colours of every vertex within
    // two edges (which covers every closed one-ring it belongs to).
    let mut colour = vec![u32::MAX; n];
    let mut used: Vec<u32> = Vec::new();
    for v in 0..n {
        used.clear();
        for w in ring(v) {
            for x in ring(w) {
                if colour[x] != u32::MAX {
                    used.push(colour[x]);
                }
            }
        }
        colour[v] = (0..).find(|c| !used.contains(c)).expect("internal: a free colour exists");
    }
    let colours = colour.iter().copied().max().map_or(0, |c| c + 1);
    let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); coarse_count];
    let mut probe = fine.clone();
    for batch in (0..colours).step_by(3) {
        let positions: Vec<DVec3> = colour
            .iter()
            .map(|&c| {
                let mut p = DVec3::ZERO;
                if (batch..batch + 3).contains(&c) {
                    p[(c - batch) as usize] = 1.0;
                }
                p
            })
            .collect();
        probe.replace_positions(positions).expect("internal: same vertex count");
        let reversed = reverse(&probe, options)?;
        for (c, row) in rows.iter_mut().enumerate() {
            let y = reversed.coarse.positions()[c];
            for w in ring(vertex_point[c]) {
                if (batch..batch + 3).contains(&colour[w]) {
                    let weight = y[(colour[w] - batch) as usize];
                    if weight != 0.0 {
                        row.push((w, weight));
                    }
                }
            }
        }
    }
    Ok((SparseMatrix::from_rows(n, rows), level.coarse, vertex_point))
}

/// Reverses `levels` levels of Loop subdivision of `mesh`.
///
/// # Errors
/// [`SplineError::ReverseLevels`] naming how many levels the connectivity allows and why
/// no more (the detection error of the failing level); [`SplineError::Loop`] for other
/// failures of the reversal.
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::forward::{LoopOptions, subdivide};
/// use tri_spline::coarsen::{CoarsenOptions, reverse_loop};
/// let coarse = HalfedgeMesh::from_soup(&shapes::octahedron())?;
/// let fine = subdivide(&coarse, 2, &LoopOptions::default())?.to_halfedge_mesh()?;
/// let c = reverse_loop(&fine, 2, &CoarsenOptions::default())?;
/// assert_eq!(c.coarse.vertex_count(), 6);
/// // Three levels are not possible:
/// assert!(reverse_loop(&fine, 3, &CoarsenOptions::default()).is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn reverse_loop(mesh: &HalfedgeMesh, levels: u32, options: &CoarsenOptions) -> Result<Coarsening, SplineError> {
    let mut current = mesh.clone();
    let mut fine_vertex: Vec<usize> = (0..mesh.vertex_count()).collect();
    let mut operator = SparseMatrix::identity(mesh.vertex_count())?;
    let mut seed = options.seed_vertex;
    for level in 0..levels {
        let reverse_options = ReverseOptions { rules: options.rules, seed_vertices: seed.into_iter().collect() };
        let (step, coarse, vertex_point) = match level_operator(&current, &reverse_options) {
            Ok(result) => result,
            Err(SplineError::Loop(error)) => {
                return Err(SplineError::ReverseLevels {
                    requested: levels,
                    possible: level,
                    reason: error.to_string(),
                });
            }
            Err(other) => return Err(other),
        };
        operator = step.mul(&operator);
        fine_vertex = vertex_point.iter().map(|&v| fine_vertex[v]).collect();
        seed = seed.and_then(|s| vertex_point.iter().position(|&v| v == s as usize)).map(|c| c as u32);
        current = coarse;
    }
    // The probed matrix reproduces the reversal itself (compared at unit scale: far from
    // 1 the lengths overflowed or underflowed and the check passed trivially).
    debug_assert!(
        {
            let unit = mesh_topo::scale::unit_scale(current.positions());
            operator
                .mul_vec(mesh.positions())
                .iter()
                .zip(current.positions())
                .all(|(a, b)| (*a * unit - *b * unit).length() <= 1e-9 * (1.0 + (*b * unit).length()))
        },
        "internal: probed reverse-Loop matrix disagrees with the reversal"
    );
    Ok(Coarsening { levels, coarse: current, fine_vertex, operator })
}

/// How many reverse-Loop levels the connectivity of `mesh` allows (up to `max`), and the
/// reason the next level is impossible.
///
/// ```
/// use mesh_topo::HalfedgeMesh;
/// use tri_spline::coarsen::{CoarsenOptions, possible_levels};
/// use tri_spline::samples::{smooth_surface, triangle_grid};
/// // 8 = 2³ segments per side: three levels down to a single triangle, and no fourth.
/// let mesh = HalfedgeMesh::from_soup(&triangle_grid(8, smooth_surface))?;
/// let (levels, reason) = possible_levels(&mesh, 5, &CoarsenOptions::default());
/// assert_eq!(levels, 3);
/// assert!(reason.is_some());
/// // Capped at `max`, with no reason to report.
/// assert_eq!(possible_levels(&mesh, 2, &CoarsenOptions::default()), (2, None));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn possible_levels(mesh: &HalfedgeMesh, max: u32, options: &CoarsenOptions) -> (u32, Option<String>) {
    let mut current = mesh.clone();
    let mut seed = options.seed_vertex;
    for level in 0..max {
        match reverse(&current, &ReverseOptions { rules: options.rules, seed_vertices: seed.into_iter().collect() }) {
            Ok(reversed) => {
                let count = reversed.coarse.vertex_count();
                let vertex_point: Vec<usize> = match &reversed.order {
                    Some(order) => order.vertex_of_canonical[..count].iter().map(|&v| v as usize).collect(),
                    None => (0..count).collect(),
                };
                seed = seed.and_then(|s| vertex_point.iter().position(|&v| v == s as usize)).map(|c| c as u32);
                current = reversed.coarse;
            }
            Err(error) => return (level, Some(error.to_string())),
        }
    }
    (max, None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_topo::shapes;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use subdiv_loop::forward::{self, subdivide};

    #[test]
    fn probed_matrix_equals_the_reversal_on_random_positions() {
        let base = HalfedgeMesh::from_soup(&shapes::grid(3, 2, shapes::CellKind::Triangles).unwrap()).unwrap();
        let fine = subdivide(&base, 2, &forward::LoopOptions { keep_corners: true, ..Default::default() })
            .unwrap()
            .to_halfedge_mesh()
            .unwrap();
        let c = reverse_loop(&fine, 2, &CoarsenOptions::default()).unwrap();
        assert_eq!(c.coarse.vertex_count(), base.vertex_count());
        // Loop refinement reverses exactly to the base.
        for (p, q) in c.coarse.positions().iter().zip(base.positions()) {
            assert!((*p - *q).length() < 1e-12);
        }
        for (coarse, &fine_v) in c.fine_vertex.iter().enumerate() {
            // Corners are kept, so corner vertex points sit on the base corners.
            let v = base.vertex(coarse).unwrap();
            if base.vertex_faces(v).count() == 1 {
                assert!((fine.positions()[fine_v] - base.positions()[coarse]).length() < 1e-15);
            }
        }
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let random: Vec<DVec3> = (0..fine.vertex_count())
            .map(|_| DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)))
            .collect();
        let mut probe = fine.clone();
        probe.replace_positions(random.clone()).unwrap();
        let direct = reverse_loop(&probe, 2, &CoarsenOptions::default()).unwrap();
        let via_matrix = c.operator.mul_vec(&random);
        for (a, b) in via_matrix.iter().zip(direct.coarse.positions()) {
            assert!((*a - *b).length() < 1e-12, "{a} vs {b}");
        }
        // Rows are affine combinations.
        for i in 0..c.operator.rows() {
            assert!((c.operator.row(i).1.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
    }

    /// Coordinates far from 1 coarsen to the unit result scaled (and the internal check
    /// of the probed matrix, in debug builds, is a real one there: it passed trivially,
    /// `inf <= inf` at 2^900 and `0 <= 1e-9` at 2^-600).
    #[test]
    fn coarsening_does_not_depend_on_the_scale() {
        let base = HalfedgeMesh::from_soup(&shapes::icosahedron()).unwrap();
        let mut fine = subdivide(&base, 2, &forward::LoopOptions::default()).unwrap().to_halfedge_mesh().unwrap();
        for (i, p) in fine.positions_mut().iter_mut().enumerate() {
            p.z += 1e-3 * (i as f64).sin();
        }
        let unit = reverse_loop(&fine, 2, &CoarsenOptions::default()).unwrap();
        for exponent in [-600, 900] {
            let factor = 2f64.powi(exponent);
            let mut scaled = fine.clone();
            scaled.positions_mut().iter_mut().for_each(|p| *p *= factor);
            let c = reverse_loop(&scaled, 2, &CoarsenOptions::default()).unwrap();
            let expected: Vec<DVec3> = unit.coarse.positions().iter().map(|p| *p * factor).collect();
            assert_eq!(c.coarse.positions(), &expected[..], "2^{exponent}");
        }
    }

    #[test]
    fn levels_beyond_the_connectivity_are_reported() {
        let base = HalfedgeMesh::from_soup(&shapes::icosahedron()).unwrap();
        let fine = subdivide(&base, 1, &forward::LoopOptions::default()).unwrap().to_halfedge_mesh().unwrap();
        let options = CoarsenOptions { rules: LoopOptions::default(), seed_vertex: None };
        assert_eq!(possible_levels(&fine, 5, &options).0, 1);
        match reverse_loop(&fine, 2, &options) {
            Err(SplineError::ReverseLevels { requested: 2, possible: 1, .. }) => {}
            other => panic!("{other:?}"),
        }
    }
}
