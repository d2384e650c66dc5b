//! Parameterization of a disk-topology triangle mesh over the domain triangle.
//!
//! * A mesh made by regular subdivision of a triangle (a regular triangular grid:
//!   three boundary corners with one face each, other boundary vertices of valence 4,
//!   interior vertices of valence 6, and lattice coordinates consistent on every face)
//!   gets its natural barycentric parameters: grid vertex `(j, k)` of an `N`-segment grid
//!   maps to `((N - j - k)/N, j/N, k/N)`. Corner 0 is the corner of smallest index;
//!   corners 1 and 2 follow counter-clockwise.
//! * Any other disk gets a convex-combination map (W. T. Tutte 1963; M. S. Floater 1997,
//!   2003): the boundary is split at three corner vertices and laid on the three edges
//!   of the domain triangle by chord length, and every interior vertex is the weighted
//!   average of its neighbours, with uniform or mean-value weights
//!   `w_ij = (tan(α_ij/2) + tan(β_ij/2)) / |x_i - x_j|`. Both weightings are positive, so
//!   for a convex boundary the map is an embedding (Tutte, Floater); the result is still
//!   checked face by face.
//!
//! The sparse system (interior vertices × interior vertices, two right-hand sides) is
//! solved by faer's sparse LU with partial pivoting (a direct solver: no tolerance to
//! tune, robust for the non-symmetric mean-value matrix), run sequentially so that the
//! parameters do not depend on the thread count.
//!
//! Corners: given by the caller, or chosen automatically: boundary vertices that are
//! the tip of an ear (one incident face) must be corners, else that face maps to a
//! segment; the rest are placed at a third and two thirds of the boundary length from
//! the first, optionally restricted to allowed vertices (the fitting pipeline allows
//! only vertices that survive the reverse-Loop levels).
//!
//! Closed meshes, meshes with holes or several components, non-triangle faces and
//! isolated vertices are typed errors, as are faces mapped to degenerate or flipped
//! triangles.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Par};
use glam::{DVec2, DVec3};
use mesh_topo::{HalfedgeMesh, VertexId};
use serde::{Deserialize, Serialize};

use crate::SplineError;
use crate::domain::{DomainTriangle, is_degenerate, orient};

/// Weights of the convex-combination map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum TutteWeights {
    /// Every neighbour counts the same (Tutte's barycentric embedding).
    Uniform,
    /// Floater's mean-value weights (closer to the mesh's own shape).
    #[default]
    MeanValue,
}

/// Options of [`parameterize`].
#[derive(Debug, Clone, PartialEq)]
pub struct ParamOptions {
    /// The domain triangle (default: [`DomainTriangle::equilateral`]).
    pub domain: DomainTriangle,
    /// Weights of the convex-combination map.
    pub weights: TutteWeights,
    /// Recognise regular triangular grids and give them their natural parameters.
    pub detect_grid: bool,
    /// Corner vertices, mapped to the domain corners in this order (counter-clockwise
    /// along the boundary); chosen automatically when `None`.
    pub corners: Option<[usize; 3]>,
    /// When choosing corners automatically, only vertices with `true` here may be corners.
    pub corner_allowed: Option<Vec<bool>>,
}

impl Default for ParamOptions {
    fn default() -> Self {
        Self {
            domain: DomainTriangle::equilateral(),
            weights: TutteWeights::default(),
            detect_grid: true,
            corners: None,
            corner_allowed: None,
        }
    }
}

/// How the parameters were obtained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ParamKind {
    /// Natural parameters of a regular triangular grid with `segments` per side;
    /// `coords[v] = (j, k)` are the lattice coordinates of vertex `v`.
    RegularGrid {
        /// Segments per side `N`.
        segments: usize,
        /// Lattice coordinates `(j, k)` of every vertex.
        coords: Vec<(u32, u32)>,
    },
    /// A convex-combination map.
    ConvexCombination {
        /// The weights used.
        weights: TutteWeights,
    },
}

/// Parameters of a mesh's vertices over the domain triangle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Parameterization {
    /// One parameter per mesh vertex.
    pub params: Vec<DVec2>,
    /// The domain triangle.
    pub domain: DomainTriangle,
    /// The vertices mapped to the domain's corners.
    pub corners: [usize; 3],
    /// How the parameters were obtained.
    pub kind: ParamKind,
}

/// The boundary of a disk-topology triangle mesh, counter-clockwise (interior on the
/// left), after checking that the mesh is one.
///
/// # Errors
/// [`SplineError::NotTriangle`], [`SplineError::IsolatedVertex`],
/// [`SplineError::NotDisk`] (closed, holes, several components).
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use tri_spline::SplineError;
/// use tri_spline::param::disk_boundary;
/// use tri_spline::samples::{smooth_surface, triangle_grid};
/// // A grid with 4 segments per side: 15 vertices, 3 of them interior.
/// let mesh = HalfedgeMesh::from_soup(&triangle_grid(4, smooth_surface))?;
/// let boundary = disk_boundary(&mesh)?;
/// assert_eq!(boundary.len(), 12);
/// // Counter-clockwise: positive signed area in the (x, y) plane of the grid.
/// let p = mesh.positions();
/// let area: f64 = (0..12).map(|i| p[boundary[i]].truncate().perp_dot(p[boundary[(i + 1) % 12]].truncate())).sum();
/// assert!(area > 0.0);
/// let closed = HalfedgeMesh::from_soup(&shapes::octahedron())?;
/// assert!(matches!(disk_boundary(&closed), Err(SplineError::NotDisk { boundary_loops: 0, .. })));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn disk_boundary(mesh: &HalfedgeMesh) -> Result<Vec<usize>, SplineError> {
    if let Some(f) = mesh.faces().find(|&f| mesh.face_degree(f) != 3) {
        return Err(SplineError::NotTriangle { face: f.index(), corners: mesh.face_degree(f) });
    }
    if let Some(v) = mesh.vertices().find(|&v| mesh.is_isolated(v)) {
        return Err(SplineError::IsolatedVertex { vertex: v.index() });
    }
    let stats = mesh.topology_stats();
    let loops = mesh.boundary_loops();
    let components = mesh.connected_components().count;
    if components != 1 || loops.len() != 1 || stats.euler != 1 {
        let hint = if loops.is_empty() {
            "a closed mesh has no boundary to map onto a triangle; cut it into disk charts first"
        } else if components != 1 {
            "fit each component separately"
        } else {
            "holes (extra boundary loops) or handles must be cut or filled first"
        };
        return Err(SplineError::NotDisk { components, boundary_loops: loops.len(), euler: stats.euler, hint });
    }
    // Boundary half-edges have the hole on their left, so they run clockwise around the
    // mesh; the counter-clockwise order is their reverse.
    let mut boundary: Vec<usize> = loops[0].iter().map(|&h| mesh.origin(h).index()).collect();
    boundary.reverse();
    Ok(boundary)
}

/// Lattice directions in counter-clockwise order (grid axes `t1 - t0`, `t2 - t0`).
const DIRECTIONS: [(i64, i64); 6] = [(1, 0), (0, 1), (-1, 1), (-1, 0), (0, -1), (1, -1)];

/// The lattice structure of a regular triangular grid.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RegularGrid {
    /// Segments per side `N`.
    pub segments: usize,
    /// Lattice coordinates `(j, k)` of every vertex (`j + k <= N`).
    pub coords: Vec<(u32, u32)>,
    /// The vertices at `(0, 0)`, `(N, 0)`, `(0, N)`.
    pub corners: [usize; 3],
}

/// Recognises a regular triangular grid (module docs); `None` if the mesh is not one.
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes::{self, CellKind}};
/// use tri_spline::index::tri_index;
/// use tri_spline::param::detect_regular_grid;
/// use tri_spline::samples::{smooth_surface, triangle_grid};
/// let mesh = HalfedgeMesh::from_soup(&triangle_grid(8, smooth_surface))?;
/// let grid = detect_regular_grid(&mesh).unwrap();
/// assert_eq!(grid.segments, 8);
/// assert_eq!(grid.corners, [0, 8, 44]);
/// // `triangle_grid` stores vertex (j, k) at position tri_index(8, j, k).
/// assert!(grid.coords.iter().enumerate().all(|(v, &(j, k))| tri_index(8, j as usize, k as usize) == v));
/// // A square grid is a disk, but not a triangular grid.
/// assert!(detect_regular_grid(&HalfedgeMesh::from_soup(&shapes::grid(4, 3, CellKind::Triangles)?)?).is_none());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn detect_regular_grid(mesh: &HalfedgeMesh) -> Option<RegularGrid> {
    let nv = mesh.vertex_count();
    let mut corners = Vec::new();
    for v in mesh.vertices() {
        let faces = mesh.vertex_faces(v).count();
        let valence = mesh.valence(v);
        match (mesh.is_boundary_vertex(v), faces, valence) {
            (true, 1, 2) => corners.push(v),
            (true, 3, 4) | (false, 6, 6) => {}
            _ => return None,
        }
    }
    if corners.len() != 3 {
        return None;
    }
    let c0 = corners[0];
    let face = mesh.vertex_faces(c0).next()?;
    let ring: Vec<VertexId> = mesh.face_vertices(face).collect();
    let at = ring.iter().position(|&v| v == c0)?;
    let (x, y) = (ring[(at + 1) % 3], ring[(at + 2) % 3]);
    let mut coords: Vec<Option<(i64, i64)>> = vec![None; nv];
    coords[c0.index()] = Some((0, 0));
    coords[x.index()] = Some((1, 0));
    coords[y.index()] = Some((0, 1));
    let mut queue = std::collections::VecDeque::from([c0, x, y]);
    let mut queued = vec![false; nv];
    for v in [c0, x, y] {
        queued[v.index()] = true;
    }
    while let Some(v) = queue.pop_front() {
        let here = coords[v.index()]?;
        let mut neighbours: Vec<VertexId> = mesh.vertex_neighbors(v).collect();
        if mesh.is_boundary_vertex(v) {
            // The circulator starts at the boundary half-edge, the last one of the fan
            // counter-clockwise; rotate it to the end so that consecutive neighbours
            // share a face.
            neighbours.rotate_left(1);
        }
        let (p, dir) = neighbours.iter().enumerate().find_map(|(p, w)| {
            let there = coords[w.index()]?;
            let d = (there.0 - here.0, there.1 - here.1);
            DIRECTIONS.iter().position(|&e| e == d).map(|i| (p, i))
        })?;
        for (q, w) in neighbours.iter().enumerate() {
            let step = DIRECTIONS[(dir as i64 + q as i64 - p as i64).rem_euclid(6) as usize];
            let c = (here.0 + step.0, here.1 + step.1);
            match coords[w.index()] {
                Some(old) if old != c => return None,
                Some(_) => {}
                None => coords[w.index()] = Some(c),
            }
            if !queued[w.index()] {
                queued[w.index()] = true;
                queue.push_back(*w);
            }
        }
    }
    let coords: Vec<(i64, i64)> = coords.into_iter().collect::<Option<_>>()?;
    let segments = coords.iter().map(|&(j, k)| j + k).max()?;
    if segments <= 0 || nv != ((segments + 1) * (segments + 2) / 2) as usize {
        return None;
    }
    let mut seen = vec![false; nv];
    for &(j, k) in &coords {
        if j < 0 || k < 0 || j + k > segments {
            return None;
        }
        let slot = crate::index::tri_index(segments as usize, j as usize, k as usize);
        if std::mem::replace(&mut seen[slot], true) {
            return None;
        }
    }
    for f in mesh.faces() {
        let c: Vec<(i64, i64)> = mesh.face_vertices(f).map(|v| coords[v.index()]).collect();
        let cross = (c[1].0 - c[0].0) * (c[2].1 - c[0].1) - (c[1].1 - c[0].1) * (c[2].0 - c[0].0);
        if cross != 1 {
            return None;
        }
    }
    let corner_at = |target: (i64, i64)| coords.iter().position(|&c| c == target);
    let corners = [corner_at((0, 0))?, corner_at((segments, 0))?, corner_at((0, segments))?];
    let coords = coords.into_iter().map(|(j, k)| (j as u32, k as u32)).collect();
    Some(RegularGrid { segments: segments as usize, coords, corners })
}

/// Parameterizes a disk-topology triangle mesh over `options.domain`.
///
/// # Errors
/// As [`disk_boundary`]; [`SplineError::ShortBoundary`] for fewer than 3 boundary
/// vertices; [`SplineError::BadCorner`] for given corners that are not distinct boundary
/// vertices; [`SplineError::DegenerateParameterTriangle`] naming a face mapped to a
/// degenerate or flipped triangle (e.g. an ear whose tip is not a corner);
/// [`SplineError::Singular`] if the sparse solve fails.
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes::{self, CellKind}};
/// use tri_spline::param::{ParamKind, ParamOptions, parameterize};
/// // A 4 x 3 planar grid is a disk but not a triangle grid: convex-combination map.
/// let mesh = HalfedgeMesh::from_soup(&shapes::grid(4, 3, CellKind::Triangles)?)?;
/// let p = parameterize(&mesh, &ParamOptions::default())?;
/// assert!(matches!(p.kind, ParamKind::ConvexCombination { .. }));
/// assert_eq!(p.params.len(), mesh.vertex_count());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn parameterize(mesh: &HalfedgeMesh, options: &ParamOptions) -> Result<Parameterization, SplineError> {
    let boundary = disk_boundary(mesh)?;
    if let Some(index) = mesh.positions().iter().position(|p| !p.is_finite()) {
        return Err(SplineError::NonFinite { what: "vertex position", index });
    }
    let domain = options.domain;
    if options.detect_grid
        && options.corners.is_none()
        && let Some(RegularGrid { segments, coords, corners }) = detect_regular_grid(mesh)
    {
        let s = segments as f64;
        let params = coords
            .iter()
            .map(|&(j, k)| {
                let (j, k) = (j as f64, k as f64);
                domain.point([(s - j - k) / s, j / s, k / s])
            })
            .collect();
        return Ok(Parameterization { params, domain, corners, kind: ParamKind::RegularGrid { segments, coords } });
    }
    if boundary.len() < 3 {
        return Err(SplineError::ShortBoundary { len: boundary.len() });
    }
    let corners = match options.corners {
        Some(c) => c,
        None => choose_corners(mesh, &boundary, options.corner_allowed.as_deref())?,
    };
    let mut positions_on_boundary = vec![usize::MAX; mesh.vertex_count()];
    for (i, &v) in boundary.iter().enumerate() {
        positions_on_boundary[v] = i;
    }
    let mut corner_at = [0usize; 3];
    for (slot, &c) in corners.iter().enumerate() {
        let pos = *positions_on_boundary.get(c).ok_or(SplineError::BadCorner { vertex: c })?;
        if pos == usize::MAX || corners[..slot].contains(&c) {
            return Err(SplineError::BadCorner { vertex: c });
        }
        corner_at[slot] = pos;
    }
    // The corners must appear counter-clockwise along the boundary in the given order.
    let len = boundary.len();
    let rel = |p: usize| (p + len - corner_at[0]) % len;
    if rel(corner_at[1]) >= rel(corner_at[2]) {
        return Err(SplineError::BadCorner { vertex: corners[2] });
    }
    let x = mesh.positions();
    let mut params = vec![DVec2::ZERO; mesh.vertex_count()];
    let dc = domain.corners();
    for side in 0..3 {
        let (from, to) = (corner_at[side], corner_at[(side + 1) % 3]);
        let steps = (to + len - from) % len;
        let run: Vec<usize> = (0..=steps).map(|s| boundary[(from + s) % len]).collect();
        let lengths: Vec<f64> = run.windows(2).map(|w| (x[w[1]] - x[w[0]]).length()).collect();
        let total: f64 = lengths.iter().sum();
        let mut acc = 0.0;
        for (s, &v) in run.iter().enumerate() {
            let t = if total > 0.0 { acc / total } else { s as f64 / steps as f64 };
            params[v] = dc[side].lerp(dc[(side + 1) % 3], t);
            if s < lengths.len() {
                acc += lengths[s];
            }
        }
    }
    solve_interior(mesh, options.weights, &positions_on_boundary, &mut params)?;
    check_faces(mesh, &params, &positions_on_boundary)?;
    Ok(Parameterization { params, domain, corners, kind: ParamKind::ConvexCombination { weights: options.weights } })
}

/// Automatic corners (module docs).
fn choose_corners(
    mesh: &HalfedgeMesh,
    boundary: &[usize],
    allowed: Option<&[bool]>,
) -> Result<[usize; 3], SplineError> {
    let x = mesh.positions();
    let len = boundary.len();
    let vertex = |i: usize| mesh.vertex(i).expect("internal: vertex index");
    let ears: Vec<usize> = (0..len).filter(|&i| mesh.vertex_faces(vertex(boundary[i])).count() == 1).collect();
    if ears.len() > 3 {
        let face = mesh.vertex_faces(vertex(boundary[ears[3]])).next().expect("internal: ear face").index();
        return Err(SplineError::DegenerateParameterTriangle {
            face,
            area: 0.0,
            hint: "more than three boundary vertices are ear tips (one face each); no choice of three corners keeps every ear from collapsing: remove the ears",
        });
    }
    let is_allowed = |i: usize| allowed.is_none_or(|a| a.get(boundary[i]).copied().unwrap_or(false));
    let mut cumulative = vec![0.0; len + 1];
    for i in 0..len {
        cumulative[i + 1] = cumulative[i] + (x[boundary[(i + 1) % len]] - x[boundary[i]]).length();
    }
    let total = cumulative[len];
    // First corner: an ear tip if any, else the allowed vertex with the sharpest turn
    // (smallest sum of incident face angles), ties to the lowest boundary position.
    let angle_sum = |i: usize| {
        let v = vertex(boundary[i]);
        mesh.vertex_faces(v)
            .map(|f| {
                let ring: Vec<usize> = mesh.face_vertices(f).map(|w| w.index()).collect();
                let at = ring.iter().position(|&w| w == boundary[i]).expect("internal: vertex on its face");
                let (a, b) = (x[ring[(at + 1) % 3]] - x[boundary[i]], x[ring[(at + 2) % 3]] - x[boundary[i]]);
                a.angle_between(b)
            })
            .sum::<f64>()
    };
    let first = match ears.first() {
        Some(&e) => e,
        None => (0..len)
            .filter(|&i| is_allowed(i))
            .min_by(|&a, &b| angle_sum(a).total_cmp(&angle_sum(b)))
            .ok_or(SplineError::ShortBoundary { len: 0 })?,
    };
    let arc = |i: usize| (cumulative[i] - cumulative[first] + total) % total.max(f64::MIN_POSITIVE);
    let mut chosen = vec![first];
    for &e in &ears {
        if !chosen.contains(&e) {
            chosen.push(e);
        }
    }
    for target in [total / 3.0, 2.0 * total / 3.0] {
        if chosen.len() == 3 {
            break;
        }
        // Skip targets already served by an ear nearby.
        let best = (0..len)
            .filter(|&i| is_allowed(i) && !chosen.contains(&i))
            .min_by(|&a, &b| (arc(a) - target).abs().total_cmp(&(arc(b) - target).abs()));
        match best {
            Some(i) => chosen.push(i),
            None => return Err(SplineError::ShortBoundary { len: chosen.len() }),
        }
    }
    chosen.sort_by(|&a, &b| arc(a).total_cmp(&arc(b)));
    Ok([boundary[chosen[0]], boundary[chosen[1]], boundary[chosen[2]]])
}

/// `tan(θ/2)` of the angle between `a` and `b`, stably.
fn tan_half_angle(a: DVec3, b: DVec3) -> f64 {
    let s = a.cross(b).length();
    let c = a.length() * b.length() + a.dot(b);
    if c > 0.0 { s / c } else { f64::INFINITY }
}

/// Solves for the interior parameters.
fn solve_interior(
    mesh: &HalfedgeMesh,
    weights: TutteWeights,
    boundary_position: &[usize],
    params: &mut [DVec2],
) -> Result<(), SplineError> {
    let x = mesh.positions();
    let interior: Vec<usize> = (0..mesh.vertex_count()).filter(|&v| boundary_position[v] == usize::MAX).collect();
    if interior.is_empty() {
        return Ok(());
    }
    let mut unknown = vec![usize::MAX; mesh.vertex_count()];
    for (i, &v) in interior.iter().enumerate() {
        unknown[v] = i;
    }
    let mut triplets = Vec::new();
    let mut rhs = Mat::<f64>::zeros(interior.len(), 2);
    for (row, &v) in interior.iter().enumerate() {
        let vid = mesh.vertex(v).expect("internal: vertex index");
        let ring: Vec<usize> = mesh.vertex_neighbors(vid).map(|w| w.index()).collect();
        let l = ring.len();
        let mut total = 0.0;
        for (q, &w) in ring.iter().enumerate() {
            let weight = match weights {
                TutteWeights::Uniform => 1.0,
                TutteWeights::MeanValue => {
                    // The two triangles on edge (v, w): neighbours q - 1 and q + 1 (the ring
                    // of an interior vertex is closed).
                    let (prev, next) = (ring[(q + l - 1) % l], ring[(q + 1) % l]);
                    let e = x[w] - x[v];
                    let t = tan_half_angle(x[prev] - x[v], e) + tan_half_angle(e, x[next] - x[v]);
                    let value = t / e.length();
                    // Degenerate 3D geometry (zero-length edge, flat angle): fall back to
                    // a uniform weight so that the row stays a convex combination.
                    if value.is_finite() && value > 0.0 { value } else { 1.0 }
                }
            };
            total += weight;
            if unknown[w] != usize::MAX {
                triplets.push(Triplet::new(row, unknown[w], -weight));
            } else {
                rhs[(row, 0)] += weight * params[w].x;
                rhs[(row, 1)] += weight * params[w].y;
            }
        }
        triplets.push(Triplet::new(row, row, total));
    }
    let n = interior.len();
    let singular = || SplineError::Singular { what: "convex-combination map (sparse LU)" };
    let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets).map_err(|_| singular())?;
    let symbolic =
        faer::sparse::linalg::lu::factorize_symbolic_lu(a.symbolic(), Default::default()).map_err(|_| singular())?;
    let mut numeric = faer::sparse::linalg::lu::NumericLu::new();
    let par = Par::Seq;
    let lu = symbolic
        .factorize_numeric_lu(
            &mut numeric,
            a.as_ref(),
            par,
            MemStack::new(&mut MemBuffer::new(symbolic.factorize_numeric_lu_scratch::<f64>(par, Default::default()))),
            Default::default(),
        )
        .map_err(|_| singular())?;
    lu.solve_in_place_with_conj(
        faer::Conj::No,
        rhs.as_mut(),
        par,
        MemStack::new(&mut MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(2, par))),
    );
    for (row, &v) in interior.iter().enumerate() {
        params[v] = DVec2::new(rhs[(row, 0)], rhs[(row, 1)]);
        if !params[v].is_finite() {
            return Err(singular());
        }
    }
    Ok(())
}

/// Every face must map to a non-degenerate counter-clockwise triangle.
fn check_faces(mesh: &HalfedgeMesh, params: &[DVec2], boundary_position: &[usize]) -> Result<(), SplineError> {
    for f in mesh.faces() {
        let v: Vec<usize> = mesh.face_vertices(f).map(|w| w.index()).collect();
        let (a, b, c) = (params[v[0]], params[v[1]], params[v[2]]);
        let area = orient(a, b, c);
        if is_degenerate(a, b, c) || area <= 0.0 {
            let on_boundary = v.iter().all(|&w| boundary_position[w] != usize::MAX);
            let hint = if on_boundary {
                "its three vertices lie on one side of the domain: make one of them a corner"
            } else {
                "the convex-combination map folded here (nearly degenerate input triangles?)"
            };
            return Err(SplineError::DegenerateParameterTriangle { face: f.index(), area, hint });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_topo::shapes::{self, CellKind};
    use mesh_topo::{PolygonSoup, VertexId};

    /// The regular triangular grid with `n` segments per side, vertex order scrambled
    /// by `stride` (coprime to the count) so that detection cannot rely on it.
    pub(crate) fn triangle_grid(n: usize, stride: usize, lift: impl Fn(f64, f64) -> f64) -> PolygonSoup {
        let count = crate::index::tri_count(n);
        let label = |i: usize| ((i * stride) % count) as u32;
        let mut positions = vec![DVec3::ZERO; count];
        for [_, j, k] in crate::index::multi_indices(n) {
            let (a, b) = (j as f64 / n as f64, k as f64 / n as f64);
            positions[label(crate::index::tri_index(n, j, k)) as usize] = DVec3::new(a, b, lift(a, b));
        }
        let faces = crate::surface::grid_triangles(n, true).into_iter().map(|f| f.map(|v| label(v as usize)));
        PolygonSoup::from_faces(positions, faces.collect::<Vec<_>>())
    }

    #[test]
    fn regular_grids_get_natural_parameters() {
        for n in [1usize, 2, 5, 12] {
            let stride = if n == 1 { 1 } else { 11 };
            let soup = triangle_grid(n, stride, |a, b| (a * b).sin());
            let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
            let p = parameterize(&mesh, &ParamOptions::default()).unwrap();
            let ParamKind::RegularGrid { segments, coords } = &p.kind else { panic!("grid not detected, n = {n}") };
            assert_eq!(*segments, n);
            for (v, &(j, k)) in coords.iter().enumerate() {
                let expected = p.domain.point([
                    (n - j as usize - k as usize) as f64 / n as f64,
                    j as f64 / n as f64,
                    k as f64 / n as f64,
                ]);
                assert!((p.params[v] - expected).length() < 1e-15);
            }
            // The lattice agrees with the geometry up to a symmetry of the triangle: the
            // x, y coordinates are an affine function of (j, k).
            let q = mesh.positions();
            let (o, a, b) = (p.corners[0], p.corners[1], p.corners[2]);
            for (v, &(j, k)) in coords.iter().enumerate() {
                let predicted = q[o] + (q[a] - q[o]) * (j as f64 / n as f64) + (q[b] - q[o]) * (k as f64 / n as f64);
                assert!((predicted.truncate() - q[v].truncate()).length() < 1e-12);
            }
        }
    }

    #[test]
    fn tutte_maps_are_embeddings_with_boundary_on_the_triangle() {
        let mesh = HalfedgeMesh::from_soup(&shapes::grid(6, 4, CellKind::Triangles).unwrap()).unwrap();
        for weights in [TutteWeights::Uniform, TutteWeights::MeanValue] {
            let options = ParamOptions { weights, ..ParamOptions::default() };
            let p = parameterize(&mesh, &options).unwrap();
            let total: f64 = mesh
                .faces()
                .map(|f| {
                    let v: Vec<usize> = mesh.face_vertices(f).map(|w| w.index()).collect();
                    orient(p.params[v[0]], p.params[v[1]], p.params[v[2]])
                })
                .sum();
            assert!((total - p.domain.det()).abs() < 1e-12, "faces tile the domain");
            for (i, c) in p.corners.iter().enumerate() {
                assert!((p.params[*c] - p.domain.corners()[i]).length() < 1e-15);
            }
        }
    }

    #[test]
    fn mean_value_weights_have_linear_precision() {
        // A planar triangle grid in its own plane, corners at the triangle's corners: the
        // mean-value map is the affine map (here the identity up to the domain's frame).
        let soup = triangle_grid(6, 5, |_, _| 0.0);
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        let grid = parameterize(&mesh, &ParamOptions::default()).unwrap();
        let options = ParamOptions { detect_grid: false, corners: Some(grid.corners), ..ParamOptions::default() };
        let p = parameterize(&mesh, &options).unwrap();
        for v in 0..mesh.vertex_count() {
            assert!((p.params[v] - grid.params[v]).length() < 1e-12);
        }
    }

    #[test]
    fn bad_meshes_are_typed_errors() {
        let closed = HalfedgeMesh::from_soup(&shapes::icosahedron()).unwrap();
        assert!(matches!(
            parameterize(&closed, &ParamOptions::default()),
            Err(SplineError::NotDisk { boundary_loops: 0, .. })
        ));
        let torus = HalfedgeMesh::from_soup(&shapes::torus(6, 4, CellKind::Triangles).unwrap()).unwrap();
        assert!(matches!(parameterize(&torus, &ParamOptions::default()), Err(SplineError::NotDisk { .. })));
        let quads = HalfedgeMesh::from_soup(&shapes::grid(2, 2, CellKind::Quads).unwrap()).unwrap();
        assert!(matches!(parameterize(&quads, &ParamOptions::default()), Err(SplineError::NotTriangle { .. })));
        // An annulus: a grid with its middle face removed.
        let mut soup = shapes::grid(3, 3, CellKind::Triangles).unwrap();
        let faces: Vec<Vec<u32>> = soup.faces().map(|f| f.to_vec()).collect();
        let mut holed = PolygonSoup::with_capacity(soup.vertex_count(), 0, 0);
        holed.positions = std::mem::take(&mut soup.positions);
        for (i, f) in faces.iter().enumerate() {
            if i != 8 && i != 9 {
                holed.push_face(f);
            }
        }
        let annulus = HalfedgeMesh::from_soup(&holed).unwrap();
        assert!(matches!(
            parameterize(&annulus, &ParamOptions::default()),
            Err(SplineError::NotDisk { boundary_loops: 2, .. })
        ));
        // Two components.
        let two = PolygonSoup::from_faces(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE, DVec3::NEG_X],
            [[0u32, 1, 2], [3, 4, 5]],
        );
        let two = HalfedgeMesh::from_soup(&two).unwrap();
        assert!(matches!(
            parameterize(&two, &ParamOptions::default()),
            Err(SplineError::NotDisk { components: 2, .. })
        ));
        // Corners that are not boundary vertices, or out of order.
        let mesh = HalfedgeMesh::from_soup(&shapes::grid(3, 3, CellKind::Triangles).unwrap()).unwrap();
        let interior = mesh.vertices().find(|&v| !mesh.is_boundary_vertex(v)).map(VertexId::index).unwrap();
        let options = ParamOptions { corners: Some([0, 3, interior]), ..ParamOptions::default() };
        assert!(matches!(parameterize(&mesh, &options), Err(SplineError::BadCorner { .. })));
        // Corners 0, 1, 2 (consecutive on the bottom side) leave the ear at vertex 3 on a
        // straight side: its face collapses to a segment.
        let options = ParamOptions { corners: Some([0, 1, 2]), detect_grid: false, ..ParamOptions::default() };
        assert!(matches!(parameterize(&mesh, &options), Err(SplineError::DegenerateParameterTriangle { .. })));
    }
}
