//! Doo-Sabin subdivision, its exact reversal, multiresolution pyramids and analysis.
//!
//! - [`forward`]: Doo-Sabin subdivision of polygon meshes (any face sizes, boundaries).
//! - [`rule`]: the three per-face rules and their inverses.
//! - [`boundary`]: the boundary rules (shrinking, or Chaikin's curve at the boundary).
//! - [`analysis`]: the local subdivision matrix, its spectrum and Reif's C1 check.

pub mod analysis;
pub mod boundary;
mod canonical;
mod corner;
mod error;
pub mod forward;
pub mod pyramid;
pub mod reverse;
pub mod rule;

pub use boundary::BoundaryRule;
pub use corner::{FaceKind, FaceOrigin};
pub use error::DooError;
pub use forward::{DooMesh, DooOptions, subdivide, subdivide_soup};
pub use pyramid::{
    DecomposeOptions, Decomposition, Depth, DooPyramid, PreparedDooPyramid, RateDistortion, decompose, is_doo_pyramid,
};
pub use reverse::{DooReversal, FineOrder, ReverseOptions, ReverseStats, SeedChoice, SeedTrial, reverse};
pub use rule::FaceRule;
