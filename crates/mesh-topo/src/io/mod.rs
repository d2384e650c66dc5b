//! Mesh files: OBJ, OFF and PLY readers and writers.
//!
//! Reading gives a [`PolygonSoup`] (positions and faces exactly as in the file, vertex
//! and face order kept, unreferenced vertices kept) plus a [`ReadReport`] listing every
//! attribute the soup cannot hold (normals, texture coordinates, colours, groups,
//! materials, other PLY properties and elements...), so nothing is lost silently.
//! Building a [`HalfedgeMesh`] from the soup is a separate step
//! ([`HalfedgeMesh::from_soup`]), so that a tool can still describe a file whose surface
//! is not manifold; [`read_mesh`] does both.
//!
//! Writers print every `f64` in the shortest form that reads back to the same bits
//! (`ryu`), so `read(write(soup)) == soup` bit for bit, in every format and every PLY
//! encoding. They buffer their output and format numbers without allocating.
//!
//! | format | reads | writes |
//! |---|---|---|
//! | OBJ | `v` (extra `w` or colour values reported), `f` with `v`, `v/vt`, `v//vn`, `v/vt/vn` corners, negative (relative) indices, forward references, any polygon size, `\` line continuations, comments; every other statement (`vt`, `vn`, `g`, `usemtl`, `l`...) is counted in the report | `v` and `f` lines |
//! | OFF | `OFF` with the optional `ST`, `C`, `N`, `n` prefixes (normals, colours, texture coordinates and face colours reported), comments, counts on the keyword line | `OFF` |
//! | PLY | ascii, binary little- and big-endian; `x y z` of any numeric type; face `vertex_indices` or `vertex_index` lists of any integer types; every other property (lists included) and element skipped and reported | ascii or binary, `double` coordinates |
//!
//! # Why our own parsers
//! The crates available when this module was written each lose something this
//! workspace promises to keep: `tobj` renumbers vertices per object/group (losing the
//! global vertex order and unreferenced vertices) and reads `f32` unless a feature is
//! set; the PLY crates (`ply-rs` and forks) build a generic property map per element
//! (slow for millions of faces) and panic on some malformed headers; there is no
//! maintained OFF crate. None reports what it drops. The formats are small, so the
//! parsers here are written for exactly these guarantees: every byte is accounted for,
//! every error names its line (or byte offset in binary PLY), no input makes them panic
//! or reserve memory the file cannot fill (they are fuzzed: `crates/mesh-topo/fuzz`).
//!
//! # Decisions where the formats are loose
//! - OFF is read line by line (a vertex or face per line, as every writer we know does),
//!   which is what lets the optional colour columns be told apart from indices. Data
//!   after the last declared face is an error, like a missing line.
//! - OBJ indices are 1-based; negative indices count back from the last vertex defined
//!   so far; positive indices may refer to vertices defined later in the file and are
//!   checked at the end. Index `0` is an error.
//! - NaN and infinite coordinates are errors in every format: no mesh can use them.
//! - Faces are kept as written even when they are degenerate (fewer than 3 corners,
//!   repeated vertices); building the mesh reports them.
//! - Comments (OBJ/OFF `#`, PLY `comment` and `obj_info`) are not attributes and are not
//!   reported.
//!
//! # Example
//! ```
//! use mesh_topo::io::{self, Format};
//!
//! let obj = b"# a square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\n";
//! let (soup, report) = io::read_bytes(obj, Format::Obj)?;
//! assert_eq!((soup.vertex_count(), soup.face_count()), (4, 1));
//! assert_eq!(soup.face(0), &[0, 1, 2, 3]);
//! // The normal and the normal references are not kept, and say so.
//! assert_eq!(report.dropped.len(), 2);
//!
//! let mut off = Vec::new();
//! io::write_to(&mut off, &soup, Format::Off, &io::WriteOptions::default())?;
//! assert_eq!(String::from_utf8(off).unwrap(), "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
//! # Ok::<(), mesh_topo::io::IoError>(())
//! ```

mod obj;
mod off;
mod ply;
mod report;
mod text;
mod write;

use std::fmt;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::error::MeshError;
use crate::mesh::HalfedgeMesh;
use crate::soup::PolygonSoup;

pub use obj::read_obj;
pub use off::read_off;
pub use ply::read_ply;
pub use report::{DroppedAttribute, ReadReport};
pub use write::{write_obj, write_off, write_ply};

/// A mesh file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Format {
    /// Wavefront OBJ.
    Obj,
    /// Object File Format (Geomview).
    Off,
    /// Polygon File Format (Stanford).
    Ply,
}

impl Format {
    /// The format named by a path's extension (`.obj`, `.off`, `.ply`, any letter case).
    ///
    /// ```
    /// use mesh_topo::io::Format;
    /// assert_eq!(Format::from_path("scan/Bunny.PLY").unwrap(), Format::Ply);
    /// assert!(Format::from_path("bunny.stl").is_err());
    /// ```
    ///
    /// # Errors
    /// [`IoError::UnknownExtension`] for any other extension or none.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Self, IoError> {
        let path = path.as_ref();
        let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
        match extension.as_deref() {
            Some("obj") => Ok(Self::Obj),
            Some("off") => Ok(Self::Off),
            Some("ply") => Ok(Self::Ply),
            _ => Err(IoError::UnknownExtension { path: path.to_path_buf() }),
        }
    }

    /// The usual file extension, without the dot.
    ///
    /// ```
    /// use mesh_topo::io::Format;
    ///
    /// assert_eq!(Format::Ply.extension(), "ply");
    /// for format in [Format::Obj, Format::Off, Format::Ply] {
    ///     assert_eq!(Format::from_path(format!("mesh.{}", format.extension()))?, format);
    /// }
    /// # Ok::<(), mesh_topo::io::IoError>(())
    /// ```
    pub fn extension(self) -> &'static str {
        match self {
            Self::Obj => "obj",
            Self::Off => "off",
            Self::Ply => "ply",
        }
    }
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Obj => "OBJ",
            Self::Off => "OFF",
            Self::Ply => "PLY",
        })
    }
}

/// How the body of a PLY file is encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
pub enum PlyEncoding {
    /// Text.
    Ascii,
    /// Binary, little-endian (the default for writing: compact, fast, what most tools write).
    #[default]
    BinaryLittleEndian,
    /// Binary, big-endian.
    BinaryBigEndian,
}

impl PlyEncoding {
    /// The name used on the PLY `format` line.
    ///
    /// ```
    /// use mesh_topo::io::{self, PlyEncoding};
    ///
    /// assert_eq!(PlyEncoding::default().header_name(), "binary_little_endian");
    /// let mut ply = Vec::new();
    /// io::write_ply(&mut ply, &mesh_topo::shapes::tetrahedron(), PlyEncoding::Ascii)?;
    /// assert!(ply.starts_with(format!("ply\nformat {} 1.0\n", PlyEncoding::Ascii.header_name()).as_bytes()));
    /// # Ok::<(), mesh_topo::io::IoError>(())
    /// ```
    pub fn header_name(self) -> &'static str {
        match self {
            Self::Ascii => "ascii",
            Self::BinaryLittleEndian => "binary_little_endian",
            Self::BinaryBigEndian => "binary_big_endian",
        }
    }
}

/// Options for writing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct WriteOptions {
    /// Encoding of PLY output (ignored for OBJ and OFF).
    pub ply_encoding: PlyEncoding,
}

/// Where in a file a problem is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Location {
    /// A 1-based line number (text formats, and the PLY header).
    Line(usize),
    /// A 0-based byte offset (binary PLY data).
    Byte(usize),
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Line(line) => write!(f, "line {line}"),
            Self::Byte(offset) => write!(f, "byte {offset}"),
        }
    }
}

/// Why a mesh file could not be read or written.
///
/// Every error in file content says where it is ([`Location`]: line number, or byte
/// offset in binary PLY data).
#[derive(Debug, Error)]
#[non_exhaustive]
pub enum IoError {
    /// The file could not be opened, read or written.
    #[error("{}: {source}", path.display())]
    File {
        /// The file.
        path: PathBuf,
        /// What the system reported.
        source: std::io::Error,
    },
    /// Writing to a stream failed.
    #[error("write failed: {0}")]
    Stream(#[source] std::io::Error),
    /// The file name does not say which format it is in.
    #[error("{}: unsupported format (the extension must be .obj, .off or .ply)", path.display())]
    UnknownExtension {
        /// The file.
        path: PathBuf,
    },
    /// A format variant this crate does not read (e.g. binary OFF, homogeneous `4OFF`).
    #[error("{at}: unsupported {what}")]
    Unsupported {
        /// Where.
        at: Location,
        /// What is not supported.
        what: String,
    },
    /// The header is malformed (OFF keyword or counts, PLY header).
    #[error("{at}: invalid header: {reason}")]
    InvalidHeader {
        /// Where.
        at: Location,
        /// What is wrong.
        reason: String,
    },
    /// The file ends before all the data its header announces.
    #[error("{at}: file ends early: expected {expected}")]
    Truncated {
        /// Where the file ends.
        at: Location,
        /// What was still expected, in words.
        expected: String,
    },
    /// A line or record holds another number of values than it must.
    #[error("{at}: {what}: expected {expected}, found {found}")]
    CountMismatch {
        /// Where.
        at: Location,
        /// What was counted, in words.
        what: &'static str,
        /// How many were expected (a minimum for coordinates).
        expected: usize,
        /// How many there are.
        found: usize,
    },
    /// Data continues after everything the header announces.
    #[error("{at}: unexpected data after the last {what} announced by the header")]
    TrailingData {
        /// Where the extra data starts.
        at: Location,
        /// The last element kind read.
        what: &'static str,
    },
    /// A token is not a number of the expected kind.
    #[error("{at}: `{token}` is not {expected}")]
    InvalidNumber {
        /// Where.
        at: Location,
        /// The token (shortened if long, invalid UTF-8 replaced).
        token: String,
        /// What was expected, in words ("a number", "a vertex index"...).
        expected: &'static str,
    },
    /// A face refers to a vertex that does not exist. `index` is as written in the file
    /// (1-based or negative in OBJ, 0-based in OFF and PLY).
    #[error("{at}: vertex index {index} is out of range (the file has {vertex_count} vertices)")]
    IndexOutOfRange {
        /// Where.
        at: Location,
        /// The index as written.
        index: i64,
        /// Number of vertices (defined so far, for OBJ negative indices).
        vertex_count: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("{at}: vertex {vertex} has a non-finite coordinate ({value})")]
    NonFiniteCoordinate {
        /// Where.
        at: Location,
        /// The 0-based vertex number.
        vertex: usize,
        /// The value.
        value: f64,
    },
    /// More elements than `u32` indices can address.
    #[error("{at}: too many {what} (at most {max} are supported)")]
    TooLarge {
        /// Where.
        at: Location,
        /// Which element kind.
        what: &'static str,
        /// The limit.
        max: usize,
    },
    /// A soup given to a writer cannot be written as a valid file.
    #[error("cannot write this soup: {0}")]
    InvalidSoup(String),
    /// The file was read but its faces do not form a valid mesh ([`read_mesh`] only).
    #[error(transparent)]
    Mesh(#[from] MeshError),
}

impl IoError {
    /// Where in the file the problem is, for content errors.
    ///
    /// ```
    /// use mesh_topo::io::{self, Format, Location};
    ///
    /// let err = io::read_bytes(b"v 0 0 0\nv 1 x 0\n", Format::Obj).unwrap_err();
    /// assert_eq!(err.location(), Some(Location::Line(2)));
    /// assert_eq!(Format::from_path("mesh.stl").unwrap_err().location(), None);
    /// ```
    pub fn location(&self) -> Option<Location> {
        match self {
            Self::Unsupported { at, .. }
            | Self::InvalidHeader { at, .. }
            | Self::Truncated { at, .. }
            | Self::CountMismatch { at, .. }
            | Self::TrailingData { at, .. }
            | Self::InvalidNumber { at, .. }
            | Self::IndexOutOfRange { at, .. }
            | Self::NonFiniteCoordinate { at, .. }
            | Self::TooLarge { at, .. } => Some(*at),
            _ => None,
        }
    }
}

/// Reads a mesh file as a polygon soup, the format chosen by the extension.
///
/// ```
/// use mesh_topo::io::{self, IoError};
///
/// let path = std::env::temp_dir().join(format!("mesh-topo-read-soup-{}.off", std::process::id()));
/// std::fs::write(&path, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")?;
/// let read = io::read_soup(&path);
/// std::fs::remove_file(&path)?;
/// let (soup, report) = read?;
/// assert_eq!((soup.vertex_count(), soup.face(0)), (3, &[0, 1, 2][..]));
/// assert!(report.is_lossless());
/// assert!(matches!(io::read_soup("mesh.stl"), Err(IoError::UnknownExtension { .. })));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// [`IoError::UnknownExtension`], [`IoError::File`] if the file cannot be read, or the
/// content error of the format's reader.
pub fn read_soup(path: impl AsRef<Path>) -> Result<(PolygonSoup, ReadReport), IoError> {
    let path = path.as_ref();
    let format = Format::from_path(path)?;
    let bytes = std::fs::read(path).map_err(|source| IoError::File { path: path.to_path_buf(), source })?;
    read_bytes(&bytes, format)
}

/// Reads a mesh file from memory.
///
/// ```
/// use mesh_topo::io::{self, Format, IoError};
///
/// let off = b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
/// let (soup, report) = io::read_bytes(off, Format::Off)?;
/// assert_eq!((soup.vertex_count(), soup.face(0)), (3, &[0, 1, 2][..]));
/// assert!(report.is_lossless());
/// // The face line is missing.
/// let err = io::read_bytes(&off[..off.len() - 8], Format::Off).unwrap_err();
/// assert!(matches!(err, IoError::Truncated { .. }), "{err}");
/// # Ok::<(), IoError>(())
/// ```
///
/// # Errors
/// The content error of the format's reader ([`read_obj`], [`read_off`], [`read_ply`]).
pub fn read_bytes(bytes: &[u8], format: Format) -> Result<(PolygonSoup, ReadReport), IoError> {
    match format {
        Format::Obj => read_obj(bytes),
        Format::Off => read_off(bytes),
        Format::Ply => read_ply(bytes),
    }
}

/// Reads a mesh file and builds the half-edge mesh.
///
/// ```no_run
/// let (mesh, report) = mesh_topo::io::read_mesh("bunny.obj")?;
/// println!("{} faces; not kept: {report}", mesh.face_count());
/// # Ok::<(), mesh_topo::io::IoError>(())
/// ```
///
/// A file that reads but whose faces do not form a mesh:
/// ```
/// use mesh_topo::MeshError;
/// use mesh_topo::io::{self, IoError};
///
/// // Both faces run along the file's vertices 1 -> 2 (0 -> 1 in the soup, 0-based).
/// let path = std::env::temp_dir().join(format!("mesh-topo-read-mesh-{}.obj", std::process::id()));
/// std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n")?;
/// let read = io::read_mesh(&path);
/// std::fs::remove_file(&path)?;
/// assert!(matches!(read, Err(IoError::Mesh(MeshError::InconsistentOrientation { from: 0, to: 1, .. }))));
/// # Ok::<(), std::io::Error>(())
/// ```
///
/// # Errors
/// Everything [`read_soup`] reports, and [`IoError::Mesh`] when the faces do not form a
/// manifold, consistently oriented mesh.
pub fn read_mesh(path: impl AsRef<Path>) -> Result<(HalfedgeMesh, ReadReport), IoError> {
    let (soup, report) = read_soup(path)?;
    Ok((HalfedgeMesh::from_soup(&soup)?, report))
}

/// Writes a soup to a file, the format chosen by the extension.
///
/// ```
/// use mesh_topo::io::{self, IoError, WriteOptions};
/// use mesh_topo::shapes;
///
/// let path = std::env::temp_dir().join(format!("mesh-topo-write-soup-{}.ply", std::process::id()));
/// let soup = shapes::icosahedron();
/// io::write_soup(&path, &soup, &WriteOptions::default())?;
/// let read = io::read_soup(&path);
/// std::fs::remove_file(&path)?;
/// assert_eq!(read?.0, soup); // binary PLY by default, bit for bit
/// let err = io::write_soup("mesh.stl", &soup, &WriteOptions::default()).unwrap_err();
/// assert!(matches!(err, IoError::UnknownExtension { .. }));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// [`IoError::UnknownExtension`], [`IoError::File`] if the file cannot be written,
/// [`IoError::InvalidSoup`] for a soup no file can represent (index out of range,
/// non-finite coordinate, inconsistent offsets).
pub fn write_soup(path: impl AsRef<Path>, soup: &PolygonSoup, options: &WriteOptions) -> Result<(), IoError> {
    let path = path.as_ref();
    let format = Format::from_path(path)?;
    write::check_writable(soup)?;
    let file = File::create(path).map_err(|source| IoError::File { path: path.to_path_buf(), source })?;
    write_to(file, soup, format, options).map_err(|error| match error {
        IoError::Stream(source) => IoError::File { path: path.to_path_buf(), source },
        other => other,
    })
}

/// Writes a mesh to a file, the format chosen by the extension.
///
/// ```
/// use mesh_topo::io::{self, WriteOptions};
/// use mesh_topo::{HalfedgeMesh, shapes};
///
/// let path = std::env::temp_dir().join(format!("mesh-topo-write-mesh-{}.obj", std::process::id()));
/// let mesh = HalfedgeMesh::from_soup(&shapes::octahedron())?;
/// io::write_mesh(&path, &mesh, &WriteOptions::default())?;
/// let read = io::read_mesh(&path);
/// std::fs::remove_file(&path)?;
/// assert_eq!(read?.0, mesh);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// As [`write_soup`] (a mesh is always a writable soup, so only extension and file
/// errors remain).
pub fn write_mesh(path: impl AsRef<Path>, mesh: &HalfedgeMesh, options: &WriteOptions) -> Result<(), IoError> {
    write_soup(path, &mesh.to_soup(), options)
}

/// Writes a soup to a stream in the given format. The stream is buffered internally.
///
/// ```
/// use mesh_topo::io::{self, Format, IoError, PlyEncoding, WriteOptions};
/// use mesh_topo::{DVec3, PolygonSoup, shapes};
///
/// let soup = shapes::tetrahedron();
/// let options = WriteOptions { ply_encoding: PlyEncoding::Ascii };
/// let mut ply = Vec::new();
/// io::write_to(&mut ply, &soup, Format::Ply, &options)?;
/// assert!(ply.starts_with(b"ply\nformat ascii 1.0\n"));
/// assert_eq!(io::read_bytes(&ply, Format::Ply)?.0, soup);
/// // Vertex 2 does not exist: no file format could hold this face.
/// let broken = PolygonSoup::from_faces(vec![DVec3::ZERO; 2], [[0u32, 1, 2]]);
/// assert!(matches!(io::write_to(Vec::new(), &broken, Format::Obj, &options), Err(IoError::InvalidSoup(_))));
/// # Ok::<(), IoError>(())
/// ```
///
/// # Errors
/// [`IoError::InvalidSoup`] (see [`write_soup`]) or [`IoError::Stream`].
pub fn write_to(out: impl Write, soup: &PolygonSoup, format: Format, options: &WriteOptions) -> Result<(), IoError> {
    match format {
        Format::Obj => write_obj(out, soup),
        Format::Off => write_off(out, soup),
        Format::Ply => write_ply(out, soup, options.ply_encoding),
    }
}

/// What the readers' tests share.
#[cfg(test)]
mod test_support {
    /// Checks that `read(bytes, parallel_min_bytes)` gives for `text`, forced into
    /// parallel pieces (a threshold of 0) on two, three and five threads, what one pass
    /// gives (no threshold reached): the same soup and report, or the same error.
    pub(crate) fn pieces_read_as_one_pass<T: std::fmt::Debug + Send>(
        text: &str,
        read: impl Fn(&[u8], usize) -> T + Sync,
    ) -> Result<(), proptest::test_runner::TestCaseError> {
        let one_pass = format!("{:?}", read(text.as_bytes(), usize::MAX));
        for threads in [2, 3, 5] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let pieces = format!("{:?}", pool.install(|| read(text.as_bytes(), 0)));
            proptest::prop_assert_eq!(&pieces, &one_pass, "{} threads", threads);
        }
        Ok(())
    }
}
