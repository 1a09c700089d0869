//! The viewer from the command line: `swarf rough --html`, `swarf view` on another system's
//! program, their errors. (What the pages do in a browser is tested in `browser.rs`.)

use crate::common::{TempDir, swarf};
use std::path::{Path, PathBuf};

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(p)
}

/// The head (JSON) of a page swarf wrote.
fn head(html: &str) -> serde_json::Value {
    let start = html.find("id=\"swarf-head\">").expect("the page's head") + "id=\"swarf-head\">".len();
    let end = start + html[start..].find("</script>").expect("its end");
    serde_json::from_str(&html[start..end].replace("<\\/", "</")).expect("JSON")
}

fn figure<'a>(program: &'a serde_json::Value, label: &str) -> &'a str {
    program["figures"]
        .as_array()
        .expect("figures")
        .iter()
        .find(|f| f[0] == label)
        .and_then(|f| f[1].as_str())
        .unwrap_or_else(|| panic!("no figure {label:?} in {}", program["figures"]))
}

#[test]
fn rough_writes_one_self_contained_page_the_same_each_time() {
    let dir = TempDir::new("view-rough");
    let case = repo("examples/cases/round_pocket.json");
    let case = case.to_str().unwrap();
    for name in ["a", "b"] {
        let run = swarf(
            dir.path(),
            &[
                "rough",
                case,
                "-o",
                &format!("{name}.ngc"),
                "--report",
                &format!("{name}.json"),
                "--html",
                &format!("{name}.html"),
                "-q",
            ],
        );
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    }
    let html = std::fs::read_to_string(dir.path().join("a.html")).unwrap();
    assert_eq!(html, std::fs::read_to_string(dir.path().join("b.html")).unwrap(), "the same page twice");
    // everything inline: no script or style from elsewhere
    assert!(!html.contains("src=\"http") && !html.contains("<link"), "a page that reaches out");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("a.json")).unwrap()).unwrap();
    let h = head(&html);
    let p = &h["runs"][0]["programs"][0];
    assert_eq!(p["moves"], report["moves"]["total"], "every move of the program");
    assert_eq!(p["levels"].as_array().unwrap().len(), report["levels"].as_array().unwrap().len());
    assert_eq!(figure(p, "machining time"), format!("{:.2} min", report["time_min"].as_f64().unwrap()));
    // the simulator's removed volume, from none to all of it
    let removal = h["runs"][0]["removal"].as_array().unwrap();
    assert_eq!(removal[0], serde_json::json!([0, 0.0]));
    let last = removal.last().unwrap();
    assert_eq!(last[0], report["moves"]["total"]);
    let all = report["removed_volume_mm3"].as_f64().unwrap();
    assert!((last[1].as_f64().unwrap() - all).abs() < 0.005 * all, "{last} against the report's {all}");
    // the stock field and the G-code lines of the moves
    assert!(h["field"]["nx"].as_u64().unwrap() > 10);
    assert!(h["arrays"]["r0p0.line"].is_array() && h["arrays"]["r0p0.gcode"].is_array());
}

#[test]
fn view_replays_freecads_program_beside_swarfs() {
    let dir = TempDir::new("view-freecad");
    let case = repo("examples/cases/pocket_islands.json");
    let fc = repo("examples/programs/freecad_adaptive_pocket_islands.ngc");
    let run = swarf(dir.path(), &["rough", case.to_str().unwrap(), "-o", "swarf.ngc", "-q"]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let run = swarf(
        dir.path(),
        &["view", fc.to_str().unwrap(), "swarf.ngc", "--case", case.to_str().unwrap(), "-o", "cmp.html"],
    );
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let said = String::from_utf8_lossy(&run.stderr);
    assert!(said.contains("freecad_adaptive_pocket_islands.ngc: 12239 moves, 8.39 min"), "{said}");
    let h = head(&std::fs::read_to_string(dir.path().join("cmp.html")).unwrap());
    let runs = h["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 2, "a run per program");
    let (fc, ours) = (&runs[0]["programs"][0], &runs[1]["programs"][0]);
    // FreeCAD's machining time as an independent checker measures it; its wall gouges found
    assert_eq!(figure(fc, "machining time"), "8.39 min");
    // (the same 102 moves an independent checker finds, 0.023 mm deep at most: the rim into
    // the islands' sides, not the islands' height)
    let gouges = figure(fc, "gouges");
    assert!(gouges.starts_with("102 (deepest 0.0"), "{gouges}");
    assert!(ours["gouges"].as_array().unwrap().is_empty());
    assert_eq!(figure(fc, "units read"), "mm");
}

#[test]
fn view_refuses_a_bad_program_naming_the_line_and_writes_nothing() {
    let dir = TempDir::new("view-bad");
    let case = repo("examples/cases/round_pocket.json");
    dir.write("bad.ngc", "G21 G90\nG0 Z5\nG0 X0 Y0\nG18 G2 X1 Z-1 I0.5 K0 F100\nM2\n");
    let run = swarf(dir.path(), &["view", "bad.ngc", "--case", case.to_str().unwrap(), "-o", "out.html"]);
    assert_eq!(run.status.code(), Some(2));
    let said = String::from_utf8_lossy(&run.stderr);
    assert!(said.contains("bad.ngc") && said.contains("line 4"), "{said}");
    assert!(!dir.path().join("out.html").exists(), "no page written");
    // an output that is one of the programs is refused before any work
    dir.write("ok.ngc", "G21 G90\nG0 Z5\nG0 X0 Y0\nG1 Z-1 F100\nG1 X5 F500\nG0 Z5\nM2\n");
    let run = swarf(dir.path(), &["view", "ok.ngc", "--case", case.to_str().unwrap(), "-o", "ok.ngc"]);
    assert_eq!(run.status.code(), Some(2), "{}", String::from_utf8_lossy(&run.stderr));
    assert!(std::fs::read_to_string(dir.path().join("ok.ngc")).unwrap().starts_with("G21 G90"), "the program kept");
    // plan's page over its tool database: refused before the search, no folder made
    let tools = dir.write("tools.json", std::fs::read(repo("examples/tools/table1.json")).unwrap());
    let bowl = repo("examples/3d/bowl_cavity.json");
    let run = swarf(
        dir.path(),
        &["plan", bowl.to_str().unwrap(), "--tools", "tools.json", "--output-dir", "p", "--html", "tools.json"],
    );
    assert_eq!(run.status.code(), Some(2), "{}", String::from_utf8_lossy(&run.stderr));
    assert!(!dir.path().join("p").exists());
    assert_eq!(std::fs::read(&tools).unwrap(), std::fs::read(repo("examples/tools/table1.json")).unwrap());
}

#[test]
fn a_program_that_changes_tools_is_replayed_a_tool_after_the_other() {
    let dir = TempDir::new("view-tools");
    let case = repo("examples/cases/round_pocket.json");
    let case = case.to_str().unwrap();
    for (d, out) in [("10", "d10.ngc"), ("6", "d6.ngc")] {
        let run = swarf(dir.path(), &["rough", case, "--tool-diameter", d, "-o", out, "-q"]);
        assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    }
    // the Ø10 program, then the Ø6 one as tool 2 (one program end, at the end)
    let d10 = std::fs::read_to_string(dir.path().join("d10.ngc")).unwrap();
    let d6 = std::fs::read_to_string(dir.path().join("d6.ngc")).unwrap();
    let first: String = d10.lines().filter(|l| l.trim() != "M2").map(|l| format!("{l}\n")).collect();
    dir.write("both.ngc", first + &d6.replace("T1 M6", "T2 M6"));
    let run =
        swarf(dir.path(), &["view", "both.ngc", "--case", case, "--tool", "1=10", "--tool", "2=6", "-o", "p.html"]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let h = head(&std::fs::read_to_string(dir.path().join("p.html")).unwrap());
    let run0 = &h["runs"][0];
    let progs = run0["programs"].as_array().unwrap();
    assert_eq!(progs.len(), 2, "a piece per tool");
    assert_eq!((progs[0]["tool"]["d"].as_f64(), progs[1]["tool"]["d"].as_f64()), (Some(10.0), Some(6.0)));
    // the Ø6 replayed on what the Ø10 left: no gouge, and it removes less than the Ø10
    let n0 = progs[0]["moves"].as_u64().unwrap();
    let removal = run0["removal"].as_array().unwrap();
    let at = |k: u64| removal.iter().find(|r| r[0] == k).map(|r| r[1].as_f64().unwrap());
    let (after10, all) = (at(n0).expect("a reading where the Ø10 ends"), removal.last().unwrap()[1].as_f64().unwrap());
    assert!(after10 > 0.5 * all && all > after10, "{after10} then {all}");
    assert!(progs.iter().all(|p| p["gouges"].as_array().unwrap().is_empty()));
    // a size that is not N=MM
    let run = swarf(dir.path(), &["view", "both.ngc", "--case", case, "--tool", "2", "-o", "q.html"]);
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("--tool 2: expected N=MM"));
    assert!(!dir.path().join("q.html").exists());
}
