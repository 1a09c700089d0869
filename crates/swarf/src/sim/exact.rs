//! Exact engagement: the arc of the tool circle that lies in uncut material, computed from the
//! cleared geometry instead of pixels.
//!
//! Every cut is kept as a swept primitive (a straight stadium or an annular arc band of the tool
//! radius) in a uniform grid. For a tool at `c` moving in direction `dir`, the ring of radius
//! `rho = R + δ` is intersected analytically: the front half of the ring inside the stock, minus
//! the angular intervals covered by every primitive that cut at or below the current level. The
//! crossing angles of the ring with each primitive's boundary (the tool circles at its ends and
//! its two side lines or side circles) split the ring into pieces that are wholly in or out; the
//! midpoint of each piece decides. The result is exact up to floating point: no pixels, no ring
//! sampling. This is the reference that the pixel method of paper 1 eq. 4 is checked against.
//!
//! A primitive whose z changes (helix, ramp) is split into pieces at most `dz` deep, each
//! counted as clearing down to its highest point — slightly conservative on the way down.
//!
//! Primitives are only ever added, so a query asked after `n` of them can be answered later
//! from those `n` alone: a replay keeps its queries ([`Query`]) and answers them all at its end
//! on every core ([`ExactModel::engagements`]), with the same bits as at once. A query reads the
//! primitives newest first and skips an older one that cannot reach the arcs still uncovered.
//! [`ExactModel::engagements_guided`] measures only anchors along a move and the stretches
//! between them where the pixel readings leave the engagement in doubt (`docs/simulation.md`).

use super::sweep::{Fast, Path};
use crate::geom::DVec2;

/// How much wider than a query's ring, in tool radii, the disk whose primitives
/// [`ExactModel::near`] keeps for the queries after it.
const NEAR_SLACK: f64 = 0.5;

/// What a replay tells the thread that keeps its exact model ([`serve`]), in the replay's order.
#[derive(Debug, Clone, Copy)]
pub enum ToExact {
    /// A move was cut: record it.
    Add(Path),
    /// The samples of a cutting move follow.
    Move,
    /// The exact engagement of a sample (its [`Query::upto`] is filled in on arrival: the
    /// primitives recorded by then), with its pixel reading.
    Query(Query, f32),
}

/// Exact engagement queries answered together, whole moves at a time (a batch bounds the memory
/// they hold; the last one is answered after the replay has walked the whole program, while it
/// waits: 2048 keep that wait short on small programs, where 16 384 left a fifth of the proof
/// to it, and still give each batch's parallel measure enough to share out). The answers do not
/// depend on it.
const QUERY_BATCH: usize = 1 << 11;

/// Keeps `model` on a thread of its own while a replay runs on another: records the cuts and
/// answers the queries it receives, in their order ([`ExactModel::engagements_guided`] with
/// `stride`, a batch of whole moves at a time), until the replay drops its sender; then sends
/// all the answers, in order, on `answers` and returns the model. The replay's cutting and
/// pixel readings and the exact engagement then run side by side, with the same answers as
/// one after the other.
pub fn serve(
    mut model: ExactModel,
    messages: std::sync::mpsc::Receiver<Vec<ToExact>>,
    answers: std::sync::mpsc::Sender<Vec<f64>>,
    stride: usize,
) -> ExactModel {
    let (mut queries, mut pixels, mut starts, mut out) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for chunk in messages {
        for m in chunk {
            match m {
                ToExact::Add(path) => model.add(&path),
                ToExact::Move => {
                    if queries.len() >= QUERY_BATCH {
                        out.extend(model.engagements_guided(&queries, &pixels, &starts, stride));
                        queries.clear();
                        pixels.clear();
                        starts.clear();
                    }
                    starts.push(queries.len());
                }
                ToExact::Query(q, px) => {
                    queries.push(Query { upto: model.recorded(), ..q });
                    pixels.push(px);
                }
            }
        }
    }
    out.extend(model.engagements_guided(&queries, &pixels, &starts, stride));
    // (the replay waits for them; it cannot have gone)
    let _ = answers.send(out);
    model
}

/// Largest departure, degrees, of a pixel reading from the line between its anchors' readings
/// for [`ExactModel::engagements_guided`] to draw the exact engagement along that line.
pub const GUIDE_SMOOTH_DEG: f64 = 3.0;
/// Largest difference, degrees, between an anchor's pixel reading and its exact engagement for
/// [`ExactModel::engagements_guided`] to trust the pixels beside it.
pub const GUIDE_AGREE_DEG: f64 = 8.0;

/// One swept primitive at constant z (the level it clears down to).
#[derive(Debug, Clone, Copy)]
struct Prim {
    path: Path,
    fast: Fast,
    z: f64,
    /// A disk that holds the whole sweep (centre, radius): the quick rejects of a query.
    hull: (DVec2, f64),
}

impl Prim {
    fn new(path: Path, z: f64, r: f64) -> Self {
        let hull = match path {
            Path::Line { a, b } => (0.5 * (a.truncate() + b.truncate()), 0.5 * (b - a).truncate().length() + r),
            Path::Arc(_) => {
                let (lo, hi) = path.bbox(r);
                (0.5 * (lo + hi), 0.5 * (hi - lo).length())
            }
        };
        Prim { path, fast: Fast::new(&path), z, hull }
    }
}

/// Which of a move's anchors (sample indices, ascending) top a peak of the pixel readings:
/// an anchor whose reading stands more than [`GUIDE_SMOOTH_DEG`] above the anchors on both
/// sides of it. The pixels round a corner's peak off and the exact peak may lie a sample or
/// two beside such an anchor, so [`ExactModel::engagements_guided`] measures both stretches
/// beside it exactly.
fn peak_anchors(pixel: &[f32], anchors: &[usize]) -> Vec<bool> {
    let above = |k: usize, j: usize| pixel[anchors[k]] as f64 > pixel[anchors[j]] as f64 + GUIDE_SMOOTH_DEG;
    (0..anchors.len()).map(|k| k > 0 && k + 1 < anchors.len() && above(k, k - 1) && above(k, k + 1)).collect()
}

/// Cleared geometry of the job so far, for exact engagement queries.
#[derive(Debug, Clone)]
pub struct ExactModel {
    r: f64,
    prims: Vec<Prim>,
    origin: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
    stock_rings: Vec<Vec<DVec2>>,
    stock_edges: crate::geom::index::EdgeIndex,
    stock_top: f64,
    dz: f64,
    scratch: Scratch,
}

/// The buffers of one engagement query (one set a thread when queries run in parallel).
#[derive(Debug, Clone, Default)]
struct Scratch {
    angles: Vec<f64>,
    base: Vec<(f64, f64)>,
    /// Covered intervals of the ring (sorted and merged by [`Scratch::gaps`]).
    covered: Vec<(f64, f64)>,
    /// A disk round each arc of the base not covered yet (centre, radius).
    disks: Vec<(DVec2, f64)>,
    /// The primitives near the last queries ([`ExactModel::near`]), newest first: those
    /// recorded before `near_upto`, at or below `near_zq`, whose hull reaches into the disk
    /// `near_disk`.
    near: Vec<u32>,
    near_disk: Option<(DVec2, f64)>,
    near_upto: u32,
    /// The height the list was made for: the primitives at or below it (a query at or below
    /// it reads the list).
    near_zq: f64,
    /// The list being made.
    near_new: Vec<u32>,
}

impl Scratch {
    /// Sorts and merges the covered intervals, and puts a disk round each arc of the base
    /// they leave uncovered into `disks`: the smallest that holds the arc (the arcs are at most
    /// a half turn, so it is the one on their chord). False when nothing is left uncovered.
    fn gaps(&mut self, ring: &Ring) -> bool {
        self.covered.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut w = 0;
        for i in 0..self.covered.len() {
            let iv = self.covered[i];
            if w > 0 && iv.0 <= self.covered[w - 1].1 {
                self.covered[w - 1].1 = self.covered[w - 1].1.max(iv.1);
            } else {
                self.covered[w] = iv;
                w += 1;
            }
        }
        self.covered.truncate(w);
        self.disks.clear();
        let disks = &mut self.disks;
        uncovered(&self.base, &self.covered, |a, b| {
            let (pa, pb) = (ring.point(a), ring.point(b));
            disks.push((0.5 * (pa + pb), 0.5 * (pb - pa).length()));
        });
        !self.disks.is_empty()
    }
}

/// An engagement query kept for later ([`ExactModel::engagements`]): the arguments of
/// [`ExactModel::engagement`] and the number of primitives recorded when it was asked.
#[derive(Debug, Clone, Copy)]
pub struct Query {
    /// Tool centre.
    pub c: DVec2,
    /// Tool tip height.
    pub z: f64,
    /// Direction of motion.
    pub dir: DVec2,
    /// Ring radius.
    pub rho: f64,
    /// Height above the tip below which material does not count.
    pub eps: f64,
    /// The part of the current move already cut.
    pub current: Option<Path>,
    /// The primitives recorded before the query: only these count.
    pub upto: u32,
}

impl ExactModel {
    /// A model for a tool of radius `r` over the box `[lo, hi]`, with the stock outline rings and
    /// top. `dz` is the depth of the pieces descending moves are split into.
    pub fn new(r: f64, lo: DVec2, hi: DVec2, stock_rings: Vec<Vec<DVec2>>, stock_top: f64, dz: f64) -> Self {
        let cell = (2.0 * r).max(0.5);
        let nx = (((hi.x - lo.x) / cell).ceil() as usize).clamp(1, 4096);
        let ny = (((hi.y - lo.y) / cell).ceil() as usize).clamp(1, 4096);
        let cell = cell.max((hi.x - lo.x) / nx as f64).max((hi.y - lo.y) / ny as f64);
        let stock_edges = crate::geom::index::EdgeIndex::from_rings(stock_rings.iter(), cell);
        Self {
            r,
            prims: Vec::new(),
            origin: lo,
            cell,
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
            stock_rings,
            stock_edges,
            stock_top,
            dz: dz.max(1e-4),
            scratch: Scratch::default(),
        }
    }

    fn cell_range(&self, lo: DVec2, hi: DVec2) -> Option<(usize, usize, usize, usize)> {
        let gx0 = ((lo.x - self.origin.x) / self.cell).floor();
        let gy0 = ((lo.y - self.origin.y) / self.cell).floor();
        let gx1 = ((hi.x - self.origin.x) / self.cell).floor();
        let gy1 = ((hi.y - self.origin.y) / self.cell).floor();
        if gx1 < 0.0 || gy1 < 0.0 || gx0 >= self.nx as f64 || gy0 >= self.ny as f64 {
            return None;
        }
        Some((
            gx0.max(0.0) as usize,
            (gx1 as usize).min(self.nx - 1),
            gy0.max(0.0) as usize,
            (gy1 as usize).min(self.ny - 1),
        ))
    }

    /// Records the cut of one move.
    pub fn add(&mut self, path: &Path) {
        let (z0, z1) = path.z_range();
        let len = path.xy_length();
        // pieces: at most 2R long (keeps the grid buckets tight) and at most dz deep
        let n_len = (len / (2.0 * self.r)).ceil().max(1.0);
        let n_dz = ((z1 - z0).abs() / self.dz).ceil().max(1.0);
        let n = n_len.max(n_dz).min(100_000.0) as usize;
        for i in 0..n {
            let p = path.sub(i as f64 / n as f64, (i + 1) as f64 / n as f64);
            let (a, b) = p.z_range();
            let z = a.max(b);
            if path.xy_length() < 1e-12 && i > 0 {
                break;
            }
            let id = self.prims.len() as u32;
            let pp = if len < 1e-12 { path.sub(0.0, 0.0) } else { p };
            self.prims.push(Prim::new(pp, z, self.r));
            let (lo, hi) = p.bbox(self.r);
            if let Some((x0, x1, y0, y1)) = self.cell_range(lo, hi) {
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        self.cells[y * self.nx + x].push(id);
                    }
                }
            }
            if len < 1e-12 {
                // a vertical move: one primitive for all of it, at its lowest point
                if let Some(last) = self.prims.last_mut() {
                    last.z = z0.min(z1);
                }
                break;
            }
        }
    }

    /// Engagement angle in degrees of a tool at `c`, tip at `z`, moving along `dir`, with
    /// material counting when it stands more than `eps` above the tip. `current` is the part of
    /// the current move already cut (excluded as material). `rho` is the ring radius.
    pub fn engagement(&mut self, c: DVec2, z: f64, dir: DVec2, rho: f64, eps: f64, current: Option<&Path>) -> f64 {
        let mut scratch = std::mem::take(&mut self.scratch);
        let q = Query { c, z, dir, rho, eps, current: current.copied(), upto: self.prims.len() as u32 };
        let tea = self.measure(&q, &mut scratch);
        self.scratch = scratch;
        tea
    }

    /// The queries' engagements, in their order, as [`Self::engagement`] would have answered
    /// each when it was asked (only the primitives recorded before it count). They run in
    /// parallel; the answers do not depend on the number of threads.
    pub fn engagements(&self, queries: &[Query]) -> Vec<f64> {
        use rayon::prelude::*;
        // fixed chunks, a scratch each: the same work whatever the number of threads
        queries
            .par_chunks(512)
            .flat_map_iter(|chunk| {
                let mut scratch = Scratch::default();
                chunk.iter().map(|q| self.measure(q, &mut scratch)).collect::<Vec<_>>()
            })
            .collect()
    }

    /// The engagements of the queries of whole moves, guided by their pixel readings: exactly
    /// at anchors (every `stride`-th sample of a move, and its first and last), and between two
    /// anchors either exactly too or, where the reading is unambiguous, along the line between
    /// the anchors' exact values. A stretch between anchors is unambiguous when its pixel
    /// readings stay within [`GUIDE_SMOOTH_DEG`] of the line between the anchors' readings and
    /// each anchor's reading is within [`GUIDE_AGREE_DEG`] of its exact value: the engagement
    /// then changes smoothly there, as the pixel ring sees it, and the pixels agree with the
    /// geometry at both ends — and neither anchor tops a peak of the readings
    /// ([`peak_anchors`]: a program of boss_with_clamp read 88.7° at such an anchor where the
    /// sample after it reads 90.5°). `pixel[i]` is the pixel reading of `queries[i]`; `starts`
    /// are the indices of the first query of each move, ascending. The answers do not depend
    /// on the number of threads.
    pub fn engagements_guided(&self, queries: &[Query], pixel: &[f32], starts: &[usize], stride: usize) -> Vec<f64> {
        assert_eq!(queries.len(), pixel.len(), "a pixel reading per query");
        let stride = stride.max(1);
        let n = queries.len();
        let mut ends: Vec<(usize, usize)> = Vec::with_capacity(starts.len());
        for (k, &a) in starts.iter().enumerate() {
            let b = starts.get(k + 1).copied().unwrap_or(n);
            if b > a {
                ends.push((a, b));
            }
        }
        // 1. the anchors
        let mut anchor = vec![false; n];
        for &(a, b) in &ends {
            for i in (a..b).step_by(stride) {
                anchor[i] = true;
            }
            anchor[b - 1] = true;
        }
        let first: Vec<usize> = (0..n).filter(|&i| anchor[i]).collect();
        let qs: Vec<Query> = first.iter().map(|&i| queries[i]).collect();
        let mut out = vec![f64::NAN; n];
        for (&i, v) in first.iter().zip(self.engagements(&qs)) {
            out[i] = v;
        }
        // 2. between anchors: exactly where the pixels are ambiguous, along the line elsewhere
        let mut second: Vec<usize> = Vec::new();
        let mut lines: Vec<(usize, usize)> = Vec::new();
        for &(a, b) in &ends {
            let anchors: Vec<usize> = (a..b).filter(|&i| anchor[i]).collect();
            let peaks = peak_anchors(pixel, &anchors);
            let at_peak = |i: usize| anchors.binary_search(&i).is_ok_and(|k| peaks[k]);
            let mut lo = a;
            while lo + 1 < b {
                let hi = (lo + stride).min(b - 1);
                if hi > lo + 1 && (at_peak(lo) || at_peak(hi)) {
                    second.extend(lo + 1..hi);
                } else if hi > lo + 1 {
                    let (pa, pb) = (pixel[lo] as f64, pixel[hi] as f64);
                    let span = (hi - lo) as f64;
                    let smooth = (lo + 1..hi).all(|i| {
                        let t = (i - lo) as f64 / span;
                        (pixel[i] as f64 - (pa + t * (pb - pa))).abs() <= GUIDE_SMOOTH_DEG
                    });
                    let agree = (out[lo] - pa).abs() <= GUIDE_AGREE_DEG && (out[hi] - pb).abs() <= GUIDE_AGREE_DEG;
                    if smooth && agree {
                        lines.push((lo, hi));
                    } else {
                        second.extend(lo + 1..hi);
                    }
                }
                lo = hi;
            }
        }
        let qs: Vec<Query> = second.iter().map(|&i| queries[i]).collect();
        for (&i, v) in second.iter().zip(self.engagements(&qs)) {
            out[i] = v;
        }
        for (lo, hi) in lines {
            let (ea, eb) = (out[lo], out[hi]);
            let span = (hi - lo) as f64;
            for (i, v) in out[lo + 1..hi].iter_mut().enumerate() {
                let t = (i + 1) as f64 / span;
                *v = ea + t * (eb - ea);
            }
        }
        out
    }

    /// The number of primitives recorded so far (a [`Query::upto`]).
    pub fn recorded(&self) -> u32 {
        self.prims.len() as u32
    }

    /// Fills `sc.near` with the primitives recorded before `upto`, at or below `zq`, whose hull
    /// reaches within `rho` of `c` — and maybe others, never fewer — newest first: the
    /// candidates of a query before its own tests. Consecutive queries of a replay stand close
    /// together, so the list is kept for a disk [`NEAR_SLACK`] radii wider than the ring and
    /// read again by the next queries whose rings lie inside that disk, with only the
    /// primitives recorded since looked up in the cells of the disk's box; a query outside it
    /// (or asked with fewer primitives, or higher) builds the list anew. Every primitive that
    /// reaches a ring inside the disk is listed in a cell of its box, and one listed that
    /// cannot reach the ring is rejected by the query's own tests or adds no interval, so the
    /// answers are those of the ring's own cells, to the bit. A replay's queries skip the scan
    /// of the cells and the sort that most of them needed (a seventh of the exact engagement's
    /// instructions on square_pocket), and in 3D the cuts of the levels above, which every
    /// cell lists.
    fn near(&self, c: DVec2, rho: f64, zq: f64, upto: u32, sc: &mut Scratch) {
        let kept = sc.near_disk.is_some_and(|(kc, kr)| (c - kc).length() + rho <= kr)
            && upto >= sc.near_upto
            && zq <= sc.near_zq;
        if !kept {
            let reach = rho + NEAR_SLACK * self.r;
            sc.near_disk = Some((c, reach));
            sc.near_zq = zq;
            sc.near_upto = 0;
            sc.near.clear();
        }
        if upto > sc.near_upto {
            // the primitives recorded since (all of them for a new list), from the cells of
            // the disk's box (those of this ring's box alone would miss one a later ring
            // reaches), at or below the height
            let (kc, kr) = sc.near_disk.expect("a disk");
            let m = DVec2::splat(kr);
            let z = sc.near_zq;
            self.listed(kc - m, kc + m, sc.near_upto, upto, &mut sc.near_new, |p| {
                p.z <= z && (p.hull.0 - kc).length() - p.hull.1 <= kr
            });
            sc.near_new.extend_from_slice(&sc.near);
            std::mem::swap(&mut sc.near, &mut sc.near_new);
            sc.near_upto = upto;
        }
    }

    /// The primitives numbered `from..upto` listed in the cells that meet the box `[lo, hi]`
    /// that pass `keep`, each once, newest first, into `out`.
    fn listed(&self, lo: DVec2, hi: DVec2, from: u32, upto: u32, out: &mut Vec<u32>, keep: impl Fn(&Prim) -> bool) {
        out.clear();
        if let Some((x0, x1, y0, y1)) = self.cell_range(lo, hi) {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    // a cell lists its primitives in the order they were recorded
                    let list = &self.cells[y * self.nx + x];
                    let end = list.partition_point(|&id| id < upto);
                    let start = list[..end].partition_point(|&id| id < from);
                    out.extend(list[start..end].iter().filter(|&&id| keep(&self.prims[id as usize])));
                }
            }
        }
        out.sort_unstable_by(|a, b| b.cmp(a));
        out.dedup();
    }

    fn measure(&self, q: &Query, sc: &mut Scratch) -> f64 {
        let Query { c, z, dir, rho, eps, current, upto } = *q;
        if z + eps >= self.stock_top || dir.length_squared() < 1e-24 {
            return 0.0;
        }
        let ring = Ring { c, rho, u: dir.normalize() };
        // 1. front half inside the stock
        sc.angles.clear();
        sc.angles.push(-1.0);
        sc.angles.push(1.0);
        let m = DVec2::splat(rho);
        let angles = &mut sc.angles;
        self.stock_edges.for_each_near(c - m, c + m, |_, a, b| ring.segment_crossings(a, b, angles));
        sc.angles.sort_by(f64::total_cmp);
        sc.base.clear();
        for w in sc.angles.windows(2) {
            if w[1] - w[0] < 1e-12 {
                continue;
            }
            if self.in_stock(ring.point(0.5 * (w[0] + w[1]))) {
                push_merge(&mut sc.base, (w[0], w[1]));
            }
        }
        if sc.base.is_empty() {
            return 0.0;
        }
        // 2. intervals covered by the move so far, then by the cuts at or below this level
        // recorded before the query near the ring ([`Self::near`]), newest first (the newest
        // cover most of what will be covered, and each of the others is then first tested
        // against the arcs still uncovered: one that cannot reach any of them adds nothing)
        sc.covered.clear();
        let rr = self.r;
        let zq = z + eps;
        if let Some(cur) = &current {
            covered_intervals(cur, &Fast::new(cur), rr, &ring, &mut sc.angles, &mut sc.covered);
        }
        if !sc.gaps(&ring) {
            return 0.0;
        }
        self.near(c, rho, zq, upto, sc);
        // (every primitive listed was recorded before the query)
        for i in 0..sc.near.len() {
            let p = &self.prims[sc.near[i] as usize];
            if p.z > zq {
                continue;
            }
            // wholly behind the front half, or beyond the ring
            let (hc, hr) = p.hull;
            let v = hc - c;
            if v.dot(ring.u) + hr < 0.0 || v.length() - hr > rho {
                continue;
            }
            if sc.disks.iter().all(|&(mc, h)| p.fast.distance(mc) > rr + h + 1e-9) {
                continue;
            }
            let n0 = sc.covered.len();
            covered_intervals(&p.path, &p.fast, rr, &ring, &mut sc.angles, &mut sc.covered);
            if sc.covered.len() > n0 && !sc.gaps(&ring) {
                return 0.0;
            }
        }
        // 3. measure base minus covered (the angle of a key t is 2 atan t)
        let mut total = 0.0;
        uncovered(&sc.base, &sc.covered, |a, b| total += 2.0 * (b.atan() - a.atan()));
        total.to_degrees()
    }

    fn in_stock(&self, q: DVec2) -> bool {
        let mut inside = false;
        for ring in &self.stock_rings {
            let n = ring.len();
            let mut j = n - 1;
            for i in 0..n {
                let (a, b) = (ring[i], ring[j]);
                if (a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) / (b.y - a.y) * (b.x - a.x) {
                    inside = !inside;
                }
                j = i;
            }
        }
        inside
    }

    /// Number of primitives recorded.
    pub fn len(&self) -> usize {
        self.prims.len()
    }

    /// True when nothing was cut yet.
    pub fn is_empty(&self) -> bool {
        self.prims.is_empty()
    }
}

/// Calls `f(a, b)` for each piece of the intervals `base` (sorted, disjoint) that none of
/// `covered` (sorted by start) covers, in order.
fn uncovered(base: &[(f64, f64)], covered: &[(f64, f64)], mut f: impl FnMut(f64, f64)) {
    for &(a, b) in base {
        let mut cur = a;
        for &(ca, cb) in covered {
            if cb <= cur {
                continue;
            }
            if ca >= b {
                break;
            }
            if ca > cur {
                f(cur, ca);
            }
            cur = cur.max(cb);
            if cur >= b {
                break;
            }
        }
        if cur < b {
            f(cur, b);
        }
    }
}

fn push_merge(v: &mut Vec<(f64, f64)>, iv: (f64, f64)) {
    if let Some(last) = v.last_mut()
        && (iv.0 - last.1).abs() < 1e-12
    {
        last.1 = iv.1;
        return;
    }
    v.push(iv);
}

/// The ring of one query: centre `c`, radius `rho`, and the unit direction of motion `u`.
///
/// A point of the ring is named by its angle θ from `u` (positive to the left), written as the
/// key `t = tan(θ/2)`, which grows with θ: the front half (|θ| ≤ 90°) is `t` in [-1, 1]. The
/// crossings, their order and the test of each piece at its middle are then plain algebra
/// (the unit vector of the crossing and the rational parametrisation of the circle); only the
/// uncovered pieces that are measured take an arctangent. A trigonometric version spent about
/// half of a simulation in `sin`, `cos`, `atan2` and `acos`.
struct Ring {
    c: DVec2,
    rho: f64,
    u: DVec2,
}

impl Ring {
    /// The point of the ring at key `t`.
    #[inline]
    fn point(&self, t: f64) -> DVec2 {
        let d = 1.0 / (1.0 + t * t);
        let (x, y) = ((1.0 - t * t) * d, 2.0 * t * d);
        self.c + self.rho * (self.u * x + self.u.perp() * y)
    }

    /// Pushes the keys of the front-half points whose direction from the centre makes an angle
    /// with the unit vector `w` of cosine `k` (on either side).
    #[inline]
    fn at_cosine(&self, w: DVec2, k: f64, out: &mut Vec<f64>) {
        if k.abs() > 1.0 {
            return;
        }
        let s = (1.0 - k * k).sqrt();
        // w in the ring's frame (x along u)
        let (wx, wy) = (w.dot(self.u), self.u.perp_dot(w));
        for (x, y) in [(wx * k - wy * s, wy * k + wx * s), (wx * k + wy * s, wy * k - wx * s)] {
            if x >= 0.0 {
                out.push((y / (1.0 + x)).clamp(-1.0, 1.0));
            }
        }
    }

    /// Keys where the ring meets the circle of centre `o`, radius `s` (front half only).
    #[inline]
    fn circle(&self, o: DVec2, s: f64, out: &mut Vec<f64>) {
        let v = o - self.c;
        let d = v.length();
        if d < 1e-12 || s <= 0.0 {
            return;
        }
        self.at_cosine(v / d, (self.rho * self.rho + d * d - s * s) / (2.0 * self.rho * d), out);
    }

    /// Keys where the ring meets the infinite line `n · x = h` (`n` unit).
    #[inline]
    fn line(&self, n: DVec2, h: f64, out: &mut Vec<f64>) {
        self.at_cosine(n, (h - n.dot(self.c)) / self.rho, out);
    }

    /// Keys where the ring meets segment `a`–`b`.
    fn segment_crossings(&self, a: DVec2, b: DVec2, out: &mut Vec<f64>) {
        let d = b - a;
        let l = d.length();
        if l < 1e-15 {
            return;
        }
        let n = DVec2::new(-d.y, d.x) / l;
        let start = out.len();
        self.line(n, n.dot(a), out);
        // keep only crossings within the segment
        let mut i = start;
        while i < out.len() {
            let t = (self.point(out[i]) - a).dot(d) / (l * l);
            if (-1e-12..=1.0 + 1e-12).contains(&t) {
                i += 1;
            } else {
                out.swap_remove(i);
            }
        }
    }
}

/// Appends to `covered` the front-half key intervals of the ring inside the sweep of `path`
/// with tool radius `r`.
fn covered_intervals(
    path: &Path,
    fast: &Fast,
    r: f64,
    ring: &Ring,
    scratch: &mut Vec<f64>,
    covered: &mut Vec<(f64, f64)>,
) {
    let (c, rho) = (ring.c, ring.rho);
    // quick reject: the ring cannot meet the sweep
    let d = fast.distance(c);
    if d > rho + r {
        return;
    }
    if d + rho <= r {
        covered.push((-1.0, 1.0));
        return;
    }
    scratch.clear();
    scratch.push(-1.0);
    scratch.push(1.0);
    match *path {
        Path::Line { a, b } => {
            let (a, b) = (a.truncate(), b.truncate());
            ring.circle(a, r, scratch);
            ring.circle(b, r, scratch);
            let dv = b - a;
            let l = dv.length();
            if l > 1e-12 {
                let n = DVec2::new(-dv.y, dv.x) / l;
                let h = n.dot(a);
                ring.line(n, h + r, scratch);
                ring.line(n, h - r, scratch);
            }
        }
        Path::Arc(g) => {
            let p0 = g.at(0.0).truncate();
            let p1 = g.at(1.0).truncate();
            ring.circle(p0, r, scratch);
            ring.circle(p1, r, scratch);
            ring.circle(g.center, g.radius + r, scratch);
            if g.radius > r {
                ring.circle(g.center, g.radius - r, scratch);
            }
            // where the ring crosses the radial lines through the arc ends
            for p in [p0, p1] {
                let dv = p - g.center;
                let l = dv.length();
                if l > 1e-12 {
                    let n = DVec2::new(-dv.y, dv.x) / l;
                    ring.line(n, n.dot(g.center), scratch);
                }
            }
        }
    }
    scratch.sort_by(f64::total_cmp);
    let start = covered.len();
    for i in 0..scratch.len().saturating_sub(1) {
        let (a0, a1) = (scratch[i], scratch[i + 1]);
        if a1 - a0 < 1e-13 {
            continue;
        }
        if fast.distance(ring.point(0.5 * (a0 + a1))) <= r {
            if covered.len() > start
                && let Some(last) = covered.last_mut()
                && (a0 - last.1).abs() < 1e-12
            {
                last.1 = a1;
                continue;
            }
            covered.push((a0, a1));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::DVec3;

    #[test]
    fn an_anchor_above_the_anchors_on_both_sides_tops_a_peak() {
        // the readings of a move round a corner (every fourth sample an anchor): a tent whose
        // top is the anchor at 8, as boss_with_clamp's program read it
        let pixel = [60.4, 60.4, 72.0, 73.3, 78.4, 79.7, 84.9, 87.4, 90.0, 87.4, 82.3, 78.4, 61.7, 59.1, 59.1];
        let anchors = [0, 4, 8, 12, 14];
        assert_eq!(peak_anchors(&pixel, &anchors), [false, false, true, false, false]);
        // a ramp has no peak, nor does a top only 3° above one side, nor the ends of a move
        let ramp = [10.0, 20.0, 30.0, 40.0, 50.0];
        assert_eq!(peak_anchors(&ramp, &[0, 2, 4]), [false, false, false]);
        let shoulder = [50.0, 52.0, 53.0, 52.0, 40.0];
        assert_eq!(peak_anchors(&shoulder, &[0, 2, 4]), [false, false, false]);
        let ends = [90.0, 50.0, 90.0];
        assert_eq!(peak_anchors(&ends, &[0, 1, 2]), [false, false, false]);
    }

    fn model(r: f64) -> ExactModel {
        let stock = vec![
            DVec2::new(-100.0, -100.0),
            DVec2::new(100.0, -100.0),
            DVec2::new(100.0, 100.0),
            DVec2::new(-100.0, 100.0),
        ];
        ExactModel::new(r, DVec2::new(-110.0, -110.0), DVec2::new(110.0, 110.0), vec![stock], 0.0, 0.05)
    }

    #[test]
    fn straight_cuts_read_the_textbook_angles() {
        // previous pass along y = 0 (moving +x), then a pass shifted by the stepover
        let r = 5.0;
        for (s, expect) in [(0.1, 36.87), (0.25, 60.0), (0.5, 90.0), (1.0, 180.0)] {
            let mut m = model(r);
            let ae = s * 2.0 * r;
            m.add(&Path::Line { a: DVec3::new(-50.0, 0.0, -1.0), b: DVec3::new(50.0, 0.0, -1.0) });
            // the new pass is ae above the previous one; uncut material lies beyond y = r
            let y = ae;
            let c = DVec2::new(0.0, y);
            let cur = Path::Line { a: DVec3::new(-20.0, y, -1.0), b: DVec3::new(0.0, y, -1.0) };
            let tea = m.engagement(c, -1.0, DVec2::X, r + 1e-4, 0.01, Some(&cur));
            let exact = 90.0 + (2.0 * s - 1.0f64).asin().to_degrees();
            assert!((exact - expect).abs() < 0.01);
            assert!((tea - exact).abs() < 0.6, "stepover {s}: {tea} vs {exact}");
        }
    }

    /// Queries answered later, all at once and in parallel, read what the model held when they
    /// were asked: the same bits as asking at once.
    #[test]
    fn deferred_queries_answer_as_at_once() {
        let r = 3.0;
        let mut m = model(r);
        let (mut now, mut queries) = (Vec::new(), Vec::new());
        for k in 0..12 {
            let y = 1.5 * k as f64;
            let (a, b) = (DVec3::new(-40.0, y, -1.0), DVec3::new(40.0, y, -1.0));
            for i in 1..=80 {
                let t = i as f64 / 80.0;
                let c = (a + (b - a) * t).truncate();
                let cur = Path::Line { a, b: a + (b - a) * t };
                now.push(m.engagement(c, -1.0, DVec2::X, r + 1e-4, 0.01, Some(&cur)));
                queries.push(Query {
                    c,
                    z: -1.0,
                    dir: DVec2::X,
                    rho: r + 1e-4,
                    eps: 0.01,
                    current: Some(cur),
                    upto: m.recorded(),
                });
            }
            m.add(&Path::Line { a, b });
        }
        let later = m.engagements(&queries);
        assert_eq!(
            now.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            later.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
        // the first pass is a full slot, the later ones read the stepover's angle
        assert!(
            (now[40] - 180.0).abs() < 0.01
                && (now[80 * 5 + 40] - 90.0 - (0.5f64 - 1.0).asin().to_degrees()).abs() < 0.6
        );
    }

    #[test]
    fn cuts_above_the_level_do_not_count() {
        let mut m = model(3.0);
        m.add(&Path::Line { a: DVec3::new(-50.0, 0.0, -1.0), b: DVec3::new(50.0, 0.0, -1.0) });
        // a slot at z = -2 under the pass at -1 is full width
        let cur = Path::Line { a: DVec3::new(-10.0, 0.0, -2.0), b: DVec3::new(0.0, 0.0, -2.0) };
        let tea = m.engagement(DVec2::ZERO, -2.0, DVec2::X, 3.0001, 0.01, Some(&cur));
        assert!((tea - 180.0).abs() < 0.01, "{tea}");
        let tea = m.engagement(DVec2::ZERO, -1.0, DVec2::X, 3.0001, 0.01, Some(&cur));
        assert!(tea < 1.0, "{tea}");
    }

    /// A model cut by random lines and arcs, and queries among them: seeded, so the same each
    /// run.
    fn random_cuts(seed: u64) -> (ExactModel, Vec<Query>, Vec<Path>, Vec<usize>) {
        let r = 3.0;
        let mut m = model(r);
        let mut x = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let mut next = move || {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((x >> 11) as f64) / ((1u64 << 53) as f64)
        };
        // the moves, and per query the number of them cut before it
        let (mut queries, mut moves, mut before) = (Vec::new(), Vec::new(), Vec::new());
        let mut at = DVec3::new(0.0, 0.0, -1.0);
        for _ in 0..100 {
            let to = DVec3::new(at.x + 8.0 * (next() - 0.5), at.y + 8.0 * (next() - 0.5), -1.0);
            let to = DVec3::new(to.x.clamp(-30.0, 30.0), to.y.clamp(-30.0, 30.0), -1.0);
            let path = if next() < 0.4 && (to - at).length() > 0.5 {
                // an arc through the two points, its centre off the chord
                let mid = 0.5 * (at + to).truncate();
                let n = (to - at).truncate().perp().normalize();
                let center = mid + n * (2.0 * next() - 1.0) * 4.0;
                Path::Arc(crate::toolpath::ArcGeom::new(at, to, center, next() < 0.5))
            } else {
                Path::Line { a: at, b: to }
            };
            for k in 1..=4 {
                let t = k as f64 / 4.0;
                let dir = path.dir(t);
                if dir.length_squared() < 1e-12 {
                    continue;
                }
                queries.push(Query {
                    c: path.at(t).truncate(),
                    z: -1.0,
                    dir,
                    rho: r + 1e-4,
                    eps: 0.01,
                    current: Some(path.sub(0.0, t)),
                    upto: m.recorded(),
                });
                before.push(moves.len());
            }
            m.add(&path);
            moves.push(path);
            at = to;
        }
        (m, queries, moves, before)
    }

    /// The measure (newest primitives first, the others tested against the arcs still
    /// uncovered) agrees with a plain count of the ring's points outside every sweep.
    #[test]
    fn the_measure_agrees_with_counting_ring_points() {
        for seed in 0..2 {
            let (m, queries, moves, before) = random_cuts(seed);
            let got = m.engagements(&queries);
            let mut seen = 0usize;
            for ((q, tea), &k) in queries.iter().zip(&got).zip(&before) {
                let n = 3600;
                let u = q.dir.normalize();
                let cut: Vec<&Path> = moves[..k].iter().chain(q.current.as_ref()).collect();
                let free = (0..n)
                    .filter(|&k| {
                        let th = (k as f64 + 0.5) / n as f64 * std::f64::consts::PI - std::f64::consts::FRAC_PI_2;
                        let p = q.c + q.rho * (u * th.cos() + u.perp() * th.sin());
                        cut.iter().all(|path| path.distance(p) > m.r)
                    })
                    .count();
                let count = 180.0 * free as f64 / n as f64;
                assert!((tea - count).abs() < 0.1, "seed {seed}: measured {tea}, counted {count}");
                seen += (count > 1.0) as usize;
            }
            // (the cuts leave material round many of the queries: the test reads real arcs)
            assert!(seen > queries.len() / 10, "{seen} of {}", queries.len());
        }
    }

    /// The primitives kept from query to query ([`ExactModel::near`]) answer as the cells of
    /// each query's own ring do, to the bit, against a fresh start for every query: queries
    /// along random cuts (each close to the one before, the cuts recorded between them), the
    /// same queries shuffled (far apart, fewer primitives than the one before), queries
    /// alternating between two levels at the same points, and queries jittering about a point
    /// with cuts anywhere around it recorded between them. (Reading a list made for the lower
    /// level at the upper one, or looking the new primitives up in the ring's own cells
    /// instead of the kept disk's, fails it.)
    #[test]
    fn kept_primitives_answer_as_the_rings_own_cells() {
        for seed in [3, 11, 29] {
            let (m, queries, _, _) = random_cuts(seed);
            let fresh: Vec<u64> = queries.iter().map(|q| m.measure(q, &mut Scratch::default()).to_bits()).collect();
            let mut sc = Scratch::default();
            let kept: Vec<u64> = queries.iter().map(|q| m.measure(q, &mut sc).to_bits()).collect();
            assert_eq!(kept, fresh, "seed {seed}, in order");
            let order: Vec<usize> = (0..queries.len()).map(|i| (i * 37 + seed as usize) % queries.len()).collect();
            let shuffled: Vec<u64> = order.iter().map(|&i| m.measure(&queries[i], &mut sc).to_bits()).collect();
            assert_eq!(shuffled, order.iter().map(|&i| fresh[i]).collect::<Vec<_>>(), "seed {seed}, shuffled");
            assert!(
                fresh.iter().filter(|&&b| f64::from_bits(b) > 1.0).count() > queries.len() / 4,
                "seed {seed}: few engaged"
            );
        }
        // two levels: cuts at the upper one do not count for the lower one, and the queries
        // alternate between the levels at the same points (a list made for the lower level
        // must not be read for the upper one)
        let r = 3.0;
        let mut m = model(r);
        let mut queries = Vec::new();
        for k in 0..10 {
            let y = 1.5 * k as f64;
            for z in [-2.0, -1.0] {
                let (a, b) = (DVec3::new(-40.0, y, z), DVec3::new(30.0, y, z));
                for i in 1..=160 {
                    let t = i as f64 / 160.0;
                    let cur = Path::Line { a, b: a + (b - a) * t };
                    let c = (a + (b - a) * t).truncate();
                    let dir = (b - a).truncate();
                    queries.push(Query { c, z, dir, rho: r + 1e-4, eps: 0.01, current: Some(cur), upto: m.recorded() });
                }
                // (the lower level cut on the left only: on the right the upper level's own
                // cuts clear its rings)
                m.add(&Path::Line { a, b: if z < -1.5 { DVec3::new(-5.0, y, z) } else { b } });
            }
        }
        let mut order: Vec<usize> = Vec::new();
        for i in 0..queries.len() / 320 {
            for j in 0..160 {
                order.push(320 * i + 160 + j);
                order.push(320 * i + j);
            }
        }
        let fresh: Vec<u64> =
            order.iter().map(|&i| m.measure(&queries[i], &mut Scratch::default()).to_bits()).collect();
        let mut sc = Scratch::default();
        let kept: Vec<u64> = order.iter().map(|&i| m.measure(&queries[i], &mut sc).to_bits()).collect();
        assert_eq!(kept, fresh, "two levels");
        let partial = fresh.iter().filter(|&&b| (1.0..179.0).contains(&f64::from_bits(b))).count();
        assert!(partial > 100, "two levels: {partial} partial engagements");
        // queries jittering about one point, short cuts anywhere around it recorded between
        // them: a primitive recorded after a list was made must be found wherever the next
        // ring inside the list's disk lies, not only near the ring that added it
        for seed in [5u64, 17, 41] {
            let mut m = model(r);
            let mut x = seed;
            let mut next = move || {
                x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                ((x >> 11) as f64) / ((1u64 << 53) as f64)
            };
            let o = DVec2::new(0.3, 0.7);
            let mut queries = Vec::new();
            for _ in 0..120 {
                let a = o + DVec2::new(40.0 * next() - 20.0, 40.0 * next() - 20.0);
                let b = a + DVec2::new(2.0 * next() - 1.0, 2.0 * next() - 1.0);
                m.add(&Path::Line { a: a.extend(-1.0), b: b.extend(-1.0) });
                let c = o + DVec2::new(2.8 * next() - 1.4, 2.8 * next() - 1.4) * std::f64::consts::FRAC_1_SQRT_2;
                let dir = DVec2::from_angle(std::f64::consts::TAU * next());
                queries.push(Query { c, z: -1.0, dir, rho: r + 1e-4, eps: 0.01, current: None, upto: m.recorded() });
            }
            let fresh: Vec<u64> = queries.iter().map(|q| m.measure(q, &mut Scratch::default()).to_bits()).collect();
            let mut sc = Scratch::default();
            let kept: Vec<u64> = queries.iter().map(|q| m.measure(q, &mut sc).to_bits()).collect();
            assert_eq!(kept, fresh, "seed {seed}, jittering");
            let partial = fresh.iter().filter(|&&b| (1.0..179.0).contains(&f64::from_bits(b))).count();
            assert!(partial > 40, "seed {seed}: {partial} partial engagements");
        }
    }

    /// Guided by pixel readings that agree with the geometry, the answers at the anchors are
    /// the exact ones and those between them stay close; with a stride of 1 they are all exact.
    #[test]
    fn guided_answers_are_exact_at_anchors() {
        let (m, queries, _, _) = random_cuts(7);
        let exact = m.engagements(&queries);
        let pixel: Vec<f32> = exact.iter().map(|&e| e as f32).collect();
        let starts: Vec<usize> = (0..queries.len()).step_by(4).collect();
        let all = m.engagements_guided(&queries, &pixel, &starts, 1);
        assert_eq!(all, exact);
        let guided = m.engagements_guided(&queries, &pixel, &starts, 2);
        for (k, (g, e)) in guided.iter().zip(&exact).enumerate() {
            if k % 4 == 1 {
                // (between anchors 0 and 2 of a move: exact, or on the line when the pixels
                // show the engagement straight there)
                let line = 0.5 * (exact[k - 1] + exact[k + 1]);
                assert!(g == e || ((g - line).abs() < 1e-9 && (e - line).abs() <= GUIDE_SMOOTH_DEG + 1e-6));
            } else {
                assert_eq!(g, e, "query {k} is an anchor");
            }
        }
        // pixels that disagree with the geometry everywhere: every answer is measured
        let wrong: Vec<f32> = exact.iter().map(|&e| e as f32 + 20.0).collect();
        assert_eq!(m.engagements_guided(&queries, &wrong, &starts, 2), exact);
    }
}
