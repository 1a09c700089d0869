//! The main job: a [`Job`] in, a program, its G-code, a report and a picture out.

use crate::error::{Error, Result};
use crate::model::Job;
use crate::plan;
use crate::post::{self, Header, Post};
use crate::report::{self, Report};
use crate::sim::SimOptions;
use crate::sim::raster::Replay;
use crate::strategy::{self, LayerGeom, Params};
use crate::toolpath::Toolpath;
use std::time::Instant;

/// Everything `rough` needs besides the job.
#[derive(Debug, Clone)]
pub struct RoughOptions {
    /// Strategy and linking parameters.
    pub params: Params,
    /// Controller dialect.
    pub post: Post,
    /// Simulation settings (planning and the report).
    pub sim: SimOptions,
    /// Simulate the program for the report (engagement, gouges, rest).
    pub simulate: bool,
    /// Name of the input for the report and the header.
    pub input_name: String,
}

impl Default for RoughOptions {
    fn default() -> Self {
        Self {
            params: Params::default(),
            post: Post::LinuxCnc,
            sim: SimOptions::default(),
            simulate: true,
            input_name: String::new(),
        }
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
    /// Simulating it.
    Simulate,
}

/// Checks the parameters a user can set.
pub fn validate_params(p: &Params) -> Result<()> {
    if !(p.feed_boost >= 1.0 && p.feed_boost <= 3.0) {
        return Err(Error::param("--feed-boost", format!("{}: must be in [1, 3]", p.feed_boost)));
    }
    if !(p.overshoot_deg >= 0.0 && p.overshoot_deg <= 90.0) {
        return Err(Error::param("--overshoot", format!("{}°: must be in [0°, 90°]", p.overshoot_deg)));
    }
    if !(p.ramp_angle_deg > 0.0 && p.ramp_angle_deg <= 45.0) {
        return Err(Error::param("--ramp-angle", format!("{}°: must be in (0°, 45°]", p.ramp_angle_deg)));
    }
    if !(p.arc_tol > 0.0 && p.arc_tol <= 0.5) {
        return Err(Error::param("--arc-tolerance", format!("{} mm: must be in (0, 0.5]", p.arc_tol)));
    }
    if !(p.stock_to_leave.is_finite() && p.stock_to_leave >= 0.0) {
        return Err(Error::param("--stock-to-leave", "must be zero or positive"));
    }
    if !(p.clearance.is_finite() && p.clearance > 0.0) {
        return Err(Error::param("--clearance", "must be positive"));
    }
    if !p.zigzag_angle_deg.is_finite() {
        return Err(Error::param("--angle", "must be a number"));
    }
    Ok(())
}

/// Computes the roughing program of `job`, posts it, and (optionally) simulates it for the
/// report.
pub fn rough(job: &Job, opts: &RoughOptions, progress: &mut dyn FnMut(Stage, f64)) -> Result<RoughResult> {
    job.validate()?;
    validate_params(&opts.params)?;
    let t0 = Instant::now();
    progress(Stage::Plan, 0.0);
    let Planned { mut toolpath, levels: zs, regions } =
        plan(job, opts)?.ok_or_else(|| Error::param("strategy", "the strategy found nothing to cut"))?;
    progress(Stage::Plan, 0.5);
    toolpath.quantize(post::COORD_STEP, post::CENTER_STEP);
    let compute_s = t0.elapsed().as_secs_f64();
    progress(Stage::Plan, 1.0);
    let about = About {
        name: &job.name,
        what: "",
        tool_diameter: job.tool.diameter,
        width: job.width,
        floor: job.floor,
        feed: job.feed,
        spindle_rpm: job.spindle_rpm,
        rapid_rate: job.rapid_rate,
    };
    finish(toolpath, zs, &about, opts, compute_s, progress, |tp, progress| {
        crate::sim::simulate(job, &regions, &opts.sim, tp, &mut |f| progress(Stage::Simulate, f))
    })
}

/// What the program's header and report say about the job.
pub(crate) struct About<'a> {
    /// The job's name (when the options name no input).
    pub name: &'a str,
    /// The kind of job, before the strategy in the header (`""` or `"z-level roughing, "`).
    pub what: &'a str,
    /// Tool diameter, mm.
    pub tool_diameter: f64,
    /// Width of cut.
    pub width: crate::model::Width,
    /// The job's floor, mm (the last level when there is none).
    pub floor: f64,
    /// Cutting feed, mm/min.
    pub feed: f64,
    /// Spindle speed, rpm.
    pub spindle_rpm: f64,
    /// Rapid rate for the time estimate, mm/min.
    pub rapid_rate: f64,
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
    simulate: impl FnOnce(&Toolpath, &mut dyn FnMut(Stage, f64)) -> Result<(Replay, crate::sim::raster::Rest)>,
) -> Result<RoughResult> {
    let mut header = Header { spindle_rpm: about.spindle_rpm, ..Default::default() };
    header.lines.push(format!(
        "job {} - {}strategy {}",
        if opts.input_name.is_empty() { about.name } else { &opts.input_name },
        about.what,
        opts.params.strategy.name()
    ));
    header.lines.push(format!(
        "stepover {:.1} pct = {:.1} deg straight-cut engagement, {} levels to z {:.3}, feed {:.0} mm/min",
        about.width.stepover() * 100.0,
        about.width.engagement_deg(),
        zs.len(),
        zs.last().copied().unwrap_or(about.floor),
        about.feed
    ));
    header.lines.push(format!("milling {}", if opts.params.climb { "climb" } else { "conventional" }));
    let gcode = post::write(&toolpath, opts.post, &header);
    let mut rep = Report {
        swarf_version: env!("CARGO_PKG_VERSION").to_string(),
        input: opts.input_name.clone(),
        strategy: opts.params.strategy.name().to_string(),
        post: format!("{:?}", opts.post).to_lowercase(),
        tool_diameter_mm: about.tool_diameter,
        stepover: about.width.stepover(),
        engagement_ref_deg: about.width.engagement_deg(),
        levels: zs,
        compute_s,
        gcode_lines: gcode.lines().count(),
        sim_res_mm: opts.sim.res_for(about.tool_diameter),
        ..Default::default()
    };
    let mut replay = None;
    if opts.simulate {
        let t1 = Instant::now();
        let (rp, rest) = simulate(&toolpath, progress)?;
        rep.simulate_s = t1.elapsed().as_secs_f64();
        report::fill(&mut rep, &toolpath, &rp, &rest, about.rapid_rate);
        replay = Some(rp);
    } else {
        let t = toolpath.totals(about.rapid_rate);
        rep.cut_length_mm = t.cut_length_mm;
        rep.rapid_length_mm = t.rapid_length_mm;
        rep.time_min = t.time_min;
        rep.entries = t.entries;
        rep.plunges = t.plunges;
    }
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
}

/// Plans the program of a 2.5D job (no posting, no simulation), or `None` when a strategy that
/// works from passes finds none.
pub fn plan(job: &Job, opts: &RoughOptions) -> Result<Option<Planned>> {
    let t0 = Instant::now();
    let debug = std::env::var("SWARF_DEBUG").is_ok();
    let regions = job.regions(job.radius(), strategy::wall_margin(&opts.params))?;
    if debug {
        eprintln!("regions {:.3} s", t0.elapsed().as_secs_f64());
    }
    let geom = LayerGeom::new(job, &regions, &opts.params)?;
    if debug {
        eprintln!("layer geometry {:.3} s", t0.elapsed().as_secs_f64());
    }
    let passes = strategy::passes(job, &geom, &opts.params)?;
    if debug {
        eprintln!("passes {:.3} s ({} passes)", t0.elapsed().as_secs_f64(), passes.len());
    }
    if passes.is_empty()
        && !matches!(
            opts.params.strategy,
            strategy::StrategyKind::Adaptive | strategy::StrategyKind::Medial | strategy::StrategyKind::Spiral
        )
    {
        return Ok(None);
    }
    let zs = job.levels();
    let levels: Vec<(f64, Vec<strategy::Pass>)> = zs.iter().map(|z| (*z, passes.clone())).collect();
    let finish: Vec<(f64, Vec<strategy::Pass>)> = if opts.params.finish {
        let fp = strategy::finish_passes(job, &regions, &opts.params);
        zs.iter().map(|z| (*z, fp.clone())).collect()
    } else {
        Vec::new()
    };
    let toolpath = if opts.params.strategy == strategy::StrategyKind::Adaptive {
        plan::adaptive::link_adaptive(job, &regions, &geom, &opts.params, &zs, &finish, &opts.sim)?
    } else if opts.params.strategy == strategy::StrategyKind::Medial {
        plan::medial::link_medial(job, &regions, &geom, &opts.params, &zs, &finish, &opts.sim)?
    } else if opts.params.strategy == strategy::StrategyKind::Spiral {
        let mut missed = None;
        let (choice, planned) = match (opts.params.spiral_zeta, opts.params.spiral_floor) {
            (None, None) => {
                let (best, trials, planned) = optimise_spiral_planned(job, &regions, &geom, opts, &zs)?;
                if debug {
                    for t in &trials {
                        eprintln!("spiral trial {t:?}");
                    }
                }
                if let Some(t) = trials.iter().find(|t| t.choice == best)
                    && let Some(sim) = t.sim.filter(|s| !s.feasible)
                {
                    missed = Some(format!(
                        "no spiral candidate was clean within the engagement bound in simulation; \
                         the nearest is kept: floor {:.2}, {} gouges, rest {:.2} %, p99 {:.0} deg \
                         against a bound of {:.0}",
                        best.floor,
                        sim.gouges,
                        100.0 * sim.rest,
                        sim.p99_deg,
                        spiral_bound(job)
                    ));
                }
                (best, planned)
            }
            (zeta, floor) => (
                plan::spiral::SpiralChoice {
                    zeta,
                    start: opts.params.spiral_start,
                    floor: floor.unwrap_or(plan::spiral::ENGAGEMENT_FLOOR),
                },
                None,
            ),
        };
        // the optimiser's program of the choice is the one wanted, unless finishing passes
        // follow it
        let mut tp = match planned {
            Some(tp) if finish.is_empty() => tp,
            _ => plan::spiral::link_spiral(job, &regions, &geom, &opts.params, &zs, &finish, &opts.sim, &choice)?,
        };
        if let Some(text) = missed {
            tp.notes.insert(0, crate::toolpath::Note { at: 0, text });
        }
        tp
    } else {
        plan::link(job, &regions, &opts.params, &levels, &finish, &opts.sim)?
    };
    Ok(Some(Planned { toolpath, levels: zs, regions }))
}

/// The built-in example job (a pocket with two islands).
pub fn example_job() -> Job {
    let text = include_str!("../examples_data/demo_pocket.json");
    match crate::io::case::parse_case(std::path::Path::new("demo_pocket.json"), text.as_bytes()) {
        Ok(j) => j,
        Err(e) => unreachable!("the built-in example is valid: {e}"),
    }
}

/// The loop of paper 4 §4 (Figs. 8–9): chooses ζ (per level, through the floor of the gaps
/// where turns are tight) and, with `opts.params.spiral_optimise`, the start point of a spiral
/// to minimise machining time subject to full clearing (rest ≤ 0.5 % of the reachable area, no
/// gouge) and the engagement bound (p99 outside the entry ≤ the reference + 10°), as swarf's
/// simulator (`opts.sim`) judges them.
///
/// Every candidate of [`plan::spiral::candidates`] is planned (quick), and its time is read off
/// its program. Simulation (the slow part) is spent only where it can change the answer: the
/// candidates are simulated in order of time, fastest first, and the first feasible one is the
/// optimum. A damping (floor) that broke the engagement bound from one start is not simulated
/// from the others: the engagement depends on the damping far more than on the start. At most
/// [`MAX_SIMULATED`] are simulated; when none of those is feasible, the one that misses by
/// least is returned (fewest gouges, then least rest beyond the limit, then least engagement
/// beyond the bound), and [`plan`] says so in the program. Returns the choice and every
/// trial.
pub fn optimise_spiral(
    job: &Job,
    regions: &crate::model::Regions,
    geom: &LayerGeom,
    opts: &RoughOptions,
    zs: &[f64],
) -> Result<(plan::spiral::SpiralChoice, Vec<plan::spiral::Trial>)> {
    optimise_spiral_planned(job, regions, geom, opts, zs).map(|(choice, trials, _)| (choice, trials))
}

/// [`optimise_spiral`], with the program of the choice as planned (without finishing passes).
fn optimise_spiral_planned(
    job: &Job,
    regions: &crate::model::Regions,
    geom: &LayerGeom,
    opts: &RoughOptions,
    zs: &[f64],
) -> Result<(plan::spiral::SpiralChoice, Vec<plan::spiral::Trial>, Option<Toolpath>)> {
    use plan::spiral::Trial;
    use rayon::prelude::*;
    let bound = spiral_bound(job);
    let p = &opts.params;
    let candidates = plan::spiral::candidates(regions, geom, p.spiral_start, p.spiral_optimise)?;
    let mut planned: Vec<Option<(Toolpath, Toolpath)>> =
        candidates.par_iter().map(|c| plan_spiral_trial(job, regions, geom, opts, zs, c)).collect();
    let mut trials: Vec<Trial> = candidates
        .iter()
        .zip(&planned)
        .map(|(c, tp)| Trial {
            choice: *c,
            time_min: tp.as_ref().map(|(_, written)| written.totals(job.rapid_rate).time_min),
            sim: None,
        })
        .collect();
    let mut order: Vec<usize> = (0..trials.len()).filter(|&i| trials[i].time_min.is_some()).collect();
    // (stable: equal times keep the candidates' order, so the result is deterministic)
    order.sort_by(|&a, &b| trials[a].time_min.unwrap_or(f64::MAX).total_cmp(&trials[b].time_min.unwrap_or(f64::MAX)));
    let mut best = None;
    let mut simulated = 0;
    for &i in &order {
        if simulated == MAX_SIMULATED {
            break;
        }
        let same_damping =
            |t: &Trial| t.choice.zeta == trials[i].choice.zeta && t.choice.floor == trials[i].choice.floor;
        if trials.iter().any(|t| same_damping(t) && t.sim.is_some_and(|s| s.p99_deg > bound)) {
            continue;
        }
        let Some((_, tp)) = &planned[i] else { continue };
        simulated += 1;
        let sim = judge_spiral(job, regions, opts, tp)?;
        trials[i].sim = Some(sim);
        if sim.feasible {
            best = Some(i);
            break;
        }
    }
    let best = best
        .or_else(|| nearest_miss(&trials, bound))
        .ok_or_else(|| Error::param("--strategy spiral", "no spiral could be made from any start or ζ"))?;
    Ok((trials[best].choice, trials, planned.swap_remove(best).map(|(tp, _)| tp)))
}

/// Of the simulated trials, the one that missed by least: fewest gouges, then least rest
/// beyond [`REST_LIMIT`], then least p99 engagement beyond `bound` (rest within the limit is
/// not traded against engagement). The first of equals.
fn nearest_miss(trials: &[plan::spiral::Trial], bound: f64) -> Option<usize> {
    let miss =
        |i: usize| trials[i].sim.map(|s| (s.gouges, (s.rest - REST_LIMIT).max(0.0), (s.p99_deg - bound).max(0.0)));
    (0..trials.len())
        .filter_map(|i| miss(i).map(|m| (i, m)))
        .min_by(|(_, (ga, ra, ea)), (_, (gb, rb, eb))| ga.cmp(gb).then(ra.total_cmp(rb)).then(ea.total_cmp(eb)))
        .map(|(i, _)| i)
}

/// [`optimise_spiral`] on a whole job (its regions, layer geometry and levels as [`plan`]
/// makes them).
pub fn optimise_spiral_job(
    job: &Job,
    opts: &RoughOptions,
) -> Result<(plan::spiral::SpiralChoice, Vec<plan::spiral::Trial>)> {
    let regions = job.regions(job.radius(), strategy::wall_margin(&opts.params))?;
    let geom = LayerGeom::new(job, &regions, &opts.params)?;
    optimise_spiral(job, &regions, &geom, opts, &job.levels())
}

/// The most candidates [`optimise_spiral`] simulates.
pub const MAX_SIMULATED: usize = 8;

/// The most rest [`optimise_spiral`] accepts, as a share of the reachable area.
pub const REST_LIMIT: f64 = 0.005;

/// The most p99 engagement outside the entry [`optimise_spiral`] accepts: the job's reference
/// + 10°.
fn spiral_bound(job: &Job) -> f64 {
    job.width.engagement_deg() + 10.0
}

/// The program of one spiral candidate as planned and as it will be written (quantised), or
/// `None` where the spiral cannot be made.
fn plan_spiral_trial(
    job: &Job,
    regions: &crate::model::Regions,
    geom: &LayerGeom,
    opts: &RoughOptions,
    zs: &[f64],
    choice: &plan::spiral::SpiralChoice,
) -> Option<(Toolpath, Toolpath)> {
    let tp = plan::spiral::link_spiral(job, regions, geom, &opts.params, zs, &[], &opts.sim, choice).ok()?;
    let mut written = tp.clone();
    written.quantize(post::COORD_STEP, post::CENTER_STEP);
    Some((tp, written))
}

/// Simulates a spiral candidate and judges it by the optimiser's criteria.
fn judge_spiral(
    job: &Job,
    regions: &crate::model::Regions,
    opts: &RoughOptions,
    tp: &Toolpath,
) -> Result<plan::spiral::TrialSim> {
    let (rp, rest) = crate::sim::simulate(job, regions, &opts.sim, tp, &mut |_| {})?;
    let mut rep = Report::default();
    report::fill(&mut rep, tp, &rp, &rest, job.rapid_rate);
    let bound = spiral_bound(job);
    Ok(plan::spiral::TrialSim {
        gouges: rep.gouges,
        rest: rep.rest_fraction,
        p99_deg: rep.engagement_deg.p99,
        feasible: rep.rest_fraction <= REST_LIMIT && rep.gouges == 0 && rep.engagement_deg.p99 <= bound,
    })
}

/// What [`spiral_study`] measured of one job.
#[derive(Debug, Clone)]
pub struct SpiralStudy {
    /// The default of `rough`: the floor chosen from the maximum of f ([`optimise_spiral`]
    /// without other starts), and its trials.
    pub default: (plan::spiral::SpiralChoice, Vec<plan::spiral::Trial>),
    /// `--optimise`: the floor and the start chosen, and the trials.
    pub optimised: (plan::spiral::SpiralChoice, Vec<plan::spiral::Trial>),
    /// The baseline: the largest feasible constant ζ ([`best_fixed_zeta`]).
    pub fixed: Option<(f64, plan::spiral::Trial)>,
}

/// The comparison of the docs' table: the default spiral, the optimiser's choice with other
/// starts, and the best constant ζ, each simulated and judged by the optimiser's criteria.
/// Slow (minutes).
pub fn spiral_study(job: &Job, opts: &RoughOptions) -> Result<SpiralStudy> {
    let regions = job.regions(job.radius(), strategy::wall_margin(&opts.params))?;
    let geom = LayerGeom::new(job, &regions, &opts.params)?;
    let zs = job.levels();
    let mut o = opts.clone();
    o.params.spiral_optimise = false;
    let default = optimise_spiral(job, &regions, &geom, &o, &zs)?;
    o.params.spiral_optimise = true;
    let optimised = optimise_spiral(job, &regions, &geom, &o, &zs)?;
    let fixed = best_fixed_zeta(job, &regions, &geom, opts, &zs)?;
    Ok(SpiralStudy { default, optimised, fixed })
}

/// The baseline of the optimiser: the largest constant ζ whose spiral (from the maximum of f)
/// is feasible by the optimiser's criteria, found by simulation (doubling or halving from
/// ζ = 0.02 to a bracket, then five geometric bisections; feasibility is taken as monotone in
/// ζ, which a wider spiral breaks by leaving more rest or engaging more). Returns ζ and its
/// trial, or `None` when no ζ down to 1e-4 is feasible. Slow (each try is simulated, and a
/// small ζ makes a long program): for comparisons, not for planning.
pub fn best_fixed_zeta(
    job: &Job,
    regions: &crate::model::Regions,
    geom: &LayerGeom,
    opts: &RoughOptions,
    zs: &[f64],
) -> Result<Option<(f64, plan::spiral::Trial)>> {
    let try_z = |z: f64| -> Result<plan::spiral::Trial> {
        let choice = plan::spiral::SpiralChoice { zeta: Some(z), ..Default::default() };
        let tp = plan_spiral_trial(job, regions, geom, opts, zs, &choice).map(|(_, written)| written);
        let sim = match &tp {
            Some(tp) => Some(judge_spiral(job, regions, opts, tp)?),
            None => None,
        };
        Ok(plan::spiral::Trial { choice, time_min: tp.map(|tp| tp.totals(job.rapid_rate).time_min), sim })
    };
    let (mut lo, mut hi): (Option<(f64, plan::spiral::Trial)>, Option<f64>) = (None, None);
    let mut z = 0.02;
    while lo.is_none() || hi.is_none() {
        let t = try_z(z)?;
        if t.feasible() {
            lo = Some((z, t));
            if z >= 0.5 {
                return Ok(lo);
            }
            z *= 2.0;
        } else {
            hi = Some(z);
            if z < 1e-4 {
                return Ok(None);
            }
            z *= 0.5;
        }
    }
    for _ in 0..5 {
        let (Some((l, _)), Some(h)) = (&lo, hi) else { break };
        let m = (l * h).sqrt();
        let t = try_z(m)?;
        if t.feasible() { lo = Some((m, t)) } else { hi = Some(m) }
    }
    Ok(lo)
}

#[cfg(test)]
mod tests {
    use super::*;
    use plan::spiral::{SpiralChoice, Trial, TrialSim};

    fn trial(floor: f64, sim: Option<(usize, f64, f64)>) -> Trial {
        Trial {
            choice: SpiralChoice { zeta: None, start: None, floor },
            time_min: Some(1.0),
            sim: sim.map(|(gouges, rest, p99_deg)| TrialSim { gouges, rest, p99_deg, feasible: false }),
        }
    }

    #[test]
    fn the_nearest_miss_is_clean_first_then_within_the_bound() {
        // rests under the limit are equal: the least engagement wins, not the least rest
        let t = [
            trial(0.5, Some((0, 0.0020, 90.0))),
            trial(0.42, None),
            trial(0.35, Some((0, 0.0031, 75.0))),
            trial(0.28, Some((0, 0.0019, 80.0))),
        ];
        assert_eq!(nearest_miss(&t, 70.0), Some(2));
        // rest beyond the limit counts before engagement, gouges before both
        let t = [
            trial(0.5, Some((0, 0.0060, 60.0))),
            trial(0.35, Some((0, 0.0040, 99.0))),
            trial(0.22, Some((1, 0.0, 60.0))),
        ];
        assert_eq!(nearest_miss(&t, 70.0), Some(1));
        let t = [trial(0.5, Some((2, 0.0, 60.0))), trial(0.35, Some((1, 0.02, 99.0)))];
        assert_eq!(nearest_miss(&t, 70.0), Some(1));
        assert_eq!(nearest_miss(&[trial(0.5, None)], 70.0), None);
    }
}
