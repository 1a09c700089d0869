//! Contours: chains of straight and circular-arc segments in the bulge form of DXF's LWPOLYLINE.
//!
//! A [`Contour`] is a list of [`Vertex`]; vertex `i` carries the *bulge* of the segment from
//! vertex `i` to vertex `i + 1` (for a closed contour the last vertex's bulge describes the
//! closing segment back to vertex 0). The bulge is `tan(sweep / 4)`: 0 is a straight line,
//! positive values are counter-clockwise arcs, negative values clockwise arcs, ±1 a half circle.
//! Arcs are kept exact until a consumer asks for a polygon with [`Contour::flatten`].

/// One vertex of a [`Contour`] and the bulge of the segment that leaves it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vertex {
    /// X in millimetres.
    pub x: f64,
    /// Y in millimetres.
    pub y: f64,
    /// `tan(sweep/4)` of the segment from this vertex to the next; 0 for a line.
    pub bulge: f64,
}

impl Vertex {
    /// A vertex with a straight segment after it.
    pub fn new(x: f64, y: f64) -> Self {
        Self { x, y, bulge: 0.0 }
    }
    /// A vertex with the given bulge after it.
    pub fn with_bulge(x: f64, y: f64, bulge: f64) -> Self {
        Self { x, y, bulge }
    }
}

/// A chain of line and arc segments, open or closed.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Contour {
    /// The vertices in order.
    pub vertices: Vec<Vertex>,
    /// Whether the last vertex connects back to the first.
    pub closed: bool,
}

/// One segment of a contour, resolved to its geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Segment {
    /// A straight line from `a` to `b`.
    Line { a: [f64; 2], b: [f64; 2] },
    /// A circular arc from `a` to `b` around `center`, counter-clockwise when `ccw`.
    Arc { a: [f64; 2], b: [f64; 2], center: [f64; 2], radius: f64, ccw: bool, sweep: f64 },
}

impl Segment {
    /// Builds the segment from `a` to `b` with the given bulge.
    pub fn from_bulge(a: [f64; 2], b: [f64; 2], bulge: f64) -> Segment {
        let dx = b[0] - a[0];
        let dy = b[1] - a[1];
        let chord = (dx * dx + dy * dy).sqrt();
        if bulge.abs() < 1e-12 || chord < 1e-12 {
            return Segment::Line { a, b };
        }
        let sweep = 4.0 * bulge.atan(); // signed
        let radius = chord / (2.0 * (sweep / 2.0).sin().abs());
        // distance from the chord midpoint to the centre, signed toward the left of a->b for ccw
        let s = (1.0 - bulge * bulge) / (4.0 * bulge) * chord; // = sagitta-complement, signed
        let mx = (a[0] + b[0]) / 2.0;
        let my = (a[1] + b[1]) / 2.0;
        let nx = -dy / chord;
        let ny = dx / chord;
        let center = [mx + nx * s, my + ny * s];
        Segment::Arc { a, b, center, radius, ccw: bulge > 0.0, sweep }
    }

    /// Start point.
    pub fn start(&self) -> [f64; 2] {
        match *self {
            Segment::Line { a, .. } | Segment::Arc { a, .. } => a,
        }
    }
    /// End point.
    pub fn end(&self) -> [f64; 2] {
        match *self {
            Segment::Line { b, .. } | Segment::Arc { b, .. } => b,
        }
    }
    /// Length along the segment.
    pub fn length(&self) -> f64 {
        match *self {
            Segment::Line { a, b } => ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt(),
            Segment::Arc { radius, sweep, .. } => radius * sweep.abs(),
        }
    }

    /// Appends points along the segment (excluding its start, including its end) so that no
    /// chord is farther than `tol` from the arc.
    pub fn flatten_into(&self, tol: f64, out: &mut Vec<[f64; 2]>) {
        match *self {
            Segment::Line { b, .. } => out.push(b),
            Segment::Arc { a, b, center, radius, sweep, .. } => {
                let n = arc_steps(radius, sweep.abs(), tol);
                let a0 = (a[1] - center[1]).atan2(a[0] - center[0]);
                for i in 1..n {
                    let t = a0 + sweep * (i as f64) / (n as f64);
                    out.push([center[0] + radius * t.cos(), center[1] + radius * t.sin()]);
                }
                out.push(b);
            }
        }
    }
}

/// Number of chords needed for an arc of `radius` and absolute `sweep` so that the sagitta
/// stays within `tol`.
pub fn arc_steps(radius: f64, sweep: f64, tol: f64) -> usize {
    let tol = tol.max(1e-9);
    let step = if tol >= radius { std::f64::consts::PI / 2.0 } else { 2.0 * (1.0 - tol / radius).acos() };
    let n = (sweep / step.max(1e-6)).ceil();
    (n as usize).clamp(1, 1 << 20)
}

impl Contour {
    /// A closed contour through the given points, all straight segments.
    pub fn polygon(points: &[[f64; 2]]) -> Contour {
        Contour { vertices: points.iter().map(|p| Vertex::new(p[0], p[1])).collect(), closed: true }
    }

    /// A full circle as two half-circle arcs (counter-clockwise).
    pub fn circle(cx: f64, cy: f64, r: f64) -> Contour {
        Contour {
            vertices: vec![Vertex::with_bulge(cx + r, cy, 1.0), Vertex::with_bulge(cx - r, cy, 1.0)],
            closed: true,
        }
    }

    /// The segments in order (the closing one included for a closed contour).
    pub fn segments(&self) -> Vec<Segment> {
        let n = self.vertices.len();
        let count = if self.closed { n } else { n.saturating_sub(1) };
        (0..count)
            .map(|i| {
                let v = self.vertices[i];
                let w = self.vertices[(i + 1) % n];
                Segment::from_bulge([v.x, v.y], [w.x, w.y], v.bulge)
            })
            .collect()
    }

    /// Points along the contour with chord error at most `tol` (mm). For a closed contour the
    /// first point is not repeated at the end.
    pub fn flatten(&self, tol: f64) -> Vec<[f64; 2]> {
        let mut out = Vec::with_capacity(self.vertices.len() * 2);
        if let Some(v) = self.vertices.first() {
            out.push([v.x, v.y]);
        }
        for s in self.segments() {
            s.flatten_into(tol, &mut out);
        }
        if self.closed && out.len() > 1 {
            out.pop();
        }
        out
    }

    /// Signed area (positive when counter-clockwise), arcs included exactly.
    pub fn signed_area(&self) -> f64 {
        if !self.closed {
            return 0.0;
        }
        let mut a = 0.0;
        for s in self.segments() {
            let p = s.start();
            let q = s.end();
            a += 0.5 * (p[0] * q[1] - q[0] * p[1]);
            if let Segment::Arc { radius, sweep, .. } = s {
                // circular segment between chord and arc, signed with the sweep
                a += 0.5 * radius * radius * (sweep - sweep.sin());
            }
        }
        a
    }

    /// Total length.
    pub fn length(&self) -> f64 {
        self.segments().iter().map(Segment::length).sum()
    }

    /// Axis-aligned bounds `[xmin, ymin, xmax, ymax]` of the flattened contour.
    pub fn bounds(&self) -> Option<[f64; 4]> {
        let pts = self.flatten(1e-3);
        let mut it = pts.iter();
        let f = it.next()?;
        let mut b = [f[0], f[1], f[0], f[1]];
        for p in it {
            b[0] = b[0].min(p[0]);
            b[1] = b[1].min(p[1]);
            b[2] = b[2].max(p[0]);
            b[3] = b[3].max(p[1]);
        }
        Some(b)
    }

    /// Reverses the direction (bulges change sign and move to the other end of their segment).
    pub fn reverse(&mut self) {
        let n = self.vertices.len();
        if n == 0 {
            return;
        }
        let old = self.vertices.clone();
        for i in 0..n {
            let v = old[n - 1 - i];
            // the segment leaving new vertex i is old segment (n-2-i) reversed (open), or for a
            // closed contour old segment (n-2-i) mod n
            let seg = if self.closed { (2 * n - 2 - i) % n } else { n.wrapping_sub(2).wrapping_sub(i) };
            let bulge = if seg < n && (self.closed || i + 1 < n) { -old[seg].bulge } else { 0.0 };
            self.vertices[i] = Vertex { x: v.x, y: v.y, bulge };
        }
    }

    /// Scales every coordinate by `s` (bulges are scale-free).
    pub fn scale(&mut self, s: f64) {
        for v in &mut self.vertices {
            v.x *= s;
            v.y *= s;
        }
    }

    /// True when every coordinate and bulge is finite.
    pub fn is_finite(&self) -> bool {
        self.vertices.iter().all(|v| v.x.is_finite() && v.y.is_finite() && v.bulge.is_finite())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_area_and_length_are_exact() {
        let c = Contour::circle(1.0, 2.0, 3.0);
        assert!((c.signed_area() - std::f64::consts::PI * 9.0).abs() < 1e-9);
        assert!((c.length() - 2.0 * std::f64::consts::PI * 3.0).abs() < 1e-9);
        let pts = c.flatten(0.001);
        for p in &pts {
            let r = ((p[0] - 1.0).powi(2) + (p[1] - 2.0).powi(2)).sqrt();
            assert!((r - 3.0).abs() < 1e-9);
        }
        assert!(pts.len() > 100);
    }

    #[test]
    fn reverse_keeps_area_magnitude_and_flips_sign() {
        let mut c = Contour {
            vertices: vec![
                Vertex::new(0.0, 0.0),
                Vertex::with_bulge(10.0, 0.0, 0.5),
                Vertex::new(10.0, 10.0),
                Vertex::new(0.0, 10.0),
            ],
            closed: true,
        };
        let a = c.signed_area();
        c.reverse();
        assert!((c.signed_area() + a).abs() < 1e-9, "{} vs {}", c.signed_area(), a);
        let mut o = Contour { vertices: vec![Vertex::with_bulge(0.0, 0.0, 1.0), Vertex::new(2.0, 0.0)], closed: false };
        let l = o.length();
        o.reverse();
        assert!((o.length() - l).abs() < 1e-12);
        assert_eq!(o.vertices[0].bulge, -1.0);
        assert_eq!(o.vertices[1].bulge, 0.0);
    }

    #[test]
    fn arc_centre_from_bulge() {
        // quarter circle ccw from (1,0) to (0,1) around the origin: bulge tan(pi/8)
        let s = Segment::from_bulge([1.0, 0.0], [0.0, 1.0], (std::f64::consts::PI / 8.0).tan());
        match s {
            Segment::Arc { center, radius, ccw, .. } => {
                assert!(center[0].abs() < 1e-12 && center[1].abs() < 1e-12);
                assert!((radius - 1.0).abs() < 1e-12);
                assert!(ccw);
            }
            Segment::Line { .. } => panic!("expected an arc"),
        }
    }
}
