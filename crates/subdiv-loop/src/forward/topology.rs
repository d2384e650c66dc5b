//! The compact triangle topology refined level after level.
//!
//! Half-edge `k` of face `f` runs from corner `k` to corner `k + 1` (mod 3) and is
//! encoded as `4f + k`, so its face, `next`, `prev`, origin and target are bit
//! operations, and only the twin is stored (after Dupuy and Vanhoey, "A halfedge
//! refinement rule for parallel Loop/Catmull-Clark subdivision", 2021). Each face stores
//! one *link* word per half-edge (the twin, [`INVALID`] on the boundary) and a fourth
//! word with its edge information: the number of edges first seen in earlier faces and
//! a 3-bit mask of which of its half-edges are the first appearance of their edge.
//! Edges are numbered by first appearance in face order, the numbering of
//! [`HalfedgeMesh`], and a half-edge is first when its twin is missing or lies in a later
//! face; the edge of any half-edge is then one look-up in its (or its twin's) face.
//!
//! After one Loop step every array of the finer level follows from the coarser one by
//! index arithmetic (see `kernel.rs`): nothing is hashed, sorted or searched. Faces
//! `4f .. 4f + 3` of a refined level are the children of face `f` of the level before
//! (a *group*); its *odd* vertices (the edge points of the level before) have valence 6
//! (4 on the boundary) and their neighbours are read off the group and its neighbour
//! group, so only the *even* vertices need a walk around their one-ring and a start
//! half-edge.

use std::mem::take;
use std::ops::Range;
use std::sync::atomic::AtomicU32;
use std::sync::atomic::Ordering::Relaxed;

use mesh_topo::{FaceId, HalfedgeMesh, MeshError};
use rayon::prelude::*;

use super::buffer::{Output, Slots};
use super::kernel::runs_in_parallel;
use crate::LoopError;

/// "No half-edge": the twin of a boundary half-edge, the start of an isolated vertex.
pub(crate) const INVALID: u32 = u32::MAX;
/// Bits of the edge-information word that hold the face's edge base; the 3 bits above
/// hold the mask of first half-edges.
pub(crate) const BASE_BITS: u32 = 29;
pub(crate) const BASE_MASK: u32 = (1 << BASE_BITS) - 1;
/// Largest number of faces of a level that is refined further (half-edges are `4f + k`).
pub(crate) const MAX_FACES: u64 = (u32::MAX / 4) as u64;

/// `k + 1 mod 3` and `k + 2 mod 3` for corners `k` in `0..4` (3 is never a corner).
pub(crate) const NEXT: [usize; 4] = [1, 2, 0, 0];
pub(crate) const PREV: [usize; 4] = [2, 0, 1, 0];

/// Connectivity of one level of a triangle mesh.
#[derive(Debug, Clone, Default)]
pub(crate) struct Topology {
    /// Corner vertices of each face (the origin of half-edge `4f + k` is `triangles[f][k]`).
    pub(crate) triangles: Vec<[u32; 3]>,
    /// Per face: the twins of its three half-edges and its edge information.
    pub(crate) links: Vec<[u32; 4]>,
    /// Per even vertex (`0 .. vertex_halfedge.len()`): an outgoing half-edge, the one
    /// whose twin is missing for boundary vertices (so that the counter-clockwise walk
    /// covers the whole fan), [`INVALID`] for isolated vertices. The remaining vertices
    /// are the odd vertices of a refined level and need none.
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

/// The edge base of an edge-information word.
#[inline(always)]
pub(crate) fn edge_base(info: u32) -> u32 {
    info & BASE_MASK
}

/// The edge of half-edge `k` of a face with edge-information word `info`, if that
/// half-edge is the first of its edge (else look in the twin's face).
#[inline(always)]
pub(crate) fn edge_at(info: u32, k: u32) -> u32 {
    let below = (1u32 << k) - 1;
    (info & BASE_MASK) + ((info >> BASE_BITS) & below).count_ones()
}

impl Topology {
    /// Builds the compact topology of a triangle mesh.
    ///
    /// # Errors
    /// [`LoopError::NotTriangle`] naming the first face that is not a triangle;
    /// [`LoopError::InteriorValenceTwo`] for two triangles glued along all three edges;
    /// [`MeshError::TooLarge`] if the mesh has too many faces or edges for the layout.
    pub(crate) fn from_mesh(mesh: &HalfedgeMesh) -> Result<Self, LoopError> {
        Self::from_mesh_with_room(mesh, 0)
    }

    /// [`Topology::from_mesh`] with its triangles in an array with room for
    /// `triangle_room` of them (reserved, not touched): the array that a later level of
    /// the same parity writes into (see `forward::refine`).
    pub(crate) fn from_mesh_with_room(mesh: &HalfedgeMesh, triangle_room: usize) -> Result<Self, LoopError> {
        let mut topology = Self { triangles: Vec::with_capacity(triangle_room), ..Self::default() };
        topology.rebuild(mesh, &mut Vec::new())?;
        Ok(topology)
    }

    /// [`Topology::from_mesh`] into the memory of `self` (its arrays are overwritten
    /// and grow only when too small); `compact` is scratch for the half-edge map. On
    /// error the arrays hold no valid topology but keep their memory.
    ///
    /// The faces are read in chunks of [`REBUILD_CHUNK`], in parallel on the current
    /// `rayon` pool by the kernel's rule ([`runs_in_parallel`]), else one after the other: at level 1 this pass is a quarter of
    /// the work, and done on one thread it would cap what a second thread can gain.
    /// Every chunk writes only its own faces' entries (and the half-edge map entries of
    /// its faces' half-edges), so the result does not depend on the number of threads.
    ///
    /// # Errors
    /// As [`Topology::from_mesh`]; when several faces are wrong, the first in face order
    /// is named, triangles checked before pillows (as in one pass after the other).
    pub(crate) fn rebuild(&mut self, mesh: &HalfedgeMesh, compact: &mut Vec<AtomicU32>) -> Result<(), LoopError> {
        let face_count = mesh.face_count();
        if face_count as u64 > MAX_FACES {
            return Err(MeshError::TooLarge { what: "faces", count: face_count, max: MAX_FACES as usize }.into());
        }
        if mesh.edge_count() > BASE_MASK as usize {
            return Err(MeshError::TooLarge { what: "edges", count: mesh.edge_count(), max: BASE_MASK as usize }.into());
        }
        let parallel = runs_in_parallel(face_count);
        let mesh_triangles = MeshTriangles::new(mesh);
        let targets = mesh.raw_halfedge_targets();
        let Self { triangles, links, vertex_halfedge, vertex_count, edge_count } = self;
        (*vertex_count, *edge_count) = (0, 0);
        let chunks = chunk_ranges(face_count);

        // Mesh half-edge -> compact half-edge (boundary half-edges have none). Each
        // face half-edge belongs to one face, so the chunks store disjoint entries.
        fill_invalid(compact, mesh.halfedge_count(), parallel);
        let compact: &[AtomicU32] = compact;
        let mut corners = Output::<[u32; 3]>::reuse(take(triangles), face_count);
        let mut not_triangles = {
            let mut slots = corners.slots();
            let pieces = split_slots(&mut slots, &chunks);
            map_chunks(parallel, pieces, |(range, mut piece)| {
                let mut first_bad = None;
                for fi in range {
                    let Some([h0, h1, h2]) = mesh_triangles.halfedges(fi) else {
                        first_bad.get_or_insert(LoopError::NotTriangle {
                            face: fi,
                            corners: mesh.face_halfedges(face_at(mesh, fi)).count(),
                        });
                        piece.push([INVALID; 3]);
                        continue;
                    };
                    let base = 4 * fi as u32;
                    // The origin of a half-edge is its twin's target (twins are `h ^ 1`).
                    let origin = |h: u32| targets[(h ^ 1) as usize];
                    piece.push([origin(h0), origin(h1), origin(h2)]);
                    compact[h0 as usize].store(base, Relaxed);
                    compact[h1 as usize].store(base + 1, Relaxed);
                    compact[h2 as usize].store(base + 2, Relaxed);
                }
                first_bad
            })
        };
        *triangles = corners.into_vec();
        if let Some(error) = not_triangles.iter_mut().find_map(Option::take) {
            return Err(error);
        }

        // Twins and edge information, each chunk numbering its edges from 0; the chunk
        // offsets are added once all counts are known.
        let triangles: &[[u32; 3]] = triangles;
        let mut output = Output::<[u32; 4]>::reuse(take(links), face_count);
        let counted = {
            let mut slots = output.slots();
            let pieces = split_slots(&mut slots, &chunks);
            map_chunks(parallel, pieces, |(range, mut piece)| {
                let (mut edges, mut pillow) = (0u32, None);
                for fi in range {
                    let base = 4 * fi as u32;
                    let Some([h0, h1, h2]) = mesh_triangles.halfedges(fi) else {
                        unreachable!("internal: every face was checked to be a triangle");
                    };
                    let twin = |h: u32| compact[(h ^ 1) as usize].load(Relaxed);
                    let [t0, t1, t2] = [twin(h0), twin(h1), twin(h2)];
                    let mask = u32::from(is_first(base, t0))
                        | u32::from(is_first(base + 1, t1)) << 1
                        | u32::from(is_first(base + 2, t2)) << 2;
                    if pillow.is_none()
                        && (t0 != INVALID && (t0 >> 2 == t1 >> 2 || t0 >> 2 == t2 >> 2)
                            || t1 != INVALID && t1 >> 2 == t2 >> 2)
                    {
                        // Two triangles sharing two edges share all three: a closed
                        // "pillow" whose vertices have interior valence 2. One Loop step
                        // would glue the children along three faces per edge (a
                        // non-manifold result).
                        pillow = Some(LoopError::InteriorValenceTwo { vertex: triangles[fi][0], face: fi });
                    }
                    piece.push([t0, t1, t2, edges | (mask << BASE_BITS)]);
                    edges += mask.count_ones();
                }
                (edges, pillow)
            })
        };
        *links = output.into_vec();
        let mut offsets = Vec::with_capacity(chunks.len());
        let mut edges_before = 0u32;
        for (edges, pillow) in counted {
            if let Some(error) = pillow {
                return Err(error);
            }
            offsets.push(edges_before);
            edges_before += edges;
        }
        debug_assert_eq!(edges_before as usize, mesh.edge_count(), "internal: edge numbering");
        let pieces: Vec<_> =
            links.chunks_mut(rebuild_chunk(face_count)).zip(offsets).filter(|(_, offset)| *offset > 0).collect();
        map_chunks(parallel, pieces, |(piece, offset)| {
            for link in piece {
                link[3] += offset;
            }
        });

        // Starts: a vertex's outgoing half-edge; on the boundary the one whose twin is
        // missing, the twin of the boundary half-edge that ends at the vertex.
        let vertices = mesh.vertex_count();
        let mut starts = Output::<u32>::reuse(take(vertex_halfedge), vertices);
        {
            let mut slots = starts.slots();
            let pieces = split_slots(&mut slots, &chunk_ranges(vertices));
            map_chunks(parallel, pieces, |(range, mut piece)| {
                for vi in range {
                    let v = mesh.vertex(vi).unwrap_or_else(|| unreachable!("internal: vertex {vi} out of range"));
                    piece.push(match mesh.vertex_halfedge(v) {
                        None => INVALID,
                        Some(h) if mesh.is_boundary_halfedge(h) => compact[mesh.prev(h).twin().index()].load(Relaxed),
                        Some(h) => compact[h.index()].load(Relaxed),
                    });
                }
            });
        }
        *vertex_halfedge = starts.into_vec();
        (*vertex_count, *edge_count) = (vertices, mesh.edge_count());
        Ok(())
    }

    /// Number of faces.
    #[inline]
    pub(crate) fn face_count(&self) -> usize {
        self.triangles.len()
    }

    /// The edge index of half-edge `h` (any half-edge, first or not).
    #[cfg(test)]
    pub(crate) fn edge_of(&self, h: u32) -> u32 {
        let twin = self.links[(h >> 2) as usize][(h & 3) as usize];
        let owner = if is_first(h, twin) { h } else { twin };
        edge_at(self.links[(owner >> 2) as usize][3], owner & 3)
    }

    /// Walks the one-ring of even vertex `v` counter-clockwise: the neighbours in order
    /// and whether `v` is on the boundary (then the first and last neighbours are its two
    /// boundary neighbours). Empty for an isolated vertex.
    #[cfg(test)]
    pub(crate) fn ring(&self, v: u32) -> (Vec<u32>, bool) {
        let start = self.vertex_halfedge[v as usize];
        let mut ring = Vec::new();
        if start == INVALID {
            return (ring, false);
        }
        let mut h = start;
        loop {
            let (f, k) = ((h >> 2) as usize, (h & 3) as usize);
            let corners = self.triangles[f];
            ring.push(corners[NEXT[k]]);
            let twin = self.links[f][PREV[k]];
            if twin == INVALID {
                ring.push(corners[PREV[k]]);
                return (ring, true);
            }
            if twin == start || ring.len() > self.triangles.len() * 3 {
                return (ring, false);
            }
            h = twin;
        }
    }
}

/// Faces (and vertices) per chunk of [`Topology::rebuild`].
const REBUILD_CHUNK: usize = 8192;

/// `0..len` in runs of [`REBUILD_CHUNK`], or of half of `len` (at least 1024) when that
/// is shorter, so that a small level still makes a chunk per thread of two.
fn chunk_ranges(len: usize) -> Vec<Range<usize>> {
    let chunk = rebuild_chunk(len);
    (0..len).step_by(chunk).map(|start| start..(start + chunk).min(len)).collect()
}

/// The chunk length of [`chunk_ranges`]`(len)`.
fn rebuild_chunk(len: usize) -> usize {
    REBUILD_CHUNK.min(len.div_ceil(2).max(1024))
}

/// One piece of `slots` per range (consecutive ranges from the front), with its range.
fn split_slots<'a, T>(slots: &mut Slots<'a, T>, ranges: &[Range<usize>]) -> Vec<(Range<usize>, Slots<'a, T>)> {
    ranges.iter().map(|range| (range.clone(), slots.take_front(range.len()))).collect()
}

/// Face `fi` of `mesh`, for an index known to be in range.
#[inline(always)]
fn face_at(mesh: &HalfedgeMesh, fi: usize) -> FaceId {
    mesh.face(fi).unwrap_or_else(|| unreachable!("internal: face {fi} out of range"))
}

/// The triangles of a half-edge mesh read from its flat arrays: the one place that says
/// how a face's three half-edges are found (the forward step's topology, the corner
/// table and the canonical detection all read faces through it).
#[derive(Clone, Copy)]
pub(crate) struct MeshTriangles<'a> {
    first_halfedge: &'a [u32],
    next_halfedge: &'a [u32],
}

impl<'a> MeshTriangles<'a> {
    pub(crate) fn new(mesh: &'a HalfedgeMesh) -> Self {
        Self { first_halfedge: mesh.raw_face_halfedges(), next_halfedge: mesh.raw_halfedge_next() }
    }

    /// The three half-edges of face `f` from its first, found by `next` alone (no
    /// circulator: this is a large part of the work of a small first level); `None` for
    /// a polygon or a face index out of range.
    #[inline(always)]
    pub(crate) fn halfedges(self, f: usize) -> Option<[u32; 3]> {
        let h0 = *self.first_halfedge.get(f)?;
        let h1 = self.next_halfedge[h0 as usize];
        let h2 = self.next_halfedge[h1 as usize];
        (h1 != h0 && self.next_halfedge[h2 as usize] == h0).then_some([h0, h1, h2])
    }
}

/// Sets `map` to `len` entries of [`INVALID`], keeping its memory.
fn fill_invalid(map: &mut Vec<AtomicU32>, len: usize, parallel: bool) {
    map.truncate(len);
    if parallel {
        map.par_iter().for_each(|entry| entry.store(INVALID, Relaxed));
    } else {
        map.iter().for_each(|entry| entry.store(INVALID, Relaxed));
    }
    map.resize_with(len, || AtomicU32::new(INVALID));
}

/// `work.map(run)` in order, on the current `rayon` pool when `parallel`.
fn map_chunks<W: Send, R: Send>(parallel: bool, work: Vec<W>, run: impl Fn(W) -> R + Sync + Send) -> Vec<R> {
    if parallel { work.into_par_iter().map(run).collect() } else { work.into_iter().map(run).collect() }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use mesh_topo::PolygonSoup;
    use mesh_topo::shapes::{self, CellKind};

    use super::*;

    #[test]
    fn edge_numbering_matches_the_halfedge_mesh() {
        for soup in [shapes::icosahedron(), shapes::grid(3, 2, CellKind::Triangles).unwrap(), shapes::tetrahedron()] {
            let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
            let topo = Topology::from_mesh(&mesh).unwrap();
            for f in mesh.faces() {
                for (k, h) in mesh.face_halfedges(f).enumerate() {
                    assert_eq!(topo.edge_of((4 * f.index() + k) as u32) as usize, h.edge().index());
                }
            }
        }
    }

    #[test]
    fn rings_match_the_halfedge_mesh() {
        let mesh = HalfedgeMesh::from_soup(&shapes::grid(3, 3, CellKind::Triangles).unwrap()).unwrap();
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

    /// A triangulated grid of several rebuild chunks with a boundary, on pools of 1 to
    /// 3 threads: the same topology, whose edges and rings match the half-edge mesh.
    #[test]
    fn chunked_rebuild_matches_the_halfedge_mesh_on_any_pool() {
        let mesh = HalfedgeMesh::from_soup(&shapes::grid(120, 80, CellKind::Triangles).unwrap()).unwrap();
        assert!(mesh.face_count() > 2 * REBUILD_CHUNK && mesh.vertex_count() > REBUILD_CHUNK);
        let on = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| Topology::from_mesh(&mesh).unwrap())
        };
        let one = on(1);
        for f in mesh.faces() {
            for (k, h) in mesh.face_halfedges(f).enumerate() {
                assert_eq!(one.edge_of((4 * f.index() + k) as u32) as usize, h.edge().index());
            }
        }
        for v in mesh.vertices() {
            let (mut ring, boundary) = one.ring(v.raw());
            assert_eq!(boundary, mesh.is_boundary_vertex(v));
            let mut expected: Vec<u32> = mesh.vertex_neighbors(v).map(|w| w.raw()).collect();
            ring.sort_unstable();
            expected.sort_unstable();
            assert_eq!(ring, expected, "vertex {v:?}");
        }
        for threads in [2, 3] {
            let other = on(threads);
            assert_eq!(other.triangles, one.triangles);
            assert_eq!(other.links, one.links);
            assert_eq!(other.vertex_halfedge, one.vertex_halfedge);
            assert_eq!((other.vertex_count, other.edge_count), (one.vertex_count, one.edge_count));
        }
    }

    /// The first bad face in face order is named, whichever chunk finds it first.
    #[test]
    fn chunked_rebuild_names_the_first_polygon() {
        let grid = shapes::grid(120, 80, CellKind::Triangles).unwrap();
        let mut faces: Vec<Vec<u32>> = grid.faces().map(<[u32]>::to_vec).collect();
        // Merge the two triangles of two cells, in the second and third chunk, into quads.
        for cell in [9000, 5000] {
            let (first, second) = (faces[2 * cell].clone(), faces.remove(2 * cell + 1));
            faces[2 * cell] = vec![first[0], first[1], first[2], second[2]];
        }
        let mesh = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(grid.positions.clone(), faces)).unwrap();
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let error = pool.install(|| Topology::from_mesh(&mesh)).unwrap_err();
            assert_eq!(error, LoopError::NotTriangle { face: 10_000, corners: 4 }, "{threads} threads");
        }
    }

    #[test]
    fn quads_and_pillows_are_rejected_by_face() {
        let mesh = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        assert_eq!(Topology::from_mesh(&mesh).unwrap_err(), LoopError::NotTriangle { face: 0, corners: 4 });
        let pillow = PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2], [0, 2, 1]]);
        let mesh = HalfedgeMesh::from_soup(&pillow).unwrap();
        assert!(matches!(Topology::from_mesh(&mesh), Err(LoopError::InteriorValenceTwo { .. })));
    }
}
