//! The same job gives the same program: `swarf::job::rough::rough` twice on the same input must
//! write byte-identical G-code and the same report (timings aside), whatever the number of
//! threads it runs on.

use std::path::Path;
use swarf::job::rough::{RoughOptions, RoughResult, Stage, rough};
use swarf::model::Job;
use swarf::report::Report;
use swarf::strategy::Strategy;

fn run(job: &Job, opts: &RoughOptions, threads: usize) -> RoughResult {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("thread pool");
    pool.install(|| rough(job, opts, &mut |_, _| {})).unwrap_or_else(|e| panic!("{}: {e}", job.name))
}

/// The report without the fields that measure time.
fn untimed(r: &Report) -> Report {
    Report { compute_s: 0.0, simulate_s: 0.0, total_s: 0.0, ..r.clone() }
}

fn check(job: &Job, opts: &RoughOptions, what: &str) {
    let a = run(job, opts, 1);
    let b = run(job, opts, 1);
    let c = run(job, opts, 4);
    assert!(a.gcode.lines().count() > 20, "{what}: suspiciously short program:\n{}", a.gcode);
    assert!(a.report.cut_length_mm > 0.0, "{what}: nothing cut");
    for (other, how) in [(&b, "a second run"), (&c, "a run on 4 threads")] {
        if a.gcode != other.gcode {
            let at = a.gcode.lines().zip(other.gcode.lines()).position(|(x, y)| x != y);
            panic!(
                "{what}: {how} wrote different G-code ({} vs {} lines, first difference at line {:?}: {:?} vs {:?})",
                a.gcode.lines().count(),
                other.gcode.lines().count(),
                at.map(|i| i + 1),
                at.and_then(|i| a.gcode.lines().nth(i)),
                at.and_then(|i| other.gcode.lines().nth(i)),
            );
        }
        assert_eq!(a.toolpath.moves, other.toolpath.moves, "{what}: {how} gave different moves");
        assert_eq!(a.toolpath.notes, other.toolpath.notes, "{what}: {how} gave different notes");
        assert_eq!(untimed(&a.report), untimed(&other.report), "{what}: {how} gave a different report");
        let (ra, ro) = (a.replay.as_ref().expect("simulated"), other.replay.as_ref().expect("simulated"));
        assert!(
            ra.samples == ro.samples,
            "{what}: {how}: different engagement samples ({} vs {})",
            ra.samples.len(),
            ro.samples.len()
        );
        assert_eq!(ra.gouges, ro.gouges, "{what}: {how}: gouges");
        assert_eq!(ra.rapid_collisions, ro.rapid_collisions, "{what}: {how}: rapid collisions");
        assert_eq!(ra.plunges, ro.plunges, "{what}: {how}: plunges");
    }
}

#[test]
fn builtin_example_is_deterministic() {
    let job = swarf::io::example_job();
    let opts = RoughOptions { input_name: "demo".into(), ..Default::default() };
    check(&job, &opts, "example_job, offset");
}

#[test]
fn case_file_is_deterministic() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cases/l_pocket.json");
    let job = swarf::io::load_job(&path, &Default::default()).unwrap_or_else(|e| panic!("{e}"));
    for kind in ["offset", "zigzag"] {
        let mut opts = RoughOptions { input_name: "l_pocket.json".into(), ..Default::default() };
        opts.strategy = Strategy::from_name(kind).expect("a strategy");
        check(&job, &opts, &format!("l_pocket, {}", kind));
    }
}

/// `rough` proves a program while it is planned (the linker hands its moves to the proof in
/// pieces): the same replay, sample for sample, and the same report as proving the finished
/// program after its planning (`plan`, then `rough_planned`): adaptive programs of tens of
/// pieces, and a zigzag program shorter than one (all of it the tail).
#[test]
fn the_proof_alongside_the_planning_is_the_proof_after_it() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cases");
    for (case, kind) in [("pocket_islands", "adaptive"), ("square_pocket", "adaptive"), ("l_pocket", "zigzag")] {
        let job = swarf::io::load_job(&dir.join(format!("{case}.json")), &Default::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let opts = RoughOptions {
            strategy: Strategy::from_name(kind).expect("a strategy"),
            input_name: case.into(),
            ..Default::default()
        };
        let what = format!("{case}, {kind}");
        let mut told = Vec::new();
        let along = rough(&job, &opts, &mut |stage, f| told.push((stage, f))).unwrap_or_else(|e| panic!("{what}: {e}"));
        // the wait for the proof is its stage: from 0 to 1, never back
        let proving: Vec<f64> = told.iter().filter(|(s, _)| *s == Stage::Simulate).map(|(_, f)| *f).collect();
        assert!(proving.len() >= 3 && proving.is_sorted() && proving[proving.len() - 1] == 1.0, "{what}: {proving:?}");
        let planned =
            swarf::job::rough::plan(&job, &opts).unwrap_or_else(|e| panic!("{what}: {e}")).expect("a program");
        let after = swarf::job::rough::rough_planned(&job, &opts, planned, std::time::Instant::now(), &mut |_, _| {})
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        let n = along.toolpath.moves.len();
        assert!(if kind == "adaptive" { n > 2000 } else { n < 500 }, "{what}: {n} moves");
        assert_eq!(along.gcode, after.gcode, "{what}: the program");
        assert_eq!(untimed(&along.report), untimed(&after.report), "{what}: the report");
        let (a, b) = (along.replay.as_ref().expect("simulated"), after.replay.as_ref().expect("simulated"));
        assert!(a.samples == b.samples, "{what}: {} samples against {}", a.samples.len(), b.samples.len());
        assert_eq!((&a.gouges, &a.rapid_collisions, &a.plunges), (&b.gouges, &b.rapid_collisions, &b.plunges));
        assert_eq!((a.removed_volume, &a.rest_cells), (b.removed_volume, &b.rest_cells), "{what}");
    }
}
