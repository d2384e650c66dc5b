//! Attractors against closed forms (ALGORITHMS.md §13, §15.3): Bézier curves, the
//! Sierpiński point count, the Lévy curve's bounding box, the quartic bump, the Gaussian.

use ifs_nonlinear::{
    AffineIfs, BarycentricIfs, ChaosGame, ComplexBezierIfs, IfsError, Probabilities, bezier_split, chaos_points,
    complex_bezier_split, deterministic_points, preset, sierpinski,
};
use num_complex::Complex64;
use proptest::prelude::*;

/// Quadratic Bézier curve point and its first two derivatives.
fn bezier2(p: &[[f64; 2]; 3], t: f64) -> ([f64; 2], [f64; 2], [f64; 2]) {
    let s = 1.0 - t;
    let point = std::array::from_fn(|k| s * s * p[0][k] + 2.0 * s * t * p[1][k] + t * t * p[2][k]);
    let d1 = std::array::from_fn(|k| 2.0 * (s * (p[1][k] - p[0][k]) + t * (p[2][k] - p[1][k])));
    let d2 = std::array::from_fn(|k| 2.0 * (p[2][k] - 2.0 * p[1][k] + p[0][k]));
    (point, d1, d2)
}

/// min over t in [lo, hi] of |B(t) - q|: the best of `samples` samples, polished by Newton
/// steps on (B - q)·B' = 0 (kept inside the interval). An upper bound of the distance to
/// the curve, equal to it when the interval holds the nearest point.
fn distance_on(p: &[[f64; 2]; 3], q: [f64; 3], lo: f64, hi: f64, samples: usize) -> f64 {
    let dist = |t: f64| {
        let (b, _, _) = bezier2(p, t);
        (b[0] - q[0]).hypot(b[1] - q[1])
    };
    // samples = 0: start at the midpoint.
    let mut best_t = if samples == 0 { 0.5 * (lo + hi) } else { lo };
    for i in 0..=samples {
        let t = lo + (hi - lo) * i as f64 / samples as f64;
        if dist(t) < dist(best_t) {
            best_t = t;
        }
    }
    let mut t = best_t;
    for _ in 0..8 {
        let (b, d1, d2) = bezier2(p, t);
        let r = [b[0] - q[0], b[1] - q[1]];
        let f = r[0] * d1[0] + r[1] * d1[1];
        let df = d1[0] * d1[0] + d1[1] * d1[1] + r[0] * d2[0] + r[1] * d2[1];
        if df <= 0.0 {
            break;
        }
        let next = (t - f / df).clamp(lo, hi);
        if dist(next) <= dist(t) {
            t = next;
        }
    }
    dist(t).min(dist(best_t))
}

/// The dyadic parameter of a word: output index `word` (letters v_1 … v_k, v_1 most
/// significant) is row j of `S_{v_1} ⋯ S_{v_k} P`, whose sub-curve starts at t = binary
/// fraction of the reversed word `0.v_k … v_1`.
fn word_parameter(word: usize, levels: u32) -> f64 {
    (0..levels).map(|i| ((word >> i) & 1) as f64 * 0.5f64.powi(i as i32 + 1)).sum()
}

/// Max distance of level-k deterministic points started at the middle control point (the
/// first and last rows are curve points exactly, see the test below) to the curve,
/// searching on each point's own sub-curve [t_w, t_w + 2^{-k}] from its midpoint: an upper
/// bound of the true distance.
fn max_distance_local(p: &[[f64; 2]; 3], levels: u32) -> f64 {
    let ifs = BarycentricIfs::new(&bezier_split(2, 0.5).unwrap(), p).unwrap();
    let points = deterministic_points(&ifs, Some(&[0.0, 1.0, 0.0]), levels, 1 << 22).unwrap();
    let width = 0.5f64.powi(levels as i32);
    points
        .iter()
        .enumerate()
        .map(|(word, q)| {
            let lo = word_parameter(word, levels);
            distance_on(p, *q, lo, lo + width, 0)
        })
        .fold(0.0, f64::max)
}

/// Max true distance (global search over [0, 1]) of level-k points.
fn max_distance_global(p: &[[f64; 2]; 3], levels: u32) -> f64 {
    let ifs = BarycentricIfs::new(&bezier_split(2, 0.5).unwrap(), p).unwrap();
    let points = deterministic_points(&ifs, None, levels, 1 << 22).unwrap();
    points.iter().map(|q| distance_on(p, *q, 0.0, 1.0, 512)).fold(0.0, f64::max)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 8, failure_persistence: None, ..ProptestConfig::default() })]

    /// MUST (§15.3): the attractor of the quadratic-Bézier IFS lies on the Bézier curve:
    /// max distance below 1e-9 after 16 levels, for random (non-collinear or collinear)
    /// control points.
    #[test]
    fn quadratic_bezier_attractor_lies_on_the_curve(
        coords in proptest::array::uniform6(-1.0f64..1.0),
    ) {
        let p = [[coords[0], coords[1]], [coords[2], coords[3]], [coords[4], coords[5]]];
        let distance = max_distance_local(&p, 16);
        eprintln!("quadratic Bézier attractor distance after 16 levels: {distance:e}");
        prop_assert!(distance < 1e-9, "distance {distance:e} for {p:?}");
    }

    /// Affine invariance (§1.2): the attractor of A·P + t is A·(attractor of P) + t, for the
    /// barycentric cubic-curve IFS and the triangular-patch IFS.
    #[test]
    fn attractors_commute_with_affine_maps(
        coords in proptest::array::uniform8(-1.0f64..1.0),
        a in proptest::array::uniform4(-2.0f64..2.0),
        t in proptest::array::uniform2(-3.0f64..3.0),
    ) {
        let affine = |p: [f64; 2]| [a[0] * p[0] + a[1] * p[1] + t[0], a[2] * p[0] + a[3] * p[1] + t[1]];
        let cubic = [[coords[0], coords[1]], [coords[2], coords[3]], [coords[4], coords[5]], [coords[6], coords[7]]];
        let triangle = [cubic[0], cubic[1], cubic[2]];
        let cases = [
            (ifs_nonlinear::bezier_split(3, 0.4).unwrap(), cubic.to_vec()),
            (ifs_nonlinear::triangle_patch_split(1).unwrap(), triangle.to_vec()),
        ];
        for (rule, control) in cases {
            let moved: Vec<[f64; 2]> = control.iter().map(|p| affine(*p)).collect();
            let before = deterministic_points(&BarycentricIfs::new(&rule, &control).unwrap(), None, 4, 1 << 16).unwrap();
            let after = deterministic_points(&BarycentricIfs::new(&rule, &moved).unwrap(), None, 4, 1 << 16).unwrap();
            for (p, q) in before.iter().zip(&after) {
                let image = affine([p[0], p[1]]);
                prop_assert!((image[0] - q[0]).abs() < 1e-12 && (image[1] - q[1]).abs() < 1e-12);
            }
        }
    }

    /// Complex subdivision matrices have rows summing to 1 for any z.
    #[test]
    fn complex_rows_sum_to_one(re in -2.0f64..2.0, im in -2.0f64..2.0, degree in 1usize..6) {
        let rule = complex_bezier_split(degree, Complex64::new(re, im)).unwrap();
        for s in rule.matrices() {
            for r in 0..s.nrows() {
                let sum: Complex64 = s.row(r).iter().sum();
                prop_assert!((sum - 1.0).norm() < 1e-12 * (1.0 + Complex64::new(re, im).norm()).powi(degree as i32));
            }
        }
    }
}

/// §15.3: for P = (0,0),(1,2),(3,0) the max distance at k = 2, 4, 6, 8 was 6.4e-2, 4.0e-3,
/// 2.5e-4, 1.5e-5 (ratio 1/4 per level).
#[test]
fn quadratic_bezier_convergence_ratio_is_one_quarter_per_level() {
    let p = [[0.0, 0.0], [1.0, 2.0], [3.0, 0.0]];
    let expected = [6.4e-2, 4.0e-3, 2.5e-4, 1.5e-5];
    let measured: Vec<f64> = [2, 4, 6, 8].iter().map(|&k| max_distance_global(&p, k)).collect();
    eprintln!("quadratic Bézier max distance at k = 2, 4, 6, 8: {measured:?}");
    for (m, e) in measured.iter().zip(expected) {
        assert!((m / e - 1.0).abs() < 0.1, "measured {measured:?}, spec {expected:?}");
    }
    for pair in measured.windows(2) {
        let ratio_per_level = (pair[1] / pair[0]).sqrt();
        assert!((ratio_per_level - 0.25).abs() < 0.01, "{measured:?}");
    }
}

/// §15.3: the first row of S_{w1}…S_{wk} P is exactly the curve point at t = binary
/// fraction of the reversed word, and chaos-game points are within 3.8e-8 of the curve after 30 burn-in steps.
#[test]
fn first_rows_are_curve_points_and_chaos_points_are_close() {
    let p = [[0.0, 0.0], [1.0, 2.0], [3.0, 0.0]];
    let ifs = BarycentricIfs::new(&bezier_split(2, 0.5).unwrap(), &p).unwrap();
    let levels = 10;
    let firsts = deterministic_points(&ifs, Some(&[1.0, 0.0, 0.0]), levels, 1 << 20).unwrap();
    for (word, q) in firsts.iter().enumerate() {
        let (b, _, _) = bezier2(&p, word_parameter(word, levels));
        assert!((b[0] - q[0]).abs() < 1e-14 && (b[1] - q[1]).abs() < 1e-14);
    }
    let game = ChaosGame { points: 4000, seed: 3, burn_in: 30, probabilities: Probabilities::Uniform };
    let points = chaos_points(&ifs, &game).unwrap();
    let worst = points.iter().map(|q| distance_on(&p, *q, 0.0, 1.0, 64)).fold(0.0, f64::max);
    eprintln!("chaos-game max distance after 30 burn-in steps: {worst:e}");
    assert!(worst < 3.8e-8, "chaos-game distance {worst:e}");
}

/// Seed form and barycentric form draw the same points.
#[test]
fn seed_and_barycentric_forms_agree() {
    let p = [[0.0, 0.0], [1.0, 2.0], [3.0, 0.0]];
    let rule = bezier_split(2, 0.5).unwrap();
    let a = deterministic_points(&BarycentricIfs::new(&rule, &p).unwrap(), None, 6, 1 << 20).unwrap();
    let seed = AffineIfs::from_rule(&rule, &p).unwrap();
    let start: Vec<f64> = p.iter().flatten().copied().collect();
    let b = deterministic_points(&seed, Some(&start), 6, 1 << 20).unwrap();
    for (x, y) in a.iter().zip(&b) {
        assert!((x[0] - y[0]).abs() < 1e-12 && (x[1] - y[1]).abs() < 1e-12);
    }
}

/// §15.3: the Sierpiński gasket has 3(3^k + 1)/2 distinct points after k levels from the
/// three corners.
#[test]
fn sierpinski_distinct_point_count() {
    let ifs = AffineIfs::from_rule(&sierpinski(), &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap();
    let corners = [0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
    for k in 0..=7u32 {
        let points = deterministic_points(&ifs, Some(&corners), k, 1 << 20).unwrap();
        let mut keys: Vec<(u64, u64)> = points.iter().map(|p| (p[0].to_bits(), p[1].to_bits())).collect();
        keys.sort_unstable();
        keys.dedup();
        assert_eq!(keys.len(), 3 * (3usize.pow(k) + 1) / 2, "level {k}");
    }
    // Contractive with ratio 1/2, seed form: last column (0, 0, 1) kept by construction.
    let report = ifs.require_contractive().unwrap();
    assert!((report.max_singular_value - 0.5).abs() < 1e-12);
}

/// §13: real z in (0, 1) reproduces the Bézier curve (first points of level k lie on it).
#[test]
fn real_complex_parameter_reproduces_the_bezier_curve() {
    let p = [[0.0, 0.0], [1.0, 2.0], [3.0, 0.0]];
    let control: Vec<Complex64> = p.iter().map(|q| Complex64::new(q[0], q[1])).collect();
    for t in [0.3, 0.5, 0.71] {
        let ifs = ComplexBezierIfs::new(Complex64::new(t, 0.0), &control).unwrap();
        let mut start = vec![0.0; 6];
        start[0] = 1.0;
        let firsts = deterministic_points(&ifs, Some(&start), 8, 1 << 20).unwrap();
        let worst = firsts.iter().map(|q| distance_on(&p, *q, 0.0, 1.0, 256)).fold(0.0, f64::max);
        assert!(worst < 1e-12, "t = {t}: {worst:e}");
        // All points converge to the curve too.
        let all = deterministic_points(&ifs, None, 10, 1 << 20).unwrap();
        let worst = all.iter().map(|q| distance_on(&p, *q, 0.0, 1.0, 32)).fold(0.0, f64::max);
        assert!(worst < 1e-2, "t = {t}: {worst:e}");
    }
}

/// §13: n = 1, z = 1/2 gives the dyadic points of the segment.
#[test]
fn two_point_scheme_at_one_half_gives_dyadic_points() {
    let control = [Complex64::new(0.0, 0.0), Complex64::new(1.0, 0.0)];
    let ifs = ComplexBezierIfs::new(Complex64::new(0.5, 0.0), &control).unwrap();
    let levels = 9;
    let points = deterministic_points(&ifs, Some(&[1.0, 0.0, 0.0, 0.0]), levels, 1 << 20).unwrap();
    let mut xs: Vec<f64> = points.iter().map(|p| p[0]).collect();
    xs.sort_by(f64::total_cmp);
    let expected: Vec<f64> = (0..1u32 << levels).map(|i| f64::from(i) / f64::from(1u32 << levels)).collect();
    assert_eq!(xs, expected);
    assert!(points.iter().all(|p| p[1] == 0.0));
}

/// §13 erratum: |z| < 1 alone does not suffice.
#[test]
fn non_contractive_parameters_are_typed_errors() {
    let segment = [Complex64::new(0.0, 0.0), Complex64::new(1.0, 0.0)];
    let quadratic = [Complex64::new(0.0, 0.0), Complex64::new(0.5, 1.0), Complex64::new(1.0, 0.0)];
    for z in [Complex64::new(-0.5, 0.0), Complex64::new(1.2, 0.0), Complex64::new(0.5, 0.9), Complex64::new(0.0, 0.0)] {
        for control in [&segment[..], &quadratic[..]] {
            let err = ComplexBezierIfs::new(z, control).unwrap_err();
            assert!(matches!(err, IfsError::NotContractive { .. }), "{z}: {err}");
        }
    }
    let err = ComplexBezierIfs::new(Complex64::new(-0.5, 0.0), &segment).unwrap_err();
    assert!(err.to_string().contains("|1 - z| = 1.5"), "{err}");
    assert!(matches!(
        ComplexBezierIfs::new(Complex64::new(0.5, 0.5), &segment[..1]),
        Err(IfsError::TooFewPoints { .. })
    ));
}

/// §13: the Lévy C curve's bounding box tends to [-1/2, 3/2] x [-1/4, 1]; within 1e-2
/// after 16 levels.
#[test]
fn levy_bounding_box_after_16_levels() {
    let scene = preset("levy").unwrap();
    let points = deterministic_points(&scene.ifs, None, 16, 1 << 20).unwrap();
    let (mut min, mut max) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in &points {
        for k in 0..2 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    }
    let expected_min = [-0.5, -0.25];
    let expected_max = [1.5, 1.0];
    for k in 0..2 {
        assert!((min[k] - expected_min[k]).abs() < 1e-2 && (max[k] - expected_max[k]).abs() < 1e-2, "{min:?} {max:?}");
    }
    eprintln!("Lévy bbox after 16 levels: [{}, {}] x [{}, {}]", min[0], max[0], min[1], max[1]);
}

/// §15.3: the quartic bump after 14 levels from the triangle; and the true Gaussian.
#[test]
fn quartic_bump_and_true_gaussian_residuals() {
    let scene = preset("quartic-bump").unwrap();
    // The control triangle (-1,0),(0,5),(1,0) of the (x, w) picture, mapped by F(x, w) = (x, w²).
    let triangle = [-1.0, 0.0, 0.0, 25.0, 1.0, 0.0];
    let points = deterministic_points(&scene.ifs, Some(&triangle), 14, 1 << 20).unwrap();
    let residual = points.iter().map(|p| (p[1] - 6.25 * (1.0 - p[0] * p[0]).powi(2)).abs()).fold(0.0, f64::max);
    eprintln!("quartic residual after 14 levels: {residual:e}");
    // Spec: 4.7e-8.
    assert!((4.0e-8..5.0e-8).contains(&residual), "{residual:e}");
    let gaussian = preset("exp-gaussian").unwrap();
    let points = deterministic_points(&gaussian.ifs, None, 14, 1 << 20).unwrap();
    let residual = points.iter().map(|p| (p[1] - (-p[0] * p[0] / 2.0).exp()).abs()).fold(0.0, f64::max);
    eprintln!("Gaussian residual after 14 levels: {residual:e}");
    assert!(residual < 1e-12, "{residual:e}");
}
