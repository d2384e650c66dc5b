//! `multires subdivide` with the Loop schemes and `multires analyze` for them.

mod common;

use common::cli::{fails, ok, path};

use multires::loop_subdiv::forward::{LoopOptions, subdivide};
use multires::mesh::HalfedgeMesh;
use multires::mesh::io::{WriteOptions, read_soup, write_soup};
use multires::mesh::shapes::{self, CellKind};
use serde_json::Value;

#[test]
fn subdivide_writes_every_loop_scheme() {
    let dir = tempfile::tempdir().unwrap();
    let input = common::data("bunny.obj");
    let (v, e, f) = (1839, 5511, 3674);
    for (scheme, levels, counts) in [
        ("loop", "2", (29394, 58784)),
        ("loop-warren", "1", (v + e, 4 * f)),
        ("ternary-loop", "1", (v + 2 * e + f, 9 * f)),
        ("quaternary-loop", "1", (v + 3 * e + 3 * f, 16 * f)),
    ] {
        let out = dir.path().join(format!("{scheme}.off"));
        let printed = ok(&["subdivide", path(&input), path(&out), "--scheme", scheme, "--levels", levels]);
        let (soup, _) = read_soup(&out).unwrap();
        assert_eq!((soup.vertex_count(), soup.face_count()), counts, "{scheme}");
        let line = format!("{scheme} x{levels}: {} vertices, {} faces", counts.0, counts.1);
        assert_eq!(printed.trim(), line);
    }
    // The file holds exactly the library's output (OFF keeps shortest round-trip decimals).
    let (soup, _) = read_soup(dir.path().join("loop.off")).unwrap();
    let (coarse, _) = read_soup(&input).unwrap();
    let expected = subdivide(&HalfedgeMesh::from_soup(&coarse).unwrap(), 2, &LoopOptions::default()).unwrap();
    assert_eq!(soup.positions, expected.positions);
    assert_eq!(soup, expected.into_soup());
}

#[test]
fn keep_corners_changes_only_the_corners() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("grid.off");
    let grid = shapes::grid(2, 1, CellKind::Triangles).unwrap();
    write_soup(&input, &grid, &WriteOptions::default()).unwrap();
    let (plain, kept) = (dir.path().join("plain.obj"), dir.path().join("kept.obj"));
    ok(&["subdivide", path(&input), path(&plain), "--scheme", "loop"]);
    let printed = ok(&["subdivide", path(&input), path(&kept), "--scheme", "loop", "--keep-corners"]);
    assert!(printed.starts_with("loop x1, corners kept: "), "{printed}");
    let (a, b) = (read_soup(&plain).unwrap().0, read_soup(&kept).unwrap().0);
    let mesh = HalfedgeMesh::from_soup(&grid).unwrap();
    let corners: Vec<usize> = mesh.vertices().filter(|&v| mesh.valence(v) == 2).map(|v| v.index()).collect();
    assert!(!corners.is_empty());
    for i in 0..a.positions.len() {
        if corners.contains(&i) {
            assert_eq!(b.positions[i], grid.positions[i]);
            assert_ne!(a.positions[i], grid.positions[i]);
        } else {
            assert_eq!(a.positions[i], b.positions[i]);
        }
    }
}

#[test]
fn subdivide_errors_name_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.obj");
    let quads = common::data("cube_quad.off");
    let message = fails(&["subdivide", path(&quads), path(&out), "--scheme", "loop"]);
    assert!(message.contains("face 0 has 4 corners"), "{message}");
    let missing = dir.path().join("missing.obj");
    let message = fails(&["subdivide", path(&missing), path(&out), "--scheme", "ternary-loop"]);
    assert!(message.contains("missing.obj"), "{message}");
    // Too many levels: refused at once, from the counts, for every scheme.
    let bunny = common::data("bunny.obj");
    for scheme in ["loop", "loop-warren", "ternary-loop", "quaternary-loop", "doo-sabin", "doo-centroid"] {
        let message = fails(&["subdivide", path(&bunny), path(&out), "--scheme", scheme, "--levels", "30"]);
        assert!(message.contains("too many"), "{scheme}: {message}");
        assert!(!out.exists(), "{scheme}");
    }
    let chaikin = ["subdivide", path(&bunny), path(&out), "--scheme", "doo-sabin", "--boundary", "chaikin"];
    let message = fails(&[&chaikin[..], &["--levels", "30"]].concat());
    assert!(message.contains("too many fine corners"), "{message}");
    // A mesh that does not grow (two points, no faces; a single triangle under Doo-Sabin):
    // the level limit, at once (it ran for hours before), and for Doo-Sabin's reversal
    // of a lone face, which is its own coarse mesh (it overflowed the stack).
    let points = dir.path().join("points.off");
    std::fs::write(&points, "OFF\n2 0 0\n0 0 0\n1 2 3\n").unwrap();
    let triangle = dir.path().join("triangle.off");
    std::fs::write(&triangle, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
    let many = "4294967295";
    for (mesh, scheme, expected) in [
        (&points, "loop", "invalid levels: 4294967295: at most 32"),
        (&points, "ternary-loop", "invalid levels: 4294967295: at most 32"),
        (&points, "quaternary-loop", "invalid levels: 4294967295: at most 16"),
        (&points, "doo-sabin", "levels = 4294967295: at most 32 levels"),
        (&triangle, "doo-simple", "levels = 4294967295: at most 32 levels"),
    ] {
        let message = fails(&["subdivide", path(mesh), path(&out), "--scheme", scheme, "--levels", many]);
        assert!(message.contains(expected), "{scheme}: {message}");
        assert!(!out.exists(), "{scheme}");
    }
    let mres = dir.path().join("triangle.mres");
    let message = fails(&["decompose", path(&triangle), path(&mres), "--scheme", "doo", "--levels", many]);
    assert!(message.contains("levels = 4294967295: decompose at most 32 levels"), "{message}");
    assert!(!mres.exists());
    let message = fails(&["reverse", path(&triangle), path(&out), "--scheme", "doo", "--levels", "33"]);
    assert!(message.contains("levels = 33: decompose at most 32 levels"), "{message}");
}

#[test]
fn analyze_reports_the_spectrum_as_json() {
    for (scheme, n, lambda) in [
        ("loop", 5, 0.375 + 0.25 * (std::f64::consts::TAU / 5.0).cos()),
        ("loop-warren", 9, 0.375 + 0.25 * (std::f64::consts::TAU / 9.0).cos()),
        ("ternary-loop", 4, 1.0 / 3.0),
        ("quaternary-loop", 3, 1.0 / 16.0),
    ] {
        let out = ok(&["analyze", "--scheme", scheme, "--valence", &n.to_string(), "--json"]);
        let json: Value = serde_json::from_str(&out).unwrap();
        assert!((json["subdominant"].as_f64().unwrap() - lambda).abs() < 1e-12, "{scheme}");
        assert_eq!(json["c1"], Value::Bool(true));
        let eigenvalues: Vec<f64> =
            json["eigenvalues"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        assert_eq!(eigenvalues.len(), 3 * n + 1);
        assert!(eigenvalues.windows(2).all(|w| w[0].abs() >= w[1].abs() - 1e-12));
        assert!((eigenvalues[0] - 1.0).abs() < 1e-12);
    }
    let text = ok(&["analyze", "--scheme", "loop", "--valence", "7"]);
    assert!(text.contains("C1: yes"), "{text}");
}

#[test]
fn analyze_rejects_bad_arguments() {
    assert!(fails(&["analyze", "--scheme", "loop"]).contains("--valence"));
    assert!(fails(&["analyze", "--scheme", "ternary-loop", "--valence", "2"]).contains("valence"));
    assert!(fails(&["analyze", "--scheme", "loop", "--valence", "5", "--tension", "0.1"]).contains("curve"));
}
