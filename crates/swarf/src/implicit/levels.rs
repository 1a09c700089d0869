//! Level sets of an implicit function by marching squares (drawn by [`crate::plot::shape`]).
//!
//! Marching squares is written here rather than taken from a crate: the crates that do it
//! (`contour`, `isoline`) are not in the project's registry cache and come with their own
//! geometry types, while the oscillator also needs the gradient along each contour (to choose
//! ζ per level), which they do not carry. Saddle cells are split by the mean of the four
//! corners.

use super::rfunc::Dual;
use super::shape::Field;
use crate::geom::DVec2;
use rayon::prelude::*;

/// `f` and `∇f` sampled on a regular grid of `(nx + 1) × (ny + 1)` nodes over `lo`–`hi`.
#[derive(Debug, Clone)]
pub struct Grid {
    /// Lower corner.
    pub lo: DVec2,
    /// Node spacing in x and y.
    pub step: DVec2,
    /// Cells in x.
    pub nx: usize,
    /// Cells in y.
    pub ny: usize,
    /// Row-major samples, `(ny + 1) × (nx + 1)`.
    pub vals: Vec<Dual>,
}

/// A contour piece: two end points with the gradient interpolated at each.
pub type ContourSeg = [(DVec2, DVec2); 2];

impl Grid {
    /// Samples `field` with about `n` cells along the longer side (rows in parallel; the result
    /// does not depend on the thread count).
    pub fn sample(field: &dyn Field, lo: DVec2, hi: DVec2, n: usize) -> Grid {
        let size = (hi - lo).max(DVec2::splat(1e-12));
        let n = n.max(2);
        let cell = size.max_element() / n as f64;
        let nx = ((size.x / cell).round() as usize).max(2);
        let ny = ((size.y / cell).round() as usize).max(2);
        let step = DVec2::new(size.x / nx as f64, size.y / ny as f64);
        let vals: Vec<Dual> = (0..=ny)
            .into_par_iter()
            .flat_map_iter(|j| (0..=nx).map(move |i| (i, j)))
            .map(|(i, j)| field.eval(lo + step * DVec2::new(i as f64, j as f64)))
            .collect();
        Grid { lo, step, nx, ny, vals }
    }

    /// `field` over its bounds padded by 2 % each side, about 256 cells along the longer side:
    /// the grid the oscillator's ζ table ([`super::oscillator`]) and the spiral strategy's core
    /// level read their level sets from (one grid serves both, and every spiral from the same
    /// field). `None` for an unbounded field.
    pub fn of_field(field: &dyn Field) -> Option<Grid> {
        let (lo, hi) = field.bounds()?;
        let pad = (hi - lo) * 0.02;
        Some(Grid::sample(field, lo - pad, hi + pad, 256))
    }

    fn at(&self, i: usize, j: usize) -> Dual {
        self.vals[j * (self.nx + 1) + i]
    }

    /// The largest sample.
    pub fn max(&self) -> f64 {
        self.vals.iter().map(|d| d.v).fold(f64::NEG_INFINITY, f64::max)
    }

    /// The level set `f = level` as segments (marching squares).
    pub fn contour(&self, level: f64) -> Vec<ContourSeg> {
        let mut out = Vec::new();
        for j in 0..self.ny {
            for i in 0..self.nx {
                // corners counter-clockwise: (i, j), (i+1, j), (i+1, j+1), (i, j+1)
                let ids = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
                let c = ids.map(|(a, b)| self.at(a, b));
                let pos = ids.map(|(a, b)| self.lo + self.step * DVec2::new(a as f64, b as f64));
                let above = c.map(|d| d.v > level);
                let mask = above.iter().enumerate().fold(0u8, |m, (k, &a)| m | ((a as u8) << k));
                if mask == 0 || mask == 15 {
                    continue;
                }
                // the crossing on edge k (corner k to corner k+1)
                let cross = |k: usize| {
                    let (a, b) = (c[k], c[(k + 1) % 4]);
                    let t = ((level - a.v) / (b.v - a.v)).clamp(0.0, 1.0);
                    (pos[k].lerp(pos[(k + 1) % 4], t), a.g.lerp(b.g, t))
                };
                let edges: &[(usize, usize)] = match mask {
                    1 | 14 => &[(3, 0)],
                    2 | 13 => &[(0, 1)],
                    3 | 12 => &[(3, 1)],
                    4 | 11 => &[(1, 2)],
                    6 | 9 => &[(0, 2)],
                    7 | 8 => &[(2, 3)],
                    5 | 10 => {
                        let centre = c.iter().map(|d| d.v).sum::<f64>() / 4.0 > level;
                        // corners 0 and 2 are on one side; join them through the centre or not
                        if (mask == 5) == centre { &[(0, 1), (2, 3)] } else { &[(3, 0), (1, 2)] }
                    }
                    _ => &[],
                };
                for &(e0, e1) in edges {
                    out.push([cross(e0), cross(e1)]);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::implicit::RFamily;
    use crate::implicit::shape::{Node, Shape};

    #[test]
    fn contour_of_a_circle_lies_on_it() {
        let s = Shape { family: RFamily::default(), root: Node::Circle { c: DVec2::new(1.0, 1.0), r: 4.0 } };
        let g = Grid::sample(&s, DVec2::splat(-5.0), DVec2::splat(7.0), 120);
        let segs = g.contour(0.0);
        let len: f64 = segs.iter().map(|[(a, _), (b, _)]| (*b - *a).length()).sum();
        assert!((len - std::f64::consts::TAU * 4.0).abs() < 0.01, "{len}");
        for [(a, ga), _] in &segs {
            assert!(((*a - DVec2::new(1.0, 1.0)).length() - 4.0).abs() < 2e-3);
            assert!((ga.length() - 1.0).abs() < 0.02);
        }
    }
}
