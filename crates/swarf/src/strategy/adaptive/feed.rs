//! The feed of paper 1 §5: higher where the engagement is low (chip thinning made up by
//! `1 / sin θ`, up to the boost), changing gradually along the pass; and the pass emitted with
//! it (simplified by Douglas–Peucker, §5.1, and arc-fitted).

use super::engine::Engine;
use crate::geom::simplify::douglas_peucker;
use crate::geom::{DVec2, polyline_length};
use crate::plan::feed::{feed_factor, smoothed_runs};
use crate::plan::{DP_TOL, Material};
use crate::toolpath::MoveKind;

impl<'a, 'b, M: Material> Engine<'a, 'b, M> {
    /// Simplifies, arc-fits and appends the pass (the material was cut step by step already),
    /// with the engagement-driven feed of §5 when it is on.
    pub(super) fn emit(&mut self, pts: &[DVec2], rem: &[u32], z: f64) {
        if pts.len() < 2 || polyline_length(pts) < 1e-6 {
            return;
        }
        // the material model was cut step by step: do not cut it again
        self.l.precut = true;
        let base = self.l.feed;
        let (res, d, boost) = (self.l.sim.grid().res, self.l.job.cutting.tool.diameter, self.l.boost());
        for (run, m) in feed_runs(pts, rem, res, self.c.r, d, boost) {
            let simple = douglas_peucker(&run, DP_TOL);
            self.l.fit_emit_feed(&simple, z, MoveKind::Cut, base * m);
        }
        self.l.precut = false;
    }
}

/// Splits a pass into runs of one feed multiplier (paper 1 §5: higher feed where the engagement
/// is low, changing gradually). The engagement of each step is read off the material it
/// removed: `cells·res² / length` is the radial depth `a` of a straight cut, `θ = acos(1 − a/R)`.
/// The multiplier at a point is the smallest of those within one tool diameter ahead along the
/// pass (so the feed is back down a diameter before the engagement rises, and a stretch of low
/// engagement shorter than a diameter between two heavier ones keeps the lower feed: the
/// smoothing §5 asks for), rounded down to a twentieth (a tenth gave away up to 8 % of the feed
/// chip thinning allows: 1.2 at 53°, where it allows 1.25); where the engagement falls the feed
/// rises at once (the chip only thins there); `boost ≤ 1` gives one run at the programmed feed.
fn feed_runs(pts: &[DVec2], rem: &[u32], res: f64, r: f64, d: f64, boost: f64) -> Vec<(Vec<DVec2>, f64)> {
    if boost <= 1.0 + 1e-9 || pts.len() < 2 || rem.len() != pts.len() {
        return vec![(pts.to_vec(), 1.0)];
    }
    let n = pts.len();
    let mut m = vec![1.0; n];
    for i in 1..n {
        let len = (pts[i] - pts[i - 1]).length();
        let a = if len > 1e-9 { rem[i] as f64 * res * res / len } else { 0.0 };
        let theta = (1.0 - (a / r).min(2.0)).clamp(-1.0, 1.0).acos();
        m[i] = feed_factor(theta, boost);
    }
    smoothed_runs(pts, m, d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn feed_factor_makes_up_chip_thinning_within_the_boost() {
        assert_eq!(feed_factor(FRAC_PI_2, 2.0), 1.0);
        assert_eq!(feed_factor(2.0, 2.0), 1.0);
        assert!((feed_factor(60f64.to_radians(), 2.0) - 1.0 / 60f64.to_radians().sin()).abs() < 1e-12);
        assert_eq!(feed_factor(0.0, 1.6), 1.6);
        assert_eq!(feed_factor(10f64.to_radians(), 1.6), 1.6);
    }

    /// Cells of 0.05 mm, a tool of radius 3 (diameter 6), steps of 0.6 mm.
    const RES: f64 = 0.05;
    const R: f64 = 3.0;
    const STEP: f64 = 0.6;

    /// A straight pass along x of `n` steps, each cutting at radial depth 1.5 mm (θ 60°) where
    /// `cutting` says of its end, else nothing: its points and the cells each step removed.
    fn straight(n: usize, cutting: impl Fn(f64) -> bool) -> (Vec<DVec2>, Vec<u32>) {
        let pts: Vec<DVec2> = (0..=n).map(|i| DVec2::new(i as f64 * STEP, 0.0)).collect();
        let cells = (1.5 * STEP / (RES * RES)).round() as u32;
        let rem = pts.iter().map(|p| if cutting(p.x) { cells } else { 0 }).collect();
        (pts, rem)
    }

    #[test]
    fn feed_runs_rise_in_air_and_come_down_a_diameter_before_the_cut() {
        // 20 mm of air, then 20 mm of cut
        let (d, step) = (2.0 * R, STEP);
        let (pts, rem) = straight(66, |x| x > 20.0);
        let runs = feed_runs(&pts, &rem, RES, R, d, 1.5);
        // off: one run at the programmed feed
        assert_eq!(feed_runs(&pts, &rem, RES, R, d, 1.0).len(), 1);
        // the air gets the full boost, the cut 1 / sin 60° = 1.155 rounded down to 1.15
        assert_eq!(runs.first().unwrap().1, 1.5);
        assert_eq!(runs.last().unwrap().1, 1.15);
        // the feed is down before the cut starts: the boosted run ends a diameter before 20 mm
        let end_fast = runs[0].0.last().unwrap().x;
        assert!(end_fast <= 20.0 - d + step + 1e-9, "{end_fast}");
        // the runs join end to start, in order, and cover the pass
        for w in runs.windows(2) {
            assert_eq!(w[0].0.last(), w[1].0.first());
        }
        assert_eq!(runs[0].0[0], pts[0]);
        assert_eq!(*runs.last().unwrap().0.last().unwrap(), *pts.last().unwrap());
        // never above the boost, never below the programmed feed
        assert!(runs.iter().all(|(_, m)| (1.0..=1.5).contains(m)));
    }

    #[test]
    fn feed_runs_rise_where_the_cut_ends_and_stay_down_between_close_cuts() {
        let (d, step) = (2.0 * R, STEP);
        // cut to 20 mm, air to 40, cut from 40 to 43.2, air to 45.6 (shorter than a diameter),
        // cut again from 45.6
        let (pts, rem) = straight(100, |x| x <= 20.0 || (x > 40.0 && x <= 43.2) || x > 45.6);
        let runs = feed_runs(&pts, &rem, RES, R, d, 1.5);
        let fast: Vec<_> = runs.iter().filter(|(_, m)| *m == 1.5).collect();
        // one boosted run: from the step after the first cut's end, down a diameter before the
        // second cut; the air between the second and third cuts keeps the cutting feed
        assert_eq!(fast.len(), 1, "{runs:?}");
        let (start, end) = (fast[0].0[0].x, fast[0].0.last().unwrap().x);
        assert!(start <= 20.0 + 1e-9, "the feed rises at {start}, not where the cut ends");
        assert!(end <= 40.0 - d + step + 1e-9, "{end}");
    }
}
