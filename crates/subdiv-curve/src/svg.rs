//! SVG drawings of a control polygon, its refined (limit) curve and marked points, written
//! directly (no dependency). Points are projected on the `xy` plane (3D input drops `z`);
//! `y` points up.
//!
//! ```
//! use subdiv_curve::{CurveScheme, Topology, svg::{Mark, SvgScene, render_svg}};
//! let control = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]];
//! let curve = CurveScheme::cubic_bspline().refine(&control, Topology::Closed, 4)?;
//! let svg = render_svg(&SvgScene { control: &control, curve: &curve, closed: true, marks: &[(0, Mark::Interpolated)] });
//! assert!(svg.starts_with("<svg") && svg.contains("<polygon") && svg.contains("<circle"));
//! # Ok::<(), subdiv_curve::CurveError>(())
//! ```

use std::fmt::Write as _;

use crate::CurvePoint;
use crate::select::PointClass;

/// How a control point is marked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mark {
    /// Interpolated because the user asked for it (black).
    Interpolated,
    /// Chosen automatically, coloured by class: cusp purple, inflection green, curvature
    /// maximum red, end point orange.
    Chosen(PointClass),
}

impl Mark {
    fn colour(self) -> &'static str {
        match self {
            Mark::Interpolated => "#000000",
            Mark::Chosen(PointClass::Cusp) => "#8e24aa",
            Mark::Chosen(PointClass::Inflection) => "#2e7d32",
            Mark::Chosen(PointClass::CurvatureMaximum) => "#d32f2f",
            Mark::Chosen(PointClass::EndPoint) => "#ef6c00",
        }
    }

    fn label(self) -> &'static str {
        match self {
            Mark::Interpolated => "interpolated",
            Mark::Chosen(class) => class.name(),
        }
    }
}

/// What to draw.
#[derive(Debug, Clone, Copy)]
pub struct SvgScene<'a, P> {
    /// Control polygon (grey, dashed, with small dots).
    pub control: &'a [P],
    /// Refined points (blue).
    pub curve: &'a [P],
    /// Draw both as closed loops.
    pub closed: bool,
    /// Marked control points: (index into `control`, mark). Indices out of range are
    /// ignored.
    pub marks: &'a [(usize, Mark)],
}

/// Width of the drawing in SVG user units; the height follows the aspect ratio.
const WIDTH: f64 = 800.0;
const MARGIN: f64 = 24.0;

/// Renders the scene as a standalone SVG document.
///
/// ```
/// use subdiv_curve::svg::{SvgScene, render_svg};
/// let empty: [[f64; 2]; 0] = [];
/// let svg = render_svg(&SvgScene { control: &empty, curve: &empty, closed: false, marks: &[] });
/// assert!(svg.ends_with("</svg>\n"));
/// ```
pub fn render_svg<P: CurvePoint>(scene: &SvgScene<'_, P>) -> String {
    // The projection of `to_dvec3` (missing coordinates are 0, so a point type of fewer
    // than two coordinates, even none, draws on the x axis or at the origin).
    let xy = |p: &P| {
        let p = p.to_dvec3();
        (p.x, p.y)
    };
    let all = scene.control.iter().chain(scene.curve).map(xy);
    let (mut lo, mut hi) = ((f64::INFINITY, f64::INFINITY), (f64::NEG_INFINITY, f64::NEG_INFINITY));
    for (x, y) in all {
        lo = (lo.0.min(x), lo.1.min(y));
        hi = (hi.0.max(x), hi.1.max(y));
    }
    if lo.0 > hi.0 {
        (lo, hi) = ((0.0, 0.0), (1.0, 1.0));
    }
    // Differences of halves: the extent of points near +-f64::MAX does not overflow (a
    // halving is exact, so other drawings are the same to the bit).
    let half = |a: f64, b: f64| a / 2.0 - b / 2.0;
    // At least the span whose scale is `f64::MAX`: points that all coincide (a span of
    // zero) are drawn at the corner, not at `0 × ∞ = NaN`.
    let half_span = half(hi.0, lo.0).max(half(hi.1, lo.1)).max((WIDTH - 2.0 * MARGIN) / f64::MAX);
    let scale = (WIDTH - 2.0 * MARGIN) / half_span;
    let height = (half(hi.1, lo.1) * scale + 2.0 * MARGIN).max(2.0 * MARGIN);
    let to_screen = |p: &P| {
        let (x, y) = xy(p);
        (MARGIN + half(x, lo.0) * scale, height - MARGIN - half(y, lo.1) * scale)
    };
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{WIDTH}\" height=\"{height:.2}\" viewBox=\"0 0 {WIDTH} {height:.2}\">"
    );
    let _ = writeln!(svg, "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>");
    let coordinates = |points: &[P]| {
        let mut text = String::with_capacity(points.len() * 18);
        for (k, p) in points.iter().enumerate() {
            let (x, y) = to_screen(p);
            let _ = write!(text, "{}{x:.3},{y:.3}", if k == 0 { "" } else { " " });
        }
        text
    };
    let shape = if scene.closed { "polygon" } else { "polyline" };
    if !scene.control.is_empty() {
        let _ = writeln!(
            svg,
            "<{shape} class=\"control\" points=\"{}\" fill=\"none\" stroke=\"#9e9e9e\" stroke-width=\"1\" stroke-dasharray=\"4 3\"/>",
            coordinates(scene.control)
        );
    }
    if !scene.curve.is_empty() {
        let _ = writeln!(
            svg,
            "<{shape} class=\"curve\" points=\"{}\" fill=\"none\" stroke=\"#1565c0\" stroke-width=\"2\"/>",
            coordinates(scene.curve)
        );
    }
    for p in scene.control {
        let (x, y) = to_screen(p);
        let _ = writeln!(svg, "<circle cx=\"{x:.3}\" cy=\"{y:.3}\" r=\"2.5\" fill=\"#9e9e9e\"/>");
    }
    let mut legend: Vec<Mark> = Vec::new();
    for &(index, mark) in scene.marks {
        let Some(p) = scene.control.get(index) else { continue };
        let (x, y) = to_screen(p);
        let _ = writeln!(
            svg,
            "<circle class=\"{}\" cx=\"{x:.3}\" cy=\"{y:.3}\" r=\"5\" fill=\"{}\" stroke=\"white\" stroke-width=\"1\"><title>point {index}: {}</title></circle>",
            mark.label(),
            mark.colour(),
            mark.label()
        );
        if !legend.contains(&mark) {
            legend.push(mark);
        }
    }
    for (row, mark) in legend.iter().enumerate() {
        let y = 16.0 + 16.0 * row as f64;
        let _ = writeln!(svg, "<circle cx=\"12\" cy=\"{y}\" r=\"5\" fill=\"{}\"/>", mark.colour());
        let _ = writeln!(
            svg,
            "<text x=\"22\" y=\"{}\" font-family=\"sans-serif\" font-size=\"12\">{}</text>",
            y + 4.0,
            mark.label()
        );
    }
    svg.push_str("</svg>\n");
    svg
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points at the ends of the `f64` range are drawn (their extent overflowed to
    /// infinity, and every coordinate was written as NaN); ordinary points are drawn at
    /// the same places as by the plain differences.
    #[test]
    fn extreme_points_are_drawn_with_finite_coordinates() {
        let extreme = [[-f64::MAX, 0.0], [f64::MAX, 1.0], [0.0, -f64::MAX]];
        let svg = render_svg(&SvgScene { control: &extreme, curve: &extreme, closed: true, marks: &[] });
        assert!(!svg.contains("NaN") && !svg.contains("inf"), "{svg}");
        assert!(svg.contains("24.000,") && svg.contains("776.000,"), "{svg}");
        let square = [[0.0, 0.0], [3.0, 0.0], [3.0, 1.5], [0.0, 1.5]];
        let svg = render_svg(&SvgScene { control: &square, curve: &[], closed: true, marks: &[] });
        let scale = (WIDTH - 2.0 * MARGIN) / 3.0;
        let height = 1.5 * scale + 2.0 * MARGIN;
        for [x, y] in square {
            let (sx, sy) = (MARGIN + x * scale, height - MARGIN - y * scale);
            assert!(svg.contains(&format!("{sx:.3},{sy:.3}")), "{sx:.3},{sy:.3} in {svg}");
        }
    }

    /// Point types of fewer than two coordinates are drawn (a zero-dimensional type
    /// indexed coordinate 0, which it does not have, and panicked): 1D points on the x
    /// axis, 0D points at the origin. Points that all coincide are drawn at the corner
    /// (every coordinate was NaN: a zero span scaled by infinity).
    #[test]
    fn low_dimensional_and_coincident_points_are_drawn() {
        let none = [[0.0f64; 0]; 3];
        let svg =
            render_svg(&SvgScene { control: &none, curve: &none, closed: false, marks: &[(1, Mark::Interpolated)] });
        // Three control points, the mark and its legend entry.
        assert_eq!(svg.matches("<circle").count(), 5, "{svg}");
        assert!(!svg.contains("NaN") && svg.contains("cx=\"24.000\" cy=\"24.000\""), "{svg}");
        let same = [[1.5, -2.0]; 2];
        let svg = render_svg(&SvgScene { control: &same, curve: &same, closed: true, marks: &[] });
        assert!(!svg.contains("NaN") && svg.contains("points=\"24.000,24.000 24.000,24.000\""), "{svg}");
        let line = [0.0f64, 2.0, 1.0];
        let svg = render_svg(&SvgScene { control: &line, curve: &line, closed: false, marks: &[] });
        assert!(svg.contains("24.000,") && svg.contains("776.000,") && !svg.contains("NaN"), "{svg}");
    }
}
