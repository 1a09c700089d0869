//! When is a point within reach of a moving tool? For a line or an arc (helical or not) and a
//! point `q`, the parameter intervals during which the tool axis is within `rho` of `q`. The
//! cutting, gouge, collision and same-move engagement tests all reduce to this.

use crate::geom::{DVec2, DVec3};
use crate::toolpath::{ArcGeom, Motion, Move};

/// A move's path resolved for fast queries.
#[derive(Debug, Clone, Copy)]
pub enum Path {
    /// Straight from `a` to `b`.
    Line {
        /// Start.
        a: DVec3,
        /// End.
        b: DVec3,
    },
    /// Arc.
    Arc(ArcGeom),
}

impl Path {
    /// The path of move `m` starting at `from`.
    pub fn of(from: DVec3, m: &Move) -> Path {
        match m.motion {
            Motion::Line => Path::Line { a: from, b: m.to },
            Motion::Arc { center, ccw } => Path::Arc(ArcGeom::new(from, m.to, center, ccw)),
        }
    }

    /// The sub-path for parameters `[t0, t1]`.
    pub fn sub(&self, t0: f64, t1: f64) -> Path {
        match *self {
            Path::Line { a, b } => Path::Line { a: a + (b - a) * t0, b: a + (b - a) * t1 },
            Path::Arc(g) => {
                let mut h = g;
                h.a0 = g.a0 + g.sweep * t0;
                h.sweep = g.sweep * (t1 - t0);
                h.z0 = g.z0 + (g.z1 - g.z0) * t0;
                h.z1 = g.z0 + (g.z1 - g.z0) * t1;
                Path::Arc(h)
            }
        }
    }

    /// Point at `t`.
    pub fn at(&self, t: f64) -> DVec3 {
        match *self {
            Path::Line { a, b } => a + (b - a) * t,
            Path::Arc(g) => g.at(t),
        }
    }

    /// Unit XY direction of motion at `t` (zero for vertical lines).
    pub fn dir(&self, t: f64) -> DVec2 {
        match *self {
            Path::Line { a, b } => (b - a).truncate().normalize_or_zero(),
            Path::Arc(g) => g.tangent(t),
        }
    }

    /// XY length.
    pub fn xy_length(&self) -> f64 {
        match *self {
            Path::Line { a, b } => (b - a).truncate().length(),
            Path::Arc(g) => g.xy_length(),
        }
    }

    /// z at the start and the end.
    pub fn z_range(&self) -> (f64, f64) {
        match *self {
            Path::Line { a, b } => (a.z, b.z),
            Path::Arc(g) => (g.z0, g.z1),
        }
    }

    /// XY bounding box, grown by `pad`.
    pub fn bbox(&self, pad: f64) -> (DVec2, DVec2) {
        let (lo, hi) = match *self {
            Path::Line { a, b } => (a.truncate().min(b.truncate()), a.truncate().max(b.truncate())),
            Path::Arc(g) => {
                let p0 = g.at(0.0).truncate();
                let p1 = g.at(1.0).truncate();
                let mut lo = p0.min(p1);
                let mut hi = p0.max(p1);
                // axis extremes inside the sweep
                for k in 0..4 {
                    let ang = k as f64 * std::f64::consts::FRAC_PI_2;
                    if angle_in_sweep(ang, g.a0, g.sweep) {
                        let p = g.center + g.radius * DVec2::new(ang.cos(), ang.sin());
                        lo = lo.min(p);
                        hi = hi.max(p);
                    }
                }
                (lo, hi)
            }
        };
        (lo - DVec2::splat(pad), hi + DVec2::splat(pad))
    }

    /// Distance in XY from `q` to the path (prepare a [`Fast`] for many queries).
    pub fn distance(&self, q: DVec2) -> f64 {
        Fast::new(self).distance(q)
    }

    /// True when z does not change along the path.
    #[inline]
    pub fn is_flat(&self) -> bool {
        let (z0, z1) = self.z_range();
        z0 == z1
    }

    /// Calls `f(t0, t1)` for each parameter interval (within [0, 1]) during which the axis is
    /// within `rho` of `q` in XY.
    #[inline]
    pub fn reach_intervals(&self, q: DVec2, rho: f64, mut f: impl FnMut(f64, f64)) {
        match *self {
            Path::Line { a, b } => {
                let d = (b - a).truncate();
                let fv = a.truncate() - q;
                let dd = d.length_squared();
                let c = fv.length_squared() - rho * rho;
                if dd < 1e-24 {
                    if c <= 0.0 {
                        f(0.0, 1.0);
                    }
                    return;
                }
                let bh = fv.dot(d);
                let disc = bh * bh - dd * c;
                if disc < 0.0 {
                    return;
                }
                let s = disc.sqrt();
                let t0 = ((-bh - s) / dd).max(0.0);
                let t1 = ((-bh + s) / dd).min(1.0);
                if t0 <= t1 {
                    f(t0, t1);
                }
            }
            Path::Arc(g) => {
                let v = q - g.center;
                let e = v.length();
                let r = g.radius;
                if e < 1e-12 {
                    if r <= rho {
                        f(0.0, 1.0);
                    }
                    return;
                }
                let k = (r * r + e * e - rho * rho) / (2.0 * r * e);
                if k > 1.0 {
                    return;
                }
                if k <= -1.0 || g.sweep.abs() < 1e-15 {
                    if k <= -1.0 {
                        f(0.0, 1.0);
                    }
                    return;
                }
                let alpha = k.acos();
                let psi = v.y.atan2(v.x);
                let d0 = crate::geom::wrap_pi(g.a0 - psi);
                let tau = std::f64::consts::TAU;
                for m in -2..=2 {
                    let lo = -alpha + tau * m as f64 - d0;
                    let hi = alpha + tau * m as f64 - d0;
                    let (mut t0, mut t1) = (lo / g.sweep, hi / g.sweep);
                    if t0 > t1 {
                        std::mem::swap(&mut t0, &mut t1);
                    }
                    let t0 = t0.max(0.0);
                    let t1 = t1.min(1.0);
                    if t0 <= t1 {
                        f(t0, t1);
                    }
                }
            }
        }
    }

    /// Lowest tool-tip z while the axis is within `rho` of `q`, if it ever is.
    #[inline]
    pub fn reach_zmin(&self, q: DVec2, rho: f64) -> Option<f64> {
        let (z0, z1) = self.z_range();
        let mut best: Option<f64> = None;
        self.reach_intervals(q, rho, |t0, t1| {
            let z = (z0 + (z1 - z0) * t0).min(z0 + (z1 - z0) * t1);
            best = Some(best.map_or(z, |b: f64| b.min(z)));
        });
        best
    }
}

/// [`Path::reach_zmin`] prepared for many cells of one sloping path: a cell within `rho` of the
/// path's lowest end (by a margin far above rounding) reaches that end's height, and a cell
/// farther than `rho` from the path in XY (by the same margin) reaches nothing, both without
/// trigonometry; the cells in between (a thin band, and the far side of a helix) are asked of
/// [`Path::reach_zmin`]. The answers are the same bits: the tip height is monotone along the
/// path, so the lowest end gives the least, computed by the same expression.
#[derive(Debug, Clone, Copy)]
pub struct Reach {
    path: Path,
    fast: Fast,
    rho: f64,
    /// The lowest end, and its height as [`Path::reach_zmin`] computes it.
    low: DVec2,
    zlow: f64,
}

/// The margin of [`Reach`]'s shortcuts, mm.
const REACH_MARGIN: f64 = 1e-7;

impl Reach {
    /// Prepares `path` for reach queries at `rho`.
    pub fn new(path: &Path, rho: f64) -> Reach {
        let (z0, z1) = path.z_range();
        let t = if z1 < z0 { 1.0 } else { 0.0 };
        Reach { path: *path, fast: Fast::new(path), rho, low: path.at(t).truncate(), zlow: z0 + (z1 - z0) * t }
    }

    /// [`Path::reach_zmin`] at `q`.
    #[inline]
    pub fn zmin(&self, q: DVec2) -> Option<f64> {
        let inner = self.rho - REACH_MARGIN;
        if inner > 0.0 && (q - self.low).length_squared() <= inner * inner {
            return Some(self.zlow);
        }
        if self.fast.distance(q) > self.rho + REACH_MARGIN {
            return None;
        }
        self.path.reach_zmin(q, self.rho)
    }
}

/// A path prepared for many distance queries: no trigonometry per query.
#[derive(Debug, Clone, Copy)]
pub enum Fast {
    /// Segment `a`–`b`.
    Line {
        /// Start.
        a: DVec2,
        /// `b - a`.
        ab: DVec2,
        /// `1 / |ab|²` (0 for a point).
        inv: f64,
    },
    /// Arc of at most one turn.
    Arc {
        /// Centre.
        c: DVec2,
        /// Radius.
        r: f64,
        /// Unit vector to the start.
        u0: DVec2,
        /// Unit vector to the end.
        u1: DVec2,
        /// Start point.
        p0: DVec2,
        /// End point.
        p1: DVec2,
        /// Signed sweep.
        sweep: f64,
    },
}

impl Fast {
    /// Prepares `path`.
    pub fn new(path: &Path) -> Fast {
        match *path {
            Path::Line { a, b } => {
                let (a, b) = (a.truncate(), b.truncate());
                let ab = b - a;
                let l2 = ab.length_squared();
                Fast::Line { a, ab, inv: if l2 > 0.0 { 1.0 / l2 } else { 0.0 } }
            }
            Path::Arc(g) => {
                let u0 = DVec2::new(g.a0.cos(), g.a0.sin());
                let a1 = g.a0 + g.sweep;
                let u1 = DVec2::new(a1.cos(), a1.sin());
                Fast::Arc {
                    c: g.center,
                    r: g.radius,
                    u0,
                    u1,
                    p0: g.center + g.radius * u0,
                    p1: g.center + g.radius * u1,
                    sweep: g.sweep,
                }
            }
        }
    }

    /// True when the direction `v` (from the centre) lies within the arc's sweep.
    #[inline]
    fn in_sector(u0: DVec2, u1: DVec2, sweep: f64, v: DVec2) -> bool {
        let (s0, s1) = if sweep >= 0.0 { (u0.perp_dot(v), v.perp_dot(u1)) } else { (v.perp_dot(u0), u1.perp_dot(v)) };
        let small = sweep.abs() <= std::f64::consts::PI;
        if small {
            s0 >= 0.0 && s1 >= 0.0
        } else {
            // a sweep over a half turn: everything but the complementary small sector
            s0 >= 0.0 || s1 >= 0.0
        }
    }

    /// Distance in XY from `q`.
    #[inline]
    pub fn distance(&self, q: DVec2) -> f64 {
        match *self {
            Fast::Line { a, ab, inv } => {
                let t = ((q - a).dot(ab) * inv).clamp(0.0, 1.0);
                (a + ab * t - q).length()
            }
            Fast::Arc { c, r, u0, u1, p0, p1, sweep } => {
                let v = q - c;
                if Self::in_sector(u0, u1, sweep, v) {
                    (v.length() - r).abs()
                } else {
                    (q - p0).length().min((q - p1).length())
                }
            }
        }
    }
}

/// True when angle `ang` lies on the arc starting at `a0` sweeping `sweep` (signed).
pub fn angle_in_sweep(ang: f64, a0: f64, sweep: f64) -> bool {
    let tau = std::f64::consts::TAU;
    if sweep.abs() >= tau {
        return true;
    }
    let mut d = (ang - a0) % tau;
    if sweep >= 0.0 {
        if d < 0.0 {
            d += tau;
        }
        d <= sweep
    } else {
        if d > 0.0 {
            d -= tau;
        }
        d >= sweep
    }
}

/// Exact distance from the XY path to the boundary of `keep` (the part and fixtures, whose
/// edges `edges` indexes), capped at `max`, or 0 when the path starts inside `keep`. Both
/// simulators use it.
pub(crate) fn keep_distance(
    keep: &crate::geom::Area,
    edges: &crate::geom::index::EdgeIndex,
    path: &Path,
    max: f64,
) -> f64 {
    let p0 = path.at(0.0).truncate();
    if keep.contains(p0) {
        return 0.0;
    }
    match *path {
        Path::Line { a, b } => edges.segment_distance(a.truncate(), b.truncate(), max),
        // (exactly, not by chords: a spiral is all arcs, and chords fine enough to measure a
        // gouge by were a third of the time to simulate one)
        Path::Arc(g) => edges.arc_distance(g.center, g.radius, g.a0, g.sweep, max),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::toolpath::{Motion, MoveKind};

    #[test]
    fn line_and_arc_reach() {
        let p = Path::Line { a: DVec3::new(0.0, 0.0, 0.0), b: DVec3::new(10.0, 0.0, -1.0) };
        let mut got = vec![];
        p.reach_intervals(DVec2::new(5.0, 3.0), 5.0, |a, b| got.push((a, b)));
        assert_eq!(got.len(), 1);
        assert!((got[0].0 - 0.1).abs() < 1e-12 && (got[0].1 - 0.9).abs() < 1e-12);
        assert!((p.reach_zmin(DVec2::new(5.0, 3.0), 5.0).unwrap() + 0.9).abs() < 1e-12);
        assert!(p.reach_zmin(DVec2::new(5.0, 6.0), 5.0).is_none());
        // half circle ccw of radius 10 from (10,0) to (-10,0): the point (0,-10) is 20 from
        // the top and reachable only near the ends with rho = 14.15
        let m = Move {
            kind: MoveKind::Cut,
            motion: Motion::Arc { center: DVec2::ZERO, ccw: true },
            to: DVec3::new(-10.0, 0.0, 0.0),
            feed: 1.0,
        };
        let a = Path::of(DVec3::new(10.0, 0.0, 0.0), &m);
        let mut iv = vec![];
        a.reach_intervals(DVec2::new(0.0, -10.0), 14.2, |x, y| iv.push((x, y)));
        assert_eq!(iv.len(), 2, "{iv:?}");
        assert!(iv[0].0.abs() < 1e-12 || iv[1].0.abs() < 1e-12);
        assert!((a.distance(DVec2::new(0.0, 5.0)) - 5.0).abs() < 1e-12);
        // the prepared form agrees with the angle test everywhere, for both directions and
        // sweeps over a half turn
        for (ccw, to) in [
            (true, DVec3::new(-10.0, 0.0, 0.0)),
            (false, DVec3::new(0.0, -10.0, 0.0)),
            (true, DVec3::new(0.0, -10.0, 0.0)),
        ] {
            let m = Move { kind: MoveKind::Cut, motion: Motion::Arc { center: DVec2::ZERO, ccw }, to, feed: 1.0 };
            let path = Path::of(DVec3::new(10.0, 0.0, 0.0), &m);
            let Path::Arc(g) = path else { panic!() };
            let f = Fast::new(&path);
            for i in 0..200 {
                let q = DVec2::new((i as f64 * 0.731).sin() * 17.0, (i as f64 * 1.37).cos() * 17.0);
                let v = q;
                let slow = if angle_in_sweep(v.y.atan2(v.x), g.a0, g.sweep) {
                    (v.length() - 10.0).abs()
                } else {
                    (q - g.at(0.0).truncate()).length().min((q - g.at(1.0).truncate()).length())
                };
                assert!((f.distance(q) - slow).abs() < 1e-9, "{q} {} {slow}", f.distance(q));
            }
        }
        assert!((a.distance(DVec2::new(0.0, -5.0)) - 125f64.sqrt()).abs() < 1e-12);
        let (lo, hi) = a.bbox(0.0);
        assert!((hi.y - 10.0).abs() < 1e-12 && lo.y.abs() < 1e-12);
    }

    #[test]
    fn prepared_reach_gives_the_same_bits() {
        // ramps up and down, helix turns both ways, a half turn and more, a vertical plunge;
        // points on a fine lattice over and round each (also on the ends' disks' edges)
        let arc = |from: DVec3, to: DVec3, ccw: bool| {
            let m =
                Move { kind: MoveKind::Cut, motion: Motion::Arc { center: DVec2::new(1.0, 0.5), ccw }, to, feed: 1.0 };
            Path::of(from, &m)
        };
        let paths = [
            Path::Line { a: DVec3::new(0.0, 0.0, 0.0), b: DVec3::new(7.0, 2.0, -1.5) },
            Path::Line { a: DVec3::new(0.0, 0.0, -2.0), b: DVec3::new(-3.0, 5.0, 0.5) },
            Path::Line { a: DVec3::new(1.0, 1.0, 0.0), b: DVec3::new(1.0, 1.0, -3.0) },
            arc(DVec3::new(3.0, 0.5, 0.0), DVec3::new(-1.0, 0.5, -0.4), true),
            arc(DVec3::new(3.0, 0.5, -0.4), DVec3::new(1.0, 2.5, 0.0), false),
            arc(DVec3::new(3.0, 0.5, 0.0), DVec3::new(1.0, -1.5, -0.7), true),
        ];
        let mut checked = 0;
        for path in &paths {
            for rho in [0.5, 3.0, 4.2] {
                let reach = Reach::new(path, rho);
                for i in -90..=90 {
                    for j in -90..=90 {
                        let q = DVec2::new(1.0 + i as f64 * 0.0731, 0.5 + j as f64 * 0.0689);
                        let (fast, slow) = (reach.zmin(q), path.reach_zmin(q, rho));
                        assert_eq!(fast.map(f64::to_bits), slow.map(f64::to_bits), "{path:?} rho {rho} at {q}");
                        checked += usize::from(slow.is_some());
                    }
                }
            }
        }
        assert!(checked > 100_000, "{checked}");
    }
}
