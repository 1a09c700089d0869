//! C1 high-speed pocketing from the medial axis (paper 2, Elber, Cohen and Drake, and its
//! planar predecessor MATHSM \[8\]).
//!
//! The program is made of circles centred on the medial axis (`geom::medial`) of the
//! tool-centre region ([`region`]), each as large as the pocket allows and the next placed where
//! the Hausdorff distance between the two reaches the stepover (§2.1), joined by bi-tangent
//! bridges (§2.2, Fig. 3), so that the path is tangent-continuous (C1) wherever the tool cuts.
//! The tool enters by a helix and a spiral of semicircles at the largest circle of each piece of
//! the axis, walks the branches depth first, and returns over the uncutting back half of each
//! circle on a smaller circle, [`CUT_BACK`] times its radius (the cut-back return, §2.1,
//! Fig. 2c; `--full-circles` turns it off). Circles smaller than [`RHO_MIN`] are not cut. The
//! walk-through (entry, circles, bridges, the cut-back return, branches) is in `docs/medial.md`.
//!
#![doc = include_str!("../../../../docs/figures/medial_axis.svg")]
//!
#![doc = include_str!("../../../../docs/figures/medial_shapes.svg")]
//!
//! *Paper 2's Figs. 1(b), 1(c) and 2(c) on swarf's example cases, drawn by the `medial_figures`
//! example.*

use super::{Clearing, Context, Program};
use crate::error::{Error, Result};
use crate::geom::DVec2;
use crate::geom::medial::{Axis, medial_axis};
use crate::model::Regions;
use crate::plan::levels::{Levels, drive};
use crate::plan::{LANDING_MARGIN, LayerGeom, Linker};
use crate::sim::sweep::Path;
use crate::toolpath::MoveKind;
use std::f64::consts::{PI, TAU};

/// Branches whose object angle is below this (degrees) are pruned from the axis.
pub const MIN_OBJECT_ANGLE: f64 = 10.0;

/// Circles smaller than this (mm) are not cut (their arcs and bridges would be shorter than a
/// controller's look-ahead resolves as curves).
pub const RHO_MIN: f64 = 0.15;

/// A tool-centre circle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Circle {
    /// Centre.
    pub c: DVec2,
    /// Radius (of the tool centre's path).
    pub rho: f64,
}

/// Circles joined by bridges, cut in one go.
#[derive(Debug, Clone, Default)]
pub struct Run {
    /// The circles in order.
    pub circles: Vec<Circle>,
    /// The first circle was cut before (a junction the walk comes back to).
    pub from_hub: bool,
}

/// The runs of every connected piece of the axis, each piece's first run starting at its
/// largest circle.
pub fn runs(axis: &Axis, step: f64, r: f64) -> Vec<Run> {
    let mut w = Walker {
        axis,
        step: Spacing { step, r },
        node_seen: vec![false; axis.nodes.len()],
        edge_seen: vec![false; axis.edges.len()],
        out: Vec::new(),
    };
    // pieces, largest circle first
    let mut roots: Vec<usize> = (0..axis.nodes.len()).collect();
    roots.sort_by(|a, b| axis.nodes[*b].r.total_cmp(&axis.nodes[*a].r));
    for root in roots {
        if w.node_seen[root] || axis.nodes[root].r < RHO_MIN {
            continue;
        }
        w.node_seen[root] = true;
        let n = &axis.nodes[root];
        let mut run = Run { circles: vec![Circle { c: n.p, rho: n.r }], from_hub: false };
        w.walk(root, &mut run);
        w.out.push(run);
    }
    // (a run that only goes back to a circle cut before has nothing to cut: the branch it
    // stood for was too small for a circle)
    w.out.retain(|r| !(r.circles.is_empty() || r.from_hub && r.circles.len() == 1));
    w.out
}

/// The depth-first walk over the axis: what it has visited and the runs it has made.
struct Walker<'a> {
    axis: &'a Axis,
    step: Spacing,
    node_seen: Vec<bool>,
    edge_seen: Vec<bool>,
    out: Vec<Run>,
}

impl Walker<'_> {
    /// True when `run` ends with the circle at node `n` (the walk can go on from it).
    fn ends_at(&self, run: &Run, n: usize) -> bool {
        run.circles.last().is_some_and(|c| (c.c - self.axis.nodes[n].p).length() < 1e-9)
    }

    /// The points of edge `e` walked from `node`, and on through the nodes where the axis
    /// merely bends (two edges: a Voronoi vertex between two boundary pieces of the same
    /// wall, every few tenths of a millimetre along a tessellated curve), so that circles
    /// are spaced along the branch rather than put at each of those vertices; and the node
    /// the chain ends at.
    fn chain(&mut self, node: usize, e: usize) -> (Vec<(DVec2, f64)>, usize) {
        let axis = self.axis;
        let mut path = axis.edges[e].from(node);
        let mut at = axis.edges[e].other(node);
        while !self.node_seen[at] && axis.nodes[at].edges.len() == 2 && axis.nodes[at].r >= RHO_MIN {
            let Some(&next) = axis.nodes[at].edges.iter().find(|&&f| !self.edge_seen[f]) else { break };
            self.node_seen[at] = true;
            self.edge_seen[next] = true;
            let more = axis.edges[next].from(at);
            path.extend_from_slice(&more[1..]);
            at = axis.edges[next].other(at);
        }
        (path, at)
    }

    /// Walks on from `node` (whose circle ends `run`).
    fn walk(&mut self, node: usize, run: &mut Run) {
        let axis = self.axis;
        let hub = Circle { c: axis.nodes[node].p, rho: axis.nodes[node].r };
        let mut first = true;
        let mut edges = axis.nodes[node].edges.clone();
        // longest branches first (ties by index: deterministic)
        edges.sort_by(|a, b| axis.edges[*b].pts.len().cmp(&axis.edges[*a].pts.len()).then(a.cmp(b)));
        for e in edges {
            if self.edge_seen[e] {
                continue;
            }
            self.edge_seen[e] = true;
            if !first {
                self.out.push(std::mem::take(run));
                *run = Run { circles: vec![hub], from_hub: true };
            }
            first = false;
            let (path, other) = self.chain(node, e);
            place(hub, &path, self.step, &mut run.circles);
            if self.node_seen[other] {
                continue;
            }
            self.node_seen[other] = true;
            // the branch goes on from the circle at the other node (placed last, when it is
            // large enough to cut)
            if self.ends_at(run, other) {
                self.walk(other, run);
            } else {
                // a node too small to cut: what lies beyond starts afresh
                self.out.push(std::mem::take(run));
                let n = &axis.nodes[other];
                if n.r >= RHO_MIN {
                    run.circles.push(Circle { c: n.p, rho: n.r });
                    self.walk(other, run);
                } else {
                    self.beyond_small(other);
                }
            }
        }
    }

    /// Goes on past a node whose circle is too small to cut: each branch beyond it starts a
    /// run of its own where its circles become large enough.
    fn beyond_small(&mut self, node: usize) {
        let axis = self.axis;
        for e in axis.nodes[node].edges.clone() {
            if self.edge_seen[e] {
                continue;
            }
            self.edge_seen[e] = true;
            let path = axis.edges[e].from(node);
            let other = axis.edges[e].other(node);
            let fresh = !self.node_seen[other];
            self.node_seen[other] = true;
            // the first point of the branch large enough to cut starts it
            let Some(k) = path.iter().position(|p| p.1 >= RHO_MIN) else {
                if fresh {
                    self.beyond_small(other);
                }
                continue;
            };
            let start = Circle { c: path[k].0, rho: path[k].1 };
            let mut run = Run { circles: vec![start], from_hub: false };
            place(start, &path[k..], self.step, &mut run.circles);
            if fresh && self.ends_at(&run, other) {
                self.walk(other, &mut run);
            }
            self.out.push(run);
        }
    }
}

/// How far apart consecutive circles may be.
#[derive(Debug, Clone, Copy)]
struct Spacing {
    /// The stepover (the Hausdorff distance between consecutive circles, §2.1).
    step: f64,
    /// Tool radius.
    r: f64,
}

impl Spacing {
    /// The largest Hausdorff distance from circle `c` to the next: the stepover, and no more
    /// than leaves a cusp of [`CUSP`] tool diameters on a wall both circles touch (two tool
    /// disks of radius ρ + R, s apart, leave s² / 8(ρ + R) between them).
    fn at(&self, c: &Circle) -> f64 {
        self.step.min((8.0 * CUSP * 2.0 * self.r * (c.rho + self.r)).sqrt())
    }
}

/// The largest cusp the circles leave on a wall, in tool diameters.
pub const CUSP: f64 = 0.02;

/// Hausdorff distance between two circles.
fn hausdorff(a: &Circle, b: &Circle) -> f64 {
    (b.c - a.c).length() + (b.rho - a.rho).abs()
}

/// Appends the circles along `path` (points and radii, starting at `from`'s centre) spaced so
/// that consecutive ones are at most `step` apart (Hausdorff), ending with the circle at the
/// path's end. Points whose circle is smaller than [`RHO_MIN`] get none.
fn place(from: Circle, path: &[(DVec2, f64)], spacing: Spacing, out: &mut Vec<Circle>) {
    // a circle whose centre is within MIN_BRIDGE of the one before it takes its place (so
    // short a bridge, printed to a micrometre, would not be tangent)
    let push = |out: &mut Vec<Circle>, c: Circle| match out.last_mut() {
        Some(q) if (q.c - c.c).length() < MIN_BRIDGE => *q = c,
        _ => out.push(c),
    };
    let mut cur = from;
    let at =
        |p0: (DVec2, f64), p1: (DVec2, f64), t: f64| Circle { c: p0.0.lerp(p1.0, t), rho: p0.1 + (p1.1 - p0.1) * t };
    for w in path.windows(2) {
        let (p0, p1) = (w[0], w[1]);
        let mut lo = 0.0;
        let mut guard = 0;
        while hausdorff(&cur, &at(p0, p1, 1.0)) > spacing.at(&cur) && guard < 10_000 {
            guard += 1;
            let step = spacing.at(&cur);
            // the point of this piece, past `lo`, at the stepover from the current circle
            let (mut a, mut b) = (lo, 1.0);
            for _ in 0..50 {
                let m = 0.5 * (a + b);
                if hausdorff(&cur, &at(p0, p1, m)) < step { a = m } else { b = m }
            }
            lo = b;
            let c = at(p0, p1, b);
            cur = c;
            if c.rho >= RHO_MIN {
                push(out, c);
            }
        }
    }
    if let Some(&(p, r)) = path.last()
        && r >= RHO_MIN
    {
        if out.last().is_none_or(|c| (c.c - p).length() > 1e-9) {
            push(out, Circle { c: p, rho: r });
        }
        return;
    }
    // a branch into a corner (its radius falls to nothing): a last circle of radius
    // `CORNER_RHO` (or the smallest that is cut, in a channel narrower than that) as far into
    // it as that allows, so that the tool reaches the corner
    let end_rho = path.iter().map(|q| q.1).fold(0.0, f64::max).min(CORNER_RHO);
    if end_rho < RHO_MIN {
        return;
    }
    if let Some(k) = path.iter().rposition(|q| q.1 >= end_rho)
        && k + 1 < path.len()
    {
        let (p0, p1) = (path[k], path[k + 1]);
        let t = ((p0.1 - end_rho) / (p0.1 - p1.1).max(1e-12)).clamp(0.0, 1.0);
        push(out, Circle { c: p0.0.lerp(p1.0, t), rho: end_rho });
    }
}

/// Consecutive circles whose centres are closer than this (mm) are one.
const MIN_BRIDGE: f64 = 0.2;

/// The radius of the last circle of a branch into a corner, mm.
pub const CORNER_RHO: f64 = 0.15;

/// Angle of a vector.
fn ang(v: DVec2) -> f64 {
    v.y.atan2(v.x)
}

/// Point of a circle at an angle.
fn on(k: &Circle, a: f64) -> DVec2 {
    k.c + k.rho * DVec2::new(a.cos(), a.sin())
}

/// Sweep from angle `a` to angle `b` in direction `s` (±1), in [0, 2π).
fn sweep(a: f64, b: f64, s: f64) -> f64 {
    ((b - a) * s).rem_euclid(TAU)
}

/// The normal (from each centre) at which the outer bi-tangent from `a` to `b` touches both
/// circles, on the side that keeps the direction `s` (+1 counter-clockwise): `None` when one
/// circle holds the other (no outer bi-tangent).
pub fn bridge_normal(a: &Circle, b: &Circle, s: f64) -> Option<DVec2> {
    let d = b.c - a.c;
    let l = d.length();
    if l < 1e-9 {
        return None;
    }
    let sin = (a.rho - b.rho) / l;
    if sin.abs() >= 1.0 - 1e-9 {
        return None;
    }
    let u = d / l;
    // right of the way for counter-clockwise circles, left for clockwise ones
    let side = DVec2::new(u.y, -u.x) * s;
    Some(side * (1.0 - sin * sin).sqrt() + u * sin)
}

/// The angle (on `k`, from its arrival angle `a_in`, in direction `s`) the tool must sweep to
/// cover the arc of `k` outside the circle `prev` before it: the whole turn without one.
fn cover(k: &Circle, prev: Option<&Circle>, a_in: f64, s: f64) -> f64 {
    let Some(p) = prev else { return TAU };
    if let Some((_, end)) = new_arc(k, p, s) {
        return sweep(a_in, end, s);
    }
    // apart from `p`, or holding it: all of it; inside it: nothing new
    let d = (p.c - k.c).length();
    if d >= k.rho + p.rho || d + p.rho <= k.rho { TAU } else { 0.0 }
}

/// The arc of `k` outside the circle `p` when the two cross: its start and end angles, in
/// direction `s` (from tc + sβ to tc − sβ, tc the angle towards `p`'s centre).
fn new_arc(k: &Circle, p: &Circle, s: f64) -> Option<(f64, f64)> {
    let d = (p.c - k.c).length();
    if d >= k.rho + p.rho || d + p.rho <= k.rho || d + k.rho <= p.rho {
        return None;
    }
    let tc = ang(p.c - k.c);
    let beta = ((k.rho * k.rho + d * d - p.rho * p.rho) / (2.0 * k.rho * d)).clamp(-1.0, 1.0).acos();
    Some((tc + s * beta, tc - s * beta))
}

/// The region whose medial axis carries the circles: where the tool centre may go, less the
/// band beyond half a radius outside the material (where the tool is open to the air, at a
/// stock edge, its centre need not go further than that to cut the edge, and circles in the
/// rest of the band would cut nothing).
pub fn region(regions: &Regions, geom: &LayerGeom) -> crate::geom::Area {
    let open = regions.material.offset(0.5 * geom.r, crate::model::REGION_TOL);
    geom.centres.intersection(&open)
}

/// The medial strategy's options (paper 2).
#[derive(Debug, Clone, PartialEq)]
pub struct MedialOptions {
    /// Return from each circle's new arc to the next circle on a smaller, "cut back" turn
    /// (paper 2 §2.1, Fig. 2c) instead of the circle's back half, which cuts nothing.
    pub cut_back: bool,
}

impl MedialOptions {
    /// Cut-back returns.
    pub const DEFAULT: MedialOptions = MedialOptions { cut_back: true };
}

impl Default for MedialOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl Clearing for MedialOptions {
    const NAME: &'static str = "medial";

    fn plan(&self, cx: &Context) -> Result<Option<Program>> {
        let axis = medial_axis(&region(cx.regions, cx.geom), MIN_OBJECT_ANGLE)
            .map_err(|e| Error::job("medial strategy", e))?;
        let runs = runs(&axis, cx.geom.step, cx.geom.r);
        if log::log_enabled!(log::Level::Debug) {
            log::debug!("medial axis: {} nodes, {} edges; {} runs", axis.nodes.len(), axis.edges.len(), runs.len());
            for r in &runs {
                let cs: Vec<String> =
                    r.circles.iter().map(|c| format!("({:.2},{:.2} r{:.2})", c.c.x, c.c.y, c.rho)).collect();
                log::trace!("  run{}: {}", if r.from_hub { " from hub" } else { "" }, cs.join(" "));
            }
        }
        if runs.is_empty() {
            return Err(Error::job("medial strategy", "the tool fits nowhere in the pocket"));
        }
        let mut levels = MedialLevels { runs: &runs, step: cx.geom.step, cut_back: self.cut_back };
        drive(cx.job, cx.regions, cx.link, cx.sim, cx.zs, cx.finish, &mut levels).map(|tp| Some(tp.into()))
    }
}

/// The runs of circles, the same at every level.
struct MedialLevels<'r> {
    runs: &'r [Run],
    step: f64,
    cut_back: bool,
}

impl<'a> Levels<'a> for MedialLevels<'_> {
    fn first(&self) -> DVec2 {
        self.runs[0].circles[0].c
    }

    fn level(&mut self, l: &mut Linker<'a>, z: f64) -> Result<()> {
        for run in self.runs {
            cut_run(l, run, z, self.step, self.cut_back);
        }
        Ok(())
    }
}

/// Cuts the arc of `k` from angle `a` through `total` (direction `s`) in pieces of at most a
/// half turn.
fn arc(l: &mut Linker, k: &Circle, a: f64, total: f64, s: f64, z: f64) {
    let feed = l.feed;
    arc_at(l, k, a, total, s, z, feed);
}

/// [`arc`] at a given feed.
fn arc_at(l: &mut Linker, k: &Circle, a: f64, total: f64, s: f64, z: f64, feed: f64) {
    if total < 1e-9 {
        return;
    }
    let pieces = (total / PI).ceil().max(1.0) as usize;
    for j in 1..=pieces {
        let t = a + s * total * j as f64 / pieces as f64;
        l.push_arc(MoveKind::Cut, on(k, t).extend(z), k.c, s > 0.0, feed);
    }
}

/// The radius of a cut-back turn as a fraction of its circle's.
pub const CUT_BACK: f64 = 0.3;

/// The cut-back return from circle `k` (its new arc ending at angle `a_e`) to the next circle
/// `nk` (paper 2 §2.1, Fig. 2c: "cut and round the back half of the circular arc ... making
/// the tool return to its next cutting position faster"): a circle `q` of radius
/// [`CUT_BACK`]·ρ inside `k`, tangent to it at `a_e` (so the turn onto it is smooth), and the
/// outer bi-tangent from `q` to `nk` on the side that keeps the direction (`a_out`: where the
/// usual bridge from `k` leaves, for the comparison of lengths). Returns `q` and the
/// angle at which the bridge leaves `q` and meets `nk` (the bi-tangent's common normal).
///
/// Nothing is lost: the back half of `k` lies inside the circle before it (that is what
/// [`cover`] leaves out), so the tool disk along it stays in the disk that circle's turn
/// cleared, and `q` lies inside `k`. `None` when the turn would not be shorter than the way
/// round `k`, or when the bridge would meet `nk` past the start of its new arc (material the
/// tool would then skip).
fn cut_back(k: &Circle, a_e: f64, nk: &Circle, a_out: f64, s: f64) -> Option<(Circle, f64)> {
    let rho = (CUT_BACK * k.rho).max(RHO_MIN);
    if rho >= 0.9 * k.rho {
        return None;
    }
    let e = DVec2::new(a_e.cos(), a_e.sin());
    let q = Circle { c: k.c + e * (k.rho - rho), rho };
    let a2 = ang(bridge_normal(&q, nk, s)?);
    // the bridge must meet `nk` outside its new arc (outside `k`)
    let (ns, ne) = new_arc(nk, k, s)?;
    if sweep(a2, ns, s) > sweep(a2, ne, s) {
        return None;
    }
    // lengths to the same point of `nk` (where the usual bridge lands, or where this one does,
    // whichever comes later)
    let usual_bridge = (on(nk, a_out) - on(k, a_out)).length();
    let new_bridge = (on(nk, a2) - on(&q, a2)).length();
    let (wait_usual, wait_new) = if sweep(a2, a_out, s) < PI {
        (0.0, nk.rho * sweep(a2, a_out, s))
    } else {
        (nk.rho * sweep(a_out, a2, s), 0.0)
    };
    let usual = k.rho * sweep(a_e, a_out, s) + usual_bridge + wait_usual;
    let short = q.rho * sweep(a_e, a2, s) + new_bridge + wait_new;
    (short < usual - 1e-6).then_some((q, a2))
}

/// Cuts one run at level `z`.
fn cut_run(l: &mut Linker, run: &Run, z: f64, step: f64, cut_backs: bool) {
    let s = if l.link.climb { 1.0 } else { -1.0 };
    let ks = &run.circles;
    if ks.is_empty() {
        return;
    }
    // where the first circle is left for the second
    let first_out = (ks.len() > 1).then(|| bridge_normal(&ks[0], &ks[1], s)).flatten();
    let mut a_in = if run.from_hub {
        let a = first_out.map_or(0.0, ang);
        match rejoin(l, &ks[0], a, z, s) {
            Some(a) => a,
            None => enter(l, &ks[0], z, step, s),
        }
    } else {
        enter(l, &ks[0], z, step, s)
    };
    // (a hub was cut before: nothing to cover on it)
    let mut prev: Option<Circle> = None;
    let mut covered_hub = run.from_hub;
    let mut i = 0;
    while i < ks.len() {
        let k = ks[i];
        let need = if covered_hub { 0.0 } else { cover(&k, prev.as_ref(), a_in, s) };
        covered_hub = false;
        // the next circle to go to: one that would cut nothing (air beside an open side, or
        // material cut already) is left out, unless it ends the run; the bridge goes on to the
        // one after it
        let idle = |k: &Circle| l.sim.is_clear(&Path::Line { a: k.c.extend(z), b: k.c.extend(z) }, k.rho + 0.05);
        let mut j = i + 1;
        while j + 1 < ks.len() && idle(&ks[j]) && bridge_normal(&k, &ks[j + 1], s).is_some() {
            j += 1;
        }
        let next = ks.get(j);
        let normal = next.and_then(|nk| bridge_normal(&k, nk, s));
        match (next, normal) {
            (Some(nk), Some(nrm)) => {
                let a_e = a_in + s * need;
                let a_out = ang(nrm);
                if cut_backs
                    && let Some((q, a2)) = cut_back(&k, a_e, nk, a_out, s)
                    && l.keep_safe(on(&q, a2), on(nk, a2), z)
                {
                    // the new arc, then the tighter turn and the bridge from it, both in the
                    // disk the circles before have cleared (at the boosted feed when the
                    // model says they cut nothing)
                    arc(l, &k, a_in, need, s, z);
                    let turn = Path::Line { a: q.c.extend(z), b: q.c.extend(z) };
                    let bridge = Path::Line { a: on(&q, a2).extend(z), b: on(nk, a2).extend(z) };
                    let air = l.sim.is_clear(&turn, q.rho + 0.05) && l.sim.is_clear(&bridge, 0.05);
                    let feed = if air { l.feed * l.boost() } else { l.feed };
                    arc_at(l, &q, a_e, sweep(a_e, a2, s), s, z, feed);
                    l.push_line(MoveKind::Cut, on(nk, a2).extend(z), feed);
                    a_in = a2;
                    prev = Some(k);
                    i = j;
                    continue;
                }
                let total = need + sweep(a_e, a_out, s);
                arc(l, &k, a_in, total, s, z);
                let to = on(nk, a_out);
                if l.keep_safe(on(&k, a_out), to, z) {
                    l.push_line(MoveKind::Cut, to.extend(z), l.feed);
                    a_in = a_out;
                    prev = Some(k);
                    i = j;
                } else {
                    // the bridge would leave the pocket: the rest is a run of its own
                    let rest = Run { circles: ks[j..].to_vec(), from_hub: false };
                    cut_run(l, &rest, z, step, cut_backs);
                    return;
                }
            }
            (Some(_), None) => {
                arc(l, &k, a_in, need, s, z);
                let rest = Run { circles: ks[j..].to_vec(), from_hub: false };
                cut_run(l, &rest, z, step, cut_backs);
                return;
            }
            (None, _) => {
                arc(l, &k, a_in, need, s, z);
                return;
            }
        }
    }
}

/// Brings the tool back onto the circle `k`, cut before, to leave it at angle `a_out`: a rapid
/// at depth straight there when the way is clear; else down where the tool lands clear of
/// material on the circle (the nearest such place before `a_out`, in direction `s`), and
/// along the circle to it. Returns the angle the tool is at on `k`; `None` when it lands clear
/// nowhere on the circle.
fn rejoin(l: &mut Linker, k: &Circle, a_out: f64, z: f64, s: f64) -> Option<f64> {
    let p = on(k, a_out);
    let cur = l.tp.end();
    if l.down_at == Some(z) && (cur.z - z).abs() < 1e-9 {
        let way = Path::Line { a: cur, b: p.extend(z) };
        if l.sim.is_clear(&way, 0.0) && l.keep_safe(cur.truncate(), p, z) {
            l.push_line(MoveKind::Rapid, p.extend(z), 0.0);
            return Some(a_out);
        }
    }
    const N: usize = 72;
    let landing = (0..N)
        .map(|j| a_out - s * TAU * j as f64 / N as f64)
        .find(|a| l.top_near(on(k, *a), l.r + LANDING_MARGIN) <= z + 0.01)?;
    arrive(l, on(k, landing), z);
    arc(l, k, landing, sweep(landing, a_out, s), s, z);
    Some(a_out)
}

/// Brings the tool, down at `z` or above, to `p` at `z` through cleared space: a rapid at
/// depth when the straight way is clear, else over the material, and a descent at the feed.
fn arrive(l: &mut Linker, p: DVec2, z: f64) {
    let cur = l.tp.end();
    if l.down_at == Some(z) && (cur.z - z).abs() < 1e-9 {
        let way = Path::Line { a: cur, b: p.extend(z) };
        if l.sim.is_clear(&way, 0.0) && l.keep_safe(cur.truncate(), p, z) {
            l.push_line(MoveKind::Rapid, p.extend(z), 0.0);
            return;
        }
    }
    let top = l.top_near(p, l.r + LANDING_MARGIN).max(z);
    l.travel(p, top + l.link.approach);
    l.push_line(MoveKind::Descend, p.extend(z), l.feed);
    l.down_at = Some(z);
}

/// Gets the tool down onto the circle `k` at `z` where nothing was cut: a descent in air where
/// it lands clear, else a helix of radius at most half the tool's round its centre; then the
/// spiral of semicircles out to `k`. Returns the angle on `k` the tool is at.
fn enter(l: &mut Linker, k: &Circle, z: f64, step: f64, s: f64) -> f64 {
    let a = k.rho.min(0.5 * l.r);
    let a0: f64 = 0.0;
    let p = k.c + a * DVec2::new(a0.cos(), a0.sin());
    let clear = l.top_near(p, l.r + LANDING_MARGIN) <= z + 0.01;
    let phi = if clear {
        arrive(l, p, z);
        a0
    } else {
        let top = l.top_near(k.c, l.r + a + 0.05).max(z);
        l.helix_down(k.c, a, top + l.link.approach, z, a0)
    };
    l.down_at = Some(z);
    // the spiral: semicircles round c and c + δ·e(φ) alternately, each half a turn wider
    let grow = k.rho - a;
    if grow > 1e-6 {
        let turns = (grow / step).ceil().max(1.0);
        let delta = grow / turns / 2.0;
        let e = DVec2::new(phi.cos(), phi.sin());
        let n = 2 * turns as usize;
        for j in 0..n {
            // even: round c, ending opposite e; odd: round c + δe, ending on e's side, wider
            let (centre, stop) = if j % 2 == 0 {
                (k.c, k.c - e * (a + j as f64 * delta))
            } else {
                (k.c + delta * e, k.c + e * (a + (j + 1) as f64 * delta))
            };
            l.push_arc(MoveKind::Cut, stop.extend(z), centre, s > 0.0, l.feed);
        }
    }
    phi
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bridges_are_tangent_to_both_circles() {
        let a = Circle { c: DVec2::new(0.0, 0.0), rho: 5.0 };
        let b = Circle { c: DVec2::new(2.0, 1.0), rho: 4.0 };
        for s in [1.0, -1.0] {
            let n = bridge_normal(&a, &b, s).expect("a bi-tangent");
            let (p, q) = (on(&a, ang(n)), on(&b, ang(n)));
            let t = (q - p).normalize();
            // tangent: perpendicular to both radii, and along the direction of travel
            assert!(t.dot(n).abs() < 1e-12);
            let vel = DVec2::new(-n.y, n.x) * s;
            assert!((t - vel).length() < 1e-9, "s {s}: {t:?} vs {vel:?}");
        }
        // one circle inside the other: none
        assert!(bridge_normal(&a, &Circle { c: DVec2::new(0.5, 0.0), rho: 1.0 }, 1.0).is_none());
    }

    #[test]
    fn circles_are_a_stepover_apart() {
        let path: Vec<(DVec2, f64)> =
            (0..=100).map(|k| (DVec2::new(k as f64 * 0.3, 0.0), 5.0 - k as f64 * 0.02)).collect();
        let start = Circle { c: path[0].0, rho: path[0].1 };
        let mut out = Vec::new();
        place(start, &path, Spacing { step: 2.0, r: 100.0 }, &mut out);
        let mut prev = start;
        for c in &out {
            assert!(hausdorff(&prev, c) <= 2.0 + 1e-9);
            prev = *c;
        }
        // the last one sits on the path's end
        assert_eq!(out.last().map(|c| c.c), Some(path[100].0));
        assert!(out.len() >= 15);
    }
}
