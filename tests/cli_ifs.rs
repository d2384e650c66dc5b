//! `multires ifs` end to end: the binary in a temporary directory.

use std::path::Path;
use std::process::{Command, Output};

fn run(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_multires")).current_dir(dir).arg("ifs").args(args).output().expect("run multires")
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

fn is_png(path: &Path) -> bool {
    std::fs::read(path).is_ok_and(|bytes| bytes.starts_with(b"\x89PNG\r\n\x1a\n"))
}

#[test]
fn levy_preset_writes_png_and_points() {
    let dir = tempfile::tempdir().unwrap();
    let output = run(
        dir.path(),
        &["--preset", "levy", "--levels", "8", "--out", "levy.png", "--out-points", "levy.txt", "--size", "120x90"],
    );
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(is_png(&dir.path().join("levy.png")));
    let text = std::fs::read_to_string(dir.path().join("levy.txt")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 2 * 256); // two start states (control points), 2^8 words
    for line in &lines {
        let values: Vec<f64> = line.split(' ').map(|v| v.parse().unwrap()).collect();
        assert_eq!(values.len(), 2);
        assert!((-0.51..=1.51).contains(&values[0]) && (-0.26..=1.01).contains(&values[1]), "{line}");
    }
}

#[test]
fn bezier_kind_with_control_points_lies_on_the_curve() {
    let dir = tempfile::tempdir().unwrap();
    let args =
        ["--kind", "bezier", "--control", "0,0 1,2 3,0", "--levels", "10", "--out", "b.png", "--out-points", "b.txt"];
    let output = run(dir.path(), &args);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = std::fs::read_to_string(dir.path().join("b.txt")).unwrap();
    // B(t) = (2t + t², 4t(1 - t)): invert x for t and compare y.
    let worst = text
        .lines()
        .map(|line| {
            let v: Vec<f64> = line.split(' ').map(|x| x.parse().unwrap()).collect();
            let t = -1.0 + (1.0 + v[0]).sqrt();
            (v[1] - 4.0 * t * (1.0 - t)).abs()
        })
        .fold(0.0, f64::max);
    assert!(worst < 1e-5, "{worst:e}");
}

#[test]
fn chaos_game_is_reproducible_for_a_seed() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["a", "b"] {
        let out = format!("{name}.png");
        let pts = format!("{name}.txt");
        let args = [
            "--preset",
            "barnsley-fern",
            "--points",
            "20000",
            "--seed",
            "9",
            "--out",
            &out,
            "--out-points",
            &pts,
            "--size",
            "64x64",
        ];
        let output = run(dir.path(), &args);
        assert!(output.status.success(), "{}", stderr(&output));
    }
    let a = std::fs::read(dir.path().join("a.txt")).unwrap();
    assert_eq!(a, std::fs::read(dir.path().join("b.txt")).unwrap());
    assert_eq!(String::from_utf8_lossy(&a).lines().count(), 20000);
    // Without --out-points the density is streamed.
    let output = run(dir.path(), &["--kind", "sierpinski", "--points", "50000", "--out", "s.png", "--size", "64x64"]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(is_png(&dir.path().join("s.png")));
}

#[test]
fn every_kind_runs() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [&[&str]; 5] = [
        &["--kind", "patch", "--control", "0,0,0 0,1,0 1,0,0 1,1,1", "--levels", "4"],
        &["--kind", "patch", "--control", "0,0 1,0 0,1", "--levels", "4"],
        &["--kind", "complex", "--z", "0.5,0.3", "--levels", "6"],
        &["--kind", "nonlinear", "--transform", "exp", "--control", "-2,-2 0,2 2,-2", "--levels", "6"],
        &["--preset", "gaussian", "--levels", "2"],
    ];
    for args in cases {
        let mut all = args.to_vec();
        all.extend(["--out", "k.png", "--size", "50x40"]);
        let output = run(dir.path(), &all);
        assert!(output.status.success(), "{args:?}: {}", stderr(&output));
        assert!(is_png(&dir.path().join("k.png")));
    }
}

/// Bad arguments: failure status and one clear line naming the problem.
#[test]
fn bad_arguments_give_one_clear_error_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&[&str], &str); 20] = [
        // |z| < 1 but |1 - z| >= 1, and |z| >= 1.
        (&["--kind", "complex", "--z", "-0.5,0"], "|1 - z| = 1.5"),
        (&["--kind", "complex", "--z", "1.2,0"], "|z| = 1.2 >= 1"),
        (&["--kind", "complex", "--z", "0,1", "--control", "0,0 1,1 2,0"], "|z| = 1 >= 1"),
        (&["--kind", "complex", "--z", "abc"], "--z"),
        // Singular (affinely dependent) control points of the seed form.
        (&["--kind", "sierpinski", "--control", "0,0 1,1 2,2"], "affinely dependent"),
        (&["--kind", "nonlinear", "--control", "-1,0 0,0 1,0"], "affinely dependent"),
        // Non-positive values for the geometric mean, and a nonlinear map leaving its domain.
        (&["--kind", "nonlinear", "--mean", "geometric", "--control", "0,1 1,2 2,-3 3,1"], "point 2"),
        (&["--kind", "nonlinear", "--mean", "harmonic", "--control", "0,1 1,0"], "point 1"),
        (&["--kind", "nonlinear", "--transform", "polar", "--control", "0,0 1,0 0,1"], "outside the domain"),
        (&["--kind", "nonlinear", "--mean", "power:x", "--control", "0,1 1,2"], "--mean power:x"),
        (&["--kind", "bezier", "--control", "0,0 1,nan"], "point 1"),
        (&["--kind", "bezier"], "needs --control"),
        (&["--kind", "spline"], "--kind spline"),
        (&["--preset", "nope"], "known: quadratic-bezier"),
        (&["--preset", "levy", "--size", "0x10"], "--size"),
        (&["--preset", "levy", "--levels", "40"], "budget"),
        // A chaos game kept in memory to be written: refused at once (not an abort on
        // the allocation, and no hours of iteration first).
        (&["--preset", "levy", "--points", "18446744073709551615", "--out-points", "p.txt"], "at most 16777216"),
        (&["--preset", "levy", "--points", "16777217", "--out-points", "p.txt"], "--points 16777217 with --out-points"),
        // Streamed into the image: used to run forever.
        (&["--kind", "bezier", "--control", "0,0 1,1 2,0", "--points", "18446744073709551615"], "at most 4294967296"),
        (&["--preset", "levy", "--points", "4294967297"], "--points 4294967297: at most 4294967296"),
    ];
    for (args, expected) in cases {
        let mut all = args.to_vec();
        all.extend(["--out", "x.png"]);
        let output = run(dir.path(), &all);
        assert!(!output.status.success(), "{args:?} should fail");
        let message = stderr(&output);
        assert_eq!(message.trim_end().lines().count(), 1, "{args:?}: {message}");
        assert!(message.contains(expected), "{args:?}: {message}");
        assert!(!dir.path().join("x.png").exists(), "{args:?} wrote an image");
        assert!(!dir.path().join("p.txt").exists(), "{args:?} wrote points");
    }
    // The geometric-mean error names the point, its value and the mean's domain.
    let output = run(
        dir.path(),
        &["--kind", "nonlinear", "--mean", "geometric", "--control", "0,1 1,2 2,-3 3,1", "--out", "x.png"],
    );
    let message = stderr(&output);
    assert!(
        message.contains("point 2: -3 is outside the domain of the geometric mean (positive numbers)"),
        "{message}"
    );
}

/// `--mean`: nonlinear subdivision of data points; the geometric mean keeps samples of
/// y = e^x on the curve, the circle-preserving mean keeps points on the circle.
#[test]
fn nonlinear_means_reproduce_exponentials_and_circles() {
    let dir = tempfile::tempdir().unwrap();
    let read = |name: &str| -> Vec<[f64; 2]> {
        std::fs::read_to_string(dir.path().join(name))
            .unwrap()
            .lines()
            .map(|line| {
                let v: Vec<f64> = line.split(' ').map(|x| x.parse().unwrap()).collect();
                [v[0], v[1]]
            })
            .collect()
    };
    let control = format!("0,1 1,{} 2,{}", 1f64.exp(), 2f64.exp());
    for scheme in ["two-point", "three-point"] {
        let args = [
            "--kind",
            "nonlinear",
            "--mean",
            "geometric",
            "--scheme",
            scheme,
            "--control",
            &control,
            "--levels",
            "5",
            "--out",
            "e.png",
            "--out-points",
            "e.txt",
        ];
        let output = run(dir.path(), &args);
        assert!(output.status.success(), "{}", stderr(&output));
        let points = read("e.txt");
        assert_eq!(points.len(), 2 * 32 + 1);
        for p in &points {
            assert!((p[1] / p[0].exp() - 1.0).abs() < 1e-13, "{scheme}: {p:?}");
        }
    }
    let args = [
        "--kind",
        "nonlinear",
        "--mean",
        "circle",
        "--center",
        "1,-1",
        "--control",
        "3,-1 1,1 -1,-1",
        "--levels",
        "4",
        "--out",
        "c.png",
        "--out-points",
        "c.txt",
    ];
    let output = run(dir.path(), &args);
    assert!(output.status.success(), "{}", stderr(&output));
    let points = read("c.txt");
    assert_eq!(points.len(), 2 * 16 + 1);
    assert!(points.iter().all(|p| ((p[0] - 1.0).hypot(p[1] + 1.0) - 2.0).abs() < 1e-13));
    // The three-point weights reach from the first to the third point of a piece: the arc
    // must span less than half a turn (0, π/4, π/2 here).
    let mut three = args.to_vec();
    three[7] = "3,-1 2.414213562373095,0.41421356237309515 1,1";
    three.extend(["--scheme", "three-point"]);
    let output = run(dir.path(), &three);
    assert!(output.status.success(), "{}", stderr(&output));
    let points = read("c.txt");
    assert_eq!(points.len(), 2 * 16 + 1); // 2n + 1 -> 4n + 1 is again 2 (count) - 1
    assert!(points.iter().all(|p| ((p[0] - 1.0).hypot(p[1] + 1.0) - 2.0).abs() < 1e-13));
}

/// The contractivity report is printed; the Bézier split parameter is honoured.
#[test]
fn contractivity_is_reported_and_split_parameter_is_used() {
    let dir = tempfile::tempdir().unwrap();
    let output = run(dir.path(), &["--preset", "levy", "--levels", "6", "--out", "l.png", "--size", "40x30"]);
    assert!(output.status.success(), "{}", stderr(&output));
    let stdout = String::from_utf8_lossy(&output.stdout);
    // Lévy: two similarities of ratio |z| = |1 - z| = 1/√2.
    assert!(stdout.contains("contractivity: largest singular value 0.707107"), "{stdout}");
    let args = [
        "--kind",
        "bezier",
        "--split",
        "0.3",
        "--control",
        "0,0 1,2 3,0",
        "--levels",
        "12",
        "--out",
        "b.png",
        "--out-points",
        "b.txt",
    ];
    let output = run(dir.path(), &args);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = std::fs::read_to_string(dir.path().join("b.txt")).unwrap();
    let worst = text
        .lines()
        .map(|line| {
            let v: Vec<f64> = line.split(' ').map(|x| x.parse().unwrap()).collect();
            let t = -1.0 + (1.0 + v[0]).sqrt();
            (v[1] - 4.0 * t * (1.0 - t)).abs()
        })
        .fold(0.0, f64::max);
    assert!(worst < 1e-2, "{worst:e}");
    let output = run(dir.path(), &["--kind", "bezier", "--split", "1.5", "--control", "0,0 1,2 3,0", "--out", "b.png"]);
    assert!(!output.status.success());
    assert!(stderr(&output).contains("parameter t = 1.5"), "{}", stderr(&output));
}
