//! Point files read from arbitrary text, then refined and reversed.
//!
//! Whatever the bytes, `parse_points` returns points or an error naming a line, never a
//! panic. Points that parse are refined by every built-in scheme on open and closed
//! polygons, and reversed by Chaikin: no panic; a reversal that succeeds is finite and
//! rebuilds the input to rounding (relative to its largest coordinate), one level and
//! a whole pyramid; Chaikin refinement reverses to its input with zero details.

#![no_main]

use libfuzzer_sys::fuzz_target;
use subdiv_curve::io::{PointSet, parse_points};
use subdiv_curve::reverse::{decompose_chaikin, reconstruct_chaikin, reverse_chaikin};
use subdiv_curve::{CurvePoint, CurveScheme, EndRule, Topology};

/// Largest absolute coordinate.
fn largest<P: CurvePoint>(points: &[P]) -> f64 {
    points.iter().flat_map(|p| (0..P::DIM).map(|axis| p.coord(axis).abs())).fold(0.0, f64::max)
}

/// Largest coordinate difference of corresponding points.
fn distance<P: CurvePoint>(a: &[P], b: &[P]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(p, q)| largest(&[p.minus(*q)])).fold(0.0, f64::max)
}

fn check<P: CurvePoint>(points: &[P]) {
    let size = largest(points);
    let schemes = [CurveScheme::chaikin(), CurveScheme::cubic_bspline(), CurveScheme::four_point(1.0 / 16.0).unwrap()];
    for topology in [Topology::Closed, Topology::Open(EndRule::Reflect), Topology::Open(EndRule::Repeat)] {
        for scheme in &schemes {
            if let Ok(fine) = scheme.refine(points, topology, 2) {
                assert!(fine.iter().all(CurvePoint::is_finite), "{} refinement is not finite", scheme.name());
            }
        }
        if let Ok(split) = reverse_chaikin(points, topology) {
            assert_eq!(split.coarse.len() + split.details.len(), points.len());
            let finite = split.coarse.iter().chain(&split.details).all(CurvePoint::is_finite);
            assert!(finite, "reverse Chaikin of finite points is not finite");
            let back = reconstruct_chaikin(&split.coarse, &split.details, topology).expect("a split reconstructs");
            let error = distance(&back, points);
            assert!(error <= 1e-12 * size, "reconstruction error {error} for points of size {size}");
            let pyramid = decompose_chaikin(points, topology, 4).expect("one level exists");
            let back = pyramid.reconstruct(pyramid.details.len()).expect("the finest level exists");
            let error = distance(&back, points);
            assert!(error <= 1e-10 * size, "pyramid reconstruction error {error} for points of size {size}");
        }
        if let Ok(fine) = CurveScheme::chaikin().refine(points, topology, 1)
            && topology != Topology::Open(EndRule::Repeat)
            && let Ok(split) = reverse_chaikin(&fine, topology)
        {
            let error = distance(&split.coarse, points);
            assert!(error <= 1e-12 * size, "reverse of Chaikin is off by {error} for points of size {size}");
            assert!(split.details.iter().all(|d| largest(&[*d]) <= 1e-12 * size));
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    match parse_points(&text) {
        Ok(PointSet::Planar(points)) => check(&points),
        Ok(PointSet::Spatial(points)) => check(&points),
        Err(error) => {
            assert!(error.to_string().starts_with("line ") || error.to_string().contains("no points"), "{error}")
        }
    }
});
