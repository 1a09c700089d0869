//! Benchmarks of the swarf library, with criterion: `cargo bench -p swarf-bench` (the planners
//! and the simulator on the example cases; see `benches/`). The library target is empty: the
//! package exists so that the benchmarks' dependencies stay out of `cargo test`.
