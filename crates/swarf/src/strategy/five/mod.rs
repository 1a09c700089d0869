//! C¹ pocketing of a freeform surface pocket in 5 axes (paper 2, Elber, Cohen, Drake, §2).
//!
//! The pocket is the region between a floor S(u, v) and a top T(u, v) over the unit square,
//! closed by walls on some sides and open on the others ([`crate::model::five`]). The path is
//! built in the parameter domain and composed through S, as the paper does:
//!
//! ```text
//!   domain (u, v), walls at v = 0 and v = 1          on the floor S(u, v)
//!        v=1 ───────────────────────────           ╭──╮╭──╮╭──╮
//!           ╭─────╮╭─────╮                         │  ││  ││  │   rounded shapes, each
//!   open    │  ·  ││  ·  │ …  → u                   ╰──╯╰──╯╰──╯   composed through S
//!   u = 0   ╰─────╯╰─────╯                        joined by the boundary segments
//!        v=0 ───────────────────────────
//! ```
//!
//! 1. **Variable offset (§2.2, Fig. 4).** The tool must stay off the walls. Geodesic distance
//!    maps from each side over the domain (`geodesic`, fast marching on the floor) give
//!    every point its distance from each side and its foot there. For each wall the least
//!    offset that keeps the tool (dropped on the floor, its axis from the field) clear of it is
//!    found by bisection at samples along the wall, smoothed into a C² function of the foot.
//!    Each side wall then pushes a point straight away from it (along the distance's
//!    gradient) by its offset times the point's share `d′/(d + d′)` of the distances to it and
//!    to the opposite side: the full offset on the wall, less inside, the bisector staying in
//!    place (the paper's rule). A wall at u = 1 pushes the same way, along the line the side
//!    pushes left the point on, so a corner stands off both walls whatever their angle
//!    (`Layout::to_floor`). The distances are smooth and so is the map: the path stays C¹.
//! 2. **Maximal shapes (§2.1, Fig. 1–2).** The domain across is measured by the share of the
//!    geodesic distances to the two sides, and scaled to the floor's mean length and width so
//!    that a circle there is round on the surface; its centre line is the geodesic bisector of
//!    the sides, the medial axis of the strip between them, and the maximal circles along it
//!    touch both offset walls. Each is cut as the paper's Fig. 2(c) shape: the front half
//!    circle, which cuts, and a shorter half ellipse behind it, which returns over cut floor
//!    (`back`).
//! 3. **Hausdorff stepover (§2.1).** Neighbouring shapes are translates, so every point of
//!    one lies on a segment of the other's translate; the Hausdorff distance on the surface is
//!    at most the step times the greatest stretch |∂S∘Φ/∂x| over the two shapes, the paper's
//!    bound `D_h · a_max` with a_max taken along the step. Steps are chosen so that it is at most
//!    0.8 of the case's stepover (the rest for a tilted tool's contact, which is not where the
//!    axis meets the floor).
//! 4. **Bridges (§2.2).** The shapes touch the offset boundary, so the paper's boundary
//!    segments join them: from the bottom of one shape along the wall to the bottom of the
//!    next. Every junction is tangent in the domain, and S is C¹, so the path is C¹.
//! 5. **Ends.** The path starts with the tool wholly past the open side (u = 0), in the air
//!    over the floor's tangent continuation, and cuts in; past an open u = 1 it runs out into
//!    the air again; before a wall at u = 1 the last shapes' fronts turn into rounded
//!    rectangles whose corners shrink into the pocket's corners, the Hausdorff distance of two
//!    of them being `(r − r′)(√2 − 1)`.
//! 6. **Orientation (§2.3).** The axis is the case's field (V = T − S, or the normal) at the
//!    point where the axis meets the floor; for a tapered tool it is turned by the taper angle
//!    q away from the nearest wall at the wall, by `q (d₂ − d₁)/(d₂ + d₁)` between (d₁, d₂
//!    the distances to the nearest and second-nearest wall), 0 on the bisector.
//! 7. **The tool on the floor.** It is lowered along its axis until it rests on the floor
//!    ([`place`]); the heights are smoothed along the path over ±0.5 mm, never below the
//!    floor, so that the kink where a flat bottom tilts through the normal is not a corner.
//! 8. **Checked.** Every position is checked against the walls (cutter, shank and holder);
//!    where one is closer than half the margin the offset there grows by the deficit and the
//!    path is built again. Turns between moves above 2° are split (down to 0.02 mm moves).
//!
//! Links: one rapid from above the start (clearance over T along the axis) down to the start,
//! in the air past the open side, and one rapid retract along the axis at the end.

mod check;
mod geodesic;
mod place;

pub use check::{FiveCheck, check};

use crate::error::{Error, Result};
use crate::geom::nurbs::SurfacePoint;
use crate::geom::{DVec2, DVec3};
use crate::model::five::{Boundary, CutterKind, FiveJob, Side};
use crate::post::five::AxisMove;
use geodesic::{DistanceMap, Lattice, Reading};
use place::{FloorGrid, Profile, WallCloud, dist_polyline, polyline_len};
use rayon::prelude::*;
use std::f64::consts::{FRAC_PI_2, PI};

/// Options of 5-axis pocketing.
#[derive(Debug, Clone, PartialEq)]
pub struct FiveOptions {
    /// The back of each shape as a fraction of its front's radius: 1 a full circle (Fig. 1),
    /// less the cut-back shape of Fig. 2(c).
    pub back: f64,
    /// The least clearance kept between the tool and a wall, mm.
    pub margin: f64,
}

impl FiveOptions {
    /// What is wrong with the options, if anything.
    pub fn validate(&self) -> std::result::Result<(), String> {
        if !(self.back >= 0.05 && self.back <= 1.0) {
            return Err(format!("{}: the back of a shape must be from 0.05 to 1 of its front", self.back));
        }
        if !(self.margin > 0.0 && self.margin <= 1.0) {
            return Err(format!("{}: the wall margin must be above 0 and at most 1 mm", self.margin));
        }
        Ok(())
    }
}

impl Default for FiveOptions {
    fn default() -> Self {
        FiveOptions { back: 0.5, margin: 0.03 }
    }
}

/// A planned 5-axis pocketing path.
#[derive(Debug, Clone)]
pub struct FivePlan {
    /// The moves: a rapid to the start over the top, one C¹ cut, a rapid retract.
    pub moves: Vec<AxisMove>,
    /// The floor's parameters (u, v) of each move (the links' are those of the cut's end).
    pub params: Vec<DVec2>,
    /// The same points in the domain before the variable offset (the rounded shapes as placed
    /// between the walls themselves), in the original job's (u, v).
    pub before: Vec<DVec2>,
    /// How many rounded shapes the cut has.
    pub shapes: usize,
    /// The rounded shape each move belongs to (with the bridge that follows it).
    pub shape_of: Vec<u32>,
    /// The least clearance of the tool from a wall over the cut, mm (infinite without walls).
    pub wall_clearance: f64,
    /// The floor's stretch bounds (a_min, a_max) over the domain.
    pub stretch: (f64, f64),
    /// The offset domain's scale: its length and width, mm.
    pub scale: (f64, f64),
}

/// The job turned so that u = 0 is open (the paper's convention), and how to undo it.
pub struct Canon {
    /// The turned job.
    pub job: FiveJob,
    /// u and v were exchanged.
    pub transposed: bool,
    /// u was reversed (after any exchange).
    pub reversed: bool,
}

impl Canon {
    /// `job` turned so that its side u = 0 is open; an error when no side is.
    pub fn of(job: &FiveJob) -> Result<Canon> {
        let open = |s: Side| matches!(job.boundary(s), Boundary::Open);
        let (transposed, reversed) = if open(Side::U0) {
            (false, false)
        } else if open(Side::U1) {
            (false, true)
        } else if open(Side::V0) {
            (true, false)
        } else if open(Side::V1) {
            (true, true)
        } else {
            return Err(Error::job(
                "boundaries",
                "every side is a wall: 5-axis pocketing enters from an open side, and this pocket has none",
            ));
        };
        let mut j = job.clone();
        if transposed {
            j.floor = j.floor.transposed();
            j.top = j.top.transposed();
            let b = job.boundaries.clone();
            // (a wall's own surface runs along its side in the floor's parameter, which the
            // exchange keeps)
            j.boundaries = [b[2].clone(), b[3].clone(), b[0].clone(), b[1].clone()];
        }
        if reversed {
            j.floor = j.floor.reversed_u();
            j.top = j.top.reversed_u();
            let b = j.boundaries.clone();
            let flip = |w: &Boundary| match w {
                Boundary::Wall(Some(s)) => Boundary::Wall(Some(s.reversed_u())),
                other => other.clone(),
            };
            j.boundaries = [b[1].clone(), b[0].clone(), flip(&b[2]), flip(&b[3])];
        }
        Ok(Canon { job: j, transposed, reversed })
    }

    /// The original job's (u, v) of the turned job's (u, v).
    pub fn original(&self, p: DVec2) -> DVec2 {
        let p = if self.reversed { DVec2::new(1.0 - p.x, p.y) } else { p };
        if self.transposed { DVec2::new(p.y, p.x) } else { p }
    }

    fn is_wall(&self, s: Side) -> bool {
        !matches!(self.job.boundary(s), Boundary::Open)
    }
}

/// The floor at (u, v), continued past the unit square as its tangent plane (C¹ across the
/// edge): the point and its first derivatives (the second are those at the edge).
pub fn at_floor(job: &FiveJob, u: f64, v: f64) -> SurfacePoint {
    let (cu, cv) = (u.clamp(0.0, 1.0), v.clamp(0.0, 1.0));
    let mut s = job.floor.eval(cu, cv);
    s.p += s.su * (u - cu) + s.sv * (v - cv);
    s
}

/// The axis field at (u, v). Past an open side, within `reach` (in the parameter: the tool's
/// radius and a millimetre), the floor's and top's edge spans are continued as polynomials and
/// the field is taken from them, as a checker evaluating the surfaces past the edge does (the
/// tool there still stands partly over the floor); farther out, where the tool is wholly in the
/// air, it stays as it is at that distance (continued surfaces turn over within a shape's width
/// of a curved edge). Past a wall it is the wall's edge value.
pub fn field_at(job: &FiveJob, u: f64, v: f64, reach: DVec2) -> DVec3 {
    let open = |s: Side| matches!(job.boundary(s), Boundary::Open);
    let lim = |x: f64, lo: Side, hi: Side, r: f64| {
        x.clamp(if open(lo) { -r } else { 0.0 }, if open(hi) { 1.0 + r } else { 1.0 })
    };
    let (u, v) = (lim(u, Side::U0, Side::U1, reach.x), lim(v, Side::V0, Side::V1, reach.y));
    if (0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v) {
        return job.axis_field(u, v);
    }
    let s = job.floor.eval_continued(u, v);
    let n = s.normal();
    let up = job.top.eval_continued(u, v).p - s.p;
    let n = if n.dot(up) < 0.0 { -n } else { n };
    match job.axis {
        crate::model::five::AxisRule::Normal => n,
        crate::model::five::AxisRule::Field => {
            if up.length() > 1e-12 {
                up.normalize()
            } else {
                n
            }
        }
    }
}

/// A smooth function of one parameter: a uniform cubic B-spline over samples (C²), its value
/// at a sample's place at least the least of the four nearest samples.
#[derive(Debug, Clone)]
struct Smooth {
    t0: f64,
    h: f64,
    c: Vec<f64>,
}

impl Smooth {
    fn eval(&self, t: f64) -> f64 {
        let s = (t - self.t0) / self.h;
        let i = s.floor();
        let f = s - i;
        let n = self.c.len() as isize;
        let c = |k: isize| self.c[k.clamp(0, n - 1) as usize];
        let i = i as isize;
        let f2 = f * f;
        let f3 = f2 * f;
        (c(i - 1) * (1.0 - f).powi(3)
            + c(i) * (3.0 * f3 - 6.0 * f2 + 4.0)
            + c(i + 1) * (-3.0 * f3 + 3.0 * f2 + 3.0 * f + 1.0)
            + c(i + 2) * f3)
            / 6.0
    }
}

/// The wall offsets, mm on the floor, as functions of the place along the wall (the floor's
/// u along v = 0 and v = 1, its v along u = 1).
struct Offsets {
    /// Required offsets at the samples (before smoothing), per side V0, V1, U1.
    need: [Vec<f64>; 3],
    smooth: [Smooth; 3],
}

/// The most points a path may have (about 300 MB of CL file).
const MAX_POINTS: usize = 5_000_000;

/// Samples along a wall for its offset.
const OFFSET_SAMPLES: usize = 96;

impl Offsets {
    fn new(need: [Vec<f64>; 3]) -> Offsets {
        let smooth = need.clone().map(|n| {
            // each control point the greatest need within two samples, so that the spline,
            // a blend of four neighbours, is at least the need at every sample
            let m = n.len();
            let c: Vec<f64> = (0..m)
                .map(|k| (k.saturating_sub(2)..(k + 3).min(m)).map(|j| n[j]).fold(f64::NEG_INFINITY, f64::max))
                .collect();
            Smooth { t0: 0.0, h: 1.0 / (m - 1) as f64, c }
        });
        Offsets { need, smooth }
    }
}

/// Everything planning needs about the pocket.
struct Pocket {
    canon: Canon,
    prof: Profile,
    floor: FloorGrid,
    walls: WallCloud,
    /// Each wall's base curve (its floor edge), sampled.
    bases: Vec<(Side, Vec<DVec3>)>,
    taper: f64,
    /// How far past an open side the field follows the continued surfaces, in u and v.
    reach: DVec2,
    /// The geodesic distance from each side, in `Side::ALL`'s order.
    maps: [DistanceMap; 4],
}

impl Pocket {
    /// The tool placed with its axis through o = S(u, v): o, the axis, and how far along the
    /// axis from o the tip is when the tool rests on the floor.
    fn place(&self, u: f64, v: f64) -> (DVec3, DVec3, f64) {
        let job = &self.canon.job;
        let sp = at_floor(job, u, v);
        let o = sp.p;
        let mut a = field_at(job, u, v, self.reach);
        if self.taper > 0.0 && !self.bases.is_empty() {
            let mut d: Vec<(f64, Side)> = self.bases.iter().map(|(s, b)| (dist_polyline(o, b), *s)).collect();
            d.sort_by(|x, y| x.0.total_cmp(&y.0));
            let (d1, s1) = d[0];
            let m = match d.get(1) {
                Some(&(d2, _)) if d1 + d2 > 1e-12 => (d2 - d1) / (d2 + d1),
                Some(_) => 0.0,
                None => 1.0,
            };
            // away from the wall: into the pocket across it
            let inward = s1.inward(&sp);
            let dir = (inward - a * inward.dot(a)).normalize_or_zero();
            let phi = self.taper * m;
            a = (a * phi.cos() + dir * phi.sin()).normalize();
        }
        let lam = self.floor.drop(&self.canon, &self.prof, u, v, o, a);
        // (a hair above the floor, for the refinement's last digits)
        (o, a, lam + 0.002)
    }

    /// The geodesic distance map of `side`.
    fn map(&self, side: Side) -> &DistanceMap {
        &self.maps[side_index(side)]
    }

    /// The four maps read at `p`, in `Side::ALL`'s order (u0, u1, v0, v1).
    fn read(&self, p: DVec2) -> [Reading; 4] {
        self.maps.each_ref().map(|m| m.at(p))
    }

    /// The pocket's two geodesic coordinates at `p` and their gradients ([`coords_of`]).
    fn coords(&self, p: DVec2, k: DVec2) -> (DVec2, DVec2, DVec2) {
        coords_of(&self.read(p), k)
    }

    /// `out` moved along the line of its across coordinate (weights `k`) to where the along
    /// coordinate is `along`: the end wall's push, after the side walls' pushes took the point
    /// to `out`.
    fn slide(&self, k: DVec2, out: DVec2, along: f64) -> DVec2 {
        self.solve(out, k, DVec2::new(self.coords(out, k).0.x, along))
    }

    /// The point near `start` where the coordinates weighted by `k` are `target`: three Newton
    /// steps on the two distance equations, so that a point moved from a wall by an offset
    /// lands that far from it, also in a corner where two walls meet at any angle.
    fn solve(&self, start: DVec2, k: DVec2, target: DVec2) -> DVec2 {
        let mut q = start;
        for _ in 0..3 {
            let (c, ga, gb) = self.coords(q, k);
            let r = target - c;
            let det = ga.x * gb.y - ga.y * gb.x;
            let step = DVec2::new(r.x * gb.y - ga.y * r.y, ga.x * r.y - gb.x * r.x) / det;
            // (the maps are read within their grid, which holds every point the path reaches)
            if !(step.is_finite() && step.length() < 1.0) {
                break;
            }
            q += step;
        }
        q
    }

    /// The least offset, mm, from the wall `side` at `s` along it that keeps the tool `margin`
    /// clear of that wall, and the foot on that wall of where the tool then stands. The end
    /// wall's is measured where [`Layout::to_floor`] puts the point: after the side walls'
    /// pushes (`layout`), along the line they leave it on.
    fn need(&self, side: Side, s: f64, margin: f64, layout: Option<&Layout>) -> Result<(f64, f64)> {
        let p0 = side.at(s);
        let (r0, sp0) = (self.read(p0), at_floor(&self.canon.job, p0.x, p0.y));
        let step = unit_step(&sp0, r0[side_index(side)].grad);
        let k = shares_of(&r0);
        let along = coords_of(&r0, k).0.y;
        let base = layout.map_or(p0, |l| l.across(self, p0, &sp0, &r0, k, None));
        let to = |t: f64| if side == Side::U1 { self.slide(k, base, along - t) } else { p0 + step * t };
        let foot = |t: f64| if side == Side::U1 { self.map(side).at(to(t)).foot } else { s };
        let clear = |t: f64| {
            let p = to(t);
            let (o, a, lam) = self.place(p.x, p.y);
            let tip = o + a * lam;
            self.walls.clearance(&self.prof, tip, a, Some(side)).0
        };
        if clear(0.0) >= margin {
            return Ok((foot(0.0), 0.0));
        }
        let hi = 0.45 * self.map(side.opposite()).at(p0).d;
        if hi.is_nan() || hi <= 0.0 || clear(hi) < margin {
            let p = to(hi.max(0.0));
            return Err(Error::job(
                "tool",
                format!(
                    "the tool (cutter, shank or holder) cannot stand clear of the wall {} near (u, v) = ({:.3}, {:.3}): the pocket is too narrow for it, its stick-out too short, or the axis leans into the wall",
                    side.key(),
                    p.x,
                    p.y
                ),
            ));
        }
        let (mut lo, mut hi) = (0.0, hi);
        for _ in 0..18 {
            let mid = 0.5 * (lo + hi);
            if clear(mid) >= margin { hi = mid } else { lo = mid }
        }
        Ok((foot(hi), hi))
    }
}

/// The index of `side` in `Side::ALL` (and in the pocket's maps).
fn side_index(side: Side) -> usize {
    Side::ALL.iter().position(|s| *s == side).expect("a side")
}

/// The pocket's two geodesic coordinates and their gradients from the maps' readings `r` at a
/// point, with weights `k` (the share of the v0 side and the share of the u0 side, held fixed
/// while a point moves): across, `k.x d(v0) − (1 − k.x) d(v1)`, and along,
/// `k.y d(u0) − (1 − k.y) d(u1)` (signed distances, mm). Each grows by a millimetre when a
/// point moves a millimetre away from the first side of its pair; near one side it is (plus
/// or minus) the distance from that side alone, whatever the angle of the other.
fn coords_of(r: &[Reading; 4], k: DVec2) -> (DVec2, DVec2, DVec2) {
    let [u0, u1, v0, v1] = r;
    (
        DVec2::new(k.x * v0.d - (1.0 - k.x) * v1.d, k.y * u0.d - (1.0 - k.y) * u1.d),
        v0.grad * k.x - v1.grad * (1.0 - k.x),
        u0.grad * k.y - u1.grad * (1.0 - k.y),
    )
}

/// Each side's share of a point against its opposite side, from the maps' readings `r` there:
/// `d(v1) / (d(v0) + d(v1))` for v0, `d(u1) / (d(u0) + d(u1))` for u0 (1 on the side, 0 on
/// the opposite one).
fn shares_of(r: &[Reading; 4]) -> DVec2 {
    let [u0, u1, v0, v1] = r.map(|x| x.d);
    DVec2::new(v1 / (v0 + v1).max(1e-9), u1 / (u0 + u1).max(1e-9))
}

/// The parameter step at `sp` that moves one millimetre on the floor along the gradient
/// `grad` (mm per unit of u, v) of a distance: G⁻¹∇d over its length in the metric G.
fn unit_step(sp: &SurfacePoint, grad: DVec2) -> DVec2 {
    let (e, f, g) = (sp.su.dot(sp.su), sp.su.dot(sp.sv), sp.sv.dot(sp.sv));
    let det = (e * g - f * f).max(1e-300);
    let x = DVec2::new(g * grad.x - f * grad.y, e * grad.y - f * grad.x) / det;
    x / grad.dot(x).max(1e-300).sqrt()
}

/// A piece of the path in the scaled offset domain (x along, y across, mm).
#[derive(Debug, Clone, Copy)]
enum Piece {
    Line(DVec2, DVec2),
    /// centre, radii (x, y), angles from and to
    Ellipse(DVec2, DVec2, f64, f64),
}

impl Piece {
    fn at(&self, t: f64) -> DVec2 {
        match *self {
            Piece::Line(a, b) => a.lerp(b, t),
            Piece::Ellipse(c, r, t0, t1) => {
                let th = t0 + (t1 - t0) * t;
                c + DVec2::new(r.x * th.cos(), r.y * th.sin())
            }
        }
    }

    /// Parameters along the piece, from 0 to 1 (0 left out), steps of at most `len` and a
    /// turn of at most `ang` radians.
    fn samples(&self, len: f64, ang: f64) -> Vec<f64> {
        match *self {
            Piece::Line(a, b) => {
                let n = ((a - b).length() / len).ceil().max(1.0) as usize;
                (1..=n).map(|k| k as f64 / n as f64).collect()
            }
            Piece::Ellipse(_, r, t0, t1) => {
                let span = t1 - t0;
                let mut out = Vec::new();
                let mut t = 0.0;
                while t < 1.0 {
                    let th = t0 + span * t;
                    let (s, c) = th.sin_cos();
                    let speed = (r.x * r.x * s * s + r.y * r.y * c * c).sqrt();
                    let rate = r.x * r.y / (speed * speed).max(1e-300);
                    let dth = (ang / rate).min(len / speed.max(1e-300));
                    t = (t + dth / span.abs()).min(1.0);
                    if 1.0 - t < 1e-3 {
                        t = 1.0;
                    }
                    out.push(t);
                }
                out
            }
        }
    }
}

/// The plan's domain layout: scale and offsets.
struct Layout {
    /// Length and width of the scaled domain, mm.
    x_len: f64,
    w: f64,
    offsets: Offsets,
    walls: [bool; 3],
}

impl Layout {
    /// The floor's (u, v) of the scaled domain's (x, y) before the offset: u = x / length, and
    /// v where the share `d(v0) / (d(v0) + d(v1))` of the geodesic distances across is
    /// y / width. The domain's centre line is so the geodesic bisector of the two sides, the
    /// medial axis of the strip between them, and the shapes centred on it are maximal.
    fn domain(&self, pocket: &Pocket, q: DVec2) -> DVec2 {
        let (u, t) = (q.x / self.x_len, q.y / self.w);
        let (m0, m1) = (pocket.map(Side::V0), pocket.map(Side::V1));
        // (Newton's method along v: the share is smooth and rises across the strip)
        let mut v = t;
        for _ in 0..4 {
            let (a, b) = (m0.at(DVec2::new(u, v)), m1.at(DVec2::new(u, v)));
            let sum = a.d + b.d;
            if sum.abs() < 1e-9 {
                break;
            }
            let share = a.d / sum;
            let slope = (a.grad.y * sum - a.d * (a.grad.y + b.grad.y)) / (sum * sum);
            let step = (t - share) / slope;
            if !(step.is_finite() && step.abs() < 1.0) {
                break;
            }
            v += step;
        }
        DVec2::new(u, v)
    }

    /// The floor's (u, v) of the scaled domain's (x, y): its point before the offset
    /// ([`Layout::domain`]) moved by the variable offset (§2.2).
    ///
    /// Each side wall pushes a point straight away from it (along its distance's gradient) by
    /// the wall's offset at the point's foot (its nearest point on the wall) times the point's
    /// share `d′ / (d + d′)` of the geodesic distances to that wall (d) and the opposite side
    /// (d′): the full offset on the wall, less inside, half at the bisector (where opposite
    /// walls' pushes cancel), nothing on an open opposite side. A wall at u = 1 then moves the
    /// point along the line of the pocket's across coordinate it was pushed onto
    /// ([`Pocket::coords`]) to where its own push (the same rule) puts it, so that in a corner
    /// the point stands off both walls by their offsets whatever their angle. The offsets are
    /// read at the feet of where the point ends, found by a second pass. The distances and
    /// their gradients are smooth, and so is this map, which keeps the path C¹.
    fn to_floor(&self, pocket: &Pocket, q: DVec2) -> DVec2 {
        let p = self.domain(pocket, q);
        let r = pocket.read(p);
        let sp = at_floor(&pocket.canon.job, p.x, p.y);
        let k = shares_of(&r);
        let out = self.across(pocket, p, &sp, &r, k, None);
        if !self.walls[2] {
            return out;
        }
        let along = coords_of(&r, k).0.y;
        let mut at = out;
        for pass in 0..2 {
            let base = if pass == 0 { out } else { self.across(pocket, p, &sp, &r, k, Some(at)) };
            let push = self.offsets.smooth[2].eval(pocket.map(Side::U1).at(at).foot) * (1.0 - k.y);
            at = pocket.slide(k, base, along - push);
        }
        at
    }

    /// `p` pushed by the side walls, with the floor `sp`, the maps' readings `r` and the
    /// shares `k` at `p`; their offsets read at the feet of `at` (where the point ends), or
    /// of `p`.
    fn across(
        &self,
        pocket: &Pocket,
        p: DVec2,
        sp: &SurfacePoint,
        r: &[Reading; 4],
        k: DVec2,
        at: Option<DVec2>,
    ) -> DVec2 {
        let mut out = p;
        for (i, side, share) in [(0, Side::V0, k.x), (1, Side::V1, 1.0 - k.x)] {
            if self.walls[i] {
                let ri = &r[side_index(side)];
                let foot = at.map_or(ri.foot, |a| pocket.map(side).at(a).foot);
                out += unit_step(sp, ri.grad) * (self.offsets.smooth[i].eval(foot) * share);
            }
        }
        out
    }
}

/// Plans the pocketing of `job`.
pub fn plan(job: &FiveJob, opts: &FiveOptions) -> Result<FivePlan> {
    let canon = Canon::of(job)?;
    let j = &canon.job;
    let prof = Profile::of(&j.tool);
    let r = prof.radius();
    opts.validate().map_err(|e| Error::job("options", e))?;
    // the floor's size: mean length along u and width across, greatest stretches
    let iso_u = |v: f64| polyline_len((0..=128).map(|i| j.floor.eval(i as f64 / 128.0, v).p));
    let iso_v = |u: f64| polyline_len((0..=64).map(|i| j.floor.eval(u, i as f64 / 64.0).p));
    let x_len = (0..5).map(|k| iso_u(0.1 + 0.2 * k as f64)).sum::<f64>() / 5.0;
    let w = (0..9).map(|k| iso_v(0.1 + 0.1 * k as f64)).sum::<f64>() / 9.0;
    let (mut su_max, mut sv_max, mut su_min, mut sv_min) = (0.0f64, 0.0f64, f64::INFINITY, f64::INFINITY);
    for i in 0..=32 {
        for k in 0..=32 {
            let s = j.floor.eval(i as f64 / 32.0, k as f64 / 32.0);
            su_max = su_max.max(s.su.length());
            sv_max = sv_max.max(s.sv.length());
            su_min = su_min.min(s.su.length());
            sv_min = sv_min.min(s.sv.length());
        }
    }
    if !(x_len > 1e-6 && w > 1e-6 && su_min > 1e-9 && sv_min > 1e-9) {
        return Err(Error::job("floor", "the floor is degenerate (no length or no width)"));
    }
    let stretch = j.floor.stretch_bounds(33);
    let walls = [canon.is_wall(Side::V0), canon.is_wall(Side::V1), canon.is_wall(Side::U1)];
    // the floor grid: past the open sides as far as the path goes (a shape's width and the tool)
    let reach_u = (2.0 * w + 2.0 * r + 4.0) / su_min;
    let ulo = -reach_u;
    let uhi = if walls[2] { 1.0 } else { 1.0 + reach_u };
    let vext = (r + 2.0) / sv_max.max(1e-9) * 2.0;
    let vlo = if walls[0] { 0.0 } else { -vext };
    let vhi = if walls[1] { 1.0 } else { 1.0 + vext };
    let floor = FloorGrid::new(&canon, (ulo, uhi), (vlo, vhi), su_max, sv_max);
    let walls_cloud = WallCloud::new(&canon);
    let bases: Vec<(Side, Vec<DVec3>)> = Side::ALL
        .into_iter()
        .filter(|s| canon.is_wall(*s))
        .map(|s| {
            (
                s,
                (0..=400)
                    .map(|i| {
                        let b = s.at(i as f64 / 400.0);
                        j.floor.eval(b.x, b.y).p
                    })
                    .collect(),
            )
        })
        .collect();
    let taper = if j.tool.kind == CutterKind::Tapered { j.tool.taper_deg.to_radians() } else { 0.0 };
    let stepover = j.stepover;
    let reach = DVec2::new((r + 1.0) / su_min, (r + 1.0) / sv_min);
    // the geodesic distance maps from the sides, over the floor grid's span, about 0.4 mm apart
    let (mut per_u, mut per_v) = ((su_max / 0.4).ceil().max(8.0), (sv_max / 0.4).ceil().max(8.0));
    // (past the walls too, as far as the planner looks)
    let (lu, hu) = (ulo, uhi.max(1.0 + (2.0 * r + 4.0) / su_min));
    let (lv, hv) = (vlo.min(-(r + 2.0) / sv_min), vhi.max(1.0 + (r + 2.0) / sv_min));
    let nodes = per_u * (hu - lu) * per_v * (hv - lv);
    if nodes > 400_000.0 {
        let f = (400_000.0 / nodes).sqrt();
        (per_u, per_v) = ((per_u * f).ceil(), (per_v * f).ceil());
    }
    let lattice = Lattice::new((lu, hu), (lv, hv), per_u as usize, per_v as usize, |u, v| at_floor(&canon.job, u, v).p);
    let maps: Vec<DistanceMap> = Side::ALL.par_iter().map(|s| DistanceMap::from_side(&lattice, *s)).collect();
    let maps: [DistanceMap; 4] = maps.try_into().map_err(|_| Error::job("floor", "four sides"))?;
    log::debug!("five: distance maps over {} nodes ({per_u} × {per_v} per unit)", lattice.len());
    let pocket = Pocket { canon, prof, floor, walls: walls_cloud, bases, taper, reach, maps };

    // 1. the offsets each wall needs, sampled along it
    let sides = [Side::V0, Side::V1, Side::U1];
    let mut need: [Vec<f64>; 3] =
        [vec![0.0; OFFSET_SAMPLES + 1], vec![0.0; OFFSET_SAMPLES + 1], vec![0.0; OFFSET_SAMPLES + 1]];
    // (the side walls' first: the end wall's are measured after their pushes)
    let mut layout = Layout { x_len, w, offsets: Offsets::new(need.clone()), walls };
    for (k, side) in sides.iter().enumerate() {
        if !walls[k] {
            continue;
        }
        if k == 2 {
            layout.offsets = Offsets::new(need.clone());
        }
        let at: Vec<(f64, f64)> = (0..=OFFSET_SAMPLES)
            .into_par_iter()
            .map(|i| pocket.need(*side, i as f64 / OFFSET_SAMPLES as f64, opts.margin, (k == 2).then_some(&layout)))
            .collect::<Result<Vec<_>>>()?;
        need[k] = resample(&at);
    }
    for (k, n) in need.iter().enumerate() {
        log::debug!(
            "five: offsets {:?}: {:?}",
            sides[k],
            n.iter().step_by(8).map(|x| (x * 1000.0).round() / 1000.0).collect::<Vec<_>>()
        );
    }
    layout.offsets = Offsets::new(need);

    let mut last = None;
    for _round in 0..5 {
        let built = build(&pocket, &layout, stepover, opts)?;
        // 7. the walls: grow the offset where the tool comes too close
        let mut grown = false;
        let mut need = layout.offsets.need.clone();
        // (the greatest deficit at each sample, added once)
        let mut deficits =
            [vec![0.0f64; OFFSET_SAMPLES + 1], vec![0.0f64; OFFSET_SAMPLES + 1], vec![0.0f64; OFFSET_SAMPLES + 1]];
        for (k, pt) in built.pts.iter().enumerate() {
            let (c, side) = built.clear[k];
            if c >= 0.5 * opts.margin {
                continue;
            }
            let Some(side) = side else { continue };
            let Some(w) = sides.iter().position(|s| *s == side) else { continue };
            let along = pocket.map(side).at(pt.uv).foot;
            let deficit = (opts.margin - c) * 1.3 + 1e-4;
            let i = (along.clamp(0.0, 1.0) * OFFSET_SAMPLES as f64).round() as usize;
            for d in deficits[w].iter_mut().take((i + 2).min(OFFSET_SAMPLES) + 1).skip(i.saturating_sub(2)) {
                *d = d.max(deficit);
            }
            grown = true;
        }
        for (n, d) in need.iter_mut().zip(&deficits) {
            for (a, b) in n.iter_mut().zip(d) {
                *a += b;
            }
        }
        if grown {
            let worst = built
                .clear
                .iter()
                .enumerate()
                .min_by(|a, b| a.1.0.total_cmp(&b.1.0))
                .map(|(k, c)| (k, c.0, c.1, built.pts[k].uv, built.pts[k].before));
            log::debug!("five: round {_round}: too close to a wall, worst {worst:?}");
        }
        // (the offsets against the width across, at each sample)
        let crowded = (0..=OFFSET_SAMPLES).any(|i| {
            let s = i as f64 / OFFSET_SAMPLES as f64;
            let across = pocket.map(Side::V1).at(Side::V0.at(s)).d;
            let along = pocket.map(Side::U0).at(Side::U1.at(s)).d;
            need[0][i] + need[1][i] > 0.9 * across || need[2][i] > 0.9 * along
        });
        if crowded {
            return Err(Error::job(
                "tool",
                "the tool cannot stand clear of the walls anywhere across the pocket: it is too wide, or the axis leans into the walls",
            ));
        }
        last = Some(built);
        if !grown {
            break;
        }
        layout.offsets = Offsets::new(need);
    }
    let built = last.expect("one round at least");
    Ok(finish(&pocket, &layout, built, stretch))
}

/// Values at places along a wall, `(place, value)` in any order, at the offset samples'
/// places: linear between them, held past the ends.
fn resample(at: &[(f64, f64)]) -> Vec<f64> {
    let mut at = at.to_vec();
    at.sort_by(|a, b| a.0.total_cmp(&b.0));
    (0..=OFFSET_SAMPLES)
        .map(|i| {
            let s = i as f64 / OFFSET_SAMPLES as f64;
            let j = at.partition_point(|p| p.0 < s);
            match (j.checked_sub(1).map(|i| at[i]), at.get(j)) {
                (Some(a), Some(b)) if b.0 - a.0 > 1e-12 => a.1 + (b.1 - a.1) * (s - a.0) / (b.0 - a.0),
                (Some(a), _) => a.1,
                (None, Some(b)) => b.1,
                (None, None) => 0.0,
            }
        })
        .collect()
}

/// One point of the cut.
#[derive(Debug, Clone, Copy)]
struct Pt {
    piece: usize,
    t: f64,
    /// The point in the domain before the offset, (x / length, y / width).
    before: DVec2,
    uv: DVec2,
    o: DVec3,
    lam: f64,
    tip: DVec3,
    axis: DVec3,
}

/// The half-width of the window over which the tip's height along the axis is smoothed, mm.
const SMOOTH_HALF: f64 = 0.5;

/// Smooths the tips' heights over the floor along the path: a tool resting on the floor has a
/// kink in its height wherever its contact jumps (a flat bottom tilting through the floor's
/// normal), which would be a corner in the path. Each height becomes the greatest within
/// `SMOOTH_HALF` along the path, then the tent-weighted mean of those over the same window;
/// every one of them is at least the height there, so the tool never sinks below the floor,
/// and it rises where the floor has a kink by about a quarter of the window times the change
/// of slope (a few micrometres).
fn smooth_heights(pts: &mut [Pt]) {
    let n = pts.len();
    let mut s = vec![0.0; n];
    for k in 1..n {
        s[k] = s[k - 1] + (pts[k].o - pts[k - 1].o).length();
    }
    // the greatest within the window (two pointers over a monotone deque)
    let mut hi = vec![0.0; n];
    let mut dq: std::collections::VecDeque<usize> = std::collections::VecDeque::new();
    let mut right = 0;
    for k in 0..n {
        while right < n && s[right] <= s[k] + SMOOTH_HALF {
            while dq.back().is_some_and(|&b| pts[b].lam <= pts[right].lam) {
                dq.pop_back();
            }
            dq.push_back(right);
            right += 1;
        }
        while dq.front().is_some_and(|&f| s[f] < s[k] - SMOOTH_HALF) {
            dq.pop_front();
        }
        hi[k] = pts[*dq.front().expect("k itself")].lam;
    }
    let mut lo = 0;
    let mut right = 0;
    for k in 0..n {
        while s[lo] < s[k] - SMOOTH_HALF {
            lo += 1;
        }
        while right + 1 < n && s[right + 1] <= s[k] + SMOOTH_HALF {
            right += 1;
        }
        let (mut sum, mut wsum) = (0.0, 0.0);
        for j in lo..=right.max(k) {
            let w = (SMOOTH_HALF - (s[j] - s[k]).abs()).max(0.0) + 1e-9;
            sum += w * hi[j];
            wsum += w;
        }
        let p = &mut pts[k];
        p.tip = p.o + p.axis * (sum / wsum);
    }
}

struct Built {
    pts: Vec<Pt>,
    /// The shape of each piece.
    piece_shape: Vec<u32>,
    clear: Vec<(f64, Option<Side>)>,
    shapes: usize,
}

/// Builds the cut for `layout`: shapes, bridges, samples, placements and clearances.
fn build(pocket: &Pocket, layout: &Layout, stepover: f64, opts: &FiveOptions) -> Result<Built> {
    let j = &pocket.canon.job;
    let (x_len, w) = (layout.x_len, layout.w);
    let rho = 0.5 * w;
    let r = pocket.prof.radius();
    let m = |q: DVec2| {
        let uv = layout.to_floor(pocket, q);
        at_floor(j, uv.x, uv.y).p
    };
    // the stretch along x, the greatest over each column of the domain
    let x_lo = -(2.0 * rho + 2.0 * r + 3.0);
    // (past a wall at u = 1 only as far as the last shapes look: the path stops at it)
    let x_hi = if layout.walls[2] { x_len + 1.5 } else { x_len + 2.0 * r + 3.0 };
    let col = 0.5;
    let ncol = ((x_hi - x_lo) / col).ceil() as usize + 1;
    // (and the greatest stretch in any direction, for shapes that change other than by a step)
    let (sx, sa): (Vec<f64>, Vec<f64>) = (0..ncol)
        .into_par_iter()
        .map(|c| {
            let x = x_lo + col * c as f64;
            (0..=16)
                .map(|k| {
                    let y = w * k as f64 / 16.0;
                    let h = 0.05;
                    let mx = (m(DVec2::new(x + h, y)) - m(DVec2::new(x - h, y))) / (2.0 * h);
                    let my = (m(DVec2::new(x, y + h)) - m(DVec2::new(x, y - h))) / (2.0 * h);
                    // the greatest singular value of [mx my]
                    let (e, f, g) = (mx.dot(mx), mx.dot(my), my.dot(my));
                    let big = (0.5 * (e + g) + (0.25 * (e - g) * (e - g) + f * f).sqrt()).sqrt();
                    (mx.length(), big)
                })
                .fold((0.0f64, 0.0f64), |a, b| (a.0.max(b.0), a.1.max(b.1)))
        })
        .unzip();
    let over = |v: &[f64], a: f64, b: f64| -> f64 {
        let c0 = (((a - x_lo) / col).floor().max(0.0) as usize).min(ncol - 1);
        let c1 = (((b - x_lo) / col).ceil().max(0.0) as usize).min(ncol - 1);
        v[c0..=c1].iter().copied().fold(1e-9, f64::max)
    };
    let sx_over = |a: f64, b: f64| over(&sx, a, b);
    let target = 0.8 * stepover;
    // 2–3. shape positions: out past the open side, in steps the stretch allows
    let at0 = sx_over(-1.0, 1.0);
    let mut xs = vec![-rho - (r + 1.0) / at0];
    let end = if layout.walls[2] { x_len - rho } else { x_len + (r + 1.0) / sx_over(x_len - 1.0, x_len + 1.0) };
    loop {
        let x = *xs.last().expect("a shape");
        if x >= end - 1e-9 {
            break;
        }
        let mut dx = target / sx_over(x - 1.0, x + rho + 1.0);
        dx = target / sx_over(x - 1.0, x + dx + rho + 1.0);
        if xs.len() > 200_000 {
            return Err(Error::job("stepover", "the pocket needs more than 200 000 shapes at this stepover"));
        }
        xs.push((x + dx).min(end.max(x + 1e-6)));
    }
    // 5. before a wall at u = 1: the fronts' corners shrink
    let mut shapes: Vec<(f64, f64)> = xs.iter().map(|&x| (x, rho)).collect();
    if layout.walls[2] {
        let x = *xs.last().expect("a shape");
        let rmin = rho.min(1.0);
        let mut rk = rho;
        while rk > rmin + 1e-9 {
            let dr = target / over(&sa, x, x + rho + 1.0) / (2f64.sqrt() - 1.0);
            rk = (rk - dr).max(rmin);
            shapes.push((x, rk));
        }
    }
    // 4. the pieces, C¹ at every junction
    let back = opts.back * rho;
    let mut pieces = Vec::new();
    let mut piece_shape = Vec::new();
    for (k, &(xc, rk)) in shapes.iter().enumerate() {
        let first = pieces.len();
        if rk >= rho - 1e-9 {
            pieces.push(Piece::Ellipse(DVec2::new(xc, rho), DVec2::splat(rho), -FRAC_PI_2, FRAC_PI_2));
        } else {
            let e = xc + rho - rk;
            pieces.push(Piece::Line(DVec2::new(xc, 0.0), DVec2::new(e, 0.0)));
            pieces.push(Piece::Ellipse(DVec2::new(e, rk), DVec2::splat(rk), -FRAC_PI_2, 0.0));
            pieces.push(Piece::Line(DVec2::new(xc + rho, rk), DVec2::new(xc + rho, w - rk)));
            pieces.push(Piece::Ellipse(DVec2::new(e, w - rk), DVec2::splat(rk), 0.0, FRAC_PI_2));
            pieces.push(Piece::Line(DVec2::new(e, w), DVec2::new(xc, w)));
        }
        pieces.push(Piece::Ellipse(DVec2::new(xc, rho), DVec2::new(back, rho), FRAC_PI_2, 1.5 * PI));
        if let Some(&(xn, _)) = shapes.get(k + 1)
            && xn > xc + 1e-9
        {
            pieces.push(Piece::Line(DVec2::new(xc, 0.0), DVec2::new(xn, 0.0)));
        }
        piece_shape.extend(std::iter::repeat_n(k as u32, pieces.len() - first));
    }
    let smax = sx.iter().copied().fold(1e-9, f64::max);
    log::debug!(
        "five: {} shapes, {} pieces, stretch along x up to {smax:.3}, w {w:.2}, x_len {x_len:.2}",
        shapes.len(),
        pieces.len()
    );
    let seg = 0.4 / smax;
    let ang = 1.5f64.to_radians();
    let mut pts: Vec<(usize, f64)> = vec![(0, 0.0)];
    for (k, p) in pieces.iter().enumerate() {
        pts.extend(p.samples(seg, ang).into_iter().map(|t| (k, t)));
    }
    let place = |(k, t): (usize, f64)| -> Pt {
        let q = pieces[k].at(t);
        let uv = layout.to_floor(pocket, q);
        let (o, axis, lam) = pocket.place(uv.x, uv.y);
        Pt { piece: k, t, before: layout.domain(pocket, q), uv, o, lam, tip: o + axis * lam, axis }
    };
    if pts.len() > MAX_POINTS {
        return Err(Error::job(
            "stepover",
            format!("the path would have more than {MAX_POINTS} points: the pocket is too large for this stepover"),
        ));
    }
    log::debug!("five: {} points", pts.len());
    let mut placed: Vec<Pt> = pts.par_iter().map(|&p| place(p)).collect();
    smooth_heights(&mut placed);
    // 7. split the sharper turns
    for _ in 0..4 {
        let mut split = vec![false; placed.len()];
        let mut any = false;
        for k in 1..placed.len().saturating_sub(1) {
            let (a, b, c) = (placed[k - 1].tip, placed[k].tip, placed[k + 1].tip);
            let (d0, d1) = (b - a, c - b);
            if d0.length() < 1e-9 || d1.length() < 1e-9 {
                continue;
            }
            // (not below 0.02 mm: the rest is the floor's own kinks, which the smoothing rounds)
            if d0.angle_between(d1) > 2f64.to_radians() && d0.length().min(d1.length()) > 0.02 {
                split[k] = true;
                split[k + 1] = true;
                any = true;
            }
        }
        if !any {
            break;
        }
        let mut want = Vec::new();
        for k in 1..placed.len() {
            if split[k] && placed[k].piece == placed[k - 1].piece {
                let t0 = if placed[k - 1].piece == placed[k].piece { placed[k - 1].t } else { 0.0 };
                want.push((k, (placed[k].piece, 0.5 * (t0 + placed[k].t))));
            } else if split[k] && placed[k].t > 0.0 {
                want.push((k, (placed[k].piece, 0.5 * placed[k].t)));
            }
        }
        let new: Vec<Pt> = want.par_iter().map(|&(_, p)| place(p)).collect();
        let mut out = Vec::with_capacity(placed.len() + new.len());
        let mut wi = 0;
        for (k, p) in placed.iter().enumerate() {
            while wi < want.len() && want[wi].0 == k {
                out.push(new[wi]);
                wi += 1;
            }
            out.push(*p);
        }
        placed = out;
        smooth_heights(&mut placed);
    }
    let clear: Vec<(f64, Option<Side>)> =
        placed.par_iter().map(|p| pocket.walls.clearance(&pocket.prof, p.tip, p.axis, None)).collect();
    Ok(Built { pts: placed, piece_shape, clear, shapes: shapes.len() })
}

/// The moves of the cut, with the links.
fn finish(pocket: &Pocket, layout: &Layout, built: Built, stretch: (f64, f64)) -> FivePlan {
    let j = &pocket.canon.job;
    let feed = j.feed;
    let above = |p: &Pt| {
        let (cu, cv) = (p.uv.x.clamp(0.0, 1.0), p.uv.y.clamp(0.0, 1.0));
        let depth = (j.top.eval(cu, cv).p - j.floor.eval(cu, cv).p).length();
        p.tip + p.axis * (depth + j.clearance)
    };
    let first = built.pts[0];
    let last = *built.pts.last().expect("a point");
    let mut moves = vec![AxisMove { tip: above(&first), axis: first.axis, rapid: true, feed }];
    let c = &pocket.canon;
    let mut params = vec![c.original(first.uv)];
    let mut before = vec![c.original(first.before)];
    moves.push(AxisMove { tip: first.tip, axis: first.axis, rapid: true, feed });
    params.push(c.original(first.uv));
    before.push(c.original(first.before));
    for p in &built.pts[1..] {
        moves.push(AxisMove { tip: p.tip, axis: p.axis, rapid: false, feed });
        params.push(c.original(p.uv));
        before.push(c.original(p.before));
    }
    moves.push(AxisMove { tip: above(&last), axis: last.axis, rapid: true, feed });
    params.push(c.original(last.uv));
    before.push(c.original(last.before));
    let wall_clearance = built.clear.iter().map(|c| c.0).fold(f64::INFINITY, f64::min);
    let sh = |p: &Pt| built.piece_shape[p.piece];
    let mut shape_of = vec![sh(&first), sh(&first)];
    shape_of.extend(built.pts[1..].iter().map(sh));
    shape_of.push(sh(&last));
    FivePlan {
        moves,
        params,
        before,
        shape_of,
        shapes: built.shapes,
        wall_clearance,
        stretch,
        scale: (layout.x_len, layout.w),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::nurbs::NurbsSurface;
    use crate::model::five::{AxisRule, FiveTool, Machine};

    /// A flat floor `len` × `width` at z = 0 (u along x, v along y), the top `h` above it: a
    /// straight channel with vertical walls at v = 0 and v = 1.
    fn flat_channel(len: f64, width: f64, h: f64, tool: FiveTool) -> FiveJob {
        let plane = |z: f64| {
            let k = vec![0.0, 0.0, 1.0, 1.0];
            let p = vec![
                vec![DVec3::new(0.0, 0.0, z), DVec3::new(0.0, width, z)],
                vec![DVec3::new(len, 0.0, z), DVec3::new(len, width, z)],
            ];
            NurbsSurface::new(1, 1, k.clone(), k, p, None).expect("a plane")
        };
        FiveJob {
            name: "flat".into(),
            floor: plane(0.0),
            top: plane(h),
            boundaries: [Boundary::Open, Boundary::Open, Boundary::Wall(None), Boundary::Wall(None)],
            tool,
            axis: AxisRule::Field,
            stepover: 0.5,
            scallop_tol: 0.02,
            wall_band_margin: 0.5,
            clearance: 5.0,
            feed: 1000.0,
            rapid_rate: 5000.0,
            machine: Machine::default(),
        }
    }

    fn ball(d: f64) -> FiveTool {
        FiveTool {
            kind: CutterKind::Ball,
            diameter: d,
            corner_radius: 0.5 * d,
            taper_deg: 0.0,
            flute_length: 20.0,
            shank_diameter: d,
            length: 30.0,
            holder: None,
        }
    }

    #[test]
    fn in_a_skewed_pocket_the_offset_holds_the_tool_off_every_wall_and_into_an_acute_corner() {
        // a flat quadrilateral: v0 from (0, 0) to (40, 0), v1 from (0, 16) to (30, 16), and an
        // end wall u1 from (40, 0) to (30, 16) meeting v0 at 58°: the floor's parameter lines
        // cross u1 and v1 askew, so only a geodesic offset keeps the ball right off them
        let plane = |z: f64| {
            let k = vec![0.0, 0.0, 1.0, 1.0];
            let p = vec![
                vec![DVec3::new(0.0, 0.0, z), DVec3::new(0.0, 16.0, z)],
                vec![DVec3::new(40.0, 0.0, z), DVec3::new(30.0, 16.0, z)],
            ];
            NurbsSurface::new(1, 1, k.clone(), k, p, None).expect("a plane")
        };
        let mut job = flat_channel(40.0, 16.0, 10.0, ball(6.0));
        job.floor = plane(0.0);
        job.top = plane(10.0);
        job.boundaries = [Boundary::Open, Boundary::Wall(None), Boundary::Wall(None), Boundary::Wall(None)];
        let p = plan(&job, &FiveOptions::default()).expect("planned");
        // the distance in the plane from the line through a and b
        let line = |t: DVec3, a: DVec2, b: DVec2| {
            let (d, q) = ((b - a).normalize(), DVec2::new(t.x, t.y) - a);
            (q.x * d.y - q.y * d.x).abs()
        };
        let (a, b) = (DVec2::new(40.0, 0.0), DVec2::new(30.0, 16.0));
        let mut corner = f64::INFINITY;
        let mut near = [f64::INFINITY; 3];
        for m in p.moves.iter().filter(|m| !m.rapid) {
            let d = [m.tip.y, line(m.tip, a, b), 16.0 - m.tip.y];
            // the ball's radius and the margin off each wall, less a hair for the floor's grid
            for (k, dk) in d.iter().enumerate() {
                assert!(*dk >= 3.0 + 0.02, "wall {k}: tip at {:?}, {dk:.3} from it", m.tip);
                near[k] = near[k].min(*dk);
            }
            if m.tip.x > 20.0 {
                corner = corner.min(d[0].max(d[1]));
            }
        }
        // and it reaches each wall, and into the acute corner, not held off farther than the
        // offset needs
        assert!(near.iter().all(|&n| n < 3.3), "nearest to the walls {near:?}");
        assert!(corner < 3.3, "in the corner the tip stays {corner:.3} from one wall");
    }

    #[test]
    fn the_smoothed_offset_is_never_under_the_need_at_a_sample() {
        let need: Vec<f64> = (0..=40).map(|i| if i == 17 { 0.3 } else { 0.1 + 0.001 * i as f64 }).collect();
        let o = Offsets::new([need.clone(), need.clone(), need.clone()]);
        for (i, n) in need.iter().enumerate() {
            assert!(o.smooth[0].eval(i as f64 / 40.0) >= n - 1e-12, "sample {i}");
        }
    }

    #[test]
    fn a_flat_channel_is_cut_flat_clear_of_the_walls_and_c1() {
        let job = flat_channel(40.0, 16.0, 10.0, ball(6.0));
        let p = plan(&job, &FiveOptions::default()).expect("planned");
        let cut: Vec<&AxisMove> = p.moves.iter().filter(|m| !m.rapid).collect();
        // on a flat floor with a vertical field the ball's tip rests on it
        for m in &cut {
            assert!((m.axis - DVec3::Z).length() < 1e-9);
            assert!(m.tip.z > -1e-9 && m.tip.z < 0.01, "tip at z {}", m.tip.z);
            // the walls are at y = 0 and y = 16: the ball stays its radius and the margin away
            assert!(m.tip.y >= 3.0 + 0.02 && m.tip.y <= 13.0 - 0.02, "tip at y {}", m.tip.y);
        }
        // it reaches the walls' band and runs out past both open ends
        let (lo, hi) = cut.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, m| (a.0.min(m.tip.y), a.1.max(m.tip.y)));
        assert!(lo < 3.1 && hi > 12.9, "y from {lo} to {hi}");
        let (x0, x1) = cut.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, m| (a.0.min(m.tip.x), a.1.max(m.tip.x)));
        assert!(x0 < -3.0 && x1 > 43.0, "x from {x0} to {x1}");
        let r = check(&job, &p.moves);
        assert!(r.failures().is_empty(), "{:?}: {r:?}", r.failures());
        assert!(r.max_turn_deg < 3.0);
        // the shapes' fronts step at most the stepover along the channel: the tips crossing
        // the middle line going forward (the fronts) are that close
        let mut fronts: Vec<f64> =
            cut.windows(2).filter(|w| w[0].tip.y < 8.0 && w[1].tip.y >= 8.0).map(|w| w[1].tip.x).collect();
        fronts.sort_by(f64::total_cmp);
        let gaps = fronts.windows(2).map(|w| w[1] - w[0]).filter(|g| *g > 1e-6).fold(0.0, f64::max);
        assert!(gaps <= 0.5 + 1e-6, "fronts {gaps} mm apart");
    }

    #[test]
    fn a_pocket_open_only_at_u1_or_v0_is_turned_and_entered_there() {
        let mut job = flat_channel(30.0, 16.0, 10.0, ball(6.0));
        job.boundaries = [Boundary::Wall(None), Boundary::Open, Boundary::Wall(None), Boundary::Wall(None)];
        let c = Canon::of(&job).expect("turned");
        assert!(c.reversed && !c.transposed);
        assert_eq!(c.original(DVec2::new(0.25, 0.5)), DVec2::new(0.75, 0.5));
        let p = plan(&job, &FiveOptions::default()).expect("planned");
        // it starts past u = 1 (x = 30), in the air
        assert!(p.moves[1].tip.x > 30.0, "{:?}", p.moves[1].tip);
        let r = check(&job, &p.moves);
        assert!(r.failures().is_empty(), "{:?}", r.failures());
        job.boundaries = [Boundary::Wall(None), Boundary::Wall(None), Boundary::Open, Boundary::Wall(None)];
        let c = Canon::of(&job).expect("turned");
        assert!(c.transposed && !c.reversed);
        assert_eq!(c.original(DVec2::new(0.25, 0.75)), DVec2::new(0.75, 0.25));
        let p = plan(&job, &FiveOptions::default()).expect("planned");
        assert!(p.moves[1].tip.y < 0.0, "{:?}", p.moves[1].tip);
        job.boundaries = [Boundary::Wall(None), Boundary::Wall(None), Boundary::Wall(None), Boundary::Wall(None)];
        assert!(plan(&job, &FiveOptions::default()).is_err());
    }

    #[test]
    fn a_tool_wider_than_the_pocket_is_refused() {
        let job = flat_channel(30.0, 8.0, 10.0, ball(10.0));
        let e = plan(&job, &FiveOptions::default()).expect_err("too wide");
        assert!(e.to_string().contains("too narrow") || e.to_string().contains("too wide"), "{e}");
    }
}
