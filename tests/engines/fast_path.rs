//! The grid fast path: `System::run` on the f32 stencil kernel agrees with the f64
//! general path to float32 round-off, falls back to the general path for anything
//! the kernel does not model, and honours pins and grabs made between runs.

use cloth_sandbox::sim::grid_kernel::Precision;
use cloth_sandbox::sim::{Engine, System};
use glam::DVec3;

use crate::common::{build, max_distance};

fn fast_and_exact(name: &str, overrides: &[&str], steps: u64) -> (System, System) {
    let mut fast = build(name, overrides);
    fast.set_fast_path(true);
    assert!(
        fast.engine().is_grid(),
        "{name} {overrides:?} should take the grid kernel"
    );
    let mut exact = build(name, overrides);
    assert_eq!(exact.engine(), Engine::General);
    fast.run(steps).unwrap();
    exact.run(steps).unwrap();
    assert_eq!(fast.steps_taken(), exact.steps_taken());
    assert_eq!(fast.time(), exact.time());
    (fast, exact)
}

#[test]
fn the_bench_scenes_agree_with_the_f64_path() {
    // One simulated second of the peers' scene; float32 over 960 steps.
    for name in ["bench", "bench-wind"] {
        let (fast, exact) = fast_and_exact(name, &[], 960);
        let d = max_distance(fast.positions(), exact.positions());
        assert!(d < 2e-5, "{name}: fast and exact differ by {d:e} m");
        assert!(
            d > 0.0,
            "{name}: identical results would mean the kernel did not run"
        );
    }
    // Other shapes, a kind left out (no shear springs) and a grid too narrow for
    // horizontal bend springs.
    for overrides in [
        &["width=96", "height=80"][..],
        &["shear_scale=0"][..],
        &["width=2", "height=40"][..],
    ] {
        let (fast, exact) = fast_and_exact("bench", overrides, 200);
        let d = max_distance(fast.positions(), exact.positions());
        assert!(d < 2e-5, "{overrides:?}: {d:e} m");
    }
}

#[test]
fn windy_cloths_agree_particle_by_particle_early_and_on_average_later() {
    let mean =
        |s: &System| s.positions().iter().copied().sum::<DVec3>() / s.particle_count() as f64;
    for name in ["cloth", "flag"] {
        // Early on, the two paths differ by float32 round-off.
        let (fast, exact) = fast_and_exact(name, &[], 50);
        let early = max_distance(fast.positions(), exact.positions());
        assert!(early < 1e-6, "{name}: {early:e} m after 50 steps");
    }
    // Flapping in the wind amplifies the round-off each step adds, so single
    // particles part (6e-5 m after 300 steps on the cloth, 2e-3 m on the gusty flag,
    // whose flapping is chaotic and parts entirely within a second), while the cloth
    // as a whole agrees: its mean position and its energy.
    for (name, steps, mean_tol, energy_tol) in
        [("cloth", 960, 1e-5, 1e-5), ("flag", 300, 1e-4, 1e-3)]
    {
        let (fast, exact) = fast_and_exact(name, &[], steps);
        let d = mean(&fast).distance(mean(&exact));
        assert!(d < mean_tol, "{name}: mean positions differ by {d:e} m");
        let (ef, ee) = (fast.energy().total(), exact.energy().total());
        assert!(
            (ef - ee).abs() < energy_tol * ee.abs(),
            "{name}: energy {ef} vs {ee}"
        );
    }
}

#[test]
fn what_the_kernel_does_not_model_runs_on_the_general_path() {
    for (name, overrides) in [
        ("cloth", &["integrator=\"rk4\""][..]),
        ("cloth", &["integrator=\"rk2\""][..]),
        ("cloth", &["integrator=\"implicit-euler\""][..]),
        ("jelly", &["integrator=\"rk4\""][..]),
        ("rope", &["integrator=\"implicit-euler\""][..]),
    ] {
        let mut system = build(name, overrides);
        system.set_fast_path(true);
        assert_eq!(system.engine(), Engine::General, "{name} {overrides:?}");
        system.run(10).unwrap();
    }
    // Topologies that are not grids take the general engine, but lattices the
    // lattice kernel (`tests/lattice_kernel.rs`).
    for name in ["chain", "jelly", "rope", "spring"] {
        let mut system = build(name, &[]);
        system.set_fast_path(true);
        system.refuse_lattice_kernel(true);
        assert_eq!(system.engine(), Engine::General, "{name}");
        assert!(!system.engine().is_fast());
        system.run(10).unwrap();
    }
    // What the kernel models since the engine took in the panel's controls.
    for (name, overrides) in [
        ("cloth", &["integrator=\"verlet\""][..]),
        ("cloth", &["integrator=\"explicit-euler\""][..]),
        ("cloth", &["stretch_limit=0.1"][..]),
        ("cloth", &["air_damping=0.1"][..]),
        ("cloth", &["ground_height=-1"][..]),
        ("sheet", &[][..]),
        ("drape", &[][..]),
    ] {
        let mut system = build(name, overrides);
        system.set_fast_path(true);
        assert!(system.engine().is_grid(), "{name} {overrides:?}");
    }
    // A spring whose stiffness differs from its kind's breaks uniformity.
    let mut system = build("bench", &[]);
    system.set_fast_path(true);
    system.set_spring_stiffness(cloth_sandbox::sim::SpringKind::Shear, 1.0);
    assert!(system.engine().is_grid(), "a whole kind may change");
}

#[test]
fn pins_and_grabs_between_runs_reach_the_kernel() {
    let mut fast = build("bench", &[]);
    fast.set_fast_path(true);
    let mut exact = build("bench", &[]);
    for system in [&mut fast, &mut exact] {
        system.run(100).unwrap();
        system.set_pinned(500, true);
        system.grab(1000, DVec3::new(0.5, 0.2, 0.3));
        system.run(100).unwrap();
    }
    assert_eq!(fast.positions()[1000], DVec3::new(0.5, 0.2, 0.3));
    let held = exact.positions()[500];
    assert!(fast.positions()[500].distance(held) < 1e-6);
    assert!(max_distance(fast.positions(), exact.positions()) < 1e-4);
    fast.release();
    fast.run(50).unwrap();
    assert_ne!(
        fast.positions()[1000],
        DVec3::new(0.5, 0.2, 0.3),
        "released, it moves again"
    );
}

#[test]
fn a_divergence_on_the_kernel_is_caught() {
    let mut system = build("cloth", &["stiffness=100000", "gust=0"]);
    system.set_fast_path(true);
    assert_eq!(
        system.engine(),
        Engine::Grid(Precision::Double),
        "k = 1e5 N/m needs float64"
    );
    let err = system.run(2_000).unwrap_err();
    assert!(err.time() < 2.0, "{err}");
}
