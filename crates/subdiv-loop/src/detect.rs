//! Recognising Loop (1-to-4) subdivision connectivity in a plain triangle mesh.
//!
//! One Loop step turns every coarse vertex into a *vertex point* (an **even** fine
//! vertex) and every coarse edge into an *edge point* (an **odd** fine vertex), and every
//! coarse triangle `(a, b, c)` into three *corner faces* `(a, ab, ca)`, `(b, bc, ab)`,
//! `(c, ca, bc)` and one *inner face* `(ab, bc, ca)`. [`detect`] recovers all of this from
//! the fine mesh alone (ALGORITHMS.md §7.4, after Taubin 2001, "Detecting and
//! reconstructing subdivision connectivity"):
//!
//! 1. **Seed.** Every edge point has valence 6 (inside) or 4 (on the boundary), so a
//!    vertex of any other valence must be a vertex point: the lowest-numbered such vertex
//!    of each connected component is the seed. A component where every valence is
//!    regular (a torus, say) admits several labelings; then the lowest-numbered vertex
//!    and, failing that, each of its neighbours is tried in turn (one of them is a vertex
//!    point of any valid labeling, so this finds one if any exists). Seeds given by the
//!    caller ([`DetectOptions::seed_vertices`]) replace the search in their components.
//! 2. **Propagation** (breadth-first). The neighbours of a vertex point are edge points;
//!    from vertex point `v` through edge point `m`, the next vertex point is the
//!    neighbour of `m` straight across from `v` (opposite in `m`'s 6-ring inside, the
//!    other boundary neighbour on the boundary). Each vertex is labelled once, so this
//!    is linear; the labeling from a seed is forced, hence unique.
//! 3. **Validation.** Every edge point has exactly two vertex-point neighbours, on its
//!    line (its coarse edge); two edge points around a vertex point must not lead to the
//!    same vertex point (a doubled coarse edge); every face must have one vertex point
//!    (a corner face) or none (an inner face); the three faces across an inner face's
//!    edges must be corner faces, so that every face belongs to exactly one group of
//!    four; the three vertex points of a group must be distinct, and each edge point of
//!    the group must lie on the line between the two vertex points of its coarse edge.
//!    A mesh passing these checks is exactly the Loop refinement of the coarse mesh
//!    found, up to numbering (a property test rebuilds the input from the result).
//!
//! Any failure is a [`LoopError::NotLoopConnectivity`] naming the fine vertex or face
//! where the structure breaks.
//!
//! # Numbering
//! Coarse vertex `i` is the `i`-th vertex point in fine order (isolated fine vertices are
//! vertex points of isolated coarse vertices, so that reversal loses nothing). Coarse
//! faces are numbered in the order their first fine face appears, and each starts at the
//! corner whose corner face comes first. Coarse edges are numbered as `mesh_topo` numbers
//! the edges of the coarse mesh. With this choice a fine mesh in the *canonical order*
//! (vertex points first, in coarse order, then one edge point per coarse edge in edge
//! order; coarse face `f = (a, b, c)` refined into faces `4f .. 4f + 4` =
//! `(a, ab, ca)`, `(b, bc, ab)`, `(c, ca, bc)`, `(ab, bc, ca)`, ALGORITHMS.md §6.1) is
//! recognised with the identity [`FineOrder`], so a pyramid of such a mesh stores no
//! connectivity at all. Any other numbering is recorded as a [`FineOrder`].

use std::fmt;
use std::ops::Range;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use glam::DVec3;
use mesh_topo::{HalfedgeMesh, PolygonSoup};

use crate::LoopError;
use crate::corner_table::{Corner, CornerTable, NONE, VertexStar, next, prev};
use crate::forward::LoopOptions;
use crate::forward::buffer::{Output, Slots, prefetch, worth_prefetching};
use crate::forward::kernel;
use crate::forward::topology::MeshTriangles;
use crate::reverse::{CanonicalLevel, reverse_canonical};

/// A fine-mesh element named by an error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum FineElement {
    /// A vertex, by index.
    Vertex(u32),
    /// A face, by index.
    Face(u32),
}

impl fmt::Display for FineElement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            FineElement::Vertex(v) => write!(f, "vertex {v}"),
            FineElement::Face(face) => write!(f, "face {face}"),
        }
    }
}

/// Options of [`detect`].
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct DetectOptions {
    /// Vertices known to be vertex points (even), typically one per connected component.
    /// The component of each is labelled from it, without search; the other components
    /// are searched as usual. Needed only to pick one of the several valid labelings of a
    /// component whose valences are all regular. Seeds that share a component must be
    /// vertex points of one labeling ([`LoopError::SeedConflict`] otherwise).
    pub seed_vertices: Vec<u32>,
}

/// How a fine mesh is numbered relative to the canonical refinement of its coarse mesh
/// (see the [module docs](self)).
///
/// Canonical fine vertex `i` (coarse vertex `i` for `i < V`, else the edge point of
/// coarse edge `i - V`) is fine vertex `vertex_of_canonical[i]`. Canonical fine face `K`
/// is fine face `face_of_canonical[K] / 3`, whose corner `j` is corner
/// `(j + face_of_canonical[K] % 3) % 3` of the canonical face.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FineOrder {
    /// Fine vertex of each canonical fine vertex (a permutation).
    pub vertex_of_canonical: Vec<u32>,
    /// `3 * face + rotation` of each canonical fine face (faces form a permutation).
    pub face_of_canonical: Vec<u32>,
}

impl FineOrder {
    /// Checks that this is an order for a fine mesh with `vertices` vertices and `faces`
    /// faces: two permutations, rotations below 3.
    ///
    /// ```
    /// use subdiv_loop::detect::FineOrder;
    ///
    /// // One triangle split 1-to-4 (6 vertices, 4 faces), the inner face rotated by one corner.
    /// let mut order = FineOrder {
    ///     vertex_of_canonical: (0..6).collect(),
    ///     face_of_canonical: vec![0, 3, 6, 10],
    /// };
    /// assert_eq!(order.check(6, 4), Ok(()));
    /// assert!(order.check(7, 4).is_err()); // one vertex too many
    /// order.face_of_canonical[3] = 6; // face 2 twice, face 3 never
    /// assert!(order.check(6, 4).unwrap_err().contains("repeated"));
    /// ```
    ///
    /// # Errors
    /// A sentence saying what is wrong.
    pub fn check(&self, vertices: usize, faces: usize) -> Result<(), String> {
        if self.vertex_of_canonical.len() != vertices {
            return Err(format!("vertex order has {} entries for {vertices} vertices", self.vertex_of_canonical.len()));
        }
        if self.face_of_canonical.len() != faces {
            return Err(format!("face order has {} entries for {faces} faces", self.face_of_canonical.len()));
        }
        let mut seen = vec![false; vertices];
        for (i, &v) in self.vertex_of_canonical.iter().enumerate() {
            if v as usize >= vertices || std::mem::replace(&mut seen[v as usize], true) {
                return Err(format!("vertex order entry {i} ({v}) is out of range or repeated"));
            }
        }
        let mut seen = vec![false; faces];
        for (k, &code) in self.face_of_canonical.iter().enumerate() {
            let face = (code / 3) as usize;
            if face >= faces || std::mem::replace(&mut seen[face], true) {
                return Err(format!("face order entry {k} (face {face}) is out of range or repeated"));
            }
        }
        Ok(())
    }
}

/// The Loop structure of a fine mesh: which fine vertices are vertex points and edge
/// points, and the coarse mesh they came from. Made by [`detect`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LoopConnectivity {
    pub(crate) coarsening: Coarsening,
}

/// The coarse connectivity plus the map from coarse elements to fine ones.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Coarsening {
    pub(crate) coarse: CornerTable,
    /// Fine vertex of each coarse vertex.
    pub(crate) vertex_point: Vec<u32>,
    /// Fine vertex of each coarse edge.
    pub(crate) edge_point: Vec<u32>,
    /// See [`FineOrder::face_of_canonical`]; empty when `canonical` (the identity).
    pub(crate) face_of_canonical: Vec<u32>,
    /// True if the fine mesh is in the canonical order.
    canonical: bool,
}

impl Coarsening {
    /// A coarsening whose fine mesh may be in any order (checked here, in one pass).
    fn new(coarse: CornerTable, vertex_point: Vec<u32>, edge_point: Vec<u32>, face_of_canonical: Vec<u32>) -> Self {
        let nv = vertex_point.len() as u32;
        let canonical = vertex_point.iter().enumerate().all(|(i, &v)| v == i as u32)
            && edge_point.iter().enumerate().all(|(e, &v)| v == nv + e as u32)
            && face_of_canonical.iter().enumerate().all(|(k, &code)| code == 3 * k as u32);
        if canonical {
            Self::canonical(coarse)
        } else {
            Self { coarse, vertex_point, edge_point, face_of_canonical, canonical }
        }
    }

    /// The coarsening of a fine mesh in the canonical order.
    pub(crate) fn canonical(coarse: CornerTable) -> Self {
        let (nv, ne) = (coarse.vertex_count() as u32, coarse.edge_count() as u32);
        Self {
            coarse,
            vertex_point: (0..nv).collect(),
            edge_point: (nv..nv + ne).collect(),
            face_of_canonical: Vec::new(),
            canonical: true,
        }
    }

    /// True if the fine mesh is in canonical order.
    pub(crate) fn is_canonical(&self) -> bool {
        self.canonical
    }

    /// The fine order, `None` when canonical.
    pub(crate) fn fine_order(&self) -> Option<FineOrder> {
        (!self.is_canonical()).then(|| FineOrder {
            vertex_of_canonical: self.vertex_point.iter().chain(&self.edge_point).copied().collect(),
            face_of_canonical: self.face_of_canonical.clone(),
        })
    }
}

impl LoopConnectivity {
    /// Number of coarse vertices (= vertex points).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::detect::{DetectOptions, detect};
    /// use subdiv_loop::forward::{LoopOptions, subdivide};
    ///
    /// let icosahedron = HalfedgeMesh::from_soup(&shapes::icosahedron())?;
    /// let fine = subdivide(&icosahedron, 1, &LoopOptions::default())?.to_halfedge_mesh()?;
    /// let structure = detect(&fine, &DetectOptions::default())?;
    /// assert_eq!(structure.coarse_vertex_count(), 12);
    /// assert_eq!((structure.coarse_edge_count(), structure.coarse_face_count()), (30, 20));
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn coarse_vertex_count(&self) -> usize {
        self.coarsening.coarse.vertex_count()
    }

    /// Number of coarse edges (= edge points).
    pub fn coarse_edge_count(&self) -> usize {
        self.coarsening.coarse.edge_count()
    }

    /// Number of coarse faces (a quarter of the fine faces).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::detect::{DetectOptions, detect};
    /// use subdiv_loop::forward::{LoopOptions, subdivide};
    ///
    /// // Two steps on a tetrahedron: detection undoes the second one.
    /// let tetrahedron = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
    /// let fine = subdivide(&tetrahedron, 2, &LoopOptions::default())?.to_halfedge_mesh()?;
    /// let structure = detect(&fine, &DetectOptions::default())?;
    /// assert_eq!((fine.face_count(), structure.coarse_face_count()), (64, 16));
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn coarse_face_count(&self) -> usize {
        self.coarsening.coarse.face_count()
    }

    /// The fine vertex (vertex point) of each coarse vertex, in increasing order.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::detect::{DetectOptions, detect};
    /// use subdiv_loop::forward::{LoopOptions, subdivide};
    ///
    /// // A subdivided icosahedron (42 vertices) with its vertex numbering reversed: the 12
    /// // vertex points, first in the canonical order, are now the last ones.
    /// let icosahedron = HalfedgeMesh::from_soup(&shapes::icosahedron())?;
    /// let fine = subdivide(&icosahedron, 1, &LoopOptions::default())?;
    /// let positions = fine.positions.iter().rev().copied().collect();
    /// let faces = fine.triangles.iter().map(|t| t.map(|v| 41 - v));
    /// let reversed = HalfedgeMesh::from_faces(positions, faces)?;
    /// let structure = detect(&reversed, &DetectOptions::default())?;
    /// assert_eq!(structure.vertex_points(), (30..42).collect::<Vec<u32>>());
    /// let mut edge_points = structure.edge_points().to_vec();
    /// edge_points.sort();
    /// assert_eq!(edge_points, (0..30).collect::<Vec<u32>>());
    /// assert!(structure.fine_order().is_some()); // not the canonical order
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn vertex_points(&self) -> &[u32] {
        &self.coarsening.vertex_point
    }

    /// The fine vertex (edge point) of each coarse edge, coarse edges numbered as
    /// `mesh_topo` numbers the edges of the coarse mesh.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::detect::{DetectOptions, detect};
    /// use subdiv_loop::forward::{LoopOptions, subdivide};
    ///
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let fine = subdivide(&octahedron, 1, &LoopOptions::default())?.to_halfedge_mesh()?;
    /// let structure = detect(&fine, &DetectOptions::default())?;
    /// // In the canonical order the edge point of coarse edge `e` is fine vertex 6 + e ...
    /// assert_eq!(structure.edge_points(), (6..18).collect::<Vec<u32>>());
    /// // ... and it is a fine neighbour of the vertex points of both ends of its edge.
    /// let fine_vertex = |v: u32| fine.vertex(v as usize).expect("a fine vertex");
    /// let ring: Vec<_> = fine.vertex_neighbors(fine_vertex(structure.edge_points()[0])).collect();
    /// let [a, b] = structure.coarse_edge(0).expect("edge 0 exists");
    /// let [pa, pb] = [a, b].map(|c| fine_vertex(structure.vertex_points()[c as usize]));
    /// assert!(ring.contains(&pa) && ring.contains(&pb));
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn edge_points(&self) -> &[u32] {
        &self.coarsening.edge_point
    }

    /// The coarse faces as coarse vertex indices, counter-clockwise like the fine faces.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::detect::{DetectOptions, detect};
    /// use subdiv_loop::forward::{LoopOptions, subdivide};
    ///
    /// let soup = shapes::icosahedron();
    /// let fine = subdivide(&HalfedgeMesh::from_soup(&soup)?, 1, &LoopOptions::default())?;
    /// let structure = detect(&fine.to_halfedge_mesh()?, &DetectOptions::default())?;
    /// // A mesh made by Loop subdivision gives back the faces it was made from.
    /// assert_eq!(structure.coarse_faces().as_flattened(), soup.indices);
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn coarse_faces(&self) -> Vec<[u32; 3]> {
        let t = &self.coarsening.coarse;
        (0..t.face_count() as u32).map(|f| [t.vertex(3 * f), t.vertex(3 * f + 1), t.vertex(3 * f + 2)]).collect()
    }

    /// The two coarse vertices of coarse edge `e`, or `None` if it does not exist.
    pub fn coarse_edge(&self, e: usize) -> Option<[u32; 2]> {
        let t = &self.coarsening.coarse;
        (e < t.edge_count()).then(|| {
            let c = t.edge_corner(e as u32);
            [t.vertex(c), t.vertex(next(c))]
        })
    }

    /// How the fine mesh is numbered relative to the canonical refinement of the coarse
    /// mesh; `None` if it is the canonical order itself.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::detect::{DetectOptions, detect};
    /// use subdiv_loop::forward::{LoopOptions, subdivide};
    ///
    /// // A subdivided icosahedron (42 vertices, 80 faces), its vertex numbering reversed and
    /// // every face starting at its second corner.
    /// let fine = subdivide(&HalfedgeMesh::from_soup(&shapes::icosahedron())?, 1, &LoopOptions::default())?;
    /// let triangles: Vec<[u32; 3]> = fine.triangles.iter().map(|&[a, b, c]| [b, c, a].map(|v| 41 - v)).collect();
    /// let renumbered = HalfedgeMesh::from_faces(fine.positions.iter().rev().copied().collect(), triangles.clone())?;
    /// let structure = detect(&renumbered, &DetectOptions::default())?;
    /// let order = structure.fine_order().expect("not the canonical order");
    /// assert_eq!(order.check(42, 80), Ok(()));
    /// // Canonical vertex i < 12 is coarse vertex i, the i-th vertex point: fine vertex 30 + i.
    /// assert_eq!(order.vertex_of_canonical[..12], (30..42).collect::<Vec<u32>>());
    /// // Canonical face 4f is the corner face (a, ab, ca) of coarse face f = (a, b, c):
    /// // its corner 0, the vertex point of a, is corner (3 - rotation) % 3 of the fine face.
    /// for (f, [a, _, _]) in structure.coarse_faces().into_iter().enumerate() {
    ///     let (face, rotation) = ((order.face_of_canonical[4 * f] / 3) as usize, order.face_of_canonical[4 * f] % 3);
    ///     assert_eq!(triangles[face][((3 - rotation) % 3) as usize], structure.vertex_points()[a as usize]);
    /// }
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn fine_order(&self) -> Option<FineOrder> {
        self.coarsening.fine_order()
    }
}

/// Finds the Loop structure of a triangle mesh: its vertex points, edge points and
/// coarse faces (see the [module docs](self) for the method and the numbering).
///
/// Linear in the mesh size. A mesh in the canonical order (as Loop subdivision writes
/// it) is recognised from its faces alone; a mesh in any other order is renumbered by a
/// search over coarse faces from its irregular vertices (or the seed); what neither
/// settles (a component whose valences are all regular, and every error) goes through
/// the general propagation over vertices (at most seven attempts in a component whose
/// valences are all regular, one otherwise). All three give the same result.
///
/// ```
/// use glam::DVec3;
/// use mesh_topo::HalfedgeMesh;
/// use subdiv_loop::detect::{DetectOptions, detect};
///
/// // One triangle split 1-to-4: vertex points 0, 1, 2, edge points 3 (01), 4 (12), 5 (20).
/// let positions = vec![
///     DVec3::ZERO, DVec3::X, DVec3::Y,
///     DVec3::new(0.5, 0.0, 0.0), DVec3::new(0.5, 0.5, 0.0), DVec3::new(0.0, 0.5, 0.0),
/// ];
/// let fine = HalfedgeMesh::from_faces(positions, [[0u32, 3, 5], [1, 4, 3], [2, 5, 4], [3, 4, 5]])?;
/// let structure = detect(&fine, &DetectOptions::default())?;
/// assert_eq!(structure.vertex_points(), &[0, 1, 2]);
/// assert_eq!(structure.edge_points(), &[3, 4, 5]);
/// assert_eq!(structure.coarse_faces(), vec![[0, 1, 2]]);
/// assert!(structure.fine_order().is_none()); // canonical order
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// [`LoopError::NotTriangle`] for a face that is not a triangle,
/// [`LoopError::SeedOutOfRange`] for a seed that does not exist,
/// [`LoopError::SeedConflict`] for seeds of one component that cannot all be vertex
/// points, [`LoopError::NoFaces`] for a mesh without faces, and
/// [`LoopError::NotLoopConnectivity`] naming the fine vertex or face where the Loop
/// structure breaks.
pub fn detect(fine: &HalfedgeMesh, options: &DetectOptions) -> Result<LoopConnectivity, LoopError> {
    let seeds = &options.seed_vertices[..];
    // A mesh in another order (a file of another tool) is renumbered into the canonical
    // order by a search over coarse faces, as the reversal does; whatever that does not
    // settle (a component whose valences are all regular, every error) goes through the
    // general detection.
    let coarsening = match detect_canonical_mesh(fine, seeds).or_else(|| detect_renumbered(fine, seeds)) {
        Some(coarsening) => coarsening,
        None => detect_table(&CornerTable::from_mesh(fine)?, seeds)?,
    };
    Ok(LoopConnectivity { coarsening })
}

/// [`detect_table`] on a validated half-edge mesh. A mesh in the canonical order (the
/// output of Loop subdivision and of reconstruction) is recognised from its face
/// corners alone, without building the fine corner table; anything else goes through
/// the corner table and the general detection, which also reports every error.
pub(crate) fn detect_mesh(fine: &HalfedgeMesh, seeds: &[u32]) -> Result<Coarsening, LoopError> {
    match detect_canonical_mesh(fine, seeds) {
        Some(coarsening) => Ok(coarsening),
        None => detect_table(&CornerTable::from_mesh(fine)?, seeds),
    }
}

/// The coarsening of a mesh in the canonical order, from its face corners alone; `None`
/// for any other mesh.
fn detect_canonical_mesh(fine: &HalfedgeMesh, seeds: &[u32]) -> Option<Coarsening> {
    // (The pairing checked the coarse faces: the edges are left.)
    detect_canonical_faces(fine.face_count(), fine.vertex_count(), seeds, mesh_face_corners(fine))
        .filter(|coarsening| coarse_edges_are_simple(&coarsening.coarse))
}

/// The coarsening of a mesh in any order through [`renumber_to_canonical`], checked as
/// the canonical path checks (the coarse twins paired from the renumbered faces, which
/// checks the coarse faces, then the coarse edges: together [`coarse_mesh_is_valid`]):
/// the very coarsening [`detect_general`] finds. `None` when
/// the renumbering is not found or does not check out.
fn detect_renumbered(fine: &HalfedgeMesh, seeds: &[u32]) -> Option<Coarsening> {
    let corners = CornerTable::mesh_corners(fine)?;
    let corner_at = |v| corners.corner_at(fine, v);
    let Renumbering { order, groups } = renumber_to_canonical(fine.vertex_count(), &corners.corners, corner_at, seeds)?;
    let (coarse, _, ()) = groups.into_table(fine.vertex_count(), (), |_, _, _| (), |_, _| ())?;
    // (The pairing checked the coarse faces: the edges are left.)
    if !coarse_edges_are_simple(&coarse) {
        return None;
    }
    let FineOrder { vertex_of_canonical: mut vertex_point, face_of_canonical } = order;
    let edge_point = vertex_point.split_off(coarse.vertex_count());
    Some(Coarsening::new(coarse, vertex_point, edge_point, face_of_canonical))
}

/// The corners of face `f` of a half-edge mesh from its first corner, `None` if it is
/// not a triangle.
fn mesh_face_corners(fine: &HalfedgeMesh) -> impl Fn(usize) -> Option<[u32; 3]> + Sync + '_ {
    let triangles = MeshTriangles::new(fine);
    let targets = fine.raw_halfedge_targets();
    // Called four times per group in the canonical pass: inlined there.
    #[inline(always)]
    move |f: usize| {
        // Corner k is the origin of half-edge k: the target of half-edge k - 1, or of
        // its twin (`h ^ 1`, index arithmetic). The first corner is read through the
        // twin of the first half-edge, beside its own target (the same cache line), so
        // that no corner waits for the third `next` step, which only checks the face.
        let [h0, h1, _] = triangles.halfedges(f)?;
        Some([targets[(h0 ^ 1) as usize], targets[h0 as usize], targets[h1 as usize]])
    }
}

/// [`reverse_canonical`] on a half-edge mesh.
pub(crate) fn reverse_canonical_mesh(
    fine: &HalfedgeMesh,
    seeds: &[u32],
    positions: &[DVec3],
    rules: &LoopOptions,
) -> Option<CanonicalLevel> {
    reverse_canonical(fine.face_count(), fine.vertex_count(), seeds, mesh_face_corners(fine), positions, rules)
}

/// [`reverse_canonical`] on the face list of a polygon
/// soup that no one has validated: a face that is not a triangle, or an index out of
/// range, reads as a mismatch (`None`), so nothing here can index out of bounds.
/// The canonical checks then prove that the soup is the Loop refinement of a coarse mesh
/// whose edges are manifold and consistently oriented, and whose faces are valid; they
/// do not see a coarse vertex whose faces form two fans, which the caller checks
/// ([`CornerTable::fans_are_single`]) before trusting the result.
pub(crate) fn reverse_canonical_soup(soup: &PolygonSoup, seeds: &[u32], rules: &LoopOptions) -> Option<CanonicalLevel> {
    let (offsets, indices, vertices) = (&soup.offsets[..], &soup.indices[..], soup.positions.len());
    let faces = offsets.len().saturating_sub(1);
    // Only triangles (face `f` at `3f..3f + 3`), so that each face is read without its
    // offsets.
    if vertices >= NONE as usize
        || indices.len() >= NONE as usize
        || indices.len() != 3 * faces
        || !offsets_are_triangles(soup)
    {
        return None;
    }
    let face = |f: usize| -> Option<[u32; 3]> {
        let face: [u32; 3] = indices.get(3 * f..3 * f + 3)?.try_into().ok()?;
        face.iter().all(|&v| (v as usize) < vertices).then_some(face)
    };
    reverse_canonical(faces, vertices, seeds, face, &soup.positions, rules)
}

/// True if the soup's offsets are `0, 3, 6, …` (face `f` a triangle at `3f`).
fn offsets_are_triangles(soup: &PolygonSoup) -> bool {
    soup.offsets.first().is_none_or(|&first| first == 0) && soup.is_triangle_soup()
}

/// [`reverse_canonical`] on a corner table.
pub(crate) fn reverse_canonical_table(
    fine: &CornerTable,
    seeds: &[u32],
    positions: &[DVec3],
    rules: &LoopOptions,
) -> Option<CanonicalLevel> {
    let corners = fine.corner_vertices();
    let face = |f: usize| Some([corners[3 * f], corners[3 * f + 1], corners[3 * f + 2]]);
    reverse_canonical(fine.face_count(), fine.vertex_count(), seeds, face, positions, rules)
}

const UNKNOWN: u8 = 0;
const EVEN: u8 = 1;
const ODD: u8 = 2;

/// [`LoopError::SeedOutOfRange`] for the first seed that is not a vertex of a mesh of
/// `vertex_count` vertices.
pub(crate) fn check_seeds(seeds: &[u32], vertex_count: usize) -> Result<(), LoopError> {
    match seeds.iter().find(|&&seed| seed as usize >= vertex_count) {
        Some(&vertex) => Err(LoopError::SeedOutOfRange { vertex, vertex_count }),
        None => Ok(()),
    }
}

fn broken(at: FineElement, reason: String) -> LoopError {
    LoopError::NotLoopConnectivity { at, reason }
}

/// [`detect`] on a corner table.
///
/// Components with an irregular vertex (the common case) are labelled by one
/// propagation from their lowest irregular vertex and their faces validated in one pass
/// in face order; only components whose valences are all regular go through the
/// candidate search, each attempt validating the component's own faces.
pub(crate) fn detect_table(fine: &CornerTable, seeds: &[u32]) -> Result<Coarsening, LoopError> {
    check_seeds(seeds, fine.vertex_count())?;
    if fine.face_count() == 0 {
        // Only isolated vertices: "reversing" would change nothing, forever.
        return Err(LoopError::NoFaces);
    }
    let coarsening = match detect_canonical(fine, seeds) {
        Some(coarsening) => coarsening,
        None => detect_general(fine, seeds)?,
    };
    check_coarse_mesh(&coarsening)?;
    Ok(coarsening)
}

/// A fine mesh can have the 1-to-4 structure of a coarse "mesh" that is not one: a
/// coarse face with a repeated vertex, two coarse edges joining the same two vertices,
/// or an interior coarse vertex of valence 2 (two faces glued along all their edges).
/// Such a coarsening is refused where it shows, so that every coarse mesh handed out
/// is valid for `mesh_topo` and can be refined again. Linear, one pass over the coarse
/// vertices.
fn check_coarse_mesh(coarsening: &Coarsening) -> Result<(), LoopError> {
    let coarse = &coarsening.coarse;
    if coarse_mesh_is_valid(coarse) {
        return Ok(());
    }
    // Something is wrong: find the first vertex point where it shows, and why.
    let bad = (0..coarse.vertex_count() as u32)
        .into_par_iter()
        .map_init(Vec::new, |neighbours: &mut Vec<u32>, v| {
            neighbours.clear();
            let star = coarse.visit_star(v, |_, n| neighbours.push(n));
            let reason = if neighbours.contains(&v) {
                Some("the coarse face at this vertex point would repeat it")
            } else if matches!(star, VertexStar::Interior { valence } if valence < 3) {
                Some("this vertex point would have interior valence 2 in the coarse mesh")
            } else {
                neighbours.sort_unstable();
                neighbours
                    .windows(2)
                    .any(|w| w[0] == w[1])
                    .then_some("two coarse edges at this vertex point would join the same vertices")
            };
            reason.map(|reason| (v, reason))
        })
        .find_first(Option::is_some)
        .flatten();
    match bad {
        None => Ok(()),
        Some((v, reason)) => Err(LoopError::NotLoopConnectivity {
            at: FineElement::Vertex(coarsening.vertex_point[v as usize]),
            reason: reason.to_string(),
        }),
    }
}

/// True if [`check_coarse_mesh`] finds nothing wrong, by cache-friendly passes instead
/// of vertex circulations: no face repeats a vertex (else some vertex would be its own
/// neighbour), no face has two edges shared with the same other face (that is how an
/// interior vertex of valence 2 shows), and no two edges join the same two vertices
/// (edges bucketed by their lower end point, a counting sort). Linear, and equivalent
/// for the verdict (the detailed check runs only when this fails).
fn coarse_mesh_is_valid(coarse: &CornerTable) -> bool {
    let face_ok = |f: u32| {
        let c = 3 * f as usize;
        let corners = |a: &[u32]| [a[c], a[c + 1], a[c + 2]];
        coarse_face_is_valid(corners(coarse.corner_vertices()), corners(coarse.twins()))
    };
    let faces = coarse.face_count() as u32;
    let faces_ok = if kernel::splits(faces as usize, GROUP_CHUNK) {
        (0..faces).into_par_iter().with_min_len(GROUP_CHUNK).all(face_ok)
    } else {
        (0..faces).all(face_ok)
    };
    faces_ok && coarse_edges_are_simple(coarse)
}

/// The face part of [`coarse_mesh_is_valid`] for one face (its corner vertices and
/// twins): no repeated vertex, no two edges shared with the same other face.
#[inline]
fn coarse_face_is_valid([a, b, d]: [u32; 3], twins: [u32; 3]) -> bool {
    let other = |k: usize| if twins[k] == NONE { NONE - k as u32 } else { twins[k] / 3 };
    a != b && b != d && d != a && other(0) != other(1) && other(1) != other(2) && other(2) != other(0)
}

/// The edge part of [`coarse_mesh_is_valid`]: no two edges join the same two vertices.
fn coarse_edges_are_simple(coarse: &CornerTable) -> bool {
    let corner_vertex = coarse.corner_vertices();
    let ends = |e: u32| {
        let c = coarse.edge_corner(e);
        [corner_vertex[c as usize], corner_vertex[next(c) as usize]]
    };
    let mut lower_ends = vec![0u32; coarse.vertex_count() + 1];
    for e in 0..coarse.edge_count() as u32 {
        let [a, b] = ends(e);
        lower_ends[a.min(b) as usize + 1] += 1;
    }
    edges_are_simple(coarse.vertex_count(), coarse.edge_count(), ends, lower_ends)
}

/// No two of the `edge_count` edges `ends(e)` join the same two of `vertex_count`
/// vertices, given `start[v + 1]`, the number of edges whose lower end point is `v`.
fn edges_are_simple(
    vertex_count: usize,
    edge_count: usize,
    ends: impl Fn(u32) -> [u32; 2],
    mut start: Vec<u32>,
) -> bool {
    // Counting sort of the edges by lower end point, then look for a repeated upper end
    // point within each bucket.
    let nv = vertex_count;
    debug_assert_eq!(start.len(), nv + 1);
    let ends = |e: u32| {
        let [a, b] = ends(e);
        (a.min(b), a.max(b))
    };
    // The running sum stays in a register (a sum through memory waits for each store).
    let mut total = 0;
    for count in &mut start {
        total += *count;
        *count = total;
    }
    let mut fill = start.clone();
    let mut upper = vec![0u32; edge_count];
    for e in 0..edge_count as u32 {
        let (lo, hi) = ends(e);
        upper[fill[lo as usize] as usize] = hi;
        fill[lo as usize] += 1;
    }
    // `fill` now holds each bucket's end; reuse it to stamp the upper end points seen
    // from the current lower one.
    let seen_from = &mut fill;
    seen_from.fill(NONE);
    for v in 0..nv {
        for &b in &upper[start[v] as usize..start[v + 1] as usize] {
            if std::mem::replace(&mut seen_from[b as usize], v as u32) == v as u32 {
                return false;
            }
        }
    }
    true
}

/// The fast path: a fine mesh in the canonical order (as made by Loop subdivision or
/// by reconstruction). Faces `4g .. 4g + 4` must be `(x_k, m_k, m_{k-1})` and
/// `(m_0, m_1, m_2)` with every `x < V` and `m_k = V + e_k`, where `V` is the smallest
/// inner-face vertex and `e_k` the edge of `x_k x_{k+1}` in the coarse mesh `(x_0, x_1,
/// x_2)`, and the vertex count must be `V + E`: then the fine faces are exactly the
/// canonical refinement of the coarse mesh, which is what [`detect_general`] finds on
/// such a mesh (each component's lowest vertex is a vertex point, so no other labeling
/// is preferred). Returns `None` as soon as anything differs.
fn detect_canonical(fine: &CornerTable, seeds: &[u32]) -> Option<Coarsening> {
    let corners = fine.corner_vertices();
    detect_canonical_faces(fine.face_count(), fine.vertex_count(), seeds, |f| {
        Some([corners[3 * f], corners[3 * f + 1], corners[3 * f + 2]])
    })
}

/// [`detect_canonical`] from the faces alone (`face(f)`: the corners of face `f`,
/// `None` if it is not a triangle) of a valid manifold mesh with `vertex_count`
/// vertices: its twins follow from the corners, so no fine connectivity is needed. The
/// coarse twins come from the shared edge points: edge point `V + e` is named by coarse
/// half-edges of edge `e` only, which must appear in order of first appearance (the
/// numbering of `mesh_topo`), at most twice and in opposite directions. Linear: one
/// parallel pass over the groups and one sequential pass over the coarse corners, no
/// hashing, no fine twins.
fn detect_canonical_faces(
    faces: usize,
    vertex_count: usize,
    seeds: &[u32],
    face: impl Fn(usize) -> Option<[u32; 3]> + Sync,
) -> Option<Coarsening> {
    let groups = canonical_groups(faces, seeds, face)?;
    let (coarse, _, ()) = groups.into_table(vertex_count, (), |_, _, _| (), |_, _| ())?;
    Some(Coarsening::canonical(coarse))
}

/// The coarse corners of a fine mesh whose faces are in the canonical order (first pass
/// of [`detect_canonical_faces`]).
pub(crate) struct CanonicalGroups {
    /// Coarse vertex of every coarse corner: the vertex point `x` of each corner face.
    pub(crate) coarse_vertex: Vec<u32>,
    /// Fine edge point of every coarse half-edge.
    edge_point: Vec<u32>,
    /// The number of vertex points `V` (the smallest edge point).
    pub(crate) first_odd: u32,
}

/// Reads the groups of four faces (in parallel): faces `4g .. 4g + 4` must be
/// `(x_k, m_k, m_{k-1})` and `(m_0, m_1, m_2)`, every `x` below every `m`, and the seed
/// (if any) a vertex point.
pub(crate) fn canonical_groups(
    faces: usize,
    seeds: &[u32],
    face: impl Fn(usize) -> Option<[u32; 3]> + Sync,
) -> Option<CanonicalGroups> {
    if faces == 0 || !faces.is_multiple_of(4) {
        return None;
    }
    let groups = faces / 4;
    // Every group is written once (no zeroing first).
    let mut coarse_vertex = Output::<[u32; 3]>::new(groups);
    let mut edge_point = Output::<[u32; 3]>::new(groups);
    let (largest_x, first_odd) = {
        let (mut xs, mut ms) = (coarse_vertex.slots(), edge_point.slots());
        // Chunks of whole groups, each a plain loop: the largest `x` and smallest `m`,
        // or `None` for a mismatch.
        let chunk = |(range, mut xs, mut ms): (Range<usize>, Slots<'_, [u32; 3]>, Slots<'_, [u32; 3]>)| {
            let (mut largest, mut smallest) = (0u32, u32::MAX);
            for g in range {
                let m = face(4 * g + 3)?;
                let mut x = [0; 3];
                for (k, x) in x.iter_mut().enumerate() {
                    let [corner, a, b] = face(4 * g + k)?;
                    if a != m[k] || b != m[(k + 2) % 3] {
                        return None;
                    }
                    *x = corner;
                }
                xs.push(x);
                ms.push(m);
                largest = largest.max(x[0].max(x[1]).max(x[2]));
                smallest = smallest.min(m[0].min(m[1]).min(m[2]));
            }
            Some((largest, smallest))
        };
        // One chunk (or a one-thread pool) is read on the calling thread: handing it to
        // the pool costs a wake-up.
        if !kernel::splits(groups, GROUP_CHUNK) {
            chunk((0..groups, xs, ms))?
        } else {
            let pieces: Vec<_> = (0..groups)
                .step_by(GROUP_CHUNK)
                .map(|g0| {
                    let n = GROUP_CHUNK.min(groups - g0);
                    (g0..g0 + n, xs.take_front(n), ms.take_front(n))
                })
                .collect();
            pieces.into_par_iter().map(chunk).try_reduce(|| (0, u32::MAX), |a, b| Some((a.0.max(b.0), a.1.min(b.1))))?
        }
    };
    let (coarse_vertex, edge_point) =
        (coarse_vertex.into_vec().into_flattened(), edge_point.into_vec().into_flattened());
    if largest_x >= first_odd || seeds.iter().any(|&s| s >= first_odd) {
        return None;
    }
    Some(CanonicalGroups { coarse_vertex, edge_point, first_odd })
}

impl CanonicalGroups {
    /// The coarse table (second pass, sequential over the coarse corners): coarse
    /// half-edge `c` has edge point `m_c = V + e_c`; in corner order an edge is new
    /// exactly when it is the next number, and an older one is its twin.
    ///
    /// `on_edge(state, ends, edge_point)` is called for every coarse edge in edge order
    /// (`ends`: the vertices of its first half-edge, `edge_point`: its fine vertex):
    /// in a second sequential pass over the corners that runs beside the pairing on
    /// another thread when the pass is large and the pool has one, else inside the
    /// pairing loop (one pass instead of two).
    ///
    /// Also returns, per coarse edge, the vertex opposite it in its second face (the
    /// face of its second half-edge; [`NONE`] on the boundary), in [`PairedEdge`]: the
    /// pairing reads that face anyway, and the edge rule needs the vertex, which edge
    /// by edge is a chain of dependent loads through the twin.
    ///
    /// `ahead(state, v)` is called for the vertex of the corner [`PAIRING_AHEAD`] places
    /// ahead of the one `on_edge` reads: a hint (say a prefetch of what `on_edge` will
    /// read for that vertex), whose misses then overlap the work in between.
    pub(crate) fn into_table<S: Send>(
        self,
        vertex_count: usize,
        mut state: S,
        on_edge: impl Fn(&mut S, [u32; 2], u32) + Sync,
        ahead: impl Fn(&S, u32) + Sync,
    ) -> Option<(CornerTable, Vec<PairedEdge>, S)> {
        let Self { coarse_vertex, edge_point: mut corner_edge, first_odd } = self;
        let corners = coarse_vertex.len();
        let edge_count = vertex_count - first_odd as usize;
        let ends = |c: usize| [coarse_vertex[c], coarse_vertex[next(c as u32) as usize]];
        let (twin, edge_corner, edges, state) = if kernel::runs_in_parallel(corners / 3) {
            let side = || {
                let mut new_edge = first_odd;
                let prefetching = worth_prefetching(corners * size_of::<PairedEdge>());
                for (c, &m) in corner_edge.iter().enumerate() {
                    if prefetching && let Some(&v) = coarse_vertex.get(c + PAIRING_AHEAD) {
                        ahead(&state, v);
                    }
                    if m == new_edge {
                        new_edge += 1;
                        on_edge(&mut state, ends(c), m);
                    }
                }
                state
            };
            let pair = || {
                let (no_edge, no_hint) = (|_: &mut (), _, _| (), |_: &(), _| ());
                pair_twins(&coarse_vertex, &corner_edge[..], first_odd, edge_count, &mut (), no_edge, no_hint)
            };
            let (paired, state) = rayon::join(pair, side);
            let (twin, edge_corner, edges) = paired?;
            corner_edge.par_iter_mut().with_min_len(3 * GROUP_CHUNK).for_each(|e| *e -= first_odd);
            (twin, edge_corner, edges, state)
        } else {
            // The edge points become the edges as the pairing reads them (no pass of
            // their own).
            let (twin, edge_corner, edges) =
                pair_twins(&coarse_vertex, &mut corner_edge[..], first_odd, edge_count, &mut state, on_edge, ahead)?;
            (twin, edge_corner, edges, state)
        };
        let table = CornerTable::from_numbered_parts(first_odd as usize, coarse_vertex, twin, corner_edge, edge_corner);
        Some((table, edges, state))
    }
}

/// What the twin pairing of [`CanonicalGroups::into_table`] keeps per coarse edge,
/// side by side, so that the second half-edge of an edge finds all it checks and
/// writes in one place (not through the first corner, a chain of dependent loads).
#[derive(Clone, Copy)]
pub(crate) struct PairedEdge {
    /// The vertices of the edge's first half-edge, from and to.
    pub(crate) ends: [u32; 2],
    /// The vertex across the edge in its second face, [`NONE`] on the boundary (and
    /// until the second half-edge is seen).
    pub(crate) opposite: u32,
    /// The edge's first corner.
    pub(crate) first: u32,
}

/// The edge points of the coarse corners as the twin pairing reads them, corner by
/// corner: read only, or turned into edge numbers in place.
trait CornerEdgePoints {
    /// The edge of corner `c`: its edge point minus `first_odd`.
    fn edge(&mut self, c: usize, first_odd: u32) -> u32;

    /// The edge point of corner `c`, not read by [`edge`](Self::edge) yet (`None` past
    /// the end).
    fn edge_point_ahead(&self, c: usize) -> Option<u32>;
}

impl CornerEdgePoints for &[u32] {
    #[inline(always)]
    fn edge(&mut self, c: usize, first_odd: u32) -> u32 {
        self[c] - first_odd
    }

    #[inline(always)]
    fn edge_point_ahead(&self, c: usize) -> Option<u32> {
        self.get(c).copied()
    }
}

/// Each entry is replaced by its edge as it is read.
impl CornerEdgePoints for &mut [u32] {
    #[inline(always)]
    fn edge(&mut self, c: usize, first_odd: u32) -> u32 {
        let e = self[c] - first_odd;
        self[c] = e;
        e
    }

    #[inline(always)]
    fn edge_point_ahead(&self, c: usize) -> Option<u32> {
        self.get(c).copied()
    }
}

/// Corners ahead at which the pairing of [`CanonicalGroups::into_table`] prefetches
/// what it will read there (the edge's record, and whatever `ahead` asks).
pub(crate) const PAIRING_AHEAD: usize = 16;

/// The twin pairing of [`CanonicalGroups::into_table`]: the twins, the first corner
/// of every edge and what [`PairedEdge`] keeps, or `None` if the edge points are not
/// numbered in order of first appearance, or an edge has more than two half-edges or
/// two in the same direction, or a coarse face fails [`coarse_face_is_valid`] (checked
/// on the way, which every caller needs: a face's vertices are distinct when each of
/// its edges joins two; two of its edges shared with the same face show when the later
/// of the two faces pairs them, as two of its corners in a row take their twins there,
/// or one takes its twin in its own face). `new_edge(state, ends, edge_point)` is
/// called when a corner starts an edge, `ahead(state, v)` for the vertex of the corner
/// [`PAIRING_AHEAD`] places ahead.
fn pair_twins<S>(
    coarse_vertex: &[u32],
    mut corner_edge: impl CornerEdgePoints,
    first_odd: u32,
    edge_count: usize,
    state: &mut S,
    new_edge: impl Fn(&mut S, [u32; 2], u32),
    ahead: impl Fn(&S, u32),
) -> Option<(Vec<u32>, Vec<u32>, Vec<PairedEdge>)> {
    let corners = coarse_vertex.len();
    let prefetching = worth_prefetching(corners * size_of::<PairedEdge>());
    let mut twin = vec![NONE; corners];
    let mut edge_corner: Vec<u32> = Vec::with_capacity(edge_count);
    let mut edges: Vec<PairedEdge> = Vec::with_capacity(edge_count);
    // The two latest pairings, as (face of the second half-edge, face of the first).
    let mut latest = [(NONE, NONE); 2];
    for c in 0..corners as u32 {
        let later = c as usize + PAIRING_AHEAD;
        if prefetching && let Some(m) = corner_edge.edge_point_ahead(later) {
            // The record of an edge seen before (its second half-edge), at random.
            prefetch(&edges, m.wrapping_sub(first_odd) as usize);
            ahead(state, coarse_vertex[later]);
        }
        let e = corner_edge.edge(c as usize, first_odd);
        let ends = [coarse_vertex[c as usize], coarse_vertex[next(c) as usize]];
        if ends[0] == ends[1] {
            return None;
        }
        if e as usize == edges.len() {
            edge_corner.push(c);
            edges.push(PairedEdge { ends, opposite: NONE, first: c });
            new_edge(state, ends, first_odd + e);
            continue;
        }
        let edge = edges.get_mut(e as usize)?;
        if edge.opposite != NONE || edge.ends != [ends[1], ends[0]] {
            return None;
        }
        let pairing = (c / 3, edge.first / 3);
        if pairing.0 == pairing.1 || latest.contains(&pairing) {
            return None;
        }
        latest = [latest[1], pairing];
        edge.opposite = coarse_vertex[prev(c) as usize];
        twin[edge.first as usize] = c;
        twin[c as usize] = edge.first;
    }
    (edges.len() == edge_count).then_some((twin, edge_corner, edges))
}

/// Groups (or faces, vertices) per parallel work item of the linear passes.
const GROUP_CHUNK: usize = 4096;

/// The general detection: propagation from seeds and validation (see the module docs).
fn detect_general(fine: &CornerTable, seeds: &[u32]) -> Result<Coarsening, LoopError> {
    let nv = fine.vertex_count();
    let mut labeler = Labeler::new(fine);
    // Valence class of every vertex, in one pass over the corners.
    let valences = Valences::of(nv, (0..fine.corner_count() as u32).map(|c| (fine.vertex(c), fine.twin(c))));
    let irregular = |v: usize| valences.is_irregular(v as u32);

    for &seed in seeds {
        match labeler.label[seed as usize] {
            // Already a vertex point of the labeling of another seed of its component.
            EVEN => {}
            ODD => return Err(LoopError::SeedConflict { vertex: seed }),
            _ if fine.is_isolated(seed) => {}
            _ => labeler.propagate(seed)?,
        }
    }
    for v in 0..nv as u32 {
        if fine.is_isolated(v) {
            labeler.label[v as usize] = EVEN;
        } else if labeler.label[v as usize] == UNKNOWN && irregular(v as usize) {
            labeler.propagate(v)?;
        }
    }
    // What is left: vertices not reached (an error) or components of regular valences.
    let mut component = Vec::new();
    let mut component_faces = Vec::new();
    for v in 0..nv as u32 {
        if labeler.label[v as usize] != UNKNOWN || labeler.component_of[v as usize] != NONE {
            continue;
        }
        labeler.collect_component(v, &mut component, &mut component_faces);
        if component.iter().any(|&u| labeler.label[u as usize] != UNKNOWN || irregular(u as usize)) {
            return Err(broken(
                FineElement::Vertex(v),
                "not reached from the vertex points of its component through the vertex-point / edge-point pattern"
                    .into(),
            ));
        }
        // `v` (the lowest index) or one of its neighbours is a vertex point of any valid
        // labeling.
        let candidates: Vec<u32> = std::iter::once(v).chain(fine.outgoing(v).map(|c| fine.vertex(next(c)))).collect();
        let mut first_error = None;
        for &seed in &candidates {
            match labeler.label_component(seed, &component, &component_faces) {
                Ok(()) => {
                    first_error = None;
                    break;
                }
                Err(error) => {
                    first_error.get_or_insert(error);
                }
            }
        }
        if let Some(error) = first_error {
            return Err(error);
        }
    }
    let ungrouped: Vec<u32> =
        (0..fine.face_count() as u32).filter(|&f| labeler.group_of_face[f as usize] == NONE).collect();
    labeler.group_faces(&ungrouped)?;
    Ok(labeler.assemble())
}

/// A fine mesh in any order, renumbered into the canonical order of the coarse mesh its
/// propagation finds (see [`renumber_to_canonical`]).
pub(crate) struct Renumbering {
    /// The fine order, exactly as [`detect_general`] numbers the coarse mesh.
    pub(crate) order: FineOrder,
    /// The coarse corners of the canonical fine faces (the fine faces renumbered and
    /// rotated by `order`), as [`canonical_groups`] reads them.
    pub(crate) groups: CanonicalGroups,
}

/// The renumbering that the general detection would find, or `None`; the fast path of a
/// fine mesh in any order, which [`reverse_canonical`] then checks and reverses.
///
/// The groups of four faces are found by a search over coarse faces instead of
/// vertices: from a corner face and its vertex point, the inner face lies across the
/// edge-point edge, the other two corner faces across the inner face's other edges, and
/// the corner faces of the neighbouring coarse faces across the corner faces' edges at
/// their vertex points: a few twin look-ups per coarse face, no circulation. Seeds as in
/// [`detect_general`] (the caller's seed, then the lowest irregular vertex not reached
/// yet; isolated vertices are vertex points). Nothing is validated here beyond what the
/// search needs (a face in two groups, a vertex both vertex point and edge point, a
/// missing twin, a face left over, say from a component whose valences are all regular:
/// `None`): the faces, renumbered and rotated by the order found, must be a valid
/// canonical refinement, which [`reverse_canonical`] checks as it does for any mesh.
/// When they are, the fine mesh has Loop connectivity with every seed a vertex point, so
/// its labeling is the one [`detect_general`] propagates from the same seeds (the
/// labeling from a vertex point is forced), and this order numbers the coarse mesh as
/// [`Labeler::assemble`] does: vertex points in fine order, coarse faces by their first
/// fine face, starting at the corner whose corner face comes first, coarse edges (edge
/// points) in order of first appearance.
pub(crate) fn renumber_to_canonical(
    vertex_count: usize,
    corners: &[Corner],
    corner_at: impl Fn(u32) -> u32,
    seeds: &[u32],
) -> Option<Renumbering> {
    let (nv, faces) = (vertex_count, corners.len() / 3);
    if faces == 0 || !faces.is_multiple_of(4) || seeds.iter().any(|&s| s as usize >= nv) {
        return None;
    }
    let mut search = GroupSearch {
        corners,
        label: vec![UNKNOWN; nv],
        grouped: vec![false; faces],
        groups: Vec::with_capacity(faces / 4),
        queue: std::collections::VecDeque::new(),
    };
    for &seed in seeds {
        match search.label[seed as usize] {
            UNKNOWN if corner_at(seed) != NONE => search.search(corner_at(seed))?,
            // An edge point of another seed's labeling (the general path names it).
            ODD => return None,
            _ => {}
        }
    }
    // Vertices reached are skipped, so the valence is counted only at the few vertices
    // before each component's first irregular one (or at every vertex of a component of
    // regular valences, which `Irregularity` counts in one pass).
    let mut irregularity = Irregularity::new(corners, nv);
    for v in 0..nv as u32 {
        if search.label[v as usize] != UNKNOWN {
            continue;
        }
        let c = irregularity.start(v).unwrap_or_else(|| corner_at(v));
        if c == NONE {
            search.label[v as usize] = EVEN;
        } else if irregularity.is_irregular(v, c) {
            search.search(c)?;
        }
    }
    let GroupSearch { label, groups, .. } = search;
    if 4 * groups.len() != faces {
        return None;
    }
    // Every face is in one group: the groups in order of their first face are the coarse
    // faces in order. The first faces, marked in a bit set that stays in cache, rank the
    // groups: each group is read in order once and written once to its place.
    let mut first_faces = RankedBits::new(faces);
    for group in &groups {
        first_faces.insert(group.first_face());
    }
    first_faces.count();
    let mut sorted = vec![FaceGroup::default(); groups.len()];
    for group in &groups {
        sorted[first_faces.rank(group.first_face()) as usize] = *group;
    }
    drop(groups);
    // Canonical vertex of every fine vertex: the vertex points in fine order (their
    // rank among the vertex points, read from a bit set small enough to stay in cache),
    // then the edge points as the coarse corners first name them.
    let mut vertex_of_canonical = Vec::with_capacity(nv);
    let mut vertex_points = RankedBits::new(nv);
    for (v, &l) in label.iter().enumerate() {
        if l == EVEN {
            vertex_points.insert(v as u32);
            vertex_of_canonical.push(v as u32);
        }
    }
    vertex_points.count();
    drop(label);
    // The smallest edge point.
    let first_odd = vertex_of_canonical.len() as u32;
    // Start at the corner whose corner face comes first.
    let first_corner = |corner: [u32; 3]| {
        let r = if corner[0] < corner[1] { 0 } else { 1 };
        if corner[2] < corner[r] { 2 } else { r }
    };
    // The edge points in order of first appearance: the only sequential part (beside
    // the rest on another thread, when the pool has one).
    let mut number_edges = || {
        let mut canonical_of_fine = vec![NONE; nv];
        let prefetching = worth_prefetching(size_of_val(&canonical_of_fine[..]));
        let mut edge_point = Vec::with_capacity(3 * sorted.len());
        for (g, &FaceGroup { corner, m: points, .. }) in sorted.iter().enumerate() {
            // The edge points of the groups a few places ahead (read at random).
            if prefetching && let Some(ahead) = sorted.get(g + NUMBERING_AHEAD) {
                for &point in &ahead.m {
                    prefetch(&canonical_of_fine, point as usize);
                }
            }
            let r = first_corner(corner);
            for s in 0..3 {
                let k = (r + s) % 3;
                let slot = &mut canonical_of_fine[points[k] as usize];
                if *slot == NONE {
                    *slot = vertex_of_canonical.len() as u32;
                    vertex_of_canonical.push(points[k]);
                }
                edge_point.push(*slot);
            }
        }
        edge_point
    };
    // Coarse corner s: the corner face (y_k, m_k, m_{k-1}) (its corners after the vertex
    // point are those of the inner face's edge across which it was found), then the
    // inner face (m_r, m_{r+1}, m_{r+2}). Group by group, in parallel.
    let corners_and_faces = || {
        let mut coarse_vertex = Output::<u32>::new(3 * sorted.len());
        let mut face_of_canonical = Output::<u32>::new(faces);
        {
            let (mut vertices, mut codes) = (coarse_vertex.slots(), face_of_canonical.slots());
            let pieces: Vec<_> = sorted
                .chunks(GROUP_CHUNK)
                .map(|chunk| (chunk, vertices.take_front(3 * chunk.len()), codes.take_front(4 * chunk.len())))
                .collect();
            let run = |(chunk, mut vertices, mut codes): (&[FaceGroup], Slots<'_, u32>, Slots<'_, u32>)| {
                for &FaceGroup { corner, inner, y, .. } in chunk {
                    let r = first_corner(corner);
                    for s in 0..3 {
                        let k = (r + s) % 3;
                        let even = corner[k];
                        // Canonical corner 0 is the vertex point: actual corner j -> rotation (3 - j) % 3.
                        codes.push(3 * (even / 3) + (3 - even % 3) % 3);
                        vertices.push(vertex_points.rank(y[k]));
                    }
                    codes.push(3 * inner + (3 - r as u32) % 3);
                }
            };
            if pieces.len() > 1 && kernel::pool_has_threads() {
                pieces.into_par_iter().for_each(run);
            } else {
                pieces.into_iter().for_each(run);
            }
        }
        (coarse_vertex.into_vec(), face_of_canonical.into_vec())
    };
    let (edge_point, (coarse_vertex, face_of_canonical)) = if kernel::pool_has_threads() {
        rayon::join(number_edges, corners_and_faces)
    } else {
        (number_edges(), corners_and_faces())
    };
    if vertex_of_canonical.len() != nv {
        return None;
    }
    let groups = CanonicalGroups { coarse_vertex, edge_point, first_odd };
    Some(Renumbering { order: FineOrder { vertex_of_canonical, face_of_canonical }, groups })
}

/// Groups ahead whose edge points the numbering of [`renumber_to_canonical`] prefetches.
const NUMBERING_AHEAD: usize = 12;

/// 64 elements of a [`RankedBits`], with the number of members below them.
#[derive(Clone, Copy, Default)]
struct RankWord {
    bits: u64,
    before: u32,
}

/// A bit set of `0..len` that ranks its members (the number of members below) in two
/// loads from one small array: 1/4 byte an element, where a table of ranks at random
/// would take 4 and miss the caches.
struct RankedBits {
    words: Vec<RankWord>,
}

impl RankedBits {
    fn new(len: usize) -> Self {
        Self { words: vec![RankWord::default(); len.div_ceil(64)] }
    }

    #[inline(always)]
    fn insert(&mut self, i: u32) {
        self.words[(i / 64) as usize].bits |= 1 << (i % 64);
    }

    /// Counts the members below every word (after the last insertion).
    fn count(&mut self) {
        let mut before = 0;
        for word in &mut self.words {
            word.before = before;
            before += word.bits.count_ones();
        }
    }

    /// The number of members below `i` (valid after [`count`](Self::count)).
    #[inline(always)]
    fn rank(&self, i: u32) -> u32 {
        let RankWord { bits, before } = self.words[(i / 64) as usize];
        before + (bits & ((1u64 << (i % 64)) - 1)).count_ones()
    }
}

/// Vertices circulated by [`Irregularity`] before it counts every vertex's corners.
const CIRCULATED: usize = 64;

/// Which vertices cannot be edge points ([`is_irregular`]), asked vertex by vertex: by
/// circulation for the first [`CIRCULATED`] vertices asked (most meshes have an
/// irregular vertex among their first few), then from the number of corners of every
/// vertex and whether one of its outgoing half-edges is on the boundary, counted in one
/// sequential pass (a mesh of regular valences is asked about every vertex, and
/// circulating each one is a chain of scattered reads). On a manifold mesh the two
/// agree; the count is the rule of the general detection.
struct Irregularity<'a> {
    corners: &'a [Corner],
    vertex_count: usize,
    asked: usize,
    /// Counted once circulation stops, with the circulation start of every vertex.
    counts: Option<(Valences, Vec<u32>)>,
}

/// The valence class of every vertex of a triangle mesh, from one sequential pass over
/// its corners: the number of corners at each vertex (its valence inside, one fewer on
/// the boundary) and whether one of its outgoing half-edges is on the boundary.
pub(crate) struct Valences {
    /// Corners of every vertex (saturated).
    outgoing: Vec<u8>,
    boundary: Vec<bool>,
}

impl Valences {
    /// From the `(vertex, twin)` of every corner (a corner's twin is that of the
    /// half-edge leaving its vertex, [`NONE`] on the boundary).
    pub(crate) fn of(vertex_count: usize, corners: impl Iterator<Item = (u32, u32)>) -> Self {
        Self::counted(vertex_count, corners, |_, _, _| ())
    }

    /// [`Valences::of`] the corners, in the same pass the circulation start of every
    /// vertex: its first corner, or its corner whose half-edge lies on the boundary (the
    /// rule of [`CornerTable::vertex_corners`], which a half-edge mesh's vertex half-edges
    /// follow too), [`NONE`] for an isolated vertex. A search over a mesh of regular
    /// valences asks for the start of every vertex, which read from the half-edge mesh is
    /// three scattered reads each.
    fn with_starts(vertex_count: usize, corners: &[Corner]) -> (Self, Vec<u32>) {
        let mut starts = vec![NONE; vertex_count];
        let valences = Self::counted(
            vertex_count,
            corners.iter().map(|corner| (corner.vertex, corner.twin)),
            |c, v, on_boundary| {
                if starts[v] == NONE || on_boundary {
                    starts[v] = c;
                }
            },
        );
        (valences, starts)
    }

    /// The pass of [`Valences::of`], calling `each(corner, vertex, on_boundary)` for
    /// every corner in order.
    #[inline(always)]
    fn counted(
        vertex_count: usize,
        corners: impl Iterator<Item = (u32, u32)>,
        mut each: impl FnMut(u32, usize, bool),
    ) -> Self {
        let mut outgoing = vec![0u8; vertex_count];
        let mut boundary = vec![false; vertex_count];
        for (c, (v, twin)) in (0u32..).zip(corners) {
            let (v, on_boundary) = (v as usize, twin == NONE);
            outgoing[v] = outgoing[v].saturating_add(1);
            boundary[v] |= on_boundary;
            each(c, v, on_boundary);
        }
        Self { outgoing, boundary }
    }

    /// True if vertex `v` cannot be an edge point: its valence is not 6 inside or 4 on
    /// the boundary (an isolated vertex included).
    pub(crate) fn is_irregular(&self, v: u32) -> bool {
        self.outgoing[v as usize] != if self.boundary[v as usize] { 3 } else { 6 }
    }
}

impl<'a> Irregularity<'a> {
    fn new(corners: &'a [Corner], vertex_count: usize) -> Self {
        Self { corners, vertex_count, asked: 0, counts: None }
    }

    /// Whether vertex `v`, of corner `c`, cannot be an edge point.
    fn is_irregular(&mut self, v: u32, c: u32) -> bool {
        if self.asked < CIRCULATED {
            self.asked += 1;
            return is_irregular(self.corners, c);
        }
        let (corners, vertex_count) = (self.corners, self.vertex_count);
        let (counts, _) = self.counts.get_or_insert_with(|| Valences::with_starts(vertex_count, corners));
        counts.is_irregular(v)
    }

    /// The circulation start of vertex `v` (as [`CornerTable::vertex_corners`] has it,
    /// [`NONE`] for an isolated vertex) once the valences are counted, `None` before.
    fn start(&self, v: u32) -> Option<u32> {
        self.counts.as_ref().map(|(_, starts)| starts[v as usize])
    }
}

/// True if the vertex of corner `start` cannot be an edge point: its number of corners
/// is not 6 inside or 3 on the boundary (counted around it through the twins).
fn is_irregular(corners: &[Corner], start: u32) -> bool {
    let twin = |c: u32| corners[c as usize].twin;
    let mut count = 1u32;
    // Counter-clockwise: the twin of the half-edge arriving at the vertex.
    let mut c = start;
    loop {
        let t = twin(prev(c));
        if t == start {
            return count != 6;
        }
        if t == NONE {
            break;
        }
        count += 1;
        c = t;
    }
    // An open fan: the rest of it, clockwise.
    let mut c = start;
    while twin(c) != NONE {
        c = next(twin(c));
        count += 1;
    }
    count != 3
}

impl Renumbering {
    /// True if the order is the identity (the fine mesh is in the canonical order).
    pub(crate) fn is_identity(&self) -> bool {
        let FineOrder { vertex_of_canonical, face_of_canonical } = &self.order;
        vertex_of_canonical.iter().enumerate().all(|(i, &v)| v == i as u32)
            && face_of_canonical.iter().enumerate().all(|(k, &code)| code == 3 * k as u32)
    }
}

/// The four faces of a coarse face found by [`GroupSearch`]: `corner[k]`, the corner at
/// the vertex point of the corner face across the inner face's edge `k - 1` (as
/// [`Group::corner`]), and the inner face.
#[derive(Clone, Copy, Default)]
struct FaceGroup {
    corner: [u32; 3],
    inner: u32,
    /// The vertex of each `corner` (vertex points).
    y: [u32; 3],
    /// The corners of the inner face (edge points; `m[k]` on the coarse edge `y[k] -> y[k + 1]`).
    m: [u32; 3],
}

impl FaceGroup {
    /// The lowest of its four faces.
    fn first_face(&self) -> u32 {
        self.corner.iter().fold(self.inner, |f, &c| f.min(c / 3))
    }
}

/// The search of [`renumber_to_canonical`].
///
/// Breadth-first, with a software pipeline: the fine mesh of another tool is in no
/// useful order, so nearly every face the search reads is a cache miss, and a
/// depth-first search (the next face is the one just found) waits for them one after
/// the other. From a queue, the coarse faces to visit next are known well ahead: the
/// lines of a queued corner's face are prefetched when it is queued, those of its inner
/// face [`FAR`](Self::FAR) places before its turn, those of its other two corner faces
/// and the labels of its edge points [`NEAR`](Self::NEAR) places before, the labels of
/// its vertex points and the flags of the faces across [`CLOSE`](Self::CLOSE) places
/// before, so that the misses overlap. The order of the
/// visit changes nothing in the result: the groups are put in the order of their first
/// face afterwards, and a component is searched to its end before the next seed.
struct GroupSearch<'a> {
    corners: &'a [Corner],
    label: Vec<u8>,
    /// True once a face is in a group (one byte a face: the flags stay in cache).
    grouped: Vec<bool>,
    groups: Vec<FaceGroup>,
    /// Corners at the vertex point of corner faces still to visit.
    queue: std::collections::VecDeque<u32>,
}

impl GroupSearch<'_> {
    /// Queue places ahead at which the inner face of a queued corner is prefetched.
    const FAR: usize = 24;
    /// Queue places ahead at which the other corner faces and the labels of the edge
    /// points are prefetched.
    const NEAR: usize = 12;
    /// Queue places ahead at which the labels of the vertex points and the flags of the
    /// faces across are prefetched.
    const CLOSE: usize = 4;

    /// [`run`](Self::run), prefetching if the fine mesh is larger than the caches.
    fn search(&mut self, start: u32) -> Option<()> {
        if worth_prefetching(size_of_val(self.corners)) { self.run::<true>(start) } else { self.run::<false>(start) }
    }

    /// Prefetches the corners and twins of the face of corner `c`.
    #[inline(always)]
    fn prefetch_face(&self, c: u32) {
        let first = 3 * (c / 3) as usize;
        prefetch(self.corners, first);
        prefetch(self.corners, first + 2);
    }

    /// The inner face across the edge-point edge of the corner face of corner `e`.
    #[inline(always)]
    fn across(&self, e: u32) -> u32 {
        self.corners[next(e) as usize].twin
    }

    /// Groups the faces reached from the corner face of corner `start`, whose vertex is
    /// taken for a vertex point; `None` where the pattern breaks.
    ///
    /// Without `PREFETCH` (a fine mesh that fits in the caches) the search is
    /// depth-first without look-ahead: no miss to hide, and the last face found is the
    /// one in cache.
    fn run<const PREFETCH: bool>(&mut self, start: u32) -> Option<()> {
        let corners = self.corners;
        self.queue.clear();
        self.queue.push_back(start);
        while let Some(e) = if PREFETCH { self.queue.pop_front() } else { self.queue.pop_back() } {
            if PREFETCH
                && let Some(&ahead) = self.queue.get(Self::FAR)
                && let across = self.across(ahead)
                && across != NONE
            {
                self.prefetch_face(across);
            }
            if PREFETCH
                && let Some(&ahead) = self.queue.get(Self::NEAR)
                && let across = self.across(ahead)
                && across != NONE
            {
                let i = 3 * (across / 3) as usize;
                for &Corner { vertex: m, twin: t } in &corners[i..i + 3] {
                    prefetch(&self.label, m as usize);
                    if t != NONE {
                        self.prefetch_face(t);
                    }
                }
            }
            if PREFETCH
                && let Some(&ahead) = self.queue.get(Self::CLOSE)
                && let across = self.across(ahead)
                && across != NONE
            {
                let i = 3 * (across / 3) as usize;
                for &Corner { twin: t, .. } in &corners[i..i + 3] {
                    if t != NONE
                        && let Some(&Corner { vertex: y, twin }) = corners.get(prev(t) as usize)
                    {
                        prefetch(&self.label, y as usize);
                        prefetch(&self.grouped, (twin / 3) as usize);
                    }
                }
            }
            if self.grouped[(e / 3) as usize] {
                continue;
            }
            let across = self.across(e);
            if across == NONE {
                return None;
            }
            let inner = across / 3;
            // Across the inner face's edge j (m_j -> m_{j+1}) lies the corner face of
            // vertex point j + 1; its corner there is the one before the twin.
            let mut corner = [0u32; 3];
            for j in 0..3 {
                let t = corners[3 * inner as usize + j].twin;
                if t == NONE {
                    return None;
                }
                corner[(j + 1) % 3] = prev(t);
            }
            for f in [inner, corner[0] / 3, corner[1] / 3, corner[2] / 3] {
                // Also refuses a face met twice in this group.
                if std::mem::replace(&mut self.grouped[f as usize], true) {
                    return None;
                }
            }
            let i = 3 * inner as usize;
            let m = [corners[i].vertex, corners[i + 1].vertex, corners[i + 2].vertex];
            for point in m {
                let label = &mut self.label[point as usize];
                if *label == EVEN {
                    return None;
                }
                *label = ODD;
            }
            let y = corner.map(|c| corners[c as usize].vertex);
            for (c, v) in corner.into_iter().zip(y) {
                let label = &mut self.label[v as usize];
                if *label == ODD {
                    return None;
                }
                *label = EVEN;
                // The neighbouring coarse face across coarse edge k (y_k -> y_{k+1}): its
                // corner face at y_k lies across this corner face's edge y_k -> m_k (the
                // other half of the coarse edge leads to the same coarse face).
                let t = corners[c as usize].twin;
                if t != NONE && !self.grouped[(t / 3) as usize] {
                    if PREFETCH {
                        self.prefetch_face(next(t));
                    }
                    self.queue.push_back(next(t));
                }
            }
            self.groups.push(FaceGroup { corner, inner, y, m });
        }
        Some(())
    }
}

/// The coarse triangle of an inner face `(ab, bc, ca)`: vertex points `y = (a, b, c)`,
/// the edge point `m[k]` of each coarse half-edge `y[k] -> y[k+1]`, and `corner[k]`, the
/// fine corner at `y[k]` in its corner face (whose half-edge is `y[k] -> m[k]`).
#[derive(Debug, Clone, Copy)]
struct Group {
    y: [u32; 3],
    m: [u32; 3],
    corner: [u32; 3],
}

/// Labelling state shared by the attempts on all components.
struct Labeler<'a> {
    fine: &'a CornerTable,
    label: Vec<u8>,
    /// Lowest vertex of each vertex's component (NONE until collected).
    component_of: Vec<u32>,
    /// The two vertex points of each edge point (its coarse edge).
    line: Vec<[u32; 2]>,
    /// Group (index into `groups`) of each face.
    group_of_face: Vec<u32>,
    groups: Vec<Group>,
    /// Per vertex point during propagation: the last vertex point that reached it (for
    /// the double-edge check).
    stamp: Vec<u32>,
    queue: std::collections::VecDeque<u32>,
}

impl<'a> Labeler<'a> {
    fn new(fine: &'a CornerTable) -> Self {
        let nv = fine.vertex_count();
        Self {
            fine,
            label: vec![UNKNOWN; nv],
            component_of: vec![NONE; nv],
            line: vec![[NONE; 2]; nv],
            group_of_face: vec![NONE; fine.face_count()],
            groups: Vec::with_capacity(fine.face_count() / 4),
            stamp: vec![NONE; nv],
            queue: std::collections::VecDeque::new(),
        }
    }

    /// Collects the vertices (breadth-first) and faces of the component of `start`.
    fn collect_component(&mut self, start: u32, vertices: &mut Vec<u32>, faces: &mut Vec<u32>) {
        let fine = self.fine;
        vertices.clear();
        faces.clear();
        self.component_of[start as usize] = start;
        vertices.push(start);
        let mut i = 0;
        while i < vertices.len() {
            let v = vertices[i];
            i += 1;
            for c in fine.outgoing(v) {
                if c.is_multiple_of(3) {
                    faces.push(c / 3);
                }
                // Both ends of the face's other corners: covers the last neighbour of an
                // open fan, which is not the target of a corner of v.
                for w in [fine.vertex(next(c)), fine.vertex(prev(c))] {
                    if self.component_of[w as usize] == NONE {
                        self.component_of[w as usize] = start;
                        vertices.push(w);
                    }
                }
            }
        }
    }

    /// Labels one component from `seed` and validates its faces.
    fn label_component(&mut self, seed: u32, vertices: &[u32], faces: &[u32]) -> Result<(), LoopError> {
        for &v in vertices {
            self.label[v as usize] = UNKNOWN;
            self.stamp[v as usize] = NONE;
        }
        self.propagate(seed)?;
        if let Some(&v) = vertices.iter().find(|&&v| self.label[v as usize] == UNKNOWN) {
            return Err(broken(
                FineElement::Vertex(v),
                format!("not reached from vertex point {seed} through the vertex-point / edge-point pattern"),
            ));
        }
        let first_group = self.groups.len();
        let result = self.group_faces(faces);
        if result.is_err() {
            self.groups.truncate(first_group);
        }
        result
    }

    /// Breadth-first propagation of vertex points through edge points.
    fn propagate(&mut self, seed: u32) -> Result<(), LoopError> {
        let fine = self.fine;
        self.queue.clear();
        self.label[seed as usize] = EVEN;
        self.queue.push_back(seed);
        while let Some(v) = self.queue.pop_front() {
            for c in fine.outgoing(v) {
                let m = fine.vertex(next(c));
                let w = match self.label[m as usize] {
                    UNKNOWN => {
                        let w = self.across(m, v)?;
                        self.label[m as usize] = ODD;
                        self.line[m as usize] = [v, w];
                        w
                    }
                    ODD => match self.line[m as usize] {
                        [a, b] if a == v => b,
                        [a, b] if b == v => a,
                        [a, b] => {
                            return Err(broken(
                                FineElement::Vertex(m),
                                format!(
                                    "edge point between vertex points {a} and {b} is also next to vertex point {v}"
                                ),
                            ));
                        }
                    },
                    _ => {
                        return Err(broken(
                            FineElement::Vertex(m),
                            format!(
                                "it and its neighbour {v} would both be vertex points (the neighbours of a vertex point are edge points)"
                            ),
                        ));
                    }
                };
                match self.label[w as usize] {
                    ODD => {
                        return Err(broken(
                            FineElement::Vertex(w),
                            format!(
                                "it is an edge point, but also the vertex point across edge point {m} from vertex point {v}"
                            ),
                        ));
                    }
                    UNKNOWN => {
                        self.label[w as usize] = EVEN;
                        self.queue.push_back(w);
                    }
                    _ => {}
                }
                if std::mem::replace(&mut self.stamp[w as usize], v) == v {
                    return Err(broken(
                        FineElement::Vertex(v),
                        format!("two of its edge points lead to the same vertex point {w} (a doubled coarse edge)"),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The neighbour of edge point `m` straight across from vertex point `v`.
    fn across(&self, m: u32, v: u32) -> Result<u32, LoopError> {
        let fine = self.fine;
        // The ring of m, counter-clockwise; the last neighbour of an open fan is not the
        // target of a corner. Stop early on a high valence.
        let boundary = fine.is_boundary_vertex(m);
        let mut ring = [NONE; 8];
        let mut count = 0usize;
        let mut last = NONE;
        for c in fine.outgoing(m).take(7) {
            ring[count] = fine.vertex(next(c));
            count += 1;
            last = c;
        }
        if boundary && count < 7 {
            ring[count] = fine.vertex(prev(last));
            count += 1;
        }
        let expected = if boundary { 4 } else { 6 };
        if count != expected {
            let valence = if count >= 7 { fine.outgoing(m).count() + usize::from(boundary) } else { count };
            return Err(broken(
                FineElement::Vertex(m),
                format!(
                    "as a neighbour of vertex point {v} it must be an edge point, but it has valence {valence} ({}); an edge point has valence 6 inside and 4 on the boundary",
                    if boundary { "on the boundary" } else { "inside" }
                ),
            ));
        }
        if boundary {
            // ring[0] and ring[3] are the boundary neighbours.
            if ring[0] == v {
                return Ok(ring[3]);
            }
            if ring[3] == v {
                return Ok(ring[0]);
            }
            return Err(broken(
                FineElement::Vertex(m),
                format!("boundary edge point whose neighbour {v}, a vertex point, is not on the boundary"),
            ));
        }
        let i = ring[..6].iter().position(|&w| w == v).expect("internal: v is a neighbour of m");
        Ok(ring[(i + 3) % 6])
    }

    /// Checks the face pattern and groups every corner face with its inner face; checks
    /// that each edge point of a group lies on the coarse edge of the group.
    fn group_faces(&mut self, faces: &[u32]) -> Result<(), LoopError> {
        let fine = self.fine;
        for &f in faces {
            self.group_of_face[f as usize] = NONE;
        }
        for &f in faces {
            let corners = [3 * f, 3 * f + 1, 3 * f + 2];
            let evens = corners.iter().filter(|&&c| self.label[fine.vertex(c) as usize] == EVEN).count();
            match evens {
                0 => {}
                1 => continue,
                _ => {
                    return Err(broken(
                        FineElement::Face(f),
                        format!(
                            "has {evens} vertex points; a face has one (corner face) or none (inner face) in a Loop mesh"
                        ),
                    ));
                }
            }
            // An inner face (ab, bc, ca): across ab -> bc lies b's corner face, across
            // bc -> ca c's, across ca -> ab a's.
            let mut y = [NONE; 3];
            let mut corner = [NONE; 3];
            let group = self.groups.len() as u32;
            for j in 0..3u32 {
                let t = fine.twin(3 * f + j);
                let (a, b) = (fine.vertex(3 * f + j), fine.vertex(next(3 * f + j)));
                if t == NONE {
                    return Err(broken(
                        FineElement::Face(f),
                        format!("inner face (all edge points) with boundary edge ({a}, {b})"),
                    ));
                }
                let even = prev(t);
                if self.label[fine.vertex(even) as usize] != EVEN {
                    return Err(broken(
                        FineElement::Face(f),
                        format!(
                            "inner face (all edge points) whose neighbour across edge ({a}, {b}) is face {}, not a corner face",
                            t / 3
                        ),
                    ));
                }
                let k = (j as usize + 1) % 3;
                y[k] = fine.vertex(even);
                corner[k] = even;
                debug_assert_eq!(self.group_of_face[(t / 3) as usize], NONE);
                self.group_of_face[(t / 3) as usize] = group;
            }
            self.group_of_face[f as usize] = group;
            let m = [fine.vertex(3 * f), fine.vertex(3 * f + 1), fine.vertex(3 * f + 2)];
            let [a, b, c] = y;
            if a == b || b == c || c == a {
                return Err(broken(
                    FineElement::Face(f),
                    format!("inner face spans the coarse triangle ({a}, {b}, {c}) with a repeated vertex"),
                ));
            }
            for k in 0..3 {
                let (from, to) = (y[k], y[(k + 1) % 3]);
                let line = self.line[m[k] as usize];
                if line != [from, to] && line != [to, from] {
                    return Err(broken(
                        FineElement::Vertex(m[k]),
                        format!(
                            "edge point between vertex points {} and {} is used by the coarse triangle ({a}, {b}, {c}) as the edge point of ({from}, {to})",
                            line[0], line[1]
                        ),
                    ));
                }
            }
            self.groups.push(Group { y, m, corner });
        }
        if let Some(&f) = faces.iter().find(|&&f| self.group_of_face[f as usize] == NONE) {
            return Err(broken(
                FineElement::Face(f),
                "corner face with no inner face across its edge-point edge".into(),
            ));
        }
        Ok(())
    }

    /// Numbers the coarse mesh (all components labelled and validated).
    fn assemble(&self) -> Coarsening {
        let fine = self.fine;
        let nv = fine.vertex_count();
        let mut coarse_of_fine = vec![NONE; nv];
        let mut vertex_point = Vec::with_capacity(nv / 4 + 1);
        for (v, (&label, coarse)) in self.label.iter().zip(&mut coarse_of_fine).enumerate() {
            if label == EVEN {
                *coarse = vertex_point.len() as u32;
                vertex_point.push(v as u32);
            }
        }
        let faces = fine.face_count();
        let coarse_faces = self.groups.len();
        debug_assert_eq!(4 * coarse_faces, faces);
        let mut coarse_of_group = vec![NONE; coarse_faces];
        let mut canonical_of_face = vec![NONE; faces];
        let mut face_of_canonical = vec![NONE; faces];
        let mut corner_vertex = Vec::with_capacity(3 * coarse_faces);
        let mut corner_edge_point = Vec::with_capacity(3 * coarse_faces);
        // Fine corner at the vertex point of each coarse corner (first half of its half-edge).
        let mut first_half = Vec::with_capacity(3 * coarse_faces);
        for f in 0..faces as u32 {
            let g = self.group_of_face[f as usize] as usize;
            if coarse_of_group[g] != NONE {
                continue;
            }
            let coarse = (corner_vertex.len() / 3) as u32;
            coarse_of_group[g] = coarse;
            let group = &self.groups[g];
            // Start at the corner whose corner face comes first.
            let r = (0..3).min_by_key(|&k| group.corner[k]).expect("internal: three corners");
            for s in 0..3 {
                let k = (r + s) % 3;
                let even = group.corner[k];
                corner_vertex.push(coarse_of_fine[group.y[k] as usize]);
                corner_edge_point.push(group.m[k]);
                first_half.push(even);
                let canonical = 4 * coarse + s as u32;
                canonical_of_face[(even / 3) as usize] = canonical;
                // Canonical corner 0 is the vertex point: actual corner j -> rotation (3 - j) % 3.
                face_of_canonical[canonical as usize] = 3 * (even / 3) + (3 - even % 3) % 3;
            }
            // The inner face is the one across the corner faces' edge-point edges.
            let inner = fine.twin(next(group.corner[0])) / 3;
            let canonical = 4 * coarse + 3;
            canonical_of_face[inner as usize] = canonical;
            face_of_canonical[canonical as usize] = 3 * inner + (3 - r as u32) % 3;
        }
        debug_assert_eq!(corner_vertex.len(), 3 * coarse_faces);
        let twin = first_half
            .iter()
            .map(|&first| {
                let t = fine.twin(first);
                if t == NONE {
                    return NONE;
                }
                // t = m -> y_l in the corner face of coarse corner l of the other face;
                // the coarse twin is that face's half-edge l - 1 -> l.
                let canonical = canonical_of_face[(t / 3) as usize];
                let (other, l) = (canonical / 4, canonical % 4);
                debug_assert!(l < 3);
                3 * other + (l + 2) % 3
            })
            .collect();
        let coarse = CornerTable::from_parts(vertex_point.len(), corner_vertex, twin);
        let edge_point =
            (0..coarse.edge_count() as u32).map(|e| corner_edge_point[coarse.edge_corner(e) as usize]).collect();
        debug_assert_eq!(vertex_point.len() + coarse.edge_count(), nv);
        Coarsening::new(coarse, vertex_point, edge_point, face_of_canonical)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::corner_table::CornerTable;
    use crate::forward::LoopOptions;
    use crate::reference::{
        bipyramid, cylinder, flip_edge, flip_random_edges, loop_step, open_fan, perturb, random_diagonal_grid,
        scramble, swap_vertices,
    };
    use glam::DVec3;
    use mesh_topo::PolygonSoup;
    use mesh_topo::shapes::{self, CellKind};
    use proptest::prelude::*;

    /// The corner counts of `Irregularity` (every vertex at once) and the circulation
    /// give the same answer at every vertex of manifold meshes, closed and open, regular
    /// and not, refined or not, renumbered, and the circulation starts counted with them
    /// are those of the corner table and of the half-edge mesh; and the first vertices
    /// asked are circulated.
    #[test]
    fn counted_and_circulated_irregularity_agree() {
        let rules = LoopOptions::default();
        let torus = shapes::torus(6, 4, CellKind::Triangles).unwrap();
        let soups = [
            torus.clone(),
            loop_step(&mesh(&torus), &rules),
            shapes::octahedron(),
            loop_step(&mesh(&shapes::icosahedron()), &rules),
            open_fan(3),
            open_fan(6),
            cylinder(5, 2),
            loop_step(&mesh(&cylinder(5, 2)), &rules),
            scramble(&loop_step(&mesh(&open_fan(5)), &rules), 3),
            scramble(&loop_step(&mesh(&torus), &rules), 4),
            scramble(&loop_step(&mesh(&cylinder(5, 2)), &rules), 5),
        ];
        let mut irregular = 0;
        for (i, soup) in soups.iter().enumerate() {
            let table = CornerTable::from_soup(soup).unwrap();
            let corners = table.corners();
            let mut counted = Irregularity::new(&corners, table.vertex_count());
            counted.asked = CIRCULATED;
            for v in 0..table.vertex_count() as u32 {
                let c = table.vertex_corners()[v as usize];
                let circulated = is_irregular(&corners, c);
                assert_eq!(counted.is_irregular(v, c), circulated, "soup {i}, vertex {v}");
                irregular += usize::from(circulated);
            }
            assert!(counted.counts.is_some(), "soup {i}: counted");
            // The starts counted beside the valences are the table's circulation starts,
            // and the half-edge mesh's, read from the mesh's own corners too.
            let starts: Vec<u32> = (0..table.vertex_count() as u32).map(|v| counted.start(v).unwrap()).collect();
            assert_eq!(starts, table.vertex_corners(), "soup {i}");
            let half_edges = mesh(soup);
            let mesh_corners = CornerTable::mesh_corners(&half_edges).unwrap();
            let (_, from_mesh) = Valences::with_starts(half_edges.vertex_count(), &mesh_corners.corners);
            for (v, &start) in from_mesh.iter().enumerate() {
                assert_eq!(start, mesh_corners.corner_at(&half_edges, v as u32), "soup {i}, vertex {v}");
            }
            let mut fresh = Irregularity::new(&corners, table.vertex_count());
            fresh.is_irregular(0, table.vertex_corners()[0]);
            assert!(fresh.counts.is_none() && fresh.asked == 1, "soup {i}: circulated first");
        }
        assert!(irregular > 0, "some vertices are irregular");
    }

    fn mesh(soup: &PolygonSoup) -> HalfedgeMesh {
        HalfedgeMesh::from_soup(soup).expect("valid test mesh")
    }

    fn refined(soup: &PolygonSoup) -> PolygonSoup {
        loop_step(&mesh(soup), &LoopOptions::default())
    }

    fn detect_soup(soup: &PolygonSoup, seed_vertex: Option<u32>) -> Result<LoopConnectivity, LoopError> {
        detect(&mesh(soup), &DetectOptions { seed_vertices: seed_vertex.into_iter().collect() })
    }

    #[test]
    fn detection_recovers_the_coarse_mesh_of_a_refinement() {
        let shapes = [
            shapes::tetrahedron(),
            shapes::icosahedron(),
            shapes::grid(4, 3, CellKind::Triangles).unwrap(),
            shapes::torus(4, 3, CellKind::Triangles).unwrap(),
            bipyramid(9),
            open_fan(3),
            cylinder(5, 2),
        ];
        for soup in shapes {
            let coarse = mesh(&soup);
            let structure = detect_soup(&refined(&soup), None).unwrap();
            let nv = coarse.vertex_count() as u32;
            assert_eq!(structure.vertex_points(), (0..nv).collect::<Vec<_>>());
            assert_eq!(structure.edge_points(), (nv..nv + coarse.edge_count() as u32).collect::<Vec<_>>());
            let faces: Vec<[u32; 3]> = soup.faces().map(|f| [f[0], f[1], f[2]]).collect();
            assert_eq!(structure.coarse_faces(), faces);
            for e in coarse.edges() {
                let [a, b] = coarse.edge_vertices(e);
                assert_eq!(structure.coarse_edge(e.index()), Some([a.raw(), b.raw()]));
            }
            assert_eq!(structure.coarse_edge(coarse.edge_count()), None);
            assert!(structure.fine_order().is_none());
        }
    }

    #[test]
    fn detection_finds_the_vertex_points_of_a_renumbered_refinement() {
        let soup = shapes::torus(5, 4, CellKind::Triangles).unwrap();
        let fine = refined(&soup);
        let scrambled = scramble(&fine, 99);
        let structure = detect_soup(&scrambled, None).unwrap();
        assert_eq!(structure.coarse_vertex_count(), 20);
        assert_eq!(structure.coarse_edge_count(), 60);
        assert_eq!(structure.coarse_face_count(), 40);
        let order = structure.fine_order().expect("renumbered");
        order.check(scrambled.vertex_count(), scrambled.face_count()).unwrap();
        // Every canonical fine face, mapped through the order, is an input face.
        let table = structure.coarsening.coarse.refine();
        for (k, &code) in order.face_of_canonical.iter().enumerate() {
            let (face, rotation) = ((code / 3) as usize, code % 3);
            for j in 0..3u32 {
                let canonical_corner = 3 * k as u32 + (j + rotation) % 3;
                let expected = order.vertex_of_canonical[table.vertex(canonical_corner) as usize];
                assert_eq!(scrambled.face(face)[j as usize], expected);
            }
        }
    }

    /// The general detection alone, on the corner table (the reference).
    fn detect_in_general(fine: &HalfedgeMesh, seed_vertex: Option<u32>) -> Result<Coarsening, LoopError> {
        detect_table(&CornerTable::from_mesh(fine)?, seed_vertex.as_slice())
    }

    /// `detect` on meshes in another order takes the renumbering path and finds exactly
    /// what the general detection finds, with and without a seed; a mesh whose valences
    /// are all regular (the torus; the open cylinder, valence 4 all along its two
    /// boundaries) has no irregular vertex to start the search from and is left to the
    /// general detection, unless a seed is given.
    #[test]
    fn detect_renumbers_meshes_in_another_order_as_the_general_detection_would() {
        let shapes = [
            ("tetrahedron", shapes::tetrahedron()),
            ("icosahedron", shapes::icosahedron()),
            ("grid", shapes::grid(4, 3, CellKind::Triangles).unwrap()),
            ("torus", shapes::torus(4, 4, CellKind::Triangles).unwrap()),
            ("bipyramid", bipyramid(9)),
            ("open fan", open_fan(3)),
            ("cylinder", cylinder(5, 2)),
        ];
        for (name, soup) in shapes {
            let fine = refined(&soup);
            for seed in [1, 2, 3] {
                let scrambled = mesh(&scramble(&fine, seed));
                let general = detect_in_general(&scrambled, None).unwrap();
                assert!(!general.is_canonical(), "{name}");
                let renumbered = detect_renumbered(&scrambled, &[]);
                let regular = name == "torus" || name == "cylinder";
                assert_eq!(renumbered.is_some(), !regular, "{name}");
                let found = detect(&scrambled, &DetectOptions::default()).unwrap();
                assert_eq!(found.coarsening, general, "{name}");
                let vertex_point = general.vertex_point[general.vertex_point.len() / 2];
                assert!(detect_renumbered(&scrambled, &[vertex_point]).is_some(), "{name}");
                let seeded = detect(&scrambled, &DetectOptions { seed_vertices: vec![vertex_point] }).unwrap();
                assert_eq!(seeded.coarsening, detect_in_general(&scrambled, Some(vertex_point)).unwrap(), "{name}");
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// `detect` (canonical, renumbering and general paths) gives what the general
        /// detection gives, results and errors alike, on refined meshes renumbered and
        /// with edges flipped (most of them no longer Loop meshes).
        #[test]
        fn detect_agrees_with_the_general_detection(
            soup in mesh_topo::testing::arb_triangle_mesh(),
            flips in 0usize..3,
            renumber in any::<bool>(),
            seed in any::<u64>(),
        ) {
            let fine = if renumber { scramble(&refined(&soup), seed) } else { refined(&soup) };
            let fine = flip_random_edges(fine, flips, seed);
            let fine = mesh(&fine);
            let found = detect(&fine, &DetectOptions::default()).map(|structure| structure.coarsening);
            prop_assert_eq!(found, detect_in_general(&fine, None));
        }
    }

    /// The canonical fast path finds exactly what the general detection finds, and
    /// declines renumbered meshes.
    #[test]
    fn canonical_fast_path_agrees_with_the_general_detection() {
        let mut with_isolated = shapes::octahedron();
        with_isolated.positions.push(DVec3::splat(3.0));
        for soup in [
            shapes::tetrahedron(),
            shapes::icosahedron(),
            shapes::grid(4, 3, CellKind::Triangles).unwrap(),
            shapes::torus(4, 4, CellKind::Triangles).unwrap(),
            bipyramid(11),
            open_fan(2),
            cylinder(5, 2),
            with_isolated,
        ] {
            let fine = CornerTable::from_soup(&refined(&soup)).unwrap();
            let fast = detect_canonical(&fine, &[]).expect("canonical");
            assert_eq!(fast, detect_general(&fine, &[]).unwrap());
            let scrambled = CornerTable::from_soup(&scramble(&refined(&soup), 8)).unwrap();
            assert!(detect_canonical(&scrambled, &[]).is_none());
            // A refinement of a refinement in canonical order, seen one level up.
            let twice = CornerTable::from_soup(&refined(&refined(&soup))).unwrap();
            assert_eq!(detect_canonical(&twice, &[]), Some(detect_general(&twice, &[]).unwrap()));
        }
        assert!(detect_canonical(&CornerTable::from_soup(&shapes::icosahedron()).unwrap(), &[]).is_none());
    }

    #[test]
    fn triangle_offsets_are_told_from_others() {
        let soup =
            |offsets: &[u32]| PolygonSoup { positions: Vec::new(), offsets: offsets.to_vec(), indices: Vec::new() };
        let triangles: Vec<u32> = (0..3000).map(|f| 3 * f).collect();
        assert!(
            offsets_are_triangles(&soup(&triangles))
                && offsets_are_triangles(&soup(&[0]))
                && offsets_are_triangles(&soup(&[]))
        );
        for changed in [0, 1, 1023, 1024, 1025, 2999] {
            let mut offsets = triangles.clone();
            offsets[changed] += 1;
            assert!(!offsets_are_triangles(&soup(&offsets)), "offset {changed}");
        }
        assert!(!offsets_are_triangles(&soup(&[1, 4])));
    }

    /// Two triangles glued along all three edges (a pillow) refine, in the canonical
    /// order, to a soup whose faces meet four at an edge: the canonical reading of a
    /// soup no one validated must not take it, and the pairing declines it because the
    /// coarse faces are not valid (each has two edges, indeed three, shared with the
    /// other), before any other check.
    #[test]
    fn the_pairing_declines_coarse_faces_glued_along_two_edges() {
        let pillow = PolygonSoup::from_faces(vec![DVec3::X, DVec3::Y, DVec3::Z], vec![[0u32, 1, 2], [1, 0, 2]]);
        let fine = refined(&pillow);
        assert!(matches!(HalfedgeMesh::from_soup(&fine), Err(mesh_topo::MeshError::NonManifoldEdge { .. })));
        let indices = &fine.indices;
        let groups = canonical_groups(fine.face_count(), &[], |f| indices[3 * f..3 * f + 3].try_into().ok())
            .expect("the faces are in the canonical order");
        assert!(groups.into_table(fine.vertex_count(), (), |_, _, _| (), |_, _| ()).is_none());
    }

    #[test]
    fn any_seed_of_a_regular_torus_gives_a_valid_labeling() {
        let fine = refined(&shapes::torus(4, 4, CellKind::Triangles).unwrap());
        for seed in 0..fine.vertex_count() as u32 {
            let structure = detect_soup(&fine, Some(seed)).unwrap();
            assert!(structure.vertex_points().contains(&seed));
            assert_eq!(structure.coarse_vertex_count(), 16);
        }
    }

    #[test]
    fn regular_meshes_fall_back_to_other_seed_candidates() {
        // On a cylinder only vertices of even rows can be vertex points. Make vertex 0
        // an edge point of a vertical edge, so the first candidate fails.
        let coarse = cylinder(4, 2);
        let fine = refined(&coarse);
        let coarse_mesh = mesh(&coarse);
        let vertical = coarse_mesh
            .edges()
            .find(|&e| {
                let [a, b] = coarse_mesh.edge_vertices(e);
                a.raw() / 4 != b.raw() / 4
            })
            .unwrap();
        let odd_row_vertex = (coarse_mesh.vertex_count() + vertical.index()) as u32;
        let swapped = swap_vertices(&fine, 0, odd_row_vertex);
        assert!(detect_soup(&swapped, Some(0)).is_err(), "an odd-row vertex cannot be a vertex point of the cylinder");
        let structure = detect_soup(&swapped, None).unwrap();
        assert_eq!(structure.coarse_vertex_count(), 12);
        assert!(!structure.vertex_points().contains(&0));
    }

    fn assert_not_loop(soup: &PolygonSoup, what: &str) {
        match detect_soup(soup, None) {
            Err(LoopError::NotLoopConnectivity { at, reason }) => {
                let index = match at {
                    FineElement::Vertex(v) => v as usize,
                    FineElement::Face(f) => f as usize,
                };
                let bound = if matches!(at, FineElement::Vertex(_)) { soup.vertex_count() } else { soup.face_count() };
                assert!(index < bound && !reason.is_empty(), "{what}: {at} {reason}");
            }
            other => panic!("{what}: expected NotLoopConnectivity, got {other:?}"),
        }
    }

    #[test]
    fn meshes_without_loop_connectivity_are_rejected_with_a_location() {
        assert_not_loop(&shapes::icosahedron(), "icosahedron");
        assert_not_loop(&shapes::octahedron(), "octahedron");
        assert_not_loop(&shapes::tetrahedron(), "tetrahedron");
        assert_not_loop(&shapes::grid(5, 5, CellKind::Triangles).unwrap(), "regular grid with odd sides");
        for seed in 0..5 {
            assert_not_loop(&random_diagonal_grid(8, seed), "irregular triangulation");
        }
        // A refined mesh with one edge flipped, for every kind of edge.
        let fine = refined(&bipyramid(5));
        let fine_mesh = mesh(&fine);
        for e in fine_mesh.edges() {
            let [a, b] = fine_mesh.edge_vertices(e);
            assert_not_loop(&flip_edge(&fine, a.raw(), b.raw()), &format!("flipped edge {e:?}"));
        }
        // A refined mesh with one face removed, for every face of one coarse face.
        for removed in 0..4 {
            let mut holed = PolygonSoup::from_faces(fine.positions.clone(), Vec::<[u32; 3]>::new());
            for (f, face) in fine.faces().enumerate() {
                if f != removed {
                    holed.push_face(face);
                }
            }
            assert_not_loop(&holed, &format!("face {removed} removed"));
        }
    }

    #[test]
    fn seed_out_of_range_and_quads_are_errors() {
        let fine = refined(&shapes::octahedron());
        assert_eq!(
            detect_soup(&fine, Some(18)).unwrap_err(),
            LoopError::SeedOutOfRange { vertex: 18, vertex_count: 18 }
        );
        assert!(matches!(
            detect(&mesh(&shapes::cube()), &DetectOptions::default()),
            Err(LoopError::NotTriangle { face: 0, corners: 4 })
        ));
        // A vertex point given as seed works, an edge point of a non-regular mesh does not.
        assert!(detect_soup(&fine, Some(0)).is_ok());
        assert!(detect_soup(&fine, Some(6)).is_err());
    }

    #[test]
    fn isolated_vertices_are_kept_as_isolated_coarse_vertices() {
        let mut coarse = shapes::octahedron();
        coarse.positions.push(DVec3::new(5.0, 5.0, 5.0));
        let fine = refined(&coarse);
        let structure = detect_soup(&fine, None).unwrap();
        assert_eq!(structure.coarse_vertex_count(), 7);
        assert!(structure.fine_order().is_none());
    }

    #[test]
    fn several_components_are_detected_independently() {
        let a = scramble(&refined(&shapes::icosahedron()), 3);
        let b = refined(&cylinder(3, 1));
        let offset = a.vertex_count() as u32;
        let mut both = a.clone();
        both.positions.extend(b.positions.iter().map(|p| *p + DVec3::X * 5.0));
        for face in b.faces() {
            both.push_face(&face.iter().map(|v| v + offset).collect::<Vec<_>>());
        }
        let structure = detect_soup(&both, None).unwrap();
        assert_eq!(structure.coarse_vertex_count(), 12 + 6);
        assert_eq!(structure.coarse_face_count(), 20 + 6);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Detection never panics; when it succeeds on an arbitrary mesh, the coarse mesh
        /// is valid and its canonical refinement, renumbered, is the input.
        #[test]
        fn detection_is_total_and_sound(
            soup in mesh_topo::testing::arb_triangle_mesh(),
            refine in any::<bool>(),
            flips in 0usize..3,
            seed in any::<u64>(),
        ) {
            // Refined meshes in canonical order (the fast path) or renumbered.
            let soup = match (refine, seed % 2) {
                (true, 0) => scramble(&refined(&soup), seed),
                (true, _) => refined(&soup),
                (false, _) => soup,
            };
            let soup = flip_random_edges(soup, flips, seed);
            let soup = perturb(&soup, 0.01, seed);
            if let Ok(structure) = detect_soup(&soup, None) {
                let coarse = structure.coarsening.coarse.clone().into_soup(vec![DVec3::ZERO; structure.coarse_vertex_count()]);
                prop_assert!(HalfedgeMesh::from_soup(&coarse).is_ok());
                let canonical = structure.coarsening.coarse.refine();
                let actual = match structure.fine_order() {
                    None => canonical,
                    Some(order) => canonical.permuted(&order.vertex_of_canonical, &order.face_of_canonical),
                };
                prop_assert_eq!(actual.into_soup(soup.positions.clone()), soup);
            }
        }
    }
}
