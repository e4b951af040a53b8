//! Placeholder until the step benchmarks land.
fn main() {}
