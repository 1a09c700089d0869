//! Each tool's own paths (paper 3 §3 Algorithm 1, §4 Algorithms 3–4): its levels, regions of
//! tool centres and contour-parallel loops, prepared once whatever the sequence, and the
//! program of a tool given the tools before it — its loops trimmed to the material they left
//! (or, for Algorithm 3, new loops over the rest region), emitted with its own entries and
//! links. See the module [`super`] for why the search keeps these paths and this emitter.

use super::{Decomposition, MAX_TOOLS, SeqOptions};
use crate::error::{Error, Result};
use crate::geom::index::{EdgeIndex, InsideIndex};
use crate::geom::{Area, DVec2, DVec3, segments_intersect};
use crate::model::tooldb::{ToolDb, ToolRun, ToolSpec};
use crate::model::{MeshJob, REGION_TOL, Tool};
use crate::toolpath::{MoveKind, Toolpath};
use rayon::prelude::*;
use std::time::Instant;

/// Points of a path are this far apart at most when trimmed (mm).
const SAMPLE: f64 = 0.5;
/// The tool disk is grown by this when it is asked whether it meets material (mm): more than
/// the sagitta of a `SAMPLE` chord on the smallest disk, so a path between two samples in air
/// is in air.
pub const NEED_MARGIN: f64 = 0.05;
/// Tool centres keep this much more than the radius from the part (mm).
const WALL_MARGIN: f64 = 0.005;
/// Material thinner than this above a level is taken as cleared (mm): levels of two tools this
/// close are one.
pub(super) const Z_TOL: f64 = 0.05;
/// Rest areas smaller than this are dropped (mm²).
pub(super) const SLIVER: f64 = 1e-3;
/// Ramps start this far above the level above (mm).
const RAMP_CLEAR: f64 = 0.05;
/// Tool centres stay this much less than the radius outside the stock (mm).
const OUTSIDE: f64 = 0.1;
/// Rapids stop this far above the material before a feed move down (mm).
const APPROACH: f64 = 0.5;

/// A continuous feed path at one level: points at most [`SAMPLE`] apart.
#[derive(Debug, Clone)]
struct Chain {
    pts: Vec<DVec2>,
    /// Arc length at each point.
    at: Vec<f64>,
    /// Index of the point closing the chain's first loop (a ramp follows that loop).
    ring_end: usize,
}

/// One level of one tool.
#[derive(Debug, Clone)]
pub(super) struct Level {
    pub(super) z: f64,
    /// The level above it for this tool (or the stock top): what the tool's own earlier levels
    /// cleared.
    above: f64,
    /// Tool centres.
    centres: Area,
    /// What the tool clears at this level (Algorithm 2).
    pub(super) access: Area,
    /// Its full contour-parallel path (Algorithm 1).
    chains: Vec<Chain>,
    /// Index of its height among every tool's levels.
    pub(super) zi: usize,
    /// Where the tool may travel just above the level above (its centres, grown by 4 µm: the
    /// tool cleared everything over them down to that level), when the level above is cut.
    over: Option<Area>,
}

/// A tool with its levels.
#[derive(Debug, Clone)]
pub(super) struct ToolGeom {
    pub(super) spec: ToolSpec,
    pub(super) number: u32,
    pub(super) levels: Vec<Level>,
}

/// Everything that does not depend on the sequence.
pub(super) struct Prepared {
    pub(super) tools: Vec<ToolGeom>,
    /// Every tool's levels, top down.
    pub(super) zs: Vec<f64>,
    /// At each of them, the part's keep grown a little (the band no tool enters counts as
    /// cleared).
    pub(super) bands: Vec<Area>,
    /// Their edges (where a piece goes down, [`Emitter::descend`]).
    band_edges: Vec<EdgeIndex>,
    pub(super) stock: Area,
    top: f64,
    clear_z: f64,
    pub(super) machine: crate::model::tooldb::Machine,
    opts: SeqOptions,
}

/// Reads the levels, shadows, regions and loops of every tool.
pub(super) fn prepare(job: &MeshJob, db: &ToolDb, opts: &SeqOptions) -> Result<Prepared> {
    job.validate()?;
    opts.validate()?;
    if db.tools.is_empty() {
        return Err(Error::job("tools", "the tool database has no tools"));
    }
    if db.tools.len() > MAX_TOOLS {
        return Err(Error::job(
            "tools",
            format!(
                "{} tools: the search covers every subset of them (2^{} sequences); at most {MAX_TOOLS}",
                db.tools.len(),
                db.tools.len() - 1
            ),
        ));
    }
    // biggest first; equal diameters in the file's order
    let mut order: Vec<usize> = (0..db.tools.len()).collect();
    order.sort_by(|&a, &b| db.tools[b].diameter.total_cmp(&db.tools[a].diameter).then(a.cmp(&b)));
    let tool_levels: Vec<Vec<f64>> = order.iter().map(|&i| job.levels_on_grid(db.tools[i].depth_of_cut)).collect();
    // every tool's levels, each shadow once, top down
    let mut zs: Vec<f64> = tool_levels.iter().flatten().copied().collect();
    zs.sort_by(|a, b| b.total_cmp(a));
    zs.dedup();
    let t0 = Instant::now();
    let mut shadows = crate::geom::mesh::Shadows::new(&job.mesh);
    let keeps: Vec<Area> = zs
        .iter()
        .map(|&z| {
            let ta = Instant::now();
            let sh = shadows.down_to(z - job.allowance_floor);
            let tb = ta.elapsed().as_secs_f64();
            let k = crate::model::keep_of(sh, job.allowance);
            log::trace!(
                "toolseq: shadow z {z:.3} {} vertices {} rings {} polys, {tb:.3} s, keep {:.3} s",
                sh.vertex_count(),
                sh.rings().count(),
                sh.polys.len(),
                ta.elapsed().as_secs_f64() - tb
            );
            k
        })
        .collect();
    log::debug!("toolseq: {} levels, shadows in {:.2} s", zs.len(), t0.elapsed().as_secs_f64());
    let bands: Vec<Area> = keeps.par_iter().map(|k| k.offset(WALL_MARGIN + 0.03, REGION_TOL)).collect();
    let band_edges: Vec<EdgeIndex> = bands.par_iter().map(|b| EdgeIndex::from_area(b, 1.0)).collect();
    let stock = job.stock_area();
    let keep_at = |z: f64| zs.iter().position(|&w| w == z).expect("a level of some tool");
    let pairs: Vec<(usize, usize)> =
        tool_levels.iter().enumerate().flat_map(|(t, ls)| (0..ls.len()).map(move |l| (t, l))).collect();
    let geoms: Vec<Option<(Area, Area, Vec<Chain>)>> = pairs
        .par_iter()
        .map(|&(t, l)| {
            let spec = &db.tools[order[t]];
            let r = spec.diameter / 2.0;
            let keep = &keeps[keep_at(tool_levels[t][l])];
            let ta = Instant::now();
            // (centres may leave the stock by up to the radius less OUTSIDE, so that the tool
            // reaches the stock's edges and the corners the part leaves there)
            let centres = stock
                .offset(r - OUTSIDE, REGION_TOL)
                .difference(&keep.offset(r + WALL_MARGIN, REGION_TOL))
                .without_slivers(SLIVER);
            if centres.is_empty() {
                return None;
            }
            let tb = Instant::now();
            let access = centres.offset(r - 0.01, REGION_TOL);
            let tc = Instant::now();
            let chains = chains_of(&centres, spec.width_of_cut.min(spec.diameter / 2.0));
            log::trace!(
                "toolseq: D{} z {:.3}: centres {:.3} s ({} vertices), access {:.3} s, {} chains {:.3} s",
                spec.diameter,
                tool_levels[t][l],
                (tb - ta).as_secs_f64(),
                centres.vertex_count(),
                (tc - tb).as_secs_f64(),
                chains.len(),
                tc.elapsed().as_secs_f64()
            );
            Some((centres, access, chains))
        })
        .collect();
    let mut tools: Vec<ToolGeom> = order
        .iter()
        .map(|&i| ToolGeom { spec: db.tools[i].clone(), number: i as u32 + 1, levels: Vec::new() })
        .collect();
    for (&(t, l), g) in pairs.iter().zip(geoms) {
        let Some((centres, access, chains)) = g else { continue };
        let z = tool_levels[t][l];
        let above = if l == 0 { job.stock_hi.z } else { tool_levels[t][l - 1] };
        let over = tools[t].levels.last().filter(|p| p.z == above).map(|p| p.centres.offset(0.004, REGION_TOL));
        tools[t].levels.push(Level { z, above, centres, access, chains, zi: keep_at(z), over });
    }
    Ok(Prepared {
        tools,
        zs,
        bands,
        band_edges,
        stock,
        top: job.stock_hi.z,
        clear_z: job.top() + opts.clearance,
        machine: db.machine.clone(),
        opts: opts.clone(),
    })
}

/// Algorithm 1: the contour-parallel path of a region of tool centres, as continuous chains.
///
/// The region and its inward offsets by `ae` form a tree (each offset polygon lies in one
/// polygon of the offset before it); the tree is cut from the leaves up (inside out, so every
/// loop cuts into material on its outer side), each loop in its stored orientation (outer
/// boundaries counter-clockwise, holes clockwise: climb milling with a clockwise spindle), from
/// its vertex nearest to where the tool is. A loop joins the chain before it by a straight step
/// when that is no longer than 1.5·`ae` and stays inside the region; otherwise it starts a
/// new chain.
fn chains_of(region: &Area, ae: f64) -> Vec<Chain> {
    let mut layers: Vec<Vec<crate::geom::area::Polygon>> = vec![region.polys.clone()];
    loop {
        let d = layers.len() as f64 * ae;
        let a = region.offset(-d, REGION_TOL).without_slivers(SLIVER);
        if a.is_empty() || layers.len() > 10_000 {
            break;
        }
        layers.push(a.polys);
    }
    // children[k][j]: the polygons of layer k + 1 inside polygon j of layer k
    let mut children: Vec<Vec<Vec<usize>>> = layers.iter().map(|l| vec![Vec::new(); l.len()]).collect();
    for k in 1..layers.len() {
        let parents: Vec<Area> = layers[k - 1].iter().map(|p| Area { polys: vec![p.clone()] }).collect();
        for (i, p) in layers[k].iter().enumerate() {
            let q = p.outer[0];
            let j = parents.iter().position(|a| a.contains(q)).unwrap_or_else(|| {
                // (on a parent's boundary within rounding: the nearest parent)
                nearest_index(parents.iter().map(|a| ring_distance(&a.polys[0].outer, q)))
            });
            children[k - 1][j].push(i);
        }
    }
    let mut b = ChainBuilder { chains: Vec::new(), cur: Vec::new(), ring_end: 0, pos: None, ae };
    let roots: Vec<usize> = (0..layers[0].len()).collect();
    for root in b.nearest_order(&roots, &layers[0]) {
        b.visit(&layers, &children, 0, root, &layers[0][root]);
    }
    b.flush();
    b.chains
}

struct ChainBuilder {
    chains: Vec<Chain>,
    cur: Vec<DVec2>,
    ring_end: usize,
    pos: Option<DVec2>,
    ae: f64,
}

impl ChainBuilder {
    /// `items` ordered greedily, each nearest (by its outer ring's vertices) to where the
    /// one before left the tool — approximated by the current position for all.
    fn nearest_order(&self, items: &[usize], polys: &[crate::geom::area::Polygon]) -> Vec<usize> {
        let mut v = items.to_vec();
        if let Some(p) = self.pos {
            v.sort_by(|&a, &b| {
                ring_distance(&polys[a].outer, p).total_cmp(&ring_distance(&polys[b].outer, p)).then(a.cmp(&b))
            });
        }
        v
    }

    fn visit(
        &mut self,
        layers: &[Vec<crate::geom::area::Polygon>],
        children: &[Vec<Vec<usize>>],
        k: usize,
        j: usize,
        root: &crate::geom::area::Polygon,
    ) {
        let mut kids = children[k][j].clone();
        while !kids.is_empty() {
            let next = self.nearest_order(&kids, &layers[k + 1])[0];
            kids.retain(|&c| c != next);
            self.visit(layers, children, k + 1, next, root);
        }
        let poly = &layers[k][j];
        let mut rings: Vec<&Vec<DVec2>> = poly.rings().collect();
        while !rings.is_empty() {
            let p = self.pos.unwrap_or(rings[0][0]);
            let (ri, vi) = rings
                .iter()
                .enumerate()
                .map(|(ri, r)| {
                    let vi = nearest_index(r.iter().map(|q| (*q - p).length_squared()));
                    (ri, vi, (r[vi] - p).length_squared())
                })
                .min_by(|a, b| a.2.total_cmp(&b.2))
                .map(|(ri, vi, _)| (ri, vi))
                .unwrap_or((0, 0));
            let ring = rings.remove(ri);
            let mut closed: Vec<DVec2> = ring[vi..].iter().chain(ring[..vi].iter()).copied().collect();
            closed.push(ring[vi]);
            self.add_ring(closed, root);
        }
    }

    fn add_ring(&mut self, closed: Vec<DVec2>, root: &crate::geom::area::Polygon) {
        let start = closed[0];
        let joined = match self.cur.last() {
            Some(&end) => (start - end).length() <= 1.5 * self.ae + 1e-9 && !crosses(root, end, start),
            None => false,
        };
        if !joined {
            self.flush();
        }
        let first = self.cur.is_empty();
        if !first {
            densify_to(&mut self.cur, start);
        } else {
            self.cur.push(start);
        }
        for &q in &closed[1..] {
            densify_to(&mut self.cur, q);
        }
        if first {
            self.ring_end = self.cur.len() - 1;
        }
        self.pos = Some(start);
    }

    fn flush(&mut self) {
        if self.cur.len() >= 2 {
            let pts = std::mem::take(&mut self.cur);
            let mut at = Vec::with_capacity(pts.len());
            let mut s = 0.0;
            for (i, p) in pts.iter().enumerate() {
                if i > 0 {
                    s += (*p - pts[i - 1]).length();
                }
                at.push(s);
            }
            self.chains.push(Chain { pts, at, ring_end: self.ring_end });
        }
        self.cur.clear();
        self.ring_end = 0;
    }
}

/// Appends points up to `q` at most [`SAMPLE`] apart (the last point of `v` is the start).
fn densify_to(v: &mut Vec<DVec2>, q: DVec2) {
    let p = *v.last().expect("a start point");
    let l = (q - p).length();
    if l < 1e-9 {
        return;
    }
    let n = (l / SAMPLE).ceil() as usize;
    for i in 1..=n {
        v.push(p + (q - p) * (i as f64 / n as f64));
    }
}

/// True when the segment `a`–`b` meets a ring of `area`.
fn crosses_area(area: &Area, a: DVec2, b: DVec2) -> bool {
    area.polys.iter().any(|p| crosses(p, a, b))
}

/// True when the open segment `a`–`b` crosses a ring of `poly`.
fn crosses(poly: &crate::geom::area::Polygon, a: DVec2, b: DVec2) -> bool {
    poly.rings().any(|r| (0..r.len()).any(|i| segments_intersect(a, b, r[i], r[(i + 1) % r.len()])))
}

fn ring_distance(ring: &[DVec2], p: DVec2) -> f64 {
    ring.iter().map(|q| (*q - p).length_squared()).fold(f64::INFINITY, f64::min)
}

fn nearest_index(it: impl Iterator<Item = f64>) -> usize {
    it.enumerate().min_by(|a, b| a.1.total_cmp(&b.1)).map_or(0, |(i, _)| i)
}

/// What one level of a tool cuts given its prefix: chains and, per point, whether the disk
/// there meets material.
struct LevelCut<'a> {
    chains: Vec<(std::borrow::Cow<'a, Chain>, Vec<bool>)>,
    /// Cut every point (Algorithm 3's rest paths), not only where material is.
    cut_all: bool,
}

fn level_cut<'a>(prep: &Prepared, k: usize, lv: &'a Level, prefix: &[usize], mats: &[Area]) -> LevelCut<'a> {
    let tg = &prep.tools[k];
    let r = tg.spec.diameter / 2.0;
    let none = LevelCut { chains: Vec::new(), cut_all: false };
    let material = &mats[lv.zi];
    if material.is_empty() {
        return none;
    }
    // the disk at p meets material: p inside it, or within the radius of its boundary
    let inside = InsideIndex::new(material);
    let rm = r + NEED_MARGIN;
    let edges = EdgeIndex::from_area(material, rm.max(1.0));
    let meets = |p: DVec2| inside.contains(p) || edges.distance(p, rm) < rm;
    match prep.opts.decomposition {
        _ if prefix.is_empty() || prep.opts.decomposition == Decomposition::Trim => {
            let chains = lv
                .chains
                .iter()
                .filter_map(|c| {
                    let need: Vec<bool> = c.pts.iter().map(|&p| meets(p)).collect();
                    need.iter().any(|&b| b).then_some((std::borrow::Cow::Borrowed(c), need))
                })
                .collect();
            LevelCut { chains, cut_all: false }
        }
        _ => {
            let reach = material.offset(rm, REGION_TOL);
            let region = lv.centres.intersection(&reach).without_slivers(SLIVER);
            if region.is_empty() {
                return none;
            }
            let chains = chains_of(&region, tg.spec.width_of_cut.min(tg.spec.diameter / 2.0))
                .into_iter()
                .map(|c| {
                    let need: Vec<bool> = c.pts.iter().map(|&p| meets(p)).collect();
                    (std::borrow::Cow::Owned(c), need)
                })
                .collect();
            LevelCut { chains, cut_all: true }
        }
    }
}

/// The program of tool `k` after the tools `prefix`, its run, and the length of its path
/// whose disk meets material.
pub(super) fn run_tool(prep: &Prepared, k: usize, prefix: &[usize], mats: &[Area]) -> (Toolpath, ToolRun, f64) {
    let tg = &prep.tools[k];
    let spec = &tg.spec;
    let t0 = Instant::now();
    let cuts: Vec<LevelCut> = tg.levels.par_iter().map(|lv| level_cut(prep, k, lv, prefix, mats)).collect();
    let t_cut = t0.elapsed().as_secs_f64();
    let tool = Tool { diameter: spec.diameter, number: tg.number, flutes: spec.teeth };
    // the pieces (one chain of one level each), cut in an order that keeps the tool in one
    // place: the nearest piece whose material above is gone (every piece of a level above
    // whose box, grown by the diameter, meets its box), so that a corner or a pocket is cut
    // level after level before the tool travels to the next
    let mut pieces: Vec<Piece> = Vec::new();
    for (li, cut) in cuts.iter().enumerate() {
        for (chain, need) in &cut.chains {
            let first = need.iter().position(|&b| b).unwrap_or(0);
            let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
            for p in &chain.pts {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
            let g = DVec2::splat(spec.diameter / 2.0 + NEED_MARGIN);
            pieces.push(Piece {
                li,
                chain,
                need,
                cut_all: cut.cut_all,
                lo: lo - g,
                hi: hi + g,
                start: chain.pts[first.saturating_sub(1)],
            });
        }
    }
    let d = spec.diameter;
    let deps: Vec<Vec<usize>> = pieces
        .iter()
        .map(|pj| {
            pieces
                .iter()
                .enumerate()
                .filter(|(_, pi)| pi.li < pj.li && boxes_meet(pi.lo, pi.hi, pj.lo, pj.hi, d))
                .map(|(i, _)| i)
                .collect()
        })
        .collect();
    let start = pieces.first().map_or(DVec2::ZERO, |p| p.start);
    let mut tp = Toolpath::new(tool, DVec3::new(start.x, start.y, prep.clear_z), prep.clear_z);
    let mut e = Emitter {
        tp: &mut tp,
        prep,
        feed: spec.feed_mm_min(),
        need_mm: 0.0,
        pieces: &pieces,
        done: vec![false; pieces.len()],
    };
    let mut pos = start;
    let mut last_level = usize::MAX;
    for _ in 0..pieces.len() {
        let next = (0..pieces.len())
            .filter(|&j| !e.done[j] && deps[j].iter().all(|&i| e.done[i]))
            .min_by(|&a, &b| {
                (pieces[a].start - pos)
                    .length_squared()
                    .total_cmp(&(pieces[b].start - pos).length_squared())
                    .then(a.cmp(&b))
            })
            .expect("the levels above a piece come first");
        let pc = &pieces[next];
        let lv = &tg.levels[pc.li];
        if pc.li != last_level {
            e.tp.note(format!("level z {:.3}", lv.z));
            last_level = pc.li;
        }
        e.chain(pc.chain, pc.need, lv, pc.li, pc.cut_all);
        e.done[next] = true;
        pos = e.tp.end().truncate();
    }
    let need_mm = e.need_mm;
    let end = tp.end();
    if end.z < prep.clear_z - 1e-9 {
        tp.rapid(DVec3::new(end.x, end.y, prep.clear_z));
    }
    let t = tp.totals(prep.machine.rapid_feed_mm_min);
    log::debug!(
        "toolseq: {} after {:?}: levels {t_cut:.3} s, program {:.3} s, {} moves",
        tg.spec.id,
        prefix.iter().map(|&i| prep.tools[i].spec.id.as_str()).collect::<Vec<_>>(),
        t0.elapsed().as_secs_f64() - t_cut,
        tp.moves.len()
    );
    let run = ToolRun {
        cut_mm: t.cut_length_mm,
        air_mm: t.rapid_length_mm,
        feed_mm_min: spec.feed_mm_min(),
        price: spec.price,
        life_min: spec.life_min,
    };
    (tp, run, need_mm)
}

/// One chain of one level, as the program cuts it.
struct Piece<'a> {
    li: usize,
    chain: &'a Chain,
    need: &'a [bool],
    cut_all: bool,
    /// Box of the chain grown by the radius.
    lo: DVec2,
    hi: DVec2,
    /// Where the tool goes down first (about).
    start: DVec2,
}

/// True when the bounding boxes of two areas overlap.
pub(super) fn boxes_overlap(a: &Area, b: &Area) -> bool {
    match (a.bounds(), b.bounds()) {
        (Some((alo, ahi)), Some((blo, bhi))) => boxes_meet(alo, ahi, blo, bhi, 0.0),
        _ => false,
    }
}

/// True when two boxes come within `d` of each other.
fn boxes_meet(alo: DVec2, ahi: DVec2, blo: DVec2, bhi: DVec2, d: f64) -> bool {
    alo.x <= bhi.x + d && blo.x <= ahi.x + d && alo.y <= bhi.y + d && blo.y <= ahi.y + d
}

struct Emitter<'a> {
    tp: &'a mut Toolpath,
    prep: &'a Prepared,
    feed: f64,
    need_mm: f64,
    pieces: &'a [Piece<'a>],
    done: Vec<bool>,
}

impl Emitter<'_> {
    /// Cuts the needed pieces of one chain.
    fn chain(&mut self, c: &Chain, need: &[bool], lv: &Level, li: usize, cut_all: bool) {
        let n = c.pts.len();
        let z = lv.z;
        for i in 1..n {
            if need[i - 1] && need[i] {
                self.need_mm += c.at[i] - c.at[i - 1];
            }
        }
        // runs of needed points, each grown by one point (in air) at both ends
        let mut groups: Vec<(usize, usize)> = Vec::new();
        if cut_all {
            groups.push((0, n - 1));
        } else {
            let mut i = 0;
            while i < n {
                if !need[i] {
                    i += 1;
                    continue;
                }
                let a = i.saturating_sub(1);
                while i < n && need[i] {
                    i += 1;
                }
                let b = i.min(n - 1);
                // feed on through the air when that is quicker than a retract and a rapid
                if let Some(last) = groups.last_mut() {
                    let gap = c.at[a] - c.at[last.1];
                    let up = 2.0 * (lv.above + APPROACH - z) + (c.pts[a] - c.pts[last.1]).length();
                    if gap / self.feed <= up / self.prep.machine.rapid_feed_mm_min + APPROACH / self.feed {
                        last.1 = b;
                        continue;
                    }
                }
                groups.push((a, b));
            }
        }
        // a chain that starts in material and has air on its first loop goes down in the air
        // there, cuts the loop round to where it went down, and goes back along it to its
        // start (cleared on the way round) to carry on: no ramp
        let re = c.ring_end;
        let rotate = if need[0] && re > 0 { (1..re).find(|&i| !need[i]) } else { None };
        if rotate.is_some() {
            let b0 = groups.iter().filter(|g| g.0 <= re).map(|g| g.1).max().unwrap_or(re).max(re);
            groups.retain(|g| g.0 > re);
            groups.insert(0, (0, b0));
        }
        let tan = self.prep.opts.ramp_deg.to_radians().tan();
        for (a, b) in groups {
            let p = c.pts[a];
            let mut a = a;
            if let (0, Some(i0)) = (a, rotate) {
                let q = c.pts[i0];
                self.descend(q, lv, li);
                self.lines(&c.pts[i0..=re], MoveKind::Cut, z);
                self.lines(&c.pts[..=i0], MoveKind::Cut, z);
                let back: Vec<DVec2> = c.pts[..=i0].iter().rev().copied().collect();
                self.lines(&back, MoveKind::Link, z);
                a = re;
            } else if a == 0 && need[0] {
                self.go_to(p, lv, li);
                // a ramp down along the first loop, from the level above
                let z0 = lv.above.min(self.prep.top) + RAMP_CLEAR;
                self.tp.rapid(DVec3::new(p.x, p.y, z0 + APPROACH));
                self.tp.line(MoveKind::Descend, DVec3::new(p.x, p.y, z0), self.feed);
                let ring_len = c.at[c.ring_end];
                if ring_len < 1e-6 {
                    self.tp.line(MoveKind::Plunge, DVec3::new(p.x, p.y, z), self.feed);
                } else {
                    let dz = z0 - z;
                    let turns = (dz / tan / ring_len).ceil().max(1.0);
                    let total = turns * ring_len;
                    for t in 0..turns as usize {
                        for i in 1..=c.ring_end {
                            let s = t as f64 * ring_len + c.at[i];
                            let q = c.pts[i];
                            self.tp.line(MoveKind::Entry, DVec3::new(q.x, q.y, z0 - dz * s / total), self.feed);
                        }
                    }
                }
            } else {
                self.descend(p, lv, li);
            }
            // the cut: straight runs merged (the points are a sampling of the loops' edges)
            let mut run: Vec<DVec2> = vec![c.pts[a]];
            let mut kind = MoveKind::Cut;
            for i in a + 1..=b {
                let k = if cut_all || need[i - 1] || need[i] { MoveKind::Cut } else { MoveKind::Link };
                if k != kind && run.len() > 1 {
                    self.lines(&run, kind, z);
                    run = vec![*run.last().expect("a point")];
                }
                kind = k;
                run.push(c.pts[i]);
            }
            self.lines(&run, kind, z);
        }
    }

    /// Down to `p` at level `lv`, where the disk is in air: a rapid to just above the level and
    /// a feed move down, at `p` or, when the disk there reaches into the band along the part
    /// that the material model counts as cleared ([`Prepared::bands`]: a sliver up to 0.03 mm
    /// wide may stand there as high as the level above, on a sloping wall), at the nearest
    /// point away from the band where it does not, and across to `p` at the level.
    fn descend(&mut self, p: DVec2, lv: &Level, li: usize) {
        let z = lv.z;
        let r = self.tp.tool.radius();
        let want = r + WALL_MARGIN;
        // (pushed off the nearest band edge a few times: in a corner, off the next one too;
        // 2 µm more, for the rounding of the coordinates; never further than NEED_MARGIN, so
        // that the disk stays in air)
        let band = &self.prep.band_edges[lv.zi];
        let mut at = p;
        for _ in 0..4 {
            match band.nearest(at, want) {
                Some((q, d)) if d > 1e-9 => at += (at - q) / d * (want - d + 0.002),
                _ => break,
            }
        }
        let clear = (at - p).length() < NEED_MARGIN
            && band.distance(at, want) >= want
            && !self.prep.bands[lv.zi].contains(at)
            && lv.centres.contains(at);
        if !clear {
            at = p;
        }
        self.go_to(at, lv, li);
        self.tp.rapid(DVec3::new(at.x, at.y, z + APPROACH));
        self.tp.line(MoveKind::Descend, DVec3::new(at.x, at.y, z), self.feed);
        if at != p {
            self.tp.line(MoveKind::Cut, DVec3::new(p.x, p.y, z), self.feed);
        }
    }

    fn lines(&mut self, run: &[DVec2], kind: MoveKind, z: f64) {
        if run.len() < 2 {
            return;
        }
        for q in crate::geom::simplify::douglas_peucker(run, 1e-4).into_iter().skip(1) {
            self.tp.line(kind, DVec3::new(q.x, q.y, z), self.feed);
        }
    }

    /// Up and across to above `p`: just above the level above where the straight way stays
    /// over the centres of that level (all cleared down to it), else at the clearance plane.
    fn go_to(&mut self, p: DVec2, lv: &Level, li: usize) {
        let end = self.tp.end();
        let cz = self.prep.clear_z;
        if self.tp.moves.is_empty() && (end.truncate() - p).length() < 1e-9 {
            return;
        }
        let low = lv.above + APPROACH;
        let e = end.truncate();
        // (the level above is cut wherever the way passes: every piece of it whose box meets
        // the way's box grown by the radius is done)
        let (lo, hi) = (e.min(p), e.max(p));
        let r = self.tp.tool.radius() + NEED_MARGIN;
        let above_done = || {
            self.pieces
                .iter()
                .zip(&self.done)
                .all(|(pc, &done)| done || li == 0 || pc.li + 1 != li || !boxes_meet(pc.lo, pc.hi, lo, hi, r))
        };
        let h = match &lv.over {
            Some(o) if end.z <= lv.above + 1e-9 && low < cz && above_done() && !crosses_area(o, e, p) => low,
            _ => cz,
        };
        if end.z < h - 1e-9 {
            self.tp.rapid(DVec3::new(end.x, end.y, h));
        }
        let h = h.max(end.z);
        self.tp.rapid(DVec3::new(p.x, p.y, h));
    }
}
