//! Command-line front end: argument definitions and dispatch.
//!
//! Each member crate's commands live in their own file (`mesh_cmds`, `loop_cmds`,
//! `doo_cmds`, `curve_cmds`, `spline_cmds`, `ifs_cmds`); commands that span several
//! crates (`subdivide`, `reverse`, `decompose`, `reconstruct`, `analyze`) are dispatched
//! here by scheme. Every command reads and writes meshes through `common`.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

mod common;
mod curve_cmds;
mod demo;
mod doo_cmds;
mod ifs_cmds;
mod loop_cmds;
mod mesh_cmds;
pub mod render;
mod spline_cmds;

/// Errors of the command-line tool: one line for the user, no backtrace.
#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
    /// The input was rejected (bad mesh, bad parameters, ...), with the reason.
    #[error("{0}")]
    Input(String),
}

/// Parameters of the curve schemes, shared by `curve` and `analyze`.
#[derive(Debug, Clone, Copy, Default, Args)]
pub struct CurveParameters {
    /// Tension w of the four-point scheme (default 1/16).
    #[arg(long, allow_hyphen_values = true)]
    pub tension: Option<f64>,
    /// Parameter omega1 of the combined scheme (interpolated pairs; default -1/16).
    #[arg(long, allow_hyphen_values = true)]
    pub omega1: Option<f64>,
    /// Parameter omega2 of the combined scheme (approximated pairs; default 0).
    #[arg(long, allow_hyphen_values = true)]
    pub omega2: Option<f64>,
    /// Parameter gamma of the combined scheme (vertex displacement; default 1/8).
    #[arg(long, allow_hyphen_values = true)]
    pub gamma: Option<f64>,
}

impl CurveParameters {
    /// True if any parameter of the combined scheme was given.
    pub fn framework_given(&self) -> bool {
        self.omega1.is_some() || self.omega2.is_some() || self.gamma.is_some()
    }

    /// True if any curve parameter was given.
    pub fn any_given(&self) -> bool {
        self.framework_given() || self.tension.is_some()
    }
}

/// Result type of the CLI.
pub type CliResult<T = ()> = Result<T, CliError>;

/// Turns any displayable error into a user-facing input error, prefixed with context.
pub fn input_error(context: impl std::fmt::Display, error: impl std::fmt::Display) -> CliError {
    CliError::Input(format!("{context}: {error}"))
}

/// Subdivision-based geometry: subdivide, reverse, decompose and reconstruct meshes and
/// curves, fit triangular splines, render fractals. Without a command, runs the demo.
#[derive(Debug, Parser)]
#[command(name = "multires", version, about, long_about = None)]
pub struct Cli {
    /// What to do (default: the demo).
    #[command(subcommand)]
    pub command: Option<Command>,
}

/// The commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Print counts, histograms, boundary loops, components, Euler characteristic, genus
    /// and manifold status of a mesh, or what a `.mres` pyramid holds level by level.
    Info(mesh_cmds::InfoArgs),
    /// Compare two meshes: counts and symmetric nearest-vertex distances.
    Compare(mesh_cmds::CompareArgs),
    /// Convert between OBJ, OFF and PLY, losslessly (vertex and face order kept).
    Convert(mesh_cmds::ConvertArgs),
    /// Subdivide a mesh with one of the surface schemes.
    Subdivide(SubdivideArgs),
    /// Reverse subdivision: compute the coarser mesh(es) of a mesh with subdivision connectivity.
    Reverse(ReverseArgs),
    /// Decompose a mesh into a base mesh plus per-level details (a `.mres` pyramid).
    Decompose(DecomposeArgs),
    /// Rebuild a mesh from a `.mres` pyramid, optionally keeping only the largest details.
    Reconstruct(ReconstructArgs),
    /// Spectral analysis of a scheme's local subdivision matrix (smoothness checks).
    Analyze(AnalyzeArgs),
    /// Subdivide a curve (a polygon from a text file) and draw it as SVG.
    Curve(curve_cmds::CurveArgs),
    /// Fit a triangular Bézier / B-patch / triangular B-spline surface to a triangle mesh.
    Fit(spline_cmds::FitArgs),
    /// Render the attractor of an iterated function system (subdivision as IFS).
    Ifs(ifs_cmds::IfsArgs),
    /// Render a mesh to PNG with a small software rasterizer.
    Render(mesh_cmds::RenderArgs),
    /// Run the demo into a directory.
    Demo(demo::DemoArgs),
}

/// Surface subdivision schemes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum SurfaceScheme {
    /// Loop subdivision with Loop's original vertex weights.
    Loop,
    /// Loop subdivision with Warren's simplified weights.
    LoopWarren,
    /// Ternary (1-to-9) Loop subdivision.
    TernaryLoop,
    /// Quaternary (1-to-16) Loop subdivision.
    QuaternaryLoop,
    /// Doo-Sabin subdivision with the original weights.
    DooSabin,
    /// Doo-Sabin with the simple averaging rule.
    DooSimple,
    /// Doo-Sabin topology with the centroid-contraction rule (not C1 on faces with 4+ sides).
    DooCentroid,
}

impl SurfaceScheme {
    /// True for the Doo-Sabin schemes.
    pub fn is_doo(self) -> bool {
        matches!(self, Self::DooSabin | Self::DooSimple | Self::DooCentroid)
    }

    /// The library's name of this scheme.
    pub fn library(self) -> multires::SurfaceScheme {
        match self {
            Self::Loop => multires::SurfaceScheme::Loop,
            Self::LoopWarren => multires::SurfaceScheme::LoopWarren,
            Self::TernaryLoop => multires::SurfaceScheme::TernaryLoop,
            Self::QuaternaryLoop => multires::SurfaceScheme::QuaternaryLoop,
            Self::DooSabin => multires::SurfaceScheme::DooSabin,
            Self::DooSimple => multires::SurfaceScheme::DooSimple,
            Self::DooCentroid => multires::SurfaceScheme::DooCentroid,
        }
    }

    /// The `--scheme` word of this scheme.
    pub fn word(self) -> String {
        self.to_possible_value().map_or_else(|| format!("{self:?}"), |value| value.get_name().to_owned())
    }
}

/// Refuses `levels` steps of `scheme` on `input` (of `counts`) when the output alone would
/// need more memory than the system has available now (see `multires::memory`), naming
/// the levels that fit.
fn check_output_fits(
    input: &std::path::Path,
    scheme: SurfaceScheme,
    counts: multires::ElementCounts,
    levels: u32,
) -> CliResult {
    scheme
        .library()
        .check_available_memory(counts, levels)
        .map_err(|refused| CliError::Input(format!("{}: {refused}", input.display())))
}

/// Options of `subdivide`.
#[derive(Debug, Args)]
pub struct SubdivideArgs {
    /// Input mesh (OBJ, OFF or PLY).
    pub mesh: PathBuf,
    /// Output mesh (OBJ, OFF or PLY).
    pub out: PathBuf,
    /// The scheme.
    #[arg(long, value_enum)]
    pub scheme: SurfaceScheme,
    /// Number of subdivision steps.
    #[arg(long, default_value_t = 1)]
    pub levels: u32,
    /// Keep boundary corners (valence-2 boundary vertices) fixed (Loop schemes).
    #[arg(long)]
    pub keep_corners: bool,
    /// What the Doo-Sabin step does at the boundary: `shrink` (no faces there, the
    /// default) or `chaikin` (boundary quads and vertex faces through the Chaikin points:
    /// the boundary converges to the quadratic B-spline of the boundary polygon).
    #[arg(long, value_enum)]
    pub boundary: Option<BoundaryArg>,
}

/// Boundary rules of the Doo-Sabin schemes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum BoundaryArg {
    /// No faces at boundary edges and vertices (the mesh shrinks level by level).
    Shrink,
    /// Boundary quads and vertex faces through the Chaikin points of the boundary edges.
    Chaikin,
}

/// Reversible schemes: the family, and the rule the mesh is assumed to come from (the
/// names of `subdivide --scheme`; `reverse(subdivide(C))` is `C` with zero details when
/// the two name the same rule).
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ReverseScheme {
    /// Reverse Loop subdivision with Loop's original vertex weights.
    Loop,
    /// Reverse Loop subdivision with Warren's simplified weights.
    LoopWarren,
    /// Reverse Doo-Sabin subdivision with the original weights (the same as `doo-sabin`).
    Doo,
    /// Reverse Doo-Sabin subdivision with the original weights.
    DooSabin,
    /// Reverse Doo-Sabin with the simple averaging rule.
    DooSimple,
    /// Reverse Doo-Sabin topology with the centroid-contraction rule (a = 1/2).
    DooCentroid,
}

impl ReverseScheme {
    /// True for the Loop schemes.
    pub fn is_loop(self) -> bool {
        matches!(self, Self::Loop | Self::LoopWarren)
    }
}

/// What `reverse` and `decompose` are told of how the fine mesh was made: the seeds of
/// its first (finest) level and the rules it was subdivided with.
#[derive(Debug, Args)]
pub struct ReadingArgs {
    /// Faces known to come from coarse faces (Doo-Sabin): at most one per connected
    /// component, repeated or separated by commas; the seeds of the other components are
    /// found automatically. They seed the first (finest) level only.
    #[arg(long, value_delimiter = ',')]
    pub seed_face: Vec<u32>,
    /// Vertices known to come from coarse vertices (Loop schemes): one per connected
    /// component at most, repeated or separated by commas; the labeling of each one's
    /// component starts from it, for the first level. Needed only to pick one of the
    /// readings of a component whose valences are all regular: without a seed, each such
    /// component gets the reading with the smallest details.
    #[arg(long, value_delimiter = ',')]
    pub seed_vertex: Vec<u32>,
    /// The mesh was subdivided with boundary corners (valence-2 boundary vertices) kept
    /// fixed (Loop schemes).
    #[arg(long)]
    pub keep_corners: bool,
    /// The boundary rule the mesh was subdivided with (Doo-Sabin): `shrink` (no faces at
    /// the boundary, the default) or `chaikin` (boundary quads and vertex faces through
    /// the Chaikin points: the boundary converges to the quadratic B-spline of the
    /// boundary polygon).
    #[arg(long, value_enum)]
    pub boundary: Option<BoundaryArg>,
}

/// Options of `reverse`.
#[derive(Debug, Args)]
pub struct ReverseArgs {
    /// Input mesh with subdivision connectivity.
    pub mesh: PathBuf,
    /// Output (coarse) mesh.
    pub out: PathBuf,
    /// The scheme to reverse.
    #[arg(long, value_enum)]
    pub scheme: ReverseScheme,
    /// Number of levels to reverse.
    #[arg(long, default_value_t = 1)]
    pub levels: u32,
    /// How the fine mesh was made.
    #[command(flatten)]
    pub reading: ReadingArgs,
}

/// Options of `decompose`.
#[derive(Debug, Args)]
pub struct DecomposeArgs {
    /// Input mesh with subdivision connectivity.
    pub mesh: PathBuf,
    /// Output pyramid (`.mres`).
    pub out: PathBuf,
    /// The scheme to reverse.
    #[arg(long, value_enum)]
    pub scheme: ReverseScheme,
    /// Number of levels to decompose.
    #[arg(long, default_value_t = 1, conflicts_with = "max")]
    pub levels: u32,
    /// Decompose as many levels as the connectivity allows.
    #[arg(long)]
    pub max: bool,
    /// Print a rate-distortion table (fraction of details kept vs error).
    #[arg(long)]
    pub report: bool,
    /// How the fine mesh was made.
    #[command(flatten)]
    pub reading: ReadingArgs,
}

/// Options of `reconstruct`.
#[derive(Debug, Args)]
pub struct ReconstructArgs {
    /// Input pyramid (`.mres`).
    pub input: PathBuf,
    /// Output mesh.
    pub out: PathBuf,
    /// Level to rebuild (0 = base mesh; default: the finest).
    // (A negative value is read as a value, so that the error says what is wrong with it.)
    #[arg(long, allow_hyphen_values = true)]
    pub level: Option<u32>,
    /// Keep only this fraction of the details, the largest ones (compression).
    #[arg(long, allow_hyphen_values = true)]
    pub keep: Option<f64>,
}

/// Schemes that `analyze` knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum AnalyzeScheme {
    /// Loop, original weights.
    Loop,
    /// Loop, Warren's weights.
    LoopWarren,
    /// Ternary Loop.
    TernaryLoop,
    /// Quaternary Loop.
    QuaternaryLoop,
    /// Doo-Sabin, original weights.
    DooSabin,
    /// Doo-Sabin, simple averaging rule.
    DooSimple,
    /// Doo-Sabin topology, centroid contraction.
    DooCentroid,
    /// Dyn-Levin-Gregory four-point curve scheme.
    FourPoint,
    /// Cubic B-spline curve scheme.
    CubicBspline,
    /// Chaikin corner cutting.
    Chaikin,
    /// The two-parameter interpolatory/approximating curve framework.
    Combined,
}

/// Options of `analyze`.
#[derive(Debug, Args)]
pub struct AnalyzeArgs {
    /// The scheme.
    #[arg(long, value_enum)]
    pub scheme: AnalyzeScheme,
    /// Valence of the extraordinary vertex (or face size for Doo-Sabin); surfaces only.
    #[arg(long)]
    pub valence: Option<u32>,
    /// Curve-scheme parameters (curves only).
    #[command(flatten)]
    pub curve: CurveParameters,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs one command (the demo when none is given).
pub fn run(cli: Cli) -> CliResult {
    match cli.command {
        None => demo::demo(&demo::DemoArgs::default()),
        Some(Command::Info(args)) => mesh_cmds::info(&args),
        Some(Command::Compare(args)) => mesh_cmds::compare(&args),
        Some(Command::Convert(args)) => mesh_cmds::convert(&args),
        Some(Command::Render(args)) => mesh_cmds::render(&args),
        Some(Command::Demo(args)) => demo::demo(&args),
        Some(Command::Subdivide(args)) if args.boundary.is_some() && !args.scheme.is_doo() => {
            Err(CliError::Input("--boundary applies to the Doo-Sabin schemes only".into()))
        }
        Some(Command::Reverse(args)) if args.reading.boundary.is_some() && args.scheme.is_loop() => {
            Err(CliError::Input("--boundary applies to the Doo-Sabin schemes only".into()))
        }
        Some(Command::Decompose(args)) if args.reading.boundary.is_some() && args.scheme.is_loop() => {
            Err(CliError::Input("--boundary applies to the Doo-Sabin schemes only".into()))
        }
        Some(Command::Subdivide(args)) => match args.scheme {
            SurfaceScheme::Loop
            | SurfaceScheme::LoopWarren
            | SurfaceScheme::TernaryLoop
            | SurfaceScheme::QuaternaryLoop => loop_cmds::subdivide(&args),
            SurfaceScheme::DooSabin | SurfaceScheme::DooSimple | SurfaceScheme::DooCentroid => {
                doo_cmds::subdivide(&args)
            }
        },
        Some(Command::Reverse(args)) => {
            if args.scheme.is_loop() {
                loop_cmds::reverse(&args)
            } else {
                doo_cmds::reverse(&args)
            }
        }
        Some(Command::Decompose(args)) => {
            if args.scheme.is_loop() {
                loop_cmds::decompose(&args)
            } else {
                doo_cmds::decompose(&args)
            }
        }
        Some(Command::Reconstruct(args)) => reconstruct(&args),
        Some(Command::Analyze(args)) => match args.scheme {
            AnalyzeScheme::Loop
            | AnalyzeScheme::LoopWarren
            | AnalyzeScheme::TernaryLoop
            | AnalyzeScheme::QuaternaryLoop => loop_cmds::analyze(&args),
            AnalyzeScheme::DooSabin | AnalyzeScheme::DooSimple | AnalyzeScheme::DooCentroid => doo_cmds::analyze(&args),
            AnalyzeScheme::FourPoint
            | AnalyzeScheme::CubicBspline
            | AnalyzeScheme::Chaikin
            | AnalyzeScheme::Combined => curve_cmds::analyze(&args),
        },
        Some(Command::Curve(args)) => curve_cmds::curve(&args),
        Some(Command::Fit(args)) => spline_cmds::fit(&args),
        Some(Command::Ifs(args)) => ifs_cmds::ifs(&args),
    }
}

/// What `reconstruct --keep FRACTION` reports it kept: the count, and the fraction
/// asked for (`{:?}`, which writes a tiny or huge number with an exponent).
fn kept_details(kept: usize, total: usize, fraction: f64) -> String {
    format!(" (keeping the largest {kept} of {total} details: --keep {fraction:?})")
}

/// `.mres` files say which scheme wrote them; dispatch on that.
fn reconstruct(args: &ReconstructArgs) -> CliResult {
    let bytes = common::read_file(&args.input)?;
    if doo_cmds::is_doo_pyramid(&bytes) {
        doo_cmds::reconstruct(args, &bytes)
    } else {
        loop_cmds::reconstruct(args, &bytes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_scheme_of_the_command_line_is_the_library_scheme_of_its_name() {
        for scheme in SurfaceScheme::value_variants() {
            assert_eq!(scheme.word(), scheme.library().name());
        }
    }
}
