//! Loop-family commands: subdivide, reverse, decompose, reconstruct, analyze.

use std::path::Path;

use mesh_topo::PolygonSoup;
use mesh_topo::io::WriteOptions;
use subdiv_loop::LoopError;
use subdiv_loop::forward::{LoopOptions, VertexWeights};
use subdiv_loop::pyramid::{self, DecomposeOptions, Levels, LoopPyramid};

use super::common::{self, note_dropped, read_soup, write_soup};
use super::{
    AnalyzeArgs, CliError, CliResult, DecomposeArgs, ReadingArgs, ReconstructArgs, ReverseArgs, ReverseScheme,
    SubdivideArgs, input_error,
};

/// `subdivide --scheme loop | loop-warren | ternary-loop | quaternary-loop`.
pub fn subdivide(args: &SubdivideArgs) -> CliResult {
    use subdiv_loop::forward;
    use subdiv_loop::mband::{self, TernaryOptions};

    use super::SurfaceScheme;

    let (soup, report) = read_soup(&args.mesh)?;
    note_dropped(&args.mesh, &report);
    if let Some(face) = soup.faces().position(|f| f.len() != 3) {
        return Err(CliError::Input(format!(
            "{}: face {face} has {} corners; Loop schemes need triangles",
            args.mesh.display(),
            soup.face(face).len()
        )));
    }
    let mesh = super::common::build_mesh(&args.mesh, &soup)?;
    drop(soup);
    super::check_output_fits(&args.mesh, args.scheme, multires::ElementCounts::of(&mesh), args.levels)?;
    let weights = if args.scheme == SurfaceScheme::LoopWarren { VertexWeights::Warren } else { VertexWeights::Loop };
    let options = LoopOptions { weights, keep_corners: args.keep_corners };
    let fine = match args.scheme {
        SurfaceScheme::Loop | SurfaceScheme::LoopWarren => forward::subdivide(&mesh, args.levels, &options),
        SurfaceScheme::QuaternaryLoop => mband::quaternary_subdivide(&mesh, args.levels, &options),
        SurfaceScheme::TernaryLoop => {
            if args.keep_corners {
                eprintln!("multires: note: --keep-corners does not apply to ternary Loop (B-spline boundary)");
            }
            mband::ternary_subdivide(&mesh, args.levels, &TernaryOptions::default())
        }
        other => return Err(CliError::Input(format!("{other:?} is not a Loop scheme"))),
    }
    .map_err(|e| super::input_error(args.mesh.display(), e))?;
    drop(mesh);
    let (vertices, faces) = (fine.vertex_count(), fine.face_count());
    super::common::write_soup(&args.out, &fine.into_soup(), &mesh_topo::io::WriteOptions::default())?;
    let corners = if args.keep_corners && args.scheme != SurfaceScheme::TernaryLoop { ", corners kept" } else { "" };
    println!("{} x{}{corners}: {vertices} vertices, {faces} faces", args.scheme.word(), args.levels);
    Ok(())
}

/// The rules that `reverse` and `decompose` invert: those of `subdivide` with the same
/// `--scheme` and `--keep-corners`.
fn reverse_rules(scheme: ReverseScheme, keep_corners: bool) -> LoopOptions {
    let weights = if scheme == ReverseScheme::LoopWarren { VertexWeights::Warren } else { VertexWeights::Loop };
    LoopOptions { weights, keep_corners }
}

fn loop_error(path: &Path, error: LoopError) -> CliError {
    input_error(path.display(), error)
}

/// The options of `reverse` and `decompose` for a Loop scheme, for `levels` (an error
/// for `--seed-face`, which only the Doo-Sabin reversal takes).
fn decompose_options(
    scheme: ReverseScheme,
    reading: &ReadingArgs,
    levels: Levels,
) -> Result<DecomposeOptions, CliError> {
    if !reading.seed_face.is_empty() {
        return Err(CliError::Input(
            "--seed-face applies to --scheme doo; Loop connectivity is detected from the mesh alone".into(),
        ));
    }
    Ok(DecomposeOptions {
        rules: reverse_rules(scheme, reading.keep_corners),
        levels,
        seed_vertices: reading.seed_vertex.clone(),
    })
}

/// [`common::decompose_file`] by `pyramid::decompose_soup` (a file written by Loop
/// subdivision is reversed without building its half-edge mesh).
fn decompose_file(path: &Path, options: &DecomposeOptions) -> CliResult<(PolygonSoup, LoopPyramid)> {
    let mesh_error = |error| match error {
        LoopError::Mesh(error) => Ok(error),
        other => Err(other),
    };
    common::decompose_file(path, |soup| pyramid::decompose_soup(soup, options), mesh_error)
}

/// `reverse --scheme loop`: the coarse mesh after `--levels` reverse Loop steps (the
/// details are dropped; `decompose` keeps them).
pub fn reverse(args: &ReverseArgs) -> CliResult {
    let options = decompose_options(args.scheme, &args.reading, Levels::Count(args.levels as usize))?;
    if args.levels == 0 {
        return Err(CliError::Input("--levels must be at least 1".into()));
    }
    let (fine, pyramid) = decompose_file(&args.mesh, &options)?;
    write_soup(&args.out, &pyramid.base, &WriteOptions::default())?;
    println!(
        "reversed {} Loop level(s): {} vertices, {} faces -> {} vertices, {} faces",
        pyramid.level_count(),
        fine.vertex_count(),
        fine.face_count(),
        pyramid.base.vertex_count(),
        pyramid.base.face_count()
    );
    Ok(())
}

/// Fractions of the rate-distortion table printed by `decompose --report`.
const REPORT_FRACTIONS: [f64; 9] = [1.0, 0.5, 0.25, 0.1, 0.05, 0.02, 0.01, 0.005, 0.0];

/// `decompose --scheme loop`: base mesh plus the details of every level, as a `.mres` file.
pub fn decompose(args: &DecomposeArgs) -> CliResult {
    let levels = if args.max { Levels::Max } else { Levels::Count(args.levels as usize) };
    let options = decompose_options(args.scheme, &args.reading, levels)?;
    if !args.max && args.levels == 0 {
        return Err(CliError::Input("--levels must be at least 1".into()));
    }
    let (_, pyramid) = decompose_file(&args.mesh, &options)?;
    let report = if args.report {
        Some(pyramid.rate_distortion(&REPORT_FRACTIONS).map_err(|e| loop_error(&args.mesh, e))?)
    } else {
        None
    };
    let bytes = pyramid.to_bytes().map_err(|e| loop_error(&args.out, e))?;
    std::fs::write(&args.out, &bytes).map_err(|source| CliError::Io { path: args.out.clone(), source })?;
    let stored_orders = pyramid.levels.iter().filter(|l| l.order.is_some()).count();
    println!(
        "decomposed {} Loop level(s){}: base {} vertices, {} faces; {} details; {} level(s) store a vertex/face order; {} bytes",
        pyramid.level_count(),
        if args.max { " (as many as the connectivity allows)" } else { "" },
        pyramid.base.vertex_count(),
        pyramid.base.face_count(),
        pyramid.detail_count(),
        stored_orders,
        bytes.len()
    );
    if let Some(rows) = report {
        println!("keep fraction  details kept  max error / diag  rms error / diag");
        for row in rows {
            println!("{:>13}  {:>12}  {:>16.3e}  {:>16.3e}", row.fraction, row.kept, row.max_error, row.rms_error);
        }
    }
    Ok(())
}

/// True if `bytes` is a Loop `.mres` pyramid.
pub fn is_loop_pyramid(bytes: &[u8]) -> bool {
    LoopPyramid::is_loop_pyramid(bytes)
}

/// `reconstruct` of a Loop pyramid.
pub fn reconstruct(args: &ReconstructArgs, bytes: &[u8]) -> CliResult {
    if !is_loop_pyramid(bytes) {
        return Err(CliError::Input(format!(
            "{}: not a multires pyramid (neither a Loop nor a Doo-Sabin .mres file)",
            args.input.display()
        )));
    }
    let pyramid = LoopPyramid::from_bytes(bytes).map_err(|e| loop_error(&args.input, e))?;
    let level = args.level.map_or(pyramid.level_count(), |l| l as usize);
    if level > pyramid.level_count() {
        return Err(CliError::Input(format!(
            "--level {level}: the pyramid has levels 0 (base) to {}",
            pyramid.level_count()
        )));
    }
    let pyramid = match args.keep {
        Some(fraction) => pyramid.compressed(fraction).map_err(|e| input_error("--keep", e))?,
        None => pyramid,
    };
    let soup = pyramid.reconstruct(level).map_err(|e| loop_error(&args.input, e))?;
    write_soup(&args.out, &soup, &WriteOptions::default())?;
    println!(
        "reconstructed level {level} of {}: {} vertices, {} faces{}",
        pyramid.level_count(),
        soup.vertex_count(),
        soup.face_count(),
        args.keep.map_or(String::new(), |fraction| {
            let total = pyramid.detail_count();
            super::kept_details(subdiv_loop::pyramid::kept_count(fraction, total), total, fraction)
        })
    );
    Ok(())
}

/// `analyze --scheme loop | loop-warren | ternary-loop | quaternary-loop --valence N`.
pub fn analyze(args: &AnalyzeArgs) -> CliResult {
    use subdiv_loop::analysis::{self, AnalysisOptions, Scheme};

    use super::AnalyzeScheme;

    let scheme = match args.scheme {
        AnalyzeScheme::Loop => Scheme::Loop,
        AnalyzeScheme::LoopWarren => Scheme::LoopWarren,
        AnalyzeScheme::TernaryLoop => Scheme::TernaryLoop,
        AnalyzeScheme::QuaternaryLoop => Scheme::QuaternaryLoop,
        other => return Err(CliError::Input(format!("{other:?} is not a Loop scheme"))),
    };
    if args.curve.any_given() {
        return Err(CliError::Input("--omega1, --omega2, --gamma and --tension apply to curve schemes only".into()));
    }
    let valence =
        args.valence.ok_or_else(|| CliError::Input(format!("analyze --scheme {scheme}: give --valence N")))?;
    let result = analysis::analyze(scheme, valence as usize, &AnalysisOptions::default())
        .map_err(|e| super::input_error(format!("analyze --scheme {scheme}"), e))?;
    if args.json {
        println!("{}", analysis_json(&result));
    } else {
        print!("{}", analysis_text(&result));
    }
    Ok(())
}

/// An eigenvalue as a JSON number when real, else `[re, im]`.
fn eigenvalue_json(z: &[f64; 2]) -> serde_json::Value {
    if z[1].abs() < 1e-12 { serde_json::json!(z[0]) } else { serde_json::json!(z) }
}

/// The analysis as one JSON object (`eigenvalues` by decreasing modulus, `subdominant`,
/// `c1`, the conditions and the characteristic-map figures).
fn analysis_json(a: &subdiv_loop::analysis::Analysis) -> serde_json::Value {
    let mut value = serde_json::to_value(a).unwrap_or_default();
    value["eigenvalues"] = a.eigenvalues.iter().map(eigenvalue_json).collect();
    value["matrix"] = serde_json::json!("two-ring local subdivision matrix");
    value
}

/// The analysis as a short report.
fn analysis_text(a: &subdiv_loop::analysis::Analysis) -> String {
    use std::fmt::Write as _;
    let yes = |b: bool| if b { "yes" } else { "NO" };
    let format_eigenvalue = |z: &[f64; 2]| {
        if z[1].abs() < 1e-12 { format!("{:.9}", z[0]) } else { format!("{:.9}{:+.9}i", z[0], z[1]) }
    };
    let mut out = String::new();
    let _ = writeln!(
        out,
        "scheme {}, valence {}: two-ring local subdivision matrix, {} x {}",
        a.scheme, a.valence, a.size, a.size
    );
    let eigenvalues: Vec<String> = a.eigenvalues.iter().map(format_eigenvalue).collect();
    let _ = writeln!(out, "eigenvalues (decreasing modulus): {}", eigenvalues.join(", "));
    let _ = writeln!(
        out,
        "subdominant {:.12} (algebraic multiplicity {}, geometric {}); next modulus {:.12}",
        a.subdominant, a.algebraic_multiplicity, a.geometric_multiplicity, a.next_modulus
    );
    let c = &a.conditions;
    let _ = writeln!(
        out,
        "Reif: l0 = 1 simple: {}; l1 = l2 real in (0, 1): {}; no Jordan block: {}; l1 > |l3|: {}",
        yes(c.dominant_simple),
        yes(c.subdominant_real_double),
        yes(c.no_jordan_block),
        yes(c.gap)
    );
    match &a.characteristic_map {
        Some(m) => {
            let _ = writeln!(
                out,
                "characteristic map ({} steps): {} triangles of the ring, {} positive, {} negative, min/max area {:.3}; boundary turns {:.6} (inner), {:.6} (outer); regular: {}, injective: {}",
                m.steps,
                m.triangles,
                m.positive,
                m.negative,
                m.area_ratio,
                m.inner_turns,
                m.outer_turns,
                yes(m.regular()),
                yes(m.injective())
            );
        }
        None => {
            let _ = writeln!(out, "characteristic map: not checked (eigenvalue conditions fail)");
        }
    }
    let _ = writeln!(out, "C1: {}", yes(a.c1));
    out
}
