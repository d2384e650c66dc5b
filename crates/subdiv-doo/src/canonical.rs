//! The reversal of a fine mesh in the canonical order of [`crate::forward`], with a given
//! seed face, read straight from the half-edge arrays.
//!
//! A mesh written by [`crate::subdivide`] (or rebuilt by a pyramid) numbers its fine
//! vertices as the coarse corners and lists its faces as the F_F faces (coarse faces in
//! order, corner `i` of coarse face `k` being fine vertex `offsets[k] + i`), then the F_E
//! quads (one per interior coarse edge, in order of its smaller corner), then the F_V
//! faces (one per interior coarse vertex). For such a mesh the coarse mesh follows from
//! the numbering: the F_F faces, the twins across the F_E quads and the coarse vertices
//! from the F_V faces are found in three streaming passes over the half-edge arrays,
//! without the corner arrays of the general path, its search and its face matching.
//!
//! Without a seed face the automatic choice is made here too: on a closed mesh by
//! [`automatic`] (the dual reading summed from the structure), on an open one by
//! [`automatic_open`] (the other readings' searches replayed to their errors).
//!
//! Every fine face is still checked, and every check of the general path is either made
//! here or follows from the ones made (see [`reverse_canonical`]): the result is the one
//! the general path gives, bit for bit. Any mismatch (a mesh in another order, a broken
//! mesh) makes this path give up, and the general path runs and names the face at fault.

use mesh_topo::memory::{advised_vec, filled_vec};
use mesh_topo::scale::{fold_magnitudes, unit_scale_of_magnitudes};
use mesh_topo::{HalfedgeMesh, PolygonSoup};

use glam::DVec3;

use crate::DooError;
use crate::corner::{CornerMesh, NONE, group_by_key, next_of_corners, prev_of_corners};
use crate::reverse::{
    CornersByVertex, DooReversal, FE, FF, FineOrder, ReverseOptions, ReverseStats, SeedChoice, SeedTrial,
    check_coarse_manifold, corners_by_vertex, details_are_zero, dual_group_energy, ff_faces_share_an_edge,
    insertion_sort, means_and_details, means_and_details_in, not_a_quad, only_valid_reason, quad_on_boundary,
    quad_read_as_ff_face, ranking_reason, zero_details_reason,
};
use crate::rule::FaceMaps;
use std::sync::atomic::{AtomicBool, Ordering};

/// The reversal of `fine` with the one given seed of `options` (or none, see
/// [`automatic`]), if every position is finite and `fine` is a valid
/// Doo-Sabin refinement of one connected coarse mesh in the canonical order and the seed
/// is one of its F_F faces; `None` otherwise (the general path then decides).
///
/// The checks, and why they are enough for the general path to give the same result:
/// - the first faces use the vertices `0, 1, 2, ..` in order, each once, up to the last
///   vertex: they are the F_F faces, every vertex is on exactly one, and fine vertex `c`
///   is coarse corner `c` (the order of the F_F faces in increasing face order);
/// - across each F_F edge not on the boundary lies a face that is a 4-cycle whose opposite
///   edge is not on the boundary and belongs to an F_F face: as each vertex is on one F_F
///   face, once, the far half-edge is the F_F edge of the twin corner, so the twins are an
///   involution and both sides see the same quad (the checks of the search and of the
///   coarse twins hold);
/// - the quads, met from their smaller corner in corner order, are the faces right after
///   the F_F faces, in that order, each starting at that corner (the canonical F_E quads,
///   unrotated, each claimed once, none an F_F face);
/// - all remaining faces are F_V faces: each, starting at its smallest corner, is the full
///   orbit, counter-clockwise, of one interior coarse vertex, and each corner is on one of
///   them at most; the corners on none form open walks (boundary vertices). This gives the
///   coarse vertices and their numbering (interior vertices as their F_V faces, then the
///   boundary vertices by first corner) and the F_V matching;
/// - the coarse mesh is connected (one component: the given seed covers the mesh), the
///   seed is an F_F face, and the coarse mesh passes the same manifold check.
pub(crate) fn reverse_canonical(fine: &HalfedgeMesh, options: &ReverseOptions) -> Option<DooReversal> {
    reverse_canonical_arrays(&HalfedgeArrays::of(fine), options)
}

/// [`reverse_canonical`] on the half-edge arrays of a mesh: a whole mesh, or the part of
/// one that [`HalfedgeArrays::prefix`] keeps.
pub(crate) fn reverse_canonical_arrays(arrays: &HalfedgeArrays<'_>, options: &ReverseOptions) -> Option<DooReversal> {
    reverse_canonical_with(arrays, None, options)
}

/// [`reverse_canonical_arrays`], with the F_F faces of `arrays` if they are known
/// (`known_ff_faces`, as [`stream_ff_faces`] reads them).
fn reverse_canonical_with(
    arrays: &HalfedgeArrays<'_>,
    known_ff_faces: Option<FfFaces>,
    options: &ReverseOptions,
) -> Option<DooReversal> {
    let seed = match options.seeds[..] {
        [seed] => Some(seed),
        [] => None,
        _ => return None,
    };
    options.rule.validate().ok()?;
    let HalfedgeArrays { vertices, faces, positions, .. } = *arrays;
    if vertices == 0 || vertices >= NONE as usize || faces >= NONE as usize {
        return None;
    }

    // F_F faces and coarse twins: from the half-edge layout in streaming passes, or else
    // one walk around each F_F face.
    let ff_faces = match known_ff_faces {
        Some(ff_faces) => {
            debug_assert!(
                stream_ff_faces(arrays).as_ref() == Some(&ff_faces),
                "internal: the F_F faces read with the arrays are those of the layout"
            );
            ff_faces
        }
        None => match stream_ff_faces(arrays) {
            Some(ff_faces) => ff_faces,
            None => walk_ff_faces(arrays)?,
        },
    };
    let FfFaces { offsets, next: coarse_next, twins, across, quads, on_boundary, unreached, layout } = ff_faces;
    // Without a seed, the choice is made here only on meshes with F_E quads and F_V
    // faces (see [`automatic`] and [`automatic_open`]); anything else goes to the general
    // path now, before the work below is done for nothing.
    let automatic_choice = seed.is_none();
    if automatic_choice && quads == 0 {
        return None;
    }
    let ff_count = offsets.len() - 1;
    let ff = ff_count as u32;
    if seed.is_some_and(|seed| seed >= ff_count) {
        return None;
    }
    let fv_first = ff_count + quads as usize;
    if fv_first > faces {
        return None;
    }
    // (Checked on a mesh known to be connected too when debug assertions are on, to
    // test the claim.)
    if (!arrays.connected || cfg!(debug_assertions))
        && !unreached.iter().all(|&k| reaches_lower_in_two(&offsets, &twins, &coarse_next, k))
    {
        // Laid out as `from_soup` lays out the canonical order, F_F face `k` is fine face
        // `k` and holds the F_F side `2c` of its corner `c`.
        let one_component = if layout {
            connected(&offsets, &twins, |_, t| arrays.face_of[2 * t as usize])
        } else {
            connected(&offsets, &twins, |c, _| across[c])
        };
        debug_assert!(one_component || !arrays.connected, "internal: a connected mesh has a connected coarse mesh");
        if !one_component {
            return None;
        }
    }
    debug_assert!(
        twins.iter().enumerate().all(|(c, &t)| t == NONE || twins[t as usize] == c as u32),
        "internal: canonical twins are an involution"
    );

    let closed = !on_boundary;
    // The coarse vertices (from the connectivity) and the candidates (from the positions)
    // do not depend on each other: on several threads they are found side by side.
    let maps = FaceMaps::new(options.rule);
    let find_vertices = || {
        let ff = FfParts { offsets: &offsets, next: &coarse_next, twins: &twins, layout, closed };
        coarse_vertices(arrays, &ff, fv_first, quads as usize, automatic_choice)
    };
    let expand = || expand_in_order(&offsets, &maps, positions, automatic_choice);
    let (found, Expanded { candidates, diagonal: scale, unit_scale }) =
        if rayon::current_num_threads() > 1 && vertices >= PARALLEL_VERTICES {
            let (found, expanded) = rayon::join(find_vertices, expand);
            (found?, expanded)
        } else {
            let found = find_vertices()?;
            (found, expand())
        };
    let CoarseVertices {
        labels,
        vertex_corner,
        fv_sizes,
        by_vertex: closed_by_vertex,
        ends: quad_ends,
        mut stamp,
        interior,
    } = found;
    let coarse_vertex_count = vertex_corner.len();
    let candidate_edges = twins.iter().filter(|&&t| t != NONE).count();
    let coarse = CornerMesh {
        offsets,
        corner_vertex: labels,
        corner_twin: twins,
        corner_next: coarse_next,
        vertex_count: coarse_vertex_count,
        vertex_corner: Some(vertex_corner),
    };
    debug_assert_eq!(closed, candidate_edges == vertices, "internal: boundary corners have no twin");
    let by_vertex = match closed_by_vertex {
        Some(by_vertex) => by_vertex,
        None => corners_by_vertex(&coarse),
    };
    if !closed {
        let ff_faces: Vec<u32> = (0..ff).collect();
        check_coarse_manifold(&coarse, &ff_faces, &by_vertex).ok()?;
    }

    let fv = FvFaces { first: fv_first, sizes_of: &fv_sizes };
    // On a closed mesh the second check of the coarse manifold (no two edges join the
    // same two vertices) is made in the same pass, on the corners of each vertex: the
    // outgoing coarse half-edges of a vertex are its corners.
    let (coarse_positions, details, vertex_energy) = if closed {
        let vertex_count = coarse.vertex_count;
        // The vertices `range`, with the check; `stamp` is scratch of [`distinct`].
        let means_checked = |range: std::ops::Range<usize>, stamp: &mut Vec<u32>| {
            let mut manifold = true;
            // The far ends of each vertex's outgoing coarse half-edges.
            let mut short_ends = [NONE; SHORT];
            let mut long_ends = Vec::new();
            let reserve = vertex_count - range.start;
            let parts = means_and_details_in(&by_vertex, &candidates, range, reserve, |u, corners| {
                let ends = if corners.len() <= SHORT {
                    &mut short_ends[..corners.len()]
                } else {
                    long_ends.resize(corners.len(), NONE);
                    &mut long_ends[..]
                };
                // Read from the quads by the F_V stream (one load per corner), or found.
                match &quad_ends {
                    Some(quad_ends) => {
                        for (end, &c) in ends.iter_mut().zip(corners) {
                            *end = quad_ends[c as usize];
                        }
                    }
                    None => {
                        for (end, &c) in ends.iter_mut().zip(corners) {
                            *end = coarse.corner_vertex[coarse.corner_next[c as usize] as usize];
                        }
                    }
                }
                manifold &= distinct(ends, stamp, interior, u as u32);
            });
            manifold.then_some(parts)
        };
        stamp.fill(NONE);
        if rayon::current_num_threads() > 1 && vertices >= PARALLEL_VERTICES {
            // Two halves side by side (each vertex's values do not depend on the others),
            // the second appended to the first (whose room covers both).
            let half = vertex_count / 2;
            let (first, second) = rayon::join(
                || means_checked(0..half, &mut stamp),
                || means_checked(half..vertex_count, &mut Vec::new()),
            );
            let ((mut means, mut details, mut energies), (more_means, more_details, more_energies)) = (first?, second?);
            means.extend_from_slice(&more_means);
            details.extend_from_slice(&more_details);
            energies.extend_from_slice(&more_energies);
            (means, details, energies)
        } else {
            means_checked(0..vertex_count, &mut stamp)?
        }
    } else {
        means_and_details(&by_vertex, &candidates)
    };
    // Every fine position is in some coarse vertex's mean: a position that is not
    // finite makes a mean that is not (the general path reports it).
    if !coarse_positions.iter().all(|p| p.is_finite()) {
        return None;
    }
    // The detail energy of the lowest face read as F_F (for the automatic choice): the
    // general path sums its groups (the F_V faces, in face order: the coarse vertices) as
    // the result sums its vertices.
    let detail_energy: f64 = vertex_energy.iter().sum();
    // A finite energy bounds every offset below 2^512, so their prefix sums, the details,
    // are finite; else (huge coordinates) they are read. An overflow is the general
    // path's to report.
    if !detail_energy.is_finite() && !details.iter().all(|d| d.is_finite()) {
        return None;
    }
    let (mut choice, stats) = match seed {
        Some(seed) => {
            let stats =
                ReverseStats { visited_faces: ff_count, edges_crossed: vertices, candidate_edges, interpretations: 0 };
            (SeedChoice::given(0, seed), stats)
        }
        None if closed => {
            let (mut choice, rejected_crossings) =
                automatic(arrays, &maps, &coarse, detail_energy, scale, &fv, candidates)?;
            let visited = if choice.trials.len() == 1 { ff_count } else { ff_count + interior + 1 };
            // Every valid reading was searched in full; the ones whose sum stopped early
            // are not counted as evaluated.
            let valid = choice.trials.iter().filter(|t| t.outcome.is_ok()).count();
            let interpretations = choice.trials.iter().filter(|t| t.outcome.is_ok() && !t.stopped_early).count();
            let edges_crossed = valid * vertices + rejected_crossings;
            choice.component = 0;
            (choice, ReverseStats { visited_faces: visited, edges_crossed, candidate_edges, interpretations })
        }
        None => {
            let (choice, stats) = automatic_open(arrays, detail_energy, scale, ff_count, fv_first)?;
            (choice, ReverseStats { candidate_edges, ..stats })
        }
    };
    choice.detail_energy = detail_energy;
    choice.detail_norm = detail_energy.sqrt();
    let reversal = DooReversal::shrink(options.rule, coarse, coarse_positions, details, FineOrder::default(), stats);
    Some(DooReversal { choices: vec![choice], fine_unit_scale: Some(unit_scale), ..reversal })
}

/// The F_F side of the first reading, as [`coarse_vertices`] reads it.
struct FfParts<'a> {
    offsets: &'a [u32],
    next: &'a [u32],
    twins: &'a [u32],
    layout: bool,
    closed: bool,
}

/// What [`coarse_vertices`] finds.
struct CoarseVertices {
    /// The coarse vertex of each corner.
    labels: Vec<u32>,
    /// A corner of each coarse vertex.
    vertex_corner: Vec<u32>,
    /// The sizes of the F_V faces.
    fv_sizes: Vec<u32>,
    /// On a closed mesh, the corners of each coarse vertex in increasing order.
    by_vertex: Option<CornersByVertex>,
    /// From the F_V stream: the coarse vertex at the far end of each corner's coarse edge.
    ends: Option<Vec<u32>>,
    /// Scratch of [`distinct`] (empty, or one slot per interior vertex).
    stamp: Vec<u32>,
    /// The number of interior coarse vertices (those with an F_V face).
    interior: usize,
}

/// The coarse vertices of the first reading of [`reverse_canonical`]: the interior ones
/// from the F_V faces (vertex `i` is F_V face `i`), then the boundary vertices in order
/// of their first corner, with the first check of the coarse manifold on a closed mesh
/// (no face visits a vertex twice); `None` at the first mismatch.
fn coarse_vertices(
    arrays: &HalfedgeArrays<'_>,
    ff: &FfParts<'_>,
    fv_first: usize,
    quads: usize,
    automatic_choice: bool,
) -> Option<CoarseVertices> {
    let HalfedgeArrays { to, next, face_halfedge, vertices, faces, .. } = *arrays;
    let FfParts { offsets, next: coarse_next, twins, layout, closed } = *ff;
    // Interior coarse vertices from the F_V faces (vertex `i` is F_V face `i`), then the
    // boundary vertices in order of their first corner.
    let clockwise = |x: u32| match twins[x as usize] {
        NONE => NONE,
        t => coarse_next[t as usize],
    };
    // On a closed mesh of the layout the F_V faces are read in one stream; else (or if
    // that finds a mismatch) by one walk around each.
    let streamed = if layout && closed { stream_fv_faces(arrays, fv_first, quads) } else { None };
    // The corners of each F_V face: sorted by the stream, or in face order by the walk.
    let mut ends = None;
    let (mut labels, mut vertex_corner, fv_sizes, fv_corners) = match streamed {
        Some(StreamedFvFaces { labels, first_corners, sizes, by_vertex, ends: quad_ends }) => {
            ends = Some(quad_ends);
            (labels, first_corners, sizes, Ok(by_vertex))
        }
        None => {
            let mut labels = vec![NONE; vertices];
            let mut vertex_corner = Vec::with_capacity(faces - fv_first + 1);
            // The corners of the F_V faces in order.
            let mut fv_vertices = Vec::with_capacity(vertices);
            let mut fv_sizes = Vec::with_capacity(faces - fv_first);
            for (i, &first) in face_halfedge[fv_first..].iter().enumerate() {
                let x0 = to[(first ^ 1) as usize];
                let mut previous = x0;
                let mut h = first;
                let mut size = 0u32;
                loop {
                    let x = to[(h ^ 1) as usize];
                    // With the layout checked, every half-edge here is the twin of a quad's side,
                    // from `clockwise(y)` to `y`: the face is a clockwise orbit walked backwards,
                    // and the orbit is checked only off the layout.
                    if std::mem::replace(&mut labels[x as usize], i as u32) != NONE || x < x0 {
                        return None;
                    }
                    if !layout && size > 0 && clockwise(x) != previous {
                        return None;
                    }
                    previous = x;
                    size += 1;
                    fv_vertices.push(x);
                    h = next[h as usize];
                    if h == first {
                        break;
                    }
                }
                if size < 3 || (!layout && clockwise(x0) != previous) {
                    return None;
                }
                debug_assert!(clockwise(x0) == previous, "internal: an F_V face of the layout is an orbit");
                vertex_corner.push(x0);
                fv_sizes.push(size);
            }
            (labels, vertex_corner, fv_sizes, Err(fv_vertices))
        }
    };
    let interior = vertex_corner.len();
    if automatic_choice && interior == 0 {
        return None;
    }
    // The first check of the coarse manifold (no face visits a vertex twice), on a closed
    // mesh made in the pass that sees that every corner has its vertex (every vertex is
    // interior: a corner on no F_V face is on a closed orbit without one).
    let mut stamp = Vec::new();
    if closed {
        for (k, w) in offsets.windows(2).enumerate() {
            if !distinct(&labels[w[0] as usize..w[1] as usize], &mut stamp, interior, k as u32) {
                return None;
            }
        }
    } else {
        for c in 0..vertices as u32 {
            if labels[c as usize] != NONE {
                continue;
            }
            let label = vertex_corner.len() as u32;
            labels[c as usize] = label;
            vertex_corner.push(c);
            let mut x = c;
            loop {
                x = clockwise(x);
                if x == NONE {
                    break;
                }
                if std::mem::replace(&mut labels[x as usize], label) != NONE {
                    // A closed orbit without its F_V face, or not a walk.
                    return None;
                }
            }
            let mut x = c;
            loop {
                let mut p = x;
                while coarse_next[p as usize] != x {
                    p = coarse_next[p as usize];
                }
                x = twins[p as usize];
                if x == NONE {
                    break;
                }
                if std::mem::replace(&mut labels[x as usize], label) != NONE {
                    return None;
                }
            }
        }
    }

    let by_vertex = closed.then(|| {
        // Every vertex is interior: its corners are those of its F_V face, sorted.
        fv_corners.unwrap_or_else(|in_face_order| by_vertex_of_fv_faces(&fv_sizes, in_face_order))
    });
    Some(CoarseVertices { labels, vertex_corner, fv_sizes, by_vertex, ends, stamp, interior })
}

/// The flat arrays of a half-edge mesh that the canonical passes read, and its sizes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct HalfedgeArrays<'a> {
    /// Target vertex of each half-edge.
    pub(crate) to: &'a [u32],
    /// Next half-edge around its face or boundary loop.
    pub(crate) next: &'a [u32],
    /// Face of each half-edge ([`NONE`] on the boundary).
    pub(crate) face_of: &'a [u32],
    /// The half-edge leaving the first corner of each face.
    pub(crate) face_halfedge: &'a [u32],
    /// The position of each vertex.
    pub(crate) positions: &'a [DVec3],
    pub(crate) vertices: usize,
    pub(crate) faces: usize,
    /// The mesh is known to be one connected component: then so is the coarse mesh of a
    /// canonical reading (see [`reverse_canonical`]), and its check is skipped.
    connected: bool,
}

impl<'a> HalfedgeArrays<'a> {
    /// The same arrays, known to be one connected component if `connected`.
    pub(crate) fn known_connected(self, connected: bool) -> Self {
        Self { connected, ..self }
    }

    pub(crate) fn of(mesh: &'a HalfedgeMesh) -> Self {
        let face_halfedge = mesh.raw_face_halfedges();
        Self {
            to: mesh.raw_halfedge_targets(),
            next: mesh.raw_halfedge_next(),
            face_of: mesh.raw_halfedge_faces(),
            face_halfedge,
            positions: mesh.positions(),
            vertices: mesh.vertex_count(),
            faces: face_halfedge.len(),
            connected: false,
        }
    }

    /// The first `faces` faces alone, on the first `vertices` vertices and the first
    /// `face_of.len()` half-edges: `face_of` is the mesh's with every face from
    /// `faces` on replaced by [`NONE`], so that the edges the other faces share with the
    /// kept ones read as boundary edges. The passes of this module follow `next` only
    /// from half-edges that have a face, so the boundary loops, which this view does not
    /// have (the `next` of such a half-edge goes on into a face that is not kept), are
    /// never walked. For the part of a Chaikin step without its boundary ring (see
    /// [`crate::boundary`]).
    pub(crate) fn prefix(self, vertices: usize, faces: usize, face_of: &'a [u32]) -> Self {
        let halfedges = face_of.len();
        Self {
            to: &self.to[..halfedges],
            next: &self.next[..halfedges],
            face_of,
            face_halfedge: &self.face_halfedge[..faces],
            positions: &self.positions[..vertices],
            vertices,
            faces,
            connected: false,
        }
    }
}

/// Half-edge arrays built from corner arrays, numbered as `HalfedgeMesh::from_soup`
/// numbers the same faces (edges in order of first appearance, corner by corner;
/// half-edge `2e` the first appearance, `2e + 1` its twin or the boundary): the view a
/// coarse mesh of a reversal needs for the canonical path of the next level, without a
/// half-edge mesh built and validated (a pyramid's coarser levels are corner arrays).
pub(crate) struct CornerHalfedges {
    to: Vec<u32>,
    next: Vec<u32>,
    face_of: Vec<u32>,
    face_halfedge: Vec<u32>,
    /// The F_F faces, when the arrays were computed from a face list in the canonical
    /// order ([`CornerHalfedges::of_canonical_faces`] reads them on the way): what
    /// [`stream_ff_faces`] would read from the arrays again.
    ff_faces: Option<FfFaces>,
}

impl CornerHalfedges {
    /// The half-edges of `mesh`, or `None` if its twins are not an involution (the
    /// canonical path then does not apply and the general one decides). Linear: each
    /// boundary half-edge's successor is found by one turn around its vertex, and a
    /// vertex has one outgoing boundary half-edge (more only at a vertex where two
    /// boundary loops touch, which the turn then still ends).
    pub(crate) fn of(mesh: &CornerMesh) -> Option<Self> {
        let corners = mesh.corner_count();
        if 2 * corners >= NONE as usize {
            return None;
        }
        let twin = &mesh.corner_twin;
        if twin.iter().enumerate().any(|(c, &t)| t != NONE && (t as usize >= corners || twin[t as usize] != c as u32)) {
            return None;
        }
        let mut halfedge_of = Vec::with_capacity(corners);
        let mut edges = 0u32;
        let mut boundary = false;
        for c in 0..corners as u32 {
            let t = twin[c as usize];
            let h = if t == NONE || t > c {
                boundary |= t == NONE;
                edges += 1;
                2 * (edges - 1)
            } else {
                // The twin comes first: its edge was numbered there, `c` is its odd half.
                halfedge_of[t as usize] | 1
            };
            halfedge_of.push(h);
        }
        let halfedges = 2 * edges as usize;
        let (mut to, mut next, mut face_of) = (vec![0u32; halfedges], vec![NONE; halfedges], vec![NONE; halfedges]);
        let mut face_halfedge = Vec::with_capacity(mesh.face_count());
        for (f, w) in mesh.offsets.windows(2).enumerate() {
            let (begin, end) = (w[0] as usize, w[1] as usize);
            face_halfedge.push(halfedge_of[begin]);
            for c in begin..end {
                let n = if c + 1 == end { begin } else { c + 1 };
                let h = halfedge_of[c] as usize;
                to[h] = mesh.corner_vertex[n];
                next[h] = halfedge_of[n];
                face_of[h] = f as u32;
                if twin[c] == NONE {
                    // The boundary half-edge runs back along the edge.
                    to[h ^ 1] = mesh.corner_vertex[c];
                }
            }
        }
        if boundary {
            // The boundary half-edge opposite corner `c` ends at `c`'s vertex; the next
            // one leaves it along the last edge of the fan that starts at `c`.
            let prev = prev_of_corners(&mesh.offsets);
            for c in 0..corners {
                if twin[c] != NONE {
                    continue;
                }
                let mut x = c;
                let mut turns = 0;
                let last = loop {
                    let p = prev[x] as usize;
                    match twin[p] {
                        NONE => break p,
                        t => x = t as usize,
                    }
                    turns += 1;
                    if turns > corners {
                        return None;
                    }
                };
                next[(halfedge_of[c] ^ 1) as usize] = halfedge_of[last] ^ 1;
            }
        }
        Some(Self { to, next, face_of, face_halfedge, ff_faces: None })
    }

    /// The half-edges `HalfedgeMesh::from_soup` would build from `soup`, computed from
    /// the soup's face list alone when it is a mesh in the canonical order of
    /// [`crate::subdivide`] under the shrinking boundary rule (see [`reverse_canonical`]),
    /// closed or not; `None` for any other soup (another order, the Chaikin ring, anything
    /// `from_soup` rejects), which then takes the way through `from_soup`.
    ///
    /// Read in that order, a Doo-Sabin soup of `V` vertices names every half-edge by
    /// arithmetic (the numbering of [`stream_ff_faces`]): the F_F faces are the first
    /// faces, on the vertices `0, 1, 2, ..` in order, and fine vertex `c` starts the F_F
    /// side `2c`, whose twin `2c + 1` lies on an F_E quad or on the boundary; quad `j` is
    /// `(c, next(t), t, next(c))`, `c < t` the twin corners, claimed in increasing order
    /// of `c` (the quads are the faces of that form after the F_F faces), with the sides
    /// `2V + 4j` (from `c`) and `2V + 4j + 2` (from `t`); every other face is an F_V face,
    /// whose side `x -> y` is the twin of the quad side from `y` (so `x` must be
    /// `next(twin(y))`), each vertex on one at most. Every other half-edge is on the
    /// boundary: it is followed by the one boundary half-edge that leaves its end.
    ///
    /// What is checked makes the soup one `from_soup` accepts, with these half-edges:
    /// indices in range and positions finite; faces of 3 or more corners, no vertex twice
    /// in a face (the F_F faces by their numbering, the F_V faces by marking each vertex
    /// once; a quad `(c, next(t), t, next(c))` with `c = next(t)` would put `c` after
    /// itself on its F_V face, and likewise `t = next(c)`); the half-edges leaving each
    /// vertex `x` (along its F_F side to `next(x)`, back along the F_F side ending at it
    /// to `prev(x)`, along its quad side to `next(twin(x))` and back along the quad side
    /// ending at it to `twin(prev(x))`, those that exist) have different targets, none
    /// `x`, so that no two sides of faces join the same two vertices. The faces around
    /// each vertex (F_F, its quad, its F_V face, the quad of the corner before it, those
    /// that exist) then form one fan: an F_V face needs both quads, so what is missing is
    /// one run of the cycle. Linear, without hashing or sorting: one pass over the faces
    /// and one over the vertices.
    pub(crate) fn of_canonical_soup(soup: &PolygonSoup) -> Option<Self> {
        Self::of_canonical_faces(&soup.positions, &soup.offsets, &soup.indices)
    }

    /// [`CornerHalfedges::of_canonical_soup`] of the soup of `positions`, with the faces
    /// `offsets` and `indices`: also the corner arrays of a coarse mesh of a canonical
    /// reversal (`offsets` and `corner_vertex`), which is in the canonical order again
    /// when its fine mesh was refined more than once.
    pub(crate) fn of_canonical_faces(positions: &[DVec3], offsets: &[u32], indices: &[u32]) -> Option<Self> {
        let vertices = positions.len();
        let faces = offsets.len().checked_sub(1)?;
        // At most 4V half-edges (2V edges), all numbered below `NONE`.
        if vertices == 0 || vertices >= (NONE as usize) / 4 || faces >= NONE as usize {
            return None;
        }
        if offsets[0] != 0
            || offsets[faces] as usize != indices.len()
            || offsets.windows(2).any(|w| u64::from(w[1]) < u64::from(w[0]) + 3)
        {
            return None;
        }
        if !positions.iter().all(|p| p.is_finite()) {
            return None;
        }
        let v = vertices as u32;
        // Room for the closed case; cut to `2V + 4 * quads` below.
        let room = 4 * vertices;
        // (Tens of megabytes for a large mesh, written at random: on huge pages.)
        let (mut to, mut next, mut face_of) = (filled_vec(room, 0u32), filled_vec(room, NONE), filled_vec(room, NONE));
        let mut face_halfedge = Vec::with_capacity(faces);
        // F_F faces: vertex `c` is corner `c`; the next and previous corner of each.
        let (mut corner_next, mut corner_prev) = (advised_vec(vertices), advised_vec(vertices));
        let mut f = 0;
        let mut start = 0u32;
        while start < v {
            let (b, e) = (offsets[f] as usize, offsets.get(f + 1).copied()? as usize);
            let size = (e - b) as u32;
            if start.checked_add(size)? > v || !indices[b..e].iter().zip(start..).all(|(&x, c)| x == c) {
                return None;
            }
            face_halfedge.push(2 * start);
            for c in start..start + size {
                let n = if c + 1 == start + size { start } else { c + 1 };
                corner_next.push(n);
                corner_prev.push(if c == start { start + size - 1 } else { c - 1 });
                let h = 2 * c as usize;
                (to[h], next[h], face_of[h]) = (n, 2 * n, f as u32);
                to[h + 1] = c;
            }
            start += size;
            f += 1;
        }
        // F_E quads, for as long as the faces are quads of that form: the twins, and the
        // quad side leaving each twinned vertex.
        let ff = f;
        let mut twin = filled_vec(vertices, NONE);
        let mut side = filled_vec(vertices, NONE);
        let mut last_claim = None;
        while f < faces {
            let Ok(&[c, a, t, b]) = <&[u32; 4]>::try_from(&indices[offsets[f] as usize..offsets[f + 1] as usize])
            else {
                break;
            };
            let (ci, ti) = (c as usize, t as usize);
            if t >= v
                || c >= t
                || last_claim.is_some_and(|last| c <= last)
                || a != corner_next[ti]
                || b != corner_next[ci]
                || twin[ci] != NONE
                || twin[ti] != NONE
            {
                break;
            }
            last_claim = Some(c);
            (twin[ci], twin[ti]) = (t, c);
            let q = 2 * vertices + 4 * (f - ff);
            (side[ci], side[ti]) = (q as u32, q as u32 + 2);
            face_halfedge.push(q as u32);
            let (back_c, back_t, face) = (2 * ci + 1, 2 * ti + 1, f as u32);
            // The 4-cycle q -> back of t's F_F side -> q + 2 -> back of c's F_F side.
            (to[q], next[q], face_of[q]) = (a, back_t as u32, face);
            (next[back_t], face_of[back_t]) = (q as u32 + 2, face);
            (to[q + 2], next[q + 2], face_of[q + 2]) = (b, back_c as u32, face);
            (next[back_c], face_of[back_c]) = (q as u32, face);
            (to[q + 1], to[q + 3]) = (c, t);
            f += 1;
        }
        let halfedges = 2 * vertices + 4 * (f - ff);
        // F_V faces: side `x -> y` is the twin of the quad side from `y`, which ends at
        // `next(twin(y))`; followed by `y -> z`.
        let back_of_side = |y: u32| side[y as usize] + 1;
        let mut on_fv = vec![false; vertices];
        let mut fv_corners = 0;
        for f in f..faces {
            let corners = &indices[offsets[f] as usize..offsets[f + 1] as usize];
            fv_corners += corners.len();
            let mut x = corners[corners.len() - 1];
            if x >= v || twin[x as usize] == NONE {
                return None;
            }
            let mut side_to_x = back_of_side(x);
            for &y in corners {
                if y >= v || std::mem::replace(&mut on_fv[y as usize], true) {
                    return None;
                }
                let t = twin[y as usize];
                if t == NONE || corner_next[t as usize] != x {
                    return None;
                }
                let side_to_y = back_of_side(y);
                (next[side_to_x as usize], face_of[side_to_y as usize]) = (side_to_y, f as u32);
                (x, side_to_x) = (y, side_to_y);
            }
            face_halfedge.push(back_of_side(corners[1]));
        }
        // Different targets out of each vertex, and its boundary half-edge, if any:
        // back along the F_F side ending at it (if that side has no quad), or back along
        // the quad side ending at it (if it has no F_V face). A closed mesh (every vertex
        // on a quad and an F_V face) has none.
        let closed = halfedges == room && fv_corners == vertices;
        let mut boundary_out = if closed { Vec::new() } else { vec![NONE; vertices] };
        for x in 0..vertices {
            let (n, p) = (corner_next[x], corner_prev[x]);
            let s = match twin[x] {
                NONE => NONE,
                t => corner_next[t as usize],
            };
            let r = twin[p as usize];
            let x = x as u32;
            // ([`NONE`] for a half-edge that does not exist; some pairs cannot meet, and
            // `s = p` at `x` is `n = r` at `p`, but all are compared.)
            let targets = [n, p, s, r];
            if targets.iter().enumerate().any(|(i, &y)| y == x || (y != NONE && targets[..i].contains(&y))) {
                return None;
            }
            if closed {
                continue;
            }
            if r == NONE {
                boundary_out[x as usize] = 2 * p + 1;
            } else if !on_fv[x as usize] {
                boundary_out[x as usize] = back_of_side(r);
            }
        }
        // The boundary half-edges: the back of an F_F side without a quad (ending at its
        // corner) and the back of a quad side without an F_V face (ending at its start).
        if !closed {
            for y in 0..vertices {
                let h = match twin[y] {
                    NONE => 2 * y + 1,
                    _ if !on_fv[y] => back_of_side(y as u32) as usize,
                    _ => continue,
                };
                // (A vertex with a boundary half-edge ending at it has one leaving it.)
                next[h] = boundary_out[y];
                if next[h] == NONE {
                    return None;
                }
            }
        }
        for array in [&mut to, &mut next, &mut face_of] {
            array.truncate(halfedges);
        }
        // The F_F faces as [`stream_ff_faces`] reads them from these arrays: face `k` is
        // unreached when no corner of it has a twin on an earlier face (below its first
        // corner; a boundary corner's `NONE` is not).
        let quads = (halfedges - 2 * vertices) / 4;
        let ff_offsets = offsets[..=ff].to_vec();
        let unreached = (1..ff)
            .filter(|&k| {
                let (b, e) = (ff_offsets[k], ff_offsets[k + 1]);
                twin[b as usize..e as usize].iter().all(|&t| t >= b)
            })
            .map(|k| k as u32)
            .collect();
        let ff_faces = FfFaces {
            offsets: ff_offsets,
            next: corner_next,
            twins: twin,
            across: Vec::new(),
            quads: quads as u32,
            on_boundary: 2 * quads < vertices,
            unreached,
            layout: true,
        };
        Some(Self { to, next, face_of, face_halfedge, ff_faces: Some(ff_faces) })
    }

    /// [`reverse_canonical_arrays`] on these arrays with the vertex `positions`, known to
    /// be one connected component if `connected` (see [`HalfedgeArrays::known_connected`]),
    /// with the F_F faces read when the arrays were computed, if they were.
    pub(crate) fn reverse_canonical(
        mut self,
        positions: &[DVec3],
        connected: bool,
        options: &ReverseOptions,
    ) -> Option<DooReversal> {
        let ff_faces = self.ff_faces.take();
        reverse_canonical_with(&self.view(positions).known_connected(connected), ff_faces, options)
    }

    /// The arrays with the vertex positions (`vertices` of them).
    pub(crate) fn view<'a>(&'a self, positions: &'a [DVec3]) -> HalfedgeArrays<'a> {
        HalfedgeArrays {
            to: &self.to,
            next: &self.next,
            face_of: &self.face_of,
            face_halfedge: &self.face_halfedge,
            positions,
            vertices: positions.len(),
            faces: self.face_halfedge.len(),
            connected: false,
        }
    }
}

/// The F_F faces of a canonical mesh and its coarse twins (see [`reverse_canonical`]).
#[derive(Debug, PartialEq)]
pub(crate) struct FfFaces {
    /// The F_F faces' corner ranges: fine vertex `c` is coarse corner `c`.
    offsets: Vec<u32>,
    /// The next corner of each corner in its F_F face.
    next: Vec<u32>,
    /// The coarse twin of each corner ([`NONE`] on the boundary).
    twins: Vec<u32>,
    /// The F_F face across each corner's edge ([`NONE`] on the boundary); empty when
    /// read from the layout (then found from the twins if needed).
    across: Vec<u32>,
    /// The number of F_E quads, the faces right after the F_F faces.
    quads: u32,
    on_boundary: bool,
    /// The F_F faces after the first that lie across no edge from an earlier one (when
    /// each of them lies across an edge from a face that does, the coarse mesh is
    /// connected without a search: see [`reaches_lower_in_two`]).
    unreached: Vec<u32>,
    /// Whether the half-edges are numbered as [`HalfedgeMesh::from_soup`] numbers those
    /// of a soup in the canonical order (see [`stream_ff_faces`]).
    layout: bool,
}

/// The F_F faces and the coarse twins of a mesh whose half-edges are laid out as
/// [`HalfedgeMesh::from_soup`] lays out a soup in the canonical order, checked in one
/// pass over the corners that reads the half-edge arrays in order; `None` at the first
/// entry off that layout (the walk of [`walk_ff_faces`] then decides).
///
/// `from_soup` numbers the edges in order of first appearance, side by side in corner
/// order, an edge's half-edges being `2e` (the first side met) and `2e + 1`. In the
/// canonical order of `V` fine vertices the F_F faces come first and share no edge, so
/// the side leaving corner `c` is half-edge `2c`, its twin `2c + 1` lies on an F_E quad
/// (or on the boundary). Quad `j`, `(c, next(t), t, next(c))` for its smaller corner
/// `c`, adds two edges, its sides `2V + 4j` (from `c`) and `2V + 4j + 2` (from `t`),
/// so that it is the 4-cycle `2V + 4j -> 2t + 1 -> 2V + 4j + 2 -> 2c + 1`; the F_V faces
/// add none: they are made of the quads' sides' twins `2V + 4j + 1` and `2V + 4j + 3`.
///
/// The checks made, and why they are the walk's:
/// - `to[2c + 1] == c` and `next[2c]` is `2c + 2` or, closing the face, twice its first
///   corner, the face's first half-edge: the F_F faces, in order (the mesh's own
///   invariants give the targets: a half-edge ends where its next one starts);
/// - `next[2c + 1]` is `2V + 4j` with `j` the number of quads claimed so far (corner `c`
///   claims quad `j`, whose `next[2V + 4j] = 2t + 1` names the twin `t > c` and whose
///   `next[2V + 4j + 2] = 2c + 1`), or `2V + 4j + 2` for a quad already claimed whose
///   `next[2V + 4j]` is `2c + 1` (corner `c` is its `t`, `next[2V + 4j + 2]` names the
///   twin): each quad is the 4-cycle above, its far side is the F_F side of the twin, the
///   twins are an involution, and the quads are claimed from their smaller corner in
///   corner order;
/// - the half-edges are exactly those (`4 * quads` after the `2V` of the F_F edges) and
///   face `ff + j` starts at `2V + 4j`: the quads are the faces right after the F_F
///   faces, in order, unrotated, and every face after them is made of the quads' sides'
///   twins.
///
/// A valid mesh is assumed (as `HalfedgeMesh` guarantees): `next` is a permutation
/// whose cycles are the faces and boundary loops.
fn stream_ff_faces(arrays: &HalfedgeArrays<'_>) -> Option<FfFaces> {
    let HalfedgeArrays { to, next, face_of, face_halfedge, vertices, faces, .. } = *arrays;
    let halfedges = to.len();
    if halfedges >= NONE as usize || halfedges < 2 * vertices || !(halfedges - 2 * vertices).is_multiple_of(4) {
        return None;
    }
    let all_quads = ((halfedges - 2 * vertices) / 4) as u32;
    let v2 = 2 * vertices as u32;
    let mut offsets = Vec::with_capacity(vertices / 3 + 2);
    offsets.push(0u32);
    let mut twins = advised_vec(vertices);
    let mut coarse_next = advised_vec(vertices);
    let mut quads = 0u32;
    let mut on_boundary = false;
    let mut unreached = Vec::new();
    // The current F_F face's first corner and its lowest twin.
    let mut start = 0u32;
    let mut lowest = NONE;
    for c in 0..vertices as u32 {
        let (h, hb) = (2 * c, 2 * c + 1);
        if to[hb as usize] != c {
            return None;
        }
        if face_of[hb as usize] == NONE {
            on_boundary = true;
            twins.push(NONE);
        } else {
            let slot = next[hb as usize].wrapping_sub(v2);
            let j = slot / 4;
            if j >= all_quads {
                return None;
            }
            let q = (v2 + (slot & !3)) as usize;
            let (n0, n2) = (next[q], next[q + 2]);
            let t = n0 / 2;
            match slot % 4 {
                0 => {
                    // `c` claims quad `j`: its far side is the twin's F_F side.
                    if j != quads || n2 != hb || n0 % 2 == 0 || t <= c || t as usize >= vertices {
                        return None;
                    }
                    quads += 1;
                    twins.push(t);
                }
                2 => {
                    // `c` is the larger corner of a quad claimed before (whose
                    // `next[q + 2]` was checked to be its smaller corner's twin side).
                    if j >= quads || n0 != hb {
                        return None;
                    }
                    let t = n2 / 2;
                    lowest = lowest.min(t);
                    twins.push(t);
                }
                _ => return None,
            }
        }
        let n = next[h as usize];
        if n == h + 2 {
            coarse_next.push(c + 1);
        } else {
            // The face closes here.
            let k = offsets.len() - 1;
            if n != 2 * start || k >= faces || face_halfedge[k] != 2 * start {
                return None;
            }
            if k > 0 && lowest >= start {
                unreached.push(k as u32);
            }
            offsets.push(c + 1);
            coarse_next.push(start);
            start = c + 1;
            lowest = NONE;
        }
    }
    let ff = offsets.len() - 1;
    if start as usize != vertices || quads != all_quads || ff + quads as usize > faces {
        return None;
    }
    let quad_faces = &face_halfedge[ff..ff + quads as usize];
    if !quad_faces.iter().zip((v2..).step_by(4)).all(|(&h, expected)| h == expected) {
        return None;
    }
    let next = coarse_next;
    Some(FfFaces { offsets, next, twins, across: Vec::new(), quads, on_boundary, unreached, layout: true })
}

/// The F_F faces and the coarse twins of a mesh in the canonical order, whatever its
/// half-edge numbering: one walk around each F_F face, through the F_E quad across each
/// edge (the checks of [`reverse_canonical`]); `None` at the first mismatch.
fn walk_ff_faces(arrays: &HalfedgeArrays<'_>) -> Option<FfFaces> {
    let HalfedgeArrays { to, next, face_of, face_halfedge, vertices, faces, .. } = *arrays;
    let mut offsets = Vec::with_capacity(vertices / 3 + 2);
    offsets.push(0u32);
    let mut twins = Vec::with_capacity(vertices);
    // The F_F face across each coarse edge (for the connectivity check).
    let mut across = Vec::with_capacity(vertices);
    let mut quads = 0u32;
    let mut quad_base = 0u32;
    let mut far_max = 0u32;
    let mut on_boundary = false;
    let mut unreached = Vec::new();
    let mut c = 0u32;
    while (c as usize) < vertices {
        let k = offsets.len() - 1;
        if k >= faces {
            return None;
        }
        let mut lowest_across = NONE;
        let first = face_halfedge[k];
        let start = c;
        if to[(first ^ 1) as usize] != start {
            return None;
        }
        let mut h = first;
        loop {
            // Corner `c` of the face, its half-edge `h` leaving vertex `c`.
            let hb = h ^ 1;
            let g = face_of[hb as usize];
            if g == NONE {
                on_boundary = true;
                twins.push(NONE);
                across.push(NONE);
            } else {
                let q1 = next[hb as usize];
                let hf = next[q1 as usize];
                let q3 = next[hf as usize];
                if next[q3 as usize] != hb || hf == hb {
                    // Not a 4-cycle.
                    return None;
                }
                let far_face = face_of[(hf ^ 1) as usize];
                if far_face == NONE {
                    return None;
                }
                let t = to[hf as usize];
                if t > c {
                    // The quad is claimed from its smaller corner, in corner order.
                    if quads == 0 {
                        quad_base = g;
                    } else if g != quad_base.wrapping_add(quads) {
                        return None;
                    }
                    if face_halfedge[g as usize] != q1 {
                        return None;
                    }
                    quads += 1;
                } else if t == c {
                    return None;
                }
                far_max = far_max.max(far_face);
                lowest_across = lowest_across.min(far_face);
                twins.push(t);
                across.push(far_face);
            }
            let target = to[h as usize];
            h = next[h as usize];
            c += 1;
            if h == first {
                if target != start {
                    return None;
                }
                break;
            }
            if target != c || c as usize >= vertices {
                return None;
            }
        }
        if k > 0 && lowest_across as usize >= k {
            unreached.push(k as u32);
        }
        offsets.push(c);
    }
    let ff = offsets.len() as u32 - 1;
    if far_max >= ff || (quads > 0 && quad_base != ff) {
        return None;
    }
    let next = next_of_corners(&offsets);
    Some(FfFaces { offsets, next, twins, across, quads, on_boundary, unreached, layout: false })
}

/// Whether F_F face `k` lies across an edge from a face that lies across an edge from a
/// face below `k`. If every face after the first lies across an edge from a face below it
/// or does this, the coarse mesh is connected: by induction on `k`, each face is joined
/// to face 0 (through a face below it, directly or through one neighbour).
fn reaches_lower_in_two(offsets: &[u32], twins: &[u32], next: &[u32], k: u32) -> bool {
    let (start, end) = (offsets[k as usize], offsets[k as usize + 1]);
    twins[start as usize..end as usize].iter().any(|&t| {
        if t == NONE {
            return false;
        }
        // Around the face of the twin.
        let mut x = t;
        loop {
            if twins[x as usize] < start {
                return true;
            }
            x = next[x as usize];
            if x == t {
                return false;
            }
        }
    })
}

/// Meshes of at least this many fine vertices are read on two threads when the pool has
/// them (below it, the tasks cost more than they save).
const PARALLEL_VERTICES: usize = 1 << 14;

/// Lists up to this long are checked for repeats by comparing their entries pairwise.
const SHORT: usize = 8;

/// Whether the `values` (each below `slots`, or [`NONE`]) are all different and none is
/// [`NONE`]: short lists pairwise, longer ones by marking each value's slot of `stamp`
/// (made on first use, `slots` long) with `mark`, which must differ between calls.
#[inline(always)]
pub(crate) fn distinct(values: &[u32], stamp: &mut Vec<u32>, slots: usize, mark: u32) -> bool {
    if values.len() <= SHORT {
        // Plain loops: they are inlined where iterator adaptors were not.
        for i in 0..values.len() {
            let v = values[i];
            if v == NONE {
                return false;
            }
            for &u in &values[..i] {
                if u == v {
                    return false;
                }
            }
        }
        return true;
    }
    if stamp.is_empty() {
        *stamp = vec![NONE; slots];
    }
    values.iter().all(|&v| v != NONE && std::mem::replace(&mut stamp[v as usize], mark) != mark)
}

/// The candidates of the coarse faces (`offsets`) whose corners are the fine vertices in
/// order (corner `c` at `positions[c]`): each face expanded straight from its slice of
/// the positions into fresh memory, in face order (on several threads it runs beside
/// [`coarse_vertices`]).
///
/// With `diagonal`, also the length of the bounding-box diagonal of all positions (the
/// scale of the automatic choice's zero test), on one thread from the slices while they
/// are in cache; else zero. Always the unit scale of the positions read
/// ([`mesh_topo::scale::unit_scale`], measured on the way), so that the caller's check of
/// the scale needs no pass of its own.
fn expand_in_order(offsets: &[u32], maps: &FaceMaps, positions: &[DVec3], diagonal: bool) -> Expanded {
    let corners = offsets.last().map_or(0, |&n| n as usize);
    // Every fine vertex is a corner of one F_F face: the unit scale is that of all of them.
    debug_assert_eq!(corners, positions.len(), "internal: the F_F faces hold every vertex");
    let mut out = advised_vec(corners);
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let mut magnitudes = DVec3::ZERO;
    for w in offsets.windows(2) {
        let (b, e) = (w[0] as usize, w[1] as usize);
        out.resize(e, DVec3::ZERO);
        let face = &positions[b..e];
        maps.inverse(face, &mut out[b..e]);
        for &p in face {
            magnitudes = fold_magnitudes(magnitudes, p);
        }
        if diagonal {
            for &p in face {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
    }
    Expanded {
        candidates: out,
        diagonal: if diagonal { (hi - lo).length() } else { 0.0 },
        unit_scale: unit_scale_of_magnitudes(magnitudes),
    }
}

/// What [`expand_in_order`] finds.
struct Expanded {
    /// The candidates, corner by corner.
    candidates: Vec<DVec3>,
    /// The bounding-box diagonal of the positions read, or zero.
    diagonal: f64,
    /// The unit scale of the positions read.
    unit_scale: f64,
}

/// Whether the coarse faces (`offsets`) form one component across the coarse edges
/// (`twins`: each corner's coarse twin, or [`NONE`]; `face_across(c, t)`: the face of
/// corner `c`'s twin `t`). A union-find over the faces that reads the corners in order,
/// each edge once (from its smaller corner), with one scattered read per edge (the face
/// across) into a forest of one entry per face; each joined pair of components is
/// counted, so that one component remains when `faces - 1` pairs were joined. (Not a
/// search from one face: its visits jump about the whole mesh.)
fn connected(offsets: &[u32], twins: &[u32], face_across: impl Fn(usize, u32) -> u32) -> bool {
    let faces = offsets.len() - 1;
    let mut parent: Vec<u32> = (0..faces as u32).collect();
    // The root of `f`'s tree, halving the path on the way up.
    let root = |parent: &mut [u32], mut f: u32| {
        while parent[f as usize] != f {
            let grandparent = parent[parent[f as usize] as usize];
            parent[f as usize] = grandparent;
            f = grandparent;
        }
        f
    };
    let mut joined = 0;
    for (f, w) in offsets.windows(2).enumerate() {
        let (start, end) = (w[0] as usize, w[1] as usize);
        for (c, &t) in (start..).zip(&twins[start..end]) {
            if t == NONE || (t as usize) < c {
                continue;
            }
            let (a, b) = (root(&mut parent, f as u32), root(&mut parent, face_across(c, t)));
            if a != b {
                // The smaller root stays a root.
                parent[a.max(b) as usize] = a.min(b);
                joined += 1;
            }
        }
    }
    joined + 1 == faces
}

/// The F_V faces of a closed mesh with the layout of [`stream_ff_faces`], read in one
/// pass over the quads instead of a walk around each: the new sides of quad `j`,
/// half-edges `2V + 4j` and `2V + 4j + 2`, end at the corners whose F_V faces hold their
/// twins. Every half-edge is an F_F side (`V` of them), a quad side (4 per quad) or an
/// F_V side: with `V + 6 * quads` half-edges and every quad twin on an F_V face, the quad
/// twins are all the F_V sides, and a corner labelled twice or a count of `2 * quads`
/// other than `V` is a mismatch. Returns each corner's F_V face (the coarse vertex), each
/// face's first corner, the face sizes and each vertex's corners in increasing order (a
/// counting sort of the corners by label); `None` on any mismatch (the walk then
/// decides), including a face of fewer than 3 sides or one that does not start at its
/// smallest corner (which the walk checks as it goes).
fn stream_fv_faces(arrays: &HalfedgeArrays<'_>, fv_first: usize, quads: usize) -> Option<StreamedFvFaces> {
    let HalfedgeArrays { to, face_of, face_halfedge, vertices, faces, .. } = *arrays;
    let fv_count = faces - fv_first;
    if to.len() != vertices + 6 * quads || 2 * quads != vertices {
        return None;
    }
    let mut labels = filled_vec(vertices, NONE);
    let mut ends = filled_vec(vertices, NONE);
    // Quad `j` of the layout, `(c, next(t), t, next(c))`: its sides `c -> next(t)` and
    // `t -> next(c)`, each followed by its twin (which ends at `c`, resp. `t`).
    let quad_sides = to[2 * vertices..].chunks_exact(4).zip(face_of[2 * vertices..].chunks_exact(4));
    for (sides, twin_faces) in quad_sides {
        // The twins' faces (NONE on the boundary wraps to a large index): the F_V faces of
        // `c` and `next(t)`, and of `t` and `next(c)`.
        let i = (twin_faces[1] as usize).wrapping_sub(fv_first);
        let k = (twin_faces[3] as usize).wrapping_sub(fv_first);
        if i >= fv_count || std::mem::replace(&mut labels[sides[0] as usize], i as u32) != NONE {
            return None;
        }
        if k >= fv_count || std::mem::replace(&mut labels[sides[2] as usize], k as u32) != NONE {
            return None;
        }
        // The far end of the coarse edge from `c` is the vertex of `next(c)`, and from `t`
        // that of `next(t)`.
        ends[sides[1] as usize] = k as u32;
        ends[sides[3] as usize] = i as u32;
    }
    // As many F_V sides as corners, none labelled twice: every corner is labelled once.
    let (offsets, corners) = group_by_key(&labels, fv_count);
    let sizes: Vec<u32> = offsets.windows(2).map(|w| w[1] - w[0]).collect();
    let first_corners: Vec<u32> = face_halfedge[fv_first..].iter().map(|&h| to[(h ^ 1) as usize]).collect();
    let starts_at_smallest = offsets.iter().zip(&first_corners).all(|(&b, &x)| corners[b as usize] == x);
    if sizes.iter().any(|&m| m < 3) || !starts_at_smallest {
        return None;
    }
    let by_vertex = CornersByVertex::from_parts((offsets, corners));
    Some(StreamedFvFaces { labels, first_corners, sizes, by_vertex, ends })
}

/// What [`stream_fv_faces`] reads.
struct StreamedFvFaces {
    labels: Vec<u32>,
    first_corners: Vec<u32>,
    sizes: Vec<u32>,
    by_vertex: CornersByVertex,
    /// The coarse vertex at the far end of each corner's coarse edge (the vertex of its
    /// next corner), from the quads ([`NONE`] for a corner on no quad).
    ends: Vec<u32>,
}

/// The corners of each coarse vertex in increasing order when every vertex is interior:
/// vertex `i` has the corners of F_V face `i` (of sizes `sizes`, corners `corners`,
/// sorted in place).
fn by_vertex_of_fv_faces(sizes: &[u32], mut corners: Vec<u32>) -> CornersByVertex {
    let mut offsets = Vec::with_capacity(sizes.len() + 1);
    offsets.push(0u32);
    let mut b = 0;
    for &m in sizes {
        let e = b + m as usize;
        insertion_sort(&mut corners[b..e]);
        offsets.push(e as u32);
        b = e;
    }
    CornersByVertex::from_parts((offsets, corners))
}

/// The F_V faces of a canonical mesh: faces `first..` and their sizes.
struct FvFaces<'a> {
    first: usize,
    sizes_of: &'a [u32],
}

/// The error the general search meets on the edges of face `quad` read as an F_F face
/// (the first checks it makes, in the same order, with the same roles: each face across
/// must be a quad whose far side has a face, no face may be both an F_F face and a quad),
/// and the number of edges it crossed up to it (its statistics), or `None` when every edge
/// passes and the search would go on beyond them (the general path then runs it).
/// `size_of`: the number of sides of each face.
fn quad_seed_error(
    arrays: &HalfedgeArrays<'_>,
    quad: usize,
    size_of: impl Fn(usize) -> usize,
) -> Option<(DooError, usize)> {
    let HalfedgeArrays { next, face_of, face_halfedge, .. } = *arrays;
    // The faces the search has given a role so far: (face, whether it is an F_F face).
    let mut roles = vec![(quad, true)];
    let role_of = |roles: &[(usize, bool)], face: usize| roles.iter().find(|r| r.0 == face).map(|r| r.1);
    let first = face_halfedge[quad];
    let mut h = first;
    let mut crossed = 0;
    loop {
        crossed += 1;
        let twin = (h ^ 1) as usize;
        if face_of[twin] != NONE {
            let g = face_of[twin] as usize;
            let sides = size_of(g);
            if sides != 4 {
                return Some((not_a_quad(quad, g, sides), crossed));
            }
            let far = next[next[twin] as usize];
            let beyond = face_of[(far ^ 1) as usize];
            if beyond == NONE {
                return Some((quad_on_boundary(quad, g), crossed));
            }
            match role_of(&roles, g) {
                Some(true) => return Some((ff_faces_share_an_edge(quad, g), crossed)),
                Some(false) => {}
                None => roles.push((g, false)),
            }
            let beyond = beyond as usize;
            match role_of(&roles, beyond) {
                Some(false) => return Some((quad_read_as_ff_face(beyond, g), crossed)),
                Some(true) => {}
                None => roles.push((beyond, true)),
            }
        }
        h = next[h as usize];
        if h == first {
            return None;
        }
    }
}

/// The automatic choice of the general path on a closed canonical mesh, made as it makes
/// it (the same readings in the same order, the same sums in the same order, the same
/// report): the lowest face as F_F (`energy`, summed by the caller over its groups, the
/// F_V faces), then, unless its details are all zero, the lowest F_F face of the dual
/// reading, and the lowest F_E quad as F_F (rejected by its own edges, see
/// [`quad_seed_error`]: a face across one of them is not a quad, as on every mesh refined
/// from one with a face or a vertex of degree other than 4). The dual reading (the lowest
/// F_V face as F_F: valid on a closed connected mesh) groups its candidates by the F_F
/// faces; its sum runs over them
/// in face order, each F_V face expanded when a group first needs it, and stops as soon
/// as it reaches `energy` (the dual reading cannot win then), so that a mesh whose
/// details are small in its first reading expands only a few F_V faces. `None` when the
/// F_E reading needs the full search, or when the dual reading wins (the general path
/// builds it).
///
/// `coarse`: the coarse mesh of the first reading (interior vertex `i` is F_V face `i`);
/// `scale`: the bounding-box diagonal of all vertices (the scale of the zero test);
/// `dual`: scratch, one entry per fine vertex. With the choice, the number of edges the
/// rejected F_E search crossed (the general path's statistics count them).
fn automatic(
    arrays: &HalfedgeArrays<'_>,
    maps: &FaceMaps,
    coarse: &CornerMesh,
    energy: f64,
    scale: f64,
    fv: &FvFaces<'_>,
    mut dual: Vec<DVec3>,
) -> Option<(SeedChoice, usize)> {
    let (ff_offsets, coarse_vertex) = (&coarse.offsets[..], &coarse.corner_vertex[..]);
    let ff_count = ff_offsets.len() - 1;
    let (faces, positions) = (arrays.faces, arrays.positions);
    let mut trials = vec![SeedTrial::valid(0, "F_F", energy, false)];
    if details_are_zero(energy, scale, faces) {
        let reason = zero_details_reason(0);
        return Some((SeedChoice::automatic(0, 0, trials, energy, reason), 0));
    }
    // The lowest F_E quad as F_F: rejected by its own edges, or left to the general path.
    let quad = ff_count;
    debug_assert!(fv.first > quad, "internal: the automatic choice needs F_E quads");
    let size_of = |g: usize| match g {
        _ if g >= fv.first => fv.sizes_of[g - fv.first] as usize,
        _ if g >= ff_count => 4,
        _ => (ff_offsets[g + 1] - ff_offsets[g]) as usize,
    };
    let (quad_error, quad_crossings) = quad_seed_error(arrays, quad, size_of)?;
    // The dual reading: its candidates are the F_V faces expanded (every vertex is on
    // one F_V face), its groups the F_F faces.
    debug_assert_eq!(dual.len(), positions.len());
    let reading = DualReading { arrays: *arrays, maps, positions, ff_offsets, coarse_vertex, fv };
    let mut dual_energy = 0.0;
    let mut stopped = false;
    if rayon::current_num_threads() > 1 && positions.len() >= PARALLEL_VERTICES {
        drop(dual);
        (dual_energy, stopped) = reading.sum_in_pairs(energy);
    } else {
        reading.groups(0..ff_count, &mut dual, |group_energy| {
            dual_energy += group_energy;
            stopped = dual_energy >= energy;
            !stopped
        });
    }
    if !stopped {
        // The dual reading is better.
        return None;
    }
    let fv_seed = fv.first;
    trials.push(SeedTrial::valid(fv_seed, "F_V", dual_energy, true));
    trials.push(SeedTrial::invalid(quad, "F_E", &quad_error));
    let reason = ranking_reason(energy, &[(fv_seed, dual_energy, true)]);
    Some((SeedChoice::automatic(0, 0, trials, energy, reason), quad_crossings))
}

/// The automatic choice of the general path on an open canonical mesh (one with F_E
/// quads and F_V faces), made as it makes it: the lowest face as F_F (the first reading,
/// valid), then, unless its details are all zero, the lowest F_V face and the lowest F_E
/// quad as F_F, in that order. On an open mesh these usually fail within a few faces of
/// their seed (the F_E quads of the dual reading meet the boundary): each search is
/// replayed on the half-edge arrays ([`search_fails`]), for the same error and the same
/// counters. `None` if one of them does not fail (the general path ranks the readings).
///
/// `energy`: the first reading's detail energy (the general path sums its groups in the
/// result's vertex order); `scale`: the bounding-box diagonal of all vertices; the F_E
/// quads start at face `ff_count`, the F_V faces at `fv_first`. Returns the choice and
/// the counters of the search (without `candidate_edges`).
fn automatic_open(
    arrays: &HalfedgeArrays<'_>,
    energy: f64,
    scale: f64,
    ff_count: usize,
    fv_first: usize,
) -> Option<(SeedChoice, ReverseStats)> {
    let mut stats = ReverseStats {
        visited_faces: ff_count,
        edges_crossed: arrays.vertices,
        candidate_edges: 0,
        interpretations: 1,
    };
    let mut trials = vec![SeedTrial::valid(0, "F_F", energy, false)];
    let reason = if details_are_zero(energy, scale, arrays.faces) {
        zero_details_reason(0)
    } else {
        for (seed, class) in [(fv_first, "F_V"), (ff_count, "F_E")] {
            let (error, visited, crossed) = search_fails(arrays, seed)?;
            stats.visited_faces += visited;
            stats.edges_crossed += crossed;
            trials.push(SeedTrial::invalid(seed, class, &error));
        }
        only_valid_reason(0)
    };
    Some((SeedChoice::automatic(0, 0, trials, energy, reason), stats))
}

/// The breadth-first search of the general path from `seed` as an F_F face, replayed on
/// the half-edge arrays (the corners of a face are its half-edges from its first one;
/// see `Search::classify`): the error it stops at, with the faces it visited and the
/// edges it crossed, or `None` if it does not stop.
fn search_fails(arrays: &HalfedgeArrays<'_>, seed: usize) -> Option<(DooError, usize, usize)> {
    let HalfedgeArrays { next, face_of, face_halfedge, faces, .. } = *arrays;
    let mut role = vec![0u8; faces];
    role[seed] = FF;
    let mut queue = vec![seed as u32];
    let (mut visited, mut crossed) = (0, 0);
    let mut head = 0;
    while let Some(&f) = queue.get(head) {
        head += 1;
        visited += 1;
        let f = f as usize;
        let start = face_halfedge[f];
        let mut h = start;
        loop {
            crossed += 1;
            let g = face_of[(h ^ 1) as usize];
            if g != NONE {
                let g = g as usize;
                // The quad across, its opposite edge, and the face beyond.
                let mut sides = 1;
                let mut x = next[(h ^ 1) as usize];
                while x != h ^ 1 {
                    sides += 1;
                    x = next[x as usize];
                }
                if sides != 4 {
                    return Some((not_a_quad(f, g, sides), visited, crossed));
                }
                let far = next[next[(h ^ 1) as usize] as usize];
                let beyond = face_of[(far ^ 1) as usize];
                if beyond == NONE {
                    return Some((quad_on_boundary(f, g), visited, crossed));
                }
                if role[g] == FF {
                    return Some((ff_faces_share_an_edge(f, g), visited, crossed));
                }
                role[g] = FE;
                let beyond = beyond as usize;
                match role[beyond] {
                    FE => return Some((quad_read_as_ff_face(beyond, g), visited, crossed)),
                    FF => {}
                    _ => {
                        role[beyond] = FF;
                        queue.push(beyond as u32);
                    }
                }
            }
            h = next[h as usize];
            if h == start {
                break;
            }
        }
    }
    None
}

/// The F_F faces of the dual reading at or above which [`DualReading::sum_in_pairs`]
/// splits its sum (each piece expands again the F_V faces it shares with the previous
/// one: pieces of many rows of faces keep that small).
const DUAL_PIECE: usize = 1 << 12;

/// The dual reading of a closed canonical mesh (the lowest F_V face as F_F): its
/// candidates are the F_V faces expanded, its groups the F_F faces (see [`automatic`]).
struct DualReading<'a> {
    arrays: HalfedgeArrays<'a>,
    maps: &'a FaceMaps,
    positions: &'a [DVec3],
    /// The F_F faces' corner ranges.
    ff_offsets: &'a [u32],
    /// The first reading's coarse vertex of each corner (its F_V face).
    coarse_vertex: &'a [u32],
    fv: &'a FvFaces<'a>,
}

impl DualReading<'_> {
    /// The detail energies of the groups `faces` (F_F faces), in face order, each handed
    /// to `take` until it returns `false`. Each F_V face is expanded when a group first
    /// needs it; `dual` holds the candidates of the corners of `faces` (from the first
    /// one on).
    fn groups(&self, faces: std::ops::Range<usize>, dual: &mut [DVec3], mut take: impl FnMut(f64) -> bool) {
        let Self { ref arrays, maps, positions, ff_offsets, coarse_vertex, fv } = *self;
        let HalfedgeArrays { to, next, face_halfedge, .. } = *arrays;
        let base = ff_offsets[faces.start] as usize;
        debug_assert_eq!(dual.len(), ff_offsets[faces.end] as usize - base);
        let mut expanded = vec![false; fv.sizes_of.len()];
        // Faces of up to [`SHORT`] sides are gathered on the stack (no growing push in the
        // gathering loop, whose bounds then stay in registers).
        let (mut short_points, mut short_expanded) = ([DVec3::ZERO; SHORT], [DVec3::ZERO; SHORT]);
        let (mut long_points, mut long_expanded) = (Vec::new(), Vec::new());
        let (mut short_face, mut long_face) = ([NONE; SHORT], Vec::new());
        let mut group_corners = Vec::new();
        for w in ff_offsets[faces.start..=faces.end].windows(2) {
            let (b, e) = (w[0] as usize, w[1] as usize);
            for &u in &coarse_vertex[b..e] {
                if std::mem::replace(&mut expanded[u as usize], true) {
                    continue;
                }
                // The face's corners in its own order (the walk of [`reverse_canonical`]).
                let m = fv.sizes_of[u as usize] as usize;
                let (points, out, face) = if m <= SHORT {
                    (&mut short_points[..m], &mut short_expanded[..m], &mut short_face[..m])
                } else {
                    long_points.resize(m, DVec3::ZERO);
                    long_expanded.resize(m, DVec3::ZERO);
                    long_face.resize(m, NONE);
                    (&mut long_points[..], &mut long_expanded[..], &mut long_face[..])
                };
                let first = face_halfedge[fv.first + u as usize];
                let mut h = first;
                for (slot, corner) in points.iter_mut().zip(face.iter_mut()) {
                    let v = to[(h ^ 1) as usize];
                    *corner = v;
                    *slot = positions[v as usize];
                    h = next[h as usize];
                }
                debug_assert_eq!(h, first, "internal: an F_V face has its counted size");
                maps.inverse(points, out);
                for (&v, &p) in face.iter().zip(out.iter()) {
                    // Only the corners of `faces` are kept (the others, of an F_V face
                    // shared with the faces before or after, are found again there).
                    let i = (v as usize).wrapping_sub(base);
                    if i < dual.len() {
                        dual[i] = p;
                    }
                }
            }
            // Summed in the order of the dual reading's coarse corners, which number the F_V
            // faces' corners in face order: by F_V face, as no face has two corners on one.
            let group_energy =
                dual_group_energy(&mut group_corners, b as u32..e as u32, coarse_vertex, dual, base as u32);
            if !take(group_energy) {
                break;
            }
        }
    }

    /// The dual reading's sum on two threads, until it reaches `energy`: the groups in
    /// pieces of [`DUAL_PIECE`] faces or more, two at a time, the first summed on from the
    /// total so far and stopped where it reaches `energy`, the second's energies kept (and
    /// given up as soon as the first stops) to be added after it. The same values are added
    /// in the same order and the sum stops at the same group as on one thread. Returns the
    /// sum and whether it reached `energy`.
    fn sum_in_pairs(&self, energy: f64) -> (f64, bool) {
        let faces = self.ff_offsets.len() - 1;
        let piece = (faces / 16).max(DUAL_PIECE);
        let corners =
            |range: &std::ops::Range<usize>| (self.ff_offsets[range.end] - self.ff_offsets[range.start]) as usize;
        let halt = AtomicBool::new(false);
        let mut total = 0.0;
        let mut start = 0;
        while start < faces {
            let first = start..(start + piece).min(faces);
            let second = first.end..(first.end + piece).min(faces);
            start = second.end;
            let ((sum, reached), later) = rayon::join(
                || {
                    let mut dual = vec![DVec3::ZERO; corners(&first)];
                    let (mut sum, mut reached) = (total, false);
                    self.groups(first.clone(), &mut dual, |group_energy| {
                        sum += group_energy;
                        reached = sum >= energy;
                        if reached {
                            halt.store(true, Ordering::Relaxed);
                        }
                        !reached
                    });
                    (sum, reached)
                },
                || {
                    let mut energies = Vec::with_capacity(second.len());
                    if !second.is_empty() {
                        let mut dual = vec![DVec3::ZERO; corners(&second)];
                        self.groups(second.clone(), &mut dual, |group_energy| {
                            energies.push(group_energy);
                            !halt.load(Ordering::Relaxed)
                        });
                    }
                    energies
                },
            );
            total = sum;
            if reached {
                return (total, true);
            }
            // The first piece did not stop, so the second was not given up.
            debug_assert_eq!(later.len(), second.len(), "internal: the second piece is complete");
            for group_energy in later {
                total += group_energy;
                if total >= energy {
                    return (total, true);
                }
            }
        }
        (total, false)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::reverse::reverse_corner_mesh;
    use crate::{DooOptions, FaceRule, subdivide_soup};
    use mesh_topo::shapes::{self, CellKind};
    use mesh_topo::{PolygonSoup, testing::scramble};

    fn general(fine: &HalfedgeMesh, options: &ReverseOptions) -> DooReversal {
        reverse_corner_mesh(&CornerMesh::from_halfedge(fine), fine.positions(), options).unwrap()
    }

    fn refine(soup: &PolygonSoup, rule: FaceRule) -> HalfedgeMesh {
        let mut fine = subdivide_soup(soup, &DooOptions::new(rule, 1)).unwrap().to_mesh().unwrap();
        for (i, p) in fine.positions_mut().iter_mut().enumerate() {
            p.x += 1e-3 * ((i * 7919) % 13) as f64;
        }
        fine
    }

    /// A closed prism over a regular `n`-gon: two caps of `n` sides and `n` quads.
    fn prism(n: u32) -> PolygonSoup {
        let angle = |i: u32| std::f64::consts::TAU * i as f64 / n as f64;
        let positions = (0..2 * n)
            .map(|i| DVec3::new(angle(i % n).cos(), angle(i % n).sin(), (i / n) as f64 + 0.01 * i as f64))
            .collect();
        let mut faces = vec![(0..n).rev().collect::<Vec<u32>>(), (n..2 * n).collect()];
        faces.extend((0..n).map(|i| vec![i, (i + 1) % n, n + (i + 1) % n, n + i]));
        PolygonSoup::from_faces(positions, faces)
    }

    #[test]
    fn a_canonical_mesh_gives_the_general_result() {
        let soups = [
            shapes::cube(),
            shapes::torus(7, 5, CellKind::Triangles).unwrap(),
            shapes::torus(6, 4, CellKind::Mixed).unwrap(),
            shapes::grid(4, 3, CellKind::Quads).unwrap(),
            shapes::grid(5, 4, CellKind::Mixed).unwrap(),
            // Caps of 10 sides (the general circulant) and of 20 (above `DENSE_MAX`: the
            // O(m) forms of the inverse map).
            prism(10),
            prism(20),
        ];
        let mut automatic = 0;
        for soup in &soups {
            for rule in [FaceRule::DooSabin, FaceRule::Simple, FaceRule::CENTROID_HALF] {
                let fine = refine(soup, rule);
                for seed in [0, 1, soup.face_count() - 1] {
                    let options = ReverseOptions::with_seed(rule, seed);
                    let fast = reverse_canonical(&fine, &options).expect("canonical order");
                    assert_eq!(fast, general(&fine, &options), "seed {seed}");
                }
                // Not an F_F face: the general path decides.
                let quad = soup.face_count();
                assert!(reverse_canonical(&fine, &ReverseOptions::with_seed(rule, quad)).is_none());
                // No seed: the same choice as the general path's, when this path makes it.
                let auto = ReverseOptions::auto(rule);
                if let Some(fast) = reverse_canonical(&fine, &auto) {
                    assert_eq!(fast, general(&fine, &auto));
                    automatic += 1;
                }
                let exact = subdivide_soup(soup, &DooOptions::new(rule, 1)).unwrap().to_mesh().unwrap();
                if let Some(fast) = reverse_canonical(&exact, &auto) {
                    assert_eq!(fast, general(&exact, &auto));
                    assert_eq!(fast.choices()[0].trials.len(), 1);
                    automatic += 1;
                }
            }
        }
        // The closed meshes that are not all quads: cube (dual reading tried) and torus.
        assert!(automatic >= 4, "{automatic}");
    }

    /// `soup` without the faces `removed` (an open mesh).
    pub(crate) fn without(soup: &PolygonSoup, removed: &[usize]) -> PolygonSoup {
        let faces = soup.faces().enumerate().filter(|(f, _)| !removed.contains(f)).map(|(_, face)| face.to_vec());
        PolygonSoup::from_faces(soup.positions.clone(), faces)
    }

    #[test]
    fn an_open_canonical_mesh_gives_the_general_choice() {
        let torus = shapes::torus(8, 6, CellKind::Quads).unwrap();
        let soups = [
            shapes::grid(4, 3, CellKind::Quads).unwrap(),
            shapes::grid(6, 5, CellKind::Triangles).unwrap(),
            shapes::grid(5, 7, CellKind::Mixed).unwrap(),
            without(&shapes::cube(), &[2]),
            without(&torus, &[0, 28]),
            without(&shapes::icosahedron(), &[0]),
        ];
        for soup in &soups {
            for rule in [FaceRule::DooSabin, FaceRule::Simple, FaceRule::CENTROID_HALF] {
                let auto = ReverseOptions::auto(rule);
                let exact = subdivide_soup(soup, &DooOptions::new(rule, 1)).unwrap().to_mesh().unwrap();
                for fine in [refine(soup, rule), exact] {
                    assert!(fine.vertices().any(|v| fine.is_boundary_vertex(v)));
                    let fast = reverse_canonical(&fine, &auto).expect("an open mesh in the canonical order");
                    let general = general(&fine, &auto);
                    // The same reversal, choice, trials (errors word for word) and counters.
                    assert_eq!(fast, general);
                    // Face 0 as F_F; unless its details are zero, the dual reading and the
                    // F_E reading tried and refused.
                    let choice = &fast.choices()[0];
                    assert_eq!((choice.seed_face, choice.trials[0].class.as_str()), (0, "F_F"));
                    // The winner's sum is the result's detail energy, bit for bit.
                    assert_eq!(choice.trials[0].outcome, Ok(choice.detail_energy));
                    let classes: Vec<&str> = choice.trials[1..].iter().map(|t| t.class.as_str()).collect();
                    assert!(classes.is_empty() || classes == ["F_V", "F_E"], "{choice:?}");
                    assert!(choice.trials[1..].iter().all(|t| t.outcome.is_err()), "{choice:?}");
                }
            }
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(48))]
        /// Random open meshes (grids and tori with faces removed, every face rule, moved
        /// vertices): the automatic choice on the canonical path is the general path's.
        #[test]
        fn open_meshes_give_the_general_choice(
            width in 1u32..7,
            height in 1u32..6,
            kind in 0usize..3,
            torus in proptest::bool::ANY,
            removed in proptest::collection::vec(0usize..200, 0..4),
            rule in 0usize..3,
            shift in -1.0f64..1.0,
        ) {
            let kind = [CellKind::Quads, CellKind::Triangles, CellKind::Mixed][kind];
            let rule = [FaceRule::DooSabin, FaceRule::Simple, FaceRule::CENTROID_HALF][rule];
            let soup = if torus {
                shapes::torus(width + 2, height + 2, kind).unwrap()
            } else {
                shapes::grid(width, height, kind).unwrap()
            };
            let removed: Vec<usize> = removed.iter().map(|&f| f % soup.face_count()).collect();
            let soup = without(&soup, &removed);
            // Only manifold meshes with faces left, without isolated vertices.
            proptest::prop_assume!(soup.face_count() > 0);
            let Ok(coarse) = HalfedgeMesh::from_soup(&soup) else { return Ok(()) };
            proptest::prop_assume!(coarse.vertices().all(|v| coarse.vertex_halfedge(v).is_some()));
            let mut fine = subdivide_soup(&soup, &DooOptions::new(rule, 1)).unwrap().to_mesh().unwrap();
            for (i, p) in fine.positions_mut().iter_mut().enumerate() {
                p.z += shift * 1e-2 * ((i * 31) % 7) as f64;
            }
            let auto = ReverseOptions::auto(rule);
            if let Some(fast) = reverse_canonical(&fine, &auto) {
                proptest::prop_assert_eq!(fast, general(&fine, &auto));
            }
        }
    }

    #[test]
    fn the_dual_reading_stops_once_it_cannot_win() {
        // Moved vertices: the first reading has small details, the dual one larger.
        let soup = shapes::torus(7, 5, CellKind::Triangles).unwrap();
        let fine = refine(&soup, FaceRule::DooSabin);
        let auto = ReverseOptions::auto(FaceRule::DooSabin);
        let fast = reverse_canonical(&fine, &auto).expect("the first reading wins");
        assert_eq!(fast, general(&fine, &auto));
        let choice = &fast.choices()[0];
        // The winner's sum is the detail energy of the result, bit for bit.
        assert_eq!(choice.trials[0].outcome, Ok(choice.detail_energy));
        let dual = &choice.trials[1];
        assert!(dual.stopped_early && dual.class == "F_V", "{dual:?}");
        assert!(!choice.trials[0].stopped_early && !choice.trials[2].stopped_early);
        // The partial sum has reached the winner's and is at most the dual reading's total.
        let partial = *dual.outcome.as_ref().unwrap();
        let whole = general(&fine, &ReverseOptions::with_seed(FaceRule::DooSabin, dual.seed_face));
        let total = whole.choices()[0].detail_energy;
        assert!(choice.detail_energy <= partial && partial <= total, "{partial} {total} {choice:?}");
        assert!(choice.reason.contains(&format!("at least {partial:.6e}")), "{}", choice.reason);
        // Only the winner counts as evaluated in full; both readings were searched.
        assert_eq!(fast.stats().interpretations, 1);
    }

    #[test]
    fn two_threads_give_the_one_thread_result() {
        // Above `PARALLEL_VERTICES`: the coarse vertices beside the expansion, the means in
        // two halves, and (automatic mode) the dual sum in pieces.
        let closed = refine(&shapes::torus(96, 48, CellKind::Triangles).unwrap(), FaceRule::DooSabin);
        let open = refine(&shapes::grid(100, 60, CellKind::Quads).unwrap(), FaceRule::DooSabin);
        assert!(closed.vertex_count() >= PARALLEL_VERTICES && open.vertex_count() >= PARALLEL_VERTICES);
        let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
        let two = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        for (fine, options) in [
            (&closed, ReverseOptions::auto(FaceRule::DooSabin)),
            (&closed, ReverseOptions::with_seed(FaceRule::DooSabin, 5)),
            (&open, ReverseOptions::with_seed(FaceRule::DooSabin, 0)),
            (&open, ReverseOptions::auto(FaceRule::DooSabin)),
        ] {
            let parallel = two.install(|| reverse_canonical(fine, &options)).expect("canonical order");
            assert_eq!(parallel, one.install(|| reverse_canonical(fine, &options)).unwrap());
            assert_eq!(parallel, general(fine, &options));
        }
    }

    #[test]
    fn the_dual_sum_in_pairs_stops_where_the_sum_in_order_stops() {
        // Pieces of at least `DUAL_PIECE` faces: a torus of several pieces.
        let soup = shapes::torus(96, 48, CellKind::Triangles).unwrap();
        let fine = refine(&soup, FaceRule::DooSabin);
        let ff = stream_ff_faces(&HalfedgeArrays::of(&fine)).expect("the layout of a canonical mesh");
        let (offsets, quads) = (ff.offsets.clone(), ff.quads as usize);
        let faces = offsets.len() - 1;
        assert!(faces > 2 * DUAL_PIECE, "{faces}");
        let arrays = HalfedgeArrays::of(&fine);
        let fv_first = faces + quads;
        let streamed = stream_fv_faces(&arrays, fv_first, quads).expect("closed");
        let fv = FvFaces { first: fv_first, sizes_of: &streamed.sizes };
        let maps = FaceMaps::new(FaceRule::DooSabin);
        let reading = DualReading {
            arrays: HalfedgeArrays::of(&fine),
            maps: &maps,
            positions: fine.positions(),
            ff_offsets: &offsets,
            coarse_vertex: &streamed.labels,
            fv: &fv,
        };
        // Every group's energy in order, on one thread.
        let mut all = Vec::new();
        reading.groups(0..faces, &mut vec![DVec3::ZERO; fine.vertex_count()], |e| {
            all.push(e);
            true
        });
        assert_eq!(all.len(), faces);
        let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
        // Thresholds reached in the first piece, in the second piece of the first pair, in
        // a later pair, at the last group, and never.
        for stop in [10, DUAL_PIECE + 7, 2 * DUAL_PIECE + 100, faces - 1] {
            let energy = all[..=stop].iter().sum::<f64>();
            // The first group at which the sum in order reaches `energy`.
            let mut sum = 0.0;
            let at = all.iter().position(|&e| {
                sum += e;
                sum >= energy
            });
            let expected = all[..=at.unwrap()].iter().sum::<f64>();
            assert_eq!(pool.install(|| reading.sum_in_pairs(energy)), (expected, true), "{stop}");
        }
        let total = all.iter().sum::<f64>();
        assert_eq!(pool.install(|| reading.sum_in_pairs(f64::INFINITY)), (total, false));
    }

    #[test]
    fn the_layout_pass_reads_what_the_walk_finds() {
        let soups = [
            shapes::cube(),
            shapes::tetrahedron(),
            shapes::torus(7, 5, CellKind::Triangles).unwrap(),
            shapes::torus(6, 4, CellKind::Mixed).unwrap(),
            shapes::grid(4, 3, CellKind::Quads).unwrap(),
            shapes::grid(5, 4, CellKind::Mixed).unwrap(),
        ];
        for soup in &soups {
            let fine = refine(soup, FaceRule::DooSabin);
            let streamed = stream_ff_faces(&HalfedgeArrays::of(&fine)).expect("the layout of a canonical mesh");
            let walked = walk_ff_faces(&HalfedgeArrays::of(&fine)).expect("a canonical mesh");
            assert!(streamed.layout && !walked.layout);
            assert_eq!(streamed.offsets, walked.offsets);
            assert_eq!(streamed.next, walked.next);
            assert_eq!(streamed.twins, walked.twins);
            assert_eq!(streamed.quads, walked.quads);
            assert_eq!(streamed.on_boundary, walked.on_boundary);
            assert_eq!(streamed.unreached, walked.unreached);
            // The face across each corner, as the connectivity check reads it on the
            // layout: the face of the twin's F_F side.
            let face_of = HalfedgeArrays::of(&fine).face_of;
            let across: Vec<u32> =
                streamed.twins.iter().map(|&t| if t == NONE { NONE } else { face_of[2 * t as usize] }).collect();
            assert_eq!(across, walked.across);
        }
        // Off the layout: both give up on another order, the walk alone on nothing here.
        let soup = subdivide_soup(&shapes::cube(), &DooOptions::default()).unwrap().into_soup();
        let scrambled = HalfedgeMesh::from_soup(&scramble(soup.clone(), 3, 0.0)).unwrap();
        assert!(
            stream_ff_faces(&HalfedgeArrays::of(&scrambled)).is_none()
                && walk_ff_faces(&HalfedgeArrays::of(&scrambled)).is_none()
        );
        // An F_E quad rotated: its sides are numbered in another order.
        let mut faces: Vec<Vec<u32>> = soup.faces().map(<[u32]>::to_vec).collect();
        faces[6].rotate_left(1);
        let rotated = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(soup.positions.clone(), faces)).unwrap();
        assert!(
            stream_ff_faces(&HalfedgeArrays::of(&rotated)).is_none()
                && walk_ff_faces(&HalfedgeArrays::of(&rotated)).is_none()
        );
        // The raw coarse cube (its faces share edges): no F_F faces.
        let cube = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        assert!(
            stream_ff_faces(&HalfedgeArrays::of(&cube)).is_none()
                && walk_ff_faces(&HalfedgeArrays::of(&cube)).is_none()
        );
    }

    #[test]
    fn the_fv_stream_reads_what_the_walk_finds() {
        for soup in [
            shapes::cube(),
            shapes::torus(7, 5, CellKind::Triangles).unwrap(),
            shapes::torus(6, 4, CellKind::Mixed).unwrap(),
        ] {
            let fine = refine(&soup, FaceRule::DooSabin);
            let arrays = HalfedgeArrays::of(&fine);
            let ff = stream_ff_faces(&HalfedgeArrays::of(&fine)).expect("the layout of a soup in the canonical order");
            let fv_first = ff.offsets.len() - 1 + ff.quads as usize;
            let StreamedFvFaces { labels, first_corners: first, sizes, by_vertex, ends } =
                stream_fv_faces(&arrays, fv_first, ff.quads as usize).expect("closed");
            // The far end of each corner's coarse edge: the vertex of its next corner.
            assert!(ends.iter().zip(&ff.next).all(|(&end, &next)| end == labels[next as usize]));
            let mut walked = Vec::new();
            for (i, &h0) in arrays.face_halfedge[fv_first..].iter().enumerate() {
                let start = walked.len();
                let mut h = h0;
                loop {
                    walked.push(arrays.to[(h ^ 1) as usize]);
                    h = arrays.next[h as usize];
                    if h == h0 {
                        break;
                    }
                }
                let face = &walked[start..];
                assert_eq!((first[i], sizes[i] as usize), (face[0], face.len()));
                assert!(face.iter().all(|&c| labels[c as usize] == i as u32));
            }
            assert_eq!(walked.len(), fine.vertex_count());
            assert_eq!(by_vertex, by_vertex_of_fv_faces(&sizes, walked));
            // An F_V face that does not start at its smallest corner is a mismatch (the
            // layout of the other faces stays).
            let mut faces: Vec<Vec<u32>> = fine.to_soup().faces().map(<[u32]>::to_vec).collect();
            faces.last_mut().unwrap().rotate_left(1);
            let rotated = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(fine.positions().to_vec(), faces)).unwrap();
            let ff = stream_ff_faces(&HalfedgeArrays::of(&rotated)).expect("the layout of the F_F faces and quads");
            assert!(stream_fv_faces(&HalfedgeArrays::of(&rotated), fv_first, ff.quads as usize).is_none());
        }
        // With a boundary the F_V sides are not all quad twins: the walk decides.
        let open = refine(&shapes::grid(4, 3, CellKind::Quads).unwrap(), FaceRule::DooSabin);
        let ff = stream_ff_faces(&HalfedgeArrays::of(&open)).expect("layout");
        let fv_first = ff.offsets.len() - 1 + ff.quads as usize;
        assert!(stream_fv_faces(&HalfedgeArrays::of(&open), fv_first, ff.quads as usize).is_none());
    }

    #[test]
    fn repeats_are_found_in_short_and_long_lists() {
        let mut stamp = Vec::new();
        assert!(distinct(&[3, 1, 2], &mut stamp, 20, 0));
        assert!(!distinct(&[3, 1, 3], &mut stamp, 20, 1));
        assert!(!distinct(&[3, NONE, 2], &mut stamp, 20, 2));
        assert!(stamp.is_empty());
        let long: Vec<u32> = (0..12).collect();
        assert!(distinct(&long, &mut stamp, 20, 3));
        assert!(distinct(&long, &mut stamp, 20, 4));
        let mut repeated = long.clone();
        repeated[11] = 5;
        assert!(!distinct(&repeated, &mut stamp, 20, 5));
        repeated[11] = NONE;
        assert!(!distinct(&repeated, &mut stamp, 20, 6));
    }

    #[test]
    fn a_face_with_no_lower_neighbour_is_searched_for_connectivity() {
        // Face 1 of the coarse grid is swapped with the last one: it has no neighbour
        // below it, so the connectivity is found by the search.
        for kind in [CellKind::Quads, CellKind::Mixed] {
            let grid = shapes::grid(5, 4, kind).unwrap();
            let mut faces: Vec<Vec<u32>> = grid.faces().map(<[u32]>::to_vec).collect();
            let last = faces.len() - 1;
            faces.swap(1, last);
            let soup = PolygonSoup::from_faces(grid.positions.clone(), faces);
            let fine = refine(&soup, FaceRule::DooSabin);
            let ff = stream_ff_faces(&HalfedgeArrays::of(&fine)).expect("the layout of a canonical mesh");
            let next = next_of_corners(&ff.offsets);
            assert!(!ff.unreached.iter().all(|&k| reaches_lower_in_two(&ff.offsets, &ff.twins, &next, k)));
            let options = ReverseOptions::with_seed(FaceRule::DooSabin, 0);
            let fast = reverse_canonical(&fine, &options).expect("canonical order");
            assert_eq!(fast, general(&fine, &options));
        }
    }

    #[test]
    fn the_faces_read_with_a_soup_are_those_of_the_layout() {
        let holed = without(&shapes::torus(8, 6, CellKind::Triangles).unwrap(), &[3, 50]);
        let cases = [
            (shapes::cube(), FaceRule::DooSabin, 1),
            (shapes::cube(), FaceRule::Simple, 3),
            (shapes::tetrahedron(), FaceRule::DooSabin, 2),
            (shapes::torus(6, 4, CellKind::Mixed).unwrap(), FaceRule::DooSabin, 2),
            (shapes::torus(5, 3, CellKind::Triangles).unwrap(), FaceRule::Centroid { a: 0.5 }, 1),
            (shapes::grid(4, 3, CellKind::Quads).unwrap(), FaceRule::DooSabin, 1),
            (shapes::grid(5, 4, CellKind::Mixed).unwrap(), FaceRule::Simple, 2),
            (holed, FaceRule::DooSabin, 2),
        ];
        let mut unreached = 0;
        for (coarse, rule, levels) in cases {
            let soup = subdivide_soup(&coarse, &DooOptions::new(rule, levels)).unwrap().into_soup();
            let mut halfedges = CornerHalfedges::of_canonical_soup(&soup).expect("a canonical soup");
            let read = halfedges.ff_faces.take().expect("the F_F faces of a canonical soup");
            let streamed = stream_ff_faces(&halfedges.view(&soup.positions)).expect("the layout of a canonical soup");
            assert_eq!(read, streamed, "{rule:?} x{levels}");
            unreached += read.unreached.len();
        }
        // (Faces with no twin on an earlier face are met: the comparison covers them.)
        assert!(unreached > 0);
        // The corner walk of any mesh reads none.
        let mesh = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
        assert!(CornerHalfedges::of(&CornerMesh::from_halfedge(&mesh)).unwrap().ff_faces.is_none());
    }

    #[test]
    fn two_components_are_found_on_the_layout_and_by_the_walk() {
        // Two cubes, the second's faces first in one face list, refined twice: the F_F
        // faces of the first level are all above the faces they lie across from, so the
        // union-find decides; the coarse mesh has two components.
        let cube = shapes::cube();
        let shift = cube.positions.len() as u32;
        let mut faces: Vec<Vec<u32>> = cube.faces().map(|f| f.iter().map(|&v| v + shift).collect()).collect();
        faces.extend(cube.faces().map(<[u32]>::to_vec));
        let positions = [&cube.positions[..], &cube.positions[..]].concat();
        let two = PolygonSoup::from_faces(positions, faces);
        for (soup, components) in [(cube, 1), (two, 2)] {
            let twice = subdivide_soup(&soup, &DooOptions::new(FaceRule::DooSabin, 2)).unwrap().to_mesh().unwrap();
            let arrays = HalfedgeArrays::of(&twice);
            let streamed = stream_ff_faces(&arrays).expect("the layout of a canonical mesh");
            let walked = walk_ff_faces(&arrays).expect("a canonical mesh");
            let next = next_of_corners(&streamed.offsets);
            assert!(!streamed.unreached.iter().all(|&k| reaches_lower_in_two(
                &streamed.offsets,
                &streamed.twins,
                &next,
                k
            )));
            let on_layout = connected(&streamed.offsets, &streamed.twins, |_, t| arrays.face_of[2 * t as usize]);
            let by_walk = connected(&walked.offsets, &walked.twins, |c, _| walked.across[c]);
            assert_eq!((on_layout, by_walk), (components == 1, components == 1));
            // The canonical path takes one component only; the general path reads both.
            let options = ReverseOptions::with_seed(FaceRule::DooSabin, 0);
            assert_eq!(reverse_canonical(&twice, &options).is_some(), components == 1);
            let general = reverse_corner_mesh(
                &CornerMesh::from_halfedge(&twice),
                twice.positions(),
                &ReverseOptions::auto(FaceRule::DooSabin),
            )
            .unwrap();
            assert_eq!(general.choices().len(), components);
        }
        // Three triangles: face 2 joined to face 0, face 1 alone; then face 1 joined to
        // face 0 as well.
        let offsets = [0, 3, 6, 9];
        let twins = [NONE, 8, NONE, NONE, NONE, NONE, NONE, NONE, 1];
        let across = [NONE, 2, NONE, NONE, NONE, NONE, NONE, NONE, 0];
        assert!(!connected(&offsets, &twins, |c, _| across[c]));
        let twins = [NONE, 8, 3, 2, NONE, NONE, NONE, NONE, 1];
        let across = [NONE, 2, 1, 0, NONE, NONE, NONE, NONE, 0];
        assert!(connected(&offsets, &twins, |c, _| across[c]));
    }

    #[test]
    fn a_face_reached_through_a_neighbour_needs_no_search() {
        // In the triangle torus, the first triangle of some cells has neighbours above it
        // only, one of which (its cell's other triangle) has one below it.
        let fine = refine(&shapes::torus(6, 4, CellKind::Triangles).unwrap(), FaceRule::DooSabin);
        let ff = stream_ff_faces(&HalfedgeArrays::of(&fine)).expect("the layout of a canonical mesh");
        let next = next_of_corners(&ff.offsets);
        assert!(!ff.unreached.is_empty());
        assert!(ff.unreached.iter().all(|&k| reaches_lower_in_two(&ff.offsets, &ff.twins, &next, k)));
        // Not through the face itself: a face whose neighbours reach below only through it.
        assert!(!reaches_lower_in_two(&[0, 3, 6], &[NONE, 4, NONE, NONE, 1, NONE], &[1, 2, 0, 4, 5, 3], 1));
    }

    /// The unit scale measured on the way is that of all the positions (which
    /// `decompose` then reads no further time), at any scale and wherever the largest
    /// coordinate is; it is left out of the comparison of reversals.
    #[test]
    fn the_unit_scale_measured_on_the_way_is_that_of_all_positions() {
        let fine = refine(&shapes::torus(6, 4, CellKind::Triangles).unwrap(), FaceRule::DooSabin);
        let options = ReverseOptions::auto(FaceRule::DooSabin);
        for (vertex, largest) in [(0, 1.5), (37, 3e80), (fine.vertex_count() - 1, 2f64.powi(300)), (11, -1e-90)] {
            let mut mesh = fine.clone();
            if largest.abs() < 1.0 {
                mesh.positions_mut().iter_mut().for_each(|p| *p *= 1e-100);
            }
            mesh.positions_mut()[vertex].y = largest;
            let scale = mesh_topo::scale::unit_scale(mesh.positions());
            let reversal = reverse_canonical(&mesh, &options).expect("canonical order");
            assert_eq!(reversal.fine_unit_scale, Some(scale), "{largest:e}");
            let general = general(&mesh, &options);
            assert_eq!(general.fine_unit_scale, None);
            assert_eq!(reversal, general);
            // The public entry points keep the measured reversal, or redo it at unit scale.
            let public = crate::reverse(&mesh, &options).unwrap();
            assert_eq!(public == reversal, scale == 1.0, "{largest:e}");
            let levels = crate::DecomposeOptions::levels(FaceRule::DooSabin, 1);
            let decomposed = crate::decompose(&mesh, &levels).unwrap();
            assert_eq!(decomposed.pyramid, crate::decompose_soup(&mesh.to_soup(), &levels).unwrap().pyramid);
            assert_eq!(decomposed.pyramid.levels[0].details, public.details);
        }
    }

    #[test]
    fn a_position_that_is_not_finite_is_left_to_the_general_check() {
        let mut fine = refine(&shapes::torus(5, 4, CellKind::Triangles).unwrap(), FaceRule::DooSabin);
        fine.positions_mut()[17].y = f64::NAN;
        fine.positions_mut()[40].z = f64::INFINITY;
        for options in [ReverseOptions::with_seed(FaceRule::DooSabin, 0), ReverseOptions::auto(FaceRule::DooSabin)] {
            assert!(reverse_canonical(&fine, &options).is_none());
            let error = crate::reverse(&fine, &options).unwrap_err();
            assert!(matches!(error, DooError::NonFinite { vertex: 17, .. }), "{error}");
            let decompose = crate::DecomposeOptions {
                seeds: options.seeds.clone(),
                ..crate::DecomposeOptions::levels(FaceRule::DooSabin, 1)
            };
            let error = crate::decompose(&fine, &decompose).unwrap_err();
            assert!(matches!(error, DooError::NonFinite { vertex: 17, .. }), "{error}");
        }
    }

    #[test]
    fn other_orders_and_broken_meshes_are_left_to_the_general_path() {
        let soup =
            subdivide_soup(&shapes::torus(5, 4, CellKind::Mixed).unwrap(), &DooOptions::default()).unwrap().into_soup();
        let options = ReverseOptions::with_seed(FaceRule::DooSabin, 0);
        // Renumbered vertices and rotated faces.
        let scrambled = HalfedgeMesh::from_soup(&scramble(soup.clone(), 3, 0.0)).unwrap();
        assert!(reverse_canonical(&scrambled, &options).is_none());
        // The last F_V face rotated by one corner.
        let mut faces: Vec<Vec<u32>> = soup.faces().map(<[u32]>::to_vec).collect();
        faces.last_mut().unwrap().rotate_left(1);
        let rotated = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(soup.positions.clone(), faces.clone())).unwrap();
        assert!(reverse_canonical(&rotated, &options).is_none());
        assert_eq!(crate::reverse(&rotated, &options).unwrap(), general(&rotated, &options));
        // Two F_E quads swapped.
        let fe = shapes::torus(5, 4, CellKind::Mixed).unwrap().face_count();
        faces.last_mut().unwrap().rotate_right(1);
        faces.swap(fe, fe + 1);
        let swapped = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(soup.positions.clone(), faces.clone())).unwrap();
        assert!(reverse_canonical(&swapped, &options).is_none());
        // Two components, refined together (F_F faces of both first): not connected.
        let mut two = shapes::torus(5, 4, CellKind::Mixed).unwrap();
        let cube = shapes::cube();
        let base = two.vertex_count() as u32;
        two.positions.extend(cube.positions.iter().map(|&p| p + glam::DVec3::splat(9.0)));
        for face in cube.faces() {
            two.push_face(&face.iter().map(|&v| v + base).collect::<Vec<u32>>());
        }
        let two = subdivide_soup(&two, &DooOptions::default()).unwrap().to_mesh().unwrap();
        assert!(reverse_canonical(&two, &options).is_none());
    }
}
