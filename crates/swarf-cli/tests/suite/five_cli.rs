//! `swarf five` end to end on the example channel (`examples/five/channel.json`): the CL file
//! and the G-code it writes agree move for move, LinuxCNC's `rs274` reads the G-code (when it is
//! on PATH; CI requires it), `--help` lists `--gcode`, and a bad case is refused with exit 2, a
//! message naming the file and the key, and nothing written.

use crate::common::{TempDir, swarf};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

fn example() -> PathBuf {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/five/channel.json");
    assert!(p.is_file(), "{} is missing", p.display());
    p
}

fn find_on_path(name: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|p| std::env::split_paths(&p).map(|d| d.join(name)).find(|p| p.is_file()))
}

#[test]
fn the_help_lists_the_gcode_option() {
    let dir = TempDir::new("five-help");
    let out = swarf(dir.path(), &["five", "--help"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("--gcode"), "{text}");
}

#[test]
fn the_picture_draws_the_four_views_of_the_plan() {
    let dir = TempDir::new("five-picture");
    let case = example();
    let out = swarf(dir.path(), &["five", case.to_str().expect("utf-8"), "-o", "out.cl", "--picture", "out.svg"]);
    assert!(out.status.success(), "swarf five failed: {}", String::from_utf8_lossy(&out.stderr));
    let svg = std::fs::read_to_string(dir.path().join("out.svg")).expect("the picture");
    assert!(svg.contains("<svg") && svg.trim_end().ends_with("</svg>"), "{}", &svg[..200.min(svg.len())]);
    for view in ["shapes between the walls", "after the variable offset", "on the floor", "the field V"] {
        assert!(svg.contains(view), "no view {view:?}");
    }
    // titled with the plan's own figures, as the command reports them
    let said = String::from_utf8_lossy(&out.stdout);
    let shapes = said.split(": ").nth(1).and_then(|t| t.split(' ').next()).expect("the shapes in the report");
    assert!(svg.contains(&format!("{shapes} rounded shapes")), "{said}");
}

#[test]
fn the_example_channel_is_pocketed_and_rs274_reads_its_gcode() {
    let dir = TempDir::new("five-e2e");
    let case = example();
    let out = swarf(dir.path(), &["five", case.to_str().expect("utf-8"), "-o", "out.cl", "--gcode", "out.ngc"]);
    assert!(out.status.success(), "swarf five failed: {}", String::from_utf8_lossy(&out.stderr));
    let cl = std::fs::read_to_string(dir.path().join("out.cl")).expect("the CL file");
    let ngc = std::fs::read_to_string(dir.path().join("out.ngc")).expect("the G-code");
    // the CL file: the statements of the format, one feed run between two rapids
    let lines: Vec<&str> = cl.lines().collect();
    assert!(lines.contains(&"UNITS/MM") && lines.contains(&"MULTAX/ON"), "{}", &cl[..300.min(cl.len())]);
    assert_eq!(lines.last(), Some(&"FINI"));
    let gotos: Vec<Vec<f64>> = lines
        .iter()
        .filter_map(|l| l.strip_prefix("GOTO/"))
        .map(|a| a.split(',').map(|x| x.parse::<f64>().expect("a number")).collect())
        .collect();
    assert!(gotos.len() > 1000, "{} GOTOs", gotos.len());
    assert_eq!(lines.iter().filter(|l| **l == "RAPID").count(), 3, "rapids: to the start, down, and the retract");
    for g in &gotos {
        assert_eq!(g.len(), 6);
        let n = (g[3] * g[3] + g[4] * g[4] + g[5] * g[5]).sqrt();
        assert!((n - 1.0).abs() < 1e-3, "axis of length {n}");
    }
    // the G-code: one motion per GOTO, its axis (sin C sin A, cos C sin A, cos A) the CL's
    let motions: Vec<&str> = ngc.lines().filter(|l| l.starts_with("G0 ") || l.starts_with("G1 ")).collect();
    assert_eq!(motions.len(), gotos.len());
    for (m, g) in motions.iter().zip(&gotos) {
        let word = |c: char| -> f64 {
            m.split_whitespace().find_map(|w| w.strip_prefix(c)).expect("the word").parse().expect("a number")
        };
        let (a, c) = (word('A').to_radians(), word('C').to_radians());
        let axis = [c.sin() * a.sin(), c.cos() * a.sin(), a.cos()];
        let dev = (0..3).map(|k| (axis[k] - g[3 + k]).powi(2)).sum::<f64>().sqrt();
        assert!(dev < 2e-4, "{m}: axis off the CL's by {dev}");
        assert!((word('X') - g[0]).abs() < 1e-3 && (word('Y') - g[1]).abs() < 1e-3 && (word('Z') - g[2]).abs() < 1e-3);
    }
    // LinuxCNC's interpreter reads it
    let Some(rs274) = find_on_path("rs274") else {
        assert!(std::env::var_os("SWARF_REQUIRE_RS274").is_none(), "rs274 is required but not on PATH");
        eprintln!("note: rs274 not on PATH; skipping the interpreter check of the 5-axis program");
        return;
    };
    let work = TempDir::new("five-rs274");
    let table: String = (1..=9).map(|i| format!("T{i} P{i} Z0 D0\n")).collect();
    std::fs::write(work.path().join("tool.tbl"), table).expect("tool table");
    let run = Command::new(rs274)
        .current_dir(work.path())
        .env("HOME", work.path())
        .args(["-g", "-t", "tool.tbl"])
        .arg(dir.path().join("out.ngc"))
        .arg("canon.txt")
        .stdin(Stdio::null())
        .output()
        .expect("run rs274");
    let err: Vec<String> = String::from_utf8_lossy(&run.stderr)
        .lines()
        .map(|l| l.trim().to_string())
        .filter(|l| !l.is_empty() && l != "executing")
        .collect();
    assert!(run.status.success() && err.is_empty(), "rs274: {:?} {err:?}", run.status);
    let canon = std::fs::read_to_string(work.path().join("canon.txt")).expect("canonical output");
    let feeds = canon.lines().filter(|l| l.contains("STRAIGHT_FEED(")).count();
    let traverses = canon.lines().filter(|l| l.contains("STRAIGHT_TRAVERSE(")).count();
    assert_eq!(feeds + traverses, motions.len(), "rs274 moved {feeds} feeds and {traverses} traverses");
}

#[test]
fn a_bad_case_is_refused_and_nothing_is_written() {
    let dir = TempDir::new("five-bad");
    let text = std::fs::read_to_string(example()).expect("the example");
    let mut v: serde_json::Value = serde_json::from_str(&text).expect("json");
    v["floor"]["knots_u"][0] = serde_json::json!(0.5);
    let bad = dir.write("bad.json", serde_json::to_string(&v).expect("json"));
    let before = dir.listing();
    let out = swarf(dir.path(), &["five", bad.to_str().expect("utf-8"), "-o", "out.cl", "--gcode", "out.ngc"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.json") && err.contains("floor.knots_u"), "{err}");
    assert!(!err.contains("panicked"));
    assert_eq!(dir.listing(), before, "nothing written");
    // every side a wall: no way in
    let mut walls = v.clone();
    walls["floor"] = serde_json::from_str::<serde_json::Value>(&text).expect("json")["floor"].clone();
    walls["boundaries"] = serde_json::json!({"u0": "wall", "u1": "wall", "v0": "wall", "v1": "wall"});
    let closed = dir.write("closed.json", serde_json::to_string(&walls).expect("json"));
    let before = dir.listing();
    let out = swarf(dir.path(), &["five", closed.to_str().expect("utf-8"), "-o", "out.cl"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("closed.json") && err.contains("open side"), "{err}");
    assert_eq!(dir.listing(), before, "nothing written");
    // cases that read but cannot be pocketed: a tool wider than the pocket, a holder that would
    // reach into the walls, a stepover that would make an endless path
    for (what, change, needle) in [
        ("wide", serde_json::json!({"tool": {"type": "ball", "diameter": 100.0}}), "cannot stand clear"),
        (
            "stubby",
            serde_json::json!({"tool": {"type": "ball", "diameter": 5.0, "flute_length": 5.0, "length": 5.0, "holder_diameter": 20, "holder_length": 30}}),
            "stick-out",
        ),
        ("fine", serde_json::json!({"stepover": 0.001}), "stepover"),
    ] {
        let mut c: serde_json::Value = serde_json::from_str(&text).expect("json");
        for (k, val) in change.as_object().expect("an object") {
            c[k] = val.clone();
        }
        let f = dir.write(&format!("{what}.json"), serde_json::to_string(&c).expect("json"));
        let before = dir.listing();
        let out = swarf(dir.path(), &["five", f.to_str().expect("utf-8"), "-o", "out.cl", "--gcode", "out.ngc"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{what}: {err}");
        assert!(err.contains(&format!("{what}.json")) && err.contains(needle), "{what}: {err}");
        assert_eq!(dir.listing(), before, "{what}: nothing written");
    }
    // an option out of range is the option's fault
    let out = swarf(dir.path(), &["five", example().to_str().expect("utf-8"), "-o", "out.cl", "--back", "0.01"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--back"));
    assert!(!dir.path().join("out.cl").exists());
    // the output may not replace the input
    let out = swarf(dir.path(), &["five", closed.to_str().expect("utf-8"), "-o", closed.to_str().expect("utf-8")]);
    assert_eq!(out.status.code(), Some(2));
    assert!(std::fs::read_to_string(&closed).expect("still there").contains("fiveaxis_pocket"));
}
