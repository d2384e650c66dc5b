//! Test inputs for examples, tests and benchmarks: regular triangular grids sampled from
//! a function, the smooth test surface of ALGORITHMS.md §12.4, and disk patches cut from
//! a mesh.

use glam::DVec3;
use mesh_topo::{HalfedgeMesh, PolygonSoup};

use crate::index::{multi_indices, tri_index};
use crate::surface::grid_triangles;

/// The smooth test surface of ALGORITHMS.md §12.4 (Appendix A):
/// `(a, b, 0.3 sin(3a) cos(2b) + 0.2 a b)`.
pub fn smooth_surface(a: f64, b: f64) -> DVec3 {
    DVec3::new(a, b, 0.3 * (3.0 * a).sin() * (2.0 * b).cos() + 0.2 * a * b)
}

/// The regular triangular grid with `n` segments per side over the unit right triangle,
/// vertex `(j, k)` at `f(j/n, k/n)` and at position [`tri_index`]`(n, j, k)`;
/// `(n+1)(n+2)/2` vertices, `n²` counter-clockwise triangles. Loop subdivision of a
/// triangle `i` times gives this connectivity with `n = 2^i`, so a grid with `n`
/// divisible by `2^i` allows `i` reverse-Loop levels.
///
/// ```
/// use tri_spline::samples::{smooth_surface, triangle_grid};
/// let soup = triangle_grid(96, smooth_surface);
/// assert_eq!((soup.vertex_count(), soup.face_count()), (4753, 9216));
/// ```
pub fn triangle_grid(n: usize, f: impl Fn(f64, f64) -> DVec3) -> PolygonSoup {
    let n = n.max(1);
    let mut positions = vec![DVec3::ZERO; crate::index::tri_count(n)];
    for [_, j, k] in multi_indices(n) {
        positions[tri_index(n, j, k)] = f(j as f64 / n as f64, k as f64 / n as f64);
    }
    PolygonSoup::from_faces(positions, grid_triangles(n, true))
}

/// The closed star of the `rings`-ring of `seed_vertex`: every face with a vertex within
/// `rings` edges of the seed (a vertex of valence 6 with `rings = 2` gives 54 faces and
/// 37 vertices, the size of seed paper 001's triangular B-spline example). Vertices are
/// renumbered in order of first use; positions are scaled about the patch's bounding-box
/// centre so that its largest extent is 1.
///
/// `None` unless the patch is a topological disk with at most three ear tips (boundary
/// vertices with one face), as the fitting pipeline needs.
pub fn disk_patch(mesh: &HalfedgeMesh, seed_vertex: usize, rings: usize) -> Option<PolygonSoup> {
    let seed = mesh.vertex(seed_vertex)?;
    let mut distance = vec![usize::MAX; mesh.vertex_count()];
    distance[seed.index()] = 0;
    let mut frontier = vec![seed];
    for d in 1..=rings {
        let mut next = Vec::new();
        for v in frontier {
            for w in mesh.vertex_neighbors(v) {
                if distance[w.index()] == usize::MAX {
                    distance[w.index()] = d;
                    next.push(w);
                }
            }
        }
        frontier = next;
    }
    let mut index = vec![u32::MAX; mesh.vertex_count()];
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for f in mesh.faces() {
        let corners: Vec<_> = mesh.face_vertices(f).collect();
        if corners.len() != 3 || corners.iter().all(|v| distance[v.index()] == usize::MAX) {
            continue;
        }
        let tri: Vec<u32> = corners
            .iter()
            .map(|&v| {
                if index[v.index()] == u32::MAX {
                    index[v.index()] = positions.len() as u32;
                    positions.push(mesh.position(v));
                }
                index[v.index()]
            })
            .collect();
        triangles.push([tri[0], tri[1], tri[2]]);
    }
    let (lo, hi) = positions.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), &p| (l.min(p), h.max(p)));
    let centre = (lo + hi) * 0.5;
    let scale = 1.0 / (hi - lo).max_element().max(f64::MIN_POSITIVE);
    let positions: Vec<DVec3> = positions.into_iter().map(|p| (p - centre) * scale).collect();
    let soup = PolygonSoup::from_faces(positions, triangles);
    let patch = HalfedgeMesh::from_soup(&soup).ok()?;
    let stats = patch.topology_stats();
    let ears = patch.vertices().filter(|&v| patch.vertex_faces(v).count() == 1).count();
    (stats.boundary_loops == 1 && stats.euler == 1 && ears <= 3).then_some(soup)
}
