//! The error type for building and validating meshes.

use thiserror::Error;

/// What is wrong with a polygon soup, named by the offending element.
///
/// Face and vertex numbers are the 0-based indices of the input soup, so the caller can
/// find the culprit in the data they gave (a file reader adds its own line numbers).
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum MeshError {
    /// A face refers to a vertex that does not exist.
    #[error(
        "face {face}, corner {corner}: vertex index {index} is out of range (the mesh has {vertex_count} vertices)"
    )]
    IndexOutOfRange {
        /// The face.
        face: usize,
        /// The corner within the face (0-based).
        corner: usize,
        /// The offending index.
        index: u64,
        /// Number of vertices in the soup.
        vertex_count: usize,
    },
    /// A face has fewer than three corners.
    #[error("face {face} has {len} corners; a face needs at least 3")]
    FaceTooSmall {
        /// The face.
        face: usize,
        /// Its number of corners.
        len: usize,
    },
    /// A face visits the same vertex twice.
    #[error("face {face} uses vertex {vertex} more than once")]
    RepeatedVertex {
        /// The face.
        face: usize,
        /// The repeated vertex.
        vertex: u32,
    },
    /// Three or more faces share one edge.
    #[error("non-manifold edge ({from}, {to}): used by faces {faces:?} (at most 2 are allowed)")]
    NonManifoldEdge {
        /// One end of the edge.
        from: u32,
        /// The other end.
        to: u32,
        /// Three of the faces that use it.
        faces: [usize; 3],
    },
    /// Two neighbouring faces traverse their common edge in the same direction.
    #[error(
        "inconsistent orientation: faces {first_face} and {second_face} both traverse edge {from} -> {to} in the same direction"
    )]
    InconsistentOrientation {
        /// Start of the directed edge.
        from: u32,
        /// End of the directed edge.
        to: u32,
        /// The first face using the edge in this direction.
        first_face: usize,
        /// The second face using it in the same direction.
        second_face: usize,
    },
    /// The faces around a vertex form more than one fan (a "pinched" vertex).
    #[error(
        "non-manifold vertex {vertex}: its faces form {fans} separate fans (e.g. faces {example_faces:?} are not connected through the vertex)"
    )]
    NonManifoldVertex {
        /// The vertex.
        vertex: u32,
        /// Number of fans found (at least 2).
        fans: usize,
        /// One face from each of two different fans.
        example_faces: [usize; 2],
    },
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex}: coordinate {axis} is not finite ({value})")]
    NonFiniteCoordinate {
        /// The vertex.
        vertex: usize,
        /// 0 = x, 1 = y, 2 = z.
        axis: usize,
        /// The value found.
        value: f64,
    },
    /// A procedural shape was asked for with parameters it cannot be built from.
    #[error("{shape} {width} x {height}: {requirement}")]
    InvalidShape {
        /// Which shape (`"grid"`, `"torus"`).
        shape: &'static str,
        /// The first size parameter given.
        width: u32,
        /// The second size parameter given.
        height: u32,
        /// What the parameters must satisfy.
        requirement: &'static str,
    },
    /// More elements than `u32` indices can address.
    #[error("too many {what}: {count} (at most {max} are supported)")]
    TooLarge {
        /// Which element kind overflowed.
        what: &'static str,
        /// How many there were.
        count: usize,
        /// The limit.
        max: usize,
    },
    /// An output that would need more memory than the system has available, refused
    /// before any work (see [`crate::memory::check_available`]).
    #[error("the {what} would take {needed_bytes} bytes; {available_bytes} bytes are available")]
    OutOfMemory {
        /// What would have been made.
        what: &'static str,
        /// The bytes it needs (at least).
        needed_bytes: u128,
        /// The bytes available.
        available_bytes: u64,
    },
}

/// An internal invariant that [`HalfedgeMesh::validate`](crate::HalfedgeMesh::validate) found broken.
///
/// Building from a soup never produces such a mesh; seeing this error means a bug in this
/// crate or in code that edits the connectivity arrays directly. Please report it.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("internal mesh invariant broken: {0}")]
pub struct InvariantError(pub String);
