//! Properties of Doo-Sabin subdivision and its reversal (specification §4.5, §5.6).

use std::collections::BTreeMap;

use mesh_topo::shapes::{self, CellKind};
use mesh_topo::testing::arb_mesh;
use mesh_topo::{DVec3, HalfedgeMesh, PolygonSoup};
use proptest::prelude::*;
use subdiv_doo::pyramid::{DecomposeOptions, decompose};
use subdiv_doo::{DooOptions, DooPyramid, FaceKind, FaceRule, ReverseOptions, reverse, subdivide, subdivide_soup};

fn rule_strategy() -> impl Strategy<Value = FaceRule> {
    prop_oneof![
        Just(FaceRule::DooSabin),
        Just(FaceRule::Simple),
        (0.05..0.95f64).prop_map(|a| FaceRule::Centroid { a })
    ]
}

fn diagonal(points: &[DVec3]) -> f64 {
    let (lo, hi) = points.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    (hi - lo).length()
}

fn max_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (*p - *q).length()).fold(0.0, f64::max)
}

/// The mesh without isolated vertices (they have no image under Doo-Sabin).
fn used_only(soup: PolygonSoup) -> PolygonSoup {
    let mut map = vec![u32::MAX; soup.vertex_count()];
    let mut positions = Vec::new();
    for &v in &soup.indices {
        if map[v as usize] == u32::MAX {
            map[v as usize] = positions.len() as u32;
            positions.push(soup.positions[v as usize]);
        }
    }
    let faces: Vec<Vec<u32>> = soup.faces().map(|f| f.iter().map(|&v| map[v as usize]).collect()).collect();
    PolygonSoup::from_faces(positions, faces)
}

/// One "edge flip" of a polygon mesh: the edge shared by faces `f = (u, v, F..)` and
/// `g = (v, u, G..)` is replaced by the edge joining the first vertices of `G..` and `F..`.
fn flip_edge(soup: &PolygonSoup, face: usize, corner: usize) -> Option<PolygonSoup> {
    let f = soup.face(face);
    let (u, v) = (f[corner], f[(corner + 1) % f.len()]);
    let g_index = soup.faces().position(|g| (0..g.len()).any(|k| g[k] == v && g[(k + 1) % g.len()] == u))?;
    let g = soup.face(g_index);
    let k = (0..g.len()).find(|&k| g[k] == v)?;
    let rest_f: Vec<u32> = (2..f.len()).map(|i| f[(corner + i) % f.len()]).collect();
    let rest_g: Vec<u32> = (2..g.len()).map(|i| g[(k + i) % g.len()]).collect();
    // New faces: (G.., v, F_0) and (F.., u, G_0).
    let mut new_f = rest_g.clone();
    new_f.push(v);
    new_f.push(rest_f[0]);
    let mut new_g = rest_f.clone();
    new_g.push(u);
    new_g.push(rest_g[0]);
    if g_index == face {
        return None;
    }
    let mut faces: Vec<Vec<u32>> = soup.faces().map(<[u32]>::to_vec).collect();
    faces[face] = new_f;
    faces[g_index] = new_g;
    Some(PolygonSoup::from_faces(soup.positions.clone(), faces))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    /// Affine invariance: subdividing a transformed mesh = transforming the result.
    #[test]
    fn subdivision_commutes_with_affine_maps(
        soup in arb_mesh(),
        rule in rule_strategy(),
        m in prop::array::uniform9(-2.0..2.0f64),
        t in prop::array::uniform3(-5.0..5.0f64),
    ) {
        let soup = used_only(soup);
        let a = glam::DMat3::from_cols_array(&m);
        prop_assume!(a.determinant().abs() > 0.1);
        let map = |p: DVec3| a * p + DVec3::from_array(t);
        let options = DooOptions::new(rule, 2);
        let fine = subdivide_soup(&soup, &options).unwrap();
        let mut moved = soup.clone();
        moved.positions.iter_mut().for_each(|p| *p = map(*p));
        let fine_moved = subdivide_soup(&moved, &options).unwrap();
        let mapped: Vec<DVec3> = fine.positions().iter().map(|&p| map(p)).collect();
        let scale = diagonal(&mapped).max(1.0);
        prop_assert!(max_distance(&mapped, fine_moved.positions()) < 1e-12 * scale);
    }

    /// Counts of §4.1, valence 4 of every interior fine vertex, valid oriented output.
    #[test]
    fn counts_and_valence(soup in arb_mesh()) {
        let soup = used_only(soup);
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        let interior_edges = mesh.edges().filter(|&e| !mesh.is_boundary_edge(e)).count();
        let interior_vertices = mesh.vertices().filter(|&v| !mesh.is_boundary_vertex(v)).count();
        let fine = subdivide(&mesh, &DooOptions::default()).unwrap();
        prop_assert_eq!(fine.vertex_count(), soup.indices.len());
        prop_assert_eq!(fine.kind_counts(), [soup.face_count(), interior_edges, interior_vertices]);
        let fine_mesh = fine.to_mesh().unwrap();
        for v in fine_mesh.vertices() {
            if !fine_mesh.is_boundary_vertex(v) {
                prop_assert_eq!(fine_mesh.valence(v), 4);
            }
        }
        for f in 0..fine.face_count() {
            if fine.face_kind(f) == FaceKind::Edge {
                prop_assert_eq!(fine.face(f).len(), 4);
            }
        }
        prop_assert_eq!(fine_mesh.topology_stats().genus, mesh.topology_stats().genus);
    }

    /// reverse(doo(M)) = M with zero details; perturbed: exact reconstruction, any reading.
    #[test]
    fn reverse_round_trips(soup in arb_mesh(), rule in rule_strategy(), seed in any::<u64>()) {
        let soup = used_only(soup);
        let fine = subdivide_soup(&soup, &DooOptions::new(rule, 1)).unwrap().to_mesh().unwrap();
        let scale = diagonal(fine.positions()).max(1e-9);
        let reversal = reverse(&fine, &ReverseOptions::auto(rule)).unwrap();
        prop_assert!(reversal.details().iter().all(|d| d.length() <= 1e-12 * scale));
        prop_assert_eq!(reversal.coarse().face_count(), soup.face_count());
        prop_assert_eq!(reversal.coarse_positions().len() + reversal.details().len(), fine.vertex_count());

        let mut moved = fine.clone();
        let mut state = seed | 1;
        for p in moved.positions_mut() {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let r = (state >> 11) as f64 / (1u64 << 53) as f64;
            *p += 0.1 * scale * DVec3::new(r - 0.5, (7.0 * r).sin(), (13.0 * r).cos());
        }
        let reversal = reverse(&moved, &ReverseOptions::auto(rule)).unwrap();
        let rebuilt = reversal.reconstruct();
        prop_assert_eq!(&rebuilt.indices, &moved.to_soup().indices);
        prop_assert!(max_distance(&rebuilt.positions, moved.positions()) <= 1e-12 * scale);
    }

    /// A Doo-Sabin mesh in any order (vertices renumbered, faces reordered, corners
    /// rotated) reverses in automatic mode to the coarse mesh with zero details, and
    /// rebuilds in its own order. Open meshes whose lowest face is an F_V face once made
    /// the automatic mode give up (fuzz finding).
    #[test]
    fn reverse_in_any_order(soup in arb_mesh(), rule in rule_strategy(), seed in any::<u64>()) {
        let soup = used_only(soup);
        let fine = subdivide_soup(&soup, &DooOptions::new(rule, 1)).unwrap().into_soup();
        let mut state = seed | 1;
        let shuffled = mesh_topo::testing::shuffle(&fine, |k| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % (k as u64 + 1)) as usize
        });
        let mesh = HalfedgeMesh::from_soup(&shuffled).unwrap();
        let scale = diagonal(mesh.positions()).max(1e-9);
        let reversal = reverse(&mesh, &ReverseOptions::auto(rule)).unwrap();
        prop_assert_eq!(reversal.coarse().face_count(), soup.face_count());
        prop_assert!(reversal.details().iter().all(|d| d.length() <= 1e-12 * scale));
        let rebuilt = reversal.reconstruct();
        prop_assert_eq!((&rebuilt.offsets, &rebuilt.indices), (&shuffled.offsets, &shuffled.indices));
        prop_assert!(max_distance(&rebuilt.positions, &shuffled.positions) <= 1e-12 * scale);
    }

    /// The automatic choice keeps the reading of smallest total detail energy: every valid
    /// reading it tried, reversed again with its seed given, has at least the winner's
    /// energy, and its reported sum is that total (or, if the sum stopped early, at most it).
    #[test]
    fn automatic_choice_has_the_smallest_detail_energy(
        soup in arb_mesh(),
        rule in rule_strategy(),
        seed in any::<u64>(),
        amount in 0.0f64..0.2,
    ) {
        let soup = used_only(soup);
        let mut fine = subdivide_soup(&soup, &DooOptions::new(rule, 1)).unwrap().to_mesh().unwrap();
        let scale = diagonal(fine.positions()).max(1e-9);
        let mut state = seed | 1;
        for p in fine.positions_mut() {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let r = (state >> 11) as f64 / (1u64 << 53) as f64;
            *p += amount * scale * DVec3::new(r - 0.5, (7.0 * r).sin(), (13.0 * r).cos());
        }
        let automatic = reverse(&fine, &ReverseOptions::auto(rule)).unwrap();
        let mut compared = 0;
        for choice in automatic.choices() {
            for trial in &choice.trials {
                let Ok(sum) = trial.outcome else { continue };
                // A reading the full check rejects has no total to compare with.
                let Ok(given) = reverse(&fine, &ReverseOptions::with_seed(rule, trial.seed_face)) else { continue };
                let total = given.choices()[choice.component].detail_energy;
                let slack = 1e-9 * total.max(1e-30);
                prop_assert!(choice.detail_energy <= total + slack, "{choice:?} against {total}");
                if trial.stopped_early {
                    prop_assert!(sum <= total + slack && sum >= choice.detail_energy - slack, "{trial:?} {total}");
                } else {
                    prop_assert!((sum - total).abs() <= slack, "{trial:?} {total}");
                }
                compared += 1;
            }
        }
        prop_assert!(compared >= automatic.choices().len());
    }

    /// Random damage (a face removed, an edge flipped) and moved vertices: reverse never
    /// panics; it fails, or finds another valid reading that reconstructs exactly.
    #[test]
    fn damaged_meshes_never_panic(
        soup in arb_mesh(),
        which in 0usize..1000,
        corner in 0usize..8,
        remove in any::<bool>(),
        jitter in 0.0..0.3f64,
    ) {
        let soup = used_only(soup);
        let mut fine = subdivide_soup(&soup, &DooOptions::default()).unwrap().into_soup();
        let f = which % fine.face_count();
        for (i, p) in fine.positions.iter_mut().enumerate() {
            *p += jitter * DVec3::new((i as f64).sin(), (2.0 * i as f64).cos(), 0.3);
        }
        let damaged = if remove {
            let faces: Vec<Vec<u32>> =
                fine.faces().enumerate().filter(|&(i, _)| i != f).map(|(_, face)| face.to_vec()).collect();
            used_only(PolygonSoup::from_faces(fine.positions.clone(), faces))
        } else {
            match flip_edge(&fine, f, corner % fine.face(f).len()) {
                Some(s) => s,
                None => fine.clone(),
            }
        };
        let Ok(mesh) = HalfedgeMesh::from_soup(&damaged) else { return Ok(()) };
        if let Ok(reversal) = reverse(&mesh, &ReverseOptions::default()) {
            let rebuilt = reversal.reconstruct();
            prop_assert_eq!(&rebuilt.indices, &damaged.indices);
            let scale = diagonal(&damaged.positions).max(1e-9);
            prop_assert!(max_distance(&rebuilt.positions, &damaged.positions) <= 1e-12 * scale);
        }
    }

    /// A corrupted pyramid file is an error or a pyramid, never a panic.
    #[test]
    fn corrupted_pyramids_never_panic(position in 12usize..4000, value in any::<u8>(), cut in any::<bool>()) {
        let fine = subdivide_soup(&shapes::cube(), &DooOptions::new(FaceRule::DooSabin, 2)).unwrap().to_mesh().unwrap();
        let mut bytes = decompose(&fine, &DecomposeOptions::max(FaceRule::DooSabin)).unwrap().pyramid.to_bytes().unwrap();
        let position = position % bytes.len();
        if cut {
            bytes.truncate(position);
        } else {
            bytes[position] = value;
        }
        if let Ok(pyramid) = DooPyramid::from_bytes(&bytes) {
            for level in 0..=pyramid.level_count() {
                let _ = pyramid.reconstruct(level, Some(0.5));
            }
        }
    }
}

#[test]
fn flipping_an_edge_breaks_the_structure() {
    let fine = subdivide_soup(&shapes::cube(), &DooOptions::default()).unwrap().into_soup();
    // Flip the first edge of F_F face 0 (shared with an F_E quad).
    let flipped = flip_edge(&fine, 0, 0).unwrap();
    let mesh = HalfedgeMesh::from_soup(&flipped).unwrap();
    let error = reverse(&mesh, &ReverseOptions::default()).unwrap_err();
    assert!(matches!(error, subdiv_doo::DooError::NotDooConnectivity { .. }), "{error}");
    // Removing a face: an F_V triangle (a hole where a coarse vertex was).
    let faces: Vec<Vec<u32>> = fine.faces().take(25).map(<[u32]>::to_vec).collect();
    let holed = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(fine.positions.clone(), faces)).unwrap();
    match reverse(&holed, &ReverseOptions::with_seed(FaceRule::DooSabin, 0)) {
        Err(subdiv_doo::DooError::NotDooConnectivity { face, .. }) => assert!(face < 25),
        Ok(r) => {
            // The open cube minus one F_V face is still Doo connectivity? Then the
            // reconstruction must be exact.
            assert!(max_distance(&r.reconstruct().positions, holed.positions()) < 1e-14);
        }
        Err(e) => panic!("{e}"),
    }
}

/// Regular quad grid with Doo-Sabin weights = tensor-product Chaikin (quadratic B-spline
/// refinement) of the grid function, at levels 1 and 2.
#[test]
fn regular_grid_is_tensor_chaikin() {
    let (w, h) = (5usize, 4usize);
    let mut soup = shapes::grid(w as u32, h as u32, CellKind::Quads).unwrap();
    for (k, p) in soup.positions.iter_mut().enumerate() {
        p.z = ((k * 7919) % 101) as f64 / 17.0 - 3.0;
    }
    // The grid function P[i][j] (x = i, y = j).
    let mut grid: Vec<Vec<DVec3>> =
        (0..=w).map(|i| (0..=h).map(|j| soup.positions[j * (w + 1) + i]).collect()).collect();
    let chaikin = |line: &[DVec3]| -> Vec<DVec3> {
        line.windows(2).flat_map(|s| [0.75 * s[0] + 0.25 * s[1], 0.25 * s[0] + 0.75 * s[1]]).collect()
    };
    for level in 1..=2u32 {
        // Chaikin along i, then along j.
        let rows: Vec<Vec<DVec3>> =
            (0..grid[0].len()).map(|j| chaikin(&grid.iter().map(|col| col[j]).collect::<Vec<_>>())).collect();
        let cols = rows[0].len();
        grid = (0..cols).map(|i| chaikin(&rows.iter().map(|row| row[i]).collect::<Vec<_>>())).collect();
        let expected: BTreeMap<(i64, i64), f64> =
            grid.iter().flatten().map(|p| (((p.x * 64.0).round() as i64, (p.y * 64.0).round() as i64), p.z)).collect();
        let fine = subdivide_soup(&soup, &DooOptions::new(FaceRule::DooSabin, level)).unwrap();
        assert_eq!(fine.vertex_count(), expected.len());
        for p in fine.positions() {
            let z = expected[&((p.x * 64.0).round() as i64, (p.y * 64.0).round() as i64)];
            assert!((p.z - z).abs() < 1e-14, "level {level}: {p} vs {z}");
        }
    }
}

/// The paper's figure: subdivide three times, move one vertex, reverse three times,
/// reconstruct exactly (every intermediate level too).
#[test]
fn three_levels_one_moved_vertex() {
    for (rule, coarse) in [
        (FaceRule::DooSabin, shapes::torus(4, 3, CellKind::Mixed).unwrap()),
        (FaceRule::Simple, shapes::icosahedron()),
        (FaceRule::CENTROID_HALF, shapes::cube()),
    ] {
        let levels: Vec<HalfedgeMesh> =
            (1..=3).map(|l| subdivide_soup(&coarse, &DooOptions::new(rule, l)).unwrap().to_mesh().unwrap()).collect();
        let mut fine = levels[2].clone();
        fine.positions_mut()[123].x += 0.3;
        let decomposition = decompose(&fine, &DecomposeOptions::levels(rule, 3)).unwrap();
        let pyramid = decomposition.pyramid;
        assert_eq!(pyramid.base.face_count(), coarse.face_count());
        assert_eq!(pyramid.base.vertex_count() + pyramid.detail_count(), fine.vertex_count());
        let rebuilt = pyramid.reconstruct(3, None).unwrap();
        assert_eq!(rebuilt.indices, fine.to_soup().indices);
        assert!(max_distance(&rebuilt.positions, fine.positions()) < 1e-13, "{rule:?}");
        // The moved vertex leaves nonzero details only near it: most details are zero.
        let nonzero = pyramid.levels.iter().flat_map(|l| &l.details).filter(|d| d.length() > 1e-12).count();
        assert!(nonzero > 0 && nonzero < pyramid.detail_count() / 4, "{nonzero} of {}", pyramid.detail_count());
        // Intermediate levels have the connectivity of the true intermediate meshes.
        for (k, level) in levels.iter().enumerate().take(2) {
            let soup = pyramid.reconstruct(k + 1, None).unwrap();
            assert_eq!(soup.offsets, level.to_soup().offsets);
        }
        // Bytes round trip.
        let again = DooPyramid::from_bytes(&pyramid.to_bytes().unwrap()).unwrap();
        assert_eq!(again, pyramid);
    }
}

#[test]
fn max_depth_stops_at_the_original_and_compression_degrades_gracefully() {
    let coarse = shapes::torus(5, 3, CellKind::Triangles).unwrap();
    let mut fine = subdivide_soup(&coarse, &DooOptions::new(FaceRule::DooSabin, 3)).unwrap().to_mesh().unwrap();
    let n = fine.vertex_count();
    for (i, p) in fine.positions_mut().iter_mut().enumerate() {
        *p += 1e-3 * DVec3::new((i as f64 * 0.37).sin(), 0.0, (i as f64 * 0.11).cos());
    }
    let decomposition = decompose(&fine, &DecomposeOptions::max(FaceRule::DooSabin)).unwrap();
    let pyramid = decomposition.pyramid;
    assert_eq!(pyramid.level_count(), 3, "{:?}", decomposition.stopped);
    assert_eq!(pyramid.base.face_count(), coarse.face_count());
    assert_eq!(pyramid.base.vertex_count() + pyramid.detail_count(), n);
    let table = pyramid.rate_distortion(&[1.0, 0.5, 0.1, 0.0]).unwrap();
    assert!(table[0].max_error < 1e-14);
    for pair in table.windows(2) {
        assert!(pair[1].rms_error >= pair[0].rms_error - 1e-15, "{table:?}");
    }
    assert!(table[3].rms_error > 1e-5);
    assert!(pyramid.reconstruct(4, None).is_err());
    assert!(pyramid.reconstruct(3, Some(1.5)).is_err());
}
