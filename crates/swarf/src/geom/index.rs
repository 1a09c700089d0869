//! [`EdgeIndex`]: a uniform grid over line segments for fast "how close is the nearest edge"
//! questions — the gouge test of a tool centre against the part, the clearance of a link; and
//! [`InsideIndex`]: "is this point in the area" for many points against one large area.
//!
//! A uniform grid suits CAM geometry (edges of similar size spread over the stock) better than
//! a tree, and it is ten lines of code; each edge is listed in every cell its bounding box
//! touches (compressed-row storage).

use super::{Area, DVec2, closest_param, dist_arc_segment, dist_point_segment, dist_segment_segment, in_sweep};

/// Segments bucketed in a uniform grid.
#[derive(Debug, Clone)]
pub struct EdgeIndex {
    edges: Vec<(DVec2, DVec2)>,
    origin: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    start: Vec<u32>,
    items: Vec<u32>,
}

impl EdgeIndex {
    /// Indexes the given segments with square cells of side `cell` (mm).
    pub fn new(edges: Vec<(DVec2, DVec2)>, cell: f64) -> Self {
        let cell = if cell.is_finite() && cell > 0.0 { cell } else { 1.0 };
        if edges.is_empty() {
            return Self { edges, origin: DVec2::ZERO, cell, nx: 0, ny: 0, start: vec![0], items: vec![] };
        }
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for (a, b) in &edges {
            lo = lo.min(a.min(*b));
            hi = hi.max(a.max(*b));
        }
        // keep the grid to a sane number of cells whatever the cell size asked
        let span = (hi - lo).max(DVec2::splat(1e-9));
        let mut cell = cell;
        while (span.x / cell).ceil() * (span.y / cell).ceil() > 4.0e6 {
            cell *= 2.0;
        }
        let nx = ((span.x / cell).floor() as usize + 1).max(1);
        let ny = ((span.y / cell).floor() as usize + 1).max(1);
        let mut counts = vec![0u32; nx * ny + 1];
        let range = |a: DVec2, b: DVec2| {
            let l = a.min(b);
            let h = a.max(b);
            let x0 = (((l.x - lo.x) / cell).floor() as usize).min(nx - 1);
            let x1 = (((h.x - lo.x) / cell).floor() as usize).min(nx - 1);
            let y0 = (((l.y - lo.y) / cell).floor() as usize).min(ny - 1);
            let y1 = (((h.y - lo.y) / cell).floor() as usize).min(ny - 1);
            (x0, x1, y0, y1)
        };
        for (a, b) in &edges {
            let (x0, x1, y0, y1) = range(*a, *b);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    counts[y * nx + x] += 1;
                }
            }
        }
        let mut start = vec![0u32; nx * ny + 1];
        for i in 0..nx * ny {
            start[i + 1] = start[i] + counts[i];
        }
        let mut fill = start.clone();
        let mut items = vec![0u32; start[nx * ny] as usize];
        for (k, (a, b)) in edges.iter().enumerate() {
            let (x0, x1, y0, y1) = range(*a, *b);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let c = y * nx + x;
                    items[fill[c] as usize] = k as u32;
                    fill[c] += 1;
                }
            }
        }
        Self { edges, origin: lo, cell, nx, ny, start, items }
    }

    /// Indexes the edges of closed rings.
    pub fn from_rings<'a>(rings: impl Iterator<Item = &'a Vec<DVec2>>, cell: f64) -> Self {
        let mut edges = Vec::new();
        for r in rings {
            let n = r.len();
            for i in 0..n {
                edges.push((r[i], r[(i + 1) % n]));
            }
        }
        Self::new(edges, cell)
    }

    /// Indexes the boundary of an area.
    pub fn from_area(a: &super::Area, cell: f64) -> Self {
        Self::from_rings(a.rings(), cell)
    }

    /// True when there are no edges.
    pub fn is_empty(&self) -> bool {
        self.edges.is_empty()
    }

    /// The indexed segments.
    pub fn edges(&self) -> &[(DVec2, DVec2)] {
        &self.edges
    }

    /// Calls `f` with every edge whose cells meet the box `[lo, hi]`; edges may repeat.
    #[inline]
    pub fn for_each_near(&self, lo: DVec2, hi: DVec2, mut f: impl FnMut(usize, DVec2, DVec2)) {
        if self.nx == 0 {
            return;
        }
        let gx0 = ((lo.x - self.origin.x) / self.cell).floor();
        let gy0 = ((lo.y - self.origin.y) / self.cell).floor();
        let gx1 = ((hi.x - self.origin.x) / self.cell).floor();
        let gy1 = ((hi.y - self.origin.y) / self.cell).floor();
        if gx1 < 0.0 || gy1 < 0.0 || gx0 >= self.nx as f64 || gy0 >= self.ny as f64 {
            return;
        }
        let x0 = gx0.max(0.0) as usize;
        let y0 = gy0.max(0.0) as usize;
        let x1 = (gx1 as usize).min(self.nx - 1);
        let y1 = (gy1 as usize).min(self.ny - 1);
        for y in y0..=y1 {
            for x in x0..=x1 {
                let c = y * self.nx + x;
                for &k in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                    let (a, b) = self.edges[k as usize];
                    f(k as usize, a, b);
                }
            }
        }
    }

    /// Distance from `p` to the nearest edge, or `max` when none is closer than `max`.
    pub fn distance(&self, p: DVec2, max: f64) -> f64 {
        let mut best = max;
        let m = DVec2::splat(max);
        self.for_each_near(p - m, p + m, |_, a, b| {
            let d = dist_point_segment(p, a, b);
            if d < best {
                best = d;
            }
        });
        best
    }

    /// The nearest point of the edges to `p` and its distance, when one is closer than `max`.
    pub fn nearest(&self, p: DVec2, max: f64) -> Option<(DVec2, f64)> {
        let mut best: Option<(DVec2, f64)> = None;
        let m = DVec2::splat(max);
        self.for_each_near(p - m, p + m, |_, a, b| {
            let q = a + (b - a) * closest_param(p, a, b);
            let d = (q - p).length();
            if d < best.map_or(max, |b| b.1) {
                best = Some((q, d));
            }
        });
        best
    }

    /// Distance from the arc of centre `c` and radius `r` from angle `a0` sweeping `sweep` to
    /// the nearest edge, or `max` when none is closer.
    pub fn arc_distance(&self, c: DVec2, r: f64, a0: f64, sweep: f64, max: f64) -> f64 {
        // the arc's box: its ends and the axis points it passes
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        let ends = [a0, a0 + sweep];
        let quarter = std::f64::consts::FRAC_PI_2;
        for (k, phi) in ends.into_iter().chain((0..4).map(|k| k as f64 * quarter)).enumerate() {
            if k >= 2 && !in_sweep(phi, a0, sweep) {
                continue;
            }
            let p = c + DVec2::from_angle(phi) * r;
            lo = lo.min(p);
            hi = hi.max(p);
        }
        let mut best = max;
        let m = DVec2::splat(max);
        self.for_each_near(lo - m, hi + m, |_, p, q| {
            let dd = dist_arc_segment(c, r, a0, sweep, p, q);
            if dd < best {
                best = dd;
            }
        });
        best
    }

    /// Distance from segment `a`–`b` to the nearest edge, or `max` when none is closer.
    pub fn segment_distance(&self, a: DVec2, b: DVec2, max: f64) -> f64 {
        let mut best = max;
        let m = DVec2::splat(max);
        self.for_each_near(a.min(b) - m, a.max(b) + m, |_, c, d| {
            let dd = dist_segment_segment(a, b, c, d);
            if dd < best {
                best = dd;
            }
        });
        best
    }
}

/// Point-in-area by even–odd crossings, with the edges bucketed in horizontal bands so that a
/// query reads only the edges of its band: for many queries against an area of many vertices
/// ([`super::Area::contains`] reads every edge).
#[derive(Debug, Clone)]
pub struct InsideIndex {
    y0: f64,
    h: f64,
    bands: Vec<Vec<(DVec2, DVec2)>>,
}

impl InsideIndex {
    /// Indexes the rings of `area` in about one band per eight vertices (at most 4096).
    pub fn new(area: &Area) -> InsideIndex {
        let Some((lo, hi)) = area.bounds() else { return InsideIndex { y0: 0.0, h: 1.0, bands: Vec::new() } };
        let n = ((area.vertex_count() / 8).clamp(1, 4096)) as f64;
        let h = ((hi.y - lo.y) / n).max(1e-3);
        let nb = ((hi.y - lo.y) / h).floor() as usize + 1;
        let mut bands = vec![Vec::new(); nb];
        for ring in area.rings() {
            for i in 0..ring.len() {
                let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
                if a.y == b.y {
                    continue;
                }
                let j0 = (((a.y.min(b.y) - lo.y) / h).floor().max(0.0) as usize).min(nb - 1);
                let j1 = (((a.y.max(b.y) - lo.y) / h).floor().max(0.0) as usize).min(nb - 1);
                for band in &mut bands[j0..=j1] {
                    band.push((a, b));
                }
            }
        }
        InsideIndex { y0: lo.y, h, bands }
    }

    /// True when `p` is inside the area (even–odd; a point on an edge falls either way).
    pub fn contains(&self, p: DVec2) -> bool {
        let f = (p.y - self.y0) / self.h;
        if f.is_nan() || f < 0.0 || f as usize >= self.bands.len() {
            return false;
        }
        let mut inside = false;
        for &(a, b) in &self.bands[f as usize] {
            if (a.y > p.y) != (b.y > p.y) {
                let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                if p.x < x {
                    inside = !inside;
                }
            }
        }
        inside
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_edge_matches_brute_force() {
        let mut edges = Vec::new();
        let mut s: u64 = 12345;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 100.0
        };
        for _ in 0..300 {
            let a = DVec2::new(rnd(), rnd());
            let b = a + DVec2::new(rnd() / 20.0 - 2.5, rnd() / 20.0 - 2.5);
            edges.push((a, b));
        }
        let idx = EdgeIndex::new(edges.clone(), 3.0);
        for _ in 0..200 {
            let p = DVec2::new(rnd(), rnd());
            let brute = edges.iter().map(|(a, b)| dist_point_segment(p, *a, *b)).fold(f64::INFINITY, f64::min);
            let got = idx.distance(p, 8.0);
            assert!((got - brute.min(8.0)).abs() < 1e-12, "{got} vs {brute}");
            let q = p + DVec2::new(rnd() / 10.0 - 5.0, rnd() / 10.0 - 5.0);
            let brute2 = edges.iter().map(|(a, b)| dist_segment_segment(p, q, *a, *b)).fold(f64::INFINITY, f64::min);
            assert!((idx.segment_distance(p, q, 8.0) - brute2.min(8.0)).abs() < 1e-12);
            match idx.nearest(p, 8.0) {
                Some((at, d)) => {
                    assert!((d - brute).abs() < 1e-12 && (at - p).length() - d < 1e-12);
                    assert!(edges.iter().any(|(a, b)| dist_point_segment(at, *a, *b) < 1e-9));
                }
                None => assert!(brute >= 8.0),
            }
        }
    }

    #[test]
    fn inside_matches_the_area() {
        // a square with a square hole and, beside it, a rectangle with round corners (slanted
        // edges)
        let mut a = Area::rect(0.0, 0.0, 40.0, 40.0).difference(&Area::rect(10.0, 10.0, 30.0, 30.0));
        a = a.union(&Area::rect(55.0, 5.0, 75.0, 30.0).offset(4.0, 0.01));
        let idx = InsideIndex::new(&a);
        let mut s: u64 = 777;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 100.0 - 10.0
        };
        for _ in 0..2000 {
            let p = DVec2::new(rnd(), rnd());
            assert_eq!(idx.contains(p), a.contains(p), "{p:?}");
        }
        assert!(!InsideIndex::new(&Area::empty()).contains(DVec2::ZERO));
    }
}
