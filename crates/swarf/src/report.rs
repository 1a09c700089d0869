//! The report: the figures that tell a machinist whether to trust a program.

use crate::sim::{Replay, Rest, SampleKind};
use crate::toolpath::{Motion, Toolpath};

/// Engagement statistics over samples with engagement above zero (the verifier's convention),
/// degrees.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Stats {
    /// Largest.
    pub max: f64,
    /// 99th percentile.
    pub p99: f64,
    /// 95th percentile.
    pub p95: f64,
    /// Median.
    pub p50: f64,
    /// Mean.
    pub mean: f64,
    /// Number of samples.
    pub n: usize,
}

impl Stats {
    /// Statistics of the values above zero.
    pub fn of(mut v: Vec<f64>) -> Stats {
        v.retain(|x| *x > 0.0);
        if v.is_empty() {
            return Stats::default();
        }
        v.sort_by(f64::total_cmp);
        let q = |p: f64| {
            // linear interpolation between closest ranks (numpy's default)
            let pos = p * (v.len() - 1) as f64;
            let lo = pos.floor() as usize;
            let hi = pos.ceil() as usize;
            v[lo] + (v[hi] - v[lo]) * (pos - lo as f64)
        };
        Stats {
            max: *v.last().unwrap_or(&0.0),
            p99: q(0.99),
            p95: q(0.95),
            p50: q(0.5),
            mean: v.iter().sum::<f64>() / v.len() as f64,
            n: v.len(),
        }
    }
}

/// How far above the reference engagement a program's engagement outside the entry bores may
/// go, degrees: the bound swarf's adaptive programs are held to and the report measures against
/// ([`Report::above_ref_plus_20`]).
pub const BOUND_OVER_REF_DEG: f64 = 20.0;

/// Time and length spent above a threshold.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Above {
    /// The threshold, degrees.
    pub threshold_deg: f64,
    /// Cutting length above it outside entry bores, mm.
    pub length_mm: f64,
    /// Share of the cutting time.
    pub time_fraction: f64,
}

/// Move counts.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct Counts {
    /// All moves.
    pub total: usize,
    /// G0.
    pub rapids: usize,
    /// G1.
    pub lines: usize,
    /// G2/G3.
    pub arcs: usize,
}

/// The report of one run.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Report {
    /// swarf version.
    pub swarf_version: String,
    /// Input file or example name.
    pub input: String,
    /// Strategy.
    pub strategy: String,
    /// Post.
    pub post: String,
    /// Tool diameter, mm.
    pub tool_diameter_mm: f64,
    /// Radial stepover as a fraction of the diameter.
    pub stepover: f64,
    /// Reference engagement of a straight cut at that stepover, degrees.
    pub engagement_ref_deg: f64,
    /// z of each level.
    pub levels: Vec<f64>,
    /// Time to compute the toolpath (s), simulation excluded.
    pub compute_s: f64,
    /// Time to simulate it for this report (s): where the simulation replays the program while
    /// it is planned (the raster proof of `rough`), the time it took after the planning ended.
    pub simulate_s: f64,
    /// Time from the start of the planning to the report: planning, posting and simulation (s).
    pub total_s: f64,
    /// Whether the program was simulated. Without a simulation (`--no-simulate`) the
    /// simulation's figures (engagement, air cutting, gouges, rapid collisions, rest) were not
    /// measured and read 0, and `plunges` counts the plunges the program marks.
    pub simulated: bool,
    /// Feed-move length, mm.
    pub cut_length_mm: f64,
    /// Rapid length, mm.
    pub rapid_length_mm: f64,
    /// Machining time estimate: feed lengths over feeds plus rapids over the rapid rate, min.
    pub time_min: f64,
    /// Exact engagement on lateral cutting outside entry bores (the helix or ramp and the first
    /// turn at its bottom, where slotting cannot be avoided).
    pub engagement_deg: Stats,
    /// Exact engagement on all lateral cutting, entry bores included.
    pub engagement_lateral_deg: Stats,
    /// Engagement by circumference pixels (paper 1 eq. 4) on the same samples as
    /// `engagement_deg`.
    pub engagement_pixel_deg: Stats,
    /// Cutting above the reference + 20°, outside entry bores.
    pub above_ref_plus_20: Above,
    /// Share of cutting length with no engagement (air cutting and links).
    pub air_cut_fraction: f64,
    /// Plunges into material.
    pub plunges: usize,
    /// Helix and ramp entries.
    pub entries: usize,
    /// Moves that rise.
    pub retracts: usize,
    /// Moves that gouge the part, a fixture or the floor.
    pub gouges: usize,
    /// Deepest gouge, mm.
    pub gouge_max_mm: f64,
    /// Where the first gouges are (move index in the toolpath, place, depth); at most 20.
    pub gouge_at: Vec<crate::sim::Event>,
    /// Where the first plunges are; at most 20.
    pub plunge_at: Vec<crate::sim::Event>,
    /// Why each of `plunge_at` is a plunge, as the program's note before it says (`no room
    /// for a helix or a ramp`, …); empty where the program gives no reason.
    pub plunge_why: Vec<String>,
    /// Where the first rapid collisions are; at most 20.
    pub rapid_collision_at: Vec<crate::sim::Event>,
    /// Rapids through uncut material.
    pub rapid_collisions: usize,
    /// Reachable material left, mm².
    pub rest_area_mm2: f64,
    /// Rest over reachable area.
    pub rest_fraction: f64,
    /// Of the rest, the terraces z-level roughing leaves by design (3D jobs): area, mm², where
    /// the stock stands no higher than the lowest level at or above what the tool reaches.
    pub rest_terrace_area_mm2: f64,
    /// Their volume, mm³.
    pub rest_terrace_volume_mm3: f64,
    /// The rest beyond the terraces (material the tool could have cut at a level and left), as
    /// a fraction of the reachable area; equal to `rest_fraction` in 2.5D.
    pub rest_beyond_terraces_fraction: f64,
    /// Its largest thickness, mm.
    pub rest_beyond_terraces_max_mm: f64,
    /// Reachable material left, mm³.
    pub rest_volume_mm3: f64,
    /// Thickest rest material, mm (2.5D: its height above the floor; 3D: above the lowest the
    /// tool reaches there).
    pub rest_max_thickness_mm: f64,
    /// Area the tool can reach, mm².
    pub reachable_area_mm2: f64,
    /// Volume removed, mm³.
    pub removed_volume_mm3: f64,
    /// The removal rate of a straight cut at the reference engagement, a level's depth and the
    /// programmed feed: stepover × depth of cut × feed, mm³/min.
    pub removal_rate_ref_mm3_min: f64,
    /// The program's efficiency: the removed volume over what the machining time would remove at
    /// [`Report::removal_rate_ref_mm3_min`] (1 = every minute cutting at the reference with no
    /// links, entries or air; the engagement-driven feed can take it above 1). 0 when not
    /// simulated.
    pub efficiency: f64,
    /// Moves by type.
    pub moves: Counts,
    /// Lines of G-code.
    pub gcode_lines: usize,
    /// Simulation cell size, mm.
    pub sim_res_mm: f64,
}

/// Fills the figures of a report that the program gives by itself: lengths, time, entries,
/// retracts, the moves by kind, and plunges as the program marks them (the simulation replaces
/// those by the plunges into material it finds, see [`fill`]).
pub fn fill_program(rep: &mut Report, tp: &Toolpath, rapid_rate: f64) {
    let t = tp.totals(rapid_rate);
    rep.cut_length_mm = t.cut_length_mm;
    rep.rapid_length_mm = t.rapid_length_mm;
    rep.time_min = t.time_min;
    rep.entries = t.entries;
    rep.retracts = t.retracts;
    rep.plunges = t.plunges;
    let mut c = Counts { total: tp.moves.len(), ..Default::default() };
    for m in &tp.moves {
        if m.is_rapid() {
            c.rapids += 1;
        } else if matches!(m.motion, Motion::Arc { .. }) {
            c.arcs += 1;
        } else {
            c.lines += 1;
        }
    }
    rep.moves = c;
}

/// The reason the program's notes give for a plunge at move `mi`: the last `plunge: …` note
/// at most two moves before it (the note precedes the travel over the place, or the plunge).
fn plunge_reason(tp: &Toolpath, mi: usize) -> String {
    tp.notes
        .iter()
        .rev()
        .filter(|n| n.at <= mi && n.at + 2 >= mi)
        .find_map(|n| n.text.strip_prefix("plunge: "))
        .unwrap_or("")
        .to_string()
}

/// Fills every figure of a report: the program's ([`fill_program`]) and the simulation's.
pub fn fill(rep: &mut Report, tp: &Toolpath, replay: &Replay, rest: &Rest, rapid_rate: f64) {
    fill_program(rep, tp, rapid_rate);
    rep.simulated = true;
    let lateral: Vec<_> = replay.samples.iter().filter(|s| s.kind == SampleKind::Lateral).collect();
    rep.engagement_lateral_deg = Stats::of(lateral.iter().map(|s| s.tea as f64).collect());
    rep.engagement_deg = Stats::of(lateral.iter().filter(|s| !s.bore).map(|s| s.tea as f64).collect());
    rep.engagement_pixel_deg = Stats::of(lateral.iter().filter(|s| !s.bore).map(|s| s.tea_pixel as f64).collect());
    let thr = rep.engagement_ref_deg + BOUND_OVER_REF_DEG;
    let total_time: f64 = replay.samples.iter().map(|s| s.len as f64 / s.feed.max(1e-9) as f64).sum();
    let mut above = Above { threshold_deg: thr, ..Default::default() };
    let mut air = 0.0;
    let mut cut = 0.0;
    for s in &replay.samples {
        cut += s.len as f64;
        if s.tea <= 0.0 {
            air += s.len as f64;
        }
        if !s.bore && s.tea as f64 > thr {
            above.length_mm += s.len as f64;
            above.time_fraction += s.len as f64 / s.feed.max(1e-9) as f64;
        }
    }
    above.time_fraction = if total_time > 0.0 { above.time_fraction / total_time } else { 0.0 };
    rep.above_ref_plus_20 = above;
    rep.air_cut_fraction = if cut > 0.0 { air / cut } else { 0.0 };
    rep.plunges = replay.plunges.len();
    rep.gouges = replay.gouges.len();
    rep.gouge_max_mm = replay.gouges.iter().map(|g| g.depth).fold(0.0, f64::max);
    rep.gouge_at = replay.gouges.iter().take(20).cloned().collect();
    rep.plunge_at = replay.plunges.iter().take(20).cloned().collect();
    rep.plunge_why = rep.plunge_at.iter().map(|e| plunge_reason(tp, e.move_index)).collect();
    rep.rapid_collision_at = replay.rapid_collisions.iter().take(20).cloned().collect();
    rep.rapid_collisions = replay.rapid_collisions.len();
    rep.rest_area_mm2 = rest.area_mm2;
    rep.rest_volume_mm3 = rest.volume_mm3;
    rep.rest_max_thickness_mm = rest.max_thickness_mm;
    rep.reachable_area_mm2 = rest.reachable_mm2;
    rep.rest_fraction = if rest.reachable_mm2 > 0.0 { rest.area_mm2 / rest.reachable_mm2 } else { 0.0 };
    rep.rest_terrace_area_mm2 = rest.terrace_mm2;
    rep.rest_terrace_volume_mm3 = rest.terrace_volume_mm3;
    let beyond = rest.area_mm2 - rest.terrace_mm2;
    rep.rest_beyond_terraces_fraction = if rest.reachable_mm2 > 0.0 { beyond / rest.reachable_mm2 } else { 0.0 };
    // (a 2.5D model has no terraces and leaves the figure at 0: all its rest is beyond)
    rep.rest_beyond_terraces_max_mm =
        if rest.terrace_mm2 > 0.0 { rest.beyond_max_thickness_mm } else { rest.max_thickness_mm };
    rep.removed_volume_mm3 = replay.removed_volume;
}

/// Fills the reference removal rate `rate` (mm³/min) and the efficiency it gives the simulated
/// removed volume and the machining time.
pub fn fill_efficiency(rep: &mut Report, rate: f64) {
    rep.removal_rate_ref_mm3_min = rate;
    let ideal = rep.time_min * rate;
    rep.efficiency = if ideal > 0.0 { rep.removed_volume_mm3 / ideal } else { 0.0 };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_interpolate() {
        let s = Stats::of((0..=100).map(f64::from).collect());
        assert_eq!(s.max, 100.0);
        assert_eq!(s.n, 100);
        assert!((s.p50 - 50.5).abs() < 1e-9);
        assert!((s.p99 - 99.01).abs() < 1e-9);
        assert_eq!(Stats::of(vec![0.0, 0.0]).n, 0);
    }

    #[test]
    fn a_plunge_gets_the_reason_noted_before_it() {
        use crate::geom::DVec3;
        use crate::toolpath::MoveKind;
        let mut tp = Toolpath::new(crate::model::Tool::flat(6.0), DVec3::new(0.0, 0.0, 5.0), 5.0);
        tp.rapid(DVec3::new(10.0, 0.0, 5.0));
        tp.note("plunge: no room for a helix or a ramp");
        tp.rapid(DVec3::new(10.0, 0.0, 1.0));
        tp.line(MoveKind::Plunge, DVec3::new(10.0, 0.0, -3.0), 500.0);
        tp.line(MoveKind::Cut, DVec3::new(20.0, 0.0, -3.0), 1000.0);
        tp.line(MoveKind::Plunge, DVec3::new(20.0, 0.0, -6.0), 500.0);
        assert_eq!(plunge_reason(&tp, 2), "no room for a helix or a ramp");
        // a note further back belongs to another plunge
        assert_eq!(plunge_reason(&tp, 4), "");
    }
}
