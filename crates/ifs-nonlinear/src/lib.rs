//! Subdivision as iterated function systems, complex-parameter subdivision, nonlinear
//! subdivision by nonlinear means, nonlinear IFS, and fractal rendering.
//!
//! References: seed 003 (nonlinear subdivisions and fractals), R. Goldman's subdivision
//! with complex parameters, Schaefer–Levin–Goldman "Subdivision schemes and attractors"
//! (2005), Schaefer–Vouga–Goldman "Nonlinear subdivision through nonlinear averaging"
//! (2008); summarised and checked in ALGORITHMS.md §9, §13–§15.
//!
//! | piece | entry points | spec |
//! |---|---|---|
//! | subdivision matrices | [`bezier_split`], [`tensor_patch_split`], [`triangle_patch_split`], [`sierpinski`], [`complex_bezier_split`], [`uniform_scheme_split`] (any uniform binary curve scheme from its mask), [`curve_scheme_split`] (any `subdiv-curve` scheme) | §13, §15.1, §9, §1.1 |
//! | linear IFS | [`AffineIfs::from_rule`] (seed form `P̂^{-1} S_i P̂`), [`BarycentricIfs`] (any number of points), [`ComplexBezierIfs`] | §15.1, §13 |
//! | contractivity | [`SubdivisionRule::contractivity`], [`ContractivityReport`] (largest singular value, joint-spectral-radius bounds) | §13, §15.1 |
//! | rendering | [`deterministic_points`], [`chaos_points`], [`chaos_density`], [`Density`], [`Image::encode_png`] | §15.2 |
//! | nonlinear means | [`Mean`], [`CircleMean`], [`two_point_subdivide`], [`three_point_subdivide`], [`subdivide_with_rule`] | §14 |
//! | nonlinear IFS | [`NonlinearIfs`] with [`SquareY`], [`ExpY`], [`Polar`] or [`FnTransform`] | §14, §15.1 |
//! | examples | [`preset`], [`PRESETS`] | §13, §15.3 |
//!
//! # Example: a Bézier curve is the attractor of its subdivision IFS
//! ```
//! use ifs_nonlinear::{BarycentricIfs, bezier_split, deterministic_points};
//! let control = [[0.0, 0.0], [1.0, 2.0], [3.0, 0.0]];
//! let ifs = BarycentricIfs::new(&bezier_split(2, 0.5)?, &control)?;
//! let points = deterministic_points(&ifs, None, 10, 1 << 20)?;
//! // Every point is within 1e-5 of the curve B(t) = (2t + t², 4t(1-t)).
//! let on_curve = |p: &[f64; 3]| {
//!     let t = -1.0 + (1.0 + p[0]).sqrt(); // invert x(t) = 2t + t²
//!     (p[1] - 4.0 * t * (1.0 - t)).abs()
//! };
//! assert!(points.iter().map(on_curve).fold(0.0, f64::max) < 1e-5);
//! # Ok::<(), ifs_nonlinear::IfsError>(())
//! ```
//!
//! # Example: the Lévy C curve from a complex parameter, as a PNG
//! ```
//! use ifs_nonlinear::{ChaosGame, ComplexBezierIfs, Projection, ToneMap, chaos_points, render_points};
//! use num_complex::Complex64;
//! let control = [Complex64::new(0.0, 0.0), Complex64::new(1.0, 0.0)];
//! let levy = ComplexBezierIfs::new(Complex64::new(0.5, 0.5), &control)?;
//! let points = chaos_points(&levy, &ChaosGame { points: 20_000, seed: 1, ..ChaosGame::default() })?;
//! let png = render_points(&points, 200, 150, Projection::Xy, ToneMap::Log)?.encode_png()?;
//! assert_eq!(&png[1..4], b"PNG");
//! # Ok::<(), ifs_nonlinear::IfsError>(())
//! ```
//!
//! # Example: nonlinear subdivision with the geometric mean
//! ```
//! use ifs_nonlinear::{Mean, MeanMode, two_point_subdivide};
//! let samples: Vec<[f64; 2]> = (0..3).map(|i| [i as f64, (-(i as f64)).exp()]).collect();
//! let fine = two_point_subdivide(&samples, Mean::Geometric, MeanMode::YOnly)?;
//! assert!((fine[1][1] - (-0.5f64).exp()).abs() < 1e-15); // stays on y = e^{-x}
//! # Ok::<(), ifs_nonlinear::IfsError>(())
//! ```
//!
//! # Errata of the seed (ALGORITHMS.md §13, §15.3, §17 rows 14–16)
//! * **Convergence of complex-parameter subdivision.** The seed says `r = |z| < 1` ensures
//!   convergence. It does not: both `|z| < 1` and `|1 - z| < 1` are needed (z = -0.5 has
//!   r = 0.5 but `|1 - z| = 1.5` and diverges); for degree ≥ 2 the joint spectral radius
//!   on the difference space is also checked. [`ComplexBezierIfs::new`] returns
//!   [`IfsError::NotContractive`] naming the failed condition.
//! * **The "Gauss curve".** The seed's IFS `F ∘ T_i ∘ F^{-1}` with `F(x, w) = (x, w²)` and
//!   control points (−1,0), (0,5), (1,0) draws the quartic `(25/4)(1 − x²)²`, not a
//!   Gaussian. The preset is called `quartic-bump` (aliases `gaussian`, `gauss`: the seed's
//!   name); a true Gaussian is `exp-gaussian` (F = exp).
//! * **"Markov matrices".** Subdivision matrices with complex entries are not stochastic;
//!   what matters (and what [`SubdivisionRule::new`] checks) is that rows sum to 1.
//!
//! # Decisions where the spec leaves a choice
//! * Chaos-game probabilities default to `|det|` of the linear parts (difference-space
//!   determinants for the barycentric form), floored at 1 % of the largest so that
//!   singular maps are still visited ([`Probabilities`]).
//! * Contractivity is certified by `max_{|w| = k} ||D_w||_2^{1/k} < 1` for some word length
//!   k ≤ 10 (at most 1024 products per length); the lower bound uses spectral radii. The
//!   work is capped ([`matrices::CONTRACTIVITY_WORK_BUDGET`]), so that large patches
//!   (degree (20, 20) and beyond) get a quick, possibly inconclusive answer
//!   ([`ContractivityReport::capped`]) instead of minutes of matrix products.
//! * Densities are accumulated in integers (bilinear weights in 1/256 steps) so that
//!   parallel results are bit-identical for any thread count; see [`render`].
//!
//! # Determinism
//! Seeded ChaCha8 streams per fixed chunk of [`CHAOS_CHUNK`] points: the output depends on
//! the seed, never on the number of threads.

pub mod error;
pub mod ifs;
pub mod matrices;
pub mod mean;
pub mod nonlinear;
pub mod presets;
pub mod render;

pub use error::{IfsError, Result};
pub use ifs::{AffineIfs, AffineMap, BarycentricIfs, ComplexBezierIfs, Ifs};
pub use matrices::{
    ContractivityReport, MAX_MULTI_INDEX_DEGREE, SubdivisionRule, bezier_split, complex_bezier_split,
    curve_scheme_split, sierpinski, tensor_patch_split, triangle_multi_indices, triangle_patch_split,
    uniform_scheme_split,
};
pub use mean::{CircleMean, Mean, MeanMode, subdivide_with_rule, three_point_subdivide, two_point_subdivide};
pub use nonlinear::{
    CoordinateTransform, ExpY, FnTransform, MAX_TRIANGLE_SAMPLES, NonlinearIfs, Polar, SquareY, triangle_samples,
};
/// Complex numbers (control points and parameters of complex-parameter subdivision).
pub use num_complex::Complex64;
pub use presets::{PRESETS, Scene, barnsley_fern, canonical_preset, preset};
pub use render::{
    CHAOS_CHUNK, Canvas, ChaosGame, Density, Image, MAX_BURN_IN, MAX_LEVELS, MAX_OCCUPANCY_GRID, PointStats,
    Probabilities, Projection, ToneMap, View, chaos_density, chaos_points, deterministic_into, deterministic_points,
    render_points,
};
