//! The error type of this crate.

use glam::DVec2;
use thiserror::Error;

/// What went wrong, naming the offending element (control point, knot, triangle, face,
/// vertex or data point index).
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum SplineError {
    /// The domain triangle is degenerate or not finite.
    #[error("degenerate domain triangle {corners:?}")]
    DegenerateDomain {
        /// Its corners.
        corners: [DVec2; 3],
    },
    /// The degree is outside the supported range.
    #[error("degree {degree} is out of range (supported: {min}..={max})")]
    Degree {
        /// The requested degree.
        degree: usize,
        /// Smallest supported degree.
        min: usize,
        /// Largest supported degree.
        max: usize,
    },
    /// A list has the wrong length.
    #[error("{what}: expected {expected} entries, got {got}")]
    Count {
        /// What the list holds.
        what: &'static str,
        /// The required length.
        expected: usize,
        /// The given length.
        got: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("{what} {index} is not finite")]
    NonFinite {
        /// What kind of value.
        what: &'static str,
        /// Its index.
        index: usize,
    },
    /// A size given by the caller is beyond the documented limit of the function (checked
    /// before anything is allocated, so that a mistyped size is an error, not an abort).
    #[error("{what} {requested} is too large (at most {max})")]
    TooLarge {
        /// What the size counts.
        what: &'static str,
        /// The requested size.
        requested: usize,
        /// The largest supported size.
        max: usize,
    },
    /// An index given by the caller is out of range.
    #[error("{what} {index} is out of range (there are {len})")]
    IndexOutOfRange {
        /// What the index selects.
        what: &'static str,
        /// The index.
        index: usize,
        /// Number of valid indices (`0..len`).
        len: usize,
    },
    /// A multi-index `β` does not have the degree of the patch or basis (`β0 + β1 + β2`
    /// must be the degree `n`).
    #[error("multi-index {beta:?} does not sum to the degree {degree}")]
    MultiIndexDegree {
        /// The multi-index.
        beta: [usize; 3],
        /// The degree it must sum to.
        degree: usize,
    },
    /// An iteration produced a NaN or infinite value from finite input: it diverged (for
    /// LSPIA and PIA usually because the step or weight is too large).
    #[error("{method} diverged at iteration {iteration}: {what} {index} is not finite; {hint}")]
    Diverged {
        /// The method (`lspia`, `pia`, `seed`).
        method: &'static str,
        /// The iteration (numbered from 1, as in the records) whose control net or
        /// residual first holds a non-finite value.
        iteration: usize,
        /// The first non-finite value: `"control point"` or `"residual of data point"`.
        what: &'static str,
        /// Its index.
        index: usize,
        /// What to do about it.
        hint: &'static str,
    },
    /// Finite input so large that a derived quantity of the result overflows the `f64`
    /// range.
    #[error(
        "{what} overflows the f64 range: the largest input coordinate is {largest_coordinate:e}; scale the input down"
    )]
    Overflow {
        /// The quantity that overflows.
        what: &'static str,
        /// The largest absolute coordinate of the input.
        largest_coordinate: f64,
    },
    /// A B-patch knot triangle `(r_i, s_j, t_k)`, `i + j + k <= n - 1`, is degenerate.
    #[error("B-patch knot triangle (r_{i}, s_{j}, t_{k}) = {points:?} is degenerate")]
    DegenerateKnotTriangle {
        /// Index into the `r` knots.
        i: usize,
        /// Index into the `s` knots.
        j: usize,
        /// Index into the `t` knots.
        k: usize,
        /// The three knots.
        points: [DVec2; 3],
    },
    /// A B-patch knot triangle is oriented against `(r_0, s_0, t_0)`.
    #[error("B-patch knot triangle (r_{i}, s_{j}, t_{k}) is oriented against (r_0, s_0, t_0)")]
    KnotTriangleOrientation {
        /// Index into the `r` knots.
        i: usize,
        /// Index into the `s` knots.
        j: usize,
        /// Index into the `t` knots.
        k: usize,
    },
    /// A triangle of the DMS parameter triangulation refers to a missing vertex.
    #[error("triangle {triangle} refers to vertex {vertex}, but there are {vertex_count} vertices")]
    VertexIndex {
        /// The triangle.
        triangle: usize,
        /// The bad index.
        vertex: u32,
        /// Number of vertices.
        vertex_count: usize,
    },
    /// A triangle of the DMS parameter triangulation is degenerate or clockwise.
    #[error("parameter triangle {triangle} (vertices {vertices:?}) is degenerate or clockwise")]
    BadDomainTriangle {
        /// The triangle.
        triangle: usize,
        /// Its vertices.
        vertices: [u32; 3],
    },
    /// A DMS knot triangle `(r_i, s_j, t_k)`, `i + j + k <= n`, of triangle `I` is
    /// degenerate or not oriented like `I`.
    #[error(
        "DMS knot condition fails in triangle {triangle}: knot triangle (r_{i}, s_{j}, t_{k}) is degenerate or oriented against the triangle"
    )]
    DmsKnotOrientation {
        /// The triangle `I`.
        triangle: usize,
        /// Knot index in the cloud of the first vertex.
        i: usize,
        /// Knot index in the cloud of the second vertex.
        j: usize,
        /// Knot index in the cloud of the third vertex.
        k: usize,
    },
    /// Three knots of one DMS triangle's knot set are (nearly) collinear: the knots
    /// are not in general position and a simplex spline would not be a function.
    #[error(
        "knots of triangle {triangle} are not in general position: {knots:?} (as (vertex, cloud index)) are collinear"
    )]
    CollinearKnots {
        /// The triangle.
        triangle: usize,
        /// The three knots as `(vertex, index in its cloud)`.
        knots: [(u32, usize); 3],
    },
    /// Too few knots for a simplex spline.
    #[error("a simplex spline needs at least 3 knots, got {got}")]
    TooFewKnots {
        /// Number of knots given.
        got: usize,
    },
    /// Knots of a simplex spline are collinear or coincident (they must be in general
    /// position, else the spline need not be a function).
    #[error("the simplex spline knots {knots:?} (indices) are collinear: knots must be in general position")]
    DegenerateSimplex {
        /// Indices of the collinear knots.
        knots: Vec<usize>,
    },
    /// The mesh is not valid.
    #[error(transparent)]
    Mesh(#[from] mesh_topo::MeshError),
    /// Reverse Loop subdivision failed.
    #[error(transparent)]
    Loop(#[from] subdiv_loop::LoopError),
    /// A face is not a triangle.
    #[error("face {face} has {corners} corners; fitting needs a triangle mesh")]
    NotTriangle {
        /// The face.
        face: usize,
        /// Its number of corners.
        corners: usize,
    },
    /// The mesh is not a topological disk.
    #[error(
        "the mesh is not a disk: {components} component(s), {boundary_loops} boundary loop(s), Euler characteristic {euler}; {hint}"
    )]
    NotDisk {
        /// Connected components.
        components: usize,
        /// Boundary loops.
        boundary_loops: usize,
        /// Euler characteristic.
        euler: i64,
        /// What to do about it (e.g. "closed meshes need to be cut into charts").
        hint: &'static str,
    },
    /// A vertex is used by no face.
    #[error("vertex {vertex} is used by no face; remove isolated vertices before fitting")]
    IsolatedVertex {
        /// The vertex.
        vertex: usize,
    },
    /// The boundary is too short to be split at three corners.
    #[error("the boundary has {len} vertices; at least 3 are needed to map it onto a triangle")]
    ShortBoundary {
        /// Number of boundary vertices.
        len: usize,
    },
    /// A given corner vertex is not a boundary vertex (or corners repeat).
    #[error("corner vertex {vertex} is not a distinct boundary vertex")]
    BadCorner {
        /// The vertex.
        vertex: usize,
    },
    /// A face maps to a degenerate or flipped triangle in the parameter domain.
    #[error("face {face} maps to a degenerate or flipped parameter triangle (signed area {area:e}); {hint}")]
    DegenerateParameterTriangle {
        /// The face.
        face: usize,
        /// Its signed parameter area.
        area: f64,
        /// What to do about it.
        hint: &'static str,
    },
    /// The mesh is not a regular triangular grid (needed for Bézier and B-patch control nets).
    #[error("the mesh is not a regular triangular grid: {reason}")]
    NotRegularGrid {
        /// What is wrong.
        reason: String,
    },
    /// More reverse-Loop levels were asked for than the connectivity allows.
    #[error("{requested} reverse Loop level(s) requested, but this mesh allows only {possible}: {reason}")]
    ReverseLevels {
        /// Requested levels.
        requested: u32,
        /// Levels the connectivity allows.
        possible: u32,
        /// Why no more.
        reason: String,
    },
    /// A linear solve failed.
    #[error("{what}: the matrix is singular or the factorization failed")]
    Singular {
        /// Which solve.
        what: &'static str,
    },
    /// The iteration matrix has spectral radius at least one: the iteration diverges or stalls.
    #[error("{method} does not converge here: spectral radius of its iteration matrix is {spectral_radius} >= 1")]
    NotConvergent {
        /// The method.
        method: &'static str,
        /// The computed spectral radius.
        spectral_radius: f64,
    },
    /// A method cannot be used with this surface or input.
    #[error("{method} is not available for {surface}: {reason}")]
    Unsupported {
        /// The method.
        method: &'static str,
        /// The surface kind.
        surface: &'static str,
        /// Why.
        reason: &'static str,
    },
    /// An option has a bad value.
    #[error("option {name} = {value}: {reason}")]
    BadOption {
        /// The option.
        name: &'static str,
        /// Its value, printed.
        value: String,
        /// What is required.
        reason: &'static str,
    },
}
