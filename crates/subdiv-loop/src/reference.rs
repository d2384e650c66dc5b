//! Test utilities: a deliberately plain reference Loop step (ALGORITHMS.md §6.1–6.3,
//! written against `HalfedgeMesh` with no shared code), mesh scrambling and test shapes.

use glam::DVec3;
use mesh_topo::{HalfedgeMesh, PolygonSoup};

use crate::forward::{LoopOptions, VertexWeights};

/// One Loop step of a triangle mesh, canonical output order: vertex `v` stays `v`, edge
/// `e` becomes vertex `V + e`, face `f = (a, b, c)` becomes faces `4f..4f+4` =
/// `(a, ab, ca)`, `(b, bc, ab)`, `(c, ca, bc)`, `(ab, bc, ca)`.
pub(crate) fn loop_step(mesh: &HalfedgeMesh, rules: &LoopOptions) -> PolygonSoup {
    let nv = mesh.vertex_count();
    let mut positions = Vec::with_capacity(nv + mesh.edge_count());
    for v in mesh.vertices() {
        let p = mesh.position(v);
        if mesh.is_isolated(v) {
            positions.push(p);
        } else if mesh.is_boundary_vertex(v) {
            let valence = mesh.valence(v);
            if rules.keep_corners && valence == 2 {
                positions.push(p);
            } else {
                let boundary_neighbours: Vec<DVec3> = mesh
                    .outgoing_halfedges(v)
                    .filter(|h| mesh.is_boundary_edge(h.edge()))
                    .map(|h| mesh.position(mesh.target(h)))
                    .collect();
                assert_eq!(boundary_neighbours.len(), 2);
                positions.push(0.75 * p + 0.125 * (boundary_neighbours[0] + boundary_neighbours[1]));
            }
        } else {
            let n = mesh.valence(v);
            let beta = match rules.weights {
                VertexWeights::Loop => {
                    let c = 3.0 / 8.0 + 0.25 * (std::f64::consts::TAU / n as f64).cos();
                    (5.0 / 8.0 - c * c) / n as f64
                }
                VertexWeights::Warren if n == 3 => 3.0 / 16.0,
                VertexWeights::Warren => 3.0 / (8.0 * n as f64),
            };
            let alpha = 1.0 - n as f64 * beta;
            let sum: DVec3 = mesh.vertex_neighbors(v).map(|w| mesh.position(w)).sum();
            positions.push(alpha * p + beta * sum);
        }
    }
    for e in mesh.edges() {
        let [a, b] = mesh.edge_vertices(e);
        let (pa, pb) = (mesh.position(a), mesh.position(b));
        if mesh.is_boundary_edge(e) {
            positions.push(0.5 * (pa + pb));
        } else {
            let opposite = |side: u32| mesh.position(mesh.target(mesh.next(e.halfedge(side))));
            positions.push(0.375 * (pa + pb) + 0.125 * (opposite(0) + opposite(1)));
        }
    }
    let edge_point = |a, b| {
        let h = mesh.find_halfedge(a, b).expect("edge of a face");
        nv as u32 + h.edge().raw()
    };
    let mut faces = Vec::with_capacity(4 * mesh.face_count());
    for f in mesh.faces() {
        let corners: Vec<_> = mesh.face_vertices(f).collect();
        let [a, b, c] = [corners[0], corners[1], corners[2]];
        let (ab, bc, ca) = (edge_point(a, b), edge_point(b, c), edge_point(c, a));
        faces.push([a.raw(), ab, ca]);
        faces.push([b.raw(), bc, ab]);
        faces.push([c.raw(), ca, bc]);
        faces.push([ab, bc, ca]);
    }
    PolygonSoup::from_faces(positions, faces)
}

/// `levels` reference Loop steps.
pub(crate) fn loop_steps(soup: &PolygonSoup, rules: &LoopOptions, levels: usize) -> PolygonSoup {
    let mut soup = soup.clone();
    for _ in 0..levels {
        soup = loop_step(&HalfedgeMesh::from_soup(&soup).expect("valid mesh"), rules);
    }
    soup
}

/// A small deterministic generator (xorshift64*).
pub(crate) struct Rng(u64);

impl Rng {
    pub(crate) fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1)
    }
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    pub(crate) fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
    /// Uniform in [-1, 1].
    pub(crate) fn signed(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
    pub(crate) fn vector(&mut self) -> DVec3 {
        DVec3::new(self.signed(), self.signed(), self.signed())
    }
}

/// Renumbers vertices and faces randomly and rotates every face's corner list.
pub(crate) fn scramble(soup: &PolygonSoup, seed: u64) -> PolygonSoup {
    let mut rng = Rng::new(seed);
    let n = soup.vertex_count();
    let mut new_of_old: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        new_of_old.swap(i, rng.below(i + 1));
    }
    let mut positions = vec![DVec3::ZERO; n];
    for (old, &new) in new_of_old.iter().enumerate() {
        positions[new as usize] = soup.positions[old];
    }
    let mut faces: Vec<Vec<u32>> = soup.faces().map(|f| f.iter().map(|&v| new_of_old[v as usize]).collect()).collect();
    for i in (1..faces.len()).rev() {
        faces.swap(i, rng.below(i + 1));
    }
    for face in &mut faces {
        let shift = rng.below(face.len());
        face.rotate_left(shift);
    }
    PolygonSoup::from_faces(positions, faces)
}

/// Moves every vertex by a random vector of length at most `amount`.
pub(crate) fn perturb(soup: &PolygonSoup, amount: f64, seed: u64) -> PolygonSoup {
    let mut rng = Rng::new(seed);
    let mut out = soup.clone();
    for p in &mut out.positions {
        *p += amount * rng.vector();
    }
    out
}

/// A bipyramid over an `n`-gon: two apices of valence `n`, equator vertices of valence 4.
pub(crate) fn bipyramid(n: u32) -> PolygonSoup {
    let mut positions: Vec<DVec3> = (0..n)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / n as f64;
            DVec3::new(t.cos(), t.sin(), 0.1 * (i % 2) as f64)
        })
        .collect();
    positions.push(DVec3::new(0.0, 0.0, 1.0));
    positions.push(DVec3::new(0.1, 0.0, -1.2));
    let (top, bottom) = (n, n + 1);
    let mut faces = Vec::new();
    for i in 0..n {
        let j = (i + 1) % n;
        faces.push([i, j, top]);
        faces.push([j, i, bottom]);
    }
    PolygonSoup::from_faces(positions, faces)
}

/// An open fan of `n` triangles around a centre (boundary valence `n + 1`; the two ends
/// are corners of valence 2).
pub(crate) fn open_fan(n: u32) -> PolygonSoup {
    let mut positions = vec![DVec3::new(0.0, 0.0, 0.3)];
    for i in 0..=n {
        let t = 1.5 * std::f64::consts::PI * i as f64 / n as f64;
        positions.push(DVec3::new(t.cos(), t.sin(), 0.05 * i as f64));
    }
    let faces: Vec<[u32; 3]> = (0..n).map(|i| [0, i + 1, i + 2]).collect();
    PolygonSoup::from_faces(positions, faces)
}

/// Largest distance between corresponding vertices divided by the bounding-box diagonal
/// of `expected`, after checking that the faces are identical.
pub(crate) fn relative_distance(actual: &PolygonSoup, expected: &PolygonSoup) -> f64 {
    assert_eq!(actual.offsets, expected.offsets, "face offsets differ");
    assert_eq!(actual.indices, expected.indices, "faces differ");
    assert_eq!(actual.positions.len(), expected.positions.len(), "vertex counts differ");
    let diagonal = crate::pyramid::bounding_box_diagonal(&expected.positions).max(f64::MIN_POSITIVE);
    actual.positions.iter().zip(&expected.positions).map(|(p, q)| p.distance(*q)).fold(0.0, f64::max) / diagonal
}

/// An open cylinder: `around` cells around, `along` cells along; every interior vertex
/// has valence 6 and every boundary vertex valence 4 (all valences regular).
pub(crate) fn cylinder(around: u32, along: u32) -> PolygonSoup {
    let index = |i: u32, j: u32| (i % around) + around * j;
    let mut positions = Vec::new();
    for j in 0..=along {
        for i in 0..around {
            let t = std::f64::consts::TAU * i as f64 / around as f64;
            positions.push(DVec3::new(t.cos(), t.sin(), j as f64 * 0.7));
        }
    }
    let mut faces = Vec::new();
    for j in 0..along {
        for i in 0..around {
            faces.push([index(i, j), index(i + 1, j), index(i + 1, j + 1)]);
            faces.push([index(i, j), index(i + 1, j + 1), index(i, j + 1)]);
        }
    }
    PolygonSoup::from_faces(positions, faces)
}

/// `flips` attempts at flipping a random edge of a valid mesh (random from `seed`): an
/// attempt that picks a boundary edge, or whose flip would not be a valid mesh, changes
/// nothing. Most refined meshes lose their Loop connectivity this way.
pub(crate) fn flip_random_edges(soup: PolygonSoup, flips: usize, seed: u64) -> PolygonSoup {
    let mut soup = soup;
    let mut rng = Rng::new(seed);
    for _ in 0..flips {
        let mesh = HalfedgeMesh::from_soup(&soup).expect("valid mesh");
        let e = mesh.edge(rng.below(mesh.edge_count())).expect("edge in range");
        if !mesh.is_boundary_edge(e) {
            let [a, b] = mesh.edge_vertices(e);
            let flipped = flip_edge(&soup, a.raw(), b.raw());
            if HalfedgeMesh::from_soup(&flipped).is_ok() {
                soup = flipped;
            }
        }
    }
    soup
}

/// Replaces the diagonal of the two triangles sharing edge (a, b) by the other one.
/// Panics if (a, b) is not an interior edge.
pub(crate) fn flip_edge(soup: &PolygonSoup, a: u32, b: u32) -> PolygonSoup {
    let mut faces: Vec<Vec<u32>> = soup.faces().map(<[u32]>::to_vec).collect();
    let find = |from: u32, to: u32, faces: &[Vec<u32>]| {
        faces.iter().position(|f| (0..3).any(|k| f[k] == from && f[(k + 1) % 3] == to)).expect("edge of a face")
    };
    let (f, g) = (find(a, b, &faces), find(b, a, &faces));
    let third = |face: &[u32]| *face.iter().find(|&&v| v != a && v != b).expect("triangle");
    let (c, d) = (third(&faces[f]), third(&faces[g]));
    faces[f] = vec![a, d, c];
    faces[g] = vec![d, b, c];
    PolygonSoup::from_faces(soup.positions.clone(), faces)
}

/// A square grid whose cells are split along a random diagonal each: an irregular
/// triangulation without subdivision connectivity.
pub(crate) fn random_diagonal_grid(n: u32, seed: u64) -> PolygonSoup {
    let mut rng = Rng::new(seed);
    let index = |i: u32, j: u32| i + (n + 1) * j;
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            positions.push(DVec3::new(
                i as f64 + 0.2 * rng.signed(),
                j as f64 + 0.2 * rng.signed(),
                0.1 * rng.signed(),
            ));
        }
    }
    let mut faces = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let (a, b, c, d) = (index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1));
            if rng.below(2) == 0 {
                faces.push([a, b, c]);
                faces.push([a, c, d]);
            } else {
                faces.push([a, b, d]);
                faces.push([b, c, d]);
            }
        }
    }
    PolygonSoup::from_faces(positions, faces)
}

/// Swaps the numbers of vertices `a` and `b`.
pub(crate) fn swap_vertices(soup: &PolygonSoup, a: u32, b: u32) -> PolygonSoup {
    let mut out = soup.clone();
    out.positions.swap(a as usize, b as usize);
    for v in &mut out.indices {
        if *v == a {
            *v = b;
        } else if *v == b {
            *v = a;
        }
    }
    out
}

/// The faces of one Loop step in the canonical order (see [`loop_step`]) of any triangle
/// soup, valid mesh or not: edge `{a, b}` is numbered by the first corner whose side
/// joins `a` and `b`, in either direction, and its edge point is vertex `V + e`. On a
/// valid mesh these are the faces of `loop_step`; on a broken one (a bowtie vertex, a
/// flipped or repeated face) they are the soup that a canonical reading must not
/// mistake for a valid refinement. Positions are random (from `seed`).
pub(crate) fn canonical_faces(coarse: &PolygonSoup, seed: u64) -> PolygonSoup {
    let nv = coarse.vertex_count() as u32;
    let mut edges = std::collections::HashMap::new();
    let mut edge_point = |a: u32, b: u32| {
        let next = nv + edges.len() as u32;
        *edges.entry((a.min(b), a.max(b))).or_insert(next)
    };
    let mut faces = Vec::new();
    for face in coarse.faces() {
        let [a, b, c] = [face[0], face[1], face[2]];
        let (ab, bc, ca) = (edge_point(a, b), edge_point(b, c), edge_point(c, a));
        faces.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    let mut rng = Rng::new(seed);
    let positions = (0..nv as usize + edges.len()).map(|_| rng.vector()).collect();
    PolygonSoup::from_faces(positions, faces)
}
