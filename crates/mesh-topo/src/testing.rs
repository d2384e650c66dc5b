//! proptest strategies for random valid meshes (feature `testing`).
//!
//! The meshes are procedural shapes (closed solids, disks, tori with triangle, quad or
//! mixed faces) with random sizes, randomly permuted vertex numbers, randomly rotated
//! face corner lists and jittered positions, so that tests see boundaries, several
//! genera, every face size up to 4 and no convenient ordering.

use glam::DVec3;
use proptest::prelude::*;

use crate::shapes::{self, CellKind};
use crate::soup::PolygonSoup;

fn cell_kind() -> impl Strategy<Value = CellKind> {
    prop_oneof![Just(CellKind::Quads), Just(CellKind::Triangles), Just(CellKind::Mixed)]
}

/// A procedural shape before scrambling.
pub fn arb_shape() -> impl Strategy<Value = PolygonSoup> {
    prop_oneof![
        Just(shapes::tetrahedron()),
        Just(shapes::cube()),
        Just(shapes::octahedron()),
        Just(shapes::icosahedron()),
        (1u32..6, 1u32..6, cell_kind()).prop_map(|(w, h, k)| shapes::grid(w, h, k).unwrap()),
        (3u32..7, 3u32..7, cell_kind()).prop_map(|(w, h, k)| shapes::torus(w, h, k).unwrap()),
    ]
}

/// Same as [`arb_shape`] but triangles only.
pub fn arb_triangle_shape() -> impl Strategy<Value = PolygonSoup> {
    prop_oneof![
        Just(shapes::tetrahedron()),
        Just(shapes::octahedron()),
        Just(shapes::icosahedron()),
        (1u32..6, 1u32..6).prop_map(|(w, h)| shapes::grid(w, h, CellKind::Triangles).unwrap()),
        (3u32..7, 3u32..7).prop_map(|(w, h)| shapes::torus(w, h, CellKind::Triangles).unwrap()),
    ]
}

/// Renumbers vertices by a permutation, rotates each face's corner list and jitters
/// positions; the result is the same surface, validly built.
pub fn scramble(soup: PolygonSoup, seed: u64, jitter: f64) -> PolygonSoup {
    let n = soup.positions.len();
    let mut state = seed | 1;
    let mut next = move || {
        // xorshift64*: deterministic, dependency-free.
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        state.wrapping_mul(0x2545_f491_4f6c_dd1d)
    };
    let mut permutation: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        let j = (next() % (i as u64 + 1)) as usize;
        permutation.swap(i, j);
    }
    let mut positions = vec![DVec3::ZERO; n];
    for (old, &new) in permutation.iter().enumerate() {
        let offset = DVec3::new(
            (next() % 2001) as f64 / 1000.0 - 1.0,
            (next() % 2001) as f64 / 1000.0 - 1.0,
            (next() % 2001) as f64 / 1000.0 - 1.0,
        );
        positions[new as usize] = soup.positions[old] + jitter * offset;
    }
    let mut out = PolygonSoup::with_capacity(n, soup.face_count(), soup.indices.len());
    out.positions = positions;
    for face in soup.faces() {
        let shift = (next() % face.len() as u64) as usize;
        let rotated: Vec<u32> = (0..face.len()).map(|k| permutation[face[(k + shift) % face.len()] as usize]).collect();
        out.push_face(&rotated);
    }
    out
}

/// Renumbers vertices, reorders faces and rotates each face's corner list, every choice
/// made by `pick(k)`, a number in `0..=k` (out-of-range answers are clamped): the same
/// surface in another order. For fuzz targets, which draw the choices from their input
/// bytes; [`scramble`] draws them from a seed and keeps the face order.
///
/// ```
/// use mesh_topo::{shapes, testing::shuffle};
/// let cube = shapes::cube();
/// let reversed = shuffle(&cube, |k| k);
/// assert_eq!((reversed.vertex_count(), reversed.face_count()), (8, 6));
/// assert_eq!(shuffle(&cube, |_| 0).face_count(), 6);
/// ```
pub fn shuffle(soup: &PolygonSoup, mut pick: impl FnMut(usize) -> usize) -> PolygonSoup {
    let mut pick = move |k: usize| pick(k).min(k);
    let n = soup.vertex_count();
    let mut new_of_old: Vec<u32> = (0..n as u32).collect();
    for i in (1..n).rev() {
        new_of_old.swap(i, pick(i));
    }
    let mut positions = vec![DVec3::ZERO; n];
    for (old, &new) in new_of_old.iter().enumerate() {
        positions[new as usize] = soup.positions[old];
    }
    let mut faces: Vec<Vec<u32>> = soup.faces().map(|f| f.iter().map(|&v| new_of_old[v as usize]).collect()).collect();
    for i in (1..faces.len()).rev() {
        faces.swap(i, pick(i));
    }
    for face in &mut faces {
        let shift = pick(face.len().saturating_sub(1));
        face.rotate_left(shift);
    }
    PolygonSoup::from_faces(positions, faces)
}

/// A random valid polygon mesh soup (see the module docs).
pub fn arb_mesh() -> impl Strategy<Value = PolygonSoup> {
    (arb_shape(), any::<u64>(), 0.0..0.2f64).prop_map(|(soup, seed, jitter)| scramble(soup, seed, jitter))
}

/// A random valid triangle mesh soup.
pub fn arb_triangle_mesh() -> impl Strategy<Value = PolygonSoup> {
    (arb_triangle_shape(), any::<u64>(), 0.0..0.2f64).prop_map(|(soup, seed, jitter)| scramble(soup, seed, jitter))
}
