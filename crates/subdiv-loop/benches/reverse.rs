//! Decomposition and reconstruction cost per fine vertex at four sizes: the Stanford
//! bunny (`tests/data/bunny.obj`, slightly perturbed with a fixed seed) refined 1 to 4
//! times. Each size `L` is timed for `decompose` down to the bunny (`L` levels), the
//! full `reconstruct` back up, and Loop subdivision of the bunny to the same level
//! (`forward`), so the ratios can be read off directly. Throughput is in fine vertices.

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use mesh_topo::{HalfedgeMesh, PolygonSoup};
use subdiv_loop::pyramid::{DecomposeOptions, Levels, LoopPyramid, decompose};
use subdiv_loop::reverse::LoopOptions;

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

    // Loop subdivision of the bunny to the same level (here: reconstruction with zero
    // details, the same code path as `reconstruct`).
    let mut group = c.benchmark_group("forward");
    for (level, fine) in &fixtures {
        let zero = LoopPyramid::smooth(base.clone(), rules, *level).expect("valid");
        group.throughput(Throughput::Elements(fine.vertex_count() as u64));
        group.bench_with_input(BenchmarkId::from_parameter(level), &zero, |b, zero| {
            b.iter(|| black_box(zero).reconstruct(*level).expect("valid"))
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
