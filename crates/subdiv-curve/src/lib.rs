//! Curve subdivision (work in progress).

pub mod analysis;
mod error;
pub mod framework;
mod point;
mod refine;
mod scheme;

pub use error::CurveError;
pub use framework::{Framework, FrameworkAnalysis, VirtualPoints, flags_from_indices};
pub use point::{CurvePoint, check_finite};
pub use refine::Refiner;
pub use scheme::{CurveScheme, EndRule, FOUR_POINT_TENSION_RANGE, Layout, MAX_RULE_LEN, Rule, Topology};
