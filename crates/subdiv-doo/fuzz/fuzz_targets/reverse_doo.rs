//! Reverse Doo-Sabin and decompose on arbitrary valid polygon meshes.
//!
//! Inputs are built structurally from the fuzz bytes: a procedural base shape (closed or
//! open, triangles, quads or mixed) or a raw polygon soup, optionally refined one or two
//! Doo-Sabin steps under any of the three face rules and either boundary rule (read back
//! with the same boundary rule), with some vertices moved (so that
//! many inputs do have Doo-Sabin connectivity without being Doo-Sabin surfaces), then
//! renumbered, and optionally damaged (a face removed, a face turned over, or one corner
//! of a face sent to another vertex). Whatever comes out, `reverse` and `decompose` must
//! not panic, with or without a seed face (in range or not); a refined, undamaged mesh
//! must reverse; whenever reversal succeeds, coarse vertices plus details are exactly as
//! many as the fine vertices and reconstruction gives the input back. For every input,
//! `decompose_soup` (which reads a closed canonical soup without building its mesh) must
//! give exactly what building the mesh and decomposing it gives, result or error. The
//! meshes are scaled by 1, 2^-600, 2^600 or 2^1000 last (reversed at unit scale).

#![no_main]

use arbitrary::{Arbitrary, Unstructured};
use glam::DVec3;
use libfuzzer_sys::fuzz_target;
use mesh_topo::shapes::{self, CellKind};
use mesh_topo::{HalfedgeMesh, PolygonSoup};
use subdiv_doo::pyramid::{DecomposeOptions, Depth, DooPyramid, decompose, decompose_soup};
use subdiv_doo::{BoundaryRule, DooError, DooOptions, FaceRule, ReverseOptions, reverse, subdivide_soup};

fn coordinate(u: &mut Unstructured<'_>) -> arbitrary::Result<f64> {
    Ok(i16::arbitrary(u)? as f64 / 256.0)
}

fn cell_kind(u: &mut Unstructured<'_>) -> arbitrary::Result<CellKind> {
    Ok(*u.choose(&[CellKind::Quads, CellKind::Triangles, CellKind::Mixed])?)
}

fn face_rule(u: &mut Unstructured<'_>) -> arbitrary::Result<FaceRule> {
    Ok(match u.int_in_range(0..=3)? {
        0 => FaceRule::DooSabin,
        1 => FaceRule::Simple,
        2 => FaceRule::CENTROID_HALF,
        _ => FaceRule::Centroid { a: *u.choose(&[0.25, 0.7, 0.9])? },
    })
}

fn base_shape(u: &mut Unstructured<'_>) -> arbitrary::Result<PolygonSoup> {
    Ok(match u.int_in_range(0..=7)? {
        0 => shapes::tetrahedron(),
        1 => shapes::cube(),
        2 => shapes::octahedron(),
        3 => shapes::icosahedron(),
        4 => shapes::grid(u.int_in_range(1..=5)?, u.int_in_range(1..=5)?, cell_kind(u)?).unwrap(),
        5 => shapes::torus(u.int_in_range(3..=6)?, u.int_in_range(3..=6)?, cell_kind(u)?).unwrap(),
        _ => {
            // A raw soup: a few vertices and arbitrary polygons (often invalid).
            let n = u.int_in_range(3..=24u32)?;
            let positions = (0..n)
                .map(|_| Ok(DVec3::new(coordinate(u)?, coordinate(u)?, coordinate(u)?)))
                .collect::<arbitrary::Result<Vec<_>>>()?;
            let faces = (0..u.int_in_range(1..=30)?)
                .map(|_| (0..u.int_in_range(3..=6)?).map(|_| u.int_in_range(0..=n - 1)).collect())
                .collect::<arbitrary::Result<Vec<Vec<u32>>>>()?;
            PolygonSoup::from_faces(positions, faces)
        }
    })
}

fn damage(soup: &PolygonSoup, u: &mut Unstructured<'_>) -> arbitrary::Result<PolygonSoup> {
    let mut faces: Vec<Vec<u32>> = soup.faces().map(<[u32]>::to_vec).collect();
    if faces.is_empty() {
        return Ok(soup.clone());
    }
    let f = u.int_in_range(0..=faces.len() - 1)?;
    match u.int_in_range(0..=2)? {
        0 => {
            faces.remove(f);
        }
        1 => faces[f].reverse(),
        _ => {
            let k = u.int_in_range(0..=faces[f].len() - 1)?;
            faces[f][k] = u.int_in_range(0..=soup.vertex_count() as u32 - 1)?;
        }
    }
    Ok(PolygonSoup::from_faces(soup.positions.clone(), faces))
}

/// Largest distance of a rebuilt vertex from its input, relative to the input's size: its
/// bounding-box diagonal, or the largest coordinate if larger (rounding is relative to the
/// coordinates, and a mesh may be flat or even one point).
/// (Measured at unit scale: the meshes may be scaled far from 1.)
fn distance_to(fine: &PolygonSoup, rebuilt: &PolygonSoup) -> f64 {
    let unit = mesh_topo::scale::unit_scale(&fine.positions);
    let (lo, hi) = fine.positions.iter().fold((DVec3::MAX, DVec3::MIN), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let largest = fine.positions.iter().map(|p| p.abs().max_element()).fold(0.0, f64::max);
    let scale = ((hi * unit) - (lo * unit)).length().max(largest * unit).max(1e-300);
    let distance = |(p, q): (&DVec3, &DVec3)| (*p * unit).distance(*q * unit);
    rebuilt.positions.iter().zip(&fine.positions).map(distance).fold(0.0, f64::max) / scale
}

/// `decompose_soup` against building the mesh and decomposing it (Debug text, so that
/// errors and NaN positions compare too), to one level and to the maximum depth.
fn check_soup_path(fine: &PolygonSoup, rule: FaceRule, boundary: BoundaryRule, seed: Option<usize>) {
    for depth in [Depth::Levels(1), Depth::Max] {
        let options = DecomposeOptions { rule, depth, seeds: seed.into_iter().collect(), boundary };
        let direct = decompose_soup(fine, &options);
        let built = HalfedgeMesh::from_soup(fine).map_err(DooError::from).and_then(|mesh| decompose(&mesh, &options));
        assert_eq!(format!("{direct:?}"), format!("{built:?}"), "decompose_soup differs");
    }
}

fn check(fine: &PolygonSoup, rule: FaceRule, boundary: BoundaryRule, seed: Option<usize>, must_succeed: bool) {
    check_soup_path(fine, rule, boundary, seed);
    let Ok(mesh) = HalfedgeMesh::from_soup(fine) else { return };
    let options = ReverseOptions { rule, seeds: seed.into_iter().collect(), boundary };
    let reversal = match reverse(&mesh, &options) {
        Ok(reversal) => reversal,
        Err(error) => {
            assert!(!must_succeed || seed.is_some(), "reverse failed on a Doo-Sabin mesh: {error}");
            return;
        }
    };
    assert_eq!(reversal.coarse_positions().len() + reversal.details().len(), mesh.vertex_count());
    let rebuilt = reversal.reconstruct();
    assert_eq!((&rebuilt.offsets, &rebuilt.indices), (&fine.offsets, &fine.indices));
    let error = distance_to(fine, &rebuilt);
    assert!(error <= 1e-9, "reconstruction error {error}");

    let seeds = options.seeds;
    let decomposition = decompose(&mesh, &DecomposeOptions { rule, depth: Depth::Max, seeds, boundary })
        .expect("a mesh that reverses decomposes");
    let pyramid = decomposition.pyramid;
    let rebuilt = pyramid.reconstruct(pyramid.level_count(), None).expect("valid pyramid");
    assert_eq!((&rebuilt.offsets, &rebuilt.indices), (&fine.offsets, &fine.indices));
    let error = distance_to(fine, &rebuilt);
    assert!(error <= 1e-9, "pyramid reconstruction error {error}");
    let _ = pyramid.reconstruct(pyramid.level_count(), Some(0.5)).expect("valid fraction");
    let decoded = DooPyramid::from_bytes(&pyramid.to_bytes().expect("encodes")).expect("decodes");
    assert_eq!(decoded, pyramid);
}

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let run = |u: &mut Unstructured<'_>| -> arbitrary::Result<()> {
        let rule = face_rule(u)?;
        let boundary = if bool::arbitrary(u)? { BoundaryRule::Chaikin } else { BoundaryRule::Shrink };
        let mut soup = base_shape(u)?;
        let refinements = u.int_in_range(0..=2)?;
        let mut doo_mesh = false;
        if refinements > 0 {
            let Ok(fine) = subdivide_soup(&soup, &DooOptions::new(rule, refinements).with_boundary(boundary)) else { return Ok(()) };
            soup = fine.into_soup();
            if soup.face_count() == 0 {
                return Ok(());
            }
            for _ in 0..u.int_in_range(0..=4)? {
                let v = u.int_in_range(0..=soup.vertex_count() - 1)?;
                soup.positions[v] += DVec3::new(coordinate(u)?, coordinate(u)?, coordinate(u)?) / 16.0;
            }
            doo_mesh = true;
        }
        if bool::arbitrary(u)? {
            soup = mesh_topo::testing::shuffle(&soup, |k| u.int_in_range(0..=k).unwrap_or(0));
        }
        let damaged = bool::arbitrary(u)?;
        if damaged {
            soup = damage(&soup, u)?;
        }
        let seed = if bool::arbitrary(u)? { Some(u.int_in_range(0..=soup.face_count() + 2)?) } else { None };
        // Far from 1 too (reversed and rebuilt at unit scale, the same result scaled).
        let factor = *u.choose(&[1.0, 2f64.powi(-600), 2f64.powi(600), 2f64.powi(1000)]).unwrap_or(&1.0);
        soup.positions.iter_mut().for_each(|p| *p *= factor);
        check(&soup, rule, boundary, seed, doo_mesh && !damaged);
        Ok(())
    };
    let _ = run(&mut u);
});
