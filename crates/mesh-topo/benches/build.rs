//! Building the half-edge mesh from a soup (validation included), in faces per second.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use mesh_topo::HalfedgeMesh;
use std::hint::black_box;
use std::time::Duration;

mod fixtures;

fn build(c: &mut Criterion) {
    let mut group = c.benchmark_group("build");
    group.sample_size(10).measurement_time(Duration::from_secs(8));
    for (name, soup) in fixtures::soups() {
        group.throughput(Throughput::Elements(soup.face_count() as u64));
        group.bench_function(name, |b| b.iter(|| HalfedgeMesh::from_soup(black_box(&soup)).expect("valid")));
    }
    group.finish();
}

criterion_group!(benches, build);
criterion_main!(benches);
