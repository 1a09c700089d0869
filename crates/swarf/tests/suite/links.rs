//! How the adaptive program gets from one pass to the next, on the pocket with two islands:
//! it starts over its first entry, lifts no higher than the material needs (minimum retract),
//! descends into cleared space at the cutting feed, and mostly stays down (links round the
//! material through cleared space instead of lifts).

use std::path::Path;
use swarf::job::rough::{RoughOptions, rough};
use swarf::toolpath::MoveKind;

#[test]
fn adaptive_links_stay_low_and_mostly_down() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cases/pocket_islands.json");
    let job = swarf::io::load_job(&path, &Default::default()).unwrap_or_else(|e| panic!("{e}"));
    let opts = RoughOptions { simulate: false, input_name: "pocket_islands.json".into(), ..Default::default() };
    let tp = rough(&job, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{e}")).toolpath;
    let moves = &tp.moves;
    assert!(moves.len() > 1000, "{} moves", moves.len());

    // the program starts over its first entry: the first move goes straight down
    assert!(
        (moves[0].to.truncate() - tp.start.truncate()).length() < 1e-9,
        "first move {:?} from {:?}",
        moves[0].to,
        tp.start
    );

    // between the first move and the final retract no rapid rises above the approach height
    // over the top of the job (the stock's top is the highest material: the minimum retract)
    let approach = opts.link.approach;
    let cap = job.top() + approach + 1e-9;
    for (k, m) in moves.iter().enumerate().take(moves.len() - 1).skip(1) {
        assert!(!m.is_rapid() || m.to.z <= cap, "move {k}: rapid to z {} above {cap}", m.to.z);
    }

    // descents into cleared space at the cutting feed
    let descents: Vec<_> = moves.iter().filter(|m| m.kind == MoveKind::Descend).collect();
    assert!(!descents.is_empty());
    for m in &descents {
        assert_eq!(m.feed, job.cutting.feed, "descent at {:?}", m.to);
    }

    // lifts off the floor (a rapid up from the level): the links go round the material instead
    // (33 lifts before keep-down routing and minimum retracts, 5 with them)
    let z = job.levels()[0];
    let mut lifts = 0;
    let mut at = tp.start;
    for m in moves {
        if m.is_rapid() && (at.z - z).abs() < 1e-9 && m.to.z > z + 1e-9 {
            lifts += 1;
        }
        at = m.to;
    }
    assert!(lifts <= 15, "{lifts} lifts off the floor");
}

/// The engagement-driven feed (paper 1 §5) is on by default: the adaptive program's cuts run
/// above the programmed feed where the tool cuts little, never above the machine's highest
/// feed (the rapid rate unless the job says), and at most the feed times the boost; with the
/// boost at 1 no cut runs above the feed.
#[test]
fn the_raised_feed_stays_under_the_machines_highest() {
    let case = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cases/l_pocket.json");
    let job = swarf::io::load_job(&case, &Default::default()).unwrap_or_else(|e| panic!("{e}"));
    let feeds = |job: &swarf::model::Job, boost: f64| {
        let mut opts = RoughOptions { simulate: false, ..RoughOptions::DEFAULT };
        opts.link.feed_boost = boost;
        let out = rough(job, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{e}"));
        out.toolpath.moves.iter().filter(|m| m.kind == MoveKind::Cut).map(|m| m.feed).collect::<Vec<f64>>()
    };
    let f = job.cutting.feed;
    let by_default = feeds(&job, RoughOptions::DEFAULT.link.feed_boost);
    let top = by_default.iter().copied().fold(0.0, f64::max);
    assert!(top >= 1.5 * f && top <= job.cutting.rapid_rate.min(3.0 * f) + 1e-9, "highest feed {top}");
    let capped = swarf::model::Job {
        cutting: swarf::model::Cutting { max_feed: Some(1.4 * f), ..job.cutting.clone() },
        ..job.clone()
    };
    let top = feeds(&capped, 3.0).iter().copied().fold(0.0, f64::max);
    assert!(top > f && top <= 1.4 * f + 1e-9, "highest feed {top} with the machine's at {}", 1.4 * f);
    assert!(feeds(&job, 1.0).iter().all(|&x| x <= f + 1e-9), "no boost, no cut above the feed");
}

/// The report's efficiency: the removed volume over what the machining time removes at the
/// reference engagement (a straight cut at the stepover), a level's depth and the programmed
/// feed. The engagement-driven feed shortens the same program's time, so it raises the
/// efficiency; at the programmed feed the links, entries and the passes' lower engagement
/// keep it under 1.
#[test]
fn efficiency_is_the_removed_volume_over_the_reference_rate() {
    let case = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cases/square_pocket.json");
    let job = swarf::io::load_job(&case, &Default::default()).unwrap_or_else(|e| panic!("{e}"));
    let report = |boost: f64| {
        let mut opts = RoughOptions::DEFAULT;
        opts.link.feed_boost = boost;
        rough(&job, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{e}")).report
    };
    let (plain, boosted) = (report(1.0), report(RoughOptions::DEFAULT.link.feed_boost));
    let levels = job.levels();
    let depth = (job.stock_top - levels.last().copied().unwrap_or(job.floor)) / levels.len() as f64;
    let rate = job.stepover_mm() * depth * job.cutting.feed;
    for r in [&plain, &boosted] {
        assert!(
            (r.removal_rate_ref_mm3_min - rate).abs() < 1e-9 * rate,
            "{} against {rate}",
            r.removal_rate_ref_mm3_min
        );
        let want = r.removed_volume_mm3 / (r.time_min * rate);
        assert!((r.efficiency - want).abs() < 1e-12, "{} against {want}", r.efficiency);
    }
    assert!(plain.efficiency > 0.3 && plain.efficiency < 1.0, "at the programmed feed: {}", plain.efficiency);
    assert!(
        boosted.efficiency > 1.05 * plain.efficiency,
        "{} with the feed raised, {} without",
        boosted.efficiency,
        plain.efficiency
    );
}
