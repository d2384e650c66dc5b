//! `multires fit`: the convergence table, JSON, plot and sampled surface, and one clear
//! error line (and no output file) for every kind of bad input.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use glam::DVec3;
use multires::mesh::io::{WriteOptions, read_soup, write_soup};
use multires::mesh::{HalfedgeMesh, PolygonSoup, shapes};
use multires::spline::SurfaceKind;
use multires::spline::pipeline::{FitOptions, Method, fit_mesh};
use multires::spline::samples::{smooth_surface, triangle_grid};
use serde_json::Value;

fn multires(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_multires")).args(args).output().expect("run multires")
}

fn ok(args: &[&str]) -> String {
    let out = multires(args);
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

fn fails(args: &[&str]) -> String {
    let out = multires(args);
    assert!(!out.status.success(), "{args:?} should fail");
    assert!(out.stdout.is_empty(), "{args:?}: nothing on stdout: {}", String::from_utf8_lossy(&out.stdout));
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "one line: {stderr}");
    stderr
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Writes `soup` as OFF into `dir` and returns the path.
fn write(dir: &Path, name: &str, soup: &PolygonSoup) -> PathBuf {
    let file = dir.join(name);
    write_soup(&file, soup, &WriteOptions::default()).unwrap();
    file
}

/// A hexagonal annulus: 12 triangles, two boundary loops.
fn annulus() -> PolygonSoup {
    let mut positions = Vec::new();
    for radius in [1.0, 2.0] {
        for i in 0..6 {
            let a = std::f64::consts::TAU * i as f64 / 6.0;
            positions.push(glam::DVec3::new(radius * a.cos(), radius * a.sin(), 0.0));
        }
    }
    let mut faces = Vec::new();
    for i in 0..6u32 {
        let j = (i + 1) % 6;
        faces.push([i, i + 6, j + 6]);
        faces.push([i, j + 6, j]);
    }
    PolygonSoup::from_faces(positions, faces)
}

#[test]
fn table_has_the_papers_form_for_every_surface_and_method() {
    let dir = tempfile::tempdir().unwrap();
    let grid16 = write(dir.path(), "grid16.off", &triangle_grid(16, smooth_surface));
    let grid12 = write(dir.path(), "grid12.off", &triangle_grid(12, smooth_surface));
    for (surface, mesh) in [("bezier", &grid16), ("bpatch", &grid12), ("tri-bspline", &grid16)] {
        for method in ["lspia", "pia", "seed"] {
            let out = ok(&["fit", path(mesh), "--surface", surface, "--method", method]);
            let lines: Vec<&str> = out.lines().collect();
            assert!(lines[0].contains(&format!("fitted by {method}")), "{out}");
            let header = lines
                .iter()
                .position(|l| l.split_whitespace().eq(["k", "eps_max", "eps_avg", "N_eps", "%", "seconds"]));
            let header = header.unwrap_or_else(|| panic!("no table header: {out}"));
            // Ten iterations by default, k = 1..10, five numeric columns.
            for (k, line) in lines[header + 1..header + 11].iter().enumerate() {
                let cols: Vec<f64> = line.split_whitespace().map(|c| c.parse().unwrap()).collect();
                assert_eq!(cols.len(), 5, "{line}");
                assert_eq!(cols[0], (k + 1) as f64);
                assert!(cols[1] >= cols[2] && cols[2] > 0.0, "eps_max >= eps_avg > 0: {line}");
                assert!((0.0..=100.0).contains(&cols[3]), "{line}");
            }
            assert!(out.contains("spectral radius ρ("), "{surface}/{method}: {out}");
            assert!(out.contains("least squares"), "{out}");
        }
    }
}

#[test]
fn json_matches_the_library_and_has_the_documented_keys() {
    let dir = tempfile::tempdir().unwrap();
    let soup = triangle_grid(16, smooth_surface);
    let mesh_path = write(dir.path(), "grid.off", &soup);
    let out = ok(&["fit", path(&mesh_path), "--surface", "bezier", "--iterations", "7", "--hit-tol", "1e-3", "--json"]);
    assert_eq!(out.lines().count(), 1, "one JSON object: {out}");
    let json: Value = serde_json::from_str(&out).unwrap();

    let (read, _) = read_soup(&mesh_path).unwrap();
    let mesh = HalfedgeMesh::from_soup(&read).unwrap();
    let options = FitOptions {
        surface: SurfaceKind::Bezier,
        method: Method::Lspia,
        iterations: 7,
        hit_tol: Some(1e-3),
        ..FitOptions::default()
    };
    let report = fit_mesh(&mesh, &options).unwrap();

    let iterations = json["iterations"].as_array().unwrap();
    assert_eq!(iterations.len(), 7);
    for (record, expected) in iterations.iter().zip(&report.iterations) {
        let mut keys: Vec<&str> = record.as_object().unwrap().keys().map(String::as_str).collect();
        keys.sort_unstable();
        assert_eq!(keys, ["eps_avg", "eps_max", "k", "n_eps", "seconds"]);
        assert_eq!(record["k"].as_u64().unwrap() as usize, expected.k);
        // serde_json parses floats to within one unit in the last place.
        let close = |key: &str, value: f64| {
            let got = record[key].as_f64().unwrap();
            assert!((got - value).abs() <= 4.0 * f64::EPSILON * value.abs(), "{key}: {got} vs {value}");
        };
        close("eps_max", expected.eps_max);
        close("eps_avg", expected.eps_avg);
        close("n_eps", expected.n_eps);
        assert!(record["seconds"].as_f64().unwrap() >= 0.0);
    }
    // Bounding-box diagonal of the input, computed here independently.
    let (lo, hi) = soup
        .positions
        .iter()
        .fold((glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY), |(l, h), &p| (l.min(p), h.max(p)));
    assert!((json["bbox_diag"].as_f64().unwrap() - (hi - lo).length()).abs() < 1e-15);
    assert!((json["hit_tol"].as_f64().unwrap() - 1e-3).abs() < 1e-18);
    let rho = json["spectral_radius"].as_f64().unwrap();
    assert!((rho - report.spectral_radius.unwrap()).abs() <= 4.0 * f64::EPSILON);
    assert!(rho > 0.0 && rho < 1.0);
    // N_eps is the percentage of the 153 points within hit_tol: a multiple of 100/153.
    let hits = iterations[6]["n_eps"].as_f64().unwrap() * 153.0 / 100.0;
    assert!((hits - hits.round()).abs() < 1e-9);
}

#[test]
fn tolerance_stops_at_the_first_iteration_below_it() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = write(dir.path(), "grid.off", &triangle_grid(16, smooth_surface));
    let json: Value = serde_json::from_str(&ok(&["fit", path(&mesh), "--json", "--iterations", "50"])).unwrap();
    let records = json["iterations"].as_array().unwrap();
    let target = records[4]["eps_avg"].as_f64().unwrap();
    let stopped: Value = serde_json::from_str(&ok(&[
        "fit",
        path(&mesh),
        "--json",
        "--iterations",
        "50",
        "--tolerance",
        &format!("{}", target * 1.000001),
    ]))
    .unwrap();
    let stopped = stopped["iterations"].as_array().unwrap();
    // Stops at the first iteration whose eps_avg is below the tolerance.
    assert_eq!(stopped.len(), 5, "{stopped:?}");
    assert!(stopped.last().unwrap()["eps_avg"].as_f64().unwrap() < target * 1.000001);
}

#[test]
fn plot_and_sampled_surface_are_written() {
    let dir = tempfile::tempdir().unwrap();
    let soup = triangle_grid(16, smooth_surface);
    let mesh_path = write(dir.path(), "grid.off", &soup);
    let plot = dir.path().join("conv.png");
    let surface = dir.path().join("surface.obj");
    ok(&["fit", path(&mesh_path), "--plot", path(&plot), "--out", path(&surface), "--samples", "10"]);

    let bytes = std::fs::read(&plot).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let reader = decoder.read_info().unwrap();
    let info = reader.info();
    assert_eq!((info.width, info.height), (960, 600));

    let (sampled, _) = read_soup(&surface).unwrap();
    assert_eq!((sampled.vertex_count(), sampled.face_count()), (66, 100));
    // The samples lie on the surface the library fits, and close to the data (a smooth
    // surface fitted to about 1e-3 of its size).
    let report = fit_mesh(&HalfedgeMesh::from_soup(&soup).unwrap(), &FitOptions::default()).unwrap();
    let (expected, triangles) = report.surface.sample(&report.domain, 10);
    assert_eq!(sampled.positions, expected);
    assert_eq!(sampled.face_count(), triangles.len());
    // Corners of the sampling reproduce the data's corners to the fit's accuracy.
    for corner in [soup.positions[0], soup.positions[16], soup.positions[152]] {
        let nearest = sampled.positions.iter().map(|p| (*p - corner).length()).fold(f64::INFINITY, f64::min);
        assert!(nearest < 0.02, "corner {corner}: {nearest}");
    }
}

#[test]
fn bad_input_gives_one_clear_line_and_no_output_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("surface.obj");
    let plot = dir.path().join("conv.png");
    let closed = write(dir.path(), "ico.off", &shapes::icosahedron());
    let ring = write(dir.path(), "annulus.off", &annulus());
    let grid12 = write(dir.path(), "grid12.off", &triangle_grid(12, smooth_surface));
    let grid10 = write(dir.path(), "grid10.off", &triangle_grid(10, smooth_surface));
    let quads = write(dir.path(), "quads.off", &shapes::grid(3, 3, shapes::CellKind::Quads).unwrap());
    let missing = dir.path().join("missing.off");
    // A square with an ear triangle on each side: four boundary vertices with one face
    // each, so some ear's three vertices end up on one side of the parameter triangle.
    let ears = PolygonSoup::from_faces(
        [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [0.5, -0.5], [1.5, 0.5], [0.5, 1.5], [-0.5, 0.5]]
            .map(|[x, y]| DVec3::new(x, y, 0.0))
            .to_vec(),
        [[0u32, 1, 2], [0, 2, 3], [0, 4, 1], [1, 5, 2], [2, 6, 3], [3, 7, 0]],
    );
    let ears = write(dir.path(), "ears.off", &ears);
    let cases: Vec<(Vec<&str>, &[&str])> = vec![
        (vec!["fit", path(&closed)], &["ico.off", "not a disk", "0 boundary loop", "closed"]),
        (vec!["fit", path(&closed), "--surface", "tri-bspline"], &["not a disk"]),
        (vec!["fit", path(&ring), "--surface", "tri-bspline"], &["annulus.off", "not a disk", "2 boundary loop"]),
        (vec!["fit", path(&grid12), "--reverse-levels", "3"], &["3 reverse Loop level(s) requested", "allows only 2"]),
        (vec!["fit", path(&grid10), "--surface", "bpatch"], &["allows only 1"]),
        (vec!["fit", path(&ring), "--surface", "bezier"], &["not a disk"]),
        (vec!["fit", path(&quads)], &["face", "triangle"]),
        (vec!["fit", path(&missing)], &["missing.off"]),
        (
            vec!["fit", path(&ears), "--surface", "tri-bspline", "--reverse-levels", "0"],
            &["ears.off", "face 2", "degenerate", "ear"],
        ),
        (vec!["fit", path(&grid12), "--iterations", "0"], &["iterations"]),
        (vec!["fit", path(&grid12), "--tolerance=-1"], &["tolerance", "positive"]),
        (vec!["fit", path(&grid12), "--hit-tol", "nan"], &["hit-tol"]),
        (vec!["fit", path(&grid12), "--samples", "0"], &["--samples"]),
        // Used to panic ("capacity overflow") or abort reserving one record per iteration.
        (vec!["fit", path(&grid12), "--iterations", "18446744073709551615"], &["--iterations", "1000000"]),
        (vec!["fit", path(&grid12), "--iterations", "100000000"], &["--iterations", "1000000"]),
        // Used to abort allocating `degree` knots per vertex before the degree was checked.
        (vec!["fit", path(&grid12), "--surface", "tri-bspline", "--degree", "4294967296"], &["degree 4294967296"]),
    ];
    for (mut args, needles) in cases {
        args.extend(["--out", path(&out), "--plot", path(&plot)]);
        let line = fails(&args);
        for needle in needles {
            assert!(line.contains(needle), "{args:?}: expected {needle:?} in {line}");
        }
        assert!(!out.exists() && !plot.exists(), "{args:?} wrote a file");
    }
}

#[test]
fn non_grid_disk_needs_the_triangular_bspline() {
    let dir = tempfile::tempdir().unwrap();
    // A Loop-subdivided disk that is not a triangular grid (a hexagon, 6 triangles).
    let hexagon = {
        let mut positions = vec![glam::DVec3::ZERO];
        for i in 0..6 {
            let a = std::f64::consts::TAU * i as f64 / 6.0;
            positions.push(glam::DVec3::new(a.cos(), a.sin(), 0.1 * (2.0 * a).sin()));
        }
        let faces: Vec<[u32; 3]> = (0..6u32).map(|i| [0, i + 1, (i + 1) % 6 + 1]).collect();
        PolygonSoup::from_faces(positions, faces)
    };
    let coarse = HalfedgeMesh::from_soup(&hexagon).unwrap();
    let fine = multires::loop_subdiv::forward::subdivide(
        &coarse,
        2,
        &multires::loop_subdiv::forward::LoopOptions { keep_corners: true, ..Default::default() },
    )
    .unwrap();
    let mesh = write(dir.path(), "hexagon.off", &fine.into_soup());
    let line = fails(&["fit", path(&mesh), "--surface", "bezier"]);
    assert!(line.contains("not a regular triangular grid") && line.contains("tri-bspline"), "{line}");
    let json: Value = serde_json::from_str(&ok(&["fit", path(&mesh), "--surface", "tri-bspline", "--json"])).unwrap();
    assert_eq!(json["control_points"].as_u64(), Some(7));
    let records = json["iterations"].as_array().unwrap();
    assert!(records[9]["eps_avg"].as_f64().unwrap() < records[0]["eps_avg"].as_f64().unwrap());
}

#[test]
fn divergent_iterations_are_reported_and_refused_with_strict() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = write(dir.path(), "grid.off", &triangle_grid(16, smooth_surface));
    // The seed loop with a quadratic triangular B-spline: rho(I - R N) > 1 here.
    let out = multires(&["fit", path(&mesh), "--surface", "tri-bspline", "--method", "seed", "--json"]);
    assert!(out.status.success());
    let json: Value = serde_json::from_slice(&out.stdout).unwrap();
    let rho = json["spectral_radius"].as_f64().unwrap();
    assert!(rho > 1.0, "{rho}");
    let warnings = json["warnings"].as_array().unwrap();
    assert!(warnings.iter().any(|w| w.as_str().unwrap().contains("does not converge")), "{warnings:?}");
    // The table form warns on stderr.
    let out = multires(&["fit", path(&mesh), "--surface", "tri-bspline", "--method", "seed"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("warning: spectral radius"));
    // --strict refuses before iterating, naming the spectral radius.
    let surface = dir.path().join("surface.obj");
    let line = fails(&[
        "fit",
        path(&mesh),
        "--surface",
        "tri-bspline",
        "--method",
        "seed",
        "--strict",
        "--out",
        path(&surface),
    ]);
    assert!(line.contains("seed does not converge"), "{line}");
    let named: f64 = line.split_whitespace().rev().nth(2).unwrap().parse().unwrap();
    assert!((named - rho).abs() <= 4.0 * f64::EPSILON * rho, "{line}");
    assert!(!surface.exists());
    // LSPIA on the same problem converges (its radius is below one) and is accepted.
    ok(&["fit", path(&mesh), "--surface", "tri-bspline", "--method", "lspia", "--strict"]);
}
