//! Golden-file tests of the posts: a small hand-built toolpath (rapids, a helical entry, lines,
//! clockwise and counter-clockwise arcs, a plunge, notes) written with every post and compared
//! byte for byte with `tests/golden/<post>.ngc`.
//!
//! The version in the first comment line (`(swarf 0.1.0 - post …)`) is replaced by `VERSION` in
//! the golden files, so that a version bump does not need a re-bless.
//!
//! To (re)write the golden files after an intended change of the output:
//!
//! ```text
//! SWARF_BLESS=1 cargo test -p swarf --test suite post_golden::
//! ```
//!
//! and review the diff before committing it. When LinuxCNC's `rs274` is on PATH, both golden
//! programs are also run through the interpreter (`SWARF_REQUIRE_RS274=1` makes its absence a
//! failure).

use std::path::{Path, PathBuf};
use swarf::geom::{DVec2, DVec3};
use swarf::model::Tool;
use swarf::post::{self, Header, Post};
use swarf::toolpath::{MoveKind, Toolpath};

const POSTS: [(Post, &str); 2] = [(Post::LinuxCnc, "linuxcnc"), (Post::Grbl, "grbl")];

/// The fixed toolpath: a D6 tool (T3), a helical entry of two half turns around (10, 10),
/// straight cuts with awkward numbers (rounding, negative zero), a CW and a CCW arc, a link, a
/// retract, a rapid, a plunge and notes.
fn fixture() -> Toolpath {
    let mut tool = Tool::flat(6.0);
    tool.number = 3;
    let mut tp = Toolpath::new(tool, DVec3::new(12.0, 10.0, 5.0), 5.0);
    tp.note("level 1 of 1 - z -2");
    tp.note("helix entry at 10 10");
    // feed down to just above the stock, then the helix: two half turns from z 0.5 to -2
    tp.line(MoveKind::Descend, DVec3::new(12.0, 10.0, 0.5), 300.0);
    tp.arc(MoveKind::Entry, DVec3::new(8.0, 10.0, -0.75), DVec2::new(10.0, 10.0), true, 300.0);
    tp.arc(MoveKind::Entry, DVec3::new(12.0, 10.0, -2.0), DVec2::new(10.0, 10.0), true, 300.0);
    tp.note("clearing");
    // rounding: 12.34567 -> 12.346, -0.0001 -> 0 (never -0), 20.0004 -> 20
    tp.line(MoveKind::Cut, DVec3::new(12.34567, -0.0001, -2.0), 1000.0);
    tp.line(MoveKind::Cut, DVec3::new(20.0004, -0.0001, -2.0), 1000.0);
    // clockwise quarter turn around (20, 5): from (20, 0) to (25, 5)
    tp.arc(MoveKind::Cut, DVec3::new(25.0, 5.0, -2.0), DVec2::new(20.0, 5.0), false, 1000.0);
    // counter-clockwise half turn around (25, 7.5): from (25, 5) to (25, 10), same feed (no F)
    tp.arc(MoveKind::Cut, DVec3::new(25.0, 10.0, -2.0), DVec2::new(25.0, 7.5), true, 1000.0);
    // a link at depth with a feed of 1234.56 (F rounds to one decimal)
    tp.line(MoveKind::Link, DVec3::new(-3.5, 10.0, -2.0), 1234.56);
    tp.line(MoveKind::Cut, DVec3::new(-3.5, 15.25, -2.0), 1000.0);
    tp.note("retract");
    tp.rapid(DVec3::new(-3.5, 15.25, 5.0));
    tp.rapid(DVec3::new(30.125, -7.0625, 5.0));
    // a plunge (straight down into material) and a cut after it
    tp.line(MoveKind::Plunge, DVec3::new(30.125, -7.0625, -2.0), 200.0);
    tp.line(MoveKind::Cut, DVec3::new(40.0, -7.0625, -2.0), 1000.0);
    tp.rapid(DVec3::new(40.0, -7.0625, 5.0));
    tp
}

fn header() -> Header {
    Header {
        lines: vec!["job golden (hand-built) - strategy none".into(), "parentheses (here) are removed".into()],
        spindle_rpm: 12000.0,
    }
}

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests").join("golden")
}

/// The program with the version in the first line replaced by `VERSION`.
fn normalised(post: Post, name: &str) -> String {
    let text = post::write(&fixture(), post, &header()).expect("writable");
    let first = format!("(swarf {} - post {name})\n", env!("CARGO_PKG_VERSION"));
    assert!(text.starts_with(&first), "the program does not start with {first:?}:\n{text}");
    format!("(swarf VERSION - post {name})\n{}", &text[first.len()..])
}

fn bless() -> bool {
    std::env::var("SWARF_BLESS").is_ok_and(|v| v == "1")
}

#[test]
fn posts_match_the_golden_files() {
    let dir = golden_dir();
    let mut diffs = Vec::new();
    for (post, name) in POSTS {
        let got = normalised(post, name);
        let path = dir.join(format!("{name}.ngc"));
        if bless() {
            std::fs::create_dir_all(&dir).expect("create tests/golden");
            std::fs::write(&path, &got).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            eprintln!("blessed {}", path.display());
            continue;
        }
        let want = std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("{}: {e} (run with SWARF_BLESS=1 to create the golden files)", path.display()));
        if got != want {
            let (g, w): (Vec<_>, Vec<_>) = (got.lines().collect(), want.lines().collect());
            let at = g.iter().zip(&w).position(|(a, b)| a != b).unwrap_or(g.len().min(w.len()));
            diffs.push(format!(
                "{}: first difference at line {}: got {:?}, golden {:?} ({} vs {} lines)",
                path.display(),
                at + 1,
                g.get(at),
                w.get(at),
                g.len(),
                w.len()
            ));
        }
    }
    assert!(
        diffs.is_empty(),
        "the posts' output changed (review, then re-bless with SWARF_BLESS=1):\n{}",
        diffs.join("\n")
    );
}

#[test]
fn same_toolpath_same_bytes() {
    for (post, _) in POSTS {
        assert_eq!(
            post::write(&fixture(), post, &header()).expect("writable"),
            post::write(&fixture(), post, &header()).expect("writable")
        );
    }
}

/// Splits a block into words (`G1`, `X12.5`, …), comments removed.
fn words(line: &str) -> Vec<String> {
    let mut code = String::new();
    let mut depth = 0;
    for c in line.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            _ if depth == 0 => code.push(c),
            _ => {}
        }
    }
    code.split_whitespace().map(str::to_string).collect()
}

/// The code lines (not pure comments) of a program.
fn code_lines(text: &str) -> Vec<&str> {
    text.lines().filter(|l| !words(l).is_empty()).collect()
}

/// Checks one number as written after an axis letter: at most `dec` decimals, no trailing
/// zeros, no bare `.`, no negative zero, parses.
fn check_number(word: &str, dec: usize, line: &str) {
    let v = &word[1..];
    assert!(v.parse::<f64>().is_ok(), "{word:?} in {line:?} is not a number");
    assert!(!(v.starts_with('-') && v.parse::<f64>() == Ok(0.0)), "negative zero {word:?} in {line:?}");
    if let Some((_, frac)) = v.split_once('.') {
        assert!(!frac.is_empty(), "{word:?} in {line:?} ends with '.'");
        assert!(frac.len() <= dec, "{word:?} in {line:?} has more than {dec} decimals");
        assert!(!frac.ends_with('0'), "{word:?} in {line:?} has a trailing zero");
    }
}

#[test]
fn program_properties() {
    for (post, name) in POSTS {
        let text = post::write(&fixture(), post, &header()).expect("writable");
        let lines: Vec<&str> = text.lines().collect();
        assert!(text.ends_with('\n'), "{name}: no final newline");
        assert!(text.is_ascii(), "{name}: not ASCII");
        // comment lines first, then the safe block
        let first_code = lines.iter().position(|l| !words(l).is_empty()).expect("code");
        assert!(lines[..first_code].iter().all(|l| l.starts_with('(') && l.ends_with(')')));
        assert!(
            lines[..first_code]
                .iter()
                .any(|l| l.split_whitespace().collect::<Vec<_>>().join(" ") == "(parentheses here are removed)"),
            "{name}: header line missing"
        );
        match post {
            Post::LinuxCnc => {
                assert_eq!(lines[first_code], "G21 G90 G17 G94 G40 G49 G80", "{name}: safe block");
                assert_eq!(lines[first_code + 1], "G64 P0.01", "{name}: path blending");
                assert!(lines.contains(&"T3 M6") && lines.contains(&"G43 H3"), "{name}: tool change");
            }
            Post::Grbl => {
                assert_eq!(lines[first_code], "G21 G90 G17 G94", "{name}: safe block");
                assert!(
                    text.contains("expects tool T3, a D6 flat end mill"),
                    "{name}: the tool is named for the operator"
                );
            }
        }
        assert!(lines.contains(&"S12000 M3"), "{name}: spindle on");
        // the end: spindle off, M2, nothing after
        assert_eq!(lines[lines.len() - 2..], ["M5", "M2"], "{name}: program end");
        // first motion: up to the clearance, then over the start
        let motions: Vec<&str> = code_lines(&text)
            .into_iter()
            .filter(|l| words(l).first().is_some_and(|w| ["G0", "G1", "G2", "G3"].contains(&w.as_str())))
            .collect();
        assert_eq!(motions[0], "G0 Z5", "{name}: first move is straight up to the clearance");
        assert_eq!(motions[1], "G0 X12 Y10", "{name}: then over the start point");
        // every move of the toolpath is one motion line (the fixture has no degenerate move)
        assert_eq!(motions.len(), 2 + fixture().moves.len(), "{name}: motion lines");
        let arcs: Vec<&&str> = motions.iter().filter(|l| l.starts_with("G2 ") || l.starts_with("G3 ")).collect();
        assert_eq!(arcs.len(), 4, "{name}: arcs");
        assert!(arcs.iter().all(|l| l.contains(" I") && l.contains(" J") && l.contains(" X") && l.contains(" Y")));
        assert_eq!(arcs.iter().filter(|l| l.starts_with("G2 ")).count(), 1, "{name}: one clockwise arc");
        assert!(arcs[0].contains(" Z-0.75"), "{name}: the helix carries Z: {}", arcs[0]);
        assert!(text.contains("(plunge)\nG1 Z-2 F200\n"), "{name}: the plunge is announced and written");
        for n in ["(level 1 of 1 - z -2)", "(helix entry at 10 10)", "(clearing)", "(retract)"] {
            assert!(lines.contains(&n), "{name}: note {n} missing");
        }
        assert!(!text.contains("-0 ") && !text.contains("-0\n"), "{name}: negative zero");
        let mut g64 = false;
        for l in code_lines(&text) {
            for w in words(l) {
                let letter = w.chars().next().expect("word");
                match letter {
                    'X' | 'Y' | 'Z' => check_number(&w, 3, l),
                    'I' | 'J' => check_number(&w, 4, l),
                    'F' => check_number(&w, 1, l),
                    _ => {}
                }
                if post == Post::Grbl {
                    assert!(w != "M6" && w != "M06", "grbl: M6 in {l:?}");
                    assert!(!w.starts_with("G43"), "grbl: G43 in {l:?}");
                    assert!(!w.starts_with("G64"), "grbl: G64 in {l:?}");
                    assert!(!w.starts_with('T'), "grbl: T word in {l:?}");
                }
                g64 |= w == "G64";
            }
        }
        assert_eq!(g64, post == Post::LinuxCnc, "{name}: G64 only for LinuxCNC");
        // modal feed: written when it changes only
        let feeds: Vec<String> =
            code_lines(&text).iter().flat_map(|l| words(l)).filter(|w| w.starts_with('F')).collect();
        assert_eq!(feeds, ["F300", "F1000", "F1234.6", "F1000", "F200", "F1000"], "{name}: feed words");
    }
}

// ---- LinuxCNC's interpreter on the golden programs (when installed) -----------------------

fn find_on_path(exe: &str) -> Option<PathBuf> {
    std::env::var_os("PATH")?.to_str()?.split(':').map(|d| Path::new(d).join(exe)).find(|p| p.is_file())
}

#[test]
fn rs274_accepts_both_programs() {
    let Some(rs274) = find_on_path("rs274") else {
        if std::env::var_os("SWARF_REQUIRE_RS274").is_some() {
            panic!(
                "rs274 (LinuxCNC's G-code interpreter, Debian package linuxcnc-uspace) is not on PATH, and SWARF_REQUIRE_RS274 is set"
            );
        }
        eprintln!("note: rs274 not on PATH; skipping the interpreter check of the golden programs");
        return;
    };
    let work = std::env::temp_dir().join(format!("swarf-post-golden-{}", std::process::id()));
    std::fs::create_dir_all(&work).expect("temp dir");
    let table: String = (1..=9).map(|i| format!("T{i} P{i} Z0 D0\n")).collect();
    std::fs::write(work.join("tool.tbl"), table).expect("tool table");
    for (post, name) in POSTS {
        let ngc = work.join(format!("{name}.ngc"));
        std::fs::write(&ngc, post::write(&fixture(), post, &header()).expect("writable")).expect("write");
        // (its own home: rs274 truncates and maps `$HOME/.tool.mmap`, which another rs274 run
        // at the same time would truncate under it)
        let out = std::process::Command::new(&rs274)
            .current_dir(&work)
            .env("HOME", &work)
            .args(["-g", "-t", "tool.tbl"])
            .arg(&ngc)
            .arg(work.join(format!("{name}.canon")))
            .stdin(std::process::Stdio::null())
            .output()
            .expect("run rs274");
        let err: Vec<String> = String::from_utf8_lossy(&out.stderr)
            .lines()
            .filter(|l| !l.trim().is_empty() && l.trim() != "executing")
            .map(str::to_string)
            .collect();
        assert!(out.status.success() && err.is_empty(), "rs274 rejected the {name} program: {:?} {err:?}", out.status);
        let canon = std::fs::read_to_string(work.join(format!("{name}.canon"))).expect("canon");
        let count = |c: &str| canon.lines().filter(|l| l.contains(&format!(" {c}("))).count();
        assert_eq!(count("ARC_FEED"), 4, "{name}: arcs as read by rs274");
        assert_eq!(count("STRAIGHT_FEED"), 7, "{name}: feeds as read by rs274");
        assert_eq!(count("STRAIGHT_TRAVERSE"), 5, "{name}: traverses as read by rs274");
    }
    let _ = std::fs::remove_dir_all(&work);
}
