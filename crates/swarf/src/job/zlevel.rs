//! Z-level roughing of a part given as a mesh (paper 3, El-Midany et al.: §2 hunting planes,
//! §3 Algorithms 1–2).
//!
//! The stock is cut in slices from the top, at every step-down and at every flat of the part.
//! Each level is a 2.5D job whose part is the shadow of the mesh above it
//! ([`crate::geom::mesh::Shadows`], grown by the allowance), planned by any 2.5D strategy (the
//! offset strategy is Algorithm 1, the level's `reachable` region Algorithm 2's accessible
//! area) on the stock the levels above left; the report's replay reads the part's surface from
//! the mesh, so a gouge anywhere on it is found. The levels' programs are then cut into pieces
//! and put in order region by region through the levels (`job/zorder.rs`), so that the tool
//! finishes a region to its bottom before it travels. The walk-through is in `docs/zlevel.md`.

use super::rough::{About, RoughOptions, RoughResult, Stage, finish};
use crate::error::{Error, Result, Setting};
use crate::model::{MeshJob, keep_of};
use crate::post;
use crate::sim::{HeightMap, SimOptions};
use crate::toolpath::Toolpath;
use std::sync::Arc;
use std::time::Instant;

/// The picture's top view of a 3D job's stock is at most this many blocks of cells to a side.
const TOP_VIEW_SIDE: usize = 800;

/// Plans the z-level program of `job` (no posting, no simulation).
pub fn plan(job: &MeshJob, opts: &RoughOptions, progress: &mut dyn FnMut(f64)) -> Result<(Toolpath, Vec<f64>)> {
    job.validate()?;
    opts.validate()?;
    let t0 = Instant::now();
    let zs = job.levels();
    let mut state = crate::sim::heights::mesh_model(job, &opts.sim)?;
    // (heights only: no engagement is measured on it)
    state.track_exact = false;
    let safe_z = job.top() + opts.link.clearance;
    let mut strategy = opts.strategy.clone();
    // (the slivers the fillets and a cell-sized model leave stack into walls a whole depth tall
    // over the levels: no fillets, and the wall contour all round)
    let wall_contours = match strategy.adaptive_mut() {
        Some(a) => {
            a.corner_fillets = false;
            a.full_wall_contour = true;
            true
        }
        None => false,
    };
    let level_opts = RoughOptions { strategy, ..opts.clone() };
    let cell = state.grid.res;
    let mut levels: Vec<(f64, Toolpath)> = Vec::new();
    let mut keeps = super::zorder::Keeps::new(job.top());
    let mut done = Vec::new();
    std::thread::scope(|scope| -> Result<()> {
        // Each level's geometry (the shadow, the level's job, its regions and the offsets of
        // its clean-up) does not depend on the material, only the planning does: it is made a
        // level or two ahead on a thread of its own, while the planner cuts the level above.
        // The same geometry in the same order, so the same program.
        let (tx, rx) = std::sync::mpsc::sync_channel(1);
        let (zs, level_opts) = (&zs, &level_opts);
        scope.spawn(move || {
            let mut shadows = crate::geom::mesh::Shadows::new(&job.mesh);
            for &z in zs {
                let ts = Instant::now();
                let shadow = shadows.down_to(z - job.allowance_floor);
                let t_shadow = ts.elapsed().as_secs_f64();
                let keep = keep_of(shadow, job.allowance);
                log::trace!(
                    "shadow at z {z:.3}: {} vertices in {t_shadow:.3} s, keep {} vertices ({} rings) in {:.3} s",
                    shadow.vertex_count(),
                    keep.vertex_count(),
                    keep.rings().count(),
                    ts.elapsed().as_secs_f64() - t_shadow
                );
                let lj = job.level_job(&keep, z);
                let geometry = super::rough::geometry(&lj, level_opts);
                if let Ok((_, g)) = &geometry
                    && wall_contours
                {
                    // (the zone of the clean-up's wall contour, see cleanup::passes_for_leftover)
                    g.centres_grown(g.r + cell);
                }
                // (the planner stopped: an error)
                if tx.send((z, keep, lj, geometry)).is_err() {
                    break;
                }
            }
        });
        for (i, (z, keep, lj, geometry)) in rx.iter().enumerate() {
            progress(i as f64 / zs.len() as f64);
            log::info!("z-level {} of {}: z {z:.3}", i + 1, zs.len());
            keeps.push(z, &keep, job.radius());
            // the level is planned on what the levels above left
            let heights = HeightMap { grid: state.grid, stock: state.heights().to_vec(), part: None };
            let lopts = RoughOptions {
                // (rapids at depth cross whole levels of cleared stock: checked against the
                // surely cut heights)
                sim: SimOptions { heights: Some(Arc::new(heights)), sure_links: true, ..level_opts.sim.clone() },
                ..level_opts.clone()
            };
            let planned = geometry.and_then(|(regions, geom)| super::rough::plan_on(&lj, &lopts, regions, &geom));
            let planned = match planned {
                Ok(p) => p,
                // a level with nothing the tool can reach
                Err(Error::Job { .. }) if lj.regions(job.radius(), 0.0).map_or(true, |r| r.reachable.is_empty()) => {
                    None
                }
                Err(e) => return Err(e),
            };
            let Some(p) = planned else { continue };
            let mut tp = p.toolpath;
            // (each level's program ends with its retract to the safe height, where the next
            // level's travel starts)
            tp.notes.retain(|n| !n.text.starts_with("level ") && !n.text.starts_with("end:"));
            log::debug!(
                "z-level {} of {} at z {z:.3}: {} moves, {:.2} s",
                i + 1,
                zs.len(),
                tp.moves.len(),
                t0.elapsed().as_secs_f64()
            );
            if tp.moves.iter().all(|m| m.is_rapid()) {
                continue;
            }
            state.cut_moves(tp.start, &tp.moves);
            done.push(z);
            levels.push((z, tp));
        }
        Ok(())
    })?;
    progress(1.0);
    // the pieces of the levels in order, region by region, on the material model of the whole
    // job (the links checked against the surely cut heights, as the levels' own)
    let mut model = crate::sim::heights::mesh_model(job, &SimOptions { sure_links: true, ..opts.sim.clone() })?;
    model.track_exact = false;
    let how = super::zorder::Linking {
        r: job.radius(),
        safe_z,
        approach: opts.link.approach,
        by_level: opts.link.by_level,
        link_feed: job.cutting.feed * job.cutting.boost_within(opts.link.feed_boost),
        keeps,
    };
    let tp = super::zorder::link(&levels, &mut model, &how, |li, z| format!("z-level {}: z {z:.3}", li + 1))
        .ok_or_else(|| {
            Error::job("stock_box", "nothing to cut: the part fills the stock, or the tool reaches no material")
        })?;
    Ok((tp, done))
}

/// Roughs a mesh job: plans, posts and (optionally) simulates it for the report. Each level is
/// planned with `opts.strategy` on the stock the levels above left.
///
/// ```
/// use swarf::{Input, Overrides, RoughOptions, load_input, rough_mesh};
/// let case = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/3d/bowl_cavity.json");
/// let Input::Mesh(job) = load_input(case.as_ref(), &Overrides::DEFAULT)? else { unreachable!() };
/// let opts = RoughOptions { simulate: false, ..RoughOptions::DEFAULT };
/// let out = rough_mesh(&job, &opts, &mut |_, _| {})?;
/// assert!(out.report.levels.len() > 1 && out.gcode.contains("z-level roughing"));
/// # Ok::<(), swarf::Error>(())
/// ```
pub fn rough(job: &MeshJob, opts: &RoughOptions, progress: &mut dyn FnMut(Stage, f64)) -> Result<RoughResult> {
    if opts.sim.engine != crate::sim::SimEngine::Raster && opts.simulate {
        return Err(Error::setting(
            Setting::SimEngine,
            "the distance-field simulator handles 2.5D jobs only; use the raster simulator",
        ));
    }
    let fitted = opts
        .sim
        .fitted(job.cutting.tool.diameter, job.stock_lo.truncate(), job.stock_hi.truncate())
        .map(|sim| RoughOptions { sim, ..opts.clone() });
    let opts = fitted.as_ref().unwrap_or(opts);
    let t0 = Instant::now();
    progress(Stage::Plan, 0.0);
    let (mut toolpath, zs) = plan(job, opts, &mut |f| progress(Stage::Plan, f))?;
    toolpath.quantize(post::COORD_STEP, post::CENTER_STEP);
    let compute_s = t0.elapsed().as_secs_f64();
    log::info!("{}: {} levels planned in {compute_s:.2} s, {} moves", job.name, zs.len(), toolpath.moves.len());
    progress(Stage::Plan, 1.0);
    let about = About {
        name: &job.name,
        what: "z-level roughing, ",
        cutting: &job.cutting,
        floor: job.floor,
        depth: job.level_depth(),
    };
    finish(toolpath, zs, &about, opts, compute_s, progress, |tp, progress| {
        let mut sim = crate::sim::heights::mesh_model(job, &opts.sim)?;
        let mut rp = sim.replay(tp, &mut |f| progress(Stage::Simulate, f));
        rp.res = sim.grid.res;
        let (rest, view) = crate::sim::heights::mesh_rest(job, &sim, TOP_VIEW_SIDE);
        rp.top_view = Some(view);
        Ok((rp, rest))
    })
}
