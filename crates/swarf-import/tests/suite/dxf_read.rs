//! Integration tests of the DXF reader, on small drawings written here and on the trimesh
//! drawings in `tests/data/dxf` (MIT, see the NOTICE there).

use std::f64::consts::PI;
use std::path::Path;
use swarf_import::dxf::read_dxf;
use swarf_import::{Drawing, ImportError, ImportOptions, Role, Units};

// ---- helpers to write DXF text -------------------------------------------------------------

/// One group-code pair.
fn p(code: i32, v: impl std::fmt::Display) -> String {
    format!("{code:>3}\n{v}\n")
}

/// An entity: type, handle, layer, then its own pairs.
fn ent(kind: &str, handle: &str, layer: &str, codes: &[(i32, f64)]) -> String {
    let mut s = p(0, kind);
    if !handle.is_empty() {
        s += &p(5, handle);
    }
    s += &p(8, layer);
    for (c, v) in codes {
        s += &p(*c, v);
    }
    s
}

fn line(h: &str, a: [f64; 2], b: [f64; 2]) -> String {
    ent("LINE", h, "0", &[(10, a[0]), (20, a[1]), (30, 0.0), (11, b[0]), (21, b[1]), (31, 0.0)])
}

fn line_on(layer: &str, a: [f64; 2], b: [f64; 2]) -> String {
    ent("LINE", "", layer, &[(10, a[0]), (20, a[1]), (11, b[0]), (21, b[1])])
}

fn arc(h: &str, c: [f64; 2], r: f64, a0: f64, a1: f64) -> String {
    ent("ARC", h, "0", &[(10, c[0]), (20, c[1]), (40, r), (50, a0), (51, a1)])
}

fn circle(layer: &str, c: [f64; 2], r: f64) -> String {
    ent("CIRCLE", "", layer, &[(10, c[0]), (20, c[1]), (40, r)])
}

/// A whole R2000 file with the given header variables (already as pairs), blocks and entities.
fn doc(header: &str, blocks: &str, entities: &str) -> String {
    let mut s = p(0, "SECTION") + &p(2, "HEADER") + &p(9, "$ACADVER") + &p(1, "AC1015") + header + &p(0, "ENDSEC");
    if !blocks.is_empty() {
        s += &(p(0, "SECTION") + &p(2, "BLOCKS") + blocks + &p(0, "ENDSEC"));
    }
    s + &p(0, "SECTION") + &p(2, "ENTITIES") + entities + &p(0, "ENDSEC") + &p(0, "EOF")
}

fn insunits(v: i32) -> String {
    p(9, "$INSUNITS") + &p(70, v)
}

fn read_with(text: &str, opts: &ImportOptions) -> Result<Drawing, ImportError> {
    read_dxf(Path::new("test.dxf"), text.as_bytes(), opts)
}

fn read(text: &str) -> Result<Drawing, ImportError> {
    read_with(text, &ImportOptions::default())
}

fn read_ok(text: &str) -> Drawing {
    match read(text) {
        Ok(d) => d,
        Err(e) => panic!("unexpected error: {e}"),
    }
}

fn read_err(bytes: &[u8]) -> ImportError {
    match read_dxf(Path::new("test.dxf"), bytes, &ImportOptions::default()) {
        Ok(d) => panic!("expected an error, got {} shapes", d.shapes.len()),
        Err(e) => e,
    }
}

fn bounds(d: &Drawing) -> [f64; 4] {
    let mut b = [f64::MAX, f64::MAX, f64::MIN, f64::MIN];
    for s in &d.shapes {
        let c = s.contour.bounds().expect("bounds");
        b = [b[0].min(c[0]), b[1].min(c[1]), b[2].max(c[2]), b[3].max(c[3])];
    }
    b
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

// ---- entity types --------------------------------------------------------------------------

#[test]
fn r12_polyline_with_vertices_and_bulge() {
    // R12: no handles, no subclass markers; a 20 x 10 rectangle whose right side is a half circle
    let vertex = |x: f64, y: f64, b: f64| ent("VERTEX", "", "0", &[(10, x), (20, y), (30, 0.0), (42, b)]);
    let ents = ent("POLYLINE", "", "0", &[(66, 1.0), (10, 0.0), (20, 0.0), (30, 0.0), (70, 1.0)])
        + &vertex(0.0, 0.0, 0.0)
        + &vertex(20.0, 0.0, 1.0)
        + &vertex(20.0, 10.0, 0.0)
        + &vertex(0.0, 10.0, 0.0)
        + &p(0, "SEQEND");
    let text = p(0, "SECTION")
        + &p(2, "HEADER")
        + &p(9, "$ACADVER")
        + &p(1, "AC1009")
        + &p(0, "ENDSEC")
        + &p(0, "SECTION")
        + &p(2, "ENTITIES")
        + &ents
        + &p(0, "ENDSEC")
        + &p(0, "EOF");
    let d = read_ok(&text);
    assert_eq!(d.units, Units::Millimetre);
    assert_eq!(d.shapes.len(), 1);
    let c = &d.shapes[0].contour;
    assert!(c.closed);
    assert_eq!(c.vertices.len(), 4);
    assert!(close(c.signed_area(), 200.0 + PI * 25.0 / 2.0, 1e-9), "{}", c.signed_area());
    assert!(d.shapes[0].origin.starts_with("POLYLINE at line "), "{}", d.shapes[0].origin);
}

#[test]
fn r2000_lwpolyline_with_bulges_and_crlf() {
    // closed by flag, CRLF line ends, bulge -1 (clockwise half circle) on the top side
    let ents = p(0, "LWPOLYLINE")
        + &p(5, "2F")
        + &p(100, "AcDbEntity")
        + &p(8, "PART")
        + &p(100, "AcDbPolyline")
        + &p(90, 4)
        + &p(70, 1)
        + &p(43, 0.0)
        + &p(10, 0.0)
        + &p(20, 0.0)
        + &p(10, 10.0)
        + &p(20, 0.0)
        + &p(10, 10.0)
        + &p(20, 5.0)
        + &p(42, 1.0)
        + &p(10, 0.0)
        + &p(20, 5.0);
    let text = doc(&insunits(4), "", &ents).replace('\n', "\r\n");
    let d = read_ok(&text);
    assert_eq!(d.shapes.len(), 1);
    let s = &d.shapes[0];
    assert_eq!(s.role, Role::Part);
    assert_eq!(s.layer, "PART");
    assert_eq!(s.origin, "LWPOLYLINE (handle 2F) at line 20");
    // a ccw half circle of radius 5 bulging out of the top side (going from (10,5) to (0,5))
    assert!(close(s.contour.signed_area(), 50.0 + PI * 12.5, 1e-9), "{}", s.contour.signed_area());
    let b = s.contour.bounds().unwrap();
    assert!(close(b[3], 10.0, 1e-3), "{b:?}");
}

#[test]
fn loose_lines_and_arcs_chain_into_one_exact_slot() {
    // a 30 x 10 slot with half-circle ends, entities scrambled and partly reversed
    let ents = arc("A1", [30.0, 5.0], 5.0, -90.0, 90.0)
        + &line("L1", [30.0, 10.0], [0.0, 10.0])
        + &line("L2", [30.0, 0.0], [0.0, 0.0]) // reversed
        + &arc("A2", [0.0, 5.0], 5.0, 90.0, 270.0);
    let d = read_ok(&doc("", "", &ents));
    assert_eq!(d.shapes.len(), 1);
    let c = &d.shapes[0].contour;
    let exact = 300.0 + 25.0 * PI;
    assert!(close(c.signed_area().abs(), exact, 1e-9), "{} vs {exact}", c.signed_area());
    assert!(close(c.length(), 60.0 + 10.0 * PI, 1e-9));
    assert!(c.vertices.iter().filter(|v| v.bulge != 0.0).count() == 2, "arcs stay arcs: {:?}", c.vertices);
    assert!(d.shapes[0].origin.contains("and 3 more entities chained"), "{}", d.shapes[0].origin);
}

#[test]
fn arcs_larger_than_180_degrees_and_full_arcs() {
    // a 270 degree arc closed by two radii: area 3/4 of the disc
    let ents = arc("1", [0.0, 0.0], 2.0, 0.0, 270.0)
        + &line("2", [0.0, -2.0], [0.0, 0.0])
        + &line("3", [0.0, 0.0], [2.0, 0.0])
        // an ARC from 0 to 360 degrees is a full circle
        + &arc("4", [10.0, 0.0], 1.0, 0.0, 360.0);
    let d = read_ok(&doc("", "", &ents));
    assert_eq!(d.shapes.len(), 2);
    assert!(close(d.shapes[0].contour.signed_area().abs(), 3.0 * PI, 1e-9));
    assert!(d.shapes[0].contour.vertices.iter().all(|v| v.bulge.abs() <= 1.0 + 1e-12));
    assert!(close(d.shapes[1].contour.signed_area().abs(), PI, 1e-9));
}

#[test]
fn circle_and_roles_from_layers() {
    let ents = circle("holes", [0.0, 10.0], 2.5)
        + &circle("Stock", [0.0, 0.0], 50.0)
        + &circle("fixture", [10.0, 0.0], 3.0)
        + &circle("PART", [0.0, 0.0], 20.0)
        + &circle("holes", [0.0, -10.0], 2.5);
    let d = read_ok(&doc("", "", &ents));
    assert_eq!(d.shapes.len(), 5);
    // roles from the layer names, shapes in file order
    let roles: Vec<Role> = d.shapes.iter().map(|s| s.role).collect();
    assert_eq!(roles, vec![Role::Auto, Role::Stock, Role::Fixture, Role::Part, Role::Auto]);
    assert_eq!(d.shapes[0].layer, "holes");
    assert_eq!(d.shapes[1].layer, "Stock");
    assert!(close(d.shapes[1].contour.signed_area().abs(), PI * 2500.0, 1e-6));
    assert!(close(d.shapes[0].contour.signed_area().abs(), PI * 6.25, 1e-9));
}

#[test]
fn pieces_chain_only_within_one_role() {
    // half the square on STOCK, half on layer 0: neither half closes
    let ents = line_on("STOCK", [0.0, 0.0], [10.0, 0.0])
        + &line_on("STOCK", [10.0, 0.0], [10.0, 10.0])
        + &line_on("0", [10.0, 10.0], [0.0, 10.0])
        + &line_on("0", [0.0, 10.0], [0.0, 0.0]);
    let e = read(&doc("", "", &ents)).unwrap_err();
    assert!(e.reason.contains("2 open contours"), "{e}");
    // on two layers of the same role (Auto) they chain
    let ents = line_on("a", [0.0, 0.0], [10.0, 0.0])
        + &line_on("a", [10.0, 0.0], [10.0, 10.0])
        + &line_on("b", [10.0, 10.0], [0.0, 10.0])
        + &line_on("b", [0.0, 10.0], [0.0, 0.0]);
    let d = read_ok(&doc("", "", &ents));
    assert_eq!(d.shapes.len(), 1);
    assert_eq!(d.shapes[0].layer, "a");
}

/// The point of the uniform cubic B-spline segment on `q` at `t` in [0, 1], from the basis
/// polynomials (independent of the de Boor evaluation in the reader).
fn uniform_cubic(q: [[f64; 2]; 4], t: f64) -> [f64; 2] {
    let b = [
        (1.0 - t).powi(3) / 6.0,
        (3.0 * t.powi(3) - 6.0 * t * t + 4.0) / 6.0,
        (-3.0 * t.powi(3) + 3.0 * t * t + 3.0 * t + 1.0) / 6.0,
        t.powi(3) / 6.0,
    ];
    let mut p = [0.0; 2];
    for i in 0..4 {
        p[0] += b[i] * q[i][0];
        p[1] += b[i] * q[i][1];
    }
    p
}

fn shoelace(pts: &[[f64; 2]]) -> f64 {
    let n = pts.len();
    (0..n).map(|i| pts[i][0] * pts[(i + 1) % n][1] - pts[(i + 1) % n][0] * pts[i][1]).sum::<f64>() / 2.0
}

#[test]
fn closed_periodic_cubic_spline_area() {
    // control polygon: an irregular hexagon; periodic = the first 3 control points repeated
    let poly = [[0.0, 0.0], [40.0, -5.0], [60.0, 20.0], [45.0, 50.0], [10.0, 45.0], [-10.0, 20.0]];
    let m = poly.len();
    let cps: Vec<[f64; 2]> = (0..m + 3).map(|i| poly[i % m]).collect();
    let n = cps.len();
    let mut codes: Vec<(i32, f64)> = vec![(70, 11.0), (71, 3.0), (72, (n + 4) as f64), (73, n as f64), (74, 0.0)];
    codes.extend((0..n + 4).map(|k| (40, k as f64)));
    for c in &cps {
        codes.extend([(10, c[0]), (20, c[1]), (30, 0.0)]);
    }
    let d = read_ok(&doc("", "", &ent("SPLINE", "5A", "0", &codes)));
    assert_eq!(d.shapes.len(), 1);
    let c = &d.shapes[0].contour;
    assert!(c.closed);
    // independent: sample each segment densely from the basis polynomials
    let mut dense = Vec::new();
    for i in 0..m {
        let q = [poly[i], poly[(i + 1) % m], poly[(i + 2) % m], poly[(i + 3) % m]];
        for k in 0..4000 {
            dense.push(uniform_cubic(q, k as f64 / 4000.0));
        }
    }
    let exact = shoelace(&dense);
    let tol = ImportOptions::default().flatten_tolerance;
    let perimeter = c.length();
    let area = c.signed_area();
    assert!((area - exact).abs() <= tol * perimeter, "area {area} vs {exact} (allowed {})", tol * perimeter);
    assert!(c.vertices.len() > 50, "{} vertices", c.vertices.len());
    // every vertex lies on the curve: its distance to the dense samples is tiny
    for v in c.vertices.iter().step_by(7) {
        let dmin = dense.iter().map(|q| ((q[0] - v.x).powi(2) + (q[1] - v.y).powi(2)).sqrt()).fold(f64::MAX, f64::min);
        assert!(dmin < 0.05, "vertex ({}, {}) is {dmin} from the curve", v.x, v.y);
    }
    // a coarser tolerance gives fewer points
    let coarse = read_with(
        &doc("", "", &ent("SPLINE", "5A", "0", &codes)),
        &ImportOptions { flatten_tolerance: 0.1, ..Default::default() },
    )
    .unwrap();
    assert!(coarse.shapes[0].contour.vertices.len() * 3 < c.vertices.len());
}

#[test]
fn clamped_bezier_splines_chain_with_lines() {
    // a cubic Bezier arch from (0,0) to (30,0) closed by a line
    let bez = ent(
        "SPLINE",
        "B1",
        "0",
        &[
            (70, 8.0),
            (71, 3.0),
            (72, 8.0),
            (73, 4.0),
            (40, 0.0),
            (40, 0.0),
            (40, 0.0),
            (40, 0.0),
            (40, 1.0),
            (40, 1.0),
            (40, 1.0),
            (40, 1.0),
            (10, 0.0),
            (20, 0.0),
            (10, 0.0),
            (20, 20.0),
            (10, 30.0),
            (20, 20.0),
            (10, 30.0),
            (20, 0.0),
        ],
    );
    let d = read_ok(&doc("", "", &(bez + &line("L", [30.0, 0.0], [0.0, 0.0]))));
    assert_eq!(d.shapes.len(), 1);
    // area under the Bezier: x = 90t² - 60t³, y = 60t(1 - t), so the integral of y dx is
    // 10800 * integral of t²(1 - t)² dt = 10800 / 30 = 360
    let a = d.shapes[0].contour.signed_area().abs();
    assert!(close(a, 360.0, 0.002 * 100.0), "{a}");
}

#[test]
fn fit_point_spline_is_interpolated() {
    // 8 fit points on a circle of radius 10, closed: the interpolant is nearly that circle
    let mut codes: Vec<(i32, f64)> = vec![(70, 1.0), (71, 3.0), (72, 0.0), (73, 0.0), (74, 8.0)];
    let fit: Vec<[f64; 2]> = (0..8).map(|k| k as f64 * PI / 4.0).map(|t| [10.0 * t.cos(), 10.0 * t.sin()]).collect();
    for f in &fit {
        codes.extend([(11, f[0]), (21, f[1]), (31, 0.0)]);
    }
    let d = read_ok(&doc("", "", &ent("SPLINE", "", "0", &codes)));
    assert_eq!(d.shapes.len(), 1);
    let c = &d.shapes[0].contour;
    for f in &fit {
        assert!(c.vertices.iter().any(|v| close(v.x, f[0], 1e-9) && close(v.y, f[1], 1e-9)), "fit point {f:?} missing");
    }
    let a = c.signed_area().abs();
    assert!((a - PI * 100.0).abs() < 0.01 * PI * 100.0, "{a}");
    for v in &c.vertices {
        let r = (v.x * v.x + v.y * v.y).sqrt();
        assert!((r - 10.0).abs() < 0.1, "{r}");
    }
}

#[test]
fn bad_splines_are_refused_clearly() {
    let codes = [
        (71, 3.0),
        (72, 5.0),
        (40, 0.0),
        (40, 0.0),
        (40, 1.0),
        (40, 1.0),
        (40, 1.0),
        (10, 0.0),
        (20, 0.0),
        (10, 1.0),
        (20, 1.0),
        (10, 2.0),
        (20, 0.0),
        (10, 3.0),
        (20, 1.0),
    ];
    let e = read(&doc("", "", &ent("SPLINE", "77", "0", &codes))).unwrap_err();
    assert!(e.place.starts_with("SPLINE (handle 77) at line "), "{e}");
    assert!(e.reason.contains("5 knots") && e.reason.contains("need 8"), "{e}");
    let e = read(&doc("", "", &ent("SPLINE", "78", "0", &[(71, 3.0)]))).unwrap_err();
    assert!(e.reason.contains("without control points or fit points"), "{e}");
}

#[test]
fn ellipses_full_partial_and_circular() {
    // full ellipse: a = 10 (major axis (8, 6)), b = 5
    let full =
        ent("ELLIPSE", "E1", "0", &[(10, 10.0), (20, 5.0), (11, 8.0), (21, 6.0), (40, 0.5), (41, 0.0), (42, 2.0 * PI)]);
    let d = read_ok(&doc("", "", &full));
    assert_eq!(d.shapes.len(), 1);
    let c = &d.shapes[0].contour;
    let exact = PI * 10.0 * 5.0;
    let a = c.signed_area();
    assert!(a > 0.0 && a < exact && exact - a < 0.002 * c.length(), "{a} vs {exact}");
    // every vertex on the ellipse
    let (ux, uy) = (0.8, 0.6);
    for v in &c.vertices {
        let (dx, dy) = (v.x - 10.0, v.y - 5.0);
        let (p, q) = (dx * ux + dy * uy, -dx * uy + dy * ux);
        assert!(close((p / 10.0).powi(2) + (q / 5.0).powi(2), 1.0, 1e-9));
    }
    // half ellipse (upper half of an axis-aligned one) closed by its diameter
    let half = ent("ELLIPSE", "E2", "0", &[(10, 0.0), (20, 0.0), (11, 4.0), (21, 0.0), (40, 0.5), (41, 0.0), (42, PI)])
        + &line("L", [-4.0, 0.0], [4.0, 0.0]);
    let d = read_ok(&doc("", "", &half));
    assert_eq!(d.shapes.len(), 1);
    let a = d.shapes[0].contour.signed_area().abs();
    assert!(close(a, PI * 4.0 * 2.0 / 2.0, 0.02), "{a}");
    // a circular ellipse is kept as exact arcs
    let round = ent("ELLIPSE", "E3", "0", &[(10, 1.0), (20, 1.0), (11, 0.0), (21, 3.0), (40, 1.0)]);
    let d = read_ok(&doc("", "", &round));
    let c = &d.shapes[0].contour;
    assert!(c.vertices.len() <= 3 && c.vertices.iter().all(|v| v.bulge != 0.0), "{:?}", c.vertices);
    assert!(close(c.signed_area().abs(), 9.0 * PI, 1e-9));
    // extrusion (0,0,-1): the minor axis is n x major = (0, -2), so the quarter from parameter
    // 0 to 90 degrees runs clockwise from (4, 0) down to (0, -2); two lines close it
    let quarter = ent(
        "ELLIPSE",
        "E4",
        "0",
        &[(10, 0.0), (20, 0.0), (11, 4.0), (21, 0.0), (40, 0.5), (41, 0.0), (42, PI / 2.0), (230, -1.0)],
    ) + &line("L1", [0.0, -2.0], [0.0, 0.0])
        + &line("L2", [0.0, 0.0], [4.0, 0.0]);
    let d = read_ok(&doc("", "", &quarter));
    assert_eq!(d.shapes.len(), 1);
    assert!(close(d.shapes[0].contour.signed_area().abs(), 2.0 * PI, 0.01));
    assert!(close(bounds(&d)[1], -2.0, 1e-9), "{:?}", bounds(&d));
}

#[test]
fn mirrored_ocs_entities() {
    // An ARC with extrusion (0,0,-1): OCS centre (-5, 0) is WCS (5, 0), and the arc from OCS
    // angle 0 to 180 runs from WCS (0, 0) over (5, 5) to (10, 0); a LINE closes it.
    let arc_ocs = ent(
        "ARC",
        "A",
        "0",
        &[(10, -5.0), (20, 0.0), (40, 5.0), (210, 0.0), (220, 0.0), (230, -1.0), (50, 0.0), (51, 180.0)],
    );
    let circle_ocs = ent("CIRCLE", "C", "0", &[(10, 20.0), (20, 3.0), (40, 1.0), (230, -1.0)]);
    let lw = p(0, "LWPOLYLINE")
        + &p(8, "0")
        + &p(90, 2)
        + &p(70, 1)
        + &p(10, 40.0)
        + &p(20, 0.0)
        + &p(42, 1.0)
        + &p(10, 50.0)
        + &p(20, 0.0)
        + &p(42, 1.0)
        + &p(210, 0.0)
        + &p(220, 0.0)
        + &p(230, -1.0);
    let ents = arc_ocs + &line("L", [10.0, 0.0], [0.0, 0.0]) + &circle_ocs + &lw;
    let d = read_ok(&doc("", "", &ents));
    assert_eq!(d.shapes.len(), 3);
    let half = &d.shapes[0].contour;
    assert!(close(half.signed_area().abs(), 12.5 * PI, 1e-9));
    let b = half.bounds().unwrap();
    assert!(close(b[0], 0.0, 1e-9) && close(b[2], 10.0, 1e-9) && close(b[3], 5.0, 1e-3), "{b:?}");
    let b = d.shapes[1].contour.bounds().unwrap();
    assert!(close((b[0] + b[2]) / 2.0, -20.0, 1e-6) && close((b[1] + b[3]) / 2.0, 3.0, 1e-6), "{b:?}");
    let b = d.shapes[2].contour.bounds().unwrap();
    assert!(close(b[0], -50.0, 1e-6) && close(b[2], -40.0, 1e-6), "{b:?}");
}

#[test]
fn nested_block_inserts_with_scale_and_rotation() {
    // HOLE: a circle of radius 2 at its base point (1, 1); PAIR: two HOLEs 10 apart.
    let blocks = p(0, "BLOCK")
        + &p(8, "0")
        + &p(2, "HOLE")
        + &p(70, 0)
        + &p(10, 1.0)
        + &p(20, 1.0)
        + &p(30, 0.0)
        + &circle("0", [1.0, 1.0], 2.0)
        + &p(0, "ENDBLK")
        + &p(0, "BLOCK")
        + &p(2, "Pair")
        + &p(10, 0.0)
        + &p(20, 0.0)
        + &ent("INSERT", "", "0", &[])
        + &p(2, "HOLE")
        + &p(10, 0.0)
        + &p(20, 0.0)
        + &ent("INSERT", "", "0", &[])
        + &p(2, "HOLE")
        + &p(10, 10.0)
        + &p(20, 0.0)
        + &p(0, "ENDBLK");
    // PAIR at (100, 50), scale 2, rotated 90 degrees, on layer PART
    let ents = ent("INSERT", "9", "PART", &[])
        + &p(2, "PAIR")
        + &p(10, 100.0)
        + &p(20, 50.0)
        + &p(41, 2.0)
        + &p(42, 2.0)
        + &p(50, 90.0);
    let d = read_ok(&doc("", &blocks, &ents));
    assert_eq!(d.shapes.len(), 2);
    for (s, cy) in d.shapes.iter().zip([50.0, 70.0]) {
        assert_eq!(s.role, Role::Part, "layer 0 in a block takes the INSERT's layer");
        assert!(close(s.contour.signed_area().abs(), PI * 16.0, 1e-9));
        let b = s.contour.bounds().unwrap();
        assert!(close((b[0] + b[2]) / 2.0, 100.0, 1e-6) && close((b[1] + b[3]) / 2.0, cy, 1e-6), "{b:?}");
        assert!(s.origin.contains("in block \"HOLE\" inserted at line"), "{}", s.origin);
    }
    // a non-uniform scale turns the circles into ellipses
    let ents = ent("INSERT", "", "0", &[]) + &p(2, "HOLE") + &p(41, 3.0) + &p(42, 1.0);
    let d = read_ok(&doc("", &blocks, &ents));
    let a = d.shapes[0].contour.signed_area().abs();
    assert!(a < PI * 12.0 && PI * 12.0 - a < 0.002 * d.shapes[0].contour.length(), "{a}");
    // MINSERT: 3 columns x 2 rows
    let ents = ent("MINSERT", "", "0", &[]) + &p(2, "HOLE") + &p(70, 3) + &p(71, 2) + &p(44, 10.0) + &p(45, 20.0);
    assert_eq!(read_ok(&doc("", &blocks, &ents)).shapes.len(), 6);
    // a negative x scale mirrors a block, arcs included
    let dome = p(0, "BLOCK")
        + &p(2, "DOME")
        + &p(10, 0.0)
        + &p(20, 0.0)
        + &arc("", [5.0, 0.0], 5.0, 0.0, 180.0)
        + &line("", [0.0, 0.0], [10.0, 0.0])
        + &p(0, "ENDBLK");
    let ents = ent("INSERT", "", "0", &[]) + &p(2, "DOME") + &p(10, 100.0) + &p(41, -1.0);
    let d = read_ok(&doc("", &dome, &ents));
    assert_eq!(d.shapes.len(), 1);
    assert!(close(d.shapes[0].contour.signed_area().abs(), 12.5 * PI, 1e-9));
    let b = bounds(&d);
    assert!(close(b[0], 90.0, 1e-9) && close(b[2], 100.0, 1e-9) && close(b[3], 5.0, 1e-3), "{b:?}");
    // a missing block and a block inserting itself are errors
    let e = read(&doc("", &blocks, &(ent("INSERT", "", "0", &[]) + &p(2, "NOPE")))).unwrap_err();
    assert!(e.reason.contains("\"NOPE\""), "{e}");
    let selfish = p(0, "BLOCK") + &p(2, "LOOP") + &ent("INSERT", "", "0", &[]) + &p(2, "LOOP") + &p(0, "ENDBLK");
    let e = read(&doc("", &selfish, &(ent("INSERT", "", "0", &[]) + &p(2, "LOOP")))).unwrap_err();
    assert!(e.reason.contains("inserts itself"), "{e}");
}

#[test]
fn degenerate_entities_are_dropped() {
    let ents = line("1", [0.0, 0.0], [10.0, 0.0])
        + &line("2", [10.0, 0.0], [10.0, 0.0]) // zero length
        + &line("3", [10.0, 0.0], [10.0, 10.0])
        + &arc("4", [10.0, 10.0], 0.0, 0.0, 90.0) // zero radius
        + &line("5", [10.0, 10.0], [0.0, 0.0])
        + &line("6", [0.0, 0.0], [10.0, 10.0]) // line 5 drawn again
        + &circle("0", [50.0, 50.0], 0.0);
    let d = read_ok(&doc("", "", &ents));
    assert_eq!(d.shapes.len(), 1);
    assert_eq!(d.shapes[0].contour.vertices.len(), 3);
}

#[test]
fn paper_space_and_text_are_ignored() {
    let text = ent("TEXT", "", "0", &[(10, 0.0), (20, 0.0), (40, 2.5)]) + &p(1, "hello");
    let paper = ent("CIRCLE", "", "0", &[(67, 1.0), (10, 0.0), (20, 0.0), (40, 5.0)]);
    let d = read_ok(&doc("", "", &(text.clone() + &paper + &circle("0", [0.0, 0.0], 1.0))));
    assert_eq!(d.shapes.len(), 1);
    assert!(close(d.shapes[0].contour.signed_area().abs(), PI, 1e-9));
    let e = read(&doc("", "", &(text + &paper))).unwrap_err();
    assert!(e.reason.starts_with("no closed contour in the drawing"), "{e}");
    assert!(e.reason.contains("1 TEXT") && e.reason.contains("1 entities in paper space"), "{e}");
}

// ---- units ---------------------------------------------------------------------------------

fn unit_square() -> String {
    line("1", [0.0, 0.0], [1.0, 0.0])
        + &line("2", [1.0, 0.0], [1.0, 1.0])
        + &line("3", [1.0, 1.0], [0.0, 1.0])
        + &line("4", [0.0, 1.0], [0.0, 0.0])
}

#[test]
fn inch_units_are_scaled_to_mm() {
    let d = read_ok(&doc(&insunits(1), "", &unit_square()));
    assert_eq!(d.units, Units::Inch);
    assert!(close(d.shapes[0].contour.signed_area().abs(), 25.4 * 25.4, 1e-9));
    let b = bounds(&d);
    assert!(close(b[2], 25.4, 1e-12) && close(b[3], 25.4, 1e-12));
    // a 100 x 100 square, so that even in micrometres it is larger than the chaining tolerance
    let square = line("1", [0.0, 0.0], [100.0, 0.0])
        + &line("2", [100.0, 0.0], [100.0, 100.0])
        + &line("3", [100.0, 100.0], [0.0, 100.0])
        + &line("4", [0.0, 100.0], [0.0, 0.0]);
    for (code, units, mm) in [
        (2, Units::Foot, 304.8),
        (5, Units::Centimetre, 10.0),
        (6, Units::Metre, 1000.0),
        (9, Units::Mil, 0.0254),
        (13, Units::Micrometre, 0.001),
        (0, Units::Millimetre, 1.0),
    ] {
        let d = read_ok(&doc(&insunits(code), "", &square));
        assert_eq!(d.units, units);
        assert!(close(bounds(&d)[2], 100.0 * mm, 1e-9), "$INSUNITS {code}");
    }
}

#[test]
fn units_override_wins() {
    let opts = ImportOptions { units: Some(Units::Centimetre), ..Default::default() };
    let d = read_with(&doc(&insunits(1), "", &unit_square()), &opts).unwrap();
    assert_eq!(d.units, Units::Centimetre);
    assert!(close(bounds(&d)[2], 10.0, 1e-12));
    // units the crate cannot name are refused, unless overridden
    let e = read(&doc(&insunits(8), "", &unit_square())).unwrap_err();
    assert!(e.reason.contains("microinches") && e.place.contains("$INSUNITS"), "{e}");
    let d = read_with(
        &doc(&insunits(8), "", &unit_square()),
        &ImportOptions { units: Some(Units::Inch), ..Default::default() },
    )
    .unwrap();
    assert!(close(bounds(&d)[2], 25.4, 1e-12));
}

#[test]
fn chaining_tolerance_applies_in_mm() {
    // a 0.001 in (0.0254 mm) gap: open at the default 0.01 mm, closed at 0.03 mm
    let ents = line("1", [0.0, 0.0], [1.0, 0.0])
        + &line("2", [1.0, 0.0], [1.0, 1.0])
        + &line("3", [1.0, 1.0], [0.0, 1.0])
        + &line("4", [0.0, 1.0], [0.0, 0.001]);
    let text = doc(&insunits(1), "", &ents);
    let e = read(&text).unwrap_err();
    assert!(e.reason.contains("0.025 mm between (0.000, 0.000) and (0.000, 0.025)"), "{e}");
    let d = read_with(&text, &ImportOptions { chain_tolerance: 0.03, ..Default::default() }).unwrap();
    assert_eq!(d.shapes.len(), 1);
}

// ---- defects and bad files -----------------------------------------------------------------

#[test]
fn open_contour_is_refused_with_its_gaps() {
    // two nested U shapes whose ends stop 3 mm apart at y = 109 (as in a real drawing)
    let ents = line("63", [23.0, 133.0], [23.0, 109.0])
        + &line("64", [83.0, 133.0], [83.0, 109.0])
        + &line("65", [23.0, 133.0], [83.0, 133.0])
        + &line("6D", [26.0, 130.0], [26.0, 109.0])
        + &line("6E", [80.0, 130.0], [80.0, 109.0])
        + &line("6F", [26.0, 130.0], [80.0, 130.0])
        + &circle("0", [50.0, 50.0], 10.0);
    let text = doc(&insunits(4), "", &ents);
    let e = read(&text).unwrap_err();
    assert_eq!(e.place, "near (23.000, 109.000)");
    assert!(e.reason.contains("open contour"), "{e}");
    assert!(
        e.reason
            .contains("2 gaps (3.000 mm between (23.000, 109.000) and (26.000, 109.000) [LINE (handle 63) at line "),
        "{e}"
    );
    assert!(
        e.reason.contains("3.000 mm between (80.000, 109.000) and (83.000, 109.000) [LINE (handle 6E) at line "),
        "{e}"
    );
    assert!(
        e.reason.ends_with(
            "join the ends or raise the chaining tolerance, or skip open contours (--skip-open) to cut the rest"
        ),
        "{e}"
    );
    // the line numbers point at the entities
    let line_of_63 = text.lines().position(|l| l.trim() == "LINE").unwrap() + 1;
    assert!(e.reason.contains(&format!("[LINE (handle 63) at line {line_of_63} /")), "{e}");
    assert!(e.to_string().starts_with("test.dxf: near (23.000, 109.000): "), "{e}");
}

#[test]
fn nan_and_infinite_coordinates_are_errors() {
    let ents = line("1", [0.0, 0.0], [1.0, 0.0])
        + &p(0, "LINE")
        + &p(5, "1A")
        + &p(8, "0")
        + &p(10, "nan")
        + &p(20, 0.0)
        + &p(11, 1.0)
        + &p(21, 1.0);
    let text = doc("", "", &ents);
    let e = read(&text).unwrap_err();
    let line_no = text.lines().position(|l| l.trim() == "nan").unwrap() + 1;
    assert!(e.place.starts_with("LINE (handle 1A) at line "), "{e}");
    assert!(e.reason.contains(&format!("line {line_no}")) && e.reason.contains("not a finite number"), "{e}");
    for bad in ["inf", "-Infinity", "1.#QNAN", "1e999"] {
        let text = doc("", "", &(p(0, "CIRCLE") + &p(8, "0") + &p(10, 0.0) + &p(20, 0.0) + &p(40, bad)));
        let e = read(&text).unwrap_err();
        assert!(e.reason.contains("not a finite number"), "{bad}: {e}");
    }
    let text = doc("", "", &(p(0, "CIRCLE") + &p(8, "0") + &p(10, "1,5") + &p(20, 0.0) + &p(40, 1.0)));
    assert!(read(&text).unwrap_err().reason.contains("\"1,5\" is not a number"));
}

#[test]
fn empty_garbage_and_binary_files_are_refused() {
    assert!(read_err(b"").reason.contains("empty file"));
    assert!(read_err(b"  \r\n\n").reason.contains("empty file"));
    let e = read_err(b"hello world\nthis is not a drawing\n");
    assert!(e.reason.starts_with("not a DXF file") && e.place == "line 1", "{e}");
    let e = read_err(b"  0\nEOF\n");
    assert!(e.reason.contains("no ENTITIES section"), "{e}");
    let e = read_err(b"  0\nSECTION\n  2\nHEADER\n  0\nENDSEC\n  0\nEOF\n");
    assert!(e.reason.contains("no ENTITIES section"), "{e}");
    let junk: Vec<u8> = (0..2000u32).map(|i| (i.wrapping_mul(2654435761) >> 13) as u8).collect();
    assert!(read_err(&junk).reason.contains("not a DXF file"));
    let mut bin = b"AutoCAD Binary DXF\r\n\x1a\x00".to_vec();
    bin.extend_from_slice(&[0, 0, b'S', b'E', b'C']);
    assert!(read_err(&bin).reason.contains("binary DXF is not supported"));
    assert!(read_err(b"AC1018\x00\x00\x00\x00").reason.contains("DWG"));
    // a group code that is not a number in the middle of the file
    let text = doc("", "", &unit_square()).replacen(" 10\n", "1O\n", 1);
    let e = read_err(text.as_bytes());
    assert!(e.reason.contains("\"1O\"") && e.place.starts_with("line "), "{e}");
}

#[test]
fn truncated_files_are_refused() {
    let text = doc("", "", &unit_square());
    let at = text.find("\n3\n").unwrap(); // the handle of the third LINE
    let e = read_err(&text.as_bytes()[..at + 3]);
    assert!(e.reason.contains("ENTITIES section never ends") && e.reason.contains("truncated"), "{e}");
    // cut between a code and its value
    let e = read_err(&text.as_bytes()[..at]);
    assert!(e.reason.contains("group code 5 has no value: the file is truncated"), "{e}");
}

#[test]
fn no_input_makes_it_panic() {
    // every prefix of a drawing, and many mutated copies of it: errors or drawings, no panics
    let text = doc(
        &insunits(1),
        "",
        &(unit_square()
            + &arc("A", [5.0, 5.0], 1.0, 0.0, 360.0)
            + &ent("ELLIPSE", "E", "0", &[(10, 0.0), (20, 0.0), (11, 2.0), (21, 0.0), (40, 0.5)])),
    );
    let bytes = text.as_bytes();
    let mut oks = 0;
    for cut in 0..bytes.len() {
        if read_dxf(Path::new("t.dxf"), &bytes[..cut], &ImportOptions::default()).is_ok() {
            oks += 1;
        }
    }
    // only cuts inside the final "EOF" pair can still read
    assert!(oks <= 8, "{oks} truncated copies were accepted");
    let mut state: u64 = 7;
    let mut next = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 33) as usize
    };
    let specials: &[&[u8]] = &[b"0", b"-", b"\n", b"e999", b"nan", b"9", b"SECTION", b"\x00", b"\xff", b"1e308"];
    for _ in 0..3000 {
        let mut m = bytes.to_vec();
        for _ in 0..1 + next() % 3 {
            let at = next() % m.len();
            let s = specials[next() % specials.len()];
            let end = (at + next() % 4).min(m.len());
            m.splice(at..end, s.iter().copied());
        }
        let _ = read_dxf(Path::new("t.dxf"), &m, &ImportOptions::default());
    }
}

// ---- real drawings (trimesh, MIT) ----------------------------------------------------------

fn data(name: &str) -> Drawing {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dxf").join(name);
    match swarf_import::read_drawing(&path, &ImportOptions::default()) {
        Ok(d) => d,
        Err(e) => panic!("{e}"),
    }
}

fn assert_extents(d: &Drawing, expected: [f64; 4]) {
    let b = bounds(d);
    for i in 0..4 {
        assert!(close(b[i], expected[i], 0.01), "extents {b:?}, expected {expected:?}");
    }
}

#[test]
fn trimesh_cycloidal_has_23_loops_in_inches() {
    let d = data("trimesh_125_cycloidal.dxf");
    assert_eq!(d.units, Units::Inch);
    assert_eq!(d.shapes.len(), 23);
    // the lobed disc: a 411-vertex LWPOLYLINE closed only by coincident endpoints
    assert!(d.shapes.iter().any(|s| s.origin.starts_with("LWPOLYLINE") && s.contour.vertices.len() >= 400));
    assert_extents(&d, [60.889, 297.895, 178.024, 363.730]);
}

#[test]
fn trimesh_wrench_chains_lines_and_arcs_into_2_loops() {
    let d = data("trimesh_wrench.dxf");
    assert_eq!(d.units, Units::Inch);
    assert_eq!(d.shapes.len(), 2);
    assert!(d.shapes.iter().all(|s| s.origin.contains("more entities chained")));
    assert_extents(&d, [75.005, 111.801, 157.579, 135.596]);
}

#[test]
fn trimesh_apu_mount_has_19_loops() {
    let d = data("trimesh_apu-mount.dxf");
    assert_eq!(d.units, Units::Inch);
    assert_eq!(d.shapes.len(), 19);
    assert_eq!(d.shapes.iter().filter(|s| s.origin.starts_with("CIRCLE")).count(), 14);
    let b = bounds(&d);
    assert!(close(b[2] - b[0], 7.91 * 25.4, 0.2) && close(b[3] - b[1], 4.5 * 25.4, 0.2), "{b:?}");
}

#[test]
fn trimesh_splines_chain_with_lines() {
    let d = data("trimesh_spline.dxf");
    assert_eq!(d.units, Units::Millimetre);
    assert_eq!(d.shapes.len(), 4);
    // extents of the curves themselves (not of their control polygons)
    assert_extents(&d, [36.929, 28.987, 252.210, 169.252]);
}

#[test]
fn damaged_real_drawings_never_panic() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/dxf/trimesh_125_cycloidal.dxf");
    let bytes = std::fs::read(&path).expect("test data");
    let opts = ImportOptions::default();
    let mut state: u64 = 99;
    let mut next = move || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 33) as usize
    };
    let mut refused = 0;
    for _ in 0..300 {
        let cut = next() % bytes.len();
        if read_dxf(&path, &bytes[..cut], &opts).is_err() {
            refused += 1;
        }
    }
    // every section must end, so only a cut inside the final "EOF" could still read
    assert!(refused >= 295, "{refused} of 300 truncated copies refused");
    let specials: &[&[u8]] = &[b"0", b"-", b"\n", b"e999", b"nan", b"SECTION", b"ENDSEC", b"INSERT", b"-1"];
    for _ in 0..300 {
        let mut m = bytes.clone();
        for _ in 0..1 + next() % 5 {
            let at = next() % m.len();
            let s = specials[next() % specials.len()];
            let end = (at + next() % 4).min(m.len());
            m.splice(at..end, s.iter().copied());
        }
        let _ = read_dxf(&path, &m, &opts);
    }
}

// ---- layers, open contours left out, units' source ------------------------------------------

/// A closed square on layer CUT, an open hatch stroke on layer HATCH.
fn cut_and_hatch() -> String {
    let sq = [[0.0, 0.0], [40.0, 0.0], [40.0, 30.0], [0.0, 30.0]];
    let mut e = String::new();
    for i in 0..4 {
        e += &line_on("CUT", sq[i], sq[(i + 1) % 4]);
    }
    e += &line_on("HATCH", [5.0, 5.0], [35.0, 25.0]);
    doc(&insunits(4), "", &e)
}

#[test]
fn an_open_contour_is_refused_with_the_option_that_skips_it() {
    let e = read(&cut_and_hatch()).unwrap_err();
    assert!(e.reason.contains("open contour") && e.reason.contains("--skip-open"), "{e}");
    let d = read_with(&cut_and_hatch(), &ImportOptions { skip_open: true, ..Default::default() }).unwrap();
    assert_eq!(d.shapes.len(), 1);
    assert_eq!(d.skipped.len(), 1);
    assert!(d.skipped[0].starts_with("open contour from (5.000, 5.000) to (35.000, 25.000)"), "{:?}", d.skipped);
}

#[test]
fn layers_are_chosen_or_left_out_in_any_case() {
    for opts in [
        ImportOptions { ignore_layers: vec!["hatch".into()], ..Default::default() },
        ImportOptions { layers: vec!["Cut".into()], ..Default::default() },
    ] {
        let d = read_with(&cut_and_hatch(), &opts).unwrap();
        assert_eq!((d.shapes.len(), d.skipped.len()), (1, 0));
        assert_eq!(d.layers, vec!["CUT".to_string(), "HATCH".to_string()]);
    }
    let e = read_with(&cut_and_hatch(), &ImportOptions { layers: vec!["ENGRAVE".into()], ..Default::default() })
        .unwrap_err();
    assert!(e.reason.contains("the drawing's layers: CUT, HATCH"), "{e}");
}

#[test]
fn the_units_say_where_they_came_from() {
    let d = read_ok(&doc(&insunits(1), "", &circle("0", [0.0, 0.0], 1.0)));
    assert_eq!((d.units, d.units_from.as_str(), d.units_assumed), (Units::Inch, "$INSUNITS = 1", false));
    let d = read_ok(&doc("", "", &circle("0", [0.0, 0.0], 1.0)));
    assert_eq!((d.units, d.units_from.as_str(), d.units_assumed), (Units::Millimetre, "no $INSUNITS", true));
    let d = read_ok(&doc(&insunits(0), "", &circle("0", [0.0, 0.0], 1.0)));
    assert!(d.units_assumed && d.units_from.contains("unitless"));
}
