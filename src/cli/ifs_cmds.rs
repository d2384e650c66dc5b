//! Iterated function systems: `ifs`.

use std::path::PathBuf;

use clap::Args;

use super::{CliError, CliResult};

/// Options of `ifs`.
#[derive(Debug, Args)]
pub struct IfsArgs {
    /// Kind: bezier, patch, complex, nonlinear or sierpinski.
    #[arg(long, default_value = "bezier")]
    pub kind: String,
    /// A named example from the literature (e.g. gaussian, complex-spiral).
    #[arg(long)]
    pub preset: Option<String>,
    /// Control points as "x,y x,y ...".
    #[arg(long)]
    pub control: Option<String>,
    /// Complex parameter as re,im.
    #[arg(long, allow_hyphen_values = true)]
    pub z: Option<String>,
    /// Output PNG.
    #[arg(long)]
    pub out: PathBuf,
    /// Also write the attractor points, one `x y` per line.
    #[arg(long)]
    pub out_points: Option<PathBuf>,
    /// Image size as WxH.
    #[arg(long, default_value = "800x800")]
    pub size: String,
    /// Deterministic algorithm with this many levels.
    #[arg(long, conflicts_with = "points")]
    pub levels: Option<u32>,
    /// Chaos game with this many points.
    #[arg(long)]
    pub points: Option<u64>,
    /// Seed of the chaos game.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// `multires ifs`.
pub fn ifs(_args: &IfsArgs) -> CliResult {
    Err(CliError::Unavailable("IFS rendering"))
}
