//! The error type of this crate.

use thiserror::Error;

use crate::detect::FineElement;

/// What went wrong, named by the offending element.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum LoopError {
    /// The input is not a valid mesh.
    #[error(transparent)]
    Mesh(#[from] mesh_topo::MeshError),
    /// Loop schemes need triangles.
    #[error("face {face} has {corners} corners; Loop subdivision needs triangles")]
    NotTriangle {
        /// The face.
        face: usize,
        /// Its number of corners.
        corners: usize,
    },
    /// The mesh does not have Loop (1-to-4) subdivision connectivity: the structure of
    /// vertex points and edge points breaks at the named vertex or face.
    #[error("no Loop subdivision connectivity at {at}: {reason}")]
    NotLoopConnectivity {
        /// Where the structure breaks (fine-mesh index).
        at: FineElement,
        /// What is wrong there.
        reason: String,
    },
    /// Reverse subdivision needs at least one face.
    #[error("the mesh has no faces: there is no Loop subdivision to reverse")]
    NoFaces,
    /// A user-given seed vertex does not exist.
    #[error("seed vertex {vertex} does not exist (the mesh has {vertex_count} vertices)")]
    SeedOutOfRange {
        /// The seed given.
        vertex: u32,
        /// Number of vertices of the mesh.
        vertex_count: usize,
    },
    /// A user-given seed vertex is an edge point of the labeling that another seed of its
    /// connected component fixes: seeds that share a component must be vertex points of
    /// one labeling.
    #[error(
        "seed vertex {vertex} would be an edge point of the labeling fixed by another seed of its connected \
         component (seeds of one component must be vertex points of one labeling; give one seed per component)"
    )]
    SeedConflict {
        /// The seed that does not fit.
        vertex: u32,
    },
    /// Details or orders do not fit the mesh they are applied to (or a pyramid is
    /// corrupted): `level` counts refinement steps from the coarse mesh (1 = the first).
    #[error("level {level}: {reason}")]
    InvalidDetails {
        /// The refinement step (1-based from the coarsest mesh).
        level: usize,
        /// What does not fit.
        reason: String,
    },
    /// A computed position overflowed to infinity or NaN.
    #[error("level {level}: vertex {vertex} has a non-finite position (details too large)")]
    NonFiniteResult {
        /// The refinement step (1-based from the coarsest mesh).
        level: usize,
        /// The vertex.
        vertex: usize,
    },
    /// Finite input whose subdivision, limit or reversal leaves the `f64` range:
    /// coordinates so large that a sum of the rules overflows (the first output vertex
    /// that is not finite; for a reversal, in the fine mesh's canonical numbering: a
    /// coarse vertex, or the detail of coarse edge `e` as the coarse vertex count plus
    /// `e`).
    #[error(
        "vertex {vertex} of the result is not finite: the input's coordinates (up to {largest:e} in magnitude) \
         overflow the f64 range when the rules sum them; scale the mesh down"
    )]
    Overflow {
        /// The first output vertex that is not finite.
        vertex: usize,
        /// The largest coordinate magnitude of the input.
        largest: f64,
    },
    /// An attribute value given to refine is NaN or infinite (see
    /// [`Attribute::is_finite`](crate::forward::Attribute::is_finite)).
    #[error("the attribute value of vertex {vertex} is not finite")]
    NonFiniteAttribute {
        /// The first vertex (or lattice point, or matrix column) whose value is not finite.
        vertex: usize,
    },
    /// Finite attribute values whose refinement leaves the `f64` range: values so large
    /// that a sum of the rules overflows.
    #[error(
        "refined attribute value {vertex} is not finite: the input values overflow the f64 range when the \
         rules sum them; scale them down"
    )]
    AttributeOverflow {
        /// The first refined value (fine vertex, lattice point or matrix row) that is not finite.
        vertex: usize,
    },
    /// A pyramid file could not be encoded or decoded.
    #[error("Loop pyramid: {0}")]
    Binary(String),
    /// A per-vertex attribute array does not have one value per vertex.
    #[error("attribute has {found} values but the mesh has {expected} vertices")]
    AttributeCount {
        /// Number of vertices (values needed).
        expected: usize,
        /// Number of values given.
        found: usize,
    },
    /// A parameter is out of its range.
    #[error("invalid {name}: {reason}")]
    InvalidParameter {
        /// The parameter.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
    /// The scheme has no rule for boundaries.
    #[error("{scheme} needs a closed mesh; edge ({from}, {to}) is on a boundary")]
    BoundaryNotSupported {
        /// The scheme.
        scheme: &'static str,
        /// One end of a boundary edge.
        from: u32,
        /// The other end.
        to: u32,
    },
    /// Two triangles glued along all three edges (a closed "pillow" whose vertices
    /// have interior valence 2): one Loop step would make the mesh non-manifold.
    #[error("interior vertex {vertex} has valence 2 (face {face} shares all its edges with one other face)")]
    InteriorValenceTwo {
        /// A vertex of valence 2.
        vertex: u32,
        /// A face of the pillow.
        face: usize,
    },
}
