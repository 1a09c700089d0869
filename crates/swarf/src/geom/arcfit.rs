//! Arc fitting: turns a polyline of tool-centre points into straight lines and circular arcs
//! (G1 / G2 / G3) that stay within a tolerance of it.
//!
//! Greedy, left to right: from the current point, the longest run of points that fits one
//! straight line and the longest run that fits one arc are found by galloping (doubling the run,
//! then bisecting), and the longer wins. A run fits an arc when, for the circle through its
//! first, middle and last points, every point is within `tol` of the circle, the points advance
//! monotonically around it in one direction (less than one turn), and each chord of the input
//! is within `tol` of the arc it stands for (the sagitta test — this is what stops an arc from
//! rounding off a sharp corner). A run fits a line when every point is within `tol` of the chord
//! and their projections advance. So the output is never farther than `tol` from the input, in
//! either direction.

use super::DVec2;

/// One piece of a fitted path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Piece {
    /// Straight to `to`.
    Line {
        /// End point.
        to: DVec2,
    },
    /// Circular arc to `to` around `center`.
    Arc {
        /// End point.
        to: DVec2,
        /// Centre.
        center: DVec2,
        /// Counter-clockwise (G3) when true, clockwise (G2) otherwise.
        ccw: bool,
    },
}

impl Piece {
    /// End point.
    pub fn end(&self) -> DVec2 {
        match *self {
            Piece::Line { to } | Piece::Arc { to, .. } => to,
        }
    }
}

/// Arcs with a radius above this are written as lines (mm).
pub const MAX_ARC_RADIUS: f64 = 2000.0;

fn circle3(a: DVec2, b: DVec2, c: DVec2) -> Option<(DVec2, f64)> {
    let d = 2.0 * (a.x * (b.y - c.y) + b.x * (c.y - a.y) + c.x * (a.y - b.y));
    if d.abs() < 1e-18 {
        return None;
    }
    let a2 = a.length_squared();
    let b2 = b.length_squared();
    let c2 = c.length_squared();
    let ux = (a2 * (b.y - c.y) + b2 * (c.y - a.y) + c2 * (a.y - b.y)) / d;
    let uy = (a2 * (c.x - b.x) + b2 * (a.x - c.x) + c2 * (b.x - a.x)) / d;
    let center = DVec2::new(ux, uy);
    let r = (a - center).length();
    if !r.is_finite() || r > MAX_ARC_RADIUS {
        return None;
    }
    Some((center, r))
}

fn fits_line(p: &[DVec2], tol: f64) -> bool {
    let a = p[0];
    let b = p[p.len() - 1];
    let ab = b - a;
    let l = ab.length();
    if l < 1e-12 {
        return p.iter().all(|q| (*q - a).length() <= tol);
    }
    let u = ab / l;
    let mut last = -tol;
    for q in &p[1..p.len() - 1] {
        let v = *q - a;
        let t = v.dot(u);
        if (v.perp_dot(u)).abs() > tol || t < last - tol || t > l + tol {
            return false;
        }
        last = last.max(t);
    }
    true
}

fn fits_arc(p: &[DVec2], tol: f64) -> Option<(DVec2, bool)> {
    let n = p.len();
    if n < 3 {
        return None;
    }
    let (c, r) = circle3(p[0], p[n / 2], p[n - 1])?;
    let mut total = 0.0;
    let mut dir = 0.0;
    for w in p.windows(2) {
        let (a, b) = (w[0] - c, w[1] - c);
        if (a.length() - r).abs() > tol {
            return None;
        }
        let ang = a.perp_dot(b).atan2(a.dot(b));
        if ang.abs() < 1e-15 {
            return None;
        }
        if dir == 0.0 {
            dir = ang.signum();
        } else if ang.signum() != dir {
            return None;
        }
        // sagitta of the sub-arc this chord stands for
        if r * (1.0 - (ang / 2.0).cos()) > tol {
            return None;
        }
        total += ang;
    }
    if ((p[n - 1] - c).length() - r).abs() > tol || total.abs() >= std::f64::consts::TAU - 1e-6 {
        return None;
    }
    Some((c, dir > 0.0))
}

/// Longest `j` (≥ `i + 1`) such that `pred(&pts[i..=j])` holds, found by galloping.
fn longest(pts: &[DVec2], i: usize, min_len: usize, pred: &dyn Fn(&[DVec2]) -> bool) -> Option<usize> {
    let n = pts.len();
    let first = i + min_len - 1;
    if first >= n || !pred(&pts[i..=first]) {
        return None;
    }
    let mut good = first;
    let mut step = 1;
    let mut bad = n; // exclusive upper bound of unknown
    loop {
        let j = good + step;
        if j >= n {
            break;
        }
        if pred(&pts[i..=j]) {
            good = j;
            step *= 2;
        } else {
            bad = j;
            break;
        }
    }
    let mut hi = bad.min(n); // first known-bad (or n)
    let mut lo = good;
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if pred(&pts[i..=mid]) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(lo)
}

/// Fits lines and arcs to `pts` within `tol`. The first point is the start and is not part of
/// the output; each piece ends on an input point.
pub fn fit(pts: &[DVec2], tol: f64) -> Vec<Piece> {
    let mut out = Vec::new();
    let n = pts.len();
    let mut i = 0;
    while i + 1 < n {
        let jl = longest(pts, i, 2, &|s| fits_line(s, tol)).unwrap_or(i + 1);
        let ja = longest(pts, i, 3, &|s| fits_arc(s, tol).is_some());
        match ja {
            Some(ja) if ja > jl => {
                if let Some((center, ccw)) = fits_arc(&pts[i..=ja], tol) {
                    out.push(Piece::Arc { to: pts[ja], center, ccw });
                    i = ja;
                    continue;
                }
                out.push(Piece::Line { to: pts[jl] });
                i = jl;
            }
            _ => {
                if (pts[jl] - pts[i]).length() > 1e-9 {
                    out.push(Piece::Line { to: pts[jl] });
                }
                i = jl;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arc_pts(c: DVec2, r: f64, a0: f64, a1: f64, n: usize) -> Vec<DVec2> {
        (0..=n)
            .map(|i| {
                let t = a0 + (a1 - a0) * i as f64 / n as f64;
                c + r * DVec2::new(t.cos(), t.sin())
            })
            .collect()
    }

    #[test]
    fn recovers_lines_and_arcs() {
        let mut pts = vec![DVec2::new(-10.0, 0.0)];
        for i in 1..=20 {
            pts.push(DVec2::new(-10.0 + 0.5 * i as f64, 0.0));
        }
        // then a ccw quarter arc of radius 5 around (0, 5), then a cw half arc
        pts.extend(arc_pts(DVec2::new(0.0, 5.0), 5.0, -std::f64::consts::FRAC_PI_2, 0.0, 90).into_iter().skip(1));
        pts.extend(arc_pts(DVec2::new(8.0, 5.0), 3.0, std::f64::consts::PI, 0.0, 90).into_iter().skip(1));
        let f = fit(&pts, 0.001);
        assert_eq!(f.len(), 3, "{f:?}");
        assert!(matches!(f[0], Piece::Line { .. }));
        match f[1] {
            Piece::Arc { center, ccw, .. } => {
                assert!(ccw);
                assert!((center - DVec2::new(0.0, 5.0)).length() < 1e-6);
            }
            Piece::Line { .. } => panic!(),
        }
        match f[2] {
            Piece::Arc { center, ccw, .. } => {
                assert!(!ccw);
                assert!((center - DVec2::new(8.0, 5.0)).length() < 1e-6);
            }
            Piece::Line { .. } => panic!(),
        }
    }

    #[test]
    fn keeps_sharp_corners() {
        let pts = vec![DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0), DVec2::new(1.0, 1.0), DVec2::new(0.0, 1.0)];
        let f = fit(&pts, 0.01);
        assert_eq!(f.len(), 3);
        assert!(f.iter().all(|p| matches!(p, Piece::Line { .. })));
    }

    #[test]
    fn output_stays_within_tolerance() {
        // a noisy wavy polyline: every fitted piece must stay within tol of the input points
        let pts: Vec<DVec2> = (0..500)
            .map(|i| {
                let t = i as f64 * 0.05;
                DVec2::new(t, (t * 0.7).sin() * 3.0 + ((i * 7919) % 13) as f64 * 1e-4)
            })
            .collect();
        let tol = 0.01;
        let f = fit(&pts, tol);
        assert!(f.len() < 200, "{}", f.len());
        let mut start = pts[0];
        let mut k = 0;
        for piece in &f {
            let end = piece.end();
            let j = pts.iter().position(|p| *p == end).unwrap();
            for p in &pts[k..=j] {
                let d = match *piece {
                    Piece::Line { to } => crate::geom::dist_point_segment(*p, start, to),
                    Piece::Arc { center, .. } => ((*p - center).length() - (start - center).length()).abs(),
                };
                assert!(d <= tol + 1e-9, "{d}");
            }
            k = j;
            start = end;
        }
        assert_eq!(k, pts.len() - 1);
    }
}
