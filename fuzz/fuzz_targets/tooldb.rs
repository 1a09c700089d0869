//! A tool database (JSON, paper 3's Table 1): parsed, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let _ = swarf::model::tooldb::ToolDb::parse(Path::new("fuzz.json"), data);
});
