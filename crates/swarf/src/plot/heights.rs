//! A picture of the stock seen from above, from a simulator's heights: grey by height (dark is
//! deep), orange where rest material stands above the lowest a tool reaches, the stronger the
//! thicker. Drawn straight into pixels (a cell each, or the worst of a block of cells on a large
//! grid) and written as PNG.

use crate::error::{Error, Result};
use crate::sim::TopView;

/// Heights on a grid of `nx × ny` cells, row-major from the bottom row (the simulator's order).
#[derive(Debug, Clone, Copy)]
pub struct RestPicture<'a> {
    /// Columns.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
    /// The stock's top at each cell.
    pub stock: &'a [f32],
    /// The lowest height the tool reaches at each cell: the rest is the stock above it, drawn
    /// where it is thicker than [`RestPicture::tol`].
    pub low: &'a [f32],
    /// The top and the bottom of the grey scale (the stock top and the floor), mm.
    pub top: f64,
    /// See [`RestPicture::top`].
    pub bottom: f64,
    /// Rest thinner than this is not drawn, mm.
    pub tol: f64,
    /// Rest this thick or more is drawn at full strength, mm.
    pub full: f64,
    /// The picture's longer side at most, pixels (blocks of cells make one pixel above it).
    pub max_side: usize,
}

/// The picture as PNG bytes.
pub fn png(p: &RestPicture) -> Result<Vec<u8>> {
    let empty = || Error::Output { what: "picture".into(), reason: "it is empty".into() };
    if p.nx == 0 || p.ny == 0 || p.stock.len() != p.nx * p.ny || p.low.len() != p.stock.len() {
        return Err(empty());
    }
    let k = p.nx.max(p.ny).div_ceil(p.max_side.max(1));
    let (w, h) = (p.nx.div_ceil(k), p.ny.div_ceil(k));
    let span = (p.top - p.bottom).max(1e-9);
    rgb_png(w, h, |bi, bj| {
        // the block: its mean height, and its thickest rest
        let (mut sum, mut n, mut t) = (0.0, 0usize, 0.0f64);
        for j in bj * k..((bj + 1) * k).min(p.ny) {
            for i in bi * k..((bi + 1) * k).min(p.nx) {
                let c = j * p.nx + i;
                let s = f64::from(p.stock[c]);
                let s = if s.is_finite() { s.clamp(p.bottom, p.top) } else { p.bottom };
                sum += s;
                n += 1;
                if f64::from(p.low[c]) < p.top {
                    t = t.max(s - f64::from(p.low[c]));
                }
            }
        }
        let v = 60.0 + 180.0 * ((sum / n as f64 - p.bottom) / span).clamp(0.0, 1.0);
        let a = if t > p.tol { (0.35 + 0.65 * (t / p.full.max(1e-9)).min(1.0)).min(1.0) } else { 0.0 };
        (v + (255.0 - v) * a, v + (140.0 - v) * a, v * (1.0 - a))
    })
}

/// A `w` × `h` picture as PNG bytes, the colour of pixel (`i`, `j`) (column, row from the
/// bottom: the grids' order) from `rgb`, 0–255 each.
fn rgb_png(w: usize, h: usize, mut rgb: impl FnMut(usize, usize) -> (f64, f64, f64)) -> Result<Vec<u8>> {
    let mut pix = resvg::tiny_skia::Pixmap::new(w as u32, h as u32)
        .ok_or_else(|| Error::Output { what: "picture".into(), reason: "it is empty".into() })?;
    let data = pix.data_mut();
    for j in 0..h {
        for i in 0..w {
            let (r, g, b) = rgb(i, j);
            // image rows top down: y up in the grid
            let o = ((h - 1 - j) * w + i) * 4;
            data[o] = r.round() as u8;
            data[o + 1] = g.round() as u8;
            data[o + 2] = b.round() as u8;
            data[o + 3] = 255;
        }
    }
    pix.encode_png()
        .map_err(|e| Error::Output { what: "picture".into(), reason: format!("cannot encode the PNG: {e}") })
}

/// Terraces thinner than this are not drawn, mm: a floor a level leaves a few hundredths above
/// (a flat's level at its highest facet) is no terrace to the eye.
const TERRACE_SHOWN: f32 = 0.05;

/// A 3D job's stock after its program from above ([`TopView`]) as PNG bytes, a pixel a block:
/// grey by height (dark is deep), amber where a terrace thicker than [`TERRACE_SHOWN`] stands
/// (stronger the thicker, full at 3 mm), red where material the tool could have cut stands
/// (full from 0.5 mm), white where there is no stock.
pub fn top_view_png(v: &TopView) -> Result<Vec<u8>> {
    let empty = || Error::Output { what: "picture".into(), reason: "it is empty".into() };
    let n = v.nx * v.ny;
    if n == 0 || v.height.len() != n || v.terrace.len() != n || v.beyond.len() != n {
        return Err(empty());
    }
    let span = (v.top - v.bottom).max(1e-9);
    rgb_png(v.nx, v.ny, |i, j| {
        let b = j * v.nx + i;
        let hgt = f64::from(v.height[b]);
        if !hgt.is_finite() {
            return (255.0, 255.0, 255.0);
        }
        let g = 60.0 + 180.0 * ((hgt - v.bottom) / span).clamp(0.0, 1.0);
        let blend = |c: (f64, f64, f64), a: f64| (g + (c.0 - g) * a, g + (c.1 - g) * a, g + (c.2 - g) * a);
        if v.beyond[b] > 0.0 {
            blend((220.0, 20.0, 20.0), (0.5 + f64::from(v.beyond[b])).min(1.0))
        } else if v.terrace[b] > TERRACE_SHOWN {
            blend((245.0, 175.0, 40.0), 0.25 + 0.5 * (f64::from(v.terrace[b]) / 3.0).min(1.0))
        } else {
            (g, g, g)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rest_is_orange_and_large_grids_are_reduced() {
        let (nx, ny) = (30, 10);
        let stock: Vec<f32> = (0..nx * ny).map(|c| if c % nx < 10 { 5.0 } else { 0.0 }).collect();
        let low = vec![0.0f32; nx * ny];
        let p = RestPicture {
            nx,
            ny,
            stock: &stock,
            low: &low,
            top: 10.0,
            bottom: 0.0,
            tol: 0.05,
            full: 5.0,
            max_side: 15,
        };
        let bytes = png(&p).expect("a picture");
        let pix = resvg::tiny_skia::Pixmap::decode_png(&bytes).expect("a PNG");
        assert_eq!((pix.width(), pix.height()), (15, 5));
        let at = |x: u32, y: u32| pix.pixel(x, y).expect("inside");
        // rest 5 mm thick: full orange; none: grey
        let (o, g) = (at(1, 1), at(10, 1));
        assert_eq!((o.red(), o.green(), o.blue()), (255, 140, 0));
        assert_eq!(g.red(), g.green());
        assert_eq!(g.green(), g.blue());
        assert!(png(&RestPicture { nx: 0, ..p }).is_err());
    }

    #[test]
    fn the_top_view_shows_terraces_amber_and_the_rest_beyond_red() {
        let v = TopView {
            nx: 4,
            ny: 1,
            x0: 0.0,
            y0: 0.0,
            side: 1.0,
            height: vec![0.0, -5.0, -5.0, f32::NAN],
            terrace: vec![0.02, 3.0, 0.0, 0.0],
            beyond: vec![0.0, 0.0, 2.0, 0.0],
            top: 0.0,
            bottom: -10.0,
        };
        let pix = resvg::tiny_skia::Pixmap::decode_png(&top_view_png(&v).expect("a picture")).expect("a PNG");
        assert_eq!((pix.width(), pix.height()), (4, 1));
        let at = |x: u32| {
            let p = pix.pixel(x, 0).expect("inside");
            (p.red(), p.green(), p.blue())
        };
        let (top, terrace, beyond, none) = (at(0), at(1), at(2), at(3));
        assert!(
            top.0 == top.1 && top.1 == top.2 && top.0 == 240,
            "the stock top light grey (a terrace too thin to see): {top:?}"
        );
        assert!(terrace.0 > terrace.1 && terrace.1 > terrace.2, "amber: {terrace:?}");
        assert_eq!(beyond, (220, 20, 20), "red");
        assert_eq!(none, (255, 255, 255), "no stock");
        assert!(top_view_png(&TopView { nx: 0, ..v }).is_err());
    }
}
