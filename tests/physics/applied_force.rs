//! Seed 001's force vector (`force`, N on every particle) and its cloth of rigid
//! bars (the `bars` scene).
//!
//! A constant force `F` on a particle of mass `m` is, for its motion, gravity
//! `F / m`: the same run with gravity swapped for that force must end in the same
//! place, on every engine. Its potential `-F·x` is counted in the energy, so an
//! undamped system under it keeps its energy as it keeps it under gravity.

use crate::common::{build, max_distance};
use cloth_sandbox::scene::{Pins, Scene};
use glam::DVec3;

#[test]
fn a_force_moves_the_cloth_as_gravity_of_force_over_mass_does() {
    // The cloth scene's particles weigh 1 g: 9.81 mN of force is Earth's gravity.
    for fast in [true, false] {
        let run = |overrides: &[&str]| {
            let mut system = build("cloth", overrides);
            system.set_fast_path(fast);
            system.run(960).unwrap();
            system
        };
        let by_gravity = run(&["gravity=0,-9.81,0"]);
        let by_force = run(&["gravity=0,0,0", "force=0,-0.00981,0"]);
        let gap = max_distance(by_gravity.positions(), by_force.positions());
        println!("fast {fast}: {:?}, gap {gap:.2e} m", by_force.engine());
        assert!(by_force.force_terms().applied && !by_force.force_terms().gravity);
        assert!(gap < 1e-9, "{gap}");
    }
}

#[test]
fn an_undamped_spring_under_a_force_keeps_its_energy() {
    // The spring scene without damping or gravity, pulled sideways and down by a
    // force: the mass swings about its new equilibrium with energy (kinetic,
    // elastic and the force's -F·x) constant to symplectic Euler's bounded swing.
    let mut system = build(
        "spring",
        &["damping=0", "gravity=0,0,0", "force=2,-3,0", "dt=0.001"],
    );
    let e0 = system.energy().total();
    let mut worst: f64 = 0.0;
    for _ in 0..200 {
        system.run(50).unwrap();
        worst = worst.max((system.energy().total() - e0).abs());
    }
    // Scale: the force times the distance it moves the mass (about 0.5 m).
    let scale = DVec3::new(2.0, -3.0, 0.0).length() * 0.5;
    println!("energy swing {worst:.3e} J against a scale of {scale:.2} J");
    assert!(worst < 0.01 * scale, "{worst}");
    // The force did move the mass (without its potential in the energy, that
    // move would show as a drift of the order of the scale).
    let moved = system.positions()[1] - build("spring", &["damping=0"]).positions()[1];
    assert!(moved.length() > 0.1);
}

#[test]
fn seed_001_cloth_of_bars_has_the_seeds_shape_and_holds_its_bars() {
    let system = build("bars", &[]);
    let p = system.params();
    // "every fourth point of the first column locked": rows 0, 4, 8, ... of column 0.
    let w = 20;
    let pinned: Vec<usize> = (0..system.particle_count())
        .filter(|&i| system.is_pinned(i))
        .collect();
    let expected: Vec<usize> = (0..20).step_by(4).map(|r| r * w).collect();
    assert_eq!(pinned, expected);
    // Structural and both diagonal bars, no springs: 2 w (w - 1) + 2 (w - 1)².
    assert_eq!(system.springs().len(), 0);
    assert_eq!(system.bars().len(), 2 * w * (w - 1) + 2 * (w - 1) * (w - 1));
    assert_eq!(p.integrator.name(), "verlet");
    assert_eq!(p.bar_iterations, 8);
    // The seed's force on every 1 kg point.
    assert_eq!(p.force, DVec3::new(165.0, -15.0, 36.0));
    assert_eq!(system.masses()[0], 1.0);

    // The bars are relaxed, not solved: under the seed's strong force the
    // Gauss-Seidel passes leave a strain that shrinks as the passes grow.
    let worst_strain = |iterations: &str, fast: bool| {
        let mut system = build("bars", &[iterations]);
        system.set_fast_path(fast);
        system.run(5 * 960).unwrap();
        let x = system.positions();
        let worst = system
            .bars()
            .iter()
            .map(|b| ((x[b.a as usize].distance(x[b.b as usize]) - b.length) / b.length).abs())
            .fold(0.0, f64::max);
        // The force's z part carried the cloth out of its plane (it starts laid
        // out along x, which the x part keeps it); the locked points stay.
        let mean = x.iter().copied().sum::<DVec3>() / x.len() as f64;
        assert!(mean.z > 0.05, "{mean}");
        for &i in &expected {
            assert_eq!(x[i], build("bars", &[]).positions()[i]);
        }
        println!(
            "{iterations} fast {fast} ({:?}): worst bar strain {worst:.2e}",
            system.engine()
        );
        worst
    };
    for fast in [true, false] {
        let strains = ["bar_iterations=4", "bar_iterations=8", "bar_iterations=32"]
            .map(|n| worst_strain(n, fast));
        assert!(
            strains[0] > strains[1] && strains[1] > strains[2],
            "{strains:?}"
        );
        assert!(strains[1] < 0.05, "{strains:?}");
    }
}

#[test]
fn bars_on_a_grid_only_and_bar_iterations_need_bars() {
    let mut scene = Scene::load("chain").unwrap();
    let message = scene.set("bars", "true").unwrap_err().to_string();
    assert!(message.contains("bars"), "{message}");
    let mut scene = Scene::load("cloth").unwrap();
    let message = scene.set("bar_iterations", "4").unwrap_err().to_string();
    assert!(message.contains("bars = true"), "{message}");
    let mut scene = Scene::load("bars").unwrap();
    scene.set("bar_iterations", "4").unwrap();
    assert!(matches!(scene.spec.pins, Some(Pins::Preset(_))));
}
