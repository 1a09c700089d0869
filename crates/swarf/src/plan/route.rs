//! Keep-tool-down routing: a way at depth from where the tool is to where the next pass starts,
//! around the material that stands on the straight way, through space the tool has cleared.
//!
//! The search is A* (Hart, Nilsson & Raphael, 1968) on a square lattice of spacing `h` anchored
//! at the start, eight neighbours per node, with the straight distance to the goal as the
//! heuristic (admissible, so the way found is the shortest on the lattice). The caller says
//! which nodes the tool may stand on — with a reach of `h·√2 / 2` beyond the tool, so that the
//! tool is also clear between two neighbours — how the tool may leave its start (it still touches
//! the material it has just cut) and which straight legs are clear. Nodes whose way cannot be
//! shorter than `budget` (the cost of lifting over, as a length at the rapid rate) are not
//! expanded: the search explores an ellipse around the straight way, not the whole pocket. The
//! lattice way is then shortened by taking, from each waypoint, the farthest later one that a
//! clear straight leg reaches ("string pulling").
//!
//! Written here rather than with the `pathfinding` crate's `astar`: that one neither stops at a
//! cost budget nor after a number of expanded nodes (its successor function does not see the
//! cost so far), so a way that does not exist would explore the whole pocket before it gives up.

use crate::geom::DVec2;
use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

/// A node waiting in the open set, ordered by `f` (smallest first), then by insertion order
/// (deterministic).
#[derive(PartialEq)]
struct Open {
    f: f64,
    seq: u64,
    node: (i32, i32),
}

impl Eq for Open {}

impl Ord for Open {
    fn cmp(&self, o: &Self) -> Ordering {
        o.f.total_cmp(&self.f).then_with(|| o.seq.cmp(&self.seq))
    }
}

impl PartialOrd for Open {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// The goal's key in the search (no lattice node has it).
const GOAL: (i32, i32) = (i32::MIN, i32::MIN);

/// A way from `a` to `b` no longer than `budget`: its waypoints after `a`, ending with `b`.
///
/// - `node_ok(p)`: the tool may stand at lattice point `p` (clear within its reach plus
///   `h·√2 / 2`);
/// - `leave_ok(p)`: the straight leg from `a` to `p` is clear (the tool leaves what it touches);
/// - `leg_ok(p, q)`: the straight leg from `p` to `q` is clear.
///
/// At most `max_nodes` nodes are expanded; `None` when no way within the budget is found.
// (the three tests are what the caller knows of its material model: one closure each)
#[allow(clippy::too_many_arguments)]
pub fn route(
    a: DVec2,
    b: DVec2,
    h: f64,
    budget: f64,
    max_nodes: usize,
    mut node_ok: impl FnMut(DVec2) -> bool,
    mut leave_ok: impl FnMut(DVec2) -> bool,
    mut leg_ok: impl FnMut(DVec2, DVec2) -> bool,
) -> Option<Vec<DVec2>> {
    if h.is_nan() || h <= 0.0 || (b - a).length() > budget {
        return None;
    }
    let at = |n: (i32, i32)| a + h * DVec2::new(n.0 as f64, n.1 as f64);
    let mut ok: HashMap<(i32, i32), bool> = HashMap::new();
    let mut g: HashMap<(i32, i32), f64> = HashMap::new();
    let mut came: HashMap<(i32, i32), (i32, i32)> = HashMap::new();
    let mut open = BinaryHeap::new();
    let mut seq = 0u64;
    // the start: nodes within two spacings that the tool can reach leaving its place
    for j in -2..=2 {
        for i in -2..=2 {
            let n = (i, j);
            let p = at(n);
            if (i, j) == (0, 0) || !node_ok(p) || !leave_ok(p) {
                continue;
            }
            ok.insert(n, true);
            let gn = (p - a).length();
            g.insert(n, gn);
            open.push(Open { f: gn + (b - p).length(), seq, node: n });
            seq += 1;
        }
    }
    let near_goal = 2.0 * h * std::f64::consts::SQRT_2 + 1e-9;
    let mut expanded = 0usize;
    while let Some(Open { f, node, .. }) = open.pop() {
        if f > budget {
            return None;
        }
        if node == GOAL {
            break;
        }
        let gn = g[&node];
        expanded += 1;
        if expanded > max_nodes {
            return None;
        }
        let p = at(node);
        if (b - p).length() <= near_goal && leg_ok(p, b) {
            let gb = gn + (b - p).length();
            if g.get(&GOAL).is_none_or(|&x| gb < x) {
                g.insert(GOAL, gb);
                came.insert(GOAL, node);
                open.push(Open { f: gb, seq, node: GOAL });
                seq += 1;
            }
        }
        for (di, dj) in [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)] {
            let m = (node.0 + di, node.1 + dj);
            let q = at(m);
            let gm = gn + if di != 0 && dj != 0 { h * std::f64::consts::SQRT_2 } else { h };
            if gm + (b - q).length() > budget || g.get(&m).is_some_and(|&x| x <= gm) {
                continue;
            }
            if !*ok.entry(m).or_insert_with(|| node_ok(q)) {
                continue;
            }
            g.insert(m, gm);
            came.insert(m, node);
            open.push(Open { f: gm + (b - q).length(), seq, node: m });
            seq += 1;
        }
    }
    // the lattice way, start to goal
    let mut nodes = vec![GOAL];
    let mut n = *came.get(&GOAL)?;
    loop {
        nodes.push(n);
        match came.get(&n) {
            Some(&m) => n = m,
            None => break,
        }
    }
    nodes.reverse();
    let pts: Vec<DVec2> = nodes.iter().map(|&n| if n == GOAL { b } else { at(n) }).collect();
    // string pulling: from each waypoint the farthest one a straight leg reaches; every leg taken
    // is checked (a way with a leg that is not clear is refused)
    let mut out = Vec::new();
    let mut i: Option<usize> = None; // None: at `a`
    while i != Some(pts.len() - 1) {
        let from = i.map_or(0, |k| k + 1);
        let mut j = pts.len() - 1;
        loop {
            let fine = match i {
                None => leave_ok(pts[j]),
                Some(k) => leg_ok(pts[k], pts[j]),
            };
            if fine {
                break;
            }
            if j == from {
                return None;
            }
            j -= 1;
        }
        out.push(pts[j]);
        i = Some(j);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Material: a wall across x = 0 from y = −5 to 5, reached within `reach`.
    fn wall_clear(p: DVec2, reach: f64) -> bool {
        let q = DVec2::new(0.0, p.y.clamp(-5.0, 5.0));
        (p - q).length() > reach
    }

    /// Is the segment clear of the wall (sampled finely)?
    fn seg_clear(p: DVec2, q: DVec2, reach: f64) -> bool {
        (0..=200).all(|k| wall_clear(p + (q - p) * (k as f64 / 200.0), reach))
    }

    #[test]
    fn goes_round_a_wall_and_pulls_the_string_tight() {
        let (a, b) = (DVec2::new(-3.0, 0.0), DVec2::new(3.0, 0.0));
        let h = 0.5;
        let r = 1.0;
        let w = route(
            a,
            b,
            h,
            100.0,
            100_000,
            |p| wall_clear(p, r + h * 0.75),
            |p| seg_clear(a, p, r),
            |p, q| seg_clear(p, q, r),
        )
        .expect("a way round the wall");
        assert_eq!(*w.last().unwrap(), b);
        // every leg clear of the wall
        let mut prev = a;
        for p in &w {
            assert!(seg_clear(prev, *p, r), "leg {prev:?} -> {p:?} touches the wall");
            prev = *p;
        }
        // round the end of the wall (|y| >= 6), and not much longer than the shortest way
        // (over the end at y = 6: 2·√(3² + 6²) = 13.4; the nodes keep a quarter more clearance
        // and stand on the lattice)
        let len: f64 = std::iter::once(a)
            .chain(w.iter().copied())
            .collect::<Vec<_>>()
            .windows(2)
            .map(|s| (s[1] - s[0]).length())
            .sum();
        assert!(w.iter().any(|p| p.y.abs() >= 6.0 - 1e-9));
        assert!(len < 1.15 * 13.4, "way {len} mm: {w:?}");
        assert!(w.len() <= 4, "string not pulled: {w:?}");
    }

    #[test]
    fn gives_up_beyond_the_budget() {
        let (a, b) = (DVec2::new(-3.0, 0.0), DVec2::new(3.0, 0.0));
        let w = route(
            a,
            b,
            0.5,
            10.0,
            100_000,
            |p| wall_clear(p, 1.4),
            |p| seg_clear(a, p, 1.0),
            |p, q| seg_clear(p, q, 1.0),
        );
        assert!(w.is_none());
    }
}
