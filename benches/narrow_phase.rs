//! Narrow-phase benchmarks (filled in with the narrow phase).
fn main() {}
