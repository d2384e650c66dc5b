//! Loop subdivision throughput: levels 1-4 of the bunny (3.7k triangles) and of
//! `bunny00.off` (75k triangles), on a rayon pool of 1 and of 2 threads. Throughput is
//! counted in output triangles. The timed call is `forward::subdivide` from a built
//! `HalfedgeMesh` (like the CGAL and OpenMesh peers, whose mesh is built before timing);
//! `from_soup+subdivide` also times building the half-edge mesh from the face list (like
//! OpenSubdiv's topology refiner creation). Like the peers' drivers, the timing covers
//! the call alone: releasing the previous result is not timed.

#[path = "../examples/support/mesh_file.rs"]
mod mesh_file;

use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use mesh_topo::{HalfedgeMesh, PolygonSoup};
use subdiv_loop::forward::{LoopOptions, subdivide};

fn read_mesh(name: &str) -> PolygonSoup {
    mesh_file::read_mesh(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data").join(name))
}

fn bench_forward(c: &mut Criterion) {
    let options = LoopOptions::default();
    for name in ["bunny.obj", "bunny00.off"] {
        let soup = read_mesh(name);
        let mesh = HalfedgeMesh::from_soup(&soup).expect("valid mesh");
        for threads in [1usize, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
            let mut group = c.benchmark_group(format!("loop/{name}/threads{threads}"));
            group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(4));
            for level in 1..=4u32 {
                group.throughput(Throughput::Elements(mesh.face_count() as u64 * 4u64.pow(level)));
                group.bench_with_input(BenchmarkId::new("subdivide", level), &level, |b, &level| {
                    b.iter_custom(|iters| {
                        pool.install(|| {
                            timed(iters, || subdivide(black_box(&mesh), level, &options).expect("subdivide"))
                        })
                    })
                });
                group.bench_with_input(BenchmarkId::new("from_soup+subdivide", level), &level, |b, &level| {
                    b.iter_custom(|iters| {
                        pool.install(|| {
                            timed(iters, || {
                                let mesh = HalfedgeMesh::from_soup(black_box(&soup)).expect("valid mesh");
                                subdivide(&mesh, level, &options).expect("subdivide")
                            })
                        })
                    })
                });
            }
            group.finish();
        }
    }
}

/// Total time of `iters` calls of `run`, each result dropped after its clock stops.
fn timed<R>(iters: u64, mut run: impl FnMut() -> R) -> Duration {
    let mut total = Duration::ZERO;
    for _ in 0..iters {
        let start = Instant::now();
        let result = black_box(run());
        total += start.elapsed();
        drop(result);
    }
    total
}

criterion_group!(benches, bench_forward);
criterion_main!(benches);
