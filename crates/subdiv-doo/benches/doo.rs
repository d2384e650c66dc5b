//! Doo-Sabin benches: forward subdivision (levels 1-3) on the bunny and on a mesh of more
//! than a million faces, single-threaded and with all threads.
//!
//! Run with `cargo bench -p subdiv-doo --bench doo`. The inputs are built before timing;
//! the timed call is `subdivide` on an already built half-edge mesh (the counterpart of
//! CGAL's `DooSabin_subdivision` on a `Surface_mesh`).

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use mesh_topo::shapes::{self, CellKind};
use mesh_topo::{DVec3, HalfedgeMesh, PolygonSoup};
use subdiv_doo::{DooOptions, FaceRule, subdivide};

/// The bunny of `tests/data` (a minimal OBJ reader: positions and faces only).
fn bunny() -> HalfedgeMesh {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/data/bunny.obj");
    let text = std::fs::read_to_string(path).expect("tests/data/bunny.obj");
    let mut positions = Vec::new();
    let mut faces: Vec<Vec<u32>> = Vec::new();
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
    HalfedgeMesh::from_soup(&PolygonSoup::from_faces(positions, faces)).unwrap()
}

/// A closed triangulated torus of 1024 x 512 x 2 = 1,048,576 faces.
fn big_torus() -> HalfedgeMesh {
    HalfedgeMesh::from_soup(&shapes::torus(1024, 512, CellKind::Triangles)).unwrap()
}

fn single_thread() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap()
}

fn forward(c: &mut Criterion) {
    let one = single_thread();
    let mut group = c.benchmark_group("doo_forward");
    group.sample_size(10).measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));
    let bunny = bunny();
    for levels in 1..=3 {
        let options = DooOptions::new(FaceRule::DooSabin, levels);
        group.bench_with_input(BenchmarkId::new("bunny_1thread", levels), &levels, |b, _| {
            b.iter(|| one.install(|| subdivide(black_box(&bunny), &options).unwrap()))
        });
        group.bench_with_input(BenchmarkId::new("bunny", levels), &levels, |b, _| {
            b.iter(|| subdivide(black_box(&bunny), &options).unwrap())
        });
    }
    let torus = big_torus();
    for levels in 1..=2 {
        let options = DooOptions::new(FaceRule::DooSabin, levels);
        group.bench_with_input(BenchmarkId::new("torus1M_1thread", levels), &levels, |b, _| {
            b.iter(|| one.install(|| subdivide(black_box(&torus), &options).unwrap()))
        });
        group.bench_with_input(BenchmarkId::new("torus1M", levels), &levels, |b, _| {
            b.iter(|| subdivide(black_box(&torus), &options).unwrap())
        });
    }
    group.finish();
}

criterion_group!(benches, forward);
criterion_main!(benches);
