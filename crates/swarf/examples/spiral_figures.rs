//! Draws paper 4's figures (Kalmar-Nagy & Erdim) on swarf's examples, as the SVG that the module
//! docs of `implicit` and `strategy::spiral` embed (`figures/` under the output folder):
//!
//! - `figures/spiral_shape.svg`: Figure 5 on `examples/shapes/disk_minus_slot.json` — the zero
//!   set and level sets of an R-function shape (a disk less a rotated slot and a notch) and the
//!   oscillator spiral from the maximum of `f` out to the boundary, as `swarf shape … --spiral`
//!   draws them;
//! - `figures/spiral_pockets.svg`: the spiral strategy's programs on `l_pocket` (one spiral, no
//!   link) and on `pocket_islands` (a spiral over the island-free core, the rest cleared by the
//!   adaptive passes).
//!
//! ```sh
//! cargo run --release -p swarf --example spiral_figures -- docs
//! ```

use std::collections::HashMap;
use std::fmt::Write;
use std::path::Path;
use swarf::geom::simplify::{douglas_peucker, douglas_peucker_ring};
use swarf::geom::{Area, DVec2};
use swarf::implicit::Field;
use swarf::implicit::levels::Grid;
use swarf::implicit::oscillator::{self, Damping};
use swarf::implicit::shape::{self, Shape};
use swarf::plan::{LayerGeom, LinkOptions};
use swarf::strategy::medial::region;
use swarf::strategy::spiral::{ENGAGEMENT_FLOOR, SpiralChoice, plan_pieces};
use swarf::strategy::{SpiralOptions, Strategy};

/// The stepover of the shape's spiral, in the shape file's units.
const STEPOVER: f64 = 8.0;
/// Positive level sets drawn between 0 and the maximum of `f`.
const LEVELS: usize = 5;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "docs".into());
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let figures = Path::new(&out).join("figures");
    std::fs::create_dir_all(&figures)?;

    // the shape, its level sets and its spiral (as `swarf shape`)
    let file = root.join("examples/shapes/disk_minus_slot.json");
    let s = Shape::load(&file)?;
    let (lo, hi) = s.bounds().ok_or("the shape is unbounded")?;
    let pad = (hi - lo) * 0.05;
    let (lo, hi) = (lo - pad, hi + pad);
    // left: the level sets; right: the spiral over the zero set
    let mut left = Panel::new(lo, hi, 0.0, 400.0);
    let mut right = Panel::new(lo, hi, 420.0, 400.0);
    let grid = Grid::sample(&s, lo, hi, 240);
    let fmax = grid.max();
    for k in 1..=LEVELS {
        let level = fmax * k as f64 / (LEVELS + 1) as f64;
        let (r, g, b) = swarf::plot::tea_color(1.0 + 150.0 * k as f64 / LEVELS as f64);
        left.level(&grid, level, &format!("#{r:02x}{g:02x}{b:02x}"), 1.2);
    }
    left.level(&grid, 0.0, "#000000", 1.8);
    right.level(&grid, 0.0, "#000000", 1.8);
    let (start, _) = shape::maximum(&s, lo, hi).ok_or("the shape is empty")?;
    let opts =
        oscillator::SpiralOptions { damping: Damping::stepover(STEPOVER), f_end: 0.1 * STEPOVER, ..Default::default() };
    let sp = oscillator::spiral(&s, start, &opts)?;
    let d = right.polyline(&douglas_peucker(&sp.polyline(), 0.25 / right.scale));
    let _ = writeln!(right.body, r##"<path d="{d}" fill="none" stroke="#b0202a" stroke-width="0.7"/>"##);
    for p in [&mut left, &mut right] {
        let (x, y) = p.at(start);
        let _ = writeln!(p.body, r##"<circle cx="{x:.1}" cy="{y:.1}" r="3" fill="#b0202a"/>"##);
    }
    let title = format!(
        "disk_minus_slot.json (paper 4 §3): left, the zero set (black) and {LEVELS} level sets of f; right, the oscillator\n\
         spiral from the maximum of f (red dot): stepover {STEPOVER}, {:.1} turns, largest spacing between turns {:.2}",
        sp.turns, sp.max_spacing
    );
    write(&figures.join("spiral_shape.svg"), &doc(&title, 840.0, &[left, right]))?;

    // the spiral strategy's spirals on two cases
    let mut panels = Vec::new();
    let mut names = Vec::new();
    let link = LinkOptions::DEFAULT;
    for (i, case) in ["l_pocket", "pocket_islands"].into_iter().enumerate() {
        let job = swarf::io::load_job(&root.join(format!("examples/cases/{case}.json")), &Default::default())?;
        let margin = Strategy::Spiral(SpiralOptions::DEFAULT).wall_margin(&link);
        let regions = job.regions(job.radius(), margin)?;
        let geom = LayerGeom::new(&job, &regions, &link, margin)?;
        let (pieces, islands) = plan_pieces(&job, &regions, &geom, &link, &SpiralChoice::default())?;
        let (lo, hi) = job.stock.bounds().ok_or("no stock")?;
        let mut p = Panel::new(lo - DVec2::splat(2.0), hi + DVec2::splat(2.0), i as f64 * 460.0, 440.0);
        p.area(&job.stock, "none", "#000000");
        p.area(&job.part, "#3a3a3a", "none");
        p.area(&region(&regions, &geom), "none", "#999999");
        let mut turns = 0.0;
        for piece in &pieces {
            let d = p.polyline(&douglas_peucker(&piece.spiral.polyline()[piece.join..], 0.25 / p.scale));
            let _ = writeln!(p.body, r##"<path d="{d}" fill="none" stroke="#2c50c8" stroke-width="0.8"/>"##);
            let (x, y) = p.at(piece.start);
            let r = piece.helix_r * p.scale;
            let _ = writeln!(
                p.body,
                r##"<circle cx="{x:.1}" cy="{y:.1}" r="{r:.1}" fill="none" stroke="#b0202a" stroke-width="1.5"/>"##
            );
            turns += piece.spiral.turns;
        }
        panels.push(p);
        names.push(format!(
            "{case}: {turns:.0} turns{}",
            if islands { ", over the island-free core (the rest: adaptive passes)" } else { "" }
        ));
    }
    let title = format!(
        "The spiral strategy's spirals (blue) in the tool-centre region (grey), entry helix red, floor {ENGAGEMENT_FLOOR}\n{}",
        names.join("    ")
    );
    write(&figures.join("spiral_pockets.svg"), &doc(&title, 920.0, &panels))?;
    Ok(())
}

/// Writes an SVG scaled to the width of the page it is shown on (a module doc).
fn write(path: &Path, svg: &str) -> std::io::Result<()> {
    std::fs::write(path, svg.replacen("<svg ", r#"<svg style="max-width:100%;height:auto" "#, 1))
}

/// One drawing, the box `lo`–`hi` fitted into a square `size` wide at `x0`. Coordinates are
/// written to a tenth of a pixel, which keeps the SVG small.
struct Panel {
    body: String,
    lo: DVec2,
    scale: f64,
    x0: f64,
    h: f64,
}

impl Panel {
    fn new(lo: DVec2, hi: DVec2, x0: f64, size: f64) -> Panel {
        let scale = size / (hi - lo).max_element();
        Panel { body: String::new(), lo, scale, x0: x0 + 10.0, h: (hi.y - lo.y) * scale }
    }
    fn at(&self, q: DVec2) -> (f64, f64) {
        (self.x0 + (q.x - self.lo.x) * self.scale, 50.0 + self.h - (q.y - self.lo.y) * self.scale)
    }
    /// `x,y` of a point on the page.
    fn xy(&self, q: DVec2) -> String {
        let (x, y) = self.at(q);
        format!("{x:.1},{y:.1}")
    }
    /// The path data of a polyline.
    fn polyline(&self, pts: &[DVec2]) -> String {
        let pts: Vec<String> = pts.iter().map(|q| self.xy(*q)).collect();
        format!("M{}", pts.join(" "))
    }
    fn area(&mut self, a: &Area, fill: &str, stroke: &str) {
        let mut d = String::new();
        for ring in a.rings() {
            d.push_str(&self.polyline(&douglas_peucker_ring(ring, 0.1 / self.scale)));
            d.push('Z');
        }
        let _ = writeln!(self.body, r#"<path d="{d}" fill="{fill}" fill-rule="evenodd" stroke="{stroke}"/>"#);
    }
    /// The level set `f = level` of a sampled field: the marching-squares segments joined into
    /// polylines where their ends meet, each simplified to a quarter of a pixel.
    fn level(&mut self, grid: &Grid, level: f64, color: &str, width: f64) {
        let segs: Vec<[DVec2; 2]> = grid.contour(level).iter().map(|[(a, _), (b, _)]| [*a, *b]).collect();
        let tiny = 1e-6 * grid.step.max_element();
        let key = |q: DVec2| ((q.x / tiny).round() as i64, (q.y / tiny).round() as i64);
        let mut ends: HashMap<(i64, i64), Vec<usize>> = HashMap::new();
        for (i, s) in segs.iter().enumerate() {
            ends.entry(key(s[0])).or_default().push(i);
            ends.entry(key(s[1])).or_default().push(i);
        }
        let mut used = vec![false; segs.len()];
        let mut d = String::new();
        for i in 0..segs.len() {
            if used[i] {
                continue;
            }
            used[i] = true;
            let mut chain = vec![segs[i][0], segs[i][1]];
            for backward in [false, true] {
                loop {
                    let end = if backward { chain[0] } else { chain[chain.len() - 1] };
                    let next = ends[&key(end)].iter().copied().find(|&j| !used[j]);
                    let Some(j) = next else { break };
                    used[j] = true;
                    let q = if key(segs[j][0]) == key(end) { segs[j][1] } else { segs[j][0] };
                    if backward { chain.insert(0, q) } else { chain.push(q) }
                }
            }
            d.push_str(&self.polyline(&douglas_peucker(&chain, 0.25 / self.scale)));
        }
        let _ = writeln!(self.body, r#"<path d="{d}" fill="none" stroke="{color}" stroke-width="{width}"/>"#);
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
    // the title last, on a band of its own
    let _ = writeln!(s, r#"<rect width="100%" height="40" fill="white"/>"#);
    for (i, line) in title.lines().enumerate() {
        let line = line.replace('&', "&amp;").replace('<', "&lt;");
        let _ = writeln!(s, r#"<text x="10" y="{}" font-size="12">{line}</text>"#, 15 + 15 * i);
    }
    s.push_str("</svg>\n");
    s
}
