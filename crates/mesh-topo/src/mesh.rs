//! The half-edge mesh: construction from a soup with full validation, element access
//! and circulators.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::error::{InvariantError, MeshError};
use crate::ids::{EdgeId, FaceId, HalfedgeId, MAX_ELEMENTS, VertexId};
use crate::soup::PolygonSoup;

/// Sentinel for "no element" in the raw connectivity arrays.
pub(crate) const INVALID: u32 = u32::MAX;

/// A manifold, consistently oriented polygon mesh with boundaries, stored as half-edges.
///
/// # Layout
/// Struct-of-arrays with `u32` indices: one array per relation (`to_vertex`, `next`,
/// `prev`, `face` per half-edge; one outgoing half-edge per vertex; one half-edge per
/// face). Half-edges come in twin pairs `2e`, `2e + 1`, so [`HalfedgeId::twin`] and
/// [`HalfedgeId::edge`] are index arithmetic (the layout of pmp and OpenMesh).
///
/// # Order guarantees
/// Building keeps everything the caller gave: vertex `i` of the soup is [`VertexId`] `i`
/// (unreferenced vertices included), face `f` is [`FaceId`] `f`, and
/// [`face_vertices`](Self::face_vertices) starts at the face's first corner as given.
/// Edges are numbered in order of first appearance when the faces are scanned in order,
/// corner by corner; half-edge `2e` is that first appearance (it always has a face) and
/// `2e + 1` its twin (a face or the boundary). [`to_soup`](Self::to_soup) therefore
/// returns the input soup exactly.
///
/// # Circulation order
/// Faces are counter-clockwise seen from outside. Around a vertex,
/// [`outgoing_halfedges`](Self::outgoing_halfedges) turns counter-clockwise; for a
/// boundary vertex it starts at the outgoing *boundary* half-edge (whose face is `None`),
/// so the faces follow in fan order.
///
/// # Handles
/// [`VertexId`], [`FaceId`], [`EdgeId`] and [`HalfedgeId`] are plain indices, not tied
/// to a mesh: the accessors that take one index this mesh's arrays with it and panic if
/// it is out of range (a handle of a larger mesh); a handle of another mesh that is in
/// range names this mesh's element of the same index. Get handles from the mesh they are
/// used with ([`vertex`](Self::vertex) and the others check the index).
///
/// ```
/// use glam::DVec3;
/// use mesh_topo::{HalfedgeMesh, PolygonSoup};
///
/// // A square split into two triangles.
/// let soup = PolygonSoup::from_faces(
///     vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
///     [[0u32, 1, 2], [0, 2, 3]],
/// );
/// let mesh = HalfedgeMesh::from_soup(&soup)?;
/// assert_eq!((mesh.vertex_count(), mesh.edge_count(), mesh.face_count()), (4, 5, 2));
/// assert_eq!(mesh.halfedge_count(), 2 * mesh.edge_count());
/// assert_eq!(mesh.vertex(4), None); // handles are checked against the mesh
/// let v0 = mesh.vertex(0).unwrap();
/// assert_eq!(mesh.position(v0), DVec3::ZERO);
/// assert!(mesh.is_boundary_vertex(v0));
/// assert_eq!(mesh.valence(v0), 3);
/// assert_eq!(mesh.to_soup(), soup);
/// # Ok::<(), mesh_topo::MeshError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(into = "PolygonSoup", try_from = "PolygonSoup")]
pub struct HalfedgeMesh {
    positions: Vec<DVec3>,
    /// Outgoing half-edge per vertex (the boundary one for boundary vertices), or INVALID.
    vertex_halfedge: Vec<u32>,
    /// Target vertex per half-edge.
    halfedge_to: Vec<u32>,
    halfedge_next: Vec<u32>,
    halfedge_prev: Vec<u32>,
    /// Face on the left of each half-edge, INVALID on the boundary.
    halfedge_face: Vec<u32>,
    /// Half-edge leaving the face's first corner.
    face_halfedge: Vec<u32>,
}

impl From<HalfedgeMesh> for PolygonSoup {
    fn from(mesh: HalfedgeMesh) -> Self {
        mesh.to_soup()
    }
}

impl TryFrom<PolygonSoup> for HalfedgeMesh {
    type Error = MeshError;
    fn try_from(soup: PolygonSoup) -> Result<Self, MeshError> {
        HalfedgeMesh::from_soup(&soup)
    }
}

impl HalfedgeMesh {
    /// Builds a mesh from positions and per-face vertex index lists.
    ///
    /// ```
    /// use glam::DVec3;
    /// use mesh_topo::{HalfedgeMesh, MeshError};
    ///
    /// let positions = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
    /// let mesh = HalfedgeMesh::from_faces(positions.clone(), [[0u32, 1, 2]])?;
    /// assert_eq!((mesh.vertex_count(), mesh.edge_count(), mesh.face_count()), (3, 3, 1));
    /// // Vertex 3 does not exist: the error names the face and the corner.
    /// let err = HalfedgeMesh::from_faces(positions, [[0u32, 1, 3]]).unwrap_err();
    /// assert_eq!(err, MeshError::IndexOutOfRange { face: 0, corner: 2, index: 3, vertex_count: 3 });
    /// # Ok::<(), MeshError>(())
    /// ```
    ///
    /// # Errors
    /// See [`from_soup`](Self::from_soup).
    pub fn from_faces<F, I>(positions: Vec<DVec3>, faces: F) -> Result<Self, MeshError>
    where
        F: IntoIterator<Item = I>,
        I: AsRef<[u32]>,
    {
        Self::from_soup(&PolygonSoup::from_faces(positions, faces))
    }

    /// Builds the half-edge structure of a polygon soup, checking every condition for a
    /// manifold, consistently oriented mesh. Runs in time linear in the number of face
    /// corners (plus a sort of each vertex's outgoing edges by target).
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh, MeshError, PolygonSoup, shapes};
    ///
    /// let mesh = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// assert_eq!((mesh.vertex_count(), mesh.edge_count(), mesh.face_count()), (8, 12, 6));
    /// // Both triangles run along 0 -> 1: no consistent orientation exists.
    /// let positions = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::NEG_Y];
    /// let soup = PolygonSoup::from_faces(positions, [[0u32, 1, 2], [0, 1, 3]]);
    /// assert_eq!(
    ///     HalfedgeMesh::from_soup(&soup).unwrap_err(),
    ///     MeshError::InconsistentOrientation { from: 0, to: 1, first_face: 0, second_face: 1 }
    /// );
    /// # Ok::<(), MeshError>(())
    /// ```
    ///
    /// # Performance
    /// A few passes over flat arrays (see the private `Builder` docs), one thread: about
    /// 15 million faces per second on a 3 674-triangle mesh, 7 million on a 75 000-triangle
    /// scan (whose vertex order is scattered) and 11 million on a million-triangle torus
    /// (criterion bench `build`), faster than building CGAL's `Surface_mesh` or
    /// OpenMesh's `PolyMesh` face by face from the same soup.
    ///
    /// # Errors
    /// The first problem found, as a [`MeshError`] naming the face, vertex or edge:
    /// non-finite coordinates, index out of range, faces with fewer than 3 corners or a
    /// repeated vertex, non-manifold edges, inconsistent orientation, non-manifold
    /// vertices, or more elements than `u32` indices address. Building never panics.
    pub fn from_soup(soup: &PolygonSoup) -> Result<Self, MeshError> {
        Builder::new(soup)?.build()
    }

    // ----------------------------------------------------------------------------------
    // Counts and element handles.

    /// Number of vertices, isolated ones included.
    #[inline]
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of half-edges (twice the number of edges).
    #[inline]
    pub fn halfedge_count(&self) -> usize {
        self.halfedge_to.len()
    }

    /// Number of undirected edges.
    #[inline]
    pub fn edge_count(&self) -> usize {
        self.halfedge_to.len() / 2
    }

    /// Number of faces.
    #[inline]
    pub fn face_count(&self) -> usize {
        self.face_halfedge.len()
    }

    /// The vertex with index `i`, if it exists.
    #[inline]
    pub fn vertex(&self, i: usize) -> Option<VertexId> {
        (i < self.vertex_count()).then(|| VertexId::new(i as u32))
    }

    /// The face with index `i`, if it exists.
    #[inline]
    pub fn face(&self, i: usize) -> Option<FaceId> {
        (i < self.face_count()).then(|| FaceId::new(i as u32))
    }

    /// The edge with index `i`, if it exists.
    #[inline]
    pub fn edge(&self, i: usize) -> Option<EdgeId> {
        (i < self.edge_count()).then(|| EdgeId::new(i as u32))
    }

    /// The half-edge with index `i`, if it exists.
    #[inline]
    pub fn halfedge(&self, i: usize) -> Option<HalfedgeId> {
        (i < self.halfedge_count()).then(|| HalfedgeId::new(i as u32))
    }

    /// All vertices in index order.
    #[inline]
    pub fn vertices(&self) -> impl ExactSizeIterator<Item = VertexId> + '_ {
        (0..self.vertex_count() as u32).map(VertexId::new)
    }

    /// All faces in index order.
    #[inline]
    pub fn faces(&self) -> impl ExactSizeIterator<Item = FaceId> + '_ {
        (0..self.face_count() as u32).map(FaceId::new)
    }

    /// All edges in index order.
    #[inline]
    pub fn edges(&self) -> impl ExactSizeIterator<Item = EdgeId> + '_ {
        (0..self.edge_count() as u32).map(EdgeId::new)
    }

    /// All half-edges in index order.
    #[inline]
    pub fn halfedges(&self) -> impl ExactSizeIterator<Item = HalfedgeId> + '_ {
        (0..self.halfedge_count() as u32).map(HalfedgeId::new)
    }

    // ----------------------------------------------------------------------------------
    // Geometry.

    /// All positions, indexed by vertex index.
    #[inline]
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// Mutable positions. Connectivity cannot be changed through this; a non-finite
    /// value written here is reported by [`validate`](Self::validate).
    #[inline]
    pub fn positions_mut(&mut self) -> &mut [DVec3] {
        &mut self.positions
    }

    /// Position of a vertex.
    ///
    /// # Panics
    /// If `v` is not a vertex of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn position(&self, v: VertexId) -> DVec3 {
        self.positions[v.index()]
    }

    /// Replaces all positions (same count). Returns the old ones.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh, PositionsError, shapes};
    ///
    /// let mut mesh = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
    /// let doubled: Vec<DVec3> = mesh.positions().iter().map(|&p| 2.0 * p).collect();
    /// let old = mesh.replace_positions(doubled)?;
    /// assert_eq!(mesh.positions()[0], 2.0 * old[0]);
    /// let err = mesh.replace_positions(vec![DVec3::ZERO; 3]).unwrap_err();
    /// assert_eq!(err, PositionsError::CountMismatch { expected: 4, found: 3 });
    /// assert!(mesh.replace_positions(vec![DVec3::NAN; 4]).is_err());
    /// assert_eq!(mesh.positions()[0], 2.0 * old[0]); // unchanged by the failed calls
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// [`MeshError::TooLarge`] is never returned; a count mismatch or a non-finite value
    /// gives the corresponding error and leaves the mesh unchanged.
    pub fn replace_positions(&mut self, positions: Vec<DVec3>) -> Result<Vec<DVec3>, PositionsError> {
        if positions.len() != self.positions.len() {
            return Err(PositionsError::CountMismatch { expected: self.positions.len(), found: positions.len() });
        }
        check_finite(&positions).map_err(PositionsError::Mesh)?;
        Ok(std::mem::replace(&mut self.positions, positions))
    }

    // ----------------------------------------------------------------------------------
    // Connectivity.

    /// The half-edge after `h` in its face (or boundary loop).
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
    /// let h = mesh.face_halfedge(mesh.face(0).unwrap()); // 0 -> 1
    /// let n = mesh.next(h);
    /// assert_eq!((mesh.origin(n).raw(), mesh.target(n).raw()), (1, 2));
    /// assert_eq!(mesh.next(mesh.next(n)), h); // three steps round the triangle
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `h` is not a half-edge of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn next(&self, h: HalfedgeId) -> HalfedgeId {
        HalfedgeId::new(self.halfedge_next[h.index()])
    }

    /// The half-edge before `h` in its face (or boundary loop).
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
    /// let h = mesh.face_halfedge(mesh.face(0).unwrap()); // 0 -> 1
    /// let p = mesh.prev(h);
    /// assert_eq!((mesh.origin(p).raw(), mesh.target(p).raw()), (2, 0));
    /// // `prev` undoes `next`, on faces and boundary loops alike.
    /// assert!(mesh.halfedges().all(|h| mesh.prev(mesh.next(h)) == h));
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `h` is not a half-edge of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn prev(&self, h: HalfedgeId) -> HalfedgeId {
        HalfedgeId::new(self.halfedge_prev[h.index()])
    }

    /// The twin (opposite) half-edge. Same as [`HalfedgeId::twin`].
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
    /// let h = mesh.face_halfedge(mesh.face(0).unwrap()); // 0 -> 1
    /// let t = mesh.twin(h);
    /// assert_eq!((mesh.origin(t).raw(), mesh.target(t).raw()), (1, 0));
    /// assert!(mesh.is_boundary_halfedge(t)); // a single triangle: the other side is the hole
    /// assert_eq!((mesh.twin(t), t.edge()), (h, h.edge()));
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    #[inline]
    pub fn twin(&self, h: HalfedgeId) -> HalfedgeId {
        h.twin()
    }

    /// The vertex `h` points to.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
    /// let targets: Vec<u32> = mesh.face_halfedges(mesh.face(0).unwrap()).map(|h| mesh.target(h).raw()).collect();
    /// assert_eq!(targets, [1, 2, 0]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `h` is not a half-edge of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn target(&self, h: HalfedgeId) -> VertexId {
        VertexId::new(self.halfedge_to[h.index()])
    }

    /// The vertex `h` starts from.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
    /// let h = mesh.face_halfedge(mesh.face(0).unwrap());
    /// assert_eq!((mesh.origin(h).raw(), mesh.target(h).raw()), (0, 1));
    /// // The origin of a half-edge is the target of its twin.
    /// assert!(mesh.halfedges().all(|h| mesh.origin(h) == mesh.target(h.twin())));
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `h` is not a half-edge of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn origin(&self, h: HalfedgeId) -> VertexId {
        VertexId::new(self.halfedge_to[h.twin().index()])
    }

    /// The face on the left of `h`, or `None` for a boundary half-edge.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// // A square split along the diagonal 0 - 2.
    /// let positions = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    /// let mesh = HalfedgeMesh::from_faces(positions, [[0u32, 1, 2], [0, 2, 3]])?;
    /// let v = |i| mesh.vertex(i).unwrap();
    /// let diagonal = mesh.find_halfedge(v(0), v(2)).unwrap();
    /// assert_eq!(mesh.halfedge_face(diagonal), mesh.face(1));
    /// assert_eq!(mesh.halfedge_face(diagonal.twin()), mesh.face(0));
    /// assert_eq!(mesh.halfedge_face(mesh.find_halfedge(v(1), v(0)).unwrap()), None);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `h` is not a half-edge of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn halfedge_face(&self, h: HalfedgeId) -> Option<FaceId> {
        let f = self.halfedge_face[h.index()];
        (f != INVALID).then(|| FaceId::new(f))
    }

    /// True if `h` has no face (it runs along a hole).
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
    /// for h in mesh.face_halfedges(mesh.face(0).unwrap()) {
    ///     assert!(!mesh.is_boundary_halfedge(h));
    ///     assert!(mesh.is_boundary_halfedge(h.twin()));
    /// }
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `h` is not a half-edge of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn is_boundary_halfedge(&self, h: HalfedgeId) -> bool {
        self.halfedge_face[h.index()] == INVALID
    }

    /// True if one side of the edge has no face.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// // A square split along the diagonal 0 - 2: only the diagonal is interior.
    /// let positions = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    /// let mesh = HalfedgeMesh::from_faces(positions, [[0u32, 1, 2], [0, 2, 3]])?;
    /// let (v0, v2) = (mesh.vertex(0).unwrap(), mesh.vertex(2).unwrap());
    /// assert!(!mesh.is_boundary_edge(mesh.find_halfedge(v0, v2).unwrap().edge()));
    /// assert_eq!(mesh.edges().filter(|&e| mesh.is_boundary_edge(e)).count(), 4);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `e` is not an edge of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn is_boundary_edge(&self, e: EdgeId) -> bool {
        self.is_boundary_halfedge(e.halfedge(0)) || self.is_boundary_halfedge(e.halfedge(1))
    }

    /// An outgoing half-edge of `v` (the boundary one if `v` is on the boundary), or
    /// `None` for an isolated vertex.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// // A triangle and an unused vertex 3.
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z], [[0u32, 1, 2]])?;
    /// let h = mesh.vertex_halfedge(mesh.vertex(0).unwrap()).unwrap();
    /// assert!(mesh.is_boundary_halfedge(h));
    /// // The boundary runs 0 -> 2 -> 1, the hole on its left.
    /// assert_eq!((mesh.origin(h).raw(), mesh.target(h).raw()), (0, 2));
    /// assert_eq!(mesh.vertex_halfedge(mesh.vertex(3).unwrap()), None);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `v` is not a vertex of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn vertex_halfedge(&self, v: VertexId) -> Option<HalfedgeId> {
        let h = self.vertex_halfedge[v.index()];
        (h != INVALID).then(|| HalfedgeId::new(h))
    }

    /// The half-edge leaving the first corner of face `f`.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    ///
    /// let mesh = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let f = mesh.face(1).unwrap(); // the cube's face [4, 5, 7, 6]
    /// let h = mesh.face_halfedge(f);
    /// assert_eq!((mesh.origin(h).raw(), mesh.target(h).raw()), (4, 5));
    /// assert_eq!(mesh.halfedge_face(h), Some(f));
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `f` is not a face of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn face_halfedge(&self, f: FaceId) -> HalfedgeId {
        HalfedgeId::new(self.face_halfedge[f.index()])
    }

    /// The two end vertices of an edge, in the direction of its half-edge 0.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
    /// // Edges are numbered in order of first appearance, in the direction of the face.
    /// let ends: Vec<[u32; 2]> = mesh.edges().map(|e| mesh.edge_vertices(e).map(|v| v.raw())).collect();
    /// assert_eq!(ends, [[0, 1], [1, 2], [2, 0]]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `e` is not an edge of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn edge_vertices(&self, e: EdgeId) -> [VertexId; 2] {
        let h = e.halfedge(0);
        [self.origin(h), self.target(h)]
    }

    /// True if `v` has no incident edge.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// // Vertex 3 is kept but no face uses it.
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z], [[0u32, 1, 2]])?;
    /// let isolated: Vec<u32> = mesh.vertices().filter(|&v| mesh.is_isolated(v)).map(|v| v.raw()).collect();
    /// assert_eq!(isolated, [3]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `v` is not a vertex of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn is_isolated(&self, v: VertexId) -> bool {
        self.vertex_halfedge[v.index()] == INVALID
    }

    /// True if `v` lies on a boundary loop.
    ///
    /// ```
    /// use mesh_topo::HalfedgeMesh;
    /// use mesh_topo::shapes::{self, CellKind};
    ///
    /// // A 2 x 2 grid of quads: only the centre vertex is interior.
    /// let mesh = HalfedgeMesh::from_soup(&shapes::grid(2, 2, CellKind::Quads)?)?;
    /// let interior: Vec<u32> = mesh.vertices().filter(|&v| !mesh.is_boundary_vertex(v)).map(|v| v.raw()).collect();
    /// assert_eq!(interior, [4]);
    /// let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// assert!(cube.vertices().all(|v| !cube.is_boundary_vertex(v)));
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `v` is not a vertex of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn is_boundary_vertex(&self, v: VertexId) -> bool {
        self.vertex_halfedge(v).is_some_and(|h| self.is_boundary_halfedge(h))
    }

    /// Number of edges at `v`. For an interior vertex this is also its number of faces;
    /// a boundary vertex has one face fewer than its valence.
    ///
    /// ```
    /// use mesh_topo::HalfedgeMesh;
    /// use mesh_topo::shapes::{self, CellKind};
    ///
    /// let mesh = HalfedgeMesh::from_soup(&shapes::grid(2, 2, CellKind::Quads)?)?;
    /// let valences: Vec<usize> = mesh.vertices().map(|v| mesh.valence(v)).collect();
    /// assert_eq!(valences, [2, 3, 2, 3, 4, 3, 2, 3, 2]);
    /// // Every edge has two ends.
    /// assert_eq!(valences.iter().sum::<usize>(), 2 * mesh.edge_count());
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `v` is not a vertex of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn valence(&self, v: VertexId) -> usize {
        self.outgoing_halfedges(v).count()
    }

    /// Number of corners of face `f`.
    ///
    /// ```
    /// use mesh_topo::HalfedgeMesh;
    /// use mesh_topo::shapes::{self, CellKind};
    ///
    /// // Quads and pairs of triangles in a checkerboard.
    /// let mesh = HalfedgeMesh::from_soup(&shapes::grid(2, 2, CellKind::Mixed)?)?;
    /// let degrees: Vec<usize> = mesh.faces().map(|f| mesh.face_degree(f)).collect();
    /// assert_eq!(degrees, [4, 3, 3, 3, 3, 4]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `f` is not a face of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn face_degree(&self, f: FaceId) -> usize {
        self.face_halfedges(f).count()
    }

    /// The half-edge from `from` to `to`, if that edge exists.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// // A square split along the diagonal 0 - 2.
    /// let positions = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    /// let mesh = HalfedgeMesh::from_faces(positions, [[0u32, 1, 2], [0, 2, 3]])?;
    /// let v = |i| mesh.vertex(i).unwrap();
    /// let h = mesh.find_halfedge(v(0), v(2)).unwrap();
    /// assert_eq!((mesh.origin(h), mesh.target(h)), (v(0), v(2)));
    /// assert_eq!(mesh.find_halfedge(v(2), v(0)), Some(h.twin()));
    /// assert_eq!(mesh.find_halfedge(v(1), v(3)), None); // the other diagonal is no edge
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `from` or `to` is not a vertex of this mesh (see [Handles](Self#handles)).
    pub fn find_halfedge(&self, from: VertexId, to: VertexId) -> Option<HalfedgeId> {
        self.outgoing_halfedges(from).find(|&h| self.target(h) == to)
    }

    // ----------------------------------------------------------------------------------
    // Circulators.

    /// The outgoing half-edges of `v`, counter-clockwise, starting at
    /// [`vertex_halfedge`](Self::vertex_halfedge) (the boundary half-edge for a boundary
    /// vertex). Empty for an isolated vertex.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// // A square split along the diagonal 0 - 2; vertex 0 is on the boundary.
    /// let positions = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    /// let mesh = HalfedgeMesh::from_faces(positions, [[0u32, 1, 2], [0, 2, 3]])?;
    /// let v0 = mesh.vertex(0).unwrap();
    /// let out: Vec<_> = mesh.outgoing_halfedges(v0).collect();
    /// // From the boundary half-edge 0 -> 3, counter-clockwise across the hole to 1, then 2.
    /// assert!(mesh.is_boundary_halfedge(out[0]));
    /// assert_eq!(out.iter().map(|&h| mesh.target(h).raw()).collect::<Vec<_>>(), [3, 1, 2]);
    /// assert!(out.iter().all(|&h| mesh.origin(h) == v0));
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `v` is not a vertex of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn outgoing_halfedges(&self, v: VertexId) -> VertexCirculator<'_> {
        let start = self.vertex_halfedge[v.index()];
        VertexCirculator { mesh: self, start, current: start }
    }

    /// The neighbours of `v` (targets of its outgoing half-edges), counter-clockwise.
    ///
    /// ```
    /// use mesh_topo::HalfedgeMesh;
    /// use mesh_topo::shapes::{self, CellKind};
    ///
    /// // The centre (1, 1) of a 2 x 2 grid: neighbours 3 = (0, 1), 1 = (1, 0), 5 = (2, 1), 7 = (1, 2).
    /// let mesh = HalfedgeMesh::from_soup(&shapes::grid(2, 2, CellKind::Quads)?)?;
    /// let ring: Vec<u32> = mesh.vertex_neighbors(mesh.vertex(4).unwrap()).map(|v| v.raw()).collect();
    /// assert_eq!(ring, [3, 1, 5, 7]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `v` is not a vertex of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn vertex_neighbors(&self, v: VertexId) -> impl Iterator<Item = VertexId> + '_ {
        self.outgoing_halfedges(v).map(|h| self.target(h))
    }

    /// The faces around `v`, counter-clockwise (for a boundary vertex from the face after
    /// the boundary to the face before it).
    ///
    /// ```
    /// use mesh_topo::HalfedgeMesh;
    /// use mesh_topo::shapes::{self, CellKind};
    ///
    /// // A 2 x 2 grid: cells 0 and 1 at the bottom, 2 and 3 at the top.
    /// let mesh = HalfedgeMesh::from_soup(&shapes::grid(2, 2, CellKind::Quads)?)?;
    /// let around = |v| mesh.vertex_faces(mesh.vertex(v).unwrap()).map(|f| f.raw()).collect::<Vec<_>>();
    /// assert_eq!(around(4), [0, 1, 3, 2]); // the centre, counter-clockwise
    /// assert_eq!(around(1), [1, 0]); // bottom middle: from after the hole to before it
    /// assert_eq!(around(0), [0]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `v` is not a vertex of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn vertex_faces(&self, v: VertexId) -> impl Iterator<Item = FaceId> + '_ {
        self.outgoing_halfedges(v).filter_map(|h| self.halfedge_face(h))
    }

    /// The half-edges of face `f` in order, starting at its first corner.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    ///
    /// let mesh = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let f = mesh.face(1).unwrap();
    /// let loop_: Vec<_> = mesh.face_halfedges(f).collect();
    /// assert_eq!(loop_.len(), 4);
    /// assert_eq!(loop_[0], mesh.face_halfedge(f));
    /// for (k, &h) in loop_.iter().enumerate() {
    ///     assert_eq!(mesh.next(h), loop_[(k + 1) % 4]);
    ///     assert_eq!(mesh.halfedge_face(h), Some(f));
    /// }
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `f` is not a face of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn face_halfedges(&self, f: FaceId) -> LoopCirculator<'_> {
        let start = self.face_halfedge[f.index()];
        LoopCirculator { mesh: self, start, current: start }
    }

    /// The half-edges of the loop through `h` (a face or a boundary loop), starting at `h`.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
    /// let outside = mesh.face_halfedge(mesh.face(0).unwrap()).twin(); // 1 -> 0
    /// let hole: Vec<u32> = mesh.halfedge_loop(outside).map(|h| mesh.origin(h).raw()).collect();
    /// assert_eq!(hole, [1, 0, 2]); // clockwise seen from +z: the hole is on the left
    /// assert!(mesh.halfedge_loop(outside).all(|h| mesh.is_boundary_halfedge(h)));
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// When iterated, if `h` is not a half-edge of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn halfedge_loop(&self, h: HalfedgeId) -> LoopCirculator<'_> {
        LoopCirculator { mesh: self, start: h.raw(), current: h.raw() }
    }

    /// The corners of face `f` in order, as given when the mesh was built.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[1u32, 2, 0]])?;
    /// let corners: Vec<u32> = mesh.face_vertices(mesh.face(0).unwrap()).map(|v| v.raw()).collect();
    /// assert_eq!(corners, [1, 2, 0]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `f` is not a face of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn face_vertices(&self, f: FaceId) -> impl Iterator<Item = VertexId> + '_ {
        self.face_halfedges(f).map(|h| self.origin(h))
    }

    /// The faces sharing an edge with `f`, in the order of `f`'s half-edges (boundary
    /// edges skipped).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    ///
    /// // Cube face 0 is [0, 2, 3, 1]; across its sides lie faces 4, 3, 5 and 2.
    /// let mesh = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let around: Vec<u32> = mesh.face_neighbors(mesh.face(0).unwrap()).map(|f| f.raw()).collect();
    /// assert_eq!(around, [4, 3, 5, 2]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Panics
    /// If `f` is not a face of this mesh (see [Handles](Self#handles)).
    #[inline]
    pub fn face_neighbors(&self, f: FaceId) -> impl Iterator<Item = FaceId> + '_ {
        self.face_halfedges(f).filter_map(|h| self.halfedge_face(h.twin()))
    }

    // ----------------------------------------------------------------------------------
    // Conversion and checks.

    /// The mesh as a polygon soup: positions and faces exactly as given to
    /// [`from_soup`](Self::from_soup).
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh, PolygonSoup};
    ///
    /// // Corner order and the unused vertex 3 come back as given.
    /// let soup = PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z], [[2u32, 0, 1]]);
    /// let mesh = HalfedgeMesh::from_soup(&soup)?;
    /// assert_eq!(mesh.to_soup(), soup);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    pub fn to_soup(&self) -> PolygonSoup {
        let mut soup = PolygonSoup::with_capacity(self.vertex_count(), self.face_count(), self.halfedge_count());
        soup.positions.extend_from_slice(&self.positions);
        for f in self.faces() {
            soup.indices.extend(self.face_vertices(f).map(VertexId::raw));
            soup.offsets.push(soup.indices.len() as u32);
        }
        soup
    }

    /// The faces that `keep` selects, as a soup of their own: the vertices they use,
    /// numbered in order of first use (faces in order, each from its first corner), and
    /// for every vertex of this mesh its number in the soup (`None` if no kept face uses
    /// it). Corner order and positions are kept as they are. With
    /// [`ring_distances`](Self::ring_distances) it cuts out a neighbourhood, say the
    /// faces around a vertex to subdivide or fit on their own.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    ///
    /// // The cube's face 1, [4, 5, 7, 6], alone.
    /// let mesh = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// let (soup, new_index) = mesh.extract_faces(|f| f.raw() == 1);
    /// assert_eq!((soup.vertex_count(), soup.face(0)), (4, &[0, 1, 2, 3][..]));
    /// assert_eq!((new_index[4], new_index[7], new_index[0]), (Some(0), Some(2), None));
    /// assert_eq!(soup.positions[2], mesh.positions()[7]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    pub fn extract_faces(&self, mut keep: impl FnMut(FaceId) -> bool) -> (PolygonSoup, Vec<Option<u32>>) {
        let mut new_index: Vec<Option<u32>> = vec![None; self.vertex_count()];
        let mut soup = PolygonSoup::with_capacity(0, 0, 0);
        for f in self.faces().filter(|&f| keep(f)) {
            for v in self.face_vertices(f) {
                let index = *new_index[v.index()].get_or_insert_with(|| {
                    soup.positions.push(self.positions[v.index()]);
                    (soup.positions.len() - 1) as u32
                });
                soup.indices.push(index);
            }
            soup.offsets.push(soup.indices.len() as u32);
        }
        (soup, new_index)
    }

    /// Checks every internal invariant of the half-edge structure (twins, next/prev
    /// cycles, face and vertex references, boundary conventions, manifold fans, finite
    /// positions). Building from a soup always gives a valid mesh; this exists for tests
    /// and for code that edits meshes.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    ///
    /// let mut mesh = HalfedgeMesh::from_soup(&shapes::cube())?;
    /// assert_eq!(mesh.validate(), Ok(()));
    /// mesh.positions_mut()[3].x = f64::NAN;
    /// assert!(mesh.validate().is_err());
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    ///
    /// # Errors
    /// The first broken invariant, described in words.
    pub fn validate(&self) -> Result<(), InvariantError> {
        let fail = |msg: String| Err(InvariantError(msg));
        let nh = self.halfedge_count() as u32;
        let nv = self.vertex_count() as u32;
        let nf = self.face_count() as u32;
        if !self.halfedge_to.len().is_multiple_of(2) {
            return fail("odd number of half-edges".into());
        }
        for (name, len) in
            [("next", self.halfedge_next.len()), ("prev", self.halfedge_prev.len()), ("face", self.halfedge_face.len())]
        {
            if len != nh as usize {
                return fail(format!("half-edge array {name} has length {len}, expected {nh}"));
            }
        }
        if self.vertex_halfedge.len() != nv as usize {
            return fail("vertex array length mismatch".into());
        }
        if let Err(e) = check_finite(&self.positions) {
            return fail(e.to_string());
        }
        for h in 0..nh {
            let (next, prev, to, face) = (
                self.halfedge_next[h as usize],
                self.halfedge_prev[h as usize],
                self.halfedge_to[h as usize],
                self.halfedge_face[h as usize],
            );
            if next >= nh || prev >= nh || to >= nv || (face != INVALID && face >= nf) {
                return fail(format!("half-edge {h}: reference out of range"));
            }
            if self.halfedge_prev[next as usize] != h || self.halfedge_next[prev as usize] != h {
                return fail(format!("half-edge {h}: next/prev are not inverse"));
            }
            if self.halfedge_face[next as usize] != face {
                return fail(format!("half-edge {h}: next lies in another face"));
            }
            let origin_of_next = self.halfedge_to[(next ^ 1) as usize];
            if origin_of_next != to {
                return fail(format!("half-edge {h}: next does not start at its target"));
            }
            if to == self.halfedge_to[(h ^ 1) as usize] {
                return fail(format!("half-edge {h}: loop edge"));
            }
            if face == INVALID && self.halfedge_face[(h ^ 1) as usize] == INVALID {
                return fail(format!("edge {}: both sides are boundary", h / 2));
            }
        }
        for f in 0..nf {
            let h = self.face_halfedge[f as usize];
            if h >= nh || self.halfedge_face[h as usize] != f {
                return fail(format!("face {f}: its half-edge does not belong to it"));
            }
            let degree = self.face_halfedges(FaceId::new(f)).take(nh as usize + 1).count();
            if degree < 3 || degree > nh as usize {
                return fail(format!("face {f}: degree {degree}"));
            }
        }
        let mut seen_out = vec![0u32; nv as usize];
        for h in 0..nh {
            seen_out[self.halfedge_to[(h ^ 1) as usize] as usize] += 1;
        }
        for v in 0..nv {
            let h = self.vertex_halfedge[v as usize];
            if h == INVALID {
                if seen_out[v as usize] != 0 {
                    return fail(format!("vertex {v}: has edges but no half-edge"));
                }
                continue;
            }
            if h >= nh || self.halfedge_to[(h ^ 1) as usize] != v {
                return fail(format!("vertex {v}: its half-edge does not start there"));
            }
            let boundary_out = self
                .outgoing_halfedges(VertexId::new(v))
                .take(nh as usize + 1)
                .filter(|&o| self.is_boundary_halfedge(o))
                .count();
            let valence = self.outgoing_halfedges(VertexId::new(v)).take(nh as usize + 1).count();
            if valence != seen_out[v as usize] as usize {
                return fail(format!(
                    "vertex {v}: circulation reaches {valence} of {} half-edges",
                    seen_out[v as usize]
                ));
            }
            if boundary_out > 1 || (boundary_out == 1 && !self.is_boundary_halfedge(HalfedgeId::new(h))) {
                return fail(format!("vertex {v}: boundary half-edge convention broken"));
            }
        }
        Ok(())
    }

    /// Raw target-vertex array, one entry per half-edge (for algorithms that want flat
    /// arrays; see the type docs for the layout).
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// // Half-edges 0, 2, 4 run 0 -> 1 -> 2 -> 0 in the face; 1, 3, 5 are their twins.
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
    /// assert_eq!(mesh.raw_halfedge_targets(), &[1, 0, 2, 1, 0, 2]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    #[inline]
    pub fn raw_halfedge_targets(&self) -> &[u32] {
        &self.halfedge_to
    }

    /// Raw next array, one entry per half-edge.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
    /// // The face loop 0 -> 2 -> 4 and the boundary loop 1 -> 5 -> 3.
    /// assert_eq!(mesh.raw_halfedge_next(), &[2, 5, 4, 1, 0, 3]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    #[inline]
    pub fn raw_halfedge_next(&self) -> &[u32] {
        &self.halfedge_next
    }

    /// Raw face array, one entry per half-edge (`u32::MAX` on the boundary).
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
    /// assert_eq!(mesh.raw_halfedge_faces(), &[0, u32::MAX, 0, u32::MAX, 0, u32::MAX]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    #[inline]
    pub fn raw_halfedge_faces(&self) -> &[u32] {
        &self.halfedge_face
    }

    /// Raw array of the half-edge leaving each face's first corner, one entry per face
    /// (see [`face_halfedge`](Self::face_halfedge)).
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// // A square split along the diagonal: face 1 starts with the diagonal's twin, 0 -> 2.
    /// let positions = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    /// let mesh = HalfedgeMesh::from_faces(positions, [[0u32, 1, 2], [0, 2, 3]])?;
    /// assert_eq!(mesh.raw_face_halfedges(), &[0, 5]);
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    #[inline]
    pub fn raw_face_halfedges(&self) -> &[u32] {
        &self.face_halfedge
    }
}

/// Error from [`HalfedgeMesh::replace_positions`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PositionsError {
    /// The new array has another length than the vertex count.
    #[error("expected {expected} positions, got {found}")]
    CountMismatch {
        /// Vertex count of the mesh.
        expected: usize,
        /// Length given.
        found: usize,
    },
    /// A new position is not finite.
    #[error(transparent)]
    Mesh(MeshError),
}

/// Counter-clockwise iterator over the outgoing half-edges of a vertex.
#[derive(Clone)]
pub struct VertexCirculator<'a> {
    mesh: &'a HalfedgeMesh,
    start: u32,
    current: u32,
}

impl Iterator for VertexCirculator<'_> {
    type Item = HalfedgeId;
    #[inline]
    fn next(&mut self) -> Option<HalfedgeId> {
        if self.current == INVALID {
            return None;
        }
        let h = self.current;
        // Counter-clockwise: the twin of the previous half-edge leaves the same vertex.
        let following = self.mesh.halfedge_prev[h as usize] ^ 1;
        self.current = if following == self.start { INVALID } else { following };
        Some(HalfedgeId::new(h))
    }
}

/// Iterator over the half-edges of one face or boundary loop.
#[derive(Clone)]
pub struct LoopCirculator<'a> {
    mesh: &'a HalfedgeMesh,
    start: u32,
    current: u32,
}

impl Iterator for LoopCirculator<'_> {
    type Item = HalfedgeId;
    #[inline]
    fn next(&mut self) -> Option<HalfedgeId> {
        if self.current == INVALID {
            return None;
        }
        let h = self.current;
        let following = self.mesh.halfedge_next[h as usize];
        self.current = if following == self.start { INVALID } else { following };
        Some(HalfedgeId::new(h))
    }
}

fn check_finite(positions: &[DVec3]) -> Result<(), MeshError> {
    for (vertex, p) in positions.iter().enumerate() {
        if !p.is_finite() {
            let axis = (0..3).find(|&a| !p[a].is_finite()).unwrap_or(0);
            return Err(MeshError::NonFiniteCoordinate { vertex, axis, value: p[axis] });
        }
    }
    Ok(())
}

/// One-shot construction state for [`HalfedgeMesh::from_soup`].
///
/// The work is a few linear passes over flat arrays, arranged so that the random
/// accesses (one vertex's outgoing sides) touch one short contiguous run each, and with
/// as few temporary arrays as possible (allocating and first touching memory is a large
/// part of the cost on big meshes):
/// 1. check every face and count the out-degree of every vertex;
/// 2. group the sides (directed face edges) by origin vertex (CSR), each group sorted
///    by (target, corner);
/// 3. pair each side with its opposite vertex by vertex (each edge from its smaller end,
///    the other end's short group searched), then number the edges in order of first
///    appearance in one pass over the corners; a vertex with two sides to one target
///    (an edge used more than twice, or twice in one direction) sends the soup to a
///    pairing in corner order, which names the first such edge;
/// 4. link next/prev/face face by face, then the boundary loops;
/// 5. check that each vertex's faces form one fan.
struct Builder<'a> {
    soup: &'a PolygonSoup,
    /// Sides grouped by origin vertex: `out_sides[out_offsets[v]..out_offsets[v + 1]]`,
    /// each entry `(target << 32) | corner`, so sorting orders by target then corner.
    out_offsets: Vec<u32>,
    out_sides: Vec<u64>,
}

#[inline]
fn side_target(side: u64) -> u32 {
    (side >> 32) as u32
}

#[inline]
fn side_corner(side: u64) -> u32 {
    side as u32
}

/// Faces up to this size are checked for repeated vertices by comparing corners pairwise;
/// larger ones with a per-vertex scratch array.
const SMALL_FACE: usize = 12;

/// Calls `visit(corner, from, to)` for every side of every face, in corner order.
#[inline]
fn for_each_side(soup: &PolygonSoup, mut visit: impl FnMut(usize, u32, u32)) {
    for window in soup.offsets.windows(2) {
        let (begin, end) = (window[0] as usize, window[1] as usize);
        let face = &soup.indices[begin..end];
        for k in 0..face.len() - 1 {
            visit(begin + k, face[k], face[k + 1]);
        }
        visit(end - 1, face[face.len() - 1], face[0]);
    }
}

/// Refuses soups whose elements `u32` handles cannot address: what
/// [`HalfedgeMesh::from_soup`] checks first, for callers that know the counts of a mesh
/// before they build it (say, a subdivision level) and want to fail before any work.
///
/// ```
/// use mesh_topo::{MAX_ELEMENTS, MeshError, check_capacity};
/// assert_eq!(check_capacity(MAX_ELEMENTS, MAX_ELEMENTS / 2), Ok(()));
/// assert!(matches!(check_capacity(3, MAX_ELEMENTS), Err(MeshError::TooLarge { what: "face corners", .. })));
/// ```
///
/// # Errors
/// [`MeshError::TooLarge`] for more than [`MAX_ELEMENTS`] vertices or more than half as
/// many face corners (every corner can create two half-edges).
pub fn check_capacity(vertices: usize, corners: usize) -> Result<(), MeshError> {
    if vertices > MAX_ELEMENTS {
        return Err(MeshError::TooLarge { what: "vertices", count: vertices, max: MAX_ELEMENTS });
    }
    // Every corner can create up to two half-edges.
    if corners > MAX_ELEMENTS / 2 {
        return Err(MeshError::TooLarge { what: "face corners", count: corners, max: MAX_ELEMENTS / 2 });
    }
    Ok(())
}

impl<'a> Builder<'a> {
    fn new(soup: &'a PolygonSoup) -> Result<Self, MeshError> {
        let nv = soup.positions.len();
        let corners = soup.indices.len();
        check_capacity(nv, corners)?;
        check_finite(&soup.positions)?;
        let faces = soup.face_count();
        let valid_offsets = soup.offsets.first().is_none_or(|&o| o == 0)
            && soup.offsets.last().is_none_or(|&o| o as usize == corners)
            && soup.offsets.windows(2).all(|w| w[0] <= w[1]);
        if !valid_offsets || (soup.offsets.is_empty() && corners != 0) {
            // A malformed offsets array can only come from building a soup by hand; it
            // is reported on the first face whose range is wrong.
            let face = soup.offsets.windows(2).position(|w| w[0] > w[1]).unwrap_or(0);
            return Err(MeshError::FaceTooSmall { face, len: 0 });
        }

        // 1. Per-face checks and the out-degree of every vertex (in `out_offsets[v + 1]`).
        let mut out_offsets = vec![0u32; nv + 1];
        let mut last_face_of_vertex: Vec<u32> = Vec::new();
        for f in 0..faces {
            let face = &soup.indices[soup.offsets[f] as usize..soup.offsets[f + 1] as usize];
            if face.len() < 3 {
                return Err(MeshError::FaceTooSmall { face: f, len: face.len() });
            }
            for (corner, &v) in face.iter().enumerate() {
                if v as usize >= nv {
                    return Err(MeshError::IndexOutOfRange { face: f, corner, index: v as u64, vertex_count: nv });
                }
                out_offsets[v as usize + 1] += 1;
            }
            if face.len() <= SMALL_FACE {
                for (k, &v) in face.iter().enumerate().skip(1) {
                    if face[..k].contains(&v) {
                        return Err(MeshError::RepeatedVertex { face: f, vertex: v });
                    }
                }
            } else {
                if last_face_of_vertex.is_empty() {
                    last_face_of_vertex = vec![u32::MAX; nv];
                }
                for &v in face {
                    if last_face_of_vertex[v as usize] == f as u32 {
                        return Err(MeshError::RepeatedVertex { face: f, vertex: v });
                    }
                    last_face_of_vertex[v as usize] = f as u32;
                }
            }
        }
        drop(last_face_of_vertex);

        // 2. Group the sides by origin: prefix sums give each group's start, which then
        // serves as its fill cursor and ends up at the next group's start.
        for i in 0..nv {
            out_offsets[i + 1] += out_offsets[i];
        }
        let mut out_sides = vec![0u64; corners];
        for_each_side(soup, |c, from, to| {
            let slot = &mut out_offsets[from as usize];
            out_sides[*slot as usize] = (u64::from(to) << 32) | c as u64;
            *slot += 1;
        });
        out_offsets.copy_within(0..nv, 1);
        out_offsets[0] = 0;
        for v in 0..nv {
            out_sides[out_offsets[v] as usize..out_offsets[v + 1] as usize].sort_unstable();
        }
        Ok(Self { soup, out_offsets, out_sides })
    }

    /// The sides from `from` to `to`, in corner order (a run of `from`'s sorted group).
    #[inline]
    fn sides_between(&self, from: u32, to: u32) -> &[u64] {
        let group =
            &self.out_sides[self.out_offsets[from as usize] as usize..self.out_offsets[from as usize + 1] as usize];
        // Groups are short (the valence): a linear scan beats a binary search.
        let start = group.iter().position(|&s| side_target(s) >= to).unwrap_or(group.len());
        let length = group[start..].iter().take_while(|&&s| side_target(s) == to).count();
        &group[start..start + length]
    }

    /// The face a corner belongs to (used on the error path only).
    fn face_of_corner(&self, corner: u32) -> usize {
        self.soup.offsets.partition_point(|&o| o <= corner) - 1
    }

    /// Step 3 for one side: checks its edge and numbers it if it is the first side seen.
    #[inline]
    fn pair(
        &self,
        c: usize,
        from: u32,
        to: u32,
        corner_halfedge: &mut [u32],
        halfedge_to: &mut Vec<u32>,
    ) -> Result<(), MeshError> {
        if corner_halfedge[c] != INVALID {
            return Ok(());
        }
        let forward = self.sides_between(from, to);
        let backward = self.sides_between(to, from);
        if forward.len() + backward.len() > 2 {
            let mut faces = forward.iter().chain(backward).map(|&s| self.face_of_corner(side_corner(s)));
            let mut three = [0usize; 3];
            for slot in &mut three {
                *slot = faces.next().unwrap_or(0);
            }
            three.sort_unstable();
            return Err(MeshError::NonManifoldEdge { from: from.min(to), to: from.max(to), faces: three });
        }
        if forward.len() == 2 {
            return Err(MeshError::InconsistentOrientation {
                from,
                to,
                first_face: self.face_of_corner(side_corner(forward[0])),
                second_face: self.face_of_corner(side_corner(forward[1])),
            });
        }
        let h = halfedge_to.len() as u32;
        corner_halfedge[c] = h;
        if let Some(&twin) = backward.first() {
            corner_halfedge[side_corner(twin) as usize] = h + 1;
        }
        halfedge_to.push(to);
        halfedge_to.push(from);
        Ok(())
    }

    /// Step 3, first part: the opposite side of every side (by corner), [`INVALID`] on
    /// the boundary, read vertex by vertex: each edge once, from its smaller end, whose
    /// group is read in order while the other end's group is searched. `None` if a vertex
    /// has two sides to the same target (an edge used twice in one direction, alone or
    /// with more sides: non-manifold or inconsistently oriented); then
    /// [`Self::pair_in_corner_order`] finds the first such edge in corner order, as the
    /// error must name it. (Every side is in its origin's group, so every edge used twice
    /// in one direction shows there.)
    fn twin_sides(&self) -> Option<Vec<u32>> {
        let mut twins = vec![INVALID; self.soup.indices.len()];
        for (v, range) in self.out_offsets.windows(2).enumerate() {
            let group = &self.out_sides[range[0] as usize..range[1] as usize];
            for (k, &side) in group.iter().enumerate() {
                let to = side_target(side);
                if group.get(k + 1).is_some_and(|&after| side_target(after) == to) {
                    return None;
                }
                // Faces repeat no vertex, so `to != v`; the edge is read from its smaller end.
                if (to as usize) < v {
                    continue;
                }
                if let &[back] = self.sides_between(to, v as u32) {
                    let (c, t) = (side_corner(side), side_corner(back));
                    twins[c as usize] = t;
                    twins[t as usize] = c;
                }
            }
        }
        Some(twins)
    }

    /// Step 3, second part: numbers the edges in order of first appearance, corner by
    /// corner, from the opposite side of each side ([`Self::twin_sides`]). Returns the
    /// half-edge of each corner and the target of each half-edge.
    ///
    /// The half-edges are written over the opposite sides: a side not yet numbered when
    /// the scan reaches it has its opposite (if any) further on (else that one, met
    /// first, would have numbered both), so each opposite is read before it is written;
    /// the sides numbered as opposites are marked, one bit each.
    fn number_edges(&self, mut twins: Vec<u32>) -> (Vec<u32>, Vec<u32>) {
        let corners = twins.len();
        let mut numbered = vec![0u64; corners.div_ceil(64)];
        let mut halfedge_to: Vec<u32> = Vec::with_capacity(corners + corners / 8);
        for_each_side(self.soup, |c, from, to| {
            if numbered[c / 64] & (1 << (c % 64)) == 0 {
                let h = halfedge_to.len() as u32;
                let twin = std::mem::replace(&mut twins[c], h) as usize;
                if twin != INVALID as usize {
                    debug_assert!(twin > c, "internal: an opposite side met first numbers both");
                    twins[twin] = h + 1;
                    numbered[twin / 64] |= 1 << (twin % 64);
                }
                halfedge_to.push(to);
                halfedge_to.push(from);
            }
        });
        (twins, halfedge_to)
    }

    /// Step 3 with every edge checked in corner order (see [`Self::pair`]): the first
    /// edge used more than twice or twice in one direction is the error.
    fn pair_in_corner_order(&self) -> Result<(Vec<u32>, Vec<u32>), MeshError> {
        let corners = self.soup.indices.len();
        let mut corner_halfedge = vec![INVALID; corners];
        let mut halfedge_to: Vec<u32> = Vec::with_capacity(corners + corners / 8);
        let mut result = Ok(());
        for_each_side(self.soup, |c, from, to| {
            if result.is_ok() {
                result = self.pair(c, from, to, &mut corner_halfedge, &mut halfedge_to);
            }
        });
        result.map(|()| (corner_halfedge, halfedge_to))
    }

    fn build(mut self) -> Result<HalfedgeMesh, MeshError> {
        let soup = self.soup;
        let nv = soup.positions.len();

        // 3. Pair sides into edges, in order of first appearance.
        let (corner_halfedge, halfedge_to) = match self.twin_sides() {
            Some(twins) => self.number_edges(twins),
            None => self.pair_in_corner_order()?,
        };
        let nh = halfedge_to.len();
        // The sides are read no more: their memory can serve the arrays below.
        self.out_sides = Vec::new();

        // 4. Faces: next, prev and face of every face half-edge, face by face.
        let mut halfedge_next = vec![INVALID; nh];
        let mut halfedge_prev = vec![INVALID; nh];
        let mut halfedge_face = vec![INVALID; nh];
        let mut face_halfedge = Vec::with_capacity(soup.face_count());
        for (f, window) in soup.offsets.windows(2).enumerate() {
            let ring = &corner_halfedge[window[0] as usize..window[1] as usize];
            let mut previous = ring[ring.len() - 1];
            for &h in ring {
                halfedge_face[h as usize] = f as u32;
                halfedge_prev[h as usize] = previous;
                halfedge_next[previous as usize] = h;
                previous = h;
            }
            face_halfedge.push(ring[0]);
        }

        // Vertex half-edges: the first corner in face order, replaced below by the
        // outgoing boundary half-edge on the boundary.
        let mut vertex_halfedge = vec![INVALID; nv];
        for (&v, &h) in soup.indices.iter().zip(&corner_halfedge) {
            let slot = &mut vertex_halfedge[v as usize];
            if *slot == INVALID {
                *slot = h;
            }
        }
        drop(corner_halfedge);

        // Boundary half-edges: at most one may leave each vertex, else the vertex joins
        // two fans through a hole.
        for h in (1..nh).step_by(2) {
            if halfedge_face[h] != INVALID {
                continue;
            }
            let origin = halfedge_to[h - 1] as usize;
            let current = vertex_halfedge[origin] as usize;
            if halfedge_face[current] == INVALID {
                return Err(MeshError::NonManifoldVertex {
                    vertex: origin as u32,
                    fans: 2,
                    example_faces: [halfedge_face[current ^ 1] as usize, halfedge_face[h ^ 1] as usize],
                });
            }
            vertex_halfedge[origin] = h as u32;
        }
        for h in (1..nh).step_by(2) {
            if halfedge_face[h] == INVALID {
                // Every vertex with an incoming boundary half-edge has an outgoing one.
                let next = vertex_halfedge[halfedge_to[h] as usize];
                halfedge_next[h] = next;
                halfedge_prev[next as usize] = h as u32;
            }
        }

        let mesh = HalfedgeMesh {
            positions: soup.positions.clone(),
            vertex_halfedge,
            halfedge_to,
            halfedge_next,
            halfedge_prev,
            halfedge_face,
            face_halfedge,
        };
        // 5. One fan per vertex.
        mesh.check_single_fans(&self.out_offsets)?;
        Ok(mesh)
    }
}

impl HalfedgeMesh {
    /// Every vertex's circulation must reach all its outgoing half-edges; otherwise its
    /// faces form several fans (e.g. two cones touching at the apex).
    fn check_single_fans(&self, corner_out_offsets: &[u32]) -> Result<(), MeshError> {
        for v in self.vertices() {
            let corner_out = (corner_out_offsets[v.index() + 1] - corner_out_offsets[v.index()]) as usize;
            if corner_out == 0 {
                continue;
            }
            let reached_faces = self.vertex_faces(v).take(corner_out + 1).count();
            if reached_faces != corner_out {
                // Count the fans: the circulation cycles among v's outgoing half-edges.
                let outgoing: Vec<HalfedgeId> = self.halfedges().filter(|&h| self.origin(h) == v).collect();
                let mut cycle_of: Vec<Option<usize>> = vec![None; outgoing.len()];
                let mut fans = 0;
                let mut first_face_of_fan = Vec::new();
                for i in 0..outgoing.len() {
                    if cycle_of[i].is_some() {
                        continue;
                    }
                    let mut h = outgoing[i];
                    let mut face = None;
                    loop {
                        let k = outgoing.iter().position(|&o| o == h).expect("internal: outgoing half-edge");
                        if cycle_of[k].is_some() {
                            break;
                        }
                        cycle_of[k] = Some(fans);
                        face = face.or(self.halfedge_face(h));
                        h = self.prev(h).twin();
                    }
                    first_face_of_fan.push(face.map_or(0, FaceId::index));
                    fans += 1;
                }
                return Err(MeshError::NonManifoldVertex {
                    vertex: v.raw(),
                    fans,
                    example_faces: [first_face_of_fan[0], first_face_of_fan[1]],
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raw_arrays_agree_with_the_handles() {
        let mesh = HalfedgeMesh::from_soup(&crate::shapes::grid(3, 2, crate::shapes::CellKind::Triangles).unwrap())
            .expect("valid grid");
        assert_eq!(mesh.raw_face_halfedges().len(), mesh.face_count());
        for f in mesh.faces() {
            let h = mesh.face_halfedge(f);
            assert_eq!(mesh.raw_face_halfedges()[f.index()], h.raw());
            assert_eq!(mesh.raw_halfedge_next()[h.index()], mesh.next(h).raw());
            assert_eq!(mesh.raw_halfedge_targets()[h.twin().index()], mesh.origin(h).raw());
        }
    }

    proptest::proptest! {
        /// The pairing read vertex by vertex numbers the edges as the pairing in corner
        /// order does, and gives up exactly on the soups where that one finds an edge used
        /// more than twice or twice in one direction (the error it then names). Damage:
        /// none, one face turned over, one face repeated, one face added turned over.
        #[test]
        fn both_pairings_agree(
            soup in crate::testing::arb_mesh(),
            damage in 0usize..4,
            at: proptest::sample::Index,
        ) {
            let mut faces: Vec<Vec<u32>> = soup.faces().map(<[u32]>::to_vec).collect();
            let f = at.index(faces.len());
            let turned: Vec<u32> = faces[f].iter().rev().copied().collect();
            match damage {
                1 => faces[f] = turned,
                2 => faces.push(faces[f].clone()),
                3 => faces.push(turned),
                _ => {}
            }
            let damaged = PolygonSoup::from_faces(soup.positions.clone(), faces);
            let builder = Builder::new(&damaged).expect("faces of 3 or more distinct vertices");
            let by_vertex = builder.twin_sides().map(|twins| builder.number_edges(twins));
            match (by_vertex, builder.pair_in_corner_order()) {
                (Some(by_vertex), Ok(in_corner_order)) => proptest::prop_assert_eq!(by_vertex, in_corner_order),
                (None, Err(error)) => {
                    let edge_error =
                        matches!(error, MeshError::NonManifoldEdge { .. } | MeshError::InconsistentOrientation { .. });
                    proptest::prop_assert!(edge_error, "{error}");
                }
                (by_vertex, in_corner_order) => proptest::prop_assert!(
                    false,
                    "by vertex: {:?}, in corner order: {:?}",
                    by_vertex.is_some(),
                    in_corner_order.err()
                ),
            }
            // No damage: a valid mesh, paired by vertex.
            proptest::prop_assert!(damage != 0 || builder.twin_sides().is_some());
        }
    }

    /// The limits themselves: a soup that big cannot be allocated in a test, so the guard
    /// the builder calls first is checked on counts alone (`shapes` tests reach the same
    /// error through a real call).
    #[test]
    fn counts_beyond_u32_handles_are_too_large() {
        assert_eq!(check_capacity(MAX_ELEMENTS, MAX_ELEMENTS / 2), Ok(()));
        assert_eq!(
            check_capacity(MAX_ELEMENTS + 1, 0),
            Err(MeshError::TooLarge { what: "vertices", count: MAX_ELEMENTS + 1, max: MAX_ELEMENTS })
        );
        let err = check_capacity(3, MAX_ELEMENTS / 2 + 1).unwrap_err();
        assert_eq!(
            err,
            MeshError::TooLarge { what: "face corners", count: MAX_ELEMENTS / 2 + 1, max: MAX_ELEMENTS / 2 }
        );
        assert_eq!(
            err.to_string(),
            format!("too many face corners: {} (at most {} are supported)", MAX_ELEMENTS / 2 + 1, MAX_ELEMENTS / 2)
        );
    }
}
