//! `swarf plan`'s report: every program of the chosen sequence is replayed on the simulator, and
//! PLAN.json gives, per program and under the names of `swarf rough`'s report, the gouges, rapid
//! collisions, plunges and the rest material after it.

use std::path::Path;

use crate::common;
use common::TempDir;

/// The bowl cavity (sloping walls, a floor, a deeper pocket) with three tools of paper 3's
/// Table 1: D25, D20 and D10.
#[test]
fn plan_report_gives_each_programs_replay() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = TempDir::new("plan-report");
    let table: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root.join("examples/tools/table1.json")).expect("the tool table"),
    )
    .expect("json");
    let tools: Vec<serde_json::Value> = table["tools"]
        .as_array()
        .expect("tools")
        .iter()
        .filter(|t| ["T4", "T5", "T8"].contains(&t["id"].as_str().expect("id")))
        .cloned()
        .collect();
    let db = dir.write(
        "tools.json",
        serde_json::to_string(&serde_json::json!({"machine": table["machine"], "tools": tools})).expect("json"),
    );
    let out = dir.path().join("out");
    let report = common::plan_report(&root.join("examples/3d/bowl_cavity.json"), &db, &out);
    assert!(report["simulate_s"].as_f64().expect("simulate_s") > 0.0);
    let programs = report["best"]["programs"].as_array().expect("programs");
    assert_eq!(programs.len(), 3, "the three tools are the cheapest sequence: {:?}", report["best"]["tools"]);
    let last = programs.last().expect("a program");
    let smallest = last["diameter"].as_f64().expect("diameter");
    let num = |p: &serde_json::Value, k: &str| p[k].as_f64().unwrap_or_else(|| panic!("{}: no {k}", p["file"]));
    let mut rest_before = f64::INFINITY;
    for p in programs {
        let name = p["file"].as_str().expect("file");
        assert_eq!(p["simulated"], true, "{name}");
        // clean: no gouge, no rapid into material, no plunge (the trimmed pieces go down in
        // air, the first tool ramps), and the count is that of the events listed
        for (count, at) in
            [("gouges", "gouge_at"), ("rapid_collisions", "rapid_collision_at"), ("plunges", "plunge_at")]
        {
            assert_eq!(p[count], 0, "{name}: {count} at {}", p[at]);
            assert_eq!(p[at].as_array().map(Vec::len), Some(0), "{name}: {at}");
        }
        for k in ["gouge_max_mm", "rapid_collision_max_mm", "plunge_max_mm"] {
            assert_eq!(num(p, k), 0.0, "{name}: {k}");
        }
        // every program cuts, and the rest (against the smallest tool's reach) only falls
        assert!(num(p, "removed_volume_mm3") > 100.0, "{name}: removed {}", p["removed_volume_mm3"]);
        assert_eq!(num(p, "rest_reach_diameter_mm"), smallest, "{name}");
        let (rest, area, reach, frac) =
            (num(p, "rest_volume_mm3"), num(p, "rest_area_mm2"), num(p, "reachable_area_mm2"), num(p, "rest_fraction"));
        assert!(rest <= rest_before + 1e-6, "{name}: rest {rest} mm³ after {rest_before}");
        assert!(reach > 0.0 && (frac - area / reach).abs() < 1e-9 && (0.0..=1.0).contains(&frac), "{name}");
        assert!(num(p, "rest_max_thickness_mm") >= 0.0 && num(p, "sim_res_mm") > 0.0, "{name}");
        rest_before = rest;
        let picture = p["rest_picture"].as_str().expect("a picture");
        assert!(out.join(picture).is_file(), "{picture}");
    }
    // after the last tool: only the steps its levels leave on the sloping walls, at most its
    // depth of cut thick (the job has no allowance), give or take a simulation cell
    let dc = tools.iter().find(|t| t["id"] == last["tool"]).expect("the last tool")["depth_of_cut"]
        .as_f64()
        .expect("depth of cut");
    let thick = num(last, "rest_max_thickness_mm");
    assert!(
        thick <= dc + num(last, "sim_res_mm") + 1e-6,
        "rest {thick} mm thick after the last tool (depth of cut {dc})"
    );
    assert!(num(last, "rest_volume_mm3") > 0.0, "the steps of the levels on the sloping walls");
}
