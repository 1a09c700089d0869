//! Geodesic distance maps over the floor (paper 2 §2.2): how far, on the surface, each point
//! of the parameter domain is from a side of the pocket, and where on that side the nearest
//! point is.
//!
//! The paper builds "a discrete distance map over the domain … starting from the boundaries
//! themselves with zero distance" and fills it by a breadth-first search. A search over grid
//! edges measures distance along the grid's few directions only (up to 8 % long on an
//! 8-neighbour grid), and its level lines are polygons whose gradient jumps, which would put
//! corners in an offset path. This is the fast marching method instead (Sethian; Kimmel and
//! Sethian for triangulated surfaces): the same front, accepted in order of distance from a
//! heap, but each node's distance is found across the triangles around it, from the front
//! passing between two accepted neighbours:
//!
//! ```text
//!        b ●──────● x        T(x) = min over λ ∈ [0, 1] of
//!          │    ╱               (1 − λ) T(a) + λ T(b) + |P(x) − ((1 − λ) P(a) + λ P(b))|
//!          │  ╱  the front
//!        a ●      crosses ab    P the floor's point of a node (in space, so the surface's
//!                               metric is the triangles' own)
//! ```
//!
//! The minimum has a closed form (the derivative's root, a quadratic). Eight triangles stand
//! around every node (its axis and diagonal neighbours in turn). The map is exact for a
//! plane, and first order on a curved floor. The nearest point on the side (its "foot", the
//! side's own parameter) is carried along with the same weights.
//!
//! The grid extends past the open sides, over the floor's tangent continuation, as the path
//! does; distances on the far side of the side's line are negative (a signed distance, linear
//! across the line). The map is read through a uniform bicubic B-spline over the nodes
//! (which reproduces linear functions), so the distance and its gradient are smooth (C², C¹),
//! and so is an offset built from them.
//!
//! No crate computes geodesic distance over a parametric surface patch given as a point grid
//! with carried labels, so this is written here.

use crate::geom::{DVec2, DVec3};
use crate::model::five::Side;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The floor sampled on a regular parameter grid that holds the lines u, v = 0 and 1.
pub struct Lattice {
    /// The parameter of node (0, 0).
    origin: DVec2,
    /// The parameter step in u and v.
    h: DVec2,
    nu: usize,
    nv: usize,
    pts: Vec<DVec3>,
}

/// The first node index at or below `lo` and the count to reach `hi`, for a step `h` that
/// divides 1, with two nodes more each side (for the spline's support).
fn span(lo: f64, hi: f64, h: f64) -> (i64, usize) {
    let i0 = (lo / h - 1e-9).floor() as i64 - 2;
    let i1 = (hi / h + 1e-9).ceil() as i64 + 2;
    (i0, (i1 - i0 + 1) as usize)
}

impl Lattice {
    /// The floor `pos` over `[ulo, uhi] × [vlo, vhi]` (which hold the unit square), `per_u`
    /// and `per_v` steps per unit of parameter.
    pub fn new(
        (ulo, uhi): (f64, f64),
        (vlo, vhi): (f64, f64),
        per_u: usize,
        per_v: usize,
        pos: impl Fn(f64, f64) -> DVec3 + Sync,
    ) -> Lattice {
        use rayon::prelude::*;
        let h = DVec2::new(1.0 / per_u.max(1) as f64, 1.0 / per_v.max(1) as f64);
        let (i0, nu) = span(ulo, uhi, h.x);
        let (j0, nv) = span(vlo, vhi, h.y);
        let origin = DVec2::new(i0 as f64 * h.x, j0 as f64 * h.y);
        let pts = (0..nu * nv)
            .into_par_iter()
            .map(|k| {
                let (i, j) = (k % nu, k / nu);
                pos(origin.x + i as f64 * h.x, origin.y + j as f64 * h.y)
            })
            .collect();
        Lattice { origin, h, nu, nv, pts }
    }

    /// The number of nodes.
    pub fn len(&self) -> usize {
        self.pts.len()
    }

    fn param(&self, i: usize, j: usize) -> DVec2 {
        self.origin + DVec2::new(i as f64 * self.h.x, j as f64 * self.h.y)
    }
}

/// A signed geodesic distance from one side, and the side's parameter of the nearest point.
pub struct DistanceMap {
    origin: DVec2,
    h: DVec2,
    nu: usize,
    nv: usize,
    d: Vec<f64>,
    foot: Vec<f64>,
}

/// The map at a point.
#[derive(Debug, Clone, Copy)]
pub struct Reading {
    /// The signed distance, mm (positive inside the pocket).
    pub d: f64,
    /// Its gradient in the parameter (mm per unit of u, v).
    pub grad: DVec2,
    /// The side's parameter of the nearest point.
    pub foot: f64,
}

/// An f64 ordered for the heap (distances are never NaN).
#[derive(PartialEq)]
struct Key(f64);
impl Eq for Key {}
impl PartialOrd for Key {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Key {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}

/// The eight neighbours in turn round a node: consecutive pairs span its triangles.
const RING: [(i64, i64); 8] = [(1, 0), (1, 1), (0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1)];

impl DistanceMap {
    /// The distance from `side` over the lattice, by fast marching.
    pub fn from_side(lat: &Lattice, side: Side) -> DistanceMap {
        let (nu, nv) = (lat.nu, lat.nv);
        let n = nu * nv;
        let mut d = vec![f64::INFINITY; n];
        let mut foot = vec![0.0; n];
        let mut done = vec![false; n];
        let mut heap = BinaryHeap::new();
        // the side's line of nodes
        let on_line = |p: DVec2| match side {
            Side::U0 => p.x.abs() < 1e-9,
            Side::U1 => (p.x - 1.0).abs() < 1e-9,
            Side::V0 => p.y.abs() < 1e-9,
            Side::V1 => (p.y - 1.0).abs() < 1e-9,
        };
        let along = |p: DVec2| if matches!(side, Side::U0 | Side::U1) { p.y } else { p.x };
        for j in 0..nv {
            for i in 0..nu {
                let p = lat.param(i, j);
                if on_line(p) {
                    let k = j * nu + i;
                    d[k] = 0.0;
                    foot[k] = along(p);
                    heap.push(Reverse((Key(0.0), k)));
                }
            }
        }
        let nb = |k: usize, (di, dj): (i64, i64)| -> Option<usize> {
            let (i, j) = ((k % nu) as i64 + di, (k / nu) as i64 + dj);
            (i >= 0 && j >= 0 && (i as usize) < nu && (j as usize) < nv).then(|| j as usize * nu + i as usize)
        };
        while let Some(Reverse((Key(t), k))) = heap.pop() {
            if done[k] || t > d[k] {
                continue;
            }
            done[k] = true;
            for off in RING {
                let Some(x) = nb(k, off) else { continue };
                if done[x] {
                    continue;
                }
                // the best over the triangles and edges round x with accepted corners
                let px = lat.pts[x];
                let ring: [Option<usize>; 8] = RING.map(|o| nb(x, o).filter(|&y| done[y]));
                let (mut best, mut bf) = (d[x], foot[x]);
                for q in 0..8 {
                    let Some(a) = ring[q] else { continue };
                    let ta = d[a] + (lat.pts[a] - px).length();
                    if ta < best {
                        (best, bf) = (ta, foot[a]);
                    }
                    let Some(b) = ring[(q + 1) % 8] else { continue };
                    if let Some((t, l)) = across(px, lat.pts[a], lat.pts[b], d[a], d[b])
                        && t < best
                    {
                        (best, bf) = (t, foot[a] + l * (foot[b] - foot[a]));
                    }
                }
                if best < d[x] {
                    d[x] = best;
                    foot[x] = bf;
                    heap.push(Reverse((Key(best), x)));
                }
            }
        }
        // negative past the side's line
        for j in 0..nv {
            for i in 0..nu {
                let p = lat.param(i, j);
                let beyond = match side {
                    Side::U0 => p.x < 0.0,
                    Side::U1 => p.x > 1.0,
                    Side::V0 => p.y < 0.0,
                    Side::V1 => p.y > 1.0,
                };
                if beyond {
                    d[j * nu + i] = -d[j * nu + i];
                }
            }
        }
        DistanceMap { origin: lat.origin, h: lat.h, nu, nv, d, foot }
    }

    /// The map at `p` (the B-spline over the nodes; held at the grid's edge).
    pub fn at(&self, p: DVec2) -> Reading {
        let s = (p - self.origin) / self.h;
        let (i, j) = (s.x.floor(), s.y.floor());
        let (bu, du) = basis(s.x - i);
        let (bv, dv) = basis(s.y - j);
        let (i, j) = (i as i64, j as i64);
        let (mut d, mut gu, mut gv, mut f) = (0.0, 0.0, 0.0, 0.0);
        for b in 0..4 {
            let jj = (j - 1 + b as i64).clamp(0, self.nv as i64 - 1) as usize;
            for a in 0..4 {
                let ii = (i - 1 + a as i64).clamp(0, self.nu as i64 - 1) as usize;
                let (c, fc) = (self.d[jj * self.nu + ii], self.foot[jj * self.nu + ii]);
                d += bu[a] * bv[b] * c;
                gu += du[a] * bv[b] * c;
                gv += bu[a] * dv[b] * c;
                f += bu[a] * bv[b] * fc;
            }
        }
        Reading { d, grad: DVec2::new(gu / self.h.x, gv / self.h.y), foot: f }
    }
}

/// The uniform cubic B-spline's four weights at `t` in [0, 1) and their derivatives.
fn basis(t: f64) -> ([f64; 4], [f64; 4]) {
    let (t2, t3, m) = (t * t, t * t * t, 1.0 - t);
    (
        [m * m * m / 6.0, (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0, (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0, t3 / 6.0],
        [-0.5 * m * m, (3.0 * t2 - 4.0 * t) / 2.0, (-3.0 * t2 + 2.0 * t + 1.0) / 2.0, 0.5 * t2],
    )
}

/// The distance at `x` from a front through the accepted `a` and `b`, and where between them
/// (0 at a, 1 at b) it comes from, when that is strictly between them.
fn across(x: DVec3, pa: DVec3, pb: DVec3, ta: f64, tb: f64) -> Option<(f64, f64)> {
    // minimise f(λ) = ta + λ Δ + |e + λ δ|: f′ = 0 where (B + Aλ) = −Δ |e + λδ|
    let (e, dl, dt) = (pa - x, pb - pa, tb - ta);
    let (a, b, c) = (dl.dot(dl), e.dot(dl), e.dot(e));
    let room = a - dt * dt;
    if a <= 1e-24 || room <= 1e-12 * a {
        return None;
    }
    let l = -b / a - dt * ((a * c - b * b).max(0.0) / (a * room)).sqrt();
    (l > 0.0 && l < 1.0).then(|| (ta + l * dt + (e + dl * l).length(), l))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(w: f64, l: f64) -> Lattice {
        // a sheared plane: u runs along x (l mm), v across at 60° (w mm)
        let sh = DVec3::new(0.5, 0.75f64.sqrt(), 0.0);
        Lattice::new((-0.2, 1.0), (0.0, 1.0), 60, 40, move |u, v| DVec3::new(l * u, 0.0, 0.0) + sh * (w * v))
    }

    #[test]
    fn a_plane_is_exact_and_its_gradient_unit() {
        let (w, l) = (20.0, 50.0);
        let lat = plane(w, l);
        let m = DistanceMap::from_side(&lat, Side::V0);
        let h = 0.75f64.sqrt() * w;
        for &(u, v) in &[(0.3, 0.5), (0.77, 0.13), (0.05, 0.93), (-0.1, 0.4)] {
            let r = m.at(DVec2::new(u, v));
            // the distance to the line v = 0 is the height across it
            assert!((r.d - h * v).abs() < 1e-6, "{u} {v}: {} against {}", r.d, h * v);
            assert!((r.grad.y - h).abs() < 1e-6 && r.grad.x.abs() < 1e-6, "{:?}", r.grad);
            // the foot: the point of v = 0 straight across, in u
            let foot = u + 0.5 * w * v / l;
            assert!((r.foot - foot).abs() < 1e-6, "{} against {foot}", r.foot);
        }
        // past the open side the sign changes for u0's map
        let m = DistanceMap::from_side(&lat, Side::U0);
        let r = m.at(DVec2::new(-0.1, 0.5));
        assert!(r.d < 0.0 && (r.d + 0.75f64.sqrt() * 0.1 * l).abs() < 0.05, "{}", r.d);
    }

    #[test]
    fn on_a_cylinder_the_distance_is_the_arc() {
        // the floor a half cylinder of radius 10 across v, 40 long in u: the distance from
        // v = 0 is the arc length π·10·v
        let lat = Lattice::new((0.0, 1.0), (0.0, 1.0), 40, 80, |u, v| {
            let t = std::f64::consts::PI * v;
            DVec3::new(40.0 * u, -10.0 * t.cos(), -10.0 * t.sin())
        });
        let m = DistanceMap::from_side(&lat, Side::V0);
        for &v in &[0.25, 0.5, 0.8] {
            let r = m.at(DVec2::new(0.5, v));
            let want = std::f64::consts::PI * 10.0 * v;
            assert!((r.d - want).abs() < 0.02 * want, "{v}: {} against {want}", r.d);
        }
    }

    #[test]
    fn a_triangle_front_is_exact() {
        // a plane front at distance x·n: a and b on it give x's distance exactly
        let n = DVec3::new(0.6, 0.8, 0.0);
        let (pa, pb, x) = (DVec3::new(0.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.9, 1.0, 0.0));
        let (t, l) = across(x, pa, pb, pa.dot(n), pb.dot(n)).expect("inside");
        assert!((t - x.dot(n)).abs() < 1e-12 && l > 0.0 && l < 1.0, "{t} {l}");
    }
}
