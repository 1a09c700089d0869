//! Direction-parallel (zigzag) clearing: rows at a settable angle, spaced by the stepover,
//! clipped to where the tool centre may go; consecutive rows are joined along the boundary
//! (so the tool stays down), and a contour along the walls at the first offset finishes the
//! level. Row directions alternate (that is what zigzag means), so climb and conventional
//! alternate on the rows; the wall contour keeps the chosen milling direction.

use super::{Clearing, Context, Program};
use crate::error::{Error, Result, Setting};
use crate::geom::{DVec2, polyline_length};
use crate::plan::{LayerGeom, Pass, PassKind};

/// The zigzag strategy's options.
#[derive(Debug, Clone, PartialEq)]
pub struct ZigzagOptions {
    /// The row angle, degrees from +X.
    pub angle_deg: f64,
}

impl ZigzagOptions {
    /// Rows along X.
    pub const DEFAULT: ZigzagOptions = ZigzagOptions { angle_deg: 0.0 };
}

impl Default for ZigzagOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

impl Clearing for ZigzagOptions {
    const NAME: &'static str = "zigzag";

    fn validate(&self) -> Result<()> {
        if !self.angle_deg.is_finite() {
            return Err(Error::setting(Setting::ZigzagAngle, format!("{}: must be a number", self.angle_deg)));
        }
        Ok(())
    }

    fn plan(&self, cx: &Context) -> Result<Option<Program>> {
        super::same_passes(cx, passes(cx.geom, cx.link.climb, self.angle_deg))
    }
}

/// Zigzag passes for one level: rows at `angle_deg` from +X, the wall contour for climb milling
/// or conventional.
pub fn passes(g: &LayerGeom, climb: bool, angle_deg: f64) -> Vec<Pass> {
    let mut out = Vec::new();
    let Some((lo, hi)) = g.centres.bounds() else { return out };
    let ang = angle_deg.to_radians();
    let (u, v) = (DVec2::new(ang.cos(), ang.sin()), DVec2::new(-ang.sin(), ang.cos()));
    // extent of the region across the rows
    let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
    let (mut vmin, mut vmax, mut umin, mut umax) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for c in corners {
        vmin = vmin.min(c.dot(v));
        vmax = vmax.max(c.dot(v));
        umin = umin.min(c.dot(u));
        umax = umax.max(c.dot(u));
    }
    // rows that never overlap the material by half a stepover only graze it (slivers of the
    // centre region beside round corners, along free edges): the wall contour or the
    // neighbouring rows clear what they would
    let strong = g.centres.intersection(&g.regions.material.offset(g.r - 0.5 * g.step, crate::model::REGION_TOL));
    let span = vmax - vmin;
    let n = (span / g.step).ceil().max(1.0) as usize;
    let gap = span / n as f64;
    // rows: segments of each line inside the centre region, sorted along u
    let mut rows: Vec<Vec<(DVec2, DVec2)>> = Vec::with_capacity(n);
    for k in 0..n {
        let vv = vmin + (k as f64 + 0.5) * gap;
        let a = u * (umin - 1.0) + v * vv;
        let b = u * (umax + 1.0) + v * vv;
        let mut segs: Vec<(DVec2, DVec2)> = g
            .centres
            .clip_polyline(&[a, b])
            .into_iter()
            .filter(|p| p.len() >= 2)
            .map(|p| {
                let (s, e) = (p[0], p[p.len() - 1]);
                if (e - s).dot(u) >= 0.0 { (s, e) } else { (e, s) }
            })
            .filter(|(s, e)| (*e - *s).length() > 1e-6)
            .filter(|(s, e)| strong.clip_polyline(&[*s, *e]).iter().any(|p| polyline_length(p) > 1e-3))
            .collect();
        segs.sort_by(|x, y| x.0.dot(u).total_cmp(&y.0.dot(u)));
        rows.push(segs);
    }
    // boustrophedon chains: follow overlapping segments row to row
    let mut used: Vec<Vec<bool>> = rows.iter().map(|r| vec![false; r.len()]).collect();
    let mut cur = lo;
    loop {
        // the unused segment nearest the current position starts a chain
        let mut best: Option<(usize, usize, f64, bool)> = None;
        for (ri, row) in rows.iter().enumerate() {
            for (si, (s, e)) in row.iter().enumerate() {
                if used[ri][si] {
                    continue;
                }
                for (p, fwd) in [(*s, true), (*e, false)] {
                    let d = (p - cur).length();
                    if best.is_none_or(|b| d < b.2) {
                        best = Some((ri, si, d, fwd));
                    }
                }
            }
        }
        let Some((mut ri, mut si, _, mut fwd)) = best else { break };
        let mut chain: Vec<DVec2> = Vec::new();
        let mut dir_up: Option<bool> = None;
        loop {
            used[ri][si] = true;
            let (s, e) = rows[ri][si];
            let (a, b) = if fwd { (s, e) } else { (e, s) };
            if let Some(last) = chain.last().copied() {
                chain.extend(boundary_link(g, last, a).unwrap_or_default());
            }
            chain.push(a);
            chain.push(b);
            // next row: an unused segment overlapping this one whose near end joins ours along
            // the boundary (or straight)
            let mut next = None;
            let limit = (3.0 * gap).max(2.0 * g.r);
            for up in [true, false] {
                if dir_up.is_some_and(|d| d != up) {
                    continue;
                }
                let nr = if up { ri + 1 } else { ri.wrapping_sub(1) };
                if nr >= rows.len() {
                    continue;
                }
                let (lo_u, hi_u) = (s.dot(u).min(e.dot(u)), s.dot(u).max(e.dot(u)));
                let mut cand: Option<(usize, f64, Vec<DVec2>)> = None;
                for (sj, (s2, e2)) in rows[nr].iter().enumerate() {
                    if used[nr][sj] {
                        continue;
                    }
                    let (l2, h2) = (s2.dot(u), e2.dot(u));
                    if h2 < lo_u || l2 > hi_u {
                        continue;
                    }
                    // the next row runs the other way: it starts at its end nearest ours
                    let a2 = if fwd { *e2 } else { *s2 };
                    if let Some(link) = boundary_link(g, b, a2) {
                        let l = polyline_length(&[vec![b], link.clone(), vec![a2]].concat());
                        if l <= limit && cand.as_ref().is_none_or(|c| l < c.1) {
                            cand = Some((sj, l, link));
                        }
                    }
                }
                if let Some((sj, _, _)) = cand {
                    next = Some((nr, sj, up));
                    break;
                }
            }
            match next {
                Some((nr, sj, up)) => {
                    dir_up = Some(up);
                    ri = nr;
                    si = sj;
                    fwd = !fwd;
                }
                None => break,
            }
        }
        cur = *chain.last().unwrap_or(&cur);
        if polyline_length(&chain) > 1e-6 {
            out.push(Pass { pts: chain, closed: false, kind: PassKind::Clear, level: f64::INFINITY, reversible: true });
        }
    }
    // the wall contour
    let toward_walls = true;
    out.extend(super::offset::level_passes(&g.keep, g.wall_level, &g.touch, climb, toward_walls, PassKind::Contour));
    out
}

/// Points to go from `a` (end of a row) to `b` (start of the next): nothing extra when the
/// straight step stays in the centre region, otherwise along the region's boundary; `None`
/// when the two points are not on one boundary ring.
fn boundary_link(g: &LayerGeom, a: DVec2, b: DVec2) -> Option<Vec<DVec2>> {
    let mid = (a + b) / 2.0;
    let straight_ok = g.centres.contains(mid) && g.centres.holds_segment(a, b, 1e-6);
    if straight_ok {
        return Some(Vec::new());
    }
    // walk the boundary ring nearest to both points, the shorter way
    let mut best: Option<(f64, Vec<DVec2>)> = None;
    for ring in g.centres.rings() {
        let (ia, ta, da) = locate(ring, a);
        let (ib, tb, db) = locate(ring, b);
        if da > 1e-3 || db > 1e-3 {
            continue;
        }
        let n = ring.len();
        let mut fwd = Vec::new();
        if !(ia == ib && tb >= ta) {
            let mut i = ia;
            loop {
                i = (i + 1) % n;
                fwd.push(ring[i]);
                if i == ib {
                    break;
                }
            }
        }
        let mut back = Vec::new();
        if !(ia == ib && tb <= ta) {
            let mut i = ia;
            loop {
                back.push(ring[i]);
                if i == (ib + 1) % n {
                    break;
                }
                i = (i + n - 1) % n;
            }
        }
        let lf = polyline_length(&[vec![a], fwd.clone(), vec![b]].concat());
        let lb = polyline_length(&[vec![a], back.clone(), vec![b]].concat());
        let (l, p) = if lf <= lb { (lf, fwd) } else { (lb, back) };
        if best.as_ref().is_none_or(|x| l < x.0) {
            best = Some((l, p));
        }
    }
    best.map(|b| b.1)
}

/// Segment index, parameter and distance of the point of `ring` nearest to `p`.
fn locate(ring: &[DVec2], p: DVec2) -> (usize, f64, f64) {
    let n = ring.len();
    let mut best = (0, 0.0, f64::INFINITY);
    for i in 0..n {
        let a = ring[i];
        let b = ring[(i + 1) % n];
        let t = crate::geom::closest_param(p, a, b);
        let d = (a + (b - a) * t - p).length();
        if d < best.2 {
            best = (i, t, d);
        }
    }
    best
}
