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
