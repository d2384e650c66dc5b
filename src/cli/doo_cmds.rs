//! Doo-Sabin-family commands: subdivide, reverse, decompose, reconstruct, analyze.

use super::{AnalyzeArgs, CliError, CliResult, DecomposeArgs, ReconstructArgs, ReverseArgs, SubdivideArgs};

/// `subdivide --scheme doo-sabin | doo-simple | doo-centroid`.
pub fn subdivide(_args: &SubdivideArgs) -> CliResult {
    Err(CliError::Unavailable("Doo-Sabin subdivision"))
}

/// `reverse --scheme doo`.
pub fn reverse(_args: &ReverseArgs) -> CliResult {
    Err(CliError::Unavailable("reverse Doo-Sabin"))
}

/// `decompose --scheme doo`.
pub fn decompose(_args: &DecomposeArgs) -> CliResult {
    Err(CliError::Unavailable("Doo-Sabin decomposition"))
}

/// `reconstruct` of a Doo-Sabin pyramid.
pub fn reconstruct(_args: &ReconstructArgs, _bytes: &[u8]) -> CliResult {
    Err(CliError::Unavailable("Doo-Sabin reconstruction"))
}

/// `analyze --scheme doo-sabin | doo-simple | doo-centroid`.
pub fn analyze(_args: &AnalyzeArgs) -> CliResult {
    Err(CliError::Unavailable("Doo-Sabin analysis"))
}

/// True if `bytes` is a Doo-Sabin `.mres` pyramid.
pub fn is_doo_pyramid(_bytes: &[u8]) -> bool {
    false
}
