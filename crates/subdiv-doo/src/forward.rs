//! Doo-Sabin subdivision: one or more steps on a polygon mesh of any face sizes, closed
//! or with boundary.
//!
//! # One step (specification §4.1)
//! Every corner of the coarse mesh becomes a fine vertex: **fine vertex `c` is coarse
//! corner `c`** (corners numbered face by face, in the order of the coarse faces, each
//! face from its first corner), placed by the face's rule ([`FaceRule`]). The fine faces
//! come in three blocks, always in this order:
//!
//! 1. **F_F** faces, one per coarse face, in coarse face order: coarse face `f` with
//!    corners `c_0 .. c_{m-1}` becomes the fine face `(c_0, .., c_{m-1})`.
//! 2. **F_E** quads, one per *interior* coarse edge, in the order in which `mesh-topo`
//!    numbers the coarse edges (first appearance, face by face, corner by corner). For
//!    the edge `u -> v` first seen at corner `c` of face `f`, with `t` the corner of
//!    `v -> u` in the other face `g`, the quad is `(c, next(t), t, next(c))`, i.e.
//!    `(ṽ_f(u), ṽ_g(u), ṽ_g(v), ṽ_f(v))`.
//! 3. **F_V** faces, one per *interior* coarse vertex, in vertex order: the corners of
//!    the vertex counter-clockwise (seen from outside), starting at its first corner (the
//!    corner with the smallest index, which is where `mesh-topo` starts its circulators).
//!
//! All fine faces keep the orientation of the coarse mesh. Counts: `|NV| = Σ|f|`,
//! `|NF| = |F| + |E_int| + |V_int|`; every interior fine vertex has valence 4.
//! [`DooMesh::face_origin`] tells each fine face's kind and parent element.
//!
//! # Boundaries
//! By default ([`BoundaryRule::Shrink`]), as in the reverse-Doo paper and in CGAL:
//! boundary edges get no F_E quad and boundary vertices no F_V face, so an open mesh
//! shrinks a little at every level and its limit surface does not reach the coarse
//! boundary. [`BoundaryRule::Chaikin`] adds a ring of boundary quads and boundary vertex
//! faces through the Chaikin points of the boundary edges, so that the boundary
//! converges to the quadratic B-spline curve of the boundary polygon
//! ([`crate::boundary`]; its ring and points come after everything listed above). Both
//! are exactly reversible ([`crate::reverse`](mod@crate::reverse)).
//!
//! # Isolated vertices
//! A vertex that no face uses has no corner, so it has no image in the fine mesh: it is
//! dropped (the specification's "copied unchanged" would break the rule "fine vertex =
//! coarse corner" that reverse Doo-Sabin and the pyramid rely on).
//!
//! # Performance
//! The first step reads the half-edge mesh once into flat corner arrays; every further
//! step builds the next level's connectivity by index arithmetic from the previous one
//! (see `corner.rs`), without a half-edge structure. Positions are computed face by face
//! in parallel with rayon; every output value is computed by one task in a fixed order,
//! so results are bit-identical for any number of threads.

use glam::DVec3;
use mesh_topo::{HalfedgeMesh, PolygonSoup};

use crate::DooError;
use crate::boundary::{BoundaryRule, Ring};
use crate::corner::{
    CornerMesh, DooTopology, FaceKind, FaceOrigin, NONE, check_step_size, doo_topology, face_points, side_by_side,
};
use crate::rule::{FaceMaps, FaceRule};

/// Options of [`subdivide`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DooOptions {
    /// The per-face rule (default: the original Doo-Sabin weights).
    pub rule: FaceRule,
    /// Number of steps (default 1). Zero returns the input mesh.
    pub levels: u32,
    /// What happens at the boundary (default: [`BoundaryRule::Shrink`]).
    pub boundary: BoundaryRule,
}

impl Default for DooOptions {
    fn default() -> Self {
        Self { rule: FaceRule::DooSabin, levels: 1, boundary: BoundaryRule::Shrink }
    }
}

impl DooOptions {
    /// `levels` steps of `rule`, boundaries shrinking.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{BoundaryRule, DooOptions, FaceRule, subdivide};
    ///
    /// let options = DooOptions::new(FaceRule::Simple, 2);
    /// assert_eq!((options.rule, options.levels), (FaceRule::Simple, 2));
    /// assert_eq!(options.boundary, BoundaryRule::Shrink);
    /// assert_eq!(DooOptions::new(FaceRule::DooSabin, 1), DooOptions::default());
    /// // Two steps on a cube: 24 vertices after the first, each on 4 faces: 24 * 4 corners.
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// assert_eq!(subdivide(&cube, &options)?.vertex_count(), 24 * 4);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn new(rule: FaceRule, levels: u32) -> Self {
        Self { rule, levels, boundary: BoundaryRule::Shrink }
    }

    /// The same options with the boundary rule `boundary`.
    ///
    /// ```
    /// use subdiv_doo::{BoundaryRule, DooOptions, FaceRule, subdivide};
    /// use mesh_topo::{HalfedgeMesh, shapes::{self, CellKind}};
    /// // A flat 2 x 2 grid of quads: 9 vertices, 8 boundary edges.
    /// let grid = HalfedgeMesh::from_soup(&shapes::grid(2, 2, CellKind::Quads)?)?;
    /// let options = DooOptions::new(FaceRule::DooSabin, 1).with_boundary(BoundaryRule::Chaikin);
    /// let fine = subdivide(&grid, &options)?;
    /// // 16 corners and 2 Chaikin points per boundary edge; F_F, F_E (4 interior + 8
    /// // boundary quads) and F_V (1 interior + 8 boundary vertex faces).
    /// assert_eq!(fine.vertex_count(), 16 + 2 * 8);
    /// assert_eq!(fine.kind_counts(), [4, 4 + 8, 1 + 8]);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn with_boundary(self, boundary: BoundaryRule) -> Self {
        Self { boundary, ..self }
    }
}

/// The result of Doo-Sabin subdivision: positions, faces, and where each face came from.
///
/// The faces are stored flat (struct-of-arrays, `u32` indices) in the order of the
/// module docs; [`face_origin`](Self::face_origin) refers to the elements of the mesh one
/// level coarser (for several levels: the second-finest level).
#[derive(Debug, Clone, PartialEq)]
pub struct DooMesh {
    positions: Vec<DVec3>,
    topology: DooTopology,
}

impl DooMesh {
    /// Number of vertices. After a step under the Shrink rule, one per corner of the coarse
    /// mesh (`|NV| = Σ|f|`).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, subdivide};
    ///
    /// let soup = shapes::tetrahedron();
    /// let fine = subdivide(&HalfedgeMesh::from_soup(&soup)?, &DooOptions::default())?;
    /// // 4 triangles, 12 corners, 12 fine vertices.
    /// assert_eq!(fine.vertex_count(), soup.indices.len());
    /// assert_eq!(fine.vertex_count(), 12);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of faces. After a step under the Shrink rule, `|F| + |E_int| + |V_int|` (one
    /// F_F face per coarse face, one F_E quad per interior edge, one F_V face per interior
    /// vertex).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, subdivide};
    ///
    /// let coarse = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
    /// let fine = subdivide(&coarse, &DooOptions::default())?;
    /// // Closed: every edge and vertex is interior, 4 + 6 + 4 faces.
    /// let (f, e, v) = (coarse.face_count(), coarse.edge_count(), coarse.vertex_count());
    /// assert_eq!(fine.face_count(), f + e + v);
    /// assert_eq!(fine.face_count(), 14);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn face_count(&self) -> usize {
        self.topology.offsets.len().saturating_sub(1)
    }

    /// Vertex positions.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, subdivide};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::default())?;
    /// assert_eq!(fine.positions().len(), fine.vertex_count());
    /// // Fine vertex `c` is coarse corner `c` moved by its face's rule. Corner 0 of the unit
    /// // square (0,0,0), (0,1,0), (1,1,0), (1,0,0): weights (9, 3, 1, 3)/16 put it a quarter of
    /// // the way to the opposite corner.
    /// assert!(fine.positions()[0].distance(DVec3::new(0.25, 0.25, 0.0)) < 1e-15);
    /// // The F_F face keeps the centroid of its coarse face.
    /// let centroid = fine.face(0).iter().map(|&c| fine.positions()[c as usize]).sum::<DVec3>() / 4.0;
    /// assert!(centroid.distance(DVec3::new(0.5, 0.5, 0.0)) < 1e-15);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// The corners of face `f`.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, subdivide};
    ///
    /// let soup = shapes::cube();
    /// let fine = subdivide(&HalfedgeMesh::from_soup(&soup)?, &DooOptions::default())?;
    /// // Fine vertex `c` is coarse corner `c`: `soup.indices[c]` is its coarse vertex.
    /// let coarse_vertices =
    ///     |f: usize| fine.face(f).iter().map(|&c| soup.indices[c as usize]).collect::<Vec<_>>();
    /// // F_F face 0: the corners of coarse face 0, in order.
    /// assert_eq!(fine.face(0), [0, 1, 2, 3]);
    /// // F_E quad 6, across coarse edge 0 (vertex 0 -> 2): two corners at each end.
    /// assert_eq!(coarse_vertices(6), [0, 0, 2, 2]);
    /// // F_V face 18: the three corners of coarse vertex 0, in faces 0, 2 and 4.
    /// assert_eq!(fine.face(18), [0, 8, 16]);
    /// assert_eq!(coarse_vertices(18), [0, 0, 0]);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    ///
    /// # Panics
    /// If `f >= self.face_count()`.
    pub fn face(&self, f: usize) -> &[u32] {
        let o = &self.topology.offsets;
        &self.topology.indices[o[f] as usize..o[f + 1] as usize]
    }

    /// All faces in order.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, subdivide};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::default())?;
    /// assert_eq!(fine.faces().len(), fine.face_count());
    /// assert!(fine.faces().enumerate().all(|(f, face)| face == fine.face(f)));
    /// // 6 F_F and 12 F_E quads, then 8 F_V triangles (the cube's vertices have valence 3).
    /// assert!(fine.faces().take(18).all(|face| face.len() == 4));
    /// assert!(fine.faces().skip(18).all(|face| face.len() == 3));
    /// // Closed mesh: every fine vertex lies on 4 faces.
    /// assert_eq!(fine.faces().map(<[u32]>::len).sum::<usize>(), 4 * fine.vertex_count());
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn faces(&self) -> impl ExactSizeIterator<Item = &[u32]> + '_ {
        self.topology.offsets.windows(2).map(|w| &self.topology.indices[w[0] as usize..w[1] as usize])
    }

    /// Kind and parent element of face `f`.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes::{self, CellKind}};
    /// use subdiv_doo::{DooOptions, FaceOrigin, subdivide};
    ///
    /// // A tetrahedron: its 4 faces, then its 6 edges, then its 4 vertices, in order.
    /// let tetrahedron = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
    /// let fine = subdivide(&tetrahedron, &DooOptions::default())?;
    /// let origins: Vec<_> = (0..fine.face_count()).map(|f| fine.face_origin(f)).collect();
    /// let expected: Vec<_> = (0..4)
    ///     .map(FaceOrigin::Face)
    ///     .chain((0..6).map(FaceOrigin::Edge))
    ///     .chain((0..4).map(FaceOrigin::Vertex))
    ///     .collect();
    /// assert_eq!(origins, expected);
    /// // Two quads side by side: only their shared edge, edge 1, gets an F_E quad.
    /// let pair = HalfedgeMesh::from_soup(&shapes::grid(2, 1, CellKind::Quads)?)?;
    /// let fine = subdivide(&pair, &DooOptions::default())?;
    /// assert_eq!(fine.face_count(), 3);
    /// assert_eq!(fine.face_origin(2), FaceOrigin::Edge(1));
    /// assert!(!pair.is_boundary_edge(pair.edges().nth(1).unwrap()));
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    ///
    /// # Panics
    /// If `f >= self.face_count()`.
    pub fn face_origin(&self, f: usize) -> FaceOrigin {
        assert!(f < self.face_count(), "face {f} out of range");
        self.topology.origin(f)
    }

    /// Kind of face `f` (F_F, F_E or F_V).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, FaceKind, subdivide};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::default())?;
    /// for f in 0..fine.face_count() {
    ///     assert_eq!(fine.face_kind(f), fine.face_origin(f).kind());
    ///     // Only the F_V faces of the cube's valence-3 vertices are triangles.
    ///     assert_eq!(fine.face_kind(f) == FaceKind::Vertex, fine.face(f).len() == 3);
    /// }
    /// assert_eq!(fine.face_kind(6), FaceKind::Edge);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    ///
    /// # Panics
    /// If `f >= self.face_count()`.
    pub fn face_kind(&self, f: usize) -> FaceKind {
        self.face_origin(f).kind()
    }

    /// Numbers of F_F, F_E and F_V faces. Under the Shrink rule they are three consecutive
    /// blocks of faces; under the Chaikin rule the boundary quads (counted as F_E) and the
    /// boundary vertex faces (counted as F_V) follow as two more blocks.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes::{self, CellKind}};
    /// use subdiv_doo::{DooOptions, subdivide};
    ///
    /// // A 3 x 2 grid of quads (Shrink rule): boundary edges and vertices get no faces.
    /// let grid = HalfedgeMesh::from_soup(&shapes::grid(3, 2, CellKind::Quads)?)?;
    /// let fine = subdivide(&grid, &DooOptions::default())?;
    /// let interior_edges = grid.edges().filter(|&e| !grid.is_boundary_edge(e)).count();
    /// let interior_vertices = grid.vertices().filter(|&v| !grid.is_boundary_vertex(v)).count();
    /// assert_eq!(fine.kind_counts(), [grid.face_count(), interior_edges, interior_vertices]);
    /// assert_eq!(fine.kind_counts(), [6, 7, 2]);
    /// assert_eq!(fine.kind_counts().iter().sum::<usize>(), fine.face_count());
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn kind_counts(&self) -> [usize; 3] {
        let t = &self.topology;
        [t.ff_count, t.fe_count + t.ring_edge_parent.len(), t.fv_count + t.ring_vertex_parent.len()]
    }

    /// The mesh as a polygon soup (copies).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, FaceRule, subdivide, subdivide_soup};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let once = subdivide(&cube, &DooOptions::default())?;
    /// let soup = once.to_soup();
    /// assert_eq!((soup.vertex_count(), soup.face_count()), (once.vertex_count(), once.face_count()));
    /// // Subdividing the soup again is the same as two steps at once, bit for bit.
    /// let twice = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 2))?;
    /// assert_eq!(subdivide_soup(&soup, &DooOptions::default())?, twice);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn to_soup(&self) -> PolygonSoup {
        PolygonSoup {
            positions: self.positions.clone(),
            offsets: self.topology.offsets.clone(),
            indices: self.topology.indices.clone(),
        }
    }

    /// The mesh as a polygon soup (no copy).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, subdivide};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::default())?;
    /// let copy = fine.to_soup();
    /// let soup = fine.into_soup(); // takes over the arrays of `fine`
    /// assert_eq!(soup, copy);
    /// assert_eq!((soup.vertex_count(), soup.face_count()), (24, 26));
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn into_soup(self) -> PolygonSoup {
        PolygonSoup { positions: self.positions, offsets: self.topology.offsets, indices: self.topology.indices }
    }

    /// Builds the half-edge mesh of the result.
    ///
    /// # Errors
    /// None in practice (a Doo-Sabin step of a valid mesh is a valid mesh); the
    /// [`DooError::Mesh`] of `mesh-topo` is passed on if it ever were not.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, subdivide};
    ///
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let fine = subdivide(&cube, &DooOptions::default())?;
    /// let mesh = fine.to_mesh()?;
    /// assert_eq!((mesh.vertex_count(), mesh.face_count()), (fine.vertex_count(), fine.face_count()));
    /// // Still a sphere (24 - 48 + 26 = 2), and every fine vertex has valence 4.
    /// assert_eq!((mesh.edge_count(), mesh.topology_stats().genus), (48, 0));
    /// assert!(mesh.vertices().all(|v| mesh.valence(v) == 4));
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn to_mesh(&self) -> Result<HalfedgeMesh, DooError> {
        Ok(HalfedgeMesh::from_soup(&self.to_soup())?)
    }
}

/// Checks that every position is finite.
pub(crate) fn check_finite(positions: &[DVec3]) -> Result<(), DooError> {
    check_finite_largest(positions).map(|_| ())
}

/// Coordinates up to this magnitude cannot overflow in a step: every rule is a sum of
/// fewer than `2^32` terms (a face's corners, a vertex's faces) with non-negative weights
/// summing to one, so no partial sum exceeds `2^32` times the largest coordinate.
const OVERFLOW_FREE: f64 = f64::MAX / 4_294_967_296.0;

/// [`check_finite`], and the largest coordinate magnitude (in the same pass).
pub(crate) fn check_finite_largest(positions: &[DVec3]) -> Result<f64, DooError> {
    let mut largest = 0.0f64;
    for (vertex, p) in positions.iter().enumerate() {
        if !p.is_finite() {
            return Err(DooError::NonFinite { vertex, value: p.to_array() });
        }
        largest = largest.max(p.abs().max_element());
    }
    Ok(largest)
}

/// Finite input of coordinates beyond [`OVERFLOW_FREE`] may subdivide into infinities:
/// then the first fine vertex that is not finite is [`DooError::Overflow`].
fn check_no_overflow(fine: DooMesh, largest: f64) -> Result<DooMesh, DooError> {
    if largest <= OVERFLOW_FREE {
        return Ok(fine);
    }
    match fine.positions.iter().position(|p| !p.is_finite()) {
        Some(vertex) => Err(DooError::Overflow { vertex, largest }),
        None => Ok(fine),
    }
}

/// Doo-Sabin subdivision of a polygon mesh, `options.levels` steps.
///
/// ```
/// use subdiv_doo::{DooOptions, FaceKind, FaceOrigin, FaceRule, subdivide};
/// use mesh_topo::{HalfedgeMesh, shapes};
///
/// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
/// let fine = subdivide(&cube, &DooOptions::default())?;
/// // 6 F_F quads, 12 F_E quads, 8 F_V triangles; 24 vertices, one per coarse corner.
/// assert_eq!(fine.kind_counts(), [6, 12, 8]);
/// assert_eq!(fine.vertex_count(), 24);
/// assert_eq!(fine.face_origin(0), FaceOrigin::Face(0));
/// assert_eq!(fine.face_kind(25), FaceKind::Vertex);
///
/// // Two more levels with the simple averaging rule: counts grow four times per level.
/// let finer = subdivide(&cube, &DooOptions::new(FaceRule::Simple, 3))?;
/// assert_eq!(finer.vertex_count(), 24 * 4 * 4);
/// # Ok::<(), subdiv_doo::DooError>(())
/// ```
///
/// # Errors
/// [`DooError::NonFinite`] for a NaN or infinite position, [`DooError::Overflow`] for
/// finite coordinates so large (beyond `f64::MAX / 2^32`) that the result is not;
/// [`DooError::ValenceTwoVertex`] for an interior vertex with two edges (its vertex face
/// would be a digon); [`DooError::InvalidParameter`] for a centroid parameter outside
/// `(0, 1)`; [`DooError::TooLarge`] if a level would not fit `u32` indices, found from
/// the input's counts before any level is built (so that too many levels fail at once,
/// not after filling the memory, with the error the build of that level would give, under
/// either boundary rule); [`DooError::Mesh`] with
/// [`MeshError::OutOfMemory`](mesh_topo::MeshError::OutOfMemory) if the output would not
/// fit in the memory the system has available (from the same counts, before any work:
/// [`check_available`](mesh_topo::memory::check_available));
/// [`DooError::InvalidParameter`] for more than [`MAX_LEVELS`] levels. Non-manifold
/// input and faces with fewer than three corners cannot be a [`HalfedgeMesh`];
/// [`subdivide_soup`] reports them.
pub fn subdivide(mesh: &HalfedgeMesh, options: &DooOptions) -> Result<DooMesh, DooError> {
    options.rule.validate()?;
    let largest = check_finite_largest(mesh.positions())?;
    if options.levels == 0 {
        let soup = mesh.to_soup();
        let topology = DooTopology {
            ff_count: soup.face_count(),
            offsets: if soup.offsets.is_empty() { vec![0] } else { soup.offsets },
            indices: soup.indices,
            ..DooTopology::default()
        };
        return Ok(DooMesh { positions: soup.positions, topology });
    }
    let corners = CornerMesh::from_halfedge(mesh);
    check_level_sizes(&corners, options.levels, options.boundary)?;
    check_output_memory(&corners, options.levels, options.boundary)?;
    check_no_overflow(subdivide_corner_mesh(corners, mesh.positions().to_vec(), options)?, largest)
}

/// Fails with [`MeshError::OutOfMemory`](mesh_topo::MeshError::OutOfMemory) before any
/// work when the output of `levels` steps (a position per fine vertex, an index per
/// corner, an offset per face) would not fit in the memory the system has available
/// ([`mesh_topo::memory::check_available`]). A bound from the corners alone first (a
/// step at most quadruples them, eight times under the Chaikin rule; no level has more
/// vertices or faces than corners), so that a small output reads neither the mesh nor
/// the system; past it the exact counts ([`LevelCounts`]). `levels` is at most
/// [`MAX_LEVELS`] ([`check_level_sizes`] comes first).
fn check_output_memory(mesh: &CornerMesh, levels: u32, boundary: BoundaryRule) -> Result<(), DooError> {
    let growth = u128::from(corner_growth(boundary));
    let corners_bound = (mesh.corner_count() as u128).saturating_mul(growth.saturating_pow(levels));
    if corners_bound.saturating_mul(32).saturating_add(4) <= mesh_topo::memory::ALWAYS_FITS_BYTES {
        return Ok(());
    }
    Ok(mesh_topo::memory::check_available("Doo-Sabin output", output_bytes(mesh, levels, boundary))?)
}

/// The most a step multiplies the corners by under `boundary` (see
/// [`check_level_sizes`]): four under the shrinking rule, eight under the Chaikin rule.
fn corner_growth(boundary: BoundaryRule) -> u32 {
    match boundary {
        BoundaryRule::Shrink => 4,
        BoundaryRule::Chaikin => 8,
    }
}

/// The bytes of the arrays of the output of `levels` steps on `mesh`: a position per fine
/// vertex, an index per corner and an offset per face and one more.
fn output_bytes(mesh: &CornerMesh, levels: u32, boundary: BoundaryRule) -> u128 {
    let mut counts = LevelCounts::of(mesh);
    let mut vertices = mesh.vertex_count;
    for _ in 0..levels {
        // Every coarse corner becomes a fine vertex; the Chaikin rule adds two points per
        // boundary edge.
        (vertices, counts) = match boundary {
            BoundaryRule::Shrink => (counts.corners, counts.next()),
            BoundaryRule::Chaikin => {
                (counts.corners.saturating_add(counts.boundary_edges.saturating_mul(2)), counts.next_chaikin())
            }
        };
    }
    PolygonSoup::array_bytes_for(vertices as u128, counts.corners as u128, counts.faces as u128)
}

/// Before any work, a level count whose output cannot be indexed fails at once, not
/// after the levels below it have filled the memory. The counts follow the boundary rule
/// ([`LevelCounts::next`], [`LevelCounts::next_chaikin`]); each level gets the checks
/// its build makes, in the same order, so the error is the one the build would give.
///
/// Then more than [`MAX_LEVELS`] levels are refused, so that a mesh that does not grow
/// (one face, or none) is not refined for hours; a mesh that grows is told its size.
fn check_level_sizes(mesh: &CornerMesh, levels: u32, boundary: BoundaryRule) -> Result<(), DooError> {
    let checked = levels.min(MAX_LEVELS + 1);
    // A Shrink step at most quadruples the corners (a closed mesh's exactly: `2C + 4E_i
    // - C_b` with `2E_i <= C`), and a step's check counts at most four times its corners;
    // a Chaikin step gives `2C + 4E_i + 6E_b = 4C + 4E_b <= 8C` corners. When `4^levels`
    // (`8^levels`) times the corners fit, every level fits, and the mesh is not read.
    let growth = corner_growth(boundary) as usize;
    let bound = (0..checked).try_fold(mesh.corner_count(), |c, _| c.checked_mul(growth).filter(|&c| c < NONE as usize));
    if bound.is_none() {
        let mut counts = LevelCounts::of(mesh);
        for _ in 0..checked {
            check_step_size(counts.corners, counts.interior_edges)?;
            counts = match boundary {
                BoundaryRule::Shrink => counts.next(),
                BoundaryRule::Chaikin => {
                    // The build counts the fine corners once the ring is added.
                    let fine = counts.next_chaikin();
                    if fine.corners >= NONE as usize {
                        let max = NONE as usize - 1;
                        return Err(DooError::TooLarge { what: "fine corners", count: fine.corners, max });
                    }
                    fine
                }
            };
        }
    }
    if levels > MAX_LEVELS {
        return Err(DooError::InvalidParameter {
            name: "levels",
            value: levels as f64,
            reason: "at most 32 levels are refined (a mesh that grows exceeds u32 indices after 16)",
        });
    }
    Ok(())
}

/// The most levels [`subdivide`] refines and [`decompose`](crate::decompose) reverses.
/// A mesh that grows no longer fits `u32` indices after 16 levels (every level at least
/// doubles the corners of a closed mesh); one that does not grow (a single face, faces
/// that share no edge, no faces at all) only repeats its step, each face contracting
/// towards its centroid, so that more levels would only take longer (`u32::MAX` of them,
/// hours).
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes::{self, CellKind}};
/// use subdiv_doo::{DooError, DooOptions, FaceRule, MAX_LEVELS, subdivide};
///
/// let quad = HalfedgeMesh::from_soup(&shapes::grid(1, 1, CellKind::Quads)?)?;
/// assert_eq!(subdivide(&quad, &DooOptions::new(FaceRule::DooSabin, MAX_LEVELS))?.face_count(), 1);
/// let error = subdivide(&quad, &DooOptions::new(FaceRule::DooSabin, MAX_LEVELS + 1)).unwrap_err();
/// assert!(matches!(error, DooError::InvalidParameter { name: "levels", .. }));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub const MAX_LEVELS: u32 = 32;

/// The messages of the level limit (here and in [`crate::pyramid`]) spell the number
/// out, as an error's reason is a static string: they change with it.
const _: () = assert!(MAX_LEVELS == 32, "update the level-limit reasons of subdivide and decompose");

/// The counts of one level that determine those of the next under the shrink boundary
/// rule, so that the sizes of many levels are known without building them.
///
/// One step (see the module docs): every corner becomes a fine vertex; the fine faces are
/// the F_F faces (their sides: one fine edge per corner), a quad per interior edge (two
/// more fine edges each, its end sides) and a face per interior vertex (whose sides are
/// quad end sides). A fine vertex lies on the boundary exactly when its coarse vertex
/// does; an F_F side along a boundary edge and a quad end side at a boundary vertex are
/// boundary edges. Hence, with `B` the boundary end points of the interior edges (an edge
/// with both ends on the boundary counts twice), the next level has `F + E_i + V_i`
/// faces, `2C + 4E_i - C_b` corners, `C + 2E_i` edges of which `E_b + B` on the
/// boundary, `C - C_b` interior vertices, `C_b + 2B` corners at boundary vertices, and
/// `2B` boundary end points of interior edges (each interior edge gives two F_F sides,
/// whose ends are on the boundary where its own are). Tested against subdivision.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct LevelCounts {
    faces: usize,
    corners: usize,
    interior_edges: usize,
    boundary_edges: usize,
    /// Interior vertices with a face (each gets an F_V face).
    interior_vertices: usize,
    /// Corners at boundary vertices.
    boundary_corners: usize,
    /// Boundary end points of the interior edges.
    boundary_ends: usize,
}

impl LevelCounts {
    /// The counts of `mesh` (one pass over its corners).
    fn of(mesh: &CornerMesh) -> Self {
        let (vertex, twin, next) = (&mesh.corner_vertex, &mesh.corner_twin, &mesh.corner_next);
        let mut on_boundary = vec![false; mesh.vertex_count];
        let mut has_corner = vec![false; mesh.vertex_count];
        let mut boundary_edges = 0;
        for c in 0..mesh.corner_count() {
            has_corner[vertex[c] as usize] = true;
            if twin[c] == NONE {
                boundary_edges += 1;
                on_boundary[vertex[c] as usize] = true;
                on_boundary[vertex[next[c] as usize] as usize] = true;
            }
        }
        let (mut interior_edges, mut boundary_corners, mut boundary_ends) = (0, 0, 0);
        for c in 0..mesh.corner_count() {
            let (from, to) = (on_boundary[vertex[c] as usize], on_boundary[vertex[next[c] as usize] as usize]);
            boundary_corners += usize::from(from);
            if twin[c] != NONE && (c as u32) < twin[c] {
                interior_edges += 1;
                boundary_ends += usize::from(from) + usize::from(to);
            }
        }
        let interior_vertices = (0..mesh.vertex_count).filter(|&v| has_corner[v] && !on_boundary[v]).count();
        Self {
            faces: mesh.face_count(),
            corners: mesh.corner_count(),
            interior_edges,
            boundary_edges,
            interior_vertices,
            boundary_corners,
            boundary_ends,
        }
    }

    /// The counts of the next level (saturating: only compared with limits).
    fn next(self) -> Self {
        let Self { faces, corners, interior_edges, boundary_edges, interior_vertices, boundary_corners, boundary_ends } =
            self;
        let edges = corners.saturating_add(interior_edges.saturating_mul(2));
        let fine_boundary_edges = boundary_edges.saturating_add(boundary_ends);
        Self {
            faces: faces.saturating_add(interior_edges).saturating_add(interior_vertices),
            corners: corners
                .saturating_mul(2)
                .saturating_add(interior_edges.saturating_mul(4))
                .saturating_sub(boundary_corners),
            interior_edges: edges.saturating_sub(fine_boundary_edges),
            boundary_edges: fine_boundary_edges,
            interior_vertices: corners.saturating_sub(boundary_corners),
            boundary_corners: boundary_corners.saturating_add(boundary_ends.saturating_mul(2)),
            boundary_ends: boundary_ends.saturating_mul(2),
        }
    }

    /// The counts of the next level under the Chaikin boundary rule (see
    /// [`crate::boundary`]): the Shrink step's faces and corners, plus per boundary edge
    /// two Chaikin points, a boundary quad and (at the vertex it leaves, one per boundary
    /// fan) a boundary vertex face of `k + 2` corners for `k` corners at that vertex.
    /// So `F + E_i + V_i + 2E_b` faces and `2C + 4E_i + 6E_b` corners. Every coarse corner
    /// is an interior fine vertex (`C`); the Chaikin points are the boundary vertices,
    /// each with two corners (`4E_b`) and one interior edge (`2E_b` ends), and the fine
    /// boundary has `2E_b` edges, so `C + 2E_i + 2E_b` of the `(C' + E_b') / 2` edges are
    /// interior. Tested against subdivision.
    fn next_chaikin(self) -> Self {
        let Self { faces, corners, interior_edges, boundary_edges, interior_vertices, .. } = self;
        let twice_boundary = boundary_edges.saturating_mul(2);
        Self {
            faces: faces
                .saturating_add(interior_edges)
                .saturating_add(interior_vertices)
                .saturating_add(twice_boundary),
            corners: corners
                .saturating_mul(2)
                .saturating_add(interior_edges.saturating_mul(4))
                .saturating_add(boundary_edges.saturating_mul(6)),
            interior_edges: corners.saturating_add(interior_edges.saturating_mul(2)).saturating_add(twice_boundary),
            boundary_edges: twice_boundary,
            interior_vertices: corners,
            boundary_corners: boundary_edges.saturating_mul(4),
            boundary_ends: twice_boundary,
        }
    }
}

/// [`subdivide`] for a polygon soup, validated first.
///
/// ```
/// use subdiv_doo::{DooError, DooOptions, subdivide_soup};
/// use mesh_topo::{DVec3, MeshError, PolygonSoup};
/// let digon = PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X], [[0u32, 1]]);
/// let error = subdivide_soup(&digon, &DooOptions::default()).unwrap_err();
/// assert!(matches!(error, DooError::Mesh(MeshError::FaceTooSmall { face: 0, len: 2 })));
/// ```
///
/// # Errors
/// [`DooError::Mesh`] if the soup is not a valid manifold mesh (naming the face, edge or
/// vertex at fault), and the errors of [`subdivide`].
pub fn subdivide_soup(soup: &PolygonSoup, options: &DooOptions) -> Result<DooMesh, DooError> {
    let mesh = HalfedgeMesh::from_soup(soup)?;
    subdivide(&mesh, options)
}

/// The subdivision loop on corner arrays. Under the Shrink rule each level's corner
/// arrays follow from the previous ones by index arithmetic; under the Chaikin rule the
/// ring ([`Ring`]) is appended to each level and the next level's corner arrays are read
/// from the result (the ring breaks the index arithmetic).
pub(crate) fn subdivide_corner_mesh(
    mut corners: CornerMesh,
    mut positions: Vec<DVec3>,
    options: &DooOptions,
) -> Result<DooMesh, DooError> {
    let maps = FaceMaps::new(options.rule);
    let chaikin = options.boundary == BoundaryRule::Chaikin;
    let mut level = 0;
    loop {
        level += 1;
        let last = level == options.levels;
        // The connectivity (from the coarse connectivity) and the positions (from the
        // coarse positions) do not depend on each other: on a pool of several threads
        // they are built side by side (the positions split further across the pool).
        let topology = || doo_topology(&corners, !last && !chaikin);
        let points = || {
            let vertex = &corners.corner_vertex;
            let coarse = &positions;
            face_points(&corners.offsets, &maps, |c| coarse[vertex[c] as usize])
        };
        let (topology, mut fine_positions) = side_by_side(corners.face_count(), topology, points);
        let mut topology = topology?;
        if chaikin {
            let ring = Ring::of(&corners)?;
            fine_positions.extend(ring.chaikin_points(&corners, &positions, None));
            ring.append_to(&mut topology);
            if topology.indices.len() >= NONE as usize {
                let count = topology.indices.len();
                return Err(DooError::TooLarge { what: "fine corners", count, max: NONE as usize - 1 });
            }
        }
        if last {
            return Ok(DooMesh { positions: fine_positions, topology });
        }
        let vertex_count = fine_positions.len();
        positions = fine_positions;
        corners = if chaikin {
            // A Chaikin step of a manifold mesh is a manifold mesh (tested on every shape).
            CornerMesh::from_faces(topology.offsets, topology.indices, vertex_count).map_err(|reason| {
                DooError::NotDooConnectivity {
                    face: 0,
                    reason: format!("internal: a Chaikin boundary step is not a manifold mesh: {reason}"),
                }
            })?
        } else {
            topology.into_corner_mesh(vertex_count)
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_topo::shapes::{self, CellKind};

    fn doo(soup: &PolygonSoup, rule: FaceRule, levels: u32) -> DooMesh {
        subdivide_soup(soup, &DooOptions::new(rule, levels)).unwrap()
    }

    #[test]
    fn two_threads_give_the_one_thread_result() {
        // Above `PARALLEL_FACES` the connectivity and the positions are built side by
        // side, and the positions in pieces: the same mesh, bit for bit.
        let torus = shapes::torus(128, 64, CellKind::Triangles).unwrap();
        let grid = shapes::grid(128, 128, CellKind::Quads).unwrap();
        for (soup, boundary) in [(torus, BoundaryRule::Shrink), (grid, BoundaryRule::Chaikin)] {
            assert!(soup.face_count() >= crate::corner::PARALLEL_FACES);
            let options = DooOptions { boundary, ..DooOptions::new(FaceRule::DooSabin, 2) };
            let on = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                pool.install(|| subdivide_soup(&soup, &options).unwrap())
            };
            assert_eq!(on(1), on(2), "{boundary:?}");
            // The reconstruction builds each level the same way.
            let fine = on(1).to_mesh().unwrap();
            let decompose = crate::pyramid::DecomposeOptions::levels(FaceRule::DooSabin, 2).with_boundary(boundary);
            let pyramid = crate::pyramid::decompose(&fine, &decompose).unwrap().pyramid;
            let rebuilt = |threads: usize| {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                pool.install(|| pyramid.reconstruct(2, None).unwrap())
            };
            assert_eq!(rebuilt(1), rebuilt(2), "{boundary:?}");
        }
    }

    /// Meshes of every kind the counts must follow: closed, open (a single quad, grids,
    /// holes), several components, an isolated vertex.
    fn count_cases() -> Vec<PolygonSoup> {
        let mut two = shapes::cube();
        let tetrahedron = shapes::tetrahedron();
        let shift = two.vertex_count() as u32;
        let mut faces: Vec<Vec<u32>> = two.faces().map(<[u32]>::to_vec).collect();
        faces.extend(tetrahedron.faces().map(|f| f.iter().map(|&v| v + shift).collect::<Vec<_>>()));
        two.positions.extend(tetrahedron.positions.iter().map(|&p| p + DVec3::X * 3.0));
        let mut positions = two.positions.clone();
        positions.push(DVec3::splat(9.0));
        let with_isolated = PolygonSoup::from_faces(positions, faces.clone());
        let two = PolygonSoup::from_faces(two.positions, faces);
        // A torus with two holes (two faces far apart removed).
        let torus = shapes::torus(8, 6, CellKind::Quads).unwrap();
        let holed = PolygonSoup::from_faces(
            torus.positions.clone(),
            torus.faces().enumerate().filter(|&(f, _)| f != 0 && f != 27).map(|(_, f)| f.to_vec()).collect::<Vec<_>>(),
        );
        vec![
            shapes::cube(),
            shapes::tetrahedron(),
            shapes::icosahedron(),
            shapes::grid(1, 1, CellKind::Quads).unwrap(),
            shapes::grid(3, 2, CellKind::Triangles).unwrap(),
            shapes::grid(4, 4, CellKind::Mixed).unwrap(),
            shapes::torus(4, 3, CellKind::Mixed).unwrap(),
            holed,
            two,
            with_isolated,
        ]
    }

    /// The counts of every level, as [`LevelCounts::next`] and
    /// [`LevelCounts::next_chaikin`] predict them from the input alone, are those of the
    /// subdivided mesh, under either boundary rule.
    fn assert_counts_follow(soup: &PolygonSoup, levels: u32) {
        let mesh = HalfedgeMesh::from_soup(soup).unwrap();
        for boundary in [BoundaryRule::Shrink, BoundaryRule::Chaikin] {
            let mut predicted = LevelCounts::of(&CornerMesh::from_halfedge(&mesh));
            for level in 1..=levels {
                let coarser = predicted;
                predicted = match boundary {
                    BoundaryRule::Shrink => predicted.next(),
                    BoundaryRule::Chaikin => predicted.next_chaikin(),
                };
                // The bound that spares the count pass (`check_level_sizes`).
                let growth = if boundary == BoundaryRule::Shrink { 4 } else { 8 };
                assert!(predicted.corners <= growth * coarser.corners && 2 * coarser.interior_edges <= coarser.corners);
                let options = DooOptions::new(FaceRule::DooSabin, level).with_boundary(boundary);
                let fine = subdivide(&mesh, &options).unwrap();
                let counted = LevelCounts::of(&CornerMesh::from_halfedge(&fine.to_mesh().unwrap()));
                assert_eq!(predicted, counted, "{boundary:?} level {level} of {soup:?}");
                assert_eq!((predicted.faces, predicted.corners), (fine.face_count(), fine.topology.indices.len()));
                // The bytes the memory check counts are those of the output's arrays.
                let arrays =
                    24 * fine.positions.len() + 4 * fine.topology.indices.len() + 4 * fine.topology.offsets.len();
                assert_eq!(output_bytes(&CornerMesh::from_halfedge(&mesh), level, boundary), arrays as u128);
            }
        }
    }

    #[test]
    fn an_output_that_cannot_fit_in_memory_is_refused_before_any_work() {
        // 7500 edges: nine levels make 3.9G corners (within the index range) and 43 GB.
        let torus = HalfedgeMesh::from_soup(&shapes::torus(50, 50, CellKind::Triangles).unwrap()).unwrap();
        let needed = output_bytes(&CornerMesh::from_halfedge(&torus), 9, BoundaryRule::Shrink);
        assert!(needed > 40_000_000_000, "{needed}");
        // Made only where it is sure to be refused (the memory is read again by
        // `subdivide`); elsewhere the bound alone is checked.
        match mesh_topo::memory::available_bytes() {
            Some(available) if u128::from(available) < needed / 3 * 2 => {
                let error = subdivide(&torus, &DooOptions::new(FaceRule::DooSabin, 9)).unwrap_err();
                let DooError::Mesh(mesh_topo::MeshError::OutOfMemory { what, needed_bytes, .. }) = error else {
                    panic!("refused for its memory: {error}");
                };
                assert_eq!((what, needed_bytes), ("Doo-Sabin output", needed));
            }
            _ => eprintln!("this machine may have room for {needed} bytes: the refusal is not tried"),
        }
        // A small output is made without reading the mesh's counts or the system.
        let cube = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        assert!(check_output_memory(&CornerMesh::from_halfedge(&cube), 3, BoundaryRule::Chaikin).is_ok());
    }

    #[test]
    fn level_counts_predict_the_subdivided_meshes() {
        for soup in count_cases() {
            assert_counts_follow(&soup, 3);
        }
        // The counts see what they must: boundary corners and ends on an open grid.
        let grid = HalfedgeMesh::from_soup(&shapes::grid(2, 1, CellKind::Quads).unwrap()).unwrap();
        let counts = LevelCounts::of(&CornerMesh::from_halfedge(&grid));
        assert_eq!((counts.interior_edges, counts.boundary_edges, counts.boundary_ends), (1, 6, 2));
        assert_eq!((counts.interior_vertices, counts.boundary_corners), (0, 8));
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
        #[test]
        fn level_counts_follow_random_meshes(soup in mesh_topo::testing::arb_mesh()) {
            assert_counts_follow(&soup, 2);
        }
    }

    #[test]
    fn too_many_levels_fail_before_any_work() {
        // The cube's corners quadruple every level (24 * 4^k); at level 13 the check of
        // the fine corners (twice the corners plus four per interior edge: 4 * 24 * 4^13)
        // exceeds the u32 range, so 14 levels or more fail at once, naming that count.
        let cube = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        for levels in [14, 30, u32::MAX] {
            let error = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, levels)).unwrap_err();
            let expected =
                DooError::TooLarge { what: "fine corners", count: 4 * 24 * 4usize.pow(13), max: NONE as usize - 1 };
            assert_eq!(error, expected, "{levels} levels");
        }
        // Under the Chaikin rule a lone quad grows (its boundary ring doubles every level)
        // where the Shrink rule's does not: its own counts (corners `C_k = 12 * 4^k - 8 *
        // 2^k`, boundary edges `4 * 2^k`) refuse the step from level 14 at once, by the
        // check its build makes first. Before, only the Shrink counts were checked, and
        // the levels were built until an allocation failed.
        let quad = HalfedgeMesh::from_soup(&shapes::grid(1, 1, CellKind::Quads).unwrap()).unwrap();
        let corners = 12 * 4usize.pow(14) - 8 * 2usize.pow(14);
        let interior_edges = (corners - 4 * 2usize.pow(14)) / 2;
        let expected = DooError::TooLarge {
            what: "fine corners",
            count: 2 * corners + 4 * interior_edges,
            max: NONE as usize - 1,
        };
        for levels in [15, 16, MAX_LEVELS + 1, u32::MAX] {
            let chaikin = DooOptions::new(FaceRule::DooSabin, levels).with_boundary(BoundaryRule::Chaikin);
            assert_eq!(subdivide(&quad, &chaikin).unwrap_err(), expected, "{levels} levels");
        }
        let grid = HalfedgeMesh::from_soup(&shapes::grid(2, 2, CellKind::Quads).unwrap()).unwrap();
        let chaikin = DooOptions { boundary: BoundaryRule::Chaikin, ..DooOptions::new(FaceRule::DooSabin, 40) };
        assert!(matches!(subdivide(&grid, &chaikin), Err(DooError::TooLarge { what: "fine corners", .. })));
        // An open mesh that shrinks does not grow: a single quad takes every level up to
        // the limit, and no more (before the limit, `u32::MAX` levels of it ran for hours;
        // so did a mesh without faces).
        let fine = subdivide(&quad, &DooOptions::new(FaceRule::DooSabin, MAX_LEVELS)).unwrap();
        assert_eq!((fine.vertex_count(), fine.face_count()), (4, 1));
        let points = PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X], Vec::<[u32; 3]>::new());
        let faceless = HalfedgeMesh::from_soup(&points).unwrap();
        let not_growing =
            [(&quad, BoundaryRule::Shrink), (&faceless, BoundaryRule::Shrink), (&faceless, BoundaryRule::Chaikin)];
        for (mesh, boundary) in not_growing {
            for rule in [FaceRule::DooSabin, FaceRule::Centroid { a: 0.25 }] {
                for levels in [MAX_LEVELS + 1, u32::MAX] {
                    let options = DooOptions::new(rule, levels).with_boundary(boundary);
                    let error = subdivide(mesh, &options).unwrap_err();
                    let DooError::InvalidParameter { name: "levels", value, reason } = error else {
                        panic!("{levels} levels: {error}");
                    };
                    assert_eq!(value, levels as f64);
                    assert!(reason.contains(&format!("at most {MAX_LEVELS} levels")), "{reason}");
                }
            }
        }
    }

    /// Finite coordinates whose rules overflow give an error naming the fine vertex, not
    /// infinities; large coordinates that do not overflow subdivide as usual.
    #[test]
    fn overflowing_coordinates_are_an_error() {
        // The cube with corners at -1 and 1, scaled.
        let mut cube = shapes::cube();
        cube.positions.iter_mut().for_each(|p| *p = 2.0 * *p - DVec3::ONE);
        let scaled = |factor: f64| {
            let positions = cube.positions.iter().map(|p| *p * factor).collect();
            HalfedgeMesh::from_soup(&PolygonSoup { positions, ..cube.clone() }).unwrap()
        };
        let mut overflowed = 0;
        for rule in [FaceRule::DooSabin, FaceRule::Simple, FaceRule::Centroid { a: 0.5 }] {
            let unit = subdivide(&scaled(1.0), &DooOptions::new(rule, 2)).unwrap();
            let same_as_unit = |fine: &DooMesh, factor: f64| {
                fine.positions.iter().zip(&unit.positions).all(|(p, q)| (*p / factor - *q).length() < 1e-12)
            };
            // Large, far from overflowing: the unit cube's result, scaled.
            assert!(same_as_unit(&subdivide(&scaled(1e300), &DooOptions::new(rule, 2)).unwrap(), 1e300));
            // At 1.7e308 a sum of two coordinates overflows: an error if the rule's sums
            // do (the centroid's does), else the scaled result, finite.
            match subdivide(&scaled(1.7e308), &DooOptions::new(rule, 2)) {
                Err(DooError::Overflow { largest, .. }) => {
                    assert_eq!(largest, 1.7e308);
                    overflowed += 1;
                }
                Ok(fine) => assert!(same_as_unit(&fine, 1.7e308), "{rule:?}"),
                Err(error) => panic!("{rule:?}: {error}"),
            }
        }
        assert!(overflowed > 0);
    }

    #[test]
    fn cube_counts_and_validity() {
        let fine = doo(&shapes::cube(), FaceRule::DooSabin, 1);
        assert_eq!((fine.vertex_count(), fine.face_count()), (24, 26));
        assert_eq!(fine.kind_counts(), [6, 12, 8]);
        let mesh = fine.to_mesh().unwrap();
        assert_eq!(mesh.topology_stats().genus, 0);
        for v in mesh.vertices() {
            assert_eq!(mesh.valence(v), 4);
        }
        // F_V faces of the cube are triangles, F_E quads.
        for f in 0..fine.face_count() {
            let expected = match fine.face_kind(f) {
                FaceKind::Face | FaceKind::Edge => 4,
                FaceKind::Vertex => 3,
            };
            assert_eq!(fine.face(f).len(), expected);
        }
    }

    #[test]
    fn index_arithmetic_equals_a_fresh_half_edge_build() {
        // Level 2 computed from level 1's corner arrays must equal level 2 computed from
        // a half-edge mesh rebuilt from level 1's soup (faces, order, origins, positions).
        for soup in [
            shapes::cube(),
            shapes::torus(5, 4, CellKind::Mixed).unwrap(),
            shapes::grid(3, 4, CellKind::Mixed).unwrap(),
            shapes::icosahedron(),
        ] {
            for rule in [FaceRule::DooSabin, FaceRule::Simple, FaceRule::CENTROID_HALF] {
                let two = doo(&soup, rule, 2);
                let one = doo(&soup, rule, 1);
                let again = doo(&one.to_soup(), rule, 1);
                assert_eq!(two.topology, again.topology);
                assert_eq!(two.positions, again.positions);
                two.to_mesh().unwrap().validate().unwrap();
            }
        }
    }

    #[test]
    fn boundary_gets_no_edge_or_vertex_faces() {
        let grid = shapes::grid(3, 2, CellKind::Quads).unwrap();
        let fine = doo(&grid, FaceRule::DooSabin, 1);
        // 6 faces, 7 interior edges, 2 interior vertices.
        assert_eq!(fine.kind_counts(), [6, 7, 2]);
        let mesh = fine.to_mesh().unwrap();
        assert_eq!(mesh.topology_stats().boundary_loops, 1);
    }

    #[test]
    fn valence_two_interior_vertex_is_an_error() {
        // Two triangles glued along all three edges: a closed "pillow", every vertex has
        // valence 2.
        let soup = PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2], [0, 2, 1]]);
        match subdivide_soup(&soup, &DooOptions::default()) {
            Err(DooError::ValenceTwoVertex { vertex: 0 }) => {}
            Err(DooError::Mesh(_)) => {} // mesh-topo may already reject the pillow
            other => panic!("unexpected {other:?}"),
        }
    }

    #[test]
    fn nan_is_an_error() {
        let mut mesh = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        mesh.positions_mut()[3].y = f64::NAN;
        assert!(matches!(subdivide(&mesh, &DooOptions::default()), Err(DooError::NonFinite { vertex: 3, .. })));
    }

    #[test]
    fn levels_zero_returns_the_input() {
        let fine = doo(&shapes::cube(), FaceRule::DooSabin, 0);
        assert_eq!(fine.to_soup(), shapes::cube());
    }
}
