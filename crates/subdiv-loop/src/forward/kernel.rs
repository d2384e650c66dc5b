//! One Loop step on the compact topology: fine values, fine triangles and (unless it is
//! the last level) the fine topology, all by index arithmetic and in parallel.
//!
//! Work is split into chunks of faces (edge points, fine faces, fine twins) and chunks
//! of vertices (vertex points). Every output element is written by exactly one chunk
//! with a fixed formula, so results are bit-identical for any number of threads.

use rayon::prelude::*;

use super::attribute::Attribute;
use super::topology::{BASE_BITS, BASE_MASK, INVALID, Topology, is_first};
use super::{LoopOptions, VertexWeights};

/// Faces per parallel work item.
const FACE_CHUNK: usize = 2048;
/// Vertices per parallel work item.
const VERTEX_CHUNK: usize = 4096;
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
    edge_values: &'a mut [T],
    triangles: &'a mut [[u32; 3]],
    twins: &'a mut [u32],
    face_info: &'a mut [u32],
    edge_starts: &'a mut [u32],
}

/// Splits `n` elements off the front of `slice` (nothing if `slice` is empty: outputs
/// that are not computed at the last level).
fn take_front<'a, T>(slice: &mut &'a mut [T], n: usize) -> &'a mut [T] {
    if slice.is_empty() {
        return &mut [];
    }
    let (front, back) = std::mem::take(slice).split_at_mut(n);
    *slice = back;
    front
}

/// One Loop step of `values` on `topo`. With `refine_topology` the fine twins, face
/// information and vertex starts are produced too (needed for a further step).
pub(crate) fn step<T: Attribute>(topo: &Topology, values: &[T], rules: &Rules, refine_topology: bool) -> Step<T> {
    let nv = topo.vertex_count;
    let ne = topo.edge_count;
    let nf = topo.face_count();
    debug_assert_eq!(values.len(), nv, "internal: one value per vertex");
    let fine_vertex_count = nv + ne;

    let mut fine_values: Vec<T> = Vec::with_capacity(fine_vertex_count);
    if let Some(placeholder) = values.first() {
        // Parallel first touch: page faults of a large output are the biggest fixed
        // cost on many machines, and they scale with threads when spread like this.
        fine_values.par_extend(rayon::iter::repeat_n(placeholder.clone(), fine_vertex_count));
    }
    let mut fine_triangles = vec![[0u32; 3]; 4 * nf];
    let (mut fine_twins, mut fine_info, mut fine_starts) = if refine_topology {
        (vec![0u32; 12 * nf], vec![0u32; 4 * nf], vec![INVALID; fine_vertex_count])
    } else {
        (Vec::new(), Vec::new(), Vec::new())
    };

    let (vertex_values, edge_values) = fine_values.split_at_mut(nv.min(fine_vertex_count));
    let (vertex_starts, edge_starts) = fine_starts.split_at_mut(if refine_topology { nv } else { 0 });

    // Face chunks: edge points, fine faces, fine twins and face information.
    let mut work = Vec::with_capacity(nf.div_ceil(FACE_CHUNK));
    {
        let (mut ev, mut tr, mut tw, mut fi, mut es) =
            (edge_values, &mut fine_triangles[..], &mut fine_twins[..], &mut fine_info[..], edge_starts);
        let edge_base = |f: usize| if f == nf { ne } else { (topo.face_info[f] & BASE_MASK) as usize };
        let mut f0 = 0;
        while f0 < nf {
            let f1 = (f0 + FACE_CHUNK).min(nf);
            let edges = edge_base(f1) - edge_base(f0);
            work.push(FaceWork {
                faces: f0..f1,
                first_edge: edge_base(f0),
                edge_values: take_front(&mut ev, edges),
                triangles: take_front(&mut tr, 4 * (f1 - f0)),
                twins: take_front(&mut tw, 12 * (f1 - f0)),
                face_info: take_front(&mut fi, 4 * (f1 - f0)),
                edge_starts: take_front(&mut es, edges),
            });
            f0 = f1;
        }
    }
    work.into_par_iter().for_each(|w| face_chunk(topo, values, w, refine_topology));

    // Vertex chunks: vertex points.
    vertex_values.par_chunks_mut(VERTEX_CHUNK).enumerate().for_each(|(chunk, out)| {
        let first = chunk * VERTEX_CHUNK;
        for (i, slot) in out.iter_mut().enumerate() {
            *slot = vertex_point(topo, values, rules, (first + i) as u32);
        }
    });
    if refine_topology {
        // Corner k of face f becomes corner 0 of child 4f + k: its outgoing half-edge
        // 3f + k becomes 12f + 3k, with the same boundary status.
        vertex_starts.par_chunks_mut(VERTEX_CHUNK).enumerate().for_each(|(chunk, out)| {
            let first = chunk * VERTEX_CHUNK;
            for (i, slot) in out.iter_mut().enumerate() {
                let h = topo.vertex_halfedge[first + i];
                *slot = if h == INVALID { INVALID } else { first_half(h) };
            }
        });
    }

    let topology = Topology {
        triangles: fine_triangles,
        twins: fine_twins,
        face_info: fine_info,
        vertex_halfedge: fine_starts,
        vertex_count: fine_vertex_count,
        edge_count: 2 * ne + 3 * nf,
    };
    Step { values: fine_values, topology }
}

/// Edge points, fine faces and (optionally) fine topology of one chunk of faces.
///
/// Face `f = (c0, c1, c2)` with edge points `m_k` on half-edge `3f + k` (from `c_k` to
/// `c_{k+1}`) gives the children `4f + k = (c_k, m_k, m_{k-1})` for `k = 0, 1, 2` and
/// `4f + 3 = (m0, m1, m2)`. Child half-edges: `12f + 3k` is the first half of `3f + k`,
/// `12f + 3k + 1` runs `m_k -> m_{k-1}`, `12f + 3k + 2` is the second half of
/// `3f + k - 1`, `12f + 9 + j` runs `m_j -> m_{j+1}`.
#[inline(never)]
fn face_chunk<T: Attribute>(topo: &Topology, values: &[T], w: FaceWork<'_, T>, refine_topology: bool) {
    let nv = topo.vertex_count as u32;
    let tri = &topo.triangles[..];
    let twins = &topo.twins[..];
    let info_of = &topo.face_info[..];
    let first_face = w.faces.start;
    for f in w.faces {
        let local = f - first_face;
        let c = tri[f];
        let h0 = 3 * f as u32;
        let tw = [twins[3 * f], twins[3 * f + 1], twins[3 * f + 2]];
        let info = info_of[f];
        let mut next_edge = info & BASE_MASK;
        let mut m = [0u32; 3];
        for k in 0..3 {
            let t = tw[k];
            if is_first(h0 + k as u32, t) {
                let e = next_edge;
                next_edge += 1;
                m[k] = nv + e;
                let slot = e as usize - w.first_edge;
                let a = &values[c[k] as usize];
                let b = &values[c[(k + 1) % 3] as usize];
                let mut point = a.clone();
                point.add(b);
                w.edge_values[slot] = if t == INVALID {
                    point.scaled(0.5)
                } else {
                    let d = tri[(t / 3) as usize][((t % 3 + 2) % 3) as usize];
                    let mut wings = values[c[(k + 2) % 3] as usize].clone();
                    wings.add(&values[d as usize]);
                    let mut point = point.scaled(0.375);
                    point.add_scaled(&wings, 0.125);
                    point
                };
                if refine_topology {
                    // A boundary edge point starts at the second half of its edge (the
                    // fine half-edge without twin); an interior one at its smallest
                    // outgoing half-edge, the start `HalfedgeMesh` would choose, so that
                    // neighbours are summed in the same order whether the levels are
                    // run at once or one by one.
                    let k = k as u32;
                    let offset = if t == INVALID || k == 2 { 3 * ((k + 1) % 3) + 2 } else { 3 * k + 1 };
                    w.edge_starts[slot] = 12 * f as u32 + offset;
                }
            } else {
                let g = t / 3;
                let info = info_of[g as usize];
                let below = (1u32 << (t % 3)) - 1;
                m[k] = nv + (info & BASE_MASK) + ((info >> BASE_BITS) & below).count_ones();
            }
        }
        let out = &mut w.triangles[4 * local..4 * local + 4];
        out[0] = [c[0], m[0], m[2]];
        out[1] = [c[1], m[1], m[0]];
        out[2] = [c[2], m[2], m[1]];
        out[3] = [m[0], m[1], m[2]];
        if refine_topology {
            let base = 12 * f as u32;
            let out = &mut w.twins[12 * local..12 * local + 12];
            for k in 0..3usize {
                let first = 3 * k;
                let second_half = 3 * ((k + 1) % 3) + 2;
                let t = tw[k];
                if t == INVALID {
                    out[first] = INVALID;
                    out[second_half] = INVALID;
                } else {
                    let (g, l) = (t / 3, t % 3);
                    out[first] = 12 * g + 3 * ((l + 1) % 3) + 2;
                    out[second_half] = first_half(t);
                }
                out[3 * k + 1] = base + 9 + ((k as u32 + 2) % 3);
                out[9 + k] = base + 3 * ((k as u32 + 1) % 3) + 1;
            }
            // Fine first-masks: child k holds the first half of 3f + k (bit 0), an
            // interior edge (bit 1, always first) and the second half of 3f + k - 1
            // (bit 2); the centre face holds no first half-edge.
            let first = (info >> BASE_BITS) & 7;
            let bit = |k: u32| (first >> k) & 1;
            let masks = [bit(0) | 2 | (bit(2) << 2), bit(1) | 2 | (bit(0) << 2), bit(2) | 2 | (bit(1) << 2), 0];
            let mut edge_base = 3 * f as u32 + 2 * (info & BASE_MASK);
            let out = &mut w.face_info[4 * local..4 * local + 4];
            for (slot, mask) in out.iter_mut().zip(masks) {
                *slot = edge_base | (mask << BASE_BITS);
                edge_base += mask.count_ones();
            }
        }
    }
}

/// The first half of half-edge `h = 3f + k`: half-edge `12f + 3k` of child `4f + k`.
#[inline(always)]
fn first_half(h: u32) -> u32 {
    4 * h - h % 3
}

/// The vertex point of coarse vertex `v`.
#[inline]
fn vertex_point<T: Attribute>(topo: &Topology, values: &[T], rules: &Rules, v: u32) -> T {
    let start = topo.vertex_halfedge[v as usize];
    let p = &values[v as usize];
    if start == INVALID {
        return p.clone();
    }
    let tri = &topo.triangles[..];
    let twins = &topo.twins[..];
    let mut h = start;
    let mut corners = tri[(h / 3) as usize];
    let mut k = (h % 3) as usize;
    let mut sum = values[corners[(k + 1) % 3] as usize].clone();
    let mut valence = 1usize;
    loop {
        let prev = h - k as u32 + ((k as u32 + 2) % 3);
        let t = twins[prev as usize];
        if t == INVALID {
            // Boundary: the fan ends here; the two boundary neighbours are the targets
            // of the first and the origin of the last fan half-edge.
            if rules.is_fixed_corner(valence + 1) {
                return p.clone();
            }
            let start_corners = tri[(start / 3) as usize];
            let mut ends = values[start_corners[((start % 3 + 1) % 3) as usize] as usize].clone();
            ends.add(&values[corners[(k + 2) % 3] as usize]);
            let mut point = p.scaled(0.75);
            point.add_scaled(&ends, 0.125);
            return point;
        }
        if t == start || valence > twins.len() {
            debug_assert!(t == start, "internal: one-ring walk did not close");
            break;
        }
        h = t;
        corners = tri[(h / 3) as usize];
        k = (h % 3) as usize;
        sum.add(&values[corners[(k + 1) % 3] as usize]);
        valence += 1;
    }
    let (alpha, beta) = rules.interior(valence);
    let mut point = p.scaled(alpha);
    point.add_scaled(&sum, beta);
    point
}
