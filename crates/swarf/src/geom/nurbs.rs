//! NURBS curves and tensor-product surfaces: evaluation with first and second derivatives, the
//! first fundamental form and its bounds over the domain, and the closest point, for the 5-axis
//! pocketing of paper 2 §2 (Elber, Cohen, Drake), whose floor and top are C¹ NURBS surfaces
//! S(u, v) over the unit square.
//!
//! The basis functions and their derivatives are Piegl & Tiller's (*The NURBS Book*, 2nd ed.,
//! algorithms A2.1 and A2.3), the rational derivatives by the quotient rule on homogeneous
//! coordinates (eq. 4.20): with `A(u, v) = Σ Nᵢ(u) Nⱼ(v) wᵢⱼ Pᵢⱼ` and `w(u, v) = Σ Nᵢ Nⱼ wᵢⱼ`,
//! `S = A / w`, `S_u = (A_u − w_u S) / w`, `S_uu = (A_uu − 2 w_u S_u − w_uu S) / w`,
//! `S_uv = (A_uv − w_u S_v − w_v S_u − w_uv S) / w`.
//!
//! Written here rather than taken from a crate: the Rust NURBS crates (`curvo`, `truck-geometry`)
//! bring their own linear algebra (nalgebra, cgmath) and a modelling kernel's worth of code,
//! where swarf needs evaluation to second order and the metric of the parameterisation in
//! `glam`'s types, which is a hundred lines over the two textbook algorithms.

use glam::{DVec2, DVec3};

/// What is wrong with a curve's or surface's definition.
pub type Invalid = String;

/// A clamped knot vector with its degree, checked.
#[derive(Debug, Clone, PartialEq)]
struct Knots {
    p: usize,
    k: Vec<f64>,
}

impl Knots {
    /// Checks `k` for `n` control points of degree `p`: `n + p + 1` finite knots,
    /// non-decreasing, clamped (the first and last repeated `p + 1` times), no interior knot
    /// repeated more than `p` times, a domain of positive length.
    fn new(p: usize, k: Vec<f64>, n: usize, what: &str) -> Result<Knots, Invalid> {
        if p == 0 {
            return Err(format!("{what}: the degree must be at least 1"));
        }
        if n < p + 1 {
            return Err(format!("{what}: degree {p} needs at least {} control points, found {n}", p + 1));
        }
        if k.len() != n + p + 1 {
            return Err(format!(
                "{what}: {n} control points of degree {p} need {} knots, found {}",
                n + p + 1,
                k.len()
            ));
        }
        if let Some(i) = k.iter().position(|x| !x.is_finite()) {
            return Err(format!("{what}: knot {i} is not a finite number"));
        }
        if let Some(i) = k.windows(2).position(|w| w[1] < w[0]) {
            return Err(format!("{what}: knot {} ({}) is below the one before it ({})", i + 1, k[i + 1], k[i]));
        }
        let (a, b) = (k[0], k[k.len() - 1]);
        // (finite, checked above)
        if b <= a {
            return Err(format!("{what}: the knots span no interval ({a} to {b})"));
        }
        if k[..=p].iter().any(|&x| x != a) || k[k.len() - p - 1..].iter().any(|&x| x != b) {
            return Err(format!("{what}: not clamped (the first and last knots must each appear {} times)", p + 1));
        }
        let mut run = 1;
        for i in p + 2..k.len() - p - 1 {
            run = if k[i] == k[i - 1] { run + 1 } else { 1 };
            if run > p {
                return Err(format!("{what}: the interior knot {} is repeated more than the degree ({p})", k[i]));
            }
        }
        Ok(Knots { p, k })
    }

    /// The parameter range.
    fn range(&self) -> (f64, f64) {
        (self.k[0], self.k[self.k.len() - 1])
    }

    /// The knot span holding `u` (A2.1), `u` clamped to the range.
    fn span(&self, u: f64) -> usize {
        let n = self.k.len() - self.p - 2; // the last control point's index
        if u >= self.k[n + 1] {
            return n;
        }
        if u <= self.k[self.p] {
            return self.p;
        }
        // the last span whose start is at or below u
        self.k[..=n + 1].partition_point(|&x| x <= u) - 1
    }

    /// The `p + 1` non-zero basis functions at `u` in span `s` and their first `d` derivatives
    /// (A2.3): `out[k][j]` is the k-th derivative of `N_{s−p+j}`.
    fn ders(&self, s: usize, u: f64, d: usize) -> [[f64; 4]; 3] {
        let p = self.p;
        debug_assert!(p <= 3 && d <= 2);
        let k = &self.k;
        let mut ndu = [[0.0; 4]; 4];
        let (mut left, mut right) = ([0.0; 4], [0.0; 4]);
        ndu[0][0] = 1.0;
        for j in 1..=p {
            left[j] = u - k[s + 1 - j];
            right[j] = k[s + j] - u;
            let mut saved = 0.0;
            for r in 0..j {
                ndu[j][r] = right[r + 1] + left[j - r];
                let t = ndu[r][j - 1] / ndu[j][r];
                ndu[r][j] = saved + right[r + 1] * t;
                saved = left[j - r] * t;
            }
            ndu[j][j] = saved;
        }
        let mut out = [[0.0; 4]; 3];
        for j in 0..=p {
            out[0][j] = ndu[j][p];
        }
        for r in 0..=p {
            let mut a = [[0.0; 4]; 2];
            let (mut s1, mut s2) = (0usize, 1usize);
            a[0][0] = 1.0;
            for kk in 1..=d.min(p) {
                let mut dd = 0.0;
                let rk = r as isize - kk as isize;
                let pk = p - kk;
                if r >= kk {
                    a[s2][0] = a[s1][0] / ndu[pk + 1][rk as usize];
                    dd = a[s2][0] * ndu[rk as usize][pk];
                }
                let j1 = if rk >= -1 { 1 } else { (-rk) as usize };
                let j2 = if r as isize - 1 <= pk as isize { kk - 1 } else { p - r };
                for j in j1..=j2 {
                    let idx = (rk + j as isize) as usize;
                    a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][idx];
                    dd += a[s2][j] * ndu[idx][pk];
                }
                if r <= pk {
                    a[s2][kk] = -a[s1][kk - 1] / ndu[pk + 1][r];
                    dd += a[s2][kk] * ndu[r][pk];
                }
                out[kk][r] = dd;
                std::mem::swap(&mut s1, &mut s2);
            }
        }
        let mut f = p as f64;
        for (kk, row) in out.iter_mut().enumerate().skip(1).take(d) {
            for v in row.iter_mut().take(p + 1) {
                *v *= f;
            }
            f *= p as f64 - kk as f64;
        }
        out
    }
}

/// The most degree swarf evaluates (cubic: the C¹ and C² surfaces CAD exports).
pub const MAX_DEGREE: usize = 3;

/// A NURBS curve.
#[derive(Debug, Clone, PartialEq)]
pub struct NurbsCurve {
    knots: Knots,
    points: Vec<DVec3>,
    weights: Vec<f64>,
}

/// A point of a curve with its first and second derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvePoint {
    /// C(u).
    pub p: DVec3,
    /// C'(u).
    pub d1: DVec3,
    /// C''(u).
    pub d2: DVec3,
}

fn check_weights(w: &[f64], what: &str) -> Result<(), Invalid> {
    match w.iter().position(|w| !(w.is_finite() && *w > 0.0)) {
        Some(i) => Err(format!("{what}: weight {i} ({}) must be a positive number", w[i])),
        None => Ok(()),
    }
}

fn check_points(p: &[DVec3], what: &str) -> Result<(), Invalid> {
    match p.iter().position(|p| !p.is_finite()) {
        Some(i) => Err(format!("{what}: control point {i} is not finite")),
        None => Ok(()),
    }
}

impl NurbsCurve {
    /// A curve of `degree` (1 to [`MAX_DEGREE`]) through `knots` (clamped), with `weights`
    /// (all 1 when `None`).
    pub fn new(degree: usize, knots: Vec<f64>, points: Vec<DVec3>, weights: Option<Vec<f64>>) -> Result<Self, Invalid> {
        if degree > MAX_DEGREE {
            return Err(format!("curve: degree {degree} is above {MAX_DEGREE}"));
        }
        let knots = Knots::new(degree, knots, points.len(), "curve")?;
        check_points(&points, "curve")?;
        let weights = weights.unwrap_or_else(|| vec![1.0; points.len()]);
        if weights.len() != points.len() {
            return Err(format!("curve: {} weights for {} control points", weights.len(), points.len()));
        }
        check_weights(&weights, "curve")?;
        Ok(NurbsCurve { knots, points, weights })
    }

    /// The parameter range.
    pub fn range(&self) -> (f64, f64) {
        self.knots.range()
    }

    /// C and its first two derivatives at `u` (clamped to the range).
    // (the indices are the algorithm's: basis function j weighs control point s − p + j)
    #[allow(clippy::needless_range_loop)]
    pub fn eval(&self, u: f64) -> CurvePoint {
        let (a, b) = self.range();
        let u = u.clamp(a, b);
        let p = self.knots.p;
        let s = self.knots.span(u);
        let n = self.knots.ders(s, u, 2);
        // homogeneous sums and their derivatives
        let (mut aw, mut w) = ([DVec3::ZERO; 3], [0.0; 3]);
        for j in 0..=p {
            let i = s - p + j;
            for k in 0..3 {
                aw[k] += self.points[i] * (n[k][j] * self.weights[i]);
                w[k] += n[k][j] * self.weights[i];
            }
        }
        let c = aw[0] / w[0];
        let d1 = (aw[1] - c * w[1]) / w[0];
        let d2 = (aw[2] - d1 * (2.0 * w[1]) - c * w[2]) / w[0];
        CurvePoint { p: c, d1, d2 }
    }
}

/// A tensor-product NURBS surface S(u, v).
#[derive(Debug, Clone, PartialEq)]
pub struct NurbsSurface {
    ku: Knots,
    kv: Knots,
    /// Control points, `points[i * nv + j]`, i along u.
    points: Vec<DVec3>,
    weights: Vec<f64>,
    nv: usize,
}

/// A point of a surface with its partial derivatives to the second order.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// S(u, v).
    pub p: DVec3,
    /// ∂S/∂u.
    pub su: DVec3,
    /// ∂S/∂v.
    pub sv: DVec3,
    /// ∂²S/∂u².
    pub suu: DVec3,
    /// ∂²S/∂u∂v.
    pub suv: DVec3,
    /// ∂²S/∂v².
    pub svv: DVec3,
}

impl SurfacePoint {
    /// The unit normal `S_u × S_v / |S_u × S_v|` (zero where the surface is degenerate).
    pub fn normal(&self) -> DVec3 {
        self.su.cross(self.sv).normalize_or_zero()
    }

    /// The first fundamental form (E, F, G): `|dS|² = E du² + 2F du dv + G dv²`.
    pub fn first_form(&self) -> (f64, f64, f64) {
        (self.su.dot(self.su), self.su.dot(self.sv), self.sv.dot(self.sv))
    }

    /// The least and greatest stretch of the parameterisation here: the square roots of the
    /// first fundamental form's eigenvalues, so that a step `d` in (u, v) moves the point by
    /// between `a_min |d|` and `a_max |d|` to first order.
    pub fn stretch(&self) -> (f64, f64) {
        let (e, f, g) = self.first_form();
        let mean = 0.5 * (e + g);
        let dev = (0.25 * (e - g) * (e - g) + f * f).sqrt();
        ((mean - dev).max(0.0).sqrt(), (mean + dev).sqrt())
    }
}

impl NurbsSurface {
    /// A surface of degrees `degree_u`, `degree_v` (1 to [`MAX_DEGREE`]) over clamped knots,
    /// with `points[i][j]` (i along u, j along v) and `weights` of the same shape (all 1 when
    /// `None`).
    pub fn new(
        degree_u: usize,
        degree_v: usize,
        knots_u: Vec<f64>,
        knots_v: Vec<f64>,
        points: Vec<Vec<DVec3>>,
        weights: Option<Vec<Vec<f64>>>,
    ) -> Result<Self, Invalid> {
        if degree_u.max(degree_v) > MAX_DEGREE {
            return Err(format!("surface: degree {} is above {MAX_DEGREE}", degree_u.max(degree_v)));
        }
        let nu = points.len();
        let nv = points.first().map_or(0, Vec::len);
        if let Some(i) = points.iter().position(|row| row.len() != nv) {
            return Err(format!("surface: control point row {i} has {} points, row 0 has {nv}", points[i].len()));
        }
        let ku = Knots::new(degree_u, knots_u, nu, "surface, u")?;
        let kv = Knots::new(degree_v, knots_v, nv, "surface, v")?;
        let flat: Vec<DVec3> = points.into_iter().flatten().collect();
        check_points(&flat, "surface")?;
        let weights = match weights {
            None => vec![1.0; flat.len()],
            Some(w) => {
                if w.len() != nu || w.iter().any(|row| row.len() != nv) {
                    return Err(format!("surface: the weights are not {nu} × {nv}, as the control points"));
                }
                w.into_iter().flatten().collect()
            }
        };
        check_weights(&weights, "surface")?;
        Ok(NurbsSurface { ku, kv, points: flat, weights, nv })
    }

    /// The same surface with u running the other way: S'(u, v) = S(u0 + u1 − u, v).
    pub fn reversed_u(&self) -> NurbsSurface {
        let (a, b) = self.ku.range();
        let k: Vec<f64> = self.ku.k.iter().rev().map(|&x| a + b - x).collect();
        let nu = self.points.len() / self.nv;
        let mut points = Vec::with_capacity(self.points.len());
        let mut weights = Vec::with_capacity(self.points.len());
        for i in (0..nu).rev() {
            points.extend_from_slice(&self.points[i * self.nv..(i + 1) * self.nv]);
            weights.extend_from_slice(&self.weights[i * self.nv..(i + 1) * self.nv]);
        }
        NurbsSurface { ku: Knots { p: self.ku.p, k }, kv: self.kv.clone(), points, weights, nv: self.nv }
    }

    /// The same surface with u and v exchanged: S'(u, v) = S(v, u).
    pub fn transposed(&self) -> NurbsSurface {
        let nu = self.points.len() / self.nv;
        let mut points = Vec::with_capacity(self.points.len());
        let mut weights = Vec::with_capacity(self.points.len());
        for j in 0..self.nv {
            for i in 0..nu {
                points.push(self.points[i * self.nv + j]);
                weights.push(self.weights[i * self.nv + j]);
            }
        }
        NurbsSurface { ku: self.kv.clone(), kv: self.ku.clone(), points, weights, nv: nu }
    }

    /// The parameter domain, ((u0, u1), (v0, v1)).
    pub fn domain(&self) -> ((f64, f64), (f64, f64)) {
        (self.ku.range(), self.kv.range())
    }

    /// S and its partial derivatives to the second order at (u, v) (clamped to the domain).
    // (the indices are the algorithm's: basis functions i, j weigh control point
    // (s_u − p + i, s_v − q + j))
    pub fn eval(&self, u: f64, v: f64) -> SurfacePoint {
        let ((u0, u1), (v0, v1)) = self.domain();
        self.eval_continued(u.clamp(u0, u1), v.clamp(v0, v1))
    }

    /// S at (u, v) as [`NurbsSurface::eval`], but past the domain's edges the edge spans'
    /// polynomials continued (the way a B-spline evaluator that only clamps the knot span
    /// extrapolates).
    #[allow(clippy::needless_range_loop)]
    pub fn eval_continued(&self, u: f64, v: f64) -> SurfacePoint {
        let (p, q) = (self.ku.p, self.kv.p);
        let (su, sv) = (self.ku.span(u), self.kv.span(v));
        let nu = self.ku.ders(su, u, 2);
        let nv = self.kv.ders(sv, v, 2);
        // A^(k,l) and w^(k,l) for k + l ≤ 2, as [00, 10, 01, 20, 11, 02]
        const ORDERS: [(usize, usize); 6] = [(0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2)];
        let (mut a, mut w) = ([DVec3::ZERO; 6], [0.0; 6]);
        for i in 0..=p {
            for j in 0..=q {
                let idx = (su - p + i) * self.nv + (sv - q + j);
                let (pt, wt) = (self.points[idx], self.weights[idx]);
                for (o, &(k, l)) in ORDERS.iter().enumerate() {
                    let b = nu[k][i] * nv[l][j] * wt;
                    a[o] += pt * b;
                    w[o] += b;
                }
            }
        }
        let s = a[0] / w[0];
        let s_u = (a[1] - s * w[1]) / w[0];
        let s_v = (a[2] - s * w[2]) / w[0];
        let s_uu = (a[3] - s_u * (2.0 * w[1]) - s * w[3]) / w[0];
        let s_uv = (a[4] - s_v * w[1] - s_u * w[2] - s * w[4]) / w[0];
        let s_vv = (a[5] - s_v * (2.0 * w[2]) - s * w[5]) / w[0];
        SurfacePoint { p: s, su: s_u, sv: s_v, suu: s_uu, suv: s_uv, svv: s_vv }
    }

    /// The least and greatest stretch ([`SurfacePoint::stretch`]) over the domain, sampled on
    /// an `n × n` grid of points (the paper's a_min and a_max, which turn a distance on the
    /// surface into one in the domain).
    pub fn stretch_bounds(&self, n: usize) -> (f64, f64) {
        let ((u0, u1), (v0, v1)) = self.domain();
        let n = n.max(2);
        let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
        for i in 0..n {
            for j in 0..n {
                let u = u0 + (u1 - u0) * i as f64 / (n - 1) as f64;
                let v = v0 + (v1 - v0) * j as f64 / (n - 1) as f64;
                let (a, b) = self.eval(u, v).stretch();
                lo = lo.min(a);
                hi = hi.max(b);
            }
        }
        (lo, hi)
    }

    /// The point of the surface closest to `x`: its parameters and the point. The nearest of a
    /// 17 × 17 grid of samples is refined by Newton's method on `(S − x)·S_u = (S − x)·S_v = 0`
    /// with steps kept inside the domain; exact for the nearest point's basin, which the grid
    /// finds unless the surface folds back within a grid cell.
    pub fn closest_point(&self, x: DVec3) -> (DVec2, DVec3) {
        let ((u0, u1), (v0, v1)) = self.domain();
        let n = 16;
        let mut best = (DVec2::new(u0, v0), f64::INFINITY);
        for i in 0..=n {
            for j in 0..=n {
                let uv = DVec2::new(u0 + (u1 - u0) * i as f64 / n as f64, v0 + (v1 - v0) * j as f64 / n as f64);
                let d = (self.eval(uv.x, uv.y).p - x).length_squared();
                if d < best.1 {
                    best = (uv, d);
                }
            }
        }
        self.closest_point_near(x, best.0)
    }

    /// The point of the surface closest to `x` in the basin of `start`: Newton's method from
    /// there, as in [`NurbsSurface::closest_point`] (for a point near one already found).
    pub fn closest_point_near(&self, x: DVec3, start: DVec2) -> (DVec2, DVec3) {
        let ((u0, u1), (v0, v1)) = self.domain();
        let mut uv = DVec2::new(start.x.clamp(u0, u1), start.y.clamp(v0, v1));
        for _ in 0..50 {
            let s = self.eval(uv.x, uv.y);
            let r = s.p - x;
            // the gradient of ½|S − x|² and its Hessian
            let g = DVec2::new(r.dot(s.su), r.dot(s.sv));
            let h00 = s.su.dot(s.su) + r.dot(s.suu);
            let h01 = s.su.dot(s.sv) + r.dot(s.suv);
            let h11 = s.sv.dot(s.sv) + r.dot(s.svv);
            let det = h00 * h11 - h01 * h01;
            let step = if det > 0.0 && h00 > 0.0 {
                DVec2::new(h11 * g.x - h01 * g.y, h00 * g.y - h01 * g.x) / det
            } else {
                // not convex here: a gradient step scaled by the metric
                g / (h00.abs() + h11.abs()).max(1e-300)
            };
            let next = DVec2::new((uv.x - step.x).clamp(u0, u1), (uv.y - step.y).clamp(v0, v1));
            // (never uphill: halve a step that would be; none found downhill ends the search)
            let mut cand = next;
            let mut k = 0;
            while (self.eval(cand.x, cand.y).p - x).length_squared() > r.length_squared() && k < 30 {
                cand = uv + (cand - uv) * 0.5;
                k += 1;
            }
            let moved = if k == 30 { 0.0 } else { (cand - uv).length() };
            uv = if k == 30 { uv } else { cand };
            if moved < 1e-14 * (u1 - u0 + v1 - v0) {
                break;
            }
        }
        (uv, self.eval(uv.x, uv.y).p)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_1_SQRT_2;

    /// A quarter of a cylinder of radius `r` about the z axis, `h` high: rational quadratic in
    /// u (weights 1, √½, 1), linear in v.
    fn quarter_cylinder(r: f64, h: f64) -> NurbsSurface {
        let arc = [DVec3::new(r, 0.0, 0.0), DVec3::new(r, r, 0.0), DVec3::new(0.0, r, 0.0)];
        let points = arc.iter().map(|p| vec![*p, *p + DVec3::Z * h]).collect();
        let weights = vec![vec![1.0, 1.0], vec![FRAC_1_SQRT_2, FRAC_1_SQRT_2], vec![1.0, 1.0]];
        NurbsSurface::new(2, 1, vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0], vec![0.0, 0.0, 1.0, 1.0], points, Some(weights))
            .expect("a valid surface")
    }

    /// A bicubic patch over [0, 1]² with an interior knot each way and a wavy height.
    fn wavy() -> NurbsSurface {
        let n = 5;
        let points = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| {
                        let (x, y) = (10.0 * i as f64, 8.0 * j as f64);
                        DVec3::new(x + 0.7 * j as f64, y, 2.0 * ((i * j) as f64).sin())
                    })
                    .collect()
            })
            .collect();
        let weights = (0..n).map(|i| (0..n).map(|j| 1.0 + 0.3 * ((i + 2 * j) % 3) as f64).collect()).collect();
        let k = vec![0.0, 0.0, 0.0, 0.0, 0.4, 1.0, 1.0, 1.0, 1.0];
        NurbsSurface::new(3, 3, k.clone(), k, points, Some(weights)).expect("a valid surface")
    }

    #[test]
    fn reversing_and_transposing_move_the_parameters_only() {
        for s in [wavy(), quarter_cylinder(2.0, 3.0)] {
            let (r, t) = (s.reversed_u(), s.transposed());
            for (u, v) in [(0.0, 0.0), (0.13, 0.71), (0.5, 0.5), (0.9, 0.2), (1.0, 1.0)] {
                assert!((r.eval(u, v).p - s.eval(1.0 - u, v).p).length() < 1e-12);
                assert!((r.eval(u, v).su + s.eval(1.0 - u, v).su).length() < 1e-9);
                assert!((t.eval(v, u).p - s.eval(u, v).p).length() < 1e-12);
                assert!((t.eval(v, u).sv - s.eval(u, v).su).length() < 1e-9);
            }
        }
    }

    #[test]
    fn the_continuation_past_the_edge_is_the_edge_span_s_polynomial() {
        let s = wavy();
        for v in [0.0, 0.3, 0.8] {
            // the same inside, and C¹ across the edge: a step out matches the derivative there
            assert_eq!(s.eval_continued(0.4, v).p, s.eval(0.4, v).p);
            let (e, h) = (s.eval(0.0, v), 1e-5);
            let out = s.eval_continued(-h, v);
            assert!((out.p - (e.p - e.su * h)).length() < 1e-6, "{v}");
            assert!((out.su - e.su).length() < 1e-3 * e.su.length().max(1.0));
        }
    }

    #[test]
    fn a_rational_quadric_is_exact() {
        let (r, h) = (7.0, 3.0);
        let s = quarter_cylinder(r, h);
        for i in 0..=20 {
            for j in 0..=4 {
                let (u, v) = (i as f64 / 20.0, j as f64 / 4.0);
                let e = s.eval(u, v);
                assert!((e.p.truncate().length() - r).abs() < 1e-12, "{u} {v}: {}", e.p);
                assert!((e.p.z - h * v).abs() < 1e-12);
                // the normal is radial (outward or inward)
                let radial = e.p.truncate().normalize().extend(0.0);
                assert!((e.normal().dot(radial).abs() - 1.0).abs() < 1e-12);
                // along v the surface is straight and h long
                assert!((e.sv - DVec3::Z * h).length() < 1e-12 && e.svv.length() < 1e-12);
            }
        }
        // the ends of the arc and its tangents there
        assert!((s.eval(0.0, 0.0).p - DVec3::new(r, 0.0, 0.0)).length() < 1e-12);
        assert!((s.eval(1.0, 0.0).p - DVec3::new(0.0, r, 0.0)).length() < 1e-12);
        assert!(s.eval(0.0, 0.0).su.normalize().abs_diff_eq(DVec3::Y, 1e-12));
    }

    #[test]
    fn derivatives_agree_with_finite_differences() {
        let s = wavy();
        let h = 1e-5;
        for &(u, v) in &[(0.1, 0.2), (0.39, 0.77), (0.41, 0.41), (0.9, 0.05), (0.55, 0.95)] {
            let e = s.eval(u, v);
            let du = |f: &dyn Fn(&SurfacePoint) -> DVec3| (f(&s.eval(u + h, v)) - f(&s.eval(u - h, v))) / (2.0 * h);
            let dv = |f: &dyn Fn(&SurfacePoint) -> DVec3| (f(&s.eval(u, v + h)) - f(&s.eval(u, v - h))) / (2.0 * h);
            let close = |a: DVec3, b: DVec3| (a - b).length() <= 1e-5 * (1.0 + b.length());
            assert!(close(e.su, du(&|x| x.p)), "S_u at {u} {v}: {} {}", e.su, du(&|x| x.p));
            assert!(close(e.sv, dv(&|x| x.p)), "S_v at {u} {v}");
            assert!(close(e.suu, du(&|x| x.su)), "S_uu at {u} {v}: {} {}", e.suu, du(&|x| x.su));
            assert!(close(e.suv, dv(&|x| x.su)), "S_uv at {u} {v}");
            assert!(close(e.suv, du(&|x| x.sv)), "S_vu at {u} {v}");
            assert!(close(e.svv, dv(&|x| x.sv)), "S_vv at {u} {v}");
        }
    }

    #[test]
    fn a_bilinear_patch_and_its_metric() {
        // the plane z = 0 stretched 30 along u and 10 along v: a_min 10, a_max 30
        let points = vec![
            vec![DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.0, 10.0, 0.0)],
            vec![DVec3::new(30.0, 0.0, 0.0), DVec3::new(30.0, 10.0, 0.0)],
        ];
        let k = vec![0.0, 0.0, 1.0, 1.0];
        let s = NurbsSurface::new(1, 1, k.clone(), k, points, None).expect("valid");
        let e = s.eval(0.25, 0.5);
        assert!((e.p - DVec3::new(7.5, 5.0, 0.0)).length() < 1e-12);
        assert_eq!(e.first_form(), (900.0, 0.0, 100.0));
        let (lo, hi) = s.stretch_bounds(9);
        assert!((lo - 10.0).abs() < 1e-12 && (hi - 30.0).abs() < 1e-12, "{lo} {hi}");
        // on the cylinder the least stretch is the height (along v), and the greatest is at
        // least the mean speed along u (the quarter circle's length over the unit domain)
        let c = quarter_cylinder(7.0, 3.0);
        let (lo, hi) = c.stretch_bounds(33);
        let mean = 7.0 * std::f64::consts::FRAC_PI_2;
        assert!(lo <= 3.0 + 1e-12 && hi >= mean, "{lo} {hi}");
    }

    #[test]
    fn the_closest_point_is_the_foot_of_the_perpendicular() {
        let c = quarter_cylinder(7.0, 3.0);
        for &(x, z) in &[(DVec3::new(20.0, 20.0, 0.0), 1.5), (DVec3::new(1.0, 3.0, 0.0), 0.2)] {
            let q = x + DVec3::Z * z;
            let (uv, p) = c.closest_point(q);
            let want = x.normalize() * 7.0 + DVec3::Z * z;
            assert!((p - want).length() < 1e-9, "{q}: {p} against {want} at {uv}");
        }
        // a point beyond the edge goes to the edge
        let (uv, p) = c.closest_point(DVec3::new(3.0, 3.0, 10.0));
        assert!((uv.y - 1.0).abs() < 1e-12 && (p.z - 3.0).abs() < 1e-12, "{uv} {p}");
        // on the wavy patch: the point's offset along the normal comes back to it
        let s = wavy();
        for &(u, v) in &[(0.3, 0.6), (0.7, 0.2)] {
            let e = s.eval(u, v);
            let (uv, _) = s.closest_point(e.p + e.normal() * 0.5);
            assert!((uv - DVec2::new(u, v)).length() < 1e-8, "{uv} against {u} {v}");
        }
    }

    #[test]
    fn a_curve_and_its_derivatives() {
        // the quarter circle as a curve: C'' points to the centre with |C'|²/r
        let arc = vec![DVec3::new(5.0, 0.0, 0.0), DVec3::new(5.0, 5.0, 0.0), DVec3::new(0.0, 5.0, 0.0)];
        let c = NurbsCurve::new(2, vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0], arc, Some(vec![1.0, FRAC_1_SQRT_2, 1.0]))
            .expect("valid");
        for i in 0..=10 {
            let e = c.eval(i as f64 / 10.0);
            assert!((e.p.length() - 5.0).abs() < 1e-12);
            assert!(e.d1.dot(e.p).abs() < 1e-9);
            // the normal part of C'' is the curvature 1/5 times |C'|²
            let t = e.d1.normalize();
            let normal = e.d2 - t * e.d2.dot(t);
            assert!((normal.length() - e.d1.length_squared() / 5.0).abs() < 1e-9);
            assert!(normal.dot(e.p) < 0.0);
        }
    }

    #[test]
    fn bad_definitions_are_refused_with_the_reason() {
        let k = vec![0.0, 0.0, 1.0, 1.0];
        let row = || vec![DVec3::ZERO, DVec3::X];
        let cases: Vec<(Result<NurbsSurface, Invalid>, &str)> = vec![
            (NurbsSurface::new(1, 1, vec![0.0, 1.0, 1.0], k.clone(), vec![row(), row()], None), "need 4 knots"),
            (NurbsSurface::new(1, 1, vec![0.0, 0.5, 1.0, 1.0], k.clone(), vec![row(), row()], None), "not clamped"),
            (NurbsSurface::new(1, 1, vec![0.0, 0.0, -1.0, -1.0], k.clone(), vec![row(), row()], None), "below"),
            (NurbsSurface::new(1, 1, k.clone(), k.clone(), vec![row(), vec![DVec3::ZERO]], None), "row 1"),
            (NurbsSurface::new(4, 1, k.clone(), k.clone(), vec![row(), row()], None), "above 3"),
            (
                NurbsSurface::new(
                    1,
                    1,
                    k.clone(),
                    k.clone(),
                    vec![row(), row()],
                    Some(vec![vec![1.0, 0.0], vec![1.0, 1.0]]),
                ),
                "positive",
            ),
            (
                NurbsSurface::new(1, 1, k.clone(), k.clone(), vec![row(), vec![DVec3::NAN, DVec3::X]], None),
                "not finite",
            ),
            (
                NurbsSurface::new(
                    1,
                    1,
                    vec![0.0, 0.0, 0.5, 0.5, 1.0, 1.0],
                    k.clone(),
                    vec![row(), row(), row(), row()],
                    None,
                ),
                "repeated more",
            ),
        ];
        for (got, want) in cases {
            match got {
                Err(e) => assert!(e.contains(want), "{e:?} should say {want:?}"),
                Ok(_) => panic!("accepted; should say {want:?}"),
            }
        }
    }
}
