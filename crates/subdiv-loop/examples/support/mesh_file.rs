//! Minimal OBJ/OFF reading and OBJ writing for the examples and benches (vertices and
//! faces only; the workspace's full readers live in `mesh_topo::io`).

#![allow(dead_code)]

use std::fmt::Write as _;
use std::path::Path;

use glam::DVec3;
use mesh_topo::PolygonSoup;

/// Reads an OBJ (`v`/`f` lines) or OFF file.
pub fn read_mesh(path: &Path) -> PolygonSoup {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut positions = Vec::new();
    let mut faces: Vec<Vec<u32>> = Vec::new();
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("off")) {
        let mut tokens = text.lines().filter(|l| !l.trim_start().starts_with('#')).flat_map(str::split_whitespace);
        assert_eq!(tokens.next(), Some("OFF"));
        let mut number = || tokens.next().expect("OFF: truncated").parse::<f64>().expect("OFF: number");
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
                    let c: Vec<f64> = parts.take(3).map(|t| t.parse().expect("OBJ: number")).collect();
                    positions.push(DVec3::new(c[0], c[1], c[2]));
                }
                Some("f") => faces.push(
                    parts.map(|t| t.split('/').next().unwrap().parse::<u32>().expect("OBJ: index") - 1).collect(),
                ),
                _ => {}
            }
        }
    }
    PolygonSoup::from_faces(positions, faces)
}

/// Writes positions (shortest round-trip decimals) and triangles as OBJ.
pub fn write_obj(path: &Path, positions: &[DVec3], triangles: &[[u32; 3]]) {
    let mut text = String::with_capacity(40 * positions.len() + 24 * triangles.len());
    for p in positions {
        writeln!(text, "v {:?} {:?} {:?}", p.x, p.y, p.z).unwrap();
    }
    for t in triangles {
        writeln!(text, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1).unwrap();
    }
    std::fs::write(path, text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
}
