//! Inputs: the benchmark case format (JSON) and drawings (DXF, SVG through `swarf-import`),
//! turned into a [`crate::model::Job`].

pub mod case;
pub mod drawing;
pub mod five;
pub mod gcode;
pub mod output;
pub mod stl;

use crate::error::{Error, Result, Setting};
use crate::geom::DVec3;
use crate::geom::mesh::Placement;
use crate::limits;
use crate::model::{Cutting, Job, MeshJob, Tool, Width};
use std::path::Path;

/// What the user may set on top of (or instead of) what the input file says.
#[derive(Debug, Clone, PartialEq)]
pub struct Overrides {
    /// Tool diameter, mm.
    pub tool_diameter: Option<f64>,
    /// Width of cut.
    pub width: Option<Width>,
    /// Step-down, mm.
    pub stepdown: Option<f64>,
    /// Cutting depth below the stock top for drawings (mm; [`Overrides::DEFAULT_DEPTH`] when
    /// not given).
    pub depth: Option<f64>,
    /// Feed, mm/min.
    pub feed: Option<f64>,
    /// The machine's highest cutting feed, mm/min.
    pub max_feed: Option<f64>,
    /// Spindle speed, rpm.
    pub spindle_rpm: Option<f64>,
    /// Stock to leave on walls, mm.
    pub allowance: Option<f64>,
    /// Drawing import options.
    pub import: swarf_import::ImportOptions,
    /// Placement of an STL part read on its own (its units' scale comes from `import.units`).
    pub placement: Placement,
    /// An STL part read on its own that was drawn sideways (its flat faces facing X or Y) is
    /// laid flat on its back ([`stl::lay_flat`]) when no rotation is given; false keeps it as
    /// drawn (the command line's `--part-rotate`, whatever its angles, says false).
    pub lay_flat: bool,
    /// Stock round an STL part read on its own: its bounds grown by this sideways, mm.
    pub stock_margin: f64,
    /// Stock above an STL part read on its own, mm: 0 (the default) puts the stock's top at
    /// the part's, so that no level faces a top nobody asked to face.
    pub stock_above: f64,
    /// What of a drawing without role layers is cut ([`drawing::Cut`]).
    pub cut: drawing::Cut,
}

impl Overrides {
    /// The depth a drawing is cut to when the overrides name none, mm.
    pub const DEFAULT_DEPTH: f64 = 3.0;

    /// Nothing overridden: the drawing import defaults, no placement, 2 mm of stock round an STL
    /// part and none above it.
    pub const DEFAULT: Overrides = Overrides {
        tool_diameter: None,
        width: None,
        stepdown: None,
        depth: None,
        feed: None,
        max_feed: None,
        spindle_rpm: None,
        allowance: None,
        import: swarf_import::ImportOptions::DEFAULT,
        placement: Placement::IDENTITY,
        lay_flat: true,
        stock_margin: 2.0,
        stock_above: 0.0,
        cut: drawing::Cut::Auto,
    };

    /// Checks every value given: the same ranges as the job's own ([`Cutting::validate`],
    /// [`Job::validate`]), a positive depth, placements and import tolerances that are numbers.
    pub fn validate(&self) -> Result<()> {
        if let Some(d) = self.tool_diameter {
            Tool::flat(d).validate()?;
        }
        if let Some(w) = self.width {
            w.validate()?;
        }
        // (each positive, and at most its limit: lengths within the coordinates' range, rates
        // within a machine's)
        let (len, rate, none) = (limits::MAX_COORD_MM, limits::MAX_RATE, f64::INFINITY);
        let positive = [
            (Setting::Stepdown, self.stepdown, "mm: the step-down must be a positive number", len),
            (Setting::Depth, self.depth, "mm: the depth must be positive", len),
            (Setting::Feed, self.feed, "mm/min: the feed must be positive", rate),
            (Setting::MaxFeed, self.max_feed, "mm/min: the highest feed must be positive", rate),
            (Setting::SpindleSpeed, self.spindle_rpm, "rpm: the spindle speed must be positive", rate),
            (Setting::SvgDpi, self.import.svg_px_per_inch, "px per inch: must be positive", none),
            (Setting::FlattenTolerance, Some(self.import.flatten_tolerance), "mm: must be positive", none),
        ];
        for (setting, v, what, max) in positive {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0) {
                    return Err(Error::setting(setting, format!("{v} {what}")));
                }
                if v > max {
                    return Err(Error::setting(setting, format!("{v}: at most {max}")));
                }
            }
        }
        let zero_or_more = [
            (Setting::Allowance, self.allowance),
            (Setting::ChainTolerance, Some(self.import.chain_tolerance)),
            (Setting::StockMargin, Some(self.stock_margin)),
            (Setting::StockAbove, Some(self.stock_above)),
        ];
        for (setting, v) in zero_or_more {
            if let Some(v) = v {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(Error::setting(setting, format!("{v} mm: must be zero or positive")));
                }
                if v > len {
                    return Err(Error::setting(setting, format!("{v} mm: at most {len} mm")));
                }
            }
        }
        if let Some(dpi) = self.import.svg_px_per_inch.filter(|d| !(*d >= 1.0 && *d <= 1e5)) {
            return Err(Error::setting(Setting::SvgDpi, format!("{dpi} px per inch: must be in [1, 100000]")));
        }
        let p = &self.placement;
        if !(p.scale.is_finite() && p.scale != 0.0) {
            return Err(Error::setting(Setting::PartScale, format!("{}: must be a non-zero number", p.scale)));
        }
        if !(1e-6..=1e6).contains(&p.scale.abs()) {
            return Err(Error::setting(Setting::PartScale, format!("{}: its size must be in [1e-6, 1e6]", p.scale)));
        }
        if !p.translate.to_array().into_iter().all(limits::coord_ok) {
            return Err(Error::setting(
                Setting::PartTranslate,
                format!("{}: each must be within ±{} mm", p.translate, limits::MAX_COORD_MM),
            ));
        }
        if !p.rotate_deg.iter().all(|a| a.is_finite()) {
            return Err(Error::setting(Setting::PartRotate, format!("{:?}: must be numbers", p.rotate_deg)));
        }
        if !p.translate.is_finite() {
            return Err(Error::setting(Setting::PartTranslate, format!("{}: must be numbers", p.translate)));
        }
        Ok(())
    }

    /// Applies the overrides of the cutting data: tool diameter, width of cut, feed, highest
    /// feed, spindle.
    pub fn apply_to_cutting(&self, c: &mut Cutting) {
        if let Some(d) = self.tool_diameter {
            c.tool.diameter = d;
        }
        if let Some(w) = self.width {
            c.width = w;
        }
        if let Some(f) = self.feed {
            c.feed = f;
        }
        if let Some(m) = self.max_feed {
            c.max_feed = Some(m);
        }
        if let Some(s) = self.spindle_rpm {
            c.spindle_rpm = s;
        }
    }

    /// Applies the overrides to a 2.5D job.
    pub fn apply_to_job(&self, job: &mut Job) {
        self.apply_to_cutting(&mut job.cutting);
        if let Some(s) = self.stepdown {
            job.stepdown = Some(s);
        }
        if let Some(a) = self.allowance {
            job.allowance = a;
        }
    }

    /// Applies the overrides to a mesh job.
    pub fn apply_to_mesh_job(&self, job: &mut MeshJob) {
        self.apply_to_cutting(&mut job.cutting);
        if let Some(s) = self.stepdown {
            job.stepdown = s;
        }
        if let Some(a) = self.allowance {
            job.allowance = a;
            job.allowance_floor = a;
        }
    }
}

impl Default for Overrides {
    fn default() -> Self {
        Overrides::DEFAULT
    }
}

/// What swarf made of an input, for the user before anything is planned: its size and units
/// (and why those units), what its contours were read as, and warnings where the file looks
/// meant otherwise (with the option that fixes it). [`Reading::line`] writes it as one line.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Reading {
    /// What the input is (`drawing`, `case`, `3D case`, `STL part`).
    pub kind: &'static str,
    /// Size in mm: the drawing's or part's extents in X, Y and Z (a drawing's Z is the depth cut).
    pub size_mm: [f64; 3],
    /// The units assumed and why (`inches: $INSUNITS = 1`).
    pub units: String,
    /// Closed contours read (drawings).
    pub contours: usize,
    /// Open contours left out (drawings, `--skip-open`).
    pub skipped: usize,
    /// Triangles read (STL parts).
    pub triangles: usize,
    /// Parts (outlines cut round or holding holes), pockets and islands read (drawings without
    /// role layers).
    pub parts: usize,
    /// Pockets read.
    pub pockets: usize,
    /// Islands read.
    pub islands: usize,
    /// What of the drawing is cut, once decided.
    pub cut: Option<drawing::Cut>,
    /// What was inferred, and why, in words.
    pub inferred: Vec<String>,
    /// What looks meant otherwise, each with the option that fixes it.
    pub warnings: Vec<String>,
    /// Every file read: the input, and the STL a 3D case names (outputs are checked against
    /// them, [`output::check`]).
    pub files: Vec<std::path::PathBuf>,
}

/// The name of a unit in words.
fn unit_name(u: swarf_import::Units) -> &'static str {
    use swarf_import::Units as U;
    match u {
        U::Millimetre => "millimetres",
        U::Centimetre => "centimetres",
        U::Metre => "metres",
        U::Inch => "inches",
        U::Foot => "feet",
        U::Mil => "thousandths of an inch",
        U::Micrometre => "micrometres",
    }
}

/// The largest extent under which a file with no unit is suspected of inches (mm), and under
/// which it is suspected of metres.
const INCH_SUSPECT_MM: f64 = 15.0;
const METRE_SUSPECT_MM: f64 = 1.0;

/// A warning when a size read in millimetres from a file with no unit looks like another unit.
fn unit_warning(largest_mm: f64) -> Option<String> {
    if largest_mm.is_nan() || largest_mm <= 0.0 {
        return None;
    }
    let (unit, flag, k) = if largest_mm < METRE_SUSPECT_MM {
        ("metres", "m", 1000.0)
    } else if largest_mm < INCH_SUSPECT_MM {
        ("inches", "in", 25.4)
    } else {
        return None;
    };
    Some(format!(
        "it is only {largest_mm:.2} mm across as millimetres: if it is in {unit} ({:.0} mm), give --units {flag}",
        largest_mm * k
    ))
}

impl Reading {
    /// One line: what was read, the tool and the width of cut, what was inferred.
    pub fn line(&self, input: &Input) -> String {
        let c = match input {
            Input::Flat(j) => &j.cutting,
            Input::Mesh(j) => &j.cutting,
        };
        let [x, y, z] = self.size_mm;
        let size = match input {
            Input::Flat(_) => format!("{x:.1} × {y:.1} mm, {z:.2} mm deep"),
            Input::Mesh(_) => format!("{x:.1} × {y:.1} × {z:.1} mm"),
        };
        let mut what = Vec::new();
        if self.triangles > 0 {
            what.push(format!("{} triangles", self.triangles));
        }
        if self.contours > 0 {
            what.push(format!("{} contours", self.contours));
        }
        if self.skipped > 0 {
            what.push(format!("{} open left out", self.skipped));
        }
        let parts = [(self.parts, "part"), (self.pockets, "pocket"), (self.islands, "island")];
        let counts: Vec<String> = parts
            .iter()
            .filter(|(n, _)| *n > 0)
            .map(|(n, w)| format!("{n} {w}{}", if *n == 1 { "" } else { "s" }))
            .collect();
        if !counts.is_empty() {
            what.push(counts.join(", "));
        }
        let mut line = format!("read {} {size}", self.kind);
        if !self.units.is_empty() {
            line.push_str(&format!(" ({})", self.units));
        }
        if !what.is_empty() {
            line.push_str(&format!(": {}", what.join("; ")));
        }
        line.push_str(&format!(
            "; tool Ø{} mm, stepover {:.0}% ({:.1} mm, reference engagement {:.1}°)",
            c.tool.diameter,
            c.width.stepover() * 100.0,
            c.stepover_mm(),
            c.width.engagement_deg()
        ));
        if let Input::Mesh(j) = input {
            line.push_str(&format!(", step-down {} mm", crate::post::num(j.stepdown, 3)));
        }
        for i in &self.inferred {
            line.push_str(&format!("; {i}"));
        }
        line
    }
}

/// What a case describes: a 2.5D job (polygons) or a 3D one (a mesh in a stock box).
#[derive(Debug, Clone)]
pub enum Input {
    /// Stock and part outlines.
    Flat(Box<Job>),
    /// A mesh part in a stock box.
    Mesh(Box<MeshJob>),
}

/// The built-in example's case file (`demo_pocket.json`): a 90 × 60 mm pocket with two
/// islands, a Ø6 mm end mill at 25 % stepover, two levels.
pub const EXAMPLE_CASE: &str = include_str!("../../examples_data/demo_pocket.json");

/// The built-in example job (a pocket with two islands, [`EXAMPLE_CASE`]).
pub fn example_job() -> Job {
    match case::parse_case(std::path::Path::new("demo_pocket.json"), EXAMPLE_CASE.as_bytes()) {
        Ok(j) => j,
        Err(e) => unreachable!("the built-in example is valid: {e}"),
    }
}

/// Reads a 2.5D case (`.json`), DXF or SVG file into a job, applies the overrides and validates it.
pub fn load_job(path: &Path, ov: &Overrides) -> Result<Job> {
    match load_input(path, ov)? {
        Input::Flat(job) => Ok(*job),
        Input::Mesh(_) => Err(Error::input(path, "file", "a 3D job (a mesh part): this reads 2.5D jobs only")),
    }
}

/// Reads a case (`.json`, 2.5D or 3D), an STL part, a DXF or an SVG file, applies the
/// overrides and validates the job.
///
/// The overrides are checked first ([`Overrides::validate`]); a case file's own values are
/// checked before the overrides apply, so that a bad value in the file is an error naming the
/// file and its key ([`Error::Input`]) and a bad override an error naming the setting
/// ([`Error::Setting`]).
///
/// An STL part alone gets a stock box round it (its bounds grown by `stock_margin` sideways and
/// by `stock_above` on top, none by default; its bottom at the part's lowest point), is placed
/// by `placement` (after the units' scale), and is roughed to its lowest point with the default
/// cutting data ([`Cutting::DEFAULT`]) and step-downs of [`MeshJob::DEFAULT_STEPDOWN_FRACTION`]
/// of the tool diameter unless the overrides say otherwise. A drawing is cut
/// [`Overrides::DEFAULT_DEPTH`] deep with the default cutting data (see
/// [`drawing::job_from_drawing`]).
///
/// ```
/// use swarf::{Input, Overrides, Setting, Width, load_input};
/// let case = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/cases/square_pocket.json");
/// let ov = Overrides { tool_diameter: Some(4.0), width: Some(Width::EngagementDeg(45.0)), ..Overrides::DEFAULT };
/// let Input::Flat(job) = load_input(case.as_ref(), &ov)? else { unreachable!() };
/// assert_eq!(job.cutting.tool.diameter, 4.0);
/// // a bad override names its setting
/// let bad = Overrides { spindle_rpm: Some(0.0), ..Overrides::DEFAULT };
/// assert!(matches!(load_input(case.as_ref(), &bad), Err(swarf::Error::Setting { setting: Setting::SpindleSpeed, .. })));
/// # Ok::<(), swarf::Error>(())
/// ```
pub fn load_input(path: &Path, ov: &Overrides) -> Result<Input> {
    read_input(path, ov).map(|(input, _)| input)
}

/// [`load_input`], and what was read and inferred ([`Reading`]).
pub fn read_input(path: &Path, ov: &Overrides) -> Result<(Input, Reading)> {
    ov.validate()?;
    let mut reading = Reading::default();
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let is_stl = ext == "stl" || (ext != "json" && ext != "dxf" && ext != "svg" && sniff_stl(path));
    let is_case = !is_stl && (ext == "json" || (ext != "dxf" && ext != "svg" && sniff_json(path)));
    // (the STL a 3D case names, found in the bytes read once)
    let mut case_stl = None;
    let input = if is_stl {
        stl_input(path, stl::read(path)?, ov, &mut reading)?
    } else if is_case {
        let bytes = std::fs::read(path).map_err(|e| Error::input(path, "file", format!("cannot read: {e}")))?;
        let input = case::parse_input(path, &bytes)?;
        case_reading(&input, &mut reading);
        case_stl = case::part_stl_of_bytes(path, &bytes);
        input
    } else {
        let d = swarf_import::read_drawing(path, &ov.import)?;
        let (job, r) = drawing::job_and_reading(&d, ov)?;
        reading = Reading { kind: "drawing", skipped: d.skipped.len(), ..r };
        let how = if d.units_assumed { " assumed" } else { "" };
        reading.units = format!("{}{how}: {}", unit_name(d.units), d.units_from);
        if d.units_assumed
            && d.path.extension().is_some_and(|e| e.eq_ignore_ascii_case("dxf"))
            && ov.placement.scale == 1.0
        {
            let [x, y, _] = reading.size_mm;
            reading.warnings.extend(unit_warning(x.max(y)));
        }
        for s in &d.skipped {
            reading.warnings.push(format!("left out: {s}"));
        }
        Input::Flat(Box::new(job))
    };
    let input = overridden(input, ov, path)?;
    reading.files.push(path.to_path_buf());
    reading.files.extend(case_stl);
    Ok((input, reading))
}

/// [`read_input`] of a case held in memory (a JSON text, `bytes`) instead of a file: `path`
/// names it in errors, and a 3D case's `part_stl` is read relative to its folder. The
/// reading's files are the STL part alone.
///
/// ```
/// use swarf::{Input, Overrides, io::read_case_bytes};
/// let text = br#"{"tool": {"diameter": 6}, "stock": [[0,0],[40,0],[40,30],[0,30]], "floor": -3}"#;
/// let (input, reading) = read_case_bytes("mine.json".as_ref(), text, &Overrides::DEFAULT)?;
/// assert!(matches!(input, Input::Flat(_)));
/// assert_eq!(reading.kind, "case");
/// // a bad case names the place and the reason
/// let err = read_case_bytes("mine.json".as_ref(), br#"{"tool": {"diameter": 6}}"#, &Overrides::DEFAULT).unwrap_err();
/// assert_eq!(err.to_string(), "mine.json: stock: missing: the raw stock outline [[x, y], …]");
/// # Ok::<(), swarf::Error>(())
/// ```
pub fn read_case_bytes(path: &Path, bytes: &[u8], ov: &Overrides) -> Result<(Input, Reading)> {
    ov.validate()?;
    let mut reading = Reading::default();
    let input = case::parse_input(path, bytes)?;
    case_reading(&input, &mut reading);
    let input = overridden(input, ov, path)?;
    if let Input::Mesh(_) = input {
        reading.files.extend(case::part_stl_of_bytes(path, bytes));
    }
    Ok((input, reading))
}

/// [`read_input`] of a part held in memory as a mesh ([`stl::from_triangles`], or
/// [`stl::parse`] of an STL file's bytes): `path` names it in errors and names the job. Placed,
/// laid flat and given its stock box as an STL file is.
///
/// ```
/// use swarf::{Input, Overrides, io::{read_mesh, stl}};
/// // a 40 × 30 × 10 mm box as 8 vertices and 12 triangles
/// let v: Vec<[f64; 3]> = (0..8).map(|i| [40.0 * (i & 1) as f64, 30.0 * (i >> 1 & 1) as f64, 10.0 * (i >> 2) as f64]).collect();
/// let t = [[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4], [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]];
/// let mesh = stl::from_triangles("box.stl".as_ref(), &v, &t)?;
/// let (input, reading) = read_mesh("box.stl".as_ref(), mesh, &Overrides::DEFAULT)?;
/// assert!(matches!(input, Input::Mesh(_)));
/// assert_eq!(reading.triangles, 12);
/// // an index out of range names the triangle
/// let err = stl::from_triangles("box.stl".as_ref(), &v, &[[0, 1, 8]]).unwrap_err();
/// assert_eq!(err.to_string(), "box.stl: triangles[0]: vertex 8 of 8 vertices");
/// # Ok::<(), swarf::Error>(())
/// ```
pub fn read_mesh(path: &Path, mesh: crate::geom::mesh::Mesh, ov: &Overrides) -> Result<(Input, Reading)> {
    ov.validate()?;
    let mut reading = Reading::default();
    let input = stl_input(path, mesh, ov, &mut reading)?;
    Ok((overridden(input, ov, path)?, reading))
}

/// The 3D job of an STL part read on its own: placed by the overrides, laid flat when drawn
/// sideways, in a stock box round it.
fn stl_input(path: &Path, mut mesh: crate::geom::mesh::Mesh, ov: &Overrides, reading: &mut Reading) -> Result<Input> {
    let mut place = ov.placement;
    place.scale *= ov.import.units.map_or(1.0, |u| u.mm());
    mesh.transform(&place);
    stl::check_size(path, &mesh, "part", "the unit, --part-scale and --part-translate")?;
    let mut sideways = None;
    if ov.placement.rotate_deg == [0.0; 3] {
        match stl::lay_flat(&mesh).filter(|_| ov.lay_flat) {
            Some((rot, what)) => {
                mesh.transform(&Placement { rotate_deg: rot, ..Placement::IDENTITY });
                reading.inferred.push(what);
            }
            None => sideways = stl::orientation_warning(&mesh),
        }
    }
    let (lo, hi) = mesh.bounds().ok_or_else(|| Error::input(path, "file", "the mesh is empty"))?;
    reading.kind = "STL part";
    reading.triangles = mesh.tris.len();
    let size = hi - lo;
    reading.size_mm = size.to_array();
    reading.units = match ov.import.units {
        Some(u) => format!("{} as given", unit_name(u)),
        None => "millimetres assumed: an STL file names no unit".into(),
    };
    if ov.import.units.is_none() && ov.placement.scale == 1.0 {
        reading.warnings.extend(unit_warning(size.max_element()));
    }
    reading.warnings.extend(sideways);
    let m = ov.stock_margin;
    if hi.z + ov.stock_above <= lo.z {
        return Err(Error::input(
            path,
            "file",
            "the part is flat: there is nothing above its lowest point to rough (--stock-above MM puts stock on it)",
        ));
    }
    let cutting = Cutting::with_tool_diameter(ov.tool_diameter.unwrap_or(Tool::DEFAULT.diameter));
    let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("part");
    let (stock_lo, stock_hi) =
        (DVec3::new(lo.x - m, lo.y - m, lo.z), DVec3::new(hi.x + m, hi.y + m, hi.z + ov.stock_above));
    Ok(Input::Mesh(Box::new(MeshJob::new(name, mesh, stock_lo, stock_hi, cutting))))
}

/// What a case is and its size, for the reading.
fn case_reading(input: &Input, reading: &mut Reading) {
    match input {
        Input::Flat(j) => {
            reading.kind = "case";
            if let Some((lo, hi)) = j.stock.union(&j.part).bounds() {
                reading.size_mm = [hi.x - lo.x, hi.y - lo.y, j.stock_top - j.floor];
            }
        }
        Input::Mesh(j) => {
            reading.kind = "3D case";
            reading.size_mm = (j.stock_hi - j.stock_lo).to_array();
        }
    }
}

/// The input with the overrides applied, and checked again (an error said of `path`).
fn overridden(input: Input, ov: &Overrides, path: &Path) -> Result<Input> {
    Ok(match input {
        Input::Flat(mut job) => {
            ov.apply_to_job(&mut job);
            job.validate().map_err(|e| e.in_file(path))?;
            Input::Flat(job)
        }
        Input::Mesh(mut job) => {
            ov.apply_to_mesh_job(&mut job);
            job.validate().map_err(|e| e.in_file(path))?;
            Input::Mesh(job)
        }
    })
}

fn head(path: &Path) -> Vec<u8> {
    use std::io::Read;
    let mut buf = vec![0u8; 512];
    let n = std::fs::File::open(path).and_then(|mut f| f.read(&mut buf)).unwrap_or(0);
    buf.truncate(n);
    buf
}

fn sniff_json(path: &Path) -> bool {
    head(path).iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{')
}

fn sniff_stl(path: &Path) -> bool {
    let h = head(path);
    let t = String::from_utf8_lossy(&h);
    let t = t.trim_start();
    (t.len() >= 5 && t[..5].eq_ignore_ascii_case("solid") && !t.contains("<svg") && !t.contains("SECTION"))
        || (h.len() >= 84
            && !h[..80].contains(&b'<')
            && std::fs::metadata(path).is_ok_and(|m| {
                let n = u32::from_le_bytes([h[80], h[81], h[82], h[83]]) as u64;
                m.len() == 84 + 50 * n
            }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A closed box from the origin to `s` as an ASCII STL.
    fn box_stl(s: [f64; 3]) -> String {
        let c = |i: usize| [(i & 1) as f64 * s[0], ((i >> 1) & 1) as f64 * s[1], ((i >> 2) & 1) as f64 * s[2]];
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let mut t = String::from("solid box\n");
        for q in quads {
            for tri in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                t += "facet normal 0 0 0\nouter loop\n";
                for v in tri {
                    let p = c(v);
                    t += &format!("vertex {} {} {}\n", p[0], p[1], p[2]);
                }
                t += "endloop\nendfacet\n";
            }
        }
        t + "endsolid box\n"
    }

    fn read_text(name: &str, text: &str, ov: &Overrides) -> Result<(Input, Reading)> {
        let dir = std::env::temp_dir().join(format!("swarf-reading-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let r = read_input(&path, ov);
        std::fs::remove_file(&path).ok();
        r
    }

    #[test]
    fn a_y_up_plate_is_named_and_the_rotation_that_lays_it_flat() {
        // a plain box: its two sides across Y alike, so it is not turned, only named
        let (_, r) = read_text("yup.stl", &box_stl([100.0, 10.0, 60.0]), &Overrides::DEFAULT).unwrap();
        assert!(
            r.warnings.iter().any(|w| w.contains("face Y") && w.contains("--part-rotate 90,0,0")),
            "{:?}",
            r.warnings
        );
        assert!(r.inferred.is_empty(), "{:?}", r.inferred);
        // laid flat, or turned by the user: no warning
        let (_, r) = read_text("flat.stl", &box_stl([100.0, 60.0, 10.0]), &Overrides::DEFAULT).unwrap();
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
        let turned = Overrides {
            placement: crate::geom::mesh::Placement { rotate_deg: [90.0, 0.0, 0.0], ..Default::default() },
            ..Overrides::DEFAULT
        };
        let (_, r) = read_text("yup2.stl", &box_stl([100.0, 10.0, 60.0]), &turned).unwrap();
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
        // a tower, as thin in X as in Y, is left alone
        let (_, r) = read_text("tower.stl", &box_stl([20.0, 20.0, 60.0]), &Overrides::DEFAULT).unwrap();
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    }

    /// A plate drawn Y-up with a pocket in its +Y face: its back (-Y, whole) goes down, the
    /// pocket faces up (+90° about X); or drawn with the pocket in its -Y face: +Y goes down
    /// (-90°). X-up alike.
    /// `--part-rotate`, even 0,0,0, keeps it as drawn (with the warning).
    #[test]
    fn a_part_drawn_sideways_is_laid_flat_on_its_back() {
        // a 100 × 60 plate 10 thick (in Y from 0 to 10) with a 40 × 30 pocket 5 deep in one face
        let pocketed = |mirror: bool, swap_xy: bool| -> String {
            let m = crate::geom::mesh::tests::pocket_block(10.0, 5.0);
            // pocket_block: [0,10]² × [0,10] with a [3,7]² pocket from the top (+Z) down to 5:
            // stretch it to 100 × 60 and turn its top to +Y (or -Y, or ±X)
            let mut t = String::from("solid p\n");
            for tri in &m.tris {
                t += "facet normal 0 0 0\nouter loop\n";
                // (y and z swapped is a reflection, and so is each of z → −z and x ↔ y: the
                // vertex order is reversed for each, so that the facets still face out)
                let mut vs: Vec<[f64; 3]> =
                    tri.iter().map(|v| [v.x * 10.0, if mirror { -v.z } else { v.z }, v.y * 6.0]).collect();
                if swap_xy {
                    for v in &mut vs {
                        v.swap(0, 1);
                    }
                }
                if !mirror ^ swap_xy {
                    vs.swap(1, 2);
                }
                for v in vs {
                    t += &format!("vertex {} {} {}\n", v[0], v[1], v[2]);
                }
                t += "endloop\nendfacet\n";
            }
            t + "endsolid p\n"
        };
        for (mirror, swap_xy, rot) in [
            (false, false, "+90° about X"),
            (true, false, "-90° about X"),
            (false, true, "-90° about Y"),
            (true, true, "+90° about Y"),
        ] {
            let (input, r) = read_text("side.stl", &pocketed(mirror, swap_xy), &Overrides::DEFAULT).unwrap();
            let Input::Mesh(job) = input else { panic!("a mesh job") };
            assert!(r.inferred.iter().any(|i| i.contains("laid flat") && i.contains(rot)), "{:?}", r.inferred);
            assert!(r.warnings.is_empty(), "{:?}", r.warnings);
            // flat on the table, 10 thick, the pocket's floor (5 below the top) facing up
            let (lo, hi) = job.mesh.bounds().unwrap();
            assert!((hi.z - lo.z - 10.0).abs() < 1e-9, "{lo:?} {hi:?}");
            let flats = crate::geom::mesh::flats(&job.mesh, 1e-6);
            assert!(
                flats.len() == 2 && (flats[0] - hi.z).abs() < 1e-9 && (flats[1] - (hi.z - 5.0)).abs() < 1e-9,
                "{flats:?}, top {}",
                hi.z
            );
            // kept as drawn when the user turns it, even by nothing
            let kept = Overrides { lay_flat: false, ..Overrides::DEFAULT };
            let (_, r) = read_text("side2.stl", &pocketed(mirror, swap_xy), &kept).unwrap();
            assert!(r.inferred.is_empty() && r.warnings.iter().any(|w| w.contains("--part-rotate")), "{r:?}");
        }
    }

    #[test]
    fn an_inch_part_read_as_millimetres_is_named_with_the_option() {
        let (input, r) = read_text("small.stl", &box_stl([4.0, 2.5, 1.4]), &Overrides::DEFAULT).unwrap();
        assert!(r.warnings.iter().any(|w| w.contains("--units in") && w.contains("102 mm")), "{:?}", r.warnings);
        assert!(
            r.line(&input).starts_with("read STL part 4.0 × 2.5 × 1.4 mm (millimetres assumed"),
            "{}",
            r.line(&input)
        );
        let inches = Overrides {
            import: swarf_import::ImportOptions { units: Some(swarf_import::Units::Inch), ..Default::default() },
            ..Overrides::DEFAULT
        };
        let (_, r) = read_text("small2.stl", &box_stl([4.0, 2.5, 1.4]), &inches).unwrap();
        assert!(r.warnings.is_empty() && r.units.starts_with("inches"), "{r:?}");
        // a DXF with no unit, a few mm across
        let dxf = "0\nSECTION\n2\nENTITIES\n0\nCIRCLE\n8\n0\n10\n2\n20\n2\n30\n0\n40\n1.5\n0\nENDSEC\n0\nEOF\n";
        let (_, r) =
            read_text("small.dxf", dxf, &Overrides { tool_diameter: Some(1.0), ..Overrides::DEFAULT }).unwrap();
        assert!(r.units.starts_with("millimetres assumed"), "{}", r.units);
        assert!(r.warnings.iter().any(|w| w.contains("--units in")), "{:?}", r.warnings);
    }

    #[test]
    fn the_line_says_size_counts_tool_and_width_of_cut() {
        let dxf = "0\nSECTION\n2\nHEADER\n9\n$INSUNITS\n70\n4\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n\
                   0\nLWPOLYLINE\n8\n0\n90\n4\n70\n1\n10\n0\n20\n0\n10\n80\n20\n0\n10\n80\n20\n50\n10\n0\n20\n50\n\
                   0\nCIRCLE\n8\n0\n10\n20\n20\n25\n30\n0\n40\n5\n0\nENDSEC\n0\nEOF\n";
        let (input, r) = read_text("plate.dxf", dxf, &Overrides::DEFAULT).unwrap();
        let line = r.line(&input);
        assert!(
            line.starts_with("read drawing 80.0 × 50.0 mm, 3.00 mm deep (millimetres: $INSUNITS = 4): 2 contours"),
            "{line}"
        );
        assert!(
            line.contains("1 pocket") && line.contains("tool Ø6 mm, stepover 25% (1.5 mm, reference engagement 60.0°)"),
            "{line}"
        );
        assert!(r.warnings.is_empty(), "{:?}", r.warnings);
    }
}
