//! Inputs: the benchmark case format (JSON) and drawings (DXF, SVG through `swarf-import`),
//! turned into a [`crate::model::Job`].

pub mod case;
pub mod drawing;
pub mod stl;

use crate::error::{Error, Result};
use crate::model::{Job, MeshJob};
use std::path::Path;

/// What the user may set on top of (or instead of) what the input file says.
#[derive(Debug, Clone)]
pub struct Overrides {
    /// Tool diameter, mm.
    pub tool_diameter: Option<f64>,
    /// Width of cut.
    pub width: Option<crate::model::Width>,
    /// Step-down, mm.
    pub stepdown: Option<f64>,
    /// Cutting depth below the stock top for drawings (mm); the floor of a case otherwise.
    pub depth: Option<f64>,
    /// Feed, mm/min.
    pub feed: Option<f64>,
    /// Spindle speed, rpm.
    pub spindle_rpm: Option<f64>,
    /// Stock to leave on walls, mm.
    pub allowance: Option<f64>,
    /// Drawing import options.
    pub import: swarf_import::ImportOptions,
    /// Placement of an STL part read on its own (its units' scale comes from `import.units`).
    pub placement: crate::geom::mesh::Placement,
    /// Stock round an STL part read on its own: its bounds grown by this sideways and on top, mm.
    pub stock_margin: f64,
}

/// What a case describes: a 2.5D job (polygons) or a 3D one (a mesh in a stock box).
#[derive(Debug, Clone)]
pub enum Input {
    /// Stock and part outlines.
    Flat(Job),
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
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let mut job = match ext.as_str() {
        "json" => case::read_case(path)?,
        "dxf" | "svg" => drawing::job_from_drawing(&swarf_import::read_drawing(path, &ov.import)?, ov)?,
        _ => {
            let bytes = std::fs::read(path).map_err(|e| Error::input(path, "file", format!("cannot read: {e}")))?;
            let head = String::from_utf8_lossy(&bytes[..bytes.len().min(512)]).trim_start().to_string();
            if head.starts_with('{') {
                case::read_case(path)?
            } else {
                drawing::job_from_drawing(&swarf_import::read_drawing(path, &ov.import)?, ov)?
            }
        }
    };
    apply(&mut job, ov);
    job.validate()?;
    Ok(job)
}

/// Reads a case (`.json`, 2.5D or 3D), an STL part, a DXF or an SVG file, applies the
/// overrides and validates the job.
///
/// An STL part alone gets a stock box round it (its bounds grown by `stock_margin` sideways and
/// on top, its bottom at the part's lowest point), is placed by `placement` (after the units'
/// scale), and is roughed to its lowest point with a step-down of half the tool diameter unless
/// the overrides say otherwise.
pub fn load_input(path: &Path, ov: &Overrides) -> Result<Input> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let is_stl = ext == "stl" || (ext != "json" && ext != "dxf" && ext != "svg" && sniff_stl(path));
    if is_stl {
        let mut mesh = stl::read(path)?;
        let mut place = ov.placement;
        place.scale *= ov.import.units.map_or(1.0, |u| u.mm());
        mesh.transform(&place);
        let (lo, hi) = mesh.bounds().ok_or_else(|| Error::input(path, "file", "the mesh is empty"))?;
        let m = ov.stock_margin;
        let d = ov.tool_diameter.unwrap_or(6.0);
        let mut job = MeshJob {
            name: path.file_stem().and_then(|s| s.to_str()).unwrap_or("part").to_string(),
            mesh,
            stock_lo: crate::geom::DVec3::new(lo.x - m, lo.y - m, lo.z),
            stock_hi: crate::geom::DVec3::new(hi.x + m, hi.y + m, hi.z + m),
            floor: lo.z,
            allowance: 0.0,
            allowance_floor: 0.0,
            tool: crate::model::Tool::flat(d),
            width: crate::model::Width::Stepover(0.4),
            stepdown: d / 2.0,
            feed: 1000.0,
            rapid_rate: 5000.0,
            spindle_rpm: 10000.0,
        };
        apply_mesh(&mut job, ov);
        job.validate()?;
        return Ok(Input::Mesh(Box::new(job)));
    }
    if ext == "json" || (ext != "dxf" && ext != "svg" && sniff_json(path)) {
        return match case::read_input(path)? {
            Input::Flat(mut job) => {
                apply(&mut job, ov);
                job.validate()?;
                Ok(Input::Flat(job))
            }
            Input::Mesh(mut job) => {
                apply_mesh(&mut job, ov);
                job.validate()?;
                Ok(Input::Mesh(job))
            }
        };
    }
    load_job(path, ov).map(Input::Flat)
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

impl Default for Overrides {
    fn default() -> Self {
        Overrides {
            tool_diameter: None,
            width: None,
            stepdown: None,
            depth: None,
            feed: None,
            spindle_rpm: None,
            allowance: None,
            import: Default::default(),
            placement: Default::default(),
            stock_margin: 2.0,
        }
    }
}

/// Applies the overrides both kinds of job share: tool diameter, width of cut, feed, spindle.
fn apply_cutting(
    ov: &Overrides,
    tool: &mut crate::model::Tool,
    width: &mut crate::model::Width,
    feed: &mut f64,
    spindle_rpm: &mut f64,
) {
    if let Some(d) = ov.tool_diameter {
        tool.diameter = d;
    }
    if let Some(w) = ov.width {
        *width = w;
    }
    if let Some(f) = ov.feed {
        *feed = f;
    }
    if let Some(s) = ov.spindle_rpm {
        *spindle_rpm = s;
    }
}

/// Applies overrides to a mesh job.
pub fn apply_mesh(job: &mut MeshJob, ov: &Overrides) {
    apply_cutting(ov, &mut job.tool, &mut job.width, &mut job.feed, &mut job.spindle_rpm);
    if let Some(s) = ov.stepdown {
        job.stepdown = s;
    }
    if let Some(a) = ov.allowance {
        job.allowance = a;
        job.allowance_floor = a;
    }
}

/// Applies overrides to a job.
pub fn apply(job: &mut Job, ov: &Overrides) {
    apply_cutting(ov, &mut job.tool, &mut job.width, &mut job.feed, &mut job.spindle_rpm);
    if let Some(s) = ov.stepdown {
        job.stepdown = Some(s);
    }
    if let Some(a) = ov.allowance {
        job.allowance = a;
    }
}
