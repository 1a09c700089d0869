//! The oscillator spiral (paper 4) on the example cases it is meant for: clean by swarf's own
//! simulator (no gouge, no rapid collision, no plunge, rest under 0.5 % of the reachable area),
//! one entry and no retract before the end, tangent-continuous wherever it cuts (no turn above
//! 1° in the planned path, 2° once written to 1 µm, and none above 30° between chords at the
//! scale of 0.05 or 0.1 mm, where runs of tiny arcs would read as a polygon), all arcs, and
//! within the engagement bound (p99 ≤ reference + 10°). A pocket with islands gets a spiral
//! over its island-free core and adaptive passes for the rest, clean and within the bound. The
//! optimiser's choice is feasible and no faster candidate is.

use std::path::Path;
use swarf::job::rough::{RoughOptions, rough};
use swarf::plan::LinkOptions;
use swarf::sim::SimOptions;
use swarf::strategy::{SpiralOptions, Strategy};
use swarf::toolpath::{Motion, MoveKind};

use crate::common;

fn case(name: &str) -> swarf::model::Job {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cases").join(name);
    swarf::io::load_job(&path, &Default::default()).unwrap_or_else(|e| panic!("{e}"))
}

// One test per case (both milling directions), so that the harness runs them side by side.

#[test]
fn the_round_pocket_spirals_are_clean_smooth_and_in_one_piece() {
    clean_smooth_and_in_one_piece("round_pocket.json");
}

#[test]
fn the_square_pocket_spirals_are_clean_smooth_and_in_one_piece() {
    clean_smooth_and_in_one_piece("square_pocket.json");
}

#[test]
fn the_l_pocket_spirals_are_clean_smooth_and_in_one_piece() {
    clean_smooth_and_in_one_piece("l_pocket.json");
}

fn clean_smooth_and_in_one_piece(name: &str) {
    let mut bad = Vec::new();
    {
        let job = case(name);
        for climb in [true, false] {
            let opts = RoughOptions {
                input_name: name.into(),
                strategy: Strategy::Spiral(SpiralOptions::DEFAULT),
                link: LinkOptions { climb, ..LinkOptions::DEFAULT },
                sim: SimOptions { res: Some(0.1), ..Default::default() },
                ..Default::default()
            };
            // planned once: the planned program is checked below, and posted and proved here
            let planned = swarf::job::rough::plan(&job, &opts).unwrap_or_else(|e| panic!("{e}")).expect("a program");
            let out = swarf::job::rough::rough_planned(
                &job,
                &opts,
                planned.clone(),
                std::time::Instant::now(),
                &mut |_, _| {},
            )
            .unwrap_or_else(|e| panic!("{name}: {e}"));
            let r = &out.report;
            let what = format!("{name} ({})", if climb { "climb" } else { "conventional" });
            common::check_clean(&what, r, &mut bad);
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
            // which tilts the ends of the shortest arcs (a few hundredths of a millimetre long,
            // in the tight tips of the levels along an L's legs) by up to 2°
            let turns = planned.toolpath.cutting_turns();
            assert!(turns.len() > 20, "{what}: {} junctions", turns.len());
            let worst = turns.iter().map(|t| t.1).fold(0.0, f64::max);
            if worst > 1.0 {
                bad.push(format!("{what}: a turn of {worst:.2}° between planned cutting moves"));
            }
            let written = tp.cutting_turns().iter().map(|t| t.1).fold(0.0, f64::max);
            if written > 2.0 {
                bad.push(format!("{what}: a turn of {written:.2}° between written cutting moves"));
            }
            // and smooth at the scale of a simulator's grid or a controller's look-ahead: no
            // run of tiny arcs that reads as a polygon (a sharp corner: a turn above 30°
            // between chords longer than the scale)
            for scale in [0.05, 0.1] {
                let coarse = tp.cutting_turns_at(scale).iter().map(|t| t.1).fold(0.0, f64::max);
                if coarse > 30.0 {
                    bad.push(format!("{what}: a turn of {coarse:.1}° at the scale of {scale} mm"));
                }
            }
            // (biarcs as planned: the written program has lines where an arc of over 10 m is
            // straight to the printed micrometre, Toolpath::quantize)
            let lines =
                planned.toolpath.moves.iter().filter(|m| m.kind == MoveKind::Cut && m.motion == Motion::Line).count();
            if lines > 2 {
                bad.push(format!("{what}: {lines} straight cutting moves"));
            }
            common::check_bound(&what, r, job.cutting.width.engagement_deg(), &mut bad);
        }
    }
    assert!(bad.is_empty(), "{bad:#?}");
}

#[test]
fn pockets_with_islands_get_a_spiral_core_and_adaptive_passes() {
    let mut bad = Vec::new();
    for name in ["pocket_islands.json", "boss_with_clamp.json"] {
        let job = case(name);
        let opts = RoughOptions {
            input_name: name.into(),
            strategy: Strategy::Spiral(SpiralOptions::DEFAULT),
            sim: SimOptions { res: Some(0.1), ..Default::default() },
            ..Default::default()
        };
        let out = rough(&job, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{name}: {e}"));
        let r = &out.report;
        common::check_clean(name, r, &mut bad);
        common::check_bound(name, r, job.cutting.width.engagement_deg(), &mut bad);
        // the spiral is there, and says what follows it
        if !out.gcode.contains("spiral over the island-free core") {
            bad.push(format!("{name}: no spiral core in the program"));
        }
        let arcs = out.toolpath.moves.iter().filter(|m| m.kind == MoveKind::Cut && m.motion != Motion::Line).count();
        if arcs < 100 {
            bad.push(format!("{name}: only {arcs} cutting arcs"));
        }
    }
    assert!(bad.is_empty(), "{bad:#?}");
}

#[test]
fn the_optimiser_keeps_the_fastest_feasible_spiral() {
    let job = case("l_pocket.json");
    let opts = RoughOptions {
        strategy: Strategy::Spiral(SpiralOptions::DEFAULT),
        sim: SimOptions { res: Some(0.1), ..Default::default() },
        ..Default::default()
    };
    let study =
        swarf::strategy::spiral_search::optimise_spiral_job(&job, &SpiralOptions::DEFAULT, &opts.link, &opts.sim)
            .unwrap_or_else(|e| panic!("{e}"));
    let (choice, trials) = &study;
    let chosen = trials.iter().find(|t| t.choice == *choice).expect("the choice is a trial");
    assert!(chosen.feasible(), "{chosen:?}");
    let t_best = chosen.time_min.expect("a time");
    for t in trials {
        let Some(time) = t.time_min else { continue };
        if time < t_best {
            // a faster candidate was simulated and failed, or shares a damping that failed, or
            // a lower floor from its start failed
            let failed = |u: &swarf::strategy::spiral::Trial| u.sim.is_some_and(|s| !s.feasible);
            let pruned = trials.iter().any(|u| {
                u.choice.zeta == t.choice.zeta
                    && (u.choice.floor == t.choice.floor
                        || (u.choice.start == t.choice.start && u.choice.floor < t.choice.floor))
                    && failed(u)
            });
            assert!(failed(t) || pruned, "a faster candidate was passed over: {t:?}");
        }
    }
    // on an L the widest floor breaks the bound (the tips of the levels along its legs), so
    // the optimiser had something to do
    let widest = trials.iter().find(|t| t.choice.floor == 0.5 && t.choice.start.is_none()).expect("floor 0.5");
    assert!(widest.sim.is_some_and(|s| !s.feasible), "{widest:?}");
    assert!(choice.floor < 0.5);
}

/// The search stops at its work bound: on the L (where the widest floors break the engagement
/// bound) a budget of one cell lets it plan and simulate its first round only, and the program
/// it keeps, the nearest miss, says the search stopped; with the default budget it goes on to a
/// feasible floor. The same choice every time (the bound counts cells, not seconds).
#[test]
fn the_spiral_search_stops_at_its_work_bound() {
    let job = case("l_pocket.json");
    let sim = SimOptions { res: Some(0.1), ..Default::default() };
    let link = RoughOptions::default().link;
    let tight = SpiralOptions { search_cells: 1.0, ..SpiralOptions::DEFAULT };
    let search = |o: &SpiralOptions| {
        swarf::strategy::spiral_search::optimise_spiral_job(&job, o, &link, &sim).unwrap_or_else(|e| panic!("{e}"))
    };
    let (choice, trials) = search(&tight);
    let planned: Vec<_> = trials.iter().filter(|t| t.time_min.is_some()).collect();
    assert_eq!(planned.len(), swarf::strategy::spiral_search::ROUND, "{trials:#?}");
    assert!(planned.iter().all(|t| t.sim.is_some_and(|s| !s.feasible)), "{trials:#?}");
    assert!(trials.iter().skip(planned.len()).all(|t| t.time_min.is_none() && t.sim.is_none()));
    assert_eq!(search(&tight).0, choice, "the same choice again");
    let (full, _) = search(&SpiralOptions::DEFAULT);
    assert!(full.floor < choice.floor.min(0.42), "{full:?} against {choice:?}");
    // the program says why it breaks the bound
    let opts = RoughOptions { strategy: Strategy::Spiral(tight), sim, ..Default::default() };
    let r = swarf::job::rough::rough(&job, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{e}"));
    let first = r.gcode.lines().find(|l| l.contains("spiral candidate")).unwrap_or_default();
    assert!(first.contains("tried within the search's bounds") && first.contains("--spiral-floor"), "{first}");
}
