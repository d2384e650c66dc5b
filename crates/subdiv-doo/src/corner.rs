//! Flat corner-based connectivity and the Doo-Sabin topology step by index arithmetic.
//!
//! A *corner* is a (face, position) pair; corners are numbered face after face, in
//! order, so corner `c` of a polygon soup is `soup.indices[c]`. Each corner also stands
//! for the half-edge leaving it inside its face, and `corner_twin[c]` is the corner of
//! the opposite half-edge (or [`NONE`] on the boundary). This is all Doo-Sabin needs:
//! one step turns every corner into a fine vertex, so the fine mesh's faces, its corner
//! twins and even the parents of its faces are index arithmetic on the coarse arrays,
//! level after level, without ever rebuilding a half-edge structure.

use glam::DVec3;
use mesh_topo::memory::filled_vec;
use mesh_topo::{HalfedgeMesh, PolygonSoup};
use rayon::prelude::*;

use crate::DooError;
use crate::rule::FaceMaps;

/// "No corner": the twin of a boundary corner, the first corner of an isolated vertex.
pub(crate) const NONE: u32 = u32::MAX;

/// Connectivity of a manifold polygon mesh as corner arrays (see the module docs).
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct CornerMesh {
    /// Start of each face's corners, plus the total (faces + 1 entries).
    pub offsets: Vec<u32>,
    /// Vertex of each corner.
    pub corner_vertex: Vec<u32>,
    /// Corner of the opposite half-edge, [`NONE`] on the boundary.
    pub corner_twin: Vec<u32>,
    /// The next corner in the same face.
    pub corner_next: Vec<u32>,
    /// Number of vertices.
    pub vertex_count: usize,
    /// Smallest corner of each vertex ([`NONE`] if isolated); `None` means the identity
    /// (vertex `v`'s smallest corner is `v`), which holds for every Doo-Sabin output.
    pub vertex_corner: Option<Vec<u32>>,
}

impl CornerMesh {
    /// Number of faces.
    #[inline]
    pub fn face_count(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Number of corners.
    #[inline]
    pub fn corner_count(&self) -> usize {
        self.corner_vertex.len()
    }

    /// The corner after `c` in its face.
    #[inline]
    pub fn next(&self, c: u32) -> u32 {
        self.corner_next[c as usize]
    }

    /// Smallest corner of vertex `v`, or [`NONE`].
    #[inline]
    pub fn first_corner(&self, v: usize) -> u32 {
        match &self.vertex_corner {
            Some(corners) => corners[v],
            None => v as u32,
        }
    }

    /// The corner arrays of a half-edge mesh (linear time). One walk around each face
    /// gives the corner vertices (the origin of a half-edge is the target of the one
    /// before it) and the half-edge of each corner; the twins go through one array
    /// from half-edges to corners.
    pub fn from_halfedge(mesh: &HalfedgeMesh) -> Self {
        let halfedges = mesh.halfedge_count();
        let target = mesh.raw_halfedge_targets();
        let next_halfedge = mesh.raw_halfedge_next();
        let mut offsets = Vec::with_capacity(mesh.face_count() + 1);
        offsets.push(0u32);
        let mut corner_vertex = Vec::with_capacity(halfedges);
        // The half-edge of each corner, turned into the twin corners below.
        let mut corner_twin = Vec::with_capacity(halfedges);
        let mut corner_next = Vec::with_capacity(halfedges);
        for f in mesh.faces() {
            let first = mesh.face_halfedge(f).raw();
            let begin = corner_vertex.len() as u32;
            let mut origin = target[(first ^ 1) as usize];
            let mut h = first;
            loop {
                corner_vertex.push(origin);
                corner_twin.push(h);
                origin = target[h as usize];
                h = next_halfedge[h as usize];
                if h == first {
                    break;
                }
            }
            let end = corner_vertex.len() as u32;
            corner_next.extend(begin + 1..end);
            corner_next.push(begin);
            offsets.push(end);
        }
        let mut halfedge_corner = vec![NONE; halfedges];
        for (c, &h) in corner_twin.iter().enumerate() {
            halfedge_corner[h as usize] = c as u32;
        }
        for t in corner_twin.iter_mut() {
            *t = halfedge_corner[(*t ^ 1) as usize];
        }
        drop(halfedge_corner);
        let mut vertex_corner = vec![NONE; mesh.vertex_count()];
        for (c, &v) in corner_vertex.iter().enumerate() {
            if vertex_corner[v as usize] == NONE {
                vertex_corner[v as usize] = c as u32;
            }
        }
        Self {
            offsets,
            corner_vertex,
            corner_twin,
            corner_next,
            vertex_count: mesh.vertex_count(),
            vertex_corner: Some(vertex_corner),
        }
    }

    /// The corner arrays of a polygon soup, checked to be a manifold polygon mesh (faces of
    /// at least three distinct vertices, each directed edge used once, each vertex's faces
    /// one fan), without building a half-edge mesh: linear time. The error says what is
    /// wrong and where.
    pub fn from_soup(soup: &PolygonSoup) -> Result<Self, String> {
        Self::from_soup_grouped(soup).map(|(mesh, _)| mesh)
    }

    /// [`Self::from_soup`], also returning the corners of each vertex in increasing
    /// order (CSR: `(offsets, corners)`, as [`group_by_key`] gives them), which the check
    /// computes anyway.
    pub fn from_soup_grouped(soup: &PolygonSoup) -> Result<(Self, VertexCorners), String> {
        Self::from_faces_grouped(soup.offsets.clone(), soup.indices.clone(), soup.positions.len())
    }

    /// [`Self::from_soup`] on face offsets and corner vertices that the mesh takes over
    /// (no positions needed: the check is on connectivity only).
    pub fn from_faces(offsets: Vec<u32>, indices: Vec<u32>, vertex_count: usize) -> Result<Self, String> {
        Self::from_faces_grouped(offsets, indices, vertex_count).map(|(mesh, _)| mesh)
    }

    /// [`Self::from_faces`], also returning the corners of each vertex as
    /// [`Self::from_soup_grouped`] does.
    pub fn from_faces_grouped(
        offsets: Vec<u32>,
        corner_vertex: Vec<u32>,
        vertex_count: usize,
    ) -> Result<(Self, VertexCorners), String> {
        let offsets = if offsets.is_empty() { vec![0] } else { offsets };
        let indices = &corner_vertex;
        if offsets[0] != 0 || offsets[offsets.len() - 1] as usize != indices.len() {
            return Err("the face offsets do not cover the corner list".into());
        }
        for (f, w) in offsets.windows(2).enumerate() {
            if w[1] < w[0] + 3 {
                return Err(format!("face {f} has fewer than three corners"));
            }
        }
        if let Some(c) = indices.iter().position(|&v| v as usize >= vertex_count) {
            return Err(format!("corner {c} refers to vertex {} of {vertex_count}", indices[c]));
        }
        let corners = indices.len();
        let next = next_of_corners(&offsets);
        let prev = prev_of_corners(&offsets);
        // Corners of each vertex (CSR, increasing corner order).
        let (start, corners_of) = group_by_key(indices, vertex_count);
        // Each directed edge once (this also rejects a face visiting a vertex twice along
        // one edge). Vertex by vertex: its outgoing edges `u -> w` are recorded by target
        // (`slot[w] = (u, corner)`); then each incoming edge `x -> u` (the
        // corner before each corner of `u`) and the outgoing `u -> x`, if any, are twins.
        let mut slot = vec![(NONE, NONE); vertex_count];
        let mut corner_twin = vec![NONE; corners];
        for u in 0..vertex_count {
            let mine = &corners_of[start[u] as usize..start[u + 1] as usize];
            for &c in mine {
                let w = indices[next[c as usize] as usize];
                if w as usize == u {
                    return Err(format!("a face has two consecutive corners at vertex {u}"));
                }
                if slot[w as usize].0 == u as u32 {
                    return Err(format!("the edge {u} -> {w} is used twice in the same direction"));
                }
                slot[w as usize] = (u as u32, c);
            }
            for &c in mine {
                let p = prev[c as usize];
                let (owner, d) = slot[indices[p as usize] as usize];
                if owner == u as u32 {
                    corner_twin[p as usize] = d;
                }
            }
        }
        // Each vertex one fan: walking around it from its first corner reaches all its corners.
        let mut vertex_corner = vec![NONE; vertex_count];
        for v in 0..vertex_count {
            let mine = &corners_of[start[v] as usize..start[v + 1] as usize];
            let Some(&first) = mine.first() else { continue };
            vertex_corner[v] = first;
            let mut reached = 1;
            let mut c = first;
            let mut closed = false;
            while corner_twin[c as usize] != NONE && reached <= mine.len() {
                c = next[corner_twin[c as usize] as usize];
                if c == first {
                    closed = true;
                    break;
                }
                reached += 1;
            }
            if !closed {
                let mut c = first;
                while corner_twin[prev[c as usize] as usize] != NONE && reached <= mine.len() {
                    c = corner_twin[prev[c as usize] as usize];
                    reached += 1;
                }
            }
            if reached != mine.len() {
                return Err(format!("vertex {v} is not manifold (its faces do not form one fan)"));
            }
        }
        let mesh = Self {
            offsets,
            corner_vertex,
            corner_twin,
            corner_next: next,
            vertex_count,
            vertex_corner: Some(vertex_corner),
        };
        Ok((mesh, (start, corners_of)))
    }

    /// Walks clockwise around the vertex of corner `start` (`c -> next(twin(c))`),
    /// calling `visit` on each corner after `start`. Returns the number of corners of
    /// the vertex if its fan is closed, `None` if the walk reaches the boundary.
    #[inline]
    pub fn walk_clockwise(&self, start: u32, mut visit: impl FnMut(u32)) -> Option<usize> {
        let mut c = start;
        let mut count = 1usize;
        loop {
            let t = self.corner_twin[c as usize];
            if t == NONE {
                return None;
            }
            c = self.corner_next[t as usize];
            if c == start {
                return Some(count);
            }
            visit(c);
            count += 1;
            debug_assert!(count <= self.corner_count(), "internal: vertex cycle does not close");
        }
    }
}

/// The corners of each vertex as CSR arrays `(offsets, corners)` ([`group_by_key`]).
pub(crate) type VertexCorners = (Vec<u32>, Vec<u32>);

/// Groups the indices `0..keys.len()` by their key (each below `key_count`) with a
/// counting sort: `members[offsets[k]..offsets[k + 1]]` are the indices whose key is `k`,
/// in increasing order. Linear in `keys.len() + key_count`.
pub(crate) fn group_by_key(keys: &[u32], key_count: usize) -> (Vec<u32>, Vec<u32>) {
    let mut offsets = filled_vec(key_count + 1, 0u32);
    for &k in keys {
        offsets[k as usize + 1] += 1;
    }
    for k in 0..key_count {
        offsets[k + 1] += offsets[k];
    }
    // Each group's start serves as its fill cursor and ends at the next group's start.
    let mut members = filled_vec(keys.len(), 0u32);
    for (i, &k) in keys.iter().enumerate() {
        let fill = &mut offsets[k as usize];
        members[*fill as usize] = i as u32;
        *fill += 1;
    }
    offsets.copy_within(0..key_count, 1);
    offsets[0] = 0;
    (offsets, members)
}

/// The next corner of every corner, from the face offsets.
pub(crate) fn next_of_corners(offsets: &[u32]) -> Vec<u32> {
    let corners = offsets.last().copied().unwrap_or(0) as usize;
    let mut next = Vec::with_capacity(corners);
    for w in offsets.windows(2) {
        if w[1] > w[0] {
            next.extend(w[0] + 1..w[1]);
            next.push(w[0]);
        }
    }
    next
}

/// The previous corner of every corner, from the face offsets.
pub(crate) fn prev_of_corners(offsets: &[u32]) -> Vec<u32> {
    let corners = offsets.last().copied().unwrap_or(0) as usize;
    let mut prev = Vec::with_capacity(corners);
    for w in offsets.windows(2) {
        if w[1] > w[0] {
            prev.push(w[1] - 1);
            prev.extend(w[0]..w[1] - 1);
        }
    }
    prev
}

/// The face of every corner, from the face offsets.
pub(crate) fn faces_of_corners(offsets: &[u32]) -> Vec<u32> {
    let corners = offsets.last().copied().unwrap_or(0) as usize;
    let mut face = Vec::with_capacity(corners);
    for (f, w) in offsets.windows(2).enumerate() {
        face.extend(std::iter::repeat_n(f as u32, (w[1] - w[0]) as usize));
    }
    face
}

/// Which element of the coarse mesh a fine face comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
pub enum FaceOrigin {
    /// An F_F face: the shrunken copy of coarse face `.0`.
    Face(u32),
    /// An F_E quad: across coarse edge `.0` (numbered as `mesh-topo` numbers the edges of
    /// the coarse mesh: in order of first appearance, face by face, corner by corner); or,
    /// under [`crate::BoundaryRule::Chaikin`], the boundary quad of boundary edge `.0`.
    Edge(u32),
    /// An F_V face: around interior coarse vertex `.0`; or, under
    /// [`crate::BoundaryRule::Chaikin`], the boundary vertex face of boundary vertex `.0`.
    Vertex(u32),
}

/// The three kinds of faces of a Doo-Sabin step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
pub enum FaceKind {
    /// F_F: from a coarse face, same number of sides.
    Face,
    /// F_E: a quad across an interior coarse edge.
    Edge,
    /// F_V: around an interior coarse vertex, as many sides as the vertex has edges.
    Vertex,
}

impl FaceOrigin {
    /// The kind of face.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_doo::{DooOptions, FaceKind, FaceOrigin, subdivide};
    ///
    /// assert_eq!(FaceOrigin::Edge(7).kind(), FaceKind::Edge);
    /// // A tetrahedron: one F_F face per face, one F_E quad per edge, one F_V face per vertex.
    /// let tetrahedron = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
    /// let fine = subdivide(&tetrahedron, &DooOptions::default())?;
    /// let count = |k| (0..fine.face_count()).filter(|&f| fine.face_origin(f).kind() == k).count();
    /// assert_eq!([count(FaceKind::Face), count(FaceKind::Edge), count(FaceKind::Vertex)], [4, 6, 4]);
    /// # Ok::<(), subdiv_doo::DooError>(())
    /// ```
    pub fn kind(self) -> FaceKind {
        match self {
            FaceOrigin::Face(_) => FaceKind::Face,
            FaceOrigin::Edge(_) => FaceKind::Edge,
            FaceOrigin::Vertex(_) => FaceKind::Vertex,
        }
    }
}

/// The fine connectivity of one Doo-Sabin step.
#[derive(Debug, Clone, PartialEq, Default)]
pub(crate) struct DooTopology {
    /// Face offsets of the fine mesh.
    pub offsets: Vec<u32>,
    /// Corner vertices of the fine mesh (fine vertex = coarse corner).
    pub indices: Vec<u32>,
    /// Number of F_F faces (= coarse faces); they come first.
    pub ff_count: usize,
    /// Number of F_E quads; they follow.
    pub fe_count: usize,
    /// Number of F_V faces; they come last.
    pub fv_count: usize,
    /// Coarse edge of each F_E quad; `None` = the identity (no boundary edge).
    pub edge_parent: Option<Vec<u32>>,
    /// Coarse vertex of each F_V face; `None` = the identity (every vertex interior).
    pub vertex_parent: Option<Vec<u32>>,
    /// Fine corner twins and next corners, if asked for.
    pub adjacency: Option<(Vec<u32>, Vec<u32>)>,
    /// Under the Chaikin boundary rule: coarse edge of each boundary quad, then coarse
    /// vertex of each boundary vertex face (faces after the F_V faces; empty otherwise).
    pub ring_edge_parent: Vec<u32>,
    pub ring_vertex_parent: Vec<u32>,
}

impl DooTopology {
    /// The fine connectivity as a corner mesh (needs the adjacency).
    pub fn into_corner_mesh(self, vertex_count: usize) -> CornerMesh {
        let (corner_twin, corner_next) = self.adjacency.expect("internal: adjacency was requested");
        CornerMesh {
            offsets: self.offsets,
            corner_vertex: self.indices,
            corner_twin,
            corner_next,
            vertex_count,
            vertex_corner: None,
        }
    }

    /// Origin of fine face `f`.
    pub fn origin(&self, f: usize) -> FaceOrigin {
        let fe_end = self.ff_count + self.fe_count;
        if f < self.ff_count {
            FaceOrigin::Face(f as u32)
        } else if f < fe_end {
            let q = f - self.ff_count;
            FaceOrigin::Edge(self.edge_parent.as_ref().map_or(q as u32, |p| p[q]))
        } else if f < fe_end + self.fv_count {
            let k = f - fe_end;
            FaceOrigin::Vertex(self.vertex_parent.as_ref().map_or(k as u32, |p| p[k]))
        } else {
            let k = f - fe_end - self.fv_count;
            match self.ring_edge_parent.get(k) {
                Some(&e) => FaceOrigin::Edge(e),
                None => FaceOrigin::Vertex(self.ring_vertex_parent[k - self.ring_edge_parent.len()]),
            }
        }
    }
}

fn check_size(what: &'static str, count: usize) -> Result<(), DooError> {
    if count >= NONE as usize {
        return Err(DooError::TooLarge { what, count, max: NONE as usize - 1 });
    }
    Ok(())
}

/// The size check of [`doo_topology`] for one step of a mesh of `corners` corners and
/// `interior_edges` interior edges: the fine vertices (one per corner), and the fine
/// corners counted as if every corner had an F_V corner.
pub(crate) fn check_step_size(corners: usize, interior_edges: usize) -> Result<(), DooError> {
    check_size("fine vertices", corners)?;
    check_size("fine corners", corners.saturating_mul(2).saturating_add(interior_edges.saturating_mul(4)))
}

/// One Doo-Sabin step on the connectivity (see [`crate::forward`] for the order of the
/// fine faces). With `with_adjacency`, also the fine corner twins and next corners, for a
/// further step. Every array is written once, front to back, except the twins of the
/// quads' two side edges, which the F_V pass fills in.
///
/// # Errors
/// [`DooError::ValenceTwoVertex`] for an interior vertex with two edges;
/// [`DooError::TooLarge`] if the fine mesh would not fit `u32` indices.
pub(crate) fn doo_topology(coarse: &CornerMesh, with_adjacency: bool) -> Result<DooTopology, DooError> {
    let corners = coarse.corner_count();
    let faces = coarse.face_count();
    let twin = &coarse.corner_twin;
    let next = &coarse.corner_next;
    let interior_edges = (0..corners as u32).filter(|&c| twin[c as usize] != NONE && c < twin[c as usize]).count();
    let quad_base = corners as u32;
    let fv_base = corners + 4 * interior_edges;
    check_step_size(corners, interior_edges)?;

    let mut offsets = Vec::with_capacity(faces + interior_edges + coarse.vertex_count + 1);
    offsets.extend_from_slice(&coarse.offsets);
    if offsets.is_empty() {
        offsets.push(0);
    }
    let mut indices = Vec::with_capacity(fv_base + corners);
    indices.extend(0..quad_base);
    let (mut twins, mut nexts) = if with_adjacency {
        let mut twins = Vec::with_capacity(fv_base + corners);
        twins.resize(corners, NONE);
        let mut nexts = Vec::with_capacity(fv_base + corners);
        nexts.extend_from_slice(next);
        (twins, nexts)
    } else {
        (Vec::new(), Vec::new())
    };

    // F_E quads (c, next(t), t, next(c)) in coarse edge order. Coarse edges are named by
    // their first corner (the smaller one; the only one on the boundary): mesh-topo's
    // edge numbering.
    let mut edge_parent: Option<Vec<u32>> = None;
    let mut edge_rank = 0u32;
    for (c, &t) in twin.iter().enumerate() {
        let c = c as u32;
        if t == NONE {
            if edge_parent.is_none() {
                edge_parent = Some((0..(offsets.len() - 1 - faces) as u32).collect());
            }
            edge_rank += 1;
            continue;
        }
        if c > t {
            continue;
        }
        let b = *offsets.last().expect("internal: offsets start with 0");
        indices.extend_from_slice(&[c, next[t as usize], t, next[c as usize]]);
        offsets.push(b + 4);
        if let Some(parents) = &mut edge_parent {
            parents.push(edge_rank);
        }
        edge_rank += 1;
        if with_adjacency {
            twins.extend_from_slice(&[NONE, t, NONE, c]);
            nexts.extend_from_slice(&[b + 1, b + 2, b + 3, b]);
            twins[c as usize] = b + 3;
            twins[t as usize] = b + 1;
        }
    }
    debug_assert_eq!(indices.len(), fv_base);

    // F_V faces: one per interior vertex, its corners counter-clockwise from its first
    // corner. The clockwise walk gives them in reverse after the first one.
    let mut vertex_parent: Option<Vec<u32>> = None;
    for v in 0..coarse.vertex_count {
        let start = coarse.first_corner(v);
        let begin = indices.len();
        let closed = if start == NONE {
            None
        } else {
            indices.push(start);
            coarse.walk_clockwise(start, |c| indices.push(c))
        };
        let Some(valence) = closed else {
            indices.truncate(begin);
            if vertex_parent.is_none() {
                vertex_parent = Some((0..(offsets.len() - 1 - faces - interior_edges) as u32).collect());
            }
            continue;
        };
        if valence == 2 {
            return Err(DooError::ValenceTwoVertex { vertex: v });
        }
        indices[begin + 1..].reverse();
        offsets.push(indices.len() as u32);
        if let Some(parents) = &mut vertex_parent {
            parents.push(v as u32);
        }
        if with_adjacency {
            // The edge c_i -> c_{i+1} of the F_V face lies on the quad of the coarse edge
            // {twin(c_{i+1}), c_{i+1}}; that quad's corner next to c_{i+1} is recorded
            // in the F_F twin of c_{i+1}: b + 3 if c_{i+1} is the edge's first corner (the
            // shared quad edge then leaves b), b + 1 otherwise (it leaves b + 2).
            let end = indices.len();
            for k in begin..end {
                let following = indices[if k + 1 == end { begin } else { k + 1 }];
                let relative = twins[following as usize] - quad_base;
                let quad_corner = quad_base + (relative & !3) + if relative & 3 == 1 { 2 } else { 0 };
                twins.push(quad_corner);
                twins[quad_corner as usize] = k as u32;
                nexts.push(if k + 1 == end { begin as u32 } else { k as u32 + 1 });
            }
        }
    }
    let fe_count = interior_edges;
    let fv_count = offsets.len() - 1 - faces - fe_count;
    check_size("fine faces", offsets.len() - 1)?;
    let adjacency = with_adjacency.then_some((twins, nexts));
    Ok(DooTopology {
        offsets,
        indices,
        ff_count: faces,
        fe_count,
        fv_count,
        edge_parent,
        vertex_parent,
        adjacency,
        ..DooTopology::default()
    })
}

/// Splits `out` into pieces following whole faces, about `pieces` of them, so that
/// faces can be processed in parallel with each piece written by one task.
fn face_chunks<'a, T>(offsets: &[u32], mut out: &'a mut [T], target: usize) -> Vec<(usize, usize, &'a mut [T])> {
    let faces = offsets.len().saturating_sub(1);
    let per = faces.div_ceil(target.max(1)).max(1);
    let mut chunks = Vec::with_capacity(faces / per + 1);
    let mut f = 0;
    while f < faces {
        let end = (f + per).min(faces);
        let len = (offsets[end] - offsets[f]) as usize;
        let (head, tail) = std::mem::take(&mut out).split_at_mut(len);
        chunks.push((f, end, head));
        out = tail;
        f = end;
    }
    chunks
}

/// Faces per parallel task below which a single task does everything.
pub(crate) const PARALLEL_FACES: usize = 1 << 14;

/// `(a(), b())`, side by side on the rayon pool for a step of at least
/// [`PARALLEL_FACES`] coarse faces when the pool has several threads (a step's fine
/// connectivity and its positions do not depend on each other), else one after the
/// other on this thread.
pub(crate) fn side_by_side<A: Send, B: Send>(
    faces: usize,
    a: impl FnOnce() -> A + Send,
    b: impl FnOnce() -> B + Send,
) -> (A, B) {
    if splits(faces) { rayon::join(a, b) } else { (a(), b()) }
}

/// Whether work over `faces` coarse faces is spread over the pool: it has several
/// threads and the faces are at least [`PARALLEL_FACES`].
fn splits(faces: usize) -> bool {
    faces >= PARALLEL_FACES && rayon::current_num_threads() > 1
}

/// Runs `work(first, end, slice)` on runs of whole faces `first..end`, `slice` being the
/// part of `out` that holds their corners: one run for small meshes or a one-thread pool
/// (handing the run to that thread from outside the pool costs a wake-up and brings
/// nothing), else pieces spread over the rayon pool. Each corner is written by one task,
/// so results do not depend on the thread count.
fn for_face_runs<T, W>(offsets: &[u32], out: &mut [T], work: W)
where
    T: Send,
    W: Fn(usize, usize, &mut [T]) + Sync,
{
    let faces = offsets.len().saturating_sub(1);
    if splits(faces) {
        let target = rayon::current_num_threads() * 8;
        face_chunks(offsets, out, target).into_par_iter().for_each(|(first, end, slice)| work(first, end, slice));
    } else {
        work(0, faces, out);
    }
}

/// Applies `map(points, out)` to every face, `points` being `point(c)` for its corners
/// `c` and `out` its corners in `out` (see [`for_face_runs`]).
fn map_faces<P, M>(offsets: &[u32], out: &mut [DVec3], point: P, map: M)
where
    P: Fn(usize) -> DVec3 + Sync,
    M: Fn(&[DVec3], &mut [DVec3]) + Sync,
{
    for_face_runs(offsets, out, |first, end, slice| {
        let base = offsets[first] as usize;
        let mut gathered: Vec<DVec3> = Vec::new();
        for f in first..end {
            let (b, e) = (offsets[f] as usize, offsets[f + 1] as usize);
            gathered.clear();
            gathered.extend((b..e).map(&point));
            map(&gathered, &mut slice[b - base..e - base]);
        }
    });
}

/// New positions of one step: for every face, its F_F corners computed from the points
/// `point(c)` of its corners `c` (the coarse vertex positions, or per-corner candidates
/// in reconstruction). Output index = corner index. Bit-identical for any thread count.
pub(crate) fn face_points<P>(offsets: &[u32], maps: &FaceMaps, point: P) -> Vec<DVec3>
where
    P: Fn(usize) -> DVec3 + Sync,
{
    let corners = offsets.last().copied().unwrap_or(0) as usize;
    let mut out = vec![DVec3::ZERO; corners];
    map_faces(offsets, &mut out, point, |points, out| maps.forward(points, out));
    out
}

/// [`face_points`] in place: `points[c]` is the point of corner `c` on entry and its
/// F_F corner on return (each face reads and writes only its own corners, so no second
/// array is needed). Bit-identical for any thread count.
pub(crate) fn face_points_in_place(offsets: &[u32], maps: &FaceMaps, points: &mut [DVec3]) {
    for_face_runs(offsets, points, |first, end, slice| {
        map_run_in_place(offsets, first..end, slice, |face, out| maps.forward(face, out));
    });
}

/// Each face of the run `faces` (its corners' points in `run`, from corner
/// `offsets[faces.start]` on) replaced by `map(face points, out)`, in place.
fn map_run_in_place(
    offsets: &[u32],
    faces: std::ops::Range<usize>,
    run: &mut [DVec3],
    map: impl Fn(&[DVec3], &mut [DVec3]),
) {
    let base = offsets[faces.start] as usize;
    let mut gathered: Vec<DVec3> = Vec::new();
    for f in faces {
        let (b, e) = (offsets[f] as usize - base, offsets[f + 1] as usize - base);
        gathered.clear();
        gathered.extend_from_slice(&run[b..e]);
        map(&gathered, &mut run[b..e]);
    }
}

/// Per-face expansion (inverse map) of the points `point(c)` at the corners of the
/// faces listed in `faces` (ranges given by `offsets`), written per corner.
/// `buffer` is reused for the result (its contents are overwritten).
pub(crate) fn expand_faces<P>(offsets: &[u32], maps: &FaceMaps, point: P, buffer: Vec<DVec3>) -> Vec<DVec3>
where
    P: Fn(usize) -> DVec3 + Sync,
{
    let corners = offsets.last().copied().unwrap_or(0) as usize;
    let mut out = buffer;
    out.resize(corners, DVec3::ZERO);
    // The points first, in one tight loop per run (scattered reads overlap), then each
    // face expanded in place: the same values as gathering face by face.
    for_face_runs(offsets, &mut out, |first, end, slice| {
        let base = offsets[first] as usize;
        for (c, out) in (base..).zip(slice.iter_mut()) {
            *out = point(c);
        }
        map_run_in_place(offsets, first..end, slice, |face, out| maps.inverse(face, out));
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use mesh_topo::shapes::{self, CellKind};

    #[test]
    fn from_soup_equals_from_halfedge() {
        for soup in [
            shapes::cube(),
            shapes::icosahedron(),
            shapes::torus(5, 4, CellKind::Mixed).unwrap(),
            shapes::grid(3, 4, CellKind::Mixed).unwrap(),
        ] {
            let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
            assert_eq!(CornerMesh::from_soup(&soup).unwrap(), CornerMesh::from_halfedge(&mesh));
        }
    }

    #[test]
    fn from_soup_rejects_what_is_not_a_manifold_mesh() {
        let square = |a: u32| [a, a + 1, a + 2];
        let p = vec![DVec3::ZERO; 7];
        // A triangle with a vertex out of range, a digon, an edge used twice in one direction.
        let bad = [
            PolygonSoup::from_faces(p.clone(), [[0u32, 1, 9]]),
            PolygonSoup::from_faces(p.clone(), [vec![0u32, 1]]),
            PolygonSoup::from_faces(p.clone(), [[0u32, 1, 2], [0, 1, 3]]),
            // Two triangle fans sharing only vertex 0 (a bow tie).
            PolygonSoup::from_faces(p.clone(), [[0u32, 1, 2], [0, 3, 4]]),
        ];
        for soup in &bad {
            assert!(CornerMesh::from_soup(soup).is_err(), "{soup:?}");
        }
        assert!(CornerMesh::from_soup(&PolygonSoup::from_faces(p, [square(0), square(3)])).is_ok());
    }
}
