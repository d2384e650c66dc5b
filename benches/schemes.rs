//! Every surface scheme on the same meshes: one loop over [`SurfaceScheme::ALL`].
//!
//! Benchmark ids are `subdivide-<mesh>/<scheme>-<threads>t/<level>` with the output face
//! count as throughput; `cargo xtask bench` reads them back to print faces per second and
//! the ratio against the peer libraries it finds on the machine. Outputs above
//! [`MAX_OUTPUT_FACES`] are skipped. The Loop and Doo-Sabin defaults also run on two
//! threads; results are bit-identical for any thread count, only the time changes.
//!
//! Each call is timed alone and its result is freed after the clock stops, before the
//! next call: the protocol of the peer drivers, which time one subdivision call per
//! repeat and free (or clear) its output between repeats. Criterion's
//! `iter_with_large_drop` would instead keep a whole batch of results alive, so that every
//! call of the batch writes fresh pages, which no peer's timing includes.
//!
//! Beside `loop-<threads>t`, the `loop-reuse-<threads>t` rows time
//! `forward::Subdivider::subdivide_into` called again and again into the same output, as
//! an editor, an animation or a pipeline stage that subdivides repeatedly does: after the
//! first call it allocates nothing and takes no page fault. Its output is the Loop
//! arrays themselves (the `loop` rows also build the facade's polygon soup). `cargo
//! xtask bench` compares these rows with the same peer runs as `loop`.

use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use multires::loop_subdiv::forward::{LoopMesh, Subdivider};
use multires::prelude::*;

/// Largest output (faces) a benchmark is run for: level 4 of the 75k-face bunny.
const MAX_OUTPUT_FACES: usize = 20_000_000;

/// The meshes, from `tests/data/` (origins in its README).
const MESHES: [(&str, &str); 2] = [("bunny", "bunny.obj"), ("bunny00", "bunny00.off")];

/// Levels 1 to 4 of `scheme` on `mesh` with their output face counts, up to the first
/// level whose output exceeds `MAX_OUTPUT_FACES`.
fn levels_within_budget(scheme: SurfaceScheme, mesh: &HalfedgeMesh) -> impl Iterator<Item = (u32, u64)> + '_ {
    (1..=4u32)
        .map(move |level| {
            (level, scheme.closed_face_count(mesh.vertex_count(), mesh.edge_count(), mesh.face_count(), level))
        })
        .take_while(|&(_, faces)| faces <= MAX_OUTPUT_FACES)
        .map(|(level, faces)| (level, faces as u64))
}

fn subdivide_all_schemes(c: &mut Criterion) {
    for (name, file) in MESHES {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(file);
        let (mesh, _) = multires::mesh::io::read_mesh(&path).expect("benchmark mesh");
        let mut group = c.benchmark_group(format!("subdivide-{name}"));
        group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(3));
        for scheme in SurfaceScheme::ALL {
            let thread_counts: &[usize] =
                if matches!(scheme, SurfaceScheme::Loop | SurfaceScheme::DooSabin) { &[1, 2] } else { &[1] };
            for &threads in thread_counts {
                let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
                for (level, faces) in levels_within_budget(scheme, &mesh) {
                    group.throughput(Throughput::Elements(faces));
                    let id = BenchmarkId::new(format!("{scheme}-{threads}t"), level);
                    group.bench_function(id, |b| {
                        pool.install(|| {
                            b.iter_custom(|calls| {
                                time_calls_freeing_outside(calls, || {
                                    scheme.subdivide(black_box(&mesh), level).expect("subdivision")
                                })
                            })
                        })
                    });
                }
                if scheme == SurfaceScheme::Loop {
                    // One subdivider and output per thread count, reused by every call.
                    let (mut subdivider, mut out) = (Subdivider::default(), LoopMesh::default());
                    for (level, faces) in levels_within_budget(scheme, &mesh) {
                        group.throughput(Throughput::Elements(faces));
                        let id = BenchmarkId::new(format!("loop-reuse-{threads}t"), level);
                        group.bench_function(id, |b| {
                            pool.install(|| {
                                b.iter(|| {
                                    subdivider.subdivide_into(black_box(&mesh), level, &mut out).expect("subdivision")
                                })
                            })
                        });
                    }
                }
            }
        }
        group.finish();
    }
}

/// Total time of `calls` calls of `call`, each timed alone; its result is freed after the
/// clock stops, before the next call (see the module docs).
fn time_calls_freeing_outside<T>(calls: u64, mut call: impl FnMut() -> T) -> Duration {
    let mut total = Duration::ZERO;
    for _ in 0..calls {
        let start = Instant::now();
        let result = black_box(call());
        total += start.elapsed();
        drop(result);
    }
    total
}

criterion_group!(benches, subdivide_all_schemes);
criterion_main!(benches);
