//! Loop-family commands: subdivide, reverse, decompose, reconstruct, analyze.

use super::{AnalyzeArgs, CliError, CliResult, DecomposeArgs, ReconstructArgs, ReverseArgs, SubdivideArgs};

/// `subdivide --scheme loop | loop-warren | ternary-loop | quaternary-loop`.
pub fn subdivide(args: &SubdivideArgs) -> CliResult {
    use subdiv_loop::forward::{self, LoopOptions, VertexWeights};
    use subdiv_loop::mband::{self, TernaryOptions};

    use super::SurfaceScheme;

    let (soup, report) = super::common::read_soup(&args.mesh)?;
    super::common::note_dropped(&args.mesh, &report);
    if let Some(face) = soup.faces().position(|f| f.len() != 3) {
        return Err(CliError::Input(format!(
            "{}: face {face} has {} corners; Loop schemes need triangles",
            args.mesh.display(),
            soup.face(face).len()
        )));
    }
    let mesh = super::common::build_mesh(&args.mesh, &soup)?;
    drop(soup);
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
    super::common::write_soup(&args.out, &fine.into_soup(), &mesh_topo::io::WriteOptions::default())
}

/// `reverse --scheme loop`.
pub fn reverse(_args: &ReverseArgs) -> CliResult {
    Err(CliError::Unavailable("reverse Loop"))
}

/// `decompose --scheme loop`.
pub fn decompose(_args: &DecomposeArgs) -> CliResult {
    Err(CliError::Unavailable("Loop decomposition"))
}

/// `reconstruct` of a Loop pyramid.
pub fn reconstruct(_args: &ReconstructArgs, _bytes: &[u8]) -> CliResult {
    Err(CliError::Unavailable("Loop reconstruction"))
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
    if args.omega1.is_some() || args.omega2.is_some() || args.gamma.is_some() || args.tension.is_some() {
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
