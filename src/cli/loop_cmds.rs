//! Loop-family commands: subdivide, reverse, decompose, reconstruct, analyze.

use super::{AnalyzeArgs, CliError, CliResult, DecomposeArgs, ReconstructArgs, ReverseArgs, SubdivideArgs};

/// `subdivide --scheme loop | loop-warren | ternary-loop | quaternary-loop`.
pub fn subdivide(_args: &SubdivideArgs) -> CliResult {
    Err(CliError::Unavailable("Loop subdivision"))
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

/// `analyze --scheme loop | loop-warren | ternary-loop | quaternary-loop`.
pub fn analyze(_args: &AnalyzeArgs) -> CliResult {
    Err(CliError::Unavailable("Loop analysis"))
}
