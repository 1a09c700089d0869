//! A drawing of an implicit shape: the zero set, a few positive levels and a path on top (in
//! the manner of Kalmar-Nagy & Erdim's Figure 5), as SVG.

use crate::geom::DVec2;
use crate::implicit::Field;
use crate::implicit::levels::{ContourSeg, Grid};
use std::fmt::Write;

/// What [`svg`] draws besides the level sets.
#[derive(Debug, Clone, Default)]
pub struct Drawing<'a> {
    /// Title line.
    pub title: String,
    /// Positive levels drawn between 0 and the maximum (0 for none).
    pub levels: usize,
    /// Grid cells along the longer side (0 for 300).
    pub resolution: usize,
    /// A path drawn on top, its first point marked.
    pub path: Option<&'a [DVec2]>,
}

impl Drawing<'_> {
    /// Refuses more level sets than [`crate::limits::MAX_SHAPE_LEVELS`].
    pub fn validate(&self) -> crate::Result<()> {
        if self.levels > crate::limits::MAX_SHAPE_LEVELS {
            return Err(crate::Error::setting(
                crate::Setting::ShapeLevels,
                format!("{} level sets: at most {}", self.levels, crate::limits::MAX_SHAPE_LEVELS),
            ));
        }
        Ok(())
    }
}

/// The zero set of `field` (black), `levels` positive level sets (blue to orange) and the path
/// (red) over the box `lo`–`hi`, as an SVG document.
pub fn svg(field: &dyn Field, lo: DVec2, hi: DVec2, d: &Drawing) -> String {
    let (w, h, top) = (800.0, 800.0, 50.0);
    let size = (hi - lo).max(DVec2::splat(1e-9));
    let s = ((w - 40.0) / size.x).min((h - top - 20.0) / size.y);
    let ox = 20.0 + ((w - 40.0) - s * size.x) / 2.0;
    let oy = top + ((h - top - 20.0) - s * size.y) / 2.0;
    let map = |p: DVec2| (ox + (p.x - lo.x) * s, oy + (hi.y - p.y) * s);
    let grid = Grid::sample(field, lo, hi, if d.resolution == 0 { 300 } else { d.resolution });
    let mut o = String::new();
    let _ = writeln!(
        o,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="DejaVu Sans, Arial, sans-serif">"#
    );
    let _ = writeln!(o, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = writeln!(o, r#"<text x="20" y="30" font-size="18">{}</text>"#, xml(&d.title));
    let (a, b) = (map(lo), map(hi));
    let _ = writeln!(
        o,
        r##"<rect x="{:.2}" y="{:.2}" width="{:.2}" height="{:.2}" fill="none" stroke="#bbb" stroke-width="0.8"/>"##,
        a.0,
        b.1,
        b.0 - a.0,
        a.1 - b.1
    );
    let path_of = |segs: &[ContourSeg]| {
        let mut p = String::new();
        for [(a, _), (b, _)] in segs {
            let (x0, y0) = map(*a);
            let (x1, y1) = map(*b);
            let _ = write!(p, "M{x0:.2},{y0:.2}L{x1:.2},{y1:.2}");
        }
        p
    };
    let fmax = grid.max();
    if d.levels > 0 && fmax > 0.0 {
        for k in 1..=d.levels {
            let level = fmax * k as f64 / (d.levels + 1) as f64;
            let (r, g, bl) = super::tea_color(1.0 + 150.0 * k as f64 / d.levels as f64);
            let _ = writeln!(
                o,
                r##"<path d="{}" fill="none" stroke="#{r:02x}{g:02x}{bl:02x}" stroke-width="0.9"/>"##,
                path_of(&grid.contour(level))
            );
        }
    }
    let _ =
        writeln!(o, r##"<path d="{}" fill="none" stroke="#000" stroke-width="1.8"/>"##, path_of(&grid.contour(0.0)));
    if let Some(path) = d.path.filter(|p| !p.is_empty()) {
        let mut p = String::new();
        for (i, q) in path.iter().enumerate() {
            let (x, y) = map(*q);
            let _ = write!(p, "{}{x:.2},{y:.2} ", if i == 0 { "M" } else { "L" });
        }
        let _ = writeln!(o, r##"<path d="{p}" fill="none" stroke="#b0202a" stroke-width="1.1"/>"##);
        let (x, y) = map(path[0]);
        let _ = writeln!(o, r##"<circle cx="{x:.2}" cy="{y:.2}" r="3.5" fill="#b0202a"/>"##);
    }
    o.push_str("</svg>\n");
    o
}

fn xml(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::RFamily;
    use crate::implicit::shape::{Node, Shape};

    #[test]
    fn draws_the_zero_set_and_the_levels() {
        let s = Shape { family: RFamily::default(), root: Node::Circle { c: DVec2::new(1.0, 1.0), r: 4.0 } };
        let text = svg(&s, DVec2::splat(-5.0), DVec2::splat(7.0), &Drawing { levels: 3, ..Default::default() });
        assert!(text.starts_with("<svg") && text.trim_end().ends_with("</svg>"));
        assert_eq!(text.matches("<path").count(), 4);
    }
}
