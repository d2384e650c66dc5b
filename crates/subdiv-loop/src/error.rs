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
}
