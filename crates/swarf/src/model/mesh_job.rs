//! A 3-axis roughing job on a mesh part (paper 3): the part placed in a stock box, the cutting
//! data, and the levels it is cut at.

use super::{Cutting, Job, REGION_TOL};
use crate::error::{Error, Result, Setting};
use crate::geom::mesh::Mesh;
use crate::geom::{Area, DVec3};
use crate::limits;

/// A 3-axis roughing job on a mesh part.
#[derive(Debug, Clone)]
pub struct MeshJob {
    /// A short name (the input's file stem).
    pub name: String,
    /// The part, placed in machine coordinates.
    pub mesh: Mesh,
    /// Stock box, lower corner.
    pub stock_lo: DVec3,
    /// Stock box, upper corner.
    pub stock_hi: DVec3,
    /// Lowest level, mm (the stock bottom unless set).
    pub floor: f64,
    /// Stock to leave on the part, sideways (mm).
    pub allowance: f64,
    /// Stock to leave on the part, above floors and tops (mm).
    pub allowance_floor: f64,
    /// Largest depth of one level, mm.
    pub stepdown: f64,
    /// The tool, the width of cut and the rates.
    pub cutting: Cutting,
}

/// The shadow is grown by this (mm): it closes the hairline gaps between the shadow and a stock
/// box drawn at the part's bounds (a mesh in single precision, scaled from inches, stops a few
/// hundred-thousandths short of them), which the planner would otherwise crawl round as
/// material. It leaves that much more stock on the part (under the 0.01 mm tolerance of the
/// rest and gouge checks).
const SHADOW_GROW: f64 = 0.003;

/// Douglas–Peucker tolerance of the shadows (mm); the keep is grown by as much.
const SHADOW_SIMPLIFY: f64 = 0.004;

/// Levels closer than this are one level, mm.
const LEVEL_MERGE: f64 = 0.02;

impl MeshJob {
    /// The step-down of a mesh job that names none, as a fraction of the tool diameter: one
    /// diameter. Adaptive clearing holds the width of cut light (a quarter of the diameter by
    /// default) so that the tool can cut deep with its flank; a diameter is within the flutes
    /// of any standard end mill and under the one and a half to two diameters tool makers
    /// give for aluminium. Terraces on slopes are then up to a diameter thick (reported apart
    /// from the rest); `stepdown` or `--stepdown` sets it.
    pub const DEFAULT_STEPDOWN_FRACTION: f64 = 1.0;

    /// A job on `mesh` in the stock box `stock_lo`–`stock_hi`, cut to the bottom of the box with
    /// no allowance and step-downs of [`MeshJob::DEFAULT_STEPDOWN_FRACTION`] of the tool
    /// diameter.
    pub fn new(name: impl Into<String>, mesh: Mesh, stock_lo: DVec3, stock_hi: DVec3, cutting: Cutting) -> MeshJob {
        MeshJob {
            name: name.into(),
            mesh,
            stock_lo,
            stock_hi,
            floor: stock_lo.z,
            allowance: 0.0,
            allowance_floor: 0.0,
            stepdown: Self::DEFAULT_STEPDOWN_FRACTION * cutting.tool.diameter,
            cutting,
        }
    }

    /// Checks the numbers a user gives: the cutting data, a positive step-down, a stock box with
    /// volume, the floor below its top, allowances of zero or more.
    pub fn validate(&self) -> Result<()> {
        self.cutting.validate()?;
        if !(self.stepdown.is_finite() && self.stepdown > 0.0) {
            return Err(Error::setting(
                Setting::Stepdown,
                format!("{} mm: the step-down must be a positive number", self.stepdown),
            ));
        }
        let size = self.stock_hi - self.stock_lo;
        if !(size.x > 0.0 && size.y > 0.0 && size.z > 0.0 && size.is_finite()) {
            return Err(Error::setting(Setting::StockBox, "the box must have positive width, length and height"));
        }
        if let Some(why) = limits::reach_refusal(&self.stock_lo.to_array(), &self.stock_hi.to_array()) {
            return Err(Error::setting(Setting::StockBox, format!("the box: {why}")));
        }
        let (lo, hi) = self.mesh.bounds().ok_or_else(|| Error::job("part", "the mesh is empty"))?;
        if let Some(why) = limits::reach_refusal(&lo.to_array(), &hi.to_array()) {
            return Err(Error::job("part", format!("the mesh: {why} (is the unit or the scale right?)")));
        }
        if !(self.floor.is_finite() && self.floor + self.allowance_floor < self.stock_hi.z) {
            return Err(Error::setting(
                Setting::Floor,
                format!(
                    "{} mm (+ {} mm floor allowance): must be below the stock top {}",
                    self.floor, self.allowance_floor, self.stock_hi.z
                ),
            ));
        }
        for (setting, v) in [(Setting::Allowance, self.allowance), (Setting::AllowanceFloor, self.allowance_floor)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::setting(setting, format!("{v} mm: must be zero or positive")));
            }
        }
        let mut levels = limits::level_count(self.stock_hi.z - (self.floor + self.allowance_floor), self.stepdown);
        if levels <= limits::MAX_LEVELS as f64 {
            // (with the part's flats, each a level of its own)
            levels = self.levels().len() as f64;
            if levels > limits::MAX_LEVELS as f64 {
                let (_, flats) = self.bottom_and_flats();
                return Err(Error::job(
                    "part",
                    format!(
                        "{levels:.0} levels, {} of them at the part's flat faces: at most {} (is it a terraced or noisy mesh?)",
                        flats.len(),
                        limits::MAX_LEVELS
                    ),
                ));
            }
        }
        if let Some(why) = limits::work_refusal(levels, size.x * size.y, self.cutting.stepover_mm()) {
            let setting = if levels > limits::MAX_LEVELS as f64 { Setting::Stepdown } else { Setting::ToolDiameter };
            return Err(Error::setting(setting, why));
        }
        Ok(())
    }

    /// Tool radius.
    pub fn radius(&self) -> f64 {
        self.cutting.tool.radius()
    }

    /// The stock outline.
    pub fn stock_area(&self) -> Area {
        Area::rect(self.stock_lo.x, self.stock_lo.y, self.stock_hi.x, self.stock_hi.y)
    }

    /// The part's outline seen from above (its shadow at the floor).
    pub fn outline(&self) -> Area {
        crate::geom::mesh::Shadows::new(&self.mesh).down_to(self.floor - self.allowance_floor).clone()
    }

    /// The part's shadow from above each of `zs` (descending tool-tip heights, as
    /// [`MeshJob::levels`] gives them): the region each level must not enter, less the
    /// allowance.
    pub fn shadows(&self, zs: &[f64]) -> Vec<Area> {
        let mut sh = crate::geom::mesh::Shadows::new(&self.mesh);
        let mut last = f64::INFINITY;
        zs.iter()
            .map(|&z| {
                // (built downwards: a level out of order gets the lowest shadow so far)
                last = last.min(z - self.allowance_floor);
                sh.down_to(last).clone()
            })
            .collect()
    }

    /// Highest point of the part with its allowance, or the stock top when the part is lower.
    pub fn top(&self) -> f64 {
        self.mesh.bounds().map_or(self.stock_hi.z, |(_, hi)| (hi.z + self.allowance_floor).max(self.stock_hi.z))
    }

    /// The levels, top down: every flat of the part (raised by the floor allowance) between the
    /// stock top and the floor (raised by as much) is a level, and between two of them (or the
    /// stock top, or the floor) the levels are spaced evenly, at most `stepdown` apart. A flat
    /// just under an even step so never makes a level that cuts a sliver over the whole area.
    pub fn levels(&self) -> Vec<f64> {
        self.levels_every(self.stepdown)
    }

    /// The mean depth of cut of the levels, mm: the stock top to the floor over their number.
    pub fn level_depth(&self) -> f64 {
        let (top, bottom) = (self.stock_hi.z, self.floor + self.allowance_floor);
        (top - bottom) / self.levels().len().max(1) as f64
    }

    /// The lowest level and the part's flats above it and under the stock top (raised by the
    /// floor allowance): the floor (with its allowance on top, protected like the part), raised
    /// to a flat that lies less than [`LEVEL_MERGE`] above it. A part whose lowest point is a
    /// few units in the last place under its base (float noise in the file) would otherwise get
    /// its last level under the base, whose shadow then holds the whole base: nothing cut there.
    fn bottom_and_flats(&self) -> (f64, Vec<f64>) {
        let top = self.stock_hi.z;
        let mut bottom = self.floor + self.allowance_floor;
        let flats: Vec<f64> =
            crate::geom::mesh::flats(&self.mesh, 1e-6).into_iter().map(|f| f + self.allowance_floor).collect();
        if let Some(&f) = flats.iter().rev().find(|&&f| f >= bottom && f <= bottom + LEVEL_MERGE && f < top) {
            bottom = f;
        }
        let between = flats.into_iter().filter(|&z| z < top - LEVEL_MERGE && z > bottom + LEVEL_MERGE).collect();
        (bottom, between)
    }

    /// The levels as [`MeshJob::levels`] with step-downs of at most `stepdown`.
    pub fn levels_every(&self, stepdown: f64) -> Vec<f64> {
        let top = self.stock_hi.z;
        let (bottom, flats) = self.bottom_and_flats();
        // the breaks: the stock top, the flats, the floor
        let mut breaks = vec![top, bottom];
        breaks.extend(flats);
        breaks.sort_by(|a, b| b.total_cmp(a));
        breaks.dedup_by(|a, b| (*b - *a).abs() <= LEVEL_MERGE);
        let mut zs: Vec<f64> = breaks.windows(2).flat_map(|w| even_steps(w[0], w[1], stepdown)).collect();
        if zs.is_empty() {
            zs.push(bottom);
        }
        zs
    }

    /// The levels of one tool of a sequence whose depth of cut is `depth`: an even grid of
    /// step-downs of at most `depth` from the stock top to the floor, and the flats between
    /// them. In a sequence the grids of tools whose depths divide the stock's height alike
    /// coincide, so a later tool's level never falls a sliver under an earlier tool's and
    /// re-cuts all the earlier tool cleared there (the flats do make such slivers, as
    /// [`MeshJob::levels`] avoids for one tool).
    pub fn levels_on_grid(&self, depth: f64) -> Vec<f64> {
        let top = self.stock_hi.z;
        let (bottom, flats) = self.bottom_and_flats();
        // (a grid level and a flat closer than LEVEL_MERGE are one level at the flat: at the
        // grid's height it would leave a skin on the flat)
        let mut zs: Vec<(f64, bool)> = even_steps(top, bottom, depth).map(|z| (z, z == bottom)).collect();
        zs.extend(flats.into_iter().map(|z| (z, true)));
        zs.sort_by(|a, b| b.0.total_cmp(&a.0));
        zs.dedup_by(|lower, upper| {
            let close = (upper.0 - lower.0).abs() <= LEVEL_MERGE;
            if close && lower.1 && !upper.1 {
                *upper = *lower;
            }
            close
        });
        zs.into_iter().map(|(z, _)| z).collect()
    }

    /// The 2.5D job of one level: the stock box, the part's shadow above it as the part.
    pub(crate) fn level_job(&self, keep: &Area, z: f64) -> Job {
        Job {
            name: self.name.clone(),
            stock: self.stock_area(),
            stock_top: self.stock_hi.z,
            part: keep.clone(),
            part_top: self.top(),
            fixtures: Area::empty(),
            floor: z,
            allowance: 0.0,
            allowance_floor: 0.0,
            stepdown: None,
            cutting: self.cutting.clone(),
        }
    }

    /// A 2.5D job over the whole stock without a part, for the job's material model.
    pub(crate) fn model_job(&self) -> Job {
        let mut j = self.level_job(&Area::empty(), self.floor + self.allowance_floor);
        j.part_top = self.stock_hi.z;
        j
    }
}

/// The heights from `a` down to `b` (not `a`, ending exactly at `b`) in the fewest even steps of
/// at most `step`.
fn even_steps(a: f64, b: f64, step: f64) -> impl Iterator<Item = f64> {
    let n = (((a - b) / step) - 1e-9).ceil().max(1.0) as usize;
    (1..=n).map(move |i| if i == n { b } else { a - (a - b) * i as f64 / n as f64 })
}

/// The region a level must not enter: the shadow grown by the allowance. The union of
/// thousands of facets has a vertex wherever two of them meet, so the shadow is simplified
/// within [`SHADOW_SIMPLIFY`] and grown by as much (the keep only grows, and the offsets of the
/// regions take a fraction of the time); the offset's output, which has runs of points a few µm
/// apart where its joins overlapped, is simplified within 1 µm after growing by 1 µm more.
pub(crate) fn keep_of(shadow: &Area, allowance: f64) -> Area {
    shadow
        .simplified(SHADOW_SIMPLIFY)
        .offset(allowance + SHADOW_GROW + SHADOW_SIMPLIFY + 0.001, REGION_TOL)
        .simplified(0.001)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::DVec3;
    use crate::model::Cutting;

    /// Upward flat squares (two triangles each) at the heights `zs`.
    fn flats_at(zs: &[f64]) -> Mesh {
        let tris = zs
            .iter()
            .enumerate()
            .flat_map(|(k, &z)| {
                let x = 20.0 * k as f64;
                let p = |dx: f64, dy: f64| DVec3::new(x + dx, dy, z);
                [[p(0.0, 0.0), p(10.0, 0.0), p(10.0, 10.0)], [p(0.0, 0.0), p(10.0, 10.0), p(0.0, 10.0)]]
            })
            .collect();
        Mesh { tris, dropped: 0, binary: false }
    }

    fn job(zs: &[f64], stepdown: f64) -> MeshJob {
        let mut j = MeshJob::new(
            "t",
            flats_at(zs),
            DVec3::new(-10.0, -10.0, 0.0),
            DVec3::new(100.0, 20.0, 50.0),
            Cutting::default(),
        );
        j.stepdown = stepdown;
        j
    }

    #[test]
    fn flats_are_levels_and_the_steps_between_them_even() {
        // 50 → 35: five of 3; 35 → 22: five of 2.6; 22 → 18: two of 2; 18 → 0: six of 3
        let j = job(&[35.0, 22.0, 18.0], 3.0);
        let want =
            [47.0, 44.0, 41.0, 38.0, 35.0, 32.4, 29.8, 27.2, 24.6, 22.0, 20.0, 18.0, 15.0, 12.0, 9.0, 6.0, 3.0, 0.0];
        let got = j.levels();
        assert_eq!(got.len(), want.len(), "{got:?}");
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() < 1e-9, "{got:?}");
        }
        // no step deeper than the step-down, none a sliver
        assert!(got.windows(2).all(|w| w[0] - w[1] <= 3.0 + 1e-9 && w[0] - w[1] >= 2.0 - 1e-9));
        assert!((j.level_depth() - 50.0 / 18.0).abs() < 1e-12);
    }

    #[test]
    fn flats_at_the_top_or_the_floor_or_together_make_one_level() {
        let j = job(&[50.0, 49.99, 35.0, 34.99, -0.005], 20.0);
        assert_eq!(j.levels(), vec![35.0, 17.5, 0.0]);
        // a flat a hair above the floor is the lowest level (else the base, above the last
        // level, is in its shadow and never cut)
        let j = job(&[35.0, 1e-9], 20.0);
        let want = [35.0, 35.0 - (35.0 - 1e-9) / 2.0, 1e-9];
        assert_eq!(j.levels(), want.to_vec());
        assert_eq!(*j.levels_on_grid(10.0).last().unwrap(), 1e-9);
    }

    #[test]
    fn every_flat_and_the_floor_are_cut_at_their_height_for_any_step_down() {
        // stock top 18.03, a flat at 10 and the floor at 0: a tool's grid of 2.004 has a level
        // at 10.014, which once stood for the flat and left a 0.014 mm skin on it
        let mut j = job(&[10.0], 2.004);
        j.stock_hi.z = 18.03;
        for zs in [j.levels(), j.levels_on_grid(2.004)] {
            assert!(zs.contains(&10.0) && zs.last() == Some(&0.0), "{zs:?}");
            assert!(!zs.iter().any(|&z| z > 10.0 && z - 10.0 <= LEVEL_MERGE), "{zs:?}");
        }
        // seeded random tops, step-downs and flats at least two merge widths apart
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut rnd = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..500 {
            let top = 5.0 + 45.0 * rnd();
            let mut flats: Vec<f64> = (0..4).map(|_| 0.1 + (top - 0.2) * rnd()).collect();
            flats.sort_by(|a, b| b.total_cmp(a));
            flats.dedup_by(|a, b| *b - *a < 3.0 * LEVEL_MERGE);
            let step = 0.05 + 5.0 * rnd();
            let mut j = job(&flats, step);
            j.stock_hi.z = top;
            for zs in [j.levels(), j.levels_on_grid(step)] {
                assert_eq!(zs.last(), Some(&0.0), "top {top} step {step} flats {flats:?}: {zs:?}");
                for f in flats.iter().filter(|&&f| f < top - LEVEL_MERGE) {
                    assert!(zs.contains(f), "top {top} step {step} flat {f}: {zs:?}");
                }
            }
        }
    }
}
