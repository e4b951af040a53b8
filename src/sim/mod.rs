//! Simulation core (headless; no graphics).

pub mod grid_kernel;
