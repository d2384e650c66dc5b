//! Loop subdivision of triangle meshes (Loop 1987), closed or with boundaries.
//!
//! # Rules
//! One step splits every triangle into four and computes
//! - a **vertex point** for every vertex `p` of valence `n` with neighbours `q_j`:
//!   `alpha_n p + beta_n sum q_j` with `alpha_n = 1 - n beta_n` and Loop's original
//!   `beta_n = (5/8 - (3/8 + cos(2 pi / n) / 4)^2) / n` ([`VertexWeights::Loop`], the
//!   default, as in OpenSubdiv, CGAL, OpenMesh) or Warren's `beta_3 = 3/16`,
//!   `beta_n = 3 / (8 n)` ([`VertexWeights::Warren`], as in libigl);
//! - an **edge point** for every interior edge `(a, b)` with opposite vertices `c, d`:
//!   `3/8 (a + b) + 1/8 (c + d)`;
//! - on the boundary (Hoppe et al. 1994): edge midpoints `(a + b) / 2` and, for a
//!   boundary vertex with boundary neighbours `q-`, `q+`, `3/4 p + 1/8 (q- + q+)`, so the
//!   boundary follows a cubic B-spline that depends on the boundary alone. With
//!   [`LoopOptions::keep_corners`] a boundary vertex of valence 2 (one incident face)
//!   stays where it is. Interior edges that touch the boundary use the interior rule.
//!
//! Isolated vertices are copied. The only manifold triangle meshes with interior
//! vertices of valence 2 are closed "pillows" (two triangles glued along all three
//! edges); their subdivision would not be a manifold, so they are rejected
//! ([`LoopError::InteriorValenceTwo`]).
//!
//! # Output order (a stable contract)
//! One step on a mesh with `V` vertices, `E` edges and `F` faces gives `V + E` vertices
//! and `4F` faces, in this order:
//! - **vertices** `0 .. V`: the vertex point of coarse vertex `i` has index `i`;
//! - **vertices** `V + e`: the edge point of coarse edge `e`, where edges are numbered in
//!   order of first appearance when the faces are scanned in order and the corners of
//!   each face in order (the edge of corner `k` of face `f` joins corners `k` and
//!   `k + 1 mod 3`). This is the numbering of [`HalfedgeMesh`]'s `EdgeId`s;
//! - **faces**: coarse face `f = (a, b, c)` (corners as given) with edge points
//!   `m_ab, m_bc, m_ca` gives
//!   `4f = (a, m_ab, m_ca)`, `4f + 1 = (b, m_bc, m_ab)`, `4f + 2 = (c, m_ca, m_bc)` and
//!   the central face `4f + 3 = (m_ab, m_bc, m_ca)`.
//!
//! Several levels are repeated single steps, each numbering the edges of the previous
//! level's output as above: `subdivide(m, 2)` has the vertex and face order of
//! `subdivide(subdivide(m, 1).to_halfedge_mesh(), 1)` and the same positions up to
//! rounding (neighbours may be summed in another order). So at every level vertex
//! `i < V` is an *even* vertex (it came from coarse vertex `i`), the others are *odd*,
//! and detail vectors can be addressed across levels by index.
//!
//! # Performance
//! After the initial conversion of the [`HalfedgeMesh`] the refinement never touches a
//! general half-edge structure: each level is a compact triangle topology (three
//! half-edges per face, one twin index each, plus one word per face and per vertex) and
//! the next level's topology follows from the previous one by index arithmetic
//! (Dupuy and Vanhoey 2021), without hashing. Faces, edges and vertices are processed in
//! parallel with `rayon`, each output written by exactly one task with a fixed formula,
//! so results are bit-identical for any number of threads; levels of fewer than 4096
//! coarse faces, and all levels on a one-thread pool, run the same tasks one after the
//! other on the calling thread, where handing them to the pool would cost more than
//! it saves. The last level computes only
//! positions and triangles. Outputs are written once, without a zero or placeholder pass
//! first, and on Linux the large ones are backed by transparent huge pages: the first
//! touch of fresh memory (a page fault per 4 KiB page, and the kernel zeroing it) is the
//! largest single cost at millions of triangles. At level 4 of a 75k-triangle mesh,
//! huge pages and the missing fill pass cut the CPU time by about 30%, and releasing
//! the result from about 50 ms to 2 ms. Peak memory beyond the output is the previous level: about 40% of the output size
//! (level 4 of a 75k-triangle mesh: peak resident memory of the whole process 1.45 times
//! the output, 1.42 without the input mesh).
//! [`LoopMesh::into_soup`] reuses the triangles' memory.
//!
//! Repeated subdivision (an editor moving vertices, an animation, a pipeline stage) should
//! use a [`Subdivider`]: it writes into the arrays of the previous result and keeps the
//! intermediate levels between calls, so after the first call nothing is allocated and no
//! page is touched for the first time. The result is flat arrays;
//! building a [`HalfedgeMesh`] from them ([`LoopMesh::to_halfedge_mesh`]) validates and
//! sorts, and costs more than the subdivision itself at large sizes.
//!
//! # References
//! C. Loop, *Smooth subdivision surfaces based on triangles*, MS thesis, Utah, 1987.
//! J. Warren, *Subdivision methods for geometric design*, 1995 (simplified weights).
//! H. Hoppe et al., *Piecewise smooth surface reconstruction*, SIGGRAPH 1994 (boundaries).
//! J. Dupuy, K. Vanhoey, *A halfedge refinement rule for parallel Loop/Catmull-Clark
//! subdivision*, HPG 2021 (index-arithmetic refinement).

mod attribute;
pub(crate) mod buffer;
pub(crate) mod kernel;
mod matrix;
mod subdivider;
pub(crate) mod topology;

use std::mem::take;

use glam::DVec3;
use mesh_topo::{HalfedgeMesh, MeshError, PolygonSoup};
use serde::{Deserialize, Serialize};

pub use attribute::Attribute;
pub(crate) use attribute::{SparseRow, check_finite_values, checked_refined};
pub use matrix::SubdivisionMatrix;
pub use subdivider::Subdivider;

use crate::LoopError;
use kernel::Rules;
use topology::{BASE_MASK, MAX_FACES, Topology};

/// The vertex weights of interior vertices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, Serialize, Deserialize)]
pub enum VertexWeights {
    /// Loop's original `beta_n = (5/8 - (3/8 + cos(2 pi / n) / 4)^2) / n`.
    #[default]
    Loop,
    /// Warren's simplification: `beta_3 = 3/16`, `beta_n = 3 / (8 n)` for `n > 3`.
    Warren,
}

/// Options of Loop subdivision.
///
/// ```
/// use subdiv_loop::forward::{LoopOptions, VertexWeights};
/// let options = LoopOptions { weights: VertexWeights::Warren, ..LoopOptions::default() };
/// assert!(!options.keep_corners);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Hash, Serialize, Deserialize)]
pub struct LoopOptions {
    /// Interior vertex weights (default: Loop's original).
    pub weights: VertexWeights,
    /// Keep boundary vertices of valence 2 (corners with one incident face) fixed.
    pub keep_corners: bool,
}

impl LoopOptions {
    /// Loop's original weights, boundary corners smoothed like other boundary vertices.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopOptions, subdivision_matrix};
    ///
    /// assert_eq!(LoopOptions::loop_weights(), LoopOptions::default());
    /// // At valence 4 (octahedron) beta_4 = (5/8 - (3/8)^2) / 4 = 31/256, alpha_4 = 33/64.
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let s = subdivision_matrix(&octahedron, 1, &LoopOptions::loop_weights())?;
    /// assert!((s.get(0, 0) - 33.0 / 64.0).abs() < 1e-15);
    /// assert!((s.get(0, 2) - 31.0 / 256.0).abs() < 1e-15);
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn loop_weights() -> Self {
        Self::default()
    }

    /// Warren's weights (libigl's variant).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopOptions, VertexWeights, subdivision_matrix};
    ///
    /// assert_eq!(LoopOptions::warren_weights().weights, VertexWeights::Warren);
    /// // At valence 4 (octahedron) beta_4 = 3 / (8 * 4) = 3/32, alpha_4 = 1 - 4 beta_4 = 5/8.
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let s = subdivision_matrix(&octahedron, 1, &LoopOptions::warren_weights())?;
    /// assert!((s.get(0, 0) - 5.0 / 8.0).abs() < 1e-15);
    /// assert!((s.get(0, 2) - 3.0 / 32.0).abs() < 1e-15);
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn warren_weights() -> Self {
        Self { weights: VertexWeights::Warren, ..Self::default() }
    }
}

/// A subdivided triangle mesh as flat arrays, in the order documented in the
/// [module docs](self). The default is the empty mesh, for instance as the output of
/// [`Subdivider::subdivide_into`] before its first call.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LoopMesh {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Triangles as vertex index triples, counter-clockwise like the input.
    pub triangles: Vec<[u32; 3]>,
}

impl LoopMesh {
    /// Number of vertices: `V + E` of the coarse mesh after one step.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopOptions, subdivide};
    ///
    /// let icosahedron = HalfedgeMesh::from_soup(&shapes::icosahedron())?;
    /// let fine = subdivide(&icosahedron, 1, &LoopOptions::default())?;
    /// // One vertex point per vertex, one edge point per edge: 12 + 30.
    /// assert_eq!(fine.vertex_count(), icosahedron.vertex_count() + icosahedron.edge_count());
    /// assert_eq!(fine.vertex_count(), 42);
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles: `4^levels` times the coarse face count.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopOptions, subdivide};
    ///
    /// let icosahedron = HalfedgeMesh::from_soup(&shapes::icosahedron())?;
    /// let fine = subdivide(&icosahedron, 3, &LoopOptions::default())?;
    /// assert_eq!(fine.face_count(), 20 * 4 * 4 * 4);
    /// assert_eq!(fine.face_count(), fine.triangles.len());
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn face_count(&self) -> usize {
        self.triangles.len()
    }

    /// The mesh as a polygon soup (copies the arrays).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopOptions, subdivide};
    ///
    /// let tetrahedron = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
    /// let fine = subdivide(&tetrahedron, 1, &LoopOptions::default())?;
    /// let soup = fine.to_soup();
    /// assert_eq!((soup.vertex_count(), soup.face_count()), (10, 16));
    /// assert!(soup.is_triangle_soup());
    /// assert_eq!(soup.face(5), fine.triangles[5]);
    /// assert_eq!(soup.positions, fine.positions);
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn to_soup(&self) -> PolygonSoup {
        PolygonSoup {
            positions: self.positions.clone(),
            offsets: triangle_offsets(self.triangles.len()),
            indices: self.triangles.as_flattened().to_vec(),
        }
    }

    /// The mesh as a polygon soup, moving the positions and reusing the triangles'
    /// memory for the indices (only the face offsets are new).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopOptions, subdivide};
    ///
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let fine = subdivide(&octahedron, 2, &LoopOptions::default())?;
    /// let copy = fine.to_soup();
    /// let soup = fine.into_soup();
    /// assert_eq!(soup, copy);
    /// assert_eq!(soup.offsets[..4], [0, 3, 6, 9]);
    /// assert_eq!(soup.offsets.len(), 8 * 16 + 1);
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn into_soup(self) -> PolygonSoup {
        PolygonSoup {
            offsets: triangle_offsets(self.triangles.len()),
            indices: self.triangles.into_flattened(),
            positions: self.positions,
        }
    }

    /// Builds the half-edge mesh (validating it; linear time plus a sort per vertex).
    /// Its edge numbering is the one the next step uses.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopOptions, subdivide};
    ///
    /// let options = LoopOptions::default();
    /// let tetrahedron = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
    /// let once = subdivide(&tetrahedron, 1, &options)?.to_halfedge_mesh()?;
    /// // E' = 2E + 3F: every edge is split in two, every face adds three inner edges.
    /// assert_eq!(once.edge_count(), 2 * 6 + 3 * 4);
    /// // Two steps are one step on the mesh of the first: same faces, same positions.
    /// let twice = subdivide(&tetrahedron, 2, &options)?;
    /// let stepwise = subdivide(&once, 1, &options)?;
    /// assert_eq!(twice.triangles, stepwise.triangles);
    /// let pairs = twice.positions.iter().zip(&stepwise.positions);
    /// assert!(pairs.map(|(p, q)| p.distance(*q)).all(|d| d < 1e-15));
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    ///
    /// # Errors
    /// [`LoopError::Mesh`] if the arrays were edited into an invalid mesh.
    pub fn to_halfedge_mesh(&self) -> Result<HalfedgeMesh, LoopError> {
        Ok(HalfedgeMesh::from_soup(&self.to_soup())?)
    }
}

/// Subdivides a triangle mesh `levels` times with Loop's scheme.
///
/// `levels = 0` returns the input as flat arrays.
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::forward::{LoopOptions, subdivide};
///
/// let tetrahedron = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
/// let fine = subdivide(&tetrahedron, 2, &LoopOptions::default())?;
/// // V' = V + E and F' = 4F per level: (4, 6, 4) -> (10, 24, 16) -> (34, 96, 64).
/// assert_eq!((fine.vertex_count(), fine.face_count()), (34, 64));
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// [`LoopError::NotTriangle`] naming the first face that is not a triangle;
/// [`LoopError::Mesh`] with [`MeshError::NonFiniteCoordinate`] if a position is NaN or
/// infinite, [`MeshError::TooLarge`] if the output would not fit `u32` indices, or
/// [`MeshError::OutOfMemory`] if it would not fit in the memory the system has available
/// (both found from the counts before any work:
/// [`check_available`](mesh_topo::memory::check_available));
/// [`LoopError::InvalidParameter`] for more than [`MAX_LEVELS`] levels;
/// [`LoopError::Overflow`] for finite coordinates so large (beyond `f64::MAX / 2^32`)
/// that the result is not.
pub fn subdivide(mesh: &HalfedgeMesh, levels: u32, options: &LoopOptions) -> Result<LoopMesh, LoopError> {
    let largest = check_finite_largest(mesh.positions())?;
    let topology = checked_base(mesh, levels, size_of::<DVec3>())?;
    let (positions, topology) = refine(topology, mesh.positions(), levels, &Rules::new(options));
    check_no_overflow(&positions, largest)?;
    Ok(LoopMesh { positions, triangles: topology.triangles })
}

/// [`subdivide`] for a polygon soup: builds (and validates) the half-edge mesh first.
///
/// ```
/// use glam::DVec3;
/// use mesh_topo::PolygonSoup;
/// use subdiv_loop::forward::{LoopOptions, subdivide_soup};
///
/// let square = PolygonSoup::from_faces(
///     vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
///     [[0u32, 1, 2], [0, 2, 3]],
/// );
/// let fine = subdivide_soup(&square, 1, &LoopOptions::default())?;
/// assert_eq!((fine.vertex_count(), fine.face_count()), (9, 8));
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// As [`subdivide`], plus [`LoopError::Mesh`] for an invalid soup (non-manifold,
/// inconsistent orientation, bad indices, ...).
pub fn subdivide_soup(soup: &PolygonSoup, levels: u32, options: &LoopOptions) -> Result<LoopMesh, LoopError> {
    check_triangles(soup)?;
    subdivide(&HalfedgeMesh::from_soup(soup)?, levels, options)
}

/// Refines any per-vertex attribute (one value per vertex of `mesh`) `levels` times
/// with the stencils of [`subdivide`]; the result is in the same vertex order.
///
/// ```
/// use glam::DVec3;
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::forward::{LoopOptions, refine_attribute, subdivide};
///
/// let mesh = HalfedgeMesh::from_soup(&shapes::octahedron())?;
/// let options = LoopOptions::default();
/// // A scalar field and an RGB colour per vertex.
/// let heat: Vec<f64> = mesh.positions().iter().map(|p| p.z).collect();
/// let colour: Vec<[f64; 3]> = (0..6).map(|i| [i as f64 / 5.0, 0.5, 1.0]).collect();
/// let fine_heat = refine_attribute(&mesh, 2, &options, &heat)?;
/// let fine_colour = refine_attribute(&mesh, 2, &options, &colour)?;
/// // Positions refined as an attribute are exactly the subdivided positions.
/// let fine = subdivide(&mesh, 2, &options)?;
/// assert_eq!(refine_attribute(&mesh, 2, &options, mesh.positions())?, fine.positions);
/// assert_eq!((fine_heat.len(), fine_colour.len()), (66, 66));
/// assert!(fine.positions.iter().zip(&fine_heat).all(|(p, h)| (p.z - h).abs() < 1e-15));
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// [`LoopError::AttributeCount`] if `values.len() != mesh.vertex_count()`,
/// [`LoopError::NonFiniteAttribute`] for a value that is not finite
/// ([`Attribute::is_finite`]), [`LoopError::AttributeOverflow`] when finite values are so
/// large that the refined ones are not; the errors of [`subdivide`] for the mesh.
pub fn refine_attribute<T: Attribute>(
    mesh: &HalfedgeMesh,
    levels: u32,
    options: &LoopOptions,
    values: &[T],
) -> Result<Vec<T>, LoopError> {
    if values.len() != mesh.vertex_count() {
        return Err(LoopError::AttributeCount { expected: mesh.vertex_count(), found: values.len() });
    }
    attribute::check_finite_values(values)?;
    let topology = checked_base(mesh, levels, size_of::<T>())?;
    attribute::checked_refined(refine(topology, values, levels, &Rules::new(options)).0)
}

/// The sparse matrix of `levels` Loop steps: row `i` holds the weights of fine vertex
/// `i` on the coarse vertices. Built by refining the unit vectors through the same
/// stencil code as [`subdivide`], so `S · positions` equals the subdivided positions.
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::forward::{LoopOptions, subdivide, subdivision_matrix};
///
/// let mesh = HalfedgeMesh::from_soup(&shapes::icosahedron())?;
/// let s = subdivision_matrix(&mesh, 1, &LoopOptions::default())?;
/// let fine = subdivide(&mesh, 1, &LoopOptions::default())?;
/// let applied = s.apply(mesh.positions())?;
/// assert!(applied.iter().zip(&fine.positions).all(|(a, b)| (*a - *b).length() < 1e-15));
/// // The vertex row of a valence-5 vertex: alpha_5 and five times beta_5.
/// assert_eq!(s.row(0).0.len(), 6);
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
///
/// # Errors
/// The errors of [`subdivide`].
pub fn subdivision_matrix(
    mesh: &HalfedgeMesh,
    levels: u32,
    options: &LoopOptions,
) -> Result<SubdivisionMatrix, LoopError> {
    let units: Vec<SparseRow> = (0..mesh.vertex_count() as u32).map(SparseRow::unit).collect();
    let rows = refine_attribute(mesh, levels, options, &units)?;
    Ok(SubdivisionMatrix::from_rows(rows, mesh.vertex_count()))
}

/// The base level of `levels` steps of `mesh` (values of `value_bytes` each), once the
/// sizes of the output are checked: errors in the order of [`subdivide`]'s docs, the
/// base level's own (not a triangle, a pillow) before the sizes'. The sizes are checked
/// first all the same, once (the memory check reads system files), because they give
/// the room of the base level's triangles: those of the finest level of the same
/// parity, the output for an even count (see [`refine`]); a count that is refused
/// reserves no room beyond the base's own.
fn checked_base(mesh: &HalfedgeMesh, levels: u32, value_bytes: usize) -> Result<Topology, LoopError> {
    // The counts of the mesh are those of its topology once built (one triangle per face).
    let last_faces = check_sizes(mesh.vertex_count(), mesh.edge_count(), mesh.face_count(), levels)
        .and_then(|(vertices, faces)| check_output_memory(vertices, faces, value_bytes, 0).map(|()| faces));
    let topology = Topology::from_mesh_with_room(mesh, base_triangle_room(mesh.face_count(), levels, &last_faces))?;
    last_faces.map(|_| topology)
}

/// The room to reserve for the base level's triangles (`faces` of them) of `levels`
/// steps whose last level has `last_faces` (if accepted): that of the finest level of
/// the same parity, if there are two levels or more; else its own.
fn base_triangle_room(faces: usize, levels: u32, last_faces: &Result<u64, LoopError>) -> usize {
    match last_faces {
        // Faces multiply by 4 per level: the finest level of even count has
        // `4^(levels & !1)` times as many as the base.
        Ok(last_faces) if levels >= 2 => (last_faces >> (2 * (levels & 1))) as usize,
        _ => faces,
    }
}

/// Runs `levels` steps; the returned topology is complete except at the last level
/// (triangles and counts only).
///
/// Each step writes into the arrays of the level two before it, which are no longer
/// needed (its values, triangles, links and starts, each only if large enough; the last
/// step takes the values and triangles only). A base level whose triangles were made
/// with the room of the finest level of the same parity ([`base_triangle_room`]) thus
/// hands its memory on to that level: to the output for an even count. Otherwise the
/// base level's arrays, freed after the first step, could stay resident: glibc raises
/// its mmap threshold as large blocks are freed (a file read before, say), so arrays
/// the size of the base level come from its heap and are kept there once freed.
pub(crate) fn refine<T: Attribute>(
    mut topology: Topology,
    values: &[T],
    levels: u32,
    rules: &Rules,
) -> (Vec<T>, Topology) {
    let mut current: Option<Vec<T>> = None;
    // The arrays of the level before `current`.
    let mut spare = kernel::Buffers::default();
    for level in 0..levels {
        let last = level + 1 == levels;
        if last {
            // The last level has no links or starts: the spare ones are freed now, not
            // held through the step.
            (spare.links, spare.starts) = (Vec::new(), Vec::new());
        }
        let step = kernel::step_into(&topology, current.as_deref().unwrap_or(values), rules, !last, take(&mut spare));
        let coarser = std::mem::replace(&mut topology, step.topology);
        spare = kernel::Buffers {
            values: current.replace(step.values).unwrap_or_default(),
            triangles: coarser.triangles,
            links: coarser.links,
            starts: coarser.vertex_halfedge,
        };
    }
    (current.unwrap_or_else(|| values.to_vec()), topology)
}

/// The offsets of a soup of `faces` triangles: `0, 3, 6, ..., 3 faces` (in parallel;
/// they are a third of the size of the indices).
pub(crate) fn triangle_offsets(faces: usize) -> Vec<u32> {
    buffer::par_fill(faces + 1, |f| (3 * f) as u32)
}

/// The largest coordinate magnitude of `positions` (0 for none).
pub(crate) fn largest_magnitude(positions: &[DVec3]) -> f64 {
    positions.iter().fold(0.0f64, |largest, p| largest.max(p.abs().max_element()))
}

/// Rejects NaN and infinite coordinates, naming the vertex; else the largest coordinate
/// magnitude (in the same pass), for [`check_no_overflow`].
pub(crate) fn check_finite_largest(positions: &[DVec3]) -> Result<f64, LoopError> {
    let mut largest = 0.0f64;
    for (vertex, p) in positions.iter().enumerate() {
        if !p.is_finite() {
            let axis = (0..3).find(|&a| !p[a].is_finite()).unwrap_or(0);
            return Err(MeshError::NonFiniteCoordinate { vertex, axis, value: p[axis] }.into());
        }
        largest = largest.max(p.abs().max_element());
    }
    Ok(largest)
}

/// Coordinates up to this magnitude cannot overflow: every rule of the crate (vertex,
/// edge, boundary and limit masks, forward and M-band) is a sum of fewer than `2^32`
/// terms (a vertex's neighbours) whose weights have absolute values summing to a few
/// units at most, so no partial sum exceeds `2^32` times the largest coordinate.
const OVERFLOW_FREE: f64 = f64::MAX / 4_294_967_296.0;

/// Finite input of coordinates beyond [`OVERFLOW_FREE`] (`largest`, from
/// [`check_finite_largest`]) may give infinities: then the first output vertex that is
/// not finite is [`LoopError::Overflow`]. Below it nothing is read.
pub(crate) fn check_no_overflow<'a>(
    output: impl IntoIterator<Item = &'a DVec3>,
    largest: f64,
) -> Result<(), LoopError> {
    if largest <= OVERFLOW_FREE {
        return Ok(());
    }
    match output.into_iter().position(|p| !p.is_finite()) {
        Some(vertex) => Err(LoopError::Overflow { vertex, largest }),
        None => Ok(()),
    }
}

/// Rejects soups with non-triangular faces, naming the first one. Reads the offsets
/// without slicing the indices, so that a hand-built soup with malformed offsets
/// (decreasing, past the indices) does not panic here: it stops at the first bad range
/// and leaves the typed error to [`HalfedgeMesh::from_soup`].
pub(crate) fn check_triangles(soup: &PolygonSoup) -> Result<(), LoopError> {
    for (face, w) in soup.offsets.windows(2).enumerate() {
        if w[1] < w[0] || w[1] as usize > soup.indices.len() {
            return Ok(());
        }
        if w[1] - w[0] != 3 {
            return Err(LoopError::NotTriangle { face, corners: (w[1] - w[0]) as usize });
        }
    }
    Ok(())
}

/// The most levels the functions of this crate refine (Loop steps; ternary levels):
/// a mesh with a face no longer fits the `u32` layout after 16 Loop steps (10 ternary
/// levels), and a mesh without faces does not change at all, so more levels could only
/// repeat work on it (`u32::MAX` of them would take hours). Asking for more is
/// [`LoopError::InvalidParameter`] at once.
///
/// ```
/// use mesh_topo::{HalfedgeMesh, PolygonSoup};
/// use subdiv_loop::LoopError;
/// use subdiv_loop::forward::{LoopOptions, MAX_LEVELS, subdivide};
///
/// // Two isolated vertices: no faces to refine.
/// let points = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(vec![glam::DVec3::ZERO; 2], Vec::<[u32; 3]>::new()))?;
/// assert_eq!(subdivide(&points, MAX_LEVELS, &LoopOptions::default())?.positions.len(), 2);
/// let error = subdivide(&points, MAX_LEVELS + 1, &LoopOptions::default()).unwrap_err();
/// assert!(matches!(error, LoopError::InvalidParameter { name: "levels", .. }));
/// # Ok::<(), LoopError>(())
/// ```
pub const MAX_LEVELS: u32 = 32;

/// The error for `levels` levels where at most `max` are refined.
pub(crate) fn too_many_levels(levels: u32, max: u32) -> LoopError {
    LoopError::InvalidParameter { name: "levels", reason: format!("{levels}: at most {max}") }
}

/// [`MAX_LEVELS`] levels or fewer, else [`too_many_levels`].
pub(crate) fn check_level_limit(levels: u32) -> Result<(), LoopError> {
    if levels > MAX_LEVELS { Err(too_many_levels(levels, MAX_LEVELS)) } else { Ok(()) }
}

/// Checks that every level of `levels` steps from a mesh of `vertices`, `edges` and
/// `faces` fits the `u32` layout: half-edge indices and edge counts of the levels that
/// are refined further, vertex indices of the last (from the counts alone, before any
/// work: `V + E`, `2E + 3F` and `4F` per step, [`counts_after_step`]); then that
/// `levels` is at most [`MAX_LEVELS`] (so that a mesh with a face, which fails the sizes
/// first, is told its size). Returns the vertices and faces of the last level.
///
/// [`counts_after_step`]: crate::mband::counts_after_step
pub(crate) fn check_sizes(vertices: usize, edges: usize, faces: usize, levels: u32) -> Result<(u64, u64), LoopError> {
    let (mut v, mut e, mut f) = (vertices as u64, edges as u64, faces as u64);
    let too_large = |what: &'static str, count: u64, max: u64| {
        Err(MeshError::TooLarge { what, count: count.min(usize::MAX as u64) as usize, max: max as usize }.into())
    };
    for _ in 0..levels.min(MAX_LEVELS + 1) {
        if f > MAX_FACES {
            return too_large("faces", f, MAX_FACES);
        }
        if e > BASE_MASK as u64 {
            return too_large("edges", e, BASE_MASK as u64);
        }
        [v, e, f] = crate::mband::counts_after_step(2, [v, e, f]);
    }
    if v >= u32::MAX as u64 {
        return too_large("vertices", v, u32::MAX as u64 - 1);
    }
    check_level_limit(levels).map(|()| (v, f))
}

/// Fails with [`MeshError::OutOfMemory`] (before any work) when an output of `vertices`
/// values of `value_bytes` each and `faces` triangles, less the `held_bytes` already
/// allocated for it (arrays it will be written into), would not fit in the memory the
/// system has available ([`mesh_topo::memory::check_available`]).
pub(crate) fn check_output_memory(
    vertices: u64,
    faces: u64,
    value_bytes: usize,
    held_bytes: u128,
) -> Result<(), LoopError> {
    let needed = output_bytes(vertices, faces, value_bytes).saturating_sub(held_bytes);
    Ok(mesh_topo::memory::check_available("Loop output", needed)?)
}

/// The bytes of an output of `vertices` values of `value_bytes` each and `faces`
/// triangles.
pub(crate) fn output_bytes(vertices: u64, faces: u64, value_bytes: usize) -> u128 {
    u128::from(vertices) * value_bytes as u128 + u128::from(faces) * 12
}

#[cfg(test)]
mod tests;
