//! Cloth sandbox: a headless mass-spring cloth simulation core.
#![warn(missing_docs)]

pub mod sim;
