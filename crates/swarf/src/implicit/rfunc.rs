//! R-functions (Kalmar-Nagy & Erdim §3, eqs. 6–8, after Rvachev and Shapiro–Tsukanov): real
//! functions whose sign is fixed by the signs of their arguments, so that a Boolean formula over
//! implicit shapes (positive inside) becomes one implicit function of the whole shape.
//!
//! Three families of conjunction ("and") and disjunction ("or") pairs, negation being the change
//! of sign: `R_α` (eq. 6, with Rvachev's `2αab` under the root where the paper prints
//! `2α a² b²`), `R_0^m` (eq. 7) and `R_p` (eq. 8). They work on [`Dual`] numbers, so the composed
//! function carries its exact gradient (the oscillator needs `∇f`); at the degenerate point
//! `a = b = 0` the gradient is the limit along the diagonal, never NaN; `R_α` and `R_p` keep a
//! normalised argument normalised. The formulas, the degenerate points and the normalisation
//! are in `docs/implicit.md`.

use crate::geom::DVec2;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// A value with its gradient in the plane: `(f, ∇f)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dual {
    /// The value.
    pub v: f64,
    /// The gradient.
    pub g: DVec2,
}

impl Dual {
    /// A value with gradient `g`.
    #[inline]
    pub const fn new(v: f64, g: DVec2) -> Self {
        Self { v, g }
    }
    /// A constant (zero gradient).
    #[inline]
    pub const fn constant(v: f64) -> Self {
        Self { v, g: DVec2::ZERO }
    }
    /// `√self`; the gradient of `√0` is taken as 0 (callers guard that point themselves).
    #[inline]
    pub fn sqrt(self) -> Self {
        let s = self.v.max(0.0).sqrt();
        let d = if s > 0.0 { 0.5 / s } else { 0.0 };
        Self { v: s, g: self.g * d }
    }
    /// `self^k` for a real k (self > 0).
    #[inline]
    pub fn powf(self, k: f64) -> Self {
        let v = self.v.powf(k);
        Self { v, g: self.g * (k * self.v.powf(k - 1.0)) }
    }
    /// `self · k`.
    #[inline]
    pub fn scale(self, k: f64) -> Self {
        Self { v: self.v * k, g: self.g * k }
    }
}

impl Add for Dual {
    type Output = Dual;
    #[inline]
    fn add(self, o: Dual) -> Dual {
        Dual { v: self.v + o.v, g: self.g + o.g }
    }
}

impl Sub for Dual {
    type Output = Dual;
    #[inline]
    fn sub(self, o: Dual) -> Dual {
        Dual { v: self.v - o.v, g: self.g - o.g }
    }
}

impl Mul for Dual {
    type Output = Dual;
    #[inline]
    fn mul(self, o: Dual) -> Dual {
        Dual { v: self.v * o.v, g: self.g * o.v + o.g * self.v }
    }
}

impl Div for Dual {
    type Output = Dual;
    #[inline]
    fn div(self, o: Dual) -> Dual {
        let v = self.v / o.v;
        Dual { v, g: (self.g - o.g * v) / o.v }
    }
}

impl Neg for Dual {
    type Output = Dual;
    #[inline]
    fn neg(self) -> Dual {
        Dual { v: -self.v, g: -self.g }
    }
}

/// One family of R-functions (eqs. 6–8).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RFamily {
    /// `R_α`, `−1 < α ≤ 1` (eq. 6); α = 1 is min/max.
    Alpha(f64),
    /// `R_0^m`, `m ≥ 0` (eq. 7).
    Zero(u32),
    /// `R_p`, p even and ≥ 2 (eq. 8).
    P(u32),
}

impl Default for RFamily {
    /// `R_0` (α = 0): analytic except where both arguments vanish, and normalised.
    fn default() -> Self {
        RFamily::Alpha(0.0)
    }
}

/// The largest `m` of `R_0^m` and `p` of `R_p` accepted: beyond it the functions only lose
/// range (values like `r^m`) and gain nothing.
pub const MAX_ORDER: u32 = 32;

impl RFamily {
    /// Checks the parameter: `Err(reason)` when it is out of its family's range.
    pub fn check(&self) -> Result<(), String> {
        match *self {
            RFamily::Alpha(a) if !a.is_finite() => Err(format!("α must be a number, got {a}")),
            RFamily::Alpha(a) if a <= -1.0 || a > 1.0 => Err(format!("α must lie in (−1, 1], got {a}")),
            RFamily::Zero(m) if m > MAX_ORDER => Err(format!("m must be at most {MAX_ORDER}, got {m}")),
            RFamily::P(p) if p < 2 || p % 2 != 0 => Err(format!("p must be an even integer ≥ 2, got {p}")),
            RFamily::P(p) if p > MAX_ORDER => Err(format!("p must be at most {MAX_ORDER}, got {p}")),
            _ => Ok(()),
        }
    }

    /// R-conjunction (Boolean "and", intersection of shapes).
    pub fn and(&self, a: Dual, b: Dual) -> Dual {
        self.combine(a, b, -1.0)
    }

    /// R-disjunction (Boolean "or", union of shapes).
    pub fn or(&self, a: Dual, b: Dual) -> Dual {
        self.combine(a, b, 1.0)
    }

    /// Conjunction of values only.
    pub fn and_value(&self, a: f64, b: f64) -> f64 {
        self.and(Dual::constant(a), Dual::constant(b)).v
    }

    /// Disjunction of values only.
    pub fn or_value(&self, a: f64, b: f64) -> f64 {
        self.or(Dual::constant(a), Dual::constant(b)).v
    }

    /// `a ∧ b` (σ = −1) or `a ∨ b` (σ = +1): the value and the two partial derivatives, then
    /// the chain rule.
    fn combine(&self, a: Dual, b: Dual, sigma: f64) -> Dual {
        let (x, y) = (a.v, b.v);
        let (v, da, db) = match *self {
            RFamily::Alpha(alpha) => {
                let k = 1.0 / (1.0 + alpha);
                let s2 = ((x - y) * (x - y) + 2.0 * (1.0 - alpha) * x * y).max(0.0);
                let s = s2.sqrt();
                let (sa, sb) = if s > 0.0 {
                    ((x - alpha * y) / s, (y - alpha * x) / s)
                } else {
                    let c = (0.5 * (1.0 - alpha)).sqrt();
                    (c, c)
                };
                (k * (x + y + sigma * s), k * (1.0 + sigma * sa), k * (1.0 + sigma * sb))
            }
            RFamily::Zero(m) => {
                let r2 = x * x + y * y;
                let r = r2.sqrt();
                if r > 0.0 {
                    let base = x + y + sigma * r;
                    let rm = r.powi(m as i32);
                    // d/dx (r^m) = m r^{m−2} x
                    let drm = if m == 0 { 0.0 } else { m as f64 * r.powi(m as i32 - 2) };
                    (
                        base * rm,
                        (1.0 + sigma * x / r) * rm + base * drm * x,
                        (1.0 + sigma * y / r) * rm + base * drm * y,
                    )
                } else if m == 0 {
                    let c = 1.0 + sigma * std::f64::consts::FRAC_1_SQRT_2;
                    (0.0, c, c)
                } else {
                    (0.0, 0.0, 0.0)
                }
            }
            RFamily::P(p) => {
                let big = x.abs().max(y.abs());
                if big > 0.0 {
                    let (u, w) = (x / big, y / big);
                    let pi = p as i32;
                    let sum = u.powi(pi) + w.powi(pi);
                    let root = sum.powf(1.0 / p as f64);
                    // ∂/∂x (x^p + y^p)^{1/p} = x^{p−1} / (x^p + y^p)^{(p−1)/p} = u^{p−1} / root^{p−1}
                    let q = root.powi(pi - 1);
                    (x + y + sigma * big * root, 1.0 + sigma * u.powi(pi - 1) / q, 1.0 + sigma * w.powi(pi - 1) / q)
                } else {
                    let c = 1.0 + sigma * 2f64.powf(1.0 / p as f64 - 1.0);
                    (0.0, c, c)
                }
            }
        };
        Dual { v, g: a.g * da + b.g * db }
    }
}

/// R-negation: `¬a = −a` in every family.
#[inline]
pub fn not(a: Dual) -> Dual {
    -a
}

#[cfg(test)]
mod tests {
    use super::*;

    fn families() -> Vec<RFamily> {
        vec![
            RFamily::Alpha(1.0),
            RFamily::Alpha(0.0),
            RFamily::Alpha(0.5),
            RFamily::Alpha(-0.9),
            RFamily::Zero(0),
            RFamily::Zero(2),
            RFamily::Zero(3),
            RFamily::P(2),
            RFamily::P(4),
            RFamily::P(8),
        ]
    }

    #[test]
    fn sign_tables() {
        // the sign of a∧b is the truth of (a > 0 and b > 0); of a∨b, (a > 0 or b > 0)
        let vals = [-3.0, -0.5, -1e-3, 1e-3, 0.7, 2.0];
        for fam in families() {
            for &a in &vals {
                for &b in &vals {
                    let and = fam.and_value(a, b);
                    let or = fam.or_value(a, b);
                    assert_eq!(and > 0.0, a > 0.0 && b > 0.0, "{fam:?} and({a}, {b}) = {and}");
                    assert_eq!(and < 0.0, a < 0.0 || b < 0.0, "{fam:?} and({a}, {b}) = {and}");
                    assert_eq!(or > 0.0, a > 0.0 || b > 0.0, "{fam:?} or({a}, {b}) = {or}");
                    assert_eq!(or < 0.0, a < 0.0 && b < 0.0, "{fam:?} or({a}, {b}) = {or}");
                }
            }
            // zero on the boundary of the result: one argument zero, the other on the right side
            assert_eq!(fam.and_value(0.0, 1.0), 0.0, "{fam:?}");
            assert_eq!(fam.or_value(0.0, -1.0), 0.0, "{fam:?}");
        }
    }

    #[test]
    fn alpha_one_is_min_max_and_de_morgan() {
        let f = RFamily::Alpha(1.0);
        for (a, b) in [(1.0, 2.0), (-1.0, 3.0), (-2.0, -5.0), (4.0, 4.0), (0.0, 0.0)] {
            assert!((f.and_value(a, b) - f64::min(a, b)).abs() < 1e-12);
            assert!((f.or_value(a, b) - f64::max(a, b)).abs() < 1e-12);
        }
        // De Morgan holds exactly in every family: ¬(a ∧ b) = ¬a ∨ ¬b
        for fam in families() {
            for (a, b) in [(1.0, 2.0), (-1.0, 3.0), (-2.0, -5.0), (0.3, -0.3)] {
                let l = -fam.and_value(a, b);
                let r = fam.or_value(-a, -b);
                assert!((l - r).abs() < 1e-12 * (1.0 + l.abs()), "{fam:?} {a} {b}: {l} vs {r}");
            }
        }
        // α = 0 is x + y ∓ √(x² + y²)
        let z = RFamily::Alpha(0.0);
        assert!((z.and_value(3.0, 4.0) - 2.0).abs() < 1e-12);
        assert!((z.or_value(3.0, 4.0) - 12.0).abs() < 1e-12);
        // R_0^0 and R_2 are R_0 too
        assert!((RFamily::Zero(0).and_value(3.0, 4.0) - 2.0).abs() < 1e-12);
        assert!((RFamily::P(2).and_value(3.0, 4.0) - 2.0).abs() < 1e-12);
    }

    #[test]
    fn gradient_matches_finite_differences() {
        // a, b: two smooth functions of the plane; compare the chain-rule gradient of a∘b
        let fa = |p: DVec2| Dual::new(p.x * p.x - 0.3 * p.y + 0.2, DVec2::new(2.0 * p.x, -0.3));
        let fb = |p: DVec2| Dual::new(0.5 * p.x + p.y * p.y - 0.1, DVec2::new(0.5, 2.0 * p.y));
        let h = 1e-6;
        for fam in families() {
            for op in [0, 1] {
                let eval = |p: DVec2| if op == 0 { fam.and(fa(p), fb(p)) } else { fam.or(fa(p), fb(p)) };
                for p in [DVec2::new(0.3, 0.7), DVec2::new(-1.1, 0.4), DVec2::new(0.8, -0.7), DVec2::new(0.05, 0.2)] {
                    let d = eval(p);
                    let gx = (eval(p + DVec2::X * h).v - eval(p - DVec2::X * h).v) / (2.0 * h);
                    let gy = (eval(p + DVec2::Y * h).v - eval(p - DVec2::Y * h).v) / (2.0 * h);
                    let err = (d.g - DVec2::new(gx, gy)).length();
                    assert!(err < 1e-5 * (1.0 + d.g.length()), "{fam:?} op {op} at {p}: {} vs ({gx}, {gy})", d.g);
                }
            }
        }
    }

    #[test]
    fn degenerate_points_are_finite() {
        let a = Dual::new(0.0, DVec2::new(1.0, 0.0));
        let b = Dual::new(0.0, DVec2::new(0.0, 1.0));
        for fam in families() {
            for r in [fam.and(a, b), fam.or(a, b)] {
                assert_eq!(r.v, 0.0, "{fam:?}");
                assert!(r.g.is_finite(), "{fam:?}: {r:?}");
            }
        }
        // α = 1 at a = b ≠ 0 (the root vanishes away from the origin)
        let f = RFamily::Alpha(1.0);
        let r = f.and(Dual::new(2.0, DVec2::X), Dual::new(2.0, DVec2::Y));
        assert_eq!(r.v, 2.0);
        assert!((r.g - DVec2::new(0.5, 0.5)).length() < 1e-12);
        // huge p does not overflow
        let r = RFamily::P(32).and(Dual::constant(1e200), Dual::constant(2e200));
        assert!(r.v.is_finite() && r.v > 0.0);
    }

    #[test]
    fn normalisation_is_kept() {
        // b = 0 < a: ∇(a ∧ b) = ∇b for R_α and R_p
        let a = Dual::new(1.5, DVec2::new(0.6, 0.8));
        let b = Dual::new(0.0, DVec2::new(0.0, 1.0));
        for fam in [RFamily::Alpha(0.0), RFamily::Alpha(0.7), RFamily::Alpha(-0.5), RFamily::P(2), RFamily::P(6)] {
            let r = fam.and(a, b);
            assert!(r.v.abs() < 1e-12 && (r.g - b.g).length() < 1e-9, "{fam:?}: {r:?}");
            let r = fam.or(-a, b);
            assert!(r.v.abs() < 1e-12 && (r.g - b.g).length() < 1e-9, "{fam:?}: {r:?}");
        }
    }

    #[test]
    fn parameter_ranges() {
        assert!(RFamily::Alpha(1.0).check().is_ok());
        assert!(RFamily::Alpha(-1.0).check().is_err());
        assert!(RFamily::Alpha(1.01).check().is_err());
        assert!(RFamily::Alpha(f64::NAN).check().is_err());
        assert!(RFamily::P(3).check().is_err());
        assert!(RFamily::P(0).check().is_err());
        assert!(RFamily::P(4).check().is_ok());
        assert!(RFamily::Zero(2).check().is_ok());
        assert!(RFamily::Zero(99).check().is_err());
    }
}
