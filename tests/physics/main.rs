//! The physics, headless: each integrator against what can be derived for it (the
//! analytic spring, orders of convergence, energy, stability limits), the forces and
//! constraints (applied force, friction, speed and stretch limits, XPBD, tearing,
//! self-collision), degenerate input, safe stepping and determinism. The tests of
//! the `report` module's study need the `report` feature.

#[path = "../common/mod.rs"]
mod common;

mod applied_force;
mod colliders;
mod convergence;
mod critical_step_undamped_explicit;
mod degenerate;
mod determinism;
mod energy;
mod energy_check;
#[cfg(feature = "report")]
mod extreme_cases;
mod friction;
mod safe_stepping;
mod self_collision;
mod speed_limit;
mod spring_analytic;
#[cfg(feature = "report")]
mod stability_limits;
mod stretch_limit;
mod tearing;
#[cfg(feature = "report")]
mod work_precision_orders;
mod xpbd;
