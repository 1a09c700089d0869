//! The main job: a [`Job`] in, a program, its G-code, a report and a picture out.

use crate::error::{Error, Result};
use crate::model::Job;
use crate::plan;
use crate::post::{self, Header, Post};
use crate::report::{self, Report};
use crate::sim::Replay;
use crate::sim::SimOptions;
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
    simulate: impl FnOnce(&Toolpath, &mut dyn FnMut(Stage, f64)) -> Result<(Replay, crate::sim::Rest)>,
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
        strategy::adaptive::link_adaptive(job, &regions, &geom, &opts.params, &zs, &finish, &opts.sim)?
    } else if opts.params.strategy == strategy::StrategyKind::Medial {
        strategy::medial::link_medial(job, &regions, &geom, &opts.params, &zs, &finish, &opts.sim)?
    } else if opts.params.strategy == strategy::StrategyKind::Spiral {
        strategy::spiral_search::plan_spiral(job, &regions, &geom, &opts.params, &zs, &finish, &opts.sim)?
    } else {
        plan::link(job, &regions, &opts.params, &levels, &finish, &opts.sim)?
    };
    Ok(Some(Planned { toolpath, levels: zs, regions }))
}
