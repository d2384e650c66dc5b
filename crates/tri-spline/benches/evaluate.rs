//! Evaluations per second of the three surface kinds at degrees 2, 3 and 4.
//!
//! Fixed-seed inputs: random control points and 1000 query points inside the domain
//! (Bézier / B-patch: the reference triangle; DMS: the interior of an 8x8 square grid
//! of 128 triangles with knot clouds of radius 0.12 edge).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use glam::{DVec2, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;
use tri_spline::index::tri_count;
use tri_spline::samples::square_triangulation;
use tri_spline::{BPatch, DmsBasis, DmsScratch, DmsSpline, DomainTriangle, KnotPlacement, KnotSequences, TriBezier};

const POINTS: usize = 1000;

fn random_point(rng: &mut ChaCha8Rng) -> DVec3 {
    DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
}

fn triangle_points(rng: &mut ChaCha8Rng) -> Vec<DVec2> {
    (0..POINTS)
        .map(|_| {
            let (a, b): (f64, f64) = (rng.random(), rng.random());
            if a + b > 1.0 { DVec2::new(1.0 - a, 1.0 - b) } else { DVec2::new(a, b) }
        })
        .collect()
}

fn bench_bezier_and_bpatch(c: &mut Criterion) {
    let mut group = c.benchmark_group("evaluate");
    group.throughput(Throughput::Elements(POINTS as u64));
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let points = triangle_points(&mut rng);
    for n in [2usize, 3, 4] {
        let control: Vec<DVec3> = (0..tri_count(n)).map(|_| random_point(&mut rng)).collect();
        let domain = DomainTriangle::reference();
        let bezier = TriBezier::new(n, domain, control.clone()).unwrap();
        group.bench_with_input(BenchmarkId::new("bezier_de_casteljau", n), &points, |b, pts| {
            b.iter(|| pts.iter().fold(DVec3::ZERO, |s, &u| s + bezier.eval(black_box(u))))
        });
        group.bench_with_input(BenchmarkId::new("bezier_bernstein", n), &points, |b, pts| {
            b.iter(|| pts.iter().fold(DVec3::ZERO, |s, &u| s + bezier.eval_bernstein(black_box(u))))
        });
        let [t0, t1, t2] = domain.corners();
        let mut seq = |corner: DVec2, away: DVec2| {
            (0..n).map(|i| corner + away * (0.05 * i as f64) + DVec2::new(rng.random_range(-0.02..0.02), 0.0)).collect()
        };
        let knots = KnotSequences {
            r: seq(t0, DVec2::new(-1.0, -1.0)),
            s: seq(t1, DVec2::new(1.0, -0.5)),
            t: seq(t2, DVec2::new(-0.5, 1.0)),
        };
        let bpatch = BPatch::new(n, knots, control).unwrap();
        group.bench_with_input(BenchmarkId::new("bpatch_de_boor", n), &points, |b, pts| {
            b.iter(|| pts.iter().fold(DVec3::ZERO, |s, &u| s + bpatch.eval(black_box(u))))
        });
    }
    group.finish();
}

fn bench_dms(c: &mut Criterion) {
    let mut group = c.benchmark_group("evaluate");
    group.throughput(Throughput::Elements(POINTS as u64));
    let (vertices, triangles) = square_triangulation(8);
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    let points: Vec<DVec2> =
        (0..POINTS).map(|_| DVec2::new(rng.random_range(0.5..7.5), rng.random_range(0.5..7.5))).collect();
    for n in [2usize, 3, 4] {
        let placement = KnotPlacement { radius: 0.12, seed: 3, boundary_outward: true };
        let basis = DmsBasis::with_generated_knots(n, vertices.clone(), triangles.clone(), placement).unwrap();
        let control: Vec<DVec3> = (0..basis.basis_count()).map(|_| random_point(&mut rng)).collect();
        let spline = DmsSpline::new(basis, control).unwrap();
        group.bench_with_input(BenchmarkId::new("dms_simplex_recurrence", n), &points, |b, pts| {
            let mut scratch = DmsScratch::default();
            let mut values = Vec::new();
            b.iter(|| {
                pts.iter().fold(DVec3::ZERO, |s, &u| s + spline.eval_with(black_box(u), &mut scratch, &mut values))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_bezier_and_bpatch, bench_dms);
criterion_main!(benches);
