//! Biarcs: a smooth curve known by points and unit tangents, written as circular arcs that
//! meet tangentially (G1), for G2/G3 programs that are C1 by construction.
//!
//! Between two points P₀, P₁ with unit tangents T₀, T₁, a biarc is two arcs: the first leaves
//! P₀ along T₀, the second arrives at P₁ along T₁, and they share their tangent at the joint J.
//! With the two control lengths equal (d₁ = d₂ = d), the control points Q₀ = P₀ + d·T₀ and
//! Q₁ = P₁ − d·T₁ are 2d apart and J is their midpoint; with v = P₁ − P₀ and t = T₀ + T₁,
//! |v − d·t|² = 4d² gives (t·t − 4)·d² − 2(v·t)·d + v·v = 0, whose positive root is taken
//! (the "equal chord" biarc of Bolton 1975 and Meek & Walton 1992).
//!
//! [`fit`] walks a dense polyline (a curve sampled finely, such as an integrated trajectory),
//! takes the tangents from it by central differences, and covers it with biarcs, each as long
//! as the polyline stays within the tolerance of it (checked at every point it spans). Written
//! here because arc fitting that keeps tangency between pieces is not in any of the geometry
//! crates this project uses (`arcfit` fits arcs greedily, without tangency between them).

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
    match *piece {
        Piece::Line { to } => super::dist_point_segment(q, from, to),
        Piece::Arc { to, center, ccw } => {
            let r = (from - center).length();
            let (a0, a1, aq) = (ang(from - center), ang(to - center), ang(q - center));
            let s = if ccw { 1.0 } else { -1.0 };
            let span = ((a1 - a0) * s).rem_euclid(std::f64::consts::TAU);
            let at = ((aq - a0) * s).rem_euclid(std::f64::consts::TAU);
            if at <= span { ((q - center).length() - r).abs() } else { (q - from).length().min((q - to).length()) }
        }
    }
}

fn ang(v: DVec2) -> f64 {
    v.y.atan2(v.x)
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

/// Covers the dense polyline `pts` (with unit tangents `tan`, one per point) by biarcs that
/// stay within `tol` of every point, each spanning as many points as that allows (found by
/// galloping, then bisecting). The pieces start at `pts[0]`; consecutive pieces meet
/// tangentially. A span the biarc cannot take (degenerate tangents) falls back to a shorter
/// one, down to the next point, where a straight line is used.
pub fn fit(pts: &[DVec2], tan: &[DVec2], tol: f64) -> Vec<Piece> {
    let n = pts.len();
    let mut out = Vec::new();
    let mut i = 0;
    let fits = |i: usize, j: usize| -> Option<[Piece; 2]> {
        let b = biarc(pts[i], tan[i], pts[j], tan[j])?;
        let mid = b[0].end();
        for q in &pts[i + 1..j] {
            let d = distance_to(pts[i], &b[0], *q).min(distance_to(mid, &b[1], *q));
            if d > tol {
                return None;
            }
        }
        Some(b)
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
        let pieces = fit(&pts, &tan, tol);
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
}
