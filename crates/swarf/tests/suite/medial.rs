//! The medial-axis strategy (paper 2) on the seven example cases: clean by swarf's own
//! simulator (no gouge, no rapid collision, no plunge, rest under 0.5 % of the reachable area),
//! tangent-continuous wherever it cuts (no turn above 1° between consecutive cutting moves of
//! the written program), and made mostly of arcs.

use std::path::Path;
use swarf::job::rough::{RoughOptions, rough};
use swarf::plan::LinkOptions;
use swarf::sim::SimOptions;
use swarf::strategy::{MedialOptions, Strategy};
use swarf::toolpath::Motion;

use crate::common;

// (the negated comparison makes NaN fail)
#[allow(clippy::neg_cmp_op_on_partial_ord)]
#[test]
fn medial_programs_are_clean_and_tangent_continuous() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cases");
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    names.sort();
    assert_eq!(names.len(), 7);
    let mut bad = Vec::new();
    for path in &names {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("?").to_string();
        let job = swarf::io::load_job(path, &Default::default()).unwrap_or_else(|e| panic!("{e}"));
        // conventional milling too on the smaller cases (the simulation of the largest takes
        // most of the time)
        let both = ["l_pocket.json", "narrow_slot.json", "round_pocket.json"].contains(&name.as_str());
        for climb in [true, false] {
            if !climb && !both {
                continue;
            }
            let opts = RoughOptions {
                input_name: name.clone(),
                strategy: Strategy::Medial(MedialOptions::DEFAULT),
                link: LinkOptions { climb, ..LinkOptions::DEFAULT },
                sim: SimOptions { res: Some(0.1), ..Default::default() },
                ..Default::default()
            };
            let out = rough(&job, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
            let r = &out.report;
            let what = format!("{name} ({})", if climb { "climb" } else { "conventional" });
            common::check_clean(&what, r, &mut bad);
            let turns = out.toolpath.cutting_turns();
            assert!(turns.len() > 20, "{what}: {} junctions", turns.len());
            let worst = turns.iter().map(|t| t.1).fold(0.0, f64::max);
            if worst > 1.0 {
                bad.push(format!("{what}: a turn of {worst:.2}° between cutting moves"));
            }
            // arcs carry most of the cutting length
            let (mut arc, mut all) = (0.0, 0.0);
            for (from, m) in out.toolpath.segments() {
                if m.is_rapid() {
                    continue;
                }
                let len = match m.motion {
                    Motion::Line => (m.to - from).truncate().length(),
                    Motion::Arc { center, ccw } => {
                        let (a0, a1) = ((from.truncate() - center), (m.to.truncate() - center));
                        let s = if ccw { 1.0 } else { -1.0 };
                        let sweep = ((a1.y.atan2(a1.x) - a0.y.atan2(a0.x)) * s).rem_euclid(std::f64::consts::TAU);
                        a0.length() * sweep
                    }
                };
                all += len;
                if matches!(m.motion, Motion::Arc { .. }) {
                    arc += len;
                }
            }
            if !(arc > 0.5 * all) {
                bad.push(format!("{what}: arcs are {:.1} % of the cutting length", 100.0 * arc / all));
            }
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// The check above is not vacuous: a program with a corner between two cutting moves reads
/// a turn of that size.
#[test]
fn a_corner_reads_as_a_turn() {
    use swarf::geom::{DVec2, DVec3};
    use swarf::toolpath::{MoveKind, Toolpath};
    let job = swarf::io::example_job();
    let mut tp = Toolpath::new(job.cutting.tool.clone(), DVec3::new(0.0, 0.0, 1.0), 5.0);
    tp.line(MoveKind::Descend, DVec3::new(0.0, 0.0, -1.0), 100.0);
    tp.line(MoveKind::Cut, DVec3::new(10.0, 0.0, -1.0), 100.0);
    // a quarter arc leaving tangentially, then a line at 30° to its end tangent
    tp.arc(MoveKind::Cut, DVec3::new(15.0, 5.0, -1.0), DVec2::new(10.0, 5.0), true, 100.0);
    let dir = DVec2::new(-0.5, 3f64.sqrt() / 2.0);
    tp.line(MoveKind::Cut, (DVec2::new(15.0, 5.0) + dir * 4.0).extend(-1.0), 100.0);
    let turns = tp.cutting_turns();
    assert_eq!(turns.len(), 2);
    assert!(turns[0].1 < 1e-9, "{turns:?}");
    assert!((turns[1].1 - 30.0).abs() < 1e-6, "{turns:?}");
}
