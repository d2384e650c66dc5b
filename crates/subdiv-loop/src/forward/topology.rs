//! The compact triangle topology refined level after level.
//!
//! Face `f` owns half-edges `3f`, `3f + 1`, `3f + 2`; half-edge `3f + k` runs from corner
//! `k` to corner `k + 1` (mod 3), so `next`, `prev`, origin and target are index
//! arithmetic and only the twin is stored (Dupuy and Vanhoey, "A halfedge refinement rule
//! for parallel Loop/Catmull-Clark subdivision", 2021). Edges are numbered by first
//! appearance when the half-edges are scanned in order, which is the edge order of
//! [`HalfedgeMesh`]: a half-edge is the *first* of its edge when its twin is missing
//! (boundary) or has a larger index. Instead of one edge index per half-edge, each face
//! stores the number of edges first seen before it plus a 3-bit mask of which of its
//! half-edges are first (`face_info`); the edge of a non-first half-edge is read from its
//! twin's face. After one Loop step all four arrays of the finer level follow by index
//! arithmetic (see `kernel.rs`): nothing is hashed, sorted or searched.

use mesh_topo::{HalfedgeMesh, MeshError};

use crate::LoopError;

/// "No half-edge": the twin of a boundary half-edge, the start of an isolated vertex.
pub(crate) const INVALID: u32 = u32::MAX;
/// Bits of `face_info` that hold the face's edge base; the 3 bits above hold the mask.
pub(crate) const BASE_BITS: u32 = 29;
pub(crate) const BASE_MASK: u32 = (1 << BASE_BITS) - 1;
/// Largest number of half-edges a level that is refined further may have.
pub(crate) const MAX_HALFEDGES: u64 = (u32::MAX - 1) as u64;

/// Connectivity of one level of a triangle mesh.
#[derive(Debug, Clone, Default)]
pub(crate) struct Topology {
    /// Corner vertices of each face (the origin of half-edge `3f + k` is `triangles[f][k]`).
    pub(crate) triangles: Vec<[u32; 3]>,
    /// Twin of each half-edge, [`INVALID`] on the boundary.
    pub(crate) twins: Vec<u32>,
    /// Per face: edges first seen in earlier faces (low [`BASE_BITS`] bits) and the
    /// mask of its first half-edges (bit `k` for half-edge `3f + k`).
    pub(crate) face_info: Vec<u32>,
    /// Per vertex: an outgoing half-edge, the one whose twin is missing for boundary
    /// vertices (so that the counter-clockwise walk covers the whole fan), [`INVALID`]
    /// for isolated vertices.
    pub(crate) vertex_halfedge: Vec<u32>,
    /// Number of vertices.
    pub(crate) vertex_count: usize,
    /// Number of edges.
    pub(crate) edge_count: usize,
}

/// True if half-edge `h` with twin `twin` is the first appearance of its edge.
#[inline(always)]
pub(crate) fn is_first(h: u32, twin: u32) -> bool {
    // INVALID is the largest u32, so boundary half-edges are first too.
    twin > h
}

impl Topology {
    /// Builds the compact topology of a triangle mesh.
    ///
    /// # Errors
    /// [`LoopError::NotTriangle`] naming the first face that is not a triangle;
    /// [`MeshError::TooLarge`] if the mesh has too many edges for the compact layout.
    pub(crate) fn from_mesh(mesh: &HalfedgeMesh) -> Result<Self, LoopError> {
        let face_count = mesh.face_count();
        if 3 * face_count as u64 > MAX_HALFEDGES {
            return Err(
                MeshError::TooLarge { what: "half-edges", count: 3 * face_count, max: MAX_HALFEDGES as usize }.into()
            );
        }
        if mesh.edge_count() > BASE_MASK as usize {
            return Err(MeshError::TooLarge { what: "edges", count: mesh.edge_count(), max: BASE_MASK as usize }.into());
        }
        // Mesh half-edge -> compact half-edge (boundary half-edges have none).
        let mut compact = vec![INVALID; mesh.halfedge_count()];
        let mut triangles = Vec::with_capacity(face_count);
        for f in mesh.faces() {
            let mut corners = [0u32; 3];
            let mut count = 0;
            for h in mesh.face_halfedges(f) {
                if count < 3 {
                    corners[count] = mesh.origin(h).raw();
                    compact[h.index()] = (3 * f.index() + count) as u32;
                }
                count += 1;
            }
            if count != 3 {
                return Err(LoopError::NotTriangle { face: f.index(), corners: count });
            }
            triangles.push(corners);
        }
        let mut twins = vec![INVALID; 3 * face_count];
        for f in mesh.faces() {
            for (k, h) in mesh.face_halfedges(f).enumerate() {
                twins[3 * f.index() + k] = compact[h.twin().index()];
            }
        }
        let mut face_info = Vec::with_capacity(face_count);
        let mut edges_before = 0u32;
        for f in 0..face_count {
            let mut mask = 0u32;
            for k in 0..3 {
                let h = (3 * f + k) as u32;
                if is_first(h, twins[h as usize]) {
                    mask |= 1 << k;
                }
            }
            face_info.push(edges_before | (mask << BASE_BITS));
            edges_before += mask.count_ones();
        }
        debug_assert_eq!(edges_before as usize, mesh.edge_count(), "internal: edge numbering");
        let mut vertex_halfedge = vec![INVALID; mesh.vertex_count()];
        for v in mesh.vertices() {
            if let Some(h) = mesh.vertex_halfedge(v) {
                // Boundary vertices get their start below.
                if !mesh.is_boundary_halfedge(h) {
                    vertex_halfedge[v.index()] = compact[h.index()];
                }
            }
        }
        for (h, &twin) in twins.iter().enumerate() {
            if twin == INVALID {
                vertex_halfedge[triangles[h / 3][h % 3] as usize] = h as u32;
            }
        }
        Ok(Self {
            triangles,
            twins,
            face_info,
            vertex_halfedge,
            vertex_count: mesh.vertex_count(),
            edge_count: mesh.edge_count(),
        })
    }

    /// Number of faces.
    #[inline]
    pub(crate) fn face_count(&self) -> usize {
        self.triangles.len()
    }

    /// The edge index of half-edge `h` (any half-edge, first or not).
    #[allow(dead_code)] // Used by the limit and M-band modules as they land.
    #[inline(always)]
    pub(crate) fn edge_of(&self, h: u32) -> u32 {
        let twin = self.twins[h as usize];
        let owner = if is_first(h, twin) { h } else { twin };
        let info = self.face_info[(owner / 3) as usize];
        let below = (1u32 << (owner % 3)) - 1;
        (info & BASE_MASK) + ((info >> BASE_BITS) & below).count_ones()
    }

    /// The first half-edge of every edge, in edge order.
    #[allow(dead_code)]
    pub(crate) fn edge_halfedges(&self) -> Vec<u32> {
        let mut out = Vec::with_capacity(self.edge_count);
        for (h, &twin) in self.twins.iter().enumerate() {
            if is_first(h as u32, twin) {
                out.push(h as u32);
            }
        }
        out
    }

    #[allow(dead_code)]
    /// Walks the one-ring of vertex `v` counter-clockwise: the neighbours in order and
    /// whether `v` is on the boundary (then the first and last neighbours are its two
    /// boundary neighbours). Empty for an isolated vertex.
    pub(crate) fn ring(&self, v: u32) -> (Vec<u32>, bool) {
        let start = self.vertex_halfedge[v as usize];
        let mut ring = Vec::new();
        if start == INVALID {
            return (ring, false);
        }
        let mut h = start;
        loop {
            let (f, k) = ((h / 3) as usize, (h % 3) as usize);
            let corners = self.triangles[f];
            ring.push(corners[(k + 1) % 3]);
            let prev = (3 * f + (k + 2) % 3) as u32;
            let twin = self.twins[prev as usize];
            if twin == INVALID {
                ring.push(corners[(k + 2) % 3]);
                return (ring, true);
            }
            if twin == start || ring.len() > self.triangles.len() * 3 {
                debug_assert!(twin == start, "internal: one-ring walk did not close");
                return (ring, false);
            }
            h = twin;
        }
    }
}

#[cfg(test)]
mod tests {
    use mesh_topo::shapes::{self, CellKind};

    use super::*;

    #[test]
    fn edge_numbering_matches_the_halfedge_mesh() {
        for soup in [shapes::icosahedron(), shapes::grid(3, 2, CellKind::Triangles), shapes::tetrahedron()] {
            let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
            let topo = Topology::from_mesh(&mesh).unwrap();
            for f in mesh.faces() {
                for (k, h) in mesh.face_halfedges(f).enumerate() {
                    assert_eq!(topo.edge_of((3 * f.index() + k) as u32) as usize, h.edge().index());
                }
            }
            assert_eq!(topo.edge_halfedges().len(), mesh.edge_count());
        }
    }

    #[test]
    fn rings_match_the_halfedge_mesh() {
        let mesh = HalfedgeMesh::from_soup(&shapes::grid(3, 3, CellKind::Triangles)).unwrap();
        let topo = Topology::from_mesh(&mesh).unwrap();
        for v in mesh.vertices() {
            let (ring, boundary) = topo.ring(v.raw());
            assert_eq!(boundary, mesh.is_boundary_vertex(v));
            let mut expected: Vec<u32> = mesh.vertex_neighbors(v).map(|w| w.raw()).collect();
            let mut sorted = ring.clone();
            sorted.sort_unstable();
            expected.sort_unstable();
            assert_eq!(sorted, expected, "vertex {v:?}");
        }
    }

    #[test]
    fn quads_are_rejected_by_face() {
        let mesh = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        assert_eq!(Topology::from_mesh(&mesh).unwrap_err(), LoopError::NotTriangle { face: 0, corners: 4 });
    }
}
