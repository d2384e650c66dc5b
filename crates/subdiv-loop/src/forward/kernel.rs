//! One Loop step on the compact topology: fine values, fine triangles and (unless it is
//! the last level) the fine topology, all by index arithmetic and in parallel.
//!
//! Work is split into chunks of faces (edge points, vertex points of odd vertices, fine
//! faces, fine links) and chunks of even vertices (vertex points by a one-ring walk).
//! Every output element is written by exactly one chunk with a fixed formula, so results
//! are bit-identical for any number of threads.

use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use super::attribute::Attribute;
use super::buffer::{Output, Slots};
use super::topology::{BASE_BITS, INVALID, NEXT, PREV, Topology, edge_at, edge_base, is_first};
use super::{LoopOptions, VertexWeights};

/// Faces per parallel work item (a multiple of 4: chunks hold whole groups).
const FACE_CHUNK: usize = 2048;
/// Vertices per parallel work item.
const VERTEX_CHUNK: usize = 4096;
/// Steps on fewer coarse faces than this run on the calling thread: handing a few
/// chunks to the thread pool costs more than it saves. Waking the pool's other thread,
/// and its first touches of fresh output pages (which contend with the calling thread's
/// in the kernel), cost tens to hundreds of microseconds on a 2-core virtual machine:
/// at 1024 the bunny's first level (3674 faces, 0.12 ms on one thread) took 0.23 ms on
/// two, and its first two levels 0.59 ms against 0.53 ms (criterion means); with the
/// second step (14 696 faces) split too, 0.57 ms against 0.49 ms. From 16 384 faces
/// on two threads gain: the bunny's third step (from 58 784 faces) split, its first
/// three levels took 2.2 ms on two threads against 3.2 ms on one.
pub(crate) const PARALLEL_MIN_FACES: usize = 16_384;
/// Whether a pass over `faces` faces is split over the current `rayon` pool: only for
/// [`PARALLEL_MIN_FACES`] faces or more, and on more than one thread.
pub(crate) fn runs_in_parallel(faces: usize) -> bool {
    faces >= PARALLEL_MIN_FACES && pool_has_threads()
}

/// Whether a pass over `items` items, cut into pieces of `piece` items, is handed to the
/// current `rayon` pool: only if it makes more than one piece and the pool has more than
/// one thread. A one-thread pool would run the pieces one after the other anyway, after
/// a hand-over to its thread (and back) when called from outside it, which on a small
/// level costs as much as the pass.
pub(crate) fn splits(items: usize, piece: usize) -> bool {
    items > piece && pool_has_threads()
}

/// `[f(0), f(1), .., f(n - 1)]`, in parallel when [`splits`]`(n, piece)` (each output
/// written by one task, so the result does not depend on the thread count).
pub(crate) fn map_indices<T: Send>(n: usize, piece: usize, f: impl Fn(u32) -> T + Sync + Send) -> Vec<T> {
    if splits(n, piece) {
        (0..n as u32).into_par_iter().with_min_len(piece).map(f).collect()
    } else {
        (0..n as u32).map(f).collect()
    }
}

/// True if the current `rayon` pool (the global one outside any pool) has more than one
/// thread.
pub(crate) fn pool_has_threads() -> bool {
    rayon::current_num_threads() > 1
}

/// Valences whose weights are tabulated.
const TABLE: usize = 32;

/// The weights of one scheme variant, with the interior vertex weights tabulated.
#[derive(Debug, Clone)]
pub(crate) struct Rules {
    keep_corners: bool,
    weights: VertexWeights,
    /// `(alpha_n, beta_n)` for `n < TABLE`.
    table: [(f64, f64); TABLE],
}

/// Loop's vertex weight `beta_n = (5/8 - (3/8 + cos(2 pi / n) / 4)^2) / n`.
pub(crate) fn loop_beta(n: usize) -> f64 {
    if n == 6 {
        // cos(pi / 3) is not exactly 1/2 in floating point: keep the regular rule exact.
        return 1.0 / 16.0;
    }
    let c = 0.375 + 0.25 * (2.0 * std::f64::consts::PI / n as f64).cos();
    (0.625 - c * c) / n as f64
}

/// Warren's vertex weight: `3/16` for `n = 3`, `3 / (8 n)` otherwise.
pub(crate) fn warren_beta(n: usize) -> f64 {
    if n == 3 { 3.0 / 16.0 } else { 3.0 / (8.0 * n as f64) }
}

impl Rules {
    pub(crate) fn new(options: &LoopOptions) -> Self {
        let mut table = [(1.0, 0.0); TABLE];
        for (n, entry) in table.iter_mut().enumerate().skip(1) {
            *entry = Self::weights_of(options.weights, n);
        }
        Self { keep_corners: options.keep_corners, weights: options.weights, table }
    }

    fn weights_of(weights: VertexWeights, n: usize) -> (f64, f64) {
        let beta = match weights {
            VertexWeights::Loop => loop_beta(n),
            VertexWeights::Warren => warren_beta(n),
        };
        (1.0 - n as f64 * beta, beta)
    }

    /// `(alpha_n, beta_n)` of an interior vertex of valence `n`.
    #[inline]
    pub(crate) fn interior(&self, n: usize) -> (f64, f64) {
        if n < TABLE { self.table[n] } else { Self::weights_of(self.weights, n) }
    }

    /// True if a boundary vertex of valence `valence` keeps its position.
    #[inline]
    pub(crate) fn is_fixed_corner(&self, valence: usize) -> bool {
        self.keep_corners && valence == 2
    }
}

/// The result of one step.
pub(crate) struct Step<T> {
    pub(crate) values: Vec<T>,
    /// Fine topology; only `triangles` and the counts are filled when the step was
    /// asked not to refine the topology (the last level).
    pub(crate) topology: Topology,
}

/// A chunk of faces and the disjoint output ranges it writes.
struct FaceWork<'a, T> {
    faces: std::ops::Range<usize>,
    first_edge: usize,
    edge_values: Slots<'a, T>,
    first_odd: usize,
    odd_values: Slots<'a, T>,
    odd_starts: Slots<'a, u32>,
    triangles: Slots<'a, [u32; 3]>,
    links: Slots<'a, [u32; 4]>,
}

/// A chunk of even vertices and the disjoint output ranges it writes.
struct VertexWork<'a, T> {
    first: usize,
    values: Slots<'a, T>,
    starts: Slots<'a, u32>,
}

/// The parallel tasks of one step.
enum Work<'a, T> {
    Faces(FaceWork<'a, T>),
    Vertices(VertexWork<'a, T>),
}

/// The first half of half-edge `h = 4f + k`: half-edge 0 of child `4f + k`.
#[inline(always)]
fn first_half(h: u32) -> u32 {
    4 * h
}

/// The second half of half-edge `h = 4f + k`: half-edge 2 of child `4f + k + 1`.
#[inline(always)]
fn second_half(h: u32) -> u32 {
    4 * (h - (h & 3) + NEXT[(h & 3) as usize] as u32) + 2
}

/// A value that carries nothing: a step on it computes only the connectivity.
#[derive(Debug, Clone, Copy)]
struct NoValue;

impl Attribute for NoValue {
    #[inline(always)]
    fn scaled(&self, _weight: f64) -> Self {
        NoValue
    }
    #[inline(always)]
    fn add_scaled(&mut self, _other: &Self, _weight: f64) {}
}

/// The next level's connectivity alone: the crate's one refinement rule, also used by
/// the corner tables of detection, reversal and pyramids.
pub(crate) fn refine_topology(topo: &Topology) -> Topology {
    let rules = Rules::new(&LoopOptions::default());
    step(topo, &vec![NoValue; topo.vertex_count], &rules, true).topology
}

/// The vectors a step writes its outputs into: their memory is reused when large enough
/// (see [`Output::reuse`]); their contents are dropped.
pub(crate) struct Buffers<T> {
    pub(crate) values: Vec<T>,
    pub(crate) triangles: Vec<[u32; 3]>,
    pub(crate) links: Vec<[u32; 4]>,
    pub(crate) starts: Vec<u32>,
}

impl<T> Default for Buffers<T> {
    fn default() -> Self {
        Self { values: Vec::new(), triangles: Vec::new(), links: Vec::new(), starts: Vec::new() }
    }
}

/// One Loop step of `values` on `topo`. With `refine_topology` the fine links and
/// vertex starts are produced too (needed for a further step).
pub(crate) fn step<T: Attribute>(topo: &Topology, values: &[T], rules: &Rules, refine_topology: bool) -> Step<T> {
    step_into(topo, values, rules, refine_topology, Buffers::default())
}

/// [`step`] with the details of a reconstruction added as the values are computed (see
/// [`Details`]).
pub(crate) fn step_with_details(
    topo: &Topology,
    values: &[DVec3],
    rules: &Rules,
    refine_topology: bool,
    details: &Details<'_>,
) -> Step<DVec3> {
    debug_assert_eq!(details.details.len(), topo.edge_count, "internal: one detail per edge");
    step_impl(topo, values, rules, refine_topology, Buffers::default(), details)
}

/// [`step`] writing into the memory of `buffers` (bit-identical results).
///
/// Steps with fewer than [`PARALLEL_MIN_FACES`] coarse faces, and every step when the
/// current rayon pool has one thread, run their chunks one after the other on the
/// calling thread, without building a list of tasks: the same chunks and formulas, so
/// the same bits.
pub(crate) fn step_into<T: Attribute>(
    topo: &Topology,
    values: &[T],
    rules: &Rules,
    refine_topology: bool,
    buffers: Buffers<T>,
) -> Step<T> {
    step_impl(topo, values, rules, refine_topology, buffers, &Plain)
}

/// [`step_into`], with `additions` made to the values it computes.
fn step_impl<T: Attribute, A: Additions<T>>(
    topo: &Topology,
    values: &[T],
    rules: &Rules,
    refine_topology: bool,
    buffers: Buffers<T>,
    additions: &A,
) -> Step<T> {
    let nv = topo.vertex_count;
    let ne = topo.edge_count;
    let nf = topo.face_count();
    let even = topo.vertex_halfedge.len();
    debug_assert_eq!(values.len(), nv, "internal: one value per vertex");
    debug_assert!(even == nv || nf.is_multiple_of(4), "internal: a refined level has whole groups");
    let fine_vertex_count = nv + ne;

    // Every output element is written exactly once below, by one task.
    let optional = |n: usize| if refine_topology { n } else { 0 };
    let mut fine_values = Output::<T>::reuse(buffers.values, fine_vertex_count);
    let mut fine_triangles = Output::<[u32; 3]>::reuse(buffers.triangles, 4 * nf);
    let mut fine_links = Output::<[u32; 4]>::reuse(buffers.links, optional(4 * nf));
    let mut fine_starts = Output::<u32>::reuse(buffers.starts, optional(nv));

    let run = |work: Work<'_, T>| match work {
        Work::Faces(mut w) => {
            if even < nv {
                odd_chunk(topo, values, rules, additions, &mut w, refine_topology);
            }
            face_chunk(topo, values, additions, &mut w, refine_topology);
        }
        Work::Vertices(w) => vertex_chunk(topo, values, rules, additions, w, refine_topology),
    };
    {
        let slots = (fine_values.slots(), fine_triangles.slots(), fine_links.slots(), fine_starts.slots());
        if !runs_in_parallel(nf) {
            additions.prepare(topo);
            split_work(topo, refine_topology, slots, run);
        } else {
            let mut work = Vec::with_capacity(nf.div_ceil(FACE_CHUNK) + even.div_ceil(VERTEX_CHUNK));
            split_work(topo, refine_topology, slots, |w| work.push(w));
            if A::ACTIVE {
                // The edge points, faces and links need nothing prepared: they run
                // beside the preparation, the vertex points after it.
                let edges = |work: &mut Work<'_, T>| {
                    if let Work::Faces(w) = work {
                        face_chunk(topo, values, additions, w, refine_topology);
                    }
                };
                rayon::join(|| additions.prepare(topo), || work.par_iter_mut().for_each(edges));
                work.into_par_iter().for_each(|work| match work {
                    Work::Faces(mut w) if even < nv => {
                        odd_chunk(topo, values, rules, additions, &mut w, refine_topology)
                    }
                    Work::Faces(_) => {}
                    Work::Vertices(w) => vertex_chunk(topo, values, rules, additions, w, refine_topology),
                });
            } else {
                work.into_par_iter().for_each(run);
            }
        }
    }

    let topology = Topology {
        triangles: fine_triangles.into_vec(),
        links: fine_links.into_vec(),
        vertex_halfedge: fine_starts.into_vec(),
        vertex_count: fine_vertex_count,
        edge_count: 2 * ne + 3 * nf,
    };
    Step { values: fine_values.into_vec(), topology }
}

/// The slots of a step's four outputs: values, triangles, links, starts.
type AllSlots<'a, T> = (Slots<'a, T>, Slots<'a, [u32; 3]>, Slots<'a, [u32; 4]>, Slots<'a, u32>);

/// Splits the outputs of a step into its chunks of work, in order (faces, then even
/// vertices), and hands each to `emit`.
fn split_work<'a, T>(
    topo: &Topology,
    refine_topology: bool,
    (mut values, mut tr, mut li, mut starts): AllSlots<'a, T>,
    mut emit: impl FnMut(Work<'a, T>),
) {
    let nv = topo.vertex_count;
    let ne = topo.edge_count;
    let nf = topo.face_count();
    let even = topo.vertex_halfedge.len();
    let optional = |n: usize| if refine_topology { n } else { 0 };
    let mut even_values = values.take_front(even);
    let mut even_starts = starts.take_front(optional(even));
    let (mut ov, mut os) = (values.take_front(nv - even), starts.take_front(optional(nv - even)));
    let mut ev = values.take_front(ne);
    // Face chunks: edge points, odd vertex points, fine faces and fine links.
    let edges_before = |f: usize| if f == nf { ne } else { edge_base(topo.links[f][3]) as usize };
    // Odd vertices are the edge points of the level before, numbered by its edges:
    // group g has 3g + 2 e_g edges before it, e_g of the level before.
    let odd_before = |f: usize| {
        if even == nv {
            0
        } else if f == nf {
            nv - even
        } else {
            (edges_before(f) - 3 * (f / 4)) / 2
        }
    };
    let mut f0 = 0;
    while f0 < nf {
        let f1 = (f0 + FACE_CHUNK).min(nf);
        let edges = edges_before(f1) - edges_before(f0);
        let odd = odd_before(f1) - odd_before(f0);
        emit(Work::Faces(FaceWork {
            faces: f0..f1,
            first_edge: edges_before(f0),
            edge_values: ev.take_front(edges),
            first_odd: even + odd_before(f0),
            odd_values: ov.take_front(odd),
            odd_starts: os.take_front(optional(odd)),
            triangles: tr.take_front(4 * (f1 - f0)),
            links: li.take_front(optional(4 * (f1 - f0))),
        }));
        f0 = f1;
    }
    // Vertex chunks: vertex points (and starts) of even vertices.
    let mut v0 = 0;
    while v0 < even {
        let v1 = (v0 + VERTEX_CHUNK).min(even);
        emit(Work::Vertices(VertexWork {
            first: v0,
            values: even_values.take_front(v1 - v0),
            starts: even_starts.take_front(optional(v1 - v0)),
        }));
        v0 = v1;
    }
}

/// Vertex points of the odd vertices owned by a chunk of groups.
///
/// Group `g` (faces `4g .. 4g + 3`) has corner faces `4g + k = (c_k, m_k, m_{k-1})` and
/// the centre face `4g + 3 = (m_0, m_1, m_2)`. The odd vertex `m_k` is owned by the group
/// where its edge `c_k c_{k+1}` was first seen (half-edge 0 of face `4g + k` is first).
/// Inside, it has valence 6 and its neighbours are `c_k, c_{k+1}`, the other two centre
/// vertices of its group and the other two centre vertices of the group across the edge;
/// on the boundary it has valence 4 and boundary neighbours `c_k, c_{k+1}`.
#[inline(never)]
fn odd_chunk<T: Attribute, A: Additions<T>>(
    topo: &Topology,
    values: &[T],
    rules: &Rules,
    additions: &A,
    w: &mut FaceWork<'_, T>,
    refine: bool,
) {
    let tri = &topo.triangles[..];
    let links = &topo.links[..];
    let (alpha, beta) = rules.interior(6);
    let mut probe = A::Probe::default();
    for g in w.faces.start / 4..w.faces.end / 4 {
        let centre = tri[4 * g + 3];
        for k in 0..3usize {
            let corner_face = 4 * g + k;
            if links[corner_face][3] & (1 << BASE_BITS) == 0 {
                continue;
            }
            let m = centre[k];
            debug_assert_eq!(m as usize - w.first_odd, w.odd_values.written(), "internal: odd vertex order");
            let p = &values[m as usize];
            let mut ends = values[tri[corner_face][0] as usize].clone();
            ends.add(&values[tri[4 * g + NEXT[k]][0] as usize]);
            let across = links[corner_face][0];
            if across == INVALID {
                let mut point = p.scaled(0.75);
                point.add_scaled(&ends, 0.125);
                if A::ACTIVE {
                    additions.boundary_vertex_point(&mut point, m, 4, rules);
                    additions.probe(&mut probe, &point);
                }
                w.odd_values.push(point);
                if refine {
                    w.odd_starts.push(first_half(second_half(corner_face as u32)));
                }
            } else {
                // `across` is the second half of the twin edge: half-edge 2 of face
                // 4g' + j of the group g' across, whose centre vertex j - 1 is m.
                let face = (across >> 2) as usize;
                let other = tri[(face & !3) + 3];
                let j = face & 3;
                debug_assert_eq!(other[PREV[j]], m, "internal: odd vertex across groups");
                let mut sum = ends;
                sum.add(&values[centre[NEXT[k]] as usize]);
                sum.add(&values[centre[PREV[k]] as usize]);
                sum.add(&values[other[j] as usize]);
                sum.add(&values[other[NEXT[j]] as usize]);
                let mut point = p.scaled(alpha);
                point.add_scaled(&sum, beta);
                if A::ACTIVE {
                    additions.interior_vertex_point(&mut point, m, 6, rules);
                    additions.probe(&mut probe, &point);
                }
                w.odd_values.push(point);
                if refine {
                    w.odd_starts.push(first_half((4 * corner_face + 1) as u32));
                }
            }
        }
    }
    additions.report(probe);
}

/// Edge points, fine faces and (optionally) fine links of one chunk of faces.
///
/// Face `f = (c0, c1, c2)` with edge points `m_k` on half-edge `4f + k` (from `c_k` to
/// `c_{k+1}`) gives the children `4f + k = (c_k, m_k, m_{k-1})` for `k = 0, 1, 2` and
/// `4f + 3 = (m0, m1, m2)`. Child half-edges: `(4f + k, 0)` is the first half of
/// `4f + k`, `(4f + k, 1)` runs `m_k -> m_{k-1}`, `(4f + k, 2)` is the second half of
/// `4f + k - 1`, `(4f + 3, j)` runs `m_j -> m_{j+1}`.
#[inline(never)]
fn face_chunk<T: Attribute, A: Additions<T>>(
    topo: &Topology,
    values: &[T],
    additions: &A,
    w: &mut FaceWork<'_, T>,
    refine_topology: bool,
) {
    let mut probe = A::Probe::default();
    let nv = topo.vertex_count as u32;
    let tri = &topo.triangles[..];
    let links = &topo.links[..];
    for f in w.faces.clone() {
        let c = tri[f];
        let link = links[f];
        let h0 = 4 * f as u32;
        let info = link[3];
        let mut next_edge = edge_base(info);
        let mut m = [0u32; 3];
        for k in 0..3 {
            let t = link[k];
            if is_first(h0 + k as u32, t) {
                let e = next_edge;
                next_edge += 1;
                m[k] = nv + e;
                let a = &values[c[k] as usize];
                let b = &values[c[NEXT[k]] as usize];
                let mut point = a.clone();
                point.add(b);
                debug_assert_eq!(e as usize - w.first_edge, w.edge_values.written(), "internal: edge order");
                let mut point = if t == INVALID {
                    point.scaled(0.5)
                } else {
                    let d = tri[(t >> 2) as usize][PREV[(t & 3) as usize]];
                    let mut wings = values[c[PREV[k]] as usize].clone();
                    wings.add(&values[d as usize]);
                    let mut point = point.scaled(0.375);
                    point.add_scaled(&wings, 0.125);
                    point
                };
                if A::ACTIVE {
                    additions.edge_point(&mut point, e);
                    additions.probe(&mut probe, &point);
                }
                w.edge_values.push(point);
            } else {
                m[k] = nv + edge_at(links[(t >> 2) as usize][3], t & 3);
            }
        }
        w.triangles.push([c[0], m[0], m[2]]);
        w.triangles.push([c[1], m[1], m[0]]);
        w.triangles.push([c[2], m[2], m[1]]);
        w.triangles.push([m[0], m[1], m[2]]);
        if refine_topology {
            let base = 16 * f as u32;
            // Fine first-masks: child k holds the first half of 4f + k (bit 0), an
            // interior edge (bit 1, always first) and the second half of 4f + k - 1
            // (bit 2); the centre face holds no first half-edge.
            let first = (info >> BASE_BITS) & 7;
            let bit = |k: usize| (first >> k) & 1;
            let mut edges = 3 * f as u32 + 2 * edge_base(info);
            for k in 0..3usize {
                let outer = link[k];
                let inner = link[PREV[k]];
                let mask = bit(k) | 2 | (bit(PREV[k]) << 2);
                w.links.push([
                    if outer == INVALID { INVALID } else { second_half(outer) },
                    base + 12 + PREV[k] as u32,
                    if inner == INVALID { INVALID } else { first_half(inner) },
                    edges | (mask << BASE_BITS),
                ]);
                edges += mask.count_ones();
            }
            w.links.push([base + 5, base + 9, base + 1, edges]);
        }
    }
    additions.report(probe);
}

/// Vertex points (and, with `refine_topology`, start half-edges) of a chunk of even
/// vertices.
#[inline(never)]
fn vertex_chunk<T: Attribute, A: Additions<T>>(
    topo: &Topology,
    values: &[T],
    rules: &Rules,
    additions: &A,
    mut w: VertexWork<'_, T>,
    refine: bool,
) {
    let mut probe = A::Probe::default();
    for v in w.first..w.first + w.values.len() {
        let point = vertex_point(topo, values, rules, additions, v as u32);
        if A::ACTIVE {
            additions.probe(&mut probe, &point);
        }
        w.values.push(point);
        if refine {
            // Corner k of face f becomes corner 0 of child 4f + k: the outgoing half-edge
            // becomes its first half, with the same boundary status.
            let h = topo.vertex_halfedge[v];
            w.starts.push(if h == INVALID { INVALID } else { first_half(h) });
        }
    }
    additions.report(probe);
}

/// The vertex point of even vertex `v`, by a walk around its one-ring (with the
/// addition of `additions`).
///
/// The walk is a chain of dependent loads (half-edge, the link of its predecessor, the
/// next half-edge), so it works on the flat arrays with the corner arithmetic inline.
#[inline]
fn vertex_point<T: Attribute, A: Additions<T>>(
    topo: &Topology,
    values: &[T],
    rules: &Rules,
    additions: &A,
    v: u32,
) -> T {
    let start = topo.vertex_halfedge[v as usize];
    let p = &values[v as usize];
    if start == INVALID {
        let mut point = p.clone();
        if A::ACTIVE {
            additions.isolated_vertex_point(&mut point);
        }
        return point;
    }
    let tri = topo.triangles.as_flattened();
    let links = topo.links.as_flattened();
    // Corner `k + 1 mod 3` of the face of `h` (the target of `h`), and the half-edge
    // before `h` in its face (`4f + k - 1 mod 3`), whose link is the next fan half-edge.
    let target = |h: u32| tri[3 * (h >> 2) as usize + if h & 3 == 2 { 0 } else { (h & 3) as usize + 1 }];
    let before = |h: u32| if h & 3 == 0 { h + 2 } else { h - 1 };
    let mut h = start;
    let mut sum = values[target(h) as usize].clone();
    let mut valence = 1usize;
    loop {
        let t = links[before(h) as usize];
        if t == INVALID {
            // Boundary: the fan ends here; the two boundary neighbours are the target of
            // the first and the origin of the last fan half-edge.
            let mut point = if rules.is_fixed_corner(valence + 1) {
                p.clone()
            } else {
                let last = tri[3 * (h >> 2) as usize + PREV[(h & 3) as usize]];
                let mut ends = values[target(start) as usize].clone();
                ends.add(&values[last as usize]);
                let mut point = p.scaled(0.75);
                point.add_scaled(&ends, 0.125);
                point
            };
            if A::ACTIVE {
                additions.boundary_vertex_point(&mut point, v, valence + 1, rules);
            }
            return point;
        }
        if t == start || valence > topo.triangles.len() {
            debug_assert!(t == start, "internal: one-ring walk did not close");
            break;
        }
        h = t;
        sum.add(&values[target(h) as usize]);
        valence += 1;
    }
    let (alpha, beta) = rules.interior(valence);
    let mut point = p.scaled(alpha);
    point.add_scaled(&sum, beta);
    if A::ACTIVE {
        additions.interior_vertex_point(&mut point, v, valence, rules);
    }
    point
}

/// What a step adds to the values it computes: nothing ([`Plain`], subdivision) or the
/// details of a reconstruction ([`Details`]). The chunks call it as they write each
/// value, so that it needs no pass over the values of its own.
pub(crate) trait Additions<T>: Sync {
    /// False when nothing is added: the chunks then skip the calls.
    const ACTIVE: bool;
    /// What the vertex points need from the coarse level, made before any of them
    /// (beside the edge points when the step runs in parallel).
    fn prepare(&self, topo: &Topology);
    /// A running test of the finiteness of the values a chunk wrote.
    type Probe: Default;
    /// Adds to the edge point of edge `edge`.
    fn edge_point(&self, point: &mut T, edge: u32);
    /// Adds to the vertex point of interior vertex `v` with `valence` edges.
    fn interior_vertex_point(&self, point: &mut T, v: u32, valence: usize, rules: &Rules);
    /// Adds to the vertex point of boundary vertex `v` with `valence` edges.
    fn boundary_vertex_point(&self, point: &mut T, v: u32, valence: usize, rules: &Rules);
    /// Adds to the vertex point of an isolated vertex.
    fn isolated_vertex_point(&self, point: &mut T);
    /// Takes a written value into the chunk's probe.
    fn probe(&self, probe: &mut Self::Probe, value: &T);
    /// The verdict of a chunk's probe.
    fn report(&self, probe: Self::Probe);
}

/// Nothing added: Loop subdivision.
struct Plain;

impl<T> Additions<T> for Plain {
    const ACTIVE: bool = false;
    type Probe = ();
    #[inline(always)]
    fn prepare(&self, _topo: &Topology) {}
    #[inline(always)]
    fn edge_point(&self, _point: &mut T, _edge: u32) {}
    #[inline(always)]
    fn interior_vertex_point(&self, _point: &mut T, _v: u32, _valence: usize, _rules: &Rules) {}
    #[inline(always)]
    fn boundary_vertex_point(&self, _point: &mut T, _v: u32, _valence: usize, _rules: &Rules) {}
    #[inline(always)]
    fn isolated_vertex_point(&self, _point: &mut T) {}
    #[inline(always)]
    fn probe(&self, _probe: &mut (), _value: &T) {}
    #[inline(always)]
    fn report(&self, _probe: ()) {}
}

/// The details of one reconstruction step (see `reverse::reconstruct_levels`): `D_e` is
/// added to the edge point of edge `e`, and to each vertex point the change that the
/// inverse relation implies: `8β_n/5` times the sum of the details of its `n` edges
/// inside, a quarter of the sum of its two boundary edges' on the boundary, nothing at a
/// fixed corner or an isolated vertex (the sums: [`detail_sums`]).
///
/// With `check_finite`, every value written is tested (a running sum of zero times each
/// value, which stays zero unless one is not finite): see [`Details::all_finite`].
pub(crate) struct Details<'a> {
    details: &'a [DVec3],
    /// One per coarse vertex, made by [`Additions::prepare`].
    sums: OnceLock<Vec<[f64; 3]>>,
    check_finite: bool,
    non_finite: AtomicBool,
}

impl<'a> Details<'a> {
    /// One detail per edge of the coarse level.
    pub(crate) fn new(details: &'a [DVec3], check_finite: bool) -> Self {
        Self { details, sums: OnceLock::new(), check_finite, non_finite: AtomicBool::new(false) }
    }

    /// With `check_finite`: true if every value the step wrote is finite.
    pub(crate) fn all_finite(&self) -> bool {
        !self.non_finite.load(Ordering::Relaxed)
    }

    #[inline(always)]
    fn sum(&self, v: u32) -> DVec3 {
        DVec3::from_array(self.sums.get().expect("internal: detail sums made before the vertex points")[v as usize])
    }
}

/// Per vertex of `topology`, the sum of the details of its edges, or of its two
/// boundary edges on the boundary: what the vertex point's correction scales (see
/// [`Details`]). Each sum starts from zero and follows the edge order, so that its bits
/// depend on nothing else (not on the thread count).
///
/// One sequential pass over the faces adds to each corner the details of the face's two
/// edges at it, in edge order (edges are numbered by faces); an edge that the face does
/// not number adds zero instead, which leaves a sum unchanged (a sum that starts at +0
/// is never −0), so the pass has no branch on which edges the face numbers. The
/// boundary vertices' sums are then made again from their boundary edges alone.
fn detail_sums(topology: &Topology, details: &[DVec3]) -> Vec<[f64; 3]> {
    // Zeroed memory from the allocator, not a pass of writes where it can.
    let mut sums = vec![[0.0f64; 3]; topology.vertex_count];
    let mut boundary_faces = Vec::new();
    let add = |sum: &mut [f64; 3], first: DVec3, second: DVec3| {
        *sum = (DVec3::from_array(*sum) + first + second).to_array();
    };
    // The details of the three edges of a face, zero for those it does not number.
    let face_details = |info: u32| {
        let detail = |k: u32| {
            // When the face does not number its edge `k`, detail 0 is read and masked
            // to zero (by arithmetic, not a branch on the unpredictable mask).
            let numbered = u64::from((info >> (BASE_BITS + k)) & 1);
            let d = details[edge_at(info, k) as usize * numbered as usize];
            let keep = |x: f64| f64::from_bits(x.to_bits() & numbered.wrapping_neg());
            DVec3::new(keep(d.x), keep(d.y), keep(d.z))
        };
        [detail(0), detail(1), detail(2)]
    };
    let on_boundary = |link: &[u32; 4]| link[0].max(link[1]).max(link[2]) == INVALID;
    if topology.vertex_halfedge.len() < topology.vertex_count {
        // A refined level: groups of four faces, corner faces `(c_k, m_k, m_{k-1})` and
        // the centre face `(m_0, m_1, m_2)`, which numbers none of its edges (they are
        // the corner faces' inner edges) and adds nothing. Each vertex's additions
        // within the group are made in one go, in the order of the faces: the
        // corner's two edges in face `k`, and the edge point `m_k`'s edges 0 and 1 in
        // face `k`, 1 and 2 in face `k + 1`.
        for g in 0..topology.triangles.len() / 4 {
            let faces = 4 * g..4 * g + 3;
            let links = &topology.links[4 * g..4 * g + 3];
            let d = [face_details(links[0][3]), face_details(links[1][3]), face_details(links[2][3])];
            let centre = topology.triangles[4 * g + 3];
            for k in 0..3 {
                add(&mut sums[topology.triangles[4 * g + k][0] as usize], d[k][0], d[k][2]);
                let n = NEXT[k];
                let sum = &mut sums[centre[k] as usize];
                if k < n {
                    add(sum, d[k][0], d[k][1]);
                    add(sum, d[n][1], d[n][2]);
                } else {
                    add(sum, d[n][1], d[n][2]);
                    add(sum, d[k][0], d[k][1]);
                }
            }
            boundary_faces.extend(faces.filter(|&f| on_boundary(&topology.links[f])));
        }
    } else {
        for (f, (corners, link)) in topology.triangles.iter().zip(&topology.links).enumerate() {
            let [d0, d1, d2] = face_details(link[3]);
            add(&mut sums[corners[0] as usize], d0, d2);
            add(&mut sums[corners[1] as usize], d0, d1);
            add(&mut sums[corners[2] as usize], d1, d2);
            if on_boundary(link) {
                boundary_faces.push(f);
            }
        }
    }
    let boundary_edges = || {
        boundary_faces.iter().flat_map(|&f| {
            let (corners, link) = (topology.triangles[f], topology.links[f]);
            (0..3)
                .filter(move |&k| link[k] == INVALID)
                .map(move |k| (edge_at(link[3], k as u32) as usize, [corners[k], corners[NEXT[k]]]))
        })
    };
    for (_, ends) in boundary_edges() {
        for v in ends {
            sums[v as usize] = [0.0; 3];
        }
    }
    for (e, ends) in boundary_edges() {
        for v in ends {
            let sum = &mut sums[v as usize];
            *sum = (DVec3::from_array(*sum) + details[e]).to_array();
        }
    }
    sums
}

impl Additions<DVec3> for Details<'_> {
    const ACTIVE: bool = true;
    type Probe = DVec3;

    fn prepare(&self, topo: &Topology) {
        debug_assert_eq!(self.details.len(), topo.edge_count, "internal: one detail per edge");
        self.sums.get_or_init(|| detail_sums(topo, self.details));
    }

    #[inline(always)]
    fn edge_point(&self, point: &mut DVec3, edge: u32) {
        *point += self.details[edge as usize];
    }

    #[inline(always)]
    fn interior_vertex_point(&self, point: &mut DVec3, v: u32, valence: usize, rules: &Rules) {
        *point += (1.6 * rules.interior(valence).1) * self.sum(v);
    }

    #[inline(always)]
    fn boundary_vertex_point(&self, point: &mut DVec3, v: u32, valence: usize, rules: &Rules) {
        *point += if rules.is_fixed_corner(valence) { DVec3::ZERO } else { 0.25 * self.sum(v) };
    }

    #[inline(always)]
    fn isolated_vertex_point(&self, point: &mut DVec3) {
        // Nothing to add, but adding zero keeps the bits of the formulation with a pass
        // of corrections after the kernel (a coordinate of −0 becomes +0).
        *point += DVec3::ZERO;
    }

    #[inline(always)]
    fn probe(&self, probe: &mut DVec3, value: &DVec3) {
        *probe += *value * 0.0;
    }

    #[inline(always)]
    fn report(&self, probe: DVec3) {
        if self.check_finite && probe.x + probe.y + probe.z != 0.0 {
            self.non_finite.store(true, Ordering::Relaxed);
        }
    }
}
