//! The case format of the benchmarks (see the project docs): one JSON file with the stock, the
//! part, fixtures, depths, tool and width of cut.
//!
//! The file is parsed into a JSON tree first (syntax errors come back with line and column) and
//! then walked by hand, so that every semantic error names the key path, e.g.
//! `part[1].holes[0][3]: expected a point [x, y] of two numbers`.

use super::Input;
use crate::error::{Error, Result, Setting};
use crate::geom::area::Fill;
use crate::geom::mesh::Placement;
use crate::geom::{Area, DVec2};
use crate::model::{Cutting, Job, MeshJob, Tool, Width};
use serde_json::Value;
use std::path::{Path, PathBuf};

struct Ctx {
    file: PathBuf,
    scale: f64,
}

impl Ctx {
    fn err(&self, place: impl Into<String>, reason: impl Into<String>) -> Error {
        Error::input(&self.file, place, reason)
    }

    /// A setting error of a value the file gave, as an error of the file at that value's key.
    fn in_file(&self, e: Error) -> Error {
        match e {
            Error::Setting { setting, reason } => self.err(key_of(setting), reason),
            other => other,
        }
    }

    fn num(&self, v: &Value, place: &str) -> Result<f64> {
        number(&self.file, v, place)
    }

    fn opt_num(&self, obj: &Value, key: &str) -> Result<Option<f64>> {
        match obj.get(key) {
            None | Some(Value::Null) => Ok(None),
            Some(v) => self.num(v, key).map(Some),
        }
    }

    fn ring(&self, v: &Value, place: &str) -> Result<Vec<DVec2>> {
        let arr =
            v.as_array().ok_or_else(|| self.err(place, format!("expected a list of points, found {}", short(v))))?;
        let mut pts = Vec::with_capacity(arr.len());
        for (i, p) in arr.iter().enumerate() {
            let pl = format!("{place}[{i}]");
            let xy = p
                .as_array()
                .filter(|a| a.len() == 2 || a.len() == 3)
                .ok_or_else(|| self.err(&pl, format!("expected a point [x, y] of two numbers, found {}", short(p))))?;
            let x = self.num(&xy[0], &pl)?;
            let y = self.num(&xy[1], &pl)?;
            let p = DVec2::new(x, y) * self.scale;
            if !(crate::limits::coord_ok(p.x) && crate::limits::coord_ok(p.y)) {
                return Err(self.err(
                    &pl,
                    format!(
                        "({}, {}) mm: every coordinate must be within ±{} mm",
                        p.x,
                        p.y,
                        crate::limits::MAX_COORD_MM
                    ),
                ));
            }
            pts.push(p);
        }
        if pts.len() > 1 && pts.first() == pts.last() {
            pts.pop();
        }
        if pts.len() < 3 {
            return Err(
                self.err(place, format!("a closed outline needs at least 3 distinct points, found {}", pts.len()))
            );
        }
        if crate::geom::ring_area(&pts).abs() < 1e-12 {
            return Err(self.err(place, "the outline has no area (all points on one line)"));
        }
        Ok(pts)
    }

    /// `[{"outer": ring, "holes": [ring...]}, ...]` (union) or `[ring, ring, ...]` (even-odd).
    fn polygons(&self, v: &Value, place: &str) -> Result<Area> {
        let arr =
            v.as_array().ok_or_else(|| self.err(place, format!("expected a list of polygons, found {}", short(v))))?;
        if arr.is_empty() {
            return Ok(Area::empty());
        }
        if arr.iter().all(Value::is_object) {
            let mut areas = Vec::new();
            for (i, p) in arr.iter().enumerate() {
                let pl = format!("{place}[{i}]");
                let outer = p.get("outer").ok_or_else(|| self.err(&pl, "polygon without \"outer\""))?;
                let mut rings = vec![self.ring(outer, &format!("{pl}.outer"))?];
                if let Some(h) = p.get("holes") {
                    let ha = h.as_array().ok_or_else(|| self.err(format!("{pl}.holes"), "expected a list of rings"))?;
                    for (k, hr) in ha.iter().enumerate() {
                        rings.push(self.ring(hr, &format!("{pl}.holes[{k}]"))?);
                    }
                }
                areas.push(Area::from_rings(&rings, Fill::EvenOdd));
            }
            Ok(Area::union_all(areas.iter()))
        } else if arr.iter().all(Value::is_array) {
            let rings = arr
                .iter()
                .enumerate()
                .map(|(i, r)| self.ring(r, &format!("{place}[{i}]")))
                .collect::<Result<Vec<_>>>()?;
            Ok(Area::from_rings(&rings, Fill::EvenOdd))
        } else {
            Err(self
                .err(place, "expected either polygons {\"outer\": …, \"holes\": …} or rings [[x, y], …], not a mix"))
        }
    }
}

/// A JSON number of `file` at `place` within the largest number swarf reads, or the error that
/// says what is there instead (the case readers' one reading of a number).
pub(super) fn number(file: &Path, v: &Value, place: &str) -> Result<f64> {
    match v.as_f64() {
        Some(x) if x.is_finite() && x.abs() <= crate::limits::MAX_NUMBER => Ok(x),
        Some(x) if x.is_finite() => Err(Error::input(
            file,
            place,
            format!("{x}: outside ±{:e}, the largest number swarf reads", crate::limits::MAX_NUMBER),
        )),
        _ => Err(Error::input(file, place, format!("expected a number, found {}", short(v)))),
    }
}

/// A JSON value, shortened for a message.
pub(super) fn short(v: &Value) -> String {
    let s = v.to_string();
    if s.len() > 40 { format!("{}…", &s[..s.char_indices().nth(40).map_or(s.len(), |(i, _)| i)]) } else { s }
}

/// Reads a case file.
pub fn read_case(path: &Path) -> Result<Job> {
    let text = std::fs::read(path).map_err(|e| Error::input(path, "file", format!("cannot read: {e}")))?;
    parse_case(path, &text)
}

/// Parses a 2.5D case; `path` names the file in messages. A 3D case (`stock_box`,
/// `part_stl`) is refused: read it with [`parse_input`].
pub fn parse_case(path: &Path, bytes: &[u8]) -> Result<Job> {
    match parse_input(path, bytes)? {
        Input::Flat(job) => Ok(*job),
        Input::Mesh(_) => {
            Err(Error::input(path, "stock_box", "a 3D case (stock_box / part_stl): this reader takes 2.5D cases only"))
        }
    }
}

/// The STL file the 3D case `bytes` (at `path`) names (`part_stl`, relative to the case), if
/// it names one.
pub fn part_stl_of_bytes(path: &Path, bytes: &[u8]) -> Option<PathBuf> {
    let root: Value = serde_json::from_slice(bytes).ok()?;
    let stl = root.get("part_stl")?.as_str()?;
    Some(path.parent().unwrap_or(Path::new("")).join(stl))
}

/// Parses case JSON of either kind; `path` names the file in messages and locates the STL of a
/// 3D case.
pub fn parse_input(path: &Path, bytes: &[u8]) -> Result<Input> {
    let file = path.to_path_buf();
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(Error::input(&file, "file", "the file is empty"));
    }
    let root: Value = serde_json::from_slice(bytes).map_err(|e| {
        Error::input(&file, format!("line {} column {}", e.line(), e.column()), format!("not valid JSON: {e}"))
    })?;
    if !root.is_object() {
        return Err(Error::input(
            &file,
            "top level",
            "a case is a JSON object {\"stock\": …, \"part\": …, \"tool\": …}",
        ));
    }
    let units = root.get("units").and_then(Value::as_str).unwrap_or("mm");
    let scale = match units {
        "mm" => 1.0,
        "in" | "inch" => 25.4,
        other => return Err(Error::input(&file, "units", format!("unknown units {other:?} (use \"mm\" or \"in\")"))),
    };
    let cx = Ctx { file: file.clone(), scale };
    if root.get("stock_box").is_some() || root.get("part_stl").is_some() {
        return mesh_case(&cx, &root, path).map(|j| Input::Mesh(Box::new(j)));
    }
    let stock_v = root.get("stock").ok_or_else(|| cx.err("stock", "missing: the raw stock outline [[x, y], …]"))?;
    let stock = if stock_v.as_array().is_some_and(|a| {
        a.first().is_some_and(Value::is_array) && a.first().and_then(|p| p.get(0)).is_some_and(Value::is_number)
    }) {
        Area::from_rings(&[cx.ring(stock_v, "stock")?], Fill::NonZero)
    } else {
        cx.polygons(stock_v, "stock")?
    };
    let part = match root.get("part") {
        None | Some(Value::Null) => Area::empty(),
        Some(v) => cx.polygons(v, "part")?,
    };
    let fixtures = match root.get("fixtures") {
        None | Some(Value::Null) => Area::empty(),
        Some(v) => cx.polygons(v, "fixtures")?,
    };
    let Common { cutting, allowance, allowance_floor, stepdown } = common(&cx, &root)?;
    let stock_top = cx.opt_num(&root, "stock_top")?.unwrap_or(0.0) * scale;
    let part_top = cx.opt_num(&root, "part_top")?.map_or(stock_top, |v| v * scale);
    let floor = cx.opt_num(&root, "floor")?.ok_or_else(|| cx.err("floor", "missing: the depth to clear to"))? * scale;
    if stock.is_empty() {
        return Err(cx.err("stock", "the stock outline has no area"));
    }
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("job").to_string();
    let job =
        Job { name, stock, stock_top, part, part_top, fixtures, floor, allowance, allowance_floor, stepdown, cutting };
    job.validate().map_err(|e| cx.in_file(e))?;
    Ok(Input::Flat(Box::new(job)))
}

/// What 2.5D and 3D cases share: the cutting data, allowances and step-down.
struct Common {
    cutting: Cutting,
    allowance: f64,
    allowance_floor: f64,
    stepdown: Option<f64>,
}

fn common(cx: &Ctx, root: &Value) -> Result<Common> {
    let scale = cx.scale;
    let tool = root.get("tool").ok_or_else(|| cx.err("tool", "missing: {\"diameter\": mm, \"type\": \"flat\"}"))?;
    if let Some(t) = tool.get("type").and_then(Value::as_str)
        && t != "flat"
    {
        return Err(cx.err("tool.type", format!("{t:?}: only flat end mills are supported")));
    }
    let diameter =
        cx.num(tool.get("diameter").ok_or_else(|| cx.err("tool.diameter", "missing"))?, "tool.diameter")? * scale;
    let allowance = cx.opt_num(root, "allowance")?.unwrap_or(0.0) * scale;
    let allowance_floor = cx.opt_num(root, "allowance_floor")?.map_or(allowance, |v| v * scale);
    let d = Cutting::DEFAULT;
    let width = match (cx.opt_num(root, "engagement_deg")?, cx.opt_num(root, "stepover")?) {
        (Some(t), _) => Width::EngagementDeg(t),
        (None, Some(s)) => Width::Stepover(s),
        (None, None) => d.width,
    };
    let stepdown = cx.opt_num(root, "stepdown")?.map(|v| v * scale);
    let feed = cx.opt_num(root, "feed_default")?.map_or(d.feed, |v| v * scale);
    let rapid_rate = cx.opt_num(root, "rapid_rate")?.map_or(d.rapid_rate, |v| v * scale);
    let spindle_rpm = cx.opt_num(root, "spindle_rpm")?.unwrap_or(d.spindle_rpm);
    let max_feed = cx.opt_num(root, "max_feed")?.map(|v| v * scale).or(d.max_feed);
    let mut tool = Tool::flat(diameter);
    if let Some(n) = tool_number(tool_num_value(root)) {
        tool.number = n;
    }
    let cutting = Cutting { tool, width, feed, rapid_rate, max_feed, spindle_rpm };
    // (each value where the file gives it: a bad one is the file's error, named by its key)
    cutting.validate().map_err(|e| cx.in_file(e))?;
    if let Some(sd) = stepdown
        && !(sd.is_finite() && sd > 0.0)
    {
        return Err(cx.err("stepdown", format!("{sd} mm: the step-down must be positive")));
    }
    Ok(Common { cutting, allowance, allowance_floor, stepdown })
}

/// A 3D case: `stock_box` [xmin, ymin, zmin, xmax, ymax, zmax], `part_stl` (relative to the
/// case file), `part_transform` {`scale`, `rotate_x_deg`, `rotate_y_deg`, `rotate_z_deg`,
/// `translate`} (in that order), `floor` (default: the stock bottom).
fn mesh_case(cx: &Ctx, root: &Value, path: &Path) -> Result<MeshJob> {
    let scale = cx.scale;
    let c = common(cx, root)?;
    let bx =
        root.get("stock_box").ok_or_else(|| cx.err("stock_box", "missing: [xmin, ymin, zmin, xmax, ymax, zmax]"))?;
    let b = bx.as_array().filter(|a| a.len() == 6).ok_or_else(|| {
        cx.err("stock_box", format!("expected [xmin, ymin, zmin, xmax, ymax, zmax], found {}", short(bx)))
    })?;
    let mut v = [0.0; 6];
    for (i, x) in v.iter_mut().enumerate() {
        *x = cx.num(&b[i], &format!("stock_box[{i}]"))? * scale;
    }
    let (lo, hi) = (crate::geom::DVec3::new(v[0], v[1], v[2]), crate::geom::DVec3::new(v[3], v[4], v[5]));
    if !(hi.x > lo.x && hi.y > lo.y && hi.z > lo.z) {
        return Err(cx.err("stock_box", "each maximum must be greater than its minimum"));
    }
    let stl = root
        .get("part_stl")
        .ok_or_else(|| cx.err("part_stl", "missing: the part's STL file, relative to this case"))?;
    let stl = stl.as_str().ok_or_else(|| cx.err("part_stl", format!("expected a file name, found {}", short(stl))))?;
    let stl_path = path.parent().unwrap_or(Path::new("")).join(stl);
    let mut mesh = super::stl::read(&stl_path)?;
    let mut place = Placement::default();
    if let Some(t) = root.get("part_transform").filter(|t| !t.is_null()) {
        if !t.is_object() {
            return Err(
                cx.err("part_transform", format!("expected {{\"scale\": …, \"rotate_x_deg\": …}}, found {}", short(t)))
            );
        }
        if let Some(s) = cx.opt_num(t, "scale")? {
            if s == 0.0 {
                return Err(cx.err("part_transform.scale", "must not be zero"));
            }
            place.scale = s;
        }
        for (i, k) in ["rotate_x_deg", "rotate_y_deg", "rotate_z_deg"].iter().enumerate() {
            if let Some(a) = cx.opt_num(t, k)? {
                place.rotate_deg[i] = a;
            }
        }
        if let Some(tr) = t.get("translate").filter(|v| !v.is_null()) {
            let a = tr.as_array().filter(|a| a.len() == 3).ok_or_else(|| {
                cx.err("part_transform.translate", format!("expected [x, y, z], found {}", short(tr)))
            })?;
            let mut d = [0.0; 3];
            for (i, x) in d.iter_mut().enumerate() {
                *x = cx.num(&a[i], &format!("part_transform.translate[{i}]"))?;
            }
            place.translate = crate::geom::DVec3::from_array(d);
        }
    }
    mesh.transform(&place);
    super::stl::check_size(path, &mesh, "part_transform", "part_transform and the units")?;
    let floor = cx.opt_num(root, "floor")?.map_or(lo.z, |f| f * scale);
    if !crate::limits::coord_ok(floor) {
        return Err(cx.err("floor", format!("{floor} mm: outside ±{} mm", crate::limits::MAX_COORD_MM)));
    }
    if floor >= hi.z {
        return Err(cx.err("floor", format!("{floor} mm: must be below the stock top {}", hi.z)));
    }
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("job");
    let mut job = MeshJob::new(name, mesh, lo, hi, c.cutting);
    job.floor = floor.max(lo.z);
    job.allowance = c.allowance;
    job.allowance_floor = c.allowance_floor;
    if let Some(sd) = c.stepdown {
        job.stepdown = sd;
    }
    job.validate().map_err(|e| cx.in_file(e))?;
    Ok(job)
}

/// The key of a case file that holds a setting.
fn key_of(setting: Setting) -> &'static str {
    match setting {
        Setting::ToolDiameter => "tool.diameter",
        Setting::Stepover => "stepover",
        Setting::Engagement => "engagement_deg",
        Setting::Feed => "feed_default",
        Setting::RapidRate => "rapid_rate",
        Setting::MaxFeed => "max_feed",
        Setting::SpindleSpeed => "spindle_rpm",
        Setting::Stepdown => "stepdown",
        Setting::Floor => "floor",
        Setting::StockTop => "stock_top",
        Setting::PartTop => "part_top",
        Setting::Allowance => "allowance",
        Setting::AllowanceFloor => "allowance_floor",
        Setting::StockBox => "stock_box",
        other => other.name(),
    }
}

fn tool_num_value(root: &Value) -> Option<&Value> {
    root.get("tool").and_then(|t| t.get("number"))
}

fn tool_number(v: Option<&Value>) -> Option<u32> {
    v.and_then(Value::as_u64).and_then(|n| u32::try_from(n).ok()).filter(|n| *n >= 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Job> {
        parse_case(Path::new("t.json"), s.as_bytes())
    }

    #[test]
    fn reads_a_pocket() {
        let j = parse(
            r#"{"units":"mm","tool":{"diameter":6,"type":"flat"},"stock":[[0,0],[60,0],[60,20],[0,20]],
            "part":[{"outer":[[-8,-8],[68,-8],[68,28],[-8,28]],"holes":[[[0,0],[60,0],[60,20],[0,20]]]}],
            "floor":-5,"engagement_deg":90}"#,
        )
        .unwrap();
        assert_eq!(j.cutting.tool.diameter, 6.0);
        assert!((j.stock.area() - 1200.0).abs() < 1e-9);
        assert!((j.part.area() - (76.0 * 36.0 - 1200.0)).abs() < 1e-6);
        assert!((j.cutting.width.stepover() - 0.5).abs() < 1e-12);
        assert_eq!(j.levels(), vec![-5.0]);
    }

    #[test]
    fn errors_name_the_place() {
        let e = parse("").unwrap_err().to_string();
        assert!(e.contains("empty"), "{e}");
        let e = parse("{\"stock\": [[0,0],[1,0]] garbage").unwrap_err().to_string();
        assert!(e.contains("line 1 column"), "{e}");
        let e = parse(r#"{"tool":{"diameter":6},"stock":[[0,0],[10,0],[10,NaN]],"floor":-1}"#).unwrap_err().to_string();
        assert!(e.contains("not valid JSON"), "{e}");
        let e = parse(r#"{"tool":{"diameter":6},"stock":[[0,0],[10,0],[10,"a"]],"floor":-1}"#).unwrap_err().to_string();
        assert!(e.contains("stock[2]"), "{e}");
        let e = parse(r#"{"tool":{"diameter":6},"stock":[[0,0],[10,0],[10,10]],"floor":-1,"stepover":1.5}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("stepover") && e.contains("(0, 1]"), "{e}");
        let e = parse(r#"{"tool":{"diameter":6},"stock":[[0,0],[10,0],[10,10]],"part":[[[0,0],[1,1]]],"floor":-1}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("part[0]"), "{e}");
    }
}
