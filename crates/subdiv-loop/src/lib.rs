//! Loop subdivision of triangle meshes, its exact reversal, M-band variants and analysis.
//!
//! - [`forward`]: one or more Loop steps (Loop's original or Warren's weights, boundary
//!   and corner rules), refinement of any per-vertex attribute, the sparse subdivision
//!   matrix. Fast: the refined connectivity follows from the coarse one by index
//!   arithmetic, in parallel, with results independent of the number of threads.
//! - [`limit`]: limit positions and normals at the vertices of any level.
//! - [`detect`]: recognising Loop (1-to-4) connectivity in a plain triangle mesh.
//! - [`reverse`]: reverse Loop with detail vectors and exact reconstruction, one level.
//! - [`pyramid`]: multiresolution pyramids (base mesh + details of every level),
//!   compression, and the `.mres` file format; [`pyramid::decompose_soup`] reads a mesh
//!   in the canonical order straight from its face list.
//! - [`mband`]: exact box-spline masks for any arity, ternary (1-to-9) and quaternary
//!   (1-to-16) Loop.
//! - [`analysis`]: local subdivision matrices, spectra and Reif's C1 check.
//!
//! ```
//! use mesh_topo::{HalfedgeMesh, shapes};
//! use subdiv_loop::forward::{LoopOptions, subdivide};
//! use subdiv_loop::limit::limit_positions;
//!
//! let tetrahedron = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
//! let fine = subdivide(&tetrahedron, 3, &LoopOptions::default())?;
//! // Every step: V' = V + E, F' = 4F (4 -> 10 -> 34 -> 130 vertices, 4 -> 256 faces).
//! assert_eq!((fine.vertex_count(), fine.face_count()), (130, 256));
//! // The first four vertices are still the tetrahedron's corners, moved towards the
//! // limit surface; the limit masks give the limit points directly.
//! let limit = limit_positions(&tetrahedron, &LoopOptions::default())?;
//! assert!((fine.positions[0] - limit[0]).length() < 0.05);
//! # Ok::<(), subdiv_loop::LoopError>(())
//! ```
//!
//! References: C. Loop, *Smooth subdivision surfaces based on triangles*, 1987 (the
//! scheme and its limit masks); J. Warren, 1995 (simplified weights); H. Hoppe et al.,
//! 1994 (boundary rules); J. Dupuy and K. Vanhoey, 2021 (index-arithmetic refinement);
//! Y. W. Zhao, multi-band subdivision from the box spline (ternary and quaternary
//! Loop); U. Reif, 1995 (the C1 criterion); J. Stam, 1998 (Loop eigenstructure).

pub mod analysis;
mod corner_table;
pub mod detect;
mod error;
pub mod forward;
pub mod limit;
pub mod mband;
pub mod pyramid;
#[cfg(test)]
mod reference;
pub mod reverse;

pub use error::LoopError;
