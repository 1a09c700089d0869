//! The catalogue of hostile input: outputs that are inputs or not regular files, huge and tiny
//! numbers in every format and option, unbounded levels and work, tiny tools, non-UTF-8 text.
//! Every entry must end with exit 2 and one line on stderr naming the file or option, the place
//! and the limit; no panic, within a time and memory bound; nothing written; every input
//! unchanged.

use crate::common::TempDir;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Each run's limits: wall time, and address space (`ulimit -v`, KiB).
const TIME_LIMIT: Duration = Duration::from_secs(20);
const MEMORY_KIB: u64 = 4 << 20;

fn example(rel: &str) -> Vec<u8> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples").join(rel);
    std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// One hostile run: the files it starts from, the arguments (run in their folder), and what
/// the message must name.
struct Entry {
    name: &'static str,
    files: Vec<(&'static str, Vec<u8>)>,
    args: Vec<String>,
    needles: Vec<&'static str>,
}

fn entry(name: &'static str, files: Vec<(&'static str, Vec<u8>)>, args: &str, needles: &[&'static str]) -> Entry {
    Entry { name, files, args: args.split_whitespace().map(str::to_string).collect(), needles: needles.to_vec() }
}

/// Runs `swarf ARGS` in `dir` under the limits; exit code (None when killed) and stderr.
fn run_limited(dir: &Path, args: &[String]) -> (Option<i32>, String, Duration) {
    let t0 = Instant::now();
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {MEMORY_KIB}; exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_swarf"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run swarf");
    loop {
        if child.try_wait().expect("wait").is_some() || t0.elapsed() > TIME_LIMIT {
            break;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let timed_out = child.try_wait().expect("wait").is_none();
    if timed_out {
        let _ = child.kill();
    }
    let out = child.wait_with_output().expect("output");
    let code = if timed_out { None } else { out.status.code() };
    (code, String::from_utf8_lossy(&out.stderr).into_owned(), t0.elapsed())
}

/// Every file in `d` with its bytes.
fn snapshot(d: &TempDir) -> Vec<(String, Vec<u8>)> {
    d.listing()
        .into_iter()
        .map(|n| {
            let bytes = std::fs::read(d.path().join(&n)).unwrap_or_default();
            (n, bytes)
        })
        .collect()
}

fn check(e: &Entry) {
    let d = TempDir::new("hostile");
    for (name, bytes) in &e.files {
        d.write(name, bytes);
    }
    let before = snapshot(&d);
    let (code, stderr, took) = run_limited(d.path(), &e.args);
    let what = format!("{}: swarf {}", e.name, e.args.join(" "));
    assert!(!stderr.contains("panicked"), "{what}: panicked:\n{stderr}");
    assert!(code.is_some(), "{what}: still running after {TIME_LIMIT:?}");
    assert_eq!(code, Some(2), "{what}: exit status after {took:?} (stderr: {stderr:?})");
    let lines: Vec<&str> = stderr.lines().collect();
    let msg = lines.last().unwrap_or_else(|| panic!("{what}: nothing on stderr"));
    assert!(msg.starts_with("swarf: "), "{what}: {stderr:?}");
    for l in &lines[..lines.len() - 1] {
        assert!(
            l.starts_with("read ") || l.starts_with("swarf: warning: "),
            "{what}: more than one error line: {stderr:?}"
        );
    }
    for n in &e.needles {
        assert!(msg.contains(n), "{what}: the message does not name {n:?}: {msg}");
    }
    let after = snapshot(&d);
    let names = |v: &[(String, Vec<u8>)]| v.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>();
    assert_eq!(names(&after), names(&before), "{what}: files written or removed");
    for ((n, a), (_, b)) in before.iter().zip(&after) {
        assert!(a == b, "{what}: {n} changed");
    }
}

// ---- inputs ----------------------------------------------------------------------------------

/// A 2.5D case: a 40 × 30 pocket, `over` replacing keys of it (JSON text after the braces).
fn case_with(over: &str) -> Vec<u8> {
    let base = r#""units": "mm", "tool": {"diameter": 6, "type": "flat"}, "stock": [[0, 0], [40, 0], [40, 30], [0, 30]], "part": [], "floor": -3"#;
    let mut v: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(&format!("{{{base}}}")).expect("base case");
    let o: serde_json::Map<String, serde_json::Value> = serde_json::from_str(&format!("{{{over}}}")).expect("over");
    v.extend(o);
    serde_json::to_vec(&v).expect("json")
}

fn case_text(over: &str) -> Vec<u8> {
    // (for values serde_json's map would not keep as written, e.g. 1e400)
    let base = r#""units": "mm", "tool": {"diameter": 6, "type": "flat"}, "floor": -3"#;
    format!("{{{base}, {over}}}").into_bytes()
}

/// An ASCII STL box 20 × 10 × 5 with one vertex replaced by `corner` when given.
fn stl_box(corner: Option<&str>) -> Vec<u8> {
    let v = |x: f64, y: f64, z: f64| [x * 20.0, y * 10.0, z * 5.0];
    let faces = [
        [(0, 0, 0), (1, 1, 0), (1, 0, 0)],
        [(0, 0, 0), (0, 1, 0), (1, 1, 0)],
        [(0, 0, 1), (1, 0, 1), (1, 1, 1)],
        [(0, 0, 1), (1, 1, 1), (0, 1, 1)],
        [(0, 0, 0), (1, 0, 0), (1, 0, 1)],
        [(0, 0, 0), (1, 0, 1), (0, 0, 1)],
        [(0, 1, 0), (1, 1, 1), (1, 1, 0)],
        [(0, 1, 0), (0, 1, 1), (1, 1, 1)],
        [(0, 0, 0), (0, 0, 1), (0, 1, 1)],
        [(0, 0, 0), (0, 1, 1), (0, 1, 0)],
        [(1, 0, 0), (1, 1, 0), (1, 1, 1)],
        [(1, 0, 0), (1, 1, 1), (1, 0, 1)],
    ];
    let mut s = String::from("solid box\n");
    for (k, f) in faces.iter().enumerate() {
        s += "facet normal 0 0 0\nouter loop\n";
        for (j, &(x, y, z)) in f.iter().enumerate() {
            let p = v(x as f64, y as f64, z as f64);
            match corner {
                Some(c) if k == 2 && j == 1 => s += &format!("vertex {c}\n"),
                _ => s += &format!("vertex {} {} {}\n", p[0], p[1], p[2]),
            }
        }
        s += "endloop\nendfacet\n";
    }
    (s + "endsolid box\n").into_bytes()
}

/// A binary STL of one triangle with the given vertices.
fn stl_binary(tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend((tris.len() as u32).to_le_bytes());
    for t in tris {
        b.extend([0u8; 12]);
        for p in t {
            for c in p {
                b.extend(c.to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
    }
    b
}

/// A 3D case over `part.stl`, with `over` keys.
fn mesh_case(over: &str) -> Vec<u8> {
    let sep = if over.is_empty() { "" } else { ", " };
    format!(r#"{{"units": "mm", "tool": {{"diameter": 3}}, "stock_box": [-2, -2, 0, 22, 12, 6], "part_stl": "part.stl"{sep}{over}}}"#)
        .into_bytes()
}

fn pair(code: i32, v: &str) -> String {
    format!("{code:>3}\n{v}\n")
}

/// A millimetre DXF with `entities` (text of group pairs).
fn dxf(units: &str, entities: &str) -> Vec<u8> {
    let head = pair(0, "SECTION") + &pair(2, "HEADER") + &pair(9, "$INSUNITS") + &pair(70, units) + &pair(0, "ENDSEC");
    (head + &pair(0, "SECTION") + &pair(2, "ENTITIES") + entities + &pair(0, "ENDSEC") + &pair(0, "EOF")).into_bytes()
}

fn dxf_circle(x: &str, y: &str, r: &str) -> String {
    pair(0, "CIRCLE") + &pair(8, "0") + &pair(10, x) + &pair(20, y) + &pair(30, "0") + &pair(40, r)
}

/// A closed LWPOLYLINE through `pts` (x, y, bulge).
fn dxf_lwpoly(pts: &[(&str, &str, &str)]) -> String {
    let mut s = pair(0, "LWPOLYLINE") + &pair(8, "0") + &pair(90, &pts.len().to_string()) + &pair(70, "1");
    for (x, y, b) in pts {
        s += &(pair(10, x) + &pair(20, y));
        if *b != "0" {
            s += &pair(42, b);
        }
    }
    s
}

fn svg(body: &str) -> Vec<u8> {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"100mm\" height=\"100mm\" viewBox=\"0 0 100 100\">\n{body}\n</svg>\n"
    )
    .into_bytes()
}

fn tools_with(key: &str, value: &str) -> Vec<u8> {
    let text = String::from_utf8(example("tools/table1.json")).expect("utf-8");
    let needle = format!("\"{key}\": ");
    let at = text.find(&needle).expect("key") + needle.len();
    let end = at + text[at..].find([',', '}']).expect("end");
    format!("{}{value}{}", &text[..at], &text[end..]).into_bytes()
}

fn catalogue() -> Vec<Entry> {
    let pocket = || ("case.json", example("cases/square_pocket.json"));
    let part = || ("part.stl", stl_box(None));
    let mesh = || ("job.json", mesh_case(""));
    let tools = || ("tools.json", example("tools/table1.json"));
    let shape = || ("shape.json", example("shapes/disk_minus_slot.json"));
    let square =
        || ("sq.dxf", dxf("4", &dxf_lwpoly(&[("0", "0", "0"), ("40", "0", "0"), ("40", "30", "0"), ("0", "30", "0")])));
    let same = "never replaces an input";
    let mut v = vec![
        // outputs that are inputs, by name and by identity
        entry("g-code over the case", vec![pocket()], "rough case.json -o case.json", &["case.json", same]),
        entry(
            "report over the case",
            vec![pocket()],
            "rough case.json -o o.ngc --report case.json",
            &["case.json", same],
        ),
        entry("samples over the case", vec![pocket()], "rough case.json -o o.ngc --samples case.json", &[same]),
        entry(
            "picture over the drawing",
            vec![("s.svg", svg("<rect x=\"10\" y=\"10\" width=\"50\" height=\"40\"/>"))],
            "rough s.svg -o o.ngc --plot s.svg",
            &["s.svg", same],
        ),
        entry(
            "default output is the input",
            vec![("case.ngc", example("cases/square_pocket.json"))],
            "rough case.ngc",
            &[same],
        ),
        entry("dotted path to the case", vec![pocket()], "rough case.json -o ./case.json", &["./case.json", same]),
        entry("g-code over the STL", vec![part()], "rough part.stl -o part.stl", &["part.stl", same]),
        entry("g-code over a 3D case's STL", vec![mesh(), part()], "rough job.json -o part.stl", &["part.stl", same]),
        entry(
            "picture over a 3D case's STL",
            vec![mesh(), part()],
            "rough job.json -o o.ngc --samples part.stl",
            &[same],
        ),
        entry("g-code over the drawing", vec![square()], "rough sq.dxf -o sq.dxf --no-simulate", &["sq.dxf", same]),
        entry(
            "plan report over the tools",
            vec![mesh(), part(), tools()],
            "plan job.json --tools tools.json --output-dir out --report tools.json",
            &["tools.json", same],
        ),
        entry(
            "plan report over the case",
            vec![mesh(), part(), tools()],
            "plan job.json --tools tools.json --output-dir out --report job.json",
            &["job.json", same],
        ),
        entry(
            "plan report over the STL",
            vec![mesh(), part(), tools()],
            "plan job.json --tools tools.json --output-dir out --report part.stl",
            &[same],
        ),
        entry("shape picture over the shape", vec![shape()], "shape shape.json -o shape.json", &["shape.json", same]),
        // outputs that are not regular files, or named twice
        entry("g-code to a device", vec![pocket()], "rough case.json -o /dev/null", &["/dev/null", "regular files"]),
        entry(
            "report to a device",
            vec![pocket()],
            "rough case.json -o o.ngc --report /dev/zero",
            &["/dev/zero", "regular files"],
        ),
        entry("shape to a device", vec![shape()], "shape shape.json -o /dev/null", &["/dev/null", "regular files"]),
        entry("g-code to a folder", vec![pocket()], "rough case.json -o .", &["folder"]),
        entry(
            "two outputs one file",
            vec![pocket()],
            "rough case.json -o o.ngc --report o.ngc",
            &["o.ngc", "two outputs"],
        ),
        // huge, tiny and unbounded numbers in a case
        entry(
            "case point 1e300",
            vec![("c.json", case_with(r#""stock": [[0, 0], [1e300, 0], [40, 30]]"#))],
            "rough c.json",
            &["c.json", "stock[1]", "1e9"],
        ),
        entry(
            "case point beyond 100 m",
            vec![("c.json", case_with(r#""stock": [[0, 0], [2e5, 0], [40, 30]]"#))],
            "rough c.json",
            &["c.json", "stock[1]", "100000 mm"],
        ),
        entry(
            "case in inches beyond 100 m",
            vec![("c.json", case_with(r#""units": "in", "stock": [[0, 0], [1e5, 0], [40, 30]]"#))],
            "rough c.json",
            &["c.json", "100000 mm"],
        ),
        entry(
            "case part point 1e300",
            vec![("c.json", case_with(r#""part": [[[1, 1], [1e300, 1], [2, 2]]]"#))],
            "rough c.json",
            &["c.json", "part"],
        ),
        entry(
            "case number 1e400",
            vec![("c.json", case_text(r#""stock": [[0, 0], [1e400, 0], [40, 30]]"#))],
            "rough c.json",
            &["c.json"],
        ),
        entry(
            "case tool 1e-6",
            vec![("c.json", case_with(r#""tool": {"diameter": 1e-6}"#))],
            "rough c.json",
            &["c.json", "tool.diameter", "0.05"],
        ),
        entry(
            "case tool 1e300",
            vec![("c.json", case_with(r#""tool": {"diameter": 1e300}"#))],
            "rough c.json",
            &["c.json", "tool.diameter"],
        ),
        entry(
            "case tool 5000",
            vec![("c.json", case_with(r#""tool": {"diameter": 5000}"#))],
            "rough c.json",
            &["c.json", "tool.diameter", "1000"],
        ),
        entry(
            "case step-down 1e-9",
            vec![("c.json", case_with(r#""stepdown": 1e-9"#))],
            "rough c.json",
            &["c.json", "stepdown", "500"],
        ),
        entry(
            "case floor -1e6",
            vec![("c.json", case_with(r#""floor": -1e6"#))],
            "rough c.json",
            &["c.json", "floor", "100000"],
        ),
        entry(
            "case feed 1e300",
            vec![("c.json", case_with(r#""feed_default": 1e300"#))],
            "rough c.json",
            &["c.json", "feed_default"],
        ),
        entry(
            "case feed 1e8",
            vec![("c.json", case_with(r#""feed_default": 1e8"#))],
            "rough c.json",
            &["c.json", "feed_default", "1000000"],
        ),
        entry(
            "case rapid 1e300",
            vec![("c.json", case_with(r#""rapid_rate": 1e300"#))],
            "rough c.json",
            &["c.json", "rapid_rate"],
        ),
        entry(
            "case allowance 1e300",
            vec![("c.json", case_with(r#""allowance": 1e300"#))],
            "rough c.json",
            &["c.json", "allowance"],
        ),
        entry(
            "case work beyond budget",
            vec![(
                "c.json",
                case_with(r#""stock": [[0, 0], [90000, 0], [90000, 90000], [0, 90000]], "tool": {"diameter": 0.1}"#),
            )],
            "rough c.json --no-simulate",
            &["c.json", "km of cutting"],
        ),
        // 3D cases
        entry(
            "3D scale 1e308",
            vec![("job.json", mesh_case(r#""part_transform": {"scale": 1e308}"#)), part()],
            "rough job.json",
            &["job.json", "scale", "1e9"],
        ),
        entry(
            "3D scale 1e5",
            vec![("job.json", mesh_case(r#""part_transform": {"scale": 1e5}"#)), part()],
            "rough job.json",
            &["job.json", "part_transform", "100000 mm"],
        ),
        entry(
            "3D translate 1e300",
            vec![("job.json", mesh_case(r#""part_transform": {"translate": [1e300, 0, 0]}"#)), part()],
            "rough job.json",
            &["job.json", "translate"],
        ),
        entry(
            "3D translate 1e8",
            vec![("job.json", mesh_case(r#""part_transform": {"translate": [1e8, 0, 0]}"#)), part()],
            "rough job.json",
            &["job.json", "100000 mm"],
        ),
        entry(
            "3D stock box 1e300",
            vec![
                (
                    "job.json",
                    String::from_utf8(mesh_case("")).expect("utf-8").replace("22, 12, 6", "22, 12, 1e300").into_bytes(),
                ),
                part(),
            ],
            "rough job.json",
            &["job.json", "stock_box"],
        ),
        entry(
            "3D step-down 1e-9",
            vec![("job.json", mesh_case(r#""stepdown": 1e-9"#)), part()],
            "rough job.json",
            &["job.json", "stepdown", "500"],
        ),
        entry(
            "3D floor -1e6",
            vec![("job.json", mesh_case(r#""floor": -1e6"#)), part()],
            "rough job.json",
            &["job.json"],
        ),
        // options
        entry("--clearance 1e308", vec![pocket()], "rough case.json --clearance 1e308", &["--clearance", "100000"]),
        entry("--feed 1e300", vec![pocket()], "rough case.json --feed 1e300", &["--feed", "1000000"]),
        entry("--max-feed 1e300", vec![pocket()], "rough case.json --max-feed 1e300", &["--max-feed"]),
        entry("--spindle 1e300", vec![pocket()], "rough case.json --spindle 1e300", &["--spindle", "1000000"]),
        entry(
            "--tool-diameter 1e-6",
            vec![pocket()],
            "rough case.json --tool-diameter 1e-6",
            &["--tool-diameter", "0.05"],
        ),
        entry(
            "--tool-diameter 0.01 on a drawing",
            vec![square()],
            "rough sq.dxf --tool-diameter 0.01",
            &["--tool-diameter", "0.05"],
        ),
        entry("--stepdown 1e-9", vec![pocket()], "rough case.json --stepdown 1e-9", &["--stepdown", "500"]),
        entry("--depth 1e6", vec![square()], "rough sq.dxf --depth 1e6", &["--depth", "100000"]),
        entry(
            "--stock-to-leave 1e300",
            vec![pocket()],
            "rough case.json --stock-to-leave 1e300",
            &["--stock-to-leave"],
        ),
        entry("--stock-margin 1e9", vec![part()], "rough part.stl --stock-margin 1e9", &["--stock-margin", "100000"]),
        entry("--stock-above 1e9", vec![part()], "rough part.stl --stock-above 1e9", &["--stock-above", "100000"]),
        entry("--part-scale 1e308", vec![part()], "rough part.stl --part-scale 1e308", &["--part-scale"]),
        entry(
            "--part-scale 1e5",
            vec![part()],
            "rough part.stl --part-scale 1e5",
            &["part.stl", "100000 mm", "--part-scale"],
        ),
        entry(
            "--part-translate 1e300",
            vec![part()],
            "rough part.stl --part-translate 1e300,0,0",
            &["--part-translate"],
        ),
        entry(
            "--units in on 1e5 mm",
            vec![("big.dxf", dxf("0", &dxf_circle("0", "0", "1e5")))],
            "rough big.dxf --units in",
            &["big.dxf", "100000 mm"],
        ),
        entry(
            "--svg-dpi 1e-300",
            vec![("s.svg", svg("<rect x=\"10\" y=\"10\" width=\"50\" height=\"40\"/>"))],
            "rough s.svg --svg-dpi 1e-300",
            &["--svg-dpi"],
        ),
        // drawings
        entry(
            "DXF line 1e300",
            vec![(
                "d.dxf",
                dxf(
                    "4",
                    &(pair(0, "LINE")
                        + &pair(8, "0")
                        + &pair(10, "0")
                        + &pair(20, "0")
                        + &pair(11, "1e300")
                        + &pair(21, "0")),
                ),
            )],
            "rough d.dxf",
            &["d.dxf"],
        ),
        entry(
            "DXF circle radius 1e300",
            vec![("d.dxf", dxf("4", &dxf_circle("0", "0", "1e300")))],
            "rough d.dxf",
            &["d.dxf"],
        ),
        entry(
            "DXF circle radius 1e6",
            vec![("d.dxf", dxf("4", &dxf_circle("0", "0", "1e6")))],
            "rough d.dxf",
            &["d.dxf", "100000 mm"],
        ),
        entry(
            "DXF circle centre 1e300",
            vec![("d.dxf", dxf("4", &dxf_circle("1e300", "0", "5")))],
            "rough d.dxf",
            &["d.dxf"],
        ),
        entry(
            "DXF bulge 1e300",
            vec![("d.dxf", dxf("4", &dxf_lwpoly(&[("0", "0", "1e300"), ("40", "0", "0"), ("40", "30", "0")])))],
            "rough d.dxf",
            &["d.dxf"],
        ),
        entry(
            "DXF in inches 1e307",
            vec![("d.dxf", dxf("1", &dxf_circle("0", "0", "1e307")))],
            "rough d.dxf",
            &["d.dxf"],
        ),
        entry(
            "DXF 1e23 under zigzag",
            vec![(
                "d.dxf",
                dxf(
                    "4",
                    &dxf_lwpoly(&[("0", "0", "0"), ("1e23", "0", "0"), ("1e23", "1e23", "0"), ("0", "1e23", "0")]),
                ),
            )],
            "rough d.dxf --strategy zigzag",
            &["d.dxf"],
        ),
        entry(
            "DXF vertex at 1e9 under offset",
            vec![(
                "d.dxf",
                dxf("4", &dxf_lwpoly(&[("0", "0", "0"), ("1e9", "0", "0"), ("40", "30", "0"), ("0", "30", "0")])),
            )],
            "rough d.dxf --strategy offset",
            &["d.dxf", "100000 mm"],
        ),
        entry(
            "SVG path 1e300",
            vec![("s.svg", svg("<path d=\"M0 0 L1e300 0 L40 30 Z\"/>"))],
            "rough s.svg",
            &["s.svg"],
        ),
        entry(
            "SVG circle r 1e300",
            vec![("s.svg", svg("<circle cx=\"0\" cy=\"0\" r=\"1e300\"/>"))],
            "rough s.svg",
            &["s.svg"],
        ),
        entry(
            "SVG transform scale 1e300",
            vec![(
                "s.svg",
                svg("<g transform=\"scale(1e300)\"><rect x=\"10\" y=\"10\" width=\"50\" height=\"40\"/></g>"),
            )],
            "rough s.svg",
            &["s.svg"],
        ),
        entry(
            "SVG of 200 000 tiny paths",
            vec![(
                "s.svg",
                svg(&(0..200_000)
                    .map(|i| {
                        format!("<path d=\"M{} {} h.05v.05h-.05z\"/>", (i % 1000) as f64 * 0.1, (i / 1000) as f64 * 0.1)
                    })
                    .collect::<String>()),
            )],
            "rough s.svg",
            &["s.svg", "10000"],
        ),
        // STL
        entry("STL vertex 1e38", vec![("p.stl", stl_box(Some("1e38 0 5")))], "rough p.stl", &["p.stl"]),
        entry("STL vertex NaN", vec![("p.stl", stl_box(Some("nan 0 5")))], "rough p.stl", &["p.stl"]),
        entry(
            "binary STL 3e38",
            vec![("p.stl", stl_binary(&[[[0.0, 0.0, 0.0], [3e38, 0.0, 1.0], [0.0, 3e38, 2.0]]]))],
            "rough p.stl",
            &["p.stl"],
        ),
        entry(
            "STL of 3000 flats",
            vec![(
                "p.stl",
                stl_binary(
                    &(0..3000)
                        .map(|i| {
                            let z = i as f32 * 0.01;
                            [[0.0, 0.0, z], [10.0, 0.0, z], [0.0, 10.0, z]]
                        })
                        .collect::<Vec<_>>(),
                ),
            )],
            "rough p.stl --stepdown 50",
            &["p.stl", "levels", "500"],
        ),
        // tool databases
        entry(
            "tools diameter 1e308",
            vec![mesh(), part(), ("tools.json", tools_with("diameter", "1e308"))],
            "plan job.json --tools tools.json",
            &["tools.json", "tools[0].diameter"],
        ),
        entry(
            "tools diameter 1e-6",
            vec![mesh(), part(), ("tools.json", tools_with("diameter", "1e-6"))],
            "plan job.json --tools tools.json",
            &["tools.json", "tools[0].diameter", "0.05"],
        ),
        entry(
            "tools cutting speed 1e308",
            vec![mesh(), part(), ("tools.json", tools_with("cutting_speed_m_min", "1e308"))],
            "plan job.json --tools tools.json",
            &["tools.json", "cutting_speed_m_min"],
        ),
        entry(
            "tools cutting speed 1e7",
            vec![mesh(), part(), ("tools.json", tools_with("cutting_speed_m_min", "1e7"))],
            "plan job.json --tools tools.json",
            &["tools.json", "cutting_speed_m_min", "rpm"],
        ),
        entry(
            "tools feed per tooth 1e6",
            vec![mesh(), part(), ("tools.json", tools_with("feed_per_tooth", "1e6"))],
            "plan job.json --tools tools.json",
            &["tools.json", "feed_per_tooth"],
        ),
        entry(
            "tools rapid 1e300",
            vec![mesh(), part(), ("tools.json", tools_with("rapid_feed_mm_min", "1e300"))],
            "plan job.json --tools tools.json",
            &["tools.json", "rapid_feed_mm_min"],
        ),
        entry(
            "plan --clearance 1e308",
            vec![mesh(), part(), tools()],
            "plan job.json --tools tools.json --clearance 1e308",
            &["--clearance"],
        ),
        // shapes
        entry("shape --levels 1e9", vec![shape()], "shape shape.json --levels 1000000000", &["--levels", "1000"]),
        entry(
            "shape not UTF-8",
            vec![("shape.json", vec![b'{', 0xff, 0xfe, b'}'])],
            "shape shape.json",
            &["shape.json", "byte 1", "UTF-8"],
        ),
    ];
    v.retain(|e| !e.name.is_empty());
    v
}

#[test]
fn every_hostile_input_is_refused_with_exit_2_and_nothing_written() {
    let entries = catalogue();
    assert!(entries.len() >= 60, "{} entries", entries.len());
    // (two at a time; every entry is run, and the failures named together at the end)
    let failed = |part: &[Entry]| -> Vec<&'static str> {
        part.iter().filter(|e| std::panic::catch_unwind(|| check(e)).is_err()).map(|e| e.name).collect()
    };
    let (a, b) = entries.split_at(entries.len() / 2);
    let mut bad = std::thread::scope(|s| {
        let h = s.spawn(|| failed(a));
        let mut v = failed(b);
        v.extend(h.join().expect("first half"));
        v
    });
    bad.sort_unstable();
    assert!(bad.is_empty(), "{} of {} failed: {bad:?}", bad.len(), entries.len());
}

/// The spiral's search, which took over 20 s on these examples, ends within the catalogue's
/// time and memory bound with its program (its work is bounded by cells, see
/// `swarf::strategy::spiral_search`).
#[test]
fn the_spiral_search_ends_within_the_bounds() {
    for n in ["simple_part", "l_pocket"] {
        let d = TempDir::new("spiral-bound");
        d.write("c.json", example(&format!("cases/{n}.json")));
        let args = ["rough", "c.json", "--strategy", "spiral", "-o", "out.ngc", "-q"].map(String::from);
        let (code, stderr, took) = run_limited(d.path(), &args);
        assert_eq!(code, Some(0), "{n}: killed or failed after {took:?}: {stderr}");
        assert!(d.path().join("out.ngc").is_file(), "{n}: no program");
    }
}

#[test]
fn outputs_named_through_links_are_compared_by_identity() {
    let d = TempDir::new("links");
    let case = d.write("case.json", example("cases/square_pocket.json"));
    std::fs::hard_link(&case, d.path().join("hard.ngc")).expect("hard link");
    std::os::unix::fs::symlink("case.json", d.path().join("soft.ngc")).expect("symlink");
    for out in ["hard.ngc", "soft.ngc"] {
        let (code, stderr, _) = run_limited(d.path(), &["rough".into(), "case.json".into(), "-o".into(), out.into()]);
        assert_eq!(code, Some(2), "{out}: {stderr}");
        assert!(stderr.contains("never replaces an input"), "{out}: {stderr}");
    }
    assert_eq!(std::fs::read(&case).expect("case"), example("cases/square_pocket.json"));
    assert_eq!(d.listing().len(), 3);
}

#[test]
fn a_signal_stops_the_run_with_no_temporary_file_left() {
    let d = TempDir::new("signal");
    d.write("case.json", example("cases/pocket_islands.json"));
    let mut child = Command::new(env!("CARGO_BIN_EXE_swarf"))
        .args(["rough", "case.json", "-o", "o.ngc", "--report", "o.json", "-q"])
        .current_dir(d.path())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run swarf");
    std::thread::sleep(Duration::from_millis(300));
    let _ = Command::new("kill").args(["-TERM", &child.id().to_string()]).status();
    let status = child.wait().expect("wait");
    // stopped by the signal (143), or done before it came (0): never a half-written output
    let names = d.listing();
    match status.code() {
        Some(143) => assert_eq!(names.len(), 1, "{names:?}"),
        Some(0) => assert_eq!(names.len(), 3, "{names:?}"),
        c => panic!("exit {c:?}"),
    }
    assert!(names.iter().all(|n| !n.contains("swarf-tmp")), "{names:?}");
}

// ---- seeded mutations of the examples --------------------------------------------------------

/// xorshift64: the mutations are the same on every run.
struct Rng(u64);

impl Rng {
    fn below(&mut self, n: usize) -> usize {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 % n.max(1) as u64) as usize
    }
}

/// One mutation of `text`: a number set to 0, −1, 1e300, 1e-300 or NaN, or a line dropped or
/// doubled.
fn mutate(text: &str, rng: &mut Rng) -> (String, String) {
    let lines: Vec<&str> = text.lines().collect();
    match rng.below(3) {
        0 => {
            // the numbers: runs of digits with their sign, point and exponent
            let b = text.as_bytes();
            let mut spans = Vec::new();
            let mut i = 0;
            while i < b.len() {
                if b[i].is_ascii_digit() {
                    let mut s = i;
                    if s > 0 && b[s - 1] == b'-' {
                        s -= 1;
                    }
                    while i < b.len() && (b[i].is_ascii_digit() || b"eE.+-".contains(&b[i])) {
                        i += 1;
                    }
                    spans.push((s, i));
                } else {
                    i += 1;
                }
            }
            if spans.is_empty() {
                return (text.to_string(), "unchanged".into());
            }
            let (s, e) = spans[rng.below(spans.len())];
            let v = ["0", "-1", "1e300", "1e-300", "NaN"][rng.below(5)];
            (format!("{}{v}{}", &text[..s], &text[e..]), format!("{} -> {v} at byte {s}", &text[s..e]))
        }
        k => {
            let at = rng.below(lines.len());
            let mut out: Vec<&str> = lines.clone();
            if k == 1 {
                out.remove(at);
            } else {
                out.insert(at, lines[at]);
            }
            (out.join("\n") + "\n", format!("line {} {}", at + 1, if k == 1 { "dropped" } else { "doubled" }))
        }
    }
}

#[test]
fn mutated_examples_end_with_0_or_2_and_never_a_bad_program() {
    // (HOSTILE_MUTATIONS=N mutates each example N times, for a longer campaign; HOSTILE_SEED
    // picks another sequence)
    let per: usize = std::env::var("HOSTILE_MUTATIONS").ok().and_then(|v| v.parse().ok()).unwrap_or(6);
    let seed: u64 = std::env::var("HOSTILE_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(0x9e37_79b9_7f4a_7c15);
    let mut rng = Rng(seed | 1);
    let mut jobs: Vec<(String, &str, Vec<u8>, Vec<String>)> = Vec::new();
    let cases = [
        "boss_with_clamp",
        "l_pocket",
        "narrow_slot",
        "pocket_islands",
        "round_pocket",
        "simple_part",
        "square_pocket",
    ];
    for name in cases {
        let text = String::from_utf8(example(&format!("cases/{name}.json"))).expect("utf-8");
        for k in 0..per {
            let (m, how) = mutate(&text, &mut rng);
            let mut args = vec!["rough".to_string(), "in.json".into(), "-o".into(), "out.ngc".into(), "-q".into()];
            if k % 2 == 1 {
                args.push("--no-simulate".into());
            }
            jobs.push((format!("{name}: {how}"), "in.json", m.into_bytes(), args));
        }
    }
    // the 3D example with its part beside it, and the tool database planned on it
    let mesh = String::from_utf8(example("3d/bowl_cavity.json"))
        .expect("utf-8")
        .replace("../parts/bowl_cavity.stl", "part.stl");
    let tools = String::from_utf8(example("tools/table1.json")).expect("utf-8");
    for _ in 0..per.div_ceil(2) + 1 {
        let (m, how) = mutate(&mesh, &mut rng);
        let args = ["rough", "in.json", "-o", "out.ngc", "-q", "--no-simulate"].map(String::from).to_vec();
        jobs.push((format!("bowl_cavity: {how}"), "in.json", m.into_bytes(), args));
    }
    for _ in 0..per.div_ceil(2) {
        let (m, how) = mutate(&tools, &mut rng);
        let args = [
            "plan",
            "bowl.json",
            "--tools",
            "in.json",
            "--report",
            "out.json",
            "--output-dir",
            "plan",
            "-q",
            "--no-simulate",
            "--no-pictures",
        ]
        .map(String::from)
        .to_vec();
        jobs.push((format!("table1: {how}"), "in.json", m.into_bytes(), args));
    }
    let shape = String::from_utf8(example("shapes/disk_minus_slot.json")).expect("utf-8");
    for _ in 0..per + 2 {
        let (m, how) = mutate(&shape, &mut rng);
        let args = ["shape", "in.json", "-o", "out.svg", "-q", "--spiral", "4"].map(String::from).to_vec();
        jobs.push((format!("shape: {how}"), "in.json", m.into_bytes(), args));
    }
    let mut bad = Vec::new();
    let mut tally = [0usize; 2];
    for (what, input, bytes, args) in &jobs {
        let d = TempDir::new("mutant");
        d.write(input, bytes);
        // (what the mutated file reads beside it)
        d.write("part.stl", example("parts/bowl_cavity.stl"));
        d.write("bowl.json", mesh.as_bytes());
        let inputs = d.listing().len();
        let (code, stderr, _) = run_limited(d.path(), args);
        let out = d.path().join(args.iter().skip_while(|a| *a != "-o" && *a != "--report").nth(1).expect("an output"));
        let written = std::fs::read_to_string(&out).unwrap_or_default();
        let verdict = match code {
            _ if stderr.contains("panicked") => Some("panicked".to_string()),
            None => Some(format!("still running after {TIME_LIMIT:?}")),
            Some(0) if !out.is_file() => Some("exit 0 and no output".into()),
            Some(0) if ["inf", "NaN", "nan"].iter().any(|w| written.contains(w)) => {
                Some("a word that is not a number".into())
            }
            Some(0) => None,
            Some(2) if d.listing().len() != inputs => Some(format!("exit 2 and files left: {:?}", d.listing())),
            Some(2) if !stderr.lines().last().is_some_and(|l| l.starts_with("swarf: ")) => {
                Some(format!("exit 2: {stderr:?}"))
            }
            // (the message names the file it is about, or the option)
            Some(2) if !["in.json", "bowl.json", "part.stl", "--"].iter().any(|n| stderr.contains(n)) => {
                Some(format!("exit 2 naming no file: {stderr:?}"))
            }
            Some(2) => None,
            Some(c) => Some(format!("exit {c}: {stderr:?}")),
        };
        if let Some(v) = verdict {
            bad.push(format!("{what}: {v}"));
        }
        match code {
            Some(0) => tally[0] += 1,
            Some(2) => tally[1] += 1,
            _ => {}
        }
    }
    eprintln!("{} mutations: {} ran (exit 0), {} refused (exit 2)", jobs.len(), tally[0], tally[1]);
    assert!(jobs.len() >= 50, "{} mutations", jobs.len());
    // (both outcomes: the mutations neither all break the files nor all miss)
    assert!(tally[0] >= 5 && tally[1] >= 5, "{tally:?}");
    assert!(bad.is_empty(), "{} of {} mutations: {bad:#?}", bad.len(), jobs.len());
}
