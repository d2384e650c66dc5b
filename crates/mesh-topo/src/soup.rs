//! Polygon soups: positions plus faces as vertex index lists, the form meshes are
//! read from files in and built from.

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Positions plus faces as lists of vertex indices, stored compactly (one flat index
/// array plus offsets, struct-of-arrays).
///
/// A soup carries no adjacency and no guarantee of validity; [`HalfedgeMesh::from_soup`]
/// checks it. Face `f` is `indices[offsets[f] .. offsets[f + 1]]`.
///
/// [`HalfedgeMesh::from_soup`]: crate::HalfedgeMesh::from_soup
///
/// Two soups are equal when they have the same positions and the same faces; a soup
/// without faces may store its offsets as `[]` or `[0]`.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct PolygonSoup {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Start of each face in `indices`, plus one final entry equal to `indices.len()`.
    /// Empty for a soup without faces.
    pub offsets: Vec<u32>,
    /// Concatenated vertex indices of all faces.
    pub indices: Vec<u32>,
}

impl PartialEq for PolygonSoup {
    fn eq(&self, other: &Self) -> bool {
        let offsets_equal = self.offsets == other.offsets
            || (self.offsets.len() <= 1
                && other.offsets.len() <= 1
                && self.offsets.first().copied().unwrap_or(0) == other.offsets.first().copied().unwrap_or(0));
        offsets_equal && self.positions == other.positions && self.indices == other.indices
    }
}

impl PolygonSoup {
    /// An empty soup with room for `vertices` positions, `faces` faces and `corners`
    /// face corners in total.
    ///
    /// ```
    /// use mesh_topo::PolygonSoup;
    ///
    /// let soup = PolygonSoup::with_capacity(4, 2, 6);
    /// assert!(soup.positions.capacity() >= 4 && soup.indices.capacity() >= 6);
    /// assert_eq!((soup.vertex_count(), soup.face_count()), (0, 0));
    /// assert_eq!(soup, PolygonSoup::default()); // empty, whatever the room reserved
    /// ```
    pub fn with_capacity(vertices: usize, faces: usize, corners: usize) -> Self {
        let mut offsets = Vec::with_capacity(faces + 1);
        offsets.push(0);
        Self { positions: Vec::with_capacity(vertices), offsets, indices: Vec::with_capacity(corners) }
    }

    /// The bytes of the arrays of a soup of `vertices` positions, `corners` face corners
    /// and `faces` faces (a position of three `f64` per vertex, a `u32` index per corner,
    /// a `u32` offset per face and one more): what an output of those counts will hold,
    /// to check against the memory available before it is made.
    ///
    /// ```
    /// use mesh_topo::{PolygonSoup, shapes};
    ///
    /// let cube = shapes::cube(); // 8 vertices, 24 corners, 6 faces
    /// assert_eq!(PolygonSoup::array_bytes_for(8, 24, 6), 8 * 24 + 24 * 4 + 7 * 4);
    /// assert_eq!(cube.array_bytes(), PolygonSoup::array_bytes_for(8, 24, 6));
    /// ```
    pub fn array_bytes_for(vertices: u128, corners: u128, faces: u128) -> u128 {
        const POSITION: u128 = size_of::<DVec3>() as u128;
        const INDEX: u128 = size_of::<u32>() as u128;
        POSITION * vertices + INDEX * corners + INDEX * (faces + 1)
    }

    /// The bytes this soup's arrays hold (their lengths, not their capacities): for a
    /// soup with faces, [`array_bytes_for`](Self::array_bytes_for) of its counts.
    pub fn array_bytes(&self) -> u128 {
        let count = |n: usize| n as u128;
        count(size_of::<DVec3>()) * count(self.positions.len())
            + count(size_of::<u32>()) * count(self.indices.len() + self.offsets.len())
    }

    /// A soup from positions and per-face index lists.
    ///
    /// ```
    /// use glam::DVec3;
    /// use mesh_topo::PolygonSoup;
    /// let soup = PolygonSoup::from_faces(
    ///     vec![DVec3::ZERO, DVec3::X, DVec3::Y],
    ///     [[0u32, 1, 2]],
    /// );
    /// assert_eq!(soup.face_count(), 1);
    /// assert_eq!(soup.face(0), &[0, 1, 2]);
    /// ```
    pub fn from_faces<F, I>(positions: Vec<DVec3>, faces: F) -> Self
    where
        F: IntoIterator<Item = I>,
        I: AsRef<[u32]>,
    {
        let mut soup = Self { positions, offsets: vec![0], indices: Vec::new() };
        for face in faces {
            soup.push_face(face.as_ref());
        }
        soup
    }

    /// Appends a face.
    ///
    /// ```
    /// use mesh_topo::{DVec3, PolygonSoup};
    ///
    /// let mut soup = PolygonSoup::default();
    /// soup.positions.extend([DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y]);
    /// soup.push_face(&[0, 1, 2, 3]);
    /// soup.push_face(&[2, 1, 3]);
    /// assert_eq!(soup.face(1), &[2, 1, 3]);
    /// assert_eq!((soup.offsets, soup.indices), (vec![0, 4, 7], vec![0, 1, 2, 3, 2, 1, 3]));
    /// ```
    pub fn push_face(&mut self, face: &[u32]) {
        if self.offsets.is_empty() {
            self.offsets.push(0);
        }
        self.indices.extend_from_slice(face);
        self.offsets.push(self.indices.len() as u32);
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// Number of faces.
    pub fn face_count(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// The vertex indices of face `f`.
    ///
    /// # Panics
    /// If `f >= self.face_count()`.
    pub fn face(&self, f: usize) -> &[u32] {
        &self.indices[self.offsets[f] as usize..self.offsets[f + 1] as usize]
    }

    /// Iterator over the faces as index slices.
    ///
    /// ```
    /// use mesh_topo::shapes;
    ///
    /// let sizes: Vec<usize> = shapes::cube().faces().map(<[u32]>::len).collect();
    /// assert_eq!(sizes, [4; 6]);
    /// assert_eq!(shapes::tetrahedron().faces().last(), Some(&[1, 3, 2][..]));
    /// ```
    ///
    /// # Panics
    /// On malformed offsets (decreasing, or past the end of the indices): only a soup
    /// built by hand has them, and [`HalfedgeMesh::from_soup`] reports them.
    ///
    /// [`HalfedgeMesh::from_soup`]: crate::HalfedgeMesh::from_soup
    pub fn faces(&self) -> impl ExactSizeIterator<Item = &[u32]> + '_ {
        self.offsets.windows(2).map(|w| &self.indices[w[0] as usize..w[1] as usize])
    }

    /// True if every face has exactly three corners (false for decreasing offsets,
    /// which a soup built by hand may have).
    ///
    /// ```
    /// use mesh_topo::shapes;
    ///
    /// assert!(shapes::icosahedron().is_triangle_soup());
    /// assert!(!shapes::cube().is_triangle_soup());
    /// ```
    pub fn is_triangle_soup(&self) -> bool {
        // By chunks of faces without a branch per face, which vectorises (a test and an
        // exit per face did not, and took 4% of reversing a Loop level of 940k faces
        // from its soup).
        const CHUNK: usize = 1024;
        let faces = self.offsets.len().saturating_sub(1);
        (0..faces).step_by(CHUNK).all(|f0| {
            let f1 = (f0 + CHUNK).min(faces);
            let (starts, ends) = (&self.offsets[f0..f1], &self.offsets[f0 + 1..=f1]);
            let not_three = |(&start, &end): (&u32, &u32)| (end.wrapping_sub(start) ^ 3) | u32::from(end < start);
            starts.iter().zip(ends).map(not_three).fold(0, |any, x| any | x) == 0
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decreasing_offsets_are_not_a_triangle_soup() {
        let soup = PolygonSoup { positions: vec![DVec3::ZERO; 3], offsets: vec![0, 3, 0], indices: vec![0, 1, 2] };
        // `w[1] - w[0]` used to wrap (a panic with overflow checks).
        assert!(!soup.is_triangle_soup());
        assert!(PolygonSoup::from_faces(vec![DVec3::ZERO; 3], [[0u32, 1, 2]]).is_triangle_soup());
        // A step of 3 that wraps past `u32::MAX` is not a face of three corners.
        let wrapped = PolygonSoup { positions: Vec::new(), offsets: vec![u32::MAX - 1, 1], indices: Vec::new() };
        assert!(!wrapped.is_triangle_soup());
    }

    #[test]
    fn a_face_of_other_size_is_found_in_any_chunk() {
        let with_offsets = |offsets: Vec<u32>| PolygonSoup { positions: Vec::new(), offsets, indices: Vec::new() };
        let triangles: Vec<u32> = (0..3000).map(|f| 3 * f).collect();
        assert!(with_offsets(triangles.clone()).is_triangle_soup());
        assert!(with_offsets(vec![0]).is_triangle_soup() && with_offsets(Vec::new()).is_triangle_soup());
        for changed in [0, 1, 1023, 1024, 1025, 2999] {
            let mut offsets = triangles.clone();
            offsets[changed] += 1;
            assert!(!with_offsets(offsets).is_triangle_soup(), "offset {changed}");
        }
    }
}
