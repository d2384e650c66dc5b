//! Rendering throughput: chaos-game points per second and deterministic map applications
//! per second, on fixed inputs (Barnsley's fern, the Sierpiński gasket, the Lévy curve,
//! a quadratic Bézier curve in barycentric form, the quartic bump).
//!
//! The comparison with the `barnsley` crate (same fern, same run) lives outside the
//! workspace, so that its CLI-only dependencies (clap, image) never enter this crate's
//! dependency tree; see the crate README.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use ifs_nonlinear::{
    Canvas, ChaosGame, Ifs, Probabilities, View, barnsley_fern, chaos_density, chaos_points, deterministic_into, preset,
};

fn chaos_game(c: &mut Criterion) {
    let fern = barnsley_fern();
    let points = 1 << 20;
    let mut group = c.benchmark_group("chaos_game");
    group.throughput(Throughput::Elements(points as u64));
    group.sample_size(10);
    let game =
        ChaosGame { points, seed: 1, burn_in: 64, probabilities: Probabilities::Custom(vec![0.01, 0.85, 0.07, 0.07]) };
    group.bench_function("fern_points_1M", |b| b.iter(|| chaos_points(black_box(&fern), &game).unwrap()));
    let canvas = Canvas::new(800, 800, View::new([-2.2, 0.0], [2.7, 10.0]).unwrap()).unwrap();
    group.bench_function("fern_density_800x800_1M", |b| {
        b.iter(|| chaos_density(black_box(&fern), &game, &canvas).unwrap())
    });
    let single = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    group.bench_function("fern_density_800x800_1M_one_thread", |b| {
        b.iter(|| single.install(|| chaos_density(black_box(&fern), &game, &canvas).unwrap()))
    });
    let levy = preset("levy").unwrap();
    let game = ChaosGame { points, seed: 1, ..ChaosGame::default() };
    group.bench_function("levy_complex_points_1M", |b| b.iter(|| chaos_points(black_box(&levy.ifs), &game).unwrap()));
    group.finish();
}

fn deterministic(c: &mut Criterion) {
    let mut group = c.benchmark_group("deterministic");
    group.sample_size(10);
    for (name, levels) in [("sierpinski", 12), ("levy", 18), ("quadratic-bezier", 18), ("quartic-bump", 16)] {
        let scene = preset(name).unwrap();
        let start = if name == "quartic-bump" { None } else { scene.start.clone() };
        let mut buffer = Vec::new();
        let applications = deterministic_into(&scene.ifs, start.as_deref(), levels, 1 << 26, &mut buffer).unwrap();
        group.throughput(Throughput::Elements(applications));
        group.bench_function(format!("{name}_{levels}_levels_maps"), |b| {
            b.iter(|| {
                deterministic_into(black_box(&scene.ifs), start.as_deref(), levels, 1 << 26, &mut buffer).unwrap()
            })
        });
        black_box(scene.ifs.map_count());
    }
    group.finish();
}

criterion_group!(benches, chaos_game, deterministic);
criterion_main!(benches);
