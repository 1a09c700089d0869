//! An STL part (ASCII or binary): parsed, placed and laid flat, never a panic.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let path = Path::new("fuzz.stl");
    if let Ok(mesh) = swarf::io::stl::parse(path, data) {
        if swarf::io::stl::check_size(path, &mesh, "part", "the placement").is_ok() {
            let _ = swarf::io::stl::lay_flat(&mesh);
        }
    }
});
