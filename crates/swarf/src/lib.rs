//! # swarf — CNC roughing toolpaths a machinist can trust
//!
//! swarf turns part and stock geometry into roughing toolpaths and G-code, and proves each one
//! on a material simulation: no gouge, bounded tool engagement, little air cutting, full
//! clearing.
//!
//! The data flows one way:
//!
//! ```text
//! inputs ──► model ──► strategy ──► plan (links, entries) ──► post ──► G-code
//! (io)       (model)   (strategy)    (plan)         │          (post)
//!                                                   └──► sim ──► report, plot
//! ```
//!
//! - [`io`]: the case format (JSON) and drawings (DXF, SVG, through `swarf-import`) into a
//!   [`model::Job`];
//! - [`geom`]: areas with holes, robust booleans and offsets, Douglas–Peucker, arc fitting;
//! - [`implicit`]: R-function shapes and oscillator spirals over their level sets (paper 4);
//! - [`strategy`]: zigzag and contour-parallel offset clearing (plus clean-up);
//! - [`plan`]: entries (helix, ramp, plunge as the last resort), keep-down links, retracts;
//! - [`toolpath`]: the move list everything downstream reads;
//! - [`sim`]: the raster material model with pixel and exact engagement, gouges, rest;
//! - [`post`]: LinuxCNC and GRBL dialects;
//! - [`report`], [`plot`]: the figures and the picture.
//!
//! ```no_run
//! use swarf::pipeline::{rough, RoughOptions};
//! let job = swarf::io::load_job("pocket.json".as_ref(), &Default::default()).unwrap();
//! let out = rough(&job, &RoughOptions::default(), &mut |_, _| {}).unwrap();
//! std::fs::write("pocket.ngc", &out.gcode).unwrap();
//! println!("max engagement {:.1}°, {} gouges", out.report.engagement_deg.max, out.report.gouges);
//! ```

pub mod error;
pub mod geom;
pub mod implicit;
pub mod io;
pub mod job;
pub mod model;
pub mod plan;
pub mod plot;
pub mod post;
pub mod report;
pub mod sim;
pub mod strategy;
pub mod toolpath;

pub use error::{Error, Result};
pub use swarf_import;
