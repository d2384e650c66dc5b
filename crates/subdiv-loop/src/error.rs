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
    /// A parameter is outside its valid range.
    #[error("invalid parameter {name} = {value}: {expected}")]
    InvalidParameter {
        /// The parameter.
        name: &'static str,
        /// The value given, printed.
        value: String,
        /// What is allowed.
        expected: &'static str,
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
    /// A pyramid file could not be encoded or decoded.
    #[error("Loop pyramid: {0}")]
    Binary(String),
}
