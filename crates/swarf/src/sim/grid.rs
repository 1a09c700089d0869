//! The raster grid: square cells of side `res`, each standing for its centre point, and an
//! exact even-odd scanline fill of polygon areas into it.

use crate::geom::{Area, DVec2};

/// A uniform grid of `nx × ny` cells starting at `(x0, y0)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// x of the left edge of column 0.
    pub x0: f64,
    /// y of the bottom edge of row 0.
    pub y0: f64,
    /// Cell size, mm.
    pub res: f64,
    /// Columns.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
}

impl Grid {
    /// A grid of cell size `res` covering `[lo, hi]` grown by `pad`, aligned so that `align`
    /// (normally the stock's lower-left corner) lies on cell boundaries.
    pub fn covering(lo: DVec2, hi: DVec2, pad: f64, res: f64, align: DVec2) -> Grid {
        let lo = lo - DVec2::splat(pad);
        let hi = hi + DVec2::splat(pad);
        let kx = ((align.x - lo.x) / res).ceil();
        let ky = ((align.y - lo.y) / res).ceil();
        let x0 = align.x - kx * res;
        let y0 = align.y - ky * res;
        let nx = ((hi.x - x0) / res).ceil().max(1.0) as usize;
        let ny = ((hi.y - y0) / res).ceil().max(1.0) as usize;
        Grid { x0, y0, res, nx, ny }
    }

    /// The values of `v` (over this grid) at the cells of `to` (cells of one size aligned
    /// alike, or the centres of blocks of them), `none` where this grid has no cell.
    pub fn resample(&self, v: &[f32], to: &Grid, none: f32) -> Vec<f32> {
        let mut out = Vec::with_capacity(to.len());
        for j in 0..to.ny {
            for i in 0..to.nx {
                out.push(self.cell_of(to.center(i, j)).map_or(none, |(a, b)| v[b * self.nx + a]));
            }
        }
        out
    }

    /// Number of cells (`usize::MAX` when that does not fit: a grid a hostile cell size asks
    /// for is refused by its size, not wrapped round to a small one).
    pub fn len(&self) -> usize {
        self.nx.saturating_mul(self.ny)
    }

    /// True for a grid without cells.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Centre of cell `(i, j)`.
    #[inline]
    pub fn center(&self, i: usize, j: usize) -> DVec2 {
        DVec2::new(self.x0 + (i as f64 + 0.5) * self.res, self.y0 + (j as f64 + 0.5) * self.res)
    }

    /// The cell containing `p`, if inside the grid.
    #[inline]
    pub fn cell_of(&self, p: DVec2) -> Option<(usize, usize)> {
        // (no floor: for the non-negative values kept it is the truncation of `as`, and a
        // call to it is a large part of the planning time where SSE4.1 is not assumed)
        let fx = (p.x - self.x0) / self.res;
        let fy = (p.y - self.y0) / self.res;
        if !(fx >= 0.0 && fy >= 0.0) {
            return None;
        }
        let (i, j) = (fx as usize, fy as usize);
        if i >= self.nx || j >= self.ny {
            return None;
        }
        Some((i, j))
    }

    /// Index ranges `(i0..=i1, j0..=j1)` of cells whose centres may lie in `[lo, hi]`.
    #[inline]
    pub fn range(&self, lo: DVec2, hi: DVec2) -> Option<(usize, usize, usize, usize)> {
        let i0 = ceil_i((lo.x - self.x0) / self.res - 0.5);
        let j0 = ceil_i((lo.y - self.y0) / self.res - 0.5);
        let i1 = floor_i((hi.x - self.x0) / self.res - 0.5);
        let j1 = floor_i((hi.y - self.y0) / self.res - 0.5);
        if i1 < 0 || j1 < 0 || i0 >= self.nx as i64 || j0 >= self.ny as i64 || i0 > i1 || j0 > j1 {
            return None;
        }
        Some((i0.max(0) as usize, (i1 as usize).min(self.nx - 1), j0.max(0) as usize, (j1 as usize).min(self.ny - 1)))
    }

    /// Exact even-odd fill of `area` at cell centres.
    pub fn rasterize(&self, area: &Area) -> Vec<bool> {
        let mut mask = vec![false; self.len()];
        let mut rows: Vec<Vec<f64>> = vec![Vec::new(); self.ny];
        for ring in area.rings() {
            let n = ring.len();
            for k in 0..n {
                let a = ring[k];
                let b = ring[(k + 1) % n];
                if a.y == b.y {
                    continue;
                }
                let (lo, hi) = if a.y < b.y { (a, b) } else { (b, a) };
                // rows whose centre y lies in [lo.y, hi.y)
                let j0 = ((lo.y - self.y0) / self.res - 0.5).ceil().max(0.0);
                let j1 = ((hi.y - self.y0) / self.res - 0.5).ceil().min(self.ny as f64);
                let mut j = j0 as usize;
                while (j as f64) < j1 {
                    let yc = self.y0 + (j as f64 + 0.5) * self.res;
                    if yc >= lo.y && yc < hi.y {
                        let x = lo.x + (yc - lo.y) / (hi.y - lo.y) * (hi.x - lo.x);
                        rows[j].push(x);
                    }
                    j += 1;
                }
            }
        }
        for (j, xs) in rows.iter_mut().enumerate() {
            xs.sort_by(f64::total_cmp);
            for pair in xs.chunks(2) {
                if pair.len() < 2 {
                    continue;
                }
                let i0 = ((pair[0] - self.x0) / self.res - 0.5).ceil().max(0.0) as usize;
                let i1f = ((pair[1] - self.x0) / self.res - 0.5).ceil().min(self.nx as f64);
                let i1 = if i1f < 0.0 { 0 } else { i1f as usize };
                for i in i0..i1 {
                    mask[j * self.nx + i] = true;
                }
            }
        }
        mask
    }
}

/// ⌈x⌉ as an integer, for finite `x` within `i64` (as `x.ceil() as i64`). `f64::ceil` is a
/// libm call on the x86-64 baseline (no SSE4.1), and the simulator's row scans make millions.
#[inline]
pub fn ceil_i(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) < x { t + 1 } else { t }
}

/// ⌊x⌋ as an integer, for finite `x` within `i64` (see [`ceil_i`]).
#[inline]
pub fn floor_i(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x { t - 1 } else { t }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resample_reads_the_cells_two_grids_share() {
        let lo = DVec2::ZERO;
        let frame = Grid::covering(lo, DVec2::new(4.0, 3.0), 0.0, 1.0, lo);
        let inner = Grid::covering(DVec2::new(1.0, 1.0), DVec2::new(3.0, 2.0), 0.0, 1.0, lo);
        assert_eq!((inner.nx, inner.ny), (2, 1));
        let v: Vec<f32> = (0..inner.len()).map(|k| k as f32 + 1.0).collect();
        let got = inner.resample(&v, &frame, -1.0);
        let mut want = vec![-1.0; frame.len()];
        want[frame.nx + 1] = 1.0;
        want[frame.nx + 2] = 2.0;
        assert_eq!(got, want);
        assert_eq!(frame.resample(&got, &inner, 0.0), v);
    }

    #[test]
    fn fill_counts_cell_centres() {
        let g = Grid::covering(DVec2::new(0.0, 0.0), DVec2::new(10.0, 10.0), 1.0, 0.5, DVec2::ZERO);
        let a = Area::rect(0.0, 0.0, 10.0, 5.0);
        let m = g.rasterize(&a);
        assert_eq!(m.iter().filter(|b| **b).count(), 20 * 10);
        let fine = Grid::covering(DVec2::new(0.0, 0.0), DVec2::new(10.0, 10.0), 1.0, 0.05, DVec2::ZERO);
        let c = Area::disk(DVec2::new(5.0, 5.0), 4.0, 0.001);
        let n = fine.rasterize(&c).iter().filter(|b| **b).count() as f64 * 0.0025;
        assert!((n - std::f64::consts::PI * 16.0).abs() < 0.1, "{n}");
        assert_eq!(g.cell_of(DVec2::new(0.1, 0.1)), Some((2, 2)));
    }

    #[test]
    fn integer_ceil_and_floor_match_std() {
        for x in [-3.0, -2.5, -1.0000001, -0.5, -0.0, 0.0, 1e-300, 0.5, 1.0, 2.9999999, 7.5, 1e12 + 0.5] {
            assert_eq!(ceil_i(x), x.ceil() as i64, "ceil {x}");
            assert_eq!(floor_i(x), x.floor() as i64, "floor {x}");
        }
    }
}
