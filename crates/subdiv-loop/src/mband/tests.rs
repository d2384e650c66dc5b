//! Tests of the M-band masks and of ternary and quaternary Loop.

use glam::DVec3;
use mesh_topo::shapes::{self, CellKind};
use mesh_topo::testing::{arb_triangle_mesh, scramble};
use mesh_topo::{HalfedgeMesh, MAX_ELEMENTS, MeshError, PolygonSoup};
use proptest::prelude::*;

use super::*;

/// `(point, numerator)` pairs of a stencil, sorted, for table comparisons.
fn table(masks: &BoxSplineMasks, s: u32, t: u32) -> Vec<((i32, i32), u64)> {
    let mut entries: Vec<_> = masks.stencil(s, t).iter().map(|w| (w.point, w.numerator)).collect();
    entries.sort_unstable();
    entries
}

fn expected(entries: &[((i32, i32), u64)]) -> Vec<((i32, i32), u64)> {
    let mut entries = entries.to_vec();
    entries.sort_unstable();
    entries
}

#[test]
fn stencil_tables_of_the_specification_are_reproduced_exactly() {
    let loop_masks = box_spline_masks(2).unwrap();
    assert_eq!(
        table(&loop_masks, 0, 0),
        expected(&[((0, 0), 10), ((1, 0), 1), ((-1, 0), 1), ((0, 1), 1), ((0, -1), 1), ((1, 1), 1), ((-1, -1), 1)])
    );
    assert_eq!(table(&loop_masks, 1, 0), expected(&[((0, 0), 6), ((1, 0), 6), ((0, -1), 2), ((1, 1), 2)]));

    // Ternary, over 81: vertex 5/9 and 2/27; 1/3-point; triangle centre.
    let ternary = box_spline_masks(3).unwrap();
    assert_eq!(
        table(&ternary, 0, 0),
        expected(&[((0, 0), 45), ((1, 0), 6), ((-1, 0), 6), ((0, 1), 6), ((0, -1), 6), ((1, 1), 6), ((-1, -1), 6)])
    );
    assert_eq!(
        table(&ternary, 1, 0),
        expected(&[((0, 0), 36), ((1, 0), 20), ((0, -1), 10), ((1, 1), 10), ((-1, -1), 2), ((0, 1), 2), ((-1, 0), 1)])
    );
    assert_eq!(
        table(&ternary, 2, 1),
        expected(&[((0, 0), 24), ((1, 0), 24), ((1, 1), 24), ((0, -1), 3), ((0, 1), 3), ((2, 1), 3)])
    );

    // Quaternary, over 256.
    let quaternary = box_spline_masks(4).unwrap();
    assert_eq!(
        table(&quaternary, 0, 0),
        expected(&[
            ((0, 0), 136),
            ((1, 0), 20),
            ((-1, 0), 20),
            ((0, 1), 20),
            ((0, -1), 20),
            ((1, 1), 20),
            ((-1, -1), 20)
        ])
    );
    assert_eq!(
        table(&quaternary, 1, 0),
        expected(&[
            ((0, 0), 120),
            ((1, 0), 50),
            ((0, -1), 30),
            ((1, 1), 30),
            ((-1, -1), 10),
            ((0, 1), 10),
            ((-1, 0), 6)
        ])
    );
    assert_eq!(
        table(&quaternary, 2, 0),
        expected(&[
            ((0, 0), 87),
            ((1, 0), 87),
            ((0, -1), 34),
            ((1, 1), 34),
            ((-1, -1), 3),
            ((0, 1), 3),
            ((1, -1), 3),
            ((2, 1), 3),
            ((-1, 0), 1),
            ((2, 0), 1),
        ])
    );
    assert_eq!(
        table(&quaternary, 2, 1),
        expected(&[
            ((0, 0), 96),
            ((1, 0), 62),
            ((1, 1), 62),
            ((0, -1), 14),
            ((0, 1), 14),
            ((2, 1), 4),
            ((-1, -1), 2),
            ((-1, 0), 2)
        ])
    );
    assert_eq!(
        table(&quaternary, 3, 1),
        expected(&[
            ((1, 0), 96),
            ((0, 0), 62),
            ((1, 1), 62),
            ((0, -1), 14),
            ((2, 1), 14),
            ((0, 1), 4),
            ((1, -1), 2),
            ((2, 0), 2)
        ])
    );
    // The seed's reference values: alpha = 5/9, beta(1) = 15/32, beta(2) = 87/256.
    assert_eq!(45 * 9, 5 * 81);
    assert_eq!(120 * 32, 15 * 256);
}

#[test]
fn every_coset_sums_to_one_and_stencils_stay_in_the_first_ring() {
    for m in 2..=9u32 {
        let masks = box_spline_masks(m).unwrap();
        let mut total = 0;
        for t in 0..m {
            for s in 0..m {
                let stencil = masks.stencil(s, t);
                assert_eq!(stencil.iter().map(|w| w.numerator).sum::<u64>(), masks.denominator(), "M = {m}");
                total += stencil.len();
                // Only the triangle's vertices and its first ring (12 points, seed 002
                // Theorem 2): every point is within one lattice step of the cell.
                assert!(stencil.iter().all(|w| (-1..=2).contains(&w.point.0) && (-1..=2).contains(&w.point.1)));
            }
        }
        assert!(total > 0);
        assert_eq!(
            (0..masks.symbol_size())
                .flat_map(|j| (0..masks.symbol_size()).map(move |i| (i, j)))
                .map(|(i, j)| masks.symbol_coefficient(i, j))
                .sum::<u64>(),
            (m as u64).pow(6)
        );
    }
    assert!(box_spline_masks(1).is_err());
    assert!(box_spline_masks(65).is_err());
}

/// `P(z) * Q(z^k)` for square coefficient arrays.
fn compose(p: &BoxSplineMasks, q: &BoxSplineMasks, k: usize) -> Vec<Vec<u64>> {
    let size = p.symbol_size() + k * (q.symbol_size() - 1);
    let mut out = vec![vec![0u64; size]; size];
    for pj in 0..p.symbol_size() {
        for pi in 0..p.symbol_size() {
            for qj in 0..q.symbol_size() {
                for qi in 0..q.symbol_size() {
                    out[pj + k * qj][pi + k * qi] += p.symbol_coefficient(pi, pj) * q.symbol_coefficient(qi, qj);
                }
            }
        }
    }
    out
}

#[test]
fn symbols_compose() {
    // a_{M1 M2}(z) = a_{M1}(z) a_{M2}(z^{M1}) (seed 002, Theorem 3), numerators exactly.
    for (m1, m2) in [(2, 2), (3, 3), (2, 3), (3, 2), (2, 4)] {
        let (p, q, r) =
            (box_spline_masks(m1).unwrap(), box_spline_masks(m2).unwrap(), box_spline_masks(m1 * m2).unwrap());
        let product = compose(&p, &q, m1 as usize);
        assert_eq!(product.len(), r.symbol_size());
        for (j, row) in product.iter().enumerate() {
            for (i, &c) in row.iter().enumerate() {
                assert_eq!(c, r.symbol_coefficient(i, j), "M = {m1} x {m2} at ({i}, {j})");
            }
        }
    }
}

/// A periodic three-direction lattice: vertex (i, j) is `i + w j`.
fn lattice_torus(w: usize, h: usize, seed: u64) -> (HalfedgeMesh, Vec<(i64, i64)>) {
    let index = |i: usize, j: usize| ((i % w) + w * (j % h)) as u32;
    let mut faces = Vec::new();
    for j in 0..h {
        for i in 0..w {
            faces.push([index(i, j), index(i + 1, j), index(i + 1, j + 1)]);
            faces.push([index(i, j), index(i + 1, j + 1), index(i, j + 1)]);
        }
    }
    let mut state = seed;
    let mut random = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let positions = (0..w * h).map(|_| DVec3::new(random(), random(), random())).collect();
    let coords = (0..w * h).map(|k| ((k % w) as i64, (k / w) as i64)).collect();
    (HalfedgeMesh::from_soup(&PolygonSoup::from_faces(positions, faces)).unwrap(), coords)
}

/// The lattice step from `a` to `b` on a periodic lattice (one of the six directions).
fn step(a: (i64, i64), b: (i64, i64), size: (i64, i64)) -> (i64, i64) {
    let wrap = |d: i64, n: i64| {
        let d = d.rem_euclid(n);
        if d > n / 2 { d - n } else { d }
    };
    (wrap(b.0 - a.0, size.0), wrap(b.1 - a.1, size.1))
}

/// Lattice coordinates of the vertices after one Loop step (in half units).
fn loop_coords(mesh: &HalfedgeMesh, coords: &[(i64, i64)], size: (i64, i64)) -> Vec<(i64, i64)> {
    let mut out: Vec<(i64, i64)> = coords.iter().map(|&(i, j)| (2 * i, 2 * j)).collect();
    for e in mesh.edges() {
        let [a, b] = mesh.edge_vertices(e);
        let (a, b) = (coords[a.index()], coords[b.index()]);
        let d = step(a, b, size);
        out.push((2 * a.0 + d.0, 2 * a.1 + d.1));
    }
    out
}

/// Lattice coordinates after one ternary step (in third units).
fn ternary_coords(mesh: &HalfedgeMesh, coords: &[(i64, i64)], size: (i64, i64)) -> Vec<(i64, i64)> {
    let mut out: Vec<(i64, i64)> = coords.iter().map(|&(i, j)| (3 * i, 3 * j)).collect();
    for e in mesh.edges() {
        let [a, b] = mesh.edge_vertices(e);
        let (a, b) = (coords[a.index()], coords[b.index()]);
        let d = step(a, b, size);
        out.push((3 * a.0 + d.0, 3 * a.1 + d.1));
        out.push((3 * a.0 + 2 * d.0, 3 * a.1 + 2 * d.1));
    }
    for f in mesh.faces() {
        let c: Vec<(i64, i64)> = mesh.face_vertices(f).map(|v| coords[v.index()]).collect();
        let (d1, d2) = (step(c[0], c[1], size), step(c[0], c[2], size));
        out.push((3 * c[0].0 + d1.0 + d2.0, 3 * c[0].1 + d1.1 + d2.1));
    }
    out
}

fn assert_matches_lattice(fine: &[DVec3], coords: &[(i64, i64)], lattice: &[DVec3], size: (i64, i64)) {
    assert_eq!(fine.len(), lattice.len());
    for (k, (p, c)) in fine.iter().zip(coords).enumerate() {
        let index = (c.0.rem_euclid(size.0) + size.0 * c.1.rem_euclid(size.1)) as usize;
        assert!((*p - lattice[index]).length() < 1e-14, "fine vertex {k} at {c:?}");
    }
}

#[test]
fn regular_meshes_reproduce_the_box_spline_for_m_2_3_4() {
    let (w, h) = (7usize, 6usize);
    let (mesh, coords) = lattice_torus(w, h, 42);
    let size = (w as i64, h as i64);
    // Loop = M = 2.
    let fine = subdivide(&mesh, 1, &LoopOptions::default()).unwrap();
    let lattice = subdivide_lattice(mesh.positions(), w, h, &box_spline_masks(2).unwrap()).unwrap();
    assert_matches_lattice(&fine.positions, &loop_coords(&mesh, &coords, size), &lattice, (2 * size.0, 2 * size.1));
    // Ternary = M = 3 (the extraordinary rules reduce to the regular ones at n = 6).
    let fine = ternary_subdivide(&mesh, 1, &TernaryOptions::default()).unwrap();
    let lattice = subdivide_lattice(mesh.positions(), w, h, &box_spline_masks(3).unwrap()).unwrap();
    assert_matches_lattice(&fine.positions, &ternary_coords(&mesh, &coords, size), &lattice, (3 * size.0, 3 * size.1));
    // Quaternary = Loop o Loop = M = 4.
    let fine = quaternary_subdivide(&mesh, 1, &LoopOptions::default()).unwrap();
    let half = subdivide(&mesh, 1, &LoopOptions::default()).unwrap().to_halfedge_mesh().unwrap();
    let half_coords = loop_coords(&mesh, &coords, size);
    let quarter_coords = loop_coords(&half, &half_coords, (2 * size.0, 2 * size.1));
    let lattice = subdivide_lattice(mesh.positions(), w, h, &box_spline_masks(4).unwrap()).unwrap();
    assert_matches_lattice(&fine.positions, &quarter_coords, &lattice, (4 * size.0, 4 * size.1));
}

/// Direct evaluation of the three-direction box spline `N(2,2,2)`, independent of any
/// subdivision mask: the hat function `M(1,1,1)` (the Courant element, piecewise linear
/// on the three-direction mesh, peak 1 at `(1, 1)`) integrated once more along each of
/// `e1`, `e2`, `e3`: `M(X + xi)(x) = int_0^1 M(X)(x - t xi) dt`. Every intermediate box
/// spline is a polynomial between the lines `x1`, `x2`, `x1 - x2` in `Z`, so each
/// integral is split where `x - t xi` crosses such a line and done by 3-point
/// Gauss-Legendre (exact for the cubic integrands). Support `(0, 4)^2`, centre `(2, 2)`.
fn box_spline_222(x: (f64, f64)) -> f64 {
    fn hat(x: (f64, f64)) -> f64 {
        let (u1, u2) = (x.0 - 1.0, x.1 - 1.0);
        (1.0 - u1.abs().max(u2.abs()).max((u1 - u2).abs())).max(0.0)
    }
    fn smoothed(x: (f64, f64), directions: &[(f64, f64)]) -> f64 {
        let Some((&xi, rest)) = directions.split_first() else { return hat(x) };
        // Values of t in (0, 1) where x - t xi crosses a mesh line.
        let mut breaks = vec![0.0, 1.0];
        for (value, rate) in [(x.0, xi.0), (x.1, xi.1), (x.0 - x.1, xi.0 - xi.1)] {
            if rate != 0.0 {
                let t = (value / rate).rem_euclid(1.0);
                if t > 0.0 && t < 1.0 {
                    breaks.push(t);
                }
            }
        }
        breaks.sort_by(f64::total_cmp);
        let nodes = [(-(0.6f64).sqrt(), 5.0 / 9.0), (0.0, 8.0 / 9.0), ((0.6f64).sqrt(), 5.0 / 9.0)];
        let mut sum = 0.0;
        for pair in breaks.windows(2) {
            let (a, b) = (pair[0], pair[1]);
            for (node, weight) in nodes {
                let t = 0.5 * (a + b) + 0.5 * (b - a) * node;
                sum += 0.5 * (b - a) * weight * smoothed((x.0 - t * xi.0, x.1 - t * xi.1), rest);
            }
        }
        sum
    }
    smoothed(x, &[(1.0, 0.0), (0.0, 1.0), (1.0, 1.0)])
}

/// `sum_p c(p) N(y - p + (2, 2))` on a periodic lattice of `w x h` values.
fn box_spline_surface(values: &[f64], w: usize, h: usize, y: (f64, f64)) -> f64 {
    let (i0, j0) = (y.0.floor() as i64, y.1.floor() as i64);
    let mut sum = 0.0;
    for j in j0 - 2..=j0 + 2 {
        for i in i0 - 2..=i0 + 2 {
            let c = values[(i.rem_euclid(w as i64) + w as i64 * j.rem_euclid(h as i64)) as usize];
            sum += c * box_spline_222((y.0 - i as f64 + 2.0, y.1 - j as f64 + 2.0));
        }
    }
    sum
}

#[test]
fn the_direct_box_spline_evaluation_is_sound() {
    // Lattice values 1/2 and 1/12 (the limit mask), partition of unity, symmetry.
    assert!((box_spline_222((2.0, 2.0)) - 0.5).abs() < 1e-14);
    for (dx, dy) in [(1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (-1.0, 0.0), (0.0, -1.0), (-1.0, -1.0)] {
        assert!((box_spline_222((2.0 + dx, 2.0 + dy)) - 1.0 / 12.0).abs() < 1e-14);
    }
    assert!(box_spline_222((3.0, 1.0)).abs() < 1e-14 && box_spline_222((4.1, 2.0)) == 0.0);
    for (x, y) in [(0.3, 0.7), (0.55, 0.1), (0.91, 0.42)] {
        let total: f64 = (-3..=3)
            .flat_map(|j| (-3..=3).map(move |i| (i, j)))
            .map(|(i, j)| box_spline_222((x + i as f64, y + j as f64)))
            .sum();
        assert!((total - 1.0).abs() < 1e-13, "partition of unity at ({x}, {y}): {total}");
        let a = box_spline_222((2.0 + x, 2.0 + y));
        assert!((a - box_spline_222((2.0 - x, 2.0 - y))).abs() < 1e-14);
        assert!((a - box_spline_222((2.0 + y, 2.0 + x))).abs() < 1e-14);
    }
}

#[test]
fn regular_patches_converge_to_the_directly_evaluated_box_spline() {
    // After one ternary or quaternary step, two Loop steps, or none, the limit mask of
    // every fine vertex (library code) gives the box spline evaluated directly at the
    // vertex's lattice position (independent code): all three schemes refine N(2,2,2).
    let (w, h) = (6usize, 5usize);
    let size = (w as i64, h as i64);
    let (mesh, coords) = lattice_torus(w, h, 11);
    let coarse: Vec<[f64; 3]> = mesh.positions().iter().map(|p| p.to_array()).collect();
    let check = |fine: &HalfedgeMesh, fine_coords: &[(i64, i64)], scale: f64, scheme: &str| {
        let limit = crate::limit::limit_positions(fine, &LoopOptions::default()).unwrap();
        let mut worst = 0.0f64;
        for (p, c) in limit.iter().zip(fine_coords) {
            let y = (c.0 as f64 / scale, c.1 as f64 / scale);
            for axis in 0..3 {
                let channel: Vec<f64> = coarse.iter().map(|v| v[axis]).collect();
                worst = worst.max((box_spline_surface(&channel, w, h, y) - p[axis]).abs());
            }
        }
        assert!(worst < 1e-13, "{scheme}: largest difference {worst:e}");
    };
    check(&mesh, &coords, 1.0, "no step");
    let half_coords = loop_coords(&mesh, &coords, size);
    let half = subdivide(&mesh, 1, &LoopOptions::default()).unwrap().to_halfedge_mesh().unwrap();
    let quarter_coords = loop_coords(&half, &half_coords, (2 * size.0, 2 * size.1));
    let two_loop = subdivide(&mesh, 2, &LoopOptions::default()).unwrap().to_halfedge_mesh().unwrap();
    check(&two_loop, &quarter_coords, 4.0, "two Loop steps");
    let quaternary = quaternary_subdivide(&mesh, 1, &LoopOptions::default()).unwrap().to_halfedge_mesh().unwrap();
    check(&quaternary, &quarter_coords, 4.0, "quaternary");
    let ternary = ternary_subdivide(&mesh, 1, &TernaryOptions::default()).unwrap().to_halfedge_mesh().unwrap();
    check(&ternary, &ternary_coords(&mesh, &coords, size), 3.0, "ternary");
}

#[test]
fn every_arity_refines_the_same_box_spline() {
    // The limit at a lattice point is c/2 + (sum of the six neighbours)/12 (the values
    // of N(2,2,2) at the lattice points); one M-adic step must keep the limit of every
    // coarse lattice point, whatever M.
    let (w, h) = (6usize, 5usize);
    let (mesh, _) = lattice_torus(w, h, 7);
    let values: Vec<f64> = mesh.positions().iter().map(|p| p.x + 2.0 * p.y * p.z).collect();
    let limit = |values: &[f64], w: usize, h: usize, i: usize, j: usize| {
        let at = |di: i64, dj: i64| {
            values[((i as i64 + di).rem_euclid(w as i64) + w as i64 * (j as i64 + dj).rem_euclid(h as i64)) as usize]
        };
        at(0, 0) / 2.0 + (at(1, 0) + at(-1, 0) + at(0, 1) + at(0, -1) + at(1, 1) + at(-1, -1)) / 12.0
    };
    for m in 2..=6usize {
        let fine = subdivide_lattice(&values, w, h, &box_spline_masks(m as u32).unwrap()).unwrap();
        for j in 0..h {
            for i in 0..w {
                let coarse = limit(&values, w, h, i, j);
                let refined = limit(&fine, m * w, m * h, m * i, m * j);
                assert!((coarse - refined).abs() < 1e-13, "M = {m} at ({i}, {j})");
            }
        }
    }
}

#[test]
fn ternary_weights_at_valence_six_are_the_regular_ones() {
    let gamma = ternary_edge_weights(6, 1.0 / 3.0).unwrap();
    for (g, expected) in gamma.iter().zip([20.0, 10.0, 2.0, 1.0, 2.0, 10.0]) {
        assert!((g * 81.0 - expected).abs() < 1e-13);
    }
    for n in 3..=20 {
        // Affine: 4/9 + sum gamma = 1, and positive at lambda = 1/3.
        let gamma = ternary_edge_weights(n, 1.0 / 3.0).unwrap();
        assert!((4.0 / 9.0 + gamma.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        assert!(gamma.iter().all(|&g| g > 0.0), "n = {n}: {gamma:?}");
    }
}

#[test]
fn counts_for_ternary_and_quaternary() {
    // Closed, open, and with a vertex on no face (which each step keeps).
    let mut with_isolated = shapes::grid(2, 2, CellKind::Triangles).unwrap();
    with_isolated.positions.push(DVec3::splat(5.0));
    for soup in [
        shapes::icosahedron(),
        shapes::grid(3, 2, CellKind::Triangles).unwrap(),
        shapes::torus(4, 3, CellKind::Triangles).unwrap(),
        with_isolated,
    ] {
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        let counts =
            |mesh: &HalfedgeMesh| [mesh.vertex_count(), mesh.edge_count(), mesh.face_count()].map(|n| n as u64);
        let (v, e, f) = (mesh.vertex_count(), mesh.edge_count(), mesh.face_count());
        for (m, fine) in [
            (2, crate::forward::subdivide(&mesh, 1, &LoopOptions::default()).unwrap()),
            (3, ternary_subdivide(&mesh, 1, &TernaryOptions::default()).unwrap()),
            (4, quaternary_subdivide(&mesh, 1, &LoopOptions::default()).unwrap()),
        ] {
            assert_eq!(fine.vertex_count(), v + (m - 1) * e + f * (m - 1) * (m - 2) / 2);
            assert_eq!(fine.face_count(), m * m * f);
            let fine_mesh = fine.to_halfedge_mesh().unwrap();
            assert_eq!(counts_after_step(m as u32, counts(&mesh)), counts(&fine_mesh), "M = {m}");
            assert_eq!(fine_mesh.euler_characteristic(), mesh.euler_characteristic());
        }
        let two = ternary_subdivide(&mesh, 2, &TernaryOptions::default()).unwrap();
        assert_eq!(two.face_count(), 81 * f);
    }
}

#[test]
fn ternary_matrix_applies_the_same_stencils() {
    let mesh = HalfedgeMesh::from_soup(&scramble(shapes::grid(3, 3, CellKind::Triangles).unwrap(), 4, 0.2)).unwrap();
    let options = TernaryOptions::default();
    let s = ternary_matrix(&mesh, 2, &options).unwrap();
    let fine = ternary_subdivide(&mesh, 2, &options).unwrap();
    let applied = s.apply(mesh.positions()).unwrap();
    for (a, b) in applied.iter().zip(&fine.positions) {
        assert!((*a - *b).length() < 1e-14);
    }
    assert!(s.row_sums().iter().all(|r| (r - 1.0).abs() < 1e-14));
}

#[test]
fn bad_parameters_are_rejected() {
    let mesh = HalfedgeMesh::from_soup(&shapes::icosahedron()).unwrap();
    for lambda in [0.1, 0.6, f64::NAN] {
        assert!(matches!(
            ternary_subdivide(&mesh, 1, &TernaryOptions { lambda }),
            Err(LoopError::InvalidParameter { name: "lambda", .. })
        ));
    }
    let quads = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
    assert!(matches!(ternary_subdivide(&quads, 1, &TernaryOptions::default()), Err(LoopError::NotTriangle { .. })));
    assert!(subdivide_lattice(&[1.0f64; 9], 3, 3, &box_spline_masks(2).unwrap()).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    #[test]
    fn ternary_is_affine_invariant(soup in arb_triangle_mesh(), shift in prop::array::uniform3(-3.0..3.0f64), scale in 0.2..5.0f64) {
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        let moved: Vec<DVec3> = mesh.positions().iter().map(|&p| scale * DVec3::new(p.y, p.z, p.x) + DVec3::from(shift)).collect();
        let mut moved_mesh = mesh.clone();
        moved_mesh.replace_positions(moved).unwrap();
        let options = TernaryOptions::default();
        let (a, b) = (ternary_subdivide(&mesh, 1, &options).unwrap(), ternary_subdivide(&moved_mesh, 1, &options).unwrap());
        prop_assert_eq!(&a.triangles, &b.triangles);
        for (p, q) in a.positions.iter().zip(&b.positions) {
            let expected = scale * DVec3::new(p.y, p.z, p.x) + DVec3::from(shift);
            prop_assert!((expected - *q).length() < 1e-12 * (1.0 + expected.length()));
        }
        prop_assert!(a.to_halfedge_mesh().is_ok());
    }
}

#[test]
fn ternary_counts_are_checked_before_any_work() {
    // The counts of each level are those of the closed form the check uses, with and
    // without a boundary.
    for soup in [shapes::icosahedron(), shapes::grid(3, 2, CellKind::Triangles).unwrap()] {
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        let (mut v, mut e, mut f) = (mesh.vertex_count(), mesh.edge_count(), mesh.face_count());
        for levels in 1..=2 {
            (v, e, f) = (v + 2 * e + f, 3 * e + 9 * f, 9 * f);
            let fine = ternary_subdivide(&mesh, levels, &TernaryOptions::default()).unwrap();
            let built = HalfedgeMesh::from_soup(&fine.to_soup()).unwrap();
            assert_eq!((built.vertex_count(), built.edge_count(), built.face_count()), (v, e, f));
        }
    }
    // The icosahedron's 20 faces become 20 * 9^8 at level 8: 3 * 20 * 9^8 face corners,
    // more than a half-edge mesh holds, so 8 levels or more fail at once.
    let mesh = HalfedgeMesh::from_soup(&shapes::icosahedron()).unwrap();
    for levels in [8, 30, u32::MAX] {
        let error = ternary_subdivide(&mesh, levels, &TernaryOptions::default()).unwrap_err();
        let corners = 60 * 9usize.pow(8);
        assert_eq!(
            error.to_string(),
            LoopError::from(MeshError::TooLarge { what: "face corners", count: corners, max: MAX_ELEMENTS / 2 })
                .to_string(),
            "{levels} levels"
        );
    }
}

/// A mesh without faces does not change under any of the schemes, so the level limit
/// is what stops a huge level count (before, `u32::MAX` levels of it ran for hours); a
/// mesh with a face is told its size first, as before.
#[test]
fn level_limits_stop_meshes_that_do_not_grow() {
    use crate::forward::{MAX_LEVELS, Subdivider, refine_attribute, subdivision_matrix};
    let points = vec![DVec3::new(1.0, 2.0, 3.0), DVec3::new(-4.0, 0.5, 8.0)];
    let soup = PolygonSoup::from_faces(points.clone(), Vec::<[u32; 3]>::new());
    let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
    let loop_options = LoopOptions::default();
    let ternary_options = TernaryOptions::default();
    let is_level_limit = |error: LoopError, levels: u32, max: u32| {
        let expected = format!("{levels}: at most {max}");
        assert!(
            matches!(&error, LoopError::InvalidParameter { name: "levels", reason } if *reason == expected),
            "{levels} levels: {error}"
        );
    };
    // Up to the limit: the points unchanged, no faces.
    let same = |fine: LoopMesh| assert_eq!((fine.positions, fine.triangles.len()), (points.clone(), 0));
    same(subdivide(&mesh, MAX_LEVELS, &loop_options).unwrap());
    same(ternary_subdivide(&mesh, MAX_LEVELS, &ternary_options).unwrap());
    same(quaternary_subdivide(&mesh, MAX_LEVELS / 2, &loop_options).unwrap());
    for levels in [MAX_LEVELS + 1, u32::MAX] {
        is_level_limit(subdivide(&mesh, levels, &loop_options).unwrap_err(), levels, MAX_LEVELS);
        is_level_limit(refine_attribute(&mesh, levels, &loop_options, &[1.0, 2.0]).unwrap_err(), levels, MAX_LEVELS);
        is_level_limit(subdivision_matrix(&mesh, levels, &loop_options).unwrap_err(), levels, MAX_LEVELS);
        let mut out = LoopMesh::default();
        let error = Subdivider::new(loop_options).subdivide_into(&mesh, levels, &mut out).unwrap_err();
        is_level_limit(error, levels, MAX_LEVELS);
        is_level_limit(ternary_subdivide(&mesh, levels, &ternary_options).unwrap_err(), levels, MAX_LEVELS);
        is_level_limit(ternary_matrix(&mesh, levels, &ternary_options).unwrap_err(), levels, MAX_LEVELS);
    }
    // Quaternary levels are two Loop steps: the limit is half, and named in its levels.
    for levels in [MAX_LEVELS / 2 + 1, MAX_LEVELS + 1, u32::MAX] {
        is_level_limit(quaternary_subdivide(&mesh, levels, &loop_options).unwrap_err(), levels, MAX_LEVELS / 2);
    }
    // A mesh with a face: the size error, at any level count past its size.
    let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron()).unwrap();
    for levels in [20, MAX_LEVELS + 1, u32::MAX] {
        let too_large = |error: LoopError| matches!(error, LoopError::Mesh(MeshError::TooLarge { .. }));
        assert!(too_large(subdivide(&octahedron, levels, &loop_options).unwrap_err()), "{levels}");
        assert!(too_large(quaternary_subdivide(&octahedron, levels, &loop_options).unwrap_err()), "{levels}");
        assert!(too_large(ternary_subdivide(&octahedron, levels, &ternary_options).unwrap_err()), "{levels}");
    }
}

#[test]
fn ternary_edge_weights_reject_bad_valences_and_lambdas() {
    // `usize::MAX` used to overflow the capacity, 200 000 to run for a minute, NaN to
    // give NaN weights.
    for n in [0, 2, crate::analysis::MAX_VALENCE + 1, 200_000, usize::MAX] {
        assert!(
            matches!(ternary_edge_weights(n, 0.3), Err(LoopError::InvalidParameter { name: "valence", .. })),
            "{n}"
        );
    }
    for lambda in [f64::NAN, f64::INFINITY, 0.1, 0.6] {
        assert!(
            matches!(ternary_edge_weights(5, lambda), Err(LoopError::InvalidParameter { name: "lambda", .. })),
            "{lambda}"
        );
    }
    assert_eq!(ternary_edge_weights(crate::analysis::MAX_VALENCE, 0.5).unwrap().len(), crate::analysis::MAX_VALENCE);
}

#[test]
fn lattice_sizes_that_overflow_are_rejected() {
    let masks = box_spline_masks(2).unwrap();
    // `width * height` used to wrap to 0 (then a panic, or `Ok(vec![])`).
    for (width, height) in [(1usize << 62, 4), (1 << 63, 4), (4, usize::MAX), (usize::MAX, usize::MAX)] {
        assert!(
            matches!(
                subdivide_lattice::<f64>(&[], width, height, &masks),
                Err(LoopError::InvalidParameter { name: "lattice", .. })
            ),
            "{width} x {height}"
        );
    }
}

#[test]
fn closed_form_edge_weights_agree_with_the_sum_and_are_linear_time() {
    for n in (3..=40).chain([199, 200, 201, 202]) {
        for lambda in [0.2, 1.0 / 3.0, 0.5] {
            let (closed, sum) = (edge_weights_closed(n, lambda), edge_weights(n.min(200), lambda));
            if n <= 200 {
                for (l, (a, b)) in closed.iter().zip(&sum).enumerate() {
                    assert!((a - b).abs() < 1e-15, "n = {n}, lambda = {lambda}, l = {l}: {a} vs {b}");
                }
            }
            assert!((4.0 / 9.0 + closed.iter().sum::<f64>() - 1.0).abs() < 1e-13, "n = {n}");
        }
    }
    // A mesh vertex of valence 200 000 used to cost 4e10 terms (minutes).
    let gamma = edge_weights(200_000, 1.0 / 3.0);
    assert!((4.0 / 9.0 + gamma.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    assert!(gamma.iter().all(|g| g.is_finite()));
}

/// Finite coordinates whose rules overflow give an error naming the output vertex, not
/// infinities, for every scheme and the limit masks (or, where a scheme's sums do not
/// overflow, the scaled result); large coordinates that do not overflow give the scaled
/// result.
#[test]
fn overflowing_coordinates_are_an_error() {
    use crate::forward::Subdivider;
    use crate::limit::{limit_positions, limit_tangents};
    // The soup with its largest coordinate magnitude scaled to `largest`.
    let scaled = |soup: &PolygonSoup, largest: f64| {
        let unit = soup.positions.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
        let positions = soup.positions.iter().map(|p| *p / unit * largest).collect();
        HalfedgeMesh::from_soup(&PolygonSoup { positions, ..soup.clone() }).unwrap()
    };
    let loop_options = LoopOptions::default();
    type Operation<'a> = Box<dyn Fn(&HalfedgeMesh) -> Result<Vec<DVec3>, LoopError> + 'a>;
    let operations: Vec<(&str, Operation<'_>)> = vec![
        ("loop", Box::new(|m| subdivide(m, 1, &loop_options).map(|f| f.positions))),
        (
            "subdivider",
            Box::new(|m| {
                let mut out = LoopMesh::default();
                let result = Subdivider::new(loop_options).subdivide_into(m, 1, &mut out);
                result.map(|()| out.positions)
            }),
        ),
        ("ternary", Box::new(|m| ternary_subdivide(m, 1, &TernaryOptions::default()).map(|f| f.positions))),
        ("quaternary", Box::new(|m| quaternary_subdivide(m, 1, &loop_options).map(|f| f.positions))),
        ("limit", Box::new(|m| limit_positions(m, &loop_options))),
        (
            "tangents",
            Box::new(|m| {
                limit_tangents(m, &loop_options).map(|f| f.iter().flat_map(|(p, [a, b])| [*p, *a, *b]).collect())
            }),
        ),
    ];
    let mut overflowed = Vec::new();
    for soup in [shapes::icosahedron(), shapes::grid(2, 2, CellKind::Triangles).unwrap()] {
        // Coordinates of magnitude up to 1, 1e300 (no overflow) and 1.7e308 (a sum of two
        // neighbours overflows).
        let (unit, large, huge) = (scaled(&soup, 1.0), scaled(&soup, 1e300), scaled(&soup, 1.7e308));
        for (name, operation) in &operations {
            let reference = operation(&unit).unwrap();
            let close = |result: &[DVec3], factor: f64| {
                result.len() == reference.len()
                    && result.iter().zip(&reference).all(|(p, q)| (*p / factor - *q).length() < 1e-12)
            };
            assert!(close(&operation(&large).unwrap(), 1e300), "{name}");
            match operation(&huge) {
                Err(LoopError::Overflow { largest, .. }) => {
                    assert_eq!(largest, 1.7e308, "{name}");
                    overflowed.push(*name);
                }
                Ok(result) => assert!(close(&result, 1.7e308), "{name}"),
                Err(error) => panic!("{name}: {error}"),
            }
        }
    }
    // Loop's edge points sum two neighbours before weighting them.
    assert!(overflowed.contains(&"loop") && overflowed.contains(&"subdivider"), "{overflowed:?}");
}

/// Attribute values that are not finite are refused by every attribute entry point,
/// naming the vertex (lattice point, matrix column); finite values so large that the
/// rules' sums overflow are reported, naming the first refined value; before, both
/// spread NaN or infinity over the neighbours' fine values and returned `Ok`. Types
/// without a finiteness test (the trait's default) refine as before.
#[test]
fn non_finite_and_overflowing_attributes_are_errors() {
    use crate::forward::{refine_attribute, subdivision_matrix};
    let mesh = HalfedgeMesh::from_soup(&shapes::icosahedron()).unwrap();
    let (loop_options, ternary) = (LoopOptions::default(), TernaryOptions::default());
    let masks = box_spline_masks(3).unwrap();
    let matrix = subdivision_matrix(&mesh, 1, &loop_options).unwrap();
    type Refine<'a> = Box<dyn Fn(&[f64]) -> Result<Vec<f64>, LoopError> + 'a>;
    let operations: Vec<(&str, Refine<'_>)> = vec![
        ("loop", Box::new(|v| refine_attribute(&mesh, 1, &loop_options, v))),
        ("ternary", Box::new(|v| ternary_refine_attribute(&mesh, 1, &ternary, v))),
        ("matrix", Box::new(|v| matrix.apply(v))),
        // The 12 values on a 4 x 3 lattice would be too small; 4 x 4 with 4 more.
        ("lattice", Box::new(|v| subdivide_lattice(&[v, &v[..4]].concat(), 4, 4, &masks))),
    ];
    let mut overflowed = Vec::new();
    for (name, operation) in &operations {
        let unit: Vec<f64> = (0..12).map(|i| (i as f64 * 0.7).sin()).collect();
        let reference = operation(&unit).unwrap();
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut values = unit.clone();
            values[7] = bad;
            match operation(&values) {
                Err(LoopError::NonFiniteAttribute { vertex: 7 }) => {}
                other => panic!("{name}: {bad}: {other:?}"),
            }
        }
        // Scaled to 1e300 the result is the scaled reference; near f64::MAX a rule that
        // sums neighbours before weighting them (Loop's edge points) overflows, the
        // others keep the constant (affine rules).
        let large: Vec<f64> = unit.iter().map(|v| v * 1e300).collect();
        let refined = operation(&large).unwrap();
        assert!(refined.iter().zip(&reference).all(|(a, b)| (a / 1e300 - b).abs() < 1e-12), "{name}");
        match operation(&[1.7e308; 12]) {
            Err(LoopError::AttributeOverflow { vertex }) => {
                assert!(vertex < reference.len(), "{name}");
                overflowed.push(*name);
            }
            Ok(constant) => assert!(constant.iter().all(|v| (v / 1.7e308 - 1.0).abs() < 1e-12), "{name}"),
            other => panic!("{name}: {other:?}"),
        }
    }
    assert!(overflowed.contains(&"loop"), "{overflowed:?}");
    let message = refine_attribute(&mesh, 1, &loop_options, &[f64::NAN; 12]).unwrap_err().to_string();
    assert_eq!(message, "the attribute value of vertex 0 is not finite");
    // Vectors and channel arrays test every component.
    let mut colours = vec![[0.5f64, 0.25, 1.0]; 12];
    colours[3][2] = f64::NAN;
    assert!(matches!(
        refine_attribute(&mesh, 1, &loop_options, &colours),
        Err(LoopError::NonFiniteAttribute { vertex: 3 })
    ));
    let mut positions = mesh.positions().to_vec();
    positions[5].y = f64::INFINITY;
    assert!(matches!(
        refine_attribute(&mesh, 1, &loop_options, &positions),
        Err(LoopError::NonFiniteAttribute { vertex: 5 })
    ));
}
