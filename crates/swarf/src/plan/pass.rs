//! What strategies hand the linker: passes (tool-centre polylines in cutting order), and the
//! geometry of a level they are made from.

use super::LinkOptions;
use crate::error::Result;
use crate::geom::{Area, DVec2};
use crate::model::{Job, REGION_TOL, Regions};

/// Douglas–Peucker tolerance for adaptive passes, mm.
pub const DP_TOL: f64 = 0.002;

/// Passes start and end this far (mm) outside the material, so that the tool lands beside it
/// and enters sideways.
pub const TOUCH_MARGIN: f64 = 0.03;

/// A tool may descend vertically where no material stands within this distance of its axis
/// beyond its radius (mm); below [`TOUCH_MARGIN`], so pass ends in the air qualify.
pub const LANDING_MARGIN: f64 = 0.02;

/// Offset tolerance of the zones that clip clean-up passes, mm (an offset within it only
/// grows the zone).
pub const ZONE_TOL: f64 = 0.01;

/// What a pass is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PassKind {
    /// Clearing.
    Clear,
    /// Contour along the walls at the roughing offset.
    Contour,
    /// Clean-up of material left by the others.
    Cleanup,
    /// Finishing contour at the final offset.
    Finish,
}

/// One tool-centre polyline at a level, in cutting order.
#[derive(Debug, Clone, PartialEq)]
pub struct Pass {
    /// Points (for a closed pass the first point is not repeated).
    pub pts: Vec<DVec2>,
    /// A loop: the linker may start it anywhere and returns to the start.
    pub closed: bool,
    /// Purpose.
    pub kind: PassKind,
    /// Offset level (distance from the walls) it was made at, when it has one; used to order.
    pub level: f64,
    /// The pass may be cut in either direction (zigzag rows alternate anyway): the linker may
    /// reverse it to start from an end where the tool can land.
    pub reversible: bool,
}

/// Geometry of a level shared by the strategies.
#[derive(Debug, Clone)]
pub struct LayerGeom {
    /// Tool radius.
    pub r: f64,
    /// Stepover, mm.
    pub step: f64,
    /// Walls the roughing keeps away from: keep grown by the stock to leave.
    pub keep: Area,
    /// Offset of the first pass from `keep` (tool radius plus a margin for arc fitting).
    pub wall_level: f64,
    /// `keep` grown by `wall_level`: its rings are the wall contours.
    pub walls: Area,
    /// Where a tool centre touches material (material grown by `R − ε`).
    pub touch: Area,
    /// Where a tool centre may go for roughing: `touch` minus `keep` grown by `wall_level`.
    pub centres: Area,
    /// Material the roughing tool can reach.
    pub reachable: Area,
    /// The job's regions.
    pub regions: Regions,
    /// `centres` grown by a distance, once asked for (see [`LayerGeom::centres_grown`]).
    grown: std::sync::OnceLock<(f64, Area)>,
}

impl LayerGeom {
    /// Derives the roughing geometry of a job whose walls the tool axis keeps `wall_margin`
    /// beyond its radius from (see [`crate::strategy::Strategy::wall_margin`]).
    pub fn new(job: &Job, regions: &Regions, link: &LinkOptions, wall_margin: f64) -> Result<LayerGeom> {
        let r = job.radius();
        let leave = if link.finish || link.stock_to_leave > 0.0 { link.stock_to_leave.max(0.0) } else { 0.0 };
        let keep = if leave > 0.0 { regions.keep.offset(leave, REGION_TOL) } else { regions.keep.clone() };
        let wall_level = r + wall_margin;
        let touch = regions.material.offset(r + TOUCH_MARGIN, REGION_TOL);
        // the regions' walls are the layer's when nothing is left for finishing
        let regions_walls = leave == 0.0 && regions.walls_at == wall_level;
        let walls = if regions_walls { regions.walls.clone() } else { keep.offset(wall_level, REGION_TOL) };
        let centres =
            if keep.is_empty() { touch.clone() } else { touch.intersection(&regions.window.difference(&walls)) };
        // the material the centres reach: the regions' own where the walls are theirs (the
        // centres here reach TOUCH_MARGIN further from the material than the regions', and a
        // disk of radius r round a centre farther than r from the material reaches none of it:
        // the same set, and an offset by the radius saved)
        let reachable = if regions_walls {
            regions.reachable.clone()
        } else {
            centres.offset(r, REGION_TOL).intersection(&regions.material).without_slivers(1e-6)
        };
        Ok(LayerGeom {
            r,
            step: job.stepover_mm(),
            keep,
            wall_level,
            walls,
            touch,
            centres,
            reachable,
            regions: regions.clone(),
            grown: std::sync::OnceLock::new(),
        })
    }

    /// `centres` grown by `d`: computed by the first call, and kept for later calls with the
    /// same `d` (a z-level job computes it for the next level while the planner cuts this
    /// one; an offset of a whole level's centres is one of the dearest steps of its clean-up).
    pub fn centres_grown(&self, d: f64) -> std::borrow::Cow<'_, Area> {
        let tol = ZONE_TOL;
        match self.grown.get() {
            Some((e, a)) if *e == d => std::borrow::Cow::Borrowed(a),
            Some(_) => std::borrow::Cow::Owned(self.centres.offset(d, tol)),
            None => std::borrow::Cow::Borrowed(&self.grown.get_or_init(|| (d, self.centres.offset(d, tol))).1),
        }
    }
}

/// True when a ring is counter-clockwise.
pub(crate) fn ccw(ring: &[DVec2]) -> bool {
    crate::geom::ring_area(ring) > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Area;

    /// The regions' reachable material stands for the layer geometry's when the walls are the
    /// same and nothing is left for finishing: the material the layer's centres reach (offset
    /// by the radius, as it was computed before) is the same set (here, to the last vertex: no
    /// area between them), on a pocket with an island and a notch (a convex and a concave
    /// wall) and on open stock round a boss (no walls round the outside).
    #[test]
    fn the_layer_reaches_the_material_the_regions_reach() {
        let pocket = Area::rect(0.0, 0.0, 40.0, 30.0).difference(&Area::rect(18.0, 0.0, 22.0, 6.0));
        let part = Area::rect(-5.0, -5.0, 45.0, 35.0).difference(&pocket).union(&Area::disk(
            DVec2::new(28.0, 18.0),
            4.0,
            0.001,
        ));
        let boss = Area::disk(DVec2::new(20.0, 15.0), 6.0, 0.001);
        for (name, stock, part) in [("pocket", pocket.clone(), part), ("boss", Area::rect(0.0, 0.0, 40.0, 30.0), boss)]
        {
            let job = Job::new(name, stock, part, 6.0, 3.0);
            let link = LinkOptions::DEFAULT;
            let regions = job.regions(job.radius(), 0.01).expect("regions");
            let geom = LayerGeom::new(&job, &regions, &link, 0.01).expect("geometry");
            let offset = geom.centres.offset(geom.r, REGION_TOL).intersection(&regions.material).without_slivers(1e-6);
            assert!(geom.reachable.area() > 100.0, "{name}: {}", geom.reachable.area());
            let apart = geom.reachable.difference(&offset).area() + offset.difference(&geom.reachable).area();
            assert!(apart.abs() < 1e-6 * offset.area(), "{name}: {apart} mm² apart of {}", offset.area());
        }
    }
}
