//! `rough` on small 2.5D cases: a case read from the input and planned, posted and simulated,
//! when it is small (a bounded budget per run: at most 60 × 60 mm, three levels, a tool of at
//! least 2 mm); never a panic, and the same bytes twice.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;
use swarf::{Input, RoughOptions};

fuzz_target!(|data: &[u8]| {
    let Ok(Input::Flat(job)) = swarf::io::case::parse_input(Path::new("fuzz.json"), data) else { return };
    if job.validate().is_err() {
        return;
    }
    let Some((lo, hi)) = job.stock.bounds() else { return };
    let small = (hi - lo).max_element() <= 60.0 && job.levels().len() <= 3 && job.cutting.tool.diameter >= 2.0;
    if !small {
        return;
    }
    let opts = RoughOptions { simulate: data.len() % 2 == 0, ..RoughOptions::DEFAULT };
    let a = swarf::rough(&job, &opts, &mut |_, _| {});
    if let Ok(a) = a {
        let b = swarf::rough(&job, &opts, &mut |_, _| {}).expect("the same job planned twice");
        assert_eq!(a.gcode, b.gcode, "the same job gave two programs");
    }
});
