//! The spiral's search (paper 4 §4, Figs. 8–9): candidate dampings and start points planned
//! two at a time, those planned simulated fastest first, the first that clears the pocket
//! within the engagement bound kept, within a bound on the work; and the baseline of the docs'
//! table, the best constant ζ.

use super::spiral::{
    ENGAGEMENT_FLOOR, SpiralChoice, SpiralFields, SpiralOptions, Trial, TrialSim, candidates, link_spiral,
};
use super::{Clearing, Context, Program, Strategy};
use crate::error::{Error, Result, Setting};
use crate::model::{Job, Regions};
use crate::plan::{LayerGeom, LinkOptions};
use crate::post;
use crate::report::{self, Report};
use crate::sim::{Replay, Rest, SimOptions};
use crate::toolpath::Toolpath;

// (the spiral's options are in `spiral.rs`; what they do as a strategy is the search's)
impl Clearing for SpiralOptions {
    const NAME: &'static str = "spiral";

    fn validate(&self) -> Result<()> {
        if let Some(z) = self.zeta
            && !(z.is_finite() && z > 0.0 && z <= 1.0)
        {
            return Err(Error::setting(Setting::Zeta, format!("{z}: ζ must be in (0, 1]")));
        }
        if let Some(f) = self.floor
            && !(f.is_finite() && f > 0.0 && f <= 1.0)
        {
            return Err(Error::setting(Setting::SpiralFloor, format!("{f}: the floor must be in (0, 1]")));
        }
        if let Some(p) = self.start
            && !p.is_finite()
        {
            return Err(Error::setting(Setting::SpiralStart, format!("{p}: must be a point of finite numbers")));
        }
        if self.search_cells.is_nan() || self.search_cells <= 0.0 {
            return Err(Error::setting(Setting::SpiralSearch, format!("{}: must be positive", self.search_cells)));
        }
        self.adaptive.validate()
    }

    /// A spiral over a pocket with islands leaves the rest to adaptive passes.
    fn wall_slack(&self) -> f64 {
        self.adaptive.wall_slack()
    }

    fn plan(&self, cx: &Context) -> Result<Option<Program>> {
        plan_spiral(cx, self).map(Some)
    }
}

/// The spiral program of a level job: the choice of `optimise_spiral` unless the options
/// pin ζ or the floor; when no candidate was feasible, the program says so in a note at its start.
/// The search's simulation of its choice is the program's proof (it simulated the program as it
/// will be written, with the job's simulation settings).
pub(crate) fn plan_spiral(cx: &Context, opts: &SpiralOptions) -> Result<Program> {
    let mut missed = None;
    let (choice, planned) = match (opts.zeta, opts.floor) {
        (None, None) => {
            let (best, trials, planned, stopped) = optimise_spiral_planned(cx, opts)?;
            for t in &trials {
                log::debug!("spiral trial {t:?}");
            }
            if let Some(t) = trials.iter().find(|t| t.choice == best)
                && let Some(sim) = t.sim.filter(|s| !s.feasible)
            {
                missed = Some(format!(
                    "no spiral candidate {}was clean within the engagement bound in simulation; \
                     the nearest is kept: floor {:.2}, {} gouges, rest {:.2} %, p99 {:.0} deg \
                     against a bound of {:.0}{}",
                    if stopped { "tried within the search's bounds " } else { "" },
                    best.floor,
                    sim.gouges,
                    100.0 * sim.rest,
                    sim.p99_deg,
                    spiral_bound(cx.job),
                    if stopped { "; a lower floor can be chosen (--spiral-floor)" } else { "" }
                ));
            }
            (best, planned)
        }
        (zeta, floor) => (SpiralChoice { zeta, start: opts.start, floor: floor.unwrap_or(ENGAGEMENT_FLOOR) }, None),
    };
    // the optimiser's program of the choice is the one wanted, unless finishing passes
    // follow it
    let mut program: Program = match planned {
        Some(p) if cx.finish.is_empty() => p,
        _ => link_spiral(cx, &SpiralFields::new(cx.regions, cx.geom), &opts.adaptive, &choice)?.into(),
    };
    if let Some(text) = missed {
        program.toolpath.notes.insert(0, crate::toolpath::Note { at: 0, text });
    }
    Ok(program)
}

/// The loop of paper 4 §4 (Figs. 8–9): chooses ζ (per level, through the floor of the gaps
/// where turns are tight) and, with [`SpiralOptions::optimise`], the start point of a spiral
/// to minimise machining time subject to full clearing (rest ≤ 0.5 % of the reachable area, no
/// gouge) and the engagement bound (p99 outside the entry ≤ the reference + 10°), as swarf's
/// simulator (`cx.sim`) judges them (`cx.finish` is not used).
///
/// The candidates of [`candidates`] are planned [`ROUND`] at a time (the one the search asks for
/// and the floor of the same spiral next to it), and each one's time is read off its program.
/// Simulation (the slow part) is spent only where it can change the answer
/// ([`next_candidate`]): the highest floor of the first spiral first (a lower floor holds the
/// engagement better in tight turns and is slower, so the fastest feasible one is as a rule a
/// high one), then the next; once two floors have broken the engagement bound, the floor where
/// the line through their p99 readings meets the bound (the p99 falls about linearly with the
/// floor: on narrow_slot and simple_part, where every floor breaks it, the lowest floor is
/// simulated third and rules out the three between, which were simulated one by one before).
/// Once a candidate is feasible, only faster ones are simulated: the floors of its spiral above
/// it that were not ruled out, then any planned faster. A damping (floor) that broke the
/// engagement bound from one start is not simulated from the others (the engagement depends on
/// the damping far more than on the start), nor is a higher floor from the same start.
///
/// The search is bounded: it simulates at most [`MAX_SIMULATED`] candidates, and begins no
/// further round once the cells its simulations swept reach [`SpiralOptions::search_cells`]
/// ([`super::spiral::SEARCH_CELLS`] by default: a large pocket is judged on its first round).
/// When no candidate it simulated is feasible, the one that misses by least is returned (fewest
/// gouges, then least rest beyond the limit, then least engagement beyond the bound), and the
/// program says so. Every bound counts the work, not the
/// clock: the choice is the same on any machine and any number of threads. Returns the choice
/// and every trial.
pub(crate) fn optimise_spiral(cx: &Context, opts: &SpiralOptions) -> Result<(SpiralChoice, Vec<Trial>)> {
    optimise_spiral_planned(cx, opts).map(|(choice, trials, ..)| (choice, trials))
}

/// Candidates planned at once, in parallel: a constant, so that what the search plans and
/// chooses does not depend on the number of threads.
pub const ROUND: usize = 2;

/// `optimise_spiral`, with the program of the choice as planned (without finishing passes) and
/// its simulation, when it was simulated.
/// And whether the search stopped at its bounds before it had tried every candidate.
#[allow(clippy::type_complexity)]
fn optimise_spiral_planned(
    cx: &Context,
    opts: &SpiralOptions,
) -> Result<(SpiralChoice, Vec<Trial>, Option<Program>, bool)> {
    use rayon::prelude::*;
    let job = cx.job;
    let bound = spiral_bound(job);
    let candidates = candidates(cx.regions, cx.geom, opts.start, opts.optimise)?;
    let t0 = std::time::Instant::now();
    let fields = SpiralFields::new(cx.regions, cx.geom);
    if let Some(c) = candidates.first() {
        fields.prepare(job, cx.geom, cx.link, c);
    }
    log::debug!("spiral: fields of {} pieces in {:.2} s", fields.pieces(), t0.elapsed().as_secs_f64());
    let n = candidates.len();
    let mut planned: Vec<Option<(Toolpath, Toolpath)>> = (0..n).map(|_| None).collect();
    let mut proofs: Vec<Option<(Replay, Rest, f64)>> = (0..n).map(|_| None).collect();
    let mut trials: Vec<Trial> = candidates.iter().map(|c| Trial { choice: *c, time_min: None, sim: None }).collect();
    let (d, res) = (job.cutting.tool.diameter, cx.sim.res_for(job.cutting.tool.diameter));
    let mut cells = vec![0.0; n];
    // which candidates the search has planned (whether or not a spiral could be made)
    let mut tried = vec![false; n];
    let mut best: Option<usize> = None;
    let mut simulated = 0;
    let mut swept = 0.0;
    let mut stopped = false;
    while let Some(i) = next_candidate(&trials, &tried, best, bound) {
        // at most MAX_SIMULATED simulations, and a new round planned only within the work bound
        if simulated == MAX_SIMULATED || (!tried[i] && swept >= opts.search_cells) {
            stopped = best.is_none();
            break;
        }
        if !tried[i] {
            let round = [Some(i), partner(&trials, &tried, i, bound)];
            let round: Vec<usize> = round.into_iter().flatten().collect();
            let t0 = std::time::Instant::now();
            let made: Vec<_> =
                round.par_iter().map(|&k| plan_spiral_trial(cx, &fields, opts, &candidates[k])).collect();
            log::debug!("spiral: candidates {round:?} planned in {:.2} s", t0.elapsed().as_secs_f64());
            for (&k, tp) in round.iter().zip(made) {
                let totals = tp.as_ref().map(|(_, written)| written.totals(job.cutting.rapid_rate));
                trials[k].time_min = totals.map(|t| t.time_min);
                // the cells the tool sweeps along its cuts, what simulating it costs
                cells[k] = totals.map_or(0.0, |t| t.cut_length_mm * d / (res * res));
                planned[k] = tp;
                tried[k] = true;
            }
            // (planned now: asked again, it may be no longer worth simulating)
            continue;
        }
        let Some((_, tp)) = &planned[i] else { continue };
        simulated += 1;
        swept += cells[i];
        let t0 = std::time::Instant::now();
        let (sim, (rp, rest)) = judge_spiral(job, cx.regions, cx.sim, tp)?;
        let secs = t0.elapsed().as_secs_f64();
        log::debug!(
            "spiral: candidate {i} simulated in {secs:.2} s: p99 {:.1}, feasible {}",
            sim.p99_deg,
            sim.feasible
        );
        trials[i].sim = Some(sim);
        proofs[i] = Some((rp, rest, secs));
        if sim.feasible && best.is_none_or(|b| trials[i].time_min < trials[b].time_min) {
            best = Some(i);
        }
    }
    let best = best
        .or_else(|| nearest_miss(&trials, bound))
        .ok_or_else(|| Error::job("spiral strategy", "no spiral could be made from any start or ζ"))?;
    if stopped {
        log::info!(
            "spiral search stopped after {} of {n} candidates ({simulated} simulated, {:.0} M cells swept)",
            tried.iter().filter(|t| **t).count(),
            swept / 1e6
        );
    }
    let (proof, proof_s) = match proofs.swap_remove(best) {
        Some((rp, rest, secs)) => (Some((rp, rest)), secs),
        None => (None, 0.0),
    };
    Ok((
        trials[best].choice,
        trials,
        planned.swap_remove(best).map(|(toolpath, _)| Program { toolpath, proof, proof_s }),
        stopped,
    ))
}

/// Did the simulated trial `t` break the engagement bound in a way that rules out `c` — the same
/// damping from any start, or a lower floor from the same start (a lower floor holds the
/// engagement better: the gaps in tight turns only widen with the floor)?
fn rules_out(t: &Trial, c: &SpiralChoice, bound: f64) -> bool {
    t.sim.is_some_and(|s| s.p99_deg > bound)
        && t.choice.zeta == c.zeta
        && (t.choice.floor == c.floor || (t.choice.start == c.start && t.choice.floor < c.floor))
}

/// The same spiral but for its floor: the same ζ and start.
fn same_spiral(a: &SpiralChoice, b: &SpiralChoice) -> bool {
    a.zeta == b.zeta && a.start == b.start
}

/// The candidate the search simulates next (planning it first where `tried` says it has not
/// been), or `None` when the search is done.
///
/// Still open are the candidates not simulated, not tried and failed to plan, and not ruled out
/// ([`rules_out`]). Before a feasible candidate is found: the first spiral (ζ and start, in the
/// candidates' order) with open floors, at the floor where the line through its two lowest
/// floors that broke the engagement bound reaches the bound (the highest open floor at or below
/// it, else the lowest open floor) — p99 falls about linearly with the floor, so one step lands
/// at or next to the fastest feasible floor, and where even the lowest floor breaks the bound
/// every floor above it is ruled out at once; with fewer than two such floors, its highest open
/// floor (the fastest). After one is found: the open floors of its spiral above it, lowest
/// first, then any open candidate planned faster than it, fastest first — so no faster
/// candidate is passed over unless it broke the bound or was ruled out.
fn next_candidate(trials: &[Trial], tried: &[bool], best: Option<usize>, bound: f64) -> Option<usize> {
    let n = trials.len();
    let open = |i: usize| {
        trials[i].sim.is_none()
            && !(tried[i] && trials[i].time_min.is_none())
            && !trials.iter().any(|t| rules_out(t, &trials[i].choice, bound))
    };
    let floor = |i: &usize| trials[*i].choice.floor;
    if let Some(b) = best {
        let (cb, tb) = (trials[b].choice, trials[b].time_min.unwrap_or(f64::INFINITY));
        let faster = |i: usize| trials[i].time_min.is_none_or(|t| t < tb);
        return (0..n)
            .filter(|&i| {
                open(i) && faster(i) && same_spiral(&trials[i].choice, &cb) && trials[i].choice.floor > cb.floor
            })
            .min_by(|a, b| floor(a).total_cmp(&floor(b)))
            .or_else(|| {
                (0..n)
                    .filter(|&i| open(i) && trials[i].time_min.is_some_and(|t| t < tb))
                    .min_by(|a, b| trials[*a].time_min.unwrap_or(0.0).total_cmp(&trials[*b].time_min.unwrap_or(0.0)))
            });
    }
    let first = (0..n).find(|&i| open(i))?;
    let g = trials[first].choice;
    let members: Vec<usize> = (0..n).filter(|&i| open(i) && same_spiral(&trials[i].choice, &g)).collect();
    let highest = || members.iter().copied().max_by(|a, b| floor(a).total_cmp(&floor(b)));
    let mut broke: Vec<(f64, f64)> = trials
        .iter()
        .filter(|t| same_spiral(&t.choice, &g))
        .filter_map(|t| t.sim.filter(|s| s.p99_deg > bound).map(|s| (t.choice.floor, s.p99_deg)))
        .collect();
    broke.sort_by(|a, b| a.0.total_cmp(&b.0));
    let [(f_lo, p_lo), (f_hi, p_hi), ..] = broke[..] else { return highest() };
    let slope = (p_hi - p_lo) / (f_hi - f_lo);
    if !(slope.is_finite() && slope > 0.0) {
        return highest();
    }
    let at = f_lo - (p_lo - bound) / slope;
    members
        .iter()
        .copied()
        .filter(|i| floor(i) <= at + 1e-12)
        .max_by(|a, b| floor(a).total_cmp(&floor(b)))
        .or_else(|| members.iter().copied().min_by(|a, b| floor(a).total_cmp(&floor(b))))
}

/// The candidate planned beside `i` (planning runs [`ROUND`] candidates at once): the open
/// floor of the same spiral next above it, else next below it.
fn partner(trials: &[Trial], tried: &[bool], i: usize, bound: f64) -> Option<usize> {
    let c = trials[i].choice;
    let open: Vec<usize> = (0..trials.len())
        .filter(|&k| {
            k != i
                && !tried[k]
                && same_spiral(&trials[k].choice, &c)
                && !trials.iter().any(|t| rules_out(t, &trials[k].choice, bound))
        })
        .collect();
    let floor = |k: &usize| trials[*k].choice.floor;
    open.iter()
        .copied()
        .filter(|k| floor(k) > c.floor)
        .min_by(|a, b| floor(a).total_cmp(&floor(b)))
        .or_else(|| open.iter().copied().filter(|k| floor(k) < c.floor).max_by(|a, b| floor(a).total_cmp(&floor(b))))
}

/// Of the simulated trials, the one that missed by least: fewest gouges, then least rest
/// beyond [`REST_LIMIT`] counted in whole steps of [`REST_STEP`] (rounded), then least p99
/// engagement beyond `bound` (rest within the limit, or in the same step as another's, is not
/// traded against engagement). The first of equals.
fn nearest_miss(trials: &[Trial], bound: f64) -> Option<usize> {
    let miss = |i: usize| {
        trials[i].sim.map(|s| {
            let rest = ((s.rest - REST_LIMIT).max(0.0) / REST_STEP).round() as u64;
            (s.gouges, rest, (s.p99_deg - bound).max(0.0))
        })
    };
    (0..trials.len())
        .filter_map(|i| miss(i).map(|m| (i, m)))
        .min_by(|(_, (ga, ra, ea)), (_, (gb, rb, eb))| ga.cmp(gb).then(ra.cmp(rb)).then(ea.total_cmp(eb)))
        .map(|(i, _)| i)
}

/// The step in which [`nearest_miss`] counts rest beyond the limit, as a share of the
/// reachable area: a tenth of a percent. Two floors of a spiral that cannot hold the bound in a
/// slot leave the same rest but for a few cells of the simulation (narrow_slot: 2.034 % and
/// 2.041 %), and that was chosen over a p99 engagement of 114° against 64°.
const REST_STEP: f64 = 0.001;

/// `optimise_spiral` on a whole job (its regions, layer geometry and levels as
/// [`crate::job::rough::plan`] makes them).
pub fn optimise_spiral_job(
    job: &Job,
    opts: &SpiralOptions,
    link: &LinkOptions,
    sim: &SimOptions,
) -> Result<(SpiralChoice, Vec<Trial>)> {
    on_job(job, opts, link, sim, |cx| optimise_spiral(cx, opts))
}

/// Calls `f` with the context of a whole job planned with `opts`.
fn on_job<T>(
    job: &Job,
    opts: &SpiralOptions,
    link: &LinkOptions,
    sim: &SimOptions,
    f: impl FnOnce(&Context) -> Result<T>,
) -> Result<T> {
    let margin = Strategy::Spiral(opts.clone()).wall_margin(link);
    let regions = job.regions(job.radius(), margin)?;
    let geom = LayerGeom::new(job, &regions, link, margin)?;
    let zs = job.levels();
    f(&Context { job, regions: &regions, geom: &geom, link, sim, zs: &zs, finish: &[] })
}

/// The most candidates `optimise_spiral` simulates.
pub const MAX_SIMULATED: usize = 8;

/// The most rest `optimise_spiral` accepts, as a share of the reachable area.
pub const REST_LIMIT: f64 = 0.005;

/// The most p99 engagement outside the entry `optimise_spiral` accepts: the job's reference
/// + 10°.
fn spiral_bound(job: &Job) -> f64 {
    job.cutting.width.engagement_deg() + 10.0
}

/// The program of one spiral candidate as planned and as it will be written (quantised), or
/// `None` where the spiral cannot be made.
fn plan_spiral_trial(
    cx: &Context,
    fields: &SpiralFields,
    opts: &SpiralOptions,
    choice: &SpiralChoice,
) -> Option<(Toolpath, Toolpath)> {
    let trial = Context { finish: &[], ..*cx };
    let tp = link_spiral(&trial, fields, &opts.adaptive, choice).ok()?;
    let mut written = tp.clone();
    written.quantize(post::COORD_STEP, post::CENTER_STEP);
    Some((tp, written))
}

/// Simulates a spiral candidate (as it will be written) and judges it by the optimiser's
/// criteria; the simulation too.
fn judge_spiral(job: &Job, regions: &Regions, sim: &SimOptions, tp: &Toolpath) -> Result<(TrialSim, (Replay, Rest))> {
    let (rp, rest) = crate::sim::simulate(job, regions, sim, tp, &mut |_| {})?;
    let mut rep = Report::default();
    report::fill(&mut rep, tp, &rp, &rest, job.cutting.rapid_rate);
    let bound = spiral_bound(job);
    let judged = TrialSim {
        gouges: rep.gouges,
        rest: rep.rest_fraction,
        p99_deg: rep.engagement_deg.p99,
        feasible: rep.rest_fraction <= REST_LIMIT && rep.gouges == 0 && rep.engagement_deg.p99 <= bound,
    };
    Ok((judged, (rp, rest)))
}

/// What [`spiral_study`] measured of one job.
#[derive(Debug, Clone)]
pub struct SpiralStudy {
    /// The default of `rough`: the floor chosen from the maximum of f (`optimise_spiral`
    /// without other starts), and its trials.
    pub default: (SpiralChoice, Vec<Trial>),
    /// `--optimise`: the floor and the start chosen, and the trials.
    pub optimised: (SpiralChoice, Vec<Trial>),
    /// The baseline: the largest feasible constant ζ (`best_fixed_zeta`).
    pub fixed: Option<(f64, Trial)>,
}

/// The comparison of the docs' table: the default spiral, the optimiser's choice with other
/// starts, and the best constant ζ, each simulated and judged by the optimiser's criteria.
/// Slow (minutes).
pub fn spiral_study(job: &Job, opts: &SpiralOptions, link: &LinkOptions, sim: &SimOptions) -> Result<SpiralStudy> {
    on_job(job, opts, link, sim, |cx| {
        let mut o = opts.clone();
        o.optimise = false;
        let default = optimise_spiral(cx, &o)?;
        o.optimise = true;
        let optimised = optimise_spiral(cx, &o)?;
        let fixed = best_fixed_zeta(cx, opts)?;
        Ok(SpiralStudy { default, optimised, fixed })
    })
}

/// The baseline of the optimiser: the largest constant ζ whose spiral (from the maximum of f)
/// is feasible by the optimiser's criteria, found by simulation (doubling or halving from
/// ζ = 0.02 to a bracket, then five geometric bisections; feasibility is taken as monotone in
/// ζ, which a wider spiral breaks by leaving more rest or engaging more). Returns ζ and its
/// trial, or `None` when no ζ down to 1e-4 is feasible. Slow (each try is simulated, and a
/// small ζ makes a long program): for comparisons, not for planning.
pub(crate) fn best_fixed_zeta(cx: &Context, opts: &SpiralOptions) -> Result<Option<(f64, Trial)>> {
    let job = cx.job;
    let fields = SpiralFields::new(cx.regions, cx.geom);
    let try_z = |z: f64| -> Result<Trial> {
        let choice = SpiralChoice { zeta: Some(z), ..Default::default() };
        let tp = plan_spiral_trial(cx, &fields, opts, &choice).map(|(_, written)| written);
        let sim = match &tp {
            Some(tp) => Some(judge_spiral(job, cx.regions, cx.sim, tp)?.0),
            None => None,
        };
        Ok(Trial { choice, time_min: tp.map(|tp| tp.totals(job.cutting.rapid_rate).time_min), sim })
    };
    let (mut lo, mut hi): (Option<(f64, Trial)>, Option<f64>) = (None, None);
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
    use crate::strategy::spiral::FLOORS;

    fn trial(floor: f64, sim: Option<(usize, f64, f64)>) -> Trial {
        Trial {
            choice: SpiralChoice { zeta: None, start: None, floor },
            time_min: Some(1.0),
            sim: sim.map(|(gouges, rest, p99_deg)| TrialSim { gouges, rest, p99_deg, feasible: false }),
        }
    }

    /// The six floors of one spiral, planned (times rising as the floor falls) and simulated
    /// where `p99` gives a reading (feasible when within `bound`).
    fn floors(p99: [Option<f64>; 6], bound: f64) -> Vec<Trial> {
        FLOORS
            .iter()
            .zip(p99)
            .enumerate()
            .map(|(i, (&floor, p))| Trial {
                choice: SpiralChoice { zeta: None, start: None, floor },
                time_min: Some(1.0 + i as f64),
                sim: p.map(|p99_deg| TrialSim { gouges: 0, rest: 0.0, p99_deg, feasible: p99_deg <= bound }),
            })
            .collect()
    }

    /// Each step of the search on a spiral whose p99 falls as the floor does: the floors
    /// simulated are the ones it needs, and what it chooses is the fastest feasible floor.
    #[test]
    fn the_search_goes_where_the_engagement_line_meets_the_bound() {
        let all = [true; 6];
        // the first two floors, highest first
        assert_eq!(next_candidate(&floors([None; 6], 63.0), &[false; 6], None, 63.0), Some(0));
        assert_eq!(
            next_candidate(&floors([Some(114.0), None, None, None, None, None], 63.0), &all, None, 63.0),
            Some(1)
        );
        // narrow_slot's readings: the line through them meets 63° below the lowest floor, so
        // the lowest is next; when it breaks the bound too, every floor above it is ruled out
        let t = floors([Some(113.9), Some(105.7), None, None, None, None], 63.1);
        assert_eq!(next_candidate(&t, &all, None, 63.1), Some(5));
        let t = floors([Some(113.9), Some(105.7), None, None, None, Some(64.6)], 63.1);
        assert_eq!(next_candidate(&t, &all, None, 63.1), None);
        // l_pocket's: the line meets 100° at a floor of 0.37, so 0.35 is next, and when it
        // holds the bound the search is done (both floors above it broke it)
        let t = floors([Some(112.5), Some(104.9), None, None, None, None], 100.0);
        assert_eq!(next_candidate(&t, &all, None, 100.0), Some(2));
        let t = floors([Some(112.5), Some(104.9), Some(97.4), None, None, None], 100.0);
        assert_eq!(next_candidate(&t, &all, Some(2), 100.0), None);
        // a step that lands lower than it had to: the open floors above the feasible one are
        // tried, lowest first, until one breaks the bound or none is left
        let t = floors([Some(112.5), Some(110.0), None, None, Some(90.0), None], 100.0);
        assert_eq!(next_candidate(&t, &all, Some(4), 100.0), Some(3));
        let t = floors([Some(112.5), Some(110.0), None, Some(99.0), Some(90.0), None], 100.0);
        assert_eq!(next_candidate(&t, &all, Some(3), 100.0), Some(2));
        let t = floors([Some(112.5), Some(110.0), Some(101.0), Some(99.0), Some(90.0), None], 100.0);
        assert_eq!(next_candidate(&t, &all, Some(3), 100.0), None);
        // a floor that could not be planned is not asked for again
        let mut t = floors([Some(113.9), Some(105.7), None, None, None, None], 63.1);
        t[5].time_min = None;
        assert_eq!(next_candidate(&t, &all, None, 63.1), Some(4));
        // planned beside a floor: the open floor next above it, else next below
        let t = floors([Some(113.9), Some(105.7), None, None, None, None], 63.1);
        let tried = [true, true, false, false, false, false];
        assert_eq!(partner(&t, &tried, 5, 63.1), Some(4));
        assert_eq!(partner(&t, &tried, 2, 63.1), Some(3));
        assert_eq!(partner(&floors([None; 6], 63.1), &[false; 6], 0, 63.1), Some(1));
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
        // rests beyond the limit that round to the same step are equal: the engagement decides
        // (narrow_slot's highest and lowest floors)
        let t = [trial(0.5, Some((0, 0.020343, 113.8))), trial(0.16, Some((0, 0.020412, 64.4)))];
        assert_eq!(nearest_miss(&t, 63.1), Some(1));
        assert_eq!(nearest_miss(&[trial(0.5, None)], 70.0), None);
    }
}
