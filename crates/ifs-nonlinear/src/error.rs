//! The error type of the crate.

use thiserror::Error;

/// Everything that can go wrong in this crate: bad user input (each variant names the
/// point, map or parameter at fault) and output failures.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum IfsError {
    /// A coordinate or parameter is NaN or infinite.
    #[error("{what} is not finite ({value})")]
    NotFinite {
        /// What the value is (e.g. "control point 3, coordinate 1").
        what: String,
        /// The offending value.
        value: f64,
    },
    /// Too few control points (or values) for the requested construction.
    #[error("{what} needs at least {needed} points, got {got}")]
    TooFewPoints {
        /// The construction.
        what: &'static str,
        /// The minimum.
        needed: usize,
        /// What was given.
        got: usize,
    },
    /// The number of control points does not match the subdivision matrices.
    #[error("the subdivision matrices act on {expected} control points, got {got}")]
    ControlCountMismatch {
        /// Size of the matrices.
        expected: usize,
        /// Number of control points given.
        got: usize,
    },
    /// A parameter is outside its valid range.
    #[error("parameter {name} = {value} is out of range: {reason}")]
    ParameterOutOfRange {
        /// The parameter's name.
        name: &'static str,
        /// Its value, printed.
        value: String,
        /// The valid range or why it is rejected.
        reason: &'static str,
    },
    /// A subdivision matrix is malformed: wrong shape or a row that does not sum to 1
    /// (the rule would not be affine invariant, ALGORITHMS.md §1.2).
    #[error("subdivision matrix {matrix}: {reason}")]
    BadMatrix {
        /// Index of the matrix.
        matrix: usize,
        /// What is wrong.
        reason: String,
    },
    /// The seed (square) IFS form needs `dim + 1` affinely independent control points;
    /// these are affinely dependent (e.g. collinear points in the plane), so `P̂` is singular.
    #[error(
        "the control points are affinely dependent (|det P̂| = {determinant:e}): the homogeneous control matrix is \
         singular; use the barycentric form"
    )]
    SingularControl {
        /// Determinant of `P̂ = [P | 1]`.
        determinant: f64,
    },
    /// The seed (square) form needs exactly `dim + 1` control points.
    #[error(
        "the square (homogeneous) IFS form needs {needed} control points in {dim}D, got {got}; use the barycentric form"
    )]
    NotSquare {
        /// Dimension of the points.
        dim: usize,
        /// `dim + 1`.
        needed: usize,
        /// Number given.
        got: usize,
    },
    /// The IFS is not contractive on the difference space, so it has no attractor (or
    /// contractivity could not be certified within the word-length budget).
    #[error(
        "the IFS is not contractive: joint spectral radius on the difference space in [{jsr_lower:.6}, {jsr_upper:.6}] \
         (needs < 1){detail}"
    )]
    NotContractive {
        /// Lower bound of the joint spectral radius.
        jsr_lower: f64,
        /// Best upper bound found.
        jsr_upper: f64,
        /// Extra explanation (e.g. which of the |z| < 1, |1 - z| < 1 conditions fails).
        detail: String,
    },
    /// A value is outside the domain of a nonlinear mean or coordinate transform
    /// (e.g. a non-positive value for the geometric mean).
    #[error("point {index}: {value} is outside the domain of the {what} ({domain})")]
    Domain {
        /// Index of the point (in the input sequence, or of the rendered point).
        index: usize,
        /// The value, printed.
        value: String,
        /// The mean or transform.
        what: String,
        /// Its domain.
        domain: &'static str,
    },
    /// The iteration left the finite numbers: a rendered point is NaN or infinite although
    /// the maps and the start states are finite. The maps are not contractive (at least not
    /// on the states reached), so the iterates diverged, or a coordinate overflowed `f64`.
    /// Raised at the first such point rather than returning it.
    #[error(
        "point {index} is not finite ({value}) after {iteration} map applications: the iteration diverged \
         (the maps are not contractive) or overflowed"
    )]
    Diverged {
        /// Index of the point in the output (chaos game: in the whole point list).
        index: usize,
        /// Map applications from the start state that produced the point: the level for
        /// the deterministic algorithm; for the chaos game, the applications since the
        /// start of the point's chunk (burn-in included), or the applications of map 0
        /// that compute the chaos game's start state when that start already diverged.
        iteration: u64,
        /// The point, printed.
        value: String,
    },
    /// The deterministic algorithm would produce more points than the budget allows.
    #[error("{levels} deterministic levels give {needed} points, more than the budget of {budget}")]
    BudgetExceeded {
        /// Requested levels.
        levels: u32,
        /// Points needed (saturated).
        needed: u128,
        /// The budget.
        budget: usize,
    },
    /// The chaos game's point list does not fit in memory (its length overflows, or the
    /// allocation is refused): [`chaos_density`](crate::chaos_density) renders any number
    /// of points without keeping them.
    #[error("{points} points ({bytes} bytes) do not fit in memory; render them into a density image instead")]
    TooManyPoints {
        /// Points asked for.
        points: usize,
        /// Bytes the list would take (saturated).
        bytes: u128,
    },
    /// A rendering parameter is unusable (empty image, empty view, ...).
    #[error("rendering: {0}")]
    Render(String),
    /// An unknown preset name.
    #[error("unknown preset `{name}`; known: {known}")]
    UnknownPreset {
        /// The name asked for.
        name: String,
        /// The known names.
        known: String,
    },
    /// Writing the PNG failed.
    #[error("PNG encoding: {0}")]
    Png(String),
}

/// Result type of the crate.
pub type Result<T, E = IfsError> = std::result::Result<T, E>;

/// Checks that `value` is finite, naming it in the error otherwise.
pub(crate) fn check_finite(value: f64, what: impl FnOnce() -> String) -> Result<f64> {
    if value.is_finite() { Ok(value) } else { Err(IfsError::NotFinite { what: what(), value }) }
}
