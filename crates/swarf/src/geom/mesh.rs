//! Triangle meshes (the parts of 3D jobs, read by [`crate::io::stl`]), their placement, and
//! slicing them for 3-axis z-level roughing (paper 3 §2: the "hunting planes").
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
//! The part's height map, which the simulators read, is `sim::heights::height_map`.

use super::area::Fill;
use super::{Area, DVec2, DVec3};
use rayon::prelude::*;

/// A triangle soup with what reading it found.
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    /// Triangles, vertices counter-clockwise seen from outside.
    pub tris: Vec<[DVec3; 3]>,
    /// Facets dropped as degenerate (zero area or repeated vertices).
    pub dropped: usize,
    /// True when the file was binary.
    pub binary: bool,
}

impl Mesh {
    /// Bounding box (min, max); `None` when empty.
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        let mut it = self.tris.iter().flatten();
        let first = *it.next()?;
        Some(it.fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))))
    }

    /// Applies a placement: scale, then rotations about X, Y and Z (degrees, right-handed, in
    /// that order), then a translation. A mirroring scale (negative) keeps the facets facing
    /// outwards by reversing their vertex order.
    pub fn transform(&mut self, t: &Placement) {
        let (sx, cx) = t.rotate_deg[0].to_radians().sin_cos();
        let (sy, cy) = t.rotate_deg[1].to_radians().sin_cos();
        let (sz, cz) = t.rotate_deg[2].to_radians().sin_cos();
        let f = |p: DVec3| {
            let p = p * t.scale;
            let p = DVec3::new(p.x, cx * p.y - sx * p.z, sx * p.y + cx * p.z);
            let p = DVec3::new(cy * p.x + sy * p.z, p.y, -sy * p.x + cy * p.z);
            let p = DVec3::new(cz * p.x - sz * p.y, sz * p.x + cz * p.y, p.z);
            p + t.translate
        };
        for tri in &mut self.tris {
            for v in tri.iter_mut() {
                *v = f(*v);
            }
            if t.scale < 0.0 {
                tri.swap(1, 2);
            }
        }
    }

    /// Edges used by exactly one facet (after welding vertices that coincide within `tol`): zero
    /// for a closed surface.
    pub fn open_edges(&self, tol: f64) -> usize {
        use std::collections::HashMap;
        let key = |p: DVec3| ((p.x / tol).round() as i64, (p.y / tol).round() as i64, (p.z / tol).round() as i64);
        let mut count: HashMap<_, i32> = HashMap::new();
        for t in &self.tris {
            for k in 0..3 {
                let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
                if a == b {
                    continue;
                }
                let e = if a < b { (a, b) } else { (b, a) };
                *count.entry(e).or_default() += 1;
            }
        }
        count.values().filter(|&&c| c == 1).count()
    }
}

/// Where a mesh goes: `p' = Rz·Ry·Rx·(scale·p) + translate`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Uniform scale (25.4 for a part drawn in inches, 1000 for metres).
    pub scale: f64,
    /// Rotations about X, Y, Z in degrees, applied in that order (−90 about X turns a Y-up part
    /// Z-up).
    pub rotate_deg: [f64; 3],
    /// Translation after scaling and rotating, mm.
    pub translate: DVec3,
}

impl Default for Placement {
    fn default() -> Self {
        Placement::IDENTITY
    }
}

impl Placement {
    /// The placement that moves nothing.
    pub const IDENTITY: Placement = Placement { scale: 1.0, rotate_deg: [0.0; 3], translate: DVec3::ZERO };

    /// True when it moves nothing.
    pub fn is_identity(&self) -> bool {
        *self == Placement::default()
    }
}

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

/// Heights of the facets that face straight up (flats: floors and tops of islands), highest
/// first, each once (within `tol`).
pub fn flats(mesh: &Mesh, tol: f64) -> Vec<f64> {
    let mut zs: Vec<f64> = mesh
        .tris
        .iter()
        .filter_map(|t| {
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            let len = n.length();
            // (its highest corner, not the mean: the mean of three equal heights can round a
            // unit in the last place below them, and the part's shadow strictly above such a
            // level then holds the whole flat, so the level cuts nothing)
            (len > 0.0 && n.z / len > 0.9999 && 0.5 * len > 1e-6).then(|| t[0].z.max(t[1].z).max(t[2].z))
        })
        .collect();
    zs.sort_by(|a, b| b.total_cmp(a));
    zs.dedup_by(|a, b| (*b - *a).abs() <= tol);
    zs
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A closed box [0,10]×[0,10]×[0,h] with a square hole [3,7]² down to `floor`, as facets.
    pub(crate) fn pocket_block(h: f64, floor: f64) -> Mesh {
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
    fn finds_the_flats() {
        let m = pocket_block(10.0, 4.0);
        assert_eq!(flats(&m, 1e-6), vec![10.0, 4.0]);
    }
}
