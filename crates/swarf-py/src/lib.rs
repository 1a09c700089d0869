//! `swarf._swarf`: the Python face of the swarf library, built by maturin into the `swarf`
//! package (its Python half, in `python/swarf`, is what users import).
//!
//! Everything here is a thin layer over the library's own entry points: [`swarf::read_input`]
//! and [`swarf::read_case_bytes`] read a job, [`swarf::Settings`] turns keywords into options
//! (the same defaults and checks as the command line's flags), [`swarf::rough`],
//! [`swarf::rough_mesh`], [`swarf::plan_tools`] and [`swarf::job::rough::prove`] do the work,
//! with the GIL released. Errors become the exceptions of [`errors`], carrying the file, the
//! place and the reason.
//!
//! (No `forbid(unsafe_code)` here, unlike the workspace's other crates: pyo3's macros expand
//! to the unsafe FFI calls a Python extension is made of. This crate writes none itself.)

use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use swarf::geom::DVec2;
use swarf::io::output::{self, OutputFile};
use swarf::io::{Input, Overrides, Reading};
use swarf::{RoughResult, Settings, Stage, Width};

mod errors;
use errors::to_py;

/// Where a job was read from: a file, or a case held in memory.
#[derive(Clone)]
enum Source {
    File(PathBuf),
    Case { path: PathBuf, text: Vec<u8> },
    Mesh { path: PathBuf, mesh: swarf::geom::mesh::Mesh },
}

/// A job read from a file or from Python data, with the overrides it was read with.
#[pyclass(module = "swarf._swarf", name = "Job", frozen)]
struct PyJob {
    input: Input,
    reading: Reading,
    source: Source,
    overrides: Overrides,
    /// The overrides as given, to merge with later ones.
    given: Keywords,
}

impl PyJob {
    /// Reads `source` with the overrides `kw` names (an unknown one is a `TypeError`).
    fn read(py: Python<'_>, source: Source, kw: Keywords) -> PyResult<PyJob> {
        let overrides = overrides_of(py, &kw)?;
        PyJob::read_with(py, source, kw, overrides)
    }

    /// Reads `source` with `overrides`, which `kw` gave.
    fn read_with(py: Python<'_>, source: Source, kw: Keywords, overrides: Overrides) -> PyResult<PyJob> {
        let src = source.clone();
        let ov = overrides.clone();
        let (input, reading) = py
            .detach(move || match &src {
                Source::File(p) => swarf::io::read_input(p, &ov),
                Source::Case { path, text } => swarf::read_case_bytes(path, text, &ov),
                Source::Mesh { path, mesh } => swarf::io::read_mesh(path, mesh.clone(), &ov),
            })
            .map_err(|e| to_py(py, e))?;
        Ok(PyJob { input, reading, source, overrides, given: kw })
    }

    fn source_path(&self) -> &Path {
        match &self.source {
            Source::File(p) => p,
            Source::Case { path, .. } | Source::Mesh { path, .. } => path,
        }
    }

    /// The name a report gives the input: the file's name.
    fn input_name(&self) -> String {
        self.source_path().file_name().and_then(|s| s.to_str()).unwrap_or("input").to_string()
    }

    /// The job again with `kw` on top of its own overrides (the job itself when none).
    fn with(&self, py: Python<'_>, kw: Keywords) -> PyResult<Option<PyJob>> {
        if kw.is_empty() {
            return Ok(None);
        }
        let mut all: Keywords = self.given.iter().map(|(k, v)| (k.clone(), v.clone_ref(py))).collect();
        for (k, v) in kw {
            all.retain(|(a, _)| *a != k);
            all.push((k, v));
        }
        PyJob::read(py, self.source.clone(), all).map(Some)
    }
}

/// Keywords as given: (name, value) pairs.
type Keywords = Vec<(String, Py<PyAny>)>;

/// The overrides' keyword names (the command line's flags).
const OVERRIDES: [&str; 21] = [
    "tool_diameter",
    "engagement",
    "stepover",
    "stepdown",
    "depth",
    "feed",
    "max_feed",
    "spindle",
    "allowance",
    "units",
    "svg_dpi",
    "chain_tolerance",
    "cut",
    "skip_open",
    "layers",
    "ignore_layers",
    "part_rotate",
    "part_translate",
    "part_scale",
    "stock_margin",
    "stock_above",
];

/// The run settings' keyword names.
const SETTINGS: [&str; 25] = [
    "strategy",
    "post",
    "conventional",
    "order",
    "angle",
    "stock_to_leave",
    "finish",
    "ramp_angle",
    "overshoot",
    "feed_boost",
    "feed_links",
    "level_by_level",
    "full_circles",
    "zeta",
    "spiral_start",
    "spiral_floor",
    "optimise",
    "arc_tolerance",
    "clearance",
    "res",
    "sim",
    "simulate",
    "exact_every_sample",
    "decomposition",
    "exhaustive",
];

fn num(py: Python<'_>, k: &str, v: &Py<PyAny>) -> PyResult<Option<f64>> {
    let v = v.bind(py);
    if v.is_none() {
        return Ok(None);
    }
    v.extract::<f64>().map(Some).map_err(|_| {
        PyTypeError::new_err(format!("{k}: expected a number, got {}", v.repr().map_or("?".into(), |r| r.to_string())))
    })
}

fn text(py: Python<'_>, k: &str, v: &Py<PyAny>) -> PyResult<Option<String>> {
    let v = v.bind(py);
    if v.is_none() {
        return Ok(None);
    }
    v.extract::<String>().map(Some).map_err(|_| PyTypeError::new_err(format!("{k}: expected a string")))
}

fn flag(py: Python<'_>, k: &str, v: &Py<PyAny>) -> PyResult<bool> {
    let v = v.bind(py);
    if v.is_none() {
        return Ok(false);
    }
    v.extract::<bool>().map_err(|_| PyTypeError::new_err(format!("{k}: expected True or False")))
}

fn numbers<const N: usize>(py: Python<'_>, k: &str, v: &Py<PyAny>) -> PyResult<Option<[f64; N]>> {
    let v = v.bind(py);
    if v.is_none() {
        return Ok(None);
    }
    let xs: Vec<f64> = v.extract().map_err(|_| PyTypeError::new_err(format!("{k}: expected {N} numbers")))?;
    <[f64; N]>::try_from(xs).map(Some).map_err(|_| PyValueError::new_err(format!("{k}: expected {N} numbers")))
}

/// The overrides the keywords give (unknown ones are a `TypeError`).
fn overrides_of(py: Python<'_>, kw: &[(String, Py<PyAny>)]) -> PyResult<Overrides> {
    let mut ov = Overrides::DEFAULT;
    let (mut engagement, mut stepover) = (None, None);
    for (k, v) in kw {
        match k.as_str() {
            "tool_diameter" => ov.tool_diameter = num(py, k, v)?,
            "engagement" => engagement = num(py, k, v)?,
            "stepover" => stepover = num(py, k, v)?,
            "stepdown" => ov.stepdown = num(py, k, v)?,
            "depth" => ov.depth = num(py, k, v)?,
            "feed" => ov.feed = num(py, k, v)?,
            "max_feed" => ov.max_feed = num(py, k, v)?,
            "spindle" => ov.spindle_rpm = num(py, k, v)?,
            "allowance" => ov.allowance = num(py, k, v)?,
            "units" => {
                use swarf::swarf_import::Units;
                ov.import.units = match text(py, k, v)?.as_deref() {
                    None => None,
                    Some("mm") => Some(Units::Millimetre),
                    Some("in") => Some(Units::Inch),
                    Some("cm") => Some(Units::Centimetre),
                    Some("m") => Some(Units::Metre),
                    Some(u) => return Err(PyValueError::new_err(format!("units: {u:?}: expected mm, in, cm or m"))),
                }
            }
            "svg_dpi" => ov.import.svg_px_per_inch = num(py, k, v)?,
            "chain_tolerance" => {
                if let Some(t) = num(py, k, v)? {
                    ov.import.chain_tolerance = t;
                }
            }
            "cut" => {
                if let Some(c) = text(py, k, v)? {
                    ov.cut = swarf::io::drawing::Cut::parse(&c).ok_or_else(|| {
                        PyValueError::new_err(format!(
                            "cut: {c:?}: expected one of {}",
                            swarf::io::drawing::Cut::NAMES.join(", ")
                        ))
                    })?;
                }
            }
            "skip_open" => ov.import.skip_open = flag(py, k, v)?,
            "layers" | "ignore_layers" => {
                let b = v.bind(py);
                let names: Vec<String> = if b.is_none() {
                    Vec::new()
                } else {
                    b.extract().map_err(|_| PyTypeError::new_err(format!("{k}: expected a list of names")))?
                };
                if k == "layers" {
                    ov.import.layers = names;
                } else {
                    ov.import.ignore_layers = names;
                }
            }
            "part_rotate" => {
                if let Some(r) = numbers::<3>(py, k, v)? {
                    ov.placement.rotate_deg = r;
                    // (a rotation given, even 0,0,0, keeps the part as the user turned it)
                    ov.lay_flat = false;
                }
            }
            "part_translate" => {
                if let Some(t) = numbers::<3>(py, k, v)? {
                    ov.placement.translate = swarf::geom::DVec3::from_array(t);
                }
            }
            "part_scale" => {
                if let Some(s) = num(py, k, v)? {
                    ov.placement.scale = s;
                }
            }
            "stock_margin" => {
                if let Some(m) = num(py, k, v)? {
                    ov.stock_margin = m;
                }
            }
            "stock_above" => {
                if let Some(m) = num(py, k, v)? {
                    ov.stock_above = m;
                }
            }
            _ => return Err(unknown(k)),
        }
    }
    if engagement.is_some() && stepover.is_some() {
        return Err(PyValueError::new_err("engagement and stepover: give one width of cut, not both"));
    }
    ov.width = engagement.map(Width::EngagementDeg).or(stepover.map(Width::Stepover));
    Ok(ov)
}

fn unknown(k: &str) -> PyErr {
    PyTypeError::new_err(format!(
        "unexpected keyword {k:?}: the job's are {}; the run's are {}",
        OVERRIDES.join(", "),
        SETTINGS.join(", ")
    ))
}

/// The run settings the keywords give.
fn settings_of(py: Python<'_>, kw: &[(String, Py<PyAny>)]) -> PyResult<Settings> {
    let mut s = Settings::default();
    for (k, v) in kw {
        match k.as_str() {
            "strategy" => s.strategy = text(py, k, v)?,
            "post" => s.post = text(py, k, v)?,
            "conventional" => s.conventional = flag(py, k, v)?,
            "order" => s.order = text(py, k, v)?,
            "angle" => s.angle = num(py, k, v)?,
            "stock_to_leave" => s.stock_to_leave = num(py, k, v)?,
            "finish" => s.finish = flag(py, k, v)?,
            "ramp_angle" => s.ramp_angle = num(py, k, v)?,
            "overshoot" => s.overshoot = num(py, k, v)?,
            "feed_boost" => s.feed_boost = num(py, k, v)?,
            "feed_links" => s.feed_links = flag(py, k, v)?,
            "level_by_level" => s.level_by_level = flag(py, k, v)?,
            "full_circles" => s.full_circles = flag(py, k, v)?,
            "zeta" => s.zeta = num(py, k, v)?,
            "spiral_start" => s.spiral_start = numbers::<2>(py, k, v)?.map(|[x, y]| DVec2::new(x, y)),
            "spiral_floor" => s.spiral_floor = num(py, k, v)?,
            "optimise" => s.optimise = flag(py, k, v)?,
            "arc_tolerance" => s.arc_tolerance = num(py, k, v)?,
            "clearance" => s.clearance = num(py, k, v)?,
            "res" => s.res = num(py, k, v)?,
            "sim" => s.sim = text(py, k, v)?,
            "simulate" => {
                let b = v.bind(py);
                s.no_simulate = !(b.is_none()
                    || b.extract::<bool>().map_err(|_| PyTypeError::new_err("simulate: expected True or False"))?);
            }
            "exact_every_sample" => s.exact_every_sample = flag(py, k, v)?,
            "decomposition" => s.decomposition = text(py, k, v)?,
            "exhaustive" => s.exhaustive = flag(py, k, v)?,
            _ => return Err(unknown(k)),
        }
    }
    Ok(s)
}

fn pairs(kw: Option<&Bound<'_, PyDict>>) -> PyResult<Keywords> {
    let mut v = Vec::new();
    if let Some(d) = kw {
        for (k, val) in d.iter() {
            v.push((k.extract::<String>()?, val.unbind()));
        }
    }
    Ok(v)
}

/// Splits keywords into the job's overrides and the run's settings.
fn split(kw: Keywords) -> PyResult<(Keywords, Keywords)> {
    let mut job = Vec::new();
    let mut run = Vec::new();
    for (k, v) in kw {
        if OVERRIDES.contains(&k.as_str()) {
            job.push((k, v));
        } else if SETTINGS.contains(&k.as_str()) {
            run.push((k, v));
        } else {
            return Err(unknown(&k));
        }
    }
    Ok((job, run))
}

#[pymethods]
impl PyJob {
    /// "2.5d" (outlines and depths) or "3d" (a mesh part in a stock box).
    #[getter]
    fn kind(&self) -> &'static str {
        match self.input {
            Input::Flat(_) => "2.5d",
            Input::Mesh(_) => "3d",
        }
    }

    /// The job's name (the file's stem).
    #[getter]
    fn name(&self) -> String {
        match &self.input {
            Input::Flat(j) => j.name.clone(),
            Input::Mesh(j) => j.name.clone(),
        }
    }

    /// The file the job was read from (or the name a case held in memory was given).
    #[getter]
    fn path(&self) -> PathBuf {
        self.source_path().to_path_buf()
    }

    /// The tool's diameter, mm.
    #[getter]
    fn tool_diameter(&self) -> f64 {
        match &self.input {
            Input::Flat(j) => j.cutting.tool.diameter,
            Input::Mesh(j) => j.cutting.tool.diameter,
        }
    }

    /// The reference engagement (a straight cut at the width of cut), degrees.
    #[getter]
    fn engagement_deg(&self) -> f64 {
        match &self.input {
            Input::Flat(j) => j.cutting.width.engagement_deg(),
            Input::Mesh(j) => j.cutting.width.engagement_deg(),
        }
    }

    /// What was read, in one line (as `swarf rough` prints it).
    #[getter]
    fn summary(&self) -> String {
        self.reading.line(&self.input)
    }

    /// What looks meant otherwise in the input, each with the option that fixes it.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.reading.warnings.clone()
    }

    /// Every file read: the input and the STL a 3D case names.
    #[getter]
    fn files(&self) -> Vec<PathBuf> {
        self.reading.files.clone()
    }

    /// The job again with more overrides.
    #[pyo3(signature = (**kw))]
    fn with_overrides(&self, py: Python<'_>, kw: Option<&Bound<'_, PyDict>>) -> PyResult<PyJob> {
        let kw = pairs(kw)?;
        Ok(match self.with(py, kw)? {
            Some(j) => j,
            None => PyJob {
                input: self.input.clone(),
                reading: self.reading.clone(),
                source: self.source.clone(),
                overrides: self.overrides.clone(),
                given: self.given.iter().map(|(k, v)| (k.clone(), v.clone_ref(py))).collect(),
            },
        })
    }

    /// A job from a case given as Python data: the case format's keys (`stock`, `part`,
    /// `floor`, `tool`, …), point lists as lists or NumPy arrays of shape (n, 2). `name` names
    /// the job (and the case in errors, as `NAME.json`); a 3D case's `part_stl` is read
    /// relative to `base_dir` (the working folder when not given). Keywords override the case
    /// as in `load`.
    #[staticmethod]
    #[pyo3(signature = (case, name="job", base_dir=None, **kw))]
    fn from_dict(
        py: Python<'_>,
        case: &Bound<'_, PyAny>,
        name: &str,
        base_dir: Option<PathBuf>,
        kw: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PyJob> {
        let plain = py.import("swarf")?.getattr("_plain")?;
        let opts = PyDict::new(py);
        opts.set_item("default", plain)?;
        let text: String = py.import("json")?.call_method("dumps", (case,), Some(&opts))?.extract()?;
        let path = base_dir.unwrap_or_default().join(format!("{name}.json"));
        load_case_text(py, &text, path, kw)
    }

    /// A 3D job from a mesh given as Python data: `vertices` (n, 3) and `triangles` (m, 3)
    /// (indices into the vertices, counter-clockwise seen from outside), as lists or NumPy
    /// arrays. It is roughed as an STL part read on its own: placed and given its stock box by
    /// the overrides (`stock_margin`, `stock_above`, `part_rotate`, …). `name` names the job
    /// (and the mesh in errors, as `NAME.stl`).
    #[staticmethod]
    #[pyo3(signature = (vertices, triangles, name="part", **kw))]
    fn from_mesh(
        py: Python<'_>,
        vertices: &Bound<'_, PyAny>,
        triangles: &Bound<'_, PyAny>,
        name: &str,
        kw: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PyJob> {
        let kw = pairs(kw)?;
        // (a bad keyword before the mesh's arrays are read)
        let overrides = overrides_of(py, &kw)?;
        let np = py.import("numpy")?;
        let v = np.call_method1("ascontiguousarray", (vertices, "float64"))?;
        let t = np.call_method1("ascontiguousarray", (triangles, "int64"))?;
        let v = v
            .cast::<numpy::PyArray2<f64>>()
            .map_err(|_| PyValueError::new_err("vertices: expected an (n, 3) array of numbers"))?;
        let t = t
            .cast::<numpy::PyArray2<i64>>()
            .map_err(|_| PyValueError::new_err("triangles: expected an (m, 3) array of vertex indices"))?;
        let (vr, tr) = (v.readonly(), t.readonly());
        let (va, ta) = (vr.as_array(), tr.as_array());
        if va.ncols() != 3 || ta.ncols() != 3 {
            return Err(PyValueError::new_err(format!(
                "vertices {:?} and triangles {:?}: each must have 3 columns",
                va.shape(),
                ta.shape()
            )));
        }
        let path = PathBuf::from(format!("{name}.stl"));
        let verts: Vec<[f64; 3]> = va.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect();
        let mut tris: Vec<[usize; 3]> = Vec::with_capacity(ta.nrows());
        for (i, r) in ta.rows().into_iter().enumerate() {
            let mut t = [0usize; 3];
            for (k, slot) in t.iter_mut().enumerate() {
                *slot = usize::try_from(r[k]).map_err(|_| {
                    to_py(
                        py,
                        swarf::Error::input(
                            &path,
                            format!("triangles[{i}]"),
                            format!("vertex {}: indices start at 0", r[k]),
                        ),
                    )
                })?;
            }
            tris.push(t);
        }
        let mesh = swarf::io::stl::from_triangles(&path, &verts, &tris).map_err(|e| to_py(py, e))?;
        PyJob::read_with(py, Source::Mesh { path, mesh }, kw, overrides)
    }

    fn __repr__(&self) -> String {
        format!("<swarf.Job {} ({}), tool Ø{} mm>", self.name(), self.kind(), self.tool_diameter())
    }
}

/// Reads a job from a file: a case (`.json`, 2.5D or 3D), an STL part, a DXF or an SVG
/// drawing, with the overrides given as keywords.
#[pyfunction]
#[pyo3(signature = (path, **kw))]
fn load(py: Python<'_>, path: PathBuf, kw: Option<&Bound<'_, PyDict>>) -> PyResult<PyJob> {
    PyJob::read(py, Source::File(path), pairs(kw)?)
}

/// Reads a case held in memory (its JSON text); `path` names it in errors and locates a 3D
/// case's `part_stl`.
#[pyfunction]
#[pyo3(signature = (text, path, **kw))]
fn load_case_text(py: Python<'_>, text: &str, path: PathBuf, kw: Option<&Bound<'_, PyDict>>) -> PyResult<PyJob> {
    PyJob::read(py, Source::Case { path, text: text.as_bytes().to_vec() }, pairs(kw)?)
}

/// A progress callback called from swarf's threads: at most every 1 % of a stage (and at each
/// stage's start and end); the first exception it raises is kept and raised when the run ends.
struct Progress {
    cb: Option<Py<PyAny>>,
    last: Mutex<(i32, f64)>,
    err: Mutex<Option<PyErr>>,
}

impl Progress {
    fn new(cb: Option<Py<PyAny>>) -> Progress {
        Progress { cb, last: Mutex::new((-1, -1.0)), err: Mutex::new(None) }
    }

    fn call(&self, stage: &str, code: i32, f: f64) {
        let Some(cb) = &self.cb else { return };
        {
            let Ok(mut last) = self.last.lock() else { return };
            if last.0 == code && f < 1.0 && f - last.1 < 0.01 {
                return;
            }
            *last = (code, f);
        }
        if self.err.lock().map_or(true, |e| e.is_some()) {
            return;
        }
        Python::attach(|py| {
            if let (Err(e), Ok(mut slot)) = (cb.call1(py, (stage, f)), self.err.lock()) {
                slot.get_or_insert(e);
            }
        });
    }

    fn finish(self) -> PyResult<()> {
        match self.err.into_inner() {
            Ok(Some(e)) => Err(e),
            _ => Ok(()),
        }
    }
}

fn stage_name(s: Stage) -> (&'static str, i32) {
    match s {
        Stage::Plan => ("plan", 0),
        Stage::Simulate => ("simulate", 1),
    }
}

/// What `rough` produced: the G-code, the report (JSON), the program and the simulation's
/// samples.
#[pyclass(module = "swarf._swarf", name = "RoughOutput", frozen)]
struct PyRough {
    res: RoughResult,
    /// The files the job was read from (no output may replace one).
    inputs: Vec<PathBuf>,
}

#[pymethods]
impl PyRough {
    /// The G-code.
    #[getter]
    fn gcode(&self) -> &str {
        &self.res.gcode
    }

    /// The report as JSON (the command line's `--report`).
    #[getter]
    fn report_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.res.report).map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// The moves: (end points (N, 3), kind codes (N,), feeds (N,), arc directions (N,),
    /// arc centres (N, 2), the start (3,), the tool's diameter).
    fn moves<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyTuple>> {
        toolpath_arrays(py, &self.res.toolpath)
    }

    /// The simulation's samples as an (M, 9) array (see `swarf.ENGAGEMENT_COLUMNS`); None when
    /// the program was not simulated.
    fn samples<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let Some(rp) = &self.res.replay else { return Ok(None) };
        let mut v = Vec::with_capacity(rp.samples.len() * 9);
        for s in &rp.samples {
            let kind = match s.kind {
                swarf::sim::SampleKind::Lateral => 0.0,
                swarf::sim::SampleKind::Descending => 1.0,
                swarf::sim::SampleKind::Plunge => 2.0,
            };
            v.extend([
                s.s,
                s.at.x,
                s.at.y,
                s.at.z,
                f64::from(s.tea),
                f64::from(s.tea_pixel),
                kind,
                f64::from(u8::from(s.bore)),
                f64::from(s.mi),
            ]);
        }
        let n = rp.samples.len();
        Ok(Some(PyArray1::from_vec(py, v).reshape([n, 9])?.into_any()))
    }

    /// Writes the G-code to `path` (and the report, as JSON, to `report` when given) atomically:
    /// each file appears whole or not at all, and none may replace one of the job's inputs.
    #[pyo3(signature = (path, report=None))]
    fn write(&self, py: Python<'_>, path: PathBuf, report: Option<PathBuf>) -> PyResult<()> {
        let mut files = vec![OutputFile::new(&path, self.res.gcode.clone())];
        if let Some(r) = report {
            let json =
                serde_json::to_string_pretty(&self.res.report).map_err(|e| PyValueError::new_err(e.to_string()))?;
            files.push(OutputFile::new(r, json + "\n"));
        }
        commit(py, &files, &self.inputs)
    }
}

fn commit(py: Python<'_>, files: &[OutputFile], inputs: &[PathBuf]) -> PyResult<()> {
    py.detach(|| {
        let ins: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
        output::check(&files.iter().map(|f| f.path.as_path()).collect::<Vec<_>>(), &ins)?;
        output::commit(files, &ins)
    })
    .map_err(|e| to_py(py, e))
}

fn toolpath_arrays<'py>(py: Python<'py>, tp: &swarf::Toolpath) -> PyResult<Bound<'py, pyo3::types::PyTuple>> {
    use swarf::toolpath::Motion;
    let n = tp.moves.len();
    let (mut xyz, mut kind, mut feed, mut arc, mut centre) = (
        Vec::with_capacity(n * 3),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n),
        Vec::with_capacity(n * 2),
    );
    for m in &tp.moves {
        xyz.extend(m.to.to_array());
        kind.push(m.kind.code());
        feed.push(if m.is_rapid() { 0.0 } else { m.feed });
        match m.motion {
            Motion::Line => {
                arc.push(0i8);
                centre.extend([f64::NAN, f64::NAN]);
            }
            Motion::Arc { center, ccw } => {
                arc.push(if ccw { 1 } else { -1 });
                centre.extend([center.x, center.y]);
            }
        }
    }
    let xyz = PyArray1::from_vec(py, xyz).reshape([n, 3])?;
    let centre = PyArray1::from_vec(py, centre).reshape([n, 2])?;
    let start = PyArray1::from_vec(py, tp.start.to_array().to_vec());
    (
        xyz,
        PyArray1::from_vec(py, kind),
        PyArray1::from_vec(py, feed),
        PyArray1::from_vec(py, arc),
        centre,
        start,
        tp.tool.diameter,
    )
        .into_pyobject(py)
}

/// Roughs a job: plans, posts and (unless `simulate=False`) proves the program, with the GIL
/// released. Keywords are the job's overrides (`tool_diameter`, `engagement`, …, read again
/// with them) and the run's settings (`strategy`, `post`, …).
#[pyfunction]
#[pyo3(signature = (job, progress=None, **kw))]
fn rough(
    py: Python<'_>,
    job: &PyJob,
    progress: Option<Py<PyAny>>,
    kw: Option<&Bound<'_, PyDict>>,
) -> PyResult<PyRough> {
    let (jkw, rkw) = split(pairs(kw)?)?;
    let settings = settings_of(py, &rkw)?;
    let again = job.with(py, jkw)?;
    let job = again.as_ref().unwrap_or(job);
    let opts = settings.rough_options(job.input_name()).map_err(|e| to_py(py, e))?;
    let progress = Progress::new(progress);
    let path = job.source_path().to_path_buf();
    let res = py.detach(|| {
        let mut tell = |s: Stage, f: f64| {
            let (name, code) = stage_name(s);
            progress.call(name, code, f);
        };
        match &job.input {
            Input::Flat(j) => swarf::rough(j, &opts, &mut tell),
            Input::Mesh(j) => swarf::rough_mesh(j, &opts, &mut tell),
        }
        .map_err(|e| e.in_file(&path))
    });
    progress.finish()?;
    let res = res.map_err(|e| to_py(py, e))?;
    Ok(PyRough { res, inputs: job.reading.files.clone() })
}

/// Proves a program given as G-code on a 2.5D job as `rough` proves its own: the report (JSON)
/// of its simulation. `tool_diameter` is the program's tool when it is not the job's.
#[pyfunction]
#[pyo3(signature = (job, gcode, name="program.ngc", tool_diameter=None, **kw))]
fn check(
    py: Python<'_>,
    job: &PyJob,
    gcode: &str,
    name: &str,
    tool_diameter: Option<f64>,
    kw: Option<&Bound<'_, PyDict>>,
) -> PyResult<String> {
    let settings = settings_of(py, &pairs(kw)?)?;
    let Input::Flat(j) = &job.input else {
        return Err(PyValueError::new_err("check: a 2.5D job (a case, a drawing); 3D jobs are proven by rough"));
    };
    let mut tool = j.cutting.tool.clone();
    if let Some(d) = tool_diameter {
        tool.diameter = d;
    }
    let opts = settings.rough_options(name).map_err(|e| to_py(py, e))?;
    let file = PathBuf::from(name);
    let rep = py
        .detach(|| {
            let prog =
                swarf::io::gcode::read(gcode, &file, &swarf::io::gcode::ReadOptions { tool, clearance_z: None })?;
            swarf::job::rough::prove(j, &prog.toolpath, &opts)
        })
        .map_err(|e| to_py(py, e))?;
    serde_json::to_string(&rep).map_err(|e| PyValueError::new_err(e.to_string()))
}

/// The cheapest tool sequence for a 3D job from a tool database (a file, or its JSON text
/// with `tools_text`): the programs' names and G-code, and the plan's report (JSON).
#[pyfunction]
#[pyo3(signature = (job, tools, tools_text=None, **kw))]
fn plan_tools<'py>(
    py: Python<'py>,
    job: &PyJob,
    tools: PathBuf,
    tools_text: Option<&str>,
    kw: Option<&Bound<'py, PyDict>>,
) -> PyResult<(Bound<'py, PyList>, String)> {
    let (jkw, rkw) = split(pairs(kw)?)?;
    let settings = settings_of(py, &rkw)?;
    let again = job.with(py, jkw)?;
    let job = again.as_ref().unwrap_or(job);
    let Input::Mesh(mj) = &job.input else {
        return Err(to_py(
            py,
            swarf::Error::input(
                job.source_path(),
                "file",
                "plan_tools needs a 3D job: a case with part_stl, or an STL part",
            ),
        ));
    };
    let post = settings.post().map_err(|e| to_py(py, e))?;
    let opts = settings.seq_options().map_err(|e| to_py(py, e))?;
    let input_name = job.input_name();
    let tools_file = tools.display().to_string();
    let path = job.source_path().to_path_buf();
    let posted = py
        .detach(|| {
            let db = match tools_text {
                Some(t) => swarf::model::tooldb::ToolDb::parse(&tools, t.as_bytes())?,
                None => swarf::model::tooldb::ToolDb::read(&tools)?,
            };
            let t0 = std::time::Instant::now();
            let sp = swarf::plan_tools(mj, &db, &opts).map_err(|e| e.in_file(&path))?;
            let about = swarf::job::toolseq::PostAbout {
                input_name: &input_name,
                tools_file: &tools_file,
                decomposition: opts.decomposition,
                compute_s: t0.elapsed().as_secs_f64(),
                rest_pictures: false,
            };
            swarf::job::toolseq::post_plan(&sp, &db, post, &about)
        })
        .map_err(|e| to_py(py, e))?;
    let list = PyList::empty(py);
    for p in &posted.programs {
        list.append((p.name.clone(), p.gcode.clone(), toolpath_arrays(py, &p.toolpath)?))?;
    }
    Ok((list, posted.report.to_string()))
}

/// Writes `files` ((path, text) pairs) atomically: each appears whole or not at all, none may
/// replace one of `inputs`, and none is written when one is refused.
#[pyfunction]
#[pyo3(signature = (files, inputs=Vec::new()))]
fn write_files(py: Python<'_>, files: Vec<(PathBuf, Vec<u8>)>, inputs: Vec<PathBuf>) -> PyResult<()> {
    let files: Vec<OutputFile> = files.into_iter().map(|(p, b)| OutputFile::new(p, b)).collect();
    commit(py, &files, &inputs)
}

/// The strategies' names, the posts' names and swarf's version.
#[pymodule]
fn _swarf(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyJob>()?;
    m.add_class::<PyRough>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(load_case_text, m)?)?;
    m.add_function(wrap_pyfunction!(rough, m)?)?;
    m.add_function(wrap_pyfunction!(check, m)?)?;
    m.add_function(wrap_pyfunction!(plan_tools, m)?)?;
    m.add_function(wrap_pyfunction!(write_files, m)?)?;
    m.add("STRATEGIES", swarf::Strategy::NAMES.to_vec())?;
    m.add("POSTS", swarf::Post::NAMES.to_vec())?;
    m.add("OVERRIDES", OVERRIDES.to_vec())?;
    m.add("SETTINGS", SETTINGS.to_vec())?;
    m.add("MOVE_KINDS", swarf::toolpath::MoveKind::NAMES.to_vec())?;
    m.add("EXAMPLE_CASE", swarf::io::EXAMPLE_CASE)?;
    m.add("DEFAULT_STEPDOWN_FRACTION", swarf::MeshJob::DEFAULT_STEPDOWN_FRACTION)?;
    m.add("VERSION", env!("CARGO_PKG_VERSION"))?;
    errors::register(m)?;
    Ok(())
}
