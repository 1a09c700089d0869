//! The feed of paper 1 §5 as multipliers of the programmed feed: chip thinning made up by
//! `1 / sin θ` below 90° of engagement, up to the boost, and a pass split into runs of one
//! multiplier, smoothed along it. The adaptive strategy feeds its passes by it (reading the
//! engagement off the cells each step removed) and the linker its clean-up
//! ([`super::Linker::emit_thinned`], the engagement measured ahead of the tool).

use crate::geom::DVec2;
use std::f64::consts::FRAC_PI_2;

/// Feed multiplier for engagement `theta` (radians) with the boost limit `boost`: chip thinning
/// — below 90° the thickest chip of a flat end mill is `f_z·sin θ` — is made up by `1 / sin θ`,
/// up to `boost`; air gets `boost`.
pub(crate) fn feed_factor(theta: f64, boost: f64) -> f64 {
    if theta >= FRAC_PI_2 { 1.0 } else { (1.0 / theta.sin().max(1e-9)).min(boost).max(1.0) }
}

/// The runs of one feed multiplier of a pass whose engagement was measured: `theta[i]`
/// (radians) is the engagement of the step ending at `pts[i]` (the adaptive strategy's
/// clean-up, whose moves the linker cuts into the model as it emits them; its own passes read
/// the engagement off the cells each step removed instead); `boost ≤ 1` gives one run at the
/// programmed feed.
pub(crate) fn feed_runs_by_engagement(pts: &[DVec2], theta: &[f64], d: f64, boost: f64) -> Vec<(Vec<DVec2>, f64)> {
    if boost <= 1.0 + 1e-9 || pts.len() < 2 || theta.len() != pts.len() {
        return vec![(pts.to_vec(), 1.0)];
    }
    smoothed_runs(pts, theta.iter().map(|&t| feed_factor(t, boost)).collect(), d)
}

/// The runs of one multiplier of a pass whose steps' multipliers are `m` (the step ending at
/// `pts[i]` has `m[i]`; `m[0]` is not read): each point takes the smallest within `d` ahead,
/// rounded down to a twentieth (the smoothing of paper 1 §5: the feed is back down a
/// diameter before the engagement rises).
pub(crate) fn smoothed_runs(pts: &[DVec2], mut m: Vec<f64>, d: f64) -> Vec<(Vec<DVec2>, f64)> {
    let n = pts.len();
    let mut s = vec![0.0; n];
    for i in 1..n {
        s[i] = s[i - 1] + (pts[i] - pts[i - 1]).length();
    }
    m[0] = m[1];
    // the smallest multiplier within d ahead along the pass
    let mut hi = 0;
    let mut sm = vec![1.0; n];
    for i in 0..n {
        hi = hi.max(i);
        while hi + 1 < n && s[hi + 1] - s[i] <= d {
            hi += 1;
        }
        let w = m[i..=hi].iter().copied().fold(f64::INFINITY, f64::min);
        sm[i] = ((w * 20.0 + 1e-9).floor() / 20.0).max(1.0);
    }
    // a step takes the multiplier of its end point; runs of equal multipliers
    let mut out: Vec<(Vec<DVec2>, f64)> = Vec::new();
    for i in 1..n {
        match out.last_mut() {
            Some((run, f)) if *f == sm[i] => run.push(pts[i]),
            _ => out.push((vec![pts[i - 1], pts[i]], sm[i])),
        }
    }
    out
}
