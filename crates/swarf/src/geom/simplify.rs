//! Douglas–Peucker simplification (paper 1 §5.1: the adaptive paths are chains of tiny linear
//! steps; Douglas–Peucker keeps the shape within a tolerance with far fewer points).
//!
//! The classic recursion (Douglas & Peucker 1973, as surveyed by Heckbert & Garland 1997): keep
//! the end points, find the point farthest from the chord, keep it and recurse on both halves if
//! it is farther than the tolerance. An explicit stack replaces recursion so that polylines of a
//! million points cannot overflow the call stack.

use super::{DVec2, dist_point_segment};

/// Simplifies an open polyline: every dropped point lies within `tol` of the result.
pub fn douglas_peucker(pts: &[DVec2], tol: f64) -> Vec<DVec2> {
    let n = pts.len();
    if n <= 2 {
        return pts.to_vec();
    }
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[n - 1] = true;
    let mut stack = vec![(0usize, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j <= i + 1 {
            continue;
        }
        let (a, b) = (pts[i], pts[j]);
        let mut worst = 0.0;
        let mut k_worst = i;
        for (k, p) in pts.iter().enumerate().take(j).skip(i + 1) {
            let d = dist_point_segment(*p, a, b);
            if d > worst {
                worst = d;
                k_worst = k;
            }
        }
        if worst > tol {
            keep[k_worst] = true;
            stack.push((i, k_worst));
            stack.push((k_worst, j));
        }
    }
    pts.iter().zip(keep).filter(|(_, k)| *k).map(|(p, _)| *p).collect()
}

/// Simplifies a closed ring (no repeated end point): splits it at the vertex farthest from the
/// first one and simplifies both halves.
pub fn douglas_peucker_ring(pts: &[DVec2], tol: f64) -> Vec<DVec2> {
    let n = pts.len();
    if n <= 3 {
        return pts.to_vec();
    }
    let far = (1..n)
        .max_by(|&a, &b| (pts[a] - pts[0]).length_squared().total_cmp(&(pts[b] - pts[0]).length_squared()))
        .unwrap_or(n / 2);
    let mut first: Vec<DVec2> = pts[..=far].to_vec();
    let mut second: Vec<DVec2> = pts[far..].to_vec();
    second.push(pts[0]);
    first = douglas_peucker(&first, tol);
    second = douglas_peucker(&second, tol);
    first.pop();
    second.pop();
    first.extend(second);
    first
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_shape_within_tolerance() {
        let pts: Vec<DVec2> = (0..=1000)
            .map(|i| {
                let t = i as f64 / 1000.0 * std::f64::consts::PI;
                DVec2::new(10.0 * t.cos(), 10.0 * t.sin())
            })
            .collect();
        let s = douglas_peucker(&pts, 0.01);
        assert!(s.len() < 80 && s.len() > 30, "{}", s.len());
        assert_eq!(s.first(), pts.first());
        assert_eq!(s.last(), pts.last());
        for p in &pts {
            let d = s.windows(2).map(|w| dist_point_segment(*p, w[0], w[1])).fold(f64::INFINITY, f64::min);
            assert!(d <= 0.01 + 1e-12);
        }
        // a straight line collapses to its ends
        let line: Vec<DVec2> = (0..50).map(|i| DVec2::new(i as f64, 2.0 * i as f64)).collect();
        assert_eq!(douglas_peucker(&line, 1e-9).len(), 2);
        let ring: Vec<DVec2> = (0..400)
            .map(|i| {
                let t = i as f64 / 400.0 * std::f64::consts::TAU;
                DVec2::new(5.0 * t.cos(), 5.0 * t.sin())
            })
            .collect();
        let r = douglas_peucker_ring(&ring, 0.005);
        assert!(r.len() < 150 && r.len() >= 60, "{}", r.len());
    }
}
