//! XPBD against what can be derived for it.
//!
//! With one constraint iteration per step from `λ = 0`, a spring of stiffness k
//! between masses of inverse masses summing to `w` moves its ends as a spring of
//! stiffness `k / (1 + k h² w)` would over the step (`Δλ = -C / (w + 1/(k h²))`).
//! So at rest XPBD hangs like the spring cloth up to a relative stiffness error
//! `k h² w`, which vanishes as `h²`: the drapes must agree better and better as the
//! substeps grow. At high k the one iteration per substep cannot converge: the
//! cloth stretches by the error of one Gauss-Seidel sweep per substep, which falls
//! as the substeps grow (Macklin et al. 2019, "Small Steps in Physics Simulation"),
//! whatever k is; nothing ever blows up.

mod common;

use cloth_sandbox::sim::System;
use common::{build, max_distance};

/// The default cloth without wind, a little air damping to let it settle, at
/// `substeps` steps per 1/60 s frame, stiffness `k`, with `integrator`, on the fast
/// engine.
fn cloth(integrator: &str, k: f64, substeps: u32) -> System {
    let dt = 1.0 / 60.0 / f64::from(substeps);
    let mut system = build(
        "cloth",
        &[
            &format!("integrator=\"{integrator}\""),
            &format!("stiffness={k}"),
            &format!("dt={dt}"),
            "wind=\"0,0,0\"",
            "gust=0",
            "air_damping=0.002",
        ],
    );
    system.set_fast_path(true);
    system
}

fn settle(system: &mut System, seconds: f64) {
    let steps = (seconds / system.params().dt).round() as u64;
    system.run(steps).unwrap();
}

/// Largest strain `(l - L) / L` over the springs.
fn largest_strain(system: &System) -> f64 {
    let x = system.positions();
    (system.springs().iter())
        .map(|s| ((x[s.a as usize] - x[s.b as usize]).length() - s.rest) / s.rest)
        .fold(0.0, f64::max)
}

#[test]
fn at_moderate_stiffness_xpbd_hangs_like_the_springs_and_closer_with_more_substeps() {
    // k = 100 N/m, m = 1 g: k h² w = 0.15 at 16 substeps, 0.01 at 64.
    let mut apart = Vec::new();
    for substeps in [16, 64] {
        let mut xpbd = cloth("xpbd", 100.0, substeps);
        let mut springs = cloth("symplectic-euler", 100.0, substeps);
        assert!(xpbd.engine().is_grid() && springs.engine().is_grid());
        settle(&mut xpbd, 4.0);
        settle(&mut springs, 4.0);
        let d = max_distance(xpbd.positions(), springs.positions());
        println!("{substeps} substeps: drapes {d:.3e} m apart");
        apart.push(d);
    }
    // Measured: 4.7e-3 and 4.1e-4 m on a 1.55 m cloth that sags 5 cm.
    assert!(apart[1] < 1e-3, "{apart:?}");
    // Four times the substeps: at least four times closer (first order; h² in theory).
    assert!(apart[1] < apart[0] / 4.0, "{apart:?}");
}

#[test]
fn at_high_stiffness_the_strain_falls_as_the_substeps_grow_and_nothing_blows_up() {
    for k in [1e5, 1e9] {
        let mut strains = Vec::new();
        for substeps in [5, 10, 20, 50] {
            let mut system = cloth("xpbd", k, substeps);
            settle(&mut system, 2.0);
            let strain = largest_strain(&system);
            let speed = (system.velocities().iter())
                .map(|v| v.length())
                .fold(0.0, f64::max);
            println!("k = {k:e}, {substeps} substeps: strain {strain:.3e}, speed {speed:.3e}");
            // Nothing in a 1.55 m cloth hanging from its corners moves faster than
            // a fall over its own size, sqrt(2 g 1.55 m) = 5.5 m/s.
            let fall = (2.0 * 9.81 * 1.55f64).sqrt();
            assert!(
                speed < fall,
                "k = {k:e}, {substeps} substeps: speed {speed}"
            );
            strains.push(strain);
        }
        // Measured at both k: 0.32, 0.087, 0.022, 0.004 to 0.007.
        assert!(
            strains.windows(2).all(|w| w[1] < 0.6 * w[0]),
            "k = {k:e}: {strains:?}"
        );
        assert!(strains[3] < 0.01, "k = {k:e}: {strains:?}");
    }
}

#[test]
fn xpbd_has_no_step_limit_from_the_springs() {
    let system = cloth("xpbd", 1e9, 16);
    let stability = system.stability();
    assert_eq!(stability.margin, 0.0);
    assert_eq!(stability.dt_critical, Some(f64::INFINITY));
    // The springs are constraints, not a force term.
    assert!(!system.force_terms().springs);
}

#[test]
fn xpbd_on_a_penalty_ground_has_the_grounds_step_limit() {
    // XPBD predicts with symplectic Euler under every force but the springs, so
    // the jelly's ground (k_c = 50,000 N/m under 0.1 kg particles, no air damping)
    // sets its limit: 2 / sqrt(k_c / m) = 2.828e-3 s. Safe stepping splits a
    // 1/60 s frame by it and the dropped jelly comes to rest on the ground; whole
    // frames run away on the first bounce.
    use cloth_sandbox::sim::safe;
    let jelly = |dt: f64| {
        let mut system = build("jelly", &["integrator=\"xpbd\"", &format!("dt={dt}")]);
        system.set_fast_path(true);
        system
    };
    let frame = 1.0 / 60.0;
    let system = jelly(frame);
    let limit = 2.0 / (50_000.0f64 / 0.1).sqrt();
    let critical = system.stability().dt_critical.unwrap();
    assert!(
        (critical - limit).abs() <= 1e-12 * limit,
        "{critical} s, not the ground's {limit} s"
    );
    let step = safe::safe_step(system.model(), frame, safe::DEFAULT_SAFETY, 1 << 20);
    assert!(step.safe && step.dt <= 0.5 * limit, "{step:?}");
    let mut safe = jelly(step.dt);
    safe.run((10.0 / step.dt).round() as u64).unwrap();
    let kinetic = safe.energy().kinetic;
    println!("safe steps of {:.3e} s: {kinetic:e} J after 10 s", step.dt);
    assert!(kinetic < 0.01, "{kinetic} J after 10 s");
    let mut whole = jelly(frame);
    assert!(whole.run(600).is_err(), "whole frames held on the ground");
}

/// The classes of independent springs that a system's constraint order falls
/// into, counted by walking the order and starting a new class whenever a spring
/// touches a particle the current class already moved (each spring once).
fn independent_classes(system: &System) -> usize {
    let model = system.model();
    assert_eq!(model.constraint_order.len(), model.springs.len());
    let mut seen = vec![false; model.springs.len()];
    let mut touched = vec![usize::MAX; system.particle_count()];
    let mut classes = 0;
    for &i in &model.constraint_order {
        assert!(
            !std::mem::replace(&mut seen[i as usize], true),
            "spring {i} twice"
        );
        let s = &model.springs[i as usize];
        let (a, b) = (s.a as usize, s.b as usize);
        if classes == 0 || touched[a] == classes || touched[b] == classes {
            classes += 1;
        }
        touched[a] = classes;
        touched[b] = classes;
    }
    classes
}

/// XPBD's spring order on a grid falls into 12 classes (6 stencil directions, 2
/// parities) in which no two springs share a particle, and on a lattice into 26
/// (13 directions, 2 parities), so that each class can be corrected in any
/// order with the same result: the fast engines' lanes and the f64 engine's one
/// spring at a time.
#[test]
fn xpbd_visits_a_grid_in_twelve_classes_and_a_lattice_in_26() {
    assert_eq!(independent_classes(&cloth("xpbd", 100.0, 16)), 12);
    for size in ["5", "6"] {
        let sizes = ["width", "height", "depth"].map(|k| format!("{k}={size}"));
        let overrides: Vec<&str> = sizes.iter().map(String::as_str).collect();
        let jelly = build(
            "jelly",
            &[&overrides[..], &["integrator=\"xpbd\""]].concat(),
        );
        assert_eq!(independent_classes(&jelly), 26, "jelly {size}³");
    }
}
