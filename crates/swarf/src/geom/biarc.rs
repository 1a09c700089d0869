//! Biarcs: a smooth curve known by points and unit tangents, written as circular arcs that
//! meet tangentially (G1), for G2/G3 programs that are C1 by construction.
//!
//! Between two points with unit tangents a biarc is two arcs sharing their tangent at the
//! joint, here the "equal chord" biarc of Bolton 1975 and Meek & Walton 1992 ([`biarc`]);
//! [`fit`] covers a dense polyline with tangents by biarcs, each as long as the polyline stays
//! within the tolerance of it, widened where arcs would be too short if the points then lie
//! within a looser tolerance on one side ([`Tolerance`]). The construction and the reasons are
//! in `docs/geometry.md`.

use super::DVec2;
use super::arcfit::Piece;

/// One arc (or line) from `from`, with its tangent at the start.
fn arc_from(from: DVec2, t: DVec2, to: DVec2) -> Piece {
    let n = DVec2::new(-t.y, t.x);
    let chord = to - from;
    let h = chord.dot(n);
    if h.abs() < 1e-9 * chord.length().max(1e-9) {
        return Piece::Line { to };
    }
    let r = chord.length_squared() / (2.0 * h);
    Piece::Arc { to, center: from + n * r, ccw: r > 0.0 }
}

/// One arc (or line) to `to`, with its tangent at the end.
fn arc_to(from: DVec2, to: DVec2, t: DVec2) -> Piece {
    let n = DVec2::new(-t.y, t.x);
    let chord = from - to;
    let h = chord.dot(n);
    if h.abs() < 1e-9 * chord.length().max(1e-9) {
        return Piece::Line { to };
    }
    let r = chord.length_squared() / (2.0 * h);
    Piece::Arc { to, center: to + n * r, ccw: r > 0.0 }
}

/// The biarc from (`p0`, `t0`) to (`p1`, `t1`) (unit tangents): two pieces meeting
/// tangentially. `None` when the tangents make it degenerate (turning back more than a half
/// turn between the two points).
pub fn biarc(p0: DVec2, t0: DVec2, p1: DVec2, t1: DVec2) -> Option<[Piece; 2]> {
    let v = p1 - p0;
    let vv = v.length_squared();
    if vv < 1e-24 {
        return None;
    }
    let t = t0 + t1;
    let a = t.length_squared() - 4.0;
    let vt = v.dot(t);
    let d = if a.abs() < 1e-12 {
        // parallel and equal tangents
        if vt.abs() < 1e-12 {
            return None;
        }
        vv / (2.0 * vt)
    } else {
        (vt - (vt * vt - a * vv).max(0.0).sqrt()) / a
    };
    if !(d > 0.0 && d.is_finite()) {
        return None;
    }
    let j = 0.5 * ((p0 + t0 * d) + (p1 - t1 * d));
    Some([arc_from(p0, t0, j), arc_to(j, p1, t1)])
}

/// Distance from `q` to a piece that starts at `from`.
pub fn distance_to(from: DVec2, piece: &Piece, q: DVec2) -> f64 {
    signed_distance_to(from, piece, q).abs()
}

/// Distance from `q` to a piece that starts at `from`, positive where `q` lies to the left of
/// the piece's direction of travel (beyond an end of the piece: the distance to that end, with
/// the side of the line or circle the piece lies on).
pub fn signed_distance_to(from: DVec2, piece: &Piece, q: DVec2) -> f64 {
    match *piece {
        Piece::Line { to } => {
            let d = super::dist_point_segment(q, from, to);
            if (to - from).perp_dot(q - from) >= 0.0 { d } else { -d }
        }
        Piece::Arc { to, center, ccw } => {
            let r = (from - center).length();
            let (a0, a1, aq) = (ang(from - center), ang(to - center), ang(q - center));
            let s = if ccw { 1.0 } else { -1.0 };
            let span = ((a1 - a0) * s).rem_euclid(std::f64::consts::TAU);
            let at = ((aq - a0) * s).rem_euclid(std::f64::consts::TAU);
            let out = (q - center).length() - r;
            let d = if at <= span { out.abs() } else { (q - from).length().min((q - to).length()) };
            // the centre is on the left of a counter-clockwise arc
            if (out <= 0.0) == ccw { d } else { -d }
        }
    }
}

fn ang(v: DVec2) -> f64 {
    v.y.atan2(v.x)
}

/// The shorter chord of a biarc starting at `from`.
fn shortest(from: DVec2, b: &[Piece; 2]) -> f64 {
    (b[0].end() - from).length().min((b[1].end() - b[0].end()).length())
}

/// Unit tangents of a polyline by central differences (one-sided at the ends).
pub fn tangents(pts: &[DVec2]) -> Vec<DVec2> {
    let n = pts.len();
    (0..n)
        .map(|i| {
            let (a, b) = (pts[i.saturating_sub(1)], pts[(i + 1).min(n - 1)]);
            (b - a).normalize_or_zero()
        })
        .collect()
}

/// How far [`fit`] may stray from the points it covers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    /// Largest distance from any point to the biarcs.
    pub tol: f64,
    /// Shortest chord wanted of each arc (0: no such wish). Where curvature changes fast, arcs
    /// within `tol` can be a few hundredths of a millimetre long, and a reader that looks at
    /// a program at a coarser scale (a controller's look-ahead, a verifier merging short
    /// moves into chords) sees their run as a polygon. A span whose arcs come out shorter is
    /// widened until they reach `min_len`, if the points then stay within `tol` on one side of
    /// the biarc and within `loose` on the other.
    pub min_len: f64,
    /// How far points may lie from a widened span on the side `side`.
    pub loose: f64,
    /// The side of the biarc (in its direction of travel, +1 left, −1 right) where points may
    /// lie up to `loose` from it: the biarc may cut the corner on the other side, never stray
    /// beyond `tol` to this one.
    pub side: f64,
}

impl Tolerance {
    /// Every point within `tol`, no widening.
    pub fn within(tol: f64) -> Self {
        Tolerance { tol, min_len: 0.0, loose: tol, side: 1.0 }
    }
}

/// Covers the dense polyline `pts` (with unit tangents `tan`, one per point) by biarcs that
/// stay within `tol.tol` of every point, each spanning as many points as that allows (found
/// by galloping, then bisecting), then widened where their arcs are shorter than
/// `tol.min_len` as far as [`Tolerance`] allows. The pieces start at `pts[0]`; consecutive
/// pieces meet tangentially. A span the biarc cannot take (degenerate tangents) falls back to
/// a shorter one, down to the next point, where a straight line is used.
pub fn fit(pts: &[DVec2], tan: &[DVec2], tol: Tolerance) -> Vec<Piece> {
    let n = pts.len();
    let mut out = Vec::new();
    let mut i = 0;
    // the largest excess over the allowed distance of any point the biarc spans (≤ 0: fits)
    let excess = |i: usize, j: usize, b: &[Piece; 2], loose: f64| -> f64 {
        let mid = b[0].end();
        pts[i + 1..j]
            .iter()
            .map(|q| {
                let (d0, d1) = (signed_distance_to(pts[i], &b[0], *q), signed_distance_to(mid, &b[1], *q));
                let d = if d0.abs() <= d1.abs() { d0 } else { d1 };
                d.abs() - if d * tol.side > 0.0 { loose } else { tol.tol }
            })
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let fits = |i: usize, j: usize| -> Option<[Piece; 2]> {
        let b = biarc(pts[i], tan[i], pts[j], tan[j])?;
        (excess(i, j, &b, tol.tol) <= 0.0).then_some(b)
    };
    while i + 1 < n {
        // gallop
        let mut good = None;
        let mut step = 1;
        let mut bad = n;
        loop {
            let j = (i + step).min(n - 1);
            match fits(i, j) {
                Some(b) => {
                    good = Some((j, b));
                    if j == n - 1 {
                        break;
                    }
                    step *= 2;
                }
                None => {
                    bad = j;
                    break;
                }
            }
        }
        // bisect between the last good and the first bad
        if let Some((mut lo, _)) = good
            && bad < n
        {
            let mut hi = bad;
            while hi - lo > 1 {
                let m = (lo + hi) / 2;
                match fits(i, m) {
                    Some(b) => {
                        lo = m;
                        good = Some((m, b));
                    }
                    None => hi = m,
                }
            }
        }
        // widen a span whose arcs came out short: to the first end point (within 4 min_len)
        // whose biarc has both arcs at least min_len long (or that is the last point) and
        // keeps the points within the loose tolerance
        if let Some((j, b)) = good
            && tol.min_len > 0.0
            && shortest(pts[i], &b) < tol.min_len
        {
            let wide = (j + 1..n)
                .take_while(|&jj| (pts[jj] - pts[i]).length() <= 4.0 * tol.min_len)
                .filter_map(|jj| biarc(pts[i], tan[i], pts[jj], tan[jj]).map(|bb| (jj, bb)))
                .filter(|(jj, bb)| *jj == n - 1 || shortest(pts[i], bb) >= tol.min_len)
                .find(|(jj, bb)| excess(i, *jj, bb, tol.loose) <= 0.0);
            if let Some(w) = wide {
                good = Some(w);
            }
        }
        match good {
            Some((j, b)) => {
                out.extend(b);
                i = j;
            }
            None => {
                out.push(Piece::Line { to: pts[i + 1] });
                i += 1;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tangent_at_start(from: DVec2, p: &Piece) -> DVec2 {
        match *p {
            Piece::Line { to } => (to - from).normalize(),
            Piece::Arc { center, ccw, .. } => {
                let r = (from - center).normalize();
                if ccw { DVec2::new(-r.y, r.x) } else { DVec2::new(r.y, -r.x) }
            }
        }
    }

    fn tangent_at_end(from: DVec2, p: &Piece) -> DVec2 {
        match *p {
            Piece::Line { to } => (to - from).normalize(),
            Piece::Arc { to, center, ccw } => {
                let r = (to - center).normalize();
                if ccw { DVec2::new(-r.y, r.x) } else { DVec2::new(r.y, -r.x) }
            }
        }
    }

    #[test]
    fn a_biarc_meets_its_tangents_and_itself_smoothly() {
        let cases = [
            (DVec2::new(0.0, 0.0), DVec2::X, DVec2::new(10.0, 3.0), DVec2::new(0.6, 0.8)),
            (DVec2::new(0.0, 0.0), DVec2::Y, DVec2::new(5.0, 0.0), -DVec2::Y),
            (
                DVec2::new(1.0, 1.0),
                DVec2::new(1.0, 1.0).normalize(),
                DVec2::new(4.0, 4.0),
                DVec2::new(1.0, 1.0).normalize(),
            ),
            (DVec2::new(0.0, 0.0), DVec2::X, DVec2::new(4.0, 1.0), DVec2::new(1.0, -0.2).normalize()),
        ];
        for (p0, t0, p1, t1) in cases {
            let b = biarc(p0, t0, p1, t1).expect("a biarc");
            let j = b[0].end();
            assert!((tangent_at_start(p0, &b[0]) - t0).length() < 1e-9, "start tangent");
            assert!((tangent_at_end(j, &b[1]) - t1).length() < 1e-9, "end tangent");
            assert!((tangent_at_end(p0, &b[0]) - tangent_at_start(j, &b[1])).length() < 1e-9, "joint");
            assert!((b[1].end() - p1).length() < 1e-12);
        }
    }

    #[test]
    fn fitting_a_spiral_is_tangent_continuous_and_within_tolerance() {
        // an Archimedean spiral, finely sampled
        let pts: Vec<DVec2> = (0..4000)
            .map(|k| {
                let t = 0.3 + k as f64 * 0.005;
                DVec2::new(t.cos(), t.sin()) * (1.0 + 0.8 * t)
            })
            .collect();
        let tan = tangents(&pts);
        let tol = 0.002;
        let pieces = fit(&pts, &tan, Tolerance::within(tol));
        assert!(pieces.len() < 400, "{} pieces", pieces.len());
        let mut from = pts[0];
        let mut prev_t: Option<DVec2> = None;
        for p in &pieces {
            let t = tangent_at_start(from, p);
            if let Some(pt) = prev_t {
                assert!(pt.angle_to(t).abs().to_degrees() < 0.01, "turn {}°", pt.angle_to(t).to_degrees());
            }
            prev_t = Some(tangent_at_end(from, p));
            from = p.end();
        }
        assert!((from - *pts.last().unwrap()).length() < 1e-12);
        // every input point is near the output
        let mut starts = vec![pts[0]];
        starts.extend(pieces.iter().map(|p| p.end()));
        for q in pts.iter().step_by(7) {
            let d = pieces.iter().zip(&starts).map(|(p, s)| distance_to(*s, p, *q)).fold(f64::MAX, f64::min);
            assert!(d <= tol + 1e-9, "{d}");
        }
    }

    /// A superellipse |x|¹⁰ + |y|¹⁰ = 2¹⁰, counter-clockwise: nearly straight sides and corners
    /// whose curvature changes fast, sampled unevenly, with exact tangents.
    fn superellipse() -> (Vec<DVec2>, Vec<DVec2>) {
        let at = |t: f64| {
            let (c, s) = (t.cos(), t.sin());
            DVec2::new(c.signum() * c.abs().powf(0.1), s.signum() * s.abs().powf(0.1)) * 2.0
        };
        let ts: Vec<f64> = (0..3000).map(|k| 0.1 + k as f64 * 0.0019 + 0.0004 * ((k * 7) % 5) as f64).collect();
        let pts: Vec<DVec2> = ts.iter().map(|&t| at(t)).collect();
        let tan = ts.iter().map(|&t| (at(t + 1e-7) - at(t - 1e-7)).normalize()).collect();
        (pts, tan)
    }

    /// How many pieces (but the last) have a chord shorter than `min_len`, the longest run of
    /// such pieces, and the largest distances of the points to the left and to the right of
    /// the pieces.
    fn measure(pts: &[DVec2], pieces: &[Piece], min_len: f64) -> (usize, usize, f64, f64) {
        let mut starts = vec![pts[0]];
        starts.extend(pieces.iter().map(|p| p.end()));
        let (mut short, mut run, mut longest) = (0, 0, 0);
        for (p, s) in pieces[..pieces.len() - 1].iter().zip(&starts) {
            if (p.end() - *s).length() < min_len {
                short += 1;
                run += 1;
                longest = longest.max(run);
            } else {
                run = 0;
            }
        }
        let (mut left, mut right) = (0.0f64, 0.0f64);
        for q in pts {
            let d = pieces
                .iter()
                .zip(&starts)
                .map(|(p, s)| signed_distance_to(*s, p, *q))
                .min_by(|a, b| a.abs().total_cmp(&b.abs()))
                .unwrap();
            left = left.max(d);
            right = right.max(-d);
        }
        (short, longest, left, right)
    }

    #[test]
    fn widened_arcs_are_seldom_short_and_cut_only_inwards() {
        let (pts, tan) = superellipse();
        let (tol, min_len) = (0.002, 0.12);
        // within the tolerance alone, the corners take runs of arcs shorter than 0.12 mm
        let tight = fit(&pts, &tan, Tolerance::within(tol));
        let (short0, run0, left, right) = measure(&pts, &tight, min_len);
        assert!(short0 >= 12 && run0 >= 3, "{short0} short, runs of {run0}");
        assert!(left <= tol + 1e-9 && right <= tol + 1e-9, "{left} {right}");
        // widened: a short arc is alone between long ones, the points are within tol on the
        // left (the outside of a counter-clockwise curve: the biarcs never stray outwards)
        // and within 0.02 on the right
        let wide = Tolerance { tol, min_len, loose: 0.02, side: -1.0 };
        let pieces = fit(&pts, &tan, wide);
        let (short, run, left, right) = measure(&pts, &pieces, min_len);
        assert!(short * 4 <= short0 && run <= 1, "{short} short, runs of {run}");
        assert!(left <= tol + 1e-9, "{left}");
        assert!(right <= 0.02 + 1e-9 && right > tol, "{right}");
        assert!((pieces.last().unwrap().end() - *pts.last().unwrap()).length() < 1e-12);
    }

    #[test]
    fn the_sign_of_the_distance_is_the_side() {
        let from = DVec2::new(1.0, 0.0);
        let ccw = Piece::Arc { to: DVec2::new(0.0, 1.0), center: DVec2::ZERO, ccw: true };
        // inside a counter-clockwise arc is its left
        assert!((signed_distance_to(from, &ccw, DVec2::new(0.5, 0.5)) - (1.0 - 0.5f64.sqrt())).abs() < 1e-12);
        assert!(signed_distance_to(from, &ccw, DVec2::new(1.0, 1.0)) < 0.0);
        let cw = Piece::Arc { to: DVec2::new(0.0, -1.0), center: DVec2::ZERO, ccw: false };
        assert!(signed_distance_to(from, &cw, DVec2::new(0.5, -0.5)) < 0.0);
        let line = Piece::Line { to: DVec2::new(3.0, 0.0) };
        assert_eq!(signed_distance_to(from, &line, DVec2::new(2.0, 0.5)), 0.5);
        assert_eq!(signed_distance_to(from, &line, DVec2::new(2.0, -0.5)), -0.5);
    }
}
