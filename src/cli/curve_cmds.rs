//! Curve commands: `curve` and `analyze` for curve schemes.

use std::path::PathBuf;

use clap::Args;

use super::{AnalyzeArgs, CliError, CliResult};

/// Options of `curve`.
#[derive(Debug, Args)]
pub struct CurveArgs {
    /// Input points: one `x y` or `x y z` per line, `#` comments.
    pub input: PathBuf,
    /// Output SVG.
    pub out: PathBuf,
    /// The curve scheme (chaikin, cubic-bspline, four-point, combined).
    #[arg(long)]
    pub scheme: String,
    /// Number of subdivision steps.
    #[arg(long, default_value_t = 5)]
    pub levels: u32,
    /// Treat the polygon as closed.
    #[arg(long)]
    pub closed: bool,
    /// Choose the points to interpolate from discrete curvature.
    #[arg(long, conflicts_with = "interpolate")]
    pub auto_interpolate: bool,
    /// Indices of the points to interpolate, comma-separated.
    #[arg(long, value_delimiter = ',')]
    pub interpolate: Vec<usize>,
    /// Also write the refined points to this file.
    #[arg(long)]
    pub out_points: Option<PathBuf>,
}

/// `multires curve`.
pub fn curve(_args: &CurveArgs) -> CliResult {
    Err(CliError::Unavailable("curve subdivision"))
}

/// `analyze` for curve schemes.
pub fn analyze(_args: &AnalyzeArgs) -> CliResult {
    Err(CliError::Unavailable("curve analysis"))
}
