//! Oscillator spirals (paper 4, Kalmar-Nagy & Erdim): one smooth path from the inside of the
//! pocket out to its walls, with no link.
//!
//! The tool-centre region of the job (the pocket less its walls grown by the tool radius,
//! [`super::medial::region`]) is embedded in an implicit function `f`, positive inside and zero
//! on the boundary ([`crate::implicit::region::AreaField`], §3). Read as the energy of an
//! oscillator with negative damping ζ (eq. 6), `f` gives a trajectory that spirals out from the
//! maximum of `f` across its level sets until it reaches the boundary, which it then follows for
//! one turn ([`crate::implicit::oscillator`]). The program:
//!
//! 1. **Entry**: a helix round the start point (the maximum of `f`, or `--spiral-start`), of
//!    radius at most half the tool's and within the region, ending a sixth of a turn before the
//!    point where the spiral leaves the bore; a biarc joins the two tangentially.
//! 2. **The spiral**: ζ either constant (`--zeta`) or chosen per level so that successive turns
//!    are at most a stepover apart and, where a turn curves tightly, no further apart than
//!    keeps the engagement at the reference ([`crate::implicit::oscillator::engagement_spacing`]).
//!    It ends with one turn along the level `f = TRACK_LEVEL` (a few µm inside the boundary).
//! 3. **Output**: the integrated polyline is written as biarcs within the arc tolerance
//!    ([`crate::geom::biarc`]), so the program is G2/G3 arcs meeting tangentially throughout.
//!
//! **What the method cannot do.** A spiral covers a simply connected region: with an island,
//! the levels of `f` split round it, and the trajectory cannot follow both parts. A region with
//! holes is refused with a message naming the other strategies; a job whose tool-centre region
//! falls apart (a pocket with narrow necks) gets one spiral per piece, each with its entry.
//!
//! The region's own `f` is scaled down with the distance from the start ([`Shaped`]), so that no
//! level runs the length of a long leg at once (a ridge of `f`).
//!
//! [`crate::pipeline::optimise_spiral`] is the loop of §4, Figs. 8–9: plan a spiral for each candidate (ζ and start
//! point), simulate it, and keep the fastest that clears the pocket within the engagement bound.

use super::Linker;
use crate::error::{Error, Result};
use crate::geom::arcfit::Piece;
use crate::geom::{Area, DVec2, biarc};
use crate::implicit::oscillator::{Damping, EngagementLimit, Spiral, SpiralOptions, Turn, spiral};
use crate::implicit::region::AreaField;
use crate::implicit::shape::{Field, maximum};
use crate::model::{Job, Regions};
use crate::sim::SimOptions;
use crate::strategy::{LayerGeom, Params, Pass};
use crate::toolpath::{MoveKind, Toolpath};
use std::f64::consts::TAU;

/// The level the last turn follows, mm inside the tool-centre region's boundary.
pub const TRACK_LEVEL: f64 = 0.005;

/// The least gap between turns, as a fraction of the stepover, that the engagement limit may
/// ask for (see [`EngagementLimit::floor`]).
pub const ENGAGEMENT_FLOOR: f64 = 0.5;

/// How a spiral is made: the damping and the start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpiralChoice {
    /// A constant ζ, or `None` for ζ per level (stepover and engagement).
    pub zeta: Option<f64>,
    /// The start point, or `None` for the maximum of `f`.
    pub start: Option<DVec2>,
}

/// The XY path of one piece of the region.
#[derive(Debug, Clone)]
pub struct PiecePath {
    /// Centre of the entry helix.
    pub start: DVec2,
    /// Its radius.
    pub helix_r: f64,
    /// The integrated spiral.
    pub spiral: Spiral,
    /// Index of the spiral point where the path leaves the bore.
    pub join: usize,
}

/// The spirals of a job's tool-centre region, one per connected piece.
pub fn plan_pieces(
    job: &Job,
    regions: &Regions,
    geom: &LayerGeom,
    params: &Params,
    choice: &SpiralChoice,
) -> Result<Vec<PiecePath>> {
    let region = super::medial::region(regions, geom);
    let mut out = Vec::new();
    for piece in region.components() {
        if piece.polys.iter().any(|p| !p.holes.is_empty()) {
            return Err(Error::param(
                "--strategy spiral",
                "the pocket has an island: an oscillator spiral covers simply connected regions only (the levels \
                 of f split round an island); use --strategy adaptive, offset or medial",
            ));
        }
        if let Some(p) = plan_piece(job, &piece, geom, params, choice)? {
            out.push(p);
        }
    }
    if out.is_empty() {
        return Err(Error::param("--strategy spiral", "the tool fits nowhere in the pocket"));
    }
    Ok(out)
}

/// The region's implicit function scaled down with the distance from the start,
/// `f · 1 / (1 + d / ℓ)`, d the distance from the start (smoothed there): the same zero set, but no plateau. Along the centre line of a
/// long leg (an L's arm) the region's own `f` is nearly constant — a ridge — so one level of it
/// reaches the whole length of the leg at once, and a spiral crossing that level would slot the
/// leg from end to end in one turn. Scaled, the levels creep along the leg a little per turn.
struct Shaped<'a> {
    f: &'a AreaField,
    s: DVec2,
    l: f64,
}

impl Field for Shaped<'_> {
    fn eval(&self, p: DVec2) -> crate::implicit::Dual {
        let d0 = self.f.eval(p);
        // (d smoothed at the start, where |p − s| has a kink: √(|p − s|² + δ²) − δ)
        let v = p - self.s;
        let delta = 0.25 * self.l;
        let r = (v.length_squared() + delta * delta).sqrt();
        let d = r - delta;
        let phi = 1.0 / (1.0 + d / self.l);
        let dphi = v / r * (-phi * phi / self.l);
        crate::implicit::Dual { v: d0.v * phi, g: d0.g * phi + dphi * d0.v }
    }
    fn bounds(&self) -> Option<(DVec2, DVec2)> {
        self.f.bounds()
    }
}

/// The length ℓ of [`Shaped`], in units of the largest value of the region's `f` (the
/// largest inscribed radius).
pub const SHAPE_LENGTH: f64 = 1.0;

fn plan_piece(
    job: &Job,
    piece: &Area,
    geom: &LayerGeom,
    params: &Params,
    choice: &SpiralChoice,
) -> Result<Option<PiecePath>> {
    let base = AreaField::new(piece);
    let Some((lo, hi)) = base.bounds() else { return Ok(None) };
    let (top, fmax) = maximum(&base, lo, hi).unwrap_or((lo, 0.0));
    let start = choice.start.unwrap_or(top);
    let field = Shaped { f: &base, s: start, l: SHAPE_LENGTH * fmax.max(1e-3) };
    let f0 = field.eval(start).v;
    if f0 <= TRACK_LEVEL + 1e-3 {
        // a sliver the tool fits in only along a line: nothing a spiral can do
        return Ok(None);
    }
    let r = geom.r;
    let theta = job.width.engagement_deg().to_radians();
    let opts = SpiralOptions {
        turn: if params.climb { Turn::Ccw } else { Turn::Cw },
        damping: match choice.zeta {
            Some(z) => Damping::Constant(z),
            None => Damping::stepover(geom.step),
        },
        f_end: TRACK_LEVEL,
        engagement: choice.zeta.is_none().then_some(EngagementLimit { r, theta, floor: ENGAGEMENT_FLOOR }),
        // (the gaps are held to the stepover and the engagement level by level; where the
        // levels round a corner they open wider, and where a level crosses a ridge of f (the
        // centre line of a leg of an L) it jumps along it: the measured gap says nothing about
        // clearing there, which the simulation judges)
        accept_gap: Some(f64::INFINITY),
        ..Default::default()
    };
    let sp = spiral(&field, start, &opts).map_err(|e| match e {
        Error::Param { reason, .. } => Error::param("--strategy spiral", reason),
        e => e,
    })?;
    // the helix: at most half the tool radius, inside the region
    let helix_r = (params.helix_radius_frac * r).min(0.5 * r).min(0.8 * (f0 - TRACK_LEVEL));
    let join = sp.points.iter().position(|q| (q.p - start).length() >= helix_r).unwrap_or(sp.points.len() - 1);
    Ok(Some(PiecePath { start, helix_r, spiral: sp, join }))
}

/// Builds the program of a level job from its spirals.
#[allow(clippy::too_many_arguments)]
pub fn link_spiral(
    job: &Job,
    regions: &Regions,
    geom: &LayerGeom,
    params: &Params,
    zs: &[f64],
    finish: &[(f64, Vec<Pass>)],
    sim_opts: &SimOptions,
    choice: &SpiralChoice,
) -> Result<Toolpath> {
    let pieces = plan_pieces(job, regions, geom, params, choice)?;
    let mut l = Linker::new(job, regions, params, sim_opts, pieces[0].start)?;
    let n = zs.len();
    for (i, z) in zs.iter().enumerate() {
        l.tp.note(format!("level {} of {}: z {:.3}", i + 1, n, z));
        l.down_at = None;
        for p in &pieces {
            cut_piece(&mut l, p, *z);
        }
    }
    l.finishing(finish);
    Ok(l.finish())
}

/// Enters at the piece's start and cuts its spiral at `z`.
fn cut_piece(l: &mut Linker, p: &PiecePath, z: f64) {
    let s = if l.params.climb { 1.0 } else { -1.0 };
    let pts = p.spiral.polyline();
    let tan = biarc::tangents(&pts);
    let k = p.join.min(pts.len() - 1);
    let target = pts[k];
    // the helix ends a sixth of a turn before the angle of the join point
    let pitch = TAU * p.helix_r * l.params.ramp_angle_deg.to_radians().tan();
    let top = l.top_near(p.start, l.r + p.helix_r + 0.05).max(z);
    let z_from = top + l.params.approach;
    let total = TAU * ((z_from - z) / pitch.max(1e-6));
    let a_join = (target - p.start).y.atan2((target - p.start).x);
    let a_end_want = a_join - s * TAU / 6.0;
    let a0 = a_end_want - s * total;
    let a_end = l.helix_down(p.start, p.helix_r, z_from, z, a0);
    l.down_at = Some(z);
    let e = DVec2::new(a_end.cos(), a_end.sin());
    let from = p.start + e * p.helix_r;
    let t_from = DVec2::new(-e.y, e.x) * s;
    let mut pieces: Vec<Piece> = Vec::new();
    match biarc::biarc(from, t_from, target, tan[k]) {
        Some(b) => pieces.extend(b),
        None => pieces.push(Piece::Line { to: target }),
    }
    pieces.extend(biarc::fit(&pts[k..], &tan[k..], l.params.arc_tol));
    let feed = l.feed;
    for piece in pieces {
        match piece {
            Piece::Line { to } => l.push_line(MoveKind::Cut, to.extend(z), feed),
            Piece::Arc { to, center, ccw } => l.push_arc(MoveKind::Cut, to.extend(z), center, ccw, feed),
        }
    }
}

/// One candidate of [`optimise`] and what its simulation said.
#[derive(Debug, Clone, PartialEq)]
pub struct Trial {
    /// The choice.
    pub choice: SpiralChoice,
    /// Machining time, min (`None`: the spiral could not be made).
    pub time_min: Option<f64>,
    /// Rest material, share of the reachable area.
    pub rest: f64,
    /// p99 engagement outside the entry, degrees.
    pub p99_deg: f64,
    /// Meets full clearing and the engagement bound.
    pub feasible: bool,
}

/// The candidates [`crate::pipeline::optimise_spiral`] tries: ζ per level from the maximum of
/// `f` and from four points around it (a third of the way to the boundary), and the fixed ζ of
/// [`fixed_zeta`] from the maximum.
pub fn candidates(job: &Job, regions: &Regions, geom: &LayerGeom, params: &Params) -> Result<Vec<SpiralChoice>> {
    let region = super::medial::region(regions, geom);
    let Some(piece) = region.components().into_iter().max_by(|a, b| a.area().total_cmp(&b.area())) else {
        return Err(Error::param("--strategy spiral", "the tool fits nowhere in the pocket"));
    };
    let field = AreaField::new(&piece);
    let (lo, hi) = field.bounds().unwrap_or_default();
    let (m, f0) = maximum(&field, lo, hi).unwrap_or((lo, 0.0));
    let mut out = vec![SpiralChoice { zeta: None, start: None }];
    for d in [DVec2::X, DVec2::Y, -DVec2::X, -DVec2::Y] {
        let p = m + d * (f0 / 3.0);
        if field.eval(p).v >= 0.5 * f0 {
            out.push(SpiralChoice { zeta: None, start: Some(p) });
        }
    }
    if let Some(z) = fixed_zeta(job, regions, geom, params)? {
        out.push(SpiralChoice { zeta: Some(z), start: None });
    }
    Ok(out)
}

/// The largest constant ζ whose spiral (from the maximum of `f`) keeps every turn within the
/// stepover, by bisection on the measured spacing: the baseline a fixed damping gives.
pub fn fixed_zeta(job: &Job, regions: &Regions, geom: &LayerGeom, params: &Params) -> Result<Option<f64>> {
    let fits = |z: f64| -> bool {
        let choice = SpiralChoice { zeta: Some(z), start: None };
        plan_pieces(job, regions, geom, params, &choice)
            .is_ok_and(|ps| ps.iter().all(|p| p.spiral.max_spacing <= geom.step))
    };
    // halving down from a wide spiral (each try is quick: few turns) to the first that fits,
    // then bisection between it and the one before
    let mut hi = 0.5;
    if fits(hi) {
        return Ok(Some(hi));
    }
    let mut lo = hi;
    loop {
        lo *= 0.5;
        if lo < 1e-4 {
            return Ok(None);
        }
        if fits(lo) {
            break;
        }
        hi = lo;
    }
    for _ in 0..6 {
        let m = (lo * hi).sqrt();
        if fits(m) { lo = m } else { hi = m }
    }
    Ok(Some(lo))
}
