//! Procedural meshes for examples, tests and benchmarks: Platonic solids, planar grids
//! (disks with one boundary loop) and tori (closed, genus 1), with triangle, quad or
//! mixed faces. All are manifold and consistently oriented (counter-clockwise seen from
//! outside, or from +z for planar grids).

use glam::DVec3;

use crate::error::MeshError;
use crate::soup::PolygonSoup;

/// How grid cells are split into faces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellKind {
    /// Every cell is a quad.
    Quads,
    /// Every cell is split into two triangles along the same diagonal (the regular
    /// three-direction triangulation: every interior vertex has valence 6).
    Triangles,
    /// Cells alternate quad / two triangles in a checkerboard.
    Mixed,
}

/// A regular tetrahedron (4 triangles).
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
///
/// let mesh = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
/// assert_eq!((mesh.vertex_count(), mesh.edge_count(), mesh.face_count()), (4, 6, 4));
/// assert!(mesh.vertices().all(|v| mesh.valence(v) == 3));
/// assert_eq!(mesh.euler_characteristic(), 2);
/// # Ok::<(), mesh_topo::MeshError>(())
/// ```
pub fn tetrahedron() -> PolygonSoup {
    PolygonSoup::from_faces(
        vec![
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(1.0, -1.0, -1.0),
            DVec3::new(-1.0, 1.0, -1.0),
            DVec3::new(-1.0, -1.0, 1.0),
        ],
        [[0u32, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]],
    )
}

/// The unit cube `[0,1]^3` (6 quads).
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
///
/// let soup = shapes::cube();
/// assert!(soup.positions.iter().all(|p| p.min_element() >= 0.0 && p.max_element() <= 1.0));
/// let mesh = HalfedgeMesh::from_soup(&soup)?;
/// assert_eq!((mesh.vertex_count(), mesh.edge_count(), mesh.face_count()), (8, 12, 6));
/// assert!(mesh.faces().all(|f| mesh.face_degree(f) == 4));
/// assert_eq!(mesh.euler_characteristic(), 2);
/// # Ok::<(), mesh_topo::MeshError>(())
/// ```
pub fn cube() -> PolygonSoup {
    let positions = (0..8).map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64)).collect();
    PolygonSoup::from_faces(
        positions,
        [[0u32, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]],
    )
}

/// A regular octahedron (8 triangles, all valence 4).
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
///
/// let mesh = HalfedgeMesh::from_soup(&shapes::octahedron())?;
/// assert_eq!((mesh.vertex_count(), mesh.edge_count(), mesh.face_count()), (6, 12, 8));
/// assert!(mesh.vertices().all(|v| mesh.valence(v) == 4));
/// assert_eq!(mesh.euler_characteristic(), 2);
/// # Ok::<(), mesh_topo::MeshError>(())
/// ```
pub fn octahedron() -> PolygonSoup {
    PolygonSoup::from_faces(
        vec![DVec3::X, DVec3::NEG_X, DVec3::Y, DVec3::NEG_Y, DVec3::Z, DVec3::NEG_Z],
        [[0u32, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]],
    )
}

/// A regular icosahedron (20 triangles, all valence 5) on the unit sphere.
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
///
/// let mesh = HalfedgeMesh::from_soup(&shapes::icosahedron())?;
/// assert_eq!((mesh.vertex_count(), mesh.edge_count(), mesh.face_count()), (12, 30, 20));
/// assert!(mesh.vertices().all(|v| mesh.valence(v) == 5));
/// assert!(mesh.positions().iter().all(|p| (p.length() - 1.0).abs() < 1e-15));
/// # Ok::<(), mesh_topo::MeshError>(())
/// ```
pub fn icosahedron() -> PolygonSoup {
    let phi = (1.0 + 5f64.sqrt()) / 2.0;
    let raw = [
        (-1.0, phi, 0.0),
        (1.0, phi, 0.0),
        (-1.0, -phi, 0.0),
        (1.0, -phi, 0.0),
        (0.0, -1.0, phi),
        (0.0, 1.0, phi),
        (0.0, -1.0, -phi),
        (0.0, 1.0, -phi),
        (phi, 0.0, -1.0),
        (phi, 0.0, 1.0),
        (-phi, 0.0, -1.0),
        (-phi, 0.0, 1.0),
    ];
    let positions = raw.iter().map(|&(x, y, z)| DVec3::new(x, y, z).normalize()).collect();
    PolygonSoup::from_faces(
        positions,
        [
            [0u32, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ],
    )
}

fn push_cell(soup: &mut PolygonSoup, kind: CellKind, parity: bool, [a, b, c, d]: [u32; 4]) {
    // Corners counter-clockwise: a = (i, j), b = (i+1, j), c = (i+1, j+1), d = (i, j+1).
    let quad = match kind {
        CellKind::Quads => true,
        CellKind::Triangles => false,
        CellKind::Mixed => parity,
    };
    if quad {
        soup.push_face(&[a, b, c, d]);
    } else {
        soup.push_face(&[a, b, c]);
        soup.push_face(&[a, c, d]);
    }
}

/// A planar `width x height` grid of cells over `[0, width] x [0, height]` in the plane
/// z = 0: a disk with one boundary loop. Vertex `(i, j)` has index `j * (width + 1) + i`.
///
/// ```
/// use mesh_topo::shapes::{grid, CellKind};
///
/// let soup = grid(3, 2, CellKind::Quads)?;
/// assert_eq!((soup.positions.len(), soup.face_count()), (12, 6));
/// assert!(grid(0, 2, CellKind::Quads).is_err());
/// # Ok::<(), mesh_topo::MeshError>(())
/// ```
///
/// # Errors
/// [`MeshError::InvalidShape`] if `width` or `height` is 0, and
/// [`MeshError::TooLarge`] if the grid would need more vertices or face corners than
/// `u32` indices address (checked before anything is allocated).
pub fn grid(width: u32, height: u32, kind: CellKind) -> Result<PolygonSoup, MeshError> {
    if width == 0 || height == 0 {
        return Err(MeshError::InvalidShape {
            shape: "grid",
            width,
            height,
            requirement: "a grid needs at least one cell each way",
        });
    }
    let vertices = (u128::from(width) + 1) * (u128::from(height) + 1);
    check_size(vertices, u128::from(width) * u128::from(height), kind)?;
    let row = width + 1;
    let mut soup = PolygonSoup::with_capacity(vertices as usize, 0, 0);
    for j in 0..=height {
        for i in 0..=width {
            soup.positions.push(DVec3::new(i as f64, j as f64, 0.0));
        }
    }
    for j in 0..height {
        for i in 0..width {
            let a = j * row + i;
            push_cell(&mut soup, kind, (i + j) % 2 == 0, [a, a + 1, a + row + 1, a + row]);
        }
    }
    Ok(soup)
}

/// Refuses shapes whose vertex or corner count does not fit the mesh's `u32` indices.
/// Counts are `u128` so that no product of two `u32` sizes overflows.
fn check_size(vertices: u128, cells: u128, kind: CellKind) -> Result<(), MeshError> {
    // A triangulated cell has 6 corners, a quad 4.
    let corners_per_cell = if kind == CellKind::Quads { 4 } else { 6 };
    crate::check_capacity(saturate(vertices), saturate(cells * corners_per_cell))
}

/// The count for the error message; saturates where `usize` cannot hold it.
fn saturate(count: u128) -> usize {
    usize::try_from(count).unwrap_or(usize::MAX)
}

/// A torus of `around x along` cells (radii 1 and 0.4): closed, genus 1.
///
/// ```
/// use mesh_topo::shapes::{torus, CellKind};
///
/// let soup = torus(8, 5, CellKind::Triangles)?;
/// assert_eq!((soup.positions.len(), soup.face_count()), (40, 80));
/// assert!(torus(2, 5, CellKind::Triangles).is_err());
/// # Ok::<(), mesh_topo::MeshError>(())
/// ```
///
/// # Errors
/// [`MeshError::InvalidShape`] if either count is below 3: with fewer cells the
/// triangulated torus is not simplicial (two triangles would share all three vertices)
/// and the quad torus has repeated edges. [`MeshError::TooLarge`] if the torus would need
/// more vertices or face corners than `u32` indices address.
pub fn torus(around: u32, along: u32, kind: CellKind) -> Result<PolygonSoup, MeshError> {
    if around < 3 || along < 3 {
        return Err(MeshError::InvalidShape {
            shape: "torus",
            width: around,
            height: along,
            requirement: "a torus needs at least 3 x 3 cells",
        });
    }
    let cells = u128::from(around) * u128::from(along);
    check_size(cells, cells, kind)?;
    let (big, small) = (1.0, 0.4);
    let mut soup = PolygonSoup::with_capacity((around * along) as usize, 0, 0);
    for j in 0..along {
        let v = std::f64::consts::TAU * j as f64 / along as f64;
        for i in 0..around {
            let u = std::f64::consts::TAU * i as f64 / around as f64;
            let r = big + small * v.cos();
            soup.positions.push(DVec3::new(r * u.cos(), r * u.sin(), small * v.sin()));
        }
    }
    let index = |i: u32, j: u32| (j % along) * around + (i % around);
    for j in 0..along {
        for i in 0..around {
            // With odd counts the mixed checkerboard has a seam; still a valid mesh.
            let cell = [index(i, j), index(i + 1, j), index(i + 1, j + 1), index(i, j + 1)];
            // d/du x d/dv points away from the tube's centre line: outward.
            push_cell(&mut soup, kind, (i + j) % 2 == 0, cell);
        }
    }
    Ok(soup)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::HalfedgeMesh;
    use crate::ids::MAX_ELEMENTS;

    #[test]
    fn shapes_have_expected_topology() {
        // (name, soup, (V, E, F), genus, boundary loops)
        type Case = (&'static str, PolygonSoup, (usize, usize, usize), i64, usize);
        let cases: Vec<Case> = vec![
            ("tetrahedron", tetrahedron(), (4, 6, 4), 0, 0),
            ("cube", cube(), (8, 12, 6), 0, 0),
            ("octahedron", octahedron(), (6, 12, 8), 0, 0),
            ("icosahedron", icosahedron(), (12, 30, 20), 0, 0),
            ("grid", grid(3, 2, CellKind::Triangles).unwrap(), (12, 23, 12), 0, 1),
            ("grid quads", grid(3, 2, CellKind::Quads).unwrap(), (12, 17, 6), 0, 1),
            ("torus", torus(6, 4, CellKind::Triangles).unwrap(), (24, 72, 48), 1, 0),
            ("torus mixed", torus(6, 4, CellKind::Mixed).unwrap(), (24, 60, 36), 1, 0),
        ];
        for (name, soup, counts, genus, loops) in cases {
            let mesh = HalfedgeMesh::from_soup(&soup).unwrap_or_else(|e| panic!("{name}: {e}"));
            mesh.validate().unwrap();
            let stats = mesh.topology_stats();
            assert_eq!((stats.vertices, stats.edges, stats.faces), counts, "{name}");
            assert_eq!(stats.genus, genus, "{name}");
            assert_eq!(stats.boundary_loops, loops, "{name}");
        }
    }

    #[test]
    fn closed_shapes_face_outward() {
        for soup in [tetrahedron(), cube(), octahedron(), icosahedron(), torus(8, 5, CellKind::Quads).unwrap()] {
            let centre = soup.positions.iter().copied().sum::<DVec3>() / soup.positions.len() as f64;
            // Signed volume from the centre is positive for outward orientation.
            let mut volume = 0.0;
            for face in soup.faces() {
                let p0 = soup.positions[face[0] as usize] - centre;
                for k in 1..face.len() - 1 {
                    let p1 = soup.positions[face[k] as usize] - centre;
                    let p2 = soup.positions[face[k + 1] as usize] - centre;
                    volume += p0.dot(p1.cross(p2));
                }
            }
            assert!(volume > 0.0);
        }
    }

    #[test]
    fn parameters_that_cannot_make_a_shape_are_errors() {
        for (around, along) in [(0, 5), (2, 5), (5, 2), (1, 1)] {
            for kind in [CellKind::Quads, CellKind::Triangles, CellKind::Mixed] {
                let err = torus(around, along, kind).unwrap_err();
                assert!(matches!(err, MeshError::InvalidShape { shape: "torus", .. }), "{err}");
                assert_eq!(err.to_string(), format!("torus {around} x {along}: a torus needs at least 3 x 3 cells"));
            }
        }
        for (width, height) in [(0, 1), (1, 0), (0, 0)] {
            let err = grid(width, height, CellKind::Quads).unwrap_err();
            assert!(matches!(err, MeshError::InvalidShape { shape: "grid", .. }), "{err}");
        }
        // The smallest valid ones build.
        assert!(HalfedgeMesh::from_soup(&torus(3, 3, CellKind::Triangles).unwrap()).is_ok());
        assert!(HalfedgeMesh::from_soup(&grid(1, 1, CellKind::Triangles).unwrap()).is_ok());
    }

    #[test]
    fn shapes_too_large_for_u32_indices_are_refused_before_allocating() {
        // 65537^2 = 4,295,098,369 vertices: just past what u32 handles address.
        let err = grid(1 << 16, 1 << 16, CellKind::Quads).unwrap_err();
        assert_eq!(err, MeshError::TooLarge { what: "vertices", count: 4_295_098_369, max: MAX_ELEMENTS });
        // The product of the largest sizes does not overflow the check itself.
        let err = grid(u32::MAX, u32::MAX, CellKind::Mixed).unwrap_err();
        assert!(matches!(err, MeshError::TooLarge { what: "vertices", .. }), "{err}");
        // Few enough vertices but too many corners once triangulated (6 per cell).
        let err = torus(1 << 16, 1 << 15, CellKind::Triangles).unwrap_err();
        assert_eq!(err, MeshError::TooLarge { what: "face corners", count: 6 << 31, max: MAX_ELEMENTS / 2 });
        assert!(err.to_string().starts_with("too many face corners: 12884901888"), "{err}");
    }
}
