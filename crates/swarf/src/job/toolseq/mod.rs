//! The cost-optimal tool sequence for z-level roughing of a mesh part (paper 3, El-Midany et
//! al.: §2 eqs. 1–4, §3 Algorithms 1–2, §4 Algorithms 3–4, §6 Tables 1–3).
//!
//! A sequence is a set of tools of the database cut biggest first (eq. 1: `x ⊆ T`); it always
//! ends with the smallest tool, which sets what the sequence can reach (every row of the
//! paper's Table 2 ends with it). Each tool cuts its own hunting planes (levels every
//! `depth_of_cut` from the stock top to the floor, plus the part's flats, as
//! [`crate::model::MeshJob::levels`]).
//!
//! **Per tool, once** (whatever the sequence): at each level, the region of tool centres `C`
//! (the stock minus the part's shadow above the level grown by the tool radius), its
//! contour-parallel path (Algorithm 1: `C`, `C ⊖ ae`, `C ⊖ 2ae`, … until empty, cut from the
//! inside out, nested loops joined by a straight step where it stays inside `C`), and the area
//! the tool clears there, its accessible area `A = C ⊕ r` (Algorithm 2). The width of cut is
//! capped at the radius (Table 1's is exactly the radius): then every point of `C` is within
//! `ae ≤ r` of a loop, so the loops leave nothing of `A` uncut and `A` is what the level clears.
//!
//! **Per tool and prefix** (the tools before it in the sequence), Algorithm 4: the material
//! left at a level `z` is the stock minus the part and minus, for each earlier tool, its
//! accessible area at its highest level at or below `z` (its levels above cleared a superset,
//! its levels below clear nothing above `z`). The tool's own path is trimmed to where its disk
//! (grown by [`NEED_MARGIN`]) meets that material — the paper's `TrimTPC(offset(A₁, −r), TPC)`
//! written for several earlier tools with their own levels. A trimmed piece starts and ends
//! where the disk is in air, so the tool goes down there without plunging into material (where
//! the disk there reaches into the thin band along the part that counts as cleared, it goes
//! down a few hundredths further from the part and feeds across: a sliver of the band may stand
//! there as high as the level above, on a sloping wall); a path that starts in material (the
//! first tool, or a region no earlier tool reached) ramps down along its first loop. Between pieces the tool either feeds on along its path through
//! the cleared air or retracts and rapids, whichever is quicker.
//!
//! Algorithm 3 (the traditional decomposition) is kept for comparison
//! ([`Decomposition::Regions`]): the rest region `Z = C ∩ (material ⊕ r)` gets its own
//! contour-parallel path (offsets recomputed for every prefix) instead of a trimmed one.
//!
//! **The search** is exact: the prefix tree of the tools, biggest first, is walked depth-first;
//! every node costs one tool given the tools before it (each such cost is computed once and
//! shared by every sequence through that node), and a subtree is cut off when its cost so far
//! plus a lower bound of the last tool's cost is already above the best complete sequence. The
//! bound is the last tool's cutting time on the material that even every other tool would leave
//! (what must be cut at the least, as the material of a smaller prefix contains it) plus its
//! tool change. The time and cost of a tool are those of the program that is written (eq. 3's
//! `l_mc` is every feed move, `l_air` every rapid).

use crate::error::{Error, Result, Setting};
use crate::model::MeshJob;
use crate::model::tooldb::{Cost, ToolDb, ToolRun, ToolSpec};
use crate::toolpath::Toolpath;
use paths::{Prepared, prepare, run_tool};
use rayon::prelude::*;
use search::{Materials, Search};
use std::collections::HashMap;
use std::time::Instant;

mod paths;
mod search;

pub use paths::NEED_MARGIN;

/// How a later tool is confined to what the earlier tools left (paper 3 §4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Decomposition {
    /// Algorithm 4: the tool's own path, trimmed to where it meets material.
    Trim,
    /// Algorithm 3: a new contour-parallel path over the rest region.
    Regions,
}

/// Options of the search.
#[derive(Debug, Clone, PartialEq)]
pub struct SeqOptions {
    /// Cavity decomposition.
    pub decomposition: Decomposition,
    /// Cut off subtrees by the lower bound (off: cost every candidate sequence).
    pub prune: bool,
    /// Largest ramp angle of an entry, degrees.
    pub ramp_deg: f64,
    /// Clearance plane above the stock top (or the part, when higher), mm.
    pub clearance: f64,
}

impl SeqOptions {
    /// Algorithm 4 (trimmed paths), the bounded search, 3° ramps, a clearance plane 2 mm above
    /// the job.
    pub const DEFAULT: SeqOptions =
        SeqOptions { decomposition: Decomposition::Trim, prune: true, ramp_deg: 3.0, clearance: 2.0 };

    /// Checks the ramp angle (in (0°, 90°)) and the clearance (zero or more).
    pub fn validate(&self) -> Result<()> {
        if !(self.ramp_deg.is_finite() && self.ramp_deg > 0.0 && self.ramp_deg < 90.0) {
            return Err(Error::setting(
                Setting::SeqRampAngle,
                format!("{}°: must be between 0° and 90°", self.ramp_deg),
            ));
        }
        if !(self.clearance.is_finite() && self.clearance >= 0.0) {
            return Err(Error::setting(
                Setting::SeqClearance,
                format!("{} mm: must be zero or positive", self.clearance),
            ));
        }
        Ok(())
    }
}

impl Default for SeqOptions {
    fn default() -> Self {
        SeqOptions::DEFAULT
    }
}

/// One costed sequence.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Sequence {
    /// Tool ids, in cutting order.
    pub tools: Vec<String>,
    /// Their diameters, mm.
    pub diameters: Vec<f64>,
    /// Each tool's path lengths.
    #[serde(skip)]
    pub runs: Vec<ToolRun>,
    /// Time and cost (eqs. 2–4).
    #[serde(flatten)]
    pub cost: Cost,
    /// Indices of the tools in the database.
    #[serde(skip)]
    pub index: Vec<usize>,
}

/// One program of the chosen sequence.
#[derive(Debug, Clone)]
pub struct Program {
    /// The tool.
    pub spec: ToolSpec,
    /// Its number in the database (1-based), written as `T`.
    pub number: u32,
    /// The path.
    pub toolpath: Toolpath,
    /// Its lengths and feed.
    pub run: ToolRun,
}

/// The outcome of a search.
#[derive(Debug, Clone)]
pub struct SeqPlan {
    /// Every sequence costed, cheapest first.
    pub sequences: Vec<Sequence>,
    /// Candidates (every subset of the bigger tools, followed by the smallest).
    pub candidates: usize,
    /// Tool-given-prefix evaluations made.
    pub evaluations: usize,
    /// The programs of the cheapest sequence, in order.
    pub programs: Vec<Program>,
    /// The stock after each tool of the cheapest sequence (paper 3, Fig. 11).
    pub rest: RestMaps,
    /// Seconds spent on the tools' own geometry (levels, shadows, regions, loops).
    pub prepare_s: f64,
    /// Seconds spent on the search.
    pub search_s: f64,
}

/// Height maps of the stock after each tool of a sequence, over a grid of the stock box.
#[derive(Debug, Clone)]
pub struct RestMaps {
    /// The grid.
    pub grid: crate::sim::grid::Grid,
    /// The part's surface at each cell (the floor where there is no part).
    pub part: Vec<f32>,
    /// The stock's top after each tool, in order.
    pub after: Vec<Vec<f32>>,
    /// Stock top and bottom.
    pub top: f64,
    /// Lowest height of the job.
    pub bottom: f64,
}

impl RestMaps {
    /// Rest after tool `i`: (largest thickness above the part, volume mm³), counted where the
    /// stock stands more than `tol` above the part.
    pub fn rest(&self, i: usize, tol: f64) -> (f64, f64) {
        let cell = self.grid.res * self.grid.res;
        let mut max = 0.0f64;
        let mut vol = 0.0;
        for (s, p) in self.after[i].iter().zip(&self.part) {
            let t = f64::from(s - p);
            if t > tol {
                max = max.max(t);
                vol += t * cell;
            }
        }
        (max, vol)
    }

    /// A picture of the stock after tool `i` seen from above: grey by height (dark is deep),
    /// orange where stock stands above the part, the stronger the thicker.
    pub fn png(&self, i: usize) -> Result<Vec<u8>> {
        let g = self.grid;
        let (w, h) = (g.nx as u32, g.ny as u32);
        let mut pix = resvg::tiny_skia::Pixmap::new(w.max(1), h.max(1))
            .ok_or_else(|| Error::Output { what: "picture".into(), reason: "it is empty".into() })?;
        let span = (self.top - self.bottom).max(1e-9);
        let data = pix.data_mut();
        for j in 0..g.ny {
            for ii in 0..g.nx {
                let k = j * g.nx + ii;
                let s = f64::from(self.after[i][k]);
                let t = (s - f64::from(self.part[k])).max(0.0);
                let v = 60.0 + 180.0 * ((s - self.bottom) / span).clamp(0.0, 1.0);
                let a = if t > 0.05 { (0.35 + 0.65 * (t / 5.0).min(1.0)).min(1.0) } else { 0.0 };
                let (r, gg, b) = (v + (255.0 - v) * a, v + (140.0 - v) * a, v * (1.0 - a));
                // image rows top down: y up in the grid
                let o = ((g.ny - 1 - j) * g.nx + ii) * 4;
                data[o] = r.round() as u8;
                data[o + 1] = gg.round() as u8;
                data[o + 2] = b.round() as u8;
                data[o + 3] = 255;
            }
        }
        pix.encode_png()
            .map_err(|e| Error::Output { what: "picture".into(), reason: format!("cannot encode the PNG: {e}") })
    }
}

impl SeqPlan {
    /// The cheapest sequence.
    pub fn best(&self) -> &Sequence {
        &self.sequences[0]
    }
}

/// Most tools a search takes (2^(n−1) candidate sequences).
pub const MAX_TOOLS: usize = 20;

/// Finds the cheapest tool sequence for `job` with the tools of `db` (the job's own tool,
/// step-down and feed are not used), and the programs of that sequence.
///
/// ```
/// use swarf::model::tooldb::ToolDb;
/// use swarf::{Input, Overrides, SeqOptions, load_input, plan_tools};
/// let root = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");
/// let case = format!("{root}/examples/3d/bowl_cavity.json");
/// let Input::Mesh(job) = load_input(case.as_ref(), &Overrides::DEFAULT)? else { unreachable!() };
/// let db = ToolDb::read(format!("{root}/examples/tools/table1.json").as_ref())?;
/// let plan = plan_tools(&job, &db, &SeqOptions::DEFAULT)?;
/// let best = plan.best();
/// // one program per tool of the cheapest sequence, biggest first
/// assert_eq!(plan.programs.len(), best.tools.len());
/// assert!(best.diameters.windows(2).all(|w| w[0] >= w[1]));
/// # Ok::<(), swarf::Error>(())
/// ```
pub fn plan(job: &MeshJob, db: &ToolDb, opts: &SeqOptions) -> Result<SeqPlan> {
    let t0 = Instant::now();
    let prep = prepare(job, db, opts)?;
    let prepare_s = t0.elapsed().as_secs_f64();
    log::info!("{} tools prepared in {prepare_s:.2} s", prep.tools.len());
    let t1 = Instant::now();
    let mut search =
        Search { prep: &prep, memo: HashMap::new(), mats: Materials::default(), done: Vec::new(), best: f64::INFINITY };
    let n = prep.tools.len();
    let last = n - 1;
    // the least the last tool must cut, whatever comes before it
    let all: Vec<usize> = (0..last).collect();
    let bound = if opts.prune && opts.decomposition == Decomposition::Trim {
        let need = search.eval(last, &all).need_mm;
        let spec = &prep.tools[last].spec;
        Some(ToolRun {
            cut_mm: need,
            air_mm: 0.0,
            feed_mm_min: spec.feed_mm_min(),
            price: spec.price,
            life_min: spec.life_min,
        })
    } else {
        None
    };
    search.walk(&mut Vec::new(), &mut Vec::new(), bound.as_ref());
    let evaluations = search.memo.len();
    let mut sequences = search.done;
    sequences.sort_by(|a, b| a.cost.total_cost.total_cmp(&b.cost.total_cost).then_with(|| a.index.cmp(&b.index)));
    let best = sequences.first().ok_or_else(|| Error::job("tools", "no sequence could be costed"))?;
    let programs = best
        .index
        .iter()
        .enumerate()
        .map(|(i, &k)| {
            let mats = search.mats.of(&prep, &best.index[..i]);
            let (toolpath, run, _) = run_tool(&prep, k, &best.index[..i], &mats);
            Program { spec: prep.tools[k].spec.clone(), number: prep.tools[k].number, toolpath, run }
        })
        .collect();
    let rest = rest_maps(job, &prep, &best.index);
    Ok(SeqPlan {
        sequences,
        candidates: 1 << last,
        evaluations,
        programs,
        rest,
        prepare_s,
        search_s: t1.elapsed().as_secs_f64(),
    })
}

/// Costs one sequence on its own (no shared work, no bound): `seq` lists database indices,
/// biggest tool first. For checking the search.
pub fn cost_of(job: &MeshJob, db: &ToolDb, seq: &[usize], opts: &SeqOptions) -> Result<Cost> {
    let prep = prepare(job, db, opts)?;
    let order: Vec<usize> = seq
        .iter()
        .map(|&i| prep.tools.iter().position(|t| t.number as usize == i + 1))
        .collect::<Option<_>>()
        .ok_or_else(|| Error::job("tools", "a tool index is out of range"))?;
    let mut mats = Materials::default();
    let runs: Vec<ToolRun> = order
        .iter()
        .enumerate()
        .map(|(i, &k)| run_tool(&prep, k, &order[..i], &mats.of(&prep, &order[..i])).1)
        .collect();
    Ok(prep.machine.cost(&runs))
}

/// The stock after each tool of `seq`: at every cell, the lowest level at which a tool so far
/// cleared it (its accessible area there).
fn rest_maps(job: &MeshJob, prep: &Prepared, seq: &[usize]) -> RestMaps {
    let size = job.stock_hi - job.stock_lo;
    let res = (size.x.max(size.y) / 500.0).max(0.05);
    let lo = job.stock_lo.truncate();
    let g = crate::sim::grid::Grid::covering(lo, job.stock_hi.truncate(), 0.0, res, lo);
    let floor = (job.floor + job.allowance_floor) as f32;
    let part: Vec<f32> = crate::sim::heights::height_map(&job.mesh, &g)
        .into_iter()
        .map(|h| (h + job.allowance_floor as f32).max(floor))
        .collect();
    let mut cur = vec![prep.top as f32; g.len()];
    let mut after = Vec::new();
    for &k in seq {
        let masks: Vec<(f32, Vec<bool>)> =
            prep.tools[k].levels.par_iter().map(|l| (l.z as f32, g.rasterize(&l.access))).collect();
        for (z, m) in masks {
            for (c, inside) in cur.iter_mut().zip(m) {
                if inside {
                    *c = c.min(z);
                }
            }
        }
        after.push(cur.clone());
    }
    RestMaps { grid: g, part, after, top: prep.top, bottom: f64::from(floor) }
}
