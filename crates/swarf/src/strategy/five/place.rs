//! The tool on the pocket: the cutter as a solid of revolution, dropped along its axis onto the
//! floor, and its clearance from the walls.
//!
//! The floor is sampled on a parameter grid about 0.25 mm apart on the surface (continued as
//! its tangent plane past the open sides, where the tool runs out into the air); a tool whose
//! axis passes through a floor point is lowered or lifted along the axis until its lower
//! envelope (flat bottom, corner arc) touches the highest sample under it, and the contact is
//! refined on the surface itself by a pattern search. The walls are sampled 0.2 mm along and
//! 0.25 mm up, with layers 0.5 to 5 mm behind their upper part (the solid blade a tool could
//! hang behind, over a twisted wall's top edge), and kept in a uniform grid of cells; the
//! clearance of a tool position is the least radial distance from the tool's side (cutter,
//! shank, holder) to a wall point within its height. Neither needs the contact geometry in closed form, so the same code serves flat,
//! bull-nose, ball and tapered tools on any C¹ floor.

use super::{Canon, at_floor};
use crate::geom::DVec3;
use crate::model::five::{Boundary, CutterKind, FiveTool, Side};

/// The tool's profile, z along the axis from the tip.
#[derive(Debug, Clone, Copy)]
pub struct Profile {
    /// The corner radius.
    rc: f64,
    /// The flat bottom's radius.
    rho_c: f64,
    /// Where the corner meets the side: the bottom's reach.
    pub foot: f64,
    r: f64,
    tan_q: f64,
    z_corner: f64,
    flutes: f64,
    shank: f64,
    length: f64,
    holder: Option<(f64, f64)>,
}

impl Profile {
    /// The profile of `tool`.
    pub fn of(tool: &FiveTool) -> Profile {
        let r = 0.5 * tool.diameter;
        let q = if tool.kind == CutterKind::Tapered { tool.taper_deg.to_radians() } else { 0.0 };
        let rc = if tool.kind == CutterKind::Ball { r } else { tool.corner_radius.min(r) };
        let rho_c = (r + rc * q.tan() - rc / q.cos()).max(0.0);
        Profile {
            rc,
            rho_c,
            foot: rho_c + rc * q.cos(),
            r,
            tan_q: q.tan(),
            z_corner: rc * (1.0 - q.sin()),
            flutes: tool.flute_length.min(tool.length.max(tool.flute_length)),
            shank: 0.5 * tool.shank_diameter,
            length: tool.length.max(tool.flute_length),
            holder: tool.holder.map(|(d, l)| (0.5 * d, l)),
        }
    }

    /// The height of the tool's lower envelope at `rho` from the axis, if the bottom reaches
    /// that far.
    pub fn bottom(&self, rho: f64) -> Option<f64> {
        if rho <= self.rho_c {
            Some(0.0)
        } else if rho <= self.foot {
            let d = rho - self.rho_c;
            Some(self.rc - (self.rc * self.rc - d * d).max(0.0).sqrt())
        } else {
            None
        }
    }

    /// The tool's radius at height `z` (cutter, shank or holder); negative where there is no
    /// tool.
    pub fn reach(&self, z: f64) -> f64 {
        if z < 0.0 {
            -1.0
        } else if z <= self.flutes {
            if z >= self.z_corner {
                self.r + z * self.tan_q
            } else {
                let dz = self.rc - z;
                self.rho_c + (self.rc * self.rc - dz * dz).max(0.0).sqrt()
            }
        } else if z <= self.length {
            self.shank
        } else if let Some((hr, hl)) = self.holder
            && z <= self.length + hl
        {
            hr
        } else {
            -1.0
        }
    }

    /// The widest the cutter and shank get.
    fn cutter_width(&self) -> f64 {
        (self.r + self.flutes * self.tan_q).max(self.shank)
    }

    /// The cutter's radius at the tip end (before the corner).
    pub fn radius(&self) -> f64 {
        self.r
    }
}

/// The floor sampled on a parameter grid (continued past the open sides).
pub struct FloorGrid {
    u0: f64,
    v0: f64,
    hu: f64,
    hv: f64,
    nu: usize,
    nv: usize,
    pts: Vec<DVec3>,
}

/// The floor samples' spacing on the surface, mm.
const FLOOR_SPACING: f64 = 0.25;

impl FloorGrid {
    /// The floor of `pocket` over u in `[ulo, uhi]`, v in `[vlo, vhi]`, with `su`, `sv` the
    /// greatest |S_u|, |S_v|.
    pub fn new(pocket: &Canon, (ulo, uhi): (f64, f64), (vlo, vhi): (f64, f64), su: f64, sv: f64) -> FloorGrid {
        use rayon::prelude::*;
        // (at most about 4 million samples: a larger floor is sampled more coarsely)
        let (wu, wv) = ((uhi - ulo) * su, (vhi - vlo) * sv);
        let spacing = FLOOR_SPACING.max((wu * wv / 4e6).sqrt());
        let nu = ((wu / spacing).ceil() as usize).clamp(2, 4000);
        let nv = ((wv / spacing).ceil() as usize).clamp(2, 4000);
        let hu = (uhi - ulo) / (nu - 1) as f64;
        let hv = (vhi - vlo) / (nv - 1) as f64;
        let pts: Vec<DVec3> = (0..nu)
            .into_par_iter()
            .flat_map_iter(|i| (0..nv).map(move |j| at_floor(&pocket.job, ulo + hu * i as f64, vlo + hv * j as f64).p))
            .collect();
        FloorGrid { u0: ulo, v0: vlo, hu, hv, nu, nv, pts }
    }

    /// The parameter box the grid covers.
    fn clamp(&self, u: f64, v: f64) -> (f64, f64) {
        (
            u.clamp(self.u0, self.u0 + self.hu * (self.nu - 1) as f64),
            v.clamp(self.v0, self.v0 + self.hv * (self.nv - 1) as f64),
        )
    }

    /// How far along `a` a tool whose axis passes through the floor point `o` = S(u, v) must
    /// be moved so that it rests on the floor: the tip is `o + λ a`.
    pub fn drop(&self, pocket: &Canon, prof: &Profile, u: f64, v: f64, o: DVec3, a: DVec3) -> f64 {
        let sp = at_floor(&pocket.job, u, v);
        let reach = prof.foot + 0.3;
        let du = reach / (0.75 * sp.su.length().max(1e-9));
        let dv = reach / (0.75 * sp.sv.length().max(1e-9));
        let i0 = (((u - du - self.u0) / self.hu).floor().max(0.0)) as usize;
        let i1 = (((u + du - self.u0) / self.hu).ceil().max(0.0) as usize).min(self.nu - 1);
        let j0 = (((v - dv - self.v0) / self.hv).floor().max(0.0)) as usize;
        let j1 = (((v + dv - self.v0) / self.hv).ceil().max(0.0) as usize).min(self.nv - 1);
        let f = |p: DVec3| -> Option<f64> {
            let d = p - o;
            let z = d.dot(a);
            let rho = (d.length_squared() - z * z).max(0.0).sqrt();
            prof.bottom(rho).map(|b| z - b)
        };
        // (where the floor is less stretched than at its most, the grid is denser than it
        // needs to be here: every few samples will do)
        let si = ((FLOOR_SPACING / (sp.su.length() * self.hu).max(1e-12)).floor() as usize).clamp(1, 64);
        let sj = ((FLOOR_SPACING / (sp.sv.length() * self.hv).max(1e-12)).floor() as usize).clamp(1, 64);
        let mut best: Option<(f64, usize, usize)> = None;
        for i in (i0..=i1).step_by(si) {
            for j in (j0..=j1).step_by(sj) {
                if let Some(h) = f(self.pts[i * self.nv + j])
                    && best.is_none_or(|b| h > b.0)
                {
                    best = Some((h, i, j));
                }
            }
        }
        let Some((mut h, i, j)) = best else { return 0.0 };
        // refined on the surface: a pattern search from the best sample
        let (mut bu, mut bv) = (self.u0 + self.hu * i as f64, self.v0 + self.hv * j as f64);
        let (mut su, mut sv) = (self.hu, self.hv);
        for _ in 0..6 {
            let mut moved = true;
            let mut k = 0;
            while moved && k < 8 {
                moved = false;
                k += 1;
                for (di, dj) in [
                    (1.0, 0.0),
                    (-1.0, 0.0),
                    (0.0, 1.0),
                    (0.0, -1.0),
                    (1.0, 1.0),
                    (-1.0, -1.0),
                    (1.0, -1.0),
                    (-1.0, 1.0),
                ] {
                    let (cu, cv) = self.clamp(bu + di * su, bv + dj * sv);
                    if let Some(c) = f(at_floor(&pocket.job, cu, cv).p)
                        && c > h
                    {
                        (h, bu, bv, moved) = (c, cu, cv, true);
                    }
                }
            }
            su *= 0.5;
            sv *= 0.5;
        }
        h
    }
}

/// Points in a uniform grid of cells, for the points near a segment.
pub struct Grid {
    lo: DVec3,
    cell: f64,
    dims: [usize; 3],
    /// Cell c's points are `idx[start[c]..start[c + 1]]`.
    start: Vec<u32>,
    idx: Vec<u32>,
}

impl Grid {
    /// The grid of `pts` in cells of `cell` (larger where that would make more than a few
    /// million cells, however far apart the points are).
    pub fn new(pts: &[DVec3], cell: f64) -> Grid {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for p in pts {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        if pts.is_empty() {
            (lo, hi) = (DVec3::ZERO, DVec3::ZERO);
        }
        let span = hi - lo;
        let cell = cell.max((span.x * span.y * span.z / 4e6).cbrt()).max(1e-6);
        let dims = [0, 1, 2].map(|k| ((span[k] / cell) as usize + 1).min(2048));
        let key = |p: DVec3| {
            let c = [0, 1, 2].map(|k| (((p[k] - lo[k]) / cell) as usize).min(dims[k] - 1));
            (c[0] * dims[1] + c[1]) * dims[2] + c[2]
        };
        let n = dims[0] * dims[1] * dims[2];
        let mut start = vec![0u32; n + 1];
        for p in pts {
            start[key(*p) + 1] += 1;
        }
        for c in 0..n {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut idx = vec![0u32; pts.len()];
        for (k, p) in pts.iter().enumerate() {
            let c = key(*p);
            idx[fill[c] as usize] = k as u32;
            fill[c] += 1;
        }
        Grid { lo, cell, dims, start, idx }
    }

    /// Calls `f` with the index of every point in the cells that come within `pad` of the
    /// segment from `a` to `b` (all the points within `pad` of it, and some more).
    pub fn near(&self, a: DVec3, b: DVec3, pad: f64, mut f: impl FnMut(usize)) {
        if self.idx.is_empty() {
            return;
        }
        let lo = a.min(b) - DVec3::splat(pad) - self.lo;
        let hi = a.max(b) + DVec3::splat(pad) - self.lo;
        let c0 = [0, 1, 2].map(|k| (lo[k] / self.cell).floor().max(0.0) as usize);
        let c1 = [0, 1, 2].map(|k| ((hi[k] / self.cell).floor().max(-1.0) as isize).min(self.dims[k] as isize - 1));
        if (0..3).any(|k| c1[k] < c0[k] as isize) {
            return;
        }
        let (len, dir) = ((b - a).length(), (b - a).normalize_or_zero());
        let half = self.cell * 0.87;
        for i in c0[0]..=c1[0] as usize {
            for j in c0[1]..=c1[1] as usize {
                for k in c0[2]..=c1[2] as usize {
                    // (a cell whose centre is farther than that holds no point near the segment)
                    let centre = self.lo + DVec3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5) * self.cell;
                    let t = (centre - a).dot(dir).clamp(0.0, len);
                    if (centre - (a + dir * t)).length() > pad + half {
                        continue;
                    }
                    let c = (i * self.dims[1] + j) * self.dims[2] + k;
                    for &p in &self.idx[self.start[c] as usize..self.start[c + 1] as usize] {
                        f(p as usize);
                    }
                }
            }
        }
    }
}

/// Wall points in a grid of cells, each with its side.
pub struct WallCloud {
    grid: Grid,
    pts: Vec<DVec3>,
    side: Vec<u8>,
}

/// Wall samples' spacing along the wall and up it, mm.
const WALL_ALONG: f64 = 0.2;
const WALL_UP: f64 = 0.25;

impl WallCloud {
    /// The walls of `pocket`, sampled.
    pub fn new(pocket: &Canon) -> WallCloud {
        let job = &pocket.job;
        let (mut pts, mut side) = (Vec::new(), Vec::new());
        for s in Side::ALL {
            if matches!(job.boundary(s), Boundary::Open) {
                continue;
            }
            let w = |a: f64, b: f64| job.wall_point(s, a, b).unwrap_or(DVec3::ZERO);
            // the wall's size along and up, from a few of its lines
            let along = (0..=4)
                .map(|k| polyline_len((0..=64).map(|i| w(i as f64 / 64.0, k as f64 / 4.0))))
                .fold(0.0f64, f64::max);
            let up = (0..=8)
                .map(|k| polyline_len((0..=16).map(|i| w(k as f64 / 8.0, i as f64 / 16.0))))
                .fold(0.0f64, f64::max);
            // (at most about a million samples a wall)
            let k = (along * up / (WALL_ALONG * WALL_UP * 1e6)).sqrt().max(1.0);
            let na = ((along / (WALL_ALONG * k)).ceil() as usize).clamp(2, 4000);
            let nw = ((up / (WALL_UP * k)).ceil() as usize).clamp(2, 2000);
            for i in 0..=na {
                for j in 0..=nw {
                    pts.push(w(i as f64 / na as f64, j as f64 / nw as f64));
                    side.push(s as u8);
                }
            }
            // Behind the upper part of the wall, layers of points in the material: a tool that
            // leans over a wall's top edge and hangs down behind it holds none of the wall's
            // own points, but it is in the part (the blade is solid), and where a wall twists
            // near its top it can come there without touching the sheet.
            let into = |a: f64| -> DVec3 {
                let b = s.at(a);
                s.inward(&job.floor.eval(b.x, b.y))
            };
            let (la, lw) =
                ((along / 0.5).ceil().clamp(2.0, 2000.0) as usize, (up / 0.5).ceil().clamp(2.0, 400.0) as usize);
            for i in 0..=la {
                let a = i as f64 / la as f64;
                let inward = into(a);
                for j in (lw * 2 / 5)..=lw {
                    let b = j as f64 / lw as f64;
                    let (h, p) = (1e-4, w(a, b));
                    let ws = w((a + h).min(1.0), b) - w((a - h).max(0.0), b);
                    let ww = w(a, (b + h).min(1.0)) - w(a, (b - h).max(0.0));
                    let mut n = ws.cross(ww).normalize_or_zero();
                    if n.dot(inward) < 0.0 {
                        n = -n;
                    }
                    for d in [0.5, 1.5, 3.0, 5.0] {
                        pts.push(p - n * d);
                        side.push(s as u8);
                    }
                }
            }
        }
        WallCloud { grid: Grid::new(&pts, 2.0), pts, side }
    }

    /// The least clearance between the tool at `tip` with axis `a` and the wall points (of
    /// `only`, or all walls): the radial distance from the tool's side to the point, negative
    /// inside the tool; with the side of that point.
    pub fn clearance(&self, prof: &Profile, tip: DVec3, a: DVec3, only: Option<Side>) -> (f64, Option<Side>) {
        let mut best = (f64::INFINITY, None);
        if self.pts.is_empty() {
            return best;
        }
        let mut segs = vec![(0.0, prof.length, prof.cutter_width())];
        if let Some((hr, hl)) = prof.holder {
            segs.push((prof.length, prof.length + hl, hr));
        }
        for (z0, z1, r) in segs {
            self.grid.near(tip + a * z0, tip + a * z1, r + 0.5, |pi| {
                let s = side_of(self.side[pi]);
                if only.is_some_and(|o| o != s) {
                    return;
                }
                let d = self.pts[pi] - tip;
                let z = d.dot(a);
                if z < z0 - 1e-9 || z > z1 {
                    return;
                }
                let r = prof.reach(z);
                if r < 0.0 {
                    return;
                }
                let rho = (d.length_squared() - z * z).max(0.0).sqrt();
                if rho - r < best.0 {
                    best = (rho - r, Some(s));
                }
            });
        }
        best
    }
}

fn side_of(k: u8) -> Side {
    Side::ALL[k as usize]
}

/// The distance from `p` to the polyline `b`.
pub fn dist_polyline(p: DVec3, b: &[DVec3]) -> f64 {
    b.windows(2)
        .map(|w| {
            let d = w[1] - w[0];
            let t = ((p - w[0]).dot(d) / d.length_squared().max(1e-300)).clamp(0.0, 1.0);
            (p - (w[0] + d * t)).length()
        })
        .fold(f64::INFINITY, f64::min)
}

/// The length of a polyline.
pub fn polyline_len(pts: impl Iterator<Item = DVec3>) -> f64 {
    let mut prev: Option<DVec3> = None;
    let mut len = 0.0;
    for p in pts {
        if let Some(q) = prev {
            len += (p - q).length();
        }
        prev = Some(p);
    }
    len
}
