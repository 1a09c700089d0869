//! The oscillator spiral (paper 4) on the example cases it is meant for: clean by swarf's own
//! simulator (no gouge, no rapid collision, no plunge, rest under 0.5 % of the reachable area),
//! one entry and no retract before the end, tangent-continuous wherever it cuts (no turn above
//! 1° in the planned path, 5° once written to 1 µm), all arcs; and within the engagement bound on the two cases whose
//! shape has no ridge. A pocket with an island is refused with a message.

use std::path::Path;
use swarf::pipeline::{RoughOptions, rough};
use swarf::sim::SimOptions;
use swarf::strategy::{Params, StrategyKind};
use swarf::toolpath::{Motion, MoveKind};

fn case(name: &str) -> swarf::model::Job {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cases").join(name);
    swarf::io::load_job(&path, &Default::default()).unwrap_or_else(|e| panic!("{e}"))
}

// (the negated comparisons make NaN fail)
#[allow(clippy::neg_cmp_op_on_partial_ord)]
#[test]
fn spirals_are_clean_smooth_and_in_one_piece() {
    let mut bad = Vec::new();
    for (name, bounded) in [("round_pocket.json", true), ("square_pocket.json", true), ("l_pocket.json", false)] {
        let job = case(name);
        for climb in [true, false] {
            let opts = RoughOptions {
                input_name: name.into(),
                params: Params { strategy: StrategyKind::Spiral, climb, ..Params::default() },
                sim: SimOptions { res: Some(0.1), ..Default::default() },
                ..Default::default()
            };
            let out = rough(&job, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
            let r = &out.report;
            let what = format!("{name} ({})", if climb { "climb" } else { "conventional" });
            if r.gouges != 0 || r.rapid_collisions != 0 || r.plunges != 0 {
                bad.push(format!(
                    "{what}: {} gouges, {} rapid collisions, {} plunges",
                    r.gouges, r.rapid_collisions, r.plunges
                ));
            }
            if !(r.rest_fraction < 0.005) {
                bad.push(format!("{what}: rest {:.4} of the reachable area", r.rest_fraction));
            }
            if r.entries != 1 {
                bad.push(format!("{what}: {} entries", r.entries));
            }
            // no move rises before the final retract
            let tp = &out.toolpath;
            let n = tp.moves.len();
            let rises = tp.segments().take(n - 1).filter(|(from, m)| m.to.z > from.z + 1e-9).count();
            if rises != 0 {
                bad.push(format!("{what}: {rises} rises before the end"));
            }
            // tangent-continuous as planned; the written program rounds coordinates to 1 µm,
            // which tilts the shortest arcs (where the last turn rounds a corner of the region
            // at a radius of hundredths of a millimetre) by a few degrees
            let planned = swarf::pipeline::plan(&job, &opts).unwrap_or_else(|e| panic!("{e}")).expect("a program");
            let turns = planned.toolpath.cutting_turns();
            assert!(turns.len() > 20, "{what}: {} junctions", turns.len());
            let worst = turns.iter().map(|t| t.1).fold(0.0, f64::max);
            if worst > 1.0 {
                bad.push(format!("{what}: a turn of {worst:.2}° between planned cutting moves"));
            }
            let written = tp.cutting_turns().iter().map(|t| t.1).fold(0.0, f64::max);
            if written > 5.0 {
                bad.push(format!("{what}: a turn of {written:.2}° between written cutting moves"));
            }
            let lines = tp.moves.iter().filter(|m| m.kind == MoveKind::Cut && m.motion == Motion::Line).count();
            if lines > 2 {
                bad.push(format!("{what}: {lines} straight cutting moves"));
            }
            let bound = job.width.engagement_deg() + 10.0;
            if bounded && !(r.engagement_deg.p99 <= bound) {
                bad.push(format!("{what}: p99 engagement {:.1}° above {bound}°", r.engagement_deg.p99));
            }
        }
    }
    assert!(bad.is_empty(), "{bad:#?}");
}

#[test]
fn a_pocket_with_an_island_is_refused_with_a_reason() {
    let job = case("pocket_islands.json");
    let opts = RoughOptions {
        params: Params { strategy: StrategyKind::Spiral, ..Params::default() },
        simulate: false,
        ..Default::default()
    };
    let e = rough(&job, &opts, &mut |_, _| {}).expect_err("an island");
    let msg = e.to_string();
    assert!(msg.contains("island") && msg.contains("--strategy"), "{msg}");
}
