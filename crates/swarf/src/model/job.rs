//! The job model: part, stock, fixtures and free space (paper 1 §4), the tool and the cutting
//! parameters, and the derived regions every strategy works with.
//!
//! Paper 1 describes a 2D milling step by two binary maps, part and stock, whose four
//! combinations are: part (must stay), fixture (part without stock: forbidden), material to
//! remove (stock without part) and free space (neither: the tool may travel and enter there).
//! swarf keeps the same four states as exact polygon areas ([`Job`]) and as a raster
//! ([`crate::sim::raster`]).

use super::cutting::Cutting;
use crate::error::{Error, Result, Setting};
use crate::geom::{Area, DVec2};
use crate::limits;

/// One 2.5D job: what to cut, with what, how.
#[derive(Debug, Clone)]
pub struct Job {
    /// A short name (the input's file stem).
    pub name: String,
    /// Raw material outline.
    pub stock: Area,
    /// Top of the stock, mm.
    pub stock_top: f64,
    /// Material that must stay.
    pub part: Area,
    /// Top of the part walls, mm.
    pub part_top: f64,
    /// Forbidden areas (clamps, vice jaws), treated like the part over the full depth.
    pub fixtures: Area,
    /// Depth to clear to, mm.
    pub floor: f64,
    /// Stock to leave on the part walls (mm); the final part is the part grown by this.
    pub allowance: f64,
    /// Stock to leave on the floor (mm).
    pub allowance_floor: f64,
    /// Largest depth of one level, mm; `None` = the full depth in one level.
    pub stepdown: Option<f64>,
    /// The tool, the width of cut and the rates.
    pub cutting: Cutting,
}

/// Regions derived from a [`Job`] for one tool, shared by every strategy.
#[derive(Debug, Clone)]
pub struct Regions {
    /// Part and fixtures grown by the allowance: the tool must not enter.
    pub keep: Area,
    /// Material to remove: stock minus keep.
    pub material: Area,
    /// Where the tool centre may be: the working window minus keep grown by the radius.
    pub centres: Area,
    /// The part of `material` the tool can reach (opening by the tool disk).
    pub reachable: Area,
    /// A box around everything, used as the "whole plane".
    pub window: Area,
    /// `keep` grown by `walls_at` (the radius plus the wall margin): `centres` is the window
    /// less this.
    pub walls: Area,
    /// The offset of `walls`, mm.
    pub walls_at: f64,
}

/// Chord tolerance used when polygons stand for circles in region computations (mm).
pub const REGION_TOL: f64 = 0.001;

impl Job {
    /// A job `depth` mm deep from z = 0, with swarf's defaults for what a drawing does not say:
    /// stock and part tops at 0, no fixtures, no allowance, one level, and the default cutting
    /// data ([`Cutting::DEFAULT`]) with a flat end mill of `tool_diameter`. Set any other field
    /// with struct update syntax:
    ///
    /// ```
    /// use swarf::geom::Area;
    /// use swarf::model::{Cutting, Job, Width};
    /// let job = Job {
    ///     stepdown: Some(2.5),
    ///     ..Job::new("pocket", Area::rect(0.0, 0.0, 40.0, 30.0), Area::empty(), 6.0, 5.0)
    /// };
    /// assert_eq!(job.floor, -5.0);
    /// assert_eq!(job.levels(), vec![-2.5, -5.0]);
    /// assert_eq!(job.cutting.width, Width::DEFAULT);
    /// ```
    pub fn new(name: impl Into<String>, stock: Area, part: Area, tool_diameter: f64, depth: f64) -> Job {
        Job {
            name: name.into(),
            stock,
            stock_top: 0.0,
            part,
            part_top: 0.0,
            fixtures: Area::empty(),
            floor: -depth,
            allowance: 0.0,
            allowance_floor: 0.0,
            stepdown: None,
            cutting: Cutting::with_tool_diameter(tool_diameter),
        }
    }

    /// Checks every value a user can get wrong: the cutting data, a positive step-down, finite
    /// heights with the floor below the stock top, allowances of zero or more, a stock outline.
    pub fn validate(&self) -> Result<()> {
        self.cutting.validate()?;
        if let Some(s) = self.stepdown
            && !(s.is_finite() && s > 0.0)
        {
            return Err(Error::setting(Setting::Stepdown, format!("{s} mm: the step-down must be a positive number")));
        }
        for (setting, v) in
            [(Setting::StockTop, self.stock_top), (Setting::PartTop, self.part_top), (Setting::Floor, self.floor)]
        {
            if !v.is_finite() {
                return Err(Error::setting(setting, format!("{v}: must be a finite number")));
            }
            if !limits::coord_ok(v) {
                return Err(Error::setting(setting, format!("{v} mm: outside ±{} mm", limits::MAX_COORD_MM)));
            }
        }
        for (what, a) in [("stock", &self.stock), ("part", &self.part), ("fixtures", &self.fixtures)] {
            if let Some((lo, hi)) = a.bounds()
                && let Some(why) = limits::reach_refusal(&lo.to_array(), &hi.to_array())
            {
                return Err(Error::job(what, format!("{why} (is the unit right?)")));
            }
        }
        if self.floor >= self.stock_top {
            return Err(Error::setting(
                Setting::Floor,
                format!("floor {} is not below the stock top {}: nothing to cut", self.floor, self.stock_top),
            ));
        }
        for (setting, v) in [(Setting::Allowance, self.allowance), (Setting::AllowanceFloor, self.allowance_floor)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::setting(setting, format!("{v} mm: must be zero or positive")));
            }
        }
        if self.stock.is_empty() || self.stock.area() <= 0.0 {
            return Err(Error::job("stock", "the stock outline is empty"));
        }
        let depth = self.stock_top - (self.floor + self.allowance_floor);
        let levels = self.stepdown.map_or(1.0, |s| limits::level_count(depth, s));
        if let Some(why) = limits::work_refusal(levels, self.stock.area(), self.stepover_mm()) {
            let setting = if levels > limits::MAX_LEVELS as f64 { Setting::Stepdown } else { Setting::ToolDiameter };
            return Err(Error::setting(setting, why));
        }
        Ok(())
    }

    /// Tool radius, mm.
    pub fn radius(&self) -> f64 {
        self.cutting.tool.radius()
    }

    /// Radial stepover in mm.
    pub fn stepover_mm(&self) -> f64 {
        self.cutting.stepover_mm()
    }

    /// The depth of cut of each level, mm: the stock top to the floor (plus floor allowance) over
    /// the number of levels.
    pub fn level_depth(&self) -> f64 {
        (self.stock_top - (self.floor + self.allowance_floor)) / self.levels().len() as f64
    }

    /// The z of each level, top to bottom, ending at the floor (plus floor allowance).
    pub fn levels(&self) -> Vec<f64> {
        let bottom = self.floor + self.allowance_floor;
        let depth = self.stock_top - bottom;
        let n = match self.stepdown {
            Some(s) if s > 0.0 => ((depth / s) - 1e-9).ceil().max(1.0) as usize,
            _ => 1,
        };
        (1..=n).map(|i| if i == n { bottom } else { self.stock_top - depth * i as f64 / n as f64 }).collect()
    }

    /// The highest thing on the table (stock or part top), mm.
    pub fn top(&self) -> f64 {
        self.stock_top.max(self.part_top)
    }

    /// Computes the derived regions for a tool of radius `r` (normally [`Job::radius`]) whose
    /// axis keeps `margin` more than `r` away from the part and fixtures (the strategies' wall
    /// clearance, see [`crate::strategy::Strategy::wall_margin`]): `centres` is where the axis may go,
    /// `reachable` the material the tool sweeps from there.
    pub fn regions(&self, r: f64, margin: f64) -> Result<Regions> {
        let forbidden = self.part.union(&self.fixtures);
        let keep = if self.allowance > 0.0 { forbidden.offset(self.allowance, REGION_TOL) } else { forbidden };
        let material = self.stock.difference(&keep).without_slivers(1e-9);
        let (lo, hi) = self.stock.bounds().ok_or_else(|| Error::job("stock", "the stock outline is empty"))?;
        let (lo, hi) = match keep.bounds() {
            Some((a, b)) => (lo.min(a), hi.max(b)),
            None => (lo, hi),
        };
        let pad = 4.0 * r + 10.0;
        let window = Area::rect(lo.x - pad, lo.y - pad, hi.x + pad, hi.y + pad);
        let walls_at = r + margin.max(0.0);
        let walls = keep.offset(walls_at, REGION_TOL);
        let centres = window.difference(&walls);
        // centres that matter: the tool touches material. A centre is farther than `r` from the
        // keep, so a point of the stock within `r` of it is material: the stock grown by `r`
        // says the same as the material grown by it, and the stock's outline is a few edges
        // where the material's holds every curve of the drawing (a growth of them all by the
        // radius, shut round thin features, was a tenth of a drawing's planning)
        let touching = centres.intersection(&self.stock.offset(r, REGION_TOL));
        let reachable = touching.offset(r, REGION_TOL).intersection(&material).without_slivers(1e-6);
        if material.is_empty() {
            return Err(Error::job(
                "stock",
                "there is no material to remove: the part and fixtures cover the whole stock",
            ));
        }
        if reachable.area() < 1e-6 {
            // the widest place: the material's point farthest from the walls
            let walls_index = crate::geom::index::EdgeIndex::from_area(&keep, (r / 2.0).max(0.05));
            let step = (r / 8.0).max(0.01);
            let widest = farthest_point(&material, &walls_index, step)
                .map(|(p, d)| {
                    // refined round the best grid point: a 9 × 9 grid, shrunk four times
                    let (mut best, mut d, mut h) = (p, d, step);
                    for _ in 0..4 {
                        let c = best;
                        for j in -4..=4 {
                            for i in -4..=4 {
                                let q = c + DVec2::new(i as f64, j as f64) * (h / 4.0);
                                let dq = walls_index.distance(q, 4.0 * r + 1.0);
                                if dq > d && material.contains(q) {
                                    (best, d) = (q, dq);
                                }
                            }
                        }
                        h /= 4.0;
                    }
                    2.0 * (d - margin.max(0.0))
                })
                .filter(|w| *w > 0.0);
            let fix = match widest {
                Some(w) => format!(
                    "; the widest place is {w:.2} mm across: a tool of Ø{:.2} mm or less fits (--tool-diameter)",
                    (w * 0.98 * 100.0).floor() / 100.0
                ),
                None => String::new(),
            };
            return Err(Error::job(
                "tool diameter",
                format!(
                    "the tool (Ø{:.3} mm) does not fit anywhere in the material to remove: the pocket is narrower than the tool{fix}",
                    2.0 * r
                ),
            ));
        }
        Ok(Regions { keep, material, centres, reachable, window, walls, walls_at })
    }
}

/// The point of `area` farthest from `edges` among a grid of candidates with spacing `step`
/// (a distance-transform maximum, as paper 1 §4.5 uses to place a helical entry), and that
/// distance.
pub fn farthest_point(area: &Area, edges: &crate::geom::index::EdgeIndex, step: f64) -> Option<(DVec2, f64)> {
    let (lo, hi) = area.bounds()?;
    // keep the candidate grid to about 40 000 points
    let step = step.max(((hi.x - lo.x) * (hi.y - lo.y) / 40_000.0).sqrt()).max(1e-3);
    let max = (hi - lo).length() + 1.0;
    let mut best: Option<(DVec2, f64)> = None;
    let nx = ((hi.x - lo.x) / step).ceil() as usize + 1;
    let ny = ((hi.y - lo.y) / step).ceil() as usize + 1;
    for j in 0..ny {
        for i in 0..nx {
            let p = DVec2::new(lo.x + (i as f64 + 0.5) * step, lo.y + (j as f64 + 0.5) * step);
            if !area.contains(p) {
                continue;
            }
            let d = edges.distance(p, max);
            if best.is_none_or(|(_, b)| d > b) {
                best = Some((p, d));
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tool_too_wide_for_every_pocket_names_the_widest_that_fits() {
        // a 4 mm wide slot in a block: a 6 mm tool fits nowhere
        let stock = Area::rect(0.0, 0.0, 50.0, 4.0);
        let part = Area::rect(-20.0, -20.0, 70.0, 24.0).difference(&stock);
        let job = Job::new("slot", stock, part, 6.0, 2.0);
        let e = job.regions(job.radius(), 0.0).unwrap_err().to_string();
        assert!(e.contains("does not fit") && e.contains("the widest place is 4.0"), "{e}");
        assert!(e.contains("--tool-diameter"), "{e}");
        assert!(job.regions(1.9, 0.0).is_ok());
    }

    /// The reachable material is the material within a radius of the centres, whatever the
    /// centres are first narrowed to (those within a radius of the stock): on a plate whose
    /// part is a wavy boss, an island and a wall that runs out of the stock and past its
    /// corner, the two leave no area between them; and on a plate crossed by a bar of part
    /// just under its edge, the strip beyond the bar is reached from centres more than half a
    /// radius outside the stock (narrowing them to half a radius left it unreached).
    #[test]
    fn the_reachable_material_is_what_the_centres_reach() {
        let stock = Area::rect(0.0, 0.0, 80.0, 50.0);
        let boss: Vec<DVec2> = (0..720)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / 720.0;
                DVec2::new(25.0, 25.0) + (9.0 + 1.5 * (6.0 * a).sin()) * DVec2::new(a.cos(), a.sin())
            })
            .collect();
        let part = Area::from_rings(&[boss], crate::geom::area::Fill::NonZero)
            .union(&Area::rect(55.0, 20.0, 62.0, 30.0))
            .union(&Area::rect(70.0, 35.0, 95.0, 60.0));
        let job = Job::new("plate", stock, part, 8.0, 3.0);
        let (r, margin) = (job.radius(), 0.005);
        let g = job.regions(r, margin).unwrap();
        let direct = g.centres.offset(r, REGION_TOL).intersection(&g.material);
        let between = direct.difference(&g.reachable).area() + g.reachable.difference(&direct).area();
        assert!(between < 0.01, "{between} mm² between them");
        assert!(g.reachable.area() > 0.9 * g.material.area(), "{} of {}", g.reachable.area(), g.material.area());
        // A bar of part right across the plate 1.5 mm under its top edge: the strip of material
        // above it is reached only from centres 2.5 mm outside the stock (the radius above the
        // bar), farther out than half a radius.
        let bar = Area::rect(-10.0, 45.0, 90.0, 48.5);
        let job = Job::new("bar", Area::rect(0.0, 0.0, 80.0, 50.0), bar, 8.0, 3.0);
        let g = job.regions(job.radius(), margin).unwrap();
        let strip = g.reachable.intersection(&Area::rect(0.0, 48.5, 80.0, 50.0)).area();
        assert!((strip - 120.0).abs() < 0.5, "{strip} mm² of the strip reached");
        let direct = g.centres.offset(r, REGION_TOL).intersection(&g.material);
        let between = direct.difference(&g.reachable).area() + g.reachable.difference(&direct).area();
        assert!(between < 0.01, "{between} mm² between them");
    }
}
