//! One step of constant-engagement milling (paper 1 §4.3, Algorithm 1, eqs. 5–11): the
//! direction read off the engaged arc of the tool's sampled circumference, checked against the
//! engagement at the point it leads to and corrected by regula falsi on the heading; the
//! shorter step where the walls are close, and the step away from a wall too heavy to follow.

use super::engine::{EngageStep, Engine};
use super::{AIR_DEG, BRACKET_RAD, HEAVY_DEG, SETTLE_DEG, SIDE_SKIP, STEP_SLACK_DEG};
use crate::geom::{DVec2, wrap_pi};
use crate::plan::Material;
use std::f64::consts::{FRAC_PI_2, TAU};

impl<'a, 'b, M: Material> Engine<'a, 'b, M> {
    /// Would eq. 9 lead away from the contour by more than the overshoot?
    pub(super) fn turns_away(&mut self, c: DVec2, alpha: f64, t: DVec2) -> bool {
        match self.direction(c, alpha) {
            Some(a) => {
                let d = wrap_pi(a - t.y.atan2(t.x)).abs().to_degrees();
                d > self.c.over && self.allowed(c + self.c.step * DVec2::new(a.cos(), a.sin()))
            }
            None => false,
        }
    }

    /// Direction of eq. 8–11 at `c` (previous direction `alpha_p`), or `None` without material.
    pub(super) fn direction(&mut self, c: DVec2, alpha_p: f64) -> Option<f64> {
        let m = self.l.sim.ring().len();
        let mut flags = std::mem::take(&mut self.flags);
        self.l.sim.ring_material(c, self.z, &mut flags);
        let mut found = flags.iter().any(|f| *f);
        if !found {
            // footnote 3: a temporarily larger tool finds the stock round a sharp corner
            let h = self.l.sim.heights();
            let g = self.l.sim.grid();
            let thr = (self.z + 0.01) as f32;
            for (k, off) in self.c.boost_ring.iter().enumerate() {
                flags[k] = g.cell_of(c + *off).is_some_and(|(i, j)| h[j * g.nx + i] > thr);
            }
            found = flags.iter().any(|f| *f);
        }
        let res = if !found {
            None
        } else if flags.iter().all(|f| *f) {
            Some(alpha_p)
        } else {
            let step = TAU / m as f64;
            let idx = |a: f64| ((a.rem_euclid(TAU) / step).floor() as usize).min(m - 1);
            // walk from the side where the material should be (the right for climb) toward
            // the front: the first engaged sample, then on while engaged; the last one is where
            // the circle leaves the material (eq. 8 / eq. 10)
            let dir = if self.c.climb { 1i64 } else { -1i64 };
            // (starting a little toward the front: the sampled circle, half a cell larger than the
            // tool, sees a sliver of the tool's own new wall right at its side)
            let side = alpha_p - dir as f64 * (FRAC_PI_2 - SIDE_SKIP.to_radians());
            let k0 = idx(side) as i64;
            let at = |k: i64| flags[k.rem_euclid(m as i64) as usize];
            let half = (m / 2) as i64;
            let mut k = k0;
            // first engaged sample within half a turn (side → front → other side)
            let mut first = None;
            for n in 0..=half {
                if at(k0 + dir * n) {
                    first = Some(k0 + dir * n);
                    break;
                }
            }
            // no material ahead on our side: take the nearest engaged sample the other way
            let first = first.or_else(|| (1..=half).map(|n| k0 - dir * n).find(|&kk| at(kk)));
            if let Some(f) = first {
                k = f;
                let mut guard = 0;
                while at(k + dir) && guard < m {
                    k += dir;
                    guard += 1;
                }
            }
            let cross = (k.rem_euclid(m as i64) as f64 + 0.5) * step + dir as f64 * 0.5 * step;
            // turned away from the material by 90° − θ (eq. 9 / eq. 11)
            Some(cross + dir as f64 * (FRAC_PI_2 - self.c.theta.to_radians()))
        };
        self.flags = flags;
        res
    }

    /// One step of constant-engagement milling (Algorithm 1): the direction of eq. 8–11, then
    /// — swarf's addition — checked against the engagement at the point it leads to (the front
    /// half of the tool, against the stock as it is). When that is off by more than a few
    /// degrees, the heading is found by regula falsi between the paper's direction and the side
    /// of the front half that moves the tool into or out of the material, so the step lands on
    /// the reference engagement and the material stays on the same side (the milling type is
    /// kept).
    pub(super) fn engage_step(&mut self, c: DVec2, alpha_p: f64) -> EngageStep {
        match self.engage_step_of(c, alpha_p, self.c.step) {
            // a full step runs into a wall: where the walls are close round the tool (a channel
            // barely wider than it), a shorter one lets it turn within the room it has — the
            // loops of trochoidal milling — before it gives up to contour milling
            EngageStep::Wall => match self.step_at(c) {
                short if short < self.c.step => self.engage_step_of(c, alpha_p, short),
                _ => EngageStep::Wall,
            },
            es => es,
        }
    }

    /// [`Self::engage_step`] with the step length `step`.
    pub(super) fn engage_step_of(&mut self, c: DVec2, alpha_p: f64, step: f64) -> EngageStep {
        let Some(guess) = self.direction(c, alpha_p) else { return EngageStep::Done };
        // keep the heading within the front half of the previous direction
        let lim = FRAC_PI_2;
        let guess = alpha_p + wrap_pi(guess - alpha_p).clamp(-lim, lim);
        // the heading by the engagement at the step's end; where the step so found crosses a
        // sliver heavier than that on its way, the heading again by the engagement along it
        // (kept as it was where every heading crosses one: ending the pass there leaves the
        // sliver to the clean-up, which takes it at full width)
        let Some(mut alpha) = self.heading(c, alpha_p, guess, step, false) else { return EngageStep::Done };
        if self.along_engagement(c, alpha, step) > self.c.theta + STEP_SLACK_DEG
            && let Some(a) = self.heading(c, alpha_p, guess, step, true)
        {
            alpha = a;
        }
        let n = c + DVec2::new(alpha.cos(), alpha.sin()) * step;
        if !self.allowed(n) || !self.step_allowed(c, n) {
            return EngageStep::Wall;
        }
        EngageStep::Moved(n, alpha)
    }

    /// The heading search of [`Self::engage_step_of`] from the direction of eq. 9 (`guess`),
    /// reading the engagement at the step's end, and along the step too when `along`; `None`
    /// when every heading of the front half is too heavy.
    fn heading(&self, c: DVec2, alpha_p: f64, guess: f64, step: f64, along: bool) -> Option<f64> {
        let toward = if self.c.climb { -1.0 } else { 1.0 };
        let lim = FRAC_PI_2;
        let eval = |me: &Self, a: f64| {
            if along {
                me.step_engagement(c, a, step)
            } else {
                let u = DVec2::new(a.cos(), a.sin());
                me.l.sim.front_engagement(c + u * step, me.z, u)
            }
        };
        let e0 = eval(self, guess);
        let mut alpha = guess;
        if (e0 - self.c.theta).abs() > STEP_SLACK_DEG {
            // the end of the front half that moves the error the right way
            let end = if e0 > self.c.theta { alpha_p - toward * lim } else { alpha_p + toward * lim };
            let e1 = eval(self, end);
            if (e0 > self.c.theta) == (e1 > self.c.theta) {
                // saturated: turn as far as the front half allows — unless even that is too
                // heavy, when the pass ends here (another start takes the material from a
                // better side)
                if e1 > self.c.theta + HEAVY_DEG {
                    return None;
                }
                alpha = end;
            } else {
                // e(lo) and e(hi) straddle theta: regula falsi with the Illinois rule (the
                // engagement is nearly linear in the heading over a bracket, so this takes 2–3
                // readings where bisection took 7), until the end that does not exceed the
                // reference reads within a pixel of it or the bracket is below 0.7°
                let (mut lo, mut hi) = (guess, end);
                let (mut flo, mut fhi) = (e0 - self.c.theta, e1 - self.c.theta);
                let (mut wlo, mut whi) = (flo, fhi);
                let mut last = 0i8;
                for _ in 0..7 {
                    if (hi - lo).abs() < BRACKET_RAD {
                        break;
                    }
                    let t = (wlo / (wlo - whi)).clamp(0.05, 0.95);
                    let mid = lo + (hi - lo) * t;
                    let fm = eval(self, mid) - self.c.theta;
                    if (fm > 0.0) == (flo > 0.0) {
                        (lo, flo, wlo) = (mid, fm, fm);
                        if last == -1 {
                            whi *= 0.5;
                        }
                        last = -1;
                    } else {
                        (hi, fhi, whi) = (mid, fm, fm);
                        if last == 1 {
                            wlo *= 0.5;
                        }
                        last = 1;
                    }
                    let under = if e0 > self.c.theta { fhi } else { flo };
                    if under >= -SETTLE_DEG {
                        break;
                    }
                }
                // the side that does not exceed the reference
                alpha = if e0 > self.c.theta { hi } else { lo };
            }
        }
        Some(alpha)
    }

    /// The engagement of a step of `step` from `c` along heading `a`: the larger of its end's
    /// and [`Self::along_engagement`].
    fn step_engagement(&self, c: DVec2, a: f64, step: f64) -> f64 {
        let u = DVec2::new(a.cos(), a.sin());
        self.l.sim.front_engagement(c + u * step, self.z, u).max(self.along_engagement(c, a, step))
    }

    /// The larger engagement at a third and at two thirds of a step of `step` from `c` along
    /// heading `a`, against the stock as it is. A step that turns toward the material (at a
    /// pass's end, round a thin remnant) can cross a sliver of stock that reads far above the
    /// reference a third of the way along and has been passed by the step's end.
    pub(super) fn along_engagement(&self, c: DVec2, a: f64, step: f64) -> f64 {
        let u = DVec2::new(a.cos(), a.sin());
        [1.0 / 3.0, 2.0 / 3.0]
            .iter()
            .fold(0.0, |m: f64, t| m.max(self.l.sim.front_engagement(c + u * (step * t), self.z, u)))
    }

    /// The shorter step of constant engagement at `c`, where a full one (`0.1·D`) runs into a
    /// wall: half the room the tool has to the walls, down to a quarter step.
    pub(super) fn step_at(&self, c: DVec2) -> f64 {
        let room = self.dk_at(c) - self.c.r - self.c.margin;
        let min = (0.25 * self.c.step).max(2.0 * self.l.sim.grid().res);
        (0.5 * room).clamp(min.min(self.c.step), self.c.step)
    }

    /// When the heading of eq. 9 runs into a wall: the heading nearest to it, turned away from
    /// the material within the front half, that the walls allow and that does not engage more
    /// than the reference (+ slack).
    pub(super) fn away_step(&mut self, c: DVec2, alpha_p: f64) -> Option<(DVec2, f64)> {
        let guess = self.direction(c, alpha_p)?;
        let guess = alpha_p + wrap_pi(guess - alpha_p).clamp(-FRAC_PI_2, FRAC_PI_2);
        let away = if self.c.climb { 1.0 } else { -1.0 };
        let end = alpha_p + away * FRAC_PI_2;
        let span = wrap_pi(end - guess) * away;
        if span <= 0.0 {
            return None;
        }
        let n_try = (span.to_degrees() / 4.0).ceil() as usize;
        for k in 1..=n_try {
            let a = guess + away * span * k as f64 / n_try as f64;
            let u = DVec2::new(a.cos(), a.sin());
            let n = c + u * self.c.step;
            if !self.allowed(n) || !self.step_allowed(c, n) {
                continue;
            }
            let e = self.step_engagement(c, a, self.c.step);
            if e <= self.c.theta + STEP_SLACK_DEG && e > AIR_DEG {
                return Some((n, a));
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::super::engine::fixture::{Pocket, clear_row, engine};
    use super::*;
    use std::f64::consts::PI;

    /// The pocket cleared above y = 5: a straight edge of material below. The tool half a
    /// millimetre into it (engagement about 42°, the reference 78.5°) heading along it with the
    /// material on the milling side — on its right for climb milling (heading +x), on its left
    /// for conventional (heading −x). One step of constant engagement advances the step length,
    /// turned toward the material until the engagement there is within a few degrees of the
    /// reference, and leaves all the material on the milling side.
    #[test]
    fn one_step_reaches_the_reference_engagement_with_the_material_on_the_milling_side() {
        for climb in [true, false] {
            let p = Pocket::new(climb);
            let z = p.z();
            let mut l = p.linker();
            for y in [7.0, 9.0, 11.0] {
                clear_row(&mut l, z, y, -3.0, 23.0);
            }
            let c = p.setup(&l);
            let mut e = engine(&mut l, &c, z);
            let (at, heading) = if climb { (DVec2::new(6.0, 6.5), 0.0) } else { (DVec2::new(14.0, 6.5), PI) };
            let u = DVec2::new(heading.cos(), heading.sin());
            let e0 = e.l.sim.front_engagement(at, z, u);
            assert!(e0 < c.theta - 20.0, "climb {climb}: {e0}° at the start");
            // eq. 8–11: where the circle leaves the material (the edge 1.5 mm from the centre,
            // on the ring half a cell outside the tool), turned by 90° − θ_ref away from it
            let ring_r = e.l.sim.ring()[0].length();
            let cross = -FRAC_PI_2 + (1.5 / ring_r).acos();
            let want = if climb {
                cross + (FRAC_PI_2 - c.theta.to_radians())
            } else {
                -cross - (FRAC_PI_2 - c.theta.to_radians())
            };
            let guess = e.direction(at, heading).expect("material on the ring");
            let off = wrap_pi(guess - heading - want).to_degrees();
            assert!(
                off.abs() < 3.0,
                "climb {climb}: eq. 9 gives {}°, {off}° off",
                wrap_pi(guess - heading).to_degrees()
            );
            let EngageStep::Moved(n, a) = e.engage_step(at, heading) else { panic!("climb {climb}: no step") };
            let v = DVec2::new(a.cos(), a.sin());
            // the step length, turned toward the material (down), still forward
            assert!(((n - at).length() - c.step).abs() < 1e-9, "climb {climb}: {n:?}");
            assert!(n.y < at.y - 0.1 && v.dot(u) > 0.5, "climb {climb}: heading {}°", a.to_degrees());
            // the engagement there near the reference, not above it by more than the slack
            let e1 = e.l.sim.front_engagement(n, z, v);
            assert!(
                e1 <= c.theta + STEP_SLACK_DEG && e1 >= c.theta - STEP_SLACK_DEG - SETTLE_DEG,
                "climb {climb}: {e1}°"
            );
            // all the material the ring sees on the milling side (the right for climb)
            let side = if climb { DVec2::new(v.y, -v.x) } else { DVec2::new(-v.y, v.x) };
            let mut flags = Vec::new();
            e.l.sim.ring_material(n, z, &mut flags);
            let (on, off) =
                e.l.sim
                    .ring()
                    .iter()
                    .zip(&flags)
                    .filter(|(_, f)| **f)
                    .fold((0, 0), |(on, off), (o, _)| if o.dot(side) > 0.0 { (on + 1, off) } else { (on, off + 1) });
            assert!(on > 0 && off == 0, "climb {climb}: {on} samples on the milling side, {off} off it");
        }
    }
}
