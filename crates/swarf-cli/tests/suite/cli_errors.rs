//! The `swarf` command on bad input: exit code 2 (1 for I/O trouble), one line on stderr that
//! names the file or the option, the place and the reason, never a panic, and no output file
//! left behind (nor an existing one destroyed). Plus the happy paths: `rough` with every output
//! and `demo`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

// ---- helpers ---------------------------------------------------------------------------------

use crate::common;
use common::{TempDir, swarf};

fn case(name: &str) -> PathBuf {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/cases").join(name);
    assert!(p.is_file(), "{} is missing", p.display());
    p
}

/// `swarf rough INPUT -o out.ngc --report out.json EXTRA…` in `dir` must fail with exit code
/// `code`, one line of error on stderr (`swarf: …`, the last) that contains every one of
/// `needles`, no panic, and no new file in `dir`. Before it only the line saying what was read
/// (`read …`) and warnings may come: an input that cannot be read gets the error alone.
/// Returns the message.
fn expect_failure(dir: &TempDir, input: &Path, extra: &[&str], code: i32, needles: &[&str]) -> String {
    let before = dir.listing();
    let mut args = vec!["rough", input.to_str().expect("utf-8 path"), "-o", "out.ngc", "--report", "out.json"];
    args.extend_from_slice(extra);
    let out = swarf(dir.path(), &args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    let what = format!("swarf {}", args.join(" "));
    assert!(!stderr.contains("panicked"), "{what}: panicked:\n{stderr}");
    assert_eq!(out.status.code(), Some(code), "{what}: exit status (stderr: {stderr:?})");
    let lines: Vec<&str> = stderr.lines().collect();
    let (msg, printed_before) = lines.split_last().unwrap_or_else(|| panic!("{what}: nothing on stderr"));
    for l in printed_before {
        assert!(
            l.starts_with("read ") || l.starts_with("swarf: warning: "),
            "{what}: expected one line of error on stderr, got {stderr:?}"
        );
    }
    assert!(printed_before.len() <= 3, "{what}: {stderr:?}");
    assert!(msg.starts_with("swarf: "), "{what}: {msg:?}");
    for n in needles {
        assert!(msg.to_lowercase().contains(&n.to_lowercase()), "{what}: the message does not contain {n:?}: {msg:?}");
    }
    assert!(out.stdout.is_empty(), "{what}: wrote to stdout: {:?}", String::from_utf8_lossy(&out.stdout));
    assert_eq!(dir.listing(), before, "{what}: files were left behind");
    msg.to_string()
}

/// 1-based line and column of the first `needle` in `text`.
fn line_col(text: &str, needle: &str) -> (usize, usize) {
    let at = text.find(needle).expect("needle");
    let line = text[..at].matches('\n').count() + 1;
    let col = at - text[..at].rfind('\n').map_or(0, |i| i + 1) + 1;
    (line, col)
}

// ---- DXF text --------------------------------------------------------------------------------

fn pair(code: i32, v: &str) -> String {
    format!("{code:>3}\n{v}\n")
}

fn dxf_line(a: [&str; 2], b: [&str; 2]) -> String {
    pair(0, "LINE")
        + &pair(8, "0")
        + &pair(10, a[0])
        + &pair(20, a[1])
        + &pair(30, "0")
        + &pair(11, b[0])
        + &pair(21, b[1])
        + &pair(31, "0")
}

/// A millimetre R2000 DXF with the given LINE entities.
fn dxf(lines: &[([&str; 2], [&str; 2])]) -> String {
    let mut s = pair(0, "SECTION")
        + &pair(2, "HEADER")
        + &pair(9, "$ACADVER")
        + &pair(1, "AC1015")
        + &pair(9, "$INSUNITS")
        + &pair(70, "4");
    s += &(pair(0, "ENDSEC") + &pair(0, "SECTION") + &pair(2, "ENTITIES"));
    for (a, b) in lines {
        s += &dxf_line(*a, *b);
    }
    s + &pair(0, "ENDSEC") + &pair(0, "EOF")
}

/// A 40 × 30 pocket drawn with four lines; `last` replaces the closing line.
fn pocket_dxf(last: ([&str; 2], [&str; 2])) -> String {
    dxf(&[(["0", "0"], ["40", "0"]), (["40", "0"], ["40", "30"]), (["40", "30"], ["0", "30"]), last])
}

// ---- empty and garbage input -----------------------------------------------------------------

#[test]
fn empty_files() {
    let d = TempDir::new("empty");
    for name in ["empty.json", "empty.dxf", "empty.svg"] {
        let p = d.write(name, "");
        expect_failure(&d, &p, &[], 2, &[name, "file", "empty"]);
    }
    // whitespace only is empty too
    let p = d.write("blank.json", " \n\t\n");
    expect_failure(&d, &p, &[], 2, &["blank.json", "empty"]);
}

#[test]
fn garbage_text() {
    let d = TempDir::new("garbage");
    let text = "hello, this is neither a case nor a drawing\n";
    let p = d.write("garbage.json", text);
    expect_failure(&d, &p, &[], 2, &["garbage.json", "line 1 column 1", "not valid JSON"]);
    let p = d.write("garbage.dxf", text);
    expect_failure(&d, &p, &[], 2, &["garbage.dxf", "line 1", "not a DXF file"]);
    let p = d.write("garbage.svg", text);
    expect_failure(&d, &p, &[], 2, &["garbage.svg", "line 1", "XML"]);
    let p = d.write("garbage.txt", text);
    expect_failure(&d, &p, &[], 2, &["garbage.txt", "neither a DXF nor an SVG"]);
    // binary junk
    let p = d.write("junk.dxf", [0u8, 159, 146, 150, 255, 0, 1, 2]);
    expect_failure(&d, &p, &[], 2, &["junk.dxf"]);
}

#[test]
fn truncated_case() {
    let d = TempDir::new("truncated");
    let full = std::fs::read_to_string(case("square_pocket.json")).expect("read case");
    let p = d.write("cut.json", &full[..full.len() / 2]);
    expect_failure(&d, &p, &[], 2, &["cut.json", "line", "column", "not valid JSON"]);
}

// ---- NaN -------------------------------------------------------------------------------------

#[test]
fn case_with_a_nan_coordinate() {
    let d = TempDir::new("nan-json");
    // JSON has no NaN literal: the parser must say where it stopped
    let text = "{\"units\": \"mm\",\n \"tool\": {\"diameter\": 6, \"type\": \"flat\"},\n \"stock\": [[0, 0], [40, 0],\n   [40, NaN], [0, 30]],\n \"floor\": -3}\n";
    let p = d.write("nan.json", text);
    let (line, col) = line_col(text, "NaN");
    let msg = expect_failure(&d, &p, &[], 2, &["nan.json", &format!("line {line} column"), "not valid JSON"]);
    // serde_json reports the column where it gave up: on the NaN token
    assert!(
        msg.contains(&format!("line {line} column {col}")) || msg.contains(&format!("line {line} column {}", col + 1)),
        "{msg}"
    );
    // a number that is too big for f64 is not finite either
    let text = "{\"tool\": {\"diameter\": 6},\n \"stock\": [[0, 0], [40, 0], [40, 1e999], [0, 30]],\n \"floor\": -3}\n";
    let p = d.write("huge.json", text);
    expect_failure(&d, &p, &[], 2, &["huge.json", "line 2"]);
}

#[test]
fn dxf_with_a_nan_coordinate() {
    let d = TempDir::new("nan-dxf");
    let text = pocket_dxf((["0", "30"], ["NaN", "0"]));
    let p = d.write("nan.dxf", &text);
    let (line, _) = line_col(&text, "NaN");
    expect_failure(&d, &p, &[], 2, &["nan.dxf", &format!("line {line}"), "NaN", "not a finite number"]);
}

#[test]
fn svg_with_a_nan_coordinate() {
    let d = TempDir::new("nan-svg");
    let text = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"40mm\" height=\"30mm\" viewBox=\"0 0 40 30\">\n<path id=\"p1\" d=\"M0 0 H40 V30 H NaN Z\"/>\n</svg>\n";
    let p = d.write("nan.svg", text);
    expect_failure(&d, &p, &[], 2, &["nan.svg", "line 2", "path"]);
}

// ---- drawings that are not pockets -----------------------------------------------------------

#[test]
fn dxf_open_contour_names_the_gap() {
    let d = TempDir::new("gap");
    // the closing line stops 2 mm short of the start
    let p = d.write("gap.dxf", pocket_dxf((["0", "30"], ["0", "2"])));
    expect_failure(&d, &p, &[], 2, &["gap.dxf", "near (0.000, 0.000)", "open contour", "gap", "2.000 mm"]);
    // within the chaining tolerance it is closed (the control: the same file reads when told so)
    let out =
        swarf(d.path(), &["rough", "gap.dxf", "-o", "gap.ngc", "--chain-tolerance", "2.5", "-q", "--no-simulate"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(d.path().join("gap.ngc").is_file());
}

#[test]
fn drawing_without_contours() {
    let d = TempDir::new("nothing");
    let p = d.write("none.dxf", dxf(&[]));
    expect_failure(&d, &p, &[], 2, &["none.dxf", "no closed contour"]);
}

// ---- options ---------------------------------------------------------------------------------

#[test]
fn tool_larger_than_the_pocket() {
    let d = TempDir::new("big-tool");
    let c = case("square_pocket.json");
    expect_failure(&d, &c, &["--tool-diameter", "200"], 2, &["tool", "200", "does not fit"]);
    // the 8.75 mm slot does not take a 10 mm tool
    expect_failure(&d, &case("narrow_slot.json"), &["--tool-diameter", "10"], 2, &["tool", "10", "does not fit"]);
}

#[test]
fn zero_and_negative_tools() {
    let d = TempDir::new("bad-tool");
    let c = case("square_pocket.json");
    expect_failure(&d, &c, &["--tool-diameter", "0"], 2, &["tool diameter", "0 mm", "positive"]);
    expect_failure(&d, &c, &["--tool-diameter", "-3"], 2, &["tool diameter", "-3 mm", "positive"]);
    expect_failure(&d, &c, &["--tool-diameter", "NaN"], 2, &["tool diameter", "positive"]);
    expect_failure(&d, &c, &["--tool-diameter", "inf"], 2, &["tool diameter", "positive"]);
    // the same on a drawing, where the tool comes only from the option
    let p = d.write("ok.dxf", pocket_dxf((["0", "30"], ["0", "0"])));
    expect_failure(&d, &p, &["--tool-diameter", "-3"], 2, &["tool diameter", "-3 mm", "positive"]);
}

#[test]
fn stepover_outside_the_range() {
    let d = TempDir::new("stepover");
    let c = case("square_pocket.json");
    for s in ["0", "1.5", "-0.2", "NaN"] {
        expect_failure(&d, &c, &["--stepover", s], 2, &["stepover", s, "outside (0, 1]"]);
    }
}

#[test]
fn engagement_outside_the_range() {
    let d = TempDir::new("engagement");
    let c = case("square_pocket.json");
    for t in ["0", "180.5", "-10", "360"] {
        expect_failure(&d, &c, &["--engagement", t], 2, &["engagement", t, "outside (0°, 180°]"]);
    }
}

#[test]
fn other_bad_numbers() {
    let d = TempDir::new("numbers");
    let c = case("square_pocket.json");
    expect_failure(&d, &c, &["--stepdown", "0"], 2, &["stepdown", "positive"]);
    expect_failure(&d, &c, &["--feed", "-100"], 2, &["feed", "positive"]);
    expect_failure(&d, &c, &["--ramp-angle", "90"], 2, &["--ramp-angle", "90"]);
    expect_failure(&d, &c, &["--res", "0"], 2, &["--res", "positive"]);
    // a cell so small that the grid's cell count overflows: refused by its size, not a panic
    // (a debug build's overflow) nor a count wrapped round to a small one (a release build's)
    expect_failure(&d, &c, &["--res", "1e-300"], 2, &["--res", "too large"]);
    expect_failure(&d, &c, &["--res", "1e-9", "--sim", "sdf"], 2, &["--res", "too large"]);
    expect_failure(&d, &c, &["--strategy", "spiral", "--spiral-floor", "0"], 2, &["--spiral-floor", "(0, 1]"]);
    expect_failure(&d, &c, &["--strategy", "spiral", "--zeta", "2"], 2, &["--zeta", "(0, 1]"]);
    // `--clearance -1` is taken by clap as an unknown flag (the option does not allow negative
    // numbers); `--clearance=-1` reaches swarf's own check
    expect_failure(&d, &c, &["--clearance=-1"], 2, &["--clearance", "positive"]);
    expect_failure(&d, &c, &["--stock-to-leave", "-0.5"], 2, &["--stock-to-leave", "positive"]);
    expect_failure(&d, &c, &["--angle", "NaN"], 2, &["--angle", "number"]);
    expect_failure(&d, &c, &["--feed-boost", "0.5"], 2, &["--feed-boost", "[1, 3]"]);
    expect_failure(&d, &c, &["--max-feed", "300"], 2, &["--max-feed", "no lower than the feed"]);
    expect_failure(&d, &c, &["--overshoot", "-5"], 2, &["--overshoot", "[0°, 90°]"]);
}

/// A spindle speed that is not a positive number must be refused: today `--spindle=-5`,
/// `--spindle=NaN` and `"spindle_rpm": 0` in a case all give `S0 M3`, a program that feeds with
/// the spindle stopped.
#[test]
fn bad_spindle_speed_is_rejected() {
    let d = TempDir::new("spindle");
    let c = case("square_pocket.json");
    for v in ["--spindle=-5", "--spindle=0", "--spindle=NaN"] {
        expect_failure(&d, &c, &[v, "--no-simulate"], 2, &["spindle"]);
    }
    let text = std::fs::read_to_string(&c).expect("case").replacen("\"floor\"", "\"spindle_rpm\": 0,\n \"floor\"", 1);
    assert!(text.contains("spindle_rpm"));
    let p = d.write("s0.json", text);
    expect_failure(&d, &p, &["--no-simulate"], 2, &["s0.json", "spindle_rpm"]);
}

/// Errors found by the argument parser (clap): exit 2, the option and the value on the first
/// line, nothing written. (clap adds a list of possible values and a pointer to `--help` on the
/// following lines, so these are not one-line messages.)
fn expect_usage_error(dir: &TempDir, args: &[&str], needles: &[&str]) {
    let before = dir.listing();
    let out = swarf(dir.path(), args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{args:?}: panicked:\n{stderr}");
    assert_eq!(out.status.code(), Some(2), "{args:?}: exit status (stderr: {stderr:?})");
    let first = stderr.lines().next().unwrap_or("");
    for n in needles {
        assert!(first.contains(n), "{args:?}: the first line does not contain {n:?}: {stderr:?}");
    }
    assert_eq!(dir.listing(), before, "{args:?}: files were left behind");
}

#[test]
fn unknown_names_and_malformed_options() {
    let d = TempDir::new("usage");
    let c = case("square_pocket.json");
    let c = c.to_str().expect("utf-8");
    expect_usage_error(&d, &["rough", c, "-o", "out.ngc", "--strategy", "trochoidal"], &["'trochoidal'", "--strategy"]);
    expect_usage_error(&d, &["rough", c, "-o", "out.ngc", "--post", "fanuc"], &["'fanuc'", "--post"]);
    expect_usage_error(&d, &["rough", c, "-o", "out.ngc", "--tool-diameter", "six"], &["'six'", "--tool-diameter"]);
    expect_usage_error(
        &d,
        &["rough", c, "-o", "out.ngc", "--stepover", "0.2", "--engagement", "60"],
        &["--engagement", "--stepover"],
    );
    expect_usage_error(&d, &["rough"], &["required"]);
    expect_usage_error(&d, &["polish", c], &["'polish'"]);
}

// ---- missing files and unwritable outputs ----------------------------------------------------

#[test]
fn missing_input_file() {
    let d = TempDir::new("missing");
    // a missing input is bad input (exit 2), whatever its kind: one line naming the file
    for (name, code) in [("nowhere.json", 2), ("nowhere.dxf", 2), ("nowhere.svg", 2), ("nowhere", 2)] {
        let p = d.path().join(name);
        expect_failure(&d, &p, &[], code, &[name, "No such file"]);
    }
}

/// An existing file at the `-o` path is left as it was when the run fails.
#[test]
fn failed_run_keeps_an_existing_output() {
    let d = TempDir::new("sentinel");
    let sentinel = "(sentinel: an earlier program the user wants to keep)\nM2\n";
    let c = case("square_pocket.json");
    for extra in [&["--tool-diameter", "200"][..], &["--stepover", "1.5"], &["--engagement", "0"]] {
        d.write("out.ngc", sentinel);
        d.write("out.json", "{\"sentinel\": true}\n");
        expect_failure(&d, &c, extra, 2, &[]);
        assert_eq!(
            std::fs::read_to_string(d.path().join("out.ngc")).expect("out.ngc"),
            sentinel,
            "{extra:?}: out.ngc changed"
        );
        assert_eq!(
            std::fs::read_to_string(d.path().join("out.json")).expect("out.json"),
            "{\"sentinel\": true}\n",
            "{extra:?}: out.json changed"
        );
    }
    let bad = d.write("bad.json", "{");
    d.write("out.ngc", sentinel);
    expect_failure(&d, &bad, &[], 2, &["bad.json"]);
    assert_eq!(std::fs::read_to_string(d.path().join("out.ngc")).expect("out.ngc"), sentinel);
}

/// When the G-code can be written but the report cannot, the run fails with exit 1 and the
/// G-code path keeps what it held before.
#[test]
fn failed_report_write_keeps_an_existing_output() {
    let d = TempDir::new("sentinel-io");
    let sentinel = "(sentinel)\nM2\n";
    d.write("out.ngc", sentinel);
    let c = case("square_pocket.json");
    let out = swarf(
        d.path(),
        &["rough", c.to_str().expect("utf-8"), "-o", "out.ngc", "--report", "no/such/dir/out.json", "-q"],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let now = std::fs::read_to_string(d.path().join("out.ngc"));
    assert_eq!(now.as_deref().ok(), Some(sentinel), "out.ngc was destroyed: {now:?}");
    // the message names the path the user gave, not a temporary file
    assert!(stderr.contains("no/such/dir/out.json") && !stderr.contains("swarf-tmp"), "{stderr}");
}

#[test]
fn unwritable_output_is_an_io_error() {
    let d = TempDir::new("unwritable");
    let c = case("square_pocket.json");
    let out =
        swarf(d.path(), &["rough", c.to_str().expect("utf-8"), "-o", "no/such/dir/out.ngc", "-q", "--no-simulate"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("no/such/dir/"), "{stderr}");
    assert!(d.listing().is_empty(), "{:?}", d.listing());
}

// ---- success -----------------------------------------------------------------------------------

const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];

fn check_outputs(ngc: &Path, report: &Path, svg: &Path, png: &Path) {
    let g = std::fs::read_to_string(ngc).unwrap_or_else(|e| panic!("{}: {e}", ngc.display()));
    assert!(g.starts_with("(swarf "), "{}: {:?}", ngc.display(), g.lines().next());
    assert!(g.lines().any(|l| l.starts_with("G1 ")) && g.trim_end().ends_with("M2"), "{}", ngc.display());
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(report).expect("report")).expect("report is JSON");
    assert!(r["cut_length_mm"].as_f64().is_some_and(|v| v > 0.0), "{r}");
    assert_eq!(r["gcode_lines"].as_u64(), Some(g.lines().count() as u64), "gcode_lines");
    assert_eq!(r["gouges"].as_u64(), Some(0));
    let s = std::fs::read_to_string(svg).expect("svg");
    assert!(s.contains("<svg") && s.trim_end().ends_with("</svg>"), "{}", svg.display());
    let p = std::fs::read(png).expect("png");
    assert!(p.len() > 1000 && p[..8] == PNG_SIGNATURE, "{}: not a PNG", png.display());
}

#[test]
fn rough_writes_every_output() {
    let d = TempDir::new("rough-ok");
    let c = case("square_pocket.json");
    let out =
        swarf(d.path(), &["rough", c.to_str().expect("utf-8"), "-o", "X.ngc", "--report", "X.json", "--plot", "X"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    // without a terminal: no progress bar, just what was read and the one-line summary
    assert_eq!(stderr.lines().count(), 2, "{stderr}");
    assert!(stderr.starts_with("read case 50.0 × 50.0 mm, 3.00 mm deep; tool Ø5 mm"), "{stderr}");
    assert!(stderr.contains("square_pocket.json") && stderr.contains("0 gouges"), "{stderr}");
    let p = |n: &str| d.path().join(n);
    check_outputs(&p("X.ngc"), &p("X.json"), &p("X.svg"), &p("X.png"));
    let want: BTreeSet<String> = ["X.ngc", "X.json", "X.svg", "X.png"].iter().map(|s| s.to_string()).collect();
    assert_eq!(d.listing(), want, "exactly the four files, no temporary left");
    // -q: nothing on stderr; an explicit .svg gives only the SVG
    let out = swarf(d.path(), &["rough", c.to_str().expect("utf-8"), "-o", "Y.ngc", "--plot", "Y.svg", "-q"]);
    assert!(out.status.success() && out.stderr.is_empty(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(p("Y.ngc").is_file() && p("Y.svg").is_file() && !p("Y.png").exists());
}

#[test]
fn rough_without_o_writes_next_to_the_cwd() {
    let d = TempDir::new("default-out");
    let c = case("l_pocket.json");
    let out = swarf(d.path(), &["rough", c.to_str().expect("utf-8"), "-q", "--no-simulate"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let want: BTreeSet<String> = ["l_pocket.ngc".to_string()].into();
    assert_eq!(d.listing(), want);
}

#[test]
fn demo_writes_every_output() {
    let d = TempDir::new("demo");
    let out = swarf(d.path(), &["demo", "out/demo", "-q"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let dir = d.path().join("out/demo");
    check_outputs(&dir.join("demo.ngc"), &dir.join("demo.report.json"), &dir.join("demo.svg"), &dir.join("demo.png"));
    // the case it ran is written too, and it reads back
    let case = dir.join("demo_pocket.json");
    assert!(case.is_file());
    let out = swarf(&dir, &["rough", "demo_pocket.json", "-o", "again.ngc", "-q", "--no-simulate"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

/// `swarf plan` refuses a 2D job and a bad tool database with one line naming the file and the
/// place, exit code 2, and no output folder.
#[test]
fn plan_errors() {
    let dir = TempDir::new("plan-errors");
    let tools = dir.write(
        "tools.json",
        r#"{"machine": {"cost_per_hour": 50, "rapid_feed_mm_min": 30000, "tool_change_min": 0.5},
            "tools": [{"id": "T1", "type": "insert", "teeth": 3, "diameter": -20, "width_of_cut": 10,
              "depth_of_cut": 3, "feed_per_tooth": 0.2, "cutting_speed_m_min": 80, "price": 72, "life_min": 60}]}"#,
    );
    let good = dir.write(
        "good.json",
        r#"{"machine": {"cost_per_hour": 50, "rapid_feed_mm_min": 30000, "tool_change_min": 0.5},
            "tools": [{"id": "T1", "type": "insert", "teeth": 3, "diameter": 20, "width_of_cut": 10,
              "depth_of_cut": 3, "feed_per_tooth": 0.2, "cutting_speed_m_min": 80, "price": 72, "life_min": 60}]}"#,
    );
    let part = dir.write(
        "part.stl",
        concat!(
            "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 10 0 0\nvertex 0 10 0\nendloop\nendfacet\n",
            "facet normal 0 -1 0\nouter loop\nvertex 0 0 0\nvertex 10 0 0\nvertex 0 0 5\nendloop\nendfacet\nendsolid t\n"
        ),
    );
    let before = dir.listing();
    let flat = case("square_pocket.json");
    let runs: [(&Path, &Path, &[&str]); 2] =
        [(&flat, &good, &["square_pocket.json", "3D job"]), (&part, &tools, &["tools.json", "tools[0].diameter"])];
    for (input, db, needles) in runs {
        let args =
            ["plan", input.to_str().expect("utf-8"), "--tools", db.to_str().expect("utf-8"), "--output-dir", "out"];
        let out = swarf(dir.path(), &args);
        let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        for n in needles {
            assert!(stderr.contains(n), "{stderr:?} lacks {n:?}");
        }
    }
    assert_eq!(dir.listing(), before, "files were left behind");
}

#[test]
fn a_drawing_is_read_as_meant_and_said_before_planning() {
    let d = TempDir::new("drawing-intent");
    // a bracket with a hole, and a construction stroke left open
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg" width="80mm" height="60mm" viewBox="0 0 80 60">
        <path d="M 5 5 L 75 5 L 75 25 L 30 25 L 30 55 L 5 55 Z"/><circle cx="17" cy="15" r="6"/>
        <path d="M 40 40 L 70 50"/></svg>"#;
    let input = d.path().join("bracket.svg");
    std::fs::write(&input, svg).expect("write");
    let m = expect_failure(&d, &input, &[], 2, &["bracket.svg", "open contour", "--skip-open"]);
    assert!(m.contains("path"), "{m}");
    let out = swarf(
        d.path(),
        &["rough", "bracket.svg", "-o", "b.ngc", "--skip-open", "--tool-diameter", "3", "--no-simulate"],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert!(lines[0].starts_with("read drawing 70.0 × 50.0 mm, 3.00 mm deep (millimetres: "), "{stderr}");
    assert!(lines[0].contains("2 contours; 1 open left out; 1 part, 1 pocket; tool Ø3 mm"), "{stderr}");
    assert!(lines[0].contains("holes and outside cut"), "{stderr}");
    assert!(lines[1].starts_with("swarf: warning: left out: open contour from (40.000, "), "{stderr}");
    // asked otherwise, said so
    let out = swarf(
        d.path(),
        &[
            "rough",
            "bracket.svg",
            "-o",
            "c.ngc",
            "--skip-open",
            "--tool-diameter",
            "3",
            "--no-simulate",
            "--cut",
            "pockets",
        ],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success() && stderr.contains("1 pocket, 1 island") && stderr.contains("pockets: as asked"),
        "{stderr}"
    );
    let bad = swarf(d.path(), &["rough", "bracket.svg", "--cut", "inside"]);
    assert_eq!(bad.status.code(), Some(2));
}
