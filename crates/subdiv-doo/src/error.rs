//! The error type of this crate.

use thiserror::Error;

/// What went wrong, named by the offending element.
///
/// Face and vertex numbers are indices into the mesh the caller passed in (for a
/// multi-level operation, into the mesh of the level named by the variant, counted from
/// the input).
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum DooError {
    /// The input is not a valid polygon mesh (non-manifold, faces with fewer than three
    /// corners, NaN coordinates, ...), as reported by `mesh-topo`.
    #[error(transparent)]
    Mesh(#[from] mesh_topo::MeshError),
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex}: position {value:?} is not finite")]
    NonFinite {
        /// The vertex.
        vertex: usize,
        /// Its position.
        value: [f64; 3],
    },
    /// An interior vertex has only two edges: its vertex face would be a two-sided
    /// polygon (a digon), which is not a face.
    #[error("interior vertex {vertex} has valence 2; its Doo-Sabin vertex face would be a digon")]
    ValenceTwoVertex {
        /// The vertex.
        vertex: usize,
    },
    /// A rule parameter is out of its range.
    #[error("invalid parameter {name} = {value}: {reason}")]
    InvalidParameter {
        /// The parameter.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The allowed range, in words.
        reason: &'static str,
    },
    /// The mesh does not have the connectivity of one Doo-Sabin step.
    #[error("not Doo-Sabin connectivity at face {face}: {reason}")]
    NotDooConnectivity {
        /// The face where the structure breaks (in the mesh being reversed).
        face: usize,
        /// What is wrong there.
        reason: String,
    },
    /// The mesh has a vertex that no face uses; reverse Doo-Sabin cannot place it.
    #[error("vertex {vertex} is not a corner of any face; a Doo-Sabin mesh has no isolated vertices")]
    IsolatedVertex {
        /// The vertex.
        vertex: usize,
    },
    /// The mesh to reverse has no faces.
    #[error("the mesh has no faces; there is nothing to reverse")]
    EmptyMesh,
    /// A seed face given by the caller does not exist.
    #[error("seed face {face} does not exist (the mesh has {face_count} faces)")]
    SeedOutOfRange {
        /// The seed given.
        face: usize,
        /// Number of faces of the mesh.
        face_count: usize,
    },
    /// Two seed faces were given for the same connected component.
    #[error("seed faces {first} and {second} lie in the same connected component; give one seed per component")]
    DuplicateSeed {
        /// The first seed.
        first: usize,
        /// The second seed in the same component.
        second: usize,
    },
    /// A multiresolution pyramid is inconsistent (wrong array lengths, bad level).
    #[error("invalid pyramid: {0}")]
    InvalidPyramid(String),
    /// A pyramid file could not be encoded or decoded.
    #[error("pyramid encoding: {0}")]
    Binary(String),
    /// Finite input whose subdivision leaves the `f64` range: coordinates so large that
    /// a sum of the rules overflows (the first fine vertex that is not finite).
    #[error(
        "fine vertex {vertex} is not finite: the input's coordinates (up to {largest:e} in magnitude) overflow the \
         f64 range when the rules sum them; scale the mesh down"
    )]
    Overflow {
        /// The first fine vertex that is not finite.
        vertex: usize,
        /// The largest coordinate magnitude of the input.
        largest: f64,
    },
    /// Finite input whose reversal leaves the `f64` range: coordinates so large that a
    /// sum of the inverse rules overflows. `index` is the first value that is not
    /// finite among the coarse positions followed by the details (the coarse vertex
    /// count plus the detail's index for a detail).
    #[error(
        "value {index} of the reversal (coarse positions, then details) is not finite: the input's coordinates \
         (up to {largest:e} in magnitude) overflow the f64 range when the inverse rules sum them; scale the mesh down"
    )]
    ReversalOverflow {
        /// The first coarse position or detail that is not finite.
        index: usize,
        /// The largest coordinate magnitude of the reversed mesh.
        largest: f64,
    },
    /// A mesh has more elements than `u32` indices can address.
    #[error("too many {what}: {count} (at most {max} are supported)")]
    TooLarge {
        /// Which element kind overflowed.
        what: &'static str,
        /// How many there would be.
        count: usize,
        /// The limit.
        max: usize,
    },
}

impl From<mesh_topo::binary::BinaryError> for DooError {
    fn from(error: mesh_topo::binary::BinaryError) -> Self {
        DooError::Binary(error.to_string())
    }
}
