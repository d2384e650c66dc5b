//! Loop subdivision throughput: levels 1-4 of the bunny (3.7k triangles) and of
//! `bunny00.off` (75k triangles), on a rayon pool of 1 and of 2 threads. Throughput is
//! counted in output triangles. The timed call is `forward::subdivide` from a built
//! `HalfedgeMesh` (like the CGAL and OpenMesh peers, whose mesh is built before timing);
//! `from_soup+subdivide` also times building the half-edge mesh from the face list (like
//! OpenSubdiv's topology refiner creation).

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use mesh_topo::{HalfedgeMesh, PolygonSoup};
use subdiv_loop::forward::{LoopOptions, subdivide};

/// Minimal OBJ/OFF reader for the benchmark inputs (triangles, `v`/`f` lines or OFF).
fn read_mesh(name: &str) -> PolygonSoup {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data").join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
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
                    b.iter(|| pool.install(|| subdivide(black_box(&mesh), level, &options).expect("subdivide")))
                });
                group.bench_with_input(BenchmarkId::new("from_soup+subdivide", level), &level, |b, &level| {
                    b.iter(|| {
                        pool.install(|| {
                            let mesh = HalfedgeMesh::from_soup(black_box(&soup)).expect("valid mesh");
                            subdivide(&mesh, level, &options).expect("subdivide")
                        })
                    })
                });
            }
            group.finish();
        }
    }
}

criterion_group!(benches, bench_forward);
criterion_main!(benches);
