//! Contour-parallel offset clearing.
//!
//! The passes are level curves of the distance to the walls: the boundary of the walls grown by
//! `R + k·s` for k = 0, 1, …, clipped to where the tool touches material. In a closed pocket
//! they are the classic shrinking loops; on a side open to free space they become open curves
//! parallel to the part that start and end in the air beside the stock, so the tool enters
//! sideways. With no walls at all (facing a block) the stock outline itself is offset inward.
//!
//! Direction: with a clockwise spindle, climb milling keeps the uncut material on the tool's
//! right. Inside-out order cuts toward the walls, so the walls are kept on the right;
//! outside-in cuts away from them, so they are kept on the left. Conventional is the reverse.

use super::{Clearing, Context, Program};
use crate::error::Result;
use crate::geom::{Area, DVec2};
use crate::model::REGION_TOL;
use crate::plan::{LayerGeom, Pass, PassKind};

/// Order of contour-parallel passes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OffsetOrder {
    /// From the farthest pass toward the walls (pocket centre first, walls last; on an open
    /// side, from the free edge of the stock toward the part).
    InsideOut,
    /// From the walls outward (the wall pass first).
    OutsideIn,
}

impl OffsetOrder {
    /// Both orders.
    pub const ALL: [OffsetOrder; 2] = [OffsetOrder::InsideOut, OffsetOrder::OutsideIn];

    /// Its name (the command line's `--order`, the Python keyword's value).
    pub const fn name(self) -> &'static str {
        match self {
            OffsetOrder::InsideOut => "inside-out",
            OffsetOrder::OutsideIn => "outside-in",
        }
    }
}

/// The offset strategy's options.
#[derive(Debug, Clone, PartialEq)]
pub struct OffsetOptions {
    /// Order of the passes.
    pub order: OffsetOrder,
}

impl OffsetOptions {
    /// Inside-out.
    pub const DEFAULT: OffsetOptions = OffsetOptions { order: OffsetOrder::InsideOut };
}

impl Default for OffsetOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl Clearing for OffsetOptions {
    const NAME: &'static str = "offset";

    fn plan(&self, cx: &Context) -> Result<Option<Program>> {
        super::same_passes(cx, passes(cx.geom, cx.link.climb, self.order))
    }
}

/// Tolerance of the simplification between grown levels (mm). Levels past the wall contour are
/// at least a stepover from the walls, so this only moves them by micrometres.
pub const GROW_SIMPLIFY: f64 = 0.002;

/// Offset passes for one level, for climb milling or conventional, in `order`.
pub fn passes(g: &LayerGeom, climb: bool, order: OffsetOrder) -> Vec<Pass> {
    let mut out = Vec::new();
    let inside_out = order == OffsetOrder::InsideOut;
    if g.keep.is_empty() {
        // facing: offsets of the material outline inward, from just touching outside
        let mut k = 0usize;
        loop {
            let a = g.touch.offset(-(k as f64) * g.step, REGION_TOL).without_slivers(1e-6);
            if a.is_empty() || k > 100_000 {
                break;
            }
            for ring in a.rings() {
                let mut pts = ring.clone();
                // rings of an area have it on their left; material is inside (left) for
                // outside-in: climb wants it on the right
                if climb == crate::plan::pass::ccw(&pts) {
                    pts.reverse();
                }
                out.push(Pass { pts, closed: true, kind: PassKind::Clear, level: -(k as f64), reversible: false });
            }
            k += 1;
        }
        return out;
    }
    // levels grow one from the other: offsetting a finely divided outline by a large distance
    // makes every segment's offset overlap many others, while a stepover at a time stays cheap
    // (for disks (A ⊕ a) ⊕ b = A ⊕ (a + b)). Each grown level is simplified within
    // GROW_SIMPLIFY before the next step, or the round joins would double its vertices every
    // level; the wall contour (level 0) is exact.
    let mut levels: Vec<Vec<Pass>> = Vec::new();
    let mut grown = g.keep.offset(g.wall_level, REGION_TOL);
    let mut k = 0usize;
    loop {
        let level = g.wall_level + k as f64 * g.step;
        if k > 0 {
            grown = grown.simplified(GROW_SIMPLIFY).offset(g.step, REGION_TOL);
        }
        let kind = if k == 0 { PassKind::Contour } else { PassKind::Clear };
        let ps = ring_passes(&grown, level, &g.touch, climb, inside_out, kind);
        if ps.is_empty() && (g.touch.difference(&grown).without_slivers(1e-6).is_empty() || k > 100_000) {
            // the grown walls cover everything the tool could touch
            break;
        }
        levels.push(ps);
        k += 1;
    }
    out.extend(order_tree(levels, g.step, inside_out));
    out
}

/// Orders the passes of all levels (`levels[k]` at distance `R + k·s` from the walls) so that
/// the tool works along one branch as long as it can. A pass at level k+1 *leans on* every pass
/// at level k that runs within 1.5 stepovers of it (where offsets merge, a pass leans on
/// several). Inside-out, a pass is cut only after everything that leans on it; outside-in,
/// only after everything it leans on. Among the passes allowed next, the nearest to where the
/// tool is wins, so the tool steps from a loop to the one around it instead of crossing the
/// part to another branch.
fn order_tree(levels: Vec<Vec<Pass>>, step: f64, inside_out: bool) -> Vec<Pass> {
    let mut passes: Vec<(usize, Pass)> = Vec::new();
    let mut first_of_level = Vec::new();
    for (k, ps) in levels.into_iter().enumerate() {
        first_of_level.push(passes.len());
        passes.extend(ps.into_iter().map(|p| (k, p)));
    }
    first_of_level.push(passes.len());
    let n = passes.len();
    if n == 0 {
        return Vec::new();
    }
    // leans_on[i]: passes one level closer to the walls next to pass i
    let mut leans_on: Vec<Vec<usize>> = vec![Vec::new(); n];
    let nlev = first_of_level.len() - 1;
    let reach = 1.5 * step;
    for k in 1..nlev {
        let (a, b) = (first_of_level[k - 1], first_of_level[k]);
        if a == b {
            continue;
        }
        let mut edges = Vec::new();
        let mut owner = Vec::new();
        for (j, (_, p)) in passes.iter().enumerate().take(b).skip(a) {
            let m = p.pts.len();
            let count = if p.closed { m } else { m.saturating_sub(1) };
            for i in 0..count {
                edges.push((p.pts[i], p.pts[(i + 1) % m]));
                owner.push(j);
            }
        }
        let idx = crate::geom::index::EdgeIndex::new(edges, (2.0 * reach).max(0.5));
        for (i, (_, p)) in passes.iter().enumerate().take(first_of_level[k + 1]).skip(b) {
            let mut near: Vec<usize> = Vec::new();
            let m = DVec2::splat(reach);
            for q in &p.pts {
                idx.for_each_near(*q - m, *q + m, |e, x, y| {
                    if !near.contains(&owner[e]) && crate::geom::dist_point_segment(*q, x, y) <= reach {
                        near.push(owner[e]);
                    }
                });
            }
            near.sort_unstable();
            leans_on[i] = near;
        }
    }
    // waiting[i]: how many passes must be cut before pass i
    let mut waiting = vec![0usize; n];
    let mut unblocks: Vec<Vec<usize>> = vec![Vec::new(); n];
    for i in 0..n {
        for &j in &leans_on[i] {
            if inside_out {
                waiting[j] += 1;
                unblocks[i].push(j);
            } else {
                waiting[i] += 1;
                unblocks[j].push(i);
            }
        }
    }
    let mut done = vec![false; n];
    let mut out = Vec::with_capacity(n);
    // start: inside-out at the deepest pass, outside-in at the first wall pass
    let mut cur = if inside_out {
        passes.iter().max_by_key(|(k, _)| *k).map_or(DVec2::ZERO, |(_, p)| p.pts[0])
    } else {
        passes[0].1.pts[0]
    };
    for _ in 0..n {
        let mut best: Option<(usize, f64)> = None;
        for i in 0..n {
            if done[i] || waiting[i] > 0 {
                continue;
            }
            let p = &passes[i].1;
            let d = if p.closed {
                let stride = (p.pts.len() / 64).max(1);
                p.pts.iter().step_by(stride).map(|q| (*q - cur).length()).fold(f64::INFINITY, f64::min)
            } else {
                (p.pts[0] - cur).length()
            };
            // prefer deeper passes on ties (inside-out) so branches finish before parents
            let key = d - if inside_out { 1e-6 * passes[i].0 as f64 } else { 0.0 };
            if best.is_none_or(|b| key < b.1) {
                best = Some((i, key));
            }
        }
        // a cycle cannot happen (levels strictly order the dependencies), but never stall
        let Some((i, _)) = best.or_else(|| (0..n).find(|&i| !done[i]).map(|i| (i, 0.0))) else { break };
        done[i] = true;
        for &j in &unblocks[i] {
            waiting[j] = waiting[j].saturating_sub(1);
        }
        let p = &passes[i].1;
        cur = if p.closed {
            // the linker starts a loop near the tool and comes back there
            let stride = (p.pts.len() / 64).max(1);
            *p.pts
                .iter()
                .step_by(stride)
                .min_by(|a, b| (**a - cur).length().total_cmp(&(**b - cur).length()))
                .unwrap_or(&cur)
        } else {
            *p.pts.last().unwrap_or(&cur)
        };
        out.push(p.clone());
    }
    out
}

/// The passes at one offset level: rings of `keep` grown by `level`, clipped to `touch`,
/// oriented for climb or conventional milling.
pub fn level_passes(
    keep: &Area,
    level: f64,
    touch: &Area,
    climb: bool,
    toward_walls: bool,
    kind: PassKind,
) -> Vec<Pass> {
    ring_passes(&keep.offset(level, REGION_TOL), level, touch, climb, toward_walls, kind)
}

/// The passes along the rings of `grown` (the walls grown by `level`), clipped to `touch`.
pub fn ring_passes(
    grown: &Area,
    level: f64,
    touch: &Area,
    climb: bool,
    toward_walls: bool,
    kind: PassKind,
) -> Vec<Pass> {
    let rings: Vec<Vec<DVec2>> = grown.rings().cloned().collect();
    rings_passes(&rings, level, touch, climb, toward_walls, kind)
}

/// [`ring_passes`] along given rings (the walls on their left).
pub fn rings_passes(
    rings: &[Vec<DVec2>],
    level: f64,
    touch: &Area,
    climb: bool,
    toward_walls: bool,
    kind: PassKind,
) -> Vec<Pass> {
    let mut out = Vec::new();
    for ring in rings {
        // rings of the grown walls have the walls on their left; cutting toward the walls
        // (inside-out) with climb wants them on the right
        let mut pts = ring.clone();
        let reverse = climb == toward_walls;
        if reverse {
            pts.reverse();
        }
        // whole loop inside the touch region: keep it closed
        let mut closed_pts = pts.clone();
        closed_pts.push(pts[0]);
        let pieces = touch.clip_polyline(&closed_pts);
        let whole = pieces.len() == 1
            && (crate::geom::polyline_length(&pieces[0]) - crate::geom::polyline_length(&closed_pts)).abs() < 1e-6;
        if whole {
            out.push(Pass { pts, closed: true, kind, level, reversible: false });
        } else {
            for p in join_wrapped(pieces, &closed_pts) {
                if crate::geom::polyline_length(&p) > 1e-3 {
                    out.push(Pass { pts: p, closed: false, kind, level, reversible: false });
                }
            }
        }
    }
    out
}

/// Clipping a closed loop cuts it at its start point too; joins the piece that ends at the
/// loop's start with the one that begins there.
fn join_wrapped(mut pieces: Vec<Vec<DVec2>>, ring: &[DVec2]) -> Vec<Vec<DVec2>> {
    // the clipper need not keep the direction: orient every piece along the ring first
    for p in &mut pieces {
        orient_along(p, ring);
    }
    let s = ring[0];
    let ends_at = pieces.iter().position(|p| p.last().is_some_and(|q| (*q - s).length() < 1e-7));
    let starts_at = pieces.iter().position(|p| p.first().is_some_and(|q| (*q - s).length() < 1e-7));
    if let (Some(e), Some(b)) = (ends_at, starts_at)
        && e != b
    {
        let tail = pieces[b].clone();
        pieces[e].extend(tail.into_iter().skip(1));
        pieces.remove(b);
    }
    pieces
}

/// Reverses `piece` when its first segment runs against the nearest segment of `path`.
pub(crate) fn orient_along(piece: &mut [DVec2], path: &[DVec2]) {
    if piece.len() < 2 || path.len() < 2 {
        return;
    }
    let d = piece[1] - piece[0];
    let mid = (piece[0] + piece[1]) / 2.0;
    let mut best = f64::INFINITY;
    let mut dir = DVec2::ZERO;
    for w in path.windows(2) {
        let dd = crate::geom::dist_point_segment(mid, w[0], w[1]);
        if dd < best {
            best = dd;
            dir = w[1] - w[0];
        }
    }
    if d.dot(dir) < 0.0 {
        piece.reverse();
    }
}
