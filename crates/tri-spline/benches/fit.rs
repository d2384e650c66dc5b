//! The whole fitting pipeline of `multires fit` at the size of seed paper 001's Bézier
//! row: 4753 points of the smooth test surface on a regular triangular grid (N = 96),
//! two reverse-Loop levels (degree 24, 325 control points), ten iterations, with the
//! spectral radius but without the least-squares baseline; and the quadratic triangular
//! B-spline over the same data (its 24-segment net).

use criterion::{Criterion, criterion_group, criterion_main};
use mesh_topo::HalfedgeMesh;
use std::hint::black_box;
use tri_spline::SurfaceKind;
use tri_spline::pipeline::{FitOptions, Method, fit_mesh};
use tri_spline::samples::{smooth_surface, triangle_grid};

fn bench_fit(c: &mut Criterion) {
    let mesh = HalfedgeMesh::from_soup(&triangle_grid(96, smooth_surface)).unwrap();
    let mut group = c.benchmark_group("fit_4753_points_i2_k10");
    group.sample_size(10);
    for (name, surface, method) in [
        ("bezier_lspia", SurfaceKind::Bezier, Method::Lspia),
        ("bezier_seed", SurfaceKind::Bezier, Method::Seed),
        ("tri_bspline_lspia", SurfaceKind::TriBspline, Method::Lspia),
    ] {
        let options = FitOptions { surface, method, least_squares: false, ..FitOptions::default() };
        group.bench_function(name, |b| b.iter(|| fit_mesh(black_box(&mesh), &options).unwrap()));
    }
    group.finish();
}

criterion_group!(benches, bench_fit);
criterion_main!(benches);
