//! `multires reverse | decompose | reconstruct --scheme loop` run as a process on files:
//! exact round trips, levels, compression, and one clear error line (with nothing
//! written) for bad input.

mod common;

use std::path::Path;

use common::cli::{fails_in as fails, ok_in as ok};

use glam::DVec3;
use multires::loop_subdiv::forward::LoopOptions;
use multires::loop_subdiv::pyramid::{LoopPyramid, bounding_box_diagonal};
use multires::mesh::io::{self, WriteOptions};
use multires::mesh::{PolygonSoup, shapes};

/// An octahedron refined three times by Loop, every vertex moved at random (fixed seed),
/// so that every level has details.
fn loop_mesh() -> PolygonSoup {
    let mut soup =
        LoopPyramid::smooth(shapes::octahedron(), LoopOptions::default(), 3).unwrap().reconstruct(3).unwrap();
    let mut state = 0x1234_5678_9abc_def1u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for p in &mut soup.positions {
        *p += 0.02 * DVec3::new(next(), next(), next());
    }
    soup
}

fn read(path: &Path) -> PolygonSoup {
    io::read_soup(path).unwrap().0
}

fn relative_error(a: &PolygonSoup, b: &PolygonSoup) -> f64 {
    assert_eq!(a.indices, b.indices, "faces differ");
    let diagonal = bounding_box_diagonal(&b.positions);
    a.positions.iter().zip(&b.positions).map(|(p, q)| p.distance(*q)).fold(0.0, f64::max) / diagonal
}

#[test]
fn decompose_then_reconstruct_reproduces_the_input() {
    let dir = tempfile::tempdir().unwrap();
    let input = loop_mesh();
    io::write_soup(dir.path().join("fine.obj"), &input, &WriteOptions::default()).unwrap();
    let printed = ok(&["decompose", "fine.obj", "fine.mres", "--scheme", "loop", "--max", "--report"], dir.path());
    assert!(printed.contains("decomposed 3 Loop level(s)"), "{printed}");
    assert!(printed.contains("base 6 vertices, 8 faces"), "{printed}");
    assert!(printed.contains("keep fraction"), "{printed}");
    ok(&["reconstruct", "fine.mres", "rebuilt.off"], dir.path());
    let rebuilt = read(&dir.path().join("rebuilt.off"));
    let error = relative_error(&rebuilt, &input);
    assert!(error < 1e-12, "{error}");
    // `compare` agrees.
    let compare = ok(&["compare", "rebuilt.off", "fine.obj", "--json"], dir.path());
    let value: serde_json::Value = serde_json::from_str(&compare).unwrap();
    assert!(value["rel_max"].as_f64().unwrap() < 1e-12, "{compare}");

    // Level 0 is the base mesh, which `reverse --levels 3` also gives.
    ok(&["reconstruct", "fine.mres", "base.obj", "--level", "0"], dir.path());
    ok(&["reverse", "fine.obj", "reversed.obj", "--scheme", "loop", "--levels", "3"], dir.path());
    let (base, reversed) = (read(&dir.path().join("base.obj")), read(&dir.path().join("reversed.obj")));
    assert_eq!(base.vertex_count(), 6);
    assert!(relative_error(&base, &reversed) < 1e-12);

    // Compression: fewer details, a bounded error; the line says how many were kept.
    let printed = ok(&["reconstruct", "fine.mres", "approx.obj", "--keep", "0.1"], dir.path());
    let approx = read(&dir.path().join("approx.obj"));
    let error = relative_error(&approx, &input);
    assert!(error > 0.0 && error < 0.05, "{error}");
    // The octahedron refined three times: 6 base vertices, 258 fine ones.
    let total = input.vertex_count() - 6;
    let kept = ((0.1 * total as f64).round()) as usize;
    assert!(printed.contains(&format!("keeping the largest {kept} of {total} details: --keep 0.1)")), "{printed}");
    let printed = ok(&["reconstruct", "fine.mres", "none.obj", "--keep", "1e-300"], dir.path());
    assert!(printed.contains(&format!("keeping the largest 0 of {total} details: --keep 1e-300)")), "{printed}");
    // A negative fraction reaches the fraction check (not taken for an option).
    let line = fails(&["reconstruct", "fine.mres", "out.obj", "--keep", "-0.1"], dir.path(), "out.obj");
    assert!(line.contains("--keep") && line.contains("-0.1"), "{line}");
}

/// Largest detail left when every detail is dropped (`--keep 0`), relative to the input:
/// zero (to rounding) when the scheme reversed is the one that made the mesh.
fn error_without_details(dir: &Path, mesh: &str, scheme_options: &[&str]) -> f64 {
    let mut args = vec!["decompose", mesh, "out.mres", "--levels", "2"];
    args.extend_from_slice(scheme_options);
    ok(&args, dir);
    ok(&["reconstruct", "out.mres", "smooth.obj", "--keep", "0"], dir);
    let error = relative_error(&read(&dir.join("smooth.obj")), &read(&dir.join(mesh)));
    std::fs::remove_file(dir.join("out.mres")).unwrap();
    error
}

#[test]
fn reverse_and_decompose_take_the_rules_subdivide_took() {
    // Warren's weights on a closed mesh, and boundary corners kept on an open grid: the
    // same `--scheme` (and `--keep-corners`) as `subdivide` gives zero details, another
    // rule details that still rebuild the mesh.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    io::write_soup(d.join("octahedron.obj"), &shapes::octahedron(), &WriteOptions::default()).unwrap();
    ok(&["subdivide", "octahedron.obj", "warren.obj", "--scheme", "loop-warren", "--levels", "2"], d);
    assert!(error_without_details(d, "warren.obj", &["--scheme", "loop-warren"]) < 1e-14);
    assert!(error_without_details(d, "warren.obj", &["--scheme", "loop"]) > 1e-3);
    let grid = shapes::grid(3, 3, shapes::CellKind::Triangles).unwrap();
    io::write_soup(d.join("grid.obj"), &grid, &WriteOptions::default()).unwrap();
    ok(&["subdivide", "grid.obj", "corners.obj", "--scheme", "loop", "--keep-corners", "--levels", "2"], d);
    assert!(error_without_details(d, "corners.obj", &["--scheme", "loop", "--keep-corners"]) < 1e-14);
    assert!(error_without_details(d, "corners.obj", &["--scheme", "loop"]) > 1e-3);
    ok(&["decompose", "corners.obj", "corners.mres", "--scheme", "loop", "--levels", "2"], d);
    ok(&["reconstruct", "corners.mres", "rebuilt.obj"], d);
    assert!(relative_error(&read(&d.join("rebuilt.obj")), &read(&d.join("corners.obj"))) < 1e-12);
    // A Doo-Sabin rule is no Loop rule, and the Loop reversal keeps its own options.
    let line = fails(&["reverse", "warren.obj", "out.obj", "--scheme", "doo-simple", "--keep-corners"], d, "out.obj");
    assert!(line.contains("--keep-corners applies to the Loop schemes only"), "{line}");
}

#[test]
fn bad_input_gives_one_error_line_and_no_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    io::write_soup(d.join("fine.obj"), &loop_mesh(), &WriteOptions::default()).unwrap();
    ok(&["decompose", "fine.obj", "fine.mres", "--scheme", "loop", "--levels", "2"], d);
    let bytes = std::fs::read(d.join("fine.mres")).unwrap();

    // Truncated and corrupted pyramids.
    std::fs::write(d.join("truncated.mres"), &bytes[..bytes.len() / 2]).unwrap();
    let line = fails(&["reconstruct", "truncated.mres", "out.obj"], d, "out.obj");
    assert!(line.contains("truncated.mres"), "{line}");
    std::fs::write(d.join("short.mres"), &bytes[..5]).unwrap();
    fails(&["reconstruct", "short.mres", "out.obj"], d, "out.obj");
    let mut wrong_count = bytes.clone();
    let last = wrong_count.len() - 1;
    wrong_count.truncate(last);
    std::fs::write(d.join("cut.mres"), &wrong_count).unwrap();
    fails(&["reconstruct", "cut.mres", "out.obj"], d, "out.obj");
    std::fs::write(d.join("foreign.mres"), b"not a pyramid at all").unwrap();
    let line = fails(&["reconstruct", "foreign.mres", "out.obj"], d, "out.obj");
    assert!(line.contains("not a multires pyramid"), "{line}");
    fails(&["reconstruct", "fine.mres", "out.obj", "--level", "3"], d, "out.obj");
    fails(&["reconstruct", "fine.mres", "out.obj", "--keep", "1.5"], d, "out.obj");

    // Meshes without Loop connectivity, quads, a mesh with one face removed.
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/bunny.obj");
    let line = fails(&["decompose", bunny.to_str().unwrap(), "out.mres", "--scheme", "loop"], d, "out.mres");
    assert!(line.contains("no Loop subdivision connectivity at vertex"), "{line}");
    let quads = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/cube_quad.off");
    let line = fails(&["reverse", quads.to_str().unwrap(), "out.obj", "--scheme", "loop"], d, "out.obj");
    assert!(line.contains("face 0 has 4 corners"), "{line}");
    let mut holed = loop_mesh();
    let faces: Vec<Vec<u32>> = holed.faces().skip(1).map(<[u32]>::to_vec).collect();
    holed = PolygonSoup::from_faces(holed.positions, faces);
    io::write_soup(d.join("holed.obj"), &holed, &WriteOptions::default()).unwrap();
    fails(&["reverse", "holed.obj", "out.obj", "--scheme", "loop"], d, "out.obj");
    // Too many levels: the octahedron has no Loop connectivity.
    fails(&["decompose", "fine.obj", "out.mres", "--scheme", "loop", "--levels", "4"], d, "out.mres");
    fails(&["reverse", "fine.obj", "out.obj", "--scheme", "loop", "--levels", "0"], d, "out.obj");
    fails(&["reverse", "fine.obj", "out.obj", "--scheme", "loop", "--seed-face", "3"], d, "out.obj");
    // NaN coordinates.
    std::fs::write(d.join("nan.obj"), "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n").unwrap();
    fails(&["reverse", "nan.obj", "out.obj", "--scheme", "loop"], d, "out.obj");
}

/// A torus whose vertices all have valence 6, refined once: several sets of the fine
/// vertices read as vertex points. The automatic choice keeps the reading with the
/// smallest details (the refinement's, zero details), in any numbering;
/// `--seed-vertex` on an edge point picks another, which rebuilds the file just as
/// exactly.
#[test]
fn a_seed_vertex_picks_the_reading_of_an_all_regular_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let torus = shapes::torus(8, 6, shapes::CellKind::Triangles).unwrap();
    io::write_soup(d.join("torus.off"), &torus, &WriteOptions::default()).unwrap();
    let printed = ok(&["subdivide", "torus.off", "fine.off", "--scheme", "loop"], d);
    assert_eq!(printed.trim(), "loop x1: 192 vertices, 384 faces");
    let fine = read(&d.join("fine.off"));

    // Automatic, and seeded on vertex 0 (a vertex of the torus): the torus, no details.
    for seed in [&[][..], &["--seed-vertex", "0"]] {
        ok(&[&["reverse", "fine.off", "coarse.off", "--scheme", "loop"][..], seed].concat(), d);
        let coarse = read(&d.join("coarse.off"));
        assert!(relative_error(&coarse, &torus) < 1e-12, "{seed:?}");
    }
    // Seeded on an edge point (vertex 48 on: one per edge of the torus): another coarse
    // mesh of the same size, with details, rebuilt exactly.
    let printed = ok(&["decompose", "fine.off", "other.mres", "--scheme", "loop", "--seed-vertex", "60"], d);
    assert!(printed.contains("base 48 vertices, 96 faces"), "{printed}");
    ok(&["reverse", "fine.off", "other.off", "--scheme", "loop", "--seed-vertex", "60"], d);
    let other = read(&d.join("other.off"));
    let moved = other.positions.iter().zip(&torus.positions).map(|(p, q)| p.distance(*q)).fold(0.0, f64::max);
    assert!(moved > 1e-3, "another reading: {moved}");
    ok(&["reconstruct", "other.mres", "rebuilt.off"], d);
    assert!(relative_error(&read(&d.join("rebuilt.off")), &fine) < 1e-12);

    // The same file with vertices 0 and 60 swapped: detection alone would start at the
    // edge point now numbered 0; the automatic choice still finds the refinement's
    // reading (every detail zero, so dropping them all changes nothing), as the seed at
    // the vertex point now numbered 60 does; seeded at the edge point, the details are
    // not zero.
    let mut swapped = fine.clone();
    swapped.positions.swap(0, 60);
    for v in &mut swapped.indices {
        *v = match *v {
            0 => 60,
            60 => 0,
            other => other,
        };
    }
    io::write_soup(d.join("swapped.off"), &swapped, &WriteOptions::default()).unwrap();
    for (seed, exact) in [(&[][..], true), (&["--seed-vertex", "60"][..], true), (&["--seed-vertex", "0"][..], false)] {
        ok(&[&["decompose", "swapped.off", "swapped.mres", "--scheme", "loop"][..], seed].concat(), d);
        ok(&["reconstruct", "swapped.mres", "smooth.off", "--keep", "0"], d);
        let error = relative_error(&read(&d.join("smooth.off")), &swapped);
        assert_eq!(error < 1e-12, exact, "{seed:?}: {error}");
    }

    // A seed that does not exist, and a seed vertex for Doo-Sabin: an error, nothing written.
    let line = fails(&["reverse", "fine.off", "out.off", "--scheme", "loop", "--seed-vertex", "999"], d, "out.off");
    assert!(line.contains("seed vertex 999 does not exist"), "{line}");
    let line = fails(&["decompose", "fine.off", "out.mres", "--scheme", "doo", "--seed-vertex", "1"], d, "out.mres");
    assert!(line.contains("--seed-vertex applies to the Loop schemes"), "{line}");
}

/// Two refined tori in one file, each numbered so that its lowest vertex is an edge
/// point: the automatic choice reads each component by itself (the refinement's reading,
/// zero details); `--seed-vertex` takes one vertex per component, repeated or separated
/// by commas; two seeds of one component that cannot both be vertex points are an error.
#[test]
fn seed_vertices_are_given_one_per_component() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let torus = shapes::torus(8, 6, shapes::CellKind::Triangles).unwrap();
    io::write_soup(d.join("torus.off"), &torus, &WriteOptions::default()).unwrap();
    ok(&["subdivide", "torus.off", "fine.off", "--scheme", "loop"], d);
    let fine = read(&d.join("fine.off"));
    // Vertices 0 and 60 swapped (vertex 0 is now an edge point), twice side by side.
    let swap = |v: u32| match v {
        0 => 60,
        60 => 0,
        other => other,
    };
    let n = fine.positions.len() as u32;
    let mut positions = fine.positions.clone();
    positions.swap(0, 60);
    let second: Vec<_> = positions.iter().map(|&p| p + DVec3::X * 10.0).collect();
    positions.extend(second);
    let faces: Vec<Vec<u32>> = fine
        .faces()
        .map(|f| f.iter().map(|&v| swap(v)).collect())
        .chain(fine.faces().map(|f| f.iter().map(|&v| swap(v) + n).collect()))
        .collect();
    let two = PolygonSoup::from_faces(positions, faces);
    io::write_soup(d.join("two.off"), &two, &WriteOptions::default()).unwrap();

    // Automatic, one seed (the other component automatic), both seeds in either form:
    // the refinement's readings, so dropping every detail changes nothing.
    let n = n.to_string();
    let both = format!("60,{}", 60 + 192);
    let cases: [&[&str]; 4] =
        [&[], &["--seed-vertex", "60"], &["--seed-vertex", &both], &["--seed-vertex", "60", "--seed-vertex", "252"]];
    for seeds in cases {
        let printed = ok(&[&["decompose", "two.off", "two.mres", "--scheme", "loop"][..], seeds].concat(), d);
        assert!(printed.contains("base 96 vertices, 192 faces"), "{seeds:?}: {printed}");
        ok(&["reconstruct", "two.mres", "smooth.off", "--keep", "0"], d);
        let error = relative_error(&read(&d.join("smooth.off")), &two);
        assert!(error < 1e-12, "{seeds:?}: {error}");
    }
    // A seed on the second component's edge point: that component is read another way.
    ok(&["decompose", "two.off", "two.mres", "--scheme", "loop", "--seed-vertex", &n], d);
    ok(&["reconstruct", "two.mres", "smooth.off", "--keep", "0"], d);
    assert!(relative_error(&read(&d.join("smooth.off")), &two) > 1e-6);
    // Vertex 60 and a neighbour of it cannot both be vertex points: an error, nothing written.
    let face = two.faces().find(|f| f.contains(&60)).unwrap();
    let neighbour = face.iter().find(|&&v| v != 60).unwrap().to_string();
    let seeds = format!("60,{neighbour}");
    let line = fails(&["reverse", "two.off", "out.off", "--scheme", "loop", "--seed-vertex", &seeds], d, "out.off");
    assert!(line.contains(&format!("seed vertex {neighbour} would be an edge point")), "{line}");
}

/// `info` on a Loop pyramid: per level the vertex and face counts of the mesh it
/// rebuilds and the lengths of its details.
#[test]
fn info_describes_a_loop_pyramid_level_by_level() {
    let dir = tempfile::tempdir().unwrap();
    let input = loop_mesh();
    io::write_soup(dir.path().join("fine.obj"), &input, &WriteOptions::default()).unwrap();
    ok(&["decompose", "fine.obj", "fine.mres", "--scheme", "loop", "--max"], dir.path());
    let info: serde_json::Value = serde_json::from_str(&ok(&["info", "fine.mres", "--json"], dir.path())).unwrap();
    assert_eq!((info["scheme"].as_str(), info["boundary_rule"].is_null()), (Some("loop"), true));
    let pyramid = LoopPyramid::from_bytes(&std::fs::read(dir.path().join("fine.mres")).unwrap()).unwrap();
    let levels = info["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 3);
    for (k, row) in levels.iter().enumerate() {
        let rebuilt = pyramid.reconstruct(k + 1).unwrap();
        let counts = (row["vertices"].as_u64(), row["faces"].as_u64());
        assert_eq!(counts, (Some(rebuilt.vertex_count() as u64), Some(rebuilt.face_count() as u64)), "level {}", k + 1);
        let details = &pyramid.levels[k].details;
        let rms = (details.iter().map(|v| v.length_squared()).sum::<f64>() / details.len() as f64).sqrt();
        let measured = row["rms_detail"].as_f64().unwrap();
        assert!((measured - rms).abs() <= 1e-15 * rms && rms > 0.0, "{measured} {rms}");
    }
    assert_eq!(info["finest_vertices"].as_u64(), Some(input.vertex_count() as u64));
    let text = ok(&["info", "fine.mres"], dir.path());
    assert!(text.contains("loop: a base mesh and 3 level(s) of details"), "{text}");
    assert!(text.contains(&format!("level 3       {} vertices, 512 faces: ", input.vertex_count())), "{text}");
}
