//! The state machine of one level (paper 1 §4.1, Fig. 5): find a start, then constant-engagement
//! milling and contour milling by turns until the pass ends; again until no reachable material
//! is left. The vocabulary it speaks (how a pass starts, what a step gives, the modes), the data
//! that stays the same from level to level ([`Setup`]) and the tool's clearance from the walls
//! are here too; the start search, the step and the feed are in the files beside this one.

use super::walls::Walls;
use super::{AdaptiveOptions, CONTOUR_SLACK_DEG, STEP_SLACK_DEG};
use crate::geom::{DVec2, polyline_length};
use crate::model::Job;
use crate::plan::{DP_TOL, LayerGeom, Linker, Material};
use crate::sim::edt;
use crate::sim::sweep::Path;
use crate::toolpath::MoveKind;
use std::f64::consts::{FRAC_PI_2, TAU};

/// A place where contouring gave way to constant engagement (§4.5: started from first).
#[derive(Debug, Clone, Copy)]
pub(super) struct Resume {
    pub(super) ring: usize,
    pub(super) s: f64,
    pub(super) dir: f64,
}

/// How a pass starts.
pub(super) enum Start {
    /// Continue a contour at `s` along `ring` in direction `dir` (±1), landing `land` mm behind.
    Resume { ring: usize, s: f64, dir: f64, land: f64 },
    /// Land beside the stock at `at` (found from the candidate `from`) and head along `dir`.
    Lateral { at: DVec2, from: DVec2, dir: f64 },
    /// Helix of radius `r` around `c`.
    Helix { c: DVec2, r: f64 },
    /// Ramp back and forth along the straight line from `c` to `to` (no room for a helix), ending
    /// at `c`.
    Ramp { c: DVec2, to: DVec2 },
    /// Plunge at `c` (nothing else fits).
    Plunge { c: DVec2 },
}

/// Mode of the state machine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Mode {
    Engage,
    Contour { ring: usize, s: f64, dir: f64, walked: f64 },
}

/// A pass as it is planned: its points, the cells each step removed (for the feed of §5), and
/// how many points reach the last step that removed material (the air after it is dropped).
pub(super) struct Trace {
    pub(super) pts: Vec<DVec2>,
    pub(super) rem: Vec<u32>,
    pub(super) last_cut: usize,
}

/// Where the state machine is within a pass: the tool's place and heading, the mode, and how far
/// the tool has gone without removing anything it must clear.
#[derive(Debug, Clone, Copy)]
pub(super) struct State {
    pub(super) c: DVec2,
    pub(super) alpha: f64,
    pub(super) mode: Mode,
    pub(super) air: f64,
}

/// Outcome of one constant-engagement step.
pub(super) enum EngageStep {
    /// Moved to the point, heading.
    Moved(DVec2, f64),
    /// The step would bring the tool into the part: contour instead.
    Wall,
    /// No material around the tool, or every heading of the front half too heavy: the pass
    /// ends.
    Done,
}

/// What the state machine works with that stays the same from level to level.
pub(super) struct Setup {
    pub(super) r: f64,
    /// The radius the planner cuts its model with: `r` less the largest distance between the
    /// planned steps and the emitted program (Douglas–Peucker, arc fitting, the post's
    /// rounding), so that the model never counts as cut what the program leaves.
    pub(super) r_plan: f64,
    pub(super) theta: f64,
    pub(super) over: f64,
    pub(super) climb: bool,
    pub(super) step: f64,
    /// Clearance of the tool axis from the walls beyond the radius.
    pub(super) margin: f64,
    pub(super) walls: Walls,
    /// Distance to the walls (mm) per cell of the planning grid.
    pub(super) dk: Vec<f32>,
    pub(super) boost_ring: Vec<DVec2>,
}

impl Setup {
    pub(super) fn new<M: Material>(l: &Linker<'_, M>, job: &Job, geom: &LayerGeom, opts: &AdaptiveOptions) -> Setup {
        let r = job.radius();
        // (the walls of the layer geometry are grown by the radius and this)
        let margin = geom.wall_level - r;
        let grid = l.sim.grid();
        let keep = l.sim.keep_mask();
        let dk: Vec<f32> = edt::distance(&keep, grid.nx, grid.ny).iter().map(|d| d * grid.res as f32).collect();
        let walls = Walls::new(&geom.walls, (2.0 * r).max(1.0));
        let theta = job.cutting.width.engagement_deg();
        let step = (0.1 * job.cutting.tool.diameter).max(2.0 * grid.res);
        // the enlarged ring of footnote 3: 10 % of the radius, at least 5 cells
        let boost = (0.1 * r).max(5.0 * grid.res);
        let ring = l.sim.ring().to_vec();
        let boost_ring = ring.iter().map(|o| *o * ((o.length() + boost) / o.length())).collect();
        Setup {
            r_plan: r - (DP_TOL + l.link.arc_tol + 0.001),
            r,
            theta,
            over: opts.overshoot_deg,
            climb: l.link.climb,
            step,
            margin,
            walls,
            dk,
            boost_ring,
        }
    }
}

/// The state machine of one level.
pub(super) struct Engine<'a, 'b, M: Material> {
    pub(super) l: &'b mut Linker<'a, M>,
    pub(super) c: &'b Setup,
    pub(super) resume: Vec<Resume>,
    /// Lateral starts that removed next to nothing this level (not tried again).
    pub(super) failed: Vec<DVec2>,
    /// Blocks of the lateral search that hold reachable material (see [`Engine::lateral`]).
    pub(super) coarse: Vec<bool>,
    /// Distance in blocks from each block to the nearest block of `coarse`: exact up to the
    /// lateral search's reach, larger than that beyond it (kept with `coarse`).
    pub(super) coarse_dist: Vec<f32>,
    /// The blocks a lateral start may be looked for at (a little more than a radius from the
    /// material by `coarse_dist`), in row order.
    pub(super) coarse_band: Vec<u32>,
    pub(super) flags: Vec<bool>,
    pub(super) z: f64,
    pub(super) why: &'static str,
    /// Lateral starts may stand anywhere in a coarse block, not only at its centre (set when
    /// the centres give no start on a level).
    pub(super) relaxed: bool,
    /// Steps the passes of this level have taken.
    pub(super) steps: usize,
}

impl<'a, 'b, M: Material> Engine<'a, 'b, M> {
    pub(super) fn new(l: &'b mut Linker<'a, M>, c: &'b Setup) -> Self {
        Engine {
            l,
            c,
            resume: Vec::new(),
            failed: Vec::new(),
            coarse: Vec::new(),
            coarse_dist: Vec::new(),
            coarse_band: Vec::new(),
            flags: Vec::new(),
            z: 0.0,
            why: "",
            relaxed: false,
            steps: 0,
        }
    }

    /// Engagement above the reference at which contouring gives way to constant engagement:
    /// the overshoot of §4.4, but at most `CONTOUR_SLACK_DEG`, so that the wall-following
    /// stays well inside the stated bound.
    pub(super) fn switch_slack(&self) -> f64 {
        (0.5 * self.c.over).min(CONTOUR_SLACK_DEG)
    }

    /// Distance from `p` to the walls read from the grid (±one cell).
    pub(super) fn dk_at(&self, p: DVec2) -> f64 {
        let g = self.l.sim.grid();
        g.cell_of(p).map_or(0.0, |(i, j)| self.c.dk[j * g.nx + i] as f64)
    }

    /// May the tool axis stand at `p`?
    pub(super) fn allowed(&self, p: DVec2) -> bool {
        let need = self.c.r + self.c.margin;
        let res = self.l.sim.grid().res;
        let d = self.dk_at(p);
        if d >= need + 2.0 * res {
            return true;
        }
        if d < need - 2.0 * res {
            return false;
        }
        self.l.sim.keep_distance(&Path::Line { a: p.extend(0.0), b: p.extend(0.0) }, need + 1.0) >= need
    }

    /// Starts the level at `z`: no resume points, no failed starts, the model counting the
    /// material left there.
    pub(super) fn begin(&mut self, z: f64) {
        self.z = z;
        self.resume.clear();
        self.failed.clear();
        self.relaxed = false;
        self.steps = 0;
        self.coarse.clear();
        self.coarse_dist.clear();
        self.coarse_band.clear();
        self.l.sim.begin_level(z);
    }

    /// One level: the state machine until no reachable material is left or no start is found.
    pub(super) fn level(&mut self, z: f64) -> Vec<Vec<DVec2>> {
        self.begin(z);
        let mut passes = Vec::new();
        let total = self.l.sim.reach_left().max(1);
        let mut idle = 0;
        while self.l.sim.reach_left() > 0 {
            let before = self.l.sim.reach_left();
            let Some(start) = self.find_start().or_else(|| {
                // no start left: look again, lateral starts anywhere in a block (channels
                // narrower than two blocks, whose centres may all miss the strip the tool can
                // stand on); done at the end only, so that open areas keep their order
                if self.relaxed {
                    return None;
                }
                self.relaxed = true;
                self.find_start()
            }) else {
                break;
            };
            let kind = match &start {
                Start::Resume { .. } => "resume",
                Start::Lateral { .. } => "lateral",
                Start::Helix { .. } => "helix",
                Start::Ramp { .. } => "ramp",
                Start::Plunge { .. } => "plunge",
            };
            let lateral_at = match &start {
                Start::Lateral { from, .. } => Some(*from),
                Start::Resume { ring, s, .. } => Some(self.c.walls.at(*ring, *s).0),
                _ => None,
            };
            let pass = self.run(start);
            log::trace!(
                "pass {} {kind}: {} points, {:.1} mm from {:?}, removed {} cells, {} left, ended: {}",
                passes.len(),
                pass.len(),
                polyline_length(&pass),
                pass.first(),
                before - self.l.sim.reach_left(),
                self.l.sim.reach_left(),
                self.why
            );
            if pass.len() > 1 {
                passes.push(pass);
            }
            // a pass that removes next to nothing, again and again: stop, the clean-up takes
            // what is left
            if before - self.l.sim.reach_left() < 4 {
                if let Some(at) = lateral_at {
                    self.failed.push(at);
                }
                idle += 1;
                if idle > 30 {
                    break;
                }
            } else {
                idle = 0;
            }
            if passes.len() > 20_000 || self.l.sim.reach_left() * 1_000_000 < total {
                break;
            }
        }
        passes
    }

    // ---- passes ----------------------------------------------------------------------------

    /// Brings the tool to depth as `start` says and runs the state machine; returns the pass.
    pub(super) fn run(&mut self, start: Start) -> Vec<DVec2> {
        let z = self.z;
        let mut st = self.land(start);
        self.l.down_at = Some(z);
        let mut tr = Trace { pts: vec![st.c], rem: vec![0], last_cut: 1 };
        let mut steps = 0usize;
        let max_steps = 200_000;
        // a pass that has cut nothing for four times the steps its air may last (`advance`
        // ends one after a turn of air) is going round a place it cannot leave: onto a wall,
        // off it again, which starts its air anew (a slot barely wider than the tool)
        let idle_max = 4 * (TAU * self.c.r / self.c.step).ceil() as usize;
        loop {
            steps += 1;
            if steps > max_steps || !self.advance(&mut st, &mut tr) {
                break;
            }
            if tr.pts.len() - tr.last_cut > idle_max {
                self.why = "going round without cutting";
                break;
            }
        }
        self.steps += steps;
        tr.pts.truncate(tr.last_cut);
        tr.rem.truncate(tr.last_cut);
        self.emit(&tr.pts, &tr.rem, z);
        tr.pts
    }

    /// Brings the tool to depth as `start` says: where it is then, its heading and its mode.
    pub(super) fn land(&mut self, start: Start) -> State {
        let z = self.z;
        let (c, alpha, mode) = match start {
            Start::Resume { ring, s, dir, land } => {
                let (q, t) = self.c.walls.at(ring, s - dir * land);
                self.arrive(q, z);
                let t = t * dir;
                (q, t.y.atan2(t.x), Mode::Contour { ring, s: s - dir * land, dir, walked: 0.0 })
            }
            Start::Lateral { at, dir, .. } => {
                self.arrive(at, z);
                // heading so that the material is on the milling side (the right for climb)
                let s = if self.c.climb { 1.0 } else { -1.0 };
                (at, dir + s * FRAC_PI_2, Mode::Engage)
            }
            Start::Helix { c, r } => {
                let a_end = self.l.helix_down(
                    c,
                    r,
                    self.l.top_near(c, self.c.r + r + 0.05).max(z) + self.l.link.approach,
                    z,
                    0.0,
                );
                let p = c + r * DVec2::new(a_end.cos(), a_end.sin());
                let s = if self.c.climb { 1.0 } else { -1.0 };
                (p, a_end + s * FRAC_PI_2, Mode::Engage)
            }
            Start::Ramp { c, to } => {
                let line = Path::Line { a: c.extend(0.0), b: to.extend(0.0) };
                let top = (self.l.sim.max_height_near(&line, self.c.r + 0.05) as f64).max(z);
                self.l.ramp(&[c, to], top + self.l.link.approach, z);
                let d = to - c;
                let s = if self.c.climb { 1.0 } else { -1.0 };
                (c, d.y.atan2(d.x) + s * FRAC_PI_2, Mode::Engage)
            }
            Start::Plunge { c } => {
                let top = self.l.top_near(c, self.c.r);
                self.l.plunge(c, top, z, "no room for a helix and no way in from the side");
                (c, 0.0, Mode::Engage)
            }
        };
        State { c, alpha, mode, air: 0.0 }
    }

    /// One move of the state machine from `st` (Fig. 5): a step of constant engagement, the
    /// handover to the wall's contour, a step along it or the switch back to constant
    /// engagement (leaving a resume point); the moves are cut into the model and appended to
    /// `tr`. False when the pass ends there (`why` says why).
    pub(super) fn advance(&mut self, st: &mut State, tr: &mut Trace) -> bool {
        let z = self.z;
        match st.mode {
            Mode::Engage => match self.engage_step(st.c, st.alpha) {
                EngageStep::Moved(n, a) => {
                    let left = self.l.sim.reach_left();
                    self.cut_to(tr, n);
                    st.c = n;
                    st.alpha = a;
                    // circling without removing anything the tool must clear
                    st.air = if self.l.sim.reach_left() == left { st.air + self.c.step } else { 0.0 };
                    if st.air > TAU * self.c.r {
                        self.why = "constant engagement in air";
                        return false;
                    }
                }
                EngageStep::Wall => {
                    let Some((ring, s, q)) = self.c.walls.project(st.c, 3.0 * self.c.step + self.c.r) else {
                        return false;
                    };
                    // the wall ahead is too heavy to follow: leave it, turning away from
                    // the material, when that is possible
                    {
                        let (_, t) = self.c.walls.at(ring, s);
                        let dir = self.contour_direction(ring, s, q, t, st.alpha);
                        let (n, t2) = self.c.walls.at(ring, s + dir * self.c.step);
                        let e = self.l.sim.front_engagement(n, z, t2 * dir);
                        // and the step onto the wall must not be heavy either, at its end or
                        // on its way
                        let e_q = if (q - st.c).length() > 1e-6 {
                            let d = q - st.c;
                            let e_end = self.l.sim.front_engagement(q, z, d.normalize());
                            e_end.max(self.along_engagement(st.c, d.y.atan2(d.x), d.length()))
                        } else {
                            0.0
                        };
                        let heavy = e > self.c.theta + self.switch_slack() || e_q > self.c.theta + STEP_SLACK_DEG;
                        if heavy && let Some((n2, a)) = self.away_step(st.c, st.alpha) {
                            self.cut_to(tr, n2);
                            st.c = n2;
                            st.alpha = a;
                            return true;
                        }
                        if e_q > self.c.theta + CONTOUR_SLACK_DEG + 5.0 {
                            self.why = "wall too heavy to reach";
                            return false;
                        }
                    }
                    if (q - st.c).length() > 1e-9 {
                        if !self.segment_allowed(st.c, q) {
                            return false;
                        }
                        self.cut_to(tr, q);
                        st.c = q;
                    }
                    st.air = 0.0;
                    let (_, t) = self.c.walls.at(ring, s);
                    let dir = self.contour_direction(ring, s, st.c, t, st.alpha);
                    st.mode = Mode::Contour { ring, s, dir, walked: 0.0 };
                    st.alpha = (t * dir).y.atan2((t * dir).x);
                }
                EngageStep::Done => {
                    self.why = "no material";
                    return false;
                }
            },
            Mode::Contour { ring, s, dir, walked } => {
                let ns = s + dir * self.c.step;
                let (n, t) = self.c.walls.at(ring, ns);
                let t = t * dir;
                // the engagement at the step's end and at the contour's vertices on the way
                let corners = self.c.walls.between(ring, s, ns);
                let mut e = self.l.sim.front_engagement(n, z, t);
                let mut prev = st.c;
                for q in &corners {
                    if (*q - prev).length() > 1e-6 {
                        e = e.max(self.l.sim.front_engagement(*q, z, (*q - prev).normalize()));
                    }
                    prev = *q;
                }
                if e > self.c.theta + self.switch_slack() || (e > self.c.theta && self.turns_away(st.c, st.alpha, t)) {
                    // back to constant engagement when a step of it is possible; come back
                    // here later (§4.5)
                    let mut es = self.engage_step(st.c, st.alpha);
                    if matches!(es, EngageStep::Wall)
                        && let Some((n2, a)) = self.away_step(st.c, st.alpha)
                    {
                        es = EngageStep::Moved(n2, a);
                    }
                    match es {
                        EngageStep::Moved(n2, a) => {
                            self.resume.push(Resume { ring, s, dir });
                            st.mode = Mode::Engage;
                            self.cut_to(tr, n2);
                            st.c = n2;
                            st.alpha = a;
                            return true;
                        }
                        // the material turns into the wall: keep to the wall while the
                        // engagement stays within the allowed overshoot
                        _ if e <= self.c.theta + self.c.over => {}
                        _ => {
                            self.why = "contour too heavy and no way off the wall";
                            return false;
                        }
                    }
                }
                let left = self.l.sim.reach_left();
                // follow the contour through its own vertices (its round corners)
                for q in corners {
                    self.cut_to(tr, q);
                }
                self.cut_to(tr, n);
                st.c = n;
                st.alpha = t.y.atan2(t.x);
                // air: nothing the tool must clear was removed by this step
                st.air = if self.l.sim.reach_left() == left { st.air + self.c.step } else { 0.0 };
                let walked = walked + self.c.step;
                if st.air > self.c.r || walked > self.c.walls.len(ring) + self.c.step {
                    self.why = "contour in air / complete";
                    return false;
                }
                st.mode = Mode::Contour { ring, s: ns, dir, walked };
            }
        }
        true
    }

    /// Cuts the model from the end of the pass to `to` and appends `to` to the pass.
    pub(super) fn cut_to(&mut self, tr: &mut Trace, to: DVec2) {
        let from = *tr.pts.last().expect("a pass starts with its landing point");
        let k = self.l.sim.cut_step_r(from, to, self.z, self.c.r_plan);
        tr.pts.push(to);
        tr.rem.push(k as u32);
        if k > 0 {
            tr.last_cut = tr.pts.len();
        }
    }

    /// Which way to follow the contour `ring` from arc length `s` (the point `c`, tangent `t`):
    /// the only way with material along the wall within a tool radius, if one way has it
    /// within the contour's slack over the reference and the other has none (a pass that
    /// reaches the wall beside cusps the passes before it left there clears them along it,
    /// rather than walking off into cleared space and leaving them each to a pass of its own);
    /// else the way that has the material on the milling side (the right for climb), so the
    /// milling type is kept along the wall too; on a tie, the way closer to the heading
    /// `alpha`.
    pub(super) fn contour_direction(&mut self, ring: usize, s: f64, c: DVec2, t: DVec2, alpha: f64) -> f64 {
        // (the largest engagement along the wall within a radius each way)
        let ahead = |e: &Self, dir: f64| {
            let n = (e.c.r / e.c.step).ceil().max(1.0) as usize;
            (1..=n)
                .map(|k| {
                    let (q, tq) = e.c.walls.at(ring, s + dir * k as f64 * e.c.step);
                    e.l.sim.front_engagement(q, e.z, tq * dir)
                })
                .fold(0.0, f64::max)
        };
        let light = |e: f64| e > 0.0 && e <= self.c.theta + self.switch_slack();
        match (ahead(self, 1.0), ahead(self, -1.0)) {
            (a, b) if light(a) && b <= 0.0 => return 1.0,
            (a, b) if a <= 0.0 && light(b) => return -1.0,
            _ => {}
        }
        let mut flags = std::mem::take(&mut self.flags);
        self.l.sim.ring_material(c, self.z, &mut flags);
        let ring = self.l.sim.ring();
        let side = if self.c.climb { -1.0 } else { 1.0 };
        let mut score = [0usize; 2];
        for (k, dir) in [1.0, -1.0].into_iter().enumerate() {
            let d = t * dir;
            let n = d.perp() * side; // the milling side
            for (off, f) in ring.iter().zip(&flags) {
                if *f && off.dot(d) >= 0.0 && off.dot(n) > 0.0 {
                    score[k] += 1;
                }
            }
        }
        self.flags = flags;
        if score[0] != score[1] {
            return if score[0] > score[1] { 1.0 } else { -1.0 };
        }
        if t.dot(DVec2::new(alpha.cos(), alpha.sin())) >= 0.0 { 1.0 } else { -1.0 }
    }

    /// Gets the tool down at `p` (clear there) for a sideways start.
    pub(super) fn arrive(&mut self, p: DVec2, z: f64) {
        let cur = self.l.tp.end();
        if self.l.down_at == Some(z)
            && self.l.keep_safe(cur.truncate(), p, z)
            && let Some(t) = self.l.sim.leaving_distance(cur, p.extend(z), self.l.clear_margin)
        {
            self.l.link_clear(p, z, t);
            return;
        }
        // a short way that crosses a little material: cut it when the engagement along it (read
        // against the stock as it is, which over-reads every point after the first) stays
        // within the step's slack — a lift over it and a descent cost more than the cut
        let len = (p - cur.truncate()).length();
        if self.l.down_at == Some(z)
            && len > 1e-9
            && len <= 1.5 * self.l.step
            && self.step_allowed(cur.truncate(), p)
            && self.l.cuts_within(cur.truncate(), p, z, self.c.theta + STEP_SLACK_DEG)
        {
            self.l.push_line(MoveKind::Cut, p.extend(z), self.l.feed);
            return;
        }
        // round the material that stands on the straight way, at depth through cleared space
        if self.l.down_at == Some(z) && self.l.link_around(p, z) {
            return;
        }
        let top = self.l.top_near(p, self.landing_reach());
        let h = (z + self.l.link.approach).max(if top.is_finite() { top + self.l.link.approach } else { z });
        self.l.travel(p, h);
        self.l.push_line(MoveKind::Descend, p.extend(z), self.l.feed);
    }

    /// The whole step keeps its clearance from the walls (a step between two allowed points can
    /// cut the corner of a convex wall by up to Δ²/8ρ).
    pub(super) fn step_allowed(&self, a: DVec2, b: DVec2) -> bool {
        let need = self.c.r + self.c.margin;
        let res = self.l.sim.grid().res;
        if self.dk_at(a).min(self.dk_at(b)) >= need + (b - a).length() + 2.0 * res {
            return true;
        }
        self.l.sim.keep_distance(&Path::Line { a: a.extend(0.0), b: b.extend(0.0) }, need + 1.0) >= need - 1e-9
    }

    pub(super) fn segment_allowed(&self, a: DVec2, b: DVec2) -> bool {
        self.l.sim.keep_distance(&Path::Line { a: a.extend(0.0), b: b.extend(0.0) }, self.c.r + 1.0) >= self.c.r
    }
}

/// Small hand-made pockets to drive the engine on, step by step.
#[cfg(test)]
pub(super) mod fixture {
    use super::{Engine, Setup};
    use crate::geom::{Area, DVec2};
    use crate::model::{Job, Regions};
    use crate::plan::{LayerGeom, LinkOptions, Linker};
    use crate::sim::SimOptions;
    use crate::sim::sweep::Path;
    use crate::strategy::{AdaptiveOptions, Strategy};

    /// A 20×10 mm pocket 2 mm deep (its walls a frame of part round the stock), a Ø4 mm tool
    /// at the default 40 % stepover, planned on 0.05 mm cells.
    pub(in super::super) struct Pocket {
        pub(in super::super) job: Job,
        regions: Regions,
        pub(in super::super) geom: LayerGeom,
        link: LinkOptions,
        sim: SimOptions,
        opts: AdaptiveOptions,
    }

    impl Pocket {
        pub(in super::super) fn new(climb: bool) -> Pocket {
            // (the tests' geometry is drawn for a 40 % stepover, 78.5°)
            Pocket::shaped(Area::rect(0.0, 0.0, 20.0, 10.0), 4.0, 2.0, 0.4, 0.05, climb)
        }

        /// The pocket `pocket` (its walls a frame of part 5 mm wide round it), `depth` deep, a
        /// tool of diameter `d` at `stepover`, planned on cells of `res`.
        pub(in super::super) fn shaped(
            pocket: Area,
            d: f64,
            depth: f64,
            stepover: f64,
            res: f64,
            climb: bool,
        ) -> Pocket {
            let (lo, hi) = pocket.bounds().expect("a pocket");
            let part = Area::rect(lo.x - 5.0, lo.y - 5.0, hi.x + 5.0, hi.y + 5.0).difference(&pocket);
            let mut job = Job::new("pocket", pocket, part, d, depth);
            job.cutting.width = crate::model::Width::Stepover(stepover);
            let link = LinkOptions { climb, ..LinkOptions::DEFAULT };
            let sim = SimOptions { res: Some(res), ..SimOptions::DEFAULT };
            let opts = AdaptiveOptions::DEFAULT;
            let margin = Strategy::Adaptive(opts.clone()).wall_margin(&link);
            let regions = job.regions(job.radius(), margin).expect("the pocket's regions");
            let geom = LayerGeom::new(&job, &regions, &link, margin).expect("the pocket's geometry");
            Pocket { job, regions, geom, link, sim, opts }
        }

        /// The level (the floor).
        pub(in super::super) fn z(&self) -> f64 {
            self.job.levels()[0]
        }

        /// A linker on a fresh model of the pocket, the tool up above its middle.
        pub(in super::super) fn linker(&self) -> Linker<'_> {
            let mut l = Linker::new(&self.job, &self.regions, &self.link, &self.sim, DVec2::new(10.0, 5.0))
                .expect("the pocket's model");
            l.clear_margin = 0.75 * l.sim.grid.res;
            l
        }

        /// What the engine keeps from level to level.
        pub(in super::super) fn setup(&self, l: &Linker) -> Setup {
            Setup::new(l, &self.job, &self.geom, &self.opts)
        }
    }

    /// Clears the model at `z` along the horizontal line at `y` from `x0` to `x1` (everything
    /// within the tool radius of it).
    pub(in super::super) fn clear_row(l: &mut Linker, z: f64, y: f64, x0: f64, x1: f64) {
        l.sim.cut(&Path::Line { a: DVec2::new(x0, y).extend(z), b: DVec2::new(x1, y).extend(z) });
    }

    /// An engine at the level of the pocket.
    pub(in super::super) fn engine<'a, 'b>(
        l: &'b mut Linker<'a>,
        c: &'b Setup,
        z: f64,
    ) -> Engine<'a, 'b, crate::sim::RasterSim> {
        let mut e = Engine::new(l, c);
        e.begin(z);
        e
    }
}

#[cfg(test)]
mod tests {
    use super::fixture::{Pocket, clear_row, engine};
    use super::*;
    use std::f64::consts::PI;

    /// A band of material 0.4 mm thick along the top wall of the pocket (y > 9.6), the rest
    /// cleared; the tool below it, heading along it with the band on the milling side, at the
    /// tool radius and a tenth from the wall: the step of eq. 9 turns toward the band and would
    /// come closer than the radius to the part, so the tool goes onto the wall's offset contour
    /// and follows it — right to left for climb milling (the band on its right), left to right
    /// for conventional.
    #[test]
    fn a_step_into_the_wall_hands_over_to_the_contour_in_the_milling_direction() {
        for (climb, heading, way) in [(true, PI, -1.0), (false, 0.0, 1.0)] {
            let p = Pocket::new(climb);
            let z = p.z();
            let mut l = p.linker();
            for y in [-0.4, 1.6, 3.6, 5.6, 7.6] {
                clear_row(&mut l, z, y, -3.0, 23.0);
            }
            let c = p.setup(&l);
            let mut e = engine(&mut l, &c, z);
            let at = DVec2::new(12.0, 7.9);
            let on_wall = 10.0 - p.geom.wall_level;
            assert!(matches!(e.engage_step(at, heading), EngageStep::Wall), "climb {climb}: the step hits no wall");
            let mut st = State { c: at, alpha: heading, mode: Mode::Engage, air: 0.0 };
            let mut tr = Trace { pts: vec![at], rem: vec![0], last_cut: 1 };
            assert!(e.advance(&mut st, &mut tr), "climb {climb}: the pass ended: {}", e.why);
            // on the offset contour, straight above where the tool was
            assert!(matches!(st.mode, Mode::Contour { .. }), "climb {climb}: {:?}", st.mode);
            assert!((st.c.y - on_wall).abs() < 0.005 && (st.c.x - at.x).abs() < 0.01, "climb {climb}: {:?}", st.c);
            assert!((st.alpha.cos() - way).abs() < 1e-6, "climb {climb}: heading {}°", st.alpha.to_degrees());
            // and along it, a step at a time, the way that keeps the band on the milling side,
            // cutting it
            for k in 1..=4 {
                let before = (st.c, e.l.sim.reach_left());
                assert!(e.advance(&mut st, &mut tr), "climb {climb}: the pass ended: {}", e.why);
                assert!(matches!(st.mode, Mode::Contour { .. }), "climb {climb}, step {k}: {:?}", st.mode);
                assert!((st.c.y - on_wall).abs() < 0.005, "climb {climb}, step {k}: {:?}", st.c);
                assert!((st.c.x - before.0.x - way * c.step).abs() < 1e-9, "climb {climb}, step {k}: {:?}", st.c);
                assert!(e.l.sim.reach_left() < before.1, "climb {climb}, step {k}: nothing cut");
            }
        }
    }

    /// The band along the top wall of the previous test cleared by the tool coming along the
    /// wall from the left to x = 12 and left to the right of it, the tool there with its
    /// heading to the left (the way the milling side ties to): the contour goes right, along
    /// the band, which it cuts at no more than the reference and its slack, not left into
    /// cleared space (the band would then be left to passes of its own). With the band
    /// cleared both ways, the heading decides.
    #[test]
    fn the_contour_goes_the_way_the_wall_still_has_material() {
        let p = Pocket::new(true);
        let z = p.z();
        let on_wall = 10.0 - p.geom.wall_level;
        for band in [true, false] {
            let mut l = p.linker();
            for y in [-0.4, 1.6, 3.6, 5.6, 7.6] {
                clear_row(&mut l, z, y, -3.0, 23.0);
            }
            // (the tool came along the wall from the left)
            clear_row(&mut l, z, on_wall, -3.0, if band { 12.0 } else { 23.0 });
            let c = p.setup(&l);
            let mut e = engine(&mut l, &c, z);
            let at = DVec2::new(12.0, on_wall);
            let (ring, s, q) = e.c.walls.project(at, 1.0).expect("the wall's contour");
            assert!((q - at).length() < 0.01, "{q:?}");
            let (_, t) = e.c.walls.at(ring, s);
            let dir = e.contour_direction(ring, s, q, t, PI);
            let way = (t * dir).x;
            assert!((way.abs() - 1.0).abs() < 1e-6, "{t:?}");
            assert_eq!(way > 0.0, band, "band {band}: the contour goes {way}");
            if band {
                let e_band = e.l.sim.front_engagement(q + DVec2::new(c.step, 0.0), z, DVec2::X);
                assert!(e_band > 0.0 && e_band <= c.theta + e.switch_slack(), "{e_band}°");
            }
        }
    }

    /// A curved slot (radii 14 to 17.49 mm over 90°, round ends) 0.49 mm wider than the Ø3
    /// tool, 3 mm deep: where the tool cannot leave a place, onto the wall and off it again
    /// (which starts its air anew), circling ahead of material it cannot reach, the pass ends
    /// within a few turns; it had gone round 200 000 steps, most of the level's planning.
    #[test]
    fn a_pass_that_goes_round_without_cutting_ends() {
        let (r0, w) = (14.0, 3.49);
        let at = |r: f64, deg: f64| r * DVec2::new(deg.to_radians().cos(), deg.to_radians().sin());
        let end = |deg: f64, from: f64| {
            let c = at(r0 + 0.5 * w, deg);
            (0..=90).map(move |k| c + at(0.5 * w, from - 2.0 * k as f64))
        };
        let ring: Vec<DVec2> = (0..=180)
            .map(|k| at(r0, 20.0 + 0.5 * k as f64))
            .chain(end(110.0, 290.0))
            .chain((0..=180).map(|k| at(r0 + w, 110.0 - 0.5 * k as f64)))
            .chain(end(20.0, 20.0))
            .collect();
        let slot = crate::geom::Area::from_rings(&[ring], crate::geom::area::Fill::NonZero);
        let p = Pocket::shaped(slot, 3.0, 3.0, 0.25, 0.03, true);
        let z = p.z();
        let mut l = p.linker();
        let c = p.setup(&l);
        let mut e = engine(&mut l, &c, z);
        let passes = e.level(z);
        assert!(!passes.is_empty());
        // the slot is 24.7 mm long at its middle: a step of a quarter of 0.3 mm is 330 steps
        assert!(e.steps < 20_000, "{} steps", e.steps);
    }
}
