//! Pictures of a 5-axis pocketing path (paper 2 §2, its Fig. 1, 4 and 5 redone on a case): the
//! rounded shapes in the parameter domain before the variable offset and after it, the path on
//! the floor seen from above with the walls, and the orientation field V over the floor.

use crate::geom::{DVec2, DVec3};
use crate::model::five::{Boundary, FiveJob, Side};
use std::fmt::Write;

/// What to draw: the path's points in the domain before and after the offset, and its tips.
pub struct FivePicture<'a> {
    /// The title.
    pub title: String,
    /// (u, v) of each move before the offset.
    pub before: &'a [DVec2],
    /// (u, v) of each move after it.
    pub after: &'a [DVec2],
    /// The tool tips.
    pub tips: &'a [DVec3],
    /// The rounded shape each move belongs to.
    pub shape: &'a [u32],
}

const PANEL: f64 = 430.0;
const PAD: f64 = 28.0;

/// A panel: a box of the plane fitted into a square.
struct Frame {
    x0: f64,
    y0: f64,
    lo: DVec2,
    scale: f64,
    h: f64,
}

impl Frame {
    fn new(x0: f64, y0: f64, lo: DVec2, hi: DVec2) -> Frame {
        let span = (hi - lo).max(DVec2::splat(1e-9));
        let scale = (PANEL - 2.0 * PAD) / span.x.max(span.y);
        Frame { x0: x0 + PAD, y0: y0 + PAD, lo, scale, h: span.y * scale }
    }
    fn at(&self, p: DVec2) -> (f64, f64) {
        (self.x0 + (p.x - self.lo.x) * self.scale, self.y0 + self.h - (p.y - self.lo.y) * self.scale)
    }
    fn polyline(&self, out: &mut String, pts: impl Iterator<Item = DVec2>, style: &str) {
        let mut d = String::new();
        for p in pts {
            let (x, y) = self.at(p);
            let _ = write!(d, "{x:.1},{y:.1} ");
        }
        let _ = writeln!(out, r#"<polyline points="{d}" fill="none" {style}/>"#);
    }
}

/// Every k-th point, so that at most `n` are drawn.
fn thin<T: Copy>(v: &[T], n: usize) -> impl Iterator<Item = T> + '_ {
    let k = v.len().div_ceil(n.max(1)).max(1);
    v.iter().step_by(k).copied()
}

/// The picture as SVG: four panels side by side.
pub fn svg(job: &FiveJob, pic: &FivePicture) -> String {
    let mut out = String::new();
    let top = 50.0;
    let mut tallest = 0.0f64;
    // a few shapes drawn bold: every twentieth, and three neighbours in the middle
    let last = pic.shape.iter().copied().max().unwrap_or(0);
    let bold = |s: u32| s.is_multiple_of(20) || (s + 1..=s + 3).contains(&(last / 2 + 2));
    // 1–2: the domain, before and after the offset
    let (mut lo, mut hi) = (DVec2::ZERO, DVec2::ONE);
    let inner_of = |v: &'_ [DVec2]| if v.len() > 2 { v[1..v.len() - 1].to_vec() } else { v.to_vec() };
    for p in inner_of(pic.before).iter().chain(&inner_of(pic.after)) {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    for (k, (pts, what)) in
        [(pic.before, "domain: shapes between the walls"), (pic.after, "domain: after the variable offset")]
            .into_iter()
            .enumerate()
    {
        let f = Frame::new(PANEL * k as f64, top, lo, hi);
        square(&mut out, job, &f);
        f.polyline(&mut out, thin(pts, 30_000), r##"stroke="#9ec5e8" stroke-width="0.3""##);
        shapes(&mut out, &f, pts, pic.shape, &bold);
        label(&mut out, &f, what);
        tallest = tallest.max(f.h);
    }
    // 3: the tips from above, with the walls' floor and top edges
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    let edge = |s: Side, top: bool| -> Vec<DVec2> {
        (0..=100)
            .map(|i| {
                let b = s.at(i as f64 / 100.0);
                let p = if top { job.top.eval(b.x, b.y).p } else { job.floor.eval(b.x, b.y).p };
                p.truncate()
            })
            .collect()
    };
    for s in Side::ALL {
        for p in edge(s, false).into_iter().chain(edge(s, true)) {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    let cut: Vec<DVec2> = pic.tips.iter().map(|t| t.truncate()).collect();
    for p in &cut[1..cut.len().saturating_sub(1)] {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    let f = Frame::new(2.0 * PANEL, top, lo, hi);
    let inner = if cut.len() > 2 { &cut[1..cut.len() - 1] } else { &cut[..] };
    f.polyline(&mut out, thin(inner, 30_000), r##"stroke="#9ec5e8" stroke-width="0.3""##);
    shapes(&mut out, &f, &cut, pic.shape, &bold);
    outline(&mut out, job, &f, &edge);
    tallest = tallest.max(f.h);
    label(&mut out, &f, "on the floor, from above (tool tips)");
    // 4: the field over the floor, from above: arrows of V, their colour its lean from the normal
    let f4 = Frame::new(3.0 * PANEL, top, lo, hi);
    outline(&mut out, job, &f4, &edge);
    let n = 11;
    let len = 0.06 * (hi - lo).max_element();
    for i in 0..=n {
        for j in 0..=n / 2 {
            let (u, v) = (i as f64 / n as f64, j as f64 / (n / 2) as f64);
            let p = job.floor.eval(u, v).p;
            let a = job.axis_field(u, v);
            let lean = a.angle_between(job.floor_normal(u, v)).to_degrees();
            let t = (lean / 30.0).min(1.0);
            let colour = format!("rgb({},{},{})", (40.0 + 200.0 * t) as u8, 80, (220.0 - 180.0 * t) as u8);
            let (x0, y0) = f4.at(p.truncate());
            let (x1, y1) = f4.at(p.truncate() + a.truncate() * (len / a.z.abs().max(0.2)));
            let _ = writeln!(
                out,
                r#"<line x1="{x0:.1}" y1="{y0:.1}" x2="{x1:.1}" y2="{y1:.1}" stroke="{colour}" stroke-width="1.6"/><circle cx="{x0:.1}" cy="{y0:.1}" r="1.8" fill="{colour}"/>"#
            );
        }
    }
    label(&mut out, &f4, "the field V from above (blue 0° to red 30° from the normal)");
    out.push_str("</svg>\n");
    let (width, height) = (4.0 * PANEL, top + tallest + 2.0 * PAD);
    let mut head = String::new();
    let _ = writeln!(
        head,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height:.0}" viewBox="0 0 {width} {height:.0}" font-family="DejaVu Sans, Arial, sans-serif" font-size="13">"#
    );
    let _ = writeln!(head, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(head, r#"<text x="10" y="22" font-size="15">{}</text>"#, escape(&pic.title));
    head + &out
}

/// The bold shapes: each a polyline of its own.
fn shapes(out: &mut String, f: &Frame, pts: &[DVec2], shape: &[u32], bold: &dyn Fn(u32) -> bool) {
    let mut k = 0;
    while k < pts.len().min(shape.len()) {
        let s = shape[k];
        let mut e = k;
        while e < shape.len().min(pts.len()) && shape[e] == s {
            e += 1;
        }
        if bold(s) {
            f.polyline(out, pts[k..e].iter().copied(), r##"stroke="#c0392b" stroke-width="1.2""##);
        }
        k = e;
    }
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

fn label(out: &mut String, f: &Frame, text: &str) {
    let _ = writeln!(out, r#"<text x="{:.1}" y="{:.1}">{}</text>"#, f.x0, f.y0 - 8.0, escape(text));
}

/// The unit square, walls solid and open sides dashed.
fn square(out: &mut String, job: &FiveJob, f: &Frame) {
    for s in Side::ALL {
        let (a, b) = (s.at(0.0), s.at(1.0));
        let style = match job.boundary(s) {
            Boundary::Open => r##"stroke="#888" stroke-width="1" stroke-dasharray="5,4""##,
            Boundary::Wall(_) => r##"stroke="black" stroke-width="2""##,
        };
        f.polyline(out, [a, b].into_iter(), style);
    }
}

/// The floor's edges (walls solid, open sides dashed) and the walls' top edges (grey).
fn outline(out: &mut String, job: &FiveJob, f: &Frame, edge: &dyn Fn(Side, bool) -> Vec<DVec2>) {
    for s in Side::ALL {
        let wall = !matches!(job.boundary(s), Boundary::Open);
        let style = if wall {
            r##"stroke="black" stroke-width="1.6""##
        } else {
            r##"stroke="#888" stroke-width="1" stroke-dasharray="5,4""##
        };
        f.polyline(out, edge(s, false).into_iter(), style);
        if wall {
            f.polyline(out, edge(s, true).into_iter(), r##"stroke="#999" stroke-width="1""##);
        }
    }
}
