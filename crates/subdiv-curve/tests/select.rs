//! Spec §16.6 (MUST): choosing the points to interpolate from discrete curvature.

use glam::DVec3;
use subdiv_curve::select::{PointClass, SelectionOptions, select_interpolation_points};
use subdiv_curve::{CurveError, EndRule, Framework, Topology};

fn classes(points: &[(usize, PointClass)], class: PointClass) -> Vec<usize> {
    points.iter().filter(|(_, c)| *c == class).map(|(i, _)| *i).collect()
}

#[test]
fn sine_has_inflections_at_zero_crossings_and_maxima_at_crests() {
    // Two periods of sin, 8 samples per half period: zero crossings at 0, 8, 16, 24, 32,
    // crests at 4, 12, 20, 28.
    let sine: Vec<[f64; 2]> = (0..=32)
        .map(|k| {
            let t = k as f64 * std::f64::consts::PI / 8.0;
            [t, t.sin()]
        })
        .collect();
    let chosen = select_interpolation_points(&sine, Topology::open(), &SelectionOptions::default()).unwrap();
    assert_eq!(classes(&chosen.points, PointClass::Inflection), vec![8, 16, 24]);
    assert_eq!(classes(&chosen.points, PointClass::CurvatureMaximum), vec![4, 12, 20, 28]);
    assert_eq!(classes(&chosen.points, PointClass::EndPoint), vec![0, 32]);
    assert!(classes(&chosen.points, PointClass::Cusp).is_empty());
    // The flags are exactly the chosen points, and the curvature is signed: negative on
    // the crest at pi/2 (clockwise turn), positive in the trough.
    let flagged: Vec<usize> = (0..sine.len()).filter(|&i| chosen.flags[i]).collect();
    let mut listed: Vec<usize> = chosen.points.iter().map(|(i, _)| *i).collect();
    listed.sort_unstable();
    assert_eq!(flagged, listed);
    assert!(chosen.curvature[4].unwrap() < 0.0 && chosen.curvature[12].unwrap() > 0.0);
    // Without the end points when asked.
    let options = SelectionOptions { include_open_ends: false, ..SelectionOptions::default() };
    let chosen = select_interpolation_points(&sine, Topology::open(), &options).unwrap();
    assert!(classes(&chosen.points, PointClass::EndPoint).is_empty());
}

#[test]
fn ellipse_has_maxima_at_the_ends_of_the_major_axis() {
    for n in [16, 24, 40] {
        let ellipse: Vec<[f64; 2]> = (0..n)
            .map(|k| {
                let t = k as f64 * std::f64::consts::TAU / n as f64;
                [3.0 * t.cos(), t.sin()]
            })
            .collect();
        let chosen = select_interpolation_points(&ellipse, Topology::Closed, &SelectionOptions::default()).unwrap();
        assert_eq!(chosen.points, vec![(0, PointClass::CurvatureMaximum), (n / 2, PointClass::CurvatureMaximum)]);
    }
}

#[test]
fn a_160_degree_turn_is_a_cusp_and_the_threshold_is_respected() {
    let turn = 160f64.to_radians();
    let (c, s) = (std::f64::consts::PI - turn).sin_cos();
    // Along x to the origin, then back out at 160 degrees of turning.
    let points = [[-3.0, 0.0], [-2.0, 0.0], [-1.0, 0.0], [0.0, 0.0], [-s, c], [-2.0 * s, 2.0 * c], [-3.0 * s, 3.0 * c]];
    let chosen = select_interpolation_points(&points, Topology::open(), &SelectionOptions::default()).unwrap();
    assert!(chosen.points.contains(&(3, PointClass::Cusp)), "{:?}", chosen.points);
    let strict = SelectionOptions { cusp_angle_degrees: 170.0, ..SelectionOptions::default() };
    let chosen = select_interpolation_points(&points, Topology::open(), &strict).unwrap();
    assert!(!chosen.points.contains(&(3, PointClass::Cusp)), "{:?}", chosen.points);
}

#[test]
fn repeated_points_and_straight_runs_give_no_nan() {
    let points = [[0.0, 0.0], [0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]];
    for topology in [Topology::Closed, Topology::Open(EndRule::Reflect), Topology::Open(EndRule::Repeat)] {
        let chosen = select_interpolation_points(&points, topology, &SelectionOptions::default()).unwrap();
        assert!(chosen.curvature.iter().flatten().all(|k| k.is_finite()), "{:?}", chosen.curvature);
        assert_eq!(chosen.flags.len(), points.len());
        // The chosen flags drive the framework without trouble.
        let fine = Framework::published().refine(&points, &chosen.flags, topology, 3).unwrap();
        assert!(fine.iter().all(|p| p[0].is_finite() && p[1].is_finite()));
    }
    // All points equal: nothing is defined, nothing is NaN.
    let same = [[1.0, 1.0]; 5];
    let chosen = select_interpolation_points(&same, Topology::Closed, &SelectionOptions::default()).unwrap();
    assert!(chosen.curvature.iter().all(|k| k.is_none_or(|k| k.is_finite())));
}

#[test]
fn space_curves_use_unsigned_curvature() {
    // A helix-like closed curve with one sharp pinch; curvature is non-negative in space.
    let points: Vec<DVec3> = (0..24)
        .map(|k| {
            let t = k as f64 * std::f64::consts::TAU / 24.0;
            DVec3::new(2.0 * t.cos(), t.sin(), 0.3 * (2.0 * t).sin())
        })
        .collect();
    let chosen = select_interpolation_points(&points, Topology::Closed, &SelectionOptions::default()).unwrap();
    assert!(chosen.curvature.iter().flatten().all(|&k| k >= 0.0));
    assert!(chosen.points.contains(&(0, PointClass::CurvatureMaximum)));
    assert!(chosen.points.contains(&(12, PointClass::CurvatureMaximum)));
}

#[test]
fn bad_input() {
    let err = select_interpolation_points(&[[0.0, 0.0], [1.0, 0.0]], Topology::Closed, &SelectionOptions::default())
        .unwrap_err();
    assert!(matches!(err, CurveError::TooFewPoints { needed: 3, got: 2, .. }), "{err}");
    let err = select_interpolation_points(
        &[[0.0, 0.0], [1.0, f64::NAN], [2.0, 0.0]],
        Topology::open(),
        &SelectionOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(err, CurveError::NonFinite { index: 1, axis: 1, .. }), "{err}");
    let options = SelectionOptions { maximum_factor: -1.0, ..SelectionOptions::default() };
    let err =
        select_interpolation_points(&[[0.0, 0.0], [1.0, 1.0], [2.0, 0.0]], Topology::open(), &options).unwrap_err();
    assert!(matches!(err, CurveError::ParameterOutOfRange { .. }), "{err}");
    let err = select_interpolation_points(&[[0.0], [1.0], [2.0]], Topology::open(), &SelectionOptions::default())
        .unwrap_err();
    assert!(matches!(err, CurveError::Dimension { dim: 1, .. }), "{err}");
}

/// Points far from 1 are chosen as at unit scale (an exact power of two): cubed speeds
/// of 2^600 overflowed and of 2^-600 underflowed, and no point had a curvature. The
/// curvatures are reported in the points' units (an inverse length).
#[test]
fn the_choice_does_not_depend_on_the_scale() {
    let ellipse: Vec<[f64; 2]> = (0..24)
        .map(|k| {
            let t = k as f64 * std::f64::consts::TAU / 24.0;
            [3.0 * t.cos(), t.sin() + 0.2 * (3.0 * t).sin()]
        })
        .collect();
    let options = SelectionOptions::default();
    let unit = select_interpolation_points(&ellipse, Topology::Closed, &options).unwrap();
    assert!(unit.curvature.iter().all(Option::is_some) && !unit.points.is_empty());
    for exponent in [-600, 600] {
        let factor = 2f64.powi(exponent);
        let scaled: Vec<[f64; 2]> = ellipse.iter().map(|p| [p[0] * factor, p[1] * factor]).collect();
        let chosen = select_interpolation_points(&scaled, Topology::Closed, &options).unwrap();
        assert_eq!(chosen.points, unit.points, "2^{exponent}");
        assert_eq!(chosen.flags, unit.flags);
        let expected: Vec<Option<f64>> = unit.curvature.iter().map(|k| k.map(|k| k / factor)).collect();
        assert_eq!(chosen.curvature, expected, "2^{exponent}");
    }
}
