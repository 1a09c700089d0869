//! Clearing strategies. Each one takes the regions of a level and returns *passes*: tool-centre
//! polylines in cutting order. Entries, links, retracts and the move list are added by
//! [`crate::plan`], the same for every strategy.
//!
//! - [`offset`]: contour-parallel offsets of the part (inside-out or outside-in);
//! - [`zigzag`]: direction-parallel rows at a settable angle, with a contour along the walls;
//! - [`cleanup`]: extra passes where the others left material the tool can reach.

pub mod cleanup;
pub mod offset;
pub mod zigzag;

pub mod adaptive;
pub mod medial;
pub mod spiral;
pub mod spiral_search;

use crate::error::Result;
use crate::model::{Job, REGION_TOL, Regions};
pub use crate::plan::{
    LANDING_MARGIN, LayerGeom, OffsetOrder, Params, Pass, PassKind, StrategyKind, TOUCH_MARGIN, wall_margin,
};

/// The passes of `strategy` for one level (the same at every level of a 2.5D job).
pub fn passes(job: &Job, geom: &LayerGeom, params: &Params) -> Result<Vec<Pass>> {
    let mut out = match params.strategy {
        // adaptive and medial programs are made while linking (the adaptive passes depend on
        // the material left; the medial path is made of exact arcs)
        StrategyKind::Adaptive | StrategyKind::Medial | StrategyKind::Spiral => Vec::new(),
        StrategyKind::Offset => offset::passes(geom, params),
        StrategyKind::Zigzag => zigzag::passes(geom, params),
    };
    if matches!(params.strategy, StrategyKind::Adaptive | StrategyKind::Medial | StrategyKind::Spiral) {
        return Ok(out);
    }
    let t = std::time::Instant::now();
    let extra = cleanup::passes(geom, params, &out);
    if std::env::var("SWARF_DEBUG").is_ok() {
        eprintln!("cleanup {:.3} s, {} passes", t.elapsed().as_secs_f64(), extra.len());
    }
    out.extend(extra);
    let _ = job;
    Ok(out)
}

/// The finishing contour passes (walls at exactly the tool radius plus the fitting margin).
pub fn finish_passes(job: &Job, regions: &Regions, params: &Params) -> Vec<Pass> {
    let r = job.radius();
    let level = r + wall_margin(params);
    let touch = regions.material.offset(r + TOUCH_MARGIN, REGION_TOL);
    offset::level_passes(&regions.keep, level, &touch, params, true, PassKind::Finish)
}
