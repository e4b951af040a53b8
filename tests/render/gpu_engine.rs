//! The GPU engine (`cloth_sandbox::gpu`) against independent references: the
//! peers' float64 NumPy bench cloth, and the f64 engine (`--exact`'s) on the
//! built-in scenes it steps, within f32 tolerances stated per test; two runs give
//! the same bits; what it cannot step it refuses with its reasons.
//!
//! Without any adapter the tests print a note and pass, unless
//! `CLOTH_REQUIRE_ADAPTER` is set (CI sets it), in which case they fail.

use cloth_sandbox::gpu::{GpuEngine, GpuError};
use cloth_sandbox::scene::Scene;
use cloth_sandbox::sim::System;
use glam::DVec3;

use crate::common::build;

/// An engine for `system`, or `None` (with a note) where the machine has no adapter.
fn engine(system: &System) -> Option<GpuEngine> {
    match GpuEngine::new(system) {
        Ok(engine) => Some(engine),
        Err(GpuError::NoAdapter) if std::env::var_os("CLOTH_REQUIRE_ADAPTER").is_none() => {
            eprintln!("note: no GPU adapter here; the GPU engine is not tested");
            None
        }
        Err(e) => panic!("the GPU engine would not start: {e}"),
    }
}

/// `system` run `steps` on the GPU (unchanged without an adapter).
fn on_gpu(mut system: System, steps: u64) -> Option<System> {
    let mut gpu = engine(&system)?;
    gpu.run(&mut system, steps)
        .expect("the GPU ran")
        .expect("no divergence");
    Some(system)
}

/// The same scene run `steps` on the f64 engine.
fn on_f64(mut system: System, steps: u64) -> System {
    system.set_fast_path(false);
    system.run(steps).expect("no divergence");
    system
}

fn mean_y(system: &System) -> f64 {
    let p = system.positions();
    p.iter().map(|p| p.y).sum::<f64>() / p.len() as f64
}

/// The largest distance between the two systems' particles, in m, and their
/// largest velocity difference, in m/s.
fn apart(a: &System, b: &System) -> (f64, f64) {
    let most = |x: &[DVec3], y: &[DVec3]| {
        x.iter()
            .zip(y)
            .map(|(p, q)| p.distance(*q))
            .fold(0.0, f64::max)
    };
    (
        most(a.positions(), b.positions()),
        most(a.velocities(), b.velocities()),
    )
}

/// The peers' bench cloth (32², symplectic Euler, 960 steps of 1/960 s): the mean
/// y after 1 s is the NumPy float64 reference's -0.064685755 m (a drop of
/// -0.5646856 m from 0.5) to f32 accuracy: the cloth's 1,024 particles each
/// rounded at about 6e-8 of their 1 m span a step, well under 1e-5 m.
#[test]
fn bench_cloth_drops_as_the_float64_reference() {
    let Some(system) = on_gpu(Scene::load("bench").unwrap().build().unwrap(), 960) else {
        return;
    };
    let mean = mean_y(&system);
    assert!((mean - -0.064685755).abs() < 1e-5, "mean y {mean}");
    assert_eq!(system.steps_taken(), 960);
    assert!((system.time() - 1.0).abs() < 1e-9);
}

/// The bounding box's diagonal of `system`, in m.
fn span(system: &System) -> f64 {
    let (lo, hi) = (system.positions().iter())
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), &q| {
            (a.min(q), b.max(q))
        });
    (hi - lo).length()
}

/// `name` with `set` run `seconds` on the GPU and on the f64 engine: the largest
/// distance between their particles in m, the cloth's span and both energies.
fn compare(name: &str, set: &[&str], seconds: f64) -> Option<(f64, f64, f64, f64)> {
    let system = build(name, set);
    let steps = (seconds / system.params().dt).round() as u64;
    let reference = on_f64(system.clone(), steps);
    let gpu = on_gpu(system, steps)?;
    let (dx, _) = apart(&gpu, &reference);
    let energies = (gpu.energy().total(), reference.energy().total());
    eprintln!("{name} {set:?}: {dx:.3e} m apart after {seconds} s, energy {energies:?} J");
    Some((dx, span(&reference), energies.0, energies.1))
}

/// Scenes without contact, where f32 rounding stays small: every particle within
/// 1e-4 of the cloth's span of the f64 engine's after 0.5 s (measured on
/// lavapipe: 1.8e-5 at most, explicit Euler's 5,000 steps), and the energy within
/// 1e-4 of it or of 1 J (measured 1e-5 at most, the chain).
#[test]
fn smooth_scenes_agree_with_the_f64_engine() {
    let cases: &[(&str, &[&str])] = &[
        ("cloth", &[]),
        ("cloth", &["integrator=\"verlet\""]),
        ("cloth", &["integrator=\"explicit-euler\"", "dt=1e-4"]),
        ("corners", &[]),
        ("bench-wind", &[]),
        ("spring", &[]),
        ("chain", &[]),
        ("jelly", &[]),
        ("hanging", &[]),
    ];
    for &(name, set) in cases {
        let Some((dx, span, e_gpu, e_f64)) = compare(name, set, 0.5) else {
            return;
        };
        assert!(
            dx <= 1e-4 * span,
            "{name} {set:?}: {dx} m apart (span {span} m)"
        );
        let de = (e_gpu - e_f64).abs();
        assert!(
            de <= 1e-4 * e_f64.abs().max(1.0),
            "{name} {set:?}: energy {e_gpu} against {e_f64} J"
        );
    }
}

/// Contact and strong gusts amplify rounding (the CPU's own f32 grid engine
/// ends 6.6 mm from the f64 engine on the drape): after 0.5 s on the sphere the
/// particles stay within 3 cm of the f64 engine's (measured 3.8 mm to 1.1 cm),
/// the energy within 2e-3 (measured 2.9e-4 at most), and no particle is inside
/// the sphere by more than 1e-5 m (f32's rounding of a 0.5 m radius is 3e-8 m).
///
/// The gusty flag is chaotic: the CPU's own f32 grid engine ends 2.9% from the
/// f64 engine's energy (`cloth run --scene flag --duration 0.5 --json`, 7.142 J,
/// against `--exact`, 7.356 J). The GPU engine's ends 2.9 cm and 0.4% from it,
/// held within 10 cm and 5%. The gusty sheet (Verlet, a 10% stretch limit) ends
/// 9.8e-7 m and 3e-8 from it, held within 1e-4 m and 1e-4.
#[test]
fn contact_and_gusts_agree_with_the_f64_engine_in_the_large() {
    let cases: &[(&str, &[&str], f64, f64)] = &[
        ("drape", &["self_collision=false"], 0.03, 2e-3),
        ("drape", &["self_collision=false", "friction=0"], 0.03, 2e-3),
        ("tablecloth", &[], 0.03, 2e-3),
        ("flag", &[], 0.1, 0.05),
        ("sheet", &[], 1e-4, 1e-4),
    ];
    for &(name, set, most, energy) in cases {
        let Some((dx, _, e_gpu, e_f64)) = compare(name, set, 0.5) else {
            return;
        };
        assert!(dx <= most, "{name} {set:?}: {dx} m apart");
        let de = (e_gpu - e_f64).abs();
        assert!(
            de <= energy * e_f64.abs(),
            "{name} {set:?}: energy {e_gpu} against {e_f64} J"
        );
    }
    let system = build("drape", &["self_collision=false"]);
    let steps = (0.5 / system.params().dt).round() as u64;
    let sphere = system.params().sphere.expect("the drape has a sphere");
    let system = on_gpu(system, steps).unwrap();
    let deepest = (system.positions().iter())
        .map(|p| sphere.radius - p.distance(sphere.center))
        .fold(f64::NEG_INFINITY, f64::max);
    assert!(
        deepest <= 1e-5,
        "a particle is {deepest} m inside the sphere"
    );
}

/// The stiff flag (k = 3e6 N/m at a step under half the critical one) does not
/// heat: its energy after 0.05 s (5,000 steps) within 0.1% of the f64 engine's
/// (measured on lavapipe: 0.013% over it). With positions in plain f32 (the
/// two-sum folded away, see `moves_below_f32_rounding_add_up`) it was 0.34%.
#[test]
fn the_stiff_flag_keeps_the_f64_engines_energy() {
    let Some((_, _, e_gpu, e_f64)) = compare("flag", &["stiffness=3e6", "dt=1e-5"], 0.05) else {
        return;
    };
    assert!(
        (e_gpu - e_f64).abs() <= 1e-3 * e_f64.abs(),
        "energy {e_gpu} against {e_f64} J"
    );
}

/// The constraint sweeps, XPBD's springs and the stretch limit, against the f64
/// engine's after 0.5 s, measured on lavapipe:
///
/// | case | apart, of the span | energy, relative |
/// |---|---|---|
/// | bench, 10% stretch limit | 2.3e-7 | 1.6e-8 |
/// | cloth, k = 40, 5% stretch limit | 4.8e-7 | 1.1e-8 |
/// | bench, XPBD | 1.3e-6 | 1.0e-5 |
/// | cloth, XPBD | 1.4e-6 | 3e-8 |
/// | jelly on two pins, XPBD (swept forward and back) | 1.9e-8 | 1.2e-8 |
///
/// Each is held within 2e-5 of the span, and the energy within 1e-4; the cloth
/// within 1e-4 of it, as its top edge amplifies rounding under XPBD (a 1e-7 m
/// nudge to its particle 14 in the f64 engine doubles every 10 steps from 0.1
/// s); the jelly within 2e-6 and 1e-6, as swept forward only it ends 1.8e-5 of
/// its span and 4.7e-5 of its energy away (checked). Each case's constraints move
/// the cloth by over 10 times its tolerance (the cloth without them, checked
/// here), so an engine that skipped a pass fails.
#[test]
fn constrained_scenes_agree_with_the_f64_engine() {
    const XPBD: &str = "integrator=\"xpbd\"";
    const PINNED: &str = "pins=\"top-corners\"";
    // The scene, its settings, the settings without the constraints, the
    // tolerances of distance (of the span) and energy (relative).
    type Case<'a> = (&'a str, &'a [&'a str], &'a [&'a str], f64, f64);
    let cases: &[Case] = &[
        ("bench", &["stretch_limit=0.1"], &[], 2e-5, 1e-4),
        (
            "cloth",
            &["stretch_limit=0.05", "stiffness=40"],
            &["stiffness=40"],
            2e-5,
            1e-4,
        ),
        (
            "bench",
            &[XPBD],
            &[XPBD, "stiffness_per_mass=1e-9"],
            2e-5,
            1e-4,
        ),
        ("cloth", &[XPBD], &[XPBD, "stiffness=1e-9"], 1e-4, 1e-4),
        // A lattice: swept forward and back.
        (
            "jelly",
            &[XPBD, PINNED],
            &[XPBD, PINNED, "stiffness=1e-9"],
            2e-6,
            1e-6,
        ),
    ];
    for &(name, set, without, most, energy) in cases {
        let Some((dx, span, e_gpu, e_f64)) = compare(name, set, 0.5) else {
            return;
        };
        let de = (e_gpu - e_f64).abs();
        eprintln!(
            "{name} {set:?}: {:.1e} of the span apart, energy {:.1e} relative",
            dx / span,
            de / e_f64.abs().max(1.0)
        );
        assert!(
            dx <= most * span,
            "{name} {set:?}: {dx} m apart (span {span} m)"
        );
        assert!(
            de <= energy * e_f64.abs().max(1.0),
            "{name} {set:?}: energy {e_gpu} against {e_f64} J"
        );
        let system = build(name, set);
        let steps = (0.5 / system.params().dt).round() as u64;
        let (with, unconstrained) = (on_f64(system, steps), on_f64(build(name, without), steps));
        let (moved, _) = apart(&with, &unconstrained);
        eprintln!("{name} {set:?}: the constraints move it {moved:.3e} m");
        assert!(
            moved >= 10.0 * most * span,
            "{name} {set:?}: the constraints move it {moved} m"
        );
    }
}

/// No atomics and no shared writes: two runs of the gusty flag give the same bits.
#[test]
fn two_runs_give_the_same_bits() {
    let system = build("flag", &[]);
    let Some(a) = on_gpu(system.clone(), 200) else {
        return;
    };
    let b = on_gpu(system, 200).unwrap();
    assert_eq!(a.positions(), b.positions());
    assert_eq!(a.velocities(), b.velocities());
}

/// Positions are two f32, so that a move far below f32's rounding of the
/// position is kept: a free cloth (no gravity, drag or pins; springs too weak to
/// round to a force) drifting at 1e-6
/// m/s moves 1.04e-9 m a step, under a twentieth of f32's 6e-8 m spacing at its
/// corners, 0.78 m from its centre. After 960 steps every particle has moved v
/// t = 1e-6 m, within 1e-9 m (a position in plain f32 stays put).
#[test]
fn moves_below_f32_rounding_add_up() {
    let mut system = build(
        "cloth",
        &[
            "gravity=\"0,0,0\"",
            "drag_coefficient=0",
            "pins=\"none\"",
            "stiffness=1e-6",
        ],
    );
    let mut state = system.state().clone();
    let v = DVec3::new(1e-6, -1e-6, 1e-6);
    state.velocities.iter_mut().for_each(|u| *u = v);
    system.set_state(state);
    let start = system.positions().to_vec();
    let Some(system) = on_gpu(system, 960) else {
        return;
    };
    let t = system.time();
    let worst = (system.positions().iter().zip(&start))
        .map(|(x, x0)| (*x - *x0 - v * t).length())
        .fold(0.0, f64::max);
    eprintln!("drift: {worst:e} m off v t = {:e} m", (v * t).length());
    assert!(worst <= 1e-9, "{worst} m off");
}

/// Where the device has timestamp queries, the GPU time of the steps is counted
/// (a step at a time from the first, 0 before any) and lies within the wall
/// clock's time of the run, which holds it.
#[test]
fn timestamps_time_the_steps_within_the_wall_clock() {
    let mut system = build("cloth", &[]);
    let Some(mut gpu) = engine(&system) else {
        return;
    };
    let Some(before) = gpu.gpu_time() else {
        eprintln!("note: the adapter has no timestamp queries");
        return;
    };
    assert_eq!((before.steps, before.per_step()), (0, None));
    let start = std::time::Instant::now();
    gpu.run(&mut system, 1500).unwrap().unwrap();
    let wall = start.elapsed().as_secs_f64();
    let time = gpu.gpu_time().unwrap();
    eprintln!("{time:?} against {wall} s by the wall");
    assert_eq!(time.steps, 1500);
    assert!(
        time.seconds > 0.0 && time.seconds <= wall,
        "{time:?} in {wall} s"
    );
    gpu.reset_gpu_time();
    assert_eq!(gpu.gpu_time().unwrap().steps, 0);
}

/// What the engine does not step yet is refused, naming it, before any GPU work.
#[test]
fn scenes_it_cannot_step_are_refused_with_the_reason() {
    let cases = [
        ("tablecloth", "constraint order"),
        ("fold", "self-collision"),
        ("tear", "tearing"),
        ("bars", "bars"),
        ("table", "colliders"),
        ("cloth", "rk4"),
    ];
    for (name, reason) in cases {
        let set: &[&str] = match name {
            "cloth" => &["integrator=\"rk4\""],
            "tablecloth" => &["stretch_limit=0.1"],
            _ => &[],
        };
        let system = build(name, set);
        match GpuEngine::new(&system) {
            Err(GpuError::Unsupported(why)) => assert!(why.contains(reason), "{name}: {why}"),
            Err(e) => panic!("{name}: {e}"),
            Ok(_) => panic!("{name} was not refused"),
        }
    }
}
