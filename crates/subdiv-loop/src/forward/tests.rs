//! Tests of the forward scheme against a plain half-edge implementation, closed forms
//! and invariants.

use glam::DVec3;
use mesh_topo::shapes::{self, CellKind};
use mesh_topo::testing::arb_triangle_mesh;
use mesh_topo::{HalfedgeMesh, MeshError, PolygonSoup};
use proptest::prelude::*;

use super::kernel::{loop_beta, warren_beta};
use super::*;

/// A straightforward Loop step on the general half-edge mesh, written independently of
/// the compact kernel (different traversal, different summation order).
fn reference_step(mesh: &HalfedgeMesh, options: &LoopOptions) -> LoopMesh {
    let nv = mesh.vertex_count();
    let p = |v: mesh_topo::VertexId| mesh.position(v);
    let mut positions = Vec::new();
    for v in mesh.vertices() {
        let valence = mesh.valence(v);
        let point = if mesh.is_isolated(v) {
            p(v)
        } else if mesh.is_boundary_vertex(v) {
            let out = mesh.vertex_halfedge(v).unwrap();
            let q_plus = mesh.target(out);
            let q_minus = mesh.origin(mesh.prev(out));
            if options.keep_corners && valence == 2 { p(v) } else { 0.75 * p(v) + 0.125 * (p(q_plus) + p(q_minus)) }
        } else {
            let beta = match options.weights {
                VertexWeights::Loop => loop_beta(valence),
                VertexWeights::Warren => warren_beta(valence),
            };
            let mut point = (1.0 - valence as f64 * beta) * p(v);
            for q in mesh.vertex_neighbors(v) {
                point += beta * p(q);
            }
            point
        };
        positions.push(point);
    }
    for e in mesh.edges() {
        let [a, b] = mesh.edge_vertices(e);
        let (h0, h1) = (e.halfedge(0), e.halfedge(1));
        positions.push(if mesh.is_boundary_edge(e) {
            0.5 * (p(a) + p(b))
        } else {
            let c = mesh.target(mesh.next(h0));
            let d = mesh.target(mesh.next(h1));
            0.375 * (p(a) + p(b)) + 0.125 * (p(c) + p(d))
        });
    }
    let mut triangles = Vec::new();
    for f in mesh.faces() {
        let c: Vec<u32> = mesh.face_vertices(f).map(|v| v.raw()).collect();
        let m: Vec<u32> = mesh.face_halfedges(f).map(|h| (nv + h.edge().index()) as u32).collect();
        triangles.push([c[0], m[0], m[2]]);
        triangles.push([c[1], m[1], m[0]]);
        triangles.push([c[2], m[2], m[1]]);
        triangles.push([m[0], m[1], m[2]]);
    }
    LoopMesh { positions, triangles }
}

fn mesh(soup: &PolygonSoup) -> HalfedgeMesh {
    HalfedgeMesh::from_soup(soup).unwrap()
}

fn assert_close(a: &[DVec3], b: &[DVec3], tolerance: f64) {
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!((*x - *y).length() <= tolerance * (1.0 + x.length()), "vertex {i}: {x} vs {y}");
    }
}

fn test_meshes() -> Vec<(&'static str, PolygonSoup)> {
    vec![
        ("tetrahedron", shapes::tetrahedron()),
        ("icosahedron", shapes::icosahedron()),
        ("octahedron", shapes::octahedron()),
        ("grid", mesh_topo::testing::scramble(shapes::grid(4, 3, CellKind::Triangles).unwrap(), 7, 0.1)),
        ("torus", mesh_topo::testing::scramble(shapes::torus(5, 4, CellKind::Triangles).unwrap(), 3, 0.1)),
        ("single triangle", PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])),
    ]
}

#[test]
fn one_step_matches_the_plain_half_edge_implementation() {
    let variants = [
        LoopOptions::default(),
        LoopOptions::warren_weights(),
        LoopOptions { keep_corners: true, ..LoopOptions::default() },
    ];
    for (name, soup) in test_meshes() {
        let m = mesh(&soup);
        for options in &variants {
            let fast = subdivide(&m, 1, options).unwrap();
            let slow = reference_step(&m, options);
            assert_eq!(fast.triangles, slow.triangles, "{name}");
            assert_close(&fast.positions, &slow.positions, 1e-15);
        }
    }
}

#[test]
fn several_levels_are_repeated_single_steps() {
    for (name, soup) in test_meshes() {
        let m = mesh(&soup);
        let options = LoopOptions { keep_corners: true, ..LoopOptions::default() };
        let three = subdivide(&m, 3, &options).unwrap();
        let mut step = subdivide(&m, 1, &options).unwrap();
        for _ in 1..3 {
            step = subdivide(&step.to_halfedge_mesh().unwrap(), 1, &options).unwrap();
        }
        assert_eq!(three.triangles, step.triangles, "{name}");
        assert_close(&three.positions, &step.positions, 4e-16);
        // And the reference agrees at every level.
        let mut reference = reference_step(&m, &options);
        for _ in 1..3 {
            reference = reference_step(&reference.to_halfedge_mesh().unwrap(), &options);
        }
        assert_eq!(three.triangles, reference.triangles);
        assert_close(&three.positions, &reference.positions, 1e-14);
    }
}

#[test]
fn each_level_is_written_in_the_memory_of_the_level_two_before_it() {
    let icosahedron = mesh(&shapes::icosahedron());
    let options = LoopOptions::default();
    let rules = Rules::new(&options);
    for levels in 0..5u32 {
        // The base triangles have the room of the finest level of their parity.
        let expected_room = if levels < 2 { 20 } else { 20 << (2 * (levels & !1)) };
        let topology = checked_base(&icosahedron, levels, size_of::<DVec3>()).unwrap();
        assert!(topology.triangles.capacity() >= expected_room, "{levels} levels");
        let base_triangles = topology.triangles.as_ptr();
        let (positions, fine) = refine(topology, icosahedron.positions(), levels, &rules);
        // An even count writes its output in that memory.
        if levels >= 2 && levels % 2 == 0 {
            assert_eq!(fine.triangles.as_ptr(), base_triangles, "{levels} levels");
        }
        // The same bits as the steps each into fresh arrays.
        let (mut fresh, mut values) = (Topology::from_mesh(&icosahedron).unwrap(), icosahedron.positions().to_vec());
        for level in 0..levels {
            let step = kernel::step(&fresh, &values, &rules, level + 1 < levels);
            (fresh, values) = (step.topology, step.values);
        }
        assert_eq!(fine.triangles, fresh.triangles, "{levels} levels");
        let bits = |p: &[DVec3]| p.iter().map(|q| q.to_array().map(f64::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&positions), bits(&values), "{levels} levels");
    }
    // A count that is refused reserves only the base's own room (and is refused).
    let refused = check_sizes(12, 30, 20, 20).map(|(_, faces)| faces);
    assert!(refused.is_err());
    assert_eq!(base_triangle_room(20, 20, &refused), 20);
    assert!(checked_base(&icosahedron, 20, size_of::<DVec3>()).is_err());
}

#[test]
fn counts_and_euler_characteristic() {
    for (name, soup) in test_meshes() {
        let m = mesh(&soup);
        let (v, e, f) = (m.vertex_count(), m.edge_count(), m.face_count());
        let fine = subdivide(&m, 2, &LoopOptions::default()).unwrap();
        let (v1, e1, f1) = (v + e, 2 * e + 3 * f, 4 * f);
        assert_eq!((fine.vertex_count(), fine.face_count()), (v1 + e1, 4 * f1), "{name}");
        let fine_mesh = fine.to_halfedge_mesh().unwrap();
        assert_eq!(fine_mesh.edge_count(), 2 * e1 + 3 * f1);
        assert_eq!(fine_mesh.euler_characteristic(), m.euler_characteristic(), "{name}");
        let stats = (m.topology_stats(), fine_mesh.topology_stats());
        assert_eq!(stats.0.boundary_loops, stats.1.boundary_loops);
    }
}

#[test]
fn zero_levels_returns_the_input() {
    let m = mesh(&shapes::icosahedron());
    let same = subdivide(&m, 0, &LoopOptions::default()).unwrap();
    assert_eq!(same.to_soup(), shapes::icosahedron());
}

#[test]
fn soups_hold_the_triangles_in_order() {
    let fine = subdivide(&mesh(&shapes::octahedron()), 2, &LoopOptions::default()).unwrap();
    let expected = PolygonSoup::from_faces(fine.positions.clone(), &fine.triangles);
    assert_eq!(fine.to_soup(), expected);
    let indices = fine.triangles.as_ptr().cast::<u32>();
    let soup = fine.into_soup();
    assert_eq!(soup, expected);
    assert_eq!(soup.offsets.len(), soup.face_count() + 1);
    // The indices reuse the triangles' memory.
    assert_eq!(soup.indices.as_ptr(), indices);
    let empty = LoopMesh { positions: vec![DVec3::ZERO], triangles: Vec::new() };
    assert_eq!(empty.clone().into_soup(), empty.to_soup());
    assert_eq!(empty.into_soup().face_count(), 0);
}

#[test]
fn results_do_not_depend_on_the_number_of_threads() {
    // 20 * 4^5 = 20 480 faces at the last input level: split into several face and
    // vertex chunks on a pool of several threads.
    let m = mesh(&mesh_topo::testing::scramble(shapes::icosahedron(), 11, 0.2));
    assert!(20 * 4usize.pow(5) >= super::kernel::PARALLEL_MIN_FACES);
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| subdivide(&m, 6, &LoopOptions::default()).unwrap())
    };
    let one = run(1);
    assert_eq!(one, run(3));
    assert_eq!(one.face_count(), 20 * 4usize.pow(6));
}

#[test]
fn regular_rules_are_the_box_spline_masks() {
    // Every vertex of this torus has valence 6: vertex rows 5/8 + 6 x 1/16, edge rows
    // 3/8, 3/8, 1/8, 1/8 (the M = 2 masks of the three-direction box spline).
    let m = mesh(&shapes::torus(6, 6, CellKind::Triangles).unwrap());
    assert!(m.vertices().all(|v| m.valence(v) == 6));
    for options in [LoopOptions::default(), LoopOptions::warren_weights()] {
        let s = subdivision_matrix(&m, 1, &options).unwrap();
        for i in 0..m.vertex_count() {
            let (cols, w) = s.row(i);
            assert_eq!(cols.len(), 7);
            for (&c, &w) in cols.iter().zip(w) {
                let expected = if c as usize == i { 10.0 / 16.0 } else { 1.0 / 16.0 };
                assert!((w - expected).abs() < 1e-15);
            }
        }
        for e in 0..m.edge_count() {
            let (_, w) = s.row(m.vertex_count() + e);
            let mut w = w.to_vec();
            w.sort_by(f64::total_cmp);
            assert_eq!(w, [0.125, 0.125, 0.375, 0.375]);
        }
    }
}

#[test]
fn boundary_rules_and_fixed_corners() {
    // A 2 x 1 grid: corners (0,0) and (2,1) have valence 2 (one face).
    let soup = shapes::grid(2, 1, CellKind::Triangles).unwrap();
    let m = mesh(&soup);
    let corners: Vec<usize> = m.vertices().filter(|&v| m.valence(v) == 2).map(|v| v.index()).collect();
    assert!(!corners.is_empty());
    let kept = subdivide(&m, 1, &LoopOptions { keep_corners: true, ..LoopOptions::default() }).unwrap();
    let smoothed = subdivide(&m, 1, &LoopOptions::default()).unwrap();
    for &c in &corners {
        assert_eq!(kept.positions[c], m.positions()[c]);
        assert_ne!(smoothed.positions[c], m.positions()[c]);
    }
    // Boundary vertices follow the boundary alone: a planar grid stays in its plane
    // and boundary points stay on the boundary lines.
    for p in &smoothed.positions {
        assert_eq!(p.z, 0.0);
    }
}

#[test]
fn loop_and_warren_weights_agree_only_at_valences_3_and_6() {
    assert!((loop_beta(3) - warren_beta(3)).abs() < 1e-16);
    assert!((loop_beta(6) - warren_beta(6)).abs() < 1e-16);
    for n in [4, 5, 7, 8, 12] {
        assert!((loop_beta(n) - warren_beta(n)).abs() > 1e-4);
    }
}

#[test]
fn bad_input_gives_typed_errors() {
    let quads = shapes::cube();
    assert_eq!(
        subdivide_soup(&quads, 1, &LoopOptions::default()).unwrap_err(),
        LoopError::NotTriangle { face: 0, corners: 4 }
    );
    let mixed = shapes::grid(2, 2, CellKind::Mixed).unwrap();
    assert!(matches!(subdivide_soup(&mixed, 1, &LoopOptions::default()), Err(LoopError::NotTriangle { .. })));
    // Three triangles on one edge.
    let fin = PolygonSoup::from_faces(
        vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::NEG_Y],
        [[0u32, 1, 2], [1, 0, 3], [0, 1, 4]],
    );
    assert!(matches!(
        subdivide_soup(&fin, 1, &LoopOptions::default()),
        Err(LoopError::Mesh(MeshError::NonManifoldEdge { .. }))
    ));
    let mut m = mesh(&shapes::tetrahedron());
    m.positions_mut()[2].y = f64::NAN;
    assert!(matches!(
        subdivide(&m, 1, &LoopOptions::default()),
        Err(LoopError::Mesh(MeshError::NonFiniteCoordinate { vertex: 2, axis: 1, .. }))
    ));
    let m = mesh(&shapes::tetrahedron());
    assert!(matches!(subdivide(&m, 40, &LoopOptions::default()), Err(LoopError::Mesh(MeshError::TooLarge { .. }))));
    assert_eq!(
        refine_attribute(&m, 1, &LoopOptions::default(), &[1.0f64; 3]).unwrap_err(),
        LoopError::AttributeCount { expected: 4, found: 3 }
    );
}

#[test]
fn the_counts_checked_before_the_work_are_those_of_the_output() {
    // Closed and open meshes: the last level's vertices and faces, whose arrays (a
    // position per vertex, three indices per triangle) the memory check counts.
    for soup in [shapes::octahedron(), shapes::grid(3, 2, CellKind::Triangles).unwrap()] {
        let m = mesh(&soup);
        for levels in 0..4 {
            let fine = subdivide(&m, levels, &LoopOptions::default()).unwrap();
            let (vertices, faces) = check_sizes(m.vertex_count(), m.edge_count(), m.face_count(), levels).unwrap();
            assert_eq!((vertices, faces), (fine.vertex_count() as u64, fine.face_count() as u64));
        }
    }
    // No machine has 2^40 positions and triangles (40 TB); where the memory cannot be
    // read, nothing is refused.
    match check_output_memory(1 << 40, 1 << 40, size_of::<DVec3>(), 0) {
        Err(LoopError::Mesh(MeshError::OutOfMemory { what, needed_bytes, .. })) => {
            assert_eq!((what, needed_bytes), ("Loop output", 36 << 40));
        }
        other => assert!(other.is_ok() && mesh_topo::memory::available_bytes().is_none(), "{other:?}"),
    }
    // Small outputs are made without asking.
    assert!(check_output_memory(1000, 2000, size_of::<DVec3>(), 0).is_ok());
}

#[test]
fn matrix_matches_positions_over_several_levels() {
    let m = mesh(&mesh_topo::testing::scramble(shapes::grid(3, 3, CellKind::Triangles).unwrap(), 5, 0.2));
    let options = LoopOptions::default();
    let s2 = subdivision_matrix(&m, 2, &options).unwrap();
    let s1 = subdivision_matrix(&m, 1, &options).unwrap();
    let fine1 = subdivide(&m, 1, &options).unwrap();
    let s1b = subdivision_matrix(&fine1.to_halfedge_mesh().unwrap(), 1, &options).unwrap();
    let composed = s1b.compose(&s1).unwrap();
    assert_eq!((s2.rows(), s2.columns()), (composed.rows(), composed.columns()));
    for i in 0..s2.rows() {
        for j in 0..s2.columns() {
            assert!((s2.get(i, j) - composed.get(i, j)).abs() < 1e-15);
        }
    }
    let fine2 = subdivide(&m, 2, &options).unwrap();
    assert_close(&s2.apply(m.positions()).unwrap(), &fine2.positions, 1e-15);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    #[test]
    fn affine_maps_commute_with_subdivision(
        soup in arb_triangle_mesh(),
        angle in 0.0..std::f64::consts::TAU,
        scale in 0.1..10.0f64,
        shift in prop::array::uniform3(-5.0..5.0f64),
        warren in any::<bool>(),
        keep_corners in any::<bool>(),
    ) {
        let options = LoopOptions {
            weights: if warren { VertexWeights::Warren } else { VertexWeights::Loop },
            keep_corners,
        };
        let m = mesh(&soup);
        let transform = glam::DAffine3::from_scale_rotation_translation(
            DVec3::new(scale, 1.0, 2.0),
            glam::DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), angle),
            DVec3::from(shift),
        );
        let moved: Vec<DVec3> = m.positions().iter().map(|&p| transform.transform_point3(p)).collect();
        let mut moved_mesh = m.clone();
        moved_mesh.replace_positions(moved).unwrap();
        let a = subdivide(&m, 2, &options).unwrap();
        let b = subdivide(&moved_mesh, 2, &options).unwrap();
        prop_assert_eq!(&a.triangles, &b.triangles);
        for (p, q) in a.positions.iter().zip(&b.positions) {
            let expected = transform.transform_point3(*p);
            prop_assert!((expected - *q).length() < 1e-11 * (1.0 + expected.length()));
        }
    }

    #[test]
    fn matrix_rows_sum_to_one(soup in arb_triangle_mesh(), warren in any::<bool>()) {
        let options = if warren { LoopOptions::warren_weights() } else { LoopOptions::default() };
        let m = mesh(&soup);
        let s = subdivision_matrix(&m, 1, &options).unwrap();
        prop_assert_eq!(s.rows(), m.vertex_count() + m.edge_count());
        for sum in s.row_sums() {
            prop_assert!((sum - 1.0).abs() < 1e-14);
        }
    }

    #[test]
    fn random_meshes_match_the_reference(soup in arb_triangle_mesh()) {
        let m = mesh(&soup);
        let options = LoopOptions::default();
        let fast = subdivide(&m, 1, &options).unwrap();
        let slow = reference_step(&m, &options);
        prop_assert_eq!(&fast.triangles, &slow.triangles);
        for (a, b) in fast.positions.iter().zip(&slow.positions) {
            prop_assert!((*a - *b).length() < 1e-14 * (1.0 + a.length()));
        }
    }
}

#[test]
fn fine_topology_equals_the_topology_of_the_output() {
    for (name, soup) in test_meshes() {
        let m = mesh(&soup);
        let rules = Rules::new(&LoopOptions::default());
        let coarse = Topology::from_mesh(&m).unwrap();
        let one = kernel::step(&coarse, m.positions(), &rules, true);
        let two = kernel::step(&one.topology, &one.values, &rules, true);
        for step in [one, two] {
            let out = LoopMesh { positions: step.values.clone(), triangles: step.topology.triangles.clone() };
            let rebuilt = Topology::from_mesh(&out.to_halfedge_mesh().unwrap()).unwrap();
            assert_eq!(step.topology.links, rebuilt.links, "{name}: links");
            assert_eq!(step.topology.edge_count, rebuilt.edge_count, "{name}");
            for v in 0..step.topology.vertex_halfedge.len() as u32 {
                let (mut a, ba) = step.topology.ring(v);
                let (mut b, bb) = rebuilt.ring(v);
                assert_eq!(ba, bb);
                a.sort_unstable();
                b.sort_unstable();
                assert_eq!(a, b, "{name}: ring of {v}");
            }
        }
    }
}

/// Any soup: random positions (some not finite), random faces of 0 to 5 corners with
/// indices that may be out of range or repeated.
fn arb_any_soup() -> impl Strategy<Value = PolygonSoup> {
    let coordinate = prop_oneof![8 => -10.0..10.0f64, 1 => Just(f64::NAN), 1 => Just(f64::INFINITY)];
    (
        prop::collection::vec(prop::array::uniform3(coordinate), 0..9),
        prop::collection::vec(prop::collection::vec(0u32..10, 0..6), 0..12),
    )
        .prop_map(|(positions, faces)| PolygonSoup::from_faces(positions.into_iter().map(DVec3::from).collect(), faces))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_soups_never_panic(soup in arb_any_soup(), levels in 0u32..3) {
        let options = LoopOptions { keep_corners: levels == 1, ..LoopOptions::default() };
        let result = subdivide_soup(&soup, levels, &options);
        if let Ok(fine) = &result {
            prop_assert!(fine.positions.iter().all(|p| p.is_finite()));
        }
        if let Ok(mesh) = HalfedgeMesh::from_soup(&soup) {
            let ternary = crate::mband::ternary_subdivide(&mesh, 1, &crate::mband::TernaryOptions::default());
            let limit = crate::limit::limit_normals(&mesh, &options);
            let one = subdivide(&mesh, 1, &options).is_ok();
            prop_assert_eq!(ternary.is_ok(), one);
            prop_assert_eq!(limit.is_ok(), one);
            prop_assert_eq!(result.is_ok(), one);
        }
    }

    #[test]
    fn polygon_meshes_are_rejected_at_their_first_non_triangle(soup in mesh_topo::testing::arb_mesh()) {
        let first = soup.faces().position(|f| f.len() != 3);
        match (subdivide_soup(&soup, 1, &LoopOptions::default()), first) {
            (Ok(fine), None) => prop_assert_eq!(fine.face_count(), 4 * soup.face_count()),
            (Err(LoopError::NotTriangle { face, corners }), Some(f)) => {
                prop_assert_eq!(face, f);
                prop_assert_eq!(corners, soup.face(f).len());
            }
            (other, _) => prop_assert!(false, "unexpected {:?}", other.map(|m| m.face_count())),
        }
    }
}
