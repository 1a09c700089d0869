//! A G-code reader: a milling program, swarf's own or another CAM system's (LinuxCNC, GRBL and
//! FreeCAD's posts among them), read into a [`Toolpath`] in millimetres so that it can be
//! simulated and reported on like one swarf planned. It reads the three linear axes and the
//! motions a roughing program uses — rapids, lines, arcs and helices in the XY plane (centre or
//! radius form, with turns), simple drilling cycles — in inches or millimetres, absolute or
//! incremental, and refuses everything else (other planes, cutter compensation, offsets set by
//! the program, parameters and subroutines, other axes) with an [`Error::Input`] that names the
//! line and column, rather than reading a different path than a controller would run. Each move
//! gets the [`MoveKind`] its geometry says (see [`read`]), so that the simulator measures a
//! foreign program as it measures swarf's own.

// Why by hand: the one maintained crate for the job, `gcode` (Michael-F-Bryan, 0.7.0 of April
// 2026: comments, `%`, modal words and spans with line numbers), holds every number as an
// `f32`, seven significant digits: a coordinate of 1234.567 mm is off by up to 0.06 µm and an
// arc centre of 12345.67891 mm by about 0.5 µm, too coarse for LinuxCNC's radius check and for
// a round trip at the post's micrometre. The word grammar itself (a letter, a number, comments)
// is some forty lines; the work is in the modal state, which no crate does for us.

use crate::error::{Error, Result, Setting};
use crate::geom::{DVec2, DVec3};
use crate::limits;
use crate::model::Tool;
use crate::toolpath::{Motion, MoveKind, Toolpath};
use std::f64::consts::{PI, TAU};
use std::path::Path;

/// How a program is read.
#[derive(Debug, Clone, PartialEq)]
pub struct ReadOptions {
    /// The tool the [`Toolpath`] carries (a program names its tool by number only).
    pub tool: Tool,
    /// The clearance height of the toolpath, mm; `None` takes the highest Z of the program.
    pub clearance_z: Option<f64>,
}

impl ReadOptions {
    /// The default tool ([`Tool::DEFAULT`]) and the program's highest Z as the clearance.
    pub const DEFAULT: ReadOptions = ReadOptions { tool: Tool::DEFAULT, clearance_z: None };
}

impl Default for ReadOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A program read.
#[derive(Debug, Clone)]
pub struct Program {
    /// The moves, in millimetres. It starts where the program first is: each of X, Y and Z at
    /// the first value the program gives it.
    pub toolpath: Toolpath,
    /// The 1-based source line of each move of `toolpath.moves` (the pieces of an arc split
    /// into half turns, and the moves of a drilling cycle, share their line).
    pub lines: Vec<u32>,
    /// The units the program is written in, `"mm"` or `"inch"` (those of its first move).
    pub units: &'static str,
    /// What was read other than as written, or may not be what the program means.
    pub warnings: Vec<String>,
    /// The tools the program changes to (`M6`), in order, each with the first move it cuts
    /// (empty when the program changes tools at most once before its first move: one tool).
    pub tools: Vec<ToolSpan>,
}

/// A tool of a program that changes tools, and where its moves begin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ToolSpan {
    /// The tool number (`T`), if the program gave one.
    pub number: Option<u32>,
    /// Its first move in [`Program::toolpath`]; its moves run to the next span's first.
    pub first_move: usize,
    /// The line of its `M6`.
    pub line: u32,
}

impl Program {
    /// The program cut at its tool changes: a toolpath per tool (starting where the one before
    /// it ended), with the source lines of its moves; `tool` gives the [`Tool`] of a tool
    /// number. One piece, with the program's own tool, when it does not change tools.
    pub fn by_tool(&self, tool: &dyn Fn(Option<u32>) -> Tool) -> Vec<(Toolpath, Vec<u32>)> {
        let tp = &self.toolpath;
        if self.tools.len() < 2 {
            let t = self.tools.first().map_or_else(|| tp.tool.clone(), |s| tool(s.number));
            return vec![(Toolpath { tool: t, ..tp.clone() }, self.lines.clone())];
        }
        let mut out = Vec::new();
        for (k, span) in self.tools.iter().enumerate() {
            let a = if k == 0 { 0 } else { span.first_move };
            let b = self.tools.get(k + 1).map_or(tp.moves.len(), |n| n.first_move);
            if b <= a {
                continue;
            }
            let start = if a == 0 { tp.start } else { tp.moves[a - 1].to };
            let mut piece = Toolpath::new(tool(span.number), start, tp.clearance_z);
            piece.moves = tp.moves[a..b].to_vec();
            out.push((piece, self.lines[a..b].to_vec()));
        }
        out
    }
}

/// LinuxCNC's `CENTER_ARC_RADIUS_TOLERANCE_MM`: how far the radius to an arc's end may differ
/// from the radius to its start, mm (in millimetre programs).
const CENTER_TOL_MM: f64 = 2.0 * 0.01 * std::f64::consts::SQRT_2;
/// LinuxCNC's `CENTER_ARC_RADIUS_TOLERANCE_INCH`, inches (in inch programs).
const CENTER_TOL_INCH: f64 = 2.0 * 0.001 * std::f64::consts::SQRT_2;
/// LinuxCNC's `SPIRAL_RELATIVE_TOLERANCE`: the same as a fraction of the radius.
const CENTER_TOL_REL: f64 = 0.001;
/// LinuxCNC's `RADIUS_TOLERANCE` (0.00005 inch), mm: a smaller arc radius is zero, and an `R`
/// may fall this much short of half the chord.
const RADIUS_TOL: f64 = 0.00005 * MM_PER_INCH;
const MM_PER_INCH: f64 = 25.4;
/// The most turns (`P`) of one arc, and repeats (`L`) of one drilling cycle.
const MAX_REPEAT: f64 = 10_000.0;
/// The most moves turns and repeats may add to a program beyond one a line.
const MAX_EXTRA_MOVES: usize = 1_000_000;

/// Reads a G-code program. `file` names it in errors.
///
/// Read: words with or without spaces (`G1X1.5 Y-2`), any case, `N` numbers, `( … )` and `;`
/// comments, `%` lines (a program opened by one ends at the next; `M2` and `M30` end it too),
/// `G0` `G1` `G2` `G3` (the motion mode is `G0` until the program names one, as in GRBL; arc
/// centres `I J` incremental by default, or absolute after `G90.1`, or a radius `R`, negative
/// for the major arc; `P` turns for helices and full circles), `G17`, `G20`/`G21`, `G90`/`G91`,
/// `G90.1`/`G91.1`, `F` (modal, in the program's units per minute). Ignored, as
/// they do not change the path: `G4`, `G40`, `G43`, `G49`, `G54`–`G59.3` (a program is read in
/// its work coordinates; switching between them is warned of), `G61`, `G61.1`, `G64`, `G80`,
/// `G94`, `G96`, `G97`, `G28.1`, `G30.1`, `S`, `H`, `D`, M-codes (the tool changes `M6` are
/// counted: a program that changes to more than one tool is warned of, as it is read with
/// `opts.tool` throughout). Lines starting with `/` (block delete) are skipped, as with the
/// switch on, and warned of.
///
/// Read as near as the program allows: `G28` and `G30` (a rapid to the intermediate point if
/// one is given, then Z up to the clearance height — the home position is a machine setting —
/// keeping X and Y, with a warning), `G53` with Z alone (Z up to the clearance height, with a
/// warning). The drilling cycles `G73` and `G81`–`G89` are expanded as a rapid above the hole,
/// a rapid down to `R`, a feed straight down to `Z` and a rapid back up (to `R` after `G99`, to
/// where the cycle began after `G98`), repeated `L` times (`L` moves on by X Y each time in
/// `G91`); pecks, dwells, spindle stops and feed-out retracts are not drawn, as they cut
/// nothing more.
///
/// Refused, with the line and column: other planes (`G18`, `G19`), cutter compensation (`G41`,
/// `G42`), feed per revolution and inverse time (`G95`, `G93`), offsets set by the program
/// other than work offsets (`G52`, `G92`; `G10 L2`/`L20` are read), `G53` in X or Y, splines, threading, probing, other G-codes, axes
/// other than X Y Z, parameters, expressions and subroutines (`#`, `[`, `O`, `M98`), garbled
/// numbers and words without one, numbers beyond [`limits::MAX_NUMBER`] and positions beyond
/// [`limits::MAX_COORD_MM`], a feed move with no feed or `F0`, arcs LinuxCNC refuses (the
/// radius to the end differing from the radius to the start by more than its
/// `CENTER_ARC_RADIUS_TOLERANCE`, 0.028 mm or 0.0028 inch, or by more than 0.1 % of the
/// radius; a radius under 0.00127 mm; an `R` shorter than half the chord; an `R` arc ending
/// where it starts; neither `I J` nor `R`), and a program without motion.
///
/// Moves get their [`MoveKind`] from their geometry: `G0` is [`MoveKind::Rapid`]; a feed move
/// straight down is a [`MoveKind::Plunge`]; one going down while moving sideways (a ramp, a
/// helix) an [`MoveKind::Entry`]; one going up a [`MoveKind::Link`]; a level one a
/// [`MoveKind::Cut`]. Arcs of more than a half turn are split into equal pieces of at most a
/// half turn, z following the angle. Position and clearance: X, Y and Z start at the first
/// value the program gives each (a program that names Z first and X Y after starts above its
/// first point); the clearance is `opts.clearance_z`, or else the highest Z of the program.
pub fn read(text: &str, file: &Path, opts: &ReadOptions) -> Result<Program> {
    opts.tool.validate()?;
    if let Some(c) = opts.clearance_z
        && !limits::coord_ok(c)
    {
        return Err(Error::setting(
            Setting::Clearance,
            format!("{c} mm: the clearance height must be a number within ±{} mm", limits::MAX_COORD_MM),
        ));
    }
    let mut r = Reader::new(file);
    // a program opened by a `%` line ends at the next one
    let mut opened = false;
    let mut any = false;
    let mut deleted: Vec<u32> = Vec::new();
    for (i, raw_line) in text.split('\n').enumerate() {
        let line = u32::try_from(i + 1).unwrap_or(u32::MAX);
        let chars: Vec<char> = raw_line.trim_end_matches('\r').chars().collect();
        let lead = chars.iter().take_while(|c| c.is_ascii_whitespace()).count();
        match chars.get(lead) {
            None => continue,
            Some('%') => {
                if opened {
                    break;
                }
                opened = !any;
                any = true;
                continue;
            }
            Some('/') => {
                any = true;
                deleted.push(line);
                continue;
            }
            _ => any = true,
        }
        let words = tokenize(&chars[lead..], lead, line, file)?;
        if r.block(line, &words)? {
            break;
        }
    }
    if !deleted.is_empty() {
        r.warnings.push(format!(
            "{} block-delete line{} (starting with /) skipped, as with the switch on: line {}",
            deleted.len(),
            if deleted.len() == 1 { "" } else { "s" },
            list(&deleted)
        ));
    }
    r.finish(opts)
}

/// Up to five numbers of a list, then how many more.
fn list(v: &[u32]) -> String {
    let mut s = v.iter().take(5).map(|l| l.to_string()).collect::<Vec<_>>().join(", ");
    if v.len() > 5 {
        s += &format!(" and {} more", v.len() - 5);
    }
    s
}

fn place(line: u32, col: u32) -> String {
    format!("line {line}, column {col}")
}

/// One word: an upper-case letter and its number, at a 1-based column.
#[derive(Debug, Clone, Copy)]
struct Word {
    letter: char,
    value: f64,
    col: u32,
}

/// The words of one line (`chars` from its first non-blank character, at `offset`).
fn tokenize(chars: &[char], offset: usize, line: u32, file: &Path) -> Result<Vec<Word>> {
    let col_of = |i: usize| u32::try_from(offset + i + 1).unwrap_or(u32::MAX);
    let err = |i: usize, reason: String| Err(Error::input(file, place(line, col_of(i)), reason));
    let mut words = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        match c {
            ' ' | '\t' => i += 1,
            ';' => break,
            '(' => match chars[i..].iter().position(|&c| c == ')') {
                Some(n) => i += n + 1,
                None => return err(i, "a comment opened by ( is not closed on its line".into()),
            },
            c if c.is_ascii_alphabetic() => {
                let letter = c.to_ascii_uppercase();
                if letter == 'O' {
                    return err(i, "O-words (subroutines and control flow) are not read".into());
                }
                let mut j = i + 1;
                while j < chars.len() && (chars[j] == ' ' || chars[j] == '\t') {
                    j += 1;
                }
                let start = j;
                while j < chars.len() && matches!(chars[j], '0'..='9' | '.' | '+' | '-') {
                    j += 1;
                }
                let text: String = chars[start..j].iter().collect();
                if text.is_empty() {
                    if let Some(&n @ ('#' | '[')) = chars.get(start) {
                        return err(start, format!("'{n}': parameters and expressions are not read"));
                    }
                    let what = match chars.get(start) {
                        Some(&n) => format!("'{n}'"),
                        None => "the end of the line".into(),
                    };
                    return err(i, format!("the word {letter} has no number (found {what})"));
                }
                let body = text.strip_prefix(['+', '-']).unwrap_or(&text);
                if body.is_empty()
                    && let Some(&n @ ('#' | '[')) = chars.get(j)
                {
                    return err(j, format!("'{n}': parameters and expressions are not read"));
                }
                if body.is_empty() {
                    return err(i, format!("the word {letter} has no number (found '{text}')"));
                }
                let well_formed = body.chars().any(|c| c.is_ascii_digit())
                    && body.chars().all(|c| c.is_ascii_digit() || c == '.')
                    && body.matches('.').count() <= 1;
                let value = match text.parse::<f64>() {
                    Ok(v) if well_formed => v,
                    _ => return err(i, format!("garbled number {letter}{text}")),
                };
                if value.is_nan() || value.abs() > limits::MAX_NUMBER {
                    return err(
                        i,
                        format!("{letter}{text} is beyond the largest number read, ±{:e}", limits::MAX_NUMBER),
                    );
                }
                words.push(Word { letter, value, col: col_of(i) });
                i = j;
            }
            '#' | '[' | ']' | '<' | '>' | '=' => {
                return err(i, format!("'{c}': parameters and expressions are not read"));
            }
            _ => return err(i, format!("unexpected character '{}'", c.escape_default())),
        }
    }
    Ok(words)
}

/// A coordinate as far as the reader knows it.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Coord {
    /// Not given yet: the first value the program gives.
    Unknown,
    /// Z at the machine's home (`G28`, `G30`, `G53`): the clearance height.
    Home,
    /// Millimetres.
    At(f64),
}

/// An arc as read: its centre, radii at start and end, start angle, signed sweep (turns
/// included) and the number of pieces it is split into.
#[derive(Debug, Clone, Copy)]
struct RawArc {
    center: DVec2,
    r0: f64,
    r1: f64,
    a0: f64,
    sweep: f64,
    pieces: usize,
}

/// A move as read, before unknown coordinates are filled in.
#[derive(Debug, Clone, Copy)]
struct Raw {
    rapid: bool,
    arc: Option<RawArc>,
    to: [Coord; 3],
    feed: f64,
    line: u32,
}

/// The words of one line by letter.
struct Words {
    by: [Option<Word>; 26],
}

impl Words {
    fn get(&self, c: char) -> Option<Word> {
        self.by[(c as u8 - b'A') as usize]
    }
    fn has(&self, c: char) -> bool {
        self.get(c).is_some()
    }
}

/// Modal groups, for two codes of one group on a line.
fn group(g: u32) -> Option<u8> {
    Some(match g {
        0 | 10 | 20 | 30 | 730 | 800 | 810..=890 => 1,
        170 | 180 | 190 => 2,
        900 | 910 => 3,
        901 | 911 => 4,
        930 | 940 | 950 => 5,
        200 | 210 => 6,
        400 | 410 | 420 => 7,
        430 | 490 => 8,
        980 | 990 => 10,
        540..=593 => 12,
        610 | 611 | 640 => 13,
        960 | 970 => 14,
        40 | 100 | 280 | 281 | 300 | 301 | 520 | 530 | 920..=923 => 0,
        _ => return None,
    })
}

/// A G-code's name (`G1`, `G90.1`) from its tenths.
fn gname(g: u32) -> String {
    if g.is_multiple_of(10) { format!("G{}", g / 10) } else { format!("G{}.{}", g / 10, g % 10) }
}

struct Reader<'a> {
    file: &'a Path,
    inch: bool,
    absolute: bool,
    ijk_absolute: bool,
    /// `G99`: drilling cycles retract to R.
    retract_to_r: bool,
    /// Motion mode in tenths (`Some(10)` is G1); `None` after `G80`.
    motion: Option<u32>,
    /// Feed, mm/min.
    feed: Option<f64>,
    pos: [Coord; 3],
    /// What each axis starts at: its first value.
    init: [Option<Coord>; 3],
    /// The last drilling cycle's R and Z words, mm.
    cycle_r: Option<f64>,
    cycle_z: Option<f64>,
    raw: Vec<Raw>,
    extra: usize,
    warnings: Vec<String>,
    tool: Option<u32>,
    changes: Vec<(Option<u32>, u32)>,
    /// Units of the first move, and whether they changed after it.
    units: Option<bool>,
    units_changed: bool,
    wcs: Vec<u32>,
    homes: Vec<u32>,
    /// The work offsets of G54 to G59 that `G10 L2`/`L20` set, mm (all zero until then: the
    /// path is in the coordinates of a G54 at zero), and which one is in use.
    offsets: [[f64; 3]; 6],
    current: usize,
}

impl<'a> Reader<'a> {
    fn new(file: &'a Path) -> Self {
        Reader {
            file,
            inch: false,
            absolute: true,
            ijk_absolute: false,
            retract_to_r: false,
            motion: Some(0),
            feed: None,
            pos: [Coord::Unknown; 3],
            init: [None; 3],
            cycle_r: None,
            cycle_z: None,
            raw: Vec::new(),
            extra: 0,
            warnings: Vec::new(),
            tool: None,
            changes: Vec::new(),
            units: None,
            units_changed: false,
            wcs: Vec::new(),
            offsets: [[0.0; 3]; 6],
            current: 0,
            homes: Vec::new(),
        }
    }

    fn err<T>(&self, line: u32, col: u32, reason: impl Into<String>) -> Result<T> {
        Err(Error::input(self.file, place(line, col), reason))
    }

    fn unit(&self) -> f64 {
        if self.inch { MM_PER_INCH } else { 1.0 }
    }

    /// Reads one line's words; true when the program ends with it.
    fn block(&mut self, line: u32, words: &[Word]) -> Result<bool> {
        let mut by: [Option<Word>; 26] = [None; 26];
        let mut gs: Vec<(u32, u32)> = Vec::new();
        let mut ms: Vec<(u32, u32)> = Vec::new();
        for w in words {
            match w.letter {
                'G' | 'M' => {
                    let tenths = w.value * 10.0;
                    let whole = (tenths - tenths.round()).abs() < 1e-6 && (0.0..=100_000.0).contains(&tenths);
                    if w.letter == 'G' {
                        let g = tenths.round() as u32;
                        if !whole || group(g).is_none() {
                            return self.err(line, w.col, format!("G{}: this G-code is not read", w.value));
                        }
                        gs.push((g, w.col));
                    } else {
                        if !whole || has_tenths(tenths) {
                            return self.err(line, w.col, format!("M{}: an M-code is a whole number", w.value));
                        }
                        ms.push(((tenths.round() as u32) / 10, w.col));
                    }
                }
                'N' => {}
                'X' | 'Y' | 'Z' | 'I' | 'J' | 'K' | 'R' | 'P' | 'Q' | 'L' | 'F' | 'S' | 'T' | 'H' | 'D' => {
                    let k = (w.letter as u8 - b'A') as usize;
                    if by[k].is_some() {
                        return self.err(line, w.col, format!("{} is given twice on one line", w.letter));
                    }
                    by[k] = Some(*w);
                }
                'A' | 'B' | 'C' | 'U' | 'V' | 'W' | 'E' => {
                    return self.err(
                        line,
                        w.col,
                        format!("the axis {} is not read: only X, Y and Z (a three-axis mill)", w.letter),
                    );
                }
                c => return self.err(line, w.col, format!("{c} is not a word this reader knows")),
            }
        }
        let w = Words { by };
        // two codes of one modal group
        for (i, &(g, col)) in gs.iter().enumerate() {
            if let Some(&(h, _)) = gs[..i].iter().find(|(h, _)| group(*h) == group(g) && group(g) != Some(0)) {
                return self.err(
                    line,
                    col,
                    format!("{} and {} are in the same modal group: one of them only", gname(h), gname(g)),
                );
            }
        }
        if gs.iter().filter(|(g, _)| group(*g) == Some(0)).count() > 1 {
            let col = gs.iter().filter(|(g, _)| group(*g) == Some(0)).nth(1).map_or(1, |x| x.1);
            return self.err(line, col, "two non-modal codes (G4, G10, G28, G30, G52, G53, G92) on one line");
        }
        // units first, then the feed in them
        for &(g, col) in &gs {
            match g {
                200 | 210 => {
                    let inch = g == 200;
                    if self.units.is_some_and(|u| u != inch) {
                        self.units_changed = true;
                    }
                    self.inch = inch;
                }
                930 | 950 => {
                    return self.err(
                        line,
                        col,
                        format!(
                            "{}: feed {} is not read, only units per minute (G94)",
                            gname(g),
                            if g == 930 { "in inverse time" } else { "per revolution" }
                        ),
                    );
                }
                180 | 190 => return self.err(line, col, "only XY-plane arcs (G17) are read"),
                410 | 420 => {
                    return self.err(
                        line,
                        col,
                        format!("{}: cutter radius compensation is not read (it moves the path)", gname(g)),
                    );
                }
                900 => self.absolute = true,
                910 => self.absolute = false,
                901 => self.ijk_absolute = true,
                911 => self.ijk_absolute = false,
                980 => self.retract_to_r = false,
                990 => self.retract_to_r = true,
                540..=593 => {
                    if !self.wcs.contains(&g) {
                        self.wcs.push(g);
                    }
                    // (G59.1 to G59.3 have no offset the program sets: read as zero)
                    self.current = if g % 10 == 0 { (g as usize - 540) / 10 } else { 6 };
                }
                _ => {}
            }
        }
        if let Some(f) = w.get('F') {
            if f.value < 0.0 {
                return self.err(line, f.col, format!("F{}: a feed is not negative", f.value));
            }
            let feed = f.value * self.unit();
            if feed > limits::MAX_RATE {
                return self.err(
                    line,
                    f.col,
                    format!("F{}: beyond the highest feed, {} mm/min", f.value, limits::MAX_RATE),
                );
            }
            self.feed = Some(feed);
        }
        if let Some(t) = w.get('T') {
            if t.value < 0.0 || t.value.fract() != 0.0 || t.value > u32::MAX as f64 {
                return self.err(line, t.col, format!("T{}: a tool number is a whole number", t.value));
            }
            self.tool = Some(t.value as u32);
        }
        let mut stop = false;
        for &(m, col) in &ms {
            match m {
                6 => self.changes.push((self.tool, line)),
                2 | 30 => stop = true,
                98 | 99 => return self.err(line, col, format!("M{m}: subprograms are not read")),
                _ => {}
            }
        }
        let axes = ['X', 'Y', 'Z'];
        let has_axes = axes.iter().any(|&a| w.has(a));
        let first_axis_col = axes.iter().filter_map(|&a| w.get(a)).map(|x| x.col).min();
        let motion_code = gs.iter().find(|(g, _)| group(*g) == Some(1)).copied();
        let nonmodal = gs.iter().find(|(g, _)| group(*g) == Some(0)).copied();
        for &(g, col) in &gs {
            if g == 100 && w.get('L').is_some_and(|l| l.value == 2.0 || l.value == 20.0) {
                self.set_offset(line, col, &w)?;
                return Ok(false);
            }
            // (G92 offsets are never applied, so cancelling them changes nothing)
            if matches!(g, 921 | 922) {
                return Ok(false);
            }
            if matches!(g, 100 | 520 | 920..=923) {
                return self.err(line, col, format!("{}: offsets set by the program are not read", gname(g)));
            }
        }
        if let Some((g, col)) = nonmodal
            && matches!(g, 280 | 300)
        {
            if let Some((_, mcol)) = motion_code
                && has_axes
            {
                return self.err(line, mcol, format!("{} and a motion on one line both use the axis words", gname(g)));
            }
            self.home(line, col, g, &w)?;
            return Ok(stop);
        }
        if let Some((code, _)) = motion_code {
            self.motion = if code == 800 { None } else { Some(code) };
        }
        let col = motion_code.map(|m| m.1).or(first_axis_col).unwrap_or(1);
        let machine = nonmodal.is_some_and(|(g, _)| g == 530);
        match self.motion {
            None if has_axes => {
                return self.err(
                    line,
                    first_axis_col.unwrap_or(col),
                    "axis words with no motion mode (G0, G1, G2, G3) in force: G80 cancelled it",
                );
            }
            None => {}
            Some(m) if machine => {
                if !matches!(m, 0 | 10) {
                    return self.err(line, col, "G53 goes with G0 or G1 only");
                }
                if let Some(a) = w.get('X').or(w.get('Y')) {
                    return self.err(
                        line,
                        a.col,
                        "G53 moves in X or Y go to machine positions the program does not relate to its work \
                         coordinates: not read",
                    );
                }
                if w.has('Z') {
                    self.homes.push(line);
                    self.motion_check(line, col, m == 0)?;
                    let to = [self.pos[0], self.pos[1], Coord::Home];
                    self.push(m == 0, None, to, line, col)?;
                }
            }
            Some(m @ (0 | 10)) if has_axes => {
                self.motion_check(line, col, m == 0)?;
                let to = self.target(line, &w)?;
                self.push(m == 0, None, to, line, col)?;
            }
            // (an arc may name its centre alone: a full circle)
            Some(m @ (20 | 30)) if has_axes || w.has('I') || w.has('J') || w.has('R') => {
                self.motion_check(line, col, false)?;
                self.arc(line, col, m == 30, &w)?;
            }
            Some(0 | 10 | 20 | 30) => {}
            Some(_) if has_axes => {
                self.motion_check(line, col, false)?;
                self.cycle(line, col, &w)?;
            }
            Some(_) => {}
        }
        Ok(stop)
    }

    /// Notes the units of the first move; a feed move needs a feed.
    fn motion_check(&mut self, line: u32, col: u32, rapid: bool) -> Result<()> {
        if self.units.is_none() {
            self.units = Some(self.inch);
        }
        if rapid {
            return Ok(());
        }
        match self.feed {
            None => self.err(line, col, "a feed move before any feed rate (F) is set"),
            Some(f) if f <= 0.0 => self.err(line, col, "a feed move at feed rate 0 (F0)"),
            Some(_) => Ok(()),
        }
    }

    fn set_init(&mut self, a: usize, c: Coord) {
        if self.init[a].is_none() {
            self.init[a] = Some(c);
        }
    }

    /// The count word `letter` of `w` (an arc's `P` turns, a cycle's `L` repeats): 1 when absent,
    /// else a whole number from 1 to [`MAX_REPEAT`].
    fn count(&self, line: u32, w: &Words, letter: char, what: &str) -> Result<f64> {
        match w.get(letter) {
            None => Ok(1.0),
            Some(c) if c.value >= 1.0 && c.value.fract() == 0.0 && c.value <= MAX_REPEAT => Ok(c.value),
            Some(c) => self.err(
                line,
                c.col,
                format!("{letter}{}: the {what} are a whole number from 1 to {MAX_REPEAT}", c.value),
            ),
        }
    }

    /// The offset of axis `a` of the work coordinate system in use, mm.
    fn offset(&self, a: usize) -> f64 {
        self.offsets.get(self.current).map_or(0.0, |o| o[a])
    }

    /// `G10 L2 Pn` (the offsets of system n, 1 to 6 for G54 to G59, 0 the one in use) or
    /// `G10 L20 Pn` (the offsets that make the present position read as the values given).
    fn set_offset(&mut self, line: u32, col: u32, w: &Words) -> Result<()> {
        let l20 = w.get('L').is_some_and(|l| l.value == 20.0);
        let p = w.get('P').map_or(0.0, |p| p.value);
        if !(p.fract() == 0.0 && (0.0..=6.0).contains(&p)) {
            return self.err(line, col, format!("G10 P{p}: a work coordinate system is P1 to P6 (G54 to G59), or P0"));
        }
        let n = if p == 0.0 { self.current } else { p as usize - 1 };
        if n >= 6 {
            return self.err(line, col, "G10 with G59.1 to G59.3 in use: their offsets are not read");
        }
        for (a, c) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            let Some(word) = w.get(c) else { continue };
            let v = word.value * self.unit();
            let off = if l20 {
                match self.pos[a] {
                    Coord::At(at) => at - v,
                    _ => {
                        return self.err(
                            line,
                            word.col,
                            format!("G10 L20 {c}: from a position the program does not state"),
                        );
                    }
                }
            } else {
                v
            };
            if !limits::coord_ok(off) {
                return self.err(
                    line,
                    word.col,
                    format!("G10 {c}: an offset of {off:.6e} mm is beyond ±{} mm", limits::MAX_COORD_MM),
                );
            }
            let said = format!("G{} offset {c}{off} mm", 54 + n);
            if off != 0.0 && self.offsets[n][a] != off && !self.warnings.iter().any(|x| x.contains(&said)) {
                self.warnings.push(format!(
                    "line {line}: {said} applied to what follows in it (the path is in the coordinates of G54 at zero)"
                ));
            }
            self.offsets[n][a] = off;
        }
        Ok(())
    }

    /// Where axis `a` goes for a word of `v` (program units), absolute or incremental.
    fn axis(&mut self, line: u32, word: Word, a: usize, incremental: bool) -> Result<Coord> {
        let v = word.value * self.unit();
        let at = if !incremental {
            v + self.offset(a)
        } else {
            match self.pos[a] {
                Coord::At(p) => p + v,
                Coord::Unknown => {
                    self.warnings.push(format!(
                        "line {line}: an incremental {} before any position of it: read as starting at 0",
                        word.letter
                    ));
                    self.set_init(a, Coord::At(0.0));
                    v
                }
                Coord::Home => {
                    return self.err(
                        line,
                        word.col,
                        format!(
                            "an incremental {} from the home position (G28, G30, G53), which the program does not \
                             state",
                            word.letter
                        ),
                    );
                }
            }
        };
        if !limits::coord_ok(at) {
            return self.err(
                line,
                word.col,
                format!(
                    "{} goes to {at:.6e} mm: every coordinate must be within ±{} mm",
                    word.letter,
                    limits::MAX_COORD_MM
                ),
            );
        }
        Ok(Coord::At(at))
    }

    /// The end of a move to the axis words of `w`.
    fn target(&mut self, line: u32, w: &Words) -> Result<[Coord; 3]> {
        let mut to = self.pos;
        for (a, c) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            if let Some(word) = w.get(c) {
                to[a] = self.axis(line, word, a, !self.absolute)?;
            }
        }
        Ok(to)
    }

    fn budget(&mut self, line: u32, col: u32, n: usize) -> Result<()> {
        self.extra += n;
        if self.extra > MAX_EXTRA_MOVES {
            return self.err(
                line,
                col,
                format!("the arcs' turns (P) and the cycles' repeats (L) add more than {MAX_EXTRA_MOVES} moves"),
            );
        }
        Ok(())
    }

    fn push(&mut self, rapid: bool, arc: Option<RawArc>, to: [Coord; 3], line: u32, col: u32) -> Result<()> {
        // (an axis known before is in `init` already)
        for (a, &c) in to.iter().enumerate() {
            if c != Coord::Unknown {
                self.set_init(a, c);
            }
        }
        let feed = if rapid { 0.0 } else { self.feed.unwrap_or(0.0) };
        self.raw.push(Raw { rapid, arc, to, feed, line });
        self.pos = to;
        self.budget(line, col, 0)
    }

    /// `G28` or `G30`: to the intermediate point, then Z home.
    fn home(&mut self, line: u32, col: u32, g: u32, w: &Words) -> Result<()> {
        let named: Vec<char> = ['X', 'Y', 'Z'].into_iter().filter(|&c| w.has(c)).collect();
        // the intermediate point: an incremental 0 (`G28 G91 Z0`) goes nowhere
        let mut to = self.pos;
        for (a, c) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            if let Some(word) = w.get(c)
                && (self.absolute || word.value != 0.0)
            {
                to[a] = self.axis(line, word, a, !self.absolute)?;
            }
        }
        if to != self.pos {
            self.push(true, None, to, line, col)?;
        }
        if named.is_empty() || named.contains(&'Z') {
            let to = [self.pos[0], self.pos[1], Coord::Home];
            self.push(true, None, to, line, col)?;
        }
        self.homes.push(line);
        if named.is_empty() || named.contains(&'X') || named.contains(&'Y') {
            self.warnings.push(format!(
                "line {line}: {} sends X and Y to a home position the program does not state: they are kept",
                gname(g)
            ));
        }
        Ok(())
    }

    /// `G2` (`ccw` false) or `G3`.
    fn arc(&mut self, line: u32, col: u32, ccw: bool, w: &Words) -> Result<()> {
        let (sx, sy) = match (self.pos[0], self.pos[1]) {
            (Coord::At(x), Coord::At(y)) => (x, y),
            _ => return self.err(line, col, "an arc from an unknown point: give X and Y before it"),
        };
        let to = self.target(line, w)?;
        let (Coord::At(ex), Coord::At(ey)) = (to[0], to[1]) else {
            return self.err(line, col, "an arc from an unknown point: give X and Y before it");
        };
        let (s, e) = (DVec2::new(sx, sy), DVec2::new(ex, ey));
        let turns = self.count(line, w, 'P', "turns of an arc")?;
        let u = self.unit();
        let center = if let Some(rw) = w.get('R') {
            if let Some(ij) = w.get('I').or(w.get('J')) {
                return self.err(line, ij.col, "an arc with both R and I/J: one or the other");
            }
            let r = rw.value * u;
            if r.abs() < RADIUS_TOL {
                return self.err(line, rw.col, format!("R{}: a zero-radius arc", rw.value));
            }
            if s == e {
                return self.err(
                    line,
                    rw.col,
                    "an R arc that ends where it starts has no one centre: a full circle needs I and J",
                );
            }
            let half = (e - s).length() / 2.0;
            let ar = r.abs();
            if half - ar > RADIUS_TOL {
                return self.err(
                    line,
                    rw.col,
                    format!(
                        "R{} cannot reach the end point: the chord, {:.4} mm, is more than 2R, {:.4} mm",
                        rw.value,
                        2.0 * half,
                        2.0 * ar
                    ),
                );
            }
            let half = if half / ar > 1.0 - 1e-12 { ar } else { half };
            // as LinuxCNC's arc_data_r: the centre is off the chord's middle to the right of a
            // clockwise minor arc, to the left of a counter-clockwise one, the other way for
            // negative R (the major arc)
            let d = e - s;
            let right = (!ccw && r > 0.0) || (ccw && r < 0.0);
            let theta = d.y.atan2(d.x) + if right { -PI / 2.0 } else { PI / 2.0 };
            let offset = ar * (half / ar).asin().cos();
            (s + e) / 2.0 + DVec2::new(theta.cos(), theta.sin()) * offset
        } else {
            let (i, j) = (w.get('I'), w.get('J'));
            if i.is_none() && j.is_none() {
                return self.err(line, col, "an arc with neither I/J nor R");
            }
            let ij = DVec2::new(i.map_or(0.0, |v| v.value), j.map_or(0.0, |v| v.value)) * u;
            let c = if self.ijk_absolute { ij } else { s + ij };
            if !(limits::coord_ok(c.x) && limits::coord_ok(c.y)) {
                return self.err(
                    line,
                    col,
                    format!("the arc's centre ({:.6e}, {:.6e}) mm is beyond ±{} mm", c.x, c.y, limits::MAX_COORD_MM),
                );
            }
            let (r0, r1) = ((s - c).length(), (e - c).length());
            if r0 < RADIUS_TOL || r1 < RADIUS_TOL {
                return self.err(
                    line,
                    col,
                    format!("a zero-radius arc: the centre is {:.5} mm from its start, {:.5} mm from its end", r0, r1),
                );
            }
            // LinuxCNC's rule (arc_data_ijk): an error when the radii differ by more than the
            // absolute tolerance or by more than 0.1 % of the larger
            let tol = if self.inch { CENTER_TOL_INCH * MM_PER_INCH } else { CENTER_TOL_MM };
            let diff = (r0 - r1).abs();
            if diff > tol || diff / r0.max(r1) > CENTER_TOL_REL {
                return self.err(
                    line,
                    col,
                    format!(
                        "the radius to the arc's end, {r1:.4} mm, differs from the radius to its start, {r0:.4} mm, by \
                         {diff:.4} mm: more than {:.4} mm or 0.1 % of the radius (LinuxCNC refuses it)",
                        tol
                    ),
                );
            }
            c
        };
        let a0 = (s - center).y.atan2((s - center).x);
        let a1 = (e - center).y.atan2((e - center).x);
        // as LinuxCNC's find_turn: an end at the start's angle is a full turn
        let mut d = a1 - a0;
        if ccw && d <= 0.0 {
            d += TAU;
        } else if !ccw && d >= 0.0 {
            d -= TAU;
        }
        let sweep = d + d.signum() * (turns - 1.0) * TAU;
        let (r0, r1) = ((s - center).length(), (e - center).length());
        if let Some(p) = arc_beyond(center, r0.max(r1), a0, sweep) {
            return self.err(
                line,
                col,
                format!(
                    "the arc reaches ({:.6e}, {:.6e}) mm: every coordinate must be within ±{} mm",
                    p.x,
                    p.y,
                    limits::MAX_COORD_MM
                ),
            );
        }
        let pieces = ((sweep.abs() / PI) - 1e-9).ceil().max(1.0) as usize;
        self.budget(line, col, pieces.saturating_sub(2))?;
        let arc = RawArc { center, r0, r1, a0, sweep, pieces };
        self.push(false, Some(arc), to, line, col)
    }

    /// A drilling cycle at the words of `w`.
    fn cycle(&mut self, line: u32, col: u32, w: &Words) -> Result<()> {
        let u = self.unit();
        let name = gname(self.motion.unwrap_or(810));
        if let Some(r) = w.get('R') {
            self.cycle_r = Some(r.value * u);
        }
        if let Some(z) = w.get('Z') {
            self.cycle_z = Some(z.value * u);
        }
        let (Some(rw), Some(zw)) = (self.cycle_r, self.cycle_z) else {
            return self.err(line, col, format!("{name} needs R (its retract plane) and Z (its bottom)"));
        };
        let reps = self.count(line, w, 'L', "repeats of a cycle")? as usize;
        let old_z = self.pos[2];
        let (r, bottom) = if self.absolute {
            (rw + self.offset(2), zw + self.offset(2))
        } else {
            match old_z {
                Coord::At(z) => (z + rw, z + rw + zw),
                _ => {
                    return self.err(line, col, format!("an incremental {name} from a Z the program does not state"));
                }
            }
        };
        for v in [r, bottom] {
            if !limits::coord_ok(v) {
                return self.err(
                    line,
                    col,
                    format!("{name} reaches Z {v:.6e} mm, beyond ±{} mm", limits::MAX_COORD_MM),
                );
            }
        }
        if bottom > r {
            return self.err(
                line,
                col,
                format!("{name}'s bottom, Z {bottom} mm, is above its retract plane, R {r} mm"),
            );
        }
        self.budget(line, col, 4 * (reps - 1))?;
        let up = match old_z {
            Coord::Unknown => return self.err(line, col, format!("{name} from a Z the program does not state")),
            Coord::At(z) if z < r => {
                let to = [self.pos[0], self.pos[1], Coord::At(r)];
                self.push(true, None, to, line, col)?;
                Coord::At(r)
            }
            z => z,
        };
        let retract = if self.retract_to_r { Coord::At(r) } else { up };
        for _ in 0..reps {
            let mut to = self.pos;
            for (a, c) in ['X', 'Y'].into_iter().enumerate() {
                if let Some(word) = w.get(c) {
                    to[a] = self.axis(line, word, a, !self.absolute)?;
                }
            }
            if matches!(to[0], Coord::Unknown) || matches!(to[1], Coord::Unknown) {
                return self.err(line, col, format!("{name} at an X or Y the program does not state"));
            }
            self.push(true, None, to, line, col)?;
            self.push(true, None, [to[0], to[1], Coord::At(r)], line, col)?;
            self.push(false, None, [to[0], to[1], Coord::At(bottom)], line, col)?;
            self.push(true, None, [to[0], to[1], retract], line, col)?;
        }
        Ok(())
    }

    /// The program: unknown coordinates filled in, home at the clearance height, arcs split.
    fn finish(mut self, opts: &ReadOptions) -> Result<Program> {
        if self.raw.is_empty() {
            return Err(Error::input(self.file, "file", "the program has no motion: no G0, G1, G2 or G3 move"));
        }
        for (a, c) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            if self.init[a].is_none() {
                self.warnings.push(format!("the program never gives {c}: read as 0"));
            }
        }
        let init = self.init.map(|c| c.unwrap_or(Coord::At(0.0)));
        let top = self
            .raw
            .iter()
            .map(|m| m.to[2])
            .chain([init[2]])
            .filter_map(|c| if let Coord::At(z) = c { Some(z) } else { None })
            .fold(f64::NEG_INFINITY, f64::max);
        let top = if top.is_finite() { top } else { opts.clearance_z.unwrap_or(0.0) };
        let clearance = opts.clearance_z.unwrap_or(top);
        let home = clearance.max(top);
        let fix = |c: Coord, a: usize| -> f64 {
            match c {
                Coord::At(v) => v,
                Coord::Home => home,
                Coord::Unknown => match init[a] {
                    Coord::At(v) => v,
                    _ => home,
                },
            }
        };
        let fix3 = |p: [Coord; 3]| DVec3::new(fix(p[0], 0), fix(p[1], 1), fix(p[2], 2));
        let start = fix3(init);
        let mut tp = Toolpath::new(opts.tool.clone(), start, clearance);
        let mut lines = Vec::with_capacity(self.raw.len());
        let mut from = start;
        let mut add = |tp: &mut Toolpath, kind: MoveKind, motion: Motion, to: DVec3, feed: f64, line: u32| {
            let n = tp.moves.len();
            tp.push(kind, motion, to, feed);
            if tp.moves.len() > n {
                lines.push(line);
            }
        };
        for m in &self.raw {
            let to = fix3(m.to);
            let dz = to.z - from.z;
            let dxy = (to.truncate() - from.truncate()).length();
            let kind = if m.rapid {
                MoveKind::Rapid
            } else if dz < -1e-9 && dxy < 1e-9 && m.arc.is_none() {
                MoveKind::Plunge
            } else if dz < -1e-9 {
                MoveKind::Entry
            } else if dz > 1e-9 {
                MoveKind::Link
            } else {
                MoveKind::Cut
            };
            match m.arc {
                None => add(&mut tp, kind, Motion::Line, to, m.feed, m.line),
                Some(a) => {
                    let ccw = a.sweep > 0.0;
                    for k in 1..=a.pieces {
                        let p = if k == a.pieces {
                            to
                        } else {
                            let t = k as f64 / a.pieces as f64;
                            let (r, ang) = (a.r0 + (a.r1 - a.r0) * t, a.a0 + a.sweep * t);
                            (a.center + DVec2::new(ang.cos(), ang.sin()) * r).extend(from.z + dz * t)
                        };
                        add(&mut tp, kind, Motion::Arc { center: a.center, ccw }, p, m.feed, m.line);
                    }
                }
            }
            from = to;
        }
        if tp.moves.is_empty() {
            return Err(Error::input(self.file, "file", "the program has no motion: every move ends where it starts"));
        }
        let distinct: Vec<Option<u32>> = self.changes.iter().fold(Vec::new(), |mut v, (t, _)| {
            if !v.contains(t) {
                v.push(*t);
            }
            v
        });
        if distinct.len() > 1 {
            let what: Vec<String> = self
                .changes
                .iter()
                .take(5)
                .map(|(t, l)| format!("{} at line {l}", t.map_or("a tool".into(), |t| format!("T{t}"))))
                .collect();
            self.warnings.push(format!(
                "the program changes tools {} times ({}{}): each tool's moves are read apart (a tool's size is not in a program: --tool N=MM gives it)",
                self.changes.len(),
                what.join(", "),
                if self.changes.len() > 5 { ", …" } else { "" }
            ));
        }
        if self.wcs.len() > 1 {
            let names: Vec<String> = self.wcs.iter().map(|&g| gname(g)).collect();
            self.warnings.push(format!(
                "the program uses {} work coordinate systems ({}): read with the offsets it sets (G10), zero otherwise",
                self.wcs.len(),
                names.join(", ")
            ));
        }
        if !self.homes.is_empty() {
            self.warnings.push(format!(
                "{} move{} to the machine's home or machine coordinates (G28, G30, G53) read as Z up to the clearance \
                 height, {:.3} mm: line {}",
                self.homes.len(),
                if self.homes.len() == 1 { "" } else { "s" },
                home,
                list(&self.homes)
            ));
        }
        if self.units_changed {
            self.warnings.push("the program changes units (G20, G21) after its first move".into());
        }
        let units = if self.units.unwrap_or(self.inch) { "inch" } else { "mm" };
        // each tool change's first move: the first whose line follows its M6
        let mut tools: Vec<ToolSpan> = Vec::new();
        for &(number, line) in &self.changes {
            let first_move = lines.partition_point(|&l| l <= line);
            if let Some(last) = tools.last_mut()
                && last.first_move == first_move
            {
                // (two changes before one move: the later one cuts)
                *last = ToolSpan { number, first_move, line };
            } else {
                tools.push(ToolSpan { number, first_move, line });
            }
        }
        Ok(Program { toolpath: tp, lines, units, warnings: self.warnings, tools })
    }
}

/// The first point of an arc round `c` of radius `r` from the angle `a0` over `sweep` (signed)
/// beyond [`limits::MAX_COORD_MM`], of those furthest along an axis, if any.
fn arc_beyond(c: DVec2, r: f64, a0: f64, sweep: f64) -> Option<DVec2> {
    (0..4).find_map(|k| {
        let ang = k as f64 * PI / 2.0;
        let ahead = if sweep > 0.0 { ang - a0 } else { a0 - ang };
        let p = c + DVec2::new(ang.cos(), ang.sin()) * r;
        (ahead.rem_euclid(TAU) <= sweep.abs() && !(limits::coord_ok(p.x) && limits::coord_ok(p.y))).then_some(p)
    })
}

/// True when a code's value in tenths has a fraction (M-codes are whole numbers).
fn has_tenths(tenths: f64) -> bool {
    (tenths.round() as i64) % 10 != 0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::toolpath::{ArcGeom, move_length};

    fn rd(text: &str) -> Result<Program> {
        read(text, Path::new("t.ngc"), &ReadOptions::DEFAULT)
    }

    fn near(a: DVec3, b: DVec3) -> bool {
        (a - b).length() < 1e-9
    }

    /// The error's place and reason.
    fn fails(text: &str) -> (String, String) {
        match rd(text) {
            Err(Error::Input { place, reason, .. }) => (place, reason),
            other => panic!("{text:?}: expected an input error, got {other:?}"),
        }
    }

    fn arc_of(m: &crate::toolpath::Move) -> (DVec2, bool) {
        match m.motion {
            Motion::Arc { center, ccw } => (center, ccw),
            Motion::Line => panic!("not an arc: {m:?}"),
        }
    }

    #[test]
    fn ij_and_r_arcs_minor_and_major() {
        let p = rd("G21 G90 G17\nG0 X10 Y0 Z0\nG3 X0 Y10 I-10 J0 F100\n\
                    G0 X10 Y0\nG3 X0 Y10 R10\n\
                    G0 X10 Y0\nG3 X0 Y10 R-10\n\
                    G0 X10 Y0\nG2 X0 Y10 R10\n\
                    G0 X10 Y0\nG2 X0 Y10 R-10\n")
        .unwrap();
        let tp = &p.toolpath;
        // each arc after its rapid back to (10, 0): (line, centre, ccw, sweep)
        let want = [
            (3, DVec2::new(0.0, 0.0), true, PI / 2.0),
            (5, DVec2::new(0.0, 0.0), true, PI / 2.0),
            (7, DVec2::new(10.0, 10.0), true, 1.5 * PI),
            (9, DVec2::new(10.0, 10.0), false, -PI / 2.0),
            (11, DVec2::new(0.0, 0.0), false, -1.5 * PI),
        ];
        for (line, c, ccw, sweep) in want {
            let pieces: Vec<(DVec3, &crate::toolpath::Move)> =
                tp.segments().zip(&p.lines).filter(|(_, l)| **l == line).map(|(s, _)| s).collect();
            assert_eq!(pieces.len(), if sweep.abs() > PI { 2 } else { 1 }, "line {line}");
            let mut total = 0.0;
            for (from, m) in &pieces {
                let (center, dir) = arc_of(m);
                assert!((center - c).length() < 1e-9 && dir == ccw, "line {line}: {center} {dir}");
                let g = ArcGeom::new(*from, m.to, center, dir);
                assert!(g.sweep.abs() <= PI + 1e-9 && (g.radius - 10.0).abs() < 1e-9, "line {line}: {g:?}");
                total += g.sweep;
                assert_eq!(m.kind, MoveKind::Cut);
            }
            assert!((total - sweep).abs() < 1e-9, "line {line}: sweep {total}, not {sweep}");
            assert!(near(pieces.last().unwrap().1.to, DVec3::new(0.0, 10.0, 0.0)));
        }
    }

    #[test]
    fn a_full_circle_is_split_into_half_turns_round_its_centre() {
        let p = rd("G0 X5 Y0 Z0\nG2 X5 Y0 I-5 J0 F100\n").unwrap();
        let m = &p.toolpath.moves;
        assert_eq!(m.len(), 2);
        assert_eq!(p.lines, vec![2, 2]);
        for mv in m {
            assert_eq!(arc_of(mv), (DVec2::ZERO, false));
        }
        assert!(near(m[0].to, DVec3::new(-5.0, 0.0, 0.0)), "{}", m[0].to);
        assert!(near(m[1].to, DVec3::new(5.0, 0.0, 0.0)));
        // clockwise from (5, 0): through (0, -5) first
        let g = ArcGeom::new(DVec3::new(5.0, 0.0, 0.0), m[0].to, DVec2::ZERO, false);
        assert!((g.sweep + PI).abs() < 1e-9 && (g.at(0.5) - DVec3::new(0.0, -5.0, 0.0)).length() < 1e-9);
        // a full circle written with I only, in incremental mode, and in absolute centre mode
        let q = rd("G0 X5 Y0 Z0\nG91\nG3 X0 Y0 I-5 F100\nG90 G90.1\nG3 X5 Y0 I0 J0\n").unwrap();
        assert_eq!(q.toolpath.moves.len(), 4);
        assert!(q.toolpath.moves.iter().all(|m| arc_of(m) == (DVec2::ZERO, true)));
    }

    #[test]
    fn a_helix_with_p2_splits_with_z_linear_in_angle() {
        let p = rd("G0 X5 Y0 Z0\nG3 X5 Y0 Z-4 I-5 J0 P2 F100\n").unwrap();
        let tp = &p.toolpath;
        assert!(tp.moves.len() >= 4, "{}", tp.moves.len());
        let mut angle = 0.0;
        for (from, m) in tp.segments() {
            let (c, ccw) = arc_of(m);
            assert!(ccw && c.length() < 1e-12);
            assert_eq!(m.kind, MoveKind::Entry);
            let g = ArcGeom::new(from, m.to, c, ccw);
            assert!(g.sweep > 0.0 && g.sweep <= PI + 1e-9);
            angle += g.sweep;
            // two turns down 4 mm: 1 mm for every half turn
            assert!((m.to.z + 4.0 * angle / (4.0 * PI)).abs() < 1e-9, "z {} at {angle}", m.to.z);
            assert!(((m.to.truncate()).length() - 5.0).abs() < 1e-9);
        }
        assert!((angle - 4.0 * PI).abs() < 1e-9);
        assert!(p.lines.iter().all(|&l| l == 2));
        let helix: f64 = tp.segments().map(|(f, m)| move_length(f, m)).sum();
        assert!((helix - ((20.0 * PI).powi(2) + 16.0).sqrt()).abs() < 1e-9);
    }

    #[test]
    fn inches_are_read_as_millimetres() {
        let p = rd("G20 G90\nG0 X1 Y2 Z0.5\nG1 Z-0.1 F10\nG1 X2\n").unwrap();
        assert_eq!(p.units, "inch");
        let tp = &p.toolpath;
        assert!(near(tp.start, DVec3::new(25.4, 50.8, 12.7)));
        assert_eq!(tp.clearance_z, 12.7);
        assert!(near(tp.moves[0].to, DVec3::new(25.4, 50.8, -2.54)));
        assert_eq!(tp.moves[0].kind, MoveKind::Plunge);
        assert!((tp.moves[0].feed - 254.0).abs() < 1e-9);
        assert!(near(tp.moves[1].to, DVec3::new(50.8, 50.8, -2.54)));
        assert_eq!(tp.moves[1].kind, MoveKind::Cut);
        assert_eq!(rd("G21 G0 X1 Y1 Z1\nX2\nG20\n").unwrap().units, "mm");
    }

    #[test]
    fn incremental_moves_add_up() {
        let p = rd("G90 G0 X0 Y0 Z5\nG91 G1 Z-6 F100\nX10\nY10 Z1\nX-5 Y-5 Z-2\nG90 X0\n").unwrap();
        let to: Vec<DVec3> = p.toolpath.moves.iter().map(|m| m.to).collect();
        let want = [(0.0, 0.0, -1.0), (10.0, 0.0, -1.0), (10.0, 10.0, 0.0), (5.0, 5.0, -2.0), (0.0, 5.0, -2.0)];
        assert_eq!(to.len(), want.len());
        for (t, w) in to.iter().zip(want) {
            assert!(near(*t, DVec3::from(w)), "{t} ≠ {w:?}");
        }
        let kinds: Vec<MoveKind> = p.toolpath.moves.iter().map(|m| m.kind).collect();
        assert_eq!(kinds, [MoveKind::Plunge, MoveKind::Cut, MoveKind::Link, MoveKind::Entry, MoveKind::Cut]);
        assert_eq!(p.lines, [2, 3, 4, 5, 6]);
    }

    #[test]
    fn a_freecad_program_is_read() {
        let text = "%\n\
            (Exported by FreeCAD)\n\
            (Post Processor: linuxcnc_post)\n\
            (Output Time:2024-05-01 10:00:00)\n\
            (begin preamble)\n\
            G17 G54 G40 G49 G80 G90\n\
            G21\n\
            (begin operation: TC: Default Tool)\n\
            (machine units: mm/min)\n\
            M6 T1\n\
            G43 H1\n\
            M3 S10000\n\
            (finish operation: TC: Default Tool)\n\
            (begin operation: Adaptive)\n\
            (machine units: mm/min)\n\
            G0 Z15.000\n\
            G0 X10.000 Y10.000\n\
            G0 Z3.000\n\
            G1 Z-1.000 F100.000\n\
            G1 X20.000 Y10.000 F300.000\n\
            G2 X30.000 Y10.000 Z-1.000 I5.000 J0.000 K0.000 F300.000\n\
            G3 X25.000 Y15.000 I-2.500 J2.500 K0\n\
            G1 X25 Y15 Z2\n\
            G0 Z15.000\n\
            (finish operation: Adaptive)\n\
            (begin postamble)\n\
            M05\n\
            G17 G54 G90 G80 G40\n\
            M2\n\
            %\n";
        let p = rd(text).unwrap();
        let tp = &p.toolpath;
        assert_eq!(p.units, "mm");
        assert!(p.warnings.is_empty(), "{:?}", p.warnings);
        assert!(near(tp.start, DVec3::new(10.0, 10.0, 15.0)), "{}", tp.start);
        assert_eq!(tp.clearance_z, 15.0);
        let kinds: Vec<MoveKind> = tp.moves.iter().map(|m| m.kind).collect();
        use MoveKind::*;
        assert_eq!(kinds, [Rapid, Plunge, Cut, Cut, Cut, Link, Rapid]);
        assert_eq!(p.lines, [18, 19, 20, 21, 22, 23, 24]);
        assert!((tp.moves[1].feed - 100.0).abs() < 1e-12 && (tp.moves[2].feed - 300.0).abs() < 1e-12);
        // the clockwise half turn over the top of (25, 10), then the quarter back round (27.5, 12.5)
        let (c, ccw) = arc_of(&tp.moves[3]);
        assert!(!ccw && (c - DVec2::new(25.0, 10.0)).length() < 1e-12);
        assert!(near(tp.moves[4].to, DVec3::new(25.0, 15.0, -1.0)));
        assert_eq!(arc_of(&tp.moves[4]), (DVec2::new(27.5, 12.5), true));
        assert!(near(tp.end(), DVec3::new(25.0, 15.0, 15.0)));
        // text after the closing % is not read
        assert!(rd(&format!("{text}G0 X1.2.3\n")).is_ok());
    }

    #[test]
    fn drilling_cycles_expand_to_a_rapid_a_feed_down_and_a_rapid_up() {
        let p = rd("G90 G0 X0 Y0 Z10\nG98 G81 X5 Y5 Z-3 R2 F100\nX10\nG99 G83 X20 Q1\nG80\nG0 Z10\n").unwrap();
        let got: Vec<(MoveKind, [f64; 3])> = p.toolpath.moves.iter().map(|m| (m.kind, m.to.to_array())).collect();
        use MoveKind::*;
        let want = [
            (Rapid, [5.0, 5.0, 10.0]),
            (Rapid, [5.0, 5.0, 2.0]),
            (Plunge, [5.0, 5.0, -3.0]),
            (Rapid, [5.0, 5.0, 10.0]),
            (Rapid, [10.0, 5.0, 10.0]),
            (Rapid, [10.0, 5.0, 2.0]),
            (Plunge, [10.0, 5.0, -3.0]),
            (Rapid, [10.0, 5.0, 10.0]),
            (Rapid, [20.0, 5.0, 10.0]),
            (Rapid, [20.0, 5.0, 2.0]),
            (Plunge, [20.0, 5.0, -3.0]),
            (Rapid, [20.0, 5.0, 2.0]),
            (Rapid, [20.0, 5.0, 10.0]),
        ];
        assert_eq!(got, want);
        assert_eq!(p.lines, [2, 2, 2, 2, 3, 3, 3, 3, 4, 4, 4, 4, 6]);
        // incremental with repeats: R above the current Z, Z below R
        let q = rd("G0 X0 Y0 Z5\nG91 G99 G81 X10 R-3 Z-4 L3 F100\n").unwrap();
        let bottoms: Vec<[f64; 3]> =
            q.toolpath.moves.iter().filter(|m| m.kind == Plunge).map(|m| m.to.to_array()).collect();
        assert_eq!(bottoms, [[10.0, 0.0, -2.0], [20.0, 0.0, -2.0], [30.0, 0.0, -2.0]]);
    }

    #[test]
    fn home_returns_rise_to_the_clearance_height() {
        let p = rd("G28 G91 Z0\nG90\nG0 X10 Y10\nG0 Z5\nG1 Z-1 F100\nG0 Z5\nG53 G0 Z0\n").unwrap();
        let tp = &p.toolpath;
        assert_eq!(tp.clearance_z, 5.0);
        assert!(near(tp.start, DVec3::new(10.0, 10.0, 5.0)), "{}", tp.start);
        assert!(near(tp.end(), DVec3::new(10.0, 10.0, 5.0)));
        assert!(p.warnings.iter().any(|w| w.contains("G28, G30, G53") && w.contains("1, 7")), "{:?}", p.warnings);
        let o = ReadOptions { clearance_z: Some(40.0), ..ReadOptions::DEFAULT };
        let q = read("G28 G91 Z0\nG90\nG0 X10 Y10\nG0 Z5\nG1 Z-1 F100\nG28\n", Path::new("t"), &o).unwrap();
        assert!(near(q.toolpath.start, DVec3::new(10.0, 10.0, 40.0)));
        assert!(near(q.toolpath.end(), DVec3::new(10.0, 10.0, 40.0)));
        assert!(q.warnings.iter().any(|w| w.contains("X and Y")), "{:?}", q.warnings);
    }

    #[test]
    fn words_comments_and_case_are_read_loosely() {
        let p = rd("n10 g0x1.5 y-2 z+3 (a comment (nested)\n/G1 X100 F1\nN20G1X.5F100.;the rest\n  G1 X 2.").unwrap();
        let to: Vec<[f64; 3]> = p.toolpath.moves.iter().map(|m| m.to.to_array()).collect();
        assert_eq!(to, [[0.5, -2.0, 3.0], [2.0, -2.0, 3.0]]);
        assert!(p.warnings.iter().any(|w| w.contains("block-delete") && w.contains("line 2")), "{:?}", p.warnings);
        // a second tool
        let q = rd("T1 M6\nG0 X0 Y0 Z1\nT2 M6\nG0 X1\n").unwrap();
        assert!(q.warnings.iter().any(|w| w.contains("changes tools 2 times") && w.contains("T2 at line 3")));
        assert!(rd("T1 M6\nG0 X0 Y0 Z1\nT1 M6\nG0 X1\n").unwrap().warnings.is_empty());
        // each tool's moves, cut apart with the tools a caller names
        let two = rd("T1 M6\nG0 X0 Y0 Z1\nG1 X2 F100\nT2 M6\nG0 X1 Y1\n").unwrap();
        let spans: Vec<(Option<u32>, usize)> = two.tools.iter().map(|t| (t.number, t.first_move)).collect();
        assert_eq!(spans, [(Some(1), 0), (Some(2), 1)]);
        let parts = two.by_tool(&|n| Tool { diameter: f64::from(n.unwrap_or(9)), number: n.unwrap_or(0), flutes: 2 });
        let got: Vec<(f64, usize, [f64; 3])> =
            parts.iter().map(|(tp, lines)| (tp.tool.diameter, lines.len(), tp.start.to_array())).collect();
        assert_eq!(got, [(1.0, 1, [0.0, 0.0, 1.0]), (2.0, 1, [2.0, 0.0, 1.0])]);
        // work offsets set to zero (CAMotics' programs reset them so) move nothing
        let z = rd("G10 L2 P1 X0 Y0 Z0\nG10 L2 P2 X0\nG55\nG92.1\nG0 X1 Y2 Z3\nG0 X4\n").unwrap();
        assert_eq!(z.toolpath.moves.last().map(|m| m.to.to_array()), Some([4.0, 2.0, 3.0]));
        // G55 moved by Y-101.6 (CAMotics' botomata): absolute words from it; L20 from where it is
        let o =
            rd("G0 X0 Y0 Z5\nG10 L2 P2 Y-101.6\nG55 G0 X1 Y2\nG91 G0 X1\nG90 G54 G0 X0 Y0\nG10 L20 P1 X10\nG0 X11\n")
                .unwrap();
        let to: Vec<[f64; 3]> = o.toolpath.moves.iter().map(|m| m.to.to_array()).collect();
        assert_eq!(to, [[1.0, -99.6, 5.0], [2.0, -99.6, 5.0], [0.0, 0.0, 5.0], [1.0, 0.0, 5.0]]);
        assert!(o.warnings.iter().any(|w| w.contains("G55 offset Y-101.6")), "{:?}", o.warnings);
    }

    #[test]
    fn errors_name_the_line_and_column() {
        let cases: &[(&str, &str, &str)] = &[
            ("G0 X0 Y0 Z0\nG1 X1 F100\n  G7 X2", "line 3, column 3", "G7: this G-code is not read"),
            ("G0 X0 Y0 Z0\nG5.1 X1", "line 2, column 1", "G5.1"),
            ("G0 X1.2.3", "line 1, column 4", "garbled number X1.2.3"),
            ("G0 X1-2", "line 1, column 4", "garbled number"),
            ("G0 X Y1", "line 1, column 4", "X has no number"),
            ("G0 X0 Y0 Z0 F", "line 1, column 13", "F has no number"),
            ("G0 Xinf", "line 1, column 4", "X has no number"),
            ("G0 X-", "line 1, column 4", "X has no number"),
            ("G0 Y99999999999", "line 1, column 4", "beyond the largest number"),
            ("G0 X200000 Y0 Z0", "line 1, column 4", "within ±100000 mm"),
            ("G20 G0 X5000", "line 1, column 8", "within ±100000 mm"),
            ("G91 G0 X90000\nX90000", "line 2, column 1", "within ±100000 mm"),
            ("G0 X10 Y0 Z0\nG2 X0 Y10.5 I-10 J0 F100", "line 2, column 1", "differs from the radius to its start"),
            // 0.02 mm off a 10 mm radius: within LinuxCNC's 0.028 mm but more than 0.1 %
            ("G0 X10 Y0 Z0\nG2 X0 Y10.02 I-10 J0 F100", "line 2, column 1", "0.1 %"),
            ("G0 X0 Y0 Z0\nG2 X10 Y0 R4 F100", "line 2, column 11", "more than 2R"),
            ("G0 X0 Y0 Z0\nG2 X0 Y0 R5 F100", "line 2, column 10", "ends where it starts"),
            ("G0 X0 Y0 Z0\nG2 X1 Y0 I0 J0 F100", "line 2, column 1", "zero-radius"),
            ("G0 X0 Y0 Z0\nG2 X0.001 Y0 R0 F100", "line 2, column 14", "zero-radius"),
            ("G0 X0 Y0 Z0\nG2 X0 Y0 I90000 F100", "line 2, column 1", "the arc reaches (1.800000e5, 0"),
            ("G0 X0 Y0 Z0\nG3 X1 Y1 F100", "line 2, column 1", "neither I/J nor R"),
            ("G0 X0 Y0 Z0\nG2 X1 Y1 R1 I1 F100", "line 2, column 13", "both R and I/J"),
            ("G0 X0 Y0 Z0\nG3 X0 Y0 I1 P0.5 F100", "line 2, column 13", "whole number"),
            ("G0 X0 Y0 Z0\n  G18\nG2 X1 Z1 I1", "line 2, column 3", "only XY-plane arcs (G17) are read"),
            ("G19", "line 1, column 1", "only XY-plane arcs (G17) are read"),
            ("G0 X0 Y0 Z0\nG95 G1 X1 F0.1", "line 2, column 1", "per revolution"),
            ("G93", "line 1, column 1", "inverse time"),
            ("G0 X0 Y0 Z0\nG41 D1", "line 2, column 1", "cutter radius compensation"),
            ("G0 X0 Y0 Z0\nG92 X0", "line 2, column 1", "offsets set by the program"),
            ("G0 X0 Y0 Z0\nG10 L2 P7 X1", "line 2, column 1", "P1 to P6"),
            (
                "G0 X0 Y0 Z0\nG2 X0 Y0 I5 J0 P0.5 F100",
                "line 2, column 16",
                "P0.5: the turns of an arc are a whole number",
            ),
            (
                "G0 X0 Y0 Z5\nG81 X1 Y1 Z-1 R2 L0 F100",
                "line 2, column 18",
                "L0: the repeats of a cycle are a whole number",
            ),
            ("G10 L20 P1 X1", "line 1, column 12", "does not state"),
            ("G0 X0 Y0 Z0\nG10 L1 P1 Z1", "line 2, column 1", "offsets set by the program"),
            ("G91 G0 G43 Z-[#[2000+#4120]] H#4120", "line 1, column 14", "parameters and expressions"),
            ("G0 X0 Y0 Z0\nG53 G0 X0", "line 2, column 8", "G53 moves in X or Y"),
            ("G0 X0 Y0 Z0\nG1 X1 F0", "line 2, column 1", "F0"),
            ("G0 X0 Y0 Z0\nG1 X1", "line 2, column 1", "before any feed rate"),
            ("G0 X0 Y0 Z0\nG80 X1", "line 2, column 5", "no motion mode"),
            ("G0 X0 Y0 Z0 A1", "line 1, column 13", "the axis A is not read"),
            ("G0 X#1", "line 1, column 5", "parameters"),
            ("O100 sub", "line 1, column 1", "O-words"),
            ("G0 X0 (open", "line 1, column 7", "not closed"),
            ("G0 X0 X1", "line 1, column 7", "X is given twice"),
            ("G0 G1 X1", "line 1, column 4", "same modal group"),
            ("G0 X0 Y0 Z0\nM98 P100", "line 2, column 1", "subprograms"),
            ("G0 X0 Y0 Z5\nG81 X1 Y1 R2 F100", "line 2, column 1", "needs R (its retract plane) and Z"),
            ("G0 X0 Y0 Z5\nG81 X1 Y1 R2 Z3 F100", "line 2, column 1", "above its retract plane"),
            ("G0 X0 Y0 Z0 é", "line 1, column 13", "unexpected character"),
        ];
        for (text, at, why) in cases {
            let (place, reason) = fails(text);
            assert!(place == *at && reason.contains(why), "{text:?}: {place}: {reason} (wanted {at}: …{why}…)");
        }
        // no motion
        for text in ["", "(nothing)\nM2\n", "%\nG21 G90\n%\nG0 X1\n", "G0 X0 Y0 Z0\nG0 X0 Y0 Z0\n"] {
            assert_eq!(fails(text).0, "file", "{text:?}");
        }
        // turns that would make millions of moves
        let many = format!("G0 X5 Y0 Z0 F100\n{}", "G2 X5 Y0 I-5 P10000\n".repeat(60));
        let (place, reason) = fails(&many);
        assert!(place == "line 52, column 1" && reason.contains("more than 1000000 moves"), "{place}: {reason}");
        let e = rd("G0 X1 Y2\nG3 X1.2.3").unwrap_err().to_string();
        assert!(e.starts_with("t.ngc: line 2, column 4: garbled number"), "{e}");
    }

    #[test]
    fn random_text_never_panics() {
        // xorshift64*: a fixed sequence, no dependency
        let mut s: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut next = move || {
            s ^= s >> 12;
            s ^= s << 25;
            s ^= s >> 27;
            s.wrapping_mul(0x2545_F491_4F6C_DD1D)
        };
        let pieces = [
            "G0", "G1", "G2", "G3", "G17", "G18", "G20", "G21", "G28", "G53", "G80", "G81", "G83", "G90", "G91",
            "G90.1", "G91.1", "G98", "G99", "X", "Y", "Z", "I", "J", "R", "P", "F", "L", "Q", "M6", "M2", "T", "-",
            ".", "0", "1", "5", "9", "10", "-3.5", "1e5", "99999", "100000", "0.0001", " ", " ", "\n", "\n", "(", ")",
            ";", "%", "/", "#", "[", "é", "\t", "\r",
        ];
        let mut ok = 0;
        for round in 0..20_000 {
            let n = (next() % 40) as usize;
            let text: String = if round % 4 == 0 {
                let bytes: Vec<u8> = (0..n * 3).map(|_| (next() % 256) as u8).collect();
                String::from_utf8_lossy(&bytes).into_owned()
            } else if round % 4 == 1 {
                // lines of words that mostly make sense
                let mut t = String::from("G0 X0 Y0 Z5 F100\n");
                for _ in 0..n / 4 + 1 {
                    let g = ["G0", "G1", "G2", "G3", "G91", "G90", "G81", "G20", "G21", "G98", "G99"];
                    t += g[(next() % g.len() as u64) as usize];
                    for l in ["X", "Y", "Z", "I", "J", "R", "P", "L"] {
                        if next() % 3 == 0 {
                            let v = (next() % 2001) as f64 / 100.0 - 10.0;
                            t += &format!(" {l}{}", if l == "P" || l == "L" { v.abs().ceil() } else { v });
                        }
                    }
                    t += "\n";
                }
                t
            } else {
                let mut t = String::from("G0 X0 Y0 Z5 F100\n");
                for _ in 0..n {
                    t += pieces[(next() % pieces.len() as u64) as usize];
                }
                t
            };
            if let Ok(p) = rd(&text) {
                ok += 1;
                assert_eq!(p.lines.len(), p.toolpath.moves.len());
                assert!(p.toolpath.moves.iter().all(|m| m.to.is_finite() && m.feed.is_finite()));
                assert!(p.toolpath.segments().all(|(f, m)| match m.motion {
                    Motion::Line => true,
                    Motion::Arc { center, ccw } => ArcGeom::new(f, m.to, center, ccw).sweep.abs() <= PI + 1e-6,
                }));
            }
        }
        assert!(ok > 500, "only {ok} of the random programs read");
    }
}
