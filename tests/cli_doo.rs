//! `multires subdivide | reverse | decompose | reconstruct | analyze` with the Doo-Sabin
//! schemes, run as a process on files: the paper's round trip (subdivide three times,
//! move a vertex, decompose, reconstruct exactly), seeds, compression, the Reif check,
//! and one clear error line (with nothing written) for bad input.

mod common;

use std::path::Path;

use common::cli::{fails_in as fails, ok_in as ok};

use glam::DVec3;
use multires::mesh::PolygonSoup;
use multires::mesh::io::{self, WriteOptions};
use multires::mesh::shapes;

fn read(path: &Path) -> PolygonSoup {
    io::read_soup(path).unwrap().0
}

fn write(path: &Path, soup: &PolygonSoup) {
    io::write_soup(path, soup, &WriteOptions::default()).unwrap();
}

fn diagonal(points: &[DVec3]) -> f64 {
    let (lo, hi) = points.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    (hi - lo).length()
}

/// Largest vertex distance over the bounding-box diagonal of `b`; the faces must be equal.
fn relative_error(a: &PolygonSoup, b: &PolygonSoup) -> f64 {
    assert_eq!(a.offsets, b.offsets, "face sizes differ");
    assert_eq!(a.indices, b.indices, "faces differ");
    a.positions.iter().zip(&b.positions).map(|(p, q)| p.distance(*q)).fold(0.0, f64::max) / diagonal(&b.positions)
}

/// The cube after three Doo-Sabin steps (through the CLI), with vertex 100 moved.
fn moved_fine_cube(dir: &Path) -> PolygonSoup {
    write(&dir.join("cube.off"), &shapes::cube());
    let printed = ok(&["subdivide", "cube.off", "fine.obj", "--scheme", "doo-sabin", "--levels", "3"], dir);
    assert!(printed.contains("384 vertices"), "{printed}");
    let mut fine = read(&dir.join("fine.obj"));
    assert_eq!((fine.vertex_count(), fine.face_count()), (384, 386));
    fine.positions[100] += DVec3::new(0.05, -0.02, 0.1);
    write(&dir.join("moved.obj"), &fine);
    fine
}

#[test]
fn subdivide_three_times_move_a_vertex_decompose_and_reconstruct_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let moved = moved_fine_cube(d);
    let printed = ok(&["decompose", "moved.obj", "moved.mres", "--scheme", "doo", "--max", "--report"], d);
    assert!(printed.contains("decomposed 3 Doo-Sabin level(s): base 8 vertices, 6 faces"), "{printed}");
    // Storage: base vertices plus details are as many 3-vectors as the input has vertices.
    assert!(printed.contains("8 + 376 = 384 3-vectors"), "{printed}");
    assert!(printed.contains("keep fraction"), "{printed}");
    ok(&["reconstruct", "moved.mres", "rebuilt.obj"], d);
    let error = relative_error(&read(&d.join("rebuilt.obj")), &moved);
    assert!(error < 1e-12, "{error}");

    // Level 0 is the base cube, moved a little by the one displaced vertex.
    let printed = ok(&["reconstruct", "moved.mres", "base.off", "--level", "0"], d);
    assert!(printed.contains("reconstructed level 0 of 3"), "{printed}");
    let base = read(&d.join("base.off"));
    assert_eq!((base.vertex_count(), base.face_count()), (8, 6));
    let cube = shapes::cube();
    let moved_by = base.positions.iter().map(|p| cube.positions.iter().map(|q| p.distance(*q)).fold(1e9, f64::min));
    assert!(moved_by.fold(0.0, f64::max) < 0.05);

    // Compression: keeping all details is exact, keeping none is the smooth subdivision of
    // the base mesh; both keep the connectivity.
    ok(&["reconstruct", "moved.mres", "all.obj", "--keep", "1"], d);
    assert!(relative_error(&read(&d.join("all.obj")), &moved) < 1e-12);
    let printed = ok(&["reconstruct", "moved.mres", "none.obj", "--keep", "0"], d);
    // As many 3-vectors as the fine mesh has vertices: base vertices plus details.
    let total = moved.vertex_count() - 8;
    assert!(printed.contains(&format!("keeping the largest 0 of {total} details: --keep 0.0)")), "{printed}");
    let none = read(&d.join("none.obj"));
    let error = relative_error(&none, &moved);
    assert!(error > 1e-4 && error < 0.1, "{error}");
}

/// `info` on a pyramid: what each level stores, from the pyramid alone; the counts are
/// those of the meshes it rebuilds, the detail lengths those of its own details.
#[test]
fn info_describes_a_pyramid_level_by_level() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    moved_fine_cube(d);
    ok(&["decompose", "moved.obj", "moved.mres", "--scheme", "doo", "--max"], d);
    let info: serde_json::Value = serde_json::from_str(&ok(&["info", "moved.mres", "--json"], d)).unwrap();
    assert_eq!((info["scheme"].as_str(), info["boundary_rule"].as_str()), (Some("doo-sabin"), Some("shrink")));
    assert_eq!(info["bytes"], std::fs::metadata(d.join("moved.mres")).unwrap().len());
    assert_eq!((info["base"]["vertices"].as_u64(), info["base"]["faces"].as_u64()), (Some(8), Some(6)));
    let pyramid =
        multires::doo::pyramid::DooPyramid::from_bytes(&std::fs::read(d.join("moved.mres")).unwrap()).unwrap();
    let levels = info["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 3);
    for (k, row) in levels.iter().enumerate() {
        // The vertex count of the mesh rebuilt at this level.
        let rebuilt = pyramid.reconstruct(k + 1, None).unwrap();
        assert_eq!(row["vertices"].as_u64(), Some(rebuilt.vertex_count() as u64), "level {}", k + 1);
        // A closed base: the face counts follow from the scheme's counts.
        assert_eq!(row["faces"].as_u64(), Some(rebuilt.face_count() as u64), "level {}", k + 1);
        assert!(row["canonical_order"] == true);
        let details = &pyramid.levels[k].details;
        assert_eq!(row["details"].as_u64(), Some(details.len() as u64));
        let largest = details.iter().map(|v| v.length()).fold(0.0, f64::max);
        assert_eq!(row["largest_detail"].as_f64(), Some(largest));
    }
    assert_eq!((info["details"].as_u64(), info["finest_vertices"].as_u64()), (Some(376), Some(384)));
    // The text says the same.
    let text = ok(&["info", "moved.mres"], d);
    assert!(text.contains("doo-sabin, shrink boundary: a base mesh and 3 level(s) of details"), "{text}");
    assert!(text.contains("level 3       384 vertices, 386 faces: "), "{text}");
    // An open base: the face counts depend on the boundary, and are not given.
    write(&d.join("grid.off"), &shapes::grid(3, 2, shapes::CellKind::Quads).unwrap());
    ok(&["subdivide", "grid.off", "grid1.obj", "--scheme", "doo-sabin"], d);
    ok(&["decompose", "grid1.obj", "grid1.mres", "--scheme", "doo"], d);
    let info: serde_json::Value = serde_json::from_str(&ok(&["info", "grid1.mres", "--json"], d)).unwrap();
    assert!(info["levels"][0]["faces"].is_null() && info["levels"][0]["vertices"].as_u64() == Some(24), "{info}");
    // A pyramid cut short is an error that says where.
    std::fs::write(d.join("cut.mres"), &std::fs::read(d.join("moved.mres")).unwrap()[..200]).unwrap();
    let line = fails(&["info", "cut.mres"], d, "none");
    assert!(line.contains("cut.mres") && line.contains("truncated"), "{line}");
}

#[test]
fn reverse_finds_the_coarse_mesh_and_reports_the_seed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(&d.join("cube.off"), &shapes::cube());
    ok(&["subdivide", "cube.off", "fine.off", "--scheme", "doo-sabin", "--levels", "2"], d);
    let printed = ok(&["reverse", "fine.off", "coarse.off", "--scheme", "doo", "--levels", "2"], d);
    assert!(
        printed.contains("reversed 2 Doo-Sabin level(s): 96 vertices, 98 faces -> 8 vertices, 6 faces"),
        "{printed}"
    );
    assert!(printed.contains("level 1, component 0: seed face"), "{printed}");
    assert!(printed.contains("as F_F (automatic, 1 valid of 1 readings tried); detail norm"), "{printed}");
    assert!(printed.contains("gives all details zero"), "{printed}");
    // reverse(doo(C)) = C: the coarse mesh is the cube (same faces, same positions).
    let coarse = read(&d.join("coarse.off"));
    assert!(relative_error(&coarse, &shapes::cube()) < 1e-12);

    // A given seed: face 0 is an F_F face (the output lists F_F faces first).
    let printed = ok(&["reverse", "fine.off", "one.off", "--scheme", "doo", "--levels", "1", "--seed-face", "0"], d);
    assert!(printed.contains("seed face 0 as F_F (given"), "{printed}");
    let one = read(&d.join("one.off"));
    assert_eq!((one.vertex_count(), one.face_count()), (24, 26));
}

/// Two copies of `soup` side by side (the second moved by `shift`), as one file's mesh of
/// two connected components; the second copy's faces follow the first's.
fn two_copies(soup: &PolygonSoup, shift: DVec3) -> PolygonSoup {
    let n = soup.vertex_count() as u32;
    let positions = soup.positions.iter().copied().chain(soup.positions.iter().map(|&p| p + shift)).collect();
    let faces: Vec<Vec<u32>> =
        soup.faces().map(<[u32]>::to_vec).chain(soup.faces().map(|f| f.iter().map(|&v| v + n).collect())).collect();
    PolygonSoup::from_faces(positions, faces)
}

#[test]
fn seed_faces_are_given_one_per_component_to_reverse_and_decompose() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(&d.join("cube.off"), &shapes::cube());
    ok(&["subdivide", "cube.off", "fine.off", "--scheme", "doo-sabin"], d);
    let fine = read(&d.join("fine.off"));
    // 24 vertices, 26 faces: 6 F_F faces, 12 F_E quads, then the 8 F_V triangles 18..26.
    assert_eq!((fine.vertex_count(), fine.face_count()), (24, 26));
    write(&d.join("two.off"), &two_copies(&fine, DVec3::new(5.0, 0.0, 0.0)));

    // One seed per component, separated by a comma or repeated: each is kept, as given.
    for seeds in [&["--seed-face", "0,26"][..], &["--seed-face", "0", "--seed-face", "26"]] {
        let printed = ok(&[&["reverse", "two.off", "coarse.off", "--scheme", "doo"][..], seeds].concat(), d);
        assert!(printed.contains("48 vertices, 52 faces -> 16 vertices, 12 faces"), "{printed}");
        assert!(printed.contains("component 0: seed face 0 as F_F (given"), "{printed}");
        assert!(printed.contains("component 1: seed face 26 as F_F (given"), "{printed}");
    }
    // A seed on an F_V triangle of the second cube: that component is read the other way
    // round (its coarse mesh is the octahedron: 6 vertices, 8 faces), the first as before.
    let printed = ok(&["reverse", "two.off", "coarse.off", "--scheme", "doo", "--seed-face", "44"], d);
    assert!(printed.contains("48 vertices, 52 faces -> 14 vertices, 14 faces"), "{printed}");
    assert!(printed.contains("component 0: seed face 0 as F_F (automatic"), "{printed}");
    assert!(printed.contains("component 1: seed face 44 as F_F (given"), "{printed}");
    // Two seeds in one component: an error naming them, nothing written.
    let line = fails(&["reverse", "two.off", "out.off", "--scheme", "doo", "--seed-face", "0,1"], d, "out.off");
    assert!(line.contains("seed"), "{line}");

    // `decompose` takes the same seeds; the octahedron reading is exact too.
    let printed =
        ok(&["decompose", "two.off", "two.mres", "--scheme", "doo", "--seed-face", "0", "--seed-face", "44"], d);
    assert!(printed.contains("base 14 vertices, 14 faces"), "{printed}");
    assert!(printed.contains("component 1: seed face 44 as F_F (given"), "{printed}");
    ok(&["reconstruct", "two.mres", "rebuilt.off"], d);
    assert!(relative_error(&read(&d.join("rebuilt.off")), &read(&d.join("two.off"))) < 1e-12);
    // The Loop schemes take no seed face.
    let line = fails(&["decompose", "two.off", "out.mres", "--scheme", "loop", "--seed-face", "0"], d, "out.mres");
    assert!(line.contains("--seed-face applies to --scheme doo"), "{line}");
}

/// A closed prism over a pentagon (two pentagons, five quads). The pentagon is not an
/// affine image of a regular one: on those, every rule here gives `(v + centroid) / 2`.
fn pentagonal_prism() -> PolygonSoup {
    let ring = |z: f64| {
        (0..5).map(move |i| {
            let t = std::f64::consts::TAU * i as f64 / 5.0;
            let r = if i == 0 { 1.5 } else { 1.0 };
            DVec3::new(r * t.cos(), r * t.sin(), z)
        })
    };
    let positions: Vec<DVec3> = ring(0.0).chain(ring(1.0)).collect();
    let mut faces: Vec<Vec<u32>> = vec![vec![4, 3, 2, 1, 0], vec![5, 6, 7, 8, 9]];
    faces.extend((0..5u32).map(|i| vec![i, (i + 1) % 5, (i + 1) % 5 + 5, i + 5]));
    PolygonSoup::from_faces(positions, faces)
}

#[test]
fn the_three_rules_agree_on_triangles_and_parallelograms_only() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(&d.join("tet.off"), &shapes::tetrahedron());
    write(&d.join("cube.off"), &shapes::cube());
    for scheme in ["doo-sabin", "doo-simple", "doo-centroid"] {
        let printed = ok(&["subdivide", "tet.off", &format!("tet-{scheme}.off"), "--scheme", scheme], d);
        assert!(printed.contains("12 vertices, 14 faces (last level: 4 F_F, 6 F_E, 4 F_V)"), "{printed}");
        ok(&["subdivide", "cube.off", &format!("cube-{scheme}.off"), "--scheme", scheme], d);
    }
    let tet = |s: &str| read(&d.join(format!("tet-{s}.off")));
    assert!(relative_error(&tet("doo-sabin"), &tet("doo-simple")) > 1e-3);
    // On triangles the centroid contraction with a = 1/2 has the Doo-Sabin weights
    // (2/3, 1/6, 1/6); on pentagons it does not.
    assert!(relative_error(&tet("doo-sabin"), &tet("doo-centroid")) < 1e-15);
    write(&d.join("prism.off"), &pentagonal_prism());
    for scheme in ["doo-sabin", "doo-centroid"] {
        ok(&["subdivide", "prism.off", &format!("poly-{scheme}.off"), "--scheme", scheme], d);
    }
    let poly = |s: &str| read(&d.join(format!("poly-{s}.off")));
    assert!(relative_error(&poly("doo-sabin"), &poly("doo-centroid")) > 1e-3);
    let cube = |s: &str| read(&d.join(format!("cube-{s}.off")));
    // On quads the simple averaging rule is the Doo-Sabin rule; on parallelograms the
    // centroid contraction with a = 1/2 is too (both give v/2 + (v_prev + v_next)/4).
    assert!(relative_error(&cube("doo-sabin"), &cube("doo-simple")) < 1e-15);
    assert!(relative_error(&cube("doo-sabin"), &cube("doo-centroid")) < 1e-15);
    assert!(
        cube("doo-centroid").positions.iter().all(|p| p.to_array().iter().all(|c| [0.0, 0.25, 0.75, 1.0].contains(c)))
    );
}

#[test]
fn reverse_and_decompose_take_the_rule_subdivide_took() {
    // An open mixed grid after one step of the simple rule: reversed with the same rule,
    // the details are zero; with the original weights (`--scheme doo`) they are not, and
    // still rebuild the mesh.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write(&d.join("grid.obj"), &shapes::grid(4, 2, shapes::CellKind::Mixed).unwrap());
    ok(&["subdivide", "grid.obj", "fine.obj", "--scheme", "doo-simple"], d);
    let fine = read(&d.join("fine.obj"));
    for (scheme, zero) in [("doo-simple", true), ("doo", false), ("doo-sabin", false)] {
        ok(&["decompose", "fine.obj", "fine.mres", "--scheme", scheme], d);
        ok(&["reconstruct", "fine.mres", "smooth.obj", "--keep", "0"], d);
        let error = relative_error(&read(&d.join("smooth.obj")), &fine);
        assert_eq!(error < 1e-14, zero, "{scheme}: {error}");
        ok(&["reconstruct", "fine.mres", "rebuilt.obj"], d);
        assert!(relative_error(&read(&d.join("rebuilt.obj")), &fine) < 1e-12, "{scheme}");
        std::fs::remove_file(d.join("fine.mres")).unwrap();
    }
    // The same mesh with an F_V face first: the automatic mode finds an F_F face two
    // faces away (its F_V and F_E neighbours give no valid reading of an open mesh).
    let last = fine.face_count() - 1;
    assert_eq!(fine.face(last).len(), 4, "an F_V face around an inner vertex of valence 4");
    let faces: Vec<Vec<u32>> = std::iter::once(last).chain(0..last).map(|f| fine.face(f).to_vec()).collect();
    write(&d.join("fv_first.obj"), &PolygonSoup::from_faces(fine.positions.clone(), faces));
    let printed = ok(&["reverse", "fv_first.obj", "coarse.obj", "--scheme", "doo-simple"], d);
    assert!(printed.contains("-> 15 vertices, 12 faces"), "{printed}");
    assert!(printed.contains("gives all details zero"), "{printed}");
}

#[test]
fn analyze_shows_the_reif_check() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = ok(&["analyze", "--scheme", "doo-sabin", "--valence", "5"], d);
    assert!(text.contains("subdominant 0.500000000000 (algebraic multiplicity 2, geometric 2)"), "{text}");
    assert!(text.contains("C1: yes"), "{text}");
    // The centroid contraction: no C1 limit on faces of four or more sides.
    for n in ["4", "5", "6", "8"] {
        let text = ok(&["analyze", "--scheme", "doo-centroid", "--valence", n], d);
        assert!(text.contains("C1: NO"), "n = {n}: {text}");
        let json = ok(&["analyze", "--scheme", "doo-centroid", "--valence", n, "--json"], d);
        let value: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert_eq!(value["c1"], serde_json::json!(false), "{json}");
        assert_eq!(value["subdominant_multiplicity"].as_u64(), Some(n.parse::<u64>().unwrap() - 1), "{json}");
    }
    // The simple variant: subdominant 1/2 + cos(2π/n)/4.
    let json = ok(&["analyze", "--scheme", "doo-simple", "--valence", "6", "--json"], d);
    let value: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert!((value["subdominant"].as_f64().unwrap() - 0.625).abs() < 1e-12, "{json}");
    assert_eq!(value["c1"], serde_json::json!(true), "{json}");
    let line = fails(&["analyze", "--scheme", "doo-sabin"], d, "none");
    assert!(line.contains("--valence"), "{line}");
    fails(&["analyze", "--scheme", "doo-sabin", "--valence", "2"], d, "none");
}

#[test]
fn bad_input_gives_one_error_line_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fine = moved_fine_cube(d);
    ok(&["decompose", "moved.obj", "moved.mres", "--scheme", "doo", "--levels", "2"], d);
    let bytes = std::fs::read(d.join("moved.mres")).unwrap();

    // Non-manifold: three triangles on one edge.
    std::fs::write(d.join("fin.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n")
        .unwrap();
    for command in [
        &["subdivide", "fin.obj", "out.obj", "--scheme", "doo-sabin"][..],
        &["reverse", "fin.obj", "out.obj", "--scheme", "doo"],
        &["decompose", "fin.obj", "out.obj", "--scheme", "doo"],
    ] {
        let line = fails(command, d, "out.obj");
        assert!(line.contains("fin.obj"), "{line}");
    }
    // A face with two corners.
    std::fs::write(d.join("digon.off"), "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n2 0 1\n").unwrap();
    fails(&["subdivide", "digon.off", "out.obj", "--scheme", "doo-sabin"], d, "out.obj");
    // NaN coordinates.
    std::fs::write(d.join("nan.obj"), "v 0 0 0\nv 1 0 0\nv nan 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n")
        .unwrap();
    fails(&["subdivide", "nan.obj", "out.obj", "--scheme", "doo-sabin"], d, "out.obj");
    fails(&["reverse", "nan.obj", "out.obj", "--scheme", "doo"], d, "out.obj");

    // Doo-like but broken: one face removed, one quad's diagonal flipped into two triangles.
    let faces: Vec<Vec<u32>> = fine.faces().map(<[u32]>::to_vec).collect();
    let removed = PolygonSoup::from_faces(fine.positions.clone(), faces[1..].to_vec());
    write(&d.join("removed.obj"), &removed);
    let line = fails(&["reverse", "removed.obj", "out.obj", "--scheme", "doo"], d, "out.obj");
    assert!(line.contains("face"), "{line}");
    fails(&["decompose", "removed.obj", "out.mres", "--scheme", "doo", "--max"], d, "out.mres");
    let quad = faces.iter().position(|f| f.len() == 4).unwrap();
    let q = faces[quad].clone();
    let mut split = faces.clone();
    split[quad] = vec![q[0], q[1], q[2]];
    split.push(vec![q[0], q[2], q[3]]);
    write(&d.join("split.obj"), &PolygonSoup::from_faces(fine.positions.clone(), split));
    let line = fails(&["reverse", "split.obj", "out.obj", "--scheme", "doo"], d, "out.obj");
    assert!(line.contains("not Doo-Sabin connectivity at face"), "{line}");
    // Not Doo connectivity at all, and too many levels.
    write(&d.join("cube.off"), &shapes::cube());
    fails(&["reverse", "cube.off", "out.obj", "--scheme", "doo"], d, "out.obj");
    fails(&["reverse", "moved.obj", "out.obj", "--scheme", "doo", "--levels", "4"], d, "out.obj");
    fails(&["reverse", "moved.obj", "out.obj", "--scheme", "doo", "--levels", "0"], d, "out.obj");
    let line = fails(&["reverse", "moved.obj", "out.obj", "--scheme", "doo", "--seed-face", "999"], d, "out.obj");
    assert!(line.contains("seed face 999"), "{line}");
    fails(&["subdivide", "cube.off", "out.obj", "--scheme", "doo-sabin", "--keep-corners"], d, "out.obj");

    // Broken pyramids and bad reconstruct options.
    std::fs::write(d.join("truncated.mres"), &bytes[..bytes.len() / 2]).unwrap();
    let line = fails(&["reconstruct", "truncated.mres", "out.obj"], d, "out.obj");
    // Named, and said where the data ends (not at the start of the payload).
    let half = bytes.len() / 2;
    assert!(line.contains("truncated.mres") && line.contains(&format!("({half} bytes, at least")), "{line}");
    assert!(line.contains("it is truncated") && !line.contains("at byte 12:"), "{line}");
    let mut corrupted = bytes.clone();
    let middle = corrupted.len() / 2;
    for b in &mut corrupted[middle..middle + 16] {
        *b = 0xff;
    }
    std::fs::write(d.join("corrupted.mres"), &corrupted).unwrap();
    fails(&["reconstruct", "corrupted.mres", "out.obj"], d, "out.obj");
    fails(&["reconstruct", "moved.mres", "out.obj", "--level", "3"], d, "out.obj");
    fails(&["reconstruct", "moved.mres", "out.obj", "--keep", "1.5"], d, "out.obj");
    fails(&["reconstruct", "moved.mres", "out.obj", "--keep", "NaN"], d, "out.obj");
    let line = fails(&["reconstruct", "moved.mres", "out.obj", "--keep", "-0.1"], d, "out.obj");
    assert!(line.contains("--keep -0.1: give a fraction between 0 and 1"), "{line}");
}

#[test]
fn the_chaikin_boundary_rule_subdivides_decomposes_and_rebuilds() {
    // An open quad grid, three Chaikin-boundary steps, one boundary point moved: the
    // pyramid of the same rule goes back to the grid and rebuilds the mesh exactly.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let grid = shapes::grid(3, 2, shapes::CellKind::Quads).unwrap();
    write(&d.join("grid.obj"), &grid);
    let printed = ok(
        &["subdivide", "grid.obj", "fine.obj", "--scheme", "doo-sabin", "--levels", "3", "--boundary", "chaikin"],
        d,
    );
    assert!(printed.contains("doo-sabin x3, chaikin boundary"), "{printed}");
    let mut fine = read(&d.join("fine.obj"));
    let last = fine.vertex_count() - 1;
    fine.positions[last].z += 0.1;
    write(&d.join("moved.obj"), &fine);
    let printed =
        ok(&["decompose", "moved.obj", "moved.mres", "--scheme", "doo-sabin", "--max", "--boundary", "chaikin"], d);
    assert!(printed.contains("decomposed 3 Doo-Sabin level(s): base 12 vertices, 6 faces"), "{printed}");
    let printed = ok(&["reconstruct", "moved.mres", "rebuilt.obj"], d);
    assert!(printed.contains("chaikin boundary"), "{printed}");
    assert!(relative_error(&read(&d.join("rebuilt.obj")), &fine) < 1e-12);
    // reverse gives the grid back (up to vertex numbering: same faces and corners).
    let printed =
        ok(&["reverse", "fine.obj", "coarse.obj", "--scheme", "doo", "--levels", "3", "--boundary", "chaikin"], d);
    assert!(printed.contains("-> 12 vertices, 6 faces"), "{printed}");
    // Loop takes no --boundary.
    let error = fails(&["subdivide", "grid.obj", "bad.obj", "--scheme", "loop", "--boundary", "chaikin"], d, "bad.obj");
    assert!(error.contains("--boundary applies to the Doo-Sabin schemes only"), "{error}");
}

#[test]
fn the_chaikin_boundary_rule_on_a_real_mesh_with_106_holes() {
    // CGAL's hole-punched elephant (genus 3, 106 boundary loops): two Chaikin-boundary
    // steps keep every hole, one vertex moved, and the pyramid goes back to the elephant
    // and rebuilds the mesh exactly.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::copy(common::data("elephant-with-holes.off"), d.join("elephant.off")).unwrap();
    let args =
        ["subdivide", "elephant.off", "fine.obj", "--scheme", "doo-sabin", "--levels", "2", "--boundary", "chaikin"];
    let printed = ok(&args, d);
    assert!(printed.contains("64380 vertices, 61564 faces"), "{printed}");
    let info: serde_json::Value = serde_json::from_str(&ok(&["info", "fine.obj", "--json"], d)).unwrap();
    assert_eq!((info["boundary_loops"].as_u64(), info["genus"].as_u64()), (Some(106), Some(3)));
    let mut fine = read(&d.join("fine.obj"));
    fine.positions[1000] += DVec3::new(0.01, 0.0, -0.01);
    write(&d.join("moved.obj"), &fine);
    let args = ["decompose", "moved.obj", "moved.mres", "--scheme", "doo-sabin", "--max", "--boundary", "chaikin"];
    let printed = ok(&args, d);
    assert!(printed.contains("decomposed 2 Doo-Sabin level(s): base 2798 vertices, 4463 faces"), "{printed}");
    assert!(printed.contains("2798 + 61582 = 64380 3-vectors"), "{printed}");
    ok(&["reconstruct", "moved.mres", "rebuilt.obj"], d);
    assert!(relative_error(&read(&d.join("rebuilt.obj")), &fine) < 1e-12);
}
