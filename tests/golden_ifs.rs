//! Golden figures of seed 003 (ALGORITHMS.md §13, §15.3), rendered as PNGs and compared
//! through point statistics (point count, bounding box, centroid, a 16 × 16 occupancy
//! map), not raw bytes. Re-bless with `MULTIRES_BLESS=1 cargo test --test golden_ifs`.
//! The PNGs are written to the target directory for inspection.

mod common;

use multires::ifs::{self, PointStats, Projection, ToneMap};

/// Renders `points` to `<target tmp>/<file>` (checked to be a PNG of the right size) and
/// returns their statistics as text.
fn render_and_summarise(file: &str, points: &[[f64; 3]]) -> String {
    let image = ifs::render_points(points, 400, 300, Projection::Xy, ToneMap::Log).unwrap();
    let bytes = image.encode_png().unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    assert_eq!(image.rgba.len(), 400 * 300 * 4);
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("golden-ifs");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(file), bytes).unwrap();
    PointStats::of(points, 16).unwrap().to_text()
}

fn preset_points(name: &str, levels: u32) -> Vec<[f64; 3]> {
    let scene = ifs::preset(name).unwrap();
    ifs::deterministic_points(&scene.ifs, scene.start.as_deref(), levels, 1 << 22).unwrap()
}

/// Seed Fig. 3: z = 0.5 + 0.5i, 12 iterations: the Lévy C curve.
#[test]
fn levy_curve_at_12_iterations() {
    let text = render_and_summarise("levy-12.png", &preset_points("levy", 12));
    common::check_golden("ifs-levy.txt", &text);
}

/// Seed Fig. 4: z = 0.5 + 0.1k i, k = 0..5, 10 iterations: segment to Lévy curve.
#[test]
fn complex_parameter_morph_at_10_iterations() {
    let mut text = String::new();
    for k in 0..=5 {
        let name = format!("complex-morph-{k}");
        text.push_str(&format!("== {name}\n"));
        text.push_str(&render_and_summarise(&format!("{name}.png"), &preset_points(&name, 10)));
    }
    common::check_golden("ifs-complex-morph.txt", &text);
}

/// The seed's "Gauss curve" (the quartic bump), deterministic from the filled triangle,
/// iterations 0, 1, 2, 3, 4, 6; and the nonlinear (polar) Sierpiński gasket.
#[test]
fn quartic_bump_iterations_and_polar_sierpinski() {
    let mut text = String::new();
    for levels in [0, 1, 2, 3, 4, 6] {
        text.push_str(&format!("== quartic-bump {levels}\n"));
        text.push_str(&render_and_summarise(
            &format!("quartic-bump-{levels}.png"),
            &preset_points("quartic-bump", levels),
        ));
    }
    text.push_str("== sierpinski-polar 7\n");
    text.push_str(&render_and_summarise("sierpinski-polar-7.png", &preset_points("sierpinski-polar", 7)));
    common::check_golden("ifs-nonlinear.txt", &text);
}
