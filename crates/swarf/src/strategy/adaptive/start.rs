//! Where a pass starts (paper 1 §4.5), in the paper's order: a resume point where contouring
//! gave way, a lateral entry tangent to the stock from free or cleared space, a helix at the
//! farthest point from the walls, a ramp where no helix fits, a plunge as the last resort.

use super::engine::{Engine, Start};
use super::{AIR_DEG, HELIX_MIN_SHARE};
use crate::geom::DVec2;
use crate::plan::{LANDING_MARGIN, Material};
use crate::sim::edt;
use crate::sim::sweep::Path;
use std::f64::consts::{FRAC_PI_2, TAU};

/// Half the width, in blocks, of the first window the lateral starts are looked for in.
const LATERAL_WINDOW: usize = 24;

/// The 128 unit directions `τk/128` the material is looked for along (once: their sines and
/// cosines were a fifth of the lateral search).
static RING_128: std::sync::LazyLock<Vec<DVec2>> = std::sync::LazyLock::new(|| {
    (0..128)
        .map(|k| {
            let a = TAU * k as f64 / 128.0;
            DVec2::new(a.cos(), a.sin())
        })
        .collect()
});

impl<'a, 'b, M: Material> Engine<'a, 'b, M> {
    // ---- starting points -------------------------------------------------------------------

    pub(super) fn find_start(&mut self) -> Option<Start> {
        // 1. resume points, last first
        while let Some(rp) = self.resume.pop() {
            let (p, t) = self.c.walls.at(rp.ring, rp.s);
            // a resume point that gave nothing before
            if self.failed.iter().any(|f| (*f - p).length() < 0.5 * self.c.step) {
                continue;
            }
            let t = t * rp.dir;
            let (ahead, _) = self.c.walls.at(rp.ring, rp.s + rp.dir * self.c.step);
            let e = self.l.sim.front_engagement(ahead, self.z, t);
            // nothing left there, or still too heavy to follow the wall: drop it
            if e > self.c.theta + self.switch_slack()
                || (e < AIR_DEG && self.l.sim.front_engagement(p + t * self.c.r, self.z, t) < AIR_DEG)
            {
                continue;
            }
            // land behind it, where the contour is already cut
            let mut back = self.c.step;
            while back < 6.0 * self.c.r {
                let (q, _) = self.c.walls.at(rp.ring, rp.s - rp.dir * back);
                if self.clear(q) {
                    return Some(Start::Resume { ring: rp.ring, s: rp.s, dir: rp.dir, land: back });
                }
                back += self.c.step;
            }
        }
        // 2. lateral entry tangent to the stock from free or cleared space
        // (the nearest 64 candidates first; all of them before a helix)
        if let Some((at, from, dir)) = self.lateral(64).or_else(|| self.lateral(usize::MAX)) {
            return Some(Start::Lateral { at, from, dir });
        }
        // 3. helix at the farthest point from the walls that has material, 4. plunge
        let (c, d) = self.deepest()?;
        // not for a few slivers within the tool's reach there (the clean-up takes them)
        if self.l.sim.material_area_near(c, self.z, 2.0 * self.c.r)
            < HELIX_MIN_SHARE * std::f64::consts::PI * self.c.r * self.c.r
        {
            return None;
        }
        // the grid's distance is good to a cell: measure exactly at the chosen centre
        let d = d.min(self.l.sim.keep_distance(&Path::Line { a: c.extend(0.0), b: c.extend(0.0) }, d + 1.0));
        let room = d - self.c.r - self.c.margin - 0.005;
        let rh = (self.l.link.helix_radius_frac * self.c.r).min(room);
        if rh >= self.l.link.helix_min_frac * self.c.r {
            Some(Start::Helix { c, r: rh })
        } else if room >= 0.0 {
            Some(match self.ramp_line(c) {
                Some(to) => Start::Ramp { c, to },
                None => Start::Plunge { c },
            })
        } else {
            None
        }
    }

    /// Where a straight ramp from `c` can run, for a start with no room for a helix (a channel
    /// about as wide as the tool): the far end of the longest straight way from `c`, among 24
    /// headings, along which the tool stays clear of the walls (by the margin), up to three
    /// diameters; none shorter than half a diameter (or 1 mm).
    pub(super) fn ramp_line(&self, c: DVec2) -> Option<DVec2> {
        let need = self.c.r + self.c.margin + 0.005;
        let max = 6.0 * self.c.r;
        let min = self.c.r.max(1.0);
        let clear =
            |b: DVec2| self.l.sim.keep_distance(&Path::Line { a: c.extend(0.0), b: b.extend(0.0) }, need + 1.0) >= need;
        let mut best: Option<(f64, DVec2)> = None;
        for k in 0..24 {
            let a = std::f64::consts::TAU * k as f64 / 24.0;
            let u = DVec2::new(a.cos(), a.sin());
            // longest clear length by bisection over [0, max]
            let (mut lo, mut hi) = (0.0, max);
            if clear(c + u * max) {
                lo = max;
            } else {
                for _ in 0..12 {
                    let mid = 0.5 * (lo + hi);
                    if clear(c + u * mid) {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
            }
            if lo >= min && best.is_none_or(|(l, _)| lo > l + 1e-9) {
                best = Some((lo, c + u * lo));
            }
        }
        best.map(|(_, to)| to)
    }

    /// No material within the tool (plus the landing margin) at `p`. The model's cells are
    /// cut by their centres, so a cell counted as cut can still hold material up to half a
    /// cell from its centre: the test reaches one and a half cells further.
    pub(super) fn clear(&self, p: DVec2) -> bool {
        self.l.top_near(p, self.landing_reach()) <= self.z + 0.01
    }

    /// How far from a landing point the material is looked for (see [`Self::clear`]).
    pub(super) fn landing_reach(&self) -> f64 {
        self.c.r + LANDING_MARGIN + 1.5 * self.l.sim.grid().res
    }

    /// A tool centre that is clear, allowed and within a few cells of remaining material,
    /// nearest to where the tool is; with the direction toward the material.
    pub(super) fn lateral(&mut self, tries: usize) -> Option<(DVec2, DVec2, f64)> {
        let g = self.l.sim.grid();
        // coarse grid: blocks of `f` cells, a block has material if any of its cells does
        let f = ((self.c.r / 4.0) / g.res).floor().max(1.0) as usize;
        let (cx, cy) = (g.nx.div_ceil(f), g.ny.div_ceil(f));
        // kept from call to call; only the blocks the passes since cleared are read again
        // (a scan of the whole grid per start dominated the planning time)
        let dirty = self.l.sim.take_dirty();
        let mut mat = std::mem::take(&mut self.coarse);
        let fresh = mat.len() != cx * cy;
        let (bi0, bi1, bj0, bj1) = if fresh {
            mat = vec![false; cx * cy];
            (0, cx - 1, 0, cy - 1)
        } else if let Some((i0, i1, j0, j1)) = dirty {
            (i0 / f, (i1 / f).min(cx - 1), j0 / f, (j1 / f).min(cy - 1))
        } else {
            (1, 0, 1, 0) // nothing to read again
        };
        {
            let reach = self.l.sim.reach_mask();
            let h = self.l.sim.heights();
            let thr = (self.z + 0.01) as f32;
            for bj in bj0..=bj1 {
                for bi in bi0..=bi1 {
                    let mut m = false;
                    'block: for j in bj * f..((bj + 1) * f).min(g.ny) {
                        for i in bi * f..((bi + 1) * f).min(g.nx) {
                            let k = j * g.nx + i;
                            if reach[k] && h[k] > thr {
                                m = true;
                                break 'block;
                            }
                        }
                    }
                    mat[bj * cx + bi] = m;
                }
            }
        }
        let cell = f as f64 * g.res;
        // the distance to the material is needed only up to `r + 2.5 cell`, `k` blocks
        let k = ((self.c.r + 2.5 * cell) / cell).ceil() as usize + 1;
        // The distance of each block to the material, kept from call to call: material only
        // goes, so only blocks within `k` of those read again can come nearer than `k` to it
        // or have been; they are transformed again over a window `k` wider still, which holds
        // all the material within `k` of them (a transform of the whole grid per start
        // dominated the planning of large levels with a small tool). A distance up to `k` is
        // the whole grid's, to the bit; one beyond it stays beyond it.
        let mut redone = None;
        if fresh {
            self.coarse_dist = edt::distance(&mat, cx, cy);
            redone = Some((0, cx - 1, 0, cy - 1));
        } else if bi0 <= bi1 && bj0 <= bj1 {
            let (oi0, oi1) = (bi0.saturating_sub(k), (bi1 + k).min(cx - 1));
            let (oj0, oj1) = (bj0.saturating_sub(k), (bj1 + k).min(cy - 1));
            let (ei0, ei1) = (oi0.saturating_sub(k), (oi1 + k).min(cx - 1));
            let (ej0, ej1) = (oj0.saturating_sub(k), (oj1 + k).min(cy - 1));
            let sx = ei1 - ei0 + 1;
            let sub: Vec<bool> = (ej0..=ej1).flat_map(|j| mat[j * cx + ei0..=j * cx + ei1].iter().copied()).collect();
            let dm = edt::distance(&sub, sx, ej1 - ej0 + 1);
            for j in oj0..=oj1 {
                let row = (j - ej0) * sx;
                self.coarse_dist[j * cx + oi0..=j * cx + oi1]
                    .copy_from_slice(&dm[row + (oi0 - ei0)..=row + (oi1 - ei0)]);
            }
            redone = Some((oi0, oi1, oj0, oj1));
        }
        // the blocks whose centres stand a little more than a radius from the material, the
        // candidates' band: kept in row order with the distances, read again where they were
        let band = |d: f32| {
            let d = d as f64 * cell;
            !(d < self.c.r + 0.5 * cell || d > self.c.r + 2.5 * cell)
        };
        if let Some((oi0, oi1, oj0, oj1)) = redone {
            // (merged in row order: the blocks before the window's on each of its rows, the
            // window's read again, the blocks after; a sort of the whole band was a tenth of
            // the search)
            let mut old = std::mem::take(&mut self.coarse_band).into_iter().peekable();
            let mut kept: Vec<u32> = Vec::with_capacity(old.len());
            for j in oj0..=oj1 {
                let row = j * cx;
                while let Some(n) = old.next_if(|&n| (n as usize) < row + oi0) {
                    kept.push(n);
                }
                while old.next_if(|&n| (n as usize) <= row + oi1).is_some() {}
                kept.extend((oi0..=oi1).filter(|&i| band(self.coarse_dist[row + i])).map(|i| (row + i) as u32));
            }
            kept.extend(old);
            self.coarse_band = kept;
        }
        let any = mat.iter().any(|m| *m);
        self.coarse = mat;
        if !any {
            return None;
        }
        let mat = &self.coarse;
        let (i0, i1, j0, j1) = {
            // (row by row: a division per block of material was a tenth of this search)
            let (mut i0, mut i1, mut j0, mut j1) = (cx, 0, cy, 0);
            for (j, row) in mat.chunks(cx).enumerate() {
                if let Some(a) = row.iter().position(|m| *m) {
                    let b = row.iter().rposition(|m| *m).unwrap_or(a);
                    (i0, i1, j0, j1) = (i0.min(a), i1.max(b), j0.min(j), j1.max(j));
                }
            }
            (i0.saturating_sub(k), (i1 + k).min(cx - 1), j0.saturating_sub(k), (j1 + k).min(cy - 1))
        };
        // The candidates nearest the tool first: those of a window of blocks round it, only
        // those nearer than any block outside the window and away from the walls; when none of
        // them gives a start, a window four times as wide, and at last the whole range. The
        // order of the candidates tried, and so the start found, is the whole range's: each
        // window's list begins with the one before it (the same candidates in the same
        // order), whose tries are not made again.
        let cur = self.l.tp.end().truncate();
        let block = |v: f64, lo: f64, a: usize, b: usize| (((v - lo) / cell).floor().max(0.0) as usize).clamp(a, b);
        let (ci, cj) = (block(cur.x, g.x0, i0, i1), block(cur.y, g.y0, j0, j1));
        // (failures of this call's tries do not change its candidates)
        let failed0 = self.failed.len();
        // (the candidates tried, and those passed over: tried or near a failed start)
        let (mut tried, mut passed) = (0usize, 0usize);
        let mut w = LATERAL_WINDOW;
        loop {
            let (wi0, wi1) = (ci.saturating_sub(w).max(i0), (ci + w).min(i1));
            let (wj0, wj1) = (cj.saturating_sub(w).max(j0), (cj + w).min(j1));
            let full = (wi0, wi1, wj0, wj1) == (i0, i1, j0, j1);
            // how near the tool every candidate outside the window is not
            let near = if full {
                f64::INFINITY
            } else {
                let (xl, xh) = (g.x0 + wi0 as f64 * cell, g.x0 + (wi1 + 1) as f64 * cell);
                let (yl, yh) = (g.y0 + wj0 as f64 * cell, g.y0 + (wj1 + 1) as f64 * cell);
                [(wi0 > i0, cur.x - xl), (wi1 < i1, xh - cur.x), (wj0 > j0, cur.y - yl), (wj1 < j1, yh - cur.y)]
                    .into_iter()
                    .filter(|s| s.0)
                    .map(|s| s.1)
                    .fold(f64::INFINITY, f64::min)
            };
            let mut cands: Vec<(f64, DVec2)> = Vec::new();
            // (the band's blocks in the window, in the order of a scan of its rows)
            for (i, j) in self.coarse_band.iter().map(|&n| (n as usize % cx, n as usize / cx)) {
                if i < wi0 || i > wi1 || j < wj0 || j > wj1 {
                    continue;
                }
                let mut p = DVec2::new(g.x0 + (i as f64 + 0.5) * cell, g.y0 + (j as f64 + 0.5) * cell);
                let mut dk = self.dk_at(p);
                if dk < self.c.r + self.c.margin + cell {
                    if !self.relaxed {
                        continue;
                    }
                    // in a channel narrower than two blocks the centres may all miss the strip
                    // the tool can stand on: the point of the block farthest from the walls
                    let third = cell / 3.0;
                    let best = (-1..=1)
                        .flat_map(|a| (-1..=1).map(move |b| p + DVec2::new(a as f64, b as f64) * third))
                        .map(|q| (self.dk_at(q), q))
                        .max_by(|a, b| a.0.total_cmp(&b.0))
                        .expect("nine points");
                    if best.0 < self.c.r + self.c.margin + 2.0 * g.res {
                        continue;
                    }
                    (dk, p) = best;
                }
                // not tangent to the part (§4.5): starts that are within a tool diameter of the
                // walls come after all the others, which clear toward the walls first
                let near_wall = dk < 3.0 * self.c.r + self.c.margin;
                let key = (p - cur).length() + if near_wall { 1e6 } else { 0.0 };
                if full || key <= near {
                    cands.push((key, p));
                }
            }
            cands.sort_by(|a, b| a.0.total_cmp(&b.0));
            let skip = passed.min(cands.len());
            for (_, p) in cands.into_iter().skip(skip) {
                passed += 1;
                // not near a start that failed before this search (asked only of the candidates
                // the search comes to: of every candidate in the window, it was a tenth of
                // stl_wheel_in_box's planning)
                let near_fail = |f: &DVec2| {
                    let v = *f - p;
                    // (the box test first: no square root for the failures far away)
                    v.x.abs() < 1.5 * cell && v.y.abs() < 1.5 * cell && v.length() < 1.5 * cell
                };
                if self.failed[..failed0].iter().any(near_fail) {
                    continue;
                }
                if tried >= tries {
                    return None;
                }
                tried += 1;
                if !self.clear(p) || !self.allowed(p) {
                    continue;
                }
                // direction to the material: the engaged samples of the enlarged rings
                let Some(dir) = self.toward_material(p) else { continue };
                // back up along the front, against the heading the pass will take, when a wall is
                // within reach that way: the pass then sweeps the whole front from that wall
                // instead of a step's worth of it (in a slot, the loops of trochoidal milling)
                let cand = p;
                let p = self.upstream(p, dir, cell);
                // slide toward the material until just before the tool touches it
                let u = DVec2::new(dir.cos(), dir.sin());
                // (by bisection to a cell: the clearance test reads a whole disk of cells)
                let ok = |me: &Self, t: f64| {
                    let n = p + u * t;
                    me.clear(n) && me.allowed(n)
                };
                let (mut lo, mut hi) = (0.0, 4.0 * cell);
                if ok(self, hi) {
                    lo = hi;
                } else {
                    while hi - lo > g.res {
                        let mid = 0.5 * (lo + hi);
                        if ok(self, mid) {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                }
                // the pass must find the material from there (its ring, or the enlarged one of
                // footnote 3), or it would end at once after a descent for nothing
                let at = p + u * lo;
                let heading = dir + if self.c.climb { 1.0 } else { -1.0 } * FRAC_PI_2;
                if self.direction(at, heading).is_none() {
                    self.failed.push(cand);
                    continue;
                }
                return Some((at, cand, dir));
            }
            if full {
                return None;
            }
            w *= 4;
        }
    }

    /// A lateral start `p` (material toward `dir`) moved back along the front, against the
    /// heading the pass will take, as long as it stays clear, allowed and beside the material —
    /// but only where walls bound the front closely both ways (a slot) and the move ends at
    /// one; otherwise `p` itself.
    pub(super) fn upstream(&self, p: DVec2, dir: f64, cell: f64) -> DVec2 {
        let s = if self.c.climb { 1.0 } else { -1.0 };
        let h = dir + s * FRAC_PI_2;
        let back = -DVec2::new(h.cos(), h.sin());
        let res = self.l.sim.grid().res;
        let rho = self.c.r + 2.5 * cell;
        let off = -DVec2::new(dir.cos(), dir.sin());
        let ds = res.max(0.5 * cell);
        // only where the front is short — a wall within half a radius behind and one within a
        // diameter ahead, as in a slot: in the open the pass runs along the front anyway (and
        // no clearance test is made: they dominate the planning time)
        let wall = |sign: f64, reach: f64| {
            (1..=(reach / ds).ceil() as usize).any(|k| !self.allowed(p + back * (sign * k as f64 * ds)))
        };
        if !wall(-1.0, 0.5 * self.c.r) || !wall(1.0, 2.0 * self.c.r) {
            return p;
        }
        let mut q = p;
        let mut t = 0.0;
        while t < 2.0 * self.c.r {
            let mut n = q + back * ds;
            if !self.allowed(n) {
                // at a wall: start there
                return q;
            }
            // the front may bulge toward the tool: step off it until clear
            let mut k = 0;
            while !self.clear(n) && k < 8 {
                n += off * ds;
                k += 1;
            }
            if !self.clear(n) || !self.allowed(n) || !self.material_on_circle(n, rho) {
                break;
            }
            q = n;
            t += ds;
        }
        p
    }

    /// Material anywhere on the circle of radius `rho` around `p`.
    pub(super) fn material_on_circle(&self, p: DVec2, rho: f64) -> bool {
        let h = self.l.sim.heights();
        let g = self.l.sim.grid();
        let thr = (self.z + 0.01) as f32;
        (0..96).any(|k| {
            let a = TAU * k as f64 / 96.0;
            g.cell_of(p + DVec2::new(a.cos(), a.sin()) * rho).is_some_and(|(i, j)| h[j * g.nx + i] > thr)
        })
    }

    /// Mean direction of the material seen on rings up to 3.5 cells of the coarse search larger
    /// than the tool ([`RING_128`]).
    pub(super) fn toward_material(&self, p: DVec2) -> Option<f64> {
        let h = self.l.sim.heights();
        let g = self.l.sim.grid();
        let thr = (self.z + 0.01) as f32;
        for extra in [0.5, 1.0, 2.0, 3.0] {
            let rho = self.c.r + extra * (self.c.r / 4.0).max(g.res);
            let mut sum = DVec2::ZERO;
            for &u in RING_128.iter() {
                if let Some((i, j)) = g.cell_of(p + u * rho)
                    && h[j * g.nx + i] > thr
                {
                    sum += u;
                }
            }
            if sum.length() > 1e-9 {
                return Some(sum.y.atan2(sum.x));
            }
        }
        None
    }

    /// The cell farthest from the walls among those with material under the tool.
    pub(super) fn deepest(&self) -> Option<(DVec2, f64)> {
        let g = self.l.sim.grid();
        let reach = self.l.sim.reach_mask();
        let h = self.l.sim.heights();
        let thr = (self.z + 0.01) as f32;
        let mut best: Option<(f32, usize)> = None;
        for k in 0..g.len() {
            if reach[k] && h[k] > thr && best.is_none_or(|b| self.c.dk[k] > b.0) {
                best = Some((self.c.dk[k], k));
            }
        }
        let (d, k) = best?;
        let p = g.center(k % g.nx, k / g.nx);
        Some((p, d as f64))
    }
}

#[cfg(test)]
mod tests {
    use super::super::engine::fixture::{Pocket, clear_row, engine};
    use super::super::engine::{Mode, State, Trace};
    use super::*;
    use std::f64::consts::PI;

    /// The pocket cleared but for a band along the top wall (y > 9.6) and a block at its left
    /// end (x < 9, y > 3.6): contouring the band from the right (climb milling) comes to the
    /// block, where the wall ahead is too heavy to follow; constant engagement takes over and
    /// the place is kept as a resume point. Once the block is cleared (but for the band), the
    /// next start is that resume point: the tool lands behind it on the contour, in cut space,
    /// and goes on contouring the same way.
    #[test]
    fn contouring_that_gives_way_leaves_a_resume_point_and_the_next_start_resumes_there() {
        let p = Pocket::new(true);
        let z = p.z();
        let mut l = p.linker();
        for y in [-0.4, 1.6, 3.6] {
            clear_row(&mut l, z, y, -3.0, 23.0);
        }
        for y in [5.6, 7.6] {
            clear_row(&mut l, z, y, 9.0, 23.0);
        }
        let c = p.setup(&l);
        let mut e = engine(&mut l, &c, z);
        let at = DVec2::new(16.0, 7.9);
        let mut st = State { c: at, alpha: PI, mode: Mode::Engage, air: 0.0 };
        let mut tr = Trace { pts: vec![at], rem: vec![0], last_cut: 1 };
        // onto the wall, along it to the block, and off it
        let mut gave_way = None;
        for _ in 0..60 {
            let before = st.mode;
            assert!(e.advance(&mut st, &mut tr), "the pass ended: {}", e.why);
            if !e.resume.is_empty() {
                gave_way = Some(before);
                break;
            }
        }
        let Some(Mode::Contour { ring, s, dir, .. }) = gave_way else { panic!("no resume point: {gave_way:?}") };
        assert_eq!(st.mode, Mode::Engage);
        let rp = e.resume[0];
        assert_eq!((rp.ring, rp.s, rp.dir), (ring, s, dir), "{rp:?}");
        // where it gave way: on the top wall's contour, between the start and the block
        let (q, t) = c.walls.at(rp.ring, rp.s);
        assert!((q.y - (10.0 - p.geom.wall_level)).abs() < 0.005 && q.x > 9.0 && q.x < at.x, "{q:?}");
        assert!((t * rp.dir).x < -0.99, "contouring right to left: {:?}", t * rp.dir);

        // the block cleared but for the band: the next start resumes there
        for y in [5.6, 7.6] {
            clear_row(e.l, z, y, -3.0, 9.0);
        }
        let Some(Start::Resume { ring, s, dir, land }) = e.find_start() else { panic!("not a resume") };
        assert_eq!((ring, s, dir), (rp.ring, rp.s, rp.dir));
        assert!(e.resume.is_empty());
        assert!(land >= c.step && land < 6.0 * c.r, "lands {land} mm behind");
        let (back, _) = c.walls.at(ring, s - dir * land);
        assert!(back.x > q.x && e.clear(back), "landing at {back:?}");
        // the tool comes down there, on the contour, going on the same way
        let st = e.land(Start::Resume { ring, s, dir, land });
        assert_eq!(st.mode, Mode::Contour { ring, s: s - dir * land, dir, walked: 0.0 });
        assert!((st.c - back).length() < 1e-12 && st.alpha.cos() < -0.99, "{st:?}");
        assert!((e.l.tp.end() - back.extend(z)).length() < 1e-9, "the tool is at {:?}", e.l.tp.end());
    }
}
