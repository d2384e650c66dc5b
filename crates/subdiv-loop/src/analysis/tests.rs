//! Tests of the spectral analysis against the published facts.

use rayon::prelude::*;

use super::*;
use crate::forward::kernel::loop_beta;

fn loop_lambda(n: usize) -> f64 {
    0.375 + 0.25 * (std::f64::consts::TAU / n as f64).cos()
}

#[test]
fn loop_subdominant_eigenvalue_is_the_closed_form_and_the_table() {
    for n in 3..=12 {
        let a = analyze(Scheme::Loop, n, &AnalysisOptions::spectrum_only()).unwrap();
        assert!((a.subdominant - loop_lambda(n)).abs() < 1e-12, "n = {n}: {}", a.subdominant);
        assert_eq!((a.algebraic_multiplicity, a.geometric_multiplicity, a.size), (2, 2, 3 * n + 1));
    }
    // The specification's table (six digits).
    for (n, table) in [(3, 0.25), (4, 0.375), (5, 0.452254), (6, 0.5), (7, 0.530872), (8, 0.551777)] {
        let a = analyze(Scheme::Loop, n, &AnalysisOptions::spectrum_only()).unwrap();
        assert!((a.subdominant - table).abs() < 5e-7, "n = {n}");
    }
}

#[test]
fn loop_spectrum_is_the_one_ring_spectrum_plus_one_eighth_and_one_sixteenth() {
    for n in 3..=12 {
        let a = analyze(Scheme::Loop, n, &AnalysisOptions::spectrum_only()).unwrap();
        let alpha = 1.0 - n as f64 * loop_beta(n);
        // One-ring: 1, alpha - 3/8 (= lambda^2 with Loop's weights), 3/8 + cos(2 pi k / n) / 4.
        assert!((alpha - 0.375 - loop_lambda(n).powi(2)).abs() < 1e-15);
        let mut expected = vec![1.0, alpha - 0.375];
        expected.extend((1..n).map(|k| 0.375 + 0.25 * (std::f64::consts::TAU * k as f64 / n as f64).cos()));
        let mut rest: Vec<f64> = a.eigenvalues.iter().map(|z| z[0]).collect();
        assert!(a.eigenvalues.iter().all(|z| z[1].abs() < 1e-12));
        for e in expected {
            let k = rest.iter().position(|x| (x - e).abs() < 1e-12).unwrap_or_else(|| panic!("n = {n}: {e} missing"));
            rest.remove(k);
        }
        // The second ring adds only the regular eigenvalues 1/8 and 1/16 (Stam 1998).
        assert_eq!(rest.len(), 2 * n);
        assert!(rest.iter().all(|x| (x - 0.125).abs() < 1e-12 || (x - 0.0625).abs() < 1e-12), "n = {n}: {rest:?}");
    }
}

#[test]
fn fourier_eigenvalues_are_the_eigenvalues_of_the_matrix() {
    // Independent of the Fourier split: traces of powers are the power sums of the
    // eigenvalues (multiplicities included), and every eigenvalue makes A - mu I singular.
    for scheme in Scheme::ALL {
        for n in [3, 5, 7, 10] {
            let a = analyze(scheme, n, &AnalysisOptions::spectrum_only()).unwrap();
            let local = local_subdivision_matrix(scheme, n, 2, &AnalysisOptions::default()).unwrap();
            let mut power = local.matrix.clone();
            for p in 1..=4 {
                let sum: f64 = a.eigenvalues.iter().map(|z| Complex::new(z[0], z[1]).powi(p).re).sum();
                assert!((power.trace() - sum).abs() < 1e-10, "{scheme} n = {n}, p = {p}");
                power *= &local.matrix;
            }
            for z in a.eigenvalues.iter().filter(|z| z[1] == 0.0) {
                let shifted = &local.matrix - DMatrix::identity(3 * n + 1, 3 * n + 1) * z[0];
                assert!(shifted.singular_values().min() < 1e-9, "{scheme} n = {n}: {}", z[0]);
            }
        }
    }
}

#[test]
fn local_matrices_are_affine_and_regular_at_valence_six() {
    for scheme in Scheme::ALL {
        for n in [3, 6, 9] {
            let local = local_subdivision_matrix(scheme, n, 2, &AnalysisOptions::default()).unwrap();
            for row in local.matrix.row_iter() {
                assert!((row.sum() - 1.0).abs() < 1e-13, "{scheme} n = {n}");
            }
        }
        // Regular: the subdominant eigenvalue is 1/M, with the regular 1/M^2 next.
        let a = analyze(scheme, 6, &AnalysisOptions::spectrum_only()).unwrap();
        let m = scheme.arity() as f64;
        assert!((a.subdominant - 1.0 / m).abs() < 1e-12, "{scheme}");
        assert!((a.next_modulus - 1.0 / (m * m)).abs() < 1e-12, "{scheme}");
    }
}

#[test]
fn ternary_one_ring_spectrum_is_one_lambda_lambda_squared_and_one_ninth() {
    for lambda in [1.0 / 3.0, 0.25] {
        let options = AnalysisOptions { lambda, ..AnalysisOptions::default() };
        for n in 3..=20 {
            let local = local_subdivision_matrix(Scheme::TernaryLoop, n, 2, &options).unwrap();
            let spectrum = fourier_spectrum(&local.matrix, n).unwrap();
            let mut one_ring: Vec<f64> = spectrum.iter().filter(|e| e.ring_one).map(|e| e.value.re).collect();
            one_ring.sort_by(|a, b| b.total_cmp(a));
            let mut expected = vec![1.0, 1.0 / 9.0];
            expected.extend((1..n).map(|k| lambda.powi(k.min(n - k) as i32)));
            expected.sort_by(|a, b| b.total_cmp(a));
            for (x, y) in one_ring.iter().zip(&expected) {
                assert!((x - y).abs() < 1e-12, "n = {n}, lambda = {lambda}: {one_ring:?}");
            }
        }
    }
}

#[test]
fn quaternary_spectrum_is_the_square_of_loops() {
    for n in [3, 5, 8, 13] {
        let (q, l) = (
            analyze(Scheme::QuaternaryLoop, n, &AnalysisOptions::spectrum_only()).unwrap(),
            analyze(Scheme::Loop, n, &AnalysisOptions::spectrum_only()).unwrap(),
        );
        for (x, y) in q.eigenvalues.iter().zip(&l.eigenvalues) {
            assert!((x[0] - y[0] * y[0]).abs() < 1e-12, "n = {n}");
        }
    }
}

/// Runs the full C1 check over valences 3 to 20.
fn c1_sweep(scheme: Scheme) -> Vec<Analysis> {
    (3..=20usize).into_par_iter().map(|n| analyze(scheme, n, &AnalysisOptions::default()).unwrap()).collect()
}

fn assert_c1(analyses: &[Analysis]) {
    for a in analyses {
        let map = a.characteristic_map.expect("eigenvalue conditions hold");
        assert!(a.c1, "{} n = {}: {:?} {map:?}", a.scheme, a.valence, a.conditions);
        assert!(map.triangles > 0 && map.area_ratio > 1e-3);
    }
}

#[test]
fn loop_and_warren_are_c1_for_valences_3_to_20() {
    assert_c1(&c1_sweep(Scheme::Loop));
    assert_c1(&c1_sweep(Scheme::LoopWarren));
}

#[test]
fn ternary_loop_is_c1_for_valences_3_to_20() {
    let analyses = c1_sweep(Scheme::TernaryLoop);
    for a in &analyses {
        assert!((a.subdominant - 1.0 / 3.0).abs() < 1e-12);
    }
    assert_c1(&analyses);
}

#[test]
fn quaternary_loop_is_c1_for_valences_3_to_20() {
    assert_c1(&c1_sweep(Scheme::QuaternaryLoop));
}

#[test]
fn a_map_that_winds_twice_is_not_injective() {
    // Mode 2 instead of mode 1: the characteristic check must notice.
    let local = local_subdivision_matrix(Scheme::Loop, 7, 4, &AnalysisOptions::default()).unwrap();
    let map = characteristic_map(Scheme::Loop, 7, loop_lambda(7), 2, &local, &AnalysisOptions::default()).unwrap();
    assert!(!map.injective(), "{map:?}");
}

#[test]
fn bad_parameters_are_rejected() {
    let options = AnalysisOptions::default();
    assert!(matches!(analyze(Scheme::Loop, 2, &options), Err(LoopError::InvalidParameter { name: "valence", .. })));
    assert!(analyze(Scheme::Loop, MAX_VALENCE + 1, &options).is_err());
    assert!(local_subdivision_matrix(Scheme::Loop, 5, 5, &options).is_err());
    let bad_lambda = AnalysisOptions { lambda: 0.9, ..options };
    assert!(analyze(Scheme::TernaryLoop, 5, &bad_lambda).is_err());
    assert_eq!("ternary-loop".parse::<Scheme>().unwrap(), Scheme::TernaryLoop);
    assert!("butterfly".parse::<Scheme>().is_err());
}

#[test]
fn too_many_characteristic_steps_are_rejected_at_once() {
    // `u32::MAX` steps used to refine until the allocation aborted.
    for (scheme, max) in
        [(Scheme::Loop, 7), (Scheme::LoopWarren, 7), (Scheme::TernaryLoop, 4), (Scheme::QuaternaryLoop, 3)]
    {
        for steps in [max + 1, u32::MAX] {
            let options = AnalysisOptions { characteristic_steps: Some(steps), ..AnalysisOptions::default() };
            assert!(
                matches!(
                    analyze(scheme, 5, &options),
                    Err(LoopError::InvalidParameter { name: "characteristic_steps", .. })
                ),
                "{scheme:?} {steps}"
            );
        }
    }
    let none = AnalysisOptions { characteristic_steps: Some(0), ..AnalysisOptions::default() };
    assert!(analyze(Scheme::Loop, 5, &none).is_ok());
}
