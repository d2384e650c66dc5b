//! Test inputs for examples, tests and benchmarks: regular triangular grids sampled from
//! a function, the smooth test surface of ALGORITHMS.md §12.4, and disk patches cut from
//! a mesh.

use glam::{DVec2, DVec3};
use mesh_topo::{HalfedgeMesh, PolygonSoup};

use crate::index::{multi_indices, tri_index};
use crate::surface::grid_triangles;

/// The smooth test surface of ALGORITHMS.md §12.4 (Appendix A):
/// `(a, b, 0.3 sin(3a) cos(2b) + 0.2 a b)`.
///
/// ```
/// use glam::DVec3;
/// use tri_spline::samples::smooth_surface;
/// assert_eq!(smooth_surface(0.0, 0.7), DVec3::new(0.0, 0.7, 0.0));
/// assert_eq!(smooth_surface(0.5, 0.0), DVec3::new(0.5, 0.0, 0.3 * 1.5f64.sin()));
/// ```
pub fn smooth_surface(a: f64, b: f64) -> DVec3 {
    DVec3::new(a, b, 0.3 * (3.0 * a).sin() * (2.0 * b).cos() + 0.2 * a * b)
}

/// The plane domain `[0, cells]²` cut into unit squares, each split along its diagonal
/// from `(i, j)` to `(i + 1, j + 1)`: `(cells + 1)²` vertices, row by row, and `2 cells²`
/// counter-clockwise triangles, the kind of triangulation a [`DmsBasis`](crate::DmsBasis)
/// is built on.
///
/// ```
/// use tri_spline::samples::square_triangulation;
/// let (vertices, triangles) = square_triangulation(2);
/// assert_eq!((vertices.len(), triangles.len()), (9, 8));
/// assert_eq!((vertices[4].x, vertices[4].y), (1.0, 1.0));
/// assert_eq!(triangles[..2], [[0, 1, 4], [0, 4, 3]]);
/// ```
pub fn square_triangulation(cells: u32) -> (Vec<DVec2>, Vec<[u32; 3]>) {
    let row = cells + 1;
    let vertices = (0..row).flat_map(|j| (0..row).map(move |i| DVec2::new(i as f64, j as f64))).collect();
    let mut triangles = Vec::with_capacity(2 * (cells * cells) as usize);
    for j in 0..cells {
        for i in 0..cells {
            let a = j * row + i;
            triangles.push([a, a + 1, a + row + 1]);
            triangles.push([a, a + row + 1, a + row]);
        }
    }
    (vertices, triangles)
}

/// Most segments per side of the grids made here ([`triangle_grid`],
/// [`resample_on_grid`]): about 8.4 million vertices and 16.8 million triangles, beyond
/// any grid the fitting pipeline can use.
pub const MAX_GRID_SEGMENTS: usize = 4096;

/// The regular triangular grid with `n` segments per side over the unit right triangle,
/// vertex `(j, k)` at `f(j/n, k/n)` and at position [`tri_index`]`(n, j, k)`;
/// `(n+1)(n+2)/2` vertices, `n²` counter-clockwise triangles (`n = 0` gives the
/// one-segment grid). Loop subdivision of a triangle `i` times gives this connectivity
/// with `n = 2^i`, so a grid with `n` divisible by `2^i` allows `i` reverse-Loop levels.
///
/// # Panics
/// Above [`MAX_GRID_SEGMENTS`] segments per side (a mistyped size used to abort the
/// process allocating); [`try_triangle_grid`] returns an error instead.
///
/// ```
/// use tri_spline::samples::{smooth_surface, triangle_grid};
/// let soup = triangle_grid(96, smooth_surface);
/// assert_eq!((soup.vertex_count(), soup.face_count()), (4753, 9216));
/// ```
pub fn triangle_grid(n: usize, f: impl Fn(f64, f64) -> DVec3) -> PolygonSoup {
    try_triangle_grid(n, f).unwrap_or_else(|e| panic!("triangle_grid: {e}"))
}

/// [`triangle_grid`] for a size given by a caller.
///
/// # Errors
/// [`SplineError::TooLarge`](crate::SplineError::TooLarge) above [`MAX_GRID_SEGMENTS`]
/// segments per side, checked before allocating.
///
/// ```
/// use tri_spline::samples::{smooth_surface, try_triangle_grid};
/// assert_eq!(try_triangle_grid(2, smooth_surface)?.face_count(), 4);
/// assert!(try_triangle_grid(1 << 40, smooth_surface).is_err());
/// # Ok::<(), tri_spline::SplineError>(())
/// ```
pub fn try_triangle_grid(n: usize, f: impl Fn(f64, f64) -> DVec3) -> Result<PolygonSoup, crate::SplineError> {
    if n > MAX_GRID_SEGMENTS {
        return Err(crate::SplineError::TooLarge {
            what: "grid segments per side",
            requested: n,
            max: MAX_GRID_SEGMENTS,
        });
    }
    let n = n.max(1);
    let mut positions = vec![DVec3::ZERO; crate::index::tri_count(n)];
    for [_, j, k] in multi_indices(n) {
        positions[tri_index(n, j, k)] = f(j as f64 / n as f64, k as f64 / n as f64);
    }
    Ok(PolygonSoup::from_faces(positions, grid_triangles(n, true)))
}

/// The closed star of the `rings`-ring of `seed_vertex`: every face with a vertex within
/// `rings` edges of the seed (a vertex of valence 6 with `rings = 2` gives 54 faces and
/// 37 vertices, the size of seed paper 001's triangular B-spline example). Vertices are
/// renumbered in order of first use; positions are scaled about the patch's bounding-box
/// centre so that its largest extent is 1.
///
/// `None` unless the patch is a topological disk with at most three ear tips (boundary
/// vertices with one face), as the fitting pipeline needs.
///
/// ```
/// use glam::DVec3;
/// use mesh_topo::HalfedgeMesh;
/// use tri_spline::index::tri_index;
/// use tri_spline::samples::{disk_patch, smooth_surface, triangle_grid};
/// let mesh = HalfedgeMesh::from_soup(&triangle_grid(16, smooth_surface))?;
/// // Grid vertex (5, 5) is interior, of valence 6.
/// let patch = disk_patch(&mesh, tri_index(16, 5, 5), 2).unwrap();
/// assert_eq!((patch.vertex_count(), patch.face_count()), (37, 54));
/// let (lo, hi) = patch.positions.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), &p| (l.min(p), h.max(p)));
/// assert!(((hi - lo).max_element() - 1.0).abs() < 1e-12);
/// assert!(disk_patch(&mesh, 10_000, 2).is_none());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn disk_patch(mesh: &HalfedgeMesh, seed_vertex: usize, rings: usize) -> Option<PolygonSoup> {
    let seed = mesh.vertex(seed_vertex)?;
    let distance = mesh.ring_distances(seed, rings);
    let (mut soup, _) = mesh
        .extract_faces(|f| mesh.face_degree(f) == 3 && mesh.face_vertices(f).any(|v| distance[v.index()].is_some()));
    let (lo, hi) =
        soup.positions.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), &p| (l.min(p), h.max(p)));
    let centre = (lo + hi) * 0.5;
    let scale = 1.0 / (hi - lo).max_element().max(f64::MIN_POSITIVE);
    for p in &mut soup.positions {
        *p = (*p - centre) * scale;
    }
    let patch = HalfedgeMesh::from_soup(&soup).ok()?;
    let stats = patch.topology_stats();
    let ears = patch.vertices().filter(|&v| patch.vertex_faces(v).count() == 1).count();
    (stats.boundary_loops == 1 && stats.euler == 1 && ears <= 3).then_some(soup)
}

/// Resamples a disk-topology triangle mesh on the regular triangular grid with `n`
/// segments per side: the mesh is mapped onto the domain triangle by
/// [`parameterize`](crate::param::parameterize) (mean-value weights, three boundary
/// corners), and grid vertex `(j, k)`, at position [`tri_index`]`(n, j, k)`, is the mesh
/// point at domain point `t0 + (j/n)(t1 - t0) + (k/n)(t2 - t0)`, found by linear
/// interpolation in the face whose parameter triangle contains it. This turns a region
/// cut from any mesh (e.g. by [`disk_patch`]) into the regular grid that Bézier and
/// B-patch fits need, with the data lying exactly on the original mesh.
///
/// # Errors
/// The errors of [`parameterize`](crate::param::parameterize) (not a disk, degenerate
/// parameter triangles, ...); [`SplineError::Degree`](crate::SplineError::Degree) for
/// `n = 0` or `n >` [`MAX_GRID_SEGMENTS`].
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes::{self, CellKind}};
/// use tri_spline::samples::resample_on_grid;
/// let square = HalfedgeMesh::from_soup(&shapes::grid(4, 4, CellKind::Triangles)?)?;
/// let grid = resample_on_grid(&square, 8)?;
/// assert_eq!((grid.vertex_count(), grid.face_count()), (45, 64));
/// // The samples lie on the (planar) mesh.
/// assert!(grid.positions.iter().all(|p| p.z.abs() < 1e-12));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn resample_on_grid(mesh: &HalfedgeMesh, n: usize) -> Result<PolygonSoup, crate::SplineError> {
    use crate::domain::BaryMap;
    use crate::param::{ParamOptions, parameterize};
    if n == 0 || n > MAX_GRID_SEGMENTS {
        return Err(crate::SplineError::Degree { degree: n, min: 1, max: MAX_GRID_SEGMENTS });
    }
    let param = parameterize(mesh, &ParamOptions { detect_grid: false, ..ParamOptions::default() })?;
    let domain = param.domain;
    let faces: Vec<[usize; 3]> = mesh
        .faces()
        .map(|f| {
            let v: Vec<usize> = mesh.face_vertices(f).map(|w| w.index()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    // Bin the parameter triangles on a uniform grid over the domain's bounding box, so
    // each lookup tests a few faces only.
    let corners = domain.corners();
    let (lo, hi) = corners.iter().fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(l, h), &c| (l.min(c), h.max(c)));
    let bins = (faces.len() as f64).sqrt().ceil().max(1.0) as usize;
    let size = (hi - lo) / bins as f64;
    let bin_of = |p: DVec2| -> (usize, usize) {
        let q = ((p - lo) / size).floor();
        ((q.x.max(0.0) as usize).min(bins - 1), (q.y.max(0.0) as usize).min(bins - 1))
    };
    let mut bin_faces: Vec<Vec<u32>> = vec![Vec::new(); bins * bins];
    let mut maps = Vec::with_capacity(faces.len());
    for (f, tri) in faces.iter().enumerate() {
        let [a, b, c] = tri.map(|v| param.params[v]);
        let map = BaryMap::new(a, b, c).ok_or(crate::SplineError::DegenerateParameterTriangle {
            face: f,
            area: crate::domain::orient(a, b, c),
            hint: "the mean-value map folded or collapsed this face",
        })?;
        maps.push(map);
        let (x0, y0) = bin_of(a.min(b).min(c));
        let (x1, y1) = bin_of(a.max(b).max(c));
        for y in y0..=y1 {
            for x in x0..=x1 {
                bin_faces[y * bins + x].push(f as u32);
            }
        }
    }
    let mut positions = vec![DVec3::ZERO; crate::index::tri_count(n)];
    for [i, j, k] in multi_indices(n) {
        let u = domain.point([i as f64 / n as f64, j as f64 / n as f64, k as f64 / n as f64]);
        let (x, y) = bin_of(u);
        // The face whose barycentric coordinates of u are "most inside" (largest minimum):
        // exact containment up to rounding, and a nearest face for points on the boundary.
        let mut best = (f64::NEG_INFINITY, 0usize, [0.0; 3]);
        for &f in &bin_faces[y * bins + x] {
            let l = maps[f as usize].coords(u);
            let inside = l[0].min(l[1]).min(l[2]);
            if inside > best.0 {
                best = (inside, f as usize, l);
            }
        }
        let (_, f, l) = best;
        let [a, b, c] = faces[f];
        let p = mesh.positions();
        positions[tri_index(n, j, k)] = p[a] * l[0] + p[b] * l[1] + p[c] * l[2];
    }
    Ok(PolygonSoup::from_faces(positions, grid_triangles(n, true)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `triangle_grid(1 << 40, ..)` used to abort the process allocating the positions.
    #[test]
    fn grid_sizes_beyond_the_limit_are_errors_before_allocating() {
        for n in [MAX_GRID_SEGMENTS + 1, 1 << 40, usize::MAX] {
            assert_eq!(
                try_triangle_grid(n, smooth_surface),
                Err(crate::SplineError::TooLarge {
                    what: "grid segments per side",
                    requested: n,
                    max: MAX_GRID_SEGMENTS
                })
            );
        }
        assert_eq!(try_triangle_grid(0, smooth_surface).unwrap(), triangle_grid(1, smooth_surface));
        let caught = std::panic::catch_unwind(|| triangle_grid(1 << 40, smooth_surface)).unwrap_err();
        let message = caught.downcast_ref::<String>().unwrap();
        assert!(message.contains("grid segments per side 1099511627776 is too large (at most 4096)"), "{message}");
    }

    #[test]
    fn disk_patch_stops_when_the_mesh_is_exhausted() {
        // usize::MAX rings used to loop over empty frontiers forever.
        let mesh = HalfedgeMesh::from_soup(&triangle_grid(4, smooth_surface)).unwrap();
        let all = disk_patch(&mesh, 0, usize::MAX).expect("the whole grid is a disk");
        assert_eq!(all.face_count(), 16);
        assert_eq!(disk_patch(&mesh, 0, 100), Some(all));
    }
}
