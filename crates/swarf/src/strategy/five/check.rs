//! swarf's own checks of a 5-axis path against the pocket's surfaces, written apart from the
//! planner (its own sampling, its own tool model): gouges of the floor and the walls by the
//! cutter, collisions of the shank and holder, rapids into the part, coverage of the floor
//! outside the wall band, turns between cutting moves, and the axis against the field.
//!
//! - The floor (inside the unit square, where there is material) and the walls are sampled
//!   about 0.2 mm apart, and the material behind the upper half of each wall more coarsely. The tool is a solid of revolution: a flat bottom, the corner as a
//!   torus, the flutes (a cone for a tapered tool), the shank and the holder, each a region of
//!   the (ρ, z) half-plane with its signed distance; a sample inside any of them is a gouge (of
//!   the cutter) or a collision (of the shank or holder), as deep as it is inside.
//! - Coverage: every floor sample outside the wall band (the fillet the tool leaves in the
//!   corner plus the case's margin, as the case format defines it) must come within
//!   `scallop_tol` of the cutter at some position along the cutting moves, those taken 0.1 mm
//!   apart.
//! - The axis is compared with the field at the floor point under the tip; a tapered tool is
//!   allowed its turn from the walls, q (d₂ − d₁)/(d₂ + d₁), or q within the band.

use super::place::{Grid, Profile, dist_polyline, polyline_len};
use crate::geom::DVec3;
use crate::model::five::{Boundary, CutterKind, FiveJob, Side};
use crate::post::five::AxisMove;
use rayon::prelude::*;

/// What the checks found.
#[derive(Debug, Clone, Default)]
pub struct FiveCheck {
    /// The deepest floor sample inside the cutter during a cut, mm.
    pub floor_depth: f64,
    /// The deepest wall sample inside the cutter during a cut, mm.
    pub wall_depth: f64,
    /// The deepest floor or wall sample inside the shank or holder, mm.
    pub collision: f64,
    /// The deepest sample inside any part of the tool during a rapid, mm.
    pub rapid_depth: f64,
    /// The share of the floor's area outside the wall band within the scallop tolerance of the
    /// cutter.
    pub coverage: f64,
    /// The farthest a floor sample outside the band stays from the cutter, mm.
    pub max_uncut: f64,
    /// The greatest turn between consecutive cutting moves, degrees.
    pub max_turn_deg: f64,
    /// The greatest angle of the axis from the field beyond its allowance, degrees.
    pub axis_excess_deg: f64,
    /// Where the axis is farthest off: the move's index and the floor's (u, v) under its tip.
    pub axis_worst: Option<(usize, f64, f64)>,
    /// Cutting moves.
    pub cuts: usize,
}

impl FiveCheck {
    /// The criteria the path fails: gouge or collision over 0.01 mm, coverage under 99 %, a
    /// turn over 5°, the axis more than 1° off.
    pub fn failures(&self) -> Vec<String> {
        let mut out = Vec::new();
        let tol = 0.01;
        if self.floor_depth > tol {
            out.push(format!("floor gouged {:.4} mm", self.floor_depth));
        }
        if self.wall_depth > tol {
            out.push(format!("wall gouged {:.4} mm", self.wall_depth));
        }
        if self.collision > tol {
            out.push(format!("shank or holder {:.4} mm into the part", self.collision));
        }
        if self.rapid_depth > tol {
            out.push(format!("a rapid {:.4} mm into the part", self.rapid_depth));
        }
        if self.coverage < 0.99 {
            out.push(format!("coverage {:.2} %", 100.0 * self.coverage));
        }
        if self.max_turn_deg > 5.0 {
            out.push(format!("a turn of {:.2}°", self.max_turn_deg));
        }
        if self.axis_excess_deg > 1.0 {
            out.push(format!("the axis {:.2}° off the field", self.axis_excess_deg));
        }
        out
    }
}

/// The tool as regions of the (ρ, z) half-plane.
struct Solid {
    rho_c: f64,
    rc: f64,
    r: f64,
    tan_q: f64,
    z_corner: f64,
    flutes: f64,
    shank: f64,
    length: f64,
    holder: Option<(f64, f64)>,
}

fn sd_box(rho: f64, z: f64, half: f64, z0: f64, z1: f64) -> f64 {
    let dx = rho.abs() - half;
    let dz = (z0 - z).max(z - z1);
    let out = (dx.max(0.0).powi(2) + dz.max(0.0).powi(2)).sqrt();
    out + dx.max(dz).min(0.0)
}

impl Solid {
    fn of(job: &FiveJob) -> Solid {
        let t = &job.tool;
        let r = 0.5 * t.diameter;
        let q = if t.kind == CutterKind::Tapered { t.taper_deg.to_radians() } else { 0.0 };
        let rc = if t.kind == CutterKind::Ball { r } else { t.corner_radius.min(r) };
        Solid {
            rho_c: (r + rc * q.tan() - rc / q.cos()).max(0.0),
            rc,
            r,
            tan_q: q.tan(),
            z_corner: rc * (1.0 - q.sin()),
            flutes: t.flute_length.min(t.length.max(t.flute_length)),
            shank: 0.5 * t.shank_diameter,
            length: t.length.max(t.flute_length),
            holder: t.holder.map(|(d, l)| (0.5 * d, l)),
        }
    }

    /// Signed distances (negative inside) to the cutter and to the shank and holder.
    fn sd(&self, rho: f64, z: f64) -> (f64, f64) {
        let bottom = sd_box(rho, z, self.rho_c, 0.0, self.rc.max(1e-9));
        let corner = ((rho - self.rho_c).powi(2) + (z - self.rc).powi(2)).sqrt() - self.rc;
        let cos_q = 1.0 / (1.0 + self.tan_q * self.tan_q).sqrt();
        let side = ((rho - self.r - z * self.tan_q) * cos_q).max(self.z_corner - z).max(z - self.flutes);
        let cutter = bottom.min(corner).min(side);
        let mut other = sd_box(rho, z, self.shank, self.flutes, self.length);
        if let Some((hr, hl)) = self.holder {
            other = other.min(sd_box(rho, z, hr, self.length, self.length + hl));
        }
        (cutter, other)
    }

    fn top(&self) -> f64 {
        self.length + self.holder.map_or(0.0, |h| h.1)
    }

    fn widest(&self) -> f64 {
        (self.r + self.flutes * self.tan_q).max(self.shank).max(self.holder.map_or(0.0, |h| h.0))
    }
}

/// Samples in a uniform grid of cells.
struct Cloud {
    grid: Grid,
    pts: Vec<DVec3>,
}

impl Cloud {
    fn new(pts: Vec<DVec3>, cell: f64) -> Cloud {
        Cloud { grid: Grid::new(&pts, cell), pts }
    }

    /// Calls `f` with every sample within `pad` of the segment `[a, b]` (and some more).
    fn near(&self, a: DVec3, b: DVec3, pad: f64, mut f: impl FnMut(DVec3)) {
        self.grid.near(a, b, pad, |k| f(self.pts[k]));
    }
}

/// The deepest sample of `cloud` inside the cutter, and inside the shank or holder, with the
/// tool at `tip` along `a` (0 when none is).
fn depths(cloud: &Cloud, solid: &Solid, tip: DVec3, a: DVec3) -> (f64, f64) {
    let (mut cut, mut other) = (0.0f64, 0.0f64);
    // the tool in two pieces, each with its own box
    let pieces = [
        (0.0, solid.length, solid.widest().min((solid.r + solid.flutes * solid.tan_q).max(solid.shank))),
        (solid.length, solid.top(), solid.widest()),
    ];
    for (z0, z1, r) in pieces {
        if z1 <= z0 {
            continue;
        }
        // (in lengths of a few millimetres, each with its own box: a long tilted tool's one
        // box would hold a wide patch of the floor)
        let n = ((z1 - z0) / 3.0).ceil().max(1.0) as usize;
        for c in 0..n {
            let (c0, c1) = (z0 + (z1 - z0) * c as f64 / n as f64, z0 + (z1 - z0) * (c + 1) as f64 / n as f64);
            cloud.near(tip + a * c0, tip + a * c1, r + 0.1, |p| {
                let d = p - tip;
                let z = d.dot(a);
                if z < c0 - if c == 0 { 0.5 } else { 0.0 } || z >= c1 && c + 1 < n || z > c1 {
                    return;
                }
                let rho = (d.length_squared() - z * z).max(0.0).sqrt();
                let (c, o) = solid.sd(rho, z);
                cut = cut.max(-c);
                other = other.max(-o);
            });
        }
    }
    (cut, other)
}

/// Checks `moves` against `job`.
pub fn check(job: &FiveJob, moves: &[AxisMove]) -> FiveCheck {
    let solid = Solid::of(job);
    let prof = Profile::of(&job.tool);
    let r = prof.radius();
    // the floor samples (where there is material: the unit square), with their areas
    let size = |f: &dyn Fn(f64) -> DVec3| polyline_len((0..=64).map(|i| f(i as f64 / 64.0)));
    let lu = (0..=4).map(|k| size(&|t| job.floor.eval(t, k as f64 / 4.0).p)).fold(0.0, f64::max);
    let lv = (0..=4).map(|k| size(&|t| job.floor.eval(k as f64 / 4.0, t).p)).fold(0.0, f64::max);
    let (nu, nv) = (((lu / 0.2).ceil() as usize).clamp(8, 4000), ((lv / 0.2).ceil() as usize).clamp(8, 4000));
    let floor: Vec<(DVec3, f64, f64, f64)> = (0..=nu)
        .into_par_iter()
        .flat_map_iter(|i| {
            (0..=nv).map(move |j| {
                let (u, v) = (i as f64 / nu as f64, j as f64 / nv as f64);
                let s = job.floor.eval(u, v);
                (s.p, s.su.cross(s.sv).length() / (nu * nv) as f64, u, v)
            })
        })
        .collect();
    let floor_cloud = Cloud::new(floor.iter().map(|f| f.0).collect(), 2.0);
    // the walls, with their base curves and the band along each
    let mut wall_pts = Vec::new();
    let mut bases: Vec<(Vec<DVec3>, f64)> = Vec::new();
    for side in Side::ALL {
        if matches!(job.boundary(side), Boundary::Open) {
            continue;
        }
        let w = |s: f64, t: f64| job.wall_point(side, s, t).expect("a wall");
        let along = size(&|s| w(s, 0.5)).max(size(&|s| w(s, 0.0))).max(size(&|s| w(s, 1.0)));
        let up = (0..=4).map(|k| size(&|t| w(k as f64 / 4.0, t))).fold(0.0, f64::max);
        let (na, nw) = (((along / 0.15).ceil() as usize).clamp(4, 20_000), ((up / 0.2).ceil() as usize).clamp(4, 4000));
        for i in 0..=na {
            for j in 0..=nw {
                wall_pts.push(w(i as f64 / na as f64, j as f64 / nw as f64));
            }
        }
        // the material behind the wall's upper part (a tool hanging over the top edge behind
        // the wall holds no point of the wall itself): samples 0.4 mm and 2 mm behind it
        let na2 = (na / 3).max(4);
        let nw2 = (nw / 3).max(4);
        for i in 0..=na2 {
            let a = i as f64 / na2 as f64;
            let b0 = side.at(a);
            let f = job.floor.eval(b0.x, b0.y);
            let inward = side.inward(&f);
            for j in nw2 / 2..=nw2 {
                let b = j as f64 / nw2 as f64;
                let e = 1e-4;
                let ds = w((a + e).min(1.0), b) - w((a - e).max(0.0), b);
                let dw = w(a, (b + e).min(1.0)) - w(a, (b - e).max(0.0));
                let n = ds.cross(dw).normalize_or_zero();
                let n = if n.dot(inward) < 0.0 { -n } else { n };
                for d in [0.4, 2.0] {
                    wall_pts.push(w(a, b) - n * d);
                }
            }
        }
        // the fillet the tool leaves: from the floor–wall angle γ at the base
        let mut fillet = r;
        let base: Vec<DVec3> = (0..=200).map(|i| w(i as f64 / 200.0, 0.0)).collect();
        for i in 0..=20 {
            let s = i as f64 / 20.0;
            let b = side.at(s);
            let f = job.floor.eval(b.x, b.y);
            let inward = side.inward(&f);
            let n = f.normal();
            let inward = (inward - n * inward.dot(n)).normalize();
            let up = (w(s, 0.05) - w(s, 0.0)).normalize();
            let gamma = inward.dot(up).clamp(-1.0, 1.0).acos();
            let fil = match job.tool.kind {
                CutterKind::Ball => r / (0.5 * gamma).tan(),
                _ if gamma >= std::f64::consts::FRAC_PI_2 => r,
                _ => 2.0 * r / gamma.sin(),
            };
            fillet = fillet.max(fil);
        }
        bases.push((base, fillet + job.wall_band_margin));
    }
    let wall_cloud = Cloud::new(wall_pts, 2.0);

    // gouges and collisions at every position; rapids every millimetre
    let mut out = FiveCheck::default();
    let positions: Vec<(DVec3, DVec3, bool)> = moves
        .windows(2)
        .flat_map(|w| {
            let n = if w[1].rapid { ((w[1].tip - w[0].tip).length() / 1.0).ceil().max(1.0) as usize } else { 1 };
            (1..=n).map(move |k| {
                let t = k as f64 / n as f64;
                (w[0].tip.lerp(w[1].tip, t), w[0].axis.lerp(w[1].axis, t).normalize(), w[1].rapid)
            })
        })
        .collect();
    let found: Vec<(f64, f64, f64, bool)> = positions
        .par_iter()
        .map(|&(tip, a, rapid)| {
            let (fc, fo) = depths(&floor_cloud, &solid, tip, a);
            let (wc, wo) = depths(&wall_cloud, &solid, tip, a);
            (fc, wc, fo.max(wo), rapid)
        })
        .collect();
    for (fc, wc, o, rapid) in found {
        if rapid {
            out.rapid_depth = out.rapid_depth.max(fc).max(wc).max(o);
        } else {
            out.floor_depth = out.floor_depth.max(fc);
            out.wall_depth = out.wall_depth.max(wc);
            out.collision = out.collision.max(o);
        }
    }

    // coverage: cutting positions 0.1 mm apart, by the cell of their tip
    let fine: Vec<(DVec3, DVec3)> = moves
        .windows(2)
        .filter(|w| !w[1].rapid)
        .flat_map(|w| {
            let n = ((w[1].tip - w[0].tip).length() / 0.1).ceil().max(1.0) as usize;
            (0..n).map(move |k| {
                let t = k as f64 / n as f64;
                (w[0].tip.lerp(w[1].tip, t), w[0].axis.lerp(w[1].axis, t).normalize())
            })
        })
        .collect();
    let tips = Cloud::new(fine.iter().map(|f| f.0).collect(), 1.0);
    let axis_of: std::collections::HashMap<[u64; 3], DVec3> =
        fine.iter().map(|(t, a)| (t.to_array().map(f64::to_bits), *a)).collect();
    let tol = job.scallop_tol;
    // a floor point no tool on the orientation rule can reach without cutting a wall: the tool
    // set down on it along the field (and, tapered, turned by q from the nearest wall)
    let q_rad = if job.tool.kind == CutterKind::Tapered { job.tool.taper_deg.to_radians() } else { 0.0 };
    let unreachable = |p: DVec3| -> bool {
        let Some((d1, k1)) =
            bases.iter().enumerate().map(|(k, (b, _))| (dist_polyline(p, b), k)).min_by(|a, b| a.0.total_cmp(&b.0))
        else {
            return false;
        };
        if d1 > 3.0 * r + 10.0 {
            return false;
        }
        let (uv, _) = job.floor.closest_point(p);
        let v = job.axis_field(uv.x, uv.y);
        let mut axes = vec![v];
        if q_rad > 0.0 {
            // away from the wall: from its base towards the point
            let b = &bases[k1].0;
            let near = b.iter().min_by(|x, y| (**x - p).length().total_cmp(&(**y - p).length())).copied().unwrap_or(p);
            let away = ((p - near) - v * (p - near).dot(v)).normalize_or_zero();
            axes.push((v * q_rad.cos() + away * q_rad.sin()).normalize());
        }
        axes.into_iter().all(|a| {
            // set down on the floor: lifted until no floor sample is under its bottom
            let mut lift = 0.0f64;
            floor_cloud.near(p, p, solid.r + 0.5, |s| {
                let d = s - p;
                let z = d.dot(a);
                let rho = (d.length_squared() - z * z).max(0.0).sqrt();
                if let Some(b) = prof.bottom(rho) {
                    lift = lift.max(z - b);
                }
            });
            let (wc, wo) = depths(&wall_cloud, &solid, p + a * lift, a);
            wc.max(wo) > 0.01
        })
    };
    let covered: Vec<(f64, f64, f64)> = floor
        .par_iter()
        .map(|&(p, area, _, _)| {
            if bases.iter().any(|(b, band)| dist_polyline(p, b) < *band) {
                return (0.0, 0.0, 0.0);
            }
            let mut best = f64::INFINITY;
            tips.near(p, p, r + 2.0 * tol + 0.5, |tip| {
                if best <= tol {
                    return;
                }
                let a = axis_of[&tip.to_array().map(f64::to_bits)];
                let d = p - tip;
                let z = d.dot(a);
                let rho = (d.length_squared() - z * z).max(0.0).sqrt();
                best = best.min(solid.sd(rho, z).0.max(0.0));
            });
            if best > tol && unreachable(p) {
                return (0.0, 0.0, 0.0);
            }
            (area, if best <= tol { area } else { 0.0 }, best.min(10.0))
        })
        .collect();
    let (total, hit) = covered.iter().fold((0.0, 0.0), |s, c| (s.0 + c.0, s.1 + c.1));
    out.coverage = if total > 0.0 { hit / total } else { 1.0 };
    out.max_uncut = covered.iter().filter(|c| c.0 > 0.0).map(|c| c.2).fold(0.0, f64::max);

    // turns between consecutive cutting moves (a rapid ends a run)
    let mut prev: Option<DVec3> = None;
    for w in moves.windows(2) {
        if w[1].rapid {
            prev = None;
            continue;
        }
        let d = w[1].tip - w[0].tip;
        if d.length() < 1e-6 {
            continue;
        }
        if let Some(p) = prev {
            out.max_turn_deg = out.max_turn_deg.max(p.angle_between(d).to_degrees());
        }
        out.cuts += 1;
        prev = Some(d);
    }

    // the axis against the field at the floor point under the tip
    let q = if job.tool.kind == CutterKind::Tapered { job.tool.taper_deg } else { 0.0 };
    // (each foot found from the last one's, along the path)
    let mut feet = Vec::new();
    let mut last: Option<crate::geom::DVec2> = None;
    for (k, m) in moves.iter().enumerate().filter(|(_, m)| !m.rapid) {
        // (a tip far from where the last foot was is off the floor, past an open side: the
        // foot found from there is at the edge, and the check below leaves it out)
        let f = match last {
            Some(uv) => job.floor.closest_point_near(m.tip, uv),
            None => job.floor.closest_point(m.tip),
        };
        last = Some(f.0);
        feet.push((k, m, f));
    }
    let excess: Vec<(f64, usize, f64, f64)> = feet
        .par_iter()
        .map(|&(k, m, (uv, foot))| {
            // (a foot on the edge is the tip's past it, where the field is not the case's)
            let edge = 1e-3;
            if (foot - m.tip).length() > 0.5 + r || uv.min_element() <= edge || uv.max_element() >= 1.0 - edge {
                return (0.0, k, uv.x, uv.y);
            }
            let dev = m.axis.angle_between(job.axis_field(uv.x, uv.y)).to_degrees();
            let allow = if q == 0.0 {
                0.0
            } else {
                let mut d: Vec<(f64, f64)> = bases.iter().map(|(b, band)| (dist_polyline(foot, b), *band)).collect();
                d.sort_by(|x, y| x.0.total_cmp(&y.0));
                match d.as_slice() {
                    [] => 0.0,
                    [(d1, band), rest @ ..] => {
                        if d1 < band {
                            q
                        } else if let Some((d2, _)) = rest.first() {
                            q * (d2 - d1) / (d2 + d1)
                        } else {
                            q
                        }
                    }
                }
            };
            ((dev - allow).max(0.0), k, uv.x, uv.y)
        })
        .collect();
    if let Some(w) = excess.iter().max_by(|a, b| a.0.total_cmp(&b.0)) {
        out.axis_excess_deg = w.0;
        out.axis_worst = Some((w.1, w.2, w.3));
    }
    out
}
