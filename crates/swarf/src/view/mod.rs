//! The viewer: one self-contained HTML page that shows a program in 3D over its stock, part and
//! fixtures, plays it back while the stock is cut away, and links the engagement chart to the
//! path both ways.
//!
//! The page works from `file://` with no network: three.js (MIT, bundled with its orbit
//! controls, `three.bundle.js`) and the viewer's own script are inlined, and the program's data
//! are packed as typed arrays ([`pack`]), gzip-compressed and base64-encoded into the page.
//!
//! What a page holds (a [`Scene`]):
//!
//! - **runs**: one or more sequences of programs, each replayed on a fresh stock: `swarf rough`
//!   makes one run of one program, `swarf plan` one run of one program per tool (each on what
//!   the tools before it left), `swarf view A.ngc B.ngc` one run per program, to compare them;
//! - per program, every move (end point, arc centre, kind, feed, the G-code line it came from,
//!   its level, its largest engagement), the engagement chart (the simulator's samples in
//!   buckets, each the largest engagement in it and the move where it was), the gouges,
//!   plunges and rapid collisions the simulator found, the rest material, and the figures of
//!   the report;
//! - the **stock field**: the simulator's heights (its cells in blocks, a block read at its
//!   centre) before the first cut, of what must stay, and after the run, which the page lowers
//!   as it plays the moves (a flat end mill's sweep, computed in the page) and shows as a mesh;
//! - the simulator's **removed volume** after every 64th of each run's moves, which the page
//!   shows beside its own and the browser tests compare;
//! - **solids**: fixtures as extruded outlines, an STL part as its triangles.
//!
//! The method and the page's controls are described in `docs/viewer.md`.

mod pack;

use crate::error::Result;
use crate::geom::{Area, DVec2, DVec3};
use crate::job::rough::RoughResult;
use crate::model::{Job, MeshJob};
use crate::report::Report;
use crate::sim::grid::Grid;
use crate::sim::raster::RasterSim;
use crate::sim::{Event, Replay, Sample, SampleKind, SimOptions};
use crate::toolpath::{Motion, MoveKind, Toolpath, move_length};
use pack::Pack;

/// The most cells of the page's stock field (the simulator's cells are taken in blocks to stay
/// under it): 600 × 600.
pub const MAX_FIELD_CELLS: usize = 360_000;

/// The most buckets of a program's engagement chart.
pub const CHART_BUCKETS: usize = 12_000;

/// Into how many parts a run's moves are cut for the simulator's removed-volume readings.
pub const REMOVAL_STEPS: usize = 64;

/// The most rest-material points drawn per program.
const MAX_REST_POINTS: usize = 40_000;

/// One program as the page shows it.
#[derive(Debug, Clone)]
pub struct ProgramView {
    /// Its name (a file name, or the tool).
    pub name: String,
    /// The moves.
    pub toolpath: Toolpath,
    /// The G-code line (1-based) each move came from, or empty when unknown.
    pub lines: Vec<u32>,
    /// The G-code text, shown beside the selected move (none: not shown).
    pub gcode: Option<String>,
    /// The simulator's engagement samples.
    pub samples: Vec<Sample>,
    /// The reference engagement, degrees (drawn on the chart).
    pub ref_deg: Option<f64>,
    /// Gouges the simulator found.
    pub gouges: Vec<Event>,
    /// Plunges into material.
    pub plunges: Vec<Event>,
    /// Rapids through material.
    pub rapid_collisions: Vec<Event>,
    /// Centres of the cells of rest material.
    pub rest: Vec<DVec2>,
    /// The report's figures, as label and value.
    pub figures: Vec<(String, String)>,
    /// The tool axis at the end of each move (5-axis programs), unit vectors.
    pub axes: Option<Vec<DVec3>>,
}

/// Programs replayed one after the other on one stock.
#[derive(Debug, Clone)]
pub struct Run {
    /// Its name.
    pub name: String,
    /// The programs, in cutting order.
    pub programs: Vec<ProgramView>,
    /// The simulator's removed volume (mm³) after so many of the run's moves (counted over its
    /// programs), from 0 to all.
    pub removal: Vec<(u32, f64)>,
    /// The simulator's stock heights after the run, on the field's cells (NaN: no stock).
    pub end: Option<Vec<f32>>,
}

/// The stock as heights over a grid of square cells.
#[derive(Debug, Clone)]
pub struct Field {
    /// x of the left edge of column 0, mm.
    pub x0: f64,
    /// y of the bottom edge of row 0, mm.
    pub y0: f64,
    /// The side of a cell, mm.
    pub res: f64,
    /// Columns.
    pub nx: usize,
    /// Rows.
    pub ny: usize,
    /// Stock heights before any cut, row-major (NaN: no stock).
    pub start: Vec<f32>,
    /// Heights of what must stay (NaN: nothing).
    pub part: Vec<f32>,
    /// The lowest the stock goes (drawn as its bottom), mm.
    pub bottom: f64,
}

/// A solid drawn as it is (it does not change).
#[derive(Debug, Clone)]
pub enum Solid {
    /// An outline extruded from `z0` to `z1`.
    Extrusion {
        /// What it is: "part", "fixture" or "stock".
        kind: &'static str,
        /// The outline.
        area: Area,
        /// Bottom, mm.
        z0: f64,
        /// Top, mm.
        z1: f64,
    },
    /// Triangles.
    Mesh {
        /// What it is.
        kind: &'static str,
        /// The triangles.
        tris: Vec<[DVec3; 3]>,
    },
}

/// Everything one page shows.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The page's title.
    pub title: String,
    /// The runs (at least one).
    pub runs: Vec<Run>,
    /// The stock field, when the job has one (a 5-axis program has none).
    pub field: Option<Field>,
    /// Solids.
    pub solids: Vec<Solid>,
    /// Lines said under the title (what was read, what is left out).
    pub notes: Vec<String>,
}

/// The figures of a report worth a glance, as label and value.
pub fn figures_of(r: &Report) -> Vec<(String, String)> {
    let mut f = vec![
        ("strategy".to_string(), r.strategy.clone()),
        ("tool".to_string(), format!("Ø{} mm", r.tool_diameter_mm)),
        ("machining time".to_string(), format!("{:.2} min", r.time_min)),
        ("cutting length".to_string(), format!("{:.2} m", r.cut_length_mm / 1000.0)),
        ("rapid length".to_string(), format!("{:.2} m", r.rapid_length_mm / 1000.0)),
        ("moves".to_string(), format!("{} ({} arcs)", r.moves.total, r.moves.arcs)),
        ("levels".to_string(), r.levels.len().to_string()),
    ];
    if r.engagement_ref_deg > 0.0 {
        f.push(("reference engagement".into(), format!("{:.1}°", r.engagement_ref_deg)));
    }
    if r.simulated {
        let e = &r.engagement_deg;
        f.extend([
            ("engagement max / p95 / mean".to_string(), format!("{:.0}° / {:.0}° / {:.1}°", e.max, e.p95, e.mean)),
            (
                format!("above ref + 20° ({:.0}°)", r.above_ref_plus_20.threshold_deg),
                format!("{:.1} mm", r.above_ref_plus_20.length_mm),
            ),
            ("air cutting".to_string(), format!("{:.1} %", r.air_cut_fraction * 100.0)),
            ("plunges".to_string(), r.plunges.to_string()),
            ("entries".to_string(), r.entries.to_string()),
            ("gouges".to_string(), format!("{} (deepest {:.3} mm)", r.gouges, r.gouge_max_mm)),
            ("rapid collisions".to_string(), r.rapid_collisions.to_string()),
            ("rest".to_string(), format!("{:.2} % of the reachable area", r.rest_fraction * 100.0)),
            ("removed".to_string(), format!("{:.1} cm³", r.removed_volume_mm3 / 1000.0)),
            ("efficiency".to_string(), format!("{:.0} %", r.efficiency * 100.0)),
            ("simulation cell".to_string(), format!("{} mm", r.sim_res_mm)),
        ]);
    } else {
        f.push(("simulated".into(), "no".into()));
    }
    f
}

/// The G-code line of each move of `tp`, read back from `gcode` (the program `tp` was posted
/// as): each move takes the line of the next move read that ends where it ends (a move the
/// post wrote as several, or left out as too short, takes the line of its last piece, or of
/// the move before it); empty when fewer than nine in ten moves are found.
pub fn lines_of(gcode: &str, tp: &Toolpath) -> Vec<u32> {
    let opts = crate::io::gcode::ReadOptions { tool: tp.tool.clone(), clearance_z: Some(tp.clearance_z) };
    let Ok(read) = crate::io::gcode::read(gcode, std::path::Path::new("program.ngc"), &opts) else {
        return Vec::new();
    };
    let got = &read.toolpath.moves;
    let mut out = Vec::with_capacity(tp.moves.len());
    let (mut j, mut found, mut last) = (0usize, 0usize, 0u32);
    for m in &tp.moves {
        // (the post writes coordinates to the micrometre)
        let hit = (j..(j + 16).min(got.len())).find(|&k| got[k].to.distance(m.to) < 2e-3);
        if let Some(k) = hit {
            last = read.lines[k];
            j = k + 1;
            found += 1;
        }
        out.push(last);
    }
    if found * 10 < tp.moves.len() * 9 { Vec::new() } else { out }
}

/// The field of a model: its cells in blocks of `f` × `f` (the fewest that keep the field
/// under [`MAX_FIELD_CELLS`]), each read at its centre.
fn field_of(model: &RasterSim, bottom: f64) -> Field {
    let g = model.grid;
    let f = ((g.nx * g.ny) as f64 / MAX_FIELD_CELLS as f64).sqrt().ceil().max(1.0) as usize;
    let blocks = Grid { res: g.res * f as f64, nx: g.nx.div_ceil(f), ny: g.ny.div_ceil(f), ..g };
    Field {
        x0: blocks.x0,
        y0: blocks.y0,
        res: blocks.res,
        nx: blocks.nx,
        ny: blocks.ny,
        start: on(&g, model.initial_heights(), &blocks),
        part: on(&g, model.part_heights(), &blocks),
        bottom,
    }
}

/// The values of `v` (over `g`) at the cells of `to`, NaN where there is none (outside `g`, or
/// no stock).
fn on(g: &Grid, v: &[f32], to: &Grid) -> Vec<f32> {
    g.resample(v, to, f32::NAN).into_iter().map(|v| if v.is_finite() { v } else { f32::NAN }).collect()
}

impl Field {
    /// The field's cells as a grid.
    pub fn grid(&self) -> Grid {
        Grid { x0: self.x0, y0: self.y0, res: self.res, nx: self.nx, ny: self.ny }
    }
}

/// The move counts after which the removed volume is read: `REMOVAL_STEPS` + 1 of them, from
/// 0 to `n`.
fn removal_marks(n: usize) -> Vec<usize> {
    let mut v: Vec<usize> = (0..=REMOVAL_STEPS).map(|i| (i * n + REMOVAL_STEPS / 2) / REMOVAL_STEPS).collect();
    v.dedup();
    v
}

/// Goes through `tp` on `model` in pieces that end at the run's marks falling in it (`before`
/// moves of the run come before `tp`, and `base` mm³ were removed by them), `piece` doing the
/// work of each (given the index of its first move and its moves as a toolpath), and reads the
/// removed volume at each mark.
fn by_marks(
    model: &mut RasterSim,
    tp: &Toolpath,
    marks: &[usize],
    before: usize,
    base: f64,
    mut piece: impl FnMut(&mut RasterSim, usize, &Toolpath),
) -> Vec<(u32, f64)> {
    let n = tp.moves.len();
    let mut out = Vec::new();
    let (mut done, mut at) = (0usize, tp.start);
    let mut ends: Vec<usize> = marks.iter().filter(|&&m| m >= before && m <= before + n).map(|&m| m - before).collect();
    if ends.last() != Some(&n) {
        ends.push(n);
    }
    for upto in ends {
        if upto > done {
            let part = Toolpath {
                tool: tp.tool.clone(),
                start: at,
                clearance_z: tp.clearance_z,
                moves: tp.moves[done..upto].to_vec(),
                notes: Vec::new(),
            };
            piece(model, done, &part);
            at = part.end();
            done = upto;
        }
        if marks.contains(&(before + upto)) {
            out.push(((before + upto) as u32, base + model.removed_volume()));
        }
    }
    out
}

/// Replays `tp` on `model`, reading the removed volume at the run's marks in it (as
/// [`by_marks`]); the samples and events come back as one replay of the whole program
/// (lengths and move indices from its start).
fn replay_reading(
    model: &mut RasterSim,
    tp: &Toolpath,
    marks: &[usize],
    before: usize,
    base: f64,
) -> (Replay, Vec<(u32, f64)>) {
    let mut all = Replay::default();
    let mut s_off = 0.0;
    // (an entry and the bore it makes may straddle a mark)
    let mut carry = crate::sim::replay::Carry::default();
    let out = by_marks(model, tp, marks, before, base, |model, done, part| {
        let rp = model.replay_carrying(part, &mut |_| {}, &mut carry);
        all.samples.extend(rp.samples.iter().map(|s| Sample { s: s.s + s_off, mi: s.mi + done as u32, ..*s }));
        let shift = |v: &[Event]| v.iter().map(|e| Event { move_index: e.move_index + done, ..*e }).collect::<Vec<_>>();
        all.gouges.extend(shift(&rp.gouges));
        all.plunges.extend(shift(&rp.plunges));
        all.rapid_collisions.extend(shift(&rp.rapid_collisions));
        s_off += part.segments().filter(|(_, m)| !m.is_rapid()).map(|(a, m)| move_length(a, m)).sum::<f64>();
    });
    all.removed_volume = model.removed_volume();
    all.res = model.grid.res;
    (all, out)
}

impl ProgramView {
    /// A program as planned and proven: `tp` with its G-code, the replay's samples and events,
    /// and the report's figures.
    pub fn of(name: impl Into<String>, tp: &Toolpath, gcode: &str, replay: Option<&Replay>, report: &Report) -> Self {
        Self::with_lines(name, tp, lines_of(gcode, tp), gcode, replay, report)
    }

    /// The same with the G-code line of each move given.
    pub fn with_lines(
        name: impl Into<String>,
        tp: &Toolpath,
        lines: Vec<u32>,
        gcode: &str,
        replay: Option<&Replay>,
        report: &Report,
    ) -> Self {
        let mut v = ProgramView {
            name: name.into(),
            toolpath: tp.clone(),
            lines,
            gcode: Some(gcode.to_string()),
            samples: Vec::new(),
            ref_deg: (report.engagement_ref_deg > 0.0).then_some(report.engagement_ref_deg),
            gouges: Vec::new(),
            plunges: Vec::new(),
            rapid_collisions: Vec::new(),
            rest: Vec::new(),
            figures: figures_of(report),
            axes: None,
        };
        if let Some(rp) = replay {
            v.take_replay(rp);
        }
        v
    }

    fn take_replay(&mut self, rp: &Replay) {
        self.samples = rp.samples.clone();
        self.gouges = rp.gouges.clone();
        self.plunges = rp.plunges.clone();
        self.rapid_collisions = rp.rapid_collisions.clone();
        let step = rp.rest_cells.len().div_ceil(MAX_REST_POINTS).max(1);
        self.rest = rp.rest_cells.iter().step_by(step).copied().collect();
    }
}

/// The page of a 2.5D job's program (`swarf rough` on a case or a drawing): the stock field
/// from a model of the job on the simulator's cells (`sim`, as the proof fitted it), the
/// removed volume read along the program, fixtures as solids.
pub fn of_rough(job: &Job, res: &RoughResult, sim: &SimOptions) -> Result<Scene> {
    let sim =
        proof_cells(sim, &res.report).unwrap_or_else(|| sim.fitted_to(job.cutting.tool.diameter, job.stock.bounds()));
    let regions = job.regions(job.radius(), 0.0)?;
    Ok(proven(RasterSim::new(job, &regions, &sim)?, job.floor, res, fixtures_of(job)))
}

/// The page of a 3D job's program (`swarf rough` on an STL part): the part's triangles, the
/// stock field of the mesh model.
pub fn of_mesh_rough(job: &MeshJob, res: &RoughResult, sim: &SimOptions) -> Result<Scene> {
    let sim = proof_cells(sim, &res.report).unwrap_or_else(|| {
        sim.fitted_to(job.cutting.tool.diameter, Some((job.stock_lo.truncate(), job.stock_hi.truncate())))
    });
    let solids = vec![Solid::Mesh { kind: "part", tris: job.mesh.tris.clone() }];
    Ok(proven(crate::sim::heights::mesh_model(job, &sim)?, job.floor, res, solids))
}

/// The page of a program `rough` planned and proved (`res`): the stock field from `model`, a
/// fresh model of its job, on which the program is cut again to read the removed volume along
/// it (its engagement and events are the proof's).
fn proven(mut model: RasterSim, floor: f64, res: &RoughResult, solids: Vec<Solid>) -> Scene {
    model.track_exact = false;
    let field = field_of(&model, floor);
    let marks = removal_marks(res.toolpath.moves.len());
    let removal =
        by_marks(&mut model, &res.toolpath, &marks, 0, 0.0, |model, _, part| model.cut_moves(part.start, &part.moves));
    let end = on(&model.grid, model.heights(), &field.grid());
    let program =
        ProgramView::of(res.report.input.clone(), &res.toolpath, &res.gcode, res.replay.as_ref(), &res.report);
    Scene {
        title: format!("{} — {}", res.report.input, res.report.strategy),
        runs: vec![Run { name: res.report.input.clone(), programs: vec![program], removal, end: Some(end) }],
        field: Some(field),
        solids,
        notes: Vec::new(),
    }
}

/// A 2.5D job's fixtures, as their outlines standing from the floor to a quarter of the job's
/// depth over its top (they are not cut, and stand out of the stock).
fn fixtures_of(job: &Job) -> Vec<Solid> {
    if job.fixtures.polys.is_empty() {
        return Vec::new();
    }
    vec![Solid::Extrusion {
        kind: "fixture",
        area: job.fixtures.clone(),
        z0: job.floor,
        z1: job.stock_top.max(job.part_top) + 0.25 * (job.stock_top - job.floor).abs().max(1.0),
    }]
}

/// The page of a tool sequence (`swarf plan`): one run of its programs, each replayed on what
/// the ones before it left (as the plan's own check does, on the cells of its smallest tool),
/// a tool per colour. `programs` are the plan's programs with their names and G-code.
pub fn of_plan(
    job: &MeshJob,
    programs: &[(&Toolpath, String, String)],
    sim: &SimOptions,
    title: impl Into<String>,
) -> Result<Scene> {
    let smallest = programs.iter().map(|p| p.0.tool.diameter).fold(f64::INFINITY, f64::min);
    let sim = SimOptions { res: Some(sim.res_for(smallest)), ..sim.clone() };
    let pieces: Vec<Piece<'_>> =
        programs.iter().map(|(tp, name, gcode)| Piece { tp, name: name.clone(), gcode, lines: None }).collect();
    let mut field = None;
    let how = Chain {
        job: Against::Mesh(job),
        sim: &|_| sim.clone(),
        exact_first: false,
        strategy: "z-level roughing",
        ref_deg: 0.0,
    };
    let run = how.run("tool sequence".into(), &pieces, &mut field)?;
    Ok(Scene {
        title: title.into(),
        runs: vec![run],
        field,
        solids: vec![Solid::Mesh { kind: "part", tris: job.mesh.tris.clone() }],
        notes: vec!["engagement by circumference pixels (paper 1 eq. 4)".into()],
    })
}

/// The job a program is read against: a 2.5D job or a mesh job.
#[derive(Debug, Clone, Copy)]
pub enum Against<'a> {
    /// A 2.5D job.
    Flat(&'a Job),
    /// A mesh job.
    Mesh(&'a MeshJob),
}

impl Against<'_> {
    /// A model of the job for `tool` on `sim`'s cells, its stock what `after` left (the job's
    /// stock without it).
    fn model(
        &self,
        tool: &crate::model::Tool,
        after: Option<crate::sim::HeightMap>,
        sim: &SimOptions,
    ) -> Result<RasterSim> {
        match *self {
            Against::Flat(j) => {
                let mut j2 = j.clone();
                j2.cutting.tool = tool.clone();
                let sim = SimOptions { heights: after.map(std::sync::Arc::new), ..sim.clone() };
                let regions = j2.regions(j2.radius(), 0.0)?;
                RasterSim::new(&j2, &regions, &sim)
            }
            Against::Mesh(j) => crate::sim::heights::mesh_model_after(j, tool, after.as_ref(), sim),
        }
    }

    /// The rest material `model` holds after `rp` (whose rest cells it fills in 2.5D).
    fn rest(&self, model: &RasterSim, rp: &mut Replay) -> crate::sim::Rest {
        match *self {
            Against::Flat(_) => {
                rp.rest_cells = model.rest_cells();
                model.rest()
            }
            Against::Mesh(j) => crate::sim::heights::mesh_rest(j, model, 64).0,
        }
    }

    fn floor(&self) -> f64 {
        match *self {
            Against::Flat(j) => j.floor,
            Against::Mesh(j) => j.floor,
        }
    }

    fn cutting(&self) -> &crate::model::Cutting {
        match *self {
            Against::Flat(j) => &j.cutting,
            Against::Mesh(j) => &j.cutting,
        }
    }

    fn name(&self) -> &str {
        match *self {
            Against::Flat(j) => &j.name,
            Against::Mesh(j) => &j.name,
        }
    }
}

/// One program of a run, as [`Chain::run`] takes it: its moves (with their tool), its name, its
/// G-code and the source line of each move (`None`: read back from the G-code).
struct Piece<'a> {
    tp: &'a Toolpath,
    name: String,
    gcode: &'a str,
    lines: Option<Vec<u32>>,
}

/// How a run of programs on one stock is replayed: a tool sequence, or a program that changes
/// tools.
struct Chain<'a> {
    job: Against<'a>,
    /// The simulation options for a tool.
    sim: &'a dyn Fn(&crate::model::Tool) -> SimOptions,
    /// The first program's engagement is measured exactly; later programs', and every
    /// program's without it, by circumference pixels (paper 1 eq. 4): the exact model starts
    /// from the stock outline, not from what the programs before left.
    exact_first: bool,
    /// What the reports call the strategy.
    strategy: &'a str,
    /// The reference engagement, degrees (0: none).
    ref_deg: f64,
}

impl Chain<'_> {
    /// Replays `pieces` one after the other on one stock, each on what the ones before it left,
    /// as the run `name`: the programs' views, the removed volume read after every 64th of their
    /// moves and where each ends, and the heights after the last on `field` (made from the first
    /// model when there is none).
    fn run(&self, name: String, pieces: &[Piece<'_>], field: &mut Option<Field>) -> Result<Run> {
        let total: usize = pieces.iter().map(|p| p.tp.moves.len()).sum();
        // (and where each program ends: the stock each tool leaves is read exactly)
        let mut marks = removal_marks(total);
        marks.extend(pieces.iter().scan(0, |n, p| {
            *n += p.tp.moves.len();
            Some(*n)
        }));
        marks.sort_unstable();
        marks.dedup();
        let (mut before, mut base) = (0usize, 0.0);
        let mut stock: Option<crate::sim::HeightMap> = None;
        let (mut views, mut removal) = (Vec::new(), Vec::new());
        for (k, piece) in pieces.iter().enumerate() {
            let tp = piece.tp;
            let exact = self.exact_first && k == 0;
            let mut model = self.job.model(&tp.tool, stock.take(), &(self.sim)(&tp.tool))?;
            model.track_exact = exact;
            if field.is_none() {
                *field = Some(field_of(&model, self.job.floor()));
            }
            let (mut rp, got) = replay_reading(&mut model, tp, &marks, before, base);
            removal.extend(got);
            if !exact {
                for s in &mut rp.samples {
                    s.tea = s.tea_pixel;
                }
            }
            let rest = self.job.rest(&model, &mut rp);
            let mut rep = Report {
                input: piece.name.clone(),
                strategy: self.strategy.into(),
                tool_diameter_mm: tp.tool.diameter,
                engagement_ref_deg: self.ref_deg,
                levels: levels_of(tp).0,
                sim_res_mm: model.grid.res,
                ..Report::default()
            };
            crate::report::fill(&mut rep, tp, &rp, &rest, self.job.cutting().rapid_rate);
            let lines = piece.lines.clone().unwrap_or_else(|| lines_of(piece.gcode, tp));
            let mut v = ProgramView::with_lines(piece.name.clone(), tp, lines, piece.gcode, Some(&rp), &rep);
            v.figures.retain(|(k, _)| k != "strategy" && k != "efficiency");
            views.push(v);
            before += tp.moves.len();
            base += rp.removed_volume;
            stock = Some(crate::sim::HeightMap { grid: model.grid, stock: model.heights().to_vec(), part: None });
        }
        let end = stock.zip(field.as_ref()).map(|(s, f)| on(&s.grid, &s.stock, &f.grid()));
        Ok(Run { name, programs: views, removal, end })
    }
}

/// A program read from G-code, as [`of_programs`] takes it.
#[derive(Debug, Clone)]
pub struct ReadProgram {
    /// Its name (the file's).
    pub name: String,
    /// Its pieces, one per tool ([`crate::io::gcode::Program::by_tool`]), each with the source
    /// lines of its moves.
    pub pieces: Vec<(Toolpath, Vec<u32>)>,
    /// The units it was read in.
    pub units: &'static str,
    /// Its text.
    pub gcode: String,
}

/// The page of programs read from G-code (`swarf view`), each replayed by swarf's simulator on
/// its own fresh stock of `job`, one run each: two programs for the same part side by side. A
/// program that changes tools is a run of one piece per tool, each replayed on what the ones
/// before it left, as a tool sequence is.
pub fn of_programs(job: Against<'_>, programs: Vec<ReadProgram>, sim: &SimOptions) -> Result<Scene> {
    let span = match job {
        Against::Flat(j) => j.stock.bounds(),
        Against::Mesh(j) => Some((j.stock_lo.truncate(), j.stock_hi.truncate())),
    };
    let sim_for = |t: &crate::model::Tool| sim.fitted_to(t.diameter, span);
    let how = Chain {
        job,
        sim: &sim_for,
        exact_first: true,
        strategy: "read from G-code",
        ref_deg: job.cutting().width.engagement_deg(),
    };
    let mut runs = Vec::new();
    let mut field = None;
    for prog in &programs {
        let several = prog.pieces.len() > 1;
        let pieces: Vec<Piece<'_>> = prog
            .pieces
            .iter()
            .map(|(tp, lines)| Piece {
                tp,
                name: if several {
                    format!("{} T{} Ø{}", prog.name, tp.tool.number, tp.tool.diameter)
                } else {
                    prog.name.clone()
                },
                gcode: &prog.gcode,
                lines: Some(lines.clone()),
            })
            .collect();
        let mut run = how.run(prog.name.clone(), &pieces, &mut field)?;
        for v in &mut run.programs {
            v.figures.insert(0, ("units read".into(), prog.units.to_string()));
        }
        runs.push(run);
    }
    let solids = match job {
        Against::Flat(j) => fixtures_of(j),
        Against::Mesh(j) => vec![Solid::Mesh { kind: "part", tris: j.mesh.tris.clone() }],
    };
    let names: Vec<&str> = runs.iter().map(|r| r.name.as_str()).collect();
    Ok(Scene { title: format!("{} — {}", job.name(), names.join(" vs ")), runs, field, solids, notes: Vec::new() })
}

/// The page of a 5-axis program (`swarf five`): the tool tip's path with the tool axis at each
/// move, over the floor and the walls drawn as surfaces. swarf has no 5-axis material model, so
/// the page has no stock field and no engagement chart.
pub fn of_five(job: &crate::model::five::FiveJob, prog: &crate::job::five::FiveProgram) -> Scene {
    use crate::model::five::{Boundary, Side};
    let moves = &prog.plan.moves;
    let tool = crate::model::Tool { diameter: job.tool.diameter, number: 1, flutes: 2 };
    let start = moves.first().map_or(DVec3::ZERO, |m| m.tip);
    let mut tp = Toolpath::new(tool, start, start.z);
    for m in moves.iter().skip(1) {
        if m.rapid {
            tp.rapid(m.tip);
        } else {
            tp.line(MoveKind::Cut, m.tip, m.feed);
        }
    }
    let axes: Vec<DVec3> = moves.iter().skip(1).map(|m| m.axis).collect();
    let figures = vec![
        ("tool".to_string(), format!("{:?} Ø{} mm", job.tool.kind, job.tool.diameter)),
        ("machining time".to_string(), format!("{:.2} min", prog.time_min)),
        ("cutting length".to_string(), format!("{:.2} m", prog.length.0 / 1000.0)),
        ("rapid length".to_string(), format!("{:.2} m", prog.length.1 / 1000.0)),
        ("moves".to_string(), tp.moves.len().to_string()),
        ("rounded shapes".to_string(), prog.plan.shapes.to_string()),
        ("closest to a wall".to_string(), format!("{:.3} mm", prog.plan.wall_clearance)),
    ];
    let program = ProgramView {
        name: job.name.clone(),
        lines: Vec::new(),
        gcode: None,
        samples: Vec::new(),
        ref_deg: None,
        gouges: Vec::new(),
        plunges: Vec::new(),
        rapid_collisions: Vec::new(),
        rest: Vec::new(),
        figures,
        axes: Some(axes),
        toolpath: tp,
    };
    // the floor, and each wall as the ruled surface from the floor's edge to the top's (or the
    // case's own), as triangles
    const N: usize = 48;
    let grid = |f: &dyn Fn(f64, f64) -> DVec3| {
        let mut tris = Vec::with_capacity(2 * N * N);
        let at = |i: usize, j: usize| f(i as f64 / N as f64, j as f64 / N as f64);
        for j in 0..N {
            for i in 0..N {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                tris.push([a, b, c]);
                tris.push([a, c, d]);
            }
        }
        tris
    };
    let on = |srf: &crate::geom::nurbs::NurbsSurface, u: f64, v: f64| {
        let ((u0, u1), (v0, v1)) = srf.domain();
        srf.eval(u0 + (u1 - u0) * u, v0 + (v1 - v0) * v).p
    };
    let mut solids = vec![Solid::Mesh { kind: "part", tris: grid(&|u, v| on(&job.floor, u, v)) }];
    for side in Side::ALL {
        match job.boundary(side) {
            Boundary::Open => {}
            Boundary::Wall(Some(w)) => solids.push(Solid::Mesh { kind: "part", tris: grid(&|s, t| on(w, s, t)) }),
            Boundary::Wall(None) => solids.push(Solid::Mesh {
                kind: "part",
                tris: grid(&|s, t| {
                    let q = side.at(s);
                    on(&job.floor, q.x, q.y).lerp(on(&job.top, q.x, q.y), t)
                }),
            }),
        }
    }
    Scene {
        title: format!("{} — 5-axis pocket", job.name),
        runs: vec![Run { name: job.name.clone(), programs: vec![program], removal: Vec::new(), end: None }],
        field: None,
        solids,
        notes: vec!["5-axis: the tool axis drawn; no material model, so no stock or engagement".into()],
    }
}

/// `sim` with the cell the proof of `report` used (none when it was not proven).
fn proof_cells(sim: &SimOptions, report: &Report) -> Option<SimOptions> {
    (report.simulated && report.sim_res_mm > 0.0).then(|| SimOptions { res: Some(report.sim_res_mm), ..sim.clone() })
}

/// The levels of a program — the heights of its horizontal cuts, highest first — and the level
/// of each move: a horizontal cut's own, any other move's the next cut's (the last cut's after
/// the last one). Heights within a micrometre are one level; more than 500 levels are merged
/// to the nearest 0.1 mm.
pub fn levels_of(tp: &Toolpath) -> (Vec<f64>, Vec<u16>) {
    let flat: Vec<Option<f64>> = tp
        .segments()
        .map(|(a, m)| {
            let cutting = matches!(m.kind, MoveKind::Cut | MoveKind::Finish);
            (cutting && (m.to.z - a.z).abs() < 1e-6).then_some(m.to.z)
        })
        .collect();
    let mut step = 1e-3;
    let mut keys: Vec<i64>;
    loop {
        keys = flat.iter().flatten().map(|z| (z / step).round() as i64).collect();
        keys.sort_unstable();
        keys.dedup();
        if keys.len() <= 500 || step >= 0.1 {
            break;
        }
        step = 0.1;
    }
    keys.reverse();
    let levels: Vec<f64> = keys.iter().map(|&k| k as f64 * step).collect();
    let index = |z: f64| {
        let k = (z / step).round() as i64;
        keys.iter().position(|&x| x == k).unwrap_or(0) as u16
    };
    let mut of = vec![0u16; flat.len()];
    let mut next: Option<u16> = None;
    for i in (0..flat.len()).rev() {
        if let Some(z) = flat[i] {
            next = Some(index(z));
        }
        of[i] = next.unwrap_or(u16::MAX);
    }
    // after the last cut: the last cut's level
    let last = of.iter().rev().find(|&&l| l != u16::MAX).copied().unwrap_or(0);
    for l in &mut of {
        if *l == u16::MAX {
            *l = last;
        }
    }
    (levels, of)
}

/// Flag bits of a packed move beside its kind.
const ARC: u8 = 0x10;
const CCW: u8 = 0x20;

impl Scene {
    /// The page: one HTML document with everything inlined.
    pub fn html(&self) -> String {
        let (head, pack) = self.packed();
        let head = serde_json::to_string(&head).unwrap_or_else(|_| "{}".into()).replace("</", "<\\/");
        let mut html = String::with_capacity(pack.len() / 2 + VIEWER_JS.len() + THREE_JS.len() + 4096);
        html.push_str("<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n");
        html.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
        html.push_str(&format!("<title>swarf — {}</title>\n", escape(&self.title)));
        html.push_str("<meta name=\"generator\" content=\"swarf ");
        html.push_str(env!("CARGO_PKG_VERSION"));
        html.push_str("\">\n<style>\n");
        html.push_str(VIEWER_CSS);
        html.push_str("</style></head>\n<body>\n");
        html.push_str(VIEWER_BODY);
        html.push_str("\n<script type=\"application/json\" id=\"swarf-head\">");
        html.push_str(&head);
        html.push_str("</script>\n<script type=\"application/octet-stream\" id=\"swarf-data\">");
        html.push_str(&pack.encoded());
        html.push_str("</script>\n<script>\n");
        html.push_str(THREE_JS);
        html.push_str("\n</script>\n<script>\n");
        html.push_str(VIEWER_JS);
        html.push_str("\n</script>\n</body></html>\n");
        html
    }

    /// The page's head (JSON) and its arrays.
    fn packed(&self) -> (serde_json::Value, Pack) {
        let mut pk = Pack::default();
        let mut runs = Vec::new();
        for (ri, run) in self.runs.iter().enumerate() {
            let mut progs = Vec::new();
            for (pi, p) in run.programs.iter().enumerate() {
                let key = format!("r{ri}p{pi}");
                progs.push(pack_program(&mut pk, &key, p));
            }
            if let Some(end) = &run.end {
                pk.f32(format!("r{ri}.end"), end.iter().copied());
            }
            runs.push(serde_json::json!({
                "name": run.name,
                "programs": progs,
                "removal": run.removal.iter().map(|(k, v)| serde_json::json!([k, (v * 1000.0).round() / 1000.0])).collect::<Vec<_>>(),
                "end": run.end.is_some(),
            }));
        }
        let field = self.field.as_ref().map(|f| {
            pk.f32("field.start", f.start.iter().copied());
            pk.f32("field.part", f.part.iter().copied());
            serde_json::json!({"x0": f.x0, "y0": f.y0, "res": f.res, "nx": f.nx, "ny": f.ny, "bottom": f.bottom})
        });
        let mut solids = Vec::new();
        for (si, s) in self.solids.iter().enumerate() {
            match s {
                Solid::Extrusion { kind, area, z0, z1 } => {
                    let mut xy = Vec::new();
                    let mut polys = Vec::new();
                    for poly in &area.polys {
                        let mut rings = Vec::new();
                        for ring in poly.rings() {
                            rings.push(serde_json::json!([xy.len() / 2, ring.len()]));
                            for p in ring {
                                xy.push(p.x as f32);
                                xy.push(p.y as f32);
                            }
                        }
                        polys.push(rings);
                    }
                    pk.f32(format!("s{si}.xy"), xy);
                    solids.push(
                        serde_json::json!({"type": "extrusion", "kind": kind, "polys": polys, "z0": z0, "z1": z1}),
                    );
                }
                Solid::Mesh { kind, tris } => {
                    pk.f32(
                        format!("s{si}.tris"),
                        tris.iter().flat_map(|t| t.iter().flat_map(|p| [p.x as f32, p.y as f32, p.z as f32])),
                    );
                    solids.push(serde_json::json!({"type": "mesh", "kind": kind, "count": tris.len()}));
                }
            }
        }
        let head = serde_json::json!({
            "format": 1,
            "swarf": env!("CARGO_PKG_VERSION"),
            "title": self.title,
            "notes": self.notes,
            "runs": runs,
            "field": field,
            "solids": solids,
            "arrays": pk.table(),
            "chartBuckets": CHART_BUCKETS,
        });
        (head, pk)
    }
}

/// Packs one program's arrays under `key` and returns its entry of the head.
fn pack_program(pk: &mut Pack, key: &str, p: &ProgramView) -> serde_json::Value {
    let tp = &p.toolpath;
    let n = tp.moves.len();
    pk.f32(format!("{key}.to"), tp.moves.iter().flat_map(|m| [m.to.x as f32, m.to.y as f32, m.to.z as f32]));
    pk.f32(
        format!("{key}.ctr"),
        tp.moves.iter().flat_map(|m| match m.motion {
            Motion::Arc { center, .. } => [center.x as f32, center.y as f32],
            Motion::Line => [f32::NAN, f32::NAN],
        }),
    );
    let flags: Vec<u8> = tp
        .moves
        .iter()
        .map(|m| {
            m.kind.code()
                | match m.motion {
                    Motion::Arc { ccw, .. } => ARC | if ccw { CCW } else { 0 },
                    Motion::Line => 0,
                }
        })
        .collect();
    pk.u8(format!("{key}.flags"), &flags);
    pk.f32(format!("{key}.feed"), tp.moves.iter().map(|m| m.feed as f32));
    let (levels, of) = levels_of(tp);
    pk.u16(format!("{key}.level"), of);
    if p.lines.len() == n {
        pk.u32(format!("{key}.line"), p.lines.iter().copied());
    }
    // cutting length at the end of each move, as the replay counts it (feed moves, in 3D)
    let mut s = 0.0;
    pk.f32(
        format!("{key}.s"),
        tp.segments()
            .map(|(a, m)| {
                if !m.is_rapid() {
                    s += move_length(a, m);
                }
                s as f32
            })
            .collect::<Vec<_>>(),
    );
    // the largest engagement on each move (lateral and descending samples; plunges are marked)
    let mut tea = vec![f32::NAN; n];
    for sm in &p.samples {
        if let Some(t) = tea.get_mut(sm.mi as usize)
            && sm.kind != SampleKind::Plunge
        {
            *t = if t.is_nan() { sm.tea } else { t.max(sm.tea) };
        }
    }
    pk.f32(format!("{key}.tea"), tea);
    // the chart: samples in buckets of equal length, the largest of each and where it was
    let total = p.samples.last().map_or(0.0, |s| s.s);
    let nb = CHART_BUCKETS.min(p.samples.len());
    if nb > 0 {
        let width = (total / nb as f64).max(1e-9);
        let mut b_s = vec![f32::NAN; nb];
        let mut b_max = vec![f32::NAN; nb];
        let mut b_mean = vec![0f32; nb];
        let mut b_n = vec![0u32; nb];
        let mut b_mi = vec![0u32; nb];
        for sm in &p.samples {
            if sm.kind == SampleKind::Plunge {
                continue;
            }
            let b = ((sm.s / width) as usize).min(nb - 1);
            if b_max[b].is_nan() || sm.tea > b_max[b] {
                b_max[b] = sm.tea;
                b_s[b] = sm.s as f32;
                b_mi[b] = sm.mi;
            }
            b_mean[b] += sm.tea;
            b_n[b] += 1;
        }
        let keep: Vec<usize> = (0..nb).filter(|&b| b_n[b] > 0).collect();
        pk.f32(format!("{key}.cs"), keep.iter().map(|&b| b_s[b]));
        pk.f32(format!("{key}.cmax"), keep.iter().map(|&b| b_max[b]));
        pk.f32(format!("{key}.cmean"), keep.iter().map(|&b| b_mean[b] / b_n[b] as f32));
        pk.u32(format!("{key}.cmi"), keep.iter().map(|&b| b_mi[b]));
    }
    if !p.rest.is_empty() {
        pk.f32(format!("{key}.rest"), p.rest.iter().flat_map(|c| [c.x as f32, c.y as f32]));
    }
    if let Some(ax) = &p.axes {
        pk.f32(format!("{key}.axis"), ax.iter().flat_map(|a| [a.x as f32, a.y as f32, a.z as f32]));
    }
    if let Some(g) = &p.gcode {
        pk.u8(format!("{key}.gcode"), g.as_bytes());
    }
    let ev = |v: &[Event]| {
        v.iter().map(|e| serde_json::json!([e.move_index, e.at[0], e.at[1], e.at[2], e.depth])).collect::<Vec<_>>()
    };
    serde_json::json!({
        "key": key,
        "name": p.name,
        "tool": {"d": tp.tool.diameter, "number": tp.tool.number},
        "start": [tp.start.x, tp.start.y, tp.start.z],
        "clearance": tp.clearance_z,
        "moves": n,
        "levels": levels,
        "ref": p.ref_deg,
        "figures": p.figures,
        "gouges": ev(&p.gouges),
        "plunges": ev(&p.plunges),
        "rapidCollisions": ev(&p.rapid_collisions),
        "cutLength": s,
    })
}

/// `s` with `&`, `<` and `>` escaped for HTML text.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// three.js with its orbit controls, one classic script (see `viewer/build.sh`).
const THREE_JS: &str = include_str!("three.bundle.js");
/// The viewer's script.
const VIEWER_JS: &str = include_str!("viewer.js");
/// Its style sheet.
const VIEWER_CSS: &str = include_str!("viewer.css");
/// Its page body.
const VIEWER_BODY: &str = include_str!("viewer.html");

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Tool;

    fn path() -> Toolpath {
        let mut tp = Toolpath::new(Tool::flat(6.0), DVec3::new(0.0, 0.0, 5.0), 5.0);
        tp.rapid(DVec3::new(0.0, 0.0, 1.0));
        tp.line(MoveKind::Plunge, DVec3::new(0.0, 0.0, -1.0), 100.0);
        tp.line(MoveKind::Cut, DVec3::new(10.0, 0.0, -1.0), 500.0);
        tp.line(MoveKind::Descend, DVec3::new(10.0, 0.0, -2.0), 100.0);
        tp.arc(MoveKind::Cut, DVec3::new(10.0, 10.0, -2.0), DVec2::new(10.0, 5.0), true, 500.0);
        tp.rapid(DVec3::new(10.0, 10.0, 5.0));
        tp
    }

    #[test]
    fn levels_are_the_heights_of_the_flat_cuts_and_every_move_takes_the_next_cuts() {
        let (levels, of) = levels_of(&path());
        assert_eq!(levels, vec![-1.0, -2.0]);
        assert_eq!(of, vec![0, 0, 0, 1, 1, 1]);
    }

    #[test]
    fn an_entry_bore_read_in_pieces_is_read_as_in_one_replay() {
        // a helix of straight moves (as FreeCAD writes it), the turn at its bottom, and a cut
        // out of the bore; the removal mark just after the helix cuts the replay in two there
        use crate::model::{Cutting, Job, Width};
        let job = Job {
            floor: -2.0,
            cutting: Cutting::with_tool_diameter(6.0).with_width(Width::Stepover(0.25)),
            ..Job::new("t", Area::rect(-20.0, -20.0, 20.0, 20.0), Area::empty(), 0.0, 0.0)
        };
        let on = |a: f64, z: f64| DVec3::new(2.0 * a.cos(), 2.0 * a.sin(), z);
        let mut tp = Toolpath::new(Tool::flat(6.0), DVec3::new(2.0, 0.0, 5.0), 5.0);
        tp.rapid(on(0.0, 1.0));
        for k in 1..=48 {
            let a = std::f64::consts::TAU * k as f64 / 16.0;
            tp.line(MoveKind::Entry, on(a, 1.0 - 3.0 * k as f64 / 48.0), 300.0);
        }
        let entry_end = tp.moves.len();
        for k in 1..=16 {
            tp.line(MoveKind::Cut, on(std::f64::consts::TAU * k as f64 / 16.0, -2.0), 500.0);
        }
        tp.line(MoveKind::Cut, DVec3::new(12.0, 0.0, -2.0), 500.0);
        tp.rapid(DVec3::new(12.0, 0.0, 5.0));
        let regions = job.regions(job.radius(), 0.0).expect("regions");
        let sim = SimOptions { res: Some(0.1), ..Default::default() };
        let whole = RasterSim::new(&job, &regions, &sim).expect("model").replay(&tp, &mut |_| {});
        let mut model = RasterSim::new(&job, &regions, &sim).expect("model");
        let (pieces, read) = replay_reading(&mut model, &tp, &[0, entry_end, tp.moves.len()], 0, 0.0);
        assert_eq!(read.len(), 3, "{read:?}");
        let flags = |rp: &Replay| rp.samples.iter().map(|s| (s.mi, s.bore)).collect::<Vec<_>>();
        assert_eq!(flags(&pieces), flags(&whole));
        // the turn at the bottom is inside the bore, the cut out of it is not
        let at_bottom = |rp: &Replay| rp.samples.iter().filter(|s| s.bore && s.mi as usize >= entry_end).count();
        assert!(at_bottom(&pieces) > 20, "{} samples of the bottom turn in the bore", at_bottom(&pieces));
        assert!(pieces.samples.iter().any(|s| !s.bore && s.at.x > 6.0));
    }

    #[test]
    fn the_removal_marks_run_from_none_to_all_and_hold_the_middle() {
        let m = removal_marks(1000);
        assert_eq!((m[0], *m.last().unwrap(), m.len()), (0, 1000, REMOVAL_STEPS + 1));
        assert!(m.contains(&500));
        assert_eq!(removal_marks(3), vec![0, 1, 2, 3]);
    }

    #[test]
    fn the_page_is_one_file_with_its_data_and_no_script_end_inside_them() {
        let p = ProgramView {
            name: "a</script>".into(),
            toolpath: path(),
            lines: vec![],
            gcode: Some("G0 X0 (</script>)\n".into()),
            samples: vec![],
            ref_deg: Some(60.0),
            gouges: vec![],
            plunges: vec![],
            rapid_collisions: vec![],
            rest: vec![],
            figures: vec![("t".into(), "</script>".into())],
            axes: None,
        };
        let scene = Scene {
            title: "t".into(),
            runs: vec![Run { name: "r".into(), programs: vec![p], removal: vec![(0, 0.0), (6, 1.0)], end: None }],
            field: None,
            solids: vec![],
            notes: vec![],
        };
        let html = scene.html();
        // the three.js bundle, the viewer's script and the head; only our own script ends
        assert_eq!(html.matches("</script>").count(), 4);
        assert!(!html.contains("src=\"http") && !html.contains("src='http"));
        let (head, _) = scene.packed();
        assert_eq!(head["runs"][0]["programs"][0]["moves"], 6);
        assert_eq!(head["arrays"]["r0p0.flags"][2], 6);
        assert_eq!(head["runs"][0]["programs"][0]["levels"], serde_json::json!([-1.0, -2.0]));
    }
}
