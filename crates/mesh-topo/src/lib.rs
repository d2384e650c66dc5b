//! Half-edge polygon meshes for subdivision and multiresolution work.
//!
//! `mesh-topo` is the bottom layer of the `multires` workspace. It knows meshes, not
//! subdivision schemes: it turns a polygon soup (positions plus faces as vertex index
//! lists, any face size, with boundaries) into a validated [`HalfedgeMesh`], answers
//! adjacency queries in constant time, circulates around vertices and faces in a
//! documented order, traverses the mesh and its dual graph, cuts out ring
//! neighbourhoods and face subsets, and reads and writes meshes without losing anything
//! the user gave.
//!
//! # Example
//! ```
//! use glam::DVec3;
//! use mesh_topo::HalfedgeMesh;
//!
//! // A tetrahedron, faces counter-clockwise seen from outside.
//! let positions = vec![
//!     DVec3::new(1.0, 1.0, 1.0),
//!     DVec3::new(1.0, -1.0, -1.0),
//!     DVec3::new(-1.0, 1.0, -1.0),
//!     DVec3::new(-1.0, -1.0, 1.0),
//! ];
//! let mesh = HalfedgeMesh::from_faces(positions, [[0u32, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]])?;
//! let stats = mesh.topology_stats();
//! assert_eq!((stats.vertices, stats.edges, stats.faces), (4, 6, 4));
//! assert_eq!((stats.euler, stats.genus, stats.boundary_loops), (2, 0, 0));
//! let apex = mesh.vertex(0).unwrap();
//! let ring: Vec<u32> = mesh.vertex_neighbors(apex).map(|v| v.raw()).collect();
//! assert_eq!(ring.len(), 3);
//! # Ok::<(), mesh_topo::MeshError>(())
//! ```
//!
//! # Glossary
//! - **soup**: positions plus faces as index lists, unchecked ([`PolygonSoup`]).
//! - **half-edge**: a directed edge with the face on its left; twins are `2e`, `2e + 1`.
//! - **boundary half-edge**: a half-edge with no face; boundary half-edges form the
//!   boundary loops, each with the hole on its left.
//! - **fan**: the faces around a vertex, consecutive ones sharing an edge. A manifold
//!   vertex has exactly one fan, closed (interior vertex) or open (boundary vertex).
//! - **valence**: number of edges at a vertex.
//!
//! # Mesh files
//! [`io`] reads and writes OBJ, OFF and PLY (ascii and binary) losslessly: a file is
//! read into a [`PolygonSoup`] plus a report of everything not kept, and built into a
//! mesh separately, so a non-manifold file can still be inspected.
//!
//! # Large arrays
//! [`memory`] holds the memory hints the crates of the workspace share for arrays of many
//! megabytes: transparent huge pages and mapping pages up front (Linux; nothing elsewhere).
//!
//! # Coordinates far from 1
//! [`scale`] measures geometry whose coordinates lie beyond `2^±256` (distances, normals,
//! squared-norm rankings) at an exact power-of-two scale, so that squares neither
//! overflow nor underflow; the crates of the workspace share it.
//!
//! # Errors
//! Building reports bad input as a [`MeshError`] naming the face, vertex or edge at fault;
//! [`HalfedgeMesh::validate`] reports broken internal invariants (bugs) as
//! [`InvariantError`]. Nothing here panics on user data.

mod error;
mod ids;
mod mesh;
mod soup;
mod topology;

pub mod binary;
pub mod graph;
pub mod io;
pub mod memory;
pub mod scale;
pub mod shapes;
#[cfg(any(test, feature = "testing"))]
pub mod testing;

pub use error::{InvariantError, MeshError};
pub use ids::{EdgeId, FaceId, HalfedgeId, MAX_ELEMENTS, VertexId};
pub use mesh::{HalfedgeMesh, LoopCirculator, PositionsError, VertexCirculator, check_capacity};
pub use soup::PolygonSoup;
pub use topology::{ComponentStats, Components, TopologyStats};

/// Re-export of the vector type used for positions.
pub use glam::DVec3;
