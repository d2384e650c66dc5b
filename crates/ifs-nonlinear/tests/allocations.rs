//! The renderers' inner loops do not allocate: the number of heap allocations of a render
//! depends on the number of parallel tasks and chunks, not on the number of points.
//!
//! Counting needs a global allocator, whose trait is `unsafe`: the only unsafe code of the
//! crate, test-only, forwarding every call to the system allocator unchanged.
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use ifs_nonlinear::{
    Canvas, ChaosGame, Ifs, View, chaos_density, chaos_points, deterministic_into, preset, render::CHAOS_CHUNK,
};

struct CountingAllocator;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator; only counts calls.
unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

fn allocations_during(work: impl FnOnce()) -> usize {
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    work();
    ALLOCATIONS.load(Ordering::Relaxed) - before
}

/// One test function (the counter is global): a single-thread pool so that other tests'
/// threads cannot add to the count.
#[test]
fn rendering_allocations_do_not_grow_with_the_point_count() {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    pool.install(|| {
        for name in ["sierpinski", "levy", "quadratic-bezier", "quartic-bump", "bicubic-patch"] {
            let scene = preset(name).unwrap();
            let mut buffer = Vec::with_capacity(1 << 22);
            // Warm up (first-use allocations of the pool and the buffer).
            deterministic_into(&scene.ifs, None, 3, 1 << 22, &mut buffer).unwrap();
            // Levels chosen so that both runs have the same number of tasks (>= 256 words
            // in the prefix) and the larger one has many times the points.
            let small_levels = if scene.ifs.map_count() == 2 { 10 } else { 5 };
            // At least 16 times the points: 2^6, 3^3, 4^2.
            let large_levels = small_levels + [6, 3, 2][scene.ifs.map_count().clamp(2, 4) - 2];
            let mut applications = [0u64; 2];
            let small = allocations_during(|| {
                applications[0] = deterministic_into(&scene.ifs, None, small_levels, 1 << 22, &mut buffer).unwrap()
            });
            let large = allocations_during(|| {
                applications[1] = deterministic_into(&scene.ifs, None, large_levels, 1 << 22, &mut buffer).unwrap()
            });
            assert!(applications[1] >= 8 * applications[0], "{name}: {applications:?}");
            // Per task: a state stack and a letter array; nothing per point or per map.
            let message =
                format!("{name}: {small} allocations for {applications:?} map applications, {large} for the larger");
            assert!(large <= small + 8 && small < 4096, "{message}");
        }

        // Chaos game: a few allocations per chunk of CHAOS_CHUNK points, none per point.
        let fern = preset("barnsley-fern").unwrap();
        let canvas = Canvas::new(200, 200, View::new([-2.5, 0.0], [3.0, 10.0]).unwrap()).unwrap();
        let points = 64 * CHAOS_CHUNK;
        let game = ChaosGame { points, seed: 5, ..ChaosGame::default() };
        let density = allocations_during(|| {
            chaos_density(&fern.ifs, &game, &canvas).unwrap();
        });
        let list = allocations_during(|| {
            chaos_points(&fern.ifs, &game).unwrap();
        });
        let chunks = points / CHAOS_CHUNK;
        assert!(density <= 4 * chunks + 32, "density: {density} allocations for {chunks} chunks");
        assert!(list <= 4 * chunks + 32, "points: {list} allocations for {chunks} chunks");
    });
}
