//! The layout is the architecture: read from the library's own sources, the modules import one
//! another without a circle, and each folder imports only the folders below it:
//!
//! ```text
//! job → strategy → plan · io · report · plot → sim · post → toolpath → model · implicit → geom
//! ```
//!
//! (`error` is below everything.) The imports are read as text: every `crate::…` and `super::…`
//! path outside comments, resolved to the file of the module it names. A module's `mod.rs`
//! declaring and re-exporting its own children is its face, not an import.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The folders (and top-level files) bottom up; a module may import its own layer and the ones
/// below.
const LAYERS: [&[&str]; 9] = [
    &["error", "limits", "geom"],
    &["model", "implicit"],
    &["toolpath"],
    &["sim", "post"],
    &["plan", "io", "report", "plot"],
    &["strategy"],
    &["job"],
    &["view"],
    &["lib"],
];

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Every source file, as its module path (`sim::raster`, `sim` for `sim/mod.rs`, `lib`).
fn modules() -> BTreeMap<String, PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).expect("src folder") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    let mut files = Vec::new();
    walk(&src(), &mut files);
    files
        .into_iter()
        .map(|p| {
            let rel = p.strip_prefix(src()).expect("under src").with_extension("");
            let mut parts: Vec<String> = rel.iter().map(|s| s.to_string_lossy().into_owned()).collect();
            if parts.last().is_some_and(|l| l == "mod") {
                parts.pop();
            }
            (parts.join("::"), p)
        })
        .collect()
}

/// The code of a file without comments, doc comments and string literals.
fn code(text: &str) -> String {
    let mut out = String::new();
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("//") || t.starts_with("#[doc") {
            continue;
        }
        let line = line.split("//").next().unwrap_or("");
        // drop string literals (paths in messages are not imports)
        let mut in_str = false;
        let mut prev = ' ';
        for c in line.chars() {
            if c == '"' && prev != '\\' {
                in_str = !in_str;
            } else if !in_str {
                out.push(c);
            }
            prev = c;
        }
        out.push('\n');
    }
    out
}

/// The paths a file names, as segment lists from the crate root (`use` groups expanded one
/// level: `crate::plan::{levels::drive, LinkOptions}` names `plan::levels::drive` and
/// `plan::LinkOptions`).
fn paths(module: &str, text: &str) -> Vec<Vec<String>> {
    let here: Vec<String> = if module == "lib" { Vec::new() } else { module.split("::").map(String::from).collect() };
    let mut out = Vec::new();
    let bytes: Vec<char> = text.chars().collect();
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut i = 0;
    while i < bytes.len() {
        let rest: String = bytes[i..bytes.len().min(i + 7)].iter().collect();
        let start = if i == 0 { true } else { !ident(bytes[i - 1]) && bytes[i - 1] != ':' };
        let (base, skip) = if start && rest.starts_with("crate::") {
            (Vec::new(), 7)
        } else if start && rest.starts_with("super::") {
            (here[..here.len().saturating_sub(1)].to_vec(), 7)
        } else {
            i += 1;
            continue;
        };
        i += skip;
        let mut segs = base.clone();
        // more super::
        loop {
            let s: String = bytes[i..bytes.len().min(i + 7)].iter().collect();
            if s == "super::" {
                segs.pop();
                i += 7;
            } else {
                break;
            }
        }
        // segments
        loop {
            let st = i;
            while i < bytes.len() && ident(bytes[i]) {
                i += 1;
            }
            if i > st {
                segs.push(bytes[st..i].iter().collect());
            }
            if i + 1 < bytes.len() && bytes[i] == ':' && bytes[i + 1] == ':' {
                i += 2;
                if i < bytes.len() && bytes[i] == '{' {
                    // a group: each member's first segment(s)
                    let close = (i..bytes.len()).find(|&k| bytes[k] == '}').unwrap_or(bytes.len());
                    let inner: String = bytes[i + 1..close].iter().collect();
                    for member in inner.split(',') {
                        let m = member.trim().trim_start_matches('{');
                        let mut s = segs.clone();
                        s.extend(m.split("::").map(|x| x.trim().to_string()).filter(|x| !x.is_empty()).take(2));
                        out.push(s);
                    }
                    i = close;
                    break;
                }
                continue;
            }
            out.push(segs.clone());
            break;
        }
    }
    out
}

/// The module a path lands in: its longest prefix that is a module.
fn resolve(mods: &BTreeMap<String, PathBuf>, path: &[String]) -> Option<String> {
    (1..=path.len()).rev().map(|n| path[..n].join("::")).find(|m| mods.contains_key(m))
}

/// The imports between modules: `a → b` when a names something of b.
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let mods = modules();
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (m, file) in &mods {
        let text = code(&std::fs::read_to_string(file).expect("source"));
        let edges = g.entry(m.clone()).or_default();
        for p in paths(m, &text) {
            let Some(to) = resolve(&mods, &p) else { continue };
            // (a module's face: a parent naming its own children)
            let child_of_m = if m == "lib" { !to.contains("::") } else { to.starts_with(&format!("{m}::")) };
            if to != *m && !child_of_m {
                edges.insert(to);
            }
        }
    }
    g
}

fn layer(module: &str) -> usize {
    let top = module.split("::").next().unwrap_or(module);
    LAYERS.iter().position(|l| l.contains(&top)).unwrap_or_else(|| panic!("{module}: in no layer of LAYERS"))
}

#[test]
fn the_reader_finds_the_imports_it_should() {
    let g = graph();
    // a sample of known imports, so that the checks below are not vacuous
    for (a, b) in [
        ("job::rough", "strategy"),
        ("strategy::adaptive", "plan::linker"),
        ("plan::linker", "sim::raster"),
        ("sim::raster", "sim::replay"),
        ("io::case", "model"),
        ("strategy::spiral_search", "strategy::spiral"),
    ] {
        assert!(g.get(a).is_some_and(|e| e.contains(b)), "{a} → {b} not seen: {:?}", g.get(a));
    }
    assert!(g.len() > 50, "only {} modules read", g.len());
}

/// A circle of `g`, if it has one.
fn find_cycle(g: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        g: &BTreeMap<String, BTreeSet<String>>,
        m: &str,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        match state.get(m) {
            Some(1) => {
                let at = stack.iter().position(|s| s == m).unwrap_or(0);
                let mut c = stack[at..].to_vec();
                c.push(m.to_string());
                return Some(c);
            }
            Some(2) => return None,
            _ => {}
        }
        state.insert(m.to_string(), 1);
        stack.push(m.to_string());
        for n in g.get(m).into_iter().flatten() {
            if let Some(c) = visit(g, n, state, stack) {
                return Some(c);
            }
        }
        stack.pop();
        state.insert(m.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    g.keys().find_map(|m| visit(g, m, &mut state, &mut Vec::new()))
}

#[test]
fn no_module_imports_one_that_imports_it() {
    let g = graph();
    if let Some(c) = find_cycle(&g) {
        panic!("an import circle: {}", c.join(" → "));
    }
    // (the search finds a circle through others)
    let mut planted = g.clone();
    planted.entry("geom".into()).or_default().insert("job::rough".into());
    let c = find_cycle(&planted).expect("the planted circle");
    assert!(c.contains(&"geom".to_string()) && c.contains(&"job::rough".to_string()), "{c:?}");
}

#[test]
fn each_folder_imports_only_the_ones_below() {
    let g = graph();
    let mut up = Vec::new();
    for (a, edges) in &g {
        for b in edges {
            if layer(b) > layer(a) {
                up.push(format!("{a} → {b}"));
            }
        }
    }
    assert!(up.is_empty(), "imports that run up the layers:\n{}", up.join("\n"));
}
