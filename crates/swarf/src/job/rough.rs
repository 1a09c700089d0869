//! The main job: a [`Job`] in, a program, its G-code, a report and a picture out.

use crate::error::{Error, Result};
use crate::model::{Cutting, Job};
use crate::plan::{LayerGeom, LinkOptions, Pass};
use crate::post::{self, Header, Post};
use crate::report::{self, Report};
use crate::sim::{Replay, SimOptions};
use crate::strategy::{self, Context, Strategy};
use crate::toolpath::Toolpath;
use std::time::Instant;

/// Everything `rough` needs besides the job.
#[derive(Debug, Clone, PartialEq)]
pub struct RoughOptions {
    /// The clearing strategy and its options.
    pub strategy: Strategy,
    /// Milling direction, entries, links and the finishing contour.
    pub link: LinkOptions,
    /// Controller dialect.
    pub post: Post,
    /// Simulation settings (planning and the report).
    pub sim: SimOptions,
    /// Simulate the program for the report (engagement, gouges, rest).
    pub simulate: bool,
    /// Name of the input for the report and the header.
    pub input_name: String,
}

impl RoughOptions {
    /// The adaptive strategy, linked and simulated with the defaults of [`LinkOptions`] and
    /// [`SimOptions`], posted for LinuxCNC.
    pub const DEFAULT: RoughOptions = RoughOptions {
        strategy: Strategy::DEFAULT,
        link: LinkOptions::DEFAULT,
        post: Post::DEFAULT,
        sim: SimOptions::DEFAULT,
        simulate: true,
        input_name: String::new(),
    };

    /// The default options with another strategy.
    pub fn with_strategy(strategy: Strategy) -> RoughOptions {
        RoughOptions { strategy, ..RoughOptions::DEFAULT }
    }

    /// Checks every option: the strategy's, the links', the simulation's.
    pub fn validate(&self) -> Result<()> {
        self.strategy.validate()?;
        self.link.validate()?;
        self.sim.validate()
    }
}

impl Default for RoughOptions {
    fn default() -> Self {
        RoughOptions::DEFAULT
    }
}

/// What `rough` produces.
#[derive(Debug, Clone)]
pub struct RoughResult {
    /// The program.
    pub toolpath: Toolpath,
    /// Its G-code.
    pub gcode: String,
    /// Its figures.
    pub report: Report,
    /// The simulation, when it was run.
    pub replay: Option<Replay>,
}

/// Stages reported to the progress callback.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Computing the toolpath.
    Plan,
    /// Simulating it (where [`rough`] proves the program alongside its planning, the wait for
    /// the proof after the planning, from the share it had replayed by then).
    Simulate,
}

/// Computes the roughing program of `job`, posts it, and (optionally) simulates it for the
/// report. `progress` hears the stage and the share of it done.
///
/// ```
/// use swarf::{Overrides, RoughOptions, load_job, rough};
/// let case = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/cases/round_pocket.json");
/// let job = load_job(case.as_ref(), &Overrides::DEFAULT)?;
/// let out = rough(&job, &RoughOptions::DEFAULT, &mut |_, _| {})?;
/// // proven on the simulator: no gouge, no rapid through material, nothing left
/// assert_eq!((out.report.gouges, out.report.rapid_collisions), (0, 0));
/// assert!(out.report.rest_fraction < 0.005);
/// assert!(out.report.engagement_deg.p99 <= job.cutting.width.engagement_deg() + 10.0);
/// # Ok::<(), swarf::Error>(())
/// ```
pub fn rough(job: &Job, opts: &RoughOptions, progress: &mut dyn FnMut(Stage, f64)) -> Result<RoughResult> {
    job.validate()?;
    opts.validate()?;
    let fitted = job
        .stock
        .bounds()
        .and_then(|(lo, hi)| opts.sim.fitted(job.cutting.tool.diameter, lo, hi))
        .map(|sim| RoughOptions { sim, ..opts.clone() });
    let opts = fitted.as_ref().unwrap_or(opts);
    let t0 = Instant::now();
    progress(Stage::Plan, 0.0);
    // the raster proof replays the program alongside its planning, piece by piece as the
    // linker makes it (the spiral's search proves its own program)
    let alongside = opts.simulate
        && opts.sim.engine == crate::sim::SimEngine::Raster
        && !matches!(opts.strategy, Strategy::Spiral(_));
    if !alongside {
        let planned = plan(job, opts)?.ok_or_else(nothing_to_cut)?;
        progress(Stage::Plan, 0.5);
        return rough_planned(job, opts, planned, t0, progress);
    }
    let (regions, geom) = geometry(job, opts)?;
    let proof_regions = regions.clone();
    let count = ProofCount::default();
    std::thread::scope(|s| {
        let (tx, rx) = std::sync::mpsc::channel();
        let proof = s.spawn(|| prove_alongside(job, &proof_regions, &opts.sim, rx, &count));
        let unstream = crate::plan::linker::stream_next_program(Some(tx.clone()));
        let planned = plan_on(job, opts, regions, &geom);
        drop(unstream);
        let planned = match planned {
            Ok(Some(p)) => p,
            // (the proof stops when every sender is gone)
            Ok(None) => return Err(nothing_to_cut()),
            Err(e) => return Err(e),
        };
        progress(Stage::Plan, 0.5);
        // (a proof that stopped early is made again after the planning)
        let _ = tx.send(crate::plan::linker::Streamed::End(planned.toolpath.clone()));
        drop(tx);
        rough_planned_with(job, opts, planned, t0, progress, Some(Alongside { proof, count: &count }))
    })
}

/// How far the proof alongside the planning has gone: the moves it has replayed, and the
/// program's (0 until it is planned).
#[derive(Debug, Default)]
struct ProofCount {
    replayed: std::sync::atomic::AtomicUsize,
    total: std::sync::atomic::AtomicUsize,
}

fn nothing_to_cut() -> Error {
    Error::job("strategy", "the strategy found nothing to cut")
}

/// The proof of a program made while it is planned: one replay on the raster model of `job`
/// (`RasterSim::replay_segments`) of the moves of each piece the linker sends as it plans
/// ([`crate::plan::linker::stream_next_program`]), then of the program's tail once it is
/// planned. Each piece is rounded to the post's step as the whole program is, so the replay is
/// the one [`crate::sim::simulate`] makes of the finished program. `None` where the pieces are
/// not the beginning of the finished program, or the model cannot be built: the program is
/// then proven after its planning.
fn prove_alongside(
    job: &Job,
    regions: &crate::model::Regions,
    sim: &SimOptions,
    rx: std::sync::mpsc::Receiver<crate::plan::linker::Streamed>,
    count: &ProofCount,
) -> Option<(Replay, crate::sim::Rest)> {
    use crate::plan::linker::Streamed;
    use crate::toolpath::Move;
    use std::sync::atomic::Ordering::Relaxed;
    let mut model = match crate::sim::RasterSim::new(job, regions, sim) {
        Ok(m) => m,
        Err(e) => {
            log::debug!("no proof alongside the planning: {e}");
            return None;
        }
    };
    // the moves as they come, each piece rounded as the whole program is (each move's ends
    // and arc centre from the rounded end before it); `received` the moves as planned
    let mut received = crate::plan::linker::Received::default();
    let mut ready: std::collections::VecDeque<(crate::geom::DVec3, Move)> = Default::default();
    let (mut ended, mut whole) = (false, false);
    let rounded = |start, moves: &[Move]| {
        let mut piece = Toolpath::new(job.cutting.tool.clone(), start, 0.0);
        piece.moves = moves.to_vec();
        piece.quantize(post::COORD_STEP, post::CENTER_STEP);
        piece.segments().map(|(from, m)| (from, *m)).collect::<Vec<_>>()
    };
    let moves = std::iter::from_fn(|| {
        loop {
            if let Some(s) = ready.pop_front() {
                count.replayed.fetch_add(1, Relaxed);
                return Some(s);
            }
            if ended {
                return None;
            }
            match rx.recv() {
                Ok(Streamed::Piece { start, moves }) => {
                    ready.extend(rounded(start, &moves));
                    received.piece(start, moves);
                }
                Ok(Streamed::End(tp)) => {
                    ended = true;
                    let Some((at, tail)) = received.tail(&tp) else {
                        log::debug!("the moves proven alongside the planning are not the program's beginning");
                        return None;
                    };
                    log::debug!("{} of {} moves proven alongside the planning", received.len(), tp.moves.len());
                    count.total.store(tp.moves.len(), Relaxed);
                    ready.extend(rounded(at, tail));
                    whole = true;
                }
                // (the planning failed)
                Err(_) => return None,
            }
        }
    });
    let mut carry = crate::sim::replay::Carry::default();
    let mut rp = model.replay_segments(moves, 0, &mut |_| {}, &mut carry);
    if !whole {
        return None;
    }
    rp.rest_cells = model.rest_cells();
    rp.res = model.grid.res;
    Some((rp, model.rest()))
}

/// The second half of [`rough`]: posts a program [`plan`] made of `job` with `opts` and proves
/// it; `started` is when the planning started (the report's `compute_s` counts from it). For a
/// program looked at as planned (before its coordinates are rounded to the post's micrometre)
/// and then written and proven as `rough` would.
pub fn rough_planned(
    job: &Job,
    opts: &RoughOptions,
    planned: Planned,
    started: Instant,
    progress: &mut dyn FnMut(Stage, f64),
) -> Result<RoughResult> {
    rough_planned_with(job, opts, planned, started, progress, None)
}

/// The proof of a program made alongside its planning ([`prove_alongside`]) and how far it has
/// gone.
struct Alongside<'s> {
    proof: std::thread::ScopedJoinHandle<'s, Option<(Replay, crate::sim::Rest)>>,
    count: &'s ProofCount,
}

impl Alongside<'_> {
    /// Waits for the proof, telling `progress` the share of the program's moves it has
    /// replayed (from where it stood when the planning ended, each percent once).
    fn wait(self, progress: &mut dyn FnMut(Stage, f64)) -> Option<(Replay, crate::sim::Rest)> {
        use std::sync::atomic::Ordering::Relaxed;
        let share = || {
            let total = self.count.total.load(Relaxed);
            if total == 0 { 0.0 } else { (self.count.replayed.load(Relaxed) as f64 / total as f64).min(1.0) }
        };
        progress(Stage::Simulate, 0.0);
        let mut told = share();
        progress(Stage::Simulate, told);
        while !self.proof.is_finished() {
            std::thread::sleep(std::time::Duration::from_millis(2));
            let now = share();
            if now >= told + 0.01 {
                told = now;
                progress(Stage::Simulate, now);
            }
        }
        let made = self.proof.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
        // (else the program is proven again, with a progress of its own)
        if made.is_some() {
            progress(Stage::Simulate, 1.0);
        }
        made
    }
}

/// [`rough_planned`], with the proof made alongside the planning when there is one: its
/// proving time is then the wait for it after the planning.
fn rough_planned_with(
    job: &Job,
    opts: &RoughOptions,
    planned: Planned,
    started: Instant,
    progress: &mut dyn FnMut(Stage, f64),
    alongside: Option<Alongside<'_>>,
) -> Result<RoughResult> {
    let Planned { mut toolpath, levels: zs, regions, proof, proof_s } = planned;
    toolpath.quantize(post::COORD_STEP, post::CENTER_STEP);
    // (a proof the strategy made while planning is proving time, not planning time)
    let proof_s = if proof.is_some() && opts.simulate { proof_s } else { 0.0 };
    let compute_s = (started.elapsed().as_secs_f64() - proof_s).max(0.0);
    log::info!("{}: {} planned in {compute_s:.2} s, {} moves", job.name, opts.strategy.name(), toolpath.moves.len());
    progress(Stage::Plan, 1.0);
    let about = About { name: &job.name, what: "", cutting: &job.cutting, floor: job.floor, depth: job.level_depth() };
    let mut done = finish(toolpath, zs, &about, opts, compute_s, progress, |tp, progress| match proof {
        // (the strategy simulated this very program with these settings while planning it)
        Some(p) => Ok(p),
        None => match alongside.and_then(|a| a.wait(progress)) {
            Some(p) => Ok(p),
            None => crate::sim::simulate(job, &regions, &opts.sim, tp, &mut |f| progress(Stage::Simulate, f)),
        },
    })?;
    done.report.simulate_s += proof_s;
    done.report.total_s += proof_s;
    Ok(done)
}

/// Proves a program made elsewhere (read from G-code by [`crate::io::gcode`], or by another
/// system) on `job` as [`rough`] proves its own: replayed on the simulator `opts.sim` names
/// (its cell size fitted to the program's tool and the stock as [`rough`] fits it), with the
/// report's figures (engagement, gouges, rapid collisions, rest, machining time at the job's
/// rapid rate). The program's tool is its own ([`Toolpath::tool`]); the report's strategy is
/// `program`.
///
/// ```
/// use swarf::{Overrides, RoughOptions, load_job, rough, io::gcode};
/// let case = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/cases/round_pocket.json");
/// let job = load_job(case.as_ref(), &Overrides::DEFAULT)?;
/// let own = rough(&job, &RoughOptions::DEFAULT, &mut |_, _| {})?;
/// // the program read back from its G-code gives the same figures
/// let read = gcode::read(&own.gcode, "p.ngc".as_ref(), &gcode::ReadOptions { tool: job.cutting.tool.clone(), clearance_z: None })?;
/// let rep = swarf::job::rough::prove(&job, &read.toolpath, &RoughOptions::DEFAULT)?;
/// assert_eq!(rep.gouges, 0);
/// assert!((rep.time_min - own.report.time_min).abs() < 1e-3 * own.report.time_min);
/// # Ok::<(), swarf::Error>(())
/// ```
pub fn prove(job: &Job, tp: &crate::toolpath::Toolpath, opts: &RoughOptions) -> Result<Report> {
    let mut job = job.clone();
    job.cutting.tool = tp.tool.clone();
    job.validate()?;
    opts.validate()?;
    let t0 = Instant::now();
    let d = job.cutting.tool.diameter;
    let sim = opts.sim.fitted_to(d, job.stock.bounds());
    let regions = job.regions(job.radius(), 0.0)?;
    let (rp, rest) = crate::sim::simulate(&job, &regions, &sim, tp, &mut |_| {})?;
    let c = &job.cutting;
    let mut rep = Report {
        swarf_version: env!("CARGO_PKG_VERSION").to_string(),
        input: opts.input_name.clone(),
        strategy: "program".into(),
        tool_diameter_mm: d,
        stepover: c.width.stepover(),
        engagement_ref_deg: c.width.engagement_deg(),
        sim_res_mm: sim.res_for(d),
        ..Default::default()
    };
    report::fill(&mut rep, tp, &rp, &rest, c.rapid_rate);
    report::fill_efficiency(&mut rep, c.stepover_mm() * job.level_depth() * c.feed);
    rep.simulate_s = t0.elapsed().as_secs_f64();
    rep.total_s = rep.simulate_s;
    Ok(rep)
}

/// What the program's header and report say about the job.
pub(crate) struct About<'a> {
    /// The job's name (when the options name no input).
    pub name: &'a str,
    /// The kind of job, before the strategy in the header (`""` or `"z-level roughing, "`).
    pub what: &'a str,
    /// The tool, the width of cut and the rates.
    pub cutting: &'a Cutting,
    /// The job's floor, mm (the last level when there is none).
    pub floor: f64,
    /// The depth of cut of a level, mm (for the reference removal rate).
    pub depth: f64,
}

/// Posts a planned program and fills its report: from `simulate` (the replay and the rest it
/// finds) when the options ask for the simulation, from the program's totals otherwise.
pub(crate) fn finish(
    toolpath: Toolpath,
    zs: Vec<f64>,
    about: &About,
    opts: &RoughOptions,
    compute_s: f64,
    progress: &mut dyn FnMut(Stage, f64),
    simulate: impl FnOnce(&Toolpath, &mut dyn FnMut(Stage, f64)) -> Result<(Replay, crate::sim::Rest)>,
) -> Result<RoughResult> {
    let t0 = Instant::now();
    let c = about.cutting;
    let mut header = Header { spindle_rpm: c.spindle_rpm, ..Default::default() };
    header.lines.push(format!(
        "job {} - {}strategy {}",
        if opts.input_name.is_empty() { about.name } else { &opts.input_name },
        about.what,
        opts.strategy.name()
    ));
    header.lines.push(format!(
        "stepover {:.1} pct = {:.1} deg straight-cut engagement, {} levels to z {:.3}, feed {:.0} mm/min",
        c.width.stepover() * 100.0,
        c.width.engagement_deg(),
        zs.len(),
        zs.last().copied().unwrap_or(about.floor),
        c.feed
    ));
    header.lines.push(format!("milling {}", if opts.link.climb { "climb" } else { "conventional" }));
    let gcode = post::write(&toolpath, opts.post, &header)?;
    let mut rep = Report {
        swarf_version: env!("CARGO_PKG_VERSION").to_string(),
        input: opts.input_name.clone(),
        strategy: opts.strategy.name().to_string(),
        post: format!("{:?}", opts.post).to_lowercase(),
        tool_diameter_mm: c.tool.diameter,
        stepover: c.width.stepover(),
        engagement_ref_deg: c.width.engagement_deg(),
        levels: zs,
        compute_s,
        gcode_lines: gcode.lines().count(),
        sim_res_mm: opts.sim.res_for(c.tool.diameter),
        ..Default::default()
    };
    let mut replay = None;
    if opts.simulate {
        let t1 = Instant::now();
        let (rp, rest) = simulate(&toolpath, progress)?;
        rep.simulate_s = t1.elapsed().as_secs_f64();
        log::info!("simulated in {:.2} s", rep.simulate_s);
        report::fill(&mut rep, &toolpath, &rp, &rest, c.rapid_rate);
        report::fill_efficiency(&mut rep, c.stepover_mm() * about.depth * c.feed);
        replay = Some(rp);
    } else {
        report::fill_program(&mut rep, &toolpath, c.rapid_rate);
    }
    rep.total_s = compute_s + t0.elapsed().as_secs_f64();
    Ok(RoughResult { toolpath, gcode, report: rep, replay })
}

/// A planned 2.5D program.
#[derive(Debug, Clone)]
pub struct Planned {
    /// The program.
    pub toolpath: Toolpath,
    /// Its levels, top down.
    pub levels: Vec<f64>,
    /// The regions of the job it was planned on.
    pub regions: crate::model::Regions,
    /// The simulation of the program as it will be written (quantised to the post's
    /// micrometre), with the options' simulation settings, when the strategy made one while
    /// planning (the spiral's search simulates its choice); [`rough`] then takes it as the
    /// program's proof instead of simulating it again.
    pub proof: Option<(Replay, crate::sim::Rest)>,
    /// Seconds the strategy spent making `proof` (the report counts them as proving).
    pub proof_s: f64,
}

/// Plans the program of a 2.5D job (no posting, no simulation), or `None` when a strategy that
/// works from passes finds none.
pub fn plan(job: &Job, opts: &RoughOptions) -> Result<Option<Planned>> {
    let (regions, geom) = geometry(job, opts)?;
    plan_on(job, opts, regions, &geom)
}

/// The regions and the level geometry [`plan`] plans `job` on (they depend on the job, the
/// strategy's wall margin and the link options only, not on the material).
pub(crate) fn geometry(job: &Job, opts: &RoughOptions) -> Result<(crate::model::Regions, LayerGeom)> {
    let t0 = Instant::now();
    let margin = opts.strategy.wall_margin(&opts.link);
    let regions = job.regions(job.radius(), margin)?;
    log::debug!("regions {:.3} s", t0.elapsed().as_secs_f64());
    let geom = LayerGeom::new(job, &regions, &opts.link, margin)?;
    log::debug!("layer geometry {:.3} s", t0.elapsed().as_secs_f64());
    Ok((regions, geom))
}

/// [`plan`] on the job's [`geometry`].
pub(crate) fn plan_on(
    job: &Job,
    opts: &RoughOptions,
    regions: crate::model::Regions,
    geom: &LayerGeom,
) -> Result<Option<Planned>> {
    let t0 = Instant::now();
    let margin = opts.strategy.wall_margin(&opts.link);
    let zs = job.levels();
    let finish: Vec<(f64, Vec<Pass>)> = if opts.link.finish {
        let fp = strategy::finish_passes(job, &regions, &opts.link, margin);
        zs.iter().map(|z| (*z, fp.clone())).collect()
    } else {
        Vec::new()
    };
    let cx = Context { job, regions: &regions, geom, link: &opts.link, sim: &opts.sim, zs: &zs, finish: &finish };
    let Some(program) = opts.strategy.plan(&cx)? else { return Ok(None) };
    log::debug!("planned in {:.3} s", t0.elapsed().as_secs_f64());
    Ok(Some(Planned {
        toolpath: program.toolpath,
        levels: zs,
        regions,
        proof: program.proof,
        proof_s: program.proof_s,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::linker::send_in_pieces;

    /// The proof alongside the planning, fed a planned program in pieces of 300 moves (from
    /// the program's start, as the linker sends them) and then the whole program: the replay
    /// and the rest of proving the finished program after its planning. Pieces that are not
    /// the program's beginning (one move off by half a millimetre): no proof, so the program is
    /// proven after its planning.
    #[test]
    fn the_proof_alongside_replays_the_pieces_as_the_whole_and_refuses_others() {
        let case = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/cases/square_pocket.json");
        let job = crate::io::load_job(case.as_ref(), &Default::default()).expect("the case");
        let opts = RoughOptions::DEFAULT;
        let planned = plan(&job, &opts).expect("planned").expect("a program");
        let tp = &planned.toolpath;
        assert!(tp.moves.len() > 1000, "{} moves", tp.moves.len());
        let fed = |off: f64| {
            let rx = send_in_pieces(tp, off);
            prove_alongside(&job, &planned.regions, &opts.sim, rx, &ProofCount::default())
        };
        let (along, rest) = fed(0.0).expect("the pieces are the program's beginning");
        let mut q = tp.clone();
        q.quantize(post::COORD_STEP, post::CENTER_STEP);
        let (after, rest_after) =
            crate::sim::simulate(&job, &planned.regions, &opts.sim, &q, &mut |_| {}).expect("proven");
        assert!(along.samples.len() > 10_000 && along.samples == after.samples);
        assert_eq!((along.removed_volume, &along.rest_cells), (after.removed_volume, &after.rest_cells));
        assert_eq!(rest, rest_after);
        assert!(fed(0.5).is_none(), "a piece off the program");
    }
}
