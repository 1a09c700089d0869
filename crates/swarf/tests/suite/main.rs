//! The library's integration tests, in one binary: one link instead of twelve, and the test
//! harness runs them all side by side (a long test in one file no longer leaves a core idle
//! while the next file waits its turn). Run one file's tests with its module name as the
//! filter, e.g. `cargo test -p swarf --test suite property::`.

mod common;

mod architecture;
mod determinism;
mod engagement;
mod five;
mod gcode_read;
mod links;
mod medial;
mod options;
mod post_golden;
mod property;
mod sdf;
mod spiral;
mod toolseq;
mod zlevel;
