//! Reverse Doo-Sabin: exactness, storage, linear cost, seeds, components, errors.

use mesh_topo::shapes::{self, CellKind};
use mesh_topo::testing::scramble;
use mesh_topo::{DVec3, HalfedgeMesh, PolygonSoup};
use subdiv_doo::{DooError, DooOptions, FaceRule, ReverseOptions, reverse, subdivide_soup};

const RULES: [FaceRule; 3] = [FaceRule::DooSabin, FaceRule::Simple, FaceRule::CENTROID_HALF];

/// A triangular prism (two triangles, three quads).
fn prism() -> PolygonSoup {
    let p = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(1.0, 0.0, 1.0),
        DVec3::new(0.0, 1.0, 1.0),
    ];
    let faces: Vec<Vec<u32>> = vec![vec![0, 2, 1], vec![3, 4, 5], vec![0, 1, 4, 3], vec![1, 2, 5, 4], vec![2, 0, 3, 5]];
    PolygonSoup::from_faces(p, faces)
}

/// A pentagonal pyramid (a pentagon and a valence-5 apex).
fn pyramid() -> PolygonSoup {
    let mut p: Vec<DVec3> = (0..5)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / 5.0;
            DVec3::new(t.cos(), t.sin(), 0.0)
        })
        .collect();
    p.push(DVec3::new(0.1, -0.2, 1.3));
    let mut faces: Vec<Vec<u32>> = vec![vec![4, 3, 2, 1, 0]];
    for i in 0..5u32 {
        faces.push(vec![i, (i + 1) % 5, 5]);
    }
    PolygonSoup::from_faces(p, faces)
}

/// The cube without its top face (one boundary loop).
fn open_box() -> PolygonSoup {
    let cube = shapes::cube();
    let faces: Vec<Vec<u32>> = cube.faces().take(5).map(<[u32]>::to_vec).collect();
    PolygonSoup::from_faces(cube.positions.clone(), faces)
}

fn coarse_meshes() -> Vec<(&'static str, PolygonSoup)> {
    vec![
        ("cube", shapes::cube()),
        ("tetrahedron", shapes::tetrahedron()),
        ("icosahedron", shapes::icosahedron()),
        ("prism", prism()),
        ("pyramid", pyramid()),
        ("open box", open_box()),
        ("grid", shapes::grid(3, 2, CellKind::Mixed).unwrap()),
        ("torus", shapes::torus(5, 4, CellKind::Mixed).unwrap()),
    ]
}

fn doo(soup: &PolygonSoup, rule: FaceRule, levels: u32) -> HalfedgeMesh {
    subdivide_soup(soup, &DooOptions::new(rule, levels)).unwrap().to_mesh().unwrap()
}

fn diagonal(points: &[DVec3]) -> f64 {
    let (lo, hi) = points.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    (hi - lo).length()
}

fn max_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(p, q)| (*p - *q).length()).fold(0.0, f64::max)
}

/// `coarse` equals `original` up to a renumbering of the vertices (same faces in the
/// same order, same first corners), positions within `tolerance`.
fn assert_same_up_to_renumbering(coarse: &PolygonSoup, original: &PolygonSoup, tolerance: f64) {
    assert_eq!(coarse.offsets, original.offsets);
    // Closed meshes come back with their own vertex numbering (read off the F_V faces).
    let closed = HalfedgeMesh::from_soup(original).unwrap().topology_stats().boundary_loops == 0;
    if closed {
        assert_eq!(coarse.indices, original.indices);
    }
    let mut map = vec![u32::MAX; coarse.vertex_count()];
    for (&c, &o) in coarse.indices.iter().zip(&original.indices) {
        assert!(map[c as usize] == u32::MAX || map[c as usize] == o, "not a renumbering");
        map[c as usize] = o;
        assert!((coarse.positions[c as usize] - original.positions[o as usize]).length() <= tolerance);
    }
}

#[test]
fn reverse_of_doo_is_the_original_with_zero_details() {
    for (name, coarse) in coarse_meshes() {
        let used = coarse.indices.iter().copied().max().unwrap() as usize + 1;
        assert_eq!(used, coarse.vertex_count(), "{name}: test meshes have no isolated vertex");
        for rule in RULES {
            let fine = doo(&coarse, rule, 1);
            let reversal = reverse(&fine, &ReverseOptions::auto(rule)).unwrap_or_else(|e| panic!("{name}: {e}"));
            let tolerance = 1e-14 * diagonal(&coarse.positions);
            assert_same_up_to_renumbering(&reversal.coarse(), &coarse, tolerance);
            assert!(reversal.details().iter().all(|d| d.length() <= tolerance), "{name} {rule:?}");
            assert!(reversal.fine_order().is_identity(), "{name}");
            // Storage: as many 3-vectors as the fine mesh has vertices.
            assert_eq!(reversal.coarse_positions().len() + reversal.details().len(), fine.vertex_count());
            let choice = &reversal.choices()[0];
            assert_eq!(choice.seed_face, 0, "{name}: {}", choice.reason);
            assert!(choice.reason.contains("zero"), "{}", choice.reason);
        }
    }
}

#[test]
fn reconstruction_is_exact_after_moving_vertices() {
    for (name, coarse) in coarse_meshes() {
        for rule in RULES {
            let mut fine = doo(&coarse, rule, 2);
            let diag = diagonal(fine.positions());
            for (i, p) in fine.positions_mut().iter_mut().enumerate() {
                let t = i as f64;
                *p += 0.05 * diag * DVec3::new((1.7 * t).sin(), (2.3 * t).cos(), (0.9 * t).sin());
            }
            let reversal = reverse(&fine, &ReverseOptions::auto(rule)).unwrap();
            let rebuilt = reversal.reconstruct();
            assert_eq!(rebuilt.offsets, fine.to_soup().offsets);
            assert_eq!(rebuilt.indices, fine.to_soup().indices);
            let error = max_distance(&rebuilt.positions, fine.positions());
            assert!(error <= 1e-12 * diag, "{name} {rule:?}: {error}");
            assert_eq!(reversal.coarse_positions().len() + reversal.details().len(), fine.vertex_count());
            assert!(reversal.details().iter().any(|d| d.length() > 1e-6 * diag));
        }
    }
}

#[test]
fn scrambled_numbering_is_reconstructed_exactly() {
    for (name, coarse) in coarse_meshes() {
        let fine = doo(&coarse, FaceRule::DooSabin, 1).to_soup();
        let scrambled = scramble(fine, 7, 0.01);
        let mesh = HalfedgeMesh::from_soup(&scrambled).unwrap();
        let reversal = reverse(&mesh, &ReverseOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(!reversal.fine_order().is_identity());
        let rebuilt = reversal.reconstruct();
        assert_eq!(rebuilt.offsets, scrambled.offsets, "{name}");
        assert_eq!(rebuilt.indices, scrambled.indices, "{name}");
        assert!(max_distance(&rebuilt.positions, &scrambled.positions) < 1e-14 * diagonal(&scrambled.positions));
    }
}

#[test]
fn traversal_cost_is_linear() {
    for (name, coarse) in coarse_meshes() {
        let fine = doo(&coarse, FaceRule::DooSabin, 2);
        let reversal = reverse(&fine, &ReverseOptions::with_seed(FaceRule::DooSabin, 0)).unwrap();
        let stats = reversal.stats();
        let nv = fine.vertex_count();
        assert!(stats.visited_faces <= nv, "{name}: {stats:?}");
        assert!(stats.edges_crossed <= nv, "{name}: {stats:?}");
        assert!(stats.candidate_edges <= nv, "{name}: {stats:?}");
        assert_eq!(stats.visited_faces, reversal.coarse().face_count());
    }
}

#[test]
fn seeding_at_a_vertex_face_gives_the_dual() {
    // Cube after one step: faces 0..6 are F_F, 6..18 F_E, 18..26 F_V (triangles).
    let fine = doo(&shapes::cube(), FaceRule::DooSabin, 1);
    let dual = reverse(&fine, &ReverseOptions::with_seed(FaceRule::DooSabin, 18)).unwrap();
    let coarse = dual.coarse();
    assert_eq!((coarse.vertex_count(), coarse.face_count()), (6, 8)); // an octahedron
    assert!(coarse.is_triangle_soup());
    assert!(dual.details().iter().any(|d| d.length() > 1e-3));
    // Reconstruction is exact whatever the reading.
    assert!(max_distance(&dual.reconstruct().positions, fine.positions()) < 1e-14);
    // Automatic mode keeps the cube (zero details).
    let auto = reverse(&fine, &ReverseOptions::default()).unwrap();
    assert_eq!(auto.coarse().face_count(), 6);

    // When face 0 is not the best reading, the automatic mode compares the classes: a
    // fine mesh whose F_V faces come first is reversed to the cube, not the octahedron.
    let soup = fine.to_soup();
    let mut faces: Vec<Vec<u32>> = soup.faces().map(<[u32]>::to_vec).collect();
    faces.reverse();
    let reversed_order = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(soup.positions.clone(), faces)).unwrap();
    let auto = reverse(&reversed_order, &ReverseOptions::default()).unwrap();
    assert_eq!(auto.coarse().face_count(), 6, "{:?}", auto.choices());
    let choice = &auto.choices()[0];
    assert!(choice.trials.len() >= 2, "{choice:?}");
    assert!(choice.detail_energy < 1e-20, "{choice:?}");
}

#[test]
fn several_components_and_genus() {
    // Two disjoint cubes and a torus in one mesh.
    let mut soup = shapes::cube();
    for other in [shapes::cube(), shapes::torus(4, 3, CellKind::Quads).unwrap()] {
        let base = soup.vertex_count() as u32;
        soup.positions.extend(other.positions.iter().map(|&p| p + DVec3::splat(5.0 * base as f64)));
        for face in other.faces() {
            soup.push_face(&face.iter().map(|&v| v + base).collect::<Vec<u32>>());
        }
    }
    let mut fine = doo(&soup, FaceRule::DooSabin, 1);
    fine.positions_mut()[3].z += 0.1;
    let reversal = reverse(&fine, &ReverseOptions::default()).unwrap();
    assert_eq!(reversal.choices().len(), 3);
    assert_eq!(reversal.coarse().face_count(), soup.face_count());
    assert!(max_distance(&reversal.reconstruct().positions, fine.positions()) < 1e-13);
    // Seeds: one per component; two in one component is an error.
    let seeds = ReverseOptions { rule: FaceRule::DooSabin, seeds: vec![0, 5], ..Default::default() };
    assert!(matches!(reverse(&fine, &seeds), Err(DooError::DuplicateSeed { first: 0, second: 5 })));
    let seeds = ReverseOptions { rule: FaceRule::DooSabin, seeds: vec![1_000_000], ..Default::default() };
    assert!(matches!(reverse(&fine, &seeds), Err(DooError::SeedOutOfRange { .. })));
}

#[test]
fn not_doo_meshes_are_rejected_with_the_face() {
    for soup in [shapes::cube(), shapes::icosahedron(), shapes::grid(3, 3, CellKind::Triangles).unwrap()] {
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        match reverse(&mesh, &ReverseOptions::default()) {
            Err(DooError::NotDooConnectivity { face, reason }) => {
                assert!(face < soup.face_count(), "{reason}");
            }
            other => panic!("expected an error, got {:?}", other.map(|r| r.coarse())),
        }
    }
    // A given seed that is an F_E quad of the cube's refinement fails (the cube has
    // triangles as F_V faces, so quads cannot be F_F faces there).
    let fine = doo(&shapes::cube(), FaceRule::DooSabin, 1);
    assert!(matches!(
        reverse(&fine, &ReverseOptions::with_seed(FaceRule::DooSabin, 6)),
        Err(DooError::NotDooConnectivity { .. })
    ));
}

#[test]
fn isolated_vertex_and_nan_are_errors() {
    let mut fine = doo(&shapes::cube(), FaceRule::DooSabin, 1).to_soup();
    fine.positions.push(DVec3::ZERO);
    let mesh = HalfedgeMesh::from_soup(&fine).unwrap();
    assert!(matches!(reverse(&mesh, &ReverseOptions::default()), Err(DooError::IsolatedVertex { vertex: 24 })));
    let mut mesh = doo(&shapes::cube(), FaceRule::DooSabin, 1);
    mesh.positions_mut()[2].x = f64::INFINITY;
    assert!(matches!(reverse(&mesh, &ReverseOptions::default()), Err(DooError::NonFinite { vertex: 2, .. })));
}

#[test]
fn decomposition_is_bit_identical_for_any_thread_count() {
    use subdiv_doo::pyramid::{DecomposeOptions, decompose};
    // A torus with a hole cut out (a boundary), every fine vertex moved.
    let mut soup = shapes::torus(24, 16, CellKind::Mixed).unwrap();
    let faces: Vec<Vec<u32>> = soup.faces().skip(3).map(<[u32]>::to_vec).collect();
    soup = PolygonSoup::from_faces(std::mem::take(&mut soup.positions), faces);
    let mut fine = doo(&soup, FaceRule::DooSabin, 1);
    for (i, p) in fine.positions_mut().iter_mut().enumerate() {
        *p += 1e-3 * DVec3::new((i as f64).sin(), (2.0 * i as f64).cos(), (3.0 * i as f64).sin());
    }
    let run = |threads: usize, seeds: Vec<usize>| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let options = DecomposeOptions { seeds, ..DecomposeOptions::levels(FaceRule::DooSabin, 1) };
            let decomposition = decompose(&fine, &options).unwrap();
            let rebuilt = decomposition.pyramid.reconstruct(1, None).unwrap();
            (decomposition, rebuilt)
        })
    };
    for seeds in [vec![], vec![0]] {
        let (one, rebuilt_one) = run(1, seeds.clone());
        let (two, rebuilt_two) = run(2, seeds);
        assert_eq!(one, two);
        assert_eq!(rebuilt_one, rebuilt_two);
        assert!(max_distance(&rebuilt_one.positions, fine.positions()) < 1e-14 * diagonal(fine.positions()));
    }
}
