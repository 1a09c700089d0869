//! Linking: turns passes into a program (entries, links, retracts) on a material model, and the
//! pass types and level geometry strategies share.
//!
//! - [`linker`]: entries, keep-down links, lifts and retracts, decided against a raster model
//!   of the material kept up to date as the program is built;
//! - [`route`]: ways at depth round the material through cleared space;
//! - [`pass`]: passes, their kinds, the geometry of a level, the parameters.

pub mod linker;
pub mod pass;
pub mod route;

pub(crate) use linker::Linker;
pub use linker::link;
pub use pass::{
    DP_TOL, LANDING_MARGIN, LayerGeom, OffsetOrder, Params, Pass, PassKind, StrategyKind, TOUCH_MARGIN, wall_margin,
};
