//! DXF reader: ASCII DXF (R12 to 2018) into closed contours in millimetres.
//!
//! A hand parser of the group-code pairs (the `dxf` crate keeps no line numbers, and every
//! message names the entity and its line, `ARC (handle 2F) at line 1234`) that reads `HEADER`
//! (`$INSUNITS`), `BLOCKS` and `ENTITIES`: `LINE`, `ARC`, `CIRCLE`, `LWPOLYLINE` and 2D
//! `POLYLINE` with exact arcs (bulges), `SPLINE` and `ELLIPSE` (flattened within
//! [`ImportOptions::flatten_tolerance`] where not circular), `INSERT`/`MINSERT` of nested
//! blocks, and the object coordinate system. Units come from `$INSUNITS` unless
//! [`ImportOptions::units`] says otherwise; roles come from layer names
//! ([`Role::from_layer_name`]); open pieces are joined by [`chain::chain`] per role. Bad input is
//! an error, never a panic, and block expansion and flattening are bounded. The entities, units,
//! layers and messages in full are in `docs/import.md`.

use crate::chain::{self, Piece};
use crate::contour::{Contour, Segment, Vertex};
use crate::{Drawing, ImportError, ImportOptions, Role, Shape, Units};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// Most vertices in one drawing (flattened curves counted twice).
const MAX_POINTS: usize = 5_000_000;
/// Deepest nesting of block insertions.
const MAX_DEPTH: usize = 32;
/// Most copies one `MINSERT` may make.
const MAX_COPIES: usize = 100_000;
/// Most entities read, counting each copy that block insertion makes.
const MAX_ENTITIES: usize = 1_000_000;
/// Highest spline degree accepted.
const MAX_DEGREE: usize = 25;
/// Points closer than this (mm) are the same point: zero-length segments are removed.
const SAME_POINT_MM: f64 = 1e-9;

/// Reads a DXF drawing from its bytes (`path` is only used in messages).
///
/// Returns the closed contours in millimetres, in file order (a chained contour sits where its
/// first entity is). Fails, with the place and the reason, on binary DXF, DWG, garbage,
/// truncated files, malformed or non-finite numbers, unsupported units, invalid splines, missing
/// or recursive blocks, chains left open (naming each gap), and drawings without any closed
/// contour.
pub fn read_dxf(path: &Path, bytes: &[u8], opts: &ImportOptions) -> Result<Drawing, ImportError> {
    let text = decode(path, bytes)?;
    let pairs = tokenize(path, &text)?;
    let file = split_sections(path, &pairs)?;

    let (units, units_from, units_assumed) = match opts.units {
        Some(u) => (u, "given".to_string(), false),
        None => header_units(path, &file.header)?,
    };
    let scale = units.mm();
    let flatten_mm =
        if opts.flatten_tolerance.is_finite() && opts.flatten_tolerance > 0.0 { opts.flatten_tolerance } else { 0.002 };

    let mut reader = Reader {
        path,
        blocks: &file.blocks,
        tol: flatten_mm / scale,
        eps: SAME_POINT_MM / scale,
        pieces: Vec::new(),
        ignored: BTreeMap::new(),
        paper_space: 0,
        points: 0,
        entities: 0,
    };
    let top = Context { xf: Affine::IDENTITY, layer: None, suffix: String::new(), stack: Vec::new() };
    reader.walk(&file.entities, &top)?;

    // to millimetres
    let Reader { pieces, ignored, paper_space, .. } = reader;
    // pieces by role, with the layer and file-order index of each
    type Group = (Role, Vec<Piece>, Vec<(String, usize)>);
    let mut by_role: Vec<Group> = Vec::new();
    let mut geometry = 0usize;
    let mut layers: Vec<String> = Vec::new();
    let mut left_out = 0usize;
    for (index, mut p) in pieces.into_iter().enumerate() {
        if !layers.contains(&p.layer) {
            layers.push(p.layer.clone());
        }
        if !opts.reads_layer([p.layer.as_str()]) {
            left_out += 1;
            continue;
        }
        p.contour.scale(scale);
        if !p.contour.is_finite() {
            return Err(ImportError::new(
                path,
                p.origin,
                "coordinates too large: they overflow when converted to millimetres",
            ));
        }
        geometry += 1;
        let role = Role::from_layer_name(&p.layer);
        let slot = match by_role.iter().position(|(r, _, _)| *r == role) {
            Some(k) => k,
            None => {
                by_role.push((role, Vec::new(), Vec::new()));
                by_role.len() - 1
            }
        };
        if let Some((_, ps, info)) = by_role.get_mut(slot) {
            ps.push(Piece { contour: p.contour, origin: p.origin });
            info.push((p.layer, index));
        }
    }

    let mut shapes: Vec<(usize, Shape)> = Vec::new();
    let mut open = Vec::new();
    for (role, ps, info) in by_role {
        // origin -> (layer, file-order index) of the first piece with that origin
        let mut first: HashMap<String, (String, usize)> = HashMap::new();
        for (p, i) in ps.iter().zip(info) {
            first.entry(p.origin.clone()).or_insert(i);
        }
        let result = chain::chain(ps, opts.chain_tolerance);
        for (contour, origins) in result.closed {
            if contour.vertices.len() < 2 || contour.signed_area().abs() < 1e-9 {
                continue; // degenerate: a line drawn there and back, a collapsed loop
            }
            let Some(head) = origins.first() else {
                continue;
            };
            let layer = first.get(head).map(|(l, _)| l.clone()).unwrap_or_default();
            let order = origins.iter().filter_map(|o| first.get(o)).map(|(_, i)| *i).min().unwrap_or(usize::MAX);
            let origin = match origins.len() {
                1 => head.clone(),
                n => format!("{head} and {} more entities chained", n - 1),
            };
            shapes.push((order, Shape { contour, role, layer, origin }));
        }
        open.extend(result.open);
    }

    let mut skipped = Vec::new();
    if opts.skip_open {
        skipped.extend(open.iter().map(chain::OpenChain::describe));
    } else if let Some((place, reason)) = chain::open_contour_message(&open) {
        return Err(ImportError::new(
            path,
            place,
            format!("{reason}, or skip open contours (--skip-open) to cut the rest"),
        ));
    }
    if shapes.is_empty() {
        let mut reason = String::from("no closed contour in the drawing");
        if left_out > 0 {
            reason.push_str(&format!(
                " on the layers read ({left_out} entities on other layers; the drawing's layers: {})",
                layers.join(", ")
            ));
        }
        if geometry == 0 {
            reason.push_str(": it has no lines, arcs, circles, polylines, splines or ellipses");
        }
        let mut notes: Vec<String> = ignored.iter().map(|(k, n)| format!("{n} {k}")).collect();
        if paper_space > 0 {
            notes.push(format!("{paper_space} entities in paper space"));
        }
        if !notes.is_empty() {
            reason.push_str(&format!(" (ignored: {})", notes.join(", ")));
        }
        return Err(ImportError::new(path, "drawing", reason));
    }
    shapes.sort_by_key(|(k, _)| *k);
    Ok(Drawing {
        path: path.to_path_buf(),
        units,
        units_from,
        units_assumed,
        shapes: shapes.into_iter().map(|(_, s)| s).collect(),
        skipped,
        layers,
    })
}

// ------------------------------------------------------------------------------------------
// Group-code pairs

/// One group-code pair and the line of its code (1-based).
#[derive(Debug, Clone, Copy)]
struct Pair<'a> {
    code: i32,
    value: &'a str,
    line: usize,
}

/// The text of the file: UTF-8, or Windows-1252/Latin-1 bytes taken as they are.
fn decode(path: &Path, bytes: &[u8]) -> Result<String, ImportError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(ImportError::new(path, "file", "empty file: no DXF data"));
    }
    if bytes.starts_with(b"AutoCAD Binary DXF") {
        return Err(ImportError::new(
            path,
            "file",
            "binary DXF is not supported: save the drawing as ASCII DXF (\"DXF\" rather than \"binary DXF\")",
        ));
    }
    let head = &bytes[..bytes.len().min(6)];
    if head.len() == 6 && head.starts_with(b"AC10") && head[4..].iter().all(u8::is_ascii_digit) {
        return Err(ImportError::new(
            path,
            "file",
            "this is a DWG file, not a DXF file: export the drawing as DXF from the CAD program",
        ));
    }
    if bytes.iter().take(4096).any(|&b| b == 0) {
        return Err(ImportError::new(path, "file", "not a DXF file: it holds binary data, not text"));
    }
    Ok(match std::str::from_utf8(bytes) {
        Ok(s) => s.to_string(),
        Err(_) => bytes.iter().map(|&b| char::from(b)).collect(),
    })
}

/// Shows a value in a message: trimmed, escaped, and cut to 40 characters.
fn shown(s: &str) -> String {
    let s = s.trim();
    let mut out: String = s.chars().take(40).flat_map(char::escape_debug).collect();
    if s.chars().count() > 40 {
        out.push('…');
    }
    out
}

/// Splits the text into group-code pairs (comments, code 999, are dropped).
fn tokenize<'a>(path: &Path, text: &'a str) -> Result<Vec<Pair<'a>>, ImportError> {
    let sep = if text.contains('\n') { '\n' } else { '\r' };
    let mut lines: Vec<&str> = text.split(sep).map(|l| l.strip_suffix('\r').unwrap_or(l)).collect();
    while lines.last().is_some_and(|l| l.trim().is_empty()) {
        lines.pop();
    }
    let mut pairs = Vec::with_capacity(lines.len() / 2);
    let mut i = 0usize;
    while i < lines.len() {
        let line = i + 1;
        let code_text = lines[i].trim();
        let code: i32 = match code_text.parse() {
            Ok(c) if (-5..=1071).contains(&c) => c,
            _ => {
                let reason = if pairs.is_empty() {
                    format!("not a DXF file: expected a group code (a number) but found \"{}\"", shown(code_text))
                } else {
                    format!(
                        "expected a group code (a number from -5 to 1071) but found \"{}\": the file is corrupted",
                        shown(code_text)
                    )
                };
                return Err(ImportError::new(path, format!("line {line}"), reason));
            }
        };
        let Some(value) = lines.get(i + 1) else {
            return Err(ImportError::new(
                path,
                format!("line {line}"),
                format!("group code {code} has no value: the file is truncated"),
            ));
        };
        if code != 999 {
            pairs.push(Pair { code, value: value.trim(), line });
        }
        i += 2;
    }
    Ok(pairs)
}

// ------------------------------------------------------------------------------------------
// Sections and entities

/// One entity: its type, the line of its type name and its other pairs.
#[derive(Debug, Clone, Copy)]
struct Ent<'a> {
    kind: &'a str,
    line: usize,
    codes: &'a [Pair<'a>],
}

/// A block definition.
struct Block<'a> {
    name: &'a str,
    base: [f64; 2],
    entities: Vec<Ent<'a>>,
}

struct DxfFile<'a> {
    header: Vec<Pair<'a>>,
    blocks: HashMap<String, Block<'a>>,
    entities: Vec<Ent<'a>>,
}

fn split_sections<'a>(path: &Path, pairs: &'a [Pair<'a>]) -> Result<DxfFile<'a>, ImportError> {
    let mut header: Vec<Pair<'a>> = Vec::new();
    let mut blocks_range: Option<&'a [Pair<'a>]> = None;
    let mut entities_range: Option<&'a [Pair<'a>]> = None;
    let mut any_section = false;
    let mut i = 0usize;
    while i < pairs.len() {
        let p = pairs[i];
        if p.code == 0 && p.value.eq_ignore_ascii_case("EOF") {
            break;
        }
        if !(p.code == 0 && p.value.eq_ignore_ascii_case("SECTION")) {
            if !any_section {
                return Err(ImportError::new(
                    path,
                    format!("line {}", p.line),
                    format!("not a DXF file: expected \"0 / SECTION\" but found \"{} / {}\"", p.code, shown(p.value)),
                ));
            }
            i += 1;
            continue;
        }
        any_section = true;
        let name = match pairs.get(i + 1) {
            Some(n) if n.code == 2 => n.value.to_ascii_uppercase(),
            _ => {
                return Err(ImportError::new(
                    path,
                    format!("line {}", p.line),
                    "SECTION without a name (group code 2)",
                ));
            }
        };
        let body_start = i + 2;
        let mut j = body_start;
        while j < pairs.len() && !(pairs[j].code == 0 && pairs[j].value.eq_ignore_ascii_case("ENDSEC")) {
            if pairs[j].code == 0 && pairs[j].value.eq_ignore_ascii_case("SECTION") {
                return Err(ImportError::new(
                    path,
                    format!("line {}", pairs[j].line),
                    format!(
                        "a new SECTION starts before the {name} section (line {}) has ended: the file is corrupted",
                        p.line
                    ),
                ));
            }
            j += 1;
        }
        if j >= pairs.len() {
            return Err(ImportError::new(
                path,
                format!("line {}", p.line),
                format!("the {name} section never ends (no ENDSEC): the file is truncated"),
            ));
        }
        let body = pairs.get(body_start..j).unwrap_or(&[]);
        match name.as_str() {
            "HEADER" => header.extend_from_slice(body),
            "BLOCKS" => blocks_range = Some(body),
            "ENTITIES" => entities_range = Some(body),
            _ => {}
        }
        i = j + 1;
    }
    let Some(entities) = entities_range else {
        let reason = if any_section {
            "no ENTITIES section: the file holds no drawing"
        } else {
            "no ENTITIES section: not a DXF drawing or an empty one"
        };
        return Err(ImportError::new(path, "file", reason));
    };
    let entities = records(entities);
    let mut blocks = HashMap::new();
    if let Some(b) = blocks_range {
        let recs = records(b);
        let mut k = 0usize;
        while k < recs.len() {
            let r = recs[k];
            k += 1;
            if !r.kind.eq_ignore_ascii_case("BLOCK") {
                continue;
            }
            let name = r.codes.iter().find(|p| p.code == 2 || p.code == 3).map_or("", |p| p.value);
            let coord = |code: i32| -> Result<f64, ImportError> {
                match r.codes.iter().find(|p| p.code == code) {
                    Some(p) => number(p).map_err(|e| ImportError::new(path, format!("BLOCK at line {}", r.line), e)),
                    None => Ok(0.0),
                }
            };
            let base = [coord(10)?, coord(20)?];
            let mut ents = Vec::new();
            while k < recs.len()
                && !recs[k].kind.eq_ignore_ascii_case("ENDBLK")
                && !recs[k].kind.eq_ignore_ascii_case("BLOCK")
            {
                ents.push(recs[k]);
                k += 1;
            }
            blocks.entry(name.to_ascii_uppercase()).or_insert(Block { name, base, entities: ents });
        }
    }
    Ok(DxfFile { header, blocks, entities })
}

/// Cuts a section body into entities at each `0` pair.
fn records<'a>(body: &'a [Pair<'a>]) -> Vec<Ent<'a>> {
    let mut out = Vec::new();
    let mut i = 0usize;
    while i < body.len() {
        if body[i].code != 0 {
            i += 1;
            continue;
        }
        let mut j = i + 1;
        while j < body.len() && body[j].code != 0 {
            j += 1;
        }
        // the line that names the entity type (the value line of its `0` pair)
        out.push(Ent { kind: body[i].value, line: body[i].line + 1, codes: body.get(i + 1..j).unwrap_or(&[]) });
        i = j;
    }
    out
}

/// Parses a number, refusing NaN and infinities (also MSVC's `1.#QNAN`, `-1.#IND`, `1.#INF`).
fn number(p: &Pair) -> Result<f64, String> {
    let v = p.value.trim();
    let what = match v.parse::<f64>() {
        Ok(x) if x.is_finite() => return Ok(x),
        Ok(_) => "is not a finite number",
        Err(_) if v.contains(".#") || v.to_ascii_lowercase().contains("nan") => "is not a finite number",
        Err(_) => "is not a number",
    };
    Err(format!("value of group code {} at line {}: \"{}\" {what}", p.code, p.line + 1, shown(v)))
}

/// Parses an integer (`1`, ` 1`, or an integral `1.0`).
fn integer(p: &Pair) -> Result<i64, String> {
    let v = p.value.trim();
    if let Ok(i) = v.parse::<i64>() {
        return Ok(i);
    }
    match v.parse::<f64>() {
        Ok(x) if x.is_finite() && x.fract() == 0.0 && x.abs() < 9.0e15 => Ok(x as i64),
        _ => Err(format!("value of group code {} at line {}: \"{}\" is not an integer", p.code, p.line + 1, shown(v))),
    }
}

impl<'a> Ent<'a> {
    fn first(&self, code: i32) -> Option<&'a Pair<'a>> {
        self.codes.iter().find(|p| p.code == code)
    }
    fn num(&self, code: i32) -> Result<Option<f64>, String> {
        self.first(code).map(number).transpose()
    }
    fn num_or(&self, code: i32, default: f64) -> Result<f64, String> {
        Ok(self.num(code)?.unwrap_or(default))
    }
    fn req(&self, code: i32, what: &str) -> Result<f64, String> {
        self.num(code)?.ok_or_else(|| format!("{} without {what} (group code {code})", self.kind))
    }
    fn int_or(&self, code: i32, default: i64) -> Result<i64, String> {
        Ok(self.first(code).map(integer).transpose()?.unwrap_or(default))
    }
    fn layer(&self) -> &'a str {
        self.first(8).map_or("0", |p| p.value)
    }
    fn origin(&self, suffix: &str) -> String {
        match self.first(5) {
            Some(h) if !h.value.is_empty() => {
                format!("{} (handle {}) at line {}{suffix}", self.kind, h.value, self.line)
            }
            _ => format!("{} at line {}{suffix}", self.kind, self.line),
        }
    }
    /// The extrusion direction (group codes 210/220/230), (0, 0, 1) when absent or zero.
    fn extrusion(&self) -> Result<[f64; 3], String> {
        let n = [self.num_or(210, 0.0)?, self.num_or(220, 0.0)?, self.num_or(230, 1.0)?];
        let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
        if !len.is_finite() || len <= 1e-12 {
            return Ok([0.0, 0.0, 1.0]);
        }
        Ok([n[0] / len, n[1] / len, n[2] / len])
    }
}

/// The units `$INSUNITS` asks for, where they came from, and whether they are a guess.
fn header_units(path: &Path, header: &[Pair]) -> Result<(Units, String, bool), ImportError> {
    let assumed = |why: &str| Ok((Units::Millimetre, why.to_string(), true));
    let Some(k) = header.iter().position(|p| p.code == 9 && p.value.eq_ignore_ascii_case("$INSUNITS")) else {
        return assumed("no $INSUNITS");
    };
    let Some(p) = header.get(k + 1).filter(|p| p.code == 70) else {
        return assumed("no $INSUNITS");
    };
    let place = format!("header $INSUNITS at line {}", p.line);
    let v = integer(p).map_err(|e| ImportError::new(path, place.clone(), e))?;
    let said = |u: Units| Ok((u, format!("$INSUNITS = {v}"), false));
    let unsupported = match v {
        0 => return assumed("$INSUNITS = 0 (unitless)"),
        1 => return said(Units::Inch),
        2 => return said(Units::Foot),
        4 => return said(Units::Millimetre),
        5 => return said(Units::Centimetre),
        6 => return said(Units::Metre),
        9 => return said(Units::Mil),
        13 => return said(Units::Micrometre),
        3 => "miles",
        7 => "kilometres",
        8 => "microinches",
        10 => "yards",
        11 => "ångströms",
        12 => "nanometres",
        14 => "decimetres",
        15 => "decametres",
        16 => "hectometres",
        17 => "gigametres",
        18 => "astronomical units",
        19 => "light years",
        20 => "parsecs",
        21 => "US survey feet",
        22 => "US survey inches",
        23 => "US survey yards",
        24 => "US survey miles",
        _ => {
            return Err(ImportError::new(
                path,
                place,
                format!("unknown drawing units ($INSUNITS = {v}); give the units explicitly (mm, in, ...)"),
            ));
        }
    };
    Err(ImportError::new(
        path,
        place,
        format!(
            "drawing units {unsupported} ($INSUNITS = {v}) are not supported; give the units explicitly (mm, in, ...)"
        ),
    ))
}

// ------------------------------------------------------------------------------------------
// 2D affine maps

/// `x' = m[0] x + m[1] y + m[2]`, `y' = m[3] x + m[4] y + m[5]`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Affine {
    m: [f64; 6],
}

impl Affine {
    const IDENTITY: Affine = Affine { m: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0] };

    fn translate(x: f64, y: f64) -> Affine {
        Affine { m: [1.0, 0.0, x, 0.0, 1.0, y] }
    }
    fn scale(sx: f64, sy: f64) -> Affine {
        Affine { m: [sx, 0.0, 0.0, 0.0, sy, 0.0] }
    }
    fn rotate(rad: f64) -> Affine {
        let (s, c) = rad.sin_cos();
        Affine { m: [c, -s, 0.0, s, c, 0.0] }
    }

    /// The object coordinate system of extrusion `n` (unit) at elevation `elev`, projected onto
    /// the XY plane (the "arbitrary axis" algorithm of the DXF reference).
    fn ocs(n: [f64; 3], elev: f64) -> Affine {
        if n[0].abs() < 1e-12 && n[1].abs() < 1e-12 && n[2] > 0.0 {
            return Affine::IDENTITY;
        }
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
        };
        let unit = |a: [f64; 3]| {
            let l = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
            if l > 0.0 { [a[0] / l, a[1] / l, a[2] / l] } else { a }
        };
        let ax = if n[0].abs() < 1.0 / 64.0 && n[1].abs() < 1.0 / 64.0 {
            unit(cross([0.0, 1.0, 0.0], n))
        } else {
            unit(cross([0.0, 0.0, 1.0], n))
        };
        let ay = unit(cross(n, ax));
        Affine { m: [ax[0], ay[0], elev * n[0], ax[1], ay[1], elev * n[1]] }
    }

    fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let m = &self.m;
        [m[0] * p[0] + m[1] * p[1] + m[2], m[3] * p[0] + m[4] * p[1] + m[5]]
    }

    /// `outer ∘ self`: first `self`, then `outer`.
    fn then(&self, outer: &Affine) -> Affine {
        let (a, b) = (&self.m, &outer.m);
        Affine {
            m: [
                b[0] * a[0] + b[1] * a[3],
                b[0] * a[1] + b[1] * a[4],
                b[0] * a[2] + b[1] * a[5] + b[2],
                b[3] * a[0] + b[4] * a[3],
                b[3] * a[1] + b[4] * a[4],
                b[3] * a[2] + b[4] * a[5] + b[5],
            ],
        }
    }

    fn det(&self) -> f64 {
        self.m[0] * self.m[4] - self.m[1] * self.m[3]
    }

    /// Largest stretch factor (largest singular value of the linear part).
    fn max_scale(&self) -> f64 {
        let [a, b, _, c, d, _] = self.m;
        let s = a * a + b * b + c * c + d * d;
        let det = self.det();
        ((s + (s * s - 4.0 * det * det).max(0.0).sqrt()) / 2.0).sqrt()
    }

    /// True when circles stay circles (rotation, uniform scale, mirror).
    fn is_similarity(&self) -> bool {
        let [a, b, _, c, d, _] = self.m;
        let (l1, l2) = (a * a + c * c, b * b + d * d);
        let dot = a * b + c * d;
        let s = l1.max(l2);
        s > 0.0 && (l1 - l2).abs() <= 1e-9 * s && dot.abs() <= 1e-9 * s
    }
}

// ------------------------------------------------------------------------------------------
// Walking the entities

/// A piece in drawing units, before conversion to mm and chaining.
struct RawPiece {
    contour: Contour,
    origin: String,
    layer: String,
}

/// Where entities are being read: the map into drawing coordinates and the block context.
struct Context {
    xf: Affine,
    /// Layer of the INSERT that brought us here (for entities on layer `0`).
    layer: Option<String>,
    /// Appended to entity origins (` in block "B" inserted at line 900`).
    suffix: String,
    /// Names of the blocks being inserted (to catch recursion).
    stack: Vec<String>,
}

struct Reader<'r, 'a> {
    path: &'r Path,
    blocks: &'r HashMap<String, Block<'a>>,
    /// Flattening tolerance in drawing units.
    tol: f64,
    /// Same-point distance in drawing units.
    eps: f64,
    pieces: Vec<RawPiece>,
    ignored: BTreeMap<String, usize>,
    paper_space: usize,
    points: usize,
    entities: usize,
}

impl<'a> Reader<'_, 'a> {
    fn walk(&mut self, ents: &[Ent<'a>], ctx: &Context) -> Result<(), ImportError> {
        let mut i = 0usize;
        while i < ents.len() {
            let e = ents[i];
            i += 1;
            self.entities += 1;
            if self.entities > MAX_ENTITIES {
                return Err(self.err(
                    &e,
                    ctx,
                    format!("more than {MAX_ENTITIES} entities once the blocks are inserted; the drawing is too large"),
                ));
            }
            // a POLYLINE owns the VERTEX entities after it, up to SEQEND
            let mut vertices: &[Ent<'a>] = &[];
            if e.kind.eq_ignore_ascii_case("POLYLINE") {
                let start = i;
                while i < ents.len() && ents[i].kind.eq_ignore_ascii_case("VERTEX") {
                    i += 1;
                }
                vertices = ents.get(start..i).unwrap_or(&[]);
                if i < ents.len() && ents[i].kind.eq_ignore_ascii_case("SEQEND") {
                    i += 1;
                }
            }
            let paper = e.first(67).map(integer).transpose().map_err(|r| self.err(&e, ctx, r))?.unwrap_or(0);
            if paper == 1 {
                self.paper_space += 1;
                continue;
            }
            let layer = match (&ctx.layer, e.layer()) {
                (Some(l), "0") => l.clone(),
                (_, l) => l.to_string(),
            };
            let kind = e.kind.to_ascii_uppercase();
            let result = match kind.as_str() {
                "LINE" => self.line(&e, ctx, &layer),
                "ARC" => self.arc(&e, ctx, &layer),
                "CIRCLE" => self.circle(&e, ctx, &layer),
                "LWPOLYLINE" => self.lwpolyline(&e, ctx, &layer),
                "POLYLINE" => self.polyline(&e, vertices, ctx, &layer),
                "SPLINE" => self.spline(&e, ctx, &layer),
                "ELLIPSE" => self.ellipse(&e, ctx, &layer),
                "INSERT" | "MINSERT" => {
                    self.insert(&e, ctx, &layer)?;
                    Ok(())
                }
                "VERTEX" | "SEQEND" | "ATTRIB" | "ENDBLK" => Ok(()),
                _ => {
                    *self.ignored.entry(kind).or_insert(0) += 1;
                    Ok(())
                }
            };
            result.map_err(|r| self.err(&e, ctx, r))?;
        }
        Ok(())
    }

    fn err(&self, e: &Ent, ctx: &Context, reason: String) -> ImportError {
        ImportError::new(self.path, e.origin(&ctx.suffix), reason)
    }

    /// Maps a contour given in the entity's own coordinates through `xf` into drawing
    /// coordinates, cleans it and keeps it unless degenerate.
    fn emit(&mut self, local: Contour, xf: &Affine, e: &Ent, ctx: &Context, layer: &str) -> Result<(), String> {
        let mut c = local;
        let has_arcs = c.vertices.iter().any(|v| v.bulge != 0.0);
        if has_arcs && !xf.is_similarity() {
            // arcs become ellipses: flatten them first, finely enough for the stretch
            let s = xf.max_scale();
            if !positive(s) {
                return Ok(());
            }
            let tol = self.tol / s;
            let mut pts: Vec<[f64; 2]> = Vec::new();
            if let Some(v) = c.vertices.first() {
                pts.push([v.x, v.y]);
            }
            for seg in c.segments() {
                if let Segment::Arc { radius, sweep, .. } = seg {
                    self.spend(crate::contour::arc_steps(radius, sweep.abs(), tol))?;
                }
                seg.flatten_into(tol, &mut pts);
            }
            if c.closed && pts.len() > 1 {
                pts.pop();
            }
            c = Contour { vertices: pts.iter().map(|p| Vertex::new(p[0], p[1])).collect(), closed: c.closed };
        }
        let flip = xf.det() < 0.0;
        for v in &mut c.vertices {
            let p = xf.apply([v.x, v.y]);
            v.x = p[0];
            v.y = p[1];
            if flip {
                v.bulge = -v.bulge;
            }
        }
        if !c.is_finite() {
            return Err("coordinates are not finite numbers".to_string());
        }
        let Some(c) = clean(c, self.eps) else {
            return Ok(());
        };
        self.spend(c.vertices.len())?;
        self.pieces.push(RawPiece { contour: c, origin: e.origin(&ctx.suffix), layer: layer.to_string() });
        Ok(())
    }

    /// Counts flattened points against the budget.
    fn spend(&mut self, n: usize) -> Result<(), String> {
        self.points = self.points.saturating_add(n);
        if self.points > MAX_POINTS {
            return Err(format!(
                "the drawing needs more than {MAX_POINTS} points (too many entities, or curves \
                 flattened too finely: raise the flattening tolerance)"
            ));
        }
        Ok(())
    }

    fn line(&mut self, e: &Ent, ctx: &Context, layer: &str) -> Result<(), String> {
        let a = [e.req(10, "a start point")?, e.req(20, "a start point")?];
        let b = [e.req(11, "an end point")?, e.req(21, "an end point")?];
        let c = Contour { vertices: vec![Vertex::new(a[0], a[1]), Vertex::new(b[0], b[1])], closed: false };
        self.emit(c, &ctx.xf, e, ctx, layer)
    }

    fn radius(e: &Ent) -> Result<Option<f64>, String> {
        let r = e.req(40, "a radius")?;
        if r < 0.0 {
            return Err(format!("negative radius {r}"));
        }
        Ok((r > 0.0).then_some(r))
    }

    fn arc(&mut self, e: &Ent, ctx: &Context, layer: &str) -> Result<(), String> {
        let (cx, cy) = (e.req(10, "a centre")?, e.req(20, "a centre")?);
        let Some(r) = Self::radius(e)? else {
            return Ok(());
        };
        let a0 = e.req(50, "a start angle")?;
        let a1 = e.req(51, "an end angle")?;
        let mut sweep = (a1 - a0).rem_euclid(360.0);
        if !(1e-9..=360.0 - 1e-9).contains(&sweep) {
            sweep = 360.0; // start == end: a full circle
        }
        let xf = Affine::ocs(e.extrusion()?, e.num_or(30, 0.0)?).then(&ctx.xf);
        let c = arc_contour([cx, cy], r, a0.to_radians(), sweep.to_radians());
        self.emit(c, &xf, e, ctx, layer)
    }

    fn circle(&mut self, e: &Ent, ctx: &Context, layer: &str) -> Result<(), String> {
        let (cx, cy) = (e.req(10, "a centre")?, e.req(20, "a centre")?);
        let Some(r) = Self::radius(e)? else {
            return Ok(());
        };
        let xf = Affine::ocs(e.extrusion()?, e.num_or(30, 0.0)?).then(&ctx.xf);
        self.emit(Contour::circle(cx, cy, r), &xf, e, ctx, layer)
    }

    fn lwpolyline(&mut self, e: &Ent, ctx: &Context, layer: &str) -> Result<(), String> {
        let flags = e.int_or(70, 0)?;
        let mut vs: Vec<Vertex> = Vec::new();
        for p in e.codes {
            match p.code {
                10 => vs.push(Vertex::new(number(p)?, 0.0)),
                20 => match vs.last_mut() {
                    Some(v) => v.y = number(p)?,
                    None => {
                        return Err(format!("y coordinate (group code 20) at line {} before any x", p.line));
                    }
                },
                42 => {
                    if let Some(v) = vs.last_mut() {
                        v.bulge = number(p)?;
                    }
                }
                _ => {}
            }
        }
        let xf = Affine::ocs(e.extrusion()?, e.num_or(38, 0.0)?).then(&ctx.xf);
        self.emit(Contour { vertices: vs, closed: flags & 1 != 0 }, &xf, e, ctx, layer)
    }

    fn polyline(&mut self, e: &Ent, vertices: &[Ent], ctx: &Context, layer: &str) -> Result<(), String> {
        let flags = e.int_or(70, 0)?;
        if flags & (16 | 64) != 0 {
            *self.ignored.entry("POLYLINE mesh".to_string()).or_insert(0) += 1;
            return Ok(());
        }
        let is_3d = flags & 8 != 0;
        let spline_fit = flags & 4 != 0;
        let mut vs = Vec::new();
        let mut frame_only = spline_fit;
        for v in vertices {
            let vflags = v.int_or(70, 0).map_err(|r| format!("{} at line {}: {r}", v.kind, v.line))?;
            if vflags & 8 != 0 {
                frame_only = false;
            }
        }
        if spline_fit && frame_only && !vertices.is_empty() {
            return Err("spline-fit POLYLINE holds only its control frame, not the fitted curve; \
                        convert it to a SPLINE or explode it"
                .to_string());
        }
        for v in vertices {
            let at = |r: String| format!("{} at line {}: {r}", v.kind, v.line);
            let vflags = v.int_or(70, 0).map_err(at)?;
            if vflags & 16 != 0 {
                continue; // spline frame control point
            }
            let x = v.req(10, "a position").map_err(at)?;
            let y = v.req(20, "a position").map_err(at)?;
            let bulge = if is_3d { 0.0 } else { v.num_or(42, 0.0).map_err(at)? };
            vs.push(Vertex::with_bulge(x, y, bulge));
        }
        let xf = if is_3d { ctx.xf } else { Affine::ocs(e.extrusion()?, e.num_or(30, 0.0)?).then(&ctx.xf) };
        self.emit(Contour { vertices: vs, closed: flags & 1 != 0 }, &xf, e, ctx, layer)
    }

    fn spline(&mut self, e: &Ent, ctx: &Context, layer: &str) -> Result<(), String> {
        let flags = e.int_or(70, 0)?;
        let closed_flag = flags & 1 != 0;
        let degree = e.int_or(71, 3)?;
        let mut knots = Vec::new();
        let mut weights = Vec::new();
        let mut cps: Vec<[f64; 2]> = Vec::new();
        let mut fit: Vec<[f64; 2]> = Vec::new();
        for p in e.codes {
            match p.code {
                40 => knots.push(number(p)?),
                41 => weights.push(number(p)?),
                10 => cps.push([number(p)?, 0.0]),
                20 => match cps.last_mut() {
                    Some(c) => c[1] = number(p)?,
                    None => {
                        return Err(format!("y coordinate (group code 20) at line {} before any x", p.line));
                    }
                },
                11 => fit.push([number(p)?, 0.0]),
                21 => match fit.last_mut() {
                    Some(c) => c[1] = number(p)?,
                    None => {
                        return Err(format!("y coordinate (group code 21) at line {} before any x", p.line));
                    }
                },
                _ => {}
            }
        }
        let s = ctx.xf.max_scale();
        if !positive(s) {
            return Ok(());
        }
        let tol = self.tol / s;
        let pts = if !cps.is_empty() {
            let curve = BSpline::new(degree, knots, cps, weights, flags & 4 != 0)?;
            let breaks = curve.breaks();
            let init = if curve.degree == 1 { 1 } else { 4 };
            flatten(&|u| curve.eval(u), &breaks, init, tol, &mut |n| self.spend(n))?
        } else if !fit.is_empty() {
            let tangent = |x: i32, y: i32| -> Result<Option<[f64; 2]>, String> {
                match (e.num(x)?, e.num(y)?) {
                    (Some(a), Some(b)) => Ok(Some([a, b])),
                    _ => Ok(None),
                }
            };
            let (t0, t1) = (tangent(12, 22)?, tangent(13, 23)?);
            let Some(curve) = FitCurve::new(&fit, closed_flag, t0, t1, self.eps) else {
                return Ok(());
            };
            flatten(&|u| curve.eval(u), &curve.t, 4, tol, &mut |n| self.spend(n))?
        } else {
            return Err("SPLINE without control points or fit points".to_string());
        };
        let closed = match (pts.first(), pts.last()) {
            (Some(a), Some(b)) => pts.len() > 2 && dist(*a, *b) <= self.eps,
            _ => false,
        };
        let c = Contour { vertices: pts.iter().map(|p| Vertex::new(p[0], p[1])).collect(), closed };
        self.emit(c, &ctx.xf, e, ctx, layer)
    }

    fn ellipse(&mut self, e: &Ent, ctx: &Context, layer: &str) -> Result<(), String> {
        let c = [e.req(10, "a centre")?, e.req(20, "a centre")?];
        let m3 = [e.req(11, "a major axis")?, e.req(21, "a major axis")?, e.num_or(31, 0.0)?];
        let ratio = e.req(40, "an axis ratio")?;
        let n = e.extrusion()?;
        let mut t0 = e.num_or(41, 0.0)?;
        let t1 = e.num_or(42, std::f64::consts::TAU)?;
        if ratio <= 0.0 {
            return Ok(()); // flat: no area
        }
        // minor axis = ratio * (n x major), projected onto XY like the major axis
        let minor = [ratio * (n[1] * m3[2] - n[2] * m3[1]), ratio * (n[2] * m3[0] - n[0] * m3[2])];
        let major = [m3[0], m3[1]];
        let mut sweep = (t1 - t0).rem_euclid(std::f64::consts::TAU);
        let full = !(1e-9..=std::f64::consts::TAU - 1e-9).contains(&sweep);
        if full {
            sweep = std::f64::consts::TAU;
            t0 = 0.0;
        }
        let lm = (major[0] * major[0] + major[1] * major[1]).sqrt();
        let ln = (minor[0] * minor[0] + minor[1] * minor[1]).sqrt();
        if lm <= self.eps || ln <= self.eps {
            return Ok(());
        }
        let point = |t: f64| {
            let (s, co) = t.sin_cos();
            [c[0] + major[0] * co + minor[0] * s, c[1] + major[1] * co + minor[1] * s]
        };
        let dot = major[0] * minor[0] + major[1] * minor[1];
        let circular = (lm - ln).abs() <= 1e-9 * lm && dot.abs() <= 1e-9 * lm * lm;
        let contour = if circular {
            // exact arcs: pieces of at most 180 degrees
            let ccw = major[0] * minor[1] - major[1] * minor[0] > 0.0;
            let k = ((sweep / std::f64::consts::PI - 1e-9).ceil() as usize).max(if full { 2 } else { 1 });
            let bulge = (sweep / k as f64 / 4.0).tan() * if ccw { 1.0 } else { -1.0 };
            let count = if full { k } else { k + 1 };
            let vertices = (0..count)
                .map(|i| {
                    let p = point(t0 + sweep * i as f64 / k as f64);
                    Vertex::with_bulge(p[0], p[1], if i < k { bulge } else { 0.0 })
                })
                .collect();
            Contour { vertices, closed: full }
        } else {
            let s = ctx.xf.max_scale();
            if !positive(s) {
                return Ok(());
            }
            let init = ((sweep / (std::f64::consts::PI / 8.0)).ceil() as usize).max(1);
            let mut pts = flatten(&point, &[t0, t0 + sweep], init, self.tol / s, &mut |n| self.spend(n))?;
            if full && pts.len() > 1 {
                pts.pop();
            }
            Contour { vertices: pts.iter().map(|p| Vertex::new(p[0], p[1])).collect(), closed: full }
        };
        self.emit(contour, &ctx.xf, e, ctx, layer)
    }

    fn insert(&mut self, e: &Ent, ctx: &Context, layer: &str) -> Result<(), ImportError> {
        let fail = |r: String| self.err(e, ctx, r);
        let name = e.first(2).map_or("", |p| p.value);
        let Some(block) = self.blocks.get(&name.to_ascii_uppercase()) else {
            return Err(fail(format!("INSERT of block \"{}\", which the BLOCKS section does not define", shown(name))));
        };
        let key = name.to_ascii_uppercase();
        if ctx.stack.contains(&key) {
            return Err(fail(format!("block \"{}\" inserts itself", shown(name))));
        }
        if ctx.stack.len() >= MAX_DEPTH {
            return Err(fail(format!("blocks nested deeper than {MAX_DEPTH} levels")));
        }
        let num = |code: i32, default: f64| e.num_or(code, default).map_err(&fail);
        let (x, y, z) = (num(10, 0.0)?, num(20, 0.0)?, num(30, 0.0)?);
        let (sx, sy) = (num(41, 1.0)?, num(42, 1.0)?);
        let rot = num(50, 0.0)?.to_radians();
        let (dx, dy) = (num(44, 0.0)?, num(45, 0.0)?);
        let cols = e.int_or(70, 1).map_err(&fail)?.max(1);
        let rows = e.int_or(71, 1).map_err(&fail)?.max(1);
        let copies =
            usize::try_from(cols).unwrap_or(usize::MAX).saturating_mul(usize::try_from(rows).unwrap_or(usize::MAX));
        if copies > MAX_COPIES {
            return Err(fail(format!("{cols} x {rows} copies of block \"{}\" are too many", shown(name))));
        }
        let ocs = Affine::ocs(e.extrusion().map_err(&fail)?, z);
        // name the three innermost insertions, then only how deep the nesting goes
        let suffix = match ctx.stack.len() {
            0..=2 => format!(" in block \"{}\" inserted at line {}{}", shown(block.name), e.line, ctx.suffix),
            3 => format!(" in block \"{}\" inserted at line {} …", shown(block.name), e.line),
            _ => format!(
                " in block \"{}\" inserted at line {} … ({} levels deep)",
                shown(block.name),
                e.line,
                ctx.stack.len() + 1
            ),
        };
        let mut stack = ctx.stack.clone();
        stack.push(key);
        for r in 0..rows {
            for c in 0..cols {
                let local = Affine::translate(-block.base[0], -block.base[1])
                    .then(&Affine::scale(sx, sy))
                    .then(&Affine::translate(c as f64 * dx, r as f64 * dy))
                    .then(&Affine::rotate(rot))
                    .then(&Affine::translate(x, y))
                    .then(&ocs);
                let inner = Context {
                    xf: local.then(&ctx.xf),
                    layer: Some(layer.to_string()),
                    suffix: suffix.clone(),
                    stack: stack.clone(),
                };
                self.walk(&block.entities, &inner)?;
            }
        }
        Ok(())
    }
}

/// `x > 0`, false for NaN.
fn positive(x: f64) -> bool {
    x > 0.0
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// An arc of radius `r` around `c` from angle `a0` sweeping `sweep` (radians, counter-clockwise,
/// up to a full turn) in pieces of at most 180 degrees; a full turn gives a closed contour.
fn arc_contour(c: [f64; 2], r: f64, a0: f64, sweep: f64) -> Contour {
    let full = sweep >= std::f64::consts::TAU - 1e-12;
    let k = ((sweep / std::f64::consts::PI - 1e-9).ceil() as usize).max(if full { 2 } else { 1 });
    let bulge = (sweep / k as f64 / 4.0).tan();
    let count = if full { k } else { k + 1 };
    let vertices = (0..count)
        .map(|i| {
            let t = a0 + sweep * i as f64 / k as f64;
            Vertex::with_bulge(c[0] + r * t.cos(), c[1] + r * t.sin(), if i < k { bulge } else { 0.0 })
        })
        .collect();
    Contour { vertices, closed: full }
}

/// Removes zero-length segments; `None` when nothing with a length is left.
fn clean(c: Contour, eps: f64) -> Option<Contour> {
    let mut out: Vec<Vertex> = Vec::with_capacity(c.vertices.len());
    for v in c.vertices {
        match out.last_mut() {
            Some(last) if dist([last.x, last.y], [v.x, v.y]) <= eps => last.bulge = v.bulge,
            _ => out.push(v),
        }
    }
    if c.closed
        && out.len() > 1
        && let (Some(f), Some(l)) = (out.first(), out.last())
        && dist([f.x, f.y], [l.x, l.y]) <= eps
    {
        out.pop();
    }
    if let Some(l) = out.last_mut()
        && !c.closed
    {
        l.bulge = 0.0;
    }
    let ok = match out.len() {
        0 | 1 => false,
        2 => !c.closed || out.iter().any(|v| v.bulge != 0.0),
        _ => true,
    };
    ok.then_some(Contour { vertices: out, closed: c.closed })
}

// ------------------------------------------------------------------------------------------
// Curves

/// Flattens the curve `f` over the parameter intervals between consecutive `breaks`, each first
/// cut into `init` equal parts, then halved until the curve lies within `tol` of the chords.
fn flatten(
    f: &dyn Fn(f64) -> [f64; 2],
    breaks: &[f64],
    init: usize,
    tol: f64,
    spend: &mut dyn FnMut(usize) -> Result<(), String>,
) -> Result<Vec<[f64; 2]>, String> {
    let mut out = Vec::new();
    let Some(&first) = breaks.first() else {
        return Ok(out);
    };
    let mut prev = f(first);
    out.push(prev);
    for w in breaks.windows(2) {
        let (a, b) = (w[0], w[1]);
        if !positive(b - a) {
            continue;
        }
        let init = init.max(1);
        for k in 0..init {
            let t0 = a + (b - a) * k as f64 / init as f64;
            let t1 = if k + 1 == init { b } else { a + (b - a) * (k + 1) as f64 / init as f64 };
            let p1 = f(t1);
            subdivide(f, t0, prev, t1, p1, tol, 0, &mut out, spend)?;
            prev = p1;
        }
    }
    Ok(out)
}

#[allow(clippy::too_many_arguments)]
fn subdivide(
    f: &dyn Fn(f64) -> [f64; 2],
    t0: f64,
    p0: [f64; 2],
    t1: f64,
    p1: [f64; 2],
    tol: f64,
    depth: u32,
    out: &mut Vec<[f64; 2]>,
    spend: &mut dyn FnMut(usize) -> Result<(), String>,
) -> Result<(), String> {
    let tm = 0.5 * (t0 + t1);
    let pm = f(tm);
    let flat = depth >= 40 || {
        let q1 = f(0.5 * (t0 + tm));
        let q3 = f(0.5 * (tm + t1));
        seg_dist(pm, p0, p1) <= tol && seg_dist(q1, p0, p1) <= tol && seg_dist(q3, p0, p1) <= tol
    };
    if flat {
        spend(1)?;
        out.push(p1);
        return Ok(());
    }
    subdivide(f, t0, p0, tm, pm, tol, depth + 1, out, spend)?;
    subdivide(f, tm, pm, t1, p1, tol, depth + 1, out, spend)
}

/// Distance from `p` to the segment `a`–`b`.
fn seg_dist(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 { (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0) } else { 0.0 };
    dist(p, [a[0] + t * dx, a[1] + t * dy])
}

/// A B-spline curve (rational when weights are given) in homogeneous coordinates.
struct BSpline {
    degree: usize,
    knots: Vec<f64>,
    /// `[w x, w y, w]`
    points: Vec<[f64; 3]>,
}

impl BSpline {
    fn new(
        degree: i64,
        knots: Vec<f64>,
        cps: Vec<[f64; 2]>,
        weights: Vec<f64>,
        rational: bool,
    ) -> Result<Self, String> {
        let p = usize::try_from(degree)
            .ok()
            .filter(|p| (1..=MAX_DEGREE).contains(p))
            .ok_or_else(|| format!("SPLINE of degree {degree}: only degrees 1 to {MAX_DEGREE} are supported"))?;
        let n = cps.len();
        if n < p + 1 {
            return Err(format!("SPLINE of degree {p} needs at least {} control points, it has {n}", p + 1));
        }
        let knots = if knots.is_empty() {
            // clamped uniform
            let inner = n - p;
            (0..n + p + 1)
                .map(|i| {
                    if i <= p {
                        0.0
                    } else if i >= n {
                        1.0
                    } else {
                        (i - p) as f64 / inner as f64
                    }
                })
                .collect()
        } else {
            knots
        };
        if knots.len() != n + p + 1 {
            return Err(format!(
                "SPLINE has {} knots, but {n} control points of degree {p} need {}",
                knots.len(),
                n + p + 1
            ));
        }
        if knots.windows(2).any(|w| w[1] < w[0]) {
            return Err("SPLINE knots are not in increasing order".to_string());
        }
        if !positive(knots[n] - knots[p]) {
            return Err("SPLINE has an empty parameter range (all its knots are equal)".to_string());
        }
        let weights = if weights.is_empty() || (!rational && weights.iter().all(|w| *w == 1.0)) {
            vec![1.0; n]
        } else if weights.len() != n {
            return Err(format!("SPLINE has {} weights for {n} control points", weights.len()));
        } else {
            weights
        };
        if let Some(w) = weights.iter().find(|w| **w <= 0.0) {
            return Err(format!("SPLINE weight {w} is not positive"));
        }
        let points = cps.iter().zip(&weights).map(|(c, w)| [c[0] * w, c[1] * w, *w]).collect();
        Ok(Self { degree: p, knots, points })
    }

    /// The distinct knots of the parameter range.
    fn breaks(&self) -> Vec<f64> {
        let n = self.points.len();
        let (lo, hi) = (self.knots[self.degree], self.knots[n]);
        let mut b: Vec<f64> = self.knots.iter().copied().filter(|k| *k >= lo && *k <= hi).collect();
        b.dedup();
        b
    }

    /// The point at parameter `u` (de Boor's algorithm).
    fn eval(&self, u: f64) -> [f64; 2] {
        let p = self.degree;
        let n = self.points.len();
        let t = &self.knots;
        // span k in [p, n-1] with t[k] <= u < t[k+1]; the last non-empty one at the range end
        let mut k = t.partition_point(|x| *x <= u).saturating_sub(1).clamp(p, n - 1);
        while k > p && t[k] >= t[k + 1] {
            k -= 1;
        }
        let mut d: Vec<[f64; 3]> = self.points[k - p..=k].to_vec();
        for r in 1..=p {
            for j in (r..=p).rev() {
                let lo = t[j + k - p];
                let hi = t[j + 1 + k - r];
                let alpha = if hi > lo { (u - lo) / (hi - lo) } else { 0.0 };
                let prev = d[j - 1];
                for (c, q) in d[j].iter_mut().zip(prev) {
                    *c = (1.0 - alpha) * q + alpha * *c;
                }
            }
        }
        let q = d[p];
        if q[2] != 0.0 { [q[0] / q[2], q[1] / q[2]] } else { [q[0], q[1]] }
    }
}

/// A C² cubic interpolating fit points (a spline given without control points).
struct FitCurve {
    /// Parameters (cumulative chord length) of the points.
    t: Vec<f64>,
    pts: Vec<[f64; 2]>,
    /// Second derivatives at the points.
    m: Vec<[f64; 2]>,
}

impl FitCurve {
    fn new(fit: &[[f64; 2]], closed: bool, t0: Option<[f64; 2]>, t1: Option<[f64; 2]>, eps: f64) -> Option<Self> {
        let mut pts: Vec<[f64; 2]> = Vec::with_capacity(fit.len() + 1);
        for p in fit {
            if pts.last().is_none_or(|q| dist(*q, *p) > eps) {
                pts.push(*p);
            }
        }
        let (&first, &last) = (pts.first()?, pts.last()?);
        let periodic = closed || (pts.len() > 2 && dist(first, last) <= eps);
        if periodic {
            if dist(first, last) <= eps {
                pts.pop();
            }
            if pts.len() < 3 {
                return None;
            }
            pts.push(first);
        } else if pts.len() < 2 {
            return None;
        }
        let count = pts.len();
        let mut t = vec![0.0; count];
        for i in 1..count {
            t[i] = t[i - 1] + dist(pts[i - 1], pts[i]);
        }
        let h: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        let unit = |v: Option<[f64; 2]>| {
            v.and_then(|v| {
                let l = (v[0] * v[0] + v[1] * v[1]).sqrt();
                (l > 0.0).then(|| [v[0] / l, v[1] / l])
            })
        };
        let (d0, d1) = (unit(t0), unit(t1));
        let mut m = vec![[0.0; 2]; count];
        for c in 0..2 {
            let y: Vec<f64> = pts.iter().map(|p| p[c]).collect();
            let slope = |i: usize| (y[i + 1] - y[i]) / h[i];
            let sol = if periodic {
                // unknowns M_0..M_{s-1}, M_s = M_0
                let s = count - 1;
                let mut a = vec![0.0; s];
                let mut b = vec![0.0; s];
                let mut cc = vec![0.0; s];
                let mut r = vec![0.0; s];
                for i in 0..s {
                    let hp = h[(i + s - 1) % s];
                    let hi = h[i];
                    a[i] = hp;
                    b[i] = 2.0 * (hp + hi);
                    cc[i] = hi;
                    r[i] = 6.0 * (slope(i) - slope((i + s - 1) % s));
                }
                let mut x = cyclic_tridiagonal(&a, &b, &cc, &r)?;
                x.push(x[0]);
                x
            } else {
                let s = count;
                let mut a = vec![0.0; s];
                let mut b = vec![1.0; s];
                let mut cc = vec![0.0; s];
                let mut r = vec![0.0; s];
                for i in 1..s - 1 {
                    a[i] = h[i - 1];
                    b[i] = 2.0 * (h[i - 1] + h[i]);
                    cc[i] = h[i];
                    r[i] = 6.0 * (slope(i) - slope(i - 1));
                }
                if let Some(d) = d0 {
                    b[0] = 2.0 * h[0];
                    cc[0] = h[0];
                    r[0] = 6.0 * (slope(0) - d[c]);
                }
                if let Some(d) = d1 {
                    a[s - 1] = h[s - 2];
                    b[s - 1] = 2.0 * h[s - 2];
                    r[s - 1] = 6.0 * (d[c] - slope(s - 2));
                }
                tridiagonal(&a, &b, &cc, &r)?
            };
            for (mi, v) in m.iter_mut().zip(sol) {
                mi[c] = v;
            }
        }
        Some(Self { t, pts, m })
    }

    fn eval(&self, u: f64) -> [f64; 2] {
        let n = self.t.len();
        let i = self.t.partition_point(|x| *x <= u).saturating_sub(1).min(n.saturating_sub(2));
        let (Some(&ta), Some(&tb)) = (self.t.get(i), self.t.get(i + 1)) else {
            return self.pts.first().copied().unwrap_or([0.0, 0.0]);
        };
        let h = tb - ta;
        if !positive(h) {
            return self.pts[i];
        }
        let (wa, wb) = (tb - u, u - ta);
        let mut out = [0.0; 2];
        for (c, o) in out.iter_mut().enumerate() {
            let (ya, yb, ma, mb) = (self.pts[i][c], self.pts[i + 1][c], self.m[i][c], self.m[i + 1][c]);
            *o = ma * wa.powi(3) / (6.0 * h)
                + mb * wb.powi(3) / (6.0 * h)
                + (ya / h - ma * h / 6.0) * wa
                + (yb / h - mb * h / 6.0) * wb;
        }
        out
    }
}

/// Solves a tridiagonal system (sub-diagonal `a`, diagonal `b`, super-diagonal `c`).
fn tridiagonal(a: &[f64], b: &[f64], c: &[f64], r: &[f64]) -> Option<Vec<f64>> {
    let n = b.len();
    if n == 0 || a.len() != n || c.len() != n || r.len() != n {
        return None;
    }
    let mut cp = vec![0.0; n];
    let mut x = vec![0.0; n];
    let mut beta = b[0];
    if beta == 0.0 {
        return None;
    }
    x[0] = r[0] / beta;
    for i in 1..n {
        cp[i] = c[i - 1] / beta;
        beta = b[i] - a[i] * cp[i];
        if beta == 0.0 {
            return None;
        }
        x[i] = (r[i] - a[i] * x[i - 1]) / beta;
    }
    for i in (0..n - 1).rev() {
        x[i] -= cp[i + 1] * x[i + 1];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Solves a cyclic tridiagonal system: `a[0]` is the corner entry of row 0 (column n-1) and
/// `c[n-1]` that of row n-1 (column 0). Sherman–Morrison on the plain tridiagonal solver.
fn cyclic_tridiagonal(a: &[f64], b: &[f64], c: &[f64], r: &[f64]) -> Option<Vec<f64>> {
    let n = b.len();
    if n < 3 || a.len() != n || c.len() != n || r.len() != n {
        return None;
    }
    let (beta, alpha) = (a[0], c[n - 1]);
    let gamma = -b[0];
    let mut bb = b.to_vec();
    bb[0] = b[0] - gamma;
    bb[n - 1] = b[n - 1] - alpha * beta / gamma;
    let mut aa = a.to_vec();
    aa[0] = 0.0;
    let mut c2 = c.to_vec();
    c2[n - 1] = 0.0;
    let x = tridiagonal(&aa, &bb, &c2, r)?;
    let mut u = vec![0.0; n];
    u[0] = gamma;
    u[n - 1] = alpha;
    let z = tridiagonal(&aa, &bb, &c2, &u)?;
    let fact = (x[0] + beta * x[n - 1] / gamma) / (1.0 + z[0] + beta * z[n - 1] / gamma);
    let out: Vec<f64> = x.iter().zip(&z).map(|(xi, zi)| xi - fact * zi).collect();
    out.iter().all(|v| v.is_finite()).then_some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn de_boor_matches_bezier() {
        // a cubic Bezier as a clamped B-spline
        let cps = vec![[0.0, 0.0], [1.0, 2.0], [3.0, 2.0], [4.0, 0.0]];
        let s = BSpline::new(3, vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0], cps.clone(), vec![], false).unwrap();
        for k in 0..=10 {
            let t = k as f64 / 10.0;
            let mt = 1.0 - t;
            let b = [mt.powi(3), 3.0 * mt * mt * t, 3.0 * mt * t * t, t.powi(3)];
            let x: f64 = (0..4).map(|i| b[i] * cps[i][0]).sum();
            let y: f64 = (0..4).map(|i| b[i] * cps[i][1]).sum();
            let p = s.eval(t);
            assert!((p[0] - x).abs() < 1e-12 && (p[1] - y).abs() < 1e-12, "t={t}: {p:?} vs {x},{y}");
        }
    }

    #[test]
    fn rational_quadratic_is_a_circle() {
        // quarter circle: weights 1, sqrt(2)/2, 1
        let w = std::f64::consts::FRAC_1_SQRT_2;
        let s = BSpline::new(
            2,
            vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
            vec![[1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            vec![1.0, w, 1.0],
            true,
        )
        .unwrap();
        for k in 0..=20 {
            let p = s.eval(k as f64 / 20.0);
            assert!(((p[0] * p[0] + p[1] * p[1]).sqrt() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn cyclic_solver_solves() {
        // 4x4 cyclic system with known solution
        let a = [1.0, 1.0, 1.0, 1.0];
        let b = [4.0, 4.0, 4.0, 4.0];
        let c = [1.0, 1.0, 1.0, 1.0];
        let x = [1.0, 2.0, 3.0, 4.0];
        let r: Vec<f64> = (0..4).map(|i| a[i] * x[(i + 3) % 4] + b[i] * x[i] + c[i] * x[(i + 1) % 4]).collect();
        let s = cyclic_tridiagonal(&a, &b, &c, &r).unwrap();
        for i in 0..4 {
            assert!((s[i] - x[i]).abs() < 1e-12, "{s:?}");
        }
    }

    #[test]
    fn fit_curve_passes_through_points_and_tangents() {
        let fit = [[0.0, 0.0], [1.0, 1.0], [2.0, 0.0], [3.0, 1.0]];
        let c = FitCurve::new(&fit, false, Some([1.0, 0.0]), None, 1e-9).unwrap();
        for (i, p) in fit.iter().enumerate() {
            let q = c.eval(c.t[i]);
            assert!(dist(*p, q) < 1e-12, "{p:?} {q:?}");
        }
        // start tangent along +x: a point just after the start stays near y = 0
        let q = c.eval(1e-4);
        assert!(q[1].abs() < 1e-6 && q[0] > 0.0, "{q:?}");
    }

    #[test]
    fn affine_ocs_mirrors_for_negative_z() {
        let m = Affine::ocs([0.0, 0.0, -1.0], 0.0);
        assert_eq!(m.apply([2.0, 3.0]), [-2.0, 3.0]);
        assert!(m.det() < 0.0 && m.is_similarity());
        let s = Affine::scale(2.0, 1.0);
        assert!(!s.is_similarity());
        assert!((s.max_scale() - 2.0).abs() < 1e-12);
    }
}
