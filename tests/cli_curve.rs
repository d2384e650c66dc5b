//! `multires curve` and `multires analyze` for the curve schemes.

mod common;

use std::path::Path;

use common::cli::{fails, ok, path};

use multires::curve::io::{PointSet, parse_points};
use multires::curve::{CurveScheme, Framework, Topology};
use serde_json::Value;

fn analyze_json(args: &[&str]) -> Value {
    let mut all = vec!["analyze"];
    all.extend_from_slice(args);
    all.push("--json");
    serde_json::from_str(&ok(&all)).unwrap()
}

fn hexagon() -> Vec<[f64; 2]> {
    (0..6)
        .map(|k| {
            let t = k as f64 * std::f64::consts::PI / 3.0;
            [t.cos(), t.sin()]
        })
        .collect()
}

fn write_points(path: &Path, points: &[[f64; 2]]) {
    let text: String = points.iter().map(|p| format!("{} {}\n", p[0], p[1])).collect();
    std::fs::write(path, format!("# test polygon\n{text}")).unwrap();
}

fn read_planar(path: &Path) -> Vec<[f64; 2]> {
    match parse_points(&std::fs::read_to_string(path).unwrap()).unwrap() {
        PointSet::Planar(points) => points.iter().map(|p| p.to_array()).collect(),
        PointSet::Spatial(_) => panic!("planar output expected"),
    }
}

#[test]
fn four_point_is_c1_not_c2_and_cubic_bspline_is_c2() {
    let dlg = analyze_json(&["--scheme", "four-point"]);
    assert_eq!(
        (dlg["smoothness"].as_u64(), dlg["c1"].as_bool(), dlg["c2"].as_bool()),
        (Some(1), Some(true), Some(false))
    );
    assert_eq!(dlg["reproduction_degree"], 3);
    assert_eq!(dlg["generation_degree"], 3);
    let moduli: Vec<f64> = dlg["eigenvalues"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| match v {
            Value::Array(z) => z[0].as_f64().unwrap().hypot(z[1].as_f64().unwrap()),
            x => x.as_f64().unwrap().abs(),
        })
        .collect();
    let expected = [1.0, 0.5, 0.25, 0.25, 0.125, 0.0625, 0.0625];
    assert_eq!(moduli.len(), expected.len());
    for (m, e) in moduli.iter().zip(expected) {
        assert!((m - e).abs() < 1e-6, "{moduli:?}");
    }

    let cubic = analyze_json(&["--scheme", "cubic-bspline"]);
    assert_eq!(
        (cubic["smoothness"].as_u64(), cubic["c1"].as_bool(), cubic["c2"].as_bool()),
        (Some(2), Some(true), Some(true))
    );
    assert_eq!((cubic["reproduction_degree"].as_u64(), cubic["generation_degree"].as_u64()), (Some(1), Some(3)));

    let chaikin = analyze_json(&["--scheme", "chaikin"]);
    assert_eq!((chaikin["smoothness"].as_u64(), chaikin["c2"].as_bool()), (Some(1), Some(false)));
    assert_eq!(chaikin["generation_degree"], 2);

    // Text output says the same.
    let text = ok(&["analyze", "--scheme", "four-point"]);
    assert!(text.contains("smoothness: C1 (c1 true, c2 false)"), "{text}");
}

#[test]
fn combined_framework_analysis() {
    let published = analyze_json(&["--scheme", "combined"]);
    assert_eq!((published["smoothness"].as_u64(), published["c2"].as_bool()), (Some(2), Some(true)));
    let spectrum: Vec<f64> = published["eigenvalues"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    for (l, e) in spectrum.iter().zip([1.0, 0.5, 0.25, 0.125, 0.125]) {
        assert!((l - e).abs() < 1e-9, "{spectrum:?}");
    }
    assert_eq!(published["parameters"]["omega1"], -0.0625);
    // Rule (5) alone is the four-point scheme: C1.
    assert_eq!(published["interpolating"]["smoothness"], 1);
    // Parameters on the C2 line omega = gamma/2 - 1/16 with another gamma.
    let other = analyze_json(&["--scheme", "combined", "--omega2", "-0.03125", "--gamma", "0.0625"]);
    assert_eq!(other["approximating"]["smoothness"], 2);
}

#[test]
fn parameters_outside_the_convergent_range_name_the_range() {
    let err = fails(&["analyze", "--scheme", "four-point", "--tension", "0.6"]);
    assert!(err.contains("tension w = 0.6 is outside the allowed range -0.4668 <= w <= 0.4692"), "{err}");
    let err = fails(&["analyze", "--scheme", "combined", "--gamma", "0.3"]);
    assert!(err.contains("gamma = 0.3 is outside the allowed range 0 <= gamma < 1/4"), "{err}");
    let err = fails(&["analyze", "--scheme", "combined", "--omega1", "0.6"]);
    assert!(err.contains("omega1") && err.contains("outside the allowed range"), "{err}");
    let err = fails(&["analyze", "--scheme", "cubic-bspline", "--gamma", "0.1"]);
    assert!(err.contains("need --scheme combined"), "{err}");
    let err = fails(&["analyze", "--scheme", "chaikin", "--valence", "5"]);
    assert!(err.contains("--valence applies to surface schemes only"), "{err}");

    // The same ranges guard `curve`, and nothing is written.
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("hexagon.txt");
    write_points(&input, &hexagon());
    let out = dir.path().join("out.svg");
    let err = fails(&["curve", path(&input), path(&out), "--scheme", "combined", "--gamma", "-0.1"]);
    assert!(err.contains("gamma = -0.1 is outside the allowed range"), "{err}");
    let err = fails(&["curve", path(&input), path(&out), "--scheme", "four-point", "--tension", "-0.5"]);
    assert!(err.contains("tension w = -0.5 is outside the allowed range"), "{err}");
    assert!(!out.exists());
}

#[test]
fn curve_writes_svg_and_the_library_points() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("hexagon.txt");
    let polygon = hexagon();
    write_points(&input, &polygon);
    for (scheme, library) in [
        ("chaikin", CurveScheme::chaikin()),
        ("cubic-bspline", CurveScheme::cubic_bspline()),
        ("four-point", CurveScheme::four_point(1.0 / 16.0).unwrap()),
    ] {
        let svg = dir.path().join(format!("{scheme}.svg"));
        let points = dir.path().join(format!("{scheme}.txt"));
        let report = ok(&[
            "curve",
            path(&input),
            path(&svg),
            "--scheme",
            scheme,
            "--closed",
            "--levels",
            "4",
            "--out-points",
            path(&points),
        ]);
        assert!(report.contains("closed 6 points, 4 levels -> 96 points"), "{report}");
        let expected = library.refine(&polygon, Topology::Closed, 4).unwrap();
        assert_eq!(read_planar(&points), expected, "{scheme}: the file holds exactly the library's points");
        let drawing = std::fs::read_to_string(&svg).unwrap();
        assert!(drawing.starts_with("<svg") && drawing.trim_end().ends_with("</svg>"));
    }

    // The framework through two flagged vertices: they are on the curve, exactly.
    let svg = dir.path().join("combined.svg");
    let points = dir.path().join("combined.txt");
    ok(&[
        "curve",
        path(&input),
        path(&svg),
        "--scheme",
        "combined",
        "--closed",
        "--levels",
        "5",
        "--interpolate",
        "0,3",
        "--out-points",
        path(&points),
    ]);
    let refined = read_planar(&points);
    let flags = [true, false, false, true, false, false];
    assert_eq!(refined, Framework::published().refine(&polygon, &flags, Topology::Closed, 5).unwrap());
    assert_eq!((refined[0], refined[3 << 5]), (polygon[0], polygon[3]));
    assert!(std::fs::read_to_string(&svg).unwrap().matches("<circle").count() >= 2);

    // Open polygon: reflect keeps the cubic B-spline end points, repeat does not.
    let open = dir.path().join("open.txt");
    ok(&["curve", path(&input), path(&svg), "--scheme", "cubic-bspline", "--levels", "3", "--out-points", path(&open)]);
    let refined = read_planar(&open);
    let close = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs().max((a[1] - b[1]).abs()) < 1e-15;
    assert_eq!(refined.len(), 41);
    assert!(close(refined[0], polygon[0]) && close(refined[40], polygon[5]), "{:?}", (refined[0], refined[40]));
    ok(&[
        "curve",
        path(&input),
        path(&svg),
        "--scheme",
        "cubic-bspline",
        "--end-rule",
        "repeat",
        "--out-points",
        path(&open),
    ]);
    assert_ne!(read_planar(&open)[0], polygon[0]);
}

#[test]
fn auto_interpolate_prints_the_chosen_flags_and_uses_them() {
    let dir = tempfile::tempdir().unwrap();
    // An ellipse: curvature maxima at the ends of the major axis.
    let ellipse: Vec<[f64; 2]> = (0..24)
        .map(|k| {
            let t = k as f64 * std::f64::consts::TAU / 24.0;
            [3.0 * t.cos(), t.sin()]
        })
        .collect();
    let input = dir.path().join("ellipse.txt");
    write_points(&input, &ellipse);
    let svg = dir.path().join("ellipse.svg");
    let points = dir.path().join("ellipse-fine.txt");
    let report = ok(&[
        "curve",
        path(&input),
        path(&svg),
        "--scheme",
        "combined",
        "--closed",
        "--auto-interpolate",
        "--levels",
        "3",
        "--out-points",
        path(&points),
    ]);
    assert!(report.contains("auto-interpolate: 2 of 24 points: 0 (maximum), 12 (maximum)"), "{report}");
    assert!(report.contains("flags: --interpolate 0,12"), "{report}");
    let refined = read_planar(&points);
    assert_eq!((refined[0], refined[12 << 3]), (ellipse[0], ellipse[12]));
    let mut flags = vec![false; 24];
    flags[0] = true;
    flags[12] = true;
    assert_eq!(refined, Framework::published().refine(&ellipse, &flags, Topology::Closed, 3).unwrap());
}

#[test]
fn bad_input_names_the_problem_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.svg");
    let points = dir.path().join("out.txt");
    let bad = dir.path().join("bad.txt");
    let run = |input: &Path, extra: &[&str]| {
        let mut args = vec!["curve", path(input), path(&out), "--out-points", path(&points)];
        args.extend_from_slice(extra);
        let err = fails(&args);
        assert!(!out.exists() && !points.exists(), "nothing written on error: {err}");
        err
    };

    std::fs::write(&bad, "# header\n0 0\n1 zero\n2 2\n").unwrap();
    let err = run(&bad, &["--scheme", "chaikin"]);
    assert!(err.contains("bad.txt: line 3: `zero` is not a number"), "{err}");

    std::fs::write(&bad, "0 0\n1 1 1\n").unwrap();
    let err = run(&bad, &["--scheme", "chaikin"]);
    assert!(err.contains("line 2: 3 coordinates, but the first point (line 1) has 2"), "{err}");

    std::fs::write(&bad, "0 0\n1 nan\n2 0\n").unwrap();
    let err = run(&bad, &["--scheme", "cubic-bspline"]);
    assert!(err.contains("line 2: coordinate 2 is not finite"), "{err}");

    std::fs::write(&bad, "# nothing here\n").unwrap();
    let err = run(&bad, &["--scheme", "chaikin"]);
    assert!(err.contains("the file has no points"), "{err}");

    std::fs::write(&bad, "0 0\n1 0\n").unwrap();
    let err = run(&bad, &["--scheme", "cubic-bspline", "--closed"]);
    assert!(err.contains("needs at least 3 points for a closed polygon, got 2"), "{err}");

    write_points(&bad, &hexagon());
    let err = run(&bad, &["--scheme", "combined", "--closed", "--interpolate", "1,6"]);
    assert!(err.contains("interpolation index 6 is out of range for a polygon of 6 points"), "{err}");
    let err = run(&bad, &["--scheme", "cubic-bspline", "--interpolate", "1"]);
    assert!(err.contains("need --scheme combined"), "{err}");
    let err = run(&bad, &["--scheme", "chaikin", "--levels", "40"]);
    assert!(err.contains("exceed the limit"), "{err}");
    let err = run(&dir.path().join("missing.txt"), &["--scheme", "chaikin"]);
    assert!(err.contains("missing.txt"), "{err}");
}
