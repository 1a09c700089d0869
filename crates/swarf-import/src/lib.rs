//! # swarf-import: drawings into contours
//!
//! Reads the 2D drawings a CNC programmer already has — DXF (R12 to 2018) and SVG — into closed
//! [`Contour`]s in millimetres, keeping circular arcs as arcs (bulge form) so that the toolpaths
//! built from them can be written as G2/G3. Loose entities are chained into contours within a
//! tolerance; a contour that stays open is refused with the size and place of each gap.
//!
//! Roles: shapes on layers (DXF) or groups (SVG) named `STOCK`, `PART` or `FIXTURE` (any case)
//! get that role; everything else is [`Role::Auto`], which the model interprets by nesting
//! (outermost contour = pocket wall, nested contours alternate island / pocket).
//!
//! ```no_run
//! let drawing = swarf_import::read_drawing("part.dxf".as_ref(), &Default::default()).unwrap();
//! for s in &drawing.shapes {
//!     println!("{:?} {} vertices, area {:.1} mm²", s.role, s.contour.vertices.len(), s.contour.signed_area().abs());
//! }
//! ```

pub mod chain;
pub mod contour;
pub mod dxf;
pub mod svg;

use std::path::{Path, PathBuf};

pub use contour::{Contour, Segment, Vertex};

/// Length units of a drawing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Units {
    /// Millimetres.
    Millimetre,
    /// Centimetres.
    Centimetre,
    /// Metres.
    Metre,
    /// Inches (25.4 mm).
    Inch,
    /// Feet (304.8 mm).
    Foot,
    /// Thousandths of an inch.
    Mil,
    /// Micrometres.
    Micrometre,
}

impl Units {
    /// Millimetres per unit.
    pub fn mm(self) -> f64 {
        match self {
            Units::Millimetre => 1.0,
            Units::Centimetre => 10.0,
            Units::Metre => 1000.0,
            Units::Inch => 25.4,
            Units::Foot => 304.8,
            Units::Mil => 0.0254,
            Units::Micrometre => 0.001,
        }
    }

    /// Parses `mm`, `cm`, `m`, `in`/`inch`, `ft`, `mil`, `um`.
    pub fn parse(s: &str) -> Option<Units> {
        Some(match s.trim().to_ascii_lowercase().as_str() {
            "mm" | "millimetre" | "millimeter" | "millimetres" | "millimeters" => Units::Millimetre,
            "cm" | "centimetre" | "centimeter" => Units::Centimetre,
            "m" | "metre" | "meter" | "metres" | "meters" => Units::Metre,
            "in" | "inch" | "inches" => Units::Inch,
            "ft" | "foot" | "feet" => Units::Foot,
            "mil" | "thou" => Units::Mil,
            "um" | "µm" | "micron" | "microns" => Units::Micrometre,
            _ => return None,
        })
    }
}

/// What a shape is in the job.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// Raw material outline.
    Stock,
    /// Material that must stay.
    Part,
    /// Forbidden area (clamps, vice jaws).
    Fixture,
    /// No role given: decided by nesting.
    Auto,
}

impl Role {
    /// The role a layer or group name asks for (`STOCK`, `PART`, `FIXTURE`, any case).
    pub fn from_layer_name(name: &str) -> Role {
        match name.trim().to_ascii_uppercase().as_str() {
            "STOCK" => Role::Stock,
            "PART" => Role::Part,
            "FIXTURE" | "FIXTURES" => Role::Fixture,
            _ => Role::Auto,
        }
    }
}

/// One closed contour of a drawing.
#[derive(Debug, Clone, PartialEq)]
pub struct Shape {
    /// The geometry, in millimetres.
    pub contour: Contour,
    /// Its role.
    pub role: Role,
    /// Layer (DXF) or group label (SVG) it came from; empty when none.
    pub layer: String,
    /// Where it came from, for messages (e.g. `LWPOLYLINE at line 812`).
    pub origin: String,
}

/// A drawing read from a file.
#[derive(Debug, Clone, PartialEq)]
pub struct Drawing {
    /// The file it was read from.
    pub path: PathBuf,
    /// The units the file was in (already converted to mm in `shapes`).
    pub units: Units,
    /// Where `units` came from, or why they were assumed, for the user (`$INSUNITS = 1`,
    /// `no $INSUNITS`, `given`, …).
    pub units_from: String,
    /// True when the file names no unit and `units` is a guess.
    pub units_assumed: bool,
    /// Its closed contours.
    pub shapes: Vec<Shape>,
    /// The open contours left out ([`ImportOptions::skip_open`]), each with its place and gaps.
    pub skipped: Vec<String>,
    /// The layers (DXF) or groups (SVG) that held geometry, in file order, before any was left
    /// out by [`ImportOptions::layers`] or [`ImportOptions::ignore_layers`].
    pub layers: Vec<String>,
}

/// Options for reading drawings.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportOptions {
    /// Use these units whatever the file says.
    pub units: Option<Units>,
    /// Endpoints closer than this (in mm, after unit conversion) are joined when chaining loose
    /// entities into contours. Default 0.01 mm.
    pub chain_tolerance: f64,
    /// Largest distance (mm) between a curve that cannot be kept exactly (spline, ellipse,
    /// Bézier) and the lines that replace it. Default 0.002 mm.
    pub flatten_tolerance: f64,
    /// SVG user units per inch (CSS: 96; Inkscape before 0.92 used 90). `None`: 96, or 90 for
    /// a file whose `inkscape:version` is older than 0.92.
    pub svg_px_per_inch: Option<f64>,
    /// Leave out contours that stay open after chaining (listed in [`Drawing::skipped`])
    /// instead of refusing the drawing.
    pub skip_open: bool,
    /// Read only these layers (DXF) or groups (SVG, by label or id, at any depth), any case;
    /// empty: all of them.
    pub layers: Vec<String>,
    /// Leave out these layers or groups, any case.
    pub ignore_layers: Vec<String>,
}

impl ImportOptions {
    /// The units the file says, 0.01 mm chaining, 0.002 mm flattening, SVG pixels per inch as the file's writer meant them,
    /// open contours refused, every layer read.
    pub const DEFAULT: ImportOptions = ImportOptions {
        units: None,
        chain_tolerance: 0.01,
        flatten_tolerance: 0.002,
        svg_px_per_inch: None,
        skip_open: false,
        layers: Vec::new(),
        ignore_layers: Vec::new(),
    };

    /// Whether geometry under these layer or group names is read ([`ImportOptions::layers`],
    /// [`ImportOptions::ignore_layers`]; names compared trimmed and in any case).
    pub fn reads_layer<'a>(&self, names: impl IntoIterator<Item = &'a str> + Clone) -> bool {
        let is = |want: &String, n: &str| want.trim().eq_ignore_ascii_case(n.trim());
        let named = |list: &[String]| names.clone().into_iter().any(|n| list.iter().any(|w| is(w, n)));
        (self.layers.is_empty() || named(&self.layers)) && !named(&self.ignore_layers)
    }
}

impl Default for ImportOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A drawing that cannot be read, with the file, the place in it and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}: {place}: {reason}", file.display())]
pub struct ImportError {
    /// The file.
    pub file: PathBuf,
    /// Where in it (`line 12`, `entity 4 (ARC) at line 230`, `path id="p3"`, `near (23.000, 109.000)`).
    pub place: String,
    /// What is wrong.
    pub reason: String,
}

impl ImportError {
    /// Builds an error.
    pub fn new(file: &Path, place: impl Into<String>, reason: impl Into<String>) -> Self {
        Self { file: file.to_path_buf(), place: place.into(), reason: reason.into() }
    }
}

/// Reads a DXF or SVG file, choosing the reader by extension (`.dxf`, `.svg`), or by content
/// when the extension is neither.
pub fn read_drawing(path: &Path, opts: &ImportOptions) -> Result<Drawing, ImportError> {
    let bytes = std::fs::read(path).map_err(|e| ImportError::new(path, "file", format!("cannot read: {e}")))?;
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    match ext.as_str() {
        "dxf" => dxf::read_dxf(path, &bytes, opts),
        "svg" => svg::read_svg(path, &bytes, opts),
        _ => {
            let head = String::from_utf8_lossy(&bytes[..bytes.len().min(4096)]).to_ascii_lowercase();
            if head.contains("<svg") {
                svg::read_svg(path, &bytes, opts)
            } else if head.contains("section") {
                dxf::read_dxf(path, &bytes, opts)
            } else {
                Err(ImportError::new(path, "file", "neither a DXF nor an SVG drawing (expected a .dxf or .svg file)"))
            }
        }
    }
}
