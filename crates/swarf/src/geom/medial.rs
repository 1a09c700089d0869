//! The medial axis of a region: the centres of its maximal inscribed circles, with their radii
//! (paper 2's \[8\], MATHSM §2: "the medial axis transform").
//!
//! It is read off the Voronoi diagram of the region's boundary segments (the `boostvoronoi`
//! crate, a port of Boost.Polygon's robust sweep over integer input): the primary edges of
//! the diagram whose points lie inside the region are the medial axis. An edge between two
//! segment sites is straight; one between a segment and an endpoint of another is a parabola,
//! sampled here exactly (the foot on the segment's line parametrises it); the radius at any
//! point is its distance to the edge's sites.
//!
//! Tiny boundary features give the axis spurious branches (every vertex of a polygon that
//! stands for a circle sends a spoke into it). A point of the axis is kept when its *object
//! angle* — the angle at the point between the directions to its two nearest boundary points
//! — is at least `min_angle`: a spoke into a vertex that turns by a few degrees sees its two
//! feet a few degrees apart, while the axis of a channel sees them on opposite sides (180°)
//! and a branch into a right-angled corner sees them 90° apart.

use super::{Area, DVec2};
use boostvoronoi::prelude::*;

/// Input units per millimetre: the diagram is built on integers (0.1 µm).
const SCALE: f64 = 1e4;

/// A vertex of the axis.
#[derive(Debug, Clone)]
pub struct Node {
    /// Position, mm.
    pub p: DVec2,
    /// Radius of the maximal inscribed circle there, mm.
    pub r: f64,
    /// Incident edges (indices into [`Axis::edges`]).
    pub edges: Vec<usize>,
}

/// An edge of the axis: a polyline from node `a` to node `b` with the radius at each point.
#[derive(Debug, Clone)]
pub struct AxisEdge {
    /// First node.
    pub a: usize,
    /// Last node.
    pub b: usize,
    /// Points from `a` to `b` (both included).
    pub pts: Vec<DVec2>,
    /// The inscribed radius at each point.
    pub rad: Vec<f64>,
}

impl AxisEdge {
    /// The node at the other end from `n`.
    pub fn other(&self, n: usize) -> usize {
        if self.a == n { self.b } else { self.a }
    }

    /// Points and radii walked from node `n`.
    pub fn from(&self, n: usize) -> Vec<(DVec2, f64)> {
        let mut v: Vec<(DVec2, f64)> = self.pts.iter().copied().zip(self.rad.iter().copied()).collect();
        if self.a != n {
            v.reverse();
        }
        v
    }
}

/// The medial axis: a graph (a tree for a region without holes).
#[derive(Debug, Clone, Default)]
pub struct Axis {
    /// Vertices.
    pub nodes: Vec<Node>,
    /// Edges.
    pub edges: Vec<AxisEdge>,
}

/// A boundary site of the diagram.
#[derive(Debug, Clone, Copy)]
enum Site {
    Point(DVec2),
    Segment(DVec2, DVec2),
}

impl Site {
    /// Nearest point of the site to `q`.
    fn foot(&self, q: DVec2) -> DVec2 {
        match *self {
            Site::Point(p) => p,
            Site::Segment(a, b) => {
                let ab = b - a;
                let t = ((q - a).dot(ab) / ab.length_squared().max(1e-300)).clamp(0.0, 1.0);
                a + ab * t
            }
        }
    }
}

/// The medial axis of `area`, with spurious branches pruned by the object angle (degrees).
/// Errors name what the Voronoi construction refused.
pub fn medial_axis(area: &Area, min_angle_deg: f64) -> Result<Axis, String> {
    let mut segs: Vec<[i32; 4]> = Vec::new();
    let q = |v: f64| -> Result<i32, String> {
        let x = (v * SCALE).round();
        if x.abs() < 2.0e9 { Ok(x as i32) } else { Err(format!("coordinate {v} mm is too large")) }
    };
    for ring in area.rings() {
        let n = ring.len();
        for i in 0..n {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            let s = [q(a.x)?, q(a.y)?, q(b.x)?, q(b.y)?];
            if s[0] != s[2] || s[1] != s[3] {
                segs.push(s);
            }
        }
    }
    if segs.is_empty() {
        return Ok(Axis::default());
    }
    let mm = |x: i32, y: i32| DVec2::new(x as f64 / SCALE, y as f64 / SCALE);
    let diagram = Builder::<i32>::default()
        .with_segments(segs.iter())
        .and_then(|b| b.build())
        .map_err(|e| format!("the Voronoi diagram of the boundary failed: {e:?}"))?;
    let site_of = |cell: CellIndex| -> Option<Site> {
        let c = diagram.cell(cell).ok()?;
        let s = segs.get(c.source_index().usize())?;
        Some(match c.source_category() {
            SourceCategory::SegmentStart => Site::Point(mm(s[0], s[1])),
            SourceCategory::SegmentEnd => Site::Point(mm(s[2], s[3])),
            SourceCategory::Segment => Site::Segment(mm(s[0], s[1]), mm(s[2], s[3])),
            SourceCategory::SinglePoint => return None,
        })
    };
    let min_cos = min_angle_deg.to_radians().cos();
    let mut axis = Axis::default();
    let mut node_of: std::collections::HashMap<usize, usize> = std::collections::HashMap::new();
    for e in diagram.edges() {
        let id = e.id();
        let Ok(twin) = e.twin() else { continue };
        if twin.usize() < id.usize() || !e.is_primary() {
            continue;
        }
        let (Some(v0), Ok(Some(v1))) = (e.vertex0(), diagram.edge_get_vertex1(id)) else { continue };
        let (Ok(p0), Ok(p1)) = (diagram.vertex(v0), diagram.vertex(v1)) else { continue };
        let (p0, p1) = (DVec2::new(p0.x(), p0.y()) / SCALE, DVec2::new(p1.x(), p1.y()) / SCALE);
        let (Ok(c1), Ok(c2)) = (e.cell(), diagram.edge(twin).and_then(|t| t.cell())) else { continue };
        let (Some(s1), Some(s2)) = (site_of(c1), site_of(c2)) else { continue };
        let pts = sample_edge(p0, p1, s1, s2);
        // inside the region (the diagram also covers the holes and the outside)
        let mid = pts[pts.len() / 2];
        if !area.contains(mid) || (pts.len() == 2 && !area.contains(0.5 * (p0 + p1))) {
            continue;
        }
        // object angle at the middle
        let (f1, f2) = (s1.foot(mid), s2.foot(mid));
        let (d1, d2) = (f1 - mid, f2 - mid);
        if d1.length() < 1e-9 || d2.length() < 1e-9 || d1.normalize().dot(d2.normalize()) > min_cos {
            continue;
        }
        let rad: Vec<f64> = pts.iter().map(|p| (s1.foot(*p) - *p).length()).collect();
        let mut node = |v: usize, p: DVec2, r: f64, axis: &mut Axis| -> usize {
            *node_of.entry(v).or_insert_with(|| {
                axis.nodes.push(Node { p, r, edges: Vec::new() });
                axis.nodes.len() - 1
            })
        };
        let a = node(v0.usize(), p0, rad[0], &mut axis);
        let b = node(v1.usize(), p1, rad[rad.len() - 1], &mut axis);
        if a == b {
            continue;
        }
        let k = axis.edges.len();
        axis.nodes[a].edges.push(k);
        axis.nodes[b].edges.push(k);
        axis.edges.push(AxisEdge { a, b, pts, rad });
    }
    Ok(axis)
}

/// Points along the Voronoi edge from `p0` to `p1` between sites `s1` and `s2`: the two ends
/// for a straight edge (two segments, or two points), a parabola sampled every ~0.1 mm when
/// one site is a point and the other a segment. Long straight edges are split too, so that
/// callers can interpolate the radius (not linear between two point sites).
fn sample_edge(p0: DVec2, p1: DVec2, s1: Site, s2: Site) -> Vec<DVec2> {
    let len = (p1 - p0).length();
    let n = ((len / 0.1).ceil() as usize).clamp(1, 256);
    let (focus, a, b) = match (s1, s2) {
        (Site::Point(f), Site::Segment(a, b)) | (Site::Segment(a, b), Site::Point(f)) => (f, a, b),
        _ => return (0..=n).map(|k| p0 + (p1 - p0) * (k as f64 / n as f64)).collect(),
    };
    let u = (b - a).normalize_or_zero();
    let mut nrm = DVec2::new(-u.y, u.x);
    let mut dp = (focus - a).dot(nrm);
    if dp < 0.0 {
        nrm = -nrm;
        dp = -dp;
    }
    if dp < 1e-9 || u == DVec2::ZERO {
        return (0..=n).map(|k| p0 + (p1 - p0) * (k as f64 / n as f64)).collect();
    }
    // points equidistant from the focus and the line: foot t along the line, height
    // h = ((t − t_f)² + d²) / 2d
    let tf = (focus - a).dot(u);
    let (t0, t1) = ((p0 - a).dot(u), (p1 - a).dot(u));
    let mut out = Vec::with_capacity(n + 1);
    out.push(p0);
    for k in 1..n {
        let t = t0 + (t1 - t0) * (k as f64 / n as f64);
        let h = ((t - tf) * (t - tf) + dp * dp) / (2.0 * dp);
        out.push(a + u * t + nrm * h);
    }
    out.push(p1);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn longest(ax: &Axis) -> f64 {
        ax.nodes.iter().map(|n| n.r).fold(0.0, f64::max)
    }

    #[test]
    fn a_rectangle_has_a_spine_and_four_corner_branches() {
        let ax = medial_axis(&Area::rect(0.0, 0.0, 40.0, 20.0), 20.0).expect("axis");
        // the spine from (10, 10) to (30, 10) at radius 10, and one branch into each corner
        assert!((longest(&ax) - 10.0).abs() < 1e-6, "{}", longest(&ax));
        let leaves: Vec<&Node> = ax.nodes.iter().filter(|n| n.edges.len() == 1).collect();
        assert_eq!(leaves.len(), 4, "{:?}", ax.nodes);
        for l in leaves {
            assert!(l.r < 1e-6, "a corner: {l:?}");
        }
        // every point of the axis is as far from the boundary as its radius says
        for e in &ax.edges {
            for (p, r) in e.pts.iter().zip(&e.rad) {
                let d = p.x.min(40.0 - p.x).min(p.y).min(20.0 - p.y);
                assert!((d - r).abs() < 1e-6, "{p:?}: {r} vs {d}");
            }
        }
    }

    #[test]
    fn a_polygon_circle_has_no_spokes() {
        // a circle of radius 15 as a 200-gon: its vertices turn by 1.8°, and the axis is pruned
        // to the few edges round the centre
        let ring: Vec<DVec2> = (0..200)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / 200.0;
                DVec2::new(15.0 * a.cos(), 15.0 * a.sin())
            })
            .collect();
        let ax = medial_axis(&Area::from_rings(&[ring], crate::geom::area::Fill::NonZero), 20.0).expect("axis");
        for n in &ax.nodes {
            assert!(n.r > 14.0, "a spoke remains: {n:?}");
        }
    }

    #[test]
    fn a_hole_makes_a_loop_and_parabolic_edges_keep_their_radius() {
        let outer = Area::rect(0.0, 0.0, 50.0, 50.0);
        let hole = Area::rect(20.0, 20.0, 30.0, 30.0);
        let region = outer.difference(&hole);
        let ax = medial_axis(&region, 20.0).expect("axis");
        assert!(!ax.edges.is_empty());
        // the axis stays between the hole and the outside, at the radius it states
        let dist = |p: DVec2| {
            let out = p.x.min(50.0 - p.x).min(p.y).min(50.0 - p.y);
            let dx = (20.0 - p.x).max(p.x - 30.0).max(0.0);
            let dy = (20.0 - p.y).max(p.y - 30.0).max(0.0);
            out.min((dx * dx + dy * dy).sqrt())
        };
        let mut curved = 0;
        for e in &ax.edges {
            curved += usize::from(e.pts.len() > 2);
            for (p, r) in e.pts.iter().zip(&e.rad) {
                assert!((dist(*p) - r).abs() < 1e-3, "{p:?}: {r} vs {}", dist(*p));
            }
        }
        assert!(curved > 0, "the hole's corners make parabolic edges");
        // a loop round the hole: more edges than a tree on the same nodes would have
        assert!(ax.edges.len() >= ax.nodes.len(), "{} edges, {} nodes", ax.edges.len(), ax.nodes.len());
    }
}
