//! Z-level roughing of a part given as a mesh (paper 3, El-Midany et al.: §2 hunting planes,
//! §3 Algorithms 1–2).
//!
//! The stock is cut in slices from the top. Each level `z` is a 2.5D job: the material is the
//! stock, the part to keep is the shadow of the mesh above the level ([`crate::mesh::Shadows`],
//! grown by the allowance), and any 2.5D strategy of swarf (adaptive, offset, zigzag) plans it.
//! The offset strategy is paper 3's Algorithm 1 (repeated inward offsets of the part contours);
//! its accessible area (Algorithm 2, the opening of the level's material by the tool disk) is
//! the `reachable` region of the level's [`crate::model::Regions`].
//!
//! Levels are the step-downs from the stock top to the floor plus one at every flat of the
//! part (the height of each upward facet, raised by the floor allowance), so that floors and
//! the tops of islands are not left a step-down thick.
//!
//! One material model follows the whole job: each level is planned on the stock that the levels
//! above left (through [`crate::sim::SimOptions::heights`]), so its links and entries see the
//! material the levels above could not reach, and the program's replay for the report reads
//! the part's surface from the mesh ([`crate::mesh::height_map`]), so a gouge anywhere on the
//! surface is found.

use crate::error::{Error, Result};
use crate::geom::{Area, DVec3};
use crate::io::stl::Mesh;
use crate::model::{Job, REGION_TOL, Tool, Width};
use crate::pipeline::{RoughOptions, RoughResult, Stage};
use crate::post;
use crate::sim::raster::RasterSim;
use crate::sim::sweep::Path;
use crate::sim::{HeightMap, SimOptions};
use crate::toolpath::Toolpath;
use std::sync::Arc;
use std::time::Instant;

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
    /// The tool.
    pub tool: Tool,
    /// Width of cut.
    pub width: Width,
    /// Largest depth of one level, mm.
    pub stepdown: f64,
    /// Cutting feed, mm/min.
    pub feed: f64,
    /// Rapid rate for time estimates, mm/min.
    pub rapid_rate: f64,
    /// Spindle speed, rpm.
    pub spindle_rpm: f64,
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
    /// Checks the numbers a user gives.
    pub fn validate(&self) -> Result<()> {
        crate::model::check_tool_and_width(&self.tool, self.width)?;
        if !(self.stepdown.is_finite() && self.stepdown > 0.0) {
            return Err(Error::param("stepdown", format!("{} mm: must be positive", self.stepdown)));
        }
        let size = self.stock_hi - self.stock_lo;
        if !(size.x > 0.0 && size.y > 0.0 && size.z > 0.0 && size.is_finite()) {
            return Err(Error::param("stock_box", "the box must have positive width, length and height"));
        }
        if !(self.floor.is_finite() && self.floor + self.allowance_floor < self.stock_hi.z) {
            return Err(Error::param(
                "floor",
                format!(
                    "{} mm (+ {} mm floor allowance): must be below the stock top {}",
                    self.floor, self.allowance_floor, self.stock_hi.z
                ),
            ));
        }
        for (name, v) in [("allowance", self.allowance), ("allowance_floor", self.allowance_floor)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::param(name, format!("{v} mm: must be zero or positive")));
            }
        }
        for (name, v) in [("feed", self.feed), ("rapid_rate", self.rapid_rate), ("spindle", self.spindle_rpm)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::param(name, format!("{v}: must be positive")));
            }
        }
        Ok(())
    }

    /// Tool radius.
    pub fn radius(&self) -> f64 {
        self.tool.radius()
    }

    /// The stock outline.
    pub fn stock_area(&self) -> Area {
        Area::rect(self.stock_lo.x, self.stock_lo.y, self.stock_hi.x, self.stock_hi.y)
    }

    /// The part's outline seen from above (its shadow at the floor).
    pub fn outline(&self) -> Area {
        crate::mesh::Shadows::new(&self.mesh).down_to(self.floor - self.allowance_floor).clone()
    }

    /// Highest point of the part with its allowance, or the stock top when the part is lower.
    pub fn top(&self) -> f64 {
        self.mesh.bounds().map_or(self.stock_hi.z, |(_, hi)| (hi.z + self.allowance_floor).max(self.stock_hi.z))
    }

    /// The levels, top down: step-downs of at most `stepdown` from the stock top to the floor
    /// (raised by the floor allowance), and the flats of the part (raised by as much) between
    /// them.
    pub fn levels(&self) -> Vec<f64> {
        self.levels_every(self.stepdown)
    }

    /// The levels as [`MeshJob::levels`] with step-downs of at most `stepdown`.
    pub fn levels_every(&self, stepdown: f64) -> Vec<f64> {
        let top = self.stock_hi.z;
        // (the floor is protected like the part: with its allowance on top)
        let bottom = self.floor + self.allowance_floor;
        let n = (((top - bottom) / stepdown) - 1e-9).ceil().max(1.0) as usize;
        let mut zs: Vec<f64> =
            (1..=n).map(|i| if i == n { bottom } else { top - (top - bottom) * i as f64 / n as f64 }).collect();
        for f in crate::mesh::flats(&self.mesh, 1e-6) {
            let z = f + self.allowance_floor;
            if z < top - LEVEL_MERGE && z > bottom + LEVEL_MERGE {
                zs.push(z);
            }
        }
        zs.sort_by(|a, b| b.total_cmp(a));
        zs.dedup_by(|a, b| (*b - *a).abs() <= LEVEL_MERGE);
        zs
    }

    /// The 2.5D job of one level: the stock box, the part's shadow above it as the part.
    fn level_job(&self, keep: &Area, z: f64) -> Job {
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
            tool: self.tool.clone(),
            width: self.width,
            stepdown: None,
            feed: self.feed,
            rapid_rate: self.rapid_rate,
            spindle_rpm: self.spindle_rpm,
        }
    }

    /// A 2.5D job over the whole stock without a part, for the job's material model.
    fn model_job(&self) -> Job {
        let mut j = self.level_job(&Area::empty(), self.floor + self.allowance_floor);
        j.part_top = self.stock_hi.z;
        j
    }
}

/// The material model of a whole mesh job: the stock box, with the part's surface from the
/// mesh (raised by the floor allowance) as what must stay.
fn model(job: &MeshJob, sim: &SimOptions) -> Result<RasterSim> {
    let mj = job.model_job();
    let regions = mj.regions(job.radius(), 0.0)?;
    let grid = RasterSim::grid_for(&mj, &regions.keep, sim)?;
    let mut part = crate::mesh::height_map(&job.mesh, &grid);
    let lift = job.allowance_floor as f32;
    for h in &mut part {
        *h += lift;
    }
    let stock = vec![f32::INFINITY; grid.len()];
    let opts = SimOptions { heights: Some(Arc::new(HeightMap { grid, stock, part: Some(part) })), ..sim.clone() };
    RasterSim::new(&mj, &regions, &opts)
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

/// Cuts every move of `tp` into `sim` (no measurements).
fn cut_all(sim: &mut RasterSim, tp: &Toolpath) {
    for (from, m) in tp.segments() {
        sim.cut_move(&Path::of(from, m));
    }
}

/// Plans the z-level program of `job` (no posting, no simulation).
pub fn plan(job: &MeshJob, opts: &RoughOptions, progress: &mut dyn FnMut(f64)) -> Result<(Toolpath, Vec<f64>)> {
    job.validate()?;
    crate::pipeline::validate_params(&opts.params)?;
    let debug = std::env::var("SWARF_DEBUG").is_ok();
    let t0 = Instant::now();
    let zs = job.levels();
    let mut shadows = crate::mesh::Shadows::new(&job.mesh);
    let mut state = model(job, &opts.sim)?;
    let safe_z = job.top() + opts.params.clearance;
    let mut out: Option<Toolpath> = None;
    let mut done = Vec::new();
    for (i, &z) in zs.iter().enumerate() {
        progress(i as f64 / zs.len() as f64);
        let ts = Instant::now();
        let shadow = shadows.down_to(z - job.allowance_floor);
        let t_shadow = ts.elapsed().as_secs_f64();
        let keep = keep_of(shadow, job.allowance);
        if debug {
            eprintln!(
                "shadow at z {z:.3}: {} vertices in {t_shadow:.3} s, keep {} vertices ({} rings) in {:.3} s",
                shadow.vertex_count(),
                keep.vertex_count(),
                keep.rings().count(),
                ts.elapsed().as_secs_f64() - t_shadow
            );
        }
        let lj = job.level_job(&keep, z);
        // the level is planned on what the levels above left
        let heights = HeightMap { grid: state.grid, stock: state.heights().to_vec(), part: None };
        let lopts = RoughOptions {
            // (rapids at depth cross whole levels of cleared stock: checked against the
            // surely cut heights)
            sim: SimOptions { heights: Some(Arc::new(heights)), sure_links: true, ..opts.sim.clone() },
            params: crate::strategy::Params { corner_fillets: false, full_wall_contour: true, ..opts.params.clone() },
            ..opts.clone()
        };
        let planned = match crate::pipeline::plan(&lj, &lopts) {
            Ok(p) => p,
            // a level with nothing the tool can reach
            Err(Error::Param { .. }) if lj.regions(job.radius(), 0.0).map_or(true, |r| r.reachable.is_empty()) => None,
            Err(e) => return Err(e),
        };
        let Some(p) = planned else { continue };
        let mut tp = p.toolpath;
        // (each level's program ends with its retract to the safe height, where the next
        // level's travel starts)
        tp.notes.retain(|n| !n.text.starts_with("level ") && !n.text.starts_with("end:"));
        if debug {
            eprintln!(
                "z-level {} of {} at z {z:.3}: {} moves, {:.2} s",
                i + 1,
                zs.len(),
                tp.moves.len(),
                t0.elapsed().as_secs_f64()
            );
        }
        if tp.moves.iter().all(|m| m.is_rapid()) {
            continue;
        }
        cut_all(&mut state, &tp);
        done.push(z);
        match &mut out {
            None => {
                let mut first = Toolpath::new(job.tool.clone(), tp.start, safe_z);
                first.note(format!("z-level {}: z {z:.3}", done.len()));
                append(&mut first, tp, safe_z);
                out = Some(first);
            }
            Some(all) => {
                all.note(format!("z-level {}: z {z:.3}", done.len()));
                append(all, tp, safe_z);
            }
        }
    }
    progress(1.0);
    let mut tp = out.ok_or_else(|| {
        Error::param("stock_box", "nothing to cut: the part fills the stock, or the tool reaches no material")
    })?;
    let end = tp.end();
    if end.z < safe_z - 1e-9 {
        tp.note("end: retract");
        tp.rapid(DVec3::new(end.x, end.y, safe_z));
    }
    Ok((tp, done))
}

/// Appends a level's program: a rapid at the safe height to above its start, then its moves.
fn append(all: &mut Toolpath, tp: Toolpath, safe_z: f64) {
    let end = all.end();
    if (end.truncate() - tp.start.truncate()).length() > 1e-9 || (end.z - tp.start.z).abs() > 1e-9 {
        if end.z < safe_z - 1e-9 {
            all.rapid(DVec3::new(end.x, end.y, safe_z));
        }
        all.rapid(DVec3::new(tp.start.x, tp.start.y, safe_z));
        if tp.start.z < safe_z - 1e-9 {
            all.rapid(tp.start);
        }
    }
    let base = all.moves.len();
    for n in tp.notes {
        all.notes.push(crate::toolpath::Note { at: base + n.at, text: n.text });
    }
    all.moves.extend(tp.moves);
}

/// Roughs a mesh job: plans, posts and (optionally) simulates it for the report.
pub fn rough(job: &MeshJob, opts: &RoughOptions, progress: &mut dyn FnMut(Stage, f64)) -> Result<RoughResult> {
    if opts.sim.engine != crate::sim::SimEngine::Raster && opts.simulate {
        return Err(Error::param("--sim", "the distance-field simulator handles 2.5D jobs only; use --sim raster"));
    }
    let t0 = Instant::now();
    progress(Stage::Plan, 0.0);
    let (mut toolpath, zs) = plan(job, opts, &mut |f| progress(Stage::Plan, f))?;
    toolpath.quantize(post::COORD_STEP, post::CENTER_STEP);
    let compute_s = t0.elapsed().as_secs_f64();
    progress(Stage::Plan, 1.0);
    let about = crate::pipeline::About {
        name: &job.name,
        what: "z-level roughing, ",
        tool_diameter: job.tool.diameter,
        width: job.width,
        floor: job.floor,
        feed: job.feed,
        spindle_rpm: job.spindle_rpm,
        rapid_rate: job.rapid_rate,
    };
    crate::pipeline::finish(toolpath, zs, &about, opts, compute_s, progress, |tp, progress| {
        let mut sim = model(job, &opts.sim)?;
        let mut rp = sim.replay(tp, &mut |f| progress(Stage::Simulate, f));
        rp.res = sim.grid.res;
        Ok((rp, rest(job, &sim)))
    })
}

/// Material the tool could have removed and left: at each cell, the stock above the lowest
/// height a flat end mill of the job's radius reaches there without touching the part (the grey
/// closing of the part's heights by the tool's disk), counted where it is thicker than the
/// simulation's tolerance.
fn rest(job: &MeshJob, sim: &RasterSim) -> crate::sim::raster::Rest {
    let g = sim.grid;
    let part = sim.part_heights();
    let floor = (job.floor + job.allowance_floor) as f32;
    let p: Vec<f32> = part.iter().map(|&h| h.max(floor)).collect();
    // the sideways allowance: the part's heights spread over a disk of its radius (a cylinder
    // round each point, which holds the ball of the allowance)
    let p = if job.allowance > 0.0 { disk_filter(&p, g.nx, g.ny, job.allowance / g.res, true) } else { p };
    // (the tool's axis kept R + res/√2 from the part's cell centres, as a path running exactly
    // at R from the true surface may be that far from the nearest centre: no phantom slivers
    // along walls; slivers thinner than that go unreported)
    let rc = job.radius() / g.res + std::f64::consts::FRAC_1_SQRT_2;
    // tool tip height at each centre: the highest part under the disk (dilation), then the
    // lowest of those over the disks that cover a cell (erosion)
    let tip = disk_filter(&p, g.nx, g.ny, rc, true);
    let reach = disk_filter(&tip, g.nx, g.ny, job.radius() / g.res, false);
    let s = sim.heights();
    let (slo, shi) = (job.stock_lo, job.stock_hi);
    let cell = g.res * g.res;
    let mut r = crate::sim::raster::Rest::default();
    let tol = 0.01f32;
    for j in 0..g.ny {
        for i in 0..g.nx {
            let c = g.center(i, j);
            if c.x < slo.x || c.x > shi.x || c.y < slo.y || c.y > shi.y {
                continue;
            }
            let k = j * g.nx + i;
            let low = reach[k].max(p[k]);
            if low >= shi.z as f32 - tol {
                continue;
            }
            r.reachable_mm2 += cell;
            let t = s[k] - low;
            if t > tol {
                if std::env::var("SWARF_DEBUG").is_ok() && t > 0.5 {
                    eprintln!("rest {t:.3} mm at {c:?} (stock {:.3}, reach {:.3}, part {:.3})", s[k], reach[k], p[k]);
                }
                r.area_mm2 += cell;
                r.volume_mm3 += t as f64 * cell;
                r.max_thickness_mm = r.max_thickness_mm.max(t as f64);
            }
        }
    }
    r
}

/// Maximum (`max`) or minimum over the disk of radius `rc` cells around every cell: for each
/// row offset, a running extreme over the row's chord (van Herk / Gil–Werman, O(1) a cell per
/// offset). Outside the grid counts as −∞ for the maximum and +∞ for the minimum.
fn disk_filter(h: &[f32], nx: usize, ny: usize, rc: f64, max: bool) -> Vec<f32> {
    use rayon::prelude::*;
    let ri = rc.floor() as i64;
    let ext = if max { f32::NEG_INFINITY } else { f32::INFINITY };
    let pick = |a: f32, b: f32| if max { a.max(b) } else { a.min(b) };
    // per distinct half-width w, the running extreme of each row over [i − w, i + w]
    let widths: Vec<usize> =
        (-ri..=ri).map(|dy| ((rc * rc - (dy * dy) as f64).max(0.0)).sqrt().floor() as usize).collect();
    let mut distinct = widths.clone();
    distinct.sort_unstable();
    distinct.dedup();
    let rows: Vec<Vec<Vec<f32>>> = (0..ny)
        .into_par_iter()
        .map(|j| {
            let row = &h[j * nx..(j + 1) * nx];
            distinct.iter().map(|&w| window(row, w, ext, &pick)).collect()
        })
        .collect();
    let mut out = vec![ext; nx * ny];
    out.par_chunks_mut(nx).enumerate().for_each(|(j, o)| {
        for (t, dy) in (-ri..=ri).enumerate() {
            let jj = j as i64 + dy;
            if jj < 0 || jj >= ny as i64 {
                continue;
            }
            let wi = distinct.binary_search(&widths[t]).unwrap_or(0);
            let src = &rows[jj as usize][wi];
            for (a, b) in o.iter_mut().zip(src) {
                *a = pick(*a, *b);
            }
        }
    });
    out
}

/// The extreme of `row` over `[i − w, i + w]` at every `i` (van Herk / Gil–Werman).
fn window(row: &[f32], w: usize, ext: f32, pick: &dyn Fn(f32, f32) -> f32) -> Vec<f32> {
    let n = row.len();
    let k = 2 * w + 1;
    // padded row: w cells of `ext` on each side
    let m = n + 2 * w;
    let at = |i: usize| if i < w || i >= w + n { ext } else { row[i - w] };
    let mut pre = vec![ext; m];
    let mut suf = vec![ext; m];
    for i in 0..m {
        pre[i] = if i % k == 0 { at(i) } else { pick(pre[i - 1], at(i)) };
    }
    for i in (0..m).rev() {
        suf[i] = if i % k == k - 1 || i == m - 1 { at(i) } else { pick(suf[i + 1], at(i)) };
    }
    (0..n).map(|i| pick(suf[i], pre[i + 2 * w])).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn window_matches_brute_force() {
        let row: Vec<f32> = (0..37).map(|i| ((i * 7919) % 23) as f32).collect();
        for w in [0usize, 1, 3, 8, 40] {
            let got = window(&row, w, f32::NEG_INFINITY, &|a: f32, b: f32| a.max(b));
            for (i, g) in got.iter().enumerate() {
                let lo = i.saturating_sub(w);
                let hi = (i + w).min(row.len() - 1);
                let want = row[lo..=hi].iter().copied().fold(f32::NEG_INFINITY, f32::max);
                assert_eq!(*g, want, "w {w} i {i}");
            }
        }
    }

    #[test]
    fn disk_filter_is_a_disk() {
        let (nx, ny) = (21, 21);
        let mut h = vec![0f32; nx * ny];
        h[10 * nx + 10] = 1.0;
        let d = disk_filter(&h, nx, ny, 4.5, true);
        for j in 0..ny {
            for i in 0..nx {
                let r2 = (i as f64 - 10.0).powi(2) + (j as f64 - 10.0).powi(2);
                assert_eq!(d[j * nx + i], if r2 <= 4.5 * 4.5 { 1.0 } else { 0.0 }, "{i} {j}");
            }
        }
    }
}
