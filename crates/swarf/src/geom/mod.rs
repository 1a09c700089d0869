//! Planar geometry: areas with holes and their booleans and offsets, polylines, distance
//! queries, simplification and arc fitting.
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
}
