//! The `spring` scene against the analytic damped oscillator, for every integrator.
//! The tolerance follows from the order: the global error of an order-p method is
//! `C (w h)^p` times the amplitude, with C of order `w T` for the duration T; we
//! allow `A (w h)^p (1 + w T)` with amplitude A, and check that halving dt cuts
//! the error as the order says (so a loose constant cannot hide a wrong method).

use crate::common;

use crate::common::{max_spring_error, spring_oscillator};
use cloth_sandbox::sim::Integrator;

#[test]
fn every_integrator_follows_the_analytic_damped_oscillator() {
    let exact = spring_oscillator(0.1, 9.81);
    let duration = 3.0;
    let amplitude = exact.u0.abs();
    for integrator in Integrator::ALL {
        let dt = 1e-3;
        let p = integrator.order() as i32;
        let tolerance = amplitude * (exact.w * dt).powi(p) * (1.0 + exact.w * duration);
        let error = max_spring_error(integrator.name(), dt, duration);
        assert!(
            error < tolerance,
            "{integrator}: max error {error:.3e} m exceeds {tolerance:.3e} m at dt = {dt}"
        );
        // And it is not trivially small: a real discretisation error of that order.
        assert!(
            error > 1e-3 * tolerance,
            "{integrator}: error {error:.3e} suspiciously small"
        );
    }
}

#[test]
fn the_spring_scene_has_the_seed_parameters() {
    let system = common::spring_system(&[]);
    assert_eq!(system.particle_count(), 2);
    assert!(system.is_pinned(0) && !system.is_pinned(1));
    let s = system.springs()[0];
    let m = system.model().material(s.kind);
    assert_eq!((s.rest, m.stiffness), (5.0, 15.0));
    assert!((m.damping - 0.1 * 2.0 * (15.0f64 * 0.5).sqrt()).abs() < 1e-12);
    assert_eq!(system.masses()[1], 0.5);
}
