//! The demo end to end: `multires demo --out DIR` writes every promised file, the HTML
//! page refers only to files that exist, and the reconstruction is exact.

use std::path::Path;
use std::process::Command;

/// Files the demo promises (pictures, meshes, pyramids, curves, fractals, page).
const PROMISED: &[&str] = &[
    "index.html",
    "bunny.obj",
    "bunny-info.json",
    "bunny-loop-3.ply",
    "bunny-doo-sabin-3.ply",
    "loop-levels.png",
    "doo-sabin-levels.png",
    "doo-sabin-boundary-shrink.png",
    "doo-sabin-boundary-chaikin.png",
    "bunny-loop-bumpy.mres",
    "bunny-doo-sabin-bumpy.mres",
    "loop-compression.png",
    "doo-sabin-compression.png",
    "curve-chaikin.svg",
    "curve-cubic-bspline.svg",
    "curve-four-point.svg",
    "curve-combined.svg",
    "fractal-levy.png",
    "fractal-complex-spiral.png",
    "fit-bezier.png",
];

#[test]
fn demo_writes_every_output_and_reconstructs_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("out");
    let output = Command::new(env!("CARGO_BIN_EXE_multires"))
        .args(["demo", "--out", out_dir.to_str().unwrap()])
        .output()
        .expect("run multires");
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stdout = String::from_utf8(output.stdout).unwrap();

    for file in PROMISED {
        let path = out_dir.join(file);
        let size = std::fs::metadata(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).len();
        assert!(size > 0, "{file} is empty");
    }

    // "max reconstruction error: 8.53e-16 (relative ...)": below 1e-12.
    let error: f64 = stdout
        .lines()
        .find_map(|l| l.strip_prefix("max reconstruction error: "))
        .and_then(|rest| rest.split_whitespace().next())
        .and_then(|number| number.parse().ok())
        .unwrap_or_else(|| panic!("no reconstruction error printed:\n{stdout}"));
    assert!(error < 1e-12, "reconstruction error {error}");

    // The closing summary names every step.
    let summary = &stdout[stdout.find("== summary").expect("summary table")..];
    for step in ["Loop subdivision", "Doo-Sabin subdivision", "compression", "fitting", "a curve", "a fractal", "total"]
    {
        assert!(summary.contains(step), "{step} missing from the summary:\n{summary}");
    }

    // Every picture the page shows exists, and every picture written is shown.
    let html = std::fs::read_to_string(out_dir.join("index.html")).unwrap();
    let shown: Vec<&str> = html.split("<img src=\"").skip(1).map(|s| &s[..s.find('"').unwrap()]).collect();
    for picture in &shown {
        assert!(out_dir.join(picture).is_file(), "index.html shows a missing {picture}");
    }
    for file in PROMISED.iter().filter(|f| f.ends_with(".png") || f.ends_with(".svg")) {
        assert!(shown.contains(file), "{file} is not shown in index.html");
    }
    assert!(html.contains("<pre>") && html.ends_with("</html>\n"));

    // The pyramid files are valid and rebuild the written level-3 mesh's face count.
    let bytes = std::fs::read(out_dir.join("bunny-loop-bumpy.mres")).unwrap();
    let pyramid = multires::Pyramid::from_bytes(&bytes).unwrap();
    assert_eq!((pyramid.level_count(), pyramid.base().face_count()), (3, 3674));
    assert!(Path::new(&out_dir).join("bunny-loop-3.ply").is_file());
}
