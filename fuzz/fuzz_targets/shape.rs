//! An implicit shape file (JSON, R-functions): parsed and evaluated, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;
use swarf::implicit::Field;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    if let Ok(s) = swarf::implicit::shape::Shape::from_json(text, Path::new("fuzz.json")) {
        if let Some((lo, hi)) = s.bounds() {
            let _ = s.eval((lo + hi) * 0.5);
        }
    }
});
