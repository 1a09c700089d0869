//! Toolpaths: a plain list of moves in absolute millimetres — rapid, linear feed, circular or
//! helical arc — each tagged with what it is for. Everything downstream (posts, simulator,
//! report, pictures) reads only this.

use crate::geom::{DVec2, DVec3};
use crate::model::Tool;

/// What a move is for (reports, pictures and G-code comments use it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MoveKind {
    /// G0 travel.
    Rapid,
    /// Cutting.
    Cut,
    /// Descending into material by helix or ramp.
    Entry,
    /// Straight vertical entry into material (avoided; reported).
    Plunge,
    /// Feed move at depth between cuts through cleared space.
    Link,
    /// Feed descent through air or cleared space.
    Descend,
    /// Finishing contour.
    Finish,
}

impl MoveKind {
    /// The kinds' names, in the order of their numbers ([`MoveKind::code`]).
    pub const NAMES: [&'static str; 7] = ["rapid", "cut", "entry", "plunge", "link", "descend", "finish"];

    /// The kind's number, its index in [`MoveKind::NAMES`]: the viewer's packed moves and the
    /// Python package's arrays hold it.
    pub fn code(self) -> u8 {
        match self {
            MoveKind::Rapid => 0,
            MoveKind::Cut => 1,
            MoveKind::Entry => 2,
            MoveKind::Plunge => 3,
            MoveKind::Link => 4,
            MoveKind::Descend => 5,
            MoveKind::Finish => 6,
        }
    }
}

/// The shape of a move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Motion {
    /// Straight line (G0 or G1).
    Line,
    /// Circular arc in XY around `center`, helical when z changes (G2 / G3). Sweeps are at most
    /// one half turn per move, so the arc is never ambiguous.
    Arc {
        /// Arc centre.
        center: DVec2,
        /// Counter-clockwise (G3) when true.
        ccw: bool,
    },
}

/// One move from the previous position to `to`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Move {
    /// Purpose.
    pub kind: MoveKind,
    /// Shape.
    pub motion: Motion,
    /// End point.
    pub to: DVec3,
    /// Feed rate in mm/min (ignored for rapids).
    pub feed: f64,
}

impl Move {
    /// True for G0.
    pub fn is_rapid(&self) -> bool {
        self.kind == MoveKind::Rapid
    }
}

/// Geometry of an arc move from `from`: radius, start angle, signed sweep.
#[derive(Debug, Clone, Copy)]
pub struct ArcGeom {
    /// Centre.
    pub center: DVec2,
    /// Radius (at the start).
    pub radius: f64,
    /// Start angle, radians.
    pub a0: f64,
    /// Signed sweep (positive counter-clockwise), radians, in (-2π, 2π).
    pub sweep: f64,
    /// Start z.
    pub z0: f64,
    /// End z.
    pub z1: f64,
}

impl ArcGeom {
    /// The arc of a move from `from` to `to` around `center`.
    pub fn new(from: DVec3, to: DVec3, center: DVec2, ccw: bool) -> ArcGeom {
        let a = from.truncate() - center;
        let b = to.truncate() - center;
        let a0 = a.y.atan2(a.x);
        let a1 = b.y.atan2(b.x);
        let mut sweep = a1 - a0;
        let tau = std::f64::consts::TAU;
        if ccw {
            while sweep <= 1e-12 {
                sweep += tau;
            }
            while sweep > tau {
                sweep -= tau;
            }
        } else {
            while sweep >= -1e-12 {
                sweep -= tau;
            }
            while sweep < -tau {
                sweep += tau;
            }
        }
        ArcGeom { center, radius: a.length(), a0, sweep, z0: from.z, z1: to.z }
    }
    /// Point at parameter `t` in [0, 1].
    pub fn at(&self, t: f64) -> DVec3 {
        let a = self.a0 + self.sweep * t;
        DVec3::new(
            self.center.x + self.radius * a.cos(),
            self.center.y + self.radius * a.sin(),
            self.z0 + (self.z1 - self.z0) * t,
        )
    }
    /// Unit tangent direction in XY at `t`.
    pub fn tangent(&self, t: f64) -> DVec2 {
        let a = self.a0 + self.sweep * t;
        let s = self.sweep.signum();
        DVec2::new(-a.sin() * s, a.cos() * s)
    }
    /// XY length.
    pub fn xy_length(&self) -> f64 {
        self.radius * self.sweep.abs()
    }
}

/// Length of a move from `from` (3D, helices included).
pub fn move_length(from: DVec3, m: &Move) -> f64 {
    match m.motion {
        Motion::Line => (m.to - from).length(),
        Motion::Arc { center, ccw } => {
            let g = ArcGeom::new(from, m.to, center, ccw);
            (g.xy_length().powi(2) + (m.to.z - from.z).powi(2)).sqrt()
        }
    }
}

/// XY length of a move from `from`.
pub fn move_xy_length(from: DVec3, m: &Move) -> f64 {
    match m.motion {
        Motion::Line => (m.to - from).truncate().length(),
        Motion::Arc { center, ccw } => ArcGeom::new(from, m.to, center, ccw).xy_length(),
    }
}

/// A section label shown as a comment before move `at`.
#[derive(Debug, Clone, PartialEq)]
pub struct Note {
    /// Index of the move the note precedes.
    pub at: usize,
    /// The text (plain ASCII, no parentheses).
    pub text: String,
}

/// A program for one tool.
#[derive(Debug, Clone)]
pub struct Toolpath {
    /// The tool.
    pub tool: Tool,
    /// Where the tool is before the first move (above the first point at clearance height).
    pub start: DVec3,
    /// Safe height for travel above everything, mm.
    pub clearance_z: f64,
    /// The moves.
    pub moves: Vec<Move>,
    /// Section comments.
    pub notes: Vec<Note>,
}

/// Totals of a toolpath.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Totals {
    /// Length of feed moves, mm.
    pub cut_length_mm: f64,
    /// Length of rapid moves, mm.
    pub rapid_length_mm: f64,
    /// Time estimate: feed lengths over their feeds plus rapid length over the rapid rate, min.
    pub time_min: f64,
    /// Number of plunge moves.
    pub plunges: usize,
    /// Number of helix or ramp entries.
    pub entries: usize,
    /// Number of moves whose z rises.
    pub retracts: usize,
}

/// Arcs of a larger radius, mm, are written as lines by [`Toolpath::quantize`] where they are
/// straight to within half the coordinates' step.
pub const STRAIGHT_ARC_RADIUS: f64 = 10_000.0;

impl Toolpath {
    /// An empty program for `tool` starting at `start`.
    pub fn new(tool: Tool, start: DVec3, clearance_z: f64) -> Self {
        Self { tool, start, clearance_z, moves: Vec::new(), notes: Vec::new() }
    }

    /// Position after the last move.
    pub fn end(&self) -> DVec3 {
        self.moves.last().map_or(self.start, |m| m.to)
    }

    /// Adds a note before the next move.
    pub fn note(&mut self, text: impl Into<String>) {
        self.notes.push(Note { at: self.moves.len(), text: text.into() });
    }

    /// Appends a move, dropping ones of zero length.
    pub fn push(&mut self, kind: MoveKind, motion: Motion, to: DVec3, feed: f64) {
        if (to - self.end()).length() < 1e-9 {
            return;
        }
        self.moves.push(Move { kind, motion, to, feed });
    }

    /// Appends a rapid.
    pub fn rapid(&mut self, to: DVec3) {
        self.push(MoveKind::Rapid, Motion::Line, to, 0.0);
    }

    /// Appends a straight feed move.
    pub fn line(&mut self, kind: MoveKind, to: DVec3, feed: f64) {
        self.push(kind, Motion::Line, to, feed);
    }

    /// Appends an arc (callers keep sweeps at or below a half turn).
    pub fn arc(&mut self, kind: MoveKind, to: DVec3, center: DVec2, ccw: bool, feed: f64) {
        self.push(kind, Motion::Arc { center, ccw }, to, feed);
    }

    /// The turns between consecutive cutting moves, in degrees, with the index of the move
    /// after each turn: the angle between the XY direction in which one feed move ends and the
    /// next begins. Rapids break the chain; moves without XY motion (straight descents) are
    /// stepped over. A tangent-continuous (C1) program reads 0 everywhere.
    pub fn cutting_turns(&self) -> Vec<(usize, f64)> {
        self.cutting_turns_at(0.0)
    }

    /// [`Self::cutting_turns`] as the path looks at the length scale `scale` (mm), as a
    /// controller's look-ahead or a simulator's grid sees it: a run of moves each no longer
    /// than `scale` (in XY) counts as the chords from its start to the first point more than
    /// `scale` away, and so on (a rest of the run shorter than that adds its turn to the next
    /// junction). A run of tiny arcs round a tight bend reads as a polygon, its turns those of
    /// the chords; a C1 program of moves longer than `scale` still reads 0 everywhere.
    pub fn cutting_turns_at(&self, scale: f64) -> Vec<(usize, f64)> {
        let mut out = Vec::new();
        let mut last: Option<DVec2> = None;
        // the start of the run of short moves not yet taken into a chord
        let mut run: Option<DVec2> = None;
        for (i, (from, m)) in self.segments().enumerate() {
            if m.is_rapid() {
                last = None;
                run = None;
                continue;
            }
            let (a, b) = (from.truncate(), m.to.truncate());
            let len = move_xy_length(from, m);
            if len < 1e-9 {
                continue;
            }
            let (t0, t1) = if len > scale {
                run = None;
                match m.motion {
                    Motion::Line => ((b - a).normalize(), (b - a).normalize()),
                    Motion::Arc { center, ccw } => {
                        let g = ArcGeom::new(from, m.to, center, ccw);
                        (g.tangent(0.0), g.tangent(1.0))
                    }
                }
            } else {
                let start = *run.get_or_insert(a);
                let chord = b - start;
                if chord.length() <= scale {
                    continue;
                }
                run = None;
                (chord.normalize(), chord.normalize())
            };
            if let Some(prev) = last {
                out.push((i, prev.dot(t0).clamp(-1.0, 1.0).acos().to_degrees()));
            }
            last = Some(t1);
        }
        out
    }

    /// Iterates `(from, move)`.
    pub fn segments(&self) -> impl Iterator<Item = (DVec3, &Move)> {
        let mut from = self.start;
        self.moves.iter().map(move |m| {
            let f = from;
            from = m.to;
            (f, m)
        })
    }

    /// Rounds every end point to a grid of `step` mm (what the post will print) and moves each
    /// arc centre onto the perpendicular bisector of its rounded chord, rounded to `center_step`,
    /// so that the start and end radii of every printed arc agree to about `center_step`
    /// (controllers reject arcs whose radii differ, and simulators misread them). An arc of more
    /// than [`STRAIGHT_ARC_RADIUS`] whose middle lies less than half a `step` off its chord is a
    /// line: its centre would be a word of many digits for a curve no one can print. After this
    /// the simulation replays exactly the program that is written.
    pub fn quantize(&mut self, step: f64, center_step: f64) {
        let q = |v: f64, s: f64| {
            let r = (v / s).round() * s;
            if r == 0.0 { 0.0 } else { r }
        };
        let q3 = |p: DVec3| DVec3::new(q(p.x, step), q(p.y, step), q(p.z, step));
        self.start = q3(self.start);
        let mut from = self.start;
        for m in &mut self.moves {
            let to = q3(m.to);
            if let Motion::Arc { center, ccw } = m.motion {
                let a = from.truncate();
                let b = to.truncate();
                let mid = (a + b) / 2.0;
                let chord = b - a;
                let c = if chord.length_squared() > 1e-18 {
                    let n = chord.perp().normalize();
                    mid + n * (center - mid).dot(n)
                } else {
                    center
                };
                let c = DVec2::new(q(c.x - a.x, center_step) + a.x, q(c.y - a.y, center_step) + a.y);
                let r = (a - c).length();
                let half = chord.length() / 2.0;
                let sagitta = r - (r * r - half * half).max(0.0).sqrt();
                m.motion = if r > STRAIGHT_ARC_RADIUS && sagitta < step / 2.0 && chord.length_squared() > 1e-18 {
                    Motion::Line
                } else {
                    Motion::Arc { center: c, ccw }
                };
            }
            m.to = to;
            from = to;
        }
    }

    /// Lengths, time and counts.
    pub fn totals(&self, rapid_rate: f64) -> Totals {
        let mut t = Totals::default();
        let mut in_entry = false;
        for (from, m) in self.segments() {
            let l = move_length(from, m);
            if m.is_rapid() {
                t.rapid_length_mm += l;
                t.time_min += l / rapid_rate;
            } else {
                t.cut_length_mm += l;
                t.time_min += l / m.feed.max(1e-9);
            }
            if m.kind == MoveKind::Plunge {
                t.plunges += 1;
            }
            if m.kind == MoveKind::Entry && !in_entry {
                t.entries += 1;
            }
            in_entry = m.kind == MoveKind::Entry;
            if m.to.z > from.z + 1e-9 {
                t.retracts += 1;
            }
        }
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_kinds_code_indexes_its_name() {
        use MoveKind::*;
        let all = [Rapid, Cut, Entry, Plunge, Link, Descend, Finish];
        for k in all {
            let serde_name = serde_json::to_value(k).unwrap();
            assert_eq!(serde_name, MoveKind::NAMES[usize::from(k.code())], "{k:?}");
        }
        assert_eq!(all.len(), MoveKind::NAMES.len());
    }

    #[test]
    fn arc_geometry_and_lengths() {
        let from = DVec3::new(10.0, 0.0, 0.0);
        let to = DVec3::new(-10.0, 0.0, -1.0);
        let g = ArcGeom::new(from, to, DVec2::ZERO, true);
        assert!((g.sweep - std::f64::consts::PI).abs() < 1e-12);
        assert!((g.at(0.5) - DVec3::new(0.0, 10.0, -0.5)).length() < 1e-12);
        let g2 = ArcGeom::new(from, to, DVec2::ZERO, false);
        assert!((g2.sweep + std::f64::consts::PI).abs() < 1e-12);
        assert!((g2.at(0.5).y + 10.0).abs() < 1e-12);
        let m = Move { kind: MoveKind::Entry, motion: Motion::Arc { center: DVec2::ZERO, ccw: true }, to, feed: 500.0 };
        let l = move_length(from, &m);
        assert!((l - ((10.0 * std::f64::consts::PI).powi(2) + 1.0).sqrt()).abs() < 1e-9);
        let mut tp = Toolpath::new(Tool::flat(6.0), DVec3::new(10.0, 0.0, 5.0), 5.0);
        tp.line(MoveKind::Descend, from, 500.0);
        tp.arc(MoveKind::Entry, to, DVec2::ZERO, true, 500.0);
        tp.rapid(DVec3::new(-10.0, 0.0, 5.0));
        let t = tp.totals(5000.0);
        assert!((t.cut_length_mm - (5.0 + l)).abs() < 1e-9);
        assert!((t.rapid_length_mm - 6.0).abs() < 1e-9);
        assert_eq!(t.entries, 1);
        assert_eq!(t.retracts, 1);
    }

    /// A line along x, a quarter turn to the left round a centre at `(5, r)` made of `k` equal
    /// arcs, and a line up along y.
    fn bend(r: f64, k: usize) -> Toolpath {
        let mut tp = Toolpath::new(Tool::flat(6.0), DVec3::new(0.0, 0.0, 0.0), 5.0);
        tp.line(MoveKind::Cut, DVec3::new(5.0, 0.0, 0.0), 500.0);
        let c = DVec2::new(5.0, r);
        for i in 1..=k {
            let a = -std::f64::consts::FRAC_PI_2 + std::f64::consts::FRAC_PI_2 * i as f64 / k as f64;
            tp.arc(MoveKind::Cut, (c + DVec2::new(a.cos(), a.sin()) * r).extend(0.0), c, true, 500.0);
        }
        tp.line(MoveKind::Cut, DVec3::new(5.0 + r, r + 5.0, 0.0), 500.0);
        tp
    }

    #[test]
    fn runs_of_tiny_arcs_read_as_chords_at_a_coarser_scale() {
        let worst = |t: Vec<(usize, f64)>| t.iter().map(|x| x.1).fold(0.0, f64::max);
        // nine arcs of 10° on a radius of 0.15 mm (0.026 mm each): C1, yet a polygon at 0.1 mm
        let tiny = bend(0.15, 9);
        assert!(worst(tiny.cutting_turns()) < 1e-6);
        assert_eq!(worst(tiny.cutting_turns_at(0.0)), worst(tiny.cutting_turns()));
        let coarse = tiny.cutting_turns_at(0.1);
        assert!(worst(coarse.clone()) >= 29.0, "{coarse:?}");
        // the same bend as one arc of 0.24 mm is smooth at that scale
        let one = bend(0.15, 1);
        assert!(worst(one.cutting_turns_at(0.1)) < 1e-6, "{:?}", one.cutting_turns_at(0.1));
        // a rapid breaks the chain (the move along -x after it turns from nothing), and the
        // descent without XY motion is stepped over
        let mut broken = bend(0.15, 1);
        broken.rapid(DVec3::new(0.0, 0.0, 5.0));
        broken.line(MoveKind::Cut, DVec3::new(0.0, 0.0, 0.0), 500.0);
        broken.line(MoveKind::Cut, DVec3::new(-3.0, 0.0, 0.0), 500.0);
        let t = broken.cutting_turns_at(0.1);
        assert!(t.len() == 2 && worst(t.clone()) < 1e-6, "{t:?}");
    }
}
