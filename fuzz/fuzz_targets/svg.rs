//! An SVG drawing: read, and made into a job as `swarf rough` does, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;
use swarf::io::Overrides;

fuzz_target!(|data: &[u8]| {
    let ov = Overrides::DEFAULT;
    if let Ok(d) = swarf::swarf_import::svg::read_svg(Path::new("fuzz.svg"), data, &ov.import) {
        let _ = swarf::io::drawing::job_and_reading(&d, &ov);
    }
});
