//! Planar geometry: areas with holes and their booleans and offsets, polylines, distance
//! queries, simplification and arc fitting; and the 3D geometry jobs read: meshes and NURBS
//! surfaces.
//!
//! Areas are polygons (arcs of the input are flattened with an explicit chord tolerance) and all
//! booleans, offsets, strokes and polyline clipping go through one thin adapter over the
//! `i_overlay` crate ([`area`]), whose integer core is robust against the coincident edges that
//! CAM inputs are full of (a part frame whose hole is exactly the stock outline, for one). Arcs
//! come back at the output: `arcfit` turns tool-centre polylines into G2/G3 arcs within a
//! tolerance.

#[doc(hidden)]
pub mod arcfit;
pub mod area;
#[doc(hidden)]
pub mod biarc;
#[doc(hidden)]
pub mod index;
#[doc(hidden)]
pub mod medial;
pub mod mesh;
pub mod nurbs;
#[doc(hidden)]
pub mod simplify;

pub use area::Area;
pub use glam::{DVec2, DVec3};

/// Distance from `p` to the segment `a`–`b`.
#[inline]
pub fn dist_point_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 { ((p - a).dot(ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
    (a + ab * t - p).length()
}

/// Parameter in `[0, 1]` of the point of segment `a`–`b` closest to `p`.
#[inline]
pub fn closest_param(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    if l2 > 0.0 { ((p - a).dot(ab) / l2).clamp(0.0, 1.0) } else { 0.0 }
}

/// Distance between segments `a`–`b` and `c`–`d`.
pub fn dist_segment_segment(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> f64 {
    if segments_intersect(a, b, c, d) {
        return 0.0;
    }
    dist_point_segment(a, c, d)
        .min(dist_point_segment(b, c, d))
        .min(dist_point_segment(c, a, b))
        .min(dist_point_segment(d, a, b))
}

#[inline]
fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// True when the closed segments `a`–`b` and `c`–`d` share a point.
pub fn segments_intersect(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let d1 = orient(c, d, a);
    let d2 = orient(c, d, b);
    let d3 = orient(a, b, c);
    let d4 = orient(a, b, d);
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0)) {
        return true;
    }
    let on = |p: DVec2, q: DVec2, r: DVec2, o: f64| {
        o == 0.0 && r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
    };
    on(c, d, a, d1) || on(c, d, b, d2) || on(a, b, c, d3) || on(a, b, d, d4)
}

/// Whether the direction at angle `phi` lies within an arc from angle `a0` sweeping `sweep`
/// (signed, positive counter-clockwise; a full turn or more covers every direction).
#[inline]
pub fn in_sweep(phi: f64, a0: f64, sweep: f64) -> bool {
    let tau = std::f64::consts::TAU;
    if sweep.abs() >= tau {
        return true;
    }
    let d = if sweep >= 0.0 { (phi - a0).rem_euclid(tau) } else { (a0 - phi).rem_euclid(tau) };
    d <= sweep.abs()
}

/// Distance from `p` to the arc of centre `c` and radius `r` from angle `a0` sweeping `sweep`.
pub fn dist_point_arc(p: DVec2, c: DVec2, r: f64, a0: f64, sweep: f64) -> f64 {
    let v = p - c;
    let l = v.length();
    if l == 0.0 {
        return r;
    }
    if in_sweep(v.y.atan2(v.x), a0, sweep) {
        return (l - r).abs();
    }
    let e0 = c + DVec2::from_angle(a0) * r;
    let e1 = c + DVec2::from_angle(a0 + sweep) * r;
    (p - e0).length().min((p - e1).length())
}

/// Distance between the arc of centre `c` and radius `r` from angle `a0` sweeping `sweep` and
/// the segment `a`–`b`; 0 where they meet. Exact: the nearest points are where they cross, an
/// end of either, or the foot of the centre on the segment where the arc faces it (a point of
/// the segment nearer the circle has its radial direction outside the sweep, and then an end
/// of the arc is nearer still).
pub fn dist_arc_segment(c: DVec2, r: f64, a0: f64, sweep: f64, a: DVec2, b: DVec2) -> f64 {
    let d = b - a;
    let f = a - c;
    let qa = d.length_squared();
    if qa > 0.0 {
        // |a + t d − c|² = r²
        let qb = 2.0 * f.dot(d);
        let disc = qb * qb - 4.0 * qa * (f.length_squared() - r * r);
        if disc >= 0.0 {
            let sq = disc.sqrt();
            for t in [(-qb - sq) / (2.0 * qa), (-qb + sq) / (2.0 * qa)] {
                let q = f + d * t;
                if (0.0..=1.0).contains(&t) && in_sweep(q.y.atan2(q.x), a0, sweep) {
                    return 0.0;
                }
            }
        }
    }
    let e0 = c + DVec2::from_angle(a0) * r;
    let e1 = c + DVec2::from_angle(a0 + sweep) * r;
    let mut best = dist_point_arc(a, c, r, a0, sweep)
        .min(dist_point_arc(b, c, r, a0, sweep))
        .min(dist_point_segment(e0, a, b))
        .min(dist_point_segment(e1, a, b));
    let v = a + d * closest_param(c, a, b) - c;
    let l = v.length();
    if l > r && in_sweep(v.y.atan2(v.x), a0, sweep) {
        best = best.min(l - r);
    }
    best
}

/// Wraps an angle into `(-π, π]`.
#[inline]
pub fn wrap_pi(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let mut x = a % t;
    if x <= -std::f64::consts::PI {
        x += t;
    } else if x > std::f64::consts::PI {
        x -= t;
    }
    x
}

/// Length of a polyline.
pub fn polyline_length(pts: &[DVec2]) -> f64 {
    pts.windows(2).map(|w| (w[1] - w[0]).length()).sum()
}

/// Signed area of a closed ring (positive counter-clockwise).
pub fn ring_area(pts: &[DVec2]) -> f64 {
    let n = pts.len();
    if n < 3 {
        return 0.0;
    }
    let mut a = 0.0;
    for i in 0..n {
        let p = pts[i];
        let q = pts[(i + 1) % n];
        a += p.x * q.y - q.x * p.y;
    }
    0.5 * a
}

/// Converts `[x, y]` points into vectors.
pub fn to_vecs(pts: &[[f64; 2]]) -> Vec<DVec2> {
    pts.iter().map(|p| DVec2::new(p[0], p[1])).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_distances() {
        let a = DVec2::new(0.0, 0.0);
        let b = DVec2::new(10.0, 0.0);
        assert!((dist_point_segment(DVec2::new(5.0, 3.0), a, b) - 3.0).abs() < 1e-12);
        assert!((dist_point_segment(DVec2::new(-4.0, 3.0), a, b) - 5.0).abs() < 1e-12);
        assert_eq!(dist_segment_segment(a, b, DVec2::new(5.0, -1.0), DVec2::new(5.0, 1.0)), 0.0);
        assert!((dist_segment_segment(a, b, DVec2::new(0.0, 2.0), DVec2::new(10.0, 2.0)) - 2.0).abs() < 1e-12);
        assert!((wrap_pi(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
        assert!((ring_area(&[a, b, DVec2::new(10.0, 10.0), DVec2::new(0.0, 10.0)]) - 100.0).abs() < 1e-12);
    }

    /// The exact arc–segment distance against the arc cut into chords whose sagitta is below
    /// 1e-7 mm, on seeded random arcs (both senses, up to a full turn) and segments, crossing
    /// or not.
    #[test]
    fn arc_segment_distance_agrees_with_fine_chords() {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut rnd = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut zero, mut apart) = (0, 0);
        for _ in 0..3000 {
            let c = DVec2::new(rnd() * 4.0 - 2.0, rnd() * 4.0 - 2.0);
            let r = 0.1 + rnd() * 5.0;
            let a0 = rnd() * 8.0 - 4.0;
            let sweep = (rnd() * 2.0 - 1.0) * std::f64::consts::TAU;
            let a = DVec2::new(rnd() * 16.0 - 8.0, rnd() * 16.0 - 8.0);
            let b = if rnd() < 0.1 { a } else { DVec2::new(rnd() * 16.0 - 8.0, rnd() * 16.0 - 8.0) };
            let half = (1.0 - 1e-7 / r).acos();
            let n = ((sweep.abs() / (2.0 * half)).ceil() as usize).max(1);
            let at = |t: f64| c + DVec2::from_angle(a0 + sweep * t) * r;
            let want = (0..n)
                .map(|i| dist_segment_segment(at(i as f64 / n as f64), at((i + 1) as f64 / n as f64), a, b))
                .fold(f64::INFINITY, f64::min);
            let got = dist_arc_segment(c, r, a0, sweep, a, b);
            assert!(
                (got - want).abs() < 1e-6,
                "arc {c} r {r} from {a0} by {sweep}, segment {a}–{b}: {got} against {want}"
            );
            if want == 0.0 { zero += 1 } else { apart += 1 }
        }
        // (both kinds were drawn)
        assert!(zero > 300 && apart > 300, "{zero} crossing, {apart} apart");
    }
}
