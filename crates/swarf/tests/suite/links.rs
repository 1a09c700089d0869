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
