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
//! The Loop refinement of a corner table ([`CornerTable::refine`]) is the forward
//! kernel's index arithmetic on the equivalent compact topology; nothing here hashes or
//! sorts.

use std::sync::OnceLock;

use glam::DVec3;
use mesh_topo::{HalfedgeMesh, PolygonSoup};
use rayon::prelude::*;

use crate::LoopError;
use crate::forward::buffer::{Output, Slots};
use crate::forward::kernel::{self, map_indices, splits};
use crate::forward::topology::{BASE_BITS, INVALID as TOPOLOGY_INVALID, MeshTriangles, Topology};

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

/// Faces per parallel work item of the linear searches over faces.
const FACE_CHUNK: usize = 4096;

/// The first face that shares two of its edges with one other face (then it shares all
/// three: a closed "pillow"), from the twins. Chunks of faces searched in parallel, each
/// by a plain loop (a search item by item through the pool costs far more than the test).
fn first_pillow_face(twin: &[u32]) -> Option<usize> {
    let pillow = |t: &[u32]| {
        let other = |k: usize| if t[k] == NONE { NONE - k as u32 } else { t[k] / 3 };
        other(0) == other(1) || other(1) == other(2) || other(2) == other(0)
    };
    let search = |(i, chunk): (usize, &[u32])| chunk.chunks_exact(3).position(pillow).map(|f| i * FACE_CHUNK + f);
    if !splits(twin.len(), 3 * FACE_CHUNK) {
        search((0, twin))
    } else {
        twin.par_chunks(3 * FACE_CHUNK).enumerate().map(search).find_first(Option::is_some).flatten()
    }
}

/// Triangle-mesh connectivity as flat `u32` arrays (see the module docs).
#[derive(Debug, Clone)]
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
    /// Made on first use (only circulations need it), from the other arrays.
    vertex_corner: OnceLock<Vec<u32>>,
}

/// The vertex and twin of one corner, side by side: a search that hops from face to
/// face at random reads both, and a face's three corners (24 bytes) then mostly lie in
/// one cache line instead of two.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Corner {
    /// Vertex of the corner.
    pub(crate) vertex: u32,
    /// Corner of the twin half-edge, or [`NONE`] on the boundary.
    pub(crate) twin: u32,
}

/// What [`CornerTable::mesh_corners`] makes.
pub(crate) struct MeshCorners {
    /// Vertex and twin of each corner.
    pub(crate) corners: Vec<Corner>,
    /// Corner of every half-edge of the mesh, [`NONE`] for a boundary half-edge.
    corner_of_halfedge: Vec<u32>,
}

impl MeshCorners {
    /// A corner at vertex `v` of `mesh` (the mesh these corners are of), [`NONE`] if it
    /// is isolated.
    #[inline]
    pub(crate) fn corner_at(&self, mesh: &HalfedgeMesh, v: u32) -> u32 {
        match mesh.vertex(v as usize).and_then(|v| mesh.vertex_halfedge(v)) {
            None => NONE,
            // A boundary half-edge has no corner; the twin of the one before it has.
            Some(h) if mesh.is_boundary_halfedge(h) => self.corner_of_halfedge[mesh.prev(h).twin().index()],
            Some(h) => self.corner_of_halfedge[h.index()],
        }
    }
}

/// Tables are equal when their connectivity is: the circulation starts follow from it.
impl PartialEq for CornerTable {
    fn eq(&self, other: &Self) -> bool {
        self.vertex_count == other.vertex_count
            && self.corner_vertex == other.corner_vertex
            && self.twin == other.twin
            && self.corner_edge == other.corner_edge
            && self.edge_corner == other.edge_corner
    }
}

impl Eq for CornerTable {}

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
        }
        Self::from_numbered_parts(vertex_count, corner_vertex, twin, corner_edge, edge_corner)
    }

    /// [`from_parts`](Self::from_parts) with the edges already numbered the same way
    /// (first appearance in corner order).
    pub(crate) fn from_numbered_parts(
        vertex_count: usize,
        corner_vertex: Vec<u32>,
        twin: Vec<u32>,
        corner_edge: Vec<u32>,
        edge_corner: Vec<u32>,
    ) -> Self {
        debug_assert_eq!(corner_edge.len(), corner_vertex.len());
        Self { vertex_count, corner_vertex, twin, corner_edge, edge_corner, vertex_corner: OnceLock::new() }
    }

    /// The circulation start of every vertex: its first corner, or its last corner
    /// whose half-edge lies on the boundary.
    pub(crate) fn vertex_corners(&self) -> &[u32] {
        self.vertex_corner.get_or_init(|| {
            let mut vertex_corner = vec![NONE; self.vertex_count];
            for (c, (&v, &t)) in self.corner_vertex.iter().zip(&self.twin).enumerate() {
                let start = &mut vertex_corner[v as usize];
                if *start == NONE || t == NONE {
                    *start = c as u32;
                }
            }
            vertex_corner
        })
    }

    /// The vertex and twin of every corner, side by side.
    pub(crate) fn corners(&self) -> Vec<Corner> {
        let pair = |(&vertex, &twin): (&u32, &u32)| Corner { vertex, twin };
        if !splits(self.corner_vertex.len(), 3 * FACE_CHUNK) {
            self.corner_vertex.iter().zip(&self.twin).map(pair).collect()
        } else {
            self.corner_vertex.par_iter().zip(&self.twin).with_min_len(3 * FACE_CHUNK).map(pair).collect()
        }
    }

    /// The corner vertices and twins of a validated half-edge mesh (what the
    /// renumbering of a fine mesh reads, without the edges and circulation starts of a
    /// whole table), and the corner of every face half-edge; `None` if a face is not a
    /// triangle.
    pub(crate) fn mesh_corners(mesh: &HalfedgeMesh) -> Option<MeshCorners> {
        let targets = mesh.raw_halfedge_targets();
        let faces = mesh.face_count();
        let mesh_triangles = MeshTriangles::new(mesh);
        let mut corner_of_halfedge = vec![NONE; mesh.halfedge_count()];
        let mut face_halfedges = Vec::with_capacity(faces);
        for f in 0..faces as u32 {
            let halfedges = mesh_triangles.halfedges(f as usize)?;
            for (k, h) in halfedges.into_iter().enumerate() {
                corner_of_halfedge[h as usize] = 3 * f + k as u32;
            }
            face_halfedges.push(halfedges);
        }
        // Every corner is written once (no zeroing first), by chunks of faces.
        let mut corners = Output::<Corner>::new(3 * faces);
        {
            let mut slots = corners.slots();
            let pieces: Vec<_> = (0..faces)
                .step_by(FACE_CHUNK)
                .map(|f0| {
                    let f1 = (f0 + FACE_CHUNK).min(faces);
                    (f0..f1, slots.take_front(3 * (f1 - f0)))
                })
                .collect();
            let fill = |(range, mut piece): (std::ops::Range<usize>, Slots<'_, Corner>)| {
                for h in &face_halfedges[range] {
                    for k in 0..3 {
                        let vertex = targets[h[(k + 2) % 3] as usize];
                        piece.push(Corner { vertex, twin: corner_of_halfedge[(h[k] ^ 1) as usize] });
                    }
                }
            };
            if !splits(faces, FACE_CHUNK) {
                pieces.into_iter().for_each(fill);
            } else {
                pieces.into_par_iter().for_each(fill);
            }
        }
        Some(MeshCorners { corners: corners.into_vec(), corner_of_halfedge })
    }

    /// The table of a validated half-edge mesh.
    ///
    /// # Errors
    /// [`LoopError::NotTriangle`] naming the first face that is not a triangle,
    /// [`LoopError::InteriorValenceTwo`] for two triangles glued along all their edges.
    pub(crate) fn from_mesh(mesh: &HalfedgeMesh) -> Result<Self, LoopError> {
        let targets = mesh.raw_halfedge_targets();
        let faces = mesh.face_count();
        let mesh_triangles = MeshTriangles::new(mesh);
        // The corner of every face half-edge: one pass over the faces, in face order, so
        // the writes follow the half-edge numbering (edges are numbered in face order).
        // The same pass finds the first face that is not a triangle (a search of its own,
        // item by item through the pool, cost as much as the whole table).
        let mut corner_of_halfedge = vec![NONE; mesh.halfedge_count()];
        for f in 0..faces as u32 {
            let Some(halfedges) = mesh_triangles.halfedges(f as usize) else {
                let face = mesh.face(f as usize).expect("internal: face in range");
                return Err(LoopError::NotTriangle { face: f as usize, corners: mesh.face_degree(face) });
            };
            for (k, h) in halfedges.into_iter().enumerate() {
                corner_of_halfedge[h as usize] = 3 * f + k as u32;
            }
        }
        let face_halfedges = |f: u32| {
            mesh_triangles.halfedges(f as usize).unwrap_or_else(|| unreachable!("internal: every face is a triangle"))
        };
        // Everything per face by gathers only, so faces are independent (parallel).
        let mut corner_vertex = vec![0u32; 3 * faces];
        let mut twin = vec![0u32; 3 * faces];
        let mut corner_edge = vec![0u32; 3 * faces];
        let fill = |f: usize, vertices: &mut [u32], twins: &mut [u32], edges: &mut [u32]| {
            let h = face_halfedges(f as u32);
            for k in 0..3 {
                // Corner k holds the origin of half-edge k: the target of half-edge k - 1.
                vertices[k] = targets[h[(k + 2) % 3] as usize];
                edges[k] = h[k] >> 1;
                // NONE for a boundary half-edge (it has no face).
                twins[k] = corner_of_halfedge[(h[k] ^ 1) as usize];
            }
        };
        if splits(faces, FACE_CHUNK) {
            corner_vertex
                .par_chunks_mut(3)
                .zip(twin.par_chunks_mut(3))
                .zip(corner_edge.par_chunks_mut(3))
                .enumerate()
                .with_min_len(FACE_CHUNK)
                .for_each(|(f, ((vertices, twins), edges))| fill(f, vertices, twins, edges));
        } else {
            let faces = corner_vertex.chunks_mut(3).zip(twin.chunks_mut(3)).zip(corner_edge.chunks_mut(3));
            faces.enumerate().for_each(|(f, ((vertices, twins), edges))| fill(f, vertices, twins, edges));
        }
        let corner_of = |h: u32| corner_of_halfedge[h as usize];
        if let Some(face) = first_pillow_face(&twin) {
            // Two triangles sharing two edges share all three (a closed "pillow"):
            // Loop refinement would glue their children non-manifoldly.
            return Err(LoopError::InteriorValenceTwo { vertex: corner_vertex[3 * face], face });
        }
        // The mesh numbers edges the same way (half-edges 2e, 2e + 1; 2e has a face).
        let edge_corner = map_indices(mesh.edge_count(), FACE_CHUNK, |e| corner_of(2 * e));
        let vertex_corner = map_indices(mesh.vertex_count(), FACE_CHUNK, |v| {
            match mesh.vertex_halfedge(mesh.vertex(v as usize).expect("internal: vertex in range")) {
                None => NONE,
                // A boundary vertex starts at the face half-edge along the boundary: the
                // twin of the boundary half-edge that arrives at it.
                Some(h) if mesh.is_boundary_halfedge(h) => corner_of(mesh.prev(h).twin().raw()),
                Some(h) => corner_of(h.raw()),
            }
        });
        let table = Self {
            vertex_count: mesh.vertex_count(),
            corner_vertex,
            twin,
            corner_edge,
            edge_corner,
            vertex_corner: OnceLock::from(vertex_corner),
        };
        #[cfg(debug_assertions)]
        {
            let from_parts = Self::from_parts(table.vertex_count, table.corner_vertex.clone(), table.twin.clone());
            assert_eq!(table, from_parts, "internal: corner table differs from its construction from parts");
            assert_eq!(table.vertex_corners(), from_parts.vertex_corners(), "internal: circulation starts differ");
        }
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

    /// The vertex of every corner (`3f + k`: corner `k` of face `f`).
    #[inline]
    pub(crate) fn corner_vertices(&self) -> &[u32] {
        &self.corner_vertex
    }

    /// The twin of every corner ([`NONE`] on the boundary).
    #[inline]
    pub(crate) fn twins(&self) -> &[u32] {
        &self.twin
    }

    /// The edge of every corner.
    #[inline]
    pub(crate) fn corner_edges(&self) -> &[u32] {
        &self.corner_edge
    }

    /// The first corner of every edge (increasing: edges are numbered by first
    /// appearance).
    #[inline]
    pub(crate) fn edge_corners(&self) -> &[u32] {
        &self.edge_corner
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

    /// First corner of edge `e`.
    #[inline]
    pub(crate) fn edge_corner(&self, e: u32) -> u32 {
        self.edge_corner[e as usize]
    }

    /// True if `v` has no incident face.
    #[inline]
    pub(crate) fn is_isolated(&self, v: u32) -> bool {
        self.vertex_corners()[v as usize] == NONE
    }

    /// True if `v` lies on the boundary.
    #[inline]
    pub(crate) fn is_boundary_vertex(&self, v: u32) -> bool {
        let c = self.vertex_corners()[v as usize];
        c != NONE && self.twin[c as usize] == NONE
    }

    /// The corners of `v` (its outgoing half-edges), counter-clockwise from the
    /// circulation start.
    #[inline]
    pub(crate) fn outgoing(&self, v: u32) -> Outgoing<'_> {
        let start = self.vertex_corners()[v as usize];
        Outgoing { table: self, start, current: start }
    }

    /// Calls `visit(edge, neighbour)` for every edge at `v`, counter-clockwise (for a
    /// boundary vertex from the boundary edge after the fan's first face to the one
    /// before its last), and reports the star.
    #[inline]
    pub(crate) fn visit_star(&self, v: u32, mut visit: impl FnMut(u32, u32)) -> VertexStar {
        let start = self.vertex_corners()[v as usize];
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

    /// True if the faces at every vertex form a single fan, closed or open: what
    /// `mesh_topo` asks of a manifold vertex, and the one property of a valid mesh that a
    /// table made from bare faces (twins paired by edges, consistently oriented, at most
    /// two per edge) can still lack, at a vertex where two fans touch. The walk from
    /// each vertex's circulation start stays at that vertex and covers its fan, and the
    /// walks of different vertices share no corner, so every fan is single exactly when
    /// the walks cover all corners together. Linear; by chunks of vertices in parallel
    /// when large. The walk is [`visit_star`](Self::visit_star)'s without the edge and
    /// neighbour it reads for its callback: through `visit_star` the whole soup
    /// decomposition took 10-17% longer (levels 3-4 of the bench).
    pub(crate) fn fans_are_single(&self) -> bool {
        let starts = self.vertex_corners();
        let fan_corners = |v: usize| {
            let start = starts[v];
            if start == NONE {
                return 0;
            }
            // The walk ends: twins pair corners one to one, so it comes back to the
            // start of a closed fan and cannot cycle elsewhere, and it cannot come back
            // to an open fan's start (whose own half-edge has no twin).
            let (mut c, mut count) = (start, 0usize);
            loop {
                count += 1;
                let t = self.twin[prev(c) as usize];
                if t == NONE || t == start {
                    return count;
                }
                c = t;
            }
        };
        let vertices = self.vertex_count;
        let covered: usize = if splits(vertices, FACE_CHUNK) {
            (0..vertices).into_par_iter().with_min_len(FACE_CHUNK).map(fan_corners).sum()
        } else {
            (0..vertices).map(fan_corners).sum()
        };
        covered == self.corner_count()
    }

    /// Loop's 1-to-4 refinement in the canonical order: vertex `v` stays `v`, the edge
    /// point of edge `e` is vertex `V + e`; coarse face `f = (a, b, c)` becomes faces
    /// `4f..4f+4` = `(a, ab, ca)`, `(b, bc, ab)`, `(c, ca, bc)`, `(ab, bc, ca)`.
    pub(crate) fn refine(&self) -> Self {
        // The forward kernel's index arithmetic, so the whole crate has one refinement.
        Self::from_topology(&kernel::refine_topology(&self.to_topology()))
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

    /// The same connectivity as the forward module's compact topology (half-edge
    /// `4f + k` for corner `3f + k`, same edge numbering, same boundary starts).
    pub(crate) fn to_topology(&self) -> Topology {
        let faces = self.face_count();
        let encode = |c: u32| if c == NONE { TOPOLOGY_INVALID } else { 4 * (c / 3) + c % 3 };
        let mut triangles = Vec::with_capacity(faces);
        let mut links = Vec::with_capacity(faces);
        let mut edges_before = 0u32;
        for f in 0..faces {
            let c = 3 * f;
            triangles.push([self.corner_vertex[c], self.corner_vertex[c + 1], self.corner_vertex[c + 2]]);
            let mut mask = 0u32;
            for k in 0..3 {
                if self.edge_corner[self.corner_edge[c + k] as usize] == (c + k) as u32 {
                    mask |= 1 << k;
                }
            }
            links.push([
                encode(self.twin[c]),
                encode(self.twin[c + 1]),
                encode(self.twin[c + 2]),
                edges_before | (mask << BASE_BITS),
            ]);
            edges_before += mask.count_ones();
        }
        Topology {
            triangles,
            links,
            vertex_halfedge: self.vertex_corners().iter().map(|&c| encode(c)).collect(),
            vertex_count: self.vertex_count,
            edge_count: self.edge_count(),
        }
    }

    /// The table of a complete forward topology (links present).
    pub(crate) fn from_topology(topology: &Topology) -> Self {
        let decode = |h: u32| if h == TOPOLOGY_INVALID { NONE } else { 3 * (h >> 2) + (h & 3) };
        let corner_vertex = topology.triangles.iter().flatten().copied().collect();
        let twin = topology.links.iter().flat_map(|l| [decode(l[0]), decode(l[1]), decode(l[2])]).collect();
        Self::from_parts(topology.vertex_count, corner_vertex, twin)
    }

    /// The faces as a polygon soup with the given positions (the corners' vertices are
    /// its indices as they are, not copied).
    pub(crate) fn into_soup(self, positions: Vec<DVec3>) -> PolygonSoup {
        debug_assert_eq!(positions.len(), self.vertex_count);
        let faces = self.face_count();
        PolygonSoup { positions, offsets: crate::forward::triangle_offsets(faces), indices: self.corner_vertex }
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
        let soup = table.clone().into_soup(vec![DVec3::ZERO; table.vertex_count()]);
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
            shapes::grid(3, 2, CellKind::Triangles).unwrap(),
            shapes::torus(4, 3, CellKind::Triangles).unwrap(),
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
    fn topology_conversions_agree_with_the_forward_module() {
        for soup in [
            shapes::icosahedron(),
            shapes::grid(3, 2, CellKind::Triangles).unwrap(),
            shapes::torus(4, 3, CellKind::Triangles).unwrap(),
        ] {
            let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
            let table = CornerTable::from_mesh(&mesh).unwrap();
            let forward = Topology::from_mesh(&mesh).unwrap();
            let converted = table.to_topology();
            assert_eq!(converted.triangles, forward.triangles);
            assert_eq!(converted.links, forward.links);
            assert_eq!(converted.vertex_halfedge, forward.vertex_halfedge);
            assert_eq!((converted.vertex_count, converted.edge_count), (forward.vertex_count, forward.edge_count));
            assert_eq!(CornerTable::from_topology(&forward), table);
        }
    }

    #[test]
    fn pillows_are_rejected() {
        let pillow = PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2], [0, 2, 1]]);
        assert!(matches!(CornerTable::from_soup(&pillow), Err(LoopError::InteriorValenceTwo { face: 0, .. })));
    }

    #[test]
    fn quads_are_rejected_with_the_face() {
        let err = CornerTable::from_soup(&shapes::cube()).unwrap_err();
        assert_eq!(err, LoopError::NotTriangle { face: 0, corners: 4 });
    }
}
