//! Mesh files for every command: reading (with a note for what the file held that is
//! not kept), building, writing. Errors name the file and, for content errors, the line.

use std::io::Write;
use std::path::{Path, PathBuf};

use mesh_topo::io::{self, IoError, ReadReport, WriteOptions};
use mesh_topo::{HalfedgeMesh, MeshError, PolygonSoup};

use super::{CliError, CliResult};

/// A library I/O error as a one-line CLI error naming the file.
pub fn io_error(path: &Path, error: IoError) -> CliError {
    match error {
        IoError::File { path, source } => CliError::Io { path, source },
        // Its message names the file already.
        unknown @ IoError::UnknownExtension { .. } => CliError::Input(unknown.to_string()),
        other => CliError::Input(format!("{}: {other}", path.display())),
    }
}

/// Reads a whole file (a `.mres` pyramid, say); an error names the file.
pub fn read_file(path: &Path) -> CliResult<Vec<u8>> {
    std::fs::read(path).map_err(|source| CliError::Io { path: path.to_path_buf(), source })
}

/// Reads a mesh file as a polygon soup (format from the extension), with the reader's
/// report of what it did not keep.
pub fn read_soup(path: &Path) -> CliResult<(PolygonSoup, ReadReport)> {
    io::read_soup(path).map_err(|e| io_error(path, e))
}

/// Prints one note per attribute the file held that the mesh does not keep.
pub fn note_dropped(path: &Path, report: &ReadReport) {
    for dropped in &report.dropped {
        eprintln!("multires: note: {}: not kept: {dropped}", path.display());
    }
}

/// Reads a mesh file as a polygon soup and decomposes it with `decompose`, which starts
/// from the face list (a file in a scheme's canonical order is reversed without building
/// its half-edge mesh); the soup read and the result. `mesh_error` picks out the error
/// of a soup that is not a valid mesh, reported as the other commands report it; any
/// other error names the file.
pub fn decompose_file<T, E: std::fmt::Display>(
    path: &Path,
    decompose: impl FnOnce(&PolygonSoup) -> Result<T, E>,
    mesh_error: impl FnOnce(E) -> Result<MeshError, E>,
) -> CliResult<(PolygonSoup, T)> {
    let (soup, report) = read_soup(path)?;
    note_dropped(path, &report);
    match decompose(&soup).map_err(mesh_error) {
        Ok(result) => Ok((soup, result)),
        Err(Ok(error)) => Err(invalid_mesh(path, error)),
        Err(Err(error)) => Err(super::input_error(path.display(), error)),
    }
}

/// Builds the half-edge mesh of a soup read from `path`.
pub fn build_mesh(path: &Path, soup: &PolygonSoup) -> CliResult<HalfedgeMesh> {
    HalfedgeMesh::from_soup(soup).map_err(|e| invalid_mesh(path, e))
}

/// The error of a mesh file whose soup is not a valid mesh.
pub fn invalid_mesh(path: &Path, error: MeshError) -> CliError {
    CliError::Input(format!("{}: not a manifold, consistently oriented mesh: {error}", path.display()))
}

/// Reads a mesh file and builds its half-edge mesh; notes dropped attributes on stderr.
pub fn read_mesh(path: &Path) -> CliResult<HalfedgeMesh> {
    let (soup, report) = read_soup(path)?;
    note_dropped(path, &report);
    build_mesh(path, &soup)
}

/// Writes a soup; the format follows the extension (PLY as `options` say).
pub fn write_soup(path: &Path, soup: &PolygonSoup, options: &WriteOptions) -> CliResult {
    io::write_soup(path, soup, options).map_err(|e| io_error(path, e))
}

/// Writes a mesh; the format follows the extension (PLY in binary little-endian).
pub fn write_mesh(path: &Path, mesh: &HalfedgeMesh) -> CliResult {
    io::write_mesh(path, mesh, &WriteOptions::default()).map_err(|e| io_error(path, e))
}

/// Prints to stdout. A closed pipe (`multires info big.off | head`) ends the output
/// quietly instead of panicking like `println!`.
pub fn print_out(text: &str) -> CliResult {
    let mut stdout = std::io::stdout().lock();
    match stdout.write_all(text.as_bytes()).and_then(|()| stdout.flush()) {
        Err(error) if error.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(CliError::Io { path: PathBuf::from("<stdout>"), source: error })
        }
        _ => Ok(()),
    }
}
