//! The raster material model and the replay of a toolpath on it.

use super::SimOptions;
use super::exact::{ExactModel, Query, ToExact};
use super::grid::{Grid, ceil_i, floor_i};
use super::replay::{Replay, Rest};
use super::sweep::{Fast, Path, Reach};
use crate::error::{Error, Result, Setting};
use crate::geom::index::EdgeIndex;
use crate::geom::{Area, DVec2, DVec3};
use crate::model::{Job, Regions};
use crate::toolpath::{Move, Toolpath};
use rayon::prelude::*;

/// Cell state bits (paper 1 §4: part / stock; fixture; neither = free space).
pub mod state {
    /// Raw stock.
    pub const STOCK: u8 = 1;
    /// Part (must stay).
    pub const PART: u8 = 2;
    /// Fixture (forbidden).
    pub const FIXTURE: u8 = 4;
}

/// Visits the cells within `rho` of the path whose value in `h` stands more than `above` over
/// the lowest tool-tip height while the axis is within `rho` of the cell centre:
/// `f(index, centre, tip_z)`; stops early when `f` returns false. Flat paths (the common case)
/// need no interval analysis: their tip height is known, so the distance test is done only for
/// cells high enough to matter.
fn visit_above(
    grid: &Grid,
    h: &[f32],
    blocks: Option<(&[f32], usize)>,
    path: &Path,
    rho: f64,
    above: f64,
    mut f: impl FnMut(usize, DVec2, f64) -> bool,
) {
    let (lo, hi) = path.bbox(rho);
    let Some((i0, i1, j0, j1)) = grid.range(lo, hi) else { return };
    let (z0, z1) = path.z_range();
    let zmin = z0.min(z1);
    let flat = path.is_flat().then(|| (Fast::new(path), z0));
    let st = stadium_of(path, rho);
    for j in j0..=j1 {
        let Some((i0, i1)) = row_columns(grid, st.as_ref(), j, i0, i1) else { continue };
        for (i0, i1) in block_runs(i0, i1) {
            // a block whose highest cell is not high enough holds nothing to visit
            if let Some((bmax, nbx)) = blocks
                && (bmax[(j / BLOCK) * nbx + i0 / BLOCK] as f64) - zmin <= above
            {
                continue;
            }
            for i in i0..=i1 {
                let k = j * grid.nx + i;
                let v = h[k];
                if v == f32::NEG_INFINITY {
                    continue;
                }
                let q = grid.center(i, j);
                let z = match &flat {
                    Some((fast, z)) => {
                        if (v as f64) - *z <= above || fast.distance(q) > rho {
                            continue;
                        }
                        *z
                    }
                    None => match path.reach_zmin(q, rho) {
                        Some(z) if (v as f64) - z > above => z,
                        _ => continue,
                    },
                };
                if !f(k, q, z) {
                    return;
                }
            }
        }
    }
}

/// The columns `i0..=i1` split where the blocks of [`BLOCK`] cells begin, in order.
#[inline]
fn block_runs(i0: usize, i1: usize) -> impl Iterator<Item = (usize, usize)> {
    let mut i = i0;
    std::iter::from_fn(move || {
        (i <= i1).then(|| {
            let e = ((i / BLOCK + 1) * BLOCK - 1).min(i1);
            let run = (i, e);
            i = e + 1;
            run
        })
    })
}

/// The points within `r` of the segment `ab` (a stadium), prepared for row spans.
struct Stadium {
    a: DVec2,
    b: DVec2,
    r: f64,
    /// The band's two sides, when the segment has a length.
    sides: Option<[Side; 2]>,
}

/// A side of a [`Stadium`]'s band: a point of it, its y-range and dx/dy (none when level: a
/// level side bounds no row's extent that the end disks do not).
struct Side {
    p: DVec2,
    ylo: f64,
    yhi: f64,
    slope: Option<f64>,
}

impl Stadium {
    fn new(a: DVec2, b: DVec2, r: f64) -> Self {
        let ab = b - a;
        // (the sides by their slopes: a planner's step reads a hundred rows, and their divisions
        // and square roots were most of its time)
        let sides = (ab.y.abs() > 1e-12 || ab.x.abs() > 1e-12).then(|| {
            let n = DVec2::new(-ab.y, ab.x).normalize() * r;
            [(a - n, b - n), (a + n, b + n)].map(|(p, q)| {
                let slope = ((q.y - p.y).abs() > 1e-12).then(|| (q.x - p.x) / (q.y - p.y));
                Side { p, ylo: q.y.min(p.y), yhi: q.y.max(p.y), slope }
            })
        });
        Stadium { a, b, r, sides }
    }

    /// Half the chord of the disk of radius `r` round `c` on the row at height `y`.
    #[inline]
    fn half(&self, c: DVec2, y: f64) -> Option<f64> {
        let dy = y - c.y;
        let w2 = self.r * self.r - dy * dy;
        (w2 >= 0.0).then(|| w2.sqrt())
    }

    /// Its x-range on the row at height `y`, when the row crosses it: the union of the two end
    /// disks' spans and of the band between them (the stadium is convex, so its extremes on a
    /// row lie on those); with the half chord of the disk at `a` on that row.
    #[inline]
    fn span_and_a(&self, y: f64) -> Option<(f64, f64, Option<f64>)> {
        let (wa, wb) = (self.half(self.a, y), self.half(self.b, y));
        let mut xlo = f64::INFINITY;
        let mut xhi = f64::NEG_INFINITY;
        if let Some(w) = wa {
            (xlo, xhi) = (self.a.x - w, self.a.x + w);
        }
        if let Some(w) = wb {
            (xlo, xhi) = (xlo.min(self.b.x - w), xhi.max(self.b.x + w));
        }
        for side in self.sides.iter().flatten() {
            if let Some(m) = side.slope
                && y >= side.ylo
                && y <= side.yhi
            {
                let x = side.p.x + (y - side.p.y) * m;
                (xlo, xhi) = (xlo.min(x), xhi.max(x));
            }
        }
        (xlo <= xhi).then_some((xlo, xhi, wa))
    }

    /// [`Self::span_and_a`] without the chord at `a`.
    #[inline]
    fn span(&self, y: f64) -> Option<(f64, f64)> {
        self.span_and_a(y).map(|(lo, hi, _)| (lo, hi))
    }
}

/// The XY stadium of a straight move (none for an arc).
fn stadium_of(path: &Path, rho: f64) -> Option<Stadium> {
    match path {
        Path::Line { a, b } => Some(Stadium::new(a.truncate(), b.truncate(), rho)),
        Path::Arc(_) => None,
    }
}

/// The columns `i0..=i1` a scan of the row `j` must visit for a path within `rho` (its box's
/// columns, narrowed for a straight move to its stadium and a cell to spare either side: a
/// long diagonal link would otherwise scan its whole bounding box, millions of cells).
fn row_columns(grid: &Grid, st: Option<&Stadium>, j: usize, i0: usize, i1: usize) -> Option<(usize, usize)> {
    let Some(st) = st else { return Some((i0, i1)) };
    let y = grid.y0 + (j as f64 + 0.5) * grid.res;
    let (lo, hi) = st.span(y)?;
    let lo = floor_i((lo - grid.x0) / grid.res - 1.5).max(i0 as i64);
    let hi = ceil_i((hi - grid.x0) / grid.res + 0.5).min(i1 as i64);
    (lo <= hi).then_some((lo as usize, hi as usize))
}

/// The columns of row `j` whose cell centres lie within `rho` of `c` (`None` when none may).
#[inline]
fn disk_columns(grid: &Grid, c: DVec2, rho: f64, j: usize) -> Option<(i64, i64)> {
    let dy = grid.y0 + (j as f64 + 0.5) * grid.res - c.y;
    let w2 = rho * rho - dy * dy;
    if w2 <= 0.0 {
        return None;
    }
    let w = w2.sqrt();
    let l = ceil_i((c.x - w - grid.x0) / grid.res - 0.5);
    let h = floor_i((c.x + w - grid.x0) / grid.res - 0.5);
    (l <= h).then_some((l, h))
}

/// Messages the replay sends the exact model's thread at a time.
const FEED_CHUNK: usize = 2048;

/// The replay's side of the exact model's thread ([`super::exact::serve`]).
#[derive(Debug)]
struct ExactFeed {
    tx: std::sync::mpsc::SyncSender<Vec<ToExact>>,
    pending: Vec<ToExact>,
    /// (in a mutex only so that the simulator stays shareable between threads)
    answers: std::sync::Mutex<std::sync::mpsc::Receiver<Vec<f64>>>,
}

/// The feed of a replay in progress; a copy of the simulator has none.
#[derive(Debug, Default)]
struct FeedSlot(Option<ExactFeed>);

impl Clone for FeedSlot {
    fn clone(&self) -> Self {
        FeedSlot(None)
    }
}

impl ExactFeed {
    fn send(&mut self, m: ToExact) {
        self.pending.push(m);
        if self.pending.len() >= FEED_CHUNK {
            self.flush();
        }
    }

    fn flush(&mut self) {
        let chunk = std::mem::replace(&mut self.pending, Vec::with_capacity(FEED_CHUNK));
        // (the thread ends only when this side is dropped, or by a panic the replay re-raises)
        let _ = self.tx.send(chunk);
    }
}

/// The raster simulator.
#[derive(Debug, Clone)]
pub struct RasterSim {
    /// The grid.
    pub grid: Grid,
    r: f64,
    tol: f64,
    eps: f64,
    ring_delta: f64,
    sample_step: f64,
    s: Vec<f32>,
    /// The heights the cuts surely reached: a cell is lowered here only by a cut whose disk
    /// holds the whole cell, not just its centre. Where several sweeps meet, a speck of
    /// material narrower than a cell can stand between them although every cell centre near
    /// it was cut (`s` then reads it as cut); rapids are checked against these heights, so
    /// that they never pass through such a speck.
    sure: Vec<f32>,
    /// Half the diagonal of a cell (the farthest a point of a cell lies from its centre).
    half_diag: f64,
    /// Where the last [`RasterSim::cut`] ended, and its z, when it was flat: every cell
    /// within the tool's radius of that point (the radius less half a cell's diagonal where
    /// `sure` is kept) then stands no higher than that z.
    last_flat_end: Option<(DVec2, f32)>,
    s0: Vec<f32>,
    p: Vec<f32>,
    /// Initial cell states (see [`state`]).
    pub state: Vec<u8>,
    reach: Vec<bool>,
    circ: Vec<DVec2>,
    /// The same offsets in cells.
    circ_cells: Vec<DVec2>,
    /// The same offsets as a step in the row-major cell index and the two thresholds on the
    /// centre's position within its cell that move it one cell on (see [`RingCell`]).
    circ_index: Vec<RingCell>,
    /// How far, in cells, the ring reaches from its centre's cell (rounded up, plus one).
    circ_reach: f64,
    exact: ExactModel,
    /// During a replay, the channel to the thread that holds the exact model (`exact` is then
    /// an empty stand-in).
    feed: FeedSlot,
    /// Every how many samples of a move the exact engagement is measured whatever the pixels
    /// read (1: at every sample; see [`ExactModel::engagements_guided`]).
    exact_stride: usize,
    keep: Area,
    keep_edges: EdgeIndex,
    part_top_eff: f64,
    floor_eff: f64,
    /// Record cuts for exact engagement (off for planning-only models).
    pub track_exact: bool,
    /// How much smaller than the tool [`Self::cut`] cuts (0 but in a planner's model): a
    /// planner whose program is written with its coordinates rounded must not count as cut a
    /// cell the written program leaves by the rounding (a rapid at depth was once planned
    /// through such a cell, 0.2 µm outside the written moves' reach).
    pub cut_shrink: f64,
    /// Level whose reachable material is counted in `reach_left` (see [`Self::begin_level`]).
    level_thr: f32,
    reach_left: usize,
    /// Cells (i0, i1, j0, j1) whose material at the level was cleared since the last
    /// [`RasterSim::take_dirty`].
    dirty: Option<(usize, usize, usize, usize)>,
    /// Highest material per block of `BLOCK`×`BLOCK` cells by the heights links are checked
    /// against (so an upper bound of the heights too), and how many cells of the block stand at that height
    /// (the block is read again when the last of them is lowered): lets
    /// [`RasterSim::max_height_near`] skip whole blocks.
    bmax: Vec<f32>,
    bcnt: Vec<u32>,
    nbx: usize,
    /// Highest protected height per block (the part never changes): lets the gouge test skip
    /// the blocks the tool passes high above the part.
    pmax: Vec<f32>,
}

/// Side of the blocks of [`RasterSim::max_height_near`], cells.
const BLOCK: usize = 8;

impl RasterSim {
    /// Builds the model of `job` for its tool.
    pub fn new(job: &Job, regions: &Regions, opts: &SimOptions) -> Result<Self> {
        let r = job.radius();
        let grid = Self::grid_for(job, &regions.keep, opts)?;
        let res = grid.res;
        let stock_mask = grid.rasterize(&job.stock);
        let part_mask = grid.rasterize(&job.part);
        let fix_mask = grid.rasterize(&job.fixtures);
        let keep_mask = grid.rasterize(&regions.keep);
        let reach = grid.rasterize(&regions.reachable.offset(-opts.tol, crate::model::REGION_TOL));
        let part_top_eff = job.part_top + job.allowance_floor;
        let floor_eff = job.floor + job.allowance_floor;
        // (row by row in parallel: on pocket_islands' 3.9 M cells, filling the arrays — and the
        // first touch of their pages — took 30–40 ms of a 0.8 s plan on one thread)
        let n = grid.len();
        // (zeroed allocations are mapped lazily, so the first touch of each page happens in
        // the parallel fill as well)
        let (mut s0, mut p, mut st) = (vec![0f32; n], vec![0f32; n], vec![0u8; n]);
        s0.par_chunks_mut(grid.nx).zip(p.par_chunks_mut(grid.nx)).zip(st.par_chunks_mut(grid.nx)).enumerate().for_each(
            |(j, ((s0, p), st))| {
                for i in 0..grid.nx {
                    let k = j * grid.nx + i;
                    s0[i] = if stock_mask[k] { job.stock_top as f32 } else { f32::NEG_INFINITY };
                    p[i] = if keep_mask[k] { part_top_eff.max(floor_eff) } else { floor_eff } as f32;
                    st[i] = (u8::from(stock_mask[k]) * state::STOCK)
                        | (u8::from(part_mask[k]) * state::PART)
                        | (u8::from(fix_mask[k]) * state::FIXTURE);
                }
            },
        );
        if let Some(hm) = &opts.heights {
            // (on a grid with the heights' origin and cell, as a z-level's models are, a cell
            // is the heights' cell of the same indices: no lookup of each centre, which was a
            // third of building a level's model)
            let h = hm.grid;
            let aligned = h.x0 == grid.x0 && h.y0 == grid.y0 && h.res == grid.res;
            s0.par_chunks_mut(grid.nx).zip(p.par_chunks_mut(grid.nx)).enumerate().for_each(|(j, (s0, p))| {
                for i in 0..grid.nx {
                    let cell =
                        if aligned { (i < h.nx && j < h.ny).then(|| j * h.nx + i) } else { hm.cell(grid.center(i, j)) };
                    if let Some(k) = cell {
                        s0[i] = s0[i].min(hm.stock[k]);
                        if let Some(hp) = &hm.part {
                            p[i] = p[i].max(hp[k]);
                        }
                    }
                }
            });
        }
        // the circumference of the discretised tool (paper 1 §4.2, eq. 5: D_D = D·p): as many
        // points as the tool image has circumference pixels, on a circle half a pixel outside
        // the tool so that they sit in the first pixels the tool has not swept
        let rp = r / res;
        let ri = rp.ceil() as i32 + 1;
        let inside = |i: i32, j: i32| ((i * i + j * j) as f64) <= rp * rp;
        let mut count = 0usize;
        for j in -ri..=ri {
            for i in -ri..=ri {
                if inside(i, j) && (!inside(i + 1, j) || !inside(i - 1, j) || !inside(i, j + 1) || !inside(i, j - 1)) {
                    count += 1;
                }
            }
        }
        let count = count.max(16);
        let rho = r + 0.5 * res;
        let circ: Vec<DVec2> = (0..count)
            .map(|k| {
                let a = std::f64::consts::TAU * (k as f64 + 0.5) / count as f64;
                DVec2::new(a.cos(), a.sin()) * rho
            })
            .collect();
        let stock_rings: Vec<Vec<DVec2>> = job.stock.rings().cloned().collect();
        let lo_g = DVec2::new(grid.x0, grid.y0);
        let hi_g = lo_g + DVec2::new(grid.nx as f64, grid.ny as f64) * res;
        let exact = ExactModel::new(r, lo_g, hi_g, stock_rings, job.stock_top, 0.05);
        let keep_edges = EdgeIndex::from_area(&regions.keep, (2.0 * r).max(1.0));
        let sample_step = opts.sample_step.unwrap_or(res);
        Ok(Self {
            grid,
            r,
            tol: opts.tol,
            eps: opts.eps,
            ring_delta: opts.ring_delta,
            sample_step,
            s: s0.clone(),
            sure: if opts.sure_links { s0.clone() } else { Vec::new() },
            half_diag: res * std::f64::consts::FRAC_1_SQRT_2,
            last_flat_end: None,
            s0,
            p,
            state: st,
            reach,
            circ_cells: circ.iter().map(|o| *o / res).collect(),
            circ_index: circ.iter().map(|o| RingCell::new(*o / res, grid.nx)).collect(),
            circ_reach: (rho / res).ceil() + 1.0,
            circ,
            exact,
            feed: FeedSlot::default(),
            exact_stride: if opts.exact_every_sample {
                1
            } else {
                // anchors about R/6 apart: the engagement of a smooth cut changes little
                // over that, and the pixels show where it does not (R/12 measured twice the
                // anchors for the same maxima and percentiles on the examples)
                ((r / 6.0) / sample_step).round().clamp(1.0, 16.0) as usize
            },
            keep: regions.keep.clone(),
            keep_edges,
            part_top_eff,
            floor_eff,
            track_exact: true,
            cut_shrink: 0.0,
            level_thr: f32::INFINITY,
            reach_left: 0,
            dirty: None,
            bmax: Vec::new(),
            pmax: Vec::new(),
            bcnt: Vec::new(),
            nbx: 0,
        }
        .with_blocks())
    }

    /// The grid a model of `job` (with `keep` to stay clear of) is built on: the stock and the
    /// part near it, padded by a tool radius and a few cells, aligned to the stock's corner.
    pub fn grid_for(job: &Job, keep: &Area, opts: &SimOptions) -> Result<Grid> {
        let r = job.radius();
        let res = opts.res_for(job.cutting.tool.diameter);
        if !(res.is_finite() && res > 0.0) {
            return Err(Error::setting(Setting::Resolution, format!("{res} mm: the cell size must be positive")));
        }
        let (slo, shi) = job.stock.bounds().ok_or_else(|| Error::job("stock", "the stock outline is empty"))?;
        let (mut lo, mut hi) = (slo, shi);
        if let Some((a, b)) = keep.bounds() {
            // the part can be a large frame: only the part near the stock matters
            let m = DVec2::splat(4.0 * r + 5.0);
            lo = lo.min(a.max(slo - m));
            hi = hi.max(b.min(shi + m));
        }
        let pad = r + 4.0 * res + 1.0;
        let grid = Grid::covering(lo, hi, pad, res, slo);
        if grid.len() > opts.max_cells {
            return Err(Error::setting(
                Setting::Resolution,
                format!("a {}×{} grid at {res} mm is too large; use a coarser cell", grid.nx, grid.ny),
            ));
        }
        Ok(grid)
    }

    /// Fills the block maxima.
    fn with_blocks(mut self) -> Self {
        self.nbx = self.grid.nx.div_ceil(BLOCK);
        let nby = self.grid.ny.div_ceil(BLOCK);
        (self.bmax, self.bcnt) = (0..self.nbx * nby).into_par_iter().map(|b| self.block_max(b)).unzip();
        self.pmax = (0..self.nbx * nby).map(|b| self.block_max_of(&self.p, b).0).collect();
        self
    }

    /// Cells (i0, i1, j0, j1) of block `b`.
    fn block_cells(&self, b: usize) -> (usize, usize, usize, usize) {
        let (bi, bj) = (b % self.nbx, b / self.nbx);
        let (i0, j0) = (bi * BLOCK, bj * BLOCK);
        (i0, (i0 + BLOCK).min(self.grid.nx) - 1, j0, (j0 + BLOCK).min(self.grid.ny) - 1)
    }

    /// Reads the maximum of block `b` and how many cells hold it.
    fn read_block(&mut self, b: usize) {
        (self.bmax[b], self.bcnt[b]) = self.block_max(b);
    }

    /// The maximum of block `b` and how many cells hold it.
    fn block_max(&self, b: usize) -> (f32, u32) {
        self.block_max_of(self.link_heights(), b)
    }

    /// The maximum of the heights `h` over block `b` and how many cells hold it.
    fn block_max_of(&self, h: &[f32], b: usize) -> (f32, u32) {
        let (i0, i1, j0, j1) = self.block_cells(b);
        let mut m = f32::NEG_INFINITY;
        let mut n = 0;
        for j in j0..=j1 {
            for &h in &h[j * self.grid.nx + i0..=j * self.grid.nx + i1] {
                if h > m {
                    m = h;
                    n = 1;
                } else if h == m {
                    n += 1;
                }
            }
        }
        (m, n)
    }

    /// The heights links and rapids are checked against: the surely cut heights when they are
    /// kept, else the heights.
    #[inline]
    fn link_heights(&self) -> &[f32] {
        if self.sure.is_empty() { &self.s } else { &self.sure }
    }

    /// Bytes the cells hold (heights, initial heights, protected heights, states, reach, and
    /// the surely cut heights when kept); the exact model's primitives are not counted.
    pub fn cell_bytes(&self) -> usize {
        self.s.len() * 4
            + self.s0.len() * 4
            + self.p.len() * 4
            + self.state.len()
            + self.reach.len()
            + self.sure.len() * 4
    }

    /// Tool radius.
    pub fn radius(&self) -> f64 {
        self.r
    }

    /// Current stock height at the cell containing `q` (−∞ outside the stock or the grid).
    pub fn height_at(&self, q: DVec2) -> f32 {
        self.grid.cell_of(q).map_or(f32::NEG_INFINITY, |(i, j)| self.s[j * self.grid.nx + i])
    }

    /// Highest material within `rho` of the path (−∞ when none), by the heights links are
    /// checked against (see the field `sure`).
    pub fn max_height_near(&self, path: &Path, rho: f64) -> f32 {
        let (lo, hi) = path.bbox(rho);
        let Some((i0, i1, j0, j1)) = self.grid.range(lo, hi) else { return f32::NEG_INFINITY };
        let mut best = f32::NEG_INFINITY;
        let f = Fast::new(path);
        // block by block: a block below the best so far, or wholly outside, is skipped; one
        // wholly inside gives its maximum; only the blocks on the circle's edge are read cell
        // by cell (the same cells, so the same answer, as reading them all)
        for bj in j0 / BLOCK..=j1 / BLOCK {
            for bi in i0 / BLOCK..=i1 / BLOCK {
                let b = bj * self.nbx + bi;
                if self.bmax[b] <= best {
                    continue;
                }
                let (ci0, ci1, cj0, cj1) = self.block_cells(b);
                let (a, c) = (self.grid.center(ci0, cj0), self.grid.center(ci1, cj1));
                let half = 0.5 * (c - a).length() + 1e-9;
                let d = f.distance(0.5 * (a + c));
                if d - half > rho {
                    continue;
                }
                let (ci0, ci1, cj0, cj1) = (ci0.max(i0), ci1.min(i1), cj0.max(j0), cj1.min(j1));
                if d + half <= rho && (ci0, ci1, cj0, cj1) == self.block_cells(b) {
                    best = self.bmax[b];
                    continue;
                }
                for j in cj0..=cj1 {
                    for i in ci0..=ci1 {
                        let h = self.link_heights()[j * self.grid.nx + i];
                        if h > best && f.distance(self.grid.center(i, j)) <= rho {
                            best = h;
                        }
                    }
                }
            }
        }
        best
    }

    /// True when no material stands more than `eps` above the tip anywhere the tool passes
    /// along `path` (checked with the full radius plus `margin`, against the heights links are
    /// checked against: see the field `sure`).
    pub fn is_clear(&self, path: &Path, margin: f64) -> bool {
        let mut clear = true;
        let rho = self.r + margin;
        visit_above(&self.grid, self.link_heights(), Some((&self.bmax, self.nbx)), path, rho, self.eps, |_, _, _| {
            clear = false;
            false
        });
        clear
    }

    /// A straight move that leaves the tool's present position, checked with the radius plus
    /// `margin`: material the tool already touches at the start (within that radius of the
    /// start, standing above its tip) does not count. `None` when the move reaches any other
    /// material; otherwise how far along it (mm) the tool has left the touched material
    /// behind — from there on it touches nothing (0 when it touches nothing at all), so the
    /// rest can be a rapid. Read like [`Self::is_clear`].
    pub fn leaving_distance(&self, a: DVec3, b: DVec3, margin: f64) -> Option<f64> {
        let rho = self.r + margin;
        let path = Path::Line { a, b };
        let (a2, b2) = (a.truncate(), b.truncate());
        let len = (b2 - a2).length();
        let u = if len > 1e-12 { (b2 - a2) / len } else { DVec2::ZERO };
        let mut clear = true;
        let mut t: f64 = 0.0;
        let h = self.link_heights();
        visit_above(&self.grid, h, Some((&self.bmax, self.nbx)), &path, rho, self.eps, |k, q, _| {
            if (q - a2).length() <= rho && h[k] as f64 > a.z + self.eps {
                // the points of the line within `rho` of q end at its projection plus the
                // half chord
                let d = q - a2;
                let along = d.dot(u);
                let perp2 = (d.length_squared() - along * along).max(0.0);
                t = t.max(along + (rho * rho - perp2).max(0.0).sqrt());
                return true;
            }
            clear = false;
            false
        });
        clear.then(|| if t > 0.0 { (t + 1e-6).min(len) } else { 0.0 })
    }

    /// Exact distance from the XY path to the part/fixture boundary (capped at `max`), or 0
    /// when the path starts inside them.
    pub fn keep_distance(&self, path: &Path, max: f64) -> f64 {
        super::sweep::keep_distance(&self.keep, &self.keep_edges, path, max)
    }

    /// Cuts the path into the material (and into the surely cut heights, when they are kept,
    /// by the radius less half a cell's diagonal).
    pub fn cut(&mut self, path: &Path) {
        let r = self.r - self.cut_shrink;
        let rs = r - self.half_diag;
        let sure = !self.sure.is_empty();
        let (lo, hi) = path.bbox(r);
        if let Some((i0, i1, j0, j1)) = self.grid.range(lo, hi) {
            let (z0, z1) = path.z_range();
            let zmin = z0.min(z1) as f32;
            let flat = path.is_flat().then(|| (Fast::new(path), z0 as f32));
            let slope = flat.is_none().then(|| (Reach::new(path, r), sure.then(|| Reach::new(path, rs))));
            let st = stadium_of(path, r);
            // The cells within reach of where the last flat cut ended stand no higher than its
            // z: when that is not above this path's lowest point, the height test below would
            // pass over every one of them, and a row is scanned on either side of that disk
            // instead (a planned program's moves are short, and most of each move's stadium
            // is the disk the move before it cut: the same cells lowered, a fraction of the
            // reads). The disk is taken a micrometre smaller than the reach, for rounding.
            let before = self
                .last_flat_end
                .filter(|(_, z)| *z <= zmin)
                .map(|(e, _)| (e, if sure { rs } else { r } - 1e-6))
                .filter(|(_, rho)| *rho > 0.0);
            for j in j0..=j1 {
                let Some((i0, i1)) = row_columns(&self.grid, st.as_ref(), j, i0, i1) else { continue };
                let runs = match before.and_then(|(e, rho)| disk_columns(&self.grid, e, rho, j)) {
                    Some((l, h)) => [(i0 as i64, (i1 as i64).min(l - 1)), ((i0 as i64).max(h + 1), i1 as i64)],
                    None => [(i0 as i64, i1 as i64), (1, 0)],
                };
                for (i0, i1) in
                    runs.into_iter().filter(|(a, b)| a <= b).flat_map(|(a, b)| block_runs(a as usize, b as usize))
                {
                    // nothing in a block stands above the path's lowest point: nothing to cut
                    if self.bmax[(j / BLOCK) * self.nbx + i0 / BLOCK] <= zmin {
                        continue;
                    }
                    for i in i0..=i1 {
                        let k = j * self.grid.nx + i;
                        // (sure >= s everywhere: nothing to do when the path is not below it;
                        // no point of the path is lower than `zmin`)
                        let h = self.link_heights()[k];
                        if h == f32::NEG_INFINITY || h <= zmin {
                            continue;
                        }
                        let q = self.grid.center(i, j);
                        if let Some((f, z)) = &flat {
                            let d = f.distance(q);
                            if d <= r {
                                self.lower(k, *z);
                            }
                            if sure && d <= rs {
                                self.lower_sure(k, *z);
                            }
                        } else if let Some((reach, reach_sure)) = &slope {
                            if let Some(z) = reach.zmin(q) {
                                self.lower(k, z as f32);
                            }
                            if let Some(z) = reach_sure.as_ref().and_then(|rs| rs.zmin(q)) {
                                self.lower_sure(k, z as f32);
                            }
                        }
                    }
                }
            }
        }
        self.last_flat_end = path.is_flat().then(|| (path.at(1.0).truncate(), path.z_range().0 as f32));
        if self.track_exact {
            match &mut self.feed.0 {
                Some(f) => f.send(ToExact::Add(*path)),
                None => self.exact.add(path),
            }
        }
    }

    /// Lowers cell `k` to `z`, keeping the count of reachable material of the level.
    #[inline]
    fn lower(&mut self, k: usize, z: f32) {
        let h = self.s[k];
        if z < h {
            if h > self.level_thr && z <= self.level_thr {
                if self.reach[k] {
                    self.reach_left -= 1;
                }
                let (i, j) = (k % self.grid.nx, k / self.grid.nx);
                self.dirty = Some(match self.dirty {
                    None => (i, i, j, j),
                    Some((i0, i1, j0, j1)) => (i0.min(i), i1.max(i), j0.min(j), j1.max(j)),
                });
            }
            self.s[k] = z;
            if self.sure.is_empty() {
                self.lowered_block(k, h);
            }
        }
    }

    /// Cell `k` of the heights the block maxima follow was lowered from `h`.
    #[inline]
    fn lowered_block(&mut self, k: usize, h: f32) {
        let b = (k / self.grid.nx / BLOCK) * self.nbx + (k % self.grid.nx) / BLOCK;
        if h == self.bmax[b] {
            self.bcnt[b] -= 1;
            if self.bcnt[b] == 0 {
                self.read_block(b);
            }
        }
    }

    /// Lowers cell `k` of the surely cut heights to `z`, keeping the block maxima.
    #[inline]
    fn lower_sure(&mut self, k: usize, z: f32) {
        let h = self.sure[k];
        if z < h {
            self.sure[k] = z;
            self.lowered_block(k, h);
        }
    }

    /// The box of cells (i0, i1, j0, j1) whose material at the level was cleared since the last
    /// call (or since [`RasterSim::begin_level`]), and forgets it.
    pub fn take_dirty(&mut self) -> Option<(usize, usize, usize, usize)> {
        self.dirty.take()
    }

    /// Starts counting the reachable material that stands above `z` (plus `eps`): the cells the
    /// tool can reach at this level and must still clear.
    pub fn begin_level(&mut self, z: f64) {
        self.level_thr = (z + self.eps) as f32;
        self.dirty = None;
        let thr = self.level_thr;
        self.reach_left = self.s.iter().zip(&self.reach).filter(|(h, r)| **r && **h > thr).count();
    }

    /// Reachable cells still standing above the level given to [`Self::begin_level`].
    pub fn reach_left(&self) -> usize {
        self.reach_left
    }

    /// Cell size, mm.
    pub fn res(&self) -> f64 {
        self.grid.res
    }

    /// Cuts a horizontal step from `a` to `b` at height `z` — the inner loop of adaptive
    /// clearing. Only the new part of the sweep is visited: on each grid row, the cells of the
    /// tool disk at `b` and of the stadium's sides, minus those of the disk at `a` that the
    /// previous step already cut. Returns how many cells it lowered.
    pub fn cut_step(&mut self, a: DVec2, b: DVec2, z: f64) -> usize {
        self.cut_step_r(a, b, z, self.r)
    }

    /// [`Self::cut_step`] with the tool radius `r` (a planner that emits its path within a
    /// tolerance cuts by the radius less that tolerance, so that it never counts as cut what the
    /// emitted program leaves).
    pub fn cut_step_r(&mut self, a: DVec2, b: DVec2, z: f64, r: f64) -> usize {
        let count = self.step_layer(a, b, z, r, false);
        if !self.sure.is_empty() {
            self.step_layer(a, b, z, r - self.half_diag, true);
        }
        count
    }

    /// The row scan of [`Self::cut_step_r`] with radius `r`, on the heights (`sure` false) or
    /// on the surely cut heights.
    fn step_layer(&mut self, a: DVec2, b: DVec2, z: f64, r: f64, sure: bool) -> usize {
        let mut count = 0;
        if r <= 0.0 {
            return 0;
        }
        let res = self.grid.res;
        let zf = z as f32;
        let lo_y = a.y.min(b.y) - r;
        let hi_y = a.y.max(b.y) + r;
        let (nx, ny) = (self.grid.nx as i64, self.grid.ny as i64);
        let j0 = ceil_i(((lo_y - self.grid.y0) / res) - 0.5).max(0);
        let j1 = floor_i(((hi_y - self.grid.y0) / res) - 0.5).min(ny - 1);
        let ab = b - a;
        let l2 = ab.length_squared();
        let inv = if l2 > 0.0 { 1.0 / l2 } else { 0.0 };
        let (x0, inv_res) = (self.grid.x0, 1.0 / res);
        // (a column's fractional index by a product: see [`Stadium::new`])
        let col = |x: f64| (x - x0) * inv_res - 0.5;
        let st = Stadium::new(a, b, r);
        for j in j0..=j1 {
            let y = self.grid.y0 + (j as f64 + 0.5) * res;
            // x-range of the stadium on this row
            let Some((xlo, xhi, wa)) = st.span_and_a(y) else { continue };
            let i0 = ceil_i(col(xlo)).max(0);
            let i1 = floor_i(col(xhi)).min(nx - 1);
            // cells inside the disk at `a` were cut by the previous step (or are about to be
            // skipped by the height test below anyway): the row is scanned on either side
            let (l, h) = wa.map_or((1, 0), |w| (ceil_i(col(a.x - w)) + 1, floor_i(col(a.x + w)) - 1));
            let runs = if l <= h { [(i0, i1.min(l - 1)), (i0.max(h + 1), i1)] } else { [(i0, i1), (1, 0)] };
            let row = j as usize * self.grid.nx;
            for (ra, rb) in runs {
                for i in ra..=rb {
                    let k = row + i as usize;
                    let above = if sure { self.sure[k] > zf } else { self.s[k] > zf };
                    if above {
                        let q = DVec2::new(x0 + (i as f64 + 0.5) * res, y);
                        let t = ((q - a).dot(ab) * inv).clamp(0.0, 1.0);
                        if (a + ab * t - q).length_squared() <= r * r {
                            if sure {
                                self.lower_sure(k, zf);
                            } else {
                                self.lower(k, zf);
                            }
                            count += 1;
                        }
                    }
                }
            }
        }
        count
    }

    /// Fills `out[i]` with whether material stands more than `eps` above `z` at `c + ring[i]`
    /// (the ring of [`Self::ring`]).
    pub fn ring_material(&self, c: DVec2, z: f64, out: &mut Vec<bool>) {
        let zq = (z + self.eps) as f32;
        out.clear();
        for off in &self.circ {
            let q = c + *off;
            out.push(self.grid.cell_of(q).is_some_and(|(i, j)| self.s[j * self.grid.nx + i] > zq));
        }
    }

    /// The tool circumference sampled like the pixel method: offsets from the tool centre,
    /// counter-clockwise from +X, half a cell outside the tool.
    pub fn ring(&self) -> &[DVec2] {
        &self.circ
    }

    /// Front-half engagement (degrees) by the pixel ring at `c` moving along `dir`, against the
    /// stock as it is (no exclusion of the current move: for planning, where the stock is cut
    /// step by step).
    ///
    /// Where the tool runs within half a pixel of a wall, the ring (half a pixel outside the
    /// tool) reads the pixels beyond the wall over a wedge of about 2·acos(R / (R + res/2))
    /// round it (16° at res = D/100): outside a pocket's stock it would count no material
    /// there although the strip between the tool and the wall is uncut (contour milling along
    /// a wall read 5–8° low, and up to 25° low at an inside corner, against the exact
    /// engagement), and on a part inside the stock it would count the part. A ring point that
    /// falls on the part or outside the stock is therefore read half a pixel inside the tool
    /// instead (within 1–2° of the exact engagement along walls).
    pub fn front_engagement(&self, c: DVec2, z: f64, dir: DVec2) -> f64 {
        let zq = (z + self.eps) as f32;
        let inward = (self.r - 0.5 * self.grid.res) / (self.r + 0.5 * self.grid.res);
        let hit = self.ring_count(c, dir, |k, cell| {
            let off = self.circ[k];
            off.dot(dir) >= 0.0
                && cell.is_some_and(|i| {
                    if self.p[i] > zq || self.s[i] == f32::NEG_INFINITY {
                        // the ring, half a pixel outside the tool, has crossed into the part
                        // or out of the stock: read half a pixel inside the tool instead (see
                        // above)
                        self.grid.cell_of(c + off * inward).is_some_and(|(i, j)| self.s[j * self.grid.nx + i] > zq)
                    } else {
                        self.s[i] > zq
                    }
                })
        });
        360.0 * hit as f64 / self.circ.len() as f64
    }

    /// Area (mm²) of the reachable material standing more than `eps` above `z` within `rho` of
    /// `c` (cells by their centres).
    pub fn material_area_near(&self, c: DVec2, z: f64, rho: f64) -> f64 {
        let at = Path::Line { a: c.extend(z), b: c.extend(z) };
        let mut n = 0usize;
        visit_above(&self.grid, &self.s, Some((&self.bmax, self.nbx)), &at, rho, self.eps, |k, _, _| {
            n += usize::from(self.reach[k]);
            true
        });
        n as f64 * self.grid.res * self.grid.res
    }

    /// Material standing more than `eps` above `z` at `q`.
    pub fn material_at(&self, q: DVec2, z: f64) -> bool {
        self.grid.cell_of(q).is_some_and(|(i, j)| self.s[j * self.grid.nx + i] > (z + self.eps) as f32)
    }

    /// Cells of the part and fixtures grown by the allowance (where the protected height is above
    /// the floor).
    pub fn keep_mask(&self) -> Vec<bool> {
        let fl = self.floor_eff as f32;
        self.p.iter().map(|p| *p > fl).collect()
    }

    /// Cells the tool can reach.
    pub fn reach_mask(&self) -> &[bool] {
        &self.reach
    }

    /// Engagement by paper 1 eq. 4: the share of the tool's circumference pixels that hold
    /// material more than `eps` above the tip, times 360°. The circumference is sampled with
    /// as many points as the discretised tool has circumference pixels, half a pixel outside the
    /// tool, each reading the pixel it falls in; only points ahead of the motion count, and
    /// points the current move has already swept (`current`) are not material.
    ///
    /// Its error is that of the pixels: where the ring runs along a wall cut at exactly R it reads
    /// a wedge of about acos(R / (R + res/2)) of that wall on the wrong side (8° at the default
    /// res = D/100), so a full-width cut reads 170–175° and retracing a cut reads ~15°. Straight
    /// cuts at 10–50 % stepover read within 2° at the default res. The exact method
    /// ([`Self::engagement_exact`]) has no such error and is what the report judges by.
    pub fn engagement_pixel(&self, c: DVec2, z: f64, dir: DVec2, current: Option<&Path>) -> f64 {
        let zq = (z + self.eps) as f32;
        let current = current.map(Fast::new);
        let hit = self.ring_count(c, dir, |k, cell| {
            cell.is_some_and(|i| self.s[i] > zq)
                && self.circ[k].dot(dir) >= 0.0
                && current.as_ref().is_none_or(|p| p.distance(c + self.circ[k]) > self.r)
        });
        360.0 * hit as f64 / self.circ.len() as f64
    }

    /// How many points of the engagement ring ahead of `dir` (within a quarter turn of it, with
    /// a point to spare at each end) `hit(k, cell)` counts, given each point's index and cell
    /// (none off the grid), found as [`Grid::cell_of`] finds it but from the centre's position in
    /// cells plus the point's offset in cells (no division per point).
    fn ring_count(&self, c: DVec2, dir: DVec2, hit: impl Fn(usize, Option<usize>) -> bool) -> usize {
        // the points stand at angles τ(k + ½)/n, so those ahead are one run of indices
        let n = self.circ.len();
        let step = std::f64::consts::TAU / n as f64;
        let mid = dir.y.atan2(dir.x) / step - 0.5;
        let quarter = 0.25 * n as f64;
        let (lo, hi) = ((mid - quarter).floor() as i64 - 1, (mid + quarter).ceil() as i64 + 1);
        let (lo, hi) = if hi - lo + 1 >= n as i64 { (0, n as i64 - 1) } else { (lo, hi) };
        // the run lo..=hi of indices modulo n, as one or two ranges
        let n = n as i64;
        let (a, b) = if lo < 0 { (lo + n, hi + n) } else { (lo, hi) };
        let run = if b >= n { [a..n, 0..b - n + 1] } else { [a..b + 1, 0..0] };
        let ks = run.into_iter().flat_map(|r| r.start as usize..r.end as usize);
        let g = &self.grid;
        let (fx0, fy0) = ((c.x - g.x0) / g.res, (c.y - g.y0) / g.res);
        let reach = self.circ_reach;
        if fx0 >= reach && fy0 >= reach && fx0 + reach < g.nx as f64 && fy0 + reach < g.ny as f64 {
            // the whole ring lies on the grid (nearly always): each point's cell is the
            // centre's cell plus a fixed step, one on where the centre's place in its cell
            // passes the point's threshold — no conversion or bounds test per point
            let (ci, cj) = (fx0 as usize, fy0 as usize);
            let (fx, fy) = (fx0 - ci as f64, fy0 - cj as f64);
            let base = (cj * g.nx + ci) as isize;
            let nx = g.nx as isize;
            ks.filter(|&k| {
                let rc = &self.circ_index[k];
                hit(k, Some((base + rc.step + (fx >= rc.tx) as isize + if fy >= rc.ty { nx } else { 0 }) as usize))
            })
            .count()
        } else {
            ks.filter(|&k| {
                let (fx, fy) = (fx0 + self.circ_cells[k].x, fy0 + self.circ_cells[k].y);
                let (i, j) = (fx as usize, fy as usize);
                hit(k, (fx >= 0.0 && fy >= 0.0 && i < g.nx && j < g.ny).then(|| j * g.nx + i))
            })
            .count()
        }
    }

    /// Exact engagement (see [`ExactModel`]).
    pub fn engagement_exact(&mut self, c: DVec2, z: f64, dir: DVec2, current: Option<&Path>) -> f64 {
        self.exact.engagement(c, z, dir, self.r + self.ring_delta, self.eps, current)
    }

    /// Highest material strictly within `R - tol` of the tool standing at `c` (for plunges).
    fn material_under(&self, c: DVec2, z: f64) -> bool {
        let rr = self.r - self.tol;
        let Some((i0, i1, j0, j1)) = self.grid.range(c - DVec2::splat(rr), c + DVec2::splat(rr)) else { return false };
        for j in j0..=j1 {
            for i in i0..=i1 {
                if (self.grid.center(i, j) - c).length() <= rr && self.s[j * self.grid.nx + i] > (z + self.eps) as f32 {
                    return true;
                }
            }
        }
        false
    }

    /// Gouge depth of a move (0 when clean): grid test against the protected heights and exact
    /// test against the part polygons.
    fn gouge_depth(&self, path: &Path) -> (f64, DVec3) {
        let rr = self.r - self.tol;
        let mut worst = 0.0f64;
        let mut at = path.at(0.0);
        // a cell of a 2.5D job's walls (the part and fixtures grown by the allowance, standing
        // to the part's top) in the tool's column is left by moving the tool up by its height
        // over the tip or sideways by the rim's overlap: the smaller is how deep the tool is in
        // (a rim that grazes a wall is not in it by the wall's whole height); the floor and a
        // mesh part's surface are gouged from above
        let wall = (self.part_top_eff - 1e-6) as f32;
        let walls = !self.keep_edges.is_empty();
        visit_above(&self.grid, &self.p, Some((&self.pmax, self.nbx)), path, rr, self.tol, |k, q, z| {
            let mut d = self.p[k] as f64 - z;
            if walls && self.p[k] >= wall {
                d = d.min(self.r - path.distance(q));
            }
            if d > worst {
                worst = d;
                at = DVec3::new(q.x, q.y, z);
            }
            true
        });
        // exact radial test where the tip is below the part top
        let (z0, z1) = path.z_range();
        let zlim = self.part_top_eff - self.tol;
        if z0.min(z1) < zlim && !self.keep_edges.is_empty() {
            let (t0, t1) = if (z1 - z0).abs() < 1e-12 {
                (0.0, 1.0)
            } else {
                let tz = (zlim - z0) / (z1 - z0);
                if z1 < z0 { (tz.clamp(0.0, 1.0), 1.0) } else { (0.0, tz.clamp(0.0, 1.0)) }
            };
            let sub = path.sub(t0, t1);
            let d = self.keep_distance(&sub, self.r);
            if d < self.r - self.tol {
                let radial = self.r - d;
                if radial > worst {
                    worst = radial;
                    at = sub.at(0.0);
                }
            }
        }
        (worst, at)
    }

    /// Replays a toolpath: cuts it, samples engagement, finds gouges, collisions and plunges.
    /// `progress` is called with the fraction done.
    ///
    /// The exact model moves to a thread of its own for the replay ([`super::exact::serve`]):
    /// it records the cuts and measures the exact engagement while this thread cuts the cells
    /// and reads the pixels, with the same answers as one after the other.
    pub fn replay(&mut self, tp: &Toolpath, progress: &mut dyn FnMut(f64)) -> Replay {
        self.replay_carrying(tp, progress, &mut super::replay::Carry::default())
    }

    /// [`RasterSim::replay`] of a piece of a program, `carry` from the piece before it.
    pub(crate) fn replay_carrying(
        &mut self,
        tp: &Toolpath,
        progress: &mut dyn FnMut(f64),
        carry: &mut super::replay::Carry,
    ) -> Replay {
        self.replay_segments(tp.segments().map(|(from, m)| (from, *m)), tp.moves.len(), progress, carry)
    }

    /// [`RasterSim::replay_carrying`] of the moves `segments` gives as they come (each with
    /// where it starts; about `nmoves` of them): a program replayed while it is planned.
    pub(crate) fn replay_segments(
        &mut self,
        segments: impl Iterator<Item = (DVec3, crate::toolpath::Move)>,
        nmoves: usize,
        progress: &mut dyn FnMut(f64),
        carry: &mut super::replay::Carry,
    ) -> Replay {
        let stand_in = ExactModel::new(self.r, DVec2::ZERO, DVec2::ONE, Vec::new(), 0.0, 1.0);
        let model = std::mem::replace(&mut self.exact, stand_in);
        let (tx, rx) = std::sync::mpsc::sync_channel(8);
        let (answers_tx, answers) = std::sync::mpsc::channel();
        let stride = self.exact_stride;
        let (replayed, model) = std::thread::scope(|s| {
            let worker = s.spawn(move || super::exact::serve(model, rx, answers_tx, stride));
            self.feed.0 = Some(ExactFeed {
                tx,
                pending: Vec::with_capacity(FEED_CHUNK),
                answers: std::sync::Mutex::new(answers),
            });
            let replayed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                super::replay::run_segments(self, segments, nmoves, progress, carry)
            }));
            // (dropping the sender ends the thread, also after a panic)
            self.feed.0 = None;
            (replayed, worker.join())
        });
        match (replayed, model) {
            (Ok(rp), Ok(model)) => {
                self.exact = model;
                rp
            }
            (Err(e), _) | (_, Err(e)) => std::panic::resume_unwind(e),
        }
    }

    /// Cuts a whole move, a long one in pieces of at most four radii (keeps the cell windows
    /// of [`RasterSim::cut`] small).
    pub fn cut_move(&mut self, path: &Path) {
        let pieces = (path.xy_length() / (4.0 * self.r)).ceil().max(1.0) as usize;
        for k in 0..pieces {
            self.cut(&path.sub(k as f64 / pieces as f64, (k + 1) as f64 / pieces as f64));
        }
    }

    /// Cuts `moves`, the first from `from`, one after the other (no measurements).
    pub fn cut_moves(&mut self, from: DVec3, moves: &[Move]) {
        let mut at = from;
        for m in moves {
            self.cut_move(&Path::of(at, m));
            at = m.to;
        }
    }

    /// Reachable material left standing more than `tol` above the floor.
    pub fn rest(&self) -> Rest {
        let cell = self.grid.res * self.grid.res;
        let mut r = Rest::default();
        let fl = self.floor_eff as f32 + self.tol as f32;
        for k in 0..self.s.len() {
            if !self.reach[k] {
                continue;
            }
            r.reachable_mm2 += cell;
            if self.s[k] > fl {
                r.area_mm2 += cell;
                let t = (self.s[k] - self.floor_eff as f32) as f64;
                r.volume_mm3 += t * cell;
                r.max_thickness_mm = r.max_thickness_mm.max(t);
            }
        }
        r
    }

    /// Heights of what must stay (row-major): the part's top, or the floor where there is no
    /// part.
    pub fn part_heights(&self) -> &[f32] {
        &self.p
    }

    /// Current stock heights (row-major, −∞ where there is no stock).
    pub fn heights(&self) -> &[f32] {
        &self.s
    }

    /// Stock heights before the first cut (row-major, −∞ where there is no stock).
    pub fn initial_heights(&self) -> &[f32] {
        &self.s0
    }

    /// Volume cut away so far, mm³ (what a replay reports as its removed volume).
    pub fn removed_volume(&self) -> f64 {
        <Self as super::replay::Engine>::removed_volume(self)
    }

    /// The reachable material standing more than `eps` above `z`, as an area (rows of cells
    /// merged into rectangles).
    pub fn material_area(&self, z: f64) -> Area {
        let thr = (z + self.eps) as f32;
        let res = self.grid.res;
        let mut rings = Vec::new();
        for j in 0..self.grid.ny {
            let row = j * self.grid.nx;
            let y0 = self.grid.y0 + j as f64 * res;
            let mut i = 0;
            while i < self.grid.nx {
                if self.reach[row + i] && self.s[row + i] > thr {
                    let start = i;
                    while i < self.grid.nx && self.reach[row + i] && self.s[row + i] > thr {
                        i += 1;
                    }
                    let x0 = self.grid.x0 + start as f64 * res;
                    let x1 = self.grid.x0 + i as f64 * res;
                    rings.push(vec![
                        DVec2::new(x0, y0),
                        DVec2::new(x1, y0),
                        DVec2::new(x1, y0 + res),
                        DVec2::new(x0, y0 + res),
                    ]);
                } else {
                    i += 1;
                }
            }
        }
        Area::from_rings(&rings, crate::geom::area::Fill::NonZero)
    }

    /// Centres of the cells of rest material (reachable and standing), for pictures.
    pub fn rest_cells(&self) -> Vec<DVec2> {
        let fl = self.floor_eff as f32 + self.tol as f32;
        let mut out = Vec::new();
        for j in 0..self.grid.ny {
            for i in 0..self.grid.nx {
                let k = j * self.grid.nx + i;
                if self.reach[k] && self.s[k] > fl {
                    out.push(self.grid.center(i, j));
                }
            }
        }
        out
    }
}

/// A point of the engagement ring as a step on the grid: with the ring's centre in cell
/// `(ci, cj)` at `(fx, fy)` within it (each in [0, 1)), the point at offset `o` (in cells)
/// falls in cell `(ci + ⌊o.x⌋ + [fx ≥ tx], cj + ⌊o.y⌋ + [fy ≥ ty])`, since
/// `⌊ci + fx + o.x⌋ = ci + ⌊o.x⌋ + ⌊fx + frac(o.x)⌋`.
#[derive(Debug, Clone, Copy)]
struct RingCell {
    /// `⌊o.y⌋ · nx + ⌊o.x⌋`.
    step: isize,
    /// `1 − frac(o.x)`.
    tx: f64,
    /// `1 − frac(o.y)`.
    ty: f64,
}

impl RingCell {
    fn new(o: DVec2, nx: usize) -> Self {
        let (ix, iy) = (o.x.floor(), o.y.floor());
        RingCell { step: iy as isize * nx as isize + ix as isize, tx: 1.0 - (o.x - ix), ty: 1.0 - (o.y - iy) }
    }
}

impl super::replay::Engine for RasterSim {
    fn radius(&self) -> f64 {
        self.r
    }

    fn spacing(&self) -> f64 {
        self.grid.res
    }

    fn sample_step(&self) -> f64 {
        self.sample_step
    }

    fn rapid_depth(&self, path: &Path, to: DVec3) -> (f64, DVec3) {
        let mut worst = 0.0f64;
        let mut at = to;
        visit_above(&self.grid, &self.s, Some((&self.bmax, self.nbx)), path, self.r - self.tol, self.eps, |k, q, z| {
            let d = self.s[k] as f64 - z;
            if d > worst {
                worst = d;
                at = DVec3::new(q.x, q.y, z);
            }
            true
        });
        (worst, at)
    }

    fn material_under(&self, c: DVec2, z: f64) -> bool {
        RasterSim::material_under(self, c, z)
    }

    fn begin_move(&mut self) {
        if let Some(f) = &mut self.feed.0 {
            f.send(ToExact::Move);
        }
    }

    fn engagement(&mut self, p: DVec3, dir: DVec2, cur: &Path, before: &Path) -> (Option<f64>, f64) {
        // A straight move sweeps nothing of the front half of a ring wider than the tool
        // around its end (every point ahead lies farther than the ring's radius from the
        // segment behind it), so only an arc's own sweep needs testing.
        let arc = matches!(cur, Path::Arc(_));
        let px = self.engagement_pixel(p.truncate(), p.z, dir, arc.then_some(before));
        let q = Query {
            c: p.truncate(),
            z: p.z,
            dir,
            rho: self.r + self.ring_delta,
            eps: self.eps,
            current: arc.then_some(*cur),
            upto: 0,
        };
        match &mut self.feed.0 {
            // the exact model's thread measures it (the primitives recorded before it count)
            Some(f) => {
                f.send(ToExact::Query(q, px as f32));
                (None, px)
            }
            None => {
                let exact = self.exact.engagement(q.c, q.z, dir, q.rho, q.eps, q.current.as_ref());
                (Some(exact), px)
            }
        }
    }

    fn deferred(&mut self) -> Vec<f64> {
        let Some(mut f) = self.feed.0.take() else { return Vec::new() };
        f.flush();
        let ExactFeed { tx, answers, .. } = f;
        drop(tx);
        let answers = answers.into_inner().unwrap_or_else(|e| e.into_inner());
        answers.recv().expect("the exact model's thread answers")
    }

    fn gouge_depth(&self, path: &Path) -> (f64, DVec3) {
        RasterSim::gouge_depth(self, path)
    }

    fn gouge_depths(&self, paths: &[Path]) -> Vec<(f64, DVec3)> {
        // (on the threads the exact model's queries leave free; the part heights and outline
        // never change, so the answers are those of the replay's own order)
        paths.par_iter().with_min_len(64).map(|p| RasterSim::gouge_depth(self, p)).collect()
    }

    fn flush(&mut self) {
        if let Some(f) = &mut self.feed.0 {
            f.flush();
        }
    }

    fn cut_move(&mut self, path: &Path) {
        RasterSim::cut_move(self, path);
    }

    fn removed_volume(&self) -> f64 {
        let cell = self.grid.res * self.grid.res;
        self.s0.iter().zip(&self.s).filter(|(a, _)| a.is_finite()).map(|(a, b)| (a - b) as f64).sum::<f64>() * cell
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Cutting, Width};

    /// A 40 mm square of stock, no part, a Ø6 tool, 0.1 mm cells.
    fn sim() -> RasterSim {
        sim_with(Area::rect(-20.0, -20.0, 20.0, 20.0), Area::empty())
    }

    /// The same with another stock and a part.
    fn sim_with(stock: Area, part: Area) -> RasterSim {
        sim_on(stock, part, &SimOptions { res: Some(0.1), ..Default::default() })
    }

    /// The same with other simulation settings.
    fn sim_on(stock: Area, part: Area, opts: &SimOptions) -> RasterSim {
        let job = Job {
            floor: -5.0,
            cutting: Cutting::with_tool_diameter(6.0).with_width(Width::Stepover(0.25)),
            ..Job::new("t", stock, part, 6.0, 5.0)
        };
        let regions = job.regions(job.radius(), 0.0).expect("regions");
        RasterSim::new(&job, &regions, opts).expect("simulator")
    }

    fn point(p: DVec2) -> Path {
        Path::Line { a: p.extend(0.0), b: p.extend(0.0) }
    }

    #[test]
    fn a_rim_that_grazes_a_wall_gouges_it_by_the_overlap_not_by_the_walls_height() {
        // an island [5, 10]² standing to the top; a Ø6 cut at the floor along y = 0 from x = -8
        // to x = 2.2: its rim reaches 0.2 mm into the island's side, 5 mm below its top
        let s = sim_with(Area::rect(-20.0, -20.0, 20.0, 20.0), Area::rect(5.0, -2.0, 10.0, 2.0));
        let graze = Path::Line { a: DVec3::new(-8.0, 0.0, -5.0), b: DVec3::new(2.2, 0.0, -5.0) };
        let (d, at) = s.gouge_depth(&graze);
        assert!((d - 0.2).abs() < 0.06, "{d} mm at {at}");
        // clear of it: no gouge; through the floor under the tool's centre: the depth below it
        let clear = Path::Line { a: DVec3::new(-8.0, 0.0, -5.0), b: DVec3::new(1.9, 0.0, -5.0) };
        assert_eq!(s.gouge_depth(&clear).0, 0.0);
        let low = Path::Line { a: DVec3::new(-8.0, 0.0, -5.3), b: DVec3::new(-4.0, 0.0, -5.3) };
        assert!((s.gouge_depth(&low).0 - 0.3).abs() < 1e-6);
    }

    #[test]
    fn the_pixel_reading_by_cell_steps_reads_the_cells_a_point_falls_in() {
        // cuts at two depths, so that the ring meets cut, uncut and half-cut cells
        let mut s = sim();
        s.cut_step(DVec2::new(-15.0, -4.0), DVec2::new(12.0, 3.0), -2.0);
        s.cut_step(DVec2::new(-6.0, -15.0), DVec2::new(4.0, 14.0), -1.0);
        let z = -2.0;
        let zq = (z + s.eps) as f32;
        // the reading as eq. 4 defines it: each point ahead of the motion in the cell
        // `Grid::cell_of` puts it in
        let by_cells = |s: &RasterSim, c: DVec2, dir: DVec2| {
            let hit = s
                .circ
                .iter()
                .filter(|o| o.dot(dir) >= 0.0)
                .filter(|o| s.grid.cell_of(c + **o).is_some_and(|(i, j)| s.s[j * s.grid.nx + i] > zq))
                .count();
            360.0 * hit as f64 / s.circ.len() as f64
        };
        // a seeded walk over the stock, off its edges too (where the ring leaves the grid and
        // the reading takes the general way), every direction
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut inside, mut engaged) = (0, 0);
        for _ in 0..4000 {
            let c = DVec2::new(-26.0 + 52.0 * next(), -26.0 + 52.0 * next());
            let a = std::f64::consts::TAU * next();
            let dir = DVec2::new(a.cos(), a.sin());
            let e = s.engagement_pixel(c, z, dir, None);
            assert_eq!(e, by_cells(&s, c, dir), "at {c:?} along {dir:?}");
            let (fx, fy) = ((c.x - s.grid.x0) / s.grid.res, (c.y - s.grid.y0) / s.grid.res);
            let r = s.circ_reach;
            inside += usize::from(fx >= r && fy >= r && fx + r < s.grid.nx as f64 && fy + r < s.grid.ny as f64);
            engaged += usize::from(e > 0.0 && e < 180.0);
        }
        // (both ways were taken, and the readings were not all 0 or 180)
        assert!(inside > 1000 && inside < 3900, "{inside} of 4000 on the grid");
        assert!(engaged > 200, "{engaged} partly engaged");
    }

    #[test]
    fn a_speck_between_two_sweeps_keeps_rapids_out() {
        let opts = SimOptions { res: Some(0.1), sure_links: true, ..Default::default() };
        let mut s = sim_on(Area::rect(-20.0, -20.0, 20.0, 20.0), Area::empty(), &opts);
        let mut plain = sim();
        let z = -2.0;
        // (the model without the surely cut heights does not see the speck)
        plain.cut_step(DVec2::new(-10.0, 0.0), DVec2::new(10.0, 0.0), z);
        plain.cut_step(DVec2::new(-10.0, 6.02), DVec2::new(10.0, 6.02), z);
        assert!(plain.is_clear(&Path::Line { a: DVec3::new(-3.0, 3.01, z), b: DVec3::new(3.0, 3.01, z) }, 0.0));
        // two passes 6.02 mm apart with a Ø6 tool: a strip 0.02 mm wide stands between them,
        // at y 3.00–3.02, and no cell centre (…, 2.95, 3.05, …) lies in it
        s.cut_step(DVec2::new(-10.0, 0.0), DVec2::new(10.0, 0.0), z);
        s.cut_step(DVec2::new(-10.0, 6.02), DVec2::new(10.0, 6.02), z);
        for y in [2.95, 3.05] {
            assert_eq!(s.height_at(DVec2::new(0.0, y)), z as f32, "every centre near the strip reads cut");
        }
        let way = Path::Line { a: DVec3::new(-3.0, 3.01, z), b: DVec3::new(3.0, 3.01, z) };
        assert!(!s.is_clear(&way, 0.0), "a rapid along the strip would hit it");
        assert!(s.max_height_near(&way, 1.0) > z as f32);
        // nor may a link cross it
        assert_eq!(s.leaving_distance(DVec3::new(0.0, 4.0, z), DVec3::new(0.0, 2.0, z), 0.0), None);
        // (the first step of a pass leaves its start disk to the step before: the way keeps
        // off it)
        // a pass along the strip removes it
        s.cut_step(DVec2::new(-10.0, 3.01), DVec2::new(10.0, 3.01), z);
        assert!(s.is_clear(&way, 0.0));
        assert_eq!(s.leaving_distance(DVec3::new(0.0, 4.0, z), DVec3::new(0.0, 2.0, z), 0.0), Some(0.0));
    }

    #[test]
    fn block_maxima_give_the_same_answer_as_every_cell() {
        let mut s = sim();
        // cut a few steps at two depths so that blocks hold several heights
        s.cut_step(DVec2::new(-25.0, -3.0), DVec2::new(2.0, -3.0), -2.0);
        s.cut_step(DVec2::new(2.0, -3.0), DVec2::new(6.0, 9.0), -2.0);
        s.cut_step(DVec2::new(-25.0, 8.0), DVec2::new(-4.0, 8.0), -1.0);
        let brute = |s: &RasterSim, p: DVec2, rho: f64| {
            let g = s.grid;
            let mut best = f32::NEG_INFINITY;
            for j in 0..g.ny {
                for i in 0..g.nx {
                    if (g.center(i, j) - p).length() <= rho {
                        best = best.max(s.link_heights()[j * g.nx + i]);
                    }
                }
            }
            best
        };
        let mut checked = 0;
        for k in 0..60 {
            let p = DVec2::new(-22.0 + 0.77 * k as f64, -15.0 + 0.53 * ((k * 7) % 60) as f64);
            for rho in [0.3, 2.0, 3.05, 5.5] {
                assert_eq!(s.max_height_near(&point(p), rho), brute(&s, p, rho), "at {p:?}, rho {rho}");
                checked += 1;
            }
        }
        assert_eq!(checked, 240);
        // the block counts follow cells lowered one by one: a point cut clean reads the level
        s.cut(&Path::Line { a: DVec3::new(10.0, 10.0, -2.0), b: DVec3::new(10.0, 10.0, -2.0) });
        assert_eq!(s.max_height_near(&point(DVec2::new(10.0, 10.0)), 2.5), -2.0);
    }

    #[test]
    fn cut_lowers_exactly_the_cells_within_the_radius_of_the_move() {
        // the scan is narrowed to each row's stadium and skips blocks below the move: it must
        // lower the same cells as a test of every cell of the grid
        let mut s = sim();
        s.cut_step(DVec2::new(-25.0, 4.0), DVec2::new(25.0, 4.0), -1.0);
        let r = s.radius();
        let moves = [
            (DVec3::new(-18.0, -17.0, -2.0), DVec3::new(16.0, 15.5, -2.0)),
            (DVec3::new(12.0, -16.0, -1.5), DVec3::new(-14.0, 11.0, -1.5)),
            (DVec3::new(-5.0, -18.0, -0.5), DVec3::new(-4.9, 18.0, -0.5)),
            (DVec3::new(3.0, 2.0, -3.0), DVec3::new(3.0, 2.0, -3.0)),
            // a ramp: not flat
            (DVec3::new(-16.0, 12.0, 0.0), DVec3::new(15.0, -3.0, -2.5)),
        ];
        for (a, b) in moves {
            let before = s.heights().to_vec();
            let path = Path::Line { a, b };
            s.cut(&path);
            let g = s.grid;
            let mut lowered = 0;
            for j in 0..g.ny {
                for i in 0..g.nx {
                    let k = j * g.nx + i;
                    let want = match path.reach_zmin(g.center(i, j), r) {
                        Some(z) if (z as f32) < before[k] && before[k] > f32::NEG_INFINITY => z as f32,
                        _ => before[k],
                    };
                    let got = s.heights()[k];
                    assert!(
                        got == want || (got - want).abs() < 1e-5,
                        "{a:?}→{b:?} at cell ({i}, {j}): {got} vs {want}"
                    );
                    lowered += usize::from(s.heights()[k] < before[k]);
                }
            }
            assert!(lowered > 100, "{a:?}→{b:?} lowered {lowered} cells");
        }
    }

    #[test]
    fn a_cut_after_a_flat_cut_lowers_the_same_cells_without_reading_the_disk_it_ended_in() {
        // a chain of short lines and arcs at one depth, a step down, a ramp, a gap, a move
        // higher up: cut as a program is (each cut may pass over the disk where the flat cut
        // before it ended) and with that forgotten before every cut, the heights are the same
        let mut pts = Vec::new();
        let mut p = DVec3::new(-12.0, -6.0, -1.0);
        for k in 0..80 {
            let a = 0.31 * k as f64;
            let q = p + DVec3::new(a.cos(), a.sin(), 0.0) * if k % 9 == 0 { 0.04 } else { 0.7 };
            let q = DVec3::new(q.x, q.y, if k == 40 { -1.6 } else { p.z });
            let m = if k % 5 == 0 {
                // an arc through the chord's end, its centre to the left
                let c = (p.truncate() + q.truncate()) / 2.0 + (q - p).truncate().perp() * 0.8;
                Path::Arc(crate::toolpath::ArcGeom::new(p, q, c, true))
            } else {
                Path::Line { a: p, b: q }
            };
            pts.push(m);
            p = q;
        }
        pts.push(Path::Line { a: p, b: p + DVec3::new(3.0, 1.0, -0.9) });
        pts.push(Path::Line { a: DVec3::new(8.0, 8.0, -2.5), b: DVec3::new(9.0, 6.0, -2.5) });
        pts.push(Path::Line { a: DVec3::new(9.0, 6.0, -0.5), b: DVec3::new(2.0, 3.0, -0.5) });
        // (cells of 4.5 mm: half their diagonal is more than the radius, and the surely cut
        // heights are lowered by no cut)
        for (sure, res) in [(false, 0.1), (true, 0.1), (true, 4.5)] {
            let opts = SimOptions { res: Some(res), sure_links: sure, ..Default::default() };
            let mut chained = sim_on(Area::rect(-20.0, -20.0, 20.0, 20.0), Area::empty(), &opts);
            let mut each = chained.clone();
            for m in &pts {
                chained.cut(m);
                each.last_flat_end = None;
                each.cut(m);
            }
            assert!(chained.heights() == each.heights(), "sure {sure}, {res} mm: the heights differ");
            assert!(chained.sure == each.sure, "sure {sure}, {res} mm: the surely cut heights differ");
            let lowered = chained.heights().iter().filter(|h| **h < 5.0).count();
            assert!(lowered as f64 * res * res > 200.0, "{lowered} cells cut");
        }
    }

    #[test]
    fn chained_steps_lower_exactly_the_swept_cells() {
        // a pass of short steps turning every way, as the planner cuts it (the tool has arrived
        // at the first point, so its disk there is cut): the cells within the radius of the
        // polyline are lowered, and no others
        let mut s = sim();
        let z = -1.0;
        let r = 2.995;
        let mut pts = vec![DVec2::new(-9.0, -4.0)];
        for k in 1..60 {
            let a = 0.37 * k as f64;
            let step = if k % 7 == 0 { 0.05 } else { 0.6 };
            pts.push(pts[k - 1] + step * DVec2::new(a.cos(), a.sin()));
        }
        s.cut(&Path::Line { a: pts[0].extend(z), b: pts[0].extend(z) });
        let before = s.heights().to_vec();
        for w in pts.windows(2) {
            s.cut_step_r(w[0], w[1], z, r);
        }
        let g = s.grid;
        let mut swept = 0;
        for j in 0..g.ny {
            for i in 0..g.nx {
                let q = g.center(i, j);
                let k = j * g.nx + i;
                let d = pts
                    .windows(2)
                    .map(|w| Path::Line { a: w[0].extend(z), b: w[1].extend(z) }.distance(q))
                    .fold(f64::INFINITY, f64::min);
                let want = if d <= r - 1e-9 && before[k] > z as f32 {
                    z as f32
                } else if d > r + 1e-9 {
                    before[k]
                } else {
                    s.heights()[k]
                };
                assert_eq!(s.heights()[k], want, "cell ({i}, {j}) at {d:.4} from the pass");
                swept += usize::from(s.heights()[k] < before[k]);
            }
        }
        assert!(swept > 3000, "{swept}");
    }

    #[test]
    fn leaving_distance_feeds_off_the_touched_material_and_refuses_new_material() {
        let mut s = sim();
        let z = -2.0;
        // a slot from outside the stock to the middle, wider than the tool, and its last half
        // millimetre with the planner's radius less 5 µm: the tool at its end touches the
        // material ahead of it
        let end = DVec2::new(0.0, 0.0);
        s.cut_step_r(DVec2::new(-30.0, 0.0), DVec2::new(-0.5, 0.0), z, 3.2);
        s.cut_step_r(DVec2::new(-0.5, 0.0), end, z, 2.995);
        let margin = 0.075;
        // back along the slot: only the material touched at the start, left behind at once
        let back = DVec2::new(-15.0, 0.0);
        let t = s.leaving_distance(end.extend(z), back.extend(z), margin).expect("the way back is clear");
        assert!(t > 0.0 && t < 0.5, "{t}");
        let rest = Path::Line { a: (end + (back - end).normalize() * t).extend(z), b: back.extend(z) };
        assert!(s.is_clear(&rest, margin), "the rest of the way is clear");
        assert!(!s.is_clear(&Path::Line { a: end.extend(z), b: back.extend(z) }, margin));
        // forward or sideways: new material
        assert!(s.leaving_distance(end.extend(z), DVec2::new(5.0, 0.0).extend(z), margin).is_none());
        assert!(s.leaving_distance(end.extend(z), DVec2::new(0.0, 5.0).extend(z), margin).is_none());
        // from a point in the clear: nothing touched, nothing to feed
        let p = DVec2::new(-12.0, 0.0);
        assert_eq!(s.leaving_distance(p.extend(z), back.extend(z), margin), Some(0.0));
    }

    #[test]
    fn front_engagement_along_a_wall_reads_the_strip_beside_it() {
        // a wall at x = 5: the part beyond it, either outside the stock (a pocket) or inside
        // it; a pass along x = -0.005 has left a strip 2 mm wide before the wall; the tool
        // follows the wall 5 µm from it, cutting the strip on its right: the arc in the
        // material is acos(1 - 2/3) = 70.5°
        let pocket = sim_with(Area::rect(-20.0, -20.0, 5.0, 20.0), Area::rect(5.0, -30.0, 30.0, 30.0));
        let island = sim_with(Area::rect(-20.0, -20.0, 20.0, 20.0), Area::rect(5.0, -20.0, 20.0, 20.0));
        for (what, mut s) in [("outside the stock", pocket), ("inside the stock", island)] {
            let z = -1.0;
            let x = 5.0 - 3.0 - 0.005;
            s.cut_step(DVec2::new(x - 2.0, -25.0), DVec2::new(x - 2.0, 25.0), z);
            s.cut_step(DVec2::new(x, -25.0), DVec2::new(x, 0.0), z);
            let expect = (1.0f64 - 2.0 / 3.0).acos().to_degrees();
            // (a step of the planner, 0.1·D, and more)
            for y in [0.6, 1.2, 2.0] {
                let e = s.front_engagement(DVec2::new(x, y), z, DVec2::Y);
                // (the ring half a pixel outside the tool reaches into the wall: read there,
                // the wedge round it would be lost or the part counted, 8° either way)
                assert!((e - expect).abs() < 2.0, "part {what}, at y {y}: {e:.1}° against {expect:.1}°");
            }
        }
    }
}
