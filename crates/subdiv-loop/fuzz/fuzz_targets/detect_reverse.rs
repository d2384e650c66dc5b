//! Detect Loop connectivity and reverse on arbitrary valid meshes.
//!
//! Inputs are built structurally from the fuzz bytes: a procedural base shape or a raw
//! index soup, optionally refined one or two Loop steps with arbitrary details (so that
//! many inputs do have Loop connectivity), then renumbered, and optionally broken by an
//! edge flip or a removed face; or a raw soup, valid or not, is given the faces of one
//! Loop step in the canonical pattern (a bowtie vertex, a flipped face...). Some inputs
//! are two copies side by side (two components), and some get up to two seed vertices
//! (any index, out of range included). Whatever
//! comes out, `reverse` and `decompose` must not panic; when they succeed,
//! reconstruction must give the input back; and `decompose_soup` must give exactly
//! what `decompose` of the soup's half-edge mesh gives, result or error. The meshes are
//! scaled by 1, 2^-600, 2^600 or 2^1000 last (energies measured at unit scale).

#![no_main]

use arbitrary::{Arbitrary, Unstructured};
use glam::DVec3;
use libfuzzer_sys::fuzz_target;
use mesh_topo::shapes::{self, CellKind};
use mesh_topo::{HalfedgeMesh, PolygonSoup};
use subdiv_loop::detect::{DetectOptions, detect};
use subdiv_loop::forward::{LoopOptions, VertexWeights};
use subdiv_loop::LoopError;
use subdiv_loop::pyramid::{DecomposeOptions, Levels, LoopPyramid, bounding_box_diagonal, decompose, decompose_soup};
use subdiv_loop::reverse::{ReverseOptions, reconstruct, reverse};

fn coordinate(u: &mut Unstructured<'_>) -> arbitrary::Result<f64> {
    Ok(i16::arbitrary(u)? as f64 / 256.0)
}

fn base_shape(u: &mut Unstructured<'_>) -> arbitrary::Result<PolygonSoup> {
    Ok(match u.int_in_range(0..=6)? {
        0 => shapes::tetrahedron(),
        1 => shapes::octahedron(),
        2 => shapes::icosahedron(),
        3 => shapes::grid(u.int_in_range(1..=5)?, u.int_in_range(1..=5)?, CellKind::Triangles).unwrap(),
        4 => shapes::torus(u.int_in_range(3..=6)?, u.int_in_range(3..=6)?, CellKind::Triangles).unwrap(),
        _ => {
            // A raw soup: a few vertices and arbitrary triangles (often invalid).
            let n = u.int_in_range(3..=24u32)?;
            let positions = (0..n)
                .map(|_| Ok(DVec3::new(coordinate(u)?, coordinate(u)?, coordinate(u)?)))
                .collect::<arbitrary::Result<Vec<_>>>()?;
            let faces = (0..u.int_in_range(1..=40)?)
                .map(|_| Ok([u.int_in_range(0..=n - 1)?, u.int_in_range(0..=n - 1)?, u.int_in_range(0..=n - 1)?]))
                .collect::<arbitrary::Result<Vec<_>>>()?;
            PolygonSoup::from_faces(positions, faces)
        }
    })
}

fn break_mesh(soup: &PolygonSoup, u: &mut Unstructured<'_>) -> arbitrary::Result<PolygonSoup> {
    let mut faces: Vec<Vec<u32>> = soup.faces().map(<[u32]>::to_vec).collect();
    if faces.is_empty() {
        return Ok(soup.clone());
    }
    let f = u.int_in_range(0..=faces.len() - 1)?;
    if bool::arbitrary(u)? {
        faces.remove(f);
    } else {
        // Flip the edge after corner k of face f, if it is interior.
        let k = u.int_in_range(0..=2usize)?;
        let (a, b) = (faces[f][k], faces[f][(k + 1) % 3]);
        let c = faces[f][(k + 2) % 3];
        if let Some(g) = faces.iter().position(|g| (0..3).any(|j| g[j] == b && g[(j + 1) % 3] == a)) {
            let d = *faces[g].iter().find(|&&v| v != a && v != b).unwrap_or(&a);
            faces[f] = vec![a, d, c];
            faces[g] = vec![d, b, c];
        }
    }
    Ok(PolygonSoup::from_faces(soup.positions.clone(), faces))
}

/// The faces of one Loop step of any triangle soup in the canonical pattern (edge points
/// numbered by first appearance), valid mesh or not; edge points at the edge midpoints.
fn canonical_faces(coarse: &PolygonSoup) -> PolygonSoup {
    let nv = coarse.vertex_count() as u32;
    let mut edges: Vec<[u32; 2]> = Vec::new();
    let mut edge_point = |a: u32, b: u32| {
        let key = [a.min(b), a.max(b)];
        let e = edges.iter().position(|&k| k == key).unwrap_or_else(|| {
            edges.push(key);
            edges.len() - 1
        });
        nv + e as u32
    };
    let mut faces = Vec::new();
    for face in coarse.faces().filter(|f| f.len() == 3) {
        let [a, b, c] = [face[0], face[1], face[2]];
        let (ab, bc, ca) = (edge_point(a, b), edge_point(b, c), edge_point(c, a));
        faces.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    let mut positions = coarse.positions.clone();
    positions.extend(edges.iter().map(|&[a, b]| 0.5 * (coarse.positions[a as usize] + coarse.positions[b as usize])));
    PolygonSoup::from_faces(positions, faces)
}

/// `soup` and a copy of it moved along x, as one soup of two components.
fn two_copies(soup: &PolygonSoup) -> PolygonSoup {
    let n = soup.vertex_count() as u32;
    let mut positions = soup.positions.clone();
    positions.extend(soup.positions.iter().map(|&p| p + DVec3::X * 100.0));
    let faces: Vec<Vec<u32>> = soup
        .faces()
        .map(<[u32]>::to_vec)
        .chain(soup.faces().map(|f| f.iter().map(|&v| v + n).collect()))
        .collect();
    PolygonSoup::from_faces(positions, faces)
}

fn check(fine: &PolygonSoup, rules: LoopOptions, seeds: &[u32], must_succeed: bool) {
    for levels in [Levels::Count(1), Levels::Max] {
        let options = DecomposeOptions { rules, levels, seed_vertices: seeds.to_vec() };
        let through_mesh =
            HalfedgeMesh::from_soup(fine).map_err(LoopError::from).and_then(|mesh| decompose(&mesh, &options));
        assert_eq!(format!("{:?}", decompose_soup(fine, &options)), format!("{through_mesh:?}"));
    }
    let Ok(mesh) = HalfedgeMesh::from_soup(fine) else { return };
    let _ = detect(&mesh, &DetectOptions::default());
    let level = match reverse(&mesh, &ReverseOptions { rules, seed_vertices: seeds.to_vec() }) {
        Ok(level) => level,
        Err(error) => {
            assert!(!must_succeed, "reverse failed on a renumbered Loop mesh: {error}");
            return;
        }
    };
    assert_eq!(level.coarse.vertex_count() + level.details.len(), mesh.vertex_count());
    let rebuilt = reconstruct(&level.coarse, &level.details, level.order.as_ref(), &rules).expect("valid level");
    let rebuilt = rebuilt.to_soup();
    assert_eq!(rebuilt.indices, fine.indices);
    // (Measured at unit scale: the meshes may be scaled far from 1.)
    let unit = mesh_topo::scale::unit_scale(&fine.positions);
    let scaled = |points: &[DVec3]| points.iter().map(|p| *p * unit).collect::<Vec<_>>();
    let (rebuilt_unit, fine_unit) = (scaled(&rebuilt.positions), scaled(&fine.positions));
    let scale = bounding_box_diagonal(&fine_unit).max(1e-300);
    for (p, q) in rebuilt_unit.iter().zip(&fine_unit) {
        assert!(p.distance(*q) <= 1e-9 * scale, "reconstruction error {}", p.distance(*q) / scale);
    }
    let pyramid = decompose(&mesh, &DecomposeOptions { rules, levels: Levels::Max, seed_vertices: seeds.to_vec() })
        .expect("one level exists");
    let rebuilt = pyramid.reconstruct(pyramid.level_count()).expect("valid pyramid");
    assert_eq!(rebuilt.indices, fine.indices);
    let decoded = LoopPyramid::from_bytes(&pyramid.to_bytes().expect("encodes")).expect("decodes");
    assert_eq!(decoded, pyramid);
}

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let run = |u: &mut Unstructured<'_>| -> arbitrary::Result<()> {
        let rules = LoopOptions {
            weights: if bool::arbitrary(u)? { VertexWeights::Warren } else { VertexWeights::Loop },
            keep_corners: bool::arbitrary(u)?,
        };
        let base = base_shape(u)?;
        let refinements = u.int_in_range(0..=2)?;
        let mut soup = base;
        let mut loop_mesh = false;
        if refinements == 0 && bool::arbitrary(u)? {
            soup = canonical_faces(&soup);
        } else if refinements > 0 {
            let Ok(mut pyramid) = LoopPyramid::smooth(soup.clone(), rules, refinements) else { return Ok(()) };
            for level in &mut pyramid.levels {
                for d in &mut level.details {
                    if bool::arbitrary(u)? {
                        *d = DVec3::new(coordinate(u)?, coordinate(u)?, coordinate(u)?) / 16.0;
                    }
                }
            }
            soup = pyramid.reconstruct(refinements).expect("valid smooth pyramid");
            loop_mesh = true;
        }
        if bool::arbitrary(u)? {
            soup = mesh_topo::testing::shuffle(&soup, |k| u.int_in_range(0..=k).unwrap_or(0));
        }
        if bool::arbitrary(u)? {
            soup = two_copies(&soup);
        }
        let broken = bool::arbitrary(u)?;
        if broken {
            soup = break_mesh(&soup, u)?;
        }
        let vertices = soup.vertex_count() as u32;
        let seeds = (0..u.int_in_range(0..=2)?)
            .map(|_| u.int_in_range(0..=vertices))
            .collect::<arbitrary::Result<Vec<u32>>>()?;
        // Far from 1 too (energies and thresholds at unit scale).
        let factor = *u.choose(&[1.0, 2f64.powi(-600), 2f64.powi(600), 2f64.powi(1000)]).unwrap_or(&1.0);
        soup.positions.iter_mut().for_each(|p| *p *= factor);
        check(&soup, rules, &seeds, loop_mesh && !broken && seeds.is_empty());
        Ok(())
    };
    let _ = run(&mut u);
});
