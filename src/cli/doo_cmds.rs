//! Doo-Sabin-family commands: subdivide, reverse, decompose, reconstruct, analyze.
//!
//! `reverse` and `decompose` invert the rule their `--scheme` names, as `subdivide`
//! names them (`doo-sabin`, `doo-simple`, `doo-centroid`); `--scheme doo` is the
//! original Doo-Sabin weights (CGAL's and most peers' choice). The rule is stored in the
//! `.mres` file, so `reconstruct` needs no option. Every command computes
//! its whole result before it writes anything: bad input writes no file.

use std::fmt::Write as _;
use std::path::Path;

use mesh_topo::PolygonSoup;
use mesh_topo::io::WriteOptions;
use multires::ElementCounts;
use subdiv_doo::analysis::{ReifReport, reif_check};
use subdiv_doo::pyramid::{DecomposeOptions, Decomposition, Depth, DooPyramid, decompose_soup};
use subdiv_doo::{BoundaryRule, DooError, DooOptions, FaceRule, SeedChoice, subdivide_soup};

use super::common::{self, note_dropped, read_soup, write_soup};
use super::{
    AnalyzeArgs, AnalyzeScheme, BoundaryArg, CliError, CliResult, DecomposeArgs, ReadingArgs, ReconstructArgs,
    ReverseArgs, ReverseScheme, SubdivideArgs, SurfaceScheme, input_error,
};

/// The per-face rule that `reverse` and `decompose` invert: that of `subdivide` with the
/// same `--scheme` (`doo` is `doo-sabin`).
fn reverse_rule(scheme: ReverseScheme, keep_corners: bool, seed_vertices: &[u32]) -> Result<FaceRule, CliError> {
    if keep_corners {
        return Err(CliError::Input("--keep-corners applies to the Loop schemes only".into()));
    }
    if !seed_vertices.is_empty() {
        return Err(CliError::Input(
            "--seed-vertex applies to the Loop schemes; Doo-Sabin reversal takes --seed-face".into(),
        ));
    }
    Ok(match scheme {
        ReverseScheme::Doo | ReverseScheme::DooSabin => FaceRule::DooSabin,
        ReverseScheme::DooSimple => FaceRule::Simple,
        ReverseScheme::DooCentroid => FaceRule::CENTROID_HALF,
        other => return Err(CliError::Input(format!("{other:?} is not a Doo-Sabin scheme"))),
    })
}

/// Fractions of the rate-distortion table printed by `decompose --report`.
const REPORT_FRACTIONS: [f64; 9] = [1.0, 0.5, 0.25, 0.1, 0.05, 0.02, 0.01, 0.005, 0.0];

/// The boundary rule of `--boundary` (default: shrink).
fn boundary_rule(arg: Option<BoundaryArg>) -> BoundaryRule {
    match arg {
        None | Some(BoundaryArg::Shrink) => BoundaryRule::Shrink,
        Some(BoundaryArg::Chaikin) => BoundaryRule::Chaikin,
    }
}

fn doo_error(path: &Path, error: DooError) -> CliError {
    input_error(path.display(), error)
}

/// `subdivide --scheme doo-sabin | doo-simple | doo-centroid`.
pub fn subdivide(args: &SubdivideArgs) -> CliResult {
    let rule = match args.scheme {
        SurfaceScheme::DooSabin => FaceRule::DooSabin,
        SurfaceScheme::DooSimple => FaceRule::Simple,
        SurfaceScheme::DooCentroid => FaceRule::CENTROID_HALF,
        other => return Err(CliError::Input(format!("{other:?} is not a Doo-Sabin scheme"))),
    };
    if args.keep_corners {
        return Err(CliError::Input("--keep-corners applies to the Loop schemes only".into()));
    }
    let (soup, report) = read_soup(&args.mesh)?;
    note_dropped(&args.mesh, &report);
    // As if closed (a closed mesh has half as many edges as corners): with the default
    // boundary rule an upper bound of what an open mesh makes.
    let counts =
        ElementCounts { vertices: soup.vertex_count(), edges: soup.indices.len() / 2, faces: soup.face_count() };
    super::check_output_fits(&args.mesh, args.scheme, counts, args.levels)?;
    let options = DooOptions::new(rule, args.levels).with_boundary(boundary_rule(args.boundary));
    let fine = subdivide_soup(&soup, &options).map_err(|e| doo_error(&args.mesh, e))?;
    drop(soup);
    let [ff, fe, fv] = fine.kind_counts();
    let (vertices, faces) = (fine.vertex_count(), fine.face_count());
    write_soup(&args.out, &fine.into_soup(), &WriteOptions::default())?;
    println!(
        "{} x{}, {} boundary: {vertices} vertices, {faces} faces (last level: {ff} F_F, {fe} F_E, {fv} F_V)",
        rule.name(),
        args.levels,
        options.boundary
    );
    Ok(())
}

/// One line per component of a reversal: the seed, its class and the detail norm.
fn choice_lines(level: usize, choices: &[SeedChoice]) -> String {
    let mut out = String::new();
    for choice in choices {
        // The class the winning seed plays in its reading (`F_F` for a given seed).
        let class = choice
            .trials
            .iter()
            .find(|t| t.seed_face == choice.seed_face && t.outcome.is_ok())
            .map_or("F_F", |t| t.class.as_str());
        let how = if choice.given { "given" } else { "automatic" };
        let valid = choice.trials.iter().filter(|t| t.outcome.is_ok()).count();
        let _ = writeln!(
            out,
            "  level {level}, component {}: seed face {} as {class} ({how}, {valid} valid of {} readings tried); detail norm {:.6e}; {}",
            choice.component,
            choice.seed_face,
            choice.trials.len(),
            choice.detail_norm,
            choice.reason
        );
    }
    out
}

/// [`common::decompose_file`] by `pyramid::decompose_soup` (the first level of a file
/// written by Doo-Sabin subdivision under the shrinking boundary rule is reversed without
/// building its half-edge mesh).
fn decompose_file(path: &Path, options: &DecomposeOptions) -> CliResult<(PolygonSoup, Decomposition)> {
    let mesh_error = |error| match error {
        DooError::Mesh(error) => Ok(error),
        other => Err(other),
    };
    common::decompose_file(path, |soup| decompose_soup(soup, options), mesh_error)
}

/// The seed faces of `--seed-face`, in the order given (the library names a seed out of
/// range, or two seeds in one component).
fn seeds(seed_faces: &[u32]) -> Vec<usize> {
    seed_faces.iter().map(|&f| f as usize).collect()
}

/// The options of `reverse` and `decompose` for a Doo-Sabin scheme, to `depth`.
fn decompose_options(scheme: ReverseScheme, reading: &ReadingArgs, depth: Depth) -> Result<DecomposeOptions, CliError> {
    Ok(DecomposeOptions {
        rule: reverse_rule(scheme, reading.keep_corners, &reading.seed_vertex)?,
        depth,
        seeds: seeds(&reading.seed_face),
        boundary: boundary_rule(reading.boundary),
    })
}

/// `reverse --scheme doo`: the coarse mesh after `--levels` reverse Doo-Sabin steps (the
/// details are dropped; `decompose` keeps them). Prints the seed and candidate class
/// chosen for every component of every level, with the detail norm `sqrt(Σ|d_i|²)`.
pub fn reverse(args: &ReverseArgs) -> CliResult {
    if args.levels == 0 {
        return Err(CliError::Input("--levels must be at least 1".into()));
    }
    let options = decompose_options(args.scheme, &args.reading, Depth::Levels(args.levels))?;
    let (mesh, decomposition) = decompose_file(&args.mesh, &options)?;
    let pyramid = &decomposition.pyramid;
    write_soup(&args.out, &pyramid.base, &WriteOptions::default())?;
    let mut text = format!(
        "reversed {} Doo-Sabin level(s): {} vertices, {} faces -> {} vertices, {} faces\n",
        pyramid.level_count(),
        mesh.vertex_count(),
        mesh.face_count(),
        pyramid.base.vertex_count(),
        pyramid.base.face_count()
    );
    for (k, choices) in decomposition.choices.iter().enumerate() {
        text.push_str(&choice_lines(k + 1, choices));
    }
    print!("{text}");
    Ok(())
}

/// `decompose --scheme doo`: base mesh plus the details of every level, as a `.mres` file.
pub fn decompose(args: &DecomposeArgs) -> CliResult {
    if !args.max && args.levels == 0 {
        return Err(CliError::Input("--levels must be at least 1".into()));
    }
    let depth = if args.max { Depth::Max } else { Depth::Levels(args.levels) };
    let options = decompose_options(args.scheme, &args.reading, depth)?;
    let (mesh, decomposition) = decompose_file(&args.mesh, &options)?;
    let pyramid = &decomposition.pyramid;
    let report = if args.report {
        Some(pyramid.rate_distortion(&REPORT_FRACTIONS).map_err(|e| doo_error(&args.mesh, e))?)
    } else {
        None
    };
    let bytes = pyramid.to_bytes().map_err(|e| doo_error(&args.out, e))?;
    std::fs::write(&args.out, &bytes).map_err(|source| CliError::Io { path: args.out.clone(), source })?;
    let mut text = format!(
        "decomposed {} Doo-Sabin level(s): base {} vertices, {} faces; {} details ({} + {} = {} 3-vectors, the input has {} vertices); {} bytes\n",
        pyramid.level_count(),
        pyramid.base.vertex_count(),
        pyramid.base.face_count(),
        pyramid.detail_count(),
        pyramid.base.vertex_count(),
        pyramid.detail_count(),
        pyramid.base.vertex_count() + pyramid.detail_count(),
        mesh.vertex_count(),
        bytes.len()
    );
    if args.max
        && let Some(why) = &decomposition.stopped
    {
        let _ = writeln!(text, "stopped: {why}");
    }
    for (k, choices) in decomposition.choices.iter().enumerate() {
        text.push_str(&choice_lines(k + 1, choices));
    }
    if let Some(rows) = report {
        text.push_str("keep fraction  details kept  max error / diag  rms error / diag\n");
        for row in rows {
            let _ = writeln!(
                text,
                "{:>13}  {:>12}  {:>16.3e}  {:>16.3e}",
                row.fraction, row.kept, row.max_error, row.rms_error
            );
        }
    }
    print!("{text}");
    Ok(())
}

/// `reconstruct` of a Doo-Sabin pyramid.
pub fn reconstruct(args: &ReconstructArgs, bytes: &[u8]) -> CliResult {
    let pyramid = DooPyramid::from_bytes(bytes).map_err(|e| doo_error(&args.input, e))?;
    let level = args.level.map_or(pyramid.level_count(), |l| l as usize);
    if level > pyramid.level_count() {
        return Err(CliError::Input(format!(
            "--level {level}: the pyramid has levels 0 (base) to {}",
            pyramid.level_count()
        )));
    }
    if let Some(keep) = args.keep
        && !(0.0..=1.0).contains(&keep)
    {
        return Err(CliError::Input(format!("--keep {keep}: give a fraction between 0 and 1")));
    }
    let soup = pyramid.reconstruct(level, args.keep).map_err(|e| doo_error(&args.input, e))?;
    write_soup(&args.out, &soup, &WriteOptions::default())?;
    println!(
        "reconstructed level {level} of {} ({}, {} boundary): {} vertices, {} faces{}",
        pyramid.level_count(),
        pyramid.rule.name(),
        pyramid.boundary,
        soup.vertex_count(),
        soup.face_count(),
        args.keep.map_or(String::new(), |fraction| {
            let total = pyramid.detail_count();
            super::kept_details(subdiv_doo::pyramid::kept_count(fraction, total), total, fraction)
        })
    );
    Ok(())
}

/// `analyze --scheme doo-sabin | doo-simple | doo-centroid --valence N` (`N` = the face
/// size: after one step the extraordinary elements of Doo-Sabin are the faces).
pub fn analyze(args: &AnalyzeArgs) -> CliResult {
    let rule = match args.scheme {
        AnalyzeScheme::DooSabin => FaceRule::DooSabin,
        AnalyzeScheme::DooSimple => FaceRule::Simple,
        AnalyzeScheme::DooCentroid => FaceRule::CENTROID_HALF,
        other => return Err(CliError::Input(format!("{other:?} is not a Doo-Sabin scheme"))),
    };
    if args.curve.any_given() {
        return Err(CliError::Input("--omega1, --omega2, --gamma and --tension apply to curve schemes only".into()));
    }
    let valence = args.valence.ok_or_else(|| {
        CliError::Input(format!("analyze --scheme {}: give --valence N (the face size)", rule.name()))
    })?;
    let report =
        reif_check(rule, valence as usize).map_err(|e| input_error(format!("analyze --scheme {}", rule.name()), e))?;
    if args.json {
        let mut value = serde_json::to_value(&report).unwrap_or_default();
        value["scheme"] = serde_json::json!(rule.name());
        value["matrix"] = serde_json::json!("local subdivision matrix around an n-gon (4n points)");
        println!("{value}");
    } else {
        print!("{}", analysis_text(&report));
    }
    Ok(())
}

/// The analysis as a short report.
fn analysis_text(a: &ReifReport) -> String {
    let yes = |b: bool| if b { "yes" } else { "NO" };
    let mut out = String::new();
    let n = a.valence;
    let _ = writeln!(
        out,
        "scheme {}, face size {n}: local subdivision matrix around the {n}-gon, {} x {}",
        a.rule.name(),
        4 * n,
        4 * n
    );
    let eigenvalues: Vec<String> = a.eigenvalues.iter().map(|x| format!("{x:.9}")).collect();
    let _ = writeln!(out, "eigenvalues (decreasing modulus): {}", eigenvalues.join(", "));
    let _ = writeln!(
        out,
        "subdominant {:.12} (algebraic multiplicity {}, geometric {}); gap to the next modulus {:.12}",
        a.subdominant, a.subdominant_multiplicity, a.geometric_multiplicity, a.gap
    );
    let _ = writeln!(
        out,
        "Reif: l0 = 1 simple: {}; l1 = l2 real in (0, 1), double, with a gap: {}",
        yes(a.dominant_simple),
        yes(a.subdominant_ok)
    );
    match &a.characteristic_map {
        Some(m) => {
            let _ = writeln!(
                out,
                "characteristic map ({} steps): {} faces, min/max signed area {:.3e}, winding {}; regular and injective: {}",
                m.steps,
                m.faces,
                m.min_area_ratio,
                m.winding,
                yes(m.ok)
            );
        }
        None => {
            let _ = writeln!(out, "characteristic map: not checked (eigenvalue conditions fail)");
        }
    }
    for note in &a.notes {
        let _ = writeln!(out, "note: {note}");
    }
    let _ = writeln!(out, "C1: {}", yes(a.c1));
    out
}

/// True if `bytes` is a Doo-Sabin `.mres` pyramid.
pub fn is_doo_pyramid(bytes: &[u8]) -> bool {
    subdiv_doo::is_doo_pyramid(bytes)
}
