//! Boundary rules: what a Doo-Sabin step puts at the boundary of an open mesh, and the
//! reversal of the Chaikin rule.
//!
//! # The two rules
//! - [`BoundaryRule::Shrink`] (the default, as in the reverse-Doo paper and in CGAL):
//!   boundary edges get no F_E quad and boundary vertices no F_V face, so an open mesh
//!   shrinks a little at every level and its limit surface does not reach the coarse
//!   boundary.
//! - [`BoundaryRule::Chaikin`]: every coarse boundary edge `u -> v` also gets its two
//!   Chaikin points `a = ¾u + ¼v` and `b = ¼u + ¾v` as fine vertices, a *boundary quad*
//!   `(ṽ_f(v), ṽ_f(u), a, b)` between them and the face's two corners at `u` and `v`, and
//!   every coarse boundary vertex gets a *boundary vertex face*: its Chaikin point on the
//!   outgoing boundary edge, its corners counter-clockwise, its Chaikin point on the
//!   incoming boundary edge (`k + 2` sides for a vertex of `k` faces). The fine boundary
//!   is then exactly the Chaikin refinement of the coarse boundary polygon, so the
//!   boundary of the limit surface is the quadratic B-spline curve of the boundary
//!   polygon of the coarsest mesh (for a flat open grid: of its outline). On a closed
//!   mesh both rules are the same.
//!
//! # Order (an extension of the canonical order of [`crate::forward`])
//! The fine mesh of the Shrink rule comes first, unchanged: fine vertex `c` is coarse
//! corner `c`, then the F_F, F_E and F_V faces. Then the Chaikin points, two per coarse
//! boundary edge (`a`, then `b`), the boundary edges in corner order (each is named by
//! its one corner); then the boundary quads in the same order; then the boundary vertex
//! faces in vertex order, each starting at its outgoing Chaikin point. So a Shrink step is
//! a prefix of the Chaikin step of the same mesh, vertices and faces both.
//!
//! # Reversal
//! The fine boundary vertices are the Chaikin points, and the faces that touch them are
//! the boundary ring (boundary quads and boundary vertex faces). Without the ring the
//! mesh is a Shrink step, reversed by [`crate::reverse`](mod@crate::reverse) as usual (its readings in turn,
//! best first, until one fits the ring); the ring is then checked face by face against
//! the boundary of the coarse mesh found. The coarse vertices are the means of their
//! F_F candidates alone, and each Chaikin point gets one detail: its offset from the
//! Chaikin point of the coarse boundary edge (`a - (¾u + ¼v)`, `b - (¼u + ¾v)`). The
//! choice keeps the interior reversal (and its automatic reading) exactly that of the
//! Shrink rule, makes a boundary detail the error of predicting the boundary by
//! Chaikin's rule (zero for a Chaikin step; dropped by compression, the boundary falls
//! back to the Chaikin points of the coarse boundary), and keeps the count: coarse
//! vertices plus details are as many 3-vectors as the fine mesh has vertices (two
//! Chaikin points and two details per boundary edge). Reconstruction adds each detail to
//! its Chaikin point: exact up to one rounding.
//!
//! A Chaikin step in the order above (as [`crate::subdivide`] and reconstruction write
//! it) is reversed without the general search: its ring is the last faces and its
//! Chaikin points the last vertices, so the half-edge arrays with the ring's faces
//! masked are those of a Shrink step in the canonical order, which the streaming path
//! of the canonical module reverses (reading, automatic choice and all, as the general
//! path would); the ring is then attached as on the general path. The coarse mesh it
//! gives is in the same order, so every level of a pyramid takes this path (the half-edge
//! arrays of a coarser level are built from its corner arrays). Any other order, or a
//! ring that does not fit, takes the general path.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use mesh_topo::HalfedgeMesh;

use crate::DooError;
use crate::canonical::{HalfedgeArrays, reverse_canonical_arrays};
use crate::corner::{CornerMesh, DooTopology, NONE, prev_of_corners};
use crate::reverse::{DooReversal, FineOrder, ReverseOptions, SeedChoice, Session};

/// What a Doo-Sabin step does at the boundary of an open mesh (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
pub enum BoundaryRule {
    /// No faces at boundary edges and vertices: the mesh shrinks level by level (the
    /// reverse-Doo paper's rule and CGAL's).
    #[default]
    Shrink,
    /// Boundary quads and boundary vertex faces through the Chaikin points of the
    /// boundary edges: the boundary converges to the quadratic B-spline curve of the
    /// boundary polygon.
    Chaikin,
}

impl std::fmt::Display for BoundaryRule {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            BoundaryRule::Shrink => "shrink",
            BoundaryRule::Chaikin => "chaikin",
        })
    }
}

/// The boundary ring of one Chaikin step: which coarse elements it comes from and its
/// faces (fine vertex numbers, Chaikin points from `corner_count` on).
#[derive(Debug, Clone, Default)]
pub(crate) struct Ring {
    /// The coarse boundary corners (one per boundary edge `vertex(c) -> vertex(next(c))`),
    /// in corner order.
    pub edges: Vec<u32>,
    /// The `mesh-topo` edge number of each boundary edge.
    pub edge_numbers: Vec<u32>,
    /// The coarse boundary vertices, in vertex order.
    pub vertices: Vec<u32>,
    /// Faces of the ring (boundary quads, then boundary vertex faces), as offsets from 0
    /// and corner vertices.
    pub offsets: Vec<u32>,
    pub indices: Vec<u32>,
}

impl Ring {
    /// The ring of the Chaikin step of `coarse` (module docs), or a
    /// [`DooError::TooLarge`] if its vertices would not fit `u32` indices.
    pub(crate) fn of(coarse: &CornerMesh) -> Result<Self, DooError> {
        let corners = coarse.corner_count();
        let twin = &coarse.corner_twin;
        let mut ring = Ring::default();
        let mut slot = vec![NONE; corners];
        let mut outgoing = vec![NONE; coarse.vertex_count];
        let mut edge_number = 0u32;
        for (c, &t) in twin.iter().enumerate() {
            if t == NONE {
                slot[c] = ring.edges.len() as u32;
                ring.edges.push(c as u32);
                ring.edge_numbers.push(edge_number);
                outgoing[coarse.corner_vertex[c] as usize] = c as u32;
            }
            if t == NONE || (c as u32) < t {
                edge_number += 1;
            }
        }
        let base = corners;
        if base + 2 * ring.edges.len() >= NONE as usize {
            return Err(DooError::TooLarge {
                what: "fine vertices",
                count: base + 2 * ring.edges.len(),
                max: NONE as usize - 1,
            });
        }
        let chaikin = |edge: u32, second: u32| (base as u32) + 2 * edge + second;
        ring.offsets.push(0);
        for (j, &c) in ring.edges.iter().enumerate() {
            ring.indices.extend_from_slice(&[coarse.next(c), c, chaikin(j as u32, 0), chaikin(j as u32, 1)]);
            ring.offsets.push(ring.indices.len() as u32);
        }
        let prev = prev_of_corners(&coarse.offsets);
        for (v, &out) in outgoing.iter().enumerate() {
            if out == NONE {
                continue;
            }
            ring.vertices.push(v as u32);
            ring.indices.push(chaikin(slot[out as usize], 0));
            // The corners of `v` counter-clockwise: from the outgoing boundary edge's
            // corner across each edge into `v`, up to the face whose edge into `v` is the
            // incoming boundary edge. A manifold vertex has one fan: at most one step per
            // corner.
            let mut corner = out;
            for _ in 0..corners {
                ring.indices.push(corner);
                let before = prev[corner as usize];
                match twin[before as usize] {
                    NONE => {
                        ring.indices.push(chaikin(slot[before as usize], 1));
                        break;
                    }
                    across => corner = across,
                }
            }
            ring.offsets.push(ring.indices.len() as u32);
        }
        Ok(ring)
    }

    /// Number of boundary quads.
    pub(crate) fn quad_count(&self) -> usize {
        self.edges.len()
    }

    /// Number of faces.
    pub(crate) fn face_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Appends the ring's faces after those of `offsets` / `indices` (a Shrink step's
    /// connectivity; `indices` may be `None` when only the face sizes are wanted).
    pub(crate) fn append_faces(&self, offsets: &mut Vec<u32>, indices: Option<&mut Vec<u32>>) {
        let base = *offsets.last().expect("internal: offsets start with 0");
        offsets.extend(self.offsets[1..].iter().map(|&o| base + o));
        if let Some(indices) = indices {
            indices.extend_from_slice(&self.indices);
        }
    }

    /// Appends the ring to a Shrink step's connectivity, with the parents of its faces for
    /// [`DooTopology::origin`].
    pub(crate) fn append_to(&self, topology: &mut DooTopology) {
        self.append_faces(&mut topology.offsets, Some(&mut topology.indices));
        topology.ring_edge_parent = self.edge_numbers.clone();
        topology.ring_vertex_parent = self.vertices.clone();
    }

    fn face(&self, k: usize) -> &[u32] {
        &self.indices[self.offsets[k] as usize..self.offsets[k + 1] as usize]
    }

    /// The Chaikin points of the boundary edges (`a`, `b` per edge, in edge order) from
    /// the coarse `positions`, each plus its detail when `details` are given.
    pub(crate) fn chaikin_points(
        &self,
        coarse: &CornerMesh,
        positions: &[DVec3],
        details: Option<&[DVec3]>,
    ) -> Vec<DVec3> {
        let mut points = Vec::with_capacity(2 * self.edges.len());
        for &c in &self.edges {
            let u = positions[coarse.corner_vertex[c as usize] as usize];
            let v = positions[coarse.corner_vertex[coarse.next(c) as usize] as usize];
            points.push(0.75 * u + 0.25 * v);
            points.push(0.25 * u + 0.75 * v);
        }
        if let Some(details) = details {
            for (p, d) in points.iter_mut().zip(details) {
                *p += *d;
            }
        }
        points
    }
}

/// Reverse Doo-Sabin of a mesh made with the Chaikin boundary rule (module docs), on
/// corner arrays.
pub(crate) fn reverse_chaikin_corner_mesh(
    fine: &CornerMesh,
    positions: &[DVec3],
    options: &ReverseOptions,
) -> Result<DooReversal, DooError> {
    let face_count = fine.face_count();
    for &s in &options.seeds {
        if s >= face_count {
            return Err(DooError::SeedOutOfRange { face: s, face_count });
        }
    }
    let faces_of = crate::corner::faces_of_corners(&fine.offsets);
    // The fine boundary vertices: the Chaikin points.
    let mut on_boundary = vec![false; fine.vertex_count];
    for (c, &t) in fine.corner_twin.iter().enumerate() {
        if t == NONE {
            on_boundary[fine.corner_vertex[c] as usize] = true;
        }
    }
    // The ring: the faces that touch a boundary vertex.
    let in_ring: Vec<bool> = fine
        .offsets
        .windows(2)
        .map(|w| fine.corner_vertex[w[0] as usize..w[1] as usize].iter().any(|&v| on_boundary[v as usize]))
        .collect();
    let ring_faces = in_ring.iter().filter(|&&r| r).count();
    for &s in &options.seeds {
        if in_ring[s] {
            return Err(DooError::NotDooConnectivity {
                face: s,
                reason: "the seed face touches the boundary: under the Chaikin boundary rule it is a boundary quad or \
                         a boundary vertex face, not an F_F face"
                    .into(),
            });
        }
    }
    // The mesh without the ring, its vertices and faces renumbered in order.
    let mut inner_vertex = vec![NONE; fine.vertex_count];
    let mut vertex_of_inner = Vec::new();
    let mut face_of_inner = Vec::new();
    let (mut inner_offsets, mut inner_indices) = (vec![0u32], Vec::new());
    for (f, w) in fine.offsets.windows(2).enumerate() {
        if in_ring[f] {
            continue;
        }
        face_of_inner.push(f as u32);
        for &v in &fine.corner_vertex[w[0] as usize..w[1] as usize] {
            if inner_vertex[v as usize] == NONE {
                inner_vertex[v as usize] = vertex_of_inner.len() as u32;
                vertex_of_inner.push(v);
            }
        }
        inner_indices
            .extend(fine.corner_vertex[w[0] as usize..w[1] as usize].iter().map(|&v| inner_vertex[v as usize]));
        inner_offsets.push(inner_indices.len() as u32);
    }
    if ring_faces == 0 {
        // No boundary: both rules are the same.
        let mut reversal = crate::reverse::reverse_corner_mesh(fine, positions, options)?;
        reversal.boundary = BoundaryRule::Chaikin;
        return Ok(reversal);
    }
    if face_of_inner.is_empty() {
        return Err(DooError::NotDooConnectivity {
            face: 0,
            reason: "every face touches the boundary: under the Chaikin boundary rule a Doo-Sabin step has F_F faces \
                     away from it"
                .into(),
        });
    }
    // Every vertex is a Chaikin point or on a face away from the boundary.
    if let Some(v) = (0..fine.vertex_count).find(|&v| !on_boundary[v] && inner_vertex[v] == NONE) {
        let face = match fine.first_corner(v) {
            NONE => return Err(DooError::IsolatedVertex { vertex: v }),
            c => faces_of[c as usize] as usize,
        };
        return Err(DooError::NotDooConnectivity {
            face,
            reason: format!(
                "vertex {v} is neither on the boundary nor on a face away from it: under the Chaikin boundary rule \
                 every fine vertex is a Chaikin point or a corner of an F_F face"
            ),
        });
    }
    let inner_positions: Vec<DVec3> = vertex_of_inner.iter().map(|&v| positions[v as usize]).collect();
    let to_input = |error: DooError| map_error(error, &face_of_inner, &vertex_of_inner);
    let inner_corners =
        CornerMesh::from_faces(inner_offsets, inner_indices, inner_positions.len()).map_err(|reason| {
            DooError::NotDooConnectivity {
                face: face_of_inner[0] as usize,
                reason: format!("without the faces that touch the boundary the mesh is not a manifold mesh: {reason}"),
            }
        })?;
    let inner_options = ReverseOptions {
        rule: options.rule,
        seeds: options
            .seeds
            .iter()
            .map(|&s| {
                face_of_inner
                    .binary_search(&(s as u32))
                    .expect("internal: a seed off the ring is a face of the inner mesh")
            })
            .collect(),
        boundary: BoundaryRule::Shrink,
    };
    let mut session = Session::new(&inner_corners, &inner_positions, &inner_options).map_err(to_input)?;
    let mut first_error = None;
    for picks in session.alternatives() {
        let attempt = session.build(picks).map_err(to_input).and_then(|reversal| {
            let input = Input {
                fine: &CornerFaces { mesh: fine, faces_of: &faces_of },
                positions,
                on_boundary: &on_boundary,
                in_ring: &in_ring,
                ring_faces,
            };
            attach_ring(reversal, &input, &face_of_inner, &vertex_of_inner)
        });
        match attempt {
            Ok(reversal) => return Ok(reversal),
            Err(error) => {
                first_error.get_or_insert(error);
            }
        }
    }
    Err(first_error.expect("internal: there is always a first reading"))
}

/// The input of [`attach_ring`].
struct Input<'a, F: FaceCorners> {
    fine: &'a F,
    positions: &'a [DVec3],
    on_boundary: &'a [bool],
    in_ring: &'a [bool],
    ring_faces: usize,
}

/// The faces of the input as [`attach_ring`] reads them: a few corners near the
/// boundary. From corner arrays, or straight from the half-edge arrays, so that the
/// streaming path builds no corner arrays of the whole mesh for them.
trait FaceCorners {
    fn face_count(&self) -> usize;
    fn vertex_count(&self) -> usize;
    /// Corner `j` of face `f`, `j` below its size.
    fn corner(&self, f: usize, j: usize) -> u32;
    /// The face of corner `c` and the place of `c` in it.
    fn face_and_place(&self, c: u32) -> (usize, u32);
    /// The number of corners of face `f`.
    fn size(&self, f: usize) -> usize;
    /// The corner across the edge from corner `c` to the next one ([`NONE`] on the
    /// boundary).
    fn twin(&self, c: u32) -> u32;
    fn next(&self, c: u32) -> u32;
    fn vertex(&self, c: u32) -> u32;
    /// A face at vertex `v`, if any (for errors).
    fn face_at(&self, v: usize) -> Option<usize>;
}

/// Corner arrays and the face of each corner.
struct CornerFaces<'a> {
    mesh: &'a CornerMesh,
    faces_of: &'a [u32],
}

impl FaceCorners for CornerFaces<'_> {
    fn face_count(&self) -> usize {
        self.mesh.face_count()
    }

    fn vertex_count(&self) -> usize {
        self.mesh.vertex_count
    }

    fn corner(&self, f: usize, j: usize) -> u32 {
        self.mesh.offsets[f] + j as u32
    }

    fn face_and_place(&self, c: u32) -> (usize, u32) {
        let f = self.faces_of[c as usize] as usize;
        (f, c - self.mesh.offsets[f])
    }

    fn size(&self, f: usize) -> usize {
        (self.mesh.offsets[f + 1] - self.mesh.offsets[f]) as usize
    }

    fn twin(&self, c: u32) -> u32 {
        self.mesh.corner_twin[c as usize]
    }

    fn next(&self, c: u32) -> u32 {
        self.mesh.next(c)
    }

    fn vertex(&self, c: u32) -> u32 {
        self.mesh.corner_vertex[c as usize]
    }

    fn face_at(&self, v: usize) -> Option<usize> {
        match self.mesh.first_corner(v) {
            NONE => None,
            c => Some(self.faces_of[c as usize] as usize),
        }
    }
}

/// Half-edge arrays read as corners: corner `h` is the corner that half-edge `h` leaves
/// (the numbering of [`CornerMesh::from_halfedge`] aside, the same corners, next
/// corners and twins).
struct HalfedgeFaces<'a> {
    arrays: HalfedgeArrays<'a>,
}

impl FaceCorners for HalfedgeFaces<'_> {
    fn face_count(&self) -> usize {
        self.arrays.faces
    }

    fn vertex_count(&self) -> usize {
        self.arrays.vertices
    }

    fn corner(&self, f: usize, j: usize) -> u32 {
        let mut h = self.arrays.face_halfedge[f];
        for _ in 0..j {
            h = self.next(h);
        }
        h
    }

    fn face_and_place(&self, c: u32) -> (usize, u32) {
        let f = self.arrays.face_of[c as usize] as usize;
        let (mut h, mut place) = (self.arrays.face_halfedge[f], 0);
        while h != c {
            h = self.next(h);
            place += 1;
        }
        (f, place)
    }

    fn size(&self, f: usize) -> usize {
        let first = self.arrays.face_halfedge[f];
        let (mut h, mut size) = (self.next(first), 1);
        while h != first {
            h = self.next(h);
            size += 1;
        }
        size
    }

    fn twin(&self, c: u32) -> u32 {
        if self.arrays.face_of[(c ^ 1) as usize] == NONE { NONE } else { c ^ 1 }
    }

    fn next(&self, c: u32) -> u32 {
        self.arrays.next[c as usize]
    }

    fn vertex(&self, c: u32) -> u32 {
        self.arrays.to[(c ^ 1) as usize]
    }

    fn face_at(&self, v: usize) -> Option<usize> {
        let HalfedgeArrays { to, face_of, .. } = self.arrays;
        (0..to.len()).find(|&h| to[h ^ 1] as usize == v && face_of[h] != NONE).map(|h| face_of[h] as usize)
    }
}

/// [`reverse_chaikin_corner_mesh`] on a Chaikin step in the canonical order (as
/// [`crate::subdivide`] writes it, see the module docs), without the general search:
/// its faces that touch the boundary (the ring) are its last faces and its Chaikin
/// points its last vertices, so the rest is a Shrink step in the canonical order, which
/// [`crate::canonical`] reverses from the half-edge arrays with the ring's faces masked
/// ([`HalfedgeArrays::prefix`]); the ring is then attached as on the general path.
/// `None` when anything differs (the general path then decides and names what is
/// wrong), when a position is not finite, or when the ring does not fit the reading
/// found (the general path then tries the other readings). Otherwise the result is the
/// general path's, bit for bit: its mesh without the ring is the same mesh, whose first
/// reading is the one found here, and that reading fits the ring.
pub(crate) fn reverse_chaikin_canonical(fine: &HalfedgeMesh, options: &ReverseOptions) -> Option<DooReversal> {
    reverse_chaikin_arrays(&HalfedgeArrays::of(fine), options)
}

/// [`reverse_chaikin_canonical`] on the half-edge arrays of a mesh (a half-edge mesh, or
/// the corner arrays of a pyramid's coarser level, see
/// [`crate::canonical::CornerHalfedges`]).
pub(crate) fn reverse_chaikin_arrays(fine: &HalfedgeArrays<'_>, options: &ReverseOptions) -> Option<DooReversal> {
    let HalfedgeArrays { to, face_of, vertices, faces, positions, .. } = *fine;
    // The Chaikin points: the fine boundary vertices (the targets of boundary half-edges).
    let mut on_boundary = vec![false; vertices];
    for (&v, &f) in to.iter().zip(face_of) {
        if f == NONE {
            on_boundary[v as usize] = true;
        }
    }
    let chaikin_points = on_boundary.iter().filter(|&&b| b).count();
    if chaikin_points == 0 {
        // Closed: both rules are the same.
        let mut reversal = reverse_canonical_arrays(fine, options)?;
        reversal.boundary = BoundaryRule::Chaikin;
        return Some(reversal);
    }
    let inner_vertices = vertices - chaikin_points;
    let chaikin_positions = &positions[inner_vertices..];
    if on_boundary[..inner_vertices].contains(&true) || !chaikin_positions.iter().all(|p| p.is_finite()) {
        return None;
    }
    // The ring: the faces with a Chaikin point, which must be the last ones.
    let mut in_ring = vec![false; faces];
    for (&v, &f) in to.iter().zip(face_of) {
        if f != NONE && v as usize >= inner_vertices {
            in_ring[f as usize] = true;
        }
    }
    let inner_faces = in_ring.iter().position(|&r| r)?;
    if inner_faces == 0 || !in_ring[inner_faces..].iter().all(|&r| r) || options.seeds.iter().any(|&s| s >= inner_faces)
    {
        return None;
    }
    // The half-edges of the kept faces and their twins, the first ones in the canonical
    // layout (the ring's own edges are numbered after them), with the ring masked: the
    // whole array masked, then cut after the last edge with a kept face (a short scan
    // back over the ring's own edges).
    let mut masked: Vec<u32> = face_of.iter().map(|&f| if (f as usize) < inner_faces { f } else { NONE }).collect();
    let halfedges = (masked.iter().rposition(|&f| f != NONE)? | 1) + 1;
    masked.truncate(halfedges);
    let arrays = fine.prefix(inner_vertices, inner_faces, &masked);
    let inner_options = ReverseOptions { boundary: BoundaryRule::Shrink, ..options.clone() };
    let reversal = reverse_canonical_arrays(&arrays, &inner_options)?;
    drop(masked);
    let input = Input {
        fine: &HalfedgeFaces { arrays: *fine },
        positions,
        on_boundary: &on_boundary,
        in_ring: &in_ring,
        ring_faces: faces - inner_faces,
    };
    let face_of_inner: Vec<u32> = (0..inner_faces as u32).collect();
    let vertex_of_inner: Vec<u32> = (0..inner_vertices as u32).collect();
    attach_ring(reversal, &input, &face_of_inner, &vertex_of_inner).ok()
}

/// Error numbers of the mesh without the ring turned into those of the input.
fn map_error(error: DooError, face_of_inner: &[u32], vertex_of_inner: &[u32]) -> DooError {
    let face = |f: usize| face_of_inner.get(f).map_or(f, |&g| g as usize);
    let vertex = |v: usize| vertex_of_inner.get(v).map_or(v, |&u| u as usize);
    match error {
        DooError::NotDooConnectivity { face: f, reason } => DooError::NotDooConnectivity {
            face: face(f),
            reason: format!("{reason} (in the mesh without the faces that touch the boundary)"),
        },
        DooError::IsolatedVertex { vertex: v } => DooError::IsolatedVertex { vertex: vertex(v) },
        DooError::NonFinite { vertex: v, value } => DooError::NonFinite { vertex: vertex(v), value },
        DooError::DuplicateSeed { first, second } => {
            DooError::DuplicateSeed { first: face(first), second: face(second) }
        }
        other => other,
    }
}

/// Matches the ring of the input against the ring of the coarse mesh of `reversal` (a
/// reversal of the mesh without its ring), and makes the reversal of the whole input:
/// its numbering, and the details of the Chaikin points.
fn attach_ring<F: FaceCorners>(
    mut reversal: DooReversal,
    input: &Input<'_, F>,
    face_of_inner: &[u32],
    vertex_of_inner: &[u32],
) -> Result<DooReversal, DooError> {
    let Input { fine, positions, on_boundary, in_ring, ring_faces } = *input;
    let coarse = &reversal.coarse;
    let ring = Ring::of(coarse)?;
    let canonical_corners = coarse.corner_count();
    let order = &reversal.order;
    // Input vertex of each canonical fine vertex (the Chaikin points found below).
    let mut vertices: Vec<u32> = (0..canonical_corners as u32)
        .map(|c| {
            let inner = if order.vertices.is_empty() { c } else { order.vertices[c as usize] };
            vertex_of_inner[inner as usize]
        })
        .collect();
    vertices.resize(canonical_corners + 2 * ring.quad_count(), NONE);
    let inner_faces = face_of_inner.len();
    let mut faces: Vec<u32> = (0..inner_faces as u32)
        .map(|k| face_of_inner[if order.faces.is_empty() { k } else { order.faces[k as usize] } as usize])
        .collect();
    let mut rotations: Vec<u32> =
        if order.rotations.is_empty() { vec![0; inner_faces] } else { order.rotations.clone() };
    // Input corner of a coarse corner (the canonical F_F corner), through its F_F face.
    let input_corner = |c: u32| {
        let k = coarse.offsets.partition_point(|&b| b <= c) - 1;
        let (b, e) = (coarse.offsets[k], coarse.offsets[k + 1]);
        let (m, j) = ((e - b) as usize, (c - b) as usize);
        let r = rotations[k] as usize;
        // Corner i of the input face is canonical corner (i + r) mod m.
        fine.corner(faces[k] as usize, (j + m - r) % m)
    };
    let edge_corners: Vec<u32> = ring.edges.iter().map(|&c| input_corner(c)).collect();
    let mut claimed_face = vec![false; fine.face_count()];
    let mut claimed_vertex = vec![false; fine.vertex_count()];
    let broken = |face: usize, reason: String| DooError::NotDooConnectivity {
        face,
        reason: format!("{reason} (Chaikin boundary rule)"),
    };
    // Boundary quads: across each coarse boundary edge's F_F edge.
    let mut quad_corner_at_u = vec![NONE; ring.quad_count()];
    for (j, &ic) in edge_corners.iter().enumerate() {
        let (ff_face, _) = fine.face_and_place(ic);
        let t = fine.twin(ic);
        if t == NONE {
            return Err(broken(ff_face, "an F_F face at the coarse boundary has an edge on the fine boundary".into()));
        }
        let (h, t_place) = fine.face_and_place(t);
        if fine.size(h) != 4 {
            return Err(broken(h, format!("next to F_F face {ff_face} at the coarse boundary: not a quad")));
        }
        let [a_corner, b_corner] = [fine.next(fine.next(t)), fine.next(fine.next(fine.next(t)))];
        for v in [fine.vertex(a_corner), fine.vertex(b_corner)] {
            if !on_boundary[v as usize] || std::mem::replace(&mut claimed_vertex[v as usize], true) {
                return Err(broken(h, format!("vertex {v} is not a Chaikin point of this boundary quad alone")));
            }
        }
        if std::mem::replace(&mut claimed_face[h], true) {
            return Err(broken(h, "the face is the boundary quad of two coarse edges".into()));
        }
        vertices[canonical_corners + 2 * j] = fine.vertex(a_corner);
        vertices[canonical_corners + 2 * j + 1] = fine.vertex(b_corner);
        quad_corner_at_u[j] = fine.next(t);
        faces.push(h as u32);
        rotations.push((4 - t_place) % 4);
    }
    // Boundary vertex faces: across the edge from the outgoing Chaikin point.
    let quads = ring.quad_count();
    let mut slot = vec![NONE; canonical_corners];
    for (j, &c) in ring.edges.iter().enumerate() {
        slot[c as usize] = j as u32;
    }
    for k in quads..ring.face_count() {
        let expected = ring.face(k);
        let out_edge = slot[expected[1] as usize] as usize;
        let at_u = quad_corner_at_u[out_edge];
        let (quad_face, _) = fine.face_and_place(at_u);
        let start = fine.twin(at_u);
        if start == NONE {
            return Err(broken(quad_face, "a boundary quad has its side edge on the fine boundary".into()));
        }
        let (h, start_place) = fine.face_and_place(start);
        let matches = fine.size(h) == expected.len() && {
            let mut corner = start;
            expected.iter().all(|&w| {
                let same = fine.vertex(corner) == vertices[w as usize];
                corner = fine.next(corner);
                same
            })
        };
        if !matches {
            return Err(broken(
                h,
                format!(
                    "not the boundary vertex face of coarse vertex {} ({} sides expected)",
                    ring.vertices[k - quads],
                    expected.len()
                ),
            ));
        }
        if std::mem::replace(&mut claimed_face[h], true) {
            return Err(broken(h, "the face is the boundary face of two coarse elements".into()));
        }
        faces.push(h as u32);
        let m = expected.len() as u32;
        rotations.push((m - start_place) % m);
    }
    if ring.face_count() != ring_faces || 2 * quads != on_boundary.iter().filter(|&&b| b).count() {
        let face = (0..fine.face_count()).find(|&f| !claimed_face[f] && in_ring[f]);
        let vertex = (0..fine.vertex_count()).find(|&v| on_boundary[v] && !claimed_vertex[v]);
        let face = face.or_else(|| vertex.and_then(|v| fine.face_at(v))).unwrap_or(0);
        return Err(broken(
            face,
            format!(
                "the faces that touch the boundary are not the boundary quads and vertex faces of the coarse boundary \
                 ({} faces and {} boundary vertices; the coarse boundary needs {} faces and {} Chaikin points)",
                ring_faces,
                on_boundary.iter().filter(|&&b| b).count(),
                ring.face_count(),
                2 * quads
            ),
        ));
    }
    // Details of the Chaikin points: their offsets from the coarse boundary's.
    let predicted = ring.chaikin_points(coarse, &reversal.coarse_positions, None);
    let chaikin_vertices = &vertices[canonical_corners..];
    reversal.details.extend(predicted.iter().zip(chaikin_vertices).map(|(p, &v)| positions[v as usize] - *p));
    let identity = |values: &[u32]| values.iter().enumerate().all(|(i, &x)| x == i as u32);
    reversal.order = FineOrder {
        vertices: if identity(&vertices) { Vec::new() } else { vertices },
        faces: if identity(&faces) { Vec::new() } else { faces },
        rotations: if rotations.iter().all(|&r| r == 0) { Vec::new() } else { rotations },
    };
    for choice in &mut reversal.choices {
        map_choice(choice, face_of_inner);
    }
    reversal.boundary = BoundaryRule::Chaikin;
    // What the inner part measured leaves out the ring's positions.
    reversal.fine_unit_scale = None;
    Ok(reversal)
}

/// Seed faces of the mesh without the ring as faces of the input.
fn map_choice(choice: &mut SeedChoice, face_of_inner: &[u32]) {
    let face = |f: usize| face_of_inner.get(f).map_or(f, |&g| g as usize);
    choice.seed_face = face(choice.seed_face);
    for trial in &mut choice.trials {
        trial.seed_face = face(trial.seed_face);
    }
}

/// One level of reconstruction under the Chaikin rule: the Shrink step's canonical mesh
/// and positions from the candidates, then the ring and the Chaikin points plus their
/// details, in canonical order (the caller applies the fine order).
pub(crate) fn append_ring_level(
    coarse: &CornerMesh,
    coarse_positions: &[DVec3],
    chaikin_details: &[DVec3],
    offsets: &mut Vec<u32>,
    indices: &mut Vec<u32>,
    positions: &mut Vec<DVec3>,
) -> Result<(), DooError> {
    let ring = Ring::of(coarse)?;
    if chaikin_details.len() != 2 * ring.quad_count() {
        return Err(DooError::InvalidPyramid(format!(
            "{} boundary details for {} Chaikin points",
            chaikin_details.len(),
            2 * ring.quad_count()
        )));
    }
    positions.extend(ring.chaikin_points(coarse, coarse_positions, Some(chaikin_details)));
    ring.append_faces(offsets, Some(indices));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DooOptions, FaceRule, subdivide_soup};
    use mesh_topo::PolygonSoup;
    use mesh_topo::shapes::{self, CellKind};
    use mesh_topo::testing::scramble;

    /// One Chaikin step of `soup` (canonical order), every position moved if `moved`.
    fn chaikin_step(soup: &PolygonSoup, rule: FaceRule, moved: bool) -> HalfedgeMesh {
        let options = DooOptions::new(rule, 1).with_boundary(BoundaryRule::Chaikin);
        let mut fine = subdivide_soup(soup, &options).unwrap().to_mesh().unwrap();
        if moved {
            for (i, p) in fine.positions_mut().iter_mut().enumerate() {
                *p += 1e-3 * DVec3::new((i as f64 * 0.7).sin(), (i as f64 * 1.3).cos(), (i as f64 * 2.1).sin());
            }
        }
        fine
    }

    fn without(soup: &PolygonSoup, removed: &[usize]) -> PolygonSoup {
        let faces: Vec<Vec<u32>> =
            (0..soup.face_count()).filter(|f| !removed.contains(f)).map(|f| soup.face(f).to_vec()).collect();
        PolygonSoup::from_faces(soup.positions.clone(), faces)
    }

    fn general(fine: &HalfedgeMesh, options: &ReverseOptions) -> DooReversal {
        reverse_chaikin_corner_mesh(&CornerMesh::from_halfedge(fine), fine.positions(), options).unwrap()
    }

    #[test]
    fn a_canonical_chaikin_step_gives_the_general_result() {
        let soups = [
            shapes::grid(4, 3, CellKind::Quads).unwrap(),
            shapes::grid(5, 4, CellKind::Mixed).unwrap(),
            shapes::grid(3, 3, CellKind::Triangles).unwrap(),
            without(&shapes::cube(), &[2]),
            without(&shapes::icosahedron(), &[0]),
            without(&shapes::torus(6, 4, CellKind::Mixed).unwrap(), &[3]),
            // Closed: both rules are the same.
            shapes::torus(5, 4, CellKind::Triangles).unwrap(),
        ];
        for soup in &soups {
            for rule in [FaceRule::DooSabin, FaceRule::Simple, FaceRule::CENTROID_HALF] {
                for moved in [false, true] {
                    let fine = chaikin_step(soup, rule, moved);
                    let auto = ReverseOptions::auto(rule).with_boundary(BoundaryRule::Chaikin);
                    let seeded = |seed| ReverseOptions::with_seed(rule, seed).with_boundary(BoundaryRule::Chaikin);
                    for options in [auto, seeded(0), seeded(soup.face_count() - 1)] {
                        let fast = reverse_chaikin_canonical(&fine, &options).expect("a canonical Chaikin step");
                        assert_eq!(fast, general(&fine, &options), "{options:?}");
                        assert_eq!(fast.boundary, BoundaryRule::Chaikin);
                    }
                }
            }
        }
    }

    #[test]
    fn other_orders_broken_rings_and_ring_seeds_are_left_to_the_general_path() {
        let soup = shapes::grid(4, 3, CellKind::Mixed).unwrap();
        let fine = chaikin_step(&soup, FaceRule::DooSabin, true);
        let auto = ReverseOptions::auto(FaceRule::DooSabin).with_boundary(BoundaryRule::Chaikin);
        // Renumbered: the general path reverses it.
        let scrambled = HalfedgeMesh::from_soup(&scramble(fine.to_soup(), 3, 0.0)).unwrap();
        assert!(reverse_chaikin_canonical(&scrambled, &auto).is_none());
        assert!(crate::reverse(&scrambled, &auto).is_ok());
        // A seed on the ring: the general path names the error.
        let ring_face = fine.face_count() - 1;
        let on_ring = ReverseOptions::with_seed(FaceRule::DooSabin, ring_face).with_boundary(BoundaryRule::Chaikin);
        assert!(reverse_chaikin_canonical(&fine, &on_ring).is_none());
        assert!(crate::reverse(&fine, &on_ring).is_err());
        // A ring face removed: not a Chaikin step.
        let broken = HalfedgeMesh::from_soup(&without(&fine.to_soup(), &[ring_face])).unwrap();
        assert!(reverse_chaikin_canonical(&broken, &auto).is_none());
        assert!(crate::reverse(&broken, &auto).is_err());
        // A Chaikin point that is not finite.
        let mut infinite = fine.clone();
        let last = infinite.vertex_count() - 1;
        infinite.positions_mut()[last] = DVec3::new(f64::NAN, 0.0, 0.0);
        assert!(reverse_chaikin_canonical(&infinite, &auto).is_none());
        assert!(matches!(crate::reverse(&infinite, &auto), Err(DooError::NonFinite { .. })));
    }
}
