//! The mesh engine against the f64 general engine (the exact reference), on the
//! scenes that are not grids: each run is built twice from the same scene, one
//! allowed the fast path (and taking the mesh engine; the jelly is kept off the
//! lattice kernel, `tests/lattice_kernel.rs`), one exact, and both stepped the
//! same number of steps.
//!
//! Tolerance: both engines compute in f64. The mesh engine evaluates each spring
//! from both of its ends (the two evaluations are exact negations of each other)
//! and sums a particle's springs in the general engine's gather order, then adds
//! air damping, ground and gravity in the same order, so symplectic and explicit
//! Euler agree bit for bit (measured: 0 m). Position Verlet differs in form: the
//! mesh engine keeps the update velocity `u = (x - x_prev)/h` and steps
//! `x += h (u + h a)`, the general engine `x_next = 2x - x_prev + h² a`, so each
//! step rounds differently, by a few ulps of the position. The bound ([`bound`]) is
//! that rounding adding up linearly: 4 ulps of the largest coordinate per step,
//! 2e-12 m for 300 steps of the jelly (coordinates up to 8 m; measured 7e-13 m) and
//! 9e-13 m for 400 steps of the rope (measured 2e-13 m) -- about 1e-12 m, a
//! ten-millionth of the float32 grid kernel's agreement (`tests/fast_path.rs`).

use cloth_sandbox::sim::mesh_kernel::{MeshKernel, MeshParams};
use cloth_sandbox::sim::{Engine, System};
use glam::DVec3;

/// Largest particle distance (m) allowed between the mesh and general engines
/// after `steps` steps of a system whose coordinates reach `scale` m: 4 ulps of
/// `scale` per step (see the module comment).
fn bound(steps: u64, scale: f64) -> f64 {
    steps as f64 * 4.0 * f64::EPSILON * scale
}

/// The largest coordinate (m), for [`bound`].
fn scale(system: &System) -> f64 {
    system
        .positions()
        .iter()
        .map(|p| p.abs().max_element())
        .fold(1.0, f64::max)
}

use crate::common::{build, max_distance};

/// Steps `name` with `overrides` on the mesh engine and on the general engine;
/// returns the largest particle distance and how far the particles moved.
fn mesh_and_exact(name: &str, overrides: &[&str], steps: u64) -> (f64, f64) {
    let mut fast = build(name, overrides);
    fast.set_fast_path(true);
    // Lattices (the jelly) take the lattice kernel unless kept off it.
    fast.refuse_lattice_kernel(true);
    assert_eq!(
        fast.engine(),
        Engine::Mesh,
        "{name} {overrides:?} should take the mesh engine"
    );
    assert!(fast.engine().is_fast() && !fast.engine().is_grid());
    let mut exact = build(name, overrides);
    assert_eq!(exact.engine(), Engine::General);
    let start = exact.positions().to_vec();
    fast.run(steps).unwrap();
    exact.run(steps).unwrap();
    assert_eq!(fast.steps_taken(), exact.steps_taken());
    assert_eq!(fast.time(), exact.time());
    let d = max_distance(fast.positions(), exact.positions());
    let dv = max_distance(fast.velocities(), exact.velocities());
    let moved = max_distance(exact.positions(), &start);
    let bound = bound(
        steps,
        scale(&exact).max(start.iter().fold(0.0, |m, p| m.max(p.abs().max_element()))),
    );
    assert!(
        d <= bound,
        "{name} {overrides:?}: engines differ by {d:e} m after {steps} steps (bound {bound:e} m)"
    );
    // Velocities are m/s over a step of ~1e-3 s: 1e-6 m/s is 1e-9 m a step.
    assert!(
        dv <= 1e-6,
        "{name} {overrides:?}: velocities differ by {dv:e}"
    );
    // Verlet's different rounding shows that the fast run did not take the general
    // path (for the Euler methods the results are identical by design).
    if fast.params().integrator == cloth_sandbox::sim::Integrator::Verlet {
        assert!(
            d > 0.0,
            "{name} {overrides:?}: identical Verlet results: the mesh engine did not run"
        );
    }
    // The run must have done something for the comparison to mean anything.
    assert!(
        moved > 1e-6,
        "{name} {overrides:?}: nothing moved ({moved:e} m)"
    );
    (d, moved)
}

/// The lowest particle height of a scene as built (m).
fn lowest(name: &str, overrides: &[&str]) -> f64 {
    build(name, overrides)
        .positions()
        .iter()
        .map(|p| p.y)
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn the_non_grid_scenes_agree_with_the_f64_engine() {
    for name in ["chain", "jelly", "rope", "spring"] {
        let (d, moved) = mesh_and_exact(name, &[], 400);
        println!("{name}: {d:e} m apart after moving {moved:.3e} m");
    }
}

#[test]
fn xpbd_runs_on_the_mesh_engine_as_on_the_f64_engine() {
    // Every scene that is not a grid, its springs made XPBD's constraints: the same
    // pass in the same order on the same f64 numbers (bit for bit; the bound is the
    // Verlet one, which this pass does not use).
    for name in ["chain", "jelly", "rope", "spring", "tablecloth"] {
        let (d, moved) = mesh_and_exact(name, &["integrator=\"xpbd\""], 400);
        println!("{name} with XPBD: {d:e} m apart after moving {moved:.3e} m");
        assert_eq!(d, 0.0, "{name}");
    }
}

#[test]
fn aerodynamic_drag_in_gusts_runs_on_the_mesh_engine_as_on_the_f64_engine() {
    // Per-triangle drag in a gusting side wind: the tablecloth (a triangle mesh)
    // and seed 001's cloth of bars (a grid, which the grid kernel leaves to the
    // mesh engine for its bars). The same arithmetic in the same order, with the wind at
    // the same times: bit for bit with symplectic Euler, Verlet's rounding with
    // Verlet (over 100 steps: later the cloth flutters, and the flutter doubles the
    // gap every 25 steps or so, measured: 6.1e-14 m at 100 steps, 6.2e-13 m at
    // 200, where the bound allows 1.8e-13 m).
    let wind = [
        "air_density=1.2",
        "drag_coefficient=1",
        "wind=\"3,0,2\"",
        "gust=2",
    ];
    for (name, integrator, steps) in [
        ("tablecloth", "symplectic-euler", 400),
        ("tablecloth", "verlet", 100),
        ("bars", "symplectic-euler", 400),
        ("bars", "verlet", 100),
    ] {
        let integrator = format!("integrator=\"{integrator}\"");
        let mut overrides = wind.to_vec();
        overrides.push(&integrator);
        let mut system = build(name, &overrides);
        system.set_fast_path(true);
        assert_eq!(
            system.engine(),
            Engine::Mesh,
            "{name}: drag on the mesh engine"
        );
        let (d, moved) = mesh_and_exact(name, &overrides, steps);
        println!("{name} in gusts, {integrator}: {d:e} m apart after moving {moved:.3e} m");
        if !integrator.contains("verlet") {
            assert_eq!(d, 0.0, "{name}");
        }
        // The drag changes the run by far more than the engines differ (so a mesh
        // engine that left it out would fail the comparison above).
        let mut still = build(name, &[integrator.as_str()]);
        still.run(steps).unwrap();
        let mut windy = build(name, &overrides);
        windy.run(steps).unwrap();
        let blown = max_distance(still.positions(), windy.positions());
        assert!(
            blown > 1e-5 && blown > 1e6 * d,
            "{name}: the wind moved the particles {blown:e} m"
        );
    }
}

#[test]
fn springs_tear_on_the_mesh_engine_as_on_the_f64_engine() {
    // The tablecloth in a 4 m/s wind with a 10% tear strain: its springs tear over
    // the sphere step after step. The mesh engine breaks them in its own copy of
    // the springs by the f64 engine's rule at the same point of the step, and the
    // model takes the breaks with the state: bit for bit the f64 engine's run,
    // breaks included, also when run ahead of its state 16 steps at a time as the
    // app runs it (the breaks then reach the model when it settles or runs again).
    let overrides = ["tear_strain=0.1", "wind=\"4,0,0\""];
    let mut fast = build("tablecloth", &overrides);
    fast.set_fast_path(true);
    let mut ahead = build("tablecloth", &overrides);
    ahead.set_fast_path(true);
    let mut exact = build("tablecloth", &overrides);
    let springs = exact.springs().len();
    for _ in 0..6 {
        fast.run(96).unwrap();
        for _ in 0..6 {
            ahead.run_ahead(16).unwrap();
        }
        ahead.settle().unwrap();
        exact.run(96).unwrap();
        for system in [&fast, &ahead] {
            assert_eq!(system.engine(), Engine::Mesh);
            assert_eq!(system.broken_springs(), exact.broken_springs());
            assert!(system.springs() == exact.springs());
            assert!(system.positions() == exact.positions());
            assert!(system.velocities() == exact.velocities());
        }
    }
    let broken = exact.broken_springs();
    println!("{broken} of {springs} springs tore in 576 steps");
    assert!(broken > 100, "{broken}");
}

#[test]
fn a_cut_between_runs_reaches_the_mesh_engine() {
    // The user's cut (Ctrl + drag) breaks springs in the model between runs: the
    // mesh engine is rebuilt on the springs left (its springs' order filtered, not
    // sorted again) and goes on as the f64 engine does.
    let mut fast = build("tablecloth", &[]);
    fast.set_fast_path(true);
    let mut exact = build("tablecloth", &[]);
    let cut: Vec<(usize, usize)> = (exact.springs().iter().step_by(7))
        .map(|s| (s.a as usize, s.b as usize))
        .collect();
    for system in [&mut fast, &mut exact] {
        system.run(200).unwrap();
        assert!(system.cut(&cut) > 1000);
        system.run(200).unwrap();
    }
    assert_eq!(fast.engine(), Engine::Mesh);
    assert!(fast.springs() == exact.springs());
    assert!(fast.positions() == exact.positions() && fast.velocities() == exact.velocities());
}

#[test]
fn a_speed_limit_runs_on_the_mesh_engine_as_on_the_f64_engine() {
    // The chain (symplectic Euler) and the rope (Verlet) swing faster than 0.5 m/s
    // within 400 steps; the limit holds them to it on both engines.
    for name in ["chain", "rope"] {
        let limited = ["max_speed=0.5"];
        let (d, moved) = mesh_and_exact(name, &limited, 400);
        println!("{name} at most 0.5 m/s: {d:e} m apart after moving {moved:.3e} m");
        // The fastest particle after 400 steps on the mesh engine.
        let fastest = |overrides: &[&str]| {
            let mut system = build(name, overrides);
            system.set_fast_path(true);
            system.run(400).unwrap();
            let speeds = system.velocities().iter().map(|v| v.length());
            speeds.fold(0.0, f64::max)
        };
        let (held, free) = (fastest(&limited), fastest(&[]));
        assert!(held <= 0.5 * (1.0 + 1e-12), "{name}: {held} m/s");
        assert!(free > 0.6, "{name}: the limit never binds ({free} m/s)");
    }
}

#[test]
fn a_bigger_jelly_agrees_feature_by_feature() {
    let big = ["width=12", "height=12", "depth=12"];
    // On the ground from the start: its lowest particle touching it (a ground
    // above it would have the scene lift the cube clear).
    let ground = format!("ground_height={}", lowest("jelly", &big));
    // A sphere inside the cube: the particles within are pushed out at once.
    let centre = build("jelly", &big)
        .positions()
        .iter()
        .copied()
        .sum::<DVec3>()
        / (12.0 * 12.0 * 12.0);
    let sphere_center = format!("sphere_center=\"{},{},{}\"", centre.x, centre.y, centre.z);
    let tilted = String::from("gravity=\"3,-9.81,0\"");
    let cases: Vec<Vec<String>> = vec![
        vec![],
        vec![ground.clone()],
        vec!["air_damping=0.5".into()],
        vec![sphere_center, "sphere_radius=2.5".into()],
        vec!["integrator=\"verlet\"".into(), ground.clone()],
        vec!["integrator=\"explicit-euler\"".into()],
        vec!["stretch_limit=0.0001".into(), ground.clone()],
        // Friction on a tilted gravity, so that the cube slides or grips.
        vec![ground.clone(), "friction=0.3".into(), tilted.clone()],
        vec![
            "integrator=\"verlet\"".into(),
            ground,
            "friction=0.3".into(),
            tilted,
        ],
    ];
    for extra in cases {
        let overrides: Vec<&str> = big
            .iter()
            .copied()
            .chain(extra.iter().map(String::as_str))
            .collect();
        let (d, moved) = mesh_and_exact("jelly", &overrides, 300);
        println!("jelly {extra:?}: {d:e} m apart after moving {moved:.3e} m");
    }
}

#[test]
fn a_jelly_big_enough_for_threads_agrees_with_the_f64_engine() {
    // 16³ = 4096 particles: past the size from which `System::run` uses threads
    // (`mesh_kernel::PARALLEL_MIN_PARTICLES`; the 12³ jelly above is too).
    let (d, _) = mesh_and_exact("jelly", &["width=16", "height=16", "depth=16"], 100);
    println!("jelly 16³: {d:e} m");
}

/// Positions and velocities after `steps` steps of the mesh engine on `threads`
/// threads (forced, whatever the size).
fn kernel_run(system: &System, threads: usize, steps: usize) -> (Vec<DVec3>, Vec<DVec3>) {
    let params = MeshParams::of(system.model()).expect("the mesh engine models it");
    let mut kernel = MeshKernel::new(system.model(), params);
    kernel.set_threads_from(threads, 0);
    assert_eq!(kernel.is_parallel(), threads > 1);
    kernel.set_state(system.positions(), system.velocities());
    kernel.steps(steps);
    let n = system.particle_count();
    let (mut x, mut v) = (vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
    kernel.positions_into(&mut x);
    kernel.velocities_into(&mut v);
    (x, v)
}

#[test]
fn one_and_two_threads_give_identical_results() {
    for (name, overrides) in [
        ("jelly", &["width=12", "height=12", "depth=12"][..]),
        (
            "jelly",
            &["width=12", "height=12", "depth=12", "integrator=\"verlet\""][..],
        ),
        ("chain", &["width=3000"][..]),
        ("rope", &[][..]),
        // Its drag's triangle pass split over the threads too.
        ("tablecloth", &["wind=\"3,0,2\"", "gust=2"][..]),
    ] {
        let system = build(name, overrides);
        let one = kernel_run(&system, 1, 200);
        let two = kernel_run(&system, 2, 200);
        assert!(one == two, "{name} {overrides:?}: 1 and 2 threads differ");
    }
}

#[test]
fn edits_between_runs_reach_the_mesh_engine() {
    let mut fast = build("chain", &[]);
    fast.set_fast_path(true);
    let mut exact = build("chain", &[]);
    for system in [&mut fast, &mut exact] {
        system.run(100).unwrap();
        system.set_pinned(10, true);
        system.run(100).unwrap();
        system.set_spring_stiffness(cloth_sandbox::sim::SpringKind::Other, 300.0);
        system.grab(5, DVec3::new(1.0, 2.0, 0.0));
        system.run(100).unwrap();
        system.release();
        system.set_pinned(10, false);
        system.set_particle_mass(0.25);
        system.run(100).unwrap();
    }
    assert_eq!(fast.engine(), Engine::Mesh);
    // Symplectic Euler: bit for bit.
    let d = max_distance(fast.positions(), exact.positions());
    assert!(d <= bound(400, scale(&exact)), "{d:e} m");
}

#[test]
fn what_the_mesh_engine_does_not_model_runs_on_the_general_path() {
    for (name, overrides) in [
        ("jelly", &["integrator=\"rk4\""][..]),
        ("chain", &["integrator=\"rk2\""][..]),
        ("rope", &["integrator=\"implicit-euler\""][..]),
    ] {
        let mut system = build(name, overrides);
        system.set_fast_path(true);
        assert_eq!(system.engine(), Engine::General, "{name} {overrides:?}");
        system.run(10).unwrap();
    }
}

#[test]
fn a_divergence_on_the_mesh_engine_is_caught_where_the_f64_engine_catches_it() {
    // Explicit Euler at 10x the jelly's step: unstable, it runs away within a few
    // hundred steps. Both engines compute the same numbers, so both stop at the
    // same check; the mesh engine checks at the end of each chunk of 32 steps (or of
    // the run), the general engine after every step, so the mesh engine stops at
    // most 31 steps later, and no later than the run's end.
    let overrides = ["integrator=\"explicit-euler\"", "dt=0.002"];
    let mut fast = build("jelly", &overrides);
    fast.set_fast_path(true);
    fast.refuse_lattice_kernel(true);
    assert_eq!(fast.engine(), Engine::Mesh);
    let mut exact = build("jelly", &overrides);
    let fast_err = fast.run(20_000).unwrap_err();
    let exact_err = exact.run(20_000).unwrap_err();
    let (f, e) = (fast.steps_taken(), exact.steps_taken());
    assert!(
        f >= e && f < e + 32,
        "mesh stopped at step {f} ({fast_err}), general at {e} ({exact_err})"
    );
}
