//! Loop subdivision of triangle meshes, its exact reversal, M-band variants and analysis.
//!
//! - [`forward`]: one or more Loop steps (Loop's original or Warren's weights, boundary
//!   and corner rules), refinement of any per-vertex attribute, the sparse subdivision
//!   matrix.
//! - [`limit`]: limit positions and normals at the vertices of any level.
//! - [`detect`]: recognising Loop (1-to-4) connectivity in a plain triangle mesh.
//! - [`reverse`]: reverse Loop with detail vectors and exact reconstruction, one level.
//! - [`pyramid`]: multiresolution pyramids (base mesh + details of every level),
//!   compression, and the `.mres` file format.
//! - [`mband`]: ternary (1-to-9) and quaternary (1-to-16) Loop from the box spline.
//! - [`analysis`]: local subdivision matrices, spectra and Reif's C1 check.

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
