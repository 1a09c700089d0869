//! [`Area`]: a set of polygons with holes, and the one adapter over `i_overlay`.
//!
//! Every boolean, offset, stroke and polyline clip of the engine goes through this module, so
//! that the pinned `i_overlay` version (its API moves fast) is touched in one place only.
//! Results are normalised the way `i_overlay` returns them: outer rings counter-clockwise, holes
//! clockwise, no self-intersections.
//!
//! Offsets use round joins. A round join is a polygon whose vertices lie on a circle of the
//! requested radius, so its chords fall *inside* that circle; an offset used to keep a tool away
//! from the part would then let the tool come closer than asked, by the sagitta. [`Area::offset`]
//! therefore pushes the join vertices out to `d / cos(step / 2)`: every chord is at least `d`
//! from the corner, and straight edges move by at most `tol` more than `d` (a quarter of `tol`
//! more again, for the simplification the offset makes first).

use super::DVec2;
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::clip::FloatClip;
use i_overlay::float::single::SingleFloatOverlay;
use i_overlay::mesh::float::outline::offset::OutlineOffset;
use i_overlay::mesh::float::stroke::offset::StrokeOffset;
use i_overlay::mesh::float::style::{LineCap, LineJoin, OutlineStyle, StrokeStyle};
use i_overlay::string::clip::ClipRule;

type Pt = [f64; 2];

/// One polygon: an outer ring (counter-clockwise) and its holes (clockwise). Rings are not
/// closed explicitly (the last point is not a copy of the first).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Polygon {
    /// Outer boundary, counter-clockwise.
    pub outer: Vec<DVec2>,
    /// Holes, clockwise.
    pub holes: Vec<Vec<DVec2>>,
}

impl Polygon {
    /// Area (outer minus holes).
    pub fn area(&self) -> f64 {
        super::ring_area(&self.outer) + self.holes.iter().map(|h| super::ring_area(h)).sum::<f64>()
    }
    /// All rings, outer first.
    pub fn rings(&self) -> impl Iterator<Item = &Vec<DVec2>> {
        std::iter::once(&self.outer).chain(self.holes.iter())
    }
}

/// A region of the plane: disjoint polygons with holes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Area {
    /// The polygons.
    pub polys: Vec<Polygon>,
}

/// How overlapping input rings combine into an area.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fill {
    /// A point is inside when it is inside an odd number of rings (nesting alternates).
    EvenOdd,
    /// A point is inside when the winding number is not zero.
    NonZero,
}

/// Share of an offset's tolerance its rings are simplified within before they are offset (see
/// [`Area::offset`]).
const OFFSET_SIMPLIFY: f64 = 0.25;

/// The smallest angular step of a round join that `i_overlay` accepts (it clamps to 0.01·π).
const MIN_JOIN_STEP: f64 = 0.01 * std::f64::consts::PI;

fn to_pts(r: &[DVec2]) -> Vec<Pt> {
    r.iter().map(|p| [p.x, p.y]).collect()
}

fn from_shapes(shapes: Vec<Vec<Vec<Pt>>>) -> Area {
    let mut polys = Vec::with_capacity(shapes.len());
    for shape in shapes {
        let mut it = shape.into_iter();
        let Some(outer) = it.next() else { continue };
        let outer: Vec<DVec2> = outer.into_iter().map(|p| DVec2::new(p[0], p[1])).collect();
        if outer.len() < 3 {
            continue;
        }
        let holes: Vec<Vec<DVec2>> = it
            .map(|h| h.into_iter().map(|p| DVec2::new(p[0], p[1])).collect::<Vec<_>>())
            .filter(|h| h.len() >= 3)
            .collect();
        polys.push(Polygon { outer, holes });
    }
    Area { polys }
}

impl Area {
    /// The empty area.
    pub fn empty() -> Area {
        Area::default()
    }

    /// An axis-aligned rectangle.
    pub fn rect(xmin: f64, ymin: f64, xmax: f64, ymax: f64) -> Area {
        Area::from_rings(
            &[vec![DVec2::new(xmin, ymin), DVec2::new(xmax, ymin), DVec2::new(xmax, ymax), DVec2::new(xmin, ymax)]],
            Fill::NonZero,
        )
    }

    /// A disk, polygonised so that it contains the true disk (vertices on radius
    /// `r / cos(step/2)`, chords within `tol` of the circle).
    pub fn disk(c: DVec2, r: f64, tol: f64) -> Area {
        let n = swarf_import::contour::arc_steps(r, std::f64::consts::TAU, tol).max(8);
        let step = std::f64::consts::TAU / n as f64;
        let rr = r / (step / 2.0).cos();
        let ring: Vec<DVec2> =
            (0..n).map(|i| c + rr * DVec2::new((i as f64 * step).cos(), (i as f64 * step).sin())).collect();
        Area::from_rings(&[ring], Fill::NonZero)
    }

    /// Builds an area from rings of any orientation, combined by `fill`.
    pub fn from_rings(rings: &[Vec<DVec2>], fill: Fill) -> Area {
        let contours: Vec<Vec<Pt>> = rings.iter().filter(|r| r.len() >= 3).map(|r| to_pts(r)).collect();
        if contours.is_empty() {
            return Area::empty();
        }
        let rule = match fill {
            Fill::EvenOdd => FillRule::EvenOdd,
            Fill::NonZero => FillRule::NonZero,
        };
        // union of the subject with nothing normalises it under the fill rule
        let empty: Vec<Vec<Pt>> = Vec::new();
        from_shapes(contours.overlay(&empty, OverlayRule::Subject, rule))
    }

    fn shapes(&self) -> Vec<Vec<Vec<Pt>>> {
        self.polys.iter().map(|p| p.rings().map(|r| to_pts(r)).collect()).collect()
    }

    fn op(&self, other: &Area, rule: OverlayRule) -> Area {
        if self.polys.is_empty() && other.polys.is_empty() {
            return Area::empty();
        }
        from_shapes(self.shapes().overlay(&other.shapes(), rule, FillRule::NonZero))
    }

    /// Points in either area.
    pub fn union(&self, other: &Area) -> Area {
        if other.is_empty() {
            return self.clone();
        }
        if self.is_empty() {
            return other.clone();
        }
        self.op(other, OverlayRule::Union)
    }

    /// Points in `self` and not in `other`.
    pub fn difference(&self, other: &Area) -> Area {
        if self.is_empty() || other.is_empty() {
            return self.clone();
        }
        self.op(other, OverlayRule::Difference)
    }

    /// Points in both areas.
    pub fn intersection(&self, other: &Area) -> Area {
        if self.is_empty() || other.is_empty() {
            return Area::empty();
        }
        self.op(other, OverlayRule::Intersect)
    }

    /// Union of many areas.
    pub fn union_all<'a>(items: impl IntoIterator<Item = &'a Area>) -> Area {
        let mut shapes: Vec<Vec<Vec<Pt>>> = Vec::new();
        for a in items {
            shapes.extend(a.shapes());
        }
        if shapes.is_empty() {
            return Area::empty();
        }
        let empty: Vec<Vec<Vec<Pt>>> = Vec::new();
        from_shapes(shapes.overlay(&empty, OverlayRule::Subject, FillRule::NonZero))
    }

    /// Offsets the boundary by `d` (grow when positive, shrink when negative) with round joins.
    /// The result never comes closer than `|d|` to the original boundary, and straight edges move
    /// by at most `|d| + 1.25·tol`.
    pub fn offset(&self, d: f64, tol: f64) -> Area {
        if self.is_empty() || d == 0.0 {
            return self.clone();
        }
        // Each ring is simplified within a quarter of the tolerance first (Douglas–Peucker), and
        // offset by that much more: a dense boundary (a drawing's splines, an earlier offset's
        // joins) gives the overlay thousands of short edges whose offsets overlap where the
        // boundary bends away by less than |d|, and their crossings, not the result, were most
        // of its time (a third of simple_part's planning, half of a gear drawing's). The
        // simplified ring is within `e` of the original both ways, so offsetting it by `|d| + e`
        // still keeps `|d|` from the original; straight edges move by `e` more than they did
        // (the joins keep the angular step they had: the medial axis of a region prunes its
        // branches by the angle they see, and a finer step changed pocket_islands' axis).
        let e = OFFSET_SIMPLIFY * tol;
        let step = join_step(d.abs(), tol);
        let dd = (d + e * d.signum()) / (step / 2.0).cos();
        let style = OutlineStyle::new(dd).line_join(LineJoin::Round(step));
        // rings the offset closes are left out first: a hole (when growing) or a polygon (when
        // shrinking) no wider than 2|d| in x or y holds no disk of radius |d|, so nothing of it
        // is left, and the offset of a dense small ring by more than its size is a tangle of
        // overlapping joins that costs the overlay seconds (a bolt hole of 700 facet edges
        // grown shut by a tool radius: 2.8 s alone)
        let gone = |r: &Vec<DVec2>| {
            let (lo, hi) = r.iter().fold((r[0], r[0]), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
            (hi - lo).min_element() <= 2.0 * d.abs()
        };
        let shapes: Vec<Vec<Vec<Pt>>> = self
            .polys
            .iter()
            .filter(|p| d > 0.0 || !gone(&p.outer))
            .map(|p| {
                std::iter::once(&p.outer)
                    .chain(p.holes.iter().filter(|h| d < 0.0 || !gone(h)))
                    .map(|r| match super::simplify::douglas_peucker_ring(r, e) {
                        s if s.len() >= 3 => to_pts(&s),
                        _ => to_pts(r),
                    })
                    .collect()
            })
            .collect();
        if shapes.is_empty() {
            return Area::empty();
        }
        from_shapes(shapes.outline(&style))
    }

    /// The region swept by a disk of radius `r` moving along each polyline (round caps and
    /// joins; chords inside the true circle, so the result slightly under-estimates the sweep by
    /// at most `tol`). `closed` treats each polyline as a loop.
    pub fn stroke(paths: &[Vec<DVec2>], r: f64, closed: bool, tol: f64) -> Area {
        let paths: Vec<Vec<Pt>> = paths.iter().filter(|p| !p.is_empty()).map(|p| to_pts(p)).collect();
        if paths.is_empty() || r <= 0.0 {
            return Area::empty();
        }
        let step = join_step(r, tol);
        let style = StrokeStyle::new(2.0 * r)
            .line_join(LineJoin::Round(step))
            .start_cap(LineCap::Round(step))
            .end_cap(LineCap::Round(step));
        // single points: a stroke of nothing; make them disks instead
        let (pts, lines): (Vec<_>, Vec<_>) = paths.into_iter().partition(|p| p.len() == 1);
        let mut out = if lines.is_empty() { Area::empty() } else { from_shapes(lines.stroke(style, closed)) };
        for p in pts {
            out = out.union(&Area::disk(DVec2::new(p[0][0], p[0][1]), r, tol));
        }
        out
    }

    /// Every ring simplified by Douglas–Peucker within `tol`, then re-normalised (rings keep
    /// their orientation, so holes stay holes).
    pub fn simplified(&self, tol: f64) -> Area {
        let rings: Vec<Vec<DVec2>> =
            self.rings().map(|r| super::simplify::douglas_peucker_ring(r, tol)).filter(|r| r.len() >= 3).collect();
        Area::from_rings(&rings, Fill::NonZero)
    }

    /// The pieces of a polyline inside the area (boundary excluded).
    pub fn clip_polyline(&self, path: &[DVec2]) -> Vec<Vec<DVec2>> {
        if self.is_empty() || path.len() < 2 {
            return Vec::new();
        }
        let line = to_pts(path);
        let rule = ClipRule { invert: false, boundary_included: false };
        let parts = line.clip_by(&self.shapes(), FillRule::NonZero, rule);
        parts.into_iter().map(|p| p.into_iter().map(|q| DVec2::new(q[0], q[1])).collect()).collect()
    }

    /// True when the segment from `a` to `b` lies inside the area but for at most `slack` of
    /// its length (the boundary excluded, as [`Area::clip_polyline`] excludes it).
    pub fn holds_segment(&self, a: DVec2, b: DVec2, slack: f64) -> bool {
        let inside: f64 = self.clip_polyline(&[a, b]).iter().map(|p| super::polyline_length(p)).sum();
        inside >= (b - a).length() - slack
    }

    /// True when there are no polygons.
    pub fn is_empty(&self) -> bool {
        self.polys.is_empty()
    }

    /// Total area.
    pub fn area(&self) -> f64 {
        self.polys.iter().map(Polygon::area).sum()
    }

    /// Drops polygons and holes whose area is below `eps`.
    pub fn without_slivers(mut self, eps: f64) -> Area {
        self.polys.retain(|p| super::ring_area(&p.outer).abs() >= eps);
        for p in &mut self.polys {
            p.holes.retain(|h| super::ring_area(h).abs() >= eps);
        }
        self
    }

    /// Bounds `[min, max]`, or `None` when empty.
    pub fn bounds(&self) -> Option<(DVec2, DVec2)> {
        let mut it = self.polys.iter().flat_map(|p| p.outer.iter());
        let f = *it.next()?;
        let (mut lo, mut hi) = (f, f);
        for p in it {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        Some((lo, hi))
    }

    /// Every ring (outer and holes) of every polygon.
    pub fn rings(&self) -> impl Iterator<Item = &Vec<DVec2>> {
        self.polys.iter().flat_map(|p| p.rings())
    }

    /// Even-odd point containment (points on the boundary may go either way).
    pub fn contains(&self, p: DVec2) -> bool {
        let mut inside = false;
        for ring in self.rings() {
            let n = ring.len();
            let mut j = n - 1;
            for i in 0..n {
                let a = ring[i];
                let b = ring[j];
                if (a.y > p.y) != (b.y > p.y) {
                    let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
                    if p.x < x {
                        inside = !inside;
                    }
                }
                j = i;
            }
        }
        inside
    }

    /// Each polygon as its own area.
    pub fn components(&self) -> Vec<Area> {
        self.polys.iter().map(|p| Area { polys: vec![p.clone()] }).collect()
    }

    /// Number of vertices over all rings.
    pub fn vertex_count(&self) -> usize {
        self.rings().map(Vec::len).sum()
    }
}

/// Angular step of round joins for radius `r` so that the offset moves straight edges by at
/// most `tol` beyond `r`: `r / cos(step/2) - r <= tol`.
fn join_step(r: f64, tol: f64) -> f64 {
    let c = r / (r + tol.max(1e-9));
    let step = 2.0 * c.clamp(-1.0, 1.0).acos();
    step.clamp(MIN_JOIN_STEP, 0.25 * std::f64::consts::PI)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::index::EdgeIndex;

    fn sq(x0: f64, y0: f64, s: f64) -> Vec<DVec2> {
        vec![DVec2::new(x0, y0), DVec2::new(x0 + s, y0), DVec2::new(x0 + s, y0 + s), DVec2::new(x0, y0 + s)]
    }

    #[test]
    fn even_odd_nesting_and_booleans() {
        let a = Area::from_rings(&[sq(0.0, 0.0, 10.0), sq(2.0, 2.0, 6.0), sq(4.0, 4.0, 2.0)], Fill::EvenOdd);
        assert!((a.area() - (100.0 - 36.0 + 4.0)).abs() < 1e-6);
        assert!(a.contains(DVec2::new(1.0, 1.0)));
        assert!(!a.contains(DVec2::new(3.0, 3.0)));
        assert!(a.contains(DVec2::new(5.0, 5.0)));
        let b = Area::rect(5.0, -5.0, 15.0, 5.0);
        assert!((a.union(&b).area() - (a.area() + 100.0 - a.intersection(&b).area())).abs() < 1e-6);
        assert!((a.difference(&b).area() + a.intersection(&b).area() - a.area()).abs() < 1e-6);
    }

    #[test]
    fn coincident_edges_are_robust() {
        // a frame whose hole is exactly the stock: stock minus frame is the stock
        let stock = Area::rect(0.0, 0.0, 60.0, 20.0);
        let frame = Area::from_rings(
            &[
                sq(-8.0, -8.0, 76.0),
                vec![DVec2::new(0.0, 0.0), DVec2::new(60.0, 0.0), DVec2::new(60.0, 20.0), DVec2::new(0.0, 20.0)],
            ],
            Fill::EvenOdd,
        );
        let m = stock.difference(&frame);
        assert!((m.area() - 1200.0).abs() < 1e-6, "{}", m.area());
        assert_eq!(m.polys.len(), 1);
    }

    #[test]
    fn offset_never_comes_closer_than_asked() {
        // shrink an L shape by 3: every vertex of the result is at least 3 from the boundary,
        // and at most 3 + 1.25·tol from it along straight edges
        let l = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(60.0, 0.0),
            DVec2::new(60.0, 20.0),
            DVec2::new(20.0, 20.0),
            DVec2::new(20.0, 60.0),
            DVec2::new(0.0, 60.0),
        ];
        let a = Area::from_rings(std::slice::from_ref(&l), Fill::NonZero);
        let tol = 0.001;
        let e = a.offset(-3.0, tol);
        let idx = EdgeIndex::from_rings([&l].into_iter(), 2.0);
        let mut dmax: f64 = 0.0;
        for r in e.rings() {
            for w in 0..r.len() {
                let p = r[w];
                let q = r[(w + 1) % r.len()];
                let d = idx.distance(p, 10.0);
                assert!(d >= 3.0 - 1e-6, "vertex {p} at {d}");
                let dm = idx.distance((p + q) / 2.0, 10.0);
                assert!(dm >= 3.0 - 1e-6, "chord midpoint at {dm}");
                dmax = dmax.max(d);
            }
        }
        assert!(dmax <= 3.0 + 1.25 * tol + 1e-6, "{dmax}");
        // grow a square by 2: the round corners contain the true rounded square
        let g = Area::from_rings(&[sq(0.0, 0.0, 10.0)], Fill::NonZero).offset(2.0, tol);
        let exact = 100.0 + 4.0 * 10.0 * 2.0 + std::f64::consts::PI * 4.0;
        assert!(g.area() >= exact - 1e-6 && g.area() <= exact + 0.1, "{} vs {exact}", g.area());
    }

    /// A dense boundary (a wave of 4000 edges along the top of a plate, as a drawing's spline
    /// gives) is simplified before it is offset: grown and shrunk, by a radius and by a
    /// distance under the tolerance (where the joins' push outward no longer covers the
    /// simplification), no vertex and no chord of the result comes closer than asked to the
    /// original edges, none is farther than the tolerance beyond it, and the area is the
    /// plate's grown or shrunk.
    #[test]
    fn offset_of_a_dense_boundary_never_comes_closer_than_asked() {
        let n = 4000;
        let mut ring: Vec<DVec2> = (0..=n)
            .map(|k| {
                let x = 100.0 * k as f64 / n as f64;
                DVec2::new(x, 20.0 + 2.0 * (x / 5.0).sin())
            })
            .rev()
            .collect();
        ring.splice(0..0, [DVec2::new(0.0, 0.0), DVec2::new(100.0, 0.0)]);
        let a = Area::from_rings(std::slice::from_ref(&ring), Fill::NonZero);
        let idx = EdgeIndex::from_rings([&ring].into_iter(), 2.0);
        let tol = 0.001;
        let mut closed = ring.clone();
        closed.push(ring[0]);
        let perimeter = crate::geom::polyline_length(&closed);
        for d in [1.5, -1.5, 0.002, -0.002] {
            let e = a.offset(d, tol);
            let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
            for r in e.rings() {
                for w in 0..r.len() {
                    let (p, q) = (r[w], r[(w + 1) % r.len()]);
                    for x in [p, (p + q) / 2.0] {
                        let dist = idx.distance(x, 10.0);
                        (lo, hi) = (lo.min(dist), hi.max(dist));
                    }
                }
            }
            assert!(lo >= d.abs() - 1e-9, "offset {d}: a point of the result {lo} from the boundary");
            assert!(hi <= d.abs() + 2.0 * tol, "offset {d}: a point of the result {hi} from the boundary");
            // Steiner's formula: the area grows by the perimeter times d, and by π·d² round the
            // boundary's turn (a shrink keeps the four corners sharp: about 4·d² instead)
            let want = a.area() + d * perimeter + d * d * if d > 0.0 { std::f64::consts::PI } else { 4.0 };
            assert!((e.area() - want).abs() < 0.5, "offset {d}: {} against {want}", e.area());
        }
    }

    #[test]
    fn stroke_and_clip() {
        let path = vec![DVec2::new(0.0, 0.0), DVec2::new(10.0, 0.0)];
        let s = Area::stroke(&[path], 1.0, false, 0.001);
        let exact = 20.0 + std::f64::consts::PI;
        assert!((s.area() - exact).abs() < 0.01, "{}", s.area());
        let a = Area::rect(2.0, -5.0, 4.0, 5.0).union(&Area::rect(6.0, -5.0, 8.0, 5.0));
        let parts = a.clip_polyline(&[DVec2::new(0.0, 0.0), DVec2::new(10.0, 0.0)]);
        assert_eq!(parts.len(), 2);
        let len: f64 = parts.iter().map(|p| crate::geom::polyline_length(p)).sum();
        assert!((len - 4.0).abs() < 1e-6);
    }

    /// A segment inside an L, one that cuts across its notch, and one along its edge.
    #[test]
    fn holds_a_segment_inside_not_one_that_leaves() {
        let l = Area::rect(0.0, 0.0, 10.0, 4.0).union(&Area::rect(0.0, 0.0, 4.0, 10.0));
        let p = DVec2::new;
        assert!(l.holds_segment(p(1.0, 1.0), p(9.0, 3.0), 1e-9));
        assert!(!l.holds_segment(p(2.0, 9.0), p(9.0, 2.0), 1e-9), "across the notch");
        assert!(l.holds_segment(p(2.0, 9.0), p(9.0, 2.0), 5.0), "within a slack longer than the part outside");
        assert!(!l.holds_segment(p(0.0, 1.0), p(0.0, 9.0), 1e-9), "along the edge (boundary excluded)");
    }
}
