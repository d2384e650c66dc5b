//! Loop-family commands: subdivide, reverse, decompose, reconstruct, analyze.

use std::path::Path;

use mesh_topo::io::WriteOptions;
use subdiv_loop::LoopError;
use subdiv_loop::forward::LoopOptions;
use subdiv_loop::pyramid::{self, DecomposeOptions, Levels, LoopPyramid};

use super::common::{read_mesh, write_soup};
use super::{
    AnalyzeArgs, CliError, CliResult, DecomposeArgs, ReconstructArgs, ReverseArgs, SubdivideArgs, input_error,
};

/// `subdivide --scheme loop | loop-warren | ternary-loop | quaternary-loop`.
pub fn subdivide(_args: &SubdivideArgs) -> CliResult {
    Err(CliError::Unavailable("Loop subdivision"))
}

/// Loop's original weights, boundary corners smoothed: the defaults of `subdivide --scheme loop`.
fn reverse_rules() -> LoopOptions {
    LoopOptions::default()
}

fn loop_error(path: &Path, error: LoopError) -> CliError {
    input_error(path.display(), error)
}

fn no_seed_face(args_seed_face: Option<u32>) -> CliResult {
    match args_seed_face {
        Some(_) => Err(CliError::Input(
            "--seed-face applies to --scheme doo; Loop connectivity is detected from the mesh alone".into(),
        )),
        None => Ok(()),
    }
}

/// `reverse --scheme loop`: the coarse mesh after `--levels` reverse Loop steps (the
/// details are dropped; `decompose` keeps them).
pub fn reverse(args: &ReverseArgs) -> CliResult {
    no_seed_face(args.seed_face)?;
    if args.levels == 0 {
        return Err(CliError::Input("--levels must be at least 1".into()));
    }
    let mesh = read_mesh(&args.mesh)?;
    let options =
        DecomposeOptions { rules: reverse_rules(), levels: Levels::Count(args.levels as usize), seed_vertex: None };
    let pyramid = pyramid::decompose(&mesh, &options).map_err(|e| loop_error(&args.mesh, e))?;
    write_soup(&args.out, &pyramid.base, &WriteOptions::default())?;
    println!(
        "reversed {} Loop level(s): {} vertices, {} faces -> {} vertices, {} faces",
        pyramid.level_count(),
        mesh.vertex_count(),
        mesh.face_count(),
        pyramid.base.vertex_count(),
        pyramid.base.face_count()
    );
    Ok(())
}

/// Fractions of the rate-distortion table printed by `decompose --report`.
const REPORT_FRACTIONS: [f64; 9] = [1.0, 0.5, 0.25, 0.1, 0.05, 0.02, 0.01, 0.005, 0.0];

/// `decompose --scheme loop`: base mesh plus the details of every level, as a `.mres` file.
pub fn decompose(args: &DecomposeArgs) -> CliResult {
    if !args.max && args.levels == 0 {
        return Err(CliError::Input("--levels must be at least 1".into()));
    }
    let mesh = read_mesh(&args.mesh)?;
    let levels = if args.max { Levels::Max } else { Levels::Count(args.levels as usize) };
    let options = DecomposeOptions { rules: reverse_rules(), levels, seed_vertex: None };
    let pyramid = pyramid::decompose(&mesh, &options).map_err(|e| loop_error(&args.mesh, e))?;
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
        args.keep.map_or(String::new(), |f| format!(" (keeping the largest {f} of the details)"))
    );
    Ok(())
}

/// `analyze --scheme loop | loop-warren | ternary-loop | quaternary-loop`.
pub fn analyze(_args: &AnalyzeArgs) -> CliResult {
    Err(CliError::Unavailable("Loop analysis"))
}
