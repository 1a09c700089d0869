//! The 5-axis pocket case (`"kind": "fiveaxis_pocket"`, `docs/five.md`): one JSON file with the
//! floor and top NURBS surfaces, the sides, the tool, the axis rule and the machine, read into a
//! [`FiveJob`]. Every error names the file and the key path (`floor.knots_u[5]`, `tool.taper_deg`)
//! and what is wrong; every default is the format's.

use super::case::short;
use crate::error::{Error, Result};
use crate::geom::DVec3;
use crate::geom::nurbs::NurbsSurface;
use crate::limits;
use crate::model::five::{AxisRule, Boundary, CutterKind, FiveJob, FiveTool, Machine, Side};
use serde_json::Value;
use std::path::{Path, PathBuf};

struct Ctx {
    file: PathBuf,
}

impl Ctx {
    fn err(&self, place: impl Into<String>, reason: impl Into<String>) -> Error {
        Error::input(&self.file, place, reason)
    }

    fn num(&self, v: &Value, place: &str) -> Result<f64> {
        super::case::number(&self.file, v, place)
    }

    /// `obj[key]` as a number, `default` when absent.
    fn num_or(&self, obj: &Value, key: &str, place: &str, default: f64) -> Result<f64> {
        match obj.get(key) {
            None | Some(Value::Null) => Ok(default),
            Some(v) => self.num(v, &format!("{place}{key}")),
        }
    }

    /// `obj[key]` as a number greater than 0.
    fn positive(&self, obj: &Value, key: &str, place: &str, default: Option<f64>) -> Result<f64> {
        let at = format!("{place}{key}");
        let x = match (obj.get(key), default) {
            (None | Some(Value::Null), Some(d)) => return Ok(d),
            (None | Some(Value::Null), None) => return Err(self.err(at, "missing")),
            (Some(v), _) => self.num(v, &at)?,
        };
        if x > 0.0 { Ok(x) } else { Err(self.err(at, format!("{x}: must be greater than 0"))) }
    }

    fn array<'a>(&self, v: &'a Value, place: &str) -> Result<&'a Vec<Value>> {
        v.as_array().ok_or_else(|| self.err(place, format!("expected a list, found {}", short(v))))
    }

    fn nurbs(&self, v: &Value, place: &str) -> Result<NurbsSurface> {
        if !v.is_object() {
            return Err(self.err(place, format!("expected a NURBS surface (an object), found {}", short(v))));
        }
        let degree = |key: &str| -> Result<usize> {
            let at = format!("{place}.{key}");
            match v.get(key).and_then(Value::as_u64) {
                Some(d) => Ok(d as usize),
                None => Err(self.err(at, "expected the degree, a whole number")),
            }
        };
        let knots = |key: &str| -> Result<Vec<f64>> {
            let at = format!("{place}.{key}");
            let list = self.array(v.get(key).unwrap_or(&Value::Null), &at)?;
            list.iter().enumerate().map(|(i, k)| self.num(k, &format!("{at}[{i}]"))).collect()
        };
        let (du, dv) = (degree("degree_u")?, degree("degree_v")?);
        let (ku, kv) = (knots("knots_u")?, knots("knots_v")?);
        for (k, key) in [(&ku, "knots_u"), (&kv, "knots_v")] {
            if k.first().is_some_and(|&a| a != 0.0) || k.last().is_some_and(|&b| b != 1.0) {
                return Err(self
                    .err(format!("{place}.{key}"), "the knots must run from 0 to 1 (the domain is the unit square)"));
            }
        }
        let cp = format!("{place}.control_points");
        let mut points = Vec::new();
        for (i, row) in self.array(v.get("control_points").unwrap_or(&Value::Null), &cp)?.iter().enumerate() {
            let mut out = Vec::new();
            for (j, p) in self.array(row, &format!("{cp}[{i}]"))?.iter().enumerate() {
                let at = format!("{cp}[{i}][{j}]");
                let xyz = self.array(p, &at)?;
                if xyz.len() != 3 {
                    return Err(self.err(at, format!("expected a point [x, y, z], found {}", short(p))));
                }
                let c: Vec<f64> = xyz.iter().map(|x| self.num(x, &at)).collect::<Result<_>>()?;
                if !c.iter().all(|x| limits::coord_ok(*x)) {
                    return Err(self.err(at, format!("beyond ±{} mm, the coordinate limit", limits::MAX_COORD_MM)));
                }
                out.push(DVec3::new(c[0], c[1], c[2]));
            }
            points.push(out);
        }
        let weights = match v.get("weights") {
            None | Some(Value::Null) => None,
            Some(w) => {
                let at = format!("{place}.weights");
                let rows = self.array(w, &at)?;
                let mut out = Vec::new();
                for (i, row) in rows.iter().enumerate() {
                    let r = self.array(row, &format!("{at}[{i}]"))?;
                    out.push(
                        r.iter()
                            .enumerate()
                            .map(|(j, x)| self.num(x, &format!("{at}[{i}][{j}]")))
                            .collect::<Result<_>>()?,
                    );
                }
                Some(out)
            }
        };
        // (the surface's own checks say what is wrong; the place is the surface's)
        NurbsSurface::new(du, dv, ku, kv, points, weights).map_err(|reason| self.err(place, reason))
    }

    fn tool(&self, v: &Value) -> Result<FiveTool> {
        let p = "tool.";
        if !v.is_object() {
            return Err(self.err("tool", format!("expected an object, found {}", short(v))));
        }
        let kind = match v.get("type").and_then(Value::as_str) {
            Some("flat") => CutterKind::Flat,
            Some("ball") => CutterKind::Ball,
            Some("tapered") => CutterKind::Tapered,
            _ => return Err(self.err("tool.type", "expected \"flat\", \"ball\" or \"tapered\"")),
        };
        let diameter = self.positive(v, "diameter", p, None)?;
        if !(limits::MIN_TOOL_MM..=limits::MAX_TOOL_MM).contains(&diameter) {
            return Err(self.err(
                "tool.diameter",
                format!("{diameter}: tools from {} to {} mm", limits::MIN_TOOL_MM, limits::MAX_TOOL_MM),
            ));
        }
        let r = 0.5 * diameter;
        let corner_radius = match kind {
            CutterKind::Ball => r,
            _ => self.num_or(v, "corner_radius", p, 0.0)?,
        };
        if !(0.0..=r).contains(&corner_radius) {
            return Err(self.err("tool.corner_radius", format!("{corner_radius}: must be from 0 to the radius ({r})")));
        }
        let taper_deg = match kind {
            CutterKind::Tapered => {
                let q = self.num_or(v, "taper_deg", p, 0.0)?;
                if !(q > 0.0 && q < 45.0) {
                    return Err(
                        self.err("tool.taper_deg", format!("{q}: a tapered tool's half angle is in (0, 45) degrees"))
                    );
                }
                q
            }
            _ => 0.0,
        };
        let flute_length = self.positive(v, "flute_length", p, Some((4.0 * diameter).max(20.0)))?;
        let cutter_at_top = r + flute_length * taper_deg.to_radians().tan();
        let shank_diameter = self.positive(v, "shank_diameter", p, Some(2.0 * cutter_at_top))?;
        let length = self.positive(v, "length", p, Some(flute_length))?;
        if length < flute_length {
            return Err(self.err("tool.length", format!("{length}: shorter than the flutes ({flute_length})")));
        }
        let holder = match v.get("holder_diameter") {
            None | Some(Value::Null) => None,
            Some(_) => {
                Some((self.positive(v, "holder_diameter", p, None)?, self.positive(v, "holder_length", p, Some(0.0))?))
            }
        };
        for (key, x) in [("flute_length", flute_length), ("shank_diameter", shank_diameter), ("length", length)] {
            if !limits::coord_ok(x) {
                return Err(self.err(format!("tool.{key}"), format!("{x}: beyond {} mm", limits::MAX_COORD_MM)));
            }
        }
        Ok(FiveTool { kind, diameter, corner_radius, taper_deg, flute_length, shank_diameter, length, holder })
    }

    fn machine(&self, v: Option<&Value>) -> Result<Machine> {
        let d = Machine::default();
        let Some(v) = v.filter(|v| !v.is_null()) else { return Ok(d) };
        if !v.is_object() {
            return Err(self.err("machine", format!("expected an object, found {}", short(v))));
        }
        let p = "machine.";
        let kinematics = match v.get("kinematics") {
            None | Some(Value::Null) => d.kinematics.clone(),
            Some(Value::String(k)) if k == "xyzac-trt" => k.clone(),
            Some(k) => return Err(self.err("machine.kinematics", format!("{}: swarf knows \"xyzac-trt\"", short(k)))),
        };
        let m = Machine {
            kinematics,
            x_rot_point: self.num_or(v, "x_rot_point", p, d.x_rot_point)?,
            y_rot_point: self.num_or(v, "y_rot_point", p, d.y_rot_point)?,
            z_rot_point: self.num_or(v, "z_rot_point", p, d.z_rot_point)?,
            y_offset: self.num_or(v, "y_offset", p, d.y_offset)?,
            z_offset: self.num_or(v, "z_offset", p, d.z_offset)?,
            tool_offset: self.num_or(v, "tool_offset", p, d.tool_offset)?,
            a_min: self.num_or(v, "a_min", p, d.a_min)?,
            a_max: self.num_or(v, "a_max", p, d.a_max)?,
        };
        if !(m.a_min < m.a_max && m.a_min >= -180.0 && m.a_max <= 180.0) {
            return Err(
                self.err("machine.a_min", format!("{} to {}: A's range must be within ±180 degrees", m.a_min, m.a_max))
            );
        }
        Ok(m)
    }
}

/// Whether the bytes are a 5-axis case (`"kind": "fiveaxis_pocket"`).
pub fn is_five(bytes: &[u8]) -> bool {
    serde_json::from_slice::<Value>(bytes)
        .ok()
        .is_some_and(|v| v.get("kind").and_then(Value::as_str) == Some("fiveaxis_pocket"))
}

/// Reads the 5-axis case at `path`.
pub fn read_five(path: &Path) -> Result<FiveJob> {
    let bytes = std::fs::read(path).map_err(|e| Error::input(path, "file", format!("cannot read: {e}")))?;
    parse_five(path, &bytes)
}

/// Parses a 5-axis case; `path` names it in errors and gives the job its name.
pub fn parse_five(path: &Path, bytes: &[u8]) -> Result<FiveJob> {
    let cx = Ctx { file: path.to_path_buf() };
    let v: Value = serde_json::from_slice(bytes)
        .map_err(|e| cx.err(format!("line {}, column {}", e.line(), e.column()), format!("not JSON: {e}")))?;
    if !v.is_object() {
        return Err(cx.err("file", format!("expected a JSON object, found {}", short(&v))));
    }
    match v.get("kind").and_then(Value::as_str) {
        Some("fiveaxis_pocket") => {}
        _ => return Err(cx.err("kind", "expected \"fiveaxis_pocket\"")),
    }
    match v.get("units") {
        None | Some(Value::Null) => {}
        Some(Value::String(u)) if u == "mm" => {}
        Some(u) => return Err(cx.err("units", format!("{}: 5-axis cases are in mm", short(u)))),
    }
    let floor = cx.nurbs(v.get("floor").unwrap_or(&Value::Null), "floor")?;
    let top = cx.nurbs(v.get("top").unwrap_or(&Value::Null), "top")?;
    let sides = v.get("boundaries").filter(|b| !b.is_null());
    if let Some(b) = sides
        && !b.is_object()
    {
        return Err(cx.err("boundaries", format!("expected an object, found {}", short(b))));
    }
    let walls = v.get("walls").filter(|b| !b.is_null());
    let mut boundaries = Vec::new();
    for side in Side::ALL {
        let default = if matches!(side, Side::U0 | Side::U1) { "open" } else { "wall" };
        let at = format!("boundaries.{}", side.key());
        let kind = match sides.and_then(|b| b.get(side.key())) {
            None | Some(Value::Null) => default,
            Some(Value::String(s)) if s == "open" || s == "wall" => s.as_str(),
            Some(x) => return Err(cx.err(at, format!("{}: expected \"wall\" or \"open\"", short(x)))),
        };
        let surface = walls.and_then(|w| w.get(side.key())).filter(|w| !w.is_null());
        boundaries.push(match (kind, surface) {
            ("open", Some(_)) => {
                return Err(cx.err(format!("walls.{}", side.key()), "a wall surface for an open side"));
            }
            ("open", None) => Boundary::Open,
            (_, None) => Boundary::Wall(None),
            (_, Some(w)) => {
                let at = format!("walls.{}.surface", side.key());
                Boundary::Wall(Some(cx.nurbs(w.get("surface").unwrap_or(&Value::Null), &at)?))
            }
        });
    }
    let boundaries: [Boundary; 4] = boundaries.try_into().map_err(|_| cx.err("boundaries", "four sides"))?;
    let tool = cx.tool(v.get("tool").unwrap_or(&Value::Null))?;
    let axis = match v.get("orientation").and_then(|o| o.get("rule")) {
        None | Some(Value::Null) => AxisRule::Field,
        Some(Value::String(r)) if r == "field" => AxisRule::Field,
        Some(Value::String(r)) if r == "normal" => AxisRule::Normal,
        Some(r) => return Err(cx.err("orientation.rule", format!("{}: expected \"field\" or \"normal\"", short(r)))),
    };
    let stepover = cx.positive(&v, "stepover", "", Some(0.5))?;
    if stepover > tool.diameter {
        return Err(cx.err("stepover", format!("{stepover}: more than the tool's diameter ({})", tool.diameter)));
    }
    let scallop_tol = cx.positive(&v, "scallop_tol", "", Some(0.02))?;
    let wall_band_margin = cx.num_or(&v, "wall_band_margin", "", 0.5)?;
    let clearance = cx.positive(&v, "clearance", "", Some(5.0))?;
    let feed = cx.positive(&v, "feed_default", "", Some(1000.0))?;
    let rapid_rate = cx.positive(&v, "rapid_rate", "", Some(5000.0))?;
    for (key, x) in [("feed_default", feed), ("rapid_rate", rapid_rate)] {
        if x > limits::MAX_RATE {
            return Err(cx.err(key, format!("{x}: above {:e} mm/min", limits::MAX_RATE)));
        }
    }
    for (key, x) in [("wall_band_margin", wall_band_margin), ("clearance", clearance)] {
        if !limits::coord_ok(x) || x < 0.0 {
            return Err(cx.err(key, format!("{x}: from 0 to {} mm", limits::MAX_COORD_MM)));
        }
    }
    let machine = cx.machine(v.get("machine"))?;
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("five").to_string();
    Ok(FiveJob {
        name,
        floor,
        top,
        boundaries,
        tool,
        axis,
        stepover,
        scallop_tol,
        wall_band_margin,
        clearance,
        feed,
        rapid_rate,
        machine,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat floor 40 × 20 at z = 0 and a top 10 above it, as bilinear patches.
    fn case(extra: &str) -> String {
        let patch = |z: f64| {
            format!(
                r#"{{"degree_u": 1, "degree_v": 1, "knots_u": [0, 0, 1, 1], "knots_v": [0, 0, 1, 1],
                   "control_points": [[[0, 0, {z}], [0, 20, {z}]], [[40, 0, {z}], [40, 20, {z}]]]}}"#
            )
        };
        format!(
            r#"{{"units": "mm", "kind": "fiveaxis_pocket", "floor": {}, "top": {},
                 "tool": {{"type": "flat", "diameter": 5, "corner_radius": 0.5}}{extra}}}"#,
            patch(0.0),
            patch(10.0)
        )
    }

    fn parse(s: &str) -> Result<FiveJob> {
        parse_five(Path::new("pocket.json"), s.as_bytes())
    }

    #[test]
    fn reads_a_case_with_the_defaults() {
        let j = parse(&case("")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(j.name, "pocket");
        assert!((j.floor.eval(0.5, 0.5).p - DVec3::new(20.0, 10.0, 0.0)).length() < 1e-12);
        assert!((j.top.eval(0.5, 0.5).p.z - 10.0).abs() < 1e-12);
        assert_eq!(j.boundary(Side::U0), &Boundary::Open);
        assert_eq!(j.boundary(Side::V1), &Boundary::Wall(None));
        assert_eq!((j.stepover, j.scallop_tol, j.wall_band_margin, j.clearance), (0.5, 0.02, 0.5, 5.0));
        assert_eq!(j.axis, AxisRule::Field);
        assert_eq!(j.machine, Machine::default());
        assert_eq!((j.tool.flute_length, j.tool.shank_diameter, j.tool.length), (20.0, 5.0, 20.0));
        let t = parse(&case(
            r#", "stepover": 0.33, "orientation": {"rule": "normal"}, "boundaries": {"u1": "wall", "v0": "open"},
               "machine": {"a_min": -90, "a_max": 30}"#,
        ))
        .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((t.stepover, t.axis), (0.33, AxisRule::Normal));
        assert_eq!((t.boundary(Side::U1), t.boundary(Side::V0)), (&Boundary::Wall(None), &Boundary::Open));
        assert_eq!((t.machine.a_min, t.machine.a_max, t.machine.z_offset), (-90.0, 30.0, -50.0));
    }

    #[test]
    fn the_field_the_normal_and_the_walls() {
        // the top leans: 10 above the floor at u = 0, and 10 up and 10 along x at u = 1
        let text = case("").replacen("[[40, 0, 10], [40, 20, 10]]", "[[50, 0, 10], [50, 20, 10]]", 1);
        let j = parse(&text).unwrap_or_else(|e| panic!("{e}"));
        assert!((j.floor_normal(0.3, 0.6) - DVec3::Z).length() < 1e-12);
        assert!((j.axis_field(0.0, 0.5) - DVec3::Z).length() < 1e-12);
        let lean = j.axis_field(1.0, 0.5);
        assert!((lean - DVec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-12, "{lean}");
        let normal = parse(&text.replace("\"kind\"", "\"orientation\": {\"rule\": \"normal\"}, \"kind\""))
            .unwrap_or_else(|e| panic!("{e}"));
        assert!((normal.axis_field(1.0, 0.5) - DVec3::Z).length() < 1e-12);
        // the ruled wall along v0 halfway up at s = 1: between (40, 0, 0) and (50, 0, 10)
        assert!((j.wall_point(Side::V0, 1.0, 0.5).expect("a wall") - DVec3::new(45.0, 0.0, 5.0)).length() < 1e-12);
        assert_eq!(j.wall_point(Side::U0, 0.5, 0.5), None);
    }

    #[test]
    fn errors_name_the_file_the_place_and_the_reason() {
        let bad = [
            (case("").replace("\"kind\": \"fiveaxis_pocket\"", "\"kind\": \"pocket\""), "kind"),
            (case("").replacen("[0, 0, 1, 1]", "[0, 0, 1, 2]", 1), "floor.knots_u"),
            (case("").replacen("[0, 0, 1, 1]", "[0, 1, 1]", 1), "need 4 knots"),
            (case("").replacen("[0, 20, 0]", "[0, 20]", 1), "floor.control_points[0][1]"),
            (case("").replacen("[0, 20, 0]", "[0, 1e300, 0]", 1), "largest number"),
            (case("").replacen("[0, 20, 0]", "[0, 2e5, 0]", 1), "coordinate limit"),
            (case("").replace("\"diameter\": 5", "\"diameter\": 0.01"), "tool.diameter"),
            (case("").replace("\"corner_radius\": 0.5", "\"corner_radius\": 3"), "tool.corner_radius"),
            (case("").replace("\"type\": \"flat\"", "\"type\": \"tapered\""), "tool.taper_deg"),
            (case(r#", "boundaries": {"u0": "door"}"#), "boundaries.u0"),
            (case(r#", "stepover": -1"#), "stepover"),
            (case(r#", "stepover": 9"#), "more than the tool"),
            (case(r#", "machine": {"kinematics": "xyzbc"}"#), "machine.kinematics"),
            (case(r#", "machine": {"a_min": 50, "a_max": 10}"#), "machine.a_min"),
            (case(r#", "walls": {"u0": {"surface": {}}}"#), "open side"),
            (case(r#", "orientation": {"rule": "up"}"#), "orientation.rule"),
            ("[1, 2]".to_string(), "JSON object"),
            ("{\"kind\": ".to_string(), "line 1"),
        ];
        for (text, want) in bad {
            match parse(&text) {
                Err(e) => {
                    let m = e.to_string();
                    assert!(m.contains("pocket.json") && m.contains(want), "{m:?} should name the file and {want:?}");
                }
                Ok(_) => panic!("accepted; should say {want:?}"),
            }
        }
    }
}
