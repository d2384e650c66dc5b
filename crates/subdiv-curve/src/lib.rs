//! Curve subdivision by masks, its exact reversal, and its smoothness analysis.
//!
//! A uniform binary curve scheme is two rules (masks): an *even* and an *odd* one
//! ([`Rule`], [`CurveScheme`]). The crate ships
//!
//! | scheme | constructor | limit | reference |
//! |---|---|---|---|
//! | Chaikin corner cutting | [`CurveScheme::chaikin`] | quadratic B-spline, C1 | Chaikin 1974; spec §2.1 |
//! | cubic B-spline | [`CurveScheme::cubic_bspline`] | C2 | Lane & Riesenfeld 1980; spec §2.2 |
//! | four-point, tension `w` | [`CurveScheme::four_point`] | interpolating, C1 at `w = 1/16` | Dyn, Levin & Gregory 1987; spec §2.3 |
//! | unified two-parameter scheme | [`CurveScheme::combined`] | C2 on `omega = gamma/2 - 1/16` | seed 004 formula (4); spec §16.2 |
//! | interpolatory-approximating framework | [`Framework`] | C2, through every flagged point | seed 004 (Yao, Zhang & Tan); spec §16 |
//!
//! and any other scheme a researcher writes down as two rules. Refinement works on open
//! and closed polygons of any [`CurvePoint`]: `[f64; D]`, [`glam::DVec2`],
//! [`glam::DVec3`], `f64`. Open polygons read phantom points past their ends
//! ([`EndRule`]: reflect or repeat, spec §16.4); Chaikin keeps the end points.
//!
//! Modules:
//! - [`reverse`]: reverse Chaikin (Samavati & Bartels): coarse points plus details,
//!   exact reconstruction, pyramids (spec §3).
//! - [`framework`]: the interpolatory-approximating framework with per-point flags, its
//!   virtual-point rules and their derivation (spec §16.3).
//! - [`select`]: choosing the points to interpolate from discrete curvature: inflections,
//!   curvature maxima, cusps (spec §16.6).
//! - [`analysis`]: symbols, polynomial generation and reproduction degrees, the
//!   difference-scheme C^k test, local subdivision matrices and their eigen conditions,
//!   the IFS matrices `L`, `R` (spec §1.1, §1.3, §15).
//! - [`io`] and [`svg`]: point files and SVG drawings.
//!
//! Speed: [`Refiner`] fuses the levels: each cache-sized block of the output is refined
//! depth-first from the few input points it depends on and written once, with inner loops
//! specialised on the rule lengths; the result equals level-by-level refinement bit for
//! bit. Ten levels of a 1,000-point polygon take 1.4-2x the time of a plain copy of the
//! output (see `benches/refine.rs`).
//!
//! # Example
//!
//! ```
//! use subdiv_curve::{CurveScheme, Framework, Topology, analysis};
//!
//! // A regular hexagon; interpolate vertices 0 and 3, approximate the others.
//! let hexagon: Vec<[f64; 2]> = (0..6)
//!     .map(|k| { let t = k as f64 * std::f64::consts::PI / 3.0; [t.cos(), t.sin()] })
//!     .collect();
//! let flags = [true, false, false, true, false, false];
//! let curve = Framework::published().refine(&hexagon, &flags, Topology::Closed, 6)?;
//! assert_eq!(curve[0], hexagon[0]);          // flagged: passed through exactly
//! assert_eq!(curve[3 << 6], hexagon[3]);
//! let near_vertex_1 = curve[1 << 6];         // not flagged: approximated (cut inside)
//! assert!(near_vertex_1[0].hypot(near_vertex_1[1]) < 0.99);
//!
//! // Smoothness, measured: the four-point scheme is C1 but not C2.
//! let dlg = analysis::analyze(&CurveScheme::four_point(1.0 / 16.0)?);
//! assert_eq!((dlg.c1, dlg.c2), (true, false));
//! # Ok::<(), subdiv_curve::CurveError>(())
//! ```
//!
//! # Errors
//!
//! Every function taking user data returns [`CurveError`]: too few points for the scheme,
//! NaN or infinite coordinates (with the point index), parameters outside the convergent
//! range (with the range), malformed point files (with the line number).

pub mod analysis;
mod error;
pub mod framework;
pub mod io;
mod point;
mod refine;
pub mod reverse;
mod scheme;
pub mod select;
pub mod svg;

pub use error::CurveError;
pub use framework::{Framework, FrameworkAnalysis, VirtualPoints, flags_from_indices};
pub use nalgebra;
pub use point::{CurvePoint, check_finite};
pub use refine::Refiner;
pub use scheme::{
    CurveScheme, EndRule, FOUR_POINT_TENSION_RANGE, Layout, MAX_REFINED_POINTS, MAX_RULE_LEN, Rule, Topology,
};
