//! Observed order of convergence of each integrator on the damped spring: halving
//! dt should divide the error by 2^p; the measured exponent must be within 0.3 of p.

use crate::common::{spring_oscillator, spring_system};
use cloth_sandbox::sim::Integrator;

/// |simulated - analytic| distance of the free mass at t = 2 s.
fn end_error(integrator: Integrator, dt: f64) -> f64 {
    let mut system = spring_system(&[
        &format!("integrator=\"{}\"", integrator.name()),
        &format!("dt={dt}"),
    ]);
    let steps = (2.0 / dt).round() as u64;
    system.run(steps).expect("stable");
    let exact = spring_oscillator(0.1, 9.81);
    (-system.positions()[1].y - exact.distance(system.time())).abs()
}

#[test]
fn observed_orders_match_theory() {
    for integrator in Integrator::ALL {
        // Steps where the error is far above round-off and in the asymptotic range.
        let dt = match integrator.order() {
            4 => 0.02,
            2 => 0.004,
            _ => 0.001,
        };
        let coarse = end_error(integrator, dt);
        let fine = end_error(integrator, dt / 2.0);
        let finer = end_error(integrator, dt / 4.0);
        let observed = ((coarse / fine).log2() + (fine / finer).log2()) / 2.0;
        let expected = integrator.order() as f64;
        assert!(
            {
                eprintln!(
                    "{integrator}: order {observed:.3} ({coarse:.3e} {fine:.3e} {finer:.3e})"
                );
                (observed - expected).abs() < 0.3
            },
            "{integrator}: observed order {observed:.3}, expected {expected} (errors {coarse:.3e}, {fine:.3e}, {finer:.3e})"
        );
    }
}
