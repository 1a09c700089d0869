//! Material simulation on a raster (paper 1 §4, §4.2): part, stock, fixture and free space in
//! cells of a size the user sets, cut by replaying lines, arcs and helices with a flat end mill.
//!
//! The simulator measures what the report and the benchmarks need: **engagement** two ways
//! (paper 1 eq. 4, the share of the tool's circumference pixels in material, and exactly, from
//! the cleared geometry), **gouges**, **rapid collisions**, **plunges**, the removed volume and
//! the **rest material**. Each cell holds the stock top height, so one model serves every level
//! of a 2.5D job, and moves are cut analytically. A second engine replays programs on sampled
//! signed distance fields (paper 4 §4, eqs. 9–12) with the same measures through the same
//! replay; [`SimOptions::engine`] picks the one [`simulate`] uses for the report. The
//! walk-through of both engines is in `docs/simulation.md`.

#[doc(hidden)]
pub mod edt;
#[doc(hidden)]
pub mod exact;
#[doc(hidden)]
pub mod grid;
#[doc(hidden)]
pub mod heights;
#[doc(hidden)]
pub mod raster;
pub(crate) mod replay;
#[doc(hidden)]
pub mod sdf;
#[doc(hidden)]
pub mod sweep;

#[doc(hidden)]
pub use raster::RasterSim;
pub use replay::{Event, Replay, Rest, Sample, SampleKind, TopView};
#[doc(hidden)]
pub use sdf::SdfSim;

use crate::error::{Error, Result, Setting};
use crate::geom;
use crate::model::{Job, Regions};
use crate::toolpath::Toolpath;

/// Which material model replays a program for the report.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum SimEngine {
    /// Heights on a raster of cells (`RasterSim`), exact engagement from the cleared
    /// geometry.
    #[default]
    Raster,
    /// Sampled signed distance fields per slab (`SdfSim`, paper 4 §4), engagement by root
    /// finding on the field.
    Sdf,
}

impl SimEngine {
    /// The engine's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SimEngine::Raster => "raster",
            SimEngine::Sdf => "sdf",
        }
    }
}

impl std::str::FromStr for SimEngine {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        match s {
            "raster" => Ok(SimEngine::Raster),
            "sdf" => Ok(SimEngine::Sdf),
            _ => Err(Error::setting(Setting::SimEngine, format!("{s:?}: expected raster or sdf"))),
        }
    }
}

/// Replays `tp` on a fresh model of `job` built by the engine `opts.engine` chooses, and
/// measures the rest material it leaves: the replay (its rest cells and cell size filled in)
/// and the rest.
pub fn simulate(
    job: &Job,
    regions: &Regions,
    opts: &SimOptions,
    tp: &Toolpath,
    progress: &mut dyn FnMut(f64),
) -> Result<(Replay, Rest)> {
    match opts.engine {
        SimEngine::Raster => {
            let mut sim = RasterSim::new(job, regions, opts)?;
            let mut rp = sim.replay(tp, progress);
            rp.rest_cells = sim.rest_cells();
            rp.res = sim.grid.res;
            Ok((rp, sim.rest()))
        }
        SimEngine::Sdf => {
            let mut sim = SdfSim::new(job, regions, opts)?;
            let mut rp = sim.replay(tp, progress);
            rp.rest_cells = sim.rest_cells();
            Ok((rp, sim.rest()))
        }
    }
}

/// Simulation settings.
#[derive(Debug, Clone, PartialEq)]
pub struct SimOptions {
    /// Cell size in mm; `None` picks `D / 100` within [0.02, 0.1].
    pub res: Option<f64>,
    /// Gouge tolerance, mm: the tool may come this close into the part before it counts.
    pub tol: f64,
    /// Material counts for engagement when it stands more than this above the tool tip, mm.
    pub eps: f64,
    /// The engagement ring is `R + ring_delta` (mm) so that the wall the tool is cutting, at
    /// exactly `R`, does not read as material.
    pub ring_delta: f64,
    /// Spacing of engagement samples along cutting moves, mm; `None` = `res` (a sample a cell:
    /// the pixel ring reads the stock to a cell).
    pub sample_step: Option<f64>,
    /// Refuse grids larger than this many cells.
    pub max_cells: usize,
    /// The cell chosen for the tool ([`SimOptions::res_for`]) is coarsened to keep a job's
    /// grid within this many cells (see [`SimOptions::fitted`]): time and memory grow with the
    /// cells, and a large plate needs no finer cell than a small pocket does. A cell the user
    /// gives is never changed.
    pub auto_cells: usize,
    /// Heights that override the job's flat stock top and part walls where they say more: the
    /// state a 3D job's earlier levels and tools left, and the part's surface (see
    /// [`HeightMap`]).
    pub heights: Option<std::sync::Arc<HeightMap>>,
    /// Keep the surely cut heights too (see `raster::RasterSim::is_clear`) and check links and
    /// rapids against them: a speck narrower than a cell between sweeps then never meets a
    /// rapid. On for the levels of z-level roughing, whose long rapids at depth cross large
    /// cleared areas; it makes cutting in the model about a tenth slower.
    pub sure_links: bool,
    /// The engine [`simulate`] replays a program with (the planner always uses the raster).
    /// For [`SimEngine::Sdf`], `res` is the sample spacing of the fields.
    pub engine: SimEngine,
    /// Measure the exact engagement at every sample. Off, the raster engine measures it exactly
    /// every `R/6` or so along a move and between those where the pixel reading is ambiguous,
    /// and draws it along the line between them where the pixels show it changing smoothly
    /// (about a fifth of the work, the same statistics to a tenth of a degree on the examples).
    pub exact_every_sample: bool,
}

impl SimOptions {
    /// The cell size for the tool ([`SimOptions::res_for`]) within 20 million cells, 0.01 mm
    /// gouge tolerance and engagement threshold, a sample every cell, at most 60 million
    /// cells, the raster engine, the exact engagement where the pixels leave it in doubt.
    pub const DEFAULT: SimOptions = SimOptions {
        res: None,
        tol: 0.01,
        eps: 0.01,
        ring_delta: 1e-4,
        sample_step: None,
        max_cells: 60_000_000,
        auto_cells: 20_000_000,
        heights: None,
        sure_links: false,
        engine: SimEngine::Raster,
        exact_every_sample: false,
    };

    /// Checks the settings: a positive cell size and sample step, tolerances of zero or more, a
    /// cell budget.
    pub fn validate(&self) -> Result<()> {
        if let Some(r) = self.res
            && !(r.is_finite() && r > 0.0)
        {
            return Err(Error::setting(Setting::Resolution, format!("{r} mm: the cell size must be positive")));
        }
        if let Some(s) = self.sample_step
            && !(s.is_finite() && s > 0.0)
        {
            return Err(Error::setting(Setting::Simulation, format!("sample step {s} mm: must be positive")));
        }
        for (what, v) in [("tol", self.tol), ("eps", self.eps), ("ring_delta", self.ring_delta)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::setting(Setting::Simulation, format!("{what} {v} mm: must be zero or positive")));
            }
        }
        if self.max_cells == 0 || self.auto_cells == 0 {
            return Err(Error::setting(Setting::Simulation, "max_cells, auto_cells: must be positive"));
        }
        Ok(())
    }
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions::DEFAULT
    }
}

/// Stock and part heights on a grid, for the models of a 3D job (z-level roughing of a mesh):
/// a model built with them in [`SimOptions::heights`] lowers its stock to `stock` and raises its
/// part to `part` at every cell whose centre falls in a cell of `grid` (cells of both grids
/// aligned to the same origin and size coincide).
#[derive(Debug, Clone, PartialEq)]
pub struct HeightMap {
    /// The grid of the heights.
    pub grid: grid::Grid,
    /// Top of the stock per cell (−∞: no stock).
    pub stock: Vec<f32>,
    /// Top of what must stay per cell (−∞: nothing), or none.
    pub part: Option<Vec<f32>>,
}

impl HeightMap {
    /// The index of the cell of `grid` holding `q`.
    pub fn cell(&self, q: geom::DVec2) -> Option<usize> {
        self.grid.cell_of(q).map(|(i, j)| j * self.grid.nx + i)
    }
}

impl SimOptions {
    /// The cell size for a tool of diameter `d`.
    pub fn res_for(&self, d: f64) -> f64 {
        self.res.unwrap_or_else(|| (d / 100.0).clamp(0.02, 0.1))
    }

    /// The coarsest cell chosen for a job too large for [`SimOptions::res_for`]'s, as a
    /// fraction of the tool's diameter: a tenth still reads the engagement to a few degrees.
    pub const COARSEST_CELL_PER_DIAMETER: f64 = 0.1;

    /// The options with the cell chosen to fit a job whose stock spans `lo`..`hi` (mm) with a
    /// tool of diameter `d`: `None` when no cell is given and the tool's cell keeps the grid
    /// (the span grown by ten radii and 20 mm) within nine tenths of [`SimOptions::auto_cells`]
    /// (or [`SimOptions::max_cells`], if fewer);
    /// else the cell coarsened just enough, up to [`SimOptions::COARSEST_CELL_PER_DIAMETER`] of
    /// the diameter (beyond that the grid stays too large and the model refuses it, naming the
    /// cell). A cell the user gave is never changed.
    pub fn fitted(&self, d: f64, lo: geom::DVec2, hi: geom::DVec2) -> Option<SimOptions> {
        if self.res.is_some() || !(d.is_finite() && d > 0.0) {
            return None;
        }
        let base = self.res_for(d);
        let span = hi - lo + geom::DVec2::splat(5.0 * d + 20.0);
        if !(span.x.is_finite() && span.y.is_finite()) {
            return None;
        }
        let cells = self.auto_cells.min(self.max_cells);
        let budget = 0.9 * cells as f64;
        if (span.x / base) * (span.y / base) <= budget {
            return None;
        }
        let need = ((span.x * span.y / budget).sqrt() * 1000.0).ceil() / 1000.0;
        let res = need.min(Self::COARSEST_CELL_PER_DIAMETER * d);
        log::warn!(
            "the job spans {:.0} × {:.0} mm: the simulation's cell is {res:.3} mm instead of {base:.3} mm to keep within {} million cells (--res sets it)",
            hi.x - lo.x,
            hi.y - lo.y,
            cells / 1_000_000
        );
        Some(SimOptions { res: Some(res), ..self.clone() })
    }

    /// [`SimOptions::fitted`] to a stock spanning `span` (when it has one), or the options as
    /// they are: the settings a program on that stock is proven with.
    pub fn fitted_to(&self, d: f64, span: Option<(geom::DVec2, geom::DVec2)>) -> SimOptions {
        span.and_then(|(lo, hi)| self.fitted(d, lo, hi)).unwrap_or_else(|| self.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::DVec2;

    #[test]
    fn a_large_job_gets_a_coarser_cell_within_the_budget_and_a_given_cell_stays() {
        let o = SimOptions::DEFAULT;
        let lo = DVec2::ZERO;
        // small: the tool's own cell
        assert_eq!(o.fitted(6.0, lo, DVec2::new(200.0, 150.0)), None);
        // 800 × 700 mm with a 6 mm tool: 0.06 mm would be ~1.6e8 cells
        let f = o.fitted(6.0, lo, DVec2::new(800.0, 700.0)).expect("coarsened");
        let res = f.res.unwrap();
        assert!(res > 0.06 && res <= 0.6, "{res}");
        let span = DVec2::new(800.0, 700.0) + DVec2::splat(5.0 * 6.0 + 20.0);
        assert!((span.x / res) * (span.y / res) <= 0.9 * o.auto_cells as f64);
        // never coarser than a tenth of the tool: beyond, the model refuses the grid
        let huge = o.fitted(6.0, lo, DVec2::new(1e5, 1e5)).unwrap();
        assert!((huge.res.unwrap() - 0.6).abs() < 1e-12, "{:?}", huge.res);
        // the user's cell is theirs
        let given = SimOptions { res: Some(0.05), ..o };
        assert_eq!(given.fitted(6.0, lo, DVec2::new(800.0, 700.0)), None);
    }
}
