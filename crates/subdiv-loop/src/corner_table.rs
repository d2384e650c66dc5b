//! Flat corner-table connectivity of triangle meshes: the working representation of
//! detection, reversal and reconstruction.
//!
//! Corner `c = 3f + k` is corner `k` of face `f`; it names the half-edge from its vertex
//! to the vertex of the next corner of the same face. `twin[c]` is the corner of the
//! opposite half-edge, or [`NONE`] on the boundary. Edges are numbered exactly as
//! `mesh_topo` numbers them (first appearance when the faces are scanned corner by
//! corner), so an edge index here is an `EdgeId` index of the same mesh built by
//! `HalfedgeMesh::from_soup`.
//!
//! The Loop refinement of a corner table is pure index arithmetic
//! ([`CornerTable::refine`]); nothing here hashes or sorts.

use glam::DVec3;
use mesh_topo::{HalfedgeMesh, PolygonSoup};

use crate::LoopError;

/// "No element": a boundary twin, an isolated vertex's corner.
pub(crate) const NONE: u32 = u32::MAX;

/// The corner after `c` in its face.
#[inline]
pub(crate) fn next(c: u32) -> u32 {
    if c % 3 == 2 { c - 2 } else { c + 1 }
}

/// The corner before `c` in its face.
#[inline]
pub(crate) fn prev(c: u32) -> u32 {
    if c.is_multiple_of(3) { c + 2 } else { c - 1 }
}

/// Triangle-mesh connectivity as flat `u32` arrays (see the module docs).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct CornerTable {
    vertex_count: usize,
    /// Vertex of each corner.
    corner_vertex: Vec<u32>,
    /// Corner of the twin half-edge, or [`NONE`] on the boundary.
    twin: Vec<u32>,
    /// Edge of each corner's half-edge.
    corner_edge: Vec<u32>,
    /// First corner of each edge (its half-edge `2e` in `mesh_topo` terms).
    edge_corner: Vec<u32>,
    /// Start of each vertex's counter-clockwise circulation: for a boundary vertex the
    /// corner whose half-edge lies on the boundary; [`NONE`] for an isolated vertex.
    vertex_corner: Vec<u32>,
}

/// What a circulation around a vertex found: the data every vertex rule needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum VertexStar {
    /// No incident edge.
    Isolated,
    /// A closed fan.
    Interior {
        /// Number of incident edges.
        valence: usize,
    },
    /// An open fan.
    Boundary {
        /// Number of incident edges.
        valence: usize,
        /// The two boundary edges (after and before the fan, counter-clockwise).
        boundary_edges: [u32; 2],
    },
}

impl CornerTable {
    /// Builds the table from corner vertices and twins, numbering edges and choosing the
    /// circulation starts. The caller guarantees a manifold, consistently oriented mesh.
    pub(crate) fn from_parts(vertex_count: usize, corner_vertex: Vec<u32>, twin: Vec<u32>) -> Self {
        debug_assert_eq!(corner_vertex.len(), twin.len());
        debug_assert!(corner_vertex.len().is_multiple_of(3));
        let corners = corner_vertex.len();
        let mut corner_edge = vec![NONE; corners];
        let mut edge_corner = Vec::with_capacity(corners / 2 + 1);
        let mut vertex_corner = vec![NONE; vertex_count];
        for c in 0..corners as u32 {
            if corner_edge[c as usize] == NONE {
                let e = edge_corner.len() as u32;
                edge_corner.push(c);
                corner_edge[c as usize] = e;
                let t = twin[c as usize];
                if t != NONE {
                    corner_edge[t as usize] = e;
                }
            }
            let v = corner_vertex[c as usize] as usize;
            if vertex_corner[v] == NONE || twin[c as usize] == NONE {
                vertex_corner[v] = c;
            }
        }
        Self { vertex_count, corner_vertex, twin, corner_edge, edge_corner, vertex_corner }
    }

    /// The table of a validated half-edge mesh.
    ///
    /// # Errors
    /// [`LoopError::NotTriangle`] naming the first face that is not a triangle.
    pub(crate) fn from_mesh(mesh: &HalfedgeMesh) -> Result<Self, LoopError> {
        let next_halfedge = mesh.raw_halfedge_next();
        let targets = mesh.raw_halfedge_targets();
        let faces = mesh.face_count();
        let mut corner_of_halfedge = vec![NONE; mesh.halfedge_count()];
        let mut corner_vertex = vec![0u32; 3 * faces];
        let mut halfedge_of_corner = vec![0u32; 3 * faces];
        for f in mesh.faces() {
            let h0 = mesh.face_halfedge(f).raw();
            let h1 = next_halfedge[h0 as usize];
            let h2 = next_halfedge[h1 as usize];
            if next_halfedge[h2 as usize] != h0 {
                return Err(LoopError::NotTriangle { face: f.index(), corners: mesh.face_degree(f) });
            }
            let c = 3 * f.raw();
            // Corner k holds the origin of half-edge k, i.e. the target of half-edge k - 1.
            for (k, (h, before)) in [(h0, h2), (h1, h0), (h2, h1)].into_iter().enumerate() {
                corner_of_halfedge[h as usize] = c + k as u32;
                corner_vertex[(c as usize) + k] = targets[before as usize];
                halfedge_of_corner[(c as usize) + k] = h;
            }
        }
        let twin = halfedge_of_corner.iter().map(|&h| corner_of_halfedge[(h ^ 1) as usize]).collect();
        let table = Self::from_parts(mesh.vertex_count(), corner_vertex, twin);
        debug_assert_eq!(table.edge_count(), mesh.edge_count(), "internal: edge numbering differs from mesh-topo");
        Ok(table)
    }

    /// The table of a polygon soup, validated by `mesh_topo`.
    ///
    /// # Errors
    /// Any [`mesh_topo::MeshError`] of the soup, or [`LoopError::NotTriangle`].
    pub(crate) fn from_soup(soup: &PolygonSoup) -> Result<Self, LoopError> {
        Self::from_mesh(&HalfedgeMesh::from_soup(soup)?)
    }

    /// Number of vertices (isolated ones included).
    #[inline]
    pub(crate) fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// Number of faces.
    #[inline]
    pub(crate) fn face_count(&self) -> usize {
        self.corner_vertex.len() / 3
    }

    /// Number of corners (three per face).
    #[inline]
    pub(crate) fn corner_count(&self) -> usize {
        self.corner_vertex.len()
    }

    /// Number of edges.
    #[inline]
    pub(crate) fn edge_count(&self) -> usize {
        self.edge_corner.len()
    }

    /// Vertex of corner `c`.
    #[inline]
    pub(crate) fn vertex(&self, c: u32) -> u32 {
        self.corner_vertex[c as usize]
    }

    /// Twin corner of `c`, or [`NONE`].
    #[inline]
    pub(crate) fn twin(&self, c: u32) -> u32 {
        self.twin[c as usize]
    }

    /// Edge of corner `c`'s half-edge.
    #[inline]
    pub(crate) fn corner_edge(&self, c: u32) -> u32 {
        self.corner_edge[c as usize]
    }

    /// First corner of edge `e`.
    #[inline]
    pub(crate) fn edge_corner(&self, e: u32) -> u32 {
        self.edge_corner[e as usize]
    }

    /// True if `v` has no incident face.
    #[inline]
    pub(crate) fn is_isolated(&self, v: u32) -> bool {
        self.vertex_corner[v as usize] == NONE
    }

    /// True if `v` lies on the boundary.
    #[inline]
    pub(crate) fn is_boundary_vertex(&self, v: u32) -> bool {
        let c = self.vertex_corner[v as usize];
        c != NONE && self.twin[c as usize] == NONE
    }

    /// The corners of `v` (its outgoing half-edges), counter-clockwise from the
    /// circulation start.
    #[inline]
    pub(crate) fn outgoing(&self, v: u32) -> Outgoing<'_> {
        let start = self.vertex_corner[v as usize];
        Outgoing { table: self, start, current: start }
    }

    /// Calls `visit(edge, neighbour)` for every edge at `v`, counter-clockwise (for a
    /// boundary vertex from the boundary edge after the fan's first face to the one
    /// before its last), and reports the star.
    #[inline]
    pub(crate) fn visit_star(&self, v: u32, mut visit: impl FnMut(u32, u32)) -> VertexStar {
        let start = self.vertex_corner[v as usize];
        if start == NONE {
            return VertexStar::Isolated;
        }
        let mut c = start;
        let mut valence = 0;
        loop {
            visit(self.corner_edge[c as usize], self.corner_vertex[next(c) as usize]);
            valence += 1;
            let p = prev(c);
            let t = self.twin[p as usize];
            if t == NONE {
                // Open fan: the edge before the last face closes the star.
                visit(self.corner_edge[p as usize], self.corner_vertex[p as usize]);
                return VertexStar::Boundary {
                    valence: valence + 1,
                    boundary_edges: [self.corner_edge[start as usize], self.corner_edge[p as usize]],
                };
            }
            if t == start {
                return VertexStar::Interior { valence };
            }
            c = t;
        }
    }

    /// Loop's 1-to-4 refinement in the canonical order: vertex `v` stays `v`, the edge
    /// point of edge `e` is vertex `V + e`; coarse face `f = (a, b, c)` becomes faces
    /// `4f..4f+4` = `(a, ab, ca)`, `(b, bc, ab)`, `(c, ca, bc)`, `(ab, bc, ca)`.
    pub(crate) fn refine(&self) -> Self {
        let nv = self.vertex_count as u32;
        let faces = self.face_count();
        let mut corner_vertex = vec![0u32; 12 * faces];
        let mut twin = vec![NONE; 12 * faces];
        for f in 0..faces as u32 {
            let base = 3 * f;
            let x = [self.vertex(base), self.vertex(base + 1), self.vertex(base + 2)];
            let m = [nv + self.corner_edge(base), nv + self.corner_edge(base + 1), nv + self.corner_edge(base + 2)];
            let fine = 12 * f;
            for k in 0..3u32 {
                let child = fine + 3 * k;
                let before = (k + 2) % 3;
                corner_vertex[child as usize] = x[k as usize];
                corner_vertex[child as usize + 1] = m[k as usize];
                corner_vertex[child as usize + 2] = m[before as usize];
                // m_k -> m_{k-1} is the twin of the inner face's half-edge m_{k-1} -> m_k.
                twin[child as usize + 1] = fine + 9 + before;
                twin[(fine + 9 + before) as usize] = child + 1;
                corner_vertex[(fine + 9 + k) as usize] = m[k as usize];
                // The two halves of coarse half-edge k: x_k -> m_k (child k, corner 0)
                // and m_k -> x_{k+1} (child k+1, corner 2).
                let t = self.twin(base + k);
                if t != NONE {
                    let (g, l) = (t / 3, t % 3);
                    let after_l = (l + 1) % 3;
                    // Twin of x_k -> m_k is m -> x_k: child l+1 of g, corner 2.
                    twin[child as usize] = 12 * g + 3 * after_l + 2;
                    // Twin of m_k -> x_{k+1}: x_{k+1} -> m, child l of g, corner 0.
                    twin[(fine + 3 * ((k + 1) % 3) + 2) as usize] = 12 * g + 3 * l;
                }
            }
        }
        Self::from_parts(self.vertex_count + self.edge_count(), corner_vertex, twin)
    }

    /// The same mesh with vertices and faces renumbered: canonical vertex `i` becomes
    /// `vertex_of_canonical[i]`; canonical face `K` becomes face `code / 3` of the
    /// result, its corner list rotated so that corner `i` of the new face is corner
    /// `(i + code % 3) % 3` of `K`, where `code = face_of_canonical[K]`. Both maps must
    /// be validated permutations.
    pub(crate) fn permuted(&self, vertex_of_canonical: &[u32], face_of_canonical: &[u32]) -> Self {
        let corners = self.corner_count();
        // New corner of every old corner.
        let mut corner_map = vec![0u32; corners];
        for (k, &code) in face_of_canonical.iter().enumerate() {
            let (face, rotation) = (code / 3, code % 3);
            for j in 0..3u32 {
                corner_map[3 * k + j as usize] = 3 * face + (j + 3 - rotation) % 3;
            }
        }
        let mut corner_vertex = vec![0u32; corners];
        let mut twin = vec![NONE; corners];
        for c in 0..corners {
            let n = corner_map[c] as usize;
            corner_vertex[n] = vertex_of_canonical[self.corner_vertex[c] as usize];
            let t = self.twin[c];
            twin[n] = if t == NONE { NONE } else { corner_map[t as usize] };
        }
        Self::from_parts(self.vertex_count, corner_vertex, twin)
    }

    /// The faces as a polygon soup with the given positions.
    pub(crate) fn to_soup(&self, positions: Vec<DVec3>) -> PolygonSoup {
        debug_assert_eq!(positions.len(), self.vertex_count);
        let faces = self.face_count();
        PolygonSoup {
            positions,
            offsets: (0..=faces as u32).map(|f| 3 * f).collect(),
            indices: self.corner_vertex.clone(),
        }
    }
}

/// Counter-clockwise iterator over the corners of a vertex (see
/// [`CornerTable::outgoing`]).
pub(crate) struct Outgoing<'a> {
    table: &'a CornerTable,
    start: u32,
    current: u32,
}

impl Iterator for Outgoing<'_> {
    type Item = u32;
    #[inline]
    fn next(&mut self) -> Option<u32> {
        if self.current == NONE {
            return None;
        }
        let c = self.current;
        let following = self.table.twin[prev(c) as usize];
        self.current = if following == self.start { NONE } else { following };
        Some(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_topo::shapes::{self, CellKind};

    fn check_against_mesh_topo(table: &CornerTable) {
        let soup = table.to_soup(vec![DVec3::ZERO; table.vertex_count()]);
        let mesh = HalfedgeMesh::from_soup(&soup).expect("refined mesh is valid");
        let rebuilt = CornerTable::from_mesh(&mesh).unwrap();
        assert_eq!(&rebuilt, table);
        for e in mesh.edges() {
            let [a, b] = mesh.edge_vertices(e);
            let c = table.edge_corner(e.raw());
            assert_eq!([table.vertex(c), table.vertex(next(c))], [a.raw(), b.raw()]);
        }
        for v in mesh.vertices() {
            let mut neighbours = Vec::new();
            let star = table.visit_star(v.raw(), |_, n| neighbours.push(n));
            let expected: Vec<u32> = mesh.vertex_neighbors(v).map(|n| n.raw()).collect();
            let mut sorted = neighbours.clone();
            sorted.sort_unstable();
            let mut expected_sorted = expected.clone();
            expected_sorted.sort_unstable();
            assert_eq!(sorted, expected_sorted, "vertex {v}");
            match star {
                VertexStar::Isolated => assert!(mesh.is_isolated(v)),
                VertexStar::Interior { valence } => {
                    assert!(!mesh.is_boundary_vertex(v));
                    assert_eq!(valence, mesh.valence(v));
                }
                VertexStar::Boundary { valence, boundary_edges } => {
                    assert!(mesh.is_boundary_vertex(v));
                    assert_eq!(valence, mesh.valence(v));
                    for e in boundary_edges {
                        assert!(mesh.is_boundary_edge(mesh.edge(e as usize).unwrap()));
                    }
                }
            }
        }
    }

    #[test]
    fn table_matches_mesh_topo_on_shapes_and_their_refinements() {
        for soup in [
            shapes::tetrahedron(),
            shapes::octahedron(),
            shapes::icosahedron(),
            shapes::grid(3, 2, CellKind::Triangles),
            shapes::torus(4, 3, CellKind::Triangles),
        ] {
            let table = CornerTable::from_soup(&soup).unwrap();
            check_against_mesh_topo(&table);
            let fine = table.refine();
            check_against_mesh_topo(&fine);
            assert_eq!(fine.vertex_count(), table.vertex_count() + table.edge_count());
            assert_eq!(fine.face_count(), 4 * table.face_count());
            assert_eq!(fine.edge_count(), 2 * table.edge_count() + 3 * table.face_count());
            check_against_mesh_topo(&fine.refine());
        }
    }

    #[test]
    fn quads_are_rejected_with_the_face() {
        let err = CornerTable::from_soup(&shapes::cube()).unwrap_err();
        assert_eq!(err, LoopError::NotTriangle { face: 0, corners: 4 });
    }
}
