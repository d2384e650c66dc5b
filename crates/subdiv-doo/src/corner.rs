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
use mesh_topo::HalfedgeMesh;
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
    /// Face of each corner.
    pub corner_face: Vec<u32>,
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
        let f = self.corner_face[c as usize] as usize;
        if c + 1 == self.offsets[f + 1] { self.offsets[f] } else { c + 1 }
    }

    /// The corner before `c` in its face.
    #[inline]
    pub fn prev(&self, c: u32) -> u32 {
        let f = self.corner_face[c as usize] as usize;
        if c == self.offsets[f] { self.offsets[f + 1] - 1 } else { c - 1 }
    }

    /// Smallest corner of vertex `v`, or [`NONE`].
    #[inline]
    pub fn first_corner(&self, v: usize) -> u32 {
        match &self.vertex_corner {
            Some(corners) => corners[v],
            None => v as u32,
        }
    }

    /// Corner range of face `f`.
    #[inline]
    pub fn face_corners(&self, f: usize) -> std::ops::Range<usize> {
        self.offsets[f] as usize..self.offsets[f + 1] as usize
    }

    /// The corner arrays of a half-edge mesh (linear time).
    pub fn from_halfedge(mesh: &HalfedgeMesh) -> Self {
        let soup_faces = mesh.face_count();
        let mut offsets = Vec::with_capacity(soup_faces + 1);
        offsets.push(0u32);
        let mut corner_vertex = Vec::with_capacity(mesh.halfedge_count());
        let mut corner_face = Vec::with_capacity(mesh.halfedge_count());
        let mut halfedge_corner = vec![NONE; mesh.halfedge_count()];
        for f in mesh.faces() {
            for h in mesh.face_halfedges(f) {
                halfedge_corner[h.index()] = corner_vertex.len() as u32;
                corner_vertex.push(mesh.origin(h).raw());
                corner_face.push(f.raw());
            }
            offsets.push(corner_vertex.len() as u32);
        }
        let mut corner_twin = vec![NONE; corner_vertex.len()];
        for (h, &c) in halfedge_corner.iter().enumerate() {
            if c != NONE {
                corner_twin[c as usize] = halfedge_corner[h ^ 1];
            }
        }
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
            corner_face,
            vertex_count: mesh.vertex_count(),
            vertex_corner: Some(vertex_corner),
        }
    }

    /// Face of every corner from the offsets.
    pub fn faces_of_corners(offsets: &[u32]) -> Vec<u32> {
        let corners = offsets.last().copied().unwrap_or(0) as usize;
        let mut corner_face = vec![0u32; corners];
        for (f, w) in offsets.windows(2).enumerate() {
            corner_face[w[0] as usize..w[1] as usize].fill(f as u32);
        }
        corner_face
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
            c = self.next(t);
            if c == start {
                return Some(count);
            }
            visit(c);
            count += 1;
            debug_assert!(count <= self.corner_count(), "internal: vertex cycle does not close");
        }
    }
}

/// Which element of the coarse mesh a fine face comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
pub enum FaceOrigin {
    /// An F_F face: the shrunken copy of coarse face `.0`.
    Face(u32),
    /// An F_E quad: across coarse edge `.0` (numbered as `mesh-topo` numbers the edges of
    /// the coarse mesh: in order of first appearance, face by face, corner by corner).
    Edge(u32),
    /// An F_V face: around interior coarse vertex `.0`.
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
    /// Coarse edge of each F_E quad (they follow the F_F faces).
    pub edge_parent: Vec<u32>,
    /// Coarse vertex of each F_V face (they come last).
    pub vertex_parent: Vec<u32>,
    /// Fine corner twins, if asked for.
    pub twins: Option<Vec<u32>>,
}

impl DooTopology {
    /// The fine connectivity as a corner mesh (needs the twins).
    pub fn into_corner_mesh(self, vertex_count: usize) -> CornerMesh {
        let corner_face = CornerMesh::faces_of_corners(&self.offsets);
        CornerMesh {
            corner_twin: self.twins.expect("internal: twins were requested"),
            offsets: self.offsets,
            corner_vertex: self.indices,
            corner_face,
            vertex_count,
            vertex_corner: None,
        }
    }

    /// Origin of fine face `f`.
    pub fn origin(&self, f: usize) -> FaceOrigin {
        let fe = self.ff_count + self.edge_parent.len();
        if f < self.ff_count {
            FaceOrigin::Face(f as u32)
        } else if f < fe {
            FaceOrigin::Edge(self.edge_parent[f - self.ff_count])
        } else {
            FaceOrigin::Vertex(self.vertex_parent[f - fe])
        }
    }
}

fn check_size(what: &'static str, count: usize) -> Result<(), DooError> {
    if count >= NONE as usize {
        return Err(DooError::TooLarge { what, count, max: NONE as usize - 1 });
    }
    Ok(())
}

/// One Doo-Sabin step on the connectivity (see the crate docs for the order of the
/// fine faces). With `with_twins`, also the fine corner twins, for a further step.
///
/// # Errors
/// [`DooError::ValenceTwoVertex`] for an interior vertex with two edges;
/// [`DooError::TooLarge`] if the fine mesh would not fit `u32` indices.
pub(crate) fn doo_topology(coarse: &CornerMesh, with_twins: bool) -> Result<DooTopology, DooError> {
    let corners = coarse.corner_count();
    let faces = coarse.face_count();
    check_size("fine vertices", corners)?;

    // Coarse edges: each edge is named by its first corner (the one with the smaller index,
    // or the only one on the boundary), in increasing order: mesh-topo's edge numbering.
    // `quad_of_first[c]` = index of the F_E quad of interior edge with first corner c.
    let mut quad_of_first = vec![NONE; corners];
    let mut edge_parent = Vec::with_capacity(corners / 2);
    let mut edge_rank = 0u32;
    for (c, &t) in coarse.corner_twin.iter().enumerate() {
        let c = c as u32;
        if t == NONE || c < t {
            if t != NONE {
                quad_of_first[c as usize] = edge_parent.len() as u32;
                edge_parent.push(edge_rank);
            }
            edge_rank += 1;
        }
    }
    let quads = edge_parent.len();

    // F_V faces: one per interior vertex, corners counter-clockwise from its first
    // corner. The clockwise walk gives them in reverse after the first one.
    let mut vertex_parent = Vec::new();
    let mut fv_offsets: Vec<u32> = Vec::new();
    let mut fv_indices: Vec<u32> = Vec::with_capacity(corners);
    let mut scratch = Vec::new();
    for v in 0..coarse.vertex_count {
        let start = coarse.first_corner(v);
        if start == NONE {
            continue;
        }
        scratch.clear();
        if let Some(valence) = coarse.walk_clockwise(start, |c| scratch.push(c)) {
            if valence == 2 {
                return Err(DooError::ValenceTwoVertex { vertex: v });
            }
            vertex_parent.push(v as u32);
            fv_indices.push(start);
            fv_indices.extend(scratch.iter().rev());
            fv_offsets.push(fv_indices.len() as u32);
        }
    }

    let fine_corners = corners + 4 * quads + fv_indices.len();
    check_size("fine corners", fine_corners)?;
    check_size("fine faces", faces + quads + vertex_parent.len())?;

    let mut offsets = Vec::with_capacity(faces + quads + vertex_parent.len() + 1);
    offsets.extend_from_slice(&coarse.offsets);
    if offsets.is_empty() {
        offsets.push(0);
    }
    let quad_base = corners as u32;
    offsets.extend((1..=quads as u32).map(|q| quad_base + 4 * q));
    let fv_base = quad_base + 4 * quads as u32;
    offsets.extend(fv_offsets.iter().map(|&o| fv_base + o));

    let mut indices = Vec::with_capacity(fine_corners);
    indices.extend(0..corners as u32);
    for (c, &q) in quad_of_first.iter().enumerate() {
        if q != NONE {
            let c = c as u32;
            let t = coarse.corner_twin[c as usize];
            indices.extend_from_slice(&[c, coarse.next(t), t, coarse.next(c)]);
        }
    }
    indices.extend_from_slice(&fv_indices);

    let twins = with_twins.then(|| {
        let mut twins = vec![NONE; fine_corners];
        // F_V corner (fine corner index) of each coarse corner, NONE at boundary vertices.
        let mut fv_slot = vec![NONE; corners];
        for (k, &c) in fv_indices.iter().enumerate() {
            fv_slot[c as usize] = fv_base + k as u32;
        }
        let quad_of = |c: u32, t: u32| quad_of_first[c.min(t) as usize];
        // F_F corners: the edge c -> next(c) is shared with the quad of the coarse edge.
        for c in 0..corners as u32 {
            let t = coarse.corner_twin[c as usize];
            if t != NONE {
                let base = quad_base + 4 * quad_of(c, t);
                twins[c as usize] = if c < t { base + 3 } else { base + 1 };
            }
        }
        // F_E quads (c, next(t), t, next(c)).
        for (c, &q) in quad_of_first.iter().enumerate() {
            if q != NONE {
                let c = c as u32;
                let t = coarse.corner_twin[c as usize];
                let base = (quad_base + 4 * q) as usize;
                twins[base] = fv_slot[coarse.next(t) as usize];
                twins[base + 1] = t;
                twins[base + 2] = fv_slot[coarse.next(c) as usize];
                twins[base + 3] = c;
            }
        }
        // F_V corners: the edge c_i -> c_{i+1} is shared with the quad of the coarse edge
        // {prev(c_i), c_{i+1}}, where c_{i+1} = twin(prev(c_i)).
        for (k, &ci) in fv_indices.iter().enumerate() {
            let before = coarse.prev(ci);
            let after = coarse.corner_twin[before as usize];
            let base = quad_base + 4 * quad_of(before, after);
            twins[fv_base as usize + k] = if before < after { base + 2 } else { base };
        }
        twins
    });

    Ok(DooTopology { offsets, indices, ff_count: faces, edge_parent, vertex_parent, twins })
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
const PARALLEL_FACES: usize = 1 << 14;

/// New positions of one step: for every face, its F_F corners computed from the points
/// `point(c)` of its corners `c` (the coarse vertex positions, or per-corner candidates
/// in reconstruction). Output index = corner index. Bit-identical for any thread count.
pub(crate) fn face_points<P>(offsets: &[u32], maps: &FaceMaps, point: P) -> Vec<DVec3>
where
    P: Fn(usize) -> DVec3 + Sync,
{
    let corners = offsets.last().copied().unwrap_or(0) as usize;
    let mut out = vec![DVec3::ZERO; corners];
    let faces = offsets.len().saturating_sub(1);
    let work = |first: usize, end: usize, slice: &mut [DVec3]| {
        let base = offsets[first] as usize;
        let mut gathered: Vec<DVec3> = Vec::new();
        for f in first..end {
            let (b, e) = (offsets[f] as usize, offsets[f + 1] as usize);
            gathered.clear();
            gathered.extend((b..e).map(&point));
            maps.forward(&gathered, &mut slice[b - base..e - base]);
        }
    };
    if faces < PARALLEL_FACES {
        work(0, faces, &mut out);
    } else {
        let target = rayon::current_num_threads() * 8;
        face_chunks(offsets, &mut out, target).into_par_iter().for_each(|(first, end, slice)| work(first, end, slice));
    }
    out
}

/// Per-face expansion (inverse map) of the points `point(c)` at the corners of the
/// faces listed in `faces` (ranges given by `offsets`), written per corner.
pub(crate) fn expand_faces<P>(offsets: &[u32], maps: &FaceMaps, point: P) -> Vec<DVec3>
where
    P: Fn(usize) -> DVec3 + Sync,
{
    let corners = offsets.last().copied().unwrap_or(0) as usize;
    let mut out = vec![DVec3::ZERO; corners];
    let faces = offsets.len().saturating_sub(1);
    let work = |first: usize, end: usize, slice: &mut [DVec3]| {
        let base = offsets[first] as usize;
        let mut gathered: Vec<DVec3> = Vec::new();
        for f in first..end {
            let (b, e) = (offsets[f] as usize, offsets[f + 1] as usize);
            gathered.clear();
            gathered.extend((b..e).map(&point));
            maps.inverse(&gathered, &mut slice[b - base..e - base]);
        }
    };
    if faces < PARALLEL_FACES {
        work(0, faces, &mut out);
    } else {
        let target = rayon::current_num_threads() * 8;
        face_chunks(offsets, &mut out, target).into_par_iter().for_each(|(first, end, slice)| work(first, end, slice));
    }
    out
}
