//! Golden files of Loop subdivision whose blessed copies were written from other
//! libraries' outputs: CGAL 5.5.1 and OpenSubdiv 3.5.0 (Loop's original weights; equal
//! to each other to 2e-16) and libigl 2.6.3 (Warren's weights). A digest of the vertex
//! set, independent of vertex order: counts, bounding box, first three moments and 20
//! samples of the vertices sorted by coordinates (the full sorted list for the small
//! open cube). Numbers must agree to 1e-12 relative (`common::check_golden`).

mod common;

use std::fmt::Write as _;

use glam::DVec3;
use multires::loop_subdiv::forward::{LoopOptions, subdivide_soup};
use multires::mesh::PolygonSoup;

/// Minimal OBJ/OFF reader (vertices and faces) for the meshes in `tests/data/`.
fn read(name: &str) -> PolygonSoup {
    let text = std::fs::read_to_string(common::data(name)).unwrap();
    let mut positions = Vec::new();
    let mut faces: Vec<Vec<u32>> = Vec::new();
    if name.ends_with(".off") {
        let mut tokens = text.lines().filter(|l| !l.trim_start().starts_with('#')).flat_map(str::split_whitespace);
        assert_eq!(tokens.next(), Some("OFF"));
        let mut number = || tokens.next().unwrap().parse::<f64>().unwrap();
        let (nv, nf, _) = (number() as usize, number() as usize, number());
        for _ in 0..nv {
            positions.push(DVec3::new(number(), number(), number()));
        }
        for _ in 0..nf {
            let n = number() as usize;
            faces.push((0..n).map(|_| number() as u32).collect());
        }
    } else {
        for line in text.lines() {
            let mut parts = line.split_whitespace();
            match parts.next() {
                Some("v") => {
                    let c: Vec<f64> = parts.take(3).map(|t| t.parse().unwrap()).collect();
                    positions.push(DVec3::new(c[0], c[1], c[2]));
                }
                Some("f") => faces.push(parts.map(|t| t.parse::<u32>().unwrap() - 1).collect()),
                _ => {}
            }
        }
    }
    PolygonSoup::from_faces(positions, faces)
}

/// The order-independent digest of a subdivided mesh (same text as the generator).
fn digest(name: &str, level: u32, warren: bool, reference: &str, full: bool) -> String {
    let options = if warren { LoopOptions::warren_weights() } else { LoopOptions::default() };
    let fine = subdivide_soup(&read(name), level, &options).unwrap();
    let v = &fine.positions;
    let n = v.len() as f64;
    let weights = if warren { "warren" } else { "loop" };
    let mut out = format!("mesh {name} level {level} weights {weights} reference {reference}\n");
    writeln!(out, "counts {} {}", v.len(), fine.triangles.len()).unwrap();
    let lo = v.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
    let hi = v.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
    let line = |out: &mut String, label: &str, xs: &[f64]| {
        let numbers: Vec<String> = xs.iter().map(|x| format!("{x:?}")).collect();
        writeln!(out, "{label} {}", numbers.join(" ")).unwrap();
    };
    line(&mut out, "min", &lo.to_array());
    line(&mut out, "max", &hi.to_array());
    let mean = |f: &dyn Fn(&DVec3) -> f64| v.iter().map(f).sum::<f64>() / n;
    line(&mut out, "mean", &[mean(&|p| p.x), mean(&|p| p.y), mean(&|p| p.z)]);
    line(
        &mut out,
        "second",
        &[
            mean(&|p| p.x * p.x),
            mean(&|p| p.y * p.y),
            mean(&|p| p.z * p.z),
            mean(&|p| p.x * p.y),
            mean(&|p| p.y * p.z),
            mean(&|p| p.z * p.x),
        ],
    );
    line(&mut out, "third", &[mean(&|p| p.x.powi(3)), mean(&|p| p.y.powi(3)), mean(&|p| p.z.powi(3))]);
    // Sorted by coordinates quantized to 1e-9 of the diagonal (robust to round-off).
    let q = 1e-9 * (hi - lo).length();
    let key = |p: &DVec3| ((p.x / q).round_ties_even(), (p.y / q).round_ties_even(), (p.z / q).round_ties_even());
    let mut order: Vec<usize> = (0..v.len()).collect();
    order.sort_by(|&a, &b| {
        let (ka, kb) = (key(&v[a]), key(&v[b]));
        (ka.0, ka.1, ka.2, v[a].x, v[a].y, v[a].z).partial_cmp(&(kb.0, kb.1, kb.2, v[b].x, v[b].y, v[b].z)).unwrap()
    });
    if full {
        for &i in &order {
            line(&mut out, "vertex", &v[i].to_array());
        }
    } else {
        for k in 0..20 {
            let i = k * v.len() / 20;
            line(&mut out, &format!("sample {i}"), &v[order[i]].to_array());
        }
    }
    out
}

#[test]
fn loop_bunny_matches_cgal_and_libigl() {
    let mut text = String::new();
    for level in 1..=2 {
        text += &digest("bunny.obj", level, false, "cgal", false);
        text += &digest("bunny.obj", level, true, "libigl", false);
    }
    common::check_golden("loop-bunny.txt", &text);
}

#[test]
fn loop_genus_two_matches_opensubdiv_and_libigl() {
    let text = digest("eight.off", 1, false, "opensubdiv", false) + &digest("eight.off", 1, true, "libigl", false);
    common::check_golden("loop-eight.txt", &text);
}

#[test]
fn loop_with_holes_matches_cgal() {
    common::check_golden("loop-elephant-with-holes.txt", &digest("elephant-with-holes.off", 1, false, "cgal", false));
}

#[test]
fn loop_open_cube_matches_cgal_vertex_by_vertex() {
    let text = digest("open_cube.off", 1, false, "cgal", true) + &digest("open_cube.off", 2, false, "cgal", true);
    common::check_golden("loop-open_cube.txt", &text);
}
