//! Triangular spline fitting: `fit`.

use std::path::PathBuf;

use clap::Args;

use super::{CliError, CliResult};

/// Options of `fit`.
#[derive(Debug, Args)]
pub struct FitArgs {
    /// The triangle mesh to fit (disk topology).
    pub mesh: PathBuf,
    /// Surface kind: bezier, bpatch or tri-bspline.
    #[arg(long, default_value = "bezier")]
    pub surface: String,
    /// Iteration: lspia (default), pia or seed.
    #[arg(long, default_value = "lspia")]
    pub method: String,
    /// Number of reverse-Loop levels that give the control net.
    #[arg(long, default_value_t = 2)]
    pub reverse_levels: u32,
    /// Maximum number of iterations.
    #[arg(long, default_value_t = 10)]
    pub iterations: u32,
    /// Stop when the mean error falls below this.
    #[arg(long)]
    pub tolerance: Option<f64>,
    /// A data point counts as hit when its error is at most this.
    #[arg(long)]
    pub hit_tol: Option<f64>,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Plot the convergence to this PNG.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Write a triangulated sampling of the fitted surface.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Samples per domain edge for `--out`.
    #[arg(long, default_value_t = 32)]
    pub samples: u32,
}

/// `multires fit`.
pub fn fit(_args: &FitArgs) -> CliResult {
    Err(CliError::Unavailable("spline fitting"))
}
