//! Runs `forward::subdivide` on a mesh file: timing, output size, optional OBJ output.
//! Used for timing and peak-memory measurements from outside (`/usr/bin/time -v`) and
//! to produce outputs for comparisons with other libraries.
//!
//! `cargo run --release --example loop_level -- MESH LEVEL [--threads T] [--repeats R]
//! [--out OUT.obj] [--warren] [--keep-corners] [--from-soup] [--reuse]`
//!
//! With `--from-soup` the timed call also builds the half-edge mesh from the face list
//! (as OpenSubdiv's timing includes building its topology refiner). With `--reuse` the
//! repeats call `Subdivider::subdivide_into` into one output, so every call after the
//! first reuses the memory of the one before (the first call is reported apart). The
//! last line gives the process's peak resident memory (Linux `VmHWM`, reset once the input
//! mesh is built) and the output size.
//!
//! The peak counts what the allocator keeps resident, not only what the subdivision
//! holds. Under glibc, whose mmap threshold grows as large blocks are freed (as they are
//! while the input is read), the base level's arrays, built on the worker thread, come
//! from the heap of its arena and stay resident once freed. `subdivide` writes the base
//! level's triangles in the memory of the finest level of the same parity (the output,
//! for an even count); the rest of the base level (links, starts, the half-edge map,
//! about 2.3 MB for `bunny00.off`) is what stays: (peak - before) / output read 1.46,
//! 1.49, 1.44 and 1.43 at levels 1-4 of `bunny00.off` on one thread (1.53 at level 2
//! before the triangles were handed on), and 1.31, 1.43, 1.42 and 1.42 with
//! `MALLOC_MMAP_THRESHOLD_=131072` (the threshold fixed at its default). The pool's
//! threads start, and allocate once, before the peak is reset.

#[path = "support/mesh_file.rs"]
mod mesh_file;

use std::path::Path;
use std::time::Instant;

use mesh_topo::HalfedgeMesh;
use subdiv_loop::forward::{LoopMesh, LoopOptions, Subdivider, VertexWeights, subdivide};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 2 {
        eprintln!(
            "usage: loop_level MESH LEVEL [--threads T] [--repeats R] [--out OUT.obj] [--warren] [--keep-corners] \
             [--from-soup] [--reuse]"
        );
        std::process::exit(2);
    }
    let level: u32 = args[1].parse().expect("LEVEL");
    let value = |flag: &str| args.iter().position(|a| a == flag).map(|i| args[i + 1].clone());
    let threads: usize = value("--threads").map_or(1, |t| t.parse().expect("--threads"));
    let repeats: usize = value("--repeats").map_or(1, |t| t.parse().expect("--repeats"));
    let options = LoopOptions {
        weights: if args.iter().any(|a| a == "--warren") { VertexWeights::Warren } else { VertexWeights::Loop },
        keep_corners: args.iter().any(|a| a == "--keep-corners"),
    };
    let soup = mesh_file::read_mesh(Path::new(&args[0]));
    let from_soup = args.iter().any(|a| a == "--from-soup");
    let mesh = HalfedgeMesh::from_soup(&soup).expect("valid mesh");
    // The pool's threads are started, and have allocated once (glibc gives each thread
    // an arena on its first allocation), before the peak is reset: their stacks and
    // arenas are not the subdivision's.
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("pool");
    pool.broadcast(|_| drop(std::hint::black_box(vec![0u8; 4096])));
    // The peak is reset here (Linux 4.0 and later; elsewhere nothing happens), so that the
    // one reported is that of the subdivision, not of reading and building the input.
    let _ = std::fs::write("/proc/self/clear_refs", "5");
    let resident_before = memory_kib("VmRSS");
    let reuse = args.iter().any(|a| a == "--reuse");
    let mut subdivider = Subdivider::new(options);
    let mut best = f64::INFINITY;
    let mut fine: Option<LoopMesh> = None;
    for repeat in 0..repeats {
        let start;
        let result = if reuse {
            // The previous result's memory is the next call's output.
            let mut out = fine.take().unwrap_or_default();
            start = Instant::now();
            pool.install(|| {
                if from_soup {
                    let mesh = HalfedgeMesh::from_soup(&soup).expect("valid mesh");
                    subdivider.subdivide_into(&mesh, level, &mut out)
                } else {
                    subdivider.subdivide_into(&mesh, level, &mut out)
                }
            })
            .expect("subdivide");
            out
        } else {
            drop(fine.take());
            start = Instant::now();
            pool.install(|| {
                if from_soup {
                    let mesh = HalfedgeMesh::from_soup(&soup).expect("valid mesh");
                    subdivide(&mesh, level, &options)
                } else {
                    subdivide(&mesh, level, &options)
                }
            })
            .expect("subdivide")
        };
        let seconds = start.elapsed().as_secs_f64();
        // With `--reuse` the first call allocates: it is not the figure of interest.
        if !(reuse && repeat == 0 && repeats > 1) {
            best = best.min(seconds);
        }
        let bytes = result.positions.len() * 24 + result.triangles.len() * 12;
        println!(
            "level {level} threads {threads}{}: {} vertices, {} faces, {:.1} MB output, {:.4} s ({:.2} M faces/s)",
            if reuse { if repeat == 0 { " reuse (first call)" } else { " reuse" } } else { "" },
            result.vertex_count(),
            result.face_count(),
            bytes as f64 / 1e6,
            seconds,
            result.face_count() as f64 / seconds / 1e6
        );
        fine = Some(result);
    }
    println!("best {:.3} ms{}", best * 1e3, if reuse && repeats > 1 { " (calls after the first)" } else { "" });
    if let Some(fine) = &fine {
        let output = (fine.positions.len() * 24 + fine.triangles.len() * 12) as f64 / 1e6;
        // KiB to MB (10^6 bytes), the unit of the output size.
        let (peak, before) = (memory_kib("VmHWM") as f64 * 1.024e-3, resident_before as f64 * 1.024e-3);
        println!(
            "memory: peak {peak:.1} MB, before subdividing {before:.1} MB, output {output:.1} MB, \
             (peak - before) / output {:.2}, peak / output {:.2}",
            (peak - before) / output,
            peak / output
        );
    }
    if let (Some(out), Some(fine)) = (value("--out"), fine) {
        mesh_file::write_obj(Path::new(&out), &fine.positions, &fine.triangles);
    }
}

/// A `/proc/self/status` memory figure in KiB (0 where unavailable).
fn memory_kib(key: &str) -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|status| {
            status.lines().find(|l| l.starts_with(key)).and_then(|l| l.split_whitespace().nth(1)?.parse().ok())
        })
        .unwrap_or(0)
}
