//! Pictures like the papers' figures: on the left the XY path coloured by tool engagement over
//! the part (dark) and the stock outline, rapids dotted, plunges and gouges marked; on the right
//! engagement against cutting length with the reference and the bound. Written as SVG, and as
//! PNG by rendering that SVG with resvg. [`heights`] draws the stock seen from above from a
//! simulator's heights.
//!
//! A 3D job's picture draws on the left the stock after the program seen from above (grey by
//! height, the terraces z-level roughing leaves by design in amber, material the tool could have
//! cut and left in red) instead of every level's path on top of the others, and below, one
//! small picture per level: that level's path coloured by engagement over the part's shadow at
//! the level, its rapids at depth dotted.

use crate::error::{Error, Result};
use crate::geom::{Area, DVec2};
use crate::sim::{Replay, SampleKind, TopView};
use crate::toolpath::{Motion, Toolpath};
use std::fmt::Write;

pub mod five;
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
    /// A 3D job's levels, top down (empty for a 2.5D job): with them and the replay's
    /// [`TopView`], the picture shows the stock after the program from above and each level's
    /// path over the part's shadow at it.
    pub levels: &'a [Level],
}

/// One level of a 3D job in its picture.
pub struct Level {
    /// The tool tip's height, mm.
    pub z: f64,
    /// The part's shadow from above the level (what the level must not enter).
    pub part: Area,
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

/// Drawing coordinates of a world rectangle fitted, centred, into a panel.
#[derive(Clone, Copy)]
struct View {
    lo: DVec2,
    hi: DVec2,
    s: f64,
    ox: f64,
    oy: f64,
}

impl View {
    /// `lo`..`hi` fitted into the panel at (`x`, `y`) of `w` × `h` pixels.
    fn fit(lo: DVec2, hi: DVec2, x: f64, y: f64, w: f64, h: f64) -> View {
        let s = (w / (hi.x - lo.x)).min(h / (hi.y - lo.y));
        View { lo, hi, s, ox: x + (w - s * (hi.x - lo.x)) / 2.0, oy: y + (h - s * (hi.y - lo.y)) / 2.0 }
    }

    fn map(&self, p: DVec2) -> (f64, f64) {
        (self.ox + (p.x - self.lo.x) * self.s, self.oy + (self.hi.y - p.y) * self.s)
    }

    fn clip(&self) -> Area {
        Area::rect(self.lo.x, self.lo.y, self.hi.x, self.hi.y)
    }
}

/// The world bounds of the picture: the stock and the cutting moves, with a margin.
fn world(f: &Figure) -> (DVec2, DVec2) {
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
    (lo - DVec2::splat(pad), hi + DVec2::splat(pad))
}

/// The part (dark), the fixtures (red) and the stock outline in `v`.
fn draw_scene(o: &mut String, part: &Area, f: &Figure, v: &View, stroke: f64) {
    let map = |p: DVec2| v.map(p);
    let part = part.intersection(&v.clip());
    let _ = writeln!(o, r##"<path d="{}" fill="#3a3a3a" fill-rule="evenodd"/>"##, area_path(&part, &map));
    let fx = f.fixtures.intersection(&v.clip());
    if !fx.is_empty() {
        let _ = writeln!(
            o,
            r##"<path d="{}" fill="#b03030" fill-opacity="0.7" fill-rule="evenodd"/>"##,
            area_path(&fx, &map)
        );
    }
    draw_stock(o, f, v, stroke);
}

/// The stock outline in `v`.
fn draw_stock(o: &mut String, f: &Figure, v: &View, stroke: f64) {
    let _ = writeln!(
        o,
        r##"<path d="{}" fill="none" stroke="#000" stroke-width="{stroke}" fill-rule="evenodd"/>"##,
        area_path(f.stock, &|p| v.map(p))
    );
}

/// The rapids of the moves `keep` accepts (by index), dotted.
fn draw_rapids(o: &mut String, f: &Figure, v: &View, keep: &dyn Fn(usize) -> bool) {
    let mut d = String::new();
    for (i, (from, m)) in f.toolpath.segments().enumerate() {
        if m.is_rapid() && keep(i) && (m.to.truncate() - from.truncate()).length() > 1e-6 {
            let (a, b) = (v.map(from.truncate()), v.map(m.to.truncate()));
            let _ = write!(d, "M{:.2},{:.2} L{:.2},{:.2} ", a.0, a.1, b.0, b.1);
        }
    }
    if !d.is_empty() {
        let _ = writeln!(o, r##"<path d="{d}" fill="none" stroke="#555" stroke-width="0.8" stroke-dasharray="2,3"/>"##);
    }
}

/// The cutting path of the moves `keep` accepts (by index) coloured by engagement: runs of
/// samples of one colour bucket.
fn draw_cuts(o: &mut String, f: &Figure, v: &View, keep: &dyn Fn(usize) -> bool) {
    let samples = &f.replay.samples;
    let width = (f.toolpath.tool.diameter * v.s * 0.08).clamp(0.6, 2.5);
    let bucket = |t: f32| if t <= 0.0 { -1 } else { (t / 10.0) as i32 };
    let mut i = 0;
    while i < samples.len() {
        if !keep(samples[i].mi as usize) {
            i += 1;
            continue;
        }
        let b0 = bucket(samples[i].tea);
        let mut j = i;
        let start = if i > 0 && samples[i - 1].mi == samples[i].mi { samples[i - 1].at } else { samples[i].at };
        let mut run = vec![DVec2::from(v.map(start.truncate()))];
        while j < samples.len()
            && bucket(samples[j].tea) == b0
            && keep(samples[j].mi as usize)
            && (j == i || samples[j].mi.abs_diff(samples[j - 1].mi) <= 1)
        {
            run.push(DVec2::from(v.map(samples[j].at.truncate())));
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
}

/// Plunges ▼ and gouges ✕ of the moves `keep` accepts.
fn draw_marks(o: &mut String, f: &Figure, v: &View, keep: &dyn Fn(usize) -> bool) {
    for pl in f.replay.plunges.iter().filter(|e| keep(e.move_index)) {
        let p = v.map(DVec2::new(pl.at[0], pl.at[1]));
        let _ = writeln!(o, r##"<path d="M{:.1},{:.1} l-6,-9 h12 z" fill="#d00"/>"##, p.0, p.1 + 4.0);
    }
    for g in f.replay.gouges.iter().filter(|e| keep(e.move_index)) {
        let p = v.map(DVec2::new(g.at[0], g.at[1]));
        let _ = writeln!(
            o,
            r##"<path d="M{:.1},{:.1} l10,10 m0,-10 l-10,10" stroke="#f00" stroke-width="2.5"/>"##,
            p.0 - 5.0,
            p.1 - 5.0
        );
    }
}

/// The level of each move of a 3D job's program (an index into `levels`, top down): the lowest
/// level at or above the move's end, for cutting moves, and for rapids that stay at one level;
/// none for the rest (rapids that rise or fall, moves above the first level).
fn move_levels(f: &Figure) -> Vec<Option<usize>> {
    const TOL: f64 = 0.002;
    let of = |z: f64| f.levels.iter().rposition(|l| l.z >= z - TOL);
    f.toolpath
        .segments()
        .map(|(from, m)| {
            let l = of(m.to.z)?;
            // (above the first level there is none)
            (!m.is_rapid() || of(from.z) == Some(l)).then_some(l)
        })
        .collect()
}

/// The figure as an SVG document.
pub fn svg(f: &Figure) -> String {
    let three_d = !f.levels.is_empty() && f.replay.top_view.is_some();
    let (w, mut h) = (1500.0, 640.0);
    let (lw, top, bottom) = (760.0, 60.0, 590.0);
    let (lo, hi) = world(f);
    let v = View::fit(lo, hi, 20.0, top, lw - 40.0, bottom - top);
    // a 3D job's levels, five to a row below
    let cols = 5usize;
    let (pw, gap) = ((w - 40.0 - (cols - 1) as f64 * 12.0) / cols as f64, 12.0);
    let ph = (pw * (hi.y - lo.y) / (hi.x - lo.x)).clamp(0.3 * pw, 1.2 * pw);
    let rows = if three_d { f.levels.len().div_ceil(cols) } else { 0 };
    h += rows as f64 * (ph + 30.0) + if rows > 0 { 20.0 } else { 0.0 };
    let mut o = String::new();
    let _ = writeln!(
        o,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="DejaVu Sans, Arial, sans-serif">"#
    );
    let _ = writeln!(o, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = writeln!(o, r#"<text x="20" y="30" font-size="18">{}</text>"#, xml(&f.title));
    let all = |_: usize| true;
    if let (true, Some(tv)) = (three_d, &f.replay.top_view) {
        // the stock after the program, from above
        draw_top_view(&mut o, tv, &v);
        draw_stock(&mut o, f, &v, 1.2);
        draw_marks(&mut o, f, &v, &all);
    } else {
        draw_scene(&mut o, f.part, f, &v, 1.2);
        draw_rapids(&mut o, f, &v, &all);
        draw_cuts(&mut o, f, &v, &all);
        // rest material: reachable material left standing
        if !f.replay.rest_cells.is_empty() {
            let side = (f.replay.res * v.s).max(1.0);
            let mut d = String::new();
            for c in f.replay.rest_cells.iter().take(200_000) {
                let (x, y) = v.map(*c);
                let _ = write!(d, "M{:.1},{:.1}h{side:.1}v{side:.1}h-{side:.1}z", x - side / 2.0, y - side / 2.0);
            }
            let _ = writeln!(o, r##"<path d="{d}" fill="#e00000"/>"##);
        }
        // start marker: circle of the tool at the first cutting point
        if let Some(first) = f.replay.samples.first() {
            let p = v.map(first.at.truncate());
            let _ = writeln!(
                o,
                r##"<circle cx="{:.2}" cy="{:.2}" r="{:.2}" fill="none" stroke="#222" stroke-width="1"/>"##,
                p.0,
                p.1,
                f.toolpath.tool.radius() * v.s
            );
        }
        draw_marks(&mut o, f, &v, &all);
    }
    draw_engagement(&mut o, f);
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
    let key = if three_d {
        "engagement (each level's path below); left: the stock after roughing, grey by height (dark is deep), amber: terraces left by design, red: material the tool could have cut"
    } else {
        "engagement; grey: no engagement; dotted: rapids; red: material left"
    };
    let _ = writeln!(
        o,
        r#"<text x="20" y="634" font-size="11">0°</text><text x="452" y="634" font-size="11" text-anchor="end">180°</text><text x="470" y="620" font-size="11">{key}</text>"#
    );
    let arcs = f.toolpath.moves.iter().filter(|m| matches!(m.motion, Motion::Arc { .. })).count();
    let _ = writeln!(
        o,
        r##"<text x="20" y="50" font-size="13" fill="#555">{} moves, {} arcs</text>"##,
        f.toolpath.moves.len(),
        arcs
    );
    if three_d {
        let of = move_levels(f);
        let n = f.levels.len();
        for (k, level) in f.levels.iter().enumerate() {
            let (c, r) = (k % cols, k / cols);
            let (x, y) = (20.0 + c as f64 * (pw + gap), 660.0 + r as f64 * (ph + 30.0));
            let pv = View::fit(lo, hi, x, y + 18.0, pw, ph);
            let keep = |i: usize| of.get(i).copied().flatten() == Some(k);
            let cut: f64 = f.replay.samples.iter().filter(|sm| keep(sm.mi as usize)).map(|sm| f64::from(sm.len)).sum();
            let _ = writeln!(
                o,
                r##"<rect x="{x:.1}" y="{:.1}" width="{pw:.1}" height="{ph:.1}" fill="#f4f4f4"/><text x="{x:.1}" y="{:.1}" font-size="12">level {} of {n}: z {:.2}, {:.2} m cut</text>"##,
                y + 18.0,
                y + 12.0,
                k + 1,
                level.z,
                cut / 1000.0
            );
            draw_scene(&mut o, &level.part, f, &pv, 0.8);
            draw_rapids(&mut o, f, &pv, &keep);
            draw_cuts(&mut o, f, &pv, &keep);
            draw_marks(&mut o, f, &pv, &keep);
        }
    }
    o.push_str("</svg>\n");
    o
}

/// A 3D job's stock after the program from above, as an image in `v`.
fn draw_top_view(o: &mut String, tv: &TopView, v: &View) {
    let Ok(png) = heights::top_view_png(tv) else { return };
    use base64::Engine as _;
    let (x, y) = v.map(DVec2::new(tv.x0, tv.y0 + tv.ny as f64 * tv.side));
    let (wpx, hpx) = (tv.nx as f64 * tv.side * v.s, tv.ny as f64 * tv.side * v.s);
    let _ = writeln!(
        o,
        r#"<image x="{x:.2}" y="{y:.2}" width="{wpx:.2}" height="{hpx:.2}" preserveAspectRatio="none" href="data:image/png;base64,{}"/>"#,
        base64::engine::general_purpose::STANDARD.encode(png)
    );
}

/// The right panel: engagement against cutting length, with the reference and the bound.
fn draw_engagement(o: &mut String, f: &Figure) {
    let samples = &f.replay.samples;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::DVec3;
    use crate::model::Tool;
    use crate::sim::Sample;
    use crate::toolpath::MoveKind;

    /// A program of two levels: 30 mm cut at z −2 and 20 mm at z −4, with a rapid at depth
    /// between two cuts of the second; samples every millimetre.
    fn two_levels() -> (Toolpath, Replay) {
        let mut tp = Toolpath::new(Tool::flat(6.0), DVec3::new(0.0, 0.0, 10.0), 10.0);
        tp.line(MoveKind::Entry, DVec3::new(0.0, 0.0, -2.0), 500.0);
        tp.line(MoveKind::Cut, DVec3::new(30.0, 0.0, -2.0), 1000.0);
        tp.rapid(DVec3::new(30.0, 0.0, 10.0));
        tp.rapid(DVec3::new(0.0, 10.0, 10.0));
        tp.line(MoveKind::Entry, DVec3::new(0.0, 10.0, -4.0), 500.0);
        tp.line(MoveKind::Cut, DVec3::new(10.0, 10.0, -4.0), 1000.0);
        tp.rapid(DVec3::new(20.0, 10.0, -4.0));
        tp.line(MoveKind::Cut, DVec3::new(30.0, 10.0, -4.0), 1000.0);
        let mut samples = Vec::new();
        let mut s = 0.0;
        for (mi, (from, m)) in tp.segments().enumerate() {
            if m.is_rapid() || m.kind == MoveKind::Entry {
                continue;
            }
            let n = (m.to - from).length().round() as usize;
            for k in 1..=n {
                s += 1.0;
                let at = from + (m.to - from) * (k as f64 / n as f64);
                samples.push(Sample {
                    s,
                    at,
                    tea: 60.0,
                    tea_pixel: 60.0,
                    kind: SampleKind::Lateral,
                    bore: false,
                    len: 1.0,
                    feed: 1000.0,
                    mi: mi as u32,
                });
            }
        }
        let (nx, ny) = (4, 2);
        let top_view = TopView {
            nx,
            ny,
            x0: -5.0,
            y0: -5.0,
            side: 10.0,
            height: vec![0.0, -2.0, -4.0, f32::NAN, 0.0, 0.0, 0.0, 0.0],
            terrace: vec![0.0, 1.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            beyond: vec![0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            top: 0.0,
            bottom: -4.0,
        };
        let rp = Replay { samples, res: 0.1, top_view: Some(top_view), ..Default::default() };
        (tp, rp)
    }

    #[test]
    fn a_3d_picture_draws_each_levels_path_and_the_stock_from_above() {
        let (tp, rp) = two_levels();
        let stock = Area::rect(-5.0, -5.0, 35.0, 15.0);
        let empty = Area::empty();
        let levels = [
            Level { z: -2.0, part: Area::rect(-5.0, 12.0, 35.0, 15.0) },
            Level { z: -4.0, part: Area::rect(-5.0, 13.0, 35.0, 15.0) },
        ];
        let fig = |levels: &'_ [Level]| -> String {
            svg(&Figure {
                title: "t".into(),
                part: &empty,
                stock: &stock,
                fixtures: &empty,
                toolpath: &tp,
                replay: &rp,
                ref_deg: 60.0,
                levels,
            })
        };
        let three = fig(&levels);
        // each level's cut: 30 mm at the first, 20 at the second (the rapid at depth apart)
        assert!(three.contains("level 1 of 2: z -2.00, 0.03 m cut"), "{three}");
        assert!(three.contains("level 2 of 2: z -4.00, 0.02 m cut"), "{three}");
        assert!(three.contains("data:image/png;base64,"));
        assert_eq!(three.matches("stroke-dasharray=\"2,3\"").count(), 1, "the rapid at depth, in its level's panel");
        // a 2.5D picture has neither
        let flat = fig(&[]);
        assert!(!flat.contains("level 1 of") && !flat.contains("data:image/png"));
        // and both render
        assert!(png(&three).is_ok() && png(&flat).is_ok());
    }

    #[test]
    fn moves_belong_to_the_lowest_level_at_or_above_their_end() {
        let (tp, rp) = two_levels();
        let (stock, empty) = (Area::rect(0.0, 0.0, 1.0, 1.0), Area::empty());
        let levels = [Level { z: -2.0, part: Area::empty() }, Level { z: -4.0, part: Area::empty() }];
        let f = Figure {
            title: String::new(),
            part: &empty,
            stock: &stock,
            fixtures: &empty,
            toolpath: &tp,
            replay: &rp,
            ref_deg: 60.0,
            levels: &levels,
        };
        // entry, cut, up, across (above the levels), entry, cut, rapid at depth, cut
        assert_eq!(move_levels(&f), vec![Some(0), Some(0), None, None, Some(1), Some(1), Some(1), Some(1)]);
    }
}
