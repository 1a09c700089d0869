//! The job model: part, stock, fixtures and free space (paper 1 §4), the tool and the cutting
//! data, the derived regions every strategy works with, mesh jobs (paper 3) and the tool
//! database of the tool-sequence search; and 5-axis pockets over NURBS surfaces ([`five`]).

mod cutting;
pub mod five;
mod job;
mod mesh_job;
pub mod tooldb;

pub use cutting::{Cutting, Tool, Width};
pub use job::{Job, REGION_TOL, Regions, farthest_point};
pub use mesh_job::MeshJob;
pub(crate) use mesh_job::keep_of;
