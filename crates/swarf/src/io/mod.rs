//! Inputs: the benchmark case format (JSON) and drawings (DXF, SVG through `swarf-import`),
//! turned into a [`crate::model::Job`].

pub mod case;
pub mod drawing;
pub mod stl;

use crate::error::{Error, Result, Setting};
use crate::geom::DVec3;
use crate::geom::mesh::Placement;
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
    /// Stock round an STL part read on its own: its bounds grown by this sideways, mm.
    pub stock_margin: f64,
    /// Stock above an STL part read on its own, mm: 0 (the default) puts the stock's top at
    /// the part's, so that no level faces a top nobody asked to face.
    pub stock_above: f64,
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
        stock_margin: 2.0,
        stock_above: 0.0,
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
        let positive = [
            (Setting::Stepdown, self.stepdown, "mm: the step-down must be a positive number"),
            (Setting::Depth, self.depth, "mm: the depth must be positive"),
            (Setting::Feed, self.feed, "mm/min: the feed must be positive"),
            (Setting::SpindleSpeed, self.spindle_rpm, "rpm: the spindle speed must be positive"),
            (Setting::SvgDpi, Some(self.import.svg_px_per_inch), "px per inch: must be positive"),
            (Setting::FlattenTolerance, Some(self.import.flatten_tolerance), "mm: must be positive"),
        ];
        for (setting, v, what) in positive {
            if let Some(v) = v
                && !(v.is_finite() && v > 0.0)
            {
                return Err(Error::setting(setting, format!("{v} {what}")));
            }
        }
        let zero_or_more = [
            (Setting::Allowance, self.allowance),
            (Setting::ChainTolerance, Some(self.import.chain_tolerance)),
            (Setting::StockMargin, Some(self.stock_margin)),
            (Setting::StockAbove, Some(self.stock_above)),
        ];
        for (setting, v) in zero_or_more {
            if let Some(v) = v
                && !(v.is_finite() && v >= 0.0)
            {
                return Err(Error::setting(setting, format!("{v} mm: must be zero or positive")));
            }
        }
        let p = &self.placement;
        if !(p.scale.is_finite() && p.scale != 0.0) {
            return Err(Error::setting(Setting::PartScale, format!("{}: must be a non-zero number", p.scale)));
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

/// What a case describes: a 2.5D job (polygons) or a 3D one (a mesh in a stock box).
#[derive(Debug, Clone)]
pub enum Input {
    /// Stock and part outlines.
    Flat(Box<Job>),
    /// A mesh part in a stock box.
    Mesh(Box<MeshJob>),
}

/// The built-in example job (a pocket with two islands).
pub fn example_job() -> Job {
    let text = include_str!("../../examples_data/demo_pocket.json");
    match case::parse_case(std::path::Path::new("demo_pocket.json"), text.as_bytes()) {
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
/// of the tool diameter unless the overrides say otherwise. A drawing is cut [`Overrides::DEFAULT_DEPTH`] deep with the default
/// cutting data (see [`drawing::job_from_drawing`]).
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
    ov.validate()?;
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let is_stl = ext == "stl" || (ext != "json" && ext != "dxf" && ext != "svg" && sniff_stl(path));
    let is_case = !is_stl && (ext == "json" || (ext != "dxf" && ext != "svg" && sniff_json(path)));
    let input = if is_stl {
        let mut mesh = stl::read(path)?;
        let mut place = ov.placement;
        place.scale *= ov.import.units.map_or(1.0, |u| u.mm());
        mesh.transform(&place);
        let (lo, hi) = mesh.bounds().ok_or_else(|| Error::input(path, "file", "the mesh is empty"))?;
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
        Input::Mesh(Box::new(MeshJob::new(name, mesh, stock_lo, stock_hi, cutting)))
    } else if is_case {
        case::read_input(path)?
    } else {
        Input::Flat(Box::new(drawing::job_from_drawing(&swarf_import::read_drawing(path, &ov.import)?, ov)?))
    };
    Ok(match input {
        Input::Flat(mut job) => {
            ov.apply_to_job(&mut job);
            job.validate()?;
            Input::Flat(job)
        }
        Input::Mesh(mut job) => {
            ov.apply_to_mesh_job(&mut job);
            job.validate()?;
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
