//! Implicit shapes and oscillator spirals (paper 4: Kalmar-Nagy & Erdim, "An oscillator-based
//! path planning for pocket milling", TMCE 2014): the mathematical core.
//!
//! The paper embeds a pocket in a function `f(x, y)` positive inside and zero on the boundary,
//! built with R-functions (§3), reads `f` as the energy of a one-degree-of-freedom oscillator
//! whose position and velocity are the plane's `x` and `y` (§2, eqs. 1–5), and adds negative
//! damping ζ (eqs. 3 and 6) so that the trajectory spirals out from the maximum of `f` across its
//! level sets until it tracks the boundary.
//!
//! - [`rfunc`]: the R-function families `R_α`, `R_0^m`, `R_p` (eqs. 6–8) on values with gradients;
//! - [`shape`]: a small shape language (circle, half-plane, box, polygon, and/or/not) with a JSON
//!   file format, and the natural start point (the maximum of `f`) ([`crate::plot::shape`]
//!   draws the level sets);
//! - [`region`]: the implicit function of any [`crate::geom::Area`] (an approximate distance
//!   field);
//! - [`oscillator`]: the damped oscillator integrated in arc length (Dormand–Prince 5(4)), with ζ
//!   constant or chosen per level so that successive turns stay within a stepover, ending with
//!   one turn along the boundary level.
//!
//! The walk-through of all four is in `docs/implicit.md`; the strategy that cuts pockets with
//! them is [`crate::strategy::spiral`].
//!
#![doc = include_str!("../../../../docs/figures/spiral_shape.svg")]
//!
//! *An R-function shape (`examples/shapes/disk_minus_slot.json`), its level sets and its spiral,
//! drawn by the `spiral_figures` example.*

#[doc(hidden)]
pub mod levels;
pub mod oscillator;
pub mod region;
pub mod rfunc;
pub mod shape;

pub use rfunc::{Dual, RFamily};
pub use shape::{Field, Shape};
