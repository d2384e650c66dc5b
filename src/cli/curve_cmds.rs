//! Curve commands: `curve` and `analyze` for curve schemes.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};
use subdiv_curve::analysis::{self, Analysis, Contractivity};
use subdiv_curve::io::{PointSet, format_points, parse_points};
use subdiv_curve::nalgebra::Complex;
use subdiv_curve::select::{SelectionOptions, select_interpolation_points};
use subdiv_curve::svg::{Mark, SvgScene, render_svg};
use subdiv_curve::{CurvePoint, CurveScheme, EndRule, Framework, FrameworkAnalysis, Topology, flags_from_indices};

use super::common::print_out;
use super::{AnalyzeArgs, AnalyzeScheme, CliError, CliResult, input_error};

/// Largest number of refined points `curve` writes (a guard against `--levels 40`).
const MAX_OUTPUT_POINTS: usize = 1 << 26;

/// Curve schemes of `multires curve`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum CurveSchemeName {
    /// Chaikin corner cutting (quadratic B-spline); open polygons keep their end points.
    Chaikin,
    /// Cubic B-spline.
    CubicBspline,
    /// Dyn-Levin-Gregory four-point interpolatory scheme (tension --tension, default 1/16).
    FourPoint,
    /// The interpolatory-approximating framework: flagged points are interpolated, the
    /// others approximated (parameters --omega1 --omega2 --gamma).
    Combined,
}

/// Phantom points past the ends of an open polygon.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum EndRuleName {
    /// `P(-1) = 2 P0 - P1`: the cubic B-spline keeps the end points.
    Reflect,
    /// `P(-1) = P0`.
    Repeat,
}

/// Options of `curve`.
#[derive(Debug, Args)]
pub struct CurveArgs {
    /// Input points: one `x y` or `x y z` per line, `#` comments.
    pub input: PathBuf,
    /// Output SVG: control polygon, refined curve, interpolated points marked.
    pub out: PathBuf,
    /// The curve scheme.
    #[arg(long, value_enum)]
    pub scheme: CurveSchemeName,
    /// Number of subdivision steps.
    #[arg(long, default_value_t = 5)]
    pub levels: u32,
    /// Treat the polygon as closed.
    #[arg(long)]
    pub closed: bool,
    /// Phantom end points of an open polygon (four-point, cubic B-spline, combined).
    #[arg(long, value_enum, default_value_t = EndRuleName::Reflect)]
    pub end_rule: EndRuleName,
    /// Choose the points to interpolate from discrete curvature (combined scheme); the
    /// choice is printed.
    #[arg(long, conflicts_with = "interpolate")]
    pub auto_interpolate: bool,
    /// Indices of the points to interpolate, comma-separated (combined scheme).
    #[arg(long, value_delimiter = ',')]
    pub interpolate: Vec<usize>,
    /// Automatic choice: cusps turn by at least this angle, in degrees.
    #[arg(long, default_value_t = 135.0)]
    pub cusp_angle: f64,
    /// Automatic choice: curvature maxima need |K| >= this factor times the median |K|.
    #[arg(long, default_value_t = 2.0)]
    pub maximum_factor: f64,
    /// Automatic choice: inflections need |K| below this factor times the median |K|.
    #[arg(long, default_value_t = 0.1)]
    pub inflection_factor: f64,
    /// Curve-scheme parameters.
    #[command(flatten)]
    pub curve: super::CurveParameters,
    /// Also write the refined points to this file (same format as the input).
    #[arg(long)]
    pub out_points: Option<PathBuf>,
}

/// What to run on the points, decided (and validated) before reading them.
enum Plan {
    Uniform(CurveScheme),
    Framework(Framework),
}

/// `multires curve`.
pub fn curve(args: &CurveArgs) -> CliResult {
    let plan = plan(args)?;
    let text =
        std::fs::read_to_string(&args.input).map_err(|source| CliError::Io { path: args.input.clone(), source })?;
    let points = parse_points(&text).map_err(|e| input_error(args.input.display(), e))?;
    let topology = if args.closed {
        Topology::Closed
    } else {
        Topology::Open(match args.end_rule {
            EndRuleName::Reflect => EndRule::Reflect,
            EndRuleName::Repeat => EndRule::Repeat,
        })
    };
    let outcome = match &points {
        PointSet::Planar(p) => run_curve(args, &plan, p, topology)?,
        PointSet::Spatial(p) => run_curve(args, &plan, p, topology)?,
    };
    // Everything is computed before anything is written: an error leaves no file behind.
    write_file(&args.out, &outcome.svg)?;
    if let Some(path) = &args.out_points {
        write_file(path, &outcome.refined)?;
    }
    print_out(&outcome.report)
}

fn plan(args: &CurveArgs) -> CliResult<Plan> {
    let framework_options = args.curve.framework_given();
    let choosing = args.auto_interpolate || !args.interpolate.is_empty();
    let name = args.scheme.to_possible_value().map(|v| v.get_name().to_string()).unwrap_or_default();
    if args.scheme != CurveSchemeName::Combined && (framework_options || choosing) {
        return Err(CliError::Input(format!(
            "curve --scheme {name}: --interpolate, --auto-interpolate, --omega1, --omega2 and --gamma need --scheme \
             combined"
        )));
    }
    if args.scheme != CurveSchemeName::FourPoint && args.curve.tension.is_some() {
        return Err(CliError::Input(format!("curve --scheme {name}: --tension applies to --scheme four-point only")));
    }
    let context = format!("curve --scheme {name}");
    Ok(match args.scheme {
        CurveSchemeName::Chaikin => Plan::Uniform(CurveScheme::chaikin()),
        CurveSchemeName::CubicBspline => Plan::Uniform(CurveScheme::cubic_bspline()),
        CurveSchemeName::FourPoint => Plan::Uniform(
            CurveScheme::four_point(args.curve.tension.unwrap_or(1.0 / 16.0)).map_err(|e| input_error(&context, e))?,
        ),
        CurveSchemeName::Combined => {
            Plan::Framework(framework(args.curve.omega1, args.curve.omega2, args.curve.gamma, &context)?)
        }
    })
}

fn framework(omega1: Option<f64>, omega2: Option<f64>, gamma: Option<f64>, context: &str) -> CliResult<Framework> {
    let (published_omega1, published_omega2, published_gamma) = Framework::published().parameters();
    Framework::new(
        omega1.unwrap_or(published_omega1),
        omega2.unwrap_or(published_omega2),
        gamma.unwrap_or(published_gamma),
    )
    .map_err(|e| input_error(context, e))
}

struct CurveOutcome {
    svg: String,
    refined: String,
    report: String,
}

fn run_curve<P: CurvePoint>(
    args: &CurveArgs,
    plan: &Plan,
    points: &[P],
    topology: Topology,
) -> CliResult<CurveOutcome> {
    let input = |e| input_error(args.input.display(), e);
    let mut report = String::new();
    let mut marks: Vec<(usize, Mark)> = Vec::new();
    // The length doubles per level: bound the levels before counting.
    let too_many = || {
        CliError::Input(format!(
            "--levels {}: {} points refined {} times exceed the limit of {MAX_OUTPUT_POINTS} output points",
            args.levels,
            points.len(),
            args.levels
        ))
    };
    if args.levels > 26 {
        return Err(too_many());
    }
    let (scheme_name, refined_len) = match plan {
        Plan::Uniform(scheme) => (scheme.name().to_string(), scheme.refined_len(points.len(), topology, args.levels)),
        Plan::Framework(f) => {
            let (o1, o2, g) = f.parameters();
            (
                format!("combined(omega1={o1}, omega2={o2}, gamma={g})"),
                f.approximating_scheme().refined_len(points.len(), topology, args.levels),
            )
        }
    };
    if refined_len > MAX_OUTPUT_POINTS {
        return Err(too_many());
    }
    let refined = match plan {
        Plan::Uniform(scheme) => {
            if args.scheme == CurveSchemeName::FourPoint {
                // Interpolatory: every control point lies on the curve.
                marks.extend((0..points.len()).map(|i| (i, Mark::Interpolated)));
            }
            scheme.refine(points, topology, args.levels).map_err(input)?
        }
        Plan::Framework(framework) => {
            let flags = if args.auto_interpolate {
                let options = SelectionOptions {
                    inflection_factor: args.inflection_factor,
                    maximum_factor: args.maximum_factor,
                    cusp_angle_degrees: args.cusp_angle,
                    ..SelectionOptions::default()
                };
                let selection = select_interpolation_points(points, topology, &options).map_err(input)?;
                let chosen: Vec<String> =
                    selection.points.iter().map(|(i, class)| format!("{i} ({})", class.name())).collect();
                let indices: Vec<String> = selection.points.iter().map(|(i, _)| i.to_string()).collect();
                let _ = writeln!(
                    report,
                    "auto-interpolate: {} of {} points: {}",
                    chosen.len(),
                    points.len(),
                    if chosen.is_empty() { "none".to_string() } else { chosen.join(", ") }
                );
                let _ = writeln!(report, "flags: --interpolate {}", indices.join(","));
                marks.extend(selection.points.iter().map(|&(i, class)| (i, Mark::Chosen(class))));
                selection.flags
            } else {
                marks.extend(args.interpolate.iter().map(|&i| (i, Mark::Interpolated)));
                flags_from_indices(points.len(), &args.interpolate).map_err(input)?
            };
            framework.refine(points, &flags, topology, args.levels).map_err(input)?
        }
    };
    marks.sort_by_key(|&(i, _)| i);
    marks.dedup_by_key(|&mut (i, _)| i);
    let svg = render_svg(&SvgScene { control: points, curve: &refined, closed: topology.is_closed(), marks: &marks });
    let _ = writeln!(
        report,
        "{scheme_name}: {} {} points, {} levels -> {} points; wrote {}{}",
        if topology.is_closed() { "closed" } else { "open" },
        points.len(),
        args.levels,
        refined.len(),
        args.out.display(),
        args.out_points.as_ref().map(|p| format!(" and {}", p.display())).unwrap_or_default()
    );
    Ok(CurveOutcome { svg, refined: format_points(&refined), report })
}

fn write_file(path: &Path, contents: &str) -> CliResult {
    std::fs::write(path, contents).map_err(|source| CliError::Io { path: path.to_path_buf(), source })
}

/// `analyze` for curve schemes.
pub fn analyze(args: &AnalyzeArgs) -> CliResult {
    let name = args.scheme.to_possible_value().map(|v| v.get_name().to_string()).unwrap_or_default();
    let context = format!("analyze --scheme {name}");
    if args.valence.is_some() {
        return Err(CliError::Input(format!("{context}: --valence applies to surface schemes only")));
    }
    let framework_options = args.curve.framework_given();
    if args.scheme != AnalyzeScheme::Combined && framework_options {
        return Err(CliError::Input(format!("{context}: --omega1, --omega2 and --gamma need --scheme combined")));
    }
    if args.scheme != AnalyzeScheme::FourPoint && args.curve.tension.is_some() {
        return Err(CliError::Input(format!("{context}: --tension applies to --scheme four-point only")));
    }
    let (text, json) = match args.scheme {
        AnalyzeScheme::Chaikin => uniform_report(&analysis::analyze(&CurveScheme::chaikin())),
        AnalyzeScheme::CubicBspline => uniform_report(&analysis::analyze(&CurveScheme::cubic_bspline())),
        AnalyzeScheme::FourPoint => {
            let scheme = CurveScheme::four_point(args.curve.tension.unwrap_or(1.0 / 16.0))
                .map_err(|e| input_error(&context, e))?;
            uniform_report(&analysis::analyze(&scheme))
        }
        AnalyzeScheme::Combined => {
            framework_report(&framework(args.curve.omega1, args.curve.omega2, args.curve.gamma, &context)?)
        }
        other => return Err(CliError::Input(format!("{other:?} is not a curve scheme"))),
    };
    if args.json { print_out(&format!("{json}\n")) } else { print_out(&text) }
}

fn eigenvalue_json(z: &Complex<f64>) -> serde_json::Value {
    if z.im.abs() < 1e-12 { serde_json::json!(z.re) } else { serde_json::json!([z.re, z.im]) }
}

fn format_eigenvalue(z: &Complex<f64>) -> String {
    if z.im.abs() < 1e-12 { format!("{:.9}", z.re) } else { format!("{:.9}{:+.9}i", z.re, z.im) }
}

fn contractivity_json(c: &Contractivity) -> serde_json::Value {
    serde_json::json!({
        "order": c.order,
        "divisible": c.divisible,
        "status": format!("{:?}", c.status()).to_lowercase(),
        "best_rate": finite_or_null(c.best_rate),
        "best_steps": c.best_steps,
        "lower_bound": finite_or_null(c.lower_bound),
    })
}

fn finite_or_null(x: f64) -> serde_json::Value {
    if x.is_finite() { serde_json::json!(x) } else { serde_json::Value::Null }
}

fn contractivity_text(out: &mut String, checks: &[Contractivity]) {
    for c in checks {
        let _ = if c.divisible {
            writeln!(
                out,
                "  C{}: {:?} (difference scheme norm rate {:.6} at L = {}, joint spectral radius >= {:.6})",
                c.order,
                c.status(),
                c.best_rate,
                c.best_steps,
                c.lower_bound
            )
        } else {
            writeln!(out, "  C{}: Refuted (the symbol lacks the factor (1+z)^{})", c.order, c.order + 1)
        };
    }
}

fn smoothness_text(smoothness: Option<usize>) -> String {
    smoothness.map_or("not even C0 established".into(), |k| format!("C{k}"))
}

fn degree_json(d: Option<usize>) -> serde_json::Value {
    d.map_or(serde_json::Value::Null, |d| serde_json::json!(d))
}

fn uniform_json(a: &Analysis) -> serde_json::Value {
    serde_json::json!({
        "scheme": a.scheme,
        "symbol": { "lowest_power": a.symbol.lowest_power(), "coefficients": a.symbol.coefficients() },
        "eigenvalues": a.eigenvalues.iter().map(eigenvalue_json).collect::<Vec<_>>(),
        "smoothness": a.smoothness,
        "c1": a.c1,
        "c2": a.c2,
        "reproduction_degree": degree_json(a.reproduction_degree),
        "generation_degree": degree_json(a.generation_degree),
        "contractivity": a.contractivity.iter().map(contractivity_json).collect::<Vec<_>>(),
        "eigen_checks": { "dominant_one": a.eigen.dominant_one, "c1": a.eigen.c1, "c2": a.eigen.c2 },
    })
}

fn uniform_text(out: &mut String, a: &Analysis) {
    let degree = |d: Option<usize>| d.map_or("none".to_string(), |d| d.to_string());
    let _ = writeln!(out, "scheme {}", a.scheme);
    let _ = writeln!(
        out,
        "symbol: z^{} * [{}]",
        a.symbol.lowest_power(),
        a.symbol.coefficients().iter().map(|c| c.to_string()).collect::<Vec<_>>().join(", ")
    );
    let _ = writeln!(
        out,
        "polynomial generation degree {}, reproduction degree {}",
        degree(a.generation_degree),
        degree(a.reproduction_degree)
    );
    let values: Vec<String> = a.eigenvalues.iter().map(format_eigenvalue).collect();
    let _ =
        writeln!(out, "local subdivision matrix {0} x {0}, eigenvalues: {1}", a.local.indices.len(), values.join(", "));
    let _ = writeln!(
        out,
        "eigen conditions: lambda0 = 1 {}, C1 {}, C2 (lambda2 = lambda1^2, |lambda3| < lambda2, eigenvectors) {}",
        a.eigen.dominant_one, a.eigen.c1, a.eigen.c2
    );
    let _ = writeln!(out, "difference schemes:");
    contractivity_text(out, &a.contractivity);
    let _ = writeln!(out, "smoothness: {} (c1 {}, c2 {})", smoothness_text(a.smoothness), a.c1, a.c2);
}

fn uniform_report(a: &Analysis) -> (String, serde_json::Value) {
    let mut text = String::new();
    uniform_text(&mut text, a);
    (text, uniform_json(a))
}

fn framework_report(framework: &Framework) -> (String, serde_json::Value) {
    let report: FrameworkAnalysis = framework.analyze();
    let (omega1, omega2, gamma) = framework.parameters();
    let a = &report.approximating;
    let json = serde_json::json!({
        "scheme": "combined",
        "parameters": { "omega1": omega1, "omega2": omega2, "gamma": gamma },
        "eigenvalues": report.eigenvalues.iter().map(eigenvalue_json).collect::<Vec<_>>(),
        "smoothness": report.smoothness,
        "c1": report.c1,
        "c2": report.c2,
        "reproduction_degree": degree_json(a.reproduction_degree),
        "generation_degree": degree_json(a.generation_degree),
        "theorem_residual": report.theorem_residual,
        "eigen_checks": { "dominant_one": report.eigen.dominant_one, "c1": report.eigen.c1, "c2": report.eigen.c2 },
        "approximating": uniform_json(a),
        "interpolating": uniform_json(&report.interpolating),
    });
    let mut text = String::new();
    let _ = writeln!(text, "combined framework, omega1 = {omega1}, omega2 = {omega2}, gamma = {gamma}");
    let values: Vec<String> = report.eigenvalues.iter().map(format_eigenvalue).collect();
    let _ = writeln!(
        text,
        "local subdivision matrix at an interpolated point {0} x {0}, eigenvalues: {1}",
        report.local.indices.len(),
        values.join(", ")
    );
    let _ = writeln!(
        text,
        "eigen conditions at the interpolated point: C1 {}, C2 {}; virtual-point theorem residual {:.3e}",
        report.eigen.c1, report.eigen.c2, report.theorem_residual
    );
    let _ = writeln!(text, "smoothness: {} (c1 {}, c2 {})", smoothness_text(report.smoothness), report.c1, report.c2);
    let _ = writeln!(text, "\napproximated pairs (rule (6)):");
    uniform_text(&mut text, a);
    let _ = writeln!(text, "\ninterpolated pairs (rule (5), as a uniform scheme):");
    uniform_text(&mut text, &report.interpolating);
    (text, json)
}
