//! Degenerate input stays finite over many steps, with every integrator:
//! coincident particles, zero rest length, zero-area triangles, 1x1 and 2x1 cloths,
//! zero and huge wind. Explicit Euler and RK2 are unstable on a lightly damped cloth
//! at the scene's step (their limit is about `2 zeta / omega`, 2e-4 s here), so they
//! run at a step they can take: the point is the degenerate input, not the step.

use cloth_sandbox::scene::Scene;
use cloth_sandbox::sim::Integrator;

fn assert_finite_for(steps: u64, overrides: &[&str]) {
    for integrator in Integrator::ALL {
        let mut scene = Scene::load("cloth").unwrap();
        scene.set_all(overrides.iter().copied()).unwrap();
        scene
            .set("integrator", &format!("\"{}\"", integrator.name()))
            .unwrap();
        if matches!(integrator, Integrator::ExplicitEuler | Integrator::Rk2)
            && !overrides.iter().any(|o| o.starts_with("dt="))
        {
            scene.set("dt", "5e-5").unwrap();
        }
        let mut system = scene.build().unwrap();
        for step in 0..steps {
            if let Err(e) = system.step() {
                panic!("{integrator} with {overrides:?}: {e} at step {step}");
            }
            assert!(
                system
                    .positions()
                    .iter()
                    .chain(system.velocities())
                    .all(|v| v.is_finite()),
                "{integrator} with {overrides:?}: non-finite at step {step}"
            );
        }
    }
}

#[test]
fn coincident_particles_with_zero_rest_length_and_zero_area_triangles() {
    // rest_length = 0 puts every particle at one point: zero-length springs and
    // zero-area triangles everywhere, in a wind.
    assert_finite_for(
        2_000,
        &["width=6", "height=6", "rest_length=0", "pins=none"],
    );
    assert_finite_for(
        2_000,
        &[
            "width=6",
            "height=6",
            "rest_length=0",
            "pins=corners",
            "wind=10,0,5",
        ],
    );
}

#[test]
fn one_by_one_and_two_by_one_cloths() {
    assert_finite_for(2_000, &["width=1", "height=1"]);
    assert_finite_for(2_000, &["width=1", "height=1", "pins=none"]);
    assert_finite_for(2_000, &["width=2", "height=1", "pins=none"]);
    assert_finite_for(2_000, &["width=1", "height=2", "pins=[0]"]);
}

#[test]
fn zero_and_huge_wind() {
    assert_finite_for(2_000, &["width=10", "height=10", "wind=0,0,0", "gust=0"]);
    // 100 m/s is a dynamic pressure of 6 kPa: a cloth must be stiff enough to carry
    // it (the default k = 100 N/m stretches metres and whips until it runs away,
    // which `check` reports; see the report's extreme cases).
    let huge = [
        "width=10",
        "height=10",
        "wind=0,0,100",
        "gust=20",
        "stiffness=1000",
        "damping=0.2",
        "dt=1e-4",
    ];
    assert_finite_for(2_000, &huge);
}

#[test]
fn a_flat_cloth_edge_on_to_the_wind_gets_no_force() {
    // Wind in the cloth's plane: v_rel · n = 0 for every triangle at the start.
    let mut scene = Scene::load("cloth").unwrap();
    scene
        .set_all([
            "gravity=0,0,0",
            "wind=30,0,0",
            "gust=0",
            "pins=none",
            "width=5",
            "height=5",
        ])
        .unwrap();
    let mut system = scene.build().unwrap();
    let start = system.positions().to_vec();
    system.run(100).unwrap();
    // Only round-off moves it (rest lengths and positions differ in the last bits);
    // a drag that pushed along the wind would move it by centimetres.
    let moved = system
        .positions()
        .iter()
        .zip(&start)
        .map(|(a, b)| a.distance(*b))
        .fold(0.0, f64::max);
    assert!(moved < 1e-12, "moved {moved:e} m");
}
