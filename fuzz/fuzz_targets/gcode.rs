//! A G-code program (swarf's or another system's): read into a toolpath, never a panic, and
//! what is read is within the limits (every coordinate finite and within ±100 m, a line per move).
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let opts = swarf::io::gcode::ReadOptions::DEFAULT;
    if let Ok(p) = swarf::io::gcode::read(text, Path::new("fuzz.ngc"), &opts) {
        assert_eq!(p.lines.len(), p.toolpath.moves.len());
        for m in &p.toolpath.moves {
            assert!(m.to.to_array().iter().all(|c| swarf::limits::coord_ok(*c)), "{:?}", m.to);
        }
    }
});
