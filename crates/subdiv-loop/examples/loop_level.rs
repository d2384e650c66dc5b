//! Times `forward::subdivide` on a mesh file and reports the output size, for timing
//! and peak-memory measurements from outside (`/usr/bin/time -v`).
//!
//! `cargo run --release --example loop_level -- MESH.off LEVEL [THREADS] [REPEATS]`

use std::path::Path;
use std::time::Instant;

use glam::DVec3;
use mesh_topo::{HalfedgeMesh, PolygonSoup};
use subdiv_loop::forward::{LoopOptions, subdivide};

/// Minimal OBJ/OFF reader for the benchmark inputs (triangles, `v`/`f` lines or OFF).
fn read_mesh(name: &str) -> PolygonSoup {
    let path = Path::new(name);
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut positions = Vec::new();
    let mut faces: Vec<Vec<u32>> = Vec::new();
    if name.ends_with(".off") {
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

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: loop_level MESH LEVEL [THREADS] [REPEATS]");
        std::process::exit(2);
    }
    let level: u32 = args[2].parse().expect("LEVEL");
    let threads: usize = args.get(3).map_or(1, |t| t.parse().expect("THREADS"));
    let repeats: usize = args.get(4).map_or(1, |t| t.parse().expect("REPEATS"));
    let soup = read_mesh(&args[1]);
    let mesh = HalfedgeMesh::from_soup(&soup).expect("valid mesh");
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
    let mut best = f64::INFINITY;
    for _ in 0..repeats {
        let start = Instant::now();
        let fine = pool.install(|| subdivide(&mesh, level, &LoopOptions::default()).expect("subdivide"));
        let seconds = start.elapsed().as_secs_f64();
        best = best.min(seconds);
        let bytes = fine.positions.len() * 24 + fine.triangles.len() * 12;
        println!(
            "level {level} threads {threads}: {} vertices, {} faces, {:.1} MB output, {:.4} s ({:.2} M faces/s)",
            fine.vertex_count(),
            fine.face_count(),
            bytes as f64 / 1e6,
            seconds,
            fine.face_count() as f64 / seconds / 1e6
        );
    }
    println!("best {best:.4} s");
}
