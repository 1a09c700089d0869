//! Clearing strategies: what the tool does at each level of a 2.5D job. Entries, links,
//! retracts and the move list are the linker's ([`crate::plan`]), the same for every strategy;
//! the levels are walked by one driver (the linker's level driver, `plan::levels`).
//!
//! One [`Strategy`] value names the strategy and carries its own options:
//!
//! - [`adaptive`]: adaptive clearing with a bound on tool engagement (paper 1), the default;
//! - [`offset`]: contour-parallel offsets of the part (inside-out or outside-in);
//! - [`zigzag`]: direction-parallel rows at a settable angle, with a contour along the walls;
//! - [`medial`]: tangent-continuous circles along the medial axis (paper 2);
//! - [`spiral`]: one oscillator spiral from the inside out to the walls (paper 4), its damping
//!   and start chosen by the spiral search (`spiral_search`);
//! - `cleanup`: extra passes where the others left material the tool can reach.
//!
//! A strategy is added by writing its file (its options struct, which implements the
//! crate-internal `Clearing` trait) and one arm of [`Strategy`] (and of the `each!` dispatch
//! below).

pub mod adaptive;
#[doc(hidden)]
pub mod cleanup;
pub mod five;
pub mod medial;
pub mod offset;
pub mod spiral;
#[doc(hidden)]
pub mod spiral_search;
pub mod zigzag;

pub use adaptive::AdaptiveOptions;
pub use medial::MedialOptions;
pub use offset::{OffsetOptions, OffsetOrder};
pub use spiral::SpiralOptions;
pub use zigzag::ZigzagOptions;

use crate::error::Result;
use crate::model::{Job, REGION_TOL, Regions};
use crate::plan::{LayerGeom, LinkOptions, Pass, PassKind, TOUCH_MARGIN};
use crate::sim::{Replay, Rest, SimOptions};
use crate::toolpath::Toolpath;

/// A clearing strategy with its options.
#[derive(Debug, Clone, PartialEq)]
pub enum Strategy {
    /// Adaptive clearing with a bound on tool engagement (paper 1).
    Adaptive(AdaptiveOptions),
    /// Contour-parallel offsets.
    Offset(OffsetOptions),
    /// Direction-parallel zigzag.
    Zigzag(ZigzagOptions),
    /// Tangent-continuous circles along the medial axis (paper 2).
    Medial(MedialOptions),
    /// One oscillator spiral from the inside out to the walls (paper 4).
    Spiral(SpiralOptions),
}

/// Calls `$e` with `$o` bound to the options of whichever strategy `$s` is.
macro_rules! each {
    ($s:expr, $o:ident => $e:expr) => {
        match $s {
            Strategy::Adaptive($o) => $e,
            Strategy::Offset($o) => $e,
            Strategy::Zigzag($o) => $e,
            Strategy::Medial($o) => $e,
            Strategy::Spiral($o) => $e,
        }
    };
}

/// Everything a strategy plans a 2.5D job's levels from.
pub(crate) struct Context<'a> {
    /// The job.
    pub job: &'a Job,
    /// Its regions for the tool.
    pub regions: &'a Regions,
    /// The roughing geometry of a level.
    pub geom: &'a LayerGeom,
    /// How passes are linked.
    pub link: &'a LinkOptions,
    /// The planning model's settings.
    pub sim: &'a SimOptions,
    /// The levels, top down.
    pub zs: &'a [f64],
    /// The finishing passes of each level, cut after all the roughing.
    pub finish: &'a [(f64, Vec<Pass>)],
}

/// A strategy's program of every level, with the simulation of it as it will be written when
/// the strategy already made one (the spiral's search simulates its choice): the job then uses
/// it as its proof instead of simulating the program again.
pub(crate) struct Program {
    /// The program.
    pub toolpath: Toolpath,
    /// Its replay and rest on the job's material model, with the job's simulation settings.
    pub proof: Option<(Replay, Rest)>,
    /// Seconds the strategy spent making `proof` (reported as proving, not planning).
    pub proof_s: f64,
}

impl From<Toolpath> for Program {
    fn from(toolpath: Toolpath) -> Program {
        Program { toolpath, proof: None, proof_s: 0.0 }
    }
}

/// What each strategy's options do (the one thing a new strategy's file implements).
pub(crate) trait Clearing {
    /// Its name (on the command line, in reports and program headers).
    const NAME: &'static str;
    /// Checks its options.
    fn validate(&self) -> Result<()> {
        Ok(())
    }
    /// How much farther than the arc tolerance its passes may come to the walls before arc
    /// fitting, mm (the walls are kept that much further away).
    fn wall_slack(&self) -> f64 {
        0.0
    }
    /// The program of every level, or `None` when the strategy finds nothing to cut.
    fn plan(&self, cx: &Context) -> Result<Option<Program>>;
}

impl Strategy {
    /// The default strategy: adaptive with its default options.
    pub const DEFAULT: Strategy = Strategy::Adaptive(AdaptiveOptions::DEFAULT);

    /// The names of the strategies, the default first.
    pub const NAMES: [&'static str; 5] = [
        <AdaptiveOptions as Clearing>::NAME,
        <OffsetOptions as Clearing>::NAME,
        <ZigzagOptions as Clearing>::NAME,
        <MedialOptions as Clearing>::NAME,
        <SpiralOptions as Clearing>::NAME,
    ];

    /// The strategy of that name, with its default options.
    pub fn from_name(name: &str) -> Option<Strategy> {
        [
            Strategy::DEFAULT,
            Strategy::Offset(OffsetOptions::DEFAULT),
            Strategy::Zigzag(ZigzagOptions::DEFAULT),
            Strategy::Medial(MedialOptions::DEFAULT),
            Strategy::Spiral(SpiralOptions::DEFAULT),
        ]
        .into_iter()
        .find(|s| s.name() == name)
    }

    /// Its name.
    pub fn name(&self) -> &'static str {
        fn name_of<C: Clearing>(_: &C) -> &'static str {
            C::NAME
        }
        each!(self, o => name_of(o))
    }

    /// Checks its options.
    pub fn validate(&self) -> Result<()> {
        each!(self, o => o.validate())
    }

    /// How much farther than its radius the tool axis stays from the walls (mm): the
    /// arc-fitting tolerance plus a micrometre, so that no fitted arc comes closer than the
    /// radius, plus the strategy's own slack (the adaptive passes' Douglas–Peucker tolerance).
    pub fn wall_margin(&self, link: &LinkOptions) -> f64 {
        link.arc_tol + 0.001 + each!(self, o => o.wall_slack())
    }

    /// The adaptive options the strategy clears with (the adaptive strategy's, and those of the
    /// adaptive passes a spiral leaves round islands to), if any.
    pub fn adaptive_mut(&mut self) -> Option<&mut AdaptiveOptions> {
        match self {
            Strategy::Adaptive(o) => Some(o),
            Strategy::Spiral(o) => Some(&mut o.adaptive),
            _ => None,
        }
    }

    /// The program of every level of a 2.5D job, or `None` when the strategy finds nothing to
    /// cut.
    pub(crate) fn plan(&self, cx: &Context) -> Result<Option<Program>> {
        each!(self, o => o.plan(cx))
    }
}

impl Default for Strategy {
    fn default() -> Self {
        Strategy::DEFAULT
    }
}

/// The finishing contour passes (walls at exactly the tool radius plus `wall_margin`).
pub fn finish_passes(job: &Job, regions: &Regions, link: &LinkOptions, wall_margin: f64) -> Vec<Pass> {
    let r = job.radius();
    let level = r + wall_margin;
    let touch = regions.material.offset(r + TOUCH_MARGIN, REGION_TOL);
    offset::level_passes(&regions.keep, level, &touch, link.climb, true, PassKind::Finish)
}

/// Passes that are the same at every level, with the clean-up passes for what they leave, as a
/// program (`None` when there are none).
fn same_passes(cx: &Context, mut passes: Vec<Pass>) -> Result<Option<Program>> {
    let t = std::time::Instant::now();
    let extra = cleanup::passes(cx.geom, cx.link.climb, &passes);
    log::debug!("cleanup {:.3} s, {} passes", t.elapsed().as_secs_f64(), extra.len());
    passes.extend(extra);
    if passes.is_empty() {
        return Ok(None);
    }
    let mut levels = crate::plan::levels::SamePasses { passes: &passes };
    crate::plan::levels::drive(cx.job, cx.regions, cx.link, cx.sim, cx.zs, cx.finish, &mut levels)
        .map(|tp| Some(tp.into()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_the_default_is_adaptive() {
        for n in Strategy::NAMES {
            assert_eq!(Strategy::from_name(n).map(|s| s.name()), Some(n));
        }
        assert_eq!(Strategy::default().name(), "adaptive");
        assert_eq!(Strategy::from_name("trochoidal"), None);
    }

    #[test]
    fn the_wall_margin_adds_the_adaptive_slack() {
        let link = LinkOptions::DEFAULT;
        let a = Strategy::DEFAULT.wall_margin(&link);
        let o = Strategy::from_name("offset").map(|s| s.wall_margin(&link));
        assert_eq!(o, Some(link.arc_tol + 0.001));
        assert!((a - (link.arc_tol + 0.001 + crate::plan::DP_TOL)).abs() < 1e-15);
    }
}
