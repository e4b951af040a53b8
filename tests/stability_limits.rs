//! Measured critical steps agree with theory (within 10%) for symplectic Euler,
//! Verlet and RK4 on the undamped spring and chain; implicit Euler survives the stiff
//! cloth at 100 times symplectic Euler's limit.

use cloth_sandbox::report::stability::{
    Measured, Theory, critical_dt, is_stable, reference_energy,
};
use cloth_sandbox::report::{cloth_undamped, eigen};
use cloth_sandbox::scene::{Resolved, Scene};
use cloth_sandbox::sim::Integrator;

fn scene(name: &str, overrides: &[&str]) -> Resolved {
    let mut scene = Scene::load(name).unwrap();
    scene.set_all(overrides.iter().copied()).unwrap();
    scene.resolve().unwrap()
}

fn check_case(name: &str, overrides: &[&str]) {
    let s = scene(name, overrides);
    let theory = Theory::of(&s);
    let horizon = 1000.0 * 2.0 / theory.omega_exact;
    let energy = reference_energy(&s, theory.omega_exact, horizon);
    for integrator in [
        Integrator::SymplecticEuler,
        Integrator::Verlet,
        Integrator::Rk4,
    ] {
        let expected = theory.exact(integrator).unwrap();
        let measured = critical_dt(&s, integrator, expected, horizon, energy, (64.0, 256.0), 8);
        let Measured::Between { lo, .. } = measured else {
            panic!("{name} {integrator}: no limit bracketed: {measured:?}");
        };
        let ratio = lo / expected;
        assert!(
            (0.9..=1.1).contains(&ratio),
            "{name} {integrator}: measured {lo:e} s, theory {expected:e} s (ratio {ratio:.3})"
        );
    }
}

#[test]
fn spring_critical_dt_matches_theory() {
    check_case("spring", &["damping=0"]);
}

/// The chain loaded along its length stays straight, so the linearisation at the
/// start holds throughout. (Falling sideways, its pendulum motion modulates the
/// springs and symplectic Euler and Verlet go unstable earlier, near
/// `omega h = sqrt 2`: a nonlinear resonance the report shows, not a linear limit.)
#[test]
fn chain_critical_dt_matches_theory() {
    check_case(
        "chain",
        &[
            "damping=0",
            "air_damping=0",
            "gravity=9.81,0,0",
            "stiffness=1000",
        ],
    );
}

#[test]
fn spring_power_iteration_finds_sqrt_k_over_m() {
    // One free mass on a spring stretched along y: the highest mode is the axial one,
    // omega² = k/m (the transverse one is k (1 - L/l) / m).
    let s = scene("spring", &[]);
    let system = s.build();
    let p = eigen::omega_max(system.model(), system.positions(), 10_000, 1e-12);
    let exact = (s.stiffness / s.particle_mass).sqrt();
    assert!((p.omega_max / exact - 1.0).abs() < 1e-9, "{p:?} vs {exact}");
}

#[test]
fn implicit_euler_is_stable_on_the_stiff_cloth_at_100x_the_symplectic_limit() {
    let mut o = cloth_undamped(8);
    o.push("stiffness=1e6".into());
    let s = scene("cloth", &o.iter().map(String::as_str).collect::<Vec<_>>());
    let theory = Theory::of(&s);
    let symplectic = theory.exact(Integrator::SymplecticEuler).unwrap();
    // The symplectic limit is real: 10% above it symplectic Euler blows up.
    let horizon = 500.0 * symplectic;
    let e = reference_energy(&s, theory.omega_exact, horizon);
    assert!(is_stable(
        &s,
        Integrator::SymplecticEuler,
        0.9 * symplectic,
        horizon,
        e
    ));
    assert!(!is_stable(
        &s,
        Integrator::SymplecticEuler,
        1.1 * symplectic,
        horizon,
        e
    ));
    // 100 times that, over the same horizon and at least 20 steps.
    assert!(is_stable(
        &s,
        Integrator::ImplicitEuler,
        100.0 * symplectic,
        horizon,
        e
    ));
}
