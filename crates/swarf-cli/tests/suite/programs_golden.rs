//! The programs swarf writes do not change unless we mean them to: every example case with every
//! strategy, the main options, drawings, STL and 3D jobs and `swarf plan`'s programs, through
//! the built `swarf` command, must give G-code whose SHA-256 is the one recorded in
//! `tests/golden/programs.sha256`.
//!
//! The record was made before the restructuring of issue 20 and is only re-made on purpose,
//! when a change fixes a defect or improves the programs (the commit says which):
//!
//! ```sh
//! SWARF_BLESS=1 cargo test -p swarf-cli --test suite programs_golden::
//! ```
//!
//! On a mismatch the programs are kept under `target/golden-actual/` (the failure names the
//! folder) so that they can be compared with those of the commit that made the record. The
//! spiral strategy runs with its default (its floor chosen by simulating candidates) on every
//! case, and on four of them also with a pinned floor and a pinned ζ.

use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common;
use common::TempDir;

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn record_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden/programs.sha256")
}

const CASES: [&str; 7] =
    ["boss_with_clamp", "l_pocket", "narrow_slot", "pocket_islands", "round_pocket", "simple_part", "square_pocket"];

/// Cases whose spiral is also recorded with a floor and a ζ given (the default's search
/// chooses without them).
const PINNED_SPIRAL: [&str; 4] = ["l_pocket", "narrow_slot", "pocket_islands", "simple_part"];

/// One `swarf rough` run: its name in the record and its arguments after the input.
struct Rough {
    name: String,
    input: PathBuf,
    args: Vec<String>,
}

fn rough(name: impl Into<String>, input: PathBuf, args: &[&str]) -> Rough {
    Rough { name: name.into(), input, args: args.iter().map(|s| s.to_string()).collect() }
}

fn case(n: &str) -> PathBuf {
    repo_root().join(format!("examples/cases/{n}.json"))
}

/// Every run of the suite.
fn runs() -> Vec<Rough> {
    let mut v = Vec::new();
    for n in CASES {
        for s in ["adaptive", "offset", "zigzag", "medial"] {
            v.push(rough(format!("{n}.{s}"), case(n), &["--strategy", s]));
        }
        v.push(rough(format!("{n}.spiral"), case(n), &["--strategy", "spiral"]));
        if PINNED_SPIRAL.contains(&n) {
            v.push(rough(format!("{n}.spiral-floor"), case(n), &["--strategy", "spiral", "--spiral-floor", "0.35"]));
            v.push(rough(format!("{n}.spiral-zeta"), case(n), &["--strategy", "spiral", "--zeta", "0.05"]));
        }
    }
    let pi = case("pocket_islands");
    for (name, args) in [
        ("conventional", &["--conventional"][..]),
        ("feed-boost", &["--feed-boost", "1.3"]),
        ("feed-links", &["--feed-links"]),
        ("finish", &["--stock-to-leave", "0.3", "--finish"]),
        ("grbl", &["--post", "grbl"]),
        ("stepdown", &["--stepdown", "2.5", "--overshoot", "10"]),
        ("tool", &["--tool-diameter", "8", "--engagement", "45", "--feed", "1500", "--spindle", "12000"]),
        ("ramp", &["--ramp-angle", "2", "--clearance", "3", "--arc-tolerance", "0.005"]),
        ("offset-outside-in", &["--strategy", "offset", "--order", "outside-in", "--conventional"]),
        ("offset-finish", &["--strategy", "offset", "--stock-to-leave", "0.2", "--finish", "--stepover", "0.3"]),
        ("zigzag-angle", &["--strategy", "zigzag", "--angle", "30", "--post", "grbl"]),
        ("medial-full-circles", &["--strategy", "medial", "--full-circles"]),
        ("medial-boost", &["--strategy", "medial", "--feed-boost", "1.5", "--conventional"]),
        ("spiral-start", &["--strategy", "spiral", "--zeta", "0.04", "--spiral-start", "20,30"]),
        ("res", &["--res", "0.08"]),
    ] {
        v.push(rough(format!("pocket_islands.{name}"), pi.clone(), args));
    }
    v.push(rough(
        "round_pocket.spiral-conventional",
        case("round_pocket"),
        &["--strategy", "spiral", "--conventional"],
    ));
    v.push(rough("l_pocket.adaptive-stepover", case("l_pocket"), &["--stepover", "0.3", "--stepdown", "2"]));
    let demo = repo_root().join("crates/swarf/examples_data/demo_pocket.json");
    v.push(rough("demo_pocket.adaptive", demo, &[]));
    // 3D
    let bowl = repo_root().join("examples/3d/bowl_cavity.json");
    v.push(rough("bowl_cavity.adaptive", bowl.clone(), &[]));
    v.push(rough("bowl_cavity.offset", bowl.clone(), &["--strategy", "offset", "--tool-diameter", "8"]));
    let stl = repo_root().join("examples/parts/bowl_cavity.stl");
    v.push(rough("bowl_cavity_stl.adaptive", stl.clone(), &[]));
    v.push(rough(
        "bowl_cavity_stl.placed",
        stl,
        &["--strategy", "zigzag", "--stock-margin", "4", "--part-rotate", "0,0,30", "--part-translate", "1,2,3"],
    ));
    // drawings
    let data = repo_root().join("crates/swarf-import/tests/data");
    v.push(rough("wrench_dxf.adaptive", data.join("dxf/trimesh_wrench.dxf"), &[]));
    v.push(rough("wrench_dxf.offset", data.join("dxf/trimesh_wrench.dxf"), &["--strategy", "offset", "--depth", "2"]));
    v.push(rough("cycloidal_dxf.zigzag", data.join("dxf/trimesh_125_cycloidal.dxf"), &["--strategy", "zigzag"]));
    v
}

fn swarf() -> Command {
    Command::new(env!("CARGO_BIN_EXE_swarf"))
}

/// Runs `r` into `dir`; its program's bytes.
fn run_rough(r: &Rough, dir: &Path) -> Vec<u8> {
    let out = dir.join(format!("{}.ngc", r.name));
    let o = swarf()
        .arg("rough")
        .arg(&r.input)
        .args(&r.args)
        .args(["--no-simulate", "-q", "-o"])
        .arg(&out)
        .output()
        .unwrap_or_else(|e| panic!("{}: cannot run swarf: {e}", r.name));
    assert!(o.status.success(), "{}: swarf rough failed: {}", r.name, String::from_utf8_lossy(&o.stderr));
    std::fs::read(&out).unwrap_or_else(|e| panic!("{}: {e}", out.display()))
}

/// `swarf plan` on the 3D example with the paper's tool table, without the replay: each program's
/// bytes by name.
fn run_plan(dir: &Path, extra: &[&str], tag: &str) -> Vec<(String, Vec<u8>)> {
    let out = dir.join(format!("plan-{tag}"));
    let o = swarf()
        .arg("plan")
        .arg(repo_root().join("examples/3d/bowl_cavity.json"))
        .arg("--tools")
        .arg(repo_root().join("examples/tools/table1.json"))
        .args(["--no-simulate", "-q", "--output-dir"])
        .arg(&out)
        .args(extra)
        .output()
        .expect("run swarf plan");
    assert!(o.status.success(), "swarf plan failed: {}", String::from_utf8_lossy(&o.stderr));
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(&out)
        .expect("plan folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "ngc"))
        .map(|p| {
            let name = format!("plan-{tag}/{}", p.file_stem().and_then(|s| s.to_str()).expect("name"));
            (name, std::fs::read(&p).expect("program"))
        })
        .collect();
    v.sort();
    assert!(!v.is_empty(), "swarf plan wrote no program");
    // --no-simulate: the programs are the same, the report says they were not replayed
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("plan.json")).expect("plan.json")).expect("json");
    let programs = report["best"]["programs"].as_array().expect("programs");
    assert_eq!(programs.len(), v.len());
    assert!(programs.iter().all(|p| p["simulated"] == false && p["rest_picture"].is_null()), "{programs:?}");
    v
}

fn sha256(bytes: &[u8]) -> String {
    Sha256::digest(bytes).iter().map(|b| format!("{b:02x}")).collect()
}

/// The record: name → (hash, bytes).
fn read_record() -> BTreeMap<String, (String, usize)> {
    let text = std::fs::read_to_string(record_path()).unwrap_or_default();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split_whitespace().collect();
            assert_eq!(f.len(), 3, "bad line in the record: {l:?}");
            (f[2].to_string(), (f[0].to_string(), f[1].parse().expect("byte count")))
        })
        .collect()
}

fn write_record(all: &BTreeMap<String, (String, usize)>) {
    let mut text = String::from(
        "# SHA-256, size in bytes and name of every program of tests/suite/programs_golden.rs\n\
         # remake with: SWARF_BLESS=1 cargo test -p swarf-cli --test suite programs_golden::\n",
    );
    for (name, (h, n)) in all {
        text.push_str(&format!("{h} {n} {name}\n"));
    }
    std::fs::create_dir_all(record_path().parent().expect("folder")).expect("golden folder");
    std::fs::write(record_path(), text).expect("write the record");
}

/// Runs every job on all cores and checks (or, with `SWARF_BLESS`, records) their programs.
fn check() {
    let dir = TempDir::new("golden");
    let jobs = runs();
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    let next = std::sync::atomic::AtomicUsize::new(0);
    let got = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|sc| {
        for _ in 0..threads {
            sc.spawn(|| {
                loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(r) = jobs.get(i) else { break };
                    let bytes = run_rough(r, dir.path());
                    got.lock().expect("lock").push((r.name.clone(), bytes));
                }
            });
        }
    });
    let mut got = got.into_inner().expect("lock");
    got.extend(run_plan(dir.path(), &[], "trim"));
    got.extend(run_plan(dir.path(), &["--decomposition", "regions", "--post", "grbl", "--clearance", "3"], "regions"));
    let mut record = read_record();
    if std::env::var_os("SWARF_BLESS").is_some() {
        for (name, bytes) in &got {
            record.insert(name.clone(), (sha256(bytes), bytes.len()));
        }
        write_record(&record);
        eprintln!("recorded {} programs in {}", got.len(), record_path().display());
        return;
    }
    let actual = repo_root().join("target/golden-actual");
    let mut bad = Vec::new();
    for (name, bytes) in &got {
        let h = sha256(bytes);
        let problem = match record.get(name) {
            Some((want, n)) if *want == h && *n == bytes.len() => None,
            Some((_, n)) => Some(format!("{name}: {} bytes, recorded {n} bytes with another hash", bytes.len())),
            None => Some(format!("{name}: not in the record")),
        };
        if let Some(problem) = problem {
            bad.push(problem);
            let p = actual.join(format!("{name}.ngc"));
            std::fs::create_dir_all(p.parent().expect("folder")).expect("actual folder");
            std::fs::write(&p, bytes).expect("write the actual program");
        }
    }
    assert!(
        bad.is_empty(),
        "{} of {} programs differ from the record (written to {}):\n{}",
        bad.len(),
        got.len(),
        actual.display(),
        bad.join("\n")
    );
}

#[test]
fn programs_are_unchanged() {
    check();
}

/// The record covers every job of the suite, and a change of one byte is a mismatch.
#[test]
fn the_record_is_complete_and_strict() {
    let record = read_record();
    for r in runs().iter() {
        assert!(record.contains_key(&r.name), "{} is not in the record", r.name);
    }
    assert!(record.keys().any(|k| k.starts_with("plan-trim/")), "no plan programs in the record");
    assert_ne!(sha256(b"G0 X1\n"), sha256(b"G0 X2\n"));
}
