//! Real drawings from sameer/svg2gcode (MIT, see `data/svg/NOTICE.md`), plus real-world
//! document quirks.

use std::f64::consts::PI;
use std::path::Path;
use swarf_import::svg::read_svg;
use swarf_import::{Drawing, ImportError, ImportOptions, Role};

const SHAPES: &str = include_str!("../data/svg/svg2gcode_shapes.svg");
const SMOOTH: &str = include_str!("../data/svg/svg2gcode_smooth_curves.svg");
const LOGO: &str = include_str!("../data/svg/svg2gcode_Vanderbilt_Commodores_logo.svg");

fn read(svg: &str) -> Result<Drawing, ImportError> {
    read_svg(Path::new("sample.svg"), svg.as_bytes(), &ImportOptions::default())
}

fn extents(d: &Drawing) -> [f64; 4] {
    let mut b = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
    for s in &d.shapes {
        let c = s.contour.bounds().expect("non-empty");
        b = [b[0].min(c[0]), b[1].min(c[1]), b[2].max(c[2]), b[3].max(c[3])];
    }
    b
}

fn assert_close(a: f64, b: f64, tol: f64, what: &str) {
    assert!((a - b).abs() <= tol, "{what}: {a} vs {b} (tolerance {tol})");
}

#[test]
fn vanderbilt_logo_with_mirroring_groups() {
    let d = read(LOGO).unwrap();
    assert_eq!(d.shapes.len(), 3);
    let b = extents(&d);
    // px at 96 px/in with a 117.73 × 115.11 px page
    assert_close(b[2] - b[0], 30.62, 0.01, "width");
    assert_close(b[3] - b[1], 29.93, 0.01, "height");
    assert!(b[0] > 0.0 && b[1] > 0.0 && b[2] < 117.73 * 25.4 / 96.0 && b[3] < 115.11 * 25.4 / 96.0, "{b:?}");
    // three nested outlines: star, inner star, "V"
    let areas: Vec<f64> = d.shapes.iter().map(|s| s.contour.signed_area().abs()).collect();
    assert!(areas[0] > areas[1] && areas[1] > areas[2], "{areas:?}");
    // the path data runs the same way for all three, and two mirrors cancel: same orientation
    let signs: Vec<bool> = d.shapes.iter().map(|s| s.contour.signed_area() > 0.0).collect();
    assert!(signs.iter().all(|s| *s == signs[0]), "{signs:?}");
    assert!(d.shapes.iter().all(|s| s.origin.starts_with("path (line 2, column ")), "{:?}", d.shapes[0].origin);
}

#[test]
fn smooth_curves_bezier_outlines_and_arcs() {
    let d = read(SMOOTH).unwrap();
    // 37 closed subpaths, 3 of which have zero area (`v0h0v0Z`-style debris)
    assert_eq!(d.shapes.len(), 34);
    let b = extents(&d);
    assert_close(b[2] - b[0], 53.11, 0.01, "width");
    assert_close(b[3] - b[1], 70.27, 0.01, "height");
    // the viewBox is 277.8 px square, at 96 px/in
    assert!(b[0] >= 0.0 && b[1] >= 0.0 && b[2] <= 73.5 && b[3] <= 73.5, "{b:?}");
    let arcs: usize = d.shapes.iter().map(|s| s.contour.vertices.iter().filter(|v| v.bulge != 0.0).count()).sum();
    assert!(arcs > 100, "the file's `a` commands are kept as arcs: {arcs}");
    assert!(d.shapes.iter().all(|s| s.layer == "Layer_3" && s.role == Role::Auto));
}

#[test]
fn shapes_primitives_open_polyline_is_refused() {
    let e = read(SHAPES).unwrap_err();
    assert!(e.place.contains("polyline id=\"polyline1\""), "{e}");
    assert!(e.reason.contains("29.842 mm"), "{e}");
}

#[test]
fn shapes_primitives_without_the_open_polyline() {
    let start = SHAPES.find("<polyline").unwrap();
    let end = start + SHAPES[start..].find("/>").unwrap() + 2;
    let svg = format!("{}{}", &SHAPES[..start], &SHAPES[end..]);
    let d = read(&svg).unwrap();
    let ids: Vec<&str> = d.shapes.iter().map(|s| s.origin.split(' ').nth(1).unwrap_or("")).collect();
    assert_eq!(
        ids,
        ["id=\"rect1\"", "id=\"rect1-2\"", "id=\"path1\"", "id=\"path1-5\"", "id=\"path2\"", "id=\"polygon1\""]
    );
    // width="200mm" with viewBox 0 0 200 200: one user unit is one millimetre
    let circle = &d.shapes[4].contour;
    assert_eq!(circle.vertices.len(), 2);
    assert_close(circle.signed_area().abs(), PI * 7.5113683f64.powi(2), 1e-9, "circle");
    let cb = circle.bounds().unwrap();
    assert_close((cb[0] + cb[2]) / 2.0, 126.20531, 1e-6, "circle centre x");
    assert_close((cb[1] + cb[3]) / 2.0, 200.0 - 87.947006, 1e-6, "circle centre y (flipped about the page)");
    // rx=4 ry=10 corners are elliptical: flattened, area w·h − (4 − π)·rx·ry
    let (w, h) = (43.444885, 33.418541);
    for i in [0, 1] {
        let r = &d.shapes[i].contour;
        assert!(r.vertices.iter().all(|v| v.bulge == 0.0));
        assert_close(r.signed_area().abs(), w * h - (4.0 - PI) * 40.0, 0.05, "rounded rect");
    }
    // ellipses: π·rx·ry times the transform's determinant; flattened within 0.002 mm, which
    // loses less than 0.002 mm × the perimeter
    let a2 = d.shapes[2].contour.signed_area().abs();
    let want = PI * 18.580959 * 5.4338274;
    assert!(a2 < want && a2 > want - 0.002 * 80.0, "ellipse {a2} vs {want}");
    let det: f64 = -0.76030559 * -0.68490244 - -0.64956556 * 0.72863478;
    let a3 = d.shapes[3].contour.signed_area().abs();
    let want = PI * 14.124 * 20.0 * det;
    assert!(a3 < want && a3 > want - 0.002 * 110.0, "transformed ellipse {a3} vs {want}");
    assert_eq!(d.shapes[5].contour.vertices.len(), 7);
}

#[test]
fn illustrator_style_doctype_with_entities() {
    let svg = r##"<?xml version="1.0" encoding="utf-8"?>
<!-- Generator: Adobe Illustrator 16.0.0, SVG Export Plug-In . SVG Version: 6.00 Build 0)  -->
<!DOCTYPE svg PUBLIC "-//W3C//DTD SVG 1.1//EN" "http://www.w3.org/Graphics/SVG/1.1/DTD/svg11.dtd" [
	<!ENTITY ns_svg "http://www.w3.org/2000/svg">
	<!ENTITY ns_xlink "http://www.w3.org/1999/xlink">
]>
<svg version="1.1" xmlns="&ns_svg;" xmlns:xlink="&ns_xlink;" width="72pt" height="72pt" viewBox="0 0 72 72"
	 xml:space="preserve">
<switch>
	<foreignObject requiredExtensions="http://ns.adobe.com/AdobeIllustrator/10.0/" x="0" y="0" width="1" height="1">
		<i:pgfRef xmlns:i="http://ns.adobe.com/AdobeIllustrator/10.0/" xlink:href="#adobe_illustrator_pgf"/>
	</foreignObject>
	<g id="Layer_1"><polygon points="0,0 72,0 72,72 0,72"/></g>
</switch>
</svg>"##;
    let d = read(svg).unwrap();
    assert_eq!(d.shapes.len(), 1);
    // 72 pt = 1 in
    assert_close(d.shapes[0].contour.signed_area().abs(), 25.4 * 25.4, 1e-9, "one square inch");
    assert_eq!(d.shapes[0].layer, "Layer_1");
}

#[test]
fn byte_order_mark_and_no_namespace() {
    let svg =
        "\u{feff}<svg width=\"10mm\" height=\"10mm\" viewBox=\"0 0 10 10\"><rect width=\"5\" height=\"5\"/></svg>";
    let d = read(svg).unwrap();
    assert_close(d.shapes[0].contour.signed_area().abs(), 25.0, 1e-9, "area");
}

#[test]
fn latin1_declared_files_are_read() {
    let mut bytes = b"<?xml version='1.0' encoding='ISO-8859-1'?>\n<!-- Zeichnung f\xfcr die Fr\xe4se -->\n".to_vec();
    bytes.extend_from_slice(
        br#"<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="10mm" viewBox="0 0 10 10">"#,
    );
    bytes.extend_from_slice(b"<g id=\"Ebene \xe4\"><rect width=\"4\" height=\"5\"/></g></svg>");
    let d = read_svg(Path::new("latin1.svg"), &bytes, &ImportOptions::default()).unwrap();
    assert_close(d.shapes[0].contour.signed_area().abs(), 20.0, 1e-9, "area");
    assert_eq!(d.shapes[0].layer, "Ebene \u{e4}");
}
