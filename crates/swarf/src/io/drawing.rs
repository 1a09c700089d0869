//! Drawings (DXF, SVG) into jobs.
//!
//! Roles come from layer or group names (`STOCK`, `PART`, `FIXTURE`). Without a `STOCK` layer:
//! when there is a `PART` layer, the stock is the part's bounding box grown by one tool
//! diameter (clearing around the part); when nothing has a role, the drawing is a pocket: the
//! outermost closed contour is the pocket wall and nested contours alternate island / pocket
//! (the even-odd rule), everything outside being part material.

use super::Overrides;
use crate::error::{Error, Result};
use crate::geom::area::Fill;
use crate::geom::{Area, DVec2};
use crate::model::{Job, Width};
use swarf_import::{Drawing, Role};

/// Chord tolerance for flattening the drawing's arcs into region polygons (mm).
pub const FLATTEN_TOL: f64 = 0.001;

fn area_of(d: &Drawing, pick: impl Fn(Role) -> bool) -> Area {
    let rings: Vec<Vec<DVec2>> = d
        .shapes
        .iter()
        .filter(|s| pick(s.role))
        .map(|s| s.contour.flatten(FLATTEN_TOL).into_iter().map(|p| DVec2::new(p[0], p[1])).collect())
        .collect();
    Area::from_rings(&rings, Fill::EvenOdd)
}

/// Builds a job from a drawing and the user's options (tool 6 mm, stepover 40 %, depth 3 mm
/// unless given).
pub fn job_from_drawing(d: &Drawing, ov: &Overrides) -> Result<Job> {
    let file = &d.path;
    if d.shapes.is_empty() {
        return Err(Error::input(file, "drawing", "no closed contour in the drawing"));
    }
    let has = |r: Role| d.shapes.iter().any(|s| s.role == r);
    let fixtures = area_of(d, |r| r == Role::Fixture);
    let tool_d = ov.tool_diameter.unwrap_or(6.0);
    let (stock, part) = if has(Role::Stock) {
        (area_of(d, |r| r == Role::Stock), area_of(d, |r| r == Role::Part || r == Role::Auto))
    } else if has(Role::Part) {
        let part = area_of(d, |r| r == Role::Part || r == Role::Auto);
        let (lo, hi) = part.bounds().ok_or_else(|| Error::input(file, "PART layer", "the part has no area"))?;
        let m = tool_d.max(1.0);
        (Area::rect(lo.x - m, lo.y - m, hi.x + m, hi.y + m), part)
    } else {
        let pocket = area_of(d, |r| r == Role::Auto);
        let (lo, hi) = pocket.bounds().ok_or_else(|| Error::input(file, "drawing", "the contours enclose no area"))?;
        let m = 2.0 * tool_d.max(1.0) + 5.0;
        let frame = Area::rect(lo.x - m, lo.y - m, hi.x + m, hi.y + m).difference(&pocket);
        (pocket, frame)
    };
    if stock.is_empty() {
        return Err(Error::input(file, "STOCK layer", "the stock contours enclose no area"));
    }
    let depth = ov.depth.unwrap_or(3.0);
    if !(depth.is_finite() && depth > 0.0) {
        return Err(Error::param("--depth", format!("{depth} mm: the depth must be positive")));
    }
    let name = file.file_stem().and_then(|s| s.to_str()).unwrap_or("drawing").to_string();
    Ok(Job { fixtures, width: ov.width.unwrap_or(Width::Stepover(0.4)), ..Job::new(name, stock, part, tool_d, depth) })
}
