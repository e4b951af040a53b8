//! Safe stepping keeps the stiff cloth finite: at k = 1e6 N/m symplectic Euler at the
//! scene's dt blows up, and with the substeps `safe_step` picks it stays finite for 10
//! simulated seconds.

use cloth_sandbox::scene::Scene;
use cloth_sandbox::sim::safe::{DEFAULT_SAFETY, safe_step, safe_substeps};
use cloth_sandbox::sim::{Integrator, System};

fn stiff_cloth() -> System {
    let mut scene = Scene::load("cloth").unwrap();
    scene
        .set_all(["width=6", "height=6", "stiffness=1e6"])
        .unwrap();
    scene.build().unwrap()
}

#[test]
fn stiff_cloth_diverges_without_safe_stepping() {
    let mut system = stiff_cloth();
    assert!(system.run(960).is_err());
}

#[test]
fn stiff_cloth_stays_finite_for_10_seconds_with_safe_stepping() {
    let mut system = stiff_cloth();
    let frame = system.params().dt;
    let choice = safe_step(system.model(), frame, DEFAULT_SAFETY, 100_000);
    assert!(choice.safe && choice.substeps > 1, "{choice:?}");
    assert!(choice.dt <= DEFAULT_SAFETY * choice.dt_critical.unwrap() * (1.0 + 1e-12));
    let mut params = *system.params();
    params.dt = choice.dt;
    system.set_params(params);
    let steps = (10.0 / choice.dt).ceil() as u64;
    system.run(steps).expect("finite for 10 s");
    assert!(system.time() >= 10.0 - 1e-6, "{}", system.time());
    assert!(system.positions().iter().all(|p| p.is_finite()));
}

#[test]
fn substeps_follow_stiffness_mass_and_integrator() {
    let mut system = stiff_cloth();
    let frame = 1.0 / 60.0;
    let stiff = safe_substeps(system.model(), frame, 0.5);
    system.set_spring_stiffness(cloth_sandbox::sim::SpringKind::Structural, 1e2);
    system.set_spring_stiffness(cloth_sandbox::sim::SpringKind::Shear, 1e2);
    system.set_spring_stiffness(cloth_sandbox::sim::SpringKind::Bend, 1e2);
    let soft = safe_substeps(system.model(), frame, 0.5);
    // omega ~ sqrt(k): 1e4 times the stiffness needs about 100 times the substeps.
    let ratio = stiff as f64 / soft as f64;
    assert!((50.0..=200.0).contains(&ratio), "{stiff} vs {soft}");
    system.set_particle_mass(1e-6);
    assert!(safe_substeps(system.model(), frame, 0.5) > soft);
    // Implicit Euler solves for the springs, but steps the wind's drag explicitly:
    // on 1 mg particles in the scene's wind that limits it; in still air nothing
    // does.
    let mut params = *system.params();
    let air_density = params.air_density;
    params.integrator = Integrator::ImplicitEuler;
    system.set_params(params);
    assert!(safe_substeps(system.model(), frame, 0.5) > 1);
    params.air_density = 0.0;
    system.set_params(params);
    assert_eq!(safe_substeps(system.model(), frame, 0.5), 1);
    params.air_density = air_density;
    // Undamped explicit Euler has no stable step: not safe, whatever the substeps.
    params.integrator = Integrator::ExplicitEuler;
    system.set_params(params);
    system.set_spring_damping(cloth_sandbox::sim::SpringKind::Structural, 0.0);
    system.set_spring_damping(cloth_sandbox::sim::SpringKind::Shear, 0.0);
    system.set_spring_damping(cloth_sandbox::sim::SpringKind::Bend, 0.0);
    assert!(!safe_step(system.model(), frame, 0.5, 1000).safe);
}

#[test]
fn safe_step_is_cheap_on_a_large_cloth() {
    let mut scene = Scene::load("cloth").unwrap();
    scene.set_all(["width=256", "height=256"]).unwrap();
    let system = scene.build().unwrap();
    let start = std::time::Instant::now();
    let n = safe_substeps(system.model(), 1.0 / 60.0, 0.5);
    assert!(n >= 1);
    assert!(start.elapsed().as_secs_f64() < 0.5);
}
