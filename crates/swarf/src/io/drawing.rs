//! Drawings (DXF, SVG) into jobs.
//!
//! Roles come from layer or group names (`STOCK`, `PART`, `FIXTURE`). Without a `STOCK` layer:
//! when there is a `PART` layer, the stock is the part's bounding box grown by one tool
//! diameter (clearing around the part); when nothing has a role, the drawing is a pocket: the
//! outermost closed contour is the pocket wall and nested contours alternate island / pocket
//! (the even-odd rule), everything outside being part material.

use super::Overrides;
use crate::error::{Error, Result, Setting};
use crate::geom::area::Fill;
use crate::geom::{Area, DVec2};
use crate::model::{Job, Tool};
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

/// Builds a job from a drawing and the user's options: [`Overrides::DEFAULT_DEPTH`] deep with the
/// default cutting data ([`crate::model::Cutting::DEFAULT`]) unless they say otherwise (the
/// overrides of the cutting data are applied by [`super::load_input`]; the tool diameter is read
/// here too, for the margin of the stock round a part).
pub fn job_from_drawing(d: &Drawing, ov: &Overrides) -> Result<Job> {
    let file = &d.path;
    if d.shapes.is_empty() {
        return Err(Error::input(file, "drawing", "no closed contour in the drawing"));
    }
    let has = |r: Role| d.shapes.iter().any(|s| s.role == r);
    let fixtures = area_of(d, |r| r == Role::Fixture);
    let tool_d = ov.tool_diameter.unwrap_or(Tool::DEFAULT.diameter);
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
    let depth = ov.depth.unwrap_or(Overrides::DEFAULT_DEPTH);
    if !(depth.is_finite() && depth > 0.0) {
        return Err(Error::setting(Setting::Depth, format!("{depth} mm: the depth must be positive")));
    }
    let name = file.file_stem().and_then(|s| s.to_str()).unwrap_or("drawing").to_string();
    Ok(Job { fixtures, ..Job::new(name, stock, part, tool_d, depth) })
}
