//! Rate-distortion of Loop multiresolution compression on a real mesh.
//!
//! Reads a triangle mesh (default: the Stanford bunny of `tests/data/bunny.obj`),
//! subdivides it twice with Loop's rules, moves every vertex by a fixed-seed random
//! offset of up to `0.1%` of the bounding-box diagonal (so that every level carries
//! details, like a scanned surface), decomposes it as far as the connectivity allows
//! and prints, for each fraction of details kept, the error of the reconstruction.
//!
//! ```sh
//! cargo run --release -p subdiv-loop --example rate_distortion [MESH]
//! ```

use glam::DVec3;
use mesh_topo::HalfedgeMesh;
use subdiv_loop::forward::LoopOptions;
use subdiv_loop::pyramid::{DecomposeOptions, Levels, LoopPyramid, bounding_box_diagonal, decompose};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/data/bunny.obj").to_string());
    let (soup, _) = mesh_topo::io::read_soup(&path)?;
    let rules = LoopOptions::default();
    let mut fine = LoopPyramid::smooth(soup, rules, 2)?.reconstruct(2)?;
    let amplitude = 1e-3 * bounding_box_diagonal(&fine.positions);
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for p in &mut fine.positions {
        *p += amplitude * DVec3::new(next(), next(), next());
    }
    let mesh = HalfedgeMesh::from_soup(&fine)?;
    let pyramid = decompose(&mesh, &DecomposeOptions { rules, levels: Levels::Max, seed_vertices: Vec::new() })?;
    println!(
        "{path}: {} vertices, {} faces; {} levels; base {} vertices; {} details",
        mesh.vertex_count(),
        mesh.face_count(),
        pyramid.level_count(),
        pyramid.base.vertex_count(),
        pyramid.detail_count()
    );
    println!("| kept fraction | details kept | max error / diag | RMS error / diag |");
    println!("|---|---|---|---|");
    for row in pyramid.rate_distortion(&[1.0, 0.5, 0.25, 0.1, 0.05, 0.02, 0.01, 0.0])? {
        println!("| {} | {} | {:.3e} | {:.3e} |", row.fraction, row.kept, row.max_error, row.rms_error);
    }
    Ok(())
}
