//! Golden files of Doo-Sabin subdivision: vertex sets compared with references made
//! outside this repository (numbers within 1e-12 relative).
//!
//! - `doo-sabin-*`: the original weights, against CGAL 5.5 `DooSabin_subdivision` (its
//!   output files, sorted the same way). Small meshes store every vertex; big ones store
//!   counts, bounding box, mean, second moments and 32 vertices sampled from the sorted
//!   list.
//! - `doo-simple-*`: the simple averaging variant, against an independent numpy script
//!   that averages the vertex, its two edge midpoints and the face centroid literally.
//!
//! Vertices are sorted by their coordinates quantized to 1e-9 of the input's bounding-box
//! diagonal, then exactly, so that rounding noise cannot reorder them. Re-bless with
//! `MULTIRES_BLESS=1 cargo test --test golden_doo` (and review the diff: the blessed text
//! must stay equal to the reference's).

mod common;

use std::collections::BTreeMap;
use std::fmt::Write;

use multires::doo::{DooOptions, FaceRule, subdivide_soup};
use multires::mesh::{DVec3, PolygonSoup};

/// Minimal OFF / OBJ reader for the test meshes (positions and polygon faces only).
fn read_mesh(name: &str) -> PolygonSoup {
    let text = std::fs::read_to_string(common::data(name)).unwrap();
    let mut positions = Vec::new();
    let mut faces: Vec<Vec<u32>> = Vec::new();
    if name.ends_with(".obj") {
        for line in text.lines() {
            let mut parts = line.split_whitespace();
            match parts.next() {
                Some("v") => {
                    let c: Vec<f64> = parts.take(3).map(|t| t.parse().unwrap()).collect();
                    positions.push(DVec3::new(c[0], c[1], c[2]));
                }
                Some("f") => {
                    faces.push(parts.map(|t| t.split('/').next().unwrap().parse::<u32>().unwrap() - 1).collect())
                }
                _ => {}
            }
        }
    } else {
        let mut tokens = text
            .lines()
            .map(|l| l.split('#').next().unwrap())
            .flat_map(str::split_whitespace)
            .skip_while(|t| *t == "OFF");
        let mut next = || tokens.next().unwrap();
        let (nv, nf): (usize, usize) = (next().parse().unwrap(), next().parse().unwrap());
        next();
        for _ in 0..nv {
            let c: Vec<f64> = (0..3).map(|_| next().parse().unwrap()).collect();
            positions.push(DVec3::new(c[0], c[1], c[2]));
        }
        for _ in 0..nf {
            let n: usize = next().parse().unwrap();
            faces.push((0..n).map(|_| next().parse().unwrap()).collect());
        }
    }
    PolygonSoup::from_faces(positions, faces)
}

fn diagonal(points: &[DVec3]) -> f64 {
    let (lo, hi) = points.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    (hi - lo).length()
}

/// The golden text of a mesh: counts, face-size histogram, then every vertex (`full`) or
/// a digest.
fn golden_text(title: &str, soup: &PolygonSoup, input_diagonal: f64, full: bool) -> String {
    let mut text = format!("{title}\nvertices {}\nfaces {}\nsizes", soup.vertex_count(), soup.face_count());
    let mut sizes = BTreeMap::new();
    for face in soup.faces() {
        *sizes.entry(face.len()).or_insert(0usize) += 1;
    }
    for (size, count) in sizes {
        write!(text, " {size}:{count}").unwrap();
    }
    text.push('\n');
    let q = 1e9 / input_diagonal;
    let key =
        |p: &DVec3| [(p.x * q + 0.5).floor() as i64, (p.y * q + 0.5).floor() as i64, (p.z * q + 0.5).floor() as i64];
    let mut points = soup.positions.clone();
    points.sort_by(|a, b| key(a).cmp(&key(b)).then(a.to_array().partial_cmp(&b.to_array()).unwrap()));
    let line = |p: DVec3| format!("{:?} {:?} {:?}", p.x, p.y, p.z);
    if full {
        for &p in &points {
            writeln!(text, "{}", line(p)).unwrap();
        }
    } else {
        let n = points.len() as f64;
        let (lo, hi) =
            points.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let mean = points.iter().copied().sum::<DVec3>() / n;
        let moment = |f: &dyn Fn(&DVec3) -> f64| points.iter().map(f).sum::<f64>() / n;
        let moments = [
            moment(&|p| p.x * p.x),
            moment(&|p| p.y * p.y),
            moment(&|p| p.z * p.z),
            moment(&|p| p.x * p.y),
            moment(&|p| p.y * p.z),
            moment(&|p| p.z * p.x),
        ];
        writeln!(text, "bbox_min {}", line(lo)).unwrap();
        writeln!(text, "bbox_max {}", line(hi)).unwrap();
        writeln!(text, "mean {}", line(mean)).unwrap();
        writeln!(text, "moments {}", moments.map(|m| format!("{m:?}")).join(" ")).unwrap();
        for s in 0..32 {
            let i = s * points.len() / 32;
            writeln!(text, "sample {i} {}", line(points[i])).unwrap();
        }
    }
    text
}

fn check(rule: FaceRule, mesh: &str, level: u32, full: bool) {
    let soup = read_mesh(mesh);
    let fine = subdivide_soup(&soup, &DooOptions::new(rule, level)).unwrap().into_soup();
    let stem = mesh.split('.').next().unwrap();
    let title = format!("{} {stem} L{level}", rule.name());
    let text = golden_text(&title, &fine, diagonal(&soup.positions), full);
    common::check_golden(&format!("{}-{stem}-L{level}.txt", rule.name()), &text);
}

#[test]
fn doo_sabin_matches_cgal_on_small_meshes() {
    for (mesh, levels) in [("cube_poly.off", 1..=3), ("torus_quad.off", 1..=2), ("double-torus-example.off", 1..=1)] {
        for level in levels {
            check(FaceRule::DooSabin, mesh, level, true);
        }
    }
    check(FaceRule::DooSabin, "eight.off", 1, true);
}

#[test]
fn doo_sabin_matches_cgal_digests() {
    check(FaceRule::DooSabin, "double-torus-example.off", 2, false);
    check(FaceRule::DooSabin, "double-torus-example.off", 3, false);
    check(FaceRule::DooSabin, "torus_quad.off", 3, false);
    check(FaceRule::DooSabin, "eight.off", 2, false);
    for level in 1..=3 {
        check(FaceRule::DooSabin, "bunny.obj", level, false);
    }
}

#[test]
fn simple_variant_matches_its_reference_and_differs_on_triangles() {
    check(FaceRule::Simple, "cube_poly.off", 1, true);
    check(FaceRule::Simple, "eight.off", 1, false);
    check(FaceRule::Simple, "bunny.obj", 1, false);
    // On triangles the two rules differ (by a visible amount); on quads they agree.
    let bunny = read_mesh("bunny.obj");
    let doo = subdivide_soup(&bunny, &DooOptions::new(FaceRule::DooSabin, 1)).unwrap();
    let simple = subdivide_soup(&bunny, &DooOptions::new(FaceRule::Simple, 1)).unwrap();
    let diag = diagonal(&bunny.positions);
    let gap = doo.positions().iter().zip(simple.positions()).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
    assert!(gap > 1e-4 * diag, "gap {gap}");
    let torus = read_mesh("torus_quad.off");
    let doo = subdivide_soup(&torus, &DooOptions::new(FaceRule::DooSabin, 2)).unwrap();
    let simple = subdivide_soup(&torus, &DooOptions::new(FaceRule::Simple, 2)).unwrap();
    assert_eq!(doo.positions(), simple.positions());
}
