//! End to end: every case in `examples/cases`, every strategy and both posts, through the
//! built `swarf rough`, then through LinuxCNC's own G-code interpreter (`rs274`, Debian package
//! `linuxcnc-uspace`).
//!
//! For each run: `swarf` exits 0; the interpreter reads the whole program without an error; the
//! feed length the interpreter moves (its `STRAIGHT_FEED` and `ARC_FEED` canonical commands,
//! helices included) equals the report's `cut_length_mm` within 0.5 %; the rapid length after
//! the initial positioning equals `rapid_length_mm` (same tolerance, plus 0.01 mm); the move
//! counts agree; and the report says 0 gouges, 0 rapid collisions and `rest_fraction` < 0.005
//! (the runs through the GRBL post, the same toolpaths as through LinuxCNC's, are not simulated,
//! and their reports say so).
//!
//! Without `rs274` on PATH the tests print a note and pass, unless `SWARF_REQUIRE_RS274` is set
//! (CI sets it), in which case they fail.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

// ---- small helpers ---------------------------------------------------------------------------

use crate::common;
use common::TempDir;

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn cases() -> Vec<PathBuf> {
    let dir = repo_root().join("examples/cases");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("dir entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    v.sort();
    assert!(v.len() >= 7, "expected the 7 example cases in {}, found {}", dir.display(), v.len());
    v
}

/// `rs274` on PATH; `None` (after a note) when it is missing and not required.
fn rs274() -> Option<PathBuf> {
    let found = std::env::var_os("PATH")
        .and_then(|path| std::env::split_paths(&path).map(|d| d.join("rs274")).find(|p| p.is_file()));
    if found.is_none() {
        if std::env::var_os("SWARF_REQUIRE_RS274").is_some() {
            panic!(
                "SWARF_REQUIRE_RS274 is set but rs274 (LinuxCNC's standalone G-code interpreter) is not on PATH; \
                 install it with `apt-get install --no-install-recommends linuxcnc-uspace`"
            );
        }
        eprintln!(
            "note: rs274 is not on PATH: skipping the LinuxCNC interpreter checks (set SWARF_REQUIRE_RS274=1 to make this a failure)"
        );
    }
    found
}

// ---- the interpreter -------------------------------------------------------------------------

/// What the interpreter did with a program.
#[derive(Debug, Default)]
struct Canon {
    traverses: usize,
    feeds: usize,
    arcs: usize,
    /// Length of STRAIGHT_TRAVERSE moves, mm, with the length of each one.
    traverse_lengths: Vec<f64>,
    /// Length of STRAIGHT_FEED and ARC_FEED moves, mm.
    feed_length: f64,
    /// The last position.
    end: [f64; 3],
}

/// Runs `rs274 -g -t tool.tbl IN.ngc OUT.txt` in a fresh folder with a zero-length tool table and
/// no var file, the folder its home too; returns the canonical text, or the interpreter's
/// complaint. (rs274 truncates and maps `$HOME/.tool.mmap` as shared memory: two of them run at
/// once with one home kill each other with SIGBUS, about one run in five with eight at once.)
fn interpret(rs274: &Path, ngc: &Path) -> Result<String, String> {
    let work = TempDir::new("rs274");
    let table: String = (1..=99).map(|i| format!("T{i} P{i} Z0 D0 ;zero-length tool\n")).collect();
    std::fs::write(work.path().join("tool.tbl"), table).map_err(|e| e.to_string())?;
    let ngc = std::fs::canonicalize(ngc).map_err(|e| format!("{}: {e}", ngc.display()))?;
    let out = Command::new(rs274)
        .current_dir(work.path())
        .env("HOME", work.path())
        .args(["-g", "-t", "tool.tbl"])
        .arg(&ngc)
        .arg("canon.txt")
        .stdin(Stdio::null())
        .output()
        .map_err(|e| format!("cannot run {}: {e}", rs274.display()))?;
    // stderr always starts with "executing"; anything else is an error message
    let err: Vec<&str> = std::str::from_utf8(&out.stderr)
        .unwrap_or("<stderr not UTF-8>")
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && *l != "executing")
        .collect();
    if !out.status.success() || !err.is_empty() {
        return Err(format!("rs274 on {}: {} - {}", ngc.display(), out.status, err.join(" | ")));
    }
    std::fs::read_to_string(work.path().join("canon.txt")).map_err(|e| format!("canonical output: {e}"))
}

/// Parses the arguments of a canonical command, `NAME(a, b, c)`.
fn args_of<'a>(line: &'a str, name: &str) -> Option<Vec<&'a str>> {
    let at = line.find(&format!(" {name}("))?;
    let rest = &line[at + name.len() + 2..];
    let end = rest.rfind(')')?;
    Some(rest[..end].split(',').map(str::trim).collect())
}

fn nums(args: &[&str], n: usize, line: &str) -> Vec<f64> {
    assert!(args.len() >= n, "too few arguments in {line:?}");
    args[..n].iter().map(|a| a.parse::<f64>().unwrap_or_else(|_| panic!("{a:?} is not a number in {line:?}"))).collect()
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Length of an XY-plane `ARC_FEED` from `start`: `rotation` < 0 is clockwise, > 0
/// counter-clockwise, |rotation| - 1 extra full turns; the z change makes it a helix.
fn arc_length(start: [f64; 3], end: [f64; 3], centre: [f64; 2], rotation: i64) -> f64 {
    use std::f64::consts::TAU;
    assert!(rotation != 0, "ARC_FEED with rotation 0");
    let a0 = (start[1] - centre[1]).atan2(start[0] - centre[0]);
    let a1 = (end[1] - centre[1]).atan2(end[0] - centre[0]);
    let mut sweep = a1 - a0;
    let extra = (rotation.unsigned_abs() - 1) as f64 * TAU;
    if rotation > 0 {
        while sweep <= 0.0 {
            sweep += TAU;
        }
        sweep += extra;
    } else {
        while sweep >= 0.0 {
            sweep -= TAU;
        }
        sweep -= extra;
    }
    let r0 = (start[0] - centre[0]).hypot(start[1] - centre[1]);
    let r1 = (end[0] - centre[0]).hypot(end[1] - centre[1]);
    // the interpreter blends the radius from start to end; the mean is exact for a linear blend
    // to first order and the difference is below 0.03 mm anyway (its own arc check)
    let xy = 0.5 * (r0 + r1) * sweep.abs();
    xy.hypot(end[2] - start[2])
}

/// Follows the canonical commands from the interpreter's initial position (0, 0, 0).
fn parse_canon(text: &str) -> Result<Canon, String> {
    let mut c = Canon::default();
    let mut pos = [0.0; 3];
    let mut plane_xy = true;
    for line in text.lines() {
        if let Some(a) = args_of(line, "USE_LENGTH_UNITS") {
            if a[0] != "CANON_UNITS_MM" {
                return Err(format!("the program is not metric: {line:?}"));
            }
        } else if let Some(a) = args_of(line, "SELECT_PLANE") {
            plane_xy = a[0] == "CANON_PLANE_XY";
        } else if let Some(a) = args_of(line, "STRAIGHT_TRAVERSE") {
            let v = nums(&a, 3, line);
            let to = [v[0], v[1], v[2]];
            c.traverses += 1;
            c.traverse_lengths.push(dist(pos, to));
            pos = to;
        } else if let Some(a) = args_of(line, "STRAIGHT_FEED") {
            let v = nums(&a, 3, line);
            let to = [v[0], v[1], v[2]];
            c.feeds += 1;
            c.feed_length += dist(pos, to);
            pos = to;
        } else if let Some(a) = args_of(line, "ARC_FEED") {
            if !plane_xy {
                return Err(format!("arc outside the XY plane: {line:?}"));
            }
            let v = nums(&a, 4, line);
            let rotation: i64 =
                a.get(4).and_then(|r| r.parse().ok()).ok_or_else(|| format!("bad rotation in {line:?}"))?;
            let z = nums(&a[5..], 1, line)[0];
            let to = [v[0], v[1], z];
            c.arcs += 1;
            c.feed_length += arc_length(pos, to, [v[2], v[3]], rotation);
            pos = to;
        } else if ["STRAIGHT_PROBE", "NURBS_FEED", "RIGID_TAP", "SPLINE_FEED"]
            .iter()
            .any(|k| line.contains(&format!(" {k}(")))
        {
            return Err(format!("unexpected motion: {line:?}"));
        }
    }
    c.end = pos;
    Ok(c)
}

#[test]
fn arc_length_of_canonical_arcs() {
    use std::f64::consts::PI;
    // half turn CCW, radius 10, no z change
    assert!((arc_length([10.0, 0.0, 0.0], [-10.0, 0.0, 0.0], [0.0, 0.0], 1) - 10.0 * PI).abs() < 1e-12);
    // quarter turn: CCW is the short way, CW the long way
    assert!((arc_length([10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0], 1) - 5.0 * PI).abs() < 1e-12);
    assert!((arc_length([10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0], -1) - 15.0 * PI).abs() < 1e-12);
    // full helical circle (start = end in XY) down 1 mm, then P2: two turns
    let full = (20.0 * PI).hypot(1.0);
    assert!((arc_length([10.0, 0.0, 0.0], [10.0, 0.0, -1.0], [0.0, 0.0], -1) - full).abs() < 1e-12);
    assert!((arc_length([10.0, 0.0, 0.0], [10.0, 0.0, -1.0], [0.0, 0.0], -2) - (40.0 * PI).hypot(1.0)).abs() < 1e-12);
    // a parsed program: the helix of the LinuxCNC docs' shape
    let canon = "   1 N..... USE_LENGTH_UNITS(CANON_UNITS_MM)\n\
                 2 N..... STRAIGHT_TRAVERSE(10.0000, 0.0000, 5.0000, 0.0000, 0.0000, 0.0000)\n\
                 3 N..... STRAIGHT_FEED(10.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)\n\
                 4 N..... ARC_FEED(-10.0000, 0.0000, 0.0000, 0.0000, 1, -1.0000, 0.0000, 0.0000, 0.0000)\n";
    let c = parse_canon(canon).expect("parse");
    assert_eq!((c.traverses, c.feeds, c.arcs), (1, 1, 1));
    assert!((c.feed_length - (5.0 + (10.0 * PI).hypot(1.0))).abs() < 1e-9, "{}", c.feed_length);
    assert!((c.traverse_lengths[0] - 125f64.sqrt()).abs() < 1e-9);
    assert_eq!(c.end, [-10.0, 0.0, -1.0]);
    assert!(parse_canon("   1 N..... USE_LENGTH_UNITS(CANON_UNITS_INCHES)\n").is_err());
}

// ---- the report ------------------------------------------------------------------------------

fn field(r: &serde_json::Value, path: &str) -> f64 {
    let v = r.pointer(&format!("/{}", path.replace('.', "/"))).unwrap_or_else(|| panic!("the report has no {path}"));
    v.as_f64().unwrap_or_else(|| panic!("report {path} is not a number: {v}"))
}

// ---- the runs --------------------------------------------------------------------------------

/// Runs one case with one strategy and post; returns the failures found (empty = fine).
/// The files of a failed run are kept for inspection.
fn check_case(rs274: &Path, case: &Path, strategy: &str, post: &str, extra: &[&str]) -> Vec<String> {
    let name = case.file_stem().and_then(|s| s.to_str()).unwrap_or("case").to_string();
    let dir = TempDir::new(&format!("{name}-{strategy}-{post}"));
    let mut bad = check_case_in(&dir, rs274, case, strategy, post, extra);
    if !bad.is_empty() {
        bad.push(format!("  (files kept in {})", dir.path().display()));
        std::mem::forget(dir);
    }
    bad
}

fn check_case_in(dir: &TempDir, rs274: &Path, case: &Path, strategy: &str, post: &str, extra: &[&str]) -> Vec<String> {
    let name = case.file_stem().and_then(|s| s.to_str()).unwrap_or("case").to_string();
    let what = format!("{name} --strategy {strategy} --post {post} {}", extra.join(" "));
    let ngc = dir.path().join(format!("{name}.ngc"));
    let json = dir.path().join(format!("{name}.json"));
    let out = Command::new(env!("CARGO_BIN_EXE_swarf"))
        .arg("rough")
        .arg(case)
        .arg("-o")
        .arg(&ngc)
        .arg("--report")
        .arg(&json)
        .args(["--strategy", strategy, "--post", post, "--quiet"])
        .args(extra)
        .stdin(Stdio::null())
        .output()
        .expect("run swarf");
    let stderr = String::from_utf8_lossy(&out.stderr);
    if !out.status.success() {
        return vec![format!("{what}: swarf failed ({}): {}", out.status, stderr.trim())];
    }
    let mut bad = Vec::new();
    if stderr.contains("panicked") {
        bad.push(format!("{what}: swarf panicked: {stderr}"));
    }
    let report: serde_json::Value = match std::fs::read(&json)
        .map_err(|e| e.to_string())
        .and_then(|b| serde_json::from_slice(&b).map_err(|e| e.to_string()))
    {
        Ok(r) => r,
        Err(e) => return vec![format!("{what}: report {}: {e}", json.display())],
    };
    let canon = match interpret(rs274, &ngc).and_then(|t| parse_canon(&t)) {
        Ok(c) => c,
        Err(e) => {
            bad.push(format!("{what}: {e}"));
            return bad;
        }
    };
    // lengths
    let cut = field(&report, "cut_length_mm");
    if !(cut > 0.0 && (canon.feed_length - cut).abs() <= 0.005 * cut) {
        bad.push(format!(
            "{what}: the interpreter feeds {:.3} mm, the report says cut_length_mm {cut:.3} ({:+.3} %)",
            canon.feed_length,
            100.0 * (canon.feed_length - cut) / cut
        ));
    }
    eprintln!(
        "{what}: feed {:.3} mm (report {cut:.3}), {} traverses, {} feeds, {} arcs",
        canon.feed_length, canon.traverses, canon.feeds, canon.arcs
    );
    if canon.traverses == 0 {
        bad.push(format!("{what}: no rapid move in the program"));
    }
    // the first two traverses position the tool (up to the clearance from the interpreter's
    // (0, 0, 0), then over the start); the toolpath's rapids come after them
    let rapid = field(&report, "rapid_length_mm");
    let interp_rapid: f64 = canon.traverse_lengths.iter().skip(2).sum();
    if (interp_rapid - rapid).abs() > 0.005 * rapid + 0.01 {
        bad.push(format!("{what}: the interpreter traverses {interp_rapid:.3} mm after positioning, the report says rapid_length_mm {rapid:.3}"));
    }
    // move counts: every move of the program is one canonical motion
    let (rapids, lines, arcs) = (
        field(&report, "moves.rapids") as usize,
        field(&report, "moves.lines") as usize,
        field(&report, "moves.arcs") as usize,
    );
    if (canon.traverses, canon.feeds, canon.arcs) != (rapids + 2, lines, arcs) {
        bad.push(format!(
            "{what}: the interpreter saw {} traverses, {} feeds, {} arcs; the report says {rapids} rapids (+2 to position), {lines} lines, {arcs} arcs",
            canon.traverses, canon.feeds, canon.arcs
        ));
    }
    // what the simulation found (a run with `--no-simulate` says it was not simulated)
    let simulate = !extra.contains(&"--no-simulate");
    if report.get("simulated").and_then(|v| v.as_bool()) != Some(simulate) {
        bad.push(format!("{what}: the report says simulated = {:?}", report.get("simulated")));
    }
    if simulate {
        for (key, max) in [("gouges", 0.0), ("rapid_collisions", 0.0)] {
            let v = field(&report, key);
            if v > max {
                bad.push(format!("{what}: report {key} = {v}"));
            }
        }
        let rest = field(&report, "rest_fraction");
        if rest.is_nan() || rest >= 0.005 {
            bad.push(format!("{what}: report rest_fraction = {rest} (>= 0.005)"));
        }
    }
    // the program ends with the tool up, above the first level
    let first_level = field(&report, "levels.0");
    if canon.end[2].is_nan() || canon.end[2] <= first_level {
        bad.push(format!(
            "{what}: the program ends at z {} (not above the first level, z {first_level})",
            canon.end[2]
        ));
    }
    if report.get("post").and_then(|p| p.as_str()) != Some(post)
        || report.get("strategy").and_then(|p| p.as_str()) != Some(strategy)
    {
        bad.push(format!(
            "{what}: the report names post {:?}, strategy {:?}",
            report.get("post"),
            report.get("strategy")
        ));
    }
    bad
}

fn run_all_with(strategy: &str, post: &str, extra: &[&str]) {
    let Some(rs274) = rs274() else { return };
    let t = std::time::Instant::now();
    let mut bad = Vec::new();
    for case in cases() {
        bad.extend(check_case(&rs274, &case, strategy, post, extra));
    }
    eprintln!("{strategy}/{post}: {} cases in {:.1} s", cases().len(), t.elapsed().as_secs_f64());
    assert!(bad.is_empty(), "{} problem(s):\n{}", bad.len(), bad.join("\n"));
}

// Each strategy on every case through both posts. The program is the same toolpath whichever
// the post, so the simulator proves it once, on the LinuxCNC run; the GRBL run is written
// without a simulation and checked by the interpreter alone.

#[test]
fn adaptive_linuxcnc() {
    run_all_with("adaptive", "linuxcnc", &[]);
}

#[test]
fn adaptive_grbl() {
    run_all_with("adaptive", "grbl", &["--no-simulate"]);
}

#[test]
fn offset_linuxcnc() {
    run_all_with("offset", "linuxcnc", &[]);
}

#[test]
fn offset_grbl() {
    run_all_with("offset", "grbl", &["--no-simulate"]);
}

#[test]
fn zigzag_linuxcnc() {
    run_all_with("zigzag", "linuxcnc", &[]);
}

#[test]
fn zigzag_grbl() {
    run_all_with("zigzag", "grbl", &["--no-simulate"]);
}

// The medial and spiral programs of the example cases are proven on the simulator by the
// library's tests (tests/suite/medial.rs at 0.1 mm cells, for the medial circles leave cusps of
// up to 2 % of the tool on the walls by design, which the default cell counts as rest in
// narrow_slot's 4 mm channel; tests/suite/spiral.rs for the spirals): the same programs are
// written here without a simulation and checked by the interpreter.

#[test]
fn medial_linuxcnc() {
    run_all_with("medial", "linuxcnc", &["--no-simulate"]);
}

#[test]
fn medial_grbl() {
    run_all_with("medial", "grbl", &["--no-simulate"]);
}

/// The oscillator spiral (paper 4) on the three cases it is meant for, and on a pocket with an
/// island (a spiral over the island-free core, adaptive passes for the rest).
#[test]
fn spiral_linuxcnc_and_grbl() {
    let Some(rs274) = rs274() else { return };
    let root = repo_root().join("examples/cases");
    let mut bad = Vec::new();
    for (case, post) in [
        ("round_pocket.json", "linuxcnc"),
        ("square_pocket.json", "grbl"),
        ("l_pocket.json", "linuxcnc"),
        ("boss_with_clamp.json", "grbl"),
    ] {
        bad.extend(check_case(&rs274, &root.join(case), "spiral", post, &["--no-simulate"]));
    }
    assert!(bad.is_empty(), "{bad:#?}");
}

/// A few option combinations the cases do not have: several levels (entries at every level),
/// the finishing contour with stock to leave, outside-in conventional offsets, an angled zigzag
/// given by engagement.
#[test]
fn option_variants() {
    let Some(rs274) = rs274() else { return };
    let root = repo_root().join("examples/cases");
    let runs: [(&str, &str, &str, &[&str]); 4] = [
        ("square_pocket.json", "offset", "linuxcnc", &["--stepdown", "1", "--finish", "--stock-to-leave", "0.3"]),
        ("l_pocket.json", "offset", "grbl", &["--order", "outside-in", "--conventional"]),
        ("narrow_slot.json", "zigzag", "linuxcnc", &["--engagement", "60", "--angle", "30", "--stepdown", "1.5"]),
        ("boss_with_clamp.json", "zigzag", "grbl", &["--angle", "-45", "--finish"]),
    ];
    let mut bad = Vec::new();
    for (case, strategy, post, extra) in runs {
        bad.extend(check_case(&rs274, &root.join(case), strategy, post, extra));
    }
    assert!(bad.is_empty(), "{} problem(s):\n{}", bad.len(), bad.join("\n"));
}

/// The harness itself: an interpreter error comes back as an error, with rs274's message.
#[test]
fn interpreter_errors_are_caught() {
    let Some(rs274) = rs274() else { return };
    let dir = TempDir::new("bad-gcode");
    let ngc = dir.path().join("bad.ngc");
    std::fs::write(&ngc, "G21 G90\nG1 X10\nM2\n").expect("write");
    let err = interpret(&rs274, &ngc).expect_err("G1 without a feed must be rejected");
    assert!(err.contains("zero feed rate"), "{err}");
    // an I/J arc whose end is not on its circle
    std::fs::write(&ngc, "G21 G90 G17\nG0 X10 Y0\nG2 X0 Y-12 I-10 J0 F100\nM2\n").expect("write");
    let err = interpret(&rs274, &ngc).expect_err("bad arc must be rejected");
    assert!(err.contains("Radius to end of arc differs"), "{err}");
    // and a good one parses, with the expected length
    std::fs::write(&ngc, "G21 G90 G17\nG0 X10 Y0 Z1\nG1 Z0 F100\nG2 X0 Y-10 I-10 J0 Z-1\nM2\n").expect("write");
    let c = parse_canon(&interpret(&rs274, &ngc).expect("good program")).expect("parse");
    let want = 1.0 + (5.0 * std::f64::consts::PI).hypot(1.0);
    assert!((c.feed_length - want).abs() < 1e-3, "{} vs {want}", c.feed_length);
    assert_eq!((c.traverses, c.feeds, c.arcs), (1, 1, 1));
}

/// A 60 × 60 × 10 mm block with a 30 × 30 mm pocket 6 mm deep, as an ASCII STL case in `dir`.
fn block_case(dir: &TempDir) -> PathBuf {
    let mut f: Vec<[[f64; 3]; 3]> = Vec::new();
    let mut quad = |a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]| {
        f.push([a, b, c]);
        f.push([a, c, d]);
    };
    let (h, fl, o, i) = (10.0, 4.0, 30.0, 15.0);
    for (x0, y0, x1, y1) in [(-o, -o, o, -i), (-o, i, o, o), (-o, -i, -i, i), (i, -i, o, i)] {
        quad([x0, y0, h], [x1, y0, h], [x1, y1, h], [x0, y1, h]);
    }
    quad([-i, -i, fl], [i, -i, fl], [i, i, fl], [-i, i, fl]);
    quad([-i, -i, h], [-i, -i, fl], [i, -i, fl], [i, -i, h]);
    quad([i, -i, h], [i, -i, fl], [i, i, fl], [i, i, h]);
    quad([i, i, h], [i, i, fl], [-i, i, fl], [-i, i, h]);
    quad([-i, i, h], [-i, i, fl], [-i, -i, fl], [-i, -i, h]);
    quad([-o, -o, 0.0], [-o, o, 0.0], [o, o, 0.0], [o, -o, 0.0]);
    quad([-o, -o, 0.0], [o, -o, 0.0], [o, -o, h], [-o, -o, h]);
    quad([o, -o, 0.0], [o, o, 0.0], [o, o, h], [o, -o, h]);
    quad([o, o, 0.0], [-o, o, 0.0], [-o, o, h], [o, o, h]);
    quad([-o, o, 0.0], [-o, -o, 0.0], [-o, -o, h], [-o, o, h]);
    let mut stl = String::from("solid block\n");
    for t in &f {
        stl += "facet normal 0 0 0\nouter loop\n";
        for v in t {
            stl += &format!("vertex {} {} {}\n", v[0], v[1], v[2]);
        }
        stl += "endloop\nendfacet\n";
    }
    stl += "endsolid block\n";
    dir.write("block.stl", stl);
    dir.write(
        "block.json",
        r#"{"tool": {"diameter": 6}, "stock_box": [-30, -30, 0, 30, 30, 10], "part_stl": "block.stl", "stepdown": 2.5}"#,
    )
}

/// A 3D case (the block with a pocket), z-level roughing.
#[test]
fn zlevel_mesh_linuxcnc() {
    let Some(rs274) = rs274() else { return };
    let dir = TempDir::new("zlevel-mesh");
    let case = block_case(&dir);
    let mut bad = Vec::new();
    for strategy in ["adaptive", "offset"] {
        bad.extend(check_case(&rs274, &case, strategy, "linuxcnc", &["--res", "0.1"]));
    }
    assert!(bad.is_empty(), "{} problem(s):\n{}", bad.len(), bad.join("\n"));
}

/// `swarf plan` on the block with three tools: every program of the chosen sequence goes
/// through the interpreter, with its tool change, and its feed length and rapid count match
/// the plan's report.
#[test]
fn plan_programs_linuxcnc() {
    let Some(rs274) = rs274() else { return };
    let dir = TempDir::new("plan");
    let case = block_case(&dir);
    let tools = dir.write(
        "tools.json",
        r#"{"machine": {"cost_per_hour": 50, "rapid_feed_mm_min": 30000, "tool_change_min": 0.5},
            "tools": [
              {"id": "T1", "type": "insert", "teeth": 3, "diameter": 20, "width_of_cut": 10, "depth_of_cut": 3,
               "feed_per_tooth": 0.2, "cutting_speed_m_min": 80, "price": 72, "life_min": 60},
              {"id": "T2", "type": "carbide", "teeth": 4, "diameter": 10, "width_of_cut": 5, "depth_of_cut": 2,
               "feed_per_tooth": 0.05, "cutting_speed_m_min": 60, "price": 120, "life_min": 45},
              {"id": "T3", "type": "carbide", "teeth": 4, "diameter": 4, "width_of_cut": 2, "depth_of_cut": 1,
               "feed_per_tooth": 0.02, "cutting_speed_m_min": 60, "price": 40, "life_min": 45}]}"#,
    );
    let out = dir.path().join("out");
    let report = common::plan_report(&case, &tools, &out);
    assert_eq!(report["candidates"], 4);
    let programs = report["best"]["programs"].as_array().expect("programs");
    assert!(!programs.is_empty());
    assert_eq!(programs.last().unwrap()["tool"], "T3", "every sequence ends with the smallest tool");
    let mut names = Vec::new();
    for p in programs {
        let name = p["file"].as_str().expect("file");
        names.push(name.to_string());
        let ngc = out.join(name);
        let text = std::fs::read_to_string(&ngc).expect("program");
        let number = p["number"].as_u64().expect("number");
        assert!(text.contains(&format!("T{number} M6")), "{name}: no tool change");
        let canon = interpret(&rs274, &ngc).and_then(|t| parse_canon(&t)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let want = p["cut_length_mm"].as_f64().expect("length");
        assert!((canon.feed_length - want).abs() <= 1e-3 * want + 0.05, "{name}: {} vs {want}", canon.feed_length);
    }
    let mut sorted = names.clone();
    sorted.sort();
    assert_eq!(sorted, names, "sorting by name gives the cutting order");
}
