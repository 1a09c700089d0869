//! End to end in a real browser: the viewer pages `swarf rough --html`, `swarf plan --html` and
//! `swarf view` write, opened in Debian's Chromium (headless) and driven by Playwright
//! (`tests/browser/viewer.test.mjs`, run with Node's test runner against the `swarf` built for
//! these tests). What they check is said at the top of that file.
//!
//! The browser tests need `node`, Debian's `chromium` and the test folder's npm packages
//! (`npm ci --prefix tests/browser`). Without them this test prints a note and passes, unless
//! `SWARF_REQUIRE_BROWSER` is set (CI sets it), in which case it fails. The screenshots and the
//! timings are kept in `target/browser-tests/`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// What is missing to run the browser tests, if anything.
fn missing() -> Option<String> {
    let root = repo_root();
    let chromium = std::env::var_os("SWARF_CHROMIUM").map_or_else(|| PathBuf::from("/usr/bin/chromium"), PathBuf::from);
    if Command::new("node").arg("--version").output().map(|o| !o.status.success()).unwrap_or(true) {
        return Some("node is not on PATH (Debian package nodejs)".into());
    }
    if !chromium.is_file() {
        return Some(format!("{} is missing (Debian package chromium)", chromium.display()));
    }
    if !root.join("tests/browser/node_modules/playwright-core").is_dir() {
        return Some("tests/browser/node_modules has no playwright-core (run `npm ci --prefix tests/browser`)".into());
    }
    None
}

#[test]
fn the_viewer_pages_work_in_a_real_browser() {
    if let Some(why) = missing() {
        if std::env::var_os("SWARF_REQUIRE_BROWSER").is_some() {
            panic!("SWARF_REQUIRE_BROWSER is set but the browser tests cannot run: {why}");
        }
        eprintln!("note: skipping the browser tests: {why} (set SWARF_REQUIRE_BROWSER=1 to make this a failure)");
        return;
    }
    let root = repo_root();
    let out = root.join("target/browser-tests");
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&out).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
    let run = Command::new("node")
        .args(["--test", "--test-reporter=spec", "viewer.test.mjs"])
        .current_dir(root.join("tests/browser"))
        .env("SWARF_BIN", env!("CARGO_BIN_EXE_swarf"))
        .env("SWARF_BROWSER_OUT", &out)
        .output()
        .expect("node runs");
    let text = format!("{}{}", String::from_utf8_lossy(&run.stdout), String::from_utf8_lossy(&run.stderr));
    assert!(run.status.success(), "the browser tests failed:\n{text}");
    // (the runner said what it ran: five tests, none failed)
    assert!(text.contains("pass 5") && text.contains("fail 0"), "unexpected test counts:\n{text}");
    for shot in ["2d_middle.png", "3d_middle.png", "plan_middle.png", "compare_middle.png", "big_end.png"] {
        let p = out.join(shot);
        let len = std::fs::metadata(&p).map(|m| m.len()).unwrap_or(0);
        assert!(len > 10_000, "{}: a screenshot of {len} bytes", p.display());
    }
}
