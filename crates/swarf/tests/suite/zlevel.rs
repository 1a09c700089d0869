//! Z-level roughing of a mesh part, end to end: a 100 × 100 × 18 mm block with a centred
//! 40 × 40 mm pocket 8 mm deep (written here as an ASCII STL), roughed from a stock box the
//! size of the block. The pocket's volume is 12 800 mm³; a round tool leaves its four sharp
//! corners, (R² − πR²/4) × 8 mm each.

use std::path::{Path, PathBuf};
use swarf::io::Input;
use swarf::job::rough::RoughOptions;
use swarf::strategy::Strategy;

/// Facets of the block (counter-clockwise seen from outside).
fn block_facets() -> Vec<[[f64; 3]; 3]> {
    let mut f = Vec::new();
    let mut quad = |a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]| {
        f.push([a, b, c]);
        f.push([a, c, d]);
    };
    let (h, fl) = (18.0, 10.0);
    // top, round the opening
    for (x0, y0, x1, y1) in
        [(-50.0, -50.0, 50.0, -20.0), (-50.0, 20.0, 50.0, 50.0), (-50.0, -20.0, -20.0, 20.0), (20.0, -20.0, 50.0, 20.0)]
    {
        quad([x0, y0, h], [x1, y0, h], [x1, y1, h], [x0, y1, h]);
    }
    // pocket floor and walls (facing into the pocket)
    quad([-20.0, -20.0, fl], [20.0, -20.0, fl], [20.0, 20.0, fl], [-20.0, 20.0, fl]);
    quad([-20.0, -20.0, h], [-20.0, -20.0, fl], [20.0, -20.0, fl], [20.0, -20.0, h]);
    quad([20.0, -20.0, h], [20.0, -20.0, fl], [20.0, 20.0, fl], [20.0, 20.0, h]);
    quad([20.0, 20.0, h], [20.0, 20.0, fl], [-20.0, 20.0, fl], [-20.0, 20.0, h]);
    quad([-20.0, 20.0, h], [-20.0, 20.0, fl], [-20.0, -20.0, fl], [-20.0, -20.0, h]);
    // bottom and sides
    quad([-50.0, -50.0, 0.0], [-50.0, 50.0, 0.0], [50.0, 50.0, 0.0], [50.0, -50.0, 0.0]);
    quad([-50.0, -50.0, 0.0], [50.0, -50.0, 0.0], [50.0, -50.0, h], [-50.0, -50.0, h]);
    quad([50.0, -50.0, 0.0], [50.0, 50.0, 0.0], [50.0, 50.0, h], [50.0, -50.0, h]);
    quad([50.0, 50.0, 0.0], [-50.0, 50.0, 0.0], [-50.0, 50.0, h], [50.0, 50.0, h]);
    quad([-50.0, 50.0, 0.0], [-50.0, -50.0, 0.0], [-50.0, -50.0, h], [-50.0, 50.0, h]);
    f
}

fn write_case(dir: &Path) -> PathBuf {
    std::fs::write(dir.join("block.stl"), crate::common::ascii_stl("block", &block_facets())).unwrap();
    let case = r#"{"units": "mm", "tool": {"diameter": 6, "type": "flat"},
        "stock_box": [-50, -50, 0, 50, 50, 18], "part_stl": "block.stl",
        "stepdown": 2.0, "stepover": 0.4, "feed_default": 1000, "rapid_rate": 5000}"#;
    let p = dir.join("block.json");
    std::fs::write(&p, case).unwrap();
    p
}

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("swarf-zlevel-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn rough(strategy: &str) -> swarf::job::rough::RoughResult {
    let dir = tmpdir(strategy);
    let case = write_case(&dir);
    let Input::Mesh(job) = swarf::io::load_input(&case, &Default::default()).unwrap_or_else(|e| panic!("{e}")) else {
        panic!("a 3D case reads as a mesh job")
    };
    let opts = RoughOptions {
        strategy: Strategy::from_name(strategy).expect("a strategy"),
        sim: swarf::sim::SimOptions { res: Some(0.1), ..Default::default() },
        ..Default::default()
    };
    let res = swarf::job::zlevel::rough(&job, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_dir_all(&dir);
    res
}

fn check(strategy: &str) {
    let res = rough(strategy);
    let r = &res.report;
    assert_eq!(r.levels, vec![16.0, 14.0, 12.0, 10.0], "levels");
    assert_eq!((r.gouges, r.rapid_collisions, r.plunges), (0, 0, 0), "{}", strategy);
    // nothing the tool can reach is left thicker than the simulation's tolerance
    assert!(r.rest_max_thickness_mm <= 0.05, "{}: rest {} mm thick", strategy, r.rest_max_thickness_mm);
    // the pocket less its four corners (res 0.1: within 0.5 %)
    let corners = 4.0 * (9.0 - std::f64::consts::PI * 9.0 / 4.0) * 8.0;
    let want = 12_800.0 - corners;
    assert!(
        (r.removed_volume_mm3 - want).abs() < 0.005 * want,
        "{}: removed {} mm³, want {want}",
        strategy,
        r.removed_volume_mm3
    );
    // every level but the first enters by a helix or ramp, and the program never goes below
    // the pocket floor
    assert!(res.toolpath.moves.iter().all(|m| m.to.z >= 10.0 - 1e-9));
    assert!(r.entries >= 4, "{} entries", r.entries);
}

#[test]
fn roughs_the_pocket_block_adaptive() {
    check("adaptive");
}

#[test]
fn roughs_the_pocket_block_offset() {
    check("offset");
}

#[test]
fn a_bad_stl_is_named() {
    let dir = tmpdir("bad");
    let case = write_case(&dir);
    std::fs::write(dir.join("block.stl"), "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0 zero 0\n")
        .unwrap();
    let e = swarf::io::load_input(&case, &Default::default()).unwrap_err().to_string();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(e.contains("block.stl: line 5"), "{e}");
}

/// An STL part read on its own gets no stock above its top unless asked (no facing), and a
/// flat part, with nothing to rough, is refused with the file named.
#[test]
fn an_stl_alone_is_not_faced_unless_asked() {
    use swarf::{Input, Overrides};
    let dir = tmpdir("alone");
    let _ = write_case(&dir);
    let stl = dir.join("block.stl");
    let load = |above: f64| match swarf::io::load_input(&stl, &Overrides { stock_above: above, ..Overrides::DEFAULT }) {
        Ok(Input::Mesh(job)) => job,
        _ => panic!("a mesh job"),
    };
    let (plain, faced) = (load(0.0), load(1.5));
    assert_eq!(plain.stock_hi.z, plain.mesh.bounds().expect("facets").1.z);
    assert!((faced.stock_hi.z - plain.stock_hi.z - 1.5).abs() < 1e-12);
    std::fs::write(
        dir.join("flat.stl"),
        "solid f\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 10 0 0\nvertex 0 10 0\nendloop\nendfacet\nendsolid f\n",
    )
    .unwrap();
    let e = swarf::io::load_input(&dir.join("flat.stl"), &Overrides::DEFAULT).map(|_| ()).unwrap_err();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(matches!(e, swarf::Error::Input { .. }) && e.to_string().contains("flat.stl"), "{e}");
}

/// A wedge: a slope from z 2 at x 0 up to z 14 at x 40, then flat to x 60, 30 mm deep in y.
fn wedge_facets() -> Vec<[[f64; 3]; 3]> {
    let mut f = Vec::new();
    let mut quad = |a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]| {
        f.push([a, b, c]);
        f.push([a, c, d]);
    };
    quad([0.0, 0.0, 2.0], [40.0, 0.0, 14.0], [40.0, 30.0, 14.0], [0.0, 30.0, 2.0]);
    quad([40.0, 0.0, 14.0], [60.0, 0.0, 14.0], [60.0, 30.0, 14.0], [40.0, 30.0, 14.0]);
    quad([0.0, 0.0, 0.0], [0.0, 30.0, 0.0], [60.0, 30.0, 0.0], [60.0, 0.0, 0.0]);
    quad([0.0, 0.0, 0.0], [0.0, 0.0, 2.0], [0.0, 30.0, 2.0], [0.0, 30.0, 0.0]);
    quad([60.0, 0.0, 0.0], [60.0, 30.0, 0.0], [60.0, 30.0, 14.0], [60.0, 0.0, 14.0]);
    // the two sides (x, z pentagons), fanned from the bottom corner
    for (y, flip) in [(0.0, false), (30.0, true)] {
        let p = [[0.0, y, 0.0], [60.0, y, 0.0], [60.0, y, 14.0], [40.0, y, 14.0], [0.0, y, 2.0]];
        for k in 1..4 {
            f.push(if flip { [p[0], p[k + 1], p[k]] } else { [p[0], p[k], p[k + 1]] });
        }
    }
    f
}

/// On a slope, z-level roughing leaves terraces by design: the report tells them apart from
/// material the tool could have cut at a level and left. Here every level is cut, so the rest is
/// the terraces, each at most a step-down thick (their volume is half the step-down times the
/// slope's plan area: a triangle under every step), and nothing beyond them.
#[test]
fn the_rest_on_a_slope_is_terraces() {
    let dir = tmpdir("wedge");
    std::fs::write(dir.join("wedge.stl"), crate::common::ascii_stl("wedge", &wedge_facets())).unwrap();
    let case = r#"{"units": "mm", "tool": {"diameter": 6, "type": "flat"},
        "stock_box": [-10, -10, 0, 70, 40, 14], "part_stl": "wedge.stl",
        "stepdown": 3.0, "engagement_deg": 60, "feed_default": 1000, "rapid_rate": 5000}"#;
    std::fs::write(dir.join("wedge.json"), case).unwrap();
    let Input::Mesh(job) = swarf::io::load_input(&dir.join("wedge.json"), &Default::default()).unwrap() else {
        panic!("a 3D case reads as a mesh job")
    };
    let opts =
        RoughOptions { sim: swarf::sim::SimOptions { res: Some(0.1), ..Default::default() }, ..Default::default() };
    let r = swarf::job::zlevel::rough(&job, &opts, &mut |_, _| {}).unwrap_or_else(|e| panic!("{e}")).report;
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!((r.gouges, r.rapid_collisions), (0, 0));
    // the slope's plan area is 40 × 30 mm: nearly all of it carries a terrace
    assert!(r.rest_terrace_area_mm2 > 0.9 * 1200.0, "terraces over {} mm²", r.rest_terrace_area_mm2);
    // (five even levels 2.8 mm apart from the top at 14 down to the floor)
    assert_eq!(r.levels.len(), 5, "{:?}", r.levels);
    let want = 0.5 * 2.8 * 1200.0;
    assert!(
        (r.rest_terrace_volume_mm3 - want).abs() < 0.1 * want,
        "terraces of {} mm³, want about {want}",
        r.rest_terrace_volume_mm3
    );
    assert!(r.rest_max_thickness_mm <= 2.8 + 0.05, "rest {} mm thick", r.rest_max_thickness_mm);
    assert!(r.rest_beyond_terraces_fraction < 0.002, "{} beyond the terraces", r.rest_beyond_terraces_fraction);
    assert!(r.rest_fraction > 0.1, "the terraces count as rest ({})", r.rest_fraction);
}
