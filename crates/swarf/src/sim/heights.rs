//! Heights from meshes for the simulators of 3D jobs: the part's height map over a grid, which
//! a model built with [`super::HeightMap`] reads to find gouges anywhere on the part's surface;
//! the material model of a whole mesh job, and the rest material it leaves (the grey closing of
//! the part's heights by the tool's disk).

use super::grid::Grid;
use super::raster::RasterSim;
use super::replay::{Rest, TopView};
use super::{HeightMap, SimOptions};
use crate::error::Result;
use crate::geom::mesh::Mesh;
use crate::model::{MeshJob, Tool};
use rayon::prelude::*;
use std::sync::Arc;

/// The highest facet over each cell centre of `grid` (−∞ where there is none), row-major.
pub fn height_map(mesh: &Mesh, grid: &Grid) -> Vec<f32> {
    let mut h = vec![f32::NEG_INFINITY; grid.len()];
    // rows in parallel: each row scans the facets whose y-range covers it
    let mut by_row: Vec<Vec<usize>> = vec![Vec::new(); grid.ny];
    for (ti, t) in mesh.tris.iter().enumerate() {
        let ylo = t[0].y.min(t[1].y).min(t[2].y);
        let yhi = t[0].y.max(t[1].y).max(t[2].y);
        let j0 = ((ylo - grid.y0) / grid.res - 0.5).ceil().max(0.0) as usize;
        let j1 = ((yhi - grid.y0) / grid.res - 0.5).floor();
        if j1 < 0.0 {
            continue;
        }
        for row in by_row.iter_mut().take((j1 as usize + 1).min(grid.ny)).skip(j0) {
            row.push(ti);
        }
    }
    h.par_chunks_mut(grid.nx).zip(by_row.par_iter()).enumerate().for_each(|(j, (row, tris))| {
        let y = grid.y0 + (j as f64 + 0.5) * grid.res;
        for &ti in tris {
            let t = &mesh.tris[ti];
            // the facet's span on this row: intersect the line y with its edges
            let mut xs = [0.0f64; 3];
            let mut zs = [0.0f64; 3];
            let mut n = 0;
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if (a.y <= y) != (b.y <= y) {
                    let u = (y - a.y) / (b.y - a.y);
                    xs[n] = a.x + (b.x - a.x) * u;
                    zs[n] = a.z + (b.z - a.z) * u;
                    n += 1;
                    if n == 2 {
                        break;
                    }
                }
            }
            if n < 2 {
                continue;
            }
            let (xa, za, xb, zb) =
                if xs[0] <= xs[1] { (xs[0], zs[0], xs[1], zs[1]) } else { (xs[1], zs[1], xs[0], zs[0]) };
            let i0 = ((xa - grid.x0) / grid.res - 0.5).ceil().max(0.0) as usize;
            let i1 = ((xb - grid.x0) / grid.res - 0.5).floor();
            if i1 < 0.0 {
                continue;
            }
            for (i, cell) in row.iter_mut().enumerate().take((i1 as usize + 1).min(grid.nx)).skip(i0) {
                let x = grid.x0 + (i as f64 + 0.5) * grid.res;
                let z = if xb - xa > 1e-12 { za + (zb - za) * (x - xa) / (xb - xa) } else { za.max(zb) };
                *cell = cell.max(z as f32);
            }
        }
    });
    h
}

/// The material model of a whole mesh job: the stock box, with the part's surface from the
/// mesh (raised by the floor allowance) as what must stay.
pub(crate) fn mesh_model(job: &MeshJob, sim: &SimOptions) -> Result<RasterSim> {
    mesh_model_after(job, &job.cutting.tool, None, sim)
}

/// The material model of a whole mesh job for `tool` (the job's own tool in [`mesh_model`]),
/// its stock what an earlier model left: the heights of `after` where a cell's centre falls in
/// its grid (cells of grids of one size aligned to the stock's corner coincide), the stock box
/// elsewhere or when there is none. A sequence of programs with tools of their own is replayed
/// on one stock this way, each on what the ones before it left.
pub(crate) fn mesh_model_after(
    job: &MeshJob,
    tool: &Tool,
    after: Option<&HeightMap>,
    sim: &SimOptions,
) -> Result<RasterSim> {
    let mut mj = job.model_job();
    mj.cutting.tool = tool.clone();
    let regions = mj.regions(mj.radius(), 0.0)?;
    let grid = RasterSim::grid_for(&mj, &regions.keep, sim)?;
    let mut part = height_map(&job.mesh, &grid);
    let lift = job.allowance_floor as f32;
    for h in &mut part {
        *h += lift;
    }
    let stock = match after {
        None => vec![f32::INFINITY; grid.len()],
        Some(a) => (0..grid.len())
            .map(|k| a.cell(grid.center(k % grid.nx, k / grid.nx)).map_or(f32::INFINITY, |c| a.stock[c]))
            .collect(),
    };
    let opts = SimOptions { heights: Some(Arc::new(HeightMap { grid, stock, part: Some(part) })), ..sim.clone() };
    RasterSim::new(&mj, &regions, &opts)
}

/// Material the tool could have removed and left: at each cell, the stock above the lowest
/// height a flat end mill of the job's radius reaches there without touching the part (the grey
/// closing of the part's heights by the tool's disk), counted where it is thicker than the
/// simulation's tolerance; and the stock seen from above, in blocks of cells at most
/// `view_side` to a side, for the picture.
///
/// The rest is split into terraces and what lies beyond them (see [`rest_above`]) by the reach
/// over the part raised at each cell to its highest within a cell and a half (every
/// neighbouring cell): a path keeps a few hundredths of a millimetre from the part (offsets,
/// simplification, arcs), and on a wall with a slight draft the cell centres within that
/// clearance stand a whole level high; such a sliver, narrower than a cell, is not material the
/// tool could have cut. (The same idea as the rest band of an independent checker that raises
/// the part by its highest within 0.02 mm.)
pub(crate) fn mesh_rest(job: &MeshJob, sim: &RasterSim, view_side: usize) -> (Rest, TopView) {
    let g = sim.grid;
    let low = reach(job, &g, sim.part_heights(), job.radius());
    let banded = disk_filter(sim.part_heights(), g.nx, g.ny, REST_BAND_CELLS, true);
    let far = reach(job, &g, &banded, job.radius());
    let levels = job.levels();
    (rest_above(job, sim, &low, &far, &levels), top_view(job, sim, &low, &far, &levels, view_side))
}

/// The lowest height a flat end mill of radius `radius` reaches at each cell of `grid` without
/// touching the part (read from the mesh, raised by the floor allowance) or going below the
/// floor, row-major: what [`mesh_rest`] measures the stock against, for any tool and on any
/// grid (a model's own, or a larger one whose cells it shares).
pub(crate) fn mesh_reach(job: &MeshJob, grid: &Grid, radius: f64) -> Vec<f32> {
    let lift = job.allowance_floor as f32;
    let part: Vec<f32> = height_map(&job.mesh, grid).into_iter().map(|h| h + lift).collect();
    reach(job, grid, &part, radius)
}

/// The grey closing of the part's heights `part` on `grid` by the disk of radius `radius`, never
/// below the part itself or the floor.
fn reach(job: &MeshJob, grid: &Grid, part: &[f32], radius: f64) -> Vec<f32> {
    let g = *grid;
    let floor = (job.floor + job.allowance_floor) as f32;
    let p: Vec<f32> = part.iter().map(|&h| h.max(floor)).collect();
    // the sideways allowance: the part's heights spread over a disk of its radius (a cylinder
    // round each point, which holds the ball of the allowance)
    let p = if job.allowance > 0.0 { disk_filter(&p, g.nx, g.ny, job.allowance / g.res, true) } else { p };
    // (the tool's axis kept R + res/√2 from the part's cell centres, as a path running exactly
    // at R from the true surface may be that far from the nearest centre: no phantom slivers
    // along walls; slivers thinner than that go unreported)
    let rc = radius / g.res + std::f64::consts::FRAC_1_SQRT_2;
    // tool tip height at each centre: the highest part under the disk (dilation), then the
    // lowest of those over the disks that cover a cell (erosion)
    let tip = disk_filter(&p, g.nx, g.ny, rc, true);
    let reach = disk_filter(&tip, g.nx, g.ny, radius / g.res, false);
    reach.iter().zip(&p).map(|(r, p)| r.max(*p)).collect()
}

/// The rest material of `sim`'s stock above `low` (the heights of [`mesh_reach`] on `sim`'s
/// grid): the stock standing more than the simulation's tolerance above it inside the stock box,
/// where `low` is below the stock top (the area the tool reaches). Split by the program's
/// `levels` (tool-tip heights): where the stock stands no higher than the lowest level (or the
/// stock top) at or above `low`, the rest is a terrace z-level roughing leaves by design (on a
/// slope, between a level and the surface below it); above that, the tool could have cut it at
/// a level and did not. `far` is the reach the split is judged by (see [`mesh_rest`]; `low`
/// itself, or higher).
pub(crate) fn rest_above(job: &MeshJob, sim: &RasterSim, low: &[f32], far: &[f32], levels: &[f64]) -> Rest {
    let terraces = Terraces::new(job, levels);
    let g = sim.grid;
    let s = sim.heights();
    let (slo, shi) = (job.stock_lo, job.stock_hi);
    let cell = g.res * g.res;
    let mut r = Rest::default();
    for j in 0..g.ny {
        for i in 0..g.nx {
            let c = g.center(i, j);
            if c.x < slo.x || c.x > shi.x || c.y < slo.y || c.y > shi.y {
                continue;
            }
            let k = j * g.nx + i;
            if low[k] >= shi.z as f32 - REST_TOL {
                continue;
            }
            r.reachable_mm2 += cell;
            let t = s[k] - low[k];
            if t > REST_TOL {
                if t > 0.5 {
                    log::trace!("rest {t:.3} mm at {c:?} (stock {:.3}, reach {:.3})", s[k], low[k]);
                }
                r.area_mm2 += cell;
                r.volume_mm3 += t as f64 * cell;
                r.max_thickness_mm = r.max_thickness_mm.max(t as f64);
                if terraces.holds(s[k], far[k]) {
                    r.terrace_mm2 += cell;
                    r.terrace_volume_mm3 += t as f64 * cell;
                } else {
                    r.beyond_max_thickness_mm = r.beyond_max_thickness_mm.max(t as f64);
                }
            }
        }
    }
    r
}

/// Rest thinner than this is none, mm.
const REST_TOL: f32 = 0.01;

/// The band round the part within which rest is judged no miss, in cells (see [`mesh_rest`]).
const REST_BAND_CELLS: f64 = 1.5;

/// The terraces z-level roughing leaves by design: over a cell the tool reaches down to `low`,
/// the lowest it can stand is the lowest level at or above `low` (or the stock top, above which
/// nothing is cut), and stock no higher than that is a terrace; above it, the tool could have
/// cut it at a level and did not.
struct Terraces {
    /// The levels and the stock top, ascending.
    zs: Vec<f32>,
}

impl Terraces {
    fn new(job: &MeshJob, levels: &[f64]) -> Terraces {
        let mut zs: Vec<f32> =
            levels.iter().chain([&job.stock_hi.z]).map(|&z| z as f32).filter(|z| z.is_finite()).collect();
        zs.sort_by(f32::total_cmp);
        Terraces { zs }
    }

    /// Whether stock standing at `s` over a cell the tool reaches down to `low` is a terrace.
    fn holds(&self, s: f32, low: f32) -> bool {
        let at = self.zs.partition_point(|&z| z < low - REST_TOL);
        self.zs.get(at).is_some_and(|&z| s <= z + REST_TOL)
    }
}

/// The stock of `sim` seen from above in square blocks of cells, at most `side` blocks to a
/// side: each block's mean stock top and its thickest rest above `low`, terraces and the rest
/// beyond them apart (as [`rest_above`]).
pub(crate) fn top_view(
    job: &MeshJob,
    sim: &RasterSim,
    low: &[f32],
    far: &[f32],
    levels: &[f64],
    side: usize,
) -> TopView {
    let terraces = Terraces::new(job, levels);
    let g = sim.grid;
    let s = sim.heights();
    let (slo, shi) = (job.stock_lo, job.stock_hi);
    // the stock box's cells only
    let (i0, j0) =
        (((slo.x - g.x0) / g.res).floor().max(0.0) as usize, ((slo.y - g.y0) / g.res).floor().max(0.0) as usize);
    let (i1, j1) =
        ((((shi.x - g.x0) / g.res).ceil() as usize).min(g.nx), (((shi.y - g.y0) / g.res).ceil() as usize).min(g.ny));
    let (w, h) = (i1.saturating_sub(i0), j1.saturating_sub(j0));
    let k = w.max(h).div_ceil(side.max(1)).max(1);
    let (nx, ny) = (w.div_ceil(k), h.div_ceil(k));
    let mut v = TopView {
        nx,
        ny,
        x0: g.x0 + i0 as f64 * g.res,
        y0: g.y0 + j0 as f64 * g.res,
        side: k as f64 * g.res,
        height: vec![f32::NAN; nx * ny],
        terrace: vec![0.0; nx * ny],
        beyond: vec![0.0; nx * ny],
        top: shi.z,
        bottom: job.floor + job.allowance_floor,
    };
    for bj in 0..ny {
        for bi in 0..nx {
            let (mut sum, mut n) = (0.0f64, 0usize);
            let b = bj * nx + bi;
            for j in j0 + bj * k..(j0 + (bj + 1) * k).min(j1) {
                for i in i0 + bi * k..(i0 + (bi + 1) * k).min(i1) {
                    let c = j * g.nx + i;
                    if s[c].is_finite() {
                        sum += f64::from(s[c]);
                        n += 1;
                    }
                    if low[c] >= shi.z as f32 - REST_TOL {
                        continue;
                    }
                    let t = s[c] - low[c];
                    if t > REST_TOL {
                        let into = if terraces.holds(s[c], far[c]) { &mut v.terrace[b] } else { &mut v.beyond[b] };
                        *into = into.max(t);
                    }
                }
            }
            if n > 0 {
                v.height[b] = (sum / n as f64) as f32;
            }
        }
    }
    v
}

/// Maximum (`max`) or minimum over the disk of radius `rc` cells around every cell. Outside the
/// grid counts as −∞ for the maximum and +∞ for the minimum.
///
/// The disk is its rows: at row offset `d` it spans the columns `±w(d)`, `w(d) = ⌊√(rc² − d²)⌋`.
/// Each source row's running extremes over `[i − w, i + w]` are built for `w = 0, 1, …` by
/// `H₀ = h`, `H₁[i] = ext(h[i−1], h[i], h[i+1])`, `H_{w+1}[i] = ext(H_w[i−1], H_w[i+1])` (the two
/// windows of width `2w+1` overlap from `w = 1` and together cover `2w+3` columns): one
/// vectorised pass a width, and each `H_{w(d)}` is folded into the output rows `d` above and
/// below it. Output rows go in bands of several radii in parallel, each band holding its own
/// rows, so a band reads every source row once (`(band + 2r) · r` passes for `band · (2r + 1)`
/// folds). Exact, so the result does not depend on the band size or the thread count. (Written
/// here: the image-processing crates' grey-level morphology is for 8-bit images and square or
/// diamond structuring elements, not f32 heights and Euclidean disks.)
fn disk_filter(h: &[f32], nx: usize, ny: usize, rc: f64, max: bool) -> Vec<f32> {
    if max { disk_filter_by::<true>(h, nx, ny, rc) } else { disk_filter_by::<false>(h, nx, ny, rc) }
}

/// The extreme of two heights (the larger for `MAX`); written so that the passes vectorise.
#[inline(always)]
fn ext2<const MAX: bool>(a: f32, b: f32) -> f32 {
    if MAX {
        if a > b { a } else { b }
    } else if a < b {
        a
    } else {
        b
    }
}

/// [`disk_filter`] for one of the two extremes.
fn disk_filter_by<const MAX: bool>(h: &[f32], nx: usize, ny: usize, rc: f64) -> Vec<f32> {
    use rayon::prelude::*;
    let ext = if MAX { f32::NEG_INFINITY } else { f32::INFINITY };
    if nx == 0 || ny == 0 {
        return Vec::new();
    }
    let ri = rc.max(0.0).floor() as usize;
    // half-width of the disk's chord at each row offset (non-increasing)
    let widths: Vec<usize> = (0..=ri).map(|d| ((rc * rc - (d * d) as f64).max(0.0)).sqrt().floor() as usize).collect();
    let wmax = widths[0];
    // a row padded by `wmax` cells of `ext` on each side: its running extremes over
    // `[i − w, i + w]` are right on the columns `w..m − w` of the padded row, which hold the
    // grid's columns
    let m = nx + 2 * wmax;
    let band = (4 * ri).max(32);
    let mut out = vec![ext; nx * ny];
    out.par_chunks_mut(band * nx).enumerate().for_each(|(b, o)| {
        let (j0, rows) = (b * band, o.len() / nx);
        let (mut cur, mut nxt) = (vec![ext; m], vec![ext; m]);
        let src_lo = j0.saturating_sub(ri);
        let src_hi = (j0 + rows - 1 + ri).min(ny - 1);
        for js in src_lo..=src_hi {
            cur.fill(ext);
            cur[wmax..wmax + nx].copy_from_slice(&h[js * nx..(js + 1) * nx]);
            let mut w = 0;
            // offsets by decreasing distance: their widths rise
            for d in (0..=ri).rev() {
                let want = widths[d];
                while w < want {
                    if w == 0 {
                        for i in 1..m - 1 {
                            nxt[i] = ext2::<MAX>(ext2::<MAX>(cur[i - 1], cur[i]), cur[i + 1]);
                        }
                    } else {
                        for ((n, a), c) in nxt[1..m - 1].iter_mut().zip(&cur[..m - 2]).zip(&cur[2..]) {
                            *n = ext2::<MAX>(*a, *c);
                        }
                    }
                    std::mem::swap(&mut cur, &mut nxt);
                    w += 1;
                }
                let src = &cur[wmax..wmax + nx];
                for jo in [js as i64 - d as i64, js as i64 + d as i64] {
                    let r = jo - j0 as i64;
                    if r >= 0 && (r as usize) < rows {
                        let row = &mut o[r as usize * nx..(r as usize + 1) * nx];
                        for (a, s) in row.iter_mut().zip(src) {
                            *a = ext2::<MAX>(*a, *s);
                        }
                    }
                    if d == 0 {
                        break;
                    }
                }
            }
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::DVec2;
    use crate::geom::mesh::tests::pocket_block;

    #[test]
    fn height_map_reads_the_top_surface() {
        let m = pocket_block(10.0, 4.0);
        let g = Grid { x0: -1.0, y0: -1.0, res: 0.5, nx: 24, ny: 24 };
        let h = height_map(&m, &g);
        let at = |x: f64, y: f64| {
            let (i, j) = g.cell_of(DVec2::new(x, y)).unwrap();
            h[j * g.nx + i]
        };
        assert_eq!(at(1.1, 1.1), 10.0);
        assert_eq!(at(5.1, 5.1), 4.0);
        assert_eq!(at(-0.6, 5.1), f32::NEG_INFINITY);
    }

    #[test]
    fn disk_filter_matches_brute_force() {
        // seeded heights on grids narrower and wider than the disk, every radius kind
        let mut seed = 0x2545_f491_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % 1000) as f32 / 100.0
        };
        for (nx, ny) in [(1usize, 1usize), (7, 3), (23, 41), (80, 75)] {
            let h: Vec<f32> = (0..nx * ny).map(|_| next()).collect();
            for rc in [0.0, 0.7, 1.0, 2.5, 4.5, 9.99, 30.2] {
                for max in [true, false] {
                    let got = disk_filter(&h, nx, ny, rc, max);
                    for j in 0..ny {
                        for i in 0..nx {
                            let mut want = if max { f32::NEG_INFINITY } else { f32::INFINITY };
                            for jj in 0..ny {
                                for ii in 0..nx {
                                    let d2 = (ii as f64 - i as f64).powi(2) + (jj as f64 - j as f64).powi(2);
                                    if d2 <= rc * rc {
                                        let v = h[jj * nx + ii];
                                        want = if max { want.max(v) } else { want.min(v) };
                                    }
                                }
                            }
                            assert_eq!(got[j * nx + i], want, "{nx}×{ny} rc {rc} max {max} at {i} {j}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn terraces_stand_no_higher_than_the_lowest_level_the_tool_could_take() {
        let job = MeshJob::new(
            "t",
            pocket_block(10.0, 4.0),
            crate::geom::DVec3::new(0.0, 0.0, -10.0),
            crate::geom::DVec3::new(10.0, 10.0, 0.0),
            crate::model::Cutting::default(),
        );
        let t = Terraces::new(&job, &[-3.0, -6.0]);
        // the tool reaches -4 here: it could stand at -3, not lower
        assert!(t.holds(-3.0, -4.0) && t.holds(-3.5, -4.0));
        assert!(!t.holds(-2.0, -4.0), "a level's worth above: missed");
        // reaching exactly a level (within the tolerance), the tool stands at it
        assert!(t.holds(-6.0, -6.005) && !t.holds(-3.0, -6.005));
        // below every level: the lowest level; above them all: the stock top, uncut
        assert!(t.holds(-6.0, -9.0) && !t.holds(-5.0, -9.0));
        assert!(t.holds(0.0, -1.0));
    }

    #[test]
    fn disk_filter_is_a_disk() {
        let (nx, ny) = (21, 21);
        let mut h = vec![0f32; nx * ny];
        h[10 * nx + 10] = 1.0;
        let d = disk_filter(&h, nx, ny, 4.5, true);
        for j in 0..ny {
            for i in 0..nx {
                let r2 = (i as f64 - 10.0).powi(2) + (j as f64 - 10.0).powi(2);
                assert_eq!(d[j * nx + i], if r2 <= 4.5 * 4.5 { 1.0 } else { 0.0 }, "{i} {j}");
            }
        }
    }
}
