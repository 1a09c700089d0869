//! Redraws paper 2's figures (Elber, Cohen and Drake) on swarf's example cases (PNG, drawn as
//! SVG and rendered by `swarf::plot::png`):
//!
//! - `medial_axis.png`: Fig. 1(b) in the plane — the medial axis of the tool-centre region of
//!   `pocket_islands` (coloured by the radius of the maximal inscribed circle) and the circles
//!   placed along it a Hausdorff stepover apart;
//! - `medial_shapes.png`: Fig. 1(c) against Fig. 2(c) — the program of `l_pocket` with every
//!   circle followed all the way round, and with the cut-back return, side by side.
//!
//! ```sh
//! cargo run --release -p swarf --example medial_figures -- docs
//! ```

use std::fmt::Write;
use std::path::Path;
use swarf::geom::medial::medial_axis;
use swarf::geom::{Area, DVec2};
use swarf::job::rough::{RoughOptions, rough};
use swarf::plan::{LayerGeom, LinkOptions};
use swarf::strategy::medial::{MIN_OBJECT_ANGLE, region, runs};
use swarf::strategy::{MedialOptions, Strategy};
use swarf::toolpath::{Motion, MoveKind, Toolpath};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "docs".into());
    let cases = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cases");
    std::fs::create_dir_all(&out)?;

    // the axis and the circles
    let job = swarf::io::load_job(&cases.join("pocket_islands.json"), &Default::default())?;
    let link = LinkOptions::DEFAULT;
    let margin = Strategy::Medial(MedialOptions::DEFAULT).wall_margin(&link);
    let regions = job.regions(job.radius(), margin)?;
    let geom = LayerGeom::new(&job, &regions, &link, margin)?;
    let c = region(&regions, &geom);
    let axis = medial_axis(&c, MIN_OBJECT_ANGLE)?;
    let rs = runs(&axis, geom.step, geom.r);
    let mut p = Panel::new(&job.stock, 0.0, 700.0);
    p.area(&job.part, "#3a3a3a", "none");
    p.area(&c, "none", "#999999");
    let rmax = axis.nodes.iter().map(|n| n.r).fold(0.0, f64::max);
    for run in &rs {
        for k in &run.circles {
            p.circle(k.c, k.rho, "#c8c8c8", 0.6);
        }
    }
    for e in &axis.edges {
        for w in e.pts.windows(2).zip(e.rad.windows(2)) {
            let t = 0.5 * (w.1[0] + w.1[1]) / rmax;
            p.line(w.0[0], w.0[1], &ramp(t), 2.0, "");
        }
    }
    let first = rs[0].circles[0];
    p.circle(first.c, first.rho, "#c0392b", 1.5);
    let n: usize = rs.iter().map(|r| r.circles.len()).sum();
    let title = format!(
        "pocket_islands: the medial axis of the tool-centre region (colour: inscribed radius, up to {rmax:.1} mm),\n\
         {n} circles a Hausdorff stepover ({:.1} mm) apart; red: the largest, where the tool enters",
        geom.step
    );
    std::fs::write(Path::new(&out).join("medial_axis.png"), swarf::plot::png(&doc(&title, 760.0, &[p]))?)?;

    // full circles against the cut-back return
    let job = swarf::io::load_job(&cases.join("l_pocket.json"), &Default::default())?;
    let mut panels = Vec::new();
    let mut names = Vec::new();
    for (i, cut_back) in [false, true].into_iter().enumerate() {
        let opts = RoughOptions { strategy: Strategy::Medial(MedialOptions { cut_back }), ..Default::default() };
        let res = rough(&job, &opts, &mut |_, _| {})?;
        let mut p = Panel::new(&job.stock, i as f64 * 620.0, 600.0);
        p.area(&job.part, "#3a3a3a", "none");
        p.path(&res.toolpath);
        panels.push(p);
        names.push(format!(
            "{}: {:.0} mm cut, {:.2} min",
            if cut_back { "right: cut-back return (Fig. 2c)" } else { "left: full circles (Fig. 1c)" },
            res.report.cut_length_mm,
            res.report.time_min
        ));
    }
    let title = format!("l_pocket, medial strategy\n{}", names.join("    "));
    std::fs::write(Path::new(&out).join("medial_shapes.png"), swarf::plot::png(&doc(&title, 1240.0, &panels))?)?;
    Ok(())
}

/// Blue to red.
fn ramp(t: f64) -> String {
    let t = t.clamp(0.0, 1.0);
    let (r, g, b) = (40.0 + 200.0 * t, 90.0 + 60.0 * (1.0 - (2.0 * t - 1.0).abs()), 220.0 - 190.0 * t);
    format!("#{:02x}{:02x}{:02x}", r as u8, g as u8, b as u8)
}

/// One drawing, the stock's bounds fitted into a square `size` wide at `x0`.
struct Panel {
    body: String,
    lo: DVec2,
    scale: f64,
    x0: f64,
    h: f64,
}

impl Panel {
    fn new(stock: &Area, x0: f64, size: f64) -> Panel {
        let (lo, hi) = stock.bounds().unwrap_or((DVec2::ZERO, DVec2::ONE));
        let (lo, hi) = (lo - DVec2::splat(2.0), hi + DVec2::splat(2.0));
        let scale = size / (hi - lo).max_element();
        let mut p = Panel { body: String::new(), lo, scale, x0: x0 + 10.0, h: (hi.y - lo.y) * scale };
        p.area(stock, "none", "#000000");
        p
    }
    fn at(&self, q: DVec2) -> (f64, f64) {
        (self.x0 + (q.x - self.lo.x) * self.scale, 40.0 + self.h - (q.y - self.lo.y) * self.scale)
    }
    fn area(&mut self, a: &Area, fill: &str, stroke: &str) {
        let mut d = String::new();
        for ring in a.rings() {
            for (i, q) in ring.iter().enumerate() {
                let (x, y) = self.at(*q);
                let _ = write!(d, "{}{x:.2},{y:.2} ", if i == 0 { "M" } else { "L" });
            }
            d.push('Z');
        }
        let _ = writeln!(self.body, r#"<path d="{d}" fill="{fill}" fill-rule="evenodd" stroke="{stroke}"/>"#);
    }
    fn line(&mut self, a: DVec2, b: DVec2, color: &str, width: f64, dash: &str) {
        let ((x1, y1), (x2, y2)) = (self.at(a), self.at(b));
        let _ = writeln!(
            self.body,
            r#"<line x1="{x1:.2}" y1="{y1:.2}" x2="{x2:.2}" y2="{y2:.2}" stroke="{color}" stroke-width="{width}" {dash}/>"#
        );
    }
    fn circle(&mut self, c: DVec2, r: f64, color: &str, width: f64) {
        let (x, y) = self.at(c);
        let r = r * self.scale;
        let _ = writeln!(
            self.body,
            r#"<circle cx="{x:.2}" cy="{y:.2}" r="{r:.2}" fill="none" stroke="{color}" stroke-width="{width}"/>"#
        );
    }
    /// The program's XY moves at depth: cutting in blue, rapids dotted.
    fn path(&mut self, tp: &Toolpath) {
        let mut from = tp.moves.first().map(|m| m.to).unwrap_or_default();
        for m in &tp.moves {
            let (a, b) = (from.truncate(), m.to.truncate());
            from = m.to;
            if m.kind == MoveKind::Rapid {
                self.line(a, b, "#c0392b", 0.8, r#"stroke-dasharray="3,3""#);
                continue;
            }
            match m.motion {
                Motion::Line => self.line(a, b, "#2c50c8", 0.7, ""),
                Motion::Arc { center, ccw } => {
                    let (x1, y1) = self.at(a);
                    let (x2, y2) = self.at(b);
                    let r = (a - center).length() * self.scale;
                    // y is flipped on the page: a counter-clockwise arc is drawn clockwise
                    let sweep = if ccw { 1 } else { 0 };
                    let _ = writeln!(
                        self.body,
                        r##"<path d="M{x1:.2},{y1:.2} A{r:.2},{r:.2} 0 0 {sweep} {x2:.2},{y2:.2}" fill="none" stroke="#2c50c8" stroke-width="0.7"/>"##
                    );
                }
            }
        }
    }
}

fn doc(title: &str, w: f64, panels: &[Panel]) -> String {
    let h = panels.iter().map(|p| p.h).fold(0.0, f64::max) + 60.0;
    let mut s = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h:.0}" viewBox="0 0 {w} {h:.0}" font-family="DejaVu Sans, Arial, sans-serif">
<rect width="100%" height="100%" fill="white"/>
"#
    );
    for p in panels {
        s.push_str(&p.body);
    }
    // the title last, on a band of its own (the part may reach past the stock)
    let _ = writeln!(s, r#"<rect width="100%" height="36" fill="white"/>"#);
    for (i, line) in title.lines().enumerate() {
        let line = line.replace('&', "&amp;").replace('<', "&lt;");
        let _ = writeln!(s, r#"<text x="10" y="{}" font-size="12">{line}</text>"#, 15 + 15 * i);
    }
    s.push_str("</svg>\n");
    s
}
