//! Point files: one point per line, `x y` or `x y z`, `#` starts a comment.
//!
//! ```
//! use subdiv_curve::io::{PointSet, parse_points};
//! let text = "# a triangle\n0 0\n1 0   # right corner\n\n0 1\n";
//! let PointSet::Planar(points) = parse_points(text)? else { panic!("2D input") };
//! assert_eq!(points.len(), 3);
//! let err = parse_points("0 0\n1 zero\n").unwrap_err();
//! assert_eq!(err.to_string(), "line 2: `zero` is not a number");
//! # Ok::<(), subdiv_curve::CurveError>(())
//! ```

use glam::{DVec2, DVec3};

use crate::{CurveError, CurvePoint};

/// The points of a file, 2D or 3D (all lines must agree).
///
/// ```
/// use subdiv_curve::io::parse_points;
/// let points = parse_points("0 0 1\n1 2 3\n")?;
/// assert_eq!((points.dimension(), points.len(), points.is_empty()), (3, 2, false));
/// # Ok::<(), subdiv_curve::CurveError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub enum PointSet {
    /// `x y` lines.
    Planar(Vec<DVec2>),
    /// `x y z` lines.
    Spatial(Vec<DVec3>),
}

impl PointSet {
    /// Number of points.
    pub fn len(&self) -> usize {
        match self {
            PointSet::Planar(p) => p.len(),
            PointSet::Spatial(p) => p.len(),
        }
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// 2 or 3.
    pub fn dimension(&self) -> usize {
        match self {
            PointSet::Planar(_) => 2,
            PointSet::Spatial(_) => 3,
        }
    }
}

/// Parses a point file.
///
/// # Errors
/// [`CurveError::Parse`] with the 1-based line number: a token that is not a number, a
/// NaN or infinite coordinate, a line with other than 2 or 3 coordinates, a line whose
/// dimension differs from the first point's, or a file without points.
///
/// ```
/// use subdiv_curve::io::parse_points;
/// assert_eq!(parse_points("0 0 0\n1 1\n").unwrap_err().to_string(),
///            "line 2: 2 coordinates, but the first point (line 1) has 3");
/// assert!(parse_points("0 NaN\n").unwrap_err().to_string().starts_with("line 1: coordinate 2 is not finite"));
/// ```
pub fn parse_points(text: &str) -> Result<PointSet, CurveError> {
    let mut planar = Vec::new();
    let mut spatial = Vec::new();
    let mut first: Option<(usize, usize)> = None; // (line, dimension)
    let mut lines = 0;
    for (number, line) in text.lines().enumerate() {
        let line_number = number + 1;
        lines = line_number;
        let content = line.split('#').next().unwrap_or("");
        let tokens: Vec<&str> =
            content.split(|c: char| c.is_whitespace() || c == ',').filter(|t| !t.is_empty()).collect();
        if tokens.is_empty() {
            continue;
        }
        let error = |message: String| CurveError::Parse { line: line_number, message };
        if !(tokens.len() == 2 || tokens.len() == 3) {
            return Err(error(format!("expected `x y` or `x y z`, found {} values", tokens.len())));
        }
        let mut coordinates = [0.0; 3];
        for (k, token) in tokens.iter().enumerate() {
            let value: f64 = token.parse().map_err(|_| error(format!("`{token}` is not a number")))?;
            if !value.is_finite() {
                return Err(error(format!("coordinate {} is not finite ({token})", k + 1)));
            }
            coordinates[k] = value;
        }
        match first {
            None => first = Some((line_number, tokens.len())),
            Some((first_line, dimension)) if dimension != tokens.len() => {
                return Err(error(format!(
                    "{} coordinates, but the first point (line {first_line}) has {dimension}",
                    tokens.len()
                )));
            }
            Some(_) => {}
        }
        if tokens.len() == 2 {
            planar.push(DVec2::new(coordinates[0], coordinates[1]));
        } else {
            spatial.push(DVec3::from_array(coordinates));
        }
    }
    match first {
        None => Err(CurveError::Parse { line: lines.max(1), message: "the file has no points".into() }),
        Some((_, 2)) => Ok(PointSet::Planar(planar)),
        Some(_) => Ok(PointSet::Spatial(spatial)),
    }
}

/// Writes points one per line, coordinates separated by a space, in the shortest form that
/// reads back to the same `f64` (so `parse_points(format_points(p)) == p`).
///
/// ```
/// use subdiv_curve::io::format_points;
/// assert_eq!(format_points(&[[0.5, -1.0], [0.1, 2e-20]]), "0.5 -1\n0.1 0.00000000000000000002\n");
/// ```
pub fn format_points<P: CurvePoint>(points: &[P]) -> String {
    let mut text = String::with_capacity(points.len() * 24 * P::DIM);
    for point in points {
        for axis in 0..P::DIM {
            if axis > 0 {
                text.push(' ');
            }
            text.push_str(&point.coord(axis).to_string());
        }
        text.push('\n');
    }
    text
}
