//! The offset contours that contour milling follows (paper 1 §4.4): the walls grown by the tool
//! radius and margin, walked by arc length in either direction, with the nearest point of them
//! to any place.

use crate::geom::DVec2;
use crate::geom::index::EdgeIndex;

/// The offset contours along the walls (followed in either direction: the one that keeps the
/// material on the milling side).
pub(super) struct Walls {
    rings: Vec<Vec<DVec2>>,
    cum: Vec<Vec<f64>>,
    index: EdgeIndex,
    owner: Vec<(usize, usize)>,
}

impl Walls {
    /// The contours of `grown` (the walls grown by the tool radius and margin).
    pub(super) fn new(grown: &crate::geom::Area, cell: f64) -> Walls {
        let mut rings = Vec::new();
        let mut cum = Vec::new();
        let mut edges = Vec::new();
        let mut owner = Vec::new();
        for ring in grown.rings() {
            let r = ring.clone();
            let n = r.len();
            let mut c = Vec::with_capacity(n + 1);
            let mut acc = 0.0;
            c.push(0.0);
            for i in 0..n {
                let (a, b) = (r[i], r[(i + 1) % n]);
                acc += (b - a).length();
                c.push(acc);
                edges.push((a, b));
                owner.push((rings.len(), i));
            }
            rings.push(r);
            cum.push(c);
        }
        Walls { rings, cum, index: EdgeIndex::new(edges, cell), owner }
    }

    pub(super) fn len(&self, ring: usize) -> f64 {
        *self.cum[ring].last().unwrap_or(&0.0)
    }

    /// Point and unit tangent at arc length `s` (wrapped) along `ring`.
    pub(super) fn at(&self, ring: usize, s: f64) -> (DVec2, DVec2) {
        let r = &self.rings[ring];
        let c = &self.cum[ring];
        let total = self.len(ring);
        let s = if total > 0.0 { s.rem_euclid(total) } else { 0.0 };
        let i = match c.binary_search_by(|v| v.total_cmp(&s)) {
            Ok(i) => i.min(r.len() - 1),
            Err(i) => i.saturating_sub(1).min(r.len() - 1),
        };
        let (a, b) = (r[i], r[(i + 1) % r.len()]);
        let seg = (c[i + 1] - c[i]).max(1e-12);
        let t = ((s - c[i]) / seg).clamp(0.0, 1.0);
        (a + (b - a) * t, (b - a).normalize_or_zero())
    }

    /// The vertices of `ring` strictly between arc lengths `s0` and `s1` (either direction, less
    /// than one turn), in the order of travel.
    pub(super) fn between(&self, ring: usize, s0: f64, s1: f64) -> Vec<DVec2> {
        let r = &self.rings[ring];
        let c = &self.cum[ring];
        let total = self.len(ring);
        if total <= 0.0 || (s1 - s0).abs() >= total {
            return Vec::new();
        }
        let n = r.len();
        let mut out = Vec::new();
        let a = s0.rem_euclid(total);
        let d = s1 - s0;
        // vertex i sits at c[i]; walk from a by d
        for i in 0..n {
            let v = c[i];
            let off = if d >= 0.0 { (v - a).rem_euclid(total) } else { (a - v).rem_euclid(total) };
            if off > 1e-9 && off < d.abs() - 1e-9 {
                out.push((off, r[i]));
            }
        }
        out.sort_by(|x, y| x.0.total_cmp(&y.0));
        out.into_iter().map(|x| x.1).collect()
    }

    /// The point of the contours nearest to `p`: ring, arc length, point.
    pub(super) fn project(&self, p: DVec2, max: f64) -> Option<(usize, f64, DVec2)> {
        let mut best: Option<(f64, usize, f64, DVec2)> = None;
        let m = DVec2::splat(max);
        self.index.for_each_near(p - m, p + m, |e, a, b| {
            let t = crate::geom::closest_param(p, a, b);
            let q = a + (b - a) * t;
            let d = (q - p).length();
            if best.is_none_or(|x| d < x.0) {
                let (ring, i) = self.owner[e];
                let s = self.cum[ring][i] + (b - a).length() * t;
                best = Some((d, ring, s, q));
            }
        });
        best.map(|(_, r, s, q)| (r, s, q))
    }
}
