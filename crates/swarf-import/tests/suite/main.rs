//! The importers' integration tests, in one binary (one link, and the harness runs them side by
//! side). Run one file's tests with its module name as the filter, e.g.
//! `cargo test -p swarf-import --test suite dxf_read::`.

mod dxf_read;
mod dxf_shared_files;
mod svg_errors;
mod svg_read;
mod svg_samples;
mod svg_shared_files;
