//! The error type of this crate.

use thiserror::Error;

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
