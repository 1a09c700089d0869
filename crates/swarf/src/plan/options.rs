//! What every strategy shares: the milling direction, entries, links and the finishing contour
//! ([`LinkOptions`]), with their defaults in one place ([`LinkOptions::DEFAULT`]).

use crate::error::{Error, Result, Setting};

/// How passes are joined into a program, the same for every strategy: the milling direction,
/// entries (helix, ramp, plunge), links and lifts, arc fitting, the stock left for a finishing
/// contour, and how far the feed may rise where the tool cuts little.
#[derive(Debug, Clone, PartialEq)]
pub struct LinkOptions {
    /// Climb milling (material on the tool's right with a clockwise spindle) or conventional.
    pub climb: bool,
    /// Radial stock the roughing passes leave on the walls for the finishing contour, mm.
    pub stock_to_leave: f64,
    /// Add a finishing contour at every level (removes `stock_to_leave`).
    pub finish: bool,
    /// Ramp and helix angle, degrees, in (0°, 45°].
    pub ramp_angle_deg: f64,
    /// Largest helix radius as a fraction of the tool radius, in (0, 1].
    pub helix_radius_frac: f64,
    /// Smallest helix radius as a fraction of the tool radius, in (0, `helix_radius_frac`].
    pub helix_min_frac: f64,
    /// Arc-fitting tolerance, mm, in (0, 0.5].
    pub arc_tol: f64,
    /// Clearance above the top of everything for travel, mm.
    pub clearance: f64,
    /// Height above material from which to start entries and descents, mm.
    pub approach: f64,
    /// Plunge feed as a fraction of the cutting feed, in (0, 1]. Descents to a level into free
    /// or cleared space (the tool touches nothing on the way down) run at the cutting feed.
    pub entry_feed_frac: f64,
    /// Helix and ramp feed as a fraction of the cutting feed, in (0, 1] (along the path: at a
    /// 3° ramp the tool descends at 5 % of it; FreeCAD's Adaptive and most CAM systems ramp at
    /// the cutting feed).
    pub ramp_feed_frac: f64,
    /// How far the feed may rise where the tool cuts little, in [1, 3] (1 = off), and never
    /// above the machine's highest feed ([`crate::model::Cutting::max_feed`]): links through
    /// cleared space at depth run at the feed times this; the adaptive strategy raises its feed
    /// where the engagement is low (chip thinning, paper 1 §5: the programmed chip thickness
    /// held) up to it; the medial strategy's cut-back returns run at it (paper 2).
    pub feed_boost: f64,
    /// Links through cleared space at depth as feed moves (G1 at the cutting feed, times the
    /// feed boost; lifted rapids when long) instead of rapids at depth (G0): for controls whose
    /// G0 does not move in a straight line.
    pub feed_links: bool,
    /// Z-level jobs: cut each level over the whole part before the next (the order the levels
    /// are planned in) instead of region by region through the levels (see
    /// `docs/zlevel.md`).
    pub by_level: bool,
}

impl LinkOptions {
    /// swarf's defaults: climb milling, no stock left and no finishing contour, 3° ramps and
    /// helices of 0.1–0.75 R, 2 µm arc fitting, 5 mm clearance, entries from 1 mm above the
    /// material, plunges at half the feed, ramps at the feed, the feed raised up to 3× where the
    /// tool cuts little, rapid links, z-levels region by region.
    pub const DEFAULT: LinkOptions = LinkOptions {
        climb: true,
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
        feed_boost: 3.0,
        feed_links: false,
        by_level: false,
    };

    /// Checks every value against its range.
    pub fn validate(&self) -> Result<()> {
        let bad = |setting, reason: String| Err(Error::setting(setting, reason));
        if !(self.stock_to_leave.is_finite()
            && self.stock_to_leave >= 0.0
            && self.stock_to_leave <= crate::limits::MAX_COORD_MM)
        {
            return bad(
                Setting::StockToLeave,
                format!(
                    "{} mm: must be zero or positive, at most {} mm",
                    self.stock_to_leave,
                    crate::limits::MAX_COORD_MM
                ),
            );
        }
        if !(self.ramp_angle_deg > 0.0 && self.ramp_angle_deg <= 45.0) {
            return bad(Setting::RampAngle, format!("{}°: must be in (0°, 45°]", self.ramp_angle_deg));
        }
        if !(self.helix_radius_frac > 0.0
            && self.helix_radius_frac <= 1.0
            && self.helix_min_frac > 0.0
            && self.helix_min_frac <= self.helix_radius_frac)
        {
            return bad(
                Setting::HelixRadius,
                format!(
                    "{} and {} of the tool radius: need 0 < smallest ≤ largest ≤ 1",
                    self.helix_min_frac, self.helix_radius_frac
                ),
            );
        }
        if !(self.arc_tol > 0.0 && self.arc_tol <= 0.5) {
            return bad(Setting::ArcTolerance, format!("{} mm: must be in (0, 0.5]", self.arc_tol));
        }
        if !(self.clearance.is_finite() && self.clearance > 0.0 && self.clearance <= crate::limits::MAX_COORD_MM) {
            return bad(
                Setting::Clearance,
                format!("{} mm: must be positive and at most {} mm", self.clearance, crate::limits::MAX_COORD_MM),
            );
        }
        if !(self.approach.is_finite() && self.approach > 0.0 && self.approach <= self.clearance) {
            return bad(Setting::Approach, format!("{} mm: must be positive and at most the clearance", self.approach));
        }
        for f in [self.entry_feed_frac, self.ramp_feed_frac] {
            if !(f > 0.0 && f <= 1.0) {
                return bad(Setting::EntryFeed, format!("{f}: a fraction of the feed must be in (0, 1]"));
            }
        }
        if !(self.feed_boost >= 1.0 && self.feed_boost <= 3.0) {
            return bad(Setting::FeedBoost, format!("{}: must be in [1, 3]", self.feed_boost));
        }
        Ok(())
    }
}

impl Default for LinkOptions {
    fn default() -> Self {
        LinkOptions::DEFAULT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_are_valid_and_each_range_is_checked() {
        assert!(LinkOptions::DEFAULT.validate().is_ok());
        let d = LinkOptions::DEFAULT;
        for (o, want) in [
            (LinkOptions { stock_to_leave: -0.1, ..d.clone() }, Setting::StockToLeave),
            (LinkOptions { ramp_angle_deg: 90.0, ..d.clone() }, Setting::RampAngle),
            (LinkOptions { helix_min_frac: 0.9, ..d.clone() }, Setting::HelixRadius),
            (LinkOptions { arc_tol: 0.0, ..d.clone() }, Setting::ArcTolerance),
            (LinkOptions { clearance: f64::INFINITY, ..d.clone() }, Setting::Clearance),
            (LinkOptions { approach: 10.0, ..d.clone() }, Setting::Approach),
            (LinkOptions { entry_feed_frac: 0.0, ..d.clone() }, Setting::EntryFeed),
            (LinkOptions { feed_boost: 0.5, ..d.clone() }, Setting::FeedBoost),
        ] {
            match o.validate() {
                Err(Error::Setting { setting, .. }) => assert_eq!(setting, want),
                other => panic!("{want:?}: {other:?}"),
            }
        }
    }
}
