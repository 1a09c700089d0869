//! The jobs a user runs, each from a job model to programs, G-code and figures:
//!
//! - [`five`]: a 5-axis pocket over a NURBS floor (paper 2 §2), as a CL file and G-code;
//! - [`settings`]: a run's options by name (the command line's flags, the Python keywords);
//! - [`rough`]: a 2.5D job (a case or a drawing) roughed with one strategy, posted and proven
//!   on the simulator;
//! - [`zlevel`]: a 3D job (a mesh part in a stock box) roughed in z-levels (paper 3);
//! - [`toolseq`]: the cost-optimal sequence of tools from a tool database for a 3D job
//!   (paper 3), one program per tool.

pub mod five;
pub mod rough;
pub mod settings;
pub mod toolseq;
pub mod zlevel;
pub(crate) mod zorder;
