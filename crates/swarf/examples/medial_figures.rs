//! Redraws paper 2's figures (Elber, Cohen and Drake) on swarf's example cases, as PNG (drawn as
//! SVG and rendered by `swarf::plot::png`) and as the SVG that the medial strategy's module doc
//! embeds (`figures/` under the output folder):
//!
//! - `medial_axis.png`, `figures/medial_axis.svg`: Fig. 1(b) in the plane — the medial axis of
//!   the tool-centre region of `pocket_islands` (coloured by the radius of the maximal inscribed
//!   circle) and the circles placed along it a Hausdorff stepover apart;
//! - `medial_shapes.png`, `figures/medial_shapes.svg`: Fig. 1(c) against Fig. 2(c) — the program
//!   of `l_pocket` with every circle followed all the way round, and with the cut-back return,
//!   side by side.
//!
//! ```sh
//! cargo run --release -p swarf --example medial_figures -- docs
//! ```

use std::fmt::Write;
use std::path::Path;
use swarf::geom::medial::medial_axis;
use swarf::geom::simplify::{douglas_peucker, douglas_peucker_ring};
use swarf::geom::{Area, DVec2};
use swarf::job::rough::{RoughOptions, rough};
use swarf::plan::{LayerGeom, LinkOptions};
use swarf::strategy::medial::{MIN_OBJECT_ANGLE, region, runs};
use swarf::strategy::{MedialOptions, Strategy};
use swarf::toolpath::{Motion, MoveKind, Toolpath};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "docs".into());
    let cases = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cases");
    let out = Path::new(&out);
    std::fs::create_dir_all(out.join("figures"))?;

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
    p.body.push_str(r##"<g fill="none" stroke="#c8c8c8" stroke-width="0.6">"##);
    for run in &rs {
        for k in &run.circles {
            p.circle(k.c, k.rho);
        }
    }
    p.body.push_str("</g>\n");
    // one path per shade (eight of them), each run of a shade simplified to a quarter of a pixel
    let shade = |w: &[f64]| (0.5 * (w[0] + w[1]) / rmax * 8.0).round() as usize;
    let mut shades = vec![String::new(); 9];
    for e in &axis.edges {
        let mut from = 0;
        for i in 1..e.pts.len() {
            let t = shade(&e.rad[i - 1..=i]);
            if i + 1 == e.pts.len() || shade(&e.rad[i..=i + 1]) != t {
                let run = douglas_peucker(&e.pts[from..=i], 0.25 / p.scale);
                shades[t].push_str(&p.polyline(&run));
                from = i;
            }
        }
    }
    for (t, d) in shades.iter().enumerate().filter(|(_, d)| !d.is_empty()) {
        let _ = writeln!(p.body, r#"<path d="{d}" fill="none" stroke="{}" stroke-width="2"/>"#, ramp(t as f64 / 8.0));
    }
    let first = rs[0].circles[0];
    p.body.push_str(r##"<g fill="none" stroke="#c0392b" stroke-width="1.5">"##);
    p.circle(first.c, first.rho);
    p.body.push_str("</g>\n");
    let n: usize = rs.iter().map(|r| r.circles.len()).sum();
    let title = format!(
        "pocket_islands: the medial axis of the tool-centre region (colour: inscribed radius, up to {rmax:.1} mm),\n\
         {n} circles a Hausdorff stepover ({:.1} mm) apart; red: the largest, where the tool enters",
        geom.step
    );
    write(out, "medial_axis", &doc(&title, 760.0, &[p]))?;

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
    write(out, "medial_shapes", &doc(&title, 1240.0, &panels))?;
    Ok(())
}

/// Writes `NAME.png` into `out` and `NAME.svg` into `out/figures`, the SVG scaled to the width
/// of the page it is shown on (a module doc).
fn write(out: &Path, name: &str, svg: &str) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::write(out.join(format!("{name}.png")), swarf::plot::png(svg)?)?;
    let fluid = svg.replacen("<svg ", r#"<svg style="max-width:100%;height:auto" "#, 1);
    std::fs::write(out.join("figures").join(format!("{name}.svg")), fluid)?;
    Ok(())
}

/// Blue to red.
fn ramp(t: f64) -> String {
    let t = t.clamp(0.0, 1.0);
    let (r, g, b) = (40.0 + 200.0 * t, 90.0 + 60.0 * (1.0 - (2.0 * t - 1.0).abs()), 220.0 - 190.0 * t);
    format!("#{:02x}{:02x}{:02x}", r as u8, g as u8, b as u8)
}

/// One drawing, the stock's bounds fitted into a square `size` wide at `x0`. Coordinates are
/// written to a tenth of a pixel, which keeps the SVG small.
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
    /// `x,y` of a point on the page.
    fn xy(&self, q: DVec2) -> String {
        let (x, y) = self.at(q);
        format!("{x:.1},{y:.1}")
    }
    fn area(&mut self, a: &Area, fill: &str, stroke: &str) {
        let mut d = String::new();
        for ring in a.rings() {
            for (i, q) in douglas_peucker_ring(ring, 0.1 / self.scale).iter().enumerate() {
                let _ = write!(d, "{}{}", if i == 0 { "M" } else { " " }, self.xy(*q));
            }
            d.push('Z');
        }
        let _ = writeln!(self.body, r#"<path d="{d}" fill="{fill}" fill-rule="evenodd" stroke="{stroke}"/>"#);
    }
    /// The path data of a polyline.
    fn polyline(&self, pts: &[DVec2]) -> String {
        let pts: Vec<String> = pts.iter().map(|q| self.xy(*q)).collect();
        format!("M{}", pts.join(" "))
    }
    /// A circle, its stroke set by the enclosing group.
    fn circle(&mut self, c: DVec2, r: f64) {
        let (x, y) = self.at(c);
        let _ = write!(self.body, r#"<circle cx="{x:.1}" cy="{y:.1}" r="{:.1}"/>"#, r * self.scale);
    }
    /// The program's XY moves at depth: cutting in blue, rapids dotted.
    fn path(&mut self, tp: &Toolpath) {
        let (mut cut, mut rapid) = (String::new(), String::new());
        let mut from = tp.moves.first().map(|m| m.to).unwrap_or_default();
        let mut down = false;
        for m in &tp.moves {
            let (a, b) = (from.truncate(), m.to.truncate());
            from = m.to;
            if m.kind == MoveKind::Rapid {
                let _ = write!(rapid, "M{}L{}", self.xy(a), self.xy(b));
                down = false;
                continue;
            }
            if !down {
                let _ = write!(cut, "M{}", self.xy(a));
                down = true;
            }
            match m.motion {
                Motion::Line => {
                    let _ = write!(cut, "L{}", self.xy(b));
                }
                Motion::Arc { center, ccw } => {
                    let r = (a - center).length() * self.scale;
                    // y is flipped on the page: a counter-clockwise arc is drawn clockwise
                    let sweep = if ccw { 1 } else { 0 };
                    let _ = write!(cut, "A{r:.1},{r:.1} 0 0 {sweep} {}", self.xy(b));
                }
            }
        }
        let _ = writeln!(self.body, r##"<path d="{cut}" fill="none" stroke="#2c50c8" stroke-width="0.7"/>"##);
        let _ = writeln!(
            self.body,
            r##"<path d="{rapid}" fill="none" stroke="#c0392b" stroke-width="0.8" stroke-dasharray="3,3"/>"##
        );
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
