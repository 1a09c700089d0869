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

/// The material model the levels' pieces are linked on has cells this many times the
/// planning's to a side. Linking cuts the whole program into it once more: on a ninth of the
/// cells that costs a ninth (stl_textbox: 2.7 s of 14.5 s of planning on the planning's cells).
/// Its links are checked against the surely cut heights (the tool's radius less half a cell's
/// diagonal, [`SimOptions::sure_links`]) and against the part's outline at each level
/// ([`super::zorder::Keeps`]), so a coarser cell only keeps them a little further from the
/// material; the proof replays the program on the fine cells.
const LINK_CELL: f64 = 3.0;

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
            let heights = Arc::new(HeightMap { grid: state.grid, stock: state.heights().to_vec(), part: None });
            let lopts = RoughOptions {
                // (rapids at depth cross whole levels of cleared stock: checked against the
                // surely cut heights)
                sim: SimOptions { heights: Some(heights.clone()), sure_links: true, ..level_opts.sim.clone() },
                ..level_opts.clone()
            };
            // The level's program is cut into the material of the levels below while it is
            // planned, piece by piece as the linker makes it (the planner works on its own copy
            // of the heights); `cut` is what was cut, and whether it is the whole program.
            let (planned, cut) = std::thread::scope(|s| {
                let (tx, rx) = std::sync::mpsc::channel();
                let state = &mut state;
                let cutter = s.spawn(move || cut_alongside(state, rx));
                let unstream = crate::plan::linker::stream_next_program(Some(tx.clone()));
                let planned = geometry.and_then(|(regions, geom)| super::rough::plan_on(&lj, &lopts, regions, &geom));
                drop(unstream);
                if let Ok(Some(p)) = &planned {
                    let _ = tx.send(crate::plan::linker::Streamed::End(p.toolpath.clone()));
                }
                drop(tx);
                let cut = cutter.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
                (planned, cut)
            });
            let planned = match planned {
                Ok(p) => p,
                // a level with nothing the tool can reach
                Err(Error::Job { .. }) if lj.regions(job.radius(), 0.0).map_or(true, |r| r.reachable.is_empty()) => {
                    None
                }
                Err(e) => return Err(e),
            };
            let Some(p) = planned else {
                restore(&mut state, job, &opts.sim, &heights, cut, None)?;
                continue;
            };
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
                restore(&mut state, job, &opts.sim, &heights, cut, None)?;
                continue;
            }
            restore(&mut state, job, &opts.sim, &heights, cut, Some(&tp))?;
            done.push(z);
            levels.push((z, tp));
        }
        Ok(())
    })?;
    progress(1.0);
    // the pieces of the levels in order, region by region, on the material model of the whole
    // job (the links checked against the surely cut heights, as the levels' own)
    // (on cells LINK_CELL times the planning's: the links read only the surely cut heights,
    // which a coarser cell keeps on the safe side, and the part from its exact outline)
    let link_sim = SimOptions { sure_links: true, res: Some(LINK_CELL * cell), ..opts.sim.clone() };
    let mut model = crate::sim::heights::mesh_model(job, &link_sim)?;
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

/// What [`cut_alongside`] cut into the material: how many moves, and whether they are the
/// level's whole program.
#[derive(Debug, Clone, Copy)]
struct Cut {
    moves: usize,
    whole: bool,
}

/// Cuts a level's program into `state` as its linker sends it
/// ([`crate::plan::linker::stream_next_program`]): each piece as it comes, then, once the
/// program is planned, its tail. The whole program only when the pieces are its beginning.
/// The cuts are the ones [`crate::sim::RasterSim::cut_moves`] makes of the whole program, one
/// move after the other, so the material is the same.
fn cut_alongside(
    state: &mut crate::sim::RasterSim,
    rx: std::sync::mpsc::Receiver<crate::plan::linker::Streamed>,
) -> Cut {
    use crate::plan::linker::Streamed;
    let mut received = crate::plan::linker::Received::default();
    for s in rx {
        match s {
            Streamed::Piece { start, moves } => {
                state.cut_moves(start, &moves);
                received.piece(start, moves);
            }
            Streamed::End(tp) => {
                let Some((at, tail)) = received.tail(&tp) else {
                    log::debug!("the moves cut alongside the planning are not the level's beginning");
                    break;
                };
                log::trace!("{} of {} moves cut alongside the planning", received.len(), tp.moves.len());
                state.cut_moves(at, tail);
                return Cut { moves: tp.moves.len(), whole: true };
            }
        }
    }
    Cut { moves: received.len(), whole: false }
}

/// Leaves in `state` (a model of `job` made with `sim`) the material of `before` cut by
/// `program` (none: not cut): what [`cut_alongside`] cut where that is it, else the model made
/// again from `before` and cut by the program.
fn restore(
    state: &mut crate::sim::RasterSim,
    job: &MeshJob,
    sim: &SimOptions,
    before: &HeightMap,
    cut: Cut,
    program: Option<&Toolpath>,
) -> Result<()> {
    match program {
        Some(_) if cut.whole => return Ok(()),
        None if cut.moves == 0 => return Ok(()),
        _ => {}
    }
    // (rare: a strategy whose program is not its linker's, or a level with nothing to cut)
    log::debug!("the level's material is cut again after its planning");
    let mut again = crate::sim::heights::mesh_model_after(job, &job.cutting.tool, Some(before), sim)?;
    again.track_exact = false;
    if let Some(tp) = program {
        again.cut_moves(tp.start, &tp.moves);
    }
    *state = again;
    Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::linker::send_in_pieces;
    use crate::{Input, Overrides, load_input};

    /// A program cut into the material piece by piece as it is planned, then its tail: the
    /// material its whole cut after the planning leaves, to the bit. Pieces that are not the
    /// program's beginning (one move off by half a millimetre) are not the whole, and the
    /// material made again from the heights before them and cut by the program is that same
    /// material.
    #[test]
    fn a_level_cut_alongside_its_planning_is_the_level_cut_after_it() {
        let case = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/3d/bowl_cavity.json");
        let Ok(Input::Mesh(job)) = load_input(case.as_ref(), &Overrides::DEFAULT) else { panic!("the example") };
        let opts = RoughOptions { simulate: false, ..RoughOptions::DEFAULT };
        let (tp, _) = plan(&job, &opts, &mut |_| {}).expect("planned");
        assert!(tp.moves.len() > 2000, "{} moves", tp.moves.len());
        let fresh = || {
            let mut m = crate::sim::heights::mesh_model(&job, &opts.sim).expect("the model");
            m.track_exact = false;
            m
        };
        let mut after = fresh();
        after.cut_moves(tp.start, &tp.moves);
        let fed = |off: f64| {
            let mut m = fresh();
            let cut = cut_alongside(&mut m, send_in_pieces(&tp, off));
            (m, cut)
        };
        let (m, cut) = fed(0.0);
        assert!(cut.whole && cut.moves == tp.moves.len(), "{cut:?}");
        assert!(m.heights() == after.heights(), "the same material");
        let (mut m, cut) = fed(0.5);
        assert!(!cut.whole, "{cut:?}");
        assert!(m.heights() != after.heights());
        let before = fresh();
        let before = HeightMap { grid: before.grid, stock: before.heights().to_vec(), part: None };
        restore(&mut m, &job, &opts.sim, &before, cut, Some(&tp)).expect("made again");
        assert!(m.heights() == after.heights(), "the same material made again");
    }
}
