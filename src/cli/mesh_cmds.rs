//! Commands on plain meshes: `info`, `compare`, `convert`, `render`, and the demo.

use std::path::PathBuf;

use clap::Args;

use super::{CliError, CliResult};

/// Options of `info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The mesh (OBJ, OFF or PLY).
    pub mesh: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Options of `compare`.
#[derive(Debug, Args)]
pub struct CompareArgs {
    /// First mesh (the reference for relative distances).
    pub a: PathBuf,
    /// Second mesh.
    pub b: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Options of `convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// Input mesh.
    pub input: PathBuf,
    /// Output mesh; the format follows the extension.
    pub out: PathBuf,
}

/// Options of `render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// The mesh.
    pub mesh: PathBuf,
    /// Output PNG.
    pub out: PathBuf,
    /// Image size as WxH.
    #[arg(long, default_value = "800x600")]
    pub size: String,
    /// Overlay the wireframe.
    #[arg(long)]
    pub wireframe: bool,
    /// View direction as azimuth,elevation in degrees.
    #[arg(long, default_value = "30,20", allow_hyphen_values = true)]
    pub view: String,
    /// Further meshes rendered side by side with the first.
    #[arg(long, num_args = 1..)]
    pub side_by_side: Vec<PathBuf>,
}

/// Options of `demo`.
#[derive(Debug, Args, Default)]
pub struct DemoArgs {
    /// Output directory.
    #[arg(long, default_value = "multires-out")]
    pub out: PathBuf,
}

/// `multires info`.
pub fn info(_args: &InfoArgs) -> CliResult {
    Err(CliError::Unavailable("info"))
}

/// `multires compare`.
pub fn compare(_args: &CompareArgs) -> CliResult {
    Err(CliError::Unavailable("compare"))
}

/// `multires convert`.
pub fn convert(_args: &ConvertArgs) -> CliResult {
    Err(CliError::Unavailable("convert"))
}

/// `multires render`.
pub fn render(_args: &RenderArgs) -> CliResult {
    Err(CliError::Unavailable("render"))
}

/// `multires demo` and `multires` without arguments.
pub fn demo(_args: &DemoArgs) -> CliResult {
    Err(CliError::Unavailable("the demo"))
}
