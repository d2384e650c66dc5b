//! Iterated function systems: `ifs`.

use std::io::Write;
use std::path::PathBuf;

use clap::Args;
use multires::ifs::{
    self as ifs, AffineIfs, BarycentricIfs, Canvas, ChaosGame, CircleMean, Complex64, ComplexBezierIfs,
    ContractivityReport, Density, ExpY, Ifs, Mean, MeanMode, NonlinearIfs, Polar, Projection, SquareY, ToneMap, View,
};

use super::{CliError, CliResult, input_error};

/// Options of `ifs`.
#[derive(Debug, Args)]
pub struct IfsArgs {
    /// Kind: bezier, patch, complex, nonlinear or sierpinski (or use --preset).
    #[arg(long)]
    pub kind: Option<String>,
    /// A named example from the literature (quartic-bump alias gaussian, levy, complex-spiral,
    /// sierpinski-polar, exp-gaussian, bicubic-patch, ...; an unknown name lists them all).
    #[arg(long, conflicts_with = "kind")]
    pub preset: Option<String>,
    /// Control points as "x,y x,y ..." (or "x,y,z ..." for patches and curves in space).
    #[arg(long, allow_hyphen_values = true)]
    pub control: Option<String>,
    /// Complex parameter as re,im (kind complex).
    #[arg(long, allow_hyphen_values = true)]
    pub z: Option<String>,
    /// Coordinate transform F of kind nonlinear: square (F(x,w) = (x,w²)), exp or polar.
    #[arg(long, default_value = "square")]
    pub transform: String,
    /// Kind nonlinear: subdivide the control points (data) with this mean instead of
    /// rendering an IFS: arithmetic, geometric, harmonic, cosine, power:P, or circle (the
    /// circle-preserving mean about --center).
    #[arg(long)]
    pub mean: Option<String>,
    /// With --mean: two-point (insert the mean of each neighbour pair) or three-point
    /// (quadratic pieces; needs an odd number of points).
    #[arg(long, default_value = "two-point")]
    pub scheme: String,
    /// With --mean: average x as well as y through the mean (default: y only, x linear).
    #[arg(long)]
    pub per_coordinate: bool,
    /// Centre of the circle-preserving mean as x,y.
    #[arg(long, allow_hyphen_values = true, default_value = "0,0")]
    pub center: String,
    /// Kind bezier: de Casteljau split parameter t in (0, 1).
    #[arg(long, default_value_t = 0.5)]
    pub split: f64,
    /// Output PNG.
    #[arg(long)]
    pub out: PathBuf,
    /// Also write the attractor points, one `x y` (or `x y z`) per line.
    #[arg(long)]
    pub out_points: Option<PathBuf>,
    /// Image size as WxH.
    #[arg(long, default_value = "800x800")]
    pub size: String,
    /// Deterministic algorithm with this many levels.
    #[arg(long, conflicts_with = "points")]
    pub levels: Option<u32>,
    /// Chaos game with this many points (at most 2^32, or 2^24 with --out-points).
    #[arg(long)]
    pub points: Option<usize>,
    /// Seed of the chaos game.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// Most points the command line keeps in memory: those of the deterministic algorithm,
/// and those of a chaos game written with `--out-points`.
const POINT_BUDGET: usize = 1 << 24;

/// Most chaos-game points streamed into the image: a bound on the running time (minutes,
/// not forever) far beyond what a density image can show.
const MAX_STREAMED_POINTS: u64 = 1 << 32;

/// What to render: the IFS, its deterministic start set and levels, and the projection.
struct Job {
    ifs: Box<dyn Ifs + Send>,
    start: Option<Vec<f64>>,
    levels: u32,
    projection: Projection,
}

/// `multires ifs`.
pub fn ifs(args: &IfsArgs) -> CliResult {
    let (width, height) = parse_size(&args.size)?;
    if let Some(mean) = &args.mean {
        if args.kind.as_deref() != Some("nonlinear") {
            return Err(CliError::Input("--mean applies to --kind nonlinear".into()));
        }
        return nonlinear_subdivision(args, mean, width, height);
    }
    let job = match (&args.preset, &args.kind) {
        (Some(name), _) => {
            let scene = ifs::preset(name).map_err(|e| CliError::Input(e.to_string()))?;
            Job { ifs: scene.ifs, start: scene.start, levels: scene.levels, projection: scene.projection }
        }
        (None, Some(kind)) => build_kind(kind, args)?,
        (None, None) => {
            return Err(CliError::Input(
                "give --kind (bezier, patch, complex, nonlinear, sierpinski) or --preset".into(),
            ));
        }
    };
    let ifs = &job.ifs;
    if let Some(report) = ifs.contractivity_report() {
        println!("{}", describe_contractivity(&report));
    }
    let (image, points) = match args.points {
        Some(n) => {
            let game = ChaosGame { points: n, seed: args.seed, ..ChaosGame::default() };
            if args.out_points.is_some() {
                if n > POINT_BUDGET {
                    return Err(CliError::Input(format!(
                        "--points {n} with --out-points: the points are kept to be written, at most \
                         {POINT_BUDGET} (without --out-points up to {MAX_STREAMED_POINTS} stream into the image)"
                    )));
                }
                let points = ifs::chaos_points(ifs, &game).map_err(|e| input_error("chaos game", e))?;
                let image = ifs::render_points(&points, width, height, job.projection, ToneMap::Log)
                    .map_err(|e| input_error("render", e))?;
                (image, Some(points))
            } else {
                if n as u64 > MAX_STREAMED_POINTS {
                    return Err(CliError::Input(format!(
                        "--points {n}: at most {MAX_STREAMED_POINTS} chaos-game points"
                    )));
                }
                // Stream into the density image; the view comes from a short run of the same game.
                let preview = ChaosGame { points: n.min(1 << 15), ..game.clone() };
                let sample = ifs::chaos_points(ifs, &preview).map_err(|e| input_error("chaos game", e))?;
                let view =
                    View::fit(&sample, job.projection, width, height, 0.05).map_err(|e| input_error("render", e))?;
                let canvas = Canvas::new(width, height, view)
                    .map_err(|e| input_error("render", e))?
                    .with_projection(job.projection);
                let density = ifs::chaos_density(ifs, &game, &canvas).map_err(|e| input_error("chaos game", e))?;
                (density.to_image(ToneMap::Log, [0, 0, 0, 255], [255, 255, 255, 255]), None)
            }
        }
        None => {
            let levels = args.levels.unwrap_or(job.levels);
            let points = ifs::deterministic_points(ifs, job.start.as_deref(), levels, POINT_BUDGET)
                .map_err(|e| input_error("deterministic algorithm", e))?;
            let view = View::fit(&points, job.projection, width, height, 0.02).map_err(|e| input_error("render", e))?;
            let canvas =
                Canvas::new(width, height, view).map_err(|e| input_error("render", e))?.with_projection(job.projection);
            let image = Density::from_points(&points, &canvas).map_err(|e| input_error("render", e))?.to_image(
                ToneMap::Log,
                [0, 0, 0, 255],
                [255, 255, 255, 255],
            );
            (image, Some(points))
        }
    };
    image.write_png(&args.out).map_err(|e| CliError::Input(e.to_string()))?;
    if let (Some(path), Some(points)) = (&args.out_points, &points) {
        write_points(path, points, ifs.point_dim())?;
    }
    let count = points.as_ref().map_or(args.points.unwrap_or(0), Vec::len);
    println!("{} points -> {}", count, args.out.display());
    Ok(())
}

fn build_kind(kind: &str, args: &IfsArgs) -> CliResult<Job> {
    let job = |ifs: Box<dyn Ifs + Send>, levels: u32| Job { ifs, start: None, levels, projection: Projection::Xy };
    let orbit = Projection::Orbit { azimuth: 0.6, elevation: 0.45 };
    let fail = |e: ifs::IfsError| CliError::Input(format!("{kind}: {e}"));
    match kind {
        "bezier" => match parse_points(args.control.as_deref().ok_or_else(|| needs("bezier", "--control"))?)? {
            Points::Planar(p) => {
                let rule = ifs::bezier_split(p.len().saturating_sub(1).max(1), args.split).map_err(fail)?;
                Ok(job(Box::new(BarycentricIfs::new(&rule, &p).map_err(fail)?), 12))
            }
            Points::Spatial(p) => {
                let rule = ifs::bezier_split(p.len().saturating_sub(1).max(1), args.split).map_err(fail)?;
                Ok(Job { projection: orbit, ..job(Box::new(BarycentricIfs::new(&rule, &p).map_err(fail)?), 12) })
            }
        },
        "patch" => {
            let points = parse_points(args.control.as_deref().ok_or_else(|| needs("patch", "--control"))?)?;
            let count = points.len();
            let rule = match count {
                4 => ifs::tensor_patch_split(1, 1),
                9 => ifs::tensor_patch_split(2, 2),
                16 => ifs::tensor_patch_split(3, 3),
                3 | 6 | 10 | 15 => {
                    ifs::triangle_patch_split([3, 6, 10, 15].iter().position(|&c| c == count).unwrap_or(0) + 1)
                }
                _ => {
                    return Err(CliError::Input(format!(
                        "patch: {count} control points; give 4, 9 or 16 (bilinear, biquadratic, bicubic tensor patch) \
                         or 3, 6, 10, 15 (triangular patch of degree 1-4)"
                    )));
                }
            }
            .map_err(fail)?;
            match points {
                Points::Planar(p) => Ok(job(Box::new(BarycentricIfs::new(&rule, &p).map_err(fail)?), 6)),
                Points::Spatial(p) => {
                    Ok(Job { projection: orbit, ..job(Box::new(BarycentricIfs::new(&rule, &p).map_err(fail)?), 6) })
                }
            }
        }
        "complex" => {
            let z = parse_pair(args.z.as_deref().ok_or_else(|| needs("complex", "--z re,im"))?, "--z")?;
            let control: Vec<Complex64> = match args.control.as_deref() {
                None => vec![Complex64::new(0.0, 0.0), Complex64::new(1.0, 0.0)],
                Some(text) => match parse_points(text)? {
                    Points::Planar(p) => p.iter().map(|q| Complex64::new(q[0], q[1])).collect(),
                    Points::Spatial(_) => {
                        return Err(CliError::Input("complex: control points must be planar (x,y)".into()));
                    }
                },
            };
            Ok(job(Box::new(ComplexBezierIfs::new(Complex64::new(z[0], z[1]), &control).map_err(fail)?), 14))
        }
        "nonlinear" => {
            let control = planar(args.control.as_deref().unwrap_or("-1,0 0,5 1,0"), "nonlinear")?;
            let linear = AffineIfs::from_rule(&ifs::bezier_split(2, 0.5).map_err(fail)?, &control).map_err(fail)?;
            let ifs: Box<dyn Ifs + Send> = match args.transform.as_str() {
                "square" => Box::new(NonlinearIfs::new(linear, SquareY)),
                "exp" => Box::new(NonlinearIfs::new(linear, ExpY)),
                "polar" => Box::new(NonlinearIfs::new(linear, Polar)),
                other => return Err(CliError::Input(format!("--transform {other}: use square, exp or polar"))),
            };
            Ok(job(ifs, 12))
        }
        "sierpinski" => {
            let control = planar(args.control.as_deref().unwrap_or("0,0 1,0 0.5,0.8660254037844386"), "sierpinski")?;
            Ok(job(Box::new(AffineIfs::from_rule(&ifs::sierpinski(), &control).map_err(fail)?), 8))
        }
        other => Err(CliError::Input(format!("--kind {other}: use bezier, patch, complex, nonlinear or sierpinski"))),
    }
}

/// One line: the largest singular value of the linear parts and the joint-spectral-radius
/// bounds on the difference space.
fn describe_contractivity(report: &ContractivityReport) -> String {
    format!(
        "contractivity: largest singular value {:.6}, joint spectral radius in [{:.6}, {:.6}] (word length {})",
        report.max_singular_value, report.jsr_lower, report.jsr_upper, report.word_length
    )
}

/// `--kind nonlinear --mean NAME`: nonlinear subdivision of the control points (data
/// values) by a nonlinear mean, `--levels` times (default 6).
fn nonlinear_subdivision(args: &IfsArgs, mean_name: &str, width: u32, height: u32) -> CliResult {
    if args.points.is_some() {
        return Err(CliError::Input("--mean subdivides deterministically: use --levels, not --points".into()));
    }
    let text = args.control.as_deref().ok_or_else(|| needs("nonlinear --mean", "--control"))?;
    let control = match parse_points(text)? {
        Points::Planar(p) => p,
        Points::Spatial(_) => return Err(CliError::Input("--mean: control points must be planar (x,y)".into())),
    };
    let levels = args.levels.unwrap_or(6);
    // Each level roughly doubles the points; cap like the deterministic algorithm.
    let final_count = (0..levels).try_fold(control.len() as u128, |n, _| {
        let next = 2 * n - 1;
        (next <= POINT_BUDGET as u128).then_some(next)
    });
    if final_count.is_none() {
        return Err(CliError::Input(format!(
            "--levels {levels}: {} points would exceed the budget of {POINT_BUDGET}",
            if levels >= 128 { "too many".to_string() } else { format!("about {}", (control.len() as u128) << levels) }
        )));
    }
    let fail = |e: ifs::IfsError| CliError::Input(format!("--mean {mean_name}: {e}"));
    let mut points = control;
    if mean_name == "circle" {
        let c = parse_pair(&args.center, "--center")?;
        let circle = CircleMean::new(Complex64::new(c[0], c[1])).map_err(fail)?;
        let mut z: Vec<Complex64> = points.iter().map(|p| Complex64::new(p[0], p[1])).collect();
        for _ in 0..levels {
            z = match args.scheme.as_str() {
                "two-point" => circle.two_point_subdivide(&z),
                "three-point" => circle.three_point_subdivide(&z),
                other => return Err(CliError::Input(format!("--scheme {other}: use two-point or three-point"))),
            }
            .map_err(fail)?;
        }
        points = z.iter().map(|q| [q.re, q.im]).collect();
    } else {
        let mean = parse_mean(mean_name)?;
        let mode = if args.per_coordinate { MeanMode::PerCoordinate } else { MeanMode::YOnly };
        for _ in 0..levels {
            points = match args.scheme.as_str() {
                "two-point" => ifs::two_point_subdivide(&points, mean, mode),
                "three-point" => ifs::three_point_subdivide(&points, mean, mode),
                other => {
                    return Err(CliError::Input(format!("--scheme {other}: use two-point or three-point")));
                }
            }
            .map_err(fail)?;
        }
    }
    let points: Vec<[f64; 3]> = points.iter().map(|p| [p[0], p[1], 0.0]).collect();
    let image = ifs::render_points(&points, width, height, Projection::Xy, ToneMap::Coverage)
        .map_err(|e| input_error("render", e))?;
    image.write_png(&args.out).map_err(|e| CliError::Input(e.to_string()))?;
    if let Some(path) = &args.out_points {
        write_points(path, &points, 2)?;
    }
    println!("{} points -> {}", points.len(), args.out.display());
    Ok(())
}

fn parse_mean(name: &str) -> CliResult<Mean> {
    Ok(match name {
        "arithmetic" => Mean::Arithmetic,
        "geometric" => Mean::Geometric,
        "harmonic" => Mean::Harmonic,
        "cosine" => Mean::Cosine,
        other => match other.strip_prefix("power:").map(|p| p.parse::<f64>()) {
            Some(Ok(p)) if p.is_finite() => Mean::Power(p),
            _ => {
                return Err(CliError::Input(format!(
                    "--mean {other}: use arithmetic, geometric, harmonic, cosine, power:P or circle"
                )));
            }
        },
    })
}

fn needs(kind: &str, option: &str) -> CliError {
    CliError::Input(format!("--kind {kind} needs {option}"))
}

enum Points {
    Planar(Vec<[f64; 2]>),
    Spatial(Vec<[f64; 3]>),
}

impl Points {
    fn len(&self) -> usize {
        match self {
            Points::Planar(p) => p.len(),
            Points::Spatial(p) => p.len(),
        }
    }
}

fn planar(text: &str, kind: &str) -> CliResult<Vec<[f64; 2]>> {
    match parse_points(text)? {
        Points::Planar(p) if p.len() == 3 => Ok(p),
        Points::Planar(p) => Err(CliError::Input(format!("{kind}: needs 3 control points, got {}", p.len()))),
        Points::Spatial(_) => Err(CliError::Input(format!("{kind}: control points must be planar (x,y)"))),
    }
}

/// Parses "x,y x,y ..." or "x,y,z ...": all points of one dimension, finite numbers.
fn parse_points(text: &str) -> CliResult<Points> {
    let mut planar = Vec::new();
    let mut spatial = Vec::new();
    for (index, token) in text.split_whitespace().enumerate() {
        let values: Vec<f64> = token
            .split(',')
            .map(|v| v.trim().parse::<f64>().ok().filter(|x| x.is_finite()))
            .collect::<Option<_>>()
            .ok_or_else(|| {
                CliError::Input(format!("--control: point {index} `{token}` is not x,y or x,y,z with finite numbers"))
            })?;
        match values.as_slice() {
            [x, y] => planar.push([*x, *y]),
            [x, y, z] => spatial.push([*x, *y, *z]),
            _ => {
                return Err(CliError::Input(format!(
                    "--control: point {index} `{token}` has {} coordinates",
                    values.len()
                )));
            }
        }
        if !planar.is_empty() && !spatial.is_empty() {
            return Err(CliError::Input(format!("--control: point {index} mixes 2D and 3D points")));
        }
    }
    match (planar.is_empty(), spatial.is_empty()) {
        (true, true) => Err(CliError::Input("--control: no points".into())),
        (false, _) => Ok(Points::Planar(planar)),
        (true, false) => Ok(Points::Spatial(spatial)),
    }
}

fn parse_pair(text: &str, option: &str) -> CliResult<[f64; 2]> {
    let values: Option<Vec<f64>> =
        text.split(',').map(|v| v.trim().parse::<f64>().ok().filter(|x| x.is_finite())).collect();
    match values.as_deref() {
        Some([a, b]) => Ok([*a, *b]),
        _ => Err(CliError::Input(format!("{option} `{text}`: expected two finite numbers re,im"))),
    }
}

fn parse_size(text: &str) -> CliResult<(u32, u32)> {
    let parsed = text.split_once(['x', 'X']).and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)));
    match parsed {
        Some((w, h))
            if (1..=ifs::render::MAX_IMAGE_SIDE).contains(&w) && (1..=ifs::render::MAX_IMAGE_SIDE).contains(&h) =>
        {
            Ok((w, h))
        }
        _ => Err(CliError::Input(format!(
            "--size `{text}`: expected WxH with sides in 1..={}",
            ifs::render::MAX_IMAGE_SIDE
        ))),
    }
}

fn write_points(path: &PathBuf, points: &[[f64; 3]], dim: usize) -> CliResult {
    let io = |source| CliError::Io { path: path.clone(), source };
    let file = std::fs::File::create(path).map_err(io)?;
    let mut out = std::io::BufWriter::new(file);
    for p in points {
        if dim == 3 {
            writeln!(out, "{} {} {}", p[0], p[1], p[2]).map_err(io)?;
        } else {
            writeln!(out, "{} {}", p[0], p[1]).map_err(io)?;
        }
    }
    out.flush().map_err(io)
}
