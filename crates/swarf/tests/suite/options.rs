//! Every option a user can set is checked by the library: a job built through the library's API
//! alone with one bad value, given to the entry point that uses it (`rough`, `zlevel::rough`,
//! `load_input`, `plan_tools`, the oscillator), fails with `Error::Setting` naming that option,
//! and nothing is planned.

use std::path::{Path, PathBuf};
use swarf::geom::{Area, DVec2};
use swarf::io::{Input, Overrides, load_input};
use swarf::job::rough::{RoughOptions, rough};
use swarf::job::toolseq::SeqOptions;
use swarf::model::{Job, MeshJob, Width};
use swarf::plan::LinkOptions;
use swarf::sim::{SimEngine, SimOptions};
use swarf::strategy::{AdaptiveOptions, SpiralOptions, Strategy, ZigzagOptions};
use swarf::{Error, Setting};

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(p)
}

/// A small pocket that plans in a blink.
fn job() -> Job {
    let part = Area::rect(-5.0, -5.0, 25.0, 15.0).difference(&Area::rect(0.0, 0.0, 20.0, 10.0));
    Job::new("pocket", Area::rect(0.0, 0.0, 20.0, 10.0), part, 4.0, 2.0)
}

fn mesh_job() -> MeshJob {
    match load_input(&repo("examples/3d/bowl_cavity.json"), &Overrides::DEFAULT) {
        Ok(Input::Mesh(j)) => *j,
        other => panic!("the 3D example: {other:?}"),
    }
}

/// The setting an error names; panics on any other outcome.
fn setting<T: std::fmt::Debug>(what: &str, r: swarf::Result<T>) -> Setting {
    match r {
        Err(Error::Setting { setting, reason }) => {
            assert!(!reason.is_empty(), "{what}: no reason");
            setting
        }
        other => panic!("{what}: expected a setting error, got {other:?}"),
    }
}

fn rough_with(what: &str, job: &Job, opts: &RoughOptions) -> Setting {
    setting(what, rough(job, opts, &mut |_, _| {}).map(|r| r.gcode.len()))
}

#[test]
fn bad_job_values_name_their_setting() {
    let opts = RoughOptions { simulate: false, ..RoughOptions::DEFAULT };
    type Edit = Box<dyn Fn(&mut Job)>;
    let cases: Vec<(&str, Edit, Setting)> = vec![
        ("tool diameter 0", Box::new(|j| j.cutting.tool.diameter = 0.0), Setting::ToolDiameter),
        ("tool diameter NaN", Box::new(|j| j.cutting.tool.diameter = f64::NAN), Setting::ToolDiameter),
        ("stepover 0", Box::new(|j| j.cutting.width = Width::Stepover(0.0)), Setting::Stepover),
        ("engagement 200°", Box::new(|j| j.cutting.width = Width::EngagementDeg(200.0)), Setting::Engagement),
        ("feed −1", Box::new(|j| j.cutting.feed = -1.0), Setting::Feed),
        ("rapid rate NaN", Box::new(|j| j.cutting.rapid_rate = f64::NAN), Setting::RapidRate),
        ("spindle 0", Box::new(|j| j.cutting.spindle_rpm = 0.0), Setting::SpindleSpeed),
        ("highest feed under the feed", Box::new(|j| j.cutting.max_feed = Some(500.0)), Setting::MaxFeed),
        ("step-down 0", Box::new(|j| j.stepdown = Some(0.0)), Setting::Stepdown),
        ("floor above the top", Box::new(|j| j.floor = 1.0), Setting::Floor),
        ("stock top inf", Box::new(|j| j.stock_top = f64::INFINITY), Setting::StockTop),
        ("part top NaN", Box::new(|j| j.part_top = f64::NAN), Setting::PartTop),
        ("allowance −0.1", Box::new(|j| j.allowance = -0.1), Setting::Allowance),
        ("floor allowance −0.1", Box::new(|j| j.allowance_floor = -0.1), Setting::AllowanceFloor),
    ];
    for (what, bad, want) in cases {
        let mut j = job();
        bad(&mut j);
        assert_eq!(rough_with(what, &j, &opts), want, "{what}");
    }
    // the job without the bad value plans
    assert!(rough(&job(), &opts, &mut |_, _| {}).is_ok());
}

#[test]
fn bad_options_name_their_setting() {
    let d = RoughOptions { simulate: false, ..RoughOptions::DEFAULT };
    let link = |l: LinkOptions| RoughOptions { link: l, ..d.clone() };
    let l = LinkOptions::DEFAULT;
    let spiral = |s: SpiralOptions| RoughOptions { strategy: Strategy::Spiral(s), ..d.clone() };
    let sim = |s: SimOptions| RoughOptions { sim: s, ..d.clone() };
    let cases: Vec<(&str, RoughOptions, Setting)> = vec![
        ("stock to leave −0.5", link(LinkOptions { stock_to_leave: -0.5, ..l.clone() }), Setting::StockToLeave),
        ("ramp angle 90°", link(LinkOptions { ramp_angle_deg: 90.0, ..l.clone() }), Setting::RampAngle),
        ("helix radius 2 R", link(LinkOptions { helix_radius_frac: 2.0, ..l.clone() }), Setting::HelixRadius),
        ("arc tolerance 0", link(LinkOptions { arc_tol: 0.0, ..l.clone() }), Setting::ArcTolerance),
        ("clearance −1", link(LinkOptions { clearance: -1.0, ..l.clone() }), Setting::Clearance),
        ("approach 0", link(LinkOptions { approach: 0.0, ..l.clone() }), Setting::Approach),
        ("ramp feed 0", link(LinkOptions { ramp_feed_frac: 0.0, ..l.clone() }), Setting::EntryFeed),
        ("feed boost 0.5", link(LinkOptions { feed_boost: 0.5, ..l.clone() }), Setting::FeedBoost),
        (
            "overshoot −5°",
            RoughOptions {
                strategy: Strategy::Adaptive(AdaptiveOptions { overshoot_deg: -5.0, ..AdaptiveOptions::DEFAULT }),
                ..d.clone()
            },
            Setting::Overshoot,
        ),
        (
            "zigzag angle NaN",
            RoughOptions { strategy: Strategy::Zigzag(ZigzagOptions { angle_deg: f64::NAN }), ..d.clone() },
            Setting::ZigzagAngle,
        ),
        ("negative ζ", spiral(SpiralOptions { zeta: Some(-0.1), ..SpiralOptions::DEFAULT }), Setting::Zeta),
        ("spiral floor 0", spiral(SpiralOptions { floor: Some(0.0), ..SpiralOptions::DEFAULT }), Setting::SpiralFloor),
        (
            "spiral start NaN",
            spiral(SpiralOptions { start: Some(DVec2::new(f64::NAN, 0.0)), ..SpiralOptions::DEFAULT }),
            Setting::SpiralStart,
        ),
        (
            "spiral search without cells",
            spiral(SpiralOptions { search_cells: f64::NAN, ..SpiralOptions::DEFAULT }),
            Setting::SpiralSearch,
        ),
        (
            "spiral's adaptive overshoot 100°",
            spiral(SpiralOptions {
                adaptive: AdaptiveOptions { overshoot_deg: 100.0, ..AdaptiveOptions::DEFAULT },
                ..SpiralOptions::DEFAULT
            }),
            Setting::Overshoot,
        ),
        ("resolution 0", sim(SimOptions { res: Some(0.0), ..SimOptions::DEFAULT }), Setting::Resolution),
        ("sample step −1", sim(SimOptions { sample_step: Some(-1.0), ..SimOptions::DEFAULT }), Setting::Simulation),
        ("gouge tolerance NaN", sim(SimOptions { tol: f64::NAN, ..SimOptions::DEFAULT }), Setting::Simulation),
        ("no cells", sim(SimOptions { max_cells: 0, ..SimOptions::DEFAULT }), Setting::Simulation),
    ];
    let j = job();
    for (what, opts, want) in &cases {
        assert_eq!(rough_with(what, &j, opts), *want, "{what}");
    }
}

#[test]
fn bad_overrides_name_their_setting() {
    let o = Overrides::DEFAULT;
    let case = repo("examples/cases/square_pocket.json");
    let drawing = repo("crates/swarf-import/tests/data/dxf/trimesh_wrench.dxf");
    let stl = repo("examples/parts/bowl_cavity.stl");
    let mut import = o.import.clone();
    let cases: Vec<(&str, &PathBuf, Overrides, Setting)> = vec![
        ("tool 0", &case, Overrides { tool_diameter: Some(0.0), ..o.clone() }, Setting::ToolDiameter),
        ("stepover 1.5", &case, Overrides { width: Some(Width::Stepover(1.5)), ..o.clone() }, Setting::Stepover),
        ("step-down −1", &case, Overrides { stepdown: Some(-1.0), ..o.clone() }, Setting::Stepdown),
        ("feed 0", &case, Overrides { feed: Some(0.0), ..o.clone() }, Setting::Feed),
        ("spindle 0", &case, Overrides { spindle_rpm: Some(0.0), ..o.clone() }, Setting::SpindleSpeed),
        ("allowance −1", &case, Overrides { allowance: Some(-1.0), ..o.clone() }, Setting::Allowance),
        ("depth −3", &drawing, Overrides { depth: Some(-3.0), ..o.clone() }, Setting::Depth),
        ("stock margin −1", &stl, Overrides { stock_margin: -1.0, ..o.clone() }, Setting::StockMargin),
        ("stock above −1", &stl, Overrides { stock_above: -1.0, ..o.clone() }, Setting::StockAbove),
        (
            "chaining tolerance −1",
            &drawing,
            {
                import.chain_tolerance = -1.0;
                Overrides { import: import.clone(), ..o.clone() }
            },
            Setting::ChainTolerance,
        ),
        (
            "SVG 0 dpi",
            &drawing,
            {
                import = o.import.clone();
                import.svg_px_per_inch = Some(0.0);
                Overrides { import: import.clone(), ..o.clone() }
            },
            Setting::SvgDpi,
        ),
        (
            "flattening 0",
            &drawing,
            {
                import = o.import.clone();
                import.flatten_tolerance = 0.0;
                Overrides { import: import.clone(), ..o.clone() }
            },
            Setting::FlattenTolerance,
        ),
    ];
    for (what, path, ov, want) in cases {
        assert_eq!(setting(what, load_input(path, &ov)), want, "{what}");
    }
    let mut ov = o.clone();
    ov.placement.scale = 0.0;
    assert_eq!(setting("scale 0", load_input(&stl, &ov)), Setting::PartScale);
    let mut ov = o.clone();
    ov.placement.rotate_deg[1] = f64::NAN;
    assert_eq!(setting("rotation NaN", load_input(&stl, &ov)), Setting::PartRotate);
    let mut ov = o.clone();
    ov.placement.translate.z = f64::INFINITY;
    assert_eq!(setting("translation inf", load_input(&stl, &ov)), Setting::PartTranslate);
    // the good ones load
    for p in [&case, &drawing, &stl] {
        assert!(load_input(p, &o).is_ok(), "{}", p.display());
    }
}

#[test]
fn bad_mesh_jobs_and_tool_sequences_name_their_setting() {
    let opts = RoughOptions { simulate: false, ..RoughOptions::DEFAULT };
    let rough_mesh = |what: &str, j: &MeshJob, opts: &RoughOptions| {
        setting(what, swarf::job::zlevel::rough(j, opts, &mut |_, _| {}).map(|r| r.gcode.len()))
    };
    let mut j = mesh_job();
    j.stepdown = 0.0;
    assert_eq!(rough_mesh("step-down 0", &j, &opts), Setting::Stepdown);
    let mut j = mesh_job();
    j.stock_hi.z = j.stock_lo.z;
    assert_eq!(rough_mesh("flat stock box", &j, &opts), Setting::StockBox);
    let mut j = mesh_job();
    j.cutting.spindle_rpm = 0.0;
    assert_eq!(rough_mesh("spindle 0", &j, &opts), Setting::SpindleSpeed);
    let sdf =
        RoughOptions { sim: SimOptions { engine: SimEngine::Sdf, ..SimOptions::DEFAULT }, ..RoughOptions::DEFAULT };
    assert_eq!(rough_mesh("distance fields on a mesh", &mesh_job(), &sdf), Setting::SimEngine);
    let bad_link = RoughOptions { link: LinkOptions { arc_tol: -1.0, ..LinkOptions::DEFAULT }, ..opts.clone() };
    assert_eq!(rough_mesh("arc tolerance −1", &mesh_job(), &bad_link), Setting::ArcTolerance);

    let db = swarf::model::tooldb::ToolDb::read(&repo("examples/tools/table1.json")).expect("tool table");
    let plan = |what: &str, o: &SeqOptions| setting(what, swarf::job::toolseq::plan(&mesh_job(), &db, o).map(|_| ()));
    assert_eq!(plan("ramp 0°", &SeqOptions { ramp_deg: 0.0, ..SeqOptions::DEFAULT }), Setting::SeqRampAngle);
    assert_eq!(plan("clearance −2", &SeqOptions { clearance: -2.0, ..SeqOptions::DEFAULT }), Setting::SeqClearance);
    let sdf = SeqOptions { sim: SimOptions { engine: SimEngine::Sdf, ..SimOptions::DEFAULT }, ..SeqOptions::DEFAULT };
    assert_eq!(plan("the replay on distance fields", &sdf), Setting::SimEngine);
}

#[test]
fn bad_oscillator_settings_name_their_setting() {
    use swarf::implicit::oscillator::{Damping, SpiralOptions as Osc, spiral};
    use swarf::implicit::shape::Shape;
    let disk =
        Shape::from_json(r#"{"shape": {"circle": {"c": [0, 0], "r": 10}}}"#, Path::new("disk.json")).expect("a shape");
    let osc = |o: Osc| setting("oscillator", spiral(&disk, DVec2::ZERO, &o).map(|s| s.turns));
    assert_eq!(osc(Osc { damping: Damping::stepover(-1.0), ..Osc::default() }), Setting::OscillatorStepover);
    assert_eq!(osc(Osc { damping: Damping::Constant(-0.1), ..Osc::default() }), Setting::Zeta);
    assert_eq!(osc(Osc { rtol: 0.0, damping: Damping::stepover(1.0), ..Osc::default() }), Setting::Oscillator);
}

/// Each setting has a name in the library, and the names are unique.
#[test]
fn setting_names_are_unique() {
    let all = [
        Setting::ToolDiameter,
        Setting::Stepover,
        Setting::Engagement,
        Setting::Feed,
        Setting::RapidRate,
        Setting::SpindleSpeed,
        Setting::Stepdown,
        Setting::Floor,
        Setting::StockTop,
        Setting::PartTop,
        Setting::Allowance,
        Setting::AllowanceFloor,
        Setting::StockBox,
        Setting::Depth,
        Setting::StockMargin,
        Setting::StockAbove,
        Setting::PartScale,
        Setting::PartRotate,
        Setting::PartTranslate,
        Setting::ChainTolerance,
        Setting::FlattenTolerance,
        Setting::SvgDpi,
        Setting::StockToLeave,
        Setting::RampAngle,
        Setting::HelixRadius,
        Setting::ArcTolerance,
        Setting::Clearance,
        Setting::Approach,
        Setting::EntryFeed,
        Setting::FeedBoost,
        Setting::Overshoot,
        Setting::ZigzagAngle,
        Setting::Zeta,
        Setting::SpiralFloor,
        Setting::SpiralStart,
        Setting::SpiralSearch,
        Setting::Resolution,
        Setting::SimEngine,
        Setting::Simulation,
        Setting::SeqRampAngle,
        Setting::SeqClearance,
        Setting::OscillatorStepover,
        Setting::Oscillator,
        Setting::ShapeLevels,
    ];
    let mut names: Vec<&str> = all.iter().map(|s| s.name()).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), all.len());
}
