//! Nonlinear IFS `f_i = F ∘ T_i ∘ F^{-1}` (seed 003, ALGORITHMS.md §14, §15.1) with a
//! locally invertible coordinate transform F.
//!
//! The maps are applied literally, one conjugated map at a time (F^{-1}, then the affine
//! `T_i`, then F), as in the seed; when the state leaves the domain of F^{-1} the renderer
//! reports [`IfsError::Domain`] with the point index. On the
//! attractor (the image under F of the linear attractor, when F^{-1} ∘ F is the identity
//! there) the conjugation telescopes: `f_{w_1} ∘ … ∘ f_{w_k} = F ∘ T_{w_1} ∘ … ∘ T_{w_k} ∘ F^{-1}`.

use crate::error::{IfsError, Result, check_finite};
use crate::ifs::{AffineIfs, Ifs};

/// A locally invertible map F of R^3 (2D IFS use the first two coordinates; z passes through).
pub trait CoordinateTransform: Sync {
    /// F.
    fn forward(&self, p: [f64; 3]) -> [f64; 3];
    /// The local inverse F^{-1}, `None` outside its domain.
    fn inverse(&self, p: [f64; 3]) -> Option<[f64; 3]>;
    /// Domain of F^{-1}, for error messages.
    fn domain(&self) -> &'static str;
}

/// `F(x, w) = (x, w²)`, `F^{-1}(x, y) = (x, √y)` for y ≥ 0: the power-mean transform of
/// the seed's "Gauss" IFS (ALGORITHMS.md §14.2, §15.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SquareY;

impl CoordinateTransform for SquareY {
    #[inline]
    fn forward(&self, p: [f64; 3]) -> [f64; 3] {
        [p[0], p[1] * p[1], p[2]]
    }
    #[inline]
    fn inverse(&self, p: [f64; 3]) -> Option<[f64; 3]> {
        (p[1] >= 0.0).then(|| [p[0], p[1].sqrt(), p[2]])
    }
    fn domain(&self) -> &'static str {
        "y >= 0 (square root)"
    }
}

/// `F(x, u) = (x, e^u)`, `F^{-1}(x, y) = (x, ln y)` for y > 0: the geometric-mean transform
/// (ALGORITHMS.md §14.1); quadratic Bézier curves in (x, u) become true Gaussians.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ExpY;

impl CoordinateTransform for ExpY {
    #[inline]
    fn forward(&self, p: [f64; 3]) -> [f64; 3] {
        [p[0], p[1].exp(), p[2]]
    }
    #[inline]
    fn inverse(&self, p: [f64; 3]) -> Option<[f64; 3]> {
        (p[1] > 0.0).then(|| [p[0], p[1].ln(), p[2]])
    }
    fn domain(&self) -> &'static str {
        "y > 0 (logarithm)"
    }
}

/// Polar coordinates: `F(r, θ) = (r cos θ, r sin θ)`, `F^{-1}(x, y) = (|(x, y)|, atan2(y, x))`
/// with θ ∈ (-π, π], defined away from the origin. Bends straight-line sets into arcs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Polar;

impl CoordinateTransform for Polar {
    #[inline]
    fn forward(&self, p: [f64; 3]) -> [f64; 3] {
        let (s, c) = p[1].sin_cos();
        [p[0] * c, p[0] * s, p[2]]
    }
    #[inline]
    fn inverse(&self, p: [f64; 3]) -> Option<[f64; 3]> {
        let r = p[0].hypot(p[1]);
        (r > 0.0).then(|| [r, p[1].atan2(p[0]), p[2]])
    }
    fn domain(&self) -> &'static str {
        "points other than the origin (polar angle)"
    }
}

/// A user-supplied pair (F, F^{-1}) of closures.
///
/// ```
/// use ifs_nonlinear::{CoordinateTransform, FnTransform};
/// let cube_y = FnTransform::new(|p: [f64; 3]| [p[0], p[1].powi(3), p[2]], |p: [f64; 3]| Some([p[0], p[1].cbrt(), p[2]]));
/// assert_eq!(cube_y.forward([1.0, 2.0, 0.0]), [1.0, 8.0, 0.0]);
/// ```
pub struct FnTransform<F, G> {
    forward: F,
    inverse: G,
}

impl<F, G> FnTransform<F, G>
where
    F: Fn([f64; 3]) -> [f64; 3] + Sync,
    G: Fn([f64; 3]) -> Option<[f64; 3]> + Sync,
{
    /// Wraps F and its local inverse.
    pub fn new(forward: F, inverse: G) -> Self {
        Self { forward, inverse }
    }
}

impl<F, G> CoordinateTransform for FnTransform<F, G>
where
    F: Fn([f64; 3]) -> [f64; 3] + Sync,
    G: Fn([f64; 3]) -> Option<[f64; 3]> + Sync,
{
    fn forward(&self, p: [f64; 3]) -> [f64; 3] {
        (self.forward)(p)
    }
    fn inverse(&self, p: [f64; 3]) -> Option<[f64; 3]> {
        (self.inverse)(p)
    }
    fn domain(&self) -> &'static str {
        "the user transform's domain"
    }
}

/// The nonlinear IFS `{F ∘ T_i ∘ F^{-1}}` of an affine IFS `{T_i}` (states are points of
/// the nonlinear picture).
///
/// ```
/// use ifs_nonlinear::{AffineIfs, NonlinearIfs, SquareY, bezier_split, deterministic_points};
/// // The seed's "Gauss curve": really the quartic (25/4)(1 - x²)² (ALGORITHMS.md §15.3).
/// let linear = AffineIfs::from_rule(&bezier_split(2, 0.5)?, &[[-1.0, 0.0], [0.0, 5.0], [1.0, 0.0]])?;
/// let ifs = NonlinearIfs::new(linear, SquareY);
/// let points = deterministic_points(&ifs, None, 10, 1 << 20)?;
/// let residual = points.iter().map(|p| (p[1] - 6.25 * (1.0 - p[0] * p[0]).powi(2)).abs()).fold(0.0, f64::max);
/// assert!(residual < 1e-4);
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub struct NonlinearIfs<F> {
    linear: AffineIfs,
    transform: F,
    start: Vec<f64>,
}

impl<F: CoordinateTransform> NonlinearIfs<F> {
    /// Conjugates `linear` by `transform`. The default start set is F of the linear IFS's
    /// default start set.
    ///
    /// ```
    /// use ifs_nonlinear::{AffineIfs, ExpY, Ifs, NonlinearIfs, bezier_split};
    /// let linear = AffineIfs::from_rule(&bezier_split(2, 0.5)?, &[[-1.0, 0.0], [0.0, 1.0], [1.0, 0.0]])?;
    /// let ifs = NonlinearIfs::new(linear.clone(), ExpY);
    /// assert_eq!((ifs.linear(), ifs.transform()), (&linear, &ExpY));
    /// // The linear start set is the curve's end points (-1, 0) and (1, 0); F = exp on y makes y = 1.
    /// let start = ifs.default_start();
    /// assert!(start.iter().zip([-1.0, 1.0, 1.0, 1.0]).all(|(s, e)| (s - e).abs() < 1e-12), "{start:?}");
    /// # Ok::<(), ifs_nonlinear::IfsError>(())
    /// ```
    pub fn new(linear: AffineIfs, transform: F) -> Self {
        let d = linear.dim();
        let start = linear
            .default_start()
            .chunks_exact(d)
            .flat_map(|s| {
                let p = transform.forward(linear.point(s));
                p[..d].to_vec()
            })
            .collect();
        Self { linear, transform, start }
    }

    /// The underlying affine IFS.
    pub fn linear(&self) -> &AffineIfs {
        &self.linear
    }

    /// The transform F.
    pub fn transform(&self) -> &F {
        &self.transform
    }

    /// Maps linear-picture points through F (e.g. a start set given before the transform).
    ///
    /// # Errors
    /// [`IfsError::NotFinite`] naming the point and coordinate of a NaN or infinite input;
    /// [`IfsError::Domain`] naming the point whose image under F is not finite (e.g. y = 1000
    /// under [`ExpY`], whose e^1000 overflows), rather than an infinite start point.
    ///
    /// ```
    /// use ifs_nonlinear::{AffineIfs, ExpY, IfsError, NonlinearIfs, bezier_split};
    /// let linear = AffineIfs::from_rule(&bezier_split(2, 0.5)?, &[[-1.0, 0.0], [0.0, 1.0], [1.0, 0.0]])?;
    /// let ifs = NonlinearIfs::new(linear, ExpY);
    /// assert_eq!(ifs.forward_points(&[[0.0, 0.0, 0.0]])?, vec![[0.0, 1.0, 0.0]]);
    /// let overflow = ifs.forward_points(&[[0.0, 0.0, 0.0], [0.0, 1000.0, 0.0]]);
    /// assert!(matches!(overflow, Err(IfsError::Domain { index: 1, .. })));
    /// # Ok::<(), IfsError>(())
    /// ```
    pub fn forward_points(&self, points: &[[f64; 3]]) -> Result<Vec<[f64; 3]>> {
        points
            .iter()
            .enumerate()
            .map(|(index, p)| {
                for (k, &v) in p.iter().enumerate() {
                    check_finite(v, || format!("point {index}, coordinate {k}"))?;
                }
                let image = self.transform.forward(*p);
                if image.iter().all(|v| v.is_finite()) {
                    Ok(image)
                } else {
                    Err(IfsError::Domain {
                        index,
                        value: format!("{p:?} (image {image:?})"),
                        what: "coordinate transform F".into(),
                        domain: "points whose image under F is finite",
                    })
                }
            })
            .collect()
    }
}

impl<F: CoordinateTransform> Ifs for NonlinearIfs<F> {
    fn map_count(&self) -> usize {
        self.linear.map_count()
    }
    fn state_len(&self) -> usize {
        self.linear.dim()
    }
    fn point_dim(&self) -> usize {
        self.linear.dim()
    }
    #[inline]
    fn apply(&self, map: usize, state: &[f64], out: &mut [f64]) -> bool {
        let d = self.linear.dim();
        let p = if d == 2 { [state[0], state[1], 0.0] } else { [state[0], state[1], state[2]] };
        let Some(u) = self.transform.inverse(p) else { return false };
        let v = self.linear.maps()[map].apply(d, u);
        let q = self.transform.forward(v);
        out[..d].copy_from_slice(&q[..d]);
        q[..d].iter().all(|x| x.is_finite())
    }
    #[inline]
    fn point(&self, state: &[f64]) -> [f64; 3] {
        self.linear.point(state)
    }
    fn default_start(&self) -> Vec<f64> {
        self.start.clone()
    }
    fn determinants(&self) -> Vec<f64> {
        self.linear.determinants()
    }
    fn domain(&self) -> &'static str {
        self.transform.domain()
    }
    fn contractivity_report(&self) -> Option<crate::ContractivityReport> {
        Some(self.linear.contractivity())
    }
}

/// Most intervals per side of [`triangle_samples`]: 4096 gives about 8.4 million points
/// (134 MB), far beyond what a start set needs, and keeps the count from overflowing.
pub const MAX_TRIANGLE_SAMPLES: usize = 4096;

/// Samples of a filled triangle: `n + 1` points per side (`n = 0` counts as 1), all lattice
/// points `(i a + j b + k c)/n`, i + j + k = n, as concatenated `x, y` states (the
/// deterministic start set "from a triangle").
///
/// # Errors
/// [`IfsError::NotFinite`] naming a NaN or infinite corner coordinate (a start set is not
/// allowed to smuggle NaN into the renderers); [`IfsError::ParameterOutOfRange`] for `n`
/// above [`MAX_TRIANGLE_SAMPLES`] (`usize::MAX` used to overflow the point count and abort).
///
/// ```
/// assert_eq!(ifs_nonlinear::triangle_samples([0.0, 0.0], [1.0, 0.0], [0.0, 1.0], 4)?.len(), 15 * 2);
/// # Ok::<(), ifs_nonlinear::IfsError>(())
/// ```
pub fn triangle_samples(a: [f64; 2], b: [f64; 2], c: [f64; 2], n: usize) -> Result<Vec<f64>> {
    for (corner, point) in [a, b, c].iter().enumerate() {
        for (k, &v) in point.iter().enumerate() {
            check_finite(v, || format!("triangle corner {corner}, coordinate {k}"))?;
        }
    }
    if n > MAX_TRIANGLE_SAMPLES {
        return Err(IfsError::ParameterOutOfRange {
            name: "n",
            value: n.to_string(),
            reason: "at most MAX_TRIANGLE_SAMPLES = 4096 intervals per side",
        });
    }
    let n = n.max(1);
    let mut out = Vec::with_capacity((n + 1) * (n + 2));
    for i in (0..=n).rev() {
        for j in (0..=n - i).rev() {
            let k = n - i - j;
            let w = [i as f64 / n as f64, j as f64 / n as f64, k as f64 / n as f64];
            out.push(w[0] * a[0] + w[1] * b[0] + w[2] * c[0]);
            out.push(w[0] * a[1] + w[1] * b[1] + w[2] * c[1]);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::matrices::{bezier_split, sierpinski};
    use crate::render::deterministic_points;

    fn quartic() -> NonlinearIfs<SquareY> {
        let linear =
            AffineIfs::from_rule(&bezier_split(2, 0.5).unwrap(), &[[-1.0, 0.0], [0.0, 5.0], [1.0, 0.0]]).unwrap();
        NonlinearIfs::new(linear, SquareY)
    }

    /// The seed's explicit maps: f_1: x' = x/2 - 1/2, y' = (5x/4 + √y/4 + 5/4)²,
    /// f_2: x' = x/2 + 1/2, y' = (-5x/4 + √y/4 + 5/4)².
    #[test]
    fn quartic_bump_maps_are_the_seed_formulas() {
        let ifs = quartic();
        let mut out = [0.0; 2];
        for (x, y) in [(0.3, 2.0), (-0.7, 0.1), (0.0, 6.25)] {
            assert!(ifs.apply(0, &[x, y], &mut out));
            let expected = [x / 2.0 - 0.5, (5.0 * x / 4.0 + y.sqrt() / 4.0 + 1.25).powi(2)];
            assert!((out[0] - expected[0]).abs() < 1e-14 && (out[1] - expected[1]).abs() < 1e-13);
            assert!(ifs.apply(1, &[x, y], &mut out));
            let expected = [x / 2.0 + 0.5, (-5.0 * x / 4.0 + y.sqrt() / 4.0 + 1.25).powi(2)];
            assert!((out[0] - expected[0]).abs() < 1e-14 && (out[1] - expected[1]).abs() < 1e-13);
        }
        assert!(!ifs.apply(0, &[0.0, -1.0], &mut out));
    }

    /// ALGORITHMS.md §15.3: residual vs (25/4)(1 - x²)² after 14 levels from the triangle
    /// is about 5e-8.
    #[test]
    fn quartic_bump_residual_after_14_levels() {
        let ifs = quartic();
        let triangle = ifs.forward_points(&[[-1.0, 0.0, 0.0], [0.0, 5.0, 0.0], [1.0, 0.0, 0.0]]).unwrap();
        let start: Vec<f64> = triangle.iter().flat_map(|p| [p[0], p[1]]).collect();
        assert_eq!(start, vec![-1.0, 0.0, 0.0, 25.0, 1.0, 0.0]);
        let points = deterministic_points(&ifs, Some(&start), 14, 1 << 20).unwrap();
        let residual = points.iter().map(|p| (p[1] - 6.25 * (1.0 - p[0] * p[0]).powi(2)).abs()).fold(0.0, f64::max);
        // Spec: 4.7e-8 (measured 4.66e-8).
        assert!((4.0e-8..5.0e-8).contains(&residual), "residual {residual:e}");
    }

    #[test]
    fn nonlinear_sierpinski_is_the_image_of_the_linear_one() {
        let linear = AffineIfs::from_rule(&sierpinski(), &[[1.0, 0.0], [2.0, 0.0], [1.0, 1.5]]).unwrap();
        let bent = NonlinearIfs::new(linear.clone(), Polar);
        let a = deterministic_points(&linear, None, 5, 1 << 16).unwrap();
        let b = deterministic_points(&bent, None, 5, 1 << 16).unwrap();
        for (p, q) in a.iter().zip(&b) {
            let f = Polar.forward(*p);
            assert!((f[0] - q[0]).abs() < 1e-12 && (f[1] - q[1]).abs() < 1e-12);
        }
    }

    /// A user-supplied pair (F, F^{-1}) gives the same system as the built-in transform.
    #[test]
    fn user_supplied_transform_pairs_work_like_the_built_in_ones() {
        let user = FnTransform::new(
            |p: [f64; 3]| [p[0], p[1] * p[1], p[2]],
            |p: [f64; 3]| (p[1] >= 0.0).then(|| [p[0], p[1].sqrt(), p[2]]),
        );
        let linear = quartic().linear().clone();
        let ours = deterministic_points(&NonlinearIfs::new(linear, user), None, 8, 1 << 16).unwrap();
        let built_in = deterministic_points(&quartic(), None, 8, 1 << 16).unwrap();
        assert_eq!(ours, built_in);
        // exp/log as a user pair: the attractor is exp of the linear attractor in y.
        let log_pair = FnTransform::new(
            |p: [f64; 3]| [p[0], p[1].exp(), p[2]],
            |p: [f64; 3]| (p[1] > 0.0).then(|| [p[0], p[1].ln(), p[2]]),
        );
        let linear = AffineIfs::from_rule(&sierpinski(), &[[0.0, -1.0], [1.0, 0.5], [0.0, 1.0]]).unwrap();
        let bent = deterministic_points(&NonlinearIfs::new(linear.clone(), log_pair), None, 5, 1 << 16).unwrap();
        let straight = deterministic_points(&linear, None, 5, 1 << 16).unwrap();
        for (p, q) in bent.iter().zip(&straight) {
            assert!((p[0] - q[0]).abs() < 1e-12 && (p[1] - q[1].exp()).abs() < 1e-12 * q[1].exp().max(1.0));
        }
    }

    /// `forward_points` used to return `Ok([0, inf, 0])` for y = 1000 under exp, and pass
    /// NaN through.
    #[test]
    fn forward_points_name_overflowing_and_non_finite_points() {
        let linear = AffineIfs::from_rule(&sierpinski(), &[[0.0, -1.0], [1.0, 0.5], [0.0, 1.0]]).unwrap();
        let ifs = NonlinearIfs::new(linear, ExpY);
        let err = ifs.forward_points(&[[0.0, 1.0, 0.0], [0.0, 1000.0, 0.0]]).unwrap_err();
        assert!(matches!(err, IfsError::Domain { index: 1, .. }), "{err:?}");
        let err = ifs.forward_points(&[[f64::NAN, 1.0, 0.0]]).unwrap_err();
        assert!(matches!(&err, IfsError::NotFinite { what, .. } if what == "point 0, coordinate 0"), "{err:?}");
        assert_eq!(ifs.forward_points(&[[2.0, 0.0, 0.0]]).unwrap(), vec![[2.0, 1.0, 0.0]]);
    }

    /// `usize::MAX` samples per side overflowed the point count (abort); NaN corners went
    /// into the start set.
    #[test]
    fn triangle_samples_check_their_input() {
        let (a, b, c) = ([0.0, 0.0], [1.0, 0.0], [0.0, 1.0]);
        assert!(matches!(triangle_samples(a, b, c, usize::MAX), Err(IfsError::ParameterOutOfRange { name: "n", .. })));
        let err = triangle_samples(a, [1.0, f64::NAN], c, 4).unwrap_err();
        assert!(matches!(&err, IfsError::NotFinite { what, .. } if what == "triangle corner 1, coordinate 1"));
        assert_eq!(triangle_samples(a, b, c, 1).unwrap(), vec![0.0, 0.0, 1.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn leaving_the_domain_is_a_typed_error() {
        // A linear IFS whose maps push y below 0, conjugated by the logarithm.
        let linear = AffineIfs::from_rule(&sierpinski(), &[[0.0, -1.0], [1.0, 0.5], [0.0, 1.0]]).unwrap();
        let ifs = NonlinearIfs::new(linear, ExpY);
        // Start at points with y <= 0 (outside ln's domain).
        let result = deterministic_points(&ifs, Some(&[0.5, -0.5]), 1, 100);
        assert!(matches!(result, Err(IfsError::Domain { index: 0, .. })), "{result:?}");
    }
}
