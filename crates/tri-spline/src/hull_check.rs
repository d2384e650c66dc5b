//! Test support: an exact point-in-convex-hull test for small 3D point sets.
//!
//! The convex-hull property of Bézier patches, B-patches and DMS splines is a statement
//! about the hull itself, which a bounding box only over-approximates (a point can lie in
//! the box of a tetrahedron and far outside the tetrahedron). The hull's facets are found
//! by brute force: a plane through three of the points bounds the hull exactly when no
//! point lies on its other side. O(n^4), fine for the few dozen points of a patch.

use glam::DVec3;

/// Whether `p` lies in the convex hull of `points` (a full-dimensional set in general
/// position), allowing `tol` of rounding outside each facet plane.
pub(crate) fn in_convex_hull(p: DVec3, points: &[DVec3], tol: f64) -> bool {
    assert!(points.len() >= 4, "a full-dimensional hull needs at least 4 points");
    let mut facets = 0;
    for i in 0..points.len() {
        for j in i + 1..points.len() {
            for k in j + 1..points.len() {
                let normal = (points[j] - points[i]).cross(points[k] - points[i]);
                if normal.length() < 1e-12 {
                    continue;
                }
                let normal = normal.normalize();
                let offset = |q: DVec3| normal.dot(q - points[i]);
                let (lo, hi) =
                    points.iter().fold((0.0f64, 0.0f64), |(lo, hi), &q| (lo.min(offset(q)), hi.max(offset(q))));
                let side = if hi <= 1e-12 {
                    -1.0
                } else if lo >= -1e-12 {
                    1.0
                } else {
                    continue; // points on both sides: not a facet plane
                };
                facets += 1;
                if side * offset(p) < -tol {
                    return false;
                }
            }
        }
    }
    assert!(facets >= 4, "degenerate point set: {facets} facet planes");
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_inside_the_box_but_outside_the_hull_are_rejected() {
        let tetrahedron = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        assert!(in_convex_hull(DVec3::splat(0.2), &tetrahedron, 1e-12));
        assert!(in_convex_hull(DVec3::new(0.5, 0.5, 0.0), &tetrahedron, 1e-12));
        // Inside the unit box, outside the tetrahedron (x + y + z = 1.8 > 1).
        assert!(!in_convex_hull(DVec3::splat(0.6), &tetrahedron, 1e-12));
        assert!(!in_convex_hull(DVec3::new(0.5, 0.5, 0.01), &tetrahedron, 1e-12));
    }
}
