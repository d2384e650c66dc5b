//! Golden test of the hexagon example of the interpolatory-approximating framework (seed
//! 004 Fig. 3, ALGORITHMS.md §16.5): a regular hexagon with some vertices flagged; the
//! curve passes through exactly those and approximates the others. The SVG and the refined
//! points written by `multires curve` are compared with `tests/golden/`; re-bless with
//! `cargo xtask golden --bless` (or `MULTIRES_BLESS=1 cargo test --test golden_curve`).

mod common;

use std::process::Command;

use multires::curve::io::{PointSet, parse_points};
use multires::curve::{Framework, Topology, flags_from_indices};

fn hexagon() -> Vec<[f64; 2]> {
    (0..6)
        .map(|k| {
            let t = k as f64 * std::f64::consts::PI / 3.0;
            [t.cos(), t.sin()]
        })
        .collect()
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Closed-form limit position of control point `j` (spec §16.3): the cubic B-spline limit
/// stencil `(1, 4, 1)/6` on the virtual polygon `G`, where each flagged point is replaced
/// by `q_i = (6 p_i - p_{i-1} - p_{i+1})/4` (valid for isolated flagged points).
fn closed_form_limit(p: &[[f64; 2]], flags: &[bool], j: usize) -> [f64; 2] {
    let n = p.len();
    let g = |i: usize| -> [f64; 2] {
        let i = i % n;
        if flags[i] {
            let (a, b) = (p[(i + n - 1) % n], p[(i + 1) % n]);
            [(6.0 * p[i][0] - a[0] - b[0]) / 4.0, (6.0 * p[i][1] - a[1] - b[1]) / 4.0]
        } else {
            p[i]
        }
    };
    let (a, b, c) = (g(j + n - 1), g(j), g(j + 1));
    [(a[0] + 4.0 * b[0] + c[0]) / 6.0, (a[1] + 4.0 * b[1] + c[1]) / 6.0]
}

#[test]
fn hexagon_with_flagged_vertices() {
    let polygon = hexagon();
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("hexagon.txt");
    let text: String = polygon.iter().map(|p| format!("{} {}\n", p[0], p[1])).collect();
    std::fs::write(&input, format!("# regular hexagon\n{text}")).unwrap();

    for (name, chosen) in [("0-3", &[0usize, 3][..]), ("0-2-4", &[0, 2, 4][..])] {
        let svg = dir.path().join(format!("{name}.svg"));
        let points = dir.path().join(format!("{name}.txt"));
        let interpolate = chosen.iter().map(|i| i.to_string()).collect::<Vec<_>>().join(",");
        let out = Command::new(env!("CARGO_BIN_EXE_multires"))
            .args(["curve", input.to_str().unwrap(), svg.to_str().unwrap(), "--scheme", "combined", "--closed"])
            .args(["--levels", "4", "--interpolate", &interpolate, "--out-points", points.to_str().unwrap()])
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let drawing = std::fs::read_to_string(&svg).unwrap();
        let listing = std::fs::read_to_string(&points).unwrap();
        common::check_golden(&format!("curve-hexagon-{name}.svg"), &drawing);
        common::check_golden(&format!("curve-hexagon-{name}.txt"), &listing);
        assert_eq!(drawing.matches("<circle class=\"interpolated\"").count(), chosen.len(), "one mark per flag");

        // The points: flagged vertices exactly on the refined polygon at every level.
        let PointSet::Planar(refined) = parse_points(&listing).unwrap() else { panic!("planar") };
        assert_eq!(refined.len(), 6 << 4);
        let flags = flags_from_indices(6, chosen).unwrap();
        for &i in chosen {
            assert_eq!(refined[i << 4].to_array(), polygon[i], "{name}: flagged vertex {i}");
        }

        // The limit: through the flagged vertices, inside the hexagon at the others; the
        // refinement converges to the closed-form limit positions.
        let fine = Framework::published().refine(&polygon, &flags, Topology::Closed, 10).unwrap();
        for j in 0..6 {
            let limit = closed_form_limit(&polygon, &flags, j);
            assert!(distance(fine[j << 10], limit) < 1e-6, "{name}: vertex {j} converges to its limit");
            if flags[j] {
                assert!(distance(limit, polygon[j]) < 1e-15, "{name}: vertex {j} interpolated");
            } else {
                let radius = limit[0].hypot(limit[1]);
                assert!(radius < 0.95, "{name}: vertex {j} approximated (limit radius {radius})");
            }
        }
    }
}
