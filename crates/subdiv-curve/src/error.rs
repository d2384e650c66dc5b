//! The error type of this crate.

use thiserror::Error;

/// What went wrong, naming the offending point, line, parameter or length.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum CurveError {
    /// The polygon has fewer points than the scheme (or operation) needs.
    #[error("{what} needs at least {needed} points for {} polygon, got {got}", if *closed { "a closed" } else { "an open" })]
    TooFewPoints {
        /// The scheme or operation.
        what: String,
        /// Minimum number of points.
        needed: usize,
        /// Number of points given.
        got: usize,
        /// Whether the polygon is closed.
        closed: bool,
    },
    /// A coordinate is NaN or infinite.
    #[error("point {index} has a non-finite coordinate {value} on axis {axis}")]
    NonFinite {
        /// Index of the point.
        index: usize,
        /// Coordinate axis (0 = x).
        axis: usize,
        /// The offending value.
        value: f64,
    },
    /// A scheme parameter lies outside the range where the scheme converges (or where the
    /// construction is defined).
    #[error("{parameter} = {value} is outside the allowed range {range}")]
    ParameterOutOfRange {
        /// The parameter (`tension w`, `omega1`, `gamma`, ...).
        parameter: &'static str,
        /// The value given.
        value: f64,
        /// The allowed range, written out.
        range: String,
    },
    /// Finite input whose result is not: the weighted sums overflow `f64` (coordinates
    /// within a factor of a few of `f64::MAX`).
    #[error("{what}: point {index} of the result is not finite (the input's coordinates are too large)")]
    Overflow {
        /// The operation.
        what: &'static str,
        /// Index of the first point of the result that is not finite.
        index: usize,
    },
    /// A subdivision rule is malformed (empty, non-finite weights, weights not summing to 1).
    #[error("invalid subdivision rule: {0}")]
    InvalidRule(String),
    /// A length does not fit the operation (e.g. a fine polygon whose length is not that of
    /// a Chaikin refinement, or details that do not match the coarse points).
    #[error("{what}: {detail}")]
    IncompatibleLength {
        /// The operation.
        what: &'static str,
        /// Which lengths, and what was expected.
        detail: String,
    },
    /// An index of a point to interpolate is not an index of the polygon.
    #[error("interpolation index {index} is out of range for a polygon of {len} points")]
    IndexOutOfRange {
        /// The index given.
        index: usize,
        /// Number of points of the polygon.
        len: usize,
    },
    /// The number of interpolation flags differs from the number of points.
    #[error("{flags} interpolation flags for {points} points")]
    FlagCount {
        /// Number of flags.
        flags: usize,
        /// Number of points.
        points: usize,
    },
    /// The operation is defined only for some point dimensions.
    #[error("{what} needs {expected} points, got {dim}-dimensional points")]
    Dimension {
        /// The operation.
        what: &'static str,
        /// What it accepts, in words.
        expected: &'static str,
        /// The dimension given.
        dim: usize,
    },
    /// A point file could not be parsed.
    #[error("line {line}: {message}")]
    Parse {
        /// 1-based line number.
        line: usize,
        /// What is wrong on that line.
        message: String,
    },
    /// A refinement would make more points than it may ([`crate::MAX_REFINED_POINTS`]).
    #[error("{points} points refined {levels} times would make more than {max} points")]
    TooLarge {
        /// Number of points given.
        points: usize,
        /// Number of levels asked for.
        levels: u32,
        /// The most points a refinement makes.
        max: usize,
    },
    /// The linear system of the exact-global virtual points could not be solved.
    #[error("virtual points: {0}")]
    VirtualPoints(String),
}
