//! The `multires` binary on real files: `info`, `compare`, `convert`, the demo, and one
//! clear error line (never a backtrace) for bad input.

mod common;

use std::path::Path;
use std::process::{Command, Output};

use serde_json::Value;

fn multires(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_multires")).args(args).current_dir(dir).output().expect("run multires")
}

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Runs a command that must succeed; returns stdout.
fn ok(args: &[&str]) -> String {
    let out = multires(args, root());
    assert!(out.status.success(), "{args:?} failed: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

fn json(args: &[&str]) -> Value {
    serde_json::from_str(&ok(args)).expect("one JSON object")
}

/// Runs a command that must fail with one `multires: ...` line on stderr; returns it.
fn fails(args: &[&str]) -> String {
    let out = multires(args, root());
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(!out.status.success(), "{args:?} succeeded");
    assert_eq!(stderr.lines().count(), 1, "{args:?}: not one line:\n{stderr}");
    assert!(stderr.starts_with("multires: "), "{stderr}");
    assert!(!stderr.contains("panicked") && !stderr.contains("backtrace"), "{stderr}");
    stderr
}

#[test]
fn info_json_on_elephant_with_holes() {
    let info = json(&["info", "tests/data/elephant-with-holes.off", "--json"]);
    for (key, value) in [
        ("vertices", 2798),
        ("edges", 7371),
        ("faces", 4463),
        ("boundary_edges", 1353),
        ("boundary_loops", 106),
        ("components", 1),
        ("euler", -110),
        ("genus", 3),
        ("unreferenced_vertices", 0),
    ] {
        assert_eq!(info[key], value, "{key}");
    }
    assert_eq!(info["manifold"], true);
    assert_eq!(info["format"], "OFF");
    assert_eq!(info["face_sizes"]["3"], 4463);
    // Valences count every non-isolated vertex once.
    let valence_total: u64 = info["valences"].as_object().unwrap().values().map(|v| v.as_u64().unwrap()).sum();
    assert_eq!(valence_total, 2798);
}

#[test]
fn info_on_polygonal_double_torus_and_bunny_text() {
    let info = json(&["info", "tests/data/double-torus-example.off", "--json"]);
    assert_eq!((info["genus"].as_i64(), info["euler"].as_i64()), (Some(2), Some(-2)));
    assert_eq!(info["face_sizes"], serde_json::json!({"4": 202, "5": 12, "6": 4, "7": 2}));
    let text = ok(&["info", "tests/data/bunny.obj"]);
    for expected in ["vertices      1839", "faces         3674", "genus         0", "manifold      yes"] {
        assert!(text.contains(expected), "missing `{expected}` in\n{text}");
    }
}

#[test]
fn info_reports_non_manifold_soups_and_dropped_attributes() {
    let dir = tempfile::tempdir().unwrap();
    // Three triangles on the edge (0, 1), one unreferenced vertex, normals.
    let path = dir.path().join("fin.obj");
    std::fs::write(
        &path,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 9 9 9\nvn 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n",
    )
    .unwrap();
    let info = json(&["info", path.to_str().unwrap(), "--json"]);
    assert_eq!(info["manifold"], false);
    let error = info["manifold_error"].as_str().unwrap();
    assert!(error.starts_with("non-manifold edge (0, 1)"), "{error}");
    assert_eq!(
        (info["vertices"].as_u64(), info["edges"].as_u64(), info["faces"].as_u64()),
        (Some(6), Some(7), Some(3))
    );
    assert_eq!(info["euler"], 6 - 7 + 3);
    assert_eq!(info["boundary_edges"], 6);
    assert!(info["genus"].is_null() && info["boundary_loops"].is_null());
    assert_eq!(info["components"], 1);
    assert_eq!(info["unreferenced_vertices"], 1);
    assert_eq!(info["unreferenced_vertex_ids"], serde_json::json!([5]));
    assert_eq!(info["dropped"][0]["what"], "normals (`vn`)");
    assert_eq!(info["dropped"][0]["first"], "line 7");
    let text = ok(&["info", path.to_str().unwrap()]);
    assert!(text.contains("manifold      no: non-manifold edge (0, 1)"), "{text}");
    assert!(text.contains("not kept      1 x normals (`vn`) (first at line 7)"), "{text}");
    assert!(text.contains("unreferenced  1 (5)"), "{text}");
}

#[test]
fn errors_are_one_line_with_the_location() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.off");
    std::fs::write(&bad, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 x\n3 0 1 2\n").unwrap();
    let err = fails(&["info", bad.to_str().unwrap()]);
    assert!(err.contains("bad.off: line 5: `x` is not a number"), "{err}");
    let truncated = dir.path().join("short.ply");
    std::fs::write(
        &truncated,
        b"ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0",
    )
    .unwrap();
    let err = fails(&["info", truncated.to_str().unwrap(), "--json"]);
    let length = std::fs::metadata(&truncated).unwrap().len();
    assert!(err.contains(&format!("short.ply: byte {length}: file ends early")), "{err}");
    let err = fails(&["info", "tests/data/README.md"]);
    // The file named once.
    assert_eq!(
        err.trim_end(),
        "multires: tests/data/README.md: unsupported format (the extension must be .obj, .off or .ply)"
    );
    let err = fails(&["info", "tests/data/no-such-mesh.off"]);
    assert!(err.contains("no-such-mesh.off"), "{err}");
    let err = fails(&["compare", "tests/data/cube_quad.off", bad.to_str().unwrap()]);
    assert!(err.contains("line 5"), "{err}");
    let err = fails(&["convert", "tests/data/cube_quad.off", "out.stl"]);
    assert!(err.contains("out.stl: unsupported format"), "{err}");
    assert_eq!(err.matches("out.stl").count(), 1, "{err}");
}

#[test]
fn compare_known_offsets() {
    let same = json(&["compare", "tests/data/cube_quad.off", "tests/data/cube_quad.off", "--json"]);
    for key in ["max_dist", "mean_dist", "rel_max", "rel_mean"] {
        assert_eq!(same[key], 0.0, "{key}");
    }
    // The cube of side 2 moved by 0.5 along z: every vertex is 0.5 from its copy.
    let dir = tempfile::tempdir().unwrap();
    let moved = dir.path().join("moved.off");
    let original = std::fs::read_to_string(common::data("cube_quad.off")).unwrap();
    let mut lines: Vec<String> = original.lines().map(str::to_string).collect();
    for line in &mut lines[2..10] {
        let p: Vec<f64> = line.split_whitespace().map(|t| t.parse().unwrap()).collect();
        *line = format!("{} {} {}", p[0], p[1], p[2] + 0.5);
    }
    std::fs::write(&moved, lines.join("\n")).unwrap();
    let result = json(&["compare", "tests/data/cube_quad.off", moved.to_str().unwrap(), "--json"]);
    assert_eq!(result["max_dist"], 0.5);
    assert_eq!(result["mean_dist"], 0.5);
    let diagonal = 2.0 * 3f64.sqrt();
    assert!((result["rel_max"].as_f64().unwrap() - 0.5 / diagonal).abs() < 1e-15);
    assert_eq!(result["a"]["vertices"], 8);
    assert_eq!(result["b"]["faces"], 6);
}

/// Coordinates far from 1 are compared at unit scale: at 2^-600 the squared distances
/// underflowed (two different meshes compared as equal, each box "a point"), beyond 1e150
/// the comparison was refused. Near `f64::MAX`, a distance beyond the range is an error.
#[test]
fn compare_far_from_one() {
    let dir = tempfile::tempdir().unwrap();
    let original = std::fs::read_to_string(common::data("cube_quad.off")).unwrap();
    let write = |name: &str, factor: f64, dz: f64| {
        let mut lines: Vec<String> = original.lines().map(str::to_string).collect();
        for line in &mut lines[2..10] {
            let p: Vec<f64> = line.split_whitespace().map(|t| t.parse().unwrap()).collect();
            *line = format!("{:e} {:e} {:e}", p[0] * factor, p[1] * factor, (p[2] + dz) * factor);
        }
        let path = dir.path().join(name);
        std::fs::write(&path, lines.join("\n")).unwrap();
        path.to_str().unwrap().to_string()
    };
    for exponent in [-600, 600] {
        let factor = 2f64.powi(exponent);
        let (a, b) = (write("a.off", factor, 0.0), write("b.off", factor, 0.5));
        let result = json(&["compare", &a, &b, "--json"]);
        assert_eq!(result["max_dist"], 0.5 * factor, "{result}");
        assert_eq!(result["mean_dist"], 0.5 * factor);
        // (serde_json reads long decimals to within an ulp.)
        let diagonal = result["bbox_diagonal_a"].as_f64().unwrap();
        assert!((diagonal / (12f64.sqrt() * factor) - 1.0).abs() < 1e-15, "{result}");
        assert!((result["rel_max"].as_f64().unwrap() - 0.5 / (2.0 * 3f64.sqrt())).abs() < 1e-15, "{result}");
    }
    let (a, b) = (write("a.off", 1e308, 0.0), write("b.off", 1e308, 0.5));
    let error = fails(&["compare", &a, &b]);
    assert!(error.contains("beyond the f64 range"), "{error}");
}

#[test]
fn compare_point_clouds_and_a_degenerate_reference() {
    // A is one point repeated (its bounding box has no diagonal); B three points on a line.
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("same.off");
    let b = dir.path().join("line.off");
    std::fs::write(&a, format!("OFF\n50 0 0\n{}", "1 1 1\n".repeat(50))).unwrap();
    std::fs::write(&b, "OFF\n3 0 0\n0 0 0\n1 0 0\n2 0 0\n").unwrap();
    let result = json(&["compare", a.to_str().unwrap(), b.to_str().unwrap(), "--json"]);
    assert_eq!(result["a_to_b"]["max"], 2f64.sqrt());
    assert_eq!(result["b_to_a"]["max"], 3f64.sqrt());
    assert_eq!(result["max_dist"], 3f64.sqrt());
    assert!(result["rel_max"].is_null() && result["rel_mean"].is_null(), "{result}");
}

#[test]
fn compare_elephants_matches_an_independent_kd_tree() {
    // Reference values from scipy's cKDTree on the same files (one-sided maxima and
    // means); the hole-punched elephant's vertices all lie on the full one.
    let result = json(&["compare", "tests/data/elephant.off", "tests/data/elephant-with-holes.off", "--json"]);
    assert!((result["a_to_b"]["max"].as_f64().unwrap() - 2.502e-2).abs() < 1e-5, "{result}");
    assert!((result["a_to_b"]["mean"].as_f64().unwrap() - 2.153e-4).abs() < 1e-7, "{result}");
    assert_eq!(result["b_to_a"]["max"], 0.0);
    assert!((result["bbox_diagonal_a"].as_f64().unwrap() - 1.372074459276901).abs() < 1e-12);
    assert!((result["rel_mean"].as_f64().unwrap() - 7.847e-5).abs() < 1e-8, "{result}");
}

#[test]
fn convert_is_lossless_through_every_format() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    ok(&["convert", "tests/data/bunny.obj", &path("a.ply")]);
    ok(&["convert", &path("a.ply"), &path("b.off")]);
    ok(&["convert", &path("b.off"), &path("c.ply"), "--ply-encoding", "ascii"]);
    ok(&["convert", &path("c.ply"), &path("d.ply"), "--ply-encoding", "binary-be"]);
    let out = ok(&["convert", &path("d.ply"), &path("e.obj")]);
    assert!(out.contains("1839 vertices, 3674 faces"), "{out}");
    let statements = |text: &str| -> Vec<String> {
        text.lines().filter(|l| !l.starts_with('#')).map(|l| l.trim_end().to_string()).collect()
    };
    let original = std::fs::read_to_string(common::data("bunny.obj")).unwrap();
    let back = std::fs::read_to_string(path("e.obj")).unwrap();
    assert_eq!(statements(&back), statements(&original));
    let ascii = std::fs::read_to_string(path("c.ply")).unwrap();
    assert!(ascii.starts_with("ply\nformat ascii 1.0\n"));
}

#[test]
fn convert_notes_dropped_attributes() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("in.obj");
    std::fs::write(&input, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n").unwrap();
    let out = multires(&["convert", input.to_str().unwrap(), dir.path().join("out.off").to_str().unwrap()], root());
    assert!(out.status.success());
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert!(stderr.contains("not kept: 1 x texture coordinates (`vt`) (first at line 4)"), "{stderr}");
}

#[test]
fn demo_without_arguments_writes_multires_out() {
    let dir = tempfile::tempdir().unwrap();
    let out = multires(&[], dir.path());
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(stdout.contains("vertices      1839"), "{stdout}");
    assert!(stdout.contains("genus         0"), "{stdout}");
    let written = dir.path().join("multires-out/bunny.obj");
    let info = json(&["info", written.to_str().unwrap(), "--json"]);
    assert_eq!((info["vertices"].as_u64(), info["faces"].as_u64()), (Some(1839), Some(3674)));
    let saved: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("multires-out/bunny-info.json")).unwrap())
            .unwrap();
    assert_eq!(saved["genus"], 0);
    // `demo --out` writes elsewhere.
    let other = dir.path().join("elsewhere");
    ok(&["demo", "--out", other.to_str().unwrap()]);
    assert!(other.join("bunny.obj").exists());
}

#[test]
fn closed_stdout_is_not_a_panic() {
    // `multires info ... | head -1`: whether the write happens before or after the pipe
    // closes, the command ends quietly.
    let mut child = Command::new(env!("CARGO_BIN_EXE_multires"))
        .args(["info", "tests/data/bunny00.off", "--json"])
        .current_dir(root())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    assert!(out.stderr.is_empty(), "{}", String::from_utf8_lossy(&out.stderr));
}
