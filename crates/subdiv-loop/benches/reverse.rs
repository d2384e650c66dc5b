//! Decomposition and reconstruction cost per fine vertex at four sizes: the Stanford
//! bunny (`tests/data/bunny.obj`, slightly perturbed with a fixed seed) refined 1 to 4
//! times. Each size `L` is timed for `decompose` down to the bunny (`L` levels), the
//! full `reconstruct` back up, and Loop subdivision of the bunny to the same level, so
//! the ratios can be read off directly. Throughput is in fine vertices.
//!
//! # What "the forward subdivision of the same size" is
//! The goal (decompose and reconstruct cost at most 1.5 times the forward subdivision
//! of the same size, flat per fine vertex) compares operations that produce or consume
//! the same fine mesh (same fine vertex count) and start from the data structure the
//! user holds:
//! - `decompose` (fine `HalfedgeMesh` to a pyramid) against `forward_mesh` (Loop
//!   subdivision of the coarse `HalfedgeMesh` to the fine mesh). Both read a built
//!   half-edge mesh; the one of `decompose` is the fine mesh, whose structure it must
//!   also detect, so it reads `4^L` times more input than `forward_mesh`.
//! - `reconstruct` (pyramid, whose base is a soup, to the fine soup) against
//!   `forward_soup` (Loop subdivision from the coarse soup, validated first as
//!   `reconstruct` validates its base mesh).
//! - `reconstruct_prepared` (pyramid with its base mesh built, `LoopPyramid::prepare`)
//!   against `forward_mesh`.
//! - `decompose_soup` (fine soup to a pyramid, as from a file: the canonical soup is
//!   read from its face list, no half-edge mesh built) against `forward_soup`, both
//!   starting from a soup.
//!
//! What each side writes: `decompose` a pyramid (the base soup, one detail per coarse
//! edge of every level), `forward_mesh` and `forward_soup` a `LoopMesh` (fine positions
//! and triangles), `reconstruct` a `PolygonSoup` (the same positions and triangles, as
//! indices, plus one offset per face, which the `LoopMesh` does not have: a small extra
//! pass that comes with the return type, counted against `reconstruct`).
//!
//! # Meshes in another order
//! The refined bunny is written by the forward subdivision, so it is in the canonical
//! order and `decompose` takes the fast path of such meshes. A mesh written by another
//! tool is numbered otherwise: `decompose_renumbered` times `decompose` of the same fine
//! mesh with its vertices and faces renumbered at random and its faces rotated
//! (`mesh_topo::testing::scramble`, seed 7), which takes the general path (detection by
//! a search over coarse faces, the level renumbered into the canonical order and
//! reversed by the canonical path, at every level, since each coarse mesh keeps the
//! fine numbering's order). Its counterpart `forward_renumbered` is Loop subdivision of
//! the bunny renumbered the same way to the same level (scattered reads on both sides).
//!
//! # One level
//! `decompose_one_level` reverses the last step alone (to the mesh one level coarser)
//! and `forward_one_level` refines that coarser mesh, given as a `HalfedgeMesh`, by one
//! step: the same fine mesh written and read, each side starting from a built half-edge
//! mesh, as in the Doo-Sabin bench. This is the "forward subdivision of the same size"
//! for one level; `forward_mesh` is cheaper per fine vertex than it (it builds only the
//! bunny's connectivity and refines the levels above by index arithmetic), so the
//! `decompose` / `forward_mesh` ratio is the stricter of the two.
//!
//! # Meshes that read several ways
//! Group `regular_torus` times one level of a refined torus (every valence regular, so
//! it has several readings and the automatic choice compares them) with and without a
//! seed vertex, in the canonical order and renumbered, beside the forward step to it;
//! the `exact_` rows time the torus refined exactly (zero details), whose first exact
//! reading settles the choice. The moved torus's readings are compared by their
//! one-pass sums (from its canonical reading, or renumbered from the first reading
//! found), which find one clearly the best, so no other is reversed.
//!
//! Ratios are only meaningful within one run (the machine is shared): group `levelL`
//! times the operations of size `L` back to back; compare `levelL/decompose` with
//! `levelL/forward_mesh`, `levelL/decompose_renumbered` with
//! `levelL/forward_renumbered`, `levelL/reconstruct` with `levelL/forward_soup` and
//! `levelL/reconstruct_prepared` with `levelL/forward_mesh`. The figures in the README
//! are for one thread (`RAYON_NUM_THREADS=1`).

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use mesh_topo::shapes::{self, CellKind};
use mesh_topo::testing::scramble;
use mesh_topo::{HalfedgeMesh, PolygonSoup};
use subdiv_loop::forward::{LoopOptions, subdivide, subdivide_soup};
use subdiv_loop::pyramid::{DecomposeOptions, Levels, LoopPyramid, decompose, decompose_soup};

/// Minimal OBJ reader for the benchmark fixture (`v` and triangular `f` lines only).
fn read_obj(text: &str) -> PolygonSoup {
    let mut positions = Vec::new();
    let mut faces = Vec::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let c: Vec<f64> = words.take(3).map(|w| w.parse().expect("coordinate")).collect();
                positions.push(DVec3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let f: Vec<u32> =
                    words.map(|w| w.split('/').next().unwrap().parse::<u32>().expect("index") - 1).collect();
                faces.push(f);
            }
            _ => {}
        }
    }
    PolygonSoup::from_faces(positions, faces)
}

fn bunny() -> PolygonSoup {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/data/bunny.obj");
    read_obj(&std::fs::read_to_string(path).expect("tests/data/bunny.obj"))
}

/// `positions` moved at random (fixed seed) by up to `amount / 2` per coordinate.
fn jitter(positions: &mut [DVec3], amount: f64) {
    let mut state = 0x9e37_79b9_7f4a_7c15u64 ^ positions.len() as u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for p in positions {
        *p += amount * DVec3::new(next(), next(), next());
    }
}

fn benches(c: &mut Criterion) {
    let rules = LoopOptions::default();
    let base = bunny();
    let bunny_mesh = HalfedgeMesh::from_soup(&base).expect("valid");
    let smooth = LoopPyramid::smooth(base.clone(), rules, 4).expect("bunny is a triangle mesh");
    // Level L: the bunny refined L times, decomposed back to the bunny (L levels). The
    // four operations of one size run back to back, so that the compared figures see
    // the same load.
    for level in 1..=4 {
        // Every fine vertex moved, so that every level has non-zero details (a refinement
        // of the bunny alone reverses to zero details).
        let mut fine = smooth.reconstruct_mesh(level).expect("refined bunny");
        jitter(fine.positions_mut(), 1e-4);
        let options = DecomposeOptions { rules, levels: Levels::Count(level), seed_vertices: Vec::new() };
        let pyramid = decompose(&fine, &options).expect("Loop mesh");
        let mut group = c.benchmark_group(format!("level{level}"));
        group.throughput(Throughput::Elements(fine.vertex_count() as u64));
        group.bench_function("decompose", |b| b.iter(|| decompose(black_box(&fine), &options).expect("Loop mesh")));
        group.bench_function("forward_mesh", |b| {
            b.iter(|| subdivide(black_box(&bunny_mesh), level as u32, &rules).expect("valid"))
        });
        group.bench_function("reconstruct", |b| {
            b.iter(|| black_box(&pyramid).reconstruct(level).expect("valid pyramid"))
        });
        // From a soup, as read from a file: the fine faces read as they are.
        let fine_soup = fine.to_soup();
        group.bench_function("decompose_soup", |b| {
            b.iter(|| decompose_soup(black_box(&fine_soup), &options).expect("Loop mesh"))
        });
        group.bench_function("forward_soup", |b| {
            b.iter(|| subdivide_soup(black_box(&base), level as u32, &rules).expect("valid"))
        });
        let prepared = pyramid.prepare().expect("valid pyramid");
        group.bench_function("reconstruct_prepared", |b| {
            b.iter(|| black_box(&prepared).reconstruct(level).expect("valid pyramid"))
        });
        // The same fine mesh in another order (general path), and its forward counterpart.
        let renumbered = HalfedgeMesh::from_soup(&scramble(fine.to_soup(), 7, 0.0)).expect("valid");
        group.bench_function("decompose_renumbered", |b| {
            b.iter(|| decompose(black_box(&renumbered), &options).expect("Loop mesh"))
        });
        let base_renumbered = HalfedgeMesh::from_soup(&scramble(base.clone(), 7, 0.0)).expect("valid");
        group.bench_function("forward_renumbered", |b| {
            b.iter(|| subdivide(black_box(&base_renumbered), level as u32, &rules).expect("valid"))
        });
        // One level: the last step alone, both sides starting from a built half-edge
        // mesh (the finest one for `decompose`, the one below it for the forward step),
        // the pair the Doo-Sabin bench times. Unlike `forward_mesh`, which builds the
        // small bunny's connectivity and refines by index arithmetic from there, the
        // forward step here reads the connectivity of a mesh a quarter the fine size.
        let one_level = DecomposeOptions { levels: Levels::Count(1), ..options };
        let below = HalfedgeMesh::from_soup(&smooth.reconstruct(level - 1).expect("refined bunny")).expect("valid");
        group.bench_function("decompose_one_level", |b| {
            b.iter(|| decompose(black_box(&fine), &one_level).expect("Loop mesh"))
        });
        group.bench_function("forward_one_level", |b| {
            b.iter(|| subdivide(black_box(&below), 1, &rules).expect("valid"))
        });
        group.finish();
    }
}

/// A mesh whose valences are all regular reads several ways: a torus of 128 x 64 x 2
/// triangles refined twice (131 072 vertices), perturbed, one level decomposed with the
/// automatic choice among its readings and with a seed vertex, in the canonical order
/// and renumbered, next to the forward step to it. The automatic rows pay the choice.
fn regular(c: &mut Criterion) {
    let rules = LoopOptions::default();
    let torus = shapes::torus(128, 64, CellKind::Triangles).expect("torus");
    let mut smooth = LoopPyramid::smooth(torus, rules, 2).expect("a triangle mesh");
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for detail in smooth.levels.iter_mut().flat_map(|level| level.details.iter_mut()) {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        *detail = DVec3::splat((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 1e-3;
    }
    let fine = HalfedgeMesh::from_soup(&smooth.reconstruct(2).expect("refined torus")).expect("valid");
    let below = HalfedgeMesh::from_soup(&smooth.reconstruct(1).expect("refined torus")).expect("valid");
    let renumbered = HalfedgeMesh::from_soup(&scramble(fine.to_soup(), 7, 0.0)).expect("valid");
    // The same torus refined exactly (all details zero): its first reading is settled.
    let exact = HalfedgeMesh::from_soup(
        &LoopPyramid::smooth(shapes::torus(128, 64, CellKind::Triangles).expect("torus"), rules, 2)
            .and_then(|pyramid| pyramid.reconstruct(2))
            .expect("refined torus"),
    )
    .expect("valid");
    let exact_renumbered = HalfedgeMesh::from_soup(&scramble(exact.to_soup(), 7, 0.0)).expect("valid");
    let automatic = DecomposeOptions { rules, levels: Levels::Count(1), seed_vertices: Vec::new() };
    let seeded = DecomposeOptions { seed_vertices: vec![0], ..automatic.clone() };
    let mut group = c.benchmark_group("regular_torus");
    group.throughput(Throughput::Elements(fine.vertex_count() as u64));
    group.bench_function("forward_one_level", |b| b.iter(|| subdivide(black_box(&below), 1, &rules).expect("valid")));
    for (name, mesh) in [
        ("canonical", &fine),
        ("renumbered", &renumbered),
        ("exact_canonical", &exact),
        ("exact_renumbered", &exact_renumbered),
    ] {
        group.bench_function(format!("decompose_{name}"), |b| {
            b.iter(|| decompose(black_box(mesh), &automatic).expect("Loop mesh"))
        });
        group.bench_function(format!("decompose_{name}_seeded"), |b| {
            b.iter(|| decompose(black_box(mesh), &seeded).expect("Loop mesh"))
        });
    }
    group.finish();
}

criterion_group! {
    name = reverse;
    config = Criterion::default().sample_size(10).measurement_time(std::time::Duration::from_secs(3));
    targets = benches, regular
}
criterion_main!(reverse);
