//! SVG reader: refusals with a clear place and reason, and no panic on hostile input.

use std::path::Path;
use swarf_import::svg::read_svg;
use swarf_import::{ImportError, ImportOptions};

const HEAD: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" width="100mm" height="100mm" viewBox="0 0 100 100">"#;

fn doc(body: &str) -> String {
    format!("{HEAD}\n{body}\n</svg>")
}

fn fail_bytes(bytes: &[u8]) -> ImportError {
    match read_svg(Path::new("bad.svg"), bytes, &ImportOptions::default()) {
        Ok(d) => panic!("accepted: {d:?}"),
        Err(e) => e,
    }
}

fn fail(svg: &str) -> ImportError {
    fail_bytes(svg.as_bytes())
}

fn has(e: &ImportError, place: &str, reason: &str) {
    assert!(
        e.place.contains(place) && e.reason.contains(reason),
        "want place ~ {place:?}, reason ~ {reason:?}; got {e}"
    );
    assert_eq!(e.file, Path::new("bad.svg"));
}

#[test]
fn empty_and_non_xml_files() {
    has(&fail(""), "file", "empty file");
    has(&fail(" \n\t "), "file", "empty file");
    has(&fail("hello, world"), "line 1", "not well-formed XML");
    has(&fail("<svg xmlns=\"http://www.w3.org/2000/svg\">\n<rect width=\"10\""), "", "not well-formed XML");
    has(&fail("<svg>\n<g>\n</svg>"), "line 3", "not well-formed XML");
    has(&fail("<?xml version=\"1.0\"?>\n<html><body/></html>"), "line 2, column 1", "not <svg>");
    has(&fail_bytes(b"<svg>\xff\xfe</svg>"), "line 1", "not UTF-8");
    has(&fail_bytes(b"\xff\xfe<\x00s\x00"), "file", "UTF-16");
    has(&fail_bytes(b"\x1f\x8b\x08\x00"), "file", "gzip");
}

#[test]
fn no_closed_contour() {
    has(&fail(&doc("")), "drawing", "no closed contour in the drawing");
    has(
        &fail(&doc(r#"<text x="1" y="1">only text</text><rect width="0" height="5"/>"#)),
        "drawing",
        "no closed contour",
    );
    has(&fail(&doc(r#"<path d="M 10 10 H 20 Z"/><path d="M 5 5 Z"/>"#)), "drawing", "no closed contour");
    has(&fail(&doc(r#"<g style="display:none"><rect width="5" height="5"/></g>"#)), "drawing", "no closed contour");
}

#[test]
fn bad_numbers_name_the_element_and_attribute() {
    has(&fail(&doc(r#"<path id="p1" d="M 0 0 L NaN 5 Z"/>"#)), "path id=\"p1\" (line 2)", "attribute d=");
    has(&fail(&doc(r#"<path id="p2" d="M 0 0 L 10 inf 5 Z"/>"#)), "path id=\"p2\"", "invalid path data");
    has(&fail(&doc(r#"<path d="M 0 0 L 10 Z"/>"#)), "path (line 2, column 1)", "attribute d=");
    has(&fail(&doc(r#"<path d="L 0 0 L 10 10 Z"/>"#)), "path (line 2", "attribute d=");
    has(&fail(&doc(r#"<rect id="r" width="abc" height="5"/>"#)), "rect id=\"r\"", "attribute width=\"abc\"");
    has(&fail(&doc(r#"<rect width="10" height="-5"/>"#)), "rect (line 2", "must not be negative");
    has(&fail(&doc(r#"<circle id="c" r="1e999"/>"#)), "circle id=\"c\"", "attribute r=");
    has(&fail(&doc(r#"<circle r="NaN"/>"#)), "circle", "attribute r=");
    has(&fail(&doc(r#"<ellipse rx="5" ry="5" cx="1..2"/>"#)), "ellipse", "attribute cx=");
    has(
        &fail(&doc(r#"<g transform="rotate(nan)"><rect width="5" height="5"/></g>"#)),
        "g (line 2",
        "attribute transform=",
    );
    has(&fail(&doc(r#"<rect transform="translate(1,2" width="5" height="5"/>"#)), "rect", "attribute transform=");
    has(&fail(&doc(r#"<polygon id="pg" points="0,0 10,0 10"/>"#)), "polygon id=\"pg\"", "odd number of coordinates");
    has(&fail(&doc(r#"<polygon points="0,0 10,x 10,10"/>"#)), "polygon", "attribute points=");
    has(
        &fail("<svg xmlns=\"http://www.w3.org/2000/svg\" viewBox=\"0 0 0 10\"><rect width=\"1\" height=\"1\"/></svg>"),
        "svg",
        "viewBox",
    );
    has(
        &fail("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"ten\"><rect width=\"1\" height=\"1\"/></svg>"),
        "svg",
        "width",
    );
    // finite numbers whose transformed coordinates overflow
    has(
        &fail(&doc(r#"<path id="big" transform="scale(1e200)" d="M 0 0 L 1e200 0 L 0 1e200 Z"/>"#)),
        "path id=\"big\"",
        "overflow",
    );
}

#[test]
fn open_outlines_are_refused_with_the_element_and_the_gap() {
    let e = fail(&doc(r#"<rect width="10" height="10"/>
<path id="stroke1" style="fill:none;stroke:#000" d="M 20 20 L 30 20 L 30 30"/>"#));
    has(&e, "path id=\"stroke1\" (line 3)", "14.142 mm");
    assert!(e.reason.contains("closed"), "{e}");
    has(
        &fail(&doc(r#"<line id="axis" x1="0" y1="50" x2="100" y2="50"/><circle r="5"/>"#)),
        "line id=\"axis\"",
        "100.000 mm",
    );
    has(&fail(&doc(r#"<polyline points="0,0 10,0 10,10"/>"#)), "polyline (line 2", "open contour");
    // two loose lines that do not meet: each gap is reported
    let e = fail(&doc(r#"<line x1="0" y1="0" x2="10" y2="0"/><line x1="10" y1="3" x2="0" y2="3"/>"#));
    assert!(e.reason.contains("3.000 mm"), "{e}");
}

#[test]
fn use_errors() {
    has(&fail(&doc(r##"<use id="u" href="#nothing"/>"##)), "use id=\"u\"", "no element has this id");
    has(&fail(&doc(r##"<g id="a"><rect width="1" height="1"/><use href="#a"/></g>"##)), "use", "loops back");
    has(&fail(&doc(r##"<use href="other.svg#a"/>"##)), "use", "same file");
}

#[test]
fn invalid_options() {
    let svg = doc(r#"<rect width="10" height="10"/>"#);
    for opts in [
        ImportOptions { flatten_tolerance: 0.0, ..Default::default() },
        ImportOptions { flatten_tolerance: f64::NAN, ..Default::default() },
        ImportOptions { svg_px_per_inch: Some(-96.0), ..Default::default() },
        ImportOptions { chain_tolerance: f64::INFINITY, ..Default::default() },
    ] {
        let e = read_svg(Path::new("bad.svg"), svg.as_bytes(), &opts).unwrap_err();
        assert_eq!(e.place, "options", "{e}");
    }
}

#[test]
fn deep_nesting_and_use_bombs_are_refused_not_crashed() {
    let deep = doc(&format!("{}<rect width=\"1\" height=\"1\"/>{}", "<g>".repeat(5000), "</g>".repeat(5000)));
    has(&fail(&deep), "g (line 2", "nested deeper");
    // every level instantiates the one below ten times: 10^9 rectangles
    let mut body = String::from(r#"<defs><rect id="l0" width="1" height="1"/>"#);
    for i in 1..10 {
        body += &format!("<g id=\"l{i}\">");
        for _ in 0..10 {
            body += &format!("<use href=\"#l{}\"/>", i - 1);
        }
        body += "</g>";
    }
    body += "</defs><use href=\"#l9\"/>";
    let t = std::time::Instant::now();
    has(&fail(&doc(&body)), "use", "use instances");
    assert!(t.elapsed().as_secs() < 20, "took {:?}", t.elapsed());
}

#[test]
fn absurd_detail_is_refused_not_exhausting_memory() {
    // a scale slip (1 unit = 1 km) with Bézier wiggles: billions of chords at 0.002 mm
    let wiggles: String = (0..400).map(|i| format!(" C {} 10 {} -10 {} 0", 3 * i + 1, 3 * i + 2, 3 * i + 3)).collect();
    let svg = doc(&format!(r#"<path id="huge" transform="scale(1e6)" d="M 0 0{wiggles} V 50 H 0 Z"/>"#));
    let t = std::time::Instant::now();
    has(&fail(&svg), "path id=\"huge\"", "vertices");
    assert!(t.elapsed().as_secs() < 30, "took {:?}", t.elapsed());
}

/// A drawing using most of the grammar, to mangle.
const RICH: &str = r##"<?xml version="1.0"?>
<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink"
     xmlns:inkscape="http://www.inkscape.org/namespaces/inkscape" width="120mm" height="90mm" viewBox="0 0 120 90">
  <defs><circle id="hole" r="3"/><symbol id="s" viewBox="0 0 10 10"><rect width="10" height="10" rx="2"/></symbol></defs>
  <g inkscape:label="PART" transform="translate(5,5) rotate(10 50 40)">
    <path id="outline" d="M0,0 h100 v60 a10 10 0 0 1 -10 10 H10 q-10 0 -10 -10 t0 -10 c0 -5 5 -10 0 -20 s -5 -10 0 -15 z
       m 20 20 l 10 0 10 10 -20 0 z M 60 20 A 8 5 30 1 0 70 25 Z"/>
    <rect x="40" y="40" width="20" height="10" ry="3" transform="skewX(15)"/>
    <ellipse cx="80" cy="15" rx="6" ry="3"/>
    <polygon points="5,50 15,50 10,58"/>
    <use xlink:href="#hole" x="90" y="50"/><use href="#s" x="70" y="50" width="8" height="8"/>
    <svg x="0" y="0" width="20" height="20" viewBox="0 0 40 40" preserveAspectRatio="xMinYMax slice"><circle cx="20" cy="20" r="10"/></svg>
    <line x1="0" y1="80" x2="10" y2="80"/><line x1="10" y1="80" x2="10" y2="85"/><polyline points="10,85 0,85 0,80"/>
  </g>
</svg>"##;

#[test]
fn the_rich_drawing_reads() {
    let d = read_svg(Path::new("rich.svg"), RICH.as_bytes(), &ImportOptions::default()).unwrap();
    assert_eq!(d.shapes.len(), 10, "{:#?}", d.shapes.iter().map(|s| &s.origin).collect::<Vec<_>>());
    assert!(d.shapes.iter().all(|s| s.contour.is_finite() && s.contour.closed && s.layer == "PART"));
}

/// A tiny deterministic generator (xorshift) so the mangling is reproducible.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

#[test]
fn truncated_and_mangled_input_never_panics() {
    let opts = ImportOptions::default();
    let bytes = RICH.as_bytes();
    for cut in 0..bytes.len() {
        let _ = read_svg(Path::new("cut.svg"), &bytes[..cut], &opts);
    }
    let alphabet = b"<>/=\"' -+.,eE0123456789MmLlHhVvCcSsQqTtAaZz#;:()nanif\n\xc3\xa9\xff";
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut accepted = 0;
    for _ in 0..3000 {
        let mut b = bytes.to_vec();
        for _ in 0..1 + rng.below(4) {
            let at = rng.below(b.len());
            match rng.below(3) {
                0 => b[at] = alphabet[rng.below(alphabet.len())],
                1 => {
                    b.remove(at);
                }
                _ => b.insert(at, alphabet[rng.below(alphabet.len())]),
            }
        }
        if let Ok(d) = read_svg(Path::new("mangled.svg"), &b, &opts) {
            accepted += 1;
            assert!(
                d.shapes.iter().all(|s| s.contour.is_finite() && s.contour.closed && s.contour.vertices.len() >= 2)
            );
        }
    }
    assert!(accepted > 100, "some mutations are harmless: {accepted}");
}
