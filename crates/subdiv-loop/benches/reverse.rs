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
//!
//! Ratios are only meaningful within one run (the machine is shared): compare
//! `decompose/L` with `forward_mesh/L` and `reconstruct/L` with `forward_soup/L`.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use mesh_topo::{HalfedgeMesh, PolygonSoup};
use subdiv_loop::forward::{LoopOptions, subdivide, subdivide_soup};
use subdiv_loop::pyramid::{DecomposeOptions, Levels, LoopPyramid, decompose};

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
    let mut soup = read_obj(&std::fs::read_to_string(path).expect("tests/data/bunny.obj"));
    // Fixed-seed perturbation so that every level has non-zero details.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for p in &mut soup.positions {
        *p += 1e-3 * DVec3::new(next(), next(), next());
    }
    soup
}

fn benches(c: &mut Criterion) {
    let rules = LoopOptions::default();
    let base = bunny();
    let smooth = LoopPyramid::smooth(base.clone(), rules, 4).expect("bunny is a triangle mesh");
    // Level L: the bunny refined L times, decomposed back to the bunny (L levels).
    let fixtures: Vec<(usize, HalfedgeMesh)> =
        (1..=4).map(|level| (level, smooth.reconstruct_mesh(level).expect("refined bunny"))).collect();

    let mut group = c.benchmark_group("decompose");
    for (level, fine) in &fixtures {
        let options = DecomposeOptions { rules, levels: Levels::Count(*level), seed_vertex: None };
        group.throughput(Throughput::Elements(fine.vertex_count() as u64));
        group.bench_with_input(BenchmarkId::from_parameter(level), fine, |b, fine| {
            b.iter(|| decompose(black_box(fine), &options).expect("Loop mesh"))
        });
    }
    group.finish();

    let mut group = c.benchmark_group("reconstruct");
    for (level, fine) in &fixtures {
        let options = DecomposeOptions { rules, levels: Levels::Count(*level), seed_vertex: None };
        let pyramid = decompose(fine, &options).expect("Loop mesh");
        group.throughput(Throughput::Elements(fine.vertex_count() as u64));
        group.bench_with_input(BenchmarkId::from_parameter(level), &pyramid, |b, pyramid| {
            b.iter(|| black_box(pyramid).reconstruct(*level).expect("valid pyramid"))
        });
    }
    group.finish();

    // Loop subdivision of the bunny to the same level, by the forward module: from a
    // built half-edge mesh (what `decompose` starts from) and from a soup, validated
    // first (what `reconstruct` starts from: the base mesh of a pyramid).
    let mut group = c.benchmark_group("forward_mesh");
    let bunny_mesh = HalfedgeMesh::from_soup(&base).expect("valid");
    for (level, fine) in &fixtures {
        group.throughput(Throughput::Elements(fine.vertex_count() as u64));
        group.bench_with_input(BenchmarkId::from_parameter(level), &bunny_mesh, |b, bunny| {
            b.iter(|| subdivide(black_box(bunny), *level as u32, &rules).expect("valid"))
        });
    }
    group.finish();
    let mut group = c.benchmark_group("forward_soup");
    for (level, fine) in &fixtures {
        group.throughput(Throughput::Elements(fine.vertex_count() as u64));
        group.bench_with_input(BenchmarkId::from_parameter(level), &base, |b, bunny| {
            b.iter(|| subdivide_soup(black_box(bunny), *level as u32, &rules).expect("valid"))
        });
    }
    group.finish();
}

criterion_group! {
    name = reverse;
    config = Criterion::default().sample_size(10).measurement_time(std::time::Duration::from_secs(3));
    targets = benches
}
criterion_main!(reverse);
