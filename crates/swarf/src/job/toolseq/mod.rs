//! The cost-optimal tool sequence for z-level roughing of a mesh part (paper 3, El-Midany et
//! al.): which tools of a database to rough with, biggest first, and one program per tool, each
//! replayed on the simulator.
//!
//! It follows the paper section by section: §2 eqs. 1–4 (a sequence is a set of the bigger tools
//! followed by the smallest, which sets what the job can reach; its cost is the machining time
//! at the machine's rate plus the tools' wear, [`crate::model::tooldb`]), §3 Algorithms 1–2
//! (each tool's contour-parallel loops at its own levels, and the area they clear), §4
//! Algorithms 3–4 (a later tool confined to what the earlier ones left: its own path trimmed,
//! [`Decomposition::Trim`], or a new path over the rest region, [`Decomposition::Regions`]) and
//! §6 Tables 1–3 (the paper's tool table and costed sequences). `docs/toolseq.md` walks through
//! them and through the exact search over the prefix tree of the tools.
//!
//! ```text
//!  tool database ─► per tool, once ──────► per tool and prefix ─────► cheapest sequence
//!                   levels, centres C,      material left, trimmed      │ its programs
//!                   loops (Alg. 1),         path, program, time and     ▼
//!                   accessible area A       cost (eqs. 2–4); bound     replay: each program on
//!                   (Alg. 2)  [paths]       [search]                   the stock the ones before
//!                                                                      it left  [replay]
//! ```
//!
//! **Proven on the simulator.** Every program of the cheapest sequence is replayed on one
//! material model of the job ([`crate::sim::heights`]: the stock box, the part's surface from
//! the mesh), each on the stock the programs before it left; [`Program::check`] holds what the
//! simulator found, under the names of `swarf rough`'s report: gouges, rapid collisions,
//! plunges and the rest material after it ([`ProgramCheck`]), and [`SeqPlan::rest`] the stock
//! after each program for pictures.
//!
//! **Its own paths, not the shared offset strategy and linker.** The search builds a program
//! for every tool after every set of tools that may come before it (194 for
//! `examples/3d/bowl_cavity.json` with paper 3's Table 1, 3.5 s in all), each trimmed to the
//! material the earlier tools left (Algorithm 4), so the tools' own loops and emitter stay
//! (`paths`). Measured on that job's best sequence (D50, D25, D20, D10: 36.6 min, no gouge,
//! rapid collision or plunge, 1738 mm³ rest), the same tools planned level by level with
//! [`crate::strategy::offset`] and the linker (`plan::linker`) on the simulated stock took 1.2–5.4
//! s a program (minutes for a search) and gave 35.2 min cutting whole levels (the D50 alone 3.2
//! min against 1.8) and 28.8 min confined to the earlier tools' rest but with a 1 mm rapid
//! collision, for 1725–1727 mm³ rest.

use crate::error::{Error, Result, Setting};
use crate::model::MeshJob;
use crate::model::tooldb::{Cost, ToolDb, ToolRun, ToolSpec};
use crate::sim::{SimEngine, SimOptions};
use crate::toolpath::Toolpath;
use paths::{prepare, run_tool};
use search::{Materials, Search};
use std::collections::HashMap;
use std::time::Instant;

mod paths;
pub mod posted;
mod replay;
mod search;

pub use paths::NEED_MARGIN;
pub use posted::{PostAbout, PostedPlan, PostedProgram, post_plan};
pub use replay::{ProgramCheck, RestMaps};

/// How a later tool is confined to what the earlier tools left (paper 3 §4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Decomposition {
    /// Algorithm 4: the tool's own path, trimmed to where it meets material.
    Trim,
    /// Algorithm 3: a new contour-parallel path over the rest region.
    Regions,
}

impl Decomposition {
    /// Both decompositions.
    pub const ALL: [Decomposition; 2] = [Decomposition::Trim, Decomposition::Regions];

    /// Its name (the command line's `--decomposition`, the Python keyword's value).
    pub const fn name(self) -> &'static str {
        match self {
            Decomposition::Trim => "trim",
            Decomposition::Regions => "regions",
        }
    }
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
    /// Replay the chosen programs on the simulator ([`Program::check`], [`SeqPlan::rest`]).
    pub simulate: bool,
    /// Simulation settings of the replay (the raster engine; the cell size, when it is not
    /// set, is the smallest tool's, [`SimOptions::res_for`]).
    pub sim: SimOptions,
}

impl SeqOptions {
    /// Algorithm 4 (trimmed paths), the bounded search, 3° ramps, a clearance plane 2 mm above
    /// the job, the programs replayed with the simulator's defaults.
    pub const DEFAULT: SeqOptions = SeqOptions {
        decomposition: Decomposition::Trim,
        prune: true,
        ramp_deg: 3.0,
        clearance: 2.0,
        simulate: true,
        sim: SimOptions::DEFAULT,
    };

    /// Checks the ramp angle (in (0°, 90°)), the clearance (zero or more) and the simulation
    /// settings (the raster engine: the distance fields model 2.5D jobs only).
    pub fn validate(&self) -> Result<()> {
        if !(self.ramp_deg.is_finite() && self.ramp_deg > 0.0 && self.ramp_deg < 90.0) {
            return Err(Error::setting(
                Setting::SeqRampAngle,
                format!("{}°: must be between 0° and 90°", self.ramp_deg),
            ));
        }
        if !(self.clearance.is_finite() && self.clearance >= 0.0 && self.clearance <= crate::limits::MAX_COORD_MM) {
            return Err(Error::setting(
                Setting::SeqClearance,
                format!("{} mm: must be zero or positive, at most {} mm", self.clearance, crate::limits::MAX_COORD_MM),
            ));
        }
        self.sim.validate()?;
        if self.simulate && self.sim.engine != SimEngine::Raster {
            return Err(Error::setting(
                Setting::SimEngine,
                "the distance-field simulator handles 2.5D jobs only; use the raster simulator",
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
    /// The path, as written: coordinates on the post's steps ([`crate::post::COORD_STEP`]).
    pub toolpath: Toolpath,
    /// Its lengths and feed (as the search costed it).
    pub run: ToolRun,
    /// What the simulator found replaying it after the programs before it (none when
    /// [`SeqOptions::simulate`] is off).
    pub check: Option<ProgramCheck>,
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
    /// The simulated stock after each program of the cheapest sequence (paper 3, Fig. 11);
    /// none when [`SeqOptions::simulate`] is off.
    pub rest: Option<RestMaps>,
    /// Seconds spent on the tools' own geometry (levels, shadows, regions, loops).
    pub prepare_s: f64,
    /// Seconds spent on the search and on writing the chosen programs.
    pub search_s: f64,
    /// Seconds spent replaying the chosen programs.
    pub simulate_s: f64,
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
/// let mut db = ToolDb::read(format!("{root}/examples/tools/table1.json").as_ref())?;
/// // three of paper 3's tools: D25, D20 and D10
/// db.tools.retain(|t| ["T4", "T5", "T8"].contains(&t.id.as_str()));
/// let plan = plan_tools(&job, &db, &SeqOptions::DEFAULT)?;
/// let best = plan.best();
/// // one program per tool of the cheapest sequence, biggest first
/// assert_eq!(plan.programs.len(), best.tools.len());
/// assert!(best.diameters.windows(2).all(|w| w[0] >= w[1]));
/// // each replayed on what the tools before it left: clean
/// for p in &plan.programs {
///     let c = p.check.as_ref().expect("replayed");
///     assert_eq!((c.gouges, c.rapid_collisions, c.plunges), (0, 0, 0));
/// }
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
    let mut programs: Vec<Program> = best
        .index
        .iter()
        .enumerate()
        .map(|(i, &k)| {
            let mats = search.mats.of(&prep, &best.index[..i]);
            let (mut toolpath, run, _) = run_tool(&prep, k, &best.index[..i], &mats);
            toolpath.quantize(crate::post::COORD_STEP, crate::post::CENTER_STEP);
            Program { spec: prep.tools[k].spec.clone(), number: prep.tools[k].number, toolpath, run, check: None }
        })
        .collect();
    let search_s = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let rest = if opts.simulate {
        Some(replay::replay(job, &mut programs, &opts.sim, db.machine.rapid_feed_mm_min)?)
    } else {
        None
    };
    let simulate_s = t2.elapsed().as_secs_f64();
    log::info!("{} programs replayed in {simulate_s:.2} s", programs.len());
    Ok(SeqPlan { sequences, candidates: 1 << last, evaluations, programs, rest, prepare_s, search_s, simulate_s })
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
