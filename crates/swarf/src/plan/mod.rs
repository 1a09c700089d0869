//! Linking: turns passes into a program (entries, links, retracts) on a material model, the
//! level driver every strategy uses, and the pass types and level geometry strategies share.
//!
//! - `linker`: entries, keep-down links, lifts and retracts, decided against a raster model of
//!   the material kept up to date as the program is built;
//! - `material`: the material model as the planner sees it (the queries and updates the
//!   linker and the adaptive engine make of it), implemented by the raster model;
//! - `levels`: the level driver (one linker for the whole program, the levels top down, the
//!   finishing contours);
//! - `route`: ways at depth round the material through cleared space;
//! - `feed`: the feed of paper 1 §5 (chip thinning), for the adaptive strategy's passes and
//!   its clean-up;
//! - `pass`: passes, their kinds, the geometry of a level;
//! - [`LinkOptions`]: what every strategy shares.

pub(crate) mod feed;
pub(crate) mod levels;
pub(crate) mod linker;
pub(crate) mod material;
mod options;
#[doc(hidden)]
pub mod pass;
#[doc(hidden)]
pub mod route;

pub(crate) use linker::Linker;
pub(crate) use material::Material;
pub use options::LinkOptions;
#[doc(hidden)]
pub use pass::{DP_TOL, LANDING_MARGIN, LayerGeom, Pass, PassKind, TOUCH_MARGIN};
