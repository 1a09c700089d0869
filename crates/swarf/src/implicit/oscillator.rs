//! The damped oscillator of Kalmar-Nagy & Erdim (§2, eqs. 3–6), integrated as a plane curve: a
//! spiral from the maximum of `f` out to a level `f_end`, then one turn along that level.
//!
//! Eq. 6 is singular where `f_y = 0` but its curve is not, so the curve is integrated in arc
//! length along `dp/ds = (t̂ + ζ n̂) / √(1 + ζ²)`, the level-set tangent plus an outward drift
//! (on a disk, the logarithmic spiral `r = r₀ e^{ζθ}`). ζ is constant or chosen per level,
//! `ζ(c) = s · w · g_min(c) / F(c)`, so that successive turns are at most a stepover `w` apart
//! (and within [`engagement_spacing`] where they curve tightly); [`spiral`] measures the result
//! ([`max_turn_spacing`]) and rescales ζ. The integrator is Dormand–Prince 5(4) with error
//! control; at `f_end` a relaxation onto the level gives the closing turn. The derivation from
//! eq. 6, the choice of ζ and the integration are in `docs/implicit.md`.

// `!(x > y)` is meant: a NaN must fail every check
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::levels::Grid;
use super::shape::Field;
use crate::error::{Error, Result, Setting};
use crate::geom::DVec2;
use crate::geom::index::EdgeIndex;
use std::sync::{Arc, Mutex, OnceLock};

/// Turning sense of the spiral around its start point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Turn {
    /// Counter-clockwise.
    #[default]
    Ccw,
    /// Clockwise.
    Cw,
}

/// The damping ζ (negative damping of eq. 6: the outward drift per unit of arc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Damping {
    /// One ζ for the whole spiral.
    Constant(f64),
    /// ζ per level so that successive turns are at most `safety · w` apart, within
    /// `[zeta_min, zeta_max]`.
    Stepover {
        /// The stepover (largest distance between turns), same unit as the field.
        w: f64,
        /// Fraction of `w` aimed at (0 < safety ≤ 1).
        safety: f64,
        /// Smallest ζ (keeps the spiral moving past flat levels, e.g. near saddles).
        zeta_min: f64,
        /// Largest ζ (near the start, where levels are tiny).
        zeta_max: f64,
    },
}

impl Damping {
    /// Stepover control with the defaults: safety 0.9, ζ in [1e-4, 1].
    pub fn stepover(w: f64) -> Damping {
        Damping::Stepover { w, safety: 0.9, zeta_min: 1e-4, zeta_max: 1.0 }
    }
}

/// Options of [`spiral`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpiralOptions {
    /// Turning sense.
    pub turn: Turn,
    /// ζ.
    pub damping: Damping,
    /// The level where the spiral stops growing and tracks (0: the boundary itself).
    pub f_end: f64,
    /// Relative tolerance of Dormand–Prince (on coordinates relative to the start).
    pub rtol: f64,
    /// Absolute tolerance; 0 for 1e-7 of the field's size.
    pub atol: f64,
    /// Largest step; 0 for w / 4 with a stepover, else 1/100 of the field's size.
    pub max_step: f64,
    /// Distance from the start point (along +x, the oscillator's `x(0)`) where the integration
    /// begins; 0 for w / 100 with a stepover, else 1e-3 of the field's size.
    pub start_offset: f64,
    /// Most turns before giving up.
    pub max_turns: usize,
    /// Most steps before giving up.
    pub max_steps: usize,
    /// With a stepover, also hold the gaps to what keeps the engagement of a flat end mill
    /// within an angle where the turns curve tightly.
    pub engagement: Option<EngagementLimit>,
    /// With a stepover: the largest measured gap [`spiral`] accepts before it rescales ζ down
    /// (default: the stepover). A roughing spiral may accept more where levels round a corner,
    /// since a tool of radius R still clears between turns up to 2R apart.
    pub accept_gap: Option<f64>,
}

/// The engagement a stepover spiral keeps to (see [`engagement_spacing`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EngagementLimit {
    /// Tool radius.
    pub r: f64,
    /// Largest engagement, radians.
    pub theta: f64,
    /// The gap is never held below this fraction of the stepover: where a level turns a corner
    /// tighter than that allows (the levels near a polygon's corner), a short stretch of
    /// higher engagement is taken instead of slowing every turn of the spiral down.
    pub floor: f64,
}

/// The largest distance between turns that keeps the engagement of a tool of radius `r`
/// within `theta` where the turn curves with radius `rho` round the cleared side.
///
/// The tool centre runs on a curve of radius ρ; the turn before, `w` inside, cleared a disk of
/// radius ρ − w + R round the same centre. The tool circle's point at angle ψ from the outward
/// normal is at distance √(ρ² + R² + 2ρR cos ψ) from the centre, so it is in material for
/// ψ < ψ₀ with cos ψ₀ = ((ρ − w + R)² − ρ² − R²) / 2ρR, and the engagement (the front half's
/// share, as for a straight cut, where it is acos(1 − w/R)) is ψ₀. Solving ψ₀ = θ for w:
/// w = ρ + R − √(ρ² + R² + 2ρR cos θ). It tends to the straight cut's R(1 − cos θ) as ρ grows
/// and to nothing as ρ shrinks (a small turn engages the tool as a slot would).
pub fn engagement_spacing(rho: f64, r: f64, theta: f64) -> f64 {
    if !(rho > 0.0) || !rho.is_finite() {
        return r * (1.0 - theta.cos());
    }
    (rho + r - (rho * rho + r * r + 2.0 * rho * r * theta.cos()).sqrt()).max(0.0)
}

impl Default for SpiralOptions {
    fn default() -> Self {
        SpiralOptions {
            turn: Turn::Ccw,
            damping: Damping::Constant(0.05),
            f_end: 0.0,
            rtol: 1e-6,
            atol: 0.0,
            max_step: 0.0,
            start_offset: 0.0,
            max_turns: 10_000,
            max_steps: 2_000_000,
            engagement: None,
            accept_gap: None,
        }
    }
}

/// One point of a spiral.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpiralPoint {
    /// Where.
    pub p: DVec2,
    /// `f` there.
    pub f: f64,
    /// The unit tangent there (the direction field of the integration; at the start point,
    /// where it is undefined, the one at the next point).
    pub t: DVec2,
}

/// A spiral: the start point, the accepted integration points out to `f_end`, then one turn
/// along `f = f_end`.
#[derive(Debug, Clone, PartialEq)]
pub struct Spiral {
    /// The polyline.
    pub points: Vec<SpiralPoint>,
    /// Index of the first point on the final level (where tracking starts).
    pub track_start: usize,
    /// Turns of the spiral part (tangent turning / 2π, before tracking).
    pub turns: f64,
    /// Largest distance between successive turns along the inward normal (see
    /// [`max_turn_spacing`]), the last spiral turn to the tracked level included.
    pub max_spacing: f64,
    /// Arc length.
    pub length: f64,
}

impl Spiral {
    /// The polyline's points.
    pub fn polyline(&self) -> Vec<DVec2> {
        self.points.iter().map(|q| q.p).collect()
    }
}

/// What the direction field does.
#[derive(Debug, Clone, Copy)]
enum Phase {
    Grow(f64),
    Track { level: f64, gain: f64 },
}

struct Rhs<'a> {
    field: &'a dyn Field,
    sense: f64,
    evals: usize,
}

impl Rhs<'_> {
    /// Unit direction at `p`, and `f(p)`.
    fn dir(&mut self, p: DVec2, phase: Phase) -> Result<(DVec2, f64)> {
        self.evals += 1;
        let d = self.field.eval(p);
        let gl = d.g.length();
        if !(gl > 1e-300) || !d.v.is_finite() {
            return Err(Error::job(
                "spiral",
                format!(
                    "the gradient of f vanishes at ({:.6}, {:.6}) (f = {}): a flat spot or a second maximum",
                    p.x, p.y, d.v
                ),
            ));
        }
        let gh = d.g / gl;
        let t = DVec2::new(gh.y, -gh.x) * self.sense;
        let n = -gh;
        let v = match phase {
            Phase::Grow(z) => (t + n * z) / (1.0 + z * z).sqrt(),
            Phase::Track { level, gain } => {
                let k = (gain * (d.v - level) / gl).clamp(-1.0, 1.0);
                (t + n * k).normalize()
            }
        };
        Ok((v, d.v))
    }
}

// Dormand–Prince 5(4)
const A: [[f64; 6]; 6] = [
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
];
const E: [f64; 7] =
    [71.0 / 57600.0, 0.0, -71.0 / 16695.0, 71.0 / 1920.0, -17253.0 / 339200.0, 22.0 / 525.0, -1.0 / 40.0];

/// One step: the new point, the error estimate, the directions at both ends and `f` at the end.
struct Step {
    y: DVec2,
    err: DVec2,
    k_end: DVec2,
    f_end: f64,
}

fn dp_step(rhs: &mut Rhs, y: DVec2, k1: DVec2, h: f64, phase: Phase) -> Result<Step> {
    let mut k = [DVec2::ZERO; 7];
    k[0] = k1;
    for s in 0..6 {
        let mut yy = y;
        for (j, kj) in k.iter().enumerate().take(s + 1) {
            yy += *kj * (h * A[s][j]);
        }
        let (d, f) = rhs.dir(yy, phase)?;
        k[s + 1] = d;
        if s == 5 {
            let err = k.iter().zip(E).fold(DVec2::ZERO, |acc, (kj, e)| acc + *kj * (h * e));
            return Ok(Step { y: yy, err, k_end: d, f_end: f });
        }
    }
    unreachable!("the loop returns at its last stage")
}

/// The spiral of the oscillator over `field` from `start` (normally the maximum of `f`, see
/// [`super::shape::maximum`]) out to the level `opts.f_end`, then one turn along it. `field`
/// must be bounded ([`Field::bounds`]). Errors (typed, never a hang): an unbounded field, bad
/// options, `f(start) ≤ f_end`, a vanishing gradient, a stalled or endless spiral.
pub fn spiral(field: &dyn Field, start: DVec2, opts: &SpiralOptions) -> Result<Spiral> {
    spiral_on(field, start, opts, None)
}

/// [`spiral`], with the samples of `field` its ζ per level reads level sets from, when the
/// caller has them: `samples` must be [`Samples::of_field`] of the same field (it is sampled
/// here, once for all the spiral's tries, when not given).
pub fn spiral_on(field: &dyn Field, start: DVec2, opts: &SpiralOptions, samples: Option<&Samples>) -> Result<Spiral> {
    let Damping::Stepover { w, .. } = opts.damping else {
        return spiral_once(field, start, opts, 1.0, None);
    };
    let sampled;
    let samples = match samples {
        Some(g) => Some(g),
        None if field.bounds().is_some_and(|(lo, hi)| (hi - lo).length().is_finite() && (hi - lo).length() > 0.0) => {
            sampled = Samples::of_field(field);
            sampled.as_ref()
        }
        None => None,
    };
    // the per-level ζ rests on a linear estimate of the gap (and a conservative table): where
    // levels bend (rounded corners, tongues into narrow parts) the real gap can be larger, and
    // elsewhere it is often smaller. Measure and rescale ζ, keeping the widest spiral within w.
    let mut gain = 1.0;
    let mut best: Option<Spiral> = None;
    for _ in 0..5 {
        let s = spiral_once(field, start, opts, gain, samples)?;
        let m = s.max_spacing;
        log::debug!("spiral gain {gain:.4}: {:.1} turns, length {:.1}, max spacing {m:.4} (w {w})", s.turns, s.length);
        let ok = m <= opts.accept_gap.unwrap_or(w);
        if ok && best.as_ref().is_none_or(|b| m > b.max_spacing) {
            best = Some(s);
        }
        // (with an engagement limit the gaps are meant to be below w where turns are tight:
        // widening the spiral to reach w would undo it)
        if ok && (m >= 0.85 * w || opts.engagement.is_some()) {
            break;
        }
        gain *= 0.95 * w / m.max(1e-3 * w);
    }
    match best {
        Some(s) => Ok(s),
        None => spiral_once(field, start, opts, gain, samples),
    }
}

/// One spiral with ζ per level scaled by `gain`; `samples`: [`Samples::of_field`] of `field`,
/// or `None` to sample it here.
fn spiral_once(
    field: &dyn Field,
    start: DVec2,
    opts: &SpiralOptions,
    gain: f64,
    samples: Option<&Samples>,
) -> Result<Spiral> {
    let (lo, hi) = field.bounds().ok_or_else(|| Error::job("spiral", "the shape is unbounded"))?;
    let size = (hi - lo).length();
    if !(size > 0.0) || !size.is_finite() {
        return Err(Error::job("spiral", "the shape has no extent"));
    }
    let stepover = match opts.damping {
        Damping::Constant(z) => {
            if !(z > 0.0 && z.is_finite()) {
                return Err(Error::setting(Setting::Zeta, format!("ζ must be positive, got {z}")));
            }
            None
        }
        Damping::Stepover { w, safety, zeta_min, zeta_max } => {
            if !(w > 0.0 && w.is_finite()) {
                return Err(Error::setting(
                    Setting::OscillatorStepover,
                    format!("the stepover must be positive, got {w}"),
                ));
            }
            if !(safety > 0.0 && safety <= 1.0 && zeta_min > 0.0 && zeta_min <= zeta_max && zeta_max.is_finite()) {
                return Err(Error::setting(Setting::OscillatorStepover, "need 0 < safety ≤ 1 and 0 < ζ_min ≤ ζ_max"));
            }
            Some(w)
        }
    };
    if !(opts.rtol > 0.0) || opts.atol < 0.0 || opts.max_step < 0.0 || opts.start_offset < 0.0 {
        return Err(Error::setting(Setting::Oscillator, "tolerances, step and start offset must be positive"));
    }
    let f0 = field.eval(start).v;
    if !(f0 > opts.f_end) {
        return Err(Error::job("spiral", format!("f at the start ({f0}) is not above the final level {}", opts.f_end)));
    }
    let atol = if opts.atol > 0.0 { opts.atol } else { 1e-7 * size };
    let h_max = if opts.max_step > 0.0 { opts.max_step } else { stepover.map_or(size / 100.0, |w| w / 4.0) };
    let eps = if opts.start_offset > 0.0 { opts.start_offset } else { stepover.map_or(size * 1e-3, |w| w / 100.0) };
    let h_min = size * 1e-12;
    let table = match opts.damping {
        Damping::Stepover { w, safety, zeta_min, zeta_max } => {
            let sampled;
            let samples = match samples {
                Some(g) => g,
                None => {
                    sampled = Samples::of_field(field).ok_or_else(|| Error::job("spiral", "the shape is unbounded"))?;
                    &sampled
                }
            };
            let profile = samples.profile(field, lo, hi, opts.f_end, f0, opts.engagement.is_some());
            Some(ZetaTable::new(&profile, gain * safety * w, zeta_min, zeta_max, opts.engagement))
        }
        Damping::Constant(_) => None,
    };
    let zeta_at = |f: f64| match (&table, opts.damping) {
        (Some(t), _) => t.zeta(f),
        (None, Damping::Constant(z)) => z,
        (None, _) => unreachable!("a stepover always has a table"),
    };
    let track = Phase::Track { level: opts.f_end, gain: 10.0 / stepover.unwrap_or(size / 20.0) };
    let sense = if opts.turn == Turn::Ccw { 1.0 } else { -1.0 };
    let mut rhs = Rhs { field, sense, evals: 0 };

    let mut y = start + DVec2::X * eps;
    let (mut k1, mut fy) = rhs.dir(y, Phase::Grow(zeta_at(f0)))?;
    if !(fy > opts.f_end) {
        return Err(Error::job("spiral", "the start offset already leaves the region"));
    }
    let mut points = vec![SpiralPoint { p: start, f: f0, t: k1 }, SpiralPoint { p: y, f: fy, t: k1 }];
    let mut thetas = vec![0.0, 0.0];
    let mut theta = 0.0;
    let mut h = (eps / 10.0).min(h_max);
    let mut length = eps;
    let mut tracking: Option<(usize, f64)> = None;
    let mut track_dir = DVec2::X;
    let mut last_turn = (0.0f64, fy);
    let mut steps = 0usize;
    let err_norm = |s: &Step, y0: DVec2| {
        let sc = |i: usize| atol + opts.rtol * (y0 - start)[i].abs().max((s.y - start)[i].abs());
        (s.err.x.abs() / sc(0)).max(s.err.y.abs() / sc(1))
    };
    loop {
        steps += 1;
        if steps > opts.max_steps {
            return Err(Error::job(
                "spiral",
                format!(
                    "no end after {} steps (at ({:.6}, {:.6}), f = {fy}, {})",
                    opts.max_steps,
                    y.x,
                    y.y,
                    if tracking.is_some() { "tracking the final level" } else { "growing" }
                ),
            ));
        }
        if h < h_min {
            return Err(Error::job("spiral", format!("the step fell below {h_min:e} at ({:.6}, {:.6})", y.x, y.y)));
        }
        let phase = if tracking.is_some() { track } else { Phase::Grow(zeta_at(fy)) };
        let s = dp_step(&mut rhs, y, k1, h, phase)?;
        let err = err_norm(&s, y);
        let turn = k1.perp_dot(s.k_end).atan2(k1.dot(s.k_end)) * sense;
        if !(err <= 1.0) || turn.abs() > 0.25 {
            let shrink = if err.is_finite() { (0.9 * err.powf(-0.2)).clamp(0.2, 0.5) } else { 0.2 };
            h *= if turn.abs() > 0.25 { shrink.min(0.5) } else { shrink };
            continue;
        }
        // accepted: events first
        if tracking.is_none() && s.f_end <= opts.f_end {
            // regula falsi on the step length for f = f_end
            let (mut a, mut fa, mut b, mut fb) = (0.0, fy - opts.f_end, h, s.f_end - opts.f_end);
            let mut best = (s.y, s.k_end, s.f_end, h);
            for _ in 0..60 {
                let m = (a * fb - b * fa) / (fb - fa);
                let m = if m > a && m < b { m } else { 0.5 * (a + b) };
                let t = dp_step(&mut rhs, y, k1, m, phase)?;
                let fm = t.f_end - opts.f_end;
                best = (t.y, t.k_end, t.f_end, m);
                if fm.abs() <= 1e-10 * (f0 - opts.f_end) || (b - a) < h_min {
                    break;
                }
                if fm > 0.0 {
                    a = m;
                    fa = fm;
                    fb *= 0.5;
                } else {
                    b = m;
                    fb = fm;
                    fa *= 0.5;
                }
            }
            let (yn, kn, fnv, hn) = best;
            theta += k1.perp_dot(kn).atan2(k1.dot(kn)) * sense;
            length += hn;
            y = yn;
            fy = fnv;
            // the direction at the switch is the tracking one
            k1 = rhs.dir(y, track)?.0;
            track_dir = k1;
            points.push(SpiralPoint { p: y, f: fy, t: k1 });
            thetas.push(theta);
            tracking = Some((points.len() - 1, theta));
            continue;
        }
        if let Some((k0, theta0)) = tracking {
            // closed when the step crosses the line through the track's first point normal to
            // its direction, near that point, after at least half a turn (the turning alone
            // does not tell: a non-convex level turns by more than 2π on parts of its way)
            let (p0, t0) = (points[k0].p, track_dir);
            let (sa, sb) = ((y - p0).dot(t0), (s.y - p0).dot(t0));
            if theta + turn >= theta0 + std::f64::consts::PI
                && sa < 0.0
                && sb >= 0.0
                && (s.y - p0).length() < 2.0 * h_max
            {
                let frac = (sa / (sa - sb)).clamp(0.0, 1.0);
                let t = dp_step(&mut rhs, y, k1, h * frac, track)?;
                points.push(SpiralPoint { p: t.y, f: t.f_end, t: t.k_end });
                thetas.push(theta + turn * frac);
                length += h * frac;
                break;
            }
            if theta < theta0 - std::f64::consts::PI {
                return Err(Error::job(
                    "spiral",
                    format!(
                        "the spiral met the level f = {} around an island (a hole of the region) at ({:.3}, {:.3}) \
                         before the outer boundary: it covers simply connected regions only",
                        opts.f_end, p0.x, p0.y
                    ),
                ));
            }
            if theta > theta0 + 3.0 * std::f64::consts::TAU {
                return Err(Error::job("spiral", format!("the level f = {} does not close", opts.f_end)));
            }
        }
        theta += turn;
        length += h;
        y = s.y;
        fy = s.f_end;
        k1 = s.k_end;
        points.push(SpiralPoint { p: y, f: fy, t: k1 });
        thetas.push(theta);
        if tracking.is_none() && theta >= last_turn.0 + std::f64::consts::TAU {
            if !(fy < last_turn.1 - 1e-12 * (f0 - opts.f_end).abs()) {
                return Err(Error::job(
                    "spiral",
                    format!("the spiral stalls at f = {fy}: a whole turn lowered f by nothing (ζ too small?)"),
                ));
            }
            last_turn = (theta, fy);
            if theta / std::f64::consts::TAU > opts.max_turns as f64 {
                return Err(Error::job("spiral", format!("more than {} turns before reaching f_end", opts.max_turns)));
            }
        }
        h = (h * (0.9 * err.max(1e-10).powf(-0.2)).clamp(0.2, 5.0)).min(h_max);
    }
    let (track_start, theta_track) = tracking.expect("the loop ends while tracking");
    // spacing: rays along ∇f
    let grads: Vec<DVec2> = points.iter().map(|q| field.eval(q.p).g).collect();
    let pts: Vec<DVec2> = points.iter().map(|q| q.p).collect();
    let reach = stepover.map_or(size, |w| 4.0 * w);
    let (max_spacing, _) = max_turn_spacing(&pts, &grads, &thetas, reach);
    Ok(Spiral { points, track_start, turns: theta_track / std::f64::consts::TAU, max_spacing, length })
}

/// Largest distance between successive turns of a spiral polyline `pts` whose tangent has turned
/// by `thetas[i]` (radians, increasing) at point i: from each point, a ray along the inward
/// direction `dirs[i]` (∇f) up to `reach` meets an earlier part of the path at least half a turn
/// back; the nearest such hit is the previous turn. Points within the first turn with no hit use
/// their distance to the first point (the start). Returns the largest spacing and the number of
/// later points whose ray met nothing within `reach`.
pub fn max_turn_spacing(pts: &[DVec2], dirs: &[DVec2], thetas: &[f64], reach: f64) -> (f64, usize) {
    if pts.len() < 3 {
        return (0.0, 0);
    }
    let segs: Vec<(DVec2, DVec2)> = pts.windows(2).map(|w| (w[0], w[1])).collect();
    let (lo, hi) = pts.iter().fold((pts[0], pts[0]), |(l, h), p| (l.min(*p), h.max(*p)));
    let cell = ((hi - lo).max_element() / 256.0).max(reach / 16.0).max(1e-9);
    let index = EdgeIndex::new(segs, cell);
    let mut worst: f64 = 0.0;
    let mut missed = 0;
    for i in 1..pts.len() {
        let p = pts[i];
        let Some(d) = dirs[i].try_normalize() else { continue };
        let limit = thetas[i] - std::f64::consts::PI;
        let mut hit = f64::INFINITY;
        let mut t0 = 0.0;
        while t0 < reach && !hit.is_finite() {
            let t1 = (t0 + cell).min(reach);
            let (a, b) = (p + d * t0, p + d * t1);
            index.for_each_near(a.min(b), a.max(b), |j, c, e| {
                if thetas[j + 1] > limit {
                    return;
                }
                // ray p + d t against segment c–e
                let ce = e - c;
                let den = d.perp_dot(ce);
                if den.abs() < 1e-300 {
                    return;
                }
                let w = c - p;
                let t = w.perp_dot(ce) / den;
                let u = w.perp_dot(d) / den;
                if (0.0..=1.0).contains(&u) && t > 1e-12 && t >= t0 && t <= t1 && t < hit {
                    hit = t;
                }
            });
            t0 = t1;
        }
        let first_turn = thetas[i] < std::f64::consts::TAU;
        if first_turn {
            worst = worst.max(hit.min((p - pts[0]).length()));
        } else if hit.is_finite() {
            worst = worst.max(hit);
        } else {
            missed += 1;
        }
    }
    (worst, missed)
}

/// The samples of a field that a spiral's ζ per level reads, kept for every spiral over the
/// field: the grid, and for each range of levels a spiral asks for, the level sets with `|∇f|`
/// and the level's radius of curvature at each of their vertices. The search's candidates
/// (each its own floor) and the rescaled gains of one spiral differ only in the arithmetic
/// [`ZetaTable::new`] does over these: the curvatures (four evaluations of `f` per vertex)
/// were half of a spiral's planning when each spiral measured them again.
pub struct Samples {
    /// [`Grid::of_field`] of the field.
    pub grid: Grid,
    /// The profiles measured so far, by (f_end, f0, with curvature).
    profiles: Mutex<Vec<(ProfileKey, SharedProfile)>>,
}

type ProfileKey = (u64, u64, bool);

/// A profile measured once by whichever spiral asks first, the others waiting for it.
type SharedProfile = Arc<OnceLock<Arc<Profile>>>;

impl Samples {
    /// The samples of `field` ([`Grid::of_field`]), or `None` where it is unbounded.
    pub fn of_field(field: &dyn Field) -> Option<Samples> {
        Some(Samples { grid: Grid::of_field(field)?, profiles: Mutex::new(Vec::new()) })
    }

    /// Measures now what a spiral over `field` (the field these samples are of) from `start`
    /// with `opts` reads from them (see [`spiral_on`]).
    pub fn prepare(&self, field: &dyn Field, start: DVec2, opts: &SpiralOptions) {
        if let (Damping::Stepover { .. }, Some((lo, hi))) = (opts.damping, field.bounds()) {
            self.profile(field, lo, hi, opts.f_end, field.eval(start).v, opts.engagement.is_some());
        }
    }

    /// The profile of the levels from `f_end` to `f0` (the field's bounds `lo`, `hi`), measured
    /// once; with `curvature` the radii of curvature too.
    fn profile(&self, field: &dyn Field, lo: DVec2, hi: DVec2, f_end: f64, f0: f64, curvature: bool) -> Arc<Profile> {
        let key = (f_end.to_bits(), f0.to_bits(), curvature);
        let cell = {
            let mut profiles = self.profiles.lock().unwrap_or_else(|e| e.into_inner());
            match profiles.iter().find(|(k, _)| *k == key) {
                Some((_, c)) => c.clone(),
                None => {
                    let c = Arc::new(OnceLock::new());
                    profiles.push((key, c.clone()));
                    c
                }
            }
        };
        cell.get_or_init(|| Arc::new(Profile::new(&self.grid, field, lo, hi, f_end, f0, curvature))).clone()
    }
}

/// The level sets of [`ZetaTable::ROWS`] levels from `f_end` up to `f0`.
struct Profile {
    rows: Vec<ProfileRow>,
}

struct ProfileRow {
    /// The level.
    c: f64,
    /// `∫ |∇f|` along the level set.
    flux: f64,
    /// `|∇f|` and the level's radius of curvature (infinite where it bends away from the
    /// cleared side, or not measured) at each end of each of the level set's segments.
    ends: Vec<(f64, f64)>,
}

impl Profile {
    /// The radius of curvature is 1/κ, κ = div(−∇f/|∇f|) by central differences.
    fn new(grid: &Grid, field: &dyn Field, lo: DVec2, hi: DVec2, f_end: f64, f0: f64, curvature: bool) -> Profile {
        use rayon::prelude::*;
        let h = 1e-4 * (hi - lo).length();
        let normal = |p: DVec2| -field.eval(p).g.normalize_or_zero();
        let rho = |p: DVec2| {
            if !curvature {
                return f64::INFINITY;
            }
            let kappa = ((normal(p + DVec2::X * h) - normal(p - DVec2::X * h)).x
                + (normal(p + DVec2::Y * h) - normal(p - DVec2::Y * h)).y)
                / (2.0 * h);
            // (a level bending the other way engages the tool less than a straight cut)
            if kappa > 1e-12 { 1.0 / kappa } else { f64::INFINITY }
        };
        let n = ZetaTable::ROWS;
        // (each row on its own: the same rows whatever the number of threads)
        let rows = (0..n)
            .into_par_iter()
            .map(|k| {
                let c = f_end + (f0 - f_end) * k as f64 / n as f64;
                let segs = grid.contour(c);
                let mut flux = 0.0;
                let mut ends = Vec::with_capacity(2 * segs.len());
                // (neighbouring segments share their end, the same point to the bit: its
                // radius is measured once, four evaluations of the field)
                let mut known: std::collections::HashMap<(u64, u64), f64> = std::collections::HashMap::new();
                let mut rho_at = |p: DVec2| *known.entry((p.x.to_bits(), p.y.to_bits())).or_insert_with(|| rho(p));
                for [(a, ga), (b, gb)] in &segs {
                    flux += (*b - *a).length() * 0.5 * (ga.length() + gb.length());
                    ends.push((ga.length(), rho_at(*a)));
                    ends.push((gb.length(), rho_at(*b)));
                }
                ProfileRow { c, flux, ends }
            })
            .collect();
        Profile { rows }
    }
}

/// ζ per level for a stepover (see the module documentation).
struct ZetaTable {
    /// (level, ζ), levels increasing.
    rows: Vec<(f64, f64)>,
    zeta_max: f64,
}

impl ZetaTable {
    /// Levels in a table.
    const ROWS: usize = 64;

    /// From the level sets of `profile`: with `eng` (tool radius, angle), the gap allowed at
    /// each point is also held to [`engagement_spacing`] at the level's radius of curvature
    /// there.
    fn new(profile: &Profile, w: f64, zmin: f64, zmax: f64, eng: Option<EngagementLimit>) -> ZetaTable {
        let allowed = |g: f64, rho: f64| {
            let w_here = match eng {
                Some(EngagementLimit { r, theta, floor }) => w.min(engagement_spacing(rho, r, theta).max(floor * w)),
                None => w,
            };
            w_here * g
        };
        let rows = profile
            .rows
            .iter()
            .map(|row| {
                if row.ends.is_empty() {
                    return (row.c, zmax);
                }
                let wg = row.ends.iter().fold(f64::INFINITY, |m, &(g, rho)| m.min(allowed(g, rho)));
                let z = if row.flux > 0.0 { wg / row.flux } else { zmax };
                (row.c, z.clamp(zmin, zmax))
            })
            .collect();
        ZetaTable { rows, zeta_max: zmax }
    }

    /// ζ at level `f`: the smaller of the two neighbouring rows; above the last row, the last
    /// row's (the levels up there are tiny loops around the maximum).
    fn zeta(&self, f: f64) -> f64 {
        let k = self.rows.partition_point(|r| r.0 <= f);
        match k {
            0 => self.rows.first().map_or(self.zeta_max, |r| r.1),
            k if k >= self.rows.len() => self.rows.last().map_or(self.zeta_max, |r| r.1),
            k => self.rows[k - 1].1.min(self.rows[k].1),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::RFamily;
    use crate::implicit::region::AreaField;
    use crate::implicit::rfunc::Dual;
    use crate::implicit::shape::{Node, Shape, maximum};

    fn disk(r: f64) -> Shape {
        Shape { family: RFamily::default(), root: Node::Circle { c: DVec2::ZERO, r } }
    }

    #[test]
    fn disk_spiral_grows_by_e_to_2_pi_zeta_per_turn() {
        for (turn, zeta) in [(Turn::Ccw, 0.05), (Turn::Cw, 0.1)] {
            let opts = SpiralOptions {
                turn,
                damping: Damping::Constant(zeta),
                f_end: 0.5,
                start_offset: 0.05,
                rtol: 1e-9,
                atol: 1e-10,
                ..Default::default()
            };
            let s = spiral(&disk(10.0), DVec2::ZERO, &opts).unwrap();
            // radius against polar angle: r = r0 e^{ζ θ} exactly (isotropic drift on circles)
            let sp = &s.points[1..s.track_start];
            let r0 = sp[0].p.length();
            let mut unwrapped = 0.0;
            let mut prev = sp[0].p.y.atan2(sp[0].p.x);
            for q in sp {
                let a = q.p.y.atan2(q.p.x);
                unwrapped += crate::geom::wrap_pi(a - prev);
                prev = a;
                let want = r0 * (zeta * unwrapped.abs()).exp();
                assert!((q.p.length() - want).abs() < 1e-6 * want, "{turn:?}: r = {} vs {want}", q.p.length());
            }
            assert_eq!(unwrapped > 0.0, turn == Turn::Ccw);
            // so each turn grows by e^{2πζ}
            let turns = unwrapped.abs() / std::f64::consts::TAU;
            let growth = (sp.last().unwrap().p.length() / r0).powf(1.0 / turns);
            assert!((growth - (std::f64::consts::TAU * zeta).exp()).abs() < 1e-6, "{growth}");
            // the last turn tracks f = 0.5: r = √(100 − 2·10·0.5) = √90
            for q in &s.points[s.track_start..] {
                assert!((q.f - 0.5).abs() < 1e-5, "{}", q.f);
            }
            let last = s.points.last().unwrap().p;
            assert!((last - s.points[s.track_start].p).length() < 0.05, "track not closed: {last}");
            // the spacing of a log spiral at radius r is r (e^{2πζ} − 1)
            let want = 90f64.sqrt() * (1.0 - (-std::f64::consts::TAU * zeta).exp());
            assert!((s.max_spacing - want).abs() < 0.05 * want, "spacing {} vs {want}", s.max_spacing);
        }
    }

    fn check_region(field: &dyn Field, inside: &dyn Fn(DVec2) -> bool, w: f64, f_end: f64) -> Spiral {
        let (lo, hi) = field.bounds().unwrap();
        let (start, _) = maximum(field, lo, hi).unwrap();
        let opts = SpiralOptions { damping: Damping::stepover(w), f_end, ..Default::default() };
        let s = spiral(field, start, &opts).unwrap();
        // inside the region and above the final level, within tolerance
        for q in &s.points {
            assert!(inside(q.p), "{} outside", q.p);
            assert!(q.f >= f_end - 1e-4 * w, "{}: f = {}", q.p, q.f);
        }
        // tracks the final level for one closed turn
        for q in &s.points[s.track_start..] {
            assert!((q.f - f_end).abs() < 1e-3 * w, "tracking off the level: {}", q.f);
        }
        let (a, b) = (s.points[s.track_start].p, s.points.last().unwrap().p);
        assert!((a - b).length() < 0.05 * w, "track not closed: {a} … {b}");
        assert!(s.points.len() - s.track_start > 20);
        // spacing within the stepover, and an independent check: every grid point of the
        // region f ≥ f_end lies within w/2 (and a little) of the path
        assert!(s.max_spacing <= w, "spacing {} > {w}", s.max_spacing);
        let path = s.polyline();
        let index = EdgeIndex::new(path.windows(2).map(|v| (v[0], v[1])).collect(), w);
        let n = 60;
        for j in 0..=n {
            for i in 0..=n {
                let p = lo + (hi - lo) * DVec2::new(i as f64, j as f64) / n as f64;
                if field.eval(p).v >= f_end {
                    let d = index.distance(p, 10.0 * w);
                    assert!(d <= 0.55 * w, "{p} is {d} from the path");
                }
            }
        }
        s
    }

    #[test]
    fn square_spiral_stays_inside_and_keeps_the_stepover() {
        let sq = Shape {
            family: RFamily::default(),
            root: Node::Rect { c: DVec2::ZERO, half: DVec2::splat(10.0), angle: 0.0 },
        };
        let s = check_region(&sq, &|p| p.x.abs() < 10.0 && p.y.abs() < 10.0, 1.5, 0.3);
        assert!(s.turns > 5.0 && s.turns < 40.0, "{}", s.turns);
        // and not needlessly dense: the rescaling brings the widest gap close to the stepover
        assert!(s.max_spacing >= 0.8 * 1.5, "spacing {}", s.max_spacing);
    }

    #[test]
    fn l_shape_spiral_stays_inside_and_keeps_the_stepover() {
        let area = crate::implicit::region::tests::l_shape();
        let field = AreaField::new(&area);
        check_region(&field, &|p| area.contains(p), 2.0, 0.2);
    }

    struct Flat;
    impl Field for Flat {
        fn eval(&self, _: DVec2) -> Dual {
            Dual::constant(1.0)
        }
        fn bounds(&self) -> Option<(DVec2, DVec2)> {
            Some((DVec2::splat(-1.0), DVec2::splat(1.0)))
        }
    }

    #[test]
    fn stalls_are_errors() {
        assert!(matches!(spiral(&Flat, DVec2::ZERO, &SpiralOptions::default()), Err(Error::Job { .. })));
        // too many turns asked for
        let opts = SpiralOptions { damping: Damping::Constant(0.001), max_turns: 3, ..Default::default() };
        let e = spiral(&disk(10.0), DVec2::ZERO, &opts).unwrap_err();
        assert!(e.to_string().contains("turns"), "{e}");
        // start outside, unbounded field, bad ζ
        assert!(spiral(&disk(1.0), DVec2::new(5.0, 0.0), &SpiralOptions::default()).is_err());
        let half = Shape { family: RFamily::default(), root: Node::HalfPlane { p: DVec2::ZERO, n: DVec2::Y } };
        assert!(spiral(&half, DVec2::Y, &SpiralOptions::default()).is_err());
        let opts = SpiralOptions { damping: Damping::Constant(-0.1), ..Default::default() };
        assert!(spiral(&disk(1.0), DVec2::ZERO, &opts).is_err());
        let opts = SpiralOptions { max_steps: 50, ..Default::default() };
        assert!(spiral(&disk(1.0), DVec2::ZERO, &opts).unwrap_err().to_string().contains("steps"));
    }
}
