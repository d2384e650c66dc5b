//! The Chaikin boundary rule: the boundary of the refined mesh is the Chaikin
//! refinement of the coarse boundary polygon (an independent closed-polygon Chaikin
//! below), and reverse Doo-Sabin undoes the rule exactly, in any order.

use std::collections::HashMap;

use mesh_topo::shapes::{self, CellKind};
use mesh_topo::testing::{arb_mesh, scramble};
use mesh_topo::{DVec3, HalfedgeMesh, PolygonSoup};
use proptest::prelude::*;
use subdiv_doo::{BoundaryRule, DooError, DooOptions, FaceKind, FaceRule, ReverseOptions, reverse, subdivide};

fn chaikin_options(rule: FaceRule, levels: u32) -> DooOptions {
    DooOptions::new(rule, levels).with_boundary(BoundaryRule::Chaikin)
}

fn chaikin_reverse(rule: FaceRule) -> ReverseOptions {
    ReverseOptions::auto(rule).with_boundary(BoundaryRule::Chaikin)
}

/// The boundary loops of a soup, each as its positions in the order of its directed
/// boundary edges (each edge whose reverse no face has).
fn boundary_loops(soup: &PolygonSoup) -> Vec<Vec<DVec3>> {
    let mut directed = std::collections::HashSet::new();
    for face in soup.faces() {
        for i in 0..face.len() {
            directed.insert((face[i], face[(i + 1) % face.len()]));
        }
    }
    let mut next: HashMap<u32, u32> = HashMap::new();
    for &(u, v) in &directed {
        if !directed.contains(&(v, u)) {
            assert!(next.insert(u, v).is_none(), "vertex {u} starts two boundary edges");
        }
    }
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut seen = std::collections::HashSet::new();
    let mut loops = Vec::new();
    for start in starts {
        if !seen.insert(start) {
            continue;
        }
        let mut polygon = vec![soup.positions[start as usize]];
        let mut v = next[&start];
        while v != start {
            seen.insert(v);
            polygon.push(soup.positions[v as usize]);
            v = next[&v];
        }
        loops.push(polygon);
    }
    loops
}

/// Closed-polygon Chaikin corner cutting.
fn chaikin(polygon: &[DVec3]) -> Vec<DVec3> {
    let n = polygon.len();
    (0..n)
        .flat_map(|i| {
            let (p, q) = (polygon[i], polygon[(i + 1) % n]);
            [0.75 * p + 0.25 * q, 0.25 * p + 0.75 * q]
        })
        .collect()
}

/// True if `a` is `b` up to a cyclic shift, to `tolerance`.
fn same_cycle(a: &[DVec3], b: &[DVec3], tolerance: f64) -> bool {
    a.len() == b.len()
        && (0..b.len()).any(|shift| (0..a.len()).all(|i| (a[i] - b[(i + shift) % b.len()]).length() <= tolerance))
}

fn max_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(p, q)| (*p - *q).length()).fold(0.0, f64::max)
}

/// A wavy open grid (not flat, so that nothing is exact by accident).
fn wavy_grid(width: u32, height: u32, kind: CellKind) -> PolygonSoup {
    let mut soup = shapes::grid(width, height, kind).unwrap();
    for p in &mut soup.positions {
        p.z = 0.3 * (1.7 * p.x).sin() * (1.3 * p.y + 0.4).cos();
    }
    soup
}

/// A torus with two faces removed: genus 1 and two boundary loops.
fn holed_torus() -> PolygonSoup {
    let torus = shapes::torus(6, 5, CellKind::Mixed).unwrap();
    let faces: Vec<Vec<u32>> =
        torus.faces().enumerate().filter(|(f, _)| *f != 3 && *f != 17).map(|(_, face)| face.to_vec()).collect();
    PolygonSoup::from_faces(torus.positions.clone(), faces)
}

#[test]
fn the_boundary_of_each_level_is_the_chaikin_refinement_of_the_coarse_boundary() {
    for (soup, loops) in
        [(wavy_grid(3, 2, CellKind::Quads), 1), (wavy_grid(2, 3, CellKind::Mixed), 1), (holed_torus(), 2)]
    {
        let coarse_loops = boundary_loops(&soup);
        assert_eq!(coarse_loops.len(), loops);
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        for levels in 1..=3 {
            for rule in [FaceRule::DooSabin, FaceRule::Simple, FaceRule::CENTROID_HALF] {
                let fine = subdivide(&mesh, &chaikin_options(rule, levels)).unwrap();
                let fine_soup = fine.to_soup();
                HalfedgeMesh::from_soup(&fine_soup).unwrap().validate().unwrap();
                let fine_loops = boundary_loops(&fine_soup);
                assert_eq!(fine_loops.len(), loops);
                for polygon in &coarse_loops {
                    let mut expected = polygon.clone();
                    for _ in 0..levels {
                        expected = chaikin(&expected);
                    }
                    assert!(
                        fine_loops.iter().any(|found| same_cycle(found, &expected, 1e-13)),
                        "level {levels} {rule:?}: a boundary loop is not the Chaikin refinement"
                    );
                }
            }
        }
    }
}

#[test]
fn counts_origins_and_the_shrink_step_as_a_prefix() {
    let soup = wavy_grid(3, 2, CellKind::Quads);
    let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
    let shrink = subdivide(&mesh, &DooOptions::new(FaceRule::DooSabin, 1)).unwrap();
    let fine = subdivide(&mesh, &chaikin_options(FaceRule::DooSabin, 1)).unwrap();
    // 6 quads, 17 edges of which 10 on the boundary, 12 vertices of which 10 on it.
    assert_eq!(shrink.kind_counts(), [6, 7, 2]);
    assert_eq!(fine.kind_counts(), [6, 7 + 10, 2 + 10]);
    assert_eq!(fine.vertex_count(), 24 + 2 * 10);
    assert_eq!(&fine.positions()[..24], shrink.positions());
    for f in 0..shrink.face_count() {
        assert_eq!(fine.face(f), shrink.face(f));
        assert_eq!(fine.face_origin(f), shrink.face_origin(f));
    }
    // The ring: boundary quads, then boundary vertex faces (a corner vertex of the grid
    // has one face: a triangle; the others two: quads).
    let ring: Vec<FaceKind> = (shrink.face_count()..fine.face_count()).map(|f| fine.face_kind(f)).collect();
    assert_eq!(ring[..10], [FaceKind::Edge; 10]);
    assert_eq!(ring[10..], [FaceKind::Vertex; 10]);
    let sizes: Vec<usize> = (shrink.face_count() + 10..fine.face_count()).map(|f| fine.face(f).len()).collect();
    assert_eq!(sizes.iter().filter(|&&s| s == 3).count(), 4);
    assert_eq!(sizes.iter().filter(|&&s| s == 4).count(), 6);
    // On a closed mesh both rules are the same.
    let cube = HalfedgeMesh::from_soup(&shapes::cube()).unwrap();
    assert_eq!(
        subdivide(&cube, &chaikin_options(FaceRule::DooSabin, 2)).unwrap(),
        subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 2)).unwrap()
    );
}

#[test]
fn reverse_of_a_chaikin_step_gives_the_coarse_mesh_with_zero_details() {
    for soup in [wavy_grid(3, 2, CellKind::Quads), wavy_grid(4, 3, CellKind::Triangles), holed_torus()] {
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        for rule in [FaceRule::DooSabin, FaceRule::Simple, FaceRule::CENTROID_HALF] {
            let fine = subdivide(&mesh, &chaikin_options(rule, 1)).unwrap().to_mesh().unwrap();
            let reversal = reverse(&fine, &chaikin_reverse(rule)).unwrap();
            assert_eq!(reversal.boundary(), BoundaryRule::Chaikin);
            // The fine vertices are in canonical order; the coarse vertices are numbered
            // in order of appearance, so the boundary vertex faces may follow another
            // vertex order.
            assert!(reversal.fine_order().vertices.is_empty() && reversal.fine_order().rotations.is_empty());
            let coarse = reversal.coarse();
            assert_eq!(coarse.offsets, soup.offsets);
            let corner_positions =
                |s: &PolygonSoup| -> Vec<DVec3> { s.indices.iter().map(|&v| s.positions[v as usize]).collect() };
            assert!(max_distance(&corner_positions(&coarse), &corner_positions(&soup)) < 1e-14, "{rule:?}");
            assert_eq!(coarse.vertex_count(), soup.vertex_count());
            assert!(reversal.details().iter().all(|d| d.length() < 1e-14), "{rule:?}");
            assert_eq!(reversal.coarse_positions().len() + reversal.details().len(), fine.vertex_count());
        }
    }
}

#[test]
fn three_levels_one_vertex_moved_reverse_three_times_and_rebuild_exactly() {
    // The paper's figure, with the Chaikin boundary: subdivide three times, move one
    // vertex (on the boundary), reverse three times, rebuild each level exactly.
    let soup = wavy_grid(3, 3, CellKind::Quads);
    let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
    let mut fine = subdivide(&mesh, &chaikin_options(FaceRule::DooSabin, 3)).unwrap().to_mesh().unwrap();
    let last = fine.vertex_count() - 1; // a Chaikin point of the last level
    fine.positions_mut()[last].z += 0.2;
    let mut levels = Vec::new();
    let mut current = fine.clone();
    for _ in 0..3 {
        let reversal = reverse(&current, &chaikin_reverse(FaceRule::DooSabin)).unwrap();
        let coarse = HalfedgeMesh::from_soup(&reversal.coarse()).unwrap();
        levels.push((current, reversal));
        current = coarse;
    }
    assert_eq!(current.face_count(), soup.face_count());
    for (level, reversal) in &levels {
        let rebuilt = reversal.reconstruct();
        assert_eq!(rebuilt.indices, level.to_soup().indices);
        assert!(max_distance(&rebuilt.positions, level.positions()) < 1e-14);
    }
    // The moved boundary point shows as non-zero details at the finest level only.
    assert!(levels[0].1.details().iter().any(|d| d.length() > 1e-3));
}

#[test]
fn any_order_and_moved_vertices_reconstruct_exactly() {
    let soup = holed_torus();
    let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
    let fine = subdivide(&mesh, &chaikin_options(FaceRule::DooSabin, 1)).unwrap().to_soup();
    for seed in 1..6 {
        let scrambled = HalfedgeMesh::from_soup(&scramble(fine.clone(), seed, 0.01)).unwrap();
        let reversal = reverse(&scrambled, &chaikin_reverse(FaceRule::DooSabin)).unwrap();
        assert!(!reversal.fine_order().is_identity());
        let rebuilt = reversal.reconstruct();
        assert_eq!(rebuilt.offsets, scrambled.to_soup().offsets);
        assert_eq!(rebuilt.indices, scrambled.to_soup().indices);
        assert!(max_distance(&rebuilt.positions, scrambled.positions()) < 1e-13);
        assert_eq!(reversal.coarse().face_count(), soup.face_count());
    }
}

#[test]
fn broken_rings_and_seeds_are_errors() {
    let soup = wavy_grid(3, 2, CellKind::Quads);
    let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
    let fine = subdivide(&mesh, &chaikin_options(FaceRule::DooSabin, 1)).unwrap();
    let fine_soup = fine.to_soup();
    // Each ring face removed in turn (isolated Chaikin points dropped, so that the mesh
    // is still valid): an error, never a panic.
    let ring_start = 6 + 7 + 2;
    for removed in ring_start..fine.face_count() {
        let faces: Vec<Vec<u32>> =
            fine_soup.faces().enumerate().filter(|(f, _)| *f != removed).map(|(_, face)| face.to_vec()).collect();
        let mut used = vec![false; fine_soup.vertex_count()];
        for face in &faces {
            for &v in face {
                used[v as usize] = true;
            }
        }
        let mut renumber = vec![u32::MAX; used.len()];
        let mut positions = Vec::new();
        for (v, &u) in used.iter().enumerate() {
            if u {
                renumber[v] = positions.len() as u32;
                positions.push(fine_soup.positions[v]);
            }
        }
        let faces: Vec<Vec<u32>> = faces.iter().map(|f| f.iter().map(|&v| renumber[v as usize]).collect()).collect();
        let Ok(broken) = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(positions, faces)) else { continue };
        let result = reverse(&broken, &chaikin_reverse(FaceRule::DooSabin));
        assert!(matches!(result, Err(DooError::NotDooConnectivity { .. })), "face {removed} removed: {result:?}");
    }
    // A seed face on the ring.
    let mesh = fine.to_mesh().unwrap();
    let seeded = ReverseOptions::with_seed(FaceRule::DooSabin, ring_start).with_boundary(BoundaryRule::Chaikin);
    assert!(matches!(reverse(&mesh, &seeded), Err(DooError::NotDooConnectivity { face, .. }) if face == ring_start));
    // A Shrink step read as a Chaikin step: its boundary vertices are F_F corners.
    let shrink =
        subdivide(&HalfedgeMesh::from_soup(&soup).unwrap(), &DooOptions::default()).unwrap().to_mesh().unwrap();
    assert!(reverse(&shrink, &chaikin_reverse(FaceRule::DooSabin)).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Any mesh (open or closed, scrambled, jittered): the Chaikin step is a valid mesh,
    /// reverses to the input's faces with zero details, and after every fine vertex is
    /// moved, rebuilds exactly.
    #[test]
    fn chaikin_steps_reverse_and_rebuild(soup in arb_mesh(), seed in 1u64..1000) {
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        let fine = match subdivide(&mesh, &chaikin_options(FaceRule::DooSabin, 1)) {
            Ok(fine) => fine,
            Err(DooError::ValenceTwoVertex { .. }) => return Ok(()),
            Err(other) => panic!("{other}"),
        };
        let fine = fine.to_mesh().unwrap();
        let reversal = reverse(&fine, &chaikin_reverse(FaceRule::DooSabin)).unwrap();
        let size = soup.positions.iter().map(|p| p.length()).fold(1.0, f64::max);
        prop_assert!(reversal.details().iter().all(|d| d.length() < 1e-12 * size));
        prop_assert_eq!(reversal.coarse().face_count(), soup.face_count());
        let moved = HalfedgeMesh::from_soup(&scramble(fine.to_soup(), seed, 0.05)).unwrap();
        let reversal = reverse(&moved, &chaikin_reverse(FaceRule::DooSabin)).unwrap();
        prop_assert_eq!(reversal.coarse_positions().len() + reversal.details().len(), moved.vertex_count());
        let rebuilt = reversal.reconstruct();
        prop_assert_eq!(&rebuilt.indices, &moved.to_soup().indices);
        prop_assert!(max_distance(&rebuilt.positions, moved.positions()) < 1e-12 * size);
    }

    /// Small topology damage (a face removed, or turned over) never panics; whatever
    /// still reverses rebuilds exactly.
    #[test]
    fn damaged_chaikin_steps_are_errors_or_exact(soup in arb_mesh(), pick in any::<u32>(), turn in any::<bool>()) {
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        let Ok(fine) = subdivide(&mesh, &chaikin_options(FaceRule::Simple, 1)) else { return Ok(()) };
        let fine = fine.to_soup();
        let victim = pick as usize % fine.face_count();
        let faces: Vec<Vec<u32>> = fine
            .faces()
            .enumerate()
            .filter(|&(f, _)| turn || f != victim)
            .map(|(f, face)| {
                let mut face = face.to_vec();
                if turn && f == victim {
                    face.reverse();
                }
                face
            })
            .collect();
        let Ok(damaged) = HalfedgeMesh::from_soup(&PolygonSoup::from_faces(fine.positions.clone(), faces)) else {
            return Ok(());
        };
        if let Ok(reversal) = reverse(&damaged, &chaikin_reverse(FaceRule::Simple)) {
            let rebuilt = reversal.reconstruct();
            prop_assert_eq!(&rebuilt.indices, &damaged.to_soup().indices);
            let size = fine.positions.iter().map(|p| p.length()).fold(1.0, f64::max);
            prop_assert!(max_distance(&rebuilt.positions, damaged.positions()) < 1e-12 * size);
        }
    }
}

#[test]
fn pyramids_decompose_rebuild_compress_and_round_trip_through_bytes() {
    use subdiv_doo::pyramid::{DecomposeOptions, DooPyramid, decompose};
    let soup = wavy_grid(3, 2, CellKind::Mixed);
    let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
    let mut fine = subdivide(&mesh, &chaikin_options(FaceRule::DooSabin, 3)).unwrap().to_mesh().unwrap();
    for (v, p) in fine.positions_mut().iter_mut().enumerate() {
        p.z += 0.01 * ((v * 7919 % 101) as f64 / 101.0 - 0.5);
    }
    let options = DecomposeOptions::max(FaceRule::DooSabin).with_boundary(BoundaryRule::Chaikin);
    let decomposition = decompose(&fine, &options).unwrap();
    let pyramid = decomposition.pyramid;
    assert_eq!(pyramid.boundary, BoundaryRule::Chaikin);
    assert_eq!(pyramid.level_count(), 3, "{:?}", decomposition.stopped);
    assert_eq!(pyramid.base.face_count(), soup.face_count());
    assert_eq!(pyramid.base.vertex_count() + pyramid.detail_count(), fine.vertex_count());
    let rebuilt = pyramid.reconstruct(3, None).unwrap();
    assert_eq!(rebuilt.indices, fine.to_soup().indices);
    assert!(max_distance(&rebuilt.positions, fine.positions()) < 1e-13);
    // Without details: the Chaikin refinement of the base, whose boundary is the Chaikin
    // refinement of the base's boundary polygon.
    let smooth = pyramid.reconstruct(3, Some(0.0)).unwrap();
    let base_mesh = HalfedgeMesh::from_soup(&pyramid.base).unwrap();
    let refined = subdivide(&base_mesh, &chaikin_options(FaceRule::DooSabin, 3)).unwrap().to_soup();
    // (The same points; the pyramid numbers them as the input was numbered.)
    let sorted = |points: &[DVec3]| {
        let mut points = points.to_vec();
        points.sort_by(|a, b| a.to_array().partial_cmp(&b.to_array()).unwrap());
        points
    };
    assert!(max_distance(&sorted(&smooth.positions), &sorted(&refined.positions)) < 1e-13);
    let mut expected = boundary_loops(&pyramid.base).remove(0);
    for _ in 0..3 {
        expected = chaikin(&expected);
    }
    assert!(same_cycle(&boundary_loops(&smooth).remove(0), &expected, 1e-13));
    // Files: the boundary rule is stored.
    let bytes = pyramid.to_bytes().unwrap();
    let decoded = DooPyramid::from_bytes(&bytes).unwrap();
    assert_eq!(decoded, pyramid);
    // A pyramid read with the other rule is refused, not misread.
    let mut wrong = pyramid.clone();
    wrong.boundary = BoundaryRule::Shrink;
    assert!(matches!(wrong.reconstruct(3, None), Err(DooError::InvalidPyramid(_))));
    assert!(DooPyramid::from_bytes(&wrong.to_bytes().unwrap()).is_err());
    // Exactly three levels asked for; a fourth does not exist.
    let three = DecomposeOptions::levels(FaceRule::DooSabin, 3).with_boundary(BoundaryRule::Chaikin);
    assert_eq!(decompose(&fine, &three).unwrap().pyramid, pyramid);
    let four = DecomposeOptions::levels(FaceRule::DooSabin, 4).with_boundary(BoundaryRule::Chaikin);
    assert!(decompose(&fine, &four).is_err());
}

#[test]
fn single_faces_and_two_components_reverse_and_stop_cleanly() {
    use subdiv_doo::pyramid::{DecomposeOptions, decompose};
    let triangle = PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]]);
    let quad =
        PolygonSoup::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.2), DVec3::Y], [[0u32, 1, 2, 3]]);
    // A closed cube and an open grid side by side: one seed-free reading per component.
    let mut two = shapes::cube();
    let grid = wavy_grid(2, 2, CellKind::Triangles);
    let shift = two.vertex_count() as u32;
    let mut faces: Vec<Vec<u32>> = two.faces().map(<[u32]>::to_vec).collect();
    faces.extend(grid.faces().map(|f| f.iter().map(|&v| v + shift).collect::<Vec<u32>>()));
    two.positions.extend(grid.positions.iter().map(|&p| p + DVec3::new(3.0, 0.0, 0.0)));
    let two = PolygonSoup::from_faces(two.positions, faces);
    for soup in [triangle, quad, two] {
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        let fine = subdivide(&mesh, &chaikin_options(FaceRule::DooSabin, 2)).unwrap().to_mesh().unwrap();
        let options = DecomposeOptions::max(FaceRule::DooSabin).with_boundary(BoundaryRule::Chaikin);
        let decomposition = decompose(&fine, &options).unwrap();
        let pyramid = decomposition.pyramid;
        // Two levels, then the base cannot be reversed (every face of a lone polygon
        // touches the boundary; the cube is not a Doo-Sabin step).
        assert_eq!(pyramid.level_count(), 2, "{:?}", decomposition.stopped);
        assert_eq!(pyramid.base.face_count(), soup.face_count());
        assert!(pyramid.levels.iter().all(|l| l.details.iter().all(|d| d.length() < 1e-13)));
        let rebuilt = pyramid.reconstruct(2, None).unwrap();
        assert_eq!(rebuilt.indices, fine.to_soup().indices);
        assert!(max_distance(&rebuilt.positions, fine.positions()) < 1e-13);
    }
}
