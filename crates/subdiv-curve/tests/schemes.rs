//! Spec §2 (MUST): uniform schemes against independent references.

use glam::{DVec2, DVec3};
use proptest::prelude::*;
use subdiv_curve::analysis::{self, Status, contractivity};
use subdiv_curve::{CurveError, CurveScheme, EndRule, Refiner, Rule, Topology};

fn close(a: &[[f64; 2]], b: &[[f64; 2]], tolerance: f64) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(p, q)| (p[0] - q[0]).abs() <= tolerance && (p[1] - q[1]).abs() <= tolerance)
}

/// Centred cardinal cubic B-spline (support [-2, 2]).
fn cubic_basis(x: f64) -> f64 {
    let x = x.abs();
    if x < 1.0 {
        (4.0 - 6.0 * x * x + 3.0 * x * x * x) / 6.0
    } else if x < 2.0 {
        (2.0 - x).powi(3) / 6.0
    } else {
        0.0
    }
}

/// Centred cardinal quadratic B-spline (support [-3/2, 3/2]).
fn quadratic_basis(x: f64) -> f64 {
    let x = x.abs();
    if x < 0.5 {
        0.75 - x * x
    } else if x < 1.5 {
        0.5 * (1.5 - x) * (1.5 - x)
    } else {
        0.0
    }
}

/// Closed uniform B-spline curve evaluated directly from its basis.
fn closed_spline(control: &[[f64; 2]], basis: fn(f64) -> f64, shift: f64, t: f64) -> [f64; 2] {
    let n = control.len() as i64;
    let mut sum = [0.0, 0.0];
    for j in (t.floor() as i64 - 3)..=(t.floor() as i64 + 4) {
        let w = basis(t + shift - j as f64);
        let c = control[j.rem_euclid(n) as usize];
        sum[0] += w * c[0];
        sum[1] += w * c[1];
    }
    sum
}

fn wobbly(n: usize) -> Vec<[f64; 2]> {
    (0..n)
        .map(|k| {
            let t = k as f64 * std::f64::consts::TAU / n as f64;
            let r = 1.0 + 0.3 * (3.0 * t).sin();
            [r * t.cos(), r * t.sin() + 0.2 * (5.0 * t).cos()]
        })
        .collect()
}

#[test]
fn cubic_bspline_converges_to_the_independently_evaluated_spline() {
    let control = wobbly(7);
    let levels = 12;
    let fine = CurveScheme::cubic_bspline().refine(&control, Topology::Closed, levels).unwrap();
    assert_eq!(fine.len(), 7 << levels);
    let mut worst: f64 = 0.0;
    for (m, p) in fine.iter().enumerate() {
        let t = m as f64 / (1 << levels) as f64;
        let exact = closed_spline(&control, cubic_basis, 0.0, t);
        worst = worst.max((p[0] - exact[0]).abs().max((p[1] - exact[1]).abs()));
    }
    assert!(worst < 1e-6, "cubic B-spline: max distance to the limit {worst}");
    // Vertex positions: (p_{i-1} + 4 p_i + p_{i+1}) / 6 at t = i.
    for i in 0..7 {
        let limit = closed_spline(&control, cubic_basis, 0.0, i as f64);
        let p = fine[i << levels];
        assert!((p[0] - limit[0]).abs() < 1e-6 && (p[1] - limit[1]).abs() < 1e-6);
    }
}

#[test]
fn chaikin_converges_to_the_quadratic_bspline() {
    let control = wobbly(6);
    let levels = 12;
    let fine = CurveScheme::chaikin().refine(&control, Topology::Closed, levels).unwrap();
    let mut worst: f64 = 0.0;
    for (m, p) in fine.iter().enumerate() {
        // Point m of level k sits at parameter (m - 1/2) / 2^k; control point j weighs the
        // quadratic B-spline centred at j - 1/2.
        let t = (m as f64 - 0.5) / (1 << levels) as f64;
        let exact = closed_spline(&control, quadratic_basis, 0.5, t);
        worst = worst.max((p[0] - exact[0]).abs().max((p[1] - exact[1]).abs()));
    }
    assert!(worst < 1e-6, "Chaikin: max distance to the limit {worst}");
}

#[test]
fn closed_polygons_double_and_four_point_interpolates_exactly() {
    let control = wobbly(9);
    let dlg = CurveScheme::four_point(1.0 / 16.0).unwrap();
    let mut fine = control.clone();
    for level in 1..=5 {
        let next = dlg.refine(&fine, Topology::Closed, 1).unwrap();
        assert_eq!(next.len(), 2 * fine.len());
        for (i, p) in fine.iter().enumerate() {
            assert_eq!(next[2 * i], *p, "level {level}: p_(2i) = p_i bit for bit");
        }
        fine = next;
    }
    // The same through several levels at once.
    let direct = dlg.refine(&control, Topology::Closed, 5).unwrap();
    assert_eq!(direct, fine);
    for (i, p) in control.iter().enumerate() {
        assert_eq!(direct[i << 5], *p);
    }
}

#[test]
fn four_point_reproduces_cubics_and_cubic_bspline_reproduces_lines() {
    let cubic = |x: f64| 0.3 * x * x * x - x * x + 2.0 * x - 1.0;
    let data: Vec<f64> = (0..12).map(|i| cubic(i as f64)).collect();
    let fine = CurveScheme::four_point(1.0 / 16.0).unwrap().refine(&data, Topology::open(), 1).unwrap();
    // Away from the phantom-influenced ends, new points are samples of the same cubic.
    let interior = 4..fine.len() - 4;
    for (m, value) in fine.iter().enumerate().filter(|(m, _)| interior.contains(m)) {
        assert!((value - cubic(m as f64 / 2.0)).abs() < 1e-11, "point {m}");
    }
    let line: Vec<f64> = (0..8).map(|i| 3.0 * i as f64 - 2.0).collect();
    let fine = CurveScheme::cubic_bspline().refine(&line, Topology::open(), 3).unwrap();
    for (m, v) in fine.iter().enumerate() {
        assert!((v - (3.0 * m as f64 / 8.0 - 2.0)).abs() < 1e-12, "reflect phantoms keep lines straight");
    }
}

#[test]
fn smoothness_numbers_match_the_spec() {
    let cubic = CurveScheme::cubic_bspline().symbol();
    for m in 0..=2 {
        let check = contractivity(&cubic, m, 6);
        assert!((check.norms[0] - 0.5).abs() < 1e-15, "cubic m = {m}: {:?}", check.norms);
        assert_eq!(check.status(), Status::Established);
    }
    assert_eq!(contractivity(&cubic, 3, 6).status(), Status::Refuted, "cubic B-spline is not C3");
    let dlg = CurveScheme::four_point(1.0 / 16.0).unwrap().symbol();
    let at_six = |m: usize| contractivity(&dlg, m, 6).norms[5].powf(1.0 / 6.0);
    // The spec quotes 0.53; ||b^[6]||^(1/6) = 0.020832^(1/6) = 0.5246.
    assert!((at_six(0) - 0.5246).abs() < 5e-4 && (at_six(0) - 0.53).abs() < 0.01, "{}", at_six(0));
    assert!((at_six(1) - 0.69).abs() < 0.005, "{}", at_six(1));
    let c2 = contractivity(&dlg, 2, 12);
    assert!(c2.norms.iter().all(|n| (n - 1.0).abs() < 1e-12), "DLG m = 2: {:?}", c2.norms);
    assert!((c2.lower_bound - 1.0).abs() < 1e-9);
    assert_eq!(c2.status(), Status::Refuted, "DLG is not C2");

    let report = |s: &CurveScheme| {
        let a = analysis::analyze(s);
        (a.smoothness, a.c1, a.c2)
    };
    assert_eq!(report(&CurveScheme::chaikin()), (Some(1), true, false));
    assert_eq!(report(&CurveScheme::four_point(1.0 / 16.0).unwrap()), (Some(1), true, false));
    assert_eq!(report(&CurveScheme::cubic_bspline()), (Some(2), true, true));
    // Quintic B-spline on the C2 line of formula (4): C4.
    assert_eq!(report(&CurveScheme::combined(1.0 / 32.0, 3.0 / 16.0).unwrap()).0, Some(4));
}

#[test]
fn generation_and_reproduction_degrees() {
    let degrees = |s: &CurveScheme| {
        let symbol = s.symbol();
        (analysis::generation_degree(&symbol), analysis::reproduction_degree(&symbol))
    };
    assert_eq!(degrees(&CurveScheme::chaikin()), (Some(2), Some(1)));
    assert_eq!(degrees(&CurveScheme::cubic_bspline()), (Some(3), Some(1)));
    assert_eq!(degrees(&CurveScheme::four_point(1.0 / 16.0).unwrap()), (Some(3), Some(3)));
    assert_eq!(degrees(&CurveScheme::four_point(0.1).unwrap()), (Some(1), Some(1)));
    assert_eq!(degrees(&CurveScheme::combined(1.0 / 32.0, 3.0 / 16.0).unwrap()), (Some(5), Some(1)));
}

#[test]
fn symbol_has_four_factors_exactly_on_the_c2_line() {
    for k in 0..=8 {
        let gamma = k as f64 / 64.0;
        let on_line = CurveScheme::combined(gamma / 2.0 - 1.0 / 16.0, gamma).unwrap().symbol();
        assert!(on_line.one_plus_z_factors() >= 4, "gamma = {gamma}");
        // The second derivative at -1 is 16 omega - 8 gamma + 1 for the polynomial z^3 a(z)
        // of the spec; for our Laurent a(z) the factor z^-3 flips its sign.
        for delta in [-0.01, 0.01] {
            let omega = gamma / 2.0 - 1.0 / 16.0 + delta;
            let off = CurveScheme::combined(omega, gamma).unwrap().symbol();
            assert_eq!(off.one_plus_z_factors(), 2, "gamma = {gamma}, omega = {omega}");
            assert!((off.derivative(-1.0, 2) + (16.0 * omega - 8.0 * gamma + 1.0)).abs() < 1e-12);
        }
        if k > 0 {
            assert!(
                analysis::analyze(&CurveScheme::combined(gamma / 2.0 - 1.0 / 16.0, gamma).unwrap()).c2,
                "C2 at {gamma}"
            );
        }
    }
}

#[test]
fn local_spectra() {
    let moduli = |s: &CurveScheme| -> Vec<f64> {
        analysis::analyze(s).eigenvalues.iter().map(|l| (l.norm() * 1e10).round() / 1e10).collect()
    };
    assert_eq!(moduli(&CurveScheme::cubic_bspline()), vec![1.0, 0.5, 0.25, 0.125, 0.125]);
    assert_eq!(moduli(&CurveScheme::chaikin()), vec![1.0, 0.5, 0.25, 0.25]);
    // The four-point scheme: 1, 1/2, then 1/4 twice (a Jordan block, computed as
    // 1/4 ± 3e-9), 1/8, -1/16, -1/16: the C2 eigen condition |λ3| < λ2 fails too.
    let dlg = analysis::analyze(&CurveScheme::four_point(1.0 / 16.0).unwrap());
    let expected = [1.0, 0.5, 0.25, 0.25, 0.125, 0.0625, 0.0625];
    for (l, e) in dlg.eigenvalues.iter().zip(expected) {
        assert!((l.norm() - e).abs() < 1e-7, "{:?}", dlg.eigenvalues);
    }
    assert!(dlg.eigen.c1 && !dlg.eigen.c2);
    let rows = analysis::local_matrix(&CurveScheme::four_point(1.0 / 16.0).unwrap()).matrix;
    for r in 0..rows.nrows() {
        assert!((rows.row(r).sum() - 1.0).abs() < 1e-15, "rows sum to 1");
    }
}

#[test]
fn ifs_matrices_converge_to_limit_points() {
    // L^k (P) converges to the limit at t = 0, R^k (P) to the limit at t = 1.
    let scheme = CurveScheme::cubic_bspline();
    let segment = analysis::ifs_matrices(&scheme);
    let control = nalgebra::DVector::from_vec(vec![0.0, 1.0, 5.0, 2.0]); // labels -1, 0, 1, 2
    let (mut left, mut right) = (control.clone(), control.clone());
    for _ in 0..60 {
        left = &segment.left * left;
        right = &segment.right * right;
    }
    assert!(left.iter().all(|v| (v - (0.0 + 4.0 + 5.0) / 6.0).abs() < 1e-12));
    assert!(right.iter().all(|v| (v - (1.0 + 20.0 + 2.0) / 6.0).abs() < 1e-12));
    let chaikin = analysis::ifs_matrices(&CurveScheme::chaikin());
    assert_eq!(chaikin.indices, vec![0, 1, 2]);
}

#[test]
fn open_end_rules() {
    let control = vec![[0.0, 0.0], [1.0, 1.0], [2.0, 0.0], [3.0, 1.0]];
    let reflect = CurveScheme::cubic_bspline().refine(&control, Topology::Open(EndRule::Reflect), 4).unwrap();
    assert_eq!((reflect[0], *reflect.last().unwrap()), (control[0], control[3]));
    assert_eq!(reflect.len(), 3 * 16 + 1);
    let repeat = CurveScheme::cubic_bspline().refine(&control, Topology::Open(EndRule::Repeat), 1).unwrap();
    assert_eq!(repeat[0], [1.0 / 8.0, 1.0 / 8.0], "(7 P0 + P1) / 8");
    let chaikin = CurveScheme::chaikin().refine(&control, Topology::open(), 3).unwrap();
    assert_eq!((chaikin[0], *chaikin.last().unwrap(), chaikin.len()), (control[0], control[3], 4 << 3));
}

#[test]
fn user_defined_scheme_and_point_types() {
    // Quartic B-spline as a dual scheme: mask (1, 5, 10, 10, 5, 1) / 16.
    let quartic = CurveScheme::dual(
        "quartic B-spline",
        Rule::new(-1, &[5.0 / 16.0, 10.0 / 16.0, 1.0 / 16.0]).unwrap(),
        Rule::new(-1, &[1.0 / 16.0, 10.0 / 16.0, 5.0 / 16.0]).unwrap(),
    )
    .unwrap();
    let a = analysis::analyze(&quartic);
    assert_eq!(a.symbol.coefficients(), &[1.0 / 16.0, 5.0 / 16.0, 10.0 / 16.0, 10.0 / 16.0, 5.0 / 16.0, 1.0 / 16.0]);
    assert_eq!((a.generation_degree, a.smoothness), (Some(4), Some(3)));
    let planar: Vec<DVec2> = wobbly(5).iter().map(|p| DVec2::from_array(*p)).collect();
    let spatial: Vec<DVec3> = planar.iter().map(|p| p.extend(0.0)).collect();
    let fine2 = quartic.refine(&planar, Topology::Closed, 3).unwrap();
    let fine3 = quartic.refine(&spatial, Topology::Closed, 3).unwrap();
    assert!(fine2.iter().zip(&fine3).all(|(p, q)| p.extend(0.0) == *q));
}

#[test]
fn bad_input_is_reported() {
    let err = CurveScheme::cubic_bspline().refine(&[[0.0, 0.0], [1.0, 0.0]], Topology::Closed, 1).unwrap_err();
    assert_eq!(err, CurveError::TooFewPoints { what: "cubic-bspline".into(), needed: 3, got: 2, closed: true });
    let err =
        CurveScheme::chaikin().refine(&[[0.0, 0.0], [1.0, f64::NAN], [0.0, 1.0]], Topology::Closed, 1).unwrap_err();
    assert!(matches!(err, CurveError::NonFinite { index: 1, axis: 1, .. }), "{err}");
    let err = CurveScheme::four_point(0.6).unwrap_err();
    assert_eq!(
        err.to_string(),
        "tension w = 0.6 is outside the allowed range -0.4668 <= w <= 0.4692 (where the four-point scheme is \
         established to converge; C1 needs 0 < w < (sqrt(5)-1)/8)"
    );
    assert!(CurveScheme::four_point(f64::NAN).is_err());
    let err = CurveScheme::combined(0.5, 0.0).unwrap_err(); // the four-point scheme with w = -1/2
    assert!(
        err.to_string().starts_with("omega = 0.5 is outside the allowed range where the scheme converges"),
        "{err}"
    );
    assert!(Rule::new(0, &[]).is_err() && Rule::new(0, &[f64::INFINITY]).is_err());
    // A rule reads near its point: far offsets made the analysis and the refinement's
    // padding as long as the offset (hours, or gigabytes, at 1e9).
    let reach = subdiv_curve::MAX_RULE_LEN as i32;
    for offset in [-reach, reach] {
        assert!(Rule::new(offset, &[1.0]).is_ok(), "{offset}");
    }
    for offset in [-reach - 1, reach + 1, 1 << 29, i32::MIN, i32::MAX] {
        let err = Rule::new(offset, &[1.0]).unwrap_err();
        assert!(err.to_string().contains(&format!("at most {reach} away")), "{offset}: {err}");
    }
    // Leading zeros count: the first non-zero weight is where the rule reads.
    assert!(Rule::new(reach - 1, &[0.0, 0.0, 1.0]).is_err());
}

/// The analysis ends on any input: a step count far beyond the memory is capped, an order
/// beyond the symbol's divisibility stops at the first failed division, and a matrix
/// with a NaN entry has NaN eigenvalues (the iteration did not end on it).
#[test]
fn analysis_ends_on_any_input() {
    let cubic = CurveScheme::cubic_bspline().symbol();
    let capped = contractivity(&cubic, 0, usize::MAX);
    assert_eq!(capped.norms.len(), analysis::MAX_CONTRACTIVITY_STEPS);
    assert_eq!(capped.norms[..6], contractivity(&cubic, 0, 6).norms[..]);
    let beyond = contractivity(&cubic, usize::MAX, 3);
    assert!(!beyond.divisible && beyond.norms.is_empty());
    let nan = nalgebra::DMatrix::from_element(3, 3, f64::NAN);
    let values = analysis::eigenvalues(&nan);
    assert_eq!(values.len(), 3);
    assert!(values.iter().all(|v| v.re.is_nan()));
    assert!(analysis::eigenvalues(&nalgebra::DMatrix::from_element(2, 2, f64::INFINITY)).iter().all(|v| v.re.is_nan()));
}

/// Hand-built local matrices whose parts do not fit together are an error (each of
/// these panicked inside the linear algebra), and a matrix that is not square, or is
/// empty, has no eigenvalues (panicked too).
#[test]
fn inconsistent_local_matrices_are_reported() {
    use analysis::{LocalMatrix, eigen_checks, local_matrix};
    use nalgebra::DMatrix;
    assert!(analysis::eigenvalues(&DMatrix::zeros(2, 3)).is_empty());
    assert!(analysis::eigenvalues(&DMatrix::zeros(0, 0)).is_empty());
    let chaikin = local_matrix(&CurveScheme::chaikin());
    let mut short = chaikin.clone();
    short.indices.pop();
    let cases = [
        (short, None, "3 labels for a local matrix of 4 rows"),
        (chaikin.clone(), Some(DMatrix::zeros(2, 2)), "the map to virtual points is 2 x 2, not 4 x 4"),
        (LocalMatrix { indices: vec![0, 1], matrix: DMatrix::zeros(2, 3) }, None, "is 2 x 3, not square"),
        (LocalMatrix { indices: vec![], matrix: DMatrix::zeros(0, 0) }, None, "is 0 x 0, not square and non-empty"),
    ];
    for (local, map, message) in cases {
        let error = eigen_checks(&local, map.as_ref()).unwrap_err();
        assert!(matches!(error, CurveError::IncompatibleLength { what: "eigen checks", .. }), "{error}");
        assert!(error.to_string().contains(message), "{error}");
    }
    // Consistent parts: the same checks as the analysis makes.
    let identity = DMatrix::identity(4, 4);
    assert_eq!(eigen_checks(&chaikin, Some(&identity)).unwrap(), eigen_checks(&chaikin, None).unwrap());
    assert_eq!(eigen_checks(&chaikin, None).unwrap(), analysis::analyze(&CurveScheme::chaikin()).eigen);
}

#[test]
fn the_tension_range_is_where_convergence_is_established() {
    let (lo, hi) = subdiv_curve::FOUR_POINT_TENSION_RANGE;
    for w in [lo, hi, 0.0, 1.0 / 16.0] {
        let symbol = CurveScheme::four_point(w).unwrap().symbol();
        assert!(contractivity(&symbol, 0, 12).established(), "w = {w}");
    }
    // Just outside, the 12-step test no longer establishes convergence.
    for w in [lo - 1e-3, hi + 1e-3] {
        let symbol = analysis::Symbol::new(-3, vec![-w, 0.0, 0.5 + w, 1.0, 0.5 + w, 0.0, -w]);
        assert!(!contractivity(&symbol, 0, 12).established(), "w = {w}");
    }
}

#[test]
fn refiner_reuses_buffers_across_calls() {
    let mut refiner = Refiner::new();
    let mut out = Vec::new();
    let scheme = CurveScheme::cubic_bspline();
    refiner.refine_into(&scheme, &wobbly(20), Topology::Closed, 4, &mut out).unwrap();
    let capacity = out.capacity();
    refiner.refine_into(&scheme, &wobbly(20), Topology::Closed, 4, &mut out).unwrap();
    assert_eq!(out.capacity(), capacity);
    assert_eq!(out, scheme.refine(&wobbly(20), Topology::Closed, 4).unwrap());
}

fn arb_polygon(min: usize) -> impl Strategy<Value = Vec<[f64; 2]>> {
    prop::collection::vec((-10.0..10.0f64, -10.0..10.0f64).prop_map(|(x, y)| [x, y]), min..24)
}

fn apply_affine(p: [f64; 2], m: [f64; 4], t: [f64; 2]) -> [f64; 2] {
    [m[0] * p[0] + m[1] * p[1] + t[0], m[2] * p[0] + m[3] * p[1] + t[1]]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    #[test]
    fn refinement_commutes_with_affine_maps(
        polygon in arb_polygon(4),
        m in prop::array::uniform4(-2.0..2.0f64),
        t in prop::array::uniform2(-5.0..5.0f64),
        closed in any::<bool>(),
        repeat in any::<bool>(),
    ) {
        let topology = if closed { Topology::Closed } else if repeat { Topology::Open(EndRule::Repeat) } else { Topology::open() };
        let moved: Vec<[f64; 2]> = polygon.iter().map(|&p| apply_affine(p, m, t)).collect();
        for scheme in [CurveScheme::chaikin(), CurveScheme::cubic_bspline(), CurveScheme::four_point(1.0 / 16.0).unwrap(),
                       CurveScheme::combined(0.01, 0.145).unwrap()] {
            let fine = scheme.refine(&polygon, topology, 3).unwrap();
            let expected: Vec<[f64; 2]> = fine.iter().map(|&p| apply_affine(p, m, t)).collect();
            let got = scheme.refine(&moved, topology, 3).unwrap();
            prop_assert!(close(&got, &expected, 1e-11 * 100.0), "{}", scheme.name());
            prop_assert_eq!(got.len(), scheme.refined_len(polygon.len(), topology, 3));
        }
    }
}
