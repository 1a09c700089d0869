//! Slicing a triangle mesh for 3-axis z-level roughing (paper 3 §2: the "hunting planes").
//!
//! A flat end mill whose tip is at height `z` touches everything within its radius at or above
//! `z`, so at a level the tool must keep its axis a radius away from the **shadow** of the part
//! above the level: the projection onto the XY plane of the part's surface above `z`. Overhangs
//! seen from above are inside it (3-axis cannot go under them), and so is every island that
//! stands higher. The shadow only grows with depth, so it is built level by level from the top:
//! the shadow at `z` is the one at the level above united with the projections of the pieces of
//! the facets between the two heights ([`Shadows`]). The projections of the facets of a closed or
//! open surface tile its outline without cracks because the pieces are cut at each facet edge
//! from the edge's two end points taken in a fixed order, so neighbouring facets share the cut
//! points bit for bit.
//!
//! The part's **height map** (the highest facet over each cell centre) is what a simulator needs
//! to find gouges and rest material ([`height_map`]).

use crate::geom::area::Fill;
use crate::geom::{Area, DVec2, DVec3};
use crate::io::stl::Mesh;
use crate::sim::grid::Grid;
use rayon::prelude::*;

/// Holes of a shadow smaller than this are filled, mm².
const PINHOLE: f64 = 1e-3;

/// Shadows of a mesh at decreasing heights.
#[derive(Debug, Clone)]
pub struct Shadows<'a> {
    mesh: &'a Mesh,
    /// Facets by decreasing top, with their (bottom, top).
    order: Vec<(usize, f64, f64)>,
    z: f64,
    shadow: Area,
}

impl<'a> Shadows<'a> {
    /// Starts above the mesh (an empty shadow).
    pub fn new(mesh: &'a Mesh) -> Self {
        let mut order: Vec<(usize, f64, f64)> = mesh
            .tris
            .iter()
            .enumerate()
            .map(|(i, t)| (i, t[0].z.min(t[1].z).min(t[2].z), t[0].z.max(t[1].z).max(t[2].z)))
            .collect();
        order.sort_by(|a, b| b.2.total_cmp(&a.2));
        Shadows { mesh, order, z: f64::INFINITY, shadow: Area::empty() }
    }

    /// The shadow of the part above `z` (strictly), for `z` not above the previous call's.
    pub fn down_to(&mut self, z: f64) -> &Area {
        assert!(z <= self.z, "shadows are built downwards");
        let (zlo, zhi) = (z, self.z);
        // facets with a piece in (zlo, zhi]: top above zlo and bottom at or below zhi
        let end = self.order.partition_point(|o| o.2 > zlo);
        let rings: Vec<Vec<DVec2>> = self.order[..end]
            .par_iter()
            .filter(|o| o.1 <= zhi)
            .filter_map(|o| band_piece(&self.mesh.tris[o.0], zlo, zhi))
            .collect();
        if !rings.is_empty() {
            let band = Area::from_rings(&rings, Fill::NonZero);
            // (each band adds its cut points all along the shadow's boundary, most of them on
            // straight edges: dropped within 1e-5 mm, so the shadow's size follows its shape,
            // not the number of levels)
            // (and pinholes, where the facets' projections do not quite tile — a mesh with
            // T-junctions — pile up by the thousand: holes under 1e-3 mm² are filled, which only
            // grows the shadow, and no tool fits in them)
            let mut sh = self.shadow.union(&band).simplified(1e-5);
            for p in &mut sh.polys {
                p.holes.retain(|h| crate::geom::ring_area(h).abs() >= PINHOLE);
            }
            self.shadow = sh;
        }
        self.z = z;
        &self.shadow
    }
}

/// The projection of the piece of facet `t` with `zlo < z <= zhi`, counter-clockwise, or none
/// when it has no area.
fn band_piece(t: &[DVec3; 3], zlo: f64, zhi: f64) -> Option<Vec<DVec2>> {
    let mut poly: Vec<DVec3> = t.to_vec();
    poly = clip(&poly, zlo, true);
    if zhi.is_finite() {
        poly = clip(&poly, zhi, false);
    }
    if poly.len() < 3 {
        return None;
    }
    let mut ring: Vec<DVec2> = poly.iter().map(|p| p.truncate()).collect();
    let a = crate::geom::ring_area(&ring);
    if a.abs() < 1e-10 {
        return None;
    }
    if a < 0.0 {
        ring.reverse();
    }
    Some(ring)
}

/// Clips a convex polygon to `z > h` (`above`) or `z <= h`. The point where an edge crosses
/// `h` is computed from its end points in a fixed order, so that the facets sharing the edge
/// get the same point.
fn clip(poly: &[DVec3], h: f64, above: bool) -> Vec<DVec3> {
    let inside = |p: &DVec3| if above { p.z > h } else { p.z <= h };
    let n = poly.len();
    let mut out = Vec::with_capacity(n + 2);
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if inside(&a) {
            out.push(a);
        }
        if inside(&a) != inside(&b) {
            let (p, q) = if (a.x, a.y, a.z) < (b.x, b.y, b.z) { (a, b) } else { (b, a) };
            let t = (h - p.z) / (q.z - p.z);
            out.push(DVec3::new(p.x + (q.x - p.x) * t, p.y + (q.y - p.y) * t, h));
        }
    }
    out
}

/// The highest facet over each cell centre of `grid` (−∞ where there is none), row-major.
pub fn height_map(mesh: &Mesh, grid: &Grid) -> Vec<f32> {
    let mut h = vec![f32::NEG_INFINITY; grid.len()];
    // rows in parallel: each row scans the facets whose y-range covers it
    let mut by_row: Vec<Vec<usize>> = vec![Vec::new(); grid.ny];
    for (ti, t) in mesh.tris.iter().enumerate() {
        let ylo = t[0].y.min(t[1].y).min(t[2].y);
        let yhi = t[0].y.max(t[1].y).max(t[2].y);
        let j0 = ((ylo - grid.y0) / grid.res - 0.5).ceil().max(0.0) as usize;
        let j1 = ((yhi - grid.y0) / grid.res - 0.5).floor();
        if j1 < 0.0 {
            continue;
        }
        for row in by_row.iter_mut().take((j1 as usize + 1).min(grid.ny)).skip(j0) {
            row.push(ti);
        }
    }
    h.par_chunks_mut(grid.nx).zip(by_row.par_iter()).enumerate().for_each(|(j, (row, tris))| {
        let y = grid.y0 + (j as f64 + 0.5) * grid.res;
        for &ti in tris {
            let t = &mesh.tris[ti];
            // the facet's span on this row: intersect the line y with its edges
            let mut xs = [0.0f64; 3];
            let mut zs = [0.0f64; 3];
            let mut n = 0;
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if (a.y <= y) != (b.y <= y) {
                    let u = (y - a.y) / (b.y - a.y);
                    xs[n] = a.x + (b.x - a.x) * u;
                    zs[n] = a.z + (b.z - a.z) * u;
                    n += 1;
                    if n == 2 {
                        break;
                    }
                }
            }
            if n < 2 {
                continue;
            }
            let (xa, za, xb, zb) =
                if xs[0] <= xs[1] { (xs[0], zs[0], xs[1], zs[1]) } else { (xs[1], zs[1], xs[0], zs[0]) };
            let i0 = ((xa - grid.x0) / grid.res - 0.5).ceil().max(0.0) as usize;
            let i1 = ((xb - grid.x0) / grid.res - 0.5).floor();
            if i1 < 0.0 {
                continue;
            }
            for (i, cell) in row.iter_mut().enumerate().take((i1 as usize + 1).min(grid.nx)).skip(i0) {
                let x = grid.x0 + (i as f64 + 0.5) * grid.res;
                let z = if xb - xa > 1e-12 { za + (zb - za) * (x - xa) / (xb - xa) } else { za.max(zb) };
                *cell = cell.max(z as f32);
            }
        }
    });
    h
}

/// Heights of the facets that face straight up (flats: floors and tops of islands), highest
/// first, each once (within `tol`).
pub fn flats(mesh: &Mesh, tol: f64) -> Vec<f64> {
    let mut zs: Vec<f64> = mesh
        .tris
        .iter()
        .filter_map(|t| {
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            let len = n.length();
            (len > 0.0 && n.z / len > 0.9999 && 0.5 * len > 1e-6).then(|| (t[0].z + t[1].z + t[2].z) / 3.0)
        })
        .collect();
    zs.sort_by(|a, b| b.total_cmp(a));
    zs.dedup_by(|a, b| (*b - *a).abs() <= tol);
    zs
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed box [0,10]×[0,10]×[0,h] with a square hole [3,7]² down to `floor`, as facets.
    fn pocket_block(h: f64, floor: f64) -> Mesh {
        let mut tris = Vec::new();
        let mut quad = |a: DVec3, b: DVec3, c: DVec3, d: DVec3| {
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        };
        let v = DVec3::new;
        // top with the opening: four strips
        for (x0, y0, x1, y1) in
            [(0.0, 0.0, 10.0, 3.0), (0.0, 7.0, 10.0, 10.0), (0.0, 3.0, 3.0, 7.0), (7.0, 3.0, 10.0, 7.0)]
        {
            quad(v(x0, y0, h), v(x1, y0, h), v(x1, y1, h), v(x0, y1, h));
        }
        // pocket floor and walls
        quad(v(3.0, 3.0, floor), v(7.0, 3.0, floor), v(7.0, 7.0, floor), v(3.0, 7.0, floor));
        quad(v(3.0, 3.0, h), v(7.0, 3.0, h), v(7.0, 3.0, floor), v(3.0, 3.0, floor));
        quad(v(7.0, 3.0, h), v(7.0, 7.0, h), v(7.0, 7.0, floor), v(7.0, 3.0, floor));
        quad(v(7.0, 7.0, h), v(3.0, 7.0, h), v(3.0, 7.0, floor), v(7.0, 7.0, floor));
        quad(v(3.0, 7.0, h), v(3.0, 3.0, h), v(3.0, 3.0, floor), v(3.0, 7.0, floor));
        // bottom and outer walls
        quad(v(0.0, 0.0, 0.0), v(0.0, 10.0, 0.0), v(10.0, 10.0, 0.0), v(10.0, 0.0, 0.0));
        quad(v(0.0, 0.0, 0.0), v(10.0, 0.0, 0.0), v(10.0, 0.0, h), v(0.0, 0.0, h));
        quad(v(10.0, 0.0, 0.0), v(10.0, 10.0, 0.0), v(10.0, 10.0, h), v(10.0, 0.0, h));
        quad(v(10.0, 10.0, 0.0), v(0.0, 10.0, 0.0), v(0.0, 10.0, h), v(10.0, 10.0, h));
        quad(v(0.0, 10.0, 0.0), v(0.0, 0.0, 0.0), v(0.0, 0.0, h), v(0.0, 10.0, h));
        Mesh { tris, dropped: 0, binary: false }
    }

    #[test]
    fn shadows_grow_downwards() {
        let m = pocket_block(10.0, 4.0);
        let mut s = Shadows::new(&m);
        assert!(s.down_to(12.0).is_empty());
        // below the top: the block without the hole (a frame of 100 − 16 mm²)
        let a = s.down_to(9.0).area();
        assert!((a - 84.0).abs() < 1e-6, "{a}");
        // at the pocket floor exactly: still the frame (the floor is not above it)
        let a = s.down_to(4.0).area();
        assert!((a - 84.0).abs() < 1e-6, "{a}");
        // below it: the whole block
        let a = s.down_to(3.0).area();
        assert!((a - 100.0).abs() < 1e-6, "{a}");
        assert_eq!(s.down_to(3.0).components().len(), 1);
    }

    #[test]
    fn height_map_reads_the_top_surface() {
        let m = pocket_block(10.0, 4.0);
        let g = Grid { x0: -1.0, y0: -1.0, res: 0.5, nx: 24, ny: 24 };
        let h = height_map(&m, &g);
        let at = |x: f64, y: f64| {
            let (i, j) = g.cell_of(DVec2::new(x, y)).unwrap();
            h[j * g.nx + i]
        };
        assert_eq!(at(1.1, 1.1), 10.0);
        assert_eq!(at(5.1, 5.1), 4.0);
        assert_eq!(at(-0.6, 5.1), f32::NEG_INFINITY);
    }

    #[test]
    fn finds_the_flats() {
        let m = pocket_block(10.0, 4.0);
        assert_eq!(flats(&m, 1e-6), vec![10.0, 4.0]);
    }
}
