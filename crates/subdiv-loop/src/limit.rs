//! Limit positions and limit normals of Loop surfaces at the vertices of a mesh.
//!
//! The limit of a vertex under repeated Loop steps is a fixed affine combination of its
//! one-ring (the left eigenvector of eigenvalue 1 of the one-ring subdivision matrix),
//! and the limit tangents are the left eigenvectors of the next eigenvalues. Applied to
//! the mesh of any level (for instance a [`LoopMesh`](crate::forward::LoopMesh) turned
//! into a [`HalfedgeMesh`]), these masks give points and normals *on* the limit surface.
//!
//! # Masks
//! Interior vertex `p` of valence `n` with neighbours `q_0 .. q_{n-1}` counter-clockwise:
//! - position `(1 - n chi) p + chi sum q_j` with `chi = 1 / (3 / (8 beta_n) + n)` (for
//!   Loop's and for Warren's `beta_n`; regular: `p / 2 + sum q_j / 12`);
//! - tangents `t1 = sum cos(2 pi j / n) q_j`, `t2 = sum sin(2 pi j / n) q_j` (Loop 1987),
//!   normal `t1 x t2`.
//!
//! Boundary vertex `p` with neighbours `v_0 .. v_k` counter-clockwise (`v_0`, `v_k` on
//! the boundary, `k` faces):
//! - position `(v_0 + 4 p + v_k) / 6`: the boundary rules are cubic B-spline subdivision
//!   of the boundary polygon, whose limit mask this is; a fixed corner
//!   ([`LoopOptions::keep_corners`], `k = 1`) stays at `p`;
//! - tangent along the boundary `v_0 - v_k` (the B-spline's, eigenvalue 1/2);
//! - tangent across the boundary: the left eigenvector of the boundary one-ring matrix
//!   for the eigenvalue `3/8 + cos(pi / k) / 4` of the interior sine mode, with weights
//!   `sin(i pi / k)` on `v_i` (`0 < i < k`) and weights on `p` and on `v_0 = v_k` solved
//!   from the two remaining eigenvector equations (this gives Hoppe et al.'s mask
//!   `v_1 - p` for `k = 2`); for `k = 1` (one face) the B-spline's second difference
//!   `v_0 + v_1 - 2p`, and for a fixed corner the face's own edges;
//! - normal `t_along x t_across`.
//!
//! Normals follow the face orientation (counter-clockwise faces give normals pointing
//! out of the side they are counter-clockwise from). With Hoppe's boundary rules the
//! second sine mode `3/8 + cos(2 pi / k) / 4` reaches the boundary eigenvalue 1/2 at
//! `k = 6` faces, so from six boundary faces on the limit surface is not tangent-plane
//! continuous at the vertex (Biermann et al. 2000) and the normal given there is that
//! of the two boundary modes; at `k = 4, 5` the surface normals converge to it slowly
//! (ratios 0.75 and 0.90 per level).

use glam::DVec3;
use mesh_topo::{HalfedgeMesh, VertexId};

use crate::LoopError;
use crate::forward::kernel::{loop_beta, warren_beta};
use crate::forward::topology::Topology;
use crate::forward::{LoopOptions, VertexWeights, check_finite_largest, check_no_overflow};

/// Limit positions of all vertices of `mesh` (isolated vertices are returned as they are).
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::forward::LoopOptions;
/// use subdiv_loop::limit::limit_positions;
///
/// let mesh = HalfedgeMesh::from_soup(&shapes::octahedron())?;
/// let limit = limit_positions(&mesh, &LoopOptions::default())?;
/// // Loop surfaces shrink away from convex corners: every limit point lies inside.
/// for (p, q) in limit.iter().zip(mesh.positions()) {
///     assert!(p.length() < q.length() && (p.normalize() - q.normalize()).length() < 1e-12);
/// }
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// [`LoopError::NotTriangle`], [`LoopError::InteriorValenceTwo`] and non-finite
/// positions, as for [`subdivide`](crate::forward::subdivide).
pub fn limit_positions(mesh: &HalfedgeMesh, options: &LoopOptions) -> Result<Vec<DVec3>, LoopError> {
    let largest = check_mesh(mesh)?;
    let positions: Vec<DVec3> = mesh.vertices().map(|v| limit_frame(mesh, v, options).0).collect();
    check_no_overflow(&positions, largest)?;
    Ok(positions)
}

/// Unit limit normals of all vertices of `mesh` (the zero vector for isolated vertices
/// and where the limit tangents are parallel).
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::forward::LoopOptions;
/// use subdiv_loop::limit::limit_normals;
///
/// let mesh = HalfedgeMesh::from_soup(&shapes::octahedron())?;
/// let normals = limit_normals(&mesh, &LoopOptions::default())?;
/// // By symmetry the normal at each vertex points along the vertex direction.
/// for (n, p) in normals.iter().zip(mesh.positions()) {
///     assert!((*n - p.normalize()).length() < 1e-12);
/// }
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// As [`limit_positions`].
pub fn limit_normals(mesh: &HalfedgeMesh, options: &LoopOptions) -> Result<Vec<DVec3>, LoopError> {
    let frames = limit_tangents(mesh, options)?;
    // (At unit scale: the product of tangents far from 1 underflowed to zero, 2^-600,
    // or overflowed, 2^600, and every normal was zero.)
    let normal = |[t1, t2]: [DVec3; 2]| mesh_topo::scale::unit_normal(t1, t2).unwrap_or(DVec3::ZERO);
    Ok(frames.iter().map(|&(_, tangents)| normal(tangents)).collect())
}

/// Limit positions and the two (unnormalized) limit tangents of every vertex: for
/// boundary vertices `[along, across]`, for interior ones `[t1, t2]` as in the
/// [module docs](self). Zero tangents for isolated vertices.
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::forward::LoopOptions;
/// use subdiv_loop::limit::{limit_normals, limit_positions, limit_tangents};
///
/// let mesh = HalfedgeMesh::from_soup(&shapes::icosahedron())?;
/// let options = LoopOptions::default();
/// let frames = limit_tangents(&mesh, &options)?;
/// let (positions, normals) = (limit_positions(&mesh, &options)?, limit_normals(&mesh, &options)?);
/// for (((p, [t1, t2]), q), n) in frames.iter().zip(&positions).zip(&normals) {
///     assert_eq!(p, q);
///     assert_eq!(t1.cross(*t2).normalize(), *n);
///     // By symmetry both tangents are orthogonal to the vertex direction.
///     assert!(t1.dot(*p).abs() < 1e-12 && t2.dot(*p).abs() < 1e-12);
/// }
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// As [`limit_positions`].
pub fn limit_tangents(mesh: &HalfedgeMesh, options: &LoopOptions) -> Result<Vec<(DVec3, [DVec3; 2])>, LoopError> {
    let largest = check_mesh(mesh)?;
    let frames: Vec<(DVec3, [DVec3; 2])> = mesh.vertices().map(|v| limit_frame(mesh, v, options)).collect();
    // Three vectors per vertex: the first that is not finite names its vertex.
    let vectors = frames.iter().flat_map(|(p, [t1, t2])| [p, t1, t2]);
    check_no_overflow(vectors, largest).map_err(|error| match error {
        LoopError::Overflow { vertex, largest } => LoopError::Overflow { vertex: vertex / 3, largest },
        other => other,
    })?;
    Ok(frames)
}

/// The checks of `subdivide`: triangles, finite positions, no pillows; the largest
/// coordinate magnitude (see [`check_no_overflow`]).
fn check_mesh(mesh: &HalfedgeMesh) -> Result<f64, LoopError> {
    let largest = check_finite_largest(mesh.positions())?;
    Topology::from_mesh(mesh)?;
    Ok(largest)
}

/// Across-boundary tangent weights for a boundary vertex with `k >= 2` faces:
/// `(w_p, w_end, [w_1 .. w_{k-1}])`.
pub(crate) fn across_mask(k: usize) -> (f64, f64, Vec<f64>) {
    let theta = std::f64::consts::PI / k as f64;
    let interior: Vec<f64> = (1..k).map(|i| (i as f64 * theta).sin()).collect();
    let sum: f64 = interior.iter().sum();
    let mu = 0.375 + 0.25 * theta.cos();
    // (3/4 - mu) w_p + w_end = -3/8 sum;  1/8 w_p + (1/2 - mu) w_end = -1/8 s_1.
    let (a11, a12, b1) = (0.75 - mu, 1.0, -0.375 * sum);
    let (a21, a22, b2) = (0.125, 0.5 - mu, -0.125 * interior[0]);
    let det = a11 * a22 - a12 * a21;
    let w_p = (b1 * a22 - a12 * b2) / det;
    let w_end = (a11 * b2 - a21 * b1) / det;
    (w_p, w_end, interior)
}

/// Limit position and tangents of one vertex.
fn limit_frame(mesh: &HalfedgeMesh, v: VertexId, options: &LoopOptions) -> (DVec3, [DVec3; 2]) {
    let p = mesh.position(v);
    if mesh.is_isolated(v) {
        return (p, [DVec3::ZERO; 2]);
    }
    // Neighbours counter-clockwise; for a boundary vertex the circulation starts at the
    // outgoing boundary half-edge, whose target is the last fan vertex v_k, and ends
    // with the first fan vertex v_0.
    let ring: Vec<DVec3> = mesh.vertex_neighbors(v).map(|q| mesh.position(q)).collect();
    let n = ring.len();
    if !mesh.is_boundary_vertex(v) {
        let beta = match options.weights {
            VertexWeights::Loop => loop_beta(n),
            VertexWeights::Warren => warren_beta(n),
        };
        let chi = 1.0 / (3.0 / (8.0 * beta) + n as f64);
        let mut position = (1.0 - n as f64 * chi) * p;
        let (mut t1, mut t2) = (DVec3::ZERO, DVec3::ZERO);
        for (j, q) in ring.iter().enumerate() {
            position += chi * *q;
            let angle = std::f64::consts::TAU * j as f64 / n as f64;
            t1 += angle.cos() * *q;
            t2 += angle.sin() * *q;
        }
        return (position, [t1, t2]);
    }
    // Reorder as v_0 .. v_k (fan order).
    let fan: Vec<DVec3> = ring[1..].iter().chain(&ring[..1]).copied().collect();
    let k = n - 1;
    let (first, last) = (fan[0], fan[k]);
    if options.keep_corners && k == 1 {
        return (p, [first - p, last - p]);
    }
    let position = (first + 4.0 * p + last) / 6.0;
    let along = first - last;
    let across = if k == 1 {
        first + last - 2.0 * p
    } else {
        let (w_p, w_end, interior) = across_mask(k);
        let mut t = w_p * p + w_end * (first + last);
        for (w, q) in interior.iter().zip(&fan[1..k]) {
            t += *w * *q;
        }
        t
    };
    (position, [along, across])
}

#[cfg(test)]
mod tests {
    use mesh_topo::PolygonSoup;
    use mesh_topo::shapes::{self, CellKind};
    use mesh_topo::testing::scramble;

    use super::*;
    use crate::forward::subdivide;

    /// Normals do not depend on the scale: at 2^-600 the tangents' cross products
    /// underflowed and at 2^600 overflowed, and every normal was zero.
    #[test]
    fn normals_do_not_depend_on_the_scale() {
        let options = LoopOptions::default();
        let mut soup = shapes::icosahedron();
        for (i, p) in soup.positions.iter_mut().enumerate() {
            p.x += 0.1 * (i as f64).sin();
        }
        let unit = limit_normals(&HalfedgeMesh::from_soup(&soup).unwrap(), &options).unwrap();
        assert!(unit.iter().all(|n| (n.length() - 1.0).abs() < 1e-15));
        for exponent in [-600, 600] {
            let factor = 2f64.powi(exponent);
            let scaled =
                PolygonSoup { positions: soup.positions.iter().map(|p| *p * factor).collect(), ..soup.clone() };
            let normals = limit_normals(&HalfedgeMesh::from_soup(&scaled).unwrap(), &options).unwrap();
            assert_eq!(normals, unit, "2^{exponent}");
        }
    }

    /// The disk of the `rings`-ring around `v` (`rings >= 1`): the faces touching a
    /// vertex closer than `rings` edges to `v`, renumbered; returns the soup and the new
    /// index of `v`.
    fn disk(mesh: &HalfedgeMesh, v: VertexId, rings: usize) -> (PolygonSoup, u32) {
        let closer = mesh.ring_distances(v, rings - 1);
        let (soup, new_index) = mesh.extract_faces(|f| mesh.face_vertices(f).any(|c| closer[c.index()].is_some()));
        (soup, new_index[v.index()].expect("the disk holds its centre"))
    }

    /// Subdivides the `rings`-disk around `v` `levels` times, cutting it back to the
    /// disk after every step (the one- and two-ring of a vertex are invariant under
    /// Loop's rules, so this is exact around `v` and cheap). `None` if a cut disk is not
    /// a manifold (it can pinch where it meets the mesh boundary).
    fn local_refinement(
        mesh: &HalfedgeMesh,
        v: VertexId,
        rings: usize,
        levels: u32,
        options: &LoopOptions,
    ) -> Option<(HalfedgeMesh, VertexId)> {
        let (soup, mut center) = disk(mesh, v, rings);
        let mut local = HalfedgeMesh::from_soup(&soup).ok()?;
        for _ in 0..levels {
            let fine = subdivide(&local, 1, options).unwrap().to_halfedge_mesh().unwrap();
            let (soup, c) = disk(&fine, fine.vertex(center as usize).unwrap(), rings);
            local = HalfedgeMesh::from_soup(&soup).ok()?;
            center = c;
        }
        let center = local.vertex(center as usize).unwrap();
        Some((local, center))
    }

    fn test_meshes() -> Vec<HalfedgeMesh> {
        [
            scramble(shapes::icosahedron(), 1, 0.15),
            scramble(shapes::grid(6, 5, CellKind::Triangles).unwrap(), 2, 0.2),
            scramble(shapes::torus(8, 7, CellKind::Triangles).unwrap(), 3, 0.1),
            scramble(shapes::tetrahedron(), 4, 0.1),
        ]
        .iter()
        .chain(&[
            without_first_face(scramble(shapes::icosahedron(), 5, 0.1)),
            without_first_face(scramble(shapes::torus(8, 7, CellKind::Triangles).unwrap(), 6, 0.1)),
        ])
        .map(|s| HalfedgeMesh::from_soup(s).unwrap())
        .collect()
    }

    /// A hole: boundary vertices with 4 (icosahedron) or 5 (torus) faces.
    fn without_first_face(soup: PolygonSoup) -> PolygonSoup {
        PolygonSoup::from_faces(soup.positions.clone(), soup.faces().skip(1))
    }

    #[test]
    fn twelve_steps_reach_the_limit_position() {
        for options in [
            LoopOptions::default(),
            LoopOptions::warren_weights(),
            LoopOptions { keep_corners: true, ..LoopOptions::default() },
        ] {
            for mesh in test_meshes() {
                let limit = limit_positions(&mesh, &options).unwrap();
                for v in mesh.vertices() {
                    let (local, center) = local_refinement(&mesh, v, 1, 12, &options).unwrap();
                    let error = (local.position(center) - limit[v.index()]).length();
                    assert!(error < 1e-6, "vertex {v:?} (valence {}): {error:e}", mesh.valence(v));
                }
            }
        }
    }

    #[test]
    fn limit_normals_match_the_refined_surface() {
        // Finite differences on the limit surface itself: after several local steps,
        // the limit points of the vertex and of its tiny one-ring span the tangent plane.
        let options = LoopOptions::default();
        let (mut checked, mut boundary, mut total) = (0, 0, 0);
        for mesh in test_meshes() {
            let normals = limit_normals(&mesh, &options).unwrap();
            for v in mesh.vertices() {
                total += 1;
                // With 5 boundary faces the error shrinks only by 0.9 per level (and
                // with 6 or more the boundary normal is not the limit of the surface's,
                // see the module docs): left to the invariance test.
                if mesh.is_boundary_vertex(v) && mesh.valence(v) >= 6 {
                    continue;
                }
                let Some((local, center)) = local_refinement(&mesh, v, 2, 7, &options) else { continue };
                let points = limit_positions(&local, &options).unwrap();
                let ring: Vec<DVec3> = local.vertex_neighbors(center).map(|q| points[q.index()]).collect();
                let c = points[center.index()];
                let mut estimate = DVec3::ZERO;
                // Counter-clockwise neighbour pairs that span a face (for a boundary
                // vertex the circulation starts with the last fan vertex).
                let skip = usize::from(local.is_boundary_vertex(center));
                for j in skip..ring.len() {
                    estimate += (ring[j] - c).cross(ring[(j + 1) % ring.len()] - c);
                }
                let angle = estimate.normalize().dot(normals[v.index()]).clamp(-1.0, 1.0).acos();
                // Boundary vertices with 4 or more faces converge slowly: the error
                // shrinks like (3/8) / (1/2) per level (second sine mode over the
                // boundary eigenvalue); exactness is checked by the invariance test.
                let tolerance = if skip == 1 && mesh.valence(v) >= 5 { 5e-2 } else { 2e-3 };
                assert!(
                    angle < tolerance,
                    "vertex {v:?} (valence {}, boundary {}): {angle}",
                    mesh.valence(v),
                    mesh.is_boundary_vertex(v)
                );
                checked += 1;
                boundary += skip;
            }
        }
        assert!(checked * 10 >= total * 9 && boundary >= 8, "{checked} of {total} checked, {boundary} on the boundary");
    }

    #[test]
    fn limits_are_invariant_under_subdivision() {
        // The masks are left eigenvectors of the subdivision matrix: applied one level
        // finer they give the same point and the same tangent plane.
        for options in [
            LoopOptions::default(),
            LoopOptions::warren_weights(),
            LoopOptions { keep_corners: true, ..LoopOptions::default() },
        ] {
            for mesh in test_meshes() {
                let fine = subdivide(&mesh, 1, &options).unwrap().to_halfedge_mesh().unwrap();
                let (p0, n0) = (limit_positions(&mesh, &options).unwrap(), limit_normals(&mesh, &options).unwrap());
                let (p1, n1) = (limit_positions(&fine, &options).unwrap(), limit_normals(&fine, &options).unwrap());
                for v in 0..mesh.vertex_count() {
                    assert!((p0[v] - p1[v]).length() < 1e-13, "position of {v}");
                    assert!((n0[v] - n1[v]).length() < 1e-12, "normal of {v}: {} vs {}", n0[v], n1[v]);
                }
            }
        }
    }

    #[test]
    fn regular_limit_mask_and_boundary_masks() {
        // Regular interior: p/2 + sum/12 for both weight variants.
        let mesh =
            HalfedgeMesh::from_soup(&scramble(shapes::torus(6, 6, CellKind::Triangles).unwrap(), 9, 0.1)).unwrap();
        for options in [LoopOptions::default(), LoopOptions::warren_weights()] {
            let limit = limit_positions(&mesh, &options).unwrap();
            for v in mesh.vertices() {
                let sum: DVec3 = mesh.vertex_neighbors(v).map(|q| mesh.position(q)).sum();
                assert!((limit[v.index()] - (mesh.position(v) / 2.0 + sum / 12.0)).length() < 1e-14);
            }
        }
        // k = 2: Hoppe et al.'s mask v_1 - p; every mask annihilates constants.
        let (w_p, w_end, interior) = across_mask(2);
        assert!((w_p + 1.0).abs() < 1e-15 && w_end.abs() < 1e-15 && (interior[0] - 1.0).abs() < 1e-15);
        for k in 2..12 {
            let (w_p, w_end, interior) = across_mask(k);
            assert!((w_p + 2.0 * w_end + interior.iter().sum::<f64>()).abs() < 1e-12, "k = {k}");
        }
    }

    #[test]
    fn bad_input_is_rejected() {
        let quads = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        assert!(matches!(
            limit_positions(&quads, &LoopOptions::default()),
            Err(LoopError::NotTriangle { face: 0, .. })
        ));
        let mut mesh = HalfedgeMesh::from_soup(&shapes::octahedron()).unwrap();
        mesh.positions_mut()[0].x = f64::INFINITY;
        assert!(limit_normals(&mesh, &LoopOptions::default()).is_err());
    }
}
