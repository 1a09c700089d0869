//! A case file (JSON, 2.5D or 3D): read and validated, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    // (a 3D case names an STL beside it; there is none, which is an error like any other)
    if let Ok(swarf::Input::Flat(job)) = swarf::io::case::parse_input(Path::new("fuzz.json"), data) {
        let _ = job.validate();
    }
});
