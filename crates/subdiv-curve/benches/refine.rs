//! Ten levels of refinement of a 1,000-point closed polygon (1,024,000 output points),
//! per scheme, against a plain memory copy of the output (the goal: within 2x of the
//! copy). Fixed-seed input.
//!
//! What is compared, exactly:
//! - `memcpy-2d` / `memcpy-3d`: `copy_from_slice` of a source buffer of 1,024,000 points
//!   (16 MB of `DVec2`, 24 MB of `DVec3`) into a target of the same length. Both buffers
//!   are allocated and touched once before timing and reused by every iteration: the
//!   time is the copy alone (read the output size, write the output size).
//! - every other row: [`Refiner::refine_into`] (or [`Framework::refine_into`]) with one
//!   `Refiner` and one output `Vec` reused by every iteration, as in an interactive loop:
//!   after the first iteration no allocation and no page fault, so the time is the
//!   refinement alone (read the 1,000 input points, write the output size once; all
//!   intermediate levels live in the refiner's cache-sized scratch).
//!
//! - `memcpy-2d-parallel`: the same copy split into one contiguous piece per thread of
//!   the pool. Large refinements spread their output blocks over the pool's threads, so
//!   the default rows compare with this row as well as with the single-threaded copy;
//!   the `-1t` rows refine on one thread.
//!
//! Both sides therefore follow the same allocation policy (reused, already faulted-in
//! output); the ratio `refine / memcpy` of the same dimension, measured in the same run,
//! is the figure the goal refers to. Throughput is reported in output points per second.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{DVec2, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use subdiv_curve::{CurveScheme, Framework, Refiner, Topology, VirtualPoints};

const POINTS: usize = 1000;
const LEVELS: u32 = 10;

fn polygon() -> Vec<DVec2> {
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    (0..POINTS)
        .map(|k| {
            let t = k as f64 * std::f64::consts::TAU / POINTS as f64;
            let r = 1.0 + 0.05 * rng.random::<f64>();
            DVec2::new(r * t.cos(), r * t.sin())
        })
        .collect()
}

fn bench_refine(c: &mut Criterion) {
    let points = polygon();
    let points3: Vec<DVec3> = points.iter().map(|p| p.extend(0.5 * p.x * p.y)).collect();
    let output_len = POINTS << LEVELS;
    let mut group = c.benchmark_group("refine-1000x10");
    group.throughput(Throughput::Elements(output_len as u64));
    group.sample_size(20);

    let source = vec![DVec2::ONE; output_len];
    let mut target = vec![DVec2::ZERO; output_len];
    group.bench_function("memcpy-2d", |b| {
        b.iter(|| {
            target.copy_from_slice(black_box(&source));
            black_box(&target);
        })
    });
    let source3 = vec![DVec3::ONE; output_len];
    let mut target3 = vec![DVec3::ZERO; output_len];
    group.bench_function("memcpy-3d", |b| {
        b.iter(|| {
            target3.copy_from_slice(black_box(&source3));
            black_box(&target3);
        })
    });

    // The same copies spread over the thread pool, the fair baseline for the rows that
    // refine their blocks on several threads.
    let copy_in_parallel = |target: &mut [DVec2], source: &[DVec2]| {
        let chunk = source.len().div_ceil(rayon::current_num_threads());
        target.par_chunks_mut(chunk).zip(source.par_chunks(chunk)).for_each(|(t, s)| t.copy_from_slice(s));
    };
    group.bench_function("memcpy-2d-parallel", |b| {
        b.iter(|| {
            copy_in_parallel(&mut target, black_box(&source));
            black_box(&target);
        })
    });

    let schemes = [
        ("chaikin", CurveScheme::chaikin()),
        ("cubic-bspline", CurveScheme::cubic_bspline()),
        ("four-point", CurveScheme::four_point(1.0 / 16.0).expect("valid tension")),
    ];
    let mut refiner = Refiner::new();
    let mut out = Vec::new();
    for (name, scheme) in &schemes {
        group.bench_function(format!("{name}-2d"), |b| {
            b.iter(|| {
                refiner
                    .refine_into(scheme, black_box(&points), Topology::Closed, LEVELS, &mut out)
                    .expect("valid input");
                black_box(&out);
            })
        });
    }
    // One thread: what a caller inside a single-threaded pool gets.
    let single = rayon::ThreadPoolBuilder::new().num_threads(1).build().expect("thread pool");
    for (name, scheme) in &schemes {
        group.bench_function(format!("{name}-2d-1t"), |b| {
            single.install(|| {
                b.iter(|| {
                    refiner
                        .refine_into(scheme, black_box(&points), Topology::Closed, LEVELS, &mut out)
                        .expect("valid input");
                    black_box(&out);
                })
            })
        });
    }
    let mut refiner3 = Refiner::new();
    let mut out3 = Vec::new();
    let cubic = CurveScheme::cubic_bspline();
    group.bench_function("cubic-bspline-3d", |b| {
        b.iter(|| {
            refiner3
                .refine_into(&cubic, black_box(&points3), Topology::Closed, LEVELS, &mut out3)
                .expect("valid input");
            black_box(&out3);
        })
    });

    // The framework with every 10th point interpolated, buffers reused as above.
    let flags: Vec<bool> = (0..POINTS).map(|i| i % 10 == 0).collect();
    for (name, mode) in
        [("framework-seed", VirtualPoints::SeedCompatible), ("framework-exact", VirtualPoints::ExactGlobal)]
    {
        let framework = Framework::published().with_mode(mode);
        group.bench_function(format!("{name}-2d"), |b| {
            b.iter(|| {
                framework
                    .refine_into(&mut refiner, black_box(&points), &flags, Topology::Closed, LEVELS, &mut out)
                    .expect("valid input");
                black_box(&out);
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_refine);
criterion_main!(benches);
