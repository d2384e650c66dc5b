//! Triangular spline fitting: `fit`.
//!
//! Reads a triangle mesh, fits a triangular Bézier patch, B-patch or DMS triangular
//! B-spline by LSPIA, classical PIA or the seed paper's reverse-Loop loop
//! ([`multires::spline::pipeline`](tri_spline::pipeline)), and prints the convergence
//! table in the form of the seed paper's Table 2 (or one JSON object), optionally with a
//! plot and a triangulated sampling of the fitted surface.

use std::io::BufWriter;
use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};
use mesh_topo::PolygonSoup;
use mesh_topo::io::WriteOptions;
use tri_spline::SurfaceKind;
use tri_spline::fit::IterationRecord;
use tri_spline::pipeline::{FitOptions, FitReport, Method, fit_mesh};

use super::common;
use super::{CliError, CliResult, input_error};

/// Surface kinds on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SurfaceArg {
    /// Triangular Bézier patch (input: a regular triangular grid).
    Bezier,
    /// Seidel's B-patch (input: a regular triangular grid).
    Bpatch,
    /// DMS triangular B-spline (input: any disk with Loop connectivity for the levels).
    TriBspline,
}

/// Iterations on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Least-squares PIA: converges to the least-squares fit, residual never increases.
    Lspia,
    /// Classical PIA: interpolates the data at the control points' own vertices.
    Pia,
    /// The seed paper's loop: P* += E, C = R(P*) with R the reverse-Loop map.
    Seed,
}

/// Options of `fit`.
#[derive(Debug, Args)]
pub struct FitArgs {
    /// The triangle mesh to fit (disk topology; OBJ, OFF or PLY).
    pub mesh: PathBuf,
    /// Surface kind.
    #[arg(long, value_enum, default_value = "bezier")]
    pub surface: SurfaceArg,
    /// Iteration.
    #[arg(long, value_enum, default_value = "lspia")]
    pub method: MethodArg,
    /// Number of reverse-Loop levels that give the control net.
    #[arg(long, default_value_t = 2)]
    pub reverse_levels: u32,
    /// Maximum number of iterations (1 to 1000000).
    #[arg(long, default_value_t = 10)]
    pub iterations: usize,
    /// Stop when the mean error falls below this (absolute).
    #[arg(long)]
    pub tolerance: Option<f64>,
    /// A data point counts as hit when its error is at most this (absolute; default
    /// 0.002 times the bounding-box diagonal).
    #[arg(long)]
    pub hit_tol: Option<f64>,
    /// Degree of the triangular B-spline.
    #[arg(long, default_value_t = 2)]
    pub degree: usize,
    /// Refuse to iterate when the computed spectral radius is at least 1 (default: warn).
    #[arg(long)]
    pub strict: bool,
    /// Skip the direct least-squares baseline.
    #[arg(long)]
    pub no_least_squares: bool,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Plot eps_max, eps_avg and N_eps against k to this PNG.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Write a triangulated sampling of the fitted surface (OBJ, OFF or PLY).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Segments per domain edge of the sampling written by `--out`.
    #[arg(long, default_value_t = 32)]
    pub samples: usize,
}

/// Most iterations `fit` runs: every one is a row of the table (and of the JSON).
const MAX_ITERATIONS: usize = 1_000_000;

/// `multires fit`.
pub fn fit(args: &FitArgs) -> CliResult {
    if args.samples == 0 || args.samples > 4096 {
        return Err(CliError::Input(format!("--samples {}: expected 1 to 4096 segments per edge", args.samples)));
    }
    if args.iterations > MAX_ITERATIONS {
        return Err(CliError::Input(format!("--iterations {}: expected 1 to {MAX_ITERATIONS}", args.iterations)));
    }
    let mesh = common::read_mesh(&args.mesh)?;
    let options = FitOptions {
        surface: match args.surface {
            SurfaceArg::Bezier => SurfaceKind::Bezier,
            SurfaceArg::Bpatch => SurfaceKind::Bpatch,
            SurfaceArg::TriBspline => SurfaceKind::TriBspline,
        },
        method: match args.method {
            MethodArg::Lspia => Method::Lspia,
            MethodArg::Pia => Method::Pia,
            MethodArg::Seed => Method::Seed,
        },
        reverse_levels: args.reverse_levels,
        iterations: args.iterations,
        tolerance: args.tolerance,
        hit_tol: args.hit_tol,
        dms_degree: args.degree,
        refuse_divergent: args.strict,
        least_squares: !args.no_least_squares,
        ..FitOptions::default()
    };
    let report = fit_mesh(&mesh, &options).map_err(|e| input_error(args.mesh.display(), e))?;
    if args.json {
        println!("{}", json_report(&report));
    } else {
        print_table(&report);
    }
    if let Some(path) = &args.plot {
        let with_text = plot_convergence(path, &report.iterations)?;
        if !with_text && !args.json {
            println!(
                "plot: {} (no fonts available: drawn without text; red eps_max and blue eps_avg on a log scale, green N_eps from 0 to 100 %)",
                path.display()
            );
        }
    }
    if let Some(path) = &args.out {
        let (positions, triangles) = report.surface.sample(&report.domain, args.samples);
        let soup = PolygonSoup::from_faces(positions, triangles);
        common::write_soup(path, &soup, &WriteOptions::default())?;
    }
    Ok(())
}

fn print_table(report: &FitReport) {
    println!(
        "{} fitted by {}: {} reverse-Loop level(s), degree {}, {} control points, {} data points",
        report.kind.name(),
        report.method.name(),
        report.reverse_levels,
        report.degree,
        report.control_points,
        report.data_points
    );
    println!(
        "errors are absolute (bounding-box diagonal {:.6}); N_eps counts |E_j| <= {:.3e}",
        report.bbox_diag, report.hit_tol
    );
    println!("{:>4} {:>13} {:>13} {:>10} {:>10}", "k", "eps_max", "eps_avg", "N_eps %", "seconds");
    for r in &report.iterations {
        println!("{:>4} {:>13.6e} {:>13.6e} {:>10.3} {:>10.4}", r.k, r.eps_max, r.eps_avg, r.n_eps, r.seconds);
    }
    match report.spectral_radius {
        Some(rho) => println!("spectral radius {} = {rho:.12} (computed)", report.spectral_note),
        None => println!("spectral radius {}", report.spectral_note),
    }
    if let Some(ls) = &report.least_squares {
        println!(
            "least squares (dense QR): eps_max {:.6e}, eps_avg {:.6e}, N_eps {:.3} %, {:.4} s",
            ls.eps_max, ls.eps_avg, ls.n_eps, ls.seconds
        );
    }
    println!("total time {:.4} s (iterations {:.4} s)", report.timings.total, report.timings.iterations);
    for w in &report.warnings {
        eprintln!("multires: warning: {w}");
    }
}

fn json_report(report: &FitReport) -> String {
    let iterations: Vec<serde_json::Value> = report
        .iterations
        .iter()
        .map(|r| serde_json::json!({"k": r.k, "eps_max": r.eps_max, "eps_avg": r.eps_avg, "n_eps": r.n_eps, "seconds": r.seconds}))
        .collect();
    let mut object = serde_json::json!({
        "surface": report.kind.name(),
        "method": report.method.name(),
        "reverse_levels": report.reverse_levels,
        "degree": report.degree,
        "control_points": report.control_points,
        "data_points": report.data_points,
        "bbox_diag": report.bbox_diag,
        "hit_tol": report.hit_tol,
        "iterations": iterations,
        "warnings": report.warnings,
        "timings": {
            "parameterize": report.timings.parameterize,
            "reverse_loop": report.timings.reverse_loop,
            "collocation": report.timings.collocation,
            "spectral": report.timings.spectral,
            "iterations": report.timings.iterations,
            "least_squares": report.timings.least_squares,
            "total": report.timings.total,
        },
    });
    if let Some(rho) = report.spectral_radius {
        object["spectral_radius"] = serde_json::json!(rho);
        object["spectral_matrix"] = serde_json::json!(report.spectral_note);
    }
    if let Some(ls) = &report.least_squares {
        object["least_squares"] = serde_json::json!({
            "eps_max": ls.eps_max, "eps_avg": ls.eps_avg, "n_eps": ls.n_eps, "seconds": ls.seconds,
        });
    }
    object.to_string()
}

const PLOT_SIZE: (u32, u32) = (960, 600);

/// Draws the convergence plot; returns whether text (axes, legend) could be drawn. Text
/// needs a system font; without one the plot is drawn again without any text.
fn plot_convergence(path: &Path, records: &[IterationRecord]) -> CliResult<bool> {
    let mut buffer = vec![255u8; (PLOT_SIZE.0 * PLOT_SIZE.1 * 3) as usize];
    let with_text = draw_plot(&mut buffer, records, true).is_ok();
    if !with_text {
        buffer.iter_mut().for_each(|b| *b = 255);
        draw_plot(&mut buffer, records, false)
            .map_err(|e| CliError::Input(format!("{}: plot: {e}", path.display())))?;
    }
    write_png(path, &buffer).map_err(|source| CliError::Io { path: path.to_path_buf(), source })?;
    Ok(with_text)
}

fn draw_plot(buffer: &mut [u8], records: &[IterationRecord], text: bool) -> Result<(), String> {
    use plotters::prelude::*;
    let k_max = records.last().map_or(1, |r| r.k).max(2) as f64;
    let positive = |v: f64| if v > 0.0 { v } else { f64::MIN_POSITIVE };
    let lo = records.iter().map(|r| positive(r.eps_avg).min(positive(r.eps_max))).fold(f64::INFINITY, f64::min);
    let hi = records.iter().map(|r| r.eps_max.max(r.eps_avg)).fold(0.0, f64::max);
    let (lo, hi) = if lo.is_finite() && hi > lo { (lo / 2.0, hi * 2.0) } else { (1e-16, 1.0) };
    let root = BitMapBackend::with_buffer(buffer, PLOT_SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut builder = ChartBuilder::on(&root);
    builder.margin(20);
    if text {
        builder
            .caption("convergence: eps_max, eps_avg (log, left), N_eps % (right)", ("sans-serif", 22))
            .x_label_area_size(45)
            .y_label_area_size(80)
            .right_y_label_area_size(60);
    }
    let mut chart = builder
        .build_cartesian_2d(1f64..k_max, (lo..hi).log_scale())
        .map_err(|e| e.to_string())?
        .set_secondary_coord(1f64..k_max, 0f64..100f64);
    if text {
        chart
            .configure_mesh()
            .x_desc("k")
            .y_desc("error")
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(|e| e.to_string())?;
        chart.configure_secondary_axes().y_desc("N_eps %").draw().map_err(|e| e.to_string())?;
    } else {
        // No text: a light grey line at every power of ten and at every k, and a frame.
        let grey = RGBColor(200, 200, 200);
        let (first, last) = (lo.log10().ceil() as i32, hi.log10().floor() as i32);
        chart
            .draw_series(
                (first..=last).map(|e| PathElement::new(vec![(1.0, 10f64.powi(e)), (k_max, 10f64.powi(e))], grey)),
            )
            .map_err(|e| e.to_string())?;
        chart
            .draw_series((1..=k_max as usize).map(|k| PathElement::new(vec![(k as f64, lo), (k as f64, hi)], grey)))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(1.0, lo), (k_max, lo), (k_max, hi), (1.0, hi), (1.0, lo)],
                BLACK,
            )))
            .map_err(|e| e.to_string())?;
    }
    let series = |f: fn(&IterationRecord) -> f64| records.iter().map(move |r| (r.k as f64, positive(f(r))));
    let max_series =
        chart.draw_series(LineSeries::new(series(|r| r.eps_max), RED.stroke_width(2))).map_err(|e| e.to_string())?;
    if text {
        max_series.label("eps_max").legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
    }
    let avg_series =
        chart.draw_series(LineSeries::new(series(|r| r.eps_avg), BLUE.stroke_width(2))).map_err(|e| e.to_string())?;
    if text {
        avg_series.label("eps_avg").legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
    }
    let hits = chart
        .draw_secondary_series(LineSeries::new(records.iter().map(|r| (r.k as f64, r.n_eps)), GREEN.stroke_width(2)))
        .map_err(|e| e.to_string())?;
    if text {
        hits.label("N_eps %").legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], GREEN));
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperMiddle)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| e.to_string())?;
    }
    root.present().map_err(|e| e.to_string())?;
    Ok(())
}

fn write_png(path: &Path, rgb: &[u8]) -> std::io::Result<()> {
    let file = std::fs::File::create(path)?;
    let mut encoder = png::Encoder::new(BufWriter::new(file), PLOT_SIZE.0, PLOT_SIZE.1);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer.write_image_data(rgb).map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)
}
