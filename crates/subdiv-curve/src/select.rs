//! Automatic choice of the points to interpolate from discrete curvature (seed 004 rule
//! (9) and spec §16.6).
//!
//! Discrete derivatives with uniform parameter and central differences (closed polygons
//! wrap; open ones use the phantom points of their [`EndRule`]):
//! `x'_i = (P_{i+1} - P_{i-1})/2`, `x''_i = P_{i+1} - 2 P_i + P_{i-1}`; the curvature is
//! `K_i = |x'_i × x''_i| / |x'_i|^3`, signed in the plane (`(x' y'' - y' x'') / |x'|^3`).
//! `K_i` is *undefined* when `|x'_i|^3 < 1e-12 scale^3` (scale = bounding-box diagonal).
//! Three classes of points are chosen:
//!
//! - **Inflection** (seed rule (9)): the curvature changes sign across `i`
//!   (`K_{i-1} K_{i+1} < 0`; in space, the binormals `x' × x''` of `i-1` and `i+1` point
//!   to opposite sides) and `|K_i| < ε` or `K_i` is undefined. The seed gives no `ε`;
//!   default `ε = 0.1 median_j |K_j|` ([`SelectionOptions::inflection_factor`]).
//! - **Curvature maximum**: `|K_i| >= |K_{i-1}|`, `|K_i| > |K_{i+1}|` and
//!   `|K_i| >= κ median_j |K_j|`, default `κ = 2` ([`SelectionOptions::maximum_factor`]).
//! - **Cusp**: turning angle between `P_i - P_{i-1}` and `P_{i+1} - P_i` of at least
//!   `θ_c` (default 135°), or `K_i` undefined because `P_{i-1} ≈ P_{i+1} != P_i` (the
//!   polygon turns back).
//!
//! Open polygons also get their two **end points** (on by default,
//! [`SelectionOptions::include_open_ends`]), so the curve starts and ends at them under
//! either end rule. A point in several classes is reported once, in the first class of
//! the order cusp, inflection, maximum, end point. Repeated points and straight runs give
//! undefined or zero curvature, never NaN.
//!
//! ```
//! use subdiv_curve::{Topology, select::{PointClass, SelectionOptions, select_interpolation_points}};
//! // A zig-zag with one sharp spike: the spike is a cusp.
//! let points = [[0.0, 0.0], [1.0, 0.1], [2.0, 0.0], [2.1, 3.0], [2.2, 0.0], [3.0, 0.1], [4.0, 0.0]];
//! let chosen = select_interpolation_points(&points, Topology::open(), &SelectionOptions::default())?;
//! assert!(chosen.points.contains(&(3, PointClass::Cusp)));
//! assert_eq!(chosen.flags.len(), points.len());
//! # Ok::<(), subdiv_curve::CurveError>(())
//! ```

use glam::DVec3;

use crate::scheme::{EndRule, Topology};
use crate::{CurveError, CurvePoint};

/// Thresholds of the selection; `Default` gives the documented defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelectionOptions {
    /// `ε = inflection_factor · median |K|` (default 0.1).
    pub inflection_factor: f64,
    /// `κ`: maxima need `|K_i| >= κ · median |K|` (default 2).
    pub maximum_factor: f64,
    /// `θ_c` in degrees: cusps turn by at least this angle (default 135).
    pub cusp_angle_degrees: f64,
    /// Flag the end points of open polygons (default true).
    pub include_open_ends: bool,
}

impl Default for SelectionOptions {
    fn default() -> Self {
        SelectionOptions {
            inflection_factor: 0.1,
            maximum_factor: 2.0,
            cusp_angle_degrees: 135.0,
            include_open_ends: true,
        }
    }
}

/// Why a point was chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum PointClass {
    /// Sharp turn (or the polygon turns back).
    Cusp,
    /// The curvature changes sign.
    Inflection,
    /// Local maximum of the curvature magnitude.
    CurvatureMaximum,
    /// End point of an open polygon.
    EndPoint,
}

impl PointClass {
    /// Lower-case name (`cusp`, `inflection`, `maximum`, `end`).
    pub fn name(self) -> &'static str {
        match self {
            PointClass::Cusp => "cusp",
            PointClass::Inflection => "inflection",
            PointClass::CurvatureMaximum => "maximum",
            PointClass::EndPoint => "end",
        }
    }
}

/// The chosen points.
#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    /// One flag per input point (`true` = interpolate), for [`crate::Framework::refine`].
    pub flags: Vec<bool>,
    /// The chosen points with their class, by increasing index.
    pub points: Vec<(usize, PointClass)>,
    /// The discrete curvature of every point (`None` where undefined); signed for planar
    /// input, non-negative in space.
    pub curvature: Vec<Option<f64>>,
}

/// Chooses the points to interpolate (see the [module docs](self)).
///
/// # Errors
/// [`CurveError::Dimension`] unless the points are 2D or 3D; [`CurveError::NonFinite`];
/// [`CurveError::TooFewPoints`] (closed: 3, open: 2); [`CurveError::ParameterOutOfRange`]
/// for a negative or non-finite threshold.
///
/// ```
/// use subdiv_curve::{Topology, select::{PointClass, SelectionOptions, select_interpolation_points}};
/// // An ellipse with semi-axes 3 and 1: curvature maxima at the ends of the major axis.
/// let ellipse: Vec<[f64; 2]> = (0..24)
///     .map(|k| { let t = k as f64 * std::f64::consts::TAU / 24.0; [3.0 * t.cos(), t.sin()] })
///     .collect();
/// let chosen = select_interpolation_points(&ellipse, Topology::Closed, &SelectionOptions::default())?;
/// assert_eq!(chosen.points, vec![(0, PointClass::CurvatureMaximum), (12, PointClass::CurvatureMaximum)]);
/// # Ok::<(), subdiv_curve::CurveError>(())
/// ```
pub fn select_interpolation_points<P: CurvePoint>(
    points: &[P],
    topology: Topology,
    options: &SelectionOptions,
) -> Result<Selection, CurveError> {
    if !(P::DIM == 2 || P::DIM == 3) {
        return Err(CurveError::Dimension { what: "curvature", expected: "2D or 3D", dim: P::DIM });
    }
    for (parameter, value) in [
        ("inflection_factor", options.inflection_factor),
        ("maximum_factor", options.maximum_factor),
        ("cusp_angle_degrees", options.cusp_angle_degrees),
    ] {
        if !(value.is_finite() && value >= 0.0) {
            return Err(CurveError::ParameterOutOfRange { parameter, value, range: "finite and >= 0".into() });
        }
    }
    let n = points.len();
    let needed = if topology.is_closed() { 3 } else { 2 };
    if n < needed {
        return Err(CurveError::TooFewPoints {
            what: "curvature-based selection".into(),
            needed,
            got: n,
            closed: topology.is_closed(),
        });
    }
    crate::point::check_finite(points)?;
    // Measured at unit scale (an exact power of two; 1 inside 2^±256): cubed speeds and
    // cross products of points far from 1 overflowed or underflowed, and every point
    // lost its curvature. The choice does not depend on the scale; curvatures are
    // reported in the points' units.
    let unit = crate::point::unit_scale(points.iter().flat_map(|q| q.to_dvec3().to_array()));
    let p: Vec<DVec3> = points.iter().map(|q| q.to_dvec3() * unit).collect();
    let scale = crate::point::bbox_diagonal(&p);
    let at = |i: i64| -> DVec3 {
        let n = n as i64;
        match topology {
            Topology::Closed => p[i.rem_euclid(n) as usize],
            Topology::Open(_) if (0..n).contains(&i) => p[i as usize],
            Topology::Open(rule) => {
                let (end, inner) = if i < 0 { (0, 1) } else { (n - 1, n - 2) };
                match rule {
                    EndRule::Reflect => 2.0 * p[end as usize] - p[inner as usize],
                    EndRule::Repeat => p[end as usize],
                }
            }
        }
    };
    let mut flags = vec![false; n];
    let mut chosen = Vec::new();
    if scale == 0.0 {
        // All points coincide: no curvature, no turn, nothing to choose.
        return Ok(Selection { flags, points: chosen, curvature: vec![None; n] });
    }
    let planar = P::DIM == 2;
    let mut binormal = vec![DVec3::ZERO; n];
    let mut curvature = vec![None; n];
    for i in 0..n {
        let (prev, here, next) = (at(i as i64 - 1), at(i as i64), at(i as i64 + 1));
        let first = (next - prev) / 2.0;
        let second = next - 2.0 * here + prev;
        let speed_cubed = first.length().powi(3);
        binormal[i] = first.cross(second);
        if speed_cubed >= 1e-12 * scale.powi(3) {
            curvature[i] = Some(if planar { binormal[i].z } else { binormal[i].length() } / speed_cubed);
        }
    }
    let magnitudes: Vec<f64> = curvature.iter().flatten().map(|k| k.abs()).collect();
    let median = median(magnitudes);
    let epsilon = options.inflection_factor * median;
    let cusp_cos = options.cusp_angle_degrees.to_radians().cos();
    let index = |i: i64| -> Option<usize> {
        match topology {
            Topology::Closed => Some(i.rem_euclid(n as i64) as usize),
            Topology::Open(_) => (0..n as i64).contains(&i).then_some(i as usize),
        }
    };
    let magnitude = |i: Option<usize>| i.and_then(|i| curvature[i]).map(f64::abs);
    let length_tolerance = 1e-9 * scale;
    for i in 0..n {
        let (prev, next) = (index(i as i64 - 1), index(i as i64 + 1));
        let interior = prev.is_some() && next.is_some();
        // Cusp: a sharp turn, or the polygon turns back on itself.
        let incoming = p[i] - at(i as i64 - 1);
        let outgoing = at(i as i64 + 1) - p[i];
        let turns_back = curvature[i].is_none()
            && (at(i as i64 + 1) - at(i as i64 - 1)).length() <= length_tolerance
            && incoming.length() > length_tolerance;
        let sharp = incoming.length() > length_tolerance
            && outgoing.length() > length_tolerance
            && incoming.dot(outgoing) <= cusp_cos * incoming.length() * outgoing.length();
        let cusp = interior && (sharp || turns_back);
        let inflection = interior && {
            let (b_prev, b_next) = (binormal[prev.expect("interior")], binormal[next.expect("interior")]);
            let opposite = curvature[prev.expect("interior")].is_some()
                && curvature[next.expect("interior")].is_some()
                && b_prev.dot(b_next) < 0.0;
            opposite && magnitude(Some(i)).is_none_or(|k| k < epsilon)
        };
        let maximum = match magnitude(Some(i)) {
            Some(k) => {
                magnitude(prev).is_none_or(|kp| k >= kp)
                    && magnitude(next).is_none_or(|kn| k > kn)
                    && k >= options.maximum_factor * median
                    && k > 0.0
            }
            None => false,
        };
        let end = !interior && options.include_open_ends;
        let class = if cusp {
            Some(PointClass::Cusp)
        } else if inflection {
            Some(PointClass::Inflection)
        } else if maximum {
            Some(PointClass::CurvatureMaximum)
        } else if end {
            Some(PointClass::EndPoint)
        } else {
            None
        };
        if let Some(class) = class {
            flags[i] = true;
            chosen.push((i, class));
        }
    }
    // Curvature is an inverse length: back to the points' units.
    let curvature = curvature.into_iter().map(|k| k.map(|k| k * unit)).collect();
    Ok(Selection { flags, points: chosen, curvature })
}

fn median(mut values: Vec<f64>) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let mid = values.len() / 2;
    if values.len() % 2 == 1 { values[mid] } else { 0.5 * (values[mid - 1] + values[mid]) }
}
