//! `multires`: subdivision-based geometry in one crate.
//!
//! This facade re-exports the member crates of the workspace, one module each, and adds
//! the few types that span them: [`SurfaceScheme`] (every surface scheme behind one name,
//! so a comparison over schemes is a loop), [`Boundaries`] (the boundary rules of open
//! meshes: Loop's fixed corners, Doo-Sabin's Chaikin ring), [`Pyramid`], [`decompose`],
//! [`decompose_with`] and [`decompose_soup`] (multiresolution by reverse Loop or reverse
//! Doo-Sabin, one file format), [`memory`] (whether an output fits before it is made:
//! [`SurfaceScheme::subdivide`] refuses one that would not) and one [`Error`]. It
//! defines no algorithm of its own. Depend on a member crate alone when you need only
//! one job; none of them pulls in the command-line dependencies.
//!
//! | module | crate | what |
//! |---|---|---|
//! | [`mesh`] | `mesh-topo` | half-edge meshes, validation, traversal, mesh files |
//! | [`curve`] | `subdiv-curve` | Chaikin and reverse Chaikin, four-point, cubic B-spline, the interpolatory-approximating framework, smoothness analysis, SVG |
//! | [`loop_subdiv`] | `subdiv-loop` | Loop subdivision, limit positions, reverse Loop, M-band Loop, analysis |
//! | [`doo`] | `subdiv-doo` | Doo-Sabin subdivision, reverse Doo-Sabin, pyramids, analysis |
//! | [`spline`] | `tri-spline` | triangular Bézier, B-patch and DMS splines; PIA / LSPIA fitting |
//! | [`ifs`] | `ifs-nonlinear` | subdivision as IFS, complex-parameter and nonlinear subdivision, fractal rendering |
//!
//! # Subdivide with every scheme
//! ```
//! use multires::prelude::*;
//!
//! let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
//! for scheme in SurfaceScheme::ALL {
//!     let fine = scheme.subdivide(&octahedron, 2)?;
//!     let stats = HalfedgeMesh::from_soup(&fine)?.topology_stats();
//!     assert_eq!(stats.euler, 2, "{scheme} keeps the topology");
//! }
//! # Ok::<(), multires::Error>(())
//! ```
//!
//! # Decompose, compress, reconstruct
//! ```
//! use multires::prelude::*;
//!
//! let cube = HalfedgeMesh::from_soup(&shapes::cube())?;
//! let fine = HalfedgeMesh::from_soup(&SurfaceScheme::DooSabin.subdivide(&cube, 3)?)?;
//! let pyramid = decompose(&fine, SurfaceScheme::DooSabin, Depth::Max)?;
//! assert_eq!(pyramid.level_count(), 3);
//! assert_eq!(pyramid.base().face_count(), 6); // the cube again, all details zero
//! let half = pyramid.reconstruct_keeping(3, 0.5)?;
//! assert_eq!(half.face_count(), fine.face_count());
//! # Ok::<(), multires::Error>(())
//! ```
//!
//! # Open meshes
//! ```
//! use multires::prelude::*;
//!
//! // Doo-Sabin with the Chaikin boundary ring, two steps on an open grid and back.
//! let grid = HalfedgeMesh::from_soup(&shapes::grid(5, 4, shapes::CellKind::Mixed)?)?;
//! let ring = Boundaries::chaikin();
//! let fine = HalfedgeMesh::from_soup(&SurfaceScheme::DooSabin.subdivide_with(&grid, 2, &ring)?)?;
//! let pyramid = decompose_with(&fine, SurfaceScheme::DooSabin, Depth::Max, &ring)?;
//! assert_eq!((pyramid.level_count(), pyramid.base().face_count()), (2, grid.face_count()));
//! // Loop with fixed corners: the vertices with one face stay where they are (the fine
//! // mesh lists the coarse vertices first, in their order).
//! let triangles = HalfedgeMesh::from_soup(&shapes::grid(3, 3, shapes::CellKind::Triangles)?)?;
//! let fixed = SurfaceScheme::Loop.subdivide_with(&triangles, 2, &Boundaries::keep_corners())?;
//! let corners: Vec<_> = triangles.vertices().filter(|&v| triangles.vertex_faces(v).count() == 1).collect();
//! assert_eq!(corners.len(), 2);
//! for v in corners {
//!     assert_eq!(fixed.positions[v.index()], triangles.positions()[v.index()]);
//! }
//! # Ok::<(), multires::Error>(())
//! ```
//!
//! # Refine a curve
//! ```
//! use multires::curve::{CurveScheme, Topology};
//!
//! let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
//! let smooth = CurveScheme::chaikin().refine(&square, Topology::Closed, 3)?;
//! assert_eq!(smooth.len(), 4 << 3);
//! # Ok::<(), multires::curve::CurveError>(())
//! ```
//!
//! # Fit a triangular spline
//! ```
//! use multires::mesh::HalfedgeMesh;
//! use multires::spline::pipeline::{FitOptions, fit_mesh};
//! use multires::spline::{SurfaceKind, index::multi_indices, surface::grid_triangles};
//! use glam::DVec3;
//!
//! // A smooth height field on a regular triangular grid, 8 segments per side.
//! let points = multi_indices(8).map(|[_, j, k]| {
//!     let (u, v) = (j as f64 / 8.0, k as f64 / 8.0);
//!     DVec3::new(u, v, (2.0 * u).sin() * v)
//! });
//! let mesh = HalfedgeMesh::from_faces(points.collect(), grid_triangles(8, true))?;
//! // Control net from one reverse-Loop level, ten LSPIA iterations.
//! let options = FitOptions { surface: SurfaceKind::Bezier, reverse_levels: 1, ..FitOptions::default() };
//! let report = fit_mesh(&mesh, &options)?;
//! assert!(report.iterations.last().unwrap().eps_avg < report.iterations[0].eps_avg);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Render a fractal
//! ```
//! use multires::ifs::{ChaosGame, Projection, ToneMap, chaos_points, preset, render_points};
//!
//! let scene = preset("levy")?;
//! let points = chaos_points(scene.ifs.as_ref(), &ChaosGame { points: 10_000, seed: 7, ..ChaosGame::default() })?;
//! let png = render_points(&points, 64, 48, Projection::Xy, ToneMap::Log)?.encode_png()?;
//! assert_eq!(&png[1..4], b"PNG");
//! # Ok::<(), multires::ifs::IfsError>(())
//! ```

mod error;
pub mod memory;
mod pyramid;
mod scheme;

pub use error::Error;
pub use pyramid::{Depth, Pyramid, RateDistortion, decompose, decompose_soup, decompose_with};
pub use scheme::{Boundaries, ElementCounts, SurfaceScheme};

pub use ifs_nonlinear as ifs;
pub use mesh_topo as mesh;
pub use subdiv_curve as curve;
pub use subdiv_doo as doo;
pub use subdiv_loop as loop_subdiv;
pub use tri_spline as spline;

/// The names most programs need: `use multires::prelude::*;`.
pub mod prelude {
    pub use crate::mesh::{HalfedgeMesh, MeshError, PolygonSoup, shapes};
    pub use crate::{
        Boundaries, Depth, Error, Pyramid, RateDistortion, SurfaceScheme, decompose, decompose_soup, decompose_with,
    };
}
