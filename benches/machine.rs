//! What two threads can gain on this machine at all: a plain parallel stream over the
//! same bytes, on one thread and on two, at working sets from cache-sized to far
//! larger than every cache.
//!
//! Each call updates every `f64` of a buffer once (`x = x / 2 + 1`: one read and one
//! write per element, no dependency between elements), on one thread or split in two
//! halves on a pool of two. Nothing is simpler to run in parallel, so the two-thread
//! speed-up it gets, `stream-1t` over `stream-2t` at the same size, is the ceiling for
//! code that moves as many bytes per operation: subdivision of a large mesh is such code
//! (an output vertex is a few multiply-adds of positions read from memory). On a machine
//! whose memory bandwidth is shared between its cores the ceiling falls well below two
//! once the buffer outgrows the caches; `cargo xtask bench` prints it beside the
//! subdivision speed-ups of the same run.
//!
//! The other thing two threads cost is waking the second one. A `rayon` worker that
//! runs out of work sleeps soon after (on this machine within 20 µs), and the first
//! fork after that waits for it to wake. `fork-after-idle` times a fork into two halves of 10 µs
//! of busy work each, every one after the second thread has had nothing to do for
//! 0.2 ms: ideally 10 µs on two threads (20 µs on one); what it takes over that is the
//! wake-up, which a small level (about 0.1 ms of work) pays whenever its second thread
//! has fallen asleep, at the start of a call or between its passes.
//!
//! Benchmark ids are `machine/stream-<threads>t/<MiB>` (throughput in elements, `f64`s)
//! and `machine/fork-after-idle-<threads>t`.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rayon::prelude::*;

/// Working sets in MiB: within the per-core cache, a few times larger, and far larger
/// than every cache (the size of a level-4 Loop output of `bunny00.off`).
const SIZES_MIB: [usize; 3] = [2, 32, 512];

/// One pass over `values`: every element read and written once.
fn update(values: &mut [f64]) {
    for x in values {
        *x = 0.5 * *x + 1.0;
    }
}

fn stream(c: &mut Criterion) {
    let mut group = c.benchmark_group("machine");
    group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2));
    for mib in SIZES_MIB {
        let len = (mib << 20) / size_of::<f64>();
        let mut values = vec![1.0f64; len];
        group.throughput(Throughput::Elements(len as u64));
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
            let half = len.div_ceil(threads);
            group.bench_function(BenchmarkId::new(format!("stream-{threads}t"), mib), |b| {
                pool.install(|| b.iter(|| black_box(&mut values[..]).par_chunks_mut(half).for_each(update)))
            });
        }
    }
    group.finish();
}

/// Busy work of each half of a fork in `fork-after-idle`.
const HALF: Duration = Duration::from_micros(10);

/// How long the second thread has nothing to do before each fork: far longer than a
/// `rayon` worker looks for work before it sleeps.
const IDLE: Duration = Duration::from_micros(200);

/// Keeps the calling thread busy for `time` (a loop, not a sleep: the thread stays on
/// its core, as a thread doing work does).
fn busy(time: Duration) {
    let start = Instant::now();
    while start.elapsed() < time {
        std::hint::spin_loop();
    }
}

fn fork_after_idle(c: &mut Criterion) {
    let mut group = c.benchmark_group("machine");
    group.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(2));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
        group.bench_function(format!("fork-after-idle-{threads}t"), |b| {
            pool.install(|| {
                b.iter_custom(|calls| {
                    let mut total = Duration::ZERO;
                    for _ in 0..calls {
                        // Only the fork is timed, not the idle time before it.
                        busy(IDLE);
                        let start = Instant::now();
                        rayon::join(|| busy(HALF), || busy(HALF));
                        total += start.elapsed();
                    }
                    total
                })
            })
        });
    }
    group.finish();
}

criterion_group!(benches, stream, fork_after_idle);
criterion_main!(benches);
