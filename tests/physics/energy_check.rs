//! The energy check (`sim::energy_budget`): runs past a stability limit are caught
//! even when nothing overflows, and no stable run is flagged.
//!
//! The limits are derived here, not taken from the code under test: the spring
//! scene's free mass m on a spring k (its fixed end pinned) oscillates along the
//! spring at `w = sqrt(k/m)`; on `x'' = -w² x` RK4 is stable for `h w < 2√2`,
//! symplectic Euler and Verlet for `h w < 2`, and explicit Euler with damping
//! ratio `zeta` for `h w < 2 zeta`.

use crate::common::build;
use cloth_sandbox::scene::{Scene, builtin_scenes};
use cloth_sandbox::sim::{Divergence, SpringKind, System};

const M: f64 = 0.5;
const K: f64 = 15.0;

fn omega() -> f64 {
    (K / M).sqrt()
}

/// The spring scene with `integrator`, undamped unless `damping_ratio` is given,
/// at `fraction` of the step limit `limit_hw / w`.
fn spring(integrator: &str, damping_ratio: f64, limit_hw: f64, fraction: f64) -> System {
    let dt = fraction * limit_hw / omega();
    build(
        "spring",
        &[
            &format!("integrator=\"{integrator}\""),
            &format!("damping_ratio={damping_ratio}"),
            &format!("dt={dt}"),
        ],
    )
}

/// Steps until the first divergence (`None`: none in `steps`).
fn first_divergence(system: &mut System, steps: u64) -> Option<Divergence> {
    (0..steps).find_map(|_| system.step().err())
}

#[test]
fn an_undamped_spring_a_little_past_rk4s_limit_is_caught_though_nothing_overflows() {
    for fraction in [1.01, 1.02, 1.05] {
        let mut system = spring("rk4", 0.0, 2.0 * 2f64.sqrt(), fraction);
        // RK4 grows the swing by |R(i h w)| (1.15 a step at 1.02) until the mass
        // swings past the pin, where the spring's force turns and the motion
        // stays bounded but chaotic: whether a given 1024-step check finds the
        // energy over its budget then depends on round-off (1.02 is caught at
        // step 2048 or at 4096), so the run is given eight checks.
        let caught = first_divergence(&mut system, 8192)
            .unwrap_or_else(|| panic!("RK4 at {fraction} of its limit was not caught"));
        // Nothing overflowed or ran away: only the energy says it diverged.
        assert!(
            matches!(caught, Divergence::EnergyGrowth { .. }),
            "at {fraction}: {caught}"
        );
        assert!(system.positions().iter().all(|p| p.is_finite()));
        assert!(
            caught.to_string().contains("as far as its budget allows"),
            "{caught}"
        );
    }
}

#[test]
fn explicit_methods_past_their_limits_are_caught_within_a_bounded_number_of_steps() {
    let cases = [
        ("rk4", 0.0, 2.0 * 2f64.sqrt(), 1.01, 2048),
        ("symplectic-euler", 0.0, 2.0, 1.01, 2048),
        ("verlet", 0.0, 2.0, 1.01, 2048),
        ("explicit-euler", 0.1, 0.2, 1.1, 4096),
        ("explicit-euler", 0.0, 0.2, 1.0, 20_000), // undamped: unstable at every step
    ];
    for (integrator, zeta, limit_hw, fraction, within) in cases {
        let mut system = spring(integrator, zeta, limit_hw, fraction);
        assert!(
            first_divergence(&mut system, within).is_some(),
            "{integrator} at {fraction} of its limit ran {within} steps uncaught"
        );
    }
}

#[test]
fn runs_at_nine_tenths_of_the_limit_are_never_flagged() {
    let cases = [
        ("rk4", 0.0, 2.0 * 2f64.sqrt()),
        ("symplectic-euler", 0.0, 2.0),
        ("verlet", 0.0, 2.0),
        ("explicit-euler", 0.1, 0.2),
    ];
    for (integrator, zeta, limit_hw) in cases {
        let mut system = spring(integrator, zeta, limit_hw, 0.9);
        if let Some(d) = first_divergence(&mut system, 20_000) {
            panic!("{integrator} at 0.9 of its limit was flagged: {d}");
        }
    }
}

#[test]
fn no_built_in_scene_at_its_defaults_is_flagged_on_either_engine() {
    for scene in builtin_scenes() {
        for fast in [false, true] {
            let mut system = Scene::load(scene.name).unwrap().build().unwrap();
            system.set_fast_path(fast);
            let steps = (4.0 / system.params().dt) as u64;
            if let Err(d) = system.run(steps) {
                panic!("{} (fast engine: {fast}) was flagged: {d}", scene.name);
            }
        }
    }
}

/// A cloth at rest whose stiffness jumps 100-fold past its stable step: before
/// the energy check this ran on with the cloth in tatters and nothing caught.
#[test]
fn a_cloth_whose_stiffness_jumps_past_its_stable_step_is_caught() {
    for fast in [false, true] {
        let mut system = build("bench", &["width=48", "height=48"]);
        system.set_fast_path(fast);
        system.run(960).unwrap();
        let k = system.model().material(system.springs()[0].kind).stiffness;
        let k_unstable = 4.0 * k / system.stability().margin.powi(2);
        for kind in [SpringKind::Structural, SpringKind::Shear, SpringKind::Bend] {
            system.set_spring_stiffness(kind, k_unstable);
        }
        assert!(system.stability().margin > 1.5);
        assert!(
            system.run(2 * 960).is_err(),
            "fast engine {fast}: the unstable cloth was not caught"
        );
    }
}

/// Dragging a particle does work on the cloth: the budget takes the work of each
/// move, so a steady drag is never flagged.
#[test]
fn dragging_a_particle_around_is_not_flagged() {
    for fast in [false, true] {
        let mut system = build("cloth", &[]);
        system.set_fast_path(fast);
        let i = system.particle_count() / 2;
        let start = system.positions()[i];
        for frame in 0..240 {
            let phase = frame as f64 * 0.1;
            let target = start + glam::DVec3::new(phase.sin(), 0.5 * phase.cos(), 0.3) * 0.8;
            system.grab(i, target);
            if let Err(d) = system.run(16) {
                panic!("fast engine {fast}: a drag was flagged at frame {frame}: {d}");
            }
        }
    }
}

/// Moving the particle held keeps the budget and adds the hand's work to it: the
/// change in the whole system's energy, summed here over every particle and
/// spring, before and after the move.
#[test]
fn moving_a_held_particle_adds_its_work_to_the_budget() {
    for fast in [false, true] {
        let mut system = build("cloth", &["width=16", "height=16"]);
        system.set_fast_path(fast);
        let i = system.particle_count() / 2;
        let start = system.positions()[i];
        system.grab(i, start);
        system.run(64).unwrap();
        let total = |s: &System| s.model().energy(s.positions(), s.velocities()).total();
        let (before, budget) = (total(&system), system.energy_budget().unwrap());
        system.grab(i, start + glam::DVec3::new(0.05, -0.1, 0.2));
        let work = total(&system) - before;
        let moved = system.energy_budget().expect("the budget was kept");
        assert!(work.abs() > 1e-3, "the move did no work to test: {work} J");
        let added = moved.base - budget.base;
        assert!(
            (added - work).abs() <= 1e-9 * work.abs(),
            "fast {fast}: the budget took {added} J for a move that did {work} J"
        );
        // The scale grows by the work's size, to the same tolerance: the engine
        // counts the work from the held particle's springs, this test from the
        // whole cloth's sum, and the two round apart by an ulp or so.
        let grown = moved.scale - budget.scale;
        assert!(
            (grown - work.abs()).abs() <= 1e-9 * work.abs(),
            "fast {fast}: the scale grew by {grown} J for a move that did {work} J"
        );
        let factor = |b: cloth_sandbox::sim::EnergyBudget| b.allowed / b.scale;
        assert!((factor(moved) / factor(budget) - 1.0).abs() < 1e-12);
    }
}

/// Undamped explicit Euler grows at every step (`|1 + i w h| > 1`): held and
/// moved back and forth every 16 steps, the cloth must still be caught by its
/// energy, as it is when left alone. A new budget at every move (as before)
/// granted it a new margin each time: it ran on until a particle passed 100 km/s,
/// 1.65 times as many steps.
#[test]
fn a_run_diverging_while_a_particle_is_dragged_is_caught_by_its_energy() {
    let overrides = [
        "width=8",
        "height=8",
        "wind=0,0,0",
        "gust=0",
        "damping=0",
        "integrator=\"explicit-euler\"",
    ];
    let omega = build("cloth", &overrides).stability().omega_max;
    // `w h` = 0.1 on the highest mode: energy growth of about 1% a step.
    let dt = format!("dt={}", 0.1 / omega);
    let divergence = |drag: bool| {
        let mut overrides = overrides.to_vec();
        overrides.push(&dt);
        let mut system = build("cloth", &overrides);
        let i = system.particle_count() / 2;
        let start = system.positions()[i];
        for frame in 0..2000 {
            if drag {
                let away = glam::DVec3::new(0.0, 0.0, 0.001 * (frame % 2) as f64);
                system.grab(i, start + away);
            }
            if let Err(d) = system.run(16) {
                return d;
            }
        }
        panic!("drag {drag}: not caught in 32,000 steps");
    };
    let (left, dragged) = (divergence(false), divergence(true));
    assert!(matches!(left, Divergence::EnergyGrowth { .. }), "{left}");
    assert!(
        matches!(dragged, Divergence::EnergyGrowth { .. }),
        "dragged: {dragged}"
    );
    assert!(
        dragged.time() <= 1.1 * left.time(),
        "dragged: caught at {} s, left alone at {} s",
        dragged.time(),
        left.time()
    );
}

#[test]
fn self_collision_thicker_than_a_ropes_bars_allow_is_caught() {
    // The rope has bars and no springs, so nothing in it oscillates and no step
    // limit bounds its energy. Self-collision 0.5 m thick pushes apart particles
    // two bars apart, which the 0.1 m bars hold within 0.2 m, and each push adds
    // its `δ / h`: the energy grows without bound.
    // At 0.05 m, under the bars' length, nothing fights and nothing is flagged.
    for fast in [false, true] {
        let mut fighting = build("rope", &["self_collision=true", "thickness=0.5"]);
        fighting.set_fast_path(fast);
        let caught = fighting
            .run(3000)
            .expect_err("the pumped rope was not caught");
        assert!(
            matches!(caught, Divergence::EnergyGrowth { .. }),
            "fast {fast}: {caught}"
        );
        let mut thin = build("rope", &["self_collision=true", "thickness=0.05"]);
        thin.set_fast_path(fast);
        thin.run(3000).unwrap();
    }
}

/// A hand that jumps a metre between frames of 4 steps (a flick of the mouse on a
/// slow frame) on the fold scene, whose cloth of 4 cm springs meets itself: put
/// at the hand at once, the held particle threw its neighbour at 780 m/s through
/// the layers, and the run ran away within 24 frames. It follows the hand at
/// most half a spring a step, and the cloth stays in one piece on both engines.
#[test]
fn a_flicked_hand_does_not_blow_up_the_folding_cloth() {
    for fast in [true, false] {
        let mut system = build("fold", &[]);
        system.set_fast_path(fast);
        let i = system.particle_count() / 2 + 3;
        let start = system.positions()[i];
        let frames = if fast { 300 } else { 120 };
        for frame in 0..frames {
            let phase = f64::from(frame) * 0.5;
            let hand = glam::DVec3::new(
                phase.sin(),
                0.7 * (1.3 * phase).cos(),
                0.5 * (0.7 * phase).sin(),
            );
            system.grab(i, start + 1.5 * hand);
            if let Err(d) = system.run(4) {
                panic!("fast engine {fast}: frame {frame}: {d}");
            }
        }
        let speed = system
            .velocities()
            .iter()
            .map(|v| v.length())
            .fold(0.0, f64::max);
        assert!(
            speed < 100.0,
            "fast engine {fast}: a particle at {speed} m/s"
        );
    }
}
