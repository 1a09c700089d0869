//! SVG reader: geometry, units, transforms, arcs, flattening, roles. Every SVG is written here.

use std::f64::consts::PI;
use std::path::Path;
use swarf_import::svg::read_svg;
use swarf_import::{Contour, Drawing, ImportOptions, Role, Segment, Units};

fn read_opts(svg: &str, opts: &ImportOptions) -> Drawing {
    match read_svg(Path::new("test.svg"), svg.as_bytes(), opts) {
        Ok(d) => d,
        Err(e) => panic!("{e}"),
    }
}

fn read(svg: &str) -> Drawing {
    read_opts(svg, &ImportOptions::default())
}

/// A document where one user unit is one millimetre, `w` × `h` mm.
fn mm_doc(w: f64, h: f64, body: &str) -> String {
    format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" width="{w}mm" height="{h}mm" viewBox="0 0 {w} {h}">{body}</svg>"#
    )
}

fn bounds(c: &Contour) -> [f64; 4] {
    c.bounds().expect("non-empty contour")
}

fn assert_close(a: f64, b: f64, tol: f64, what: &str) {
    assert!((a - b).abs() <= tol, "{what}: {a} vs {b} (tolerance {tol})");
}

fn assert_bounds(c: &Contour, want: [f64; 4], tol: f64) {
    let b = bounds(c);
    for i in 0..4 {
        assert_close(b[i], want[i], tol, &format!("bounds[{i}] of {b:?}"));
    }
}

fn bulges(c: &Contour) -> Vec<f64> {
    c.vertices.iter().map(|v| v.bulge).collect()
}

/// Distance from `p` to the segment `a`–`b`.
fn seg_dist(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 == 0.0 { 0.0 } else { (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0) };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

#[test]
fn rect_100_by_65_mm() {
    let d = read(&mm_doc(100.0, 65.0, r#"<rect x="0" y="0" width="100" height="65"/>"#));
    assert_eq!(d.shapes.len(), 1);
    assert_eq!(d.units, Units::Millimetre);
    let c = &d.shapes[0].contour;
    assert!(c.closed);
    assert_eq!(c.vertices.len(), 4);
    assert_close(c.signed_area().abs(), 6500.0, 1e-6, "area");
    assert_bounds(c, [0.0, 0.0, 100.0, 65.0], 1e-9);
    // clockwise on screen stays clockwise with Y up (the page is flipped, the picture is not)
    assert!(c.signed_area() < 0.0);
}

#[test]
fn circle_is_two_exact_half_arcs() {
    let d = read(&mm_doc(100.0, 100.0, r#"<circle cx="30" cy="40" r="12.5"/>"#));
    let c = &d.shapes[0].contour;
    assert_eq!(c.vertices.len(), 2, "{c:?}");
    for b in bulges(c) {
        assert_close(b.abs(), 1.0, 1e-12, "half-circle bulge");
    }
    assert_close(c.signed_area().abs(), PI * 12.5 * 12.5, 1e-9, "area");
    // centre (30, 40) on screen = (30, 60) with Y up
    for v in &c.vertices {
        assert_close((v.x - 30.0).hypot(v.y - 60.0), 12.5, 1e-12, "radius");
    }
    assert_bounds(c, [17.5, 47.5, 42.5, 72.5], 1e-3);
}

#[test]
fn path_arcs_half_quarter_and_large_stay_exact() {
    // two half circles
    let d = read(&mm_doc(100.0, 100.0, r#"<path d="M 60 50 A 10 10 0 0 1 40 50 A 10 10 0 0 1 60 50 Z"/>"#));
    let c = &d.shapes[0].contour;
    assert_eq!(c.vertices.len(), 2);
    assert_eq!(bulges(c), vec![-1.0, -1.0], "sweep-flag 1 is clockwise on screen, and so in the result");
    assert_close(c.signed_area(), -PI * 100.0, 1e-9, "area");

    // a quarter-circle sector, relative arc command
    let d = read(&mm_doc(100.0, 100.0, r#"<path d="M 50 50 h 10 a 10 10 0 0 1 -10 10 z"/>"#));
    let c = &d.shapes[0].contour;
    assert_eq!(c.vertices.len(), 3);
    let b = bulges(c);
    assert_eq!(b.iter().filter(|b| **b != 0.0).count(), 1);
    let q = b.iter().copied().find(|b| *b != 0.0).unwrap();
    assert_close(q.abs(), (PI / 8.0).tan(), 1e-12, "quarter bulge");
    assert_close(c.signed_area().abs(), PI * 100.0 / 4.0, 1e-9, "quarter sector area");

    // a 270° arc is split into two arcs of 135°
    let d = read(&mm_doc(100.0, 100.0, r#"<path d="M 50 50 L 60 50 A 10 10 0 1 0 50 60 Z"/>"#));
    let c = &d.shapes[0].contour;
    let arcs: Vec<f64> = bulges(c).into_iter().filter(|b| *b != 0.0).collect();
    assert_eq!(arcs.len(), 2, "{c:?}");
    for b in arcs {
        assert_close(b.abs(), (3.0 * PI / 16.0).tan(), 1e-12, "135° bulge");
    }
    assert_close(c.signed_area().abs(), PI * 100.0 * 0.75, 1e-9, "three-quarter sector area");
    for s in c.segments() {
        if let Segment::Arc { center, radius, .. } = s {
            assert_close(radius, 10.0, 1e-9, "radius");
            assert_close(center[0], 50.0, 1e-9, "centre x");
            assert_close(center[1], 50.0, 1e-9, "centre y");
        }
    }
}

#[test]
fn arc_radii_too_small_are_scaled_up() {
    // radius 1 cannot span 20: SVG scales it to 10, a half circle
    let d = read(&mm_doc(100.0, 100.0, r#"<path d="M 40 50 A 1 1 0 0 0 60 50 Z"/>"#));
    let c = &d.shapes[0].contour;
    assert_eq!(c.vertices.len(), 2);
    assert_close(c.signed_area().abs(), PI * 100.0 / 2.0, 1e-9, "half disc");
    // sweep-flag 0 (counter-clockwise on screen) from left to right passes below the chord on
    // screen (larger y), which is below it with Y up too: the page is flipped, not the drawing
    let b = bounds(c);
    assert_close(b[1], 40.0, 1e-3, "lowest point");
    assert_close(b[3], 50.0, 1e-9, "chord");
}

#[test]
fn rotated_scaled_groups_keep_circles_exact() {
    let body = r#"<g transform="rotate(30) scale(2)"><g transform="translate(10 5) rotate(-17 3 4)">
        <circle cx="7" cy="3" r="5"/>
        <path d="M 0 0 m 20 0 a 5 5 0 1 1 0 10 a 5 5 0 1 1 0 -10 z"/></g></g>"#;
    let d = read(&mm_doc(200.0, 200.0, body));
    assert_eq!(d.shapes.len(), 2);
    for s in &d.shapes {
        let c = &s.contour;
        assert_eq!(c.vertices.len(), 2, "{}", s.origin);
        for b in bulges(c) {
            assert_close(b.abs(), 1.0, 1e-9, "half circle");
        }
        assert_close(c.signed_area().abs(), PI * 100.0, 1e-9, "radius 5 scaled by 2");
    }
    // mirrored similarity (scale(-3 3)) is still a circle
    let d = read(&mm_doc(200.0, 200.0, r#"<circle transform="translate(100 100) scale(-3 3) rotate(10)" r="4"/>"#));
    let c = &d.shapes[0].contour;
    assert_eq!(c.vertices.len(), 2);
    assert_close(c.signed_area().abs(), PI * 144.0, 1e-9, "area");
}

#[test]
fn skewed_circle_is_flattened_within_tolerance() {
    let tol = 0.002;
    let t = 30f64.to_radians().tan();
    let d = read(&mm_doc(100.0, 100.0, r#"<circle transform="translate(50 50) skewX(30)" r="10"/>"#));
    let c = &d.shapes[0].contour;
    assert!(c.vertices.iter().all(|v| v.bulge == 0.0), "an ellipse cannot be kept as bulge arcs");
    assert!(c.vertices.len() > 50);
    // output (X, Y) = (x + t·y + 50, 50 − y) for (x, y) on the circle of radius 10
    let param = |p: [f64; 2]| {
        let y = 50.0 - p[1];
        let x = p[0] - 50.0 - t * y;
        (y.atan2(x), x.hypot(y))
    };
    let curve = |th: f64| {
        let (x, y) = (10.0 * th.cos(), 10.0 * th.sin());
        [x + t * y + 50.0, 50.0 - y]
    };
    let pts: Vec<[f64; 2]> = c.vertices.iter().map(|v| [v.x, v.y]).collect();
    let mut worst: f64 = 0.0;
    for i in 0..pts.len() {
        let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
        let (ta, ra) = param(a);
        let (tb, _) = param(b);
        assert_close(ra, 10.0, 1e-9, "vertex on the ellipse");
        let mut dt = tb - ta;
        if dt > PI {
            dt -= 2.0 * PI;
        } else if dt < -PI {
            dt += 2.0 * PI;
        }
        for k in 0..=200 {
            let p = curve(ta + dt * k as f64 / 200.0);
            worst = worst.max(seg_dist(p, a, b));
        }
    }
    assert!(worst <= tol * (1.0 + 1e-9), "max deviation {worst} > {tol}");
    assert!(worst > tol / 10.0, "needlessly fine: {worst}");
    // area of the sheared disc is unchanged by a shear
    assert_close(c.signed_area().abs(), PI * 100.0, 2.0 * tol * 2.0 * PI * 12.0, "area");
}

#[test]
fn cubic_bezier_flattened_within_tolerance_adaptively() {
    let svg = mm_doc(200.0, 200.0, r#"<path d="M 10 100 C 40 20 80 180 110 60 L 110 190 L 10 190 Z"/>"#);
    let bez = |t: f64| {
        let p = [[10.0, 100.0], [40.0, 20.0], [80.0, 180.0], [110.0, 60.0]];
        let u = 1.0 - t;
        let w = [u * u * u, 3.0 * u * u * t, 3.0 * u * t * t, t * t * t];
        let x: f64 = (0..4).map(|i| w[i] * p[i][0]).sum();
        let y: f64 = (0..4).map(|i| w[i] * p[i][1]).sum();
        [x, 200.0 - y]
    };
    let dense: Vec<[f64; 2]> = (0..=100_000).map(|i| bez(i as f64 / 100_000.0)).collect();
    let mut counts = Vec::new();
    for tol in [0.1, 0.01, 0.001] {
        let d = read_opts(&svg, &ImportOptions { flatten_tolerance: tol, ..Default::default() });
        let pts: Vec<[f64; 2]> = d.shapes[0].contour.vertices.iter().map(|v| [v.x, v.y]).collect();
        // the flattened curve: every vertex but the last two (the closing corners)
        assert!(pts.len() > 4);
        let poly = &pts[..pts.len() - 2];
        assert_eq!(poly[0], [10.0, 100.0]);
        assert_eq!(poly[poly.len() - 1], [110.0, 140.0]);
        // every point of the curve is within tol of the polyline
        let mut worst: f64 = 0.0;
        for p in &dense {
            let m = poly.windows(2).map(|w| seg_dist(*p, w[0], w[1])).fold(f64::INFINITY, f64::min);
            worst = worst.max(m);
        }
        assert!(worst <= tol * (1.0 + 1e-9), "tol {tol}: curve strays {worst} from its chords");
        // and every chord point is within tol of the curve (checked at chord midpoints, to the
        // dense samples, which are at most ~0.003 mm apart)
        let mut back: f64 = 0.0;
        for w in poly.windows(2) {
            let m = [(w[0][0] + w[1][0]) / 2.0, (w[0][1] + w[1][1]) / 2.0];
            let nearest = dense.iter().map(|q| (q[0] - m[0]).hypot(q[1] - m[1])).fold(f64::INFINITY, f64::min);
            back = back.max(nearest);
        }
        assert!(back <= tol + 0.002, "tol {tol}: chord strays {back} from the curve");
        counts.push(poly.len());
    }
    assert!(counts[0] < counts[1] && counts[1] < counts[2], "not adaptive: {counts:?}");
    assert!(counts[2] < 20 * counts[0], "too many points: {counts:?}");
}

#[test]
fn smooth_and_quadratic_commands() {
    // The lowest point (Y up) of the vertices strictly between x0 and x1.
    let low = |c: &Contour, x0: f64, x1: f64| {
        c.vertices.iter().filter(|v| v.x > x0 && v.x < x1).map(|v| v.y).fold(f64::INFINITY, f64::min)
    };
    let high = |c: &Contour, x0: f64, x1: f64| {
        c.vertices.iter().filter(|v| v.x > x0 && v.x < x1).map(|v| v.y).fold(f64::NEG_INFINITY, f64::max)
    };
    // T reflects the previous control point: the second hump goes the other way
    for d in ["M 0 50 Q 50 0 100 50 T 200 50 L 200 5 L 0 5 Z", "m0 50 q50-50 100 0 t100 0 l 0 -45 h -200 z"] {
        let c = &read(&mm_doc(300.0, 100.0, &format!(r#"<path d="{d}"/>"#))).shapes[0].contour;
        assert_bounds(c, [0.0, 50.0 - 25.0, 200.0, 95.0], 0.002);
        assert_close(high(c, 0.0, 100.0), 75.0, 0.002, "first hump");
        assert_close(low(c, 100.0, 200.0), 25.0, 0.002, "second hump, T-reflected");
    }
    // S likewise for cubics
    let c = &read(&mm_doc(300.0, 100.0, r#"<path d="M0 50 C 0 0 50 0 50 50 S 100 100 100 50 L 100 5 L 0 5 Z"/>"#))
        .shapes[0]
        .contour;
    assert_bounds(c, [0.0, 12.5, 100.0, 95.0], 0.002);
    assert_close(high(c, 0.0, 50.0), 87.5, 0.002, "first hump");
    assert_close(low(c, 50.0, 100.0), 12.5, 0.002, "second hump, S-reflected");
    // implicit repeats, subpaths
    let d = read(&mm_doc(300.0, 100.0, r#"<path d="M10 10 20 10 20 20 10 20z m 50 0 h 10 v 10 h -10 z"/>"#));
    assert_eq!(d.shapes.len(), 2);
    for s in &d.shapes {
        assert_close(s.contour.signed_area().abs(), 100.0, 1e-9, "square");
        assert!(s.origin.contains("subpath"), "{}", s.origin);
    }
}

#[test]
fn px_documents_at_96_and_90_px_per_inch() {
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="354.33071" height="230.31496">
        <rect width="354.33071" height="230.31496"/></svg>"#;
    let d96 = read(svg);
    let d90 = read_opts(svg, &ImportOptions { svg_px_per_inch: Some(90.0), ..Default::default() });
    assert_bounds(&d96.shapes[0].contour, [0.0, 0.0, 93.75, 60.9375], 1e-4);
    assert_bounds(&d90.shapes[0].contour, [0.0, 0.0, 100.0, 65.0], 1e-4);
    // a unit override: one user unit is one millimetre
    let dmm = read_opts(svg, &ImportOptions { units: Some(Units::Millimetre), ..Default::default() });
    assert_eq!(dmm.units, Units::Millimetre);
    assert_bounds(&dmm.shapes[0].contour, [0.0, 0.0, 354.33071, 230.31496], 1e-9);
    let din = read_opts(svg, &ImportOptions { units: Some(Units::Inch), ..Default::default() });
    assert_eq!(din.units, Units::Inch);
    assert_bounds(&din.shapes[0].contour, [0.0, 0.0, 354.33071 * 25.4, 230.31496 * 25.4], 1e-6);
    // width in inches, no viewBox: user units are still px
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="2in" height="1in"><rect x="0" y="0" width="96" height="48"/></svg>"#;
    let d = read(svg);
    assert_eq!(d.units, Units::Inch);
    assert_bounds(&d.shapes[0].contour, [0.0, 25.4 - 12.7, 25.4, 25.4], 1e-9);
}

#[test]
fn viewbox_scaling_and_aspect_ratio() {
    // 20 × 10 user units onto 200 × 100 mm: 10 mm per unit
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="100mm" viewBox="0 0 20 10">
        <rect x="1" y="1" width="2" height="3"/></svg>"#;
    assert_bounds(&read(svg).shapes[0].contour, [10.0, 60.0, 30.0, 90.0], 1e-9);
    // viewBox with an offset
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="100mm" viewBox="-5 -5 20 10">
        <rect x="-5" y="-5" width="2" height="3"/></svg>"#;
    assert_bounds(&read(svg).shapes[0].contour, [0.0, 70.0, 20.0, 100.0], 1e-9);
    // meet (default xMidYMid): scale min(10, 20) = 10, centred vertically: 50 mm margin
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="200mm" viewBox="0 0 20 10">
        <rect x="0" y="0" width="20" height="10"/></svg>"#;
    assert_bounds(&read(svg).shapes[0].contour, [0.0, 50.0, 200.0, 150.0], 1e-9);
    // none: 10 × 20 mm per unit; the circle becomes an ellipse and is flattened
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="200mm" height="200mm" viewBox="0 0 20 10"
        preserveAspectRatio="none"><circle cx="10" cy="5" r="2"/></svg>"#;
    let c = &read(svg).shapes[0].contour;
    assert!(c.vertices.len() > 20 && c.vertices.iter().all(|v| v.bulge == 0.0));
    assert_bounds(c, [80.0, 60.0, 120.0, 140.0], 0.003);
    // only a width: the height follows the viewBox
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="4in" viewBox="0 0 40 20"><rect width="40" height="20"/></svg>"#;
    assert_bounds(&read(svg).shapes[0].contour, [0.0, 0.0, 101.6, 50.8], 1e-9);
    // neither: user unit = px
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 96 96"><rect width="96" height="48"/></svg>"#;
    assert_bounds(&read(svg).shapes[0].contour, [0.0, 12.7, 25.4, 25.4], 1e-9);
    // a nested svg with its own viewBox: 10 units onto 50 mm at (10, 10)
    let svg = mm_doc(
        100.0,
        100.0,
        r#"<svg x="10" y="10" width="50" height="50" viewBox="0 0 10 10"><rect width="10" height="10"/></svg>"#,
    );
    assert_bounds(&read(&svg).shapes[0].contour, [10.0, 40.0, 60.0, 90.0], 1e-9);
    // lengths with units inside a px document
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="100mm" height="100mm"><rect width="10mm" height="1in"/></svg>"#;
    assert_bounds(&read(svg).shapes[0].contour, [0.0, 74.6, 10.0, 100.0], 1e-9);
}

#[test]
fn negative_determinant_transforms_reverse_orientation() {
    let plain = read(&mm_doc(100.0, 100.0, r#"<path d="M 10 10 H 30 V 20 H 10 Z"/>"#));
    let flipped =
        read(&mm_doc(100.0, 100.0, r#"<path transform="matrix(1 0 0 -1 0 50)" d="M 10 10 H 30 V 20 H 10 Z"/>"#));
    let (a, b) = (plain.shapes[0].contour.signed_area(), flipped.shapes[0].contour.signed_area());
    assert_close(a, -200.0, 1e-9, "clockwise on screen stays clockwise with Y up");
    assert_close(b, 200.0, 1e-9, "mirrored: counter-clockwise");
    assert_bounds(&flipped.shapes[0].contour, [10.0, 60.0, 30.0, 70.0], 1e-9);
    // arcs follow: a circle's bulges flip sign under a mirror, its area stays
    let c1 = read(&mm_doc(100.0, 100.0, r#"<circle cx="50" cy="50" r="10"/>"#));
    let c2 =
        read(&mm_doc(100.0, 100.0, r#"<circle transform="translate(100 0) scale(-1 1)" cx="50" cy="50" r="10"/>"#));
    assert_eq!(bulges(&c1.shapes[0].contour), vec![-1.0, -1.0]);
    assert_eq!(bulges(&c2.shapes[0].contour), vec![1.0, 1.0]);
    // the same with an arc path inside a flipped group (PDF-style, like many exported logos)
    let body = r#"<g transform="matrix(1 0 0 -1 0 100)"><path d="M 60 50 A 10 10 0 0 0 40 50 L 50 50 Z"/></g>"#;
    let d = read(&mm_doc(100.0, 100.0, body));
    let c = &d.shapes[0].contour;
    // in group space the arc from (60,50) to (40,50) with sweep-flag 0 passes through (50,40);
    // the group puts that at y = 60 on the page, which is y = 40 with Y up
    assert_bounds(c, [40.0, 40.0, 60.0, 50.0], 1e-3);
    for s in c.segments() {
        if let Segment::Arc { center, radius, .. } = s {
            assert_close(radius, 10.0, 1e-9, "radius");
            assert_close(center[1], 50.0, 1e-9, "centre");
        }
    }
    assert_close(c.signed_area().abs(), PI * 50.0, 1e-9, "half disc");
}

#[test]
fn rounded_rect_area_and_corner_arcs() {
    let d = read(&mm_doc(100.0, 100.0, r#"<rect x="10" y="10" width="40" height="30" rx="5"/>"#));
    let c = &d.shapes[0].contour;
    assert_eq!(c.vertices.len(), 8);
    let arcs: Vec<f64> = bulges(c).into_iter().filter(|b| *b != 0.0).collect();
    assert_eq!(arcs.len(), 4);
    for b in arcs {
        assert_close(b, -(PI / 8.0).tan(), 1e-12, "quarter-circle corner, clockwise like the rect");
    }
    assert_close(c.signed_area(), -(40.0 * 30.0 - (4.0 - PI) * 25.0), 1e-9, "w·h − (4 − π)·r²");
    // rx larger than half the height is clamped: a stadium (half circles at both ends)
    let d = read(&mm_doc(100.0, 100.0, r#"<rect x="10" y="10" width="40" height="20" ry="15" rx="10"/>"#));
    let c = &d.shapes[0].contour;
    assert_close(c.signed_area().abs(), 40.0 * 20.0 - (4.0 - PI) * 100.0, 1e-9, "clamped radius");
    assert_eq!(c.vertices.len(), 6, "the zero-length sides vanish: {c:?}");
    // elliptical corners are flattened
    let d = read(&mm_doc(100.0, 100.0, r#"<rect x="10" y="10" width="40" height="30" rx="8" ry="4"/>"#));
    let c = &d.shapes[0].contour;
    assert!(c.vertices.iter().all(|v| v.bulge == 0.0));
    assert_close(c.signed_area().abs(), 1200.0 - (4.0 - PI) * 32.0, 0.02 * 4.0 * 10.0, "elliptic corners");
}

#[test]
fn group_roles_and_layers() {
    let body = r#"
      <g inkscape:label="Stock" inkscape:groupmode="layer" id="layer1"><rect width="100" height="100"/></g>
      <g id="PART"><g inkscape:label="holes" id="g7"><circle cx="50" cy="50" r="10"/></g>
        <rect x="20" y="20" width="60" height="60"/></g>
      <g inkscape:label="fixture"><rect x="0" y="0" width="5" height="5"/></g>
      <g inkscape:label="Layer 2" id="layer2"><g id="inner"><rect x="30" y="30" width="5" height="5"/></g>
        <rect x="40" y="40" width="5" height="5"/></g>
      <rect x="45" y="45" width="1" height="1"/>"#;
    let d = read(&mm_doc(100.0, 100.0, body));
    let got: Vec<(Role, &str)> = d.shapes.iter().map(|s| (s.role, s.layer.as_str())).collect();
    assert_eq!(
        got,
        vec![
            (Role::Stock, "Stock"),
            (Role::Part, "PART"),
            (Role::Part, "PART"),
            (Role::Fixture, "fixture"),
            (Role::Auto, "inner"),
            (Role::Auto, "Layer 2"),
            (Role::Auto, ""),
        ]
    );
    assert!(d.shapes[1].origin.starts_with("circle (line "), "{}", d.shapes[1].origin);
}

#[test]
fn hidden_and_non_geometry_elements_are_skipped() {
    let body = r#"
      <defs><rect id="r0" width="10" height="10"/></defs>
      <clipPath id="cp"><rect width="10" height="10"/></clipPath>
      <mask id="m"><rect width="10" height="10"/></mask>
      <pattern id="p"><rect width="10" height="10"/></pattern>
      <symbol id="s"><rect width="10" height="10"/></symbol>
      <marker id="mk"><rect width="10" height="10"/></marker>
      <text x="10" y="10">Hello</text>
      <metadata><rect width="10" height="10"/></metadata>
      <sodipodi:namedview xmlns:sodipodi="http://sodipodi.sourceforge.net/DTD/sodipodi-0.dtd"/>
      <foo:rect xmlns:foo="urn:foo" width="10" height="10"/>
      <g display="none"><rect width="10" height="10"/></g>
      <g style="fill:red; display : none"><rect width="10" height="10"/></g>
      <rect style="display:none" width="10" height="10"/>
      <g visibility="hidden"><rect width="10" height="10"/><rect id="shown" visibility="visible" x="20" width="10" height="10"/></g>
      <rect id="kept" x="50" y="50" width="10" height="10"/>
      <rect width="0" height="10"/>
      <circle r="0"/>
      <rect transform="scale(0)" width="10" height="10"/>"#;
    let d = read(&mm_doc(100.0, 100.0, body));
    let ids: Vec<&str> = d.shapes.iter().map(|s| s.origin.as_str()).collect();
    assert_eq!(d.shapes.len(), 2, "{ids:?}");
    assert!(ids[0].starts_with("rect id=\"shown\""), "{ids:?}");
    assert!(ids[1].starts_with("rect id=\"kept\""), "{ids:?}");
}

#[test]
fn use_and_symbol_instances() {
    let body = r##"
      <defs><circle id="c" r="5"/>
        <symbol id="sq" viewBox="0 0 1 1"><rect width="1" height="1"/></symbol></defs>
      <use id="u1" href="#c" x="20" y="20"/>
      <use xmlns:xlink="http://www.w3.org/1999/xlink" xlink:href="#c" transform="translate(50 0)" x="0" y="20"/>
      <use href="#sq" x="70" y="70" width="10" height="10"/>"##;
    let d = read(&mm_doc(100.0, 100.0, body));
    assert_eq!(d.shapes.len(), 3);
    assert_bounds(&d.shapes[0].contour, [15.0, 75.0, 25.0, 85.0], 1e-3);
    assert_bounds(&d.shapes[1].contour, [45.0, 75.0, 55.0, 85.0], 1e-3);
    assert_bounds(&d.shapes[2].contour, [70.0, 20.0, 80.0, 30.0], 1e-9);
    assert!(d.shapes[0].origin.contains("via use id=\"u1\""), "{}", d.shapes[0].origin);
    assert_eq!(d.shapes[0].contour.vertices.len(), 2);
}

#[test]
fn pocket_with_two_round_islands_at_90_px_per_inch() {
    // The structure of a classic old-Inkscape sample: an A4 page in mm with no viewBox (so user
    // units are px), one path with three subpaths: a 100 × 65 mm rectangle and two Ø25 circles
    // drawn as four cubic Béziers each, running the other way. At 90 px/in: 1 mm = 90/25.4 px.
    let px = 90.0 / 25.4;
    let page_h = 297.0 * px;
    let k = 0.5523 * 12.5 * px; // control-arm length of a quarter-circle cubic
    let r = 12.5 * px;
    // top → right → bottom → left (angles −90°, 0°, 90°, 180° with y down): clockwise on screen,
    // against the rectangle below
    let circle = |cx: f64, cy: f64| {
        let at = |i: i32| {
            let th = (-90.0 + 90.0 * i as f64).to_radians();
            let (s, c) = th.sin_cos();
            ([cx + r * c, cy + r * s], [-s, c]) // point and unit tangent (direction of travel)
        };
        let (p0, _) = at(0);
        let mut d = format!("M {},{}", p0[0], p0[1]);
        for i in 0..4 {
            let ((a, ta), (b, tb)) = (at(i), at(i + 1));
            let c1 = [a[0] + k * ta[0], a[1] + k * ta[1]];
            let c2 = [b[0] - k * tb[0], b[1] - k * tb[1]];
            d += &format!(" C {},{} {},{} {},{}", c1[0], c1[1], c2[0], c2[1], b[0], b[1]);
        }
        d + " Z"
    };
    let cy = page_h - 27.5 * px;
    // left side down, bottom to the right, right side up: counter-clockwise on screen
    let d = format!(
        "m 0,{} 0,{} {},0 0,{} z {} {}",
        page_h - 65.0 * px,
        65.0 * px,
        100.0 * px,
        -65.0 * px,
        circle(27.5 * px, cy),
        circle(72.5 * px, cy)
    );
    let svg = format!(
        r#"<?xml version="1.0" encoding="UTF-8" standalone="no"?>
<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape"
   width="210mm" height="297mm" id="svg2" version="1.1">
  <defs id="defs4" />
  <g inkscape:label="Layer 1" inkscape:groupmode="layer" id="layer1">
    <path style="fill:#000000;fill-rule:evenodd;stroke:none" d="{d}" id="path1" />
  </g>
</svg>"#
    );
    let d90 = read_opts(&svg, &ImportOptions { svg_px_per_inch: Some(90.0), ..Default::default() });
    assert_eq!(d90.shapes.len(), 3);
    let areas: Vec<f64> = d90.shapes.iter().map(|s| s.contour.signed_area()).collect();
    assert_close(areas[0].abs(), 6500.0, 1e-6, "outer rectangle");
    assert_bounds(&d90.shapes[0].contour, [0.0, 0.0, 100.0, 65.0], 1e-6);
    assert_bounds(&d90.shapes[1].contour, [15.0, 15.0, 40.0, 40.0], 0.01);
    assert_bounds(&d90.shapes[2].contour, [60.0, 15.0, 85.0, 40.0], 0.01);
    assert!(areas[0] * areas[1] < 0.0 && areas[0] * areas[2] < 0.0, "islands run the other way: {areas:?}");
    let pocket = areas[0].abs() - areas[1].abs() - areas[2].abs();
    // the four-cubic circle itself is 0.03 % larger than the circle (≈0.14 mm² each)
    assert_close(pocket, 100.0 * 65.0 - 2.0 * PI * 12.5 * 12.5, 0.5, "pocket area");
    assert!(d90.shapes.iter().all(|s| s.layer == "Layer 1" && s.role == Role::Auto));
    // the CSS assumption gives the well-known wrong size
    let d96 = read(&svg);
    let b = bounds(&d96.shapes[0].contour);
    assert_close(b[2] - b[0], 93.75, 1e-6, "width at 96 px/in");
}

#[test]
fn loose_lines_are_chained() {
    let body = r#"<line id="a" x1="10" y1="10" x2="50" y2="10"/><line id="b" x1="50" y1="10" x2="50" y2="40"/>
        <polyline id="c" points="10 40 50 40.004" /><line id="d" x1="10" y1="10" x2="10" y2="40"/>"#;
    let d = read(&mm_doc(100.0, 100.0, body));
    assert_eq!(d.shapes.len(), 1);
    assert_close(d.shapes[0].contour.signed_area().abs(), 1200.0, 0.1, "chained rectangle");
    for id in ["\"a\"", "\"b\"", "\"c\"", "\"d\""] {
        assert!(d.shapes[0].origin.contains(id), "{}", d.shapes[0].origin);
    }
    // a path whose ends meet within the chain tolerance closes without Z
    let d = read(&mm_doc(100.0, 100.0, r#"<path d="M 10 10 H 50 V 40 H 10 V 10.005"/>"#));
    assert!(d.shapes[0].contour.closed);
    assert_eq!(d.shapes[0].contour.vertices.len(), 4);
}

#[test]
fn groups_are_chosen_by_label_or_id_at_any_depth() {
    let body = r#"<g inkscape:label="Cut" id="layer1"><g id="g7"><rect x="0" y="0" width="10" height="10"/></g></g>
                  <g inkscape:label="Hatch"><rect x="20" y="0" width="10" height="10"/><path d="M 20 0 L 30 10"/></g>"#;
    let doc = mm_doc(40.0, 20.0, body);
    let only_cut = read_opts(&doc, &ImportOptions { layers: vec!["cut".into()], ..Default::default() });
    assert_eq!(only_cut.shapes.len(), 1);
    let by_id = read_opts(&doc, &ImportOptions { layers: vec!["g7".into()], ..Default::default() });
    assert_eq!(by_id.shapes.len(), 1);
    let no_hatch = read_opts(&doc, &ImportOptions { ignore_layers: vec!["HATCH".into()], ..Default::default() });
    assert_eq!((no_hatch.shapes.len(), no_hatch.skipped.len()), (1, 0));
    // all of it: the open stroke is refused, or left out when asked
    let e = read_svg(Path::new("test.svg"), doc.as_bytes(), &ImportOptions::default()).unwrap_err();
    assert!(e.reason.contains("--skip-open"), "{e}");
    let skip = read_opts(&doc, &ImportOptions { skip_open: true, ..Default::default() });
    assert_eq!((skip.shapes.len(), skip.skipped.len()), (2, 1));
}

#[test]
fn old_inkscape_files_are_read_at_90_pixels_per_inch() {
    let doc = |version: &str| {
        format!(
            r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" inkscape:version="{version}" width="210mm" height="297mm"><rect x="0" y="0" width="90" height="90"/></svg>"#
        )
    };
    let side = |d: &Drawing| {
        let b = bounds(&d.shapes[0].contour);
        b[2] - b[0]
    };
    let old = read(&doc("0.48.3 r9886"));
    assert!((side(&old) - 25.4).abs() < 1e-9, "{}", side(&old));
    assert!(old.units_assumed && old.units_from.contains("90 per inch"), "{}", old.units_from);
    let new = read(&doc("1.2.2 (b0a8486541, 2022-12-01)"));
    assert!((side(&new) - 90.0 * 25.4 / 96.0).abs() < 1e-9);
    // given, the pixels per inch win
    let given = read_opts(&doc("0.48.3 r9886"), &ImportOptions { svg_px_per_inch: Some(96.0), ..Default::default() });
    assert!((side(&given) - side(&new)).abs() < 1e-12);
}
