//! The distance-field simulator (paper 4 §4) against the raster one on the same programs: on
//! four example cases, the removed volume agrees within 1 % and the 95th percentile of the
//! lateral engagement outside the entry bores (the figure the report judges by) within 3°; both
//! find the same gouges, rapid collisions and plunges (none), and about the same rest.

use std::path::Path;
use swarf::job::rough::{RoughOptions, plan};
use swarf::report::Stats;
use swarf::sim::{Replay, SampleKind, SimEngine, SimOptions, simulate};

fn p95(rp: &Replay) -> f64 {
    Stats::of(rp.samples.iter().filter(|s| s.kind == SampleKind::Lateral && !s.bore).map(|s| s.tea as f64).collect())
        .p95
}

#[test]
fn sdf_and_raster_agree_on_example_programs() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cases");
    let mut bad = Vec::new();
    for name in ["l_pocket", "narrow_slot", "round_pocket", "simple_part"] {
        let path = dir.join(format!("{name}.json"));
        let job = swarf::io::load_job(&path, &Default::default()).unwrap_or_else(|e| panic!("{e}"));
        let opts = RoughOptions { sim: SimOptions { res: Some(0.1), ..Default::default() }, ..Default::default() };
        let planned = plan(&job, &opts).unwrap_or_else(|e| panic!("{name}: {e}")).expect("a program");
        let run = |engine| {
            let sim = SimOptions { engine, ..opts.sim.clone() };
            simulate(&job, &planned.regions, &sim, &planned.toolpath, &mut |_| {}).unwrap_or_else(|e| panic!("{e}"))
        };
        let (ra, rest_a) = run(SimEngine::Raster);
        let (sd, rest_s) = run(SimEngine::Sdf);
        assert!(ra.removed_volume > 0.0 && p95(&ra) > 0.0, "{name}: nothing cut");
        let dv = (sd.removed_volume - ra.removed_volume) / ra.removed_volume;
        let de = p95(&sd) - p95(&ra);
        eprintln!(
            "{name}: volume {:.1} / {:.1} mm³ ({:+.3} %), p95 engagement {:.2}° / {:.2}° ({de:+.2}°), rest {:.2} / {:.2} mm²",
            ra.removed_volume,
            sd.removed_volume,
            100.0 * dv,
            p95(&ra),
            p95(&sd),
            rest_a.area_mm2,
            rest_s.area_mm2
        );
        if dv.abs() > 0.01 {
            bad.push(format!("{name}: removed volume differs by {:.3} %", 100.0 * dv));
        }
        if de.abs() > 3.0 {
            bad.push(format!("{name}: p95 engagement differs by {de:.2}°"));
        }
        for (what, a, b) in [
            ("gouges", ra.gouges.len(), sd.gouges.len()),
            ("rapid collisions", ra.rapid_collisions.len(), sd.rapid_collisions.len()),
            ("plunges", ra.plunges.len(), sd.plunges.len()),
        ] {
            if a != b {
                bad.push(format!("{name}: {a} {what} by the raster, {b} by the distance field"));
            }
        }
        // the same samples, at the same places
        assert_eq!(ra.samples.len(), sd.samples.len(), "{name}");
        let slack = 0.005 * rest_a.reachable_mm2;
        if (rest_a.area_mm2 - rest_s.area_mm2).abs() > slack {
            bad.push(format!("{name}: rest {:.2} vs {:.2} mm²", rest_a.area_mm2, rest_s.area_mm2));
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn sdf_refuses_nonsense_spacing() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cases");
    let job = swarf::io::load_job(&dir.join("l_pocket.json"), &Default::default()).unwrap_or_else(|e| panic!("{e}"));
    let regions = job.regions(job.radius(), 0.0).expect("regions");
    for res in [0.0, -1.0, f64::NAN, 1e-6] {
        let opts = SimOptions { res: Some(res), engine: SimEngine::Sdf, ..Default::default() };
        assert!(swarf::sim::SdfSim::new(&job, &regions, &opts).is_err(), "res {res}");
    }
}
