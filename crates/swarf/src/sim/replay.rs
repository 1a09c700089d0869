//! The replay of a toolpath, shared by the simulation engines: it walks the moves, tracks the
//! entry bores, samples engagement along cutting moves and asks the engine for what depends on
//! its material model (engagement, collisions, plunges, gouges, the cut itself, the removed
//! volume). Both [`super::raster::RasterSim`] and [`super::sdf::SdfSim`] replay through it, so
//! their samples stand at the same places and carry the same kinds, bores and lengths.

use super::sweep::Path;
use crate::geom::{DVec2, DVec3};
use crate::toolpath::{MoveKind, Toolpath, move_length};

/// What kind of motion an engagement sample was taken on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SampleKind {
    /// Horizontal cutting.
    Lateral,
    /// Descending (ramp, helix).
    Descending,
    /// A plunge (360°).
    Plunge,
}

/// One engagement sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Cutting length from the start of the program to this sample, mm.
    pub s: f64,
    /// Tool position.
    pub at: DVec3,
    /// Exact engagement, degrees.
    pub tea: f32,
    /// Engagement by circumference pixels (paper 1 eq. 4), degrees.
    pub tea_pixel: f32,
    /// Motion kind.
    pub kind: SampleKind,
    /// Inside an entry bore (the entry and the first turn at its bottom).
    pub bore: bool,
    /// Length of cutting this sample stands for, mm.
    pub len: f32,
    /// Feed of the move, mm/min.
    pub feed: f32,
    /// Index of the move.
    pub mi: u32,
}

/// A located problem (gouge, collision, plunge).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Event {
    /// Index of the move in the toolpath.
    pub move_index: usize,
    /// Where (end of the move for plunges, the worst point otherwise).
    pub at: [f64; 3],
    /// How deep into the part or the material, mm.
    pub depth: f64,
}

/// Everything a replay found.
#[derive(Debug, Clone, Default)]
pub struct Replay {
    /// Engagement samples along cutting moves.
    pub samples: Vec<Sample>,
    /// Moves that gouge.
    pub gouges: Vec<Event>,
    /// Rapid moves through uncut material.
    pub rapid_collisions: Vec<Event>,
    /// Plunges into material.
    pub plunges: Vec<Event>,
    /// Volume removed, mm³.
    pub removed_volume: f64,
    /// Centres of the cells of rest material after the program (filled by the pipeline).
    pub rest_cells: Vec<DVec2>,
    /// Cell size of the simulation, mm.
    pub res: f64,
    /// A 3D job's stock after the program seen from above, for its picture (filled by the
    /// pipeline).
    pub top_view: Option<TopView>,
}

/// The stock after a 3D job's program seen from above, in square blocks of the simulation's
/// cells (row-major from the bottom row): each block's mean height and its thickest rest, the
/// terraces z-level roughing leaves by design apart from the rest beyond them (see
/// [`Rest::terrace_mm2`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TopView {
    /// Columns.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
    /// x of the left edge of column 0, mm.
    pub x0: f64,
    /// y of the bottom edge of row 0, mm.
    pub y0: f64,
    /// A block's side, mm.
    pub side: f64,
    /// Mean stock top per block, mm (NaN: no stock).
    pub height: Vec<f32>,
    /// Thickest terrace per block, mm (0: none).
    pub terrace: Vec<f32>,
    /// Thickest rest beyond the terraces per block, mm (0: none).
    pub beyond: Vec<f32>,
    /// The stock top, mm.
    pub top: f64,
    /// The floor, mm.
    pub bottom: f64,
}

/// Rest material: reachable material left standing.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Rest {
    /// Area of the reachable region where material stands more than `tol` above the floor, mm².
    pub area_mm2: f64,
    /// Its volume, mm³.
    pub volume_mm3: f64,
    /// Its largest thickness, mm.
    pub max_thickness_mm: f64,
    /// Area the tool can reach, mm².
    pub reachable_mm2: f64,
    /// Of `area_mm2`, the terraces z-level roughing leaves by design: where the stock stands
    /// no higher than the lowest level at or above the reachable height (3D jobs; 0 in 2.5D).
    pub terrace_mm2: f64,
    /// Their volume, mm³.
    pub terrace_volume_mm3: f64,
    /// The largest thickness of the rest beyond the terraces, mm.
    pub beyond_max_thickness_mm: f64,
}

/// What a material model answers during a replay.
pub(crate) trait Engine {
    /// Tool radius, mm.
    fn radius(&self) -> f64;
    /// The model's cell size or sample spacing, mm (the slack of the entry-bore test).
    fn spacing(&self) -> f64;
    /// Spacing of engagement samples along cutting moves, mm.
    fn sample_step(&self) -> f64;
    /// How deep a rapid along `path` runs into uncut material (0 when it does not), and where.
    fn rapid_depth(&self, path: &Path, to: DVec3) -> (f64, DVec3);
    /// Material within `R − tol` of a tool standing at `c` with its tip at `z`.
    fn material_under(&self, c: DVec2, z: f64) -> bool;
    /// Engagement (the engine's own measure, and the pixel measure or the same again), degrees,
    /// of the tool at `p` moving along `dir`; `cur` is the current move up to this sample,
    /// `before` up to the previous one. The engine's own measure may be left for later (`None`):
    /// [`Engine::deferred`] then gives it.
    fn engagement(&mut self, p: DVec3, dir: DVec2, cur: &Path, before: &Path) -> (Option<f64>, f64);
    /// The samples of a cutting move follow (the engine may group its deferred measures by
    /// move).
    fn begin_move(&mut self) {}
    /// The engagements left for later, in the order they were asked.
    fn deferred(&mut self) -> Vec<f64> {
        Vec::new()
    }
    /// Gouge depth of a move (0 when clean) and where.
    fn gouge_depth(&self, path: &Path) -> (f64, DVec3);
    /// [`Engine::gouge_depth`] of every move (an engine whose part never changes may measure
    /// them after the replay, and in parallel).
    fn gouge_depths(&self, paths: &[Path]) -> Vec<(f64, DVec3)> {
        paths.iter().map(|p| self.gouge_depth(p)).collect()
    }
    /// The replay has asked for everything: engagements left for later may start.
    fn flush(&mut self) {}
    /// Cuts a whole move into the material.
    fn cut_move(&mut self, path: &Path);
    /// Volume removed so far, mm³.
    fn removed_volume(&self) -> f64;
}

/// What a replay of a program in pieces carries from one piece to the next: the entry being
/// read, and the bore it made (the samples of the turn at its bottom are inside it).
#[derive(Debug, Clone, Default)]
pub(crate) struct Carry {
    /// The bore: centre, radius, and the cutting length still allowed inside it.
    bore: Option<(DVec2, f64, f64)>,
    /// The points of the entry so far.
    entry_pts: Vec<DVec3>,
    /// The centre of the entry's arcs, and their largest radius.
    entry_arc_center: Option<(DVec2, f64)>,
}

/// Replays `tp` on `m`: cuts it, samples engagement, finds gouges, collisions and plunges.
/// `progress` is called with the fraction done.
pub(crate) fn run<M: Engine>(m_: &mut M, tp: &Toolpath, progress: &mut dyn FnMut(f64)) -> Replay {
    run_carrying(m_, tp, progress, &mut Carry::default())
}

/// [`run`] on a piece of a program, `carry` from the piece before it (and for the next).
pub(crate) fn run_carrying<M: Engine>(
    m_: &mut M,
    tp: &Toolpath,
    progress: &mut dyn FnMut(f64),
    carry: &mut Carry,
) -> Replay {
    run_segments(m_, tp.segments().map(|(from, m)| (from, *m)), tp.moves.len(), progress, carry)
}

/// [`run_carrying`] on the moves `segments` gives (each with where it starts), as they come:
/// about `nmoves` of them (for `progress`).
pub(crate) fn run_segments<M: Engine>(
    m_: &mut M,
    segments: impl Iterator<Item = (DVec3, crate::toolpath::Move)>,
    nmoves: usize,
    progress: &mut dyn FnMut(f64),
    carry: &mut Carry,
) -> Replay {
    let Carry { bore, entry_pts, entry_arc_center } = carry;
    let mut out = Replay::default();
    let mut cum = 0.0;
    let nmoves = nmoves.max(1);
    let r = m_.radius();
    let step = m_.sample_step();
    let slack = m_.spacing().max(0.05 * r);
    // samples whose engagement the engine measures after the replay
    let mut later: Vec<usize> = Vec::new();
    // every move, for the gouge test after the replay (the part does not change)
    let mut paths: Vec<Path> = Vec::with_capacity(nmoves);
    for (mi, (from, m)) in segments.enumerate() {
        if mi % 256 == 0 {
            progress((mi as f64 / nmoves as f64).min(1.0));
        }
        let m = &m;
        let path = Path::of(from, m);
        let len3 = move_length(from, m);
        if m.kind == MoveKind::Entry || m.kind == MoveKind::Plunge {
            if entry_pts.is_empty() {
                entry_pts.push(from);
            }
            entry_pts.push(m.to);
            if let crate::toolpath::Motion::Arc { center, .. } = m.motion {
                let rr = (from.truncate() - center).length();
                *entry_arc_center = Some((center, entry_arc_center.map_or(rr, |(_, r): (DVec2, f64)| r.max(rr))));
            }
        } else if !entry_pts.is_empty() {
            let (c, rad) = match *entry_arc_center {
                Some(cr) => cr,
                None => {
                    let mut lo = entry_pts[0].truncate();
                    let mut hi = lo;
                    for p in entry_pts.iter() {
                        lo = lo.min(p.truncate());
                        hi = hi.max(p.truncate());
                    }
                    ((lo + hi) / 2.0, (hi - lo).length() / 2.0)
                }
            };
            *bore = Some((c, rad, std::f64::consts::TAU * rad + r));
            entry_pts.clear();
            *entry_arc_center = None;
        }
        if m.is_rapid() {
            // a rapid must not touch uncut material
            let (worst, at) = m_.rapid_depth(&path, m.to);
            if worst > 0.0 {
                out.rapid_collisions.push(Event { move_index: mi, at: at.to_array(), depth: worst });
            }
            *bore = None;
        } else {
            let xy = path.xy_length();
            let dz = m.to.z - from.z;
            let steep = xy <= 1e-3 || (dz < 0.0 && (-dz).atan2(xy).to_degrees() >= 80.0);
            if steep && dz < 0.0 && m_.material_under(m.to.truncate(), m.to.z) {
                out.plunges.push(Event { move_index: mi, at: m.to.to_array(), depth: -dz });
            }
            if xy > 1e-9 {
                let n = (xy / step).ceil().max(1.0) as usize;
                let kind = if steep && dz < 0.0 {
                    SampleKind::Plunge
                } else if dz.abs() > 1e-9 {
                    SampleKind::Descending
                } else {
                    SampleKind::Lateral
                };
                let step_len = len3 / n as f64;
                if kind != SampleKind::Plunge {
                    m_.begin_move();
                }
                for k in 1..=n {
                    let t = k as f64 / n as f64;
                    let p = path.at(t);
                    let dir = path.dir(t);
                    let cur = path.sub(0.0, t);
                    // the pixel ring is half a pixel outside the tool; the move's own cut up
                    // to the previous sample is what it must not see (up to this one would
                    // swallow the ring's sides)
                    let before = path.sub(0.0, (k - 1) as f64 / n as f64);
                    let (tea, tea_px) = if kind == SampleKind::Plunge {
                        (360.0, 360.0)
                    } else {
                        match m_.engagement(p, dir, &cur, &before) {
                            (Some(tea), px) => (tea, px),
                            (None, px) => {
                                later.push(out.samples.len());
                                (f64::NAN, px)
                            }
                        }
                    };
                    cum += step_len;
                    let in_bore = match (&mut *bore, kind) {
                        (_, SampleKind::Descending | SampleKind::Plunge)
                            if matches!(m.kind, MoveKind::Entry | MoveKind::Plunge) =>
                        {
                            true
                        }
                        (Some((c, rad, left)), SampleKind::Lateral) => {
                            let inside = (p.truncate() - *c).length() <= *rad + slack && *left > 0.0;
                            *left -= step_len;
                            if !inside {
                                *bore = None;
                            }
                            inside
                        }
                        _ => false,
                    };
                    out.samples.push(Sample {
                        s: cum,
                        at: p,
                        tea: tea as f32,
                        tea_pixel: tea_px as f32,
                        kind,
                        bore: in_bore,
                        len: step_len as f32,
                        feed: m.feed as f32,
                        mi: mi as u32,
                    });
                }
            } else {
                cum += len3;
            }
        }
        m_.cut_move(&path);
        paths.push(path);
    }
    m_.flush();
    for (mi, (g, at)) in m_.gouge_depths(&paths).into_iter().enumerate() {
        if g > 0.0 {
            out.gouges.push(Event { move_index: mi, at: at.to_array(), depth: g });
        }
    }
    let exact = m_.deferred();
    assert_eq!(exact.len(), later.len(), "an engine answers every engagement it left for later");
    for (k, tea) in later.into_iter().zip(exact) {
        out.samples[k].tea = tea as f32;
    }
    progress(1.0);
    out.removed_volume = m_.removed_volume();
    out
}
