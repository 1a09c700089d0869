//! A small implicit-shape language (Kalmar-Nagy & Erdim §3, Figure 5): primitives whose function
//! is positive inside, zero on the boundary and normalised there (`|∇f| = 1`), combined by the
//! R-functions of [`super::rfunc`].
//!
//! The primitives are the circle, the half-plane, the box (axis-aligned or rotated) and the
//! polygon (for large polygons and polygons with holes, [`super::region::AreaField`]); and, or
//! and not apply the shape's [`RFamily`]. A shape file is JSON, and every error in it names the
//! file and the JSON place:
//!
//! ```json
//! { "rfunction": { "alpha": 0.0 },
//!   "shape": { "and": [ { "circle": { "c": [0, 0], "r": 10 } },
//!                       { "not": { "box": { "c": [4, 0], "size": [6, 3], "angle": 30 } } } ] } }
//! ```
//!
//! The primitives' functions and the file format in full are in `docs/implicit.md`.

// `!(x > y)` is meant: a NaN must fail every check
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::rfunc::{Dual, RFamily};
use crate::error::{Error, Result};
use crate::geom::DVec2;
use serde_json::{Map, Value};
use std::path::Path;

/// A function of the plane with its gradient, positive inside a shape and zero on its boundary.
pub trait Field: Sync {
    /// `(f(p), ∇f(p))`.
    fn eval(&self, p: DVec2) -> Dual;
    /// A box holding the region `f ≥ 0`, when it is bounded.
    fn bounds(&self) -> Option<(DVec2, DVec2)>;
}

/// One node of a shape.
#[derive(Debug, Clone, PartialEq)]
pub enum Node {
    /// Disk of centre `c`, radius `r > 0`.
    Circle {
        /// Centre.
        c: DVec2,
        /// Radius.
        r: f64,
    },
    /// Half-plane through `p` whose unit normal `n` points inside.
    HalfPlane {
        /// A point of the boundary line.
        p: DVec2,
        /// Unit inward normal.
        n: DVec2,
    },
    /// Box of centre `c`, half-sizes `half`, turned by `angle` radians counter-clockwise.
    Rect {
        /// Centre.
        c: DVec2,
        /// Half width and half height, both > 0.
        half: DVec2,
        /// Rotation, radians.
        angle: f64,
    },
    /// Polygon by its signed distance (positive inside).
    Polygon(Vec<DVec2>),
    /// R-conjunction of the children.
    And(Vec<Node>),
    /// R-disjunction of the children.
    Or(Vec<Node>),
    /// R-negation.
    Not(Box<Node>),
}

/// A shape: a node tree and the R-function family of its combinators.
#[derive(Debug, Clone, PartialEq)]
pub struct Shape {
    /// The family of And / Or.
    pub family: RFamily,
    /// The tree.
    pub root: Node,
}

impl Shape {
    /// `(f(p), ∇f(p))`.
    pub fn eval(&self, p: DVec2) -> Dual {
        self.root.eval(&self.family, p)
    }

    /// Parses a shape file's text; `file` names it in errors.
    pub fn from_json(text: &str, file: &Path) -> Result<Shape> {
        let v: Value = serde_json::from_str(text).map_err(|e| {
            Error::input(file, format!("line {} column {}", e.line(), e.column()), format!("not JSON: {e}"))
        })?;
        Parser { file }.shape(&v)
    }

    /// Reads and parses a shape file.
    pub fn load(path: &Path) -> Result<Shape> {
        let bytes = std::fs::read(path).map_err(|e| Error::input(path, "file", format!("cannot read: {e}")))?;
        let text = String::from_utf8(bytes).map_err(|e| {
            Error::input(path, format!("byte {}", e.utf8_error().valid_up_to()), "not UTF-8 text: a shape file is JSON")
        })?;
        Shape::from_json(&text, path)
    }
}

impl Field for Shape {
    fn eval(&self, p: DVec2) -> Dual {
        Shape::eval(self, p)
    }
    fn bounds(&self) -> Option<(DVec2, DVec2)> {
        self.root.bounds()
    }
}

fn rot(v: DVec2, angle: f64) -> DVec2 {
    let (s, c) = angle.sin_cos();
    DVec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

impl Node {
    /// `(f(p), ∇f(p))` with the family `fam` for the combinators.
    pub fn eval(&self, fam: &RFamily, p: DVec2) -> Dual {
        match self {
            Node::Circle { c, r } => {
                let d = p - *c;
                Dual::new((r * r - d.length_squared()) / (2.0 * r), -d / *r)
            }
            Node::HalfPlane { p: o, n } => Dual::new(n.dot(p - *o), *n),
            Node::Rect { c, half, angle } => {
                let u = rot(p - *c, -angle);
                let sx = Dual::new((half.x * half.x - u.x * u.x) / (2.0 * half.x), DVec2::new(-u.x / half.x, 0.0));
                let sy = Dual::new((half.y * half.y - u.y * u.y) / (2.0 * half.y), DVec2::new(0.0, -u.y / half.y));
                let f = RFamily::Alpha(0.0).and(sx, sy);
                Dual::new(f.v, rot(f.g, *angle))
            }
            Node::Polygon(pts) => polygon_sdf(pts, p),
            Node::And(ch) => fold(ch, fam, p, |a, b| fam.and(a, b)),
            Node::Or(ch) => fold(ch, fam, p, |a, b| fam.or(a, b)),
            Node::Not(n) => super::rfunc::not(n.eval(fam, p)),
        }
    }

    /// A box holding the node's positive set, when bounded.
    pub fn bounds(&self) -> Option<(DVec2, DVec2)> {
        match self {
            Node::Circle { c, r } => Some((*c - DVec2::splat(*r), *c + DVec2::splat(*r))),
            Node::HalfPlane { .. } | Node::Not(_) => None,
            Node::Rect { c, half, angle } => {
                let e = DVec2::new(
                    (half.x * angle.cos()).abs() + (half.y * angle.sin()).abs(),
                    (half.x * angle.sin()).abs() + (half.y * angle.cos()).abs(),
                );
                Some((*c - e, *c + e))
            }
            Node::Polygon(pts) => {
                Some(pts.iter().fold((DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)), |(lo, hi), q| {
                    (lo.min(*q), hi.max(*q))
                }))
            }
            Node::And(ch) => ch.iter().filter_map(Node::bounds).reduce(|(l0, h0), (l1, h1)| (l0.max(l1), h0.min(h1))),
            Node::Or(ch) => {
                let mut acc: Option<(DVec2, DVec2)> = None;
                for c in ch {
                    let (l, h) = c.bounds()?;
                    acc = Some(match acc {
                        None => (l, h),
                        Some((l0, h0)) => (l0.min(l), h0.max(h)),
                    });
                }
                acc
            }
        }
    }
}

fn fold(ch: &[Node], fam: &RFamily, p: DVec2, op: impl Fn(Dual, Dual) -> Dual) -> Dual {
    let mut it = ch.iter();
    let first = it.next().map(|n| n.eval(fam, p)).unwrap_or(Dual::constant(0.0));
    it.fold(first, |acc, n| op(acc, n.eval(fam, p)))
}

/// Signed distance to a closed polygon (either orientation), positive inside, with its gradient;
/// on the boundary the gradient is the inward normal of the nearest edge.
fn polygon_sdf(pts: &[DVec2], p: DVec2) -> Dual {
    let n = pts.len();
    if n < 3 {
        return Dual::constant(-1.0);
    }
    let ccw = crate::geom::ring_area(pts) >= 0.0;
    let mut best = f64::INFINITY;
    let mut q = pts[0];
    let mut edge = (pts[0], pts[1]);
    let mut inside = false;
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (pts[j], pts[i]);
        let ab = b - a;
        let l2 = ab.length_squared();
        let t = if l2 > 0.0 { ((p - a).dot(ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
        let c = a + ab * t;
        let d = (p - c).length_squared();
        if d < best {
            best = d;
            q = c;
            edge = (a, b);
        }
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
            if p.x < x {
                inside = !inside;
            }
        }
        j = i;
    }
    let d = best.sqrt();
    if d > 0.0 {
        let g = (p - q) / d;
        if inside { Dual::new(d, g) } else { Dual::new(-d, -g) }
    } else {
        let t = (edge.1 - edge.0).normalize_or_zero();
        let left = DVec2::new(-t.y, t.x);
        Dual::new(0.0, if ccw { left } else { -left })
    }
}

/// The maximum of `f` over the box `lo`–`hi`: the best point of a 64 × 64 grid, refined by
/// gradient ascent with a step that grows on success and halves on failure. `None` when `f` is
/// nowhere positive on the grid. Deterministic.
pub fn maximum(field: &dyn Field, lo: DVec2, hi: DVec2) -> Option<(DVec2, f64)> {
    let n = 64;
    let size = hi - lo;
    let mut best = (lo, f64::NEG_INFINITY);
    for j in 0..=n {
        for i in 0..=n {
            let p = lo + size * DVec2::new(i as f64 / n as f64, j as f64 / n as f64);
            let v = field.eval(p).v;
            if v > best.1 {
                best = (p, v);
            }
        }
    }
    if best.1.is_nan() || best.1 <= 0.0 {
        return None;
    }
    let (mut p, mut fv) = best;
    let mut step = size.max_element() / n as f64;
    let stop = size.max_element() * 1e-10;
    for _ in 0..2000 {
        if step < stop {
            break;
        }
        let g = field.eval(p).g;
        if !(g.length() > 0.0) {
            break;
        }
        let q = p + g.normalize() * step;
        let fq = field.eval(q).v;
        if fq > fv {
            p = q;
            fv = fq;
            step *= 1.5;
        } else {
            step *= 0.5;
        }
    }
    Some((p, fv))
}

/// JSON walker with places for errors.
struct Parser<'a> {
    file: &'a Path,
}

impl Parser<'_> {
    fn err(&self, place: &str, reason: impl Into<String>) -> Error {
        Error::input(self.file, place, reason)
    }

    fn obj<'v>(&self, v: &'v Value, place: &str, keys: &[&str]) -> Result<&'v Map<String, Value>> {
        let m = v.as_object().ok_or_else(|| self.err(place, format!("expected an object, got {}", kind(v))))?;
        for k in m.keys() {
            if !keys.contains(&k.as_str()) {
                return Err(self.err(place, format!("unknown key \"{k}\" (expected one of {})", keys.join(", "))));
            }
        }
        Ok(m)
    }

    fn req<'v>(&self, m: &'v Map<String, Value>, key: &str, place: &str) -> Result<&'v Value> {
        m.get(key).ok_or_else(|| self.err(place, format!("missing \"{key}\"")))
    }

    fn num(&self, v: &Value, place: &str) -> Result<f64> {
        let x = v.as_f64().ok_or_else(|| self.err(place, format!("expected a number, got {}", kind(v))))?;
        if !x.is_finite() {
            return Err(self.err(place, "not a finite number"));
        }
        Ok(x)
    }

    fn point(&self, v: &Value, place: &str) -> Result<DVec2> {
        let a = v.as_array().ok_or_else(|| self.err(place, format!("expected [x, y], got {}", kind(v))))?;
        if a.len() != 2 {
            return Err(self.err(place, format!("expected [x, y], got {} numbers", a.len())));
        }
        Ok(DVec2::new(self.num(&a[0], &format!("{place}[0]"))?, self.num(&a[1], &format!("{place}[1]"))?))
    }

    fn uint(&self, v: &Value, place: &str) -> Result<u32> {
        v.as_u64()
            .and_then(|x| u32::try_from(x).ok())
            .ok_or_else(|| self.err(place, format!("expected a non-negative integer, got {v}")))
    }

    fn shape(&self, v: &Value) -> Result<Shape> {
        let m = self.obj(v, "top level", &["rfunction", "shape"])?;
        let family = match m.get("rfunction") {
            None => RFamily::default(),
            Some(f) => self.family(f, "rfunction")?,
        };
        let root = self.node(self.req(m, "shape", "top level")?, "shape")?;
        Ok(Shape { family, root })
    }

    fn family(&self, v: &Value, place: &str) -> Result<RFamily> {
        if v.as_str() == Some("min") {
            return Ok(RFamily::Alpha(1.0));
        }
        let m = self.obj(v, place, &["alpha", "zero", "p"])?;
        if m.len() != 1 {
            return Err(self.err(place, "give exactly one of \"alpha\", \"zero\", \"p\""));
        }
        let (k, x) = m.iter().next().expect("one key");
        let at = format!("{place}.{k}");
        let fam = match k.as_str() {
            "alpha" => RFamily::Alpha(self.num(x, &at)?),
            "zero" => RFamily::Zero(self.uint(x, &at)?),
            _ => RFamily::P(self.uint(x, &at)?),
        };
        fam.check().map_err(|r| self.err(&at, r))?;
        Ok(fam)
    }

    fn node(&self, v: &Value, place: &str) -> Result<Node> {
        let m = self.obj(v, place, &["circle", "halfplane", "box", "polygon", "and", "or", "not"])?;
        if m.len() != 1 {
            return Err(self.err(place, format!("a shape node has exactly one key, got {}", m.len())));
        }
        let (k, x) = m.iter().next().expect("one key");
        let at = format!("{place}.{k}");
        match k.as_str() {
            "circle" => {
                let c = self.obj(x, &at, &["c", "r"])?;
                let centre = self.point(self.req(c, "c", &at)?, &format!("{at}.c"))?;
                let r = self.num(self.req(c, "r", &at)?, &format!("{at}.r"))?;
                if r <= 0.0 {
                    return Err(self.err(&format!("{at}.r"), format!("the radius must be positive, got {r}")));
                }
                Ok(Node::Circle { c: centre, r })
            }
            "halfplane" => {
                let c = self.obj(x, &at, &["p", "n"])?;
                let p = self.point(self.req(c, "p", &at)?, &format!("{at}.p"))?;
                let n = self.point(self.req(c, "n", &at)?, &format!("{at}.n"))?;
                if !(n.length() > 1e-300) {
                    return Err(self.err(&format!("{at}.n"), "the normal must not be zero"));
                }
                Ok(Node::HalfPlane { p, n: n.normalize() })
            }
            "box" => {
                let c = self.obj(x, &at, &["min", "max", "c", "size", "angle"])?;
                let (centre, half, angle) = if c.contains_key("min") || c.contains_key("max") {
                    if c.contains_key("c") || c.contains_key("size") || c.contains_key("angle") {
                        return Err(self.err(&at, "give either min and max, or c, size and angle"));
                    }
                    let lo = self.point(self.req(c, "min", &at)?, &format!("{at}.min"))?;
                    let hi = self.point(self.req(c, "max", &at)?, &format!("{at}.max"))?;
                    if !(hi.x > lo.x && hi.y > lo.y) {
                        return Err(self.err(&format!("{at}.max"), "max must exceed min in x and in y"));
                    }
                    ((lo + hi) / 2.0, (hi - lo) / 2.0, 0.0)
                } else {
                    let centre = self.point(self.req(c, "c", &at)?, &format!("{at}.c"))?;
                    let size = self.point(self.req(c, "size", &at)?, &format!("{at}.size"))?;
                    if !(size.x > 0.0 && size.y > 0.0) {
                        return Err(self.err(&format!("{at}.size"), "both sizes must be positive"));
                    }
                    let angle = match c.get("angle") {
                        Some(a) => self.num(a, &format!("{at}.angle"))?.to_radians(),
                        None => 0.0,
                    };
                    (centre, size / 2.0, angle)
                };
                Ok(Node::Rect { c: centre, half, angle })
            }
            "polygon" => {
                let a = x.as_array().ok_or_else(|| self.err(&at, format!("expected [[x, y], …], got {}", kind(x))))?;
                if a.len() < 3 {
                    return Err(self.err(&at, format!("a polygon needs at least 3 points, got {}", a.len())));
                }
                let pts = a
                    .iter()
                    .enumerate()
                    .map(|(i, p)| self.point(p, &format!("{at}[{i}]")))
                    .collect::<Result<Vec<_>>>()?;
                let span = pts.iter().fold(0.0f64, |m, p| m.max((*p - pts[0]).length()));
                if crate::geom::ring_area(&pts).abs() <= 1e-12 * span * span {
                    return Err(self.err(&at, "the polygon has no area"));
                }
                Ok(Node::Polygon(pts))
            }
            "and" | "or" => {
                let a =
                    x.as_array().ok_or_else(|| self.err(&at, format!("expected a list of shapes, got {}", kind(x))))?;
                if a.is_empty() {
                    return Err(self.err(&at, "the list of shapes is empty"));
                }
                let ch = a
                    .iter()
                    .enumerate()
                    .map(|(i, c)| self.node(c, &format!("{at}[{i}]")))
                    .collect::<Result<Vec<_>>>()?;
                Ok(if k == "and" { Node::And(ch) } else { Node::Or(ch) })
            }
            _ => Ok(Node::Not(Box::new(self.node(x, &at)?))),
        }
    }
}

fn kind(v: &Value) -> &'static str {
    match v {
        Value::Null => "null",
        Value::Bool(_) => "a boolean",
        Value::Number(_) => "a number",
        Value::String(_) => "a string",
        Value::Array(_) => "a list",
        Value::Object(_) => "an object",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Shape> {
        Shape::from_json(s, Path::new("s.json"))
    }

    fn place_of(s: &str) -> (String, String) {
        match parse(s) {
            Err(Error::Input { file, place, reason }) => {
                assert_eq!(file, Path::new("s.json"));
                (place, reason)
            }
            other => panic!("expected an input error for {s}, got {other:?}"),
        }
    }

    fn fd_grad(f: &dyn Fn(DVec2) -> f64, p: DVec2) -> DVec2 {
        let h = 1e-6;
        DVec2::new(
            (f(p + DVec2::X * h) - f(p - DVec2::X * h)) / (2.0 * h),
            (f(p + DVec2::Y * h) - f(p - DVec2::Y * h)) / (2.0 * h),
        )
    }

    #[test]
    fn parse_errors_name_the_place() {
        let (p, r) =
            place_of(r#"{"shape": {"and": [{"circle": {"c": [0, 0], "r": 1}}, {"circle": {"c": [0, 0], "r": -2}}]}}"#);
        assert_eq!(p, "shape.and[1].circle.r");
        assert!(r.contains("positive"), "{r}");
        let (p, r) = place_of(r#"{"shape": {"polygon": [[0, 0], [1, 0]]}}"#);
        assert_eq!(p, "shape.polygon");
        assert!(r.contains("at least 3"), "{r}");
        let (p, _) = place_of(r#"{"rfunction": {"alpha": 1.5}, "shape": {"circle": {"c": [0, 0], "r": 1}}}"#);
        assert_eq!(p, "rfunction.alpha");
        let (p, _) = place_of(r#"{"rfunction": {"p": 3}, "shape": {"circle": {"c": [0, 0], "r": 1}}}"#);
        assert_eq!(p, "rfunction.p");
        let (p, r) = place_of(r#"{"shape": {"circle": {"c": [0, "NaN"], "r": 1}}}"#);
        assert_eq!(p, "shape.circle.c[1]");
        assert!(r.contains("number"), "{r}");
        let (p, _) = place_of(r#"{"shape": {"not": {"box": {"min": [0, 0], "max": [0, 1]}}}}"#);
        assert_eq!(p, "shape.not.box.max");
        let (p, r) = place_of(r#"{"shape": {"circle": {"c": [0, 0], "r": 1}, "box": {}}}"#);
        assert_eq!(p, "shape");
        assert!(r.contains("exactly one"), "{r}");
        let (p, r) = place_of(r#"{"shape": {"cirle": {}}}"#);
        assert_eq!(p, "shape");
        assert!(r.contains("unknown key"), "{r}");
        let (p, _) = place_of(r#"{"shape": {"or": []}}"#);
        assert_eq!(p, "shape.or");
        let (p, _) = place_of(r#"{"shape": {"halfplane": {"p": [0, 0], "n": [0, 0]}}}"#);
        assert_eq!(p, "shape.halfplane.n");
        let (p, _) = place_of(r#"{"rfunction": {"alpha": 0}}"#);
        assert_eq!(p, "top level");
        let (p, r) = place_of("{\"shape\": \n [}");
        assert!(p.starts_with("line 2"), "{p}");
        assert!(r.contains("JSON"), "{r}");
        let (p, _) = place_of(r#"{"shape": {"circle": {"c": [0, 0], "r": 1e999}}}"#);
        assert!(p.starts_with("line 1"), "{p}");
    }

    #[test]
    fn parses_the_documented_example() {
        let s = parse(
            r#"{ "rfunction": { "alpha": 0.0 },
                 "shape": { "and": [ { "circle": { "c": [0, 0], "r": 10 } },
                                     { "not": { "box": { "c": [4, 0], "size": [6, 3], "angle": 30 } } } ] } }"#,
        )
        .unwrap();
        assert!(s.eval(DVec2::new(-5.0, 0.0)).v > 0.0);
        assert!(s.eval(DVec2::new(4.0, 0.0)).v < 0.0);
        assert!(s.eval(DVec2::new(11.0, 0.0)).v < 0.0);
        let (lo, hi) = s.root.bounds().unwrap();
        assert_eq!((lo, hi), (DVec2::splat(-10.0), DVec2::splat(10.0)));
    }

    #[test]
    fn primitives_are_normalised_on_their_boundary() {
        let prims = [
            Node::Circle { c: DVec2::new(1.0, 2.0), r: 3.0 },
            Node::HalfPlane { p: DVec2::new(1.0, 0.0), n: DVec2::new(0.6, 0.8) },
            Node::Rect { c: DVec2::new(1.0, -1.0), half: DVec2::new(4.0, 2.0), angle: 0.4 },
            Node::Polygon(vec![DVec2::ZERO, DVec2::new(5.0, 0.0), DVec2::new(5.0, 3.0), DVec2::new(2.0, 5.0)]),
        ];
        let fam = RFamily::default();
        for prim in &prims {
            // walk each primitive's boundary by bisection on rays from an inside point
            let (lo, hi) = prim.bounds().unwrap_or((DVec2::splat(-5.0), DVec2::splat(5.0)));
            let inside = match prim {
                Node::HalfPlane { p, n } => *p + *n,
                _ => (lo + hi) / 2.0,
            };
            assert!(prim.eval(&fam, inside).v > 0.0, "{prim:?}");
            for k in 0..24 {
                let a = (k as f64 + 0.37) * std::f64::consts::TAU / 24.0;
                let dir = DVec2::new(a.cos(), a.sin());
                let (mut t0, mut t1) = (0.0, 1.0);
                while prim.eval(&fam, inside + dir * t1).v > 0.0 && t1 < 1e3 {
                    t1 *= 2.0;
                }
                if t1 >= 1e3 {
                    continue; // a half-plane: this ray never leaves
                }
                for _ in 0..80 {
                    let m = 0.5 * (t0 + t1);
                    if prim.eval(&fam, inside + dir * m).v > 0.0 { t0 = m } else { t1 = m }
                }
                let b = inside + dir * t0;
                let d = prim.eval(&fam, b);
                assert!(d.v.abs() < 1e-9, "{prim:?} at {b}: {}", d.v);
                // corners of the box and polygon are the exceptions; skip points within 1e-3 of them
                let near_corner = match prim {
                    Node::Rect { c, half, angle } => {
                        let u = rot(b - *c, -angle);
                        (u.x.abs() - half.x).abs() < 1e-3 && (u.y.abs() - half.y).abs() < 1e-3
                    }
                    Node::Polygon(p) => p.iter().any(|q| (*q - b).length() < 1e-3),
                    _ => false,
                };
                if !near_corner {
                    assert!((d.g.length() - 1.0).abs() < 1e-6, "{prim:?} at {b}: |∇f| = {}", d.g.length());
                }
            }
        }
    }

    #[test]
    fn shape_gradient_matches_finite_differences() {
        for fam in [RFamily::Alpha(0.0), RFamily::Alpha(0.5), RFamily::Zero(2), RFamily::P(4)] {
            let s = Shape {
                family: fam,
                root: Node::And(vec![
                    Node::Circle { c: DVec2::ZERO, r: 10.0 },
                    Node::Not(Box::new(Node::Rect { c: DVec2::new(4.0, 0.0), half: DVec2::new(3.0, 1.5), angle: 0.5 })),
                    Node::Or(vec![
                        Node::HalfPlane { p: DVec2::new(0.0, -6.0), n: DVec2::Y },
                        Node::Circle { c: DVec2::new(0.0, -7.0), r: 2.0 },
                    ]),
                ]),
            };
            for p in [DVec2::new(-3.0, 1.0), DVec2::new(2.0, 4.0), DVec2::new(8.5, -2.0), DVec2::new(0.3, -6.5)] {
                let d = s.eval(p);
                let g = fd_grad(&|q| s.eval(q).v, p);
                assert!((d.g - g).length() < 1e-5 * (1.0 + g.length()), "{fam:?} at {p}: {} vs {g}", d.g);
            }
        }
    }

    #[test]
    fn maximum_of_a_disk_is_its_centre() {
        let s = Shape { family: RFamily::default(), root: Node::Circle { c: DVec2::new(3.0, -2.0), r: 5.0 } };
        let (p, v) = maximum(&s, DVec2::new(-3.0, -8.0), DVec2::new(9.0, 4.0)).unwrap();
        assert!((p - DVec2::new(3.0, -2.0)).length() < 1e-6, "{p}");
        assert!((v - 2.5).abs() < 1e-9);
        let out = Shape { family: RFamily::default(), root: Node::Circle { c: DVec2::new(30.0, 0.0), r: 1.0 } };
        assert!(maximum(&out, DVec2::splat(-1.0), DVec2::splat(1.0)).is_none());
    }
}
