//! DMS triangular B-splines (Dahmen, Micchelli, Seidel 1992; ALGORITHMS.md §11).
//!
//! Inputs: a proper triangulation `Δ` of the parameter domain (vertices and
//! counter-clockwise triangles), a degree `n`, and for every vertex `i` a knot cloud
//! `t_{i,0} = vertex i, t_{i,1}, …, t_{i,n}`. For triangle `I = (i0, i1, i2)` with clouds
//! `r = cloud(i0)`, `s = cloud(i1)`, `t = cloud(i2)` and `|β| = n`:
//! `V^I_β = {r_0..r_{β0}, s_0..s_{β1}, t_0..t_{β2}}` (`n + 3` knots) and
//! `N^I_β(u) = |det(r_{β0}, s_{β1}, t_{β2})| M(u | V^I_β)` with the simplex spline `M`
//! of [`crate::simplex`]. The spline is `F(u) = sum_I sum_β c^I_β N^I_β(u)`.
//!
//! Knot conditions, checked when the basis is built (typed errors name the triangle and
//! knots): every triangle of `Δ` is counter-clockwise and non-degenerate; for every `I`
//! and `i + j + k <= n` the knot triangle `(r_i, s_j, t_k)` is non-degenerate and
//! counter-clockwise; the `3n + 3` knots of each triangle are in general position (no
//! three collinear, which also excludes coincident knots).
//!
//! Properties (tested): the `N^I_β` are non-negative and sum to one wherever the
//! configuration is complete (away from the outer boundary of `Δ`, whose missing
//! neighbours would contribute near it); with `c^I_β = F_P(r_0..r_{β0-1},
//! s_0..s_{β1-1}, t_0..t_{β2-1})` (blossom of a polynomial `P` of degree `n`) the spline
//! reproduces `P` on the same region; the value does not depend on the recurrence's
//! choice of `W`; the spline is `C^{n-1}` for knots in general position.
//!
//! Evaluation (§11.3): a uniform grid over the bounding boxes of the triangles' knot
//! sets lists the candidate triangles of a query point; for each, the simplex splines of
//! its `(n+1)(n+2)/2` functions are evaluated by the recurrence memoised over subsets of
//! the triangle's `3n + 3` knots (the `V^I_β` are nested subsets of one set), with the
//! half-open rule making sums exact on knot lines.
//!
//! Note on seed 001, eqs. (2)–(3) (ALGORITHMS.md §11.5, erratum): the seed defines its
//! "triangular B-spline" basis as a product of three univariate B-splines along the
//! barycentric directions "of degree r + s + t - 2". A product of univariate B-splines of
//! degrees r, s, t has degree r + s + t; the degree r + s + t - 2 belongs to the
//! three-direction box spline (a convolution). That formula is not a usable definition;
//! this module implements DMS splines as defined above instead.
//!
//! References: W. Dahmen, C. A. Micchelli, H.-P. Seidel, Blossoming begets B-spline
//! bases built better by B-patches, Math. Comp. 59 (1992) 97–115; P. Fong, H.-P. Seidel,
//! An implementation of triangular B-spline surfaces over arbitrary triangulations,
//! CAGD 10 (1993) 267–275.

use glam::{DVec2, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::SplineError;
use crate::domain::{is_degenerate, orient};
use crate::index::multi_indices;
use crate::point::Point;
use crate::simplex::{Memo, SimplexRecurrence, WChoice};

/// Largest supported DMS degree (each triangle has `3n + 3` knots; the memo table grows
/// quickly with `n`; degrees 2 and 3 are the practical ones).
pub const MAX_DMS_DEGREE: usize = 6;

/// A uniform grid over the plane listing, per cell, the triangles whose knot bounding
/// box meets the cell.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct SupportGrid {
    origin: DVec2,
    inv_cell: DVec2,
    nx: usize,
    ny: usize,
    /// `cell_start[c]..cell_start[c + 1]` indexes `items` for cell `c`.
    cell_start: Vec<u32>,
    items: Vec<u32>,
}

impl SupportGrid {
    fn new(boxes: &[[DVec2; 2]]) -> Self {
        let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
        for b in boxes {
            lo = lo.min(b[0]);
            hi = hi.max(b[1]);
        }
        let extent = (hi - lo).max(DVec2::splat(1e-300));
        // About one cell per box, in the aspect ratio of the domain.
        let cells = (boxes.len().max(1) as f64).max(1.0);
        let aspect = extent.x / extent.y;
        let nx = ((cells * aspect).sqrt().ceil() as usize).clamp(1, 4096);
        let ny = ((cells / aspect).sqrt().ceil() as usize).clamp(1, 4096);
        let inv_cell = DVec2::new(nx as f64 / extent.x, ny as f64 / extent.y);
        let cell_range = |b: &[DVec2; 2]| {
            let a = ((b[0] - lo) * inv_cell).floor();
            let z = ((b[1] - lo) * inv_cell).floor();
            let clamp = |v: f64, n: usize| (v.max(0.0) as usize).min(n - 1);
            (clamp(a.x, nx), clamp(z.x, nx), clamp(a.y, ny), clamp(z.y, ny))
        };
        let mut counts = vec![0u32; nx * ny + 1];
        for b in boxes {
            let (x0, x1, y0, y1) = cell_range(b);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    counts[y * nx + x + 1] += 1;
                }
            }
        }
        for c in 0..nx * ny {
            counts[c + 1] += counts[c];
        }
        let mut fill = counts.clone();
        let mut items = vec![0u32; counts[nx * ny] as usize];
        for (i, b) in boxes.iter().enumerate() {
            let (x0, x1, y0, y1) = cell_range(b);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let c = y * nx + x;
                    items[fill[c] as usize] = i as u32;
                    fill[c] += 1;
                }
            }
        }
        Self { origin: lo, inv_cell, nx, ny, cell_start: counts, items }
    }

    /// Candidate triangles for `u`, ascending.
    fn candidates(&self, u: DVec2) -> &[u32] {
        let p = (u - self.origin) * self.inv_cell;
        if !(p.x >= 0.0 && p.y >= 0.0) {
            return &[];
        }
        // Points on the far boundary belong to the last cell.
        let (x, y) = (p.x.floor() as usize, p.y.floor() as usize);
        let x = if x == self.nx && p.x == self.nx as f64 { x - 1 } else { x };
        let y = if y == self.ny && p.y == self.ny as f64 { y - 1 } else { y };
        if x >= self.nx || y >= self.ny {
            return &[];
        }
        let c = y * self.nx + x;
        &self.items[self.cell_start[c] as usize..self.cell_start[c + 1] as usize]
    }
}

/// How [`DmsBasis::with_generated_knots`] places the extra knots of each vertex.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KnotPlacement {
    /// Knots lie within this fraction of the vertex's shortest incident edge.
    pub radius: f64,
    /// Seed of the random offsets (the result is a deterministic function of it).
    pub seed: u64,
    /// Place the knots of boundary vertices outside the triangulation (Fong–Seidel
    /// practice), within the outward half-disk.
    pub boundary_outward: bool,
}

impl Default for KnotPlacement {
    fn default() -> Self {
        Self { radius: 0.15, seed: 0x5eed, boundary_outward: true }
    }
}

/// Scratch memory for DMS evaluation (the simplex-spline memo); reuse it across calls.
#[derive(Debug, Default, Clone)]
pub struct DmsScratch {
    memo: Memo,
}

/// The DMS basis over a triangulation with knot clouds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DmsBasis {
    degree: usize,
    vertices: Vec<DVec2>,
    triangles: Vec<[u32; 3]>,
    /// `n + 1` knots per vertex, the vertex itself first.
    clouds: Vec<DVec2>,
    /// Per triangle its `3n + 3` knots `r_0..r_n, s_0..s_n, t_0..t_n`.
    tri_knots: Vec<DVec2>,
    /// `|det(r_{β0}, s_{β1}, t_{β2})|` per basis function.
    scales: Vec<f64>,
    /// Knot subset `V^I_β` of each multi-index (same for every triangle), as a mask over
    /// the triangle's knots.
    masks: Vec<u64>,
    /// Bounding box of each triangle's knots.
    boxes: Vec<[DVec2; 2]>,
    grid: SupportGrid,
}

impl DmsBasis {
    /// The basis of degree `degree` over the triangulation `(vertices, triangles)` with
    /// the given extra knots: `degree` per vertex, vertex `v`'s at
    /// `extra_knots[v * degree .. (v + 1) * degree]` (its first knot is the vertex).
    ///
    /// # Errors
    /// [`SplineError::Degree`] outside `1..=MAX_DMS_DEGREE`; [`SplineError::Count`],
    /// [`SplineError::NonFinite`], [`SplineError::VertexIndex`] for malformed input;
    /// [`SplineError::BadDomainTriangle`] for a degenerate or clockwise triangle;
    /// [`SplineError::DmsKnotOrientation`] and [`SplineError::CollinearKnots`] for
    /// knots violating the DMS conditions (module docs).
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::DmsBasis;
    /// // Two triangles of the unit square, degree 1, one extra knot per vertex.
    /// let vertices = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let triangles = vec![[0, 1, 2], [0, 2, 3]];
    /// let extra = vec![
    ///     DVec2::new(-0.1, -0.05), DVec2::new(1.1, -0.07),
    ///     DVec2::new(1.05, 1.1), DVec2::new(-0.08, 1.06),
    /// ];
    /// let basis = DmsBasis::new(1, vertices, triangles, extra)?;
    /// let values = basis.eval_basis(DVec2::new(0.5, 0.45));
    /// assert!(values.iter().all(|&(_, v)| v >= 0.0));
    /// assert_eq!(basis.basis_count(), 6);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn new(
        degree: usize,
        vertices: Vec<DVec2>,
        triangles: Vec<[u32; 3]>,
        extra_knots: Vec<DVec2>,
    ) -> Result<Self, SplineError> {
        if !(1..=MAX_DMS_DEGREE).contains(&degree) {
            return Err(SplineError::Degree { degree, min: 1, max: MAX_DMS_DEGREE });
        }
        let n = degree;
        if let Some(index) = vertices.iter().position(|p| !p.is_finite()) {
            return Err(SplineError::NonFinite { what: "vertex", index });
        }
        if extra_knots.len() != vertices.len() * n {
            return Err(SplineError::Count {
                what: "extra knots (degree per vertex)",
                expected: vertices.len() * n,
                got: extra_knots.len(),
            });
        }
        if let Some(index) = extra_knots.iter().position(|p| !p.is_finite()) {
            return Err(SplineError::NonFinite { what: "knot", index });
        }
        for (t, tri) in triangles.iter().enumerate() {
            if let Some(&v) = tri.iter().find(|&&v| v as usize >= vertices.len()) {
                return Err(SplineError::VertexIndex { triangle: t, vertex: v, vertex_count: vertices.len() });
            }
            let [a, b, c] = tri.map(|v| vertices[v as usize]);
            if is_degenerate(a, b, c) || orient(a, b, c) <= 0.0 {
                return Err(SplineError::BadDomainTriangle { triangle: t, vertices: *tri });
            }
        }
        let mut clouds = Vec::with_capacity(vertices.len() * (n + 1));
        for (v, &p) in vertices.iter().enumerate() {
            clouds.push(p);
            clouds.extend_from_slice(&extra_knots[v * n..(v + 1) * n]);
        }
        let k = n + 1;
        let mut tri_knots = Vec::with_capacity(triangles.len() * 3 * k);
        for tri in &triangles {
            for &v in tri {
                tri_knots.extend_from_slice(&clouds[v as usize * k..(v as usize + 1) * k]);
            }
        }
        // Knot conditions.
        for (t, tri) in triangles.iter().enumerate() {
            let knots = &tri_knots[t * 3 * k..(t + 1) * 3 * k];
            for d in 0..=n {
                for [i, j, l] in multi_indices(d) {
                    let (a, b, c) = (knots[i], knots[k + j], knots[2 * k + l]);
                    if is_degenerate(a, b, c) || orient(a, b, c) <= 0.0 {
                        return Err(SplineError::DmsKnotOrientation { triangle: t, i, j, k: l });
                    }
                }
            }
            let name = |p: usize| (tri[p / k], p % k);
            for a in 0..3 * k {
                for b in a + 1..3 * k {
                    for c in b + 1..3 * k {
                        if is_degenerate(knots[a], knots[b], knots[c]) {
                            return Err(SplineError::CollinearKnots {
                                triangle: t,
                                knots: [name(a), name(b), name(c)],
                            });
                        }
                    }
                }
            }
        }
        let masks: Vec<u64> = multi_indices(n)
            .map(|[i, j, l]| {
                let run = |start: usize, len: usize| ((1u64 << (len + 1)) - 1) << start;
                run(0, i) | run(k, j) | run(2 * k, l)
            })
            .collect();
        let mut scales = Vec::with_capacity(triangles.len() * masks.len());
        let mut boxes = Vec::with_capacity(triangles.len());
        for t in 0..triangles.len() {
            let knots = &tri_knots[t * 3 * k..(t + 1) * 3 * k];
            for [i, j, l] in multi_indices(n) {
                scales.push(orient(knots[i], knots[k + j], knots[2 * k + l]).abs());
            }
            let lo = knots.iter().fold(DVec2::INFINITY, |m, &p| m.min(p));
            let hi = knots.iter().fold(DVec2::NEG_INFINITY, |m, &p| m.max(p));
            boxes.push([lo, hi]);
        }
        let grid = SupportGrid::new(&boxes);
        Ok(Self { degree, vertices, triangles, clouds, tri_knots, scales, masks, boxes, grid })
    }

    /// The basis with generated knot clouds: each vertex gets `degree` extra knots at
    /// seeded random offsets within `placement.radius` times its shortest incident edge
    /// (outward for boundary vertices when asked). If the knot conditions fail, the
    /// radius is halved and the seed advanced, up to 12 times; the last error is returned.
    ///
    /// # Errors
    /// As [`new`](Self::new) (for the triangulation itself, or when no placement passes).
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::{DmsBasis, KnotPlacement, SplineError};
    /// // The two triangles of the unit square, degree 2: six functions per triangle.
    /// let vertices = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let triangles = vec![[0, 1, 2], [0, 2, 3]];
    /// let basis = DmsBasis::with_generated_knots(2, vertices.clone(), triangles.clone(), KnotPlacement::default())?;
    /// assert_eq!((basis.degree(), basis.basis_count()), (2, 12));
    /// // A partition of unity inside.
    /// let sum: f64 = basis.eval_basis(DVec2::new(0.3, 0.6)).iter().map(|&(_, v)| v).sum();
    /// assert!((sum - 1.0).abs() < 1e-12);
    /// let clockwise = vec![[0, 2, 1], [0, 2, 3]];
    /// let bad = DmsBasis::with_generated_knots(2, vertices, clockwise, KnotPlacement::default());
    /// assert!(matches!(bad, Err(SplineError::BadDomainTriangle { triangle: 0, .. })));
    /// # Ok::<(), SplineError>(())
    /// ```
    pub fn with_generated_knots(
        degree: usize,
        vertices: Vec<DVec2>,
        triangles: Vec<[u32; 3]>,
        placement: KnotPlacement,
    ) -> Result<Self, SplineError> {
        // Checked before `generate_knots` allocates `degree` knots per vertex.
        if !(1..=MAX_DMS_DEGREE).contains(&degree) {
            return Err(SplineError::Degree { degree, min: 1, max: MAX_DMS_DEGREE });
        }
        let mut last = None;
        let mut radius = placement.radius;
        for attempt in 0..12u64 {
            let extra = generate_knots(
                degree,
                &vertices,
                &triangles,
                radius,
                placement.seed.wrapping_add(attempt),
                placement.boundary_outward,
            )?;
            match Self::new(degree, vertices.clone(), triangles.clone(), extra) {
                Ok(basis) => return Ok(basis),
                Err(e @ (SplineError::DmsKnotOrientation { .. } | SplineError::CollinearKnots { .. })) => {
                    last = Some(e);
                    if attempt % 2 == 1 {
                        radius *= 0.5;
                    }
                }
                Err(e) => return Err(e),
            }
        }
        Err(last.expect("internal: at least one attempt"))
    }

    /// The degree `n`.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The triangulation's vertices.
    pub fn vertices(&self) -> &[DVec2] {
        &self.vertices
    }

    /// The triangulation's triangles.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The knot cloud of vertex `v` (`n + 1` knots, the vertex first).
    ///
    /// # Panics
    /// If `v` is not a vertex (the message names it and the vertex count);
    /// [`try_cloud`](Self::try_cloud) returns an error instead.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// let cloud = basis.cloud(2);
    /// assert_eq!(cloud.len(), 3);
    /// assert_eq!(cloud[0], DVec2::ONE);
    /// // Boundary knots lie outside the square (`KnotPlacement::boundary_outward`).
    /// assert!(cloud[1..].iter().all(|k| k.x > 1.0 || k.y > 1.0));
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn cloud(&self, v: usize) -> &[DVec2] {
        self.try_cloud(v).unwrap_or_else(|e| panic!("DmsBasis::cloud: {e}"))
    }

    /// The knot cloud of vertex `v`, for an index given by a caller.
    ///
    /// # Errors
    /// [`SplineError::IndexOutOfRange`] if `v` is not a vertex.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// # use tri_spline::SplineError;
    /// assert_eq!(basis.try_cloud(1)?[0], DVec2::X);
    /// assert!(matches!(basis.try_cloud(4), Err(SplineError::IndexOutOfRange { what: "vertex", index: 4, len: 4 })));
    /// # Ok::<(), SplineError>(())
    /// ```
    pub fn try_cloud(&self, v: usize) -> Result<&[DVec2], SplineError> {
        if v >= self.vertices.len() {
            return Err(SplineError::IndexOutOfRange { what: "vertex", index: v, len: self.vertices.len() });
        }
        let k = self.degree + 1;
        Ok(&self.clouds[v * k..(v + 1) * k])
    }

    /// Number of basis functions: `(n + 1)(n + 2)/2` per triangle.
    pub fn basis_count(&self) -> usize {
        self.triangles.len() * self.masks.len()
    }

    /// Index of `N^I_β` (triangle-major, multi-indices in [`crate::index`] order).
    ///
    /// # Panics
    /// If `triangle` is not a triangle or `|β|` is not the degree (it used to return the
    /// index of another basis function, or one beyond them all);
    /// [`try_basis_index`](Self::try_basis_index) returns an error instead.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// // Six functions per triangle, multi-indices in storage order: triangle 1 starts at 6.
    /// assert_eq!(basis.basis_index(0, [2, 0, 0]), 0);
    /// assert_eq!(basis.basis_index(1, [1, 1, 0]), 7);
    /// assert_eq!(basis.basis_index(1, [0, 0, 2]), 11);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn basis_index(&self, triangle: usize, beta: [usize; 3]) -> usize {
        self.try_basis_index(triangle, beta).unwrap_or_else(|e| panic!("DmsBasis::basis_index: {e}"))
    }

    /// Index of `N^I_β`, for a triangle and multi-index given by a caller.
    ///
    /// # Errors
    /// [`SplineError::IndexOutOfRange`] if `triangle` is not a triangle,
    /// [`SplineError::MultiIndexDegree`] unless `β0 + β1 + β2` is the degree.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::{DmsBasis, SplineError};
    /// let extra = vec![DVec2::new(-0.1, -0.05), DVec2::new(1.1, -0.07), DVec2::new(-0.08, 1.06)];
    /// let basis = DmsBasis::new(1, vec![DVec2::ZERO, DVec2::X, DVec2::Y], vec![[0, 1, 2]], extra)?;
    /// assert_eq!(basis.try_basis_index(0, [0, 0, 1])?, 2);
    /// assert!(matches!(basis.try_basis_index(1, [1, 0, 0]), Err(SplineError::IndexOutOfRange { what: "triangle", .. })));
    /// assert!(matches!(basis.try_basis_index(0, [1, 1, 0]), Err(SplineError::MultiIndexDegree { degree: 1, .. })));
    /// # Ok::<(), SplineError>(())
    /// ```
    pub fn try_basis_index(&self, triangle: usize, beta: [usize; 3]) -> Result<usize, SplineError> {
        self.check_basis_function(triangle, beta)?;
        Ok(triangle * self.masks.len() + crate::index::beta_index(beta))
    }

    /// Whether `N^I_β` exists: `triangle` is a triangle and `|β|` is the degree.
    fn check_basis_function(&self, triangle: usize, beta: [usize; 3]) -> Result<(), SplineError> {
        if triangle >= self.triangles.len() {
            return Err(SplineError::IndexOutOfRange { what: "triangle", index: triangle, len: self.triangles.len() });
        }
        if beta[0].checked_add(beta[1]).and_then(|s| s.checked_add(beta[2])) != Some(self.degree) {
            return Err(SplineError::MultiIndexDegree { beta, degree: self.degree });
        }
        Ok(())
    }

    /// The blossom arguments `r_0..r_{β0-1}, s_0..s_{β1-1}, t_0..t_{β2-1}` of the control
    /// point `c^I_β`: with `c^I_β = F_P(args)` the spline reproduces the polynomial `P`.
    ///
    /// # Panics
    /// As [`basis_index`](Self::basis_index); [`try_blossom_args`](Self::try_blossom_args)
    /// returns an error instead.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// // Triangle 1 is (0, 2, 3): r, s, t are the clouds of vertices 0, 2 and 3.
    /// assert_eq!(basis.blossom_args(1, [1, 0, 1]), vec![DVec2::ZERO, DVec2::Y]);
    /// assert_eq!(basis.blossom_args(1, [0, 2, 0]), basis.cloud(2)[..2].to_vec());
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn blossom_args(&self, triangle: usize, beta: [usize; 3]) -> Vec<DVec2> {
        self.try_blossom_args(triangle, beta).unwrap_or_else(|e| panic!("DmsBasis::blossom_args: {e}"))
    }

    /// The blossom arguments of `c^I_β`, for a triangle and multi-index given by a caller.
    ///
    /// # Errors
    /// As [`try_basis_index`](Self::try_basis_index).
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// # use tri_spline::SplineError;
    /// assert_eq!(basis.try_blossom_args(0, [1, 1, 0])?, vec![DVec2::ZERO, DVec2::X]);
    /// assert!(matches!(basis.try_blossom_args(0, [1, 0, 0]), Err(SplineError::MultiIndexDegree { degree: 2, .. })));
    /// assert!(matches!(basis.try_blossom_args(2, [2, 0, 0]), Err(SplineError::IndexOutOfRange { .. })));
    /// # Ok::<(), SplineError>(())
    /// ```
    pub fn try_blossom_args(&self, triangle: usize, beta: [usize; 3]) -> Result<Vec<DVec2>, SplineError> {
        self.check_basis_function(triangle, beta)?;
        let k = self.degree + 1;
        let knots = self.triangle_knots(triangle);
        let mut args = Vec::with_capacity(self.degree);
        args.extend_from_slice(&knots[..beta[0]]);
        args.extend_from_slice(&knots[k..k + beta[1]]);
        args.extend_from_slice(&knots[2 * k..2 * k + beta[2]]);
        Ok(args)
    }

    /// The Greville point of basis function `index`: the mean of its blossom arguments
    /// (a linear function's control point is its value there).
    ///
    /// # Panics
    /// If `index >= basis_count()` (the message names both);
    /// [`try_greville`](Self::try_greville) returns an error instead.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, DmsSpline, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// // Control points f(Greville point) reproduce a linear function f.
    /// let f = |p: DVec2| 2.0 * p.x - p.y + 1.0;
    /// let control = (0..basis.basis_count()).map(|i| f(basis.greville(i))).collect();
    /// let spline = DmsSpline::new(basis, control)?;
    /// let u = DVec2::new(0.3, 0.6);
    /// assert!((spline.eval(u) - f(u)).abs() < 1e-12);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn greville(&self, index: usize) -> DVec2 {
        self.try_greville(index).unwrap_or_else(|e| panic!("DmsBasis::greville: {e}"))
    }

    /// The Greville point of basis function `index`, for an index given by a caller.
    ///
    /// # Errors
    /// [`SplineError::IndexOutOfRange`] if `index >= basis_count()`.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// // N^0_(1,1,0) has the blossom arguments r_0 = (0, 0) and s_0 = (1, 0).
    /// assert_eq!(basis.try_greville(basis.basis_index(0, [1, 1, 0]))?, DVec2::new(0.5, 0.0));
    /// assert!(basis.try_greville(12).is_err());
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn try_greville(&self, index: usize) -> Result<DVec2, SplineError> {
        self.check_basis_function_index(index)?;
        let nb = self.masks.len();
        let beta = multi_indices(self.degree).nth(index % nb).expect("internal: multi-index");
        let args = self.try_blossom_args(index / nb, beta)?;
        Ok(args.iter().copied().sum::<DVec2>() / self.degree as f64)
    }

    fn check_basis_function_index(&self, index: usize) -> Result<(), SplineError> {
        if index >= self.basis_count() {
            return Err(SplineError::IndexOutOfRange { what: "basis function", index, len: self.basis_count() });
        }
        Ok(())
    }

    /// The non-zero basis functions at `u` as `(index, value)`, ascending by index.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// let values = basis.eval_basis(DVec2::new(0.5, 0.45));
    /// assert!(values.windows(2).all(|w| w[0].0 < w[1].0));
    /// assert!(values.iter().all(|&(_, v)| v > 0.0));
    /// assert!((values.iter().map(|&(_, v)| v).sum::<f64>() - 1.0).abs() < 1e-12);
    /// // Far outside every knot cloud: none.
    /// assert!(basis.eval_basis(DVec2::splat(5.0)).is_empty());
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval_basis(&self, u: DVec2) -> Vec<(usize, f64)> {
        let mut out = Vec::new();
        self.eval_basis_with(u, &mut DmsScratch::default(), &mut out);
        out
    }

    /// As [`eval_basis`](Self::eval_basis) with caller-provided scratch and output.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// # use tri_spline::DmsScratch;
    /// let (mut scratch, mut values) = (DmsScratch::default(), Vec::new());
    /// for u in [DVec2::new(0.5, 0.45), DVec2::new(0.1, 0.8), DVec2::new(0.9, 0.2)] {
    ///     basis.eval_basis_with(u, &mut scratch, &mut values);
    ///     assert_eq!(values, basis.eval_basis(u));
    /// }
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval_basis_with(&self, u: DVec2, scratch: &mut DmsScratch, out: &mut Vec<(usize, f64)>) {
        out.clear();
        let nb = self.masks.len();
        self.for_each_triangle_at(u, &mut scratch.memo, |t, rec| {
            for (b, &mask) in self.masks.iter().enumerate() {
                let m = rec.value(mask);
                if m != 0.0 {
                    out.push((t * nb + b, self.scales[t * nb + b] * m));
                }
            }
        });
    }

    /// The non-zero basis functions at `u` with their gradients: `(index, value, d/dx, d/dy)`.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// # use tri_spline::DmsScratch;
    /// let mut out = Vec::new();
    /// basis.eval_basis_gradient_with(DVec2::new(0.3, 0.6), &mut DmsScratch::default(), &mut out);
    /// // The basis sums to one, so the gradients sum to zero.
    /// assert!((out.iter().map(|e| e.1).sum::<f64>() - 1.0).abs() < 1e-12);
    /// assert!(out.iter().map(|e| e.2).sum::<DVec2>().length() < 1e-12);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval_basis_gradient_with(&self, u: DVec2, scratch: &mut DmsScratch, out: &mut Vec<(usize, f64, DVec2)>) {
        out.clear();
        let nb = self.masks.len();
        self.for_each_triangle_at(u, &mut scratch.memo, |t, rec| {
            for (b, &mask) in self.masks.iter().enumerate() {
                let scale = self.scales[t * nb + b];
                let m = rec.value(mask);
                let gx = rec.derivative(mask, DVec2::X);
                let gy = rec.derivative(mask, DVec2::Y);
                if m != 0.0 || gx != 0.0 || gy != 0.0 {
                    out.push((t * nb + b, scale * m, DVec2::new(gx, gy) * scale));
                }
            }
        });
    }

    /// Calls `visit(t, recurrence)` for every domain triangle `t` whose bounding box holds
    /// `u` (the only ones whose basis functions can be non-zero there), with the simplex
    /// recurrence over that triangle's knot sets, its memo reset.
    fn for_each_triangle_at(
        &self,
        u: DVec2,
        memo: &mut Memo,
        mut visit: impl FnMut(usize, &mut SimplexRecurrence<'_>),
    ) {
        for &t in self.grid.candidates(u) {
            let t = t as usize;
            let [lo, hi] = self.boxes[t];
            if u.x < lo.x || u.y < lo.y || u.x > hi.x || u.y > hi.y {
                continue;
            }
            memo.reset(3 * (self.degree + 1));
            let mut rec =
                SimplexRecurrence { knots: self.triangle_knots(t), u, choice: WChoice::Widest, memo, degenerate: None };
            visit(t, &mut rec);
            debug_assert!(rec.degenerate.is_none(), "internal: knots were checked to be in general position");
        }
    }

    /// The `3 (degree + 1)` knots of domain triangle `t`.
    fn triangle_knots(&self, t: usize) -> &[DVec2] {
        let k = self.degree + 1;
        &self.tri_knots[t * 3 * k..(t + 1) * 3 * k]
    }

    /// Evaluates one basis function with a chosen `W` rule (for testing that the value
    /// does not depend on it).
    ///
    /// # Panics
    /// If `index >= basis_count()` (the message names both);
    /// [`try_eval_one_with`](Self::try_eval_one_with) returns an error instead.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// # use tri_spline::WChoice;
    /// let u = DVec2::new(0.5, 0.45);
    /// for (index, value) in basis.eval_basis(u) {
    ///     for choice in [WChoice::Widest, WChoice::First, WChoice::Last, WChoice::Spread] {
    ///         assert!((basis.eval_one_with(index, u, choice) - value).abs() < 1e-10);
    ///     }
    /// }
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval_one_with(&self, index: usize, u: DVec2, choice: WChoice) -> f64 {
        self.try_eval_one_with(index, u, choice).unwrap_or_else(|e| panic!("DmsBasis::eval_one_with: {e}"))
    }

    /// Evaluates basis function `index` with a chosen `W` rule, for an index given by a
    /// caller.
    ///
    /// # Errors
    /// [`SplineError::IndexOutOfRange`] if `index >= basis_count()`.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// # use tri_spline::WChoice;
    /// let u = DVec2::new(0.5, 0.45);
    /// assert!(basis.try_eval_one_with(0, u, WChoice::First)? >= 0.0);
    /// assert!(basis.try_eval_one_with(12, u, WChoice::First).is_err());
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn try_eval_one_with(&self, index: usize, u: DVec2, choice: WChoice) -> Result<f64, SplineError> {
        self.check_basis_function_index(index)?;
        let nb = self.masks.len();
        let t = index / nb;
        let mut memo = Memo::default();
        memo.reset(3 * (self.degree + 1));
        let mut rec = SimplexRecurrence { knots: self.triangle_knots(t), u, choice, memo: &mut memo, degenerate: None };
        Ok(self.scales[index] * rec.value(self.masks[index % nb]))
    }
}

/// Seeded knot clouds for [`DmsBasis::with_generated_knots`].
fn generate_knots(
    degree: usize,
    vertices: &[DVec2],
    triangles: &[[u32; 3]],
    radius: f64,
    seed: u64,
    boundary_outward: bool,
) -> Result<Vec<DVec2>, SplineError> {
    let nv = vertices.len();
    let mut shortest = vec![f64::INFINITY; nv];
    // Outward direction of boundary vertices: sum of the outward normals of their
    // boundary edges (an edge is on the boundary when only one triangle uses it).
    let mut edges: Vec<(u32, u32)> = Vec::with_capacity(triangles.len() * 3);
    for (t, tri) in triangles.iter().enumerate() {
        for c in 0..3 {
            let (a, b) = (tri[c], tri[(c + 1) % 3]);
            if a as usize >= nv || b as usize >= nv {
                return Err(SplineError::VertexIndex { triangle: t, vertex: a.max(b), vertex_count: nv });
            }
            let len = (vertices[a as usize] - vertices[b as usize]).length();
            shortest[a as usize] = shortest[a as usize].min(len);
            shortest[b as usize] = shortest[b as usize].min(len);
            edges.push((a, b));
        }
    }
    let mut sorted: Vec<(u32, u32)> = edges.iter().map(|&(a, b)| (a.min(b), a.max(b))).collect();
    sorted.sort_unstable();
    let mut outward = vec![DVec2::ZERO; nv];
    for &(a, b) in &edges {
        let key = (a.min(b), a.max(b));
        let count = sorted.partition_point(|&e| e <= key) - sorted.partition_point(|&e| e < key);
        if count == 1 {
            // Triangles are counter-clockwise, so the outside is on the right of a -> b.
            let d = vertices[b as usize] - vertices[a as usize];
            let normal = DVec2::new(d.y, -d.x).normalize_or_zero();
            outward[a as usize] += normal;
            outward[b as usize] += normal;
        }
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut extra = Vec::with_capacity(nv * degree);
    for v in 0..nv {
        let h = if shortest[v].is_finite() { shortest[v] } else { 1.0 };
        let out = outward[v].normalize_or_zero();
        for _ in 0..degree {
            let mut offset;
            loop {
                offset = DVec2::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
                let len = offset.length();
                if (0.25..=1.0).contains(&len) {
                    break;
                }
            }
            if boundary_outward && out != DVec2::ZERO && offset.dot(out) < 0.0 {
                offset -= out * (2.0 * offset.dot(out));
            }
            extra.push(vertices[v] + offset * (radius * h));
        }
    }
    Ok(extra)
}

/// A DMS spline surface: a basis and one control point per basis function.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DmsSpline<P = DVec3> {
    basis: DmsBasis,
    control: Vec<P>,
}

impl<P: Point> DmsSpline<P> {
    /// The spline with `control[i]` for basis function `i`.
    ///
    /// # Errors
    /// [`SplineError::Count`], [`SplineError::NonFinite`].
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, DmsSpline, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// // Equal control points: a constant (the basis sums to one).
    /// let spline = DmsSpline::new(basis.clone(), vec![4.0; 12])?;
    /// assert!((spline.eval(DVec2::new(0.3, 0.6)) - 4.0).abs() < 1e-12);
    /// assert!(DmsSpline::new(basis.clone(), vec![4.0; 11]).is_err());
    /// assert!(DmsSpline::new(basis, vec![f64::INFINITY; 12]).is_err());
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn new(basis: DmsBasis, control: Vec<P>) -> Result<Self, SplineError> {
        if control.len() != basis.basis_count() {
            return Err(SplineError::Count {
                what: "DMS control points",
                expected: basis.basis_count(),
                got: control.len(),
            });
        }
        if let Some(index) = control.iter().position(|p| !p.is_finite_point()) {
            return Err(SplineError::NonFinite { what: "control point", index });
        }
        Ok(Self { basis, control })
    }

    /// The control points that reproduce a polynomial with blossom `blossom` (called
    /// with the `n` blossom arguments of each control point).
    ///
    /// # Errors
    /// As [`new`](Self::new).
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, DmsSpline, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// // x y has the blossom F(a, b) = (a.x b.y + b.x a.y) / 2 and is reproduced.
    /// let xy = DmsSpline::from_blossom(basis, |a: &[DVec2]| (a[0].x * a[1].y + a[1].x * a[0].y) / 2.0)?;
    /// for u in [DVec2::new(0.5, 0.45), DVec2::new(0.1, 0.8)] {
    ///     assert!((xy.eval(u) - u.x * u.y).abs() < 1e-12);
    /// }
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn from_blossom(basis: DmsBasis, blossom: impl Fn(&[DVec2]) -> P) -> Result<Self, SplineError> {
        let n = basis.degree();
        let mut control = Vec::with_capacity(basis.basis_count());
        for t in 0..basis.triangles().len() {
            for beta in multi_indices(n) {
                control.push(blossom(&basis.blossom_args(t, beta)));
            }
        }
        Self::new(basis, control)
    }

    /// The basis.
    pub fn basis(&self) -> &DmsBasis {
        &self.basis
    }

    /// The control points (one per basis function).
    pub fn control_points(&self) -> &[P] {
        &self.control
    }

    /// `F(u)`.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, DmsSpline, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// // A linear function's blossom is its mean over the arguments: reproduced exactly.
    /// let f = |p: DVec2| 2.0 * p.x - p.y + 1.0;
    /// let spline = DmsSpline::from_blossom(basis, |a: &[DVec2]| a.iter().map(|&p| f(p)).sum::<f64>() / a.len() as f64)?;
    /// let u = DVec2::new(0.7, 0.2);
    /// assert!((spline.eval(u) - f(u)).abs() < 1e-12);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval(&self, u: DVec2) -> P {
        self.eval_with(u, &mut DmsScratch::default(), &mut Vec::new())
    }

    /// `F(u)` with reusable scratch memory.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, DmsSpline, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// # use tri_spline::DmsScratch;
    /// let spline = DmsSpline::new(basis, (0..12).map(|i| i as f64).collect())?;
    /// let (mut scratch, mut values) = (DmsScratch::default(), Vec::new());
    /// for u in [DVec2::new(0.5, 0.45), DVec2::new(0.1, 0.8)] {
    ///     assert_eq!(spline.eval_with(u, &mut scratch, &mut values), spline.eval(u));
    /// }
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval_with(&self, u: DVec2, scratch: &mut DmsScratch, values: &mut Vec<(usize, f64)>) -> P {
        self.basis.eval_basis_with(u, scratch, values);
        values.iter().fold(P::ZERO, |sum, &(i, v)| sum + self.control[i] * v)
    }

    /// `F(u)` and its partial derivatives along the domain axes.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, DmsSpline, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// // x y (see `from_blossom`): gradient (y, x).
    /// let xy = DmsSpline::from_blossom(basis, |a: &[DVec2]| (a[0].x * a[1].y + a[1].x * a[0].y) / 2.0)?;
    /// let (value, [dx, dy]) = xy.eval_with_gradient(DVec2::new(0.3, 0.6));
    /// assert!((value - 0.18).abs() < 1e-12);
    /// assert!((dx - 0.6).abs() < 1e-12 && (dy - 0.3).abs() < 1e-12);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval_with_gradient(&self, u: DVec2) -> (P, [P; 2]) {
        let mut values = Vec::new();
        self.basis.eval_basis_gradient_with(u, &mut DmsScratch::default(), &mut values);
        let mut out = (P::ZERO, [P::ZERO; 2]);
        for &(i, v, g) in &values {
            let c = self.control[i];
            out.0 = out.0 + c * v;
            out.1[0] = out.1[0] + c * g.x;
            out.1[1] = out.1[1] + c * g.y;
        }
        out
    }
}

impl DmsSpline<DVec3> {
    /// The unit normal; `None` where the surface is singular.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{DmsBasis, DmsSpline, KnotPlacement};
    /// let square = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y];
    /// let basis = DmsBasis::with_generated_knots(2, square, vec![[0, 1, 2], [0, 2, 3]], KnotPlacement::default())?;
    /// # use glam::DVec3;
    /// // The plane (x, y, x + y): normal (-1, -1, 1) / √3.
    /// let plane = DmsSpline::from_blossom(basis, |a: &[DVec2]| {
    ///     let p = a.iter().sum::<DVec2>() / a.len() as f64;
    ///     DVec3::new(p.x, p.y, p.x + p.y)
    /// })?;
    /// let normal = plane.normal(DVec2::new(0.3, 0.6)).unwrap();
    /// assert!((normal - DVec3::new(-1.0, -1.0, 1.0) / 3f64.sqrt()).length() < 1e-12);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn normal(&self, u: DVec2) -> Option<DVec3> {
        let (_, [du, dv]) = self.eval_with_gradient(u);
        // (At unit scale: the product of tangents far from 1 underflows or overflows.)
        mesh_topo::scale::unit_normal(du, dv)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::samples::square_triangulation;
    use crate::{DomainTriangle, TriBezier, index::tri_count};

    fn basis(n: usize, seed: u64) -> DmsBasis {
        let (v, t) = square_triangulation(4);
        DmsBasis::with_generated_knots(n, v, t, KnotPlacement { radius: 0.12, seed, boundary_outward: true }).unwrap()
    }

    fn interior_points(count: usize, seed: u64) -> Vec<DVec2> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..count).map(|_| DVec2::new(rng.random_range(1.0..3.0), rng.random_range(1.0..3.0))).collect()
    }

    #[test]
    fn partition_of_unity_and_non_negativity_in_the_interior() {
        for n in 1..=3 {
            let b = basis(n, 7 + n as u64);
            for u in interior_points(40, n as u64) {
                let values = b.eval_basis(u);
                let sum: f64 = values.iter().map(|v| v.1).sum();
                assert!((sum - 1.0).abs() < 1e-12, "n = {n}, u = {u}: {sum}");
                assert!(values.iter().all(|v| v.1 >= 0.0));
            }
        }
    }

    #[test]
    fn affine_invariance_and_convex_hull() {
        let b = basis(2, 5);
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut random =
            || DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
        let control: Vec<DVec3> = (0..b.basis_count()).map(|_| random()).collect();
        let (m, shift) = (glam::DMat3::from_cols(random(), random(), random()), random());
        let spline = DmsSpline::new(b.clone(), control.clone()).unwrap();
        let mapped = DmsSpline::new(b, control.iter().map(|&c| m * c + shift).collect()).unwrap();
        for u in interior_points(30, 12) {
            let p = spline.eval(u);
            assert!((mapped.eval(u) - (m * p + shift)).length() < 1e-12, "{u}");
            // Local convex hull: inside the hull of the control points whose basis
            // functions do not vanish at u (a much smaller set than all of them).
            let active: Vec<DVec3> =
                spline.basis().eval_basis(u).iter().filter(|v| v.1 > 0.0).map(|v| control[v.0]).collect();
            assert!(active.len() >= 4 && active.len() < control.len(), "{u}: {} active", active.len());
            assert!(crate::hull_check::in_convex_hull(p, &active, 1e-12), "{u}: {p}");
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]
        /// Random knot clouds (any seed, radius up to 0.2 edge) and random interior points:
        /// every basis function is non-negative and they sum to one.
        #[test]
        fn basis_is_a_non_negative_partition_of_unity(
            degree in 1usize..=3,
            seed in 0u64..1_000_000,
            radius in 0.02f64..0.2,
            x in 1.0f64..3.0,
            y in 1.0f64..3.0,
        ) {
            let (v, t) = square_triangulation(4);
            let placement = KnotPlacement { radius, seed, boundary_outward: true };
            let b = match DmsBasis::with_generated_knots(degree, v, t, placement) {
                Ok(b) => b,
                // A random cloud may violate the knot conditions: a typed error, not a basis.
                Err(SplineError::DmsKnotOrientation { .. } | SplineError::CollinearKnots { .. }) => return Ok(()),
                Err(other) => panic!("{other}"),
            };
            let values = b.eval_basis(DVec2::new(x, y));
            let sum: f64 = values.iter().map(|v| v.1).sum();
            proptest::prop_assert!((sum - 1.0).abs() < 1e-11, "sum {}", sum);
            proptest::prop_assert!(values.iter().all(|v| v.1 >= 0.0));
        }
    }

    #[test]
    fn partition_of_unity_on_knot_lines() {
        // Grid vertices are knots and edges are knot lines; dyadic points on them make
        // the half-open rule decide exactly.
        let b = basis(2, 3);
        for i in 2..=6 {
            for j in 2..=6 {
                for u in [DVec2::new(i as f64 * 0.5, j as f64 * 0.5), DVec2::new(i as f64 * 0.5 + 0.25, j as f64 * 0.5)]
                {
                    let sum: f64 = b.eval_basis(u).iter().map(|v| v.1).sum();
                    assert!((sum - 1.0).abs() < 1e-12, "{u}: {sum}");
                }
            }
        }
    }

    #[test]
    fn polynomials_of_the_degree_are_reproduced() {
        let mut rng = ChaCha8Rng::seed_from_u64(99);
        for n in 1..=3 {
            let control = (0..tri_count(n)).map(|_| rng.random_range(-1.0..1.0)).collect();
            let domain = DomainTriangle::new([DVec2::ZERO, DVec2::new(4.0, 0.0), DVec2::new(0.0, 4.0)]).unwrap();
            let poly = TriBezier::<f64>::new(n, domain, control).unwrap();
            let spline = DmsSpline::from_blossom(basis(n, 21), |args| poly.blossom(args).unwrap()).unwrap();
            for u in interior_points(30, 5) {
                let (value, [dx, dy]) = spline.eval_with_gradient(u);
                assert!((value - poly.eval(u)).abs() < 1e-10, "n = {n}: {value} vs {}", poly.eval(u));
                assert!((spline.eval(u) - value).abs() < 1e-14);
                let (_, [px, py]) = poly.eval_with_gradient(u);
                assert!((dx - px).abs() < 1e-8 && (dy - py).abs() < 1e-8);
            }
        }
    }

    #[test]
    fn value_does_not_depend_on_the_choice_of_w() {
        let b = basis(2, 4);
        for u in interior_points(10, 8) {
            for (index, value) in b.eval_basis(u) {
                for choice in [WChoice::First, WChoice::Last, WChoice::Spread] {
                    let other = b.eval_one_with(index, u, choice);
                    assert!((other - value).abs() <= 1e-11 * value.max(1.0), "{choice:?}: {other} vs {value}");
                }
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let b = basis(2, 6);
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let control: Vec<DVec3> = (0..b.basis_count())
            .map(|_| DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)))
            .collect();
        let spline = DmsSpline::new(b, control).unwrap();
        let h = 1e-6;
        for u in interior_points(10, 2) {
            let (_, [du, dv]) = spline.eval_with_gradient(u);
            let fd_u = (spline.eval(u + DVec2::X * h) - spline.eval(u - DVec2::X * h)) / (2.0 * h);
            let fd_v = (spline.eval(u + DVec2::Y * h) - spline.eval(u - DVec2::Y * h)) / (2.0 * h);
            assert!((du - fd_u).length() < 1e-6 * du.length().max(1.0), "{du} vs {fd_u}");
            assert!((dv - fd_v).length() < 1e-6 * dv.length().max(1.0));
            let normal = spline.normal(u).unwrap();
            assert!(normal.dot(du).abs() < 1e-10);
        }
    }

    #[test]
    fn knot_conditions_are_checked() {
        let (v, t) = square_triangulation(2);
        let n = 2;
        let good = generate_knots(n, &v, &t, 0.1, 1, true).unwrap();
        assert!(DmsBasis::new(n, v.clone(), t.clone(), good.clone()).is_ok());
        // A knot far away breaks the orientation of some knot triangle.
        let mut bad = good.clone();
        bad[4 * n] = DVec2::new(-10.0, 5.0);
        assert!(matches!(
            DmsBasis::new(n, v.clone(), t.clone(), bad),
            Err(SplineError::DmsKnotOrientation { .. } | SplineError::CollinearKnots { .. })
        ));
        // A knot on the line through two others.
        let mut bad = good.clone();
        bad[4 * n] = v[4] + (good[4 * n + 1] - v[4]) * 0.5;
        assert!(matches!(DmsBasis::new(n, v.clone(), t.clone(), bad), Err(SplineError::CollinearKnots { .. })));
        // Clockwise triangle, bad index, wrong counts, degree.
        let mut flipped = t.clone();
        flipped[3].swap(0, 1);
        assert!(matches!(
            DmsBasis::new(n, v.clone(), flipped, good.clone()),
            Err(SplineError::BadDomainTriangle { triangle: 3, .. })
        ));
        let mut out_of_range = t.clone();
        out_of_range[0][2] = 99;
        assert!(matches!(
            DmsBasis::new(n, v.clone(), out_of_range, good.clone()),
            Err(SplineError::VertexIndex { vertex: 99, .. })
        ));
        assert!(matches!(DmsBasis::new(n, v.clone(), t.clone(), good[1..].to_vec()), Err(SplineError::Count { .. })));
        assert!(matches!(DmsBasis::new(0, v.clone(), t.clone(), vec![]), Err(SplineError::Degree { .. })));
        assert!(matches!(DmsBasis::new(7, v, t, vec![]), Err(SplineError::Degree { .. })));
    }

    /// Out-of-range indices used to panic with bare slice messages (`cloud`,
    /// `blossom_args`, `greville`, `eval_one_with`) or to return another function's index
    /// (`basis_index`).
    #[test]
    fn index_accessors_check_their_indices() {
        let b = basis(2, 3);
        let (vertices, triangles, count) = (b.vertices().len(), b.triangles().len(), b.basis_count());
        assert_eq!(b.try_cloud(vertices - 1).unwrap(), b.cloud(vertices - 1));
        assert_eq!(
            b.try_cloud(vertices),
            Err(SplineError::IndexOutOfRange { what: "vertex", index: vertices, len: vertices })
        );
        let triangle_error = SplineError::IndexOutOfRange { what: "triangle", index: triangles, len: triangles };
        assert_eq!(b.try_basis_index(triangles, [2, 0, 0]), Err(triangle_error.clone()));
        assert_eq!(b.try_blossom_args(triangles, [2, 0, 0]), Err(triangle_error));
        for beta in [[3, 0, 0], [0, 0, 1], [usize::MAX, 3, 0]] {
            let degree_error = SplineError::MultiIndexDegree { beta, degree: 2 };
            assert_eq!(b.try_basis_index(0, beta), Err(degree_error.clone()));
            assert_eq!(b.try_blossom_args(0, beta), Err(degree_error));
        }
        assert_eq!(b.try_basis_index(triangles - 1, [0, 0, 2]), Ok(count - 1));
        let function_error = SplineError::IndexOutOfRange { what: "basis function", index: count, len: count };
        assert_eq!(b.try_greville(count), Err(function_error.clone()));
        assert_eq!(b.try_eval_one_with(count, DVec2::ONE, WChoice::First), Err(function_error));
        assert_eq!(b.try_greville(count - 1), Ok(b.greville(count - 1)));
        let caught = std::panic::catch_unwind(|| b.basis_index(0, [3, 0, 0])).unwrap_err();
        let message = caught.downcast_ref::<String>().unwrap();
        assert!(message.contains("multi-index [3, 0, 0] does not sum to the degree 2"), "{message}");
        let caught = std::panic::catch_unwind(|| b.cloud(vertices)).unwrap_err();
        let message = caught.downcast_ref::<String>().unwrap();
        assert!(message.contains(&format!("vertex {vertices} is out of range (there are {vertices})")), "{message}");
    }

    #[test]
    fn generated_knots_check_the_degree_before_allocating() {
        // Used to abort allocating `degree` knots per vertex before `new` checked it.
        let v = vec![DVec2::ZERO, DVec2::X, DVec2::Y];
        for degree in [0, 1 << 33, usize::MAX] {
            let basis = DmsBasis::with_generated_knots(degree, v.clone(), vec![[0, 1, 2]], KnotPlacement::default());
            assert!(
                matches!(basis, Err(SplineError::Degree { degree: d, max: MAX_DMS_DEGREE, .. }) if d == degree),
                "{basis:?}"
            );
        }
    }
}
