//! A DMS spline whose control net is a triangle mesh: one free control point per mesh
//! vertex, as in the seed paper's pipeline, where the reverse-Loop mesh is the control
//! net of every surface kind.
//!
//! DMS splines have `(n+1)(n+2)/2` control points per triangle, not one per vertex, and
//! the seed paper does not say how its control mesh feeds them (its eqs. (2)–(3) are
//! not a usable definition; see [`crate::dms`]). Our documented choice:
//!
//! 1. **Domain.** The net's parameter triangulation, extended by one ring of *ghost*
//!    triangles outside its boundary: every boundary vertex `p` gets a ghost
//!    `g_p = p + h m_p`, `m_p` the miter of the outward normals of its two boundary edges
//!    (so the ring has constant width `h`, the mean length of those edges), and every
//!    boundary edge `p → q` the quad `(p, g_p, g_q, q)` split along its shorter diagonal.
//!    DMS bases sum to one only where the knot configuration is complete, i.e. away from
//!    the outer boundary of their triangulation; with the ghost ring that region covers
//!    the whole original domain (tested), so the fitted surface is affine invariant up to
//!    the domain's edges. Knot clouds are generated as in
//!    [`DmsBasis::with_generated_knots`], outward on the ghost boundary.
//! 2. **Ghost values.** A ghost's control value is the affine extrapolation of the net
//!    over the boundary triangles at `p` (the mean of the extrapolations from the one or
//!    two triangles holding `p`'s boundary edges): exact for affine data.
//! 3. **Control points.** `c^I_β` is the value at the Greville point `ξ^I_β` (mean of the
//!    blossom arguments) of the affine interpolant of the net over triangle `I`. For
//!    affine data this equals the blossom of the data's affine function at the blossom
//!    arguments, so affine functions are reproduced exactly; in general it is a linear
//!    map `L` (basis functions × net vertices) with rows summing to one.
//!
//! The effective basis of the net is `Ñ_v = sum_b N_b L_bv`: it sums to one on the domain
//! but may dip slightly below zero (ghost extrapolation and Greville points outside their
//! triangle give `L` a few negative weights). Fitting acts on the net vertices; the DMS
//! control points are `L V`.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::domain::{BaryMap, is_degenerate, orient};
use crate::index::multi_indices;
use crate::linalg::SparseMatrix;
use crate::{DmsBasis, KnotPlacement, SplineError};

/// A DMS basis driven by the vertices of a triangle net.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DmsNet {
    /// The DMS basis over the net's triangulation plus its ghost ring.
    pub basis: DmsBasis,
    /// `L`: DMS control points from net vertices (`basis_count × net vertices`).
    pub lift: SparseMatrix,
    /// Number of net vertices.
    pub net_vertices: usize,
    /// Number of triangles of the net (the ghost triangles follow them in the basis).
    pub net_triangles: usize,
}

impl DmsNet {
    /// Builds the basis over the net `(params, triangles)` (counter-clockwise triangles
    /// forming a disk) with a ghost ring.
    ///
    /// # Errors
    /// [`SplineError::BadDomainTriangle`] for a degenerate or clockwise triangle (ghost
    /// triangles are numbered after the net's, e.g. at a reflex boundary corner);
    /// [`SplineError::NotDisk`] if the boundary edges do not form one loop; the knot
    /// errors of [`DmsBasis::new`].
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::{KnotPlacement, dms_net::DmsNet};
    /// let params = vec![DVec2::ZERO, DVec2::X, DVec2::new(0.5, 0.8), DVec2::new(0.5, 0.3)];
    /// let triangles = vec![[0, 1, 3], [1, 2, 3], [2, 0, 3]];
    /// let net = DmsNet::new(&params, &triangles, 2, KnotPlacement::default())?;
    /// assert_eq!(net.lift.cols(), 4);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn new(
        params: &[DVec2],
        triangles: &[[u32; 3]],
        degree: usize,
        placement: KnotPlacement,
    ) -> Result<Self, SplineError> {
        let nv = params.len();
        if let Some(index) = params.iter().position(|p| !p.is_finite()) {
            return Err(SplineError::NonFinite { what: "net vertex parameter", index });
        }
        for (t, tri) in triangles.iter().enumerate() {
            if let Some(&v) = tri.iter().find(|&&v| v as usize >= nv) {
                return Err(SplineError::VertexIndex { triangle: t, vertex: v, vertex_count: nv });
            }
            let [a, b, c] = tri.map(|v| params[v as usize]);
            if is_degenerate(a, b, c) || orient(a, b, c) <= 0.0 {
                return Err(SplineError::BadDomainTriangle { triangle: t, vertices: *tri });
            }
        }
        // Boundary edges (used by one triangle), as directed edges with the interior on
        // the left, and the triangle holding each.
        let mut directed: Vec<((u32, u32), usize)> = Vec::with_capacity(3 * triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            for c in 0..3 {
                directed.push(((tri[c], tri[(c + 1) % 3]), t));
            }
        }
        let mut keys: Vec<(u32, u32)> = directed.iter().map(|&((a, b), _)| (a.min(b), a.max(b))).collect();
        keys.sort_unstable();
        let uses = |a: u32, b: u32| {
            let key = (a.min(b), a.max(b));
            keys.partition_point(|&k| k <= key) - keys.partition_point(|&k| k < key)
        };
        let boundary: Vec<((u32, u32), usize)> = directed.into_iter().filter(|&((a, b), _)| uses(a, b) == 1).collect();
        let mut next_of = vec![u32::MAX; nv];
        let mut edge_triangle = vec![usize::MAX; nv];
        for &((a, b), t) in &boundary {
            if next_of[a as usize] != u32::MAX {
                return Err(not_disk(boundary.len()));
            }
            next_of[a as usize] = b;
            edge_triangle[a as usize] = t;
        }
        let start = boundary.iter().map(|&((a, _), _)| a).min().ok_or(not_disk(0))?;
        let mut ring = vec![start];
        let mut v = next_of[start as usize];
        while v != start {
            if v == u32::MAX || ring.len() > boundary.len() {
                return Err(not_disk(boundary.len()));
            }
            ring.push(v);
            v = next_of[v as usize];
        }
        if ring.len() != boundary.len() {
            return Err(not_disk(boundary.len()));
        }
        // Ghost vertices.
        let len = ring.len();
        let mut prev_of = vec![u32::MAX; nv];
        for i in 0..len {
            prev_of[ring[(i + 1) % len] as usize] = ring[i];
        }
        let outward = |a: DVec2, b: DVec2| {
            let d = (b - a).normalize();
            DVec2::new(d.y, -d.x)
        };
        let mut ghost_index = vec![u32::MAX; nv];
        let mut vertices = params.to_vec();
        let mut weights: Vec<Vec<(usize, f64)>> = (0..nv).map(|v| vec![(v, 1.0)]).collect();
        for &p in &ring {
            let (o, q) = (prev_of[p as usize], next_of[p as usize]);
            let (po, pp, pq) = (params[o as usize], params[p as usize], params[q as usize]);
            let (n1, n2) = (outward(po, pp), outward(pp, pq));
            let mut miter = (n1 + n2) / (1.0 + n1.dot(n2)).max(1e-9);
            if miter.length() > 3.0 {
                miter = miter.normalize() * 3.0;
            }
            let h = 0.5 * ((pp - po).length() + (pq - pp).length());
            let g = pp + miter * h;
            // Affine extrapolation from the triangles of the two boundary edges at p.
            let mut row: Vec<(usize, f64)> = Vec::new();
            let sources = [edge_triangle[o as usize], edge_triangle[p as usize]];
            let distinct = if sources[0] == sources[1] { 1 } else { 2 };
            for &t in &sources[..distinct] {
                let tri = triangles[t];
                let map = BaryMap::new(params[tri[0] as usize], params[tri[1] as usize], params[tri[2] as usize])
                    .expect("internal: triangles were checked");
                let l = map.coords(g);
                for c in 0..3 {
                    row.push((tri[c] as usize, l[c] / distinct as f64));
                }
            }
            ghost_index[p as usize] = vertices.len() as u32;
            vertices.push(g);
            weights.push(row);
        }
        let mut all_triangles = triangles.to_vec();
        for i in 0..len {
            let (p, q) = (ring[i], ring[(i + 1) % len]);
            let (gp, gq) = (ghost_index[p as usize], ghost_index[q as usize]);
            let quality = |t: [u32; 3]| {
                let [a, b, c] = t.map(|v| vertices[v as usize]);
                let longest = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
                orient(a, b, c) / longest
            };
            let split_p = [[p, gp, gq], [p, gq, q]];
            let split_q = [[p, gp, q], [q, gp, gq]];
            let min_q = |s: &[[u32; 3]; 2]| quality(s[0]).min(quality(s[1]));
            let chosen = if min_q(&split_p) >= min_q(&split_q) { split_p } else { split_q };
            all_triangles.extend_from_slice(&chosen);
        }
        let basis = DmsBasis::with_generated_knots(degree, vertices.clone(), all_triangles.clone(), placement)?;
        // L: Greville value of the affine interpolant over each triangle.
        let mut rows = Vec::with_capacity(basis.basis_count());
        for (t, tri) in all_triangles.iter().enumerate() {
            let map = BaryMap::new(vertices[tri[0] as usize], vertices[tri[1] as usize], vertices[tri[2] as usize])
                .expect("internal: triangles were checked by the DMS basis");
            for beta in multi_indices(degree) {
                let xi = basis.greville(basis.basis_index(t, beta));
                let l = map.coords(xi);
                let mut row = Vec::new();
                for c in 0..3 {
                    for &(v, w) in &weights[tri[c] as usize] {
                        row.push((v, l[c] * w));
                    }
                }
                rows.push(row);
            }
        }
        let lift = SparseMatrix::from_rows(nv, rows);
        Ok(Self { basis, lift, net_vertices: nv, net_triangles: triangles.len() })
    }
}

fn not_disk(boundary_edges: usize) -> SplineError {
    SplineError::NotDisk {
        components: 1,
        boundary_loops: usize::from(boundary_edges > 0),
        euler: 0,
        hint: "the control net's boundary edges do not form a single loop",
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DomainTriangle, SurfaceBasis};
    use glam::DVec3;

    /// The regular triangle grid with `n` segments over the equilateral domain.
    fn net(n: usize) -> (Vec<DVec2>, Vec<[u32; 3]>) {
        let d = DomainTriangle::equilateral();
        let params = multi_indices(n)
            .map(|[i, j, k]| d.point([i as f64 / n as f64, j as f64 / n as f64, k as f64 / n as f64]))
            .collect();
        (params, crate::surface::grid_triangles(n, true))
    }

    #[test]
    fn partition_of_unity_and_affine_reproduction_on_the_whole_domain() {
        let d = DomainTriangle::equilateral();
        let (params, triangles) = net(3);
        for degree in [2usize, 3] {
            let dn = DmsNet::new(&params, &triangles, degree, KnotPlacement::default()).unwrap();
            // Samples on the whole closed domain, corners and edges included.
            let s = 17;
            let samples: Vec<DVec2> = multi_indices(s)
                .map(|[i, j, k]| d.point([i as f64 / s as f64, j as f64 / s as f64, k as f64 / s as f64]))
                .collect();
            let n = SurfaceBasis::Dms(dn.basis.clone()).collocation(&samples).unwrap().mul(&dn.lift);
            let affine = |u: DVec2| DVec3::new(2.0 * u.x - u.y + 0.5, u.x + 3.0 * u.y, -u.x + 0.25);
            let values: Vec<DVec3> = params.iter().map(|&u| affine(u)).collect();
            let fitted = n.mul_vec(&values);
            for (i, &u) in samples.iter().enumerate() {
                let sum: f64 = n.row(i).1.iter().sum();
                assert!((sum - 1.0).abs() < 1e-12, "degree {degree}, {u}: {sum}");
                assert!((fitted[i] - affine(u)).length() < 1e-11, "degree {degree}, {u}");
            }
        }
    }

    #[test]
    fn bad_nets_are_rejected() {
        let (params, mut triangles) = net(2);
        triangles[1].swap(0, 1);
        assert!(matches!(
            DmsNet::new(&params, &triangles, 2, KnotPlacement::default()),
            Err(SplineError::BadDomainTriangle { triangle: 1, .. })
        ));
        let (params, triangles) = net(2);
        let mut nan = params.clone();
        nan[2].x = f64::NAN;
        assert!(DmsNet::new(&nan, &triangles, 2, KnotPlacement::default()).is_err());
    }
}
