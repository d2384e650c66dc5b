//! Planar triangles: barycentric coordinates, orientation, the half-open membership rule.

use glam::DVec2;
use serde::{Deserialize, Serialize};

use crate::SplineError;

/// Relative tolerance under which a triangle counts as degenerate: `|det| <= DEGENERATE
/// * scale^2`, with `scale` the longest edge.
pub const DEGENERATE: f64 = 1e-12;

/// `det(a, b, c) = (b - a) x (c - a)`: twice the signed area, positive counter-clockwise.
///
/// ```
/// use glam::DVec2;
/// use tri_spline::domain::orient;
/// assert_eq!(orient(DVec2::ZERO, DVec2::X, DVec2::Y), 1.0);
/// assert_eq!(orient(DVec2::ZERO, DVec2::Y, DVec2::X), -1.0);
/// assert_eq!(orient(DVec2::ZERO, DVec2::ONE, DVec2::splat(3.0)), 0.0);
/// ```
#[inline(always)]
pub fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Whether `(a, b, c)` is degenerate relative to its own size (or not finite).
///
/// ```
/// use glam::DVec2;
/// use tri_spline::domain::is_degenerate;
/// assert!(is_degenerate(DVec2::ZERO, DVec2::X, DVec2::X * 2.0));
/// assert!(is_degenerate(DVec2::ZERO, DVec2::X, DVec2::NAN));
/// // Relative to its size: a tiny triangle is fine.
/// assert!(!is_degenerate(DVec2::ZERO, DVec2::X * 1e-9, DVec2::Y * 1e-9));
/// ```
pub fn is_degenerate(a: DVec2, b: DVec2, c: DVec2) -> bool {
    let scale2 = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
    let det = orient(a, b, c);
    !det.is_finite() || scale2 == 0.0 || det.abs() <= DEGENERATE * scale2
}

/// The affine map from the plane to barycentric coordinates with respect to a
/// non-degenerate triangle, precomputed (six numbers) for fast repeated evaluation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BaryMap {
    origin: DVec2,
    /// `λ1 = g1 · (u - origin)`.
    g1: DVec2,
    /// `λ2 = g2 · (u - origin)`.
    g2: DVec2,
}

impl BaryMap {
    /// The map for triangle `(a, b, c)`; `None` when it is degenerate.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::domain::BaryMap;
    /// let map = BaryMap::new(DVec2::X, DVec2::new(3.0, 0.0), DVec2::new(1.0, 2.0)).unwrap();
    /// assert_eq!(map.coords(DVec2::new(2.0, 1.0)), [0.0, 0.5, 0.5]);
    /// assert!(BaryMap::new(DVec2::ZERO, DVec2::X, DVec2::X * 2.0).is_none());
    /// ```
    pub fn new(a: DVec2, b: DVec2, c: DVec2) -> Option<Self> {
        if is_degenerate(a, b, c) {
            return None;
        }
        let (e1, e2) = (b - a, c - a);
        let det = e1.perp_dot(e2);
        // u - a = λ1 e1 + λ2 e2  =>  λ1 = (u - a) x e2 / det, λ2 = e1 x (u - a) / det.
        Some(Self { origin: a, g1: DVec2::new(e2.y, -e2.x) / det, g2: DVec2::new(-e1.y, e1.x) / det })
    }

    /// Barycentric coordinates of `u` (they sum to one).
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::domain::BaryMap;
    /// let (a, b, c) = (DVec2::new(0.5, 0.0), DVec2::new(2.0, 0.5), DVec2::new(1.0, 2.0));
    /// let map = BaryMap::new(a, b, c).unwrap();
    /// let l = map.coords(DVec2::new(1.2, 0.8));
    /// assert!((l.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    /// assert!((a * l[0] + b * l[1] + c * l[2] - DVec2::new(1.2, 0.8)).length() < 1e-15);
    /// ```
    #[inline(always)]
    pub fn coords(&self, u: DVec2) -> [f64; 3] {
        let w = u - self.origin;
        let l1 = self.g1.dot(w);
        let l2 = self.g2.dot(w);
        [1.0 - l1 - l2, l1, l2]
    }

    /// Barycentric coordinates of the vector `d` (they sum to zero): the directional
    /// derivatives of the three coordinate functions along `d`.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::domain::BaryMap;
    /// let map = BaryMap::new(DVec2::ZERO, DVec2::X, DVec2::Y).unwrap();
    /// assert_eq!(map.direction(DVec2::X), [-1.0, 1.0, 0.0]);
    /// assert_eq!(map.direction(DVec2::new(0.5, 0.5)), [-1.0, 0.5, 0.5]);
    /// ```
    #[inline(always)]
    pub fn direction(&self, d: DVec2) -> [f64; 3] {
        let l1 = self.g1.dot(d);
        let l2 = self.g2.dot(d);
        [-l1 - l2, l1, l2]
    }
}

/// The domain triangle `(t0, t1, t2)` of a patch (any orientation, not degenerate).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DomainTriangle {
    corners: [DVec2; 3],
    map: BaryMap,
}

impl DomainTriangle {
    /// A triangle from its corners.
    ///
    /// # Errors
    /// [`SplineError::DegenerateDomain`] if the corners are not finite or (nearly) collinear.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::DomainTriangle;
    /// let t = DomainTriangle::new([DVec2::ZERO, DVec2::X, DVec2::Y])?;
    /// assert_eq!(t.barycentric(DVec2::new(0.25, 0.5)), [0.25, 0.25, 0.5]);
    /// assert!(DomainTriangle::new([DVec2::ZERO, DVec2::X, DVec2::X * 2.0]).is_err());
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn new(corners: [DVec2; 3]) -> Result<Self, SplineError> {
        let [a, b, c] = corners;
        BaryMap::new(a, b, c).map(|map| Self { corners, map }).ok_or(SplineError::DegenerateDomain { corners })
    }

    /// The reference triangle `(0,0), (1,0), (0,1)`.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::DomainTriangle;
    /// let t = DomainTriangle::reference();
    /// assert_eq!(t.corners(), [DVec2::ZERO, DVec2::X, DVec2::Y]);
    /// assert_eq!(t.barycentric(DVec2::new(0.5, 0.25)), [0.25, 0.5, 0.25]);
    /// ```
    pub fn reference() -> Self {
        Self::new([DVec2::ZERO, DVec2::X, DVec2::Y]).expect("internal: reference triangle")
    }

    /// The equilateral triangle `(0,0), (1,0), (1/2, √3/2)` (the fitting domain).
    ///
    /// ```
    /// use tri_spline::DomainTriangle;
    /// let [a, b, c] = DomainTriangle::equilateral().corners();
    /// for side in [b - a, c - b, a - c] {
    ///     assert!((side.length() - 1.0).abs() < 1e-15);
    /// }
    /// ```
    pub fn equilateral() -> Self {
        Self::new([DVec2::ZERO, DVec2::X, DVec2::new(0.5, 0.75f64.sqrt())]).expect("internal: equilateral triangle")
    }

    /// The corners `t0, t1, t2`.
    pub fn corners(&self) -> [DVec2; 3] {
        self.corners
    }

    /// Barycentric coordinates of `u`.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::DomainTriangle;
    /// let t = DomainTriangle::equilateral();
    /// let [_, b, c] = t.corners();
    /// assert!((t.barycentric((b + c) * 0.5)[0]).abs() < 1e-15);
    /// // `point` inverts it.
    /// let u = DVec2::new(0.4, 0.3);
    /// assert!((t.point(t.barycentric(u)) - u).length() < 1e-15);
    /// ```
    #[inline]
    pub fn barycentric(&self, u: DVec2) -> [f64; 3] {
        self.map.coords(u)
    }

    /// Barycentric coordinates of a direction vector (summing to zero).
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::DomainTriangle;
    /// let t = DomainTriangle::equilateral();
    /// let (u, d) = (DVec2::new(0.4, 0.3), DVec2::new(0.1, -0.2));
    /// // The change of the barycentric coordinates along d.
    /// let (l, m, dl) = (t.barycentric(u), t.barycentric(u + d), t.direction(d));
    /// assert!((0..3).all(|i| (m[i] - l[i] - dl[i]).abs() < 1e-15));
    /// assert!(dl.iter().sum::<f64>().abs() < 1e-15);
    /// ```
    #[inline]
    pub fn direction(&self, d: DVec2) -> [f64; 3] {
        self.map.direction(d)
    }

    /// The point with barycentric coordinates `l`.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::DomainTriangle;
    /// let t = DomainTriangle::new([DVec2::ZERO, DVec2::new(3.0, 0.0), DVec2::new(0.0, 3.0)])?;
    /// assert_eq!(t.point([0.0, 1.0, 0.0]), DVec2::new(3.0, 0.0));
    /// assert_eq!(t.point([1.0 / 3.0; 3]), DVec2::ONE);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    #[inline]
    pub fn point(&self, l: [f64; 3]) -> DVec2 {
        self.corners[0] * l[0] + self.corners[1] * l[1] + self.corners[2] * l[2]
    }

    /// The precomputed barycentric map.
    pub fn bary_map(&self) -> &BaryMap {
        &self.map
    }

    /// Twice the signed area.
    ///
    /// ```
    /// use glam::DVec2;
    /// use tri_spline::DomainTriangle;
    /// assert_eq!(DomainTriangle::reference().det(), 1.0);
    /// assert!((DomainTriangle::equilateral().det() - 0.75f64.sqrt()).abs() < 1e-15);
    /// // Clockwise triangles are allowed, with a negative determinant.
    /// assert_eq!(DomainTriangle::new([DVec2::ZERO, DVec2::Y, DVec2::X])?.det(), -1.0);
    /// # Ok::<(), tri_spline::SplineError>(())
    /// ```
    pub fn det(&self) -> f64 {
        orient(self.corners[0], self.corners[1], self.corners[2])
    }
}

/// The fixed direction of the half-open rule, `(1, √2)/|.|`, and its tie-breaker
/// `(-√3, 1)/|.|` (ALGORITHMS.md §11.1).
const HALF_OPEN_DIRECTIONS: [DVec2; 2] = [
    DVec2::new(0.577_350_269_189_625_8, 0.816_496_580_927_726), // (1, √2)/√3
    DVec2::new(-0.866_025_403_784_438_6, 0.5),                  // (-√3, 1)/2
];

/// Whether `u` lies in the half-open triangle `[a, b, c)`: inside, or on an edge or
/// corner from which the fixed direction `d` (then `d'`) points into the interior.
///
/// With this rule the triangles of any triangulation partition the plane they cover
/// exactly, so sums of characteristic functions are exactly one on shared edges.
/// Each edge sign is computed as `(p - u) x (q - u)` for the edge's two end points, the
/// same expression (up to an exact sign change) in every triangle sharing that edge.
///
/// ```
/// use glam::DVec2;
/// use tri_spline::domain::in_half_open;
/// // The two triangles of the unit square share the diagonal.
/// let (a, b, c, d) = (DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y);
/// assert!(in_half_open(DVec2::new(0.6, 0.2), a, b, c));
/// assert!(!in_half_open(DVec2::new(0.2, 0.6), a, b, c));
/// // A point on the shared edge belongs to exactly one of them.
/// let on_edge = DVec2::new(0.5, 0.5);
/// assert!(in_half_open(on_edge, a, b, c) != in_half_open(on_edge, a, c, d));
/// ```
pub fn in_half_open(u: DVec2, a: DVec2, b: DVec2, c: DVec2) -> bool {
    let det = orient(a, b, c);
    if det == 0.0 {
        return false;
    }
    let sign = det.signum();
    // Coordinate j vanishes on the edge opposite corner j.
    for (p, q) in [(b, c), (c, a), (a, b)] {
        let s = (p - u).perp_dot(q - u) * sign;
        if s > 0.0 {
            continue;
        }
        if s < 0.0 {
            return false;
        }
        // On the edge line: the derivative of this coordinate along d is ((q - p) x d) / det.
        let edge = q - p;
        let mut entering = false;
        let mut decided = false;
        for d in HALF_OPEN_DIRECTIONS {
            let g = edge.perp_dot(d) * sign;
            if g != 0.0 {
                entering = g > 0.0;
                decided = true;
                break;
            }
        }
        if !decided || !entering {
            return false;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barycentric_round_trip() {
        let t = DomainTriangle::new([DVec2::new(0.3, -1.0), DVec2::new(2.0, 0.5), DVec2::new(-0.5, 1.5)]).unwrap();
        let u = DVec2::new(0.4, 0.2);
        let l = t.barycentric(u);
        assert!((l.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert!((t.point(l) - u).length() < 1e-15);
        let d = t.direction(DVec2::new(0.7, -0.1));
        assert!(d.iter().sum::<f64>().abs() < 1e-15);
        let moved = t.barycentric(u + DVec2::new(0.7, -0.1));
        for i in 0..3 {
            assert!((moved[i] - l[i] - d[i]).abs() < 1e-14);
        }
    }

    #[test]
    fn half_open_rule_partitions_a_square() {
        // Two triangulations of the unit square; every point of a lattice (many on edges
        // and corners) belongs to exactly one triangle of each.
        let (p00, p10, p11, p01) = (DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y);
        let mid = DVec2::splat(0.5);
        let splits: [Vec<[DVec2; 3]>; 2] = [
            vec![[p00, p10, p11], [p00, p11, p01]],
            vec![[p00, p10, mid], [p10, p11, mid], [p11, p01, mid], [p01, p00, mid]],
        ];
        for triangles in &splits {
            for i in 1..8 {
                for j in 1..8 {
                    let u = DVec2::new(i as f64 / 8.0, j as f64 / 8.0);
                    let hits = triangles.iter().filter(|t| in_half_open(u, t[0], t[1], t[2])).count();
                    assert_eq!(hits, 1, "{u}");
                    // Orientation does not matter.
                    let hits = triangles.iter().filter(|t| in_half_open(u, t[0], t[2], t[1])).count();
                    assert_eq!(hits, 1, "{u}");
                }
            }
        }
    }

    #[test]
    fn degenerate_domain_is_an_error() {
        assert!(DomainTriangle::new([DVec2::ZERO, DVec2::ONE, DVec2::splat(2.0)]).is_err());
        assert!(DomainTriangle::new([DVec2::ZERO, DVec2::X, DVec2::new(f64::NAN, 1.0)]).is_err());
    }
}
