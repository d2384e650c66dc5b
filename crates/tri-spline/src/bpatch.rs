//! B-patches (H.-P. Seidel 1991; ALGORITHMS.md §10).
//!
//! A B-patch of degree `n` is a polynomial of total degree `n` given by three knot
//! sequences `r_0..r_{n-1}`, `s_0..s_{n-1}`, `t_0..t_{n-1}` in the plane and control
//! points `c_β`, `|β| = n`, with the meaning `c_ijk = F(r_0..r_{i-1}, s_0..s_{j-1},
//! t_0..t_{k-1})` for the polynomial's blossom `F`. When all `r_i` are `t0`, all `s_j`
//! are `t1` and all `t_k` are `t2` it is the Bézier patch over `(t0, t1, t2)`.
//!
//! Evaluation is the de Boor-like triangle recursion: `c^0_β = c_β` and, for level
//! `l = 1..n` and `|β| = n - l`, `c^l_β = sum_i λ_i c^{l-1}_{β + e_i}` with `λ` the
//! barycentric coordinates of `u` with respect to the knot triangle
//! `(r_{β0}, s_{β1}, t_{β2})`; then `c^n_000 = P(u)`. By induction
//! `c^l_β = F(r_{<β0}, s_{<β1}, t_{<β2}, u^l)`, so running the levels with different
//! points evaluates the blossom, and using a vector at the last level gives
//! `D_d P(u) = n F(u^{n-1}, d)`.
//!
//! Admissibility (checked when the patch is built): every knot triangle
//! `(r_i, s_j, t_k)` with `i + j + k <= n - 1` is non-degenerate and oriented like
//! `(r_0, s_0, t_0)`.
//!
//! Reference: H.-P. Seidel, Symmetric recursive algorithms for surfaces: B-patches and
//! the de Boor algorithm for polynomials over triangles, Constr. Approx. 7 (1991) 257–279.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::SplineError;
use crate::bezier::with_scratch;
use crate::domain::{BaryMap, DomainTriangle, orient};
use crate::index::{multi_indices, tet_count, tri_count, tri_index};
use crate::point::{Point, combine3};

/// Largest supported B-patch degree.
pub const MAX_BPATCH_DEGREE: usize = 32;

/// The three knot sequences of a B-patch, `n` knots each.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KnotSequences {
    /// Knots `r_0 .. r_{n-1}` (attached to corner 0).
    pub r: Vec<DVec2>,
    /// Knots `s_0 .. s_{n-1}` (attached to corner 1).
    pub s: Vec<DVec2>,
    /// Knots `t_0 .. t_{n-1}` (attached to corner 2).
    pub t: Vec<DVec2>,
}

impl KnotSequences {
    /// Coincident knots at the corners of `domain`: the B-patch is then the Bézier patch.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::{BPatch, DomainTriangle, KnotSequences, TriBezier};
    /// let domain = DomainTriangle::reference();
    /// let control = vec![0.0, 1.0, 4.0, 2.0, 3.0, 5.0];
    /// let bpatch = BPatch::new(2, KnotSequences::bezier(&domain, 2), control.clone())?;
    /// let bezier = TriBezier::new(2, domain, control)?;
    /// assert_eq!(bpatch.base_triangle(), domain.corners());
    /// let u = DVec2::new(0.2, 0.5);
    /// assert!((bpatch.eval(u) - bezier.eval(u)).abs() < 1e-14);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn bezier(domain: &DomainTriangle, degree: usize) -> Self {
        let [t0, t1, t2] = domain.corners();
        Self { r: vec![t0; degree], s: vec![t1; degree], t: vec![t2; degree] }
    }

    /// The knot triangle `(r_i, s_j, t_k)`.
    ///
    /// # Panics
    /// If an index is beyond its sequence (the message names the sequence, the index and
    /// the length); [`try_triangle`](Self::try_triangle) returns an error instead.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::KnotSequences;
    /// let knots = KnotSequences {
    ///     r: vec![DVec2::ZERO, DVec2::new(-0.1, 0.0)],
    ///     s: vec![DVec2::X, DVec2::new(1.1, 0.0)],
    ///     t: vec![DVec2::Y, DVec2::new(0.0, 1.1)],
    /// };
    /// assert_eq!(knots.triangle(1, 0, 1), [DVec2::new(-0.1, 0.0), DVec2::X, DVec2::new(0.0, 1.1)]);
    /// ```
    pub fn triangle(&self, i: usize, j: usize, k: usize) -> [DVec2; 3] {
        self.try_triangle(i, j, k).unwrap_or_else(|e| panic!("KnotSequences::triangle: {e}"))
    }

    /// The knot triangle `(r_i, s_j, t_k)`, for indices given by a caller (the sequences
    /// are public fields, so their lengths are not known to match a degree).
    ///
    /// # Errors
    /// [`SplineError::IndexOutOfRange`] naming the first index beyond its sequence.
    ///
    /// ```
    /// use tri_spline::{DomainTriangle, KnotSequences, SplineError};
    /// let knots = KnotSequences::bezier(&DomainTriangle::reference(), 2);
    /// assert_eq!(knots.try_triangle(1, 0, 1)?, DomainTriangle::reference().corners());
    /// assert!(matches!(knots.try_triangle(0, 2, 0), Err(SplineError::IndexOutOfRange { what: "s knot", index: 2, len: 2 })));
    /// # Ok::<(), SplineError>(())
    /// ```
    pub fn try_triangle(&self, i: usize, j: usize, k: usize) -> Result<[DVec2; 3], SplineError> {
        let knot = |what: &'static str, sequence: &[DVec2], index: usize| {
            sequence.get(index).copied().ok_or(SplineError::IndexOutOfRange { what, index, len: sequence.len() })
        };
        Ok([knot("r knot", &self.r, i)?, knot("s knot", &self.s, j)?, knot("t knot", &self.t, k)?])
    }
}

/// A B-patch with control points of type `P`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BPatch<P = DVec3> {
    degree: usize,
    knots: KnotSequences,
    control: Vec<P>,
    /// Barycentric maps of the knot triangles `(r_{β0}, s_{β1}, t_{β2})`, `|β| = d`,
    /// at position `tet_count(d) + tri_index(d, β1, β2)`.
    maps: Vec<BaryMap>,
}

/// Checks the knot conditions and precomputes the knot triangles' barycentric maps.
fn knot_maps(degree: usize, knots: &KnotSequences) -> Result<Vec<BaryMap>, SplineError> {
    for (what, seq) in [("r knots", &knots.r), ("s knots", &knots.s), ("t knots", &knots.t)] {
        if seq.len() != degree {
            return Err(SplineError::Count { what, expected: degree, got: seq.len() });
        }
        if let Some(index) = seq.iter().position(|p| !p.is_finite()) {
            return Err(SplineError::NonFinite { what, index });
        }
    }
    let mut maps = Vec::with_capacity(tet_count(degree));
    if degree == 0 {
        return Ok(maps);
    }
    let reference = orient(knots.r[0], knots.s[0], knots.t[0]).signum();
    for d in 0..degree {
        for [i, j, k] in multi_indices(d) {
            let [a, b, c] = knots.triangle(i, j, k);
            let map =
                BaryMap::new(a, b, c).ok_or(SplineError::DegenerateKnotTriangle { i, j, k, points: [a, b, c] })?;
            if orient(a, b, c).signum() != reference {
                return Err(SplineError::KnotTriangleOrientation { i, j, k });
            }
            maps.push(map);
        }
    }
    Ok(maps)
}

impl<P: Point> BPatch<P> {
    /// A B-patch of degree `degree` (1 to [`MAX_BPATCH_DEGREE`]).
    ///
    /// # Errors
    /// [`SplineError::Degree`], [`SplineError::Count`] (knots or control points),
    /// [`SplineError::NonFinite`], and the admissibility errors
    /// [`SplineError::DegenerateKnotTriangle`] / [`SplineError::KnotTriangleOrientation`]
    /// naming the first bad knot triangle `(r_i, s_j, t_k)`.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::{BPatch, KnotSequences, SplineError};
    /// let knots = KnotSequences {
    ///     r: vec![DVec2::new(0.0, 0.0), DVec2::new(-0.1, -0.1)],
    ///     s: vec![DVec2::new(1.0, 0.0), DVec2::new(1.1, -0.1)],
    ///     t: vec![DVec2::new(0.0, 1.0), DVec2::new(0.0, 1.1)],
    /// };
    /// let patch = BPatch::new(2, knots.clone(), vec![1.0; 6])?;
    /// assert!((patch.eval(DVec2::new(0.3, 0.3)) - 1.0).abs() < 1e-15);
    /// // A knot triangle collapsing to a segment is reported by name.
    /// let mut bad = knots;
    /// bad.t[1] = DVec2::new(0.5, 0.0);
    /// assert!(matches!(BPatch::new(2, bad, vec![1.0; 6]), Err(SplineError::DegenerateKnotTriangle { i: 0, j: 0, k: 1, .. })));
    /// # Ok::<(), SplineError>(())
    /// ```
    pub fn new(degree: usize, knots: KnotSequences, control: Vec<P>) -> Result<Self, SplineError> {
        if !(1..=MAX_BPATCH_DEGREE).contains(&degree) {
            return Err(SplineError::Degree { degree, min: 1, max: MAX_BPATCH_DEGREE });
        }
        if control.len() != tri_count(degree) {
            return Err(SplineError::Count {
                what: "B-patch control points",
                expected: tri_count(degree),
                got: control.len(),
            });
        }
        if let Some(index) = control.iter().position(|p| !p.is_finite_point()) {
            return Err(SplineError::NonFinite { what: "control point", index });
        }
        let maps = knot_maps(degree, &knots)?;
        Ok(Self { degree, knots, control, maps })
    }

    /// The degree `n`.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The knot sequences.
    pub fn knots(&self) -> &KnotSequences {
        &self.knots
    }

    /// The control points in storage order ([`crate::index`]).
    pub fn control_points(&self) -> &[P] {
        &self.control
    }

    /// Mutable control points.
    pub fn control_points_mut(&mut self) -> &mut [P] {
        &mut self.control
    }

    /// The base triangle `(r_0, s_0, t_0)` (the patch's natural domain).
    pub fn base_triangle(&self) -> [DVec2; 3] {
        self.knots.triangle(0, 0, 0)
    }

    #[inline(always)]
    fn map(&self, m: usize, j: usize, k: usize) -> &BaryMap {
        &self.maps[tet_count(m) + tri_index(m, j, k)]
    }

    /// One de Boor level in place: degree `m + 1` values to degree `m`, with weights
    /// from `weights(map of the destination knot triangle)`.
    #[inline]
    fn level(&self, buf: &mut [P], m: usize, weights: impl Fn(&BaryMap) -> [f64; 3]) {
        let mut dst = 0;
        for k in 0..=m {
            let row = tri_index(m + 1, 0, k);
            let next_row = tri_index(m + 1, 0, k + 1);
            for j in 0..=m - k {
                let w = weights(self.map(m, j, k));
                buf[dst] = combine3(buf[row + j], buf[row + j + 1], buf[next_row + j], w);
                dst += 1;
            }
        }
    }

    /// `P(u)` by the de Boor-like recursion.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::index::multi_indices;
    /// # use tri_spline::{BPatch, KnotSequences};
    /// # let knots = KnotSequences {
    /// #     r: vec![DVec2::new(0.0, 0.0), DVec2::new(-0.1, -0.1)],
    /// #     s: vec![DVec2::new(1.0, 0.0), DVec2::new(1.1, -0.1)],
    /// #     t: vec![DVec2::new(0.0, 1.0), DVec2::new(0.0, 1.1)],
    /// # };
    /// // `knots`: the admissible degree-2 knots of the `BPatch::new` example.
    /// // c_ijk = F(r_0..r_{i-1}, s_0..s_{j-1}, t_0..t_{k-1}) for the identity u -> u,
    /// // whose blossom is the mean of its arguments: the patch reproduces the identity.
    /// let control: Vec<DVec2> = multi_indices(2)
    ///     .map(|[i, j, k]| knots.r[..i].iter().chain(&knots.s[..j]).chain(&knots.t[..k]).sum::<DVec2>() / 2.0)
    ///     .collect();
    /// let patch = BPatch::new(2, knots.clone(), control)?;
    /// let u = DVec2::new(0.3, 0.2);
    /// assert!((patch.eval(u) - u).length() < 1e-15);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval(&self, u: DVec2) -> P {
        with_scratch(&self.control, |buf| {
            for m in (0..self.degree).rev() {
                self.level(buf, m, |map| map.coords(u));
            }
            buf[0]
        })
    }

    /// The blossom `F(u_1, …, u_n)` of the patch's polynomial.
    ///
    /// # Errors
    /// [`SplineError::Count`] unless exactly `n` arguments are given.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::index::multi_indices;
    /// # use tri_spline::{BPatch, KnotSequences};
    /// # let knots = KnotSequences {
    /// #     r: vec![DVec2::new(0.0, 0.0), DVec2::new(-0.1, -0.1)],
    /// #     s: vec![DVec2::new(1.0, 0.0), DVec2::new(1.1, -0.1)],
    /// #     t: vec![DVec2::new(0.0, 1.0), DVec2::new(0.0, 1.1)],
    /// # };
    /// // `knots`: the admissible degree-2 knots of the `BPatch::new` example.
    /// # use tri_spline::SplineError;
    /// let patch = BPatch::new(2, knots.clone(), vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0])?;
    /// // The control points are blossom values at the knots: c_200 = F(r_0, r_1), c_011 = F(s_0, t_0).
    /// assert!((patch.blossom(&[knots.r[0], knots.r[1]])? - 1.0).abs() < 1e-14);
    /// assert!((patch.blossom(&[knots.s[0], knots.t[0]])? - 5.0).abs() < 1e-14);
    /// // On the diagonal it is the patch.
    /// let u = DVec2::new(0.3, 0.2);
    /// assert!((patch.blossom(&[u, u])? - patch.eval(u)).abs() < 1e-14);
    /// assert!(matches!(patch.blossom(&[u]), Err(SplineError::Count { expected: 2, got: 1, .. })));
    /// # Ok::<(), SplineError>(())
    /// ```
    pub fn blossom(&self, args: &[DVec2]) -> Result<P, SplineError> {
        if args.len() != self.degree {
            return Err(SplineError::Count { what: "blossom arguments", expected: self.degree, got: args.len() });
        }
        Ok(with_scratch(&self.control, |buf| {
            for (level, m) in (0..self.degree).rev().enumerate() {
                self.level(buf, m, |map| map.coords(args[level]));
            }
            buf[0]
        }))
    }

    /// The directional derivative `D_d P(u) = n F(u^{n-1}, d)`.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::index::multi_indices;
    /// # use tri_spline::{BPatch, KnotSequences};
    /// # let knots = KnotSequences {
    /// #     r: vec![DVec2::new(0.0, 0.0), DVec2::new(-0.1, -0.1)],
    /// #     s: vec![DVec2::new(1.0, 0.0), DVec2::new(1.1, -0.1)],
    /// #     t: vec![DVec2::new(0.0, 1.0), DVec2::new(0.0, 1.1)],
    /// # };
    /// // `knots`: the admissible degree-2 knots of the `BPatch::new` example.
    /// // c_ijk = F(r_0..r_{i-1}, s_0..s_{j-1}, t_0..t_{k-1}) for the identity u -> u,
    /// // whose blossom is the mean of its arguments: the patch reproduces the identity.
    /// let control: Vec<DVec2> = multi_indices(2)
    ///     .map(|[i, j, k]| knots.r[..i].iter().chain(&knots.s[..j]).chain(&knots.t[..k]).sum::<DVec2>() / 2.0)
    ///     .collect();
    /// let patch = BPatch::new(2, knots.clone(), control)?;
    /// // The derivative of the identity along d is d.
    /// let d = DVec2::new(0.6, -0.8);
    /// assert!((patch.derivative(DVec2::new(0.3, 0.2), d) - d).length() < 1e-14);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn derivative(&self, u: DVec2, d: DVec2) -> P {
        with_scratch(&self.control, |buf| {
            for m in (1..self.degree).rev() {
                self.level(buf, m, |map| map.coords(u));
            }
            self.level(buf, 0, |map| map.direction(d));
            buf[0] * self.degree as f64
        })
    }

    /// `P(u)` and its partial derivatives along the two domain axes in one pass.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::index::multi_indices;
    /// # use tri_spline::{BPatch, KnotSequences};
    /// # let knots = KnotSequences {
    /// #     r: vec![DVec2::new(0.0, 0.0), DVec2::new(-0.1, -0.1)],
    /// #     s: vec![DVec2::new(1.0, 0.0), DVec2::new(1.1, -0.1)],
    /// #     t: vec![DVec2::new(0.0, 1.0), DVec2::new(0.0, 1.1)],
    /// # };
    /// // `knots`: the admissible degree-2 knots of the `BPatch::new` example.
    /// // c_ijk = F(r_0..r_{i-1}, s_0..s_{j-1}, t_0..t_{k-1}) for the identity u -> u,
    /// // whose blossom is the mean of its arguments: the patch reproduces the identity.
    /// let control: Vec<DVec2> = multi_indices(2)
    ///     .map(|[i, j, k]| knots.r[..i].iter().chain(&knots.s[..j]).chain(&knots.t[..k]).sum::<DVec2>() / 2.0)
    ///     .collect();
    /// let patch = BPatch::new(2, knots.clone(), control)?;
    /// let u = DVec2::new(0.3, 0.2);
    /// let (value, [dx, dy]) = patch.eval_with_gradient(u);
    /// assert!((value - u).length() < 1e-15);
    /// assert!((dx - DVec2::X).length() < 1e-14 && (dy - DVec2::Y).length() < 1e-14);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval_with_gradient(&self, u: DVec2) -> (P, [P; 2]) {
        with_scratch(&self.control, |buf| {
            for m in (1..self.degree).rev() {
                self.level(buf, m, |map| map.coords(u));
            }
            let base = self.map(0, 0, 0);
            let n = self.degree as f64;
            let value = combine3(buf[0], buf[1], buf[2], base.coords(u));
            let du = combine3(buf[0], buf[1], buf[2], base.direction(DVec2::X)) * n;
            let dv = combine3(buf[0], buf[1], buf[2], base.direction(DVec2::Y)) * n;
            (value, [du, dv])
        })
    }

    /// The B-patch basis functions at `u` (the weights of the control points in `P(u)`),
    /// by the transposed recursion: `O(n³)` for all of them. `out` is resized.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::index::multi_indices;
    /// # use tri_spline::{BPatch, KnotSequences};
    /// # let knots = KnotSequences {
    /// #     r: vec![DVec2::new(0.0, 0.0), DVec2::new(-0.1, -0.1)],
    /// #     s: vec![DVec2::new(1.0, 0.0), DVec2::new(1.1, -0.1)],
    /// #     t: vec![DVec2::new(0.0, 1.0), DVec2::new(0.0, 1.1)],
    /// # };
    /// // `knots`: the admissible degree-2 knots of the `BPatch::new` example.
    /// let patch = BPatch::new(2, knots, vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0])?;
    /// let u = DVec2::new(0.3, 0.2);
    /// let mut values = Vec::new();
    /// patch.basis(u, &mut values);
    /// // A partition of unity, and the weights of the control points in P(u).
    /// assert!((values.iter().sum::<f64>() - 1.0).abs() < 1e-14);
    /// let weighted: f64 = values.iter().zip(patch.control_points()).map(|(w, c)| w * c).sum();
    /// assert!((weighted - patch.eval(u)).abs() < 1e-14);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn basis(&self, u: DVec2, out: &mut Vec<f64>) {
        bpatch_basis(self.degree, &self.maps, u, out);
    }
}

/// Shared by [`BPatch::basis`] and [`BPatchBasis`]: push the weight 1 at the apex down
/// through the levels, `w^{m+1}_{β + e_i} += λ_i(T_β) w^m_β`.
fn bpatch_basis(degree: usize, maps: &[BaryMap], u: DVec2, out: &mut Vec<f64>) {
    out.clear();
    out.resize(tri_count(degree), 0.0);
    out[0] = 1.0;
    for m in 0..degree {
        // In place: every target position of a degree-m source is at or after the
        // source's own position, so visiting sources backwards (reading and clearing
        // each before scattering it) never reads a value that was already updated.
        for k in (0..=m).rev() {
            let row = tri_index(m + 1, 0, k);
            let next_row = tri_index(m + 1, 0, k + 1);
            for j in (0..=m - k).rev() {
                let src = tri_index(m, j, k);
                let w = std::mem::take(&mut out[src]);
                if w == 0.0 {
                    continue;
                }
                let l = maps[tet_count(m) + src].coords(u);
                out[row + j] += l[0] * w;
                out[row + j + 1] += l[1] * w;
                out[next_row + j] += l[2] * w;
            }
        }
    }
}

/// The basis of a B-patch without control points: for collocation matrices.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BPatchBasis {
    degree: usize,
    knots: KnotSequences,
    maps: Vec<BaryMap>,
}

impl BPatchBasis {
    /// The basis of degree `degree` over `knots`.
    ///
    /// # Errors
    /// As [`BPatch::new`].
    ///
    /// ```
    /// use tri_spline::{BPatchBasis, DomainTriangle, KnotSequences, SplineError};
    /// let domain = DomainTriangle::reference();
    /// let basis = BPatchBasis::new(3, KnotSequences::bezier(&domain, 3))?;
    /// assert_eq!(basis.degree(), 3);
    /// // Three knots per sequence do not make a degree-2 basis, and degree 0 has none.
    /// assert!(matches!(BPatchBasis::new(2, KnotSequences::bezier(&domain, 3)), Err(SplineError::Count { .. })));
    /// assert!(matches!(BPatchBasis::new(0, KnotSequences::bezier(&domain, 0)), Err(SplineError::Degree { .. })));
    /// # Ok::<(), SplineError>(())
    /// ```
    pub fn new(degree: usize, knots: KnotSequences) -> Result<Self, SplineError> {
        if !(1..=MAX_BPATCH_DEGREE).contains(&degree) {
            return Err(SplineError::Degree { degree, min: 1, max: MAX_BPATCH_DEGREE });
        }
        let maps = knot_maps(degree, &knots)?;
        Ok(Self { degree, knots, maps })
    }

    /// The degree.
    pub fn degree(&self) -> usize {
        self.degree
    }

    /// The knots.
    pub fn knots(&self) -> &KnotSequences {
        &self.knots
    }

    /// The basis functions at `u` in storage order. `out` is resized.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{BPatchBasis, KnotSequences};
    /// # let knots = KnotSequences {
    /// #     r: vec![DVec2::new(0.0, 0.0), DVec2::new(-0.1, -0.1)],
    /// #     s: vec![DVec2::new(1.0, 0.0), DVec2::new(1.1, -0.1)],
    /// #     t: vec![DVec2::new(0.0, 1.0), DVec2::new(0.0, 1.1)],
    /// # };
    /// // `knots`: the admissible degree-2 knots of the `BPatch::new` example.
    /// let basis = BPatchBasis::new(2, knots)?;
    /// let mut values = Vec::new();
    /// basis.eval(DVec2::new(0.3, 0.2), &mut values);
    /// // Six functions, non-negative inside the base triangle and summing to one.
    /// assert_eq!(values.len(), 6);
    /// assert!(values.iter().all(|&v| v >= 0.0));
    /// assert!((values.iter().sum::<f64>() - 1.0).abs() < 1e-14);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn eval(&self, u: DVec2, out: &mut Vec<f64>) {
        bpatch_basis(self.degree, &self.maps, u, out);
    }

    /// The patch with these knots and the given control points.
    ///
    /// # Errors
    /// As [`BPatch::new`] for the control points.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::{BPatch, BPatchBasis, KnotSequences};
    /// # let knots = KnotSequences {
    /// #     r: vec![DVec2::new(0.0, 0.0), DVec2::new(-0.1, -0.1)],
    /// #     s: vec![DVec2::new(1.0, 0.0), DVec2::new(1.1, -0.1)],
    /// #     t: vec![DVec2::new(0.0, 1.0), DVec2::new(0.0, 1.1)],
    /// # };
    /// // `knots`: the admissible degree-2 knots of the `BPatch::new` example.
    /// let basis = BPatchBasis::new(2, knots.clone())?;
    /// let control = vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
    /// assert_eq!(basis.with_control(control.clone())?, BPatch::new(2, knots, control)?);
    /// assert!(basis.with_control(vec![1.0; 5]).is_err());
    /// assert!(basis.with_control(vec![f64::NAN; 6]).is_err());
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn with_control<P: Point>(&self, control: Vec<P>) -> Result<BPatch<P>, SplineError> {
        if control.len() != tri_count(self.degree) {
            return Err(SplineError::Count {
                what: "B-patch control points",
                expected: tri_count(self.degree),
                got: control.len(),
            });
        }
        if let Some(index) = control.iter().position(|p| !p.is_finite_point()) {
            return Err(SplineError::NonFinite { what: "control point", index });
        }
        Ok(BPatch { degree: self.degree, knots: self.knots.clone(), control, maps: self.maps.clone() })
    }
}

impl BPatch<DVec3> {
    /// The unit normal `P_x × P_y / |P_x × P_y|`; `None` where the patch is singular.
    ///
    /// ```
    /// # use glam::DVec2;
    /// # use tri_spline::index::multi_indices;
    /// # use tri_spline::{BPatch, KnotSequences};
    /// # let knots = KnotSequences {
    /// #     r: vec![DVec2::new(0.0, 0.0), DVec2::new(-0.1, -0.1)],
    /// #     s: vec![DVec2::new(1.0, 0.0), DVec2::new(1.1, -0.1)],
    /// #     t: vec![DVec2::new(0.0, 1.0), DVec2::new(0.0, 1.1)],
    /// # };
    /// // `knots`: the admissible degree-2 knots of the `BPatch::new` example.
    /// # use glam::DVec3;
    /// // The plane z = 0 (the identity map of the other B-patch examples, lifted to 3D).
    /// let control: Vec<DVec3> = multi_indices(2)
    ///     .map(|[i, j, k]| knots.r[..i].iter().chain(&knots.s[..j]).chain(&knots.t[..k]).sum::<DVec2>() / 2.0)
    ///     .map(|p| p.extend(0.0))
    ///     .collect();
    /// let patch = BPatch::new(2, knots, control)?;
    /// assert!((patch.normal(DVec2::new(0.3, 0.2)).unwrap() - DVec3::Z).length() < 1e-14);
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
    use crate::TriBezier;
    use proptest::prelude::*;

    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
        fn vec2(&mut self) -> DVec2 {
            DVec2::new(self.next(), self.next())
        }
    }

    /// Knots perturbed from the corners of the reference triangle by up to `spread`.
    fn perturbed_knots(n: usize, spread: f64, rng: &mut Lcg) -> KnotSequences {
        let d = DomainTriangle::reference();
        let [t0, t1, t2] = d.corners();
        let mut seq = |corner: DVec2| {
            (0..n).map(|i| if i == 0 { corner } else { corner + rng.vec2() * (2.0 * spread) }).collect()
        };
        KnotSequences { r: seq(t0), s: seq(t1), t: seq(t2) }
    }

    fn random_polynomial(n: usize, rng: &mut Lcg) -> TriBezier<DVec3> {
        let control = (0..tri_count(n)).map(|_| DVec3::new(rng.next(), rng.next(), rng.next())).collect();
        TriBezier::new(n, DomainTriangle::reference(), control).unwrap()
    }

    /// The B-patch representing `poly`: `c_ijk = F(r_<i, s_<j, t_<k)`.
    fn bpatch_of(poly: &TriBezier<DVec3>, knots: KnotSequences) -> BPatch<DVec3> {
        let n = poly.degree();
        let control = multi_indices(n)
            .map(|[i, j, k]| {
                let args: Vec<DVec2> = knots.r[..i].iter().chain(&knots.s[..j]).chain(&knots.t[..k]).copied().collect();
                poly.blossom(&args).unwrap()
            })
            .collect();
        BPatch::new(n, knots, control).unwrap()
    }

    #[test]
    fn coincident_knots_give_the_bezier_patch() {
        let mut rng = Lcg(1);
        for n in 1..8 {
            let poly = random_polynomial(n, &mut rng);
            let knots = KnotSequences::bezier(poly.domain(), n);
            let patch = BPatch::new(n, knots, poly.control_points().to_vec()).unwrap();
            for _ in 0..10 {
                let u = rng.vec2() + DVec2::splat(0.3);
                assert!((patch.eval(u) - poly.eval(u)).length() < 1e-13);
            }
        }
    }

    #[test]
    fn polynomials_are_reproduced_from_blossom_control_points() {
        // ALGORITHMS.md §10 (i): n = 3, knots perturbed by 0.15; identical to 10 digits.
        let mut rng = Lcg(2);
        for n in 1..6 {
            let poly = random_polynomial(n, &mut rng);
            let patch = bpatch_of(&poly, perturbed_knots(n, 0.15, &mut rng));
            for _ in 0..20 {
                let u = rng.vec2() + DVec2::splat(0.3);
                assert!((patch.eval(u) - poly.eval(u)).length() < 1e-10, "n = {n}");
                let d = rng.vec2();
                assert!((patch.derivative(u, d) - poly.derivative(u, d)).length() < 1e-9);
                let args: Vec<DVec2> = (0..n).map(|_| rng.vec2()).collect();
                assert!((patch.blossom(&args).unwrap() - poly.blossom(&args).unwrap()).length() < 1e-10);
            }
        }
    }

    #[test]
    fn basis_sums_to_one_is_the_weight_of_each_control_point_and_is_non_negative_inside() {
        let mut rng = Lcg(3);
        let n = 4;
        let knots = perturbed_knots(n, 0.08, &mut rng);
        let basis = BPatchBasis::new(n, knots.clone()).unwrap();
        let mut values = Vec::new();
        for _ in 0..20 {
            // Points well inside every knot triangle.
            let l = [0.2 + 0.6 * (rng.next() + 0.5), 0.2, 0.2];
            let s: f64 = l.iter().sum();
            let u = DomainTriangle::reference().point([l[0] / s, l[1] / s, l[2] / s]);
            basis.eval(u, &mut values);
            assert!((values.iter().sum::<f64>() - 1.0).abs() < 1e-13);
            assert!(values.iter().all(|&v| v >= 0.0));
            // The weight of control point i is the patch with the i-th unit control point.
            for (i, value) in values.iter().enumerate() {
                let unit = (0..tri_count(n)).map(|k| if k == i { 1.0 } else { 0.0 }).collect();
                let patch = basis.with_control(unit).unwrap();
                assert!((patch.eval(u) - value).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn patch_lies_in_the_convex_hull_of_its_control_points() {
        let mut rng = Lcg(5);
        for n in 2..6 {
            let knots = perturbed_knots(n, 0.08, &mut rng);
            let control: Vec<DVec3> =
                (0..tri_count(n)).map(|_| DVec3::new(rng.next(), rng.next(), rng.next())).collect();
            let patch = BPatch::new(n, knots, control.clone()).unwrap();
            for _ in 0..20 {
                // Where the basis is non-negative (well inside every knot triangle).
                let l = [0.2 + 0.6 * (rng.next() + 0.5), 0.2 + 0.3 * (rng.next() + 0.5), 0.2];
                let s: f64 = l.iter().sum();
                let u = DomainTriangle::reference().point([l[0] / s, l[1] / s, l[2] / s]);
                assert!(crate::hull_check::in_convex_hull(patch.eval(u), &control, 1e-13), "n = {n}, u = {u}");
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let mut rng = Lcg(4);
        let n = 3;
        let knots = perturbed_knots(n, 0.15, &mut rng);
        let control = (0..tri_count(n)).map(|_| DVec3::new(rng.next(), rng.next(), rng.next())).collect();
        let patch = BPatch::new(n, knots, control).unwrap();
        let h = 1e-6;
        for _ in 0..10 {
            let u = rng.vec2() + DVec2::splat(0.3);
            let (value, [du, dv]) = patch.eval_with_gradient(u);
            assert!((value - patch.eval(u)).length() < 1e-14);
            let fd_u = (patch.eval(u + DVec2::X * h) - patch.eval(u - DVec2::X * h)) / (2.0 * h);
            let fd_v = (patch.eval(u + DVec2::Y * h) - patch.eval(u - DVec2::Y * h)) / (2.0 * h);
            assert!((du - fd_u).length() < 1e-7 && (dv - fd_v).length() < 1e-7);
            let normal = patch.normal(u).unwrap();
            assert!(normal.dot(du).abs() < 1e-12);
        }
    }

    #[test]
    fn bad_knots_are_named() {
        let d = DomainTriangle::reference();
        let mut knots = KnotSequences::bezier(&d, 3);
        knots.s[2] = DVec2::new(0.0, 2.0); // (r_0, s_2, t_0) = (0,0), (0,2), (0,1): collinear
        assert!(matches!(
            BPatchBasis::new(3, knots.clone()),
            Err(SplineError::DegenerateKnotTriangle { i: 0, j: 2, k: 0, .. })
        ));
        knots.s[2] = DVec2::new(-1.0, 0.5); // (r_0, s_2, t_0) clockwise
        assert!(matches!(
            BPatchBasis::new(3, knots.clone()),
            Err(SplineError::KnotTriangleOrientation { i: 0, j: 2, k: 0 })
        ));
        knots.s[2] = DVec2::new(f64::NAN, 0.5);
        assert!(matches!(BPatchBasis::new(3, knots), Err(SplineError::NonFinite { index: 2, .. })));
        let short = KnotSequences { r: vec![DVec2::ZERO], s: vec![DVec2::X], t: vec![] };
        assert!(matches!(BPatchBasis::new(1, short), Err(SplineError::Count { .. })));
        assert!(BPatchBasis::new(0, KnotSequences::bezier(&d, 0)).is_err());
    }

    /// The sequences are public fields of any length: an index beyond one used to panic
    /// with a bare slice-index message.
    #[test]
    fn knot_triangle_indices_are_checked() {
        let knots = KnotSequences { r: vec![DVec2::ZERO; 3], s: vec![DVec2::X; 1], t: vec![] };
        assert_eq!(knots.try_triangle(2, 0, 0), Err(SplineError::IndexOutOfRange { what: "t knot", index: 0, len: 0 }));
        assert_eq!(knots.try_triangle(3, 0, 0), Err(SplineError::IndexOutOfRange { what: "r knot", index: 3, len: 3 }));
        assert_eq!(knots.try_triangle(0, 1, 0), Err(SplineError::IndexOutOfRange { what: "s knot", index: 1, len: 1 }));
        let caught = std::panic::catch_unwind(|| knots.triangle(0, 0, 5)).unwrap_err();
        let message = caught.downcast_ref::<String>().unwrap();
        assert!(message.contains("t knot 5 is out of range (there are 0)"), "{message}");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]

        #[test]
        fn affine_invariance_and_partition_of_unity(seed in 0u64..10_000, n in 1usize..6,
                a in 0.1..0.8f64, b in 0.1..0.8f64,
                m in proptest::array::uniform9(-2.0..2.0f64), t in proptest::array::uniform3(-3.0..3.0f64)) {
            let mut rng = Lcg(seed);
            let knots = perturbed_knots(n, 0.1, &mut rng);
            let control: Vec<DVec3> = (0..tri_count(n)).map(|_| DVec3::new(rng.next(), rng.next(), rng.next())).collect();
            let map = |q: DVec3| DVec3::new(
                m[0] * q.x + m[1] * q.y + m[2] * q.z + t[0],
                m[3] * q.x + m[4] * q.y + m[5] * q.z + t[1],
                m[6] * q.x + m[7] * q.y + m[8] * q.z + t[2],
            );
            let patch = BPatch::new(n, knots.clone(), control.clone()).unwrap();
            let mapped = BPatch::new(n, knots, control.iter().map(|&q| map(q)).collect()).unwrap();
            let u = DVec2::new(a * (1.0 - b), b);
            prop_assert!((mapped.eval(u) - map(patch.eval(u))).length() < 1e-11);
            let mut values = Vec::new();
            patch.basis(u, &mut values);
            prop_assert!((values.iter().sum::<f64>() - 1.0).abs() < 1e-13);
        }
    }
}
