//! The fast engines against the f64 general engine (the exact reference) and the
//! peers' float64 reference: the grid fast path and its kernel, the lattice and mesh
//! engines, `System::run_ahead`, and the `bench` scenes.

#[path = "../common/mod.rs"]
mod common;

mod bench_reference;
mod fast_engine;
mod fast_path;
mod grid_kernel;
mod lattice_kernel;
mod run_ahead;
