//! Adaptive clearing with a stated bound on tool engagement — paper 1 (Dumitrache, Borangiu &
//! Dogar), built on swarf's raster material model. Level by level, the state machine of §4.1
//! (Fig. 5) finds a start (§4.5: a resume point, a lateral entry, a helix or a ramp, a plunge as
//! the last resort), mills at constant engagement (§4.3, Algorithm 1: the tool's circumference
//! sampled by eqs. 5–7, the direction of eqs. 8–9 for climb milling and 10–11 for conventional,
//! checked and corrected by regula falsi on the heading), follows the offset contour of the walls
//! where a step would come closer than the radius to the part (§4.4), and raises the feed where
//! the engagement is low (§5); clean-up passes take what the passes leave. The walk-through of
//! the paper and of swarf's additions to it (thresholds, the adaptive step length, the starts,
//! the links, the feed) is in `docs/adaptive.md`.
//!
//! ```text
//! ┌──► find a start (§4.5) ──── none left: the level is done
//! │      resume point · lateral entry · helix · ramp · plunge
//! │                 │
//! │                 ▼
//! │      constant engagement (§4.3) ── a step comes closer than R to the part ──┐
//! │                 │       ▲                                                   ▼
//! │                 │       └── engagement ahead too high: resume point ── contour (§4.4)
//! │                 ▼                                                           │
//! └────────── pass ends ◄───────── air, contour complete, too heavy ────────────┘
//!       (no material, too heavy, air)
//! ```
//!
//! The engine is split by concern: `engine` (the state machine of a level, its vocabulary, what
//! stays the same from level to level, the clearance from the walls), `start` (start finding), `walls` (the offset
//! contours), `step` (one constant-engagement step and its regula falsi), `feed` (§5 and the
//! emission of a pass). It talks to the material model only through the planner's narrow trait
//! (`plan::material::Material`) and to the program through the linker.

mod engine;
mod feed;
mod start;
mod step;
mod walls;

use super::{Clearing, Context, Program};
use crate::error::{Error, Result, Setting};
use crate::geom::DVec2;
use crate::model::Job;
use crate::plan::levels::{Levels, drive};
use crate::plan::{DP_TOL, LayerGeom, Linker};
use engine::{Engine, Setup};

/// How much above the reference a constant-engagement step may read before it is steered away
/// from the material, degrees.
const STEP_SLACK_DEG: f64 = 3.0;
/// Largest engagement above the reference that contouring tolerates before it switches back
/// to constant engagement, degrees.
const CONTOUR_SLACK_DEG: f64 = 5.0;
/// Engagement above the reference at which a constant-engagement step that cannot turn
/// further from the material is not taken, degrees.
const HEAVY_DEG: f64 = 10.0;
/// The heading search of a constant-engagement step stops when the heading that does not exceed
/// the reference reads within this of it (about a pixel of the ring: 360° / 2π(R/res + ½))…
const SETTLE_DEG: f64 = 1.5;
/// …or when its bracket is narrower than this (radians; 0.7°).
const BRACKET_RAD: f64 = 0.7 * std::f64::consts::PI / 180.0;
/// Engagement below which contouring counts as cutting air, degrees.
const AIR_DEG: f64 = 3.0;
/// A helix start is made only where at least this share of the tool's disk in material stands
/// within a tool diameter of its centre.
const HELIX_MIN_SHARE: f64 = 0.05;
/// Degrees skipped at the tool's side when looking for the engaged arc (eq. 8).
const SIDE_SKIP: f64 = 15.0;

/// The adaptive strategy's options (paper 1).
#[derive(Debug, Clone, PartialEq)]
pub struct AdaptiveOptions {
    /// How far above the reference engagement contouring along a wall may go before the tool
    /// turns back to constant-engagement milling (paper 1 §4.4), degrees, in [0°, 90°].
    pub overshoot_deg: f64,
    /// Clean-up: round the wall contour's inside corners (a fillet of at most 0.15 R that holds
    /// the engagement there down and leaves a sliver of at most 0.3 % of the reachable area).
    /// Off for z-level jobs, where the slivers of every level stack into a wall corner a whole
    /// depth tall.
    pub corner_fillets: bool,
    /// Clean-up: contour every wall at every level, not only near the material the passes left
    /// as the planner's raster sees it (a sliver thinner than a cell along a wall escapes it;
    /// z-level jobs stack such slivers into walls a whole depth tall).
    pub full_wall_contour: bool,
}

impl AdaptiveOptions {
    /// A 20° overshoot, fillets in the corners, the wall contour where material is left.
    pub const DEFAULT: AdaptiveOptions =
        AdaptiveOptions { overshoot_deg: 20.0, corner_fillets: true, full_wall_contour: false };
}

impl Default for AdaptiveOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl Clearing for AdaptiveOptions {
    const NAME: &'static str = "adaptive";

    fn validate(&self) -> Result<()> {
        if !(self.overshoot_deg >= 0.0 && self.overshoot_deg <= 90.0) {
            return Err(Error::setting(Setting::Overshoot, format!("{}°: must be in [0°, 90°]", self.overshoot_deg)));
        }
        Ok(())
    }

    /// Adaptive passes are also simplified (Douglas–Peucker) before arc fitting.
    fn wall_slack(&self) -> f64 {
        DP_TOL
    }

    fn plan(&self, cx: &Context) -> Result<Option<Program>> {
        let first = cx.geom.centres.bounds().map_or(DVec2::ZERO, |(lo, _)| lo);
        let mut levels = AdaptiveLevels::new(cx, self, first, |_: &mut Linker, _| {});
        drive(cx.job, cx.regions, cx.link, cx.sim, cx.zs, cx.finish, &mut levels).map(|tp| Some(tp.into()))
    }
}

/// The adaptive clearing of every level, after `before` has cut what it cuts at that level
/// (nothing for plain adaptive; the spiral over a pocket's island-free core for the spiral
/// strategy on a pocket with islands): the constant-engagement passes start from what the
/// material model says is left, and clean-up passes follow them at each level.
pub(super) struct AdaptiveLevels<'c, F> {
    job: &'c Job,
    geom: &'c LayerGeom,
    opts: &'c AdaptiveOptions,
    first: DVec2,
    setup: Option<Setup>,
    before: F,
    t0: std::time::Instant,
    done: usize,
}

impl<'c, F> AdaptiveLevels<'c, F> {
    pub(super) fn new(cx: &Context<'c>, opts: &'c AdaptiveOptions, first: DVec2, before: F) -> Self {
        AdaptiveLevels {
            job: cx.job,
            geom: cx.geom,
            opts,
            first,
            setup: None,
            before,
            t0: std::time::Instant::now(),
            done: 0,
        }
    }
}

impl<'a, F: FnMut(&mut Linker<'a>, f64)> Levels<'a> for AdaptiveLevels<'_, F> {
    fn first(&self) -> DVec2 {
        self.first
    }

    fn begin(&mut self, l: &mut Linker<'a>) -> Result<()> {
        l.clear_margin = 0.75 * l.sim.grid.res;
        // the clean-up's entries hold the bound the passes are held to
        l.entry_bound = Some(self.job.cutting.width.engagement_deg() + crate::report::BOUND_OVER_REF_DEG);
        // and their cutting is fed as the passes are (§5)
        l.thinned_feed = true;
        self.setup = Some(Setup::new(l, self.job, self.geom, self.opts));
        Ok(())
    }

    fn level(&mut self, l: &mut Linker<'a>, z: f64) -> Result<()> {
        let Some(setup) = &self.setup else { return Ok(()) };
        (self.before)(l, z);
        Engine::new(l, setup).level(z);
        self.done += 1;
        log::debug!("adaptive level {} done at {:.3} s", self.done, self.t0.elapsed().as_secs_f64());
        // what the constant-engagement passes left (read off the material model): clean-up
        // passes, before the next level so that neither they nor the next level's passes cut
        // deeper than one step-down
        let left = l.sim.material_area(z);
        if left.is_empty() && !self.opts.full_wall_contour {
            return Ok(());
        }
        let extra = super::cleanup::passes_for_leftover(self.geom, l.link.climb, self.opts, &left, l.sim.grid.res);
        if log::log_enabled!(log::Level::Debug) {
            log::debug!("leftover at z {z}: {:.2} mm2, {} clean-up passes", left.area(), extra.len());
            for ring in left.rings().filter(|r| crate::geom::ring_area(r).abs() > 0.5) {
                log::trace!("  piece of {:.2} mm2 at {:?}", crate::geom::ring_area(ring), ring[0]);
            }
        }
        if extra.is_empty() {
            return Ok(());
        }
        l.tp.note(format!("clean-up at z {z:.3}"));
        // (a tool still down at the level where the passes ended goes on from there: the
        // clean-up's first pass starts at its nearest point and is reached sideways if the
        // way is clear or short, as between passes)
        if (l.tp.end().z - z).abs() > 1e-9 {
            l.down_at = None;
        }
        for p in crate::plan::linker::order(&extra, l.tp.end().truncate()) {
            l.pass(p, z);
        }
        Ok(())
    }
}
