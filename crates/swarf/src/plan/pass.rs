//! What strategies hand the linker: passes (tool-centre polylines in cutting order), the
//! geometry of a level they are made from, and the parameters of both.

use crate::error::Result;
use crate::geom::{Area, DVec2};
use crate::model::{Job, REGION_TOL, Regions};

/// Douglas–Peucker tolerance for adaptive passes, mm.
pub const DP_TOL: f64 = 0.002;

/// Passes start and end this far (mm) outside the material, so that the tool lands beside it
/// and enters sideways.
pub const TOUCH_MARGIN: f64 = 0.03;

/// A tool may descend vertically where no material stands within this distance of its axis
/// beyond its radius (mm); below [`TOUCH_MARGIN`], so pass ends in the air qualify.
pub const LANDING_MARGIN: f64 = 0.02;

/// How much farther than its radius the tool axis stays from the walls (mm): the arc-fitting
/// tolerance plus a micrometre, so that no fitted arc comes closer than the radius.
pub fn wall_margin(params: &Params) -> f64 {
    // adaptive passes are also simplified (Douglas–Peucker) before arc fitting (and a spiral
    // over a pocket with islands leaves the rest to adaptive passes)
    let dp = if matches!(params.strategy, StrategyKind::Adaptive | StrategyKind::Spiral) { DP_TOL } else { 0.0 };
    params.arc_tol + 0.001 + dp
}

/// The strategies swarf has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StrategyKind {
    /// Adaptive clearing with a bound on tool engagement (paper 1).
    Adaptive,
    /// Contour-parallel offsets.
    Offset,
    /// Direction-parallel zigzag.
    Zigzag,
    /// Tangent-continuous circles along the medial axis (paper 2).
    Medial,
    /// One oscillator spiral from the inside out to the walls (paper 4).
    Spiral,
}

impl StrategyKind {
    /// Parses a strategy name.
    pub fn parse(s: &str) -> Option<StrategyKind> {
        match s {
            "adaptive" => Some(StrategyKind::Adaptive),
            "offset" | "contour" => Some(StrategyKind::Offset),
            "zigzag" | "raster" => Some(StrategyKind::Zigzag),
            "medial" | "mat" => Some(StrategyKind::Medial),
            "spiral" => Some(StrategyKind::Spiral),
            _ => None,
        }
    }
    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            StrategyKind::Adaptive => "adaptive",
            StrategyKind::Offset => "offset",
            StrategyKind::Zigzag => "zigzag",
            StrategyKind::Medial => "medial",
            StrategyKind::Spiral => "spiral",
        }
    }
}

/// Order of contour-parallel passes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OffsetOrder {
    /// From the farthest pass toward the walls (pocket centre first, walls last; on an open
    /// side, from the free edge of the stock toward the part).
    InsideOut,
    /// From the walls outward (the wall pass first).
    OutsideIn,
}

/// Parameters shared by the strategies and the linker.
#[derive(Debug, Clone, PartialEq)]
pub struct Params {
    /// Strategy.
    pub strategy: StrategyKind,
    /// Climb milling (material on the tool's right with a clockwise spindle) or conventional.
    pub climb: bool,
    /// Order of offset passes.
    pub offset_order: OffsetOrder,
    /// Zigzag row angle, degrees from +X.
    pub zigzag_angle_deg: f64,
    /// Radial stock the roughing passes leave on the walls for the finishing contour, mm.
    pub stock_to_leave: f64,
    /// Add a finishing contour at every level (removes `stock_to_leave`).
    pub finish: bool,
    /// Ramp and helix angle, degrees.
    pub ramp_angle_deg: f64,
    /// Largest helix radius as a fraction of the tool radius.
    pub helix_radius_frac: f64,
    /// Smallest helix radius as a fraction of the tool radius.
    pub helix_min_frac: f64,
    /// Arc-fitting tolerance, mm.
    pub arc_tol: f64,
    /// Clearance above the top of everything for travel, mm.
    pub clearance: f64,
    /// Height above material from which to start entries and descents, mm.
    pub approach: f64,
    /// Plunge feed as a fraction of the cutting feed. Descents to a level into free or
    /// cleared space (the tool touches nothing on the way down) run at the cutting feed.
    pub entry_feed_frac: f64,
    /// Helix and ramp feed as a fraction of the cutting feed (along the path: at a 3° ramp the
    /// tool descends at 5 % of it; FreeCAD's Adaptive and most CAM systems ramp at the cutting
    /// feed).
    pub ramp_feed_frac: f64,
    /// Adaptive: how far above the reference engagement contouring along a wall may go before
    /// the tool turns back to constant-engagement milling (paper 1 §4.4), degrees.
    pub overshoot_deg: f64,
    /// Adaptive: raise the feed where the engagement is low (paper 1 §5), up to this factor
    /// (1 = off).
    pub feed_boost: f64,
    /// Links through cleared space at depth as feed moves (G1 at the cutting feed, times the
    /// feed boost; lifted rapids when long) instead of rapids at depth (G0): for controls
    /// whose G0 does not move in a straight line.
    pub feed_links: bool,
    /// Adaptive clean-up: round the wall contour's inside corners (a fillet of at most 0.15 R
    /// that holds the engagement there down and leaves a sliver of at most 0.3 % of the
    /// reachable area). Off for z-level jobs, where the slivers of every level stack into a
    /// wall corner a whole depth tall.
    pub corner_fillets: bool,
    /// Adaptive clean-up: contour every wall at every level, not only near the material the
    /// passes left as the planner's raster sees it (a sliver thinner than a cell along a wall
    /// escapes it; z-level jobs stack such slivers into walls a whole depth tall).
    pub full_wall_contour: bool,
    /// Medial: return from each circle's new arc to the next circle on a smaller, "cut back"
    /// turn (paper 2 §2.1, Fig. 2c) instead of the circle's back half, which cuts nothing.
    pub medial_cut_back: bool,
    /// Spiral: a constant damping ζ (paper 4 eq. 6) instead of ζ chosen per level for the
    /// stepover and the engagement.
    pub spiral_zeta: Option<f64>,
    /// Spiral: start here instead of at the maximum of the region's implicit function.
    pub spiral_start: Option<crate::geom::DVec2>,
    /// Spiral, ζ per level: the least gap between turns the engagement limit may ask for where
    /// turns curve tightly, as a fraction of the stepover
    /// ([`crate::implicit::oscillator::EngagementLimit::floor`]); `None` (the default) tries
    /// [`crate::plan::spiral::FLOORS`] and keeps the fastest within the engagement bound
    /// ([`crate::strategy::spiral_search::optimise_spiral`]).
    pub spiral_floor: Option<f64>,
    /// Spiral: also try four other start points round the maximum of f (paper 4 §4, Figs.
    /// 8–9); the floor is chosen by simulation unless `spiral_floor` or `spiral_zeta` is set.
    pub spiral_optimise: bool,
}

impl Default for Params {
    fn default() -> Self {
        Self {
            strategy: StrategyKind::Adaptive,
            climb: true,
            offset_order: OffsetOrder::InsideOut,
            zigzag_angle_deg: 0.0,
            stock_to_leave: 0.0,
            finish: false,
            ramp_angle_deg: 3.0,
            helix_radius_frac: 0.75,
            helix_min_frac: 0.1,
            arc_tol: 0.002,
            clearance: 5.0,
            approach: 1.0,
            entry_feed_frac: 0.5,
            ramp_feed_frac: 1.0,
            overshoot_deg: 20.0,
            feed_boost: 1.0,
            feed_links: false,
            corner_fillets: true,
            full_wall_contour: false,
            medial_cut_back: true,
            spiral_zeta: None,
            spiral_start: None,
            spiral_floor: None,
            spiral_optimise: false,
        }
    }
}

/// What a pass is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PassKind {
    /// Clearing.
    Clear,
    /// Contour along the walls at the roughing offset.
    Contour,
    /// Clean-up of material left by the others.
    Cleanup,
    /// Finishing contour at the final offset.
    Finish,
}

/// One tool-centre polyline at a level, in cutting order.
#[derive(Debug, Clone, PartialEq)]
pub struct Pass {
    /// Points (for a closed pass the first point is not repeated).
    pub pts: Vec<DVec2>,
    /// A loop: the linker may start it anywhere and returns to the start.
    pub closed: bool,
    /// Purpose.
    pub kind: PassKind,
    /// Offset level (distance from the walls) it was made at, when it has one; used to order.
    pub level: f64,
    /// The pass may be cut in either direction (zigzag rows alternate anyway): the linker may
    /// reverse it to start from an end where the tool can land.
    pub reversible: bool,
}

/// Geometry of a level shared by the strategies.
#[derive(Debug, Clone)]
pub struct LayerGeom {
    /// Tool radius.
    pub r: f64,
    /// Stepover, mm.
    pub step: f64,
    /// Walls the roughing keeps away from: keep grown by the stock to leave.
    pub keep: Area,
    /// Offset of the first pass from `keep` (tool radius plus a margin for arc fitting).
    pub wall_level: f64,
    /// `keep` grown by `wall_level`: its rings are the wall contours.
    pub walls: Area,
    /// Where a tool centre touches material (material grown by `R − ε`).
    pub touch: Area,
    /// Where a tool centre may go for roughing: `touch` minus `keep` grown by `wall_level`.
    pub centres: Area,
    /// Material the roughing tool can reach.
    pub reachable: Area,
    /// The job's regions.
    pub regions: Regions,
}

impl LayerGeom {
    /// Derives the roughing geometry of a job.
    pub fn new(job: &Job, regions: &Regions, params: &Params) -> Result<LayerGeom> {
        let r = job.radius();
        let leave = if params.finish || params.stock_to_leave > 0.0 { params.stock_to_leave.max(0.0) } else { 0.0 };
        let keep = if leave > 0.0 { regions.keep.offset(leave, REGION_TOL) } else { regions.keep.clone() };
        let wall_level = r + wall_margin(params);
        let touch = regions.material.offset(r + TOUCH_MARGIN, REGION_TOL);
        // (the regions have it when nothing is left for finishing)
        let walls = if leave == 0.0 && regions.walls_at == wall_level {
            regions.walls.clone()
        } else {
            keep.offset(wall_level, REGION_TOL)
        };
        let centres =
            if keep.is_empty() { touch.clone() } else { touch.intersection(&regions.window.difference(&walls)) };
        let reachable = centres.offset(r, REGION_TOL).intersection(&regions.material).without_slivers(1e-6);
        Ok(LayerGeom {
            r,
            step: job.stepover_mm(),
            keep,
            wall_level,
            walls,
            touch,
            centres,
            reachable,
            regions: regions.clone(),
        })
    }
}

/// True when a ring is counter-clockwise.
pub(crate) fn ccw(ring: &[DVec2]) -> bool {
    crate::geom::ring_area(ring) > 0.0
}
