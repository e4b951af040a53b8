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

/// The step limit is local (the Gershgorin bound is a maximum over particles of
/// their own springs, and the drag's over their own triangles), so a 256 x 256
/// cloth of the default material gets the substeps of a 16 x 16 one: the fewest
/// that keep each step within `DEFAULT_SAFETY` of the limit. (What the estimate
/// costs on the large cloth is measured by `benches/step.rs`, `safe_substeps`.)
#[test]
fn a_large_cloth_gets_the_substeps_of_a_small_one_of_its_material() {
    let frame = 1.0 / 60.0;
    let step = |n: usize| {
        let mut scene = Scene::load("cloth").unwrap();
        let (width, height) = (format!("width={n}"), format!("height={n}"));
        scene.set_all([width.as_str(), height.as_str()]).unwrap();
        safe_step(scene.build().unwrap().model(), frame, DEFAULT_SAFETY, 1000)
    };
    let (small, large) = (step(16), step(256));
    let limit = DEFAULT_SAFETY * large.dt_critical.unwrap();
    assert!(limit.is_finite() && limit > 0.0, "{large:?}");
    assert_eq!(small.dt_critical, large.dt_critical);
    assert_eq!(small.substeps, large.substeps);
    assert!(large.safe && large.dt <= limit, "{large:?}");
    if large.substeps > 1 {
        assert!(
            frame / (large.substeps - 1) as f64 > limit,
            "{large:?}: not the fewest"
        );
    }
}

/// A running system's step is chosen again at once when the critical step has
/// shrunk so far that the step is over three quarters of it, and, when it had been
/// cut, grows back only after a second of room at every check (under a quarter of
/// it): a cloth flapping in the wind, whose areas swing from frame to frame, does
/// not make the step swing with them.
#[test]
fn the_step_watch_cuts_at_once_and_grows_back_after_a_second_of_room() {
    use cloth_sandbox::sim::safe::StepWatch;
    let safety = DEFAULT_SAFETY;
    let mut watch = StepWatch::default();
    let dt = 1e-3;
    // A step cut from the scene's own, for the second part.
    let scene_dt = 2e-3;
    // Chosen at half of 2e-3; still within three quarters of 1.4e-3, not of 1.3e-3.
    assert!(!watch.outgrown(0.0, (dt, dt), Some(2e-3), safety));
    assert!(!watch.outgrown(0.1, (dt, dt), Some(1.4e-3), safety));
    assert!(watch.outgrown(0.2, (dt, dt), Some(1.3e-3), safety));
    // A cut step with room (critical step over 4 ms) for most of a second, with one
    // frame between that has none: no growing back until a whole second of room.
    let frame = 1.0 / 60.0;
    let mut t = 1.0;
    for k in 0..59 {
        let critical = if k == 30 { 3e-3 } else { 5e-3 };
        assert!(
            !watch.outgrown(t, (dt, scene_dt), Some(critical), safety),
            "{k}"
        );
        t += frame;
    }
    let roomy_from = t - 28.0 * frame;
    while !watch.outgrown(t, (dt, scene_dt), Some(5e-3), safety) {
        t += frame;
        assert!(
            t < roomy_from + 1.0 + 1.5 * frame,
            "not grown back by {t} s"
        );
    }
    assert!(
        t - roomy_from > 1.0 - 0.5 * frame,
        "grown back after {} s",
        t - roomy_from
    );
    // A step that was never cut is not grown, however much room it has.
    assert!(!watch.outgrown(t + 5.0, (dt, dt), Some(1.0), safety));
}

/// The watch kept on a bare system (a recording, `cloth run --safe`) splits the
/// scene's step and never takes a longer one: the peers' cloth in its wind at 32 x
/// 32 has room to spare at the scene's 1/960 s, which stays, while at 128 x 128 on
/// Verlet the step is cut as the cloth stretches.
#[test]
fn following_the_drag_areas_never_lengthens_the_scenes_step() {
    use cloth_sandbox::sim::safe::{StepWatch, follow_areas};
    for (size, integrator, cuts) in [("32", "symplectic-euler", false), ("128", "verlet", true)] {
        let mut scene = Scene::load("bench-wind").unwrap();
        let integrator = format!("integrator=\"{integrator}\"");
        let overrides = [
            format!("width={size}"),
            format!("height={size}"),
            integrator,
        ];
        scene.set_all(overrides.iter().map(String::as_str)).unwrap();
        let mut system = scene.build().unwrap();
        system.set_fast_path(true);
        let scene_dt = system.params().dt;
        let mut watch = StepWatch::default();
        let mut shortest = scene_dt;
        while system.time() < 2.5 {
            let dt = system.params().dt;
            system.run(((1.0 / 60.0) / dt).ceil() as u64).unwrap();
            follow_areas(&mut system, &mut watch, scene_dt);
            let dt = system.params().dt;
            assert!(
                dt <= scene_dt,
                "{size}: {dt} s over the scene's {scene_dt} s"
            );
            shortest = shortest.min(dt);
        }
        assert_eq!(shortest < scene_dt, cuts, "{size}: down to {shortest} s");
    }
}
