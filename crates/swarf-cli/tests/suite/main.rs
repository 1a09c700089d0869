//! The command line's integration tests, in one binary (one link, and the harness runs them side
//! by side). Run one file's tests with its module name as the filter, e.g.
//! `cargo test -p swarf-cli --test suite e2e_rs274::`.

mod common;

mod browser;
mod cli_errors;
mod e2e_rs274;
mod five_cli;
mod hostile;
mod plan_report;
mod programs_golden;
mod view_cli;
