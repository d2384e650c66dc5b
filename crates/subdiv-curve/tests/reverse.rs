//! Spec §3 (MUST): reverse Chaikin.

use glam::DVec3;
use proptest::prelude::*;
use subdiv_curve::reverse::{decompose_chaikin, reconstruct_chaikin, reverse_chaikin};
use subdiv_curve::{CurveError, CurveScheme, Topology};

fn max_difference(a: &[DVec3], b: &[DVec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(p, q)| (*p - *q).abs().max_element()).fold(0.0, f64::max)
}

fn arb_points(len: impl Into<prop::collection::SizeRange>) -> impl Strategy<Value = Vec<DVec3>> {
    prop::collection::vec(prop::array::uniform3(-100.0..100.0f64).prop_map(DVec3::from_array), len)
}

fn topologies() -> [Topology; 2] {
    [Topology::Closed, Topology::open()]
}

#[test]
fn coarse_and_detail_rows() {
    // Probe the linear maps with unit vectors on a closed fine polygon of 12 points.
    for k in 0..12 {
        let mut fine = vec![0.0; 12];
        fine[k] = 1.0;
        let split = reverse_chaikin(&fine, Topology::Closed).unwrap();
        // Coarse point 3 reads fine points 4, 5, 6, 7 with (-1/4, 3/4, 3/4, -1/4).
        let expected = match k {
            4 | 7 => -0.25,
            5 | 6 => 0.75,
            _ => 0.0,
        };
        assert_eq!(split.coarse[3], expected, "coarse row, fine point {k}");
        let expected_detail = match k {
            4 => 0.25,
            5 => -0.75,
            6 => 0.75,
            7 => -0.25,
            _ => 0.0,
        };
        assert_eq!(split.details[3], expected_detail, "detail row, fine point {k}");
    }
}

#[test]
fn storage_and_lengths() {
    for topology in topologies() {
        let fine: Vec<DVec3> = (0..20).map(|k| DVec3::new(k as f64, (k * k) as f64, 1.0)).collect();
        let split = reverse_chaikin(&fine, topology).unwrap();
        assert_eq!(split.coarse.len() + split.details.len(), fine.len());
    }
    let seven = vec![DVec3::ZERO; 7];
    assert!(matches!(reverse_chaikin(&seven, Topology::Closed), Err(CurveError::IncompatibleLength { .. })));
    assert!(matches!(reverse_chaikin(&seven, Topology::open()), Err(CurveError::IncompatibleLength { .. })));
    assert!(matches!(
        reverse_chaikin(&[DVec3::ZERO; 4], Topology::Closed),
        Err(CurveError::TooFewPoints { needed: 6, got: 4, .. })
    ));
    assert!(matches!(
        reverse_chaikin(&[DVec3::ZERO; 2], Topology::open()),
        Err(CurveError::TooFewPoints { needed: 4, got: 2, .. })
    ));
    let mut nan = vec![DVec3::ZERO; 6];
    nan[5].y = f64::NAN;
    assert!(matches!(reverse_chaikin(&nan, Topology::Closed), Err(CurveError::NonFinite { index: 5, axis: 1, .. })));
    assert!(reconstruct_chaikin(&[DVec3::ZERO; 3], &[DVec3::ZERO; 4], Topology::Closed).is_err());
}

#[test]
fn moved_vertex_round_trip_over_three_levels() {
    // Subdivide three times, move one point, decompose three levels, rebuild exactly.
    let base: Vec<DVec3> = (0..5).map(|k| DVec3::new((k as f64).cos(), (k as f64).sin(), 0.1 * k as f64)).collect();
    for topology in topologies() {
        let mut fine = CurveScheme::chaikin().refine(&base, topology, 3).unwrap();
        fine[7] += DVec3::new(0.3, -0.2, 0.5);
        let pyramid = decompose_chaikin(&fine, topology, 3).unwrap();
        assert_eq!(pyramid.details.len(), 3);
        assert!(max_difference(&pyramid.reconstruct(3).unwrap(), &fine) < 1e-14);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn reverse_of_chaikin_is_the_original_with_zero_details(coarse in arb_points(3..30), closed in any::<bool>()) {
        let topology = if closed { Topology::Closed } else { Topology::open() };
        let fine = CurveScheme::chaikin().refine(&coarse, topology, 1).unwrap();
        let split = reverse_chaikin(&fine, topology).unwrap();
        let scale = 100.0;
        prop_assert!(max_difference(&split.coarse, &coarse) <= 4e-16 * scale * 4.0);
        prop_assert!(split.details.iter().all(|d| d.abs().max_element() <= 4e-16 * scale * 4.0));
    }

    #[test]
    fn reconstruct_of_reverse_is_the_input(half in 3usize..30, points in arb_points(60), closed in any::<bool>()) {
        let topology = if closed { Topology::Closed } else { Topology::open() };
        let fine = &points[..2 * half];
        let split = reverse_chaikin(fine, topology).unwrap();
        let back = reconstruct_chaikin(&split.coarse, &split.details, topology).unwrap();
        prop_assert!(max_difference(&back, fine) <= 1e-15 * 100.0 * 4.0, "{}", max_difference(&back, fine));
    }

    #[test]
    fn coarse_is_affine_invariant_and_details_translation_invariant(
        half in 3usize..20, points in arb_points(40), shift in prop::array::uniform3(-50.0..50.0f64),
        scale in 0.1..3.0f64, closed in any::<bool>(),
    ) {
        let topology = if closed { Topology::Closed } else { Topology::open() };
        let fine = &points[..2 * half];
        let shift = DVec3::from_array(shift);
        let split = reverse_chaikin(fine, topology).unwrap();
        let moved: Vec<DVec3> = fine.iter().map(|p| *p * scale + shift).collect();
        let moved_split = reverse_chaikin(&moved, topology).unwrap();
        let expected: Vec<DVec3> = split.coarse.iter().map(|p| *p * scale + shift).collect();
        prop_assert!(max_difference(&moved_split.coarse, &expected) < 1e-12);
        let translated: Vec<DVec3> = fine.iter().map(|p| *p + shift).collect();
        let translated_split = reverse_chaikin(&translated, topology).unwrap();
        prop_assert!(max_difference(&translated_split.details, &split.details) < 1e-12);
    }
}

#[test]
fn open_end_rule_keeps_the_end_points_and_records_the_end_details() {
    // Forward: the endpoint-keeping variant, 2n points for n coarse points.
    let coarse = [DVec3::new(0.0, 0.0, 0.0), DVec3::new(4.0, 0.0, 1.0), DVec3::new(4.0, 8.0, 2.0)];
    let fine = CurveScheme::chaikin().refine(&coarse, Topology::open(), 1).unwrap();
    let expected = [
        coarse[0],
        0.75 * coarse[0] + 0.25 * coarse[1],
        0.25 * coarse[0] + 0.75 * coarse[1],
        0.75 * coarse[1] + 0.25 * coarse[2],
        0.25 * coarse[1] + 0.75 * coarse[2],
        coarse[2],
    ];
    assert_eq!(fine, expected.to_vec());

    // Reverse of an arbitrary open polygon: the end coarse points are the fine end points,
    // their details the offset of the single candidate from them (spec §3.2).
    let moved: Vec<DVec3> = (0..8).map(|k| DVec3::new(k as f64, ((k * 7) % 5) as f64, (k % 3) as f64)).collect();
    let split = reverse_chaikin(&moved, Topology::open()).unwrap();
    let (n, last) = (split.coarse.len(), moved.len() - 1);
    assert_eq!(n, 4);
    assert_eq!((split.coarse[0], split.coarse[n - 1]), (moved[0], moved[last]));
    let first_candidate = 1.5 * moved[1] - 0.5 * moved[2];
    let last_candidate = 1.5 * moved[last - 1] - 0.5 * moved[last - 2];
    assert!((split.details[0] - (first_candidate - moved[0])).length() < 1e-15);
    assert!((split.details[n - 1] - (last_candidate - moved[last])).length() < 1e-15);
    // Interior points: the mean of the two candidates, half their difference as detail.
    let (a1, b1) = (1.5 * moved[3] - 0.5 * moved[4], 1.5 * moved[2] - 0.5 * moved[1]);
    assert!((split.coarse[1] - 0.5 * (a1 + b1)).length() < 1e-15);
    assert!((split.details[1] - 0.5 * (a1 - b1)).length() < 1e-15);
    let back = reconstruct_chaikin(&split.coarse, &split.details, Topology::open()).unwrap();
    assert!(max_difference(&back, &moved) < 1e-14);
    // A Chaikin refinement reverses to its coarse polygon with zero details, ends included.
    let split = reverse_chaikin(&fine, Topology::open()).unwrap();
    assert!(max_difference(&split.coarse, &coarse) < 1e-15);
    assert!(split.details.iter().all(|d| d.length() < 1e-15));
}

#[test]
fn coordinates_that_overflow_are_an_error_not_infinities() {
    // Found by the `points_chaikin` fuzz target: finite points beyond half of `f64::MAX`
    // reversed to infinite coarse points, and reconstruction then gave NaN.
    let huge: Vec<[f64; 2]> = (0..6).map(|i| [1.7e308, f64::from(i)]).collect();
    for topology in topologies() {
        let error = reverse_chaikin(&huge, topology).unwrap_err();
        assert!(matches!(error, CurveError::Overflow { .. }), "{error}");
        assert!(error.to_string().starts_with("reverse Chaikin (coarse points): point "), "{error}");
        assert!(decompose_chaikin(&huge, topology, 3).is_err());
    }
    // Details that push a reconstructed point past the largest `f64`.
    let coarse = [[1e308, 0.0], [1e308, 1.0], [0.0, 1.0]];
    let details = [[1e308, 0.0], [0.0, 0.0], [0.0, 0.0]];
    let error = reconstruct_chaikin(&coarse, &details, Topology::Closed).unwrap_err();
    assert_eq!(error, CurveError::Overflow { what: "Chaikin reconstruction", index: 0 });
    // Finite coarse points and details whose candidates `c + d`, `c - d` are not: refused
    // (reconstruction forms them). Found by the fuzz target after the first fix.
    let text = "1.7e308 0\n-1.7e08 3\n1.7308 1\n1.7e308 2\n-1.e307 4\n1.7e208 5\n";
    let subdiv_curve::io::PointSet::Planar(points) = subdiv_curve::io::parse_points(text).unwrap() else {
        panic!("planar points")
    };
    let error = reverse_chaikin(&points, Topology::Closed).unwrap_err();
    assert!(matches!(error, CurveError::Overflow { what: "reverse Chaikin (candidate points)", .. }), "{error}");
    // Large coordinates that stay finite are reversed exactly.
    let large: Vec<[f64; 2]> = (0..6).map(|i| [8.0e307 + f64::from(i) * 1e300, 1.0]).collect();
    let split = reverse_chaikin(&large, Topology::Closed).unwrap();
    let back = reconstruct_chaikin(&split.coarse, &split.details, Topology::Closed).unwrap();
    assert!(back.iter().zip(&large).all(|(a, b)| (a[0] - b[0]).abs() <= 1e-15 * b[0]));
}

#[test]
fn refinement_that_overflows_is_an_error_and_large_finite_input_is_not() {
    // Found by the same fuzz target: the four-point rule (weights -1/16, 9/16, 9/16,
    // -1/16) puts the new point between two points of 1.7e308 whose outer neighbours
    // are -1.7e308 at 9/8 of that, past the largest `f64`.
    let alternating: Vec<[f64; 2]> =
        [1.7e308, -1.7e308, 1.7e308, -1.7e308, 1.7e308, 1.7e308].iter().map(|&x| [x, 1.0]).collect();
    let four_point = CurveScheme::four_point(1.0 / 16.0).unwrap();
    for topology in [Topology::Closed, Topology::open()] {
        let error = four_point.refine(&alternating, topology, 1).unwrap_err();
        assert!(matches!(error, CurveError::Overflow { what: "refinement", .. }), "{error}");
    }
    // Chaikin's weights are convex: the same points refine to finite points.
    let fine = CurveScheme::chaikin().refine(&alternating, Topology::Closed, 3).unwrap();
    assert!(fine.iter().all(|p| p[0].is_finite()));
    // The framework checks its result too (every point interpolated: virtual points).
    let framework = subdiv_curve::Framework::published();
    let error = framework.refine(&alternating, &[true; 6], Topology::Closed, 2).unwrap_err();
    assert!(matches!(error, CurveError::Overflow { what: "framework refinement", .. }), "{error}");
}
