//! Chaining loose pieces (lines, arcs, open polylines) into closed contours.
//!
//! Drawings often describe one outline as many separate entities whose endpoints merely touch.
//! [`chain`] joins such [`Piece`]s end to end, taking at each step the nearest unused end within
//! `tol` (found in a hash grid, so `O(n)` on ordinary drawings), closing a chain as soon as its
//! own ends meet, snapping each joint to the midpoint of its two ends and keeping arcs exact
//! (reversed with [`Contour::reverse`]); repeated pieces and edges drawn twice are handled
//! without zero-area loops. A chain that stays open is reported with its gaps
//! ([`open_contour_message`]), and the output is deterministic. The rules in full are in
//! `docs/import.md`.

use crate::contour::{Contour, Segment, Vertex};
use std::collections::HashMap;

/// An open (or closed) piece of an outline, with where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Piece {
    /// The geometry.
    pub contour: Contour,
    /// Where it came from, for messages (e.g. `LINE at line 345`).
    pub origin: String,
}

/// Where a chain is open: one of its dangling ends and the nearest other dangling end.
#[derive(Debug, Clone, PartialEq)]
pub struct Gap {
    /// The dangling end.
    pub a: [f64; 2],
    /// The nearest other dangling end.
    pub b: [f64; 2],
    /// Distance from `a` to `b`.
    pub distance: f64,
    /// Origin of the piece that ends at `a`.
    pub origin_a: String,
    /// Origin of the piece that ends at `b`.
    pub origin_b: String,
}

/// A chain that could not be closed.
#[derive(Debug, Clone, PartialEq)]
pub struct OpenChain {
    /// The joined pieces (open).
    pub contour: Contour,
    /// Origins of the pieces, in chain order.
    pub origins: Vec<String>,
    /// Where it is open: one gap per dangling end (one only when both ends name the same gap).
    pub gaps: Vec<Gap>,
}

/// The result of [`chain`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Chained {
    /// Closed contours with the origins of their pieces, in chain order.
    pub closed: Vec<(Contour, Vec<String>)>,
    /// Chains left open.
    pub open: Vec<OpenChain>,
}

/// Joins pieces whose endpoints lie within `tol` of each other into contours.
///
/// See the [module documentation](self) for the method. A `tol` that is not a positive finite
/// number joins only endpoints that are exactly equal.
pub fn chain(pieces: Vec<Piece>, tol: f64) -> Chained {
    let tol = if tol.is_finite() && tol > 0.0 { tol } else { 0.0 };
    let cell = if tol > 0.0 { tol } else { 1e-6 };
    let n = pieces.len();

    // Ends of the open pieces: id = 2 * piece + (0 start, 1 end).
    let mut ends: Vec<Option<([f64; 2], [f64; 2])>> = Vec::with_capacity(n);
    let mut grid = Grid::new(cell);
    for (i, p) in pieces.iter().enumerate() {
        let vs = &p.contour.vertices;
        let e = match (vs.first(), vs.last()) {
            (Some(f), Some(l)) if !p.contour.closed && vs.len() >= 2 => Some(([f.x, f.y], [l.x, l.y])),
            _ => None,
        };
        if let Some((s, t)) = e {
            grid.insert(s, 2 * i);
            grid.insert(t, 2 * i + 1);
        }
        ends.push(e);
    }
    let lengths: Vec<f64> = pieces.iter().map(|p| if p.contour.closed { 0.0 } else { p.contour.length() }).collect();

    let mut used = vec![false; n];
    let twin = twins(&pieces, &ends, &grid, tol, &mut used);
    let mut in_closed = vec![false; n];
    let mut out = Chained::default();
    let mut open_seqs: Vec<Vec<(usize, bool)>> = Vec::new();

    for seed in 0..n {
        if used[seed] {
            continue;
        }
        used[seed] = true;
        let piece = &pieces[seed];
        if piece.contour.closed {
            if piece.contour.vertices.len() >= 2 {
                out.closed.push((piece.contour.clone(), vec![piece.origin.clone()]));
            }
            continue;
        }
        let Some((s0, e0)) = ends[seed] else { continue };
        // (piece, reversed) in chain order
        let mut seq: std::collections::VecDeque<(usize, bool)> = std::collections::VecDeque::new();
        seq.push_back((seed, false));
        let (mut head, mut tail) = (s0, e0);
        let mut length = lengths[seed];
        let mut closed = false;
        let closes = |head: [f64; 2], tail: [f64; 2], length: f64| dist(head, tail) <= tol && length > 2.0 * tol;

        // forward from the tail
        loop {
            if closes(head, tail, length) {
                closed = true;
                break;
            }
            // never straight back along a twin of the last piece
            let last = seq.back().map_or(seed, |&(i, _)| i);
            let Some(id) = grid.nearest(tail, tol, |id| !used[id / 2] && twin[id / 2] != twin[last]) else {
                break;
            };
            let (p, at_end) = (id / 2, id % 2 == 1);
            used[p] = true;
            seq.push_back((p, at_end));
            if let Some((s, e)) = ends[p] {
                tail = if at_end { s } else { e };
            }
            length += lengths[p];
        }
        // backward from the head
        if !closed {
            loop {
                if closes(head, tail, length) {
                    closed = true;
                    break;
                }
                let first = seq.front().map_or(seed, |&(i, _)| i);
                let Some(id) = grid.nearest(head, tol, |id| !used[id / 2] && twin[id / 2] != twin[first]) else {
                    break;
                };
                let (p, at_end) = (id / 2, id % 2 == 1);
                used[p] = true;
                // met at its end: keeps its direction; met at its start: reversed
                seq.push_front((p, !at_end));
                if let Some((s, e)) = ends[p] {
                    head = if at_end { s } else { e };
                }
                length += lengths[p];
            }
        }

        // nothing left to join: a loop smaller than `2 * tol` still closes
        closed = closed || dist(head, tail) <= tol;

        let seq: Vec<(usize, bool)> = seq.into_iter().collect();
        let contour = join(&pieces, &seq, closed);
        if closed {
            if contour.vertices.len() < 2 {
                continue; // shorter than the tolerance: nothing to keep
            }
            for &(i, _) in &seq {
                in_closed[i] = true;
            }
            out.closed.push((contour, seq.iter().map(|&(i, _)| pieces[i].origin.clone()).collect()));
        } else {
            out.open.push(OpenChain {
                contour,
                origins: seq.iter().map(|&(i, _)| pieces[i].origin.clone()).collect(),
                gaps: Vec::new(),
            });
            open_seqs.push(seq);
        }
    }

    // An open chain made only of repeats of pieces that closed contours use is redundant
    // geometry (an edge drawn twice), not a defect: drop it.
    let mut covered = vec![false; n];
    for i in 0..n {
        if in_closed[i] {
            covered[twin[i]] = true;
        }
    }
    let mut k = 0;
    while k < open_seqs.len() {
        if open_seqs[k].iter().all(|&(i, _)| covered[twin[i]] && !in_closed[i]) {
            open_seqs.remove(k);
            out.open.remove(k);
        } else {
            k += 1;
        }
    }

    report_gaps(&mut out.open, &open_seqs, &pieces);
    out
}

/// Groups the pieces that repeat each other: `twin[i]` is the lowest index of a piece with the
/// same geometry as piece `i` (the same vertices within `tol / 1000` and the same bulges; an open
/// piece also when reversed), `i` itself when there is none. A closed piece that repeats an
/// earlier one is marked as used (dropped). (Within `tol` itself, any two pieces shorter than
/// `tol` would look alike.)
fn twins(
    pieces: &[Piece],
    ends: &[Option<([f64; 2], [f64; 2])>],
    grid: &Grid,
    tol: f64,
    used: &mut [bool],
) -> Vec<usize> {
    let near = tol / 1000.0;
    let same = |a: &Contour, b: &Contour| {
        a.vertices.len() == b.vertices.len()
            && a.vertices
                .iter()
                .zip(&b.vertices)
                .all(|(v, w)| dist([v.x, v.y], [w.x, w.y]) <= near && (v.bulge - w.bulge).abs() <= 1e-9)
    };
    let mut twin: Vec<usize> = (0..pieces.len()).collect();
    // open pieces: candidates are the earlier pieces with an end at this one's start
    for (i, e) in ends.iter().enumerate() {
        let Some((s, _)) = *e else { continue };
        let c = &pieces[i].contour;
        let mut rev: Option<Contour> = None;
        let found = grid.within(s, near).into_iter().find(|&id| {
            let j = id / 2;
            if j >= i || pieces[j].contour.vertices.len() != c.vertices.len() {
                return false;
            }
            if id % 2 == 0 {
                same(&pieces[j].contour, c)
            } else {
                let r = rev.get_or_insert_with(|| {
                    let mut r = c.clone();
                    r.reverse();
                    r
                });
                same(&pieces[j].contour, r)
            }
        });
        if let Some(id) = found {
            twin[i] = twin[id / 2];
        }
    }
    // closed pieces: the same vertices from the same start
    let cell = if tol > 0.0 { tol } else { 1e-6 };
    let mut firsts: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
    for (i, p) in pieces.iter().enumerate() {
        let Some(f) = p.contour.vertices.first().filter(|_| p.contour.closed) else {
            continue;
        };
        let key = ((f.x / cell).round() as i64, (f.y / cell).round() as i64);
        let list = firsts.entry(key).or_default();
        if let Some(&j) = list.iter().find(|&&j| same(&pieces[j].contour, &p.contour)) {
            twin[i] = j;
            used[i] = true;
        } else {
            list.push(i);
        }
    }
    twin
}

impl OpenChain {
    /// One line for the user: its ends, length and first pieces, e.g. `open contour from
    /// (23.000, 109.000) to (83.000, 109.000), 172.0 mm, of LINE at line 2074 and 5 more`.
    pub fn describe(&self) -> String {
        let vs = &self.contour.vertices;
        let (a, b) = match (vs.first(), vs.last()) {
            (Some(a), Some(b)) => ([a.x, a.y], [b.x, b.y]),
            _ => return "an empty open contour".into(),
        };
        let length: f64 = vs.windows(2).map(|w| (w[1].x - w[0].x).hypot(w[1].y - w[0].y)).sum();
        let first = self.origins.first().map(String::as_str).unwrap_or("?");
        let more = match self.origins.len() {
            0 | 1 => String::new(),
            n => format!(" and {} more", n - 1),
        };
        format!(
            "open contour from ({:.3}, {:.3}) to ({:.3}, {:.3}), about {length:.1} mm, of {first}{more}",
            a[0], a[1], b[0], b[1]
        )
    }
}

/// Builds the message for chains left open: `(place, reason)`, e.g.
/// `("near (23.000, 109.000)", "open contour: 2 gaps (3.000 mm between … [LINE at line 812 /
/// LINE at line 830]; …); join the ends or raise the chaining tolerance")`. Coordinates are
/// printed as they are (the readers work in mm). `None` when nothing is open.
pub fn open_contour_message(open: &[OpenChain]) -> Option<(String, String)> {
    let first = open.first()?;
    let mut gaps: Vec<&Gap> = Vec::new();
    for g in open.iter().flat_map(|c| c.gaps.iter()) {
        let same = |h: &&Gap| (h.a == g.a && h.b == g.b) || (h.a == g.b && h.b == g.a);
        if !gaps.iter().any(same) {
            gaps.push(g);
        }
    }
    gaps.sort_by(|p, q| {
        p.distance.total_cmp(&q.distance).then(p.a[0].total_cmp(&q.a[0])).then(p.a[1].total_cmp(&q.a[1]))
    });
    let place = match gaps.first() {
        Some(g) => format!("near {}", pt(g.a)),
        None => match first.contour.vertices.first() {
            Some(v) => format!("near {}", pt([v.x, v.y])),
            None => "drawing".to_string(),
        },
    };
    const SHOWN: usize = 6;
    let mut list: Vec<String> = gaps
        .iter()
        .take(SHOWN)
        .map(|g| {
            // the lower point first, so that a gap reads the same from either side
            let ((p, op), (q, oq)) = if (g.a[0], g.a[1]) <= (g.b[0], g.b[1]) {
                ((g.a, &g.origin_a), (g.b, &g.origin_b))
            } else {
                ((g.b, &g.origin_b), (g.a, &g.origin_a))
            };
            format!("{:.3} mm between {} and {} [{op} / {oq}]", g.distance, pt(p), pt(q))
        })
        .collect();
    if gaps.len() > SHOWN {
        list.push(format!("and {} more", gaps.len() - SHOWN));
    }
    let what = if open.len() == 1 { "open contour".to_string() } else { format!("{} open contours", open.len()) };
    let count = if gaps.len() == 1 { "1 gap".to_string() } else { format!("{} gaps", gaps.len()) };
    let reason = format!("{what}: {count} ({}); join the ends or raise the chaining tolerance", list.join("; "));
    Some((place, reason))
}

fn pt(p: [f64; 2]) -> String {
    format!("({:.3}, {:.3})", p[0], p[1])
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

fn mid(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]
}

/// Joins the oriented pieces of `seq` into one contour, snapping each joint to the midpoint of
/// the two endpoints it joins.
fn join(pieces: &[Piece], seq: &[(usize, bool)], closed: bool) -> Contour {
    let oriented: Vec<Contour> = seq
        .iter()
        .map(|&(i, rev)| {
            let mut c = pieces[i].contour.clone();
            c.closed = false;
            if rev {
                c.reverse();
            }
            c
        })
        .collect();
    let mut verts: Vec<Vertex> = Vec::new();
    let mut prev_last: Option<Vertex> = None;
    for c in &oriented {
        let vs = &c.vertices;
        let count = vs.len().saturating_sub(1); // the last vertex merges into the next joint
        for (j, v) in vs.iter().take(count).enumerate() {
            let mut v = *v;
            if j == 0
                && let Some(p) = prev_last
            {
                let m = mid([p.x, p.y], [v.x, v.y]);
                v.x = m[0];
                v.y = m[1];
            }
            verts.push(v);
        }
        prev_last = vs.last().copied();
    }
    if let Some(last) = prev_last {
        if closed {
            if let Some(first) = verts.first_mut() {
                let m = mid([last.x, last.y], [first.x, first.y]);
                first.x = m[0];
                first.y = m[1];
            }
            if verts.len() == 1 {
                // A single arc closing on itself: make it the full circle through the snapped
                // point, as two half circles, so that the closed contour has two segments.
                let orig = oriented.first().and_then(|c| c.vertices.first()).copied();
                if let Some(o) = orig
                    && let Segment::Arc { center, .. } = Segment::from_bulge([o.x, o.y], [last.x, last.y], o.bulge)
                {
                    let p = verts[0];
                    let b = if o.bulge > 0.0 { 1.0 } else { -1.0 };
                    verts[0].bulge = b;
                    verts.push(Vertex::with_bulge(2.0 * center[0] - p.x, 2.0 * center[1] - p.y, b));
                }
            }
        } else {
            verts.push(Vertex::new(last.x, last.y));
        }
    }
    Contour { vertices: verts, closed }
}

/// Fills in the gaps of the open chains: for each dangling end, the nearest other dangling end.
fn report_gaps(open: &mut [OpenChain], seqs: &[Vec<(usize, bool)>], pieces: &[Piece]) {
    struct End {
        p: [f64; 2],
        chain: usize,
        origin: usize, // piece index
    }
    let mut ends: Vec<End> = Vec::with_capacity(open.len() * 2);
    for (k, (c, seq)) in open.iter().zip(seqs).enumerate() {
        if let (Some(f), Some(l), Some(&(pf, _)), Some(&(pl, _))) =
            (c.contour.vertices.first(), c.contour.vertices.last(), seq.first(), seq.last())
        {
            ends.push(End { p: [f.x, f.y], chain: k, origin: pf });
            ends.push(End { p: [l.x, l.y], chain: k, origin: pl });
        }
    }
    // sweep over the ends sorted by x
    let mut order: Vec<usize> = (0..ends.len()).collect();
    order.sort_by(|&i, &j| ends[i].p[0].total_cmp(&ends[j].p[0]).then(i.cmp(&j)));
    let mut rank = vec![0usize; ends.len()];
    for (r, &i) in order.iter().enumerate() {
        rank[i] = r;
    }
    let mut nearest: Vec<Option<(usize, f64)>> = vec![None; ends.len()];
    for (i, e) in ends.iter().enumerate() {
        let mut best: Option<(usize, f64)> = None;
        let better = |best: &Option<(usize, f64)>, j: usize, d: f64| match *best {
            None => true,
            Some((bj, bd)) => d < bd || (d == bd && j < bj),
        };
        let r = rank[i];
        // to the right
        for &j in order.iter().skip(r + 1) {
            let dx = ends[j].p[0] - e.p[0];
            if let Some((_, bd)) = best
                && dx > bd
            {
                break;
            }
            let d = dist(e.p, ends[j].p);
            if better(&best, j, d) {
                best = Some((j, d));
            }
        }
        // to the left
        for &j in order.iter().take(r).rev() {
            let dx = e.p[0] - ends[j].p[0];
            if let Some((_, bd)) = best
                && dx > bd
            {
                break;
            }
            let d = dist(e.p, ends[j].p);
            if better(&best, j, d) {
                best = Some((j, d));
            }
        }
        nearest[i] = best;
    }
    for (i, e) in ends.iter().enumerate() {
        let Some((j, d)) = nearest[i] else { continue };
        let f = &ends[j];
        let gap = Gap {
            a: e.p,
            b: f.p,
            distance: d,
            origin_a: pieces[e.origin].origin.clone(),
            origin_b: pieces[f.origin].origin.clone(),
        };
        let gaps = &mut open[e.chain].gaps;
        let dup = gaps.iter().any(|g| g.a == gap.b && g.b == gap.a);
        if !dup {
            gaps.push(gap);
        }
    }
}

/// Points (with their ids) in one grid cell.
type Cell = Vec<(usize, [f64; 2])>;

/// A uniform hash grid of points, `cell` wide.
struct Grid {
    cell: f64,
    map: HashMap<(i64, i64), Cell>,
}

impl Grid {
    fn new(cell: f64) -> Self {
        Self { cell, map: HashMap::new() }
    }

    fn key(&self, p: [f64; 2]) -> (i64, i64) {
        // `as` saturates (and maps NaN to 0), so any coordinate is safe here
        ((p[0] / self.cell).floor() as i64, (p[1] / self.cell).floor() as i64)
    }

    fn insert(&mut self, p: [f64; 2], id: usize) {
        let k = self.key(p);
        self.map.entry(k).or_default().push((id, p));
    }

    /// The ids of the points within `tol` of `p`, in ascending order.
    fn within(&self, p: [f64; 2], tol: f64) -> Vec<usize> {
        let mut ids = Vec::new();
        self.visit(p, tol, |id, q| {
            if dist(p, q) <= tol {
                ids.push(id);
            }
        });
        ids.sort_unstable();
        ids
    }

    /// The nearest point within `tol` of `p` whose id passes `ok` (ties: lowest id).
    fn nearest(&self, p: [f64; 2], tol: f64, ok: impl Fn(usize) -> bool) -> Option<usize> {
        let mut best: Option<(f64, usize)> = None;
        self.visit(p, tol, |id, q| {
            if !ok(id) {
                return;
            }
            let d = dist(p, q);
            if d <= tol && best.is_none_or(|(bd, bid)| d < bd || (d == bd && id < bid)) {
                best = Some((d, id));
            }
        });
        best.map(|(_, id)| id)
    }

    /// Calls `f` with every point in the cells that a square of half-width `tol` around `p`
    /// touches (the cells are `tol` wide, so these are at most 3 x 3 cells).
    fn visit(&self, p: [f64; 2], tol: f64, mut f: impl FnMut(usize, [f64; 2])) {
        let lo = self.key([p[0] - tol, p[1] - tol]);
        let hi = self.key([p[0] + tol, p[1] + tol]);
        let mut kx = lo.0;
        loop {
            let mut ky = lo.1;
            loop {
                for &(id, q) in self.map.get(&(kx, ky)).into_iter().flatten() {
                    f(id, q);
                }
                if ky >= hi.1 {
                    break;
                }
                ky = ky.saturating_add(1);
            }
            if kx >= hi.0 {
                break;
            }
            kx = kx.saturating_add(1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn line(a: [f64; 2], b: [f64; 2], origin: &str) -> Piece {
        Piece {
            contour: Contour { vertices: vec![Vertex::new(a[0], a[1]), Vertex::new(b[0], b[1])], closed: false },
            origin: origin.to_string(),
        }
    }

    fn arc(a: [f64; 2], b: [f64; 2], bulge: f64, origin: &str) -> Piece {
        Piece {
            contour: Contour {
                vertices: vec![Vertex::with_bulge(a[0], a[1], bulge), Vertex::new(b[0], b[1])],
                closed: false,
            },
            origin: origin.to_string(),
        }
    }

    #[test]
    fn square_from_reversed_lines_closes() {
        // edges given in scrambled order and directions
        let pieces = vec![
            line([10.0, 0.0], [0.0, 0.0], "a"),
            line([10.0, 10.0], [10.0, 0.0], "b"),
            line([0.0, 10.0], [0.0, 0.0], "c"),
            line([0.0, 10.0], [10.0, 10.0], "d"),
        ];
        let r = chain(pieces, 0.01);
        assert!(r.open.is_empty());
        assert_eq!(r.closed.len(), 1);
        let (c, origins) = &r.closed[0];
        assert!(c.closed);
        assert_eq!(c.vertices.len(), 4);
        assert!((c.signed_area().abs() - 100.0).abs() < 1e-9);
        let mut o = origins.clone();
        o.sort();
        assert_eq!(o, vec!["a", "b", "c", "d"]);
    }

    #[test]
    fn arcs_keep_exact_bulges_after_reversal() {
        // a 20 x 10 slot: two lines and two half circles, one arc given backwards
        let pieces = vec![
            line([0.0, 0.0], [20.0, 0.0], "bottom"),
            arc([20.0, 10.0], [20.0, 0.0], -1.0, "right arc reversed"), // cw from top to bottom
            line([20.0, 10.0], [0.0, 10.0], "top"),
            arc([0.0, 10.0], [0.0, 0.0], 1.0, "left arc"),
        ];
        let r = chain(pieces, 0.01);
        assert!(r.open.is_empty(), "{:?}", r.open);
        assert_eq!(r.closed.len(), 1);
        let c = &r.closed[0].0;
        let expected = 20.0 * 10.0 + PI * 25.0;
        assert!((c.signed_area() - expected).abs() < 1e-9, "area {} vs {}", c.signed_area(), expected);
        let bulges: Vec<f64> = c.vertices.iter().map(|v| v.bulge).collect();
        assert_eq!(bulges.iter().filter(|b| **b == 1.0).count(), 2, "{bulges:?}");
        assert!((c.length() - (40.0 + 10.0 * PI)).abs() < 1e-9);
    }

    #[test]
    fn joints_snap_to_midpoints_within_tolerance() {
        let pieces = vec![
            line([0.0, 0.0], [10.0, 0.004], "a"),
            line([10.0, -0.004], [10.0, 10.0], "b"),
            line([10.0, 10.0], [0.0, 0.006], "c"),
        ];
        let r = chain(pieces, 0.01);
        assert_eq!(r.closed.len(), 1);
        let c = &r.closed[0].0;
        assert_eq!(c.vertices.len(), 3);
        assert!(c.vertices.iter().any(|v| v.x == 10.0 && v.y == 0.0));
        assert!(c.vertices.iter().any(|v| v.x == 0.0 && v.y == 0.003));
        // too far apart at 0.005
        let pieces = vec![line([0.0, 0.0], [10.0, 0.0], "a"), line([10.0, 0.02], [0.0, 0.0], "b")];
        let r = chain(pieces, 0.005);
        assert!(r.closed.is_empty());
        assert_eq!(r.open.len(), 1);
    }

    #[test]
    fn gaps_report_nearest_dangling_ends() {
        // a U and a smaller U inside it, both open at y = 109: gaps of 3 mm at each side
        let pieces = vec![
            line([23.0, 109.0], [23.0, 130.0], "outer left"),
            line([23.0, 130.0], [83.0, 130.0], "outer top"),
            line([83.0, 130.0], [83.0, 109.0], "outer right"),
            line([26.0, 109.0], [26.0, 127.0], "inner left"),
            line([26.0, 127.0], [80.0, 127.0], "inner top"),
            line([80.0, 127.0], [80.0, 109.0], "inner right"),
        ];
        let r = chain(pieces, 0.01);
        assert!(r.closed.is_empty());
        assert_eq!(r.open.len(), 2);
        for oc in &r.open {
            assert_eq!(oc.gaps.len(), 2);
            for g in &oc.gaps {
                assert!((g.distance - 3.0).abs() < 1e-12, "{g:?}");
                assert_eq!(g.a[1], 109.0);
                assert_eq!(g.b[1], 109.0);
            }
        }
        let g0 = &r.open[0].gaps[0];
        assert_eq!(g0.a, [23.0, 109.0]);
        assert_eq!(g0.b, [26.0, 109.0]);
        assert_eq!(g0.origin_a, "outer left");
        assert_eq!(g0.origin_b, "inner left");
        let (place, reason) = open_contour_message(&r.open).expect("message");
        assert_eq!(place, "near (23.000, 109.000)");
        assert!(reason.starts_with("2 open contours: 2 gaps (3.000 mm between (23.000, 109.000) and (26.000, 109.000) [outer left / inner left]; 3.000 mm between (80.000, 109.000) and (83.000, 109.000)"), "{reason}");
        assert!(reason.ends_with("join the ends or raise the chaining tolerance"));
    }

    #[test]
    fn nearly_closed_chain_reports_its_own_gap() {
        let pieces = vec![
            line([0.0, 0.0], [10.0, 0.0], "a"),
            line([10.0, 0.0], [10.0, 10.0], "b"),
            line([10.0, 10.0], [0.0, 0.5], "c"),
        ];
        let r = chain(pieces, 0.01);
        assert_eq!(r.open.len(), 1);
        let gaps = &r.open[0].gaps;
        assert_eq!(gaps.len(), 1, "both ends name the same gap: {gaps:?}");
        assert!((gaps[0].distance - 0.5).abs() < 1e-12);
        assert!(open_contour_message(&r.open).is_some_and(|(_, m)| m.starts_with("open contour: 1 gap (0.500 mm")));
        assert!(open_contour_message(&[]).is_none());
    }

    #[test]
    fn closed_pieces_pass_through_in_order() {
        let circle = Piece { contour: Contour::circle(0.0, 0.0, 5.0), origin: "CIRCLE".into() };
        let square = Piece {
            contour: Contour::polygon(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]),
            origin: "LWPOLYLINE".into(),
        };
        let pieces = vec![
            circle.clone(),
            line([0.0, 0.0], [1.0, 0.0], "l1"),
            square.clone(),
            line([1.0, 0.0], [0.0, 1.0], "l2"),
            line([0.0, 1.0], [0.0, 0.0], "l3"),
        ];
        let r = chain(pieces, 0.01);
        assert_eq!(r.closed.len(), 3);
        assert_eq!(r.closed[0], (circle.contour, vec!["CIRCLE".to_string()]));
        assert_eq!(r.closed[1].1, vec!["l1", "l2", "l3"]);
        assert_eq!(r.closed[2], (square.contour, vec!["LWPOLYLINE".to_string()]));
    }

    #[test]
    fn open_polyline_with_coincident_ends_closes() {
        let p = Piece {
            contour: Contour {
                vertices: vec![
                    Vertex::new(0.0, 0.0),
                    Vertex::new(4.0, 0.0),
                    Vertex::with_bulge(4.0, 3.0, 0.3),
                    Vertex::new(0.0, 0.0),
                ],
                closed: false,
            },
            origin: "LWPOLYLINE".into(),
        };
        let r = chain(vec![p], 0.01);
        assert_eq!(r.closed.len(), 1);
        let c = &r.closed[0].0;
        assert_eq!(c.vertices.len(), 3);
        assert_eq!(c.vertices[2].bulge, 0.3);
    }

    #[test]
    fn single_arc_closing_on_itself_gets_two_segments() {
        // an arc of almost 360 degrees whose ends are 0.001 apart
        let r = 5.0;
        let sweep = 2.0 * PI - 0.001 / r;
        let b = [r * sweep.cos(), r * sweep.sin()];
        let p = arc([r, 0.0], b, (sweep / 4.0).tan(), "ARC");
        let out = chain(vec![p], 0.01);
        assert_eq!(out.closed.len(), 1);
        let c = &out.closed[0].0;
        assert_eq!(c.vertices.len(), 2);
        assert!((c.signed_area() - PI * r * r).abs() < 0.01, "{}", c.signed_area());
    }

    #[test]
    fn branching_point_does_not_panic_and_is_deterministic() {
        // two squares sharing the corner (10, 10), plus a stray line ending there
        let sq = |x: f64, y: f64, tag: &str| {
            vec![
                line([x, y], [x + 10.0, y], &format!("{tag}1")),
                line([x + 10.0, y], [x + 10.0, y + 10.0], &format!("{tag}2")),
                line([x + 10.0, y + 10.0], [x, y + 10.0], &format!("{tag}3")),
                line([x, y + 10.0], [x, y], &format!("{tag}4")),
            ]
        };
        let mut pieces = sq(0.0, 0.0, "a");
        pieces.extend(sq(10.0, 10.0, "b"));
        pieces.push(line([10.0, 10.0], [30.0, 0.0], "stray"));
        let r1 = chain(pieces.clone(), 0.01);
        let r2 = chain(pieces, 0.01);
        assert_eq!(r1, r2);
        assert_eq!(r1.closed.len(), 2);
        for (c, _) in &r1.closed {
            assert!((c.signed_area().abs() - 100.0).abs() < 1e-9);
        }
        assert_eq!(r1.open.len(), 1);
        assert_eq!(r1.open[0].origins, vec!["stray"]);
    }

    #[test]
    fn degenerate_input_does_not_panic() {
        let pieces = vec![
            Piece { contour: Contour::default(), origin: "empty".into() },
            Piece { contour: Contour { vertices: vec![Vertex::new(1.0, 1.0)], closed: false }, origin: "dot".into() },
            line([f64::NAN, 0.0], [1.0, f64::INFINITY], "nan"),
            line([0.0, 0.0], [0.001, 0.0], "tiny"),
        ];
        for tol in [0.01, 0.0, -1.0, f64::NAN, f64::INFINITY] {
            let r = chain(pieces.clone(), tol);
            assert!(r.closed.is_empty(), "tol {tol}: {:?}", r.closed);
        }
    }

    #[test]
    fn duplicate_pieces_are_dropped() {
        // the bottom edge drawn twice (once reversed), and the circle twice
        let pieces = vec![
            line([0.0, 0.0], [10.0, 0.0], "bottom"),
            line([10.0, 0.0], [0.0, 0.0], "bottom again"),
            line([10.0, 0.0], [10.0, 10.0], "right"),
            line([10.0, 10.0], [0.0, 10.0], "top"),
            line([0.0, 10.0], [0.0, 0.0], "left"),
            Piece { contour: Contour::circle(5.0, 5.0, 1.0), origin: "hole".into() },
            Piece { contour: Contour::circle(5.0, 5.0, 1.0), origin: "hole again".into() },
        ];
        let r = chain(pieces, 0.01);
        assert!(r.open.is_empty(), "{:?}", r.open);
        assert_eq!(r.closed.len(), 2);
        assert!((r.closed[0].0.signed_area().abs() - 100.0).abs() < 1e-9);
        assert_eq!(r.closed[0].1, vec!["bottom", "right", "top", "left"]);
        assert_eq!(r.closed[1].1, vec!["hole"]);
        // two squares sharing an edge, each drawn with its own copy of it: both close
        let pieces = vec![
            line([0.0, 0.0], [10.0, 0.0], "a1"),
            line([10.0, 0.0], [10.0, 10.0], "shared"),
            line([10.0, 10.0], [0.0, 10.0], "a3"),
            line([0.0, 10.0], [0.0, 0.0], "a4"),
            line([10.0, 10.0], [10.0, 0.0], "shared again"),
            line([10.0, 0.0], [20.0, 0.0], "b2"),
            line([20.0, 0.0], [20.0, 10.0], "b3"),
            line([20.0, 10.0], [10.0, 10.0], "b4"),
        ];
        let r = chain(pieces, 0.01);
        assert!(r.open.is_empty(), "{:?}", r.open);
        assert_eq!(r.closed.len(), 2);
        for (c, _) in &r.closed {
            assert!((c.signed_area().abs() - 100.0).abs() < 1e-9);
        }
        // two different arcs between the same points are not duplicates
        let pieces = vec![arc([1.0, 0.0], [-1.0, 0.0], 1.0, "upper"), arc([1.0, 0.0], [-1.0, 0.0], -1.0, "lower")];
        let r = chain(pieces, 0.01);
        assert_eq!(r.closed.len(), 1);
        assert!((r.closed[0].0.signed_area().abs() - PI).abs() < 1e-9);
    }

    #[test]
    fn loops_smaller_than_the_tolerance_close_or_vanish() {
        // a 0.004 mm triangle with tolerance 0.01: closes (nothing else to join)
        let pieces = vec![
            line([0.0, 0.0], [0.004, 0.0], "a"),
            line([0.004, 0.0], [0.0, 0.004], "b"),
            line([0.0, 0.004], [0.0, 0.0], "c"),
        ];
        let r = chain(pieces, 0.01);
        assert!(r.open.is_empty());
        assert_eq!(r.closed.len(), 1);
        // a lone line shorter than the tolerance leaves nothing
        let r = chain(vec![line([0.0, 0.0], [0.004, 0.0], "tiny")], 0.01);
        assert!(r.open.is_empty() && r.closed.is_empty());
        // but a tiny first piece does not stop a real loop from forming
        let pieces = vec![
            line([0.0, 0.0], [0.004, 0.0], "tiny"),
            line([0.004, 0.0], [10.0, 0.0], "a"),
            line([10.0, 0.0], [10.0, 10.0], "b"),
            line([10.0, 10.0], [0.0, 0.0], "c"),
        ];
        let r = chain(pieces, 0.01);
        assert_eq!(r.closed.len(), 1);
        assert_eq!(r.closed[0].1.len(), 4);
        assert!((r.closed[0].0.signed_area().abs() - 50.0).abs() < 1e-9);
    }

    #[test]
    fn many_pieces_chain_fast() {
        // 40 000 lines forming 10 000 unit squares, shuffled and half of them reversed
        let mut pieces = Vec::new();
        for k in 0..10_000 {
            let x = (k % 100) as f64 * 2.0;
            let y = (k / 100) as f64 * 2.0;
            let c = [[x, y], [x + 1.0, y], [x + 1.0, y + 1.0], [x, y + 1.0]];
            for i in 0..4 {
                let (a, b) = (c[i], c[(i + 1) % 4]);
                let p = if (k + i) % 2 == 0 { line(a, b, "l") } else { line(b, a, "l") };
                pieces.push(p);
            }
        }
        // deterministic shuffle
        let mut state: u64 = 12345;
        for i in (1..pieces.len()).rev() {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let j = (state >> 33) as usize % (i + 1);
            pieces.swap(i, j);
        }
        let t = std::time::Instant::now();
        let r = chain(pieces, 0.01);
        let elapsed = t.elapsed();
        assert_eq!(r.closed.len(), 10_000);
        assert!(r.open.is_empty());
        assert!(r.closed.iter().all(|(c, _)| (c.signed_area().abs() - 1.0).abs() < 1e-12));
        assert!(elapsed.as_secs_f64() < 5.0, "took {elapsed:?}");
    }
}
