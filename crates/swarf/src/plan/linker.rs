//! Linking: turns passes into a program — entries, links, retracts — while keeping a model of
//! the material up to date (through [`Material`]) so that every decision is made against what
//! is really left. For each pass: a keep-down link at depth through cleared space when the tool
//! is down (a short feed move while it leaves the material, then a rapid; a short step through
//! material as a cut), else a lift to the minimum retract and an entry, the first that fits of a
//! descent into free or cleared space, a lateral landing, a helix, a ramp, a helix round a
//! centre nearby, a bore plunged before and, noted, a plunge;
//! then the pass, arc-fitted and cut into the model. The walk-through, with a figure, is in
//! `docs/linking.md`.

use super::LinkOptions;
use super::material::Material;
use super::pass::{LANDING_MARGIN, Pass, PassKind};
use crate::error::Result;
use crate::geom::arcfit::{self, Piece};
use crate::geom::{DVec2, DVec3, polyline_length};
use crate::model::{Job, Regions};
use crate::sim::SimOptions;
use crate::sim::raster::RasterSim;
use crate::sim::sweep::Path;
use crate::toolpath::{MoveKind, Toolpath};

use super::route;

/// Puts into the closed loop `pts` (its last point not repeating its first) a vertex at its
/// point nearest `p`, unless that point is within a micrometre of a vertex.
fn insert_nearest(pts: &mut Vec<DVec2>, p: DVec2) {
    let n = pts.len();
    if n < 2 {
        return;
    }
    let mut best = (f64::INFINITY, 0, pts[0]);
    for k in 0..n {
        let (a, b) = (pts[k], pts[(k + 1) % n]);
        let ab = b - a;
        let t = if ab.length_squared() > 0.0 { ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0) } else { 0.0 };
        let q = a + ab * t;
        let d = (q - p).length_squared();
        if d < best.0 {
            best = (d, k, q);
        }
    }
    let (_, k, q) = best;
    if (q - pts[k]).length() > 1e-3 && (q - pts[(k + 1) % n]).length() > 1e-3 {
        pts.insert(k + 1, q);
    }
}

/// Keeps the strategy's order, except that clean-up passes of one level are visited nearest
/// first.
pub(crate) fn order(passes: &[Pass], from: DVec2) -> Vec<Pass> {
    let mut out = Vec::with_capacity(passes.len());
    let mut cur = from;
    let mut i = 0;
    while i < passes.len() {
        let mut j = i;
        while j < passes.len() && passes[j].level == passes[i].level && passes[j].kind == passes[i].kind {
            j += 1;
        }
        if passes[i].kind != PassKind::Cleanup {
            out.extend(passes[i..j].iter().cloned());
            cur = passes[j - 1].pts.last().copied().unwrap_or(cur);
            i = j;
            continue;
        }
        let mut group: Vec<&Pass> = passes[i..j].iter().collect();
        while !group.is_empty() {
            let (k, _) = group
                .iter()
                .enumerate()
                .map(|(k, p)| {
                    let d = if p.closed {
                        p.pts.iter().map(|q| (*q - cur).length_squared()).fold(f64::INFINITY, f64::min)
                    } else {
                        (p.pts[0] - cur).length_squared()
                    };
                    (k, d)
                })
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap_or((0, 0.0));
            let p = group.remove(k);
            cur = if p.closed { cur } else { *p.pts.last().unwrap_or(&cur) };
            out.push(p.clone());
        }
        i = j;
    }
    out
}

/// Builds the program pass by pass on the material model `M` (the raster model by default).
pub(crate) struct Linker<'a, M = RasterSim> {
    pub(crate) job: &'a Job,
    pub(crate) link: &'a LinkOptions,
    /// The planning model of the material, kept up to date with every move pushed.
    pub(crate) sim: M,
    pub(crate) tp: Toolpath,
    pub(crate) safe_z: f64,
    pub(crate) r: f64,
    pub(crate) feed: f64,
    pub(crate) entry_feed: f64,
    /// Helix and ramp feed.
    pub(crate) ramp_feed: f64,
    /// The level the tool is down at, if it is.
    pub(crate) down_at: Option<f64>,
    pub(crate) step: f64,
    /// Moves pushed now were already cut into the model (adaptive passes).
    pub(crate) precut: bool,
    /// Extra radius for the clearance tests of links and lifted rapids, mm. The model cuts
    /// cells by their centres, so a cell counted as cut can still hold material up to half a
    /// cell from its centre; a strategy whose passes end anywhere in the material (adaptive)
    /// tests three quarters of a cell further (a half-cut cell holds material up to 0.71 cell
    /// from its centre).
    pub(crate) clear_margin: f64,
    /// The bores this program plunged straight down (centre and level): a later entry nearby
    /// at that level goes down one of them again, through space already cut, instead of
    /// plunging a second time.
    pub(crate) bores: Vec<(DVec2, f64)>,
    /// The largest engagement a lateral entry may cut, degrees (see [`Self::enter`]): set by a
    /// strategy that states a bound (adaptive: the reference + 20°); `None`, no limit.
    pub(crate) entry_bound: Option<f64>,
    /// Passes' cutting runs fed as paper 1 §5 feeds the adaptive strategy's own passes (see
    /// [`Self::emit_thinned`]): set by the adaptive strategy, for its clean-up.
    pub(crate) thinned_feed: bool,
    /// Where the moves go as they are planned, for a proof alongside the planning (see
    /// [`stream_next_program`]).
    stream: Option<Stream>,
}

/// How far above a floor the program cut itself an entry starts at most, mm (see
/// [`Linker::start_over`]).
pub const MACHINED_APPROACH: f64 = 0.25;

/// What a proof alongside the planning receives ([`stream_next_program`]).
#[derive(Debug)]
pub(crate) enum Streamed {
    /// The program's next moves, after `start`, as planned (not yet rounded to the post's
    /// step).
    Piece { start: DVec3, moves: Vec<crate::toolpath::Move> },
    /// The whole program as planned: the moves not sent yet are its tail, and the pieces must
    /// be its beginning.
    End(Toolpath),
}

/// What a receiver of a stream ([`stream_next_program`]) has been sent so far: the pieces'
/// moves, and where the first began. The finished program ([`Streamed::End`]) holds them as
/// its beginning, or the pieces were of another program.
#[derive(Debug, Default)]
pub(crate) struct Received {
    first: Option<DVec3>,
    sent: Vec<crate::toolpath::Move>,
}

impl Received {
    /// Notes a piece ([`Streamed::Piece`]).
    pub(crate) fn piece(&mut self, start: DVec3, moves: Vec<crate::toolpath::Move>) {
        self.first.get_or_insert(start);
        self.sent.extend(moves);
    }

    /// Moves received.
    pub(crate) fn len(&self) -> usize {
        self.sent.len()
    }

    /// The moves of the finished program `tp` after those received, and where they start, when
    /// the pieces received are its beginning.
    pub(crate) fn tail<'t>(&self, tp: &'t Toolpath) -> Option<(DVec3, &'t [crate::toolpath::Move])> {
        let n = self.sent.len();
        if self.first.is_some_and(|f| f != tp.start) || tp.moves.len() < n || tp.moves[..n] != self.sent[..] {
            return None;
        }
        Some((self.sent.last().map_or(tp.start, |m| m.to), &tp.moves[n..]))
    }
}

/// A finished program `tp` sent as a linker would, for the tests of its receivers: in pieces
/// of 300 moves from its start (all but its last 10 moves), the 8th move of the second piece
/// moved `off` mm along x, then the whole program.
#[cfg(test)]
pub(crate) fn send_in_pieces(tp: &Toolpath, off: f64) -> std::sync::mpsc::Receiver<Streamed> {
    let (tx, rx) = std::sync::mpsc::channel();
    let mut at = tp.start;
    for (k, chunk) in tp.moves[..tp.moves.len() - 10].chunks(300).enumerate() {
        let mut moves = chunk.to_vec();
        if k == 1 {
            moves[7].to.x += off;
        }
        tx.send(Streamed::Piece { start: at, moves }).expect("the receiver listens");
        at = chunk[chunk.len() - 1].to;
    }
    tx.send(Streamed::End(tp.clone())).expect("the receiver listens");
    rx
}

/// Moves a stream sends at a time.
const STREAM_PIECE: usize = 512;

/// A linker's stream: the sender, the moves sent, and whether the program's first move that
/// stays was found.
#[derive(Debug)]
struct Stream {
    tx: std::sync::mpsc::Sender<Streamed>,
    sent: usize,
    started: bool,
}

/// Is `m` part of the travel at the start height `start_z` before a program's first move
/// down ([`Linker::finish`] drops it)?
fn leading_travel(m: &crate::toolpath::Move, start_z: f64) -> bool {
    m.is_rapid() && (m.to.z - start_z).abs() < 1e-9
}

thread_local! {
    static NEXT_STREAM: std::cell::RefCell<Option<std::sync::mpsc::Sender<Streamed>>> =
        const { std::cell::RefCell::new(None) };
}

/// The next linker made on this thread sends its moves to `tx` as it plans them, in pieces
/// ([`Streamed::Piece`]); `None` takes back a sender no linker took. A job's program is made
/// by one linker (`plan::levels::drive`), so the proof can replay the program while it is
/// planned.
pub(crate) fn stream_next_program(tx: Option<std::sync::mpsc::Sender<Streamed>>) -> Unstream {
    NEXT_STREAM.with(|s| *s.borrow_mut() = tx);
    Unstream
}

/// Takes back the sender [`stream_next_program`] left that no linker took when it is dropped,
/// also when the planning panics (a receiver waits for every sender to go).
#[must_use = "the sender is taken back when this is dropped"]
pub(crate) struct Unstream;

impl Drop for Unstream {
    fn drop(&mut self) {
        NEXT_STREAM.with(|s| *s.borrow_mut() = None);
    }
}

impl<'a> Linker<'a> {
    /// A linker with a fresh planning model, the tool at the safe height above `first`.
    pub(crate) fn new(
        job: &'a Job,
        regions: &Regions,
        link: &'a LinkOptions,
        sim_opts: &SimOptions,
        first: DVec2,
    ) -> Result<Self> {
        let mut sim = RasterSim::new(job, regions, sim_opts)?;
        sim.track_exact = false;
        // the program is written with its coordinates rounded to the post's step
        sim.cut_shrink = crate::post::COORD_STEP;
        Ok(Linker::with_model(job, link, sim, first))
    }
}

impl<'a, M: Material> Linker<'a, M> {
    /// The feed boost of the links' options within the machine's highest feed (see
    /// [`crate::model::Cutting::boost_within`]; the linker's feed is the job's).
    pub(crate) fn boost(&self) -> f64 {
        self.job.cutting.boost_within(self.link.feed_boost)
    }

    /// A linker on the material model `sim`, the tool at the safe height above `first`.
    pub(crate) fn with_model(job: &'a Job, link: &'a LinkOptions, sim: M, first: DVec2) -> Self {
        let safe_z = job.top() + link.clearance;
        let tp = Toolpath::new(job.cutting.tool.clone(), DVec3::new(first.x, first.y, safe_z), safe_z);
        Linker {
            job,
            link,
            sim,
            tp,
            safe_z,
            r: job.radius(),
            feed: job.cutting.feed,
            entry_feed: job.cutting.feed * link.entry_feed_frac,
            ramp_feed: job.cutting.feed * link.ramp_feed_frac,
            down_at: None,
            step: job.stepover_mm(),
            thinned_feed: false,
            precut: false,
            clear_margin: 0.0,
            entry_bound: None,
            stream: NEXT_STREAM.with(|s| s.borrow_mut().take()).map(|tx| Stream { tx, sent: 0, started: false }),
            bores: Vec::new(),
        }
    }

    /// Plunges straight down at `c` to `z` from the approach height above `top`, noted with
    /// `why`: the last resort of an entry. The bore is kept for later entries (see
    /// [`Linker::down_a_bore`]).
    pub(crate) fn plunge(&mut self, c: DVec2, top: f64, z: f64, why: &str) {
        self.travel(c, self.start_over(top));
        self.tp.note(format!("plunge: {why}"));
        self.push_line(MoveKind::Plunge, c.extend(z), self.entry_feed);
        self.bores.push((c, z));
    }

    /// A bore this program plunged at level `z` from which the tool can go sideways to `start`
    /// (within a radius, without touching the part): the nearest such. (The plunge cut the
    /// tool's whole cylinder down to `z`, and material is only ever taken away: going down it
    /// again cuts nothing, whatever the model's cells read at its edge.)
    fn bore_to(&self, start: DVec2, z: f64) -> Option<DVec2> {
        self.bores
            .iter()
            .filter(|(c, zb)| (zb - z).abs() < 1e-9 && (start - *c).length() <= self.r)
            .map(|(c, _)| *c)
            .filter(|&c| self.keep_safe(c, start, z))
            .min_by(|a, b| (start - *a).length_squared().total_cmp(&(start - *b).length_squared()))
    }

    /// Cuts the finishing contours of each level (`finish[i] = (z, passes)`), after the roughing.
    pub(crate) fn finishing(&mut self, finish: &[(f64, Vec<Pass>)]) {
        for (i, (z, passes)) in finish.iter().enumerate() {
            self.tp.note(format!("finishing contour {} of {}: z {:.3}", i + 1, finish.len(), z));
            self.down_at = None;
            for p in order(passes, self.tp.end().truncate()) {
                self.pass(p, *z);
            }
        }
    }

    /// Retracts and hands over the program.
    pub(crate) fn finish(mut self) -> Toolpath {
        // the linker starts above a guess of where the first pass begins; the program starts
        // above where it really does (the travel at the safe height before the first move down
        // is dropped: the post's opening rapid goes there directly)
        let start_z = self.tp.start.z;
        let k = self.tp.moves.iter().take_while(|m| leading_travel(m, start_z)).count();
        if k > 0 && k < self.tp.moves.len() {
            self.tp.start = self.tp.moves[k - 1].to;
            self.tp.moves.drain(..k);
            for n in &mut self.tp.notes {
                n.at = n.at.saturating_sub(k);
            }
        }
        if log::log_enabled!(log::Level::Debug) {
            let mut by: std::collections::BTreeMap<String, (f64, usize)> = Default::default();
            let mut at = self.tp.start;
            for m in &self.tp.moves {
                let e = by.entry(format!("{:?}", m.kind)).or_default();
                e.0 += (m.to - at).length();
                e.1 += 1;
                at = m.to;
            }
            log::debug!("moves by kind (chord length mm, count): {by:?}");
        }
        let end = self.tp.end();
        self.tp.note("end: retract");
        self.tp.rapid(DVec3::new(end.x, end.y, self.safe_z));
        self.tp
    }

    pub(crate) fn push_line(&mut self, kind: MoveKind, to: DVec3, feed: f64) {
        let from = self.tp.end();
        if (to - from).length() < 1e-9 {
            return;
        }
        if kind == MoveKind::Rapid {
            self.tp.rapid(to);
        } else {
            self.tp.line(kind, to, feed);
        }
        if !self.precut
            && let Some(m) = self.tp.moves.last().copied()
        {
            self.sim.cut(&Path::of(from, &m));
        }
        self.send_moves();
    }

    pub(crate) fn push_arc(&mut self, kind: MoveKind, to: DVec3, center: DVec2, ccw: bool, feed: f64) {
        let from = self.tp.end();
        if (to - from).length() < 1e-9 {
            return;
        }
        self.tp.arc(kind, to, center, ccw, feed);
        if !self.precut
            && let Some(m) = self.tp.moves.last().copied()
        {
            self.sim.cut(&Path::of(from, &m));
        }
        self.send_moves();
    }

    /// Sends the moves pushed since the last piece to the stream, if any, once there are
    /// [`STREAM_PIECE`] of them: from the first move [`Self::finish`] keeps (it drops the
    /// travel at the start height before the first move down), the piece starting where the
    /// move before it ends.
    fn send_moves(&mut self) {
        let Some(st) = &mut self.stream else { return };
        if !st.started {
            let z0 = self.tp.start.z;
            let Some(k) = self.tp.moves.iter().position(|m| !leading_travel(m, z0)) else { return };
            (st.sent, st.started) = (k, true);
        }
        let n = self.tp.moves.len();
        if n - st.sent < STREAM_PIECE {
            return;
        }
        let start = if st.sent > 0 { self.tp.moves[st.sent - 1].to } else { self.tp.start };
        let piece = Streamed::Piece { start, moves: self.tp.moves[st.sent..n].to_vec() };
        if st.tx.send(piece).is_err() {
            // (the proof has stopped: it proves the program once it is planned)
            self.stream = None;
            return;
        }
        st.sent = n;
    }

    /// Is the tool clear of the part along the XY segment at height z?
    pub(crate) fn keep_safe(&self, a: DVec2, b: DVec2, z: f64) -> bool {
        if z >= self.job.part_top + self.job.allowance_floor + 0.01 {
            return true;
        }
        let p = Path::Line { a: a.extend(z), b: b.extend(z) };
        self.sim.keep_distance(&p, self.r) >= self.r - 1e-6
    }

    /// When the way from `a` to `b` at `z` is clear of material except within one tool
    /// diameter of `b` (arriving there is a lateral entry, not a cut through material): the
    /// point `m` that far from `b`, and how far the way to it still touches what the tool
    /// touches at `a` (see [`RasterSim::leaving_distance`]).
    pub(crate) fn clear_until_near(&self, a: DVec2, b: DVec2, z: f64) -> Option<(DVec2, f64)> {
        let len = (b - a).length();
        let keep_out = 2.0 * self.r;
        if len <= keep_out {
            return None;
        }
        let m = a + (b - a) * ((len - keep_out) / len);
        self.sim.leaving_distance(a.extend(z), m.extend(z), self.clear_margin).map(|t| (m, t))
    }

    /// Highest material within `rho` of the point (−∞ when none).
    pub(crate) fn top_near(&self, p: DVec2, rho: f64) -> f64 {
        let h = self.sim.max_height_near(&Path::Line { a: p.extend(0.0), b: p.extend(0.0) }, rho);
        h as f64
    }

    /// The minimum retract for a rapid from `a` to `b` that cannot go at `z`: the approach
    /// height above the highest material the tool passes near on the way (the model's top
    /// within the radius plus the links' margin and half a millimetre), when that is below the
    /// safe height and the way there is clear of the model and of the part. With fixtures on
    /// the table the way must also keep off them in plan (a clamp may stand above the stock).
    pub(crate) fn lowest_clear(&self, a: DVec2, b: DVec2, z: f64) -> Option<f64> {
        let line = |h: f64| Path::Line { a: a.extend(h), b: b.extend(h) };
        let top = self.sim.max_height_near(&line(z), self.r + 0.5 + self.clear_margin) as f64;
        let zl = (top + self.link.approach).max(z);
        // off the part (and, with fixtures, off the part and the fixtures in plan at any height)
        let kept = || {
            if self.job.fixtures.is_empty() {
                self.keep_safe(a, b, zl)
            } else {
                self.sim.keep_distance(&line(zl), self.r) >= self.r - 1e-6
            }
        };
        (zl < self.safe_z - 1e-9 && self.sim.is_clear(&line(zl), 0.5 + self.clear_margin) && kept()).then_some(zl)
    }

    /// What lifting over from the tool's place to `to` (down at `z`) and descending there costs,
    /// as a length of rapid: the way across, up to the minimum retract and down to the approach
    /// height by rapids, and the descent from there at the feed.
    pub(crate) fn lift_cost(&self, to: DVec2, z: f64) -> f64 {
        let a = self.tp.end().truncate();
        let up = self.lowest_clear(a, to, z).unwrap_or(self.safe_z) - z;
        let approach = self.link.approach.min(up);
        (to - a).length() + 2.0 * up - approach + approach * self.job.cutting.rapid_rate / self.feed.max(1e-9)
    }

    /// Keeps the tool down at `z` on the way to `to` (where it can stand) round the material on
    /// the straight way, through cleared space, when that costs less than lifting over (see
    /// [`route`]): rapids at depth, the first fed while the tool leaves the material it touches.
    /// False when there is no such way.
    pub(crate) fn link_around(&mut self, to: DVec2, z: f64) -> bool {
        let cur = self.tp.end();
        let a = cur.truncate();
        let h = (0.5 * self.r).max(4.0 * self.sim.grid().res);
        let reach = self.r + self.clear_margin + 0.75 * h;
        let budget = self.lift_cost(to, z);
        let margin = self.clear_margin;
        let way = route::route(
            a,
            to,
            h,
            budget,
            20_000,
            |p| self.sim.grid().cell_of(p).is_some() && self.top_near(p, reach) <= z + 0.01 && self.keep_safe(p, p, z),
            |p| self.keep_safe(a, p, z) && self.sim.leaving_distance(cur, p.extend(z), margin).is_some(),
            |p, q| self.keep_safe(p, q, z) && self.sim.is_clear(&Path::Line { a: p.extend(z), b: q.extend(z) }, margin),
        );
        let Some(way) = way else { return false };
        for (k, w) in way.into_iter().enumerate() {
            let t = if k == 0 { self.sim.leaving_distance(cur, w.extend(z), margin).unwrap_or(0.0) } else { 0.0 };
            self.link_clear(w, z, t);
        }
        true
    }

    /// Brings the tool above `target` at height at least `h` (rapids only, through clear space):
    /// at the height it is at when the way there is clear, else at the minimum retract (see
    /// [`Self::lowest_clear`]), else at the safe height.
    pub(crate) fn travel(&mut self, target: DVec2, h: f64) {
        let cur = self.tp.end();
        let h = h.min(self.safe_z);
        if (cur.truncate() - target).length() < 1e-9 {
            if cur.z < h {
                self.push_line(MoveKind::Rapid, target.extend(h), 0.0);
            }
            return;
        }
        let z = cur.z.max(h);
        if cur.z < z {
            self.push_line(MoveKind::Rapid, cur.truncate().extend(z), 0.0);
        }
        let across = Path::Line { a: cur.truncate().extend(z), b: target.extend(z) };
        let ok = z >= self.safe_z - 1e-9
            || (self.sim.is_clear(&across, 0.5 + self.clear_margin) && self.keep_safe(cur.truncate(), target, z));
        if ok {
            self.push_line(MoveKind::Rapid, target.extend(z), 0.0);
        } else if let Some(zl) = self.lowest_clear(cur.truncate(), target, z) {
            self.push_line(MoveKind::Rapid, cur.truncate().extend(zl), 0.0);
            self.push_line(MoveKind::Rapid, target.extend(zl), 0.0);
        } else {
            self.push_line(MoveKind::Rapid, cur.truncate().extend(self.safe_z), 0.0);
            self.push_line(MoveKind::Rapid, target.extend(self.safe_z), 0.0);
        }
        let now = self.tp.end();
        if now.z > h {
            self.push_line(MoveKind::Rapid, target.extend(h), 0.0);
        }
    }

    /// Moves the tool, down at `z`, to `to` along a straight way already found clear: a rapid at
    /// depth (as FreeCAD's Adaptive links, `LiftDistance` 0), or with `feed_links` a feed move
    /// at the cutting feed times the feed boost (§5: no engagement), lifted by a hair and
    /// taken as a rapid when longer than two diameters.
    /// `t`: how far along the way the tool still touches the material it touched at the start
    /// (see [`RasterSim::leaving_distance`]): that part is fed, never a rapid.
    pub(crate) fn link_clear(&mut self, to: DVec2, z: f64, t: f64) {
        if !self.link.feed_links {
            let a = self.tp.end().truncate();
            let len = (to - a).length();
            if t > 0.0 {
                let m = if len > 1e-12 { a + (to - a) * (t / len) } else { to };
                self.push_line(MoveKind::Link, m.extend(z), self.feed * self.boost());
            }
            if t < len {
                self.push_line(MoveKind::Rapid, to.extend(z), 0.0);
            }
        } else if (to - self.tp.end().truncate()).length() > 2.0 * self.job.cutting.tool.diameter {
            let lift = (z + 0.5).min(self.safe_z);
            let cur = self.tp.end();
            self.push_line(MoveKind::Rapid, cur.truncate().extend(lift), 0.0);
            self.push_line(MoveKind::Rapid, to.extend(lift), 0.0);
            self.push_line(MoveKind::Descend, to.extend(z), self.feed);
        } else {
            self.push_line(MoveKind::Link, to.extend(z), self.feed * self.boost());
        }
    }

    pub(crate) fn pass(&mut self, pass: Pass, z: f64) {
        if pass.pts.is_empty() {
            return;
        }
        let mut pts = pass.pts.clone();
        let cur = self.tp.end();
        if !pass.closed && pass.reversible && pts.len() > 1 {
            // start from the end where the tool can land, or else the nearer one
            let landing = |p: DVec2| self.top_near(p, self.r + LANDING_MARGIN) <= z + 0.01;
            let (a, b) = (pts[0], pts[pts.len() - 1]);
            let reverse = if self.down_at == Some(z) {
                (b - cur.truncate()).length() < (a - cur.truncate()).length()
            } else {
                match (landing(a), landing(b)) {
                    (false, true) => true,
                    (true, false) => false,
                    _ => (b - cur.truncate()).length() < (a - cur.truncate()).length(),
                }
            };
            if reverse {
                pts.reverse();
            }
        }
        if pass.closed {
            if self.down_at == Some(z) {
                // down already: the loop starts at its nearest point to the tool, a vertex put
                // there if it falls on an edge (a loop's vertices may lie a wall's length apart)
                insert_nearest(&mut pts, cur.truncate());
            }
            let k = self.pick_start(&pts, z, cur);
            pts.rotate_left(k);
            pts.push(pts[0]);
        }
        let start = pts[0];
        let eps = 0.01;
        let mut arrived = false;
        if self.down_at == Some(z) {
            let len = (start - cur.truncate()).length();
            if len < 1e-9 {
                arrived = true;
            } else if self.keep_safe(cur.truncate(), start, z) {
                if let Some(t) = self.sim.leaving_distance(cur, start.extend(z), self.clear_margin) {
                    self.link_clear(start, z, t);
                    arrived = true;
                } else if len <= (1.5 * self.step).max(0.5 * self.r) {
                    // a short step: a lateral entry into the pass (unless it cuts heavier than
                    // the strategy's bound: a remnant on its way; the entry below then finds
                    // another way in)
                    if self.light_entry(cur.truncate(), start, z) {
                        self.push_line(MoveKind::Cut, start.extend(z), self.feed);
                        arrived = true;
                    }
                } else if let Some((m, t)) = self.clear_until_near(cur.truncate(), start, z)
                    && self.light_entry(m, start, z)
                {
                    // a way through cleared space that only meets material on arriving: a link
                    // to a tool diameter before it, then a lateral entry
                    self.link_clear(m, z, t);
                    self.push_line(MoveKind::Cut, start.extend(z), self.feed);
                    arrived = true;
                }
            }
        }
        if !arrived {
            self.enter(start, &pts, z, eps);
        }
        self.down_at = Some(z);
        let kind = if pass.kind == PassKind::Finish { MoveKind::Finish } else { MoveKind::Cut };
        self.emit(&pts, z, kind);
    }

    /// Chooses where to start a loop: where the tool can land without entering material if
    /// anywhere, else where a helix fits best; when already down, the nearest point.
    pub(crate) fn pick_start(&self, pts: &[DVec2], z: f64, cur: DVec3) -> usize {
        let nearest = pts
            .iter()
            .enumerate()
            .min_by(|a, b| {
                (*a.1 - cur.truncate()).length_squared().total_cmp(&(*b.1 - cur.truncate()).length_squared())
            })
            .map_or(0, |(k, _)| k);
        if self.down_at == Some(z) {
            return nearest;
        }
        let n = pts.len();
        let stride = (n / 48).max(1);
        let mut best = (nearest, f64::NEG_INFINITY);
        for k in (0..n).step_by(stride).chain(std::iter::once(nearest)) {
            let p = pts[k];
            let clear = self.top_near(p, self.r + LANDING_MARGIN) <= z + 0.01;
            let kd = self.sim.keep_distance(&Path::Line { a: p.extend(z), b: p.extend(z) }, 10.0 * self.r);
            let score = if clear { 1e9 - (p - cur.truncate()).length() } else { kd };
            if score > best.1 {
                best = (k, score);
            }
        }
        best.0
    }

    /// Gets the tool down to `z` at `start`, entering material as gently as possible.
    pub(crate) fn enter(&mut self, start: DVec2, pts: &[DVec2], z: f64, eps: f64) {
        let r = self.r;
        let top = self.top_near(start, r + LANDING_MARGIN);
        if top <= z + eps {
            // free or cleared space: rapid close, feed the last bit
            self.travel(start, self.start_over(top.max(z)));
            self.push_line(MoveKind::Descend, start.extend(z), self.feed);
            return;
        }
        // a lateral entry: land in free or cleared space close by and come in sideways
        // (paper 1 §4.5: entering tangent to the stock from free space before any plunge)
        // — unless the way in cuts heavier than the strategy's bound (a remnant the start
        // stands deep in): a helix or a ramp then enters it, as an entry bore
        if let Some(p) = self.lateral_landing(start, z, 1.5 * r)
            && self.light_entry(p, start, z)
        {
            self.land_and_approach(p, start, z);
            return;
        }
        // helix around the start
        let rh = self.helix_room(start);
        if rh >= self.link.helix_min_frac * r {
            let top_h = self.top_near(start, r + rh + 0.05).max(z);
            self.helix(start, rh, self.start_over(top_h), z, pts);
            return;
        }
        // ramp along the start of the pass
        let total = polyline_length(pts);
        let want = (3.0 * self.job.cutting.tool.diameter).min(total);
        if want >= (0.5 * self.job.cutting.tool.diameter).max(1.0) {
            let prefix = prefix_of(pts, want);
            let mut top_r = z;
            for w in prefix.windows(2) {
                top_r = top_r
                    .max(self.sim.max_height_near(&Path::Line { a: w[0].extend(0.0), b: w[1].extend(0.0) }, r + 0.05)
                        as f64);
            }
            self.ramp(&prefix, self.start_over(top_r), z);
            return;
        }
        // a helix round a centre nearby that ends by the start (a pass that starts on the wall
        // of a bore just wider than the tool: the bore's centre has the room)
        if let Some((c, rh)) = self.helix_near(start, pts) {
            let top_h = self.top_near(c, r + rh + 0.05).max(z);
            let on = start - c;
            // (started so that it ends on the way from the centre to the start)
            let turn = self.helix_turn(rh, self.start_over(top_h), z);
            let a0 = on.y.atan2(on.x) - if self.link.climb { turn } else { -turn };
            self.helix_down(c, rh, self.start_over(top_h), z, a0);
            self.push_line(MoveKind::Cut, start.extend(z), self.feed);
            return;
        }
        // down a bore this program already plunged at this level, then sideways (a clean-up
        // contour round a bore barely wider than the tool, after the pass that plunged it)
        if let Some(c) = self.bore_to(start, z) {
            self.travel(c, self.start_over(self.top_near(c, r + LANDING_MARGIN).max(z)));
            self.tp.note("entry down a bore plunged before");
            self.push_line(MoveKind::Descend, c.extend(z), self.feed);
            self.push_line(MoveKind::Cut, start.extend(z), self.feed);
            return;
        }
        // a longer way in sideways before a plunge
        if let Some(p) = self.lateral_landing(start, z, 4.0 * r) {
            self.land_and_approach(p, start, z);
            return;
        }
        // nothing fits: plunge
        self.plunge(start, top, z, "no room for a helix or a ramp");
    }

    /// Does a straight lateral entry from `a` to `b` at `z` cut within the entry bound (see
    /// [`Self::entry_bound`])?
    fn light_entry(&self, a: DVec2, b: DVec2, z: f64) -> bool {
        self.entry_bound.is_none_or(|bound| self.cuts_within(a, b, z, bound))
    }

    /// Does the straight cut from `a` to `b` at `z` engage at most `bound` degrees, read by the
    /// front half against the stock as it is (which over-reads every point after the first) at
    /// points a cell apart, the end included?
    pub(crate) fn cuts_within(&self, a: DVec2, b: DVec2, z: f64, bound: f64) -> bool {
        let len = (b - a).length();
        if len < 1e-9 {
            return true;
        }
        let dir = (b - a) / len;
        let n = (len / self.sim.grid().res).ceil().max(1.0) as usize;
        (1..=n).all(|k| self.sim.front_engagement(a + dir * (len * k as f64 / n as f64), z, dir) <= bound)
    }

    /// The largest helix radius round `c` that keeps the tool off the part (the arc tolerance
    /// and 5 µm to spare), at most the one the options want (negative where the tool itself
    /// does not fit).
    fn helix_room(&self, c: DVec2) -> f64 {
        let kd = self.sim.keep_distance(&Path::Line { a: c.extend(0.0), b: c.extend(0.0) }, 10.0 * self.r);
        (self.link.helix_radius_frac * self.r).min(kd - self.r - self.link.arc_tol - 0.005)
    }

    /// A helix near `start` for a start with no room for one itself (a pass that starts on the
    /// wall of a bore just wider than the tool): a centre with room for a helix of at least the
    /// smallest radius, whose circle holds `start` or passes within a tenth of that radius
    /// outside it; the centre and the radius, the largest radius (up to the one the options
    /// want) among the centroid of the pass `pts` and centres round `start` at 24 headings and
    /// 8 distances.
    fn helix_near(&self, start: DVec2, pts: &[DVec2]) -> Option<(DVec2, f64)> {
        let r = self.r;
        let (lo, hi) = (self.link.helix_min_frac * r, self.link.helix_radius_frac * r);
        let centroid = pts.iter().fold(DVec2::ZERO, |a, p| a + *p) / pts.len().max(1) as f64;
        let around = (1..=8).flat_map(|k| {
            (0..24).map(move |j| {
                let a = j as f64 * std::f64::consts::TAU / 24.0;
                start + hi * k as f64 / 8.0 * DVec2::new(a.cos(), a.sin())
            })
        });
        let mut best: Option<(DVec2, f64)> = None;
        for c in std::iter::once(centroid).chain(around) {
            let rh = self.helix_room(c);
            let off = (start - c).length();
            if rh >= lo && off <= rh + 0.1 * lo && best.is_none_or(|b| rh > b.1 + 1e-9) {
                best = Some((c, rh));
            }
        }
        best
    }

    /// The nearest point within `max` of `start` where the tool can land at `z` (no material
    /// within its radius) and from which a straight move to `start` does not touch the part.
    pub(crate) fn lateral_landing(&self, start: DVec2, z: f64, max: f64) -> Option<DVec2> {
        let r = self.r;
        let mut best: Option<(f64, DVec2)> = None;
        for ring in 1..=8 {
            let d = max * ring as f64 / 8.0;
            for k in 0..24 {
                let a = std::f64::consts::TAU * k as f64 / 24.0;
                let p = start + d * DVec2::new(a.cos(), a.sin());
                if self.top_near(p, r + LANDING_MARGIN) > z + 0.01 {
                    continue;
                }
                if self.keep_safe(p, start, z) && best.is_none_or(|b| d < b.0) {
                    best = Some((d, p));
                }
            }
            if best.is_some() {
                break;
            }
        }
        best.map(|b| b.1)
    }

    /// The height an entry or a descent onto material whose top is `top` starts from: the
    /// approach above it, where the top may be the stock's own (whose height is the user's
    /// word), and at most [`MACHINED_APPROACH`] above it where it lies under the stock's top: a
    /// floor this program cut at a level above, or free space (a helix or ramp 1 mm over a
    /// floor cut 1 mm higher ran half its length in the air).
    pub(crate) fn start_over(&self, top: f64) -> f64 {
        let a = if top < self.job.stock_top - 1e-6 {
            self.link.approach.min(MACHINED_APPROACH)
        } else {
            self.link.approach
        };
        top + a
    }

    /// Lands at `p` and cuts sideways to `start`.
    pub(crate) fn land_and_approach(&mut self, p: DVec2, start: DVec2, z: f64) {
        let top = self.top_near(p, self.r + LANDING_MARGIN);
        self.travel(p, self.start_over(top.max(z)));
        self.push_line(MoveKind::Descend, p.extend(z), self.feed);
        self.tp.note("lateral entry");
        self.push_line(MoveKind::Cut, start.extend(z), self.feed);
    }

    pub(crate) fn helix(&mut self, c: DVec2, rh: f64, z_from: f64, z: f64, pts: &[DVec2]) {
        // start on the circle opposite the pass direction, so the last turn ends facing it
        let dir = if pts.len() > 1 { (pts[1] - pts[0]).normalize_or_zero() } else { DVec2::X };
        let a0 = if dir.length_squared() > 0.0 { dir.y.atan2(dir.x) + std::f64::consts::PI } else { 0.0 };
        self.helix_down(c, rh, z_from, z, a0);
        self.push_line(MoveKind::Cut, c.extend(z), self.feed);
    }

    /// A helix of radius `rh` around `c` from `z_from` down to `z`, starting at angle `a0`, then
    /// one full turn at depth that cleans the bottom; returns the angle it ends at (on the
    /// circle). Counter-clockwise for climb milling (the material outside the circle is then on
    /// the tool's right).
    pub(crate) fn helix_down(&mut self, c: DVec2, rh: f64, z_from: f64, z: f64, a0: f64) -> f64 {
        let ccw = self.link.climb;
        let on = |a: f64| c + rh * DVec2::new(a.cos(), a.sin());
        self.travel(c, z_from);
        self.tp.note(format!("helix entry r {:.3} at X{:.3} Y{:.3}", rh, c.x, c.y));
        self.push_line(MoveKind::Rapid, on(a0).extend(z_from), 0.0);
        let total = self.helix_turn(rh, z_from, z);
        let n = (total / std::f64::consts::PI).ceil().max(1.0) as usize;
        let s = if ccw { 1.0 } else { -1.0 };
        for k in 1..=n {
            let t = k as f64 / n as f64;
            let a = a0 + s * total * t;
            // exactly `z` at the bottom: a last bit of rounding would print the turn at depth
            // as a rise of 1 µm and count it outside the bore
            let zk = if k == n { z } else { z_from + (z - z_from) * t };
            self.push_arc(MoveKind::Entry, on(a).extend(zk), c, ccw, self.ramp_feed);
        }
        let a_end = a0 + s * total;
        self.push_arc(MoveKind::Cut, on(a_end + s * std::f64::consts::PI).extend(z), c, ccw, self.feed);
        self.push_arc(MoveKind::Cut, on(a_end).extend(z), c, ccw, self.feed);
        a_end
    }

    /// The angle a helix of radius `rh` turns through from `z_from` down to `z` at the ramp
    /// angle, radians.
    fn helix_turn(&self, rh: f64, z_from: f64, z: f64) -> f64 {
        let pitch = std::f64::consts::TAU * rh * self.link.ramp_angle_deg.to_radians().tan();
        std::f64::consts::TAU * ((z_from - z) / pitch.max(1e-6))
    }

    pub(crate) fn ramp(&mut self, prefix: &[DVec2], z_from: f64, z: f64) {
        let len = polyline_length(prefix);
        let drop_per_len = self.link.ramp_angle_deg.to_radians().tan();
        self.travel(prefix[0], z_from);
        self.tp.note(format!("ramp entry along {:.3} mm", len));
        let mut zc = z_from;
        let mut forward = true;
        let mut guard = 0;
        while zc > z + 1e-9 && guard < 10_000 {
            guard += 1;
            let seq: Vec<DVec2> = if forward { prefix.to_vec() } else { prefix.iter().rev().copied().collect() };
            let mut prev = seq[0];
            for q in &seq[1..] {
                let d = (*q - prev).length();
                zc = (zc - d * drop_per_len).max(z);
                self.push_line(MoveKind::Entry, q.extend(zc), self.ramp_feed);
                prev = *q;
            }
            forward = !forward;
        }
        // clean the wedge at full depth and come back to the start
        if !forward {
            // ended at the far end: back to the start
            for q in prefix.iter().rev().skip(1) {
                self.push_line(MoveKind::Cut, q.extend(z), self.feed);
            }
        } else {
            for q in prefix.iter().skip(1) {
                self.push_line(MoveKind::Cut, q.extend(z), self.feed);
            }
            for q in prefix.iter().rev().skip(1) {
                self.push_line(MoveKind::Cut, q.extend(z), self.feed);
            }
        }
    }

    /// Appends a pass at `z`: stretches where the tool would only cut air become rapids lifted
    /// clear of the floor (when long enough to be worth it and the straight way is clear); the
    /// rest is arc-fitted into lines and arcs.
    pub(crate) fn emit(&mut self, pts: &[DVec2], z: f64, kind: MoveKind) {
        let cur = self.tp.end().truncate();
        let mut poly = Vec::with_capacity(pts.len() + 1);
        poly.push(cur);
        if (pts[0] - cur).length() > 1e-9 {
            poly.push(pts[0]);
        }
        poly.extend_from_slice(&pts[1..]);
        // split into pieces at most R long and classify them
        let piece = self.r.max(0.5);
        let mut fine: Vec<(DVec2, bool)> = vec![(poly[0], false)];
        for w in poly.windows(2) {
            let n = ((w[1] - w[0]).length() / piece).ceil().max(1.0) as usize;
            let mut prev = w[0];
            for k in 1..=n {
                let q = w[0] + (w[1] - w[0]) * (k as f64 / n as f64);
                let clear = self.sim.is_clear(&Path::Line { a: prev.extend(z), b: q.extend(z) }, -0.005);
                fine.push((q, clear));
                prev = q;
            }
        }
        // runs of equal classification; a point belongs to the run of the segment ending at it
        let min_air = 2.0 * self.job.cutting.tool.diameter;
        let mut i = 0;
        while i + 1 < fine.len() {
            let air = fine[i + 1].1;
            let mut j = i + 1;
            while j + 1 < fine.len() && fine[j + 1].1 == air {
                j += 1;
            }
            let run: Vec<DVec2> = fine[i..=j].iter().map(|p| p.0).collect();
            if air && polyline_length(&run) >= min_air && self.lift_across(run[0], run[run.len() - 1], z) {
                // done by lift_across
            } else if self.thinned_feed && !air && kind == MoveKind::Cut {
                self.emit_thinned(&run, z, kind);
            } else {
                self.fit_emit(&run, z, if air { MoveKind::Link } else { kind });
            }
            i = j;
        }
    }

    /// [`Self::fit_emit`] at the feed of paper 1 §5 (see
    /// [`super::feed::feed_runs_by_engagement`]): higher where the
    /// engagement is low, up to the boost. The engagement is measured ahead of the tool every
    /// quarter of a radius along `run` (which starts where the tool is), on the material as it
    /// stands before the run is cut. (A clean-up contour along a wall mostly shaves slivers a
    /// few hundredths of a millimetre thin, at a few degrees.)
    pub(crate) fn emit_thinned(&mut self, run: &[DVec2], z: f64, kind: MoveKind) {
        let h = (0.25 * self.r).max(1e-3);
        let mut pts = vec![run[0]];
        let mut theta = vec![0.0];
        for w in run.windows(2) {
            let d = w[1] - w[0];
            let len = d.length();
            if len < 1e-9 {
                continue;
            }
            let n = (len / h).ceil().max(1.0) as usize;
            for k in 1..=n {
                let q = w[0] + d * (k as f64 / n as f64);
                pts.push(q);
                theta.push(self.sim.front_engagement(q, z, d / len).to_radians());
            }
        }
        let runs = super::feed::feed_runs_by_engagement(&pts, &theta, self.job.cutting.tool.diameter, self.boost());
        for (sub, m) in runs {
            // (the samples between the run's own vertices dropped again)
            let sub = crate::geom::simplify::douglas_peucker(&sub, 1e-6);
            self.fit_emit_feed(&sub, z, kind, self.feed * m);
        }
    }

    /// Rapid from `a` to `b` lifted by half a millimetre, when the straight way is clear.
    pub(crate) fn lift_across(&mut self, a: DVec2, b: DVec2, z: f64) -> bool {
        let lift = (z + 0.5).min(self.safe_z);
        let across = Path::Line { a: a.extend(lift), b: b.extend(lift) };
        if !(self.sim.is_clear(&across, self.clear_margin) && self.keep_safe(a, b, lift)) {
            return false;
        }
        self.push_line(MoveKind::Rapid, a.extend(lift), 0.0);
        self.push_line(MoveKind::Rapid, b.extend(lift), 0.0);
        self.push_line(MoveKind::Rapid, b.extend(z), 0.0);
        true
    }

    /// Arc-fits the polyline (which starts where the tool is) and appends it at `z`.
    pub(crate) fn fit_emit(&mut self, poly: &[DVec2], z: f64, kind: MoveKind) {
        self.fit_emit_feed(poly, z, kind, self.feed);
    }

    /// [`Self::fit_emit`] at the given feed.
    pub(crate) fn fit_emit_feed(&mut self, poly: &[DVec2], z: f64, kind: MoveKind, feed: f64) {
        for piece in arcfit::fit(poly, self.link.arc_tol) {
            match piece {
                Piece::Line { to } => self.push_line(kind, to.extend(z), feed),
                Piece::Arc { to, center, ccw } => {
                    // split arcs over a half turn so that every move is unambiguous
                    let from = self.tp.end().truncate();
                    let g = crate::toolpath::ArcGeom::new(from.extend(z), to.extend(z), center, ccw);
                    if g.sweep.abs() > std::f64::consts::PI {
                        let mid = g.at(0.5).truncate();
                        self.push_arc(kind, mid.extend(z), center, ccw, feed);
                    }
                    self.push_arc(kind, to.extend(z), center, ccw, feed);
                }
            }
        }
    }
}

/// The first `len` mm of a polyline.
fn prefix_of(pts: &[DVec2], len: f64) -> Vec<DVec2> {
    let mut out = vec![pts[0]];
    let mut acc = 0.0;
    for w in pts.windows(2) {
        let d = (w[1] - w[0]).length();
        if acc + d >= len {
            let t = if d > 0.0 { (len - acc) / d } else { 0.0 };
            out.push(w[0] + (w[1] - w[0]) * t);
            return out;
        }
        acc += d;
        out.push(w[1]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::Area;
    use crate::toolpath::{Motion, Move};

    /// A `w`×`h` mm pocket 2 mm deep, its walls a frame of part round the stock, a Ø4 mm tool,
    /// planned on 0.05 mm cells.
    struct Pocket {
        job: Job,
        regions: Regions,
        link: LinkOptions,
        sim: SimOptions,
    }

    impl Pocket {
        fn new(w: f64, h: f64) -> Pocket {
            let part = Area::rect(-5.0, -5.0, w + 5.0, h + 5.0).difference(&Area::rect(0.0, 0.0, w, h));
            let job = Job::new("pocket", Area::rect(0.0, 0.0, w, h), part, 4.0, 2.0);
            let link = LinkOptions::DEFAULT;
            let regions = job.regions(job.radius(), link.arc_tol + 0.001).expect("the pocket's regions");
            Pocket { job, regions, link, sim: SimOptions { res: Some(0.05), ..SimOptions::DEFAULT } }
        }

        /// The level (the floor).
        fn z(&self) -> f64 {
            self.job.levels()[0]
        }

        /// A linker on a fresh model of the pocket, the tool up above `first`.
        fn linker(&self, first: DVec2) -> Linker<'_> {
            Linker::new(&self.job, &self.regions, &self.link, &self.sim, first).expect("the pocket's model")
        }
    }

    /// Clears the model at `z` along the horizontal line at `y` from `x0` to `x1` (everything
    /// within the tool radius of it).
    fn clear_row(l: &mut Linker, z: f64, y: f64, x0: f64, x1: f64) {
        l.sim.cut(&Path::Line { a: DVec2::new(x0, y).extend(z), b: DVec2::new(x1, y).extend(z) });
    }

    /// Puts the tool down at `p` at `z` (in space already cut) without cutting the model.
    fn stand_at(l: &mut Linker, p: DVec2, z: f64) {
        l.precut = true;
        l.push_line(MoveKind::Rapid, p.extend(l.safe_z), 0.0);
        l.push_line(MoveKind::Descend, p.extend(z), l.feed);
        l.precut = false;
        l.down_at = Some(z);
    }

    fn count(moves: &[Move], kind: MoveKind) -> usize {
        moves.iter().filter(|m| m.kind == kind).count()
    }

    fn noted(l: &Linker, start: &str) -> bool {
        l.tp.notes.iter().any(|n| n.text.starts_with(start))
    }

    /// The pocket full of stock, the start in its middle, 5 mm from the walls: no landing
    /// beside the material within reach, room for a helix of 0.75 R. The tool goes down by a
    /// helix round the start (arcs at the ramp feed, ending at depth), one turn at depth, and is
    /// at the start.
    #[test]
    fn the_entry_is_a_helix_where_one_fits() {
        let p = Pocket::new(20.0, 10.0);
        let z = p.z();
        let start = DVec2::new(10.0, 5.0);
        let mut l = p.linker(start);
        l.enter(start, &[start, DVec2::new(15.0, 5.0)], z, 0.01);
        let entry: Vec<&Move> = l.tp.moves.iter().filter(|m| m.kind == MoveKind::Entry).collect();
        assert!(!entry.is_empty() && noted(&l, "helix entry r 1.500"), "{:?}", l.tp.notes);
        for m in &entry {
            assert!(matches!(m.motion, Motion::Arc { center, .. } if (center - start).length() < 1e-9), "{m:?}");
            assert!(((m.to.truncate() - start).length() - 1.5).abs() < 1e-9 && m.feed == l.ramp_feed, "{m:?}");
        }
        assert_eq!(entry.last().map(|m| m.to.z), Some(z));
        assert_eq!(l.tp.end(), start.extend(z));
        assert_eq!(count(&l.tp.moves, MoveKind::Plunge) + count(&l.tp.moves, MoveKind::Descend), 0);
    }

    /// A helix over the stock's own top starts the approach above it; over a floor the program
    /// cut 1 mm under the top, at most `MACHINED_APPROACH` above that floor (the approach would
    /// spend most of a 1 mm descent in the air).
    #[test]
    fn an_entry_over_a_floor_cut_before_starts_just_above_it() {
        let p = Pocket::new(20.0, 10.0);
        let z = p.z();
        let start = DVec2::new(10.0, 5.0);
        let pts = [start, DVec2::new(15.0, 5.0)];
        let entry_top = |l: &Linker| {
            let k = l.tp.moves.iter().position(|m| m.kind == MoveKind::Entry).expect("a helix");
            assert!(k > 0 && l.tp.moves[k - 1].is_rapid(), "{:?}", &l.tp.moves[..=k]);
            l.tp.moves[k - 1].to.z
        };
        let mut raw = p.linker(start);
        raw.enter(start, &pts, z, 0.01);
        assert!((entry_top(&raw) - (p.job.stock_top + p.link.approach)).abs() < 1e-9);
        let mut cut = p.linker(start);
        let floor = p.job.stock_top - 1.0;
        for k in 0..=12 {
            clear_row(&mut cut, floor, 1.0 + 0.7 * k as f64, 1.0, 19.0);
        }
        assert!(cut.top_near(start, 6.0) <= floor as f32 as f64 + 1e-6, "the floor is cut round the start");
        cut.enter(start, &pts, z, 0.01);
        assert!(noted(&cut, "helix entry"), "{:?}", cut.tp.notes);
        assert!((entry_top(&cut) - (floor + MACHINED_APPROACH)).abs() < 1e-6, "{}", entry_top(&cut));
        assert!(entry_top(&cut) < floor + p.link.approach - 0.5, "not the whole approach over the cut floor");
    }

    /// A slot 4.3 mm wide for the Ø4 mm tool: 0.15 mm on either side, less than the smallest
    /// helix (0.1 R) needs. The tool ramps down along the start of the pass (straight lines
    /// back and forth along it at the ramp angle), then is at the start at depth.
    #[test]
    fn the_entry_is_a_ramp_where_no_helix_fits() {
        let p = Pocket::new(30.0, 4.3);
        let z = p.z();
        let start = DVec2::new(10.0, 2.15);
        let mut l = p.linker(start);
        let pass = [start, DVec2::new(25.0, 2.15)];
        l.enter(start, &pass, z, 0.01);
        let entry: Vec<&Move> = l.tp.moves.iter().filter(|m| m.kind == MoveKind::Entry).collect();
        assert!(entry.len() >= 2 && noted(&l, "ramp entry along 12.000 mm"), "{:?}", l.tp.notes);
        let mut prev_z = f64::INFINITY;
        for m in &entry {
            assert!(matches!(m.motion, Motion::Line) && m.feed == l.ramp_feed, "{m:?}");
            // along the pass, never deeper than the level, always down or level
            assert!((m.to.y - 2.15).abs() < 1e-9 && (10.0..=22.0 + 1e-9).contains(&m.to.x), "{m:?}");
            assert!(m.to.z <= prev_z + 1e-12 && m.to.z >= z, "{m:?}");
            prev_z = m.to.z;
        }
        assert_eq!(prev_z, z);
        assert_eq!(l.tp.end(), start.extend(z));
        assert!(!noted(&l, "helix") && count(&l.tp.moves, MoveKind::Plunge) == 0);
    }

    /// The pocket with a hole already cleared 0.2 mm from the start, and the adaptive
    /// strategy's bound on entries: the tool lands in the hole (descending at the feed through
    /// cleared space) and comes in sideways, although a helix would fit at the start; where the
    /// start stands 2.5 mm from the hole, the way in sideways would cut a slot (180°, over the
    /// reference + 20°) and a helix enters instead; and where the start itself is in cleared
    /// space, it just descends there.
    #[test]
    fn a_lateral_landing_from_cleared_space_comes_before_a_helix() {
        let p = Pocket::new(20.0, 10.0);
        let z = p.z();
        let fresh = |start: DVec2| {
            let mut l = p.linker(start);
            // (the adaptive strategy's: the reference + 20°)
            l.entry_bound = Some(p.job.cutting.width.engagement_deg() + crate::report::BOUND_OVER_REF_DEG);
            for y in [4.5, 5.5] {
                clear_row(&mut l, z, y, 2.0, 6.0);
            }
            l
        };
        let deep = DVec2::new(8.5, 5.0);
        let mut l = fresh(deep);
        l.enter(deep, &[deep, DVec2::new(15.0, 5.0)], z, 0.01);
        assert!(!noted(&l, "lateral entry") && noted(&l, "helix"), "{:?}", l.tp.notes);
        assert_eq!(l.tp.end(), deep.extend(z));
        let start = DVec2::new(6.2, 5.0);
        let mut l = fresh(start);
        assert!(l.top_near(start, l.r + LANDING_MARGIN) > z + 0.01, "material within the tool's reach at the start");
        l.enter(start, &[start, DVec2::new(15.0, 5.0)], z, 0.01);
        assert!(noted(&l, "lateral entry") && !noted(&l, "helix"), "{:?}", l.tp.notes);
        assert_eq!(count(&l.tp.moves, MoveKind::Entry) + count(&l.tp.moves, MoveKind::Plunge), 0);
        let n = l.tp.moves.len();
        let (land, side) = (l.tp.moves[n - 2], l.tp.moves[n - 1]);
        assert!(land.kind == MoveKind::Descend && land.to.z == z && land.feed == l.feed, "{land:?}");
        let d = (land.to.truncate() - start).length();
        assert!(d > 0.0 && d <= 1.5 * l.r + 1e-9, "landed {d} mm away");
        assert!(l.top_near(land.to.truncate(), l.r + LANDING_MARGIN) <= z + 0.01);
        assert!(side.kind == MoveKind::Cut && side.to == start.extend(z), "{side:?}");
        // from cleared space: straight down
        let at = DVec2::new(4.0, 5.0);
        let before = l.tp.moves.len();
        l.down_at = None;
        l.enter(at, &[at, DVec2::new(4.0, 6.0)], z, 0.01);
        let down = &l.tp.moves[before..];
        assert!(down.iter().all(|m| m.is_rapid() || m.kind == MoveKind::Descend), "{down:?}");
        assert_eq!(down.last().map(|m| (m.kind, m.to)), Some((MoveKind::Descend, at.extend(z))));
    }

    /// The tool down in a hole cleared in the pocket's stock, the next pass starting 0.9 mm on
    /// into the stock beyond the hole's end: a short step, which the linker takes straight at
    /// depth into the pass. Across the hole's round end that cuts a slot (180°): with the
    /// adaptive strategy's bound on entries, the tool enters by a helix instead, and the
    /// straight step stays for strategies without that bound.
    #[test]
    fn a_short_step_at_depth_into_a_pass_holds_the_entry_bound() {
        let p = Pocket::new(20.0, 10.0);
        let z = p.z();
        let (here, start) = (DVec2::new(6.0, 5.0), DVec2::new(6.9, 5.0));
        for bound in [true, false] {
            let mut l = p.linker(here);
            if bound {
                l.entry_bound = Some(p.job.cutting.width.engagement_deg() + crate::report::BOUND_OVER_REF_DEG);
            }
            for y in [4.5, 5.5] {
                clear_row(&mut l, z, y, 2.0, 6.0);
            }
            stand_at(&mut l, here, z);
            assert!(!l.cuts_within(here, start, z, 100.0), "the step cuts lightly");
            let n = l.tp.moves.len();
            let pass = Pass {
                pts: vec![start, DVec2::new(15.0, 5.0)],
                closed: false,
                kind: PassKind::Clear,
                level: 0.0,
                reversible: false,
            };
            l.pass(pass, z);
            let straight = l.tp.moves[n].kind == MoveKind::Cut && l.tp.moves[n].to == start.extend(z);
            assert_eq!(straight, !bound, "bound {bound}: {:?}", &l.tp.moves[n..]);
            assert_eq!(noted(&l, "helix"), bound, "bound {bound}: {:?}", l.tp.notes);
            assert_eq!(count(&l.tp.moves, MoveKind::Plunge), 0);
        }
    }

    /// The tool down on a closed clean-up loop, midway along an edge 16 mm long, with stock
    /// left along the walls: the loop starts where the tool stands, and the pass is the loop
    /// alone, cut all round once (not a link at depth or a retract to a vertex 8 mm away
    /// first).
    #[test]
    fn a_loop_reached_down_on_it_starts_where_the_tool_stands() {
        let p = Pocket::new(20.0, 10.0);
        let z = p.z();
        let here = DVec2::new(10.0, 2.0);
        let mut l = p.linker(here);
        clear_row(&mut l, z, 2.0, 6.0, 14.0);
        stand_at(&mut l, here, z);
        let n = l.tp.moves.len();
        let corners = vec![DVec2::new(2.0, 2.0), DVec2::new(18.0, 2.0), DVec2::new(18.0, 8.0), DVec2::new(2.0, 8.0)];
        let pass = Pass { pts: corners, closed: true, kind: PassKind::Cleanup, level: 0.0, reversible: true };
        l.pass(pass, z);
        let moves = &l.tp.moves[n..];
        // (cut, and linked through the cleared stretch of the row)
        assert!(moves.iter().all(|m| matches!(m.kind, MoveKind::Cut | MoveKind::Link) && m.to.z == z), "{moves:?}");
        let mut at = here.extend(z);
        let mut length = 0.0;
        for m in moves {
            length += (m.to - at).length();
            at = m.to;
        }
        assert!((length - 44.0).abs() < 1e-9, "{length} mm: {moves:?}");
        assert_eq!(at, here.extend(z));
    }

    /// A slot cleared along the pocket's middle (y = 5) and a run 0.2 mm off its centre line:
    /// it shaves a strip 0.2 mm thin, at about 26°, where chip thinning allows 2.3 times the
    /// feed. With the thinned feed (the adaptive strategy's clean-up) the run goes faster than
    /// the programmed feed by chip thinning's measure, along the same path; without it, at the
    /// programmed feed.
    #[test]
    fn a_thin_cut_is_fed_faster_when_its_feed_is_thinned() {
        let p = Pocket::new(20.0, 10.0);
        let z = p.z();
        let (a, b) = (DVec2::new(4.0, 5.2), DVec2::new(16.0, 5.2));
        let run = |thinned: bool| {
            let mut l = p.linker(a);
            clear_row(&mut l, z, 5.0, 2.0, 18.0);
            stand_at(&mut l, a, z);
            l.thinned_feed = thinned;
            let n = l.tp.moves.len();
            l.emit(&[a, b], z, MoveKind::Cut);
            let boost = l.boost();
            let moves = l.tp.moves[n..].to_vec();
            (moves, l.feed, boost)
        };
        let (plain, feed, boost) = run(false);
        let (thin, _, _) = run(true);
        assert!(boost > 2.0, "the boost {boost}");
        assert!(plain.iter().all(|m| m.kind == MoveKind::Cut && m.feed == feed), "{plain:?}");
        assert!(thin.iter().all(|m| m.kind == MoveKind::Cut && m.feed <= feed * boost + 1e-9), "{thin:?}");
        let length = |ms: &[Move]| {
            let mut at = a.extend(z);
            ms.iter().fold(0.0, |acc, m| {
                let d = (m.to - at).length();
                at = m.to;
                acc + d
            })
        };
        assert!((length(&thin) - 12.0).abs() < 1e-9 && (length(&plain) - 12.0).abs() < 1e-9);
        assert_eq!(thin.last().map(|m| m.to), Some(b.extend(z)));
        // (the feed comes down a diameter before the run's end, where the strip meets the
        // uncut stock beyond the slot's round end)
        // 1 / sin θ at θ = acos(1 − 0.2 / R) is 2.29; the engagement is read off the cells of
        // the ring, the multiplier rounded down to a twentieth
        assert!(thin.iter().all(|m| m.feed >= 2.0 * feed && m.feed <= 2.35 * feed), "{thin:?}");
    }

    /// A point beside an edge of a square, beside its closing edge, and near a corner.
    #[test]
    fn the_nearest_point_of_a_loop_becomes_a_vertex_unless_it_is_one() {
        let square = vec![DVec2::ZERO, DVec2::new(4.0, 0.0), DVec2::new(4.0, 4.0), DVec2::new(0.0, 4.0)];
        let mut pts = square.clone();
        insert_nearest(&mut pts, DVec2::new(1.0, -3.0));
        assert_eq!(pts[1], DVec2::new(1.0, 0.0));
        assert_eq!(pts.len(), 5);
        // on the closing edge, from the last vertex back to the first
        let mut pts = square.clone();
        insert_nearest(&mut pts, DVec2::new(-1.0, 2.5));
        assert_eq!(pts[4], DVec2::new(0.0, 2.5));
        // at a vertex (within a micrometre): unchanged
        let mut pts = square.clone();
        insert_nearest(&mut pts, DVec2::new(4.0 + 1e-4, 4.0 + 2.0));
        assert_eq!(pts, square);
    }

    /// A linker made after [`stream_next_program`] sends its moves in pieces of
    /// [`STREAM_PIECE`] as it pushes them, from the first move its program keeps (the travel at
    /// the start height before it is dropped by `finish`), each piece from where the move
    /// before it ends: the pieces are the finished program's beginning.
    #[test]
    fn a_streaming_linker_sends_the_programs_beginning_in_pieces() {
        let p = Pocket::new(20.0, 10.0);
        let z = p.z();
        let (tx, rx) = std::sync::mpsc::channel();
        let _unstream = stream_next_program(Some(tx));
        let mut l = p.linker(DVec2::new(2.0, 2.0));
        let quiet = p.linker(DVec2::new(2.0, 2.0));
        l.precut = true;
        l.push_line(MoveKind::Rapid, DVec3::new(5.0, 5.0, l.safe_z), 0.0);
        l.push_line(MoveKind::Descend, DVec3::new(5.0, 5.0, z), l.feed);
        for k in 0..1200 {
            let y = 5.0 + 0.001 * (k + 1) as f64;
            l.push_line(MoveKind::Cut, DVec3::new(if k % 2 == 0 { 6.0 } else { 5.0 }, y, z), l.feed);
        }
        assert!(quiet.stream.is_none(), "only the first linker streams");
        let tp = l.finish();
        let pieces: Vec<Streamed> = rx.try_iter().collect();
        assert_eq!(pieces.len(), 2, "{} pieces", pieces.len());
        let mut at = 0;
        for piece in pieces {
            let Streamed::Piece { start, moves } = piece else { panic!("a piece") };
            let before = if at == 0 { tp.start } else { tp.moves[at - 1].to };
            assert_eq!(start, before);
            assert!(moves.len() >= STREAM_PIECE && tp.moves[at..at + moves.len()] == moves[..]);
            at += moves.len();
        }
        assert_eq!(tp.moves[0].kind, MoveKind::Descend, "the travel at the start height dropped");
    }

    /// A square bore 0.8 mm wider than the tool and a pass that starts 0.35 mm off its centre:
    /// no room for a helix at the start, but round a centre nearby whose circle holds the start:
    /// the tool goes down on that circle and ends where the pass starts, without a plunge.
    #[test]
    fn a_helix_off_the_start_when_the_start_has_no_room() {
        let p = Pocket::new(4.8, 4.8);
        let z = p.z();
        let start = DVec2::new(2.75, 2.4);
        let mut l = p.linker(start);
        l.enter(start, &[start, DVec2::new(2.75, 2.5)], z, 0.01);
        assert!(noted(&l, "helix entry"), "{:?}", l.tp.notes);
        assert_eq!(count(&l.tp.moves, MoveKind::Plunge), 0);
        let entry: Vec<&Move> = l.tp.moves.iter().filter(|m| m.kind == MoveKind::Entry).collect();
        let Motion::Arc { center: c, .. } = entry[0].motion else { panic!("{:?}", entry[0]) };
        // every arc of it on a circle round that centre, which holds the start (or nearly), and
        // it ends at the start, at depth
        let rh =
            l.tp.moves
                .iter()
                .filter(|m| m.kind == MoveKind::Entry)
                .map(|m| (m.to.truncate() - c).length())
                .fold(0.0, f64::max);
        assert!(
            rh >= l.link.helix_min_frac * l.r - 1e-9 && (start - c).length() <= 1.1 * rh,
            "a helix of {rh} mm round {c:?}"
        );
        for m in l.tp.moves.iter().filter(|m| matches!(m.motion, Motion::Arc { .. })) {
            assert!(((m.to.truncate() - c).length() - rh).abs() < 1e-9, "{m:?}");
        }
        assert!((l.tp.end() - start.extend(z)).length() < 1e-9, "{:?}", l.tp.end());
        // and it keeps off the bore's walls (x and y 0 and 4.8)
        let wall = c.x.min(c.y).min(4.8 - c.x).min(4.8 - c.y);
        assert!(rh + l.r <= wall, "centre {c:?}, r {rh}");
    }

    /// A pocket just wider than the tool each way and a pass too short to ramp along: no
    /// helix, no ramp, no landing beside it. Only then a plunge, at the entry feed, with a note
    /// in the program; and a later entry beside it at that level goes down that bore again.
    #[test]
    fn a_plunge_only_when_nothing_fits_and_it_is_noted() {
        let p = Pocket::new(4.3, 4.3);
        let z = p.z();
        let start = DVec2::new(2.15, 2.15);
        let mut l = p.linker(start);
        l.enter(start, &[start, DVec2::new(2.2, 2.15)], z, 0.01);
        assert!(noted(&l, "plunge: no room for a helix or a ramp"), "{:?}", l.tp.notes);
        let last = l.tp.moves.last().copied().expect("moves");
        assert_eq!((last.kind, last.to, last.feed), (MoveKind::Plunge, start.extend(z), l.entry_feed));
        assert_eq!(count(&l.tp.moves, MoveKind::Entry) + count(&l.tp.moves, MoveKind::Descend), 0);
        // a second entry at that level 0.1 mm off it (a clean-up contour round the bore): down
        // the bore again, then sideways; no second plunge
        l.down_at = None;
        let other = DVec2::new(2.25, 2.15);
        l.enter(other, &[other, DVec2::new(2.25, 2.2)], z, 0.01);
        assert_eq!(count(&l.tp.moves, MoveKind::Plunge), 1);
        let n = l.tp.moves.len();
        let (down, side) = (l.tp.moves[n - 2], l.tp.moves[n - 1]);
        assert_eq!((down.kind, down.to), (MoveKind::Descend, start.extend(z)));
        assert_eq!((side.kind, side.to), (MoveKind::Cut, other.extend(z)));
        assert!(noted(&l, "entry down a bore plunged before"), "{:?}", l.tp.notes);
        // not at another level
        l.down_at = None;
        l.enter(other, &[other, DVec2::new(2.25, 2.2)], z + 0.5, 0.01);
        assert_eq!(count(&l.tp.moves, MoveKind::Plunge), 2);
    }

    /// The pocket cleared below y = 7; the tool down at y = 5.3, its edge 0.3 mm into the
    /// material above. To the next pass, 2.8 mm straight down through cleared space, it stays
    /// down: fed (at the boosted feed) for the little way it still touches the material, then
    /// a rapid at depth.
    #[test]
    fn through_cleared_space_the_link_stays_down() {
        let p = Pocket::new(20.0, 10.0);
        let z = p.z();
        let (a, b) = (DVec2::new(10.0, 5.3), DVec2::new(10.0, 2.5));
        let mut l = p.linker(a);
        for y in [-1.0, 1.0, 3.0, 5.0] {
            clear_row(&mut l, z, y, -3.0, 23.0);
        }
        stand_at(&mut l, a, z);
        let before = l.tp.moves.len();
        l.pass(
            Pass {
                pts: vec![b, DVec2::new(14.0, 2.5)],
                closed: false,
                kind: PassKind::Clear,
                level: 0.0,
                reversible: false,
            },
            z,
        );
        let link = &l.tp.moves[before..before + 2];
        assert_eq!(link[0].kind, MoveKind::Link, "{link:?}");
        assert_eq!(link[0].feed, l.feed * l.boost());
        let fed = (link[0].to.truncate() - a).length();
        assert!(fed > 0.2 && fed < 0.35, "fed for {fed} mm");
        assert_eq!((link[1].kind, link[1].to), (MoveKind::Rapid, b.extend(z)));
        assert!(l.tp.moves[before..].iter().all(|m| m.to.z == z), "the tool left the level");
    }

    /// The pocket cleared but for a wall of material across it (8 < x < 12): from one side to
    /// the other the tool cannot stay down. It lifts just over the material — the approach
    /// height above the stock top, not the safe height — crosses, comes down by rapids to
    /// `MACHINED_APPROACH` above the level (cleared space under the stock's top) and descends
    /// at the feed.
    #[test]
    fn material_in_the_way_lifts_the_tool_no_higher_than_it_must() {
        let p = Pocket::new(20.0, 10.0);
        let z = p.z();
        let (a, b) = (DVec2::new(4.0, 5.0), DVec2::new(16.0, 5.0));
        let mut l = p.linker(a);
        for y in [1.0, 3.0, 5.0, 7.0, 9.0] {
            clear_row(&mut l, z, y, -3.0, 6.0);
            clear_row(&mut l, z, y, 14.0, 23.0);
        }
        stand_at(&mut l, a, z);
        let before = l.tp.moves.len();
        l.pass(
            Pass {
                pts: vec![b, DVec2::new(16.0, 8.0)],
                closed: false,
                kind: PassKind::Clear,
                level: 0.0,
                reversible: false,
            },
            z,
        );
        let moves = &l.tp.moves[before..];
        let k = moves.iter().position(|m| m.kind == MoveKind::Descend).expect("a descent");
        let top = moves[..k].iter().map(|m| m.to.z).fold(f64::NEG_INFINITY, f64::max);
        assert_eq!(top, p.job.top() + l.link.approach);
        assert!(top < l.safe_z);
        assert!(moves[..k].iter().all(|m| m.is_rapid()), "{:?}", &moves[..k]);
        assert_eq!(moves[k - 1].to, b.extend(z + MACHINED_APPROACH));
        assert_eq!((moves[k].to, moves[k].feed), (b.extend(z), l.feed));
    }

    /// After the last pass the tool goes straight up to the safe height, and the program says
    /// so.
    #[test]
    fn the_program_ends_with_a_retract_to_the_safe_height() {
        let p = Pocket::new(20.0, 10.0);
        let z = p.z();
        let a = DVec2::new(4.0, 5.0);
        let mut l = p.linker(a);
        l.pass(
            Pass {
                pts: vec![a, DVec2::new(16.0, 5.0)],
                closed: false,
                kind: PassKind::Clear,
                level: 0.0,
                reversible: false,
            },
            z,
        );
        let (end, safe) = (l.tp.end(), l.safe_z);
        let tp = l.finish();
        let last = tp.moves.last().copied().expect("moves");
        assert_eq!((last.kind, last.to), (MoveKind::Rapid, DVec3::new(end.x, end.y, safe)));
        assert_eq!(tp.notes.last().map(|n| (n.at, n.text.as_str())), Some((tp.moves.len() - 1, "end: retract")));
    }
}
