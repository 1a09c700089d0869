//! Oscillator spirals (paper 4, Kalmar-Nagy & Erdim): one smooth path from the inside of the
//! pocket out to its walls, with no link.
//!
//! The tool-centre region ([`super::medial::region`]) is embedded in an implicit function `f`,
//! positive inside and zero on the boundary ([`crate::implicit::region::AreaField`], §3), and
//! `f`, read as the energy of an oscillator with negative damping ζ (eq. 6), gives a trajectory
//! that spirals out from a helix entry at the maximum of `f` across its level sets to the
//! boundary and follows it for one turn ([`crate::implicit::oscillator`]); ζ is constant or
//! chosen per level for the stepover and the engagement, and the trajectory is written as
//! tangent-continuous G2/G3 biarcs. A region with islands gets a spiral over its island-free
//! core only ([`core_level`], [`CORE_FRACTION`]) and the adaptive strategy (paper 1) clears the
//! rest; the engagement floor is chosen by the spiral search of §4, Figs. 8–9. The walk-through
//! (entry, spiral, output, islands, the floor) is in `docs/spiral.md`, the mathematics in
//! `docs/implicit.md`.
//!
#![doc = include_str!("../../../../docs/figures/spiral_pockets.svg")]
//!
//! *The strategy's spirals on two example cases, drawn by the `spiral_figures` example.*

use super::{AdaptiveOptions, Context};
use crate::error::{Error, Result};
use crate::geom::arcfit::Piece;
use crate::geom::{DVec2, biarc};
use crate::implicit::levels::Grid;
use crate::implicit::oscillator::{self, Damping, EngagementLimit, Samples, Spiral, Turn, spiral_on};
use crate::implicit::region::AreaField;
use crate::implicit::shape::{Field, maximum};
use crate::model::{Job, Regions};
use crate::plan::levels::{Levels, drive};
use crate::plan::{LayerGeom, LinkOptions, Linker};
use crate::toolpath::{MoveKind, Toolpath};
use std::f64::consts::TAU;
use std::sync::{Arc, Mutex, OnceLock};

/// The level the last turn follows, mm inside the tool-centre region's boundary.
pub const TRACK_LEVEL: f64 = 0.005;

/// The radius, mm, to which the tool-centre region's convex corners are rounded before its
/// implicit function is made. At a sharp corner the last turn (the level `TRACK_LEVEL`) bends
/// at a radius of about two of that level's micrometres, and once its arcs are written to 1 µm
/// their tangents at the ends tilted by several degrees (5.4° on square_pocket). Rounded, they
/// bend gently; at a right-angled corner the tool (radius r) then leaves a sliver of about
/// (1 − π/4)·((r + R)² − r²) mm² more than it must, R this radius.
pub const CORNER_RADIUS: f64 = 0.25;

/// Points of the integrated spiral closer than this, mm, to the one kept before are dropped
/// before the biarcs are fitted.
pub const MIN_POINT_GAP: f64 = 0.01;

/// Shortest chord wanted of a written arc, mm (see `geom::biarc::Tolerance::min_len`).
pub const MIN_ARC: f64 = 0.12;

/// How far a written arc may cut inside the integrated spiral where it is widened to
/// [`MIN_ARC`], mm (outwards it keeps to the arc tolerance).
pub const CORNER_CUT: f64 = 0.02;

/// The least gap between turns, as a fraction of the stepover, that the engagement limit may
/// ask for in a spiral made with a constant ζ or a [`SpiralChoice::default`] (see
/// [`EngagementLimit::floor`]). Where levels turn tighter than the floor allows (the hairpin
/// tips of the levels creeping along an L's legs, the levels near a polygon's corners) the
/// engagement rises above the reference; a `rough` job chooses the floor among [`FLOORS`] by
/// simulation unless one is given (the spiral search (`optimise_spiral`)).
pub const ENGAGEMENT_FLOOR: f64 = 0.35;

/// The spiral strategy's options (paper 4).
#[derive(Debug, Clone, PartialEq)]
pub struct SpiralOptions {
    /// A constant damping ζ (eq. 6) in (0, 1] instead of ζ chosen per level for the stepover and
    /// the engagement.
    pub zeta: Option<f64>,
    /// Start here instead of at the maximum of the region's implicit function.
    pub start: Option<DVec2>,
    /// With ζ per level: the least gap between turns the engagement limit may ask for where
    /// turns curve tightly, as a fraction of the stepover in (0, 1]
    /// ([`EngagementLimit::floor`]); `None` tries [`FLOORS`] and keeps the fastest within the
    /// engagement bound (the spiral search (`optimise_spiral`)).
    pub floor: Option<f64>,
    /// Also try four other start points round the maximum of f (paper 4 §4, Figs. 8–9); the
    /// floor is chosen by simulation unless `floor` or `zeta` is set.
    pub optimise: bool,
    /// The cells the search's simulations may sweep before it begins no new round of
    /// candidates (see `optimise_spiral`): [`SEARCH_CELLS`] by default.
    pub search_cells: f64,
    /// The adaptive passes that clear round islands (a pocket with islands gets a spiral over
    /// its island-free core only).
    pub adaptive: AdaptiveOptions,
}

impl SpiralOptions {
    /// ζ per level, the floor chosen by simulation, from the maximum of f.
    pub const DEFAULT: SpiralOptions = SpiralOptions {
        zeta: None,
        start: None,
        floor: None,
        optimise: false,
        search_cells: SEARCH_CELLS,
        adaptive: AdaptiveOptions::DEFAULT,
    };
}

impl Default for SpiralOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// How a spiral is made: the damping and the start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpiralChoice {
    /// A constant ζ, or `None` for ζ per level (stepover and engagement).
    pub zeta: Option<f64>,
    /// The start point, or `None` for the maximum of `f`.
    pub start: Option<DVec2>,
    /// With ζ per level: the least gap the engagement limit may ask for, as a fraction of the
    /// stepover ([`EngagementLimit::floor`]).
    pub floor: f64,
}

impl Default for SpiralChoice {
    fn default() -> Self {
        SpiralChoice { zeta: None, start: None, floor: ENGAGEMENT_FLOOR }
    }
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

/// The spirals of a job's tool-centre region, one per connected piece, and whether the pieces
/// leave material to other passes: a piece with islands gets a spiral over its island-free
/// core only ([`core_level`]), and the adaptive strategy clears the rest.
pub fn plan_pieces(
    job: &Job,
    regions: &Regions,
    geom: &LayerGeom,
    link: &LinkOptions,
    choice: &SpiralChoice,
) -> Result<(Vec<PiecePath>, bool)> {
    plan_pieces_in(job, &SpiralFields::new(regions, geom), geom, link, choice)
}

/// [`plan_pieces`] on the fields of the region's pieces, made once for every spiral the search
/// tries.
pub(crate) fn plan_pieces_in(
    job: &Job,
    fields: &SpiralFields,
    geom: &LayerGeom,
    link: &LinkOptions,
    choice: &SpiralChoice,
) -> Result<(Vec<PiecePath>, bool)> {
    let mut out = Vec::new();
    let mut islands = false;
    for piece in &fields.pieces {
        islands |= piece.holes;
        if let Some(p) = plan_piece(job, piece, geom, link, choice)? {
            out.push(p);
        }
    }
    if out.is_empty() && !islands {
        return Err(Error::job("spiral strategy", "the tool fits nowhere in the pocket"));
    }
    Ok((out, islands))
}

/// What every spiral over a job's region shares, whatever its damping: each connected piece of
/// the region, its implicit function with the piece's corners rounded, the maximum of that
/// function, and the samples of the function shaped from each start (the grid the core level
/// and the ζ per level read). The spiral search plans a dozen spirals over the same region:
/// made once, these are most of a spiral's planning.
pub(crate) struct SpiralFields {
    pieces: Vec<PieceField>,
}

/// One connected piece of the region.
struct PieceField {
    /// It has islands.
    holes: bool,
    /// Its rounded implicit function and where that is largest, unless the piece vanishes when
    /// rounded.
    shape: Option<PieceShape>,
}

/// A grid sampled once and shared by the threads that ask for it.
type SharedGrid = Arc<OnceLock<Option<Samples>>>;

struct PieceShape {
    base: AreaField,
    top: DVec2,
    fmax: f64,
    /// [`Samples::of_field`] of the shaped function from each start asked for so far.
    grids: Mutex<Vec<(DVec2, SharedGrid)>>,
}

impl SpiralFields {
    /// The fields of the region of `regions` and `geom` the spiral covers (that of the medial
    /// strategy).
    pub(crate) fn new(regions: &Regions, geom: &LayerGeom) -> SpiralFields {
        let region = super::medial::region(regions, geom);
        let pieces = region
            .components()
            .into_iter()
            .map(|piece| {
                let holes = piece.polys.iter().any(|p| !p.holes.is_empty());
                // the region with its convex corners rounded (an opening by CORNER_RADIUS)
                let rounded = piece.offset(-CORNER_RADIUS, 1e-3).offset(CORNER_RADIUS, 1e-3);
                let shape = (!rounded.is_empty()).then(|| AreaField::new(&rounded)).and_then(|base| {
                    let (lo, hi) = base.bounds()?;
                    let (top, fmax) = maximum(&base, lo, hi).unwrap_or((lo, 0.0));
                    Some(PieceShape { base, top, fmax, grids: Mutex::new(Vec::new()) })
                });
                PieceField { holes, shape }
            })
            .collect();
        SpiralFields { pieces }
    }

    /// The region's connected pieces.
    pub(crate) fn pieces(&self) -> usize {
        self.pieces.len()
    }

    /// Samples now, every piece at once, what the spirals of `choice`'s start read (each piece's
    /// grid and the profile of its levels, the same for every damping): the spirals of a round
    /// of the search, planned in parallel, would otherwise wait for them one piece after another.
    pub(crate) fn prepare(&self, job: &Job, geom: &LayerGeom, link: &LinkOptions, choice: &SpiralChoice) {
        use rayon::prelude::*;
        self.pieces.par_iter().for_each(|piece| {
            if let Some(s) = piece_spiral(job, piece, geom, link, choice)
                && let Some(samples) = s.samples.get().and_then(Option::as_ref)
            {
                samples.prepare(&s.field, s.start, &s.opts);
            }
        });
    }
}

impl PieceShape {
    /// The shaped function from `start` and its samples (sampled once for every spiral from
    /// there).
    fn shaped(&self, start: DVec2) -> (Shaped<'_>, SharedGrid) {
        let field = Shaped { f: &self.base, s: start, l: SHAPE_LENGTH * self.fmax.max(1e-3) };
        let cell = {
            let mut grids = self.grids.lock().unwrap_or_else(|e| e.into_inner());
            match grids.iter().find(|(s, _)| *s == start) {
                Some((_, c)) => c.clone(),
                None => {
                    let c = Arc::new(OnceLock::new());
                    grids.push((start, c.clone()));
                    c
                }
            }
        };
        cell.get_or_init(|| Samples::of_field(&field));
        (field, cell)
    }
}

/// The lowest level of `f` down to which the set `f ≥ c` round `start` is simply connected
/// (it has not yet closed round an island), from `f` sampled on a 256² grid: bisection on c,
/// each test a flood fill of the set from the start and of the rest from the grid's border
/// (4- and 8-connected, so that a diagonal pair of cells neither closes nor opens a hole). A
/// spiral out to a level above it covers a simply connected core.
pub fn core_level(field: &dyn Field, start: DVec2, f_floor: f64) -> Option<f64> {
    core_level_on(field, &Grid::of_field(field)?, start, f_floor)
}

/// [`core_level`] on `grid`, [`Grid::of_field`] of `field`.
fn core_level_on(field: &dyn Field, grid: &Grid, start: DVec2, f_floor: f64) -> Option<f64> {
    // (nodes: one more than cells each way)
    let (nx, ny) = (grid.nx + 1, grid.ny + 1);
    let at = |i: usize, j: usize| grid.vals[j * nx + i].v;
    let si = (((start.x - grid.lo.x) / grid.step.x).round().max(0.0) as usize).min(nx - 1);
    let sj = (((start.y - grid.lo.y) / grid.step.y).round().max(0.0) as usize).min(ny - 1);
    let simple = |c: f64| -> bool {
        let mut inside = vec![false; nx * ny];
        let mut stack = vec![(si, sj)];
        if at(si, sj) < c {
            return true;
        }
        inside[sj * nx + si] = true;
        while let Some((i, j)) = stack.pop() {
            for (di, dj) in [(1i64, 0i64), (-1, 0), (0, 1), (0, -1)] {
                let (a, b) = (i as i64 + di, j as i64 + dj);
                if a < 0 || b < 0 || a >= nx as i64 || b >= ny as i64 {
                    continue;
                }
                let (a, b) = (a as usize, b as usize);
                if !inside[b * nx + a] && at(a, b) >= c {
                    inside[b * nx + a] = true;
                    stack.push((a, b));
                }
            }
        }
        let mut outside = vec![false; nx * ny];
        let mut stack = Vec::new();
        let border = (0..nx).flat_map(|i| [(i, 0), (i, ny - 1)]).chain((0..ny).flat_map(|j| [(0, j), (nx - 1, j)]));
        for (i, j) in border {
            if !inside[j * nx + i] && !outside[j * nx + i] {
                outside[j * nx + i] = true;
                stack.push((i, j));
            }
        }
        while let Some((i, j)) = stack.pop() {
            for di in -1i64..=1 {
                for dj in -1i64..=1 {
                    let (a, b) = (i as i64 + di, j as i64 + dj);
                    if a < 0 || b < 0 || a >= nx as i64 || b >= ny as i64 {
                        continue;
                    }
                    let (a, b) = (a as usize, b as usize);
                    if !inside[b * nx + a] && !outside[b * nx + a] {
                        outside[b * nx + a] = true;
                        stack.push((a, b));
                    }
                }
            }
        }
        inside.iter().zip(&outside).all(|(a, b)| *a || *b)
    };
    let f0 = field.eval(start).v;
    if simple(f_floor) {
        return Some(f_floor);
    }
    let (mut lo_c, mut hi_c) = (f_floor, f0);
    for _ in 0..30 {
        let m = 0.5 * (lo_c + hi_c);
        if simple(m) { hi_c = m } else { lo_c = m }
    }
    Some(hi_c)
}

/// With islands, the spiral ends at this fraction of f at its start at the lowest. Further out,
/// its levels reach round the islands in long arms (each one a ridge, as along an L's leg),
/// whose turns crowd where they start. Measured with the floor at 0.35: on boss_with_clamp a
/// spiral out to where its set closes round the boss made a 12.7 min program against 2.6 min
/// with this fraction, and on pocket_islands it met an island's level (the grid's estimate of
/// the closing level was not safe by a quarter of a stepover there).
pub const CORE_FRACTION: f64 = 0.5;

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

/// The length ℓ of `Shaped`, in units of the largest value of the region's `f` (the
/// largest inscribed radius).
pub const SHAPE_LENGTH: f64 = 1.0;

/// What a spiral over a piece from a start is made from: the shaped function and its samples,
/// the start, f there and the level the spiral ends at, and the oscillator's options.
struct PieceSpiral<'a> {
    field: Shaped<'a>,
    samples: SharedGrid,
    start: DVec2,
    f0: f64,
    f_end: f64,
    opts: oscillator::SpiralOptions,
}

/// The spiral of `choice` over `piece`, before it is made; `None` where no spiral can be made
/// there.
fn piece_spiral<'a>(
    job: &Job,
    piece: &'a PieceField,
    geom: &LayerGeom,
    link: &LinkOptions,
    choice: &SpiralChoice,
) -> Option<PieceSpiral<'a>> {
    let islands = piece.holes;
    let shape = piece.shape.as_ref()?;
    let start = choice.start.unwrap_or(shape.top);
    let (field, cell) = shape.shaped(start);
    let grid = &cell.get().and_then(Option::as_ref)?.grid;
    let f0 = field.eval(start).v;
    // with islands, out to a level a quarter of a stepover above the one where the spiral's
    // set would close round an island (the level there pinches to a point), and no further
    // than CORE_FRACTION of the way down
    let f_end = match islands {
        true => (core_level_on(&field, grid, start, TRACK_LEVEL)? + 0.25 * geom.step).max(CORE_FRACTION * f0),
        false => TRACK_LEVEL,
    };
    if f0 <= f_end + 1e-3 {
        // a sliver the tool fits in only along a line, or a core too small: nothing a spiral
        // can do
        return None;
    }
    let r = geom.r;
    let theta = job.cutting.width.engagement_deg().to_radians();
    let opts = oscillator::SpiralOptions {
        turn: if link.climb { Turn::Ccw } else { Turn::Cw },
        damping: match choice.zeta {
            Some(z) => Damping::Constant(z),
            None => Damping::stepover(geom.step),
        },
        f_end,
        engagement: choice.zeta.is_none().then_some(EngagementLimit { r, theta, floor: choice.floor }),
        // (the gaps are held to the stepover and the engagement level by level; where the
        // levels round a corner they open wider, and where a level crosses a ridge of f (the
        // centre line of a leg of an L) it jumps along it: the measured gap says nothing about
        // clearing there, which the simulation judges)
        accept_gap: Some(f64::INFINITY),
        ..Default::default()
    };
    Some(PieceSpiral { field, samples: cell, start, f0, f_end, opts })
}

fn plan_piece(
    job: &Job,
    piece: &PieceField,
    geom: &LayerGeom,
    link: &LinkOptions,
    choice: &SpiralChoice,
) -> Result<Option<PiecePath>> {
    let islands = piece.holes;
    let Some(PieceSpiral { field, samples, start, f0, f_end, opts }) = piece_spiral(job, piece, geom, link, choice)
    else {
        return Ok(None);
    };
    let Some(samples) = samples.get().and_then(Option::as_ref) else { return Ok(None) };
    let r = geom.r;
    let sp = match spiral_on(&field, start, &opts, Some(samples)) {
        Ok(sp) => sp,
        // (with islands the adaptive passes clear what a spiral cannot)
        Err(_) if islands => return Ok(None),
        Err(Error::Job { reason, .. }) => return Err(Error::job("spiral strategy", reason)),
        Err(e) => return Err(e),
    };
    // the helix: at most half the tool radius, inside the region
    let helix_r = (link.helix_radius_frac * r).min(0.5 * r).min(0.8 * (f0 - f_end));
    let join = sp.points.iter().position(|q| (q.p - start).length() >= helix_r).unwrap_or(sp.points.len() - 1);
    Ok(Some(PiecePath { start, helix_r, spiral: sp, join }))
}

/// Builds the program of a level job from its spirals (with the adaptive passes of `adaptive`
/// round islands).
pub(crate) fn link_spiral(
    cx: &Context,
    fields: &SpiralFields,
    adaptive: &AdaptiveOptions,
    choice: &SpiralChoice,
) -> Result<Toolpath> {
    let (pieces, islands) = plan_pieces_in(cx.job, fields, cx.geom, cx.link, choice)?;
    let first = pieces.first().map_or_else(|| cx.geom.centres.bounds().map_or(DVec2::ZERO, |(lo, _)| lo), |p| p.start);
    if islands {
        let mut levels = super::adaptive::AdaptiveLevels::new(cx, adaptive, first, |l: &mut Linker, z| {
            l.tp.note("spiral over the island-free core; adaptive passes for the rest");
            for p in &pieces {
                cut_piece(l, p, z);
            }
        });
        return drive(cx.job, cx.regions, cx.link, cx.sim, cx.zs, cx.finish, &mut levels);
    }
    drive(cx.job, cx.regions, cx.link, cx.sim, cx.zs, cx.finish, &mut SpiralLevels { pieces: &pieces, first })
}

/// The spirals of the pieces, the same at every level.
struct SpiralLevels<'p> {
    pieces: &'p [PiecePath],
    first: DVec2,
}

impl<'a> Levels<'a> for SpiralLevels<'_> {
    fn first(&self) -> DVec2 {
        self.first
    }

    fn level(&mut self, l: &mut Linker<'a>, z: f64) -> Result<()> {
        for p in self.pieces {
            cut_piece(l, p, z);
        }
        Ok(())
    }
}

/// Enters at the piece's start and cuts its spiral at `z`.
fn cut_piece(l: &mut Linker, p: &PiecePath, z: f64) {
    let s = if l.link.climb { 1.0 } else { -1.0 };
    // points closer than MIN_POINT_GAP to the one before are dropped (the last one is kept
    // and its predecessor dropped instead): a biarc between two such points is a few µm
    // long, and once written to 1 µm its ends point anywhere
    let all = &p.spiral.points;
    let mut pts: Vec<DVec2> = Vec::with_capacity(all.len());
    let mut tan: Vec<DVec2> = Vec::with_capacity(all.len());
    let mut k = 0;
    for (i, q) in all.iter().enumerate() {
        if let Some(last) = pts.last()
            && (q.p - *last).length() < MIN_POINT_GAP
        {
            if i + 1 < all.len() || pts.len() < 2 {
                continue;
            }
            pts.pop();
            tan.pop();
        }
        if i <= p.join {
            k = pts.len();
        }
        pts.push(q.p);
        tan.push(q.t);
    }
    let k = k.min(pts.len() - 1);
    let target = pts[k];
    // the helix ends a sixth of a turn before the angle of the join point
    let pitch = TAU * p.helix_r * l.link.ramp_angle_deg.to_radians().tan();
    let top = l.top_near(p.start, l.r + p.helix_r + 0.05).max(z);
    let z_from = top + l.link.approach;
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
    let tol = biarc::Tolerance {
        tol: l.link.arc_tol,
        min_len: MIN_ARC,
        loose: CORNER_CUT,
        // the biarcs may cut a bend inwards (towards the start), never outwards
        side: -s,
    };
    pieces.extend(biarc::fit(&pts[k..], &tan[k..], tol));
    let feed = l.feed;
    for piece in pieces {
        match piece {
            Piece::Line { to } => l.push_line(MoveKind::Cut, to.extend(z), feed),
            Piece::Arc { to, center, ccw } => l.push_arc(MoveKind::Cut, to.extend(z), center, ccw, feed),
        }
    }
}

/// One candidate of the spiral search (`optimise_spiral`) and what was found out about it.
#[derive(Debug, Clone, PartialEq)]
pub struct Trial {
    /// The choice.
    pub choice: SpiralChoice,
    /// Machining time of its program, min (`None`: the spiral could not be made).
    pub time_min: Option<f64>,
    /// What its simulation said; `None` where it was not simulated (a faster candidate was
    /// already found feasible, or it could not be made).
    pub sim: Option<TrialSim>,
}

/// A simulated candidate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrialSim {
    /// Gouges (cuts into the part).
    pub gouges: usize,
    /// Rest material, share of the reachable area.
    pub rest: f64,
    /// p99 engagement outside the entry, degrees.
    pub p99_deg: f64,
    /// Meets full clearing and the engagement bound.
    pub feasible: bool,
}

impl Trial {
    /// Simulated and feasible.
    pub fn feasible(&self) -> bool {
        self.sim.is_some_and(|s| s.feasible)
    }
}

/// The cells the search's simulations may sweep (cutting length × tool diameter / cell², summed
/// over the candidates simulated) before it stops beginning new rounds. Simulating a spiral
/// costs about 0.04–0.1 s per million cells on the 2-core machine the shared drawings were
/// timed on; this keeps a search within about 10 s there.
pub const SEARCH_CELLS: f64 = 60e6;

/// The floors ([`SpiralChoice::floor`]) the optimiser tries, widest first.
pub const FLOORS: [f64; 6] = [0.5, 0.42, 0.35, 0.28, 0.22, 0.16];

/// The candidates the spiral search (`optimise_spiral`) tries: ζ per level with each of
/// [`FLOORS`], from `start` (`None`: the maximum of `f`), and with `around` also from four
/// points round the maximum (a third of the way to the boundary). (A constant ζ is not among
/// them: where it keeps the engagement it is slower than ζ per level on every case measured,
/// see `best_fixed_zeta`.)
pub fn candidates(
    regions: &Regions,
    geom: &LayerGeom,
    start: Option<DVec2>,
    around: bool,
) -> Result<Vec<SpiralChoice>> {
    let mut starts = vec![start];
    if around {
        let region = super::medial::region(regions, geom);
        let Some(piece) = region.components().into_iter().max_by(|a, b| a.area().total_cmp(&b.area())) else {
            return Err(Error::job("spiral strategy", "the tool fits nowhere in the pocket"));
        };
        let field = AreaField::new(&piece);
        let (lo, hi) = field.bounds().unwrap_or_default();
        let (m, f0) = maximum(&field, lo, hi).unwrap_or((lo, 0.0));
        for d in [DVec2::X, DVec2::Y, -DVec2::X, -DVec2::Y] {
            let p = m + d * (f0 / 3.0);
            if field.eval(p).v >= 0.5 * f0 {
                starts.push(Some(p));
            }
        }
    }
    let mut out = Vec::new();
    for start in starts {
        for floor in FLOORS {
            out.push(SpiralChoice { zeta: None, start, floor });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Area;

    #[test]
    fn the_core_of_a_pocket_with_an_island_stops_short_of_the_island() {
        // a 40 × 20 rectangle with a 4 × 4 island off-centre: from the maximum of f in the
        // larger part, the set f ≥ c closes round the island at some level between 0 and the top
        let area = Area::rect(0.0, 0.0, 40.0, 20.0).difference(&Area::rect(26.0, 8.0, 30.0, 12.0));
        let field = AreaField::new(&area);
        let start = DVec2::new(10.0, 10.0);
        let f0 = field.eval(start).v;
        let c = core_level(&field, start, TRACK_LEVEL).expect("a bounded field");
        assert!(c > 0.05 * f0 && c < f0, "core level {c} of {f0}");
        // just above it the set is a disk round the start that has not reached round the
        // island: the island's centre is outside it, and so is the far end of the pocket
        let far = DVec2::new(38.0, 10.0);
        assert!(field.eval(far).v < c, "the far end is reached before the island is enclosed");
        // a region without islands is simply connected all the way down
        let plain = AreaField::new(&Area::rect(0.0, 0.0, 40.0, 20.0));
        assert_eq!(core_level(&plain, start, TRACK_LEVEL), Some(TRACK_LEVEL));
    }
}
