//! Inputs: the benchmark case format (JSON) and drawings (DXF, SVG through `swarf-import`),
//! turned into a [`crate::model::Job`].

pub mod case;
pub mod drawing;
pub mod stl;

use crate::error::{Error, Result};
use crate::model::Job;
use std::path::Path;

/// What the user may set on top of (or instead of) what the input file says.
#[derive(Debug, Clone, Default)]
pub struct Overrides {
    /// Tool diameter, mm.
    pub tool_diameter: Option<f64>,
    /// Width of cut.
    pub width: Option<crate::model::Width>,
    /// Step-down, mm.
    pub stepdown: Option<f64>,
    /// Cutting depth below the stock top for drawings (mm); the floor of a case otherwise.
    pub depth: Option<f64>,
    /// Feed, mm/min.
    pub feed: Option<f64>,
    /// Spindle speed, rpm.
    pub spindle_rpm: Option<f64>,
    /// Stock to leave on walls, mm.
    pub allowance: Option<f64>,
    /// Drawing import options.
    pub import: swarf_import::ImportOptions,
}

/// Reads a case (`.json`), DXF or SVG file into a job, applies the overrides and validates it.
pub fn load_job(path: &Path, ov: &Overrides) -> Result<Job> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let mut job = match ext.as_str() {
        "json" => case::read_case(path)?,
        "dxf" | "svg" => drawing::job_from_drawing(&swarf_import::read_drawing(path, &ov.import)?, ov)?,
        _ => {
            let bytes = std::fs::read(path).map_err(|e| Error::input(path, "file", format!("cannot read: {e}")))?;
            let head = String::from_utf8_lossy(&bytes[..bytes.len().min(512)]).trim_start().to_string();
            if head.starts_with('{') {
                case::read_case(path)?
            } else {
                drawing::job_from_drawing(&swarf_import::read_drawing(path, &ov.import)?, ov)?
            }
        }
    };
    apply(&mut job, ov);
    job.validate()?;
    Ok(job)
}

/// Applies overrides to a job.
pub fn apply(job: &mut Job, ov: &Overrides) {
    if let Some(d) = ov.tool_diameter {
        job.tool.diameter = d;
    }
    if let Some(w) = ov.width {
        job.width = w;
    }
    if let Some(s) = ov.stepdown {
        job.stepdown = Some(s);
    }
    if let Some(f) = ov.feed {
        job.feed = f;
    }
    if let Some(s) = ov.spindle_rpm {
        job.spindle_rpm = s;
    }
    if let Some(a) = ov.allowance {
        job.allowance = a;
    }
}
