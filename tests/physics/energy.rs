//! With no damping and no external force, symplectic Euler keeps the energy of the
//! spring bounded (it conserves a shadow energy), while explicit Euler's grows every
//! step (its amplification is `sqrt(1 + w² h²) > 1`).

use crate::common::spring_system;
use cloth_sandbox::sim::Divergence;

fn energy_history(integrator: &str, steps: usize) -> Vec<f64> {
    let mut system = spring_system(&[
        &format!("integrator=\"{integrator}\""),
        "damping=0",
        "gravity=0,0,0",
        "dt=0.01",
    ]);
    let mut history = vec![system.energy().total()];
    for _ in 0..steps {
        // The energy check may flag explicit Euler's growth (it is a divergence);
        // the step is taken all the same, and the growth law is what is tested here.
        match system.step() {
            Ok(()) | Err(Divergence::EnergyGrowth { .. }) => {}
            Err(other) => panic!("{other}"),
        }
        history.push(system.energy().total());
    }
    history
}

#[test]
fn symplectic_euler_energy_stays_bounded_over_100k_steps() {
    let history = energy_history("symplectic-euler", 100_000);
    let e0 = history[0];
    let worst = history
        .iter()
        .map(|e| (e - e0).abs() / e0)
        .fold(0.0, f64::max);
    // The shadow-energy oscillation is O(w h) = 0.055 relative; no drift on top.
    assert!(worst < 0.06, "relative energy excursion {worst:.4}");
    let last_tenth = &history[90_000..];
    let late = last_tenth
        .iter()
        .map(|e| (e - e0).abs() / e0)
        .fold(0.0, f64::max);
    assert!(late < 0.06, "energy drifted late in the run: {late:.4}");
}

#[test]
fn explicit_euler_energy_grows() {
    let history = energy_history("explicit-euler", 2_000);
    let e0 = history[0];
    // Energy scales by (1 + w² h²) per step: after 2000 steps about e^{0.6 * 2000 * 0.003}.
    let growth = history[2_000] / e0;
    let expected = (1.0 + 30.0 * 1e-4f64).powi(2_000);
    assert!(
        growth > 0.5 * expected && growth < 2.0 * expected,
        "growth {growth:.3}, theory {expected:.3}"
    );
    assert!(
        history.windows(200).all(|w| w[199] > w[0]),
        "energy must keep growing"
    );
}
