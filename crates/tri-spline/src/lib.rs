//! Triangular splines and their fitting to triangle meshes.
//!
//! Three surface kinds over a triangular parameter domain, each with evaluation,
//! derivatives, normals and basis functions, and one fitting pipeline for all of them:
//!
//! - [`bezier`]: triangular Bézier patches of any degree (de Casteljau, Bernstein sum,
//!   blossom, degree elevation, sub-patches; ALGORITHMS.md §9).
//! - [`bpatch`]: Seidel's B-patches (de Boor-like triangle recursion over three knot
//!   sequences, admissibility checked at construction; §10).
//! - [`simplex`], [`dms`]: bivariate simplex splines by their recurrence and the
//!   Dahmen–Micchelli–Seidel triangular B-splines built from them (knot clouds per
//!   vertex, knot conditions checked at construction; §11).
//! - [`param`]: parameters of the data points (natural ones for a regular triangular
//!   grid, a Tutte or mean-value map of any disk onto the domain triangle otherwise).
//! - [`coarsen`]: the control net by `i` levels of reverse Loop, and the reverse-Loop
//!   map as a sparse matrix.
//! - [`fit`]: LSPIA, classical PIA, the seed paper's reverse-Loop loop, their spectral
//!   radii and the least-squares baseline (§12).
//! - [`pipeline`]: mesh in, fitted surface and convergence table out (`multires fit`).
//!
//! Convergence is computed, not assumed: the seed paper's proof is wrong (§12.5), so the
//! pipeline computes the spectral radius of the iteration matrix at hand.
//!
//! ```
//! use tri_spline::SurfaceKind;
//! use tri_spline::pipeline::{FitOptions, Method, fit_mesh};
//! use tri_spline::samples::{smooth_surface, triangle_grid};
//!
//! // 153 points of a smooth surface on a regular triangular grid (16 segments per side),
//! // fitted by a quartic Bézier patch whose control net is 2 levels of reverse Loop.
//! let mesh = mesh_topo::HalfedgeMesh::from_soup(&triangle_grid(16, smooth_surface))?;
//! let options = FitOptions { surface: SurfaceKind::Bezier, method: Method::Lspia, ..FitOptions::default() };
//! let report = fit_mesh(&mesh, &options)?;
//! assert_eq!((report.degree, report.control_points), (4, 15));
//! let last = report.iterations.last().unwrap();
//! assert!(last.eps_avg < 0.01 * report.bbox_diag);
//! assert!(report.spectral_radius.unwrap() < 1.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod error;

pub mod bezier;
pub mod bpatch;
pub mod coarsen;
pub mod dms;
pub mod dms_net;
pub mod domain;
pub mod fit;
#[cfg(test)]
mod hull_check;
pub mod index;
pub mod linalg;
pub mod param;
pub mod pipeline;
pub mod point;
pub mod samples;
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
