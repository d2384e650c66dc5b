//! Doo-Sabin subdivision, its exact reversal, multiresolution pyramids and analysis.
//!
//! - [`forward`]: Doo-Sabin subdivision of polygon meshes (any face sizes, boundaries),
//!   with the provenance (F_F, F_E, F_V and parent element) of every fine face.
//! - [`rule`]: the three per-face rules and their inverses.
//! - [`boundary`]: the boundary rules (shrinking, or Chaikin's curve at the boundary).
//! - [`reverse`](mod@reverse): reverse Doo-Sabin of any mesh with the connectivity of one step
//!   (positions free): coarse mesh plus local details, exact reconstruction.
//! - [`pyramid`]: several levels, compression by keeping the largest details, `.mres`
//!   files; [`pyramid::decompose_soup`] starts from a polygon soup as a file holds it.
//! - [`analysis`]: the local subdivision matrix, its spectrum and Reif's C1 check.
//!
//! ```
//! use mesh_topo::{HalfedgeMesh, shapes};
//! use subdiv_doo::pyramid::{DecomposeOptions, decompose};
//! use subdiv_doo::{DooOptions, FaceRule, subdivide};
//!
//! // Three steps on a cube: 6 -> 26 -> 98 -> 386 faces, one fine vertex per coarse corner.
//! let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
//! let mut fine = subdivide(&cube, &DooOptions::new(FaceRule::DooSabin, 3))?.to_mesh()?;
//! assert_eq!((fine.vertex_count(), fine.face_count()), (384, 386));
//! // Move one vertex: no longer a Doo-Sabin surface, still Doo-Sabin connectivity.
//! fine.positions_mut()[100].z += 0.1;
//! // Back to the cube in three reverse steps; the details rebuild the mesh exactly.
//! let pyramid = decompose(&fine, &DecomposeOptions::max(FaceRule::DooSabin))?.pyramid;
//! assert_eq!((pyramid.level_count(), pyramid.base.face_count()), (3, 6));
//! assert_eq!(pyramid.base.vertex_count() + pyramid.detail_count(), fine.vertex_count());
//! let rebuilt = pyramid.reconstruct(3, None)?;
//! let error = rebuilt.positions.iter().zip(fine.positions()).map(|(a, b)| a.distance(*b)).fold(0.0, f64::max);
//! assert!(error < 1e-14);
//! # Ok::<(), subdiv_doo::DooError>(())
//! ```

pub mod analysis;
pub mod boundary;
mod canonical;
mod corner;
mod error;
pub mod forward;
pub mod pyramid;
pub mod reverse;
pub mod rule;
mod scale;

pub use boundary::BoundaryRule;
pub use corner::{FaceKind, FaceOrigin};
pub use error::DooError;
pub use forward::{DooMesh, DooOptions, MAX_LEVELS, subdivide, subdivide_soup};
pub use pyramid::{
    DecomposeOptions, Decomposition, Depth, DooPyramid, PreparedDooPyramid, RateDistortion, decompose, decompose_soup,
    is_doo_pyramid,
};
pub use reverse::{DooReversal, FineOrder, ReverseOptions, ReverseStats, SeedChoice, SeedTrial, reverse};
pub use rule::FaceRule;
