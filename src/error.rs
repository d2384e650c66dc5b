//! The facade's one error type: each member crate's error, plus the few mistakes only the
//! facade can make (an unknown scheme name, a scheme without a reverse).

use crate::SurfaceScheme;

/// Everything that can go wrong through the facade. The member crates' errors are kept
/// whole (`source()` and `Display` are theirs), so nothing about where the input is wrong
/// (face, vertex, line number) is lost.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Building or reading a mesh.
    #[error(transparent)]
    Mesh(#[from] mesh_topo::MeshError),
    /// Loop subdivision, reverse Loop, M-band Loop.
    #[error(transparent)]
    Loop(#[from] subdiv_loop::LoopError),
    /// Doo-Sabin subdivision and its reverse.
    #[error(transparent)]
    Doo(#[from] subdiv_doo::DooError),
    /// Curve schemes.
    #[error(transparent)]
    Curve(#[from] subdiv_curve::CurveError),
    /// Triangular splines and fitting.
    #[error(transparent)]
    Spline(#[from] tri_spline::SplineError),
    /// Iterated function systems and fractals.
    #[error(transparent)]
    Ifs(#[from] ifs_nonlinear::IfsError),
    /// A scheme name that is not one of [`SurfaceScheme::ALL`].
    #[error("unknown scheme {name:?} (known: {known})")]
    UnknownScheme {
        /// The name given.
        name: String,
        /// The known names, comma-separated.
        known: String,
    },
    /// [`decompose`](crate::decompose) was asked for a scheme that has no reverse.
    #[error("{scheme} has no reverse subdivision (reversible: loop, loop-warren, doo-sabin, doo-simple, doo-centroid)")]
    NotReversible {
        /// The scheme.
        scheme: SurfaceScheme,
    },
    /// A boundary option ([`Boundaries`](crate::Boundaries)) that the scheme does not have.
    #[error("{scheme} does not take {option}")]
    NotApplicable {
        /// The scheme.
        scheme: SurfaceScheme,
        /// The option and the schemes it belongs to.
        option: &'static str,
    },
    /// A subdivision whose output alone would need more memory than the system has
    /// available, refused before any work (see [`crate::memory`]).
    #[error(transparent)]
    OutputTooLarge(#[from] crate::memory::OutputTooLarge),
    /// The bytes start with neither the Loop nor the Doo-Sabin pyramid magic number.
    #[error("not a multiresolution pyramid (.mres) file: unknown magic number")]
    NotAPyramid,
}
