//! Reversal of meshes whose coordinates are far from 1, at unit scale.
//!
//! The automatic choice ranks the readings of a mesh by their detail energies, sums of
//! squared detail lengths, and tests them against a zero threshold `(1e-12 d)^2` per
//! face (`d` the bounding-box diagonal). Squares overflow from about `1e154` and
//! underflow below about `1e-154`: a mesh scaled to `2^900` gave every reading an
//! infinite energy and one scaled to `2^-600` a zero one, so that all looked alike and
//! the first reading tried was kept, not the best (the reversal was still exact, of
//! another coarse mesh than the unscaled mesh's).
//!
//! Such a mesh is reversed as a copy scaled by the power of two that brings its largest
//! coordinate magnitude into `[1, 2)`, and the result is scaled back. Scaling by a power
//! of two is exact and commutes with every operation of the reversal (sums, products by
//! rule weights, comparisons) unless a value leaves the normal range, so the result is
//! the unscaled reversal as if its energies could not overflow, bit for bit (a value of
//! the copy below `2^-1022`, `2^-1023` times the largest coordinate and far below the
//! reconstruction tolerance, loses bits as a subnormal). Inside `2^±256` nothing is
//! copied and nothing changes. When the scaled-back result does not fit in `f64` (input
//! near `f64::MAX`), the mesh is reversed as it is, which reports the overflow as before.
//!
//! A pyramid whose base coordinates and details lie that far from 1 is reconstructed
//! (and its rate-distortion measured, and its details ranked for `keep`) the same way:
//! at unit scale the sums of the forward rules do not overflow where their result fits
//! (a reversal at unit scale may return coordinates near `f64::MAX` whose unscaled
//! reconstruction overflowed on the way); a result beyond `f64` is what the arithmetic
//! gives, as at any scale.
//!
//! Energies reported in [`SeedChoice`] are scaled back too, so they may be infinite or
//! zero where the true value is outside the `f64` range; the reason of the choice says
//! the ranking was made at unit scale and in what units its figures are.

use glam::DVec3;

use crate::reverse::SeedChoice;

/// An exact power-of-two change of scale: `down` brings the largest coordinate into
/// `[1, 2)`, [`up`](Self::up) undoes it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct UnitScale {
    down: f64,
}

impl UnitScale {
    /// The change of scale of `positions` ([`mesh_topo::scale::unit_scale`]), or `None`
    /// when they need none: their largest coordinate magnitude is within `2^±256` (where
    /// squared details stay well inside the `f64` range), or zero, or infinite, or they
    /// are empty (a NaN coordinate is passed over: the reversal of the scaled copy fails
    /// on it, and the mesh as given then reports it).
    pub(crate) fn of(positions: &[DVec3]) -> Option<Self> {
        Self::of_values(positions)
    }

    /// [`Self::of`], from the unit scale of `positions` if a pass that read them all
    /// measured it on the way (`measured`, [`mesh_topo::scale::unit_scale`]), else by a
    /// pass of its own.
    pub(crate) fn of_measured(measured: Option<f64>, positions: &[DVec3]) -> Option<Self> {
        match measured {
            Some(down) => (down != 1.0).then_some(Self { down }),
            None => Self::of(positions),
        }
    }

    /// [`Self::of`] for values in several arrays (a pyramid's base and details).
    pub(crate) fn of_values<'a>(values: impl IntoIterator<Item = &'a DVec3>) -> Option<Self> {
        let down = mesh_topo::scale::unit_scale(values);
        (down != 1.0).then_some(Self { down })
    }

    /// The inverse factor (exact: both are normal powers of two).
    fn up(&self) -> f64 {
        1.0 / self.down
    }

    /// `log2` of [`Self::up`].
    fn exponent(&self) -> i32 {
        self.up().log2() as i32
    }

    /// `positions` brought to unit scale.
    pub(crate) fn scale_down(&self, positions: &mut [DVec3]) {
        mesh_topo::scale::rescale(positions, self.down);
    }

    /// `values` of a reversal at unit scale brought back to the input's scale; whether
    /// they are all finite then.
    pub(crate) fn scale_up(&self, values: &mut [DVec3]) -> bool {
        mesh_topo::scale::rescale(values, self.up())
    }

    /// The energies of `choices`, made at unit scale, brought back to the input's scale
    /// (squares: twice the factor), their detail norms set (from the energies at unit
    /// scale: finite where the energies in the input's units are not), and a note of it
    /// in each reason.
    pub(crate) fn scale_up_choices(&self, choices: &mut [SeedChoice]) {
        // Two products, not one by `up * up`, which overflows for exponents above 511
        // (and `0 * inf` would be NaN).
        let up = self.up();
        let energy = |e: f64| e * up * up;
        for choice in choices {
            // The norm from the energy at unit scale: finite where the energy is not.
            choice.detail_norm = choice.detail_energy.sqrt() * up;
            choice.detail_energy = energy(choice.detail_energy);
            for trial in &mut choice.trials {
                if let Ok(e) = &mut trial.outcome {
                    *e = energy(*e);
                }
            }
            if !choice.given {
                choice.reason.push_str(&format!(
                    " (ranked on the mesh scaled by 2^{}, exactly, to keep the squares in range: the figures in \
                     this reason are in those units, the energies of the choice and its trials in the input's)",
                    -self.exponent()
                ));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_are_exact_powers_of_two_outside_the_safe_range() {
        let at = |x: f64| UnitScale::of(&[DVec3::new(0.5 * x, -x, 0.0)]);
        assert_eq!(at(1.0), None);
        assert_eq!(at(2f64.powi(256) * 1.9), None);
        assert_eq!(at(2f64.powi(-256)), None);
        assert_eq!(at(0.0), None);
        assert_eq!(UnitScale::of(&[]), None);
        assert_eq!(UnitScale::of(&[DVec3::new(1e-300, f64::NAN, 0.0)]).unwrap().exponent(), -997);
        assert_eq!(UnitScale::of(&[DVec3::new(1e300, f64::INFINITY, 0.0)]), None);
        let large = at(1e300).unwrap();
        assert_eq!((large.exponent(), large.up(), large.down), (996, 2f64.powi(996), 2f64.powi(-996)));
        assert_eq!(at(f64::MAX).unwrap().exponent(), 1022);
        assert_eq!(at(2f64.powi(-300)).unwrap().exponent(), -300);
        // A subnormal largest value: clamped, the factors still normal and exact.
        let tiny = UnitScale::of(&[DVec3::new(0.0, 0.0, 1e-320)]).unwrap();
        assert_eq!(tiny.exponent(), -1022);
        assert_eq!(tiny.up() * tiny.down, 1.0);
        let mut values = [DVec3::new(1e300, -3e299, 1.0)];
        large.scale_down(&mut values);
        assert!(large.scale_up(&mut values));
        assert_eq!(values, [DVec3::new(1e300, -3e299, 1.0)]);
        let mut overflowing = [DVec3::new(4.0, 0.0, 0.0)];
        assert!(!at(f64::MAX).unwrap().scale_up(&mut overflowing));
    }

    #[test]
    fn energies_are_scaled_back_by_the_square() {
        let scale = UnitScale::of(&[DVec3::splat(2f64.powi(600))]).unwrap();
        let mut choices = vec![SeedChoice {
            component: 0,
            seed_face: 3,
            given: false,
            trials: vec![crate::reverse::SeedTrial::valid(3, "F_F", 0.0, false)],
            detail_energy: 2f64.powi(-1000),
            detail_norm: f64::NAN,
            reason: "smallest".into(),
        }];
        scale.scale_up_choices(&mut choices);
        assert_eq!(choices[0].detail_energy, 2f64.powi(200));
        assert_eq!(choices[0].detail_norm, 2f64.powi(100));
        assert_eq!(choices[0].trials[0].outcome, Ok(0.0));
        assert!(choices[0].reason.starts_with("smallest (ranked on the mesh scaled by 2^-600"));
    }
}
