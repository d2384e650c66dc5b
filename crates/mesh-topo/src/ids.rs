//! Typed element handles.
//!
//! Handles are `u32` indices wrapped in newtypes so that a vertex index can never be
//! passed where a face index is expected. They are created only by a [`HalfedgeMesh`]
//! (or read back from one), so a handle obtained from a mesh is always in range for it.
//! The index is stored inverted in a `NonZeroU32`, which gives `Option<Id>` the size
//! of a plain `u32` (pinned by a test).
//!
//! [`HalfedgeMesh`]: crate::HalfedgeMesh

use std::fmt;
use std::num::NonZeroU32;

/// Largest number of elements of one kind a mesh may hold (`u32::MAX - 1`).
pub const MAX_ELEMENTS: usize = (u32::MAX - 1) as usize;

macro_rules! define_id {
    ($(#[$doc:meta])* $name:ident, $prefix:literal) => {
        $(#[$doc])*
        #[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub struct $name(NonZeroU32);

        impl $name {
            /// Handle of index `index`. Crate-private: only the mesh hands out handles.
            #[inline]
            pub(crate) fn new(index: u32) -> Self {
                debug_assert!(index != u32::MAX, "internal: handle index out of range");
                // `!index` is non-zero for every index below u32::MAX.
                Self(NonZeroU32::new(!index).expect("internal: handle index u32::MAX"))
            }

            /// The index of this element in the mesh's arrays (`0..count`).
            #[inline]
            pub fn index(self) -> usize {
                (!self.0.get()) as usize
            }

            /// The index as `u32`.
            #[inline]
            pub fn raw(self) -> u32 {
                !self.0.get()
            }
        }

        impl fmt::Debug for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, concat!($prefix, "{}"), self.raw())
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "{}", self.raw())
            }
        }
    };
}

define_id!(
    /// A vertex of a [`HalfedgeMesh`](crate::HalfedgeMesh).
    VertexId,
    "v"
);
define_id!(
    /// A directed half-edge. Half-edges come in twin pairs `2e` and `2e + 1` of edge `e`.
    HalfedgeId,
    "h"
);
define_id!(
    /// An undirected edge: a pair of twin half-edges.
    EdgeId,
    "e"
);
define_id!(
    /// A face (a polygon with three or more corners).
    FaceId,
    "f"
);

impl HalfedgeId {
    /// The twin (opposite) half-edge: same edge, other direction. Pure index arithmetic.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
    /// let h = mesh.halfedge(4).unwrap(); // 2 -> 0
    /// assert_eq!((h.twin().raw(), h.twin().twin()), (5, h));
    /// assert_eq!(mesh.origin(h.twin()), mesh.target(h));
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    #[inline]
    pub fn twin(self) -> HalfedgeId {
        HalfedgeId::new(self.raw() ^ 1)
    }

    /// The undirected edge this half-edge belongs to.
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
    /// let h = mesh.halfedge(5).unwrap();
    /// assert_eq!((h.edge().raw(), h.twin().edge()), (2, h.edge()));
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    #[inline]
    pub fn edge(self) -> EdgeId {
        EdgeId::new(self.raw() >> 1)
    }
}

impl EdgeId {
    /// One of the two half-edges of this edge: `side` 0 is the half-edge created first
    /// (it always lies in a face), `side` 1 its twin (in a face, or on the boundary).
    ///
    /// ```
    /// use mesh_topo::{DVec3, HalfedgeMesh};
    ///
    /// let mesh = HalfedgeMesh::from_faces(vec![DVec3::ZERO, DVec3::X, DVec3::Y], [[0u32, 1, 2]])?;
    /// let e = mesh.edge(1).unwrap();
    /// assert_eq!((e.halfedge(0).raw(), e.halfedge(1)), (2, e.halfedge(0).twin()));
    /// assert_eq!(e.halfedge(1).edge(), e);
    /// assert!(mesh.halfedge_face(e.halfedge(0)).is_some());
    /// assert!(mesh.is_boundary_halfedge(e.halfedge(1))); // a lone triangle: the hole
    /// # Ok::<(), mesh_topo::MeshError>(())
    /// ```
    #[inline]
    pub fn halfedge(self, side: u32) -> HalfedgeId {
        debug_assert!(side < 2);
        HalfedgeId::new(self.raw() * 2 + (side & 1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn option_of_handle_is_as_small_as_u32() {
        assert_eq!(size_of::<Option<HalfedgeId>>(), size_of::<u32>());
        assert_eq!(size_of::<Option<VertexId>>(), size_of::<u32>());
    }

    #[test]
    fn twin_and_edge_are_index_arithmetic() {
        let h = HalfedgeId::new(7);
        assert_eq!(h.twin().raw(), 6);
        assert_eq!(h.twin().twin(), h);
        assert_eq!(h.edge().raw(), 3);
        assert_eq!(h.edge().halfedge(0).raw(), 6);
        assert_eq!(h.edge().halfedge(1), h);
        assert_eq!(format!("{h:?}"), "h7");
        assert_eq!(HalfedgeId::new(0).index(), 0);
    }
}
