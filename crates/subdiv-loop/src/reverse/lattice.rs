//! The readings of a closed mesh of valence 6 everywhere, summed from its first reading.
//!
//! Such a mesh is a piece of the regular triangular lattice, and reads four ways: the
//! vertex points of a reading are one coset of the lattice's sublattice of index 4 (the
//! points of even coordinates and its three translates by half a coarse edge). When the
//! mesh is in the canonical order its first reading is known (vertex points `0..V`, edge
//! point `V + e` of coarse edge `e`), and so are the other three: the coarse edges take
//! three colours, the lattice's directions, one of each on every coarse face, and the
//! reading of colour `k` has the edge points of the edges of colour `k` as its vertex
//! points. Every fine vertex is a vertex point in exactly one reading, where its coarse
//! position is the inverse vertex rule on its ring; in each of the other three it is the
//! edge point of a coarse edge whose ends and opposite vertices are fine vertices found
//! from the first reading's corners by index arithmetic. So one pass over the coarse
//! corners gives every reading's sum of squared details, without the searches and
//! reversals of the readings in turn. The reading at hand is reversed already, so its
//! own sum is known: on a mesh of one component the pass stops as soon as the other
//! readings' partial sums (lower bounds of their sums) show it clearly the best.
//!
//! The lattice, with the first reading's coarse face `(a, b, c)` over corner `c0` (the
//! half-edge `a -> b`, its edge point `m`) and the face `(b, a, d)` of its twin `t0`:
//! the edge of `next(t0)` (`a -> d`) is parallel to that of `next(c0)` (`b -> c`) and has
//! its colour, the edge of `prev(t0)` that of `prev(c0)`. Seen from `m`, whose ring is
//! `a, b` and the four other edge points of the two faces:
//! - in the reading of `prev(c0)`'s colour, `m` is the edge point between the edge points
//!   of `prev(c0)` and `prev(t0)`, with opposite vertices the edge points of
//!   `next(twin(next(c0)))` and `next(twin(next(t0)))`;
//! - in the reading of `next(c0)`'s colour, between those of `next(c0)` and `next(t0)`,
//!   opposite `prev(twin(prev(t0)))` and `prev(twin(prev(c0)))`;
//! - in the first reading, between `a` and `b`, opposite `c` and `d`.
//!
//! A vertex point `x` is, in the reading of colour `k`, the edge point between the edge
//! points of its two edges of colour `k`, opposite the edge points of the edges of colour
//! `k` across `x` in its faces.

use glam::DVec3;

use super::{InverseWeights, coarse_position, interior_edge_point};
use crate::corner_table::{CornerTable, NONE, next, prev};
use crate::forward::LoopOptions;

/// The first reading is taken without comparing the readings in turn only where its sum
/// of squared details is below this fraction of every other reading's: the sums here are
/// those of the reversals up to round-off, which is far smaller than this margin (the
/// readings in turn, which decide the closer cases, are the reference).
const CLEAR_MARGIN: f64 = 0.01;

/// Whether, in every component, the first reading of a closed mesh of valence 6
/// everywhere in the canonical order (`coarse`: its coarse mesh, `fine`: the fine
/// positions, `first_energy`: the sum of squared details of that reading's reversal)
/// has a sum of squared details clearly smaller than the other three readings' (see
/// [`CLEAR_MARGIN`]), so that comparing the readings in turn would keep it. `false` when
/// the sums cannot be formed (a boundary, edges without a lattice colouring) or are not
/// clear.
pub(super) fn first_reading_is_clearly_best(
    coarse: &CornerTable,
    fine: &[DVec3],
    first_energy: f64,
    rules: &LoopOptions,
) -> bool {
    match Readings::judged(coarse, fine, first_energy, rules) {
        None => false,
        Some(Judged::FirstClearlyBest) => true,
        Some(Judged::Summed(readings)) => (0..readings.sums.len()).all(|k| readings.clear_winner(k) == Some(0)),
    }
}

/// What [`Readings::judged`] found.
pub(super) enum Judged<'a> {
    /// The mesh is one component, and its first reading is clearly the best.
    FirstClearlyBest,
    /// The sums of every reading of every component.
    Summed(Readings<'a>),
}

/// What [`summed`] found.
enum Summed {
    /// The sums of every component, and the colouring (see [`summed`]).
    All(Vec<[f64; 4]>, Colouring),
    /// One component, whose other readings' partial sums all passed the bound given.
    Enough,
}

/// The four readings of every component of a closed mesh of valence 6 everywhere, seen
/// from one of them (the first reading: `coarse` and the fine mesh in its canonical
/// order): their sums of squared details and which reading each fine vertex is a vertex
/// point of.
pub(super) struct Readings<'a> {
    coarse: &'a CornerTable,
    colouring: Colouring,
    /// Per component, see [`summed`].
    sums: Vec<[f64; 4]>,
}

impl<'a> Readings<'a> {
    /// The readings seen from the first one (`coarse`, `fine` in its canonical order),
    /// whose sum of squared details (of its reversal) is `first_energy`. On a mesh of one
    /// component the pass stops as soon as the other readings' partial sums all exceed
    /// `first_energy / (1 - CLEAR_MARGIN)`: a partial sum is a lower bound of the whole,
    /// so the first reading is then known to be clearly the best. `None` where
    /// [`summed`] is.
    pub(super) fn judged(
        coarse: &'a CornerTable,
        fine: &[DVec3],
        first_energy: f64,
        rules: &LoopOptions,
    ) -> Option<Judged<'a>> {
        let enough = first_energy / (1.0 - CLEAR_MARGIN);
        Some(match summed(coarse, fine, rules, Some(enough))? {
            Summed::Enough => Judged::FirstClearlyBest,
            Summed::All(sums, colouring) => Judged::Summed(Self { coarse, colouring, sums }),
        })
    }

    /// The reading whose vertex point canonical fine vertex `v` is: 0 for the first
    /// reading (`v` below the coarse vertex count), `1 + k` for the edge points of colour
    /// `k`.
    pub(super) fn reading_of(&self, v: usize) -> usize {
        match v.checked_sub(self.coarse.vertex_count()) {
            None => 0,
            Some(e) => 1 + self.colouring.colour(self.coarse.edge_corners()[e]),
        }
    }

    /// The component of canonical fine vertex `v` (as [`summed`] numbers them).
    pub(super) fn component_of(&self, v: usize) -> usize {
        let corner = match v.checked_sub(self.coarse.vertex_count()) {
            None => self.coarse.vertex_corners()[v],
            Some(e) => self.coarse.edge_corners()[e],
        };
        self.colouring.component[(corner / 3) as usize] as usize
    }

    /// The reading of component `k` whose sum is clearly the smallest (see
    /// [`clear_winner`]), if one is.
    pub(super) fn clear_winner(&self, k: usize) -> Option<usize> {
        clear_winner(self.sums[k])
    }
}

/// The reading whose sum is clearly the smallest of `sums` (below `1 - CLEAR_MARGIN`
/// times every other), if one is.
fn clear_winner(sums: [f64; 4]) -> Option<usize> {
    let (winner, &least) = sums.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1))?;
    let clear = sums.iter().enumerate().all(|(r, &sum)| r == winner || least < (1.0 - CLEAR_MARGIN) * sum);
    clear.then_some(winner)
}

/// The sums of [`summed`] without a bound.
#[cfg(test)]
pub(super) fn energies(coarse: &CornerTable, fine: &[DVec3], rules: &LoopOptions) -> Option<Vec<[f64; 4]>> {
    match summed(coarse, fine, rules, None)? {
        Summed::All(sums, _) => Some(sums),
        Summed::Enough => None,
    }
}

/// Edges of the pass over the edge points between two looks at the partial sums.
const EDGES_BETWEEN_LOOKS: usize = 3 << 9;

/// Per component of `coarse` (in order of its lowest face), the sums of squared details
/// of the first reading (at 0) and of the readings of the three edge colours (at `1 + k`),
/// with the colouring found; `None` for an open mesh, a vertex of valence other than 6, a
/// fine mesh of another size, or edges that take no lattice colouring.
///
/// Given `enough`, a mesh of one component is only summed until the sums of readings 1
/// to 3 all exceed it ([`Summed::Enough`]): the edge points' terms come first, by chunks
/// of edges (three quarters of the fine vertices, and the pass that reads the most),
/// then the vertex points'.
fn summed(coarse: &CornerTable, fine: &[DVec3], rules: &LoopOptions, enough: Option<f64>) -> Option<Summed> {
    let (vertex, twin, edge) = (coarse.corner_vertices(), coarse.twins(), coarse.corner_edges());
    let first_odd = coarse.vertex_count();
    if twin.contains(&NONE) || fine.len() != first_odd + coarse.edge_count() {
        return None;
    }
    // Closed: a vertex's valence is its number of corners.
    let mut valence = vec![0u8; first_odd];
    for &v in vertex {
        valence[v as usize] = valence[v as usize].saturating_add(1);
    }
    if valence.iter().any(|&n| n != 6) {
        return None;
    }
    drop(valence);
    let colouring = Colouring::of(twin)?;
    let (colour, component) = (|c: u32| colouring.colour(c), &colouring.component);
    let edge_point = |c: u32| first_odd + edge[c as usize] as usize;

    // Every fine vertex's coarse position in the reading where it is a vertex point, from
    // its ring, summed face by face (no walk through the twins): corner `c`'s edge point
    // `m` has on its ring the face's two other edge points and the vertex at `c` (the
    // face across gives the rest), and that vertex has `m`.
    let mut ring = vec![DVec3::ZERO; fine.len()];
    for (corners, edges) in vertex.chunks_exact(3).zip(edge.chunks_exact(3)) {
        let m = [0, 1, 2].map(|k| first_odd + edges[k] as usize);
        let points = m.map(|m| fine[m]);
        let [p0, p1, p2] = points;
        let others = [p1 + p2, p2 + p0, p0 + p1];
        for k in 0..3 {
            let x = corners[k] as usize;
            ring[m[k]] += others[k] + fine[x];
            ring[x] += points[k];
        }
    }
    let weights = InverseWeights::new(rules.weights);
    // (The ring sums become the positions in place.)
    let mut position = ring;
    for (sum, &p) in position.iter_mut().zip(fine) {
        *sum = coarse_position(p, *sum, 6, false, rules, &weights);
    }
    let position = position;
    let predicted = |ends: [usize; 2], across: [usize; 2]| {
        interior_edge_point(position[ends[0]], position[ends[1]], position[across[0]], position[across[1]])
    };

    let mut sums = vec![[0.0; 4]; colouring.components];
    // Edge points, from the first corner of each edge: the first reading and the readings
    // of the colours of the face's two other edges.
    let add_edge_point = |c: u32, sums: &mut [[f64; 4]]| {
        let t = twin[c as usize];
        let m = edge_point(c);
        let corner = |c: u32| vertex[c as usize] as usize;
        let sum = &mut sums[component[(c / 3) as usize] as usize];
        let first = fine[m] - predicted([corner(c), corner(next(c))], [corner(prev(c)), corner(prev(t))]);
        sum[0] += first.length_squared();
        let by_prev = fine[m]
            - predicted(
                [edge_point(prev(c)), edge_point(prev(t))],
                [edge_point(next(twin[next(c) as usize])), edge_point(next(twin[next(t) as usize]))],
            );
        sum[1 + colour(prev(c))] += by_prev.length_squared();
        let by_next = fine[m]
            - predicted(
                [edge_point(next(c)), edge_point(next(t))],
                [edge_point(prev(twin[prev(t) as usize])), edge_point(prev(twin[prev(c) as usize]))],
            );
        sum[1 + colour(next(c))] += by_next.length_squared();
    };
    let enough = enough.filter(|_| colouring.components == 1);
    // Edge by edge from its first corner, in corner order (not every corner with a test
    // of its twin, as likely to fail as not).
    for first_corners in coarse.edge_corners().chunks(EDGES_BETWEEN_LOOKS) {
        for &c in first_corners {
            add_edge_point(c, &mut sums);
        }
        if let Some(enough) = enough
            && sums[0][1..].iter().all(|&sum| sum > enough)
        {
            return Some(Summed::Enough);
        }
    }
    // Vertex points, reading `1 + k`: the edge rule on their two edges of colour `k`
    // (weight 3/8) and the two edges of colour `k` across them (1/8), summed per vertex.
    let mut predicted_at = vec![[DVec3::ZERO; 3]; first_odd];
    let mut vertex_component = vec![0u32; first_odd];
    for c in 0..vertex.len() as u32 {
        let x = vertex[c as usize] as usize;
        predicted_at[x][colour(c)] += 0.375 * position[edge_point(c)];
        predicted_at[x][colour(next(c))] += 0.125 * position[edge_point(next(c))];
        vertex_component[x] = component[(c / 3) as usize];
    }
    for (x, predicted) in predicted_at.iter().enumerate() {
        let sum = &mut sums[vertex_component[x] as usize];
        for (k, &predicted) in predicted.iter().enumerate() {
            sum[1 + k] += (fine[x] - predicted).length_squared();
        }
    }
    Some(Summed::All(sums, colouring))
}

/// A colouring of the edges of a closed triangle mesh by three lattice directions: every
/// face has the three colours, in the same cyclic order on every face (corner `k` of face
/// `f` has colour `k + shift(f)` modulo 3), and the two corners of an edge one colour.
struct Colouring {
    /// The colour of every corner.
    corner_colour: Vec<u8>,
    /// Component of every face (by a search from its lowest face).
    component: Vec<u32>,
    components: usize,
}

impl Colouring {
    /// `None` where a face is reached with two shifts (no lattice colouring).
    ///
    /// A breadth-first search whose steps do not branch on what they find: the next face
    /// read is the next in the queue whatever the last one found, so the reads of
    /// successive faces overlap (a stack's top would wait on the last read), and whether
    /// a face across was reached before, as likely as not, decides no branch: it is
    /// written at the queue's tail, which only advances for a new face, and the check of
    /// its shift is folded into one flag per component.
    fn of(twin: &[u32]) -> Option<Self> {
        const UNSET: u8 = u8::MAX;
        let faces = twin.len() / 3;
        let mut shift = vec![UNSET; faces];
        let mut component = vec![0u32; faces];
        let mut components = 0u32;
        // A face is queued once, when first reached: `faces` slots, plus one for the
        // write of a face reached before.
        let mut queue = vec![0u32; faces + 1];
        let mut tail = 0;
        for start in 0..faces {
            if shift[start] != UNSET {
                continue;
            }
            shift[start] = 0;
            component[start] = components;
            let mut head = tail;
            queue[tail] = start as u32;
            tail += 1;
            let mut consistent = true;
            while head < tail {
                let f = queue[head] as usize;
                head += 1;
                let s = u32::from(shift[f]);
                for k in 0..3 {
                    let t = *twin.get(3 * f + k)?;
                    let g = (t / 3) as usize;
                    // The twin's corner takes the same colour, `k + s`.
                    let wanted = ((k as u32 + s + 3 - t % 3) % 3) as u8;
                    let seen = *shift.get(g)?;
                    let new = seen == UNSET;
                    consistent &= new | (seen == wanted);
                    shift[g] = if new { wanted } else { seen };
                    // A face reached before is of this component already.
                    component[g] = components;
                    queue[tail] = g as u32;
                    tail += usize::from(new);
                }
            }
            if !consistent {
                return None;
            }
            components += 1;
        }
        const ROTATED: [[u8; 3]; 3] = [[0, 1, 2], [1, 2, 0], [2, 0, 1]];
        let mut corner_colour = Vec::with_capacity(twin.len());
        for &s in &shift {
            corner_colour.extend_from_slice(&ROTATED[s as usize]);
        }
        Some(Self { corner_colour, component, components: components as usize })
    }

    /// The colour of corner `c`.
    #[inline]
    fn colour(&self, c: u32) -> usize {
        self.corner_colour[c as usize] as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::forward::{VertexWeights, subdivide};
    use crate::reference::perturb;
    use crate::reverse::{FineLevel, ReverseOptions, detail_energy, reverse, reverse_level_fast};
    use mesh_topo::shapes::{self, CellKind};
    use mesh_topo::{HalfedgeMesh, PolygonSoup};

    /// A torus of `columns x rows x 2` triangles refined `levels` times (the canonical
    /// order), every vertex moved at random by up to `amount`.
    fn moved_torus(columns: u32, rows: u32, levels: u32, rules: &LoopOptions, amount: f64, seed: u64) -> HalfedgeMesh {
        let base = HalfedgeMesh::from_soup(&shapes::torus(columns, rows, CellKind::Triangles).unwrap()).unwrap();
        let fine = subdivide(&base, levels, rules).unwrap();
        let soup = PolygonSoup::from_faces(fine.positions, fine.triangles);
        HalfedgeMesh::from_soup(&perturb(&soup, amount, seed)).unwrap()
    }

    /// The first reading of a mesh in the canonical order, as `reverse_level` has it.
    fn first_reading(fine: &HalfedgeMesh, rules: &LoopOptions) -> CornerTable {
        let level = reverse_level_fast(FineLevel::Mesh(fine), fine.positions(), &[], rules).unwrap().unwrap();
        assert!(level.order.is_none() && level.several_readings, "a canonical reading of a regular mesh");
        level.coarse
    }

    /// The sums are those of the reversals of the four readings (each seeded with one of
    /// its vertex points), under both vertex weights, on tori of several sizes.
    #[test]
    fn the_sums_are_those_of_the_readings_reversed() {
        for weights in [VertexWeights::Loop, VertexWeights::Warren] {
            let rules = LoopOptions { weights, keep_corners: false };
            for (columns, rows, levels, seed) in [(6, 4, 1, 1), (8, 6, 2, 2), (12, 8, 1, 3), (9, 7, 1, 4)] {
                let fine = moved_torus(columns, rows, levels, &rules, 0.05, seed);
                let coarse = first_reading(&fine, &rules);
                let sums = energies(&coarse, fine.positions(), &rules).expect("a lattice");
                assert_eq!(sums.len(), 1, "one component");
                let colouring = Colouring::of(coarse.twins()).unwrap();
                let first_odd = coarse.vertex_count() as u32;
                let mut compared = 0;
                for (reading, &by_lattice) in sums[0].iter().enumerate() {
                    // A vertex point of the reading: vertex 0, or the edge point of an
                    // edge of its colour.
                    let seed = match reading {
                        0 => 0,
                        _ => {
                            let c = (0..coarse.corner_count() as u32).find(|&c| colouring.colour(c) + 1 == reading);
                            first_odd + coarse.corner_edges()[c.unwrap() as usize]
                        }
                    };
                    let options = ReverseOptions { rules, seed_vertices: vec![seed] };
                    let Ok(level) = reverse(&fine, &options) else { continue };
                    let energy = detail_energy(&level.details);
                    assert!(
                        (by_lattice - energy).abs() <= 1e-12 * energy,
                        "{columns} x {rows}, {levels} level(s), {weights:?}, reading {reading}: {by_lattice} vs {energy}"
                    );
                    compared += 1;
                }
                assert!(compared >= 3, "{columns} x {rows}: several readings ({compared})");
            }
        }
    }

    /// The answer of the pass that stops once the other readings' partial sums pass the
    /// bound is that of the full sums, on tori moved a little (the first reading clearly
    /// the best: the pass stops early on the larger tori) and a lot (it is not).
    #[test]
    fn stopping_early_gives_the_answer_of_the_full_sums() {
        let (mut early, mut clear, mut unclear) = (0, 0, 0);
        for weights in [VertexWeights::Loop, VertexWeights::Warren] {
            let rules = LoopOptions { weights, keep_corners: false };
            for (columns, rows, levels) in [(8, 6, 1), (32, 16, 2), (48, 24, 1)] {
                for (k, amount) in [1e-4, 1e-3, 0.01, 0.05, 0.3, 1.0].into_iter().enumerate() {
                    let fine = moved_torus(columns, rows, levels, &rules, amount, 10 + k as u64);
                    let level = reverse_level_fast(FineLevel::Mesh(&fine), fine.positions(), &[], &rules);
                    let level = level.unwrap().unwrap();
                    let first_energy = detail_energy(&level.details);
                    let sums = energies(&level.coarse, fine.positions(), &rules).expect("a lattice");
                    let by_full_sums = clear_winner(sums[0]) == Some(0);
                    let answer = first_reading_is_clearly_best(&level.coarse, fine.positions(), first_energy, &rules);
                    assert_eq!(
                        answer, by_full_sums,
                        "{columns} x {rows}, moved by {amount}: {sums:?} vs {first_energy}"
                    );
                    let bound = Some(first_energy / (1.0 - CLEAR_MARGIN));
                    early += usize::from(matches!(
                        summed(&level.coarse, fine.positions(), &rules, bound),
                        Some(Summed::Enough)
                    ));
                    (clear, unclear) = if by_full_sums { (clear + 1, unclear) } else { (clear, unclear + 1) };
                }
            }
        }
        assert!(early > 0 && clear > early && unclear > 0, "{early} early of {clear} clear, {unclear} not");
    }

    /// Two tori refined together: one sum per component, each that of the torus alone.
    #[test]
    fn components_are_summed_apart() {
        let rules = LoopOptions::default();
        let (a, b) =
            (shapes::torus(6, 4, CellKind::Triangles).unwrap(), shapes::torus(8, 6, CellKind::Triangles).unwrap());
        let mut both = a.clone();
        let offset = a.vertex_count() as u32;
        both.positions.extend(b.positions.iter().map(|&p| p + DVec3::splat(10.0)));
        for face in b.faces() {
            both.push_face(&face.iter().map(|&v| v + offset).collect::<Vec<u32>>());
        }
        let refine = |soup: &PolygonSoup| {
            let fine = subdivide(&HalfedgeMesh::from_soup(soup).unwrap(), 1, &rules).unwrap();
            HalfedgeMesh::from_soup(&perturb(&PolygonSoup::from_faces(fine.positions, fine.triangles), 0.05, 7))
                .unwrap()
        };
        let fine = refine(&both);
        let sums = energies(&first_reading(&fine, &rules), fine.positions(), &rules).unwrap();
        assert_eq!(sums.len(), 2);
        assert!(sums.iter().all(|s| s.iter().all(|&e| e > 0.0)));
    }

    /// The colouring gives the two corners of every edge one colour and every face the
    /// three, one component per torus; two edges of different colours with their twins
    /// crossed (every valence still 6) leave none.
    #[test]
    fn the_colouring_is_the_lattice_one_and_crossed_edges_have_none() {
        let torus = |columns, rows| CornerTable::from_soup(&shapes::torus(columns, rows, CellKind::Triangles).unwrap());
        for (columns, rows) in [(6, 4), (9, 7), (32, 16)] {
            let table = torus(columns, rows).unwrap();
            let twin = table.twins();
            let colouring = Colouring::of(twin).expect("a lattice colouring");
            assert_eq!(colouring.components, 1);
            for c in 0..twin.len() as u32 {
                assert_eq!(colouring.colour(c), colouring.colour(twin[c as usize]), "corner {c}");
                let f = 3 * (c / 3);
                let mut face = [0, 1, 2].map(|k| colouring.colour(f + k));
                face.sort_unstable();
                assert_eq!(face, [0, 1, 2], "face {}", c / 3);
            }
            let first = 0u32;
            let other = (1..twin.len() as u32)
                .find(|&c| c / 3 != 0 && twin[c as usize] / 3 != 0 && colouring.colour(c) != colouring.colour(first))
                .unwrap();
            let mut crossed = twin.to_vec();
            let (t_first, t_other) = (twin[first as usize], twin[other as usize]);
            crossed[first as usize] = t_other;
            crossed[t_other as usize] = first;
            crossed[other as usize] = t_first;
            crossed[t_first as usize] = other;
            assert!(Colouring::of(&crossed).is_none(), "{columns} x {rows}: corners {first} and {other} crossed");
        }
        // Two tori side by side: two components.
        let (a, b) = (torus(6, 4).unwrap(), torus(8, 6).unwrap());
        let offset = a.corner_count() as u32;
        let both: Vec<u32> = a.twins().iter().copied().chain(b.twins().iter().map(|&t| t + offset)).collect();
        assert_eq!(Colouring::of(&both).unwrap().components, 2);
    }

    /// A closed mesh with a vertex of valence other than 6 has no sums.
    #[test]
    fn irregular_valences_have_no_sums() {
        let rules = LoopOptions::default();
        let fine = subdivide(&HalfedgeMesh::from_soup(&shapes::octahedron()).unwrap(), 1, &rules).unwrap();
        let fine = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(fine.positions, fine.triangles)).unwrap();
        let level = reverse_level_fast(FineLevel::Mesh(&fine), fine.positions(), &[], &rules).unwrap().unwrap();
        assert!(energies(&level.coarse, fine.positions(), &rules).is_none());
    }

    /// A mesh with a boundary has no sums here (the readings in turn decide it).
    #[test]
    fn an_open_mesh_has_no_sums() {
        let rules = LoopOptions::default();
        let grid = shapes::grid(4, 4, CellKind::Triangles).unwrap();
        let fine = subdivide(&HalfedgeMesh::from_soup(&grid).unwrap(), 1, &rules).unwrap();
        let fine = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(fine.positions, fine.triangles)).unwrap();
        let level = reverse_level_fast(FineLevel::Mesh(&fine), fine.positions(), &[], &rules).unwrap().unwrap();
        assert!(energies(&level.coarse, fine.positions(), &rules).is_none());
        // (Not even with a first reading of no detail at all.)
        assert!(!first_reading_is_clearly_best(&level.coarse, fine.positions(), 0.0, &rules));
    }
}
