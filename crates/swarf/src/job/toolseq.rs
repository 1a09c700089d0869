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
//! where the disk is in air, so the tool goes down there without plunging into material; a
//! path that starts in material (the first tool, or a region no earlier tool reached) ramps
//! down along its first loop. Between pieces the tool either feeds on along its path through
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
use crate::geom::{Area, DVec2, DVec3, segments_intersect};
use crate::model::tooldb::{Cost, ToolDb, ToolRun, ToolSpec};
use crate::model::{MeshJob, REGION_TOL, Tool};
use crate::toolpath::{MoveKind, Toolpath};
use rayon::prelude::*;
use std::collections::HashMap;
use std::time::Instant;

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

/// Points of a path are this far apart at most when trimmed (mm).
const SAMPLE: f64 = 0.5;
/// The tool disk is grown by this when it is asked whether it meets material (mm): more than
/// the sagitta of a `SAMPLE` chord on the smallest disk, so a path between two samples in air
/// is in air.
pub const NEED_MARGIN: f64 = 0.05;
/// Tool centres keep this much more than the radius from the part (mm).
const WALL_MARGIN: f64 = 0.005;
/// Material thinner than this above a level is taken as cleared (mm): levels of two tools this
/// close are one.
const Z_TOL: f64 = 0.05;
/// Rest areas smaller than this are dropped (mm²).
const SLIVER: f64 = 1e-3;
/// Ramps start this far above the level above (mm).
const RAMP_CLEAR: f64 = 0.05;
/// Tool centres stay this much less than the radius outside the stock (mm).
const OUTSIDE: f64 = 0.1;
/// Rapids stop this far above the material before a feed move down (mm).
const APPROACH: f64 = 0.5;

/// A continuous feed path at one level: points at most [`SAMPLE`] apart.
#[derive(Debug, Clone)]
struct Chain {
    pts: Vec<DVec2>,
    /// Arc length at each point.
    at: Vec<f64>,
    /// Index of the point closing the chain's first loop (a ramp follows that loop).
    ring_end: usize,
}

/// One level of one tool.
#[derive(Debug, Clone)]
struct Level {
    z: f64,
    /// The level above it for this tool (or the stock top): what the tool's own earlier levels
    /// cleared.
    above: f64,
    /// Tool centres.
    centres: Area,
    /// What the tool clears at this level (Algorithm 2).
    access: Area,
    /// Its full contour-parallel path (Algorithm 1).
    chains: Vec<Chain>,
    /// Index of its height among every tool's levels.
    zi: usize,
    /// Where the tool may travel just above the level above (its centres, grown by 4 µm: the
    /// tool cleared everything over them down to that level), when the level above is cut.
    over: Option<Area>,
}

/// A tool with its levels.
#[derive(Debug, Clone)]
struct ToolGeom {
    spec: ToolSpec,
    number: u32,
    levels: Vec<Level>,
}

/// Everything that does not depend on the sequence.
struct Prepared {
    tools: Vec<ToolGeom>,
    /// Every tool's levels, top down.
    zs: Vec<f64>,
    /// At each of them, the part's keep grown a little (the band no tool enters counts as
    /// cleared).
    bands: Vec<Area>,
    stock: Area,
    top: f64,
    clear_z: f64,
    machine: crate::model::tooldb::Machine,
    opts: SeqOptions,
}

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

/// The material left by a prefix at every level height, each the one before it minus the last
/// tool's accessible area there (shared by every sequence through the prefix).
#[derive(Default)]
struct Materials {
    memo: HashMap<Vec<usize>, std::sync::Arc<Vec<Area>>>,
}

impl Materials {
    fn of(&mut self, prep: &Prepared, prefix: &[usize]) -> std::sync::Arc<Vec<Area>> {
        if let Some(m) = self.memo.get(prefix) {
            return m.clone();
        }
        // only the heights of the tools that can follow the prefix are read
        let from = prefix.last().map_or(0, |&j| j + 1);
        let mut wanted = vec![false; prep.zs.len()];
        for t in &prep.tools[from..] {
            for l in &t.levels {
                wanted[l.zi] = true;
            }
        }
        let m: Vec<Area> = match prefix.split_last() {
            None => prep
                .bands
                .par_iter()
                .zip(&wanted)
                .map(|(b, &w)| if w { prep.stock.difference(b).without_slivers(SLIVER) } else { Area::empty() })
                .collect(),
            Some((&j, parent)) => {
                let before = self.of(prep, parent);
                let levels = &prep.tools[j].levels;
                prep.zs
                    .par_iter()
                    .zip(before.par_iter())
                    .zip(&wanted)
                    .map(|((&z, m), &w)| {
                        if !w || m.is_empty() {
                            return Area::empty();
                        }
                        // the tool's highest level at or below z: its levels above cleared less
                        // deep, its levels below nothing above z
                        match levels.iter().find(|l| l.z <= z + Z_TOL) {
                            Some(l) if boxes_overlap(m, &l.access) => m.difference(&l.access).without_slivers(SLIVER),
                            _ => m.clone(),
                        }
                    })
                    .collect()
            }
        };
        let m = std::sync::Arc::new(m);
        self.memo.insert(prefix.to_vec(), m.clone());
        m
    }
}

/// The result of one tool given its prefix.
#[derive(Debug, Clone, Copy)]
struct Eval {
    run: ToolRun,
    /// Length of path whose disk meets material (a lower bound of the cutting length).
    need_mm: f64,
}

struct Search<'a> {
    prep: &'a Prepared,
    memo: HashMap<(usize, Vec<usize>), Eval>,
    mats: Materials,
    done: Vec<Sequence>,
    best: f64,
}

impl Search<'_> {
    fn eval(&mut self, k: usize, prefix: &[usize]) -> Eval {
        if let Some(e) = self.memo.get(&(k, prefix.to_vec())) {
            return *e;
        }
        let mats = self.mats.of(self.prep, prefix);
        let (_, run, need_mm) = run_tool(self.prep, k, prefix, &mats);
        let e = Eval { run, need_mm };
        self.memo.insert((k, prefix.to_vec()), e);
        e
    }

    /// Visits the node `prefix` (with its tools' runs): costs the sequence that ends it with the
    /// last tool, then each child.
    fn walk(&mut self, prefix: &mut Vec<usize>, runs: &mut Vec<ToolRun>, bound: Option<&ToolRun>) {
        let n = self.prep.tools.len();
        let last = n - 1;
        let m = self.prep.machine.clone();
        let e = self.eval(last, prefix);
        let mut all = runs.clone();
        all.push(e.run);
        let cost = m.cost(&all);
        self.best = self.best.min(cost.total_cost);
        let mut index: Vec<usize> = prefix.clone();
        index.push(last);
        self.done.push(Sequence {
            tools: index.iter().map(|&k| self.prep.tools[k].spec.id.clone()).collect(),
            diameters: index.iter().map(|&k| self.prep.tools[k].spec.diameter).collect(),
            runs: all,
            cost,
            index,
        });
        let from = prefix.last().map_or(0, |&k| k + 1);
        for j in from..last {
            let e = self.eval(j, prefix);
            runs.push(e.run);
            let prune = bound.is_some_and(|b| {
                let mut lb = runs.clone();
                lb.push(*b);
                m.cost(&lb).total_cost > self.best * (1.0 + 1e-12)
            });
            if !prune {
                prefix.push(j);
                self.walk(prefix, runs, bound);
                prefix.pop();
            }
            runs.pop();
        }
    }
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

/// Reads the levels, shadows, regions and loops of every tool.
fn prepare(job: &MeshJob, db: &ToolDb, opts: &SeqOptions) -> Result<Prepared> {
    job.validate()?;
    opts.validate()?;
    if db.tools.is_empty() {
        return Err(Error::job("tools", "the tool database has no tools"));
    }
    if db.tools.len() > MAX_TOOLS {
        return Err(Error::job(
            "tools",
            format!(
                "{} tools: the search covers every subset of them (2^{} sequences); at most {MAX_TOOLS}",
                db.tools.len(),
                db.tools.len() - 1
            ),
        ));
    }
    // biggest first; equal diameters in the file's order
    let mut order: Vec<usize> = (0..db.tools.len()).collect();
    order.sort_by(|&a, &b| db.tools[b].diameter.total_cmp(&db.tools[a].diameter).then(a.cmp(&b)));
    let tool_levels: Vec<Vec<f64>> = order.iter().map(|&i| job.levels_every(db.tools[i].depth_of_cut)).collect();
    // every tool's levels, each shadow once, top down
    let mut zs: Vec<f64> = tool_levels.iter().flatten().copied().collect();
    zs.sort_by(|a, b| b.total_cmp(a));
    zs.dedup();
    let t0 = Instant::now();
    let mut shadows = crate::geom::mesh::Shadows::new(&job.mesh);
    let keeps: Vec<Area> = zs
        .iter()
        .map(|&z| {
            let ta = Instant::now();
            let sh = shadows.down_to(z - job.allowance_floor);
            let tb = ta.elapsed().as_secs_f64();
            let k = crate::model::keep_of(sh, job.allowance);
            log::trace!(
                "toolseq: shadow z {z:.3} {} vertices {} rings {} polys, {tb:.3} s, keep {:.3} s",
                sh.vertex_count(),
                sh.rings().count(),
                sh.polys.len(),
                ta.elapsed().as_secs_f64() - tb
            );
            k
        })
        .collect();
    log::debug!("toolseq: {} levels, shadows in {:.2} s", zs.len(), t0.elapsed().as_secs_f64());
    let bands: Vec<Area> = keeps.par_iter().map(|k| k.offset(WALL_MARGIN + 0.03, REGION_TOL)).collect();
    let stock = job.stock_area();
    let keep_at = |z: f64| zs.iter().position(|&w| w == z).expect("a level of some tool");
    let pairs: Vec<(usize, usize)> =
        tool_levels.iter().enumerate().flat_map(|(t, ls)| (0..ls.len()).map(move |l| (t, l))).collect();
    let geoms: Vec<Option<(Area, Area, Vec<Chain>)>> = pairs
        .par_iter()
        .map(|&(t, l)| {
            let spec = &db.tools[order[t]];
            let r = spec.diameter / 2.0;
            let keep = &keeps[keep_at(tool_levels[t][l])];
            let ta = Instant::now();
            // (centres may leave the stock by up to the radius less OUTSIDE, so that the tool
            // reaches the stock's edges and the corners the part leaves there)
            let centres = stock
                .offset(r - OUTSIDE, REGION_TOL)
                .difference(&keep.offset(r + WALL_MARGIN, REGION_TOL))
                .without_slivers(SLIVER);
            if centres.is_empty() {
                return None;
            }
            let tb = Instant::now();
            let access = centres.offset(r - 0.01, REGION_TOL);
            let tc = Instant::now();
            let chains = chains_of(&centres, spec.width_of_cut.min(spec.diameter / 2.0));
            log::trace!(
                "toolseq: D{} z {:.3}: centres {:.3} s ({} vertices), access {:.3} s, {} chains {:.3} s",
                spec.diameter,
                tool_levels[t][l],
                (tb - ta).as_secs_f64(),
                centres.vertex_count(),
                (tc - tb).as_secs_f64(),
                chains.len(),
                tc.elapsed().as_secs_f64()
            );
            Some((centres, access, chains))
        })
        .collect();
    let mut tools: Vec<ToolGeom> = order
        .iter()
        .map(|&i| ToolGeom { spec: db.tools[i].clone(), number: i as u32 + 1, levels: Vec::new() })
        .collect();
    for (&(t, l), g) in pairs.iter().zip(geoms) {
        let Some((centres, access, chains)) = g else { continue };
        let z = tool_levels[t][l];
        let above = if l == 0 { job.stock_hi.z } else { tool_levels[t][l - 1] };
        let over = tools[t].levels.last().filter(|p| p.z == above).map(|p| p.centres.offset(0.004, REGION_TOL));
        tools[t].levels.push(Level { z, above, centres, access, chains, zi: keep_at(z), over });
    }
    Ok(Prepared {
        tools,
        zs,
        bands,
        stock,
        top: job.stock_hi.z,
        clear_z: job.top() + opts.clearance,
        machine: db.machine.clone(),
        opts: opts.clone(),
    })
}

/// Algorithm 1: the contour-parallel path of a region of tool centres, as continuous chains.
///
/// The region and its inward offsets by `ae` form a tree (each offset polygon lies in one
/// polygon of the offset before it); the tree is cut from the leaves up (inside out, so every
/// loop cuts into material on its outer side), each loop in its stored orientation (outer
/// boundaries counter-clockwise, holes clockwise: climb milling with a clockwise spindle), from
/// its vertex nearest to where the tool is. A loop joins the chain before it by a straight step
/// when that is no longer than 1.5·`ae` and stays inside the region; otherwise it starts a
/// new chain.
fn chains_of(region: &Area, ae: f64) -> Vec<Chain> {
    let mut layers: Vec<Vec<crate::geom::area::Polygon>> = vec![region.polys.clone()];
    loop {
        let d = layers.len() as f64 * ae;
        let a = region.offset(-d, REGION_TOL).without_slivers(SLIVER);
        if a.is_empty() || layers.len() > 10_000 {
            break;
        }
        layers.push(a.polys);
    }
    // children[k][j]: the polygons of layer k + 1 inside polygon j of layer k
    let mut children: Vec<Vec<Vec<usize>>> = layers.iter().map(|l| vec![Vec::new(); l.len()]).collect();
    for k in 1..layers.len() {
        let parents: Vec<Area> = layers[k - 1].iter().map(|p| Area { polys: vec![p.clone()] }).collect();
        for (i, p) in layers[k].iter().enumerate() {
            let q = p.outer[0];
            let j = parents.iter().position(|a| a.contains(q)).unwrap_or_else(|| {
                // (on a parent's boundary within rounding: the nearest parent)
                nearest_index(parents.iter().map(|a| ring_distance(&a.polys[0].outer, q)))
            });
            children[k - 1][j].push(i);
        }
    }
    let mut b = ChainBuilder { chains: Vec::new(), cur: Vec::new(), ring_end: 0, pos: None, ae };
    let roots: Vec<usize> = (0..layers[0].len()).collect();
    for root in b.nearest_order(&roots, &layers[0]) {
        b.visit(&layers, &children, 0, root, &layers[0][root]);
    }
    b.flush();
    b.chains
}

struct ChainBuilder {
    chains: Vec<Chain>,
    cur: Vec<DVec2>,
    ring_end: usize,
    pos: Option<DVec2>,
    ae: f64,
}

impl ChainBuilder {
    /// `items` ordered greedily, each nearest (by its outer ring's vertices) to where the
    /// one before left the tool — approximated by the current position for all.
    fn nearest_order(&self, items: &[usize], polys: &[crate::geom::area::Polygon]) -> Vec<usize> {
        let mut v = items.to_vec();
        if let Some(p) = self.pos {
            v.sort_by(|&a, &b| {
                ring_distance(&polys[a].outer, p).total_cmp(&ring_distance(&polys[b].outer, p)).then(a.cmp(&b))
            });
        }
        v
    }

    fn visit(
        &mut self,
        layers: &[Vec<crate::geom::area::Polygon>],
        children: &[Vec<Vec<usize>>],
        k: usize,
        j: usize,
        root: &crate::geom::area::Polygon,
    ) {
        let mut kids = children[k][j].clone();
        while !kids.is_empty() {
            let next = self.nearest_order(&kids, &layers[k + 1])[0];
            kids.retain(|&c| c != next);
            self.visit(layers, children, k + 1, next, root);
        }
        let poly = &layers[k][j];
        let mut rings: Vec<&Vec<DVec2>> = poly.rings().collect();
        while !rings.is_empty() {
            let p = self.pos.unwrap_or(rings[0][0]);
            let (ri, vi) = rings
                .iter()
                .enumerate()
                .map(|(ri, r)| {
                    let vi = nearest_index(r.iter().map(|q| (*q - p).length_squared()));
                    (ri, vi, (r[vi] - p).length_squared())
                })
                .min_by(|a, b| a.2.total_cmp(&b.2))
                .map(|(ri, vi, _)| (ri, vi))
                .unwrap_or((0, 0));
            let ring = rings.remove(ri);
            let mut closed: Vec<DVec2> = ring[vi..].iter().chain(ring[..vi].iter()).copied().collect();
            closed.push(ring[vi]);
            self.add_ring(closed, root);
        }
    }

    fn add_ring(&mut self, closed: Vec<DVec2>, root: &crate::geom::area::Polygon) {
        let start = closed[0];
        let joined = match self.cur.last() {
            Some(&end) => (start - end).length() <= 1.5 * self.ae + 1e-9 && !crosses(root, end, start),
            None => false,
        };
        if !joined {
            self.flush();
        }
        let first = self.cur.is_empty();
        if !first {
            densify_to(&mut self.cur, start);
        } else {
            self.cur.push(start);
        }
        for &q in &closed[1..] {
            densify_to(&mut self.cur, q);
        }
        if first {
            self.ring_end = self.cur.len() - 1;
        }
        self.pos = Some(start);
    }

    fn flush(&mut self) {
        if self.cur.len() >= 2 {
            let pts = std::mem::take(&mut self.cur);
            let mut at = Vec::with_capacity(pts.len());
            let mut s = 0.0;
            for (i, p) in pts.iter().enumerate() {
                if i > 0 {
                    s += (*p - pts[i - 1]).length();
                }
                at.push(s);
            }
            self.chains.push(Chain { pts, at, ring_end: self.ring_end });
        }
        self.cur.clear();
        self.ring_end = 0;
    }
}

/// Appends points up to `q` at most [`SAMPLE`] apart (the last point of `v` is the start).
fn densify_to(v: &mut Vec<DVec2>, q: DVec2) {
    let p = *v.last().expect("a start point");
    let l = (q - p).length();
    if l < 1e-9 {
        return;
    }
    let n = (l / SAMPLE).ceil() as usize;
    for i in 1..=n {
        v.push(p + (q - p) * (i as f64 / n as f64));
    }
}

/// True when the segment `a`–`b` meets a ring of `area`.
fn crosses_area(area: &Area, a: DVec2, b: DVec2) -> bool {
    area.polys.iter().any(|p| crosses(p, a, b))
}

/// True when the open segment `a`–`b` crosses a ring of `poly`.
fn crosses(poly: &crate::geom::area::Polygon, a: DVec2, b: DVec2) -> bool {
    poly.rings().any(|r| (0..r.len()).any(|i| segments_intersect(a, b, r[i], r[(i + 1) % r.len()])))
}

fn ring_distance(ring: &[DVec2], p: DVec2) -> f64 {
    ring.iter().map(|q| (*q - p).length_squared()).fold(f64::INFINITY, f64::min)
}

fn nearest_index(it: impl Iterator<Item = f64>) -> usize {
    it.enumerate().min_by(|a, b| a.1.total_cmp(&b.1)).map_or(0, |(i, _)| i)
}

/// Point-in-area by even–odd crossings, with the edges bucketed in horizontal bands so that a
/// query reads only the edges of its band.
struct Inside {
    y0: f64,
    h: f64,
    bands: Vec<Vec<(DVec2, DVec2)>>,
}

impl Inside {
    fn new(area: &Area) -> Inside {
        let Some((lo, hi)) = area.bounds() else { return Inside { y0: 0.0, h: 1.0, bands: Vec::new() } };
        let n = ((area.vertex_count() / 8).clamp(1, 4096)) as f64;
        let h = ((hi.y - lo.y) / n).max(1e-3);
        let nb = ((hi.y - lo.y) / h).floor() as usize + 1;
        let mut bands = vec![Vec::new(); nb];
        for ring in area.rings() {
            for i in 0..ring.len() {
                let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
                if a.y == b.y {
                    continue;
                }
                let j0 = (((a.y.min(b.y) - lo.y) / h).floor().max(0.0) as usize).min(nb - 1);
                let j1 = (((a.y.max(b.y) - lo.y) / h).floor().max(0.0) as usize).min(nb - 1);
                for band in &mut bands[j0..=j1] {
                    band.push((a, b));
                }
            }
        }
        Inside { y0: lo.y, h, bands }
    }

    fn contains(&self, p: DVec2) -> bool {
        let f = (p.y - self.y0) / self.h;
        if f.is_nan() || f < 0.0 || f as usize >= self.bands.len() {
            return false;
        }
        let mut inside = false;
        for &(a, b) in &self.bands[f as usize] {
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if p.x < x {
                    inside = !inside;
                }
            }
        }
        inside
    }
}

/// What one level of a tool cuts given its prefix: chains and, per point, whether the disk
/// there meets material.
struct LevelCut<'a> {
    chains: Vec<(std::borrow::Cow<'a, Chain>, Vec<bool>)>,
    /// Cut every point (Algorithm 3's rest paths), not only where material is.
    cut_all: bool,
}

fn level_cut<'a>(prep: &Prepared, k: usize, lv: &'a Level, prefix: &[usize], mats: &[Area]) -> LevelCut<'a> {
    let tg = &prep.tools[k];
    let r = tg.spec.diameter / 2.0;
    let none = LevelCut { chains: Vec::new(), cut_all: false };
    let material = &mats[lv.zi];
    if material.is_empty() {
        return none;
    }
    // the disk at p meets material: p inside it, or within the radius of its boundary
    let inside = Inside::new(material);
    let rm = r + NEED_MARGIN;
    let edges = crate::geom::index::EdgeIndex::from_area(material, rm.max(1.0));
    let meets = |p: DVec2| inside.contains(p) || edges.distance(p, rm) < rm;
    match prep.opts.decomposition {
        _ if prefix.is_empty() || prep.opts.decomposition == Decomposition::Trim => {
            let chains = lv
                .chains
                .iter()
                .filter_map(|c| {
                    let need: Vec<bool> = c.pts.iter().map(|&p| meets(p)).collect();
                    need.iter().any(|&b| b).then_some((std::borrow::Cow::Borrowed(c), need))
                })
                .collect();
            LevelCut { chains, cut_all: false }
        }
        _ => {
            let reach = material.offset(rm, REGION_TOL);
            let region = lv.centres.intersection(&reach).without_slivers(SLIVER);
            if region.is_empty() {
                return none;
            }
            let chains = chains_of(&region, tg.spec.width_of_cut.min(tg.spec.diameter / 2.0))
                .into_iter()
                .map(|c| {
                    let need: Vec<bool> = c.pts.iter().map(|&p| meets(p)).collect();
                    (std::borrow::Cow::Owned(c), need)
                })
                .collect();
            LevelCut { chains, cut_all: true }
        }
    }
}

/// The program of tool `k` after the tools `prefix`, its run, and the length of its path
/// whose disk meets material.
fn run_tool(prep: &Prepared, k: usize, prefix: &[usize], mats: &[Area]) -> (Toolpath, ToolRun, f64) {
    let tg = &prep.tools[k];
    let spec = &tg.spec;
    let t0 = Instant::now();
    let cuts: Vec<LevelCut> = tg.levels.par_iter().map(|lv| level_cut(prep, k, lv, prefix, mats)).collect();
    let t_cut = t0.elapsed().as_secs_f64();
    let tool = Tool { diameter: spec.diameter, number: tg.number, flutes: spec.teeth };
    // the pieces (one chain of one level each), cut in an order that keeps the tool in one
    // place: the nearest piece whose material above is gone (every piece of a level above
    // whose box, grown by the diameter, meets its box), so that a corner or a pocket is cut
    // level after level before the tool travels to the next
    let mut pieces: Vec<Piece> = Vec::new();
    for (li, cut) in cuts.iter().enumerate() {
        for (chain, need) in &cut.chains {
            let first = need.iter().position(|&b| b).unwrap_or(0);
            let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            for p in &chain.pts {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
            let g = DVec2::splat(spec.diameter / 2.0 + NEED_MARGIN);
            pieces.push(Piece {
                li,
                chain,
                need,
                cut_all: cut.cut_all,
                lo: lo - g,
                hi: hi + g,
                start: chain.pts[first.saturating_sub(1)],
            });
        }
    }
    let d = spec.diameter;
    let deps: Vec<Vec<usize>> = pieces
        .iter()
        .map(|pj| {
            pieces
                .iter()
                .enumerate()
                .filter(|(_, pi)| pi.li < pj.li && boxes_meet(pi.lo, pi.hi, pj.lo, pj.hi, d))
                .map(|(i, _)| i)
                .collect()
        })
        .collect();
    let start = pieces.first().map_or(DVec2::ZERO, |p| p.start);
    let mut tp = Toolpath::new(tool, DVec3::new(start.x, start.y, prep.clear_z), prep.clear_z);
    let mut e = Emitter {
        tp: &mut tp,
        prep,
        feed: spec.feed_mm_min(),
        need_mm: 0.0,
        pieces: &pieces,
        done: vec![false; pieces.len()],
    };
    let mut pos = start;
    let mut last_level = usize::MAX;
    for _ in 0..pieces.len() {
        let next = (0..pieces.len())
            .filter(|&j| !e.done[j] && deps[j].iter().all(|&i| e.done[i]))
            .min_by(|&a, &b| {
                (pieces[a].start - pos)
                    .length_squared()
                    .total_cmp(&(pieces[b].start - pos).length_squared())
                    .then(a.cmp(&b))
            })
            .expect("the levels above a piece come first");
        let pc = &pieces[next];
        let lv = &tg.levels[pc.li];
        if pc.li != last_level {
            e.tp.note(format!("level z {:.3}", lv.z));
            last_level = pc.li;
        }
        e.chain(pc.chain, pc.need, lv, pc.li, pc.cut_all);
        e.done[next] = true;
        pos = e.tp.end().truncate();
    }
    let need_mm = e.need_mm;
    let end = tp.end();
    if end.z < prep.clear_z - 1e-9 {
        tp.rapid(DVec3::new(end.x, end.y, prep.clear_z));
    }
    let t = tp.totals(prep.machine.rapid_feed_mm_min);
    log::debug!(
        "toolseq: {} after {:?}: levels {t_cut:.3} s, program {:.3} s, {} moves",
        tg.spec.id,
        prefix.iter().map(|&i| prep.tools[i].spec.id.as_str()).collect::<Vec<_>>(),
        t0.elapsed().as_secs_f64() - t_cut,
        tp.moves.len()
    );
    let run = ToolRun {
        cut_mm: t.cut_length_mm,
        air_mm: t.rapid_length_mm,
        feed_mm_min: spec.feed_mm_min(),
        price: spec.price,
        life_min: spec.life_min,
    };
    (tp, run, need_mm)
}

/// One chain of one level, as the program cuts it.
struct Piece<'a> {
    li: usize,
    chain: &'a Chain,
    need: &'a [bool],
    cut_all: bool,
    /// Box of the chain grown by the radius.
    lo: DVec2,
    hi: DVec2,
    /// Where the tool goes down first (about).
    start: DVec2,
}

/// True when the bounding boxes of two areas overlap.
fn boxes_overlap(a: &Area, b: &Area) -> bool {
    match (a.bounds(), b.bounds()) {
        (Some((alo, ahi)), Some((blo, bhi))) => boxes_meet(alo, ahi, blo, bhi, 0.0),
        _ => false,
    }
}

/// True when two boxes come within `d` of each other.
fn boxes_meet(alo: DVec2, ahi: DVec2, blo: DVec2, bhi: DVec2, d: f64) -> bool {
    alo.x <= bhi.x + d && blo.x <= ahi.x + d && alo.y <= bhi.y + d && blo.y <= ahi.y + d
}

struct Emitter<'a> {
    tp: &'a mut Toolpath,
    prep: &'a Prepared,
    feed: f64,
    need_mm: f64,
    pieces: &'a [Piece<'a>],
    done: Vec<bool>,
}

impl Emitter<'_> {
    /// Cuts the needed pieces of one chain.
    fn chain(&mut self, c: &Chain, need: &[bool], lv: &Level, li: usize, cut_all: bool) {
        let n = c.pts.len();
        let z = lv.z;
        for i in 1..n {
            if need[i - 1] && need[i] {
                self.need_mm += c.at[i] - c.at[i - 1];
            }
        }
        // runs of needed points, each grown by one point (in air) at both ends
        let mut groups: Vec<(usize, usize)> = Vec::new();
        if cut_all {
            groups.push((0, n - 1));
        } else {
            let mut i = 0;
            while i < n {
                if !need[i] {
                    i += 1;
                    continue;
                }
                let a = i.saturating_sub(1);
                while i < n && need[i] {
                    i += 1;
                }
                let b = i.min(n - 1);
                // feed on through the air when that is quicker than a retract and a rapid
                if let Some(last) = groups.last_mut() {
                    let gap = c.at[a] - c.at[last.1];
                    let up = 2.0 * (lv.above + APPROACH - z) + (c.pts[a] - c.pts[last.1]).length();
                    if gap / self.feed <= up / self.prep.machine.rapid_feed_mm_min + APPROACH / self.feed {
                        last.1 = b;
                        continue;
                    }
                }
                groups.push((a, b));
            }
        }
        // a chain that starts in material and has air on its first loop goes down in the air
        // there, cuts the loop round to where it went down, and goes back along it to its
        // start (cleared on the way round) to carry on: no ramp
        let re = c.ring_end;
        let rotate = if need[0] && re > 0 { (1..re).find(|&i| !need[i]) } else { None };
        if rotate.is_some() {
            let b0 = groups.iter().filter(|g| g.0 <= re).map(|g| g.1).max().unwrap_or(re).max(re);
            groups.retain(|g| g.0 > re);
            groups.insert(0, (0, b0));
        }
        let tan = self.prep.opts.ramp_deg.to_radians().tan();
        for (a, b) in groups {
            let p = c.pts[a];
            let mut a = a;
            if let (0, Some(i0)) = (a, rotate) {
                let q = c.pts[i0];
                self.go_to(q, lv, li);
                self.tp.rapid(DVec3::new(q.x, q.y, z + APPROACH));
                self.tp.line(MoveKind::Descend, DVec3::new(q.x, q.y, z), self.feed);
                self.lines(&c.pts[i0..=re], MoveKind::Cut, z);
                self.lines(&c.pts[..=i0], MoveKind::Cut, z);
                let back: Vec<DVec2> = c.pts[..=i0].iter().rev().copied().collect();
                self.lines(&back, MoveKind::Link, z);
                a = re;
            } else if a == 0 && need[0] {
                self.go_to(p, lv, li);
                // a ramp down along the first loop, from the level above
                let z0 = lv.above.min(self.prep.top) + RAMP_CLEAR;
                self.tp.rapid(DVec3::new(p.x, p.y, z0 + APPROACH));
                self.tp.line(MoveKind::Descend, DVec3::new(p.x, p.y, z0), self.feed);
                let ring_len = c.at[c.ring_end];
                if ring_len < 1e-6 {
                    self.tp.line(MoveKind::Plunge, DVec3::new(p.x, p.y, z), self.feed);
                } else {
                    let dz = z0 - z;
                    let turns = (dz / tan / ring_len).ceil().max(1.0);
                    let total = turns * ring_len;
                    for t in 0..turns as usize {
                        for i in 1..=c.ring_end {
                            let s = t as f64 * ring_len + c.at[i];
                            let q = c.pts[i];
                            self.tp.line(MoveKind::Entry, DVec3::new(q.x, q.y, z0 - dz * s / total), self.feed);
                        }
                    }
                }
            } else {
                self.go_to(p, lv, li);
                self.tp.rapid(DVec3::new(p.x, p.y, z + APPROACH));
                self.tp.line(MoveKind::Descend, DVec3::new(p.x, p.y, z), self.feed);
            }
            // the cut: straight runs merged (the points are a sampling of the loops' edges)
            let mut run: Vec<DVec2> = vec![c.pts[a]];
            let mut kind = MoveKind::Cut;
            for i in a + 1..=b {
                let k = if cut_all || need[i - 1] || need[i] { MoveKind::Cut } else { MoveKind::Link };
                if k != kind && run.len() > 1 {
                    self.lines(&run, kind, z);
                    run = vec![*run.last().expect("a point")];
                }
                kind = k;
                run.push(c.pts[i]);
            }
            self.lines(&run, kind, z);
        }
    }

    fn lines(&mut self, run: &[DVec2], kind: MoveKind, z: f64) {
        if run.len() < 2 {
            return;
        }
        for q in crate::geom::simplify::douglas_peucker(run, 1e-4).into_iter().skip(1) {
            self.tp.line(kind, DVec3::new(q.x, q.y, z), self.feed);
        }
    }

    /// Up and across to above `p`: just above the level above where the straight way stays
    /// over the centres of that level (all cleared down to it), else at the clearance plane.
    fn go_to(&mut self, p: DVec2, lv: &Level, li: usize) {
        let end = self.tp.end();
        let cz = self.prep.clear_z;
        if self.tp.moves.is_empty() && (end.truncate() - p).length() < 1e-9 {
            return;
        }
        let low = lv.above + APPROACH;
        let e = end.truncate();
        // (the level above is cut wherever the way passes: every piece of it whose box meets
        // the way's box grown by the radius is done)
        let (lo, hi) = (e.min(p), e.max(p));
        let r = self.tp.tool.radius() + NEED_MARGIN;
        let above_done = || {
            self.pieces
                .iter()
                .zip(&self.done)
                .all(|(pc, &done)| done || li == 0 || pc.li + 1 != li || !boxes_meet(pc.lo, pc.hi, lo, hi, r))
        };
        let h = match &lv.over {
            Some(o) if end.z <= lv.above + 1e-9 && low < cz && above_done() && !crosses_area(o, e, p) => low,
            _ => cz,
        };
        if end.z < h - 1e-9 {
            self.tp.rapid(DVec3::new(end.x, end.y, h));
        }
        let h = h.max(end.z);
        self.tp.rapid(DVec3::new(p.x, p.y, h));
    }
}
