//! Measuring geometry far from 1 at unit scale.
//!
//! Squares of coordinates beyond about `1e154` overflow and below about `1e-154`
//! underflow: distances, areas, cross products and squared-norm rankings of such meshes
//! come out infinite or zero although the quantities themselves fit in `f64`. Scaling by
//! a power of two is exact and commutes with every arithmetic operation unless a value
//! leaves the normal range, so a quantity measured on values scaled by
//! [`unit_scale`] and scaled back is that of the values as given. Inside `2^±256` the
//! scale is 1 and nothing changes, to the bit.
//!
//! ```
//! use mesh_topo::DVec3;
//! use mesh_topo::scale::{unit_normal, unit_scale};
//!
//! let tiny = [DVec3::new(3e-200, 0.0, 0.0), DVec3::new(0.0, 1e-200, 0.0)];
//! let scale = unit_scale(&tiny);
//! assert_eq!(scale, 2f64.powi(663)); // 3e-200 lies in [2^-663, 2^-662)
//! // The cross product underflows to zero; the unit normal does not.
//! assert_eq!(tiny[0].cross(tiny[1]), DVec3::ZERO);
//! assert_eq!(unit_normal(tiny[0], tiny[1]), Some(DVec3::Z));
//! assert_eq!(unit_scale(&[DVec3::new(1e10, -2.0, 0.5)]), 1.0);
//! ```

use glam::DVec3;

/// Values whose largest magnitude has a binary exponent within `±SAFE_EXPONENT` are
/// measured as they are: their squares, and sums of many squares, stay well inside the
/// normal range.
pub const SAFE_EXPONENT: i32 = 256;

/// The power of two that brings `largest` (a largest magnitude) into `[1, 2)` when its
/// binary exponent lies outside `±`[`SAFE_EXPONENT`], else 1 (also for zero and
/// non-finite values). Always a normal number: a subnormal `largest` is brought near
/// `2^-41`, still far inside the safe range.
///
/// ```
/// use mesh_topo::scale::unit_scale_of;
///
/// assert_eq!(unit_scale_of(1e10), 1.0); // inside 2^±256: left alone
/// assert_eq!(unit_scale_of(-1e300), 2f64.powi(-996)); // 1e300 lies in [2^996, 2^997)
/// assert!((1.0..2.0).contains(&(1e300 * unit_scale_of(1e300))));
/// assert_eq!(unit_scale_of(f64::INFINITY), 1.0);
/// ```
pub fn unit_scale_of(largest: f64) -> f64 {
    let largest = largest.abs();
    if largest == 0.0 || !largest.is_finite() {
        return 1.0;
    }
    let exponent = largest.log2().floor() as i32;
    if (-SAFE_EXPONENT..=SAFE_EXPONENT).contains(&exponent) {
        return 1.0;
    }
    // 2^-exponent, with the exponent kept where both it and its inverse are normal.
    f64::from_bits(((1023 - exponent.clamp(-1022, 1022)) as u64) << 52)
}

/// [`unit_scale_of`] the largest coordinate magnitude of `points` (NaN coordinates are
/// passed over).
pub fn unit_scale<'a>(points: impl IntoIterator<Item = &'a DVec3>) -> f64 {
    unit_scale_of_magnitudes(largest_magnitudes(points))
}

/// The running maxima of [`fold_magnitudes`] over `points`, from `DVec3::ZERO`, in four
/// lanes (points `4i + k` in lane `k`) joined at the end: one running maximum is a chain
/// of dependent vector maxima, about four cycles a point, which made this pass 4% of a
/// two-level Loop decomposition; four chains run side by side at the speed of the loads.
/// The maximum does not depend on the order, so the result is that of one chain.
fn largest_magnitudes<'a>(points: impl IntoIterator<Item = &'a DVec3>) -> DVec3 {
    let mut points = points.into_iter();
    let mut lanes = [DVec3::ZERO; 4];
    'points: loop {
        for lane in &mut lanes {
            let Some(&p) = points.next() else { break 'points };
            *lane = fold_magnitudes(*lane, p);
        }
    }
    lanes.into_iter().fold(DVec3::ZERO, fold_magnitudes)
}

/// One step of the running maximum that [`unit_scale`] folds over its points: each
/// coordinate's largest magnitude so far (`largest`, from `DVec3::ZERO`) against that of
/// `p`, a NaN coordinate passed over. For a pass that reads the points anyway and can
/// measure them on the way, in any order, instead of a pass of its own; then
/// [`unit_scale_of_magnitudes`].
///
/// ```
/// use mesh_topo::DVec3;
/// use mesh_topo::scale::{fold_magnitudes, unit_scale, unit_scale_of_magnitudes};
///
/// let points = [DVec3::new(1e300, -2.0, f64::NAN), DVec3::new(0.5, -3e301, 1.0)];
/// let largest = points.iter().fold(DVec3::ZERO, |m, &p| fold_magnitudes(m, p));
/// assert_eq!(largest, DVec3::new(1e300, 3e301, 1.0));
/// assert_eq!(unit_scale_of_magnitudes(largest), unit_scale(&points));
/// ```
#[inline]
pub fn fold_magnitudes(largest: DVec3, p: DVec3) -> DVec3 {
    // A plain comparison, which compiles to a vector maximum (`f64::max` handles NaN
    // and does not): one pass at memory speed, cheap beside any operation on the mesh.
    let p = p.abs();
    DVec3::new(larger(p.x, largest.x), larger(p.y, largest.y), larger(p.z, largest.z))
}

/// [`unit_scale_of`] the largest of the three magnitudes that [`fold_magnitudes`] kept.
///
/// ```
/// use mesh_topo::DVec3;
/// use mesh_topo::scale::unit_scale_of_magnitudes;
///
/// assert_eq!(unit_scale_of_magnitudes(DVec3::new(1.0, 1e300, 2.0)), 2f64.powi(-996));
/// assert_eq!(unit_scale_of_magnitudes(DVec3::ZERO), 1.0);
/// ```
pub fn unit_scale_of_magnitudes(largest: DVec3) -> f64 {
    unit_scale_of(larger(largest.x, larger(largest.y, largest.z)))
}

/// `a` if it is larger than `b`, else `b` (so a NaN `a` gives `b`).
#[inline]
fn larger(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

/// Multiplies every one of `values` by `factor` (for a change of scale, a power of two:
/// exact unless a value leaves the range); whether they are all finite then.
///
/// ```
/// use mesh_topo::DVec3;
/// use mesh_topo::scale::{rescale, unit_scale};
///
/// let original = [DVec3::new(1e300, -2.0, 0.0)];
/// let mut values = original;
/// let scale = unit_scale(&values);
/// assert!(rescale(&mut values, scale));
/// assert!((1.0..2.0).contains(&values[0].x));
/// assert!(rescale(&mut values, 1.0 / scale));
/// assert_eq!(values, original); // powers of two: exact both ways
/// assert!(!rescale(&mut values, 2f64.powi(100))); // 1e300 * 2^100 overflows
/// ```
pub fn rescale(values: &mut [DVec3], factor: f64) -> bool {
    let mut finite = true;
    for value in values {
        *value *= factor;
        finite &= value.is_finite();
    }
    finite
}

/// The unit vector along `a × b`, measured at unit scale so that the product neither
/// overflows nor underflows (see the [module docs](self)); `None` when `a` and `b` are
/// parallel, one is zero, or a coordinate is not finite.
///
/// ```
/// use mesh_topo::DVec3;
/// use mesh_topo::scale::unit_normal;
///
/// let (a, b) = (DVec3::new(1e200, 0.0, 0.0), DVec3::new(0.0, 3e200, 0.0));
/// assert_eq!(a.cross(b).z, f64::INFINITY); // the plain product overflows
/// assert_eq!(unit_normal(a, b), Some(DVec3::Z));
/// assert_eq!(unit_normal(a, -2.0 * a), None); // parallel
/// assert_eq!(unit_normal(DVec3::ZERO, b), None);
/// ```
pub fn unit_normal(a: DVec3, b: DVec3) -> Option<DVec3> {
    let scale = unit_scale_of(a.abs().max_element().max(b.abs().max_element()));
    (a * scale).cross(b * scale).try_normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_are_exact_powers_of_two_outside_the_safe_range() {
        assert_eq!(unit_scale_of(2f64.powi(256) * 1.99), 1.0);
        assert_eq!(unit_scale_of(2f64.powi(-256)), 1.0);
        assert_eq!(unit_scale_of(-1e300), 2f64.powi(-996));
        assert_eq!(unit_scale_of(f64::MAX), 2f64.powi(-1022));
        assert_eq!(unit_scale_of(2f64.powi(-300)), 2f64.powi(300));
        assert_eq!(unit_scale_of(5e-324), 2f64.powi(1022));
        for x in [0.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(unit_scale_of(x), 1.0, "{x}");
        }
        assert_eq!(unit_scale(&[]), 1.0);
        assert_eq!(unit_scale(&[DVec3::new(f64::NAN, 1e300, 0.0)]), 2f64.powi(-996));
        let mut values = [DVec3::new(1e300, -2.0, 0.0)];
        assert!(rescale(&mut values, 2f64.powi(-996)));
        assert!(rescale(&mut values, 2f64.powi(996)));
        assert_eq!(values, [DVec3::new(1e300, -2.0, 0.0)]);
        assert!(!rescale(&mut values, 2f64.powi(100)));
    }

    #[test]
    fn the_lanes_of_the_largest_magnitudes_agree_with_one_chain() {
        let values = [1.0, -3e300, f64::NAN, 0.5, -7.0, 2e-300, f64::INFINITY, -0.0, 4.0, -1e10, 3.0];
        for n in 0..=values.len() {
            for shift in 0..3 {
                let points: Vec<DVec3> = (0..n)
                    .map(|i| DVec3::new(values[i], values[(i + shift) % n], values[(i + 2 * shift + 1) % n]))
                    .collect();
                let one_chain = points.iter().fold(DVec3::ZERO, |largest, &p| fold_magnitudes(largest, p));
                assert_eq!(largest_magnitudes(&points), one_chain, "{n} points, shift {shift}");
            }
        }
    }

    #[test]
    fn unit_normals_do_not_depend_on_the_scale() {
        let (a, b) = (DVec3::new(1.0, 0.25, -0.5), DVec3::new(-0.125, 1.0, 0.75));
        let unit = unit_normal(a, b).unwrap();
        assert_eq!(unit, a.cross(b).normalize());
        for exponent in [-1000, -600, 600, 1000] {
            let factor = 2f64.powi(exponent);
            assert_eq!(unit_normal(a * factor, b * factor), Some(unit), "2^{exponent}");
        }
        assert_eq!(unit_normal(a, 2.0 * a), None);
        assert_eq!(unit_normal(DVec3::ZERO, b), None);
        assert_eq!(unit_normal(DVec3::new(f64::NAN, 0.0, 0.0), b), None);
        assert_eq!(unit_normal(DVec3::new(f64::MAX, 0.0, 0.0), DVec3::new(0.0, f64::MAX, 0.0)), Some(DVec3::Z));
    }
}
