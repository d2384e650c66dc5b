//! `multires`: subdivision-based geometry in one crate.
//!
//! This facade re-exports the member crates of the workspace, one module each; it
//! defines no algorithm of its own.
//!
//! | module | crate | what |
//! |---|---|---|
//! | [`mesh`] | `mesh-topo` | half-edge meshes, validation, traversal, mesh files |
//! | [`loop_subdiv`] | `subdiv-loop` | Loop subdivision, reverse Loop, M-band Loop, analysis |
//! | [`doo`] | `subdiv-doo` | Doo-Sabin subdivision, reverse Doo-Sabin, pyramids, analysis |
//! | [`ifs`] | `ifs-nonlinear` | subdivision as IFS, complex-parameter and nonlinear subdivision, fractal rendering |
//! | [`spline`] | `tri-spline` | triangular Bézier, B-patch and DMS splines; PIA / LSPIA fitting |
//!
//! ```
//! use multires::mesh::{HalfedgeMesh, shapes};
//! let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
//! assert_eq!(cube.topology_stats().genus, 0);
//! # Ok::<(), multires::mesh::MeshError>(())
//! ```

pub use ifs_nonlinear as ifs;
pub use mesh_topo as mesh;
pub use subdiv_doo as doo;
pub use subdiv_loop as loop_subdiv;
pub use tri_spline as spline;
