//! Region by region through the levels: the order and the links of a z-level program (paper 3:
//! a program's cost counts its air length `l_air` beside its cutting length, §3 eq. 3).
//!
//! Each level is planned on the stock the levels above left, as one 2.5D job, so a level's
//! program goes from region to region at its own depth: on a cavity with four corner bores,
//! every level under the floor crosses the part four times at the safe height. Here the levels'
//! programs are cut into *pieces* at every travel (a run of rapids that rises, and the runs
//! that begin and end a level): a piece begins where the tool arrives above its entry and ends
//! where it leaves its last cut. Two pieces whose footprints share a cell keep the order they
//! were planned in (a footprint: the cells, [`CELL_FRAC`] of a tool radius wide, that the tool's
//! disk meets along every move of the piece, grown by [`FOOTPRINT_PAD`]), so that every piece
//! meets the very material it was planned on; pieces apart may change places. From the first
//! piece on, the next is the ready one (every piece it must follow cut) whose link is the
//! shortest, measured for the nearest few on the material the pieces so far left:
//!
//! ```text
//!   level 20     A ██        B ██          order planned:  A20 B20 A21 B21 A22 B22 …
//!   level 21     A ██        B ██          order linked:   A20 A21 A22 … B20 B21 B22 …
//!   level 22     A ██        B ██          (each bore cut to its bottom in turn)
//! ```
//!
//! A link is the piece's own planned travel where it follows its planned predecessor and every
//! piece planned before it has been cut (the material is then what it was planned on, or less);
//! else straight across at the height of the higher end when that way is clear (or only leaves
//! the material the tool touches at its start, that stretch fed); else round the material at
//! that height (the keep-down search of [`crate::plan::route`]) when shorter than lifting; else
//! just over the material on the way (its top within the radius and half a millimetre, plus the
//! approach height); else at the safe height. Every way is tested on the model's cells and on
//! the part's exact outline at its height ([`Keeps`]: a rib thinner than a cell is invisible to
//! the cells). [`crate::plan::LinkOptions::by_level`] keeps the planned order (each level over
//! the whole part before the next), with the links still planned so.

use crate::geom::index::EdgeIndex;
use crate::geom::{Area, DVec2, DVec3};
use crate::sim::raster::RasterSim;
use crate::sim::sweep::{Path, keep_distance};
use crate::toolpath::{ArcGeom, Motion, Move, MoveKind, Note, Toolpath, move_xy_length};

/// The footprint cells' size as a fraction of the tool radius: a footprint reaches up to a cell
/// beyond the tool, so cells a whole radius wide tied the pieces on the two sides of any wall
/// thinner than about two radii (a frame's inside was then cut level by level with its outside);
/// with a quarter, walls from about 0.6 R + 1 mm part them.
pub(crate) const CELL_FRAC: f64 = 0.25;
/// How far beyond the tool's radius a footprint reaches, mm (on top of the sampling's own
/// allowance): the model's cells and the links' margins.
pub(crate) const FOOTPRINT_PAD: f64 = 0.5;
/// How many of the ready pieces, nearest first by a cheap estimate, have their links planned
/// to choose the next.
const CANDIDATES: usize = 4;
/// The most lattice nodes a link's search round the material expands.
const ROUTE_NODES: usize = 4000;

/// A piece of a level's program between two travels.
struct Piece {
    /// Index of the level (in planning order).
    level: usize,
    /// The level's depth.
    z: f64,
    /// Where the tool is when the piece begins (above its entry, or at depth).
    start: DVec3,
    moves: Vec<Move>,
    /// Notes, `at` counted from the piece's first move.
    notes: Vec<Note>,
    /// The planned travel into the piece from `prev`'s end.
    travel: Vec<Move>,
    /// The piece planned just before this one in the same level, when there is one.
    prev: Option<usize>,
}

#[cfg(test)]
impl Piece {
    fn end(&self) -> DVec3 {
        self.moves.last().map_or(self.start, |m| m.to)
    }
}

/// The levels' programs cut into pieces (in planning order).
fn pieces_of(levels: &[(f64, Toolpath)]) -> Vec<Piece> {
    let mut out: Vec<Piece> = Vec::new();
    for (li, (z, tp)) in levels.iter().enumerate() {
        let n = tp.moves.len();
        let mut from = Vec::with_capacity(n);
        let mut p = tp.start;
        for m in &tp.moves {
            from.push(p);
            p = m.to;
        }
        // the travels: runs of rapids that rise, and the runs a level begins and ends with
        let mut runs = Vec::new();
        let mut i = 0;
        while i < n {
            if !tp.moves[i].is_rapid() {
                i += 1;
                continue;
            }
            let a = i;
            while i < n && tp.moves[i].is_rapid() {
                i += 1;
            }
            if a == 0 || i == n || (a..i).any(|k| tp.moves[k].to.z > from[k].z + 1e-9) {
                runs.push((a, i));
            }
        }
        runs.push((n, n));
        let mut cur = 0;
        let mut before = (0, 0);
        let mut first = true;
        for &(a, b) in &runs {
            if a > cur {
                let notes = tp
                    .notes
                    .iter()
                    .filter(|nt| nt.at >= before.0 && nt.at < a)
                    .map(|nt| Note { at: nt.at.saturating_sub(cur), text: nt.text.clone() })
                    .collect();
                let id = out.len();
                out.push(Piece {
                    level: li,
                    z: *z,
                    start: if cur == 0 { tp.start } else { from[cur] },
                    moves: tp.moves[cur..a].to_vec(),
                    notes,
                    travel: if first { Vec::new() } else { tp.moves[before.0..before.1].to_vec() },
                    prev: if first { None } else { Some(id - 1) },
                });
                first = false;
            }
            before = (a, b);
            cur = b;
        }
    }
    out
}

/// The footprint of `piece` on cells of `size` from `origin` (`nx` cells a row), sorted.
#[cfg(test)]
fn footprint(piece: &Piece, r: f64, origin: DVec2, size: f64, nx: i64) -> Vec<u32> {
    footprint_marked(piece, r, origin, size, nx, &mut Marks::default())
}

/// Cells already in the footprint being built: the mark of the footprint that last took each
/// cell (a piece's disk covers a hundred cells at every half-cell step, mostly the same ones as
/// the step before: listing them all and sorting was most of the linking's time).
#[derive(Default)]
struct Marks {
    by_cell: Vec<u32>,
    now: u32,
}

/// [`footprint`] with `marks` kept from one footprint to the next.
fn footprint_marked(piece: &Piece, r: f64, origin: DVec2, size: f64, nx: i64, marks: &mut Marks) -> Vec<u32> {
    marks.now += 1;
    let now = marks.now;
    let reach = r + FOOTPRINT_PAD + 0.25 * size;
    let mut cells = Vec::new();
    let mut mark = |p: DVec2| {
        let lo = ((p - reach - origin) / size).floor();
        let hi = ((p + reach - origin) / size).floor();
        for j in (lo.y.max(0.0) as i64)..=(hi.y.max(0.0) as i64) {
            for i in (lo.x.max(0.0) as i64)..=(hi.x.max(0.0) as i64).min(nx - 1) {
                let c = (j * nx + i) as usize;
                if c >= marks.by_cell.len() {
                    marks.by_cell.resize(c + 1, 0);
                }
                if marks.by_cell[c] != now {
                    marks.by_cell[c] = now;
                    cells.push(c as u32);
                }
            }
        }
    };
    let mut from = piece.start;
    mark(from.truncate());
    for m in &piece.moves {
        let len = move_xy_length(from, m);
        let steps = (len / (0.5 * size)).ceil().max(1.0) as usize;
        for k in 1..=steps {
            let t = k as f64 / steps as f64;
            let p = match m.motion {
                Motion::Line => from.lerp(m.to, t),
                Motion::Arc { center, ccw } => ArcGeom::new(from, m.to, center, ccw).at(t),
            };
            mark(p.truncate());
        }
        from = m.to;
    }
    cells.sort_unstable();
    cells
}

/// The part as each level saw it: the shadow of the mesh above the level grown by the
/// allowance (exact outlines, where the model's cells can miss a thin rib).
pub(crate) struct Keeps {
    /// Each level's depth and its region to keep out of, top down.
    levels: Vec<(f64, Area, EdgeIndex)>,
    /// Above this nothing is kept out of (the part's top with its allowance).
    top: f64,
}

impl Keeps {
    /// No level yet; above `top` nothing is kept out of.
    pub(crate) fn new(top: f64) -> Self {
        Keeps { levels: Vec::new(), top }
    }

    /// Adds the region to keep out of at depth `z` (levels in order, top down).
    pub(crate) fn push(&mut self, z: f64, keep: &Area, r: f64) {
        self.levels.push((z, keep.clone(), EdgeIndex::from_area(keep, (2.0 * r).max(1.0))));
    }

    /// Does the tool of radius `r` along the straight `path` at height `z` keep off the part?
    /// Tested against the region of the highest level at or below `z` (the shadow only grows
    /// downward, so that region holds everything above `z`), or the lowest one.
    fn clear(&self, path: &Path, z: f64, r: f64) -> bool {
        if z >= self.top + 0.01 {
            return true;
        }
        let Some((_, keep, edges)) = self.levels.iter().find(|l| l.0 <= z + 1e-9).or(self.levels.last()) else {
            return true;
        };
        keep_distance(keep, edges, path, r) >= r - 1e-6
    }
}

/// The links' planner on the material the pieces so far left.
pub(crate) struct Links<'a> {
    pub(crate) sim: &'a RasterSim,
    pub(crate) keeps: &'a Keeps,
    pub(crate) r: f64,
    pub(crate) safe_z: f64,
    pub(crate) approach: f64,
    /// Extra radius for the tests of the model's cut cells (see the linker's `clear_margin`).
    pub(crate) margin: f64,
}

/// A step of a link: a rapid, or a feed move while the tool leaves material it touches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Step {
    pub(crate) to: DVec3,
    pub(crate) fed: bool,
}

impl Links<'_> {
    /// The way from `e` to `s`: straight across at the higher end's height when clear (with
    /// half a millimetre to spare), or when it only leaves material the tool touches at the
    /// start (that stretch fed, as the linker's links at depth) and touches nothing else;
    /// else just over the material on the way; else at the safe height. Rises and descents
    /// are vertical.
    pub(crate) fn way(&self, e: DVec3, s: DVec3) -> Vec<Step> {
        let (a, b) = (e.truncate(), s.truncate());
        if (a - b).length() < 1e-9 {
            return if (e.z - s.z).abs() > 1e-9 { vec![Step { to: s, fed: false }] } else { Vec::new() };
        }
        let wide = 0.5 + self.margin;
        let across = |h: f64| Path::Line { a: a.extend(h), b: b.extend(h) };
        let h0 = e.z.max(s.z);
        let kept = |h: f64| self.keeps.clear(&across(h), h, self.r);
        if self.sim.is_clear(&across(h0), wide) && kept(h0) {
            return at_height(e, s, h0, &[b], 0.0);
        }
        if let Some(t) = self.sim.leaving_distance(a.extend(h0), b.extend(h0), self.margin)
            && kept(h0)
        {
            return at_height(e, s, h0, &[b], t);
        }
        // over the material on the way, or at the safe height
        let top = self.sim.max_height_near(&across(h0), self.r + wide) as f64;
        let over = (top + self.approach).max(h0);
        let h = if over < self.safe_z - 1e-9 && self.sim.is_clear(&across(over), wide) && kept(over) {
            over
        } else {
            self.safe_z.max(h0)
        };
        let lifted = at_height(e, s, h, &[b], 0.0);
        // or round the material at the height of the higher end, when that is shorter
        let rise = (h0 - e.z) + (h0 - s.z);
        let budget = steps_length(e, &lifted) - rise;
        if budget > (b - a).length() + 1e-6
            && let Some(way) = self.around(a, b, h0, budget)
        {
            let from = if h0 > e.z + 1e-9 { a.extend(h0) } else { e };
            let t = way.first().and_then(|w| self.sim.leaving_distance(from, w.extend(h0), self.margin)).unwrap_or(0.0);
            return at_height(e, s, h0, &way, t);
        }
        lifted
    }

    /// A way at `z` from `a` to `b` round the material (see [`crate::plan::route`]), its
    /// legs no longer than `budget` in all: its waypoints after `a`.
    fn around(&self, a: DVec2, b: DVec2, z: f64, budget: f64) -> Option<Vec<DVec2>> {
        let h = (0.5 * self.r).max(4.0 * self.sim.grid.res);
        let reach = self.r + self.margin + 0.75 * h;
        let top = |p: DVec2| self.sim.max_height_near(&Path::Line { a: p.extend(0.0), b: p.extend(0.0) }, reach) as f64;
        let line = |p: DVec2, q: DVec2| Path::Line { a: p.extend(z), b: q.extend(z) };
        let g = &self.sim.grid;
        let lo = DVec2::new(g.x0, g.y0) - 2.0 * reach;
        let hi = DVec2::new(g.x0 + g.nx as f64 * g.res, g.y0 + g.ny as f64 * g.res) + 2.0 * reach;
        crate::plan::route::route(
            a,
            b,
            h,
            budget,
            ROUTE_NODES,
            // (beyond the model's grid there is no material: the way may go round the stock)
            |p| {
                p.cmpge(lo).all() && p.cmple(hi).all() && top(p) <= z + 0.01 && self.keeps.clear(&line(p, p), z, self.r)
            },
            |p| {
                self.sim.leaving_distance(a.extend(z), p.extend(z), self.margin).is_some()
                    && self.keeps.clear(&line(a, p), z, self.r)
            },
            |p, q| self.sim.is_clear(&line(p, q), self.margin) && self.keeps.clear(&line(p, q), z, self.r),
        )
    }
}

/// The steps of a way at height `h` from `e` to `s` through the places `legs` (the last one
/// `s`'s): up to `h` when `e` is below it, the first leg fed for its first `t` mm (where the
/// tool still touches what it touched at `e`), rapids otherwise, down to `s` when it is below.
fn at_height(e: DVec3, s: DVec3, h: f64, legs: &[DVec2], t: f64) -> Vec<Step> {
    let rapid = |to: DVec3| Step { to, fed: false };
    let mut out = Vec::with_capacity(legs.len() + 3);
    if h > e.z + 1e-9 {
        out.push(rapid(e.truncate().extend(h)));
    }
    let mut from = e.truncate();
    for (k, w) in legs.iter().enumerate() {
        if k == 0 && t > 0.0 {
            let len = (*w - from).length().max(1e-12);
            out.push(Step { to: from.lerp(*w, (t / len).min(1.0)).extend(h), fed: true });
        }
        out.push(rapid(w.extend(h)));
        from = *w;
    }
    if h > s.z + 1e-9 {
        out.push(rapid(s));
    }
    out
}

fn steps_length(from: DVec3, way: &[Step]) -> f64 {
    let mut p = from;
    let mut l = 0.0;
    for q in way {
        l += (q.to - p).length();
        p = q.to;
    }
    l
}

fn moves_length(from: DVec3, moves: &[Move]) -> f64 {
    let mut p = from;
    let mut l = 0.0;
    for m in moves {
        l += crate::toolpath::move_length(p, m);
        p = m.to;
    }
    l
}

/// What the relinking needs to know of the job.
pub(crate) struct Linking {
    pub(crate) r: f64,
    pub(crate) safe_z: f64,
    pub(crate) approach: f64,
    /// Keep the planned order (level by level).
    pub(crate) by_level: bool,
    /// The feed of a link's stretch that leaves material the tool touches, mm/min.
    pub(crate) link_feed: f64,
    /// The part as each level saw it.
    pub(crate) keeps: Keeps,
}

/// Orders the pieces of the levels' programs `levels` (planned in this order, each on what the
/// ones before it left) region by region, or level by level with `how.by_level`, and links them
/// on `sim`, the material model of the whole job before any cut (cut as the pieces are
/// placed). `number` gives the note a level's pieces are announced with.
pub(crate) fn link(
    levels: &[(f64, Toolpath)],
    sim: &mut RasterSim,
    how: &Linking,
    number: impl Fn(usize, f64) -> String,
) -> Option<Toolpath> {
    let pieces = pieces_of(levels);
    let first = pieces.first()?;
    let tool = levels[0].1.tool.clone();
    let margin = 0.75 * sim.grid.res;

    // the order the pieces must keep: a piece follows the last one before it (in planning
    // order) on each of its cells
    let size = CELL_FRAC * how.r;
    let g = &sim.grid;
    let lo = DVec2::new(g.x0, g.y0);
    let hi = lo + DVec2::new(g.nx as f64, g.ny as f64) * g.res;
    let reach = how.r + FOOTPRINT_PAD + size;
    let origin = lo - reach;
    let nx = (((hi.x - lo.x) + 2.0 * reach) / size).ceil() as i64 + 2;
    // (the last piece on each cell, by cell: usize::MAX for none)
    let mut last: Vec<usize> = Vec::new();
    let mut marks = Marks::default();
    let mut need = vec![0usize; pieces.len()];
    let mut followers: Vec<Vec<usize>> = vec![Vec::new(); pieces.len()];
    for (k, p) in pieces.iter().enumerate() {
        let mut before: Vec<usize> = Vec::new();
        for c in footprint_marked(p, how.r, origin, size, nx, &mut marks) {
            let c = c as usize;
            if c >= last.len() {
                last.resize(c + 1, usize::MAX);
            }
            let j = std::mem::replace(&mut last[c], k);
            if j != usize::MAX {
                before.push(j);
            }
        }
        before.sort_unstable();
        before.dedup();
        need[k] = before.len();
        for j in before {
            followers[j].push(k);
        }
    }

    let mut tp = Toolpath::new(tool, first.start.truncate().extend(how.safe_z), how.safe_z);
    let mut ready: Vec<usize> = (0..pieces.len()).filter(|&k| need[k] == 0).collect();
    let mut cut = vec![false; pieces.len()];
    // every piece before this one in planning order is cut
    let mut prefix = 0;
    let mut last_piece: Option<usize> = None;
    let mut level_now: Option<usize> = None;
    // (planned travels kept and their length, links planned again and theirs)
    let mut stats = (0usize, 0.0, 0usize, 0.0);
    while !ready.is_empty() {
        let e = tp.end();
        let links = Links { sim, keeps: &how.keeps, r: how.r, safe_z: how.safe_z, approach: how.approach, margin };
        let own = |k: usize| last_piece.is_some() && pieces[k].prev == last_piece && prefix >= k;
        let pick = if how.by_level {
            // planning order: the lowest ready piece
            let (i, _) = ready.iter().enumerate().min_by_key(|(_, k)| **k).unwrap_or((0, &0));
            i
        } else {
            // the nearest few by an estimate, then the shortest link among them
            let estimate = |k: usize| {
                let p = &pieces[k];
                if own(k) {
                    moves_length(e, &p.travel)
                } else {
                    (p.start.truncate() - e.truncate()).length() + (p.start.z - e.z).abs()
                }
            };
            let mut by: Vec<(f64, usize, usize)> =
                ready.iter().enumerate().map(|(i, &k)| (estimate(k), k, i)).collect();
            by.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            by.truncate(CANDIDATES);
            by.iter()
                .map(|&(est, k, i)| {
                    let cost = if own(k) { est } else { steps_length(e, &links.way(e, pieces[k].start)) };
                    (cost, k, i)
                })
                .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
                .map_or(0, |c| c.2)
        };
        let k = ready.swap_remove(pick);
        let p = &pieces[k];
        if own(k) {
            stats.0 += 1;
            stats.1 += moves_length(e, &p.travel);
            tp.moves.extend(p.travel.iter().copied());
        } else {
            let way = links.way(e, p.start);
            log::trace!(
                "link {e:.2} -> {:.2} (level {} -> {}): {:.1} mm by {:?}",
                p.start,
                last_piece.map_or(0, |l| pieces[l].level),
                p.level,
                steps_length(e, &way),
                way.iter().map(|q| q.to.z).collect::<Vec<_>>()
            );
            stats.2 += 1;
            stats.3 += steps_length(e, &way);
            for q in way {
                if q.fed {
                    tp.line(MoveKind::Link, q.to, how.link_feed);
                } else {
                    tp.rapid(q.to);
                }
            }
        }
        if level_now != Some(p.level) {
            tp.note(number(p.level, p.z));
            level_now = Some(p.level);
        }
        let base = tp.moves.len();
        for n in &p.notes {
            tp.notes.push(Note { at: base + n.at, text: n.text.clone() });
        }
        sim.cut_moves(tp.end(), &p.moves);
        tp.moves.extend(p.moves.iter().copied());
        cut[k] = true;
        while prefix < pieces.len() && cut[prefix] {
            prefix += 1;
        }
        last_piece = Some(k);
        for &f in &followers[k] {
            need[f] -= 1;
            if need[f] == 0 {
                ready.push(f);
            }
        }
    }
    debug_assert!(cut.iter().all(|&c| c), "every piece placed");
    log::debug!(
        "{} pieces: {} planned travels kept ({:.0} mm), {} links planned again ({:.0} mm)",
        pieces.len(),
        stats.0,
        stats.1,
        stats.2,
        stats.3
    );
    let end = tp.end();
    if end.z < how.safe_z - 1e-9 {
        tp.note("end: retract");
        tp.rapid(end.truncate().extend(how.safe_z));
    }
    Some(tp)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Tool;

    fn level(z: f64, spots: &[DVec2]) -> (f64, Toolpath) {
        // a level that visits each spot: travel over it, descend from 2 mm above, a short cut,
        // leave
        let safe = 10.0;
        let mut tp = Toolpath::new(Tool::flat(4.0), spots[0].extend(safe), safe);
        for (i, s) in spots.iter().enumerate() {
            if i > 0 {
                tp.rapid(tp.end().truncate().extend(safe));
                tp.rapid(s.extend(safe));
            }
            tp.rapid(s.extend(z + 2.0));
            tp.line(MoveKind::Descend, s.extend(z), 100.0);
            tp.line(MoveKind::Cut, (*s + DVec2::new(1.0, 0.0)).extend(z), 100.0);
        }
        tp.rapid(tp.end().truncate().extend(safe));
        (z, tp)
    }

    #[test]
    fn a_level_is_cut_into_pieces_at_its_travels() {
        let a = DVec2::new(0.0, 0.0);
        let b = DVec2::new(50.0, 0.0);
        let pieces = pieces_of(&[level(-1.0, &[a, b]), level(-2.0, &[a, b])]);
        assert_eq!(pieces.len(), 4);
        assert_eq!(pieces.iter().map(|p| p.moves.len()).collect::<Vec<_>>(), vec![2, 2, 2, 2]);
        assert_eq!(pieces[1].prev, Some(0));
        assert_eq!(pieces[2].prev, None);
        // the travel into the second piece: up, across, down to its approach
        assert_eq!(pieces[1].travel.len(), 3);
        assert_eq!(pieces[1].start, b.extend(1.0));
        assert_eq!(pieces[3].end(), (b + DVec2::new(1.0, 0.0)).extend(-2.0));
    }

    #[test]
    fn footprints_of_pieces_apart_do_not_meet_and_of_pieces_above_each_other_do() {
        let a = DVec2::new(0.0, 0.0);
        let b = DVec2::new(50.0, 0.0);
        let pieces = pieces_of(&[level(-1.0, &[a, b]), level(-2.0, &[a, b])]);
        let fp = |k: usize| footprint(&pieces[k], 2.0, DVec2::splat(-20.0), 2.0, 60);
        let meet = |x: &[u32], y: &[u32]| x.iter().any(|c| y.binary_search(c).is_ok());
        assert!(meet(&fp(0), &fp(2)) && meet(&fp(1), &fp(3)));
        assert!(!meet(&fp(0), &fp(1)) && !meet(&fp(0), &fp(3)) && !meet(&fp(1), &fp(2)));
        // every point the tool's disk covers is in the footprint
        let f = fp(0);
        for p in [DVec2::new(-2.0, 0.0), DVec2::new(3.0, 2.0), DVec2::new(0.5, -2.0)] {
            let c = ((p - DVec2::splat(-20.0)) / 2.0).floor();
            assert!(f.binary_search(&((c.y as i64 * 60 + c.x as i64) as u32)).is_ok(), "{p}");
        }
    }

    /// Two bores 60 mm apart in a 100 × 40 block, each cut at two levels.
    fn bores(by_level: bool) -> Toolpath {
        use crate::geom::Area;
        use crate::model::Job;
        use crate::sim::SimOptions;
        let job = Job::new("bores", Area::rect(0.0, 0.0, 100.0, 40.0), Area::empty(), 4.0, 2.0);
        let regions = job.regions(job.radius(), 0.0).expect("the block's regions");
        let mut sim = RasterSim::new(&job, &regions, &SimOptions { res: Some(0.1), ..SimOptions::DEFAULT })
            .expect("the block's model");
        let (a, b) = (DVec2::new(20.0, 20.0), DVec2::new(80.0, 20.0));
        let how = Linking { r: 2.0, safe_z: 10.0, approach: 1.0, by_level, link_feed: 500.0, keeps: Keeps::new(0.0) };
        link(&[level(-1.0, &[a, b]), level(-2.0, &[a, b])], &mut sim, &how, |li, z| format!("level {li} at {z}"))
            .expect("a program")
    }

    /// The levels the program's notes announce, in order.
    fn announced(tp: &Toolpath) -> Vec<&str> {
        tp.notes.iter().map(|n| n.text.as_str()).filter(|t| t.starts_with("level")).collect()
    }

    #[test]
    fn a_bore_is_cut_to_its_bottom_before_the_tool_leaves_it() {
        let tp = bores(false);
        assert_eq!(announced(&tp), ["level 0 at -1", "level 1 at -2", "level 0 at -1", "level 1 at -2"]);
        // the cutting moves are the levels' own, in the order A1 A2 B1 B2
        let cuts: Vec<DVec3> = tp.moves.iter().filter(|m| m.kind == MoveKind::Cut).map(|m| m.to).collect();
        assert_eq!(
            cuts,
            [
                DVec3::new(21.0, 20.0, -1.0),
                DVec3::new(21.0, 20.0, -2.0),
                DVec3::new(81.0, 20.0, -1.0),
                DVec3::new(81.0, 20.0, -2.0)
            ]
        );
        // one crossing from one bore to the other, over the block's top (0) and below the
        // safe height
        let crossings: Vec<(DVec3, DVec3)> =
            tp.segments().filter(|(f, m)| (f.x - 50.0) * (m.to.x - 50.0) < 0.0).map(|(f, m)| (f, m.to)).collect();
        assert_eq!(crossings.len(), 1, "{crossings:?}");
        assert!(crossings[0].0.z >= 0.0 && crossings[0].0.z < 10.0, "{crossings:?}");
        assert!(tp.moves.iter().all(|m| m.to.z <= 10.0 + 1e-9) && tp.end().z == 10.0);
    }

    #[test]
    fn level_by_level_keeps_the_planned_order() {
        let tp = bores(true);
        assert_eq!(announced(&tp), ["level 0 at -1", "level 1 at -2"]);
        let cuts: Vec<f64> = tp.moves.iter().filter(|m| m.kind == MoveKind::Cut).map(|m| m.to.x).collect();
        assert_eq!(cuts, [21.0, 81.0, 21.0, 81.0]);
        assert_eq!(tp.segments().filter(|(f, m)| (f.x - 50.0) * (m.to.x - 50.0) < 0.0).count(), 3);
    }

    /// A rib thinner than the model's cells, which the model does not see, is kept off by the
    /// level's exact outline: the link along a channel 10 mm wide lifts over it.
    #[test]
    fn a_link_keeps_off_a_rib_the_cells_miss() {
        use crate::geom::Area;
        use crate::model::Job;
        use crate::sim::SimOptions;
        let job = Job::new("channel", Area::rect(0.0, 0.0, 100.0, 40.0), Area::empty(), 4.0, 2.0);
        let regions = job.regions(job.radius(), 0.0).expect("the block's regions");
        let mut sim = RasterSim::new(&job, &regions, &SimOptions { res: Some(0.1), ..SimOptions::DEFAULT })
            .expect("the block's model");
        let (e, s) = (DVec3::new(20.0, 20.0, -1.0), DVec3::new(80.0, 20.0, -1.0));
        for dy in [-3.0, 0.0, 3.0] {
            let off = DVec3::new(0.0, dy, 0.0);
            sim.cut(&Path::Line { a: e + off - DVec3::X * 5.0, b: s + off + DVec3::X * 5.0 });
        }
        let mut keeps = Keeps::new(0.0);
        let crossing = |keeps: &Keeps| {
            let links = Links { sim: &sim, keeps, r: 2.0, safe_z: 10.0, approach: 1.0, margin: 0.075 };
            let mut from = e;
            let mut low = f64::INFINITY;
            for q in links.way(e, s) {
                if (from.x - 50.0) * (q.to.x - 50.0) <= 0.0 {
                    low = low.min(from.z.min(q.to.z));
                }
                from = q.to;
            }
            low
        };
        // without the rib the way is straight along the channel
        assert_eq!(crossing(&keeps), -1.0);
        keeps.push(-1.0, &Area::rect(50.0, 0.0, 50.04, 40.0), 2.0);
        assert!(crossing(&keeps) >= 0.0, "{}", crossing(&keeps));
    }
}
