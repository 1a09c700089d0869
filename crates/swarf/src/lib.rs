//! # swarf — CNC roughing toolpaths a machinist can trust
//!
//! swarf turns part and stock geometry into roughing toolpaths and G-code, and proves each one
//! on a material simulation: no gouge, bounded tool engagement, little air cutting, full
//! clearing.
//!
//! ## The entry points
//!
//! - [`load_input`] reads a case (JSON), a drawing (DXF, SVG) or an STL part into an [`Input`]:
//!   a 2.5D [`Job`] or a 3D [`MeshJob`], with the user's [`Overrides`];
//! - [`rough`] roughs a 2.5D job with a [`Strategy`] ([`RoughOptions`]): the program, its
//!   G-code, its [`Report`] and the simulation that proves it;
//! - [`rough_mesh`] roughs a 3D job in z-levels (paper 3), each level a 2.5D job;
//! - [`plan_tools`] finds the cheapest sequence of tools from a tool database for a 3D job
//!   (paper 3), one program per tool.
//!
//! Every options struct has its defaults in one place (`DEFAULT`) and a `validate` that the
//! entry points call: a bad value is an [`Error::Setting`] naming the [`Setting`].
//!
//! ```
//! use swarf::{RoughOptions, Strategy, rough};
//! let job = swarf::example_job();
//! let opts = RoughOptions { strategy: Strategy::from_name("offset").unwrap(), simulate: false, ..RoughOptions::DEFAULT };
//! let out = rough(&job, &opts, &mut |_, _| {})?;
//! assert!(out.gcode.starts_with("(swarf "));
//! assert!(out.report.cut_length_mm > 0.0);
//! # Ok::<(), swarf::Error>(())
//! ```
//!
//! ## The layers
//!
//! Each folder uses only the ones below it:
//!
//! ```text
//!  view      the program viewer: one self-contained HTML page (three.js) the page a user looks at
//!  job       rough (2.5D)   zlevel (3D)   toolseq (tool sequence)        the jobs a user runs
//!  strategy  adaptive  offset  zigzag  medial  spiral (+ its search)    what the tool does at a level
//!  plan      linker (entries, links, retracts)   levels (the driver)   pass types, LinkOptions
//!  io · report · plot                                                   readers, figures, pictures
//!  sim · post                                                           material models, G-code
//!  toolpath                                                             the move list
//!  model · implicit                                                     Job, MeshJob, cutting data;
//!                                                                       R-function shapes, spirals
//!  geom                                                                 areas, meshes, arcs
//! ```
//!
//! - [`geom`]: areas with holes, robust booleans and offsets, Douglas–Peucker, arc fitting,
//!   meshes and their shadows;
//! - [`model`]: the 2.5D job (paper 1 §4), the mesh job, the cutting data, the tool database;
//! - [`implicit`]: R-function shapes and oscillator spirals over their level sets (paper 4);
//! - [`toolpath`]: the move list everything downstream reads;
//! - [`sim`]: the raster and distance-field material models (engagement, gouges, rest);
//! - [`post`]: LinuxCNC and GRBL dialects, and the 5-axis CL file and A/C G-code;
//! - [`io`], [`report`], [`plot`]: readers, the figures and the pictures;
//! - [`plan`]: entries (helix, ramp, plunge as the last resort), keep-down links, retracts, the
//!   level driver;
//! - [`strategy`]: the five clearing strategies, and 5-axis pocketing over a NURBS floor
//!   ([`strategy::five`], paper 2 §2);
//! - [`job`]: rough, z-level, tool-sequence and 5-axis jobs;
//! - [`view`]: the program viewer, one self-contained HTML page: the path in 3D over the
//!   stock, part and fixtures, played back while the stock is cut, the engagement chart linked
//!   to it.
//!
//! Progress and timings are logged through the [`log`] crate (`debug` and `trace` levels); a
//! program that wants them installs a logger.

#![warn(missing_docs)]

mod error;
pub mod geom;
pub mod implicit;
pub mod io;
pub mod job;
pub mod limits;
pub mod model;
pub mod plan;
pub mod plot;
pub mod post;
pub mod report;
pub mod sim;
pub mod strategy;
pub mod toolpath;
pub mod view;

pub use error::{Error, Result, Setting};
pub use io::{Input, Overrides, example_job, load_input, load_job, read_case_bytes};
pub use job::rough::{RoughOptions, RoughResult, Stage, rough};
pub use job::settings::Settings;
pub use job::toolseq::{SeqOptions, SeqPlan, plan as plan_tools};
pub use job::zlevel::rough as rough_mesh;
pub use model::{Cutting, Job, MeshJob, Tool, Width};
pub use plan::LinkOptions;
pub use post::Post;
pub use report::Report;
pub use sim::{SimEngine, SimOptions};
pub use strategy::Strategy;
pub use swarf_import;
pub use toolpath::Toolpath;
