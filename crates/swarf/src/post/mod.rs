//! Posts: toolpaths into G-code for a controller dialect.
//!
//! One writer, one small [`Dialect`] per controller: the dialects differ in the start block,
//! the tool change and what they accept (GRBL has no tool changer and no `G43`/`G64`). Output is
//! metric and absolute (`G21 G90`), arcs in the XY plane (`G17`) with incremental centres
//! (`I J`, the default on both), helical arcs carry `Z`. Numbers are fixed-point with trailing
//! zeros trimmed (`X12.5`, `Y-3`), words that did not change are left out, feeds are written
//! when they change, and a comment says what each section is. The same toolpath always gives
//! the same bytes.

pub mod five;
pub mod grbl;
pub mod linuxcnc;

use crate::geom::DVec3;
use crate::toolpath::{Motion, MoveKind, Toolpath};
use std::fmt::Write;

/// A controller dialect.
pub trait Dialect {
    /// Name for comments and the command line.
    fn name(&self) -> &'static str;
    /// Lines after the header comments: units, modes, cancels.
    fn start_block(&self) -> Vec<String>;
    /// Tool change and length offset for tool `t` (may be empty).
    fn tool_change(&self, t: u32, diameter: f64) -> Vec<String>;
    /// Program end.
    fn end_block(&self) -> Vec<String>;
}

/// Available posts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Post {
    /// LinuxCNC (rs274ngc).
    LinuxCnc,
    /// GRBL 1.1.
    Grbl,
}

impl Post {
    /// LinuxCNC.
    pub const DEFAULT: Post = Post::LinuxCnc;
    /// The names of the posts, the default first.
    pub const NAMES: [&'static str; 2] = ["linuxcnc", "grbl"];

    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Post::LinuxCnc => "linuxcnc",
            Post::Grbl => "grbl",
        }
    }

    /// Parses a post name.
    pub fn parse(s: &str) -> Option<Post> {
        match s.to_ascii_lowercase().as_str() {
            "linuxcnc" | "emc" | "emc2" => Some(Post::LinuxCnc),
            "grbl" => Some(Post::Grbl),
            _ => None,
        }
    }

    fn dialect(self) -> Box<dyn Dialect> {
        match self {
            Post::LinuxCnc => Box::new(linuxcnc::LinuxCnc),
            Post::Grbl => Box::new(grbl::Grbl),
        }
    }
}

impl Default for Post {
    fn default() -> Self {
        Post::DEFAULT
    }
}

/// What the header says about the job.
#[derive(Debug, Clone, Default)]
pub struct Header {
    /// Free lines of description (plain ASCII; parentheses are removed).
    pub lines: Vec<String>,
    /// Spindle speed, rpm.
    pub spindle_rpm: f64,
}

/// Formats a number with at most `dec` decimals, trailing zeros and `-0` removed.
pub fn num(v: f64, dec: usize) -> String {
    let mut s = format!("{v:.dec$}");
    if s.contains('.') {
        while s.ends_with('0') {
            s.pop();
        }
        if s.ends_with('.') {
            s.pop();
        }
    }
    if s == "-0" {
        s = "0".into();
    }
    s
}

fn round_to(v: f64, step: f64) -> f64 {
    (v / step).round() * step
}

fn comment(text: &str) -> String {
    let clean: String = text
        .chars()
        .map(|c| if c == '(' || c == ')' || !c.is_ascii() || c.is_ascii_control() { ' ' } else { c })
        .collect();
    format!("({})", clean.trim())
}

/// Decimals of coordinates (X, Y, Z) in the output.
pub const COORD_STEP: f64 = 0.001;
/// Decimals of arc centre offsets (I, J): finer than coordinates so that the start and end
/// radii of an arc agree (see [`crate::toolpath::Toolpath::quantize`]).
pub const CENTER_STEP: f64 = 0.00001;

/// The largest magnitude of any word a post writes (coordinates and centres in mm, feeds in
/// mm/min, the spindle speed in rpm): six digits before the point, what the controllers swarf
/// posts for read. The limits a job is validated against ([`crate::limits`]) keep every
/// program well inside it; this is the posts' own last check.
pub const MAX_WORD: f64 = 999_999.0;

/// Whether a post can write `v`: finite and within [`MAX_WORD`].
pub(crate) fn writable(v: f64) -> bool {
    v.is_finite() && v.abs() <= MAX_WORD
}

/// Refuses a toolpath with a number no controller reads as one: not finite, or larger than
/// [`MAX_WORD`].
pub fn check_writable(tp: &Toolpath, header: &Header) -> crate::Result<()> {
    let bad = |what: String, v: f64| {
        Err(crate::Error::job(
            "G-code",
            format!("{what} is {v}: a post writes numbers within ±{MAX_WORD} only; nothing written"),
        ))
    };
    for (what, v) in [
        ("the spindle speed", header.spindle_rpm),
        ("the tool diameter", tp.tool.diameter),
        ("the clearance height", tp.clearance_z),
        ("the start's X", tp.start.x),
        ("the start's Y", tp.start.y),
        ("the start's Z", tp.start.z),
    ] {
        if !writable(v) {
            return bad(what.into(), v);
        }
    }
    for (i, m) in tp.moves.iter().enumerate() {
        let mut words = vec![('X', m.to.x), ('Y', m.to.y), ('Z', m.to.z)];
        if !m.is_rapid() {
            words.push(('F', m.feed));
        }
        if let Motion::Arc { center, .. } = m.motion {
            words.extend([('I', center.x), ('J', center.y)]);
        }
        if let Some((w, v)) = words.into_iter().find(|&(_, v)| !writable(v)) {
            return bad(format!("move {}'s {w}", i + 1), v);
        }
    }
    Ok(())
}

/// Writes the program (call [`crate::toolpath::Toolpath::quantize`] with [`COORD_STEP`] and
/// [`CENTER_STEP`] first so that what is simulated is what is written), after
/// [`check_writable`].
pub fn write(tp: &Toolpath, post: Post, header: &Header) -> crate::Result<String> {
    check_writable(tp, header)?;
    let d = post.dialect();
    let mut out = String::new();
    let mut line = |s: &str| {
        out.push_str(s);
        out.push('\n');
    };
    line(&comment(&format!("swarf {} - post {}", env!("CARGO_PKG_VERSION"), d.name())));
    for h in &header.lines {
        line(&comment(h));
    }
    for s in d.start_block() {
        line(&s);
    }
    line(&comment(&format!("tool T{} flat end mill D{}", tp.tool.number, num(tp.tool.diameter, 3))));
    for s in d.tool_change(tp.tool.number, tp.tool.diameter) {
        line(&s);
    }
    line(&format!("S{} M3", num(header.spindle_rpm.max(0.0), 0)));
    let p = tp.start;
    line(&format!("G0 Z{}", num(tp.clearance_z.max(p.z), 3)));
    line(&format!("G0 X{} Y{}", num(p.x, 3), num(p.y, 3)));
    if p.z < tp.clearance_z - 1e-9 {
        line(&format!("G0 Z{}", num(p.z, 3)));
    }
    let mut pos = p;
    let mut last_feed = f64::NAN;
    let mut last_kind: Option<MoveKind> = None;
    let mut notes = tp.notes.iter().peekable();
    for (i, m) in tp.moves.iter().enumerate() {
        while let Some(n) = notes.peek() {
            if n.at <= i {
                line(&comment(&n.text));
                notes.next();
            } else {
                break;
            }
        }
        if m.kind != MoveKind::Rapid && last_kind != Some(m.kind) && matches!(m.kind, MoveKind::Plunge) {
            line(&comment("plunge"));
        }
        last_kind = Some(m.kind);
        let mut w = String::new();
        match m.motion {
            Motion::Line => {
                w.push_str(if m.is_rapid() { "G0" } else { "G1" });
                axes(&mut w, pos, m.to, false);
            }
            Motion::Arc { center, ccw } => {
                w.push_str(if ccw { "G3" } else { "G2" });
                axes(&mut w, pos, m.to, true);
                // the controller starts the arc where the previous line ended, as written
                let (px, py) = (round_to(pos.x, COORD_STEP), round_to(pos.y, COORD_STEP));
                let _ = write!(w, " I{} J{}", num(center.x - px, 5), num(center.y - py, 5));
            }
        }
        if !m.is_rapid() {
            let f = (m.feed * 10.0).round() / 10.0;
            if f != last_feed {
                let _ = write!(w, " F{}", num(f, 1));
                last_feed = f;
            }
        }
        line(&w);
        pos = m.to;
    }
    line("M5");
    for s in d.end_block() {
        line(&s);
    }
    Ok(out)
}

fn axes(w: &mut String, from: DVec3, to: DVec3, arc: bool) {
    let same = |a: f64, b: f64| num(a, 3) == num(b, 3);
    if arc || !same(from.x, to.x) {
        let _ = write!(w, " X{}", num(to.x, 3));
    }
    if arc || !same(from.y, to.y) {
        let _ = write!(w, " Y{}", num(to.y, 3));
    }
    if !same(from.z, to.z) {
        let _ = write!(w, " Z{}", num(to.z, 3));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_tidy() {
        assert_eq!(num(12.5, 3), "12.5");
        assert_eq!(num(-0.0001, 3), "0");
        assert_eq!(num(3.0, 3), "3");
        assert_eq!(num(-2.12345, 3), "-2.123");
        assert_eq!(num(1000.0, 1), "1000");
    }

    #[test]
    fn a_number_no_controller_reads_is_refused_not_written() {
        use crate::toolpath::{Move, MoveKind};
        let header = Header { lines: Vec::new(), spindle_rpm: 10000.0 };
        let mut tp = Toolpath::new(crate::model::Tool::flat(6.0), DVec3::new(0.0, 0.0, 5.0), 5.0);
        let cut = |to: DVec3, feed: f64| Move { kind: MoveKind::Cut, motion: Motion::Line, to, feed };
        tp.moves.push(cut(DVec3::new(10.0, 0.0, 0.0), 1000.0));
        assert!(write(&tp, Post::LinuxCnc, &header).is_ok());
        for (to, feed, word) in [
            (DVec3::new(10.0, 0.0, f64::INFINITY), 1000.0, "Z is inf"),
            (DVec3::new(1e7, 0.0, 0.0), 1000.0, "X is 10000000"),
            (DVec3::new(10.0, 0.0, 0.0), 1e300, "F is 1"),
        ] {
            tp.moves[0] = cut(to, feed);
            let e = write(&tp, Post::Grbl, &header).unwrap_err().to_string();
            assert!(e.contains(&format!("move 1's {word}")), "{e}");
        }
        tp.moves[0] = cut(DVec3::new(10.0, 0.0, 0.0), 1000.0);
        let huge_s = Header { spindle_rpm: 1e300, ..header };
        assert!(write(&tp, Post::LinuxCnc, &huge_s).unwrap_err().to_string().contains("spindle speed"));
    }
}
