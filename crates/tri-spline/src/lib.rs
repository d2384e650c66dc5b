//! Triangular splines and their fitting to triangle meshes.
//!
//! (Crate documentation is completed with the fitting pipeline.)

mod error;

pub mod bezier;
pub mod bpatch;
pub mod dms;
pub mod dms_net;
pub mod domain;
pub mod fit;
pub mod index;
pub mod linalg;
pub mod param;
pub mod point;
pub mod simplex;
pub mod surface;

pub use bezier::TriBezier;
pub use bpatch::{BPatch, BPatchBasis, KnotSequences};
pub use dms::{DmsBasis, DmsScratch, DmsSpline, KnotPlacement};
pub use domain::DomainTriangle;
pub use error::SplineError;
pub use point::Point;
pub use simplex::{SimplexSpline, WChoice};
pub use surface::{FittedSurface, SurfaceBasis, SurfaceKind};
