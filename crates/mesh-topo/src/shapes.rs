//! Procedural meshes for examples, tests and benchmarks: Platonic solids, planar grids
//! (disks with one boundary loop) and tori (closed, genus 1), with triangle, quad or
//! mixed faces. All are manifold and consistently oriented (counter-clockwise seen from
//! outside, or from +z for planar grids).

use glam::DVec3;

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
pub fn cube() -> PolygonSoup {
    let positions = (0..8).map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64)).collect();
    PolygonSoup::from_faces(
        positions,
        [[0u32, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]],
    )
}

/// A regular octahedron (8 triangles, all valence 4).
pub fn octahedron() -> PolygonSoup {
    PolygonSoup::from_faces(
        vec![DVec3::X, DVec3::NEG_X, DVec3::Y, DVec3::NEG_Y, DVec3::Z, DVec3::NEG_Z],
        [[0u32, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]],
    )
}

/// A regular icosahedron (20 triangles, all valence 5) on the unit sphere.
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
/// # Panics
/// If `width` or `height` is 0.
pub fn grid(width: u32, height: u32, kind: CellKind) -> PolygonSoup {
    assert!(width > 0 && height > 0, "grid needs at least one cell");
    let row = width + 1;
    let mut soup = PolygonSoup::with_capacity(((width + 1) * (height + 1)) as usize, 0, 0);
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
    soup
}

/// A torus of `around x along` cells (radii 1 and 0.4): closed, genus 1.
/// Triangulated tori need at least 3 cells each way to be simplicial.
///
/// # Panics
/// If either count is below 3.
pub fn torus(around: u32, along: u32, kind: CellKind) -> PolygonSoup {
    assert!(around >= 3 && along >= 3, "torus needs at least 3 x 3 cells");
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
    soup
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::HalfedgeMesh;

    #[test]
    fn shapes_have_expected_topology() {
        // (name, soup, (V, E, F), genus, boundary loops)
        type Case = (&'static str, PolygonSoup, (usize, usize, usize), i64, usize);
        let cases: Vec<Case> = vec![
            ("tetrahedron", tetrahedron(), (4, 6, 4), 0, 0),
            ("cube", cube(), (8, 12, 6), 0, 0),
            ("octahedron", octahedron(), (6, 12, 8), 0, 0),
            ("icosahedron", icosahedron(), (12, 30, 20), 0, 0),
            ("grid", grid(3, 2, CellKind::Triangles), (12, 23, 12), 0, 1),
            ("grid quads", grid(3, 2, CellKind::Quads), (12, 17, 6), 0, 1),
            ("torus", torus(6, 4, CellKind::Triangles), (24, 72, 48), 1, 0),
            ("torus mixed", torus(6, 4, CellKind::Mixed), (24, 60, 36), 1, 0),
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
        for soup in [tetrahedron(), cube(), octahedron(), icosahedron(), torus(8, 5, CellKind::Quads)] {
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
}
