//! Pictures like the papers' figures: on the left the XY path coloured by tool engagement over
//! the part (dark) and the stock outline, rapids dotted, plunges and gouges marked; on the right
//! engagement against cutting length with the reference and the bound. Written as SVG, and as
//! PNG by rendering that SVG with resvg. [`heights`] draws the stock seen from above from a
//! simulator's heights.

use crate::error::{Error, Result};
use crate::geom::{Area, DVec2};
use crate::sim::{Replay, SampleKind};
use crate::toolpath::{Motion, Toolpath};
use std::fmt::Write;

pub mod heights;
pub mod shape;

/// What to draw.
pub struct Figure<'a> {
    /// Title line.
    pub title: String,
    /// Part (dark).
    pub part: &'a Area,
    /// Stock outline.
    pub stock: &'a Area,
    /// Fixtures (red).
    pub fixtures: &'a Area,
    /// The program.
    pub toolpath: &'a Toolpath,
    /// Its simulation.
    pub replay: &'a Replay,
    /// Reference engagement, degrees.
    pub ref_deg: f64,
}

/// Engagement colour: grey for air, then blue → cyan → yellow → orange → red up to 180°.
pub fn tea_color(t: f64) -> (u8, u8, u8) {
    if t <= 0.0 {
        return (190, 190, 190);
    }
    let stops: [(f64, (f64, f64, f64)); 6] = [
        (0.0, (44.0, 80.0, 200.0)),
        (40.0, (40.0, 170.0, 220.0)),
        (80.0, (110.0, 200.0, 90.0)),
        (110.0, (250.0, 210.0, 50.0)),
        (140.0, (245.0, 120.0, 40.0)),
        (180.0, (200.0, 20.0, 30.0)),
    ];
    let t = t.min(180.0);
    for w in stops.windows(2) {
        let (a, ca) = w[0];
        let (b, cb) = w[1];
        if t <= b {
            let u = (t - a) / (b - a);
            let m = |x: f64, y: f64| (x + (y - x) * u).round() as u8;
            return (m(ca.0, cb.0), m(ca.1, cb.1), m(ca.2, cb.2));
        }
    }
    (200, 20, 30)
}

fn hex(c: (u8, u8, u8)) -> String {
    format!("#{:02x}{:02x}{:02x}", c.0, c.1, c.2)
}

fn area_path(a: &Area, map: &dyn Fn(DVec2) -> (f64, f64)) -> String {
    let mut d = String::new();
    for ring in a.rings() {
        for (i, p) in ring.iter().enumerate() {
            let (x, y) = map(*p);
            let _ = write!(d, "{}{:.2},{:.2} ", if i == 0 { "M" } else { "L" }, x, y);
        }
        d.push_str("Z ");
    }
    d
}

/// The figure as an SVG document.
pub fn svg(f: &Figure) -> String {
    let (w, h) = (1500.0, 640.0);
    let (lw, top, bottom) = (760.0, 60.0, 590.0);
    // world bounds: stock and path
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    if let Some((a, b)) = f.stock.bounds() {
        lo = lo.min(a);
        hi = hi.max(b);
    }
    for (from, m) in f.toolpath.segments() {
        if !m.is_rapid() {
            lo = lo.min(from.truncate()).min(m.to.truncate());
            hi = hi.max(from.truncate()).max(m.to.truncate());
        }
    }
    if !lo.is_finite() {
        lo = DVec2::ZERO;
        hi = DVec2::ONE;
    }
    let pad = (hi - lo).max_element() * 0.04 + f.toolpath.tool.radius();
    lo -= DVec2::splat(pad);
    hi += DVec2::splat(pad);
    let sx = (lw - 40.0) / (hi.x - lo.x);
    let sy = (bottom - top) / (hi.y - lo.y);
    let s = sx.min(sy);
    let ox = 20.0 + ((lw - 40.0) - s * (hi.x - lo.x)) / 2.0;
    let oy = top + ((bottom - top) - s * (hi.y - lo.y)) / 2.0;
    let map = |p: DVec2| (ox + (p.x - lo.x) * s, oy + (hi.y - p.y) * s);
    let clip = Area::rect(lo.x, lo.y, hi.x, hi.y);
    let mut o = String::new();
    let _ = writeln!(
        o,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="DejaVu Sans, Arial, sans-serif">"#
    );
    let _ = writeln!(o, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = writeln!(o, r#"<text x="20" y="30" font-size="18">{}</text>"#, xml(&f.title));
    // part, fixtures, stock
    let part = f.part.intersection(&clip);
    let _ = writeln!(o, r##"<path d="{}" fill="#3a3a3a" fill-rule="evenodd"/>"##, area_path(&part, &map));
    let fx = f.fixtures.intersection(&clip);
    if !fx.is_empty() {
        let _ = writeln!(
            o,
            r##"<path d="{}" fill="#b03030" fill-opacity="0.7" fill-rule="evenodd"/>"##,
            area_path(&fx, &map)
        );
    }
    let _ = writeln!(
        o,
        r##"<path d="{}" fill="none" stroke="#000" stroke-width="1.2" fill-rule="evenodd"/>"##,
        area_path(f.stock, &map)
    );
    // rapids dotted
    let mut d = String::new();
    for (from, m) in f.toolpath.segments() {
        if m.is_rapid() && (m.to.truncate() - from.truncate()).length() > 1e-6 {
            let (a, b) = (map(from.truncate()), map(m.to.truncate()));
            let _ = write!(d, "M{:.2},{:.2} L{:.2},{:.2} ", a.0, a.1, b.0, b.1);
        }
    }
    let _ = writeln!(o, r##"<path d="{d}" fill="none" stroke="#555" stroke-width="0.8" stroke-dasharray="2,3"/>"##);
    // cutting path coloured by engagement: runs of samples of one colour bucket
    let samples = &f.replay.samples;
    let mut i = 0;
    let width = (f.toolpath.tool.diameter * s * 0.08).clamp(0.6, 2.5);
    while i < samples.len() {
        let bucket = |t: f32| if t <= 0.0 { -1 } else { (t / 10.0) as i32 };
        let b0 = bucket(samples[i].tea);
        let mut j = i;
        let start = if i > 0 && samples[i - 1].mi == samples[i].mi { samples[i - 1].at } else { samples[i].at };
        let mut run = vec![DVec2::from(map(start.truncate()))];
        while j < samples.len()
            && bucket(samples[j].tea) == b0
            && (j == i || samples[j].mi.abs_diff(samples[j - 1].mi) <= 1)
        {
            run.push(DVec2::from(map(samples[j].at.truncate())));
            j += 1;
        }
        // a third of a pixel is invisible: keep the file small
        let run = crate::geom::simplify::douglas_peucker(&run, 0.3);
        let mut d = String::new();
        for (k, p) in run.iter().enumerate() {
            let _ = write!(d, "{}{:.1},{:.1}", if k == 0 { "M" } else { " L" }, p.x, p.y);
        }
        let tea = if b0 < 0 { 0.0 } else { b0 as f64 * 10.0 + 5.0 };
        let _ = writeln!(
            o,
            r#"<path d="{d}" fill="none" stroke="{}" stroke-width="{width:.2}" stroke-linejoin="round"/>"#,
            hex(tea_color(tea))
        );
        i = j.max(i + 1);
    }
    // rest material: reachable material left standing
    if !f.replay.rest_cells.is_empty() {
        let side = (f.replay.res * s).max(1.0);
        let mut d = String::new();
        for c in f.replay.rest_cells.iter().take(200_000) {
            let (x, y) = map(*c);
            let _ = write!(d, "M{:.1},{:.1}h{side:.1}v{side:.1}h-{side:.1}z", x - side / 2.0, y - side / 2.0);
        }
        let _ = writeln!(o, r##"<path d="{d}" fill="#e00000"/>"##);
    }
    // start marker: circle of the tool at the first cutting point
    if let Some(first) = samples.first() {
        let p = map(first.at.truncate());
        let _ = writeln!(
            o,
            r##"<circle cx="{:.2}" cy="{:.2}" r="{:.2}" fill="none" stroke="#222" stroke-width="1"/>"##,
            p.0,
            p.1,
            f.toolpath.tool.radius() * s
        );
    }
    for pl in &f.replay.plunges {
        let p = map(DVec2::new(pl.at[0], pl.at[1]));
        let _ = writeln!(o, r##"<path d="M{:.1},{:.1} l-6,-9 h12 z" fill="#d00"/>"##, p.0, p.1 + 4.0);
    }
    for g in &f.replay.gouges {
        let p = map(DVec2::new(g.at[0], g.at[1]));
        let _ = writeln!(
            o,
            r##"<path d="M{:.1},{:.1} l10,10 m0,-10 l-10,10" stroke="#f00" stroke-width="2.5"/>"##,
            p.0 - 5.0,
            p.1 - 5.0
        );
    }
    // right panel: engagement against cutting length
    let (px0, px1, py0, py1) = (840.0, 1470.0, 80.0, 560.0);
    let total = samples.last().map_or(1.0, |s| s.s).max(1e-9);
    let ymap = |t: f64| py1 - (t.clamp(0.0, 200.0) / 200.0) * (py1 - py0);
    let xmap = |l: f64| px0 + l / total * (px1 - px0);
    let _ = writeln!(
        o,
        r##"<rect x="{px0}" y="{py0}" width="{}" height="{}" fill="none" stroke="#000"/>"##,
        px1 - px0,
        py1 - py0
    );
    for t in [0.0, 45.0, 90.0, 135.0, 180.0] {
        let y = ymap(t);
        let _ = writeln!(
            o,
            r##"<line x1="{px0}" x2="{px1}" y1="{y:.1}" y2="{y:.1}" stroke="#ddd"/><text x="{}" y="{:.1}" font-size="12" text-anchor="end">{t}°</text>"##,
            px0 - 6.0,
            y + 4.0
        );
    }
    for (t, dash, label) in [(f.ref_deg, "", "reference"), (f.ref_deg + 20.0, "6,4", "reference + 20°")] {
        let y = ymap(t);
        let _ = writeln!(
            o,
            r##"<line x1="{px0}" x2="{px1}" y1="{y:.1}" y2="{y:.1}" stroke="#1a7f37" stroke-width="1.2" stroke-dasharray="{dash}"/><text x="{}" y="{:.1}" font-size="11" fill="#1a7f37" text-anchor="end">{label}</text>"##,
            px1 - 4.0,
            y - 4.0
        );
    }
    // engagement curve, reduced to at most ~3000 columns of min/max
    let cols = 1500usize;
    let mut colv: Vec<Option<(f64, f64)>> = vec![None; cols];
    for sm in samples.iter().filter(|s| s.kind != SampleKind::Plunge || s.tea > 0.0) {
        let c = ((sm.s / total) * (cols - 1) as f64) as usize;
        let t = sm.tea as f64;
        colv[c.min(cols - 1)] = Some(colv[c.min(cols - 1)].map_or((t, t), |(a, b)| (a.min(t), b.max(t))));
    }
    let mut d = String::new();
    let mut first = true;
    for (c, v) in colv.iter().enumerate() {
        if let Some((a, b)) = v {
            let x = xmap(total * c as f64 / (cols - 1) as f64);
            let _ = write!(d, "{}{:.2},{:.2} L{:.2},{:.2} ", if first { "M" } else { "L" }, x, ymap(*a), x, ymap(*b));
            first = false;
        }
    }
    let _ = writeln!(o, r##"<path d="{d}" fill="none" stroke="#1f4e9c" stroke-width="0.8"/>"##);
    let _ = writeln!(
        o,
        r#"<text x="{}" y="{}" font-size="13" text-anchor="middle">cutting length (mm), total {:.0}</text>"#,
        (px0 + px1) / 2.0,
        py1 + 32.0,
        total
    );
    let _ = writeln!(
        o,
        r#"<text x="{}" y="{}" font-size="13" transform="rotate(-90 {} {})" text-anchor="middle">engagement (°)</text>"#,
        px0 - 44.0,
        (py0 + py1) / 2.0,
        px0 - 44.0,
        (py0 + py1) / 2.0
    );
    // colour key
    for k in 0..18 {
        let t = k as f64 * 10.0 + 5.0;
        let _ = writeln!(
            o,
            r#"<rect x="{}" y="610" width="24" height="10" fill="{}"/>"#,
            20.0 + k as f64 * 24.0,
            hex(tea_color(t))
        );
    }
    let _ = writeln!(
        o,
        r#"<text x="20" y="634" font-size="11">0°</text><text x="452" y="634" font-size="11" text-anchor="end">180°</text><text x="470" y="620" font-size="11">engagement; grey: no engagement; dotted: rapids; red: material left</text>"#
    );
    let arcs = f.toolpath.moves.iter().filter(|m| matches!(m.motion, Motion::Arc { .. })).count();
    let _ = writeln!(
        o,
        r##"<text x="20" y="50" font-size="13" fill="#555">{} moves, {} arcs</text>"##,
        f.toolpath.moves.len(),
        arcs
    );
    o.push_str("</svg>\n");
    o
}

fn xml(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// Renders an SVG document to PNG bytes.
pub fn png(svg_text: &str) -> Result<Vec<u8>> {
    let mut opt = resvg::usvg::Options::default();
    opt.fontdb_mut().load_system_fonts();
    let tree = resvg::usvg::Tree::from_str(svg_text, &opt)
        .map_err(|e| Error::Output { what: "picture".into(), reason: format!("cannot render it: {e}") })?;
    let size = tree.size().to_int_size();
    let mut pix = resvg::tiny_skia::Pixmap::new(size.width(), size.height())
        .ok_or_else(|| Error::Output { what: "picture".into(), reason: "it is empty".into() })?;
    resvg::render(&tree, resvg::tiny_skia::Transform::identity(), &mut pix.as_mut());
    pix.encode_png()
        .map_err(|e| Error::Output { what: "picture".into(), reason: format!("cannot encode the PNG: {e}") })
}
