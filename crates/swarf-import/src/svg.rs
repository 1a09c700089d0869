//! SVG reader: an `<svg>` document into closed [`Contour`]s in millimetres, circular arcs kept as
//! arcs.
//!
//! Every closed subpath of the shape elements (`path`, `rect`, `circle`, `ellipse`, `line`,
//! `polyline`, `polygon`, through `g`, nested `svg`, `switch` and `use`) becomes one [`Shape`];
//! each element's `transform` is composed down the tree and the root's user space mapped to
//! millimetres (its units, `viewBox` and `preserveAspectRatio`, or [`ImportOptions::units`]),
//! with Y flipped about the bottom edge of the page so that the drawing reads as on screen. Arcs
//! that stay circular are kept exact as bulges (SVG 1.1 appendix F.6.5–F.6.6); other curves are
//! flattened within [`ImportOptions::flatten_tolerance`] by proven bounds. Open subpaths are
//! chained; an outline that stays open is refused with the element and the gap. Groups named
//! `STOCK`, `PART` or `FIXTURE` give their role ([`Role::from_layer_name`]); every error is an
//! [`ImportError`], never a panic. What is read and skipped, the coordinate mapping, arcs, the
//! flattening bounds, open outlines, roles and errors are walked through in `docs/import.md`.

use crate::chain::{Piece, chain, open_contour_message};
use crate::contour::{Contour, Vertex};
use crate::{Drawing, ImportError, ImportOptions, Role, Shape, Units};
use roxmltree::{Document, Node, NodeId, ParsingOptions};
use std::collections::HashMap;
use std::f64::consts::{PI, TAU};
use std::path::Path;
use std::str::FromStr;
use svgtypes::{Align, AspectRatio, Length, LengthUnit, PathParser, PathSegment, ViewBox};

type P = [f64; 2];

const SVG_NS: &str = "http://www.w3.org/2000/svg";
const INKSCAPE_NS: &str = "http://www.inkscape.org/namespaces/inkscape";
const XLINK_NS: &str = "http://www.w3.org/1999/xlink";

/// Deepest element nesting followed (the walk is recursive).
const MAX_DEPTH: usize = 128;
/// Most `use` instantiations followed in one document (guards against exponential fan-out).
const MAX_USES: usize = 100_000;
/// Consecutive points closer than this (mm) are one point.
const MERGE_EPS: f64 = 1e-9;
/// A `Z` whose gap is smaller than this (mm) merges the last point into the first.
const Z_SNAP: f64 = 1e-4;
/// Closed contours with less area than this (mm²) are dropped as degenerate.
const MIN_AREA: f64 = 1e-9;
/// Deepest Bézier subdivision (2^16 pieces: a 4 km curve at 1 µm).
const MAX_BEZIER_DEPTH: u32 = 16;
/// Most chords for one elliptical arc.
const MAX_ARC_STEPS: usize = 1 << 16;
/// Most vertices in one drawing (about 240 MB of contours).
const MAX_VERTICES: usize = 10_000_000;
/// Default font size for `em`/`ex` lengths (CSS medium).
const FONT_SIZE_PX: f64 = 16.0;

/// Reads an SVG drawing from its bytes; see the module documentation for the rules.
///
/// `path` is only used to name the file in the [`Drawing`] and in errors.
pub fn read_svg(path: &Path, bytes: &[u8], opts: &ImportOptions) -> Result<Drawing, ImportError> {
    let err = |place: &str, reason: String| ImportError::new(path, place, reason);
    check_options(opts).map_err(|r| err("options", r))?;
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(err("file", "empty file".into()));
    }
    if bytes.starts_with(&[0x1f, 0x8b]) {
        return Err(err("file", "gzip-compressed SVG (.svgz); decompress it first".into()));
    }
    if bytes.starts_with(&[0xff, 0xfe]) || bytes.starts_with(&[0xfe, 0xff]) {
        return Err(err("file", "UTF-16 text; save the SVG as UTF-8".into()));
    }
    let latin1: String;
    let text = match std::str::from_utf8(bytes) {
        Ok(t) => t,
        Err(_) if declares_latin1(bytes) => {
            latin1 = bytes.iter().map(|&b| char::from(b)).collect();
            &latin1
        }
        Err(e) => {
            let good = &bytes[..e.valid_up_to()];
            let line = 1 + good.iter().filter(|&&b| b == b'\n').count();
            return Err(err(
                &format!("line {line}"),
                format!("not UTF-8 text (invalid byte at offset {})", e.valid_up_to()),
            ));
        }
    };
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let popts = ParsingOptions { allow_dtd: true, ..ParsingOptions::default() };
    let doc = Document::parse_with_options(text, popts).map_err(|e| {
        let place = match e {
            roxmltree::Error::UnexpectedEndOfStream => "end of file".to_string(),
            _ => {
                let p = e.pos();
                format!("line {}, column {}", p.row, p.col)
            }
        };
        err(&place, format!("not well-formed XML: {e}"))
    })?;
    let root = doc.root_element();
    if root.tag_name().name() != "svg" || !is_svg_ns(root) {
        let p = doc.text_pos_at(root.range().start);
        return Err(err(
            &format!("line {}, column {}", p.row, p.col),
            format!("the root element is <{}>, not <svg>: not an SVG drawing", root.tag_name().name()),
        ));
    }

    let mut ids = HashMap::new();
    for n in doc.descendants().filter(Node::is_element) {
        if let Some(id) = n.attribute("id") {
            ids.entry(id.to_string()).or_insert(n.id());
        }
    }
    let ppi = opts.svg_px_per_inch.unwrap_or_else(|| if legacy_inkscape(root) { 90.0 } else { 96.0 });
    let abs_mm_to_user = match opts.units {
        Some(u) => 1.0 / u.mm(),
        None => ppi / 25.4,
    };
    let mut r = Reader {
        file: path,
        doc: &doc,
        opts,
        abs_mm_to_user,
        ids,
        ppi,
        use_stack: Vec::new(),
        uses: 0,
        vertices: 0,
        shapes: Vec::new(),
        open: Vec::new(),
        skipped: Vec::new(),
        layers: Vec::new(),
        line_starts: std::iter::once(0)
            .chain(doc.input_text().bytes().enumerate().filter(|&(_, b)| b == b'\n').map(|(i, _)| i + 1))
            .collect(),
        last_pos: std::cell::Cell::new((0, 0, 0)),
    };
    let (map, vp, units, units_from, units_assumed) = r.root_mapping(root)?;
    if display_none(root) {
        return Err(err("drawing", "the root <svg> is hidden (display:none): no closed contour in the drawing".into()));
    }
    let mut ctx = Ctx {
        ctm: map,
        vp,
        role: Role::Auto,
        role_fixed: false,
        layer: String::new(),
        groups: Vec::new(),
        visible: true,
        via: String::new(),
    };
    if let Some(t) = root.attribute("transform") {
        ctx.ctm = ctx.ctm.mul(r.transform_attr(root, t)?);
    }
    if let Some(v) = visibility(root) {
        ctx.visible = v;
    }
    r.children(root, &ctx, 0)?;
    r.close_open_pieces()?;
    if r.shapes.is_empty() {
        let mut reason = String::from("no closed contour in the drawing");
        if !(opts.layers.is_empty() && opts.ignore_layers.is_empty()) {
            let names: Vec<&str> = r.layers.iter().map(|l| if l.is_empty() { "(none)" } else { l }).collect();
            reason.push_str(&format!(" on the groups read (the drawing's groups: {})", names.join(", ")));
        }
        return Err(err("drawing", reason));
    }
    Ok(Drawing {
        path: path.to_path_buf(),
        units,
        units_from,
        units_assumed,
        shapes: r.shapes,
        skipped: r.skipped,
        layers: r.layers,
    })
}

/// Whether the file was written by Inkscape before 0.92, which drew at 90 px per inch (its
/// `inkscape:version`, e.g. `0.48.3 r9886`).
fn legacy_inkscape(root: Node) -> bool {
    let Some(v) = root.attribute((INKSCAPE_NS, "version")) else { return false };
    let mut parts = v.split(|c: char| !c.is_ascii_digit()).map(|p| p.parse::<u32>().ok());
    matches!((parts.next().flatten(), parts.next().flatten()), (Some(0), Some(minor)) if minor < 92)
}

/// Whether the XML declaration names a single-byte Latin encoding (ISO-8859-1, Windows-1252), which
/// old exporters use; such a file is read byte for byte.
fn declares_latin1(bytes: &[u8]) -> bool {
    let head = String::from_utf8_lossy(&bytes[..bytes.len().min(200)]).to_ascii_lowercase();
    let Some(decl) = head.strip_prefix("<?xml").and_then(|h| h.split("?>").next()) else { return false };
    ["iso-8859-1", "iso8859-1", "latin1", "latin-1", "windows-1252", "cp1252"]
        .iter()
        .any(|e| decl.contains(&format!("\"{e}\"")) || decl.contains(&format!("'{e}'")))
}

fn check_options(opts: &ImportOptions) -> Result<(), String> {
    if !(opts.flatten_tolerance.is_finite() && opts.flatten_tolerance > 0.0) {
        return Err(format!("flatten_tolerance must be a positive number of mm, not {}", opts.flatten_tolerance));
    }
    if let Some(ppi) = opts.svg_px_per_inch
        && !(ppi.is_finite() && ppi > 0.0)
    {
        return Err(format!("svg_px_per_inch must be a positive number, not {ppi}"));
    }
    if !(opts.chain_tolerance.is_finite() && opts.chain_tolerance >= 0.0) {
        return Err(format!("chain_tolerance must be zero or a positive number of mm, not {}", opts.chain_tolerance));
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Affine maps

/// `x' = a·x + c·y + e`, `y' = b·x + d·y + f` (the SVG `matrix(a b c d e f)`).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Affine {
    a: f64,
    b: f64,
    c: f64,
    d: f64,
    e: f64,
    f: f64,
}

impl Affine {
    const IDENTITY: Affine = Affine { a: 1.0, b: 0.0, c: 0.0, d: 1.0, e: 0.0, f: 0.0 };

    fn translate(x: f64, y: f64) -> Affine {
        Affine { e: x, f: y, ..Affine::IDENTITY }
    }

    /// `self ∘ o`: applies `o` first, then `self`.
    fn mul(&self, o: Affine) -> Affine {
        Affine {
            a: self.a * o.a + self.c * o.b,
            b: self.b * o.a + self.d * o.b,
            c: self.a * o.c + self.c * o.d,
            d: self.b * o.c + self.d * o.d,
            e: self.a * o.e + self.c * o.f + self.e,
            f: self.b * o.e + self.d * o.f + self.f,
        }
    }

    fn apply(&self, p: P) -> P {
        [self.a * p[0] + self.c * p[1] + self.e, self.b * p[0] + self.d * p[1] + self.f]
    }

    fn det(&self) -> f64 {
        self.a * self.d - self.b * self.c
    }

    fn is_finite(&self) -> bool {
        [self.a, self.b, self.c, self.d, self.e, self.f].iter().all(|v| v.is_finite())
    }

    /// The singular values (largest first) of the linear part: the semi-axes of the image of
    /// the unit circle.
    fn singular_values(&self) -> (f64, f64) {
        let e = (self.a + self.d) / 2.0;
        let f = (self.a - self.d) / 2.0;
        let g = (self.b + self.c) / 2.0;
        let h = (self.b - self.c) / 2.0;
        let q = e.hypot(h);
        let r = f.hypot(g);
        (q + r, (q - r).abs())
    }
}

/// The map from a viewBox onto a `w` × `h` viewport (no flip), following `preserveAspectRatio`.
fn viewbox_map(vb: ViewBox, par: AspectRatio, w: f64, h: f64) -> Affine {
    let mut sx = w / vb.w;
    let mut sy = h / vb.h;
    let (fx, fy) = match par.align {
        Align::None => (0.0, 0.0),
        Align::XMinYMin => (0.0, 0.0),
        Align::XMidYMin => (0.5, 0.0),
        Align::XMaxYMin => (1.0, 0.0),
        Align::XMinYMid => (0.0, 0.5),
        Align::XMidYMid => (0.5, 0.5),
        Align::XMaxYMid => (1.0, 0.5),
        Align::XMinYMax => (0.0, 1.0),
        Align::XMidYMax => (0.5, 1.0),
        Align::XMaxYMax => (1.0, 1.0),
    };
    if par.align != Align::None {
        let s = if par.slice { sx.max(sy) } else { sx.min(sy) };
        sx = s;
        sy = s;
    }
    let ox = (w - vb.w * sx) * fx;
    let oy = (h - vb.h * sy) * fy;
    Affine { a: sx, b: 0.0, c: 0.0, d: sy, e: ox - sx * vb.x, f: oy - sy * vb.y }
}

fn dist(p: P, q: P) -> f64 {
    (q[0] - p[0]).hypot(q[1] - p[1])
}

// ---------------------------------------------------------------------------------------------
// Subpaths in user space

#[derive(Debug, Clone, Copy)]
enum Seg {
    Line(P),
    Cubic(P, P, P),
    Arc { rx: f64, ry: f64, phi: f64, large: bool, sweep: bool, to: P },
}

impl Seg {
    fn end(&self) -> P {
        match *self {
            Seg::Line(p) | Seg::Cubic(_, _, p) | Seg::Arc { to: p, .. } => p,
        }
    }
}

#[derive(Debug, Clone)]
struct SubPath {
    start: P,
    segs: Vec<Seg>,
    closed: bool,
}

impl SubPath {
    fn new(start: P) -> SubPath {
        SubPath { start, segs: Vec::new(), closed: false }
    }

    fn polygon(points: &[P], closed: bool) -> SubPath {
        let mut sp = SubPath::new(points[0]);
        sp.segs.extend(points[1..].iter().map(|&p| Seg::Line(p)));
        sp.closed = closed;
        sp
    }
}

/// Parses path data into subpaths (user units); quadratics become cubics.
fn parse_path(d: &str) -> Result<Vec<SubPath>, String> {
    let mut subs: Vec<SubPath> = Vec::new();
    let mut cur: Option<SubPath> = None;
    let mut pos: P = [0.0, 0.0];
    let mut start: P = [0.0, 0.0];
    // Last control point of a cubic (for S) or of a quadratic (for T), in absolute coordinates.
    let mut last_cubic: Option<P> = None;
    let mut last_quad: Option<P> = None;
    fn flush(subs: &mut Vec<SubPath>, cur: &mut Option<SubPath>) {
        if let Some(sp) = cur.take()
            && !sp.segs.is_empty()
        {
            subs.push(sp);
        }
    }
    for seg in PathParser::from(d) {
        let seg = seg.map_err(|e| format!("invalid path data: {e}"))?;
        let rel = |abs: bool, x: f64, y: f64| if abs { [x, y] } else { [pos[0] + x, pos[1] + y] };
        let (mut next_cubic, mut next_quad) = (None, None);
        if let PathSegment::MoveTo { abs, x, y } = seg {
            flush(&mut subs, &mut cur);
            pos = rel(abs, x, y);
            start = pos;
            cur = Some(SubPath::new(pos));
            last_cubic = None;
            last_quad = None;
            continue;
        }
        if let PathSegment::ClosePath { .. } = seg {
            if let Some(sp) = cur.as_mut() {
                sp.closed = true;
            }
            flush(&mut subs, &mut cur);
            pos = start;
            last_cubic = None;
            last_quad = None;
            continue;
        }
        // A drawing command right after Z starts a new subpath at the old start.
        let sp = cur.get_or_insert_with(|| SubPath::new(pos));
        let s = match seg {
            PathSegment::LineTo { abs, x, y } => Seg::Line(rel(abs, x, y)),
            PathSegment::HorizontalLineTo { abs, x } => Seg::Line([if abs { x } else { pos[0] + x }, pos[1]]),
            PathSegment::VerticalLineTo { abs, y } => Seg::Line([pos[0], if abs { y } else { pos[1] + y }]),
            PathSegment::CurveTo { abs, x1, y1, x2, y2, x, y } => {
                let c2 = rel(abs, x2, y2);
                next_cubic = Some(c2);
                Seg::Cubic(rel(abs, x1, y1), c2, rel(abs, x, y))
            }
            PathSegment::SmoothCurveTo { abs, x2, y2, x, y } => {
                let c1 = last_cubic.map_or(pos, |c| [2.0 * pos[0] - c[0], 2.0 * pos[1] - c[1]]);
                let c2 = rel(abs, x2, y2);
                next_cubic = Some(c2);
                Seg::Cubic(c1, c2, rel(abs, x, y))
            }
            PathSegment::Quadratic { abs, x1, y1, x, y } => {
                let q = rel(abs, x1, y1);
                next_quad = Some(q);
                quad_to_cubic(pos, q, rel(abs, x, y))
            }
            PathSegment::SmoothQuadratic { abs, x, y } => {
                let q = last_quad.map_or(pos, |c| [2.0 * pos[0] - c[0], 2.0 * pos[1] - c[1]]);
                next_quad = Some(q);
                quad_to_cubic(pos, q, rel(abs, x, y))
            }
            PathSegment::EllipticalArc { abs, rx, ry, x_axis_rotation, large_arc, sweep, x, y } => {
                Seg::Arc { rx, ry, phi: x_axis_rotation, large: large_arc, sweep, to: rel(abs, x, y) }
            }
            PathSegment::MoveTo { .. } | PathSegment::ClosePath { .. } => unreachable!("handled above"),
        };
        pos = s.end();
        sp.segs.push(s);
        last_cubic = next_cubic;
        last_quad = next_quad;
    }
    flush(&mut subs, &mut cur);
    Ok(subs)
}

fn quad_to_cubic(p0: P, q: P, p: P) -> Seg {
    let c1 = [p0[0] + 2.0 / 3.0 * (q[0] - p0[0]), p0[1] + 2.0 / 3.0 * (q[1] - p0[1])];
    let c2 = [p[0] + 2.0 / 3.0 * (q[0] - p[0]), p[1] + 2.0 / 3.0 * (q[1] - p[1])];
    Seg::Cubic(c1, c2, p)
}

/// An elliptical arc in centre form (SVG 1.1 F.6.5), radii already corrected (F.6.6).
#[derive(Debug, Clone, Copy)]
struct CenterArc {
    c: P,
    rx: f64,
    ry: f64,
    /// x-axis rotation, radians.
    phi: f64,
    theta1: f64,
    /// Signed sweep, radians, in `[-2π, 2π]`.
    dtheta: f64,
}

impl CenterArc {
    fn point(&self, theta: f64) -> P {
        let (s, c) = self.phi.sin_cos();
        let (x, y) = (self.rx * theta.cos(), self.ry * theta.sin());
        [self.c[0] + c * x - s * y, self.c[1] + s * x + c * y]
    }
}

/// Endpoint → centre conversion of an SVG arc. `None` when the arc is degenerate (same end
/// points, which SVG omits, or a zero radius, which SVG draws as a line).
fn endpoint_to_center(p1: P, p2: P, rx: f64, ry: f64, phi_deg: f64, large: bool, sweep: bool) -> Option<CenterArc> {
    let (mut rx, mut ry) = (rx.abs(), ry.abs());
    if p1 == p2 || rx == 0.0 || ry == 0.0 {
        return None;
    }
    let phi = (phi_deg % 360.0).to_radians();
    let (sin, cos) = phi.sin_cos();
    let dx2 = (p1[0] - p2[0]) / 2.0;
    let dy2 = (p1[1] - p2[1]) / 2.0;
    let x1p = cos * dx2 + sin * dy2;
    let y1p = -sin * dx2 + cos * dy2;
    // F.6.6: scale up radii that cannot span the end points.
    let lambda = (x1p / rx).powi(2) + (y1p / ry).powi(2);
    if lambda > 1.0 {
        let s = lambda.sqrt();
        rx *= s;
        ry *= s;
    }
    // F.6.5.2, with the radicand written relative to the radii to avoid overflow. The square
    // root turns rounding in a radicand near 0 (end points a diameter apart, as in every half
    // circle) into an offset of the centre (1e-16 → 1e-8·r, and a half circle whose bulge is not
    // quite 1), so a radicand under 1e-14 (an offset under 1e-7·r) puts the centre on the chord.
    let (ux, uy) = (x1p / rx, y1p / ry);
    let den = ux * ux + uy * uy;
    let q = if den > 0.0 { (1.0 - den) / den } else { 0.0 };
    let mut coef = if q > 1e-14 { q.sqrt() } else { 0.0 };
    if large == sweep {
        coef = -coef;
    }
    let cxp = coef * rx * y1p / ry;
    let cyp = -coef * ry * x1p / rx;
    let c = [cos * cxp - sin * cyp + (p1[0] + p2[0]) / 2.0, sin * cxp + cos * cyp + (p1[1] + p2[1]) / 2.0];
    let u = [(x1p - cxp) / rx, (y1p - cyp) / ry];
    let v = [(-x1p - cxp) / rx, (-y1p - cyp) / ry];
    let theta1 = u[1].atan2(u[0]);
    let mut dtheta = (u[0] * v[1] - u[1] * v[0]).atan2(u[0] * v[0] + u[1] * v[1]);
    if !sweep && dtheta > 0.0 {
        dtheta -= TAU;
    } else if sweep && dtheta < 0.0 {
        dtheta += TAU;
    }
    Some(CenterArc { c, rx, ry, phi, theta1, dtheta })
}

/// `x` folded into `(-π, π]`.
fn wrap_pi(x: f64) -> f64 {
    x - TAU * (x / TAU).round()
}

/// The bulge of an arc of signed sweep `sweep` (radians), exact ±1 for half circles.
fn bulge_of(sweep: f64) -> f64 {
    if (sweep.abs() - PI).abs() < 1e-12 { sweep.signum() } else { (sweep / 4.0).tan() }
}

/// Appends points (not `p0`, ending with `p3`) of the cubic Bézier within `tol` of it.
fn flatten_cubic(p0: P, p1: P, p2: P, p3: P, tol: f64, out: &mut impl FnMut(P)) {
    let mut stack = vec![(p0, p1, p2, p3, 0u32)];
    while let Some((a, b, c, d, depth)) = stack.pop() {
        let d1 = [b[0] - (2.0 * a[0] + d[0]) / 3.0, b[1] - (2.0 * a[1] + d[1]) / 3.0];
        let d2 = [c[0] - (a[0] + 2.0 * d[0]) / 3.0, c[1] - (a[1] + 2.0 * d[1]) / 3.0];
        let bound = 0.75 * d1[0].hypot(d1[1]).max(d2[0].hypot(d2[1]));
        if bound <= tol || depth >= MAX_BEZIER_DEPTH || !bound.is_finite() {
            out(d);
            continue;
        }
        let mid = |p: P, q: P| [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0];
        let ab = mid(a, b);
        let bc = mid(b, c);
        let cd = mid(c, d);
        let abc = mid(ab, bc);
        let bcd = mid(bc, cd);
        let m = mid(abc, bcd);
        // second half below the first so the first is popped (and emitted) first
        stack.push((m, bcd, cd, d, depth + 1));
        stack.push((a, ab, abc, m, depth + 1));
    }
}

/// Builds a contour in output coordinates, dropping zero-length segments.
struct Builder {
    v: Vec<Vertex>,
    /// Vertices still allowed in the drawing; pushes beyond it are dropped and `full` is set.
    room: usize,
    full: bool,
}

impl Builder {
    fn last(&self) -> P {
        let v = self.v[self.v.len() - 1];
        [v.x, v.y]
    }

    fn has_room(&mut self) -> bool {
        if self.v.len() >= self.room {
            self.full = true;
        }
        !self.full
    }

    fn line_to(&mut self, p: P) {
        if dist(self.last(), p) > MERGE_EPS && self.has_room() {
            self.v.push(Vertex::new(p[0], p[1]));
        }
    }

    fn arc_to(&mut self, p: P, bulge: f64) {
        if dist(self.last(), p) > MERGE_EPS && self.has_room() {
            let n = self.v.len();
            self.v[n - 1].bulge = bulge;
            self.v.push(Vertex::new(p[0], p[1]));
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The document walk

#[derive(Debug, Clone)]
struct Ctx {
    /// Current user space → output millimetres (flip included).
    ctm: Affine,
    /// Nearest viewport size in current user units (for percentages).
    vp: [f64; 2],
    role: Role,
    /// A STOCK/PART/FIXTURE group is above: `layer` is its name and stays.
    role_fixed: bool,
    layer: String,
    /// Labels and ids of the groups above, outermost first (for [`ImportOptions::layers`]).
    groups: Vec<String>,
    visible: bool,
    /// ` via use id="…" (line n)` for instances.
    via: String,
}

struct OpenPiece {
    contour: Contour,
    origin: String,
    role: Role,
    layer: String,
}

struct Reader<'a, 'input> {
    file: &'a Path,
    doc: &'a Document<'input>,
    opts: &'a ImportOptions,
    /// User units per millimetre for lengths with absolute units (`mm`, `in`, …).
    abs_mm_to_user: f64,
    ids: HashMap<String, NodeId>,
    /// SVG user units (px) per inch.
    ppi: f64,
    use_stack: Vec<NodeId>,
    uses: usize,
    /// Vertices built so far.
    vertices: usize,
    /// The byte offset where each line of the file starts: a node's line and column by a
    /// binary search (roxmltree's `text_pos_at` scans from the start each time, which made a
    /// file of many elements quadratic).
    line_starts: Vec<usize>,
    /// The last position asked for (line index, byte offset, character column): nodes are
    /// asked for in document order, so a long line's columns are counted on from there.
    last_pos: std::cell::Cell<(usize, usize, usize)>,
    shapes: Vec<Shape>,
    /// Open contours left out ([`ImportOptions::skip_open`]).
    skipped: Vec<String>,
    /// Groups that held geometry (their layer names), in file order.
    layers: Vec<String>,
    open: Vec<OpenPiece>,
}

#[derive(Debug, Clone, Copy)]
enum Axis {
    X,
    Y,
    Other,
}

/// A root `width`/`height`.
enum RootLen {
    /// Absolute, in mm, with the unit it was written in.
    Abs(f64, Units),
    /// Unitless or px.
    Px(f64),
    /// Missing, percentage or font-relative.
    Missing,
}

fn is_svg_ns(n: Node) -> bool {
    matches!(n.tag_name().namespace(), None | Some(SVG_NS))
}

/// A presentation property: the last `style` declaration, else the attribute.
fn property<'a>(n: Node<'a, '_>, name: &str) -> Option<&'a str> {
    let mut found = None;
    if let Some(style) = n.attribute("style") {
        for decl in style.split(';') {
            if let Some((k, v)) = decl.split_once(':')
                && k.trim() == name
            {
                found = Some(v.trim().trim_end_matches("!important").trim());
            }
        }
    }
    found.or_else(|| n.attribute(name).map(str::trim))
}

fn display_none(n: Node) -> bool {
    property(n, "display") == Some("none")
}

fn visibility(n: Node) -> Option<bool> {
    match property(n, "visibility") {
        Some("hidden") | Some("collapse") => Some(false),
        Some("visible") => Some(true),
        _ => None,
    }
}

fn clip(s: &str) -> String {
    let s = s.trim();
    if s.chars().count() > 60 { format!("{}…", s.chars().take(60).collect::<String>()) } else { s.to_string() }
}

impl<'a, 'input> Reader<'a, 'input> {
    fn err(&self, place: impl Into<String>, reason: impl Into<String>) -> ImportError {
        ImportError::new(self.file, place, reason)
    }

    /// 1-based line and column (in characters) of a node's start.
    fn pos(&self, n: Node) -> (usize, usize) {
        let at = n.range().start;
        let i = self.line_starts.partition_point(|&s| s <= at).saturating_sub(1);
        let (li, from, col0) = self.last_pos.get();
        let (from, col0) = if li == i && from <= at { (from, col0) } else { (self.line_starts[i], 0) };
        let col = col0 + self.doc.input_text().get(from..at).map_or(at - from, |s| s.chars().count());
        self.last_pos.set((i, at, col));
        (i + 1, col + 1)
    }

    fn line(&self, n: Node) -> usize {
        self.pos(n).0
    }

    /// `path id="p1" (line 12)`.
    fn describe(&self, n: Node) -> String {
        let name = n.tag_name().name();
        match n.attribute("id") {
            Some(id) => format!("{name} id=\"{}\" (line {})", clip(id), self.line(n)),
            None => {
                let (row, col) = self.pos(n);
                format!("{name} (line {row}, column {col})")
            }
        }
    }

    fn attr_err(&self, n: Node, attr: &str, value: &str, why: impl std::fmt::Display) -> ImportError {
        self.err(self.describe(n), format!("attribute {attr}=\"{}\": {why}", clip(value)))
    }

    fn transform_attr(&self, n: Node, t: &str) -> Result<Affine, ImportError> {
        let ts = svgtypes::Transform::from_str(t)
            .map_err(|e| self.attr_err(n, "transform", t, format!("invalid transform: {e}")))?;
        let m = Affine { a: ts.a, b: ts.b, c: ts.c, d: ts.d, e: ts.e, f: ts.f };
        if !m.is_finite() {
            return Err(self.attr_err(n, "transform", t, "the transform is not finite"));
        }
        Ok(m)
    }

    fn length_to_user(&self, l: Length, axis: Axis, vp: [f64; 2]) -> f64 {
        let n = l.number;
        match l.unit {
            LengthUnit::None | LengthUnit::Px => n,
            LengthUnit::Mm => n * self.abs_mm_to_user,
            LengthUnit::Cm => n * 10.0 * self.abs_mm_to_user,
            LengthUnit::In => n * 25.4 * self.abs_mm_to_user,
            LengthUnit::Pt => n * 25.4 / 72.0 * self.abs_mm_to_user,
            LengthUnit::Pc => n * 25.4 / 6.0 * self.abs_mm_to_user,
            LengthUnit::Em => n * FONT_SIZE_PX,
            LengthUnit::Ex => n * FONT_SIZE_PX / 2.0,
            LengthUnit::Percent => {
                let base = match axis {
                    Axis::X => vp[0],
                    Axis::Y => vp[1],
                    Axis::Other => ((vp[0] * vp[0] + vp[1] * vp[1]) / 2.0).sqrt(),
                };
                n / 100.0 * base
            }
        }
    }

    /// A length attribute in user units; `None` when absent (or `auto`).
    fn len(&self, n: Node, attr: &str, axis: Axis, ctx: &Ctx) -> Result<Option<f64>, ImportError> {
        let Some(v) = n.attribute(attr) else { return Ok(None) };
        if v.trim() == "auto" {
            return Ok(None);
        }
        let l = Length::from_str(v.trim()).map_err(|e| self.attr_err(n, attr, v, format!("not a length: {e}")))?;
        let u = self.length_to_user(l, axis, ctx.vp);
        if !u.is_finite() {
            return Err(self.attr_err(n, attr, v, "not a finite number"));
        }
        Ok(Some(u))
    }

    /// A length that must not be negative.
    fn len_nonneg(&self, n: Node, attr: &str, axis: Axis, ctx: &Ctx) -> Result<Option<f64>, ImportError> {
        let v = self.len(n, attr, axis, ctx)?;
        if let Some(x) = v
            && x < 0.0
        {
            return Err(self.attr_err(n, attr, n.attribute(attr).unwrap_or(""), "must not be negative"));
        }
        Ok(v)
    }

    fn viewbox(&self, n: Node) -> Result<Option<ViewBox>, ImportError> {
        let Some(v) = n.attribute("viewBox") else { return Ok(None) };
        let vb = ViewBox::from_str(v).map_err(|e| self.attr_err(n, "viewBox", v, e))?;
        if ![vb.x, vb.y, vb.w, vb.h].iter().all(|x| x.is_finite()) {
            return Err(self.attr_err(n, "viewBox", v, "not finite"));
        }
        Ok(Some(vb))
    }

    fn aspect(&self, n: Node) -> Result<AspectRatio, ImportError> {
        match n.attribute("preserveAspectRatio") {
            None => Ok(AspectRatio::default()),
            Some(v) => AspectRatio::from_str(v).map_err(|e| self.attr_err(n, "preserveAspectRatio", v, e)),
        }
    }

    fn root_len(&self, n: Node, attr: &str) -> Result<RootLen, ImportError> {
        let Some(v) = n.attribute(attr) else { return Ok(RootLen::Missing) };
        if v.trim() == "auto" {
            return Ok(RootLen::Missing);
        }
        let l = Length::from_str(v.trim()).map_err(|e| self.attr_err(n, attr, v, format!("not a length: {e}")))?;
        if l.number < 0.0 {
            return Err(self.attr_err(n, attr, v, "must not be negative"));
        }
        if l.number == 0.0 {
            return Ok(RootLen::Missing);
        }
        let x = l.number;
        Ok(match l.unit {
            LengthUnit::None | LengthUnit::Px => RootLen::Px(x),
            LengthUnit::Mm => RootLen::Abs(x, Units::Millimetre),
            LengthUnit::Cm => RootLen::Abs(10.0 * x, Units::Centimetre),
            LengthUnit::In => RootLen::Abs(25.4 * x, Units::Inch),
            LengthUnit::Pt => RootLen::Abs(25.4 / 72.0 * x, Units::Millimetre),
            LengthUnit::Pc => RootLen::Abs(25.4 / 6.0 * x, Units::Millimetre),
            LengthUnit::Percent | LengthUnit::Em | LengthUnit::Ex => RootLen::Missing,
        })
    }

    /// The root user space → output mm (Y flipped about the page bottom), the root viewport in
    /// user units, the drawing's units, where they came from and whether they are a guess.
    fn root_mapping(&self, root: Node) -> Result<(Affine, [f64; 2], Units, String, bool), ImportError> {
        let px_mm = 25.4 / self.ppi;
        let w = self.root_len(root, "width")?;
        let h = self.root_len(root, "height")?;
        let vb = self.viewbox(root)?;
        let par = self.aspect(root)?;
        let mm = |l: &RootLen| match *l {
            RootLen::Abs(v, _) => Some(v),
            RootLen::Px(v) => Some(v * px_mm),
            RootLen::Missing => None,
        };
        let file_units = match (&w, &h) {
            (RootLen::Abs(_, u), _) | (_, RootLen::Abs(_, u)) => *u,
            _ => Units::Millimetre,
        };
        let flip = |height: f64| Affine { a: 1.0, b: 0.0, c: 0.0, d: -1.0, e: 0.0, f: height };
        let (map, vp) = match (self.opts.units, vb) {
            (Some(u), Some(vb)) => {
                let k = u.mm();
                (
                    flip(k * vb.h).mul(viewbox_map(vb, AspectRatio { align: Align::None, ..par }, k * vb.w, k * vb.h)),
                    [vb.w, vb.h],
                )
            }
            (Some(u), None) => {
                let k = u.mm();
                let user = |l: &RootLen| match *l {
                    RootLen::Px(v) => Some(v),
                    RootLen::Abs(v, _) => Some(v / k),
                    RootLen::Missing => None,
                };
                let hu = user(&h).unwrap_or(0.0);
                let wu = user(&w).unwrap_or(0.0);
                (Affine { a: k, b: 0.0, c: 0.0, d: -k, e: 0.0, f: k * hu }, [wu, hu])
            }
            (None, Some(vb)) => {
                let (wm, hm) = match (mm(&w), mm(&h)) {
                    (Some(wm), Some(hm)) => (wm, hm),
                    (Some(wm), None) => (wm, wm * vb.h / vb.w),
                    (None, Some(hm)) => (hm * vb.w / vb.h, hm),
                    (None, None) => (vb.w * px_mm, vb.h * px_mm),
                };
                (flip(hm).mul(viewbox_map(vb, par, wm, hm)), [vb.w, vb.h])
            }
            (None, None) => {
                let hm = mm(&h).unwrap_or(0.0);
                let wm = mm(&w).unwrap_or(0.0);
                (Affine { a: px_mm, b: 0.0, c: 0.0, d: -px_mm, e: 0.0, f: hm }, [wm / px_mm, hm / px_mm])
            }
        };
        if !map.is_finite() || map.det() == 0.0 {
            return Err(self.err(self.describe(root), "the page size and viewBox give no usable scale"));
        }
        let abs = matches!(w, RootLen::Abs(..)) || matches!(h, RootLen::Abs(..));
        let writer = if legacy_inkscape(root) { ", as Inkscape before 0.92 drew" } else { "" };
        let (from, assumed) = match (self.opts.units, vb.is_some() && abs) {
            (Some(_), _) => ("given".to_string(), false),
            (None, true) => ("the page's width and height with its viewBox".to_string(), false),
            (None, false) => (format!("user units as pixels at {} per inch{writer}", self.ppi), true),
        };
        Ok((map, vp, self.opts.units.unwrap_or(file_units), from, assumed))
    }

    fn children(&mut self, n: Node, ctx: &Ctx, depth: usize) -> Result<(), ImportError> {
        for c in n.children().filter(Node::is_element) {
            self.element(c, ctx, depth + 1)?;
        }
        Ok(())
    }

    fn element(&mut self, n: Node, ctx: &Ctx, depth: usize) -> Result<(), ImportError> {
        if !is_svg_ns(n) {
            return Ok(());
        }
        if depth > MAX_DEPTH {
            return Err(self.err(self.describe(n), format!("elements nested deeper than {MAX_DEPTH} levels")));
        }
        enum Kind {
            Group,
            Switch,
            Svg,
            Use,
            Shape,
        }
        let kind = match n.tag_name().name() {
            "g" | "a" => Kind::Group,
            "switch" => Kind::Switch,
            "svg" => Kind::Svg,
            "use" => Kind::Use,
            "path" | "rect" | "circle" | "ellipse" | "line" | "polyline" | "polygon" => Kind::Shape,
            _ => return Ok(()),
        };
        if display_none(n) {
            return Ok(());
        }
        let mut ctx = ctx.clone();
        if let Some(v) = visibility(n) {
            ctx.visible = v;
        }
        if let Some(t) = n.attribute("transform") {
            ctx.ctm = ctx.ctm.mul(self.transform_attr(n, t)?);
        }
        if !ctx.ctm.is_finite() {
            return Err(self.err(self.describe(n), "the composed transform overflows"));
        }
        if ctx.ctm.det() == 0.0 {
            return Ok(()); // scale(0) and the like: nothing is drawn
        }
        match kind {
            Kind::Group => {
                if n.tag_name().name() == "g" {
                    enter_group(n, &mut ctx);
                }
                self.children(n, &ctx, depth)
            }
            // The first child we can render: we support no extensions, so skip `foreignObject`
            // and children that require one (Illustrator puts its private data there first).
            Kind::Switch => match n.children().find(|c| {
                c.is_element()
                    && is_svg_ns(*c)
                    && c.tag_name().name() != "foreignObject"
                    && c.attribute("requiredExtensions").is_none_or(|e| e.trim().is_empty())
            }) {
                Some(c) => self.element(c, &ctx, depth + 1),
                None => Ok(()),
            },
            Kind::Svg => self.nested_svg(n, ctx, depth),
            Kind::Use => self.use_element(n, ctx, depth),
            Kind::Shape if ctx.visible => self.shape(n, &ctx),
            Kind::Shape => Ok(()),
        }
    }

    fn nested_svg(&mut self, n: Node, mut ctx: Ctx, depth: usize) -> Result<(), ImportError> {
        let x = self.len(n, "x", Axis::X, &ctx)?.unwrap_or(0.0);
        let y = self.len(n, "y", Axis::Y, &ctx)?.unwrap_or(0.0);
        let w = self.len_nonneg(n, "width", Axis::X, &ctx)?.unwrap_or(ctx.vp[0]);
        let h = self.len_nonneg(n, "height", Axis::Y, &ctx)?.unwrap_or(ctx.vp[1]);
        if self.viewport(n, &mut ctx, [x, y], [w, h])? { self.children(n, &ctx, depth) } else { Ok(()) }
    }

    /// Enters a new viewport at `at` of `size`, with the `viewBox` and `preserveAspectRatio` of
    /// `vb_node`. `false` when nothing in it can be drawn (an empty viewport).
    fn viewport(&self, vb_node: Node, ctx: &mut Ctx, at: P, size: [f64; 2]) -> Result<bool, ImportError> {
        if size[0] <= 0.0 || size[1] <= 0.0 {
            return Ok(false);
        }
        ctx.ctm = ctx.ctm.mul(Affine::translate(at[0], at[1]));
        match self.viewbox(vb_node)? {
            Some(vb) => {
                let par = self.aspect(vb_node)?;
                ctx.ctm = ctx.ctm.mul(viewbox_map(vb, par, size[0], size[1]));
                ctx.vp = [vb.w, vb.h];
            }
            None => ctx.vp = size,
        }
        Ok(ctx.ctm.is_finite() && ctx.ctm.det() != 0.0)
    }

    fn use_element(&mut self, n: Node, mut ctx: Ctx, depth: usize) -> Result<(), ImportError> {
        let Some(href) = n.attribute((XLINK_NS, "href")).or_else(|| n.attribute("href")) else { return Ok(()) };
        let Some(id) = href.trim().strip_prefix('#') else {
            return Err(self.attr_err(n, "href", href, "only references into the same file (#id) are supported"));
        };
        let Some(&target_id) = self.ids.get(id) else {
            return Err(self.attr_err(n, "href", href, "no element has this id"));
        };
        if self.use_stack.contains(&target_id) {
            return Err(self.attr_err(n, "href", href, "the reference loops back on itself"));
        }
        self.uses += 1;
        if self.uses > MAX_USES {
            return Err(
                self.err(self.describe(n), format!("more than {MAX_USES} use instances: refusing to expand further"))
            );
        }
        let Some(target) = self.doc.get_node(target_id) else { return Ok(()) };
        let x = self.len(n, "x", Axis::X, &ctx)?.unwrap_or(0.0);
        let y = self.len(n, "y", Axis::Y, &ctx)?.unwrap_or(0.0);
        ctx.via = format!(" via {}{}", self.describe(n), ctx.via);
        self.use_stack.push(target_id);
        let result = if target.tag_name().name() == "symbol" && is_svg_ns(target) {
            if display_none(target) {
                Ok(())
            } else {
                let w = self.len_nonneg(n, "width", Axis::X, &ctx)?.unwrap_or(ctx.vp[0]);
                let h = self.len_nonneg(n, "height", Axis::Y, &ctx)?.unwrap_or(ctx.vp[1]);
                if let Some(v) = visibility(target) {
                    ctx.visible = v;
                }
                if self.viewport(target, &mut ctx, [x, y], [w, h])? {
                    self.children(target, &ctx, depth + 1)
                } else {
                    Ok(())
                }
            }
        } else {
            ctx.ctm = ctx.ctm.mul(Affine::translate(x, y));
            self.element(target, &ctx, depth + 1)
        };
        self.use_stack.pop();
        result
    }

    fn shape(&mut self, n: Node, ctx: &Ctx) -> Result<(), ImportError> {
        let subs = self.geometry(n, ctx)?;
        let base = self.describe(n);
        let many = subs.len() > 1;
        for (i, sp) in subs.iter().enumerate() {
            let origin =
                if many { format!("{base}, subpath {}{}", i + 1, ctx.via) } else { format!("{base}{}", ctx.via) };
            let Some(contour) = self.build(sp, &ctx.ctm) else {
                return Err(self.err(
                    origin,
                    format!(
                        "the drawing needs more than {MAX_VERTICES} vertices at a flatten tolerance of {} mm \
                         (is its scale right?)",
                        self.opts.flatten_tolerance
                    ),
                ));
            };
            self.vertices += contour.vertices.len();
            if !contour.is_finite() {
                return Err(self.err(origin, "the coordinates overflow (not finite after the transforms)"));
            }
            if !self.layers.contains(&ctx.layer) {
                self.layers.push(ctx.layer.clone());
            }
            if !self.opts.reads_layer(ctx.groups.iter().map(String::as_str)) {
                continue;
            }
            if contour.closed {
                if contour.vertices.len() >= 2 && contour.signed_area().abs() >= MIN_AREA {
                    self.shapes.push(Shape { contour, role: ctx.role, layer: ctx.layer.clone(), origin });
                }
            } else if contour.vertices.len() >= 2 {
                self.open.push(OpenPiece { contour, origin, role: ctx.role, layer: ctx.layer.clone() });
            }
        }
        Ok(())
    }

    /// The element's subpaths in its user space.
    fn geometry(&self, n: Node, ctx: &Ctx) -> Result<Vec<SubPath>, ImportError> {
        let num =
            |attr: &str, axis: Axis| -> Result<f64, ImportError> { Ok(self.len(n, attr, axis, ctx)?.unwrap_or(0.0)) };
        Ok(match n.tag_name().name() {
            "path" => match n.attribute("d") {
                Some(d) => parse_path(d).map_err(|e| self.attr_err(n, "d", d, e))?,
                None => Vec::new(),
            },
            "rect" => {
                let (x, y) = (num("x", Axis::X)?, num("y", Axis::Y)?);
                let w = self.len_nonneg(n, "width", Axis::X, ctx)?.unwrap_or(0.0);
                let h = self.len_nonneg(n, "height", Axis::Y, ctx)?.unwrap_or(0.0);
                let rx = self.len_nonneg(n, "rx", Axis::X, ctx)?;
                let ry = self.len_nonneg(n, "ry", Axis::Y, ctx)?;
                if w == 0.0 || h == 0.0 {
                    return Ok(Vec::new());
                }
                let (rx, ry) = match (rx, ry) {
                    (None, None) => (0.0, 0.0),
                    (Some(r), None) | (None, Some(r)) => (r, r),
                    (Some(a), Some(b)) => (a, b),
                };
                vec![rect_path(x, y, w, h, rx.min(w / 2.0), ry.min(h / 2.0))]
            }
            "circle" => {
                let (cx, cy) = (num("cx", Axis::X)?, num("cy", Axis::Y)?);
                let r = self.len_nonneg(n, "r", Axis::Other, ctx)?.unwrap_or(0.0);
                if r == 0.0 { Vec::new() } else { vec![ellipse_path(cx, cy, r, r)] }
            }
            "ellipse" => {
                let (cx, cy) = (num("cx", Axis::X)?, num("cy", Axis::Y)?);
                let rx = self.len_nonneg(n, "rx", Axis::X, ctx)?;
                let ry = self.len_nonneg(n, "ry", Axis::Y, ctx)?;
                let (rx, ry) = match (rx, ry) {
                    (Some(a), Some(b)) => (a, b),
                    (Some(r), None) | (None, Some(r)) => (r, r),
                    (None, None) => (0.0, 0.0),
                };
                if rx == 0.0 || ry == 0.0 { Vec::new() } else { vec![ellipse_path(cx, cy, rx, ry)] }
            }
            "line" => {
                let a = [num("x1", Axis::X)?, num("y1", Axis::Y)?];
                let b = [num("x2", Axis::X)?, num("y2", Axis::Y)?];
                vec![SubPath::polygon(&[a, b], false)]
            }
            "polyline" | "polygon" => {
                let pts = self.points(n)?;
                if pts.is_empty() { Vec::new() } else { vec![SubPath::polygon(&pts, n.tag_name().name() == "polygon")] }
            }
            _ => Vec::new(),
        })
    }

    fn points(&self, n: Node) -> Result<Vec<P>, ImportError> {
        let Some(v) = n.attribute("points") else { return Ok(Vec::new()) };
        let mut nums = Vec::new();
        for x in svgtypes::NumberListParser::from(v) {
            nums.push(x.map_err(|e| self.attr_err(n, "points", v, format!("invalid number: {e}")))?);
        }
        if nums.len() % 2 != 0 {
            return Err(self.attr_err(n, "points", v, format!("odd number of coordinates ({})", nums.len())));
        }
        Ok(nums.chunks_exact(2).map(|c| [c[0], c[1]]).collect())
    }

    /// The subpath in output millimetres: closed when it has `Z` or its ends meet within the
    /// chain tolerance.
    fn build(&self, sp: &SubPath, m: &Affine) -> Option<Contour> {
        let tol = self.opts.flatten_tolerance;
        let p = m.apply(sp.start);
        let mut b =
            Builder { v: vec![Vertex::new(p[0], p[1])], room: MAX_VERTICES.saturating_sub(self.vertices), full: false };
        let mut cur = sp.start;
        for seg in &sp.segs {
            match *seg {
                Seg::Line(p) => b.line_to(m.apply(p)),
                Seg::Cubic(c1, c2, p) => {
                    flatten_cubic(m.apply(cur), m.apply(c1), m.apply(c2), m.apply(p), tol, &mut |q| b.line_to(q));
                }
                Seg::Arc { rx, ry, phi, large, sweep, to } => self.arc(&mut b, m, cur, rx, ry, phi, large, sweep, to),
            }
            cur = seg.end();
        }
        if b.full {
            return None;
        }
        let mut v = b.v;
        let gap = |v: &[Vertex]| dist([v[0].x, v[0].y], [v[v.len() - 1].x, v[v.len() - 1].y]);
        let closed = if sp.closed {
            if v.len() >= 2 && gap(&v) <= Z_SNAP {
                v.pop();
            }
            true
        } else if v.len() >= 3 && gap(&v) <= self.opts.chain_tolerance {
            v.pop();
            true
        } else {
            false
        };
        Some(Contour { vertices: v, closed })
    }

    #[allow(clippy::too_many_arguments)]
    fn arc(&self, b: &mut Builder, m: &Affine, p0: P, rx: f64, ry: f64, phi: f64, large: bool, sweep: bool, p1: P) {
        if p0 == p1 {
            return; // SVG omits an arc to its own start point
        }
        let Some(ea) = endpoint_to_center(p0, p1, rx, ry, phi, large, sweep) else {
            b.line_to(m.apply(p1));
            return;
        };
        let tol = self.opts.flatten_tolerance;
        let (sin, cos) = ea.phi.sin_cos();
        let l = m.mul(Affine { a: cos * ea.rx, b: sin * ea.rx, c: -sin * ea.ry, d: cos * ea.ry, e: 0.0, f: 0.0 });
        let (s1, s2) = l.singular_values();
        let a_out = m.apply(p0);
        let b_out = m.apply(p1);
        if s1 - s2 <= 0.5 * tol {
            // A circle in the output: exact bulge arcs.
            let c = m.apply(ea.c);
            let dir = if m.det() < 0.0 { -1.0 } else { 1.0 };
            let a0 = (a_out[1] - c[1]).atan2(a_out[0] - c[0]);
            let a1 = (b_out[1] - c[1]).atan2(b_out[0] - c[0]);
            let mut sw = ea.dtheta * dir;
            sw += wrap_pi((a1 - a0) - sw);
            let n = if sw.abs() > PI * (1.0 + 1e-9) { 2 } else { 1 };
            let r = (dist(a_out, c) + dist(b_out, c)) / 2.0;
            for k in 1..=n {
                let q = if k == n {
                    b_out
                } else {
                    let t = a0 + sw * k as f64 / n as f64;
                    [c[0] + r * t.cos(), c[1] + r * t.sin()]
                };
                b.arc_to(q, bulge_of(sw / n as f64));
            }
        } else {
            let step = (8.0 * tol / s1).sqrt();
            let steps = (ea.dtheta.abs() / step).ceil();
            let steps = if steps.is_finite() { (steps as usize).clamp(1, MAX_ARC_STEPS) } else { MAX_ARC_STEPS };
            for k in 1..steps {
                let t = ea.theta1 + ea.dtheta * k as f64 / steps as f64;
                b.line_to(m.apply(ea.point(t)));
            }
            b.line_to(b_out);
        }
    }

    /// Chains the open subpaths; any that stays open is an error.
    fn close_open_pieces(&mut self) -> Result<(), ImportError> {
        if self.open.is_empty() {
            return Ok(());
        }
        let pieces = std::mem::take(&mut self.open);
        let (closed, report, each) = chain_pieces(pieces, self.opts.chain_tolerance);
        if self.opts.skip_open {
            self.skipped = each;
        } else if let Some((place, reason)) = report {
            return Err(self.err(place, reason));
        }
        for s in closed {
            if s.contour.vertices.len() >= 2 && s.contour.signed_area().abs() >= MIN_AREA && s.contour.is_finite() {
                self.shapes.push(s);
            }
        }
        Ok(())
    }
}

/// Updates role and layer on entering a `g`.
fn enter_group(n: Node, ctx: &mut Ctx) {
    let label = n.attribute((INKSCAPE_NS, "label"));
    let id = n.attribute("id");
    ctx.groups.extend([label, id].into_iter().flatten().map(str::to_string));
    for name in [label, id].into_iter().flatten() {
        let role = Role::from_layer_name(name);
        if role != Role::Auto {
            ctx.role = role;
            ctx.layer = name.trim().to_string();
            ctx.role_fixed = true;
            return;
        }
    }
    if !ctx.role_fixed
        && let Some(name) = label.or(id)
    {
        ctx.layer = name.to_string();
    }
}

fn rect_path(x: f64, y: f64, w: f64, h: f64, rx: f64, ry: f64) -> SubPath {
    if rx <= 0.0 || ry <= 0.0 {
        return SubPath::polygon(&[[x, y], [x + w, y], [x + w, y + h], [x, y + h]], true);
    }
    let arc = |to: P| Seg::Arc { rx, ry, phi: 0.0, large: false, sweep: true, to };
    let mut sp = SubPath::new([x + rx, y]);
    sp.segs = vec![
        Seg::Line([x + w - rx, y]),
        arc([x + w, y + ry]),
        Seg::Line([x + w, y + h - ry]),
        arc([x + w - rx, y + h]),
        Seg::Line([x + rx, y + h]),
        arc([x, y + h - ry]),
        Seg::Line([x, y + ry]),
        arc([x + rx, y]),
    ];
    sp.closed = true;
    sp
}

fn ellipse_path(cx: f64, cy: f64, rx: f64, ry: f64) -> SubPath {
    let arc = |to: P| Seg::Arc { rx, ry, phi: 0.0, large: false, sweep: true, to };
    let mut sp = SubPath::new([cx + rx, cy]);
    sp.segs = vec![arc([cx - rx, cy]), arc([cx + rx, cy])];
    sp.closed = true;
    sp
}

/// The closed shapes, the error's place and reason when some outline stays open, and a line for
/// each chain left open.
type Chaining = (Vec<Shape>, Option<(String, String)>, Vec<String>);

/// Joins open pieces end to end with [`crate::chain::chain`].
fn chain_pieces(pieces: Vec<OpenPiece>, tol: f64) -> Chaining {
    let mut roles: HashMap<String, (Role, String)> = HashMap::new();
    let mut input = Vec::with_capacity(pieces.len());
    for p in pieces {
        roles.entry(p.origin.clone()).or_insert((p.role, p.layer));
        input.push(Piece { contour: p.contour, origin: p.origin });
    }
    let chained = chain(input, tol);
    let shapes = chained
        .closed
        .into_iter()
        .map(|(contour, origins)| {
            let (role, layer) =
                origins.first().and_then(|o| roles.get(o)).cloned().unwrap_or((Role::Auto, String::new()));
            let mut names: Vec<&str> = Vec::new();
            for o in &origins {
                if !names.contains(&o.as_str()) {
                    names.push(o);
                }
            }
            Shape { contour, role, layer, origin: names.join(" + ") }
        })
        .collect();
    let report = open_contour_message(&chained.open).map(|(near, reason)| {
        let smallest = chained.open.iter().flat_map(|c| c.gaps.iter()).min_by(|a, b| a.distance.total_cmp(&b.distance));
        let place = match (smallest, chained.open.first()) {
            (Some(g), _) => g.origin_a.clone(),
            (None, Some(c)) => c.origins.first().cloned().unwrap_or(near),
            (None, None) => near,
        };
        (
            place,
            format!(
                "{reason}. A pocket outline must be closed: close the path (Z), delete or hide \
                 (display:none) open strokes such as construction lines, or skip open contours \
                 (--skip-open) to cut the rest"
            ),
        )
    });
    let each = chained.open.iter().map(crate::chain::OpenChain::describe).collect();
    (shapes, report, each)
}
