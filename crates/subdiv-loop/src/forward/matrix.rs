//! Sparse subdivision matrices in compressed-row form.

use serde::{Deserialize, Serialize};

use super::attribute::{Attribute, SparseRow, check_finite_values, checked_refined};
use crate::LoopError;

/// A sparse matrix in compressed-row (CSR) form: `P_fine = S · P_coarse`, one row per
/// fine vertex, one column per coarse vertex.
///
/// Row `i` holds the stencil of fine vertex `i`: its columns in increasing order and
/// their weights. Every row of a subdivision matrix sums to 1 (affine invariance).
///
/// ```
/// use mesh_topo::{HalfedgeMesh, shapes};
/// use subdiv_loop::forward::{LoopOptions, subdivision_matrix};
///
/// let mesh = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
/// let s = subdivision_matrix(&mesh, 1, &LoopOptions::default())?;
/// assert_eq!((s.rows(), s.columns()), (10, 4));
/// assert!(s.row_sums().iter().all(|&sum| (sum - 1.0).abs() < 1e-15));
/// # Ok::<(), subdiv_loop::LoopError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SubdivisionMatrix {
    columns: usize,
    row_offsets: Vec<usize>,
    column_indices: Vec<u32>,
    values: Vec<f64>,
}

impl SubdivisionMatrix {
    /// Builds the matrix from sorted sparse rows.
    pub(crate) fn from_rows(rows: Vec<SparseRow>, columns: usize) -> Self {
        let mut row_offsets = Vec::with_capacity(rows.len() + 1);
        row_offsets.push(0);
        let nnz = rows.iter().map(|r| r.0.len()).sum();
        let mut column_indices = Vec::with_capacity(nnz);
        let mut values = Vec::with_capacity(nnz);
        for row in rows {
            for (c, w) in row.0 {
                column_indices.push(c);
                values.push(w);
            }
            row_offsets.push(column_indices.len());
        }
        Self { columns, row_offsets, column_indices, values }
    }

    /// A matrix from explicit CSR arrays.
    ///
    /// ```
    /// use subdiv_loop::forward::SubdivisionMatrix;
    ///
    /// // Two coarse points, three fine ones: both ends and the midpoint.
    /// let s = SubdivisionMatrix::from_csr(2, vec![0, 1, 3, 4], vec![0, 0, 1, 1], vec![1.0, 0.5, 0.5, 1.0])?;
    /// assert_eq!((s.rows(), s.columns(), s.nnz()), (3, 2, 4));
    /// assert_eq!(s.apply(&[2.0f64, 4.0])?, [2.0, 3.0, 4.0]);
    /// // Columns must increase strictly within a row and stay below `columns`.
    /// assert!(SubdivisionMatrix::from_csr(2, vec![0, 2], vec![1, 0], vec![0.5, 0.5]).is_err());
    /// assert!(SubdivisionMatrix::from_csr(2, vec![0, 1], vec![2], vec![1.0]).is_err());
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    ///
    /// # Errors
    /// [`LoopError::InvalidParameter`] if the arrays are inconsistent: offsets not
    /// starting at 0, decreasing or not ending at the entry count, columns out of range
    /// or not strictly increasing within a row, lengths that differ, non-finite values.
    pub fn from_csr(
        columns: usize,
        row_offsets: Vec<usize>,
        column_indices: Vec<u32>,
        values: Vec<f64>,
    ) -> Result<Self, LoopError> {
        let bad = |reason: String| LoopError::InvalidParameter { name: "csr", reason };
        if row_offsets.first() != Some(&0) || row_offsets.last() != Some(&column_indices.len()) {
            return Err(bad("row offsets must start at 0 and end at the number of entries".into()));
        }
        if column_indices.len() != values.len() {
            return Err(bad(format!("{} column indices but {} values", column_indices.len(), values.len())));
        }
        // All offsets first: with the ends checked, non-decreasing offsets stay within
        // the entries, so the rows below can be sliced.
        if let Some(row) = row_offsets.windows(2).position(|w| w[0] > w[1]) {
            return Err(bad(format!("row {row}: offsets decrease")));
        }
        for (row, w) in row_offsets.windows(2).enumerate() {
            let cols = &column_indices[w[0]..w[1]];
            if cols.windows(2).any(|p| p[0] >= p[1]) || cols.last().is_some_and(|&c| c as usize >= columns) {
                return Err(bad(format!("row {row}: columns must increase strictly and stay below {columns}")));
            }
        }
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            return Err(bad(format!("entry {i} is not finite")));
        }
        Ok(Self { columns, row_offsets, column_indices, values })
    }

    /// Number of rows (fine vertices).
    pub fn rows(&self) -> usize {
        self.row_offsets.len() - 1
    }

    /// Number of columns (coarse vertices).
    pub fn columns(&self) -> usize {
        self.columns
    }

    /// Number of stored entries.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopOptions, subdivision_matrix};
    ///
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let s = subdivision_matrix(&octahedron, 1, &LoopOptions::default())?;
    /// // 6 vertex rows of 1 + 4 entries (valence 4), 12 edge rows of 4 entries.
    /// assert_eq!(s.nnz(), 6 * 5 + 12 * 4);
    /// assert_eq!(s.nnz(), (0..s.rows()).map(|i| s.row(i).0.len()).sum::<usize>());
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// The columns and weights of row `i`.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopOptions, subdivision_matrix};
    ///
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let s = subdivision_matrix(&octahedron, 1, &LoopOptions::default())?;
    /// // Row 6 is the edge point of edge 0, (0, 2) in face (0, 2, 4), with the opposite
    /// // vertices 4 and 5: 3/8 on each end, 1/8 on each opposite vertex.
    /// let (columns, weights) = s.row(6);
    /// assert_eq!(columns, [0, 2, 4, 5]);
    /// assert_eq!(weights, [0.375, 0.375, 0.125, 0.125]);
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    ///
    /// # Panics
    /// If `i >= self.rows()`.
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let range = self.row_offsets[i]..self.row_offsets[i + 1];
        (&self.column_indices[range.clone()], &self.values[range])
    }

    /// The entry at `(row, column)` (0 if not stored, or out of range).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopOptions, subdivision_matrix};
    ///
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let s = subdivision_matrix(&octahedron, 1, &LoopOptions::default())?;
    /// // Vertex 0 (+X) has valence 4: alpha_4 = 33/64 on itself, nothing on -X (vertex 1).
    /// assert!((s.get(0, 0) - 33.0 / 64.0).abs() < 1e-15);
    /// assert_eq!(s.get(0, 1), 0.0);
    /// assert_eq!(s.get(s.rows(), 0), 0.0); // out of range
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn get(&self, row: usize, column: usize) -> f64 {
        if row >= self.rows() {
            return 0.0;
        }
        // A column past `u32` would alias a small one if cast.
        let Ok(column) = u32::try_from(column) else {
            return 0.0;
        };
        let (cols, vals) = self.row(row);
        cols.binary_search(&column).map_or(0.0, |k| vals[k])
    }

    /// The raw CSR arrays: row offsets, column indices, values.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopOptions, SubdivisionMatrix, subdivision_matrix};
    ///
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let s = subdivision_matrix(&octahedron, 1, &LoopOptions::default())?;
    /// let (offsets, columns, values) = s.csr();
    /// assert_eq!((offsets.len(), columns.len(), values.len()), (s.rows() + 1, s.nnz(), s.nnz()));
    /// // Row 6 (the edge point of edge (0, 2)) is the run of entries between two offsets.
    /// assert_eq!(columns[offsets[6]..offsets[7]], [0, 2, 4, 5]);
    /// // The arrays rebuild the same matrix.
    /// let copy = SubdivisionMatrix::from_csr(s.columns(), offsets.to_vec(), columns.to_vec(), values.to_vec())?;
    /// assert_eq!(copy, s);
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn csr(&self) -> (&[usize], &[u32], &[f64]) {
        (&self.row_offsets, &self.column_indices, &self.values)
    }

    /// The sum of each row (1 for every row of a subdivision matrix, up to rounding).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes::{self, CellKind}};
    /// use subdiv_loop::forward::{LoopOptions, subdivision_matrix};
    ///
    /// // Affine invariance under every rule at once: interior and boundary vertices and
    /// // edges, fixed corners, Warren's weights, two steps.
    /// let grid = HalfedgeMesh::from_soup(&shapes::grid(3, 3, CellKind::Triangles)?)?;
    /// let options = LoopOptions { keep_corners: true, ..LoopOptions::warren_weights() };
    /// let s = subdivision_matrix(&grid, 2, &options)?;
    /// let sums = s.row_sums();
    /// assert_eq!(sums.len(), s.rows());
    /// assert!(sums.iter().all(|&sum| (sum - 1.0).abs() < 1e-14));
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn row_sums(&self) -> Vec<f64> {
        (0..self.rows()).map(|i| self.row(i).1.iter().sum()).collect()
    }

    /// `S · values`: applies the stencils to per-vertex data.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopOptions, refine_attribute, subdivision_matrix};
    ///
    /// let mesh = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let options = LoopOptions::default();
    /// let s = subdivision_matrix(&mesh, 2, &options)?;
    /// let heat: Vec<f64> = mesh.positions().iter().map(|p| p.x + 2.0 * p.z).collect();
    /// let fine = s.apply(&heat)?;
    /// let refined = refine_attribute(&mesh, 2, &options, &heat)?;
    /// assert!(fine.iter().zip(&refined).all(|(a, b)| (a - b).abs() < 1e-15));
    /// assert!(s.apply(&heat[1..]).is_err()); // one value per column
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    ///
    /// # Errors
    /// [`LoopError::AttributeCount`] if `values` does not have one entry per column,
    /// [`LoopError::NonFiniteAttribute`] (naming the column) for a value that is not
    /// finite, [`LoopError::AttributeOverflow`] (naming the row) when finite values are
    /// so large that a row's sum is not.
    pub fn apply<T: Attribute>(&self, values: &[T]) -> Result<Vec<T>, LoopError> {
        if values.len() != self.columns {
            return Err(LoopError::AttributeCount { expected: self.columns, found: values.len() });
        }
        check_finite_values(values)?;
        let Some(zero) = values.first().map(|v| v.scaled(0.0)) else {
            return if self.rows() == 0 {
                Ok(Vec::new())
            } else {
                Err(LoopError::InvalidParameter { name: "matrix", reason: "rows over zero columns".into() })
            };
        };
        checked_refined(
            (0..self.rows())
                .map(|i| {
                    let (cols, weights) = self.row(i);
                    match cols.first() {
                        None => zero.clone(),
                        Some(&c0) => {
                            let mut acc = values[c0 as usize].scaled(weights[0]);
                            for (&c, &w) in cols.iter().zip(weights).skip(1) {
                                acc.add_scaled(&values[c as usize], w);
                            }
                            acc
                        }
                    }
                })
                .collect::<Vec<T>>(),
        )
    }

    /// The product `self · other` (apply `other` first): the matrix of two steps.
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopOptions, subdivide, subdivision_matrix};
    ///
    /// let options = LoopOptions::default();
    /// let coarse = HalfedgeMesh::from_soup(&shapes::tetrahedron())?;
    /// let fine = subdivide(&coarse, 1, &options)?.to_halfedge_mesh()?;
    /// let first = subdivision_matrix(&coarse, 1, &options)?;
    /// let second = subdivision_matrix(&fine, 1, &options)?;
    /// let product = second.compose(&first)?;
    /// assert_eq!((product.rows(), product.columns()), (34, 4));
    /// let (a, b) = (product.to_dense(), subdivision_matrix(&coarse, 2, &options)?.to_dense());
    /// assert!(a.iter().flatten().zip(b.iter().flatten()).all(|(x, y)| (x - y).abs() < 1e-15));
    /// assert!(first.compose(&second).is_err()); // 4 columns, 34 rows
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    ///
    /// # Errors
    /// [`LoopError::InvalidParameter`] if `self.columns() != other.rows()`.
    pub fn compose(&self, other: &SubdivisionMatrix) -> Result<SubdivisionMatrix, LoopError> {
        if self.columns != other.rows() {
            return Err(LoopError::InvalidParameter {
                name: "matrix",
                reason: format!("cannot multiply {} columns by {} rows", self.columns, other.rows()),
            });
        }
        let rows = (0..self.rows())
            .map(|i| {
                let (cols, weights) = self.row(i);
                let mut acc = SparseRow::default();
                for (&c, &w) in cols.iter().zip(weights) {
                    let (oc, ow) = other.row(c as usize);
                    acc.add_scaled(&SparseRow(oc.iter().copied().zip(ow.iter().copied()).collect()), w);
                }
                acc
            })
            .collect();
        Ok(Self::from_rows(rows, other.columns))
    }

    /// The dense matrix, row by row (for small matrices: analysis, tests).
    ///
    /// ```
    /// use mesh_topo::{HalfedgeMesh, shapes};
    /// use subdiv_loop::forward::{LoopOptions, subdivision_matrix};
    ///
    /// let octahedron = HalfedgeMesh::from_soup(&shapes::octahedron())?;
    /// let s = subdivision_matrix(&octahedron, 1, &LoopOptions::default())?;
    /// let dense = s.to_dense();
    /// assert_eq!((dense.len(), dense[0].len()), (18, 6));
    /// assert_eq!(dense[6], [0.375, 0.0, 0.375, 0.0, 0.125, 0.125]); // edge (0, 2)
    /// assert_eq!(dense.iter().flatten().filter(|&&w| w != 0.0).count(), s.nnz());
    /// # Ok::<(), subdiv_loop::LoopError>(())
    /// ```
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        (0..self.rows())
            .map(|i| {
                let mut row = vec![0.0; self.columns];
                let (cols, weights) = self.row(i);
                for (&c, &w) in cols.iter().zip(weights) {
                    row[c as usize] = w;
                }
                row
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use mesh_topo::PolygonSoup;

    use super::*;
    use crate::forward::{LoopOptions, subdivide_soup};

    #[test]
    fn from_csr_rejects_an_offset_past_the_entries() {
        // Ends right, middle past the 3 entries: used to panic slicing row 0.
        let error = SubdivisionMatrix::from_csr(2, vec![0, 5, 3], vec![0, 1, 0], vec![1.0; 3]).unwrap_err();
        assert!(matches!(error, LoopError::InvalidParameter { name: "csr", .. }));
    }

    #[test]
    fn get_beyond_u32_columns_is_zero() {
        let s = SubdivisionMatrix::from_csr(2, vec![0, 1], vec![0], vec![0.5]).unwrap();
        assert_eq!(s.get(0, 0), 0.5);
        // `1 << 32` used to be cast to column 0.
        assert_eq!(s.get(0, 1usize << 32), 0.0);
    }

    /// `check_triangles` (in `forward.rs`, whose tests live elsewhere) on malformed
    /// offsets: a typed mesh error, not a slice panic.
    #[test]
    fn subdivide_soup_with_malformed_offsets_is_an_error() {
        for offsets in [vec![0, 5, 3], vec![4, 3], vec![0, 3, 0]] {
            let soup =
                PolygonSoup { positions: vec![DVec3::ZERO, DVec3::X, DVec3::Y], offsets, indices: vec![0, 1, 2] };
            let error = subdivide_soup(&soup, 1, &LoopOptions::default()).unwrap_err();
            assert!(matches!(error, LoopError::Mesh(_)), "{error:?}");
        }
    }
}
