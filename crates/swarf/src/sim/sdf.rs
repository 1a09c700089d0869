//! Material simulation on sampled signed distance fields (Erdim et al., paper 4 §4: the
//! workpiece as a signed Euclidean distance field, eq. 9, cut by the distance field of the
//! tool's swept volume, eq. 10–12), a second engine beside the raster of [`super::raster`].
//!
//! The material of a 2.5D job is a stack of slabs between the heights at which the program cuts
//! flat, each a cross-section kept as a signed distance (positive in material, eq. 9) sampled on
//! a lattice of spacing `h`, truncated to `±2h` and stored sparsely in 16 × 16 tiles (after the
//! adaptively sampled distance fields of Frisken et al.). A move cuts it by
//! `d ← min(d, dist(q, P) − R)`, the distance to the axis path `P` in closed form (eq. 12 for a
//! flat tool in a section, §4's `S = P ⊕ T`), and engagement is root finding on the field along
//! the tool's ring. The field, the cutting and every measure are in `docs/simulation.md`.

use super::SimOptions;
use super::replay::Engine;
use super::replay::{Replay, Rest};
use super::sweep::{Fast, Path};
use crate::error::{Error, Result, Setting};
use crate::geom::index::EdgeIndex;
use crate::geom::{Area, DVec2, DVec3};
use crate::model::{Job, Regions};
use crate::toolpath::Toolpath;
use rayon::prelude::*;

/// Side of a tile, samples.
const T: usize = 16;
/// Samples in a tile.
const TT: usize = T * T;

/// A tile of the field.
#[derive(Debug, Clone)]
enum Tile {
    /// Every sample at `+band`.
    Inside,
    /// Every sample at `−band`.
    Outside,
    /// Samples row by row.
    Dense(Box<[f32; TT]>),
}

/// One truncated field: its tiles row by row.
#[derive(Debug, Clone)]
struct Field {
    tiles: Vec<Tile>,
    dense: usize,
}

/// The sample lattice: sample `(i, j)` stands at `(x0 + i·h, y0 + j·h)`.
#[derive(Debug, Clone, Copy)]
struct Lattice {
    x0: f64,
    y0: f64,
    h: f64,
    ntx: usize,
    nty: usize,
    band: f32,
}

impl Lattice {
    fn nx(&self) -> usize {
        self.ntx * T
    }

    fn ny(&self) -> usize {
        self.nty * T
    }

    #[inline]
    fn at(&self, i: usize, j: usize) -> DVec2 {
        DVec2::new(self.x0 + i as f64 * self.h, self.y0 + j as f64 * self.h)
    }

    /// Centre of tile `(tx, ty)` and the distance from it to its farthest sample.
    fn tile_centre(&self, tx: usize, ty: usize) -> (DVec2, f64) {
        let half = 0.5 * (T - 1) as f64;
        let c = DVec2::new(
            self.x0 + (tx as f64 * T as f64 + half) * self.h,
            self.y0 + (ty as f64 * T as f64 + half) * self.h,
        );
        (c, half * self.h * std::f64::consts::SQRT_2)
    }

    /// Tiles `(tx0, tx1, ty0, ty1)` holding samples in `[lo, hi]`.
    fn tiles_in(&self, lo: DVec2, hi: DVec2) -> Option<(usize, usize, usize, usize)> {
        let fx0 = ((lo.x - self.x0) / self.h).floor();
        let fy0 = ((lo.y - self.y0) / self.h).floor();
        let fx1 = ((hi.x - self.x0) / self.h).ceil();
        let fy1 = ((hi.y - self.y0) / self.h).ceil();
        if !(fx1 >= 0.0 && fy1 >= 0.0 && fx0 < self.nx() as f64 && fy0 < self.ny() as f64) {
            return None;
        }
        let tx0 = (fx0.max(0.0) as usize) / T;
        let ty0 = (fy0.max(0.0) as usize) / T;
        let tx1 = ((fx1 as usize).min(self.nx() - 1)) / T;
        let ty1 = ((fy1 as usize).min(self.ny() - 1)) / T;
        Some((tx0, tx1, ty0, ty1))
    }
}

impl Field {
    /// Sample `(i, j)`; `−band` outside the lattice.
    #[inline]
    fn node(&self, lat: &Lattice, i: i64, j: i64) -> f32 {
        if i < 0 || j < 0 || i as usize >= lat.nx() || j as usize >= lat.ny() {
            return -lat.band;
        }
        let (i, j) = (i as usize, j as usize);
        match &self.tiles[(j / T) * lat.ntx + i / T] {
            Tile::Inside => lat.band,
            Tile::Outside => -lat.band,
            Tile::Dense(s) => s[(j % T) * T + i % T],
        }
    }

    /// The field at `q`, bilinear between samples.
    #[inline]
    fn value(&self, lat: &Lattice, q: DVec2) -> f64 {
        let fx = (q.x - lat.x0) / lat.h;
        let fy = (q.y - lat.y0) / lat.h;
        if !(fx.is_finite() && fy.is_finite()) {
            return -lat.band as f64;
        }
        let (i, j) = (fx.floor(), fy.floor());
        let (tx, ty) = (fx - i, fy - j);
        let (i, j) = (i as i64, j as i64);
        let v00 = self.node(lat, i, j) as f64;
        let v10 = self.node(lat, i + 1, j) as f64;
        let v01 = self.node(lat, i, j + 1) as f64;
        let v11 = self.node(lat, i + 1, j + 1) as f64;
        let a = v00 + (v10 - v00) * tx;
        let b = v01 + (v11 - v01) * tx;
        a + (b - a) * ty
    }

    /// Material area: the area where the bilinear field is positive, cell by cell (the field
    /// is linear along each of [`AREA_ROWS`] rows of a cell, so each row's share is exact).
    /// Reading the samples' signs alone would be noisier, and a coverage `½ + d/h` per sample
    /// would count a wall cut exactly along the stock's outline — where the field is a ridge
    /// `−|x|` that touches zero without enclosing anything — as a quarter-cell strip of
    /// material.
    fn area(&self, lat: &Lattice) -> f64 {
        let cell = lat.h * lat.h;
        let constant = |tx: usize, ty: usize| -> Option<bool> {
            let mut v = None;
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let (x, y) = (tx + dx, ty + dy);
                let t = if x < lat.ntx && y < lat.nty { &self.tiles[y * lat.ntx + x] } else { &Tile::Outside };
                let inside = match t {
                    Tile::Inside => true,
                    Tile::Outside => false,
                    Tile::Dense(_) => return None,
                };
                if v.is_some_and(|w| w != inside) {
                    return None;
                }
                v = Some(inside);
            }
            v
        };
        let mut total = 0.0;
        for ty in 0..lat.nty {
            for tx in 0..lat.ntx {
                match constant(tx, ty) {
                    Some(true) => total += TT as f64,
                    Some(false) => {}
                    None => {
                        for jj in 0..T {
                            for ii in 0..T {
                                let (i, j) = ((tx * T + ii) as i64, (ty * T + jj) as i64);
                                total += cell_share(
                                    self.node(lat, i, j),
                                    self.node(lat, i + 1, j),
                                    self.node(lat, i, j + 1),
                                    self.node(lat, i + 1, j + 1),
                                );
                            }
                        }
                    }
                }
            }
        }
        total * cell
    }

    /// `d ← min(d, dist(q, path) − r)`: removes the sweep of a disk of radius `r` along `fast`
    /// (whose XY box grown by `r` is `[lo, hi]`).
    fn cut(&mut self, lat: &Lattice, fast: &Fast, lo: DVec2, hi: DVec2, r: f64) {
        let band = lat.band as f64;
        let pad = DVec2::splat(band);
        let Some((tx0, tx1, ty0, ty1)) = lat.tiles_in(lo - pad, hi + pad) else { return };
        for ty in ty0..=ty1 {
            for tx in tx0..=tx1 {
                let k = ty * lat.ntx + tx;
                if matches!(self.tiles[k], Tile::Outside) {
                    continue;
                }
                let (c, hd) = lat.tile_centre(tx, ty);
                let dc = fast.distance(c);
                if dc - hd - r >= band {
                    // the sweep's field is above the band over the whole tile: nothing changes
                    continue;
                }
                if dc + hd - r <= -band {
                    // the whole tile lies deep in the sweep
                    if matches!(self.tiles[k], Tile::Dense(_)) {
                        self.dense -= 1;
                    }
                    self.tiles[k] = Tile::Outside;
                    continue;
                }
                if matches!(self.tiles[k], Tile::Inside) {
                    self.tiles[k] = Tile::Dense(Box::new([lat.band; TT]));
                    self.dense += 1;
                }
                let Tile::Dense(s) = &mut self.tiles[k] else { continue };
                let mut all_out = true;
                for jj in 0..T {
                    for ii in 0..T {
                        let q = lat.at(tx * T + ii, ty * T + jj);
                        let v = ((fast.distance(q) - r) as f32).clamp(-lat.band, lat.band);
                        let d = &mut s[jj * T + ii];
                        if v < *d {
                            *d = v;
                        }
                        all_out &= *d <= -lat.band;
                    }
                }
                if all_out {
                    self.tiles[k] = Tile::Outside;
                    self.dense -= 1;
                }
            }
        }
    }

    /// Bytes the field holds.
    fn bytes(&self) -> usize {
        self.tiles.len() * std::mem::size_of::<Tile>() + self.dense * std::mem::size_of::<[f32; TT]>()
    }
}

/// Rows per cell of [`Field::area`].
const AREA_ROWS: usize = 8;

/// The share of the unit cell where the bilinear interpolation of the corner values
/// (`v00` at (0, 0), `v10` at (1, 0), …) is positive: along each of [`AREA_ROWS`] rows it is
/// linear in x, and its positive length is exact.
fn cell_share(v00: f32, v10: f32, v01: f32, v11: f32) -> f64 {
    let (v00, v10, v01, v11) = (v00 as f64, v10 as f64, v01 as f64, v11 as f64);
    if v00 > 0.0 && v10 > 0.0 && v01 > 0.0 && v11 > 0.0 {
        return 1.0;
    }
    if v00 <= 0.0 && v10 <= 0.0 && v01 <= 0.0 && v11 <= 0.0 {
        return 0.0;
    }
    let mut sum = 0.0;
    for k in 0..AREA_ROWS {
        let y = (k as f64 + 0.5) / AREA_ROWS as f64;
        // f(x) = a + b·x on the row
        let a = v00 + (v01 - v00) * y;
        let b = (v10 + (v11 - v10) * y) - a;
        sum += if b.abs() < 1e-30 {
            f64::from(u8::from(a > 0.0))
        } else {
            let x0 = -a / b;
            if b > 0.0 { 1.0 - x0.clamp(0.0, 1.0) } else { x0.clamp(0.0, 1.0) }
        };
    }
    sum / AREA_ROWS as f64
}

/// One slab of the material: the heights `(bottom, top]` and the cross-section at `at`.
#[derive(Debug, Clone)]
struct Slab {
    top: f64,
    bottom: f64,
    at: f64,
    field: Field,
}

/// The distance-field simulator (see the module docs).
#[derive(Debug, Clone)]
pub struct SdfSim {
    lat: Lattice,
    r: f64,
    tol: f64,
    eps: f64,
    ring_delta: f64,
    sample_step: f64,
    stock_top: f64,
    floor_eff: f64,
    part_top_eff: f64,
    /// The stock's section before any cut.
    base: Field,
    base_area: f64,
    slabs: Vec<Slab>,
    keep: Area,
    keep_edges: EdgeIndex,
    reachable: Area,
    peak_bytes: usize,
}

impl SdfSim {
    /// Builds the field of `job`'s stock for its tool: sample spacing `opts.res` (by default
    /// the raster's cell size, [`SimOptions::res_for`]). The slabs are laid out by the program
    /// at [`SdfSim::replay`]. 3D jobs (height maps) are not supported.
    pub fn new(job: &Job, regions: &Regions, opts: &SimOptions) -> Result<Self> {
        if opts.heights.is_some() {
            return Err(Error::setting(
                Setting::SimEngine,
                "the distance-field simulator handles 2.5D jobs only; use the raster simulator",
            ));
        }
        let r = job.radius();
        let h = opts.res_for(job.cutting.tool.diameter);
        if !(h.is_finite() && h > 0.0) {
            return Err(Error::setting(Setting::Resolution, format!("{h} mm: the sample spacing must be positive")));
        }
        let (lo, hi) = job.stock.bounds().ok_or_else(|| Error::job("stock", "the stock outline is empty"))?;
        let band = 2.0 * h;
        let pad = band + 2.0 * h;
        let (x0, y0) = (lo.x - pad, lo.y - pad);
        let nx = ((hi.x + pad - x0) / h).ceil() as usize + 1;
        let ny = ((hi.y + pad - y0) / h).ceil() as usize + 1;
        let (ntx, nty) = (nx.div_ceil(T), ny.div_ceil(T));
        if ntx.saturating_mul(nty).saturating_mul(TT) > opts.max_cells.saturating_mul(4) {
            return Err(Error::setting(
                Setting::Resolution,
                format!("a {}×{} sample field at {h} mm is too large; use a coarser spacing", ntx * T, nty * T),
            ));
        }
        let lat = Lattice { x0, y0, h, ntx, nty, band: band as f32 };
        let edges = EdgeIndex::from_area(&job.stock, (T as f64 * h).max(1.0));
        let stock = &job.stock;
        let tiles: Vec<Tile> = (0..ntx * nty)
            .into_par_iter()
            .map(|k| {
                let (tx, ty) = (k % ntx, k / ntx);
                let (c, hd) = lat.tile_centre(tx, ty);
                let dc = edges.distance(c, hd + band + h);
                if dc >= hd + band {
                    return if stock.contains(c) { Tile::Inside } else { Tile::Outside };
                }
                let mut s = Box::new([0f32; TT]);
                for jj in 0..T {
                    for ii in 0..T {
                        let q = lat.at(tx * T + ii, ty * T + jj);
                        let d = edges.distance(q, band);
                        let d = if stock.contains(q) { d } else { -d };
                        s[jj * T + ii] = (d as f32).clamp(-lat.band, lat.band);
                    }
                }
                if s.iter().all(|&v| v >= lat.band) {
                    Tile::Inside
                } else if s.iter().all(|&v| v <= -lat.band) {
                    Tile::Outside
                } else {
                    Tile::Dense(s)
                }
            })
            .collect();
        let dense = tiles.iter().filter(|t| matches!(t, Tile::Dense(_))).count();
        let base = Field { tiles, dense };
        let base_area = base.area(&lat);
        Ok(Self {
            lat,
            r,
            tol: opts.tol,
            eps: opts.eps,
            ring_delta: opts.ring_delta,
            sample_step: opts.sample_step.unwrap_or(h),
            stock_top: job.stock_top,
            floor_eff: job.floor + job.allowance_floor,
            part_top_eff: job.part_top + job.allowance_floor,
            base_area,
            peak_bytes: base.bytes(),
            base,
            slabs: Vec::new(),
            keep: regions.keep.clone(),
            keep_edges: EdgeIndex::from_area(&regions.keep, (2.0 * r).max(1.0)),
            reachable: regions.reachable.offset(-opts.tol, crate::model::REGION_TOL),
        })
    }

    /// The sample spacing, mm.
    pub fn spacing(&self) -> f64 {
        self.lat.h
    }

    /// Number of slabs (after [`SdfSim::replay`]).
    pub fn slab_count(&self) -> usize {
        self.slabs.len()
    }

    /// Bytes the fields hold now.
    pub fn bytes(&self) -> usize {
        self.base.bytes() + self.slabs.iter().map(|s| s.field.bytes()).sum::<usize>()
    }

    /// The most bytes the fields held during the replay.
    pub fn peak_bytes(&self) -> usize {
        self.peak_bytes
    }

    /// Lays the slabs out for `tp`: bounded by the stock top, the heights of its flat cutting
    /// moves below it and its lowest point.
    fn layout(&mut self, tp: &Toolpath) {
        let mut hs = Vec::new();
        let mut zmin = f64::INFINITY;
        for (from, m) in tp.segments() {
            let z = from.z.min(m.to.z);
            zmin = zmin.min(z);
            let path = Path::of(from, m);
            if !m.is_rapid() && path.is_flat() && path.xy_length() > 1e-9 && z < self.stock_top - 1e-9 {
                hs.push(z);
            }
        }
        if zmin < self.stock_top - 1e-9 {
            hs.push(zmin);
        }
        hs.sort_by(|a, b| b.total_cmp(a));
        hs.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
        let mut top = self.stock_top;
        self.slabs = hs
            .into_iter()
            .map(|bottom| {
                let slab =
                    Slab { top, bottom, at: bottom + self.eps.min(0.5 * (top - bottom)), field: self.base.clone() };
                top = bottom;
                slab
            })
            .collect();
        self.peak_bytes = self.peak_bytes.max(self.bytes());
    }

    /// Replays a toolpath on fresh slabs laid out for it (see [`super::replay`]).
    pub fn replay(&mut self, tp: &Toolpath, progress: &mut dyn FnMut(f64)) -> Replay {
        self.layout(tp);
        let mut rp = super::replay::run(self, tp, progress);
        rp.res = self.lat.h;
        rp
    }

    /// The slab whose heights hold `z`.
    fn slab_at(&self, z: f64) -> Option<&Slab> {
        self.slabs.iter().find(|s| z > s.bottom && z <= s.top)
    }

    /// Height of the top of the material at sample `(i, j)` (none outside the stock): the top
    /// of the highest slab holding material there, else the bottom of the lowest.
    fn top_at(&self, i: i64, j: i64) -> Option<f64> {
        if self.base.node(&self.lat, i, j) <= 0.0 {
            return None;
        }
        for s in &self.slabs {
            if s.field.node(&self.lat, i, j) > 0.0 {
                return Some(s.top);
            }
        }
        Some(self.slabs.last().map_or(self.stock_top, |s| s.bottom))
    }

    /// Calls `f(i, j, centre)` for every sample of the reachable area (tile rows rasterised one
    /// at a time).
    fn for_each_reachable(&self, mut f: impl FnMut(usize, usize, DVec2)) {
        let lat = &self.lat;
        for ty in 0..lat.nty {
            let strip = super::grid::Grid {
                x0: lat.x0 - 0.5 * lat.h,
                y0: lat.y0 + ((ty * T) as f64 - 0.5) * lat.h,
                res: lat.h,
                nx: lat.nx(),
                ny: T,
            };
            let mask = strip.rasterize(&self.reachable);
            for jj in 0..T {
                for i in 0..lat.nx() {
                    if mask[jj * lat.nx() + i] {
                        let j = ty * T + jj;
                        f(i, j, lat.at(i, j));
                    }
                }
            }
        }
    }

    /// Reachable material left standing more than `tol` above the floor.
    pub fn rest(&self) -> Rest {
        let cell = self.lat.h * self.lat.h;
        let mut r = Rest::default();
        let fl = self.floor_eff + self.tol;
        self.for_each_reachable(|i, j, _| {
            r.reachable_mm2 += cell;
            if let Some(top) = self.top_at(i as i64, j as i64)
                && top > fl
            {
                let t = top - self.floor_eff;
                r.area_mm2 += cell;
                r.volume_mm3 += t * cell;
                r.max_thickness_mm = r.max_thickness_mm.max(t);
            }
        });
        r
    }

    /// Samples of rest material (reachable and standing), for pictures.
    pub fn rest_cells(&self) -> Vec<DVec2> {
        let fl = self.floor_eff + self.tol;
        let mut out = Vec::new();
        self.for_each_reachable(|i, j, q| {
            if self.top_at(i as i64, j as i64).is_some_and(|t| t > fl) {
                out.push(q);
            }
        });
        out
    }

    /// Engagement (degrees) of the tool at `c`, tip at `z`, moving along `dir`, with the
    /// current move's cut so far (`current`) not material: the measure of the front half of
    /// the ring where the field is positive, its sign changes found by bisection.
    pub fn engagement(&self, c: DVec2, z: f64, dir: DVec2, current: Option<&Path>) -> f64 {
        if z + self.eps >= self.stock_top || dir.length_squared() < 1e-24 {
            return 0.0;
        }
        let Some(slab) = self.slab_at(z + self.eps) else { return 0.0 };
        let rho = self.r + self.ring_delta;
        let base = dir.y.atan2(dir.x);
        let cur = current.map(Fast::new);
        let g = |th: f64| {
            let a = base + th;
            let q = c + rho * DVec2::new(a.cos(), a.sin());
            let d = slab.field.value(&self.lat, q);
            match &cur {
                Some(f) => d.min(f.distance(q) - self.r),
                None => d,
            }
        };
        let half = std::f64::consts::FRAC_PI_2;
        let n = ((std::f64::consts::PI * rho / (0.5 * self.lat.h)).ceil() as usize).clamp(32, 100_000);
        let step = 2.0 * half / n as f64;
        let mut total = 0.0;
        let (mut ta, mut ga) = (-half, g(-half));
        for k in 1..=n {
            let tb = -half + k as f64 * step;
            let gb = g(tb);
            let (ia, ib) = (ga > 0.0, gb > 0.0);
            if ia && ib {
                total += tb - ta;
            } else if ia != ib {
                // bisect the crossing
                let (mut lo, mut hi) = (ta, tb);
                while hi - lo > 1e-9 {
                    let mid = 0.5 * (lo + hi);
                    if (g(mid) > 0.0) == ia {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                let x = 0.5 * (lo + hi);
                total += if ia { x - ta } else { tb - x };
            }
            (ta, ga) = (tb, gb);
        }
        total.to_degrees()
    }

    /// Exact distance from the XY path to the part/fixture boundary (capped at `max`), or 0
    /// when the path starts inside them.
    fn keep_distance(&self, path: &Path, max: f64) -> f64 {
        super::sweep::keep_distance(&self.keep, &self.keep_edges, path, max)
    }

    /// Calls `f(slab, i, j, q)` for the samples of the slabs with material within `rho` of
    /// `fast` (a slab at a time, top down; tiles wholly outside skipped).
    fn material_near(&self, lo: DVec2, hi: DVec2, fast: &Fast, rho: f64, mut f: impl FnMut(&Slab, DVec2)) {
        let lat = &self.lat;
        let Some((tx0, tx1, ty0, ty1)) = lat.tiles_in(lo, hi) else { return };
        for s in &self.slabs {
            for ty in ty0..=ty1 {
                for tx in tx0..=tx1 {
                    let tile = &s.field.tiles[ty * lat.ntx + tx];
                    if matches!(tile, Tile::Outside) {
                        continue;
                    }
                    let (c, hd) = lat.tile_centre(tx, ty);
                    if fast.distance(c) - hd > rho {
                        continue;
                    }
                    for jj in 0..T {
                        for ii in 0..T {
                            let v = match tile {
                                Tile::Dense(d) => d[jj * T + ii],
                                _ => lat.band,
                            };
                            let q = lat.at(tx * T + ii, ty * T + jj);
                            if v > 0.0 && fast.distance(q) <= rho {
                                f(s, q);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// The part of `path` whose tip is below `z`, if any.
fn below(path: &Path, z: f64) -> Option<Path> {
    let (z0, z1) = path.z_range();
    match (z0 < z, z1 < z) {
        (true, true) => Some(*path),
        (false, false) => None,
        (a, _) => {
            let t = ((z - z0) / (z1 - z0)).clamp(0.0, 1.0);
            Some(if a { path.sub(0.0, t) } else { path.sub(t, 1.0) })
        }
    }
}

impl Engine for SdfSim {
    fn radius(&self) -> f64 {
        self.r
    }

    fn spacing(&self) -> f64 {
        self.lat.h
    }

    fn sample_step(&self) -> f64 {
        self.sample_step
    }

    fn rapid_depth(&self, path: &Path, to: DVec3) -> (f64, DVec3) {
        let (z0, z1) = path.z_range();
        let mut worst = 0.0f64;
        let mut at = to;
        if z0.min(z1) + self.eps >= self.stock_top {
            return (worst, at);
        }
        let rr = self.r - self.tol;
        let (lo, hi) = path.bbox(rr);
        self.material_near(lo, hi, &Fast::new(path), rr, |s, q| {
            let Some(z) = path.reach_zmin(q, rr) else { return };
            if s.at > z + self.eps && s.top - z > worst {
                worst = s.top - z;
                at = DVec3::new(q.x, q.y, z);
            }
        });
        (worst, at)
    }

    fn material_under(&self, c: DVec2, z: f64) -> bool {
        let Some(slab) = self.slab_at(z + self.eps) else { return false };
        let rr = self.r - self.tol;
        let (lo, hi) = (c - DVec2::splat(rr), c + DVec2::splat(rr));
        let Some((tx0, tx1, ty0, ty1)) = self.lat.tiles_in(lo, hi) else { return false };
        let (i0, j0) = (tx0 * T, ty0 * T);
        for j in j0..(ty1 + 1) * T {
            for i in i0..(tx1 + 1) * T {
                let q = self.lat.at(i, j);
                if (q - c).length() <= rr && slab.field.node(&self.lat, i as i64, j as i64) > 0.0 {
                    return true;
                }
            }
        }
        false
    }

    fn engagement(&mut self, p: DVec3, dir: DVec2, cur: &Path, _before: &Path) -> (Option<f64>, f64) {
        // (no pixel measure here: the field's engagement stands for both)
        let e = SdfSim::engagement(self, p.truncate(), p.z, dir, Some(cur));
        (Some(e), e)
    }

    fn gouge_depth(&self, path: &Path) -> (f64, DVec3) {
        let rr = self.r - self.tol;
        let (z0, z1) = path.z_range();
        let mut worst = 0.0f64;
        let mut at = path.at(0.0);
        // below the floor
        let zmin = z0.min(z1);
        if self.floor_eff - zmin > self.tol {
            worst = self.floor_eff - zmin;
            at = if z0 <= z1 { path.at(0.0) } else { path.at(1.0) };
        }
        // into the part or a fixture, where the tip is below their top
        let zlim = self.part_top_eff - self.tol;
        if zmin < zlim
            && !self.keep_edges.is_empty()
            && let Some(sub) = below(path, zlim)
        {
            let d = self.keep_distance(&sub, self.r);
            if d < rr {
                let (a, b) = sub.z_range();
                let depth = (self.part_top_eff - a.min(b)).max(self.r - d);
                if depth > worst {
                    worst = depth;
                    at = sub.at(0.0);
                }
            }
        }
        (worst, at)
    }

    fn cut_move(&mut self, path: &Path) {
        let lat = self.lat;
        let r = self.r;
        let (z0, z1) = path.z_range();
        let zmin = z0.min(z1);
        self.slabs.par_iter_mut().filter(|s| zmin < s.at).for_each(|s| {
            if let Some(sub) = below(path, s.at) {
                let (lo, hi) = sub.bbox(r);
                s.field.cut(&lat, &Fast::new(&sub), lo, hi, r);
            }
        });
        self.peak_bytes = self.peak_bytes.max(self.bytes());
    }

    fn removed_volume(&self) -> f64 {
        self.slabs.iter().map(|s| (self.base_area - s.field.area(&self.lat)) * (s.top - s.bottom)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Cutting, Width};
    use crate::toolpath::{Motion, Move, MoveKind};

    fn job() -> Job {
        Job {
            floor: -2.0,
            cutting: Cutting::with_tool_diameter(6.0).with_width(Width::Stepover(0.25)),
            ..Job::new("t", Area::rect(-20.0, -20.0, 20.0, 20.0), Area::empty(), 6.0, 2.0)
        }
    }

    fn sim(job: &Job) -> SdfSim {
        let regions = job.regions(job.radius(), 0.0).expect("regions");
        SdfSim::new(job, &regions, &SimOptions { res: Some(0.05), ..Default::default() }).expect("simulator")
    }

    fn feed(to: DVec3) -> Move {
        Move { to, motion: Motion::Line, kind: MoveKind::Cut, feed: 1000.0 }
    }

    #[test]
    fn a_slot_removes_its_stadium_and_engages_half_the_tool() {
        let job = job();
        let mut s = sim(&job);
        let z = -2.0;
        let mut tp = Toolpath::new(job.cutting.tool, DVec3::new(-10.0, 0.0, 5.0), 5.0);
        tp.moves.push(Move {
            to: DVec3::new(-10.0, 0.0, z),
            motion: Motion::Line,
            kind: MoveKind::Plunge,
            feed: 300.0,
        });
        tp.moves.push(feed(DVec3::new(10.0, 0.0, z)));
        let rp = s.replay(&tp, &mut |_| {});
        // a stadium 20 mm long, Ø6, 2 mm deep
        let want = (20.0 * 6.0 + std::f64::consts::PI * 9.0) * 2.0;
        assert!((rp.removed_volume - want).abs() < 0.002 * want, "{} vs {want}", rp.removed_volume);
        // a full slot engages the whole front half
        let mid: Vec<_> = rp.samples.iter().filter(|p| p.at.x > -5.0 && p.at.x < 5.0).collect();
        assert!(!mid.is_empty());
        for p in mid {
            assert!((p.tea - 180.0).abs() < 0.5, "{}", p.tea);
        }
        // a second pass 4.5 mm over (25 % stepover): the ring meets the first slot's wall 30°
        // behind the side
        let e = s.engagement(DVec2::new(0.0, 4.5), z, DVec2::X, None);
        let want = 90.0 + 30.0;
        assert!((e - want).abs() < 0.2, "{e} vs {want}");
    }

    #[test]
    fn a_cut_along_the_outline_leaves_no_phantom_strip() {
        // the tool's side runs exactly along the stock's edge at y = −20: the field there is a
        // ridge touching zero, which holds no area
        let job = job();
        let mut s = sim(&job);
        let mut tp = Toolpath::new(job.cutting.tool, DVec3::new(-10.0, -17.0, 5.0), 5.0);
        tp.moves.push(Move {
            to: DVec3::new(-10.0, -17.0, -2.0),
            motion: Motion::Line,
            kind: MoveKind::Plunge,
            feed: 300.0,
        });
        tp.moves.push(feed(DVec3::new(10.0, -17.0, -2.0)));
        let rp = s.replay(&tp, &mut |_| {});
        let want = (20.0 * 6.0 + std::f64::consts::PI * 9.0) * 2.0;
        assert!((rp.removed_volume - want).abs() < 0.001 * want, "{} vs {want}", rp.removed_volume);
    }

    #[test]
    fn tiles_are_freed_once_cut_through() {
        let job = job();
        let mut s = sim(&job);
        let mut tp = Toolpath::new(job.cutting.tool, DVec3::new(-20.0, -20.0, 5.0), 5.0);
        tp.moves.push(Move {
            to: DVec3::new(-20.0, -20.0, -2.0),
            motion: Motion::Line,
            kind: MoveKind::Plunge,
            feed: 300.0,
        });
        // rows 4 mm apart over the whole stock
        let mut y = -20.0;
        let mut left = true;
        while y <= 20.0 {
            let x = if left { 20.0 } else { -20.0 };
            tp.moves.push(feed(DVec3::new(x, y, -2.0)));
            y += 4.0;
            left = !left;
            tp.moves.push(feed(DVec3::new(x, y.min(20.0), -2.0)));
        }
        let rp = s.replay(&tp, &mut |_| {});
        let all = 40.0 * 40.0 * 2.0;
        assert!((rp.removed_volume - all).abs() < 0.002 * all, "{}", rp.removed_volume);
        assert_eq!(s.slab_count(), 1);
        // nothing but the band round the outline holds samples
        assert!(s.bytes() < 2 * s.base.bytes(), "{} vs {}", s.bytes(), s.base.bytes());
        assert!(s.rest().area_mm2 < 1.0);
    }
}
