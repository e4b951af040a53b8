//! Regression: undamped, explicit Euler and RK2 have no stable step, and
//! `critical_step` must say so (`None`) rather than return a tiny finite step that
//! passes its round-off tolerance (it returned about 1.4e-6 / omega for explicit Euler
//! and 2e-3 / omega for RK2).

use cloth_sandbox::sim::Integrator;
use cloth_sandbox::sim::stability::{critical_step, estimate};

#[test]
fn undamped_explicit_euler_and_rk2_have_no_stable_step() {
    for omega in [1.0, 5.477, 1.5e5] {
        assert_eq!(critical_step(Integrator::ExplicitEuler, omega, 0.0), None);
        assert_eq!(critical_step(Integrator::Rk2, omega, 0.0), None);
    }
}

#[test]
fn damped_explicit_euler_limit_is_two_zeta_over_omega() {
    // |1 + h lambda|² = 1 - 2 zeta y + y² < 1 for y = omega h < 2 zeta.
    let (omega, zeta) = (10.0, 0.1);
    let h = critical_step(Integrator::ExplicitEuler, omega, zeta).unwrap();
    assert!((h * omega / (2.0 * zeta) - 1.0).abs() < 1e-6, "{h}");
    assert!(critical_step(Integrator::Rk2, omega, zeta).unwrap() > 0.0);
}

#[test]
fn the_app_estimate_reports_no_stable_step_for_undamped_explicit_euler() {
    let mut scene = cloth_sandbox::scene::Scene::load("spring").unwrap();
    scene
        .set_all(["damping=0", "integrator=explicit-euler"])
        .unwrap();
    let s = estimate(scene.build().unwrap().model());
    assert_eq!(s.dt_critical, None);
    assert!(s.margin.is_infinite());
}
