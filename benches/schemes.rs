//! Every surface scheme on the same meshes: one loop over [`SurfaceScheme::ALL`].
//!
//! Benchmark ids are `subdivide-<mesh>/<scheme>-<threads>t/<level>` with the output face
//! count as throughput; `cargo xtask bench` reads them back to print faces per second and
//! the ratio against the peer libraries it finds on the machine. Outputs above
//! [`MAX_OUTPUT_FACES`] are skipped. The Loop and Doo-Sabin defaults also run on two
//! threads; results are bit-identical for any thread count, only the time changes.
//! Doo-Sabin also runs levels 1 to 3 on a mesh of more than a million faces,
//! [`LARGE_MESH`] (group `subdivide-bunny00-loop2`), made here and written to
//! `target/bench-meshes/` for the peer drivers; it is built only when one of its
//! benchmarks is selected.
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
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use multires::loop_subdiv::forward::{LoopMesh, Subdivider};
use multires::prelude::*;

/// Largest output (faces) a benchmark is run for: level 4 of the 75k-face bunny.
const MAX_OUTPUT_FACES: usize = 20_000_000;

/// The meshes, from `tests/data/` (origins in its README).
const MESHES: [(&str, &str); 2] = [("bunny", "bunny.obj"), ("bunny00", "bunny00.off")];

/// A mesh of more than a million faces for Doo-Sabin levels 1 to 3 (the Doo-Sabin goal
/// asks for one): `bunny00.off` refined twice by Loop subdivision, 1,206,528 triangles,
/// written to `target/bench-meshes/` so that the peer drivers read the same file.
const LARGE_MESH: &str = "bunny00-loop2";

/// Largest output (faces) of a benchmark on [`LARGE_MESH`]: its Doo-Sabin level 3
/// (about 58M faces).
const LARGE_MESH_MAX_OUTPUT_FACES: usize = 60_000_000;

/// Levels 1 to 4 of `scheme` on a closed mesh of `counts` (vertices, edges, faces) with
/// their output face counts, up to the first level whose output exceeds `max_faces`.
fn levels_within_budget(
    scheme: SurfaceScheme,
    (vertices, edges, faces): (usize, usize, usize),
    max_faces: usize,
) -> impl Iterator<Item = (u32, u64)> {
    (1..=4u32)
        .map(move |level| (level, scheme.closed_face_count(vertices, edges, faces, level)))
        .take_while(move |&(_, faces)| faces <= max_faces)
        .map(|(level, faces)| (level, faces as u64))
}

/// Vertices, edges and faces of a mesh.
fn counts(mesh: &HalfedgeMesh) -> (usize, usize, usize) {
    (mesh.vertex_count(), mesh.edge_count(), mesh.face_count())
}

/// The counts after `levels` Loop steps of a closed triangle mesh of `counts`.
fn loop_counts((mut v, mut e, mut f): (usize, usize, usize), levels: u32) -> (usize, usize, usize) {
    for _ in 0..levels {
        (v, e, f) = (v + e, 2 * e + 3 * f, 4 * f);
    }
    (v, e, f)
}

/// The build directory (`CARGO_TARGET_DIR` or the workspace's `target/`).
fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("target"))
}

/// [`LARGE_MESH`], made from `bunny00` and written as OFF for the peers (shortest
/// round-trip decimals: they read the very positions we subdivide).
fn large_mesh(bunny00: &HalfedgeMesh) -> HalfedgeMesh {
    let soup = SurfaceScheme::Loop.subdivide(bunny00, 2).expect("Loop subdivision of bunny00");
    let folder = target_dir().join("bench-meshes");
    std::fs::create_dir_all(&folder).expect("target/bench-meshes");
    let path = folder.join(format!("{LARGE_MESH}.off"));
    multires::mesh::io::write_soup(&path, &soup, &Default::default()).expect("writing the large mesh");
    HalfedgeMesh::from_soup(&soup).expect("a valid mesh")
}

fn subdivide_all_schemes(c: &mut Criterion) {
    for (name, file) in MESHES {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(file);
        let (mesh, _) = multires::mesh::io::read_mesh(&path).expect("benchmark mesh");
        bench_mesh(c, name, counts(&mesh), &|| &mesh, &SurfaceScheme::ALL, MAX_OUTPUT_FACES);
        if name == "bunny00" {
            // Built the first time a benchmark on it runs (criterion runs only the
            // selected ones): it takes a few seconds.
            let large = OnceLock::new();
            let get = || large.get_or_init(|| large_mesh(&mesh));
            let large_counts = loop_counts(counts(&mesh), 2);
            bench_mesh(c, LARGE_MESH, large_counts, &get, &[SurfaceScheme::DooSabin], LARGE_MESH_MAX_OUTPUT_FACES);
        }
    }
}

/// The benchmarks of `schemes` on `mesh()` (group `subdivide-<name>`), a closed mesh of
/// `counts`, up to `max_faces` output faces.
fn bench_mesh<'a>(
    c: &mut Criterion,
    name: &str,
    counts: (usize, usize, usize),
    mesh: &dyn Fn() -> &'a HalfedgeMesh,
    schemes: &[SurfaceScheme],
    max_faces: usize,
) {
    let mut group = c.benchmark_group(format!("subdivide-{name}"));
    group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(3));
    for &scheme in schemes {
        let thread_counts: &[usize] =
            if matches!(scheme, SurfaceScheme::Loop | SurfaceScheme::DooSabin) { &[1, 2] } else { &[1] };
        for &threads in thread_counts {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
            for (level, faces) in levels_within_budget(scheme, counts, max_faces) {
                group.throughput(Throughput::Elements(faces));
                let id = BenchmarkId::new(format!("{scheme}-{threads}t"), level);
                group.bench_function(id, |b| {
                    let mesh = mesh();
                    pool.install(|| {
                        b.iter_custom(|calls| {
                            time_calls_freeing_outside(calls, || {
                                scheme.subdivide(black_box(mesh), level).expect("subdivision")
                            })
                        })
                    })
                });
            }
            if scheme == SurfaceScheme::Loop {
                // One subdivider and output per thread count, reused by every call.
                let (mut subdivider, mut out) = (Subdivider::default(), LoopMesh::default());
                for (level, faces) in levels_within_budget(scheme, counts, max_faces) {
                    group.throughput(Throughput::Elements(faces));
                    let id = BenchmarkId::new(format!("loop-reuse-{threads}t"), level);
                    group.bench_function(id, |b| {
                        let mesh = mesh();
                        pool.install(|| {
                            b.iter(|| subdivider.subdivide_into(black_box(mesh), level, &mut out).expect("subdivision"))
                        })
                    });
                }
            }
        }
    }
    group.finish();
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
