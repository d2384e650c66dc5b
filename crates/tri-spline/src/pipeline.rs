//! The fitting pipeline of seed paper 001 (ALGORITHMS.md §12.4), with LSPIA and
//! classical PIA as alternatives: from a triangle mesh to a fitted surface and the
//! convergence table.
//!
//! 1. **Parameters** ([`crate::param`]): natural barycentric parameters for a regular
//!    triangular grid, a convex-combination map otherwise.
//! 2. **Control net** ([`crate::coarsen`]): `i` levels of reverse Loop subdivision. For a
//!    Bézier patch or B-patch the input must be a regular triangular grid with `N`
//!    segments per side, `N` divisible by `2^i`: the coarse net is then a grid of
//!    `n = N / 2^i` segments, the control net of a degree-`n` patch (control point `β` at
//!    the coarse vertex with lattice coordinates `(β1, β2)`). A triangular B-spline takes
//!    the coarse mesh, with its vertices' parameters, as the control net of a DMS spline
//!    of degree 2 (or as chosen) through [`crate::dms_net`].
//! 3. **Knots.** Bézier patches have none. B-patch knots are our documented choice (the
//!    seed says only that its knots are "updated", without a rule; ALGORITHMS.md §10
//!    keeps them fixed): `r_0, s_0, t_0` are the domain corners and `r_i = t0 + (i/n) δ
//!    (t0 - centre)` (likewise `s_i`, `t_i`) with `δ =`
//!    [`FitOptions::bpatch_knot_spread`], so every knot triangle contains the domain and
//!    has its orientation. DMS knot clouds: [`KnotPlacement`] around every vertex of the
//!    net and of its ghost ring.
//! 4. **Iteration** ([`crate::fit`]): LSPIA (default), classical PIA towards the data at
//!    the control points' own vertices (Chen–Wang's setting for Bézier patches), or the
//!    seed loop with `R` the `i`-fold reverse Loop map. Every iteration reports `k`,
//!    `ε_max`, `ε_avg`, `N_ε` and the elapsed time; the loop stops at the tolerance or
//!    after the given number of iterations. `k = 1` is the first control net (the
//!    reverse-Loop net for LSPIA and the seed loop, the targets themselves for PIA),
//!    before any correction, as in the seed's Table 2.
//! 5. **Convergence** is computed, not assumed: for up to
//!    [`FitOptions::spectral_limit`] control points the spectral radius of the method's
//!    iteration matrix is computed (`ρ(I - μ NᵀN)`, `ρ(I - w N_T)`, `ρ(I - R N)`) before
//!    iterating; at or above 1 the fit warns, or refuses with
//!    [`SplineError::NotConvergent`] when [`FitOptions::refuse_divergent`] is set.
//! 6. **Baseline**: the direct least-squares fit of the same control net (dense QR),
//!    with its errors and time.
//!
//! **Scale.** Every step is linear in the data or invariant under scaling it, so
//! coordinates beyond `2^±256` in magnitude (e.g. a mesh given in units of `1e300`) are
//! first scaled by an exact power of two to unit size, fitted, and the results scaled
//! back: the same fit, where squared distances would otherwise overflow to infinity (and
//! the default hit tolerance with them) or underflow to zero errors. Only a result that
//! does not fit in `f64` in the input's units is an error ([`SplineError::Overflow`]).

use std::str::FromStr;
use std::time::Instant;

use glam::{DVec2, DVec3};
use mesh_topo::HalfedgeMesh;
use serde::{Deserialize, Serialize};
use subdiv_loop::forward::LoopOptions;

use crate::coarsen::{CoarsenOptions, reverse_loop};
use crate::dms_net::DmsNet;
use crate::fit::{
    IterationOptions, IterationOutcome, IterationRecord, default_lspia_step, least_squares_fit, lspia, lspia_spectrum,
    pia, pia_spectral_radius, seed_iteration, seed_spectral_radius,
};
use crate::index::{tri_count, tri_index};
use crate::linalg::SparseMatrix;
use crate::param::{ParamKind, ParamOptions, TutteWeights, detect_regular_grid, disk_boundary, parameterize};
use crate::{
    BPatchBasis, DomainTriangle, FittedSurface, KnotPlacement, KnotSequences, SplineError, SurfaceBasis, SurfaceKind,
};

/// The iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Least-squares PIA (Deng & Lin 2014).
    #[default]
    Lspia,
    /// Classical PIA (interpolation of the data at the control points' vertices).
    Pia,
    /// The seed paper's loop `P* += E`, `C = R(P*)`.
    Seed,
}

impl Method {
    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Lspia => "lspia",
            Self::Pia => "pia",
            Self::Seed => "seed",
        }
    }
}

impl FromStr for Method {
    type Err = SplineError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "lspia" => Ok(Self::Lspia),
            "pia" => Ok(Self::Pia),
            "seed" => Ok(Self::Seed),
            _ => Err(SplineError::BadOption { name: "method", value: s.into(), reason: "one of lspia, pia, seed" }),
        }
    }
}

impl FromStr for SurfaceKind {
    type Err = SplineError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "bezier" => Ok(Self::Bezier),
            "bpatch" => Ok(Self::Bpatch),
            "tri-bspline" => Ok(Self::TriBspline),
            _ => Err(SplineError::BadOption {
                name: "surface",
                value: s.into(),
                reason: "one of bezier, bpatch, tri-bspline",
            }),
        }
    }
}

/// Default hit tolerance for `N_ε`, relative to the bounding-box diagonal of the data.
pub const DEFAULT_HIT_TOL_FRACTION: f64 = 2e-3;

/// Options of [`fit_mesh`].
#[derive(Debug, Clone, PartialEq)]
pub struct FitOptions {
    /// Surface kind.
    pub surface: SurfaceKind,
    /// Iteration.
    pub method: Method,
    /// Reverse-Loop levels `i` giving the control net.
    pub reverse_levels: u32,
    /// Largest number of iterations `k`.
    pub iterations: usize,
    /// Stop when `ε_avg` falls below this (absolute).
    pub tolerance: Option<f64>,
    /// A data point is hit when its error is at most this (absolute); default
    /// [`DEFAULT_HIT_TOL_FRACTION`] times the bounding-box diagonal.
    pub hit_tol: Option<f64>,
    /// Degree of the triangular B-spline.
    pub dms_degree: usize,
    /// Knot clouds of the triangular B-spline.
    pub knots: KnotPlacement,
    /// B-patch knot spread `δ` (pipeline docs), relative to the corner-to-centre distance.
    pub bpatch_knot_spread: f64,
    /// Compute spectral radii up to this many control points.
    pub spectral_limit: usize,
    /// Refuse (instead of warn) when the spectral radius is at least 1.
    pub refuse_divergent: bool,
    /// Also solve the least-squares problem directly (baseline).
    pub least_squares: bool,
    /// LSPIA step `μ`; default `1/c` with `c >= λ_max(NᵀN)`.
    pub lspia_step: Option<f64>,
    /// PIA weight `w`.
    pub pia_weight: f64,
    /// Weights of the convex-combination map (non-grid meshes).
    pub tutte_weights: TutteWeights,
    /// Loop rules assumed by the reversal.
    pub loop_rules: LoopOptions,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            surface: SurfaceKind::Bezier,
            method: Method::Lspia,
            reverse_levels: 2,
            iterations: 10,
            tolerance: None,
            hit_tol: None,
            dms_degree: 2,
            knots: KnotPlacement::default(),
            bpatch_knot_spread: 0.1,
            spectral_limit: 2000,
            refuse_divergent: false,
            least_squares: true,
            lspia_step: None,
            pia_weight: 1.0,
            tutte_weights: TutteWeights::MeanValue,
            loop_rules: CoarsenOptions::default().rules,
        }
    }
}

/// The least-squares baseline in a report.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LeastSquaresSummary {
    /// Largest error.
    pub eps_max: f64,
    /// Mean error.
    pub eps_avg: f64,
    /// Percentage of hits.
    pub n_eps: f64,
    /// Seconds to solve.
    pub seconds: f64,
}

/// Seconds spent per stage.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Timings {
    /// Parameterization.
    pub parameterize: f64,
    /// Reverse Loop (control net and the matrix `R`).
    pub reverse_loop: f64,
    /// Basis and collocation matrix.
    pub collocation: f64,
    /// Spectral radius.
    pub spectral: f64,
    /// The iterations.
    pub iterations: f64,
    /// Least-squares baseline.
    pub least_squares: f64,
    /// Everything.
    pub total: f64,
}

/// Everything [`fit_mesh`] found.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitReport {
    /// The fitted surface.
    pub surface: FittedSurface,
    /// Its domain triangle.
    pub domain: DomainTriangle,
    /// Surface kind.
    pub kind: SurfaceKind,
    /// Iteration used.
    pub method: Method,
    /// Polynomial degree.
    pub degree: usize,
    /// Reverse-Loop levels.
    pub reverse_levels: u32,
    /// Control points iterated on (the net's vertices).
    pub control_points: usize,
    /// Data points.
    pub data_points: usize,
    /// Bounding-box diagonal of the data (errors are absolute; divide by this for
    /// relative errors).
    pub bbox_diag: f64,
    /// The hit tolerance used for `N_ε`.
    pub hit_tol: f64,
    /// One record per iteration.
    pub iterations: Vec<IterationRecord>,
    /// Residual 2-norm per iteration.
    pub residual_norms: Vec<f64>,
    /// Spectral radius of the iteration matrix, when computed.
    pub spectral_radius: Option<f64>,
    /// Why it was not computed, or what it means.
    pub spectral_note: String,
    /// Warnings (e.g. a spectral radius at or above 1).
    pub warnings: Vec<String>,
    /// The least-squares baseline, when computed.
    pub least_squares: Option<LeastSquaresSummary>,
    /// Time per stage.
    pub timings: Timings,
    /// The control net: final positions and its triangles.
    pub control_net: (Vec<DVec3>, Vec<[u32; 3]>),
    /// Parameter of every data point.
    pub params: Vec<DVec2>,
}

/// Everything the iterations need.
struct Problem {
    basis: SurfaceBasis,
    /// DMS control points from net vertices (`None`: the net is the control net).
    lift: Option<SparseMatrix>,
    /// Effective collocation matrix (data × net vertices).
    n: SparseMatrix,
    /// Reverse-Loop map (net vertices × data).
    r: SparseMatrix,
    /// Data index of each net vertex.
    own_vertex: Vec<usize>,
    /// Net triangles.
    triangles: Vec<[u32; 3]>,
    degree: usize,
}

fn check_options(options: &FitOptions) -> Result<(), SplineError> {
    if options.iterations == 0 {
        return Err(SplineError::BadOption { name: "iterations", value: "0".into(), reason: "at least 1" });
    }
    let positive = |name: &'static str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(SplineError::BadOption { name, value: v.to_string(), reason: "a positive finite number" })
        }
    };
    if let Some(t) = options.tolerance {
        positive("tolerance", t)?;
    }
    if let Some(h) = options.hit_tol {
        positive("hit-tol", h)?;
    }
    if let Some(mu) = options.lspia_step {
        positive("lspia step", mu)?;
    }
    positive("pia weight", options.pia_weight)?;
    if !(options.bpatch_knot_spread.is_finite() && options.bpatch_knot_spread >= 0.0) {
        return Err(SplineError::BadOption {
            name: "bpatch knot spread",
            value: options.bpatch_knot_spread.to_string(),
            reason: "a non-negative finite number",
        });
    }
    Ok(())
}

/// The B-patch knots of the pipeline docs.
///
/// ```
/// use tri_spline::pipeline::bpatch_knots;
/// use tri_spline::{BPatchBasis, DomainTriangle, KnotSequences};
/// let domain = DomainTriangle::equilateral();
/// let knots = bpatch_knots(&domain, 3, 0.1);
/// // r_0, s_0, t_0 are the domain corners; the later knots move away from the centre.
/// assert_eq!([knots.r[0], knots.s[0], knots.t[0]], domain.corners());
/// assert!(knots.r[2].length() > 0.0 && knots.r[2].x < 0.0);
/// assert!(BPatchBasis::new(3, knots).is_ok());
/// // Without spread they are the Bézier knots.
/// assert_eq!(bpatch_knots(&domain, 3, 0.0), KnotSequences::bezier(&domain, 3));
/// ```
pub fn bpatch_knots(domain: &DomainTriangle, degree: usize, spread: f64) -> KnotSequences {
    let corners = domain.corners();
    let centre = (corners[0] + corners[1] + corners[2]) / 3.0;
    let seq = |c: DVec2| (0..degree).map(|i| c + (c - centre) * (spread * i as f64 / degree as f64)).collect();
    KnotSequences { r: seq(corners[0]), s: seq(corners[1]), t: seq(corners[2]) }
}

/// Fits a surface to the vertices of `mesh` (module docs).
///
/// # Errors
/// [`SplineError::BadOption`] for bad options; the mesh errors of
/// [`crate::param::disk_boundary`]; [`SplineError::NotRegularGrid`] when a Bézier patch or
/// B-patch is asked of a mesh that is not a regular triangular grid;
/// [`SplineError::ReverseLevels`] naming how many reverse-Loop levels are possible;
/// [`SplineError::DegenerateParameterTriangle`], DMS knot errors,
/// [`SplineError::NotConvergent`] when refusing a divergent iteration,
/// [`SplineError::Diverged`] when the iteration overflowed (e.g. an LSPIA step far too
/// large), [`SplineError::Singular`] for a failed solve; [`SplineError::Degree`] when
/// the grid and levels give a patch degree above the supported one;
/// [`SplineError::Overflow`] for coordinates so close to `f64::MAX` that the result
/// (a control point, the bounding-box diagonal) does not fit in `f64` (module docs,
/// "Scale").
///
/// ```
/// use glam::DVec3;
/// use mesh_topo::{HalfedgeMesh, PolygonSoup};
/// use tri_spline::SurfaceKind;
/// use tri_spline::pipeline::{FitOptions, Method, fit_mesh};
/// use tri_spline::surface::grid_triangles;
/// use tri_spline::index::multi_indices;
///
/// // A regular triangular grid with 8 segments per side on a smooth surface.
/// let n = 8;
/// let positions: Vec<DVec3> = multi_indices(n)
///     .map(|[_, j, k]| {
///         let (a, b) = (j as f64 / n as f64, k as f64 / n as f64);
///         DVec3::new(a, b, 0.3 * (3.0 * a).sin() * (2.0 * b).cos())
///     })
///     .collect();
/// let mesh = HalfedgeMesh::from_faces(positions, grid_triangles(n, true))?;
/// let options = FitOptions { surface: SurfaceKind::Bezier, method: Method::Lspia, reverse_levels: 1, ..FitOptions::default() };
/// let report = fit_mesh(&mesh, &options)?;
/// assert_eq!(report.degree, 4);
/// assert_eq!(report.iterations.len(), 10);
/// assert!(report.spectral_radius.unwrap() < 1.0);
/// assert!(report.iterations[9].eps_avg < report.iterations[0].eps_avg);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn fit_mesh(mesh: &HalfedgeMesh, options: &FitOptions) -> Result<FitReport, SplineError> {
    let start = Instant::now();
    check_options(options)?;
    disk_boundary(mesh)?;
    if let Some(index) = mesh.positions().iter().position(|p| !p.is_finite()) {
        return Err(SplineError::NonFinite { what: "vertex position", index });
    }
    // Fit at unit scale when the coordinates are extreme (module docs, "Scale"): the
    // same fit, without squares of distances overflowing or underflowing.
    let unit = UnitScale::of(mesh.positions());
    let requested_hit_tol = options.hit_tol;
    let unit_mesh;
    let unit_options;
    let (mesh, options) = if unit.is_identity() {
        (mesh, options)
    } else {
        let mut scaled = mesh.clone();
        for p in scaled.positions_mut() {
            *p = unit.to_unit(*p);
        }
        unit_mesh = scaled;
        unit_options = FitOptions {
            tolerance: options.tolerance.map(|t| unit.distance_to_unit(t)),
            hit_tol: options.hit_tol.map(|h| unit.distance_to_unit(h)),
            ..options.clone()
        };
        (&unit_mesh, &unit_options)
    };
    let data = mesh.positions().to_vec();
    let (lo, hi) = data.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), &p| (l.min(p), h.max(p)));
    let mut bbox_diag = (hi - lo).length();
    let mut hit_tol = options.hit_tol.unwrap_or(DEFAULT_HIT_TOL_FRACTION * bbox_diag);
    let mut timings = Timings::default();
    let domain = DomainTriangle::equilateral();
    let levels = options.reverse_levels;

    let (problem, params) = match options.surface {
        SurfaceKind::Bezier | SurfaceKind::Bpatch => grid_problem(mesh, options, &domain, &mut timings)?,
        SurfaceKind::TriBspline => net_problem(mesh, options, &domain, &mut timings)?,
    };
    let Problem { basis, lift, n, r, own_vertex, triangles, degree } = problem;
    let control_count = n.cols();

    // Initial net and the method's operands.
    let initial = r.mul_vec(&data);
    let targets: Vec<DVec3> = own_vertex.iter().map(|&v| data[v]).collect();
    let n_targets = || {
        SparseMatrix::from_rows(
            n.cols(),
            own_vertex
                .iter()
                .map(|&v| {
                    let (cols, vals) = n.row(v);
                    cols.iter().zip(vals).map(|(&c, &x)| (c as usize, x)).collect()
                })
                .collect(),
        )
    };
    let mu = match options.method {
        Method::Lspia => Some(options.lspia_step.unwrap_or_else(|| default_lspia_step(&n))),
        _ => None,
    };

    // Convergence, computed before iterating.
    let t = Instant::now();
    let mut warnings = Vec::new();
    let (spectral_radius, spectral_note) = if control_count <= options.spectral_limit {
        let rho = match options.method {
            Method::Lspia => {
                let s = lspia_spectrum(&n, mu.expect("internal: LSPIA step"))?;
                if s.lambda_min <= 1e-14 * s.lambda_max {
                    warnings.push(format!(
                        "NᵀN is (numerically) singular (λ_min = {:.3e}, λ_max = {:.3e}): LSPIA converges to a least-squares fit only on the range of N",
                        s.lambda_min, s.lambda_max
                    ));
                }
                s.spectral_radius
            }
            Method::Pia => pia_spectral_radius(&n_targets(), options.pia_weight)?,
            Method::Seed => seed_spectral_radius(&n, &r)?,
        };
        let matrix = match options.method {
            Method::Lspia => "I - μ NᵀN",
            Method::Pia => "I - w N_T",
            Method::Seed => "I - R N",
        };
        (Some(rho), format!("ρ({matrix})"))
    } else {
        (None, format!("not computed: {control_count} control points > limit {}", options.spectral_limit))
    };
    timings.spectral = t.elapsed().as_secs_f64();
    if let Some(rho) = spectral_radius {
        if rho >= 1.0 {
            if options.refuse_divergent {
                return Err(SplineError::NotConvergent { method: options.method.name(), spectral_radius: rho });
            }
            warnings.push(format!("spectral radius {rho} >= 1: the iteration does not converge"));
        } else if rho > 1.0 - 1e-6 {
            warnings.push(format!("spectral radius 1 - {:.2e}: convergence is extremely slow", 1.0 - rho));
        }
    }

    let iteration_options =
        IterationOptions { max_iterations: options.iterations, tolerance: options.tolerance, hit_tol };
    let t = Instant::now();
    let mut outcome: IterationOutcome = match options.method {
        Method::Lspia => lspia(&n, &data, initial, mu.expect("internal: LSPIA step"), &iteration_options)?,
        Method::Pia => pia(&n, &data, &n_targets(), &targets, targets.clone(), options.pia_weight, &iteration_options)?,
        Method::Seed => seed_iteration(&n, &data, &r, &iteration_options)?,
    };
    timings.iterations = t.elapsed().as_secs_f64();

    let mut least_squares = if options.least_squares {
        let t = Instant::now();
        let report = least_squares_fit(&n, &data, hit_tol);
        timings.least_squares = t.elapsed().as_secs_f64();
        match report {
            Ok(ls) => Some(LeastSquaresSummary {
                eps_max: ls.stats.eps_max,
                eps_avg: ls.stats.eps_avg,
                n_eps: ls.stats.n_eps,
                seconds: ls.seconds,
            }),
            Err(e) => {
                warnings.push(format!("least-squares baseline: {e}"));
                None
            }
        }
    } else {
        None
    };

    let mut control = match &lift {
        Some(l) => l.mul_vec(&outcome.control),
        None => outcome.control.clone(),
    };
    // Back to the input's units (exact, as the scaling was; nothing to do at unit scale).
    if !unit.is_identity() {
        unit.points_to_input(&mut control, "a control point of the fitted surface")?;
        unit.points_to_input(&mut outcome.control, "a point of the control net")?;
        bbox_diag = unit.distance_to_input(bbox_diag, "the bounding-box diagonal")?;
        hit_tol = match requested_hit_tol {
            Some(given) => given,
            None => unit.distance_to_input(hit_tol, "the default hit tolerance")?,
        };
        for record in &mut outcome.records {
            record.eps_max = unit.distance_to_input(record.eps_max, "the largest error")?;
            record.eps_avg = unit.distance_to_input(record.eps_avg, "the mean error")?;
        }
        for norm in &mut outcome.residual_norms {
            *norm = unit.distance_to_input(*norm, "the residual 2-norm")?;
        }
        if let Some(ls) = &mut least_squares {
            ls.eps_max = unit.distance_to_input(ls.eps_max, "the least-squares largest error")?;
            ls.eps_avg = unit.distance_to_input(ls.eps_avg, "the least-squares mean error")?;
        }
    }
    let surface = basis.with_control(control)?;
    timings.total = start.elapsed().as_secs_f64();
    Ok(FitReport {
        surface,
        domain,
        kind: options.surface,
        method: options.method,
        degree,
        reverse_levels: levels,
        control_points: control_count,
        data_points: data.len(),
        bbox_diag,
        hit_tol,
        iterations: outcome.records,
        residual_norms: outcome.residual_norms,
        spectral_radius,
        spectral_note,
        warnings,
        least_squares,
        timings,
        control_net: (outcome.control, triangles),
        params,
    })
}

/// Coordinates of magnitude in `[1/SAFE_MAGNITUDE, SAFE_MAGNITUDE]` (`2^±256`) are fitted
/// as given: squared distances and their sums over many points stay far inside the `f64`
/// range. Others are fitted at unit scale.
const SAFE_MAGNITUDE: f64 = f64::from_bits((1023 + 256) << 52);

/// The exact power-of-two scaling `x ↦ x 2^exponent` that brings extreme coordinates to
/// unit size (module docs, "Scale").
#[derive(Debug, Clone, Copy, PartialEq)]
struct UnitScale {
    exponent: i32,
    /// The largest absolute input coordinate (for [`SplineError::Overflow`]).
    largest_coordinate: f64,
}

impl UnitScale {
    /// The scaling for `positions` (finite): the identity unless their largest absolute
    /// coordinate is outside the safe range, else one that makes it about 1.
    fn of(positions: &[DVec3]) -> Self {
        let largest_coordinate = positions.iter().fold(0.0f64, |m, p| m.max(p.abs().max_element()));
        let safe = largest_coordinate == 0.0 || (1.0 / SAFE_MAGNITUDE..=SAFE_MAGNITUDE).contains(&largest_coordinate);
        // log2 is exact enough: off by one only moves the scaled maximum into [1/2, 4).
        let exponent = if safe { 0 } else { -(largest_coordinate.log2().floor() as i32) };
        Self { exponent, largest_coordinate }
    }

    fn is_identity(self) -> bool {
        self.exponent == 0
    }

    /// A position in unit scale (exact: scaling by a power of two rounds only values that
    /// become subnormal, which are negligible next to the largest coordinate, about 1).
    fn to_unit(self, p: DVec3) -> DVec3 {
        p.map(|x| times_power_of_two(x, self.exponent))
    }

    /// A distance option (tolerance, hit tolerance) in unit scale; one beyond the `f64`
    /// range there stays the largest finite distance, which compares the same way.
    fn distance_to_unit(self, d: f64) -> f64 {
        times_power_of_two(d, self.exponent).min(f64::MAX)
    }

    /// A distance of the unit-scale fit in the input's units.
    ///
    /// # Errors
    /// [`SplineError::Overflow`] if it is beyond the `f64` range there.
    fn distance_to_input(self, d: f64, what: &'static str) -> Result<f64, SplineError> {
        let back = times_power_of_two(d, -self.exponent);
        if back.is_finite() {
            Ok(back)
        } else {
            Err(SplineError::Overflow { what, largest_coordinate: self.largest_coordinate })
        }
    }

    /// Points of the unit-scale fit in the input's units, in place.
    ///
    /// # Errors
    /// [`SplineError::Overflow`] if a coordinate is beyond the `f64` range there.
    fn points_to_input(self, points: &mut [DVec3], what: &'static str) -> Result<(), SplineError> {
        for p in points {
            *p = p.map(|x| times_power_of_two(x, -self.exponent));
            if !p.is_finite() {
                return Err(SplineError::Overflow { what, largest_coordinate: self.largest_coordinate });
            }
        }
        Ok(())
    }
}

/// `x 2^exponent`, exact unless the result leaves the normal range: in factors that are
/// themselves normal powers of two (`2^±1074` is not one).
fn times_power_of_two(mut x: f64, exponent: i32) -> f64 {
    let mut remaining = exponent;
    while remaining != 0 {
        let step = remaining.clamp(-1022, 1023);
        x *= f64::from_bits(((step + 1023) as u64) << 52);
        remaining -= step;
    }
    x
}

/// Bézier patch or B-patch over a regular triangular grid.
fn grid_problem(
    mesh: &HalfedgeMesh,
    options: &FitOptions,
    domain: &DomainTriangle,
    timings: &mut Timings,
) -> Result<(Problem, Vec<DVec2>), SplineError> {
    let t = Instant::now();
    let Some(grid) = detect_regular_grid(mesh) else {
        return Err(SplineError::NotRegularGrid {
            reason: format!(
                "{} needs a regular triangular grid (three corners with one face, boundary valence 4, interior valence 6); use tri-bspline for other disk meshes",
                options.surface.name()
            ),
        });
    };
    let param = parameterize(mesh, &ParamOptions { domain: *domain, ..ParamOptions::default() })?;
    timings.parameterize = t.elapsed().as_secs_f64();
    let segments = grid.segments;
    let levels = options.reverse_levels;
    let possible = segments.trailing_zeros().min(31);
    if levels > possible {
        return Err(SplineError::ReverseLevels {
            requested: levels,
            possible,
            reason: format!(
                "a regular grid of N = {segments} segments per side has Loop connectivity only while N is even (N = 2^{possible} x {})",
                segments >> possible
            ),
        });
    }
    let degree = segments >> levels;
    // Checked before the reversal and the collocation matrix (dense rows of
    // (n+1)(n+2)/2 entries), which would run for minutes before the patch refused it.
    let max_degree = match options.surface {
        SurfaceKind::Bezier => crate::bezier::MAX_BEZIER_DEGREE,
        _ => crate::bpatch::MAX_BPATCH_DEGREE,
    };
    if degree > max_degree {
        return Err(SplineError::Degree { degree, min: 1, max: max_degree });
    }
    let t = Instant::now();
    let coarsening = reverse_loop(
        mesh,
        levels,
        &CoarsenOptions { rules: options.loop_rules, seed_vertex: Some(grid.corners[0] as u32) },
    )?;
    // Coarse vertex -> control point β, by the lattice coordinates of its vertex point.
    let mut slot_of_coarse = vec![0usize; coarsening.fine_vertex.len()];
    let mut own_vertex = vec![usize::MAX; tri_count(degree)];
    for (c, &v) in coarsening.fine_vertex.iter().enumerate() {
        let (j, k) = grid.coords[v];
        let step = 1u32 << levels;
        debug_assert!(j % step == 0 && k % step == 0, "internal: vertex points sit on the coarse lattice");
        let slot = tri_index(degree, (j / step) as usize, (k / step) as usize);
        slot_of_coarse[c] = slot;
        own_vertex[slot] = v;
    }
    debug_assert!(own_vertex.iter().all(|&v| v != usize::MAX), "internal: every control point has a vertex");
    let mut rows = vec![Vec::new(); own_vertex.len()];
    for (c, &slot) in slot_of_coarse.iter().enumerate() {
        let (cols, vals) = coarsening.operator.row(c);
        rows[slot] = cols.iter().zip(vals).map(|(&col, &v)| (col as usize, v)).collect();
    }
    let r = SparseMatrix::from_rows(mesh.vertex_count(), rows);
    timings.reverse_loop = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let basis = match options.surface {
        SurfaceKind::Bezier => SurfaceBasis::Bezier { degree, domain: *domain },
        _ => SurfaceBasis::Bpatch(BPatchBasis::new(
            degree.max(1),
            bpatch_knots(domain, degree, options.bpatch_knot_spread),
        )?),
    };
    if matches!(basis, SurfaceBasis::Bpatch(_)) && degree == 0 {
        return Err(SplineError::Degree { degree, min: 1, max: crate::bpatch::MAX_BPATCH_DEGREE });
    }
    let n = basis.collocation(&param.params)?;
    timings.collocation = t.elapsed().as_secs_f64();
    let triangles = crate::surface::grid_triangles(degree, true);
    Ok((Problem { basis, lift: None, n, r, own_vertex, triangles, degree }, param.params))
}

/// DMS spline over the reverse-Loop net of any disk.
fn net_problem(
    mesh: &HalfedgeMesh,
    options: &FitOptions,
    domain: &DomainTriangle,
    timings: &mut Timings,
) -> Result<(Problem, Vec<DVec2>), SplineError> {
    let t = Instant::now();
    let grid = detect_regular_grid(mesh);
    let seed = grid.as_ref().map(|g| g.corners[0] as u32);
    let coarsening =
        reverse_loop(mesh, options.reverse_levels, &CoarsenOptions { rules: options.loop_rules, seed_vertex: seed })?;
    timings.reverse_loop = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let mut allowed = vec![false; mesh.vertex_count()];
    for &v in &coarsening.fine_vertex {
        allowed[v] = true;
    }
    let param_options = ParamOptions {
        domain: *domain,
        weights: options.tutte_weights,
        corner_allowed: Some(allowed),
        ..ParamOptions::default()
    };
    let param = parameterize(mesh, &param_options)?;
    if let ParamKind::RegularGrid { .. } = param.kind {
        // Grid corners must be vertex points at every level for the net to span the domain.
        if !param.corners.iter().all(|c| coarsening.fine_vertex.contains(c)) {
            return Err(SplineError::ReverseLevels {
                requested: options.reverse_levels,
                possible: 0,
                reason: "the grid's corners are not vertex points of the detected Loop structure".into(),
            });
        }
    }
    timings.parameterize = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let net_params: Vec<DVec2> = coarsening.fine_vertex.iter().map(|&v| param.params[v]).collect();
    let triangles: Vec<[u32; 3]> = coarsening
        .coarse
        .faces()
        .map(|f| {
            let v: Vec<u32> = coarsening.coarse.face_vertices(f).map(|w| w.raw()).collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    let net = DmsNet::new(&net_params, &triangles, options.dms_degree, options.knots)?;
    let basis = SurfaceBasis::Dms(net.basis.clone());
    let n = basis.collocation(&param.params)?.mul(&net.lift);
    timings.collocation = t.elapsed().as_secs_f64();
    let problem = Problem {
        basis,
        lift: Some(net.lift),
        n,
        r: coarsening.operator,
        own_vertex: coarsening.fine_vertex,
        triangles,
        degree: options.dms_degree,
    };
    Ok((problem, param.params))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::samples::{smooth_surface, triangle_grid};

    fn grid_mesh(segments: usize, scale: f64) -> HalfedgeMesh {
        HalfedgeMesh::from_soup(&triangle_grid(segments, |a, b| smooth_surface(a, b) * scale)).unwrap()
    }

    fn options(surface: SurfaceKind) -> FitOptions {
        FitOptions { surface, reverse_levels: 1, ..FitOptions::default() }
    }

    fn relative_gap(a: f64, b: f64) -> f64 {
        (a - b).abs() / a.abs().max(b.abs())
    }

    /// A grid scaled to about 1e307 used to fail with "option hit_tol = inf" (the default
    /// hit tolerance is 2e-3 of a bounding-box diagonal whose square overflowed); at
    /// 1e-300 every error underflowed to 0, a perfect fit. Both now give the unit grid's
    /// fit in the input's units.
    #[test]
    fn extreme_coordinates_are_fitted_at_unit_scale() {
        for surface in [SurfaceKind::Bezier, SurfaceKind::Bpatch, SurfaceKind::TriBspline] {
            let unit = fit_mesh(&grid_mesh(8, 1.0), &options(surface)).unwrap();
            // An exact power of two (the largest coordinate is 1): the same fit to the bit.
            let power = 2f64.powi(1019);
            let exact = fit_mesh(&grid_mesh(8, power), &options(surface)).unwrap();
            assert_eq!(exact.bbox_diag, unit.bbox_diag * power);
            for (a, b) in exact.iterations.iter().zip(&unit.iterations) {
                assert_eq!((a.eps_max, a.eps_avg, a.n_eps), (b.eps_max * power, b.eps_avg * power, b.n_eps));
            }
            let scaled_net: Vec<DVec3> = unit.control_net.0.iter().map(|&p| p * power).collect();
            assert_eq!(exact.control_net.0, scaled_net, "{surface:?}");
            for scale in [1e307, 1e-300] {
                let report = fit_mesh(&grid_mesh(8, scale), &options(surface)).unwrap();
                assert!(relative_gap(report.bbox_diag / scale, unit.bbox_diag) < 1e-12, "{surface:?} {scale:e}");
                assert!(relative_gap(report.hit_tol, DEFAULT_HIT_TOL_FRACTION * report.bbox_diag) < 1e-15);
                for (a, b) in report.iterations.iter().zip(&unit.iterations) {
                    assert!(relative_gap(a.eps_avg / scale, b.eps_avg) < 1e-9, "{surface:?} {scale:e}: {a:?} {b:?}");
                    assert!(a.eps_max > 0.0 && a.eps_max.is_finite());
                }
                let ls = report.least_squares.unwrap();
                assert!(relative_gap(ls.eps_avg / scale, unit.least_squares.unwrap().eps_avg) < 1e-9);
                assert!(report.surface.eval(DVec2::new(0.3, 0.2)).is_finite());
            }
        }
        // A hit tolerance given in the input's units is used and reported as given.
        let given = FitOptions { hit_tol: Some(1e305), ..options(SurfaceKind::Bezier) };
        let report = fit_mesh(&grid_mesh(8, 1e307), &given).unwrap();
        assert_eq!(report.hit_tol, 1e305);
        let unit = fit_mesh(&grid_mesh(8, 1.0), &FitOptions { hit_tol: Some(1e-2), ..given }).unwrap();
        for (a, b) in report.iterations.iter().zip(&unit.iterations) {
            assert_eq!(a.n_eps, b.n_eps);
        }
    }

    /// Where the result itself does not fit in f64 (coordinates spanning ±1.75e308: the
    /// diagonal and control points beyond f64::MAX) the error says so; the reversal used
    /// to panic in subdiv-loop on NaN coarse positions.
    #[test]
    fn results_beyond_the_f64_range_are_overflow_errors() {
        let soup = triangle_grid(8, |a, b| (smooth_surface(a, b) - DVec3::splat(0.5)) * 3.5e300 * 1e8);
        let mesh = HalfedgeMesh::from_soup(&soup).unwrap();
        for surface in [SurfaceKind::Bezier, SurfaceKind::TriBspline] {
            let result = fit_mesh(&mesh, &options(surface));
            assert!(
                matches!(result, Err(SplineError::Overflow { largest_coordinate, .. }) if largest_coordinate > 1.7e308),
                "{surface:?}: {result:?}"
            );
        }
    }

    /// An LSPIA step far beyond `2/λ_max` used to end in NaN control points, reported as
    /// "control point 0 is not finite" by the surface constructor.
    #[test]
    fn a_step_far_too_large_is_reported_as_divergence() {
        let step = FitOptions { lspia_step: Some(1e300), ..options(SurfaceKind::Bezier) };
        let result = fit_mesh(&grid_mesh(8, 1.0), &step);
        assert!(matches!(result, Err(SplineError::Diverged { method: "lspia", iteration: 3, .. })), "{result:?}");
    }

    /// A 65-segment grid without reverse levels asks for a degree-65 Bézier patch: it used
    /// to build the dense 2211 x 2211 collocation matrix, iterate and solve least squares
    /// before the patch refused the degree.
    #[test]
    fn a_patch_degree_beyond_the_limit_is_refused_before_fitting() {
        let mesh = grid_mesh(65, 1.0);
        let start = Instant::now();
        for (surface, max) in [
            (SurfaceKind::Bezier, crate::bezier::MAX_BEZIER_DEGREE),
            (SurfaceKind::Bpatch, crate::bpatch::MAX_BPATCH_DEGREE),
        ] {
            let at_full_size = FitOptions { reverse_levels: 0, ..options(surface) };
            assert_eq!(fit_mesh(&mesh, &at_full_size).unwrap_err(), SplineError::Degree { degree: 65, min: 1, max });
        }
        assert!(start.elapsed().as_secs_f64() < 1.0);
    }
}
